//! Functionals of sampled time series: expressions of aggregations of named columns, each column
//! sampled at the same increasing times. A run's summaries (`summaries:` in a model file) and a
//! sweep's outputs are written so: `integral(pump_power) / integral(motor_power)`,
//! `max(abs(motor.effort))`, `at(0.5, crank.phi)`.
//!
//! Each aggregation's argument is itself an expression of the columns (`max(abs(rod.omega) * 2)`),
//! evaluated at every row; `time` is the sample times. `max` and `min` with two arguments are
//! the element-wise functions of the expression language, inside an aggregation or around them.
//! Around the aggregations the expression is the usual arithmetic of numbers and named values
//! (a model's parameters, [`Names`]); a column there, outside any aggregation, is refused.
//!
//! | aggregation | value over the rows |
//! | --- | --- |
//! | `max(f)`, `min(f)` | the largest and smallest value at a row |
//! | `peak(f)` | the largest absolute value at a row |
//! | `integral(f)` | `integral f dt` from the first row's time to the last's (below) |
//! | `mean(f)` | `integral(f) / T`, `T` the span of the rows (the value at the row of a one-row series) |
//! | `rms(f)` | `sqrt(mean(f^2))` |
//! | `initial(f)`, `final(f)` | the first and the last row |
//! | `at(time, f)` | the spline below at `time`, within the span of the rows |
//!
//! # Quadrature
//!
//! `integral(f)` integrates exactly the not-a-knot cubic spline through the samples `(t_i, f_i)`
//! ([`Spline`], as a table's `spline(name, x)`): piece by piece,
//! `h_i (f_i + f_i+1) / 2 + h_i^2 (m_i - m_i+1) / 12` with the spline's slopes `m_i`
//! ([`Spline::integral`]). For `f` with a bounded fourth derivative the error is `O(h^4)`, `h`
//! the largest step between rows, on any spacing whose steps stay within a bounded ratio of each
//! other: the spline's own error (de Boor, *A Practical Guide to Splines*, ch. V) integrated over
//! the span. A cubic is integrated exactly; two rows give the trapezoidal rule and three the
//! parabola through them. Where `f` has a corner between rows (a contact's first touch, a
//! friction force reversing) the error near it is `O(h^2)` times the jump in slope, as the
//! trapezoidal rule's: the spline's response to it dies away within a few rows.

use std::fmt;

use super::spline::Method;
use super::{Expr, Names, Spline};
use crate::error::seconds;

/// The name of the sample times among the columns.
pub const TIME: &str = "time";

/// The aggregations, by name.
pub const AGGREGATIONS: &[&str] = &["max", "min", "peak", "integral", "mean", "rms", "initial", "final", "at"];

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Max,
    Min,
    Peak,
    Integral,
    Mean,
    Rms,
    Initial,
    Final,
    At(f64),
}

/// One aggregation: its kind and its argument, an expression whose slot `k` is the column
/// `columns[k]` (`time` among them).
#[derive(Debug, Clone)]
struct Aggregate {
    kind: Kind,
    arg: Expr,
    columns: Vec<String>,
    /// The aggregation as written (`max(abs(motor.effort))`), for messages.
    text: String,
}

/// An expression of aggregations of columns, parsed once.
#[derive(Debug, Clone)]
pub struct Functional {
    source: String,
    /// The expression with aggregation `k` as variable slot `k`.
    outer: Expr,
    aggregates: Vec<Aggregate>,
}

/// Why a functional has no value on a series.
#[derive(Debug, Clone, PartialEq)]
pub enum EvalError {
    /// The series lacks what the functional reads (a column, any row, the time of an `at`):
    /// what is missing.
    Missing(String),
    /// A value that is not a finite number: the value; what gave it (an aggregation's
    /// argument, or the expression with the aggregations' values); the time of the row where an
    /// argument gave it (`None`: the expression around the aggregations).
    NonFinite {
        /// The value.
        value: f64,
        /// What gave it.
        what: String,
        /// The row's time, s, for an argument.
        time: Option<f64>,
    },
}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvalError::Missing(message) => f.write_str(message),
            EvalError::NonFinite { value, what, time: Some(t) } => {
                write!(f, "{what} is {value} at t = {} s", seconds(t))
            }
            EvalError::NonFinite { value, what, time: None } => write!(f, "{what} is {value}"),
        }
    }
}

