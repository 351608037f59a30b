//! A force at a body point and a torque on a body, each a constant or an expression of time and
//! state.
//!
//! ```text
//! force f at P on body i, global frame:  Q_i = (f_x, f_y, (A_i s'_P) x f)
//! follower force, body frame:            f = A_i f'
//! torque tau on body i:                  Q_i = (0, 0, tau)
//! ```
//! The moment term is `dr_P/dphi . f = (B_i s'_P) . f = (A_i s'_P) x f` (Haug 1989 section 6.2).

use super::{cross, layout, rotate, Data, Force, ForceContext, ForceLaw, Load, Local, Quantity};
use crate::element::{vector, PointRef, POINT};
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A force at a point of a body.
#[derive(Debug, Clone)]
pub struct PointLoad {
    body: Local,
    /// Point of application, body frame, m.
    s: [f64; 2],
    /// True when `(fx, fy)` are body-frame components.
    follower: bool,
    fx: Load,
    fy: Load,
    columns: Vec<usize>,
}

impl PointLoad {
    /// The force `(fx, fy)` at `s` (body frame) of the body whose `x` is `q[body]`; components
    /// in the body's frame when `follower`.
    pub fn new(body: usize, s: [f64; 2], follower: bool, mut fx: Load, mut fy: Load) -> PointLoad {
        let (columns, locals) = layout(&[Some(body)], &mut [&mut fx, &mut fy]);
        PointLoad { body: locals[0], s, follower, fx, fy, columns }
    }
}

impl ForceLaw for PointLoad {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        let f = [self.fx.value(x, v, t), self.fy.value(x, v, t)];
        self.law(x, self.s.map(S::constant), f, out);
    }
    fn potential<S: Scalar>(&self, _x: &[S]) -> S {
        S::constant(0.0)
    }
    /// None: its work is not counted in the potential energy.
    fn potential_data<S: Scalar>(&self, _x: &[S], _data: &[S], _params: &[S]) -> Option<S> {
        Some(S::constant(0.0))
    }
    fn applied(&self) -> bool {
        true
    }
    fn expressions(&self) -> Vec<(&'static str, &str)> {
        [("fx", &self.fx), ("fy", &self.fy)].into_iter().filter_map(|(k, l)| Some((k, l.source()?))).collect()
    }
    /// `point`, and `fx` and `fy` when they are numbers.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let loads = [self.fx.data("fx"), self.fy.data("fy")];
        vector(POINT, self.s).into_iter().chain(loads.into_iter().flatten()).collect()
    }
    fn load_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &[S], params: &[S], out: &mut [S]) -> bool {
        let mut data = Data::new(data);
        let s = data.pair();
        let f = [self.fx.value_data(x, v, t, &mut data, params), self.fy.value_data(x, v, t, &mut data, params)];
        self.law(x, s, f, out);
        true
    }
}

impl PointLoad {
    /// `Q_e` of the force `f` (global, or body frame for a follower) at `s` (body frame).
    #[inline]
    fn law<S: Scalar>(&self, x: &[S], s: [S; 2], mut f: [S; 2], out: &mut [S]) {
        out.fill(S::constant(0.0));
        let [_, _, phi] = self.body.pose(x);
        if self.follower {
            let (c, s) = (phi.cos(), phi.sin());
            f = [c * f[0] - s * f[1], s * f[0] + c * f[1]];
        }
        let arm = rotate(phi, s);
        self.body.add(out, [f[0], f[1], cross(arm, f)]);
    }
}

/// A torque on a body.
#[derive(Debug, Clone)]
pub struct Torque {
    body: Local,
    torque: Load,
    columns: Vec<usize>,
}

impl Torque {
    /// The torque `torque` on the body whose `x` is `q[body]`.
    pub fn new(body: usize, mut torque: Load) -> Torque {
        let (columns, locals) = layout(&[Some(body)], &mut [&mut torque]);
        Torque { body: locals[0], torque, columns }
    }
}

impl Torque {
    /// `Q_e` of the torque `torque`.
    #[inline]
    fn law<S: Scalar>(&self, torque: S, out: &mut [S]) {
        out.fill(S::constant(0.0));
        let zero = S::constant(0.0);
        self.body.add(out, [zero, zero, torque]);
    }
}

impl ForceLaw for Torque {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        self.law(self.torque.value(x, v, t), out);
    }
    /// `torque` when it is a number.
    fn data(&self) -> Vec<(&'static str, f64)> {
        self.torque.data("torque").into_iter().collect()
    }
    fn load_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &[S], params: &[S], out: &mut [S]) -> bool {
        let torque = self.torque.value_data(x, v, t, &mut Data::new(data), params);
        self.law(torque, out);
        true
    }
    fn applied(&self) -> bool {
        true
    }
    fn expressions(&self) -> Vec<(&'static str, &str)> {
        self.torque.source().map(|s| ("torque", s)).into_iter().collect()
    }
    fn potential<S: Scalar>(&self, _x: &[S]) -> S {
        S::constant(0.0)
    }
    /// None: its work is not counted in the potential energy.
    fn potential_data<S: Scalar>(&self, _x: &[S], _data: &[S], _params: &[S]) -> Option<S> {
        Some(S::constant(0.0))
    }
}

