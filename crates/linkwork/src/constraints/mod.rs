//! The joint library: one file per joint family, all behind the [`Constraint`] trait.
//!
//! Each constraint contributes `rows()` equations `Phi(q, t) = 0` to the system and supplies, for the
//! columns of `q` it touches, its analytic Jacobian block `Phi_q`, the velocity right-hand side
//! `nu = -Phi_t` and the acceleration right-hand side
//! `gamma = -(Phi_q qdot)_q qdot - 2 Phi_qt qdot - Phi_tt` (Haug 1989, sections 3.3 and 3.4;
//! Nikravesh 2018, chapter 7).
//!
//! Body coordinates: body `k` (ground excluded) owns `q[3k..3k+3] = (x, y, phi)`, the position of
//! its centre of mass and the angle of its frame. A point `P` fixed on body `i` is
//! `r_P = r_i + A(phi_i) s'_P` with `A(phi) = [[cos, -sin], [sin, cos]]`.

mod absolute;
mod belt;
mod cam;
mod cam_profile;
mod distance;
mod driver;
mod expression;
mod friction;
mod gear;
mod point_line;
mod registry;
mod revolute;
mod rolling;
mod schema;
mod translational;

pub(crate) use crate::element::{vector, Frame, Pose, Source, AXIS_I, AXIS_J, POINT, POINT_I, POINT_J};
pub use crate::element::{BodyIx, PointRef, Tagged, DEFAULT_TRANSITION_VELOCITY};
use crate::expr::{Dual, HyperDual, Scalar, TimeTri, Tri};
pub use absolute::{Absolute, AbsoluteAngleJoint, AbsoluteKind, AbsolutePoint};
pub(crate) use cam::cam_row;
pub use cam::{Cam, CamFrame, CamJoint, CamProfileSpec, CamRow, PitchPoint, ProfileColumn};
pub use cam_profile::{CamProfile, Curve, CurveError};
pub use distance::{Distance, DistanceJoint};
pub use driver::{AngleDriver, DistanceDriver, Driver, DriverKind, PointDriver, RelativeAngleDriver};
pub use expression::{ExpressionJoint, GeneralConstraint, Var};
pub use friction::{Friction, FrictionLaw};
pub use gear::{GearJoint, GearKind, GearPair};
pub use point_line::{PointOnLine, PointOnLineJoint, RevoluteTranslationalJoint};
pub use registry::{CompiledJoint, DriverSpec, JointSpec};
pub use revolute::{PinFriction, Revolute, RevoluteJoint};
pub use rolling::{RackPinion, Rolling, RollingDisc, RollingJoint};
pub(crate) use schema::JointContext;
use std::fmt::Debug;
use std::ops::Deref;
pub use translational::{SlideFriction, Translational, TranslationalJoint};

/// Positions `q (n)` together with each body's rotation `(cos phi, sin phi)`, computed once per
/// evaluation of the whole system rather than once per joint (a fifth of the kinematic run's time
/// went to `sin`/`cos` before). Derefs to `q`.
#[derive(Debug, Clone, Copy)]
pub struct Config<'a> {
    q: &'a [f64],
    /// (bodies) `(cos phi, sin phi)` of each body.
    rot: &'a [[f64; 2]],
}

impl<'a> Config<'a> {
    /// A view of `q` with the rotations `rot` that [`Config::rotations`] computed from it.
    #[inline]
    pub fn new(q: &'a [f64], rot: &'a [[f64; 2]]) -> Config<'a> {
        debug_assert_eq!(3 * rot.len(), q.len(), "one rotation per body");
        Config { q, rot }
    }

    /// `(q) => rot`: each body's `(cos phi, sin phi)`, `rot: (bodies)`.
    #[inline]
    pub fn rotations(q: &[f64], rot: &mut [[f64; 2]]) {
        for (r, body) in rot.iter_mut().zip(q.chunks_exact(3)) {
            let (s, c) = body[2].sin_cos();
            *r = [c, s];
        }
    }
}

impl Deref for Config<'_> {
    type Target = [f64];
    #[inline]
    fn deref(&self) -> &[f64] {
        self.q
    }
}

