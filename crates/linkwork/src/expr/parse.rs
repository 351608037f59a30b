//! Lexer, parser and bytecode compiler for expressions.
//!
//! The parser emits postfix bytecode ([`Op`]) directly, folding constant
//! subexpressions as it goes (a subexpression without variables is evaluated once, in
//! `f64`, and replaced by its value; constants have zero derivatives, so folding is
//! exact for every [`Scalar`] type). A power whose exponent folds to a constant is
//! compiled to [`Unary::Powi`] (integer exponent) or [`Unary::Powf`], never to
//! `exp(b ln a)`.
//!
//! A source that names a parameter ([`Names::parameter`]) is compiled twice: once with the
//! parameter's value folded like a number (the program [`super::Expr::eval`] runs), and once
//! more, in the *side* mode, with each parameter an input ([`Op::Param`]) that nothing folds
//! (the program [`super::Expr::eval_params`] runs). Both run the same floating-point operations
//! on the values, folded early or not, so the side program's value is the folded one's to the
//! bit. A power whose exponent has no variables but a parameter compiles, in the side mode, to
//! [`Binary::PowParam`]: the folded program's power rule at the exponent's value, times the
//! exponent's motion.
//!
//! Grammar (lowest precedence first), parsed by operator precedence with an explicit
//! stack rather than by recursion:
//!
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary (('^' | '**') unary)?        right associative
//! primary := number | name | name '(' args ')' | '(' expr ')'
//! ```
//!
//! Nesting (parentheses, function calls, unary minus signs, chained powers) is limited
//! to [`MAX_DEPTH`] levels, which bounds the parser's memory and the evaluation stack.
//! Nothing recurses, so hostile input cannot overflow the call stack.

use super::laws::Law;
use super::scalar::Scalar;
use super::spline::Spline;
use super::{ExprError, Names};
use std::sync::Arc;

/// Maximum nesting depth accepted by the parser.
pub const MAX_DEPTH: usize = 200;

/// Largest evaluation stack an expression may need. With [`MAX_DEPTH`] = 200 at most
/// about 3 values are pending per nesting level, so this is never reached in practice;
/// the compiler still checks it.
pub(crate) const MAX_STACK: usize = 1024;

/// Integer exponents up to this magnitude compile to [`Unary::Powi`].
const MAX_POWI: f64 = 1024.0;

/// The power rule of a constant exponent `c`: none for `c = 1` (`a^1 = a`), [`Unary::Powi`] for
/// an integer up to [`MAX_POWI`], else [`Unary::Powf`].
fn constant_power(c: f64) -> Option<Unary> {
    if c == 1.0 {
        None
    } else if c.fract() == 0.0 && c.abs() <= MAX_POWI {
        // exact conversion: |c| <= 1024 is an integer
        Some(Unary::Powi(c as i32))
    } else {
        Some(Unary::Powf(c))
    }
}

/// `a^b` for an exponent `b` that depends on parameters only ([`Binary::PowParam`]): at `b`'s
/// value `c`, the rule a folded exponent gets ([`constant_power`]), so the value is the folded
/// program's; where `b` moves, times `a^(b - c) = exp((b - c) ln a)`, whose value is 1 and whose
/// derivatives are exact (defined for `a > 0`).
fn pow_param<S: Scalar>(a: S, b: S) -> S {
    let c = S::constant(b.value());
    let at_c = constant_power(b.value()).map_or(a, |u| u.apply(a));
    if b == c {
        at_c
    } else {
        at_c * ((b - c) * a.ln()).exp()
    }
}

/// One-argument operations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Unary {
    Neg,
    Powi(i32),
    Powf(f64),
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Sqrt,
    Abs,
    Sign,
}

impl Unary {
    #[inline(always)]
    pub(crate) fn apply<S: Scalar>(self, a: S) -> S {
        match self {
            Unary::Neg => -a,
            Unary::Powi(n) => a.powi(n),
            Unary::Powf(c) => a.powf(c),
            Unary::Sin => a.sin(),
            Unary::Cos => a.cos(),
            Unary::Tan => a.tan(),
            Unary::Asin => a.asin(),
            Unary::Acos => a.acos(),
            Unary::Atan => a.atan(),
            Unary::Sinh => a.sinh(),
            Unary::Cosh => a.cosh(),
            Unary::Tanh => a.tanh(),
            Unary::Exp => a.exp(),
            Unary::Ln => a.ln(),
            Unary::Sqrt => a.sqrt(),
            Unary::Abs => a.abs(),
            Unary::Sign => a.sign(),
        }
    }
}

