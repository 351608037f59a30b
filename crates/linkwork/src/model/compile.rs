//! [`ModelSpec`] => [`Model`]: check names, numbers and expressions (every problem, with its path),
//! resolve names to indices and build each joint's constraint.

use super::placement::{drawn, Drawn};
use super::spec::*;
use super::structure::Dyad;
use super::{
    Analysis, Body, Effort, Element, ForceElement, IntegratorSettings, Measure, MeasureKind, Model, PathPoint,
    SolverSettings, ENERGY_COLUMNS, INVERSE_COLUMNS, REACTION_QUANTITIES,
};
use crate::constraints::{
    Absolute, AbsoluteKind, BodyIx, Cam, CamProfile, CamRow, Constraint, Curve, Distance, Driver, DriverKind, Frame,
    Friction, FrictionLaw, GearKind, GearPair, GeneralConstraint, PointOnLine, RackPinion, Revolute, RollingDisc,
    Shape, Sketch, Translational, Var, DEFAULT_TRANSITION_VELOCITY,
};
use crate::error::Problem;
use crate::expr::functional::{Functional, TIME};
use crate::expr::{Expr, Names, Spline, TimeFunction};
use crate::forces::{
    Contact, Force, Load, PointLoad, RotationalSpringDamper, Shape as ContactShape, SpringDamper, StateExpr, StateVar,
    Torque,
};
use indexmap::IndexMap;
use std::path::Path;
use std::sync::Arc;

/// The name of the column that says how a run or a sweep's variant ended (summary.json's
/// `status`, the sweep table's column): no measure may take it.
const STATUS: &str = "status";

/// The most output points one analysis may ask for; more would exhaust memory rather than finish.
const MAX_OUTPUT_POINTS: f64 = 1e7;

/// What is wrong with output every `h` s (positive) from `t0` to `t1` (not before it), if
/// anything: more than [`MAX_OUTPUT_POINTS`] points, or a step longer than a span that is not
/// empty, which would silently give only the span's two ends.
fn output_step_problem(t0: f64, t1: f64, h: f64) -> Option<String> {
    let span = t1 - t0;
    if span / h > MAX_OUTPUT_POINTS {
        Some(format!("{} output points requested; at most {MAX_OUTPUT_POINTS:e} are allowed", (span / h).ceil()))
    } else if span > 0.0 && h > span {
        Some(format!(
            "the output step ({h} s) is longer than the analysis ({span} s from t_start to t_end), which would give \
             only its two ends; expected at most {span} s"
        ))
    } else {
        None
    }
}

/// What is wrong with stepping by `step` s at the time `t`, if anything: doubles there lie
/// farther apart than half the step, so output times `t_start + k step` (or sub-steps) round to
/// one another and a step can come out as zero. Half: a step must change `t` by at least two
/// units of its spacing for the rounded steps to stay within a factor of two of the one asked.
pub(crate) fn time_round_off(t: f64, step: f64) -> Option<String> {
    let spacing = f64::from_bits(t.abs().to_bits() + 1) - t.abs();
    (spacing > 0.5 * step).then(|| {
        format!(
            "time round-off at t = {} s: double precision spaces times there {spacing:.3e} s apart, too coarse for \
             steps of {step:e} s; keep the analysis's times nearer 0 (shift the drivers' time origin)",
            crate::error::seconds(&t)
        )
    })
}

/// Build the model, or list every problem found.
/// (a table's `file:` relative to the working folder).
pub fn compile(spec: &ModelSpec) -> Result<Model, Vec<Problem>> {
    compile_partial(spec, &[], Path::new(""))
}

/// Build the model from the entries that were read; `broken` names (`section.name`) the entries
/// that were not: they are taken as existing, so that only their own problems are reported. A
/// table's `file:` is relative to `folder`.
pub fn compile_partial(spec: &ModelSpec, broken: &[String], folder: &Path) -> Result<Model, Vec<Problem>> {
    let mut cx = Cx {
        spec,
        points: IndexMap::new(),
        placed: IndexMap::new(),
        tables: IndexMap::new(),
        problems: Vec::new(),
        q0: Vec::new(),
        broken,
        folder,
    };
    // A table that cannot be built (or read) stands in as zero, so that an expression using it
    // reports only its own problems; the model is refused for the table's.
    let stand_in = || Arc::new(Spline::new(vec![0.0, 1.0], vec![0.0, 0.0], Default::default()).expect("two points"));
    for (name, table) in &spec.tables {
        let path = format!("tables.{name}");
        cx.name(&path, name);
        let built = super::tables::table(&path, table, folder).map(Arc::new).unwrap_or_else(|problems| {
            cx.problems.extend(problems);
            stand_in()
        });
        cx.tables.insert(name.clone(), built);
    }
    for name in broken.iter().filter_map(|b| b.strip_prefix("tables.")) {
        cx.tables.insert(name.to_string(), stand_in());
    }
    let bodies = cx.bodies();
    cx.q0 = bodies.iter().flat_map(|b| b.q0).collect();
    cx.unique_names();
    let joints = cx.entries("joints", &spec.joints, |cx, name, path, j| {
        let (constraint, friction) = cx.joint(path, j)?;
        Some(Element { name: name.into(), kind: j.name(), constraint, friction })
    });
    let drivers = cx.entries("drivers", &spec.drivers, |cx, name, path, d| {
        Some(Element { name: name.into(), kind: d.name(), constraint: cx.driver(path, d)?, friction: None })
    });
    let forces = cx.entries("forces", &spec.forces, |cx, name, path, f| {
        let applied = matches!(f, ForceSpec::Force(..) | ForceSpec::Torque(..));
        Some(ForceElement { name: name.into(), kind: f.name(), applied, force: cx.force(path, f)? })
    });
    let measures = cx.entries("measures", &spec.measures, |cx, name, path, m| {
        Some(Measure { name: name.into(), kind: cx.measure(path, m, &joints)? })
    });
    let paths = cx.paths();
    let summaries = cx.entries("summaries", &spec.summaries, |cx, name, path, source| {
        Some((name.to_string(), cx.summary(path, source)?))
    });
    cx.distinct_measures();
    let gravity = spec.gravity.and_then(|g| cx.vec2("gravity", g)).unwrap_or([0.0, 0.0]);
    // Each number is a double, but the weight is their product: past 1.8e308 it is infinite,
    // and every reaction and potential energy with it.
    let g = gravity[0].hypot(gravity[1]);
    if !g.is_finite() {
        cx.problem("gravity", format!("its size |g| = {g} is out of range: a double holds up to 1.8e308"));
    } else {
        for b in bodies.iter().filter(|b| !(b.mass * g).is_finite()) {
            cx.problem(
                format!("bodies.{}.mass", b.name),
                format!("the weight m |g| = {:e} kg x {g} m/s^2 is out of range: a double holds up to 1.8e308", b.mass),
            );
        }
    }
    let analyses = cx.analyses();
    let branches = cx.branches(&joints, &bodies);
    if cx.problems.is_empty() {
        let name = spec.name.clone().unwrap_or_else(|| "model".into());
        Ok(Model {
            name,
            bodies,
            joints,
            drivers,
            gravity,
            forces,
            measures,
            paths,
            summaries: summaries.into_iter().collect(),
            analyses,
            source: String::new(),
            folder: folder.to_path_buf(),
            table_files: spec
                .tables
                .values()
                .filter_map(|t| t.file.clone())
                .chain(spec.joints.values().filter_map(|j| match j {
                    JointSpec::Cam(CamJoint { profile: Some(p), .. }) => p.file.clone(),
                    _ => None,
                }))
                .collect(),
            parameters: spec.parameters.clone(),
            parameter_units: IndexMap::new(),
            display: super::units::Display::read(&spec.display).unwrap_or_default(),
            warnings: Vec::new(),
            set: Vec::new(),
            placed: cx.placed,
            branches,
            branch_mode: spec.branch.unwrap_or_default(),
        })
    } else {
        Err(cx.problems)
    }
}

/// What expressions name of a body (`crank.phi`, `crank.omega`): its coordinates, their rates
/// and their accelerations.
const QUANTITIES: [&str; 9] = ["x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha"];

/// A body and a point of it, body frame.
type End = (BodyIx, [f64; 2]);

struct Cx<'s> {
    spec: &'s ModelSpec,
    /// Each body's named points in its frame (`points`, and `points_global` and those placed by
    /// lengths computed), and ground's (`ground`), global.
    points: IndexMap<String, IndexMap<String, [f64; 2]>>,
    /// What was placed from global coordinates ([`Model::placed`]).
    placed: IndexMap<String, [f64; 2]>,
    /// The tables that could be built, by name.
    tables: IndexMap<String, Arc<Spline>>,
    problems: Vec<Problem>,
    /// (3 * bodies) initial guess, for constants that default to their initial value.
    q0: Vec<f64>,
    /// `section.name` of entries that exist but could not be read.
    broken: &'s [String],
    /// The folder a table's or a profile's `file:` is relative to.
    folder: &'s Path,
}

/// What a model's expressions name besides the state: its parameters and tables.
struct ModelNames<'a> {
    parameters: &'a IndexMap<String, f64>,
    tables: &'a IndexMap<String, Arc<Spline>>,
}

impl Names for ModelNames<'_> {
    fn constant(&self, name: &str) -> Option<f64> {
        self.parameters.get(name).copied()
    }

    fn table(&self, name: &str) -> Option<Arc<Spline>> {
        self.tables.get(name).cloned()
    }
}

/// "it has A, B", the named points `names` of a body, or "it has `none`" when there are none.
pub(super) fn it_has(names: &[&str], none: &str) -> String {
    if names.is_empty() {
        format!("it has {none}")
    } else {
        format!("it has {}", names.join(", "))
    }
}

/// The problem with a body `name` that is none of `known`.
pub(super) fn unknown_body(name: &str, known: &[&str]) -> String {
    format!("unknown body '{name}'; expected ground or one of: {}", known.join(", "))
}

/// Names become CSV column prefixes and expression variables (`crank.phi`): identifiers only.
fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

