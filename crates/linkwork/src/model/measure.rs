//! A measure over any number type, with its own numbers given: what design sensitivities
//! differentiate (docs/sensitivities.md). [`Measure::value`] is the plain evaluation.

use super::{spec, Effort, Measure, MeasureKind};
use crate::expr::{Nestable, Scalar};
use crate::forces::Data;

impl Measure {
    /// The value at `(q, qdot, qddot, t)` over `S`, with the reactions row `reactions` (as
    /// [`Measure::value`]'s: empty in an analysis that has none), the measure's numbers `data`
    /// in the order of [`MeasureKind::data`] and the model's parameters `params` (file order):
    /// each may carry derivatives.
    #[allow(clippy::too_many_arguments)]
    pub fn value_generic<S: Nestable>(
        &self,
        q: &[S],
        qdot: &[S],
        qddot: &[S],
        reactions: &[S],
        t: S,
        data: &[S],
        params: &[S],
    ) -> S {
        match &self.kind {
            MeasureKind::Expression(e) => e.eval_params(q, qdot, qddot, reactions, t, params),
            MeasureKind::Point { body: b, component, .. } => {
                point_component(q, qdot, qddot, *b, [data[0], data[1]], *component)
            }
            MeasureKind::TransmissionAngle { coupler: (c, _), rocker: (r, _) } => {
                let turn = |body: crate::constraints::BodyIx, v: [S; 2]| match body.0 {
                    Some(k) => {
                        let (sn, cs) = (q[k + 2].sin(), q[k + 2].cos());
                        [cs * v[0] - sn * v[1], sn * v[0] + cs * v[1]]
                    }
                    None => v,
                };
                let u = turn(*c, [data[0], data[1]]);
                let v = turn(*r, [data[2], data[3]]);
                acute_angle(u, v)
            }
            MeasureKind::VelocityRatio { input, output } => {
                if qdot[*input].value() == 0.0 {
                    qddot[*output] / qddot[*input]
                } else {
                    qdot[*output] / qdot[*input]
                }
            }
            MeasureKind::PressureAngle(cam) => cam.pressure_angle_generic(q, qdot, data, params),
            MeasureKind::MechanicalAdvantage { input, output } => {
                let effort = |e: &Effort| e.value_generic(q, qdot, reactions, t, params);
                -effort(output) / effort(input)
            }
        }
    }
}

impl Effort {
    /// Its value over `S` (as [`Measure::value`] reads it): a driver's effort from the reactions
    /// row, a `torque` force's torque from `(q, qdot)` at the time `t` (held) with the model's
    /// parameters `params`, which its expression reads ([`crate::forces::Load::value_data`]). A
    /// torque written as a number is a constant: the parameters write a force's `torque` only as
    /// an expression (`torque: -load`), which reads them.
    fn value_generic<S: Scalar>(&self, q: &[S], qdot: &[S], reactions: &[S], t: S, params: &[S]) -> S {
        match self {
            Effort::Driver { slot } => reactions.get(*slot).copied().unwrap_or(S::constant(f64::NAN)),
            Effort::Torque { torque, .. } => {
                let own: Vec<S> = torque.data("torque").map(|(_, c)| S::constant(c)).into_iter().collect();
                torque.value_data(q, qdot, t.value(), &mut Data::new(&own), params)
            }
        }
    }
}

/// The `component` of the point `s` (body frame) of the body whose `x` is `q[b]`, global frame:
/// a point measure's value.
pub(super) fn point_component<S: Scalar>(
    q: &[S],
    qdot: &[S],
    qddot: &[S],
    b: usize,
    s: [S; 2],
    component: spec::PointComponent,
) -> S {
    use spec::PointComponent as C;
    let (sn, c) = (q[b + 2].sin(), q[b + 2].cos());
    let a = [c * s[0] - sn * s[1], sn * s[0] + c * s[1]];
    let (w, al) = (qdot[b + 2], qddot[b + 2]);
    match component {
        C::X => q[b] + a[0],
        C::Y => q[b + 1] + a[1],
        C::Vx => qdot[b] - w * a[1],
        C::Vy => qdot[b + 1] + w * a[0],
        C::Ax => qddot[b] - al * a[1] - w * w * a[0],
        C::Ay => qddot[b + 1] + al * a[0] - w * w * a[1],
    }
}

/// The acute angle between the lines along `u` and `v` (global frame): the angle in `[0, pi]`
/// from both its sine and cosine (accurate near 0 and pi, where acos of the cosine is not),
/// folded to the acute one. A transmission angle's value.
pub(super) fn acute_angle<S: Scalar>(u: [S; 2], v: [S; 2]) -> S {
    let gamma = (u[0] * v[1] - u[1] * v[0]).abs().atan2(u[0] * v[0] + u[1] * v[1]);
    gamma.min(S::constant(std::f64::consts::PI) - gamma)
}
