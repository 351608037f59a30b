//! Design sensitivities of kinematic, inverse, static, modes and dynamic analyses
//! (docs/sensitivities.md), checked against central finite differences of whole runs of every
//! example with parameters, and against closed forms.

mod common;

use linkwork::model::spec::{AnalysisKind, IntegratorKind};
use linkwork::{Error, Model, Results, RunOptions};
use std::collections::HashMap;

/// `model` with every analysis's Newton tolerance at the round-off floor (1e-15 asks for it;
/// the solver stops at the floor), so that the finite differences below see the positions to
/// round-off rather than to the default 1e-12; and every dynamic analysis integrated at
/// `rtol = atol = rtol` ([`SENSITIVITY_RTOL`] for the runs with sensitivities, [`FINEST_RTOL`]
/// for the finite differences, whose runs [`REFERENCE`] integrates).
fn tight(mut model: Model, rtol: f64) -> Model {
    for a in model.analyses.values_mut() {
        a.settings.tolerance = 1e-15;
        if a.kind == AnalysisKind::Dynamic {
            a.integrator.rtol = rtol;
            a.integrator.atol = rtol;
        }
    }
    model
}

/// The tolerance of a dynamic run with sensitivities: where the issue asks them to agree.
const SENSITIVITY_RTOL: f64 = 1e-10;

/// The tolerance of the dynamic runs of the finite differences: each run's error, divided by
/// the step, is the differences' noise, so they run as finely as the [`REFERENCE`] integrator
/// converges. abam's quick-return under its crank torque (`dynamics_loaded`): `slider_d.x` at 2 s
/// `-0.2018808649`, `-0.2018808911`, `-0.2018808923` at rtol 1e-11, 1e-12, 1e-13 (0.28 s a run,
/// release build); bdf's does not converge below 1e-11 (`-0.20188093`, `-0.20190104`,
/// `-0.20199446`: SI2's Newton fails at regular positions near the quick stroke and the index-3
/// corrector takes the step, docs/integrators.md), so its runs are not the reference.
const FINEST_RTOL: f64 = 1e-13;

/// The integrator of the dynamic runs of the finite differences, at [`FINEST_RTOL`]: abam
/// (explicit Adams formulas in the independent coordinates), whatever integrator the analysis
/// names. An independent reference for the sensitivities of either integrator at
/// [`SENSITIVITY_RTOL`]: bdf's are the BDF discretisation differentiated, abam's the sensitivity
/// equations integrated at 1e-10, each 1e3 times looser than these runs.
const REFERENCE: IntegratorKind = IntegratorKind::Abam;

/// A run of `analysis` with the derivatives of every column with respect to `parameters`.
fn run_with(model: &Model, analysis: &str, parameters: &[String]) -> Result<Results, Error> {
    let options = RunOptions { sensitivities: parameters.to_vec(), ..Default::default() };
    model.run(analysis, &options).map_err(|f| f.error)
}

/// The columns of a plain run of `analysis` with parameter `name` set to `value` (SI); a dynamic
/// one integrated by [`REFERENCE`].
fn run_at(model: &Model, analysis: &str, name: &str, value: f64) -> Results {
    let set = model.with_parameters(&[(name.to_string(), format!("{value:e}"))]).expect("the model with the value set");
    let dynamic = model.analyses[analysis].kind == AnalysisKind::Dynamic;
    let overrides = linkwork::Overrides { integrator: dynamic.then_some(REFERENCE), ..Default::default() };
    tight(set, FINEST_RTOL)
        .run(analysis, &RunOptions { overrides, ..Default::default() })
        .unwrap_or_else(|f| panic!("{analysis} with {name} = {value}: {}", f.error))
}

/// The central difference with respect to parameter `name` of each number `read` takes from a
/// whole run of `analysis`, by Richardson's extrapolation of the steps `h`, `h/2`, ...
/// ([`halvings`] of them): with two, `(4 D(h/2) - D(h)) / 3`, whose truncation error is of order
/// `h^4`; with three, the next column of the tableau, of order `h^6`. `h` is [`step`]: the runs
/// converge their positions to round-off ([`tight`]), so a difference quotient is good to about
/// `eps / h` of the run's size (the floor below). A number that some run lacks (`None`) has
/// none.
fn differences(
    model: &Model,
    analysis: &str,
    name: &str,
    read: impl Fn(&Results) -> Vec<Option<f64>>,
) -> Vec<Option<f64>> {
    let value = model.parameters[name];
    let h = step(model, analysis, name);
    let steps: Vec<f64> = (0..halvings(model, analysis)).map(|k| h / f64::from(1 << k)).collect();
    let runs: Vec<[Vec<Option<f64>>; 2]> =
        steps.iter().map(|&d| [-d, d].map(|d| read(&run_at(model, analysis, name, value + d)))).collect();
    (0..runs[0][0].len())
        .map(|k| {
            // The tableau's first column, the central differences; each next column
            // `(4^j R[i][j-1] - R[i-1][j-1]) / (4^j - 1)`.
            let mut column = steps
                .iter()
                .zip(&runs)
                .map(|(&d, [a, b])| Some((b.get(k).copied().flatten()? - a.get(k).copied().flatten()?) / (2.0 * d)))
                .collect::<Option<Vec<f64>>>()?;
            for j in 1..column.len() {
                let w = 4f64.powi(j as i32);
                column = column.windows(2).map(|r| (w * r[1] - r[0]) / (w - 1.0)).collect();
            }
            column.first().copied()
        })
        .collect()
}

/// The steps of [`differences`]: two (the truncation `h^4`, with `h` 3e-4 of the parameter,
/// `~1e-14`), three for a dynamic analysis, whose runs are smooth in the parameters only to the
/// integrator's error at [`FINEST_RTOL`], so the step cannot be small: the quick-return under its
/// crank torque speeds its slider to 570 m/s in 2 s, and its state's higher derivatives in `crank`
/// are large. Measured (bdf's sensitivities at 1e-10, the largest disagreement of a column over
/// its largest derivative, `crank`): two steps of 2.5e-4, 1.25e-4 leave `1.2e-5`, three steps
/// from 5e-4 `4.9e-7`.
fn halvings(model: &Model, analysis: &str) -> usize {
    if model.analyses[analysis].kind == AnalysisKind::Dynamic {
        3
    } else {
        2
    }
}

