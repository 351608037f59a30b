//! Model files: schema ([`spec`]), reading with every problem located ([`parse_partial`]), and
//! compilation into an indexed, immutable [`Model`] ([`compile_partial`]), whose analyses carry
//! the compiled form of their `solver:` section ([`SolverSettings`], [`IntegratorSettings`]).

mod compile;
mod drawing;
mod measure;
mod params;
mod parse;
mod placement;
mod settings;
pub mod spec;
pub mod structure;
mod tables;
pub mod units;

pub use compile::{compile, compile_partial};
pub(crate) use compile::{is_identifier, revise, time_round_off};
pub use drawing::{BodyDrawing, Drawing, DriverDrawing, ElementDrawing, JointDrawing, PathPoint};
pub use params::{Distribution, Tolerance};
pub use parse::{parse_partial, parse_partial_with, parse_spec, Parsed};
pub use settings::{IntegratorSettings, SolverSettings, MAX_STEPS};

use crate::constraints::{BodyIx, CamRow, Constraint, Frame, Friction};
use crate::error::{Error, Problem, Result};
use crate::expr::functional::Functional;
use crate::forces::{Force, Load, StateExpr};
use indexmap::IndexMap;
use spec::AnalysisKind;
use std::path::{Path, PathBuf};

/// The reaction columns of each joint, `<joint>.<quantity>`: the force on its first body in the
/// global frame, N, and the torque, N m. Measures read them by these names.
pub const REACTION_QUANTITIES: [&str; 3] = ["fx", "fy", "torque"];

/// The columns of a dynamic analysis written after the body quantities, reactions and efforts
/// (measures read them by these names).
pub const ENERGY_COLUMNS: [&str; 5] =
    ["kinetic_energy", "potential_energy", "nonconservative_work", "position_residual", "velocity_residual"];

/// The columns of an inverse dynamic analysis written after the reactions and efforts.
pub const INVERSE_COLUMNS: [&str; 4] = ["kinetic_energy", "potential_energy", "driver_power", "applied_power"];

/// The columns of each contact, `<contact>.<quantity>`, after the measures: its normal force
/// `fn` (N, `>= 0`), its friction `ft` on the circle's body along the tangent `R90 n` (N) and
/// its penetration (m, 0 when separated).
pub const CONTACT_QUANTITIES: [&str; 3] = ["fn", "ft", "penetration"];

/// A moving body.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name in the model file.
    pub name: String,
    /// Position in the model's body list; its coordinates are `q[3 index .. 3 index + 3]`.
    pub index: usize,
    /// Mass, kg.
    pub mass: f64,
    /// Moment of inertia about the centre of mass, kg m^2.
    pub inertia: f64,
    /// Named points, body frame, m.
    pub points: IndexMap<String, [f64; 2]>,
    /// Initial guess `(x, y, phi)`.
    pub q0: [f64; 3],
    /// Initial guess `(vx, vy, omega)`.
    pub v0: [f64; 3],
    /// Which of `(x, y, phi, vx, vy, omega)` assembly holds at their initial values.
    pub given: [bool; 6],
}

