//! Named points where the drawing puts them at the initial position: each body's pose (its
//! `position`, by coordinates or by the name of one of its `points_global`, and its `angle`), and
//! every named point of ground and of the bodies in its owner's frame: `points` as given,
//! `points_global` turned into the body frame, and points placed from others (`body.B`, where
//! that point is; `{from: [B, C], distances: [d, e], side: left}`, by lengths) computed from the
//! points they name, in whatever order they need (docs/model-format.md, "Points placed by
//! lengths").
//!
//! A point is resolved to where it is in the global frame at the initial position, depth first
//! and once: a point in a body frame needs its body's pose, a position by name the point it
//! names, a point placed from others those points. Meeting again a point (or a pose) still being
//! resolved is a cycle, reported once.
//!
//! For a file with parameters, each pose and point also gets its derivatives with respect to
//! them, differentiated by hand alongside (a point in a body frame moves with its body's pose; a
//! point placed by lengths by the derivative of its two distance equations).

use super::compile::{it_has, unknown_body};
use super::spec::{ByLengths, ModelSpec, PointRef, PointSpec, Side};
use crate::constraints::Frame;
use crate::element::finite;
use crate::error::Problem;
use indexmap::IndexMap;
use std::collections::HashMap;

/// How much a flat triangle's two distances may fall short of `|BC|` (or their difference exceed
/// it), relative to `|BC|`, and still be taken as the flat triangle, the point on the line BC:
/// `|BC|` is computed from coordinates (often themselves results of expressions) with a rounding
/// error of a few 1e-16 relative, and lengths written to close exactly (`d + e = |BC|`) must not
/// be refused for it. 1e-12 is thousands of such roundings and far below any drawing's precision.
const FLAT: f64 = 1e-12;

/// Every body's initial pose and every named point, each in its owner's frame.
#[derive(Debug, Default)]
pub(super) struct Drawn {
    /// Each moving body's initial `[x, y, phi]`, by name; `[0, 0, 0]` stands in for one that
    /// could not be read (its problem is reported).
    pub poses: IndexMap<String, [f64; 3]>,
    /// Each owner's named points in its frame (ground's global), by owner (`ground` and the
    /// bodies), `points` then `points_global` in file order; `[0, 0]` stands in for a point that
    /// could not be placed (its problem is reported), so that what names it is not refused again.
    pub points: IndexMap<String, IndexMap<String, [f64; 2]>>,
    /// What was computed rather than given in its frame ([`super::Model::placed`]): each point of
    /// a body's `points_global` and each placed from others (`bodies.<body>.points.<point>`, body
    /// frame), and each of ground's placed from others (`ground.points.<point>`).
    pub placed: IndexMap<String, [f64; 2]>,
    /// The derivatives of each point of [`Drawn::points`] with respect to the parameters, by
    /// owner and name, in its owner's frame; empty for a file without parameters.
    pub gradients: IndexMap<String, IndexMap<String, Grad2>>,
    /// The derivatives of each body's initial `[x, y, phi]`, by name; empty without parameters.
    pub pose_gradients: IndexMap<String, [Vec<f64>; 3]>,
}

/// The derivatives of a pair of numbers (a point, a direction) with respect to each parameter.
pub(super) type Grad2 = [Vec<f64>; 2];

/// The derivatives `(d x, d y)` along each of `count` parameters, `along(k)` the `k`-th.
fn each(count: usize, along: impl Fn(usize) -> [f64; 2]) -> Grad2 {
    let (x, y) = (0..count).map(along).map(|[x, y]| (x, y)).unzip();
    [x, y]
}

/// The derivatives of `A^T w` (a global vector `w` seen in the frame `f`) from those of `w`
/// (`dw`) and of the frame's angle (`dphi`): `A^T (dw - dphi R90 w)`, since `d(A^T)/dphi =
/// -A^T R90`.
pub(super) fn unrotate_gradient(f: &Frame, dphi: &[f64], w: [f64; 2], dw: &Grad2) -> Grad2 {
    each(dphi.len(), |k| f.unrotate([dw[0][k] + dphi[k] * w[1], dw[1][k] - dphi[k] * w[0]]))
}

