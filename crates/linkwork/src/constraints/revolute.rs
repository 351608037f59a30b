//! Revolute (pin) joint: point `P` on body i coincides with point `Q` on body j. Two rows.
//!
//! ```text
//! Phi   = r_i + A_i s'_P - r_j - A_j s'_Q                       (2)
//! Phi_q = [ I   B_i s'_P   -I   -B_j s'_Q ]                      (2 x 6)
//! nu    = 0
//! gamma = A_i s'_P omega_i^2 - A_j s'_Q omega_j^2                (2)
//! ```
//! with `B = dA/dphi`. Haug (1989) section 3.3.1; Nikravesh (2018) section 7.1.

use super::schema::{with_friction, JointContext};
use super::CompiledJoint;
use super::{phi_tri_generic, separation, slot2, vector, At, GenericPhi, Pose, POINT_I, POINT_J};
use super::{Anchor, BodyIx, Config, Constraint, Frame, Friction, FrictionLaw, Pair, Separation, Shape, Sketch};
use crate::element::fields;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A revolute joint between body i (point `P`) and body j (point `Q`).
#[derive(Debug, Clone)]
pub struct Revolute {
    pair: Pair,
    s_p: [f64; 2],
    s_q: [f64; 2],
}

impl Revolute {
    /// `s_p`, `s_q`: the joint point in the frames of body i and body j.
    pub fn new(i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2]) -> Revolute {
        Revolute { pair: Pair::new(i, j), s_p, s_q }
    }

    /// Coulomb friction in this joint's pin of `radius` (m) ([`Friction`]).
    pub fn friction(&self, law: FrictionLaw, radius: f64) -> Friction {
        Friction::pin(law, self.anchor(), radius)
    }
}

impl Constraint for Revolute {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.s_p)
    }
    fn sketch(&self) -> Option<Sketch> {
        Some(Sketch { i: self.pair.i, p: self.s_p, j: self.pair.j, q: self.s_q, shape: Shape::Pin })
    }
    fn row_names(&self) -> &[&'static str] {
        &["x", "y"]
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        // Phi = -d, d = r_Q - r_P summed as the origins' difference plus the offsets'.
        let d = Separation::of(self.pair.i, self.s_p, self.pair.j, self.s_q, q).d;
        out[0] = -d[0];
        out[1] = -d[1];
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let bi = Frame::of(self.pair.i, q).rotate_d(self.s_p);
        let bj = Frame::of(self.pair.j, q).rotate_d(self.s_q);
        let w = self.pair.width();
        self.pair.scatter([1.0, 0.0, bi[0]], [-1.0, 0.0, -bj[0]], &mut out[..w]);
        self.pair.scatter([0.0, 1.0, bi[1]], [0.0, -1.0, -bj[1]], &mut out[w..2 * w]);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        let wi = self.pair.i.coords(qdot)[2];
        let wj = self.pair.j.coords(qdot)[2];
        let ai = Frame::of(self.pair.i, q).rotate(self.s_p);
        let aj = Frame::of(self.pair.j, q).rotate(self.s_q);
        out[0] = ai[0] * wi * wi - aj[0] * wj * wj;
        out[1] = ai[1] * wi * wi - aj[1] * wj * wj;
    }
    /// `point_i`, `point_j`.
    fn data(&self) -> Vec<(&'static str, f64)> {
        [vector(POINT_I, self.s_p), vector(POINT_J, self.s_q)].concat()
    }
    phi_tri_generic!();
}

impl GenericPhi for Revolute {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let (fi, fj) = (Pose::of(self.pair.i, at.q), Pose::of(self.pair.j, at.q));
        let d = separation(&fi, slot2(data, 0), &fj, slot2(data, 2));
        out[0] = -d[0];
        out[1] = -d[1];
    }
}

fields! {
    /// Pin: `point_i` of `body_i` coincides with `point_j` of `body_j`. 2 equations.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct RevoluteJoint {
        [body_i, point_i?, body_j, point_j?, at,]
        /// Coulomb friction in the pin.
        #[serde(default)]
        pub friction: Option<PinFriction>,
    }
}

/// Coulomb friction in a revolute joint: a torque `mu tanh(r omega / v_s) r |F|` opposing the
/// relative rotation `omega = omega_i - omega_j`, `|F|` the magnitude of the joint's reaction force
/// (docs/model-format.md, "Joint friction").
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PinFriction {
    /// Coefficient of friction, `>= 0`.
    pub mu: f64,
    /// Radius of the pin, m, `> 0`.
    pub radius: f64,
    /// Sliding speed on the pin's surface at which the coefficient reaches `tanh(1) = 76%` of
    /// `mu`, m/s, `> 0`; default 0.001.
    #[serde(default)]
    pub transition_velocity: Option<f64>,
}

