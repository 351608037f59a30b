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
//!
//! # Derivatives
//!
//! [`Functional::derivative`] differentiates the value along one direction (a parameter of the
//! model, for design sensitivities), given the derivative of every column it reads at every
//! row and of every named value it reads. The rows' times are fixed: a derivative is taken on
//! the same output grid (`time` has derivative 0). Each aggregation is differentiated as its
//! value is computed, by evaluating the same code over [`Dual`] numbers:
//!
//! - `max`, `min`, `peak`: the derivative of the argument (of its absolute value, for `peak`) at
//!   the row the value is taken from, the first of the rows that reach it. Where two rows tie,
//!   or where the largest row changes as the parameter moves, the value has a corner and this
//!   is the derivative from one side of it; between sample rows the derivative is that of the
//!   sampled maximum, not of the maximum of the continuous motion.
//! - `integral`, `mean`, `rms`: the spline's integral is linear in the samples, so its derivative
//!   is the integral of the spline through the derivatives' samples (exactly, not to `O(h^4)`:
//!   the derivative of the number computed, not of the continuous integral).
//! - `at(time, f)`: the spline through the derivatives' samples at `time`, plus the spline's
//!   slope times the derivative of `time` when it is written with named values (`at(T/2, x)`).
//! - `initial`, `final`: the derivative at the first and last row.
//!
//! The named values (a model's parameters) are folded into the expressions for the value; the
//! derivative reads each expression again with them as variables, so that `max(slider.x) - r`
//! has its `-1` with respect to `r`.

use std::fmt;

use super::spline::Method;
use super::{Dual, Expr, Names, Scalar, Spline};
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
    /// The argument with the named values as variables, for derivatives.
    open: Open,
    /// The time of an `at`, with the named values as variables.
    at: Option<Open>,
}

/// An expression of aggregations of columns, parsed once.
#[derive(Debug, Clone)]
pub struct Functional {
    source: String,
    /// The expression with aggregation `k` as variable slot `k`.
    outer: Expr,
    aggregates: Vec<Aggregate>,
    /// The expression around the aggregations with the named values as variables.
    open: Open,
}

/// What a slot of an [`Open`] expression reads.
#[derive(Debug, Clone, PartialEq)]
enum Slot {
    /// A column, or `time`.
    Column(String),
    /// A named value ([`Names::constant`]), with the value it had when read.
    Value(String, f64),
    /// The value of aggregation `k` (in the expression around them).
    Aggregate(usize),
}

/// An expression read with the named values as variables rather than folded: what its
/// derivative with respect to them needs. Its slot `k` reads `slots[k]`.
#[derive(Debug, Clone)]
struct Open {
    expr: Expr,
    slots: Vec<Slot>,
}

impl Open {
    /// Read `source` with `names`' values as [`Slot::Value`]s, its tables as tables, and every
    /// other name as `other` says (a column, an aggregation, or an error).
    fn parse(
        source: &str,
        names: &dyn Names,
        other: &mut dyn FnMut(&str) -> Result<Slot, String>,
    ) -> Result<Open, String> {
        let mut slots: Vec<Slot> = Vec::new();
        let mut resolve = |name: &str| -> Result<usize, String> {
            let slot = match names.constant(name) {
                Some(value) => Slot::Value(name.to_string(), value),
                None => other(name)?,
            };
            Ok(slots.iter().position(|s| *s == slot).unwrap_or_else(|| {
                slots.push(slot);
                slots.len() - 1
            }))
        };
        let expr = Expr::parse_with(source, &Tables(names), &mut resolve).map_err(|e| format!("'{source}': {e}"))?;
        Ok(Open { expr, slots })
    }

    /// Its value over [`Dual`] numbers, each slot's from `slot`.
    fn eval(&self, slot: &dyn Fn(&Slot) -> Dual) -> Dual {
        let vars: Vec<Dual> = self.slots.iter().map(slot).collect();
        self.expr.eval(&vars)
    }
}

/// The tables of a model's names, without its values: what an [`Open`] expression is read with.
struct Tables<'a>(&'a dyn Names);

impl Names for Tables<'_> {
    fn constant(&self, _name: &str) -> Option<f64> {
        None
    }

    fn table(&self, name: &str) -> Option<std::sync::Arc<Spline>> {
        self.0.table(name)
    }
}

