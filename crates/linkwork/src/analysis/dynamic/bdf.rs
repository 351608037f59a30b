//! Variable-order (1 to 6), variable-step BDF on the equations of motion, in the manner of
//! DASSL (Brenan, Campbell and Petzold 1996, chapter 5) and Adams GSTIFF.
//!
//! The method works on the first-order form `q' = v`, `M v' + Phi_q^T lambda = Q(q, v, t)`,
//! `Phi(q, t) = 0`. Over the nodes `t_{n+1} > t_n > ... > t_{n+1-k}` it replaces each derivative
//! by the derivative at `t_{n+1}` of the polynomial through the solution at the nodes
//! (the variable-coefficient form):
//!
//! ```text
//! y'_{n+1} = c y_{n+1} + b,    c = sum_{j=1..k} 1 / (t_{n+1} - t_{n+1-j}),   b from the history
//! ```
//!
//! **Index 3** (`formulation: index3`): `v = c q + b_q`, `a = c v + b_v` are functions of
//! `q`, and Newton's method solves `M a + Phi_q^T lambda - Q = 0`, `Phi = 0` for `q` and
//! `lambda` with the scaled matrix [`Dae::factor`]`(1/c, 1/c^2)` in the unknowns
//! `(c^2 dq, dlambda)`: the constraint rows are multiplied by `c^2`, so the matrix has the
//! sizes of `M` and `Phi_q` whatever the step (Bottasso, Bauchau and Cardona 2007), where the
//! unscaled matrix has a condition number growing as `h^-4`.
//!
//! **Stabilised index 2** (`formulation: si2`, the default, as Adams SI2; Gear, Gupta and Leimkuhler 1985):
//! `q` and `v` are both unknowns, the velocity constraints `Phi_q v = nu` join the position
//! constraints, and a second multiplier `mu` (zero on the exact solution) projects the
//! positions back onto `Phi = 0`, mass-orthogonally:
//!
//! ```text
//! M (q' - v) + Phi_q^T mu = 0,   M v' + Phi_q^T lambda = Q,   Phi = 0,   Phi_q v = nu
//! ```
//!
//! Each Newton step solves two systems that share `Phi_q`: `[M, Phi_q^T; Phi_q, 0]` for `mu`
//! and a position correction, then `K(1/c, 1/c^2)` for `(dv, dlambda / c)` (the second
//! factorization is [`Dae::factor_mass`]). The velocities then satisfy their constraints at
//! every step, and the error test may include them without the order reduction that index-3
//! velocities suffer at small steps. Where SI2's Newton fails (a singular position, where its
//! projection divides the round-off of `Phi` by a vanishing singular value) the index-3
//! corrector takes the step, and the next steps test the velocities as index 3 does.
//!
//! **Predictor and corrector.** The predictor is the polynomial through `t_n, ..., t_{n-k}`
//! extrapolated to `t_{n+1}`; Newton starts there, with the matrix kept across iterations and
//! steps while it contracts (it is refreshed when `c` changes by more than 25%, when the
//! contraction is slower than 0.9 per iteration, and after a failure; a Newton that fails with a
//! matrix from an earlier attempt is retried once with a fresh one before the step is reduced,
//! in either corrector). Newton has converged
//! when the estimated distance to the solution, `rate / (1 - rate) |dy|`, is below a third of
//! the error tolerance, as in DASSL; when it stops contracting or runs out of iterations, it has
//! converged if its corrections are round-off ([`super::roundoff_ratio`]), or (index 3, with a
//! fresh matrix) if its iterate satisfies the constraints to round-off (near a singular position
//! the matrix amplifies that round-off over the floor), failed otherwise.
//!
//! **Error test** on positions and velocities (never on the multipliers), in the weighted RMS
//! norm ([`super::wrms`]): in SI2 the local error of order `k` is
//! `alpha_{k+1} |y_{n+1} - P_k(t_{n+1})|`, `alpha_{k+1} = h / (t_{n+1} - t_{n-k})` (DASSL's and
//! IDA's constant, `1/(k+1)` at constant steps), velocities in full. In index 3 the velocities are
//! weighted by the step (`h v`): they are index-2 variables there, whose local error estimate does
//! not shrink with the step like that of the positions (Brenan et al. section 5.4); the constant
//! is the method's own, `1 / (c (t_{n+1} - t_{n-k}))` (`2/9` for BDF2), as DASSL's larger one
//! lifts that estimate's noise over the tolerance. The estimate is floored at round-off
//! (`roundoff_ratio` of `y_{n+1} - P_k(t_{n+1})` when smaller than the norm), so that no tolerance
//! asks the error test to resolve noise. Velocities outside the error test are why
//! index 3's global error is 1e3 to 1e4 times the tolerance (docs/integrators.md).
//!
//! **Order and step** as DASSL: estimates at orders `k - 1` and (after `k + 1` steps at one order)
//! `k + 1` from the same formula with predictors of those orders; the order whose estimate is
//! smallest is taken; the step changes by `r = (2 est + 1e-4)^(-1/(k+1))` when `r >= 2` (to `2 h`)
//! or `r <= 1` (to `h max(0.5, min(0.9, r))`), and otherwise stays, which keeps the matrix valid.
//! The first steps double the step and raise the order until the error estimate objects.
//! After a rejection the step shrinks by `0.9 r` (within `[1/4, 0.9]`), then by `1/4`, then
//! the order drops to 1. Output at the requested times by the interpolating polynomial of the
//! last step (DASSL's DDATRP), for positions and velocities.

use super::{
    step_failure, Dae, DynamicStats, Formulation, IntegratorKind, IntegratorSettings, Outcome, Output, Span, Start,
    CONTACT_UNRESOLVED,
};
use crate::analysis::sensitivity::{DynamicSensitivity, Track};
use crate::error::Error;

/// Newton iterations per attempt, as DASSL.
const MAX_NEWTON: usize = 4;
/// Newton's convergence test: estimated remaining error below this fraction of the error
/// tolerance (DASSL's 0.33).
const NEWTON_TOL: f64 = 0.33;

/// Most nodes kept: order 6 needs 7 for its predictor and 8 to estimate order 7.
const MAX_NODES: usize = 8;