/// An owned [`Config`], for evaluations outside the analysis loops (model compilation, tests).
#[derive(Debug, Clone)]
pub struct ConfigBuf {
    q: Vec<f64>,
    rot: Vec<[f64; 2]>,
}

impl ConfigBuf {
    /// Copy `q` and compute its rotations.
    pub fn new(q: &[f64]) -> ConfigBuf {
        let mut rot = vec![[1.0, 0.0]; q.len() / 3];
        Config::rotations(q, &mut rot);
        ConfigBuf { q: q.to_vec(), rot }
    }
    /// The view the constraints take.
    pub fn view(&self) -> Config<'_> {
        Config::new(&self.q, &self.rot)
    }
}

/// One joint, driver or general constraint: a block of rows of `Phi(q, t) = 0`.
///
/// Implementations are immutable after construction and allocate nothing in these methods, which
/// the analysis loops call at every iteration.
pub trait Constraint: Debug + Send + Sync {
    /// Number of equations this constraint adds: one per row name.
    fn rows(&self) -> usize {
        self.row_names().len()
    }
    /// The first body (whose reaction is reported), the second, and the point of the first body
    /// (its frame; the global frame when it is ground) about which the reaction moment is taken.
    fn anchor(&self) -> Anchor;
    /// A short name for each row, used when a row is reported as redundant or singular.
    fn row_names(&self) -> &[&'static str];
    /// Global indices into `q` of the coordinates the rows depend on (its Jacobian columns).
    fn columns(&self) -> &[usize];
    /// `(q, t) => Phi`, `out: (rows)`.
    fn phi(&self, q: &Config<'_>, t: f64, out: &mut [f64]);
    /// `(q, t) => Phi_q` restricted to `columns()`, `out: (rows x columns().len())`, row-major.
    fn jacobian(&self, q: &Config<'_>, t: f64, out: &mut [f64]);
    /// `(q, t) => nu = -Phi_t`, `out: (rows)`. Zero unless the rows depend on time explicitly
    /// (drivers, general constraints in `t`).
    fn nu(&self, _q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[..self.rows()].fill(0.0);
    }
    /// `(q, qdot, t) => gamma`, `out: (rows)`.
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], t: f64, out: &mut [f64]);
    /// The function of time a driver prescribes, for messages (`None` for a joint).
    fn time_function(&self) -> Option<&crate::expr::TimeFunction> {
        None
    }
    /// What a value that is not finite means for this row, when it has a cause of its own (a
    /// cam's nearest point that is not unique), for the error that stops an analysis there.
    fn non_finite_cause(&self) -> Option<&'static str> {
        None
    }
    /// How the joint is drawn (the report's picture of the mechanism); `None` for rows with no
    /// picture of their own (drivers, general constraints).
    fn sketch(&self) -> Option<Sketch> {
        None
    }
    /// The coordinate a driver prescribes (the report plots against it); `None` for a joint.
    fn driven(&self) -> Option<&DriverKind> {
        None
    }
    /// The numbers of this element that a parameter can move (its points, lengths, radii,
    /// axes), each named as its field in the model file, with the component for a vector:
    /// `point_i[0]`, `point_i[1]`, `length`. The model's compiler gives each its derivative with
    /// respect to the parameters under the same name (design sensitivities, docs/sensitivities.md).
    fn data(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// `Phi` at `at`, over [`Tri`] numbers, with the element's own numbers `data` in the order of
    /// [`Constraint::data`] (each seeded with its derivative along a parameter): `out: (rows)`.
    /// Every derivative of the rows that a sensitivity needs (with respect to the coordinates,
    /// time, the data and the parameters, to third order) follows from this one function.
    /// `false`: the element has no derivatives with respect to its data yet.
    fn phi_tri(&self, _at: &At<'_, Tri>, _data: &[Tri], _out: &mut [Tri]) -> bool {
        false
    }
    /// [`Constraint::phi_tri`] over [`Dual`] numbers: the first derivatives alone, which the
    /// position level of a sensitivity needs, at a quarter of the work.
    fn phi_dual(&self, _at: &At<'_, Dual>, _data: &[Dual], _out: &mut [Dual]) -> bool {
        false
    }
    /// [`Constraint::phi_tri`] over [`HyperDual`] numbers: the derivatives to the second order
    /// along two directions, which the velocity level of a sensitivity needs, at half the work.
    fn phi_hyper(&self, _at: &At<'_, HyperDual>, _data: &[HyperDual], _out: &mut [HyperDual]) -> bool {
        false
    }
    /// [`Constraint::phi_tri`] over [`TimeTri`] numbers, `Tri` with its first two directions one
    /// (time): the acceleration level of a kinematic sensitivity, the same parts for less work.
    fn phi_time_tri(&self, _at: &At<'_, TimeTri>, _data: &[TimeTri], _out: &mut [TimeTri]) -> bool {
        false
    }
    /// The model's parameters (their indices, sorted) the rows read besides the element's
    /// numbers ([`Constraint::data`]): those of a driver's function or of an expression (the
    /// generic rows' own list, which every element with them gives). `None` when not known, taken
    /// as every parameter. A
    /// parameter that moves none of these nor the data leaves the rows where they are: their
    /// derivative along it at fixed coordinates and time is zero.
    fn parameters(&self) -> Option<&[usize]> {
        None
    }
}

/// An element's `Phi` written once over any [`Scalar`], with the element's data in the order of
/// [`Constraint::data`]: `out: (rows)`. Over `f64` with `data()`'s values it is `phi` (the same
/// arithmetic, up to the order of a few operations and the rotations computed rather than
/// cached); over [`Tri`] it is [`Constraint::phi_tri`], which [`phi_tri_generic!`] forwards to it.
pub(crate) trait GenericPhi {
    /// `(at, data) => Phi`, `out: (rows)`.
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]);
    /// The model's parameters (their indices, sorted) that [`GenericPhi::phi_generic`] reads
    /// from `at.params`: those of a driver's function or of an expression. Required, so that
    /// no element can leave it out: a design sensitivity skips the element for a parameter
    /// that moves neither these nor its data ([`Constraint::parameters`]).
    fn parameters(&self) -> &[usize];
}

