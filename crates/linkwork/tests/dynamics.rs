//! Dynamics against independent references: conservation of energy, closed-form accelerations,
//! Newton-Euler balances of the reported reactions, and a second formulation of a mechanism.

mod common;

use common::{col, energy_drift, integrators, patch, pendulum_with_torque};
use linkwork::analysis::dynamic::IntegratorKind;

/// The double pendulum's energy (about 15 J of motion) over 5 s at the default tolerances
/// (1e-6): a per-step error of 1e-6 over some 600 to 1300 steps bounds the drift near 1e-2 J.
/// Measured: bdf 1.8e-2 J (index 3), 8.4e-4 J (SI2, whose velocities are also under error
/// control), hht 2.7e-2 J (its numerical damping removes energy). Bounds: twice the
/// measurement, so that a lost order or a broken error test fails.
#[test]
fn double_pendulum_energy() {
    for (integrator, formulation, bound) in [("bdf", "index3", 4e-2), ("bdf", "si2", 2e-3), ("hht", "", 6e-2)] {
        let settings =
            if formulation.is_empty() { String::new() } else { format!(", solver: {{formulation: {formulation}}}") };
        let text = patch(
            &common::example_text("double_pendulum.yaml"),
            "dynamics: {type: dynamic, t_end: 5, step: 0.01}",
            &format!("dynamics: {{type: dynamic, integrator: {integrator}, t_end: 5, step: 0.01{settings}}}"),
        );
        let r = linkwork::Model::from_yaml(&text)
            .unwrap()
            .run("dynamics", &Default::default())
            .unwrap_or_else(|f| panic!("{}", f.error));
        // The run is the one patched in, not the file's default integrator and formulation.
        assert_eq!(r.summary_json(None)["integrator"]["kind"], integrator);
        if !formulation.is_empty() {
            assert_eq!(r.summary_json(None)["integrator"]["formulation"], formulation);
        }
        let drift = energy_drift(&r);
        eprintln!("{integrator} {formulation}: drift {drift:e} J, {}", r.summary_json(None)["statistics"]);
        assert!(drift < bound, "{integrator} {formulation}: drift {drift}");
    }
}

