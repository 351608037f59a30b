//! The model file schema: plain serde types, one per section, mirrored by the JSON Schema that
//! `linkwork schema` prints. Units are SI and angles radians throughout. Each joint's fields are
//! its module's, in `constraints` ([`JointSpec`] lists them), and each force element's its
//! module's in `forces` ([`ForceSpec`]); checks beyond types (names that
//! must exist, finite numbers, non-zero axes) are the compiler's (`compile`) and the elements' compile steps.

pub use crate::constraints::{
    AbsoluteAngleJoint, AbsolutePoint, AngleDriver, CamJoint, CamProfileSpec, DistanceDriver, DistanceJoint,
    DriverSpec, ExpressionJoint, GearJoint, JointSpec, PinFriction, PointDriver, PointOnLineJoint, PointRef,
    ProfileColumn, RelativeAngleDriver, RevoluteJoint, RevoluteTranslationalJoint, RollingJoint, SlideFriction, Tagged,
    TranslationalJoint,
};
use crate::element::{named, pair};
pub use crate::forces::{
    CircleShape, ContactFriction, ContactSpec, ForceFrame, ForceSpec, PointForce, Quantity, RotationalSpringDamperSpec,
    ShapeSpec, SpringDamperSpec, TorqueSpec,
};
use indexmap::IndexMap;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A planar mechanism: bodies, the joints and drivers between them, and the analyses to run.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// A title for reports.
    #[serde(default)]
    pub name: Option<String>,
    /// Named values, in order: a number (SI), a number with a unit (`"140 mm"`), or an expression
    /// of the parameters before it. Every numeric field may be written as an expression of them,
    /// and expressions of time and the state may use them. A parameter may carry a tolerance:
    /// `{value: 150 mm, tolerance: 0.1 mm, distribution: normal}` or `150 mm ± 0.1 mm`. After
    /// reading: the SI values.
    #[serde(default)]
    #[schemars(schema_with = "super::params::written_schema")]
    pub parameters: IndexMap<String, f64>,
    /// The derivatives of the parameters and of the fields written as expressions of them with
    /// respect to each parameter, found when the file is read (empty for a spec built otherwise,
    /// whose numbers then have no derivatives); not a field of model files.
    #[serde(skip)]
    #[schemars(skip)]
    pub(crate) gradients: super::params::Gradients,
    /// The units results are shown in (the command line's output, the report, `Results.plot`),
    /// by quantity: `{length: mm, angle: deg, force: N, torque: N m}`; the quantities are
    /// `length`, `angle`, `time`, `velocity`, `angular_velocity`, `acceleration`,
    /// `angular_acceleration`, `force`, `torque`, `energy`, `power` and `mass`. A velocity or an
    /// acceleration not named follows the length (angle) and time shown (`mm/s`). Files stay SI
    /// (`linkwork run --units display` writes `results.csv` in these units).
    #[serde(default)]
    pub display: IndexMap<String, String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Gravitational acceleration `[gx, gy]`, m/s^2, acting on every body's centre of mass.
    /// Default: none (`[0, 0]`).
    #[serde(default)]
    pub gravity: Option<[f64; 2]>,
    /// The fixed body `ground`: named points only (its frame is the global frame).
    #[serde(default)]
    pub ground: Option<GroundSpec>,
    /// Moving bodies by name. `ground` is the fixed body and is not listed here.
    pub bodies: IndexMap<String, BodySpec>,
    /// Joints (kinematic constraints) by name.
    #[serde(default)]
    pub joints: IndexMap<String, JointSpec>,
    /// Drivers (prescribed motions) by name; each analysis chooses which are active.
    #[serde(default)]
    pub drivers: IndexMap<String, DriverSpec>,
    /// Applied forces and force elements by name.
    #[serde(default)]
    pub forces: IndexMap<String, ForceSpec>,
    /// Named output quantities, written as extra columns of `results.csv`.
    #[serde(default)]
    pub measures: IndexMap<String, MeasureSpec>,
    /// The points whose paths the report draws (solid, on the mechanism and in a panel of their
    /// own), in order: `<body>.<point>` (a named point of a moving body) or `<body>` (its centre
    /// of mass). Default: the points of the point measures.
    #[serde(default)]
    pub paths: Vec<String>,
    /// Whole-run quantities by name, each one number written to `summary.json` under
    /// `summaries`: an expression of aggregations of the result columns over the run
    /// (`integral`, `mean`, `rms`, `min`, `max`, `peak`, `initial`, `final`, `at(time, f)`) and
    /// of parameters, such as `"integral(pump_power) / integral(motor_power)"`
    /// (docs/model-format.md, "Summaries").
    #[serde(default)]
    pub summaries: IndexMap<String, String>,
    /// Tabulated functions by name, for `spline(<name>, x)` in any expression.
    #[serde(default)]
    pub tables: IndexMap<String, TableSpec>,
    /// Assembly modes by joint: `{F: {line: [E, D], side: right}}` puts the pin `F` to the right
    /// of the directed line from joint `E` to joint `D`, whatever side the drawing puts it on
    /// (docs/model-format.md, "Branches").
    #[serde(default)]
    pub branches: IndexMap<String, BranchSpec>,
    /// How a disagreement between the drawing and the assembled branch is treated: `follow`
    /// (default: the drawing's side is kept, a declared one over it with a warning) or `strict`
    /// (every disagreement is an assembly error).
    #[serde(default)]
    pub branch: Option<BranchMode>,
    /// Analyses by name.
    #[serde(default)]
    pub analyses: IndexMap<String, AnalysisSpec>,
}

