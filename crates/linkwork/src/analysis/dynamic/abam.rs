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
//! factored once per accepted step and when Newton is slow (221 factorizations in 108 steps on
//! the N = 40 N-four-bar) instead of at every iterate.
//!
//! **Integrator.** Shampine and Gordon's STEP and INTRP on `y` (`adams.rs`: variable order
//! 1 to `max_order`, default 12).
//! **Error norm** (`Split::norm`): each error estimate, a change of `(q_I, v_I)`, is mapped to
//! the change of every position and velocity it makes (`dq_D = -B^-1 Phi_q[rows, I] dq_I`, and
//! `dv_D` with the derivative of `Phi_q v` in the positions), each weighted by
//! `atol + rtol |y_k|`, and the norm is the largest; a step passes at an error of 1. Near a
//! fold, an error of `q_I` is an error of `q_D` amplified by `dq_D / dq_I`: measured on
//! `(q_I, v_I)` alone, the error test let the kinetic energy of the coasting quick-return jump by
//! 1e-4 relative at each re-partition at `rtol = 1e-6`. The mapping is linear: with the
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
//! The sensitivity measures what matters directly; the pivot ratio of `B` was tried and rejected:
//! it is dominated by pivots unrelated to the fold and only falls within a few hundredths of a
//! radian of it, which one step can straddle. If the new choice keeps the same independent
//! coordinates, only the reference sensitivity is updated; otherwise the Adams method is carried
//! over to the new coordinates with its order, step and history (`Adams::rebase`: their
//! differences rebuilt from their velocities and accelerations at the last accepted states,
//! which every partition computes for all coordinates). It used to restart at order 1 with at
//! most the initial step: the quick-return under its crank torque re-partitions 97 times in 2 s
//! and took 2,232 steps at `1e-4`, now 1,344. `partitions` counts the choices that set up the
//! coordinates: the first and each change.
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

use super::adams::{Adams, MAX_ORDER};
use super::{
    hermite5, roundoff_ratio, step_failure, Dae, DynamicStats, IntegratorKind, IntegratorSettings, Outcome, Output,
    Span, Start, CONTACT_UNRESOLVED,
};
use crate::error::Error;
use crate::linalg::dense::RANK_TOLERANCE;
use crate::linalg::Pattern;
use crate::linalg::SparseLu;

/// Newton iterations for the dependent coordinates before the attempt fails. The iteration uses
/// the factors of `B` at the accepted state (a chord method, linear convergence at a rate of the
/// order of the step's motion) and refactors `B` at the iterate when it contracts slowly or has
/// not converged in [`REFACTOR_AFTER`] iterations, so that a far start (an output time early in a
/// long step, a large first step) converges as Newton's method does.
const MAX_NEWTON: usize = 12;
/// Iterations with one factorization of `B` before it is refactored at the iterate.
const REFACTOR_AFTER: usize = 3;
/// More Newton iterations than this at an accepted step mean the dependent coordinates are badly
/// conditioned in the independent ones: the partition is chosen again.
const NEWTON_SLOW: usize = 3;
/// Newton has converged when the weighted RMS norm of the correction (weights
/// `atol + rtol |q|`) is below this; Newton's quadratic convergence leaves the remaining error
/// far smaller still, so the dependent coordinates add no noise to the Adams differences.
const NEWTON_TOL: f64 = 1e-4;
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
/// Re-partition when the sensitivity `max |dq_D / dq_I|` has grown by more than this factor since
/// the partition was chosen. Near a position where `q_I` stops determining `q_D` (a fold: the
/// independent coordinate at an extreme) the sensitivity grows as `1 / distance`; a factor 4 is
/// reached about three steps of a well-resolved motion before the fold, early enough that no step
/// straddles it, and late enough that a coordinate far from its fold is kept.
const GROWTH: f64 = 4.0;
/// A failed error estimate within this many times the noise sampled at the same point
/// ([`Split::noise_dominates`]) is that noise: a single sample of a random quantity may fall a
/// few times below its spread (on A02 at `1e-13`, approaching a flat position, the first noisy
/// estimates were 1.5 to 3.5 times the sample), while an estimate of truncation error stands
/// orders of magnitude above it (the sample is `1e-16` relative away from singular positions).
const NOISE_MARGIN: f64 = 8.0;
/// `bdf` takes over for this many of `abam`'s recent steps (the largest of about the last 20)
/// when the error estimate is noise: long enough to carry the state past the singular position
/// (on A02 at `1e-12` the estimate is noise from `6e-4` s before a flat position), short enough
/// that `abam` soon resumes. The recent steps are the cruise's, `1e-2` to `3e-2` s on A02: its
/// stretches last 0.12 to 0.30 s at `1e-12` (1.7 s of the 20 s in `bdf`) and 0.06 to 0.23 s at
/// `1e-13` (2.9 s).
const CROSSING_STEPS: f64 = 16.0;
/// Most independent coordinates for which an evaluation solves the accelerations in them
/// ([`Split::reduced_accelerations`]: `p + 2` solves with the factors of `B` and a `p x p`
/// Cholesky) instead of factoring the `(n + m)` augmented matrix, and the error norm is a
/// `2n x 2p` map built once an attempt ([`Split::norm`]). The reduced solve costs about `p` times
/// a solve with `B`, the augmented one a factorization of twice `B`'s order and three solves: on
/// the quick-return (`p = 1`, order 14 against 29) an evaluation's linear algebra falls from
/// about 6 to 2 us. At 8 the reduced solve's `p` solves still cost less than the factorization;
/// mechanisms of many degrees of freedom keep the augmented solve.
const REDUCED_MAX: usize = 8;
/// Partitions whose blocks are kept for a return ([`Split::choose`]): the quick-return under
/// its crank torque passes through 4 to 6 partitions a turn, 97 changes in 2 s, each of which
/// built its block and the symbolic structure of its factors afresh (the block's pattern, its
/// maps and an LU order found by partial pivoting).
const KEPT_BLOCKS: usize = 8;
/// Decay per accepted step of the recent step size (the largest recent step): about the last 20
/// steps count.
const RECENT_DECAY: f64 = 0.9;

/// What an evaluation is for: how far its Newton iteration goes, and whether it solves the
/// multipliers.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Purpose {
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
enum Eval {
    /// Converged in `iterations` Newton corrections.
    Done { iterations: usize },
    /// Newton did not converge or `B` is singular; `residual` is the largest `|Phi|` reached.
    Failed { residual: f64 },
}

/// The dependent block `B = Phi_q[rows, dep]` of a partition as a sparse matrix: its pattern
/// (fixed while the partition is), where each entry of `Phi_q` goes, and its LU factors.
struct Block {
    /// The partition's independent rows and dependent coordinates, ascending.
    rows: Vec<usize>,
    dep: Vec<usize>,
    /// (entries of `Phi_q`) position of each entry in `B`'s values, `usize::MAX` outside `B`.
    map: Vec<usize>,
    /// (n - r) for each independent coordinate, its entries in the independent rows:
    /// `(position in rows, index into Phi_q's entries)`, the columns of `Phi_q[rows, I]`.
    ind_cols: Vec<Vec<(usize, usize)>>,
    lu: SparseLu,
}

impl Block {
    /// The block of the rows `rows` and dependent coordinates `dep` (both ascending) of `Phi_q`
    /// with entries `entries`; `ind` are the other coordinates.
    fn new(entries: &[(usize, usize)], m: usize, n: usize, rows: &[usize], dep: &[usize], ind: &[usize]) -> Block {
        let mut row_pos = vec![usize::MAX; m];
        for (k, &r) in rows.iter().enumerate() {
            row_pos[r] = k;
        }
        // Column role: dependent (local index) or independent (!local index).
        let mut dep_pos = vec![usize::MAX; n];
        let mut ind_pos = vec![usize::MAX; n];
        for (k, &c) in dep.iter().enumerate() {
            dep_pos[c] = k;
        }
        for (k, &c) in ind.iter().enumerate() {
            ind_pos[c] = k;
        }
        let mut ind_cols = vec![vec![]; ind.len()];
        // (local column, local row, entry) of every entry of B, in compressed-column order.
        let mut inside: Vec<(usize, usize, usize)> = Vec::new();
        for (e, &(r, c)) in entries.iter().enumerate() {
            let i = row_pos[r];
            if i == usize::MAX {
                continue;
            }
            if dep_pos[c] != usize::MAX {
                inside.push((dep_pos[c], i, e));
            } else {
                ind_cols[ind_pos[c]].push((i, e));
            }
        }
        inside.sort_unstable();
        let r = dep.len();
        let mut col_ptr = vec![0; r + 1];
        let mut row_idx = Vec::with_capacity(inside.len());
        let mut map = vec![usize::MAX; entries.len()];
        let mut last = (usize::MAX, usize::MAX);
        for &(c, i, e) in &inside {
            if (c, i) != last {
                row_idx.push(i);
                col_ptr[c + 1] += 1;
                last = (c, i);
            }
            map[e] = row_idx.len() - 1;
        }
        for c in 0..r {
            col_ptr[c + 1] += col_ptr[c];
        }
        let pattern = Pattern { col_ptr, row_idx, map: vec![], nrows: r };
        // The pattern has a nonzero pivot in every column (the partition found one), so the
        // symbolic analysis cannot fail for want of one; only allocation can.
        let lu = SparseLu::new(pattern).expect("symbolic LU of the dependent block");
        Block { rows: rows.to_vec(), dep: dep.to_vec(), map, ind_cols, lu }
    }

    /// Factor `B` with the values `jac` of `Phi_q`'s entries; false when it is singular.
    fn factor(&mut self, jac: &[f64]) -> bool {
        let (_, values) = self.lu.pattern_and_values();
        values.fill(0.0);
        for (&p, &v) in self.map.iter().zip(jac) {
            if p != usize::MAX {
                values[p] += v;
            }
        }
        self.lu.factor().is_ok()
    }
}

