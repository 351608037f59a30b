//! Analyses: the run entry point ([`crate::Model::run`], with the run's [`RunOptions`]) and its
//! dispatch; assembly of an initial guess, checks (degrees of freedom, redundant rows), and the
//! kinematic, inverse, static, modes and dynamic analyses. Each reads a compiled
//! [`crate::model::Model`] and writes [`crate::results::Results`].

mod assembly;
mod branches;
mod check;
pub mod dynamic;
mod inverse;
mod kinematic;
mod modes;
pub mod promise;
mod run;
mod sensitivity;
mod setup;
mod statics;

pub use crate::system::length_scale;
pub use assembly::{assemble, Assembly, Start};
pub(crate) use branches::{assemble_into, singular_start};
pub use branches::{assemble_on_branches, blame};
pub use check::{assembled_branches, check, AnalysisCheck, CheckReport, SystemCheck};
pub(crate) use inverse::reaction_columns;
pub(crate) use inverse::run_inverse;
pub use inverse::INVERSE_COLUMNS;
pub(crate) use kinematic::run_kinematic;
pub(crate) use modes::run_modes;
pub(crate) use run::Run;
pub use run::{Overrides, RunOptions, Sink};
pub(crate) use setup::measure_reactions;
pub(crate) use statics::run_static;

use crate::linalg::dense::null_space;
use crate::linalg::rows::{RowSpace, Scaled};
use crate::linalg::ColMatrix;
use faer::Mat;

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

/// The residual of `Phi` free of units, and its row: `max_i |Phi_i| R_i / L`, `R` the row scales
/// of `Phi_q` ([`crate::linalg::rows::row_scales`] with [`column_scales`]) and `L` the length
/// scale. A row of lengths, whose scaled row has a norm of order 1, gives its residual over `L`;
/// a row of angles, whose scaled row has a norm of order `1 / L`, its residual in radians: both
/// relative, so that the position solvers, which stop when it is below `solver.tolerance`, stop
/// at the same point of their iterations whatever the unit of length.
pub(crate) fn scaled_residual(phi: &[f64], row_scales: &[f64], length: f64) -> (usize, f64) {
    phi.iter().zip(row_scales).map(|(p, r)| (p * r / length).abs()).enumerate().fold((0, 0.0f64), |(bk, bx), (k, x)| {
        if x > bx || x.is_nan() {
            (k, x)
        } else {
            (bk, bx)
        }
    })
}

/// Each row's weight `R_i / L` in `scaled_residual` for `model` with the active `drivers` at
/// `(q, t)`: the residual assembly and the kinematics bound by `solver.tolerance` is
/// `max_i |Phi_i| w_i`, and the length scale `L` ([`length_scale`]) is returned beside them.
pub fn residual_weights(model: &crate::model::Model, drivers: &[usize], q: &[f64], t: f64) -> (Vec<f64>, f64) {
    let mut sys = crate::system::System::new(model, drivers);
    let jac = sys.jacobian(&crate::constraints::ConfigBuf::new(q).view(), t);
    let mut weights = vec![0.0; sys.m];
    crate::linalg::rows::row_scales(
        &jac.col_ptr,
        &jac.row_idx,
        &jac.values,
        &column_scales(&sys, 0..sys.n),
        &mut weights,
    );
    weights.iter_mut().for_each(|w| *w /= sys.length);
    (weights, sys.length)
}

