//! Every joint and driver type, from a model file, through a kinematic analysis, against a closed
//! form. Small mechanisms written inline; tolerance 1e-10 as in `closed_forms.rs`.

mod common;

use common::{c, check_coordinate};
use linkwork::expr::{HyperDual, Scalar};
use linkwork::{Model, Results};

const TOL: f64 = 1e-10;

fn run(text: &str) -> Results {
    let model = Model::from_yaml(text).unwrap_or_else(|e| panic!("{e}"));
    model.run("k", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error))
}

/// Two gears on fixed ground pins, external then internal: `r1 omega1 = -r2 omega2` (external),
/// `r1 omega1 = r2 omega2` (internal, gear 2 a ring around gear 1).
#[test]
fn gear_pairs() {
    for (internal, centre2, sign) in [(false, 0.5, -1.0), (true, -0.1, 1.0)] {
        let text = format!(
            "bodies:
  g1: {{mass: 1, inertia: 1, position: [0, 0], angle: 0}}
  g2: {{mass: 1, inertia: 1, position: [{centre2}, 0], angle: 0.1}}
joints:
  p1: {{type: revolute, body_i: g1, point_i: [0, 0], body_j: ground, point_j: [0, 0]}}
  p2: {{type: revolute, body_i: g2, point_i: [0, 0], body_j: ground, point_j: [{centre2}, 0]}}
  mesh: {{type: gear, body_i: g1, point_i: [0, 0], radius_i: 0.2, body_j: g2, point_j: [0, 0], radius_j: 0.3, internal: {internal}}}
drivers:
  m: {{type: angle, body: g1, function: \"0.5*t + 0.3*t^2\"}}
analyses:
  k: {{type: kinematic, t_end: 2, step: 0.1}}
"
        );
        let r = run(&text);
        let ratio = sign * 0.2 / 0.3;
        check_coordinate(
            &r,
            "g2",
            "phi",
            move |t: HyperDual| c::<HyperDual>(0.1) + (t * c(0.5) + t * t * c(0.3)) * c(ratio),
            TOL,
        );
    }
}

/// A pinion (radius 0.1) on a ground pin drives a rack on a horizontal guide whose pitch line is
/// 0.1 below the pinion centre; no slip at the contact point: the rack moves `+r theta`. A disc of
/// radius 0.25 rolls on the ground x-axis (given as the direction `[-1, 0]`, to check that the
/// direction does not matter), its centre driven along x: `phi = -(x - x0) / r`.
#[test]
fn rack_pinion_and_rolling_disc() {
    let text = "bodies:
  pinion: {mass: 1, inertia: 1, position: [0, 0], angle: 0}
  rack: {mass: 1, inertia: 1, position: [0, -0.1], angle: 0}
  disc: {mass: 1, inertia: 1, position: [2, 0.25], angle: 0}
joints:
  pin: {type: revolute, body_i: pinion, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
  guide: {type: translational, body_i: ground, point_i: [0, -0.1], axis_i: [1, 0], body_j: rack, point_j: [0, 0], axis_j: [1, 0]}
  mesh: {type: rack_pinion, body_i: pinion, point_i: [0, 0], radius: 0.1, body_j: rack, point_j: [0, 0], axis_j: [1, 0]}
  roll: {type: rolling_disc, body_i: disc, point_i: [0, 0], radius: 0.25, body_j: ground, point_j: [0, 0], axis_j: [-1, 0]}
drivers:
  turn: {type: angle, body: pinion, function: \"sin(2*t)\"}
  push: {type: x, body: disc, function: \"2 + t^2\"}
analyses:
  k: {type: kinematic, t_end: 2, step: 0.1}
";
    let r = run(text);
    // The pinion's surface at the contact point (0, -r) moves at omega x (0, -r) = (r omega, 0).
    check_coordinate(&r, "rack", "x", |t: HyperDual| (t * c(2.0)).sin() * c(0.1), TOL);
    check_coordinate(&r, "disc", "y", |_| c(0.25), TOL);
    check_coordinate(&r, "disc", "phi", |t: HyperDual| -(t * t) / c(0.25), TOL);
}

/// A crank held on a circle by a general constraint instead of a pin, a point held by absolute
/// joints, and a rod of fixed length between them (`distance`): the crank centre stays on
/// `x^2 + y^2 = 0.5625` and turns with its `relative_angle` driver against a fixed reference body.
#[test]
fn expression_absolute_distance_and_relative_angle() {
    let text = "bodies:
  crank: {mass: 1, inertia: 1, position: [0.75, 0], angle: 0}
  base: {mass: 1, inertia: 1, position: [0, 0], angle: 0}
  slider: {mass: 1, inertia: 1, position: [2, 0], angle: 0}
joints:
  circle: {type: expression, expression: \"crank.x^2 + crank.y^2 - 0.5625\"}
  radial: {type: expression, expression: \"crank.y*cos(crank.phi) - crank.x*sin(crank.phi)\"}
  base_x: {type: absolute_x, body: base, value: 0}
  base_y: {type: absolute_y, body: base, point: [1, 0], value: 0}
  base_a: {type: absolute_angle, body: base}
  rod: {type: distance, body_i: crank, point_i: [0, 0], body_j: slider, point_j: [0, 0], length: 2}
  slide_y: {type: absolute_y, body: slider, value: 0}
  slide_a: {type: absolute_angle, body: slider, value: 0}
drivers:
  turn: {type: relative_angle, body_i: crank, body_j: base, function: \"1.5*t\"}
analyses:
  k: {type: kinematic, t_end: 3, step: 0.05}
";
    let r = run(text);
    let th = |t: HyperDual| t * c(1.5);
    check_coordinate(&r, "crank", "x", move |t| th(t).cos() * c(0.75), TOL);
    check_coordinate(&r, "crank", "y", move |t| th(t).sin() * c(0.75), TOL);
    check_coordinate(&r, "base", "x", |_| c(0.0), TOL);
    // x_slider = 0.75 cos th + sqrt(4 - 0.5625 sin^2 th)
    check_coordinate(
        &r,
        "slider",
        "x",
        move |t| th(t).cos() * c(0.75) + (c::<HyperDual>(4.0) - th(t).sin() * th(t).sin() * c(0.5625)).sqrt(),
        TOL,
    );
}

/// A telescoping arm pinned to ground whose length is driven (`distance` driver) while its angle
/// follows a `y` driver of its tip, and a follower kept at a fixed offset from the arm's line
/// (`revolute_translational`) and driven along the line by a `y` driver.
#[test]
fn distance_y_drivers_and_revolute_translational() {
    let text = "bodies:
  arm: {mass: 1, inertia: 1, position: [0.5, 0], angle: 0}
  tip: {mass: 1, inertia: 1, position: [1, 0], angle: 0}
  follower: {mass: 1, inertia: 1, position: [0.5, 0.2], angle: 0}
joints:
  root: {type: revolute, body_i: arm, point_i: [-0.5, 0], body_j: ground, point_j: [0, 0]}
  slide: {type: translational, body_i: arm, point_i: [0, 0], axis_i: [1, 0], body_j: tip, point_j: [0, 0], axis_j: [1, 0]}
  offset: {type: revolute_translational, body_i: arm, point_i: [0, 0], axis_i: [1, 0], body_j: follower, point_j: [0, 0], offset: 0.2}
  follower_angle: {type: absolute_angle, body: follower, value: 0}
drivers:
  reach: {type: distance, body_i: ground, point_i: [0, 0], body_j: tip, point_j: [0, 0], function: \"1 + 0.5*t\"}
  lift: {type: y, body: tip, function: \"0.3*sin(t)\"}
  along: {type: x, body: follower, function: \"0.5 + 0.1*t\"}
analyses:
  k: {type: kinematic, t_end: 2, step: 0.1}
";
    let r = run(text);
    let reach = |t: HyperDual| c::<HyperDual>(1.0) + t * c(0.5);
    let lift = |t: HyperDual| t.sin() * c(0.3);
    let angle = move |t: HyperDual| (lift(t) / reach(t)).asin();
    check_coordinate(&r, "tip", "x", move |t| (reach(t) * reach(t) - lift(t) * lift(t)).sqrt(), TOL);
    check_coordinate(&r, "arm", "phi", angle, TOL);
    // The follower is 0.2 to the left of the arm's line: y = x tan(a) + 0.2 / cos(a).
    let x = |t: HyperDual| c::<HyperDual>(0.5) + t * c(0.1);
    check_coordinate(&r, "follower", "y", move |t| x(t) * angle(t).tan() + c::<HyperDual>(0.2) / angle(t).cos(), TOL);
}

/// A translational joint's relative angle takes whole turns from the file's guess: a slider
/// written a turn and a bit from its guide (`angle: 6.35`, the guide at 0, axes parallel) is the
/// same position as one at 0.067 rad, so assembly turns it back by 0.067, not by a turn and a
/// bit, and keeps its angle near 2 pi (found by the property tests, `tests/properties.rs`).
#[test]
fn translational_angle_takes_whole_turns_from_the_guess() {
    let text = "bodies:
  guide: {mass: 1, inertia: 1, position: [0, 0], angle: 0}
  slider: {mass: 1, inertia: 1, position: [0.5, 0.01], angle: 6.35}
joints:
  pin: {type: revolute, body_i: guide, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
  slide: {type: translational, body_i: guide, point_i: [0, 0], axis_i: [1, 0], body_j: slider, point_j: [0, 0], axis_j: [1, 0]}
drivers:
  turn: {type: angle, body: guide, function: \"0.5*t\"}
  push: {type: distance, body_i: ground, point_i: [0, 0], body_j: slider, point_j: [0, 0], function: \"0.5 + 0.1*t\"}
analyses:
  k: {type: kinematic, t_end: 1, step: 0.5}
";
    let r = run(text);
    let (phi, time) = (r.column("slider.phi").unwrap(), r.column("time").unwrap());
    for (p, t) in phi.iter().zip(time) {
        assert!((p - 2.0 * std::f64::consts::PI - 0.5 * t).abs() < TOL, "slider.phi {p} at t = {t}");
    }
}