/// A choice of independent coordinates and the machinery that recovers the others.
struct Split<'a, 'm> {
    dae: &'a mut Dae<'m>,
    rtol: f64,
    atol: f64,
    /// (r) independent rows of `Phi_q` (the pivot rows), `r` its numerical rank.
    rows: Vec<usize>,
    /// The partition's elimination's buffers, and a scratch for the independent coordinates.
    pivot_work: PivotWork,
    ind_scratch: Vec<usize>,
    /// (r) dependent coordinates (the pivot columns), ascending.
    dep: Vec<usize>,
    /// (n - r) independent coordinates, ascending.
    ind: Vec<usize>,
    /// `max |dq_D / dq_I|` when the partition was chosen, and at the last accepted step.
    influence0: f64,
    influence1: f64,
    /// The positions at which `B` was last factored.
    factored_q: Vec<f64>,
    /// The chord iteration's contraction per unit distance from `factored_q` (the largest
    /// coordinate change), as last measured (infinite before).
    chord: f64,
    /// The sparse dependent block and its factors (`None` before the first choice).
    block: Option<Block>,
    /// The blocks of the last [`KEPT_BLOCKS`] other partitions, the newest last: a mechanism
    /// turning round passes through the same few partitions again.
    kept: Vec<Block>,
    /// The values of `Phi_q`'s entries that `B`'s current factors were made from, and whether
    /// they are factors (false after a singular `B`).
    factored: Vec<f64>,
    factored_ok: bool,
    /// Whether the accelerations are solved in the independent coordinates
    /// ([`Split::reduced_accelerations`]): at most [`REDUCED_MAX`] of them, no redundant rows
    /// (their multipliers are the augmented solve's), no joint friction (its load depends on the
    /// multipliers).
    reduced: bool,
    /// Scratch of the reduced solve: (n) the load, (m) `gamma`, (r) `B^-1 gamma`, (r p) the
    /// columns `B^-1 Phi_q[rows, I]`, (p p) the reduced mass matrix, (p) its right-hand side.
    load: Vec<f64>,
    gamma: Vec<f64>,
    particular: Vec<f64>,
    sens: Vec<f64>,
    /// Whether `sens` is that of the last evaluation, with `B` as factored now.
    sens_fresh: bool,
    reduced_mass: Vec<f64>,
    reduced_rhs: Vec<f64>,
    /// With at most [`REDUCED_MAX`] independent coordinates, the error map of this attempt:
    /// column `k` is the change `(dq_D, dv_D)` (2r) that a unit change of the `k`-th entry of
    /// `(q_I, v_I)` makes ([`Split::dependent_changes`]), built at the attempt's first
    /// [`Split::norm`] (`map_ready`).
    map: Vec<f64>,
    map_ready: bool,
    /// Scratch of [`Split::norm`]: (2r) the dependent changes, (2p) a unit change.
    changes: Vec<f64>,
    unit: Vec<f64>,
    /// The state [`Split::noise_dominates`] restores (positions, velocities, solution, factored
    /// entries) and its sample of the noise: kept here so that a step allocates nothing.
    saved: [Vec<f64>; 4],
    sample: Vec<f64>,
    /// (r) right-hand side and solution; (r) the dependent positions of a Newton iterate.
    rhs: Vec<f64>,
    qd: Vec<f64>,
    /// (r) zeros, the size of a residual's exact value.
    zeros: Vec<f64>,
    /// (m) `Phi_q v`; (n) a change of the positions and the changed positions.
    phiv: Vec<f64>,
    dq: Vec<f64>,
    qe: Vec<f64>,
    /// Time of the last evaluation that converged (NaN after a failure).
    t_last: f64,
    /// (m) `nu`.
    nu: Vec<f64>,
    /// (n + m) `[qddot; lambda]` of the last evaluation with accelerations.
    sol: Vec<f64>,
    /// (n) positions and velocities of the last evaluation.
    q: Vec<f64>,
    v: Vec<f64>,
    /// (n) reciprocal error weights `1 / (atol + rtol |y|)` of positions and velocities at the
    /// accepted state (the norms multiply: a step asks for three to five).
    wq: Vec<f64>,
    wv: Vec<f64>,
    /// The accepted state before the last: time, (n) positions, velocities, accelerations.
    tp: f64,
    qp: Vec<f64>,
    vp: Vec<f64>,
    ap: Vec<f64>,
    /// The last accepted state: time, (n) positions, velocities, accelerations, (m) multipliers.
    ta: f64,
    qa: Vec<f64>,
    va: Vec<f64>,
    aa: Vec<f64>,
    la: Vec<f64>,
    /// The velocities and accelerations of the last `MAX_ORDER + 1` accepted states, a ring
    /// (`past_at` the newest), with their times: the derivatives a re-partition carries the
    /// Adams history over with ([`Adams::rebase`]).
    past_t: Vec<f64>,
    past_v: Vec<Vec<f64>>,
    past_a: Vec<Vec<f64>>,
    past_at: usize,
    /// Newton iterations in all evaluations.
    newton_iterations: usize,
}

impl<'a, 'm> Split<'a, 'm> {
    /// The machinery at the accepted state `start`, before any partition is chosen.
    fn new(dae: &'a mut Dae<'m>, settings: &IntegratorSettings, start: Start) -> Split<'a, 'm> {
        let (n, m) = (dae.n, dae.m);
        let Start { t, q, qdot, qddot, lambda } = start;
        let mut s = Split {
            dae,
            rtol: settings.rtol,
            atol: settings.atol,
            rows: vec![],
            pivot_work: PivotWork::default(),
            ind_scratch: vec![],
            dep: vec![],
            ind: vec![],
            influence0: 0.0,
            influence1: 0.0,
            factored_q: vec![0.0; n],
            chord: f64::INFINITY,
            block: None,
            kept: vec![],
            factored: vec![],
            factored_ok: false,
            reduced: false,
            load: vec![],
            gamma: vec![],
            particular: vec![],
            sens: vec![],
            sens_fresh: false,
            reduced_mass: vec![],
            reduced_rhs: vec![],
            map: vec![],
            map_ready: false,
            changes: vec![],
            unit: vec![],
            saved: [vec![], vec![], vec![], vec![]],
            sample: vec![],
            rhs: vec![],
            qd: vec![],
            phiv: vec![0.0; m],
            dq: vec![0.0; n],
            qe: vec![0.0; n],
            zeros: vec![],
            t_last: f64::NAN,
            wq: vec![0.0; n],
            wv: vec![0.0; n],
            nu: vec![0.0; m],
            sol: vec![0.0; n + m],
            q: q.clone(),
            v: qdot.clone(),
            tp: t,
            qp: q.clone(),
            vp: qdot.clone(),
            ap: qddot.clone(),
            ta: t,
            qa: q,
            va: qdot,
            aa: qddot,
            la: lambda,
            past_t: vec![t; MAX_ORDER + 1],
            past_v: vec![vec![0.0; n]; MAX_ORDER + 1],
            past_a: vec![vec![0.0; n]; MAX_ORDER + 1],
            past_at: 0,
            newton_iterations: 0,
        };
        s.record();
        s
    }
}

impl Split<'_, '_> {
    /// Choose the partition at the accepted state `(qa, ta)`; true when the independent
    /// coordinates changed.
    fn choose(&mut self) -> bool {
        let (m, n) = (self.dae.m, self.dae.n);
        self.dae.positions(&self.qa, self.ta);
        let (entries, jac) = self.dae.jacobian_entries();
        let work = &mut self.pivot_work;
        work.run(m, n, entries, jac);
        let (rows, dep) = (&work.prow, &work.pcol);
        let mut ind = std::mem::take(&mut self.ind_scratch);
        ind.clear();
        let mut next = dep.iter().peekable();
        for c in 0..n {
            if next.peek() == Some(&&c) {
                next.next();
            } else {
                ind.push(c);
            }
        }
        let changed = ind != self.ind;
        if changed || *rows != self.rows || self.block.is_none() {
            let block = match self.kept.iter().position(|b| b.rows == *rows && b.dep == *dep) {
                Some(k) => self.kept.remove(k),
                None => Block::new(entries, m, n, rows, dep, &ind),
            };
            if let Some(old) = self.block.replace(block) {
                if self.kept.len() == KEPT_BLOCKS {
                    self.kept.remove(0);
                }
                self.kept.push(old);
            }
        }
        let (r, p) = (dep.len(), ind.len());
        self.reduced = r > 0 && r == m && p <= REDUCED_MAX && !self.dae.has_friction();
        self.rows.clone_from(rows);
        self.dep.clone_from(dep);
        self.ind_scratch = std::mem::replace(&mut self.ind, ind);
        self.rhs.resize(r, 0.0);
        self.qd.resize(r, 0.0);
        self.zeros.resize(r, 0.0);
        self.particular.resize(r, 0.0);
        self.load.resize(n, 0.0);
        self.gamma.resize(m, 0.0);
        self.sens.resize(r * p, 0.0);
        self.reduced_mass.resize(p * p, 0.0);
        self.reduced_rhs.resize(p, 0.0);
        self.map.resize(4 * r * p, 0.0);
        self.changes.resize(2 * r, 0.0);
        self.unit.resize(2 * p, 0.0);
        self.map_ready = false;
        self.sens_fresh = false;
        self.factored_ok = false;
        self.factor();
        self.influence0 = self.influence();
        self.influence1 = self.influence0;
        changed
    }

    /// `max |dq_D / dq_I|`, the largest entry of `-B^-1 Phi_q[rows, I]`, with `B` factored at
    /// the last [`Dae::positions`]: how strongly the independent coordinates move the others
    /// (0 when there are none).
    fn influence(&mut self) -> f64 {
        if !self.sens_fresh {
            self.sensitivities();
        }
        self.sens.iter().fold(0.0f64, |a, x| a.max(x.abs()))
    }

    /// `sens = B^-1 Phi_q[rows, I]` (`p` solves, column `j` that of the `j`-th independent
    /// coordinate), with `B` as factored and `Phi_q` at the last [`Dae::positions`].
    fn sensitivities(&mut self) {
        let r = self.dep.len();
        let Some(block) = self.block.as_mut() else { return };
        let (_, jac) = self.dae.jacobian_entries();
        for (j, col) in block.ind_cols.iter().enumerate() {
            let s = &mut self.sens[j * r..(j + 1) * r];
            s.fill(0.0);
            for &(i, e) in col {
                s[i] += jac[e];
            }
            block.lu.solve(s);
        }
        self.sens_fresh = true;
    }