/// [`differences`] of every column at each of the output times of the `nominal` run (only those
/// that every run shares: a parameter that sets `t_end` moves the last), column by column. An
/// angle is taken within half a turn of the nominal run's: an equilibrium is the same with a
/// body turned whole turns, and the hanging four-bar's crank, started near its highest
/// position, comes to rest a turn apart as the parameter moves either side.
fn finite_differences(model: &Model, analysis: &str, name: &str, nominal: &Results) -> Vec<Vec<Option<f64>>> {
    let times = &nominal.time;
    let turn = 2.0 * std::f64::consts::PI;
    let read = |r: &Results| -> Vec<Option<f64>> {
        let at = |c: usize, (k, &t): (usize, &f64)| {
            let v = r.columns[c][r.time.iter().position(|&x| x == t)?];
            let angle = r.names[c].ends_with(".phi");
            Some(if angle { v + turn * ((nominal.columns[c][k] - v) / turn).round() } else { v })
        };
        (0..r.names.len()).flat_map(|c| times.iter().enumerate().map(move |x| at(c, x))).collect()
    };
    let flat = differences(model, analysis, name, read);
    flat.chunks(times.len().max(1)).map(<[Option<f64>]>::to_vec).collect()
}

/// The step of the finite differences of `analysis` in parameter `name`: 3e-4 of its value (of
/// 1e-3 for a parameter that is zero). At 1e-3 the six-bar's accelerations near its start, whose
/// higher derivatives are large, kept a truncation error of 1.3e-7 after the extrapolation.
/// A modes analysis takes 1e-2: its frequencies carry the rounding of the geometric
/// stiffness's central difference and the equilibrium's convergence (force balance to 1e-10 of
/// the load, `analysis::statics`), about 1e-10 of the frequency, which a difference quotient
/// divides by the step. Measured on the hanging four-bar (example): with steps of 3e-3 the
/// extrapolated differences of its frequency scatter by 2.3e-7 about the exact derivative, with
/// 1e-2 they agree with it to 6e-8 (and with 3e-2 the truncation shows, 2e-6). A dynamic
/// analysis takes 5e-4 and [`halvings`] three: a run's error (`~1e-12` of its size at
/// [`FINEST_RTOL`]) divided by the smallest step, 1.25e-4, is `~1e-8` of the derivative, and
/// the truncation of three extrapolated steps is measured above.
/// An inverse analysis with a mechanical advantage takes 3e-5: `-output / input` has a
/// pole where the input's effort crosses zero, and the column's largest derivatives are next to
/// it, where the truncation is `(h / distance to the pole)^4`. Measured on `fourbar_measures.yaml`
/// at 2.06 s (effort 1e-3 N m, `ma = -1452`), the extrapolated differences of `d(ma)/d(d)` err by
/// 6.5e-5, 7.9e-7 and 6.2e-9 of it at 3e-4, 1e-4 and 3e-5 (falling as `h^4`), and stay at
/// 2e-9 at 1e-5 (round-off); `d(ma)/d(c)` likewise, 9.6e-5, 1.2e-6, 1.0e-8.
fn step(model: &Model, analysis: &str, name: &str) -> f64 {
    let pole =
        model.measures.iter().any(|m| matches!(m.kind, linkwork::model::MeasureKind::MechanicalAdvantage { .. }));
    let relative = match model.analyses[analysis].kind {
        AnalysisKind::Modes => 1e-2,
        AnalysisKind::Dynamic => 5e-4,
        AnalysisKind::Inverse if pole => 3e-5,
        _ => 3e-4,
    };
    relative * model.parameters[name].abs().max(1e-3)
}

/// The analysis types whose sensitivities are checked against finite differences.
const DIFFERENTIATED: [AnalysisKind; 5] =
    [AnalysisKind::Kinematic, AnalysisKind::Inverse, AnalysisKind::Static, AnalysisKind::Modes, AnalysisKind::Dynamic];

/// The agreement asked of an analysis of type `kind`: 1e-7 of the quantity's largest derivative
/// (what the issue asks, and 100 times the differences' own truncation and convergence error),
/// 1e-5 for a dynamic one at rtol 1e-10 (what the issue asks: the sensitivities are as accurate
/// as the integrator, whose error at 1e-10 is `~1e-6` of the quick-return's derivatives, the
/// differences' own error `~1e-8`).
fn agreement(kind: AnalysisKind) -> f64 {
    if kind == AnalysisKind::Dynamic {
        1e-5
    } else {
        1e-7
    }
}

/// A quantity of a mode, where it has one.
type Quantity = fn(&linkwork::results::Mode) -> Option<f64>;

/// Where the derivatives of `results` (a run of `analysis` of `model` with sensitivities)
/// disagree with the finite differences of whole runs, one message per quantity at its first
/// disagreement: every column, and a modes analysis's frequencies, damped frequencies and
/// growth rates (`modes.<k>.<quantity>` of the summary, the modes in the order the analysis
/// sorts them). Each to [`agreement`] of the quantity's largest derivative. Where the derivative is zero
/// (a parameter that does not move the quantity) the differences are round-off: a run whose
/// largest value is `|c|` (the quick-return's accelerations, 60 m/s^2; an inverse analysis's
/// largest reaction) computes each column to about `eps |c|`, so a difference quotient to about
/// `eps |c| / h`; the floor is 100 times that, or 1e-10, whichever is larger (2e-9 for the
/// quick-return's step of 6e-4 m).
fn disagreements(model: &Model, name: &str, results: &Results) -> Vec<String> {
    disagreements_with(model, name, results, &mut HashMap::new())
}