impl Functional {
    /// Read `source`: its aggregations, their arguments' count and expressions, and the
    /// expression around them, where `names` gives the values of named numbers (a model's
    /// parameters). The column names are checked against a series later ([`Functional::check`],
    /// [`Functional::eval`]). `Err` says what is wrong.
    pub fn parse(source: &str, names: &dyn Names) -> Result<Functional, String> {
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
            let Some(open) = open.filter(|&j| bytes[j] == b'(' && AGGREGATIONS.contains(&word)) else {
                outer.push_str(word);
                i = end;
                continue;
            };
            let close = matching(bytes, open).ok_or_else(|| format!("'{source}': unbalanced parentheses"))?;
            let args = split_top(&source[open + 1..close]);
            let kind = match (word, args.len()) {
                // Element-wise, left for the expression language.
                ("max" | "min", 2) => None,
                ("max", 1) => Some(Kind::Max),
                ("min", 1) => Some(Kind::Min),
                ("peak", 1) => Some(Kind::Peak),
                ("integral", 1) => Some(Kind::Integral),
                ("mean", 1) => Some(Kind::Mean),
                ("rms", 1) => Some(Kind::Rms),
                ("initial", 1) => Some(Kind::Initial),
                ("final", 1) => Some(Kind::Final),
                ("at", 2) => {
                    let mut number = |n: &str| Err(format!("'{n}': the time of at() is a number"));
                    let time = Expr::parse_with(args[0], names, &mut number)
                        .ok()
                        .and_then(|e| e.constant_value())
                        .filter(|t| t.is_finite())
                        .ok_or_else(|| {
                            format!("'{source}': at(time, f) needs a number for time, found '{}'", args[0].trim())
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
            let Some(kind) = kind else {
                outer.push_str(word);
                i = end;
                continue;
            };
            let arg = if matches!(kind, Kind::At(_)) { args[1] } else { args[0] };
            let mut columns: Vec<String> = Vec::new();
            let mut column = |name: &str| -> Result<usize, String> {
                Ok(columns.iter().position(|c| c == name).unwrap_or_else(|| {
                    columns.push(name.to_string());
                    columns.len() - 1
                }))
            };
            let arg = Expr::parse_with(arg.trim(), names, &mut column).map_err(|e| format!("'{}': {e}", arg.trim()))?;
            outer.push_str(&format!("__aggregate{}", aggregates.len()));
            aggregates.push(Aggregate { kind, arg, columns, text: source[i..=close].to_string() });
            i = close + 1;
        }
        // The expression around the aggregations names nothing else.
        let count = aggregates.len();
        let mut aggregate = |n: &str| {
            n.strip_prefix("__aggregate").and_then(|k| k.parse::<usize>().ok()).filter(|&k| k < count).ok_or_else(|| {
                format!(
                    "'{n}' outside an aggregation; write max({n}), min, peak, integral, mean, rms, initial, final or at(time, {n})"
                )
            })
        };
        let outer = Expr::parse_with(&outer, names, &mut aggregate).map_err(|e| format!("'{source}': {e}"))?;
        Ok(Functional { source: source.to_string(), outer, aggregates })
    }

    /// The text it was read from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// What is wrong with evaluating it on a series whose columns are those `known` accepts
    /// (`time` aside) and whose rows span `[t0, t1]`, if anything: the first column that is not
    /// known (the message says `expected` in its place), or an `at` time outside the span.
    pub fn check(&self, known: &dyn Fn(&str) -> bool, [t0, t1]: [f64; 2], expected: &str) -> Result<(), String> {
        for a in &self.aggregates {
            if let Some(c) = a.columns.iter().find(|c| *c != TIME && !known(c)) {
                return Err(format!("no result column '{c}' (in {}); expected {expected}", a.text));
            }
            if let Kind::At(t) = a.kind {
                if !(t0..=t1).contains(&t) {
                    return Err(format!("{}: the output is from t = {t0} to {t1} s", a.text));
                }
            }
        }
        Ok(())
    }

    /// Every column it reads (`time` among them when it does), each once.
    pub fn columns(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for c in self.aggregates.iter().flat_map(|a| &a.columns) {
            if !out.contains(&c.as_str()) {
                out.push(c);
            }
        }
        out
    }

    /// The value on the series sampled at `time` (strictly increasing), whose columns `column` gives by
    /// name (each as long as `time`; `time` itself is not asked for).
    pub fn eval<'c>(&self, time: &'c [f64], column: &dyn Fn(&str) -> Option<&'c [f64]>) -> Result<f64, EvalError> {
        let values = self.aggregates.iter().map(|a| a.eval(time, column)).collect::<Result<Vec<f64>, EvalError>>()?;
        let value = self.outer.eval(&values);
        if value.is_finite() {
            return Ok(value);
        }
        let parts: Vec<String> =
            self.aggregates.iter().zip(&values).map(|(a, v)| format!("{} = {v}", a.text)).collect();
        let what = if parts.is_empty() {
            format!("'{}'", self.source)
        } else {
            format!("'{}' with {}", self.source, parts.join(", "))
        };
        Err(EvalError::NonFinite { value, what, time: None })
    }
}

impl Aggregate {
    /// Its value on the series sampled at `time`.
    fn eval<'c>(&self, time: &'c [f64], column: &dyn Fn(&str) -> Option<&'c [f64]>) -> Result<f64, EvalError> {
        let columns = self
            .columns
            .iter()
            .map(|name| {
                let c = if name == TIME { Some(time) } else { column(name) };
                c.ok_or_else(|| {
                    EvalError::Missing(format!("no result column '{name}' (the columns of results.csv, and time)"))
                })
            })
            .collect::<Result<Vec<&[f64]>, EvalError>>()?;
        let n = time.len();
        if n == 0 {
            return Err(EvalError::Missing("the run wrote no output rows".into()));
        }
        let mut row = vec![0.0; columns.len()];
        let mut f = Vec::with_capacity(n);
        for (i, &t) in time.iter().enumerate() {
            for (slot, c) in row.iter_mut().zip(&columns) {
                *slot = c[i];
            }
            let value = self.arg.eval(&row);
            if !value.is_finite() {
                let what = format!("'{}', the argument of {}", self.arg.source(), self.text);
                return Err(EvalError::NonFinite { value, what, time: Some(t) });
            }
            f.push(value);
        }
        let span = time[n - 1] - time[0];
        Ok(match self.kind {
            Kind::Max => f.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Kind::Min => f.iter().copied().fold(f64::INFINITY, f64::min),
            Kind::Peak => f.iter().map(|v| v.abs()).fold(0.0, f64::max),
            Kind::Initial => f[0],
            Kind::Final => f[n - 1],
            Kind::Integral => integral(time, f),
            Kind::Mean if n > 1 => integral(time, f) / span,
            Kind::Rms if n > 1 => (integral(time, f.iter().map(|v| v * v).collect()) / span).sqrt(),
            Kind::Mean => f[0],
            Kind::Rms => f[0].abs(),
            Kind::At(t) => {
                if !(time[0]..=time[n - 1]).contains(&t) {
                    let message =
                        format!("{}: the run's output is from t = {} to {} s", self.text, time[0], time[n - 1]);
                    return Err(EvalError::Missing(message));
                }
                if n == 1 {
                    f[0]
                } else {
                    spline(time, f).map_or(f64::NAN, |s| s.eval(t).0)
                }
            }
        })
    }
}

/// The integral of the spline through `(time, f)` (0 over the one row of a one-row series).
fn integral(time: &[f64], f: Vec<f64>) -> f64 {
    if time.len() == 1 {
        return 0.0;
    }
    spline(time, f).map_or(f64::NAN, |s| s.integral())
}

/// The not-a-knot spline through `(time, f)`, two rows or more; `None` when its slopes overflow
/// (values near a double's largest) or `time` does not increase strictly: the aggregation is then
/// NaN, and reported as not finite.
fn spline(time: &[f64], f: Vec<f64>) -> Option<Spline> {
    Spline::new(time.to_vec(), f, Method::NotAKnot).ok()
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
