//! HHT-alpha on the index-3 equations with step-size control (Hilber, Hughes and Taylor 1977;
//! for constrained multibody systems Negrut, Rampalli, Ottarsson and Sajdak 2007, "On the use of
//! the HHT method in the context of index 3 differential algebraic equations of multibody
//! dynamics", J. Comput. Nonlinear Dynam. 2(1)).
//!
//! With `alpha` in `[-1/3, 0]`, `beta = (1 - alpha)^2 / 4`, `gamma = 1/2 - alpha`, one step from
//! `t_n` to `t_{n+1} = t_n + h` solves for `qddot_{n+1}` and `lambda_{n+1}`:
//!
//! ```text
//! q_{n+1}    = q_n + h qdot_n + h^2/2 ((1 - 2 beta) qddot_n + 2 beta qddot_{n+1})      (Newmark)
//! qdot_{n+1} = qdot_n + h ((1 - gamma) qddot_n + gamma qddot_{n+1})
//! M qddot_{n+1} + (1 + alpha) F_{n+1} - alpha F_n = 0,   F = Phi_q^T lambda - Q
//! Phi(q_{n+1}, t_{n+1}) / (beta h^2) = 0                                               (scaled)
//! ```
//!
//! Newton in `(qddot, mu = (1 + alpha) lambda)` with the matrix [`Dae::factor`]`(c_v, c_q)`,
//! `c_v = (1 + alpha) gamma h`, `c_q = (1 + alpha) beta h^2` (the scaled form of Negrut et al.
//! section 3.1, well conditioned as `h -> 0`), from `qddot`, `mu` extrapolated from the last two
//! steps. The matrix is kept across iterations and steps while Newton contracts; it is
//! re-evaluated when convergence is slow and after a change of step of more than 20%. Newton
//! has converged when both the position and the velocity corrections are below
//! `NEWTON_TOL` (0.1%) of the tolerance, or are round-off ([`super::roundoff_ratio`]).
//!
//! Error control (Negrut et al. section 3.3): the local error of the positions is estimated as
//! `(beta - 1/6) h^2 (qddot_{n+1} - qddot_n)`; a step is accepted when its weighted RMS norm
//! ([`super::wrms`]) is at most 1, or when the estimate is round-off of the positions
//! ([`super::roundoff_ratio`]), or within `NOISE_MARGIN` times the noise Newton left when it
//! stopped at round-off (near a singular position, where the Jacobian amplifies round-off); the
//! step is then kept. The next step is sized for `0.9^3` of the
//! tolerance from the error coefficient `err / h^3` extrapolated to the centre of that step
//! (`Controller`: the classical `h (0.9^3 / err)^(1/3)` lags the motion and costs a pendulum its
//! energy), within `[h / 5, 2 h]` and the maximum step. Output by quintic Hermite interpolation
//! ([`super::hermite5`]) of each accepted step.

use super::{hermite5, step_failure, wrms, Dae, DynamicStats, IntegratorSettings, Outcome, Output, Span, Start};
use crate::error::Error;

/// Newton iterations per attempt. Four: from the extrapolated predictor a converging iteration
/// reaches the tolerance in two or three; more means the matrix is stale or the step too large.
const MAX_NEWTON: usize = 4;
/// Newton has converged when the weighted norms of the position and the velocity corrections are
/// below this fraction of the error tolerance.
///
/// The error Newton leaves is not like the truncation error: it has the sign of the predictor's
/// error step after step and is carried forward, so it adds up over the run (on a pendulum it
/// changes the energy, hence the period, and the phase error grows with the square of time).
/// Testing only the position correction `beta h^2 da` at 1% of the tolerance (as before) let the
/// velocity correction `gamma h da`, `gamma / (beta h)` times larger (1,900 times at h = 1e-3),
/// through at about `20 tol` per step: the global error then fell only ~5 times per 100 times
/// tighter tolerance and the A01 pendulum lost its phase. Measured on A01 at a fixed step of
/// 1e-3 s over 2000 s (tolerance 1e-8): the error is 0.13 m with both corrections at 1e-2,
/// 2.18e-2 m at 1e-3, and 2.17e-2 m at 1e-4 and 1e-5: 1e-3 is where Newton's share vanishes.
const NEWTON_TOL: f64 = 1e-3;

