//! Cam and roller (or knife-edge) follower: the follower point `P` (the roller's centre) stays on
//! the cam's pitch curve, given in polar form `R(psi)` about the cam's centre `C` in the cam's
//! frame. One row.
//!
//! ```text
//! d     = A_i^T (r_j + A_j s'_j - r_i) - s'_i     (P relative to C, cam frame)
//! psi   = atan2(d_y, d_x)
//! Phi   = |d| - R(psi)
//! Phi_q = dPhi/dq over the two bodies' coordinates (one Dual pass per column)     (1 x 6)
//! nu    = 0
//! gamma = -qdot^T H qdot   (H the Hessian of Phi in q; one HyperDual pass)
//! ```
//! `R` is an expression of `psi` (its parameters and tables are constants), so every derivative
//! is exact: forward-mode automatic differentiation through `d`, `atan2`, `hypot` and `R`, as in
//! the general constraint (expression.rs). The pitch curve is the path of the roller's centre;
//! the cam's working surface is its inward offset by the roller radius, which the row does not
//! need. The row is undefined where `P` is at the centre (`d = 0`). Norton, Design of Machinery,
//! chapter 8; Haug (1989) section 3.5.
//!
//! Design sensitivities: the pitch-curve cam's numbers are its two points, and `R` reads the
//! parameters as inputs ([`Expr::eval_params`]); its pressure angle's slope `R'(psi)` at a `psi`
//! that carries derivatives is one evaluation over a number type with one more direction
//! ([`Nestable`]). The working-surface cam ([`CamProfile`]) has its own (cam_profile.rs).

use super::schema::JointContext;
use super::CompiledJoint;
use super::PointRef;
use super::{phi_tri_generic, slot2, vector, At, GenericPhi, POINT_I, POINT_J};
use super::{Anchor, BodyIx, CamProfile, Config, Constraint};
use super::{Curve, CurveError};
use crate::element::Pose;
use crate::expr::{Dual, Expr, HyperDual, Nestable, Scalar};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Where a cam joint measures from: the cam `i` with its centre `si`, the follower `j` with its
/// point `sj` (the roller's centre), each in its body's frame. Shared by the pitch-curve cam and
/// the working-surface cam ([`CamProfile`]).
#[derive(Debug, Clone, Copy)]
pub struct CamFrame {
    pub(crate) i: BodyIx,
    pub(crate) si: [f64; 2],
    pub(crate) j: BodyIx,
    pub(crate) sj: [f64; 2],
}

impl CamFrame {
    /// The coordinates `(x, y, phi)` of body `b` from `q`, each seeded by `seed(column index)`.
    #[inline]
    fn body<S: Scalar>(&self, b: BodyIx, q: &[f64], seed: &impl Fn(usize, f64) -> S) -> [S; 3] {
        match b.0 {
            None => [S::constant(0.0); 3],
            Some(c) => [seed(c, q[c]), seed(c + 1, q[c + 1]), seed(c + 2, q[c + 2])],
        }
    }

    /// `d`, the follower's point relative to the cam's centre in the cam's frame.
    #[inline]
    pub(crate) fn offset<S: Scalar>(&self, q: &[f64], seed: &impl Fn(usize, f64) -> S) -> [S; 2] {
        let [xi, yi, pi] = self.body(self.i, q, seed);
        let [xj, yj, pj] = self.body(self.j, q, seed);
        let (cj, sn) = (pj.cos(), pj.sin());
        let k = |v: f64| S::constant(v);
        let gx = xj + cj * k(self.sj[0]) - sn * k(self.sj[1]) - xi;
        let gy = yj + sn * k(self.sj[0]) + cj * k(self.sj[1]) - yi;
        let (ci, si) = (pi.cos(), pi.sin());
        [ci * gx + si * gy - k(self.si[0]), ci * gy - si * gx - k(self.si[1])]
    }

