//! The expression language of model files, with exact derivatives.
//!
//! Model files contain expressions such as driver time functions
//! (`"6.1506 + 2*pi*t"`, `"0.3*sin(4*t)"`) and general constraint equations
//! (`"crank.x^2 + crank.y^2 - 0.5625"`). [`Expr::parse`] compiles the source into
//! compact bytecode over numbered variable *slots* (the caller maps names to slots);
//! [`Expr::eval`] runs it generically over any [`Scalar`] without allocating. Evaluating
//! over [`Dual`] or [`HyperDual`] numbers gives exact first and second derivatives
//! (forward-mode automatic differentiation), see [`gradient`], [`directional2`] and
//! [`TimeFunction::eval`]. [`functional`] reads expressions of aggregations of sampled
//! columns (`integral(pump_power) / integral(motor_power)`): a model's summaries and a sweep's
//! outputs.
//!
//! # Parameters
//!
//! A model's parameters appear in expressions as named numbers ([`Names`]): [`Expr::eval`] runs
//! a program in which each is folded like a number written out, exactly as fast as if it had
//! been. When the caller also says which parameter a name is ([`Names::parameter`], its index
//! in the model's parameter list), the expression keeps a second, *side* program in which each
//! parameter is an input instead, never folded with other numbers: [`Expr::eval_params`] runs
//! it with the parameters' values given over any [`Scalar`], so that seeding them gives the
//! exact derivatives of the expression with respect to the parameters (with [`Tri`], seeded
//! along time and one parameter, also those of its time derivatives). Its value is the folded
//! program's to the bit. An exponent that a parameter moves (`x^n`, `n` a parameter) keeps the
//! folded program's power rule at the parameter's value and has derivatives along the
//! parameter where the base is positive (elsewhere, with the exponent seeded, the result is
//! NaN: the derivative does not exist). An expression that names no parameter has no side
//! program; [`Expr::eval_params`] then runs [`Expr::eval`]'s.
//!
//! # Language
//!
//! * Numbers: `2`, `0.5`, `.5`, `1e-3`, `6.1506`.
//! * Names: letters, digits and `_`, starting with a letter or `_`, with at most one
//!   dotted part: `t`, `crank.x`, `slider_d.vx`. The constants `pi` and `e` are
//!   built in; every other name is resolved by the caller.
//! * Operators, loosest first: binary `+ -`; `* /`; unary `-` and `+`; `^` (also written
//!   `**`, right associative and tighter than unary minus, so `2^3^2 = 512` and
//!   `-2^2 = -4`); parentheses.
//! * Functions: `sin cos tan asin acos atan atan2(y, x) sinh cosh tanh exp log`
//!   (natural) `sqrt abs min(a, b) max(a, b) sign pow(a, b) hypot(a, b)`; the motion laws
//!   `step step5 poly345 cycloidal harmonic modified_trapezoid`, each `(x, x0, h0, x1, h1)`
//!   ([`laws`]); `if(c, a, b)`, `a` where `c` is not 0, else `b`; `spline(name, x)`, the
//!   table `name` at `x` ([`spline`]; the caller names the tables, [`Names`]).
//! * Comparisons `< > <= >= == !=`, looser than every other operator, give 1 or 0 (no
//!   derivative).
//!
//! A power with a constant exponent (`x^2`, `pow(x, 3)`, `x^(1/2)`) is evaluated with
//! an integer or real power rule, so `x^2` is exact at `x = 0` (value 0, derivative 0,
//! second derivative 2). A non-constant exponent uses `a^b = exp(b ln a)`, defined for
//! `a > 0`. `abs`, `sign`, `min` and `max` are differentiated piecewise (`abs'(0) = 0`,
//! `sign' = 0`, `min`/`max` follow the selected argument).
//!
//! # Example
//!
//! ```
//! use linkwork::expr::{Expr, TimeFunction};
//!
//! let names = ["crank.x", "crank.y"];
//! let e = Expr::parse("crank.x^2 + crank.y^2 - 0.5625", &mut |name| {
//!     names
//!         .iter()
//!         .position(|n| *n == name)
//!         .ok_or_else(|| "expected crank.x or crank.y".to_string())
//! })
//! .unwrap();
//! assert_eq!(e.slots(), &[0, 1]);
//! assert_eq!(e.eval(&[0.6, 0.45]), 0.0);
//!
//! let f = TimeFunction::parse("0.3*sin(4*t)").unwrap();
//! let (v, dv, ddv) = f.eval(0.0);
//! assert_eq!((v, dv, ddv), (0.0, 1.2, 0.0));
//! ```

