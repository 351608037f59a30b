//! Kinematic analysis of a fully driven mechanism (Haug 1989 chapter 4; Nikravesh 2018 chapter 8).
//!
//! At each output time: Newton-Raphson on `Phi(q, t) = 0` from the predictor
//! `q + h qdot + h^2/2 qddot`, then the linear solves `Phi_q qdot = nu` and `Phi_q qddot = gamma`
//! with the factorization of `Phi_q` at the converged position. Between output times the solver
//! takes sub-steps: no body may turn more than `max_rotation` in one, and a sub-step whose Newton
//! iteration fails, or whose correction is larger than half the predicted motion (a jump to the
//! other assembly branch), is halved. The square system keeps the independent rows only; rows
//! found redundant at assembly hold implicitly and are reported.
//!
//! One sparse symbolic factorization per analysis; one numeric factorization per sub-step (it
//! also serves as the chord-Newton matrix of the next sub-step); nothing is allocated in the time
//! loop except the growth of the output columns, reserved up front.

use super::sensitivity::Sensitivity;
use super::setup::{fail, held, output_times, unmet_freedom};
use super::{assemble_into, scaled_residual, scaled_residual_floor, Assembly, Run, SINGULAR_RATIO_KINEMATIC};
use crate::constraints::{Config, ConfigBuf};
use crate::error::{Error, Problem, RowName};
use crate::linalg::rows::row_scales;
use crate::linalg::{ColMatrix, FactorError, SparseLu};
use crate::model::{Analysis, Model};
use crate::results::{Failure, KinematicStats, Results, Statistics};
use crate::system::System;

/// Sub-steps between two output times beyond which the motion is too fast to follow: 100,000,
/// a body turning up to 35,000 rad (5,600 turns, at the default `max_rotation`) between two
/// outputs, which no output grid can show. Without it a driver `exp(40*t)` took 2.5e8
/// sub-steps (430 s) to reach the `min_substep` floor.
const MAX_SUBSTEPS_PER_OUTPUT: usize = 100_000;

/// Why a Newton attempt failed.
struct NewtonFailure {
    residual: f64,
    row: usize,
    iterations: usize,
}

/// How the attempt at a sub-step ended.
enum Attempt {
    /// Newton converged near the predictor: the sub-step is accepted.
    Converged,
    /// Newton converged farther from the predictor than half the predicted motion: a jump to
    /// the other assembly branch.
    BranchJump,
    /// Newton did not converge.
    Failed(NewtonFailure),
}

/// State and buffers of one kinematic analysis.
struct Solver<'m> {
    sys: System<'m>,
    /// (n) independent rows of the system, ascending.
    rows: Vec<usize>,
    lu: SparseLu,
    /// (m) full residual / right-hand side buffer.
    full: Vec<f64>,
    /// (n) right-hand side in the independent rows.
    rhs: Vec<f64>,
    /// (n) position, velocity and acceleration at `t`.
    q: Vec<f64>,
    qdot: Vec<f64>,
    qddot: Vec<f64>,
    /// (n) Newton iterate of the sub-step being tried.
    trial: Vec<f64>,
    /// (bodies) `(cos phi, sin phi)` of `q` and of `trial`, computed once per position.
    rot_q: Vec<[f64; 2]>,
    rot_trial: Vec<[f64; 2]>,
    /// (n) scales of the coordinates and of the independent rows of the last factorization
    /// (`super::Scaled`): the residual and the condition free of units.
    col_scale: Vec<f64>,
    row_scale: Vec<f64>,
    t: f64,
    tolerance: f64,
    max_iterations: usize,
    stats: KinematicStats,
}

