//! Coordinate partitioning with variable-order, variable-step Adams-Bashforth-Moulton on the
//! independent coordinates, as Adams' ABAM (Wehage and Haug 1982, "Generalized coordinate
//! partitioning for dimension reduction in analysis of constrained dynamic systems", J. Mech.
//! Des. 104(1); Haug 1989 section 7.3; Shampine and Gordon 1975, "Computer Solution of Ordinary
//! Differential Equations: The Initial Value Problem", Freeman, chapters 4 to 10).
//!
//! **Partition.** A Gaussian elimination of the constraint Jacobian `Phi_q` (`PivotWork::run`:
//! threshold pivoting, each pivot at least 0.9 times the largest remaining entry and, among
//! those, of least Markowitz count) picks `r` pivots, `r` the numerical rank (it stops when no
//! entry above [`crate::linalg::dense::RANK_TOLERANCE`] times the largest of `Phi_q` remains): the
//! pivot rows are the independent rows (redundant rows are left out, they hold wherever the
//! others do), the pivot columns the dependent coordinates `q_D`, and the other `n - r` columns
//! the independent coordinates `q_I`, those with the smallest coupling to the constraints there.
//! Its work grows with the entries of `Phi_q` (linearly in a chain of bodies). The dependent
//! block `B = Phi_q[rows, D]` is a sparse matrix factored by faer's sparse LU
//! ([`crate::linalg::SparseLu`], symbolic analysis once per partition).
//!
//! **ODE.** The state is `y = (q_I, v_I)`, `2 (n - r)` numbers. Its derivative at `(t, y)`:
//!
//! ```text
//! Phi(q_I, q_D, t) = 0          Newton in q_D with the block B = Phi_q[rows, D], q_I fixed
//! B v_D = nu - Phi_q[rows, I] v_I                                     (dependent velocities)
//! [M, Phi_q^T; Phi_q, 0] [qddot; lambda] = [Q; gamma]                 (the accelerations)
//! y' = (v_I, qddot_I)
//! ```
//!
//! With few independent coordinates (at most `REDUCED_MAX`), no redundant rows and no joint
//! friction, the accelerations are solved in the independent coordinates with the factors of
//! `B` at the evaluation (`Split::reduced_accelerations`: `(M_I + S^T M_D S) qddot_I = ...`,
//! `S = B^-1 Phi_q[rows, I]`), the multipliers by a solve with `B^T`; otherwise the augmented
//! system is factored (`Dae::accelerations`).
//!
//! Newton starts from the Taylor extrapolation `q_D + dt v_D + dt^2/2 a_D` of the last accepted
//! state (for the corrector, the predictor's solution moved with the correction to first order,
//! `-S dq_I`; the quintic Hermite interpolant of the step's ends for an output time) and
//! iterates with the factors of `B` at the accepted state, evaluating `Phi` alone
//! (`Dae::constraints_only`), refactoring `B` at the iterate when it contracts slower than
//! `SLOW_RATE` or has not converged in `REFACTOR_AFTER` iterations. It has converged when the
//! estimated distance to the solution (`rate / (1 - rate)` times the correction) is below
//! `NEWTON_TOL` in the weighted norm (`PREDICTION_NEWTON_TOL` for the prediction), or the
//! correction or the residual is within `NEWTON_ROUNDOFF` of round-off
//! ([`super::roundoff_ratio`] at the positions' scale); `v_D` is corrected the same way. `B` is
//! factored once per accepted step and when Newton is slow, not at every iterate. The parts:
//! `newton.rs` (this Newton), `partition.rs` and `pivots.rs` (the partition), `block.rs` (the
//! dependent block, its factors and the blocks kept), `reduced.rs` (the reduced accelerations),
//! `norm.rs` (the error norm), `noise.rs` (the noise test), `accepted.rs` (the accepted states),
//! `split.rs` (the state that holds them), `sensitivities.rs` (design sensitivities integrated with
//! the state as more components of `y`, docs/sensitivities.md).
//!
//! **Integrator.** Shampine and Gordon's STEP and INTRP on `y` (`adams.rs`: variable order
//! 1 to `max_order`, default 12).
//! **Error norm** (`Split::norm`): each error estimate, a change of `(q_I, v_I)`, is mapped to
//! the change of every position and velocity it makes (`dq_D = -B^-1 Phi_q[rows, I] dq_I`, and
//! `dv_D` with the derivative of `Phi_q v` in the positions), each weighted by
//! `atol + rtol |y_k|`, and the norm is the largest; a step passes at an error of 1. Near a
//! fold, an error of `q_I` is an error of `q_D` amplified by `dq_D / dq_I`, which a norm of
//! `(q_I, v_I)` alone would not see. The mapping is linear: with the
//! reduced accelerations it is a `2r x 2p` matrix built once an evaluation from their `S` and
//! one difference quotient per independent coordinate, instead of two evaluations of `Phi_q` at
//! each of the three to five norms an attempt asks for. Output at the requested times uses the
//! method's own interpolating polynomial (STEP's companion INTRP) for `(q_I, v_I)`,
//! then recovers `q_D, v_D` as above. Departures from STEP: the step never passes the end time
//! or the maximum step, and the "tolerance too small for the machine precision" return is
//! replaced by the smallest-step failure.
//!
//! **Re-partition.** The partition is chosen again at the last accepted state when
//! - Newton for `q_D` needs more than `NEWTON_SLOW` (3) iterations at an accepted step, or
//! - the sensitivity of the dependent coordinates to the independent ones, `max |dq_D / dq_I|`
//!   (the largest entry of `-B^-1 Phi_q[rows, I]`), extrapolated to the next step from its growth
//!   over the last one, exceeds `GROWTH` (4) times its value when the partition was chosen: the
//!   independent coordinates approach a position where they no longer determine the others (a
//!   crank's `x` at its extreme), or
//! - Newton fails or `B` is singular during a step, and the partition was chosen before the last
//!   accepted step.
//!
//! The sensitivity measures what matters directly (docs/integrators.md says which trigger was
//! tried before it). If the new choice keeps the same independent
//! coordinates, only the reference sensitivity is updated; otherwise the Adams method is carried
//! over to the new coordinates with its order, step and history (`Adams::rebase`: their
//! differences rebuilt from their velocities and accelerations at the last accepted states,
//! which every partition computes for all coordinates). `partitions` counts the choices that
//! set up the coordinates: the first and each change.
//!
//! **Crossing singular positions.** Where `Phi_q` loses rank for every choice of `B` (A02's flat
//! chain) the constraints fix `q_D` only to `|B^-1|` times the round-off of `Phi`, and the
//! accelerations vary across that band as `1 / sigma_min(B)^2`: an error estimate there is noise
//! that no step resolves, and steps that approach shrink without end. A failed estimate within
//! `NOISE_MARGIN` (8) times a sample of that noise (`Split::noise_dominates`) hands the state, from
//! the last accepted step, to `bdf` (SI2, index 3 where SI2's Newton fails there) for
//! `CROSSING_STEPS` (16) recent steps
//! ([`super::bdf::run_until`], writing the output times); the method then restarts there with a
//! new partition. `crossings` counts the hand-overs, and the summary warns.

