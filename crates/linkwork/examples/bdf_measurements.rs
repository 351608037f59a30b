//! The `bdf` measurements of docs/integrators.md (`bdf` section): each case's error against its
//! independent reference (`tests/common/references.rs`), steps, rejected steps, Newton failures
//! and CPU time, for each formulation and tolerance, as Markdown table rows.
//!
//! ```sh
//! cargo run --release -p linkwork --example bdf_measurements -- quick_return  # the unloaded quick-return A
//! cargo run --release -p linkwork --example bdf_measurements -- a01           # the IFToMM A01 pendulum
//! cargo run --release -p linkwork --example bdf_measurements -- andrews       # digits against the converged end
//! cargo run --release -p linkwork --example bdf_measurements -- a02           # the IFToMM A02 N-four-bar
//! cargo run --release -p linkwork --example bdf_measurements -- sweep         # every example's failures, 1e-4 .. 1e-13
//! ```
//!
//! Environment: `TOLS=1e-8,1e-10` chooses the tolerances, `FORM=index3|si2` the formulation
//! (both without it), `MAX_ORDER=k` the order limit, `T_END` shortens A01 and A02, `ALL=1` makes
//! `sweep` print the runs that reach their end too.

// 6.283 rad/s is the file's given crank speed, not 2 pi.
#![allow(clippy::approx_constant)]

#[path = "../tests/common/mod.rs"]
mod common;

use common::references::{andrews_digits, nfourbar_error, pendulum_error, QuickReturn, ANDREWS_END_CONVERGED, SAMPLES};
use common::run_bdf as run;
use linkwork::analysis::dynamic::Formulation;
use linkwork::{Model, Results};

/// The example `name`, every analysis with the order limit of `MAX_ORDER`, if set.
fn load(name: &str) -> Model {
    let mut model = Model::load(common::example(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    if let Some(k) = std::env::var("MAX_ORDER").ok().and_then(|s| s.parse().ok()) {
        for analysis in model.analyses.values_mut() {
            analysis.integrator.max_order = Some(k);
        }
    }
    model
}

fn stat(r: &Results, name: &str) -> f64 {
    r.summary_json(None)["statistics"][name].as_f64().unwrap_or(f64::NAN)
}

/// The tolerances of `TOLS`, or `default`.
fn tols(default: &[f64]) -> Vec<f64> {
    std::env::var("TOLS")
        .map(|s| s.split(',').map(|x| x.parse().expect("TOLS: numbers separated by commas")).collect())
        .unwrap_or_else(|_| default.to_vec())
}

/// The formulations of `FORM`, or both.
fn forms() -> Vec<(&'static str, Formulation)> {
    match std::env::var("FORM").as_deref() {
        Ok("index3") => vec![("index3", Formulation::Index3)],
        Ok("si2") => vec![("si2", Formulation::Si2)],
        _ => vec![("si2", Formulation::Si2), ("index3", Formulation::Index3)],
    }
}

/// `T_END`, or `default`.
fn t_end(default: Option<f64>) -> Option<f64> {
    std::env::var("T_END").ok().and_then(|s| s.parse().ok()).or(default)
}

/// One table row: case, formulation, tolerance, the error as `what`, the statistics, the CPU
/// time, where the run ended and its error if it stopped.
fn report(name: &str, fname: &str, tol: f64, what: &str, r: &Results, e: Option<String>, cpu: f64) {
    println!(
        "| {name} | {fname} | {tol:.0e} | {what} | {} | {} | {} | {cpu:.3} | {} {} |",
        stat(r, "steps"),
        stat(r, "rejected_steps"),
        stat(r, "newton_failures"),
        r.time[r.len() - 1],
        e.map(|e| e.chars().take(120).collect::<String>()).unwrap_or_default()
    );
}

fn quick_return() {
    let mut model = load("quick_return_a.yaml");
    let reference = QuickReturn::new(&model, 6.283, SAMPLES);
    for (fname, f) in forms() {
        for tol in tols(&[1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13]) {
            let (r, e, cpu) = run(&mut model, "dynamics", f, tol, None);
            let err = reference.error(&r);
            report("quick_return_a", fname, tol, &format!("{err:.2e} ({:.0} x tol)", err / tol), &r, e, cpu);
        }
    }
}

fn a01() {
    let mut model = load("iftomm_a01_pendulum.yaml");
    for (fname, f) in forms() {
        for tol in tols(&[1e-8, 1e-10, 1e-12]) {
            let (r, e, cpu) = run(&mut model, "dynamics", f, tol, t_end(None));
            report("A01", fname, tol, &format!("{:.2e}", pendulum_error(&r)), &r, e, cpu);
        }
    }
}

fn andrews() {
    let mut model = load("andrews.yaml");
    for (fname, f) in forms() {
        for tol in tols(&[1e-6, 1e-8, 1e-10, 1e-12]) {
            let (r, e, cpu) = run(&mut model, "dynamics", f, tol, None);
            let digits = format!("{:.2} digits", andrews_digits(&r, &ANDREWS_END_CONVERGED));
            report("andrews", fname, tol, &digits, &r, e, cpu);
        }
    }
}

fn a02() {
    let mut model = load("iftomm_a02_nfourbar.yaml");
    for (fname, f) in forms() {
        for tol in tols(&[1e-8, 1e-10, 1e-12]) {
            let (r, e, cpu) = run(&mut model, "dynamics", f, tol, t_end(None));
            report("A02", fname, tol, &format!("{:.2e}", nfourbar_error(&r, 40)), &r, e, cpu);
        }
    }
}

/// Every example's dynamic analyses at tolerances `1e-4` to `1e-13` (A01 over 20 s): prints
/// the failures.
fn sweep() {
    let cases: &[(&str, &str, Option<f64>)] = &[
        ("quick_return_a.yaml", "dynamics", None),
        ("quick_return_a.yaml", "dynamics_loaded", None),
        ("quick_return_b.yaml", "dynamics", None),
        ("quick_return_b.yaml", "dynamics_loaded", None),
        ("andrews.yaml", "dynamics", None),
        ("iftomm_a01_pendulum.yaml", "dynamics", Some(20.0)),
        ("iftomm_a02_nfourbar.yaml", "dynamics", t_end(None)),
        ("double_pendulum.yaml", "dynamics", None),
        ("wedge.yaml", "dynamics", None),
    ];
    for (fname, f) in forms() {
        for &(file, analysis, t_end) in cases {
            let mut model = load(file);
            for k in 4..=13 {
                let tol = 10f64.powi(-k);
                let (r, e, cpu) = run(&mut model, analysis, f, tol, t_end);
                if e.is_some() || std::env::var("ALL").is_ok() {
                    report(&format!("{file} {analysis}"), fname, tol, "", &r, e, cpu);
                }
            }
        }
    }
}

fn main() {
    let what = std::env::args().nth(1).unwrap_or_default();
    match what.as_str() {
        "quick_return" => quick_return(),
        "a01" => a01(),
        "andrews" => andrews(),
        "a02" => a02(),
        "sweep" => sweep(),
        _ => {
            eprintln!("usage: bdf_measurements quick_return|a01|andrews|a02|sweep");
            std::process::exit(2);
        }
    }
}