impl Solver<'_> {
    fn factor_error(&self, e: FactorError) -> Error {
        match e {
            FactorError::StructurallySingular { column } => Error::Singular {
                time: self.t,
                rows: vec![],
                detail: format!(
                    "no equation determines coordinate {column} (the driven Jacobian is structurally singular)"
                ),
            },
            FactorError::OutOfMemory => Error::OutOfMemory { time: self.t, what: "while factorizing".into() },
        }
    }

    /// Factorize `Phi_q` at `q`.
    fn factor_at(&mut self, q_is_trial: bool, t: f64) -> Result<(), Error> {
        // `rot_trial` always matches `trial` here: Newton evaluates the residual first.
        let q = if q_is_trial { Config::new(&self.trial, &self.rot_trial) } else { Config::new(&self.q, &self.rot_q) };
        let (pattern, values) = self.lu.pattern_and_values();
        self.sys.fill_jacobian(pattern, &q, t, values);
        row_scales(&pattern.col_ptr, &pattern.row_idx, values, &self.col_scale, &mut self.row_scale);
        self.stats.factorizations += 1;
        self.lu.factor().map_err(|e| self.factor_error(e))
    }

    /// With `Phi_q` factorized at `(q, t)`: `qdot` from `nu` and `qddot` from `gamma`.
    fn velocities(&mut self) {
        let q = Config::new(&self.q, &self.rot_q);
        self.sys.nu(&q, self.t, &mut self.full);
        gather(&self.full, &self.rows, &mut self.rhs);
        self.lu.solve(&mut self.rhs);
        self.qdot.copy_from_slice(&self.rhs);
        self.sys.gamma(&q, &self.qdot, self.t, &mut self.full);
        gather(&self.full, &self.rows, &mut self.rhs);
        self.lu.solve(&mut self.rhs);
        self.qddot.copy_from_slice(&self.rhs);
    }

    /// Newton on `trial` at time `t`, starting from the current factorization (chord steps).
    /// The Jacobian is refactorized at the iterate when the observed contraction `rho` would need
    /// more than three further chord steps to reach the tolerance (`r rho^3 > tol`): a chord step
    /// costs a residual and a solve, a refactorization several solves.
    /// Ends [`Attempt::Converged`] or [`Attempt::Failed`]; the caller tells a branch jump.
    fn newton(&mut self, t: f64) -> Result<Attempt, Error> {
        let mut previous = f64::INFINITY;
        for it in 0..=self.max_iterations {
            Config::rotations(&self.trial, &mut self.rot_trial);
            self.sys.phi(&Config::new(&self.trial, &self.rot_trial), t, &mut self.full);
            gather(&self.full, &self.rows, &mut self.rhs);
            let (row, r) = scaled_residual(&self.rhs, &self.row_scale, self.sys.length);
            let tolerance = self.tolerance.max(scaled_residual_floor(&self.trial, self.sys.length));
            if r <= tolerance {
                self.stats.max_residual = self.stats.max_residual.max(worst(&self.rhs).1);
                return Ok(Attempt::Converged);
            }
            if it == self.max_iterations || !r.is_finite() || r > 1e3 * previous.min(1e300) {
                let residual = self.rhs[row].abs();
                return Ok(Attempt::Failed(NewtonFailure { residual, row: self.rows[row], iterations: it }));
            }
            let rho = r / previous;
            if r * rho * rho * rho > tolerance {
                self.factor_at(true, t)?;
            }
            previous = r;
            self.stats.newton_iterations += 1;
            self.lu.solve(&mut self.rhs);
            for (x, d) in self.trial.iter_mut().zip(&self.rhs) {
                *x -= d;
            }
        }
        unreachable!("the loop returns at it == max_iterations")
    }

    /// The residual of every row (the redundant ones too) at the solver's position, checked
    /// against what an output promises ([`super::promise::check_kinematic`]).
    fn check_output(&mut self) -> Result<(), Error> {
        self.sys.phi(&Config::new(&self.q, &self.rot_q), self.t, &mut self.full);
        let (row, residual) = worst(&self.full);
        let sys = &self.sys;
        super::promise::check_kinematic(self.t, &self.q, &self.qdot, residual, || sys.row_name(row), self.tolerance)
    }

    /// The ratio of the smallest to the largest singular value of the driven Jacobian at `q`,
    /// and the rows of the smallest ([`RowSpace::smallest_singular`](crate::linalg::rows::RowSpace::smallest_singular)).
    fn diagnose(&mut self) -> (f64, Vec<RowName>) {
        let pattern = self.sys.pattern(&self.rows);
        let mut values = vec![0.0; pattern.row_idx.len()];
        self.sys.fill_jacobian(&pattern, &Config::new(&self.q, &self.rot_q), self.t, &mut values);
        let jac = ColMatrix::new(&pattern, values);
        let Ok(mut space) = super::scaled_row_space(&self.sys, &jac, 0..jac.ncols(), self.t) else {
            return (0.0, vec![]);
        };
        let (ratio, rows) = space.smallest_singular();
        (ratio, rows.into_iter().map(|i| self.sys.row_name(self.rows[i])).collect())
    }
}

