//! Drivers: rheonomic constraints that prescribe a coordinate as a function of time,
//! `g(q) - f(t) = 0`. One row each.
//!
//! ```text
//! kind            g(q)                  g_q                                     gamma_g
//! Angle           phi_i                 [ 0 0 1 ]                               0
//! RelativeAngle   phi_i - phi_j         [ 0 0 1   0 0 -1 ]                      0
//! Distance        |d|, d = r_Q - r_P    e^T [ -I  -B_i s'_P  I  B_j s'_Q ]      -(d'.d' - (e.d')^2 + d.d''_free) / |d|
//! X               x_i + (A_i s'_P)_x    [ 1 0 (B_i s'_P)_x ]                    (A_i s'_P)_x omega_i^2
//! Y               y_i + (A_i s'_P)_y    [ 0 1 (B_i s'_P)_y ]                    (A_i s'_P)_y omega_i^2
//!
//! Phi   = g(q) - f(t),   Phi_q = g_q,   nu = -Phi_t = f'(t),   gamma = gamma_g + f''(t)
//! ```
//! with `e = d / |d|` and `d''_free = A_i s'_P omega_i^2 - A_j s'_Q omega_j^2`. `f`, `f'`, `f''`
//! are exact (automatic differentiation of the time function).
//!
//! The distance driver uses `|d|`, not `d . d`, so that its multiplier is the force along the line
//! `P Q` (its effort); it is singular when `P` and `Q` coincide (`|d| = 0`, division by zero), which
//! the prescribed `f(t)` must keep away from. Haug (1989) section 3.5; Nikravesh (2018) section 7.5.

use super::schema::JointContext;
use super::PointRef;
use super::{dot, Absolute, AbsoluteKind, Anchor, BodyIx, Config, Constraint, Pair, PointPair};
use super::{phi_tri_generic, separation, slot2, vector, At, GenericPhi, Pose, POINT_I, POINT_J};
use crate::element::fields;
use crate::expr::{Scalar, TimeFunction};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What a [`Driver`] prescribes.
#[derive(Debug, Clone, PartialEq)]
pub enum DriverKind {
    /// The angle of a body (rad).
    Angle { body: BodyIx },
    /// `phi_i - phi_j` (rad).
    RelativeAngle { i: BodyIx, j: BodyIx },
    /// The distance from point `s_p` of body i to point `s_q` of body j (m).
    Distance { i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2] },
    /// The global x of a body point (m).
    X { body: BodyIx, point: [f64; 2] },
    /// The global y of a body point (m).
    Y { body: BodyIx, point: [f64; 2] },
}

/// A coordinate prescribed as a function of time.
#[derive(Debug)]
pub struct Driver {
    kind: DriverKind,
    f: TimeFunction,
    /// `g(q)`: a time-independent one-row constraint (its `nu` is zero).
    g: Coordinate,
}

/// The coordinate `g(q)` a [`Driver`] prescribes.
#[derive(Debug)]
enum Coordinate {
    /// An angle, x or y ([`Absolute::coordinate`]).
    Held(Absolute),
    /// `phi_i - phi_j`.
    Relative(RelativeAngle),
    /// `|d|`.
    Length(Length),
}

impl Coordinate {
    /// The coordinate as a constraint row.
    #[inline]
    fn row(&self) -> &dyn Constraint {
        match self {
            Coordinate::Held(c) => c,
            Coordinate::Relative(c) => c,
            Coordinate::Length(c) => c,
        }
    }
}

impl GenericPhi for Coordinate {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        match self {
            Coordinate::Held(c) => c.phi_generic(at, data, out),
            Coordinate::Relative(c) => c.phi_generic(at, data, out),
            Coordinate::Length(c) => c.phi_generic(at, data, out),
        }
    }
}

impl Driver {
    /// The row `g(q) - f(t)` for the coordinate `g` that `kind` names.
    pub fn new(kind: DriverKind, f: TimeFunction) -> Driver {
        let g = match kind {
            DriverKind::Angle { body } => Coordinate::Held(Absolute::coordinate(AbsoluteKind::Angle, body, [0.0; 2])),
            DriverKind::X { body, point } => Coordinate::Held(Absolute::coordinate(AbsoluteKind::X, body, point)),
            DriverKind::Y { body, point } => Coordinate::Held(Absolute::coordinate(AbsoluteKind::Y, body, point)),
            DriverKind::RelativeAngle { i, j } => Coordinate::Relative(RelativeAngle { pair: Pair::new(i, j) }),
            DriverKind::Distance { i, s_p, j, s_q } => Coordinate::Length(Length(PointPair::new(i, s_p, j, s_q))),
        };
        Driver { kind, f, g }
    }