    /// Factor `B = Phi_q[rows, dep]` at the last [`Dae::positions`]; false when singular. The
    /// factors already made from the same values are kept (the accepted state is the corrector's
    /// evaluation, factored there).
    fn factor(&mut self) -> bool {
        let (_, jac) = self.dae.jacobian_entries();
        if self.factored_ok && self.factored == jac {
            return true;
        }
        self.factored.clear();
        self.factored.extend_from_slice(jac);
        self.factored_q.copy_from_slice(self.dae.jacobian_point());
        self.sens_fresh = false;
        self.factored_ok = self.block.as_mut().is_none_or(|b| b.factor(jac));
        self.dae.stats.factorizations += 1;
        self.factored_ok
    }

    /// `rhs <- B^-1 rhs` with the factors of [`Split::factor`].
    fn solve(&mut self) {
        if let Some(b) = self.block.as_mut() {
            b.lu.solve(&mut self.rhs);
        }
    }

    /// `rhs <- Phi_q[rows, I] x`, `x: (n - r)` indexed as `ind`, at the last positions.
    fn times_independent(&mut self, x: &[f64]) {
        self.rhs.fill(0.0);
        let Some(block) = self.block.as_ref() else { return };
        let (_, jac) = self.dae.jacobian_entries();
        for (col, &xj) in block.ind_cols.iter().zip(x) {
            for &(i, e) in col {
                self.rhs[i] += jac[e] * xj;
            }
        }
    }

    /// Reciprocal error weights of every position and velocity at the accepted state.
    fn weights(&mut self) {
        for (w, x) in self.wq.iter_mut().zip(&self.qa) {
            *w = 1.0 / (self.atol + self.rtol * x.abs());
        }
        for (w, x) in self.wv.iter_mut().zip(&self.va) {
            *w = 1.0 / (self.atol + self.rtol * x.abs());
        }
    }

    /// The error norm of a change `x = (dq_I, dv_I)` of the independent state at the last
    /// evaluation: the largest weighted change `|dy_k| / (atol + rtol |y_k|)` over all `2 n`
    /// positions and velocities, the dependent ones changed as [`Split::dependent_changes`] says.
    /// The largest, not the mean, because the amplified error sits in a few coordinates (the crank
    /// of a quick-return whose slider is independent), which a mean over all would dilute. With
    /// at most [`REDUCED_MAX`] independent coordinates the changes, linear in `x`, come from the
    /// attempt's map (`2p` columns built at its first norm; an attempt asks for three to five
    /// norms, each of which otherwise evaluates `Phi_q` twice).
    fn norm(&mut self, x: &[f64]) -> f64 {
        let (p, r) = (self.ind.len(), self.dep.len());
        let mut s = 0.0f64;
        for (j, &c) in self.ind.iter().enumerate() {
            s = s.max((x[j] * self.wq[c]).abs()).max((x[p + j] * self.wv[c]).abs());
        }
        if r == 0 {
            return s;
        }
        let mut changes = std::mem::take(&mut self.changes);
        if self.reduced {
            if !self.map_ready {
                let mut map = std::mem::take(&mut self.map);
                let mut unit = std::mem::take(&mut self.unit);
                for (k, column) in map.chunks_exact_mut(2 * r).enumerate() {
                    unit.fill(0.0);
                    unit[k] = 1.0;
                    if self.sens_fresh {
                        // `B^-1 Phi_q[rows, I]` of this evaluation is `sens`: a unit change of
                        // `q_I` moves `q_D` by minus its column, and of `v_I` moves `v_D` so.
                        let j = k % p;
                        let (dq, dv) = column.split_at_mut(r);
                        if k < p {
                            for (d, s) in dq.iter_mut().zip(&self.sens[j * r..(j + 1) * r]) {
                                *d = -s;
                            }
                            self.velocity_changes(&unit, dq, dv);
                        } else {
                            dq.fill(0.0);
                            for (d, s) in dv.iter_mut().zip(&self.sens[j * r..(j + 1) * r]) {
                                *d = -s;
                            }
                        }
                    } else {
                        self.dependent_changes(&unit, column);
                    }
                }
                (self.map, self.unit, self.map_ready) = (map, unit, true);
            }
            changes.fill(0.0);
            for (column, &xk) in self.map.chunks_exact(2 * r).zip(x) {
                for (c, m) in changes.iter_mut().zip(column) {
                    *c += m * xk;
                }
            }
        } else {
            self.dependent_changes(x, &mut changes);
        }
        let (dq, dv) = changes.split_at(r);
        for ((&c, a), b) in self.dep.iter().zip(dq).zip(dv) {
            s = s.max((a * self.wq[c]).abs()).max((b * self.wv[c]).abs());
        }
        self.changes = changes;
        s
    }

    /// The changes `out = (dq_D, dv_D)` (2r) of the dependent positions and velocities that a
    /// change `x = (dq_I, dv_I)` of the independent state makes at the last evaluation
    /// `(q, v, t)`, to first order through `Phi = 0` and `Phi_q v = nu` (`B` as factored,
    /// `Phi_q` at the evaluation):
    ///
    /// ```text
    /// dq_D = -B^-1 Phi_q[rows, I] dq_I
    /// dv_D = -B^-1 (Phi_q[rows, I] dv_I + d(Phi_q v)/dq dq)        (dq = (dq_I, dq_D))
    /// ```
    ///
    /// An error of the independent coordinates is an error of every coordinate they determine,
    /// amplified by `dq_D / dq_I`, which grows without bound near a fold (an independent
    /// coordinate at its extreme); there the velocities' dependence on the positions (the second
    /// term, `~ (dq_D / dq_I)^3 v_I`) dominates. The directional derivative of `Phi_q v` is a
    /// difference quotient over a relative change `sqrt(eps)` of the positions. Uses `dq`, `qe`
    /// as scratch.
    fn dependent_changes(&mut self, x: &[f64], out: &mut [f64]) {
        let (p, r) = (self.ind.len(), self.dep.len());
        self.times_independent(&x[..p]);
        self.solve();
        let (dq, dv) = out.split_at_mut(r);
        for (o, d) in dq.iter_mut().zip(&self.rhs) {
            *o = -d;
        }
        self.velocity_changes(x, dq, dv);
    }

    /// `dv_D` (into `dv`) of [`Split::dependent_changes`] for the change `x = (dq_I, dv_I)`
    /// whose dependent positions change by `dq_D`.
    fn velocity_changes(&mut self, x: &[f64], dq_d: &[f64], dv: &mut [f64]) {
        let (n, p) = (self.dae.n, self.ind.len());
        let mut dq = std::mem::take(&mut self.dq);
        dq.fill(0.0);
        for (j, &c) in self.ind.iter().enumerate() {
            dq[c] = x[j];
        }
        for (&c, &d) in self.dep.iter().zip(dq_d) {
            dq[c] = d;
        }
        // d(Phi_q v)/dq dq by a difference quotient, then dv_D.
        let size = dq.iter().fold(0.0f64, |a, d| a.max(d.abs()));
        let t = self.t_last;
        self.times_independent(&x[p..]);
        if size > 0.0 && t.is_finite() {
            let scale = self.q.iter().fold(1.0f64, |a, x| a.max(x.abs()));
            let e = f64::EPSILON.sqrt() * scale / size;
            for k in 0..n {
                self.qe[k] = self.q[k] + e * dq[k];
            }
            self.dae.positions(&self.q, t);
            self.dae.jv(&self.v, &mut self.nu);
            self.dae.jv_at(&self.qe, t, &self.v, &mut self.phiv);
            for (b, &row) in self.rhs.iter_mut().zip(&self.rows) {
                *b += (self.phiv[row] - self.nu[row]) / e;
            }
        }
        self.solve();
        for (o, d) in dv.iter_mut().zip(&self.rhs) {
            *o = -d;
        }
        self.dq = dq;
    }

    /// Whether the error estimate `d` (the difference of `y'` at the prediction from its
    /// extrapolation) of the last evaluation, at `t`, is round-off noise: at most
    /// [`NOISE_MARGIN`] times the change of `y'` that one more Newton correction of the dependent
    /// positions makes (fresh factors of `B` at the evaluation's positions, `v_D` and the
    /// accelerations solved again there).
    ///
    /// Near a singular position (`Phi_q` losing rank, as A02's flat chain, where every choice of
    /// `B` is singular) the constraints fix `q_D` only to the round-off of `Phi` times
    /// `|B^-1|`, and the accelerations vary across that band as `1 / sigma_min(B)^2`: at
    /// `t = 2.68716 s` on A02 Newton, run to its fixed point from six starts, stalls with
    /// corrections of `1e-11` m and accelerations `2e-2` m/s^2 apart. One more correction moves
    /// `q_D` within that band; the change it makes is a sample of the noise. The last evaluation's
    /// state, the factors of `B` and the positions are restored, so that the steps that follow are
    /// those without the sample (the factors to rounding: they are made again from the same
    /// values, in the pivot order the small LU keeps, which the sample may have changed).
    fn noise_dominates(&mut self, t: f64, d: &[f64]) -> bool {
        if self.dep.is_empty() || !t.is_finite() {
            return false;
        }
        let p = self.ind.len();
        let ok_before = self.factored_ok;
        let [mut q0, mut v0, mut s0, mut factored] = std::mem::take(&mut self.saved);
        for (to, from) in
            [(&mut q0, &self.q), (&mut v0, &self.v), (&mut s0, &self.sol), (&mut factored, &self.factored)]
        {
            to.clear();
            to.extend_from_slice(from);
        }
        self.dae.positions(&self.q, t);
        for (b, &row) in self.rhs.iter_mut().zip(&self.rows) {
            *b = -self.dae.phi[row];
        }
        let mut ok = self.factor();
        if ok {
            self.solve();
            for (&c, dc) in self.dep.iter().zip(&self.rhs) {
                self.q[c] += dc;
            }
            self.dae.positions(&self.q, t);
            ok = self.factor();
        }
        if ok {
            // Phi_q v = nu with the fresh factors: two corrections reach round-off (the first
            // from velocities that met the constraints at a point round-off away).
            self.dae.nu(&self.q, t, &mut self.nu);
            for _ in 0..2 {
                self.dae.jv(&self.v, &mut self.phiv);
                for (b, &row) in self.rhs.iter_mut().zip(&self.rows) {
                    *b = self.nu[row] - self.phiv[row];
                }
                self.solve();
                for (&c, dc) in self.dep.iter().zip(&self.rhs) {
                    self.v[c] += dc;
                }
            }
            ok = self.accelerations(t, false).is_ok();
            // `sens` is now the sample's: the map and the influence must not take it for the
            // evaluation's.
            self.sens_fresh = false;
        }
        let mut sample = std::mem::take(&mut self.sample);
        sample.clear();
        sample.resize(2 * p, 0.0);
        for (j, &c) in self.ind.iter().enumerate() {
            sample[p + j] = self.sol[c] - s0[c];
        }
        ok = ok && sample.iter().all(|x| x.is_finite());
        self.q.copy_from_slice(&q0);
        self.v.copy_from_slice(&v0);
        self.sol.copy_from_slice(&s0);
        if let Some(b) = self.block.as_mut() {
            b.factor(&factored);
        }
        std::mem::swap(&mut self.factored, &mut factored);
        self.factored_ok = ok_before;
        self.dae.positions(&self.q, t);
        let dominates = ok && self.norm(d) <= NOISE_MARGIN * self.norm(&sample);
        self.saved = [q0, v0, s0, factored];
        self.sample = sample;
        dominates
    }