struct Hht<'a, 'm> {
    dae: &'a mut Dae<'m>,
    n: usize,
    alpha: f64,
    beta: f64,
    gamma: f64,
    rtol: f64,
    atol: f64,
    /// State at `t_n`.
    t: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    /// (n) `F_n = Phi_q^T lambda_n - Q_n`.
    f: Vec<f64>,
    /// (m) `mu_n = (1 + alpha) lambda_n`.
    mu: Vec<f64>,
    /// Iterate of the step being tried.
    q1: Vec<f64>,
    v1: Vec<f64>,
    a1: Vec<f64>,
    mu1: Vec<f64>,
    /// (n + m) residual and Newton step.
    r: Vec<f64>,
    /// (n) scratch.
    work: Vec<f64>,
    /// (m) zeros.
    zero_m: Vec<f64>,
    /// (n) the applied loads at the start, middle and end of the step, and the state at its
    /// middle ([`Self::load_bump`]).
    loads: [Vec<f64>; 3],
    mid: [Vec<f64>; 2],
    /// Step size of the current factorization, or `None` when there is none.
    factored_h: Option<f64>,
    /// When this step's Newton stopped at round-off ([`Self::at_roundoff`]): its last position
    /// correction, the noise it left in the iterate, in units of [`super::roundoff_ratio`]'s
    /// floor and at least 1 (above 1 only when settled near a singular position).
    noise: Option<f64>,
    stats: DynamicStats,
}

/// How a Newton attempt ended.
enum Newton {
    Converged,
    /// Did not converge; `fresh` tells whether the matrix was evaluated in this attempt.
    Failed {
        fresh: bool,
    },
}

impl Hht<'_, '_> {
    /// The error of the method's assumption that the accelerations vary linearly over the step
    /// `h`, measured by the applied loads at its middle: a parabolic bump of height
    /// `d = M^-1 (Q(t + h/2) - (Q(t) + Q(t + h)) / 2)` on the linear accelerations changes the
    /// velocities at the end of the step by `2 h d / 3`; returned as its weighted RMS norm
    /// against the velocities. Gravity gives nothing and a smooth load `O(h^3)`, the order of the
    /// position estimate. A load singular in time inside the step (`1/(t - c)`) gives a large `d`,
    /// which the position estimate alone does not see: the velocity's singularity is only
    /// logarithmic, so a step of `2.3e-7` s straddling the pole changed the positions by less than
    /// the tolerance while its bump changed the velocity by 47 rad/s, and the run ended `ok`.
    /// With this test the steps shrink onto the pole, where [`step_failure`] names the load.
    fn load_bump(&mut self, h: f64) -> f64 {
        let n = self.n;
        let [q_mid, v_mid] = &mut self.mid;
        for k in 0..n {
            q_mid[k] = 0.5 * (self.q[k] + self.q1[k]);
            v_mid[k] = 0.5 * (self.v[k] + self.v1[k]);
        }
        let [start, middle, end] = &mut self.loads;
        self.dae.load(&self.q, &self.v, self.t, start);
        self.dae.load(q_mid, v_mid, self.t + 0.5 * h, middle);
        self.dae.load(&self.q1, &self.v1, self.t + h, end);
        // A massless coordinate's acceleration is set by the constraints, not by its loads.
        let bumps = (0..n).filter(|&k| self.dae.mass[k] > 0.0).map(|k| {
            let d = (middle[k] - 0.5 * (start[k] + end[k])) / self.dae.mass[k];
            (2.0 * h * d / 3.0, self.v[k].abs().max(self.v1[k].abs()))
        });
        wrms(bumps, n, self.rtol, self.atol)
    }