/// [`disagreements`], the finite differences of the columns with respect to each parameter
/// taken from `known` when it has them and kept there (two runs of one analysis by two
/// integrators share them: the derivatives at the same output times are the same).
fn disagreements_with(
    model: &Model,
    name: &str,
    results: &Results,
    known: &mut HashMap<String, Vec<Vec<Option<f64>>>>,
) -> Vec<String> {
    let mut failures = Vec::new();
    let failures = &mut failures;
    let sens = results.sensitivities.as_ref().expect("the sensitivities asked for");
    let parameters = &sens.parameters;
    // The run's size: its largest value (every column is computed with the others).
    let size = results.columns.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let tolerance = agreement(model.analyses[name].kind);
    // A dynamic run leaves out the columns it has no derivatives of (the reactions).
    if model.analyses[name].kind != AnalysisKind::Dynamic {
        assert_eq!(sens.names, results.names, "{name}: every column has its derivatives");
    }
    let compare =
        |failures: &mut Vec<String>, what: &dyn Fn(usize) -> String, exact: &[f64], fd: &[Option<f64>], floor: f64| {
            let scale = fd.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for (row, (&exact, approx)) in exact.iter().zip(fd).enumerate() {
                let Some(approx) = approx else { continue };
                if (exact - approx).abs() > tolerance * scale + floor {
                    failures.push(format!("{}: {exact:e}, differences {approx:e}", what(row)));
                    break;
                }
            }
        };
    for (k, p) in parameters.iter().enumerate() {
        let floor = (100.0 * f64::EPSILON * size / step(model, name, p)).max(1e-10);
        let fd = known.entry(p.clone()).or_insert_with(|| finite_differences(model, name, p, results));
        for (column_name, column) in sens.names.iter().zip(&sens.values[k]) {
            let c = results.names.iter().position(|n| n == column_name).expect("a column of the run");
            let what = |row: usize| format!("d({})/d({p}) at t = {}", results.names[c], results.time[row]);
            compare(failures, &what, column, &fd[c], floor);
        }
        let Some(modes) = &results.summary.modes else { continue };
        let derivatives = results.summary.sensitivities.as_ref().expect("the summary's sensitivities");
        let quantities: [(&str, Quantity); 3] = [
            ("frequency", |m| m.frequency),
            ("damped_frequency", |m| Some(m.damped_frequency)),
            ("growth_rate", |m| m.growth_rate),
        ];
        for (quantity, get) in quantities {
            let read = |r: &Results| r.summary.modes.iter().flatten().map(get).collect::<Vec<_>>();
            let fd = differences(model, name, p, read);
            for (number, mode) in modes.iter().enumerate() {
                let key = format!("modes.{}.{quantity}", number + 1);
                let exact = derivatives.get(&key).and_then(|d| d.get(p.as_str()));
                match (exact, fd.get(number).copied().flatten(), get(mode)) {
                    (Some(&exact), approx, _) => {
                        let what = |_| format!("d({key})/d({p})");
                        let value = get(mode).unwrap_or(0.0).abs();
                        compare(
                            failures,
                            &what,
                            &[exact],
                            &[approx],
                            (100.0 * f64::EPSILON * value / step(model, name, p)).max(1e-10),
                        );
                    }
                    (None, _, Some(_)) if mode.kind != linkwork::results::ModeKind::Neutral => {
                        failures.push(format!("no derivative {key}/d({p})"));
                    }
                    _ => {}
                }
            }
        }
    }
    std::mem::take(failures)
}

/// Every kinematic, inverse, static, modes and dynamic analysis of every example with parameters: the
/// derivative of every column (and mode) with respect to every parameter agrees with the finite
/// differences of whole runs ([`disagreements`]). A dynamic analysis is run as the file names it
/// and again integrated by abam (`--integrator abam`), a row of its own (`<file> <analysis>
/// abam`), against the same differences.
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
    let mut failures = Vec::new();
    for path in files {
        let file = path.file_name().expect("a name").to_string_lossy().into_owned();
        let model = tight(Model::load(&path).unwrap_or_else(|e| panic!("{file}: {e}")), SENSITIVITY_RTOL);
        if model.parameters.is_empty() {
            continue;
        }
        let parameters: Vec<String> = model.parameters.keys().cloned().collect();
        let rows = model.analyses.iter().flat_map(|(name, analysis)| {
            let abam = analysis.kind == AnalysisKind::Dynamic && analysis.integrator.kind != IntegratorKind::Abam;
            [(name, analysis, false), (name, analysis, true)].into_iter().take(if abam { 2 } else { 1 })
        });
        let mut known = HashMap::new();
        for (name, analysis, abam) in rows {
            if !DIFFERENTIATED.contains(&analysis.kind) {
                continue;
            }
            let run = if abam { run_abam(&model, name, &parameters) } else { run_with(&model, name, &parameters) };
            let row = if abam { format!("{name} abam") } else { name.clone() };
            let results = match run {
                Ok(r) => r,
                Err(e) => {
                    failures.push(format!("{file} {row}: {e}"));
                    continue;
                }
            };
            let known = known.entry(name.clone()).or_default();
            let failures_here = disagreements_with(&model, name, &results, known);
            failures.extend(failures_here.into_iter().map(|d| format!("{file} {row}: {d}")));
            checked.push(format!("{file} {row}"));
        }
    }
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
    for expected in [
        "slider_crank_param.yaml kinematics",
        "quick_return_a.yaml kinematics",
        "sixbar_leg.yaml kinematics",
        "hanging_fourbar.yaml rest",
        "hanging_fourbar.yaml vibration",
        "ellipse_trammel.yaml equilibrium",
        "slider_crank_param.yaml inverse",
        "quick_return_a.yaml inverse",
        "motion_laws.yaml drive",
        "cam_table.yaml drive",
        "cam_roller.yaml motion",
        "cam_profile.yaml motion",
        "cam_profile.yaml drive",
        "quick_return_a.yaml dynamics",
        "quick_return_a.yaml dynamics abam",
        "quick_return_a.yaml dynamics_loaded",
        "quick_return_a.yaml dynamics_loaded abam",
        "slider_crank_friction.yaml inverse",
        "fourbar_measures.yaml inverse",
    ] {
        assert!(checked.iter().any(|c| c == expected), "{expected} was checked; checked: {checked:?}");
    }
}

/// The quick-return's free motion with one parameter, where each iteration of the sensitivities
/// evaluates the derivative of `Phi_q^T lambda` whole (with two or more, the table above, it
/// comes from the geometric stiffness assembled once per step): against the finite differences
/// of whole runs ([`disagreements`]), as in the table.
#[test]
fn a_dynamic_analysis_with_one_parameter_agrees_with_finite_differences() {
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let model = tight(Model::load(&path).expect("the quick-return"), SENSITIVITY_RTOL);
    let results = run_with(&model, "dynamics", &["crank".to_string()]).expect("the run");
    let failures = disagreements(&model, "dynamics", &results);
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
}

