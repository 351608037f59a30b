//! Analyses: the run entry point ([`crate::Model::run`], with the run's [`Overrides`]) and its
//! dispatch; assembly of an initial guess, checks (degrees of freedom, redundant rows), and the
//! kinematic, inverse, static, modes and dynamic analyses. Each reads a compiled
//! [`crate::model::Model`] and writes [`crate::results::Results`].

mod assembly;
mod check;
pub mod dynamic;
mod inverse;
mod kinematic;
mod modes;
mod run;
mod statics;

pub use assembly::{assemble, Assembly};
pub use check::{check, independent_rows, AnalysisCheck, CheckReport, SystemCheck};
pub(crate) use inverse::reaction_columns;
pub use inverse::run_inverse;
pub use kinematic::run_kinematic;
pub use modes::run_modes;
pub use run::Overrides;
pub use statics::run_static;

use faer::{Mat, MatRef};

/// Units of round-off in a constraint residual: each row of `Phi` adds a few products of
/// coordinates, rotations and point offsets, each rounded to half a unit of the largest; 64
/// covers the longest rows (gears, expressions) with a margin.
pub const RESIDUAL_ROUNDOFF_UNITS: f64 = 64.0;

/// The smallest max-norm of `Phi` that round-off lets Newton reach at positions `q`, m or rad:
/// `RESIDUAL_ROUNDOFF_UNITS eps max(1, max |q_k|)` (`1.4e-14` on a mechanism of a metre or two
/// whose angles are below a radian; `1.4e-11` after 1000 rad). Every position solver stops at
/// `max(tolerance, residual_floor(q))`, so no tolerance asks for the impossible.
pub fn residual_floor(q: &[f64]) -> f64 {
    RESIDUAL_ROUNDOFF_UNITS * f64::EPSILON * q.iter().fold(1.0f64, |a, x| a.max(x.abs()))
}

/// The tightest relative tolerance of an integrator: 100 units of round-off, as DASSL. Below it
/// the error estimate is round-off; a smaller `rtol` is raised to it, with a warning.
pub const RTOL_FLOOR: f64 = 100.0 * f64::EPSILON;

/// The summary's warnings about `analysis`: each tolerance below what the arithmetic can reach,
/// and the value used instead. `q`: the positions at the start (assembled, or the guess).
pub fn tolerance_warnings(analysis: &crate::model::Analysis, q: &[f64]) -> Vec<String> {
    let mut warnings = Vec::new();
    let floor = residual_floor(q);
    if analysis.settings.tolerance < floor {
        warnings.push(format!(
            "solver.tolerance {:e} is below what round-off allows at this mechanism's size; the position solvers stop at {floor:.2e}",
            analysis.settings.tolerance
        ));
    }
    if analysis.kind == crate::model::spec::AnalysisKind::Dynamic && analysis.integrator.rtol < RTOL_FLOOR {
        warnings.push(format!(
            "solver.rtol {:e} is below what round-off allows (100 units, {RTOL_FLOOR:.2e}); the integrator uses {RTOL_FLOOR:.2e}",
            analysis.integrator.rtol
        ));
    }
    warnings
}

/// Relative size of a singular value (to the largest) below which it counts as zero when
/// finding the rank of `Phi_q`: `1e-9` sits far above rounding (`~1e-16 * cond`) and far below
/// any physical ratio of a well-posed mechanism.
pub const RANK_TOLERANCE: f64 = 1e-9;

/// Minimum-norm least-squares solution `x (cols)` of `a x = b` by the SVD, dropping singular values
/// below `RANK_TOLERANCE` times the largest. `None` when the SVD fails (non-finite input).
pub(crate) fn min_norm_solve(a: MatRef<'_, f64>, b: &[f64]) -> Option<Vec<f64>> {
    let (m, n) = (a.nrows(), a.ncols());
    if n == 0 || m == 0 {
        return Some(vec![0.0; n]);
    }
    let svd = a.thin_svd().ok()?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    let smax = (0..s.nrows()).map(|k| s[k]).fold(0.0f64, f64::max);
    let mut x = vec![0.0; n];
    for k in 0..s.nrows() {
        if s[k] <= RANK_TOLERANCE * smax || s[k] == 0.0 {
            continue;
        }
        let c: f64 = (0..m).map(|i| u[(i, k)] * b[i]).sum::<f64>() / s[k];
        for (j, xj) in x.iter_mut().enumerate() {
            *xj += v[(j, k)] * c;
        }
    }
    Some(x)
}

