//! The `hht` measurements of docs/integrators.md (`hht` section): errors against the independent
//! references (`tests/common/references.rs`), energy loss, steps and CPU time of the cases that
//! `DIAG` names, at the tolerances of `TOLS`, printed one line a run.
//!
//! ```sh
//! DIAG=bar,a01,qr,andr,iftomm_a02 TOLS=1e-6,1e-8 [TEND=..] cargo run --release -p linkwork --example hht_measurements
//! ```
//!
//! `bar`: a bar pinned off its centre on a torsion spring (`phi = 0.5 cos 2t` exactly), 20
//! periods; `a01`: the IFToMM A01 pendulum; `qr`: the coasting quick-return A; `andr`, `iftomm_a02`:
//! Andrews' mechanism and the A02 N-four-bar, whether they reach their end. `TEND` ends every run
//! there.

#[path = "../tests/common/mod.rs"]
mod common;

use common::references::{
    a01_energy_loss_per_period, pendulum_error as a01_error, QuickReturn, A01_PERIOD, QUICK_RETURN_CRANK_SPEED, SAMPLES,
};
use common::{at_tolerance, col, energy_drift, run_tol};
use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Model, Results};

/// The bar of `bar`.
const BAR: &str = include_str!("../tests/models/pinned_bar.yaml");
/// How long `bar` runs without `TEND`, s: 20 periods.
const BAR_END: f64 = 62.83185307179586;

fn load(name: &str) -> Model {
    Model::load(common::example(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn steps(r: &Results) -> u64 {
    r.summary_json(None)["statistics"]["steps"].as_u64().unwrap_or_default()
}

fn main() {
    let what = std::env::var("DIAG").unwrap_or_default();
    let tols: Vec<f64> =
        std::env::var("TOLS").unwrap_or("1e-6,1e-8".into()).split(',').map(|s| s.parse().unwrap()).collect();
    let t_end: Option<f64> = std::env::var("TEND").ok().map(|s| s.parse().unwrap());
    if what.contains("bar") {
        let m = Model::from_yaml(BAR).unwrap();
        for &tol in &tols {
            let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, tol, t_end.or(Some(BAR_END)));
            let (t, v) = (col(&r, "kinetic_energy"), col(&r, "potential_energy"));
            let e: Vec<f64> = (0..r.len()).map(|k| t[k] + v[k]).collect();
            let periods = r.time[r.len() - 1] / std::f64::consts::PI;
            let phi = col(&r, "bar.phi");
            let err = r.time.iter().zip(phi).map(|(t, p)| (p - 0.5 * (2.0 * t).cos()).abs()).fold(0.0, f64::max);
            eprintln!("BAR tol {tol:e}: energy loss per period {:.4e} (E0 {:.4}, min {:.4e} max {:.4e}) phi error {err:.3e} steps {} cpu {cpu:.2} {}", (e[0] - e[e.len() - 1]) / e[0] / periods, e[0], e.iter().cloned().fold(f64::INFINITY, f64::min), e.iter().cloned().fold(0.0, f64::max), steps(&r), r.summary_json(None)["statistics"]);
        }
    }
    if what.contains("a01") {
        let m = load("iftomm_a01_pendulum.yaml");
        for &tol in &tols {
            let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, tol, t_end);
            let (ke, pe) = (col(&r, "kinetic_energy"), col(&r, "potential_energy"));
            let e: Vec<f64> = (0..r.len()).map(|k| ke[k] + pe[k]).collect();
            let per = ((A01_PERIOD / (r.time[1] - r.time[0])).round() as usize).clamp(1, r.len() / 2);
            eprintln!(
                "A01 secular energy loss per period {:.3e} relative (of 9.81 J), oscillation {:.3e}",
                a01_energy_loss_per_period(&r),
                e[..per].iter().map(|x| (x - e[0]).abs()).fold(0.0, f64::max)
            );
            eprintln!("A01 residuals {}", r.summary_json(None)["residuals"]);
            eprintln!(
                "A01 hht tol {tol:e}: error {:.3e} drift {:.3e} steps {} cpu {cpu:.2} s stats {}",
                a01_error(&r),
                energy_drift(&r),
                steps(&r),
                r.summary_json(None)["statistics"]
            );
        }
    }
    for name in ["iftomm_a02_nfourbar.yaml", "andrews.yaml"] {
        if !what.contains(&name[..4]) {
            continue;
        }
        let m = load(name);
        for &tol in &tols {
            let o = at_tolerance(IntegratorKind::Hht, tol, t_end);
            let clock = std::time::Instant::now();
            match m.run("dynamics", &o.clone().into()) {
                Ok(r) => eprintln!(
                    "{name} hht {tol:e}: ok in {:.2} s, {}",
                    clock.elapsed().as_secs_f64(),
                    r.summary_json(None)["statistics"]
                ),
                Err(f) => {
                    eprintln!("{name} hht {tol:e}: stopped in {:.2} s: {}", clock.elapsed().as_secs_f64(), f.error)
                }
            }
        }
    }
    if what.contains("qr") {
        let m = load("quick_return_a.yaml");
        let qr = QuickReturn::new(&m, QUICK_RETURN_CRANK_SPEED, SAMPLES);
        for &tol in &tols {
            let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, tol, None);
            eprintln!(
                "QR hht tol {tol:e}: error {:.3e} steps {} cpu {cpu:.2} s stats {}",
                qr.error(&r),
                steps(&r),
                r.summary_json(None)["statistics"]
            );
        }
    }
}
