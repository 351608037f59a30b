//! The model file schema: plain serde types, one per section, mirrored by the JSON Schema that
//! `linkwork schema` prints. Units are SI and angles radians throughout. Validation beyond types
//! (names that must exist, finite numbers, non-zero axes) lives in `validate.rs`.

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
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
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
    /// Analyses by name.
    #[serde(default)]
    pub analyses: IndexMap<String, AnalysisSpec>,
}

/// The fixed body.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Named points in the global frame, m.
    #[serde(default)]
    pub points: IndexMap<String, [f64; 2]>,
}

/// A rigid body. Its frame's origin is its centre of mass.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Mass, kg.
    pub mass: f64,
    /// Moment of inertia about the centre of mass, kg m^2.
    pub inertia: f64,
    /// Initial (guessed) position of the centre of mass, m, global frame.
    pub position: [f64; 2],
    /// Initial (guessed) angle of the body frame, rad.
    pub angle: f64,
    /// Initial velocity of the centre of mass, m/s. Default: zero.
    #[serde(default)]
    pub velocity: [f64; 2],
    /// Initial angular velocity, rad/s. Default: zero.
    #[serde(default)]
    pub omega: f64,
    /// Named points in the body frame, m, for joints and drawing.
    #[serde(default)]
    pub points: IndexMap<String, [f64; 2]>,
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

/// A point of a body: its coordinates `[x, y]` in the body frame, m, or the name of one of the
/// body's `points`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum PointRef {
    /// Coordinates in the body frame.
    Coords([f64; 2]),
    /// A named point of the body.
    Name(String),
}

impl Default for PointRef {
    fn default() -> Self {
        PointRef::Coords([0.0, 0.0])
    }
}

/// A joint between two bodies (or a body and `ground`), or a general constraint. The first body
/// (`body_i`) is the one whose reaction is reported.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum JointSpec {
    /// Pin: `point_i` of `body_i` coincides with `point_j` of `body_j`. 2 equations.
    Revolute {
        /// First body.
        body_i: String,
        /// Pin location on the first body.
        point_i: PointRef,
        /// Second body.
        body_j: String,
        /// Pin location on the second body.
        point_j: PointRef,
    },
    /// Prismatic: `point_j` of `body_j` slides on the line of `body_i` through `point_i` along
    /// `axis_i`, and the bodies keep the relative angle that makes `axis_i` and `axis_j` parallel.
    /// 2 equations.
    Translational {
        /// Body carrying the line.
        body_i: String,
        /// A point of the line, body i frame.
        point_i: PointRef,
        /// Direction of the line, body i frame (any non-zero length).
        axis_i: [f64; 2],
        /// The sliding body.
        body_j: String,
        /// The point of body j that stays on the line.
        point_j: PointRef,
        /// Direction in body j that stays parallel to `axis_i`.
        axis_j: [f64; 2],
    },
    /// Pin in slot: `point_j` of `body_j` stays on the line of `body_i` through `point_i` along
    /// `axis_i`; rotation stays free. 1 equation.
    PointOnLine {
        /// Body carrying the slot (line).
        body_i: String,
        /// A point of the line, body i frame.
        point_i: PointRef,
        /// Direction of the line, body i frame.
        axis_i: [f64; 2],
        /// Body carrying the pin.
        body_j: String,
        /// The pin, body j frame.
        point_j: PointRef,
    },
    /// Revolute-translational composite: `point_j` of `body_j` keeps a constant signed distance
    /// `offset` from the line of `body_i` (a link pinned at `point_j` and sliding, at right angles,
    /// on the line). 1 equation.
    RevoluteTranslational {
        /// Body carrying the line.
        body_i: String,
        /// A point of the line, body i frame.
        point_i: PointRef,
        /// Direction of the line, body i frame.
        axis_i: [f64; 2],
        /// Body carrying the pin.
        body_j: String,
        /// The pin, body j frame.
        point_j: PointRef,
        /// Signed distance from the line to the pin (positive to the left of `axis_i`), m.
        /// Default: its value in the initial configuration.
        #[serde(default)]
        offset: Option<f64>,
    },
    /// Distance (revolute-revolute link): the two points stay `length` apart. 1 equation.
    Distance {
        /// First body.
        body_i: String,
        /// Point on the first body.
        point_i: PointRef,
        /// Second body.
        body_j: String,
        /// Point on the second body.
        point_j: PointRef,
        /// Distance, m. Default: its value in the initial configuration.
        #[serde(default)]
        length: Option<f64>,
    },
    /// Absolute x of a body point is constant. 1 equation.
    AbsoluteX {
        /// The body.
        body: String,
        /// The point (default: the centre of mass).
        #[serde(default)]
        point: PointRef,
        /// The x value, m. Default: its value in the initial configuration.
        #[serde(default)]
        value: Option<f64>,
    },
    /// Absolute y of a body point is constant. 1 equation.
    AbsoluteY {
        /// The body.
        body: String,
        /// The point (default: the centre of mass).
        #[serde(default)]
        point: PointRef,
        /// The y value, m. Default: its value in the initial configuration.
        #[serde(default)]
        value: Option<f64>,
    },
    /// Absolute angle of a body is constant. 1 equation.
    AbsoluteAngle {
        /// The body.
        body: String,
        /// The angle, rad. Default: its value in the initial configuration.
        #[serde(default)]
        value: Option<f64>,
    },
    /// Gear pair: pitch circles of radius `radius_i` and `radius_j` about `point_i` and `point_j`
    /// roll without slip. The centre distance must be kept by other joints. 1 equation.
    Gear {
        /// First gear.
        body_i: String,
        /// Centre of the first gear, body i frame.
        point_i: PointRef,
        /// Pitch radius of the first gear, m.
        radius_i: f64,
        /// Second gear (the ring when `internal`).
        body_j: String,
        /// Centre of the second gear, body j frame.
        point_j: PointRef,
        /// Pitch radius of the second gear, m.
        radius_j: f64,
        /// True when gear j is an internal (ring) gear with gear i inside it. Default: false.
        #[serde(default)]
        internal: bool,
    },
    /// Rack and pinion: the pinion's pitch circle (centre `point_i`, `radius`) rolls without slip
    /// on the rack's pitch line through `point_j` along `axis_j`. The centre-to-line distance must
    /// be kept by other joints. 1 equation.
    RackPinion {
        /// The pinion.
        body_i: String,
        /// Centre of the pinion, body i frame.
        point_i: PointRef,
        /// Pitch radius, m.
        radius: f64,
        /// The rack.
        body_j: String,
        /// A point of the pitch line, body j frame.
        point_j: PointRef,
        /// Direction of the pitch line, body j frame.
        axis_j: [f64; 2],
    },
    /// A disc (centre `point_i`, `radius`) rolling without slip on the line of `body_j` through
    /// `point_j` along `axis_j`: contact and no slip. 2 equations.
    RollingDisc {
        /// The disc.
        body_i: String,
        /// Centre of the disc, body i frame.
        point_i: PointRef,
        /// Radius, m.
        radius: f64,
        /// The body carrying the line.
        body_j: String,
        /// A point of the line, body j frame.
        point_j: PointRef,
        /// Direction of the line, body j frame.
        axis_j: [f64; 2],
    },
    /// A general constraint `expression = 0` in body coordinates (`crank.x`, `crank.y`,
    /// `crank.phi`) and time `t`, differentiated exactly. 1 equation.
    Expression {
        /// The left-hand side, e.g. `"crank.x^2 + crank.y^2 - 0.5625"`.
        expression: String,
    },
}

