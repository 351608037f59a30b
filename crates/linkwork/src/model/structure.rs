//! The structure of a mechanism: its bodies split into the groups a designer solves one after
//! another (the input links, then Assur groups such as the RRR dyad, each placed by the groups
//! before it), and the assembly mode (branch) of each dyad.
//!
//! The decomposition is read from the constraint rows alone: a set of bodies not yet placed is a
//! group when the rows of the elements (joints and active drivers) that touch it and otherwise
//! only bodies already placed number at least its coordinates, `3 k`. Groups are taken smallest
//! first, so that the Jacobian of the driven mechanism, with its rows and columns in group order,
//! is block lower-triangular with one square block per group: the whole is singular exactly when
//! one group's own block is, and that group is the part of the mechanism that locks
//! (`analysis::branches`). Where the active drivers leave freedom (the mechanism alone, a dynamic
//! analysis), the body that the rows to placed bodies hold best is taken as an input link.
//!
//! A dyad is a group of two bodies joined by three pins: `E` to a placed body, `F` between the
//! two, `D` to a placed body. Given `E` and `D`, `F` lies on one of two sides of the directed line
//! `E -> D`: its two assembly modes.

use super::spec::Side;
use super::{Body, Element, Model};
use crate::constraints::{BodyIx, Frame, Shape};

/// Bodies above which the decomposition is not attempted: it searches the connected sets of up
/// to `MAX_GROUP` bodies next to the bodies placed, at each of up to `bodies` stages, each set
/// against every element; a free chain of 200 bodies takes about 6 ms (a run computes the
/// groups three times), and no designer reads the groups of a larger mechanism.
pub const MAX_BODIES: usize = 200;

/// Bodies of the largest group searched for: four covers the dyads (2), and the triads of the
/// Stephenson six-bars and the double-butterfly linkages (4 with their ternary link).
const MAX_GROUP: usize = 4;

/// `|sin|` of the angle at `E` between `E -> D` and `E -> F` below which a drawn dyad has no side:
/// its pins drawn on one line (0.06 degrees), as a rough sketch of a toggle position may be.
pub const DRAWN_MIN_SINE: f64 = 1e-3;

/// One structural group: bodies placed together by the elements that reach them.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// The bodies (indices into [`Model::bodies`]).
    pub bodies: Vec<usize>,
    /// The elements whose rows place them: joint `k` as `k`, driver `d` as `joints + d`.
    pub elements: Vec<usize>,
    /// The coordinates its rows leave free: 0 for a group the rows place, more for an input
    /// link taken where the drivers leave freedom.
    pub free: usize,
    /// Its dyad, when it is two bodies joined by three pins.
    pub dyad: Option<Dyad>,
}

/// A dyad of pins: bodies `bodies[0]` (holding `E`) and `bodies[1]` (holding `D`), joined at `F`.
#[derive(Debug, Clone, PartialEq)]
pub struct Dyad {
    /// Joint indices `[E, F, D]`.
    pub joints: [usize; 3],
    /// The two bodies, the one with `E` first.
    pub bodies: [usize; 2],
    /// Each joint's two ends: `(body, point in its frame)`.
    ends: [[(BodyIx, [f64; 2]); 2]; 3],
    /// Each body's own points at its two pins: `[E, F]` on the first, `[F, D]` on the second.
    links: [[[f64; 2]; 2]; 2],
}

/// The pins of `joint`: its two ends, when it is a pin joint.
fn pin(joint: &Element) -> Option<[(BodyIx, [f64; 2]); 2]> {
    let sketch = joint.constraint.sketch()?;
    (joint.kind == "revolute" && sketch.shape == Shape::Pin).then_some([(sketch.i, sketch.p), (sketch.j, sketch.q)])
}

/// Which of `ends` lies on `body`, and its point there.
fn on(ends: &[(BodyIx, [f64; 2]); 2], body: usize) -> Option<[f64; 2]> {
    ends.iter().find(|(b, _)| b.0 == Some(3 * body)).map(|&(_, s)| s)
}