/// `out[k] = full[rows[k]]`.
fn gather(full: &[f64], rows: &[usize], out: &mut [f64]) {
    for (o, &r) in out.iter_mut().zip(rows) {
        *o = full[r];
    }
}

/// Index and absolute value of the largest entry.
fn worst(v: &[f64]) -> (usize, f64) {
    v.iter()
        .enumerate()
        .fold((0, 0.0f64), |(bk, bx), (k, x)| if x.abs() > bx || x.is_nan() { (k, x.abs()) } else { (bk, bx) })
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Run a kinematic analysis. On failure the results up to the last good output time are kept.
pub(crate) fn run_kinematic(model: &Model, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
    let names = model.measures.iter().map(|m| m.name.clone()).collect();
    let values = |t: f64, q: &[f64], qdot: &[f64], qddot: &[f64], extra: &mut Vec<f64>| {
        extra.clear();
        extra.extend(model.measures.iter().map(|m| m.value(q, qdot, qddot, &[], t)));
        Ok(())
    };
    run_driven(model, analysis, run, names, values, |s, p, t, x, _, row| {
        s.measures(p, t, x, &[], row);
        Ok(())
    })
}

/// The kinematic solution of a fully driven mechanism, with the columns `names` after the body
/// quantities, whose values at each output time `extra(t, q, qdot, qddot, values)` writes into
/// `values`, each output point pushed as `run`. Shared by the kinematic and the inverse dynamic
/// analyses. A run asked for sensitivities also pushes the derivatives of every column: the
/// bodies' from the motion's ([`Sensitivity::push`]), then those of `names`, which
/// `extra_derivatives(sensitivity, p, t, (q, qdot, qddot), lu, row)` appends to `row` for
/// parameter `p`, right after the values of the same output time (`lu` the factorization of
/// `Phi_q`'s independent rows there).
pub(crate) fn run_driven(
    model: &Model,
    analysis: &Analysis,
    run: &mut Run<'_>,
    names: Vec<String>,
    mut extra_values: impl FnMut(f64, &[f64], &[f64], &[f64], &mut Vec<f64>) -> Result<(), Error>,
    mut extra_derivatives: impl FnMut(
        &mut Sensitivity<'_>,
        usize,
        f64,
        (&[f64], &[f64], &[f64]),
        &mut SparseLu,
        &mut Vec<f64>,
    ) -> Result<(), Error>,
) -> Result<Results, Box<Failure>> {
    let mut results = run.results(model, analysis);
    let mut extra = Vec::with_capacity(names.len());
    results.add_columns(names);
    let settings = analysis.settings;
    let n = model.n();
    let mut sys = System::new(model, &analysis.drivers);
    let t0 = analysis.t_start;
    // The drivers determine every coordinate, so nothing is held: least change from the guess.
    let given = held(model, false);
    let assembly: Assembly = match assemble_into(model, analysis, &mut sys, &given, t0, &mut results.summary) {
        Ok(a) => a,
        Err(e) => return Err(fail(results, e)),
    };
    let jac = sys.jacobian(&ConfigBuf::new(&assembly.q).view(), t0);
    let (rows, redundant) = match super::scaled_row_space(&sys, &jac, 0..n, t0) {
        Ok(space) => space.independent_rows(),
        Err(e) => return Err(fail(results, e)),
    };
    if rows.len() < n {
        if let Some(e) = super::singular_start(model, &analysis.drivers, &mut sys, &assembly.q, t0) {
            return Err(fail(results, e));
        }
    }
    if let Some(message) = unmet_freedom(model, analysis, sys.m, rows.len()) {
        let problem = Problem::new(format!("analyses.{}.drivers", analysis.name), message);
        return Err(fail(results, Error::Model(vec![problem])));
    }
    let redundant_rows: Vec<RowName> = redundant.iter().map(|&r| sys.row_name(r)).collect();
    let pattern = sys.pattern(&rows);
    let lu = match SparseLu::new(pattern) {
        Ok(lu) => lu,
        Err(_) => {
            let error = Error::OutOfMemory { time: t0, what: "in the symbolic factorization".into() };
            return Err(fail(results, error));
        }
    };
    let m = sys.m;
    let col_scale = super::column_scales(&sys, 0..n);
    let mut s = Solver {
        sys,
        rows,
        lu,
        full: vec![0.0; m],
        rhs: vec![0.0; n],
        q: assembly.q.clone(),
        qdot: vec![0.0; n],
        qddot: vec![0.0; n],
        trial: vec![0.0; n],
        rot_q: {
            let mut rot = vec![[1.0, 0.0]; n / 3];
            Config::rotations(&assembly.q, &mut rot);
            rot
        },
        rot_trial: vec![[1.0, 0.0]; n / 3],
        col_scale,
        row_scale: vec![1.0; n],
        t: t0,
        tolerance: settings.tolerance,
        max_iterations: settings.max_iterations,
        stats: KinematicStats {
            assembly_iterations: assembly.iterations,
            assembly_max_change: assembly.change.iter().fold(0.0f64, |a, x| a.max(x.abs())),
            max_residual: assembly.residual,
            ..Default::default()
        },
    };
    let mut sensitivity = match run.sensitivities.as_slice() {
        [] => None,
        asked => match Sensitivity::new(model, analysis, asked) {
            Ok(s) => Some(s),
            Err(e) => return Err(fail(results, e)),
        },
    };
    let h = analysis.step;
    let times = output_times(analysis);
    results.reserve(times.len());

    let outcome = (|| -> Result<(), Error> {
        s.factor_at(false, t0)?;
        s.velocities();
        check_condition(&mut s, model, &analysis.drivers, settings.singular_condition)?;
        s.check_output()?;
        extra_values(t0, &s.q, &s.qdot, &s.qddot, &mut extra)?;
        run.push(&mut results, t0, &s.q, &s.qdot, &s.qddot, &extra)?;
        if let Some(sensitivity) = &mut sensitivity {
            let x = (s.q.as_slice(), s.qdot.as_slice(), s.qddot.as_slice());
            sensitivity.push(&mut results, &mut s.lu, &s.rows, t0, x, |d, p, lu, row| {
                extra_derivatives(d, p, t0, x, lu, row)
            })?;
        }
        let mut dt = h;
        let mut q_pred = vec![0.0; n];
        for &target in &times[1..] {
            let span = target - s.t;
            dt = dt.min(span);
            let mut substeps = 0usize;
            while s.t < target {
                let mut step = dt.min(target - s.t);
                if target - s.t - step <= 1e-12 * h {
                    step = target - s.t;
                }
                let wmax = model.bodies.iter().map(|b| s.qdot[3 * b.index + 2].abs()).fold(0.0f64, f64::max);
                if wmax * step > settings.max_rotation {
                    step = settings.max_rotation / wmax;
                    // The same floor as for a failing Newton: below it the sub-steps would
                    // creep (a driver `1/(t-1)` took 2.9 million of them to reach 0.999999 s, and
                    // time stopped advancing before t = 1).
                    // (An infinite rate gives a zero step.)
                    if step < settings.min_substep * h {
                        let limit = "the sub-steps that keep each body's turn under solver.max_rotation fell below solver.min_substep";
                        return Err(too_fast(&mut s, model, analysis, target, step, limit));
                    }
                }
                substeps += 1;
                if substeps > MAX_SUBSTEPS_PER_OUTPUT {
                    let limit = format!("more than {MAX_SUBSTEPS_PER_OUTPUT} sub-steps, each turning a body by at most solver.max_rotation, between two output times");
                    return Err(too_fast(&mut s, model, analysis, target, step, &limit));
                }
                let t_new = if step == target - s.t { target } else { s.t + step };
                for (k, p) in q_pred.iter_mut().enumerate() {
                    *p = s.q[k] + step * s.qdot[k] + 0.5 * step * step * s.qddot[k];
                }
                s.trial.copy_from_slice(&q_pred);
                let motion = max_abs_diff(&q_pred, &s.q);
                let attempt = match s.newton(t_new)? {
                    Attempt::Converged
                        if max_abs_diff(&s.trial, &q_pred) <= 0.5 * motion + 100.0 * settings.tolerance =>
                    {
                        Attempt::Converged
                    }
                    Attempt::Converged => Attempt::BranchJump,
                    failed => failed,
                };
                match attempt {
                    Attempt::Converged => {
                        std::mem::swap(&mut s.q, &mut s.trial);
                        std::mem::swap(&mut s.rot_q, &mut s.rot_trial);
                        s.t = t_new;
                        s.factor_at(false, t_new)?;
                        s.velocities();
                        s.stats.substeps += 1;
                        dt = (2.0 * step).min(h);
                    }
                    rejected => {
                        s.stats.rejected_substeps += 1;
                        s.factor_at(false, s.t)?;
                        dt = 0.5 * step;
                        if dt < settings.min_substep * h {
                            return Err(give_up(&mut s, model, &analysis.drivers, t_new, step, rejected));
                        }
                    }
                }
            }
            check_condition(&mut s, model, &analysis.drivers, settings.singular_condition)?;
            s.check_output()?;
            extra_values(target, &s.q, &s.qdot, &s.qddot, &mut extra)?;
            run.push(&mut results, target, &s.q, &s.qdot, &s.qddot, &extra)?;
            if let Some(sensitivity) = &mut sensitivity {
                let x = (s.q.as_slice(), s.qdot.as_slice(), s.qddot.as_slice());
                let extra = |d: &mut Sensitivity<'_>, p, lu: &mut SparseLu, row: &mut Vec<f64>| {
                    extra_derivatives(d, p, target, x, lu, row)
                };
                sensitivity.push(&mut results, &mut s.lu, &s.rows, target, x, extra)?;
            }
        }
        Ok(())
    })();
    s.stats.output_points = results.len();
    insert_summary(&mut results, &s.stats, &assembly, redundant_rows);
    match outcome {
        Ok(()) => Ok(results),
        Err(e) => Err(fail(results, e)),
    }
}