pub mod functional;
pub mod laws;
mod parse;
mod scalar;
pub mod spline;

#[cfg(test)]
pub(crate) mod tests;

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use parse::{Binary, Op, MAX_STACK};

pub use parse::MAX_DEPTH;
pub use scalar::{Dual, HyperDual, Nestable, Quad, Scalar, TimeTri, Tri};
pub use spline::Spline;

/// The most slots (distinct names of coordinates, velocities and the like) an expression over a
/// mechanism's state may use: a general constraint's or a state-dependent force's. Its derivative
/// passes run on stack arrays of this many numbers.
pub const MAX_SLOTS: usize = 64;

/// What a model names besides an expression's variables: values folded as numbers (its
/// parameters) and tables for `spline(name, x)`. A closure `Fn(&str) -> Option<f64>` names
/// values, no parameters and no tables.
pub trait Names {
    /// The value named `name`, if any.
    fn constant(&self, name: &str) -> Option<f64>;

    /// The index of the parameter named `name` (in the model's parameter list, file order), if
    /// the value [`Names::constant`] gives for `name` is a parameter's: an expression then reads
    /// it from the parameters [`Expr::eval_params`] is given. Asked only of names that
    /// [`Names::constant`] gives a value.
    fn parameter(&self, _name: &str) -> Option<usize> {
        None
    }

    /// The table named `name`, if any.
    fn table(&self, _name: &str) -> Option<Arc<Spline>> {
        None
    }

    /// Whether `name` is a variable of the caller's even where a built-in constant has that
    /// name: a parameter called `e`, read as a variable to differentiate with respect to it.
    fn shadows(&self, _name: &str) -> bool {
        false
    }
}

impl<F: Fn(&str) -> Option<f64>> Names for F {
    fn constant(&self, name: &str) -> Option<f64> {
        self(name)
    }
}

/// Names nothing.
fn nothing(_: &str) -> Option<f64> {
    None
}

/// A parse error: what is wrong and the byte offset in the source where it was found.
///
/// Displays as `"<message> at column <offset + 1>"`, e.g.
/// `unknown name 'rokcer.x' (expected <body>.x, <body>.y, <body>.phi or t) at column 3`.
#[derive(Debug, Clone, PartialEq)]
pub struct ExprError {
    /// Description of the problem (for unknown names it includes the resolver's hint).
    pub message: String,
    /// Byte offset in the source where the problem was found.
    pub offset: usize,
}

impl ExprError {
    /// An error with the given message at byte `offset`.
    pub fn new(message: impl Into<String>, offset: usize) -> Self {
        ExprError { message: message.into(), offset }
    }

    /// 1-based column of the error (`offset + 1`).
    pub fn column(&self) -> usize {
        self.offset + 1
    }

    /// The source line containing the error with a caret under the offending
    /// character, for terminal output:
    ///
    /// ```text
    /// 2*rokcer.x
    ///   ^
    /// ```
    pub fn snippet(&self, src: &str) -> String {
        let mut at = self.offset.min(src.len());
        while !src.is_char_boundary(at) {
            at -= 1;
        }
        let line_start = src[..at].rfind('\n').map_or(0, |i| i + 1);
        let line_end = src[at..].find('\n').map_or(src.len(), |i| at + i);
        let pad = src[line_start..at].chars().count();
        format!("{}\n{}^", &src[line_start..line_end], " ".repeat(pad))
    }
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at column {}", self.message, self.column())
    }
}

impl std::error::Error for ExprError {}

