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

use super::{Anchor, BodyIx, CamProfile, Config, Constraint};
use crate::expr::{Dual, Expr, HyperDual, Scalar};

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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{check_fd_random, OnSlice};

    fn radius(src: &str) -> Expr {
        Expr::parse(src, &mut |n| if n == "psi" { Ok(0) } else { Err(format!("unknown {n}")) }).unwrap()
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let r = radius("1 + 0.2*sin(psi) + 0.05*cos(3*psi)");
        let cam = Cam::try_new(BodyIx(Some(0)), [0.1, -0.2], BodyIx(Some(3)), [0.3, 0.1], r.clone()).unwrap();
        assert_eq!(cam.columns(), [0, 1, 2, 3, 4, 5]);
        check_fd_random(&cam, 2, 11);
        let grounded = Cam::try_new(BodyIx::GROUND, [0.0, 0.0], BodyIx(Some(0)), [0.2, 0.0], r).unwrap();
        assert_eq!(grounded.columns(), [0, 1, 2]);
        check_fd_random(&grounded, 1, 12);
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