    /// `d` over any [`Scalar`] from all coordinates `q` and the two points `si`, `sj` (the cam's
    /// numbers, [`Cam::data`]'s order): [`CamFrame::offset`]'s arithmetic.
    #[inline]
    pub(crate) fn offset_generic<S: Scalar>(&self, q: &[S], si: [S; 2], sj: [S; 2]) -> [S; 2] {
        let (fi, fj) = (Pose::of(self.i, q), Pose::of(self.j, q));
        let a = fj.rotate(sj);
        let (gx, gy) = (fj.o[0] + a[0] - fi.o[0], fj.o[1] + a[1] - fi.o[1]);
        let (ci, si_) = (fi.phi.cos(), fi.phi.sin());
        [ci * gx + si_ * gy - si[0], ci * gy - si_ * gx - si[1]]
    }

    /// `point_i` and `point_j`.
    pub(crate) fn data(&self) -> Vec<(&'static str, f64)> {
        [vector(POINT_I, self.si), vector(POINT_J, self.sj)].concat()
    }

    /// The columns of the two bodies' coordinates.
    pub(crate) fn columns(&self) -> Vec<usize> {
        [self.i, self.j].iter().filter_map(|b| b.0).flat_map(|c| c..c + 3).collect()
    }

    /// The joint's reaction point: the cam's centre.
    pub(crate) fn anchor(&self) -> Anchor {
        Anchor { i: self.i, j: self.j, point: self.si }
    }
}

/// The cam's pitch curve `|d| = R(psi)` between the cam's centre and the follower's point.
#[derive(Debug, Clone)]
pub struct Cam {
    at: CamFrame,
    /// `R(psi)`, slot 0 the polar angle `psi`, m.
    radius: Expr,
    columns: Vec<usize>,
}

/// The pitch curve where the follower's point is: `(psi, R, dR/dpsi, dpsi/dt)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PitchPoint {
    /// Polar angle of the follower's point about the cam's centre, cam frame, rad.
    pub psi: f64,
    /// Pitch radius at `psi`, m.
    pub radius: f64,
    /// Its slope `dR/dpsi`, m/rad.
    pub slope: f64,
    /// `dpsi/dt`: how fast the point runs round the cam, rad/s.
    pub psi_rate: f64,
}

impl Cam {
    /// The row for the cam `i` (centre `si`, its frame) and the follower point `sj` of body `j`,
    /// the pitch radius `radius` an expression whose slot 0 is `psi`.
    ///
    /// # Errors
    ///
    /// `radius` uses a slot other than 0 (a name that is not `psi`).
    pub fn try_new(i: BodyIx, si: [f64; 2], j: BodyIx, sj: [f64; 2], radius: Expr) -> Result<Cam, String> {
        if radius.slots().iter().any(|&s| s != 0) {
            return Err("the pitch radius may name only psi, parameters and tables".into());
        }
        let at = CamFrame { i, si, j, sj };
        Ok(Cam { at, radius, columns: at.columns() })
    }

    /// `Phi = |d| - R(psi)`.
    #[inline]
    fn residual<S: Scalar>(&self, q: &[f64], seed: &impl Fn(usize, f64) -> S) -> S {
        let [dx, dy] = self.at.offset(q, seed);
        dx.hypot(dy) - self.radius.eval(&[dy.atan2(dx)])
    }

    /// Where the follower's point is on the pitch curve, and how fast it runs round it.
    pub fn pitch_point(&self, q: &[f64], qdot: &[f64]) -> PitchPoint {
        let [dx, dy] = self.at.offset(q, &|c, v| Dual { v, d: qdot[c] });
        let psi = dy.atan2(dx);
        let r = self.radius.eval(&[Dual { v: psi.v, d: 1.0 }]);
        PitchPoint { psi: psi.v, radius: r.v, slope: r.d, psi_rate: psi.d }
    }

