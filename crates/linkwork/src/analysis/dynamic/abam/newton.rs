//! The dependent-coordinate Newton: an evaluation at `(t, y)` recovers the dependent positions
//! from `Phi(q, t) = 0` and velocities from `Phi_q v = nu`, by a chord iteration with the factors
//! of the dependent block, then the accelerations ([`Split::evaluate`]).

use super::super::roundoff_ratio;
use super::Split;
use crate::error::Error;

/// Newton iterations for the dependent coordinates before the attempt fails. The iteration uses
/// the factors of `B` at the accepted state (a chord method, linear convergence at a rate of the
/// order of the step's motion) and refactors `B` at the iterate when it contracts slowly or has
/// not converged in [`REFACTOR_AFTER`] iterations, so that a far start (an output time early in a
/// long step, a large first step) converges as Newton's method does.
const MAX_NEWTON: usize = 12;
/// Iterations with one factorization of `B` before it is refactored at the iterate.
const REFACTOR_AFTER: usize = 3;
/// Newton has converged when the weighted RMS norm of the correction (weights
/// `atol + rtol |q|`) is below this; Newton's quadratic convergence leaves the remaining error
/// far smaller still, so the dependent coordinates add no noise to the Adams differences.
pub(super) const NEWTON_TOL: f64 = 1e-4;
/// [`NEWTON_TOL`] of the prediction's evaluation. Its derivative only enters the error estimate
/// and the corrector's formula, both times the step (Shampine and Gordon's PECE: the corrected
/// state is evaluated again, and only that evaluation enters the differences); a hundredth of
/// the tolerance changes the estimate by about a hundredth of itself. The prediction starts
/// from a Taylor polynomial and the factors of `B` a step old, which contract slowly when the
/// mechanism turns fast: on the quick-return under its crank torque at `1e-4`, 3.8 iterations
/// and 0.67 refactorizations a prediction at [`NEWTON_TOL`], 2.5 and 0.15 at this, with the
/// same steps and error.
const PREDICTION_NEWTON_TOL: f64 = 1e-2;
/// Newton's first correction is accepted when it is below the tolerance times this factor over
/// the contraction expected of the chord iteration: the rate per unit distance from where `B`
/// was factored, as last measured, times that distance (the rate of a chord iteration grows
/// with the distance from its matrix's point). The expectation is rough: on the loaded
/// quick-return at `1e-4` the measured rate over the expected one had a median of 1.5, a 90th
/// percentile of 12 and a few far beyond. With 100 none of the 1,444 evaluations that stopped
/// after one correction was left more than its tolerance from the solution (at most 0.58 of it,
/// checked against one more correction with `B` factored there); with no factor 88 of 1,772
/// were, by up to 38 times. DASSL keeps its rate factor `S = rate / (1 - rate)` from step to
/// step in the same way, and starts it at 100 (`DDASTP`).
const CHORD_SAFETY: f64 = 100.0;
/// Newton for the dependent positions and velocities stops at a residual or correction of this
/// fraction of [`super::roundoff_ratio`]'s round-off (its `ROUNDOFF_UNITS`, 1000 units of `eps`
/// at the positions' scale): 10 units. Near a flat position (the Jacobian losing rank) `B` is
/// nearly singular, Newton converges linearly, and stopping at 1000 units left `q_D` up to
/// `|B^-1|` times that residual off (240 times `9e-12` m on A02 at `t = 0.7203 s`): the
/// accelerations changed by `2e-6 .. 7e-6` m/s^2 between evaluations, and the error test on that
/// noise crept at the first flat position at `rtol = 1e-12` and stopped at `10.55 s` at `1e-11`.
/// With 100 units `1e-11` runs but ends `2.0e-6` m off; with 10, `1.5e-7` m
/// (docs/integrators.md).
const NEWTON_ROUNDOFF: f64 = 0.01;
/// Newton contracting more slowly than this per iteration with the factors of `B` from the
/// accepted state refactors `B` at the iterate.
const SLOW_RATE: f64 = 0.25;
/// What an evaluation is for: how far its Newton iteration goes, and whether it solves the
/// multipliers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Purpose {
    /// The prediction: Newton to [`PREDICTION_NEWTON_TOL`], no multipliers (its derivative only
    /// enters the error estimate and the corrector's formula).
    Prediction,
    /// A prediction whose error test failed, converged to [`NEWTON_TOL`] before it is judged
    /// again (and, if it still fails, its noise sampled); no multipliers.
    Judged,
    /// A state that may be accepted or written (the correction, an output time): Newton to
    /// [`NEWTON_TOL`], and the multipliers.
    State,
}

