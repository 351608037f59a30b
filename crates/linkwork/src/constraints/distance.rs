//! Distance constraint (revolute-revolute composite, a massless link): point `P` of body i and point
//! `Q` of body j stay a distance `L` apart. One row.
//!
//! ```text
//! d     = r_j + A_j s'_Q - r_i - A_i s'_P
//! Phi   = d . d - L^2
//! Phi_q = 2 d^T [ -I   -B_i s'_P   I   B_j s'_Q ]                     (1 x 6)
//! nu    = 0
//! gamma = -2 d' . d' + 2 d . (A_j s'_Q omega_j^2 - A_i s'_P omega_i^2)
//! ```
//! The squared form stays smooth when the points coincide (where `|d|` is not differentiable), at the
//! price of a multiplier that is a force divided by `2 L`. Haug (1989) section 3.4.1; Nikravesh
//! (2018) section 7.2.

use super::schema::JointContext;
use super::CompiledJoint;
use super::{dot, Anchor, BodyIx, Config, Constraint, PointPair, Shape, Sketch};
use super::{phi_tri_generic, separation, slot2, vector, At, GenericPhi, Pose, Source, POINT_I, POINT_J};
use crate::element::fields;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Two body points at a fixed distance.
#[derive(Debug, Clone)]
pub struct Distance {
    points: PointPair,
    length: f64,
    /// Where `length` comes from: the file (a data slot) or the initial configuration.
    length_from: Source,
}

impl Distance {
    /// `s_p`, `s_q`: the points in the frames of body i and body j; `length`: their distance (m).
    pub fn new(i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2], length: f64) -> Distance {
        Distance { points: PointPair::new(i, s_p, j, s_q), length, length_from: Source::File }
    }
}

impl Constraint for Distance {
    fn anchor(&self) -> Anchor {
        self.points.anchor()
    }
    fn sketch(&self) -> Option<Sketch> {
        let pts = &self.points;
        Some(Sketch { i: pts.pair.i, p: pts.s_p, j: pts.pair.j, q: pts.s_q, shape: Shape::Rod })
    }
    fn row_names(&self) -> &[&'static str] {
        &["distance"]
    }
    fn columns(&self) -> &[usize] {
        self.points.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let d = self.points.separation(q).d;
        out[0] = dot(d, d) - self.length * self.length;
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let d = self.points.separation(q);
        let (bi, bj) = d.chain([2.0 * d.d[0], 2.0 * d.d[1]]);
        self.points.pair.scatter(bi, bj, out);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        let sep = self.points.separation(q);
        let (qd_i, qd_j) = (self.points.pair.i.coords(qdot), self.points.pair.j.coords(qdot));
        let rate = sep.rate(qd_i, qd_j);
        let free = sep.accel_free(qd_i[2], qd_j[2]);
        out[0] = -2.0 * (dot(rate, rate) + dot(sep.d, free));
    }
    /// `point_i`, `point_j`, and `length` when the file gives it.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let points = [vector(POINT_I, self.points.s_p), vector(POINT_J, self.points.s_q)].concat();
        self.length_from.data(points, "length", self.length)
    }
    phi_tri_generic!();
}

impl GenericPhi for Distance {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let pair = &self.points.pair;
        let (s_p, s_q) = (slot2(data, 0), slot2(data, 2));
        let d = separation(&Pose::of(pair.i, at.q), s_p, &Pose::of(pair.j, at.q), s_q);
        let length = self.length_from.value(data, |[fi, fj]| {
            let d0 = separation(&fi, s_p, &fj, s_q);
            d0[0].hypot(d0[1])
        });
        out[0] = dot(d, d) - length * length;
    }
}

fields! {
    /// Distance (revolute-revolute link): the two points stay `length` apart. 1 equation.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct DistanceJoint {
        [body_i, point_i, body_j, point_j,]
        /// Distance, m. Default: its value in the initial configuration.
        #[serde(default)]
        pub length: Option<f64>,
    }
}

