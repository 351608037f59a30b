//! The mechanism as a picture, for the report and notebooks: each body's points in its own frame
//! (its named points and every joint point on it), and each joint's [`Sketch`] with its bodies by
//! name, the points whose paths are drawn, and the coordinate each driver prescribes. The picture
//! at time `t` follows from the body coordinates of `results.csv`: `r_P = (x, y) + A(phi) s'_P`.
//! Ground's points are global.

use super::Model;
use crate::constraints::{BodyIx, DriverKind, Shape, Sketch};
use indexmap::IndexMap;
use serde::Serialize;

/// Everything needed to draw the mechanism in any pose.
#[derive(Debug, Clone, Serialize)]
pub struct Drawing {
    /// The moving bodies, in file order.
    pub bodies: Vec<BodyDrawing>,
    /// The joints with a picture, in file order.
    pub joints: Vec<JointDrawing>,
    /// The points whose paths are drawn ([`Model::paths`]).
    pub paths: Vec<PathPoint>,
    /// Each driver's coordinate, in file order.
    pub drivers: Vec<DriverDrawing>,
}

/// A point whose path the report draws: one of the model file's `paths:`, or by default a point
/// of a point measure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathPoint {
    /// `<body>.<point>`, `<body>` for its centre of mass, or `<body> [x, y]` for a point a
    /// measure gives by coordinates that no named point has.
    pub name: String,
    /// The moving body.
    pub body: String,
    /// The point, body frame, m.
    pub point: [f64; 2],
}

/// An element drawn between two bodies: its name and type, and the point it acts at on each.
#[derive(Debug, Clone, Serialize)]
pub struct ElementDrawing {
    /// Name in the model file.
    pub name: String,
    /// Its `type` in the model file.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// The first (or only) body, or `ground`.
    pub body_i: String,
    /// Its point, body i frame (global on ground), m.
    pub p: [f64; 2],
    /// The second body (`ground` where there is none).
    pub body_j: String,
    /// Its point, body j frame (global on ground), m.
    pub q: [f64; 2],
}

/// The coordinate a driver prescribes, as its bodies' coordinates give it: `angle` is `phi` of
/// `body_i`; `relative_angle` `phi_i - phi_j`; `x` and `y` the global coordinate of the point `p`
/// of `body_i`; `distance` the distance from `p` of `body_i` to `q` of `body_j`. The points are
/// `[0, 0]` where the coordinate has none.
pub type DriverDrawing = ElementDrawing;

/// One body's points, body frame, m.
#[derive(Debug, Clone, Serialize)]
pub struct BodyDrawing {
    /// Name in the model file.
    pub name: String,
    /// The named points of the model file.
    pub points: IndexMap<String, [f64; 2]>,
    /// Each joint's point on this body that is not also a named point, by joint name: the
    /// outline is drawn through these and the named points.
    pub joint_points: IndexMap<String, [f64; 2]>,
}

/// One joint as drawn.
#[derive(Debug, Clone, Serialize)]
pub struct JointDrawing {
    /// The joint, its bodies and its point on each.
    #[serde(flatten)]
    pub element: ElementDrawing,
    /// What is drawn.
    #[serde(flatten)]
    pub shape: Shape,
}

impl Model {
    /// The picture of the mechanism: bodies' points and joints' sketches.
    pub fn drawing(&self) -> Drawing {
        let name = |b: BodyIx| b.0.map_or("ground".to_string(), |k| self.bodies[k / 3].name.clone());
        let mut bodies: Vec<BodyDrawing> = self
            .bodies
            .iter()
            .map(|b| BodyDrawing { name: b.name.clone(), points: b.points.clone(), joint_points: IndexMap::new() })
            .collect();
        let mut joints = Vec::new();
        for joint in &self.joints {
            let Some(Sketch { i, p, j, q, shape }) = joint.constraint.sketch() else { continue };
            for (body, point) in [(i, p), (j, q)] {
                if let Some(k) = body.0 {
                    let body = &mut bodies[k / 3];
                    if !body.points.values().chain(body.joint_points.values()).any(|&s| s == point) {
                        body.joint_points.entry(joint.name.clone()).or_insert(point);
                    }
                }
            }
            let element =
                ElementDrawing { name: joint.name.clone(), kind: joint.kind, body_i: name(i), p, body_j: name(j), q };
            joints.push(JointDrawing { element, shape });
        }
        let drivers = self
            .drivers
            .iter()
            .filter_map(|d| {
                let (i, p, j, q) = match *d.constraint.driven()? {
                    DriverKind::Angle { body } => (body, [0.0; 2], BodyIx::GROUND, [0.0; 2]),
                    DriverKind::RelativeAngle { i, j } => (i, [0.0; 2], j, [0.0; 2]),
                    DriverKind::Distance { i, s_p, j, s_q } => (i, s_p, j, s_q),
                    DriverKind::X { body, point } | DriverKind::Y { body, point } => {
                        (body, point, BodyIx::GROUND, [0.0; 2])
                    }
                };
                Some(ElementDrawing { name: d.name.clone(), kind: d.kind, body_i: name(i), p, body_j: name(j), q })
            })
            .collect();
        Drawing { bodies, joints, paths: self.paths.clone(), drivers }
    }
}