/// [`Constraint::phi_tri`], [`Constraint::phi_dual`], [`Constraint::phi_hyper`] and
/// [`Constraint::phi_time_tri`] of an element, and its [`Constraint::parameters`],
/// that implements [`GenericPhi`], written inside its `impl Constraint`.
macro_rules! phi_tri_generic {
    () => {
        $crate::constraints::phi_tri_generic!(phi_tri, $crate::expr::Tri);
        $crate::constraints::phi_tri_generic!(phi_dual, $crate::expr::Dual);
        $crate::constraints::phi_tri_generic!(phi_hyper, $crate::expr::HyperDual);
        $crate::constraints::phi_tri_generic!(phi_time_tri, $crate::expr::TimeTri);
        fn parameters(&self) -> Option<&[usize]> {
            Some($crate::constraints::GenericPhi::parameters(self))
        }
    };
    ($name:ident, $S:ty) => {
        fn $name(&self, at: &$crate::constraints::At<'_, $S>, data: &[$S], out: &mut [$S]) -> bool {
            $crate::constraints::GenericPhi::phi_generic(self, at, data, out);
            true
        }
    };
}
pub(crate) use phi_tri_generic;

/// `data[k..k + 2]`: a vector among an element's data.
#[inline]
pub(crate) fn slot2<S: Copy>(data: &[S], k: usize) -> [S; 2] {
    [data[k], data[k + 1]]
}

/// `(2)` `d = r_Q - r_P` over any [`Scalar`], from `P` (`s_p`, frame `fi`) to `Q` (`s_q`, frame
/// `fj`), summed as [`Separation::of`] sums it.
#[inline]
pub(crate) fn separation<S: Scalar>(fi: &Pose<S>, s_p: [S; 2], fj: &Pose<S>, s_q: [S; 2]) -> [S; 2] {
    difference(fi.o, fi.rotate(s_p), fj.o, fj.rotate(s_q))
}

/// `w . d` over any [`Scalar`]: [`Projection`]'s row with the direction `w` (body i frame) and the
/// points given.
#[inline]
pub(crate) fn projection<S: Scalar>(w: [S; 2], fi: &Pose<S>, s_p: [S; 2], fj: &Pose<S>, s_q: [S; 2]) -> S {
    dot(fi.rotate(w), separation(fi, s_p, fj, s_q))
}