/// A compiled expression over variable slots `0..k` numbered by the caller's resolver.
///
/// Internally a postfix bytecode program with constant subexpressions folded;
/// evaluation uses a fixed-size stack array and never allocates.
#[derive(Debug, Clone)]
pub struct Expr {
    source: String,
    code: Vec<Op>,
    slots: Vec<usize>,
    max_stack: usize,
    /// The tables of `spline(name, x)`, shared with the model.
    tables: Vec<Arc<Spline>>,
    /// The program with the parameters as inputs and the parameters it reads (see the module's
    /// Parameters), when the source names any.
    side: Option<Box<parse::Side>>,
}

impl Expr {
    /// Parses `src`. Every identifier that is not a built-in constant (`pi`, `e`) or a
    /// function name followed by `(` is passed to `resolve`, which returns `Ok(slot)`
    /// or `Err(hint)`; the hint (e.g. `"expected <body>.x, <body>.y, <body>.phi or t"`)
    /// is included in the "unknown name" error. `resolve` may be called several times
    /// for the same name.
    ///
    /// # Errors
    ///
    /// An [`ExprError`] with the byte offset of the problem for: an unexpected
    /// character, a malformed or out-of-range number, unbalanced parentheses, a missing
    /// operand, trailing input, an unknown function, a wrong number of function
    /// arguments, an unknown name, an empty expression, or nesting deeper than
    /// [`MAX_DEPTH`].
    pub fn parse(src: &str, resolve: &mut dyn FnMut(&str) -> Result<usize, String>) -> Result<Expr, ExprError> {
        Expr::parse_with(src, &nothing, resolve)
    }

    /// As [`Expr::parse`], with named values and tables: a name for which `names` gives a value
    /// (a model's parameter) is that number, folded as if written out; it hides a variable of
    /// the same name, and the built-in `pi` and `e` hide it. A value that `names` says is a
    /// parameter ([`Names::parameter`]) is also kept as an input of [`Expr::eval_params`].
    /// `spline(name, x)` is the table `names` gives for `name` at `x`, with its exact
    /// derivatives ([`Spline::eval`]). `resolve` is called again for each name when the source
    /// names a parameter (the side program is compiled separately).
    ///
    /// # Errors
    ///
    /// As [`Expr::parse`].
    pub fn parse_with(
        src: &str,
        names: &dyn Names,
        resolve: &mut dyn FnMut(&str) -> Result<usize, String>,
    ) -> Result<Expr, ExprError> {
        let c = parse::compile(src, names, resolve)?;
        Ok(Expr {
            source: src.to_string(),
            code: c.program.code,
            slots: c.slots,
            max_stack: c.program.max_stack,
            tables: c.tables,
            side: c.side,
        })
    }

    /// The parameters the expression names (their indices, [`Names::parameter`]), sorted, each
    /// once: those [`Expr::eval_params`] reads.
    pub fn parameters(&self) -> &[usize] {
        self.side.as_ref().map_or(&[], |s| &s.parameters)
    }

    /// The source text the expression was parsed from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Distinct slots used, sorted ascending.
    pub fn slots(&self) -> &[usize] {
        &self.slots
    }

    /// True when the expression uses no slots (a constant).
    pub fn is_constant(&self) -> bool {
        self.slots.is_empty()
    }

    /// The value of a constant expression (constants are folded at parse time), or
    /// `None` if the expression uses any slot.
    pub fn constant_value(&self) -> Option<f64> {
        match self.code.as_slice() {
            [Op::Const(c)] => Some(*c),
            _ => None,
        }
    }

    /// Evaluates the expression with slot values `vars` (indexed by slot). Does not
    /// allocate. Only the entries at [`slots`](Expr::slots) are read.
    ///
    /// # Panics
    ///
    /// If `vars.len()` is not greater than the largest slot used.
    pub fn eval<S: Scalar>(&self, vars: &[S]) -> S {
        self.exec(&self.code, self.max_stack, vars, &[])
    }

