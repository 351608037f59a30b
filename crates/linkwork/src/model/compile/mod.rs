//! [`ModelSpec`] => [`Model`]: check names, numbers and expressions (every problem, with its path),
//! resolve names to indices and build each element. The compiler [`Cx`] is every element's
//! [`Context`], the joints' and drivers' [`JointContext`] (each compiles itself in its
//! `constraints` module) and the force elements' [`ForceContext`] (each in its `forces` module);
//! its other pieces are the sections' own: [`bodies`], [`expressions`], [`measures`],
//! [`analyses`], and [`gradients`], the derivatives of the model's numbers with respect to its
//! parameters.

mod analyses;
mod bodies;
mod expressions;
mod gradients;
mod measures;

pub(crate) use analyses::{revise, time_round_off};

use super::placement::{drawn, Drawn, Grad2};
use super::spec::*;
use super::structure::Dyad;
use super::{
    Analysis, Body, Effort, Element, ForceElement, IntegratorSettings, Measure, MeasureKind, Model, PathPoint,
    SolverSettings, ENERGY_COLUMNS, INVERSE_COLUMNS, REACTION_QUANTITIES,
};
use crate::constraints::{cam_row, GeneralConstraint, JointContext, Shape, Sketch, Var};
use crate::element::{finite, positive, BodyIx, Context, Frame, Placed};
use crate::error::Problem;
use crate::expr::functional::{Functional, TIME};
use crate::expr::{Expr, Names, Spline, TimeFunction};
use crate::forces::{ForceContext, StateExpr, StateVar};
use indexmap::IndexMap;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Build the model, or list every problem found.
/// (a table's `file:` relative to the working folder).
pub fn compile(spec: &ModelSpec) -> Result<Model, Vec<Problem>> {
    compile_partial(spec, &[], Path::new(""))
}

/// Build the model from the entries that were read; `broken` names (`section.name`) the entries
/// that were not: they are taken as existing, so that only their own problems are reported. A
/// table's `file:` is relative to `folder`.
pub fn compile_partial(spec: &ModelSpec, broken: &[String], folder: &Path) -> Result<Model, Vec<Problem>> {
    compiled(spec, broken, folder).0
}

/// Each number handed to an element, with its derivatives with respect to the parameters, by
/// path ([`Cx::handed`]).
type Handed = HashMap<String, (f64, Vec<f64>)>;

/// As [`compile_partial`], with every number handed to an element and its derivatives
/// ([`Handed`]), which the tests of the derivatives check one by one.
fn compiled(spec: &ModelSpec, broken: &[String], folder: &Path) -> (Result<Model, Vec<Problem>>, Handed) {
    let mut cx = Cx {
        spec,
        points: IndexMap::new(),
        placed: IndexMap::new(),
        tables: IndexMap::new(),
        problems: Vec::new(),
        q0: Vec::new(),
        broken,
        folder,
        handed: HashMap::new(),
        point_gradients: IndexMap::new(),
        pose_gradients: IndexMap::new(),
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
        let (constraint, friction) = j.compile(cx, path)?;
        Some(Element { name: name.into(), kind: j.name(), constraint, friction })
    });
    let drivers = cx.entries("drivers", &spec.drivers, |cx, name, path, d| {
        Some(Element { name: name.into(), kind: d.name(), constraint: d.compile(cx, path)?, friction: None })
    });
    let forces = cx.entries("forces", &spec.forces, |cx, name, path, f| {
        let force = f.compile(cx, path)?;
        Some(ForceElement { name: name.into(), kind: f.name(), applied: force.applied(), force })
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
    let gradients = cx.gradients(&bodies, &joints, &drivers, &forces, &measures);
    let model = if cx.problems.is_empty() {
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
            tolerances: IndexMap::new(),
            display: super::units::Display::read(&spec.display).unwrap_or_default(),
            warnings: Vec::new(),
            set: Vec::new(),
            placed: cx.placed,
            branches,
            branch_mode: spec.branch.unwrap_or_default(),
            gradients,
        })
    } else {
        Err(cx.problems)
    };
    (model, cx.handed)
}