/// The derivatives of a compiled model's numbers with respect to its parameters: every vector
/// here has one entry per parameter (file order), in SI per SI unit of the parameter. A number
/// that no parameter moves has a zero gradient.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DataGradients {
    /// Each parameter's value, with respect to each parameter given from outside: the identity,
    /// plus the chain rule through the expressions of earlier parameters (`m: rho * r`).
    pub params: Vec<Vec<f64>>,
    /// Each joint ([`Model::joints`] order), each of its numbers ([`Constraint::data`] order).
    pub joints: Vec<Vec<Vec<f64>>>,
    /// Each driver ([`Model::drivers`] order), each of its numbers ([`Constraint::data`] order).
    pub drivers: Vec<Vec<Vec<f64>>>,
    /// Each joint's friction ([`Model::joints`] order), each of its numbers ([`Friction::data`]
    /// order; none for a joint without friction).
    pub friction: Vec<Vec<Vec<f64>>>,
    /// Each body's mass and moment of inertia.
    pub bodies: Vec<[Vec<f64>; 2]>,
    /// Each body's named points ([`Body::points`] order), each coordinate.
    pub points: Vec<Vec<[Vec<f64>; 2]>>,
    /// Each measure ([`Model::measures`] order), each of its numbers (`MeasureKind::data` order).
    pub measures: Vec<Vec<Vec<f64>>>,
    /// Gravity's two components.
    pub gravity: [Vec<f64>; 2],
    /// Each force ([`Model::forces`] order), each of its numbers ([`crate::forces::Force::data`]
    /// order).
    pub forces: Vec<Vec<Vec<f64>>>,
}

/// A named joint or driver and its constraint rows.
#[derive(Debug)]
pub struct Element {
    /// Name in the model file.
    pub name: String,
    /// Its `type` in the model file.
    pub kind: &'static str,
    /// The equations.
    pub constraint: Box<dyn Constraint>,
    /// Coulomb friction (revolute and translational joints with a `friction:` mapping).
    pub friction: Option<Friction>,
}

/// A named applied force or force element.
#[derive(Debug)]
pub struct ForceElement {
    /// Name in the model file.
    pub name: String,
    /// Its `type` in the model file.
    pub kind: &'static str,
    /// Whether it is an applied force or torque (`force`, `torque`) rather than a force element
    /// (a spring-damper).
    pub applied: bool,
    /// The force law.
    pub force: Box<dyn Force>,
}

impl Model {
    /// The first of the active `drivers` whose value, rate or acceleration is not finite at one
    /// of `times`, as a [`Error::NonFinite`].
    pub fn non_finite_driver(&self, drivers: &[usize], times: &[f64]) -> Option<Error> {
        for &t in times {
            for &k in drivers {
                let d = &self.drivers[k];
                let Some(f) = d.constraint.time_function() else { continue };
                let (v, rate, acc) = f.eval(t);
                if let Some(value) = [v, rate, acc].into_iter().find(|x| !x.is_finite()) {
                    let (element, expression) = (format!("drivers.{}", d.name), f.source().to_string());
                    return Some(Error::NonFinite { time: t, element, expression, value });
                }
            }
        }
        None
    }

    /// The active driver with the fastest rate at `t`, as an [`Error::Unbounded`] that reached
    /// `limit`.
    pub fn fastest_driver(&self, drivers: &[usize], t: f64, limit: &str) -> Option<Error> {
        let rated = drivers.iter().filter_map(|&k| {
            let d = &self.drivers[k];
            let f = d.constraint.time_function()?;
            Some((d, f, f.eval(t).1))
        });
        let (d, f, rate) = rated.max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))?;
        let (element, expression) = (format!("drivers.{}", d.name), f.source().into());
        Some(Error::Unbounded { time: t, element, expression, rate, limit: limit.into() })
    }
}

impl Model {
    /// The name of entry `k` of the reactions row: `<joint>.fx`, `.fy`, `.torque` or
    /// `<driver>.effort`.
    pub fn reaction_name(&self, k: usize) -> String {
        match self.joints.get(k / 3) {
            Some(j) => format!("{}.{}", j.name, REACTION_QUANTITIES[k % 3]),
            None => format!("{}.effort", self.drivers[k - 3 * self.joints.len()].name),
        }
    }

