//! Measures over reactions and efforts, and the standard measures (transmission angle, velocity
//! ratio, mechanical advantage), against closed forms of the four-bar of
//! `examples/fourbar_measures.yaml`; and their bad inputs, each refused at its path.

mod common;

use common::{col, example_text, patch, problems};
use linkwork::{Error, Model, Results};
use std::f64::consts::PI;

/// The example's links: crank, coupler, rocker, ground, m.
const A: f64 = 0.1;
const B: f64 = 0.3;
const C: f64 = 0.25;
const D: f64 = 0.3;
/// The example's load torque, N m (the brake's torque is `-LOAD`).
const LOAD: f64 = 1.5;

/// The closed-form position of the four-bar at crank angle `theta2`: the coupler's angle
/// `theta3` (A to B) and the rocker's `theta4` (O4 to B), the open assembly (B left of the line
/// from A to O4, above the ground link), by the intersection of the circles about A (radius b)
/// and O4 (radius c).
fn closed_position(theta2: f64) -> (f64, f64) {
    let pa = [A * theta2.cos(), A * theta2.sin()];
    let (ex, ey) = (D - pa[0], -pa[1]);
    let e = ex.hypot(ey);
    let (ux, uy) = (ex / e, ey / e);
    let l = (B * B - C * C + e * e) / (2.0 * e);
    let h = (B * B - l * l).sqrt();
    let pb = [pa[0] + l * ux - h * uy, pa[1] + l * uy + h * ux];
    ((pb[1] - pa[1]).atan2(pb[0] - pa[0]), pb[1].atan2(pb[0] - D))
}

/// The transmission angle at crank angle `theta2` by the law of cosines in the triangles
/// O2 A O4 and A B O4 (the diagonal A O4 shared): `cos gamma = (b^2 + c^2 - a^2 - d^2 +
/// 2 a d cos theta2) / (2 b c)`, folded to the acute angle (Norton, Design of Machinery).
fn closed_transmission_angle(theta2: f64) -> f64 {
    let gamma = ((B * B + C * C - A * A - D * D + 2.0 * A * D * theta2.cos()) / (2.0 * B * C)).acos();
    gamma.min(PI - gamma)
}

/// `omega4 / omega2` at crank angle `theta2`, the classic four-bar formula (Norton, Design of
/// Machinery, velocity analysis of the four-bar): `a sin(theta2 - theta3) / (c sin(theta4 - theta3))`.
fn closed_velocity_ratio(theta2: f64) -> f64 {
    let (theta3, theta4) = closed_position(theta2);
    A * (theta2 - theta3).sin() / (C * (theta4 - theta3).sin())
}

fn run(text: &str, analysis: &str, set: &[(&str, &str)]) -> Results {
    let set: Vec<(String, String)> = set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let model = Model::from_yaml_with(text, &set).unwrap_or_else(|e| panic!("{e}"));
    model.run(analysis, &Default::default()).unwrap_or_else(|f| panic!("{}", f.error))
}

/// The example as written (links with mass): the transmission angle and the velocity ratio
/// against their closed forms at the driven crank angle `2 t`. Both columns follow from the
/// positions and velocities Newton and the velocity solve leave, the positions within the
/// solver's `1e-12` m of the constraints: on links of 0.1 to 0.3 m an angle is off by at most
/// about `1e-11` rad, and the ratio by as much relative to `sin(theta4 - theta3) >= 0.66`. The
/// closed forms are exact to round-off except `acos` of the cosine, which loses
/// `eps / sin(gamma)` (`gamma` stays within 41 to 93 degrees here). `1e-10` leaves a factor of
/// ten over the worst of these (measured: 6.1e-12 rad and 3.9e-12).
#[test]
fn transmission_angle_and_velocity_ratio_match_the_closed_forms() {
    let r = run(&example_text("fourbar_measures.yaml"), "inverse", &[]);
    let (mu, vr) = (col(&r, "mu"), col(&r, "vr"));
    let (mut worst_mu, mut worst_vr) = (0.0f64, 0.0f64);
    let (mut folded, mut unfolded) = (0, 0);
    for (k, &t) in r.time.iter().enumerate() {
        let theta2 = 2.0 * t;
        let (want_mu, want_vr) = (closed_transmission_angle(theta2), closed_velocity_ratio(theta2));
        worst_mu = worst_mu.max((mu[k] - want_mu).abs());
        worst_vr = worst_vr.max((vr[k] - want_vr).abs() / want_vr.abs().max(1.0));
        assert!((mu[k] - want_mu).abs() <= 1e-10, "mu at t = {t}: engine {}, law of cosines {want_mu}", mu[k]);
        assert!((vr[k] - want_vr).abs() <= 1e-10 * want_vr.abs().max(1.0), "vr at t = {t}: {} vs {want_vr}", vr[k]);
        // The interior angle passes 90 degrees near theta2 = pi, where mu folds.
        if B * B + C * C - A * A - D * D + 2.0 * A * D * theta2.cos() < 0.0 {
            folded += 1;
        } else {
            unfolded += 1;
        }
    }
    assert!(folded > 0 && unfolded > 0, "the run crosses 90 degrees: {folded} folded, {unfolded} not");
    eprintln!("largest differences: mu {worst_mu:.2e} rad, vr {worst_vr:.2e}");
}

