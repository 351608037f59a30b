//! A run's status means what it says: tolerances that
//! cannot mean anything are refused, and a run that ended is checked against what it promised
//! (docs/integrators.md, "What a run promises"; docs/kinematics.md, "The residual at every
//! output").

mod common;

use common::{col, energy_drift, example, integrators, patch, patched_example};
use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Error, Model, Overrides, Results};

/// `rtol` or `atol` of `1e300` ran the double pendulum to a pin 1,168 m off its anchor with
/// status ok; `0.1` left it 4 cm off. Each is refused at the option that set it, and in a model
/// file at its field; `1e-2` is the loosest accepted.
#[test]
fn meaningless_tolerances_are_refused() {
    let model = Model::load(example("double_pendulum.yaml")).unwrap();
    let cases = [
        (Overrides { rtol: Some(1e300), ..Default::default() }, "--rtol"),
        (Overrides { atol: Some(1e300), ..Default::default() }, "--atol"),
        (Overrides { rtol: Some(0.1), atol: Some(1e-6), ..Default::default() }, "--rtol"),
    ];
    for (overrides, option) in cases {
        let failure = model.run("dynamics", &overrides.clone().into()).unwrap_err();
        let Error::Model(problems) = &failure.error else { panic!("{option}: {}", failure.error) };
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0].path, option);
        assert!(problems[0].message.starts_with("expected at most 1e-2, found"), "{}", problems[0].message);
    }
    let text = patched_example(
        "double_pendulum.yaml",
        &[("dynamics: {type: dynamic, t_end: 5,", "dynamics: {type: dynamic, solver: {atol: 0.05}, t_end: 5,")],
    );
    let Err(Error::Model(problems)) = Model::from_yaml(&text) else { panic!("atol 0.05 was accepted") };
    assert!(problems.iter().any(|p| p.path == "analyses.dynamics.solver.atol"), "{problems:?}");
    let loosest = Overrides { rtol: Some(1e-2), atol: Some(1e-2), t_end: Some(1.0), ..Default::default() };
    model.run("dynamics", &loosest.clone().into()).unwrap_or_else(|f| panic!("{}", f.error));
}

/// The distance of the double pendulum's pin `O` from its anchor at the origin, largest over the
/// run, from the positions alone (the upper rod's end `(-0.5, 0)` in its frame).
fn pin_gap(r: &Results) -> f64 {
    let (x, y, phi) = (col(r, "upper.x"), col(r, "upper.y"), col(r, "upper.phi"));
    (0..r.len()).map(|k| (x[k] - 0.5 * phi[k].cos()).hypot(y[k] - 0.5 * phi[k].sin())).fold(0.0, f64::max)
}

/// At the loosest tolerances accepted, `1e-2`, the pin stays within the position check's bound,
/// `POSITION_FACTOR (atol + rtol L)` (`L` the largest coordinate, 2 m at most: 0.3 m), and is
/// measured from the positions, independently of the engine's residual column: 2.9 mm for
/// `bdf`, 1.4 mm for `hht`.
/// The bound is what `1e-2` asks of a 2 m mechanism, ten times over: the check does not judge
/// the tolerance, which the bound on `rtol` does.
#[test]
fn the_loosest_tolerances_keep_the_pin_within_what_they_ask() {
    let model = Model::load(example("double_pendulum.yaml")).unwrap();
    for (name, kind) in integrators() {
        let o = Overrides { integrator: Some(kind), rtol: Some(1e-2), atol: Some(1e-2), ..Default::default() };
        let r = match model.run("dynamics", &o.clone().into()) {
            Ok(r) => r,
            // The energy check may fail such a run; never the residual check.
            Err(f) => {
                let Error::Accuracy { quantity, .. } = &f.error else { panic!("{name}: {}", f.error) };
                assert_eq!(*quantity, "energy drift", "{name}: {}", f.error);
                f.results
            }
        };
        let gap = pin_gap(&r);
        let bound = linkwork::analysis::promise::POSITION_FACTOR * (1e-2 + 1e-2 * 2.0);
        eprintln!("{name}: pin {gap:.3e} m off its anchor (bound {bound:.3e})");
        assert!(gap < bound, "{name}: {gap}");
    }
}

/// A block held by a spring of 1e12 N/m, stretched by 1 mm (the file says more).
const STIFF_SPRING: &str = include_str!("models/stiff_spring.yaml");