    /// The pressure angle of a radial follower: `atan(sigma R' / R)`, `sigma = sign(dpsi/dt)`,
    /// rad, positive while the cam pushes the follower outward.
    pub fn pressure_angle(&self, q: &[f64], qdot: &[f64]) -> f64 {
        let p = self.pitch_point(q, qdot);
        // At rest the follower's direction of motion is taken as the rise's (psi falling as the
        // cam turns counter-clockwise under it), whatever the sign of the zero.
        let sense = if p.psi_rate > 0.0 { 1.0 } else { -1.0 };
        (sense * p.slope).atan2(p.radius)
    }

    /// [`Cam::pressure_angle`] over a number type that carries derivatives, with the cam's
    /// numbers `data` ([`Constraint::data`]) and the parameters `params`; the sense `sigma` is
    /// that of the values.
    fn pressure_angle_generic<S: Nestable>(&self, q: &[S], qdot: &[S], data: &[S], params: &[S]) -> S {
        let values = |x: &[S]| x.iter().map(|v| v.value()).collect::<Vec<f64>>();
        let sense = if self.pitch_point(&values(q), &values(qdot)).psi_rate > 0.0 { 1.0 } else { -1.0 };
        let [dx, dy] = self.at.offset_generic(q, slot2(data, 0), slot2(data, 2));
        let psi = dy.atan2(dx);
        let up: Vec<S::Up> = params.iter().map(|p| p.seed(0.0)).collect();
        let slope = S::slope(self.radius.eval_params(&[psi.seed(1.0)], &up));
        (S::constant(sense) * slope).atan2(self.radius.eval_params(&[psi], params))
    }
}

impl GenericPhi for Cam {
    fn parameters(&self) -> &[usize] {
        self.radius.parameters()
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let [dx, dy] = self.at.offset_generic(at.q, slot2(data, 0), slot2(data, 2));
        out[0] = dx.hypot(dy) - self.radius.eval_params(&[dy.atan2(dx)], at.params);
    }
}

/// A cam joint's row: on a pitch curve ([`Cam`]) or on a working surface ([`CamProfile`]).
#[derive(Debug, Clone)]
pub enum CamRow {
    /// The follower's point on the polar pitch curve.
    Pitch(Cam),
    /// The roller tangent to the working surface.
    Surface(CamProfile),
}

impl CamRow {
    /// The pressure angle of a radial follower, rad ([`Cam::pressure_angle`],
    /// [`CamProfile::pressure_angle`]).
    pub fn pressure_angle(&self, q: &[f64], qdot: &[f64]) -> f64 {
        match self {
            CamRow::Pitch(c) => c.pressure_angle(q, qdot),
            CamRow::Surface(c) => c.pressure_angle(q, qdot),
        }
    }

    /// The pressure angle over a number type that carries derivatives, with the cam's numbers
    /// `data` ([`Constraint::data`]) and the parameters `params`.
    pub fn pressure_angle_generic<S: Nestable>(&self, q: &[S], qdot: &[S], data: &[S], params: &[S]) -> S {
        match self {
            CamRow::Pitch(c) => c.pressure_angle_generic(q, qdot, data, params),
            CamRow::Surface(c) => c.pressure_angle_generic(q, qdot, data, params),
        }
    }

    /// The cam's numbers a parameter can move ([`Constraint::data`]).
    pub fn data(&self) -> Vec<(&'static str, f64)> {
        match self {
            CamRow::Pitch(c) => c.data(),
            CamRow::Surface(c) => c.data(),
        }
    }

    /// The row as a constraint.
    pub fn boxed(self) -> Box<dyn Constraint> {
        match self {
            CamRow::Pitch(c) => Box::new(c),
            CamRow::Surface(c) => Box::new(c),
        }
    }
}