impl Dyad {
    /// The dyad of pins `e`, `f`, `d` (joint indices of `model`): `f` joins two moving bodies,
    /// `e` one of them to another body, `d` the other. Otherwise what is wrong, in words.
    pub fn new(joints: &[Element], bodies: &[Body], [e, f, d]: [usize; 3]) -> Result<Dyad, String> {
        let name = |k: usize| &joints[k].name;
        let ends = |k: usize| pin(&joints[k]).ok_or_else(|| format!("joint '{}' is not a revolute joint", name(k)));
        let (ee, fe, de) = (ends(e)?, ends(f)?, ends(d)?);
        let [Some(a), Some(b)] = fe.map(|(b, _)| b.0.map(|k| k / 3)) else {
            return Err(format!(
                "joint '{}' joins a body to ground: a dyad's middle pin joins two moving bodies",
                name(f)
            ));
        };
        let holds = |ends: &[(BodyIx, [f64; 2]); 2], body: usize| on(ends, body).is_some();
        let (first, second) = match (holds(&ee, a), holds(&ee, b), holds(&de, a), holds(&de, b)) {
            (true, false, false, true) => (a, b),
            (false, true, true, false) => (b, a),
            _ => {
                let (ba, bb) = (&bodies[a].name, &bodies[b].name);
                return Err(format!(
                    "joints '{}' and '{}' must each pin one of the bodies '{ba}' and '{bb}' that '{}' joins, one each, to another body",
                    name(e),
                    name(d),
                    name(f)
                ));
            }
        };
        let point = |ends: &[(BodyIx, [f64; 2]); 2], body: usize| on(ends, body).unwrap_or_default();
        Ok(Dyad {
            joints: [e, f, d],
            bodies: [first, second],
            ends: [ee, fe, de],
            links: [[point(&ee, first), point(&fe, first)], [point(&fe, second), point(&de, second)]],
        })
    }

    /// Where joint `k` (0 `E`, 1 `F`, 2 `D`) is at `q`: the middle of its two ends (one point
    /// when assembled; the drawing's guess may hold them apart).
    fn at(&self, k: usize, q: &[f64]) -> [f64; 2] {
        let [a, b] = self.ends[k].map(|(body, s)| Frame::of_slice(body, q).point(s));
        [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
    }

    /// The sine of the angle at `E` from `E -> D` to `E -> F` at `q`: positive with `F` to the
    /// left of the line, negative to the right, 0 on it (or when two pins coincide).
    pub fn sine(&self, q: &[f64]) -> f64 {
        let [e, f, d] = [0, 1, 2].map(|k| self.at(k, q));
        let (ed, ef) = ([d[0] - e[0], d[1] - e[1]], [f[0] - e[0], f[1] - e[1]]);
        let size = ed[0].hypot(ed[1]) * ef[0].hypot(ef[1]);
        if size > 0.0 {
            (ed[0] * ef[1] - ed[1] * ef[0]) / size
        } else {
            0.0
        }
    }

    /// The side of `E -> D` that `F` is drawn on at `q`; `None` within [`DRAWN_MIN_SINE`] of the
    /// line.
    pub fn drawn_side(&self, q: &[f64]) -> Option<Side> {
        let s = self.sine(q);
        (s.abs() > DRAWN_MIN_SINE).then(|| side_of(s))
    }

    /// The side of `E -> D` that `F` lies on at an assembled `q`; `None` exactly on the line.
    pub fn side(&self, q: &[f64]) -> Option<Side> {
        let s = self.sine(q);
        (s != 0.0).then(|| side_of(s))
    }

    /// The link lengths `|EF|` (first body) and `|FD|` (second body), and the distance `|ED|`
    /// at `q`, m.
    /// `E` and `D` are taken on the bodies the dyad is pinned to, which place them: where
    /// assembly failed, the dyad's own ends may be anywhere.
    pub fn lengths(&self, q: &[f64]) -> [f64; 3] {
        let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        let outer = |k: usize, own: usize| {
            let ends = &self.ends[k];
            let (body, s) = ends.iter().find(|(b, _)| b.0 != Some(3 * own)).copied().unwrap_or(ends[0]);
            Frame::of_slice(body, q).point(s)
        };
        let [e, d] = [outer(0, self.bodies[0]), outer(2, self.bodies[1])];
        [dist(self.links[0][0], self.links[0][1]), dist(self.links[1][0], self.links[1][1]), dist(e, d)]
    }

    /// `q` with the dyad reflected in the line `E -> D`: each body turned about its end pin so
    /// that `F` goes to its mirror image (the other assembly mode, for Newton to start from).
    pub fn reflected(&self, q: &[f64]) -> Vec<f64> {
        let [e, f, d] = [0, 1, 2].map(|k| self.at(k, q));
        let (ux, uy) = (d[0] - e[0], d[1] - e[1]);
        let len2 = ux * ux + uy * uy;
        let mut out = q.to_vec();
        if len2 == 0.0 {
            return out;
        }
        let t = ((f[0] - e[0]) * ux + (f[1] - e[1]) * uy) / len2;
        let foot = [e[0] + t * ux, e[1] + t * uy];
        let mirror = [2.0 * foot[0] - f[0], 2.0 * foot[1] - f[1]];
        for (body, pivot) in self.bodies.iter().zip([e, d]) {
            let (a, b) = ([f[0] - pivot[0], f[1] - pivot[1]], [mirror[0] - pivot[0], mirror[1] - pivot[1]]);
            let turn = (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]);
            let (s, c) = turn.sin_cos();
            let k = 3 * body;
            let r = [q[k] - pivot[0], q[k + 1] - pivot[1]];
            out[k] = pivot[0] + c * r[0] - s * r[1];
            out[k + 1] = pivot[1] + s * r[0] + c * r[1];
            out[k + 2] = q[k + 2] + turn;
        }
        out
    }