mod accepted;
mod block;
mod newton;
mod noise;
mod norm;
mod partition;
mod pivots;
mod reduced;
mod sensitivities;
mod split;

use super::adams::{Adams, MAX_ORDER};
use super::{
    step_failure, Dae, DynamicStats, IntegratorKind, IntegratorSettings, Outcome, Output, Span, Start,
    CONTACT_UNRESOLVED,
};
use crate::analysis::sensitivity::{DynamicSensitivity, Track};
use crate::error::Error;
use newton::{Eval, Purpose};
use sensitivities::Sensitivities;
use split::Split;

/// More Newton iterations than this at an accepted step mean the dependent coordinates are badly
/// conditioned in the independent ones: the partition is chosen again.
const NEWTON_SLOW: usize = 3;
/// Re-partition when the sensitivity `max |dq_D / dq_I|` has grown by more than this factor since
/// the partition was chosen. Near a position where `q_I` stops determining `q_D` (a fold: the
/// independent coordinate at an extreme) the sensitivity grows as `1 / distance`; a factor 4 is
/// reached about three steps of a well-resolved motion before the fold, early enough that no step
/// straddles it, and late enough that a coordinate far from its fold is kept.
const GROWTH: f64 = 4.0;
/// `bdf` takes over for this many of `abam`'s recent steps (the largest of about the last 20)
/// when the error estimate is noise: long enough to carry the state past the singular position
/// (on A02 at `1e-12` the estimate is noise from `6e-4` s before a flat position), short enough
/// that `abam` soon resumes. The recent steps are the cruise's, `1e-2` to `3e-2` s on A02: its
/// stretches last 0.12 to 0.30 s at `1e-12` (1.7 s of the 20 s in `bdf`) and 0.06 to 0.23 s at
/// `1e-13` (2.9 s).
const CROSSING_STEPS: f64 = 16.0;
/// Decay per accepted step of the recent step size (the largest recent step): about the last 20
/// steps count.
const RECENT_DECAY: f64 = 0.9;
/// (Re)start the Adams method at the accepted state in the coordinates of the partition (with
/// the sensitivities after the state when the run has them).
fn begin(s: &Split<'_, '_>, sens: Option<&Sensitivities<'_, '_>>, ad: &mut Adams) {
    ad.resize(Sensitivities::width(sens, s.part.ind.len()));
    s.state(&mut ad.y, &mut ad.yp);
    if let Some(z) = sens {
        z.state(&s.part.ind, &mut ad.y, &mut ad.yp);
    }
    ad.restart(s.accepted.ta);
}