/// A four-bar hanging under gravity alone (the hanging four-bar example without its spring and
/// load), its lengths, masses and a pivot as parameters: its rest and its modes agree with the
/// finite differences of whole runs ([`disagreements`]): the reactions' levers, the anchor points'
/// gradients, the geometric stiffness's derivative and the masses' all enter.
#[test]
fn a_four_bar_hanging_under_gravity_agrees_with_finite_differences() {
    let text = "
name: hanging four-bar under gravity
parameters: {a: 0.5, b: 1.0, c: 0.7, d: 1.0, m_coupler: 3.0, j_rocker: 0.08}
gravity: [0, -9.81]
bodies:
  crank: {mass: 2.0, inertia: 0.04, position: [0.0052, -0.25], angle: -1.55, points: {O: [-a/2, 0], A: [a/2, 0]}}
  coupler: {mass: m_coupler, inertia: 0.1, position: [0.5, -0.6], angle: 0.2, points: {A: [-b/2, 0], B: [b/2, 0]}}
  rocker: {mass: 2.5, inertia: j_rocker, position: [1.0, -0.35], angle: -1.58, points: {C: [-c/2, 0], B: [c/2, 0]}}
ground:
  points: {O: [0, 0], C: [d, 0]}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: O}
  A: {type: revolute, body_i: crank, point_i: A, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: coupler, point_i: B, body_j: rocker, point_j: B}
  C: {type: revolute, body_i: ground, point_i: C, body_j: rocker, point_j: C}
analyses:
  rest: {type: static}
  vibration: {type: modes}
";
    let model = tight(Model::from_yaml(text).expect("the four-bar"), SENSITIVITY_RTOL);
    let parameters: Vec<String> = model.parameters.keys().cloned().collect();
    let mut failures = Vec::new();
    for name in ["rest", "vibration"] {
        let results = run_with(&model, name, &parameters).expect("the run");
        failures.extend(disagreements(&model, name, &results).into_iter().map(|d| format!("{name}: {d}")));
    }
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
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

/// A name the model does not define, and modes about the initial state (which have no
/// sensitivities yet), are errors at the field `sensitivities` that say what is wrong.
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
    let mut model = Model::load(common::example("hanging_fourbar.yaml")).expect("the example");
    model.analyses["vibration"].about = linkwork::model::spec::LinearisePoint::Initial;
    let Err(Error::Model(problems)) = run_with(&model, "vibration", &["k".to_string()]) else {
        panic!("modes about the initial state are refused for now")
    };
    assert_eq!(problems[0].path, "sensitivities");
    assert!(problems[0].message.contains("about an equilibrium"), "{}", problems[0].message);
}

/// A compound pendulum: one body of mass `m` and inertia `J` about its centre, hanging from a
/// revolute at `L` from the centre, under gravity `g`; its weight pulls it straight down.
const COMPOUND_PENDULUM: &str = "
name: compound pendulum
parameters: {m: 2.0, L: 0.4, J: 0.05}
gravity: [0, -9.81]
bodies:
  bob: {mass: m, inertia: J, position: [0.01, -0.39], angle: 0.02, points: {O: [0, L]}}
joints:
  O: {type: revolute, body_i: bob, point_i: O, body_j: ground, point_j: [0, 0]}
analyses:
  rest: {type: static}
  vibration: {type: modes}
";

/// The compound pendulum's frequency `f = omega / 2 pi`, `omega^2 = m g L / (J + m L^2)`:
/// `d(omega^2)/dm = g L J / D^2`, `d/dL = m g (J - m L^2) / D^2`, `d/dJ = -m g L / D^2` with
/// `D = J + m L^2`, and `df = d(omega^2) / (2 omega 2 pi)`. To 1e-10 of each derivative, what the
/// issue asks: the equilibrium is exact (the pendulum hangs straight down), the derivative's
/// parts are exact to rounding, and the frequency itself carries the geometric stiffness's
/// central difference (about 4e-11 relative, `analysis::statics`).
#[test]
fn compound_pendulum_frequency_follows_its_closed_form() {
    let model = Model::from_yaml(COMPOUND_PENDULUM).expect("the pendulum");
    let names: Vec<String> = ["m", "L", "J"].map(String::from).to_vec();
    let results = run_with(&model, "vibration", &names).expect("the run");
    let (m, l, j, g): (f64, f64, f64, f64) = (2.0, 0.4, 0.05, 9.81);
    let d = j + m * l * l;
    let omega = (m * g * l / d).sqrt();
    let modes = results.summary.modes.as_ref().expect("the modes");
    assert_eq!(modes.len(), 1);
    let f = modes[0].frequency.expect("a vibration");
    assert!((f - omega / (2.0 * std::f64::consts::PI)).abs() < 1e-10 * f, "f = {f}");
    let sensitivities = results.summary.sensitivities.as_ref().expect("asked for");
    let derivatives = &sensitivities["modes.1.frequency"];
    let d_sigma = [g * l * j / (d * d), m * g * (j - m * l * l) / (d * d), -m * g * l / (d * d)];
    for (p, ds) in names.iter().zip(d_sigma) {
        let expected = ds / (2.0 * omega) / (2.0 * std::f64::consts::PI);
        let got = derivatives[p.as_str()];
        assert!((got - expected).abs() < 1e-10 * expected.abs(), "d(f)/d({p}): {got} against {expected}");
        assert_eq!(sensitivities["modes.1.damped_frequency"][p.as_str()], got);
        assert_eq!(sensitivities["modes.1.damping_ratio"][p.as_str()], 0.0);
    }
}