    /// `f(t)` over any [`Scalar`] at `at`, with the parameters of `at` (so that its derivative
    /// along a parameter is there): the one place the generic `Phi` evaluates the prescribed
    /// function.
    #[inline]
    fn prescribed<S: Scalar>(&self, at: &At<'_, S>) -> S {
        self.f.eval_params(at.t, at.params)
    }

    /// What this driver prescribes.
    pub fn kind(&self) -> &DriverKind {
        &self.kind
    }

    /// The prescribed function of time.
    pub fn function(&self) -> &TimeFunction {
        &self.f
    }
}

impl Constraint for Driver {
    fn time_function(&self) -> Option<&TimeFunction> {
        Some(&self.f)
    }
    fn driven(&self) -> Option<&DriverKind> {
        Some(&self.kind)
    }
    fn anchor(&self) -> Anchor {
        self.g.row().anchor()
    }
    fn row_names(&self) -> &[&'static str] {
        self.g.row().row_names()
    }
    fn columns(&self) -> &[usize] {
        self.g.row().columns()
    }
    fn phi(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        self.g.row().phi(q, t, out);
        out[0] -= self.f.eval(t).0;
    }
    fn jacobian(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        self.g.row().jacobian(q, t, out);
    }
    fn nu(&self, _q: &Config<'_>, t: f64, out: &mut [f64]) {
        out[0] = self.f.eval(t).1;
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], t: f64, out: &mut [f64]) {
        self.g.row().gamma(q, qdot, t, out);
        out[0] += self.f.eval(t).2;
    }
    /// The coordinate's: `point` of an x or y driver, `point_i` and `point_j` of a distance
    /// driver, none for an angle (the function's numbers are parameters, read from `At`).
    fn data(&self) -> Vec<(&'static str, f64)> {
        self.g.row().data()
    }
    phi_tri_generic!();
}

impl GenericPhi for Driver {
    fn parameters(&self) -> &[usize] {
        self.f.expr().parameters()
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        self.g.phi_generic(at, data, out);
        out[0] = out[0] - self.prescribed(at);
    }
}

/// `phi_i - phi_j`.
#[derive(Debug)]
struct RelativeAngle {
    pair: Pair,
}

impl Constraint for RelativeAngle {
    fn anchor(&self) -> Anchor {
        self.pair.anchor([0.0, 0.0])
    }
    fn row_names(&self) -> &[&'static str] {
        &["relative_angle"]
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.pair.i.coords(q)[2] - self.pair.j.coords(q)[2];
    }
    fn jacobian(&self, _q: &Config<'_>, _t: f64, out: &mut [f64]) {
        self.pair.scatter([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], out);
    }
    fn gamma(&self, _q: &Config<'_>, _qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = 0.0;
    }
}

impl GenericPhi for RelativeAngle {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, _data: &[S], out: &mut [S]) {
        out[0] = self.pair.i.pose(at.q)[2] - self.pair.j.pose(at.q)[2];
    }
}

/// `|d|`, `d = r_Q - r_P`.
#[derive(Debug)]
struct Length(PointPair);

impl Constraint for Length {
    fn anchor(&self) -> Anchor {
        self.0.anchor()
    }
    fn row_names(&self) -> &[&'static str] {
        &["distance"]
    }
    fn columns(&self) -> &[usize] {
        self.0.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let d = self.0.separation(q).d;
        out[0] = dot(d, d).sqrt();
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let sep = self.0.separation(q);
        let len = dot(sep.d, sep.d).sqrt();
        let (bi, bj) = sep.chain([sep.d[0] / len, sep.d[1] / len]);
        self.0.pair.scatter(bi, bj, out);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        let sep = self.0.separation(q);
        let (qd_i, qd_j) = (self.0.pair.i.coords(qdot), self.0.pair.j.coords(qdot));
        let rate = sep.rate(qd_i, qd_j);
        let free = sep.accel_free(qd_i[2], qd_j[2]);
        let len = dot(sep.d, sep.d).sqrt();
        let along = dot(sep.d, rate) / len;
        out[0] = -(dot(rate, rate) - along * along + dot(sep.d, free)) / len;
    }
    /// `point_i`, `point_j`.
    fn data(&self) -> Vec<(&'static str, f64)> {
        [vector(POINT_I, self.0.s_p), vector(POINT_J, self.0.s_q)].concat()
    }
}