impl Constraint for Cam {
    fn anchor(&self) -> Anchor {
        self.at.anchor()
    }
    fn row_names(&self) -> &[&'static str] {
        &["pitch curve"]
    }
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.residual(q, &|_, v| v);
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        for (o, &col) in out.iter_mut().zip(&self.columns) {
            *o = self.residual(q, &|c, v| Dual { v, d: if c == col { 1.0 } else { 0.0 } }).d;
        }
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = -self.residual(q, &|c, v| HyperDual::seed(v, qdot[c], qdot[c])).e12;
    }
    /// `point_i` and `point_j`.
    fn data(&self) -> Vec<(&'static str, f64)> {
        self.at.data()
    }
    phi_tri_generic!();
}

/// Cam and roller (or knife-edge) follower, the cam given by one of: its pitch curve `radius`
/// (the path of the roller's centre, polar), or its working surface, `surface_radius` (polar) or
/// `profile` (a closed Cartesian curve), which the roller of `roller_radius` touches from outside
/// (docs/model-format.md, "Cams"). 1 equation.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CamJoint {
    /// The cam.
    pub body_i: String,
    /// The cam's centre, body i frame: the origin of `psi` and of the profile. Default: its
    /// frame's origin.
    #[serde(default)]
    pub point_i: PointRef,
    /// The follower.
    pub body_j: String,
    /// The roller's centre (the knife edge), body j frame.
    pub point_j: PointRef,
    /// The pitch radius, m: an expression of the polar angle `psi` (rad, cam frame, from the
    /// cam's x axis), parameters and tables, e.g. `"0.05 + cycloidal(psi, 0, 0, 2*pi/3, 0.02)"`.
    /// The pitch curve `|d| = radius(psi)` is the path of the roller's centre. Give one of
    /// `radius`, `surface_radius` and `profile`.
    #[serde(default)]
    pub radius: Option<String>,
    /// The working surface's radius, m: an expression of the polar angle `psi` (as `radius`), the
    /// surface `radius(psi) (cos psi, sin psi)` about `point_i` in the cam's frame.
    #[serde(default)]
    pub surface_radius: Option<String>,
    /// The working surface as a closed curve about `point_i` in the cam's frame.
    #[serde(default)]
    pub profile: Option<CamProfileSpec>,
    /// The roller's radius, m: the pitch curve's offset to the surface. Default: 0, a knife edge
    /// (on a profile or surface radius: a point on the curve).
    #[serde(default)]
    pub roller_radius: f64,
}

/// A cam's working surface as a closed curve `(x, y)` about the cam's centre in its frame, m:
/// expressions `x(u)`, `y(u)` of a parameter `u` over one `period`; or points in order (the last
/// joined to the first), inline or two columns of a CSV file, joined by periodic cubic splines
/// over their chord length.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CamProfileSpec {
    /// A CSV file whose first row names its columns, relative to the model file's folder (the
    /// working folder for a model given as text). With it, `x` and `y` are column names.
    #[serde(default)]
    pub file: Option<String>,
    /// An expression of `u`, parameters and tables; the points' x coordinates, m; or, with
    /// `file`, the name of their column.
    pub x: ProfileColumn,
    /// As `x`, for y.
    pub y: ProfileColumn,
    /// The period of `u` for expressions (the curve closes: the same point and slope at `u = 0`
    /// and `u = period`). Default: `2 pi`. Points take none (their parameter is the chord
    /// length).
    #[serde(default)]
    pub period: Option<f64>,
}

/// A coordinate of a cam profile: the points' values, or text (an expression of `u`, or a column
/// of the profile's file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "an expression of u (text), a list of numbers (the points' coordinates, m), or with `file:` the name of a column"
)]
pub enum ProfileColumn {
    /// The points' coordinates.
    Values(Vec<f64>),
    /// An expression of `u`, or a column of the file.
    Text(String),
}

/// A cam joint at `path` compiled in `cx`.
pub(crate) fn compile(cam: &CamJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    Some((cam_row(cam, cx, path)?.boxed(), None))
}

