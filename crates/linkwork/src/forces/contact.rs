//! Unilateral contact between a circle fixed to body a and a circle or polyline fixed to body b
//! (docs/model-format.md, "Contact").
//!
//! ```text
//! circle-circle:    d = c_a - c_b,  l = |d|,  delta = r_a + r_b - l,  n = d / l
//!                   P = c_b + n (r_b - delta / 2)
//! circle-polyline:  Q the point of the polyline closest to c_a,  d = c_a - Q,  l = |d|,
//!                   delta = r_a - l,  n = d / l,  P = Q - n delta / 2
//! slip:             w = v_a(P) - v_b(P),  v(P) = rdot + omega R90 (P - r)
//!                   ddelta/dt = -n . w,  v_t = t . w,  t = R90 n
//! normal:           F_n = max(0, k delta^e (1 + c ddelta/dt))   (delta > 0; else no force)
//! friction:         F_t = -mu F_n tanh(v_t / v_s)
//! on a:             f = F_n n + F_t t at P;  on b: -f at P;  V = k delta^(e+1) / (e+1)
//! ```
//!
//! `n` points from b into a, `P` is the middle of the overlap. The normal law is Hunt and
//! Crossley's (1975), `F_n = k delta^e (1 + (3/2) alpha ddelta/dt)` with `c = 3 alpha / 2`; it
//! vanishes at first touch and at separation, and the clamp keeps it from pulling as the bodies
//! part. Polylines are two-sided: the penetration must stay below the circle's radius.

use super::{cross, layout, rotate, Data, Force, ForceContext, ForceLaw, Local};
use crate::element::{BodyIx, Context, DEFAULT_TRANSITION_VELOCITY};
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

/// The shape of body b.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A circle: centre (body frame) and radius.
    Circle([f64; 2], f64),
    /// A chain of two or more points (body frame).
    Polyline(Vec<[f64; 2]>),
}

/// Where two shapes overlap: the penetration, the normal from b into a, and the contact point.
struct Touch<S> {
    delta: S,
    n: [S; 2],
    p: [S; 2],
}

/// The normal force and the friction of a contact at a state, for output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactState {
    /// Penetration `delta`, m (`0` when separated).
    pub penetration: f64,
    /// Normal force `F_n >= 0`, N.
    pub normal: f64,
    /// Friction `F_t` on body a along `t = R90 n`, N.
    pub friction: f64,
}

/// A contact between a circle on body a and a shape on body b.
#[derive(Debug, Clone)]
pub struct Contact {
    a: Local,
    centre: [f64; 2],
    radius: f64,
    b: Local,
    shape: Shape,
    stiffness: f64,
    exponent: f64,
    damping: f64,
    mu: f64,
    transition_velocity: f64,
    max_penetration: f64,
    /// The model-file fields of the circle and of body b's shape (`shape_i.circle`,
    /// `shape_j.polyline`, ...), which name its data.
    fields: [&'static str; 2],
    columns: Vec<usize>,
}

impl Contact {
    /// A contact between the circle `(centre, radius)` of the body whose `x` is `q[a]` and
    /// `shape` of the body whose `x` is `q[b]` (`None` for ground), with the normal law
    /// `(stiffness, exponent, damping)`, friction `(mu, transition_velocity)` and the penetration
    /// `max_penetration` above which a step into first contact is rejected.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        a: Option<usize>,
        centre: [f64; 2],
        radius: f64,
        b: Option<usize>,
        shape: Shape,
        (stiffness, exponent, damping): (f64, f64, f64),
        (mu, transition_velocity): (f64, f64),
        max_penetration: f64,
    ) -> Contact {
        let (columns, l) = layout(&[a, b], &mut []);
        let other = if matches!(shape, Shape::Circle(..)) { "shape_j.circle" } else { "shape_j.polyline" };
        Contact {
            a: l[0],
            centre,
            radius,
            b: l[1],
            shape,
            stiffness,
            exponent,
            damping,
            mu,
            transition_velocity,
            max_penetration,
            fields: ["shape_i.circle", other],
            columns,
        }
    }

    /// The same contact with the circle given at the model-file field `circle` and body b's
    /// shape at `other` (`shape_j.polyline`, ...), which name its data.
    pub(crate) fn with_fields(mut self, circle: &'static str, other: &'static str) -> Contact {
        self.fields = [circle, other];
        self
    }