/// The derivatives of `A^T (g - r)` (a global point `g` in the frame `f`, whose pose has the
/// derivatives `df`) from those of `g` (`dg`).
pub(super) fn local_gradient(f: &Frame, df: &[Vec<f64>; 3], g: [f64; 2], dg: &Grad2) -> Grad2 {
    let dw = each(df[2].len(), |k| [dg[0][k] - df[0][k], dg[1][k] - df[1][k]]);
    unrotate_gradient(f, &df[2], [g[0] - f.x, g[1] - f.y], &dw)
}

/// The derivatives of `r + A s` (a point `s` of the frame `f`, whose pose has the derivatives
/// `df`) from those of `s` (`ds`): `dr + A ds + dphi R90 A s`.
fn global_gradient(f: &Frame, df: &[Vec<f64>; 3], s: [f64; 2], ds: &Grad2) -> Grad2 {
    let a = f.rotate(s);
    each(df[2].len(), |k| {
        let d = f.rotate([ds[0][k], ds[1][k]]);
        [df[0][k] + d[0] - df[2][k] * a[1], df[1][k] + d[1] + df[2][k] * a[0]]
    })
}

/// The derivatives of the corner `p` of [`triangle`] from those of `b`, `c` and the distances
/// `d` and `e`: `|p - b| = d` and `|p - c| = e` differentiated, `(p - b) . (dp - db) = d dd`
/// and `(p - c) . (dp - dc) = e de`, solved for `dp` (not finite for a flat triangle, whose
/// corner moves infinitely fast).
fn triangle_gradient(
    p: [f64; 2],
    [b, c]: [[f64; 2]; 2],
    [d, e]: [f64; 2],
    [db, dc]: [&Grad2; 2],
    [dd, de]: [&[f64]; 2],
) -> Grad2 {
    let (m, n) = ([p[0] - b[0], p[1] - b[1]], [p[0] - c[0], p[1] - c[1]]);
    let det = m[0] * n[1] - m[1] * n[0];
    each(dd.len(), |k| {
        let u = d * dd[k] + m[0] * db[0][k] + m[1] * db[1][k];
        let v = e * de[k] + n[0] * dc[0][k] + n[1] * dc[1][k];
        [(u * n[1] - m[1] * v) / det, (m[0] * v - u * n[0]) / det]
    })
}

/// Resolve the poses and named points of `spec`; `broken` names the entries that could not be
/// read (`bodies.<name>`), whose points are taken as unknown without a problem.
pub(super) fn drawn(spec: &ModelSpec, broken: &[String], problems: &mut Vec<Problem>) -> Drawn {
    let mut r = Resolver {
        spec,
        broken,
        problems,
        points: HashMap::new(),
        poses: HashMap::new(),
        trail: Vec::new(),
        point_gradients: HashMap::new(),
        pose_gradients: HashMap::new(),
    };
    let differentiate = spec.gradients.count() > 0;
    let mut out = Drawn::default();
    let mut ground = IndexMap::new();
    for (p, v) in spec.ground.iter().flat_map(|g| &g.points) {
        let at = r.global("ground", p);
        if let (PointSpec::At(_) | PointSpec::Lengths(_), Some(at)) = (v, at) {
            out.placed.insert(format!("ground.points.{p}"), at);
        }
        ground.insert(p.clone(), at.unwrap_or_default());
        if differentiate {
            let g = r.gradient("ground", p);
            out.gradients.entry("ground".to_string()).or_default().insert(p.clone(), g);
        }
    }
    out.points.insert("ground".to_string(), ground);
    // A body called `ground` is refused by its name; its points would shadow ground's.
    for (name, b) in spec.bodies.iter().filter(|(name, _)| *name != "ground") {
        let frame = r.pose(name);
        out.poses.insert(name.clone(), frame.map_or([0.0; 3], |f| [f.x, f.y, f.phi]));
        let pose_gradient = r.pose_gradients.get(name.as_str()).cloned();
        if let (true, Some(g)) = (differentiate, &pose_gradient) {
            out.pose_gradients.insert(name.clone(), g.clone());
        }
        let mut points = IndexMap::new();
        let all = b.points.iter().map(|p| (p, false)).chain(b.points_global.iter().map(|p| (p, true)));
        for ((p, v), global) in all {
            if global && b.points.contains_key(p) {
                r.problems.push(Problem::new(
                    format!("bodies.{name}.points_global.{p}"),
                    format!("'{p}' is also in points: name each point once"),
                ));
                continue;
            }
            let at = r.global(name, p);
            let local = match v {
                PointSpec::Coords(v) if !global => Some(*v),
                _ => {
                    let local = frame.zip(at).map(|(f, at)| f.local(at));
                    if let Some(local) = local {
                        out.placed.insert(format!("bodies.{name}.points.{p}"), local);
                    }
                    local
                }
            };
            points.insert(p.clone(), local.unwrap_or_default());
            if differentiate {
                let g = match (v, global, frame, at, &pose_gradient) {
                    (PointSpec::Coords(_), false, ..) => r.written(&format!("bodies.{name}.points.{p}")),
                    (_, _, Some(f), Some(at), Some(df)) => local_gradient(&f, df, at, &r.gradient(name, p)),
                    // Not placed: its problem is reported, and the model is not built.
                    _ => r.gradient(name, p),
                };
                out.gradients.entry(name.clone()).or_default().insert(p.clone(), g);
            }
        }
        out.points.insert(name.clone(), points);
    }
    out
}

