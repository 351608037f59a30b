//! Assembly: move an approximate initial guess onto `Phi(q, t) = 0` with the least change, holding
//! the coordinates the user marks as given; then make the velocities consistent,
//! `Phi_q qdot = nu`, again with the least change and the given velocities held.
//!
//! Each Newton step is the minimum-norm solution of `Phi_q,F dq_F = -Phi` over the free
//! coordinates `F` (Gauss-Newton on an underdetermined system, Haug 1989 section 4.6), computed
//! so that redundant rows and remaining freedom are both handled (by the SVD for a small
//! mechanism, over the independent rows by the Gram matrix for a large one:
//! [`crate::linalg::rows`]); a backtracking line search on `|Phi|_2` keeps a rough guess from
//! diverging.

use super::{column_scales, scaled_residual, scaled_residual_floor, scaled_row_space};
use crate::constraints::ConfigBuf;
use crate::error::{Error, Result};
use crate::linalg::rows::row_scales;
use crate::results::AssemblyReport;
use crate::system::System;

/// Newton iterations allowed from a rough guess.
const MAX_ITERATIONS: usize = 60;
/// Relative residual of the velocity equations (to `1 + max |qdot|`) above which they cannot
/// hold: a least-squares solve of consistent equations leaves round-off, `~1e-15` times the
/// condition of `Phi_q`; `1e-8` leaves room for conditions up to `1e7`.
const VELOCITY_TOLERANCE: f64 = 1e-8;
/// Step halvings tried by the line search before a full step is taken anyway.
const MAX_HALVINGS: usize = 12;

/// An assembled configuration and how far it moved from the guess.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Assembly {
    /// (n) assembled positions.
    pub q: Vec<f64>,
    /// (n) consistent velocities.
    pub qdot: Vec<f64>,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Max-norm of `Phi` at `q`.
    pub residual: f64,
    /// Max-norm of `Phi_q qdot - nu` at `q`.
    pub velocity_residual: f64,
    /// (n) `q - q_guess`.
    pub change: Vec<f64>,
}

impl Assembly {
    /// What the summary says of it.
    pub fn report(&self) -> AssemblyReport {
        AssemblyReport {
            iterations: self.iterations,
            residual: self.residual,
            velocity_residual: self.velocity_residual,
        }
    }
}

/// Where an assembly starts and what it must reach: the guess, the coordinates it holds, the
/// time and the tolerance.
#[derive(Debug, Clone, Copy)]
pub struct Start<'a> {
    /// (n) guessed positions.
    pub q: &'a [f64],
    /// (n) guessed velocities.
    pub qdot: &'a [f64],
    /// (2n) the positions (first `n`) and velocities (last `n`) to hold.
    pub given: &'a [bool],
    /// Time, s.
    pub t: f64,
    /// Bound on the residual of `Phi` relative to the model's size (`scaled_residual`).
    pub tolerance: f64,
}

/// Assemble `sys` from `start`.
pub fn assemble(sys: &mut System<'_>, start: &Start<'_>) -> Result<Assembly> {
    assemble_or_best(sys, start).map_err(|stopped| stopped.0)
}

/// [`assemble`], with the positions Newton reached (its best) beside the error when it fails, and
/// whether they hold (the positions assembled, the velocities did not).
pub(crate) fn assemble_or_best(
    sys: &mut System<'_>,
    start: &Start<'_>,
) -> std::result::Result<Assembly, Box<(Error, Vec<f64>, bool)>> {
    let mut best = start.q.to_vec();
    let mut assembled = false;
    assemble_tracking(sys, start, &mut best, &mut assembled).map_err(|e| Box::new((e, best, assembled)))
}

