//! Fuzz target: model file text to a short analysis, the whole path a user's file takes. The
//! input is the YAML text; each execution parses and compiles it (`Model::from_yaml`), checks
//! and assembles the mechanism and every analysis's system (`analysis::check`), then runs every
//! analysis over a few output steps and at most [`MAX_STEPS`] integrator steps
//! (`Model::run`). It holds the engine's promises
//! (docs/reliability.md), not only "no panic":
//!
//! - every step returns its value or a typed [`Error`] whose message can be written;
//! - a model that does not compile says why: at least one problem, each with a message;
//! - no NaN or infinity leaves the engine: every number of a check report (the assembled
//!   positions, velocities and residuals) and every column of a run's results, the rows of a
//!   failed run included (they are the results "computed before it", kept for the user), and
//!   every summary;
//! - results are whole: one value per output time in every column, times increasing;
//! - no input hangs it: libFuzzer's `-timeout` (5 s in `fuzz/run.sh`, for at most
//!   [`MAX_ANALYSES`] analyses) reports an input that runs longer as a failure.
//!
//! Byte-level mutation alone rarely keeps a model valid: after twelve minutes of it 15 of the 3,126
//! inputs of the corpus compiled (the seeds), the rest covering the reader's error paths. So
//! three mutations in four are structural ([`mutate`]): the text is read as a YAML tree, one node
//! changes (a number scaled or replaced by an edge value, a name swapped for another of the file,
//! an expression extended, an entry removed, copied under a new name or added), and the tree is
//! written back; the fourth, and any input that is not YAML, gets libFuzzer's own mutations.

#![no_main]

use libfuzzer_sys::{fuzz_mutator, fuzz_target};
use linkwork::{analysis, Error, Model, Overrides, Results};
use serde_yaml_ng::{Mapping, Value};

/// Output steps an analysis runs: enough for the first step from the assembled start and two
/// more with the integrator's or the kinematic predictor's history, few enough that an execution
/// costs milliseconds rather than the file's full run (a thousand output steps or more).
const OUTPUT_STEPS: f64 = 3.0;

/// Longest span an analysis runs, s. A mutated `step` of hours would otherwise make three
/// output steps an hour of dynamics, which a stiff model integrates in millions of steps (the
/// engine bounds it by its 5-million-step budget, about a minute: a timeout here, not a bug).
/// The examples' steps are at most 0.05 s, so their three steps fit.
const MAX_SPAN: f64 = 0.2;

/// Step budget of a dynamic analysis (`IntegratorSettings::max_steps`). The engine's, 5 million,
/// is minutes of CPU: a pendulum under a mutated gravity of 9.2e18 m/s^2 took two to spend it on
/// 0.03 s of motion. The examples' three output steps take at most 85; the mutants of
/// the 7-body `andrews.yaml` that spend 2,000 take 70 to 830 ms.
const MAX_STEPS: usize = 2_000;

/// Analyses run per input, in file order. A kinematic or inverse analysis whose driver has a pole
/// between output times (`2*pi*t/(t - 0.01)`) spends its bound of 100,000 sub-steps an output
/// interval before it names the driver, about 0.4 s (docs/reliability.md, "Bounded loops"), and
/// a mutation may copy an analysis many times; the examples have at most 4. With this cap an
/// input is bounded by 4 such runs, hence `-timeout=5` in `fuzz/run.sh`.
const MAX_ANALYSES: usize = 4;

/// Most moving bodies a model may have to be analysed (a larger one is only read and compiled).
/// The check's rank test and assembly are dense, `O((3 bodies)^3)` per Newton step: the IFToMM
/// N-four-bar example (81 bodies) takes 0.6 s an execution (its mutants passed a 1 s timeout),
/// its 21-body version (`examples/nfourbar.py 10`) 36 ms. Every other example has at most 7.
const MAX_BODIES: usize = 24;

fuzz_target!(|data: &[u8]| {
    // The engine reads text; other bytes are the file reader's concern (`Error::Io`).
    if let Ok(text) = std::str::from_utf8(data) {
        fuzz_one(text);
    }
});