/// The compound pendulum at rest: its centre at `y = -L`, the pin holding its weight
/// (`O.fy = m g` on the bob, no moment about the pin), its potential energy `-m g L`:
/// `d(bob.y)/dL = -1`, `d(O.fy)/dm = g`, `d(potential_energy)/dm = -g L`, `d/dL = -m g`, and
/// nothing moves with `J`. To 1e-12 (absolute, the quantities being of order one): the
/// equilibrium is exact and so is each part of its derivative.
#[test]
fn compound_pendulum_at_rest_follows_its_closed_form() {
    let model = Model::from_yaml(COMPOUND_PENDULUM).expect("the pendulum");
    let names: Vec<String> = ["m", "L", "J"].map(String::from).to_vec();
    let results = run_with(&model, "rest", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    assert_eq!(sens.names, results.names, "every column has its derivatives");
    let (m, l, g) = (2.0, 0.4, 9.81);
    let expected = [
        ("bob.x", [0.0, 0.0, 0.0]),
        ("bob.y", [0.0, -1.0, 0.0]),
        ("bob.phi", [0.0, 0.0, 0.0]),
        ("O.fx", [0.0, 0.0, 0.0]),
        ("O.fy", [g, 0.0, 0.0]),
        ("O.torque", [0.0, 0.0, 0.0]),
        ("potential_energy", [-g * l, -m * g, 0.0]),
    ];
    for (column, by_parameter) in expected {
        let c = sens.names.iter().position(|n| n == column).unwrap_or_else(|| panic!("{column}"));
        for (p, want) in by_parameter.iter().enumerate() {
            let got = sens.values[p][c][0];
            assert!((got - want).abs() < 1e-12, "d({column})/d({}): {got} against {want}", names[p]);
        }
    }
}

/// A slider hanging on a spring in a vertical guide (mass `m`, stiffness `k`, free length `l0`,
/// gravity `g`): at rest the spring is stretched by `m g / k`, so `y = -(l0 + m g / k)`, the
/// potential energy `V = m g y + k (m g / k)^2 / 2 = -m g l0 - (m g)^2 / (2 k)`, and the guide
/// carries nothing. Their derivatives with respect to `m`, `k` and `l0` to 1e-10 of each (the
/// derivatives solve the equilibrium's equations exactly; measured: 1e-15), a zero to 1e-12
/// (the guide's force, of the order of the weight, 20 N, to rounding: measured 7e-15): the
/// spring's numbers enter its load and its potential. The guide has friction (`mu`): at rest
/// the smooth law gives none, so nothing moves with `mu` and the friction column and its
/// derivatives are zero.
#[test]
fn a_slider_on_a_spring_rests_where_its_closed_form_says() {
    let text = "
name: slider on a spring
parameters: {m: 2.0, k: 400.0, l0: 0.5, mu: 0.3}
gravity: [0, -9.81]
bodies:
  slider: {mass: m, inertia: 0.01, position: [0, -0.6], angle: 0}
joints:
  guide:
    {type: translational, body_i: slider, point_i: [0, 0], axis_i: [0, 1], body_j: ground, point_j: [0, 0],
     axis_j: [0, 1], friction: {mu: mu, length: 0.1}}
forces:
  spring: {type: spring_damper, body_i: ground, point_i: [0, 0], body_j: slider, point_j: [0, 0], stiffness: k, free_length: l0}
analyses:
  rest: {type: static}
";
    let model = Model::from_yaml(text).expect("the slider");
    let names: Vec<String> = ["m", "k", "l0", "mu"].map(String::from).to_vec();
    let results = run_with(&model, "rest", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    let (m, k, l0, g): (f64, f64, f64, f64) = (2.0, 400.0, 0.5, 9.81);
    let w = m * g;
    let expected = [
        ("slider.y", [-g / k, w / (k * k), -1.0, 0.0]),
        ("potential_energy", [-g * l0 - w * g / k, w * w / (2.0 * k * k), -w, 0.0]),
        ("guide.fx", [0.0; 4]),
        ("guide.fy", [0.0; 4]),
        ("guide.friction", [0.0; 4]),
    ];
    for (column, by_parameter) in expected {
        let c = sens.names.iter().position(|n| n == column).unwrap_or_else(|| panic!("{column}"));
        for (p, want) in by_parameter.iter().enumerate() {
            let got = sens.values[p][c][0];
            assert!(
                (got - want).abs() <= 1e-10 * want.abs() + 1e-12,
                "d({column})/d({}): {got:e} against {want:e}",
                names[p]
            );
        }
    }
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
    let model = tight(Model::from_yaml(text).expect("the double parallelogram"), SENSITIVITY_RTOL);
    let parameters: Vec<String> = ["L", "d", "e", "m"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &parameters).expect("the run");
    let redundant = results.summary.redundant_rows.as_ref().map_or(0, Vec::len);
    assert_eq!(redundant, 1, "one row is redundant");
    let failures = disagreements(&model, "inverse", &results);
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
    let model = tight(Model::from_yaml(text).expect("the crank with forces"), SENSITIVITY_RTOL);
    let parameters: Vec<String> = ["m", "r", "P", "c"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &parameters).expect("the run");
    let failures = disagreements(&model, "inverse", &results);
    assert!(failures.is_empty(), "{} disagreements:\n{}", failures.len(), failures.join("\n"));
}

/// A block sliding from rest down a frictionless incline at angle `alpha` below the horizontal
/// under gravity `g` (a translational joint on the ground): `s = g sin(alpha) t^2 / 2` along the
/// incline, so `x = g sin(alpha) cos(alpha) t^2 / 2 = g sin(2 alpha) t^2 / 4`,
/// `y = -g sin^2(alpha) t^2 / 2`, their velocities and accelerations the time derivatives, and
/// `d/d alpha`, `d/dg` in closed form; the mass `m` moves nothing. Integrated by bdf in both
/// formulations and by abam at rtol 1e-10, to 1e-7 of each column's largest derivative (the
/// motion is a quadratic in time, which every BDF order and every Adams order from 2 integrates
/// to round-off: what remains is the corrector's convergence, a third of the tolerance, and
/// abam's first steps at order 1).
#[test]
fn a_block_on_an_incline_matches_its_closed_form() {
    // The integrator and its formulation (a setting of bdf only).
    for (integrator, formulation) in [("bdf", ", formulation: si2"), ("bdf", ", formulation: index3"), ("abam", "")] {
        let text = format!(
            "
name: incline
parameters: {{alpha: 0.5, g: 9.81, m: 2}}
gravity: [0, -g]
bodies:
  block: {{mass: m, inertia: 0.1, position: [0, 0], angle: 0, given: [x, vx]}}
joints:
  slide:
    type: translational
    body_i: block
    point_i: [0, 0]
    axis_i: [cos(alpha), -sin(alpha)]
    body_j: ground
    point_j: [0, 0]
    axis_j: [cos(alpha), -sin(alpha)]
analyses:
  fall:
    type: dynamic
    t_end: 1
    step: 0.1
    integrator: {integrator}
    solver: {{rtol: 1e-10, atol: 1e-10{formulation}}}
"
        );
        let model = Model::from_yaml(&text).expect("the incline");
        let names: Vec<String> = ["alpha", "g", "m"].map(String::from).to_vec();
        let results = run_with(&model, "fall", &names).expect("the run");
        let sens = results.sensitivities.as_ref().expect("asked for");
        let (alpha, g) = (0.5f64, 9.81);
        let column = |name: &str| sens.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("{name}"));
        // (column, d/dalpha, d/dg) as functions of t.
        type Closed = fn(f64, f64, f64) -> [f64; 2];
        let expected: [(&str, Closed); 6] = [
            ("block.x", |a, g, t| [g * (2.0 * a).cos() * t * t / 2.0, (2.0 * a).sin() * t * t / 4.0]),
            ("block.y", |a, g, t| [-g * (2.0 * a).sin() * t * t / 2.0, -a.sin().powi(2) * t * t / 2.0]),
            ("block.vx", |a, g, t| [g * (2.0 * a).cos() * t, (2.0 * a).sin() * t / 2.0]),
            ("block.vy", |a, g, t| [-g * (2.0 * a).sin() * t, -a.sin().powi(2) * t]),
            ("block.ax", |a, g, _| [g * (2.0 * a).cos(), (2.0 * a).sin() / 2.0]),
            ("block.ay", |a, g, _| [-g * (2.0 * a).sin(), -a.sin().powi(2)]),
        ];
        for (name, closed) in expected {
            let c = column(name);
            let scale: [f64; 2] =
                [0, 1].map(|p| results.time.iter().map(|&t| closed(alpha, g, t)[p].abs()).fold(0.0, f64::max));
            for (row, &t) in results.time.iter().enumerate() {
                let want = closed(alpha, g, t);
                for p in 0..2 {
                    let got = sens.values[p][c][row];
                    assert!(
                        (got - want[p]).abs() <= 1e-7 * scale[p],
                        "{integrator}{formulation}: d({name})/d({}) at t = {t}: {got:e} against {:e}",
                        names[p],
                        want[p]
                    );
                }
                let by_mass = sens.values[2][c][row];
                assert!(
                    by_mass.abs() <= 1e-9 * scale[0],
                    "{integrator}{formulation}: d({name})/d(m) at t = {t}: {by_mass:e}"
                );
            }
        }
    }
}

/// A dynamic analysis integrated by hht (which has no sensitivities) is refused at its integrator; a
/// start that the given coordinates do not fix (the assembly then takes the least change from
/// the file's guess, which has no derivative) is refused at `sensitivities`.
#[test]
fn dynamic_analyses_without_sensitivities_are_refused() {
    let path = common::example("quick_return_a.yaml");
    let mut model = Model::load(&path).expect("the example");
    model.analyses["dynamics"].integrator.kind = IntegratorKind::Hht;
    let Err(Error::Model(problems)) = run_with(&model, "dynamics", &["crank".to_string()]) else {
        panic!("hht is refused")
    };
    assert_eq!(problems[0].path, "analyses.dynamics.integrator");
    assert!(problems[0].message.contains("use bdf or abam"), "{}", problems[0].message);
    let text = "
name: loose
parameters: {g: 9.81}
gravity: [0, -g]
bodies:
  block: {mass: 1, inertia: 0.1, position: [0, 0], angle: 0}
joints:
  slide: {type: translational, body_i: block, point_i: [0, 0], axis_i: [1, -1], body_j: ground, point_j: [0, 0], axis_j: [1, -1]}
analyses:
  fall: {type: dynamic, t_end: 0.1, step: 0.1}
";
    let model = Model::from_yaml(text).expect("the model");
    let Err(Error::Model(problems)) = run_with(&model, "fall", &["g".to_string()]) else {
        panic!("a start the given coordinates do not fix is refused")
    };
    assert_eq!(problems[0].path, "sensitivities");
    assert!(problems[0].message.contains("1 degree(s) of freedom, 0 given"), "{}", problems[0].message);
}

/// A mass `m` on a spring of stiffness `k` (along a guide; the spring anchored 1 m away at its
/// free length, so that its force is exactly `-k x`), released from `x0` at rest:
/// `x = x0 cos(w t)`, `w = sqrt(k / m)`, so `dx/dk = dx/dw / (2 sqrt(k m))` and
/// `dx/dm = -dx/dw w / (2 m)` with `dx/dw = -x0 t sin(w t)`, and the same for the velocity and
/// the acceleration. Integrated by bdf and by abam at rtol 1e-10 over a period and a half, to 1e-6
/// of each column's largest derivative (the state's global error there is `~1e-9` of its size,
/// and the sensitivities are as accurate as the integrator: measured `~1e-8`).
#[test]
fn a_mass_on_a_spring_matches_its_closed_form() {
    for integrator in ["bdf", "abam"] {
        a_mass_on_a_spring_by(integrator);
    }
}

/// [`a_mass_on_a_spring_matches_its_closed_form`] integrated by `integrator`.
fn a_mass_on_a_spring_by(integrator: &str) {
    let text = "
name: mass-spring
parameters: {k: 100, m: 2}
bodies:
  block: {mass: m, inertia: 0.1, position: [0.1, 0], angle: 0, given: [x, vx]}
joints:
  guide: {type: translational, body_i: block, point_i: [0, 0], axis_i: [1, 0], body_j: ground, point_j: [0, 0], axis_j: [1, 0]}
forces:
  spring: {type: spring_damper, body_i: ground, point_i: [-1, 0], body_j: block, point_j: [0, 0], stiffness: k, free_length: 1}
analyses:
  oscillate: {type: dynamic, t_end: 1.35, step: 0.05, forces: [spring], solver: {rtol: 1e-10, atol: 1e-10}}
"
    .replace("forces: [spring],", &format!("forces: [spring], integrator: {integrator},"));
    let model = Model::from_yaml(&text).expect("the mass on a spring");
    let names: Vec<String> = ["k", "m"].map(String::from).to_vec();
    let results = run_with(&model, "oscillate", &names).expect("the run");
    let sens = results.sensitivities.as_ref().expect("asked for");
    let (k, m, x0) = (100.0f64, 2.0f64, 0.1);
    let w = (k / m).sqrt();
    let (dw_dk, dw_dm) = (1.0 / (2.0 * (k * m).sqrt()), -w / (2.0 * m));
    // Each column's derivative with respect to w.
    let by_w: [(&str, &dyn Fn(f64) -> f64); 3] = [
        ("block.x", &|t| -x0 * t * (w * t).sin()),
        ("block.vx", &|t| -x0 * ((w * t).sin() + w * t * (w * t).cos())),
        ("block.ax", &|t| -x0 * (2.0 * w * (w * t).cos() - w * w * t * (w * t).sin())),
    ];
    for (name, d) in by_w {
        let c = sens.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("{name}"));
        for (p, dw) in [dw_dk, dw_dm].into_iter().enumerate() {
            let scale = results.time.iter().map(|&t| (d(t) * dw).abs()).fold(0.0, f64::max);
            for (row, &t) in results.time.iter().enumerate() {
                let (got, want) = (sens.values[p][c][row], d(t) * dw);
                assert!(
                    (got - want).abs() <= 1e-6 * scale,
                    "{integrator}: d({name})/d({}) at t = {t}: {got:e} against {want:e}",
                    names[p]
                );
            }
        }
    }
}