/// `(o_j - o_i) + (a_q - a_p)`: a separation from the origins and the rotated offsets, the
/// origins' difference first (see [`Separation::of`]).
#[inline]
fn difference<S: Scalar>(o_i: [S; 2], a_p: [S; 2], o_j: [S; 2], a_q: [S; 2]) -> [S; 2] {
    [(o_j[0] - o_i[0]) + (a_q[0] - a_p[0]), (o_j[1] - o_i[1]) + (a_q[1] - a_p[1])]
}

/// Where an element's equations are evaluated over a number type `S` that carries derivatives
/// (design sensitivities): every coordinate `q (n)`, the time, and the model's parameters
/// (file order, SI), which expressions in the element (a driver's function) read.
#[derive(Debug, Clone, Copy)]
pub struct At<'a, S> {
    /// All coordinates.
    pub q: &'a [S],
    /// Time.
    pub t: S,
    /// The parameters' values.
    pub params: &'a [S],
}

/// A joint as a picture: the point `p` of body i and the point `q` of body j it joins (each in
/// its body's frame; ground's frame is the global one), and its shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sketch {
    /// The first body.
    pub i: BodyIx,
    /// Its point, body i frame, m.
    pub p: [f64; 2],
    /// The second body.
    pub j: BodyIx,
    /// Its point, body j frame, m.
    pub q: [f64; 2],
    /// What is drawn at the points.
    pub shape: Shape,
}

/// The shape of a [`Sketch`], serialized as `{"shape": "pin"}`, `{"shape": "slide", "axis": [..],
/// "offset": ..}` and so on.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Shape {
    /// A pin: `p` and `q` coincide.
    Pin,
    /// `q` slides on body i's guide line through `p` along `axis` (body i frame, unit), at a
    /// signed distance `offset` (m) to its left.
    Slide {
        /// Direction of the guide, body i frame, unit.
        axis: [f64; 2],
        /// Signed distance of `q` from the line, m (0 for a slider or pin-in-slot).
        offset: f64,
    },
    /// A massless rod from `p` to `q`.
    Rod,
    /// Pitch circles of radius `r_i` about `p` and `r_j` about `q` (m); `internal`: j is a ring.
    Gears {
        /// Pitch radius of gear i, m.
        r_i: f64,
        /// Pitch radius of gear j, m.
        r_j: f64,
        /// Whether gear j is a ring with gear i inside it.
        internal: bool,
    },
    /// A disc of `radius` (m) about `q` rolling on body i's line through `p` along `axis`.
    Disc {
        /// Direction of the line, body i frame, unit.
        axis: [f64; 2],
        /// Radius (pitch radius of a pinion), m.
        radius: f64,
    },
    /// Body i's point `p` held in x, y or angle against ground (`j` is ground, `q = p`).
    Held,
}

/// Where a joint's reaction is reported: on body `i`, about `point` (body i frame), with `j` the
/// body the joint connects it to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    /// The first body.
    pub i: BodyIx,
    /// The second body (ground when there is none).
    pub j: BodyIx,
    /// The reaction point, body i frame.
    pub point: [f64; 2],
}

/// The reaction of a joint on its first body, from the multipliers `lambda` of its rows: the
/// force `f` (global frame) and its moment about `anchor.point` (body i frame; the global frame
/// when body i is ground). `columns` and `block` are the joint's Jacobian columns and block
/// (`rows x columns`, row-major) at `q`. Generic over [`Scalar`] so that friction, which depends on
/// the reaction, gets its exact derivatives by the multipliers.
///
/// ```text
/// g_b = -Phi_q,b^T lambda          generalised reaction on body b: (fx, fy, moment about its centre)
/// body i moving:  f = g_i[0..2],   moment = g_i[2] - (A_i s'_P) x f
/// body i ground:  f = -g_j[0..2],  moment = -(g_j[2] + (r_j - P) x g_j[0..2])
/// ```
pub fn reaction<S: Scalar>(
    anchor: Anchor,
    columns: &[usize],
    block: &[f64],
    lambda: &[S],
    q: &Config<'_>,
) -> ([S; 2], S) {
    let Anchor { i, j, point } = anchor;
    let lever = match i.0 {
        Some(_) => Frame::of(i, q).rotate(point),
        None => {
            let rj = j.coords(q);
            [rj[0] - point[0], rj[1] - point[1]]
        }
    };
    reaction_about(anchor, columns, |k| S::constant(block[k]), lambda, lever.map(S::constant))
}