fn fuzz_one(text: &str) {
    let mut model = match Model::from_yaml(text) {
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
    for a in model.analyses.values_mut() {
        a.integrator.max_steps = MAX_STEPS;
    }
    match analysis::check(&model) {
        Ok(report) => {
            let systems =
                std::iter::once(&report.mechanism).chain(report.analyses.values().filter_map(|a| a.system.as_ref()));
            for s in systems {
                let a = &s.assembly;
                let mut numbers = a.q.iter().chain(&a.qdot).chain(&a.change).chain([&a.residual, &a.velocity_residual]);
                assert!(numbers.all(|x| x.is_finite()), "check: a non-finite assembly: {a:?}");
            }
        }
        Err(e) => assert!(!e.to_string().is_empty(), "an error says what went wrong"),
    }
    for (name, a) in model.analyses.iter().take(MAX_ANALYSES) {
        match model.run(name, &short(a).into()) {
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
/// infinite, nor any summary.
fn whole_and_finite(r: &Results, analysis: &str, status: &str) {
    for (name, value) in r.summary.summaries.iter().flatten() {
        assert!(value.is_finite(), "{analysis} ({status}): summary {name} is {value}");
    }
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

fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    let mut rng = Rng(u64::from(seed).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    // One mutation in four is libFuzzer's own (bytes, dictionary words), so that broken YAML and
    // the reader's error paths stay covered.
    if rng.below(4) == 0 {
        return libfuzzer_sys::fuzzer_mutate(data, size, max_size);
    }
    let text = std::str::from_utf8(&data[..size]).ok().and_then(|t| serde_yaml_ng::from_str::<Value>(t).ok()).and_then(
        |mut doc| {
            mutate(&mut doc, &mut rng);
            serde_yaml_ng::to_string(&doc).ok()
        },
    );
    match text.filter(|t| t.len() <= max_size) {
        Some(t) => {
            data[..t.len()].copy_from_slice(t.as_bytes());
            t.len()
        }
        None => libfuzzer_sys::fuzzer_mutate(data, size, max_size),
    }
});

/// xorshift64: the mutator must be deterministic in libFuzzer's seed, so that a run replays.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in `0..n` (`n > 0`), up to a bias of `n / 2^64`.
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that break solvers: zero, round-off, huge, the edges of a double.
const EDGE_NUMBERS: [f64; 8] = [0.0, 1e-12, -1e-12, 1e9, -1e9, 1e300, 5e-324, 1.0];

/// Fragments appended to an expression: growth, poles in time, domains that end.
const EXPRESSION_TAILS: [&str; 8] =
    [" + t", "*t", " + sin(50*t)", "/(t - 0.01)", "^2", " + exp(40*t)", " + sqrt(0.02 - t)", " - 1e9"];

/// Optional fields with a plausible value, added to a mapping (where one does not belong, the
/// reader's unknown-field path).
const OPTIONAL_FIELDS: [(&str, &str); 14] = [
    ("given", "[phi, omega]"),
    ("integrator", "hht"),
    ("integrator", "abam"),
    ("solver", "{rtol: 1e-10, atol: 1e-10}"),
    ("solver", "{max_step: 1e-4, formulation: index3}"),
    ("gravity", "[0, -9.81]"),
    ("velocity", "[1, 0]"),
    ("omega", "20"),
    ("t_start", "0.5"),
    ("about", "initial"),
    ("free_length", "0.01"),
    ("frame", "body"),
    ("internal", "true"),
    ("damping", "1e6"),
];

/// Change one node of `doc`, chosen uniformly.
fn mutate(doc: &mut Value, rng: &mut Rng) {
    let mut names = Vec::new();
    strings(doc, &mut names);
    let mut k = rng.below(count(doc));
    let Some(node) = nth(doc, &mut k) else { return };
    match node {
        Value::Number(n) => {
            let x = n.as_f64().unwrap_or(0.0);
            let y = match rng.below(6) {
                0 => 2.0 * x,
                1 => 0.5 * x,
                2 => -x,
                3 => x * (1.0 + 1e-9),
                4 => x + 1.0,
                _ => *rng.pick(&EDGE_NUMBERS),
            };
            // Counts (`max_iterations`, `max_order`) stay integers when they were.
            *node = if n.is_f64() || y.fract() != 0.0 { Value::from(y) } else { Value::from(y as i64) };
        }
        Value::String(s) => match rng.below(3) {
            0 if !names.is_empty() => *s = rng.pick(&names).clone(),
            1 => s.push_str(EXPRESSION_TAILS[rng.below(EXPRESSION_TAILS.len())]),
            _ => *s = format!("{}({s})", rng.pick(&["sqrt", "exp", "1/", "abs", "log", "sin"])),
        },
        Value::Bool(b) => *b = !*b,
        Value::Sequence(items) if !items.is_empty() => {
            let i = rng.below(items.len());
            if rng.below(2) == 0 {
                items.remove(i);
            } else {
                items.push(items[i].clone());
            }
        }
        Value::Mapping(map) if !map.is_empty() => mutate_mapping(map, rng),
        Value::Mapping(map) => add_field(map, rng),
        _ => *node = Value::from(*rng.pick(&EDGE_NUMBERS)),
    }
}

/// Remove an entry, copy one under a new name (a second body, joint or analysis), or add a field.
fn mutate_mapping(map: &mut Mapping, rng: &mut Rng) {
    let i = rng.below(map.len());
    let (key, value) = map.iter().nth(i).map(|(k, v)| (k.clone(), v.clone())).expect("i < len");
    match rng.below(3) {
        0 => {
            map.shift_remove(&key);
        }
        1 => {
            let name = format!("{}2", key.as_str().unwrap_or("x"));
            map.insert(Value::from(name), value);
        }
        _ => add_field(map, rng),
    }
}

fn add_field(map: &mut Mapping, rng: &mut Rng) {
    let (key, value) = rng.pick(&OPTIONAL_FIELDS);
    if let Ok(v) = serde_yaml_ng::from_str::<Value>(value) {
        map.insert(Value::from(*key), v);
    }
}

/// Nodes of the tree (mapping keys not counted).
fn count(v: &Value) -> usize {
    1 + match v {
        Value::Sequence(items) => items.iter().map(count).sum(),
        Value::Mapping(map) => map.values().map(count).sum(),
        Value::Tagged(t) => count(&t.value),
        _ => 0,
    }
}

/// The `k`-th node in pre-order.
fn nth<'a>(v: &'a mut Value, k: &mut usize) -> Option<&'a mut Value> {
    if *k == 0 {
        return Some(v);
    }
    *k -= 1;
    match v {
        Value::Sequence(items) => items.iter_mut().find_map(|x| nth(x, k)),
        Value::Mapping(map) => map.values_mut().find_map(|x| nth(x, k)),
        Value::Tagged(t) => nth(&mut t.value, k),
        _ => None,
    }
}

/// Every string of the tree, mapping keys included: the names a mutation may swap in.
fn strings(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::String(s) => out.push(s.clone()),
        Value::Sequence(items) => items.iter().for_each(|x| strings(x, out)),
        Value::Mapping(map) => map.iter().for_each(|(k, x)| {
            strings(k, out);
            strings(x, out);
        }),
        Value::Tagged(t) => strings(&t.value, out),
        _ => {}
    }
}