/// The integrator's state.
struct Bdf<'a, 'm> {
    dae: &'a mut Dae<'m>,
    n: usize,
    si2: bool,
    rtol: f64,
    atol: f64,
    /// History, newest first: times and the positions and velocities there.
    ts: Vec<f64>,
    qs: Vec<Vec<f64>>,
    vs: Vec<Vec<f64>>,
    /// (n) accelerations at the start (the predictor of the first step).
    a0: Vec<f64>,
    /// (m) multipliers of the last step.
    lambda: Vec<f64>,
    /// Iterate of the step being tried: positions, velocities, accelerations, multipliers
    /// (`lambda`, and `mu` in SI2).
    q1: Vec<f64>,
    v1: Vec<f64>,
    a1: Vec<f64>,
    lam1: Vec<f64>,
    mu1: Vec<f64>,
    /// (n) `b_q`, `b_v` of the BDF derivatives.
    bq: Vec<f64>,
    bv: Vec<f64>,
    /// (n + m) residuals and steps.
    r: Vec<f64>,
    r2: Vec<f64>,
    /// (n) scratch.
    work: Vec<f64>,
    /// (m) scratch.
    rows: Vec<f64>,
    /// (n) Newton's corrections of positions and velocities.
    dq: Vec<f64>,
    dv: Vec<f64>,

    /// Round-off of the positions in the history in units of [`super::roundoff_ratio`]'s floor:
    /// 1, or the largest correction that a settled Newton (index 3 at a singular position) left
    /// in the last `MAX_NODES` steps.
    noise_amp: f64,
    /// The last Newton's settled correction in those units (1 when it converged otherwise).
    settled_amp: f64,
    /// `c` of the current factorization, or `None` when there is none.
    factored_c: Option<f64>,
    stats: DynamicStats,
    /// The sensitivity equations when the run computes design sensitivities, and each
    /// parameter's history and iterate (none otherwise).
    sens: Option<&'a mut DynamicSensitivity<'m>>,
    tracks: Vec<SensTrack>,
}

/// One parameter's sensitivities in the integrator: the history of `dq/dp` and `dqdot/dp` (newest
/// first, beside the state's), their accelerations at the start, the iterate of the step being
/// tried (with `dlambda/dp`) and `dmu/dp`, the accepted `dlambda/dp`, the BDF terms `b` of the
/// step, and the absolute tolerance of its error test.
struct SensTrack {
    qs: Vec<Vec<f64>>,
    vs: Vec<Vec<f64>>,
    a0: Vec<f64>,
    now: Track,
    mu: Vec<f64>,
    lambda: Vec<f64>,
    bq: Vec<f64>,
    bv: Vec<f64>,
    atol: f64,
}

/// How a Newton attempt ended.
enum Newton {
    Converged,
    /// Did not converge; `fresh` tells whether the matrix was evaluated in this attempt.
    Failed {
        fresh: bool,
    },
}

/// Lagrange basis weights at `t` of the polynomial through `nodes`.
fn value_weights(nodes: &[f64], t: f64, w: &mut [f64]) {
    for (j, wj) in w.iter_mut().enumerate().take(nodes.len()) {
        *wj = nodes.iter().enumerate().filter(|&(i, _)| i != j).map(|(_, &ti)| (t - ti) / (nodes[j] - ti)).product();
    }
}

/// Weights of the derivative at `nodes[0]` of the polynomial through `nodes`.
fn derivative_weights(nodes: &[f64], w: &mut [f64]) {
    let t = nodes[0];
    w[0] = nodes[1..].iter().map(|&ti| 1.0 / (t - ti)).sum();
    for j in 1..nodes.len() {
        let num: f64 = nodes[1..].iter().enumerate().filter(|&(i, _)| i + 1 != j).map(|(_, &ti)| t - ti).product();
        let den: f64 = nodes.iter().enumerate().filter(|&(i, _)| i != j).map(|(_, &ti)| nodes[j] - ti).product();
        w[j] = num / den;
    }
}

/// The weighted norm of a change `(dq, dv)` against the iterate `(q1, v1)`, velocities weighted
/// by `vscale` (the step in index 3, 1 in SI2).
fn norm_of(
    q1: &[f64],
    v1: &[f64],
    dq: impl Fn(usize) -> f64,
    dv: impl Fn(usize) -> f64,
    vscale: f64,
    rtol: f64,
    atol: f64,
) -> f64 {
    let n = q1.len();
    let terms = (0..n).flat_map(|k| [(dq(k), q1[k]), (vscale * dv(k), vscale * v1[k])]);
    super::wrms(terms, 2 * n, rtol, atol)
}

/// The corrector's update from its solved systems `(r, r2)` (`r2` the projection's, SI2 only):
/// the multipliers `(lambda, mu)` corrected in place (`mu` in SI2 only), the corrections of the
/// positions and velocities into `(dq, dv)` (in index 3 the velocity follows the positions,
/// `dv = c dq`; in SI2 `dq = (dv - w) / c` with `w` the projection's).
fn corrections(
    si2: bool,
    c: f64,
    (r, r2): (&[f64], &[f64]),
    (lambda, mu): (&mut [f64], &mut [f64]),
    (dq, dv): (&mut [f64], &mut [f64]),
) {
    let n = dq.len();
    if si2 {
        for (mu, y) in mu.iter_mut().zip(&r2[n..]) {
            *mu -= y;
        }
        for (l, d) in lambda.iter_mut().zip(&r[n..]) {
            *l += c * d;
        }
        for i in 0..n {
            dq[i] = (r[i] - r2[i]) / c;
            dv[i] = r[i];
        }
    } else {
        for (l, d) in lambda.iter_mut().zip(&r[n..]) {
            *l += d;
        }
        for i in 0..n {
            dq[i] = r[i] / (c * c);
            dv[i] = r[i] / c;
        }
    }
}

