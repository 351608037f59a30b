//! Checks and failures: redundant rows named, a lock-up reported with time and joints and the
//! results before it kept, and a model that is not fully driven refused.

mod common;

use common::{example, example_text, patch, patched_example, run};
use linkwork::analysis::check;
use linkwork::{Error, Model};

/// A parallelogram with a third parallel link: Gruebler says 0, the rank says 1, and one row of
/// the third link's joints is redundant. The kinematic analysis still runs, and the coupler stays
/// parallel to the ground (its angle is 0 throughout).
#[test]
fn redundant_parallelogram() {
    let model = Model::load(example("parallelogram.yaml")).unwrap();
    let report = check(&model).unwrap();
    let mech = &report.mechanism;
    assert_eq!(mech.gruebler_dof, 0);
    assert_eq!(mech.dof, 1);
    assert_eq!(mech.redundant.len(), 1, "{:?}", mech.redundant);
    assert!(["ground_3", "coupler_3"].contains(&mech.redundant[0].element.as_str()), "{:?}", mech.redundant);
    let driven = report.analyses["kinematics"].system.as_ref().expect("assembles with its driver");
    assert_eq!((driven.dof, driven.redundant.len()), (0, 1));

    let (_, r) = run("parallelogram.yaml", "kinematics");
    assert_eq!(r.len(), 41);
    let coupler = r.column("coupler.phi").unwrap();
    assert!(coupler.iter().all(|p| p.abs() < 1e-11), "coupler turned");
    // All three cranks turn together, so the redundant link's pins stay together.
    for name in ["crank_2.phi", "crank_3.phi"] {
        let (a, b) = (r.column("crank_1.phi").unwrap(), r.column(name).unwrap());
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-10), "{name}");
    }
    assert_eq!(r.summary.redundant_rows.as_ref().map(Vec::len), Some(1));
}

/// The rod (0.12 m) is shorter than the crank (0.2 m): lock-up at theta = asin(0.6), t = 0.6435 s.
#[test]
fn lockup_is_reported_with_time_joints_and_partial_results() {
    let model = Model::load(example("slider_crank_lockup.yaml")).unwrap();
    let failure = model.run("kinematics", &Default::default()).expect_err("the mechanism locks up");
    let t_lock = 0.6f64.asin();
    match &failure.error {
        Error::Singular { time, rows, .. } => {
            assert!(*time < t_lock && t_lock - time < 1e-4, "stopped at {time}, lock-up at {t_lock}");
            assert!(!rows.is_empty());
            let joints = failure.error.elements();
            assert!(joints.iter().any(|j| ["A", "B", "guide"].contains(&j.as_str())), "{joints:?}");
        }
        other => panic!("expected a singular position, got {other}"),
    }
    // Every output time before the lock-up, and none after.
    let r = &failure.results;
    assert_eq!(r.len(), 13, "t = 0, 0.05, ..., 0.6");
    assert!((r.time.last().unwrap() - 0.6).abs() < 1e-12);
    let msg = failure.error.to_string();
    assert!(msg.contains("t = 0.64") && msg.contains("singular"), "{msg}");
}

/// Without its driver the quick-return mechanism keeps one degree of freedom: a kinematic
/// analysis is refused with a model error naming the analysis and how many drivers are missing.
#[test]
fn kinematic_analysis_needs_a_fully_driven_model() {
    let text = patch(
        &example_text("quick_return_b.yaml"),
        "kinematics: {type: kinematic, drivers: [crank_drive],",
        "kinematics: {type: kinematic, drivers: [],",
    );
    let model = Model::from_yaml(&text).unwrap();
    let failure = model.run("kinematics", &Default::default()).expect_err("not fully driven");
    match &failure.error {
        Error::Model(problems) => {
            assert_eq!(problems.len(), 1);
            assert_eq!(problems[0].path, "analyses.kinematics.drivers");
            assert!(problems[0].message.contains("add 1 driver"), "{}", problems[0].message);
            assert!(!problems[0].message.contains("singular"), "fewer equations than coordinates: drivers are missing");
        }
        other => panic!("expected a model error, got {other}"),
    }
}