    /// The measures `analysis` cannot compute, each a problem at the measure (or its field):
    /// a reaction, an effort or a mechanical advantage in an analysis with no reactions
    /// (`kinematic`, `modes`); the effort of a driver it does not hold; a torque it does not
    /// apply; a velocity ratio at rest (a `static` analysis, a `modes` one about an equilibrium).
    pub fn unavailable_measures(&self, analysis: &Analysis) -> Vec<Problem> {
        let mut problems = Vec::new();
        let drivers = 3 * self.joints.len();
        let named = |names: Vec<&str>| if names.is_empty() { "none".to_string() } else { names.join(", ") };
        for m in &self.measures {
            let path = format!("measures.{}", m.name);
            let (kind, name) = (analysis.kind, &analysis.name);
            let reads = m.reads();
            if matches!(kind, AnalysisKind::Kinematic | AnalysisKind::Modes) && !reads.is_empty() {
                let what =
                    match reads.iter().find_map(|(_, r)| if let Reads::Reaction(k) = r { Some(*k) } else { None }) {
                        Some(k) => format!("it reads {}, a joint reaction or driver effort", self.reaction_name(k)),
                        None => "a mechanical advantage needs the loads".to_string(),
                    };
                problems.push(Problem::new(
                    path,
                    format!(
                        "{what}, which the {} analysis '{name}' does not compute; expected an inverse, static or dynamic analysis (an inverse analysis with the same drivers has the same motion, and the reactions)",
                        kind.name()
                    ),
                ));
                continue;
            }
            let at_rest = kind == AnalysisKind::Static
                || (kind == AnalysisKind::Modes && analysis.about == spec::LinearisePoint::Equilibrium);
            if at_rest && matches!(m.kind, MeasureKind::VelocityRatio { .. }) {
                problems.push(Problem::new(
                    path,
                    format!("a velocity ratio needs velocities, and the {} analysis '{name}' is at rest (every velocity 0); expected a kinematic, inverse or dynamic analysis", kind.name()),
                ));
                continue;
            }
            for (field, read) in reads {
                let at = format!("{path}{field}");
                match read {
                    Reads::Reaction(k) if k >= drivers && !analysis.drivers.contains(&(k - drivers)) => {
                        let active = named(analysis.drivers.iter().map(|&d| self.drivers[d].name.as_str()).collect());
                        problems.push(Problem::new(
                            at,
                            format!(
                                "driver '{}' is not active in the analysis '{name}' (its drivers: {active}), so it has no {}; expected the effort of one of its drivers",
                                self.drivers[k - drivers].name,
                                self.reaction_name(k)
                            ),
                        ));
                    }
                    Reads::Force(f) if !analysis.forces.contains(&f) => {
                        let active = named(analysis.forces.iter().map(|&k| self.forces[k].name.as_str()).collect());
                        problems.push(Problem::new(
                            at,
                            format!(
                                "force '{}' does not load the analysis '{name}' (its forces: {active}); expected one of its forces or drivers",
                                self.forces[f].name
                            ),
                        ));
                    }
                    _ => {}
                }
            }
        }
        problems
    }
}

impl ForceElement {
    /// The element's generalised force at `(q, qdot, t)`, on its columns.
    fn generalised(&self, q: &[f64], qdot: &[f64], t: f64) -> Vec<f64> {
        let columns = self.force.columns();
        let x: Vec<f64> = columns.iter().map(|&c| q[c]).collect();
        let v: Vec<f64> = columns.iter().map(|&c| qdot[c]).collect();
        let mut out = vec![0.0; columns.len()];
        self.force.load(&x, &v, t, &mut out);
        out
    }

    /// A non-finite entry of the element's generalised force at `(q, qdot, t)`, if it has one.
    pub fn non_finite(&self, q: &[f64], qdot: &[f64], t: f64) -> Option<f64> {
        self.generalised(q, qdot, t).into_iter().find(|f| !f.is_finite())
    }