    /// Evaluates the expression with slot values `vars` (as [`Expr::eval`]) and the model's
    /// parameters `params` (indexed as [`Names::parameter`] numbers them): each parameter the
    /// source names is read from `params` instead of folded, so that derivative parts seeded on
    /// the parameters carry through exactly. With `params` at the values the expression was
    /// parsed with, the value is [`Expr::eval`]'s to the bit. Does not allocate.
    ///
    /// # Panics
    ///
    /// If `vars` is not longer than the largest slot used, or `params` not longer than the
    /// largest of [`Expr::parameters`].
    pub fn eval_params<S: Scalar>(&self, vars: &[S], params: &[S]) -> S {
        match &self.side {
            Some(side) => self.exec(&side.program.code, side.program.max_stack, vars, params),
            None => self.eval(vars),
        }
    }

    /// Runs `code`, which needs a stack of `max_stack`, on the smallest stack that fits, so
    /// small expressions do not pay for initialising a large array.
    #[inline]
    fn exec<S: Scalar>(&self, code: &[Op], max_stack: usize, vars: &[S], params: &[S]) -> S {
        match max_stack {
            0..=8 => self.run::<S, 8>(code, vars, params),
            9..=32 => self.run::<S, 32>(code, vars, params),
            33..=128 => self.run::<S, 128>(code, vars, params),
            _ => self.run::<S, MAX_STACK>(code, vars, params),
        }
    }

    /// The bytecode interpreter; `N` is at least the program's stack depth (checked at compile
    /// time of the expression), so the stack indexing cannot go out of bounds.
    fn run<S: Scalar, const N: usize>(&self, code: &[Op], vars: &[S], params: &[S]) -> S {
        let mut stack = [S::constant(0.0); N];
        let mut sp = 0usize;
        for op in code {
            match *op {
                Op::Const(c) => {
                    stack[sp] = S::constant(c);
                    sp += 1;
                }
                Op::Var(slot) => {
                    stack[sp] = vars[slot];
                    sp += 1;
                }
                Op::Param(i) => {
                    stack[sp] = params[i];
                    sp += 1;
                }
                Op::Unary(u) => stack[sp - 1] = u.apply(stack[sp - 1]),
                Op::Binary(b) => {
                    sp -= 1;
                    stack[sp - 1] = Binary::apply(b, stack[sp - 1], stack[sp]);
                }
                Op::Nary(n) => {
                    let arity = n.arity();
                    sp -= arity - 1;
                    stack[sp - 1] = n.apply(&stack[sp - 1..sp - 1 + arity]);
                }
                Op::Table(i) => stack[sp - 1] = self.tables[i].lifted(stack[sp - 1]),
            }
        }
        stack[0]
    }
}

impl fmt::Display for Expr {
    /// Writes the source text.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source)
    }
}

/// Hint given for any name other than `t` in a driver function.
const TIME_HINT: &str = "only t (time) may appear in a driver function";

/// A function of time only, for drivers: an [`Expr`] whose single variable `t` is
/// slot 0.
#[derive(Debug, Clone)]
pub struct TimeFunction {
    expr: Expr,
}

impl TimeFunction {
    /// Parses `src`, where `t` is the only name allowed (besides `pi` and `e`).
    ///
    /// # Errors
    ///
    /// As [`Expr::parse`]; any other name gives "unknown name '…' (only t (time) may
    /// appear in a driver function)".
    pub fn parse(src: &str) -> Result<TimeFunction, ExprError> {
        TimeFunction::parse_with(src, &nothing)
    }

    /// As [`TimeFunction::parse`], with named values and tables (a model's parameters and
    /// tables) as in [`Expr::parse_with`].
    ///
    /// # Errors
    ///
    /// As [`TimeFunction::parse`].
    pub fn parse_with(src: &str, names: &dyn Names) -> Result<TimeFunction, ExprError> {
        let expr = Expr::parse_with(src, names, &mut |name| {
            if name == "t" {
                Ok(0)
            } else {
                Err(TIME_HINT.to_string())
            }
        })?;
        Ok(TimeFunction { expr })
    }

