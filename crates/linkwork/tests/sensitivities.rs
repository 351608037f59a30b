//! Design sensitivities of kinematic analyses (docs/sensitivities.md), checked against central
//! finite differences of whole runs of every example with parameters, and against closed forms.

mod common;

use linkwork::model::spec::AnalysisKind;
use linkwork::{Error, Model, Results, RunOptions};

/// `model` with every analysis's Newton tolerance at the round-off floor (1e-15 asks for it;
/// the solver stops at the floor), so that the finite differences below see the positions to
/// round-off rather than to the default 1e-12.
fn tight(mut model: Model) -> Model {
    model.analyses.values_mut().for_each(|a| a.settings.tolerance = 1e-15);
    model
}

/// A run of `analysis` with the derivatives of every column with respect to `parameters`.
fn run_with(model: &Model, analysis: &str, parameters: &[String]) -> Result<Results, Error> {
    let options = RunOptions { sensitivities: parameters.to_vec(), ..Default::default() };
    model.run(analysis, &options).map_err(|f| f.error)
}

/// The columns of a plain run of `analysis` with parameter `name` set to `value` (SI).
fn run_at(model: &Model, analysis: &str, name: &str, value: f64) -> Results {
    let set = model.with_parameters(&[(name.to_string(), format!("{value:e}"))]).expect("the model with the value set");
    tight(set)
        .run(analysis, &RunOptions::default())
        .unwrap_or_else(|f| panic!("{analysis} with {name} = {value}: {}", f.error))
}

/// The central difference of every column with respect to parameter `name` by Richardson's
/// extrapolation of the steps `h` and `h/2`: `(4 D(h/2) - D(h)) / 3`, whose truncation error is
/// of order `h^4`. `h` is 3e-4 of the parameter's size ([`step`]): the runs converge their
/// positions to round-off ([`tight`]), so a difference quotient is good to about `eps / h` of
/// the run's size (the floor below), and the truncation is about `(3e-4)^4`. Only the
/// output times that every run shares are kept (a parameter that sets `t_end` moves the last).
fn finite_differences(model: &Model, analysis: &str, name: &str, times: &[f64]) -> Vec<Vec<Option<f64>>> {
    let value = model.parameters[name];
    let h = step(model, name);
    let runs: Vec<Results> =
        [-h, h, -h / 2.0, h / 2.0].iter().map(|d| run_at(model, analysis, name, value + d)).collect();
    let columns = runs[0].names.len();
    (0..columns)
        .map(|c| {
            times
                .iter()
                .map(|&t| {
                    let at = |r: &Results| r.time.iter().position(|&x| x == t).map(|k| r.columns[c][k]);
                    let [a, b, c2, d] = [&runs[0], &runs[1], &runs[2], &runs[3]].map(at);
                    let (a, b, c2, d) = (a?, b?, c2?, d?);
                    let wide = (b - a) / (2.0 * h);
                    let narrow = (d - c2) / h;
                    Some((4.0 * narrow - wide) / 3.0)
                })
                .collect()
        })
        .collect()
}

/// The step of the finite differences in parameter `name`: 3e-4 of its value (of 1e-3 for a
/// parameter that is zero). At 1e-3 the six-bar's accelerations near its start, whose higher
/// derivatives are large, kept a truncation error of 1.3e-7 after the extrapolation.
fn step(model: &Model, name: &str) -> f64 {
    3e-4 * model.parameters[name].abs().max(1e-3)
}

/// Where the derivatives of `results` (a run of `analysis` with sensitivities with respect to
/// `parameters`) disagree with the finite differences of whole runs: to 1e-7 of the column's
/// largest derivative, or, where the derivative is zero (a parameter that does not move the
/// column), beyond the differences' round-off. A run whose largest value is `|c|` computes each
/// column to about `eps |c|`, so a difference quotient to about `eps |c| / h`; the floor is 100
/// times that, or 1e-10, whichever is larger. One message per column, at its first
/// disagreement.
fn disagreements(model: &Model, analysis: &str, parameters: &[String], results: &Results) -> Vec<String> {
    let sens = results.sensitivities.as_ref().expect("the sensitivities asked for");
    // The run's size: its largest value (every column is computed with the others).
    let size = results.columns.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut failures = Vec::new();
    for (k, p) in parameters.iter().enumerate() {
        let fd = finite_differences(model, analysis, p, &results.time);
        for (c, column) in sens.values[k].iter().enumerate() {
            let scale = fd[c].iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            let floor = (100.0 * f64::EPSILON * size / step(model, p)).max(1e-10);
            let rows = column.iter().zip(&fd[c]).enumerate();
            let first = rows
                .filter_map(|(row, (&exact, approx))| approx.map(|a| (row, exact, a)))
                .find(|&(_, exact, approx)| (exact - approx).abs() > 1e-7 * scale + floor);
            if let Some((row, exact, approx)) = first {
                failures.push(format!(
                    "d({})/d({p}) at t = {}: {exact:e}, differences {approx:e}",
                    results.names[c], results.time[row]
                ));
            }
        }
    }
    failures
}