    /// The smallest radius of the pair, m.
    pub fn smallest_radius(&self) -> f64 {
        match self.shape {
            Shape::Circle(_, r) => self.radius.min(r),
            Shape::Polyline(_) => self.radius,
        }
    }

    /// The circle's centre, global frame.
    fn centre<S: Scalar>(&self, x: &[S]) -> [S; 2] {
        self.centre_at(x, self.centre.map(S::constant))
    }

    /// The circle's centre `centre` (body a's frame) in the global frame.
    fn centre_at<S: Scalar>(&self, x: &[S], centre: [S; 2]) -> [S; 2] {
        let pa = self.a.pose(x);
        let s = rotate(pa[2], centre);
        [pa[0] + s[0], pa[1] + s[1]]
    }

    /// Its own numbers, as constants.
    fn own<S: Scalar>(&self) -> Numbers<S, impl Fn(usize) -> [S; 2] + '_> {
        let (circle, points): (_, &[[f64; 2]]) = match &self.shape {
            Shape::Circle(c, r) => (Some((c.map(S::constant), S::constant(*r))), &[]),
            Shape::Polyline(points) => (None, points),
        };
        Numbers {
            centre: self.centre.map(S::constant),
            radius: S::constant(self.radius),
            circle,
            vertex: move |k: usize| points[k].map(S::constant),
            stiffness: S::constant(self.stiffness),
            exponent_shift: None,
            damping: S::constant(self.damping),
            mu: S::constant(self.mu),
            transition_velocity: S::constant(self.transition_velocity),
            friction: self.mu > 0.0,
        }
    }

    /// How many vertices body b's polyline has (none for a circle).
    fn vertices(&self) -> usize {
        match &self.shape {
            Shape::Circle(..) => 0,
            Shape::Polyline(points) => points.len(),
        }
    }

    /// Where the shapes touch; `None` when they do not overlap (or the centres coincide, where
    /// the normal has no direction).
    fn touch<S: Scalar>(&self, x: &[S]) -> Option<Touch<S>> {
        self.touch_with(x, &self.own())
    }

    /// [`Contact::touch`] with the numbers `nums`.
    fn touch_with<S: Scalar>(&self, x: &[S], nums: &Numbers<S, impl Fn(usize) -> [S; 2]>) -> Option<Touch<S>> {
        let ca = self.centre_at(x, nums.centre);
        let pb = self.b.pose(x);
        let global = |s: [S; 2]| {
            let r = rotate(pb[2], s);
            [pb[0] + r[0], pb[1] + r[1]]
        };
        let (q, reach) = match nums.circle {
            Some((c, r)) => (global(c), nums.radius + r),
            None => {
                let mut best: Option<([S; 2], f64)> = None;
                let mut from = global((nums.vertex)(0));
                for k in 1..self.vertices() {
                    let to = global((nums.vertex)(k));
                    let e = [to[0] - from[0], to[1] - from[1]];
                    let u = ((ca[0] - from[0]) * e[0] + (ca[1] - from[1]) * e[1]) / (e[0] * e[0] + e[1] * e[1]);
                    let u = if u.value() < 0.0 {
                        S::constant(0.0)
                    } else if u.value() > 1.0 {
                        S::constant(1.0)
                    } else {
                        u
                    };
                    let near = [from[0] + u * e[0], from[1] + u * e[1]];
                    let dist = (ca[0].value() - near[0].value()).hypot(ca[1].value() - near[1].value());
                    if best.as_ref().is_none_or(|b| dist < b.1) {
                        best = Some((near, dist));
                    }
                    from = to;
                }
                (best.map(|b| b.0).unwrap_or(from), nums.radius)
            }
        };
        let d = [ca[0] - q[0], ca[1] - q[1]];
        let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let delta = reach - l;
        if delta.value() <= 0.0 || l.value() < 1e-300 {
            return None;
        }
        let n = [d[0] / l, d[1] / l];
        // P = c_a - n (r_a - delta / 2): the middle of the overlap, for either shape of b.
        let back = nums.radius - delta * S::constant(0.5);
        Some(Touch { delta, n, p: [ca[0] - n[0] * back, ca[1] - n[1] * back] })
    }

    /// `(F_n, F_t)` and the touch, from the velocities `v`.
    fn forces<S: Scalar>(&self, x: &[S], v: &[S]) -> Option<(S, S, Touch<S>)> {
        self.forces_with(x, v, &self.own())
    }

    /// [`Contact::forces`] with the numbers `nums`.
    fn forces_with<S: Scalar>(
        &self,
        x: &[S],
        v: &[S],
        nums: &Numbers<S, impl Fn(usize) -> [S; 2]>,
    ) -> Option<(S, S, Touch<S>)> {
        let touch = self.touch_with(x, nums)?;
        let (pa, pb, va, vb) = (self.a.pose(x), self.b.pose(x), self.a.pose(v), self.b.pose(v));
        let p = touch.p;
        // v(P) = rdot + omega R90 (P - r), for a minus for b.
        let w = [
            va[0] - va[2] * (p[1] - pa[1]) - vb[0] + vb[2] * (p[1] - pb[1]),
            va[1] + va[2] * (p[0] - pa[0]) - vb[1] - vb[2] * (p[0] - pb[0]),
        ];
        let n = touch.n;
        let rate = -(n[0] * w[0] + n[1] * w[1]);
        let mut power = touch.delta.powf(self.exponent);
        if let Some(shift) = nums.exponent_shift {
            // delta^e = delta^e0 exp((e - e0) ln delta), exact in every derivative part.
            power = power * (shift * touch.delta.ln()).exp();
        }
        let elastic = nums.stiffness * power;
        let normal = elastic * (S::constant(1.0) + nums.damping * rate);
        if normal.value() <= 0.0 {
            return None;
        }
        let slip = n[0] * w[1] - n[1] * w[0];
        let friction = if nums.friction {
            -(nums.mu * normal * (slip / nums.transition_velocity).tanh())
        } else {
            S::constant(0.0)
        };
        Some((normal, friction, touch))
    }

    /// Penetration, normal force and friction at `(x, v)` (local columns), for output.
    pub fn state(&self, x: &[f64], v: &[f64]) -> ContactState {
        let penetration = self.touch(x).map_or(0.0, |t| t.delta);
        let (normal, friction) = self.forces(x, v).map_or((0.0, 0.0), |(n, f, _)| (n, f));
        ContactState { penetration, normal, friction }
    }

    /// The gap between the shapes at `x` (local columns), m: negative when they overlap.
    fn gap(&self, x: &[f64]) -> f64 {
        let ca = self.centre(x);
        let pb = self.b.pose(x);
        let global = |s: [f64; 2]| {
            let r = rotate(pb[2], s);
            [pb[0] + r[0], pb[1] + r[1]]
        };
        match &self.shape {
            Shape::Circle(c, r) => {
                let cb = global(*c);
                (ca[0] - cb[0]).hypot(ca[1] - cb[1]) - self.radius - r
            }
            Shape::Polyline(points) => {
                let mut dist = f64::INFINITY;
                for w in points.windows(2) {
                    let (from, to) = (global(w[0]), global(w[1]));
                    let e = [to[0] - from[0], to[1] - from[1]];
                    let u = (((ca[0] - from[0]) * e[0] + (ca[1] - from[1]) * e[1]) / (e[0] * e[0] + e[1] * e[1]))
                        .clamp(0.0, 1.0);
                    dist = dist.min((ca[0] - from[0] - u * e[0]).hypot(ca[1] - from[1] - u * e[1]));
                }
                dist - self.radius
            }
        }
    }

    /// The circle's centre in body b's frame, relative to its reference.
    fn centre_in_b(&self, x: &[f64]) -> [f64; 2] {
        let ca = self.centre(x);
        let pb = self.b.pose(x);
        let (c, s) = (pb[2].cos(), pb[2].sin());
        let d = [ca[0] - pb[0], ca[1] - pb[1]];
        [c * d[0] + s * d[1], -s * d[0] + c * d[1]]
    }

    /// For a step from `x0` to `x1` (local columns) that begins separated: the fraction of the
    /// step to retry with when the step ends deeper than `max_penetration` (aiming, by linear
    /// interpolation of the gap, at half of it) or moves the circle relative to body b by more
    /// than the smallest radius (a step that could carry it through a thin shape unseen);
    /// `None` when the step may stand. Within `[0.05, 0.9]`.
    pub fn event(&self, x0: &[f64], x1: &[f64]) -> Option<f64> {
        let g0 = self.gap(x0);
        if g0 <= 0.0 {
            return None; // in contact already: the force acts and the error test sees it
        }
        let g1 = self.gap(x1);
        let (c0, c1) = (self.centre_in_b(x0), self.centre_in_b(x1));
        let moved = (c1[0] - c0[0]).hypot(c1[1] - c0[1]);
        let reach = self.smallest_radius();
        let mut fraction: Option<f64> = None;
        if -g1 > self.max_penetration {
            fraction = Some((g0 + 0.5 * self.max_penetration) / (g0 - g1));
        }
        if moved > reach {
            let f = 0.5 * reach / moved;
            fraction = Some(fraction.map_or(f, |g| g.min(f)));
        }
        fraction.map(|f| f.clamp(0.05, 0.9))
    }
}

