//! Linkwork: a planar multibody kinematics and dynamics engine.

pub mod constraints;
pub mod expr;
