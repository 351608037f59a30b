//! The force element types, by the name model files call them in `type`: one line each, the only
//! place besides the type's own module that names it.

use super::{contact, point, spring, Force};
use crate::element::registry;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

registry! {
    /// An applied force or a force element.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(tag = "type")]
    pub enum ForceSpec -> Box<dyn Force>, in super::ForceContext {
        /// A force `[fx, fy]` at a point of a body, in the global frame or the body's frame; each
        /// component a number or an expression of time and state.
        "force" => Force(point::PointForce, point::compile_force),
        /// A torque on a body (counter-clockwise positive), a number or an expression.
        "torque" => Torque(point::TorqueSpec, point::compile_torque),
        /// Translational spring-damper-actuator between two points: the force pushing the points
        /// apart is `-stiffness (l - free_length) - damping dl/dt + actuator`.
        "spring_damper" => SpringDamper(spring::SpringDamperSpec, spring::compile),
        /// Rotational spring-damper-actuator between two bodies: the torque on `body_i` (its
        /// opposite on `body_j`) is `-stiffness (theta - free_angle) - damping dtheta/dt + actuator`,
        /// `theta = phi_i - phi_j`.
        "rotational_spring_damper" => RotationalSpringDamper(spring::RotationalSpringDamperSpec, spring::compile_rotational),
        /// Unilateral contact between a circle and a circle, segment or polyline fixed to two
        /// bodies: a Hunt-Crossley normal force and smoothed Coulomb friction
        /// (docs/model-format.md, "Contact").
        "contact" => Contact(contact::ContactSpec, contact::compile),
    }
}