/// A cam joint's row at `path` compiled in `cx`: its ends, and its pitch curve (`radius`) or its
/// working surface (`surface_radius`, `profile`) with the roller on it. Every field is read
/// before any problem returns, so that each is reported.
pub(crate) fn cam_row(cam: &CamJoint, cx: &mut impl JointContext, path: &str) -> Option<CamRow> {
    let CamJoint { body_i, point_i, body_j, point_j, radius, surface_radius, profile, roller_radius } = cam;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j);
    let roller = cx.non_negative(&format!("{path}.roller_radius"), *roller_radius);
    // Either the pitch radius (`Ok`) or the surface (`Err`), each `None` when it has a problem.
    let given = match (radius, surface_radius, profile) {
        (Some(r), None, None) => {
            Ok(cx.curve_expr(&format!("{path}.radius"), r, "psi", "the polar angle of the follower's point"))
        }
        (None, Some(r), None) => {
            let expr = cx.curve_expr(&format!("{path}.surface_radius"), r, "psi", "the polar angle of the surface");
            Err(expr.and_then(|e| curve_at(cx, path, Curve::polar(e))))
        }
        (None, None, Some(p)) => Err(profile_curve(cx, &format!("{path}.profile"), p)),
        _ => {
            let message = "give one of radius (the pitch curve), surface_radius or profile (the working surface)";
            cx.problem(path, message);
            return None;
        }
    };
    let ([(i, si), (j, sj)], roller) = (ends?, roller?);
    let expr = match given {
        Ok(expr) => expr?,
        Err(curve) => {
            return match CamProfile::try_new([(i, si), (j, sj)], curve?, roller) {
                Ok(c) => Some(CamRow::Surface(c)),
                Err(e) => {
                    cx.problem(format!("{path}.{}", e.field), e.message);
                    None
                }
            };
        }
    };
    // Closer than 1e-12 m the follower's polar angle about the centre is round-off.
    if cx.initial_distance([(i, si), (j, sj)]) < 1e-12 {
        let message = "the follower's point is at the cam's centre in the initial configuration: psi is undefined";
        cx.problem(path, message);
        return None;
    }
    match Cam::try_new(i, si, j, sj, expr) {
        Ok(c) => Some(CamRow::Pitch(c)),
        Err(e) => {
            cx.problem(format!("{path}.radius"), e);
            None
        }
    }
}

/// A curve, or its problem at its field of the joint at `path`.
fn curve_at(cx: &mut impl JointContext, path: &str, curve: Result<Curve, CurveError>) -> Option<Curve> {
    curve.map_err(|e| cx.problem(format!("{path}.{}", e.field), e.message)).ok()
}

/// Whether the points of a profile at `path` come without a `period`; a problem there when not.
fn no_period(cx: &mut impl JointContext, path: &str, period: Option<f64>) -> bool {
    if period.is_some() {
        cx.problem(format!("{path}.period"), "points take no period (their parameter is the chord length)");
        return false;
    }
    true
}