/// Carry the Adams method over to a new partition's coordinates at the accepted state, its
/// order, step and history kept: the differences of the new coordinates are rebuilt from their
/// derivatives at the past accepted states ([`Adams::rebase`]). The number of independent
/// coordinates is the rank's complement and does not change; if it did, a restart.
fn carry(s: &Split<'_, '_>, sens: Option<&Sensitivities<'_, '_>>, ad: &mut Adams) {
    if ad.neq != Sensitivities::width(sens, s.part.ind.len()) {
        begin(s, sens, ad);
        return;
    }
    debug_assert_eq!(ad.x, s.accepted.ta);
    s.state(&mut ad.y, &mut ad.yp);
    if let Some(z) = sens {
        z.state(&s.part.ind, &mut ad.y, &mut ad.yp);
    }
    ad.rebase(&mut |j, t, out| {
        s.past(j, t, out);
        if let Some(z) = sens {
            z.past(j, t, &s.part.ind, out);
        }
    });
}

/// [`Split::evaluate`] at `(t, y)` with `y'` into `yp`, and the sensitivities' part of `y'` when
/// the run has them (a failure when their derivatives cannot be made there).
fn evaluate(
    s: &mut Split<'_, '_>,
    sens: Option<&mut Sensitivities<'_, '_>>,
    t: f64,
    y: &[f64],
    yp: &mut [f64],
    purpose: Purpose,
) -> Result<Eval, Error> {
    let eval = s.evaluate(t, y, Some(&mut *yp), purpose)?;
    if let (Eval::Done { .. }, Some(z)) = (eval, sens) {
        if !z.derivatives(s, t, y, yp)? {
            return Ok(Eval::Failed { residual: s.dae.phi.iter().fold(0.0f64, |a, x| a.max(x.abs())) });
        }
    }
    Ok(eval)
}

/// The error norm of a change `x` of `y`: the state's ([`Split::norm`]), and the largest of it and
/// the sensitivities' when the run has them (IDAS's `errconS`).
fn norm(s: &mut Split<'_, '_>, sens: Option<&Sensitivities<'_, '_>>, x: &[f64]) -> f64 {
    let w = 2 * s.part.ind.len();
    let state = s.norm(&x[..w]);
    match sens {
        None => state,
        Some(z) => state.max(z.norm(s, &x[w..])),
    }
}