impl ForceLaw for Contact {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], _t: f64, out: &mut [S]) {
        self.law(x, v, &self.own(), out);
    }
    fn potential<S: Scalar>(&self, x: &[S]) -> S {
        match self.touch(x) {
            Some(t) => S::constant(self.stiffness / (self.exponent + 1.0)) * t.delta.powf(self.exponent + 1.0),
            None => S::constant(0.0),
        }
    }
    fn contact(&self) -> Option<&Contact> {
        Some(self)
    }
    /// The circle's `centre` and `radius`, the other shape's (a circle's, or each point of a
    /// segment or polyline), `stiffness`, `exponent`, `damping`, `friction.mu` and
    /// `friction.transition_velocity` (a default, or friction not given, has no derivatives).
    fn data(&self) -> Vec<(&'static str, f64)> {
        let [circle, other] = self.fields;
        let named = |field: &str, v: f64| (interned(field), v);
        let mut data = vec![
            named(&format!("{circle}.centre[0]"), self.centre[0]),
            named(&format!("{circle}.centre[1]"), self.centre[1]),
            named(&format!("{circle}.radius"), self.radius),
        ];
        match &self.shape {
            Shape::Circle(c, r) => data.extend([
                named(&format!("{other}.centre[0]"), c[0]),
                named(&format!("{other}.centre[1]"), c[1]),
                named(&format!("{other}.radius"), *r),
            ]),
            Shape::Polyline(points) => {
                for (k, p) in points.iter().enumerate() {
                    data.extend([0, 1].map(|c| named(&format!("{other}[{k}][{c}]"), p[c])));
                }
            }
        }
        data.extend([
            ("stiffness", self.stiffness),
            ("exponent", self.exponent),
            ("damping", self.damping),
            ("friction.mu", self.mu),
            ("friction.transition_velocity", self.transition_velocity),
        ]);
        data
    }
    /// Along the data, friction is evaluated also at `mu = 0`: its derivative with respect to
    /// `mu` there is that of the side `mu > 0`, the only one.
    fn load_data<S: Scalar>(&self, x: &[S], v: &[S], _t: f64, data: &[S], _params: &[S], out: &mut [S]) -> bool {
        let mut d = Data::new(data);
        let (centre, radius) = (d.pair(), d.next());
        let circle = match self.shape {
            Shape::Circle(..) => Some((d.pair(), d.next())),
            Shape::Polyline(_) => None,
        };
        let vertices = d.take(2 * self.vertices());
        let nums = Numbers {
            centre,
            radius,
            circle,
            vertex: |k: usize| [vertices[2 * k], vertices[2 * k + 1]],
            stiffness: d.next(),
            exponent_shift: Some(d.next() - S::constant(self.exponent)),
            damping: d.next(),
            mu: d.next(),
            transition_velocity: d.next(),
            friction: true,
        };
        self.law(x, v, &nums, out);
        true
    }
}