/// A crank started from rest at a constant acceleration (`theta = 1.5 t^2`: `omega = 0`,
/// `alpha = 3 / s^2` at t = 0, as a mechanism released from rest): the
/// velocity ratio at the start comes from the accelerations (`alpha_out = G alpha_in` where the
/// input is at rest) and is the closed form's there, as it is after. Same tolerance and reasons
/// as above (the accelerations come from the same exact linear solve as the velocities).
#[test]
fn the_velocity_ratio_of_a_start_from_rest_is_the_closed_forms() {
    let text = patch(&example_text("fourbar_measures.yaml"), "function: \"2*t\"", "function: \"1.5*t^2\"");
    let r = run(&text, "inverse", &[]);
    let vr = col(&r, "vr");
    let omega = col(&r, "crank.omega");
    assert_eq!(omega[0], 0.0, "the run starts at rest");
    for (k, &t) in r.time.iter().enumerate().filter(|&(_, &t)| t <= 1.0) {
        let theta2 = 1.5 * t * t;
        let want = closed_velocity_ratio(theta2);
        assert!((vr[k] - want).abs() <= 1e-10 * want.abs().max(1.0), "vr at t = {t}: {} vs {want}", vr[k]);
    }
}

/// Massless links (`rho = 0`), no friction: the motor's power goes to the brake, `T2 omega2 +
/// T_brake omega4 = 0`, so the mechanical advantage `-T_brake / T2` is `omega2 / omega4`, the
/// inverse of the closed-form velocity ratio; and the coupler is a two-force member, so the pin
/// B carries `|F_B| = load / (c |sin(theta4 - theta3)|)`, the load's moment over the rocker's
/// arm. The efforts and reactions come from the multipliers' least-squares solve, exact to
/// round-off of the loads at the positions Newton left (within `1e-12` m): `|F_B|`, the powers'
/// balance and `ma vr = 1` (both from the engine's state) to `1e-10` relative (measured below
/// 5e-12). Against the closed form the ratio is off by the positions' error: Newton leaves
/// the angles within about `1e-11` rad (`1e-12` m on links of 0.1 to 0.3 m), which moves the
/// velocity ratio by as much absolute (its derivatives in the angles are below 1), and so
/// `ma = 1 / vr` by `1e-11 |ma|` relative, large where the rocker stops at its limit positions
/// and both powers vanish (`|ma|` reaches 741 at the samples nearest them). So
/// `1e-10 + 1e-11 |ma|` relative (measured: at most 0.29 of it, 1.3e-10 at |ma| = 55).
#[test]
fn mechanical_advantage_is_the_inverse_velocity_ratio_when_massless() {
    let r = run(&example_text("fourbar_measures.yaml"), "inverse", &[("rho", "0")]);
    let (ma, vr, b_load) = (col(&r, "ma"), col(&r, "vr"), col(&r, "B_load"));
    let (effort, omega2, omega4) = (col(&r, "motor.effort"), col(&r, "crank.omega"), col(&r, "rocker.omega"));
    let (mut worst_ma, mut worst_product, mut worst_b, mut worst_power) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (k, &t) in r.time.iter().enumerate() {
        let theta2 = 2.0 * t;
        let want_ma = 1.0 / closed_velocity_ratio(theta2);
        let (theta3, theta4) = closed_position(theta2);
        let want_b = LOAD / (C * (theta4 - theta3).sin().abs());
        let power = (effort[k] * omega2[k] - LOAD * omega4[k]).abs() / (effort[k] * omega2[k]).abs().max(1e-300);
        let tol_ma = 1e-10 + 1e-11 * want_ma.abs();
        worst_ma = worst_ma.max((ma[k] - want_ma).abs() / want_ma.abs() / tol_ma);
        worst_product = worst_product.max((ma[k] * vr[k] - 1.0).abs());
        worst_b = worst_b.max((b_load[k] - want_b).abs() / want_b);
        worst_power = worst_power.max(power);
        assert!(
            (ma[k] - want_ma).abs() <= tol_ma * want_ma.abs(),
            "ma at t = {t}: {} vs omega2/omega4 {want_ma}",
            ma[k]
        );
        assert!((ma[k] * vr[k] - 1.0).abs() <= 1e-10, "ma vr at t = {t}: {}", ma[k] * vr[k]);
        assert!((b_load[k] - want_b).abs() <= 1e-10 * want_b, "|F_B| at t = {t}: {} vs {want_b}", b_load[k]);
        assert!(power <= 1e-10, "motor and brake powers at t = {t} differ by {power:e} relative");
    }
    let largest = ma.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!(
        "largest differences: ma {worst_ma:.2} of its tolerance, ma vr - 1 {worst_product:.2e}, |F_B| {worst_b:.2e} relative, power {worst_power:.2e} relative; largest |ma| {largest:.1}"
    );
}

