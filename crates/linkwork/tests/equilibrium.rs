//! Statics, inverse dynamics, redundant supports and modes against closed forms, virtual work
//! and hand derivations.

mod common;

use common::{col, patch, SLIDER_CRANK_JOINTS};
use linkwork::{Error, Model, Results};

fn run(yaml: &str, analysis: &str) -> Results {
    let model = Model::from_yaml(yaml).unwrap_or_else(|e| panic!("{e}"));
    model.run(analysis, &Default::default()).unwrap_or_else(|f| panic!("{}", f.error))
}

/// A centred slider-crank (crank r = 0.1, rod L = 0.3) with a force `P` along the guide on the
/// slider, the crank held by an angle driver at `theta = 0.3 + t`, `t` in 0..1.
fn slider_crank(extra_bodies: &str, forces: &str, analysis: &str) -> String {
    format!(
        r#"
gravity: [0, 0]
bodies:
  crank: {{mass: 1.0, inertia: 0.001, position: [0.05, 0.01], angle: 0.3, points: {{O: [-0.05, 0], A: [0.05, 0]}}}}
  rod: {{mass: 2.0, inertia: 0.015, position: [0.24, 0.01], angle: -0.1, points: {{A: [-0.15, 0], B: [0.15, 0]}}}}
  slider: {{mass: 1.5, inertia: 0.001, position: [0.38, 0.0], angle: 0.0}}
{extra_bodies}
{SLIDER_CRANK_JOINTS}drivers:
  motor: {{type: angle, body: crank, function: "0.3 + t"}}
forces:
{forces}
analyses:
{analysis}
"#
    )
}

/// Virtual work on the slider-crank: the crank torque that holds a force `P` on the slider is
/// `M = -P dx/dtheta`, `x = r cos(theta) + sqrt(L^2 - r^2 sin^2(theta))`. Quasi-static at five
/// crank angles. Tolerance 1e-9 relative to `P r`: the force balance converges to 1e-10 of the
/// load, the rest is rounding.
#[test]
fn slider_crank_torque_is_virtual_work() {
    let p = -250.0;
    let yaml = slider_crank(
        "",
        &format!("  push: {{type: force, body: slider, fx: {p}}}"),
        "  hold: {type: static, drivers: [motor], t_end: 1.0, step: 0.25}",
    );
    let r = run(&yaml, "hold");
    assert_eq!(r.len(), 5);
    let (rc, l) = (0.1f64, 0.3f64);
    for (k, &t) in r.time.iter().enumerate() {
        let th = 0.3 + t;
        let s = (l * l - rc * rc * th.sin().powi(2)).sqrt();
        let dx = -rc * th.sin() - rc * rc * th.sin() * th.cos() / s;
        let want = -p * dx;
        let got = col(&r, "motor.effort")[k];
        assert!((got - want).abs() <= 1e-9 * (p * rc).abs(), "t = {t}: {got} vs {want}");
        assert!((col(&r, "slider.x")[k] - (rc * th.cos() + s)).abs() < 1e-11);
    }
}