    /// How the element's generalised force at the positions `q`, at rest, changes from `t` to
    /// `t + h`: `(largest change, that change relative to the larger force)`. Where the force has a
    /// singularity in time (`1/(t - c)`) the change over a step of a few units of round-off of `t`
    /// is of the order of the force itself; a smooth force changes by `~h` relative.
    pub fn change_over(&self, q: &[f64], t: f64, h: f64) -> (f64, f64) {
        let rest = vec![0.0; q.len()];
        let (a, b) = (self.generalised(q, &rest, t), self.generalised(q, &rest, t + h));
        let size = a.iter().chain(&b).fold(0.0f64, |m, x| m.max(x.abs()));
        let change = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((y - x).abs()));
        (change, if size > 0.0 { change / size } else { 0.0 })
    }

    /// Its expressions for a message, `field: source` joined by `; ` (empty when it has none).
    pub fn expressions(&self) -> String {
        self.force
            .expressions()
            .iter()
            .map(|(field, source)| format!("{field}: {source}"))
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// A named output quantity.
#[derive(Debug)]
pub struct Measure {
    /// Name in the model file (the column's name).
    pub name: String,
    /// How it is computed.
    pub kind: MeasureKind,
}

/// How a measure is computed.
#[derive(Debug)]
pub enum MeasureKind {
    /// An expression of time, positions, velocities, accelerations, and entries of the
    /// reactions row (joints' reactions and drivers' efforts).
    Expression(StateExpr),
    /// A component of a body point (global frame).
    Point {
        /// Index in `q` of the body's `x`.
        body: usize,
        /// The point, body frame, m.
        s: [f64; 2],
        /// Which component.
        component: spec::PointComponent,
    },
    /// The acute angle between two lines, each fixed in a body: the coupler's and the rocker's,
    /// each `(body, direction in its frame from the common pin to the body's other pin)`.
    TransmissionAngle {
        /// The coupler's line.
        coupler: (BodyIx, [f64; 2]),
        /// The rocker's line.
        rocker: (BodyIx, [f64; 2]),
    },
    /// `omega_output / omega_input`.
    VelocityRatio {
        /// Index in `q` of the input body's `phi`.
        input: usize,
        /// Index in `q` of the output body's `phi`.
        output: usize,
    },
    /// The pressure angle of a cam joint with a radial follower: the angle between the line from
    /// the cam's centre to the follower's point and the contact normal (`atan(sigma R' / R)`,
    /// `sigma = sign(dpsi/dt)`, on a polar pitch curve).
    PressureAngle(CamRow),
    /// `-output / input`, each applied to the mechanism.
    MechanicalAdvantage {
        /// The effort at the input.
        input: Effort,
        /// The load at the output.
        output: Effort,
    },
}

impl MeasureKind {
    /// The numbers of this measure that a parameter can move, each named as its field with the
    /// component: a point measure's `point[0]`, `point[1]`; a transmission angle's lines,
    /// `coupler[0]` ... `rocker[1]`. The model gives each its derivatives with respect to the
    /// parameters ([`DataGradients::measures`]).
    pub fn data(&self) -> Vec<(&'static str, f64)> {
        match self {
            MeasureKind::Point { s, .. } => vec![("point[0]", s[0]), ("point[1]", s[1])],
            MeasureKind::TransmissionAngle { coupler: (_, c), rocker: (_, r) } => {
                vec![("coupler[0]", c[0]), ("coupler[1]", c[1]), ("rocker[0]", r[0]), ("rocker[1]", r[1])]
            }
            MeasureKind::PressureAngle(cam) => cam.data(),
            _ => Vec::new(),
        }
    }
}

/// A torque or force applied to the mechanism, as a mechanical advantage reads it.
#[derive(Debug)]
pub enum Effort {
    /// A driver's effort: entry `slot` of the reactions row.
    Driver {
        /// Its entry in the reactions row.
        slot: usize,
    },
    /// A `torque` force's torque.
    Torque {
        /// Index into [`Model::forces`].
        force: usize,
        /// The torque, over global coordinates.
        torque: Load,
    },
}

impl Effort {
    fn value(&self, q: &[f64], qdot: &[f64], reactions: &[f64], t: f64) -> f64 {
        match self {
            Effort::Driver { slot } => reactions.get(*slot).copied().unwrap_or(f64::NAN),
            Effort::Torque { torque, .. } => torque.value(q, qdot, t),
        }
    }
}

/// What a measure reads besides the motion, at the field that names it.
enum Reads {
    /// Entry `k` of the reactions row.
    Reaction(usize),
    /// Force `k` of [`Model::forces`].
    Force(usize),
}

impl Measure {
    /// Its expression's source for a message (empty for the other kinds).
    pub fn expression(&self) -> &str {
        match &self.kind {
            MeasureKind::Expression(e) => e.source(),
            _ => "",
        }
    }

    /// The value at `(q, qdot, qddot, t)`, each `(n)`, with `reactions` the reactions row: every
    /// joint's `fx, fy, torque`, then every driver's effort, in model order (empty in an analysis
    /// that has none: [`Model::unavailable_measures`] refuses a measure that reads it there).
    pub fn value(&self, q: &[f64], qdot: &[f64], qddot: &[f64], reactions: &[f64], t: f64) -> f64 {
        match &self.kind {
            MeasureKind::Expression(e) => e.eval_global(q, qdot, qddot, reactions, t),
            MeasureKind::Point { body: b, s, component } => {
                measure::point_component(q, qdot, qddot, *b, *s, *component)
            }
            MeasureKind::TransmissionAngle { coupler: (c, u), rocker: (r, v) } => {
                let (u, v) = (Frame::of_slice(*c, q).rotate(*u), Frame::of_slice(*r, q).rotate(*v));
                measure::acute_angle(u, v)
            }
            MeasureKind::VelocityRatio { input, output } => {
                // omega_out = G(q) omega_in, so alpha_out = G alpha_in + G' omega_in^2: where the
                // input is at rest (a start from rest) the accelerations give G exactly.
                if qdot[*input] == 0.0 {
                    qddot[*output] / qddot[*input]
                } else {
                    qdot[*output] / qdot[*input]
                }
            }
            MeasureKind::PressureAngle(cam) => cam.pressure_angle(q, qdot),
            MeasureKind::MechanicalAdvantage { input, output } => {
                -output.value(q, qdot, reactions, t) / input.value(q, qdot, reactions, t)
            }
        }
    }

    /// Whether it reads anything besides the motion (reactions, efforts, forces).
    pub(crate) fn reads_beyond_motion(&self) -> bool {
        !self.reads().is_empty()
    }

    /// What it reads besides the motion, each with the field of its entry that names it (`""`:
    /// the entry itself).
    fn reads(&self) -> Vec<(&'static str, Reads)> {
        let effort = |field, e: &Effort| match e {
            Effort::Driver { slot } => (field, Reads::Reaction(*slot)),
            Effort::Torque { force, .. } => (field, Reads::Force(*force)),
        };
        match &self.kind {
            MeasureKind::Expression(e) => e.reactions().map(|k| ("", Reads::Reaction(k))).collect(),
            MeasureKind::MechanicalAdvantage { input, output } => {
                vec![effort(".input", input), effort(".output", output)]
            }
            _ => Vec::new(),
        }
    }
}

/// A named analysis, resolved.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// Name in the model file.
    pub name: String,
    /// What to compute.
    pub kind: AnalysisKind,
    /// Indices into [`Model::drivers`] of the active drivers.
    pub drivers: Vec<usize>,
    /// Indices into [`Model::forces`] of the active forces (a dynamic analysis applies only
    /// these).
    pub forces: Vec<usize>,
    /// Start time, s.
    pub t_start: f64,
    /// End time, s.
    pub t_end: f64,
    /// Output step, s.
    pub step: f64,
    /// Position solver settings.
    pub settings: SolverSettings,
    /// Integrator settings (dynamic analyses).
    pub integrator: IntegratorSettings,
    /// Where a modes analysis linearises.
    pub about: spec::LinearisePoint,
    /// The result columns kept (`None`: all), their bodies and joints known to the model.
    pub outputs: Option<spec::OutputsSpec>,
}