/// Why no triangle has the given lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Impossible {
    /// A distance is zero or negative.
    NotPositive,
    /// B and C are the same point.
    Coincident,
    /// `d + e < |BC|`: the two links cannot meet.
    TooShort,
    /// `|d - e| > |BC|`: one link is too long for the other to reach.
    TooLong,
    /// The point is past the largest double.
    OutOfRange,
}

/// The point at distance `d` from `b` and `e` from `c`, on `side` of the directed line from `b` to
/// `c` (left: counter-clockwise of it, `(c - b) x (p - b) > 0`): `b + a u + h n`, with `u` the unit
/// vector from `b` to `c`, `n` it turned by +90 degrees (by -90 degrees on the right), `a` =
/// `(|bc|^2 + d^2 - e^2) / (2 |bc|)` the distance from `b` of the foot of the altitude along `u`
/// and `h = sqrt(d^2 - a^2)` the altitude. Written with `d^2 - e^2 = (d - e)(d + e)` and `d^2 -
/// a^2 = (d - a)(d + a)`, so that a triangle of lengths of any size loses no digits to squaring.
pub(crate) fn triangle(b: [f64; 2], c: [f64; 2], [d, e]: [f64; 2], side: Side) -> Result<[f64; 2], Impossible> {
    let bc = (c[0] - b[0]).hypot(c[1] - b[1]);
    // Also refuses a NaN distance.
    if !(d > 0.0 && e > 0.0) {
        return Err(Impossible::NotPositive);
    }
    if bc == 0.0 {
        return Err(Impossible::Coincident);
    }
    if d + e < bc * (1.0 - FLAT) {
        return Err(Impossible::TooShort);
    }
    if (d - e).abs() > bc * (1.0 + FLAT) {
        return Err(Impossible::TooLong);
    }
    let u = [(c[0] - b[0]) / bc, (c[1] - b[1]) / bc];
    let a = 0.5 * (bc + (d - e) * (d + e) / bc);
    // Zero for a flat triangle, which `FLAT` lets through slightly past flat.
    let h = ((d - a) * (d + a)).max(0.0).sqrt();
    let h = match side {
        Side::Left => h,
        Side::Right => -h,
    };
    let p = [b[0] + a * u[0] - h * u[1], b[1] + a * u[1] + h * u[0]];
    if p.iter().all(|x| x.is_finite()) {
        Ok(p)
    } else {
        Err(Impossible::OutOfRange)
    }
}