impl Cx<'_> {
    /// Every body named in the file, read or not.
    fn body_names(&self) -> Vec<&str> {
        let broken = self.broken.iter().filter_map(|b| b.strip_prefix("bodies."));
        self.spec.bodies.keys().map(String::as_str).chain(broken).collect()
    }

    fn is_broken_body(&self, name: &str) -> bool {
        self.broken.iter().any(|b| b.strip_prefix("bodies.") == Some(name))
    }

    fn problem(&mut self, path: impl Into<String>, msg: impl Into<String>) {
        self.problems.push(Problem::new(path, msg));
    }

    /// Each entry of the model's `section` (`entries`) whose name is checked and which `build`
    /// builds from its name, path and spec, in file order.
    fn entries<S, T>(
        &mut self,
        section: &str,
        entries: &IndexMap<String, S>,
        mut build: impl FnMut(&mut Self, &str, &str, &S) -> Option<T>,
    ) -> Vec<T> {
        let mut out = Vec::new();
        for (name, entry) in entries {
            let path = format!("{section}.{name}");
            self.name(&path, name);
            out.extend(build(self, name, &path, entry));
        }
        out
    }

    fn name(&mut self, path: &str, name: &str) {
        if !is_identifier(name) {
            self.problem(
                path,
                format!("'{name}' is not a valid name: use letters, digits and _, not starting with a digit"),
            );
        }
    }

    fn finite(&mut self, path: &str, v: f64) -> Option<f64> {
        finite(&mut self.problems, path, v)
    }

    fn positive(&mut self, path: &str, v: f64) -> Option<f64> {
        positive(&mut self.problems, path, v)
    }

    fn vec2(&mut self, path: &str, v: [f64; 2]) -> Option<[f64; 2]> {
        let a = self.finite(&format!("{path}[0]"), v[0]);
        let b = self.finite(&format!("{path}[1]"), v[1]);
        Some([a?, b?])
    }

    fn axis(&mut self, path: &str, v: [f64; 2]) -> Option<[f64; 2]> {
        let v = self.vec2(path, v)?;
        if v[0].hypot(v[1]) < 1e-12 {
            self.problem(path, "zero-length axis: expected a non-zero direction [x, y]");
            return None;
        }
        Some(v)
    }

    fn bodies(&mut self) -> Vec<Body> {
        if self.body_names().is_empty() {
            self.problem("bodies", "at least one moving body is required");
        }
        let spec = self.spec;
        let Drawn { poses, points, placed } = drawn(spec, self.broken, &mut self.problems);
        self.placed.extend(placed);
        let bodies = spec
            .bodies
            .iter()
            .enumerate()
            .map(|(k, (name, b))| {
                let path = format!("bodies.{name}");
                if name == "ground" {
                    self.problem(&path, "'ground' is the fixed body and cannot be listed among the moving bodies");
                }
                self.name(&path, name);
                if let Some(m) = self.finite(&format!("{path}.mass"), b.mass) {
                    if m < 0.0 {
                        self.problem(format!("{path}.mass"), format!("expected a mass >= 0 kg, found {m}"));
                    }
                }
                if let Some(j) = self.finite(&format!("{path}.inertia"), b.inertia) {
                    if j < 0.0 {
                        self.problem(
                            format!("{path}.inertia"),
                            format!("expected a moment of inertia >= 0 kg m^2, found {j}"),
                        );
                    }
                }
                let q0 = poses.get(name).copied().unwrap_or_default();
                let vel = self.vec2(&format!("{path}.velocity"), b.velocity).unwrap_or([0.0; 2]);
                let omega = self.finite(&format!("{path}.omega"), b.omega).unwrap_or(0.0);
                let points = points.get(name).cloned().unwrap_or_default();
                let mut given = [false; 6];
                for g in &b.given {
                    given[*g as usize] = true;
                }
                Body {
                    name: name.clone(),
                    index: k,
                    mass: b.mass,
                    inertia: b.inertia,
                    points,
                    q0,
                    v0: [vel[0], vel[1], omega],
                    given,
                }
            })
            .collect();
        self.points = points;
        bodies
    }

    /// Names are shared by bodies, joints, drivers, forces and measures (they label output
    /// columns).
    /// The declared assembly modes (`branches:`), each a dyad of the joints it names; a joint
    /// that is missing (or was not read) or does not make a dyad is a problem at its entry.
    fn branches(&mut self, joints: &[Element], bodies: &[Body]) -> Vec<(Dyad, Side)> {
        let spec = self.spec;
        let mut out = Vec::new();
        for (name, branch) in &spec.branches {
            let path = format!("branches.{name}");
            let broken = |j: &str| self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(j));
            let index = |j: &str| joints.iter().position(|e| e.name == j);
            let names = [branch.line[0].as_str(), name.as_str(), branch.line[1].as_str()];
            let fields = [format!("{path}.line[0]"), path.clone(), format!("{path}.line[1]")];
            let mut found = [0; 3];
            let mut ok = true;
            for ((j, field), slot) in names.iter().zip(&fields).zip(&mut found) {
                match index(j) {
                    Some(k) => *slot = k,
                    None => {
                        ok = false;
                        if !broken(j) && !spec.joints.contains_key(*j) {
                            let known: Vec<&str> = spec.joints.keys().map(String::as_str).collect();
                            self.problem(field, format!("unknown joint '{j}'; expected one of: {}", known.join(", ")));
                        }
                    }
                }
            }
            if !ok {
                continue;
            }
            match Dyad::new(joints, bodies, found) {
                Ok(dyad) => out.push((dyad, branch.side)),
                Err(why) => self.problem(
                    path,
                    format!("{why}; expected a dyad: the entry's joint a pin between two moving bodies, `line` the pins [E, D] joining each of them to another body"),
                ),
            }
        }
        out
    }

    fn unique_names(&mut self) {
        let spec = self.spec;
        let mut seen: IndexMap<&str, &str> = IndexMap::new();
        let broken = self.broken.iter().filter_map(|b| b.split_once('.'));
        let all = spec
            .bodies
            .keys()
            .map(|k| ("bodies", k.as_str()))
            .chain(spec.joints.keys().map(|k| ("joints", k.as_str())))
            .chain(spec.drivers.keys().map(|k| ("drivers", k.as_str())))
            .chain(spec.forces.keys().map(|k| ("forces", k.as_str())))
            .chain(spec.measures.keys().map(|k| ("measures", k.as_str())))
            .chain(broken.filter(|(s, _)| ["bodies", "joints", "drivers", "forces", "measures"].contains(s)));
        for (section, name) in all {
            if let Some(first) = seen.get(name) {
                self.problem(
                    format!("{section}.{name}"),
                    format!("duplicate name: '{name}' is already used in {first}"),
                );
            } else {
                seen.insert(name, section);
            }
        }
    }

    /// A measure is read by name (its column of `results.csv`, by summaries, sweep outputs and
    /// Python), and expressions read the parameters by name: a measure named as a built-in column
    /// (`time`, `kinetic_energy` ...), as `status` (of a run and of a sweep's variant) or as a
    /// parameter is a problem at it naming the other (a measure `kinetic_energy` gave
    /// `results.csv` two columns of that name, and Python and the summaries read different ones).
    /// Summaries have names of their own (keys of `summary.json`'s `summaries`, read by nothing
    /// else), which collide with none of these.
    fn distinct_measures(&mut self) {
        let spec = self.spec;
        let built_in = std::iter::once(TIME).chain(ENERGY_COLUMNS).chain(INVERSE_COLUMNS);
        for name in spec.measures.keys() {
            let other = if built_in.clone().any(|c| c == name) {
                format!("the built-in column {name} of results.csv")
            } else if name == STATUS {
                "the status of a run (summary.json) and of a sweep's variant (a column of its table)".to_string()
            } else if spec.parameters.contains_key(name) {
                format!("the parameter parameters.{name}, which expressions read by that name")
            } else {
                continue;
            };
            self.problem(format!("measures.{name}"), format!("'{name}' is already {other}; choose another name"));
        }
    }

    fn body(&mut self, path: &str, name: &str) -> Option<BodyIx> {
        if name == "ground" {
            return Some(BodyIx::GROUND);
        }
        match self.spec.bodies.get_index_of(name) {
            Some(k) => Some(BodyIx(Some(3 * k))),
            None if self.is_broken_body(name) => None,
            None => {
                let message = unknown_body(name, &self.body_names());
                self.problem(path, message);
                None
            }
        }
    }

    fn point(&mut self, path: &str, body: &str, p: &PointRef) -> Option<[f64; 2]> {
        match p {
            PointRef::Coords(v) => self.vec2(path, *v),
            PointRef::Name(n) => {
                match self.points.get(body).map(|ps| (ps.get(n), ps)) {
                    Some((Some(v), _)) => Some(*v),
                    Some((None, ps)) => {
                        let known: Vec<&str> = ps.keys().map(String::as_str).collect();
                        let list = it_has(&known, "no named points");
                        self.problem(
                            path,
                            format!("unknown point '{n}' of body '{body}' ({list}); or give coordinates [x, y]"),
                        );
                        None
                    }
                    // The body itself is unknown: reported where the body is named.
                    None => None,
                }
            }
        }
    }

    /// The points of `paths:` (each `<body>.<point>` or `<body>`), or when it names none the
    /// points of the point measures, each once (a measure's own problems are reported at it).
    fn paths(&mut self) -> Vec<PathPoint> {
        let spec = self.spec;
        let mut out: Vec<PathPoint> = Vec::new();
        if spec.paths.is_empty() {
            for m in spec.measures.values() {
                let MeasureSpec::Point(PointMeasure { body, point, .. }) = m else { continue };
                let Some(points) = self.points.get(body) else { continue };
                let (named, s) = match point {
                    PointRef::Name(n) => (points.get_key_value(n), points.get(n).copied()),
                    PointRef::Coords(v) => (points.iter().find(|(_, s)| *s == v), Some(*v)),
                };
                let Some(s) = s.filter(|s| s.iter().all(|x| x.is_finite())) else { continue };
                let name = match named {
                    Some((n, _)) => format!("{body}.{n}"),
                    None if s == [0.0; 2] => body.clone(),
                    None => format!("{body} [{}, {}]", s[0], s[1]),
                };
                if !out.iter().any(|p| p.body == *body && p.point == s) {
                    out.push(PathPoint { name, body: body.clone(), point: s });
                }
            }
            return out;
        }
        for (k, entry) in spec.paths.iter().enumerate() {
            let path = format!("paths[{k}]");
            let (body, point) = match entry.split_once('.') {
                Some((body, point)) => (body, Some(point)),
                None => (entry.as_str(), None),
            };
            if self.moving(&path, body).is_none() {
                continue;
            }
            let Some(points) = self.points.get(body) else { continue };
            let s = match point {
                None => [0.0; 2],
                Some(p) => match points.get(p) {
                    Some(s) => *s,
                    None => {
                        let known: Vec<&str> = points.keys().map(String::as_str).collect();
                        let list = if known.is_empty() {
                            "it has no named points".to_string()
                        } else {
                            format!("it has {}", known.join(", "))
                        };
                        self.problem(&path, format!("unknown point '{p}' of body '{body}' ({list}); expected <body>.<point>, or <body> for its centre of mass"));
                        continue;
                    }
                },
            };
            if let Some(first) = spec.paths[..k].iter().position(|e| e == entry) {
                self.problem(&path, format!("'{entry}' is already paths[{first}]: name each point once"));
                continue;
            }
            out.push(PathPoint { name: entry.clone(), body: body.to_string(), point: s });
        }
        out
    }

    /// Body `name`'s frame at its initial position (ground's is the global one); `None` for a
    /// body that is not known (reported where it is named).
    fn initial_frame(&self, name: &str) -> Option<Frame> {
        if name == "ground" {
            return Some(Frame::of_slice(BodyIx::GROUND, &self.q0));
        }
        let k = self.spec.bodies.get_index_of(name)?;
        (self.q0.len() >= 3 * k + 3).then(|| Frame::of_slice(BodyIx(Some(3 * k)), &self.q0))
    }

    /// The two points of a joint at `path` that coincide at the initial position: `point_i` and
    /// `point_j` as given, or both from `at`, the global point, in each body's frame.
    fn placed_points(
        &mut self,
        path: &str,
        bodies: [&str; 2],
        points: [&Option<PointRef>; 2],
        at: &Option<[f64; 2]>,
    ) -> Option<(PointRef, PointRef)> {
        match (at, points) {
            (Some(_), [Some(_), _] | [_, Some(_)]) => {
                self.problem(format!("{path}.at"), "give at (global) or point_i and point_j (body frames), not both");
                None
            }
            (Some(at), _) => {
                let at = self.vec2(&format!("{path}.at"), *at)?;
                // An unknown body is reported where the joint names it (`ends`).
                let [pi, pj] = bodies.map(|b| self.initial_frame(b).map_or([0.0; 2], |f| f.local(at)));
                self.placed.insert(format!("{path}.point_i"), pi);
                self.placed.insert(format!("{path}.point_j"), pj);
                Some((PointRef::Coords(pi), PointRef::Coords(pj)))
            }
            (None, [Some(pi), Some(pj)]) => Some((pi.clone(), pj.clone())),
            (None, [pi, _]) => {
                let field = if pi.is_none() { "point_i" } else { "point_j" };
                self.problem(
                    format!("{path}.{field}"),
                    "missing: give point_i and point_j (body frames), or at: [x, y] (the global point)",
                );
                None
            }
        }
    }

    /// The directions of a joint at `path`, each `(field, body, value)`: as given, or all from
    /// `axis`, the global direction at the initial position, in each body's frame.
    fn placed_axes<const N: usize>(
        &mut self,
        path: &str,
        fields: [(&str, &str, &Option<[f64; 2]>); N],
        axis: &Option<[f64; 2]>,
    ) -> Option<[[f64; 2]; N]> {
        let names = fields.map(|(f, _, _)| f).join(" and ");
        match axis {
            Some(_) if fields.iter().any(|(_, _, v)| v.is_some()) => {
                self.problem(format!("{path}.axis"), format!("give axis (global) or {names} (body frames), not both"));
                None
            }
            Some(a) => {
                let a = self.axis(&format!("{path}.axis"), *a)?;
                // An unknown body is reported where the joint names it.
                let local = fields.map(|(_, b, _)| self.initial_frame(b).map_or(a, |f| f.unrotate(a)));
                for ((field, _, _), v) in fields.iter().zip(&local) {
                    self.placed.insert(format!("{path}.{field}"), *v);
                }
                Some(local)
            }
            None => {
                if let Some((field, _, _)) = fields.iter().find(|(_, _, v)| v.is_none()) {
                    let message =
                        format!("missing: give {names} (body frames), or axis: [x, y] (the global direction)");
                    self.problem(format!("{path}.{field}"), message);
                    return None;
                }
                Some(fields.map(|(_, _, v)| v.unwrap_or_default()))
            }
        }
    }

    /// A body and one of its points, both resolved.
    fn body_point(&mut self, path: &str, bfield: &str, body: &str, pfield: &str, p: &PointRef) -> Option<End> {
        let b = self.body(&format!("{path}.{bfield}"), body);
        let s = self.point(&format!("{path}.{pfield}"), body, p);
        Some((b?, s?))
    }

    /// The two ends of an element between two bodies (`body_i`, `point_i`, `body_j`, `point_j`
    /// at `path`), resolved; a problem at `body_j` when both are the same body. An element between
    /// the bodies themselves (a torque, a relative angle) takes their origins.
    fn ends(
        &mut self,
        path: &str,
        body_i: &str,
        point_i: &PointRef,
        body_j: &str,
        point_j: &PointRef,
    ) -> Option<[End; 2]> {
        let a = self.body_point(path, "body_i", body_i, "point_i", point_i);
        let b = self.body_point(path, "body_j", body_j, "point_j", point_j);
        if body_i == body_j {
            let message = format!("a joint needs two different bodies, found '{body_i}' twice");
            self.problem(format!("{path}.body_j"), message);
            return None;
        }
        Some([a?, b?])
    }

    /// A moving body and one of its points (`body`, `point` at `path`), resolved; ground is
    /// refused, as what cannot be `verb` ("constrained", "driven").
    fn moving_point(&mut self, path: &str, body: &str, point: &PointRef, verb: &str) -> Option<End> {
        let (b, s) = self.body_point(path, "body", body, "point", point)?;
        if b == BodyIx::GROUND {
            self.problem(format!("{path}.body"), format!("ground cannot be {verb}; name a moving body"));
            return None;
        }
        Some((b, s))
    }

    /// The distance between two body points in the initial guess, m.
    fn initial_distance(&self, [(i, sp), (j, sq)]: [End; 2]) -> f64 {
        let (p, r) = (Frame::of_slice(i, &self.q0).point(sp), Frame::of_slice(j, &self.q0).point(sq));
        (r[0] - p[0]).hypot(r[1] - p[1])
    }

    /// The coefficient and transition velocity of the `friction:` mapping at `path`, checked.
    fn friction_law(&mut self, path: &str, mu: f64, transition_velocity: Option<f64>) -> Option<FrictionLaw> {
        let mu = self.finite(&format!("{path}.mu"), mu).and_then(|mu| {
            if mu >= 0.0 {
                Some(mu)
            } else {
                self.problem(format!("{path}.mu"), format!("expected a coefficient of friction >= 0, found {mu}"));
                None
            }
        });
        let v_s = match transition_velocity {
            Some(v) => self.positive(&format!("{path}.transition_velocity"), v),
            None => Some(DEFAULT_TRANSITION_VELOCITY),
        };
        Some(FrictionLaw { mu: mu?, transition_velocity: v_s? })
    }

    /// A joint's constraint, and its friction when it has a `friction:` mapping.
    fn joint(&mut self, path: &str, j: &JointSpec) -> Option<(Box<dyn Constraint>, Option<Friction>)> {
        use JointSpec as J;
        let mut friction = None;
        let c: Box<dyn Constraint> = match j {
            J::Revolute(RevoluteJoint { body_i, point_i, body_j, point_j, at, friction: pin }) => {
                let points = self.placed_points(path, [body_i, body_j], [point_i, point_j], at);
                // The bodies are checked (`ends`) whether or not the points could be placed.
                let (pi, pj) = points.clone().unwrap_or_default();
                let ends = self.ends(path, body_i, &pi, body_j, &pj);
                let law = pin.as_ref().map(|f| {
                    let at = format!("{path}.friction");
                    (
                        self.friction_law(&at, f.mu, f.transition_velocity),
                        self.positive(&format!("{at}.radius"), f.radius),
                    )
                });
                let (_, [(i, sp), (j, sq)]) = (points?, ends?);
                let joint = Revolute::new(i, sp, j, sq);
                if let Some((law, radius)) = law {
                    friction = Some(joint.friction(law?, radius?));
                }
                Box::new(joint)
            }
            J::Translational(TranslationalJoint {
                body_i,
                point_i,
                axis_i,
                body_j,
                point_j,
                axis_j,
                at,
                axis,
                friction: slide,
            }) => {
                let points = self.placed_points(path, [body_i, body_j], [point_i, point_j], at);
                let axes = self.placed_axes(path, [("axis_i", body_i, axis_i), ("axis_j", body_j, axis_j)], axis);
                let (pi, pj) = points.clone().unwrap_or_default();
                let ends = self.ends(path, body_i, &pi, body_j, &pj);
                let vi = axes.and_then(|[ai, _]| self.axis(&format!("{path}.axis_i"), ai));
                let vj = axes.and_then(|[_, aj]| self.axis(&format!("{path}.axis_j"), aj));
                let law = slide.as_ref().map(|f| {
                    let at = format!("{path}.friction");
                    (
                        self.friction_law(&at, f.mu, f.transition_velocity),
                        self.positive(&format!("{at}.length"), f.length),
                    )
                });
                let (_, [(i, sp), (j, sq)], vi, vj) = (points?, ends?, vi?, vj?);
                let relative = i.coords(&self.q0)[2] - j.coords(&self.q0)[2];
                let joint = Translational::new(i, sp, vi, j, sq, vj).near(relative);
                if let Some((law, length)) = law {
                    friction = Some(joint.friction(law?, length?));
                }
                Box::new(joint)
            }
            J::PointOnLine(PointOnLineJoint { body_i, point_i, axis_i, body_j, point_j, at, axis }) => {
                let points = self.placed_points(path, [body_i, body_j], [point_i, point_j], at);
                let axes = self.placed_axes(path, [("axis_i", body_i, axis_i)], axis);
                let (pi, pj) = points.clone().unwrap_or_default();
                let ends = self.ends(path, body_i, &pi, body_j, &pj);
                let vi = axes.and_then(|[ai]| self.axis(&format!("{path}.axis_i"), ai));
                let (_, [(i, sp), (j, sq)], vi) = (points?, ends?, vi?);
                Box::new(PointOnLine::new(i, sp, vi, j, sq, 0.0))
            }
            J::RevoluteTranslational(RevoluteTranslationalJoint {
                body_i,
                point_i,
                axis_i,
                body_j,
                point_j,
                offset,
            }) => {
                let ([(i, sp), (j, sq)], vi) = self.line_and_point(path, body_i, point_i, axis_i, body_j, point_j)?;
                let offset = match offset {
                    Some(o) => self.finite(&format!("{path}.offset"), *o)?,
                    None => {
                        let (fi, fj) = (Frame::of_slice(i, &self.q0), Frame::of_slice(j, &self.q0));
                        let (p, r, a) = (fi.point(sp), fj.point(sq), fi.rotate(vi));
                        let n = [-a[1], a[0]];
                        ((r[0] - p[0]) * n[0] + (r[1] - p[1]) * n[1]) / a[0].hypot(a[1])
                    }
                };
                Box::new(PointOnLine::new(i, sp, vi, j, sq, offset))
            }
            J::Distance(DistanceJoint { body_i, point_i, body_j, point_j, length }) => {
                let ends = self.ends(path, body_i, point_i, body_j, point_j)?;
                let [(i, sp), (j, sq)] = ends;
                let length = match length {
                    Some(l) => self.positive(&format!("{path}.length"), *l)?,
                    None => {
                        let l = self.initial_distance(ends);
                        if l < 1e-12 {
                            self.problem(
                                format!("{path}.length"),
                                "the points coincide in the initial configuration: give a positive length",
                            );
                            return None;
                        }
                        l
                    }
                };
                Box::new(Distance::new(i, sp, j, sq, length))
            }
            J::AbsoluteX(AbsolutePoint { body, point, value }) | J::AbsoluteY(AbsolutePoint { body, point, value }) => {
                let (b, s) = self.moving_point(path, body, point, "constrained")?;
                let x = matches!(j, J::AbsoluteX(..));
                let value = match value {
                    Some(v) => self.finite(&format!("{path}.value"), *v)?,
                    None => Frame::of_slice(b, &self.q0).point(s)[if x { 0 } else { 1 }],
                };
                let kind = if x { AbsoluteKind::X } else { AbsoluteKind::Y };
                Box::new(Absolute::new(kind, b, s, value))
            }
            J::AbsoluteAngle(AbsoluteAngleJoint { body, value }) => {
                let (b, _) = self.moving_point(path, body, &PointRef::default(), "constrained")?;
                let value = match value {
                    Some(v) => self.finite(&format!("{path}.value"), *v)?,
                    None => b.coords(&self.q0)[2],
                };
                Box::new(Absolute::new(AbsoluteKind::Angle, b, [0.0, 0.0], value))
            }
            J::Gear(GearJoint { body_i, point_i, radius_i, body_j, point_j, radius_j, internal }) => {
                let ends = self.ends(path, body_i, point_i, body_j, point_j);
                let ri = self.positive(&format!("{path}.radius_i"), *radius_i);
                let rj = self.positive(&format!("{path}.radius_j"), *radius_j);
                let (ends, ri, rj) = (ends?, ri?, rj?);
                let [(i, si), (j, sj)] = ends;
                if self.initial_distance(ends) < 1e-9 {
                    self.problem(
                        path,
                        "the gear centres coincide in the initial configuration: the line of centres is undefined",
                    );
                    return None;
                }
                let kind = if *internal { GearKind::Internal } else { GearKind::External };
                Box::new(GearPair::new(kind, i, si, ri, j, sj, rj, &self.q0))
            }
            J::RackPinion(RollingJoint { body_i, point_i, radius, body_j, point_j, axis_j })
            | J::RollingDisc(RollingJoint { body_i, point_i, radius, body_j, point_j, axis_j }) => {
                let rack = matches!(j, J::RackPinion(..));
                let ends = self.ends(path, body_i, point_i, body_j, point_j);
                let r = self.positive(&format!("{path}.radius"), *radius);
                let v = self.axis(&format!("{path}.axis_j"), *axis_j);
                let ([(i, sc), (j, sl)], r, v) = (ends?, r?, v?);
                if rack {
                    Box::new(RackPinion::new(i, sc, r, j, sl, v, &self.q0))
                } else {
                    Box::new(RollingDisc::new(i, sc, r, j, sl, v, &self.q0))
                }
            }
            J::Expression(ExpressionJoint { expression }) => self.general(&format!("{path}.expression"), expression)?,
            J::Cam(cam) => self.cam(path, cam)?.boxed(),
        };
        Some((c, friction))
    }

    /// The ends of a point-on-line joint and the line's axis `axis_i`, resolved.
    fn line_and_point(
        &mut self,
        path: &str,
        body_i: &str,
        point_i: &PointRef,
        axis_i: &[f64; 2],
        body_j: &str,
        point_j: &PointRef,
    ) -> Option<([End; 2], [f64; 2])> {
        let ends = self.ends(path, body_i, point_i, body_j, point_j);
        let v = self.axis(&format!("{path}.axis_i"), *axis_i);
        Some((ends?, v?))
    }

    /// A cam joint's row: its ends, and its pitch curve (`radius`) or its working surface
    /// (`surface_radius`, `profile`) with the roller on it. Every field is read before any
    /// problem returns, so that each is reported.
    fn cam(&mut self, path: &str, cam: &CamJoint) -> Option<CamRow> {
        let CamJoint { body_i, point_i, body_j, point_j, radius, surface_radius, profile, roller_radius } = cam;
        let ends = self.ends(path, body_i, point_i, body_j, point_j);
        let roller = self.non_negative(&format!("{path}.roller_radius"), *roller_radius);
        // Either the pitch radius (`Ok`) or the surface (`Err`), each `None` when it has a problem.
        let given = match (radius, surface_radius, profile) {
            (Some(r), None, None) => {
                Ok(self.curve_expr(&format!("{path}.radius"), r, "psi", "the polar angle of the follower's point"))
            }
            (None, Some(r), None) => {
                let expr =
                    self.curve_expr(&format!("{path}.surface_radius"), r, "psi", "the polar angle of the surface");
                Err(expr.and_then(|e| self.curve_at(path, Curve::polar(e))))
            }
            (None, None, Some(p)) => Err(self.profile(&format!("{path}.profile"), p)),
            _ => {
                let message = "give one of radius (the pitch curve), surface_radius or profile (the working surface)";
                self.problem(path, message);
                return None;
            }
        };
        let ([(i, si), (j, sj)], roller) = (ends?, roller?);
        let expr = match given {
            Ok(expr) => expr?,
            Err(curve) => {
                return match CamProfile::try_new(i, si, j, sj, curve?, roller) {
                    Ok(c) => Some(CamRow::Surface(c)),
                    Err(e) => {
                        self.problem(format!("{path}.{}", e.field), e.message);
                        None
                    }
                };
            }
        };
        if self.initial_distance([(i, si), (j, sj)]) < 1e-12 {
            let message = "the follower's point is at the cam's centre in the initial configuration: psi is undefined";
            self.problem(path, message);
            return None;
        }
        match Cam::try_new(i, si, j, sj, expr) {
            Ok(c) => Some(CamRow::Pitch(c)),
            Err(e) => {
                self.problem(format!("{path}.radius"), e);
                None
            }
        }
    }

    /// An expression at `path` of the curve parameter `var` (slot 0; `what` it is), parameters
    /// and tables.
    fn curve_expr(&mut self, path: &str, src: &str, var: &str, what: &str) -> Option<Expr> {
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        let mut resolve = |name: &str| {
            if name == var {
                Ok(0)
            } else {
                Err(format!("expected {var} ({what}), a parameter or a table"))
            }
        };
        match Expr::parse_with(src, &names, &mut resolve) {
            Ok(e) => Some(e),
            Err(e) => {
                self.problem(path, format!("cannot read the expression '{src}': {e}"));
                None
            }
        }
    }

    /// A curve, or its problem at its field of the joint at `path`.
    fn curve_at(&mut self, path: &str, curve: Result<Curve, crate::constraints::CurveError>) -> Option<Curve> {
        curve.map_err(|e| self.problem(format!("{path}.{}", e.field), e.message)).ok()
    }

    /// A cam's `profile` at `path`: expressions of `u`, or points inline or from a file.
    fn profile(&mut self, path: &str, p: &CamProfileSpec) -> Option<Curve> {
        use ProfileColumn::{Text, Values};
        let joint = path.strip_suffix(".profile").unwrap_or(path).to_string();
        let points = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(&a, &b)| [a, b]).collect::<Vec<[f64; 2]>>();
        let no_period = |cx: &mut Self| {
            if p.period.is_some() {
                cx.problem(format!("{path}.period"), "points take no period (their parameter is the chord length)");
                return false;
            }
            true
        };
        let curve = match (&p.file, &p.x, &p.y) {
            (None, Text(x), Text(y)) => {
                let period = match p.period {
                    Some(v) => self.positive(&format!("{path}.period"), v),
                    // A parameter u that is an angle round the cam: one turn.
                    None => Some(2.0 * std::f64::consts::PI),
                };
                let x = self.curve_expr(&format!("{path}.x"), x, "u", "the profile's parameter");
                let y = self.curve_expr(&format!("{path}.y"), y, "u", "the profile's parameter");
                Curve::parametric(x?, y?, period?)
            }
            (None, Values(x), Values(y)) => {
                if x.len() != y.len() {
                    let message = format!("x has {} values and y {}; expected as many of each", x.len(), y.len());
                    self.problem(path, message);
                    return None;
                }
                if !no_period(self) {
                    return None;
                }
                Curve::points(&points(x, y))
            }
            (Some(file), Text(x), Text(y)) => {
                if !no_period(self) {
                    return None;
                }
                let (x, y, _) = super::tables::columns(path, &self.folder.join(file), x, y)
                    .map_err(|problems| self.problems.extend(problems))
                    .ok()?;
                Curve::points(&points(&x, &y))
            }
            (Some(_), x, y) => {
                for (field, c) in [("x", x), ("y", y)] {
                    if matches!(c, Values(_)) {
                        self.problem(format!("{path}.{field}"), "expected the name of a column of the file");
                    }
                }
                return None;
            }
            (None, _, _) => {
                self.problem(path, "expected x and y both expressions of u (text) or both lists of numbers (points)");
                return None;
            }
        };
        self.curve_at(&joint, curve)
    }

    /// A general constraint: names are `<body>.x`, `<body>.y`, `<body>.phi` and `t`.
    fn general(&mut self, path: &str, src: &str) -> Option<Box<dyn Constraint>> {
        let var = |v: Option<(usize, usize)>| v.map_or(Var::Time, |(col, _)| Var::Coord(col));
        let c = self.expression(path, src, 3, var, None, GeneralConstraint::try_new)?;
        Some(Box::new(c))
    }

    /// An expression of time and state: `<body>.x, .y, .phi, .vx, .vy, .omega` and `t`; for a
    /// `measure` also the accelerations `.ax, .ay, .alpha`, the joints' reactions
    /// `<joint>.fx, .fy, .torque` and the drivers' efforts `<driver>.effort`.
    fn state_expr(&mut self, path: &str, src: &str, measure: bool) -> Option<StateExpr> {
        let var = |v: Option<(usize, usize)>| match v {
            None => StateVar::Time,
            Some((col, 0)) => StateVar::Position(col),
            Some((col, 1)) => StateVar::Velocity(col),
            Some((col, _)) => StateVar::Acceleration(col),
        };
        let reaction = measure.then_some(StateVar::Reaction as fn(usize) -> StateVar);
        self.expression(path, src, if measure { 9 } else { 6 }, var, reaction, StateExpr::try_new)
    }

    /// The expression `src` at `path` compiled by `build` from its variables: `t`, and
    /// `<body>.<q>` for `q` among the first `quantities` of [`QUANTITIES`]; `var` makes each
    /// variable from `None` (time) or `Some((column, order of derivative))`. With `reaction`, also
    /// `<joint>.fx, .fy, .torque` and `<driver>.effort`, made by `reaction` from their entry in
    /// the reactions row (every joint's three, then every driver's effort, in file order). `None`
    /// (with the problem recorded, unless it names an entry that could not be read) when it
    /// cannot be compiled.
    fn expression<V: PartialEq, T>(
        &mut self,
        path: &str,
        src: &str,
        quantities: usize,
        var: impl Fn(Option<(usize, usize)>) -> V,
        reaction: Option<fn(usize) -> V>,
        build: impl FnOnce(Expr, Vec<V>) -> Result<T, String>,
    ) -> Option<T> {
        let spec = self.spec;
        let known = self.body_names().join(", ");
        let all_broken = self.broken;
        let broken = |section: &str| -> Vec<&str> {
            all_broken.iter().filter_map(|b| b.strip_prefix(section)?.strip_prefix('.')).collect()
        };
        let (broken_bodies, broken_joints, broken_drivers) = (broken("bodies"), broken("joints"), broken("drivers"));
        let names = |section: Vec<&str>, broken: &[&str]| {
            section.into_iter().chain(broken.iter().copied()).collect::<Vec<_>>().join(", ")
        };
        let joints = names(spec.joints.keys().map(String::as_str).collect(), &broken_joints);
        let drivers = names(spec.drivers.keys().map(String::as_str).collect(), &broken_drivers);
        let quantities = &QUANTITIES[..quantities];
        let hint = || {
            let mut q: Vec<String> = quantities.iter().map(|q| format!("<body>.{q}")).collect();
            if reaction.is_none() {
                return format!("expected {} or t, with a body among: {known}", q.join(", "));
            }
            q.extend(REACTION_QUANTITIES.iter().map(|q| format!("<joint>.{q}")));
            q.push("<driver>.effort".into());
            format!(
                "expected {} or t, with a body among: {known}; a joint among: {joints}; a driver among: {drivers}",
                q.join(", ")
            )
        };
        // The entry in the reactions row of `<owner>.<quantity>`: `Some(None)` for a joint or
        // driver that could not be read (its own problem is reported), `None` when the name is
        // not a reaction or effort.
        let reaction_of = |owner: &str, quantity: &str| -> Option<Option<usize>> {
            let component = REACTION_QUANTITIES.iter().position(|q| *q == quantity);
            if let Some(j) = spec.joints.get_index_of(owner) {
                return component.map(|c| Some(3 * j + c));
            }
            if let Some(d) = spec.drivers.get_index_of(owner) {
                return (quantity == "effort").then_some(Some(3 * spec.joints.len() + d));
            }
            let broken = (component.is_some() && broken_joints.contains(&owner))
                || (quantity == "effort" && broken_drivers.contains(&owner));
            broken.then_some(None)
        };
        let mut uses_broken = false;
        let mut vars: Vec<V> = Vec::new();
        let mut resolve = |name: &str| -> Result<usize, String> {
            let v = if name == "t" {
                var(None)
            } else {
                let (b, c) = name.split_once('.').ok_or_else(hint)?;
                let row = reaction.and_then(|r| Some((r, reaction_of(b, c)?)));
                match (spec.bodies.get_index_of(b), row) {
                    (None, Some((r, Some(k)))) => r(k),
                    (None, Some((r, None))) => {
                        uses_broken = true;
                        r(0)
                    }
                    (k, _) => {
                        let at = quantities.iter().position(|q| *q == c).ok_or_else(hint)?;
                        // A body that exists but could not be read: its own problem is reported.
                        let k = match k {
                            Some(k) => k,
                            None if broken_bodies.contains(&b) => {
                                uses_broken = true;
                                0
                            }
                            None => return Err(hint()),
                        };
                        var(Some((3 * k + at % 3, at / 3)))
                    }
                }
            };
            Ok(match vars.iter().position(|u| *u == v) {
                Some(s) => s,
                None => {
                    vars.push(v);
                    vars.len() - 1
                }
            })
        };
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        let expr = match Expr::parse_with(src, &names, &mut resolve) {
            Ok(e) => e,
            Err(e) => {
                self.problem(path, format!("cannot read the expression '{src}': {e}"));
                return None;
            }
        };
        if uses_broken {
            return None;
        }
        match build(expr, vars) {
            Ok(t) => Some(t),
            Err(e) => {
                self.problem(path, e);
                None
            }
        }
    }

    fn load(&mut self, path: &str, q: &Quantity) -> Option<Load> {
        match q {
            Quantity::Number(v) => self.finite(path, *v).map(Load::Constant),
            Quantity::Expression(src) => self.state_expr(path, src, false).map(Load::Expression),
        }
    }

    fn non_negative(&mut self, path: &str, v: f64) -> Option<f64> {
        let v = self.finite(path, v)?;
        if v < 0.0 {
            self.problem(path, format!("expected a number >= 0, found {v}"));
            return None;
        }
        Some(v)
    }

    fn moving(&mut self, path: &str, name: &str) -> Option<usize> {
        let b = self.body(path, name)?;
        if b == BodyIx::GROUND {
            self.problem(path, "ground does not move: name a moving body");
            return None;
        }
        b.0
    }

    fn force(&mut self, path: &str, f: &ForceSpec) -> Option<Box<dyn Force>> {
        Some(match f {
            ForceSpec::Force(PointForce { body, point, frame, fx, fy }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let s = self.point(&format!("{path}.point"), body, point);
                let fx = self.load(&format!("{path}.fx"), fx);
                let fy = self.load(&format!("{path}.fy"), fy);
                Box::new(PointLoad::new(b?, s?, *frame == ForceFrame::Body, fx?, fy?))
            }
            ForceSpec::Torque(TorqueSpec { body, torque }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let t = self.load(&format!("{path}.torque"), torque);
                Box::new(Torque::new(b?, t?))
            }
            ForceSpec::SpringDamper(SpringDamperSpec {
                body_i,
                point_i,
                body_j,
                point_j,
                stiffness,
                damping,
                free_length,
                actuator,
            }) => {
                let ends = self.ends(path, body_i, point_i, body_j, point_j);
                let k = self.non_negative(&format!("{path}.stiffness"), *stiffness);
                let c = self.non_negative(&format!("{path}.damping"), *damping);
                let act = self.load(&format!("{path}.actuator"), actuator);
                let (ends, k, c, act) = (ends?, k?, c?, act?);
                let [(i, sp), (j, sq)] = ends;
                let l0 = match free_length {
                    Some(l) => self.non_negative(&format!("{path}.free_length"), *l)?,
                    None => self.initial_distance(ends),
                };
                Box::new(SpringDamper::new(i.0, sp, j.0, sq, k, c, l0, act))
            }
            ForceSpec::RotationalSpringDamper(RotationalSpringDamperSpec {
                body_i,
                body_j,
                stiffness,
                damping,
                free_angle,
                actuator,
            }) => {
                let origin = PointRef::default();
                let ends = self.ends(path, body_i, &origin, body_j, &origin);
                let k = self.non_negative(&format!("{path}.stiffness"), *stiffness);
                let c = self.non_negative(&format!("{path}.damping"), *damping);
                let act = self.load(&format!("{path}.actuator"), actuator);
                let ([(i, _), (j, _)], k, c, act) = (ends?, k?, c?, act?);
                let theta0 = match free_angle {
                    Some(a) => self.finite(&format!("{path}.free_angle"), *a)?,
                    None => i.coords(&self.q0)[2] - j.coords(&self.q0)[2],
                };
                Box::new(RotationalSpringDamper::new(i.0, j.0, k, c, theta0, act))
            }
            ForceSpec::Contact(spec) => self.contact(path, spec)?,
        })
    }

    /// A contact: its bodies, shapes (one a circle), normal law, friction and event depth.
    fn contact(&mut self, path: &str, spec: &ContactSpec) -> Option<Box<dyn Force>> {
        let bi = self.body(&format!("{path}.body_i"), &spec.body_i);
        let bj = self.body(&format!("{path}.body_j"), &spec.body_j);
        if spec.body_i == spec.body_j {
            let message = format!("a contact needs two different bodies, found '{}' twice", spec.body_i);
            self.problem(format!("{path}.body_j"), message);
        }
        let si = self.shape(&format!("{path}.shape_i"), &spec.shape_i);
        let sj = self.shape(&format!("{path}.shape_j"), &spec.shape_j);
        let k = self.positive(&format!("{path}.stiffness"), spec.stiffness);
        let e = match spec.exponent {
            Some(e) => self.finite(&format!("{path}.exponent"), e).and_then(|e| {
                if e < 1.0 {
                    self.problem(format!("{path}.exponent"), format!("expected a number >= 1 (the force's derivative is infinite at first touch below 1), found {e}"));
                    return None;
                }
                Some(e)
            }),
            None => Some(DEFAULT_CONTACT_EXPONENT),
        };
        let c = self.non_negative(&format!("{path}.damping"), spec.damping);
        let friction = match &spec.friction {
            Some(ContactFriction { mu, transition_velocity }) => {
                let mu = self.non_negative(&format!("{path}.friction.mu"), *mu);
                let v_s = match transition_velocity {
                    Some(v) => self.positive(&format!("{path}.friction.transition_velocity"), *v),
                    None => Some(DEFAULT_TRANSITION_VELOCITY),
                };
                mu.zip(v_s)
            }
            None => Some((0.0, DEFAULT_TRANSITION_VELOCITY)),
        };
        let depth = spec.max_penetration.map(|d| self.positive(&format!("{path}.max_penetration"), d));
        let (bi, bj, si, sj, k, e, c, friction) = (bi?, bj?, si?, sj?, k?, e?, c?, friction?);
        if bi == BodyIx::GROUND && bj == BodyIx::GROUND {
            self.problem(format!("{path}.body_j"), "both shapes are on ground: name a moving body");
            return None;
        }
        let ((a, (centre, radius)), (b, other)) = match (si, sj) {
            (ContactShape::Circle(centre, radius), other) => ((bi, (centre, radius)), (bj, other)),
            (other, ContactShape::Circle(centre, radius)) => ((bj, (centre, radius)), (bi, other)),
            _ => {
                self.problem(
                    format!("{path}.shape_j"),
                    "a contact between two segments or polylines is not supported; expected a circle on one of the bodies",
                );
                return None;
            }
        };
        let smallest = match other {
            ContactShape::Circle(_, r) => radius.min(r),
            ContactShape::Polyline(_) => radius,
        };
        let depth = match depth {
            Some(d) => d?,
            None => DEFAULT_PENETRATION_FRACTION * smallest,
        };
        Some(Box::new(Contact::new(a.0, centre, radius, b.0, other, (k, e, c), friction, depth)))
    }

    /// A contact shape, in its body's frame.
    fn shape(&mut self, path: &str, spec: &ShapeSpec) -> Option<ContactShape> {
        match (&spec.circle, &spec.segment, &spec.polyline) {
            (Some(CircleShape { centre, radius }), None, None) => {
                let c = self.vec2(&format!("{path}.circle.centre"), *centre);
                let r = self.positive(&format!("{path}.circle.radius"), *radius);
                Some(ContactShape::Circle(c?, r?))
            }
            (None, Some(points), None) => self.polyline(&format!("{path}.segment"), points),
            (None, None, Some(points)) => self.polyline(&format!("{path}.polyline"), points),
            _ => {
                self.problem(path, "expected exactly one of circle, segment, polyline");
                None
            }
        }
    }

    /// A chain of two or more points, each segment of positive length.
    fn polyline(&mut self, path: &str, points: &[[f64; 2]]) -> Option<ContactShape> {
        if points.len() < 2 {
            self.problem(path, format!("expected two or more points, found {}", points.len()));
            return None;
        }
        let mut ok = true;
        for (k, p) in points.iter().enumerate() {
            ok &= self.vec2(&format!("{path}[{k}]"), *p).is_some();
        }
        if !ok {
            return None;
        }
        for (k, w) in points.windows(2).enumerate() {
            if (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) < 1e-12 {
                self.problem(
                    format!("{path}[{}]", k + 1),
                    format!("the point repeats point {k}: a segment needs two distinct ends"),
                );
                ok = false;
            }
        }
        ok.then(|| ContactShape::Polyline(points.to_vec()))
    }

    /// A summary: a functional of the result columns, with the model's parameters and tables.
    fn summary(&mut self, path: &str, source: &str) -> Option<Functional> {
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        Functional::parse(source, &names).map_err(|message| self.problem(path, message)).ok()
    }

    /// A measure; `joints`: the joints compiled, whose pins a transmission angle takes.
    fn measure(&mut self, path: &str, m: &MeasureSpec, joints: &[Element]) -> Option<MeasureKind> {
        match m {
            MeasureSpec::Expression(src) => self.state_expr(path, src, true).map(MeasureKind::Expression),
            MeasureSpec::Point(PointMeasure { body, point, component }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let s = self.point(&format!("{path}.point"), body, point);
                Some(MeasureKind::Point { body: b?, s: s?, component: *component })
            }
            MeasureSpec::Standard(StandardMeasure::TransmissionAngle(TransmissionAngleMeasure {
                joint,
                coupler_joint,
                rocker_joint,
            })) => {
                let b = self.pin(&format!("{path}.joint"), joint, joints);
                let c = self.pin(&format!("{path}.coupler_joint"), coupler_joint, joints);
                let r = self.pin(&format!("{path}.rocker_joint"), rocker_joint, joints);
                let (b, c, r) = (b?, c?, r?);
                let coupler = self.link(&format!("{path}.coupler_joint"), "coupler", (joint, &b), (coupler_joint, &c));
                let rocker = self.link(&format!("{path}.rocker_joint"), "rocker", (joint, &b), (rocker_joint, &r));
                let (coupler, rocker) = (coupler?, rocker?);
                if coupler.0 == rocker.0 {
                    let body = self.body_name(coupler.0);
                    self.problem(
                        format!("{path}.rocker_joint"),
                        format!("'{rocker_joint}' is a pin of '{body}', the coupler (the body '{joint}' shares with '{coupler_joint}'); expected a pin of the other body of '{joint}'"),
                    );
                    return None;
                }
                Some(MeasureKind::TransmissionAngle { coupler, rocker })
            }
            MeasureSpec::Standard(StandardMeasure::VelocityRatio(VelocityRatioMeasure { input, output })) => {
                let i = self.moving(&format!("{path}.input"), input);
                let o = self.moving(&format!("{path}.output"), output);
                Some(MeasureKind::VelocityRatio { input: i? + 2, output: o? + 2 })
            }
            MeasureSpec::Standard(StandardMeasure::MechanicalAdvantage(MechanicalAdvantageMeasure {
                input,
                output,
            })) => {
                let i = self.effort(&format!("{path}.input"), input);
                let o = self.effort(&format!("{path}.output"), output);
                Some(MeasureKind::MechanicalAdvantage { input: i?, output: o? })
            }
            MeasureSpec::Standard(StandardMeasure::PressureAngle(PressureAngleMeasure { joint })) => {
                let path = format!("{path}.joint");
                let cam = match self.spec.joints.get(joint) {
                    // A cam joint that did not compile has its own problem.
                    Some(JointSpec::Cam(cam)) if joints.iter().any(|j| j.name == *joint) => cam,
                    Some(JointSpec::Cam(_)) => return None,
                    Some(other) => {
                        self.problem(path, format!("'{joint}' is a {} joint; expected a cam joint", other.name()));
                        return None;
                    }
                    None => {
                        if !self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(joint)) {
                            let known: Vec<&str> = self.spec.joints.keys().map(String::as_str).collect();
                            self.problem(
                                path,
                                format!("unknown joint '{joint}'; expected one of: {}", known.join(", ")),
                            );
                        }
                        return None;
                    }
                };
                self.cam(&format!("joints.{joint}"), cam).map(MeasureKind::PressureAngle)
            }
        }
    }

    /// The name of body `b` (`ground` for ground).
    fn body_name(&self, b: BodyIx) -> &str {
        b.0.map_or("ground", |k| self.spec.bodies.get_index(k / 3).map_or("ground", |(n, _)| n.as_str()))
    }

    /// The revolute joint `name` at `path` as its [`Sketch`] (its two bodies and their points);
    /// `None` with a problem when there is no such joint or it is not a pin (nothing more when
    /// the joint's own entry has a problem, reported there).
    fn pin(&mut self, path: &str, name: &str, joints: &[Element]) -> Option<Sketch> {
        let Some(spec) = self.spec.joints.get(name) else {
            if !self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(name)) {
                let known: Vec<&str> = self.spec.joints.keys().map(String::as_str).collect();
                self.problem(path, format!("unknown joint '{name}'; expected one of: {}", known.join(", ")));
            }
            return None;
        };
        let sketch = joints.iter().find(|j| j.name == name)?.constraint.sketch();
        match sketch {
            Some(s @ Sketch { shape: Shape::Pin, .. }) => Some(s),
            _ => {
                self.problem(path, format!("'{name}' is a {} joint; expected a revolute joint (a pin)", spec.name()));
                None
            }
        }
    }

    /// One of the two links whose lines make a transmission angle (`role`: coupler or rocker):
    /// the body the pin `common` shares with the pin `other` (named at `path`), and the line from
    /// `common` to `other` in its frame.
    fn link(
        &mut self,
        path: &str,
        role: &str,
        (common, b): (&str, &Sketch),
        (other, o): (&str, &Sketch),
    ) -> Option<(BodyIx, [f64; 2])> {
        let ends = |s: &Sketch| [(s.i, s.p), (s.j, s.q)];
        let shared: Vec<(BodyIx, [f64; 2], [f64; 2])> = ends(b)
            .into_iter()
            .flat_map(|(bb, sb)| ends(o).into_iter().filter(move |(ob, _)| *ob == bb).map(move |(_, so)| (bb, sb, so)))
            .collect();
        let bodies = |s: &Sketch| format!("'{}' and '{}'", self.body_name(s.i), self.body_name(s.j));
        let [(body, from, to)] = shared[..] else {
            let why = if shared.is_empty() { "shares no body with" } else { "joins the same two bodies as" };
            let message = format!(
                "'{other}' (between {}) {why} '{common}' (between {}); expected the {role}'s other pin, on one of the bodies of '{common}'",
                bodies(o),
                bodies(b)
            );
            self.problem(path, message);
            return None;
        };
        let line = [to[0] - from[0], to[1] - from[1]];
        // Pins closer than 1e-12 m (the round-off of coordinates of a few metres) give the line
        // no direction.
        if line[0].hypot(line[1]) < 1e-12 {
            let body = self.body_name(body).to_string();
            self.problem(path, format!("'{other}' and '{common}' are at the same point of '{body}': the {role}'s line is undefined; expected its pin at the other end of the {role}"));
            return None;
        }
        Some((body, line))
    }

    /// The input or output of a mechanical advantage at `path`: a driver (its effort) or a
    /// `torque` force (its torque).
    fn effort(&mut self, path: &str, name: &str) -> Option<Effort> {
        let spec = self.spec;
        if let Some(d) = spec.drivers.get_index_of(name) {
            return Some(Effort::Driver { slot: 3 * spec.joints.len() + d });
        }
        match spec.forces.get_full(name) {
            Some((k, _, ForceSpec::Torque(TorqueSpec { torque, .. }))) => {
                // The torque is compiled again over global coordinates; its problems are the
                // force's, reported at its own entry.
                let before = self.problems.len();
                let torque = self.load(&format!("forces.{name}.torque"), torque);
                self.problems.truncate(before);
                Some(Effort::Torque { force: k, torque: torque? })
            }
            Some((_, _, other)) => {
                self.problem(path, format!("'{name}' is a {} force; expected a driver or a torque force (for another load, write an expression of the result columns)", other.name()));
                None
            }
            None if self.broken.iter().any(|b| [format!("drivers.{name}"), format!("forces.{name}")].contains(b)) => {
                None
            }
            None => {
                let torques =
                    spec.forces.iter().filter(|(_, f)| matches!(f, ForceSpec::Torque(..))).map(|(n, _)| n.as_str());
                let known: Vec<&str> = spec.drivers.keys().map(String::as_str).chain(torques).collect();
                self.problem(path, format!("unknown driver or torque '{name}'; expected one of: {}", known.join(", ")));
                None
            }
        }
    }

    fn function(&mut self, path: &str, src: &str) -> Option<TimeFunction> {
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        match TimeFunction::parse_with(src, &names) {
            Ok(f) => Some(f),
            Err(e) => {
                self.problem(path, format!("cannot read the function '{src}': {e}"));
                None
            }
        }
    }

    fn driver(&mut self, path: &str, d: &DriverSpec) -> Option<Box<dyn Constraint>> {
        use DriverSpec as D;
        let (kind, f) = match d {
            D::Angle(AngleDriver { body, function }) => {
                let b = self.moving_point(path, body, &PointRef::default(), "driven");
                let f = self.function(&format!("{path}.function"), function);
                let ((b, _), f) = (b?, f?);
                (DriverKind::Angle { body: b }, f)
            }
            D::RelativeAngle(RelativeAngleDriver { body_i, body_j, function }) => {
                let origin = PointRef::default();
                let ends = self.ends(path, body_i, &origin, body_j, &origin);
                let f = self.function(&format!("{path}.function"), function);
                let [(i, _), (j, _)] = ends?;
                (DriverKind::RelativeAngle { i, j }, f?)
            }
            D::Distance(DistanceDriver { body_i, point_i, body_j, point_j, function }) => {
                let ends = self.ends(path, body_i, point_i, body_j, point_j);
                let f = self.function(&format!("{path}.function"), function);
                let [(i, s_p), (j, s_q)] = ends?;
                (DriverKind::Distance { i, s_p, j, s_q }, f?)
            }
            D::X(PointDriver { body, point, function }) | D::Y(PointDriver { body, point, function }) => {
                let bp = self.moving_point(path, body, point, "driven");
                let f = self.function(&format!("{path}.function"), function);
                let (b, p) = bp?;
                let kind = if matches!(d, D::X(..)) {
                    DriverKind::X { body: b, point: p }
                } else {
                    DriverKind::Y { body: b, point: p }
                };
                (kind, f?)
            }
        };
        Some(Box::new(Driver::new(kind, f)))
    }

    fn analyses(&mut self) -> IndexMap<String, Analysis> {
        let spec = self.spec;
        let mut out = IndexMap::new();
        for (name, a) in &spec.analyses {
            let path = format!("analyses.{name}");
            let driver_names: Vec<&str> = spec.drivers.keys().map(String::as_str).collect();
            let drivers = self.selection(&path, "drivers", "driver", &driver_names, a.drivers.as_deref());
            let force_names: Vec<&str> = spec.forces.keys().map(String::as_str).collect();
            let forces = self.selection(&path, "forces", "force", &force_names, a.forces.as_deref());
            let timing = timing(&mut self.problems, name, a, &Fallback::file());
            if a.kind != AnalysisKind::Modes && a.about.is_some() {
                self.problem(format!("{path}.about"), "only a modes analysis has a point to linearise about");
                continue;
            }
            if let Some(o) = &a.outputs {
                let path = format!("{path}.outputs");
                let body_names: Vec<&str> = spec.bodies.keys().map(String::as_str).collect();
                self.selection(&path, "bodies", "body", &body_names, Some(&o.bodies));
                let joint_names: Vec<&str> = spec.joints.keys().map(String::as_str).collect();
                self.selection(&path, "joints", "joint", &joint_names, Some(&o.joints));
            }
            let Some(Timing { t_start, t_end, step, settings, integrator }) = timing else { continue };
            out.insert(
                name.clone(),
                Analysis {
                    name: name.clone(),
                    kind: a.kind,
                    drivers,
                    forces,
                    t_start,
                    t_end,
                    step,
                    settings,
                    integrator,
                    about: a.about.unwrap_or_default(),
                    outputs: a.outputs.clone(),
                },
            );
        }
        out
    }

    /// The indices into `known` (the model's `section`: drivers or forces) of the names an
    /// analysis at `path` lists, every one when it lists none; each unknown name is a problem at
    /// `<path>.<section>[k]` (a name whose own entry is broken was reported there already).
    fn selection(
        &mut self,
        path: &str,
        section: &str,
        what: &str,
        known: &[&str],
        list: Option<&[String]>,
    ) -> Vec<usize> {
        let Some(list) = list else { return (0..known.len()).collect() };
        list.iter()
            .enumerate()
            .filter_map(|(k, d)| match known.iter().position(|&n| n == d) {
                Some(i) => Some(i),
                None if self.broken.contains(&format!("{section}.{d}")) => None,
                None => {
                    let message = if known.is_empty() {
                        format!("unknown {what} '{d}'; the model has no {section}")
                    } else {
                        format!("unknown {what} '{d}'; the model's {section} are: {}", known.join(", "))
                    };
                    self.problem(format!("{path}.{section}[{k}]"), message);
                    None
                }
            })
            .collect()
    }
}