/// Add the solver's statistics, the rows left out and the assembly at the start to the summary
/// of `results`.
fn insert_summary(results: &mut Results, stats: &KinematicStats, assembly: &Assembly, redundant_rows: Vec<RowName>) {
    let summary = &mut results.summary;
    summary.dof = Some(0);
    summary.statistics = Some(Statistics::Kinematic(stats.clone()));
    summary.redundant_rows = Some(redundant_rows);
    summary.assembly = Some(assembly.report());
}

fn check_condition(s: &mut Solver<'_>, model: &Model, drivers: &[usize], limit: f64) -> Result<(), Error> {
    let cond = s.lu.scaled_condition_estimate(Some((&s.row_scale, &s.col_scale)));
    s.stats.max_condition = s.stats.max_condition.max(cond);
    if cond > limit {
        let (ratio, rows) = s.diagnose();
        let detail = format!("the driven Jacobian is nearly singular (condition estimate {cond:.3e}, smallest/largest singular value {ratio:.3e}): a dead centre or lost degree of freedom");
        return Err(singular(s, model, drivers, rows, detail));
    }
    Ok(())
}

/// A singular position at the solver's last position, blamed on the group of the mechanism that
/// locks when the structure names one ([`super::blame`]): its rows, and its reason before
/// `detail`; otherwise the rows of the whole Jacobian's smallest singular value.
fn singular(s: &mut Solver<'_>, model: &Model, drivers: &[usize], rows: Vec<RowName>, detail: String) -> Error {
    match super::blame(model, drivers, &mut s.sys, &s.q, s.t) {
        Some((rows, words)) => Error::Singular { time: s.t, rows, detail: format!("{words}; {detail}") },
        None => Error::Singular { time: s.t, rows, detail },
    }
}

