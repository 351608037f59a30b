//! Inverse dynamics (kinetostatics) of a fully driven mechanism.
//!
//! The drivers fix the motion, so the kinematic analysis gives `q`, `qdot` and `qddot` at each
//! output time; the equations of motion then leave only the multipliers unknown:
//!
//! ```text
//! Phi_q^T lambda = Q(q, qdot, t) - M qddot          (n equations, m unknowns, rank n)
//! ```
//!
//! Joint reactions and driver efforts follow from `lambda` as in dynamics
//! ([`Dae::reactions`]). With redundant rows (`m > rank`) `lambda` is not unique: the
//! minimum-norm solution is taken, and the joints that share a load in a way rigid bodies
//! leave open are named in the summary (`indeterminate_joints`). The solve is by the dense SVD
//! for a small mechanism and by the sparse Gram matrix `Phi_q Phi_q^T` for a large one
//! ([`crate::linalg::rows`]), so its cost per output time grows linearly with a chain's bodies.

use super::dynamic::{factor_error, Dae, FRICTION_RTOL, NEWTON_FRICTION_ITERATIONS};
use super::kinematic::run_driven;
use super::sensitivity::{InverseAt, InverseSensitivity, Sensitivity};
use super::{element_names, row_space, Run};
use crate::error::Error;
use crate::linalg::rows::RowSpace;
use crate::linalg::{ColMatrix, Pattern, SparseLu};
use crate::model::{Analysis, Model};
use crate::results::{Failure, Results};
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::cell::RefCell;

/// The largest force or moment left unbalanced by the multipliers, relative to the largest
/// load or inertia force, before the position counts as singular: `1e-5`. A backward-stable
/// least-squares solve leaves about `eps cond` of the loads, at most `2.2e-6` within the
/// kinematics' `singular_condition` (1e10); a direction dropped as rank-deficient leaves the
/// whole load along it.
pub const BALANCE_TOLERANCE: f64 = 1e-5;

pub use crate::model::INVERSE_COLUMNS;