/// The assembly mode of the dyad whose middle pin is the entry's joint.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BranchSpec {
    /// The dyad's end joints `[E, D]`, each a pin of one of the two bodies the middle joint
    /// joins: the directed line from `E` to `D`.
    pub line: [String; 2],
    /// The side of that line the middle joint lies on, looking from `E` to `D`.
    pub side: Side,
}

named! {
    /// A side of a directed line, looking along it.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
    pub enum Side {
        /// To the left (counter-clockwise of the direction).
        "left" => Left,
        /// To the right.
        "right" => Right,
    }
}

named! {
    /// How assembly treats the drawing's branches (`branch:` in the model file).
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
    pub enum BranchMode {
        /// Keep each dyad on the side the drawing puts it, or the declared side, with a warning
        /// when the two disagree.
        #[default]
        "follow" => Follow,
        /// Every disagreement between the drawing, a declared side and the assembled pose is an
        /// assembly error.
        "strict" => Strict,
    }
}

/// A named output: an expression of time and state (`"slider_d.x + 4"`; besides positions and
/// velocities it may use accelerations `<body>.ax, .ay, .alpha`, and where the analysis has them
/// the reactions `<joint>.fx, .fy, .torque` and efforts `<driver>.effort`), a component of a body
/// point, or a standard quantity of mechanism design named by its `type`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum MeasureSpec {
    /// An expression.
    Expression(String),
    /// A component of a point of a body.
    Point(PointMeasure),
    /// A standard quantity: transmission angle, velocity ratio, mechanical advantage.
    Standard(StandardMeasure),
}

named! {
    tagged
    /// The standard quantities of mechanism design, each named by its `type`
    /// (docs/model-format.md, "Measures").
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(tag = "type")]
    pub enum StandardMeasure {
        /// The transmission angle `mu` at a pin between a coupler and an output link (rocker):
        /// the acute angle between the coupler's line and the rocker's line, in `[0, pi/2]` rad,
        /// as R. L. Norton defines it (Design of Machinery: `|theta3 - theta4|`, folded to
        /// `pi - mu` when obtuse).
        "transmission_angle" => TransmissionAngle(TransmissionAngleMeasure),
        /// `omega_output / omega_input`, the angular velocity ratio of two bodies.
        "velocity_ratio" => VelocityRatio(VelocityRatioMeasure),
        /// `-F_output / F_input`: the load at the output over the effort at the input, each the
        /// torque (or force) applied to the mechanism there; `omega_input / omega_output` in a
        /// frictionless, massless mechanism.
        "mechanical_advantage" => MechanicalAdvantage(MechanicalAdvantageMeasure),
        /// The pressure angle of a cam joint with a radial follower (one that moves along the
        /// line through the cam's centre): the angle between the contact normal (the pitch
        /// curve's normal at the follower's point) and that line, rad, positive while the cam
        /// pushes the follower outward; `atan(sigma R'(psi) / R(psi))` with
        /// `sigma = sign(dpsi/dt)` on a polar pitch curve.
        "pressure_angle" => PressureAngle(PressureAngleMeasure),
    }
}