/// Integrate from `start` to the output's end time.
pub fn run(dae: &mut Dae<'_>, out: &mut Output, settings: &IntegratorSettings, start: Start) -> Outcome {
    integrate(dae, out, settings, start, None)
}

/// [`run`], with design sensitivities when given: their equations and each parameter's at the
/// start ([`DynamicSensitivity::start`]); the outputs then get their derivatives.
pub(crate) fn integrate<'m>(
    dae: &mut Dae<'m>,
    out: &mut Output,
    settings: &IntegratorSettings,
    start: Start,
    sensitivities: Option<(&mut DynamicSensitivity<'m>, Vec<Track>)>,
) -> Outcome {
    let run = Span::new(settings, &start, out.t_end(), 0);
    let (t_end, h_max, h_start) = (run.t_end, run.h_max, run.h_start);
    let mut stats = DynamicStats::default();
    let (t0, m) = (start.t, dae.m);
    let mut sens =
        sensitivities.map(|(eq, tracks)| Sensitivities::new(eq, tracks, t0, (settings.rtol, settings.atol), m));
    let mut s = Split::new(dae, settings, start);
    let mut ad = Adams::new(settings.order_limit().clamp(1, MAX_ORDER));
    let mut h = h_start;
    // The largest recent accepted step, decaying by RECENT_DECAY a step.
    let mut h_recent = h_start;
    // Partition at the start and (y, y') there.
    s.choose();
    stats.partitions += 1;
    begin(&s, sens.as_ref(), &mut ad);
    let mut chosen_at = 0;
    let width = Sensitivities::width(sens.as_ref(), s.dae.n);
    let (mut yo, mut ypo) = (vec![0.0; width], vec![0.0; width]);
    let outcome = (|| -> Result<(), Error> {
        while run.before_end(ad.x) {
            // Adams' accepted steps shrink the step only by a bounded factor; the error test
            // decides below the smallest step.
            let h_min = run.smallest_step(out, s.dae, &s.accepted.qa, stats.steps, ad.x, h, settings, false)?;
            h = run.fit(ad.x, h);
            // (y, phi, h) => prediction p at x + h => y'(p).
            s.error.weights(&s.accepted);
            ad.coefficients(h);
            ad.predict(h);
            let t1 = ad.x;
            let mut eval = evaluate(&mut s, sens.as_mut(), t1, &ad.p, &mut ad.yp, Purpose::Prediction)?;
            let mut err = f64::NAN;
            let mut noise = false;
            if let Eval::Done { .. } = eval {
                err = ad.error_test(h, &mut |x| norm(&mut s, sens.as_ref(), x));
                if err > 1.0 {
                    // Judged on the prediction converged as every other evaluation is: the noise
                    // test samples one more Newton correction, and the prediction's looser stop
                    // would be that sample's size.
                    eval = evaluate(&mut s, sens.as_mut(), t1, &ad.p, &mut ad.yp, Purpose::Judged)?;
                    if let Eval::Done { .. } = eval {
                        err = ad.error_test(h, &mut |x| norm(&mut s, sens.as_ref(), x));
                    }
                }
                if err <= 1.0 {
                    // (p, y'(p)) => corrected yc => y'(yc).
                    ad.correct(h);
                    eval = evaluate(&mut s, sens.as_mut(), t1, &ad.yc, &mut ad.yp, Purpose::State)?;
                } else if let Eval::Done { .. } = eval {
                    noise = s.noise_dominates(t1, &ad.d);
                }
            }
            if noise {
                // The estimate is the noise of a singular position, which no step of this method
                // can resolve: `bdf`, which solves for every coordinate at once (SI2, falling back
                // to index 3 where SI2's Newton fails at the singular position), takes the state
                // across it from the last accepted step, then the method restarts.
                ad.reject(h);
                stats.rejected_steps += 1;
                if sens.is_some() {
                    let cause = "the error estimate is the round-off noise of a singular position, which abam crosses with bdf: its design sensitivities do not cross it (run with --integrator bdf)";
                    return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h, cause));
                }
                let stop = (s.accepted.ta + CROSSING_STEPS * h_recent).min(t_end);
                if stop - s.accepted.ta < h_min {
                    let cause = "the error estimate is the round-off noise of a singular position, and the step left to cross it is below the smallest";
                    return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h, cause));
                }
                stats.crossings += 1;
                stats.first_crossing.get_or_insert(s.accepted.ta);
                // bdf's own first step and order limit; the same tolerances, formulation and budget.
                let across =
                    IntegratorSettings { kind: IntegratorKind::Bdf, max_order: None, initial_step: None, ..*settings };
                let begin_at = Start {
                    t: s.accepted.ta,
                    q: s.accepted.qa.clone(),
                    qdot: s.accepted.va.clone(),
                    qddot: s.accepted.aa.clone(),
                    lambda: s.accepted.la.clone(),
                };
                let (crossed, reached) = super::bdf::run_until(s.dae, out, &across, begin_at, stop, stats.steps);
                stats.absorb(&crossed);
                let (t, q, v) = reached?;
                s.resume(t, &q, &v)?;
                chosen_at = stats.steps;
                if s.choose() {
                    stats.partitions += 1;
                }
                begin(&s, sens.as_ref(), &mut ad);
                h = h_start.min(h_recent);
                continue;
            }
            let iterations = match eval {
                Eval::Done { iterations } if err <= 1.0 => iterations,
                Eval::Done { .. } => {
                    stats.rejected_steps += 1;
                    h = ad.reject(h);
                    if h < h_min {
                        let cause = format!(
                            "the error test fails (error {err:.3e} of the tolerance) even with the smallest step"
                        );
                        return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h, &cause));
                    }
                    continue;
                }
                Eval::Failed { residual } => {
                    stats.newton_failures += 1;
                    h = ad.reject(h);
                    if stats.steps > chosen_at && s.choose() {
                        // The dependent coordinates may be the trouble: new ones.
                        stats.partitions += 1;
                        carry(&s, sens.as_ref(), &mut ad);
                    }
                    chosen_at = stats.steps;
                    if h < h_min {
                        let cause = format!(
                            "Newton's method for the dependent coordinates does not converge (constraint residual {residual:.3e}) even with the smallest step"
                        );
                        return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h, &cause));
                    }
                    continue;
                }
            };
            if let Some(r) = s.dae.contact_event(&s.accepted.qa, &s.q) {
                // A first contact inside the step: shorter, until the step ends just into it (as
                // bdf and hht; the corrected positions of the step are those tested).
                stats.rejected_steps += 1;
                ad.reject(h);
                h *= r;
                if h < h_min {
                    return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h, CONTACT_UNRESOLVED));
                }
                continue;
            }
            // Accept: differences, order and next step; the state; work; output times.
            let h_used = h;
            h_recent = h_used.max(RECENT_DECAY * h_recent);
            h = ad.accept(h, &mut |x| norm(&mut s, sens.as_ref(), x)).min(h_max);
            let singular = !s.commit(ad.x);
            if let Some(z) = &mut sens {
                z.commit(ad.x);
            }
            stats.accept(h_used);
            stats.max_order_used = stats.max_order_used.max(ad.kold);
            // The sensitivity at the next step, extrapolated from its growth over this one: the
            // partition changes before a step would carry it past GROWTH, not after.
            let influence = s.influence();
            let next = influence * (influence / s.part.influence1).max(1.0);
            s.part.influence1 = influence;
            let degraded = singular || iterations > NEWTON_SLOW || next.is_nan() || next > GROWTH * s.part.influence0;
            out.advance_work(s.dae, s.accepted.ta, &s.accepted.qa, &s.accepted.va, &s.accepted.la);
            let neq = ad.neq;
            while let Some(to) = out.due(ad.x) {
                ad.interpolate(to, &mut yo[..neq], &mut ypo[..neq]);
                // With the accelerations: the reduced solve where it applies is cheaper than
                // the augmented one the output would make (the same solution, to its
                // regularisation).
                match evaluate(&mut s, sens.as_mut(), to, &yo[..neq], &mut ypo[..neq], Purpose::State)? {
                    Eval::Done { .. } => {
                        out.push_solved(s.dae, to, &s.q, &s.v, &s.sol)?;
                        if let Some(z) = &mut sens {
                            z.push(&mut s, out, to)?;
                        }
                    }
                    // The interpolated q_I leaves no nearby q_D (a partition near its fold inside
                    // a long step): the output is the quintic Hermite interpolant of the whole
                    // state between the step's ends, within the step's error, its constraint
                    // residual reported with it.
                    Eval::Failed { .. } if s.accepted.ta > s.accepted.tp && to >= s.accepted.tp => {
                        s.accepted.interpolate(to, &mut s.q, &mut s.v);
                        s.t_last = f64::NAN;
                        out.push(s.dae, to, &s.q, &s.v)?;
                        if let Some(z) = &mut sens {
                            z.push_interpolated(&mut s, out, to)?;
                        }
                    }
                    Eval::Failed { residual } => {
                        let cause = format!(
                            "Newton's method for the dependent coordinates at the output time {to} does not converge (constraint residual {residual:.3e})"
                        );
                        return Err(step_failure(s.dae, &s.accepted.qa, s.accepted.ta, h_used, &cause));
                    }
                }
            }
            if degraded {
                chosen_at = stats.steps;
                if s.choose() {
                    stats.partitions += 1;
                    carry(&s, sens.as_ref(), &mut ad);
                }
            }
        }
        Ok(())
    })();
    stats.newton_iterations += s.newton.iterations;
    (stats, outcome)
}