/// The analysis `base` of a compiled model with the fields `changes` gives: an entry of the model
/// file's `analyses:` of `base`'s type and start, whose `t_end`, `step`, `integrator` and `solver`
/// are read (its `drivers`, `forces` and `about` are not). Checked as the file's own entries
/// are, each problem at its path in the file (`analyses.<name>.t_end`). Another integrator
/// returns the settings that belong to `base`'s (`max_order`, `alpha`, `formulation`) to their
/// defaults; the tolerances, steps and step budget carry over.
pub(crate) fn revise(base: &Analysis, changes: &AnalysisSpec) -> Result<Analysis, Vec<Problem>> {
    debug_assert!(changes.kind == base.kind && changes.t_start == base.t_start, "a change of type or start");
    let mut integrator = base.integrator;
    if let Some(kind) = changes.integrator.filter(|&k| k != base.integrator.kind) {
        let d = IntegratorSettings::default();
        integrator = IntegratorSettings {
            kind,
            max_order: d.max_order,
            alpha: d.alpha,
            formulation: d.formulation,
            fixed_step: d.fixed_step,
            ..base.integrator
        };
    }
    let fallback = Fallback { t_end: Some(base.t_end), step: Some(base.step), settings: base.settings, integrator };
    let mut problems = Vec::new();
    match timing(&mut problems, &base.name, changes, &fallback) {
        Some(Timing { t_start, t_end, step, settings, integrator }) if problems.is_empty() => {
            Ok(Analysis { t_start, t_end, step, settings, integrator, ..base.clone() })
        }
        _ => Err(problems),
    }
}

