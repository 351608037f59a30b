//! The work-precision table of docs/integrators.md: for each model, integrator and tolerance
//! (`rtol = atol`), the global error against an independent reference and the cost.
//!
//! ```sh
//! cargo run --release -p linkwork --example work_precision            # every case
//! cargo run --release -p linkwork --example work_precision -- a01    # cases whose name has "a01"
//! cargo run --release -p linkwork --example work_precision -- output # A01 with and without the
//!                                                                    # step capped at the output step
//! cargo run --release -p linkwork --example work_precision -- sweep [FILTER] [INTEGRATOR]
//!     # every dynamic analysis of every example at rtol = atol = 1e-4 .. 1e-13: does it reach its end?
//! cargo run --release -p linkwork --example work_precision -- one FILE INTEGRATOR TOL
//!     # one run of a file's `dynamics` (for a profiler: `valgrind --tool=callgrind` counts its
//!     # instructions whatever else the machine runs); an N-four-bar's (N = 40) B0 error too
//! cargo run --release -p linkwork --example work_precision -- spread FILE INTEGRATOR TOL [COUNT]
//!     # a table case's error at COUNT (20) tolerances TOL (1 + k 1e-6), k = 0, 1, ..: how far
//!     # a change of the steps by rounding moves it (its smallest, median and largest)
//! ```
//!
//! Prints a Markdown table: the error (largest over the output times of the positions named
//! per model, m or rad; for Andrews the significant digits at t = 0.03 as the test set counts
//! them, `-log10` of the largest relative error, against the converged solution
//! `ANDREWS_END_CONVERGED`), the CPU time of `Model::run` (the best of
//! three for runs under a second), steps, rejected steps and factorizations. A failed run prints
//! its error and where it stopped.

#[path = "../tests/common/references.rs"]
#[allow(dead_code)]
mod references;

use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::model::spec::AnalysisKind;
use linkwork::{Model, Overrides, Results};
use references::{
    andrews_digits, nfourbar_error, pendulum_error, QuickReturn, ANDREWS_END_CONVERGED, QUICK_RETURN_CRANK_SPEED,
    SAMPLES,
};
use std::time::Instant;

/// Every integrator, with its name in model files.
fn integrators() -> impl Iterator<Item = (&'static str, IntegratorKind)> {
    IntegratorKind::NAMES.iter().filter_map(|&name| Some((name, IntegratorKind::from_name(name)?)))
}