/// The analyses of examples with parameters that have no sensitivities yet, each with the
/// element the run names: the cam joints (this increment differentiates the geometric joints and
/// the drivers), a mechanical advantage that reads a torque force, and joint friction in an
/// inverse analysis.
const NOT_YET: &[(&str, &str, &str)] = &[
    ("cam_profile.yaml", "drive", "joints."),
    ("cam_profile.yaml", "motion", "joints."),
    ("cam_roller.yaml", "drive", "joints."),
    ("cam_roller.yaml", "motion", "joints."),
    ("fourbar_measures.yaml", "inverse", "measures.ma"),
    ("slider_crank_friction.yaml", "inverse", "joints.O.friction"),
];

/// Every kinematic and inverse analysis of every example with parameters: the derivative of
/// every column with respect to every parameter agrees with the finite differences of whole runs
/// ([`disagreements`]) to 1e-7 of the column's largest derivative: what the issue asks, and 100
/// times the differences' own truncation and convergence error above. Where the derivative is
/// zero the floor is the differences' round-off: 2e-9 for the quick-return's kinematics
/// (accelerations of 60 m/s^2, a step of 6e-4 m); an inverse analysis's largest value is its
/// largest reaction.
#[test]
fn every_example_agrees_with_finite_differences_of_whole_runs() {
    let dir = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("the examples")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    files.sort();
    let mut checked = Vec::new();
    let mut refused = Vec::new();
    let mut failures = Vec::new();
    for path in files {
        let file = path.file_name().expect("a name").to_string_lossy().into_owned();
        let model = tight(Model::load(&path).unwrap_or_else(|e| panic!("{file}: {e}")));
        if model.parameters.is_empty() {
            continue;
        }
        let parameters: Vec<String> = model.parameters.keys().cloned().collect();
        for (name, analysis) in &model.analyses {
            if !matches!(analysis.kind, AnalysisKind::Kinematic | AnalysisKind::Inverse) {
                continue;
            }
            let results = match run_with(&model, name, &parameters) {
                Ok(r) => r,
                Err(Error::Model(problems))
                    if NOT_YET.iter().any(|(f, a, p)| *f == file && a == name && problems[0].path.starts_with(p)) =>
                {
                    refused.push((file.clone(), name.clone()));
                    continue;
                }
                Err(e) => {
                    failures.push(format!("{file} {name}: {e}"));
                    continue;
                }
            };
            let sens = results.sensitivities.as_ref().expect("the sensitivities asked for");
            assert_eq!(sens.names, results.names, "{file}: every column has its derivatives");
            let disagreements = disagreements(&model, name, &parameters, &results);
            failures.extend(disagreements.into_iter().map(|d| format!("{file} {name}: {d}")));
            checked.push(format!("{file} {name}"));
        }
    }
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
    // The list of what is not differentiated yet stays true: each analysis on it is refused.
    refused.sort();
    let mut expected: Vec<(String, String)> = NOT_YET.iter().map(|(f, a, _)| (f.to_string(), a.to_string())).collect();
    expected.sort();
    assert_eq!(refused, expected);
    for expected in [
        "slider_crank_param.yaml kinematics",
        "quick_return_a.yaml kinematics",
        "sixbar_leg.yaml kinematics",
        "slider_crank_param.yaml inverse",
        "quick_return_a.yaml inverse",
        "motion_laws.yaml drive",
        "cam_table.yaml drive",
    ] {
        assert!(checked.iter().any(|c| c == expected), "{expected} was checked; checked: {checked:?}");
    }
}