impl Contact {
    /// `Q_e` at `(x, v)` with the numbers `nums`.
    fn law<S: Scalar>(&self, x: &[S], v: &[S], nums: &Numbers<S, impl Fn(usize) -> [S; 2]>, out: &mut [S]) {
        out.fill(S::constant(0.0));
        let Some((normal, friction, touch)) = self.forces_with(x, v, nums) else {
            return;
        };
        let (n, p) = (touch.n, touch.p);
        let f = [normal * n[0] - friction * n[1], normal * n[1] + friction * n[0]];
        let (pa, pb) = (self.a.pose(x), self.b.pose(x));
        self.a.add(out, [f[0], f[1], cross([p[0] - pa[0], p[1] - pa[1]], f)]);
        let g = [-f[0], -f[1]];
        self.b.add(out, [g[0], g[1], cross([p[0] - pb[0], p[1] - pb[1]], g)]);
    }
}

/// A contact's numbers over any [`Scalar`]: its own as constants ([`ForceLaw::load`]) or its
/// data ([`ForceLaw::load_data`]).
struct Numbers<S, V> {
    /// The circle's centre (body a's frame) and radius.
    centre: [S; 2],
    radius: S,
    /// Body b's circle, centre and radius; `None` for a polyline, whose vertices `vertex` gives.
    circle: Option<([S; 2], S)>,
    /// Body b's polyline's vertex `k` (its frame).
    vertex: V,
    stiffness: S,
    /// The exponent's departure from its own value, along the data (`None`: its own value).
    exponent_shift: Option<S>,
    damping: S,
    mu: S,
    transition_velocity: S,
    /// Whether the friction is evaluated.
    friction: bool,
}