/// [`reaction`] with everything it reads over `S` (design sensitivities differentiate it along
/// the Jacobian's, the multipliers' and the point's derivatives): `block(k)` the `k`-th entry of
/// the joint's Jacobian block (row-major), and `lever` the vector the moment is moved by: body i
/// moving, `A_i s'_P` (global frame, from its centre to `P`); body i ground, `r_j - P` ([`lever`]).
pub fn reaction_about<S: Scalar>(
    anchor: Anchor,
    columns: &[usize],
    block: impl Fn(usize) -> S,
    lambda: &[S],
    lever: [S; 2],
) -> ([S; 2], S) {
    let w = columns.len();
    // g = -Phi_q,b^T lambda on the body's columns. The sum starts at -0.0, as `f64`'s `Sum`
    // does, so that the result is bit for bit that of the sum it replaced.
    let generalised = |body: BodyIx| -> [S; 3] {
        let mut g = [S::constant(0.0); 3];
        let Some(b) = body.0 else { return g };
        for (ci, &col) in columns.iter().enumerate() {
            if (b..b + 3).contains(&col) {
                let sum = lambda.iter().enumerate().fold(S::constant(-0.0), |a, (ri, &l)| a + block(ri * w + ci) * l);
                g[col - b] = -sum;
            }
        }
        g
    };
    let Anchor { i, j, .. } = anchor;
    let a = lever;
    match i.0 {
        Some(_) => {
            // Moment about P = moment about the centre of mass - (A s'_P) x f.
            let [fx, fy, m] = generalised(i);
            ([fx, fy], m - (a[0] * fy - a[1] * fx))
        }
        None => {
            // On ground: the opposite of the reaction on body j, its moment taken about P.
            let [fx, fy, m] = generalised(j);
            ([-fx, -fy], -(m + a[0] * fy - a[1] * fx))
        }
    }
}

/// The lever of [`reaction_about`] over any [`Scalar`], from all coordinates `q (n)` and the
/// reaction point `point` (body i frame).
pub fn lever<S: Scalar>(anchor: Anchor, point: [S; 2], q: &[S]) -> [S; 2] {
    match anchor.i.0 {
        Some(_) => Pose::of(anchor.i, q).rotate(point),
        None => {
            let rj = Pose::of(anchor.j, q).o;
            [rj[0] - point[0], rj[1] - point[1]]
        }
    }
}

impl Frame {
    #[inline]
    pub fn of(body: BodyIx, q: &Config<'_>) -> Frame {
        match body.0 {
            Some(k) => {
                let [c, s] = q.rot[k / 3];
                Frame { x: q[k], y: q[k + 1], phi: q[k + 2], c, s }
            }
            None => Frame { x: 0.0, y: 0.0, phi: 0.0, c: 1.0, s: 0.0 },
        }
    }
}

/// `R90 v`: `v` turned by +90 degrees.
#[inline]
pub(crate) fn perp<S: Scalar>(v: [S; 2]) -> [S; 2] {
    [-v[1], v[0]]
}

/// `a . b`.
#[inline]
pub(crate) fn dot<S: Scalar>(a: [S; 2], b: [S; 2]) -> S {
    a[0] * b[0] + a[1] * b[1]
}

/// The two bodies of a joint and the Jacobian columns they own.
///
/// Joint code computes full `1 x 3` Jacobian blocks for both bodies; [`Pair::scatter`] keeps the
/// blocks of bodies that have coordinates, in the order of [`Pair::columns`].
#[derive(Debug, Clone)]
pub(crate) struct Pair {
    pub i: BodyIx,
    pub j: BodyIx,
    columns: Vec<usize>,
}