/// The compiler of one model file: the file, what has been resolved of it so far (the bodies'
/// points, the tables, the initial configuration) and the problems found.
struct Cx<'s> {
    /// The file.
    spec: &'s ModelSpec,
    /// Each body's named points in its frame (`points`, and `points_global` and those placed by
    /// lengths computed), and ground's (`ground`), global.
    points: IndexMap<String, IndexMap<String, [f64; 2]>>,
    /// What was placed from global coordinates ([`Model::placed`]).
    placed: IndexMap<String, [f64; 2]>,
    /// The tables that could be built, by name.
    tables: IndexMap<String, Arc<Spline>>,
    /// Every problem found so far, each at its path.
    problems: Vec<Problem>,
    /// (3 * bodies) initial guess, for constants that default to their initial value.
    q0: Vec<f64>,
    /// `section.name` of entries that exist but could not be read.
    broken: &'s [String],
    /// The folder a table's or a profile's `file:` is relative to.
    folder: &'s Path,
    /// Each number handed to an element ([`Context::hand`]) or placed for one, with its
    /// derivatives with respect to the parameters, by path (`joints.A.point_i[0]`); empty for a
    /// file without parameters.
    handed: Handed,
    /// The derivatives of each owner's named points, in its frame ([`Drawn::gradients`]).
    point_gradients: IndexMap<String, IndexMap<String, Grad2>>,
    /// The derivatives of each body's initial pose ([`Drawn::pose_gradients`]).
    pose_gradients: IndexMap<String, [Vec<f64>; 3]>,
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

    /// Every named value is a parameter: its index in file order ([`Model::parameters`]).
    fn parameter(&self, name: &str) -> Option<usize> {
        self.parameters.get_index_of(name)
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
pub(crate) fn is_identifier(s: &str) -> bool {
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

    /// Whether body `name` exists in the file but could not be read.
    fn is_broken_body(&self, name: &str) -> bool {
        self.broken.iter().any(|b| b.strip_prefix("bodies.") == Some(name))
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

    /// A problem at `path` when the entry's `name` is not an identifier.
    fn name(&mut self, path: &str, name: &str) {
        if !is_identifier(name) {
            self.problem(
                path,
                format!("'{name}' is not a valid name: use letters, digits and _, not starting with a digit"),
            );
        }
    }
}

/// Every element's [`Context`]: the model's bodies, points and names.
impl Context for Cx<'_> {
    fn problems(&mut self) -> &mut Vec<Problem> {
        &mut self.problems
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
                    Some((Some(v), _)) => {
                        let v = *v;
                        self.hand_point(path, (body, n), v);
                        Some(v)
                    }
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

    fn q0(&self) -> &[f64] {
        &self.q0
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

    fn place(&mut self, path: String, value: [f64; 2], from: Placed<'_>) {
        self.differentiate_placed(&path, value, from);
        self.placed.insert(path, value);
    }

    fn hand(&mut self, path: &str, v: f64) {
        if self.spec.gradients.count() > 0 && !self.handed.contains_key(path) {
            self.handed.insert(path.to_string(), (v, self.spec.gradients.field(path)));
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

    fn csv_columns(&mut self, path: &str, file: &str, x: &str, y: &str) -> Option<(Vec<f64>, Vec<f64>)> {
        let (x, y, _) = super::tables::columns(path, &self.folder.join(file), x, y)
            .map_err(|problems| self.problems.extend(problems))
            .ok()?;
        Some((x, y))
    }

    fn time_function(&mut self, path: &str, src: &str) -> Option<TimeFunction> {
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        match TimeFunction::parse_with(src, &names) {
            Ok(f) => Some(f),
            Err(e) => {
                self.problem(path, format!("cannot read the function '{src}': {e}"));
                None
            }
        }
    }
}

/// The joints' and drivers' [`JointContext`]: general constraints of the model's coordinates.
impl JointContext for Cx<'_> {
    fn coordinate_constraint(&mut self, path: &str, src: &str) -> Option<GeneralConstraint> {
        let var = |v: Option<(usize, usize)>| v.map_or(Var::Time, |(col, _)| Var::Coord(col));
        self.expression(path, src, 3, var, None, GeneralConstraint::try_new)
    }
}

/// The force elements' [`ForceContext`]: expressions of time and the model's state.
impl ForceContext for Cx<'_> {
    fn force_expr(&mut self, path: &str, src: &str) -> Option<StateExpr> {
        self.state_expr(path, src, false)
    }
}