/// `name` as a `&'static str`, for the data names a contact builds from its shapes' fields (a
/// polyline has as many vertices as the file gives): each distinct name is allocated once and
/// kept for the program's life, so their number is bounded by the fields and the longest
/// polyline ever compiled, not by the number of runs.
fn interned(name: &str) -> &'static str {
    static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    // A poisoned lock still holds a valid set: only a finished insertion is ever seen.
    let mut names = NAMES.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&known) = names.get(name) {
        return known;
    }
    let kept: &'static str = Box::leak(name.to_string().into_boxed_str());
    names.insert(kept);
    kept
}

/// The exponent of a contact's penetration when none is given: 1.5, Hertz's for two cylinders'
/// ends or spheres, the usual choice (Lankarani and Nikravesh 1990).
pub const DEFAULT_CONTACT_EXPONENT: f64 = 1.5;

/// A contact's `max_penetration` when none is given, as a fraction of the smallest radius of the
/// pair: 1e-3. A step into first contact then ends at most that deep, where the force is a small
/// fraction of its peak in any impact that deforms the shapes less than their size.
pub const DEFAULT_PENETRATION_FRACTION: f64 = 1e-3;

/// Unilateral contact between shapes fixed to two bodies (one may be ground); one of the shapes is
/// a circle. The normal force is `k delta^n (1 + c ddelta/dt)`, never negative, `delta` the
/// penetration; the friction `mu tanh(v_t / v_s)` times it opposes the slip `v_t`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// First body (or ground).
    pub body_i: String,
    /// The shape fixed to the first body, in its frame.
    pub shape_i: ShapeSpec,
    /// Second body (or ground).
    pub body_j: String,
    /// The shape fixed to the second body, in its frame.
    pub shape_j: ShapeSpec,
    /// Contact stiffness `k`, N/m^n, `> 0`.
    pub stiffness: f64,
    /// Exponent `n` of the penetration, `>= 1`. Default 1.5 (Hertz).
    #[serde(default)]
    pub exponent: Option<f64>,
    /// Hunt-Crossley hysteresis damping factor `c`, s/m, `>= 0`. Default 0 (elastic).
    #[serde(default)]
    pub damping: f64,
    /// Coulomb friction at the contact point. Default: none.
    #[serde(default)]
    pub friction: Option<ContactFriction>,
    /// Penetration at which a step that begins separated and ends in contact is rejected and
    /// retried shorter, m, `> 0`. Default: 1e-3 of the smallest radius of the pair.
    #[serde(default)]
    pub max_penetration: Option<f64>,
}

/// A shape fixed to a body, in the body's frame (points relative to its reference): exactly one
/// of `circle`, `segment`, `polyline`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// A circle (a disc's rim).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub circle: Option<CircleShape>,
    /// A segment between two points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segment: Option<[[f64; 2]; 2]>,
    /// A chain of segments through two or more points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polyline: Option<Vec<[f64; 2]>>,
}

/// A circle fixed to a body.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CircleShape {
    /// Centre, body frame, m. Default: the body's reference `[0, 0]`.
    #[serde(default)]
    pub centre: [f64; 2],
    /// Radius, m, `> 0`.
    pub radius: f64,
}

/// Coulomb friction at a contact: `mu tanh(v_t / v_s)` times the normal force, opposing the
/// slip velocity `v_t`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactFriction {
    /// Coefficient of friction, `>= 0`.
    pub mu: f64,
    /// Slip velocity at which the coefficient reaches `tanh(1) = 76%` of `mu`, m/s, `> 0`;
    /// default 0.001.
    #[serde(default)]
    pub transition_velocity: Option<f64>,
}

