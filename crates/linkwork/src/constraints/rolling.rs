//! Rolling without slip on a line: a rack and pinion (one row), and a disc rolling on a line of
//! another body (two rows). The line is the rack's pitch line, or the surface the disc rolls on,
//! through `L` (`s'_L` on the line body) along `v'_L`; the pinion or disc has centre `C` and
//! radius `rho`.
//!
//! ```text
//! u       = A_l v'_L / |v'_L|,   n = R90 u,   d = r_C - r_L
//! side    = sign of n . d at the initial configuration (+1 when 0): +1 when the disc is on the
//!           left of v'_L
//! contact = n . d - side rho                                         (disc only)
//! rolling = u . d + side rho (phi_disc - phi_line) - c               (c from the initial configuration)
//! ```
//! Both are rows `w . d` (`w = n`, `w = u`) plus, for the rolling row, the linear term, which adds
//! the constant entries `+side rho` (`phi_disc`) and `-side rho` (`phi_line`) to the Jacobian and
//! nothing to gamma:
//! ```text
//! Phi_q_line = [ -w^T   (R90 w) . d - w . B_l s'_L ]      Phi_q_disc = [ w^T   w . B_c s'_C ]
//! nu         = 0
//! gamma      = (w . d) omega_l^2 - 2 omega_l (R90 w) . d' + w . (A_c s'_C omega_c^2 - A_l s'_L omega_l^2)
//! ```
//!
//! Why the rolling row: the contact point is `K = C - side rho n`. The disc's material point at `K`
//! moves at `v_C + side rho omega_disc u`; the line body's material point there at
//! `v_L + omega_line R90 (K - r_L)`, whose `u` component is `u . v_L - omega_line (n . d - side rho)`.
//! Their difference along `u`, the slip, is
//! `u . (v_C - v_L) + side rho omega_disc + omega_line (n . d - side rho)`, which (with
//! `u' = omega_line n`) is exactly the time derivative of the rolling row. So a pinion on the left of a fixed rack (`side = +1`) rolling along `+u`
//! turns clockwise and one on the right turns counterclockwise; the side is fixed once, from the
//! initial configuration, so that the row is right whichever way `v'_L` points.
//!
//! A rack and pinion keeps the centre distance by other joints (typically the pinion pinned to the
//! frame and the rack on a translational joint), so it has only the rolling row; a rolling disc
//! adds the contact row. Haug (1989) section 3.4.5; Nikravesh (2018) section 7.4.

use super::schema::JointContext;
use super::CompiledJoint;
use super::PointRef;
use super::{perp, unit, Anchor, BodyIx, Config, ConfigBuf, Constraint, Pair, Projection, Shape, Sketch};
use super::{phi_tri_generic, projection, slot2, vector, At, GenericPhi, Pose, Source, AXIS_J, POINT_I, POINT_J};
use crate::element::End;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The no-slip row shared by [`RackPinion`] and [`RollingDisc`].
#[derive(Debug, Clone)]
struct RollingRow {
    /// `u . d`, with `i` the line body and `j` the disc.
    along: Projection,
    /// `side * rho`.
    lever: f64,
    c: f64,
}

impl RollingRow {
    /// `(q) => u . d + side rho (phi_disc - phi_line) - c`.
    #[inline]
    fn value(&self, q: &Config<'_>) -> f64 {
        let turn = self.along.j.coords(q)[2] - self.along.i.coords(q)[2];
        self.along.value(q) + self.lever * turn - self.c
    }
    /// `(q) => (Phi_q_disc, Phi_q_line)`.
    #[inline]
    fn blocks(&self, q: &Config<'_>) -> ([f64; 3], [f64; 3]) {
        let (mut line, mut disc) = self.along.blocks(q);
        line[2] -= self.lever;
        disc[2] += self.lever;
        (disc, line)
    }
}

/// A disc rolling without slip on a line of another body. `CONTACT`: whether the disc also stays
/// on the line (the contact row, then the rolling row); a rack and pinion leaves the centre
/// distance to other joints and has the rolling row only.
#[derive(Debug, Clone)]
pub struct Rolling<const CONTACT: bool> {
    /// The disc (or pinion) and the line body (or rack).
    pair: Pair,
    /// The disc's centre, its frame.
    s_c: [f64; 2],
    /// `n . d`, with `i` the line body and `j` the disc.
    normal: Projection,
    /// `side * rho`.
    lever: f64,
    rolling: RollingRow,
    /// `v'_L` as given.
    axis: [f64; 2],
    /// The line body's and the disc's poses in the initial configuration, which fixes the rolling
    /// row's constant and the side (held: not data).
    start: [[f64; 3]; 2],
}

