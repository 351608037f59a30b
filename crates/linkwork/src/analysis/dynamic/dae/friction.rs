//! The joints' friction: where each friction joint's rows, Jacobian block and columns sit, its
//! generalised force `Q_f(q, qdot, lambda)` and exact derivatives, and the Newton iteration on
//! the accelerations and multipliers it makes nonlinear.

use super::{gather, Dae};
use crate::constraints::{Config, Friction};
use crate::error::{Error, RowName};
use crate::expr::Dual;

/// The most Newton iterations [`Dae::accelerations`] (and the inverse analysis' Newton on the
/// multipliers) takes when joints have friction: 30. The
/// friction depends on the reactions only through their magnitudes, so Newton converges
/// quadratically once the reactions' directions settle, in the three solves of the frictionless
/// refinement or a few more. A reaction near zero (a pin unloaded while the mechanism moves)
/// turns its direction fast, which costs a few more; 30 leaves room for those and still fails fast
/// where there is no solution.
pub(crate) const NEWTON_FRICTION_ITERATIONS: usize = 30;

/// An iteration on the multipliers with joint friction (Newton on the accelerations, and on the
/// inverse analysis's friction rows) has converged when its last correction of the multipliers is below this
/// fraction of the largest multiplier: `1e-10`. Once the friction holds still the rest is linear
/// and the correction is the refinement's, which the frictionless solve stops after three solves,
/// each shrinking it by the regularisation's `~1e-10`; `1e-10` is a hundred to ten thousand times
/// the round-off of the multipliers (`1e-16` times the condition, `1e2` to `1e4` on the examples),
/// and far below the accuracy to which any coefficient of friction is known. Measured against the
/// largest multiplier (forces and torques alike, for a mechanism of metres), not each its own, so
/// that the round-off of a joint that carries nothing does not count as a change.
pub(crate) const FRICTION_RTOL: f64 = 1e-10;

/// One joint's friction and where its rows, Jacobian block and columns sit.
#[derive(Debug)]
pub(super) struct FrictionSlot<'m> {
    pub(super) friction: &'m Friction,
    /// The joint's name, for messages.
    pub(super) name: &'m str,
    /// Its rows in `lambda`.
    pub(super) rows: std::ops::Range<usize>,
    /// Its Jacobian block among the Jacobian's values.
    pub(super) block: std::ops::Range<usize>,
    /// Its columns (those of its constraint).
    pub(super) columns: &'m [usize],
}

/// Columns and rows of a friction joint, at most: a revolute or translational joint between two
/// bodies.
const FRICTION_WIDTH: usize = 6;
const FRICTION_ROWS: usize = 2;