/// A contact at `path` compiled in `cx`: its bodies, shapes (one a circle), normal law, friction and event depth.
pub(crate) fn compile(spec: &ContactSpec, cx: &mut impl ForceContext, path: &str) -> Option<Box<dyn Force>> {
    let bi = cx.body(&format!("{path}.body_i"), &spec.body_i);
    let bj = cx.body(&format!("{path}.body_j"), &spec.body_j);
    if spec.body_i == spec.body_j {
        let message = format!("a contact needs two different bodies, found '{}' twice", spec.body_i);
        cx.problem(format!("{path}.body_j"), message);
    }
    let si = shape(cx, &format!("{path}.shape_i"), &spec.shape_i);
    let sj = shape(cx, &format!("{path}.shape_j"), &spec.shape_j);
    let k = cx.positive(&format!("{path}.stiffness"), spec.stiffness);
    let e = match spec.exponent {
        Some(e) => cx.finite(&format!("{path}.exponent"), e).and_then(|e| {
            if e < 1.0 {
                cx.problem(
                    format!("{path}.exponent"),
                    format!(
                        "expected a number >= 1 (the force's derivative is infinite at first touch below 1), found {e}"
                    ),
                );
                return None;
            }
            Some(e)
        }),
        None => Some(DEFAULT_CONTACT_EXPONENT),
    };
    let c = cx.non_negative(&format!("{path}.damping"), spec.damping);
    let friction = match &spec.friction {
        Some(ContactFriction { mu, transition_velocity }) => {
            let mu = cx.non_negative(&format!("{path}.friction.mu"), *mu);
            let v_s = match transition_velocity {
                Some(v) => cx.positive(&format!("{path}.friction.transition_velocity"), *v),
                None => Some(DEFAULT_TRANSITION_VELOCITY),
            };
            mu.zip(v_s)
        }
        None => Some((0.0, DEFAULT_TRANSITION_VELOCITY)),
    };
    let depth = spec.max_penetration.map(|d| cx.positive(&format!("{path}.max_penetration"), d));
    let (bi, bj, si, sj, k, e, c, friction) = (bi?, bj?, si?, sj?, k?, e?, c?, friction?);
    if bi == BodyIx::GROUND && bj == BodyIx::GROUND {
        cx.problem(format!("{path}.body_j"), "both shapes are on ground: name a moving body");
        return None;
    }
    let ((a, (centre, radius)), (b, other), fields) = match (si, sj) {
        (Shape::Circle(centre, radius), other) => {
            ((bi, (centre, radius)), (bj, other), ["shape_i.circle", shape_field("shape_j", &spec.shape_j)])
        }
        (other, Shape::Circle(centre, radius)) => {
            ((bj, (centre, radius)), (bi, other), ["shape_j.circle", shape_field("shape_i", &spec.shape_i)])
        }
        _ => {
            cx.problem(
                format!("{path}.shape_j"),
                "a contact between two segments or polylines is not supported; expected a circle on one of the bodies",
            );
            return None;
        }
    };
    let smallest = match other {
        Shape::Circle(_, r) => radius.min(r),
        Shape::Polyline(_) => radius,
    };
    let depth = match depth {
        Some(d) => d?,
        None => DEFAULT_PENETRATION_FRACTION * smallest,
    };
    let contact = Contact::new(a.0, centre, radius, b.0, other, (k, e, c), friction, depth);
    Some(Box::new(contact.with_fields(fields[0], fields[1])))
}