/// A pinion rolling on a rack's pitch line without slip: the rolling row only.
pub type RackPinion = Rolling<false>;

/// A disc rolling without slip on a line of another body, in contact with it: two rows.
pub type RollingDisc = Rolling<true>;

impl<const CONTACT: bool> Rolling<CONTACT> {
    /// `s_c`, `radius`: the disc's (pinion's) centre in its frame and its radius (pitch radius)
    /// (m); `s_l`, `v_l`: a point of the line (the rack's pitch line) and its direction in the line
    /// body's frame (non-zero). `q0`: the initial configuration, which fixes `c` and the side of
    /// the line the disc is on.
    pub fn new(
        disc: BodyIx,
        s_c: [f64; 2],
        radius: f64,
        line_body: BodyIx,
        s_l: [f64; 2],
        v_l: [f64; 2],
        q0: &[f64],
    ) -> Rolling<CONTACT> {
        let start = [line_body.coords(q0), disc.coords(q0)];
        let q0 = ConfigBuf::new(q0);
        let q0 = &q0.view();
        let u = unit(v_l);
        let normal = Projection { i: line_body, w: perp(u), s_p: s_l, j: disc, s_q: s_c };
        let side = if normal.value(q0) < 0.0 { -1.0 } else { 1.0 };
        let mut rolling = RollingRow {
            along: Projection { i: line_body, w: u, s_p: s_l, j: disc, s_q: s_c },
            lever: side * radius,
            c: 0.0,
        };
        rolling.c = rolling.value(q0);
        Rolling { pair: Pair::new(disc, line_body), s_c, normal, lever: side * radius, rolling, axis: v_l, start }
    }
}

impl<const CONTACT: bool> Constraint for Rolling<CONTACT> {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.s_c)
    }
    fn sketch(&self) -> Option<Sketch> {
        // Drawn from the line body (i) to the disc (j), the order the line's projection has.
        let n = &self.normal;
        let shape = Shape::Disc { axis: n.along(), radius: self.lever.abs() };
        Some(Sketch { i: n.i, p: n.s_p, j: n.j, q: n.s_q, shape })
    }
    fn row_names(&self) -> &[&'static str] {
        if CONTACT {
            &["contact", "rolling"]
        } else {
            &["rolling"]
        }
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        if CONTACT {
            out[0] = self.normal.value(q) - self.lever;
        }
        out[usize::from(CONTACT)] = self.rolling.value(q);
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let w = self.pair.width();
        if CONTACT {
            let (line, disc) = self.normal.blocks(q);
            self.pair.scatter(disc, line, &mut out[..w]);
        }
        let k = usize::from(CONTACT) * w;
        let (disc, line) = self.rolling.blocks(q);
        self.pair.scatter(disc, line, &mut out[k..k + w]);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        if CONTACT {
            out[0] = self.normal.gamma(q, qdot);
        }
        out[usize::from(CONTACT)] = self.rolling.along.gamma(q, qdot);
    }
    /// `point_i` (the centre), `point_j` (the line's point), `radius`, `axis_j` (the rolling row's
    /// constant follows them; the initial poses that fix it, and the side, are held).
    fn data(&self) -> Vec<(&'static str, f64)> {
        let n = &self.normal;
        let radius = [("radius", self.lever.abs())];
        [&vector(POINT_I, n.s_q)[..], &vector(POINT_J, n.s_p), &radius, &vector(AXIS_J, self.axis)].concat()
    }
    phi_tri_generic!();
}

impl<const CONTACT: bool> GenericPhi for Rolling<CONTACT> {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let (s_c, s_l, u) = (slot2(data, 0), slot2(data, 2), unit(slot2(data, 5)));
        let lever = S::constant(self.lever.signum()) * data[4];
        // (contact without the radius, rolling without its constant) in the line's and the disc's frames.
        let rows = |[fl, fd]: [Pose<S>; 2]| {
            let along = projection(u, &fl, s_l, &fd, s_c) + lever * (fd.phi - fl.phi);
            (projection(perp(u), &fl, s_l, &fd, s_c), along)
        };
        let (contact, along) = rows([Pose::of(self.normal.i, at.q), Pose::of(self.normal.j, at.q)]);
        if CONTACT {
            out[0] = contact - lever;
        }
        out[usize::from(CONTACT)] = along - rows(Source::poses(self.start)).1;
    }
}