    /// Resume at `(t, q, v)`, reached by another method: the accelerations and multipliers
    /// there, and that state as the accepted one (with no step before it).
    fn resume(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), Error> {
        let n = q.len();
        self.dae.accelerations(q, v, t, &mut self.sol)?;
        self.ta = t;
        self.qa.copy_from_slice(q);
        self.va.copy_from_slice(v);
        self.aa.copy_from_slice(&self.sol[..n]);
        self.la.copy_from_slice(&self.sol[n..]);
        self.tp = t;
        self.qp.copy_from_slice(q);
        self.vp.copy_from_slice(v);
        self.ap.copy_from_slice(&self.sol[..n]);
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        self.t_last = f64::NAN;
        self.record();
        Ok(())
    }

    /// Add the correction in `rhs` to the dependent positions (`positions`) or velocities, copy
    /// their new values into `qd`, and return the correction's weighted RMS norm.
    fn correct_dependent(&mut self, positions: bool) -> f64 {
        let x = if positions { &mut self.q } else { &mut self.v };
        let size =
            super::wrms(self.dep.iter().zip(&self.rhs).map(|(&c, &d)| (d, x[c])), self.dep.len(), self.rtol, self.atol);
        for ((&c, &d), out) in self.dep.iter().zip(&self.rhs).zip(self.qd.iter_mut()) {
            x[c] += d;
            *out = x[c];
        }
        size
    }