impl Pair {
    pub fn new(i: BodyIx, j: BodyIx) -> Pair {
        let columns = [i, j].iter().filter_map(|b| b.0).flat_map(|k| [k, k + 1, k + 2]).collect();
        Pair { i, j, columns }
    }
    pub fn columns(&self) -> &[usize] {
        &self.columns
    }
    /// The joint's reaction reported on body i about `point` (body i frame).
    pub fn anchor(&self, point: [f64; 2]) -> Anchor {
        Anchor { i: self.i, j: self.j, point }
    }
    /// Write one Jacobian row from the blocks of body i and body j into `out` (the row's slice).
    #[inline]
    pub fn scatter(&self, row_i: [f64; 3], row_j: [f64; 3], out: &mut [f64]) {
        let mut k = 0;
        if self.i.0.is_some() {
            out[..3].copy_from_slice(&row_i);
            k = 3;
        }
        if self.j.0.is_some() {
            out[k..k + 3].copy_from_slice(&row_j);
        }
    }
    /// Number of Jacobian columns (0, 3 or 6).
    #[inline]
    pub fn width(&self) -> usize {
        self.columns.len()
    }
}

/// The unit vector along `v` (callers guarantee `v != 0`).
#[inline]
pub(crate) fn unit<S: Scalar>(v: [S; 2]) -> [S; 2] {
    let n = v[0].hypot(v[1]);
    [v[0] / n, v[1] / n]
}

/// `d = r_Q - r_P` from a point `P` of body i to a point `Q` of body j, with the rotated body vectors
/// its derivatives need. Any scalar row `f(d)` gets its Jacobian from [`Separation::chain`] and the
/// acceleration-free part of its second time derivative from [`Separation::rate`] and
/// [`Separation::accel_free`]:
///
/// ```text
/// d      = r_j + A_j s'_Q - r_i - A_i s'_P
/// d_q    = [ -I   -B_i s'_P   I   B_j s'_Q ]                     (2 x 6), B s' = R90 A s'
/// d'     = r_j' + omega_j R90 A_j s'_Q - r_i' - omega_i R90 A_i s'_P
/// d''    = (terms in qddot) + A_i s'_P omega_i^2 - A_j s'_Q omega_j^2
/// ```
#[derive(Debug, Clone, Copy)]
pub(crate) struct Separation {
    /// `(2)` `r_Q - r_P`.
    pub d: [f64; 2],
    /// `(2)` `A_i s'_P`.
    pub a_p: [f64; 2],
    /// `(2)` `A_j s'_Q`.
    pub a_q: [f64; 2],
    /// `(2)` `(phi_i, phi_j)`.
    pub phi: [f64; 2],
}

/// Two body points, `P` on body i and `Q` on body j: what the distance joint and the distance
/// driver share.
#[derive(Debug, Clone)]
pub(crate) struct PointPair {
    pub pair: Pair,
    pub s_p: [f64; 2],
    pub s_q: [f64; 2],
}

impl PointPair {
    pub fn anchor(&self) -> Anchor {
        self.pair.anchor(self.s_p)
    }
    pub fn new(i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2]) -> PointPair {
        PointPair { pair: Pair::new(i, j), s_p, s_q }
    }
    /// `d = r_Q - r_P` and its derivatives.
    #[inline]
    pub fn separation(&self, q: &Config<'_>) -> Separation {
        Separation::of(self.pair.i, self.s_p, self.pair.j, self.s_q, q)
    }
}

