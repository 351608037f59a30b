//! Point on line: point `Q` of body j stays at a signed distance `e` from the line of body i
//! through `P` along `v'_i`. One row. With `e = 0` it is the pin-in-slot joint; with `e != 0` it
//! is the revolute-translational composite joint (a massless link of length `e`, pinned to body j
//! at `Q` and sliding perpendicular to itself along body i's line; Haug 1989 section 3.4.2).
//!
//! ```text
//! n_i   = A_i R90 v'_i / |v'_i|,    d = r_j + A_j s'_Q - r_i - A_i s'_P
//! Phi   = n_i . d - e
//! Phi_q = [ -n_i^T   (R90 n_i) . d - n_i . B_i s'_P    n_i^T   n_i . B_j s'_Q ]      (1 x 6)
//! nu    = 0
//! gamma = (n_i . d) omega_i^2 - 2 omega_i (R90 n_i) . d' + n_i . (A_j s'_Q omega_j^2 - A_i s'_P omega_i^2)
//! ```
//! `e > 0` puts `Q` on the left of the line (the side `R90 v'_i` points to). Haug (1989) sections
//! 3.3.2 and 3.4.2; Nikravesh (2018) section 7.1.

use super::schema::JointContext;
use super::CompiledJoint;
use super::Frame;
use super::{perp, unit, Anchor, BodyIx, Config, Constraint, Pair, Projection, Shape, Sketch};
use super::{phi_tri_generic, projection, slot2, vector, At, GenericPhi, Pose, Source, AXIS_I, POINT_I, POINT_J};
use crate::element::fields;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A point of body j on (or at a fixed offset from) a line of body i.
#[derive(Debug, Clone)]
pub struct PointOnLine {
    pair: Pair,
    line: Projection,
    /// `v'_i` as given.
    axis: [f64; 2],
    offset: f64,
    /// Where `offset` comes from: the file (a data slot), the initial configuration, or none (a pin
    /// in a slot).
    offset_from: Source,
}

impl PointOnLine {
    /// `s_p`, `v_i`: a point of the line and its direction in body i's frame (non-zero, need not be
    /// unit); `s_q`: the point of body j; `offset`: its signed distance from the line (m), positive
    /// on the left of `v_i`.
    pub fn new(i: BodyIx, s_p: [f64; 2], v_i: [f64; 2], j: BodyIx, s_q: [f64; 2], offset: f64) -> PointOnLine {
        let line = Projection { i, w: perp(unit(v_i)), s_p, j, s_q };
        PointOnLine { pair: Pair::new(i, j), line, axis: v_i, offset, offset_from: Source::File }
    }
}

impl Constraint for PointOnLine {
    fn anchor(&self) -> Anchor {
        self.pair.anchor(self.line.s_p)
    }
    fn sketch(&self) -> Option<Sketch> {
        let l = &self.line;
        Some(Sketch {
            i: l.i,
            p: l.s_p,
            j: l.j,
            q: l.s_q,
            shape: Shape::Slide { axis: l.along(), offset: self.offset },
        })
    }
    fn row_names(&self) -> &[&'static str] {
        &["line"]
    }
    fn columns(&self) -> &[usize] {
        self.pair.columns()
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.line.value(q) - self.offset;
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let (bi, bj) = self.line.blocks(q);
        self.pair.scatter(bi, bj, out);
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = self.line.gamma(q, qdot);
    }
    /// `point_i`, `point_j`, `axis_i`, and `offset` when the file gives it.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let l = &self.line;
        let data = [vector(POINT_I, l.s_p), vector(POINT_J, l.s_q), vector(AXIS_I, self.axis)].concat();
        self.offset_from.data(data, "offset", self.offset)
    }
    phi_tri_generic!();
}

impl GenericPhi for PointOnLine {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let (s_p, s_q, w) = (slot2(data, 0), slot2(data, 2), perp(unit(slot2(data, 4))));
        let value = |[fi, fj]: [Pose<S>; 2]| projection(w, &fi, s_p, &fj, s_q);
        let offset = self.offset_from.value(data, value);
        out[0] = value([Pose::of(self.pair.i, at.q), Pose::of(self.pair.j, at.q)]) - offset;
    }
}

fields! {
    /// Pin in slot: `point_j` of `body_j` stays on the line of `body_i` through `point_i` along
    /// `axis_i`; rotation stays free. 1 equation.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct PointOnLineJoint {
        [body_i, point_i?, axis_i?, body_j, point_j?, at, axis,]
        }
}

fields! {
    /// Revolute-translational composite: `point_j` of `body_j` keeps a constant signed distance
    /// `offset` from the line of `body_i` (a link pinned at `point_j` and sliding, at right angles,
    /// on the line). 1 equation.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct RevoluteTranslationalJoint {
        [body_i, point_i, axis_i, body_j, point_j,]
        /// Signed distance from the line to the pin (positive to the left of `axis_i`), m.
        /// Default: its value in the initial configuration.
        #[serde(default)]
        pub offset: Option<f64>,
    }
}