/// An analysis whose drivers cannot be met does not sink the report: the mechanism alone and the
/// other analyses are still checked.
#[test]
fn an_analysis_that_cannot_assemble_is_reported_in_its_entry() {
    let text = patched_example(
        "quick_return_b.yaml",
        &[
            ("drivers:\n", "drivers:\n  too_far: {type: angle, body: rocker, function: \"9\"}\n"),
            (
                "analyses:\n",
                "analyses:\n  clash: {type: kinematic, drivers: [crank_drive, too_far], t_end: 1, step: 0.1}\n",
            ),
        ],
    );
    let model = Model::from_yaml(&text).unwrap();
    let report = check(&model).unwrap();
    assert_eq!(report.mechanism.dof, 1);
    let clash = &report.analyses["clash"];
    assert!(clash.system.is_none());
    assert!(clash.error.as_deref().unwrap_or_default().contains("assembly at t = 0 s failed"), "{:?}", clash.error);
    assert_eq!(report.analyses["kinematics"].system.as_ref().map(|s| s.dof), Some(0));
    assert_eq!(report.coordinate_names[..3], ["crank.x", "crank.y", "crank.phi"]);
}

/// A guessed velocity near the largest double overflows `Phi_q qdot`: the least-change solve
/// then leaves NaN velocities, which passed the tolerance test (`max` skips NaN) with a velocity
/// residual of 0 (found by the fuzzer). Each assembly fails instead, naming the overflow.
#[test]
fn velocities_out_of_range_fail_the_assembly() {
    let text = patch(
        &example_text("slider_crank.yaml"),
        "angle: 0.0, points: {O",
        "angle: 0.0, velocity: [1.7e308, -1.7e308], omega: 1.7e308, points: {O",
    );
    let model = Model::from_yaml(&text).unwrap();
    let error = match check(&model) {
        Ok(report) => report.analyses["kinematics"].error.clone().expect("the kinematics cannot assemble"),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("the velocities are out of range"), "{error}");
    let failure = model.run("kinematics", &Default::default()).expect_err("no assembly");
    assert!(failure.error.to_string().contains("the velocities are out of range"), "{}", failure.error);
}

/// Assembly is the least change: a body held on the unit circle by a general constraint, guessed
/// at (1.5, 1.5), lands on the nearest point (1/sqrt 2, 1/sqrt 2) with its angle untouched; its
/// guessed velocity (2, 0) loses exactly its radial component, giving (1, -1); with `x` given
/// (0.6), `y` becomes 0.8 and the velocity's `vx` is held.
#[test]
fn assembly_is_the_least_change() {
    let text = |given: &str, x: f64| {
        format!(
            "bodies:\n  b: {{mass: 1, inertia: 1, position: [{x}, 1.5], angle: 0.3, velocity: [2, 0], omega: 5, given: {given}}}\n\
             joints:\n  circle: {{type: expression, expression: \"b.x^2 + b.y^2 - 1\"}}\n"
        )
    };
    let model = Model::from_yaml(&text("[]", 1.5)).unwrap();
    let a = check(&model).unwrap().mechanism.assembly;
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let expected = [r, r, 0.3, 1.0, -1.0, 5.0];
    let got = [a.q[0], a.q[1], a.q[2], a.qdot[0], a.qdot[1], a.qdot[2]];
    // Gauss-Newton's minimum-norm steps from a point move along the circle's normal, which keeps
    // them on the line to the nearest point: the answer is exact to rounding (1e-12).
    assert!(got.iter().zip(expected).all(|(g, e)| (g - e).abs() < 1e-12), "{got:?}");

    let model = Model::from_yaml(&text("[x, vx]", 0.6)).unwrap();
    let a = check(&model).unwrap().mechanism.assembly;
    assert_eq!(a.q[0], 0.6, "x is given");
    assert!((a.q[1] - 0.8).abs() < 1e-12, "y = {}", a.q[1]);
    assert_eq!(a.qdot[0], 2.0, "vx is given");
    // x vx + y vy = 0: vy = -0.6 * 2 / 0.8.
    assert!((a.qdot[1] + 1.5).abs() < 1e-12, "vy = {}", a.qdot[1]);
}