    /// Its joints' names `[E, F, D]`.
    pub fn names<'m>(&self, model: &'m Model) -> [&'m str; 3] {
        self.joints.map(|k| model.joints[k].name.as_str())
    }

    /// The plain-words reason of a dyad at a toggle position at `q`: its links collinear at `F`,
    /// stretched (`|ED|` at their sum) or folded (at their difference).
    pub fn toggle(&self, model: &Model, q: &[f64]) -> String {
        let [e, f, d] = self.names(model);
        let [b1, b2] = self.bodies.map(|b| model.bodies[b].name.as_str());
        let [l1, l2, ed] = self.lengths(q);
        let (sum, diff) = (l1 + l2, (l1 - l2).abs());
        let (how, bound, words, op) = if (ed - sum).abs() <= (ed - diff).abs() {
            ("stretched", sum, format!("|{e}{f}| + |{f}{d}|"), "+")
        } else {
            ("folded", diff, format!("||{e}{f}| - |{f}{d}||"), "-")
        };
        let show = |x: f64| model.display.show("length", x);
        format!(
            "links {b1} and {b2} are collinear at joint {f} ({how}): |{e}{d}| = {} against {words} = {} {op} {} = {}",
            show(ed),
            show(l1),
            show(l2),
            show(bound)
        )
    }
}