/// A prescribed motion: a coordinate of the mechanism equals `function` of time `t` (an
/// expression such as `"6.1506 + 2*pi*t"`; its derivatives are exact).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum DriverSpec {
    /// Angle of `body`, rad.
    Angle {
        /// The driven body.
        body: String,
        /// Angle as a function of `t`, rad.
        function: String,
    },
    /// Angle of `body_i` minus angle of `body_j`, rad.
    RelativeAngle {
        /// First body.
        body_i: String,
        /// Second body.
        body_j: String,
        /// Relative angle as a function of `t`, rad.
        function: String,
    },
    /// Distance between two points, m.
    Distance {
        /// First body.
        body_i: String,
        /// Point on the first body.
        point_i: PointRef,
        /// Second body.
        body_j: String,
        /// Point on the second body.
        point_j: PointRef,
        /// Distance as a function of `t`, m (must stay positive).
        function: String,
    },
    /// Global x of a body point, m.
    X {
        /// The body.
        body: String,
        /// The point (default: the centre of mass).
        #[serde(default)]
        point: PointRef,
        /// x as a function of `t`, m.
        function: String,
    },
    /// Global y of a body point, m.
    Y {
        /// The body.
        body: String,
        /// The point (default: the centre of mass).
        #[serde(default)]
        point: PointRef,
        /// y as a function of `t`, m.
        function: String,
    },
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
    /// Start time, s. Default: 0.
    #[serde(default)]
    pub t_start: f64,
    /// End time, s.
    pub t_end: f64,
    /// Output step, s.
    pub step: f64,
    /// Solver settings; every field has a default.
    #[serde(default)]
    pub solver: SolverSpec,
}

/// Kinds of analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisKind {
    /// Position, velocity and acceleration of a fully driven mechanism.
    Kinematic,
}

/// Settings of the position solver (assembly and kinematics). Defaults and their reasons are in
/// `docs/kinematics.md` and on [`crate::analysis::SolverSettings`].
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
}