/// The singular-position test at output times bites: the quick-return run's largest condition
/// estimate is ~287 (reported in its summary), so a limit of 1e3 lets it run and a limit of 100
/// stops it with a singular-position error naming rows, keeping the points before.
#[test]
fn condition_limit_stops_the_analysis() {
    let mut model = Model::load(example("quick_return_a.yaml")).unwrap();
    let full = model.run("kinematics", &Default::default()).unwrap();
    let max = full.summary_json(None)["statistics"]["max_condition"].as_f64().unwrap();
    assert!(max > 100.0 && max < 1e3, "max condition {max}");
    model.analyses[0].settings.singular_condition = 1e3;
    assert_eq!(model.run("kinematics", &Default::default()).unwrap().len(), 41);
    model.analyses[0].settings.singular_condition = 100.0;
    let failure = model.run("kinematics", &Default::default()).expect_err("stops above the limit");
    match &failure.error {
        Error::Singular { rows, detail, .. } => {
            assert!(!rows.is_empty());
            assert!(detail.contains("condition estimate"), "{detail}");
        }
        other => panic!("expected a singular position, got {other}"),
    }
    assert!(failure.results.len() < 41);
}

/// A slider-crank driven by its slider's x from the dead centre (crank and rod in line): as many
/// equations as coordinates, but the rank drops at the start. It was refused as a model short of
/// a driver ("add 1 driver(s), unless ..."), or, when the slider starts moving (`0.4 - 0.1*t`
/// asks for a velocity the dead centre cannot give), as drivers asking for velocities that
/// cannot hold ("two drivers of one motion"), depending on where the rank test fell. Both are a
/// singular position at t = 0 naming the dyad whose links are collinear, in the run and in the
/// check.
#[test]
fn a_start_at_a_dead_centre_is_a_singular_position_naming_its_dyad() {
    for function in ["0.4 - 0.1*t", "0.4 - 0.1*t^2"] {
        let text = patched_example(
            "slider_crank.yaml",
            &[
                (
                    "motor: {type: angle, body: crank, function: \"2*pi*t\"}",
                    &format!("push: {{type: x, body: slider, function: \"{function}\"}}"),
                ),
                ("drivers: [motor]", "drivers: [push]"),
            ],
        );
        let model = Model::from_yaml(&text).unwrap();
        let failure = model.run("kinematics", &Default::default()).expect_err("singular start");
        let message = failure.error.to_string();
        assert!(matches!(failure.error, Error::Singular { time: 0.0, .. }), "{function}: {message}");
        assert!(
            message.starts_with("singular position at t = 0 s: the start is a dead centre"),
            "{function}: {message}"
        );
        assert!(message.contains("links crank and rod are collinear at joint A (stretched)"), "{function}: {message}");
        assert!(!message.contains("add 1 driver") && !message.contains("cannot all hold"), "{function}: {message}");
        let report = check(&model).unwrap();
        let entry = &report.analyses["kinematics"];
        let said = entry.warning.clone().or(entry.error.clone()).unwrap_or_default();
        assert!(said.contains("the start is a dead centre") && said.contains("joint A"), "{function}: {said}");
    }
}