/// Newton's contraction after iteration `it` (from 0) whose correction has the norm `d`, the
/// last one's `previous`: updates `ss = rate / (1 - rate)` and returns whether it has stalled
/// (contracting slower than 0.9, or out of iterations). The contraction of the last iteration
/// (Hairer and Wanner's RADAU5). DASSL's mean contraction since the first correction,
/// `(d / d_0)^(1 / it)`, was tried: a slow first contraction then fails steps that converge (SI2
/// BDF5 at h = 0.05 s in order_tests.rs), which shrinks the step by 4.
fn contraction(it: usize, d: f64, previous: f64, ss: &mut f64) -> bool {
    let mut stalled = it + 1 == MAX_NEWTON;
    if it > 0 {
        let rate = d / previous;
        if rate > 0.9 {
            stalled = true;
            *ss = f64::INFINITY;
        } else {
            *ss = rate / (1.0 - rate);
        }
    }
    stalled
}

/// A history of the integrator, newest first: the times and the positions and velocities there
/// (the state's, or one parameter's sensitivities).
struct History<'h> {
    ts: &'h [f64],
    qs: &'h [Vec<f64>],
    vs: &'h [Vec<f64>],
}

impl History<'_> {
    /// Predict `(q1, v1)` at `t1` with order `k` (the first step: the Taylor predictor with the
    /// start's accelerations `a0`) and set `(bq, bv)`, the `b` of the corrector. Returns `c`.
    fn predict(
        &self,
        k: usize,
        t1: f64,
        a0: &[f64],
        (q1, v1): (&mut [f64], &mut [f64]),
        (bq, bv): (&mut [f64], &mut [f64]),
    ) -> f64 {
        let n = q1.len();
        let h = t1 - self.ts[0];
        if self.ts.len() == 1 {
            // First step: the Taylor predictor from the consistent start.
            for i in 0..n {
                q1[i] = self.qs[0][i] + h * self.vs[0][i];
                v1[i] = self.vs[0][i] + h * a0[i];
            }
        } else {
            let mut w = [0.0; MAX_NODES];
            value_weights(&self.ts[..=k], t1, &mut w);
            for i in 0..n {
                q1[i] = (0..=k).map(|j| w[j] * self.qs[j][i]).sum();
                v1[i] = (0..=k).map(|j| w[j] * self.vs[j][i]).sum();
            }
        }
        let mut nodes = [0.0; MAX_NODES];
        nodes[0] = t1;
        nodes[1..=k].copy_from_slice(&self.ts[..k]);
        let mut d = [0.0; MAX_NODES];
        derivative_weights(&nodes[..=k], &mut d);
        for i in 0..n {
            bq[i] = (1..=k).map(|j| d[j] * self.qs[j - 1][i]).sum();
            bv[i] = (1..=k).map(|j| d[j] * self.vs[j - 1][i]).sum();
        }
        d[0]
    }

    /// The error estimate of order `j` of the new point `(q1, v1)` at `t1` against this history
    /// ([`Bdf::error_at`]), in the weighted norm of `(rtol, atol)`; `(dq, dv)` scratch.
    #[allow(clippy::too_many_arguments)]
    fn error(
        &self,
        j: usize,
        t1: f64,
        (q1, v1): (&[f64], &[f64]),
        vscale: f64,
        si2: bool,
        noise_amp: f64,
        (rtol, atol): (f64, f64),
        (dq, dv): (&mut [f64], &mut [f64]),
    ) -> f64 {
        let mut w = [0.0; MAX_NODES];
        value_weights(&self.ts[..=j], t1, &mut w);
        for k in 0..q1.len() {
            dq[k] = q1[k] - (0..=j).map(|i| w[i] * self.qs[i][k]).sum::<f64>();
            dv[k] = v1[k] - (0..=j).map(|i| w[i] * self.vs[i][k]).sum::<f64>();
        }
        let d = norm_of(q1, v1, |k| dq[k], |k| dv[k], vscale, rtol, atol);
        let scale = |y: &[f64]| y.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let mut noise = super::roundoff_ratio(dq, q1, scale(q1));
        if vscale == 1.0 {
            // Velocities tested in full (in index 3 they are differences of the positions and
            // inherit their noise).
            noise = noise.max(super::roundoff_ratio(dv, v1, scale(v1)));
        }
        // Near a singular position the history carries Newton's settled noise, `noise_amp` times
        // the floor (see `newton`).
        let d = d.min(noise / noise_amp);
        if si2 {
            // DASSL's and IDA's constant, `alpha_{j+1} = h / (t1 - t_{n-j})`, `1/(j+1)` at
            // constant steps: `sum_{i<=j} 1/i` times the method's own (the error in `h y'`
            // rather than in `y`).
            d * (t1 - self.ts[0]) / (t1 - self.ts[j])
        } else {
            // Index 3: the method's own constant `1 / (c (t1 - t_{n-j}))` (`2/9` for BDF2). Its
            // step-weighted velocities carry Newton's position noise times `c h`, which does not
            // shrink with the step: DASSL's larger constant lifts it over the tolerance and the
            // step collapses (quick-return at 1e-8: 12477 steps instead of 749).
            let c: f64 = self.ts[..j].iter().map(|&ti| 1.0 / (t1 - ti)).sum();
            d / (c * (t1 - self.ts[j]))
        }
    }
}

impl Bdf<'_, '_> {
    /// The weighted norm of a change `(dq, dv)` against the iterate, velocities weighted by
    /// `vscale` (the step in index 3, 1 in SI2).
    fn norm(&self, dq: impl Fn(usize) -> f64, dv: impl Fn(usize) -> f64, vscale: f64) -> f64 {
        norm_of(&self.q1, &self.v1, dq, dv, vscale, self.rtol, self.atol)
    }