/// How a named point is given.
#[derive(Clone, Copy)]
enum Given<'s> {
    /// Coordinates in its body's frame.
    Local([f64; 2]),
    /// Coordinates in the global frame (ground's points, `points_global`).
    Global([f64; 2]),
    /// Where another point is.
    At(&'s str),
    /// By lengths.
    Lengths(&'s ByLengths),
}

/// What is resolved: a point of an owner (`ground` or a body), or a body's pose.
#[derive(Clone, Copy, PartialEq)]
enum Node<'s> {
    Point(&'s str, &'s str),
    Pose(&'s str),
}

/// A node being resolved, or its value (`None`: it could not be, and its problem is reported).
#[derive(Clone, Copy)]
enum Mark<T> {
    Open,
    Done(Option<T>),
}

struct Resolver<'s, 'p> {
    spec: &'s ModelSpec,
    broken: &'s [String],
    problems: &'p mut Vec<Problem>,
    /// Each point's global position at the start, by owner and name.
    points: HashMap<(&'s str, &'s str), Mark<[f64; 2]>>,
    /// Each body's frame at the start, by name.
    poses: HashMap<&'s str, Mark<Frame>>,
    /// The nodes being resolved, the innermost last: from where a node is met again, a cycle.
    trail: Vec<Node<'s>>,
    /// The derivatives of each point's global position resolved, by owner and name (none
    /// without parameters).
    point_gradients: HashMap<(&'s str, &'s str), Grad2>,
    /// The derivatives of each body's `[x, y, phi]` at the start, by name.
    pose_gradients: HashMap<&'s str, [Vec<f64>; 3]>,
}

impl<'s> Resolver<'s, '_> {
    /// How point `name` of `owner` is given, and its entry's path; `None` when there is none.
    fn given(&self, owner: &str, name: &str) -> Option<(Given<'s>, String)> {
        let spec = self.spec;
        let (v, global, path) = if owner == "ground" {
            (spec.ground.as_ref()?.points.get(name)?, true, format!("ground.points.{name}"))
        } else {
            let b = spec.bodies.get(owner)?;
            match (b.points.get(name), b.points_global.get(name)) {
                (Some(v), _) => (v, false, format!("bodies.{owner}.points.{name}")),
                (None, Some(v)) => (v, true, format!("bodies.{owner}.points_global.{name}")),
                (None, None) => return None,
            }
        };
        let given = match v {
            PointSpec::Coords(v) if global => Given::Global(*v),
            PointSpec::Coords(v) => Given::Local(*v),
            PointSpec::At(text) => Given::At(text),
            PointSpec::Lengths(by) => Given::Lengths(by),
        };
        Some((given, path))
    }

    /// Where point `name` of `owner` (which has it) is at the start, global frame.
    fn global(&mut self, owner: &'s str, name: &'s str) -> Option<[f64; 2]> {
        match self.points.get(&(owner, name)) {
            Some(Mark::Done(v)) => return *v,
            Some(Mark::Open) => return self.cycle(Node::Point(owner, name)),
            None => {}
        }
        self.points.insert((owner, name), Mark::Open);
        self.trail.push(Node::Point(owner, name));
        let v = match self.given(owner, name) {
            Some((Given::Global(v), path)) => self.coords(&path, v),
            Some((Given::Local(v), path)) => {
                let v = self.coords(&path, v);
                self.pose(owner).zip(v).map(|(f, v)| f.point(v))
            }
            Some((Given::At(text), path)) => self.reference(owner, text, &path).and_then(|(o, p)| self.global(o, p)),
            Some((Given::Lengths(by), path)) => self.by_lengths(owner, &path, by),
            None => None,
        };
        self.trail.pop();
        self.points.insert((owner, name), Mark::Done(v));
        if let (Some(v), Some((given, path)), true) = (v, self.given(owner, name), self.spec.gradients.count() > 0) {
            let g = self.differentiate(owner, given, &path, v);
            self.point_gradients.insert((owner, name), g);
        }
        v
    }

    /// The derivatives of the coordinates `[x, y]` written at `path` (zero for numbers).
    fn written(&self, path: &str) -> Grad2 {
        [0, 1].map(|k| self.spec.gradients.field(&format!("{path}[{k}]")))
    }

    /// The derivatives of point `name` of `owner`'s global position; not a number for a point
    /// that could not be placed (whose problem is reported), never zero.
    fn gradient(&self, owner: &str, name: &str) -> Grad2 {
        self.point_gradients.get(&(owner, name)).cloned().unwrap_or_else(|| self.unknown())
    }

    /// The derivatives of what could not be placed: not a number.
    fn unknown(&self) -> Grad2 {
        [0, 1].map(|_| vec![f64::NAN; self.spec.gradients.count()])
    }

    /// The derivatives of the global position `v` of a point of `owner` `given` at `path`, from
    /// those of what it is placed from (resolved before it).
    fn differentiate(&mut self, owner: &'s str, given: Given<'s>, path: &str, v: [f64; 2]) -> Grad2 {
        match given {
            Given::Global(_) => self.written(path),
            Given::Local(s) => match (self.pose(owner), self.pose_gradients.get(owner)) {
                (Some(f), Some(df)) => global_gradient(&f, df, s, &self.written(path)),
                _ => self.unknown(),
            },
            Given::At(text) => match self.reference(owner, text, path) {
                Some((o, p)) => self.gradient(o, p),
                None => self.unknown(),
            },
            Given::Lengths(by) => {
                let mut ends = [([0.0; 2], self.unknown()), ([0.0; 2], self.unknown())];
                for (k, end) in ends.iter_mut().enumerate() {
                    if let Some((o, p)) = self.reference(owner, &by.from[k], &format!("{path}.from[{k}]")) {
                        *end = (self.global(o, p).unwrap_or_default(), self.gradient(o, p));
                    }
                }
                let [(b, db), (c, dc)] = ends;
                let [dd, de] = [0, 1].map(|k| self.spec.gradients.field(&format!("{path}.distances[{k}]")));
                triangle_gradient(v, [b, c], by.distances, [&db, &dc], [&dd, &de])
            }
        }
    }

    /// Body `body`'s frame at the start.
    fn pose(&mut self, body: &'s str) -> Option<Frame> {
        match self.poses.get(body) {
            Some(Mark::Done(v)) => return *v,
            Some(Mark::Open) => return self.cycle(Node::Pose(body)),
            None => {}
        }
        let b = self.spec.bodies.get(body)?;
        self.poses.insert(body, Mark::Open);
        self.trail.push(Node::Pose(body));
        let here = format!("bodies.{body}.position");
        let position = match &b.position {
            PointRef::Coords(v) => self.coords(&here, *v),
            // A value that is not finite is reported at the point itself.
            PointRef::Name(n) if b.points_global.contains_key(n) => self.global(body, n),
            PointRef::Name(n) => {
                let known: Vec<&str> = b.points_global.keys().map(String::as_str).collect();
                let message = format!(
                    "unknown point '{n}': a position by name is one of points_global ({}); or give [x, y]",
                    it_has(&known, "none")
                );
                self.problems.push(Problem::new(here, message));
                None
            }
        };
        let angle = finite(self.problems, &format!("bodies.{body}.angle"), b.angle);
        let v = position.zip(angle).map(|([x, y], phi)| Frame::at([x, y, phi]));
        self.trail.pop();
        self.poses.insert(body, Mark::Done(v));
        if v.is_some() && self.spec.gradients.count() > 0 {
            let [dx, dy] = match &b.position {
                PointRef::Coords(_) => self.written(&format!("bodies.{body}.position")),
                PointRef::Name(n) => self.gradient(body, n),
            };
            let dphi = self.spec.gradients.field(&format!("bodies.{body}.angle"));
            self.pose_gradients.insert(body, [dx, dy, dphi]);
        }
        v
    }

    /// Coordinates at `path`, each checked to be finite.
    fn coords(&mut self, path: &str, v: [f64; 2]) -> Option<[f64; 2]> {
        let x = finite(self.problems, &format!("{path}[0]"), v[0]);
        let y = finite(self.problems, &format!("{path}[1]"), v[1]);
        Some([x?, y?])
    }

    /// The point of `owner` at `path` placed by lengths `by`, global frame.
    fn by_lengths(&mut self, owner: &'s str, path: &str, by: &'s ByLengths) -> Option<[f64; 2]> {
        let mut ends = [None; 2];
        for (k, end) in ends.iter_mut().enumerate() {
            let at = format!("{path}.from[{k}]");
            *end = self.reference(owner, &by.from[k], &at).and_then(|(o, p)| self.global(o, p));
        }
        let distances = format!("{path}.distances");
        let d = finite(self.problems, &format!("{distances}[0]"), by.distances[0]);
        let e = finite(self.problems, &format!("{distances}[1]"), by.distances[1]);
        let ([Some(b), Some(c)], Some(d), Some(e)) = (ends, d, e) else { return None };
        let (nb, nc) = (&by.from[0], &by.from[1]);
        let bc = (c[0] - b[0]).hypot(c[1] - b[1]);
        let lengths = format!("d = {d} m (to {nb}), e = {e} m (to {nc}) and |{nb} {nc}| = {bc} m");
        let (field, message) = match triangle(b, c, [d, e], by.side) {
            Ok(p) => return Some(p),
            Err(Impossible::NotPositive) => (distances, format!("expected two distances > 0, found {lengths}")),
            Err(Impossible::Coincident) => (
                format!("{path}.from"),
                format!(
                    "{nb} and {nc} are the same point, [{}, {}], at the start: a point is placed by its distances to two distinct points",
                    b[0], b[1]
                ),
            ),
            Err(Impossible::TooShort) => (
                distances,
                format!("no triangle has the sides {lengths}: d + e = {} m is less than |{nb} {nc}|, so the two links cannot meet", d + e),
            ),
            Err(Impossible::TooLong) => (
                distances,
                format!(
                    "no triangle has the sides {lengths}: |d - e| = {} m is more than |{nb} {nc}|, so one link is too long for the other to reach",
                    (d - e).abs()
                ),
            ),
            Err(Impossible::OutOfRange) => {
                (distances, format!("the sides {lengths} place the point past the largest double, 1.8e308"))
            }
        };
        self.problems.push(Problem::new(field, message));
        None
    }

    /// The owner and name of the point `text` names, to place a point of `owner` (at `path`):
    /// `B`, a point of `owner`, or `body.B`; `None`, with a problem, when there is none.
    fn reference(&mut self, owner: &'s str, text: &'s str, path: &str) -> Option<(&'s str, &'s str)> {
        let (body, point) = text.split_once('.').unwrap_or((owner, text));
        if body != "ground" && !self.spec.bodies.contains_key(body) {
            if !self.broken.iter().any(|b| b.strip_prefix("bodies.") == Some(body)) {
                let broken = self.broken.iter().filter_map(|b| b.strip_prefix("bodies."));
                let known: Vec<&str> = self.spec.bodies.keys().map(String::as_str).chain(broken).collect();
                let message = format!(
                    "in '{text}': {}; write B for a point of the same body, body.B for another's",
                    unknown_body(body, &known)
                );
                self.problems.push(Problem::new(path, message));
            }
            return None;
        }
        if self.given(body, point).is_some() {
            return Some((body, point));
        }
        let known: Vec<&str> = if body == "ground" {
            self.spec.ground.iter().flat_map(|g| g.points.keys()).map(String::as_str).collect()
        } else {
            let b = &self.spec.bodies[body];
            b.points.keys().chain(b.points_global.keys()).map(String::as_str).collect()
        };
        let same = if body == owner && !text.contains('.') {
            " (B names a point of the same body; body.B another's)"
        } else {
            ""
        };
        let message = format!("unknown point '{point}' of body '{body}' ({}){same}", it_has(&known, "no named points"));
        self.problems.push(Problem::new(path, message));
        None
    }

    /// `node`, met again while it is being resolved: the cycle from its first meeting, reported at
    /// its first point placed from others, at the `from` of one placed by lengths (every cycle has
    /// one: a pose needs only a point of `points_global`, which needs nothing unless it is placed
    /// from others).
    fn cycle<T>(&mut self, node: Node<'s>) -> Option<T> {
        let start = self.trail.iter().position(|n| *n == node).unwrap_or(0);
        let members = &self.trail[start..];
        let label = |n: &Node| match n {
            Node::Point(owner, name) => format!("{owner}.{name}"),
            Node::Pose(body) => format!("{body}.position"),
        };
        let chain: Vec<String> = members.iter().chain([&node]).map(label).collect();
        let at = members.iter().find_map(|n| match n {
            Node::Point(owner, name) => match self.given(owner, name) {
                Some((Given::Lengths(_), path)) => Some(format!("{path}.from")),
                Some((Given::At(_), path)) => Some(path),
                _ => None,
            },
            Node::Pose(_) => None,
        });
        let message =
            format!("these points are placed from each other, {}: give one of them by coordinates", chain.join(" -> "));
        self.problems.push(Problem::new(at.unwrap_or_default(), message));
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same corner by the law of cosines, in angles: the angle at B between BC and BP is
    /// `beta = acos((d^2 + |BC|^2 - e^2) / (2 d |BC|))`, counter-clockwise from BC on the left,
    /// clockwise on the right, and `P = B + d (cos(theta +- beta), sin(theta +- beta))`, `theta`
    /// BC's direction.
    fn law_of_cosines(b: [f64; 2], c: [f64; 2], [d, e]: [f64; 2], side: Side) -> [f64; 2] {
        let bc = (c[0] - b[0]).hypot(c[1] - b[1]);
        let theta = (c[1] - b[1]).atan2(c[0] - b[0]);
        let beta = ((d * d + bc * bc - e * e) / (2.0 * d * bc)).acos();
        let angle = if side == Side::Left { theta + beta } else { theta - beta };
        [b[0] + d * angle.cos(), b[1] + d * angle.sin()]
    }

    /// Triangles of every shape and orientation (acute, right, obtuse, nearly flat, lengths
    /// from 1e-3 to 1e3 m), both sides: the placement equals the law of cosines to 1e-12 relative
    /// to the triangle's size (both are exact to a few roundings,
    /// ~2e-16 relative here; the angle form loses most near flat, where `acos` is steep: 4e-15 on
    /// the case 1e-4 from flat), the distances hold to 4e-15 relative (a few roundings), and the
    /// side is the one asked for.
    #[test]
    fn a_triangle_by_lengths_is_the_law_of_cosines_corner() {
        let shapes: [([f64; 2], [f64; 2], [f64; 2]); 7] = [
            ([0.0, 0.0], [0.3, 0.0], [0.2, 0.25]),
            ([0.1, -0.2], [-0.4, 0.35], [0.6, 0.2]),
            ([1.0, 1.0], [1.5, 1.2], [0.1, 0.6]),
            ([-2e-3, 1e-3], [1e-3, 3e-3], [2.5e-3, 1.5e-3]),
            ([300.0, -700.0], [-250.0, 400.0], [900.0, 1100.0]),
            ([0.0, 0.0], [0.0, 1.0], [0.6, 0.8]),
            ([0.0, 0.0], [1.0, 0.0], [0.5, 0.5 + 1e-4]),
        ];
        for (b, c, [d, e]) in shapes {
            let size = d.max(e).max((c[0] - b[0]).hypot(c[1] - b[1]));
            for side in [Side::Left, Side::Right] {
                let p = triangle(b, c, [d, e], side).unwrap();
                let q = law_of_cosines(b, c, [d, e], side);
                let worst = (p[0] - q[0]).abs().max((p[1] - q[1]).abs());
                assert!(worst < 1e-12 * size, "{b:?} {c:?} {d} {e} {side:?}: {p:?} vs {q:?}");
                let (to_b, to_c) = ((p[0] - b[0]).hypot(p[1] - b[1]), (p[0] - c[0]).hypot(p[1] - c[1]));
                assert!((to_b - d).abs() < 4e-15 * size && (to_c - e).abs() < 4e-15 * size, "{to_b} {to_c}");
                let cross = (c[0] - b[0]) * (p[1] - b[1]) - (c[1] - b[1]) * (p[0] - b[0]);
                assert_eq!(cross > 0.0, side == Side::Left, "{b:?} {c:?} {side:?}");
            }
        }
    }

    /// A flat triangle whose lengths close only to a rounding, `0.1 + 0.7 < 0.8` in doubles, is the
    /// point on the line (to 1e-15 m, a few roundings of 0.8 m); past `FLAT` it is refused.
    #[test]
    fn a_flat_triangle_is_on_the_line_and_an_impossible_one_is_refused() {
        let (short, bc) = (std::hint::black_box(0.1) + 0.7, 0.8);
        assert!(short < bc, "0.1 + 0.7 rounds below 0.8");
        for side in [Side::Left, Side::Right] {
            let p = triangle([0.0, 0.0], [0.8, 0.0], [0.1, 0.7], side).unwrap();
            assert!((p[0] - 0.1).abs() < 1e-15 && p[1].abs() < 1e-15, "{p:?}");
            let p = triangle([0.0, 0.0], [0.8, 0.0], [0.9, 0.1], side).unwrap();
            assert!((p[0] - 0.9).abs() < 1e-15 && p[1].abs() < 1e-15, "{p:?}");
        }
        let (b, c) = ([0.0, 0.0], [0.8, 0.0]);
        for (d, e, why) in [
            (0.1, 0.7 - 1e-9, Impossible::TooShort),
            (0.9 + 1e-9, 0.1, Impossible::TooLong),
            (0.1, 1.0, Impossible::TooLong),
            (0.0, 0.8, Impossible::NotPositive),
            (0.5, -0.5, Impossible::NotPositive),
            (f64::NAN, 0.5, Impossible::NotPositive),
            // d + e overflows, and (d - e)(d + e) is 0 inf.
            (1e308, 1e308, Impossible::OutOfRange),
        ] {
            assert_eq!(triangle(b, c, [d, e], Side::Left), Err(why), "{d} {e}");
        }
        assert_eq!(triangle(b, b, [0.5, 0.5], Side::Left), Err(Impossible::Coincident));
    }
}