/// [`assemble`], keeping in `best` the last positions Newton accepted, and `assembled` true once
/// they hold.
fn assemble_tracking(
    sys: &mut System<'_>,
    &Start { q: q0, qdot: qdot0, given, t, tolerance }: &Start<'_>,
    best: &mut Vec<f64>,
    assembled: &mut bool,
) -> Result<Assembly> {
    let (n, m) = (sys.n, sys.m);
    let free: Vec<usize> = (0..n).filter(|&k| !given[k]).collect();
    let mut q = q0.to_vec();
    let mut phi = vec![0.0; m];
    sys.phi(&ConfigBuf::new(&q).view(), t, &mut phi);
    // A driver that is NaN or infinite at `t` (`sqrt(t - 1)` at 0) is the cause, not the guess;
    // and a NaN must not pass the tolerance test below (`max` skips NaN).
    if let Some(e) = sys.non_finite(&phi, t) {
        return Err(e);
    }
    let mut iterations = 0;
    let norm2 = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let maxabs = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let fail = |sys: &System<'_>, phi: &[f64], iterations: usize, hint: &str| {
        let (row, residual) = sys.worst_row(phi);
        Error::Assembly { time: t, iterations, residual, row, hint: hint.to_string() }
    };
    let scales = column_scales(sys, 0..n);
    let mut weights = vec![0.0; m];
    loop {
        // The residual free of units (`super::scaled_residual`): `tolerance` relative to the
        // model's length scale on rows of lengths, in radians on rows of angles.
        let jac = sys.jacobian(&ConfigBuf::new(&q).view(), t);
        row_scales(&jac.col_ptr, &jac.row_idx, &jac.values, &scales, &mut weights);
        if scaled_residual(&phi, &weights, sys.length).1 <= tolerance.max(scaled_residual_floor(&q, sys.length)) {
            break;
        }
        if iterations == MAX_ITERATIONS || !phi.iter().all(|x| x.is_finite()) {
            return Err(fail(sys, &phi, iterations, "the initial guess may be too far from an assembled configuration, or the joints, drivers and given coordinates cannot all hold at once (check lengths, points and given values)"));
        }
        iterations += 1;
        let jf = jac.columns(&free);
        let rhs: Vec<f64> = phi.iter().map(|x| -x).collect();
        let Some(dq) = scaled_row_space(sys, &jf, free.iter().copied(), t)?.min_norm_solve(&rhs) else {
            return Err(fail(sys, &phi, iterations, "the Jacobian is not finite at the guess"));
        };
        let before = norm2(&phi);
        let mut alpha = 1.0;
        let mut trial = q.clone();
        for _ in 0..=MAX_HALVINGS {
            trial.copy_from_slice(&q);
            for (k, &c) in free.iter().enumerate() {
                trial[c] += alpha * dq[k];
            }
            sys.phi(&ConfigBuf::new(&trial).view(), t, &mut phi);
            if norm2(&phi) < before {
                break;
            }
            alpha *= 0.5;
        }
        if norm2(&phi) >= before {
            return Err(fail(sys, &phi, iterations, "Newton cannot reduce the residual further: the constraints, drivers and given coordinates conflict, or the guess is near a singular position"));
        }
        q = trial;
        best.clone_from(&q);
    }
    let residual = maxabs(&phi);
    best.clone_from(&q);
    *assembled = true;
    // Velocities: least change from the guess, given ones held.
    let config = ConfigBuf::new(&q);
    let jac = sys.jacobian(&config.view(), t);
    let mut nu = vec![0.0; m];
    sys.nu(&config.view(), t, &mut nu);
    if let Some(e) = sys.non_finite(&nu, t) {
        return Err(e);
    }
    let mut qdot = qdot0.to_vec();
    let free_v: Vec<usize> = (0..n).filter(|&k| !given[n + k]).collect();
    let r: Vec<f64> = jac.times(&qdot).iter().zip(&nu).map(|(jv, nu)| nu - jv).collect();
    let dv = scaled_row_space(sys, &jac.columns(&free_v), free_v.iter().copied(), t)?
        .min_norm_solve(&r)
        .ok_or_else(|| fail(sys, &phi, iterations, "the Jacobian is not finite"))?;
    for (k, &c) in free_v.iter().enumerate() {
        qdot[c] += dv[k];
    }
    // Velocities so large that `Phi_q qdot` overflows (a guess near 1.8e308 m/s) leave an
    // infinity or a NaN, which the tolerance test would pass (`max` skips NaN): such a row's
    // residual is infinite, and the run fails on it.
    let in_range = qdot.iter().all(|v| v.is_finite());
    let vres: Vec<f64> = jac
        .times(&qdot)
        .iter()
        .zip(&nu)
        .map(|(jv, nu)| if (jv - nu).is_finite() && in_range { jv - nu } else { f64::INFINITY })
        .collect();
    let velocity_residual = maxabs(&vres);
    let scale = if in_range { 1.0 + maxabs(&qdot) } else { 1.0 };
    if velocity_residual > VELOCITY_TOLERANCE * scale {
        let (row, res) = sys.worst_row(&vres);
        let rows: Vec<String> = (0..m)
            .filter(|&i| vres[i].abs() > VELOCITY_TOLERANCE * scale)
            .map(|i| sys.row_name(i).to_string())
            .collect();
        let cause = if velocity_residual.is_infinite() {
            "the velocities are out of range (a double holds up to 1.8e308): the guessed or given ones overflow"
        } else if free_v.len() < n {
            "the given velocities conflict with the joints and drivers"
        } else {
            "the joints and drivers ask for velocities that cannot all hold (two drivers of one motion, or a driver of a motion the joints lock)"
        };
        return Err(Error::Assembly {
            time: t,
            iterations,
            residual: res,
            row,
            hint: format!("{cause}: the velocity equations Phi_q qdot = nu of {} disagree", rows.join(", ")),
        });
    }
    let change = q.iter().zip(q0).map(|(a, b)| a - b).collect();
    Ok(Assembly { q, qdot, iterations, residual, velocity_residual, change })
}