/// Two-argument operations; the left operand is pushed first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    /// General power `a^b = exp(b ln a)` (only emitted for non-constant exponents).
    Pow,
    /// A power whose exponent depends on parameters only (side programs only, [`pow_param`]).
    PowParam,
    Atan2,
    Hypot,
    Min,
    Max,
    /// Comparisons: 1 when true, 0 when false, derivatives 0.
    Lt,
    Gt,
    Le,
    Ge,
    Eq,
    Ne,
}

impl Binary {
    #[inline(always)]
    pub(crate) fn apply<S: Scalar>(self, a: S, b: S) -> S {
        match self {
            Binary::Add => a + b,
            Binary::Sub => a - b,
            Binary::Mul => a * b,
            Binary::Div => a / b,
            Binary::Pow => a.pow(b),
            Binary::PowParam => pow_param(a, b),
            Binary::Atan2 => a.atan2(b),
            Binary::Hypot => a.hypot(b),
            Binary::Min => a.min(b),
            Binary::Max => a.max(b),
            Binary::Lt => truth(a.value() < b.value()),
            Binary::Gt => truth(a.value() > b.value()),
            Binary::Le => truth(a.value() <= b.value()),
            Binary::Ge => truth(a.value() >= b.value()),
            Binary::Eq => truth(a.value() == b.value()),
            Binary::Ne => truth(a.value() != b.value()),
        }
    }
}

/// A comparison's value: 1 or 0, a constant.
fn truth<S: Scalar>(holds: bool) -> S {
    S::constant(if holds { 1.0 } else { 0.0 })
}

/// Operations of more than two arguments, the arguments pushed in order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Nary {
    /// `if(c, a, b)`: `a` where `c` is not 0, else `b` (each with its own derivatives).
    If,
    /// A motion law `law(x, x0, h0, x1, h1)` ([`super::laws`]).
    Law(super::laws::Law),
}

impl Nary {
    /// Number of arguments.
    pub(crate) fn arity(self) -> usize {
        match self {
            Nary::If => 3,
            Nary::Law(_) => 5,
        }
    }

    #[inline(always)]
    pub(crate) fn apply<S: Scalar>(self, args: &[S]) -> S {
        match self {
            Nary::If => {
                if args[0].value() != 0.0 {
                    args[1]
                } else {
                    args[2]
                }
            }
            Nary::Law(law) => law.apply(args[0], args[1], args[2], args[3], args[4]),
        }
    }
}

/// One bytecode instruction of a stack machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Op {
    /// Push a constant.
    Const(f64),
    /// Push the value of a variable slot.
    Var(usize),
    /// Push the model's parameter of this index (side programs only).
    Param(usize),
    /// Replace the top of the stack by a function of it.
    Unary(Unary),
    /// Pop `b`, pop `a`, push `a op b`.
    Binary(Binary),
    /// Pop the operation's arguments (the last pushed last), push its value.
    Nary(Nary),
    /// Replace the top of the stack by the value of the expression's table of this index
    /// (`spline(name, x)`).
    Table(usize),
}