/// Rate of the fastest driver, to its rate at the start, up to which its motion counts as
/// bounded: 10. A driver that grows without bound (`exp(40*t)`, `tan(pi*t)`) reaches the limits
/// of the sub-steps at rates thousands of times those of its start; one that keeps its rate
/// (`2*pi*t`) reaches them only when the output step or the time's round-off asks too much.
const BOUNDED_RATE_GROWTH: f64 = 10.0;

/// Why the bodies turn too fast for a sub-step above the floor: a driver not finite now or at
/// the next output time `target`; else the time's round-off (at a time so large that double
/// precision cannot take the sub-step or the output step); else a singular
/// position (the driven Jacobian nearly loses rank, so the velocities it gives grow); else an
/// output step too long for a motion whose rate stays bounded; else the fastest driver, whose
/// motion grows without bound.
fn too_fast(s: &mut Solver<'_>, model: &Model, analysis: &Analysis, target: f64, step: f64, limit: &str) -> Error {
    let drivers = &analysis.drivers;
    if let Some(e) = model.non_finite_driver(drivers, &[s.t, target]) {
        return e;
    }
    let problem = |field: &str, message: String| {
        Error::Model(vec![Problem::new(format!("analyses.{}.{field}", analysis.name), message)])
    };
    // Doubles at `s.t` lie too far apart for the sub-step (the output step is checked when the
    // model is compiled).
    if let Some(message) = crate::model::time_round_off(s.t, step) {
        let field = if s.t.abs() <= 2.0 * analysis.t_start.abs() { "t_start" } else { "t_end" };
        return problem(field, message);
    }
    let (ratio, rows) = s.diagnose();
    if ratio >= SINGULAR_RATIO_KINEMATIC {
        let rate = |k: usize, t: f64| model.drivers[k].constraint.time_function().map_or(0.0, |f| f.eval(t).1.abs());
        let fastest = drivers.iter().copied().max_by(|&a, &b| rate(a, s.t).total_cmp(&rate(b, s.t)));
        if let Some(k) = fastest.filter(|&k| rate(k, s.t) <= BOUNDED_RATE_GROWTH * rate(k, analysis.t_start)) {
            let (d, r, h) = (&model.drivers[k], rate(k, s.t), analysis.step);
            let expression = d.constraint.time_function().map_or("", |f| f.source());
            return problem(
                "step",
                format!(
                    "the output step {h:e} s is too long for the motion: drivers.{} ({expression}) moves {r:.3e} per second, {:.3e} between two outputs, and {limit}; shorten the step",
                    d.name,
                    r * h
                ),
            );
        }
    }
    let fastest = if ratio < SINGULAR_RATIO_KINEMATIC { None } else { model.fastest_driver(drivers, s.t, limit) };
    fastest.unwrap_or_else(|| Error::Singular {
        time: s.t,
        rows,
        detail: format!(
            "the bodies turn too fast to follow ({limit}; last sub-step {step:.3e} s); smallest/largest singular value of the driven Jacobian {ratio:.3e}"
        ),
    })
}