/// The numbers the aggregations are computed over: `f64` for a value, [`Dual`] for a value and
/// its derivative along one direction.
trait Sample: Scalar {
    /// The derivative part (0 for a plain number).
    fn derivative(self) -> f64;
    /// The number of `value` and `derivative` (a plain number drops the derivative).
    fn join(value: f64, derivative: f64) -> Self;
}

impl Sample for f64 {
    fn derivative(self) -> f64 {
        0.0
    }

    fn join(value: f64, _derivative: f64) -> f64 {
        value
    }
}

impl Sample for Dual {
    fn derivative(self) -> f64 {
        self.d
    }

    fn join(value: f64, derivative: f64) -> Dual {
        Dual::new(value, derivative)
    }
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
            let (at, arg) = match kind {
                Kind::At(_) => {
                    let mut refuse = |n: &str| Err(format!("'{n}': the time of at() is a number"));
                    (Some(Open::parse(args[0].trim(), names, &mut refuse)?), args[1])
                }
                _ => (None, args[0]),
            };
            let mut columns: Vec<String> = Vec::new();
            let mut column = |name: &str| -> Result<usize, String> {
                Ok(columns.iter().position(|c| c == name).unwrap_or_else(|| {
                    columns.push(name.to_string());
                    columns.len() - 1
                }))
            };
            let arg = arg.trim();
            let open = Open::parse(arg, names, &mut |n| Ok(Slot::Column(n.to_string())))?;
            let arg = Expr::parse_with(arg, names, &mut column).map_err(|e| format!("'{arg}': {e}"))?;
            outer.push_str(&format!("__aggregate{}", aggregates.len()));
            aggregates.push(Aggregate { kind, arg, columns, text: source[i..=close].to_string(), open, at });
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
        let folded = Expr::parse_with(&outer, names, &mut aggregate).map_err(|e| format!("'{source}': {e}"))?;
        let open = Open::parse(&outer, names, &mut |n| aggregate(n).map(Slot::Aggregate))
            .map_err(|_| format!("'{source}': cannot be read with its named values as variables"))?;
        Ok(Functional { source: source.to_string(), outer: folded, aggregates, open })
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

    /// The derivative of the value on the series sampled at `time` along one direction (a
    /// parameter): `column` gives each column by name as in [`Functional::eval`], `derivative`
    /// each column's derivative at every row (`time`'s is 0: the rows stay where they are), and
    /// `value` each named value's derivative (a model's parameter's, by name). The rules at a
    /// largest row and the rest are in the module's documentation. The derivative may not be a
    /// finite number where the value has none (`rms` of a column that is 0 throughout).
    ///
    /// # Errors
    ///
    /// As [`Functional::eval`], and [`EvalError::Missing`] for a column without derivatives.
    pub fn derivative<'c>(
        &self,
        time: &'c [f64],
        column: &dyn Fn(&str) -> Option<&'c [f64]>,
        derivative: &dyn Fn(&str) -> Option<&'c [f64]>,
        value: &dyn Fn(&str) -> f64,
    ) -> Result<f64, EvalError> {
        let aggregates = self
            .aggregates
            .iter()
            .map(|a| a.derivative(time, column, derivative, value))
            .collect::<Result<Vec<Dual>, EvalError>>()?;
        let outer = self.open.eval(&|slot| match slot {
            Slot::Aggregate(k) => aggregates[*k],
            other => named(other, value),
        });
        Ok(outer.d)
    }
}

/// A named value's number along the direction: its value and derivative. Only named values
/// reach here (the time of an `at` reads nothing else, and the expression around the
/// aggregations reads them and the aggregations); anything else is NaN.
fn named(slot: &Slot, derivative: &dyn Fn(&str) -> f64) -> Dual {
    match slot {
        Slot::Value(name, value) => Dual::new(*value, derivative(name)),
        _ => Dual::constant(f64::NAN),
    }
}

/// The column `name` of a series whose columns `column` gives (`time` is the sample times).
fn read<'c>(name: &str, time: &'c [f64], column: &dyn Fn(&str) -> Option<&'c [f64]>) -> Result<&'c [f64], EvalError> {
    let c = if name == TIME { Some(time) } else { column(name) };
    c.ok_or_else(|| EvalError::Missing(format!("no result column '{name}' (the columns of results.csv, and time)")))
}

