//! Expressions of time and state inside force elements: `"-20*crank.omega + 100*sin(t)"`.
//!
//! The model compiler resolves each name to a [`StateVar`] (a global coordinate, velocity or
//! time); the force element then maps the coordinates onto its local columns
//! ([`Load::localize`]), so that evaluation reads only the element's `x` and `v`.

use super::Data;
use crate::expr::MAX_SLOTS;
use crate::expr::{Expr, Scalar};

/// What an expression slot stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateVar {
    /// `q[index]`.
    Position(usize),
    /// `qdot[index]`.
    Velocity(usize),
    /// `qddot[index]` (measures only).
    Acceleration(usize),
    /// Entry `index` of the reactions row: every joint's `fx, fy, torque`, then every driver's
    /// effort, in model order (measures only).
    Reaction(usize),
    /// The time `t`.
    Time,
}

/// An expression over state slots, with at most [`MAX_SLOTS`] names.
#[derive(Debug, Clone)]
pub struct StateExpr {
    expr: Expr,
    /// (slots) what each slot stands for, global indices.
    vars: Vec<StateVar>,
}

impl StateExpr {
    /// `expr` with slot `k` standing for `vars[k]`.
    ///
    /// # Errors
    ///
    /// More than [`MAX_SLOTS`] names.
    pub fn try_new(expr: Expr, vars: Vec<StateVar>) -> Result<StateExpr, String> {
        if vars.len() > MAX_SLOTS {
            return Err(format!("the expression uses {} names; at most {MAX_SLOTS} are supported", vars.len()));
        }
        Ok(StateExpr { expr, vars })
    }

    /// The source text.
    pub fn source(&self) -> &str {
        self.expr.source()
    }

    /// The entries of the reactions row it reads ([`StateVar::Reaction`]).
    pub fn reactions(&self) -> impl Iterator<Item = usize> + '_ {
        self.vars.iter().filter_map(|v| match *v {
            StateVar::Reaction(k) => Some(k),
            _ => None,
        })
    }

    /// The model's parameters it names (their indices, [`Expr::parameters`]).
    pub fn parameters(&self) -> &[usize] {
        self.expr.parameters()
    }

    /// Value from global `q`, `qdot`, `qddot` and the reactions row `reactions` (the last two
    /// may be empty when no slot needs them; an entry that is not there reads as NaN).
    pub fn eval_global(&self, q: &[f64], qdot: &[f64], qddot: &[f64], reactions: &[f64], t: f64) -> f64 {
        let z = self.slots(q, qdot, qddot, reactions, t);
        self.expr.eval(&z[..self.vars.len()])
    }

    /// As [`StateExpr::eval_global`] over any [`Scalar`], with the model's parameters `params`
    /// (file order) read as inputs ([`Expr::eval_params`]): seeded along a parameter (and along
    /// time, [`crate::expr::Tri`]), it gives the expression's exact derivatives.
    ///
    /// # Panics
    ///
    /// If `params` is not longer than the largest of [`StateExpr::parameters`].
    pub fn eval_params<S: Scalar>(&self, q: &[S], qdot: &[S], qddot: &[S], reactions: &[S], t: S, params: &[S]) -> S {
        let z = self.slots(q, qdot, qddot, reactions, t);
        self.expr.eval_params(&z[..self.vars.len()], params)
    }

    /// The value of each slot, from global `q`, `qdot`, `qddot`, the reactions row and `t` (an
    /// entry of the reactions row that is not there reads as NaN).
    #[inline]
    fn slots<S: Scalar>(&self, q: &[S], qdot: &[S], qddot: &[S], reactions: &[S], t: S) -> [S; MAX_SLOTS] {
        let mut z = [S::constant(0.0); MAX_SLOTS];
        for (zk, v) in z.iter_mut().zip(&self.vars) {
            *zk = match *v {
                StateVar::Position(c) => q[c],
                StateVar::Velocity(c) => qdot[c],
                StateVar::Acceleration(c) => qddot[c],
                StateVar::Reaction(k) => reactions.get(k).copied().unwrap_or(S::constant(f64::NAN)),
                StateVar::Time => t,
            };
        }
        z
    }
}

/// A force magnitude: a constant or an expression of time and state over local columns.
#[derive(Debug, Clone)]
pub enum Load {
    /// A constant.
    Constant(f64),
    /// An expression; once localized to an element, its coordinate slots index the element's columns.
    Expression(StateExpr),
}

impl Load {
    /// Whether the load is the constant zero (no actuator).
    pub(crate) fn is_zero(&self) -> bool {
        matches!(self, Load::Constant(v) if *v == 0.0)
    }

    /// Map the expression's coordinates onto local columns, appending those not yet in
    /// `columns`.
    pub(crate) fn localize(&mut self, columns: &mut Vec<usize>) {
        let Load::Expression(e) = self else { return };
        let mut local = |c: usize| match columns.iter().position(|&k| k == c) {
            Some(k) => k,
            None => {
                columns.push(c);
                columns.len() - 1
            }
        };
        for v in e.vars.iter_mut() {
            *v = match *v {
                StateVar::Position(c) => StateVar::Position(local(c)),
                StateVar::Velocity(c) => StateVar::Velocity(local(c)),
                other => other,
            };
        }
    }

    /// The source text of an expression (`None` for a constant).
    pub(crate) fn source(&self) -> Option<&str> {
        match self {
            Load::Constant(_) => None,
            Load::Expression(e) => Some(e.source()),
        }
    }

    /// The value from local `x`, `v` (after [`Load::localize`]).
    #[inline]
    pub(crate) fn value<S: Scalar>(&self, x: &[S], v: &[S], t: f64) -> S {
        match self {
            Load::Constant(c) => S::constant(*c),
            Load::Expression(e) => e.expr.eval(&Load::local_slots(e, x, v, t)[..e.vars.len()]),
        }
    }

    /// Its number as one of the force's data, named `field` (a constant); none for an
    /// expression, whose numbers are the model's parameters ([`crate::forces::ForceLaw::data`]).
    pub(crate) fn data(&self, field: &'static str) -> Option<(&'static str, f64)> {
        match self {
            Load::Constant(c) => Some((field, *c)),
            Load::Expression(_) => None,
        }
    }

    /// As [`Load::value`] with the numbers as inputs: a constant is the next of `data`, an
    /// expression reads the model's parameters from `params` ([`Expr::eval_params`]).
    #[inline]
    pub(crate) fn value_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &mut Data<'_, S>, params: &[S]) -> S {
        match self {
            Load::Constant(_) => data.next(),
            Load::Expression(e) => e.expr.eval_params(&Load::local_slots(e, x, v, t)[..e.vars.len()], params),
        }
    }

    /// The value of each slot of `e` from local `x`, `v` and `t`.
    #[inline]
    fn local_slots<S: Scalar>(e: &StateExpr, x: &[S], v: &[S], t: f64) -> [S; MAX_SLOTS] {
        let mut z = [S::constant(0.0); MAX_SLOTS];
        for (zk, var) in z.iter_mut().zip(&e.vars) {
            *zk = match *var {
                StateVar::Position(k) => x[k],
                StateVar::Velocity(k) => v[k],
                StateVar::Acceleration(_) | StateVar::Reaction(_) => S::constant(f64::NAN),
                StateVar::Time => S::constant(t),
            };
        }
        z
    }
}