/// Run an inverse dynamic analysis. On failure the results up to the last good output time are
/// kept.
pub(crate) fn run_inverse(model: &Model, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
    let dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => {
            let error = factor_error(e, analysis.t_start);
            return Err(Box::new(Failure { error, results: Results::new(model, analysis) }));
        }
    };
    let derivatives = match run.sensitivities.as_slice() {
        [] => None,
        asked => {
            match Sensitivity::new(model, analysis, asked).and_then(|s| InverseSensitivity::new(&s, &dae, analysis)) {
                Ok(d) => Some(d),
                Err(error) => return Err(Box::new(Failure { error, results: Results::new(model, analysis) })),
            }
        }
    };
    let (n, m) = (dae.n, dae.m);
    let mut names = reaction_columns(model, analysis);
    names.extend(INVERSE_COLUMNS.map(String::from));
    names.extend(model.measures.iter().map(|m| m.name.clone()));
    let mut rhs = vec![0.0; n];
    let mut nu = vec![0.0; m];
    let mut reactions = Vec::new();
    let pattern = Pattern::new(m, n, dae.jacobian_entries().0.iter().map(|&e| Some(e)));
    let mut indeterminate: Option<Vec<String>> = None;
    // What the values of an output time leave for its derivatives (read by the second closure).
    let state = RefCell::new(Solved { dae, derivatives, lambda: Vec::new(), react: Vec::new(), space: None });
    let values = |t: f64, q: &[f64], qdot: &[f64], qddot: &[f64], extra: &mut Vec<f64>| {
        let solved = &mut *state.borrow_mut();
        let dae = &mut solved.dae;
        dae.positions(q, t);
        dae.load(q, qdot, t, &mut rhs);
        let mut size = 0.0f64;
        for k in 0..n {
            size = size.max(rhs[k].abs()).max((dae.mass[k] * qddot[k]).abs());
            rhs[k] -= dae.mass[k] * qddot[k];
        }
        let jac = ColMatrix::from_entries(&pattern, dae.jacobian_entries().1);
        let mut space = row_space(&jac, t)?;
        let lambda = if dae.has_friction() {
            let lambda = with_friction(dae, &mut space, (t, q, qdot), &rhs)?;
            dae.add_friction(q, qdot, &lambda, 1.0, &mut rhs, None);
            lambda
        } else {
            transpose_solve(&mut space, &rhs, t)?
        };
        // The multipliers must balance every body. Near a singular position the solve drops
        // the directions whose singular values are below RANK_TOLERANCE while the kinematics,
        // whose limit is `singular_condition`, still goes on: the load along such a direction is
        // then carried by nothing.
        let unbalanced =
            jac.transpose_times(&lambda).iter().zip(&rhs).map(|(a, b)| (a - b).abs()).fold(0.0f64, f64::max);
        if unbalanced > BALANCE_TOLERANCE * size {
            return Err(Error::Singular {
                time: t,
                rows: space.dependent_rows().into_iter().map(|r| dae.sys.row_name(r)).collect(),
                detail: format!(
                    "the joints and drivers cannot hold the loads here: the reactions leave {unbalanced:.3e} (N or N m) of loads of {size:.3e} that do not balance (a position next to a singular one, where the reactions grow without bound)"
                ),
            });
        }
        if indeterminate.is_none() {
            indeterminate = Some(element_names(&dae.sys, &space.dependent_rows()));
        }
        let react = &mut solved.react;
        dae.reactions(q, qdot, &lambda, react);
        super::measure_reactions(model, &analysis.drivers, react, &mut reactions);
        extra.clear();
        extra.extend_from_slice(react);
        let kinetic = dae.kinetic_energy(qdot);
        let potential = dae.potential_energy(q);
        let driver = dae.driver_power(q, t, &lambda, &mut nu);
        let applied = dae.applied_power(q, qdot, t);
        extra.extend([kinetic, potential, driver, applied]);
        extra.extend(model.measures.iter().map(|m| m.value(q, qdot, qddot, &reactions, t)));
        solved.lambda = lambda;
        solved.space = Some(space);
        Ok(())
    };
    let derivatives = |s: &mut Sensitivity<'_>,
                       p: usize,
                       t: f64,
                       x: (&[f64], &[f64], &[f64]),
                       lu: &mut SparseLu,
                       row: &mut Vec<f64>| {
        let solved = &mut *state.borrow_mut();
        let Solved { dae, derivatives: Some(d), lambda, react, space: Some(space) } = solved else {
            unreachable!("a run with sensitivities has their buffers, and its values come first")
        };
        let at = InverseAt { t, x, lambda, react };
        d.push(s, dae, (space, lu), &at, p, row)
    };
    let outcome = run_driven(model, analysis, run, names, values, derivatives);
    let finish = |results: &mut Results| {
        results.summary.indeterminate_joints = Some(indeterminate.clone().unwrap_or_default());
        results.insert_reaction_summary(model);
    };
    match outcome {
        Ok(mut results) => {
            finish(&mut results);
            Ok(results)
        }
        Err(mut failure) => {
            finish(&mut failure.results);
            Err(failure)
        }
    }
}

/// What the values of an output time of an inverse analysis leave for its derivatives: the
/// equations at its positions, the multipliers, the reactions and the row space of `Phi_q`.
struct Solved<'m> {
    dae: Dae<'m>,
    /// The sensitivities' buffers, when the run asked for them.
    derivatives: Option<InverseSensitivity>,
    lambda: Vec<f64>,
    react: Vec<f64>,
    space: Option<RowSpace>,
}

/// `lambda` solving `Phi_q^T lambda = rhs` (minimum norm) in the row space `space` at `t`.
fn transpose_solve(space: &mut RowSpace, rhs: &[f64], t: f64) -> Result<Vec<f64>, Error> {
    space.min_norm_transpose_solve(rhs).ok_or_else(|| svd_failure(t))
}

/// The failure of the dense SVD of the constraint Jacobian at `t`.
fn svd_failure(t: f64) -> Error {
    Error::Singular {
        time: t,
        rows: vec![],
        detail: "the singular value decomposition of the constraint Jacobian failed (a non-finite entry)".into(),
    }
}