/// The ellipse trammel (bar of 1 m, ends A on the x-axis and B on the y-axis, `A = (cos psi, 0)`,
/// `B = (0, -sin psi)`) with a force `Fx` on A and `Fy` on B rests where the virtual work
/// `-Fx sin(psi) - Fy cos(psi)` vanishes: `tan(psi) = -Fy / Fx`. The reactions of the guides
/// balance the forces (the guides carry only normal forces).
#[test]
fn ellipse_trammel_rests_where_the_virtual_work_vanishes() {
    let model = Model::load(format!("{}/../../examples/ellipse_trammel.yaml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let r = model.run("equilibrium", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let (fx, fy) = (30.0f64, -40.0f64);
    let psi = col(&r, "bar.phi")[0];
    assert!((psi - (-fy / fx).atan()).abs() < 1e-10, "psi = {psi}");
    // The guide of A (ground first) pushes A vertically only: its reaction on ground balances it.
    assert!(col(&r, "guide_a.fx")[0].abs() < 1e-8, "{}", col(&r, "guide_a.fx")[0]);
    assert!(col(&r, "guide_b.fy")[0].abs() < 1e-8, "{}", col(&r, "guide_b.fy")[0]);
    assert_eq!(r.summary_json(None)["stable"], serde_json::json!(true));
}

/// A four-bar (ground pivots O = (0, 0) and C = (d, 0); crank a, coupler b, rocker c) with a
/// rotational spring on the crank (k, free angle theta0) and a downward force F at the rocker's
/// tip B. Equilibrium by virtual work: `k (theta - theta0) = -F dy_B/dtheta` with
/// `dy_B/dtheta = c cos(psi) dpsi/dtheta` and, from the loop closure
/// `a e^{i theta} + b e^{i beta} = d + c e^{i psi}`, `dpsi/dtheta = a sin(theta - beta) / (c sin(psi - beta))`.
/// Modes about it: one degree of freedom, `omega^2 = V''(theta) / M(theta)` with the generalised
/// mass from the same kinematic coefficients (`dbeta/dtheta = a sin(theta - psi) / (b sin(psi - beta))`)
/// and `V''` from the derivative of `dy_B/dtheta`, by a central difference of the closed form
/// (step 1e-5: error ~1e-10).
const SPRING_FOURBAR: &str = r#"
gravity: [0, 0]
bodies:
  crank: {mass: 2.0, inertia: 0.04, position: [0.2, 0.3], angle: 1.0, points: {O: [-0.25, 0], A: [0.25, 0]}}
  coupler: {mass: 3.0, inertia: 0.1, position: [0.8, 0.6], angle: 0.0, points: {A: [-0.5, 0], B: [0.5, 0]}}
  rocker: {mass: 2.5, inertia: 0.08, position: [1.1, 0.3], angle: 1.4, points: {C: [-0.35, 0], B: [0.35, 0]}}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
  A: {type: revolute, body_i: crank, point_i: A, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: coupler, point_i: B, body_j: rocker, point_j: B}
  C: {type: revolute, body_i: rocker, point_i: C, body_j: ground, point_j: [1.0, 0]}
forces:
  spring: {type: rotational_spring_damper, body_i: crank, body_j: ground, stiffness: 400, free_angle: 1.2}
  load: {type: force, body: rocker, point: B, fy: -300}
analyses:
  rest: {type: static}
  vibration: {type: modes}
"#;

/// `(psi, beta, dpsi/dtheta, dbeta/dtheta)` of the four-bar of [`SPRING_FOURBAR`] at crank
/// angle `theta`, on the assembly branch with B above the ground line.
fn fourbar(theta: f64) -> (f64, f64, f64, f64) {
    let (a, b, c, d) = HANGING;
    let ([ax, ay], [bx, by]) = match loop_closure(theta, 1.0) {
        ([ax, ay], [bx, by]) if by > 0.0 => ([ax, ay], [bx, by]),
        _ => loop_closure(theta, -1.0),
    };
    let psi = (by).atan2(bx - d);
    let beta = (by - ay).atan2(bx - ax);
    let dpsi = a * (theta - beta).sin() / (c * (psi - beta).sin());
    let dbeta = a * (theta - psi).sin() / (b * (psi - beta).sin());
    (psi, beta, dpsi, dbeta)
}

#[test]
fn spring_fourbar_rests_by_virtual_work_and_vibrates_as_derived() {
    let (k, theta0, f, a, b, c) = (400.0f64, 1.2f64, 300.0f64, 0.5f64, 1.0f64, 0.7f64);
    let r = run(SPRING_FOURBAR, "rest");
    let theta = col(&r, "crank.phi")[0];
    let dyb = |th: f64| {
        let (psi, _, dpsi, _) = fourbar(th);
        c * psi.cos() * dpsi
    };
    let balance = k * (theta - theta0) + f * dyb(theta);
    assert!(balance.abs() < 1e-8 * k * (theta - theta0).abs(), "virtual work residual {balance} at theta {theta}");
    let (psi, beta, _, _) = fourbar(theta);
    assert!((col(&r, "rocker.phi")[0] - psi).abs() < 1e-10 && (col(&r, "coupler.phi")[0] - beta).abs() < 1e-10);

    // Modes: generalised mass and stiffness at the equilibrium.
    let (_, _, dpsi, dbeta) = fourbar(theta);
    let (m1, j1, m2, j2, m3, j3) = (2.0, 0.04, 3.0, 0.1, 2.5, 0.08);
    // Coupler centre of mass: A + (b/2) e^{i beta}; its velocity per unit crank rate.
    let vx = -a * theta.sin() - 0.5 * b * dbeta * beta.sin();
    let vy = a * theta.cos() + 0.5 * b * dbeta * beta.cos();
    let mass =
        m1 * a * a / 4.0 + j1 + m2 * (vx * vx + vy * vy) + j2 * dbeta * dbeta + (m3 * c * c / 4.0 + j3) * dpsi * dpsi;
    let h = 1e-5;
    let stiffness = k + f * (dyb(theta + h) - dyb(theta - h)) / (2.0 * h);
    let want = (stiffness / mass).sqrt() / (2.0 * std::f64::consts::PI);
    let modes = run(SPRING_FOURBAR, "vibration");
    let list = modes.summary.modes.as_deref().unwrap();
    assert_eq!(list.len(), 1);
    let got = list[0].frequency.unwrap();
    assert!((got - want).abs() < 1e-7 * want, "{got} Hz vs {want} Hz");
    assert!((col(&modes, "crank.phi")[0] - theta).abs() < 1e-10);
}

/// A door (10 kg, 1 m wide, centre of mass midway between its hinges) hung on two hinges 2 m
/// apart on a vertical line: the vertical loads are indeterminate (one redundant row), and the
/// minimum-norm reactions share the weight equally; the horizontal ones are determinate, the
/// couple `m g (w / 2) / 2 m` that holds the door's moment.
#[test]
fn symmetric_door_hinges_share_the_weight() {
    let yaml = r#"
gravity: [0, -9.81]
bodies:
  door: {mass: 10, inertia: 4.2, position: [0.5, 1.0], angle: 0, points: {low: [-0.5, -1.0], high: [-0.5, 1.0]}}
joints:
  lower: {type: revolute, body_i: door, point_i: low, body_j: ground, point_j: [0, 0]}
  upper: {type: revolute, body_i: door, point_i: high, body_j: ground, point_j: [0, 2]}
analyses:
  hang: {type: static}
"#;
    let r = run(yaml, "hang");
    let w = 10.0 * 9.81;
    for j in ["lower", "upper"] {
        assert!((col(&r, &format!("{j}.fy"))[0] - w / 2.0).abs() < 1e-10 * w, "{j}");
    }
    assert!((col(&r, "lower.fx")[0] - w * 0.5 / 2.0).abs() < 1e-10 * w);
    assert!((col(&r, "upper.fx")[0] + w * 0.5 / 2.0).abs() < 1e-10 * w);
    assert_eq!(r.summary_json(None)["indeterminate_joints"], serde_json::json!(["lower", "upper"]));
    let model = Model::from_yaml(yaml).unwrap();
    let check = linkwork::analysis::check(&model).unwrap();
    assert_eq!(check.mechanism.indeterminate, ["lower", "upper"]);
}

/// Small oscillations of a simple pendulum (a point mass: a body with no inertia about its centre
/// of mass, pinned at `L` from it) and a compound one (a uniform rod about its end):
/// `omega = sqrt(g / L)` and `sqrt(3 g / (2 L))`, about the equilibrium found from a guess 0.4 rad
/// off. Tolerance 1e-9: the geometric stiffness is a central difference (~1e-10), the eigenvalues
/// are exact to rounding.
#[test]
fn pendulum_frequencies_are_the_closed_forms() {
    let (g, l) = (9.81f64, 1.5f64);
    for (inertia, arm, want) in [(0.0, l, (g / l).sqrt()), (4.0 * l * l / 12.0, l / 2.0, (1.5 * g / l).sqrt())] {
        let yaml = format!(
            r#"
gravity: [0, -{g}]
bodies:
  bob: {{mass: 4.0, inertia: {inertia}, position: [0.6, -{arm}], angle: 0.4, points: {{P: [0, {arm}]}}}}
joints:
  pivot: {{type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}}
analyses:
  small: {{type: modes}}
"#
        );
        let r = run(&yaml, "small");
        let modes = r.summary.modes.as_deref().unwrap();
        assert_eq!(modes.len(), 1);
        let got = 2.0 * std::f64::consts::PI * modes[0].frequency.unwrap();
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
        assert!(col(&r, "bob.phi")[0].abs() < 1e-12, "hangs straight down");
    }
}

/// A slider (m) on a horizontal guide held by a spring-damper (k, c) to ground: one mode with
/// `omega_n = sqrt(k / m)` and `zeta = c / (2 sqrt(k m))`, through the first-order eigenproblem.
#[test]
fn spring_mass_slider_has_the_closed_form_frequency_and_damping() {
    let (m, k, c) = (2.0f64, 800.0f64, 12.0f64);
    let yaml = format!(
        r#"
gravity: [0, -9.81]
bodies:
  block: {{mass: {m}, inertia: 0.01, position: [0.3, 0], angle: 0}}
joints:
  guide: {{type: translational, body_i: ground, point_i: [0, 0], axis_i: [1, 0], body_j: block, point_j: [0, 0], axis_j: [1, 0]}}
forces:
  spring: {{type: spring_damper, body_i: ground, point_i: [-1, 0], body_j: block, point_j: [0, 0], stiffness: {k}, damping: {c}, free_length: 1.2}}
analyses:
  shake: {{type: modes}}
"#
    );
    let r = run(&yaml, "shake");
    let modes = r.summary.modes.as_deref().unwrap();
    assert_eq!(modes.len(), 1, "{modes:?}");
    let wn = 2.0 * std::f64::consts::PI * modes[0].frequency.unwrap();
    let zeta = modes[0].damping_ratio.unwrap();
    assert!((wn - (k / m).sqrt()).abs() < 1e-10 * wn, "{wn}");
    assert!((zeta - c / (2.0 * (k * m).sqrt())).abs() < 1e-10, "{zeta}");
    assert!((col(&r, "block.x")[0] - 0.2).abs() < 1e-12, "rest at the free length");
    assert_eq!(modes[0].shape["block.x"], 1.0);
}

/// Inverse dynamics of a slider-crank under gravity, a spring-damper on the slider and a torque
/// on the crank, driven at `theta = 0.3 + t`: at every output time the motor's power equals
/// `dT/dt + dV_gravity/dt` minus the power of the applied forces, each computed here from the
/// body columns alone (`dT/dt = sum m v.a + J omega alpha`). Tolerance 1e-8 relative to the
/// largest term: the multipliers are exact solutions of a linear system, so only rounding remains.
#[test]
fn inverse_dynamics_balances_power() {
    let (k, c, x0, torque) = (500.0, 20.0, 0.3, 7.0);
    let yaml = slider_crank(
        "",
        &format!(
            "  spring: {{type: spring_damper, body_i: ground, point_i: [0, 0], body_j: slider, point_j: [0, 0], stiffness: {k}, damping: {c}, free_length: {x0}}}\n  drag: {{type: torque, body: crank, torque: \"{torque}*cos(3*t)\"}}"
        ),
        "  drive: {type: inverse, drivers: [motor], t_end: 2.0, step: 0.1}",
    );
    let yaml = patch(&yaml, "gravity: [0, 0]", "gravity: [0, -9.81]");
    let r = run(&yaml, "drive");
    let bodies = [("crank", 1.0, 0.001), ("rod", 2.0, 0.015), ("slider", 1.5, 0.001)];
    for (i, &t) in r.time.iter().enumerate() {
        let v = |b: &str, q: &str| col(&r, &format!("{b}.{q}"))[i];
        let (mut dt, mut dv, mut kinetic, mut height) = (0.0, 0.0, 0.0, 0.0);
        for (b, m, j) in bodies {
            dt += m * (v(b, "vx") * v(b, "ax") + v(b, "vy") * v(b, "ay")) + j * v(b, "omega") * v(b, "alpha");
            dv += m * 9.81 * v(b, "vy");
            kinetic += 0.5 * (m * (v(b, "vx").powi(2) + v(b, "vy").powi(2)) + j * v(b, "omega").powi(2));
            height += m * 9.81 * v(b, "y");
        }
        let (x, vx) = (v("slider", "x"), v("slider", "vx"));
        // The energy columns: T, and V of gravity plus the spring (its length is |x| on the guide).
        assert!((col(&r, "kinetic_energy")[i] - kinetic).abs() < 1e-12 * kinetic.max(1.0));
        let potential = height + 0.5 * k * (x.abs() - x0).powi(2);
        assert!((col(&r, "potential_energy")[i] - potential).abs() < 1e-12 * potential.abs().max(1.0));
        let applied = (-k * (x - x0) - c * vx) * vx + torque * (3.0 * t).cos() * v("crank", "omega");
        let motor = col(&r, "motor.effort")[i] * v("crank", "omega");
        let scale = dt.abs().max(dv.abs()).max(applied.abs()).max(1.0);
        assert!((motor - (dt + dv - applied)).abs() < 1e-8 * scale, "t = {t}: {motor} vs {}", dt + dv - applied);
        assert!((col(&r, "driver_power")[i] - motor).abs() < 1e-9 * scale);
        assert!((col(&r, "applied_power")[i] - applied).abs() < 1e-12 * scale);
    }
    let peak = &r.summary_json(None)["peaks"]["motor.effort"];
    let max = col(&r, "motor.effort").iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert_eq!(peak["max_abs"].as_f64().unwrap(), max);
}

/// Bad input: a static (or modes) analysis of a mechanism free to move with nothing to hold it,
/// and an inverse analysis of a model that is not fully driven, each get a model error naming the cause.
#[test]
fn statics_and_inverse_refuse_what_they_cannot_solve() {
    let free =
        slider_crank("", "  none: {type: torque, body: crank, torque: 0}", "  rest: {type: static, drivers: []}");
    let model = Model::from_yaml(&free).unwrap();
    let e = model.run("rest", &Default::default()).unwrap_err().error.to_string();
    assert!(e.contains("analyses.rest") && e.contains("free to move") && e.contains("crank.phi"), "{e}");
    // A modes analysis about the equilibrium names itself, not "a static analysis".
    let free_modes =
        slider_crank("", "  none: {type: torque, body: crank, torque: 0}", "  shake: {type: modes, drivers: []}");
    let e = Model::from_yaml(&free_modes).unwrap().run("shake", &Default::default()).unwrap_err().error.to_string();
    assert!(e.contains("analyses.shake: a modes analysis needs every degree of freedom held"), "{e}");
    assert!(!e.contains("static"), "{e}");
    let undriven = slider_crank(
        "",
        "  none: {type: torque, body: crank, torque: 0}",
        "  inv: {type: inverse, drivers: [], t_end: 1, step: 0.1}",
    );
    let model = Model::from_yaml(&undriven).unwrap();
    let e = model.run("inv", &Default::default()).unwrap_err().error.to_string();
    assert!(e.contains("analyses.inv.drivers") && e.contains("an inverse analysis needs a fully driven model"), "{e}");
}

/// A pendulum under a torque larger than its weight can hold (`T = 20 N m > m g L = 9.81 N m`)
/// has no equilibrium: the torque turns it downhill without end. The solver marches along that
/// path a bounded distance and stops with `NoEquilibrium`, naming the coordinate that turns and
/// no joint (a body is not a joint), instead of a wrong answer or a hang; the summary says
/// `stable: false` with no index.
#[test]
fn no_equilibrium_is_an_error_not_an_answer() {
    let yaml = r#"
gravity: [0, -9.81]
bodies:
  bob: {mass: 1.0, inertia: 0.0, position: [0, -1], angle: 0, points: {P: [0, 1]}}
joints:
  pivot: {type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}
forces:
  twist: {type: torque, body: bob, torque: 20}
analyses:
  rest: {type: static}
"#;
    let model = Model::from_yaml(yaml).unwrap();
    let failure = model.run("rest", &Default::default()).unwrap_err();
    match &failure.error {
        linkwork::Error::NoEquilibrium { time, index, coordinates, .. } => {
            assert_eq!(*time, 0.0);
            assert_eq!(*index, None);
            assert!(coordinates.contains(&"bob.phi".to_string()), "{coordinates:?}");
        }
        other => panic!("expected a NoEquilibrium error, got {other}"),
    }
    let message = failure.error.to_string();
    assert!(message.contains("no stable static equilibrium found") && message.contains("none exists"), "{message}");
    assert!(failure.error.elements().is_empty(), "{:?}", failure.error.elements());
    assert!(failure.results.is_empty());
    assert_eq!(failure.results.summary_json(None)["stable"], serde_json::json!(false));
    assert!(failure.results.summary_json(None)["index"].is_null());
}

/// An equilibrium left unbalanced in a body coordinate's force balance names that coordinate,
/// and no joint: `elements()` (the Python `joints`, the command line's "in joint(s)") lists
/// joints and drivers only: a four-bar's unbalanced `coupler.phi` is not reported "in joint(s)
/// coupler".
#[test]
fn an_unbalanced_body_coordinate_is_not_a_joint() {
    let e = linkwork::Error::Equilibrium {
        time: 0.0,
        residual: 0.16,
        equation: linkwork::Unbalanced::Coordinate("coupler.phi".into()),
        iterations: 77,
        load_fraction: 0.0,
    };
    assert!(e.elements().is_empty());
    assert!(e.to_string().contains("largest in the force balance of coupler.phi"), "{e}");
    let row = linkwork::RowName { element: "B".into(), equation: "x".into() };
    let e = linkwork::Error::Equilibrium {
        time: 0.0,
        residual: 0.16,
        equation: linkwork::Unbalanced::Row(row),
        iterations: 77,
        load_fraction: 0.0,
    };
    assert_eq!(e.elements(), ["B"]);
}

/// The spring four-bar under a load three times larger against a spring four times softer: Newton
/// from the guess finds a stationary point where the load has turned the rocker over (unstable),
/// so the solver descends from it along its negative curvature and rests on the stable branch,
/// without load stepping. Checked by virtual work and by the sign of `V''` from the closed form,
/// as above.
#[test]
fn descent_leaves_the_unstable_equilibrium_for_the_stable_one() {
    let (k, theta0, f, c) = (100.0f64, 1.2f64, 1000.0f64, 0.7f64);
    let yaml = patch(&patch(SPRING_FOURBAR, "stiffness: 400", "stiffness: 100"), "fy: -300", "fy: -1000");
    let r = run(&yaml, "rest");
    assert_eq!(r.summary_json(None)["statistics"]["descents"], serde_json::json!(1));
    assert_eq!(r.summary_json(None)["statistics"]["load_steps"], serde_json::json!(0));
    assert_eq!(r.summary_json(None)["stable"], serde_json::json!(true));
    let theta = col(&r, "crank.phi")[0];
    let dyb = |th: f64| {
        let (psi, _, dpsi, _) = fourbar(th);
        c * psi.cos() * dpsi
    };
    let balance = k * (theta - theta0) + f * dyb(theta);
    assert!(balance.abs() < 1e-8 * f * c, "virtual work residual {balance} at theta {theta}");
    let h = 1e-5;
    assert!(k + f * (dyb(theta + h) - dyb(theta - h)) / (2.0 * h) > 0.0, "V'' > 0: a minimum of the potential");
}

/// Modes about a state that is not an equilibrium (`about: initial`): a pendulum held at rest at
/// `phi0 = 0.5` rad. The frozen linearisation's stiffness is the tension's `m g L cos(phi0)`
/// (the multiplier from the equations of motion at rest is the tension `m g cos(phi0)`), so
/// `omega^2 = g cos(phi0) / L`; about the equilibrium it would be `g / L`.
#[test]
fn modes_about_the_initial_state_use_its_multipliers() {
    let (g, l, phi0) = (9.81f64, 1.5f64, 0.5f64);
    let yaml = format!(
        r#"
gravity: [0, -{g}]
bodies:
  bob: {{mass: 4.0, inertia: 0.0, position: [0.7, -1.3], angle: {phi0}, points: {{P: [0, {l}]}}, given: [phi]}}
joints:
  pivot: {{type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}}
analyses:
  here: {{type: modes, about: initial}}
"#
    );
    let r = run(&yaml, "here");
    assert!((col(&r, "bob.phi")[0] - phi0).abs() < 1e-12, "the initial angle is held");
    let got = 2.0 * std::f64::consts::PI * r.summary_json(None)["modes"][0]["frequency"].as_f64().unwrap();
    let want = (g * phi0.cos() / l).sqrt();
    assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
}

/// Lengths `(a, b, c, d)` of `examples/hanging_fourbar.yaml` and of [`SPRING_FOURBAR`]: crank,
/// coupler, rocker, ground.
const HANGING: (f64, f64, f64, f64) = (0.5, 1.0, 0.7, 1.0);

/// The joints `A` (crank-coupler) and `B` (coupler-rocker) of a four-bar of lengths [`HANGING`]
/// at crank angle `theta`, by intersecting the circles `|B - A| = b` and `|B - C| = c`; `side`
/// 1 puts B to the left of the line from A to the ground pivot C, -1 to the right.
fn loop_closure(theta: f64, side: f64) -> ([f64; 2], [f64; 2]) {
    let (a, b, c, d) = HANGING;
    let (ax, ay) = (a * theta.cos(), a * theta.sin());
    let (dx, dy) = (d - ax, -ay);
    let e = dx.hypot(dy);
    let along = (b * b - c * c + e * e) / (2.0 * e);
    let h = side * (b * b - along * along).sqrt();
    let (ux, uy) = (dx / e, dy / e);
    ([ax, ay], [ax + along * ux - h * uy, ay + along * uy + h * ux])
}

/// The joints of the hanging four-bar at crank angle `theta`, on its assembly branch (B to the
/// left of the line from A to C).
fn hanging_joints(theta: f64) -> ([f64; 2], [f64; 2]) {
    loop_closure(theta, 1.0)
}

/// The potential energy of the hanging four-bar at crank angle `theta`, J, written out by hand
/// from the closed-loop positions: gravity on the three bodies (centres of mass at the links'
/// midpoints), the 150 N load at B, and the spring (500 N/m, free length 0.2 m) from
/// `G = (0.5, -0.8)` to the coupler's centre.
fn hanging_energy(theta: f64) -> f64 {
    let ([ax, ay], [bx, by]) = hanging_joints(theta);
    let (g, w, k, free, gx, gy) = (9.81, 150.0, 500.0, 0.2, 0.5, -0.8);
    let (mx, my) = (0.5 * (ax + bx), 0.5 * (ay + by));
    let stretch = (mx - gx).hypot(my - gy) - free;
    g * (2.0 * 0.5 * ay + 3.0 * my + 2.5 * 0.5 * by) + w * by + 0.5 * k * stretch * stretch
}

/// The hanging four-bar's model file with the guess placed exactly at crank angle `theta`.
fn hanging_fourbar_at(theta: f64) -> String {
    let text = common::example_text("hanging_fourbar.yaml");
    let ([ax, ay], [bx, by]) = hanging_joints(theta);
    let coupler = (by - ay).atan2(bx - ax);
    let rocker = by.atan2(bx - HANGING.3);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut placed = 0;
    for line in &mut lines {
        let (name, x, y, angle) = match line.split(':').next().unwrap_or("") {
            "  crank" => ("crank", 0.5 * ax, 0.5 * ay, theta),
            "  coupler" => ("coupler", 0.5 * (ax + bx), 0.5 * (ay + by), coupler),
            "  rocker" => ("rocker", 0.5 * (bx + HANGING.3), 0.5 * by, rocker),
            _ => continue,
        };
        let points = &line[line.find("points").unwrap()..];
        let mass = &line[line.find("mass").unwrap()..line.find("position").unwrap()];
        *line = format!("  {name}: {{{mass}position: [{x}, {y}], angle: {angle}, {points}");
        placed += 1;
    }
    assert_eq!(placed, 3, "the crank, coupler and rocker lines of hanging_fourbar.yaml are placed");
    lines.join("\n")
}

/// The hanging four-bar, started from every 10 degrees of crank angle, comes to rest at the
/// minimum of its potential energy every time, never at the maximum. The reference is independent
/// of the solver: the potential energy written out by hand along the closed-loop path, sampled
/// every 0.1 degree, its one interior minimum refined by golden-section search to 1e-10 rad. The
/// solver's crank angle (modulo a turn) must match it to 1e-7 rad: the force balance converges to
/// 1e-10 of the load, and with `V'' ~ 10^2 J/rad^2` against loads of `10^2 N` that places the angle to
/// about 1e-10 rad; the golden section's own error is `sqrt(eps |V| / V'')`, about 1e-8 rad
/// (measured difference: 2.3e-8 rad). Newton alone would return the maximum (1.550 rad) with
/// `stable: false` from starts between 40 and 160 degrees and fail from 330 to 30 degrees: the
/// descents take every start to the minimum.
#[test]
fn hanging_fourbar_rests_at_the_energy_minimum_from_every_start() {
    let tau = std::f64::consts::TAU;
    let samples = 3600;
    let v: Vec<f64> = (0..samples).map(|i| hanging_energy(tau * i as f64 / samples as f64)).collect();
    let minima: Vec<usize> =
        (0..samples).filter(|&i| v[i] < v[(i + samples - 1) % samples] && v[i] < v[(i + 1) % samples]).collect();
    assert_eq!(minima.len(), 1, "the fixture has one minimum per turn");
    let (mut lo, mut hi) =
        (tau * (minima[0] as f64 - 1.0) / samples as f64, tau * (minima[0] as f64 + 1.0) / samples as f64);
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    while hi - lo > 1e-10 {
        let (x1, x2) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
        if hanging_energy(x1) < hanging_energy(x2) {
            hi = x2;
        } else {
            lo = x1;
        }
    }
    let minimum = 0.5 * (lo + hi);
    for degrees in (0..360).step_by(10) {
        let start = (degrees as f64).to_radians();
        let model = Model::from_yaml(&hanging_fourbar_at(start)).unwrap_or_else(|e| panic!("{e}"));
        let r = model.run("rest", &Default::default()).unwrap_or_else(|f| panic!("from {degrees} deg: {}", f.error));
        let theta = col(&r, "crank.phi")[0];
        let off = (theta - minimum) - tau * ((theta - minimum) / tau).round();
        assert!(off.abs() < 1e-7, "from {degrees} deg: rests at {theta} rad, the minimum is {minimum} rad");
        assert_eq!(r.summary_json(None)["stable"], serde_json::json!(true), "from {degrees} deg");
        assert_eq!(r.summary_json(None)["index"], serde_json::json!(0), "from {degrees} deg");
        // Pinned work (measured: 0 or 1 descent, 3 to 10 Newton iterations per start).
        let stats = &r.summary_json(None)["statistics"];
        assert!(stats["descents"].as_u64().unwrap() <= 1 && stats["iterations"].as_u64().unwrap() <= 10, "{stats}");
    }
}

/// `(m, J_c, l, g)` of the compound pendulum below: kg, kg m^2, m, m/s^2.
const COMPOUND: (f64, f64, f64, f64) = (4.0, 0.3, 0.5, 9.81);

/// The compound pendulum `COMPOUND` pinned to the ground at its point `P`, `l` above its centre
/// of mass, with the body fields `placed` (position, angle, ...) and the `analyses` entries.
fn compound_pendulum(placed: &str, analyses: &str) -> String {
    let (m, jc, l, g) = COMPOUND;
    format!(
        "gravity: [0, -{g}]
bodies:
  bob: {{mass: {m}, inertia: {jc}, {placed}, points: {{P: [0, {l}]}}}}
joints:
  pivot: {{type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}}
analyses:
  {analyses}
"
    )
}

/// A compound pendulum (mass m, inertia `J_c` about its centre of mass, pivot at `l` from it)
/// released horizontally: gravity loads it although the guess has no stiffness (the rod carries
/// no tension). It hangs straight down, `(x, y) = (0, -l)`, and swings at
/// `omega = sqrt(m g l / J_O)`, `J_O = J_c + m l^2`. Tolerances: positions 1e-12 m (the
/// constraint tolerance), angle 1e-10 rad (the force balance, 1e-10 of the weight, over a
/// stiffness of `m g l`), frequency 1e-9 (the geometric stiffness's central difference).
#[test]
fn horizontal_pendulum_hangs_down_and_swings_at_the_closed_form() {
    let (m, jc, l, g) = COMPOUND;
    let yaml = compound_pendulum(
        &format!("position: [{l}, 0], angle: {}", std::f64::consts::FRAC_PI_2),
        "rest: {type: static}\n  swing: {type: modes}",
    );
    let r = run(&yaml, "rest");
    let phi = col(&r, "bob.phi")[0];
    let tau = std::f64::consts::TAU;
    assert!((phi - tau * (phi / tau).round()).abs() < 1e-10, "phi = {phi}");
    assert!(col(&r, "bob.x")[0].abs() < 1e-12 && (col(&r, "bob.y")[0] + l).abs() < 1e-12);
    assert_eq!(r.summary_json(None)["stable"], serde_json::json!(true));
    let modes = run(&yaml, "swing");
    let got = tau * modes.summary_json(None)["modes"][0]["frequency"].as_f64().unwrap();
    let want = (m * g * l / (jc + m * l * l)).sqrt();
    assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
}

/// The same pendulum standing upside down, linearised where it stands (`about: initial`): its
/// one mode is a divergence at the rate `sqrt(m g l / J_O)` (1/s), flagged unstable, with no
/// frequency or damping ratio. About the equilibrium instead, the static solver leaves the
/// unstable balance and the pendulum swings about the bottom. Tolerance 1e-9 as above.
#[test]
fn inverted_pendulum_modes_are_a_divergence() {
    let (m, jc, l, g) = COMPOUND;
    let yaml = compound_pendulum(
        &format!("position: [0, {l}], angle: {}, given: [x, y, phi]", std::f64::consts::PI),
        "here: {type: modes, about: initial}\n  settled: {type: modes}",
    );
    let rate = (m * g * l / (jc + m * l * l)).sqrt();
    let r = run(&yaml, "here");
    let mode = &r.summary_json(None)["modes"][0];
    assert_eq!(r.summary_json(None)["stable"], serde_json::json!(false));
    assert_eq!(mode["kind"], serde_json::json!("divergence"), "{mode}");
    assert!((mode["growth_rate"].as_f64().unwrap() - rate).abs() < 1e-9 * rate, "{mode}");
    assert!(mode["frequency"].is_null() && mode["damping_ratio"].is_null(), "{mode}");
    let r = run(&yaml, "settled");
    assert_eq!(r.summary_json(None)["stable"], serde_json::json!(true));
    let got = std::f64::consts::TAU * r.summary_json(None)["modes"][0]["frequency"].as_f64().unwrap();
    assert!((got - rate).abs() < 1e-9 * rate, "{got} vs {rate}");
    assert_eq!(r.summary_json(None)["modes"][0]["kind"], serde_json::json!("vibration"));
}

/// No non-finite number leaves a static or modes analysis. A weight past a double's range
/// (`1.9e307 kg` under `9.81 m/s^2`, as `tests/test_properties.py` draws) would give NaN
/// reactions and potential energy: it is a model error at the mass. A measure that
/// is NaN at the equilibrium (`sqrt(-1 - bob.phi*bob.phi)`) stops the analysis naming its column,
/// with no row written.
#[test]
fn a_non_finite_equilibrium_is_not_written() {
    let at_rest = compound_pendulum("position: [0, -0.5], angle: 0", "rest: {type: static}");
    let heavy = patch(&at_rest, "mass: 4", "mass: 1.9e307");
    let Err(problems) = Model::from_yaml(&heavy) else { panic!("a weight past 1.8e308 loaded") };
    let text = problems.to_string();
    assert!(text.contains("bodies.bob.mass: the weight m |g| = 1.9e307 kg x 9.81 m/s^2 is out of range"), "{text}");
    // Gravity whose components are doubles but whose size is not is blamed on gravity, not on
    // every body's mass.
    let fast = patch(&at_rest, "gravity: [0, -9.81]", "gravity: [1.5e308, -1.5e308]");
    let Err(problems) = Model::from_yaml(&fast) else { panic!("gravity of size 2.1e308 loaded") };
    let text = problems.to_string();
    assert!(text.contains("gravity: its size |g| = inf is out of range") && !text.contains("mass"), "{text}");
    let nan = patch(
        &compound_pendulum("position: [0, -0.5], angle: 0", "rest: {type: static}\n  swing: {type: modes}"),
        "analyses:",
        "measures:\n  odd: \"sqrt(-1 - bob.phi*bob.phi)\"\nanalyses:",
    );
    let model = Model::from_yaml(&nan).unwrap();
    for analysis in ["rest", "swing"] {
        let failure = model.run(analysis, &Default::default()).unwrap_err();
        let Error::NonFinite { element, time, .. } = &failure.error else { panic!("{analysis}: {}", failure.error) };
        assert_eq!((element.as_str(), *time), ("odd", 0.0), "{analysis}");
        assert!(failure.results.is_empty(), "{analysis}: a row was written");
    }
}

/// A parallelogram four-bar (cranks 1 m, ground and coupler 2 m) under gravity, its crank
/// driven through the flat position `theta = 0` so that at t = 0.1 s it is `d` rad past it. The
/// driven Jacobian's smallest singular value is about `d / 5` of the largest (its condition
/// estimate `5e9` at `d = 1e-9`, `2.5e9` at `2e-9`, `5e8` at `1e-8`). At `d = 1e-8` the
/// reactions are found (tests/properties.rs checks the balance on random mechanisms). At
/// `d = 1e-9` and `2e-9` the condition is inside the kinematics' `singular_condition` (1e10),
/// with room on both sides, while the least-squares solve drops the direction as rank-deficient
/// (below 1e-9 of the largest), so that reactions from it would leave more than half the loads
/// unbalanced: the analysis stops with a `Singular` error at 0.1 s naming the joints, with the
/// t = 0 row kept.
#[test]
fn reactions_that_cannot_balance_the_loads_are_not_written() {
    let parallelogram = |d: &str| {
        format!(
            "gravity: [0, -9.81]
bodies:
  crank_1: {{mass: 1, inertia: 0.083, position: [0.4975, -0.05], angle: -0.1, points: {{O: [-0.5, 0], P: [0.5, 0]}}}}
  crank_2: {{mass: 1, inertia: 0.083, position: [2.4975, -0.05], angle: -0.1, points: {{O: [-0.5, 0], P: [0.5, 0]}}}}
  coupler: {{mass: 2, inertia: 0.667, position: [1.995, -0.0998], angle: 0.0, points: {{P1: [-1, 0], P2: [1, 0]}}}}
joints:
  ground_1: {{type: revolute, body_i: crank_1, point_i: O, body_j: ground, point_j: [0, 0]}}
  coupler_1: {{type: revolute, body_i: crank_1, point_i: P, body_j: coupler, point_j: P1}}
  ground_2: {{type: revolute, body_i: crank_2, point_i: O, body_j: ground, point_j: [2, 0]}}
  coupler_2: {{type: revolute, body_i: crank_2, point_i: P, body_j: coupler, point_j: P2}}
drivers:
  motor: {{type: angle, body: crank_1, function: \"-0.1 + t + {d}\"}}
analyses:
  inv: {{type: inverse, drivers: [motor], t_end: 0.1, step: 0.1}}
"
        )
    };
    let r = run(&parallelogram("1e-8"), "inv");
    assert_eq!(r.len(), 2);
    for d in ["1e-9", "2e-9"] {
        let failure = Model::from_yaml(&parallelogram(d)).unwrap().run("inv", &Default::default()).unwrap_err();
        let Error::Singular { time, rows, detail } = &failure.error else { panic!("{d}: {}", failure.error) };
        assert_eq!(*time, 0.1, "{d}");
        assert!(rows.iter().any(|r| r.element == "coupler_2"), "{d}: {}", failure.error);
        assert!(detail.contains("do not balance"), "{d}: {detail}");
        assert_eq!(failure.results.len(), 1, "{d}: the t = 0 row is kept, the unbalanced one not written");
    }
}
