//! Absolute constraints: the global x or y of a body point, or the angle of a body, held at a value.
//! One row each.
//!
//! ```text
//! X:      Phi = x_i + (A_i s'_P)_x - c     Phi_q = [ 1  0  (B_i s'_P)_x ]    gamma = (A_i s'_P)_x omega_i^2
//! Y:      Phi = y_i + (A_i s'_P)_y - c     Phi_q = [ 0  1  (B_i s'_P)_y ]    gamma = (A_i s'_P)_y omega_i^2
//! Angle:  Phi = phi_i - c                  Phi_q = [ 0  0  1 ]               gamma = 0
//! nu = 0
//! ```
//! Haug (1989) section 3.2; Nikravesh (2018) section 7.3.

use super::schema::JointContext;
use super::CompiledJoint;
use super::Frame;
use super::PointRef;
use super::{phi_tri_generic, separation, slot2, vector, At, GenericPhi, Pose, Source, POINT};
use super::{Anchor, BodyIx, Config, Constraint, Pair, Separation, Shape, Sketch};
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Which coordinate an [`Absolute`] constraint holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AbsoluteKind {
    /// The global x of a body point.
    X,
    /// The global y of a body point.
    Y,
    /// The angle of the body frame.
    Angle,
}

/// A body point's global x or y, or a body's angle, equal to a constant.
#[derive(Debug, Clone)]
pub struct Absolute {
    kind: AbsoluteKind,
    pair: Pair,
    point: [f64; 2],
    value: f64,
    /// Where `value` comes from: the file (a data slot), the initial configuration, or none (a
    /// driver's coordinate, `value` 0).
    value_from: Source,
}

impl Absolute {
    /// `point`: the point in the body frame (ignored for [`AbsoluteKind::Angle`]); `value`: the
    /// coordinate it is held at (m or rad).
    pub fn new(kind: AbsoluteKind, body: BodyIx, point: [f64; 2], value: f64) -> Absolute {
        Absolute { kind, pair: Pair::new(body, BodyIx::GROUND), point, value, value_from: Source::File }
    }

    /// The coordinate itself, `value` 0 and not data: what a driver prescribes.
    pub(crate) fn coordinate(kind: AbsoluteKind, body: BodyIx, point: [f64; 2]) -> Absolute {
        Absolute { value_from: Source::Zero, ..Absolute::new(kind, body, point, 0.0) }
    }

    /// `(pose, point) => r_P` measured from the global origin, over any [`Scalar`].
    #[inline]
    fn position_of<S: Scalar>(pose: &Pose<S>, point: [S; 2]) -> [S; 2] {
        let zero = S::constant(0.0);
        separation(&Pose::of(BodyIx::GROUND, &[]), [zero, zero], pose, point)
    }

    /// `(q) => r_P` measured from the global origin.
    #[inline]
    fn position(&self, q: &Config<'_>) -> Separation {
        Separation::of(BodyIx::GROUND, [0.0; 2], self.pair.i, self.point, q)
    }

    /// The component of `r_P` this row holds (0 or 1), `None` for the angle.
    #[inline]
    fn axis(&self) -> Option<usize> {
        match self.kind {
            AbsoluteKind::X => Some(0),
            AbsoluteKind::Y => Some(1),
            AbsoluteKind::Angle => None,
        }
    }
}