#[cfg(test)]
mod tests {
    use super::newton::NEWTON_TOL;
    use super::*;

    /// The quick-return with its forces (the crank torque and the slider's force), partitioned
    /// at the file's positions at rest: `test` gets the split, with these settings.
    fn on_the_quick_return(settings: &IntegratorSettings, test: impl FnOnce(&mut Split<'_, '_>)) {
        let text = include_str!("../../../../../../examples/quick_return_a.yaml");
        let model = crate::model::Model::from_yaml(text).unwrap();
        let forces: Vec<usize> = (0..model.forces.len()).collect();
        let mut dae = Dae::new(&model, &[], &forces).unwrap();
        let (n, m) = (dae.n, dae.m);
        let start = Start { t: 0.0, q: model.q0(), qdot: model.qdot0(), qddot: vec![0.0; n], lambda: vec![0.0; m] };
        let mut s = Split::new(&mut dae, settings, start);
        s.choose();
        test(&mut s);
    }

    /// The reduced accelerations and the error map against the computations they replace, at a
    /// state of the quick-return under its crank torque and the slider's force (gravity on):
    /// the file's positions, the independent coordinate's velocity set to 5 (m/s or rad/s) and
    /// the others solved from it, so that the velocity terms of `gamma` and of the map weigh:
    ///
    /// - `[qddot; lambda]` from `Split::reduced_accelerations` against the augmented system's
    ///   (`Dae::accelerations`, a second formulation), within `1e-10` of the largest of each,
    ///   the augmented system's regularisation `eps` (measured: `1.5e-16` and `1.4e-16`);
    /// - the error norm of a change of the independent state through the map (built from `S`
    ///   and one difference quotient) against the norm computed directly for that change, within
    ///   `1e-6` relative: both take the derivative of `Phi_q v` by a difference quotient over
    ///   `sqrt(eps)`, along the same direction when there is one independent coordinate.
    #[test]
    fn reduced_accelerations_and_error_map_match_the_direct_computations() {
        on_the_quick_return(&IntegratorSettings::default(), |s| {
            let (n, m) = (s.dae.n, s.dae.m);
            assert!(s.part.reduced, "one independent coordinate, no redundant rows, no friction");
            let p = s.part.ind.len();
            let (mut y, mut yp) = (vec![0.0; 2 * p], vec![0.0; 2 * p]);
            s.state(&mut y, &mut yp);
            y[p] = 5.0;
            s.error.weights(&s.accepted);
            let eval = s.evaluate(0.0, &y, Some(&mut yp), Purpose::State).unwrap();
            assert!(matches!(eval, Eval::Done { .. }), "{eval:?}");
            let (q, v, reduced) = (s.q.clone(), s.v.clone(), s.sol.clone());
            let mut full = vec![0.0; n + m];
            s.dae.accelerations(&q, &v, 0.0, &mut full).unwrap();
            for (part, range) in [("accelerations", 0..n), ("multipliers", n..n + m)] {
                let big = full[range.clone()].iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let worst = range.clone().map(|k| (reduced[k] - full[k]).abs()).fold(0.0f64, f64::max);
                eprintln!("{part}: largest {big:.3e}, reduced against augmented {worst:.2e}");
                assert!(big > 0.0 && worst <= 1e-10 * big, "{part}: {worst:e} of {big:e}");
            }
            // The velocities (`v_D = -S v_I`, no constraint moves with time here) meet `Phi_q v = nu`
            // to round-off: 1e-12 of the largest velocity times the largest entry of `Phi_q`.
            let mut phiv = vec![0.0; m];
            let mut nu = vec![0.0; m];
            s.dae.positions(&q, 0.0);
            s.dae.jv(&v, &mut phiv);
            s.dae.nu(&q, 0.0, &mut nu);
            let vmax = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let jmax = s.dae.jacobian_entries().1.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let vres = phiv.iter().zip(&nu).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(vmax > 1.0 && vres <= 1e-12 * vmax * jmax, "velocity residual {vres:e}");
            // The corrector's start (the last evaluation moved by -S dq_I, at the same time) reaches
            // the state a start from the accepted one reaches, to Newton's tolerance (`1e-4` of the
            // weights `atol + rtol |q|`, 1e-6 each by default: bound 1e-9 of the scale).
            let mut moved = y.clone();
            (moved[0], moved[p]) = (moved[0] + 1e-3, moved[p] - 0.2);
            s.norm(&vec![1e-6; 2 * p]);
            assert!(s.error.map_ready);
            assert!(matches!(s.evaluate(0.0, &moved, Some(&mut yp), Purpose::State).unwrap(), Eval::Done { .. }));
            assert!(s.error.map_ready, "the map is kept at the same time");
            let (q1, v1) = (s.q.clone(), s.v.clone());
            s.t_last = f64::NAN;
            assert!(matches!(s.evaluate(0.0, &moved, Some(&mut yp), Purpose::State).unwrap(), Eval::Done { .. }));
            let scale = q1.iter().chain(&v1).fold(1.0f64, |a, x| a.max(x.abs()));
            let apart = q1.iter().zip(&s.q).chain(v1.iter().zip(&s.v)).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(apart <= 1e-9 * scale, "corrector's start against the accepted state's: {apart:e}");
            // Back to the first evaluation for the map's check.
            s.t_last = f64::NAN;
            s.evaluate(0.0, &y, Some(&mut yp), Purpose::State).unwrap();
            // The map is built at the first norm after an evaluation; the direct path at every norm.
            let x: Vec<f64> = (0..2 * p).map(|k| 1e-6 * (1.0 + k as f64)).collect();
            let via_map = s.norm(&x);
            assert!(s.error.map_ready);
            s.part.reduced = false;
            let direct = s.norm(&x);
            eprintln!("error norm through the map {via_map:.6e}, directly {direct:.6e}");
            assert!((via_map - direct).abs() <= 1e-6 * direct, "{via_map:e} against {direct:e}");
        });
    }