/// A measure over the result columns is the same number as the expression of those columns,
/// in every analysis that has them: inverse, dynamic (a driven one, whose efforts come from the
/// integrator's output solve) and static (`B_load` at rest under the brake, the crank held).
#[test]
fn measures_read_the_reaction_and_effort_columns_of_every_analysis() {
    let text = patch(
        &example_text("fourbar_measures.yaml"),
        "  inverse: {type: inverse, drivers: [motor], t_end: 3.14, step: 0.01}",
        "  inverse: {type: inverse, drivers: [motor], t_end: 3.14, step: 0.01}
  dynamics: {type: dynamic, drivers: [motor], t_end: 0.5, step: 0.05}",
    );
    // A static analysis is at rest: no velocity ratio (refused, below).
    let still = patch(&text, "  vr: {type: velocity_ratio, input: crank, output: rocker}\n", "");
    let still = patch(
        &still,
        "  dynamics: {type: dynamic,",
        "  still: {type: static, drivers: [motor], t_end: 1, step: 0.25}\n  dynamics: {type: dynamic,",
    );
    for (text, analysis) in [(&text, "inverse"), (&text, "dynamics"), (&still, "still")] {
        let r = run(text, analysis, &[]);
        assert!(r.len() > 1, "{analysis}: {} rows", r.len());
        let (fx, fy, b_load) = (col(&r, "B.fx"), col(&r, "B.fy"), col(&r, "B_load"));
        let (effort, omega2, power) = (col(&r, "motor.effort"), col(&r, "crank.omega"), col(&r, "motor_power"));
        for k in 0..r.len() {
            let hypot = fx[k].hypot(fy[k]);
            // `sqrt(B.fx^2 + B.fy^2)` rounds each step: a few units of round-off from hypot.
            assert!(
                (b_load[k] - hypot).abs() <= 4.0 * f64::EPSILON * hypot,
                "{analysis}: B_load {} vs {hypot}",
                b_load[k]
            );
            assert_eq!(power[k], effort[k] * omega2[k], "{analysis}: motor_power at row {k}");
            assert!(b_load[k] > 0.0, "{analysis}: the pin carries the load");
        }
    }
}

/// The problems of running `analysis` of `text` (it compiles; the run is refused).
fn run_problems(text: &str, analysis: &str) -> Vec<String> {
    let model = Model::from_yaml(text).unwrap_or_else(|e| panic!("{e}"));
    match model.run(analysis, &Default::default()) {
        Err(f) => match f.error {
            Error::Model(p) => {
                assert!(f.results.is_empty(), "nothing is computed");
                p.iter().map(|p| p.to_string()).collect()
            }
            e => panic!("expected a model error, got {e}"),
        },
        Ok(_) => panic!("expected the run of '{analysis}' to be refused"),
    }
}