    /// The error estimate of order `j` for the new point `(t1, q1, v1)`:
    /// `|y - P_j(t1)| / (c_j (t1 - t_{n-j}))`, with `P_j` through the `j + 1` newest nodes, in
    /// the weighted norm, floored at round-off: where the difference `y - P_j(t1)` is smaller
    /// than round-off at the state's scale ([`super::roundoff_ratio`] below the norm), the ratio
    /// takes the norm's place. The tolerance is then in effect raised to round-off, as for
    /// Newton: the estimate of noise measures nothing, and at tolerances near round-off it hovers
    /// between 0.25 and 1 whatever the step, which stops the step from growing and ratchets it
    /// down (A02 at `1e-13` fell to `5e-15` s before its flat position). Above `rtol ~ 1e-11`
    /// the ratio is always the larger and this changes nothing.
    fn error_at(&mut self, j: usize, t1: f64, vscale: f64) -> f64 {
        let history = History { ts: &self.ts, qs: &self.qs, vs: &self.vs };
        let (rtol, atol) = (self.rtol, self.atol);
        let tested = (&self.q1[..], &self.v1[..]);
        let error =
            history.error(j, t1, tested, vscale, self.si2, self.noise_amp, (rtol, atol), (&mut self.dq, &mut self.dv));
        if self.tracks.is_empty() {
            return error;
        }
        // The sensitivities' local errors join the state's (IDAS's `errconS`).
        let mut worst = error;
        for tr in &self.tracks {
            let history = History { ts: &self.ts, qs: &tr.qs, vs: &tr.vs };
            let tested = (&tr.now.q[..], &tr.now.v[..]);
            let scratch = (&mut self.dq[..], &mut self.dv[..]);
            worst = worst.max(history.error(j, t1, tested, vscale, self.si2, self.noise_amp, (rtol, tr.atol), scratch));
        }
        worst
    }

    /// Predict `(q1, v1)` at `t1` with order `k` and set `c`, `b_q`, `b_v` of the corrector.
    /// Returns `c`.
    fn predict(&mut self, k: usize, t1: f64) -> f64 {
        let history = History { ts: &self.ts, qs: &self.qs, vs: &self.vs };
        history.predict(k, t1, &self.a0, (&mut self.q1, &mut self.v1), (&mut self.bq, &mut self.bv))
    }

    /// Factorise the Newton matrices at the iterate.
    fn refactor(&mut self, t1: f64, c: f64) -> Result<(), Error> {
        self.dae
            .factor(&self.q1, &self.v1, t1, 1.0 / c, 1.0 / (c * c), &self.lam1, 1.0)
            .map_err(|e| super::factor_error(e, t1))?;
        if self.si2 {
            self.dae.factor_mass().map_err(|e| super::factor_error(e, t1))?;
        }
        self.factored_c = Some(c);
        Ok(())
    }

    /// Newton iterations at `t1` from the predictor.
    fn newton(&mut self, t1: f64, c: f64, vscale: f64) -> Result<Newton, Error> {
        let n = self.n;
        let mut fresh = false;
        let mut previous = f64::INFINITY;
        // No rate is known before the second iteration: the first correction must be small.
        let mut ss = 1e3;
        self.settled_amp = 1.0;
        for it in 0..MAX_NEWTON {
            if !self.si2 {
                for i in 0..n {
                    self.v1[i] = c * self.q1[i] + self.bq[i];
                }
            }
            for i in 0..n {
                self.a1[i] = c * self.v1[i] + self.bv[i];
            }
            self.dae.positions(&self.q1, t1);
            // r = -[M a + Phi_q^T lambda - Q;  c^2 Phi] (index 3) or -[... ; Phi_q v - nu] (SI2).
            self.dae.load(&self.q1, &self.v1, t1, &mut self.work);
            self.dae.add_friction(&self.q1, &self.v1, &self.lam1, 1.0, &mut self.work, None);
            let (r1, r2) = self.r.split_at_mut(n);
            for i in 0..n {
                r1[i] = self.work[i] - self.dae.mass[i] * self.a1[i];
            }
            self.work.fill(0.0);
            self.dae.add_jt(&self.lam1, &mut self.work);
            for i in 0..n {
                r1[i] -= self.work[i];
            }
            if self.si2 {
                self.dae.jv(&self.v1, r2);
                self.dae.nu(&self.q1, t1, &mut self.rows);
                for (r, nu) in r2.iter_mut().zip(&self.rows) {
                    *r = nu - *r;
                }
                // [E1; c E3 - E4] for the projection, E1 = M (c q + b_q - v) + Phi_q^T mu.
                let (p1, p2) = self.r2.split_at_mut(n);
                self.work.fill(0.0);
                self.dae.add_jt(&self.mu1, &mut self.work);
                for i in 0..n {
                    p1[i] = self.dae.mass[i] * (c * self.q1[i] + self.bq[i] - self.v1[i]) + self.work[i];
                }
                for ((p, phi), e4) in p2.iter_mut().zip(&self.dae.phi).zip(r2.iter()) {
                    *p = c * phi + e4;
                }
                for x in r1.iter_mut() {
                    *x /= c;
                }
            } else {
                for (r, p) in r2.iter_mut().zip(&self.dae.phi) {
                    *r = -c * c * p;
                }
            }
            if !self.r.iter().chain(&self.r2).all(|x| x.is_finite()) {
                return Ok(Newton::Failed { fresh });
            }
            let stale = self.factored_c.is_none_or(|fc| !(0.8..=1.25).contains(&(c / fc)));
            if stale || (it >= 2 && !fresh) {
                self.refactor(t1, c)?;
                fresh = true;
            }
            self.dae.solve(&mut self.r);
            self.stats.newton_iterations += 1;
            // The corrections of positions and velocities (in index 3 the velocity follows the
            // positions, `dv = c dq`).
            if self.si2 {
                self.dae.solve_mass(&mut self.r2);
            }
            let solved = (&self.r[..], &self.r2[..]);
            corrections(self.si2, c, solved, (&mut self.lam1, &mut self.mu1), (&mut self.dq, &mut self.dv));
            let d = self.norm(|i| self.dq[i], |i| self.dv[i], vscale);
            // Round-off: the corrections against round-off at the scale of the state (the largest
            // position, the largest velocity).
            let qscale = self.q1.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let mut noise = super::roundoff_ratio(&self.dq, &self.q1, qscale);
            if self.si2 {
                let vscale = self.v1.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                noise = noise.max(super::roundoff_ratio(&self.dv, &self.v1, vscale));
            }
            for i in 0..n {
                self.q1[i] += self.dq[i];
                if self.si2 {
                    self.v1[i] += self.dv[i];
                }
            }
            let stalled = contraction(it, d, previous, &mut ss);
            // A Newton that no longer contracts, or has run out of iterations, has converged when
            // its corrections are round-off at the state's scale, or (index 3, a fresh matrix)
            // when the iterate it started this iteration from satisfies the constraints to
            // round-off: near a singular position (the flat N-four-bar) the matrix, whose
            // condition reaches `1e9` there, amplifies the round-off of `Phi` (`7e-15`) into
            // corrections of `1e-11` m that no iteration can remove (the backward error is
            // round-off; hht's test is the same).
            // (Not with contacts: their stiff forces, not the constraints, can stall Newton while
            // `Phi` is at round-off, and a settled step would then pass with its error untested.)
            let settled = stalled && !self.si2 && fresh && !self.dae.has_contacts() && {
                self.rows.fill(0.0);
                super::roundoff_ratio(&self.dae.phi, &self.rows, qscale) <= 1.0
            };
            let converged = ss * d <= NEWTON_TOL || d <= 1e-3 * NEWTON_TOL || (stalled && noise <= 1.0) || settled;
            previous = d;
            if converged {
                if settled && ss * d > NEWTON_TOL {
                    self.settled_amp = noise.max(1.0);
                }
                for i in 0..n {
                    if !self.si2 {
                        self.v1[i] = c * self.q1[i] + self.bq[i];
                    }
                    self.a1[i] = c * self.v1[i] + self.bv[i];
                }
                return Ok(Newton::Converged);
            }
            if stalled {
                break;
            }
        }
        Ok(Newton::Failed { fresh })
    }