/// A point-on-line joint at `path` compiled in `cx`.
pub(crate) fn compile(spec: &PointOnLineJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let PointOnLineJoint { body_i, point_i, axis_i, body_j, point_j, at, axis } = spec;
    let points = cx.placed_points(path, [body_i, body_j], [point_i, point_j], at);
    let axes = cx.placed_axes(path, [("axis_i", body_i, axis_i)], axis);
    let (pi, pj) = points.clone().unwrap_or_default();
    let ends = cx.ends(path, body_i, &pi, body_j, &pj);
    let vi = axes.and_then(|[ai]| cx.axis(&format!("{path}.axis_i"), ai));
    let (_, [(i, sp), (j, sq)], vi) = (points?, ends?, vi?);
    let mut c = PointOnLine::new(i, sp, vi, j, sq, 0.0);
    c.offset_from = Source::Zero;
    Some((Box::new(c), None))
}

/// A revolute-translational joint at `path` compiled in `cx`: its offset as given, or as the
/// initial configuration has it.
pub(crate) fn compile_offset(
    spec: &RevoluteTranslationalJoint,
    cx: &mut impl JointContext,
    path: &str,
) -> Option<CompiledJoint> {
    let RevoluteTranslationalJoint { body_i, point_i, axis_i, body_j, point_j, offset } = spec;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j);
    let v = cx.axis(&format!("{path}.axis_i"), *axis_i);
    let ([(i, sp), (j, sq)], vi) = (ends?, v?);
    let (offset, offset_from) = match offset {
        Some(o) => (cx.finite(&format!("{path}.offset"), *o)?, Source::File),
        None => {
            let (fi, fj) = (Frame::of_slice(i, cx.q0()), Frame::of_slice(j, cx.q0()));
            let (p, r, a) = (fi.point(sp), fj.point(sq), fi.rotate(vi));
            let n = [-a[1], a[0]];
            (((r[0] - p[0]) * n[0] + (r[1] - p[1]) * n[1]) / a[0].hypot(a[1]), Source::start(i, j, cx.q0()))
        }
    };
    let mut c = PointOnLine::new(i, sp, vi, j, sq, offset);
    c.offset_from = offset_from;
    Some((Box::new(c), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{
        assert_close, assert_data_fields, check_fd_random, check_generic_random, evaluate, Lcg,
    };

    #[test]
    fn derivatives_match_finite_differences() {
        let c = PointOnLine::new(BodyIx(Some(0)), [0.3, -0.2], [1.0, 2.0], BodyIx(Some(3)), [-1.1, 0.4], 0.0);
        check_fd_random(&c, 2, 1);
        check_generic_random(&c, 2, 1);
        assert_data_fields::<RevoluteTranslationalJoint>(&c);
        let g = PointOnLine::new(BodyIx::GROUND, [0.5, -2.0], [2.0, 0.5], BodyIx(Some(3)), [0.7, 0.1], 0.3);
        check_fd_random(&g, 2, 2);
        check_generic_random(&g, 2, 2);
        let h = PointOnLine::new(BodyIx(Some(0)), [0.5, -2.0], [0.3, -0.4], BodyIx::GROUND, [0.7, 0.1], -1.2);
        check_fd_random(&h, 2, 3);
        check_generic_random(&h, 2, 3);
    }

    /// A pin in a slot has no offset among its data; an offset from the initial configuration is
    /// the point's distance from the line at the held initial poses, so it follows the data.
    #[test]
    fn offsets_that_are_not_data() {
        let q0 = Lcg::new(8).vec(6, -2.0, 2.0);
        let new = |from: Source| {
            let mut c = PointOnLine::new(BodyIx(Some(0)), [0.3, -0.2], [1.0, 2.0], BodyIx(Some(3)), [-1.1, 0.4], 0.0);
            c.offset_from = from;
            c
        };
        let slot = new(Source::Zero);
        assert_eq!(slot.data().len(), 6);
        assert_data_fields::<PointOnLineJoint>(&slot);
        check_generic_random(&slot, 2, 4);
        let mut start = new(Source::start(BodyIx(Some(0)), BodyIx(Some(3)), &q0));
        start.offset = start.line.value(&crate::constraints::ConfigBuf::new(&q0).view());
        assert_eq!(start.data().len(), 6);
        check_generic_random(&start, 2, 5);
    }

    /// Hand-derived: a slotted crank (body i) with centre at the origin, angle 0, slot along (3, 0)
    /// through its centre, and a ground pin Q = (1, 0.5) held at offset 0.5: n = (0, 1), d = (1, 0.5),
    /// Phi = 0.5 - 0.5 = 0. Turning the slot by delta gives n . d = 0.5 cos(delta) - sin(delta), so
    /// Phi_phi_i = -1. Spinning it at omega = 2: Phi(t) = 0.5 cos(2t) - sin(2t), Phi'' = -2 at t = 0,
    /// gamma = 2.
    #[test]
    fn hand_derived_spinning_slot() {
        let c = PointOnLine::new(BodyIx(Some(0)), [0.0, 0.0], [3.0, 0.0], BodyIx::GROUND, [1.0, 0.5], 0.5);
        let (phi, jac, g) = evaluate(&c, &[0.0, 0.0, 0.0], &[0.0, 0.0, 2.0]);
        assert!(phi[0].abs() < 1e-15, "{phi:?}");
        assert_close(&jac, &[0.0, -1.0, -1.0], 1e-14);
        assert!((g[0] - 2.0).abs() < 1e-14, "{g:?}");
    }
}
