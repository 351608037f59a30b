//! No tolerance asks a solver for less than round-off: a tolerance below what the arithmetic can
//! reach at the mechanism's size gets a warning in the summary, and the solver delivers its best.

mod common;

use common::{at_tolerance, col, example_text, integrators, patch};
use linkwork::Model;

fn warnings(r: &linkwork::Results) -> Vec<String> {
    r.summary_json(None)["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect()
}

/// The quick-return's kinematics with `solver.tolerance: 1e-18` (below the 1.4e-14 that 64 units
/// of round-off allow at its 6 rad crank angle): the run succeeds, says so in its warnings, and
/// agrees with the default run to `1e-11`, relative above 1 (positions and velocities to the default tolerance
/// amplified by the Jacobian's condition, as the closed-form tests measure).
#[test]
fn a_position_tolerance_below_round_off_warns_and_runs() {
    let text = example_text("quick_return_a.yaml");
    let tight = patch(
        &text,
        "kinematics: {type: kinematic, drivers: [crank_drive], t_end: 2.0, step: 0.05}",
        "kinematics: {type: kinematic, drivers: [crank_drive], t_end: 2.0, step: 0.05, solver: {tolerance: 1e-18}}",
    );
    let reference = Model::from_yaml(&text).unwrap().run("kinematics", &Default::default()).unwrap();
    assert_eq!(warnings(&reference), Vec::<String>::new());
    let r = Model::from_yaml(&tight)
        .unwrap()
        .run("kinematics", &Default::default())
        .unwrap_or_else(|f| panic!("{}", f.error));
    let w = warnings(&r);
    assert!(w.len() == 1 && w[0].contains("solver.tolerance 1e-18"), "{w:?}");
    for name in ["rocker.phi", "slider_d.x", "slider_d.vx", "link.omega"] {
        let worst = col(&r, name)
            .iter()
            .zip(col(&reference, name))
            .map(|(a, b)| (a - b).abs() / b.abs().max(1.0))
            .fold(0.0, f64::max);
        assert!(worst < 1e-11, "{name}: {worst}");
    }
}

/// The A01 pendulum moved 100 km from the origin: at that size round-off alone is `1e-11` m, so
/// the default position tolerance (`1e-12` m) cannot be reached. Assembly stops at the floor
/// (`64 eps 1e5 = 1.4e-9` m), with a warning, and the dynamics run with every integrator. The
/// error tolerance is relative to the coordinates, so `rtol = 1e-11` makes the far run's weight
/// `1e-6` m, and the motion matches the pendulum at the origin to `1e-5` m over 1 s.
#[test]
fn a_mechanism_far_from_the_origin_assembles_at_the_round_off_floor() {
    let text = example_text("iftomm_a01_pendulum.yaml");
    let far = patch(
        &patch(&text, "position: [-1, 0]", "position: [99999, 0]"),
        "body_j: ground, point_j: [0, 0]",
        "body_j: ground, point_j: [100000, 0]",
    );
    for (integrator, kind) in integrators() {
        let o = linkwork::Overrides { atol: Some(1e-8), ..at_tolerance(kind, 1e-11, Some(1.0)) };
        let near = Model::from_yaml(&text).unwrap().run("dynamics", &o.clone().into()).unwrap();
        let r = Model::from_yaml(&far)
            .unwrap()
            .run("dynamics", &o.clone().into())
            .unwrap_or_else(|f| panic!("{integrator}: {}", f.error));
        let w = warnings(&r);
        assert!(w.iter().any(|w| w.contains("solver.tolerance")), "{integrator}: {w:?}");
        let (x_far, x_near) = (col(&r, "P1_x"), col(&near, "P1_x"));
        let worst = x_far.iter().zip(x_near).map(|(a, b)| (a - 1e5 - b).abs()).fold(0.0, f64::max);
        eprintln!("{integrator}: far pendulum differs by {worst:.2e} m");
        assert!(worst < 1e-5, "{integrator}: {worst}");
    }
}

/// `rtol = 1e-16` is below the 100 units of round-off (`2.2e-14`) that an error estimate can
/// resolve: the integrator raises it to that, says so, and runs the pendulum's first 0.2 s,
/// matching the exact solution to `1e-6` m (measured 3.2e-11 with `hht`, 1.0e-13 with `bdf`,
/// 1.7e-15 with `abam`). Without the round-off floor of the Newton tests, `bdf` stops at t = 0
/// with a step of 2.7e-16 s.
#[test]
fn an_integrator_tolerance_below_round_off_warns_and_runs() {
    let model = Model::load(common::example("iftomm_a01_pendulum.yaml")).unwrap();
    for (integrator, kind) in integrators() {
        let o = at_tolerance(kind, 1e-16, Some(0.2));
        let r = model.run("dynamics", &o.clone().into()).unwrap_or_else(|f| panic!("{integrator}: {}", f.error));
        let w = warnings(&r);
        assert!(w.iter().any(|w| w.contains("solver.rtol 1e-16")), "{integrator}: {w:?}");
        let worst = common::references::pendulum_error(&r);
        eprintln!("{integrator}: {worst:.2e} m, statistics {}", r.summary_json(None)["statistics"]);
        assert!(worst < 1e-6, "{integrator}: {worst}");
    }
}