/// An active driver whose position jumps between `t0` and `t1` (the smallest sub-step): one that
/// changes by more than ten times what the larger of its rates at the two ends explains over the
/// step, plus a thousand units of round-off of its values. A continuous function changes by at
/// most its largest rate inside the step times the step, and its rates at the ends differ from
/// that by its curvature times the step, nothing over a sub-step of `min_substep` of the output
/// step; a step function changes by its jump however short the step.
fn jumping_driver(model: &Model, drivers: &[usize], t0: f64, t1: f64) -> Option<Error> {
    drivers.iter().find_map(|&k| {
        let d = &model.drivers[k];
        let f = d.constraint.time_function()?;
        let ((before, rate0, _), (after, rate1, _)) = (f.eval(t0), f.eval(t1));
        let explained =
            10.0 * rate0.abs().max(rate1.abs()) * (t1 - t0) + 1e3 * f64::EPSILON * before.abs().max(after.abs());
        ((after - before).abs() > explained).then(|| Error::Jump {
            time: t1,
            element: format!("drivers.{}", d.name),
            expression: f.source().to_string(),
            jump: after - before,
            step: t1 - t0,
        })
    })
}

/// The smallest sub-step failed (`rejected`, how): a driver not finite at the time sought; else a
/// singular position (no assembled position beyond `s.t`); else a plain convergence failure.
fn give_up(s: &mut Solver<'_>, model: &Model, drivers: &[usize], t_new: f64, step: f64, rejected: Attempt) -> Error {
    if let Some(e) = model.non_finite_driver(drivers, &[t_new]).or_else(|| jumping_driver(model, drivers, s.t, t_new)) {
        return e;
    }
    let (ratio, rows) = s.diagnose();
    if ratio < SINGULAR_RATIO_KINEMATIC {
        let detail = format!(
            "no assembled position beyond this time (lock-up or dead centre): the driven Jacobian is nearly singular, smallest/largest singular value {ratio:.3e}, and Newton fails with sub-steps down to {step:.3e} s"
        );
        return singular(s, model, drivers, rows, detail);
    }
    match rejected {
        Attempt::Failed(f) => Error::Convergence {
            time: t_new,
            residual: f.residual,
            row: s.sys.row_name(f.row),
            iterations: f.iterations,
            substep: step,
        },
        // A branch jump, every time down to the smallest sub-step.
        Attempt::BranchJump | Attempt::Converged => Error::Convergence {
            time: t_new,
            residual: 0.0,
            row: rows.into_iter().next().unwrap_or(RowName { element: "?".into(), equation: "?".into() }),
            iterations: s.max_iterations,
            substep: step,
        },
    }
}
