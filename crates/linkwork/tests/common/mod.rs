//! Shared harness of the reference tests: load an example, run it, and compare columns with a
//! reference given as closed-form functions of time. Closed forms are written once, generically,
//! and evaluated with hyper-dual numbers, so that the reference velocity and acceleration are the
//! exact first and second time derivatives of the reference position (no finite differences).

#![allow(dead_code)]

pub mod references;

use linkwork::analysis::dynamic::{Formulation, IntegratorKind};
use linkwork::expr::{HyperDual, Scalar};
use linkwork::{Model, Overrides, Results};
use std::time::Instant;

/// Path of a file in the repository's `examples/` folder.
pub fn example(name: &str) -> String {
    format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The text of an example's model file.
pub fn example_text(name: &str) -> String {
    std::fs::read_to_string(example(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `text` with `from` replaced by `to`; panics unless `from` occurs exactly once, so that a test
/// whose model text changed under it fails instead of running the text unchanged.
pub fn patch(text: &str, from: &str, to: &str) -> String {
    let count = text.matches(from).count();
    assert_eq!(count, 1, "{from:?} occurs {count} times in the text to patch, not once");
    text.replacen(from, to, 1)
}

/// Overrides that select the integrator `kind` at `rtol = atol = tol` over `t_end` (the
/// analysis's own when `None`).
pub fn at_tolerance(kind: IntegratorKind, tol: f64, t_end: Option<f64>) -> Overrides {
    Overrides { integrator: Some(kind), rtol: Some(tol), atol: Some(tol), t_end, ..Default::default() }
}

/// Every integrator, with its name in model files.
pub fn integrators() -> impl Iterator<Item = (&'static str, IntegratorKind)> {
    IntegratorKind::NAMES.iter().map(|&name| (name, IntegratorKind::from_name(name).expect("a name of NAMES")))
}

/// The joints of a slider-crank of bodies `crank` (points `O`, `A`), `rod` (`A`, `B`) and
/// `slider`: the crank pinned to ground at `O`, the rod to the crank at `A` and to the slider at
/// `B`, the slider on a guide along x through the origin.
pub const SLIDER_CRANK_JOINTS: &str = "joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
  A: {type: revolute, body_i: crank, point_i: A, body_j: rod, point_j: A}
  B: {type: revolute, body_i: rod, point_i: B, body_j: slider, point_j: [0, 0]}
  guide: {type: translational, body_i: ground, point_i: [0, 0], axis_i: [1, 0], body_j: slider, point_j: [0, 0], axis_j: [1, 0]}
";

/// The text of an example's model file with each `(from, to)` of `changes` made in turn, by
/// [`patch`].
pub fn patched_example(name: &str, changes: &[(&str, &str)]) -> String {
    changes.iter().fold(example_text(name), |text, (from, to)| patch(&text, from, to))
}

/// Load and run an example's analysis; panics with the engine's message on failure.
pub fn run(name: &str, analysis: &str) -> (Model, Results) {
    let model = Model::load(example(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let results = model.run(analysis, &Default::default()).unwrap_or_else(|f| panic!("{name}: {}", f.error));
    (model, results)
}

/// Run `analysis` of `model` with `bdf` in `formulation` at `rtol = atol = tol`, up to `t_end`
/// (the analysis's own when `None`); returns the results (up to the failure, if one), the error
/// message if any, and the CPU time, s.
pub fn run_bdf(
    model: &mut Model,
    analysis: &str,
    formulation: Formulation,
    tol: f64,
    t_end: Option<f64>,
) -> (Results, Option<String>, f64) {
    model.analyses[analysis].integrator.formulation = formulation;
    let o = at_tolerance(IntegratorKind::Bdf, tol, t_end);
    let start = Instant::now();
    let r = model.run(analysis, &o.into());
    let cpu = start.elapsed().as_secs_f64();
    match r {
        Ok(r) => (r, None, cpu),
        Err(f) => (f.results, Some(f.error.to_string()), cpu),
    }
}

/// Run `analysis` of `model` with the integrator `kind` at `rtol = atol = tol`, up to `t_end`;
/// returns the results and the CPU time, s; panics with the engine's message on failure.
pub fn run_tol(model: &Model, analysis: &str, kind: IntegratorKind, tol: f64, t_end: Option<f64>) -> (Results, f64) {
    let o = at_tolerance(kind, tol, t_end);
    let clock = Instant::now();
    let r = model.run(analysis, &o.into()).unwrap_or_else(|f| panic!("{} {analysis} {tol}: {}", model.name, f.error));
    (r, clock.elapsed().as_secs_f64())
}

/// The problems loading `text` reports; panics when it loads or fails otherwise.
pub fn model_problems(text: &str) -> Vec<linkwork::Problem> {
    match Model::from_yaml(text) {
        Err(linkwork::Error::Model(p)) => p,
        Err(e) => panic!("expected a model error, got {e}"),
        Ok(_) => panic!("expected a model error, the model compiled"),
    }
}

/// The problems loading `text` reports, each as `path: message`.
pub fn problems(text: &str) -> Vec<String> {
    model_problems(text).iter().map(ToString::to_string).collect()
}

/// The column `name` of `r`; panics naming it when there is none.
pub fn col<'a>(r: &'a Results, name: &str) -> &'a [f64] {
    r.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Largest change of the total mechanical energy `T + V - W` over the run.
pub fn energy_drift(r: &Results) -> f64 {
    let (t, v, w) = (col(r, "kinetic_energy"), col(r, "potential_energy"), col(r, "nonconservative_work"));
    let e0 = t[0] + v[0] - w[0];
    (0..r.len()).map(|k| (t[k] + v[k] - w[k] - e0).abs()).fold(0.0, f64::max)
}

/// `(f(t), f'(t), f''(t))` of a closed form `f`, exactly.
pub fn derivatives(f: impl Fn(HyperDual) -> HyperDual, t: f64) -> [f64; 3] {
    let y = f(HyperDual::variable(t));
    [y.v, y.e1, y.e12]
}

/// Tolerance of a quantity: `tol` absolute below magnitude 1, relative above (accelerations of a
/// fast mechanism reach hundreds of m/s^2, where 1e-10 absolute would ask for 1e-13 relative).
pub fn close(got: f64, want: f64, tol: f64) -> bool {
    (got - want).abs() <= tol * want.abs().max(1.0)
}

/// Compare body `body`'s column `<body>.<q>` (q = x, y or phi) and its two derivative columns
/// with the closed form `f` at every output time.
pub fn check_coordinate(r: &Results, body: &str, q: &str, f: impl Fn(HyperDual) -> HyperDual, tol: f64) {
    let names = match q {
        "x" => ["x", "vx", "ax"],
        "y" => ["y", "vy", "ay"],
        "phi" => ["phi", "omega", "alpha"],
        _ => panic!("coordinate {q}"),
    };
    let cols: Vec<&[f64]> = names.iter().map(|n| r.column(&format!("{body}.{n}")).expect("column")).collect();
    let mut worst = [0.0f64; 3];
    for (k, &t) in r.time.iter().enumerate() {
        let want = derivatives(&f, t);
        for d in 0..3 {
            let got = cols[d][k];
            assert!(close(got, want[d], tol), "{body}.{} at t = {t}: engine {got}, closed form {}", names[d], want[d]);
            worst[d] = worst[d].max((got - want[d]).abs());
        }
    }
    eprintln!(
        "{body}.{q}: largest differences (position, velocity, acceleration) {:.2e} {:.2e} {:.2e}",
        worst[0], worst[1], worst[2]
    );
}

/// `x^2` for any scalar.
pub fn sq<S: Scalar>(x: S) -> S {
    x * x
}

/// A constant as a scalar.
pub fn c<S: Scalar>(v: f64) -> S {
    S::constant(v)
}

/// A bar pinned at one end under gravity, driven by the torque `name` of expression `torque`,
/// N m, its dynamics to 1 s output every `step` s (`tests/models/pendulum_torque.yaml`).
pub fn pendulum_with_torque(name: &str, torque: &str, step: f64) -> linkwork::Model {
    let text = patch(
        include_str!("../models/pendulum_torque.yaml"),
        "kick: {type: torque, body: bar, torque: \"0\"}",
        &format!("{name}: {{type: torque, body: bar, torque: \"{torque}\"}}"),
    );
    linkwork::Model::from_yaml(&patch(&text, "step: 0.01}", &format!("step: {step}}}"))).unwrap()
}

/// The `motion` analysis of the cam example `name` (1.5 s at a degree a step: 541 rows, the cam
/// past a whole turn) and its follower's `y`, `vy` and `ay`.
pub fn cam_motion(name: &str) -> (Results, [Vec<f64>; 3]) {
    let (_, r) = run(name, "motion");
    assert_eq!(r.len(), 541, "{name}: 1.5 s at a degree a step");
    let follower = ["y", "vy", "ay"].map(|q| col(&r, &format!("follower.{q}")).to_vec());
    (r, follower)
}

/// A cam's lift in the cam angle `theta` (any turn): a cycloidal rise of `h` over `rise` rad from
/// 0, a dwell to pi, a cycloidal return over `ret` rad, a dwell to 2 pi; `(s, s', s'')` in `theta`.
/// Written out from the law `s(u) = u - sin(2 pi u) / (2 pi)`, independently of the engine's.
pub fn cycloidal_cam_lift(theta: f64, h: f64, rise: f64, ret: f64) -> (f64, f64, f64) {
    use std::f64::consts::PI;
    let theta = theta.rem_euclid(2.0 * PI);
    let cycloidal = |u: f64, beta: f64| {
        let w = 2.0 * PI * u;
        (h * (u - w.sin() / (2.0 * PI)), h * (1.0 - w.cos()) / beta, h * 2.0 * PI * w.sin() / (beta * beta))
    };
    if theta <= rise {
        cycloidal(theta / rise, rise)
    } else if theta <= PI {
        (h, 0.0, 0.0)
    } else if theta <= PI + ret {
        let (s, d1, d2) = cycloidal((theta - PI) / ret, ret);
        (h - s, -d1, -d2)
    } else {
        (0.0, 0.0, 0.0)
    }
}