impl Separation {
    /// `(q) => d` and the rotated body vectors.
    #[inline]
    pub fn of(i: BodyIx, s_p: [f64; 2], j: BodyIx, s_q: [f64; 2], q: &Config<'_>) -> Separation {
        let (fi, fj) = (Frame::of(i, q), Frame::of(j, q));
        let (a_p, a_q) = (fi.rotate(s_p), fj.rotate(s_q));
        // The origins' difference, then the offsets': the round-off is the offsets' (metres), not
        // the positions' (far from the origin, much larger), and Newton near a singular position
        // multiplies it by |B^-1| (docs/integrators.md, `abam`).
        let d = difference([fi.x, fi.y], a_p, [fj.x, fj.y], a_q);
        Separation { d, a_p, a_q, phi: [fi.phi, fj.phi] }
    }
    /// `g = df/dd => (f_{q_i}, f_{q_j})`: the `1 x 3` Jacobian blocks of a scalar `f(d)`.
    #[inline]
    pub fn chain(&self, g: [f64; 2]) -> ([f64; 3], [f64; 3]) {
        ([-g[0], -g[1], -dot(g, perp(self.a_p))], [g[0], g[1], dot(g, perp(self.a_q))])
    }
    /// `(qdot_i, qdot_j) => d'`.
    #[inline]
    pub fn rate(&self, qd_i: [f64; 3], qd_j: [f64; 3]) -> [f64; 2] {
        let (bp, bq) = (perp(self.a_p), perp(self.a_q));
        [qd_j[0] + bq[0] * qd_j[2] - qd_i[0] - bp[0] * qd_i[2], qd_j[1] + bq[1] * qd_j[2] - qd_i[1] - bp[1] * qd_i[2]]
    }
    /// `(omega_i, omega_j) => d''` at zero accelerations: `A_i s'_P omega_i^2 - A_j s'_Q omega_j^2`.
    #[inline]
    pub fn accel_free(&self, w_i: f64, w_j: f64) -> [f64; 2] {
        let (wi2, wj2) = (w_i * w_i, w_j * w_j);
        [self.a_p[0] * wi2 - self.a_q[0] * wj2, self.a_p[1] * wi2 - self.a_q[1] * wj2]
    }
}

/// `Phi = w . d`: the component along a direction `w = A_i w'` fixed in body i of the separation
/// `d = r_Q - r_P` from `P` on body i to `Q` on body j. The line-type rows (translational,
/// point-on-line, rolling) are this with `w'` the unit normal or direction of a line of body i.
///
/// ```text
/// Phi     = w . d
/// Phi_q_i = [ -w^T   (R90 w) . d - w . B_i s'_P ]
/// Phi_q_j = [  w^T   w . B_j s'_Q ]
/// gamma   = (w . d) omega_i^2 - 2 omega_i (R90 w) . d' + w . (A_j s'_Q omega_j^2 - A_i s'_P omega_i^2)
/// ```
/// from `w' = omega_i R90 w` and `w'' = alpha_i R90 w - omega_i^2 w` (Haug 1989, section 3.3.2).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Projection {
    pub i: BodyIx,
    /// `(2)` the direction in body i's frame (unit when the row must be a distance).
    pub w: [f64; 2],
    pub s_p: [f64; 2],
    pub j: BodyIx,
    pub s_q: [f64; 2],
}

impl Projection {
    /// The line's direction when `w` is its unit normal `R90 u`: `u = -R90 w`.
    pub fn along(&self) -> [f64; 2] {
        [self.w[1], -self.w[0]]
    }
    #[inline]
    fn geometry(&self, q: &Config<'_>) -> ([f64; 2], Separation) {
        let w = Frame::of(self.i, q).rotate(self.w);
        (w, Separation::of(self.i, self.s_p, self.j, self.s_q, q))
    }
    /// `(q) => w . d`.
    #[inline]
    pub fn value(&self, q: &Config<'_>) -> f64 {
        let (w, sep) = self.geometry(q);
        dot(w, sep.d)
    }
    /// `(q) => (Phi_q_i, Phi_q_j)`, `1 x 3` each.
    #[inline]
    pub fn blocks(&self, q: &Config<'_>) -> ([f64; 3], [f64; 3]) {
        let (w, sep) = self.geometry(q);
        let (mut bi, bj) = sep.chain(w);
        bi[2] += dot(perp(w), sep.d);
        (bi, bj)
    }
    /// `(q, qdot) => gamma`.
    #[inline]
    pub fn gamma(&self, q: &Config<'_>, qdot: &[f64]) -> f64 {
        let (w, sep) = self.geometry(q);
        let (qd_i, qd_j) = (self.i.coords(qdot), self.j.coords(qdot));
        let wi = qd_i[2];
        let free = sep.accel_free(wi, qd_j[2]);
        dot(w, sep.d) * wi * wi - 2.0 * wi * dot(perp(w), sep.rate(qd_i, qd_j)) - dot(w, free)
    }
}

#[cfg(test)]
pub(crate) mod testing;