impl Constraint for Absolute {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.point)
    }
    fn sketch(&self) -> Option<Sketch> {
        Some(Sketch { i: self.pair.i, p: self.point, j: BodyIx::GROUND, q: self.point, shape: Shape::Held })
    }
    fn row_names(&self) -> &[&'static str] {
        match self.kind {
            AbsoluteKind::X => &["x"],
            AbsoluteKind::Y => &["y"],
            AbsoluteKind::Angle => &["angle"],
        }
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = match self.axis() {
            Some(k) => self.position(q).d[k],
            None => self.pair.i.coords(q)[2],
        } - self.value;
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let row = match self.axis() {
            Some(k) => {
                let mut g = [0.0; 2];
                g[k] = 1.0;
                self.position(q).chain(g).1
            }
            None => [0.0, 0.0, 1.0],
        };
        self.pair.scatter(row, [0.0; 3], out);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = match self.axis() {
            Some(k) => -self.position(q).accel_free(0.0, self.pair.i.coords(qdot)[2])[k],
            None => 0.0,
        };
    }
    /// `point` (not for the angle), and `value` when the file gives it.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let point = match self.axis() {
            Some(_) => vector(POINT, self.point).to_vec(),
            None => Vec::new(),
        };
        self.value_from.data(point, "value", self.value)
    }
    phi_tri_generic!();
}

impl GenericPhi for Absolute {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let at_pose = |pose: &Pose<S>| match self.axis() {
            Some(k) => Absolute::position_of(pose, slot2(data, 0))[k],
            None => pose.phi,
        };
        let value = self.value_from.value(data, |[start, _]| at_pose(&start));
        out[0] = at_pose(&Pose::of(self.pair.i, at.q)) - value;
    }
}

/// `absolute_x` / `absolute_y`: a global coordinate of a body point is constant.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AbsolutePoint {
    /// The body.
    pub body: String,
    /// The point (default: the centre of mass).
    #[serde(default)]
    pub point: PointRef,
    /// The value of the x (or y) coordinate, m. Default: its value in the initial configuration.
    #[serde(default)]
    pub value: Option<f64>,
}

/// Absolute angle of a body is constant. 1 equation.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AbsoluteAngleJoint {
    /// The body.
    pub body: String,
    /// The angle, rad. Default: its value in the initial configuration.
    #[serde(default)]
    pub value: Option<f64>,
}

/// An `absolute_x` joint at `path` compiled in `cx`.
pub(crate) fn compile_x(spec: &AbsolutePoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    held_point(AbsoluteKind::X, spec, cx, path)
}

/// An `absolute_y` joint at `path` compiled in `cx`.
pub(crate) fn compile_y(spec: &AbsolutePoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    held_point(AbsoluteKind::Y, spec, cx, path)
}

/// The joint holding coordinate `kind` (x or y) of a body point: its value as given, or as the
/// initial configuration has it.
fn held_point(
    kind: AbsoluteKind,
    spec: &AbsolutePoint,
    cx: &mut impl JointContext,
    path: &str,
) -> Option<CompiledJoint> {
    let AbsolutePoint { body, point, value } = spec;
    let (b, s) = cx.moving_point(path, body, point, "constrained")?;
    let (value, value_from) = match value {
        Some(v) => (cx.finite(&format!("{path}.value"), *v)?, Source::File),
        None => {
            let v = Frame::of_slice(b, cx.q0()).point(s)[if kind == AbsoluteKind::X { 0 } else { 1 }];
            (v, Source::start(b, BodyIx::GROUND, cx.q0()))
        }
    };
    Some((Box::new(Absolute { value_from, ..Absolute::new(kind, b, s, value) }), None))
}

