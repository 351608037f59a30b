//! Translational (prismatic) joint: point `Q` of body j slides on the line of body i through `P`
//! along `v'_i`, and the bodies keep their relative angle so that the axes `v'_i` and `v'_j` stay
//! parallel. Two rows.
//!
//! ```text
//! n_i   = A_i R90 v'_i / |v'_i|,    d = r_j + A_j s'_Q - r_i - A_i s'_P
//! Phi   = [ n_i . d                 ]                                      (2)
//!         [ phi_i - phi_j - c       ],   c = atan2(v'_j) - atan2(v'_i)
//! Phi_q = [ -n_i^T   (R90 n_i) . d - n_i . B_i s'_P    n_i^T   n_i . B_j s'_Q ]
//!         [  0  0    1                                  0  0   -1             ]   (2 x 6)
//! nu    = 0
//! gamma = [ (n_i . d) omega_i^2 - 2 omega_i (R90 n_i) . d'
//!             + n_i . (A_j s'_Q omega_j^2 - A_i s'_P omega_i^2) ]
//!         [ 0 ]
//! ```
//! `c` comes from the axes, not from an initial configuration: the joint forces `A_i v'_i` and
//! `A_j v'_j` to point the same way. The axes fix it modulo a turn only; [`Translational::near`]
//! takes the whole turns from the starting relative angle, so that a body written a turn away
//! (`phi = 2 pi + 0.1` against the axes' `0.1`) stays on its branch. Haug (1989) section 3.3.2; Nikravesh (2018) section 7.1.

use super::schema::{with_friction, JointContext};
use super::CompiledJoint;
use super::{perp, unit, Anchor, BodyIx, Config, Constraint, Friction, FrictionLaw, Pair, Projection, Shape, Sketch};
use super::{phi_tri_generic, projection, slot2, vector, At, GenericPhi, Pose, AXIS_I, AXIS_J, POINT_I, POINT_J};
use crate::element::fields;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A translational joint between body i (line through `P` along `v_i`) and body j (point `Q`, axis
/// `v_j`).
#[derive(Debug, Clone)]
pub struct Translational {
    pair: Pair,
    line: Projection,
    /// `v'_i` and `v'_j` as given.
    axes: [[f64; 2]; 2],
    c: f64,
    /// The whole turns [`Translational::near`] added to `c` (held: not data).
    turns: f64,
}

impl Translational {
    /// `s_p`, `v_i`: a point of the sliding axis and its direction in body i's frame; `s_q`, `v_j`:
    /// a point of body j on the axis and the axis direction in body j's frame. The directions need
    /// not be unit, but must be non-zero.
    pub fn new(i: BodyIx, s_p: [f64; 2], v_i: [f64; 2], j: BodyIx, s_q: [f64; 2], v_j: [f64; 2]) -> Translational {
        let c = v_j[1].atan2(v_j[0]) - v_i[1].atan2(v_i[0]);
        let line = Projection { i, w: perp(unit(v_i)), s_p, j, s_q };
        Translational { pair: Pair::new(i, j), line, axes: [v_i, v_j], c, turns: 0.0 }
    }

    /// The joint with its angle constant `c` moved by whole turns to the nearest of `relative`
    /// (the starting `phi_i - phi_j`): the axes fix the angle modulo a turn, and a body written a
    /// turn away from them is the same position, to be kept on its branch, not turned back.
    pub fn near(mut self, relative: f64) -> Translational {
        let turn = 2.0 * std::f64::consts::PI;
        let whole = turn * ((relative - self.c) / turn).round();
        self.c += whole;
        self.turns += whole;
        self
    }

    /// Coulomb friction in this joint, its sliding block of `length` (m) centred at body j's point
    /// ([`Friction`]).
    pub fn friction(&self, law: FrictionLaw, length: f64) -> Friction {
        let l = &self.line;
        Friction::slide(law, (l.i, l.s_p, self.axes[0]), (l.j, l.s_q), length)
    }
}

impl Constraint for Translational {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.line.s_p)
    }
    fn sketch(&self) -> Option<Sketch> {
        let l = &self.line;
        Some(Sketch { i: l.i, p: l.s_p, j: l.j, q: l.s_q, shape: Shape::Slide { axis: l.along(), offset: 0.0 } })
    }
    fn row_names(&self) -> &[&'static str] {
        &["line", "angle"]
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.line.value(q);
        out[1] = self.pair.i.coords(q)[2] - self.pair.j.coords(q)[2] - self.c;
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let w = self.pair.width();
        let (bi, bj) = self.line.blocks(q);
        self.pair.scatter(bi, bj, &mut out[..w]);
        self.pair.scatter([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], &mut out[w..2 * w]);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = self.line.gamma(q, qdot);
        out[1] = 0.0;
    }
    /// `point_i`, `point_j`, `axis_i`, `axis_j` (the angle constant follows the axes; its whole
    /// turns, from the initial configuration, are held).
    fn data(&self) -> Vec<(&'static str, f64)> {
        let (l, [v_i, v_j]) = (&self.line, self.axes);
        [vector(POINT_I, l.s_p), vector(POINT_J, l.s_q), vector(AXIS_I, v_i), vector(AXIS_J, v_j)].concat()
    }
    phi_tri_generic!();
}