    /// `(q1, v1)` from `a1` by the Newmark formulas over a step `h`.
    fn newmark(&mut self, h: f64) {
        let (b, g) = (self.beta, self.gamma);
        for k in 0..self.n {
            self.q1[k] = self.q[k] + h * self.v[k] + 0.5 * h * h * ((1.0 - 2.0 * b) * self.a[k] + 2.0 * b * self.a1[k]);
            self.v1[k] = self.v[k] + h * ((1.0 - g) * self.a[k] + g * self.a1[k]);
        }
    }

    /// Newton iterations at `t1 = t + h`, starting from `a1`, `mu1`.
    fn newton(&mut self, h: f64) -> Result<Newton, Error> {
        let (n, t1) = (self.n, self.t + h);
        let (al, b) = (self.alpha, self.beta);
        let mut fresh = false;
        let mut previous = f64::INFINITY;
        self.noise = None;
        for it in 0..MAX_NEWTON {
            self.newmark(h);
            self.dae.positions(&self.q1, t1);
            // r = -[M a + Phi_q^T mu - (1 + alpha) Q - alpha F_n;  Phi / (beta h^2)]
            self.dae.load(&self.q1, &self.v1, t1, &mut self.work);
            self.dae.add_friction(&self.q1, &self.v1, &self.mu1, 1.0 + al, &mut self.work, None);
            let (r1, r2) = self.r.split_at_mut(n);
            for k in 0..n {
                r1[k] = (1.0 + al) * self.work[k] + al * self.f[k] - self.dae.mass[k] * self.a1[k];
            }
            self.work.fill(0.0);
            self.dae.add_jt(&self.mu1, &mut self.work);
            for k in 0..n {
                r1[k] -= self.work[k];
            }
            for (r, p) in r2.iter_mut().zip(&self.dae.phi) {
                *r = -p / (b * h * h);
            }
            if !self.r.iter().all(|x| x.is_finite()) {
                return Ok(Newton::Failed { fresh });
            }
            let stale = self.factored_h.is_none_or(|fh| !(0.8..=1.25).contains(&(h / fh)));
            if stale || (it >= 2 && !fresh) {
                self.dae
                    .factor(
                        &self.q1,
                        &self.v1,
                        t1,
                        (1.0 + al) * self.gamma * h,
                        (1.0 + al) * b * h * h,
                        &self.mu1,
                        1.0 + al,
                    )
                    .map_err(|e| super::factor_error(e, t1))?;
                self.factored_h = Some(h);
                fresh = true;
            }
            self.dae.solve(&mut self.r);
            self.stats.newton_iterations += 1;
            for k in 0..n {
                self.a1[k] += self.r[k];
            }
            for (mu, d) in self.mu1.iter_mut().zip(&self.r[n..]) {
                *mu += d;
            }
            // The corrections of positions and velocities, beta h^2 da and gamma h da, weighted
            // like the error test: both, since a velocity error left by Newton is carried into
            // every later step (see NEWTON_TOL).
            let (cq, cv, da) = (b * h * h, self.gamma * h, &self.r[..n]);
            let dq = wrms(da.iter().zip(&self.q1).map(|(e, y)| (cq * e, *y)), n, self.rtol, self.atol).max(wrms(
                da.iter().zip(&self.v1).map(|(e, y)| (cv * e, *y)),
                n,
                self.rtol,
                self.atol,
            ));
            let rate = dq / previous;
            if dq <= NEWTON_TOL
                || (it > 0 && rate < 1.0 && rate / (1.0 - rate) * dq <= NEWTON_TOL)
                || self.at_roundoff(h, (it > 0 && rate > 0.5) || it + 1 == MAX_NEWTON, fresh)
            {
                self.newmark(h);
                return Ok(Newton::Converged);
            }
            if it > 0 && rate > 0.9 {
                break;
            }
            previous = dq;
        }
        Ok(Newton::Failed { fresh })
    }
}