impl Aggregate {
    /// Its value on the series sampled at `time`.
    fn eval<'c>(&self, time: &'c [f64], column: &dyn Fn(&str) -> Option<&'c [f64]>) -> Result<f64, EvalError> {
        let columns = self.columns.iter().map(|name| read(name, time, column)).collect::<Result<Vec<_>, _>>()?;
        let mut row = vec![0.0; columns.len()];
        let f = self.rows(time, |i| {
            for (slot, c) in row.iter_mut().zip(&columns) {
                *slot = c[i];
            }
            self.arg.eval(&row)
        })?;
        self.reduce(time, &f, 0.0)
    }

    /// Its value and derivative on the series sampled at `time` ([`Functional::derivative`]).
    fn derivative<'c>(
        &self,
        time: &'c [f64],
        column: &dyn Fn(&str) -> Option<&'c [f64]>,
        derivative: &dyn Fn(&str) -> Option<&'c [f64]>,
        value: &dyn Fn(&str) -> f64,
    ) -> Result<Dual, EvalError> {
        /// Where a slot's number at a row comes from.
        enum Source<'c> {
            /// A column and its derivatives (`time`'s are 0).
            Series(&'c [f64], Option<&'c [f64]>),
            /// A named value, the same at every row.
            Fixed(Dual),
        }
        let n = time.len();
        let sources = self
            .open
            .slots
            .iter()
            .map(|slot| match slot {
                Slot::Column(name) if name == TIME => Ok(Source::Series(time, None)),
                Slot::Column(name) => {
                    let values = read(name, time, column)?;
                    let d = derivative(name).filter(|d| d.len() == n).ok_or_else(|| {
                        EvalError::Missing(format!("no derivatives of the column '{name}' at the {n} rows"))
                    })?;
                    Ok(Source::Series(values, Some(d)))
                }
                other => Ok(Source::Fixed(named(other, value))),
            })
            .collect::<Result<Vec<Source<'_>>, EvalError>>()?;
        let mut row = vec![Dual::default(); sources.len()];
        let f = self.rows(time, |i| {
            for (slot, source) in row.iter_mut().zip(&sources) {
                *slot = match source {
                    Source::Series(v, d) => Dual::new(v[i], d.map_or(0.0, |d| d[i])),
                    Source::Fixed(x) => *x,
                };
            }
            self.open.expr.eval(&row)
        })?;
        let dt = self.at.as_ref().map_or(0.0, |at| at.eval(&|slot| named(slot, value)).d);
        self.reduce(time, &f, dt)
    }

    /// The argument at every row of `time`, `at_row(i)` at row `i`; an error at the first
    /// that is not a finite number.
    fn rows<S: Scalar>(&self, time: &[f64], mut at_row: impl FnMut(usize) -> S) -> Result<Vec<S>, EvalError> {
        if time.is_empty() {
            return Err(EvalError::Missing("the run wrote no output rows".into()));
        }
        let mut f = Vec::with_capacity(time.len());
        for (i, &t) in time.iter().enumerate() {
            let value = at_row(i);
            if !value.value().is_finite() {
                let what = format!("'{}', the argument of {}", self.arg.source(), self.text);
                return Err(EvalError::NonFinite { value: value.value(), what, time: Some(t) });
            }
            f.push(value);
        }
        Ok(f)
    }

    /// The aggregation of the argument's rows `f` (at least one) sampled at `time`, over plain
    /// numbers or [`Dual`] ones; `dt`: the derivative of an `at`'s time.
    fn reduce<S: Sample>(&self, time: &[f64], f: &[S], dt: f64) -> Result<S, EvalError> {
        let n = time.len();
        let span = time[n - 1] - time[0];
        let values = || f.iter().map(|v| v.value());
        Ok(match self.kind {
            Kind::Max => reached(f, values().fold(f64::NEG_INFINITY, f64::max)),
            Kind::Min => reached(f, values().fold(f64::INFINITY, f64::min)),
            Kind::Peak => {
                let magnitudes: Vec<S> = f.iter().map(|v| v.abs()).collect();
                reached(&magnitudes, values().map(f64::abs).fold(0.0, f64::max))
            }
            Kind::Initial => f[0],
            Kind::Final => f[n - 1],
            Kind::Integral => sampled_integral(time, f),
            Kind::Mean if n > 1 => sampled_integral(time, f) / S::constant(span),
            Kind::Rms if n > 1 => {
                let squares: Vec<S> = f.iter().map(|&v| v * v).collect();
                (sampled_integral(time, &squares) / S::constant(span)).sqrt()
            }
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
                    interpolated(time, f, t, dt)
                }
            }
        })
    }
}