/// Each `(path, words)` is a problem of `list`.
fn has_each(list: &[String], expected: &[(&str, &str)]) {
    let missing: Vec<_> = expected
        .iter()
        .filter(|(path, words)| !list.iter().any(|p| p.starts_with(&format!("{path}: ")) && p.contains(words)))
        .collect();
    assert!(missing.is_empty(), "not found: {missing:#?}\nin {list:#?}");
}

/// A reaction or effort where the analysis has none, a driver it does not hold, a torque that
/// does not load it, a velocity ratio at rest: the run is refused before it starts, each at the
/// measure's path (its field for a mechanical advantage), saying why and what was expected.
#[test]
fn a_measure_the_analysis_cannot_compute_is_refused_at_its_path() {
    let text = patch(
        &example_text("fourbar_measures.yaml"),
        "  inverse: {type: inverse, drivers: [motor], t_end: 3.14, step: 0.01}",
        "  inverse: {type: inverse, drivers: [motor], t_end: 3.14, step: 0.01}
  kin: {type: kinematic, drivers: [motor], t_end: 1, step: 0.1}
  unloaded: {type: inverse, drivers: [motor], forces: [], t_end: 1, step: 0.1}
  free: {type: dynamic, drivers: [], t_end: 1, step: 0.1}
  still: {type: static, drivers: [motor], t_end: 1, step: 0.1}
  modes: {type: modes, drivers: []}",
    );
    let kinematic = "joint reaction or driver effort, which the kinematic analysis 'kin' does not compute; expected an inverse, static or dynamic analysis";
    has_each(
        &run_problems(&text, "kin"),
        &[
            ("measures.B_load", &format!("it reads B.fx, a {kinematic}")),
            ("measures.motor_power", "it reads motor.effort"),
            ("measures.ma", "it reads motor.effort, a joint reaction or driver effort, which the kinematic"),
        ],
    );
    let p = run_problems(&text, "kin");
    assert_eq!(p.len(), 3, "mu and vr need only the motion: {p:#?}");
    has_each(
        &run_problems(&text, "modes"),
        &[
            ("measures.B_load", "which the modes analysis 'modes' does not compute"),
            ("measures.vr", "a velocity ratio needs velocities, and the modes analysis 'modes' is at rest"),
        ],
    );
    has_each(
        &run_problems(&text, "unloaded"),
        &[("measures.ma.output", "force 'brake' does not load the analysis 'unloaded' (its forces: none)")],
    );
    has_each(
        &run_problems(&text, "free"),
        &[
            (
                "measures.ma.input",
                "driver 'motor' is not active in the analysis 'free' (its drivers: none), so it has no motor.effort",
            ),
            ("measures.motor_power", "driver 'motor' is not active"),
        ],
    );
    has_each(
        &run_problems(&text, "still"),
        &[("measures.vr", "a velocity ratio needs velocities, and the static analysis 'still' is at rest")],
    );
    // `linkwork check` tells the same before a run.
    let model = Model::from_yaml(&text).unwrap();
    let report = linkwork::analysis::check(&model).unwrap();
    let warning = report.analyses["kin"].warning.clone().unwrap_or_default();
    assert!(warning.contains("measures.B_load: it reads B.fx"), "{warning}");
    assert_eq!(report.analyses["inverse"].warning, None);
}

const FOURBAR: &str = "bodies:
  crank: {mass: 1, inertia: 1, position: [0.05, 0], points: {O2: [-0.05, 0], A: [0.05, 0]}}
  coupler: {mass: 1, inertia: 1, position: [0.18, 0.13], angle: 0.95, points: {A: [-0.15, 0], B: [0.15, 0]}}
  rocker: {mass: 1, inertia: 1, position: [0.29, 0.12], angle: 1.7, points: {O4: [-0.125, 0], B: [0.125, 0]}}
joints:
  O2: {type: revolute, body_i: crank, point_i: O2, body_j: ground, point_j: [0, 0]}
  A: {type: revolute, body_i: crank, point_i: A, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: coupler, point_i: B, body_j: rocker, point_j: B}
  O4: {type: revolute, body_i: rocker, point_i: O4, body_j: ground, point_j: [0.3, 0]}
  S: {type: point_on_line, body_i: ground, point_i: [0, 0], axis_i: [1, 0], body_j: crank, point_j: O2}
  P: {type: revolute, body_i: coupler, point_i: A, body_j: rocker, point_j: O4}
