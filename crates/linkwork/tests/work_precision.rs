//! Work-precision tests: the global error of an integrator against independent references
//! (accuracy, not timing), and the references' own checks. The references
//! (`common/references.rs`) use no integrator of the engine.
//! The long runs of the same comparison (A01 over 2000 s, A02 over 20 s, tolerances to 1e-13) are
//! in the work-precision table of docs/integrators.md, made by
//! `cargo run --release -p linkwork --example work_precision`.

mod common;

use common::references::{
    andrews_digits, pendulum_a01, pendulum_error, QuickReturn, ANDREWS_END, ANDREWS_END_CONVERGED,
    QUICK_RETURN_CRANK_SPEED, SAMPLES,
};
use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Model, Overrides, Results};

fn load(name: &str) -> Model {
    Model::load(common::example(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Run `analysis` with `integrator` at `rtol = atol = tol` (and `t_end` if given).
fn run(model: &Model, analysis: &str, integrator: IntegratorKind, tol: f64, t_end: Option<f64>) -> Results {
    let o = Overrides { integrator: Some(integrator), rtol: Some(tol), atol: Some(tol), t_end, ..Default::default() };
    model
        .run(analysis, &o.clone().into())
        .unwrap_or_else(|f| panic!("{} {integrator:?} {tol:e}: {}", model.name, f.error))
}

/// The references are what they claim. The quick-return's quadrature from 256 and from 512
/// samples of the crank turn agree to `2e-11` (m, rad; measured 5.7e-12, and 3.9e-12 between 512
/// and 1024: the series has converged, and what is left is the kinematic samples' own Newton
/// tolerance, 1e-12, carried through 2 s of motion), and its crank starts at the given 6.283 rad/s
/// (central differences, `h = 1e-4` s: error `~1e-8`). The pendulum's solution satisfies
/// `theta'' = -g sin theta` to the `3e-5` of central differences at `h = 1e-3` s
/// (`h^2 theta'''' / 12`, `theta''''` up to `~100 s^-4`), and keeps its energy to `1e-6` J/kg: the
/// speed (up to 4.4 rad/s) by central differences at `h = 1e-4` s is good to `7e-8` (`h^2 theta''' / 6`; the
/// `1e-12` rounding of the angle near `t = 2000 s` divided by `h`).
#[test]
fn references_are_converged_and_exact() {
    let model = load("quick_return_a.yaml");
    let fine = QuickReturn::new(&model, QUICK_RETURN_CRANK_SPEED, SAMPLES);
    let coarse = QuickReturn::new(&model, QUICK_RETURN_CRANK_SPEED, SAMPLES / 2);
    let mut worst = 0.0f64;
    for k in 0..=40 {
        let t = 0.05 * k as f64;
        for name in fine.names() {
            worst = worst.max((fine.position(name, t) - coarse.position(name, t)).abs());
        }
    }
    eprintln!("quick-return reference: 256 against {SAMPLES} samples {worst:.2e}");
    assert!(worst < 2e-11, "{worst}");
    let h = 1e-4;
    let speed = (fine.crank_angle(h) - fine.crank_angle(-h)) / (2.0 * h);
    assert!((speed - QUICK_RETURN_CRANK_SPEED).abs() < 1e-7, "initial crank speed {speed}");

    let theta = |t: f64| {
        let p = pendulum_a01(t);
        (-p[0]).atan2(-p[1])
    };
    let (h, g) = (1e-3, 9.81);
    let (mut ode, mut energy) = (0.0f64, 0.0f64);
    for i in 0..2000 {
        let t = 0.37 + 0.997 * i as f64;
        let acc = (theta(t + h) - 2.0 * theta(t) + theta(t - h)) / (h * h);
        ode = ode.max((acc + g * theta(t).sin()).abs());
        let w = (theta(t + 1e-4) - theta(t - 1e-4)) / 2e-4;
        energy = energy.max((0.5 * w * w - g * theta(t).cos()).abs());
    }
    eprintln!("pendulum reference: ODE residual {ode:.2e}, energy {energy:.2e}");
    assert!(ode < 3e-5, "{ode}");
    assert!(energy < 1e-6, "{energy}");
}

/// `hht` is second order under error control: its local error estimate is `O(h^3)`, so the step
/// goes as `tol^(1/3)` and the global error as `h^2 ~ tol^(2/3)`, 21.5 times smaller per 100 times
/// tighter tolerance. Asserted: at least 10 times smaller from `1e-6` to `1e-8` (an order
/// reduction to first order gives 4.6), on the quick-return and on the pendulum's first 20 s;
/// and at `1e-8` within `1e-4` on the quick-return (measured 8.2e-5) and
/// `1e-3` on the pendulum (measured 3.4e-4 after 8 swings: HHT's period error accumulates).
#[test]
fn hht_is_second_order_under_error_control() {
    let qr = load("quick_return_a.yaml");
    let reference = QuickReturn::new(&qr, QUICK_RETURN_CRANK_SPEED, SAMPLES);
    let pendulum = load("iftomm_a01_pendulum.yaml");
    let errors = |f: &dyn Fn(f64) -> f64| [1e-6, 1e-8].map(f);
    let cases: [(&str, [f64; 2], f64); 2] = [
        ("quick-return", errors(&|tol| reference.error(&run(&qr, "dynamics", IntegratorKind::Hht, tol, None))), 1e-4),
        (
            "pendulum",
            errors(&|tol| pendulum_error(&run(&pendulum, "dynamics", IntegratorKind::Hht, tol, Some(20.0)))),
            1e-3,
        ),
    ];
    for (name, [coarse, fine], bound) in cases {
        eprintln!("hht {name}: error {coarse:.2e} at 1e-6, {fine:.2e} at 1e-8 (ratio {:.1})", coarse / fine);
        assert!(coarse >= 10.0 * fine, "{name}: {coarse:.3e} at 1e-6, {fine:.3e} at 1e-8");
        assert!(fine <= bound, "{name}: {fine:.3e} at 1e-8");
    }
}

/// `bdf` (SI2, the default) and `abam` on the coasting quick-return (2 s, the crank turning
/// twice): the largest position error over the run is at most `K = 1000` times the tolerance at
/// `1e-6`, `1e-8` and `1e-10` (measured: `bdf` 11, 580 and 163 times; `abam` 330, 270 and 160
/// times, through about ten re-partitions). The tolerance bounds each step's local error
/// relative to the coordinates (up to 14 rad for the crank's angle); the run takes 500 to 2000
/// steps, whose local errors add up and shift the crank's phase, and the slider's x moves up to 12
/// times the crank angle on the return stroke.
#[test]
fn error_follows_the_tolerance_on_the_quick_return() {
    let model = load("quick_return_a.yaml");
    let reference = QuickReturn::new(&model, QUICK_RETURN_CRANK_SPEED, SAMPLES);
    for kind in [IntegratorKind::Bdf, IntegratorKind::Abam] {
        for tol in [1e-6, 1e-8, 1e-10] {
            let r = run(&model, "dynamics", kind, tol, None);
            let err = reference.error(&r);
            eprintln!(
                "quick-return {kind:?} {tol:e}: error {err:.2e} ({:.0} x tol), {}",
                err / tol,
                r.summary_json(None)["statistics"]
            );
            assert!(err <= 1000.0 * tol, "{kind:?} at {tol:e}: {err:.3e}");
            assert_eq!(
                r.summary_json(None)["statistics"]["crossings"],
                0,
                "{kind:?} at {tol:e}: no singular position to cross"
            );
        }
    }
}

/// IFToMM A01 over its 2000 s (about 870 periods) at `rtol = atol = 1e-10`: `bdf` (order 6, SI2)
/// and `abam` end within `1e-3` m of the exact elliptic solution, the benchmark's requirement
/// (measured: `bdf` 1.2e-4, `abam` 3.4e-6). The phase error of a conservative oscillation adds up
/// over the periods; `bdf` at order 5 ended 6.5e-3 off (its damping shifts the period).
#[test]
fn a01_over_2000_s_within_1e_3_at_1e_10() {
    let model = load("iftomm_a01_pendulum.yaml");
    for kind in [IntegratorKind::Bdf, IntegratorKind::Abam] {
        let r = run(&model, "dynamics", kind, 1e-10, None);
        let err = pendulum_error(&r);
        eprintln!("A01 2000 s {kind:?} 1e-10: error {err:.2e}, {}", r.summary_json(None)["statistics"]);
        assert!(err < 1e-3, "{kind:?}: {err:.3e}");
        assert_eq!(r.summary_json(None)["statistics"]["crossings"], 0, "{kind:?}: no singular position to cross");
    }
}

/// Andrews' mechanism to t = 0.03 at `rtol = atol = 1e-12`: at least 9 significant digits for
/// `bdf` and 10 for `abam` (the test set's digits at this tolerance), counted as the test set counts them, against the
/// converged solution of the test set's own equations (`ANDREWS_END_CONVERGED`, good to about
/// 11.5 digits). The published values are only 9.57 digits from that solution (gamma), so against
/// them no converged run can show more than about 9.6: both runs are also asserted to be that
/// close to the published values, which checks the converged reference from the other side.
#[test]
fn andrews_digits_at_1e_12() {
    let model = load("andrews.yaml");
    for (kind, want) in [(IntegratorKind::Bdf, 9.0), (IntegratorKind::Abam, 10.0)] {
        let r = run(&model, "dynamics", kind, 1e-12, None);
        let digits = andrews_digits(&r, &ANDREWS_END_CONVERGED);
        let published = andrews_digits(&r, &ANDREWS_END);
        eprintln!("andrews {kind:?} 1e-12: {digits:.2} digits ({published:.2} against the published values)");
        assert!(digits >= want, "{kind:?}: {digits:.2} digits");
        assert_eq!(r.summary_json(None)["statistics"]["crossings"], 0, "{kind:?}: no singular position to cross");
        assert!(published >= 9.3, "{kind:?}: {published:.2} digits against the published values");
    }
}