/// What an analysis has where its entry leaves a field out: the engine's defaults for an entry
/// of a model file (which must give `t_end` and `step`), the compiled analysis for
/// [`revise`].
struct Fallback {
    t_end: Option<f64>,
    step: Option<f64>,
    settings: SolverSettings,
    integrator: IntegratorSettings,
}

impl Fallback {
    fn file() -> Fallback {
        Fallback {
            t_end: None,
            step: None,
            settings: SolverSettings::default(),
            integrator: IntegratorSettings::default(),
        }
    }
}

/// The times and solver settings of a compiled analysis.
struct Timing {
    t_start: f64,
    t_end: f64,
    step: f64,
    settings: SolverSettings,
    integrator: IntegratorSettings,
}

/// The times and solver settings of the analysis `name` from its entry `a`, each field it
/// leaves out taken from `base`; `None` after a problem (every one is added to `problems`, at
/// `analyses.<name>.<field>`).
fn timing(problems: &mut Vec<Problem>, name: &str, a: &AnalysisSpec, base: &Fallback) -> Option<Timing> {
    let path = format!("analyses.{name}");
    let t0 = finite(problems, &format!("{path}.t_start"), a.t_start);
    let span = span(problems, &path, a, base, t0);
    let settings = solver_settings(problems, &format!("{path}.solver"), &a.solver, &base.settings);
    let integrator = integrator(problems, &path, name, a, &base.integrator);
    let (t0, (t1, h)) = (t0?, span?);
    if t1 < t0 {
        problems.push(Problem::new(format!("{path}.t_end"), format!("t_end ({t1}) is before t_start ({t0})")));
        return None;
    }
    if let Some(message) = output_step_problem(t0, t1, h) {
        problems.push(Problem::new(format!("{path}.step"), message));
        return None;
    }
    let far = if t0.abs() >= t1.abs() { t0 } else { t1 };
    if let Some(message) = time_round_off(far, h).filter(|_| t1 > t0) {
        let field = if 2.0 * t0.abs() >= t1.abs() { "t_start" } else { "t_end" };
        problems.push(Problem::new(format!("{path}.{field}"), message));
        return None;
    }
    Some(Timing { t_start: t0, t_end: t1, step: h, settings: settings?, integrator: integrator? })
}