/// `rack_pinion` / `rolling_disc`: a pitch circle rolling on a pitch line.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RollingJoint {
    /// The pinion.
    pub body_i: String,
    /// Centre of the pinion, body i frame.
    pub point_i: PointRef,
    /// Pitch radius, m.
    pub radius: f64,
    /// The rack.
    pub body_j: String,
    /// A point of the pitch line, body j frame.
    pub point_j: PointRef,
    /// Direction of the pitch line, body j frame.
    pub axis_j: [f64; 2],
}

/// The fields of a rolling joint at `path`, resolved: the circle's centre and radius, the line's
/// point and direction.
fn rolling_ends(spec: &RollingJoint, cx: &mut impl JointContext, path: &str) -> Option<([End; 2], f64, [f64; 2])> {
    let RollingJoint { body_i, point_i, radius, body_j, point_j, axis_j } = spec;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j);
    let r = cx.positive(&format!("{path}.radius"), *radius);
    let v = cx.axis(&format!("{path}.axis_j"), *axis_j);
    Some((ends?, r?, v?))
}

/// A `rack_pinion` joint at `path` compiled in `cx`.
pub(crate) fn compile_rack(spec: &RollingJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let ([(i, sc), (j, sl)], r, v) = rolling_ends(spec, cx, path)?;
    Some((Box::new(RackPinion::new(i, sc, r, j, sl, v, cx.q0())), None))
}