/// A run of `analysis` with the derivatives with respect to `parameters`, integrated by `abam`
/// (the command line's `--integrator abam`).
fn run_abam(model: &Model, analysis: &str, parameters: &[String]) -> Result<Results, Error> {
    let overrides = linkwork::Overrides { integrator: Some(IntegratorKind::Abam), ..Default::default() };
    let options = RunOptions { sensitivities: parameters.to_vec(), overrides, ..Default::default() };
    model.run(analysis, &options).map_err(|f| f.error)
}

/// The quick-return's free motion (`dynamics`) with every parameter: abam's sensitivities
/// against bdf's (a second formulation: the BDF discretisation differentiated, against the
/// sensitivity equations integrated by the Adams formulas in the independent coordinates), both
/// at rtol 1e-10, to 1e-6 of each column's largest derivative: each is as accurate as its
/// integrator, `1e-8` to `1e-5` of the derivative at that tolerance (bdf's measured in
/// docs/sensitivities.md); measured `4e-8` apart. Where a derivative is zero (the ground-fixed
/// slider's `y`, `phi`) both are round-off, below the floor of `1e-10`.
#[test]
fn abam_and_bdf_sensitivities_agree() {
    let model = tight(Model::load(common::example("quick_return_a.yaml")).expect("the example"), SENSITIVITY_RTOL);
    let parameters: Vec<String> = model.parameters.keys().cloned().collect();
    let bdf = run_with(&model, "dynamics", &parameters).expect("bdf");
    let abam = run_abam(&model, "dynamics", &parameters).expect("abam");
    let (sb, sa) = (bdf.sensitivities.as_ref().unwrap(), abam.sensitivities.as_ref().unwrap());
    assert_eq!(sb.names, sa.names);
    assert_eq!(bdf.time, abam.time);
    let mut largest = 0.0f64;
    for (k, p) in parameters.iter().enumerate() {
        for (c, name) in sb.names.iter().enumerate() {
            let scale = sb.values[k][c].iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let apart = sb.values[k][c].iter().zip(&sa.values[k][c]).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(apart <= 1e-6 * scale + 1e-10, "d({name})/d({p}): bdf and abam {apart:e} apart, largest {scale:e}");
            if apart > 1e-10 {
                largest = largest.max(apart / scale);
            }
        }
    }
    eprintln!("abam and bdf apart by at most {largest:.1e} of a column's largest derivative");
}

