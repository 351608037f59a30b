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
use crate::element::fields;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Two body points at a fixed distance.
#[derive(Debug, Clone)]
pub struct Distance {
    points: PointPair,
    length: f64,
}

impl Distance {
    /// `s_p`, `s_q`: the points in the frames of body i and body j; `length`: their distance (m).
    pub fn new(i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2], length: f64) -> Distance {
        Distance { points: PointPair::new(i, s_p, j, s_q), length }
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
            l
        }
    };
    Some((Box::new(Distance::new(i, sp, j, sq, length)), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{assert_close, check_fd_random, evaluate};

    #[test]
    fn derivatives_match_finite_differences() {
        let c = Distance::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-1.1, 0.4], 1.7);
        check_fd_random(&c, 2, 1);
        let g = Distance::new(BodyIx::GROUND, [0.5, -2.0], BodyIx(Some(3)), [0.75, 0.1], 2.0);
        check_fd_random(&g, 2, 2);
        let h = Distance::new(BodyIx(Some(0)), [0.5, -2.0], BodyIx::GROUND, [0.75, 0.1], 2.0);
        check_fd_random(&h, 2, 3);
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