/// `(t_end, step)` of the analysis at `path`: both required (unless `base` has them), except
/// that `static` defaults to one equilibrium at `t_start` and `modes` is at `t_start` and takes
/// neither.
fn span(
    problems: &mut Vec<Problem>,
    path: &str,
    a: &AnalysisSpec,
    base: &Fallback,
    t0: Option<f64>,
) -> Option<(f64, f64)> {
    let kind = a.kind;
    if kind == AnalysisKind::Modes {
        for (field, given) in [("t_end", a.t_end.is_some()), ("step", a.step.is_some())] {
            if given {
                problems.push(Problem::new(
                    format!("{path}.{field}"),
                    "a modes analysis is at one time (t_start); remove t_end and step",
                ));
            }
        }
        return if a.t_end.is_some() || a.step.is_some() { None } else { Some((t0?, 1.0)) };
    }
    let t1 = match (a.t_end, base.t_end) {
        (Some(t), _) => finite(problems, &format!("{path}.t_end"), t),
        (None, Some(t)) => Some(t),
        (None, None) if kind == AnalysisKind::Static && a.step.is_none() => return Some((t0?, 1.0)),
        (None, None) => {
            problems.push(Problem::new(
                format!("{path}.t_end"),
                format!("required: the end time of the {} analysis, s", kind.name()),
            ));
            None
        }
    };
    let h = match (a.step, base.step) {
        (Some(h), _) => positive(problems, &format!("{path}.step"), h),
        (None, Some(h)) => Some(h),
        (None, None) => {
            problems.push(Problem::new(format!("{path}.step"), "required: the output step, s"));
            None
        }
    };
    Some((t1?, h?))
}

