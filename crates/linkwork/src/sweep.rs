//! Sweeps: one analysis run for many values of a model's parameters, in parallel, each run
//! reduced to a few numbers by output expressions.
//!
//! An output is an expression (the language of [`crate::expr`]) of aggregations of the run's
//! result columns: `max(slider.x) - min(slider.x)`, `peak(motor.effort)`,
//! `at(0.5, crank.phi)`. Each aggregation's argument is itself an expression of the columns
//! (`max(abs(rod.omega) * 2)`), evaluated at every output row. `max` and `min` with two
//! arguments are the element-wise functions, inside an aggregation.
//!
//! | aggregation | value over the output rows |
//! | --- | --- |
//! | `max(f)`, `min(f)` | the largest and smallest value |
//! | `peak(f)` | the largest absolute value |
//! | `mean(f)`, `rms(f)` | time averages by the trapezoidal rule, `int f dt / T` and `sqrt(int f^2 dt / T)` (the value at the one row of a one-row run) |
//! | `initial(f)`, `final(f)` | the first and last row |
//! | `at(time, f)` | linear interpolation between the rows around `time` |
//!
//! The sweep sits above `results`: it runs analyses ([`Model::run`]) on models made with
//! [`Model::with_parameters`] and reads their [`Results`]; nothing below imports it.

use crate::error::{Error, Problem};
use crate::expr::Expr;
use crate::progress::Progress;
use crate::{Model, Overrides, Results};
use rayon::prelude::*;
use std::sync::Arc;

/// The aggregations, by name.
const AGGREGATIONS: &[&str] = &["max", "min", "peak", "mean", "rms", "initial", "final", "at"];

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Max,
    Min,
    Peak,
    Mean,
    Rms,
    Initial,
    Final,
    At(f64),
}

/// One aggregation of an output: its kind and its argument, over the columns in `columns`
/// (slot `k` of `arg` is the result column `columns[k]`, `"time"` included).
#[derive(Debug, Clone)]
struct Aggregate {
    kind: Kind,
    arg: String,
}

/// An output of a sweep: a name and an expression of aggregations of result columns.
#[derive(Debug, Clone)]
pub struct Output {
    /// The output's name (a column of the sweep's table).
    pub name: String,
    /// Its text, as written.
    pub source: String,
    /// The expression with each aggregation `k` as variable slot `k`, parsed once.
    outer: Expr,
    aggregates: Vec<Aggregate>,
}

impl Output {
    /// Read `source`, checking its shape (aggregations, their arguments' count, the expression
    /// around them); the column names are checked against each run's results. `Err` says what
    /// is wrong, for the output `name`.
    pub fn parse(name: &str, source: &str) -> Result<Output, String> {
        let mut outer = String::new();
        let mut aggregates = Vec::new();
        let bytes = source.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            let starts_name = (c.is_ascii_alphabetic() || c == b'_') && (i == 0 || !is_name_byte(bytes[i - 1]));
            if !starts_name {
                outer.push(c as char);
                i += 1;
                continue;
            }
            let end = (i..bytes.len()).find(|&j| !is_name_byte(bytes[j])).unwrap_or(bytes.len());
            let word = &source[i..end];
            let open = (end..bytes.len()).find(|&j| !bytes[j].is_ascii_whitespace());
            match open.filter(|&j| bytes[j] == b'(' && AGGREGATIONS.contains(&word)) {
                Some(open) => {
                    let close = matching(bytes, open).ok_or_else(|| format!("'{source}': unbalanced parentheses"))?;
                    let args = split_top(&source[open + 1..close]);
                    let kind = match (word, args.len()) {
                        // Element-wise, left for the expression language.
                        ("max" | "min", 2) => None,
                        ("max", 1) => Some(Kind::Max),
                        ("min", 1) => Some(Kind::Min),
                        ("peak", 1) => Some(Kind::Peak),
                        ("mean", 1) => Some(Kind::Mean),
                        ("rms", 1) => Some(Kind::Rms),
                        ("initial", 1) => Some(Kind::Initial),
                        ("final", 1) => Some(Kind::Final),
                        ("at", 2) => {
                            let time =
                                Expr::parse(args[0], &mut |n| Err(format!("'{n}': the time of at() is a number")))
                                    .ok()
                                    .and_then(|e| e.constant_value())
                                    .filter(|t| t.is_finite())
                                    .ok_or_else(|| {
                                        format!(
                                            "'{source}': at(time, f) needs a number for time, found '{}'",
                                            args[0].trim()
                                        )
                                    })?;
                            Some(Kind::At(time))
                        }
                        (w, n) => {
                            return Err(format!(
                                "'{source}': {w}() takes {}, found {n} argument{}",
                                if w == "at" { "a time and an expression (2 arguments)" } else { "one expression" },
                                if n == 1 { "" } else { "s" }
                            ))
                        }
                    };
                    match kind {
                        Some(kind) => {
                            let arg = if matches!(kind, Kind::At(_)) { args[1] } else { args[0] };
                            outer.push_str(&format!("__aggregate{}", aggregates.len()));
                            aggregates.push(Aggregate { kind, arg: arg.trim().to_string() });
                            i = close + 1;
                        }
                        None => {
                            outer.push_str(word);
                            i = end;
                        }
                    }
                }
                None => {
                    outer.push_str(word);
                    i = end;
                }
            }
        }
        // The expression around the aggregations names nothing else.
        let count = aggregates.len();
        let outer = Expr::parse(&outer, &mut |n| {
            n.strip_prefix("__aggregate").and_then(|k| k.parse::<usize>().ok()).filter(|&k| k < count).ok_or_else(
                || format!("'{n}' outside an aggregation; write max({n}), min, peak, mean, rms, initial, final or at(time, {n})"),
            )
        })
        .map_err(|e| format!("'{source}': {e}"))?;
        Ok(Output { name: name.to_string(), source: source.to_string(), outer, aggregates })
    }

    /// The output's value for one run's results. `Err` names an unknown column or a value that is
    /// not a finite number.
    pub fn evaluate(&self, results: &Results) -> Result<f64, String> {
        let time = &results.time;
        let values =
            self.aggregates.iter().map(|a| aggregate(a, results, time)).collect::<Result<Vec<f64>, String>>()?;
        let v = self.outer.eval(&values);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("'{}' is {v} on this run", self.source))
        }
    }
}