drivers:
  motor: {type: angle, body: crank, function: 2*t}
forces:
  push: {type: force, body: rocker, fx: 1}
  brake: {type: torque, body: rocker, torque: -1}
";

/// Bad names and kinds in the standard measures and in expressions over reactions: each a
/// problem at its field, naming what was found and what was expected.
#[test]
fn bad_standard_measures_are_refused_at_their_fields() {
    let measures = "measures:
  m1: {type: transmission_angle, joint: Bx, coupler_joint: S, rocker_joint: O4}
  m2: {type: transmission_angle, joint: B, coupler_joint: O2, rocker_joint: O4}
  m3: {type: transmission_angle, joint: B, coupler_joint: A, rocker_joint: P}
  m4: {type: transmission_angle, joint: B, coupler_joint: A, rocker_joint: A}
  m5: {type: velocity_ratio, input: crank, output: rockr}
  m6: {type: velocity_ratio, input: ground, output: rocker}
  m7: {type: mechanical_advantage, input: motr, output: push}
  m8: {type: transmission_angle, joint: B, coupler_joint: A}
  m9: {type: angle_of_attack, body: crank}
  e1: \"Q.fx / motor.effort\"
  e2: \"B.fz + crank.effort\"
  e3: \"O2.torque + brake.torque\"
  e4: 3
";
    let p = problems(&format!("{FOURBAR}{measures}"));
    has_each(
        &p,
        &[
            ("measures.m1.joint", "unknown joint 'Bx'; expected one of: O2, A, B, O4, S, P"),
            ("measures.m1.coupler_joint", "'S' is a point_on_line joint; expected a revolute joint (a pin)"),
            ("measures.m2.coupler_joint", "'O2' (between 'crank' and 'ground') shares no body with 'B' (between 'coupler' and 'rocker'); expected the coupler's other pin"),
            ("measures.m3.rocker_joint", "'P' (between 'coupler' and 'rocker') joins the same two bodies as 'B'"),
            ("measures.m4.rocker_joint", "'A' is a pin of 'coupler', the coupler"),
            ("measures.m5.output", "unknown body 'rockr'"),
            ("measures.m6.input", "ground does not move"),
            ("measures.m7.input", "unknown driver or torque 'motr'; expected one of: motor, brake"),
            ("measures.m7.output", "'push' is a force force; expected a driver or a torque force"),
            ("measures.m8", "missing field `rocker_joint`"),
            ("measures.m9.type", "unknown type `angle_of_attack`, expected one of: transmission_angle, velocity_ratio, mechanical_advantage"),
            ("measures.e1", "unknown name 'Q.fx'"),
            ("measures.e1", "<joint>.fx, <joint>.fy, <joint>.torque, <driver>.effort or t, with a body among: crank, coupler, rocker; a joint among: O2, A, B, O4, S, P; a driver among: motor"),
            ("measures.e2", "unknown name 'B.fz'"),
            ("measures.e3", "unknown name 'brake.torque'"),
            ("measures.e4", "expected an expression (a string), a mapping with body, point and component, or a mapping with a `type`"),
        ],
    );
    // A force's expression may not read reactions: only measures do.
    let force = FOURBAR.replace("torque: -1", "torque: \"-B.fx\"");
    has_each(&problems(&force), &[("forces.brake.torque", "unknown name 'B.fx'")]);
    // The pins of a transmission angle at the same point of a body.
    let same = patch(FOURBAR, "A: [0.05, 0]}}\n", "A: [0.05, 0]}}\n  extra: {mass: 1, inertia: 1, position: [0, 0]}\n");
    let same = patch(
        &same,
        "drivers:\n",
        "  E: {type: revolute, body_i: coupler, point_i: B, body_j: extra, point_j: [0, 0]}\ndrivers:\n",
    ) + "measures:\n  mu: {type: transmission_angle, joint: B, coupler_joint: E, rocker_joint: O4}\n";
    has_each(
        &problems(&same),
        &[(
            "measures.mu.coupler_joint",
            "'E' and 'B' are at the same point of 'coupler': the coupler's line is undefined",
        )],
    );
}