    /// `(f(t), f'(t), f''(t))` exactly, by one [`HyperDual`] evaluation seeded with
    /// `(t, 1, 1, 0)`.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let r = self.expr.eval(&[HyperDual::variable(t)]);
        (r.v, r.e1, r.e12)
    }

    /// `f(t)` alone (plain `f64` evaluation).
    pub fn value(&self, t: f64) -> f64 {
        self.expr.eval(&[t])
    }

    /// `f` at time `t` with the model's parameters `params` read as inputs
    /// ([`Expr::eval_params`]): seeded with [`Tri::trajectory`] (time along `ε1` and `ε2`, the
    /// parameters along `ε3`), the result holds `f`, `f'`, `f''` and their parameter
    /// derivatives.
    ///
    /// # Panics
    ///
    /// If `params` is not longer than the largest of the expression's
    /// [`parameters`](Expr::parameters).
    pub fn eval_params<S: Scalar>(&self, t: S, params: &[S]) -> S {
        self.expr.eval_params(&[t], params)
    }

    /// The underlying expression (`t` is slot 0).
    pub fn expr(&self) -> &Expr {
        &self.expr
    }

    /// The source text.
    pub fn source(&self) -> &str {
        self.expr.source()
    }

    /// True when the function does not depend on `t`.
    pub fn is_constant(&self) -> bool {
        self.expr.is_constant()
    }
}

impl FromStr for TimeFunction {
    type Err = ExprError;

    /// Same as [`TimeFunction::parse`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        TimeFunction::parse(s)
    }
}

impl fmt::Display for TimeFunction {
    /// Writes the source text.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.expr.source())
    }
}

/// Gradient of `e` at `x` (indexed by slot), written into `grad`: one [`Dual`] pass per
/// slot in [`e.slots()`](Expr::slots). Every other entry of `grad` is set to 0.
///
/// `work` is caller-provided scratch so that nothing allocates; only its entries at
/// the slots of `e` are written.
///
/// # Panics
///
/// If `x`, `grad` or `work` is not longer than the largest slot of `e`.
pub fn gradient(e: &Expr, x: &[f64], grad: &mut [f64], work: &mut [Dual]) {
    grad.fill(0.0);
    for &s in e.slots() {
        work[s] = Dual::new(x[s], 0.0);
    }
    for &s in e.slots() {
        work[s].d = 1.0;
        grad[s] = e.eval(work).d;
        work[s].d = 0.0;
    }
}

/// Sparse gradient: `out[j]` = ∂e/∂x at slot `e.slots()[j]`, for `j < e.slots().len()`
/// (one [`Dual`] pass per slot). Returns the value of `e` at `x`.
///
/// Same as [`gradient`] but touches only the slots of `e`, which suits assembling a
/// sparse Jacobian row.
///
/// # Panics
///
/// If `out` is shorter than `e.slots()`, or `x` or `work` is not longer than the
/// largest slot of `e`.
pub fn gradient_sparse(e: &Expr, x: &[f64], out: &mut [f64], work: &mut [Dual]) -> f64 {
    let slots = e.slots();
    let out = &mut out[..slots.len()];
    for &s in slots {
        work[s] = Dual::new(x[s], 0.0);
    }
    let mut value = None;
    for (&s, g) in slots.iter().zip(out.iter_mut()) {
        work[s].d = 1.0;
        let r = e.eval(work);
        *g = r.d;
        value = Some(r.v);
        work[s].d = 0.0;
    }
    value.unwrap_or_else(|| e.eval::<Dual>(work).v)
}

/// `(value, ∇e·dir, dirᵀ H dir)` of `e` at `x` in one [`HyperDual`] pass (`H` is the
/// Hessian of `e`); `x` and `dir` are indexed by slot.
///
/// `work` is caller-provided scratch so that nothing allocates; only its entries at
/// the slots of `e` are written.
///
/// # Panics
///
/// If `x`, `dir` or `work` is not longer than the largest slot of `e`.
pub fn directional2(e: &Expr, x: &[f64], dir: &[f64], work: &mut [HyperDual]) -> (f64, f64, f64) {
    for &s in e.slots() {
        work[s] = HyperDual::seed(x[s], dir[s], dir[s]);
    }
    let r = e.eval(work);
    (r.v, r.e1, r.e12)
}