fn is_name_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'.'
}

/// The index of the `)` that closes the `(` at `open`.
fn matching(bytes: &[u8], open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (j, &b) in bytes.iter().enumerate().skip(open) {
        match b {
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(j);
                }
            }
            _ => {}
        }
    }
    None
}

/// `text` split at the commas outside parentheses.
fn split_top(text: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (j, b) in text.bytes().enumerate() {
        match b {
            b'(' => depth += 1,
            b')' => depth -= 1,
            b',' if depth == 0 => {
                parts.push(&text[start..j]);
                start = j + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// One aggregation over a run's rows.
fn aggregate(a: &Aggregate, results: &Results, time: &[f64]) -> Result<f64, String> {
    let mut columns: Vec<&[f64]> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let expr = Expr::parse(&a.arg, &mut |name| {
        if let Some(k) = names.iter().position(|n| n == name) {
            return Ok(k);
        }
        let column = if name == "time" { Some(time) } else { results.column(name) };
        match column {
            Some(c) => {
                columns.push(c);
                names.push(name.to_string());
                Ok(names.len() - 1)
            }
            None => Err(format!("no result column '{name}' (the columns of results.csv, and time)")),
        }
    })
    .map_err(|e| format!("'{}': {e}", a.arg))?;
    if time.is_empty() {
        return Err("the run wrote no output rows".into());
    }
    let mut row = vec![0.0; columns.len()];
    let f: Vec<f64> = (0..time.len())
        .map(|i| {
            for (slot, c) in row.iter_mut().zip(&columns) {
                *slot = c[i];
            }
            expr.eval(&row)
        })
        .collect();
    let n = f.len();
    let span = time[n - 1] - time[0];
    // Trapezoidal integral of g over the output times.
    let integral = |g: &dyn Fn(f64) -> f64| -> f64 {
        (1..n).map(|i| 0.5 * (g(f[i]) + g(f[i - 1])) * (time[i] - time[i - 1])).sum()
    };
    Ok(match a.kind {
        Kind::Max => f.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        Kind::Min => f.iter().copied().fold(f64::INFINITY, f64::min),
        Kind::Peak => f.iter().map(|v| v.abs()).fold(0.0, f64::max),
        Kind::Initial => f[0],
        Kind::Final => f[n - 1],
        Kind::Mean if span > 0.0 => integral(&|v| v) / span,
        Kind::Rms if span > 0.0 => (integral(&|v| v * v) / span).sqrt(),
        Kind::Mean => f[0],
        Kind::Rms => f[0].abs(),
        Kind::At(t) => {
            if !(time[0]..=time[n - 1]).contains(&t) {
                return Err(format!("at({t}, ...): the run's output is from t = {} to {} s", time[0], time[n - 1]));
            }
            if n == 1 {
                return Ok(f[0]);
            }
            // The rows k - 1 and k around t (t at the first row: the first two).
            let k = time.partition_point(|&x| x < t).clamp(1, n - 1);
            let w = (t - time[k - 1]) / (time[k] - time[k - 1]);
            f[k - 1] + w * (f[k] - f[k - 1])
        }
    })
}

/// The outcome of one variant: its outputs in the order given, or the error that stopped it.
pub type Row = Result<Vec<f64>, Error>;

/// Run `analysis` for each of `variants` (parameter values, `(name, text)` as
/// [`Model::with_parameters`] takes them) on `workers` threads (all cores when `None`), each run
/// reduced to `outputs`. A variant that fails is an `Err` row, not the end of the sweep; an
/// output that cannot be evaluated on a run is a model error at `outputs.<name>`. Rows are in the
/// order of `variants` whatever the threads. `watch` counts the variants finished
/// ([`Progress::finished`]); once it is stopped, the variants running end as
/// [`Error::Interrupted`] at their next step, and so does every later one at its first.
pub fn sweep(
    model: &Model,
    analysis: &str,
    variants: &[Vec<(String, String)>],
    outputs: &[Output],
    workers: Option<usize>,
    watch: &Arc<Progress>,
) -> Result<Vec<Row>, Error> {
    let t_start = model.analysis(analysis)?.t_start;
    // The file's text parsed once; each variant reads its parameters from the document.
    let document = model.document()?;
    let one = |values: &Vec<(String, String)>| -> Row {
        let run = || -> Row {
            // Stopped before this variant began: not compiled, not run.
            if watch.stopped() {
                return Err(Error::Interrupted { time: t_start });
            }
            let variant = model.with_parameters_in(&document, values)?;
            let results = variant.run_watched(analysis, &Overrides::default(), &watch.part()).map_err(|f| f.error)?;
            outputs
                .iter()
                .map(|o| {
                    o.evaluate(&results).map_err(|e| Error::Model(vec![Problem::new(format!("outputs.{}", o.name), e)]))
                })
                .collect()
        };
        let row = run();
        watch.finish_part();
        row
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(k) = workers {
        pool = pool.num_threads(k.max(1));
    }
    let pool = pool.build().map_err(|e| Error::Model(vec![Problem::new("workers", e.to_string())]))?;
    Ok(pool.install(|| variants.par_iter().map(one).collect()))
}