/// A compiled mechanism: bodies with coordinate offsets, constraints built, names resolved.
#[derive(Debug)]
pub struct Model {
    /// Title.
    pub name: String,
    /// Moving bodies; `n = 3 * bodies.len()` coordinates.
    pub bodies: Vec<Body>,
    /// Joints (always active).
    pub joints: Vec<Element>,
    /// Drivers (active per analysis).
    pub drivers: Vec<Element>,
    /// Gravitational acceleration, m/s^2.
    pub gravity: [f64; 2],
    /// Applied forces and force elements.
    pub forces: Vec<ForceElement>,
    /// Named outputs.
    pub measures: Vec<Measure>,
    /// The points whose paths the report draws: the file's `paths:`, else the points of its
    /// point measures (each once), in file order.
    pub paths: Vec<PathPoint>,
    /// Whole-run quantities by name, evaluated after a run (`Results`' summary, `summaries`).
    pub summaries: IndexMap<String, Functional>,
    /// Analyses by name, in file order.
    pub analyses: IndexMap<String, Analysis>,
    /// The text of the model file it was compiled from (empty for a model compiled from a
    /// spec): what an output folder keeps as `model.yaml`, to reproduce the run.
    pub source: String,
    /// The folder a table's `file:` is relative to: the model file's (empty, the working
    /// folder, for a model compiled from text).
    pub folder: PathBuf,
    /// Each table's `file:` as written, relative to [`Model::folder`] or absolute, in file order.
    pub table_files: Vec<String>,
    /// The parameters' values used, SI, in file order (the file's, with [`Model::set`] over them).
    pub parameters: IndexMap<String, f64>,
    /// The unit the file writes each parameter in, for those it writes with one (`r: mm` for
    /// `r: 100 mm`): what a value given from outside is shown in.
    pub parameter_units: IndexMap<String, String>,
    /// The tolerance of each parameter the file gives one (`r: 150 mm ± 0.1 mm`), in file
    /// order; a value given from outside keeps the file's tolerance.
    pub tolerances: IndexMap<String, Tolerance>,
    /// The units results are shown in (the file's `display:` section; SI without one).
    pub display: units::Display,
    /// Warnings about the parameter values given from outside ([`Model::set`]): a bare number
    /// far from the value the file writes with a unit, each `parameters.<name>: ...`.
    pub warnings: Vec<String>,
    /// Parameter values given from outside (`--set`, [`Model::with_parameters`]) over the file's:
    /// `(name, text)`, the text a bare number (SI) or a number with a unit.
    pub set: Vec<(String, String)>,
    /// What was placed from global coordinates or from other points, in body frames: each point
    /// of a body's `points_global` or placed from others (`bodies.<body>.points.<point>`), each
    /// of ground's placed from others (`ground.points.<point>`, global), and each joint point and
    /// axis given by `at` and `axis` (`joints.<joint>.point_i`, `.axis_j`, ...), in file order.
    pub placed: IndexMap<String, [f64; 2]>,
    /// The declared assembly modes (`branches:`): each dyad, by its middle pin, and its side.
    pub branches: Vec<(structure::Dyad, spec::Side)>,
    /// How assembly treats the drawing's branches (`branch:`).
    pub branch_mode: spec::BranchMode,
    /// The derivatives of the model's numbers with respect to its parameters, which design
    /// sensitivities seed the elements with (docs/sensitivities.md).
    pub gradients: DataGradients,
}