/// Two formulations of the kinematic levels give the same derivatives: with several parameters
/// the coordinates' share of the velocity and acceleration levels goes by the time derivatives
/// of `Phi_q` made once per output point, with one parameter by evaluating every element along
/// it (docs/sensitivities.md, "Cost"). Each parameter alone (the second) against all of them at
/// once (the first), on every column of a kinematic and an inverse analysis, to 1e-11 of the
/// largest derivative of the run with respect to the parameter: both are exact, and differ by
/// the round-off of sums taken in another order, which the solves amplify by the condition of
/// `Phi_q` (below 1e3 here); a column whose derivative is zero gets that round-off too.
#[test]
fn the_levels_by_matrices_agree_with_the_levels_by_evaluation() {
    for (file, analysis) in [
        ("quick_return_a.yaml", "kinematics"),
        ("quick_return_a.yaml", "inverse"),
        ("slider_crank_param.yaml", "kinematics"),
    ] {
        let model = Model::load(common::example(file)).expect("the example");
        let names: Vec<String> = model.parameters.keys().cloned().collect();
        let all = run_with(&model, analysis, &names).expect("the run");
        let all = all.sensitivities.as_ref().expect("asked for");
        for (p, name) in names.iter().enumerate() {
            let one = run_with(&model, analysis, std::slice::from_ref(name)).expect("the run");
            let one = one.sensitivities.as_ref().expect("asked for");
            assert_eq!(one.names, all.names, "{file} {analysis}");
            let scale = one.values[0].iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for (c, column) in one.values[0].iter().enumerate() {
                for (k, (a, b)) in column.iter().zip(&all.values[p][c]).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-11 * scale,
                        "{file} {analysis}: d({})/d({name}) at point {k}: {a} alone, {b} with all",
                        one.names[c]
                    );
                }
            }
        }
    }
}

/// The derivatives of column `name` of `results` with respect to each parameter of `names` and
/// its values: `(values, derivatives[parameter])`, each one per output time.
fn column_and_derivatives(results: &Results, name: &str, names: &[String]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let sens = results.sensitivities.as_ref().expect("asked for");
    let c = sens.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("d({name})"));
    let values = results.columns[results.names.iter().position(|n| n == name).expect("the column")].clone();
    (values, (0..names.len()).map(|p| sens.values[p][c].clone()).collect())
}