    /// The corrector from the predictor of order `k` at `t1` (already set by [`Self::predict`]):
    /// Newton's method, and when it fails with a matrix from an earlier attempt, once more from
    /// the predictor with a matrix evaluated there (DASSL), before the step is reduced. Returns
    /// whether it converged. The index-3 fallback after an SI2 failure goes through here too: it
    /// inherits the matrix SI2 evaluated at its own (diverged) iterate, and near a singular
    /// position it stalls at once at the noise that matrix makes of `Phi`'s round-off; only a
    /// fresh matrix lets `newton` judge that stall (A02 at `1e-12` stopped at 0.7216 s: the stall
    /// is the same at every step size, so reducing the step could not help).
    fn correct(&mut self, k: usize, t1: f64, c: f64, vscale: f64) -> Result<bool, Error> {
        match self.newton(t1, c, vscale)? {
            Newton::Converged => Ok(true),
            Newton::Failed { fresh: true } => Ok(false),
            Newton::Failed { fresh: false } => {
                self.factored_c = None;
                self.predict(k, t1);
                self.lam1.copy_from_slice(&self.lambda);
                self.mu1.fill(0.0);
                Ok(matches!(self.newton(t1, c, vscale)?, Newton::Converged))
            }
        }
    }

    /// The sensitivities of the step just solved at `t1` (order `k`, BDF constant `c`), as
    /// DASPK3 and IDAS's staggered direct method: each parameter's derivative of the discretised
    /// equations (the corrector's own residuals, differentiated along the parameter), linear in
    /// the unknowns, solved by the corrector's iteration with the Newton matrix it has, from the
    /// predictor of the sensitivities' history. The matrix leaves out `(Phi_q^T lambda)_q` (the
    /// module docs of `dae`), so the iteration converges at the state's Newton rate to the exact
    /// solution of the linear equations; its convergence test is Newton's, on the sensitivities'
    /// weights. A matrix from an earlier step that does not converge is evaluated again at the
    /// state once. Returns whether every parameter's iteration converged.
    fn sensitivities(&mut self, k: usize, t1: f64, c: f64, vscale: f64) -> Result<bool, Error> {
        let Some(eq) = self.sens.take() else { return Ok(true) };
        eq.prepare(t1, &self.q1, &self.lam1, self.si2.then_some(&self.mu1[..]));
        let mut tracks = std::mem::take(&mut self.tracks);
        let mut outcome = Ok(true);
        for (j, tr) in tracks.iter_mut().enumerate() {
            let mut fresh = false;
            let converged = loop {
                let history = History { ts: &self.ts, qs: &tr.qs, vs: &tr.vs };
                history.predict(k, t1, &tr.a0, (&mut tr.now.q, &mut tr.now.v), (&mut tr.bq, &mut tr.bv));
                tr.now.lambda.copy_from_slice(&tr.lambda);
                tr.mu.fill(0.0);
                match self.sensitivity_iterations(eq, j, tr, t1, c, vscale) {
                    Ok(true) => break Ok(true),
                    Ok(false) if fresh => break Ok(false),
                    Ok(false) => {
                        self.dae.positions(&self.q1, t1);
                        if let Err(e) = self.refactor(t1, c) {
                            break Err(e);
                        }
                        fresh = true;
                    }
                    Err(e) => break Err(e),
                }
            };
            match converged {
                Ok(true) => {}
                other => {
                    outcome = other;
                    break;
                }
            }
        }
        self.tracks = tracks;
        self.sens = Some(eq);
        outcome
    }