impl GenericPhi for Length {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let pair = &self.0.pair;
        let d = separation(&Pose::of(pair.i, at.q), slot2(data, 0), &Pose::of(pair.j, at.q), slot2(data, 2));
        out[0] = dot(d, d).sqrt();
    }
}

/// Angle of `body`, rad.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AngleDriver {
    /// The driven body.
    pub body: String,
    /// Angle as a function of `t`, rad.
    pub function: String,
}

/// Angle of `body_i` minus angle of `body_j`, rad.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RelativeAngleDriver {
    /// First body.
    pub body_i: String,
    /// Second body.
    pub body_j: String,
    /// Relative angle as a function of `t`, rad.
    pub function: String,
}

fields! {
    /// Distance between two points, m.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct DistanceDriver {
        [body_i, point_i, body_j, point_j,]
        /// Distance as a function of `t`, m (must stay positive).
        pub function: String,
    }
}

/// `x` / `y` drivers: a global coordinate of a body point.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PointDriver {
    /// The body.
    pub body: String,
    /// The point (default: the centre of mass).
    #[serde(default)]
    pub point: PointRef,
    /// The x (or y) coordinate as a function of `t`, m.
    pub function: String,
}

/// The driver of `kind` prescribing `function` (the field at `path`), or `None` when either has
/// a problem.
fn driver(
    cx: &mut impl JointContext,
    path: &str,
    kind: Option<DriverKind>,
    function: &str,
) -> Option<Box<dyn Constraint>> {
    let f = cx.time_function(&format!("{path}.function"), function);
    Some(Box::new(Driver::new(kind?, f?)))
}

/// An `angle` driver at `path` compiled in `cx`.
pub(crate) fn compile_angle(spec: &AngleDriver, cx: &mut impl JointContext, path: &str) -> Option<Box<dyn Constraint>> {
    let b = cx.moving_point(path, &spec.body, &PointRef::default(), "driven");
    driver(cx, path, b.map(|(body, _)| DriverKind::Angle { body }), &spec.function)
}

/// A `relative_angle` driver at `path` compiled in `cx`.
pub(crate) fn compile_relative(
    spec: &RelativeAngleDriver,
    cx: &mut impl JointContext,
    path: &str,
) -> Option<Box<dyn Constraint>> {
    let origin = PointRef::default();
    let ends = cx.ends(path, &spec.body_i, &origin, &spec.body_j, &origin);
    driver(cx, path, ends.map(|[(i, _), (j, _)]| DriverKind::RelativeAngle { i, j }), &spec.function)
}

/// A `distance` driver at `path` compiled in `cx`.
pub(crate) fn compile_distance(
    spec: &DistanceDriver,
    cx: &mut impl JointContext,
    path: &str,
) -> Option<Box<dyn Constraint>> {
    let ends = cx.ends(path, &spec.body_i, &spec.point_i, &spec.body_j, &spec.point_j);
    let kind = ends.map(|[(i, s_p), (j, s_q)]| DriverKind::Distance { i, s_p, j, s_q });
    driver(cx, path, kind, &spec.function)
}

/// An `x` driver at `path` compiled in `cx`.
pub(crate) fn compile_x(spec: &PointDriver, cx: &mut impl JointContext, path: &str) -> Option<Box<dyn Constraint>> {
    let bp = cx.moving_point(path, &spec.body, &spec.point, "driven");
    driver(cx, path, bp.map(|(body, point)| DriverKind::X { body, point }), &spec.function)
}