impl Hht<'_, '_> {
    /// Whether the last correction `da` (in `r`) is round-off, so that Newton can do no better
    /// ([`super::roundoff_ratio`]). In the index-3 equations the accelerations answer the
    /// position constraints scaled by `1 / (beta h^2)`, so the noise of `da` is round-off of the
    /// positions over `beta h^2`, and the velocity correction `gamma h da` then carries that
    /// noise times `gamma / (beta h)`, far above the velocities' own round-off at small steps.
    /// Hence round-off is:
    ///
    /// - the position correction at round-off, and the velocity correction either at its own
    ///   round-off or no longer falling (`stalled`: the iteration has met the floor); or
    /// - a fresh matrix making no progress while the constraints hold to round-off: near a
    ///   singular position (A02's flat positions) the nearly singular matrix amplifies the
    ///   round-off of the residual into position corrections a few times the floor (measured
    ///   2.6 times on A02 at 1e-8, constraint residual 7e-15, while Newton stalled).
    ///
    /// When it is, the position correction's ratio is kept in `noise` for the error test.
    fn at_roundoff(&mut self, h: f64, stalled: bool, fresh: bool) -> bool {
        let n = self.n;
        let scale = |y: &[f64]| y.iter().fold(0.0f64, |x, y| x.max(y.abs()));
        let qscale = scale(&self.q1);
        for k in 0..n {
            self.work[k] = self.beta * h * h * self.r[k];
        }
        let position = super::roundoff_ratio(&self.work, &self.q1, qscale);
        // The constraint residual (of the iterate before this correction) against zero.
        let settled = stalled && fresh && super::roundoff_ratio(&self.dae.phi, &self.zero_m, qscale) <= 1.0;
        let at_floor = settled
            || position <= 1.0 && {
                for k in 0..n {
                    self.work[k] = self.gamma * h * self.r[k];
                }
                stalled || super::roundoff_ratio(&self.work, &self.v1, scale(&self.v1)) <= 1.0
            };
        if at_floor {
            self.noise = Some(position.max(1.0));
        }
        at_floor
    }
}

/// How far above the noise Newton left in the positions the error estimate may lie and still be
/// that noise. The last correction samples the noise once (the estimate measured up to 2.1 times
/// it on A02 at 1e-11). Noise in the poorly determined direction of a singular position is not
/// removed by the constraints: through the accelerations it enters the velocities as
/// `gamma / (beta h)` times itself and the next positions as `gamma / beta` (1.9) times, damped
/// per step by the method's spectral radius `(1 + alpha) / (1 - alpha)` (0.54), which sums to
/// about 4. Measured on A02 at 1e-12: with 4 the estimate reached 5.4 times the noise over a few
/// steps and the run stopped at 0.7215 s; with 8 it runs at 1e-12 and 1e-13.
const NOISE_MARGIN: f64 = 8.0;

/// The same for a Newton that stopped at round-off with its last correction within the floor:
/// the positions of this step and the last each carry up to a unit of noise, which reaches the
/// estimate as 0.6 times itself plus what the velocities carry forward (about 4 in all, see
/// `NOISE_MARGIN`). Measured on A02 at 1e-12 before its first flat position, where Newton has not
/// yet settled: the estimate at a constant step rose to 2.2 units, and with a floor of 2 the run
/// stopped at 0.7204 s (1e-13: 0.7195 s). The price is accuracy at tolerances within a few units
/// of round-off: the quick-return at 1e-12 ends 3.2e-7 off in 80,227 steps (1.8e-7 in 88,118
/// with a floor of 1; 5.3e-7 with 8).
const STOP_MARGIN: f64 = 4.0;

/// Accepted steps whose Newton did not stop at round-off after which its noise is forgotten: 8,
/// as `bdf` keeps a settled Newton's noise for its 8 history nodes.
const NOISE_MEMORY: usize = 8;

/// The error estimate a step is sized for: `0.9^3`, the classical safety factor 0.9 on the step.
const TARGET: f64 = 0.729;

