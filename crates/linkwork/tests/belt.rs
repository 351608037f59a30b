//! The belt joint against its closed form: two pulleys on ground pins, open and crossed, and on a
//! turning carrier, through a kinematic run (angles, speeds and accelerations), and its reaction
//! from an inverse run against the free-body balance of the driven pulley.

mod common;

use common::{c, check_coordinate, col};
use linkwork::expr::{HyperDual, Scalar};
use linkwork::{Model, Results};

/// The angle rows are linear in the coordinates: positions hold to the position solver's
/// tolerance (1e-10), velocities and accelerations come from exact linear solves (rounding).
const TOL: f64 = 1e-10;

/// Radii of the pulleys: i (driven) and j.
const R_I: f64 = 0.2;
const R_J: f64 = 0.5;

fn run(text: &str, analysis: &str) -> Results {
    let model = Model::from_yaml(text).unwrap_or_else(|e| panic!("{e}"));
    model.run(analysis, &Default::default()).unwrap_or_else(|f| panic!("{}", f.error))
}

/// Pulley `a` (radius 0.2, at the origin) and pulley `b` (radius 0.5, starting at 0.3 rad) on
/// pins of `carrier`, a belt between them, `a` driven by `motor` and the carrier by `arm_motor`.
/// `b` has inertia 0.3 kg m^2 and a load torque of -2 N m.
fn drive(crossed: bool, carrier: &str, arm: &str) -> String {
    format!(
        "bodies:
  arm: {{mass: 1, inertia: 1, position: [0.5, 0], angle: 0}}
  a: {{mass: 1, inertia: 0.1, position: [0, 0], angle: 0}}
  b: {{mass: 1, inertia: 0.3, position: [1, 0], angle: 0.3}}
joints:
  pivot: {{type: revolute, body_i: arm, point_i: [-0.5, 0], body_j: ground, point_j: [0, 0]}}
  pa: {{type: revolute, body_i: a, body_j: {carrier}, at: [0, 0]}}
  pb: {{type: revolute, body_i: b, body_j: {carrier}, at: [1, 0]}}
  belt: {{type: belt, body_i: a, radius_i: {R_I}, body_j: b, radius_j: {R_J}, crossed: {crossed}, carrier: {carrier}}}
drivers:
  motor: {{type: angle, body: a, function: \"0.5*t + 0.3*t^2\"}}
  arm_motor: {{type: angle, body: arm, function: \"{arm}\"}}
forces:
  load: {{type: torque, body: b, torque: -2}}
analyses:
  k: {{type: kinematic, t_end: 2, step: 0.1}}
  inverse: {{type: inverse, t_end: 2, step: 0.1}}
"
    )
}

/// `sigma`: -1 open, +1 crossed.
fn sigma(crossed: bool) -> f64 {
    if crossed {
        1.0
    } else {
        -1.0
    }
}

/// On ground (the arm held still, and not the carrier), relative to a fixed frame:
/// `r_i phi_a + sigma r_j phi_b = const`, so `phi_b = 0.3 - r_i / (sigma r_j) phi_a` and the
/// speed ratio `omega_b / omega_a` is `r_i / r_j` open (the same way) and `-r_i / r_j` crossed.
#[test]
fn pulleys_on_ground_turn_at_the_ratio_of_their_radii() {
    for crossed in [false, true] {
        let r = run(&drive(crossed, "ground", "0"), "k");
        let ratio = -R_I / (sigma(crossed) * R_J);
        check_coordinate(
            &r,
            "b",
            "phi",
            move |t: HyperDual| c::<HyperDual>(0.3) + (t * c(0.5) + t * t * c(0.3)) * c(ratio),
            TOL,
        );
        let (wa, wb) = (col(&r, "a.omega"), col(&r, "b.omega"));
        let expected = if crossed { -R_I / R_J } else { R_I / R_J };
        for k in 0..r.len() {
            assert!((wb[k] / wa[k] - expected).abs() < TOL, "crossed {crossed}: omega_b / omega_a = {}", wb[k] / wa[k]);
        }
    }
}

/// On the arm, turning at 0.4 rad/s about the origin: the pulleys' rotations relative to the arm
/// keep the ratio, `r_i (phi_a - phi_c) + sigma r_j (phi_b - phi_c) = sigma r_j 0.3`:
/// `phi_b = phi_c + 0.3 - r_i / (sigma r_j) (phi_a - phi_c)`.
#[test]
fn pulleys_on_a_turning_carrier_keep_the_ratio_relative_to_it() {
    for crossed in [false, true] {
        let r = run(&drive(crossed, "arm", "0.4*t"), "k");
        let ratio = -R_I / (sigma(crossed) * R_J);
        let phi_b = move |t: HyperDual| {
            let (phi_a, phi_c) = (t * c(0.5) + t * t * c(0.3), t * c(0.4));
            phi_c + c(0.3) + (phi_a - phi_c) * c(ratio)
        };
        check_coordinate(&r, "b", "phi", phi_b, TOL);
        // The arm carries b's centre round the origin: a check that the carrier did turn.
        check_coordinate(&r, "b", "x", |t: HyperDual| (t * c(0.4)).cos(), TOL);
    }
}

/// The belt's reaction from an inverse run on ground: its torque on pulley a (`belt.torque`) is
/// what the free body of pulley b asks of the belt, `T_b = J_b alpha_b - M_load`, carried across
/// by the radii, `T_a = r_i T_b / (sigma r_j)` (a pull `F_tight - F_slack = T_a / r_i` at both
/// rims); the belt pushes neither pulley's centre (`fx = fy = 0`).
#[test]
fn belt_torque_balances_the_driven_pulley() {
    for crossed in [false, true] {
        let r = run(&drive(crossed, "ground", "0"), "inverse");
        let (alpha_b, torque) = (col(&r, "b.alpha"), col(&r, "belt.torque"));
        let (fx, fy) = (col(&r, "belt.fx"), col(&r, "belt.fy"));
        let (inertia_b, load) = (0.3, -2.0);
        let mut worst = 0.0f64;
        for k in 0..r.len() {
            let t_b = inertia_b * alpha_b[k] - load;
            let want = R_I * t_b / (sigma(crossed) * R_J);
            worst = worst.max((torque[k] - want).abs());
            assert!(fx[k] == 0.0 && fy[k] == 0.0, "a belt pushes no centre: ({}, {})", fx[k], fy[k]);
        }
        // One well-conditioned linear solve for the multipliers: rounding on torques of 1 N m.
        assert!(worst < 1e-10, "crossed {crossed}: belt torque off the free-body balance by {worst:e} N m");
        // The load dominates: the belt's pull is that of 2 N m at b's rim, 4 N, either way.
        assert!((torque[0] / R_I).abs() > 3.0, "tension difference {}", torque[0] / R_I);
    }
}

/// Bad fields are refused at their paths: a radius that is not positive, a carrier that is one
/// of the pulleys, a pulley that is not a body.
#[test]
fn bad_belts_are_refused_at_their_fields() {
    let problems = |from: &str, to: &str| {
        let text = common::patch(&drive(false, "ground", "0"), from, to);
        match Model::from_yaml(&text) {
            Ok(_) => panic!("{to}: compiled"),
            Err(e) => e.to_string(),
        }
    };
    let e = problems(&format!("radius_j: {R_J}"), "radius_j: -1");
    assert!(e.contains("joints.belt.radius_j: expected a positive number, found -1"), "{e}");
    let e = problems("carrier: ground}", "carrier: b}");
    assert!(e.contains("joints.belt.carrier: the carrier 'b' is a pulley"), "{e}");
    let e = problems("body_j: b, radius_j", "body_j: c, radius_j");
    assert!(e.contains("joints.belt.body_j: unknown body 'c'"), "{e}");
}