/// A block of mass `m` pushed along a ground guide at constant speed `V` by an `x` driver at the
/// height `h` above its centre, against the guide's friction (`mu`, block length `L`,
/// transition velocity `v_s`) under gravity: the guide carries the weight and the couple `F h`
/// of the push, `N = m g + F h / L`, and the push balances the friction, `F = mu_e N`, so
/// `F = mu_e m g / D`, `D = 1 - mu_e h / L`, `mu_e = mu tanh(V / v_s)`. The push's effort and
/// the guide's friction (on ground, along the axis: `+F`) and their derivatives with respect to
/// the six parameters, by hand, to 1e-12 of their size: the friction's fixed point converges
/// quadratically, so its last correction (below 1e-10) leaves round-off, and the speed is twice
/// `v_s`, where `tanh` is far from its saturation and every derivative is large.
#[test]
fn a_block_pushed_against_friction_matches_its_closed_form() {
    let text = "
name: block pushed along a guide
parameters: {mu: 0.3, m: 2.0, V: 0.002, v_s: 0.001, L: 0.05, h: 0.01}
gravity: [0, -9.81]
bodies:
  block: {mass: m, inertia: 0.001, position: [0, 0], angle: 0}
joints:
  guide:
    type: translational
    body_i: ground
    point_i: [0, 0]
    axis_i: [1, 0]
    body_j: block
    point_j: [0, 0]
    axis_j: [1, 0]
    friction: {mu: mu, length: L, transition_velocity: v_s}
drivers:
  push: {type: x, body: block, point: [0, h], function: V*t}
analyses:
  inverse: {type: inverse, drivers: [push], t_end: 1.0, step: 0.25}
";
    let model = Model::from_yaml(text).expect("the block");
    let names: Vec<String> = model.parameters.keys().cloned().collect();
    let results = run_with(&model, "inverse", &names).expect("the run");
    let [mu, m, v, v_s, l, h] = ["mu", "m", "V", "v_s", "L", "h"].map(|p| model.parameters[p]);
    let g = 9.81;
    let (tanh, sech2) = ((v / v_s).tanh(), 1.0 / (v / v_s).cosh().powi(2));
    let mu_e = mu * tanh;
    let d = 1.0 - mu_e * h / l;
    let force = mu_e * m * g / d;
    // dF/dmu_e = m g / D^2; the others through D directly.
    let by_mu_e = m * g / (d * d);
    let expected = [
        by_mu_e * tanh,
        mu_e * g / d,
        by_mu_e * mu * sech2 / v_s,
        -by_mu_e * mu * sech2 * v / (v_s * v_s),
        -mu_e * m * g * mu_e * h / (l * l) / (d * d),
        mu_e * m * g * mu_e / l / (d * d),
    ];
    for column in ["push.effort", "guide.friction"] {
        let (values, derivatives) = column_and_derivatives(&results, column, &names);
        for (k, &value) in values.iter().enumerate() {
            assert!((value - force).abs() <= 1e-12 * force, "{column}: {value} against {force}");
            for (p, want) in expected.iter().enumerate() {
                let got = derivatives[p][k];
                let scale = want.abs().max(force / model.parameters[&names[p]]);
                assert!((got - want).abs() <= 1e-12 * scale, "d({column})/d({}): {got} against {want}", names[p]);
            }
        }
    }
}

/// A wheel of mass `m` turned at the constant speed `w` on a pin of radius `r` with friction
/// `mu` (transition velocity 1 mm/s, the default), its centre on the pin, pulled sideways by a
/// force `P` under gravity: the pin carries `N = sqrt(P^2 + (m g)^2)`, its friction torque on
/// the wheel is `-mu_e r N` with `mu_e = mu tanh(r w / v_s)`, and the motor's effort `mu_e r N`.
/// Both and their derivatives with respect to `mu`, `r` (which enters `mu_e` too), `m`, `w` and
/// `P`, by hand, to 1e-12 of their size (`r w = 2 v_s`: `tanh` far from saturated).
#[test]
fn a_pin_with_friction_under_a_known_load_matches_its_closed_form() {
    let text = "
name: wheel on a pin with friction
parameters: {mu: 0.2, r: 0.01, m: 3.0, w: 0.2, P: 20.0}
gravity: [0, -9.81]
bodies:
  wheel: {mass: m, inertia: 0.01, position: [0, 0], angle: 0}
joints:
  O: {type: revolute, body_i: wheel, point_i: [0, 0], body_j: ground, point_j: [0, 0], friction: {mu: mu, radius: r}}
drivers:
  motor: {type: angle, body: wheel, function: w*t}
forces:
  pull: {type: force, body: wheel, fx: P}
analyses:
  inverse: {type: inverse, drivers: [motor], forces: [pull], t_end: 1.0, step: 0.25}
";
    let model = Model::from_yaml(text).expect("the wheel");
    let names: Vec<String> = model.parameters.keys().cloned().collect();
    let results = run_with(&model, "inverse", &names).expect("the run");
    let [mu, r, m, w, p] = ["mu", "r", "m", "w", "P"].map(|p| model.parameters[p]);
    let (g, v_s) = (9.81, 1e-3);
    let (tanh, sech2) = ((r * w / v_s).tanh(), 1.0 / (r * w / v_s).cosh().powi(2));
    let mu_e = mu * tanh;
    let n = p.hypot(m * g);
    let effort = mu_e * r * n;
    let expected = [
        tanh * r * n,
        mu * sech2 * w / v_s * r * n + mu_e * n,
        mu_e * r * m * g * g / n,
        mu * sech2 * r / v_s * r * n,
        mu_e * r * p / n,
    ];
    for (column, sign) in [("motor.effort", 1.0), ("O.friction", -1.0)] {
        let (values, derivatives) = column_and_derivatives(&results, column, &names);
        for (k, &value) in values.iter().enumerate() {
            assert!((value - sign * effort).abs() <= 1e-12 * effort, "{column}: {value} against {}", sign * effort);
            for (j, want) in expected.iter().enumerate() {
                let (got, want) = (derivatives[j][k], sign * want);
                let scale = want.abs().max(effort / model.parameters[&names[j]]);
                assert!((got - want).abs() <= 1e-12 * scale, "d({column})/d({}): {got} against {want}", names[j]);
            }
        }
    }
}

/// The four-bar of `fourbar_measures.yaml` with massless links (`rho = 0`): the motor's power is
/// the brake's, so the mechanical advantage `-brake / motor.effort` is `1 / vr`, the inverse of
/// the velocity ratio, whatever the load. Its derivatives with respect to the four lengths are
/// `-d(vr)/dx / vr^2` (the velocity ratio's, a kinematic measure), and with respect to the load
/// zero, to 1e-10 of their size (the two formulations share the positions, converged to 1e-12).
#[test]
fn a_massless_four_bars_mechanical_advantage_is_the_inverse_velocity_ratio() {
    let model = Model::load(common::example("fourbar_measures.yaml")).expect("the example");
    let model = model.with_parameters(&[("rho".to_string(), "0".to_string())]).expect("massless");
    let names: Vec<String> = ["a", "b", "c", "d", "load"].map(String::from).to_vec();
    let results = run_with(&model, "inverse", &names).expect("the run");
    let (ma, dma) = column_and_derivatives(&results, "ma", &names);
    let (vr, dvr) = column_and_derivatives(&results, "vr", &names);
    for k in 0..ma.len() {
        assert!((ma[k] - 1.0 / vr[k]).abs() <= 1e-10 * ma[k].abs(), "ma {} against 1/vr {}", ma[k], 1.0 / vr[k]);
        let scale = dma.iter().map(|d| d[k].abs()).fold(ma[k].abs(), f64::max);
        for (p, name) in names.iter().enumerate() {
            let want = if name == "load" { 0.0 } else { -dvr[p][k] / (vr[k] * vr[k]) };
            let got = dma[p][k];
            assert!(
                (got - want).abs() <= 1e-10 * scale,
                "d(ma)/d({name}) at {}: {got} against {want}",
                results.time[k]
            );
        }
    }
}
