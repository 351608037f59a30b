//! Fuzz target: model file text to a short analysis, the whole path a user's file takes. The
//! input is the YAML text; each execution parses and compiles it (`Model::from_yaml`), checks
//! and assembles the mechanism and every analysis's system (`analysis::check`), then runs every
//! analysis over a few output steps (`Model::run_with`). It holds the engine's promises
//! (docs/reliability.md), not only "no panic":
//!
//! - every step returns its value or a typed [`Error`] whose message can be written;
//! - a model that does not compile says why: at least one problem, each with a message;
//! - no NaN or infinity leaves the engine: every number of a check report (the assembled
//!   positions, velocities and residuals) and every column of a run's results, the rows of a
//!   failed run included (they are the results "computed before it", kept for the user);
//! - results are whole: one value per output time in every column, times increasing;
//! - no input hangs it: libFuzzer's `-timeout` (1 s in `.ci/run`) reports an input that runs
//!   longer as a failure.

#![no_main]

use libfuzzer_sys::fuzz_target;
use linkwork::{analysis, Error, Model, Overrides, Results};

/// Output steps an analysis runs: enough for the first step from the assembled start and two
/// more with the integrator's or the kinematic predictor's history, few enough that an execution
/// costs milliseconds rather than the file's full run (a thousand output steps or more).
const OUTPUT_STEPS: f64 = 3.0;

/// Longest span an analysis runs, s. A mutated `step` of hours would otherwise make three
/// output steps an hour of dynamics, which a stiff model integrates in millions of steps (the
/// engine bounds it by its 5-million-step budget, about a minute: a timeout here, not a bug).
/// The examples' steps are at most 0.05 s, so their three steps fit.
const MAX_SPAN: f64 = 0.2;

/// Most moving bodies a model may have to be analysed (a larger one is only read and compiled).
/// The check's rank test and assembly are dense, `O((3 bodies)^3)` per Newton step: the IFToMM
/// N-four-bar example (81 bodies) takes 0.6 s an execution and its mutants pass the 1 s timeout,
/// its 21-body version (`examples/nfourbar.py 10`) 36 ms. Every other example has at most 7.
const MAX_BODIES: usize = 24;

fuzz_target!(|data: &[u8]| {
    // The engine reads text; other bytes are the file reader's concern (`Error::Io`).
    if let Ok(text) = std::str::from_utf8(data) {
        fuzz_one(text);
    }
});

fn fuzz_one(text: &str) {
    let model = match Model::from_yaml(text) {
        Ok(model) => model,
        Err(Error::Model(problems)) => {
            assert!(!problems.is_empty(), "a model error lists at least one problem");
            assert!(problems.iter().all(|p| !p.message.is_empty()), "every problem says what is wrong: {problems:?}");
            return;
        }
        Err(other) => panic!("reading a model's text can only fail with a model error, not: {other:?}"),
    };
    if model.bodies.len() > MAX_BODIES {
        return;
    }
    match analysis::check(&model) {
        Ok(report) => {
            let systems =
                std::iter::once(&report.mechanism).chain(report.analyses.values().filter_map(|a| a.system.as_ref()));
            for s in systems {
                let a = &s.assembly;
                let numbers = a.q.iter().chain(&a.qdot).chain(&a.change).chain([&a.residual, &a.velocity_residual]);
                assert!(numbers.clone().all(|x| x.is_finite()), "check: a non-finite assembly: {a:?}");
            }
        }
        Err(e) => assert!(!e.to_string().is_empty(), "an error says what went wrong"),
    }
    for (name, a) in &model.analyses {
        let overrides = short(a);
        match model.run_with(name, &overrides) {
            Ok(results) => whole_and_finite(&results, name, "ok"),
            Err(failure) => {
                assert!(!failure.error.to_string().is_empty(), "an error says what went wrong");
                whole_and_finite(&failure.results, name, "failed");
            }
        }
    }
}

/// Overrides that end analysis `a` after at most [`OUTPUT_STEPS`] output steps and
/// [`MAX_SPAN`] seconds (the output step shrunk to the span if it is longer). A modes analysis
/// is at one time and takes none; neither does a run already that short.
fn short(a: &linkwork::model::Analysis) -> Overrides {
    let span = a.t_end - a.t_start;
    let want = span.min(OUTPUT_STEPS * a.step).min(MAX_SPAN);
    if a.kind == linkwork::model::spec::AnalysisKind::Modes || want >= span {
        return Overrides::default();
    }
    let t_end = a.t_start + want;
    let step = (a.step > t_end - a.t_start && t_end > a.t_start).then_some(t_end - a.t_start);
    Overrides { t_end: Some(t_end), step, ..Overrides::default() }
}

/// Every column of `r` has one value per output time, times increase, and no value is NaN or
/// infinite.
fn whole_and_finite(r: &Results, analysis: &str, status: &str) {
    assert_eq!(r.names.len(), r.columns.len(), "{analysis} ({status}): one name per column");
    assert!(r.time.windows(2).all(|w| w[0] < w[1]), "{analysis} ({status}): times increase: {:?}", r.time);
    assert!(r.time.iter().all(|t| t.is_finite()), "{analysis} ({status}): a non-finite time: {:?}", r.time);
    for (name, column) in r.names.iter().zip(&r.columns) {
        assert_eq!(column.len(), r.len(), "{analysis} ({status}): column {name} has one value per time");
        if let Some(k) = column.iter().position(|x| !x.is_finite()) {
            panic!("{analysis} ({status}): column {name} is {} at t = {}", column[k], r.time[k]);
        }
    }
}
