//! Summaries (`summaries:` of a model file, docs/model-format.md "Summaries"): whole-run
//! quantities against closed forms, the quadrature's order observed on refinement, the same values
//! from a streamed run and from columns `outputs` leaves out, the analyses that write none, and
//! each error at `summaries.<name>`.

mod common;

use common::example_text;
use linkwork::results::stream::{CsvSink, RowSink};
use linkwork::{Error, Model, Results, RunOptions, Sink};

/// A wheel pinned to ground and turned at `w = 3` rad/s, with the measures `s = sin(3 t)` and
/// `p = t^3 - t`; a kinematic analysis from 0 to 2 s every `step` s, and `summaries` (lines of
/// `name: "expression"`).
fn wheel(step: f64, summaries: &str) -> Model {
    let text = format!(
        "parameters: {{w: 3, span: 2}}
bodies:
  wheel: {{mass: 1, inertia: 0.1, position: [0, 0], points: {{O: [0, 0]}}}}
joints:
  O: {{type: revolute, body_i: wheel, point_i: O, body_j: ground, point_j: [0, 0]}}
drivers:
  motor: {{type: angle, body: wheel, function: \"w*t\"}}
measures:
  s: \"sin(3*t)\"
  p: \"t^3 - t\"
summaries:
{summaries}
analyses:
  kinematics: {{type: kinematic, t_end: span, step: {step}}}
"
    );
    Model::from_yaml(&text).unwrap_or_else(|e| panic!("{e}"))
}

/// The summary `name` of `r`.
fn summary(r: &Results, name: &str) -> f64 {
    r.summary.summaries.as_ref().expect("summaries written")[name]
}

/// Each aggregation against its closed form over `t` in `[0, 2]` (21 rows): `p = t^3 - t` is a
/// cubic, which the not-a-knot spline reproduces, so its integral, mean and value between rows
/// are exact to round-off (1e-12 of values of order 1); the wheel's angle `3 t` and speed 3 are
/// exact at the rows; parameters and `time` enter as in any expression.
#[test]
fn summaries_match_their_closed_forms() {
    let model = wheel(
        0.1,
        "  integral: \"integral(p)\"
  mean: \"mean(p)\"
  per_span: \"integral(p) / span\"
  at: \"at(0.55, p)\"
  rms: \"rms(wheel.omega)\"
  max: \"max(wheel.phi) / w\"
  min: \"min(p)\"
  peak: \"peak(p - 10)\"
  initial: \"initial(wheel.phi)\"
  final: \"final(p)\"
  time: \"integral(time * w)\"",
    );
    let r = model.run("kinematics", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let min_p = -2.0 / (3.0 * 3f64.sqrt()); // at t = 1/sqrt(3), not a row: the rows' least
    let rows_min = r.column("p").unwrap().iter().copied().fold(f64::INFINITY, f64::min);
    assert!(rows_min > min_p && rows_min - min_p < 1e-2);
    let expected = [
        ("integral", 2.0),
        ("mean", 1.0),
        ("per_span", 1.0),
        ("at", 0.55f64.powi(3) - 0.55),
        ("rms", 3.0),
        ("max", 2.0),
        ("min", rows_min),
        ("peak", 10.0 - rows_min),
        ("initial", 0.0),
        ("final", 6.0),
        ("time", 6.0),
    ];
    for (name, value) in expected {
        let got = summary(&r, name);
        assert!((got - value).abs() < 1e-12, "{name}: {got} against {value}");
    }
    // In the file's order in the summary, alphabetical in summary.json.
    let names: Vec<&str> = r.summary.summaries.as_ref().unwrap().keys().map(String::as_str).collect();
    assert_eq!(names, expected.map(|(n, _)| n));
    let json = r.summary_json(None);
    assert_eq!(json["summaries"]["integral"].as_f64(), Some(summary(&r, "integral")));
}

/// `integral(sin(3 t))` from 0 to 2 s on steps of 0.1, 0.05 and 0.025 s against
/// `(1 - cos 6) / 3`: the error falls as `h^4` (docs/model-format.md, "Summaries"), each halving
/// dividing it by about 16; judged at `2^3.5`, so that the asymptote need not be reached exactly.
/// The observed orders are printed.
#[test]
fn the_integral_converges_at_fourth_order() {
    let exact = (1.0 - 6f64.cos()) / 3.0;
    let errors: Vec<f64> = [0.1, 0.05, 0.025]
        .iter()
        .map(|&h| {
            let r = wheel(h, "  s: \"integral(s)\"")
                .run("kinematics", &Default::default())
                .unwrap_or_else(|f| panic!("{}", f.error));
            (summary(&r, "s") - exact).abs()
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("errors {errors:?}, observed orders {orders:.2?}");
    assert!(orders.iter().all(|&p| p > 3.5), "{orders:?}");
}

/// A [`CsvSink`] that is given each row as it comes, so that no row stays in memory.
struct EveryRow(CsvSink);

impl RowSink for EveryRow {
    fn begin(&mut self, names: &[String]) -> std::io::Result<()> {
        self.0.begin(names)
    }
    fn write(&mut self, time: &[f64], columns: &[Vec<f64>]) -> std::io::Result<()> {
        self.0.write(time, columns)
    }
    fn finish(&mut self) -> std::io::Result<()> {
        self.0.finish()
    }
    fn path(&self) -> String {
        self.0.path()
    }
    fn chunk_bytes(&self) -> usize {
        // Less than a row: a chunk of one row.
        1
    }
}

/// The summaries of a streamed run (its rows leave memory one by one) and of a run whose
/// `outputs` leave out the columns they read are those of the run that keeps every row and
/// column, bit for bit: the columns they read are kept aside as the rows go by.
#[test]
fn streamed_and_selected_runs_have_the_same_summaries() {
    let list = "  a: \"integral(p * wheel.omega)\"\n  b: \"max(s) - at(1.05, wheel.phi)\"";
    let model = wheel(0.05, list);
    let held = model.run("kinematics", &Default::default()).unwrap();
    let path = std::env::temp_dir().join(format!("linkwork-summaries-{}.csv", std::process::id()));
    let sink = Box::new(EveryRow(CsvSink::at(&path)));
    let streamed = model.run("kinematics", &RunOptions { sink: Sink::stream(sink), ..RunOptions::default() }).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert!(streamed.time.is_empty());
    assert_eq!(streamed.summary.summaries, held.summary.summaries);
    let text = model.source.replace(
        "kinematics: {type: kinematic, t_end: span, step: 0.05}",
        "kinematics: {type: kinematic, t_end: span, step: 0.05, outputs: {columns: [s]}}",
    );
    let selected = Model::from_yaml(&text).unwrap().run("kinematics", &Default::default()).unwrap();
    assert_eq!(selected.names, ["s"]);
    assert_eq!(selected.summary.summaries, held.summary.summaries);
}

/// A `static` analysis at one time and a `modes` analysis have one row and no span: they write
/// no summaries (nor fail for them). A run that fails writes none either, whatever it computed.
#[test]
fn runs_without_a_span_or_that_fail_write_no_summaries() {
    let text = example_text("hanging_fourbar.yaml") + "summaries:\n  top: \"max(crank.phi)\"\n";
    let model = Model::from_yaml(&text).unwrap();
    for analysis in ["rest", "vibration"] {
        let r = model.run(analysis, &Default::default()).unwrap_or_else(|f| panic!("{analysis}: {}", f.error));
        assert!(r.summary.summaries.is_none() && r.summary_json(None).get("summaries").is_none(), "{analysis}");
    }
    let text = example_text("slider_crank_lockup.yaml") + "summaries:\n  top: \"max(crank.phi)\"\n";
    let failure = Model::from_yaml(&text).unwrap().run("kinematics", &Default::default()).unwrap_err();
    assert!(matches!(failure.error, Error::Singular { .. }), "{}", failure.error);
    assert!(failure.results.len() > 1 && failure.results.summary.summaries.is_none());
}

/// The problem at `summaries.<name>` of a model error, or of a run's failure.
fn problem(error: &Error) -> String {
    match error {
        Error::Model(problems) => problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; "),
        other => panic!("a model error, not {other}"),
    }
}

/// Each error names its summary and what is wrong. At load: a column outside an aggregation, a
/// wrong count of arguments, an unknown function, a name that is not one, a value that is not an
/// expression. Before the first row: a column the analysis does not have, an `at` time outside
/// its span. After the run: a value that is not finite, the whole expression's (a division by
/// zero, with each aggregation's value) or an argument's at a row (with its time); the run then
/// fails with every row kept and no summary written.
#[test]
fn each_error_names_its_summary() {
    let text = |summaries: &str| {
        format!("bodies: {{b: {{mass: 1, inertia: 1, position: [0, 0]}}}}\nsummaries:\n{summaries}\n")
    };
    for (summaries, path, says) in [
        ("  x: \"p + integral(p)\"", "summaries.x", "'p' outside an aggregation"),
        ("  x: \"integral(p, 2)\"", "summaries.x", "integral() takes one expression, found 2 arguments"),
        ("  x: \"integrate(p)\"", "summaries.x", "integrate"),
        ("  2x: \"max(p)\"", "summaries.2x", "not a valid name"),
        ("  x: 3", "summaries.x", "expected an expression of aggregations of result columns (a string)"),
    ] {
        let error = Model::from_yaml(&text(summaries)).unwrap_err();
        let message = problem(&error);
        assert!(message.contains(&format!("{path}: ")) && message.contains(says), "{summaries}: {message}");
    }

    for (summaries, says) in [
        (
            "  x: \"integral(wheel.effort)\"",
            "no result column 'wheel.effort' (in integral(wheel.effort)); expected a column of the kinematic analysis 'kinematics'",
        ),
        ("  x: \"at(3, p)\"", "at(3, p): the output is from t = 0 to 2 s"),
    ] {
        let failure = wheel(0.1, summaries).run("kinematics", &Default::default()).unwrap_err();
        let message = problem(&failure.error);
        assert!(message.starts_with("summaries.x: ") && message.contains(says), "{message}");
        assert_eq!(failure.results.len(), 0, "refused before the first row");
    }

    let failure = wheel(0.1, "  x: \"final(p) / initial(time)\"").run("kinematics", &Default::default()).unwrap_err();
    let message = failure.error.to_string();
    let Error::NonFinite { time, ref element, value, .. } = failure.error else { panic!("{message}") };
    assert_eq!((element.as_str(), time, value), ("summaries.x", 2.0, f64::INFINITY), "{message}");
    assert!(message.contains("initial(time) = 0") && message.contains("final(p) = 6"), "{message}");
    assert_eq!(failure.results.len(), 21);
    assert!(failure.results.summary.summaries.is_none());
    let json = failure.results.summary_json(Some(&failure.error));
    assert_eq!((json["status"].as_str(), json.get("summaries")), (Some("failed"), None));

    let failure = wheel(0.1, "  x: \"max(1 / (p - 6))\"").run("kinematics", &Default::default()).unwrap_err();
    let message = failure.error.to_string();
    let Error::NonFinite { time, .. } = failure.error else { panic!("{message}") };
    assert_eq!(time, 2.0, "{message}");
    assert!(message.contains("'1 / (p - 6)', the argument of max(1 / (p - 6))"), "{message}");
}