    /// `(t, y) => (q, v)` and, when `yp` is given, `[qddot; lambda]` into `sol` and
    /// `yp = (v_I, qddot_I)`.
    fn evaluate(&mut self, t: f64, y: &[f64], yp: Option<&mut [f64]>, purpose: Purpose) -> Result<Eval, Error> {
        let (p, r) = (self.ind.len(), self.dep.len());
        // Initial q_D, v_D: the last evaluation's when it was at this time (the corrector after
        // the predictor), moved with q_I's change to first order when that evaluation's
        // sensitivities are at hand (`dq_D = -S dq_I`, `dv_D = -S dv_I`: the corrector's first
        // correction is then of second order in the change); else inside the last step (an
        // output time) the quintic Hermite interpolant of its ends; else the Taylor
        // extrapolation of the accepted state. Two more starts were tried (2026-11-27): the
        // interpolant extrapolated a step ahead for the prediction (1.9 Newton iterations
        // instead of 2.6 on the loaded quick-return; but one step out it amplifies its ends'
        // errors 31 times, and at A02's flat positions, where `q_D` is noise of `|B^-1|` times
        // the round-off, `rtol = 1e-11` failed), and the interpolant at an output time moved to
        // its q_I by the last `S` (near a flat position `S` is unbounded: A02 erred 7 times more
        // at `1e-10`).
        let shift = t == self.t_last && self.sens_fresh;
        // The error map of the prediction serves the correction's norms too (the same time;
        // the positions differ by the correction, of the order of the error itself).
        self.sens_fresh = false;
        if t != self.t_last {
            self.map_ready = false;
            let h = self.ta - self.tp;
            if h > 0.0 && t >= self.tp && t < self.ta {
                let (y0, y1) = ([&self.qp[..], &self.vp[..], &self.ap[..]], [&self.qa[..], &self.va[..], &self.aa[..]]);
                hermite5((t - self.tp) / h, h, y0, y1, &mut self.q, &mut self.v);
            } else {
                let dt = t - self.ta;
                for &c in &self.dep {
                    self.q[c] = self.qa[c] + dt * (self.va[c] + 0.5 * dt * self.aa[c]);
                    self.v[c] = self.va[c] + dt * self.aa[c];
                }
            }
        }
        if shift {
            for (j, &c) in self.ind.iter().enumerate() {
                let (dq, dv) = (y[j] - self.q[c], y[p + j] - self.v[c]);
                let column = &self.sens[j * r..(j + 1) * r];
                for (&d, &sk) in self.dep.iter().zip(column) {
                    self.q[d] -= sk * dq;
                    self.v[d] -= sk * dv;
                }
            }
        }
        self.t_last = f64::NAN;
        for (j, &c) in self.ind.iter().enumerate() {
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
                for (b, &row) in self.rhs.iter_mut().zip(&self.rows) {
                    *b = -self.dae.phi[row];
                }
                // A residual that is round-off at the positions' scale is the solution: near a
                // singular position B amplifies it into corrections that are noise.
                if since > 0 && roundoff_ratio(&self.rhs, &self.zeros, scale) <= NEWTON_ROUNDOFF {
                    break;
                }
                self.solve();
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
                let distance = self.q.iter().zip(&self.factored_q).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                let left = if since == 1 {
                    let expected = CHORD_SAFETY * self.chord * distance;
                    if expected < 1.0 {
                        size * (expected / (1.0 - expected)).min(1.0)
                    } else {
                        size
                    }
                } else {
                    if distance > 0.0 {
                        self.chord = rate / distance;
                    }
                    size * rate / (1.0 - rate).max(f64::MIN_POSITIVE)
                };
                // Converged when that is far below the tolerance, or the correction is
                // round-off: no tolerance asks Newton for less than the positions' rounding.
                if (rate < 1.0 && left <= purpose.newton_tol())
                    || roundoff_ratio(&self.rhs, &self.qd, scale) <= NEWTON_ROUNDOFF
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
            let exact = self.reduced && yp.is_some();
            if exact {
                if !self.factor() {
                    return Ok(Eval::Failed { residual });
                }
                fresh = true;
            }
            self.dae.nu(&self.q, t, &mut self.nu);
            let vscale = self.v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let (mut since, mut previous) = (0, f64::INFINITY);
            let solved = exact && self.rows.iter().all(|&row| self.nu[row] == 0.0);
            if solved {
                // No constraint moves with time: `v_D = -S v_I` exactly, with the
                // sensitivities the accelerations use.
                self.sensitivities();
                for (k, &c) in self.dep.iter().enumerate() {
                    self.v[c] =
                        -self.ind.iter().enumerate().map(|(j, &i)| self.sens[j * r + k] * self.v[i]).sum::<f64>();
                }
            } else {
                loop {
                    self.dae.jv(&self.v, &mut self.phiv);
                    for (b, &row) in self.rhs.iter_mut().zip(&self.rows) {
                        *b = self.nu[row] - self.phiv[row];
                    }
                    self.solve();
                    since += 1;
                    let size = self.correct_dependent(false);
                    if !size.is_finite() {
                        return Ok(Eval::Failed { residual });
                    }
                    if exact || size <= NEWTON_TOL || roundoff_ratio(&self.rhs, &self.qd, vscale) <= NEWTON_ROUNDOFF {
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
        self.newton_iterations += iterations;
        self.t_last = t;
        // (q, v, t) => (qddot, lambda) => y' = (v_I, qddot_I).
        if let Some(yp) = yp {
            self.accelerations(t, purpose == Purpose::State)?;
            if !self.sol.iter().all(|x| x.is_finite()) {
                return Ok(Eval::Failed { residual });
            }
            for (j, &c) in self.ind.iter().enumerate() {
                yp[j] = self.v[c];
                yp[p + j] = self.sol[c];
            }
        }
        Ok(Eval::Done { iterations })
    }

    /// `sol = [qddot; lambda]` at the last evaluation `(q, v, t)`, with `B` factored at `q`:
    /// [`Split::reduced_accelerations`] when the partition allows (the multipliers only when
    /// asked: they are read from the accepted states and the output times alone), else the
    /// augmented system.
    fn accelerations(&mut self, t: f64, multipliers: bool) -> Result<(), Error> {
        if !(self.reduced && self.reduced_accelerations(t, multipliers)) {
            self.dae.accelerations(&self.q, &self.v, t, &mut self.sol)?;
        }
        Ok(())
    }

    /// `sol = [qddot; lambda]` at the last evaluation `(q, v, t)` in the independent
    /// coordinates, with `B` factored at `q` (the embedding of Wehage and Haug's partition):
    /// with `S = B^-1 Phi_q[rows, I]` ([`Split::sensitivities`], `p` solves, kept when fresh)
    /// and `w = B^-1 gamma`, the accelerations
    /// meeting the constraints are `qddot_D = w - S qddot_I`, and `Z = [I; -S]` spans the
    /// motions they allow, so `Z^T (M qddot - Q) = 0` is
    ///
    /// ```text
    /// (M_I + S^T M_D S) qddot_I = Q_I - S^T (Q_D - M_D w)        (p x p, positive definite)
    /// B^T lambda = (Q - M qddot)_D                                (the multipliers)
    /// ```
    ///
    /// The multipliers only when `multipliers` (else `sol`'s are left as they were).
    /// The same solution as the augmented system's (`Dae::accelerations`) to its regularisation
    /// `eps` (`1e-10` relative) for the rows without redundancy that this is used with. False
    /// when the reduced mass matrix is not positive definite to rounding (a coordinate with no
    /// mass): the caller solves the augmented system.
    fn reduced_accelerations(&mut self, t: f64, multipliers: bool) -> bool {
        let (n, p, r) = (self.dae.n, self.ind.len(), self.dep.len());
        if !self.sens_fresh {
            self.sensitivities();
        }
        let Some(block) = self.block.as_mut() else { return false };
        self.dae.load(&self.q, &self.v, t, &mut self.load);
        self.dae.gamma(&self.q, &self.v, t, &mut self.gamma);
        let mass = &self.dae.mass;
        for (w, &row) in self.particular.iter_mut().zip(&self.rows) {
            *w = self.gamma[row];
        }
        block.lu.solve(&mut self.particular);
        // The reduced mass matrix (row-major) and right-hand side.
        for (i, &ci) in self.ind.iter().enumerate() {
            let si = &self.sens[i * r..(i + 1) * r];
            let mut rhs = self.load[ci];
            for (k, &c) in self.dep.iter().enumerate() {
                rhs -= si[k] * (self.load[c] - mass[c] * self.particular[k]);
            }
            self.reduced_rhs[i] = rhs;
            for j in 0..=i {
                let sj = &self.sens[j * r..(j + 1) * r];
                let mut mij = if i == j { mass[ci] } else { 0.0 };
                for (k, &c) in self.dep.iter().enumerate() {
                    mij += mass[c] * si[k] * sj[k];
                }
                self.reduced_mass[i * p + j] = mij;
                self.reduced_mass[j * p + i] = mij;
            }
        }
        if !crate::linalg::dense::cholesky_solve_small(&mut self.reduced_mass, p, &mut self.reduced_rhs) {
            return false;
        }
        let (a, lambda) = self.sol.split_at_mut(n);
        for (&c, &x) in self.ind.iter().zip(&self.reduced_rhs) {
            a[c] = x;
        }
        for (k, &c) in self.dep.iter().enumerate() {
            a[c] = self.particular[k] - (0..p).map(|j| self.sens[j * r + k] * self.reduced_rhs[j]).sum::<f64>();
        }
        if multipliers {
            // (Q - M qddot)_D, then B^T lambda_rows = it; every row is a pivot row here.
            for (x, &c) in self.particular.iter_mut().zip(&self.dep) {
                *x = self.load[c] - mass[c] * a[c];
            }
            block.lu.solve_transpose(&mut self.particular);
            for (&row, &x) in self.rows.iter().zip(&self.particular) {
                lambda[row] = x;
            }
        }
        true
    }

    /// The last evaluation (with accelerations) at `t` becomes the accepted state, and `B` is
    /// factored there (false when singular).
    fn commit(&mut self, t: f64) -> bool {
        let n = self.q.len();
        self.tp = self.ta;
        std::mem::swap(&mut self.qp, &mut self.qa);
        std::mem::swap(&mut self.vp, &mut self.va);
        std::mem::swap(&mut self.ap, &mut self.aa);
        self.ta = t;
        self.qa.copy_from_slice(&self.q);
        self.va.copy_from_slice(&self.v);
        self.aa.copy_from_slice(&self.sol[..n]);
        self.la.copy_from_slice(&self.sol[n..]);
        self.record();
        self.factor()
    }

    /// The accepted state's time, velocities and accelerations become the newest of the ring.
    fn record(&mut self) {
        self.past_at = (self.past_at + 1) % self.past_t.len();
        self.past_t[self.past_at] = self.ta;
        self.past_v[self.past_at].copy_from_slice(&self.va);
        self.past_a[self.past_at].copy_from_slice(&self.aa);
    }

    /// `(v_I, qddot_I)` of the `j`-th accepted state back (0: the last), which is at `t`.
    fn past(&self, j: usize, t: f64, out: &mut [f64]) {
        let len = self.past_t.len();
        let at = (self.past_at + len - j) % len;
        debug_assert!(
            (self.past_t[at] - t).abs() <= 1e-9 * t.abs().max(1.0),
            "state {j} back at {} not {t}",
            self.past_t[at]
        );
        let p = self.ind.len();
        for (k, &c) in self.ind.iter().enumerate() {
            (out[k], out[p + k]) = (self.past_v[at][c], self.past_a[at][c]);
        }
    }

    /// `(y, y')` of the accepted state in the current coordinates.
    fn state(&self, y: &mut [f64], yp: &mut [f64]) {
        let p = self.ind.len();
        for (j, &c) in self.ind.iter().enumerate() {
            (y[j], y[p + j]) = (self.qa[c], self.va[c]);
            (yp[j], yp[p + j]) = (self.va[c], self.aa[c]);
        }
    }
}

/// A pivot may be at most this many times smaller than the largest entry of its row: the
/// threshold of the partition's elimination (partial pivoting by rows is 1). Among the entries
/// above it the sparsest pivot (Markowitz's count) is taken, so that the elimination keeps
/// `Phi_q`'s sparsity.
const PIVOT_THRESHOLD: f64 = 0.9;

/// Rows searched for the pivot at each elimination step: those with the fewest entries.
const PIVOT_ROWS: usize = 4;

/// Up to this many rows the partition's elimination runs on a dense copy of `Phi_q`
/// ([`PivotWork::run_dense`]), above it on sparse rows ([`PivotWork::run_sparse`]); both choose
/// the same pivots. The dense scans cost `m n` a step, `m^2 n` in all; the sparse path's heaps
/// and merges cost more per entry but grow with the entries alone. Measured on the N-four-bar's
/// `Phi_q` (one choice, dense against sparse): 4.3 against 6.5 us at 14 rows (the quick-return's
/// size), 7.8 against 10.3 at 20, 12.5 against 14.6 at 26; 18.2 against 16.6 at 32, 28.5
/// against 24.2 at 50. The crossover is between 26 and 32. Those matrices have one column more
/// than rows; the dense path's scans grow with the columns and the sparse path's work does not,
/// so a matrix of more than `28 x 29` entries (few constraints on many coordinates) goes sparse.
const DENSE_PIVOT_MAX_ROWS: usize = 28;

/// The partition's elimination ([`PivotWork::run`]) and its buffers, kept from one partition
/// to the next so that a choice allocates nothing once they have grown (allocation was a third
/// of the choice's cost on the quick-return).
#[derive(Debug, Default)]
struct PivotWork {
    /// Rows as sorted (column, value) lists, columns as the rows they hold entries in.
    rows: Vec<Vec<(usize, f64)>>,
    col_rows: Vec<Vec<usize>>,
    col_count: Vec<usize>,
    version: Vec<usize>,
    active: Vec<bool>,
    heap: std::collections::BinaryHeap<std::cmp::Reverse<(usize, usize, usize)>>,
    large: std::collections::BinaryHeap<(u64, usize, usize)>,
    skipped: Vec<std::cmp::Reverse<(usize, usize, usize)>>,
    top: Vec<std::cmp::Reverse<(usize, usize, usize)>>,
    merged: Vec<(usize, f64)>,
    /// The dense path's matrix (row-major, `m x n`), which of its entries are structural, each
    /// row's entry count and largest entry.
    dense: Vec<f64>,
    structural: Vec<bool>,
    row_len: Vec<usize>,
    row_big: Vec<f64>,
    /// The result: pivot rows and columns, ascending.
    prow: Vec<usize>,
    pcol: Vec<usize>,
}

impl PivotWork {
    /// The partition from the sparse `Phi_q` (`m x n`, entries `(row, column)` with values `jac`):
    /// Gaussian elimination with threshold pivoting, a structural choice with a numerical test as
    /// sparse LU codes make it (Duff, Erisman and Reid, "Direct Methods for Sparse Matrices",
    /// chapter 7). At each step the [`PIVOT_ROWS`] rows with the fewest entries are searched; the
    /// pivot is, among their entries of at least [`PIVOT_THRESHOLD`] times their row's largest, the
    /// one of least Markowitz count `(row entries - 1)(column entries - 1)`, ties to the larger
    /// relative to its row. A row whose entries have all fallen below [`RANK_TOLERANCE`] times the
    /// largest entry of `Phi_q` is numerically zero: redundant, it is left out. The pivots are the
    /// numerical rank. The pivot rows and columns, ascending, go to `prow` and `pcol`. Dense up
    /// to [`DENSE_PIVOT_MAX_ROWS`] rows (and `28 x 29` entries), sparse above (whose work grows
    /// with the fill, linearly in the length of a chain of bodies).
    fn run(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) {
        if m <= DENSE_PIVOT_MAX_ROWS && m * n <= DENSE_PIVOT_MAX_ROWS * (DENSE_PIVOT_MAX_ROWS + 1) {
            self.run_dense(m, n, entries, jac);
        } else {
            self.run_sparse(m, n, entries, jac);
        }
    }

    /// [`PivotWork::run`]'s choice on a dense copy of `Phi_q` that keeps which entries are
    /// structural (an entry made by fill stays one when it cancels, as in the sparse rows), with
    /// the same arithmetic and the same ties, so the same pivots: each step scans the active rows
    /// for the largest entry and the candidate rows, where the sparse path keeps heaps.
    fn run_dense(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) {
        let PivotWork { dense, structural, row_len, row_big, col_count, active, merged, prow, pcol, .. } = self;
        dense.clear();
        dense.resize(m * n, 0.0);
        structural.clear();
        structural.resize(m * n, false);
        row_len.clear();
        row_len.resize(m, 0);
        col_count.clear();
        col_count.resize(n, 0);
        for (&(r, c), &v) in entries.iter().zip(jac) {
            dense[r * n + c] += v;
            if !structural[r * n + c] {
                structural[r * n + c] = true;
                row_len[r] += 1;
                col_count[c] += 1;
            }
        }
        let big_of =
            |a: &[f64], s: &[bool]| a.iter().zip(s).fold(0.0f64, |x, (v, &e)| if e { x.max(v.abs()) } else { x });
        row_big.clear();
        row_big.extend(dense.chunks_exact(n.max(1)).zip(structural.chunks_exact(n.max(1))).map(|(a, s)| big_of(a, s)));
        row_big.resize(m, 0.0);
        let zero = RANK_TOLERANCE * row_big.iter().fold(0.0f64, |a, &x| a.max(x));
        active.clear();
        active.resize(m, true);
        prow.clear();
        pcol.clear();
        loop {
            let largest = (0..m).filter(|&r| active[r]).fold(0.0f64, |a, r| a.max(row_big[r]));
            if largest <= zero || largest.is_nan() {
                break;
            }
            // The PIVOT_ROWS active rows of fewest entries (ties to the lower row) whose largest
            // entry passes the threshold, by the test each entry then meets (so that each of them
            // holds an entry that passes it).
            let mut top = [(usize::MAX, usize::MAX); PIVOT_ROWS];
            for r in (0..m).filter(|&r| active[r] && row_big[r] / largest >= PIVOT_THRESHOLD) {
                let key = (row_len[r], r);
                if key < top[PIVOT_ROWS - 1] {
                    let at = top.iter().position(|&t| key < t).unwrap_or(PIVOT_ROWS - 1);
                    top.copy_within(at..PIVOT_ROWS - 1, at + 1);
                    top[at] = key;
                }
            }
            let mut best: Option<(usize, usize, usize, f64)> = None;
            for &(len, r) in top.iter().take_while(|t| t.1 != usize::MAX) {
                for c in (0..n).filter(|&c| structural[r * n + c]) {
                    let rel = dense[r * n + c].abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let cost = (len - 1) * (col_count[c] - 1);
                    if best.is_none_or(|(_, _, bc, brel)| cost < bc || (cost == bc && rel > brel)) {
                        best = Some((r, c, cost, rel));
                    }
                }
            }
            let (pr, pc, _, _) = best.expect("the largest entry's row passes the threshold");
            active[pr] = false;
            prow.push(pr);
            pcol.push(pc);
            // The pivot row's entries, then each active row holding column pc less its multiple.
            merged.clear();
            let at = pr * n..(pr + 1) * n;
            merged
                .extend((0..n).zip(&dense[at.clone()]).zip(&structural[at]).filter(|e| *e.1).map(|(e, _)| (e.0, *e.1)));
            for &(c, _) in merged.iter() {
                col_count[c] -= 1;
            }
            let pv = dense[pr * n + pc];
            for r in 0..m {
                if !active[r] || !structural[r * n + pc] {
                    continue;
                }
                let (values, flags) = (&mut dense[r * n..(r + 1) * n], &mut structural[r * n..(r + 1) * n]);
                let l = values[pc] / pv;
                for &(c, b) in merged.iter() {
                    if flags[c] {
                        values[c] -= l * b;
                    } else {
                        (values[c], flags[c]) = (-l * b, true);
                        row_len[r] += 1;
                        col_count[c] += 1;
                    }
                }
                (values[pc], flags[pc]) = (0.0, false);
                row_len[r] -= 1;
                col_count[pc] -= 1;
                row_big[r] = big_of(values, flags);
            }
        }
        prow.sort_unstable();
        pcol.sort_unstable();
    }

    /// [`PivotWork::run`] on sparse rows, with heaps of the rows by entry count and by largest
    /// entry: work linear in the entries of a chain. Returns the work (entries merged).
    fn run_sparse(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> usize {
        use std::cmp::Reverse;
        let PivotWork {
            rows, col_rows, col_count, version, active, heap, large, skipped, top, merged, prow, pcol, ..
        } = self;
        rows.resize_with(m, Vec::new);
        rows.iter_mut().for_each(Vec::clear);
        for (&(r, c), &v) in entries.iter().zip(jac) {
            rows[r].push((c, v));
        }
        col_rows.resize_with(n, Vec::new);
        col_rows.iter_mut().for_each(Vec::clear);
        for (r, row) in rows.iter_mut().enumerate() {
            row.sort_unstable_by_key(|e| e.0);
            row.dedup_by(|b, a| {
                let same = a.0 == b.0;
                if same {
                    a.1 += b.1;
                }
                same
            });
            for &(c, _) in row.iter() {
                col_rows[c].push(r);
            }
        }
        col_count.clear();
        col_count.extend(col_rows.iter().map(|r| r.len()));
        let row_max = |row: &[(usize, f64)]| row.iter().fold(0.0f64, |a, e| a.max(e.1.abs()));
        let big = rows.iter().fold(0.0f64, |a, row| a.max(row_max(row)));
        let zero = RANK_TOLERANCE * big;
        // Min-heap of (entries, row, version); stale versions are skipped.
        version.clear();
        version.resize(m, 0);
        heap.clear();
        heap.extend(rows.iter().enumerate().map(|(r, row)| Reverse((row.len(), r, 0))));
        // Max-heap of (largest |entry| as ordered bits, row, version): the largest remaining entry.
        large.clear();
        large.extend(rows.iter().enumerate().map(|(r, row)| (row_max(row).to_bits(), r, 0)));
        active.clear();
        active.resize(m, true);
        prow.clear();
        pcol.clear();
        let mut work = 0usize;
        loop {
            // The largest remaining entry; none above the rank tolerance: the rank is reached.
            let largest = loop {
                match large.peek() {
                    Some(&(_, r, v)) if !active[r] || version[r] != v => {
                        large.pop();
                    }
                    Some(&(bits, _, _)) => break f64::from_bits(bits),
                    None => break 0.0,
                }
            };
            if largest <= zero || largest.is_nan() {
                break;
            }
            // The sparsest rows holding an entry above the threshold (fresh heap entries only), by
            // the test each entry then meets.
            top.clear();
            skipped.clear();
            while top.len() < PIVOT_ROWS {
                let Some(e) = heap.pop() else { break };
                let r = e.0 .1;
                if !active[r] || version[r] != e.0 .2 {
                    continue;
                }
                if row_max(&rows[r]) / largest >= PIVOT_THRESHOLD {
                    top.push(e);
                } else {
                    skipped.push(e);
                }
            }
            heap.extend(skipped.iter().copied());
            let mut best: Option<(usize, usize, usize, f64, f64)> = None;
            for &Reverse((_, r, _)) in top.iter() {
                for &(c, v) in &rows[r] {
                    let rel = v.abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let cost = (rows[r].len() - 1) * (col_count[c] - 1);
                    let better = match best {
                        None => true,
                        Some((_, _, bc, _, brel)) => cost < bc || (cost == bc && rel > brel),
                    };
                    if better {
                        best = Some((r, c, cost, v, rel));
                    }
                }
            }
            // The other rows go back on the heap unchanged.
            let (pr, pc, _, pv, _) = best.expect("the largest entry's row passes the threshold");
            for &e in top.iter() {
                if e.0 .1 != pr {
                    heap.push(e);
                }
            }
            active[pr] = false;
            for &(c, _) in &rows[pr] {
                col_count[c] -= 1;
            }
            prow.push(pr);
            pcol.push(pc);
            // Eliminate column pc from the other active rows that hold it.
            let pivot_row = std::mem::take(&mut rows[pr]);
            for k in 0..col_rows[pc].len() {
                let r = col_rows[pc][k];
                if !active[r] {
                    continue;
                }
                let Ok(at) = rows[r].binary_search_by_key(&pc, |e| e.0) else { continue };
                let l = rows[r][at].1 / pv;
                merged.clear();
                let (a, b) = (&rows[r], &pivot_row);
                let (mut i, mut j) = (0, 0);
                while i < a.len() || j < b.len() {
                    let ca = a.get(i).map_or(usize::MAX, |e| e.0);
                    let cb = b.get(j).map_or(usize::MAX, |e| e.0);
                    if ca < cb {
                        merged.push(a[i]);
                        i += 1;
                    } else if cb < ca {
                        // Fill: a new entry of row r in column cb.
                        merged.push((cb, -l * b[j].1));
                        col_rows[cb].push(r);
                        col_count[cb] += 1;
                        j += 1;
                    } else {
                        merged.push((ca, a[i].1 - l * b[j].1));
                        i += 1;
                        j += 1;
                    }
                }
                work += merged.len();
                merged.retain(|e| e.0 != pc);
                col_count[pc] -= 1;
                // Copied, not swapped: each row keeps its own buffer, which stops growing after
                // the first choices (a swap hands buffers round, and a short one grows again).
                rows[r].clear();
                rows[r].extend_from_slice(merged);
                version[r] += 1;
                heap.push(Reverse((rows[r].len(), r, version[r])));
                large.push((row_max(&rows[r]).to_bits(), r, version[r]));
            }
            rows[pr] = pivot_row;
        }
        prow.sort_unstable();
        pcol.sort_unstable();
        work
    }
}

/// (Re)start the Adams method at the accepted state in the coordinates of the partition.
fn begin(s: &Split<'_, '_>, ad: &mut Adams) {
    ad.resize(2 * s.ind.len());
    s.state(&mut ad.y, &mut ad.yp);
    ad.restart(s.ta);
}

/// Carry the Adams method over to a new partition's coordinates at the accepted state, its
/// order, step and history kept: the differences of the new coordinates are rebuilt from their
/// derivatives at the past accepted states ([`Adams::rebase`]). The number of independent
/// coordinates is the rank's complement and does not change; if it did, a restart.
fn carry(s: &Split<'_, '_>, ad: &mut Adams) {
    if ad.neq != 2 * s.ind.len() {
        begin(s, ad);
        return;
    }
    debug_assert_eq!(ad.x, s.ta);
    s.state(&mut ad.y, &mut ad.yp);
    ad.rebase(&mut |j, t, out| s.past(j, t, out));
}

/// Integrate from `start` to the output's end time.
pub fn run(dae: &mut Dae<'_>, out: &mut Output, settings: &IntegratorSettings, start: Start) -> Outcome {
    let run = Span::new(settings, &start, out.t_end(), 0);
    let (t_end, h_max, h_start) = (run.t_end, run.h_max, run.h_start);
    let mut stats = DynamicStats::default();
    let mut s = Split::new(dae, settings, start);
    let mut ad = Adams::new(settings.order_limit().clamp(1, MAX_ORDER));
    let mut h = h_start;
    // The largest recent accepted step, decaying by RECENT_DECAY a step.
    let mut h_recent = h_start;
    // Partition at the start and (y, y') there.
    s.choose();
    stats.partitions += 1;
    begin(&s, &mut ad);
    let mut chosen_at = 0;
    let n = s.dae.n;
    let (mut yo, mut ypo) = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
    let outcome = (|| -> Result<(), Error> {
        while run.before_end(ad.x) {
            // Adams' accepted steps shrink the step only by a bounded factor; the error test
            // decides below the smallest step.
            let h_min = run.smallest_step(out, s.dae, &s.qa, stats.steps, ad.x, h, settings, false)?;
            h = run.fit(ad.x, h);
            // (y, phi, h) => prediction p at x + h => y'(p).
            s.weights();
            ad.coefficients(h);
            ad.predict(h);
            let t1 = ad.x;
            let mut eval = s.evaluate(t1, &ad.p, Some(&mut ad.yp), Purpose::Prediction)?;
            let mut err = f64::NAN;
            let mut noise = false;
            if let Eval::Done { .. } = eval {
                err = ad.error_test(h, &mut |x| s.norm(x));
                if err > 1.0 {
                    // Judged on the prediction converged as every other evaluation is: the noise
                    // test samples one more Newton correction, and the prediction's looser stop
                    // would be that sample's size.
                    eval = s.evaluate(t1, &ad.p, Some(&mut ad.yp), Purpose::Judged)?;
                    if let Eval::Done { .. } = eval {
                        err = ad.error_test(h, &mut |x| s.norm(x));
                    }
                }
                if err <= 1.0 {
                    // (p, y'(p)) => corrected yc => y'(yc).
                    ad.correct(h);
                    eval = s.evaluate(t1, &ad.yc, Some(&mut ad.yp), Purpose::State)?;
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
                let stop = (s.ta + CROSSING_STEPS * h_recent).min(t_end);
                if stop - s.ta < h_min {
                    let cause = "the error estimate is the round-off noise of a singular position, and the step left to cross it is below the smallest";
                    return Err(step_failure(s.dae, &s.qa, s.ta, h, cause));
                }
                stats.crossings += 1;
                stats.first_crossing.get_or_insert(s.ta);
                // bdf's own first step and order limit; the same tolerances, formulation and budget.
                let across =
                    IntegratorSettings { kind: IntegratorKind::Bdf, max_order: None, initial_step: None, ..*settings };
                let begin_at =
                    Start { t: s.ta, q: s.qa.clone(), qdot: s.va.clone(), qddot: s.aa.clone(), lambda: s.la.clone() };
                let (crossed, reached) = super::bdf::run_until(s.dae, out, &across, begin_at, stop, stats.steps);
                stats.absorb(&crossed);
                let (t, q, v) = reached?;
                s.resume(t, &q, &v)?;
                chosen_at = stats.steps;
                if s.choose() {
                    stats.partitions += 1;
                }
                begin(&s, &mut ad);
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
                        return Err(step_failure(s.dae, &s.qa, s.ta, h, &cause));
                    }
                    continue;
                }
                Eval::Failed { residual } => {
                    stats.newton_failures += 1;
                    h = ad.reject(h);
                    if stats.steps > chosen_at && s.choose() {
                        // The dependent coordinates may be the trouble: new ones.
                        stats.partitions += 1;
                        carry(&s, &mut ad);
                    }
                    chosen_at = stats.steps;
                    if h < h_min {
                        let cause = format!(
                            "Newton's method for the dependent coordinates does not converge (constraint residual {residual:.3e}) even with the smallest step"
                        );
                        return Err(step_failure(s.dae, &s.qa, s.ta, h, &cause));
                    }
                    continue;
                }
            };
            if let Some(r) = s.dae.contact_event(&s.qa, &s.q) {
                // A first contact inside the step: shorter, until the step ends just into it (as
                // bdf and hht; the corrected positions of the step are those tested).
                stats.rejected_steps += 1;
                ad.reject(h);
                h *= r;
                if h < h_min {
                    return Err(step_failure(s.dae, &s.qa, s.ta, h, CONTACT_UNRESOLVED));
                }
                continue;
            }
            // Accept: differences, order and next step; the state; work; output times.
            let h_used = h;
            h_recent = h_used.max(RECENT_DECAY * h_recent);
            h = ad.accept(h, &mut |x| s.norm(x)).min(h_max);
            let singular = !s.commit(ad.x);
            stats.accept(h_used);
            stats.max_order_used = stats.max_order_used.max(ad.kold);
            // The sensitivity at the next step, extrapolated from its growth over this one: the
            // partition changes before a step would carry it past GROWTH, not after.
            let influence = s.influence();
            let next = influence * (influence / s.influence1).max(1.0);
            s.influence1 = influence;
            let degraded = singular || iterations > NEWTON_SLOW || next.is_nan() || next > GROWTH * s.influence0;
            out.advance_work(s.dae, s.ta, &s.qa, &s.va, &s.la);
            let neq = ad.neq;
            while let Some(to) = out.due(ad.x) {
                ad.interpolate(to, &mut yo[..neq], &mut ypo[..neq]);
                // With the accelerations: the reduced solve where it applies is cheaper than
                // the augmented one the output would make (the same solution, to its
                // regularisation).
                match s.evaluate(to, &yo[..neq], Some(&mut ypo[..neq]), Purpose::State)? {
                    Eval::Done { .. } => out.push_solved(s.dae, to, &s.q, &s.v, &s.sol)?,
                    // The interpolated q_I leaves no nearby q_D (a partition near its fold inside
                    // a long step): the output is the quintic Hermite interpolant of the whole
                    // state between the step's ends, within the step's error, its constraint
                    // residual reported with it.
                    Eval::Failed { .. } if s.ta > s.tp && to >= s.tp => {
                        let h = s.ta - s.tp;
                        let (y0, y1) = ([&s.qp[..], &s.vp[..], &s.ap[..]], [&s.qa[..], &s.va[..], &s.aa[..]]);
                        hermite5((to - s.tp) / h, h, y0, y1, &mut s.q, &mut s.v);
                        s.t_last = f64::NAN;
                        out.push(s.dae, to, &s.q, &s.v)?
                    }
                    Eval::Failed { residual } => {
                        let cause = format!(
                            "Newton's method for the dependent coordinates at the output time {to} does not converge (constraint residual {residual:.3e})"
                        );
                        return Err(step_failure(s.dae, &s.qa, s.ta, h_used, &cause));
                    }
                }
            }
            if degraded {
                chosen_at = stats.steps;
                if s.choose() {
                    stats.partitions += 1;
                    carry(&s, &mut ad);
                }
            }
        }
        Ok(())
    })();
    stats.newton_iterations += s.newton_iterations;
    (stats, outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`PivotWork::run_sparse`] with fresh buffers: the pivot rows and columns and the work.
    fn pivots(m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> (Vec<usize>, Vec<usize>, usize) {
        let mut w = PivotWork::default();
        let work = w.run_sparse(m, n, entries, jac);
        (w.prow, w.pcol, work)
    }

    /// `pivots` of a dense matrix given by rows.
    fn dense_pivots(rows: &[&[f64]], n: usize) -> (Vec<usize>, Vec<usize>) {
        let mut entries = vec![];
        let mut values = vec![];
        for (r, row) in rows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    entries.push((r, c));
                    values.push(v);
                }
            }
        }
        let (m, (rows, cols, _)) = (rows.len(), pivots(rows.len(), n, &entries, &values));
        let mut dense = PivotWork::default();
        dense.run_dense(m, n, &entries, &values);
        assert_eq!((&dense.prow, &dense.pcol), (&rows, &cols), "the dense path chooses as the sparse one");
        (rows, cols)
    }

    /// The pivots skip a redundant row (row 1 = row 0 + row 2 / 2: two of the three rows) and a
    /// column that no constraint touches, and take the large entries: columns 1 (entry 5, not
    /// the 1 beside it) and 2.
    #[test]
    fn pivots_skip_redundant_rows() {
        let (rows, cols) = dense_pivots(&[&[1.0, 5.0, 0.0, 0.0], &[1.0, 5.0, 2.0, 0.0], &[0.0, 0.0, 4.0, 0.0]], 4);
        assert_eq!(cols, vec![1, 2]);
        assert!(rows.len() == 2 && rows.contains(&2), "{rows:?}");
        assert_eq!(dense_pivots(&[&[0.0, 0.0, 4.0]], 3), (vec![0], vec![2]));
        assert_eq!(dense_pivots(&[], 3), (vec![], vec![]));
        // Numerically dependent rows are left out: row 1 is row 0 times 2 up to 1e-12, below
        // RANK_TOLERANCE times the largest entry; the larger row's larger entry is the pivot.
        assert_eq!(dense_pivots(&[&[1.0, 3.0], &[2.0, 6.0 + 1e-12]], 2), (vec![1], vec![1]));
    }

    /// [`PivotWork::run`]'s choice, written densely and by brute force: at each step, of the
    /// active rows whose largest entry is at least [`PIVOT_THRESHOLD`] of the largest remaining,
    /// the [`PIVOT_ROWS`] with the fewest entries (ties to the lower row); among their entries
    /// of at least that fraction of the largest, the least Markowitz count, ties to the larger.
    /// Entries are structural (an entry made by fill stays one when it cancels).
    fn reference_pivots(m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> (Vec<usize>, Vec<usize>) {
        let mut a = vec![vec![None::<f64>; n]; m];
        for (&(r, c), &v) in entries.iter().zip(jac) {
            a[r][c] = Some(a[r][c].unwrap_or(0.0) + v);
        }
        let row_max = |row: &[Option<f64>]| row.iter().flatten().fold(0.0f64, |x, v| x.max(v.abs()));
        let zero = RANK_TOLERANCE * a.iter().map(|row| row_max(row)).fold(0.0, f64::max);
        let mut active = vec![true; m];
        let (mut prow, mut pcol) = (vec![], vec![]);
        loop {
            let largest = (0..m).filter(|&r| active[r]).map(|r| row_max(&a[r])).fold(0.0, f64::max);
            if largest <= zero || largest.is_nan() {
                break;
            }
            let len = |row: &[Option<f64>]| row.iter().flatten().count();
            let mut candidates: Vec<(usize, usize)> = (0..m)
                .filter(|&r| active[r] && row_max(&a[r]) / largest >= PIVOT_THRESHOLD)
                .map(|r| (len(&a[r]), r))
                .collect();
            candidates.sort_unstable();
            candidates.truncate(PIVOT_ROWS);
            let mut best: Option<(usize, usize, usize, f64)> = None;
            for &(l, r) in &candidates {
                for c in 0..n {
                    let Some(v) = a[r][c] else { continue };
                    let rel = v.abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let count = (0..m).filter(|&k| active[k] && a[k][c].is_some()).count();
                    let cost = (l - 1) * (count - 1);
                    if best.is_none_or(|(_, _, bc, brel)| cost < bc || (cost == bc && rel > brel)) {
                        best = Some((r, c, cost, rel));
                    }
                }
            }
            let (pr, pc, _, _) = best.unwrap();
            active[pr] = false;
            prow.push(pr);
            pcol.push(pc);
            let pivot = a[pr].clone();
            let pv = pivot[pc].unwrap();
            for r in (0..m).filter(|&r| active[r]) {
                let Some(x) = a[r][pc] else { continue };
                let l = x / pv;
                for c in 0..n {
                    if let Some(b) = pivot[c] {
                        a[r][c] = Some(a[r][c].map_or(-l * b, |y| y - l * b));
                    }
                }
                a[r][pc] = None;
            }
        }
        prow.sort_unstable();
        pcol.sort_unstable();
        (prow, pcol)
    }

    /// The partition's elimination, sparse (its heaps, versions and merges) and dense, chooses as
    /// the brute-force reference does, on 600 random sparse matrices of 2 to 24 rows: entries of
    /// one size (most rows pass the threshold), entries over six decades (few pass), a fifth with
    /// entries of 1 and 2 only (exact ties, broken by the rule's order), and a third with a row
    /// repeated as the sum of two others (redundant, left out).
    #[test]
    fn pivots_match_the_dense_reference() {
        let mut seed = 11u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut redundant = 0;
        // One set of buffers for every case, as a partition keeps them.
        let mut dense_work = PivotWork::default();
        for case in 0..600 {
            let m = 2 + (random() * 23.0) as usize;
            let n = m + 1 + (random() * 3.0) as usize;
            let mut dense = vec![vec![None::<f64>; n]; m];
            for (r, row) in dense.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    if random() < 0.25 || c == r {
                        let size = match case % 5 {
                            // Exact ties, as a Jacobian's unit entries make them.
                            4 => 1.0 + (random() * 2.0).floor(),
                            _ if case % 2 == 0 => 0.5 + 0.5 * random(),
                            _ => 10f64.powf(6.0 * random() - 3.0),
                        };
                        *x = Some(if random() < 0.5 { size } else { -size });
                    }
                }
            }
            let repeated = case % 3 == 0 && m >= 3;
            if repeated {
                dense[m - 1] = (0..n)
                    .map(|c| match (dense[0][c], dense[1][c]) {
                        (None, None) => None,
                        (x, y) => Some(x.unwrap_or(0.0) + y.unwrap_or(0.0)),
                    })
                    .collect();
            }
            let (mut entries, mut jac) = (vec![], vec![]);
            for (r, row) in dense.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    if let Some(v) = x {
                        entries.push((r, c));
                        jac.push(*v);
                    }
                }
            }
            let (rows, cols, _) = pivots(m, n, &entries, &jac);
            redundant += usize::from(repeated && rows.len() < m);
            let reference = reference_pivots(m, n, &entries, &jac);
            assert_eq!((rows, cols), reference, "case {case}: {m} x {n}, sparse");
            dense_work.run_dense(m, n, &entries, &jac);
            assert_eq!((&dense_work.prow, &dense_work.pcol), (&reference.0, &reference.1), "case {case}: dense");
        }
        assert!(redundant > 150, "{redundant} repeated rows found redundant");
    }

    /// The quick-return with its forces (the crank torque and the slider's force), partitioned
    /// at the file's positions at rest: `test` gets the split, with these settings.
    fn on_the_quick_return(settings: &IntegratorSettings, test: impl FnOnce(&mut Split<'_, '_>)) {
        let text = include_str!("../../../../../examples/quick_return_a.yaml");
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
            assert!(s.reduced, "one independent coordinate, no redundant rows, no friction");
            let p = s.ind.len();
            let (mut y, mut yp) = (vec![0.0; 2 * p], vec![0.0; 2 * p]);
            s.state(&mut y, &mut yp);
            y[p] = 5.0;
            s.weights();
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
            assert!(s.map_ready);
            assert!(matches!(s.evaluate(0.0, &moved, Some(&mut yp), Purpose::State).unwrap(), Eval::Done { .. }));
            assert!(s.map_ready, "the map is kept at the same time");
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
            assert!(s.map_ready);
            s.reduced = false;
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
    /// with [`CHORD_SAFETY`] 1 (the expected rate taken as it is). The chord's rate must have
    /// been measured, and most corrections must stop after one iteration (93 of 100), so that
    /// the expectation is what is tested.
    #[test]
    fn newton_leaves_each_state_within_its_tolerance() {
        let settings = IntegratorSettings { rtol: 1e-4, atol: 1e-4, ..IntegratorSettings::default() };
        on_the_quick_return(&settings, |s| {
            let p = s.ind.len();
            let (mut y, mut yp) = (vec![0.0; 2 * p], vec![0.0; 2 * p]);
            s.state(&mut y, &mut yp);
            y[p] = 50.0;
            s.weights();
            assert!(matches!(s.evaluate(0.0, &y, Some(&mut yp), Purpose::State).unwrap(), Eval::Done { .. }));
            assert!(s.commit(0.0));
            let (h, mut one, mut worst) = (1.5e-3, 0, 0.0f64);
            let steps = 100;
            for k in 1..=steps {
                let t = k as f64 * h;
                s.weights();
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
                let before = s.newton_iterations;
                let eval = s.evaluate(t, &corrected, Some(&mut yp), Purpose::State).unwrap();
                assert!(matches!(eval, Eval::Done { .. }), "correction at {t}: {eval:?}");
                one += usize::from(s.newton_iterations - before == 1);
                // One more correction, with B factored at the state reached.
                let q = s.q.clone();
                s.dae.positions(&q, t);
                s.factored_ok = false;
                assert!(s.factor());
                for (b, &row) in s.rhs.iter_mut().zip(&s.rows) {
                    *b = -s.dae.phi[row];
                }
                s.solve();
                let left =
                    super::super::wrms(s.dep.iter().zip(&s.rhs).map(|(&c, &d)| (d, q[c])), s.dep.len(), s.rtol, s.atol);
                worst = worst.max(left / NEWTON_TOL);
                s.dae.positions(&q, t);
                assert!(s.commit(t));
                y = corrected;
                // Re-partitioned as `run` does.
                let influence = s.influence();
                let next = influence * (influence / s.influence1).max(1.0);
                s.influence1 = influence;
                if next > GROWTH * s.influence0 {
                    s.choose();
                    s.state(&mut y, &mut yp);
                }
            }
            eprintln!("{one} of {steps} corrections in one iteration; the worst left {worst:.3} of the tolerance");
            assert!(s.chord.is_finite(), "the chord's rate was measured");
            assert!(one > steps / 2, "{one} of {steps} in one iteration");
            assert!(worst <= 0.1, "a state left {worst:.3} times Newton's tolerance from the solution");
        });
    }

    /// The IFToMM A02 N-four-bar with `n` loops, as `examples/nfourbar.py` writes it.
    fn nfourbar(n: usize) -> String {
        let mut y = String::from("name: nfourbar\ngravity: [0, -9.81]\nbodies:\n");
        for k in 0..=n {
            y += &format!("  r{k}: {{mass: 1, inertia: 0.0833333333333333, position: [{k}, 0.5], angle: 1.5707963267948966, velocity: [0.5, 0], omega: -1, points: {{A: [-0.5, 0], B: [0.5, 0]}}}}\n");
        }
        for k in 1..=n {
            y += &format!("  c{k}: {{mass: 1, inertia: 0.0833333333333333, position: [{}, 1], angle: 0, velocity: [1, 0], points: {{L: [-0.5, 0], R: [0.5, 0]}}}}\n", k as f64 - 0.5);
        }
        y += "joints:\n";
        for k in 0..=n {
            y += &format!("  A{k}: {{type: revolute, body_i: r{k}, point_i: A, body_j: ground, point_j: [{k}, 0]}}\n");
        }
        for k in 1..=n {
            y += &format!("  L{k}: {{type: revolute, body_i: c{k}, point_i: L, body_j: r{}, point_j: B}}\n", k - 1);
            y += &format!("  R{k}: {{type: revolute, body_i: c{k}, point_i: R, body_j: r{k}, point_j: B}}\n");
        }
        y + "analyses:\n  dynamics: {type: dynamic, t_end: 1, step: 0.01}\n"
    }

    /// The partition's elimination keeps `Phi_q`'s sparsity: on the N-four-bar (`6N + 3`
    /// coordinates, `6N + 2` rows of which `N - 1` are redundant) its work grows linearly with
    /// N, as the number of entries does. Measured: 591 entries merged at N = 10, 4,931 at N = 80
    /// (8.3 times for 8 times the bodies). The dense full-pivoting LU it replaced costs `~m n^2`
    /// (512 times); a first sparse version that took its pivots from the rows with the largest
    /// entries filled in along the chain (0.59 M entries merged at N = 100, 8.5 M at N = 200). The
    /// rank is the mechanism's: one degree of freedom.
    #[test]
    fn partition_work_grows_linearly() {
        let mut work = vec![];
        for n in [10, 80] {
            let model = crate::model::Model::from_yaml(&nfourbar(n)).unwrap();
            let mut dae = Dae::new(&model, &[], &[]).unwrap();
            dae.positions(&model.q0(), 0.0);
            let (entries, jac) = dae.jacobian_entries();
            let (rows, cols, w) = pivots(dae.m, dae.n, entries, jac);
            assert_eq!((rows.len(), cols.len()), (dae.n - 1, dae.n - 1), "N = {n}: one degree of freedom");
            eprintln!("N = {n}: {} coordinates, {} entries, work {w}", dae.n, entries.len());
            work.push(w as f64);
        }
        let growth = work[1] / work[0];
        assert!(growth < 12.0, "work grows {growth} times for 8 times the bodies");
    }
}