/// The text of the model file at `path`: a regular file (a device such as `/dev/zero`, or a
/// FIFO, which would be read without end or wait for a writer, is refused before it is opened) of
/// at most [`parse::MAX_MODEL_BYTES`], read no further than that (a file that grows while it is
/// read included).
fn read_model_file(path: &Path) -> Result<String> {
    use std::io::Read;
    let fail = |message: String| Error::Io { path: path.display().to_string(), message };
    let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
    if !meta.is_file() {
        let what = if meta.is_dir() { "a folder" } else { "not a regular file (a device, a FIFO or a socket)" };
        return Err(fail(format!("{what}; expected a model file (YAML)")));
    }
    let too_large = |size: String| fail(format!("{size}; {}", parse::LIMIT));
    if meta.len() > parse::MAX_MODEL_BYTES {
        return Err(too_large(parse::size(meta.len())));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(parse::MAX_MODEL_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| fail(e.to_string()))?;
    if bytes.len() as u64 > parse::MAX_MODEL_BYTES {
        return Err(too_large(format!("more than {} (it grew while read)", parse::size(parse::MAX_MODEL_BYTES))));
    }
    String::from_utf8(bytes).map_err(|_| fail("stream did not contain valid UTF-8".into()))
}

impl Model {
    /// Read and compile a model file.
    pub fn load(path: impl AsRef<Path>) -> Result<Model> {
        Model::load_with(path, &[])
    }

    /// Read and compile a model file with parameter values given from outside, as
    /// [`Model::from_yaml_with`].
    pub fn load_with(path: impl AsRef<Path>, set: &[(String, String)]) -> Result<Model> {
        let path = path.as_ref();
        let text = read_model_file(path)?;
        // The folder made absolute, so that a model sent to another process (a Dask worker, in
        // another working folder) still finds its tables' files.
        let folder = path.parent().unwrap_or(Path::new(""));
        let folder = std::fs::canonicalize(if folder.as_os_str().is_empty() { Path::new(".") } else { folder })
            .unwrap_or_else(|_| folder.to_path_buf());
        Model::from_yaml_in(&text, set, folder)
    }

    /// Compile a model from the text of a model file.
    pub fn from_yaml(text: &str) -> Result<Model> {
        Model::from_yaml_with(text, &[])
    }

    /// Compile a model from the text of a model file with parameter values given from outside,
    /// `(name, text)`: a bare number is SI whatever unit the file used; a number with a unit is
    /// converted and must have the dimension of the file's value. A name the file's `parameters:`
    /// does not define is a model error at `parameters.<name>`.
    pub fn from_yaml_with(text: &str, set: &[(String, String)]) -> Result<Model> {
        Model::from_yaml_in(text, set, PathBuf::new())
    }

    /// As [`Model::from_yaml_with`], for the text of a model file in `folder`: a table's
    /// `file:` is read from there ([`Model::load_with`] gives the file's folder).
    pub fn from_yaml_in(text: &str, set: &[(String, String)], folder: impl Into<PathBuf>) -> Result<Model> {
        Model::from_document(text, parse::parse_document(text).map_err(Error::Model)?, set, folder.into())
    }

    /// The model of `text`, whose YAML document is `document`, with the values `set`.
    fn from_document(
        text: &str,
        document: serde_yaml_ng::Value,
        set: &[(String, String)],
        folder: PathBuf,
    ) -> Result<Model> {
        let parsed = parse::parse_document_with(document, set).map_err(Error::Model)?;
        match compile_partial(&parsed.spec, &parsed.broken, &folder) {
            Ok(model) if parsed.problems.is_empty() => {
                let (parameter_units, warnings, tolerances) =
                    (parsed.parameter_units, parsed.warnings, parsed.tolerances);
                let source = text.to_string();
                Ok(Model { source, set: set.to_vec(), folder, parameter_units, warnings, tolerances, ..model })
            }
            Ok(_) => Err(Error::Model(parsed.problems)),
            // A problem the reading already reported is not reported again by the compilation
            // (a missing `bodies:` section is also an empty one).
            Err(more) => {
                let again = |p: &crate::error::Problem| {
                    parsed.problems.iter().any(|r| r.path == p.path && r.message.contains(&p.message))
                };
                let more: Vec<_> = more.into_iter().filter(|p| !again(p)).collect();
                Err(Error::Model(parsed.problems.into_iter().chain(more).collect()))
            }
        }
    }

    /// The same model file with `values` given over this model's parameters (as
    /// [`Model::from_yaml_with`]; values given before and not named again stay). Parameters
    /// computed from others follow them.
    pub fn with_parameters(&self, values: &[(String, String)]) -> Result<Model> {
        let document = parse::parse_document(&self.source).map_err(Error::Model)?;
        Model::from_document(&self.source, document, &self.given_with(values), self.folder.clone())
    }

    /// As [`Model::with_parameters`], with this model's text already parsed into `document`
    /// ([`Model::document`]): a sweep parses the text once, not once a variant.
    pub(crate) fn with_parameters_in(
        &self,
        document: &serde_yaml_ng::Value,
        values: &[(String, String)],
    ) -> Result<Model> {
        Model::from_document(&self.source, document.clone(), &self.given_with(values), self.folder.clone())
    }

    /// The YAML document of this model's text, for [`Model::with_parameters_in`].
    pub(crate) fn document(&self) -> Result<serde_yaml_ng::Value> {
        parse::parse_document(&self.source).map_err(Error::Model)
    }

    /// The values given over the file's: this model's, with `values` over them.
    fn given_with(&self, values: &[(String, String)]) -> Vec<(String, String)> {
        let mut set: Vec<(String, String)> =
            self.set.iter().filter(|(n, _)| !values.iter().any(|(m, _)| m == n)).cloned().collect();
        set.extend(values.iter().cloned());
        set
    }

    /// Number of coordinates, `3 * bodies`.
    pub fn n(&self) -> usize {
        3 * self.bodies.len()
    }

    /// The initial guess of positions, `(n)`.
    pub fn q0(&self) -> Vec<f64> {
        self.bodies.iter().flat_map(|b| b.q0).collect()
    }

    /// The initial guess of velocities, `(n)`.
    pub fn qdot0(&self) -> Vec<f64> {
        self.bodies.iter().flat_map(|b| b.v0).collect()
    }

    /// The analysis called `name`, or a model error listing the ones there are.
    pub fn analysis(&self, name: &str) -> Result<&Analysis> {
        self.analyses.get(name).ok_or_else(|| {
            let known: Vec<&str> = self.analyses.keys().map(String::as_str).collect();
            let list = if known.is_empty() {
                "the model names no analyses".to_string()
            } else {
                format!("the model has: {}", known.join(", "))
            };
            Error::Model(vec![crate::error::Problem::new(
                format!("analyses.{name}"),
                format!("no analysis named '{name}'; {list}"),
            )])
        })
    }

    /// The JSON Schema of model files. Every number may also be written as a string (a number
    /// with a unit or an expression of parameters, read by `params`), which the Rust types, holding
    /// the numbers read, do not say: the schema's numeric types are widened here, in one place.
    pub fn json_schema() -> String {
        fn widen(v: &mut serde_json::Value) {
            match v {
                serde_json::Value::Object(map) => {
                    let numeric = |t: &serde_json::Value| matches!(t.as_str(), Some("number" | "integer"));
                    match map.get_mut("type") {
                        Some(t) if numeric(t) => *t = serde_json::json!([t.clone(), "string"]),
                        Some(serde_json::Value::Array(types)) if types.iter().any(numeric) => {
                            types.push("string".into())
                        }
                        _ => {}
                    }
                    map.values_mut().for_each(widen);
                }
                serde_json::Value::Array(items) => items.iter_mut().for_each(widen),
                _ => {}
            }
        }
        let mut schema = serde_json::to_value(schemars::schema_for!(spec::ModelSpec)).expect("a schema is JSON");
        widen(&mut schema);
        serde_json::to_string_pretty(&schema).expect("a JSON Schema always serializes")
    }
}