/// The integrator of the analysis `name` at `path` and its settings, each left out taken from
/// The loosest `rtol` and `atol` a dynamic analysis accepts: `1e-2`. The error test lets each
/// step err by about the tolerance, relative to the state (`rtol`) or in its units (`atol`: m,
/// rad, m/s); above a percent the steps' errors are as large as the motion over a few dozen
/// steps (the double pendulum at `0.1` ends with a pin 4 cm off its anchor, at `1e300` 1,168 m
/// off, and both passed), and no check after the run could tell such results from an answer.
pub const MAX_INTEGRATOR_TOLERANCE: f64 = 1e-2;

/// `base`: only a dynamic analysis names one or gives its settings, each given tolerance and
/// step must be positive (a tolerance at most [`MAX_INTEGRATOR_TOLERANCE`]), and each setting
/// must belong to the integrator.
fn integrator(
    problems: &mut Vec<Problem>,
    path: &str,
    name: &str,
    a: &AnalysisSpec,
    base: &IntegratorSettings,
) -> Option<IntegratorSettings> {
    let s = &a.solver;
    let spath = format!("{path}.solver");
    if a.kind != AnalysisKind::Dynamic {
        let given = [
            (format!("{path}.integrator"), a.integrator.is_some()),
            (format!("{spath}.rtol"), s.rtol.is_some()),
            (format!("{spath}.atol"), s.atol.is_some()),
            (format!("{spath}.initial_step"), s.initial_step.is_some()),
            (format!("{spath}.max_step"), s.max_step.is_some()),
            (format!("{spath}.max_order"), s.max_order.is_some()),
            (format!("{spath}.alpha"), s.alpha.is_some()),
            (format!("{spath}.formulation"), s.formulation.is_some()),
        ];
        let mut ok = true;
        for (field, _) in given.into_iter().filter(|(_, given)| *given) {
            let message = format!("only a dynamic analysis has an integrator; '{name}' is {}", a.kind.name());
            problems.push(Problem::new(field, message));
            ok = false;
        }
        return ok.then_some(*base);
    }
    let kind = a.integrator.unwrap_or(base.kind);
    let mut ok = true;
    let mut pos = |problems: &mut Vec<Problem>, field: &str, v: Option<f64>| -> Option<f64> {
        let path = format!("{spath}.{field}");
        let r = positive(problems, &path, v?);
        let r = if matches!(field, "rtol" | "atol") { r.and_then(|v| tolerance_bound(problems, &path, v)) } else { r };
        ok &= r.is_some();
        r
    };
    let rtol = pos(problems, "rtol", s.rtol).unwrap_or(base.rtol);
    let atol = pos(problems, "atol", s.atol).unwrap_or(base.atol);
    let initial_step = pos(problems, "initial_step", s.initial_step).or(base.initial_step);
    let max_step = pos(problems, "max_step", s.max_step).or(base.max_step);
    let bound = IntegratorSettings::order_bound(kind);
    if let Some(k) = s.max_order {
        if kind == IntegratorKind::Hht {
            problems.push(Problem::new(
                format!("{spath}.max_order"),
                "hht has a fixed order (2); max_order is for bdf and abam",
            ));
            ok = false;
        } else if k == 0 || k > bound {
            problems.push(Problem::new(
                format!("{spath}.max_order"),
                format!("expected 1 to {bound} for {}, found {k}", kind.name()),
            ));
            ok = false;
        }
    }
    let alpha = match s.alpha {
        Some(al) if kind != IntegratorKind::Hht => {
            problems.push(Problem::new(format!("{spath}.alpha"), format!("alpha ({al}) is a setting of hht only")));
            ok = false;
            base.alpha
        }
        Some(al) if !(-1.0 / 3.0 - 1e-12..=0.0).contains(&al) => {
            problems.push(Problem::new(format!("{spath}.alpha"), format!("expected alpha in [-1/3, 0], found {al}")));
            ok = false;
            base.alpha
        }
        Some(al) => al,
        None => base.alpha,
    };
    if s.formulation.is_some() && kind != IntegratorKind::Bdf {
        problems.push(Problem::new(format!("{spath}.formulation"), "formulation is a setting of bdf only"));
        ok = false;
    }
    ok.then_some(IntegratorSettings {
        kind,
        rtol,
        atol,
        initial_step,
        max_step,
        max_order: s.max_order.or(base.max_order),
        alpha,
        formulation: s.formulation.unwrap_or(base.formulation),
        ..*base
    })
}