/// The transmission angle at the pin `joint` between a coupler and a rocker: the coupler's line
/// runs from `joint` to its other pin `coupler_joint`, the rocker's from `joint` to its other pin
/// `rocker_joint` (its pivot). All three are revolute joints; the coupler is the body `joint`
/// shares with `coupler_joint`, the rocker the body it shares with `rocker_joint`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransmissionAngleMeasure {
    /// The revolute joint between the coupler and the rocker.
    pub joint: String,
    /// The coupler's other revolute joint (to the crank, the input).
    pub coupler_joint: String,
    /// The rocker's other revolute joint (its pivot, usually on ground).
    pub rocker_joint: String,
}

/// `omega_output / omega_input`, rad/s over rad/s.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VelocityRatioMeasure {
    /// The input body (a crank).
    pub input: String,
    /// The output body (a rocker).
    pub output: String,
}

/// `-F_output / F_input`: each the name of a driver (its effort) or of a `torque` force (its
/// torque), the torque or force applied to the mechanism at the input and at the output.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MechanicalAdvantageMeasure {
    /// The input: a driver or a `torque` force.
    pub input: String,
    /// The output (the load): a driver or a `torque` force.
    pub output: String,
}

/// The pressure angle of the cam joint `joint` with a radial follower.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PressureAngleMeasure {
    /// The cam joint.
    pub joint: String,
}

/// A tabulated function `y(x)`, interpolated by a piecewise cubic with exact derivatives
/// (docs/model-format.md, "Tables"): the points inline, or two columns of a CSV file.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// A CSV file whose first row names its columns, relative to the model file's folder (the
    /// working folder for a model given as text). With it, `x` and `y` are column names.
    #[serde(default)]
    pub file: Option<String>,
    /// The abscissae, strictly increasing (or, with `file`, the name of their column).
    pub x: TableColumn,
    /// The values (or, with `file`, the name of their column).
    pub y: TableColumn,
    /// How the points are joined. Default `not_a_knot`.
    #[serde(default)]
    pub method: SplineMethod,
}

/// A table's column: its numbers, or the name of a column of the table's file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "a list of plain numbers (SI, without units or parameters), or the name of a column of the table's file"
)]
pub enum TableColumn {
    /// The numbers.
    Values(Vec<f64>),
    /// A column of the file, by the name in its first row.
    Column(String),
}

/// How a table's points are joined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SplineMethod {
    /// The cubic spline with not-a-knot ends: continuous second derivative; a straight line
    /// continues each end.
    #[default]
    NotAKnot,
    /// The periodic cubic spline (the first and last values equal): repeats outside the table.
    Periodic,
    /// Akima's piecewise cubic (Adams' AKISPL): no overshoot at corners; continuous first
    /// derivative only.
    Akima,
}

/// A component of a point of a body, global frame.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PointMeasure {
    /// The body.
    pub body: String,
    /// The point (default: the centre of mass).
    #[serde(default)]
    pub point: PointRef,
    /// Which component.
    pub component: PointComponent,
}

/// A component of a point's position, velocity or acceleration, global frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PointComponent {
    /// x, m.
    X,
    /// y, m.
    Y,
    /// x-velocity, m/s.
    Vx,
    /// y-velocity, m/s.
    Vy,
    /// x-acceleration, m/s^2.
    Ax,
    /// y-acceleration, m/s^2.
    Ay,
}

/// The fixed body.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Named points in the global frame, m: `[x, y]`, or placed by their distances to two other
    /// points.
    #[serde(default)]
    pub points: IndexMap<String, PointSpec>,
}