/// Weight of a new sample in the filtered slope of [`Controller`]: about five steps.
const SLOPE_WEIGHT: f64 = 0.2;

/// Step-size selection centred on the step it sizes.
///
/// The classical choice `h_{n+1} = h_n (TARGET / err_n)^(1/3)` sizes step `n + 1` by the error
/// coefficient `err / h^3 ~ |q'''|` measured on step `n`, whose acceleration difference is
/// centred at `t_n + (1/2 + alpha) h` (the accelerations of HHT lag by `alpha h`), that is
/// `(1 - alpha) h` before the centre of step `n + 1`. On a periodic motion the step then lags
/// the motion by about 1.3 steps; a step that follows the phase but is not symmetric in time
/// breaks the swing-by-swing cancellation of the method's `O(h^2)` energy oscillation, and the
/// energy changes secularly by `-(integral of G d(h^2))` per swing (`h^2 G` the energy error at a
/// constant step). On the A01 pendulum this doubled the energy loss of the method's damping, and
/// with it the phase error (docs/integrators.md). So the logarithm of the error coefficient is
/// extrapolated over those `(1 - alpha) h` with its slope in time, the slope filtered over about
/// five steps (unfiltered, the error estimate's own response to a step change made the
/// controller ring), and the extrapolated step is kept within `[0.8, 1.25]` of the classical one.
#[derive(Default)]
struct Controller {
    /// Filtered `d ln(err / h^3) / dt`.
    slope: Option<f64>,
    /// `ln(err / h^3)` of the last accepted step and the time its estimate is centred at.
    last: Option<(f64, f64)>,
}

impl Controller {
    /// The factor on `h` after a step `[t, t + h]` with error estimate `err`.
    fn factor(&mut self, err: f64, t: f64, h: f64, alpha: f64) -> f64 {
        let err = err.max(1e-10);
        let classical = (TARGET / err).powf(1.0 / 3.0).clamp(0.2, 2.0);
        if err > 1.0 {
            return classical;
        }
        let l = (err / (h * h * h)).ln();
        let centre = t + (0.5 + alpha) * h;
        let mut factor = classical;
        if let Some((l0, t0)) = self.last {
            let sample = (l - l0) / (centre - t0);
            let slope = self.slope.map_or(sample, |s| s + SLOPE_WEIGHT * (sample - s));
            self.slope = Some(slope);
            let predicted = l + slope * (1.0 - alpha) * h;
            let h_next = (TARGET / predicted.exp()).powf(1.0 / 3.0);
            factor = (h_next / h).clamp(0.8 * classical, 1.25 * classical).clamp(0.2, 2.0);
        }
        self.last = Some((l, centre));
        factor
    }
}

