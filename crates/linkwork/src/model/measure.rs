//! A measure over any number type, with its own numbers given: what design sensitivities
//! differentiate (docs/sensitivities.md). [`Measure::value`] is the plain evaluation.

use super::{spec, Measure, MeasureKind};
use crate::expr::Scalar;

impl Measure {
    /// The value at `(q, qdot, qddot, t)` over `S`, with the measure's numbers `data` in the order
    /// of [`MeasureKind::data`] and the model's parameters `params` (file order): each may carry
    /// derivatives. `None` for a kind that has no derivatives yet (a cam's pressure angle, a
    /// mechanical advantage, an expression that reads reactions).
    pub fn value_generic<S: Scalar>(
        &self,
        q: &[S],
        qdot: &[S],
        qddot: &[S],
        t: S,
        data: &[S],
        params: &[S],
    ) -> Option<S> {
        match &self.kind {
            MeasureKind::Expression(e) => {
                if e.reactions().next().is_some() {
                    return None;
                }
                Some(e.eval_params(q, qdot, qddot, &[], t, params))
            }
            MeasureKind::Point { body: b, component, .. } => {
                use spec::PointComponent as C;
                let (sn, c) = (q[b + 2].sin(), q[b + 2].cos());
                let a = [c * data[0] - sn * data[1], sn * data[0] + c * data[1]];
                let (w, al) = (qdot[b + 2], qddot[b + 2]);
                Some(match component {
                    C::X => q[*b] + a[0],
                    C::Y => q[b + 1] + a[1],
                    C::Vx => qdot[*b] - w * a[1],
                    C::Vy => qdot[b + 1] + w * a[0],
                    C::Ax => qddot[*b] - al * a[1] - w * w * a[0],
                    C::Ay => qddot[b + 1] + al * a[0] - w * w * a[1],
                })
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
                let gamma = (u[0] * v[1] - u[1] * v[0]).abs().atan2(u[0] * v[0] + u[1] * v[1]);
                Some(gamma.min(S::constant(std::f64::consts::PI) - gamma))
            }
            MeasureKind::VelocityRatio { input, output } => Some(if qdot[*input].value() == 0.0 {
                qddot[*output] / qddot[*input]
            } else {
                qdot[*output] / qdot[*input]
            }),
            MeasureKind::PressureAngle(_) | MeasureKind::MechanicalAdvantage { .. } => None,
        }
    }
}