impl Purpose {
    fn newton_tol(self) -> f64 {
        if self == Purpose::Prediction {
            PREDICTION_NEWTON_TOL
        } else {
            NEWTON_TOL
        }
    }
}

/// How an evaluation at `(t, y)` ended.
#[derive(Debug, Clone, Copy)]
pub(super) enum Eval {
    /// Converged in `iterations` Newton corrections.
    Done { iterations: usize },
    /// Newton did not converge or `B` is singular; `residual` is the largest `|Phi|` reached.
    Failed { residual: f64 },
}

/// The dependent-coordinate Newton's scratch, its chord rate, and its work.
pub(super) struct Newton {
    /// (r) the dependent positions or velocities of an iterate.
    pub(super) qd: Vec<f64>,
    /// (r) zeros, the size of a residual's exact value.
    pub(super) zeros: Vec<f64>,
    /// The chord iteration's contraction per unit distance from the point where `B` was
    /// factored (the largest coordinate change), as last measured (infinite before).
    pub(super) chord: f64,
    /// Newton iterations in all evaluations.
    pub(super) iterations: usize,
}

impl Newton {
    /// Nothing measured, no work.
    pub(super) fn new() -> Newton {
        Newton { qd: vec![], zeros: vec![], chord: f64::INFINITY, iterations: 0 }
    }

    /// Sizes for `r` dependent coordinates.
    pub(super) fn resize(&mut self, r: usize) {
        self.qd.resize(r, 0.0);
        self.zeros.resize(r, 0.0);
    }
}

impl Split<'_, '_> {
    /// Add the correction in `rhs` to the dependent positions (`positions`) or velocities, copy
    /// their new values into `qd`, and return the correction's weighted RMS norm.
    fn correct_dependent(&mut self, positions: bool) -> f64 {
        let x = if positions { &mut self.q } else { &mut self.v };
        let size = super::super::wrms(
            self.part.dep.iter().zip(&self.blocks.rhs).map(|(&c, &d)| (d, x[c])),
            self.part.dep.len(),
            self.error.rtol,
            self.error.atol,
        );
        for ((&c, &d), out) in self.part.dep.iter().zip(&self.blocks.rhs).zip(self.newton.qd.iter_mut()) {
            x[c] += d;
            *out = x[c];
        }
        size
    }