/// A four-bar under gravity with a motor torque, a spring-damper between the coupler and ground,
/// a rotational spring on the rocker and a follower force on the coupler; one variant drives the
/// crank so that a driver effort appears, and one flips the first joint to ground-first.
fn loaded_fourbar(driven: bool) -> String {
    let base = common::example_text("fourbar.yaml");
    let base = base.split("drivers:").next().unwrap().to_string();
    let base = patch(
        &base,
        "  O4: {type: revolute, body_i: rocker, point_i: O4, body_j: ground, point_j: O4}",
        "  O4: {type: revolute, body_i: ground, point_i: O4, body_j: rocker, point_j: O4}",
    );
    let analysis = if driven {
        "  dynamics: {type: dynamic, integrator: hht, drivers: [motor], t_end: 0.5, step: 0.05}"
    } else {
        "  dynamics: {type: dynamic, integrator: hht, drivers: [], t_end: 0.5, step: 0.05}"
    };
    format!(
        "{base}gravity: [0, -9.81]
drivers:
  motor: {{type: angle, body: crank, function: \"2*t + 0.3*sin(3*t)\"}}
forces:
  motor_torque: {{type: torque, body: crank, torque: \"0.4 - 0.05*crank.omega\"}}
  spring: {{type: spring_damper, body_i: coupler, point_i: [0.05, 0.02], body_j: ground, point_j: [0.1, 0.4], stiffness: 40, damping: 0.3, free_length: 0.2}}
  torsion: {{type: rotational_spring_damper, body_i: rocker, body_j: ground, stiffness: 0.5, damping: 0.01}}
  push: {{type: force, body: coupler, point: B, frame: body, fx: 0.7, fy: \"-0.2*t\"}}
analyses:
{analysis}
"
    )
}

/// Reactions from the multipliers against a Newton-Euler balance of every body: at each output
/// time, `m a = sum of joint forces + applied forces + m g` and `J alpha = sum of moments about
/// the centre of mass`, with each joint's force on its second body the opposite of the reported
/// force on its first body. The applied loads come from the force elements, the joint forces from
/// the `<joint>.fx, .fy, .torque` columns (moments about the joint's point, moved to each centre of
/// mass here). Tolerance `1e-8` relative to the largest force: both sides come from one linear
/// solve at the output state, so only rounding separates them.
#[test]
fn reactions_balance_every_body() {
    for driven in [false, true] {
        let model = linkwork::Model::from_yaml(&loaded_fourbar(driven)).unwrap();
        let r = model.run("dynamics", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
        let g = model.gravity;
        for k in 0..r.len() {
            let at = |name: &str| col(&r, name)[k];
            let q: Vec<f64> =
                model.bodies.iter().flat_map(|b| ["x", "y", "phi"].map(|c| at(&format!("{}.{c}", b.name)))).collect();
            let v: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| ["vx", "vy", "omega"].map(|c| at(&format!("{}.{c}", b.name))))
                .collect();
            let t = r.time[k];
            // Residual per body: m a - (applied + joint forces), J alpha - moments.
            let mut res: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| {
                    let a = ["ax", "ay", "alpha"].map(|c| at(&format!("{}.{c}", b.name)));
                    [b.mass * a[0] - b.mass * g[0], b.mass * a[1] - b.mass * g[1], b.inertia * a[2]]
                })
                .collect();
            let mut scale = 1.0f64;
            for f in &model.forces {
                let cols = f.force.columns();
                let x: Vec<f64> = cols.iter().map(|&c| q[c]).collect();
                let xv: Vec<f64> = cols.iter().map(|&c| v[c]).collect();
                let mut out = vec![0.0; cols.len()];
                f.force.load(&x, &xv, t, &mut out);
                for (&c, &val) in cols.iter().zip(&out) {
                    res[c] -= val;
                    scale = scale.max(val.abs());
                }
            }
            for j in &model.joints {
                let anchor = j.constraint.anchor();
                let f = [at(&format!("{}.fx", j.name)), at(&format!("{}.fy", j.name))];
                let torque = at(&format!("{}.torque", j.name));
                scale = scale.max(f[0].abs()).max(f[1].abs());
                // The joint's point in the global frame.
                let p = match anchor.i.0 {
                    Some(b) => {
                        let (s, c) = q[b + 2].sin_cos();
                        let sp = anchor.point;
                        [q[b] + c * sp[0] - s * sp[1], q[b + 1] + s * sp[0] + c * sp[1]]
                    }
                    None => anchor.point,
                };
                // Force-moment systems: (f, torque about p) on i, the opposite on j.
                for (body, sign) in [(anchor.i, 1.0), (anchor.j, -1.0)] {
                    let Some(b) = body.0 else { continue };
                    let d = [p[0] - q[b], p[1] - q[b + 1]];
                    let (fx, fy) = (sign * f[0], sign * f[1]);
                    res[b] -= fx;
                    res[b + 1] -= fy;
                    res[b + 2] -= sign * torque + d[0] * fy - d[1] * fx;
                }
            }
            if driven {
                // The angle driver's effort is a torque on the crank (body 0).
                res[2] -= at("motor.effort");
            }
            let worst = res.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(worst < 1e-8 * scale, "driven {driven}, t = {t}: Newton-Euler residual {worst:e} (scale {scale})");
        }
        if driven {
            assert!(col(&r, "motor.effort").iter().any(|e| e.abs() > 1e-3), "the motor works");
        }
    }
}

/// A bar pinned off its centre of mass and turned by a linear rotational spring: `J_O phi'' =
/// -k phi` exactly, `phi = 0.5 cos(2 t)` (see the crate's order tests for the derivation).
fn torsion_bar(integrator: &str, settings: &str) -> String {
    format!(
        "
name: pinned bar on a torsion spring
bodies:
  bar: {{mass: 2, inertia: 0.5, position: [0.43879128094518, 0.23971276930210], angle: 0.5, points: {{O: [-0.5, 0]}}, given: [phi]}}
joints:
  O: {{type: revolute, body_i: bar, point_i: O, body_j: ground, point_j: [0, 0]}}
forces:
  spring: {{type: rotational_spring_damper, body_i: bar, body_j: ground, stiffness: 4, free_angle: 0}}
analyses:
  dynamics: {{type: dynamic, integrator: {integrator}, t_end: 10, step: 0.1, solver: {{{settings}}}}}
"
    )
}

/// The global error follows the tolerance: over ten periods of the torsion bar, tightening
/// rtol = atol by 100 must shrink the largest angle error by at least 5. Error control is per
/// step, so the global error is near `N tol` with `N` the steps, which grow as tol^(-1/(k+1)):
/// theory gives factors of 21 (hht, order 2) to 46 (order 5). Measured (tol 1e-4, 1e-6, 1e-8):
/// bdf 2.0e-3, 3.0e-5, 4.7e-6 (index-3 BDF5 meets the floor of the order tests near 1e-6; with
/// max_order 4: 5.6e-3, 2.6e-4, 6.1e-6); bdf si2 8.2e-4, 4.1e-5, 7.9e-7; hht 2.0e-2, 1.0e-3,
/// 6.3e-5 (its numerical damping adds a phase and amplitude error the local estimate does not
/// see). The error must also stay within `bound * tol`: 1000 for bdf, 10^4 for hht.
#[test]
fn error_follows_the_tolerance() {
    for (integrator, extra, bound) in [("bdf", "", 1e3), ("bdf", ", formulation: si2", 1e3), ("hht", "", 1e4)] {
        let errors: Vec<f64> = [1e-4, 1e-6, 1e-8]
            .iter()
            .map(|tol| {
                let text = torsion_bar(integrator, &format!("rtol: {tol}, atol: {tol}{extra}"));
                let r = linkwork::Model::from_yaml(&text)
                    .unwrap()
                    .run("dynamics", &Default::default())
                    .unwrap_or_else(|f| panic!("{}", f.error));
                let phi = col(&r, "bar.phi");
                let e = r.time.iter().zip(phi).map(|(t, p)| (p - 0.5 * (2.0 * t).cos()).abs()).fold(0.0, f64::max);
                assert!(e < bound * tol, "{integrator}{extra} tol {tol}: error {e}");
                e
            })
            .collect();
        eprintln!("{integrator}{extra}: errors {errors:?}");
        for w in errors.windows(2) {
            assert!(w[1] < w[0] / 5.0, "{integrator}{extra}: errors {errors:?}");
        }
    }
}

/// HHT with `alpha = 0` (the trapezoidal rule, no damping) on Andrews' stiff mechanism: the
/// undamped oscillation of the index-3 accelerations drives the step down through accepted
/// steps. The run must stop with a typed error naming the time, soon, not creep on for millions
/// of steps (before the smallest-step check covered accepted steps it ran to the 5-million-step
/// limit, the step near 1e-84 s).
#[test]
fn a_vanishing_step_stops_the_run() {
    let text = patch(
        &common::example_text("andrews.yaml"),
        "solver: {rtol: 1e-8, atol: 1e-8}",
        "integrator: hht\n    solver: {rtol: 1e-9, atol: 1e-9, alpha: 0}",
    );
    let model = linkwork::Model::from_yaml(&text).unwrap();
    let failure = model.run("dynamics", &Default::default()).expect_err("the undamped run cannot finish");
    match failure.error {
        linkwork::Error::Integration { time, step, .. } => {
            assert!(time > 0.0 && time < 0.03 && step < 1e-15, "t {time}, step {step}");
            // The results up to the failure are kept.
            let last = failure.results.time.last().copied().unwrap_or(-1.0);
            assert!(failure.results.len() > 1 && last <= time, "{} outputs to {last}", failure.results.len());
        }
        other => panic!("expected an integration error, got {other}"),
    }
}

/// `model`'s `dynamics` run with each integrator, each of which must stop (`why`): the
/// integrator, its failure and the failure's message.
fn stops(model: &linkwork::Model, why: &str) -> Vec<(IntegratorKind, linkwork::Failure, String)> {
    let stop = |(_, integrator)| {
        let o = linkwork::Overrides { integrator: Some(integrator), ..Default::default() };
        let failure = *model.run("dynamics", &o.clone().into()).expect_err(why);
        let message = failure.error.to_string();
        (integrator, failure, message)
    };
    integrators().map(stop).collect()
}

/// A torque that turns NaN between output times, `sqrt(0.503 - t)`: its rate grows without
/// bound, but its value goes to 0 and is NaN past 0.503 s, so every integrator stops there saying
/// it is NaN, naming it and its expression (not a torque that grows without bound).
#[test]
fn a_torque_that_turns_nan_inside_a_step_is_named() {
    let model = pendulum_with_torque("kick", "sqrt(0.503-t)", 0.01);
    for (integrator, failure, message) in stops(&model, "NaN past t = 0.503 s") {
        let linkwork::Error::NonFinite { time, element, expression, value } = &failure.error else {
            panic!("{integrator:?}: expected a NaN force, got {message}")
        };
        assert!((time - 0.503).abs() < 1e-9 && value.is_nan(), "{integrator:?}: {message}");
        assert_eq!((element.as_str(), expression.as_str()), ("forces.kick", "torque: sqrt(0.503-t)"));
        assert_eq!(failure.results.len(), 51, "{integrator:?}: outputs at 0 to 0.5 kept");
    }
}

/// A torque that is NaN at one instant, `(t - 0.5) / abs(t - 0.5)` (0/0 at t = 0.5 s, an output
/// time of a 0.1 s grid): with every integrator the run stops at 0.5 s with a `NonFinite` error
/// naming the force and its expression, rather than running to the end with status ok and NaN in
/// the accelerations and reactions there; the results before it are kept and hold no NaN.
#[test]
fn a_nan_torque_stops_the_run_naming_it() {
    let model = pendulum_with_torque("flip", "(t-0.5)/abs(t-0.5)", 0.1);
    for (integrator, failure, message) in stops(&model, "NaN at t = 0.5 s") {
        match &failure.error {
            linkwork::Error::NonFinite { time, element, expression, value } => {
                assert!((time - 0.5).abs() < 1e-12, "{integrator:?}: {message}");
                assert_eq!(element, "forces.flip", "{integrator:?}");
                assert_eq!(expression, "torque: (t-0.5)/abs(t-0.5)", "{integrator:?}");
                assert!(value.is_nan(), "{integrator:?}: {value}");
            }
            other => panic!("{integrator:?}: expected a non-finite error, got {other}"),
        }
        let r = &failure.results;
        assert_eq!(r.len(), 5, "{integrator:?}: outputs at 0 to 0.4 kept");
        for (name, column) in r.names.iter().zip(&r.columns) {
            assert!(column.iter().all(|x| x.is_finite()), "{integrator:?}: {name}");
        }
    }
}

/// A torque with a pole between output times, `1/(t - 0.503)`, cannot be integrated through:
/// the velocity grows like `ln|t - 0.503|` on both sides, so what follows the pole is not
/// determined. Every integrator stops there naming the torque, its expression and its rate
/// (not the joint, "rows involved: O.y"), with the outputs before it kept; `hht` too, whose error
/// test measures positions, which a logarithmic velocity hardly moves (a step of `2.3e-7` s
/// straddling the pole would pass it).
#[test]
fn a_torque_with_a_pole_stops_the_run_naming_it() {
    let model = pendulum_with_torque("kick", "1/(t-0.503)", 0.01);
    for (integrator, failure, message) in stops(&model, "a pole at t = 0.503 s") {
        match &failure.error {
            linkwork::Error::Unbounded { time, element, expression, rate, .. } => {
                // The failure is at the smallest step, 16 units of round-off of t, from the pole.
                assert!((time - 0.503).abs() < 1e-9, "{integrator:?}: {message}");
                assert_eq!(element, "forces.kick", "{integrator:?}");
                assert_eq!(expression, "torque: 1/(t-0.503)", "{integrator:?}");
                assert!(*rate > 1e20, "{integrator:?}: {message}");
            }
            other => panic!("{integrator:?}: expected an unbounded force, got {other}"),
        }
        let r = &failure.results;
        assert_eq!(r.len(), 51, "{integrator:?}: outputs at 0 to 0.5 kept");
    }
}

/// A pendulum under a gravity of 9.2e18 m/s^2 (a mutated example, found by the fuzzer, `fuzz/`)
/// swings at 3e9 rad/s: 0.03 s of it takes more steps than the budget, and spending the default
/// budget of 5 million took two minutes. A caller that lowers it (`IntegratorSettings::
/// max_steps`) has the budget's error after that many steps, with every integrator.
#[test]
fn a_lowered_step_budget_stops_the_run_at_it() {
    let text = "gravity: [9223372036854775807, -9.81]\n\
                bodies:\n  P1: {mass: 1, inertia: 0, position: [-1, 0], angle: 3.141592653589793, points: {pivot: [-1, 0]}}\n\
                joints:\n  pivot: {type: revolute, body_i: P1, point_i: pivot, body_j: ground, point_j: [0, 0]}\n\
                analyses:\n  dynamics: {type: dynamic, t_end: 0.03, step: 0.01}\n";
    let mut model = linkwork::Model::from_yaml(text).unwrap();
    model.analyses["dynamics"].integrator.max_steps = 1000;
    for (integrator, failure, message) in stops(&model, "3e9 rad/s for 0.03 s") {
        eprintln!("{integrator:?}: {message}");
        assert!(matches!(failure.error, linkwork::Error::Integration { .. }), "{integrator:?}: {message}");
        assert!(message.contains("more than 1000 steps (the step budget)"), "{integrator:?}: {message}");
    }
}