/// The groups of `model` with the active `drivers`, in the order they are placed; empty above
/// [`MAX_BODIES`] bodies.
pub fn groups(model: &Model, drivers: &[usize]) -> Vec<Group> {
    let bodies = model.bodies.len();
    if bodies > MAX_BODIES {
        return Vec::new();
    }
    // Each element's rows and the bodies it touches.
    let elements: Vec<(usize, &Element)> = model
        .joints
        .iter()
        .enumerate()
        .chain(drivers.iter().map(|&d| (model.joints.len() + d, &model.drivers[d])))
        .collect();
    let touched: Vec<Vec<usize>> = elements
        .iter()
        .map(|(_, e)| {
            let mut b: Vec<usize> = e.constraint.columns().iter().map(|c| c / 3).collect();
            b.sort_unstable();
            b.dedup();
            b
        })
        .collect();
    let mut neighbours = vec![Vec::new(); bodies];
    for t in &touched {
        for &a in t {
            neighbours[a].extend(t.iter().copied().filter(|&b| b != a));
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    let mut placed = vec![false; bodies];
    let mut used = vec![false; elements.len()];
    let mut out = Vec::new();
    // The elements a candidate set `s` would take, and their rows.
    let take = |s: &[usize], placed: &[bool], used: &[bool]| {
        let mut rows = 0;
        let mut taken = Vec::new();
        for (k, t) in touched.iter().enumerate() {
            let inside = |b: &usize| placed[*b] || s.contains(b);
            if !used[k] && !t.is_empty() && t.iter().all(inside) && t.iter().any(|b| s.contains(b)) {
                rows += elements[k].1.constraint.rows();
                taken.push(k);
            }
        }
        (rows, taken)
    };
    while placed.iter().any(|p| !p) {
        let mut found = None;
        // A group is reached from the bodies already placed: its seeds are the bodies with an
        // element whose other bodies are all placed (ground included). Sets grow one
        // neighbour at a time, each set once (sorted), smallest first.
        let mut seeds: Vec<usize> = touched
            .iter()
            .zip(&used)
            .filter(|(_, &u)| !u)
            .filter_map(|(t, _)| match t.iter().filter(|&&b| !placed[b]).collect::<Vec<_>>()[..] {
                [&b] => Some(b),
                _ => None,
            })
            .collect();
        seeds.sort_unstable();
        seeds.dedup();
        let mut level: Vec<Vec<usize>> = seeds.iter().map(|&b| vec![b]).collect();
        'sizes: for size in 1..=MAX_GROUP {
            for set in &level {
                let (rows, taken) = take(set, &placed, &used);
                if rows >= 3 * size {
                    found = Some((set.clone(), taken, 0));
                    break 'sizes;
                }
            }
            level = grown(&neighbours, &placed, &level);
        }
        // No group is placed by its rows: the freedom the drivers leave. The body the rows to
        // placed bodies hold best is an input link (a crank pinned to ground).
        let found = found.or_else(|| {
            seeds
                .iter()
                .map(|&b| (b, take(&[b], &placed, &used)))
                .filter(|(_, (rows, _))| *rows > 0)
                .max_by_key(|(b, (rows, _))| (*rows, std::cmp::Reverse(*b)))
                .map(|(b, (rows, taken))| (vec![b], taken, 3 - rows))
        });
        let Some((set, taken, free)) = found else {
            // Bodies that nothing reaches from ground: one group of them all.
            let rest: Vec<usize> = (0..bodies).filter(|&b| !placed[b]).collect();
            let (rows, taken) = take(&rest, &placed, &used);
            out.push(Group { free: (3 * rest.len()).saturating_sub(rows), bodies: rest, elements: taken, dyad: None });
            break;
        };
        for &b in &set {
            placed[b] = true;
        }
        for &k in &taken {
            used[k] = true;
        }
        let indices: Vec<usize> = taken.iter().map(|&k| elements[k].0).collect();
        let dyad = dyad_of(model, &set, &indices);
        out.push(Group { bodies: set, elements: indices, free, dyad });
    }
    out
}

/// The dyad of a group of two bodies placed by three pins, with `E` the end pin first in the file.
fn dyad_of(model: &Model, bodies: &[usize], elements: &[usize]) -> Option<Dyad> {
    let joints = model.joints.len();
    if bodies.len() != 2 || elements.len() != 3 || elements.iter().any(|&k| k >= joints) {
        return None;
    }
    let middle = elements
        .iter()
        .copied()
        .find(|&k| pin(&model.joints[k]).is_some_and(|ends| bodies.iter().all(|&b| on(&ends, b).is_some())))?;
    let mut ends = elements.iter().copied().filter(|&k| k != middle);
    let (e, d) = (ends.next()?, ends.next()?);
    Dyad::new(&model.joints, &model.bodies, [e.min(d), middle, e.max(d)]).ok()
}

/// Each set of `sets` with one more neighbour not yet `placed`: every such set once, sorted.
fn grown(neighbours: &[Vec<usize>], placed: &[bool], sets: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let mut out = std::collections::BTreeSet::new();
    for set in sets {
        for &a in set {
            for &b in &neighbours[a] {
                if !placed[b] && !set.contains(&b) {
                    let mut bigger = set.clone();
                    bigger.push(b);
                    bigger.sort_unstable();
                    out.insert(bigger);
                }
            }
        }
    }
    out.into_iter().collect()
}

/// The dyads whose branch a run keeps and reports: each declared one (`branches:`), then every
/// other dyad of the groups with `drivers`, each once by its middle pin.
pub fn dyads(model: &Model, drivers: &[usize]) -> Vec<(Dyad, Option<Side>)> {
    let mut out: Vec<(Dyad, Option<Side>)> = model.branches.iter().map(|(d, s)| (d.clone(), Some(*s))).collect();
    for g in groups(model, drivers) {
        if let Some(d) = g.dyad {
            if !out.iter().any(|(o, _)| o.joints[1] == d.joints[1]) {
                out.push((d, None));
            }
        }
    }
    out
}

/// The branch of one dyad, as `check`, the summary and the report state it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Branch {
    /// The dyad's middle pin, `F`.
    pub joint: String,
    /// Its end pins `[E, D]`: the directed line the side is taken from.
    pub line: [String; 2],
    /// Its two bodies, the one with `E` first.
    pub bodies: [String; 2],
    /// The side of `E -> D` that `F` was assembled on (`None` on the line: a toggle position).
    pub side: Option<Side>,
    /// The side the drawing puts it on (`None`: drawn on the line).
    pub drawn: Option<Side>,
    /// The side declared in `branches:`, if any.
    pub declared: Option<Side>,
}