impl GenericPhi for Translational {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let (v_i, v_j) = (slot2(data, 4), slot2(data, 6));
        let (fi, fj) = (Pose::of(self.pair.i, at.q), Pose::of(self.pair.j, at.q));
        out[0] = projection(perp(unit(v_i)), &fi, slot2(data, 0), &fj, slot2(data, 2));
        let c = (v_j[1].atan2(v_j[0]) - v_i[1].atan2(v_i[0])) + S::constant(self.turns);
        out[1] = fi.phi - fj.phi - c;
    }
}

/// Coulomb friction in a translational joint: a force `mu tanh(v / v_s) (|F| + |M| / L)` opposing
/// the sliding velocity `v`, `|F|` the magnitude of the joint's reaction force and `M` its moment
/// about `point_j`, the centre of the sliding block of length `L` (docs/model-format.md, "Joint
/// friction").
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SlideFriction {
    /// Coefficient of friction, `>= 0`.
    pub mu: f64,
    /// Length of the sliding block (its contact with the guide), centred at `point_j`, m, `> 0`.
    pub length: f64,
    /// Sliding velocity at which the coefficient reaches `tanh(1) = 76%` of `mu`, m/s, `> 0`;
    /// default 0.001.
    #[serde(default)]
    pub transition_velocity: Option<f64>,
}

fields! {
    /// Prismatic: `point_j` of `body_j` slides on the line of `body_i` through `point_i` along
    /// `axis_i`, and the bodies keep the relative angle that makes `axis_i` and `axis_j` parallel.
    /// 2 equations.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct TranslationalJoint {
        [body_i, point_i?, axis_i?, body_j, point_j?, axis_j?, at, axis,]
        /// Coulomb friction in the slider.
        #[serde(default)]
        pub friction: Option<SlideFriction>,
    }
}