/// An `absolute_angle` joint at `path` compiled in `cx`.
pub(crate) fn compile_angle(
    spec: &AbsoluteAngleJoint,
    cx: &mut impl JointContext,
    path: &str,
) -> Option<CompiledJoint> {
    let AbsoluteAngleJoint { body, value } = spec;
    let (b, _) = cx.moving_point(path, body, &PointRef::default(), "constrained")?;
    let (value, value_from) = match value {
        Some(v) => (cx.finite(&format!("{path}.value"), *v)?, Source::File),
        None => (b.coords(cx.q0())[2], Source::start(b, BodyIx::GROUND, cx.q0())),
    };
    Some((Box::new(Absolute { value_from, ..Absolute::new(AbsoluteKind::Angle, b, [0.0, 0.0], value) }), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{assert_data_fields, check_fd_random, check_generic_random, Lcg};

    #[test]
    fn derivatives_match_finite_differences() {
        let q0 = Lcg::new(6).vec(6, -2.0, 2.0);
        for (seed, kind) in [AbsoluteKind::X, AbsoluteKind::Y, AbsoluteKind::Angle].into_iter().enumerate() {
            let c = Absolute::new(kind, BodyIx(Some(3)), [0.4, -0.7], 0.25);
            check_fd_random(&c, 2, seed as u64);
            check_generic_random(&c, 2, seed as u64);
            if kind == AbsoluteKind::Angle {
                assert_data_fields::<AbsoluteAngleJoint>(&c);
            } else {
                assert_data_fields::<AbsolutePoint>(&c);
            }
            // The value from the initial configuration: the held coordinate there, not data.
            let mut start = Absolute { value_from: Source::start(BodyIx(Some(3)), BodyIx::GROUND, &q0), ..c.clone() };
            let mut phi = [0.0];
            Absolute { value: 0.0, ..start.clone() }.phi_at(&q0, 0.0, &mut phi);
            start.value = phi[0];
            assert_eq!(start.data().len(), c.data().len() - 1);
            check_generic_random(&start, 2, 10 + seed as u64);
            check_generic_random(&Absolute::coordinate(kind, BodyIx(Some(3)), [0.4, -0.7]), 2, 20 + seed as u64);
        }
    }

    /// Hand-derived: a bar at angle pi/2 with centre (1, 2); its end s' = (0.5, 0) is at
    /// (1, 2.5). x row: Phi = 1 - 0.2 = 0.8, d x_P / d phi = -0.5 sin(pi/2) = -0.5, gamma =
    /// (A s')_x omega^2 = 0 for x, and (A s')_y omega^2 = 0.5 * 9 = 4.5 for y (omega = 3).
    #[test]
    fn hand_derived_bar_end() {
        let q = [1.0, 2.0, std::f64::consts::FRAC_PI_2];
        let qdot = [0.1, -0.2, 3.0];
        let (mut phi, mut jac, mut g) = ([0.0], [0.0; 3], [0.0]);

        let x = Absolute::new(AbsoluteKind::X, BodyIx(Some(0)), [0.5, 0.0], 0.2);
        x.phi_at(&q, 0.0, &mut phi);
        x.jacobian_at(&q, 0.0, &mut jac);
        x.gamma_at(&q, &qdot, 0.0, &mut g);
        assert!((phi[0] - 0.8).abs() < 1e-14, "{phi:?}");
        assert!((jac[0] - 1.0).abs() < 1e-14 && jac[1] == 0.0 && (jac[2] + 0.5).abs() < 1e-14, "{jac:?}");
        assert!(g[0].abs() < 1e-14, "{g:?}");

        let y = Absolute::new(AbsoluteKind::Y, BodyIx(Some(0)), [0.5, 0.0], 2.5);
        y.phi_at(&q, 0.0, &mut phi);
        y.jacobian_at(&q, 0.0, &mut jac);
        y.gamma_at(&q, &qdot, 0.0, &mut g);
        assert!(phi[0].abs() < 1e-14, "{phi:?}");
        assert!(jac[0] == 0.0 && jac[1] == 1.0 && jac[2].abs() < 1e-14, "{jac:?}");
        assert!((g[0] - 4.5).abs() < 1e-14, "{g:?}");

        let a = Absolute::new(AbsoluteKind::Angle, BodyIx(Some(0)), [9.0, 9.0], 1.0);
        a.phi_at(&q, 0.0, &mut phi);
        a.jacobian_at(&q, 0.0, &mut jac);
        a.gamma_at(&q, &qdot, 0.0, &mut g);
        assert!((phi[0] - (std::f64::consts::FRAC_PI_2 - 1.0)).abs() < 1e-15);
        assert_eq!(jac, [0.0, 0.0, 1.0]);
        assert_eq!(g, [0.0]);
    }
}