/// Integrate from `start` to the output's end time.
pub fn run(dae: &mut Dae<'_>, out: &mut Output, settings: &IntegratorSettings, start: Start) -> Outcome {
    let (n, m) = (dae.n, dae.m);
    let alpha = settings.alpha;
    let run = Span::new(settings, &start, out.t_end(), 0);
    let Start { t, q, qdot, qddot, lambda } = start;
    // F_0 = Phi_q^T lambda_0 - Q_0 = -M qddot_0 at a consistent start.
    let f: Vec<f64> = qddot.iter().zip(&dae.mass).map(|(a, mass)| -mass * a).collect();
    let mu: Vec<f64> = lambda.iter().map(|l| (1.0 + alpha) * l).collect();
    let mut s = Hht {
        dae,
        n,
        alpha,
        beta: (1.0 - alpha) * (1.0 - alpha) / 4.0,
        gamma: 0.5 - alpha,
        rtol: settings.rtol,
        atol: settings.atol,
        t,
        q1: q.clone(),
        v1: qdot.clone(),
        a1: qddot.clone(),
        mu1: mu.clone(),
        q,
        v: qdot,
        a: qddot,
        f,
        mu,
        r: vec![0.0; n + m],
        work: vec![0.0; n],
        zero_m: vec![0.0; m],
        loads: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        mid: [vec![0.0; n], vec![0.0; n]],
        factored_h: None,
        noise: None,
        stats: DynamicStats { max_order_used: 2, ..Default::default() },
    };
    let fixed_step = settings.fixed_step;
    let mut h = fixed_step.unwrap_or(run.h_start);
    let (mut qo, mut vo) = (vec![0.0; n], vec![0.0; n]);
    let mut controller = Controller::default();
    let mut lambda1 = vec![0.0; m];
    // The accelerations and multipliers of the step before, and its size (0: none yet).
    let (mut a_prev, mut mu_prev, mut h_prev) = (vec![0.0; n], vec![0.0; m], 0.0);
    // The position noise of Newton's round-off stops: the largest `Hht::noise` of the attempts
    // since `NOISE_MEMORY` accepted steps without one (`noise_memory` 0: none).
    let (mut noise_amp, mut noise_memory) = (1.0f64, 0usize);
    let outcome = (|| -> Result<(), Error> {
        while run.before_end(s.t) {
            let h_min = run.smallest_step(out, s.dae, &s.q, s.stats.steps, s.t, h, settings, true)?;
            h = run.fit(s.t, h);
            // Predictor: qddot and mu extrapolated linearly from the last two steps (constant on
            // the first step): the starting error O(h^2) rather than O(h), so that Newton's
            // tighter test costs fewer iterations (measured: 12,100 -> 9,500 on the quick-return
            // at 1e-8, 54,000 -> 41,000 at 1e-10).
            let r = if h_prev > 0.0 { h / h_prev } else { 0.0 };
            for k in 0..n {
                s.a1[k] = s.a[k] + r * (s.a[k] - a_prev[k]);
            }
            for k in 0..m {
                s.mu1[k] = s.mu[k] + r * (s.mu[k] - mu_prev[k]);
            }
            let newton = s.newton(h)?;
            let converged = match newton {
                Newton::Converged => true,
                Newton::Failed { fresh: false, .. } => {
                    // Retry once with a fresh matrix before shrinking the step, from the
                    // constant predictor (the safer start).
                    s.factored_h = None;
                    s.a1.copy_from_slice(&s.a);
                    s.mu1.copy_from_slice(&s.mu);
                    matches!(s.newton(h)?, Newton::Converged)
                }
                Newton::Failed { fresh: true, .. } => false,
            };
            if !converged {
                s.stats.newton_failures += 1;
                s.factored_h = None;
                h *= 0.25;
                if h < h_min {
                    let residual = s.dae.phi.iter().fold(0.0f64, |x, p| x.max(p.abs()));
                    let cause = format!(
                        "Newton's method does not converge (constraint residual {residual:.3e}) even with the smallest step"
                    );
                    return Err(step_failure(s.dae, &s.q, s.t, h, &cause));
                }
                continue;
            }
            // Error test on positions.
            let c = s.beta - 1.0 / 6.0;
            for k in 0..n {
                s.work[k] = c * h * h * (s.a1[k] - s.a[k]);
            }
            let mut err = wrms((0..n).map(|k| (s.work[k], s.q1[k].abs().max(s.q[k].abs()))), n, s.rtol, s.atol);
            let bump = if s.dae.forces.is_empty() { 0.0 } else { s.load_bump(h) };
            let qscale = s.q1.iter().fold(0.0f64, |x, y| x.max(y.abs()));
            // Round-off floor: an estimate at the round-off of the positions
            // ([`super::roundoff_ratio`] at most 1) says only that the error is below round-off:
            // the step is accepted and kept, and the controller learns nothing from it (its
            // slope would read the clamped estimate as a growing error coefficient and shrink
            // the step without end). Growing the step instead (as for an error `TARGET * ratio`)
            // measured a rejection every other step on A02 at 1e-12.
            //
            // When Newton stops at round-off it leaves that much noise in the positions, and the
            // estimate `(beta - 1/6) h^2 (a1 - a)` carries the noise of two steps' positions
            // through their accelerations (`(beta - 1/6) / beta`, 0.6, times each), whatever the
            // step. Near a singular position a settled Newton leaves `noise` times the floor. On
            // A02 the estimate then stayed at the noise while the step fell to `6e-14` s and the
            // run stopped at the first flat position (0.72 s): at 1e-11 `4e-11` to `1.5e-10` m,
            // 0.6 to 2.1 times the last correction (`7.3e-11` m); at 1e-12 1.6 times the floor.
            // An estimate up to `NOISE_MARGIN` times the largest recent noise of a settled Newton,
            // or `STOP_MARGIN` times the floor after a Newton stopped at round-off, is that noise.
            if let Some(noise) = s.noise {
                noise_amp = if noise_memory > 0 { noise_amp.max(noise) } else { noise };
                noise_memory = NOISE_MEMORY;
            }
            let floor = match noise_memory {
                0 => 1.0,
                _ if noise_amp > 1.0 => NOISE_MARGIN * noise_amp,
                _ => STOP_MARGIN,
            };
            // (The floor is the positions' own: it never excuses the loads' error.)
            let factor = if err > TARGET && bump <= TARGET && super::roundoff_ratio(&s.work, &s.q1, qscale) <= floor {
                err = TARGET;
                1.0
            } else {
                err = err.max(bump);
                controller.factor(err, s.t, h, s.alpha)
            };
            if err > 1.0 && fixed_step.is_none() {
                s.stats.rejected_steps += 1;
                h *= factor.min(0.9);
                if h < h_min {
                    return Err(step_failure(
                        s.dae,
                        &s.q,
                        s.t,
                        h,
                        &format!("the error test fails (error {err:.3e} of the tolerance) even with the smallest step"),
                    ));
                }
                continue;
            }
            if let Some(r) = s.dae.contact_event(&s.q, &s.q1) {
                // A first contact inside the step: shorter, until the step ends just into it.
                s.stats.rejected_steps += 1;
                h *= r;
                if h < h_min {
                    return Err(step_failure(s.dae, &s.q, s.t, h, super::CONTACT_UNRESOLVED));
                }
                continue;
            }
            // Accept.
            let t1 = s.t + h;
            s.stats.accept(h);
            for (l, mu) in lambda1.iter_mut().zip(&s.mu1) {
                *l = mu / (1.0 + s.alpha);
            }
            out.advance_work(s.dae, t1, &s.q1, &s.v1, &lambda1);
            while let Some(to) = out.due(t1) {
                let theta = ((to - s.t) / h).clamp(0.0, 1.0);
                hermite5(theta, h, [&s.q, &s.v, &s.a], [&s.q1, &s.v1, &s.a1], &mut qo, &mut vo);
                out.push(s.dae, to, &qo, &vo)?;
            }
            // F_{n+1} from the converged equation: M a + (1 + alpha) F_{n+1} - alpha F_n = 0.
            // (With Newton converged as above this equals Phi_q^T lambda - Q evaluated at the new
            // state: measured, the two agree to four digits of the A01 error at fixed steps.)
            for k in 0..n {
                s.f[k] = (s.alpha * s.f[k] - s.dae.mass[k] * s.a1[k]) / (1.0 + s.alpha);
            }
            a_prev.copy_from_slice(&s.a);
            mu_prev.copy_from_slice(&s.mu);
            h_prev = h;
            if s.noise.is_none() {
                noise_memory = noise_memory.saturating_sub(1);
            }
            std::mem::swap(&mut s.q, &mut s.q1);
            std::mem::swap(&mut s.v, &mut s.v1);
            std::mem::swap(&mut s.a, &mut s.a1);
            std::mem::swap(&mut s.mu, &mut s.mu1);
            s.t = t1;
            h = fixed_step.unwrap_or((h * factor).min(run.h_max));
        }
        Ok(())
    })();
    (s.stats, outcome)
}
