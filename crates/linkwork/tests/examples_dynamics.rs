//! The dynamic examples against independent references: conservation laws, closed forms, a
//! published reference solution, and a second model of the same mechanism. Every example's
//! `dynamics` analysis runs from its file with each integrator of [`INTEGRATORS`]; long runs are
//! shortened with [`Overrides`].

mod common;

use common::references::{elliptic_k, nfourbar_error, nfourbar_reference, ANDREWS, ANDREWS_END, ANDREWS_START};
use common::{at_tolerance, col, energy_drift};

use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Error, Model, Overrides, Results};

/// The integrators every example runs with: all of them.
const INTEGRATORS: &[&str] = IntegratorKind::NAMES;

fn kind(name: &str) -> IntegratorKind {
    IntegratorKind::from_name(name).unwrap_or_else(|| panic!("unknown integrator {name}"))
}

fn load(name: &str) -> Model {
    Model::load(common::example(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Overrides that select `integrator` and change nothing else.
fn with(integrator: &str) -> Overrides {
    Overrides { integrator: Some(kind(integrator)), ..Default::default() }
}

/// Overrides that select `integrator` with `rtol = atol = tol`.
fn tight(integrator: &str, tol: f64) -> Overrides {
    at_tolerance(kind(integrator), tol, None)
}

/// Run `analysis` of `model`; panics with the engine's message on failure.
fn run(model: &Model, analysis: &str, overrides: &Overrides) -> Results {
    let r = model
        .run(analysis, &overrides.clone().into())
        .unwrap_or_else(|f| panic!("{} {analysis}: {}", model.name, f.error));
    eprintln!(
        "{} {analysis} {:?}: {} outputs, statistics {}",
        model.name,
        overrides.integrator,
        r.len(),
        r.summary_json(None)["statistics"]
    );
    r
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |a, x| a.max(x.abs()))
}

// ---------------------------------------------------------------------------------------------
// Quick-return mechanism

/// Unloaded, undriven and without gravity, the quick-return mechanism coasts: its kinetic energy
/// stays at its initial value (the crank's 6.283 rad/s, held by assembly), nothing does work.
/// Run at rtol = atol = 1e-8. Tolerance `1e-3` relative: HHT's energy error, which converges
/// slowly with the tolerance on this model (model A: 1.7e-3 at 1e-6, 3.8e-4 at 1e-8, 7.3e-5 at
/// 1e-10; model B: 4.9e-4 at 1e-8), with a factor 2 of margin.
#[test]
#[allow(clippy::approx_constant)] // 6.283 rad/s is the file's given crank speed, not 2 pi
fn quick_return_coasts_with_constant_kinetic_energy() {
    for file in ["quick_return_a.yaml", "quick_return_b.yaml"] {
        let model = load(file);
        for &integrator in INTEGRATORS {
            let r = run(&model, "dynamics", &tight(integrator, 1e-8));
            assert_eq!(r.time.last().copied(), Some(2.0));
            assert!((col(&r, "crank.omega")[0] - 6.283).abs() < 1e-12, "the crank's initial speed is given");
            let t = col(&r, "kinetic_energy");
            assert!(t[0] > 1e4, "{file}: kinetic energy {}", t[0]);
            assert_eq!(max_abs(col(&r, "potential_energy").iter().copied()), 0.0, "no gravity, no spring");
            assert_eq!(max_abs(col(&r, "nonconservative_work").iter().copied()), 0.0, "forces: [] applies none");
            let drift = energy_drift(&r) / t[0];
            eprintln!("{file} {integrator}: relative kinetic energy drift {drift:.2e}");
            assert!(drift < 1e-3, "{file} {integrator}: drift {drift}");
        }
    }
}

/// Under the constant crank torque the work done equals the gain of kinetic energy,
/// `T - W = T(0)`; the torque's work is also `165521 (phi - phi0)` exactly, which checks the
/// work integral and that the zero force on slider D (model A) does nothing. At rtol = atol =
/// 1e-8; tolerances: `5e-3` of the largest kinetic energy, HHT's energy error (model A: 1.9e-3
/// at 1e-8, 6e-4 at 1e-10, as the crank speeds up to ~100 rad/s) with a factor 2.5 of margin;
/// the work against the crank angle `1e-4` relative: the work integral is the trapezoidal rule
/// between accepted steps, second order whatever the integrator's order, so its error follows
/// the step length (measured on model A: hht 4.8e-9, bdf 1.3e-6, abam 1.7e-5 with the longest
/// steps).
#[test]
fn quick_return_loaded_gains_the_torque_work() {
    for file in ["quick_return_a.yaml", "quick_return_b.yaml"] {
        let model = load(file);
        for &integrator in INTEGRATORS {
            let r = run(&model, "dynamics_loaded", &tight(integrator, 1e-8));
            let (t, w, phi) = (col(&r, "kinetic_energy"), col(&r, "nonconservative_work"), col(&r, "crank.phi"));
            let t_max = max_abs(t.iter().copied());
            let drift = energy_drift(&r) / t_max;
            let work_err =
                max_abs((0..r.len()).map(|k| w[k] - 165521.0 * (phi[k] - phi[0]))) / max_abs(w.iter().copied());
            eprintln!("{file} {integrator}: energy balance {drift:.2e}, work against angle {work_err:.2e}");
            assert!(t[r.len() - 1] > 2.0 * t[0], "{file}: the torque speeds the crank up");
            assert!(drift < 5e-3, "{file} {integrator}: energy balance {drift}");
            assert!(work_err < 1e-4, "{file} {integrator}: work {work_err}");
        }
    }
}

/// Model B's equations (revolutes O, A, C; the crank's B on the rocker's line; the link's D on
/// y = 2) evaluated on model A's motion, free and loaded: the models differ in mass (A's sliders)
/// so their motions differ, but A's crank, rocker and link move as B's joints allow. B's equations
/// are consequences of A's, with lever arms up to 4 m: tolerance `10 x` the largest residual of
/// A's own equations (the integrator's Newton tolerance), and at most `1e-6` m.
#[test]
fn quick_return_a_moves_as_model_b_allows() {
    let model = load("quick_return_a.yaml");
    for analysis in ["dynamics", "dynamics_loaded"] {
        for &integrator in INTEGRATORS {
            let r = run(&model, analysis, &with(integrator));
            let mut worst = 0.0f64;
            for k in 0..r.len() {
                let body = |b: &str| ["x", "y", "phi"].map(|c| col(&r, &format!("{b}.{c}"))[k]);
                let point = |q: [f64; 3], s: [f64; 2]| {
                    let (sn, cs) = q[2].sin_cos();
                    [q[0] + cs * s[0] - sn * s[1], q[1] + sn * s[0] + cs * s[1]]
                };
                let (crank, rocker, link) = (body("crank"), body("rocker"), body("link"));
                let o = point(crank, [0.75, 0.0]);
                let a = point(rocker, [2.0, 0.0]);
                let (c_rocker, c_link) = (point(rocker, [-2.0, 0.0]), point(link, [0.95, 0.0]));
                let b = point(crank, [-0.75, 0.0]);
                let d = point(link, [-0.95, 0.0]);
                let normal = [-rocker[2].sin(), rocker[2].cos()];
                let residuals = [
                    o[0],
                    o[1],
                    a[0],
                    a[1] + 2.0,
                    c_rocker[0] - c_link[0],
                    c_rocker[1] - c_link[1],
                    (b[0] - a[0]) * normal[0] + (b[1] - a[1]) * normal[1],
                    d[1] - 2.0,
                ];
                worst = worst.max(max_abs(residuals));
            }
            let own = r.summary_json(None)["residuals"]["max_position"].as_f64().expect("residuals");
            eprintln!(
                "quick-return A {analysis} {integrator}: model B's equations to {worst:.2e}, A's own to {own:.2e}"
            );
            assert!(worst <= 10.0 * own && worst < 1e-6, "{analysis} {integrator}: {worst} (A's own {own})");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Andrews' squeezing mechanism

/// At t = 0 the measures are the test set's initial values: the file's positions are that state
/// and assembly keeps them. Tolerance `1e-14` rad: the positions are written to ~17 digits.
/// At t = 0.03 they match the reference solution to `1e-4` rad (`6e-6` relative on the crank
/// angle, ~16 rad), run at rtol = atol = 1e-11: HHT's global error, mostly a phase error of the
/// crank's 2.5 turns, measured 2.8e-4, 1.4e-4 and 6.7e-5 rad on beta at 1e-9, 1e-10 and 1e-11
/// (at the file's 1e-8, 7.6e-4 rad); the other angles are closer.
#[test]
fn andrews_matches_the_test_set() {
    let model = load("andrews.yaml");
    for &integrator in INTEGRATORS {
        let r = run(&model, "dynamics", &tight(integrator, 1e-11));
        let n = r.len() - 1;
        assert!((r.time[n] - 0.03).abs() < 1e-15);
        let mut worst_start = 0.0f64;
        let mut worst_end = 0.0f64;
        for (k, name) in ANDREWS.iter().enumerate() {
            let c = col(&r, name);
            worst_start = worst_start.max((c[0] - ANDREWS_START[k]).abs());
            let err = (c[n] - ANDREWS_END[k]).abs();
            eprintln!("{name}: {:.12} reference {:.12} difference {err:.2e}", c[n], ANDREWS_END[k]);
            worst_end = worst_end.max(err);
        }
        eprintln!("andrews {integrator}: start {worst_start:.2e}, end {worst_end:.2e}");
        assert!(worst_start < 1e-14, "{integrator}: start {worst_start}");
        assert!(worst_end < 1e-4, "{integrator}: end {worst_end}");
    }
}

// ---------------------------------------------------------------------------------------------
// IFToMM A01: simple pendulum

/// Times where `x` changes sign, located by the cubic Hermite interpolant of `x` and its rate `v`
/// between output times (bisection): an interpolation error `~h^4 x''''/384`, 1e-10 s at
/// h = 0.01 s.
fn zero_crossings(t: &[f64], x: &[f64], v: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 0..t.len() - 1 {
        if x[k] == 0.0 || x[k].signum() == x[k + 1].signum() {
            continue;
        }
        let h = t[k + 1] - t[k];
        let at = |s: f64| {
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * x[k]
                + (s3 - 2.0 * s2 + s) * h * v[k]
                + (-2.0 * s3 + 3.0 * s2) * x[k + 1]
                + (s3 - s2) * h * v[k + 1]
        };
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if at(mid).signum() == x[k].signum() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        out.push(t[k] + 0.5 * (lo + hi) * h);
    }
    out
}

/// The pendulum released at 90 degrees: P1_x crosses zero at `(2j + 1) T / 4` with the exact
/// large-amplitude period `T = 4 sqrt(L/g) K(sin 45 deg)`, over 20 s (8 periods) of the
/// benchmark's 2000 s, with rtol = atol = 1e-11. Tolerance `2e-6` relative on each crossing
/// time: HHT's phase error at that tolerance, measured 9.2e-7 at the last of the 17 crossings
/// (4e-6 at 1e-9), with a factor 2 of margin; the crossings themselves are located to 1e-10 s.
/// Energy: `2e-4` J of 9.81 J, twice HHT's numerical dissipation (alpha = -0.3) measured at that
/// tolerance (8.5e-5 J). The link stays 1 m long to `1e-9` m (Newton on the index-3 equations).
#[test]
fn pendulum_a01_period_and_energy() {
    let model = load("iftomm_a01_pendulum.yaml");
    let (g, l) = (9.81f64, 1.0f64);
    let period = 4.0 * (l / g).sqrt() * elliptic_k(std::f64::consts::FRAC_PI_4.sin());
    assert!((period - 2.367841947576).abs() < 1e-11, "T = {period}");
    for &integrator in INTEGRATORS {
        let o = Overrides { t_end: Some(20.0), ..tight(integrator, 1e-11) };
        let r = run(&model, "dynamics", &o);
        let (x, y) = (col(&r, "P1_x"), col(&r, "P1_y"));
        assert_eq!((x[0], y[0]), (-1.0, 0.0));
        let length = max_abs((0..r.len()).map(|k| x[k].hypot(y[k]) - l));
        let crossings = zero_crossings(&r.time, x, col(&r, "P1.vx"));
        assert_eq!(crossings.len(), 17, "{crossings:?}");
        let phase = max_abs(crossings.iter().enumerate().map(|(j, &tc)| {
            let want = (2 * j + 1) as f64 * period / 4.0;
            (tc - want) / want
        }));
        let drift = energy_drift(&r);
        eprintln!("pendulum {integrator}: crossing times to {phase:.2e} relative, energy {drift:.2e} J, length {length:.2e} m");
        assert!(phase < 2e-6, "{integrator}: {phase}");
        assert!(drift < 2e-4, "{integrator}: energy {drift}");
        assert!(length < 1e-9, "{integrator}: length {length}");
    }
}

// ---------------------------------------------------------------------------------------------
// IFToMM A02: N-four-bar

/// The N = 40 file over its first 2.5 s at rtol = atol = 1e-8: the chain falls through the flat
/// position (B0_y = 0) at about 0.72 s, hangs at about 1 s and rises through the flat position on
/// the other side at about 1.25 s. Either the run passes the flat positions, and then B0 follows
/// the one-degree-of-freedom reference, every rocker stays parallel to the first and the energy
/// is kept; or it stops with a typed error (`Singular` or `Integration`) that names the time and
/// the rows and keeps the results up to there, which must then be right. Tolerances (measured
/// with hht: 3.3e-4 m, 6e-10 rad, 4.2e-5): B0 to `1e-3` m, HHT's phase error over the swing;
/// rockers parallel to `1e-8` rad, what Newton leaves of the constraints; energy to `2e-4` of
/// the largest kinetic energy, HHT's energy error at this tolerance.
#[test]
fn nfourbar_a02_moves_as_one_degree_of_freedom() {
    let model = load("iftomm_a02_nfourbar.yaml");
    let n = 40;
    for &integrator in INTEGRATORS {
        let o = Overrides { t_end: Some(2.5), ..tight(integrator, 1e-8) };
        let (r, error) = match model.run("dynamics", &o.clone().into()) {
            Ok(r) => (r, None),
            Err(f) => (f.results, Some(f.error)),
        };
        eprintln!("nfourbar {integrator}: {} outputs, error {error:?}", r.len());
        eprintln!(
            "summary: redundant rows {}, dof {}",
            r.summary_json(None)["redundant_rows"],
            r.summary_json(None)["dof"]
        );
        if let Some(e) = &error {
            match e {
                Error::Singular { time, rows, .. } | Error::Integration { time, rows, .. } => {
                    assert!(*time > 0.0 && !rows.is_empty(), "{e}");
                    assert!(r.time.last().is_some_and(|&t| t <= *time + 1e-12), "results kept up to {time}");
                }
                other => panic!("{integrator}: unexpected error {other}"),
            }
        }
        assert!(r.len() > 10, "results kept");
        let reference = nfourbar_reference(n, &r.time);
        let (bx, by) = (col(&r, "B0_x"), col(&r, "B0_y"));
        let mut worst = 0.0f64;
        let mut parallel = 0.0f64;
        for k in 0..r.len() {
            let psi = reference[k][0];
            worst = worst.max((bx[k] - psi.cos()).abs()).max((by[k] - psi.sin()).abs());
            let phi0 = col(&r, "r0.phi")[k];
            for j in 1..=n {
                parallel = parallel.max((col(&r, &format!("r{j}.phi"))[k] - phi0).abs());
            }
        }
        let t0 = col(&r, "kinetic_energy")[0];
        assert!((t0 - ((n as f64 + 1.0) / 6.0 + n as f64 / 2.0)).abs() < 1e-9, "initial kinetic energy {t0}");
        let drift = energy_drift(&r) / max_abs(col(&r, "kinetic_energy").iter().copied());
        let min_y = by.iter().copied().fold(f64::INFINITY, f64::min);
        eprintln!(
            "nfourbar {integrator}: to t = {}, lowest B0_y {min_y:.3}, B0 to {worst:.2e} m, rockers parallel to {parallel:.2e} rad, energy {drift:.2e}",
            r.time[r.len() - 1]
        );
        if error.is_none() {
            assert!(min_y < -0.99, "{integrator}: a completed run hangs below the pivots at ~1 s ({min_y})");
        }
        assert!(worst < 1e-3, "{integrator}: B0 {worst}");
        assert!(parallel < 1e-8, "{integrator}: rockers {parallel}");
        assert!(drift < 2e-4, "{integrator}: energy {drift}");
    }
}

// ---------------------------------------------------------------------------------------------
// Block on a sliding wedge

/// Constant accelerations: the wedge's `-m g sin cos / (M + m sin^2)` along x and the block's
/// `(M + m) g sin / (M + m sin^2)` down the incline relative to it. At every output time the
/// accelerations come from one linear solve at the state, so they match to `1e-9` relative
/// (rounding and the regularisation's remainder after refinement). Positions and velocities
/// are the quadratic and linear functions of time they imply, to `1e-5`: ten times the default
/// integrator tolerance, a global error. HHT and BDF2 integrate constant accelerations exactly,
/// but `bdf` starts at order 1, whose first steps' local errors (each within the tolerance) the
/// later, exact steps carry along (measured: 5.5e-6 with `bdf`).
#[test]
fn wedge_accelerations_are_the_closed_form() {
    let model = load("wedge.yaml");
    let (big_m, m, g, th) = (3.0f64, 1.0f64, 9.81f64, std::f64::consts::FRAC_PI_6);
    let den = big_m + m * th.sin().powi(2);
    let a_wedge = -m * g * th.sin() * th.cos() / den;
    let a_rel = (big_m + m) * g * th.sin() / den;
    for &integrator in INTEGRATORS {
        let r = run(&model, "dynamics", &with(integrator));
        let (wx, wax, wvx) = (col(&r, "wedge.x"), col(&r, "wedge.ax"), col(&r, "wedge.vx"));
        let (s, ar) = (col(&r, "s_rel"), col(&r, "a_rel"));
        let (wy, wphi, bphi) = (col(&r, "wedge.y"), col(&r, "wedge.phi"), col(&r, "block.phi"));
        let mut acc = 0.0f64;
        let mut pos = 0.0f64;
        for k in 0..r.len() {
            let t = r.time[k];
            acc = acc.max(((wax[k] - a_wedge) / a_wedge).abs()).max(((ar[k] - a_rel) / a_rel).abs());
            pos = pos
                .max((wx[k] - (wx[0] + 0.5 * a_wedge * t * t)).abs())
                .max((wvx[k] - a_wedge * t).abs())
                .max((s[k] - (s[0] + 0.5 * a_rel * t * t)).abs());
            assert!((wy[k] - wy[0]).abs() < 1e-12 && wphi[k].abs() < 1e-12, "the wedge stays on the floor");
            assert!((bphi[k] + th).abs() < 1e-12, "the block keeps its angle");
        }
        eprintln!("wedge {integrator}: accelerations to {acc:.2e} relative, positions and speeds to {pos:.2e}");
        assert!(acc < 1e-9, "{integrator}: accelerations {acc}");
        assert!(pos < 1e-5, "{integrator}: positions {pos}");
        // Horizontal momentum stays zero.
        let momentum = max_abs((0..r.len()).map(|k| big_m * wvx[k] + m * col(&r, "block.vx")[k]));
        assert!(momentum < 1e-9, "momentum {momentum}");
    }
}

/// `abam` on the N = 40 file over its 20 s, through six flat positions, against the
/// one-degree-of-freedom reference, at `1e-11`, `1e-12` and `1e-13`.
///
/// - At `1e-11` Newton for the dependent coordinates must stop below 1000 units of round-off:
///   near a flat position that leaves them `|B^-1|` times off, and the error test would measure
///   that noise and fail even with the smallest step.
/// - At `1e-12` and `1e-13`, within about `1e-3` s of a flat position the accelerations are
///   round-off noise whatever Newton does (the constraints fix the dependent positions only to
///   `|B^-1|` times the round-off of `Phi`), which no step resolves: `bdf` takes the state
///   across and `abam` resumes, with a warning. The step budget of 50,000 (the runs take 1,616,
///   4,367 and 8,339 steps) makes a creep at tiny steps a failure here: without the crossing the
///   run stops at the budget at `t = 2.687 s` at `1e-12`.
///
/// Measured: B0 within `9.6e-8`, `2.3e-6` and `5.8e-7` m (2, 9 and 20 crossings; which passage
/// leaves which noise changes with the last bits of the error estimates). Bounds: `2e-6` m at `1e-11`, and `2e-5` at `1e-12` and
/// `1e-13` (`bdf`'s own bound on A02 at `1e-12`): the floor of a run through singular positions,
/// where each passage fixes the positions only to the noise the near-singular Jacobian allows
/// (docs/integrators.md, `abam`; `bdf` alone ends `5.5e-6` off at `1e-12`).
#[test]
fn nfourbar_a02_abam_crosses_the_flat_positions_at_1e_11_to_1e_13() {
    let mut model = load("iftomm_a02_nfourbar.yaml");
    model.analyses["dynamics"].integrator.max_steps = 50_000;
    for (tol, bound) in [(1e-11, 2e-6), (1e-12, 2e-5), (1e-13, 2e-5)] {
        let r = model.run("dynamics", &tight("abam", tol).into()).unwrap_or_else(|f| panic!("{tol:e}: {}", f.error));
        assert!((r.time[r.len() - 1] - 20.0).abs() < 1e-9, "{tol:e}: ran to {}", r.time[r.len() - 1]);
        // Every output time once, in order, across the hand-overs to bdf and back.
        assert_eq!(r.len(), 2001, "{tol:e}: output rows");
        assert!(r.time.windows(2).all(|w| w[1] > w[0]), "{tol:e}: output times out of order");
        let error = nfourbar_error(&r, 40);
        assert!(error < bound, "{tol:e}: B0 {error:e}");
        if tol < 1e-11 {
            let crossings = r.summary_json(None)["statistics"]["crossings"].as_u64().unwrap_or(0);
            assert!(crossings > 0, "{tol:e}: no crossing");
            let warnings = r.summary_json(None)["warnings"].as_array().cloned().unwrap_or_default();
            let warned = warnings.iter().any(|w| w.as_str().is_some_and(|w| w.contains("bdf took the state across")));
            assert!(warned, "{tol:e}: {warnings:?}");
        }
    }
    // The budget counts abam's steps and bdf's together (the first crossing comes before step
    // 400 at 1e-12): it named the remainder bdf was given, "more than 141 steps".
    model.analyses["dynamics"].integrator.max_steps = 400;
    let f = model.run("dynamics", &tight("abam", 1e-12).into()).expect_err("a budget of 400 steps");
    assert!(f.error.to_string().contains("more than 400 steps"), "{}", f.error);
    assert!(
        f.results.summary_json(None)["statistics"]["crossings"].as_u64().unwrap_or(0) > 0,
        "no crossing before the budget"
    );
}