/// Built-in functions: name, number of arguments, operation.
pub(crate) const FUNCTIONS: &[(&str, usize, Op)] = &[
    ("sin", 1, Op::Unary(Unary::Sin)),
    ("cos", 1, Op::Unary(Unary::Cos)),
    ("tan", 1, Op::Unary(Unary::Tan)),
    ("asin", 1, Op::Unary(Unary::Asin)),
    ("acos", 1, Op::Unary(Unary::Acos)),
    ("atan", 1, Op::Unary(Unary::Atan)),
    ("atan2", 2, Op::Binary(Binary::Atan2)),
    ("hypot", 2, Op::Binary(Binary::Hypot)),
    ("sinh", 1, Op::Unary(Unary::Sinh)),
    ("cosh", 1, Op::Unary(Unary::Cosh)),
    ("tanh", 1, Op::Unary(Unary::Tanh)),
    ("exp", 1, Op::Unary(Unary::Exp)),
    ("log", 1, Op::Unary(Unary::Ln)),
    ("sqrt", 1, Op::Unary(Unary::Sqrt)),
    ("abs", 1, Op::Unary(Unary::Abs)),
    ("min", 2, Op::Binary(Binary::Min)),
    ("max", 2, Op::Binary(Binary::Max)),
    ("sign", 1, Op::Unary(Unary::Sign)),
    ("pow", 2, Op::Binary(Binary::Pow)),
    ("if", 3, Op::Nary(Nary::If)),
    ("step", 5, Op::Nary(Nary::Law(Law::Step))),
    ("step5", 5, Op::Nary(Nary::Law(Law::Step5))),
    ("poly345", 5, Op::Nary(Nary::Law(Law::Step5))),
    ("cycloidal", 5, Op::Nary(Nary::Law(Law::Cycloidal))),
    ("harmonic", 5, Op::Nary(Nary::Law(Law::Harmonic))),
    ("modified_trapezoid", 5, Op::Nary(Nary::Law(Law::ModifiedTrapezoid))),
];

/// The function whose first argument names a table: `spline(name, x)`.
const SPLINE: &str = "spline";

/// Built-in constants.
const CONSTANTS: &[(&str, f64)] = &[("pi", std::f64::consts::PI), ("e", std::f64::consts::E)];

fn function(name: &str) -> Option<(usize, Op)> {
    FUNCTIONS.iter().find(|(n, _, _)| *n == name).map(|&(_, arity, op)| (arity, op))
}

/// Whether `name` is a function's (so it cannot be a variable's).
fn is_function(name: &str) -> bool {
    name == SPLINE || function(name).is_some()
}

/// A bytecode program and the deepest stack it needs.
#[derive(Debug, Clone)]
pub(crate) struct Program {
    pub code: Vec<Op>,
    pub max_stack: usize,
}

/// The program with parameters as inputs, and the parameters it reads (sorted, each once).
#[derive(Debug, Clone)]
pub(crate) struct Side {
    pub program: Program,
    pub parameters: Vec<usize>,
}

/// The result of compiling a source string.
#[derive(Debug, Clone)]
pub(crate) struct Compiled {
    /// The program with parameters folded as numbers.
    pub program: Program,
    pub slots: Vec<usize>,
    /// The tables `Op::Table` indexes.
    pub tables: Vec<Arc<Spline>>,
    /// The side program, when the source names a parameter (boxed: most expressions have none).
    pub side: Option<Box<Side>>,
}

/// Parses and compiles `src`: a name is a built-in constant, else a named value of `names`
/// (folded like a number), else a variable resolved with `resolve`; `spline(name, x)` names a
/// table of `names`. When a named value is a parameter ([`Names::parameter`]), `src` is compiled
/// a second time with the parameters as inputs (the side program).
pub(crate) fn compile(
    src: &str,
    names: &dyn Names,
    resolve: &mut dyn FnMut(&str) -> Result<usize, String>,
) -> Result<Compiled, ExprError> {
    let (mut compiled, mut parameters) = compile_mode(src, names, resolve, false)?;
    if !parameters.is_empty() {
        parameters.sort_unstable();
        parameters.dedup();
        let program = compile_mode(src, names, resolve, true)?.0.program;
        compiled.side = Some(Box::new(Side { program, parameters }));
    }
    Ok(compiled)
}

/// One compilation of `src` (parameters as inputs when `side`), without a side program, and
/// the parameters it folded (in order of use).
fn compile_mode(
    src: &str,
    names: &dyn Names,
    resolve: &mut dyn FnMut(&str) -> Result<usize, String>,
    side: bool,
) -> Result<(Compiled, Vec<usize>), ExprError> {
    let mut p = Parser {
        lex: Lexer { src, pos: 0 },
        peeked: None,
        stack: Vec::new(),
        depth: 0,
        code: Vec::new(),
        free: Vec::new(),
        names,
        tables: Vec::new(),
        resolve,
        side,
        parameters: Vec::new(),
    };
    p.parse()?;

    let code = p.code;
    let mut depth = 0usize;
    let mut max_stack = 0usize;
    let mut slots = Vec::new();
    for op in &code {
        match *op {
            Op::Const(_) | Op::Param(_) => depth += 1,
            Op::Var(s) => {
                depth += 1;
                slots.push(s);
            }
            Op::Unary(_) | Op::Table(_) => {}
            Op::Binary(_) => depth -= 1,
            Op::Nary(n) => depth -= n.arity() - 1,
        }
        max_stack = max_stack.max(depth);
    }
    debug_assert_eq!(depth, 1);
    if max_stack > MAX_STACK {
        return Err(ExprError::new("expression too complex", 0));
    }
    slots.sort_unstable();
    slots.dedup();
    Ok((Compiled { program: Program { code, max_stack }, slots, tables: p.tables, side: None }, p.parameters))
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok<'a> {
    Num(f64),
    Name(&'a str),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    /// A comparison operator.
    Cmp(Binary),
    End,
}

/// A token and its byte range in the source.
#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    tok: Tok<'a>,
    start: usize,
    end: usize,
}