    /// The iterations of [`Self::sensitivities`] for parameter `j` from its predictor in `tr`.
    fn sensitivity_iterations(
        &mut self,
        eq: &mut DynamicSensitivity<'_>,
        j: usize,
        tr: &mut SensTrack,
        t1: f64,
        c: f64,
        vscale: f64,
    ) -> Result<bool, Error> {
        let n = self.n;
        self.dae.positions(&self.q1, t1);
        let mut previous = f64::INFINITY;
        // No rate is known before the second iteration, as for the state's Newton. (Starting
        // from the rate the state's Newton measured with the same matrix, as IDA does, passed
        // the first correction more often but left the sensitivities' error estimates noisier:
        // the quick-return then took 671 steps instead of 564, and was no faster.)
        let mut ss = 1e3;
        for it in 0..MAX_NEWTON {
            let now = &mut tr.now;
            if !self.si2 {
                for i in 0..n {
                    now.v[i] = c * now.q[i] + tr.bq[i];
                }
            }
            for i in 0..n {
                now.a[i] = c * now.v[i] + tr.bv[i];
            }
            // The derivative of the corrector's residuals (see `newton`).
            let (r1, r2) = self.r.split_at_mut(n);
            let (p1, p2) = self.r2.split_at_mut(n);
            p1.fill(0.0);
            let projection = if self.si2 { Some((&self.mu1[..], &mut *p1)) } else { None };
            let state = (&self.q1[..], &self.v1[..], &self.a1[..]);
            eq.along(self.dae, j, t1, state, &self.lam1, now, r1, projection, true);
            self.work.fill(0.0);
            self.dae.add_jt(&now.lambda, &mut self.work);
            for i in 0..n {
                r1[i] -= self.work[i];
            }
            eq.constraints_along(j, t1, &self.q1, &now.q, None, &mut self.rows);
            if self.si2 {
                eq.constraints_along(j, t1, &self.q1, &now.q, Some((&self.v1, &now.v)), r2);
                r2.iter_mut().for_each(|r| *r = -*r);
                // d/dp [M (c q + b_q - v) + Phi_q^T mu] (`p1` holds `(d/dp Phi_q)^T mu`).
                for i in 0..n {
                    self.work[i] = c * self.q1[i] + self.bq[i] - self.v1[i];
                }
                self.dae.add_mass_along(eq.parameter(j), &self.work, p1);
                self.work.fill(0.0);
                self.dae.add_jt(&tr.mu, &mut self.work);
                for i in 0..n {
                    p1[i] += self.dae.mass[i] * (c * now.q[i] + tr.bq[i] - now.v[i]) + self.work[i];
                }
                for ((p, phi), e4) in p2.iter_mut().zip(&self.rows).zip(r2.iter()) {
                    *p = c * phi + e4;
                }
                for x in r1.iter_mut() {
                    *x /= c;
                }
            } else {
                for (r, p) in r2.iter_mut().zip(&self.rows) {
                    *r = -c * c * p;
                }
            }
            if !self.r.iter().chain(&self.r2).all(|x| x.is_finite()) {
                return Ok(false);
            }
            self.dae.solve(&mut self.r);
            if self.si2 {
                self.dae.solve_mass(&mut self.r2);
            }
            let solved = (&self.r[..], &self.r2[..]);
            corrections(self.si2, c, solved, (&mut now.lambda, &mut tr.mu), (&mut self.dq, &mut self.dv));
            let d = norm_of(&now.q, &now.v, |i| self.dq[i], |i| self.dv[i], vscale, self.rtol, tr.atol);
            let scale = now.q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let noise = super::roundoff_ratio(&self.dq, &now.q, scale);
            for i in 0..n {
                now.q[i] += self.dq[i];
                if self.si2 {
                    now.v[i] += self.dv[i];
                }
            }
            let stalled = contraction(it, d, previous, &mut ss);
            previous = d;
            if ss * d <= NEWTON_TOL || d <= 1e-3 * NEWTON_TOL || (stalled && noise <= 1.0) {
                for i in 0..n {
                    if !self.si2 {
                        now.v[i] = c * now.q[i] + tr.bq[i];
                    }
                    now.a[i] = c * now.v[i] + tr.bv[i];
                }
                return Ok(true);
            }
            if stalled {
                break;
            }
        }
        Ok(false)
    }

    /// The first step's error estimate of the sensitivities (the largest of the parameters'),
    /// as the state's: the Taylor predictor's difference.
    fn first_sensitivity_error(&self, h: f64, vscale: f64) -> f64 {
        self.tracks
            .iter()
            .map(|tr| {
                let (q0, v0, now) = (&tr.qs[0], &tr.vs[0], &tr.now);
                let dq = |i: usize| now.q[i] - q0[i] - h * v0[i];
                let dv = |i: usize| now.v[i] - v0[i] - h * tr.a0[i];
                norm_of(&now.q, &now.v, dq, dv, vscale, self.rtol, tr.atol)
            })
            .fold(0.0, f64::max)
    }

    /// Add the accepted point `(t1, q1, v1)` to the history, newest first.
    fn push_history(&mut self, t1: f64) {
        if self.ts.len() == MAX_NODES {
            self.ts.pop();
            let (mut q, mut v) = (self.qs.pop().unwrap_or_default(), self.vs.pop().unwrap_or_default());
            q.copy_from_slice(&self.q1);
            v.copy_from_slice(&self.v1);
            self.qs.insert(0, q);
            self.vs.insert(0, v);
        } else {
            self.qs.insert(0, self.q1.clone());
            self.vs.insert(0, self.v1.clone());
        }
        self.ts.insert(0, t1);
        for tr in &mut self.tracks {
            if tr.qs.len() == MAX_NODES {
                tr.qs.pop();
                tr.vs.pop();
            }
            tr.qs.insert(0, tr.now.q.clone());
            tr.vs.insert(0, tr.now.v.clone());
            tr.lambda.copy_from_slice(&tr.now.lambda);
        }
    }
}

/// Integrate from `start` to the output's end time.
pub fn run(dae: &mut Dae<'_>, out: &mut Output, settings: &IntegratorSettings, start: Start) -> Outcome {
    let stop = out.t_end();
    let (stats, outcome) = run_until(dae, out, settings, start, stop, 0);
    (stats, outcome.map(|_| ()))
}

/// Where a run stopped: the time, positions and velocities reached.
pub type Reached = (f64, Vec<f64>, Vec<f64>);

/// Integrate from `start` to `stop` (at most the output's end time), writing the output times
/// on the way, after `taken` steps of the method that hands the run over (counted in the step
/// budget).
pub fn run_until(
    dae: &mut Dae<'_>,
    out: &mut Output,
    settings: &IntegratorSettings,
    start: Start,
    stop: f64,
    taken: usize,
) -> (DynamicStats, Result<Reached, Error>) {
    integrate(dae, out, settings, start, stop, taken, None)
}

/// [`run`] with design sensitivities: `eq` their equations and `tracks` each parameter's at the
/// start ([`DynamicSensitivity::start`]); the outputs get their derivatives.
pub(crate) fn run_sensitive<'m>(
    dae: &mut Dae<'m>,
    out: &mut Output,
    settings: &IntegratorSettings,
    start: Start,
    eq: &mut DynamicSensitivity<'m>,
    tracks: Vec<Track>,
) -> Outcome {
    let stop = out.t_end();
    let (stats, outcome) = integrate(dae, out, settings, start, stop, 0, Some((eq, tracks)));
    (stats, outcome.map(|_| ()))
}