/// A spring of 1e12 N/m between a body on a guide and ground, stretched 1 mm (500 kJ, a period of
/// 6.3 us): conservative, so its energy must stay. At the default tolerances `abam` keeps it to
/// `1.1e-4`; `hht`, whose `alpha` damps the motions its steps do not resolve, loses `43%`, and
/// `bdf` `99.7%` in 1 ms, both with status ok before. Now `hht`'s loss is a warning naming the
/// remedies, and `bdf`'s fails the run as an energy drift, with the results kept, the time and
/// the remedies. (`bdf`'s cause: SI2's Newton judged stalled at its second correction, where the
/// projection's change reaches the spring's force one iteration late; each stall hands the step
/// to index 3, whose step-weighted velocity test lets BDF's damping through: docs/integrators.md,
/// "What a run promises". `formulation: index3` loses the same.)
#[test]
fn a_stiff_spring_keeps_its_energy_or_says_so() {
    let model = Model::from_yaml(STIFF_SPRING).unwrap();
    // The energy of the stretch, k d^2 / 2.
    let energy = 0.5 * 1e12 * 1e-3f64.powi(2);
    for (name, kind) in integrators() {
        let o = Overrides { integrator: Some(kind), ..Default::default() };
        let (r, failure) = match model.run("free", &o.clone().into()) {
            Ok(r) => (r, None),
            Err(f) => (f.results, Some(f.error)),
        };
        let drift = energy_drift(&r) / energy;
        let warned = r.summary.warnings.iter().any(|w| w.contains("energy of this conservative system"));
        eprintln!("{name}: drift {drift:.3e}, warned {warned}, {failure:?}");
        match kind {
            IntegratorKind::Abam => assert!(drift < 1e-2 && !warned && failure.is_none(), "{name}: {drift}"),
            IntegratorKind::Hht => assert!(warned && drift > 1e-2 && failure.is_none(), "{name}: {drift}"),
            IntegratorKind::Bdf => {
                assert_eq!(r.len(), 11, "every output kept");
                let Some(e @ Error::Accuracy { quantity, value, time, .. }) = &failure else { panic!("{failure:?}") };
                assert_eq!(*quantity, "energy drift");
                assert!(*value > linkwork::analysis::promise::DRIFT_FAILURE && *time > 0.0, "{e}");
                let message = e.to_string();
                assert!(message.contains("tighten rtol and atol") && message.contains("use abam"), "{message}");
                assert_eq!(r.summary_json(Some(e))["status"], "failed");
            }
        }
    }
}

/// A damped spring is not conservative: the same loss is its damper's work, not an error.
#[test]
fn a_damped_system_is_not_held_to_its_energy() {
    let text = patch(
        &patch(STIFF_SPRING, "stiffness: 1e12,", "stiffness: 1e4, damping: 50,"),
        "t_end: 0.001, step: 0.0001",
        "t_end: 1, step: 0.01",
    );
    let r = Model::from_yaml(&text).unwrap().run("free", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let kinetic = col(&r, "kinetic_energy");
    assert!(kinetic[kinetic.len() - 1] < 1e-6 * 5e-3, "the damper took the energy");
    assert!(r.summary.warnings.is_empty(), "{:?}", r.summary.warnings);
}

/// The slider-crank's kinematics started at `t = 1e12` s: the crank's angle is `6.3e12` rad,
/// whose round-off (`1e-3` rad) Newton's floor follows, so the run can end with a joint open by
/// 5.4 cm (residual `4.9e-2`) and the slider on the other branch: it fails at the first output,
/// saying why; from `t = 0` the same analysis passes the same check.
#[test]
fn kinematics_at_a_huge_time_fails_saying_why() {
    let late = patched_example("slider_crank.yaml", &[("t_end: 2.0,", "t_start: 1.0e12, t_end: 1000000000000.5,")]);
    let failure = Model::from_yaml(&late).unwrap().run("kinematics", &Default::default()).unwrap_err();
    let message = failure.error.to_string();
    let Error::Accuracy { quantity, time, rows, value, .. } = &failure.error else { panic!("{message}") };
    assert_eq!((*quantity, *time), ("position residual", 1e12), "{message}");
    assert!(*value > 1e-6 * 0.4 && !rows.is_empty(), "{message}");
    assert!(message.contains("round-off") && message.contains("start the analysis near t = 0"), "{message}");

    let (_, r) = common::run("slider_crank.yaml", "kinematics");
    assert_eq!(r.len(), 201);
}
