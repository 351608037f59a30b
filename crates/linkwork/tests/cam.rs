//! Cam joints (`type: cam`): `examples/cam_roller.yaml`, a disc cam given by its pitch curve
//! lifting a radial roller follower, against the motion law the curve was made from, the closed
//! form of the pressure angle, and virtual work; bad cams.

mod common;

use linkwork::{Error, Model};
use std::f64::consts::PI;

/// The example's lift in the cam angle `theta`: a cycloidal rise of 20 mm over 120 deg, a dwell
/// to 180, a cycloidal return over 90 deg, a dwell to 360. `(s, s', s'')` in `theta`.
fn lift(theta: f64) -> (f64, f64, f64) {
    common::cycloidal_cam_lift(theta, 0.02, 2.0 * PI / 3.0, PI / 2.0)
}

const BASE: f64 = 0.05;

fn cam() -> Model {
    Model::load(format!("{}/../../examples/cam_roller.yaml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn the_follower_moves_by_the_law_and_the_pressure_angle_is_its_closed_form() {
    let r = cam().run("motion").unwrap_or_else(|f| panic!("{}", f.error));
    // 1.5 s at a degree a step: the cam turns on past 360 deg, across the pitch curve's seam
    // (psi = +-pi, at theta = 270 deg) twice.
    assert_eq!(r.len(), 541);
    let col = |n: &str| r.column(n).unwrap_or_else(|| panic!("no column {n}")).to_vec();
    let (y, vy, ay, pressure) = (col("follower.y"), col("follower.vy"), col("follower.ay"), col("pressure_angle"));
    let omega = 2.0 * PI;
    let mut worst = [0.0f64; 4];
    let (mut low, mut high) = (0.0f64, 0.0f64);
    for (k, &t) in r.time.iter().enumerate() {
        let (s, d1, d2) = lift(omega * t);
        worst[0] = worst[0].max((y[k] - BASE - s).abs());
        worst[1] = worst[1].max((vy[k] - d1 * omega).abs());
        worst[2] = worst[2].max((ay[k] - d2 * omega * omega).abs());
        worst[3] = worst[3].max((pressure[k] - (d1 / (BASE + s)).atan()).abs());
        (low, high) = (low.min(pressure[k]), high.max(pressure[k]));
    }
    // The pitch curve is the law itself (no interpolation): the lift is exact to the position
    // solver's tolerance, 1e-10 on the constraint, and velocity and acceleration come from
    // linear solves with the exact Jacobian and gamma, rounding on values of 0.1 m/s and
    // 2 m/s^2. The pressure angle is the law's slope over the radius at the solved position.
    // Measured: 2e-17 m, 1e-16 m/s, 3e-13 m/s^2 and 2e-16 rad.
    assert!(worst[0] < 1e-9, "lift error {:e}", worst[0]);
    assert!(worst[1] < 1e-9, "velocity error {:e}", worst[1]);
    assert!(worst[2] < 1e-8, "acceleration error {:e}", worst[2]);
    assert!(worst[3] < 1e-9, "pressure angle error {:e}", worst[3]);
    // The extremes lie near the law's steepest points (mid-rise 2H/beta = 0.019 m/rad over a
    // radius of 0.06 m, mid-return 0.025 m/rad): atan(0.318) = 0.308 rad on the rise (the
    // quotient peaks a little earlier, at 0.311) and -0.405 rad on the steeper return, whose sign
    // says the cam lets the follower in.
    assert!((0.305..0.315).contains(&high) && (-0.41..-0.40).contains(&low), "pressure angle in [{low}, {high}]");
}

#[test]
fn the_motor_torque_pays_the_followers_work() {
    let r = cam().run("drive").unwrap_or_else(|f| panic!("{}", f.error));
    let col = |n: &str| r.column(n).unwrap_or_else(|| panic!("no column {n}")).to_vec();
    let (ay, torque) = (col("follower.ay"), col("motor.effort"));
    // Virtual work: the cam turns steadily about its centre of mass and the guide is frictionless,
    // so T omega = F v_y with F = m (a_y + g) the force the follower needs and v_y = s' omega:
    // T = F ds/dtheta.
    let (m, g, omega) = (0.3, 9.81, 2.0 * PI);
    let peak = torque.iter().fold(0.0f64, |p, t| p.max(t.abs()));
    let mut worst = 0.0f64;
    for k in 0..r.len() {
        let (_, d1, _) = lift(omega * r.time[k]);
        let want = m * (ay[k] + g) * d1;
        worst = worst.max((torque[k] - want).abs());
    }
    // The multipliers come from one well-conditioned linear solve: 1e-10 N m against a peak of
    // 0.08 N m is rounding with room (measured 7e-15 N m).
    assert!(worst < 1e-10, "torque error {worst:e}");
    assert!(peak > 0.01, "the follower's lift needs torque: peak {peak}");
}

fn problems(text: &str) -> Vec<String> {
    match Model::from_yaml(text) {
        Err(Error::Model(p)) => p.iter().map(|p| p.to_string()).collect(),
        Err(e) => panic!("expected a model error, got {e}"),
        Ok(_) => panic!("expected a model error, the model compiled"),
    }
}

#[test]
fn bad_cams_are_problems_at_their_fields() {
    let model = |joint: &str, measure: &str| {
        format!(
            "parameters:\n  r0: 0.05\n\
             bodies:\n  cam: {{mass: 1, inertia: 0.1, position: [0, 0]}}\n  \
             follower: {{mass: 1, inertia: 0.1, position: [0, 0.05]}}\n\
             joints:\n  pin: {{type: revolute, body_i: ground, body_j: cam, at: [0, 0]}}\n  \
             contact: {{type: cam, {joint}}}\n\
             measures:\n  p: {{type: pressure_angle, joint: {measure}}}\n"
        )
    };
    let good = "body_i: cam, body_j: follower, point_j: [0, 0]";
    let cases = [
        (
            "body_i: cma, body_j: follower, point_j: [0, 0], radius: r0",
            "contact",
            "joints.contact.body_i: unknown body 'cma'",
        ),
        (&format!("{good}, radius: 'r0 +'"), "contact", "joints.contact.radius: cannot read the expression 'r0 +'"),
        (
            &format!("{good}, radius: 'r0 + cam.phi'"),
            "contact",
            "joints.contact.radius: cannot read the expression 'r0 + cam.phi'",
        ),
        (&format!("{good}, radius: 'r0 + t'"), "contact", "expected psi (the polar angle"),
        (
            &format!("{good}, radius: r0, roller_radius: -1"),
            "contact",
            "joints.contact.roller_radius: expected a number >= 0",
        ),
        (&format!("{good}, radius: r0"), "pin", "measures.p.joint: 'pin' is a revolute joint; expected a cam joint"),
        (&format!("{good}, radius: r0"), "cams", "measures.p.joint: unknown joint 'cams'"),
    ];
    let centred = model(&format!("{good}, radius: r0"), "contact").replace("position: [0, 0.05]", "position: [0, 0]");
    let list = problems(&centred);
    assert!(
        list.iter().any(|p| p.starts_with("joints.contact: the follower's point is at the cam's centre")),
        "{list:#?}"
    );
    for (joint, measure, want) in cases {
        let list = problems(&model(joint, measure));
        assert!(list.iter().any(|p| p.contains(want)), "no '{want}' in {list:#?}");
    }
}