impl Dae<'_> {
    /// Whether a joint has friction.
    pub fn has_friction(&self) -> bool {
        !self.friction.is_empty()
    }

    /// Each joint with friction, in the model's order: its friction, its rows in `lambda`, its
    /// Jacobian block among the Jacobian's values (the elements' blocks one after the other,
    /// row-major, in the system's order) and its columns.
    pub(crate) fn friction_joints(
        &self,
    ) -> impl Iterator<Item = (&Friction, std::ops::Range<usize>, std::ops::Range<usize>, &[usize])> {
        self.friction.iter().map(|s| (s.friction, s.rows.clone(), s.block.clone(), s.columns))
    }

    /// The multipliers' rows and the coordinates' columns that joint friction involves, each
    /// ascending without repeats: `Q_f` is zero off `columns` and depends on `lambda` only
    /// through `rows`.
    pub(crate) fn friction_support(&self) -> (Vec<usize>, Vec<usize>) {
        let mut rows: Vec<usize> = self.friction.iter().flat_map(|s| s.rows.clone()).collect();
        let mut columns: Vec<usize> = self.friction.iter().flat_map(|s| s.columns.iter().copied()).collect();
        for v in [&mut rows, &mut columns] {
            v.sort_unstable();
            v.dedup();
        }
        (rows, columns)
    }

    /// `out (n x rows.len())`, column-major, `= dQ_f / dlambda[rows]`: the exact derivatives of
    /// the joints' friction by the multipliers of `rows` ([`Dae::friction_support`]'s), positions
    /// as at the last [`Dae::positions`].
    pub(crate) fn friction_by_multipliers(
        &self,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        rows: &[usize],
        out: &mut [f64],
    ) {
        let n = self.n;
        out.fill(0.0);
        for (k, slot) in self.friction.iter().enumerate() {
            let count = slot.rows.len();
            let (by_l, _) = self.slot_derivatives(k, q, qdot, multipliers, 1.0);
            for (r, row) in slot.rows.clone().enumerate() {
                let Ok(j) = rows.binary_search(&row) else { continue };
                for (c, &col) in slot.columns.iter().enumerate() {
                    out[j * n + col] += by_l[c * count + r];
                }
            }
        }
    }

    /// The exact derivatives of slot `k`'s friction ([`Friction::derivatives`]) with the
    /// multipliers `multipliers / per`: by its multipliers `(columns x rows)` and by its
    /// velocities `(columns x columns)`, row-major.
    pub(super) fn slot_derivatives(
        &self,
        k: usize,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        per: f64,
    ) -> ([f64; FRICTION_WIDTH * FRICTION_ROWS], [f64; FRICTION_WIDTH * FRICTION_WIDTH]) {
        let slot = &self.friction[k];
        let (w, rows) = (slot.columns.len(), slot.rows.len());
        let (mut v, mut lambda) = ([0.0; FRICTION_WIDTH], [0.0; FRICTION_ROWS]);
        gather(qdot, slot.columns, &mut v[..w]);
        for (l, &x) in lambda.iter_mut().zip(&multipliers[slot.rows.clone()]) {
            *l = x / per;
        }
        let (mut by_l, mut by_v) = ([0.0; FRICTION_WIDTH * FRICTION_ROWS], [0.0; FRICTION_WIDTH * FRICTION_WIDTH]);
        let mut work = [Dual::new(0.0, 0.0); 2 * FRICTION_WIDTH + FRICTION_ROWS];
        let config = Config::new(q, &self.rot);
        let block = &self.jac[slot.block.clone()];
        let lambda = &lambda[..rows];
        slot.friction.derivatives(&config, slot.columns, block, &v[..w], lambda, &mut by_l, &mut by_v, &mut work);
        (by_l, by_v)
    }

    /// `out (n) += Q_f(q, qdot, multipliers / per)`: the joints' friction ([`Friction`]) with the
    /// multipliers `multipliers / per` (`per`: `1 + alpha` where an integrator's unknowns are
    /// `(1 + alpha) lambda`, else 1); positions as at the last [`Dae::positions`]. Each joint's
    /// friction (on its first body: N m or N) goes to `values` when it is given.
    pub fn add_friction(
        &self,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        per: f64,
        out: &mut [f64],
        mut values: Option<&mut Vec<f64>>,
    ) {
        for (k, slot) in self.friction.iter().enumerate() {
            let (mut lambda, mut load) = ([0.0; FRICTION_ROWS], [0.0; FRICTION_WIDTH]);
            for (l, &x) in lambda.iter_mut().zip(&multipliers[slot.rows.clone()]) {
                *l = x / per;
            }
            let value = self.slot_friction(k, q, qdot, &lambda, &mut load);
            for (&c, &f) in slot.columns.iter().zip(&load) {
                out[c] += f;
            }
            if let Some(values) = values.as_mut() {
                values.push(value);
            }
        }
    }

    /// The friction of slot `k` with its multipliers `lambda` (its rows'): `Q_f` on its columns
    /// into `load`, and its value.
    fn slot_friction(&self, k: usize, q: &[f64], qdot: &[f64], lambda: &[f64], load: &mut [f64]) -> f64 {
        let slot = &self.friction[k];
        let w = slot.columns.len();
        let mut v = [0.0; FRICTION_WIDTH];
        gather(qdot, slot.columns, &mut v[..w]);
        let block = &self.jac[slot.block.clone()];
        let config = Config::new(q, &self.rot);
        slot.friction.load(&config, slot.columns, block, &v[..w], &lambda[..slot.rows.len()], &mut load[..w])
    }

    /// [`Dae::accelerations`] with joint friction: Newton on `(qddot, lambda)`, at least the three
    /// solves of the frictionless refinement.
    pub(super) fn friction_newton(
        &mut self,
        q: &[f64],
        qdot: &[f64],
        t: f64,
        out: &mut [f64],
        r: &mut [f64],
    ) -> Result<(), Error> {
        let n = self.n;
        let mut worst = (0, f64::INFINITY);
        for it in 0..NEWTON_FRICTION_ITERATIONS {
            self.residual(q, qdot, t, out, r);
            self.factor(q, qdot, t, 0.0, 0.0, &out[n..], 1.0).map_err(|e| super::super::factor_error(e, t))?;
            self.solve(r);
            for (o, d) in out.iter_mut().zip(r.iter()) {
                *o += d;
            }
            worst = self.friction_change(q, qdot, &r[n..], &out[n..]);
            if it >= 2 && worst.1 <= FRICTION_RTOL {
                return Ok(());
            }
        }
        Err(self.friction_error(worst, t, NEWTON_FRICTION_ITERATIONS, "the accelerations and reactions"))
    }

    /// How far an iteration that changed the multipliers by `delta (m)` to `lambda (m)` is from
    /// converged: the largest change relative to the largest multiplier (0 when both are 0); and
    /// the friction joint whose friction force changed most with it (its generalised force's
    /// largest entry, N or N m), to blame if it does not converge.
    pub(crate) fn friction_change(&self, q: &[f64], qdot: &[f64], delta: &[f64], lambda: &[f64]) -> (usize, f64) {
        let size = lambda.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let largest = delta.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let relative = if largest == 0.0 { 0.0 } else { largest / size };
        let change = |k: usize| {
            let rows = self.friction[k].rows.clone();
            let (mut after, mut before) = ([0.0; FRICTION_ROWS], [0.0; FRICTION_ROWS]);
            for (r, row) in rows.enumerate() {
                after[r] = lambda[row];
                before[r] = lambda[row] - delta[row];
            }
            let (mut a, mut b) = ([0.0; FRICTION_WIDTH], [0.0; FRICTION_WIDTH]);
            self.slot_friction(k, q, qdot, &after, &mut a);
            self.slot_friction(k, q, qdot, &before, &mut b);
            a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        let changes: Vec<f64> = (0..self.friction.len()).map(change).collect();
        let blamed = (0..changes.len()).fold(0, |b, k| if changes[k] > changes[b] { k } else { b });
        (blamed, relative)
    }

    /// [`Error::Friction`] at the friction joint `k` of [`Dae::friction_change`], whose `what`
    /// still changed by `change` of the largest multiplier after `iterations` iterations at `t`.
    pub(crate) fn friction_error(&self, (k, change): (usize, f64), t: f64, iterations: usize, what: &str) -> Error {
        let slot = &self.friction[k];
        Error::Friction {
            time: t,
            row: RowName { element: slot.name.to_string(), equation: "friction".into() },
            detail: format!(
                "{what} and the friction that depends on them did not converge in {iterations} iterations (the \
                 multipliers still changed by {change:.3e} of the largest): the friction may lock the mechanism here \
                 (a self-locking position, where no finite effort moves it), or the coefficient is too large for \
                 this geometry"
            ),
        }
    }

    /// Power of the joints' friction `Q_f . qdot` (at most zero), W; positions as at the last
    /// [`Dae::positions`].
    pub fn friction_power(&self, q: &[f64], qdot: &[f64], lambda: &[f64]) -> f64 {
        if self.friction.is_empty() {
            return 0.0;
        }
        let mut load = vec![0.0; self.n];
        self.add_friction(q, qdot, lambda, 1.0, &mut load, None);
        load.iter().zip(qdot).map(|(f, v)| f * v).sum()
    }
}
