//! Gear pair: the pitch circles of gear i (centre `C_i`, radius `r_i`) and gear j (centre `C_j`,
//! radius `r_j`) roll on each other without slip. One row.
//!
//! The centres may move (a planet on a carrier): the centre distance is kept by other joints, and
//! the row is written relative to the line of centres, at angle `theta`. Relative to that line the
//! gears turn at `phi_i' - theta'` and `phi_j' - theta'`, and their pitch points share a velocity:
//!
//! ```text
//! d      = C_j - C_i = r_j + A_j s'_j - r_i - A_i s'_i,   rho = d . d,   theta = atan2(d_y, d_x)
//! sigma  = +1 external (opposite rotation), -1 internal (j is the ring, i runs inside it)
//! k      = r_i + sigma r_j
//! Phi    = r_i phi_i + sigma r_j phi_j - k theta - c           (c from the initial configuration)
//! theta_q = (R90 d / rho)^T [ -I   -B_i s'_i   I   B_j s'_j ]
//! Phi_q  = [ 0 0 r_i   0 0 sigma r_j ] - k theta_q                                    (1 x 6)
//! nu     = 0
//! gamma  = k theta''_free,  theta''_free = (R90 d) . (A_i s'_i omega_i^2 - A_j s'_j omega_j^2) / rho
//!                                          - 2 ((R90 d) . d') (d . d') / rho^2
//! ```
//! (`theta' = (R90 d) . d' / rho`; differentiating again, `(R90 d') . d' = 0`.) With both centres
//! fixed `theta` is constant and the row is `r_i phi_i + sigma r_j phi_j = const`: the speed ratio
//! `omega_j / omega_i` is `-r_i / r_j` for an external pair and `+r_i / r_j` for an internal one.
//!
//! `atan2` jumps by `2 pi` when the line of centres crosses the negative x axis, which a carrier
//! does once per turn. The residual is therefore reduced modulo `2 pi |k|` into
//! `(-pi |k|, pi |k|]`: the same constraint (a full turn of the line of centres changes
//! `k theta` by `2 pi k`), continuous everywhere except half a period away from the solution.
//!
//! `theta` is undefined when the centres coincide (`rho = 0`: a concentric internal pair); the row
//! then evaluates to NaN. The caller must not create a pair with coincident centres. Haug (1989)
//! section 3.4.4; Nikravesh (2018) section 7.4.

use std::f64::consts::TAU;

use super::schema::JointContext;
use super::CompiledJoint;
use super::PointRef;
use super::{dot, perp, Anchor, BodyIx, Config, ConfigBuf, Constraint, Pair, Separation, Shape, Sketch};
use super::{phi_tri_generic, separation, slot2, vector, At, GenericPhi, Pose, Source, POINT_I, POINT_J};
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// External or internal meshing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GearKind {
    /// Two gears side by side: they turn in opposite directions.
    External,
    /// Gear i inside the ring gear j: they turn in the same direction.
    Internal,
}

/// Two gears whose pitch circles roll without slip.
#[derive(Debug, Clone)]
pub struct GearPair {
    kind: GearKind,
    pair: Pair,
    s_i: [f64; 2],
    s_j: [f64; 2],
    /// `r_i`.
    r_i: f64,
    /// `sigma r_j`.
    r_j: f64,
    /// `r_i + sigma r_j`.
    k: f64,
    c: f64,
    /// The bodies' poses in the initial configuration, which fixes `c` (held: not data).
    start: [[f64; 3]; 2],
}