/// A translational joint at `path` compiled in `cx`, with its friction.
pub(crate) fn compile(spec: &TranslationalJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let TranslationalJoint { body_i, point_i, axis_i, body_j, point_j, axis_j, at, axis, friction: slide } = spec;
    let points = cx.placed_points(path, [body_i, body_j], [point_i, point_j], at);
    let axes = cx.placed_axes(path, [("axis_i", body_i, axis_i), ("axis_j", body_j, axis_j)], axis);
    let (pi, pj) = points.clone().unwrap_or_default();
    let ends = cx.ends(path, body_i, &pi, body_j, &pj);
    let vi = axes.and_then(|[ai, _]| cx.axis(&format!("{path}.axis_i"), ai));
    let vj = axes.and_then(|[_, aj]| cx.axis(&format!("{path}.axis_j"), aj));
    let law = slide.as_ref().map(|f| cx.sized_friction(path, f.mu, f.transition_velocity, ("length", f.length)));
    let (_, [(i, sp), (j, sq)], vi, vj) = (points?, ends?, vi?, vj?);
    let relative = i.coords(cx.q0())[2] - j.coords(cx.q0())[2];
    with_friction(Translational::new(i, sp, vi, j, sq, vj).near(relative), law, Translational::friction)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{
        assert_close, assert_data_fields, check_fd_random, check_generic_random, evaluate, OnSlice,
    };

    #[test]
    fn derivatives_match_finite_differences() {
        let c = Translational::new(BodyIx(Some(0)), [0.3, -0.2], [1.0, 2.0], BodyIx(Some(3)), [-1.1, 0.4], [0.0, -3.0]);
        check_fd_random(&c, 2, 1);
        check_generic_random(&c, 2, 1);
        assert_data_fields::<TranslationalJoint>(&c);
        let g = Translational::new(BodyIx::GROUND, [0.5, -2.0], [2.0, 0.0], BodyIx(Some(3)), [0.7, 0.1], [1.0, 1.0]);
        check_fd_random(&g, 2, 2);
        check_generic_random(&g.near(-7.0), 2, 2);
        let h = Translational::new(BodyIx(Some(0)), [0.5, -2.0], [0.3, -0.4], BodyIx::GROUND, [0.7, 0.1], [1.0, 0.0]);
        check_fd_random(&h, 2, 3);
        check_generic_random(&h, 2, 3);
    }

    /// The angle constant takes whole turns from the starting relative angle: parallel axes give
    /// `c = 0`, and near `phi_i - phi_j = -2 pi - 0.1` it becomes `-2 pi` (the angle row is
    /// `-0.1` there, not `-2 pi - 0.1`); half a turn away or less it stays.
    #[test]
    fn angle_takes_whole_turns_from_the_start() {
        let turn = 2.0 * std::f64::consts::PI;
        let joint =
            || Translational::new(BodyIx(Some(0)), [0.0, 0.0], [1.0, 0.0], BodyIx(Some(3)), [0.0, 0.0], [2.0, 0.0]);
        assert_eq!(joint().c, 0.0);
        assert_eq!(joint().near(-turn - 0.1).c, -turn);
        assert_eq!(joint().near(2.0 * turn + 3.0).c, 2.0 * turn);
        assert_eq!(joint().near(3.0).c, 0.0);
        let mut phi = [1.0; 2];
        joint().near(-turn - 0.1).phi_at(&[0.0, 0.0, 0.0, 0.0, 0.0, turn + 0.1], 0.0, &mut phi);
        assert!((phi[1] + 0.1).abs() < 1e-14, "{phi:?}");
    }

    /// Hand-derived: a guide (body i) with centre at the origin, angle 0, axis (2, 0) through its
    /// centre; a slider (body j, axis (0, 1) in its own frame) with centre (1.5, 0.25) and s'_Q = 0, at
    /// angle -pi/2 so that its axis points along +x. n_i = (0, 1); d = (1.5, 0.25): line row = 0.25; c = pi/2 - 0 so the angle row is
    /// 0 - (-pi/2) - pi/2 = 0. Line row Phi_phi_i = (R90 n) . d = (-1, 0) . (1.5, 0.25) = -1.5.
    /// With the guide spinning at omega_i = 2 (slider at rest): d' = 0 (P is the guide's centre),
    /// so gamma = (n . d) omega_i^2 = 0.25 * 4 = 1.
    #[test]
    fn hand_derived_slider_on_spinning_guide() {
        let c = Translational::new(BodyIx(Some(0)), [0.0, 0.0], [2.0, 0.0], BodyIx(Some(3)), [0.0, 0.0], [0.0, 1.0]);
        let q = [0.0, 0.0, 0.0, 1.5, 0.25, -std::f64::consts::FRAC_PI_2];
        let qdot = [0.0, 0.0, 2.0, 0.0, 0.0, 0.0];
        let (phi, jac, g) = evaluate(&c, &q, &qdot);
        assert!((phi[0] - 0.25).abs() < 1e-14 && phi[1].abs() < 1e-15, "{phi:?}");
        assert_close(&jac, &[0.0, -1.0, -1.5, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0], 1e-14);
        assert!((g[0] - 1.0).abs() < 1e-14 && g[1] == 0.0, "{g:?}");
    }
}