/// A rigid body. Its frame's origin is its centre of mass.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Mass, kg.
    pub mass: f64,
    /// Moment of inertia about the centre of mass, kg m^2.
    pub inertia: f64,
    /// Initial (guessed) position of the centre of mass, m, global frame: `[x, y]`, or the name of
    /// one of `points_global`.
    pub position: PointRef,
    /// Initial (guessed) angle of the body frame, rad. Default: 0, the body frame parallel to the
    /// global one.
    #[serde(default)]
    pub angle: f64,
    /// Initial velocity of the centre of mass, m/s. Default: zero.
    #[serde(default)]
    pub velocity: [f64; 2],
    /// Initial angular velocity, rad/s. Default: zero.
    #[serde(default)]
    pub omega: f64,
    /// Named points in the body frame, m, for joints and drawing: `[x, y]`, or placed by their
    /// distances to two other points.
    #[serde(default)]
    pub points: IndexMap<String, PointSpec>,
    /// Named points in the global frame at the initial position, m, as a drawing gives them:
    /// each becomes a body-frame point through `position` and `angle`. `[x, y]`, or placed by
    /// their distances to two other points.
    #[serde(default)]
    pub points_global: IndexMap<String, PointSpec>,
    /// Initial values that assembly must keep (for example `[phi, omega]` for a crank whose angle
    /// and speed are known); the others may change. Default: none.
    #[serde(default)]
    pub given: Vec<Given>,
}

/// A body coordinate or velocity that assembly holds at its initial value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Given {
    /// x of the centre of mass.
    X,
    /// y of the centre of mass.
    Y,
    /// Angle of the body.
    Phi,
    /// x-velocity of the centre of mass.
    Vx,
    /// y-velocity of the centre of mass.
    Vy,
    /// Angular velocity.
    Omega,
}

/// A named point: its coordinates `[x, y]`, m (in the frame of the section that lists it), the
/// place of another body's point (`body.B`), or its place by its distances to two other points
/// (docs/model-format.md, "Points placed by lengths").
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum PointSpec {
    /// Coordinates.
    Coords([f64; 2]),
    /// Where another point is at the initial position: `body.B` (a point of another body or of
    /// `ground`), or `B`, another point of the same body.
    At(String),
    /// By its distances to two other points.
    Lengths(ByLengths),
}

/// Read by hand, as [`PointRef`] is, so that a bad field keeps its path.
impl<'de> Deserialize<'de> for PointSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = PointSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a point: [x, y], body.B (where that point is), or {from: [B, C], distances: [d, e], side: left or right}")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<PointSpec, E> {
                Ok(PointSpec::At(v.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<PointSpec, A::Error> {
                pair(seq, &self).map(PointSpec::Coords)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<PointSpec, A::Error> {
                ByLengths::deserialize(serde::de::value::MapAccessDeserializer::new(map)).map(PointSpec::Lengths)
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// A point placed by its distances to two other points, on one side of the line through them:
/// the third corner of the triangle whose sides are the two distances and the distance between
/// the two points, where the drawing puts them at the initial position.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ByLengths {
    /// The two points, B and C: `B`, a point of the same body (or of ground, for a point of
    /// ground), or `body.B`, a point of another body or of `ground`.
    pub from: [String; 2],
    /// The point's distances to B and to C, m (> 0).
    pub distances: [f64; 2],
    /// The side of the directed line from B to C the point lies on, looking from B towards C.
    pub side: Side,
}

/// An analysis of the model.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSpec {
    /// What to compute.
    #[serde(rename = "type")]
    pub kind: AnalysisKind,
    /// Names of the drivers active in this analysis. Default: every driver of the model.
    #[serde(default)]
    pub drivers: Option<Vec<String>>,
    /// Names of the forces (applied forces and force elements) that load the mechanism in this
    /// analysis. Default: every force of the model.
    #[serde(default)]
    pub forces: Option<Vec<String>>,
    /// Start time, s. Default: 0.
    #[serde(default)]
    pub t_start: f64,
    /// End time, s. Required, except for `static` (default: `t_start`, one equilibrium) and
    /// `modes` (which is at `t_start` and takes none).
    #[serde(default)]
    pub t_end: Option<f64>,
    /// Output step, s. Required with `t_end`; `modes` takes none.
    #[serde(default)]
    pub step: Option<f64>,
    /// Where `modes` linearises: `equilibrium` (default: the static equilibrium under the
    /// analysis's loads, found first) or `initial` (the assembled initial state).
    #[serde(default)]
    pub about: Option<LinearisePoint>,
    /// Integrator of a dynamic analysis. Default: bdf.
    #[serde(default)]
    pub integrator: Option<IntegratorKind>,
    /// Solver settings; every field has a default.
    #[serde(default)]
    pub solver: SolverSpec,
    /// The result columns to keep (default: all of them), for a large mechanism whose every
    /// column would fill memory and disk.
    #[serde(default)]
    pub outputs: Option<OutputsSpec>,
}

/// The result columns an analysis keeps: `time`, and only those named here.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputsSpec {
    /// Bodies whose nine columns (`x, y, phi, vx, vy, omega, ax, ay, alpha`) are kept.
    #[serde(default)]
    pub bodies: Vec<String>,
    /// Joints whose reaction columns (`fx, fy, torque`) are kept.
    #[serde(default)]
    pub joints: Vec<String>,
    /// Other columns kept, by name: `kinetic_energy`, `motor.effort`, a measure, `crank.phi`.
    #[serde(default)]
    pub columns: Vec<String>,
}

named! {
    /// The integrators of dynamic analyses (`docs/integrators.md`).
    #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
    pub enum IntegratorKind {
        /// Variable-order (1 to 6), variable-step BDF on the stabilised index-2 equations (or the
        /// index-3 ones), as Adams GSTIFF and DASSL.
        #[default]
        "bdf" => Bdf,
        /// HHT-alpha on the index-3 equations with step-size control (Negrut et al. 2007).
        "hht" => Hht,
        /// Coordinate partitioning with a variable-order, variable-step Adams-Bashforth-Moulton method
        /// on the independent coordinates (Wehage and Haug 1982), as Adams ABAM.
        "abam" => Abam,
    }
}

/// Which equations `bdf` discretises.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// The position constraints `Phi = 0` (index 3); the error test weights the velocities by the
    /// step, so they are not controlled.
    Index3,
    /// The velocity constraints with a position correction (stabilised index 2, GGL; Adams SI2);
    /// the error test includes the velocities. The default: the global error follows the
    /// tolerance (docs/integrators.md).
    #[default]
    Si2,
}