/// A `rolling_disc` joint at `path` compiled in `cx`.
pub(crate) fn compile_disc(spec: &RollingJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let ([(i, sc), (j, sl)], r, v) = rolling_ends(spec, cx, path)?;
    Some((Box::new(RollingDisc::new(i, sc, r, j, sl, v, cx.q0())), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{assert_data_fields, check_fd_random, check_generic_random, check_rebuilt, Lcg};

    #[test]
    fn derivatives_match_finite_differences() {
        let q0 = Lcg::new(5).vec(6, -2.0, 2.0);
        let (a, b) = (BodyIx(Some(0)), BodyIx(Some(3)));
        let g = BodyIx::GROUND;
        for (seed, (p, l)) in [(a, b), (b, a), (g, b), (a, g)].into_iter().enumerate() {
            let s = 10 * seed as u64;
            let rp = RackPinion::new(p, [0.3, -0.2], 0.6, l, [-1.1, 0.4], [1.0, 2.0], &q0);
            check_fd_random(&rp, 2, s + 1);
            check_generic_random(&rp, 2, s + 1);
            let build = |d: &[f64]| RackPinion::new(p, [d[0], d[1]], d[4], l, [d[2], d[3]], [d[5], d[6]], &q0);
            check_rebuilt(&rp, &build, 2, s + 1);
            let rd = RollingDisc::new(p, [0.3, -0.2], 0.6, l, [-1.1, 0.4], [-3.0, 0.5], &q0);
            check_fd_random(&rd, 2, s + 2);
            check_generic_random(&rd, 2, s + 2);
            let build = |d: &[f64]| RollingDisc::new(p, [d[0], d[1]], d[4], l, [d[2], d[3]], [d[5], d[6]], &q0);
            check_rebuilt(&rd, &build, 2, s + 2);
            assert_data_fields::<RollingJoint>(&rp);
            assert_data_fields::<RollingJoint>(&rd);
        }
    }

    fn eval(c: &dyn Constraint, q: &[f64], qdot: &[f64]) -> ([f64; 2], [f64; 6], [f64; 2]) {
        let (mut phi, mut jac, mut gamma) = ([0.0; 2], [0.0; 6], [0.0; 2]);
        let m = c.rows();
        c.phi_at(q, 0.0, &mut phi[..m]);
        c.jacobian_at(q, 0.0, &mut jac[..3 * m]);
        c.gamma_at(q, qdot, 0.0, &mut gamma[..m]);
        (phi, jac, gamma)
    }

    /// Hand-derived: a disc of radius 0.5 on the ground x axis, centre (x, 0.5). Contact row
    /// y - 0.5, rolling row x + 0.5 phi - c, Jacobian rows (0, 1, 0) and (1, 0, 0.5), gamma 0: rolling
    /// at omega = -2 (clockwise) gives vx = -0.5 omega = 1 and, with alpha = 0, ax = 0 and ay = 0.
    #[test]
    fn hand_derived_disc_on_ground() {
        let q0 = [0.2, 0.5, 0.1];
        let d = RollingDisc::new(BodyIx(Some(0)), [0.0; 2], 0.5, BodyIx::GROUND, [0.0; 2], [2.0, 0.0], &q0);
        let q = [1.2, 0.5, 0.1 - 2.0];
        let (phi, jac, gamma) = eval(&d, &q, &[1.0, 0.0, -2.0]);
        assert!(phi[0].abs() < 1e-15 && phi[1].abs() < 1e-14, "{phi:?}");
        assert_eq!(jac, [0.0, 1.0, 0.0, 1.0, 0.0, 0.5]);
        assert_eq!(gamma, [0.0, 0.0]);
        // Velocity: solve the rolling row for vx with omega = -2.
        let vx = -jac[5] * -2.0 / jac[3];
        assert!((vx - 1.0).abs() < 1e-15);
    }

    /// Hand-derived: the same disc under a ceiling (centre (x, -0.5), side -1) rolls along +x
    /// counterclockwise: rows y + 0.5 and x - 0.5 phi - c.
    #[test]
    fn hand_derived_disc_under_ceiling() {
        let q0 = [0.0, -0.5, 0.0];
        let d = RollingDisc::new(BodyIx(Some(0)), [0.0; 2], 0.5, BodyIx::GROUND, [0.0; 2], [1.0, 0.0], &q0);
        let (phi, jac, _) = eval(&d, &[1.0, -0.5, 2.0], &[0.0; 3]);
        assert!(phi[0].abs() < 1e-15 && phi[1].abs() < 1e-15, "{phi:?}");
        assert_eq!(jac, [0.0, 1.0, 0.0, 1.0, 0.0, -0.5]);
    }

    /// Hand-derived gamma: the line body spins about its centre at the origin (omega_l = 1, angle
    /// 0, line along x through the centre) under a disc at rest with centre (2, 0.5). At angle t:
    /// u . d = 2 cos t + 0.5 sin t and n . d = -2 sin t + 0.5 cos t, so at t = 0 gamma = -(u . d)''
    /// = 2 (rolling; the -rho phi_l term is linear) and -(n . d)'' = 0.5 (contact). Rolling row
    /// Jacobian on phi_l: (R90 u) . d - rho = 0.5 - 0.5 = 0.
    #[test]
    fn hand_derived_spinning_line() {
        let q = [2.0, 0.5, 0.0, 0.0, 0.0, 0.0];
        let (disc, line) = (BodyIx(Some(0)), BodyIx(Some(3)));
        let d = RollingDisc::new(disc, [0.0; 2], 0.5, line, [0.0; 2], [1.0, 0.0], &q);
        let (mut phi, mut jac, mut gamma) = ([1.0; 2], [1.0; 12], [0.0; 2]);
        d.phi_at(&q, 0.0, &mut phi);
        d.jacobian_at(&q, 0.0, &mut jac);
        d.gamma_at(&q, &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], 0.0, &mut gamma);
        assert!(phi[0].abs() < 1e-15 && phi[1].abs() < 1e-15, "{phi:?}");
        assert!(jac[11].abs() < 1e-15 && (jac[8] - 0.5).abs() < 1e-15, "{jac:?}");
        assert!((gamma[0] - 0.5).abs() < 1e-14 && (gamma[1] - 2.0).abs() < 1e-14, "{gamma:?}");
    }

    /// Hand-derived: a pinion of radius 1 pinned at (0, 1) above a rack (pitch line the rack's x
    /// axis, rack centre (3, 0)): c = u . d0 = -3. After the pinion turns by 0.3 and the rack moves
    /// by 0.3: Phi = -3.3 + 0.3 + 3 = 0. Jacobian: pinion (u^T, rho), rack (-u^T, n . d - rho = 0).
    /// Turning the pinion counterclockwise at omega = 1 drives the rack along +x at 1.
    #[test]
    fn hand_derived_rack_and_pinion() {
        let q0 = [0.0, 1.0, 0.0, 3.0, 0.0, 0.0];
        let rp = RackPinion::new(BodyIx(Some(0)), [0.0; 2], 1.0, BodyIx(Some(3)), [0.0; 2], [1.0, 0.0], &q0);
        let q = [0.0, 1.0, 0.3, 3.3, 0.0, 0.0];
        let (mut phi, mut jac) = ([1.0], [0.0; 6]);
        rp.phi_at(&q, 0.0, &mut phi);
        rp.jacobian_at(&q, 0.0, &mut jac);
        assert!(phi[0].abs() < 1e-15, "{phi:?}");
        assert_eq!(jac, [1.0, 0.0, 1.0, -1.0, 0.0, 0.0]);
        // Phi_q qdot = 0 with pinion omega = 1, rack vx free (vy, omega_rack = 0): vx = 1.
        let vx = -jac[2] / jac[3];
        assert!((vx - 1.0).abs() < 1e-15);
    }
}
