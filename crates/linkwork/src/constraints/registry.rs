//! The joint and driver types, by the name model files call them in `type`: one line each, the
//! only place besides the type's own module that names it.

use super::{absolute, cam, distance, driver, expression, gear, point_line, revolute, rolling, translational};
use super::{Constraint, Friction};
use crate::element::registry;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A joint compiled: its rows, and its friction when it has a `friction:` mapping.
pub type CompiledJoint = (Box<dyn Constraint>, Option<Friction>);

registry! {
    /// A joint between two bodies (or a body and `ground`), or a general constraint. The first body
    /// (`body_i`) is the one whose reaction is reported.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(tag = "type")]
    pub enum JointSpec -> CompiledJoint, in super::JointContext {
        /// Pin: `point_i` of `body_i` coincides with `point_j` of `body_j`. 2 equations.
        "revolute" => Revolute(revolute::RevoluteJoint, revolute::compile),
        /// Prismatic: `point_j` of `body_j` slides on the line of `body_i` through `point_i` along
        /// `axis_i`, and the bodies keep the relative angle that makes `axis_i` and `axis_j` parallel.
        /// 2 equations.
        "translational" => Translational(translational::TranslationalJoint, translational::compile),
        /// Pin in slot: `point_j` of `body_j` stays on the line of `body_i` through `point_i` along
        /// `axis_i`; rotation stays free. 1 equation.
        "point_on_line" => PointOnLine(point_line::PointOnLineJoint, point_line::compile),
        /// Revolute-translational composite: `point_j` of `body_j` keeps a constant signed distance
        /// `offset` from the line of `body_i` (a link pinned at `point_j` and sliding, at right angles,
        /// on the line). 1 equation.
        "revolute_translational" => RevoluteTranslational(point_line::RevoluteTranslationalJoint, point_line::compile_offset),
        /// Distance (revolute-revolute link): the two points stay `length` apart. 1 equation.
        "distance" => Distance(distance::DistanceJoint, distance::compile),
        /// Absolute x of a body point is constant. 1 equation.
        "absolute_x" => AbsoluteX(absolute::AbsolutePoint, absolute::compile_x),
        /// Absolute y of a body point is constant. 1 equation.
        "absolute_y" => AbsoluteY(absolute::AbsolutePoint, absolute::compile_y),
        /// Absolute angle of a body is constant. 1 equation.
        "absolute_angle" => AbsoluteAngle(absolute::AbsoluteAngleJoint, absolute::compile_angle),
        /// Gear pair: pitch circles of radius `radius_i` and `radius_j` about `point_i` and `point_j`
        /// roll without slip. The centre distance must be kept by other joints. 1 equation.
        "gear" => Gear(gear::GearJoint, gear::compile),
        /// Rack and pinion: the pinion's pitch circle (centre `point_i`, `radius`) rolls without slip
        /// on the rack's pitch line through `point_j` along `axis_j`. The centre-to-line distance must
        /// be kept by other joints. 1 equation.
        "rack_pinion" => RackPinion(rolling::RollingJoint, rolling::compile_rack),
        /// A disc (centre `point_i`, `radius`) rolling without slip on the line of `body_j` through
        /// `point_j` along `axis_j`: contact and no slip. 2 equations.
        "rolling_disc" => RollingDisc(rolling::RollingJoint, rolling::compile_disc),
        /// A general constraint `expression = 0` in body coordinates (`crank.x`, `crank.y`,
        /// `crank.phi`) and time `t`, differentiated exactly. 1 equation.
        "expression" => Expression(expression::ExpressionJoint, expression::compile),
        /// Cam and roller (or knife-edge) follower: `point_j` of `body_j` (the roller's centre)
        /// stays on the pitch curve of the cam `body_i`, `radius` a function of the polar angle
        /// `psi` about `point_i` in the cam's frame; or the roller (`roller_radius`) touches the
        /// cam's working surface from outside, given by `surface_radius` (polar) or `profile` (a
        /// closed Cartesian curve). 1 equation.
        "cam" => Cam(cam::CamJoint, cam::compile),
        "belt" => Belt(super::belt::BeltJoint, super::belt::compile),
    }
}

registry! {
    /// A prescribed motion: a coordinate of the mechanism equals `function` of time `t` (an
    /// expression such as `"6.1506 + 2*pi*t"`; its derivatives are exact).
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(tag = "type")]
    pub enum DriverSpec -> Box<dyn Constraint>, in super::JointContext {
        /// Angle of `body`, rad.
        "angle" => Angle(driver::AngleDriver, driver::compile_angle),
        /// Angle of `body_i` minus angle of `body_j`, rad.
        "relative_angle" => RelativeAngle(driver::RelativeAngleDriver, driver::compile_relative),
        /// Distance between two points, m.
        "distance" => Distance(driver::DistanceDriver, driver::compile_distance),
        /// Global x of a body point, m.
        "x" => X(driver::PointDriver, driver::compile_x),
        /// Global y of a body point, m.
        "y" => Y(driver::PointDriver, driver::compile_y),
    }
}