/// The centred slider-crank `x = r cos(theta) + sqrt(L^2 - r^2 sin^2(theta))`, `theta = speed t`:
/// `dx/dr = cos(theta) - r sin^2(theta) / s`, `dx/dL = L / s` with `s = sqrt(L^2 - r^2 sin^2)`,
/// and `dx/dspeed = x'(theta) t`. To 1e-9 of the stroke: the positions are converged to 1e-12 of
/// the mechanism's size, and the derivatives inherit it through the Jacobian's conditioning.
#[test]
fn slider_crank_slider_matches_its_closed_form() {
    let model = Model::load(common::example("slider_crank_param.yaml")).expect("the example");
    let names: Vec<String> = ["r", "L", "speed"].map(String::from).to_vec();
    let results = run_with(&model, "kinematics", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    let column = sens.names.iter().position(|n| n == "slider.x").expect("slider.x");
    let (r, l, w) = (model.parameters["r"], model.parameters["L"], model.parameters["speed"]);
    for (k, &t) in results.time.iter().enumerate() {
        let th = w * t;
        let s = (l * l - r * r * th.sin().powi(2)).sqrt();
        let dr = th.cos() - r * th.sin().powi(2) / s;
        let dl = l / s;
        let dth = -r * th.sin() - r * r * th.sin() * th.cos() / s;
        for (p, expected) in [(0, dr), (1, dl), (2, dth * t)] {
            let got = sens.values[p][column][k];
            assert!((got - expected).abs() < 1e-9, "d(slider.x)/d({}) at t = {t}: {got} against {expected}", names[p]);
        }
    }
}

/// A four-bar (crank a, coupler b, rocker c, ground d) whose transmission angle `mu` follows the
/// cosine law `cos mu = (b^2 + c^2 - f^2) / (2 b c)`, `f^2 = a^2 + d^2 - 2 a d cos(theta)` (the
/// diagonal from A to O4): `d mu / d x = -d(cos mu)/dx / sin mu` for x = a, b, c, d, to 1e-10
/// (the positions are converged to 1e-12; mu stays away from 0 and pi, where 1/sin mu grows).
#[test]
fn four_bar_transmission_angle_follows_the_cosine_law() {
    let text = "
name: four-bar
parameters: {a: 0.1, b: 0.3, c: 0.25, d: 0.3}
bodies:
  crank: {mass: 1, inertia: 1, position: [0.05, 0], angle: 0, points: {O2: [-a/2, 0], A: [a/2, 0]}}
  coupler: {mass: 1, inertia: 1, position: [0.18, 0.13], angle: 0.95, points: {A: [-b/2, 0], B: [b/2, 0]}}
  rocker: {mass: 1, inertia: 1, position: [0.29, 0.12], angle: 1.7, points: {O4: [-c/2, 0], B: [c/2, 0]}}
ground:
  points: {O2: [0, 0], O4: [d, 0]}
joints:
  O2: {type: revolute, body_i: crank, point_i: O2, body_j: ground, point_j: O2}
  A: {type: revolute, body_i: crank, point_i: A, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: coupler, point_i: B, body_j: rocker, point_j: B}
  O4: {type: revolute, body_i: rocker, point_i: O4, body_j: ground, point_j: O4}
drivers:
  motor: {type: angle, body: crank, function: 2*t}
measures:
  mu: {type: transmission_angle, joint: B, coupler_joint: A, rocker_joint: O4}
analyses:
  kinematics: {type: kinematic, drivers: [motor], t_end: 3.1, step: 0.05}
";
    let model = Model::from_yaml(text).expect("the four-bar");
    let names: Vec<String> = ["a", "b", "c", "d"].map(String::from).to_vec();
    let results = run_with(&model, "kinematics", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    let column = sens.names.iter().position(|n| n == "mu").expect("mu");
    let (a, b, c, d) = (0.1, 0.3, 0.25, 0.3);
    for (k, &t) in results.time.iter().enumerate() {
        let th = 2.0 * t;
        let f2 = a * a + d * d - 2.0 * a * d * th.cos();
        let cos_mu = (b * b + c * c - f2) / (2.0 * b * c);
        let sin_mu = (1.0 - cos_mu * cos_mu).sqrt();
        // d(cos mu)/dx for each of a, b, c, d.
        let df2 = [2.0 * a - 2.0 * d * th.cos(), 0.0, 0.0, 2.0 * d - 2.0 * a * th.cos()];
        let dcos = [
            -df2[0] / (2.0 * b * c),
            (2.0 * b) / (2.0 * b * c) - cos_mu / b,
            (2.0 * c) / (2.0 * b * c) - cos_mu / c,
            -df2[3] / (2.0 * b * c),
        ];
        // mu is the acute angle: min(gamma, pi - gamma) turns the sign past 90 degrees.
        let sign = if cos_mu >= 0.0 { 1.0 } else { -1.0 };
        for p in 0..4 {
            let expected = -sign * dcos[p] / sin_mu;
            let got = sens.values[p][column][k];
            assert!((got - expected).abs() < 1e-10, "d(mu)/d({}) at t = {t}: {got} against {expected}", names[p]);
        }
    }
}

/// A name the model does not define, and an analysis type without sensitivities yet, are errors
/// at the field `sensitivities` that say what is wrong.
#[test]
fn unknown_parameters_and_other_analyses_are_refused() {
    let model = Model::load(common::example("slider_crank_param.yaml")).expect("the example");
    let Err(Error::Model(problems)) = run_with(&model, "kinematics", &["R".to_string()]) else {
        panic!("an unknown parameter is refused")
    };
    assert_eq!(problems[0].path, "sensitivities");
    assert!(
        problems[0].message.contains("unknown parameter 'R'") && problems[0].message.contains("r, L"),
        "{}",
        problems[0].message
    );
    let model = Model::load(common::example("quick_return_a.yaml")).expect("the example");
    let Err(Error::Model(problems)) = run_with(&model, "dynamics", &["crank".to_string()]) else {
        panic!("a dynamic analysis is refused for now")
    };
    assert_eq!(problems[0].path, "sensitivities");
    assert!(problems[0].message.contains("kinematic and inverse analyses"), "{}", problems[0].message);
}

/// A crank turning at constant speed `w` about a fixed pin O, carrying a point mass `m` at
/// radius `r` under gravity `g` (its centre of mass at `r (cos theta, sin theta)`, `theta = w
/// t`). Its angular momentum about O is constant, so the motor's effort balances gravity's
/// moment about O, `tau = m g r cos(theta)`, and the pin's reaction on the crank is the mass's
/// acceleration less gravity, `F = (-m w^2 r cos(theta), m g - m w^2 r sin(theta))`. Their
/// derivatives with respect to `m` and `r` (and the values, which fix the signs of the effort
/// convention), to 1e-12 of the largest value: both are products of the parameters with
/// `cos` and `sin` of an angle the drivers give exactly, so only round-off separates them.
#[test]
fn crank_effort_and_reaction_match_their_closed_forms() {
    let text = "
name: crank with a point mass
parameters: {m: 2.5, r: 0.4}
gravity: [0, -9.81]
bodies:
  crank: {mass: m, inertia: 1e-3, position: [r, 0], angle: 0, points: {O: [-r, 0]}}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
drivers:
  motor: {type: angle, body: crank, function: 3*t}
measures:
  power: motor.effort * crank.omega
analyses:
  inverse: {type: inverse, drivers: [motor], t_end: 2.5, step: 0.05}
";
    let model = Model::from_yaml(text).expect("the crank");
    let names: Vec<String> = ["m", "r"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    let column = |name: &str| results.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("{name}"));
    let [effort, fx, fy, torque, power] = ["motor.effort", "O.fx", "O.fy", "O.torque", "power"].map(column);
    let (m, r, g, w) = (2.5, 0.4, 9.81, 3.0);
    let size = m * (g + w * w * r) * w;
    for (k, &t) in results.time.iter().enumerate() {
        let (c, s) = ((w * t).cos(), (w * t).sin());
        let checks = [
            // (column, value, d/dm, d/dr)
            (effort, m * g * r * c, g * r * c, m * g * c),
            (fx, -m * w * w * r * c, -w * w * r * c, -m * w * w * c),
            (fy, m * g - m * w * w * r * s, g - w * w * r * s, -m * w * w * s),
            (torque, 0.0, 0.0, 0.0),
            (power, m * g * r * c * w, g * r * c * w, m * g * c * w),
        ];
        for (col, value, dm, dr) in checks {
            let name = &results.names[col];
            let got = [results.columns[col][k], sens.values[0][col][k], sens.values[1][col][k]];
            for (what, got, expected) in [("value", got[0], value), ("d/dm", got[1], dm), ("d/dr", got[2], dr)] {
                assert!(
                    (got - expected).abs() <= 1e-12 * size,
                    "{what} of {name} at t = {t}: {got} against {expected}"
                );
            }
        }
    }
}

/// A double parallelogram (three parallel cranks of length `L`, pivots at 0, `d` and `e`, one coupler)
/// has a redundant row throughout its motion, so its multipliers are the minimum-norm ones and
/// their derivatives carry the pseudo-inverse's second term (docs/sensitivities.md, "Inverse
/// dynamics"): every column against the finite differences of whole runs, as for the examples
/// (same steps, tolerance and floor).
#[test]
fn redundant_rows_take_the_minimum_norm_derivative() {
    let text = "
name: double parallelogram
parameters: {L: 0.3, d: 0.5, e: 1.3, m: 1.2}
gravity: [0, -9.81]
bodies:
  c1: {mass: m, inertia: m*L^2/12, position: [0, 0], angle: 1, points: {O: [-L/2, 0], T: [L/2, 0]}}
  c2: {mass: 2*m, inertia: m*L^2/6, position: [d, 0], angle: 1, points: {O: [-L/2, 0], T: [L/2, 0]}}
  c3: {mass: 0.5, inertia: 0.01, position: [1.3, 0], angle: 1, points: {O: [-L/2, 0], T: [L/2, 0]}}
  coupler: {mass: 3, inertia: 0.2, position: [0.6, 0.25], angle: 0, points: {A: [-d, 0], B: [0, 0], C: [e - d, 0]}}
joints:
  O1: {type: revolute, body_i: c1, point_i: O, body_j: ground, point_j: [0, 0]}
  O2: {type: revolute, body_i: c2, point_i: O, body_j: ground, point_j: [d, 0]}
  O3: {type: revolute, body_i: c3, point_i: O, body_j: ground, point_j: [e, 0]}
  A: {type: revolute, body_i: c1, point_i: T, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: c2, point_i: T, body_j: coupler, point_j: B}
  C: {type: revolute, body_i: c3, point_i: T, body_j: coupler, point_j: C}
drivers:
  motor: {type: angle, body: c1, function: 0.6 + 1.5*t}
analyses:
  inverse: {type: inverse, drivers: [motor], t_end: 1.2, step: 0.1}
";
    let model = tight(Model::from_yaml(text).expect("the double parallelogram"));
    let parameters: Vec<String> = ["L", "d", "e", "m"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &parameters).expect("the run");
    let redundant = results.summary.redundant_rows.as_ref().map_or(0, Vec::len);
    assert_eq!(redundant, 1, "one row is redundant");
    let failures = disagreements(&model, "inverse", &parameters, &results);
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
}

/// Forces in an inverse analysis: the crank above with a force at its mass written with a
/// parameter (in the crank's frame, so that its moment turns with it), a damping torque whose
/// coefficient is one, and a spring to ground whose numbers no parameter writes (its potential
/// moves only with the coordinates): every column (the effort, the reactions, the applied
/// power and the potential energy among them) against the finite differences of whole runs, as
/// for the examples (same steps, tolerance and floor).
#[test]
fn forces_in_an_inverse_analysis_agree_with_finite_differences() {
    let text = "
name: crank with forces
parameters: {m: 2.5, r: 0.4, P: 3, c: 0.7}
gravity: [0, -9.81]
bodies:
  crank: {mass: m, inertia: 1e-3, position: [r, 0], angle: 0, points: {O: [-r, 0]}}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
drivers:
  motor: {type: angle, body: crank, function: 3*t}
forces:
  push: {type: force, body: crank, point: [0, 0], frame: body, fx: P, fy: 1.5}
  damper: {type: torque, body: crank, torque: -c*crank.omega}
  spring: {type: spring_damper, body_i: ground, point_i: [0.2, 0.5], body_j: crank, point_j: [0, 0], stiffness: 40, free_length: 0.3}
analyses:
  inverse: {type: inverse, drivers: [motor], t_end: 2.5, step: 0.1}
";
    let model = tight(Model::from_yaml(text).expect("the crank with forces"));
    let parameters: Vec<String> = ["m", "r", "P", "c"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &parameters).expect("the run");
    let failures = disagreements(&model, "inverse", &parameters, &results);
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
}