/// The position solver's settings at `path`, each left out taken from `base`.
fn solver_settings(
    problems: &mut Vec<Problem>,
    path: &str,
    s: &SolverSpec,
    base: &SolverSettings,
) -> Option<SolverSettings> {
    let mut ok = true;
    let mut pos = |problems: &mut Vec<Problem>, field: &str, v: Option<f64>, default: f64| -> f64 {
        match v {
            Some(v) => positive(problems, &format!("{path}.{field}"), v).unwrap_or_else(|| {
                ok = false;
                default
            }),
            None => default,
        }
    };
    let tolerance = pos(problems, "tolerance", s.tolerance, base.tolerance);
    let max_rotation = pos(problems, "max_rotation", s.max_rotation, base.max_rotation);
    let min_substep = pos(problems, "min_substep", s.min_substep, base.min_substep);
    let singular_condition = pos(problems, "singular_condition", s.singular_condition, base.singular_condition);
    let max_iterations = s.max_iterations.unwrap_or(base.max_iterations);
    if max_iterations == 0 || max_iterations > 1000 {
        problems.push(Problem::new(
            format!("{path}.max_iterations"),
            format!("expected 1 to 1000 iterations, found {max_iterations}"),
        ));
        ok = false;
    }
    if min_substep >= 1.0 {
        problems.push(Problem::new(format!("{path}.min_substep"), "expected a fraction of the output step below 1"));
        ok = false;
    }
    ok.then_some(SolverSettings { tolerance, max_iterations, max_rotation, min_substep, singular_condition })
}