/// The frame a force's components are given in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ForceFrame {
    /// The global frame (the force keeps its direction as the body turns).
    #[default]
    Global,
    /// The body's frame (the force turns with the body, a follower force).
    Body,
}

/// A force at a point of a body.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PointForce {
    /// The body the force acts on.
    pub body: String,
    /// Where it acts (default: the centre of mass).
    #[serde(default)]
    pub point: PointRef,
    /// The frame of `fx` and `fy`. Default: global.
    #[serde(default)]
    pub frame: ForceFrame,
    /// x component, N. Default 0.
    #[serde(default)]
    pub fx: Quantity,
    /// y component, N. Default 0.
    #[serde(default)]
    pub fy: Quantity,
}

/// A torque on a body.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TorqueSpec {
    /// The body.
    pub body: String,
    /// Torque, N m, counter-clockwise positive.
    pub torque: Quantity,
}

/// A force at `path` compiled in `cx`.
pub(crate) fn compile_force(spec: &PointForce, cx: &mut impl ForceContext, path: &str) -> Option<Box<dyn Force>> {
    let PointForce { body, point, frame, fx, fy } = spec;
    let b = cx.moving(&format!("{path}.body"), body);
    let s = cx.point(&format!("{path}.point"), body, point);
    let fx = cx.load(&format!("{path}.fx"), fx);
    let fy = cx.load(&format!("{path}.fy"), fy);
    Some(Box::new(PointLoad::new(b?, s?, *frame == ForceFrame::Body, fx?, fy?)))
}

/// A torque at `path` compiled in `cx`.
pub(crate) fn compile_torque(spec: &TorqueSpec, cx: &mut impl ForceContext, path: &str) -> Option<Box<dyn Force>> {
    let b = cx.moving(&format!("{path}.body"), &spec.body);
    let t = cx.load(&format!("{path}.torque"), &spec.torque);
    Some(Box::new(Torque::new(b?, t?)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::testing::{assert_data_fields, check_data, check_derivatives, expression, expression_with};

    /// Hand-derived: a unit force along +y at `s' = (1, 0)` on a body at angle 0 gives moment
    /// `1 x 1 = 1`; along the body's own y (follower) at angle pi/2 it points along -x and its
    /// moment about the centre is still +1.
    #[test]
    fn moment_of_a_force_hand_derived() {
        let f = PointLoad::new(0, [1.0, 0.0], false, Load::Constant(0.0), Load::Constant(1.0));
        let mut out = [0.0; 3];
        ForceLaw::load(&f, &[0.0, 0.0, 0.0], &[0.0; 3], 0.0, &mut out);
        assert_eq!(out, [0.0, 1.0, 1.0]);
        let g = PointLoad::new(0, [1.0, 0.0], true, Load::Constant(0.0), Load::Constant(1.0));
        ForceLaw::load(&g, &[0.0, 0.0, std::f64::consts::FRAC_PI_2], &[0.0; 3], 0.0, &mut out);
        assert!((out[0] + 1.0).abs() < 1e-15 && out[1].abs() < 1e-15 && (out[2] - 1.0).abs() < 1e-15, "{out:?}");
    }

    #[test]
    fn derivatives_match_finite_differences() {
        // Expressions of the body's own state and of another body's (coordinates 3..6).
        let fx = expression("-20*b0.vx + 3*sin(b1.phi) + t", 2);
        let fy = expression("b0.x*b1.omega - 2*b0.phi^2", 2);
        for follower in [false, true] {
            let f = PointLoad::new(0, [0.3, -0.2], follower, fx.clone(), fy.clone());
            check_derivatives(&f, 6, 11);
        }
        let tq = Torque::new(3, expression("-5*b1.omega*abs(b1.omega) + 2*b0.y", 2));
        check_derivatives(&tq, 6, 12);
    }

    /// The load over the data and the parameters (design sensitivities): a force with an
    /// expression of a parameter and time and a number, in either frame, and a torque as a
    /// number and as an expression of parameters.
    #[test]
    fn load_over_data_and_parameters() {
        let params = [("g", 2.5), ("w", 0.7)];
        let values = params.map(|p| p.1);
        let fx = expression_with("-g*b0.vx + 3*sin(w*t) + b1.phi", 2, &params);
        for follower in [false, true] {
            let f = PointLoad::new(0, [0.3, -0.2], follower, fx.clone(), Load::Constant(4.0));
            assert_eq!(ForceLaw::data(&f).iter().map(|d| d.0).collect::<Vec<_>>(), ["point[0]", "point[1]", "fy"]);
            check_data(&f, &values, 13);
            assert_data_fields::<PointForce>(&f);
        }
        let tq = Torque::new(3, Load::Constant(-2.0));
        assert_eq!(ForceLaw::data(&tq), [("torque", -2.0)]);
        check_data(&tq, &values, 14);
        assert_data_fields::<TorqueSpec>(&tq);
        let te = Torque::new(3, expression_with("g*b1.omega + w^2*b0.x", 2, &params));
        assert!(ForceLaw::data(&te).is_empty());
        check_data(&te, &values, 15);
    }
}
