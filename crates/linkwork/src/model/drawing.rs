//! The mechanism as a picture, for the report and notebooks: each body's points in its own frame
//! (its named points and every joint point on it), and each joint's [`Sketch`] with its bodies by
//! name. The picture at time `t` follows from the body coordinates of `results.csv`:
//! `r_P = (x, y) + A(phi) s'_P`. Ground's points are global.

use super::Model;
use crate::constraints::{BodyIx, Shape, Sketch};
use indexmap::IndexMap;
use serde::Serialize;

/// Everything needed to draw the mechanism in any pose.
#[derive(Debug, Clone, Serialize)]
pub struct Drawing {
    /// The moving bodies, in file order.
    pub bodies: Vec<BodyDrawing>,
    /// The joints with a picture, in file order.
    pub joints: Vec<JointDrawing>,
}

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
    /// Name in the model file.
    pub name: String,
    /// Its `type` in the model file.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// The first body, or `ground`.
    pub body_i: String,
    /// Its point, body i frame (global on ground), m.
    pub p: [f64; 2],
    /// The second body, or `ground`.
    pub body_j: String,
    /// Its point, body j frame (global on ground), m.
    pub q: [f64; 2],
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
            joints.push(JointDrawing {
                name: joint.name.clone(),
                kind: joint.kind,
                body_i: name(i),
                p,
                body_j: name(j),
                q,
                shape,
            });
        }
        Drawing { bodies, joints }
    }
}