/// [`run_until`], with the sensitivities of [`run_sensitive`] when given.
fn integrate<'a, 'm>(
    dae: &'a mut Dae<'m>,
    out: &mut Output,
    settings: &IntegratorSettings,
    start: Start,
    stop: f64,
    taken: usize,
    sensitivities: Option<(&'a mut DynamicSensitivity<'m>, Vec<Track>)>,
) -> (DynamicStats, Result<Reached, Error>) {
    let (n, m) = (dae.n, dae.m);
    let (sens, tracks) = match sensitivities {
        None => (None, Vec::new()),
        Some((eq, tracks)) => {
            let tracks = tracks
                .into_iter()
                .enumerate()
                .map(|(j, now)| SensTrack {
                    qs: vec![now.q.clone()],
                    vs: vec![now.v.clone()],
                    a0: now.a.clone(),
                    mu: vec![0.0; m],
                    lambda: now.lambda.clone(),
                    bq: vec![0.0; n],
                    bv: vec![0.0; n],
                    // IDAS's `atolS = atol / pbar`: a sensitivity times its parameter's size is
                    // the change of the state for a relative change of 1 of the parameter.
                    atol: settings.atol / eq.size(j),
                    now,
                })
                .collect();
            (Some(eq), tracks)
        }
    };
    let run = Span::new(settings, &start, stop.min(out.t_end()), taken);
    let Start { t, q, qdot, qddot, lambda } = start;
    let k_max = settings.order_limit().clamp(1, IntegratorSettings::order_bound(IntegratorKind::Bdf));
    let mut s = Bdf {
        dae,
        n,
        si2: settings.formulation == Formulation::Si2,
        rtol: settings.rtol,
        atol: settings.atol,
        ts: vec![t],
        q1: q.clone(),
        v1: qdot.clone(),
        a1: qddot.clone(),
        qs: vec![q],
        vs: vec![qdot],
        a0: qddot,
        lam1: lambda.clone(),
        lambda,
        mu1: vec![0.0; m],
        bq: vec![0.0; n],
        bv: vec![0.0; n],
        r: vec![0.0; n + m],
        r2: vec![0.0; n + m],
        work: vec![0.0; n],
        rows: vec![0.0; m],
        dq: vec![0.0; n],
        dv: vec![0.0; n],
        factored_c: None,
        noise_amp: 1.0,
        settled_amp: 1.0,
        stats: DynamicStats::default(),
        sens,
        tracks,
    };
    let mut h = match settings.fixed_step {
        Some(fixed) => settings.initial_step.unwrap_or(fixed).min(fixed),
        None => run.h_start,
    };
    let (mut qo, mut vo) = (vec![0.0; n], vec![0.0; n]);
    let mut k = 1;
    // Steps taken at the current order, and whether the start-up (doubling) phase is on.
    let mut at_order = 0;
    let mut start_up = true;
    let mut failures = 0;
    let mut recent_index3 = 0usize;
    let mut recent_settled = 0usize;
    let outcome = (|| -> Result<(), Error> {
        while run.before_end(s.ts[0]) {
            let t0 = s.ts[0];
            let h_min = run.smallest_step(out, s.dae, &s.qs[0], s.stats.steps, t0, h, settings, true)?;
            h = run.fit(t0, h);
            let t1 = t0 + h;
            // Order k needs k + 1 nodes for its predictor (the first step uses the start's
            // derivatives instead).
            k = k.min(s.ts.len().saturating_sub(1)).max(1);
            let c = s.predict(k, t1);
            s.lam1.copy_from_slice(&s.lambda);
            s.mu1.fill(0.0);
            s.si2 = settings.formulation == Formulation::Si2;
            // Velocities enter the error test in full in SI2, weighted by the step in index 3 (and
            // while the history holds index-3 velocities).
            let nvs = if s.si2 { 1.0 } else { h };
            let mut evs = if recent_index3 > 0 { h } else { nvs };
            let mut converged = s.correct(k, t1, c, nvs)?;
            if !converged && s.si2 && settings.fixed_step.is_none() {
                // SI2's Newton fails where Phi_q loses rank (the flat N-four-bar): its velocity
                // constraints and the projection multiply the round-off of Phi by c / sigma_min.
                // The index-3 corrector, which imposes Phi = 0 alone, takes the step.
                s.si2 = false;
                s.predict(k, t1);
                s.lam1.copy_from_slice(&s.lambda);
                converged = s.correct(k, t1, c, h)?;
                evs = h;
            }
            if converged && !s.tracks.is_empty() {
                let vscale = if s.si2 { 1.0 } else { h };
                converged = s.sensitivities(k, t1, c, vscale)?;
            }
            if !converged {
                s.stats.newton_failures += 1;
                s.factored_c = None;
                start_up = false;
                h *= 0.25;
                if h < h_min {
                    let residual = s.dae.phi.iter().fold(0.0f64, |x, p| x.max(p.abs()));
                    let cause = format!(
                        "Newton's method does not converge (constraint residual {residual:.3e}) even with the smallest step"
                    );
                    return Err(step_failure(s.dae, &s.qs[0], t0, h, &cause));
                }
                continue;
            }
            if s.settled_amp > 1.0 {
                s.noise_amp = s.noise_amp.max(s.settled_amp);
                recent_settled = MAX_NODES + 1;
            }
            let err = if settings.fixed_step.is_some() {
                0.0
            } else if s.ts.len() == 1 {
                let e = s.norm(|i| s.q1[i] - s.qs[0][i] - h * s.vs[0][i], |i| s.v1[i] - s.vs[0][i] - h * s.a0[i], evs);
                if s.tracks.is_empty() {
                    e
                } else {
                    e.max(s.first_sensitivity_error(h, evs))
                }
            } else {
                s.error_at(k, t1, evs)
            };
            let lower = if k > 1 { s.error_at(k - 1, t1, evs) } else { f64::INFINITY };
            if err > 1.0 {
                s.stats.rejected_steps += 1;
                failures += 1;
                start_up = false;
                at_order = 0;
                let (est, order) = if lower <= err { (lower, k - 1) } else { (err, k) };
                let r = match failures {
                    1 => (0.9 * (2.0 * est + 1e-4).powf(-1.0 / (order as f64 + 1.0))).clamp(0.25, 0.9),
                    _ => 0.25,
                };
                k = if failures >= 3 { 1 } else { order };
                h *= r;
                if h < h_min {
                    return Err(step_failure(
                        s.dae,
                        &s.qs[0],
                        t0,
                        h,
                        &format!("the error test fails (error {err:.3e} of the tolerance) even with the smallest step"),
                    ));
                }
                continue;
            }
            if let Some(r) = s.dae.contact_event(&s.qs[0], &s.q1) {
                // A first contact inside the step: shorter, until the step ends just into it, at
                // order 1 (the step falls far below the history's spacing, and the contact's
                // onset is not smooth: a high order would extrapolate free flight through it).
                s.stats.rejected_steps += 1;
                start_up = false;
                at_order = 0;
                k = 1;
                h *= r;
                if h < h_min {
                    return Err(step_failure(s.dae, &s.qs[0], t0, h, CONTACT_UNRESOLVED));
                }
                continue;
            }
            // Accept: estimate the next order before the history moves.
            if !s.si2 && settings.formulation == Formulation::Si2 {
                // The index-3 velocities (differences of positions) stay in the history for
                // MAX_NODES steps; their error estimate does not shrink with the step.
                recent_index3 = MAX_NODES + 1;
            }
            failures = 0;
            recent_index3 = recent_index3.saturating_sub(1);
            recent_settled = recent_settled.saturating_sub(1);
            if recent_settled == 0 {
                s.noise_amp = 1.0;
            }
            at_order += 1;
            let raise = k < k_max && at_order > k && s.ts.len() > k + 1;
            let higher = if raise { s.error_at(k + 1, t1, evs) } else { f64::INFINITY };
            s.stats.accept(h);
            s.stats.max_order_used = s.stats.max_order_used.max(k);
            s.push_history(t1);
            s.lambda.copy_from_slice(&s.lam1);
            out.advance_work(s.dae, t1, &s.q1, &s.v1, &s.lam1);
            while let Some(to) = out.due(t1) {
                let mut w = [0.0; MAX_NODES];
                value_weights(&s.ts[..=k], to, &mut w);
                for i in 0..n {
                    qo[i] = (0..=k).map(|j| w[j] * s.qs[j][i]).sum();
                    vo[i] = (0..=k).map(|j| w[j] * s.vs[j][i]).sum();
                }
                out.push(s.dae, to, &qo, &vo)?;
                if let Some(eq) = s.sens.as_deref_mut() {
                    // The sensitivities by the same interpolant, their accelerations and
                    // multipliers from the output's state.
                    let sol = out.solution().to_vec();
                    let mut at = Vec::with_capacity(s.tracks.len());
                    for (j, tr) in s.tracks.iter().enumerate() {
                        let mut track =
                            Track { q: vec![0.0; n], v: vec![0.0; n], a: vec![0.0; n], lambda: vec![0.0; m] };
                        for i in 0..n {
                            track.q[i] = (0..=k).map(|j| w[j] * tr.qs[j][i]).sum();
                            track.v[i] = (0..=k).map(|j| w[j] * tr.vs[j][i]).sum();
                        }
                        eq.accelerations(s.dae, j, to, &qo, &vo, &sol, &mut track);
                        at.push(track);
                    }
                    eq.push(&mut out.results, s.dae, to, &qo, &vo, &sol, &at)?;
                }
            }
            let (est, order) = if let Some(fixed) = settings.fixed_step {
                // Verification: the order climbs to its limit and stays there; order 6 waits
                // until every node of its history is the fixed step apart (below).
                let even = s.ts.len() == MAX_NODES && s.ts.windows(2).all(|w| w[0] - w[1] >= fixed * (1.0 - 1e-9));
                (err, if k < k_max && (k < 5 || even) { k + 1 } else { k })
            } else if lower <= err {
                (lower, k - 1)
            } else if start_up && k < k_max {
                (err, k + 1)
            } else if higher < err {
                (higher, k + 1)
            } else {
                (err, k)
            };
            if order != k {
                at_order = 0;
            }
            k = order;
            if let Some(fixed) = settings.fixed_step {
                // Verification: no error test; the start-up raises the order one step at a time
                // and grows the step by 1.25 a step from the initial step up to the fixed one.
                // (A variable step is zero-stable only for step ratios below a bound that falls
                // with the order: growing by 1.25 a step at order 6 left an error of 5e-4
                // whatever the fixed step.)
                h = (1.25 * h).min(fixed);
                continue;
            }
            let r = (2.0 * est + 1e-4).powf(-1.0 / (k as f64 + 1.0));
            if start_up && r >= 2.0 {
                h *= 2.0;
            } else {
                start_up = false;
                if r >= 2.0 {
                    h *= 2.0;
                } else if r <= 1.0 {
                    h *= r.clamp(0.5, 0.9);
                }
            }
            h = h.min(run.h_max);
        }
        Ok(())
    })();
    let reached = outcome.map(|()| (s.ts[0], s.qs[0].clone(), s.vs[0].clone()));
    (s.stats, reached)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weights reproduce a cubic's value and derivative exactly on uneven nodes.
    #[test]
    fn weights_are_exact_for_polynomials() {
        let p = |t: f64| 2.0 - t + 0.5 * t * t - 0.25 * t.powi(3);
        let dp = |t: f64| -1.0 + t - 0.75 * t * t;
        let nodes = [1.3, 1.1, 0.95, 0.4];
        let mut w = [0.0; 4];
        value_weights(&nodes, 1.7, &mut w);
        let v: f64 = nodes.iter().zip(&w).map(|(&t, w)| w * p(t)).sum();
        assert!((v - p(1.7)).abs() < 1e-13, "{v}");
        derivative_weights(&nodes, &mut w);
        let d: f64 = nodes.iter().zip(&w).map(|(&t, w)| w * p(t)).sum();
        assert!((d - dp(1.3)).abs() < 1e-12, "{d}");
        // The leading weight is the BDF coefficient c.
        let c: f64 = nodes[1..].iter().map(|t| 1.0 / (1.3 - t)).sum();
        assert!((w[0] - c).abs() < 1e-12);
    }
}