/// The smallest [`scaled_residual`] round-off lets Newton reach at `q`:
/// `RESIDUAL_ROUNDOFF_UNITS eps max(1, max |x, y| / L, max |phi|)`, [`residual_floor`] in the
/// scaled coordinates (lengths over `L`, angles in radians).
pub(crate) fn scaled_residual_floor(q: &[f64], length: f64) -> f64 {
    let size =
        q.iter().enumerate().fold(1.0f64, |a, (k, x)| a.max(if k % 3 == 2 { x.abs() } else { x.abs() / length }));
    RESIDUAL_ROUNDOFF_UNITS * f64::EPSILON * size
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

/// Smallest/largest singular value of the driven Jacobian at which the kinematic solver gives
/// up, below which the failure is blamed on a singular position (a lock-up or dead centre) rather
/// than on a driver or on Newton: `1e-3`. The solver gives up at a singular position after
/// halving its sub-step down to `min_substep` of the output step, which leaves it close to but
/// not at the position: measured, the slider-crank's lock-up stops at `1.3e-6`, and the dead
/// centres the property tests drive random loops into at `3.5e-7` to `4.2e-6`; a failure at a
/// regular position (a driver too fast to follow) at `3e-2` and above. `1e-3` sits more than
/// two hundred times above the first and thirty times below the second.
///
/// [`SINGULAR_RATIO_DYNAMIC`] answers the same question for the integrators, whose failures sit
/// elsewhere on the scale, so the two are two numbers: `1e-6` here would miss most singular
/// stops of the kinematic solver, and `1e-3` there would sit close above regular failures.
pub(crate) const SINGULAR_RATIO_KINEMATIC: f64 = 1e-3;

/// Smallest/largest singular value of `Phi_q` at which an integrator gives up, below which the
/// failure is blamed on a singular position (a dead centre or lock-up) rather than on the forces
/// or the tolerances: `1e-6`. An integrator gives up only when its step has fallen to 16 units
/// of round-off of the time ([`dynamic::min_step`]) or its step budget is spent, by then at a
/// singular position itself (measured: `3e-17` at the slider-crank's lock-up); while its failures
/// at regular positions (a step budget spent, an error estimate that drove the step to round-off)
/// came at ratios from `2.1e-3` up, only two to three times above the kinematic `1e-3`
/// ([`SINGULAR_RATIO_KINEMATIC`]). `1e-6` keeps three orders of magnitude from each.
pub(crate) const SINGULAR_RATIO_DYNAMIC: f64 = 1e-6;

/// Rows of `jac (m x n)` whose multipliers `Phi_q^T lambda = g` does not determine: those in a
/// linear dependence among the rows (one per redundant row). Their joints share a load in a way
/// rigid bodies leave open; the minimum-norm multipliers are one choice. Empty when the rows are
/// independent.
pub(crate) use crate::linalg::dense::dependent_rows as indeterminate_rows;
pub(crate) use crate::linalg::dense::independent_rows;

/// Entries `m n` of `Phi_q` above which a static or modes analysis refuses to start:
/// `4,000,000` (a mechanism of about 700 bodies). Their solvers are still dense (the SVD of
/// `Phi_q` and its null space at every iteration, docs/performance.md, "Scale"): a matrix of that
/// size takes 32 MB a copy and tens of seconds a decomposition, and one of a 10,000-body chain
/// would ask for 29 GB. Refused up front with the reason, rather than running for hours or
/// failing an allocation.
pub(crate) const DENSE_ANALYSIS_MAX_ENTRIES: usize = 4_000_000;

/// `Err` when `analysis` (static or modes) is too large for its dense solvers
/// ([`DENSE_ANALYSIS_MAX_ENTRIES`]), at `analyses.<name>.type`.
pub(crate) fn dense_size(analysis: &crate::model::Analysis, m: usize, n: usize) -> crate::error::Result<()> {
    if m * n <= DENSE_ANALYSIS_MAX_ENTRIES {
        return Ok(());
    }
    Err(crate::Error::Model(vec![crate::Problem::new(
        format!("analyses.{}.type", analysis.name),
        format!(
            "a {} analysis solves with dense matrices, up to {DENSE_ANALYSIS_MAX_ENTRIES} entries of the constraint \
             Jacobian; this model has {m} x {n} = {}: run a dynamic analysis instead (to rest, with damping, for an \
             equilibrium)",
            analysis.kind.name(),
            m * n
        ),
    )]))
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

/// A coordinate whose mass (or inertia) is below this fraction of the largest mass (or inertia)
/// counts as having none: `1e-12`, far below the mass ratios within one mechanism and far above
/// rounding. Masses are compared with masses and inertias with inertias: an inertia in kg m^2
/// against a mass in kg would depend on the unit of length (a 10 um body's `1e-15` against `1`).
const MASSLESS: f64 = 1e-12;

/// A motion the joints allow at `q` (`jac`, `Phi_q` there) that no mass or inertia resists: the
/// mass matrix reduced to the null space of `Phi_q` is singular, and so are the equations of
/// motion (their accelerations are not determined). A massless body is fine where the joints
/// carry it along (a massless connecting rod between massive ones); a massless wheel turning
/// freely on its axle is not. `Some` problem at the mass or inertia field of the first body in
/// that motion, naming its coordinates.
///
/// The mass matrix is diagonal (each body's mass twice and its inertia), so a motion without
/// mass moves only the massless coordinates: it is a null vector of `Phi_q`'s columns of those
/// coordinates, over the rows that touch them. That small dense matrix is all the SVD sees,
/// whatever the size of the mechanism.
pub(crate) fn massless_motion(model: &crate::model::Model, jac: &ColMatrix) -> Option<crate::Problem> {
    let mass: Vec<f64> = model.bodies.iter().flat_map(|b| [b.mass, b.mass, b.inertia]).collect();
    let largest = |kind: usize| mass.iter().skip(kind).step_by(3).fold(0.0f64, |a, &m| a.max(m));
    let (largest_mass, largest_inertia) = (largest(0), largest(2));
    let light: Vec<usize> = (0..mass.len())
        .filter(|&k| mass[k] <= MASSLESS * if k % 3 == 2 { largest_inertia } else { largest_mass })
        .collect();
    if light.is_empty() {
        return None;
    }
    let sub = jac.columns(&light);
    let mut rows = sub.row_idx.clone();
    rows.sort_unstable();
    rows.dedup();
    let mut dense = Mat::<f64>::zeros(rows.len(), light.len());
    for (c, w) in sub.col_ptr.windows(2).enumerate() {
        for (&r, &v) in sub.row_idx[w[0]..w[1]].iter().zip(&sub.values[w[0]..w[1]]) {
            dense[(rows.binary_search(&r).ok()?, c)] += v;
        }
    }
    let basis = null_space(dense.as_ref());
    if basis.ncols() == 0 {
        return None;
    }
    let mut motion = vec![0.0; mass.len()];
    for (k, &c) in light.iter().enumerate() {
        motion[c] = basis[(k, 0)];
    }
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

/// The row space of `Phi_q` (`jac`) at time `t` ([`RowSpace`]: dense for a small mechanism, the
/// Gram factorization for a large one).
pub(crate) fn row_space(jac: &ColMatrix, t: f64) -> crate::error::Result<RowSpace> {
    RowSpace::new(jac.as_ref())
        .map_err(|_| crate::Error::OutOfMemory { time: t, what: "in the rank of the constraint Jacobian".into() })
}

/// The scale of each coordinate of `columns` (indices into `q`) for [`Scaled`]: 1 for `x` and
/// `y`, `1 / L` for an angle (`L` = `sys.length`, [`length_scale`]), so that a column of `Phi_q`
/// holds the change of a row per metre of the coordinate or of the arc `L phi`: a point at the
/// lever arm `L` moves as far when its body turns by `d(L phi)` as when it slides by `dx`.
pub(crate) fn column_scales(sys: &crate::system::System<'_>, columns: impl Iterator<Item = usize>) -> Vec<f64> {
    columns.map(|c| if c % 3 == 2 { 1.0 / sys.length } else { 1.0 }).collect()
}

/// The row space of `Phi_q` (`jac`, whose columns are the coordinates `columns`) scaled to be
/// free of units ([`Scaled`], [`column_scales`]): for the rank (degrees of freedom, redundant
/// rows) and the singular ratios, and for assembly's least change, the same whatever the model's
/// unit of length.
pub(crate) fn scaled_row_space(
    sys: &crate::system::System<'_>,
    jac: &ColMatrix,
    columns: impl Iterator<Item = usize>,
    t: f64,
) -> crate::error::Result<Scaled> {
    Scaled::new(jac, &column_scales(sys, columns))
        .map_err(|_| crate::Error::OutOfMemory { time: t, what: "in the rank of the constraint Jacobian".into() })
}