/// A distance joint at `path` compiled in `cx`: its length as given, or as the initial
/// configuration has it.
pub(crate) fn compile(spec: &DistanceJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let DistanceJoint { body_i, point_i, body_j, point_j, length } = spec;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j)?;
    let [(i, sp), (j, sq)] = ends;
    let length = match length {
        Some(l) => cx.positive(&format!("{path}.length"), *l)?,
        None => {
            let l = cx.initial_distance(ends);
            // Below 1e-12 m the points coincide but for round-off: no length to keep.
            if l < 1e-12 {
                cx.problem(
                    format!("{path}.length"),
                    "the points coincide in the initial configuration: give a positive length",
                );
                return None;
            }
            let mut c = Distance::new(i, sp, j, sq, l);
            c.length_from = Source::start(i, j, cx.q0());
            return Some((Box::new(c), None));
        }
    };
    Some((Box::new(Distance::new(i, sp, j, sq, length)), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{
        assert_close, assert_data_fields, check_fd_random, check_generic_random, evaluate, Lcg,
    };
    use crate::expr::HyperDual;

    #[test]
    fn derivatives_match_finite_differences() {
        let c = Distance::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-1.1, 0.4], 1.7);
        check_fd_random(&c, 2, 1);
        check_generic_random(&c, 2, 1);
        assert_data_fields::<DistanceJoint>(&c);
        let g = Distance::new(BodyIx::GROUND, [0.5, -2.0], BodyIx(Some(3)), [0.75, 0.1], 2.0);
        check_fd_random(&g, 2, 2);
        check_generic_random(&g, 2, 2);
        let h = Distance::new(BodyIx(Some(0)), [0.5, -2.0], BodyIx::GROUND, [0.75, 0.1], 2.0);
        check_fd_random(&h, 2, 3);
        check_generic_random(&h, 2, 3);
    }

    /// A length the initial configuration gives is not a data slot: it is the points' distance at
    /// the held initial poses, so it follows the points. Closed form: with body i's centre at the
    /// origin at angle 0 and body j's at (3, 0) at angle 0, the points (a, 0) and (b, 0) are
    /// `L = 3 + b - a` apart there, and `Phi = |d|^2 - L^2` at any `q` has
    /// `dPhi/da = -2 d . A_i e_x + 2 L` (moving `P` along body i's x moves `d` by `-A_i e_x` and
    /// `L` by `-1`).
    #[test]
    fn a_length_from_the_start_follows_the_points() {
        let q0 = [0.0, 0.0, 0.0, 3.0, 0.0, 0.0];
        let mut c = Distance::new(BodyIx(Some(0)), [0.5, 0.0], BodyIx(Some(3)), [-0.25, 0.0], 2.25);
        c.length_from = Source::start(BodyIx(Some(0)), BodyIx(Some(3)), &q0);
        assert_eq!(
            c.data().iter().map(|d| d.0).collect::<Vec<_>>(),
            ["point_i[0]", "point_i[1]", "point_j[0]", "point_j[1]"]
        );
        check_generic_random(&c, 2, 4);
        let q = Lcg::new(9).vec(6, -1.0, 1.0);
        let qs: Vec<HyperDual> = q.iter().map(|&v| HyperDual::constant(v)).collect();
        let mut data: Vec<HyperDual> = c.data().iter().map(|&(_, v)| HyperDual::constant(v)).collect();
        data[0].e1 = 1.0;
        let mut out = [HyperDual::constant(0.0)];
        c.phi_generic(&At { q: &qs, t: HyperDual::constant(0.0), params: &[] }, &data, &mut out);
        let mut phi = [0.0];
        c.phi_at(&q, 0.0, &mut phi);
        let dx = q[3] - 0.25 * q[5].cos() - q[0] - 0.5 * q[2].cos();
        let dy = q[4] - 0.25 * q[5].sin() - q[1] - 0.5 * q[2].sin();
        let want = -2.0 * (dx * q[2].cos() + dy * q[2].sin()) + 2.0 * 2.25;
        assert!((out[0].v - phi[0]).abs() < 1e-14, "{out:?} vs {phi:?}");
        assert!((out[0].e1 - want).abs() < 1e-14, "{out:?} vs {want}");
    }

    /// Hand-derived: the ground point P = (1, 2) tied by a link of length 2 to the tip s' = (0.5, 0)
    /// of a crank with centre (0.5, 0) at angle 0, so Q = (1, 0), d = (0, -2) and Phi = 4 - 4 = 0.
    /// Crank block: Phi_q_j = 2 d^T [I  B s'] with B s' = (0, 0.5): (0, -4, -2). Spinning the crank
    /// about its centre at omega = 3: d' = B s' omega = (0, 1.5) and A s' omega^2 = (4.5, 0) is
    /// normal to d, so gamma = -2 d'.d' = -4.5.
    #[test]
    fn hand_derived_crank_link() {
        let c = Distance::new(BodyIx::GROUND, [1.0, 2.0], BodyIx(Some(0)), [0.5, 0.0], 2.0);
        let (phi, jac, g) = evaluate(&c, &[0.5, 0.0, 0.0], &[0.0, 0.0, 3.0]);
        assert!(phi[0].abs() < 1e-14, "{phi:?}");
        // d = r_Q - r_P = (1, 0) - (1, 2) = (0, -2); Phi_q_j = 2 d^T [I  B s'] = (0, -4, -2).
        assert_close(&jac, &[0.0, -4.0, -2.0], 1e-14);
        assert!((g[0] + 4.5).abs() < 1e-14, "{g:?}");
    }
}