/// A revolute joint at `path` compiled in `cx`, with its friction.
pub(crate) fn compile(spec: &RevoluteJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let RevoluteJoint { body_i, point_i, body_j, point_j, at, friction: pin } = spec;
    let points = cx.placed_points(path, [body_i, body_j], [point_i, point_j], at);
    // The bodies are checked (`ends`) whether or not the points could be placed.
    let (pi, pj) = points.clone().unwrap_or_default();
    let ends = cx.ends(path, body_i, &pi, body_j, &pj);
    let law = pin.as_ref().map(|f| cx.sized_friction(path, f.mu, f.transition_velocity, ("radius", f.radius)));
    let (_, [(i, sp), (j, sq)]) = (points?, ends?);
    with_friction(Revolute::new(i, sp, j, sq), law, Revolute::friction)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{assert_data_fields, check_fd_random, check_generic_random};

    #[test]
    fn derivatives_match_finite_differences() {
        let j = Revolute::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-1.1, 0.4]);
        check_fd_random(&j, 2, 1);
        check_generic_random(&j, 2, 1);
        assert_data_fields::<RevoluteJoint>(&j);
        let g = Revolute::new(BodyIx(Some(3)), [0.75, 0.0], BodyIx::GROUND, [0.5, -2.0]);
        check_fd_random(&g, 2, 2);
        check_generic_random(&g, 2, 2);
    }

    /// `Phi` far from the origin (bodies 1e4 m out) carries the round-off of the offsets, not of
    /// the positions: near a singular position Newton multiplies it by `|B^-1|` (docs/integrators.md,
    /// `abam`). Reference: the same expression with the rotations' cosines and sines as computed,
    /// its products exact (`mul_add`) and its sum in double-double (Knuth's two-sum), so accurate to
    /// `~eps^2` of its terms. Bound: 8 units of round-off of the offsets (about 1 m), where
    /// summing `r + A s'` first errs by up to half a unit of `1e4` (`9e-13`).
    #[test]
    fn phi_far_from_the_origin_has_the_round_off_of_the_offsets() {
        use crate::constraints::testing::Lcg;
        use crate::constraints::ConfigBuf;
        let two_sum = |(hi, lo): (f64, f64), x: f64| {
            let s = hi + x;
            let v = s - hi;
            (s, lo + ((hi - (s - v)) + (x - v)))
        };
        let mut rng = Lcg::new(7);
        let mut worst = 0.0f64;
        for _ in 0..200 {
            let (sp, sq) =
                ([rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)], [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)]);
            let j = Revolute::new(BodyIx(Some(0)), sp, BodyIx(Some(3)), sq);
            let mut q = rng.vec(6, -1.0, 1.0);
            q[0] += 1e4;
            q[1] -= 1e4;
            q[3] += 1e4;
            q[4] -= 1e4;
            let mut phi = [0.0; 2];
            j.phi_at(&q, 0.0, &mut phi);
            let buf = ConfigBuf::new(&q);
            let config = buf.view();
            let ([ci, si], [cj, sj]) = (config.rot[0], config.rot[1]);
            for (k, out) in phi.iter().enumerate() {
                let terms = if k == 0 {
                    [(1.0, q[0]), (ci, sp[0]), (-si, sp[1]), (-1.0, q[3]), (-cj, sq[0]), (sj, sq[1])]
                } else {
                    [(1.0, q[1]), (si, sp[0]), (ci, sp[1]), (-1.0, q[4]), (-sj, sq[0]), (-cj, sq[1])]
                };
                let mut acc = (0.0, 0.0);
                for (a, b) in terms {
                    let p = a * b;
                    acc = two_sum(two_sum(acc, p), a.mul_add(b, -p));
                }
                worst = worst.max((out - (acc.0 + acc.1)).abs());
            }
        }
        assert!(worst <= 8.0 * f64::EPSILON, "{worst:e}");
    }

    /// Hand-derived case: a crank of half-length 0.75 at angle pi/2, pinned at its end (0.75, 0)
    /// to the ground origin. The pin is at (x - 0.75 sin.. ) => centre must be at (0, -0.75).
    #[test]
    fn hand_derived_crank_pin() {
        let j = Revolute::new(BodyIx(Some(0)), [0.75, 0.0], BodyIx::GROUND, [0.0, 0.0]);
        let q = [0.0, -0.75, std::f64::consts::FRAC_PI_2];
        let mut phi = [1.0; 2];
        j.phi_at(&q, 0.0, &mut phi);
        assert!(phi[0].abs() < 1e-15 && phi[1].abs() < 1e-15, "{phi:?}");
        // B s' = (-sin*0.75, cos*0.75) = (-0.75, 0) at phi = pi/2.
        let mut jac = [0.0; 6];
        j.jacobian_at(&q, 0.0, &mut jac);
        let expect = [1.0, 0.0, -0.75, 0.0, 1.0, 0.0];
        for (a, b) in jac.iter().zip(expect) {
            assert!((a - b).abs() < 1e-15, "{jac:?}");
        }
        // Centripetal: gamma = A s' omega^2 = (0, 0.75) * 4 for omega = 2.
        let mut g = [0.0; 2];
        j.gamma_at(&q, &[0.0, 0.0, 2.0], 0.0, &mut g);
        assert!(g[0].abs() < 1e-14 && (g[1] - 3.0).abs() < 1e-14, "{g:?}");
    }
}