impl Branch {
    /// The branch of `dyad` drawn at `q0` and assembled at `q`.
    pub fn of(model: &Model, dyad: &Dyad, declared: Option<Side>, q0: &[f64], q: &[f64]) -> Branch {
        let [e, f, d] = dyad.names(model).map(String::from);
        Branch {
            joint: f,
            line: [e, d],
            bodies: dyad.bodies.map(|b| model.bodies[b].name.clone()),
            side: dyad.side(q),
            drawn: dyad.drawn_side(q0),
            declared,
        }
    }
}

/// The side of a positive (left) or negative (right) sine.
pub fn side_of(sine: f64) -> Side {
    if sine > 0.0 {
        Side::Left
    } else {
        Side::Right
    }
}

/// A side in words.
pub fn side_name(side: Option<Side>) -> &'static str {
    side.map_or("on", |s| s.name())
}

/// A dyad that passed into its other assembly mode during a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BranchChange {
    /// The dyad's middle pin, `F`.
    pub joint: String,
    /// Its end pins `[E, D]`.
    pub line: [String; 2],
    /// When `F` crossed the line, s: between two output times, where the sine of the angle at
    /// `E` (linear between them) is zero.
    pub time: f64,
    /// The side before.
    pub from: Side,
    /// The side after.
    pub to: Side,
}

impl BranchChange {
    /// The change as the error of a run that must keep its branches (`why`: what says so).
    pub fn error(&self, why: &str) -> crate::error::Error {
        crate::error::Error::Branch {
            time: self.time,
            joint: self.joint.clone(),
            detail: format!("{} ({why})", self.message()),
        }
    }

    /// The change in words, for warnings and errors.
    pub fn message(&self) -> String {
        let (f, [e, d]) = (&self.joint, &self.line);
        format!(
            "the dyad of joint {f} changed branch at t = {:.6} s (through a toggle position): {f} went from {} to {} of the line {e} -> {d}",
            self.time,
            self.from.name(),
            self.to.name()
        )
    }
}

/// The branch of every dyad of a run, watched from one output time to the next.
#[derive(Debug, Clone, Default)]
pub struct BranchWatch {
    /// Each dyad, and the time and sine of the angle at `E` at the last output.
    dyads: Vec<(Dyad, f64, f64)>,
    /// The names `[E, F, D]` of each dyad.
    names: Vec<[String; 3]>,
}

impl BranchWatch {
    /// The watch of the dyads of `model` with the active `drivers`.
    pub fn new(model: &Model, drivers: &[usize]) -> BranchWatch {
        let dyads: Vec<Dyad> = dyads(model, drivers).into_iter().map(|(d, _)| d).collect();
        let names = dyads.iter().map(|d| d.names(model).map(String::from)).collect();
        BranchWatch { dyads: dyads.into_iter().map(|d| (d, f64::NAN, 0.0)).collect(), names }
    }

    /// The output at `t` with positions `q`: the first dyad whose side changed since the last.
    pub fn push(&mut self, t: f64, q: &[f64]) -> Option<BranchChange> {
        let mut change = None;
        for ((dyad, last_t, last), [e, f, d]) in self.dyads.iter_mut().zip(&self.names) {
            let sine = dyad.sine(q);
            // Exactly on the line has no side: the last side is kept, to compare with the next.
            if sine == 0.0 {
                continue;
            }
            if change.is_none() && *last != 0.0 && (sine > 0.0) != (*last > 0.0) {
                let time = *last_t + (t - *last_t) * *last / (*last - sine);
                let (from, to) = (side_of(*last), side_of(sine));
                change = Some(BranchChange { joint: f.clone(), line: [e.clone(), d.clone()], time, from, to });
            }
            (*last_t, *last) = (t, sine);
        }
        change
    }
}