named! {
    /// Kinds of analysis.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
    pub enum AnalysisKind {
        /// Position, velocity and acceleration of a fully driven mechanism.
        "kinematic" => Kinematic,
        /// Motion under forces: the equations of motion integrated in time, with joint reactions.
        "dynamic" => Dynamic,
        /// Inverse dynamics (kinetostatics) of a fully driven mechanism: the kinematic motion, and
        /// the joint reactions and driver efforts it needs.
        "inverse" => Inverse,
        /// Static equilibrium under the loads, at `t_start` or, quasi-statically, at each output time
        /// of a slowly driven mechanism.
        "static" => Static,
        /// Linearisation about an equilibrium (or the initial state): natural frequencies, damping
        /// ratios and mode shapes.
        "modes" => Modes,
    }
}

/// The state a `modes` analysis linearises about.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LinearisePoint {
    /// The static equilibrium under the analysis's loads.
    #[default]
    Equilibrium,
    /// The assembled initial positions and velocities, as they are.
    Initial,
}

/// Settings of the position solver (assembly and kinematics). Defaults and their reasons are in
/// `docs/kinematics.md` and on [`crate::model::SolverSettings`].
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Newton convergence: max-norm of `Phi` (m or rad).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Newton iterations per attempt before the sub-step is halved.
    #[serde(default)]
    pub max_iterations: Option<usize>,
    /// Largest rotation of any body within one sub-step, rad.
    #[serde(default)]
    pub max_rotation: Option<f64>,
    /// Smallest sub-step as a fraction of the output step before giving up.
    #[serde(default)]
    pub min_substep: Option<f64>,
    /// Condition number of the driven Jacobian above which the position counts as singular.
    #[serde(default)]
    pub singular_condition: Option<f64>,
    /// Dynamics: relative error tolerance per step.
    #[serde(default)]
    pub rtol: Option<f64>,
    /// Dynamics: absolute error tolerance per step (m, rad, m/s, rad/s).
    #[serde(default)]
    pub atol: Option<f64>,
    /// Dynamics: first step, s.
    #[serde(default)]
    pub initial_step: Option<f64>,
    /// Dynamics: largest step, s.
    #[serde(default)]
    pub max_step: Option<f64>,
    /// Dynamics (`bdf`, `abam`): highest order.
    #[serde(default)]
    pub max_order: Option<usize>,
    /// Dynamics (`hht`): numerical damping `alpha`, in [-1/3, 0].
    #[serde(default)]
    pub alpha: Option<f64>,
    /// Dynamics (`bdf`): the equations discretised. Default: si2.
    #[serde(default)]
    pub formulation: Option<Formulation>,
}