struct Lexer<'a> {
    src: &'a str,
    pos: usize,
}

fn is_name_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

fn is_name_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

impl<'a> Lexer<'a> {
    fn byte(&self, i: usize) -> Option<u8> {
        self.src.as_bytes().get(i).copied()
    }

    fn skip_while(&mut self, f: impl Fn(u8) -> bool) {
        while self.byte(self.pos).is_some_and(&f) {
            self.pos += 1;
        }
    }

    fn next_token(&mut self) -> Result<Token<'a>, ExprError> {
        // skip whitespace (any Unicode whitespace)
        let rest = &self.src[self.pos..];
        let trimmed = rest.trim_start();
        self.pos += rest.len() - trimmed.len();

        let start = self.pos;
        let Some(c) = self.byte(start) else {
            return Ok(Token { tok: Tok::End, start, end: start });
        };
        let single = |tok| Token { tok, start, end: start + 1 };
        let token = match c {
            b'+' => single(Tok::Plus),
            b'-' => single(Tok::Minus),
            b'/' => single(Tok::Slash),
            b'^' => single(Tok::Caret),
            b'(' => single(Tok::LParen),
            b')' => single(Tok::RParen),
            b',' => single(Tok::Comma),
            b'<' | b'>' | b'=' | b'!' => {
                let equals = self.byte(start + 1) == Some(b'=');
                let op = match (c, equals) {
                    (b'<', false) => Binary::Lt,
                    (b'>', false) => Binary::Gt,
                    (b'<', true) => Binary::Le,
                    (b'>', true) => Binary::Ge,
                    (b'=', true) => Binary::Eq,
                    (b'!', true) => Binary::Ne,
                    _ => {
                        let hint = if c == b'=' { " (a comparison is written '==')" } else { "" };
                        return Err(ExprError::new(format!("unexpected character '{}'{hint}", c as char), start));
                    }
                };
                Token { tok: Tok::Cmp(op), start, end: start + 1 + usize::from(equals) }
            }
            b'*' if self.byte(start + 1) == Some(b'*') => Token { tok: Tok::Caret, start, end: start + 2 },
            b'*' => single(Tok::Star),
            b'0'..=b'9' => return self.number(),
            b'.' if self.byte(start + 1).is_some_and(|b| b.is_ascii_digit()) => return self.number(),
            c if is_name_start(c) => return self.name(),
            _ => {
                let ch = self.src[start..].chars().next().unwrap_or('?');
                return Err(ExprError::new(format!("unexpected character '{}'", ch.escape_debug()), start));
            }
        };
        self.pos = token.end;
        Ok(token)
    }

    fn number(&mut self) -> Result<Token<'a>, ExprError> {
        let start = self.pos;
        self.skip_while(|b| b.is_ascii_digit());
        if self.byte(self.pos) == Some(b'.') {
            self.pos += 1;
            self.skip_while(|b| b.is_ascii_digit());
        }
        if matches!(self.byte(self.pos), Some(b'e' | b'E')) {
            let mut i = self.pos + 1;
            if matches!(self.byte(i), Some(b'+' | b'-')) {
                i += 1;
            }
            if !self.byte(i).is_some_and(|b| b.is_ascii_digit()) {
                return Err(ExprError::new("malformed number: exponent has no digits", start));
            }
            self.pos = i;
            self.skip_while(|b| b.is_ascii_digit());
        }
        let text = &self.src[start..self.pos];
        let v: f64 = text.parse().map_err(|_| ExprError::new(format!("malformed number '{text}'"), start))?;
        if !v.is_finite() {
            return Err(ExprError::new(format!("number '{text}' is out of range"), start));
        }
        Ok(Token { tok: Tok::Num(v), start, end: self.pos })
    }

    fn name(&mut self) -> Result<Token<'a>, ExprError> {
        let start = self.pos;
        self.skip_while(is_name_char);
        if self.byte(self.pos) == Some(b'.') {
            self.pos += 1;
            if !self.byte(self.pos).is_some_and(is_name_start) {
                return Err(ExprError::new(
                    format!("expected a letter or '_' after '.' in name '{}'", &self.src[start..self.pos]),
                    self.pos,
                ));
            }
            self.skip_while(is_name_char);
            if self.byte(self.pos) == Some(b'.') {
                return Err(ExprError::new("a name may contain only one '.'", self.pos));
            }
        }
        Ok(Token { tok: Tok::Name(&self.src[start..self.pos]), start, end: self.pos })
    }
}

