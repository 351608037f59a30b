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

use super::dynamic::{factor_error, Dae, FRICTION_RTOL};
use super::kinematic::run_driven;
use super::{element_names, row_space};
use crate::error::Error;
use crate::linalg::rows::RowSpace;
use crate::linalg::{ColMatrix, Pattern};
use crate::model::{Analysis, Model};
use crate::results::{Failure, Results};

/// The largest force or moment left unbalanced by the multipliers, relative to the largest
/// load or inertia force, before the position counts as singular: `1e-5`. A backward-stable
/// least-squares solve leaves about `eps cond` of the loads, at most `2.2e-6` within the
/// kinematics' `singular_condition` (1e10); a direction dropped as rank-deficient leaves the
/// whole load along it.
pub const BALANCE_TOLERANCE: f64 = 1e-5;

/// The most fixed-point iterations on the multipliers at one output time when joints have
/// friction: 100. Each iteration shrinks the error by the contraction `rho`, the friction's
/// change per change of the multipliers it depends on (`~ mu r / arm` for a pin of radius `r` whose
/// load turns about a lever `arm`: `1e-3` to `1e-1` in machines); 100 iterations reach
/// [`FRICTION_RTOL`] for any `rho` up to 0.79, and the iteration stops at once where it diverges.
const FIXED_POINT_FRICTION_ITERATIONS: usize = 100;

/// Columns after the reactions and efforts.
pub const INVERSE_COLUMNS: [&str; 4] = ["kinetic_energy", "potential_energy", "driver_power", "applied_power"];

/// Run an inverse dynamic analysis. On failure the results up to the last good output time are
/// kept.
pub fn run_inverse(model: &Model, analysis: &Analysis) -> Result<Results, Box<Failure>> {
    let mut dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => {
            let error = factor_error(e, analysis.t_start);
            return Err(Box::new(Failure { error, results: Results::new(model, analysis) }));
        }
    };
    let (n, m) = (dae.n, dae.m);
    let mut names = reaction_columns(model, analysis);
    names.extend(INVERSE_COLUMNS.map(String::from));
    names.extend(model.measures.iter().map(|m| m.name.clone()));
    let mut rhs = vec![0.0; n];
    let mut nu = vec![0.0; m];
    let mut react = Vec::new();
    let mut reactions = Vec::new();
    let pattern = Pattern::new(m, n, dae.jacobian_entries().0.iter().map(|&e| Some(e)));
    let mut indeterminate: Option<Vec<String>> = None;
    let outcome = run_driven(model, analysis, names, |t, q, qdot, qddot, extra| {
        dae.positions(q, t);
        dae.load(q, qdot, t, &mut rhs);
        let mut size = 0.0f64;
        for k in 0..n {
            size = size.max(rhs[k].abs()).max((dae.mass[k] * qddot[k]).abs());
            rhs[k] -= dae.mass[k] * qddot[k];
        }
        let jac = ColMatrix::from_entries(&pattern, dae.jacobian_entries().1);
        let mut space = row_space(&jac, t)?;
        let mut lambda = transpose_solve(&mut space, &rhs, t)?;
        if dae.has_friction() {
            lambda = with_friction(&dae, &mut space, (t, q, qdot), &rhs, lambda)?;
            dae.add_friction(q, qdot, &lambda, 1.0, &mut rhs, None);
        }
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
        dae.reactions(q, qdot, &lambda, &mut react);
        super::measure_reactions(model, &analysis.drivers, &react, &mut reactions);
        extra.clear();
        extra.extend_from_slice(&react);
        let kinetic = dae.kinetic_energy(qdot);
        let potential = dae.potential_energy(q);
        let driver = dae.driver_power(q, t, &lambda, &mut nu);
        let applied = dae.applied_power(q, qdot, t);
        extra.extend([kinetic, potential, driver, applied]);
        extra.extend(model.measures.iter().map(|m| m.value(q, qdot, qddot, &reactions, t)));
        Ok(())
    });
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

/// `lambda` solving `Phi_q^T lambda = rhs` (minimum norm) in the row space `space` at `t`.
fn transpose_solve(space: &mut RowSpace, rhs: &[f64], t: f64) -> Result<Vec<f64>, Error> {
    space.min_norm_transpose_solve(rhs).ok_or_else(|| Error::Singular {
        time: t,
        rows: vec![],
        detail: "the singular value decomposition of the constraint Jacobian failed (a non-finite entry)".into(),
    })
}

/// The multipliers with joint friction: `Phi_q^T lambda = rhs + Q_f(q, qdot, lambda)`, by the
/// fixed point `lambda_{k+1} = solve(rhs + Q_f(lambda_k))` from the frictionless `lambda`, each
/// solve with the factorization of `space` already made. Converged when the estimated distance
/// to the fixed point, `rho / (1 - rho)` times the last change (`rho` the last contraction; the
/// change itself at the first iteration), is below [`FRICTION_RTOL`] of the largest multiplier;
/// [`Error::Friction`] when it is not after `FIXED_POINT_FRICTION_ITERATIONS` or when it diverges (a
/// contraction of 1 or more twice running: the friction, through the reactions, asks for more
/// than it gives, as at a self-locking position).
fn with_friction(
    dae: &Dae<'_>,
    space: &mut RowSpace,
    (t, q, qdot): (f64, &[f64], &[f64]),
    rhs: &[f64],
    mut lambda: Vec<f64>,
) -> Result<Vec<f64>, Error> {
    let mut loaded = rhs.to_vec();
    let mut previous = f64::INFINITY;
    let mut growing = 0;
    let mut worst = (0, f64::INFINITY);
    for it in 1..=FIXED_POINT_FRICTION_ITERATIONS {
        loaded.copy_from_slice(rhs);
        dae.add_friction(q, qdot, &lambda, 1.0, &mut loaded, None);
        let next = transpose_solve(space, &loaded, t)?;
        let delta: Vec<f64> = next.iter().zip(&lambda).map(|(a, b)| a - b).collect();
        lambda = next;
        worst = dae.friction_change(q, qdot, &delta, &lambda);
        let rate = worst.1 / previous;
        let distance = if it == 1 || worst.1 == 0.0 { worst.1 } else { rate / (1.0 - rate) * worst.1 };
        if (rate < 1.0 || it == 1) && distance <= FRICTION_RTOL {
            return Ok(lambda);
        }
        growing = if it > 1 && rate >= 1.0 { growing + 1 } else { 0 };
        if growing >= 2 {
            return Err(dae.friction_error(worst, t, it, "the reactions"));
        }
        previous = worst.1;
    }
    Err(dae.friction_error(worst, t, FIXED_POINT_FRICTION_ITERATIONS, "the reactions"))
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