/// The model-file field of the shape `spec` at `side` (`shape_i`, `shape_j`): `<side>.circle`,
/// `<side>.segment` or `<side>.polyline`.
fn shape_field(side: &'static str, spec: &ShapeSpec) -> &'static str {
    let kind = if spec.circle.is_some() {
        "circle"
    } else if spec.segment.is_some() {
        "segment"
    } else {
        "polyline"
    };
    interned(&format!("{side}.{kind}"))
}

/// A contact shape, in its body's frame.
fn shape(cx: &mut impl Context, path: &str, spec: &ShapeSpec) -> Option<Shape> {
    match (&spec.circle, &spec.segment, &spec.polyline) {
        (Some(CircleShape { centre, radius }), None, None) => {
            let c = cx.vec2(&format!("{path}.circle.centre"), *centre);
            let r = cx.positive(&format!("{path}.circle.radius"), *radius);
            Some(Shape::Circle(c?, r?))
        }
        (None, Some(points), None) => polyline(cx, &format!("{path}.segment"), points),
        (None, None, Some(points)) => polyline(cx, &format!("{path}.polyline"), points),
        _ => {
            cx.problem(path, "expected exactly one of circle, segment, polyline");
            None
        }
    }
}

/// A chain of two or more points, each segment of positive length.
fn polyline(cx: &mut impl Context, path: &str, points: &[[f64; 2]]) -> Option<Shape> {
    if points.len() < 2 {
        cx.problem(path, format!("expected two or more points, found {}", points.len()));
        return None;
    }
    let mut ok = true;
    for (k, p) in points.iter().enumerate() {
        ok &= cx.vec2(&format!("{path}[{k}]"), *p).is_some();
    }
    if !ok {
        return None;
    }
    for (k, w) in points.windows(2).enumerate() {
        if (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) < 1e-12 {
            cx.problem(
                format!("{path}[{}]", k + 1),
                format!("the point repeats point {k}: a segment needs two distinct ends"),
            );
            ok = false;
        }
    }
    ok.then(|| Shape::Polyline(points.to_vec()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::testing::{assert_data_fields, check_conservative, check_data, check_derivatives};
    use crate::forces::Force;

    fn disc_on_floor(friction: (f64, f64)) -> Contact {
        let floor = Shape::Polyline(vec![[-5.0, 0.0], [5.0, 0.0]]);
        Contact::new(Some(0), [0.0, 0.0], 0.5, None, floor, (1e4, 1.5, 0.2), friction, 1e-4)
    }

    /// Hand-derived: a disc of radius 0.5 at height 0.49 on a floor: `delta = 0.01`,
    /// `F_n = 1e4 * 0.01^1.5 = 10 N`; sinking at 1 m/s with `c = 0.2` multiplies it by 1.2; sliding
    /// at +2 m/s with `mu = 0.3`, `v_s = 1`: friction `-0.3 * 12 * tanh(2)` along x, at the contact
    /// point 0.495 below the centre.
    #[test]
    fn hand_derived() {
        let c = disc_on_floor((0.3, 1.0));
        let mut out = [0.0; 3];
        ForceLaw::load(&c, &[0.0, 0.49, 0.0], &[2.0, -1.0, 0.0], 0.0, &mut out);
        let fn_ = 1e4 * 0.01f64.powf(1.5) * 1.2;
        let ft = -0.3 * fn_ * 2.0f64.tanh();
        // The contact point is 0.495 below the centre: the moment of (ft, fn) about the centre
        // is (-0.495 along y) x (ft, fn) = 0.495 ft.
        let want = [ft, fn_, 0.495 * ft];
        for k in 0..3 {
            assert!((out[k] - want[k]).abs() < 1e-12, "{out:?} vs {want:?}");
        }
        let s = c.state(&[0.0, 0.49, 0.0], &[2.0, -1.0, 0.0]);
        assert!((s.penetration - 0.01).abs() < 1e-15 && (s.normal - fn_).abs() < 1e-12);
        // Parting fast enough that 1 + c ddelta/dt < 0: no pull.
        ForceLaw::load(&c, &[0.0, 0.49, 0.0], &[0.0, 6.0, 0.0], 0.0, &mut out);
        assert_eq!(out, [0.0; 3]);
        // Separated.
        ForceLaw::load(&c, &[0.0, 0.51, 0.0], &[0.0, -1.0, 0.0], 0.0, &mut out);
        assert_eq!(out, [0.0; 3]);
    }

    /// Shapes large enough that the random states of the harness overlap (asserted), so the
    /// derivatives checked are those of a contact that acts.
    #[test]
    fn derivatives_match_finite_differences() {
        let law = (50.0, 1.5, 0.3);
        let circles =
            Contact::new(Some(0), [0.2, 0.1], 3.0, Some(3), Shape::Circle([-0.3, 0.4], 2.5), law, (0.4, 0.7), 1e-3);
        let chain = Shape::Polyline(vec![[-3.0, -0.5], [0.0, 0.5], [3.0, 0.0]]);
        let poly = Contact::new(Some(3), [0.1, -0.2], 5.0, Some(0), chain.clone(), law, (0.4, 0.7), 1e-3);
        let grounded = Contact::new(Some(0), [0.1, -0.2], 5.0, None, chain, law, (0.4, 0.7), 1e-3);
        for (c, seed) in [(&circles, 41), (&poly, 42), (&grounded, 43)] {
            let x = [0.3, -0.2, 0.4, -0.5, 0.6, 1.1];
            assert!(c.state(&x[..c.columns.len()], &[0.0; 6][..c.columns.len()]).normal > 0.0);
            check_derivatives(c as &dyn Force, 6, seed);
        }
    }

    /// The load over the data (design sensitivities): each pair of shapes of
    /// `derivatives_match_finite_differences`, and one without friction (its derivative with
    /// respect to `mu` is taken all the same).
    #[test]
    fn load_over_data() {
        let law = (50.0, 1.5, 0.3);
        let circles =
            Contact::new(Some(0), [0.2, 0.1], 3.0, Some(3), Shape::Circle([-0.3, 0.4], 2.5), law, (0.4, 0.7), 1e-3);
        let chain = Shape::Polyline(vec![[-3.0, -0.5], [0.0, 0.5], [3.0, 0.0]]);
        let poly = Contact::new(Some(3), [0.1, -0.2], 5.0, Some(0), chain.clone(), law, (0.4, 0.7), 1e-3);
        let grounded = Contact::new(Some(0), [0.1, -0.2], 5.0, None, chain, law, (0.0, 0.7), 1e-3)
            .with_fields("shape_j.circle", "shape_i.segment");
        let names = |c: &Contact| ForceLaw::data(c).iter().map(|d| d.0).collect::<Vec<_>>();
        let tail = ["stiffness", "exponent", "damping", "friction.mu", "friction.transition_velocity"];
        let circle = ["shape_i.circle.centre[0]", "shape_i.circle.centre[1]", "shape_i.circle.radius"];
        let other = ["shape_j.circle.centre[0]", "shape_j.circle.centre[1]", "shape_j.circle.radius"];
        assert_eq!(names(&circles), [&circle[..], &other[..], &tail[..]].concat());
        assert_eq!(
            names(&grounded)[3..9],
            [
                "shape_i.segment[0][0]",
                "shape_i.segment[0][1]",
                "shape_i.segment[1][0]",
                "shape_i.segment[1][1]",
                "shape_i.segment[2][0]",
                "shape_i.segment[2][1]"
            ]
        );
        for (c, seed) in [(&circles, 44), (&poly, 45), (&grounded, 46)] {
            check_data(c, &[], seed);
            assert_data_fields::<ContactSpec>(c);
        }
    }

    /// Without damping or friction the load is minus the gradient of `k delta^(e+1) / (e+1)`.
    #[test]
    fn elastic_contact_is_conservative() {
        let circles = Contact::new(
            Some(0),
            [0.2, 0.1],
            2.5,
            Some(3),
            Shape::Circle([-0.3, 0.4], 2.0),
            (50.0, 1.5, 0.0),
            (0.0, 1.0),
            1e-3,
        );
        check_conservative(&circles, 51);
        let chain = Shape::Polyline(vec![[-3.0, -0.5], [0.0, 0.5], [3.0, 0.0]]);
        let poly = Contact::new(Some(3), [0.1, -0.2], 3.0, Some(0), chain, (50.0, 1.0, 0.0), (0.0, 1.0), 1e-3);
        check_conservative(&poly, 52);
    }

    /// A step from 1 mm above the floor to 3 mm into it (allowed 0.1 mm) is cut to
    /// `(1 + 0.05) / 4` of itself; one ending 0.05 mm in stands; one carrying the disc across more
    /// than its radius is cut to half the radius over the motion.
    #[test]
    fn events() {
        let c = disc_on_floor((0.0, 1.0));
        let f = c.event(&[0.0, 0.501, 0.0], &[0.0, 0.497, 0.0]).unwrap();
        assert!((f - 1.05e-3 / 4e-3).abs() < 1e-9, "{f}");
        assert_eq!(c.event(&[0.0, 0.501, 0.0], &[0.0, 0.49995, 0.0]), None);
        assert_eq!(c.event(&[0.0, 0.49, 0.0], &[0.0, 0.45, 0.0]), None);
        let f = c.event(&[0.0, 2.0, 0.0], &[2.0, 2.0, 0.0]).unwrap();
        assert!((f - 0.125).abs() < 1e-12, "{f}");
    }
}