/// Infix operators.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Infix {
    /// A comparison (loosest of all: `t - 1 > 0` compares `t - 1`).
    Cmp(Binary),
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

impl Infix {
    /// Binding power; unary minus sits between `* /` and `^` (see [`NEG_PREC`]).
    fn prec(self) -> u8 {
        match self {
            Infix::Cmp(_) => 1,
            Infix::Add | Infix::Sub => 2,
            Infix::Mul | Infix::Div => 3,
            Infix::Pow => 5,
        }
    }

    fn binary(self) -> Binary {
        match self {
            Infix::Cmp(b) => b,
            Infix::Add => Binary::Add,
            Infix::Sub => Binary::Sub,
            Infix::Mul => Binary::Mul,
            Infix::Div => Binary::Div,
            Infix::Pow => Binary::Pow,
        }
    }
}

/// Binding power of unary minus: tighter than `*` and `/`, looser than `^`, so
/// `-x*y = (-x)*y` and `-x^2 = -(x^2)`.
const NEG_PREC: u8 = 4;

/// An entry of the parser's explicit operator stack.
#[derive(Debug, Clone, Copy)]
enum Frame<'a> {
    /// A binary operator waiting for its right operand.
    Infix(Infix),
    /// A unary minus waiting for its operand.
    Neg,
    /// An open parenthesis at this byte offset.
    Paren(usize),
    /// An open function call.
    Call {
        name: &'a str,
        /// Offset of the function name.
        start: usize,
        /// Offset of the `(`.
        open: usize,
        arity: usize,
        op: Op,
        /// Arguments completed so far.
        args: usize,
    },
}

impl Frame<'_> {
    /// Binding power of an operator frame; `None` for parentheses and calls.
    fn prec(&self) -> Option<u8> {
        match self {
            Frame::Infix(op) => Some(op.prec()),
            Frame::Neg => Some(NEG_PREC),
            Frame::Paren(_) | Frame::Call { .. } => None,
        }
    }

    /// Whether the frame counts towards the nesting depth. Pending `+ - * /` do not:
    /// at most two of them can be pending per nesting level.
    fn nests(&self) -> bool {
        !matches!(self, Frame::Infix(op) if *op != Infix::Pow)
    }
}

/// An operator-precedence (shunting-yard) parser with an explicit stack, so that
/// deeply nested input costs heap memory bounded by [`MAX_DEPTH`], never call stack.
struct Parser<'a, 'r> {
    lex: Lexer<'a>,
    peeked: Option<Token<'a>>,
    stack: Vec<Frame<'a>>,
    /// Number of frames on `stack` for which [`Frame::nests`] holds.
    depth: usize,
    code: Vec<Op>,
    /// For each operand `code` computes, in order: whether it reads no variable (only numbers
    /// and parameters). A power's exponent that reads none but a parameter gets
    /// [`Binary::PowParam`] in the side mode.
    free: Vec<bool>,
    /// Named values and tables given by the caller (a model's parameters and tables).
    names: &'r dyn Names,
    /// The tables used, in order of first use.
    tables: Vec<Arc<Spline>>,
    resolve: &'r mut dyn FnMut(&str) -> Result<usize, String>,
    /// Whether parameters are inputs ([`Op::Param`]) rather than folded numbers.
    side: bool,
    /// The parameters folded as numbers, in order of use (not in the side mode).
    parameters: Vec<usize>,
}