/// A crank driven by `function` over `t_end`, kinematics with output step 0.01 s.
fn crank_driven_by(function: &str, t_end: f64) -> Model {
    Model::from_yaml(&format!(
        "
name: crank
bodies:
  crank: {{mass: 1, inertia: 0.1, position: [0.5, 0], angle: 0, points: {{O: [-0.5, 0]}}}}
joints:
  O: {{type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}}
drivers:
  motor: {{type: angle, body: crank, function: \"{function}\"}}
analyses:
  kinematics: {{type: kinematic, drivers: [motor], t_end: {t_end}, step: 0.01}}
"
    ))
    .unwrap()
}

/// Drivers the sub-steps cannot follow (`1/(t-1)`, `tan(pi*t)`, `exp(40*t)` with `t_end: 2`):
/// the sub-step, sized so no body turns more than `max_rotation`, has the same floor as a failing
/// Newton's (`min_substep` of the output step), and below it the analysis stops naming the
/// driver and its expression instead of hanging: `1/(t-1)` is infinite at the next output time
/// (1 s), a `NonFinite` error; `tan(pi*t)` is finite there (1.6e16), and the regular Jacobian
/// leaves the driver's rate (3.5e9 rad/s when it stops) as the cause, an `Unbounded` one.
/// `exp(40*t)` is never infinite before 2 s, but it turns the crank by 1e8 rad by 0.46 s, which
/// would take 2.5e8 sub-steps (430 s) to reach the floor: it stops when one output interval
/// needs more than 100,000 sub-steps (at 0.29 s), also naming it. The outputs before
/// each stop are kept. Measured: 100,367, about 95,000 and about 309,000 sub-steps.
#[test]
fn a_driver_without_bound_stops_the_kinematics_naming_it() {
    for (function, blows_up) in [("1/(t-1)", 1.0), ("tan(pi*t)", 0.5), ("exp(40*t)", 2.0)] {
        let model = crank_driven_by(function, 2.0);
        let failure = model.run("kinematics", &Default::default()).expect_err("the driver cannot be followed");
        let message = failure.error.to_string();
        match &failure.error {
            Error::NonFinite { element, expression, .. } | Error::Unbounded { element, expression, .. } => {
                assert_eq!((element.as_str(), expression.as_str()), ("drivers.motor", function), "{message}");
            }
            other => panic!("{function}: expected the driver to be named, got {other}"),
        }
        let r = &failure.results;
        let last = *r.time.last().unwrap();
        assert!(last < blows_up && (blows_up - last < 0.0101 || function.starts_with("exp")), "{function}: to {last}");
        assert!(r.len() > 10, "{function}: outputs kept");
        eprintln!("{function}: {message}; {} outputs, {}", r.len(), r.summary_json(None)["statistics"]);
    }
}

/// A driver that is NaN where the run starts (`sqrt(t-1)` at 0: a residual test that takes the
/// larger of 0 and NaN would pass it and write the t = 0 row), and one that turns NaN during the
/// run (`sqrt(1-t)`, whose rate is infinite at 1 s and value NaN past it), stop the run naming
/// the driver, its expression and the time, written the same way as the command line writes it,
/// not as a position solution that did not converge.
#[test]
fn a_nan_driver_is_named_not_blamed_on_newton() {
    let at_start =
        crank_driven_by("sqrt(t-1)", 2.0).run("kinematics", &Default::default()).expect_err("NaN at the start");
    let message = at_start.error.to_string();
    let Error::NonFinite { element, expression, time, value } = &at_start.error else {
        panic!("expected the driver to be named, got {message}")
    };
    assert_eq!((element.as_str(), expression.as_str(), *time), ("drivers.motor", "sqrt(t-1)", 0.0), "{message}");
    assert!(value.is_nan() && message == "drivers.motor is NaN at t = 0 s (sqrt(t-1))", "{message}");
    assert!(at_start.results.is_empty(), "no row may be written from a NaN driver");

    let later = crank_driven_by("sqrt(1-t)", 2.0).run("kinematics", &Default::default()).expect_err("NaN past 1 s");
    let message = later.error.to_string();
    let Error::NonFinite { element, time, .. } = &later.error else { panic!("expected the driver, got {message}") };
    assert_eq!(element, "drivers.motor", "{message}");
    assert!((1.0..1.01).contains(time), "{message}");
    assert!(message.starts_with("drivers.motor is ") && message.contains("(sqrt(1-t))"), "{message}");
    let last = *later.results.time.last().unwrap();
    assert!((0.99..1.0).contains(&last), "the outputs before 1 s (its rate is infinite there) are kept: {last}");
}

/// A driver whose rate is infinite at the start (`sqrt(t)` at 0) makes the velocity equations
/// non-finite: it is named, not reported as conflicting velocities.
#[test]
fn an_infinite_driver_rate_at_the_start_is_named() {
    let failure =
        crank_driven_by("sqrt(t)", 1.0).run("kinematics", &Default::default()).expect_err("infinite rate at 0");
    let message = failure.error.to_string();
    assert!(message.starts_with("drivers.motor is inf at t = 0 s (sqrt(t))"), "{message}");
}

/// Two drivers of the crank's angle at different speeds (`2*t` and `3*t`) agree on the position
/// at t = 0, so the positions assemble, but not on the velocity. It was reported as "the given
/// velocities conflict" although no velocity was given. Now the message says the drivers ask for
/// velocities that cannot all hold, and names both rows.
#[test]
fn conflicting_drivers_are_not_blamed_on_given_velocities() {
    let patched = patched_example(
        "fourbar.yaml",
        &[
            (
                "  motor: {type: angle, body: crank, function: \"2*t\"}",
                "  motor: {type: angle, body: crank, function: \"2*t\"}\n  motor2: {type: angle, body: crank, function: \"3*t\"}",
            ),
            ("drivers: [motor]", "drivers: [motor, motor2]"),
        ],
    );
    let failure =
        Model::from_yaml(&patched).unwrap().run("kinematics", &Default::default()).expect_err("the drivers conflict");
    let message = failure.error.to_string();
    assert!(matches!(failure.error, Error::Assembly { .. }), "{message}");
    assert!(!message.contains("given velocities"), "{message}");
    assert!(message.contains("the joints and drivers ask for velocities that cannot all hold"), "{message}");
    assert!(message.contains("motor.angle") && message.contains("motor2.angle"), "{message}");
}

/// A pendulum a million kilometres from the origin, its guess two units of round-off off the
/// assembled position: the assembly tolerance (1e-12 m) is below the round-off of coordinates of
/// 1e9 m (1.2e-7 m), so it was blamed on "conflicting constraints". The position solvers stop at
/// the round-off floor of the mechanism's size instead, and say so in a warning.
#[test]
fn the_assembly_tolerance_scales_with_the_mechanism() {
    let far = r#"
bodies:
  bar: {mass: 1, inertia: 0.1, position: [1000000000.5000003, 0], angle: 0, points: {O: [-0.5, 0]}}
ground:
  points: {O: [1000000000.0, 0]}
joints:
  O: {type: revolute, body_i: bar, point_i: O, body_j: ground, point_j: O}
drivers:
  motor: {type: angle, body: bar, function: "t"}
analyses:
  kinematics: {type: kinematic, drivers: [motor], t_end: 1, step: 0.1}
"#;
    let model = Model::from_yaml(far).unwrap();
    assert_ne!(model.q0()[0], 1e9 + 0.5, "the guess is off the assembled position");
    let r = model.run("kinematics", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let warnings = r.summary_json(None)["warnings"].to_string();
    assert!(warnings.contains("below what round-off allows"), "{warnings}");
    // Independent check: the pin stays at the ground point to the round-off of 1e9 m.
    let (x, y, phi) = (r.column("bar.x").unwrap(), r.column("bar.y").unwrap(), r.column("bar.phi").unwrap());
    for k in 0..r.len() {
        let (px, py) = (x[k] - 0.5 * phi[k].cos() - 1e9, y[k] - 0.5 * phi[k].sin());
        assert!(px.abs() < 1e-5 && py.abs() < 1e-5, "pin off by ({px:e}, {py:e}) at {k}");
    }
}

/// A massless wheel turning freely on its axle: no mass resists that motion, so the equations of
/// motion are singular: `linkwork check` and the dynamics both name the inertia field and the
/// coordinate (rather than a NaN solution of the equations of motion at t = 0). A massless connecting rod, carried by the massive crank and slider, still runs.
#[test]
fn a_massless_free_motion_is_named_before_the_dynamics_run() {
    let wheel = r#"
gravity: [0, -9.81]
bodies:
  wheel: {mass: 1.0, inertia: 0.0, position: [0, 0], angle: 0}
  bob: {mass: 1.0, inertia: 0.1, position: [1, 0], angle: 0, points: {P: [-1, 0]}}
joints:
  axle: {type: revolute, body_i: wheel, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
  pivot: {type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}
analyses:
  dyn: {type: dynamic, t_end: 0.5, step: 0.01}
"#;
    let model = Model::from_yaml(wheel).unwrap();
    let warning = check(&model).unwrap().analyses["dyn"].warning.clone().unwrap_or_default();
    assert!(warning.starts_with("bodies.wheel.inertia: wheel.phi can move with no mass or inertia"), "{warning}");
    let e = model.run("dyn", &Default::default()).unwrap_err().error;
    let Error::Model(problems) = &e else { panic!("expected a model error, got {e}") };
    assert_eq!(problems[0].path, "bodies.wheel.inertia", "{e}");
    assert!(problems[0].message.contains("wheel.phi can move with no mass or inertia"), "{e}");

    let massless_rod = patched_example(
        "slider_crank.yaml",
        &[
            ("{mass: 2.0, inertia: 0.015,", "{mass: 0.0, inertia: 0.0,"),
            (
                "kinematics: {type: kinematic, drivers: [motor], t_end: 2.0, step: 0.01}",
                "dyn: {type: dynamic, drivers: [], t_end: 0.2, step: 0.01}",
            ),
            ("name: slider-crank", "name: slider-crank\ngravity: [0, -9.81]"),
        ],
    );
    let model = Model::from_yaml(&massless_rod).unwrap();
    assert_eq!(check(&model).unwrap().analyses["dyn"].warning, None);
    let r = model.run("dyn", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    assert!(r.column("crank.phi").unwrap().iter().all(|x| x.is_finite()));
}

/// A driver whose position jumps (`2*pi*t + 0.5*(t > 0.5)`: half a radian at 0.5 s) cannot be
/// followed: Newton lands on the new position, farther than half the predicted motion, at every
/// sub-step down to the smallest: the driver is named with its jump (0.5 rad) and the time, not
/// reported as a position solution that did not converge with a residual of 0.
#[test]
fn a_driver_that_jumps_is_named_with_its_jump_and_time() {
    let model = crank_driven_by("2*pi*t + 0.5*(t > 0.5)", 1.0);
    let failure = model.run("kinematics", &Default::default()).expect_err("the jump cannot be followed");
    let message = failure.error.to_string();
    match &failure.error {
        Error::Jump { time, element, expression, jump, .. } => {
            assert_eq!((element.as_str(), expression.as_str()), ("drivers.motor", "2*pi*t + 0.5*(t > 0.5)"));
            // The jump and its time, to the smallest sub-step (1e-10 s) and the ramp over it.
            assert!((time - 0.5).abs() < 1e-9 && (jump - 0.5).abs() < 1e-8, "{message}");
        }
        other => panic!("expected the driver's jump, got {other}"),
    }
    assert!(message.contains("drivers.motor jumps by 5.000e-1 at t = 0.5 s"), "{message}");
    let last = *failure.results.time.last().unwrap();
    assert!((0.49..=0.5).contains(&last), "outputs up to the jump kept: the last at {last}");
}

/// The slider-crank example's crank turning at 1 rev/s over `t_end: 1e15` with outputs every `1e8` s (10 million points,
/// the most allowed) was stopped as "drivers.motor grows without bound": its rate never grows,
/// the output step asks for 6.3e8 rad between two outputs. Now the step is named. The same crank
/// started at `t_start: 1e15`, where double precision spaces times 0.125 s apart and the
/// sub-steps of 0.35 rad are 0.056 s, cannot advance the time: its round-off is named.
#[test]
fn a_huge_time_span_names_the_step_or_the_time_round_off() {
    let crank = |times: &str| {
        Model::from_yaml(&patch(&example_text("slider_crank.yaml"), "t_end: 2.0, step: 0.01", times)).unwrap()
    };
    let error =
        crank("t_end: 1e15, step: 1e8").run("kinematics", &Default::default()).expect_err("too long a step").error;
    let message = error.to_string();
    assert!(
        message.contains("analyses.kinematics.step: the output step 1e8 s is too long for the motion"),
        "{message}"
    );
    assert!(message.contains("drivers.motor (2*pi*t) moves 6.283e0 per second"), "{message}");
    assert!(!message.contains("without bound"), "{message}");

    // An output step finer than the spacing of doubles at the start is refused on loading.
    let late = Model::from_yaml(&patch(
        &example_text("slider_crank.yaml"),
        "t_end: 2.0, step: 0.01",
        "t_start: 1e15, t_end: 1000000000000010, step: 0.01",
    ));
    let message = late.expect_err("time round-off").to_string();
    assert!(message.contains("analyses.kinematics.t_start: time round-off at t = 1e+15 s"), "{message}");
    assert!(message.contains("1.250e-1 s apart, too coarse for steps of 1e-2 s"), "{message}");
}