/// A cam's `profile` at `path`: expressions of `u`, or points inline or from a file.
fn profile_curve(cx: &mut impl JointContext, path: &str, p: &CamProfileSpec) -> Option<Curve> {
    use ProfileColumn::{Text, Values};
    let joint = path.strip_suffix(".profile").unwrap_or(path).to_string();
    let points = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(&a, &b)| [a, b]).collect::<Vec<[f64; 2]>>();
    let curve = match (&p.file, &p.x, &p.y) {
        (None, Text(x), Text(y)) => {
            let period = match p.period {
                Some(v) => cx.positive(&format!("{path}.period"), v),
                // A parameter u that is an angle round the cam: one turn.
                None => Some(2.0 * std::f64::consts::PI),
            };
            let x = cx.curve_expr(&format!("{path}.x"), x, "u", "the profile's parameter");
            let y = cx.curve_expr(&format!("{path}.y"), y, "u", "the profile's parameter");
            Curve::parametric(x?, y?, period?)
        }
        (None, Values(x), Values(y)) => {
            if x.len() != y.len() {
                let message = format!("x has {} values and y {}; expected as many of each", x.len(), y.len());
                cx.problem(path, message);
                return None;
            }
            if !no_period(cx, path, p.period) {
                return None;
            }
            Curve::points(&points(x, y))
        }
        (Some(file), Text(x), Text(y)) => {
            if !no_period(cx, path, p.period) {
                return None;
            }
            let (x, y) = cx.csv_columns(path, file, x, y)?;
            Curve::points(&points(&x, &y))
        }
        (Some(_), x, y) => {
            for (field, c) in [("x", x), ("y", y)] {
                if matches!(c, Values(_)) {
                    cx.problem(format!("{path}.{field}"), "expected the name of a column of the file");
                }
            }
            return None;
        }
        (None, _, _) => {
            cx.problem(path, "expected x and y both expressions of u (text) or both lists of numbers (points)");
            return None;
        }
    };
    curve_at(cx, &joint, curve)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{assert_data_fields, check_fd_random, check_generic_random, OnSlice};

    fn radius(src: &str) -> Expr {
        Expr::parse(src, &mut |n| if n == "psi" { Ok(0) } else { Err(format!("unknown {n}")) }).unwrap()
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let r = radius("1 + 0.2*sin(psi) + 0.05*cos(3*psi)");
        let cam = Cam::try_new(BodyIx(Some(0)), [0.1, -0.2], BodyIx(Some(3)), [0.3, 0.1], r.clone()).unwrap();
        assert_eq!(cam.columns(), [0, 1, 2, 3, 4, 5]);
        check_fd_random(&cam, 2, 11);
        check_generic_random(&cam, 2, 13);
        assert_data_fields::<CamJoint>(&cam);
        let grounded = Cam::try_new(BodyIx::GROUND, [0.0, 0.0], BodyIx(Some(0)), [0.2, 0.0], r).unwrap();
        assert_eq!(grounded.columns(), [0, 1, 2]);
        check_fd_random(&grounded, 1, 12);
        check_generic_random(&grounded, 1, 14);
    }

    /// A circle of radius 2 about the cam's centre: the row is the distance's, `|d| - 2`; at
    /// `d = (3, 4)` with the follower moving at `(vx, vy) = (1, 0)`, `Phi = 3`,
    /// `Phi_q = d/|d| = (0.6, 0.8)` and `gamma = -|v|^2 (1 - (d.v/|d||v|)^2)/|d| = -(1 - 0.36)/5`.
    #[test]
    fn hand_derived_circle() {
        let cam = Cam::try_new(BodyIx::GROUND, [0.0, 0.0], BodyIx(Some(0)), [0.0, 0.0], radius("2")).unwrap();
        let q = [3.0, 4.0, 0.7];
        let (mut phi, mut jac, mut g) = ([0.0], [0.0; 3], [0.0]);
        cam.phi_at(&q, 0.0, &mut phi);
        cam.jacobian_at(&q, 0.0, &mut jac);
        cam.gamma_at(&q, &[1.0, 0.0, 5.0], 0.0, &mut g);
        assert!((phi[0] - 3.0).abs() < 1e-15, "{phi:?}");
        assert!((jac[0] - 0.6).abs() < 1e-15 && (jac[1] - 0.8).abs() < 1e-15 && jac[2].abs() < 1e-15, "{jac:?}");
        assert!((g[0] + 0.64 / 5.0).abs() < 1e-15, "{g:?}");
    }

    #[test]
    fn a_radius_of_other_names_is_refused() {
        let expr = Expr::parse("psi + x", &mut |n| Ok(if n == "psi" { 0 } else { 1 })).unwrap();
        let err = Cam::try_new(BodyIx::GROUND, [0.0; 2], BodyIx(Some(0)), [0.0; 2], expr).unwrap_err();
        assert!(err.contains("only psi"), "{err}");
    }
}