impl<'a> Parser<'a, '_> {
    fn peek(&mut self) -> Result<Token<'a>, ExprError> {
        if let Some(t) = self.peeked {
            return Ok(t);
        }
        let t = self.lex.next_token()?;
        self.peeked = Some(t);
        Ok(t)
    }

    /// Returns and consumes the next token.
    fn next(&mut self) -> Result<Token<'a>, ExprError> {
        let t = self.peek()?;
        self.peeked = None;
        Ok(t)
    }

    /// A human-readable description of a token for error messages.
    fn describe(&self, t: Token<'_>) -> String {
        let text = &self.lex.src[t.start..t.end];
        match t.tok {
            Tok::End => "end of input".to_string(),
            Tok::Num(_) => format!("number '{text}'"),
            Tok::Name(_) => format!("name '{text}'"),
            _ => format!("'{text}'"),
        }
    }

    /// Parses the whole input into `self.code`.
    fn parse(&mut self) -> Result<(), ExprError> {
        if self.peek()?.tok == Tok::End {
            return Err(ExprError::new("empty expression", 0));
        }
        let mut expect_operand = true;
        loop {
            let t = self.next()?;
            if expect_operand {
                // `true` once a complete operand has been read.
                expect_operand = !self.operand(t)?;
                continue;
            }
            match t.tok {
                Tok::Plus | Tok::Minus | Tok::Star | Tok::Slash | Tok::Caret | Tok::Cmp(_) => {
                    let op = match t.tok {
                        Tok::Cmp(b) => Infix::Cmp(b),
                        Tok::Plus => Infix::Add,
                        Tok::Minus => Infix::Sub,
                        Tok::Star => Infix::Mul,
                        Tok::Slash => Infix::Div,
                        _ => Infix::Pow,
                    };
                    // `^` is right associative: an equal-precedence `^` stays pending.
                    let right_assoc = op == Infix::Pow;
                    self.reduce(op.prec() + u8::from(right_assoc));
                    self.push(Frame::Infix(op), t.start)?;
                    expect_operand = true;
                }
                Tok::RParen => {
                    self.reduce(0);
                    match self.stack.last_mut() {
                        Some(Frame::Paren(_)) => self.pop(),
                        Some(Frame::Call { args, .. }) => {
                            *args += 1;
                            self.close_call()?;
                        }
                        _ => return Err(ExprError::new("unbalanced parentheses: ')' has no matching '('", t.start)),
                    }
                }
                Tok::Comma if self.innermost_group().is_some_and(|f| matches!(f, Frame::Call { .. })) => {
                    self.reduce(0);
                    if let Some(Frame::Call { args, .. }) = self.stack.last_mut() {
                        *args += 1;
                    }
                    expect_operand = true;
                }
                Tok::End => {
                    self.reduce(0);
                    return match self.stack.last() {
                        None => Ok(()),
                        Some(Frame::Paren(open) | Frame::Call { open, .. }) => {
                            Err(ExprError::new("unbalanced parentheses: '(' is never closed", *open))
                        }
                        Some(_) => unreachable!("reduce(0) leaves no operator on top"),
                    };
                }
                _ => return Err(self.missing_operator(t)),
            }
        }
    }

    /// Handles token `t` where an operand is expected. Returns `true` when an operand
    /// is complete (a number, a name, a constant, or an argument-less call), `false`
    /// when still waiting for one (after `(`, a unary sign, or a call's `(`).
    fn operand(&mut self, t: Token<'a>) -> Result<bool, ExprError> {
        match t.tok {
            Tok::Num(v) => {
                self.code.push(Op::Const(v));
                self.free.push(true);
                Ok(true)
            }
            Tok::Name(name) => {
                if self.peek()?.tok == Tok::LParen {
                    let open = self.next()?;
                    if name == SPLINE {
                        let call = self.table(t.start, open.start)?;
                        self.push(call, t.start)?;
                        return Ok(false);
                    }
                    let Some((arity, op)) = function(name) else {
                        return Err(ExprError::new(format!("unknown function '{name}'"), t.start));
                    };
                    let call = Frame::Call { name, start: t.start, open: open.start, arity, op, args: 0 };
                    self.push(call, t.start)?;
                    if self.peek()?.tok == Tok::RParen {
                        self.next()?;
                        self.close_call()?;
                        return Ok(true);
                    }
                    return Ok(false);
                }
                self.name(name, t.start)?;
                Ok(true)
            }
            Tok::LParen => {
                self.push(Frame::Paren(t.start), t.start)?;
                Ok(false)
            }
            Tok::Minus => {
                self.push(Frame::Neg, t.start)?;
                Ok(false)
            }
            Tok::Plus => Ok(false),
            _ => Err(ExprError::new(
                format!("missing operand: expected a number, name or '(', found {}", self.describe(t)),
                t.start,
            )),
        }
    }

    /// Emits a name used as an operand: a built-in constant, a named value of the caller's or a
    /// resolved variable.
    fn name(&mut self, name: &str, start: usize) -> Result<(), ExprError> {
        // The caller's names first: a model's parameter may be called `e` (it may not be `pi`).
        let builtin = !self.names.shadows(name);
        let constant = CONSTANTS.iter().find(|(n, _)| builtin && *n == name).map(|&(_, v)| v);
        if let Some(v) = self.names.constant(name).or(constant) {
            match self.names.parameter(name) {
                Some(i) if self.side => self.code.push(Op::Param(i)),
                parameter => {
                    self.code.push(Op::Const(v));
                    self.parameters.extend(parameter);
                }
            }
            self.free.push(true);
            return Ok(());
        }
        if is_function(name) {
            return Err(ExprError::new(format!("function '{name}' needs its arguments in parentheses"), start));
        }
        match (self.resolve)(name) {
            Ok(slot) => {
                self.code.push(Op::Var(slot));
                self.free.push(false);
                Ok(())
            }
            Err(hint) => {
                let message = if hint.is_empty() {
                    format!("unknown name '{name}'")
                } else {
                    format!("unknown name '{name}' ({hint})")
                };
                Err(ExprError::new(message, start))
            }
        }
    }

    /// Reads `name ,` after `spline(` (at `start`, the `(` at `open`): the call of the table's
    /// function, its first argument complete.
    fn table(&mut self, start: usize, open: usize) -> Result<Frame<'a>, ExprError> {
        let t = self.next()?;
        let Tok::Name(name) = t.tok else {
            return Err(ExprError::new(
                format!("expected a table's name as the first argument of 'spline', found {}", self.describe(t)),
                t.start,
            ));
        };
        let Some(table) = self.names.table(name) else {
            return Err(ExprError::new(format!("unknown table '{name}' (tables are defined under tables:)"), t.start));
        };
        let comma = self.next()?;
        if comma.tok != Tok::Comma {
            return Err(ExprError::new(
                format!("expected ',' after the table's name in 'spline', found {}", self.describe(comma)),
                comma.start,
            ));
        }
        let index = match self.tables.iter().position(|u| Arc::ptr_eq(u, &table)) {
            Some(i) => i,
            None => {
                self.tables.push(table);
                self.tables.len() - 1
            }
        };
        Ok(Frame::Call { name: SPLINE, start, open, arity: 2, op: Op::Table(index), args: 1 })
    }

    /// The error for an operand (or `,`) found where an operator was expected.
    fn missing_operator(&self, t: Token<'_>) -> ExprError {
        let found = self.describe(t);
        let message = match self.innermost_group() {
            Some(Frame::Call { name, .. }) => {
                format!("expected ',' or ')' in the arguments of '{name}', found {found}")
            }
            Some(_) => format!("expected ')' or an operator, found {found}"),
            None => format!("unexpected {found} after a complete expression (missing operator?)"),
        };
        ExprError::new(message, t.start)
    }

    /// The innermost open parenthesis or call.
    fn innermost_group(&self) -> Option<&Frame<'a>> {
        self.stack.iter().rev().find(|f| f.prec().is_none())
    }

    /// Pushes a frame, enforcing the nesting limit.
    fn push(&mut self, frame: Frame<'a>, at: usize) -> Result<(), ExprError> {
        if frame.nests() {
            if self.depth >= MAX_DEPTH {
                return Err(ExprError::new(format!("expression nested too deeply (more than {MAX_DEPTH} levels)"), at));
            }
            self.depth += 1;
        }
        self.stack.push(frame);
        Ok(())
    }

    /// Pops the top frame (without emitting anything).
    fn pop(&mut self) {
        if let Some(f) = self.stack.pop() {
            if f.nests() {
                self.depth -= 1;
            }
        }
    }

    /// Emits pending operators with binding power `>= min_prec` from the top of the
    /// stack; `reduce(0)` empties it down to the innermost open group.
    fn reduce(&mut self, min_prec: u8) {
        while let Some(&top) = self.stack.last() {
            match (top, top.prec()) {
                (Frame::Infix(op), Some(p)) if p >= min_prec => {
                    self.pop();
                    self.emit_binary(op.binary());
                }
                (Frame::Neg, Some(p)) if p >= min_prec => {
                    self.pop();
                    self.emit_unary(Unary::Neg);
                }
                _ => break,
            }
        }
    }

    /// Pops the call frame on top of the stack, checks its argument count and emits
    /// the function.
    fn close_call(&mut self) -> Result<(), ExprError> {
        let Some(Frame::Call { name, start, arity, op, args, .. }) = self.stack.last().copied() else {
            unreachable!("close_call without a call frame");
        };
        self.pop();
        if args != arity {
            let plural = if arity == 1 { "" } else { "s" };
            return Err(ExprError::new(
                format!("function '{name}' takes {arity} argument{plural}, found {args}"),
                start,
            ));
        }
        match op {
            Op::Unary(u) => self.emit_unary(u),
            Op::Binary(b) => self.emit_binary(b),
            Op::Nary(n) => self.emit_nary(n),
            Op::Table(i) => match self.code.last_mut() {
                Some(Op::Const(a)) => *a = self.tables[i].eval(*a).0,
                _ => self.code.push(Op::Table(i)),
            },
            Op::Const(_) | Op::Var(_) | Op::Param(_) => unreachable!("FUNCTIONS holds only operations"),
        }
        Ok(())
    }

    /// Emits a unary operation, folding it if its operand is a constant.
    fn emit_unary(&mut self, u: Unary) {
        if let Some(Op::Const(a)) = self.code.last_mut() {
            *a = u.apply(*a);
        } else {
            self.code.push(Op::Unary(u));
        }
    }

    /// Emits an operation of more than two arguments, folded when they are all constants (the
    /// last `arity` instructions are then the arguments, as in [`Self::emit_binary`]).
    fn emit_nary(&mut self, op: Nary) {
        let arity = op.arity();
        let operands = self.free.len() - arity;
        let free = self.free.drain(operands..).all(|f| f);
        self.free.push(free);
        let n = self.code.len();
        if n >= arity {
            let args: Vec<f64> = self.code[n - arity..]
                .iter()
                .map_while(|o| if let Op::Const(c) = o { Some(*c) } else { None })
                .collect();
            if args.len() == arity {
                self.code.truncate(n - arity);
                self.code.push(Op::Const(op.apply(&args)));
                return;
            }
        }
        self.code.push(Op::Nary(op));
    }

    /// Emits a binary operation, folding constant operands and turning powers with a
    /// constant exponent into [`Unary::Powi`] / [`Unary::Powf`].
    ///
    /// Folding by peeking at the last instructions is sound: an operand whose code ends
    /// in `Const` consists of that single instruction (it is the operand's root and
    /// takes no inputs), and then the instruction before it ends the left operand.
    fn emit_binary(&mut self, b: Binary) {
        let n = self.code.len();
        let exponent_free = self.free.pop().unwrap_or(false);
        let base_free = self.free.pop().unwrap_or(false);
        self.free.push(base_free && exponent_free);
        if b == Binary::Pow {
            if let Some(&Op::Const(c)) = self.code.last() {
                self.code.pop();
                if let Some(u) = constant_power(c) {
                    self.emit_unary(u);
                }
                return;
            }
            // Only in the side mode: elsewhere an exponent without variables is a number here.
            if exponent_free {
                self.code.push(Op::Binary(Binary::PowParam));
                return;
            }
        }
        if n >= 2 {
            if let (Op::Const(x), Op::Const(y)) = (self.code[n - 2], self.code[n - 1]) {
                self.code.pop();
                self.code[n - 2] = Op::Const(b.apply(x, y));
                return;
            }
        }
        self.code.push(Op::Binary(b));
    }
}