/// The multipliers with joint friction: `Phi_q^T lambda = rhs + Q_f(q, qdot, lambda)`.
///
/// `Q_f` depends on `lambda` only through the friction joints' rows `z` (their reactions'
/// magnitudes) and the solve `S` (minimum norm, in the row space `space`) is linear, so
/// `lambda = lambda_0 + (S E) Q_f(z)`: `lambda_0 = S rhs` the frictionless multipliers, `S E` the
/// response to a unit load on each friction column, all from one solve of those columns together.
/// Newton then solves the small system `g(z) = lambda_0[rows] + (S E)[rows] Q_f(z) - z = 0` with
/// `dQ_f/dz` exact ([`Dae::friction_by_multipliers`]), and no more solves. A fixed point
/// `z <- lambda_0[rows] + (S E)[rows] Q_f(z)` contracts by the friction's gain (`~ mu r / arm`
/// for a pin, `mu tan(beta)` for a slider pushed at an angle `beta`) and stalls as the gain nears
/// 1 on the way to a self-locking position; Newton converges there as well, and fails only where
/// there is no solution. Converged when the correction is below [`FRICTION_RTOL`] of the largest
/// multiplier; [`Error::Friction`] naming the joint whose friction changed most when it is not
/// after `NEWTON_FRICTION_ITERATIONS`.
fn with_friction(
    dae: &Dae<'_>,
    space: &mut RowSpace,
    (t, q, qdot): (f64, &[f64], &[f64]),
    rhs: &[f64],
) -> Result<Vec<f64>, Error> {
    let n = rhs.len();
    let (rows, columns) = dae.friction_support();
    let (nr, nc) = (rows.len(), columns.len());
    // Column 0 the loads, column 1 + j a unit load on friction column j.
    let loads = Mat::<f64>::from_fn(n, 1 + nc, |i, j| match j {
        0 => rhs[i],
        _ => f64::from(u8::from(columns[j - 1] == i)),
    });
    let solved = space.min_norm_transpose_solve_columns(loads.as_ref()).ok_or_else(|| svd_failure(t))?;
    let mut lambda: Vec<f64> = solved.col(0).iter().copied().collect();
    let base: Vec<f64> = rows.iter().map(|&r| lambda[r]).collect();
    let scale = lambda.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let (mut load, mut by) = (vec![0.0; n], vec![0.0; n * nr]);
    let mut delta = vec![0.0; lambda.len()];
    let mut worst = (0, f64::INFINITY);
    for _ in 0..NEWTON_FRICTION_ITERATIONS {
        load.fill(0.0);
        dae.add_friction(q, qdot, &lambda, 1.0, &mut load, None);
        dae.friction_by_multipliers(q, qdot, &lambda, &rows, &mut by);
        let g = Mat::<f64>::from_fn(nr, 1, |i, _| {
            let r = rows[i];
            base[i] + (0..nc).map(|j| solved[(r, 1 + j)] * load[columns[j]]).sum::<f64>() - lambda[r]
        });
        let jacobian = Mat::<f64>::from_fn(nr, nr, |i, k| {
            let slope: f64 = (0..nc).map(|j| solved[(rows[i], 1 + j)] * by[k * n + columns[j]]).sum();
            f64::from(u8::from(i == k)) - slope
        });
        let step = jacobian.partial_piv_lu().solve(&g);
        delta.fill(0.0);
        for (i, &r) in rows.iter().enumerate() {
            delta[r] = step[(i, 0)];
        }
        if !delta.iter().all(|d: &f64| d.is_finite()) {
            break;
        }
        for &r in &rows {
            lambda[r] += delta[r];
        }
        let largest = scale.max(rows.iter().fold(0.0f64, |a, &r| a.max(lambda[r].abs())));
        let change = delta.iter().fold(0.0f64, |a, d| a.max(d.abs()));
        if change <= FRICTION_RTOL * largest {
            // Every multiplier from the converged friction: lambda_0 + (S E) Q_f(z).
            load.fill(0.0);
            dae.add_friction(q, qdot, &lambda, 1.0, &mut load, None);
            for (r, l) in lambda.iter_mut().enumerate() {
                *l = solved[(r, 0)] + (0..nc).map(|j| solved[(r, 1 + j)] * load[columns[j]]).sum::<f64>();
            }
            return Ok(lambda);
        }
        worst = dae.friction_change(q, qdot, &delta, &lambda);
    }
    Err(dae.friction_error(worst, t, NEWTON_FRICTION_ITERATIONS, "the reactions"))
}

/// `<joint>.fx, .fy, .torque` for every joint, then `<driver>.effort` for every active driver,
/// then `<joint>.friction` for every joint with friction.
pub(crate) fn reaction_columns(model: &Model, analysis: &Analysis) -> Vec<String> {
    let mut names = Vec::new();
    for j in &model.joints {
        names.extend(crate::results::REACTION_QUANTITIES.map(|q| format!("{}.{q}", j.name)));
    }
    names.extend(analysis.drivers.iter().map(|&d| format!("{}.effort", model.drivers[d].name)));
    let friction = model.joints.iter().filter(|j| j.friction.is_some());
    names.extend(friction.map(|j| format!("{}.{}", j.name, crate::results::FRICTION_QUANTITY)));
    names
}