impl GearPair {
    /// `s_i`, `r_i`: centre of gear i in body i's frame and its pitch radius (m); likewise `s_j`,
    /// `r_j` (for an internal pair, gear j is the ring). `q0` is the initial configuration, where
    /// the row is made to hold. The centres must not coincide at `q0`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        kind: GearKind,
        i: BodyIx,
        s_i: [f64; 2],
        r_i: f64,
        j: BodyIx,
        s_j: [f64; 2],
        r_j: f64,
        q0: &[f64],
    ) -> GearPair {
        let r_j = match kind {
            GearKind::External => r_j,
            GearKind::Internal => -r_j,
        };
        let start = [i.coords(q0), j.coords(q0)];
        let mut g = GearPair { kind, pair: Pair::new(i, j), s_i, s_j, r_i, r_j, k: r_i + r_j, c: 0.0, start };
        g.c = g.unwrapped(&ConfigBuf::new(q0).view());
        g
    }

    /// `sigma`: `1` external, `-1` internal.
    fn sigma(&self) -> f64 {
        match self.kind {
            GearKind::External => 1.0,
            GearKind::Internal => -1.0,
        }
    }

    /// `r_i phi_i + sigma r_j phi_j - k theta` in the frames `fi`, `fj` over any [`Scalar`], with
    /// the data of [`Constraint::data`].
    fn raw<S: Scalar>(&self, fi: &Pose<S>, fj: &Pose<S>, data: &[S]) -> S {
        let d = separation(fi, slot2(data, 0), fj, slot2(data, 2));
        let theta = d[1].atan2(d[0]);
        let (r_i, r_j) = (data[4], S::constant(self.sigma()) * data[5]);
        r_i * fi.phi + r_j * fj.phi - (r_i + r_j) * theta
    }

    /// External or internal.
    pub fn kind(&self) -> GearKind {
        self.kind
    }

    #[inline]
    fn separation(&self, q: &Config<'_>) -> Separation {
        Separation::of(self.pair.i, self.s_i, self.pair.j, self.s_j, q)
    }

    /// `(q) => r_i phi_i + sigma r_j phi_j - k theta - c` with `theta` in `(-pi, pi]`.
    #[inline]
    fn unwrapped(&self, q: &Config<'_>) -> f64 {
        let sep = self.separation(q);
        let theta = sep.d[1].atan2(sep.d[0]);
        self.r_i * sep.phi[0] + self.r_j * sep.phi[1] - self.k * theta - self.c
    }
}

impl Constraint for GearPair {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.s_i)
    }
    fn sketch(&self) -> Option<Sketch> {
        let (r_i, r_j, internal) = (self.r_i, self.r_j.abs(), self.kind == GearKind::Internal);
        Some(Sketch {
            i: self.pair.i,
            p: self.s_i,
            j: self.pair.j,
            q: self.s_j,
            shape: Shape::Gears { r_i, r_j, internal },
        })
    }
    fn row_names(&self) -> &[&'static str] {
        &["rolling"]
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let raw = self.unwrapped(q);
        let period = TAU * self.k.abs();
        out[0] = if period > 0.0 { raw - period * (raw / period).round() } else { raw };
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let sep = self.separation(q);
        let rho = dot(sep.d, sep.d);
        let n = perp(sep.d);
        let (ti, tj) = sep.chain([n[0] / rho, n[1] / rho]);
        let k = self.k;
        let bi = [-k * ti[0], -k * ti[1], self.r_i - k * ti[2]];
        let bj = [-k * tj[0], -k * tj[1], self.r_j - k * tj[2]];
        self.pair.scatter(bi, bj, out);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        let sep = self.separation(q);
        let (qd_i, qd_j) = (self.pair.i.coords(qdot), self.pair.j.coords(qdot));
        let rate = sep.rate(qd_i, qd_j);
        let free = sep.accel_free(qd_i[2], qd_j[2]);
        let rho = dot(sep.d, sep.d);
        let n = perp(sep.d);
        let theta_free = dot(n, free) / rho - 2.0 * dot(n, rate) * dot(sep.d, rate) / (rho * rho);
        out[0] = self.k * theta_free;
    }
    /// `point_i`, `point_j`, `radius_i`, `radius_j` (`c` follows them; the initial poses that fix
    /// it are held).
    fn data(&self) -> Vec<(&'static str, f64)> {
        let radii = [("radius_i", self.r_i), ("radius_j", self.sigma() * self.r_j)];
        [&vector(POINT_I, self.s_i)[..], &vector(POINT_J, self.s_j), &radii].concat()
    }
    phi_tri_generic!();
}

impl GenericPhi for GearPair {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let [hi, hj] = Source::poses(self.start);
        let c = self.raw(&hi, &hj, data);
        let raw = self.raw(&Pose::of(self.pair.i, at.q), &Pose::of(self.pair.j, at.q), data) - c;
        // Reduced as `phi` reduces it; the whole periods taken off are constant where it is smooth.
        let k = data[4] + S::constant(self.sigma()) * data[5];
        let period = S::constant(TAU) * k.abs();
        out[0] =
            if period.value() > 0.0 { raw - period * S::constant((raw.value() / period.value()).round()) } else { raw };
    }
}