/// `v`, or a problem at `path` when it is not finite.
pub(super) fn finite(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    if v.is_finite() {
        Some(v)
    } else {
        problems.push(Problem::new(path, format!("expected a finite number, found {v}")));
        None
    }
}

/// The exponent of a contact's penetration when none is given: 1.5, Hertz's for two cylinders'
/// ends or spheres, the usual choice (Lankarani and Nikravesh 1990).
pub const DEFAULT_CONTACT_EXPONENT: f64 = 1.5;

/// A contact's `max_penetration` when none is given, as a fraction of the smallest radius of the
/// pair: 1e-3. A step into first contact then ends at most that deep, where the force is a small
/// fraction of its peak in any impact that deforms the shapes less than their size.
pub const DEFAULT_PENETRATION_FRACTION: f64 = 1e-3;

/// `v`, or a problem at `path` when it is not a finite number above zero.
/// `v`, an integrator's tolerance at `path`, if at most [`MAX_INTEGRATOR_TOLERANCE`].
fn tolerance_bound(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    if v <= MAX_INTEGRATOR_TOLERANCE {
        return Some(v);
    }
    problems.push(Problem::new(
        path,
        format!(
            "expected at most {MAX_INTEGRATOR_TOLERANCE:e}, found {v:e}: a looser tolerance lets each step err by more \
             than a percent of the motion, and the results mean nothing"
        ),
    ));
    None
}

fn positive(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    let v = finite(problems, path, v)?;
    if v > 0.0 {
        Some(v)
    } else {
        problems.push(Problem::new(path, format!("expected a positive number, found {v}")));
        None
    }
}

#[cfg(test)]
mod tests {
    use crate::model::Model;
    use crate::Error;

    /// A pendulum with the analyses `analyses` (YAML flow mappings, one a line).
    fn pendulum(analyses: &str) -> Result<Model, Error> {
        Model::from_yaml(&format!(
            "bodies:\n  p: {{mass: 1, inertia: 0.1, position: [1, 0], angle: 0, points: {{o: [-1, 0]}}}}\n\
             joints:\n  o: {{type: revolute, body_i: p, point_i: o, body_j: ground, point_j: [0, 0]}}\n\
             analyses:\n{analyses}"
        ))
    }

    fn problems(analyses: &str) -> Vec<String> {
        match pendulum(analyses) {
            Err(Error::Model(p)) => p.iter().map(|p| p.to_string()).collect(),
            other => panic!("expected a model error, found {other:?}"),
        }
    }

    /// The settings of an integrator belong to a dynamic analysis, as the integrator does (a
    /// kinematic analysis ignored an `rtol` before, while it refused an `integrator`).
    #[test]
    fn dynamics_settings_belong_to_a_dynamic_analysis() {
        let p = problems("  s: {type: static, integrator: hht, solver: {rtol: 1e-3, formulation: index3}}\n");
        let only = "only a dynamic analysis has an integrator; 's' is static";
        for field in ["analyses.s.integrator", "analyses.s.solver.rtol", "analyses.s.solver.formulation"] {
            assert!(p.contains(&format!("{field}: {only}")), "{field}: {p:?}");
        }
        assert_eq!(p.len(), 3, "{p:?}");
    }

    /// An `rtol` below what round-off resolves is raised to it with a warning when the analysis
    /// runs, in the file as in an override (the file refused one below `1e-14` before).
    #[test]
    fn a_tolerance_below_round_off_compiles() {
        let model = pendulum("  d: {type: dynamic, t_end: 1, step: 0.1, solver: {rtol: 1e-16}}\n").unwrap();
        assert_eq!(model.analyses["d"].integrator.rtol, 1e-16);
    }

    /// Every problem of an analysis is reported, not only the first: a bad tolerance does not
    /// hide an end time before the start.
    #[test]
    fn every_problem_of_an_analysis_is_reported() {
        let p = problems("  d: {type: dynamic, t_start: 1, t_end: 0.5, step: 0.1, solver: {atol: 0}}\n");
        assert!(p.iter().any(|p| p == "analyses.d.t_end: t_end (0.5) is before t_start (1)"), "{p:?}");
        assert!(p.iter().any(|p| p == "analyses.d.solver.atol: expected a positive number, found 0"), "{p:?}");
    }
}