    /// Newton's stop leaves every state that may be accepted far within its tolerance of the
    /// solution, after one correction as after more. A crank turning at 50 rad/s, steps of
    /// 1.5 ms (0.075 rad): each step a prediction from the Taylor expansion of the accepted
    /// state, and a correction moved from it by half the weights (an error estimate's size);
    /// then one more Newton correction with `B` factored at the state reached, whose weighted
    /// size must be within a tenth of [`NEWTON_TOL`]: measured 0.007 of it, and 3.8 times it
    /// with `CHORD_SAFETY` 1 (the expected rate taken as it is). The chord's rate must have
    /// been measured, and most corrections must stop after one iteration (93 of 100), so that
    /// the expectation is what is tested.
    #[test]
    fn newton_leaves_each_state_within_its_tolerance() {
        let settings = IntegratorSettings { rtol: 1e-4, atol: 1e-4, ..IntegratorSettings::default() };
        on_the_quick_return(&settings, |s| {
            let p = s.part.ind.len();
            let (mut y, mut yp) = (vec![0.0; 2 * p], vec![0.0; 2 * p]);
            s.state(&mut y, &mut yp);
            y[p] = 50.0;
            s.error.weights(&s.accepted);
            assert!(matches!(s.evaluate(0.0, &y, Some(&mut yp), Purpose::State).unwrap(), Eval::Done { .. }));
            assert!(s.commit(0.0));
            let (h, mut one, mut worst) = (1.5e-3, 0, 0.0f64);
            let steps = 100;
            for k in 1..=steps {
                let t = k as f64 * h;
                s.error.weights(&s.accepted);
                let mut prediction = y.clone();
                let mut eval = Eval::Failed { residual: f64::NAN };
                for attempt in 0..2 {
                    prediction.clone_from(&y);
                    for j in 0..p {
                        prediction[j] += h * (yp[j] + 0.5 * h * yp[p + j]);
                        prediction[p + j] += h * yp[p + j];
                    }
                    eval = s.evaluate(t, &prediction, Some(&mut yp), Purpose::Prediction).unwrap();
                    if attempt == 0 && matches!(eval, Eval::Failed { .. }) {
                        // The independent coordinate predicted past its extreme: another
                        // partition, as `run` would choose after the failed step.
                        s.choose();
                        s.state(&mut y, &mut yp);
                        s.t_last = f64::NAN;
                    } else {
                        break;
                    }
                }
                assert!(matches!(eval, Eval::Done { .. }), "prediction at {t}: {eval:?}");
                let mut corrected = prediction.clone();
                for (c, &x) in corrected.iter_mut().zip(&prediction) {
                    *c += 0.5 * (settings.atol + settings.rtol * x.abs());
                }
                let before = s.newton.iterations;
                let eval = s.evaluate(t, &corrected, Some(&mut yp), Purpose::State).unwrap();
                assert!(matches!(eval, Eval::Done { .. }), "correction at {t}: {eval:?}");
                one += usize::from(s.newton.iterations - before == 1);
                // One more correction, with B factored at the state reached.
                let q = s.q.clone();
                s.dae.positions(&q, t);
                s.blocks.factored_ok = false;
                assert!(s.factor());
                for (b, &row) in s.blocks.rhs.iter_mut().zip(&s.part.rows) {
                    *b = -s.dae.phi[row];
                }
                s.blocks.solve();
                let left = super::super::wrms(
                    s.part.dep.iter().zip(&s.blocks.rhs).map(|(&c, &d)| (d, q[c])),
                    s.part.dep.len(),
                    s.error.rtol,
                    s.error.atol,
                );
                worst = worst.max(left / NEWTON_TOL);
                s.dae.positions(&q, t);
                assert!(s.commit(t));
                y = corrected;
                // Re-partitioned as `run` does.
                let influence = s.influence();
                let next = influence * (influence / s.part.influence1).max(1.0);
                s.part.influence1 = influence;
                if next > GROWTH * s.part.influence0 {
                    s.choose();
                    s.state(&mut y, &mut yp);
                }
            }
            eprintln!("{one} of {steps} corrections in one iteration; the worst left {worst:.3} of the tolerance");
            assert!(s.newton.chord.is_finite(), "the chord's rate was measured");
            assert!(one > steps / 2, "{one} of {steps} in one iteration");
            assert!(worst <= 0.1, "a state left {worst:.3} times Newton's tolerance from the solution");
        });
    }
}