/// The columns `cols` of `a`, as a new matrix.
pub(crate) fn select_columns(a: MatRef<'_, f64>, cols: &[usize]) -> Mat<f64> {
    Mat::from_fn(a.nrows(), cols.len(), |i, j| a[(i, cols[j])])
}

/// Rows of `jac (m x n)` whose multipliers `Phi_q^T lambda = g` does not determine: those with a
/// component in the left null space of `jac` (the combinations of rows that vanish, one per
/// redundant row). Their joints share a load in a way rigid bodies leave open; the minimum-norm
/// multipliers are one choice. Empty when the rows are independent.
pub(crate) fn indeterminate_rows(jac: MatRef<'_, f64>) -> Vec<usize> {
    let (m, n) = (jac.nrows(), jac.ncols());
    if m == 0 || n == 0 {
        return (0..m).collect();
    }
    let Ok(svd) = jac.svd() else { return vec![] };
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|k| s[k]).fold(0.0f64, f64::max);
    let rank = (0..s.nrows()).filter(|&k| s[k] > RANK_TOLERANCE * smax).count();
    let u = svd.U();
    // The left singular vectors are unit vectors: a component above 1e-8 is far above rounding.
    (0..m).filter(|&i| (rank..m).any(|k| u[(i, k)].abs() > 1e-8)).collect()
}

/// The names of the elements (joints, drivers) of `rows`, each once, in row order.
pub(crate) fn element_names(sys: &crate::system::System<'_>, rows: &[usize]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for &r in rows {
        let e = sys.row_name(r).element;
        if !names.contains(&e) {
            names.push(e);
        }
    }
    names
}

/// The smallest eigenvalue of the mass reduced to the free motions, as a fraction of the largest,
/// below which a motion has no mass: `1e-12`. Mass ratios within one mechanism are far above it,
/// and the round-off of the null-space basis leaves a massless motion at `~eps` of the largest.
const MASSLESS: f64 = 1e-12;

/// A motion the joints allow at `q` (`jac`, the dense `Phi_q` there) that no mass or inertia
/// resists: the mass matrix reduced to the null space of `Phi_q`, `N^T M N`, is singular, and so
/// are the equations of motion (their accelerations are not determined). A massless body is
/// fine where the joints carry it along (a massless connecting rod between massive ones); a
/// massless wheel turning freely on its axle is not. `Some` problem at the mass or inertia field
/// of the first body in that motion, naming its coordinates.
pub(crate) fn massless_motion(model: &crate::model::Model, jac: MatRef<'_, f64>) -> Option<crate::Problem> {
    let basis = statics::null_space(jac);
    let f = basis.ncols();
    if f == 0 {
        return None;
    }
    let mass: Vec<f64> = model.bodies.iter().flat_map(|b| [b.mass, b.mass, b.inertia]).collect();
    let reduced =
        Mat::<f64>::from_fn(f, f, |i, j| (0..mass.len()).map(|k| basis[(k, i)] * mass[k] * basis[(k, j)]).sum());
    let eig = reduced.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let s = eig.S().column_vector();
    let largest = (0..f).fold(0.0f64, |a, k| a.max(s[k].abs()));
    // Eigenvalues ascend: the first is the least massive motion.
    if s[0] > MASSLESS * largest {
        return None;
    }
    let motion: Vec<f64> = (0..mass.len()).map(|k| (0..f).map(|j| basis[(k, j)] * eig.U()[(j, 0)]).sum()).collect();
    let coordinates = statics::coordinates_of(model, &motion);
    let first = coordinates.first()?;
    let (body, coordinate) = first.rsplit_once('.')?;
    let field = if coordinate == "phi" { "inertia" } else { "mass" };
    Some(crate::Problem::new(
        format!("bodies.{body}.{field}"),
        format!(
            "{} can move with no mass or inertia to resist: the equations of motion are singular; give it {field} \
             above zero, or a joint that carries it",
            coordinates.join(", ")
        ),
    ))
}