/// Gear pair: pitch circles of radius `radius_i` and `radius_j` about `point_i` and `point_j`
/// roll without slip. The centre distance must be kept by other joints. 1 equation.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GearJoint {
    /// First gear.
    pub body_i: String,
    /// Centre of the first gear, body i frame.
    pub point_i: PointRef,
    /// Pitch radius of the first gear, m.
    pub radius_i: f64,
    /// Second gear (the ring when `internal`).
    pub body_j: String,
    /// Centre of the second gear, body j frame.
    pub point_j: PointRef,
    /// Pitch radius of the second gear, m.
    pub radius_j: f64,
    /// True when gear j is an internal (ring) gear with gear i inside it. Default: false.
    #[serde(default)]
    pub internal: bool,
}

/// A gear joint at `path` compiled in `cx`.
pub(crate) fn compile(spec: &GearJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let GearJoint { body_i, point_i, radius_i, body_j, point_j, radius_j, internal } = spec;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j);
    let ri = cx.positive(&format!("{path}.radius_i"), *radius_i);
    let rj = cx.positive(&format!("{path}.radius_j"), *radius_j);
    let (ends, ri, rj) = (ends?, ri?, rj?);
    let [(i, si), (j, sj)] = ends;
    // Centres closer than 1e-9 m leave the line of centres to round-off.
    if cx.initial_distance(ends) < 1e-9 {
        cx.problem(path, "the gear centres coincide in the initial configuration: the line of centres is undefined");
        return None;
    }
    let kind = if *internal { GearKind::Internal } else { GearKind::External };
    Some((Box::new(GearPair::new(kind, i, si, ri, j, sj, rj, cx.q0())), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{
        assert_data_fields, check_fd_random_where, check_generic_random_where, check_rebuilt, Lcg,
    };
    use crate::constraints::ConfigBuf;

    /// Finite differences lose their accuracy as the centres approach each other (`1 / rho`
    /// terms, with fourth derivatives growing like |d|^-4): check at states where they are at least 1
    /// apart.
    fn check(g: &GearPair, seed: u64) {
        let apart = |q: &[f64]| {
            let d = g.separation(&ConfigBuf::new(q).view()).d;
            dot(d, d) > 1.0
        };
        check_fd_random_where(g, 2, seed, &apart);
        check_generic_random_where(g, 2, seed, &apart);
        let build =
            |d: &[f64]| GearPair::new(g.kind, g.pair.i, [d[0], d[1]], d[4], g.pair.j, [d[2], d[3]], d[5], &q0(g));
        check_rebuilt(g, &build, 2, seed);
        assert_data_fields::<GearJoint>(g);
    }

    /// The initial configuration `g` was built at, from the poses it keeps.
    fn q0(g: &GearPair) -> Vec<f64> {
        let mut q = vec![0.0; 6];
        for (body, pose) in [g.pair.i, g.pair.j].iter().zip(g.start) {
            if let Some(k) = body.0 {
                q[k..k + 3].copy_from_slice(&pose);
            }
        }
        q
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let q0 = Lcg::new(7).vec(6, -2.0, 2.0);
        for (seed, kind) in [GearKind::External, GearKind::Internal].into_iter().enumerate() {
            let s = 10 * seed as u64;
            check(
                &GearPair::new(kind, BodyIx(Some(0)), [0.3, -0.2], 0.4, BodyIx(Some(3)), [-1.1, 0.4], 1.3, &q0),
                s + 1,
            );
            check(&GearPair::new(kind, BodyIx::GROUND, [0.5, -2.0], 0.7, BodyIx(Some(3)), [0.2, 0.1], 0.4, &q0), s + 2);
            check(&GearPair::new(kind, BodyIx(Some(0)), [0.5, -2.0], 0.7, BodyIx::GROUND, [0.2, 0.1], 0.4, &q0), s + 3);
        }
    }

    /// `(gear, q, qdot) => (Phi, Phi_q, gamma)` for a two-body pair.
    fn eval(g: &GearPair, q: &[f64], qdot: &[f64]) -> (f64, [f64; 6], f64) {
        let (mut phi, mut jac, mut gamma) = ([0.0], [0.0; 6], [0.0]);
        g.phi_at(q, 0.0, &mut phi);
        g.jacobian_at(q, 0.0, &mut jac);
        g.gamma_at(q, qdot, 0.0, &mut gamma);
        (phi[0], jac, gamma[0])
    }

    /// Hand-derived: gear i (r_i = 1) and gear j (r_j = 0.5) at their body origins, centres
    /// (0, 0) and (1.5, 0) for the external pair, (0, 0) and (-0.5, 0) for the internal pair (ring
    /// j of radius 1.5 around gear i: centre distance 1.5 - 1 = 0.5, ring radius passed as 1.5).
    /// With the centres held, Phi_q qdot = r_i omega_i + sigma r_j omega_j = 0 gives the speed ratio.
    /// Phi_y_j = -k d_x / rho: external k = 1.5, d = (1.5, 0): -1; internal k = 1 - 1.5 = -0.5,
    /// d = (-0.5, 0): -1 as well.
    #[test]
    fn hand_derived_fixed_centres_speed_ratio() {
        let ext = [0.0, 0.0, 0.3, 1.5, 0.0, -0.2];
        let g = GearPair::new(GearKind::External, BodyIx(Some(0)), [0.0; 2], 1.0, BodyIx(Some(3)), [0.0; 2], 0.5, &ext);
        // Turn gear i by 0.1: gear j turns by -0.2 (ratio -r_i / r_j = -2).
        let q = [0.0, 0.0, 0.4, 1.5, 0.0, -0.4];
        let (phi, jac, gamma) = eval(&g, &q, &[0.0, 0.0, 1.0, 0.0, 0.0, -2.0]);
        assert!(phi.abs() < 1e-14, "{phi}");
        assert_eq!((jac[2], jac[5]), (1.0, 0.5));
        assert!((jac[4] + 1.0).abs() < 1e-14, "{jac:?}");
        assert!(gamma.abs() < 1e-14, "{gamma}");
        // omega_j from the row with omega_i = 1: -(r_i omega_i) / (sigma r_j) = -2.
        assert!((-jac[2] / jac[5] + 2.0).abs() < 1e-14);

        let int = [0.0, 0.0, 0.3, -0.5, 0.0, -0.2];
        let g = GearPair::new(GearKind::Internal, BodyIx(Some(0)), [0.0; 2], 1.0, BodyIx(Some(3)), [0.0; 2], 1.5, &int);
        // Turn gear i by 0.15: the ring turns by +0.1 (ratio +r_i / r_j = 2/3).
        let q = [0.0, 0.0, 0.45, -0.5, 0.0, -0.1];
        let (phi, jac, gamma) = eval(&g, &q, &[0.0, 0.0, 1.5, 0.0, 0.0, 1.0]);
        assert!(phi.abs() < 1e-14, "{phi}");
        assert_eq!((jac[2], jac[5]), (1.0, -1.5));
        assert!((jac[4] + 1.0).abs() < 1e-14, "{jac:?}");
        assert!(gamma.abs() < 1e-14, "{gamma}");
        assert!((-jac[2] / jac[5] - 2.0 / 3.0).abs() < 1e-14);
    }

    /// Hand-derived gamma with a moving centre: gear j (body j, centre at its origin) at (R, 0),
    /// R = 1.5, moving with d' = (u, v) = (0.3, 0.6) around gear i fixed at the ground origin.
    /// theta = atan(v t / (R + u t)) = v t / R - u v t^2 / R^2 + ..., so theta'' = -2 u v / R^2 =
    /// -0.16 and gamma = k theta'' = 1.5 * -0.16 = -0.24.
    #[test]
    fn hand_derived_moving_centre() {
        let q = [1.5, 0.0, 0.0];
        let g = GearPair::new(GearKind::External, BodyIx::GROUND, [0.0; 2], 1.0, BodyIx(Some(0)), [0.0; 2], 0.5, &q);
        let mut gamma = [0.0];
        g.gamma_at(&q, &[0.3, 0.6, 0.7], 0.0, &mut gamma);
        assert!((gamma[0] + 0.24).abs() < 1e-14, "{gamma:?}");
    }

    /// A planet carried across the negative x axis: atan2 jumps by 2 pi, the residual does not.
    #[test]
    fn planet_crosses_the_branch_cut() {
        let (r_i, r_j) = (1.0, 0.5);
        let planet = |a: f64, spin: f64| [1.5 * a.cos(), 1.5 * a.sin(), spin];
        let q0 = planet(3.0, 0.0);
        let g = GearPair::new(GearKind::External, BodyIx::GROUND, [0.0; 2], r_i, BodyIx(Some(0)), [0.0; 2], r_j, &q0);
        // Rolling on the fixed sun: r_j (phi_j - theta) = r_i theta + const, phi_j = 3 theta + const.
        for a in [3.0, 3.1, 3.2, 3.5, 6.0, 9.0, -4.0] {
            let mut phi = [1.0];
            g.phi_at(&planet(a, 3.0 * (a - 3.0)), 0.0, &mut phi);
            assert!(phi[0].abs() < 1e-13, "carrier at {a}: {phi:?}");
        }
    }
}
