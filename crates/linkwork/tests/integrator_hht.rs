//! The `hht` integrator (HHT-alpha) under error control: its global error follows the
//! tolerance at the rate of a second-order method with a local error test (`tol^(2/3)`), against
//! independent references (`common::references`). Its order at constant steps and its energy
//! loss against the method's numerical damping are measured in `src/analysis/dynamic/order_tests.rs`.

mod common;

use common::references::{nfourbar_error, pendulum_error as a01_error, QuickReturn, QUICK_RETURN_CRANK_SPEED, SAMPLES};
use common::{at_tolerance, col, energy_drift};
use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Model, Results};

/// A bar pinned off its centre on a torsion spring: `phi = 0.5 cos 2t` exactly (as order_tests.rs).
const BAR: &str = include_str!("models/pinned_bar.yaml");
/// How long `diag` runs the bar without `TEND`, s: 20 periods.
const BAR_END: f64 = 62.83185307179586;

fn load(name: &str) -> Model {
    Model::load(common::example(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn run_tol(model: &Model, analysis: &str, kind: IntegratorKind, tol: f64, t_end: Option<f64>) -> (Results, f64) {
    let o = at_tolerance(kind, tol, t_end);
    let clock = std::time::Instant::now();
    let r = model
        .run(analysis, &o.clone().into())
        .unwrap_or_else(|f| panic!("{} {analysis} {tol}: {}", model.name, f.error));
    (r, clock.elapsed().as_secs_f64())
}

fn steps(r: &Results) -> u64 {
    r.summary_json(None)["statistics"]["steps"].as_u64().unwrap()
}

/// The coasting quick-return A (analysis `dynamics`, 2 s) at 1e-6, 1e-8, 1e-10 against the
/// quadrature reference. Measured: 1.79e-3, 8.22e-5, 3.71e-6 in 886, 4115, 19101 steps: 22 times
/// smaller per 100 times tighter tolerance, the `tol^(2/3)` of a second-order method whose step
/// follows a local error `~h^3`. Before the fix of Newton's convergence test: 1.37e-2, 3.33e-3,
/// 6.37e-4 (4.1 and 5.2 times: first order). Bounds: the issue's "within 1e-4 at 1e-8, and at
/// least 10 times larger at 1e-6", and the same factor 10 from 1e-8 to 1e-10 (half the
/// expected 21, twice the first-order 4.6).
#[test]
fn quick_return_error_follows_the_tolerance() {
    let m = load("quick_return_a.yaml");
    let qr = QuickReturn::new(&m, QUICK_RETURN_CRANK_SPEED, SAMPLES);
    let e: Vec<f64> = [1e-6, 1e-8, 1e-10]
        .iter()
        .map(|&tol| {
            let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, tol, None);
            let e = qr.error(&r);
            eprintln!("quick-return hht {tol:e}: error {e:.3e}, {} steps, {cpu:.2} s", steps(&r));
            e
        })
        .collect();
    assert!(e[1] < 1e-4, "{e:?}");
    assert!(e[0] > 10.0 * e[1] && e[1] > 10.0 * e[2], "{e:?}");
}

/// A01's period, s: `4 sqrt(L / g) K(sin 45 deg)`.
const A01_PERIOD: f64 = 2.3678419;

/// The secular energy change of A01 per period, relative to `m g L = 9.81 J` (positive: a loss):
/// the mean energy over the first period minus that over the last, per period between them
/// (the means remove the energy's oscillation within a swing, `1.6e-4` at 1e-8).
fn a01_energy_loss_per_period(r: &Results) -> f64 {
    let (ke, pe) = (col(r, "kinetic_energy"), col(r, "potential_energy"));
    let e: Vec<f64> = (0..r.len()).map(|k| ke[k] + pe[k]).collect();
    let per = ((A01_PERIOD / (r.time[1] - r.time[0])).round() as usize).clamp(1, r.len() / 2);
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let periods = (r.time[r.len() - 1] - A01_PERIOD) / A01_PERIOD;
    (mean(&e[..per]) - mean(&e[e.len() - per..])) / 9.81 / periods
}

/// IFToMM A01 over the benchmark's 2000 s (845 swings) at 1e-8 against the exact solution.
/// Measured: 9.3e-3 m in 1.89 M steps (4 s). Before the step-size controller was centred on the
/// step it sizes: 8.5e-2 m in the same 1.89 M steps (its energy loss twice the method's own, see
/// the next test), and 2.0 m before the fix of Newton's convergence test. Bound: the issue's
/// 5e-2, which the lagging controller missed by 1.7 times.
#[test]
fn pendulum_a01_keeps_its_phase_over_2000_s() {
    let m = load("iftomm_a01_pendulum.yaml");
    let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, 1e-8, None);
    let e = a01_error(&r);
    eprintln!("A01 hht 1e-8: error {e:.3e}, {} steps, {cpu:.2} s", steps(&r));
    assert!(e < 5e-2, "{e}");
    assert!(steps(&r) < 2_500_000, "{}", steps(&r));
}

/// The step-size control costs A01 no energy beyond the method's damping: over 100 s at 1e-8
/// (94,000 steps) the secular energy loss per period is 4.2e-8 of `m g L`, less than the 6.9e-8
/// that a constant step of 1e-3 s (100,000 steps, about as many) loses. Before the controller
/// was centred on the step it sizes it was 1.38e-7 in the same number of steps: the classical
/// controller sizes each step from the previous step's error, so the step lags the motion by
/// about 1.3 steps and is not symmetric in time over a swing, which leaves the method's `O(h^2)`
/// energy oscillation (1.6e-4 within a swing) a secular part (docs/integrators.md). Bound: the
/// constant step's loss.
#[test]
fn pendulum_a01_step_control_costs_no_energy() {
    let m = load("iftomm_a01_pendulum.yaml");
    let (r, cpu) = run_tol(&m, "dynamics", IntegratorKind::Hht, 1e-8, Some(100.0));
    let loss = a01_energy_loss_per_period(&r);
    eprintln!("A01 hht 1e-8, 100 s: energy loss per period {loss:.3e}, {} steps, {cpu:.2} s", steps(&r));
    assert!(loss < 6.9e-8, "{loss:e}");
    assert!(steps(&r) < 100_000, "{}", steps(&r));
}

/// The N-four-bar A02 through its first flat position (0.72 s), where `Phi_q` nearly loses rank
/// and Newton's iterate carries round-off amplified into position noise of `1e-11` m, at
/// `rtol = atol = 1e-12` and `1e-13`. The error estimate is then that noise whatever the step;
/// before it was recognised as noise (`NOISE_MARGIN`, `STOP_MARGIN` in hht.rs) the step fell to
/// `6e-14` s and the run stopped at 0.72 s. Asserted: both run to 1 s, and B0 stays within `1e-6` m of the
/// one-degree-of-freedom reference (measured 1.1e-7 and 7.2e-8 m: past the flat position the
/// error is set by its noise, not by the tolerance; the bound is about ten times the larger).
#[test]
fn a02_passes_the_flat_position_at_1e_12_and_1e_13() {
    let model = load("iftomm_a02_nfourbar.yaml");
    for tol in [1e-12, 1e-13] {
        let (r, _) = run_tol(&model, "dynamics", IntegratorKind::Hht, tol, Some(1.0));
        let err = nfourbar_error(&r, 40);
        eprintln!("A02 to 1 s at {tol:e}: error {err:.2e}, {}", r.summary_json(None)["statistics"]);
        assert!(err < 1e-6, "{tol:e}: {err:.3e}");
    }
}

/// The measurements of docs/integrators.md (`DIAG=a01,qr,andr,iftomm_a02 TOLS=1e-6,1e-8
/// [TEND=..] cargo test --release --test integrator_hht -- --ignored --nocapture`).
#[test]
#[ignore]
fn diag() {
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