fn example(name: &str) -> String {
    format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// How to measure a run's error: `(error, unit)`.
type ErrorMeasure = Box<dyn Fn(&Results) -> (f64, &'static str)>;

/// A model, its analysis, the tolerances to try and how to measure a run's error.
struct Case {
    name: &'static str,
    file: &'static str,
    tolerances: &'static [f64],
    error: ErrorMeasure,
}

fn cases() -> Vec<Case> {
    let qr = Model::load(example("quick_return_a.yaml")).expect("quick_return_a.yaml");
    let reference = QuickReturn::new(&qr, QUICK_RETURN_CRANK_SPEED, SAMPLES);
    vec![
        Case {
            name: "quick-return A, unloaded, 2 s",
            file: "quick_return_a.yaml",
            tolerances: &[1e-6, 1e-8, 1e-10, 1e-12],
            error: Box::new(move |r| (reference.error(r), "m, rad")),
        },
        Case {
            name: "Andrews, 0.03 s",
            file: "andrews.yaml",
            tolerances: &[1e-6, 1e-8, 1e-10, 1e-12],
            error: Box::new(|r| (andrews_digits(r, &ANDREWS_END_CONVERGED), "digits")),
        },
        Case {
            name: "IFToMM A01 pendulum, 2000 s",
            file: "iftomm_a01_pendulum.yaml",
            tolerances: &[1e-6, 1e-8, 1e-10, 1e-12],
            error: Box::new(|r| (pendulum_error(r), "m")),
        },
        Case {
            name: "IFToMM A02 N-four-bar, N = 40, 20 s",
            file: "iftomm_a02_nfourbar.yaml",
            tolerances: &[1e-6, 1e-8, 1e-10, 1e-12],
            error: Box::new(|r| (nfourbar_error(r, 40), "m")),
        },
    ]
}

/// A01's 2000 s with its 200,001 output times, with the step capped at the output step (the old
/// default, `solver.max_step: 0.01`) and free (the default): steps, time and error.
fn output_step_effect() {
    let text = std::fs::read_to_string(example("iftomm_a01_pendulum.yaml")).expect("A01");
    let from = "dynamics: {type: dynamic, t_end: 2000, step: 0.01}";
    assert!(text.contains(from), "the A01 file's analysis line changed");
    let capped = text.replace(from, "dynamics: {type: dynamic, t_end: 2000, step: 0.01, solver: {max_step: 0.01}}");
    println!("| A01, 200,001 outputs | integrator | rtol = atol | max_step | error (m) | CPU time (s) | steps |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (label, kind) in integrators() {
        for tol in [1e-6, 1e-8] {
            for (cap, yaml) in [("0.01 (output step)", &capped), ("default", &text)] {
                let model = Model::from_yaml(yaml).expect("model");
                let o = Overrides { integrator: Some(kind), rtol: Some(tol), atol: Some(tol), ..Default::default() };
                let start = Instant::now();
                let (r, note) = match model.run("dynamics", &o.clone().into()) {
                    Ok(r) => (r, String::new()),
                    Err(f) => (f.results, format!(" (failed: {})", f.error)),
                };
                let time = start.elapsed().as_secs_f64();
                let err = pendulum_error(&r);
                let steps = &r.summary_json(None)["statistics"]["steps"];
                println!("| | {label} | {tol:e} | {cap} | {err:.2e}{note} | {time:.2} | {steps} |");
            }
        }
    }
}

/// Every dynamic analysis of every example file whose name contains `filter`, with every
/// integrator whose name contains `integrator`, at `rtol = atol = 1e-4, 1e-5, .., 1e-13`: whether
/// it reaches its end, and if not, the error and where it stopped, with the steps and CPU time.
fn sweep(filter: &str, integrator: &str) {
    let dir = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("examples/")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| f.ends_with(".yaml") && f.contains(filter))
        .collect();
    files.sort();
    println!("| file | analysis | integrator | rtol = atol | outcome | CPU time (s) | steps |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    let (mut runs, mut failures) = (0, 0);
    for file in files {
        let model = Model::load(example(&file)).expect("model");
        let dynamic: Vec<&String> =
            model.analyses.iter().filter(|(_, a)| a.kind == AnalysisKind::Dynamic).map(|(name, _)| name).collect();
        for analysis in dynamic {
            for (label, kind) in integrators().filter(|(l, _)| l.contains(integrator)) {
                for e in 4..=13 {
                    let tol = 10f64.powi(-e);
                    let o =
                        Overrides { integrator: Some(kind), rtol: Some(tol), atol: Some(tol), ..Default::default() };
                    let start = Instant::now();
                    let run = model.run(analysis, &o.clone().into());
                    let time = start.elapsed().as_secs_f64();
                    runs += 1;
                    let (outcome, r) = match run {
                        Ok(r) => ("end".to_string(), r),
                        Err(f) => {
                            failures += 1;
                            (format!("**stopped**: {}", f.error), f.results)
                        }
                    };
                    let steps = &r.summary_json(None)["statistics"]["steps"];
                    println!("| {file} | {analysis} | {label} | {tol:e} | {outcome} | {time:.2} | {steps} |");
                }
            }
        }
    }
    println!("\n{runs} runs, {failures} stopped before their end");
}

/// One run of `file`'s `dynamics` with `integrator` at `rtol = atol = tol`: its outcome, CPU
/// time and statistics.
fn one(file: &str, integrator: &str, tol: f64) {
    let kind = IntegratorKind::from_name(integrator)
        .unwrap_or_else(|| panic!("INTEGRATOR: one of {}", IntegratorKind::NAMES.join(", ")));
    let model = Model::load(example(file)).expect("model");
    let o = Overrides { integrator: Some(kind), rtol: Some(tol), atol: Some(tol), ..Default::default() };
    let start = Instant::now();
    let run = model.run("dynamics", &o.clone().into());
    let time = start.elapsed().as_secs_f64();
    let r = match run {
        Ok(r) => r,
        Err(f) => {
            println!("stopped: {}", f.error);
            f.results
        }
    };
    println!("{file} {integrator} {tol:e}: {time:.3} s, {}", r.summary_json(None)["statistics"]);
    if file.contains("nfourbar") {
        println!("B0 error to t = {}: {:.3e} m", r.time.last().unwrap_or(&0.0), nfourbar_error(&r, 40));
    }
    println!("warnings: {}", r.summary_json(None)["warnings"]);
}

/// The error of the table's case for `file` with `integrator` at `COUNT` tolerances
/// `tol (1 + k 1e-6)`: a change far below any tolerance's meaning, which moves every step by a
/// relative `1e-6 / order` and so samples how far rounding-sized changes of the steps move the
/// error (on A02, whose flat positions amplify them, by up to two decades at `1e-8`).
fn spread(file: &str, integrator: &str, tol: f64, count: usize) {
    let kind = IntegratorKind::from_name(integrator)
        .unwrap_or_else(|| panic!("INTEGRATOR: one of {}", IntegratorKind::NAMES.join(", ")));
    let case = cases().into_iter().find(|c| c.file == file).expect("FILE: a file of the table's cases");
    let model = Model::load(example(file)).expect("model");
    let mut errors = Vec::with_capacity(count);
    for k in 0..count {
        let t = tol * (1.0 + k as f64 * 1e-6);
        let o = Overrides { integrator: Some(kind), rtol: Some(t), atol: Some(t), ..Default::default() };
        let r = match model.run("dynamics", &o.clone().into()) {
            Ok(r) => r,
            Err(f) => {
                println!("{t:e}: stopped: {}", f.error);
                continue;
            }
        };
        let (error, unit) = (case.error)(&r);
        println!("{t:e}: {error:.3e} {unit}");
        errors.push(error);
    }
    errors.sort_by(f64::total_cmp);
    if let (Some(first), Some(last)) = (errors.first(), errors.last()) {
        let median = errors[errors.len() / 2];
        println!("{} runs: smallest {first:.3e}, median {median:.3e}, largest {last:.3e}", errors.len());
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).map(|a| a.to_lowercase()).collect();
    let filter = args.first().cloned().unwrap_or_default();
    if filter == "output" {
        return output_step_effect();
    }
    let arg = |k: usize| args.get(k).map_or("", String::as_str);
    if filter == "sweep" {
        return sweep(arg(1), arg(2));
    }
    if filter == "one" {
        return one(arg(1), arg(2), arg(3).parse().expect("TOL: a number"));
    }
    if filter == "spread" {
        let count = if arg(4).is_empty() { 20 } else { arg(4).parse().expect("COUNT: a whole number") };
        return spread(arg(1), arg(2), arg(3).parse().expect("TOL: a number"), count);
    }
    println!("| model | integrator | rtol = atol | error | unit | CPU time (s) | steps | rejected | factorizations |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for case in cases() {
        if !case.name.to_lowercase().contains(&filter) && !case.file.contains(&filter) {
            continue;
        }
        let model = Model::load(example(case.file)).expect("model");
        for (label, kind) in integrators() {
            for &tol in case.tolerances {
                let o = Overrides { integrator: Some(kind), rtol: Some(tol), atol: Some(tol), ..Default::default() };
                let (mut best, mut outcome) = (f64::INFINITY, None);
                for _ in 0..3 {
                    let start = Instant::now();
                    let run = model.run("dynamics", &o.clone().into());
                    best = best.min(start.elapsed().as_secs_f64());
                    outcome = Some(run);
                    if best > 1.0 {
                        break;
                    }
                }
                let (results, failure) = match outcome.expect("ran") {
                    Ok(r) => (r, String::new()),
                    Err(f) => (f.results, format!(" (failed: {})", f.error)),
                };
                let (error, unit) = (case.error)(&results);
                let s = &results.summary_json(None)["statistics"];
                let error = if unit == "digits" { format!("{error:.2}") } else { format!("{error:.2e}") };
                println!(
                    "| {} | {label} | {tol:e} | {error}{failure} | {unit} | {best:.3} | {} | {} | {} |",
                    case.name, s["steps"], s["rejected_steps"], s["factorizations"]
                );
            }
        }
    }
}