/// A `y` driver at `path` compiled in `cx`.
pub(crate) fn compile_y(spec: &PointDriver, cx: &mut impl JointContext, path: &str) -> Option<Box<dyn Constraint>> {
    let bp = cx.moving_point(path, &spec.body, &spec.point, "driven");
    driver(cx, path, bp.map(|(body, point)| DriverKind::Y { body, point }), &spec.function)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{assert_data_fields, check_fd_random_where, check_generic_random_where};
    use crate::constraints::{ConfigBuf, Separation};

    fn f() -> TimeFunction {
        TimeFunction::parse("0.3 + 2*t + 0.5*sin(3*t)").unwrap()
    }

    fn kinds(a: BodyIx, b: BodyIx) -> [DriverKind; 5] {
        [
            DriverKind::Angle { body: a },
            DriverKind::RelativeAngle { i: a, j: b },
            DriverKind::Distance { i: a, s_p: [0.3, -0.2], j: b, s_q: [-1.1, 0.4] },
            DriverKind::X { body: a, point: [0.4, -0.7] },
            DriverKind::Y { body: a, point: [0.4, -0.7] },
        ]
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let (a, b, g) = (BodyIx(Some(0)), BodyIx(Some(3)), BodyIx::GROUND);
        for (seed, (p, r)) in [(a, b), (b, g), (g, a)].into_iter().enumerate() {
            for (k, kind) in kinds(p, r).into_iter().enumerate() {
                let d = Driver::new(kind.clone(), f());
                assert_eq!(d.kind(), &kind);
                // The distance row is singular at |d| = 0, and finite differences lose accuracy
                // near it: check where the points are at least 1 apart.
                let apart = |q: &[f64]| match kind {
                    DriverKind::Distance { i, s_p, j, s_q } => {
                        let d = Separation::of(i, s_p, j, s_q, &ConfigBuf::new(q).view()).d;
                        dot(d, d) > 1.0
                    }
                    _ => true,
                };
                check_fd_random_where(&d, 2, (10 * seed + k) as u64, &apart);
                check_generic_random_where(&d, 2, (10 * seed + k) as u64, &apart);
                let names: Vec<&str> = d.data().iter().map(|(name, _)| *name).collect();
                let want: &[&str] = match kind {
                    DriverKind::Angle { .. } | DriverKind::RelativeAngle { .. } => &[],
                    DriverKind::Distance { .. } => &["point_i[0]", "point_i[1]", "point_j[0]", "point_j[1]"],
                    DriverKind::X { .. } | DriverKind::Y { .. } => &["point[0]", "point[1]"],
                };
                assert_eq!(names, want);
                match kind {
                    DriverKind::Angle { .. } => assert_data_fields::<AngleDriver>(&d),
                    DriverKind::RelativeAngle { .. } => assert_data_fields::<RelativeAngleDriver>(&d),
                    DriverKind::Distance { .. } => assert_data_fields::<DistanceDriver>(&d),
                    DriverKind::X { .. } | DriverKind::Y { .. } => assert_data_fields::<PointDriver>(&d),
                }
            }
        }
    }

    /// Hand-derived: f(t) = 0.3 + 2 t + 0.5 sin(3 t) at t = 0: f = 0.3, f' = 3.5, f'' = 0.
    /// At t = pi / 6: f = 0.8 + pi / 3, f' = 2, f'' = -4.5.
    /// Distance driver from the ground origin to the centre of a body at (3, 4), moving at (0, 1):
    /// |d| = 5, Phi_y = 4 / 5, d' = (0, 1), e . d' = 0.8, gamma_g = -(1 - 0.64) / 5 = -0.072.
    #[test]
    fn hand_derived_distance_and_angle() {
        let kind = DriverKind::Distance { i: BodyIx::GROUND, s_p: [0.0; 2], j: BodyIx(Some(0)), s_q: [0.0; 2] };
        let d = Driver::new(kind, f());
        let q = [3.0, 4.0, 1.0];
        let qdot = [0.0, 1.0, 0.5];
        let t = std::f64::consts::FRAC_PI_6;
        let (mut phi, mut jac, mut nu, mut g) = ([0.0], [0.0; 3], [0.0], [0.0]);
        d.phi_at(&q, t, &mut phi);
        d.jacobian_at(&q, t, &mut jac);
        d.nu_at(&q, t, &mut nu);
        d.gamma_at(&q, &qdot, t, &mut g);
        assert!((phi[0] - (5.0 - 0.8 - std::f64::consts::FRAC_PI_3)).abs() < 1e-14, "{phi:?}");
        assert!((jac[0] - 0.6).abs() < 1e-15 && (jac[1] - 0.8).abs() < 1e-15 && jac[2] == 0.0, "{jac:?}");
        assert!((nu[0] - 2.0).abs() < 1e-14, "{nu:?}");
        assert!((g[0] - (-0.072 - 4.5)).abs() < 1e-14, "{g:?}");

        let a = Driver::new(DriverKind::Angle { body: BodyIx(Some(0)) }, f());
        a.phi_at(&q, 0.0, &mut phi);
        a.nu_at(&q, 0.0, &mut nu);
        a.gamma_at(&q, &qdot, 0.0, &mut g);
        assert!((phi[0] - 0.7).abs() < 1e-15 && (nu[0] - 3.5).abs() < 1e-15 && g[0].abs() < 1e-15);
        assert_eq!(a.row_names(), ["angle"]);
    }
}