/// The first of `f` whose value is `best` (one of them: a largest or smallest value), with that
/// value: the derivative of a `max`, `min` or `peak` is the argument's at that row.
fn reached<S: Sample>(f: &[S], best: f64) -> S {
    // `lift` keeps the fold's own `best` (its sign of a zero) and the row's derivative.
    f.iter().find(|v| v.value() == best).map_or(S::constant(best), |v| v.lift(best, 1.0, 0.0, 0.0))
}

/// The integral of the spline through `(time, f)`: of the values, and of the derivatives (the
/// spline's integral is linear in the samples).
fn sampled_integral<S: Sample>(time: &[f64], f: &[S]) -> S {
    let value = integral(time, f.iter().map(|v| v.value()).collect());
    if S::ORDER == 0 {
        return S::constant(value);
    }
    S::join(value, integral(time, f.iter().map(|v| v.derivative()).collect()))
}

/// The spline through `(time, f)` (two rows or more) at `t`, whose derivative is `dt`: the
/// spline through the derivatives there, plus its slope times `dt`.
fn interpolated<S: Sample>(time: &[f64], f: &[S], t: f64, dt: f64) -> S {
    let Some((value, slope, _)) = spline(time, f.iter().map(|v| v.value()).collect()).map(|s| s.eval(t)) else {
        return S::constant(f64::NAN);
    };
    if S::ORDER == 0 {
        return S::constant(value);
    }
    let moved = spline(time, f.iter().map(|v| v.derivative()).collect()).map_or(f64::NAN, |s| s.eval(t).0);
    S::join(value, moved + if dt == 0.0 { 0.0 } else { slope * dt })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An uneven grid of `n` rows over `[0, 2]` (a smooth stretching of an even one), so that
    /// nothing depends on equal steps.
    fn grid(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let u = i as f64 / (n - 1) as f64;
                2.0 * (u + 0.1 * (std::f64::consts::PI * u).sin() / std::f64::consts::PI)
            })
            .collect()
    }

    /// The named values at `p`: `p` itself and `T = 3 p`, with their derivatives along `p`.
    fn names(p: f64) -> impl Fn(&str) -> Option<f64> {
        move |n: &str| match n {
            "p" => Some(p),
            "T" => Some(3.0 * p),
            _ => None,
        }
    }

    fn named_derivative(n: &str) -> f64 {
        match n {
            "p" => 1.0,
            "T" => 3.0,
            _ => f64::NAN,
        }
    }

    /// The columns `a = sin(p t) + p t^2` and `b = exp(-p t)` at `p` and their derivatives along
    /// `p`, sampled at `time`: `[a, b, da, db]`.
    fn columns(time: &[f64], p: f64) -> [Vec<f64>; 4] {
        let a = time.iter().map(|t| (p * t).sin() + p * t * t).collect();
        let b = time.iter().map(|t| (-p * t).exp()).collect();
        let da = time.iter().map(|t| t * (p * t).cos() + t * t).collect();
        let db = time.iter().map(|t| -t * (-p * t).exp()).collect();
        [a, b, da, db]
    }

    fn value(source: &str, time: &[f64], p: f64) -> f64 {
        let f = Functional::parse(source, &names(p)).unwrap();
        let [a, b, _, _] = columns(time, p);
        f.eval(time, &|n| match n {
            "a" => Some(&a),
            "b" => Some(&b),
            _ => None,
        })
        .unwrap()
    }

    fn derivative(source: &str, time: &[f64], p: f64) -> f64 {
        let f = Functional::parse(source, &names(p)).unwrap();
        let [a, b, da, db] = columns(time, p);
        let pick = |n: &str, x: usize| match n {
            "a" => Some([&a, &da][x].as_slice()),
            "b" => Some([&b, &db][x].as_slice()),
            _ => None,
        };
        f.derivative(time, &|n| pick(n, 0), &|n| pick(n, 1), &named_derivative).unwrap()
    }

    /// Every aggregation, and arithmetic of them with named values, against central differences
    /// of the functional's value on the same grid (the columns and the named values recomputed
    /// at `p -+ h`, the expression read again with them). Step `h = 1e-5`: the differences' error
    /// is `h^2 f''' / 6 ~ 1e-10` (third derivatives of order 1-10 here) plus round-off
    /// `1e-16 * |f| / h ~ 1e-10`; the tolerance 1e-8 (relative, or absolute below 1) stands above
    /// both. `max`, `min` and `peak` keep their row within `p -+ h` on this grid.
    #[test]
    fn derivatives_match_central_differences() {
        let time = grid(41);
        let p = 0.7;
        let h = 1e-5;
        for source in [
            "max(a)",
            "min(a * b)",
            "peak(a - 3)",
            "integral(a * b)",
            "mean(b^2)",
            "rms(a)",
            "initial(a)",
            "final(b)",
            "at(0.55, a)",
            "at(T / 3, a * b)",
            "integral(a) / mean(b) + p * max(b)",
            "max(abs(a) * p) - p^2",
            "integral(time * a)",
        ] {
            let exact = derivative(source, &time, p);
            let differences = (value(source, &time, p + h) - value(source, &time, p - h)) / (2.0 * h);
            let error = (exact - differences).abs() / exact.abs().max(1.0);
            assert!(error < 1e-8, "{source}: {exact} against differences {differences} ({error:.1e})");
        }
    }

    /// At a corner the derivative is the argument's at the first row that reaches the largest
    /// (smallest, largest absolute) value: rows 1 and 3 tie, row 1's derivative is taken; the
    /// value is the fold's, unchanged.
    #[test]
    fn a_tie_takes_the_first_row_reaching_the_extreme() {
        let time = [0.0, 1.0, 2.0, 3.0, 4.0];
        let f = [0.0, 1.0, 0.5, 1.0, -1.0];
        let g = [0.0, -1.0, 0.5, 1.0, 0.0];
        let df = [9.0, 2.0, 9.0, 5.0, 7.0];
        let check = |source: &str, column: &[f64], expected: f64| {
            let functional = Functional::parse(source, &|_: &str| None).unwrap();
            let d = functional
                .derivative(&time, &|n| (n == "f").then_some(column), &|n| (n == "f").then_some(&df[..]), &|_| 0.0)
                .unwrap();
            assert_eq!(d, expected, "{source} of {column:?}");
        };
        check("max(f)", &f, 2.0);
        check("min(f)", &g, 2.0);
        check("peak(f)", &f, 2.0);
        // |-1| at row 1 reaches the peak before 1 at row 3: the derivative of |f| there, -2.
        check("peak(f)", &g, -2.0);
        check("min(f)", &f, 7.0);
    }

    /// A column with a kink at its largest row (`p (1 - |t - 1|)` at a row `t = 1`): the
    /// derivative is the argument's there, `1 - 0 = 1`, and the one-sided differences of the
    /// value agree with it from both sides (the kink is in time, not in `p`).
    #[test]
    fn a_kinked_column_takes_the_derivative_at_its_largest_row() {
        let time = grid(21);
        let column = |p: f64| -> Vec<f64> { time.iter().map(|t| p * (1.0 - (t - 1.0).abs())).collect() };
        let peak = time.iter().map(|t| 1.0 - (t - 1.0).abs()).fold(f64::NEG_INFINITY, f64::max);
        let dp: Vec<f64> = time.iter().map(|t| 1.0 - (t - 1.0).abs()).collect();
        let f = Functional::parse("max(c)", &|_: &str| None).unwrap();
        let at = |p: f64| {
            let c = column(p);
            f.eval(&time, &|n| (n == "c").then_some(c.as_slice())).unwrap()
        };
        let c = column(2.0);
        let d =
            f.derivative(&time, &|n| (n == "c").then_some(c.as_slice()), &|n| (n == "c").then_some(&dp[..]), &|_| 0.0);
        assert_eq!(d, Ok(peak));
        // Linear in p: the differences are exact to round-off of values of order 2.
        let h = 1e-3;
        assert!(((at(2.0 + h) - at(2.0)) / h - peak).abs() < 1e-12);
        assert!(((at(2.0) - at(2.0 - h)) / h - peak).abs() < 1e-12);
    }

    /// A column without derivatives is missing, named; `time` needs none.
    #[test]
    fn a_column_without_derivatives_is_missing() {
        let time = [0.0, 1.0];
        let x = [1.0, 2.0];
        let f = Functional::parse("integral(x * time)", &|_: &str| None).unwrap();
        let missing = f.derivative(&time, &|n| (n == "x").then_some(&x[..]), &|_| None, &|_| 0.0);
        assert!(matches!(&missing, Err(EvalError::Missing(m)) if m.contains("'x'")), "{missing:?}");
        let d = f.derivative(&time, &|n| (n == "x").then_some(&x[..]), &|_| Some(&[1.0, 1.0][..]), &|_| 0.0);
        // integral of t over [0, 1] (two rows: the trapezoid), exactly.
        assert_eq!(d, Ok(0.5));
    }
}