    /// `(t, y) => (q, v)` and, when `yp` is given, `[qddot; lambda]` into `sol` and
    /// `yp = (v_I, qddot_I)`.
    pub(super) fn evaluate(
        &mut self,
        t: f64,
        y: &[f64],
        yp: Option<&mut [f64]>,
        purpose: Purpose,
    ) -> Result<Eval, Error> {
        let (p, r) = (self.part.ind.len(), self.part.dep.len());
        // Initial q_D, v_D: the last evaluation's when it was at this time (the corrector after
        // the predictor), moved with q_I's change to first order when that evaluation's
        // sensitivities are at hand (`dq_D = -S dq_I`, `dv_D = -S dv_I`: the corrector's first
        // correction is then of second order in the change); else inside the last step (an
        // output time) the quintic Hermite interpolant of its ends; else the Taylor
        // extrapolation of the accepted state (docs/integrators.md says which other starts were
        // tried, and why they were not kept).
        let shift = t == self.t_last && self.blocks.sens_fresh;
        // The error map of the prediction serves the correction's norms too (the same time;
        // the positions differ by the correction, of the order of the error itself).
        self.blocks.sens_fresh = false;
        if t != self.t_last {
            self.error.map_ready = false;
            if self.accepted.ta > self.accepted.tp && t >= self.accepted.tp && t < self.accepted.ta {
                self.accepted.interpolate(t, &mut self.q, &mut self.v);
            } else {
                let dt = t - self.accepted.ta;
                for &c in &self.part.dep {
                    self.q[c] = self.accepted.qa[c] + dt * (self.accepted.va[c] + 0.5 * dt * self.accepted.aa[c]);
                    self.v[c] = self.accepted.va[c] + dt * self.accepted.aa[c];
                }
            }
        }
        if shift {
            for (j, &c) in self.part.ind.iter().enumerate() {
                let (dq, dv) = (y[j] - self.q[c], y[p + j] - self.v[c]);
                let column = &self.blocks.sens[j * r..(j + 1) * r];
                for (&d, &sk) in self.part.dep.iter().zip(column) {
                    self.q[d] -= sk * dq;
                    self.v[d] -= sk * dv;
                }
            }
        }
        self.t_last = f64::NAN;
        for (j, &c) in self.part.ind.iter().enumerate() {
            self.q[c] = y[j];
            self.v[c] = y[p + j];
        }
        // (q_I, q_D guess, t) => q_D with Phi(q, t) = 0 by Newton's method with the factors of
        // B at the accepted state, refactored at the iterate if they converge slowly.
        let (mut iterations, mut residual) = (0, 0.0);
        if r > 0 {
            let scale = self.q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            // Whether B is factored at an iterate of this evaluation; iterations since.
            let (mut fresh, mut since, mut previous) = (false, 0, f64::INFINITY);
            loop {
                // The residual alone: the iteration's matrix is B as factored (the Jacobian at
                // the converged positions is evaluated below).
                self.dae.constraints_only(&self.q, t);
                residual = self.dae.phi.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                if !residual.is_finite() {
                    return Ok(Eval::Failed { residual });
                }
                for (b, &row) in self.blocks.rhs.iter_mut().zip(&self.part.rows) {
                    *b = -self.dae.phi[row];
                }
                // A residual that is round-off at the positions' scale is the solution: near a
                // singular position B amplifies it into corrections that are noise.
                if since > 0 && roundoff_ratio(&self.blocks.rhs, &self.newton.zeros, scale) <= NEWTON_ROUNDOFF {
                    break;
                }
                self.blocks.solve();
                (iterations, since) = (iterations + 1, since + 1);
                let size = self.correct_dependent(true);
                if !size.is_finite() {
                    return Ok(Eval::Failed { residual });
                }
                // The distance to the solution after this correction: `rate / (1 - rate)` times
                // it for a contraction `rate` (the correction itself before a rate is known).
                let rate = size / previous;
                // The chord iteration contracts at a rate proportional to the distance from
                // the point where `B` was factored: measured once a second correction shows it,
                // predicted from that distance before (the correction itself while no rate has
                // been measured).
                let distance =
                    self.q.iter().zip(&self.blocks.factored_q).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                let left = if since == 1 {
                    let expected = CHORD_SAFETY * self.newton.chord * distance;
                    if expected < 1.0 {
                        size * (expected / (1.0 - expected)).min(1.0)
                    } else {
                        size
                    }
                } else {
                    if distance > 0.0 {
                        self.newton.chord = rate / distance;
                    }
                    size * rate / (1.0 - rate).max(f64::MIN_POSITIVE)
                };
                // Converged when that is far below the tolerance, or the correction is
                // round-off: no tolerance asks Newton for less than the positions' rounding.
                if (rate < 1.0 && left <= purpose.newton_tol())
                    || roundoff_ratio(&self.blocks.rhs, &self.newton.qd, scale) <= NEWTON_ROUNDOFF
                {
                    break;
                }
                previous = size;
                if (fresh && since > 1 && rate >= 1.0) || iterations == MAX_NEWTON {
                    return Ok(Eval::Failed { residual });
                }
                if (since > 1 && rate > SLOW_RATE) || since == REFACTOR_AFTER {
                    // Slow with the accepted state's factors: new ones at this iterate.
                    self.dae.positions(&self.q, t);
                    if !self.factor() {
                        return Ok(Eval::Failed { residual });
                    }
                    (fresh, since, previous) = (true, 0, f64::INFINITY);
                }
            }
            // (q, v_I, t) => v_D from Phi_q v = nu: corrections B^-1 (nu - Phi_q v) of the
            // extrapolated v_D, to round-off or far below the tolerance; B refactored here if
            // the old factors converge slowly. The reduced accelerations need B at q: factored
            // here first, the velocities are then a linear solve with exact factors.
            self.dae.positions(&self.q, t);
            // B factored at q: one solve is the exact v_D (the equations are linear in it).
            let exact = self.part.reduced && yp.is_some();
            if exact {
                if !self.factor() {
                    return Ok(Eval::Failed { residual });
                }
                fresh = true;
            }
            self.dae.nu(&self.q, t, &mut self.nu);
            let vscale = self.v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let (mut since, mut previous) = (0, f64::INFINITY);
            let solved = exact && self.part.rows.iter().all(|&row| self.nu[row] == 0.0);
            if solved {
                // No constraint moves with time: `v_D = -S v_I` exactly, with the
                // sensitivities the accelerations use.
                self.blocks.sensitivities(self.dae.jacobian_entries().1);
                for (k, &c) in self.part.dep.iter().enumerate() {
                    self.v[c] = -self
                        .part
                        .ind
                        .iter()
                        .enumerate()
                        .map(|(j, &i)| self.blocks.sens[j * r + k] * self.v[i])
                        .sum::<f64>();
                }
            } else {
                loop {
                    self.dae.jv(&self.v, &mut self.phiv);
                    for (b, &row) in self.blocks.rhs.iter_mut().zip(&self.part.rows) {
                        *b = self.nu[row] - self.phiv[row];
                    }
                    self.blocks.solve();
                    since += 1;
                    let size = self.correct_dependent(false);
                    if !size.is_finite() {
                        return Ok(Eval::Failed { residual });
                    }
                    if exact
                        || size <= NEWTON_TOL
                        || roundoff_ratio(&self.blocks.rhs, &self.newton.qd, vscale) <= NEWTON_ROUNDOFF
                    {
                        break;
                    }
                    let rate = size / previous;
                    previous = size;
                    if (fresh && since > 1 && rate >= 1.0) || since == MAX_NEWTON {
                        return Ok(Eval::Failed { residual });
                    }
                    if (since > 1 && rate > SLOW_RATE) || since == REFACTOR_AFTER {
                        if !self.factor() {
                            return Ok(Eval::Failed { residual });
                        }
                        (fresh, since, previous) = (true, 0, f64::INFINITY);
                    }
                }
            }
        }
        self.newton.iterations += iterations;
        self.t_last = t;
        // (q, v, t) => (qddot, lambda) => y' = (v_I, qddot_I).
        if let Some(yp) = yp {
            self.accelerations(t, purpose == Purpose::State)?;
            if !self.sol.iter().all(|x| x.is_finite()) {
                return Ok(Eval::Failed { residual });
            }
            for (j, &c) in self.part.ind.iter().enumerate() {
                yp[j] = self.v[c];
                yp[p + j] = self.sol[c];
            }
        }
        Ok(Eval::Done { iterations })
    }
}
