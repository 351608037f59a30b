//! Dynamic analysis: Lagrange's equations of the first kind, an index-3 DAE,
//!
//! ```text
//! M qddot + Phi_q^T lambda = Q(q, qdot, t)
//! Phi(q, t) = 0
//! ```
//!
//! (Haug 1989 chapter 6; Nikravesh 2018 chapter 11). The analysis assembles the initial guess
//! (holding each body's `given` coordinates and velocities), computes consistent accelerations
//! and multipliers, and integrates with the method the analysis names:
//!
//! - [`bdf`]: variable order, variable step BDF on the index-3 (or stabilised index-2) form,
//!   as Adams GSTIFF / DASSL;
//! - [`hht`]: HHT-alpha on the index-3 form with step-size control (Negrut et al. 2007);
//! - [`abam`]: coordinate partitioning with Adams-Bashforth-Moulton on the independent
//!   coordinates (Wehage and Haug 1982), as Adams ABAM.
//!
//! Each integrator writes the output times through [`Output`], which computes accelerations,
//! multipliers, reactions, energies and residuals from the state it is given.

// Numerical kernels index several arrays with one loop variable.
#![allow(clippy::needless_range_loop)]

pub mod abam;
mod adams;
pub mod bdf;
mod dae;
pub mod hht;
#[cfg(test)]
mod order_tests;
mod output;

pub use crate::model::spec::{Formulation, IntegratorKind};
pub use dae::{Dae, LinearStats, EPS_REL};
pub(crate) use dae::{FRICTION_RTOL, NEWTON_FRICTION_ITERATIONS};
pub use output::{factor_error, Output, CONTACT_QUANTITIES, ENERGY_COLUMNS};

use super::promise;
use super::setup::{fail, held};
use super::{assemble_into, Run};
use crate::analysis::sensitivity::DynamicSensitivity;
use crate::constraints::ConfigBuf;
use crate::error::{Error, RowName};
use crate::model::{Analysis, IntegratorSettings, Model};
pub use crate::results::DynamicStats;
use crate::results::{Failure, Residuals, Results, Statistics};

/// The smallest step an integrator may take at `t` in a run of length `span`, s: 16 units of
/// round-off of the time, below which `t + h` no longer differs from `t` in a useful way.
/// When `steps` has used up the budget (`settings.max_steps`, by default
/// [`crate::model::MAX_STEPS`]) the run stops, with the cause [`step_failure`] sees at `(q, t)`
/// (a force or driver singular in time, a singular position), else naming the tolerances of `settings` that asked for so many steps.
pub fn min_step(
    dae: &mut Dae<'_>,
    q: &[f64],
    steps: usize,
    t: f64,
    h: f64,
    span: f64,
    settings: &IntegratorSettings,
) -> Result<f64, Error> {
    let h_min = 16.0 * f64::EPSILON * t.abs().max(span);
    if steps >= settings.max_steps {
        let (rtol, atol, budget) = (settings.rtol, settings.atol, settings.max_steps);
        let cause = format!("more than {budget} steps (the step budget)");
        return Err(match step_failure(dae, q, t, h.max(h_min), &cause) {
            Error::Integration { time, step, rows, .. } => Error::Integration {
                time,
                step,
                cause: format!("{cause} at rtol {rtol:e}, atol {atol:e}; loosen rtol/atol, or the model may be too stiff for this integrator"),
                rows,
            },
            named => named,
        });
    }
    Ok(h_min)
}

impl DynamicStats {
    /// Record an accepted step of size `h`.
    pub fn accept(&mut self, h: f64) {
        self.steps += 1;
        if self.steps == 1 {
            self.smallest_step = h;
        }
        self.smallest_step = self.smallest_step.min(h);
        self.largest_step = self.largest_step.max(h);
    }

    /// Add the steps and iterations of a stretch integrated by another method.
    pub fn absorb(&mut self, other: &DynamicStats) {
        if other.steps > 0 {
            self.smallest_step =
                if self.steps == 0 { other.smallest_step } else { self.smallest_step.min(other.smallest_step) };
            self.largest_step = self.largest_step.max(other.largest_step);
        }
        self.steps += other.steps;
        self.rejected_steps += other.rejected_steps;
        self.newton_failures += other.newton_failures;
        self.newton_iterations += other.newton_iterations;
        self.max_order_used = self.max_order_used.max(other.max_order_used);
    }
}

/// The consistent initial state handed to an integrator.
#[derive(Debug, Clone)]
pub struct Start {
    /// Start time, s.
    pub t: f64,
    /// (n) positions.
    pub q: Vec<f64>,
    /// (n) velocities.
    pub qdot: Vec<f64>,
    /// (n) accelerations.
    pub qddot: Vec<f64>,
    /// (m) multipliers.
    pub lambda: Vec<f64>,
}

/// Weighted root-mean-square norm `sqrt(sum_k (v_k / (atol + rtol |y_k|))^2 / count)` of an
/// error estimate or correction `v` against the solution `y`, given as the pairs `(v_k, y_k)`,
/// over `count` components (0 for none), as DASSL and Hairer-Wanner: 1 means "at the tolerance".
/// The norm of `bdf`'s and `hht`'s error tests, of every integrator's Newton test, and of the
/// starting step (`abam`'s error test takes the largest weighted change of every coordinate
/// instead, its `Split::norm`); `count` may exceed the pairs given when some components carry no error (a massless
/// coordinate's load), which then count as zero in the mean.
pub fn wrms(terms: impl IntoIterator<Item = (f64, f64)>, count: usize, rtol: f64, atol: f64) -> f64 {
    let s: f64 = terms.into_iter().map(|(v, y)| (v / (atol + rtol * y.abs())).powi(2)).sum();
    (s / count.max(1) as f64).sqrt()
}

/// Units of round-off that a Newton correction cannot get below: the residual of the equations
/// carries a few units of round-off of its largest terms (forces, lever arms of metres), and the
/// solve multiplies them by the condition of the Newton matrix (`1e2` to `1e4` on the examples).
pub const ROUNDOFF_UNITS: f64 = 1e3;

/// The largest correction `|dy_k|` relative to round-off at the scale of the state:
/// `max_k |dy_k| / (ROUNDOFF_UNITS eps (|y_k| + scale))`, `scale` the size of the quantity (the
/// largest `|y|` of its kind, so that a coordinate passing through zero is measured against the
/// mechanism's size). At most 1: the correction is noise, Newton can do no better, and a
/// convergence test that asks for more asks for the impossible.
pub fn roundoff_ratio(dy: &[f64], y: &[f64], scale: f64) -> f64 {
    let unit = ROUNDOFF_UNITS * f64::EPSILON;
    dy.iter().zip(y).map(|(d, x)| d.abs() / (unit * (x.abs() + scale)).max(f64::MIN_POSITIVE)).fold(0.0, f64::max)
}

/// The largest and the first step of an integrator, `(h_max, h0)`, s, for a run of length
/// `span` from `start`.
///
/// - `h_max`: the user's `max_step`, else the span. The output times do not limit the step:
///   every integrator interpolates at its own order between its steps, and the error test, not
///   the output grid, decides the step (as DASSL, whose `HMAX` is unbounded by default).
/// - `h0`: the user's `initial_step`, else Hairer, Norsett and Wanner's starting step (Solving ODEs
///   I, section II.4): `0.01 |y| / |y'|` in the weighted norm [`wrms`] of `y = (q, qdot)`, the
///   time in which the state changes by about 1% (`1e-6` s when either norm is below `1e-5`: a
///   state at rest or at the origin). It depends on the tolerance and the motion, not on the
///   output step; a first step too large is shrunk by the error test.
pub fn step_bounds(settings: &IntegratorSettings, start: &Start, span: f64) -> (f64, f64) {
    let span = span.max(f64::MIN_POSITIVE);
    let h_max = settings.max_step.unwrap_or(span).min(span);
    let h0 = settings.initial_step.unwrap_or_else(|| {
        let (rt, at) = (settings.rtol, settings.atol);
        let y = || start.q.iter().chain(&start.qdot).copied();
        let dy = start.qdot.iter().chain(&start.qddot).copied();
        let count = 2 * start.q.len();
        let (d0, d1) = (wrms(y().zip(y()), count, rt, at), wrms(dy.zip(y()), count, rt, at));
        if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        }
    });
    (h_max, h0.min(h_max))
}

/// A run's span of time and the bounds of its steps, as every integrator uses them.
#[derive(Debug, Clone, Copy)]
pub struct Span {
    /// End time, s.
    pub t_end: f64,
    /// Length of the run, s.
    length: f64,
    /// Largest and first step, s ([`step_bounds`]).
    pub h_max: f64,
    pub h_start: f64,
    /// Steps taken before this run (by the method that handed it over), counted in the budget.
    taken: usize,
}

impl Span {
    /// The run from `start` to `t_end` under `settings`, after `taken` steps of another run
    /// (0 for a whole analysis).
    pub fn new(settings: &IntegratorSettings, start: &Start, t_end: f64, taken: usize) -> Span {
        let (h_max, h_start) = step_bounds(settings, start, t_end - start.t);
        Span { t_end, length: t_end - start.t, h_max, h_start, taken }
    }

    /// Whether `t` is short of the end by more than `1e-12` of the run, the rounding of a sum of
    /// steps.
    pub fn before_end(&self, t: f64) -> bool {
        t < self.t_end - 1e-12 * self.length.max(1e-300)
    }

    /// The step `h` from `t`, made to end at the end time when it would pass it or fall short of
    /// it by less than `1e-3` of itself (a sliver of a last step would be all round-off).
    pub fn fit(&self, t: f64, h: f64) -> f64 {
        if t + h > self.t_end || self.t_end - (t + h) < 1e-3 * h {
            self.t_end - t
        } else {
            h
        }
    }

    /// The smallest step at `t` ([`min_step`] over this run), or the error that stops the run:
    /// an interruption (every step attempt reports its time to the run through `out`, and
    /// stops there once the run has been asked to stop), the step budget spent, or (`shrunk`: for methods whose accepted steps can shrink the step
    /// too, as an error estimate that grows from step to step) `h` already below the smallest.
    #[allow(clippy::too_many_arguments)]
    pub fn smallest_step(
        &self,
        out: &Output<'_, '_>,
        dae: &mut Dae<'_>,
        q: &[f64],
        steps: usize,
        t: f64,
        h: f64,
        settings: &IntegratorSettings,
        shrunk: bool,
    ) -> Result<f64, Error> {
        out.attempt(t)?;
        let h_min = min_step(dae, q, self.taken + steps, t, h, self.length, settings)?;
        if shrunk && h < h_min {
            // Stop here rather than creep towards zero.
            return Err(step_failure(dae, q, t, h, "the error estimate has driven the step below the smallest step"));
        }
        Ok(h_min)
    }
}

/// The ratio of the smallest to the largest singular value of `Phi_q` at `(q, t)`, and the rows
/// of the smallest ([`RowSpace::smallest_singular`](crate::linalg::rows::RowSpace::smallest_singular)):
/// the evidence of a singular position.
pub fn singular_rows(dae: &mut Dae<'_>, q: &[f64], t: f64) -> (f64, Vec<RowName>) {
    let jac = dae.sys.jacobian(&ConfigBuf::new(q).view(), t);
    let Ok(mut space) = crate::analysis::scaled_row_space(&dae.sys, &jac, 0..jac.ncols(), t) else {
        return (0.0, vec![]);
    };
    let (ratio, rows) = space.smallest_singular();
    (ratio, rows.into_iter().map(|i| dae.sys.row_name(i)).collect())
}

/// A force that changes by more than this fraction of itself over the step at which an
/// integrator fails, the mechanism held at rest, has a singularity in time there: 1%. That step
/// is 16 units of round-off of `t` or of the span ([`min_step`]), over which a smooth force
/// changes by `~1e-12` of itself even at a frequency of `1e2` rad/s, and `1/(t - c)` by its whole
/// size.
const SUDDEN_FORCE: f64 = 1e-2;

/// The cause of a step failure when a first contact cannot be reached within `max_penetration`
/// by shortening the step.
pub const CONTACT_UNRESOLVED: &str =
    "a first contact cannot be located: the step that ends within the contact's max_penetration is below the smallest";

/// The failure of an integrator whose step fell below `h_min` at `t`: names a force or driver
/// that is not finite at `t + h` ([`Error::NonFinite`]), else a force with a singularity in time
/// there ([`Error::Unbounded`]), else, where `Phi_q` has (nearly) lost rank,
/// the rows of the singularity, else the rows with the largest position residual.
pub fn step_failure(dae: &mut Dae<'_>, q: &[f64], t: f64, h: f64, cause: &str) -> Error {
    // A force or driver that is NaN or infinite just past the failure (`sqrt(0.503 - t)`) is the
    // cause: name it, its expression and the time (the mechanism held at rest, as below). The
    // step that failed may be up to 4 times `h` (the last cut), hence the probes to `16 h`.
    for probe in [1.0, 4.0, 16.0].map(|k| t + k * h) {
        if let Some(e) = non_finite_element(dae, q, probe) {
            return e;
        }
    }
    // A force with a singularity in time at the failure (a torque `1/(t - 0.503)`): the
    // integrator cannot pass it, and it, not a joint, is the cause.
    let sudden = dae
        .forces
        .iter()
        .map(|f| (f, f.change_over(q, t, h)))
        .filter(|(_, (change, relative))| change.is_finite() && *relative > SUDDEN_FORCE)
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1));
    if let Some((f, (change, _))) = sudden {
        return Error::Unbounded {
            time: t,
            element: format!("forces.{}", f.name),
            expression: f.expressions(),
            rate: change / h,
            limit: format!("the integrator's step fell to {h:.3e} s ({cause})"),
        };
    }
    let (ratio, rows) = singular_rows(dae, q, t);
    if ratio < crate::analysis::SINGULAR_RATIO_DYNAMIC {
        return Error::Singular {
            time: t,
            rows,
            detail: format!(
                "the integrator cannot step past this position ({cause}, step {h:.3e} s); the constraint Jacobian is nearly singular there (smallest/largest singular value {ratio:.3e}): a dead centre or bifurcation"
            ),
        };
    }
    Error::Integration { time: t, step: h, cause: cause.to_string(), rows }
}

/// The first force or driver of `dae` that is NaN or infinite at `(q, t)`, at rest.
fn non_finite_element(dae: &mut Dae<'_>, q: &[f64], t: f64) -> Option<Error> {
    let rest = vec![0.0; q.len()];
    if let Some((f, value)) = dae.forces.iter().find_map(|f| Some((f, f.non_finite(q, &rest, t)?))) {
        return Some(Error::NonFinite {
            time: t,
            element: format!("forces.{}", f.name),
            expression: f.expressions(),
            value,
        });
    }
    let config = ConfigBuf::new(q);
    let mut rows = vec![0.0; dae.m];
    dae.sys.phi(&config.view(), t, &mut rows);
    dae.sys.non_finite(&rows, t).or_else(|| {
        dae.sys.nu(&config.view(), t, &mut rows);
        dae.sys.non_finite(&rows, t)
    })
}

/// Hermite interpolation on `[t0, t0 + h]` of positions from `(q, qdot, qddot)` at both ends
/// (quintic) and of velocities as its derivative; `theta = (t - t0) / h`.
pub fn hermite5(theta: f64, h: f64, y0: [&[f64]; 3], y1: [&[f64]; 3], q: &mut [f64], qdot: &mut [f64]) {
    let t = theta;
    let (t2, t3, t4, t5) = (t * t, t * t * t, t.powi(4), t.powi(5));
    let h0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5;
    let h1 = t - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
    let h2 = 0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5;
    let h3 = 0.5 * t3 - t4 + 0.5 * t5;
    let h4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
    let h5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
    let d0 = -30.0 * t2 + 60.0 * t3 - 30.0 * t4;
    let d1 = 1.0 - 18.0 * t2 + 32.0 * t3 - 15.0 * t4;
    let d2 = t - 4.5 * t2 + 6.0 * t3 - 2.5 * t4;
    let d3 = 1.5 * t2 - 4.0 * t3 + 2.5 * t4;
    let d4 = -12.0 * t2 + 28.0 * t3 - 15.0 * t4;
    let d5 = 30.0 * t2 - 60.0 * t3 + 30.0 * t4;
    let [q0, v0, a0] = y0;
    let [q1, v1, a1] = y1;
    for k in 0..q.len() {
        let (hv0, ha0, hv1, ha1) = (h * v0[k], h * h * a0[k], h * v1[k], h * h * a1[k]);
        q[k] = h0 * q0[k] + h1 * hv0 + h2 * ha0 + h3 * ha1 + h4 * hv1 + h5 * q1[k];
        qdot[k] = (d0 * q0[k] + d1 * hv0 + d2 * ha0 + d3 * ha1 + d4 * hv1 + d5 * q1[k]) / h;
    }
}

/// Run a dynamic analysis. On failure the results up to the last good output time are kept.
pub(crate) fn run_dynamic(model: &Model, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
    let mut settings = analysis.integrator;
    // A tighter rtol would ask the error test to resolve round-off (warned in the summary).
    settings.rtol = settings.rtol.max(super::RTOL_FLOOR);
    let n = model.n();
    let mut dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => return Err(fail(Results::new(model, analysis), factor_error(e, analysis.t_start))),
    };
    let m = dae.m;
    let mut sensitivity = match run.sensitivities.as_slice() {
        [] => None,
        asked => match DynamicSensitivity::new(model, analysis, asked, &dae) {
            Ok(s) => Some(s),
            Err(e) => return Err(fail(Results::new(model, analysis), e)),
        },
    };
    let mut out = Output::new(model, analysis, n, m, run);
    let t0 = analysis.t_start;
    // Assembly holds what the user marked as given.
    let given = held(model, true);
    let assembly = match assemble_into(model, analysis, &mut dae.sys, &given, t0, &mut out.results.summary) {
        Ok(a) => a,
        Err(e) => return Err(fail(out.results, e)),
    };
    let jac = dae.sys.jacobian(&ConfigBuf::new(&assembly.q).view(), t0);
    let mut rows = match crate::analysis::scaled_row_space(&dae.sys, &jac, 0..n, t0) {
        Ok(rows) => rows,
        Err(e) => return Err(fail(out.results, e)),
    };
    let (independent, redundant) = rows.independent_rows();
    let redundant_rows: Vec<RowName> = redundant.iter().map(|&r| dae.sys.row_name(r)).collect();
    let indeterminate = crate::analysis::element_names(&dae.sys, &rows.dependent_rows());
    if let Some(problem) = crate::analysis::massless_motion(model, &jac) {
        return Err(fail(out.results, Error::Model(vec![problem])));
    }
    let mut sol = vec![0.0; n + m];
    if let Err(e) = dae.accelerations(&assembly.q, &assembly.qdot, t0, &mut sol) {
        return Err(fail(out.results, e));
    }
    let start = Start {
        t: t0,
        q: assembly.q.clone(),
        qdot: assembly.qdot.clone(),
        qddot: sol[..n].to_vec(),
        lambda: sol[n..].to_vec(),
    };
    out.start_work(&mut dae, t0, &start.q, &start.qdot, &start.lambda);
    let pushed = out.push(&mut dae, t0, &start.q, &start.qdot).and_then(|()| match &mut sensitivity {
        None => Ok(None),
        Some(eq) => {
            let sol = out.solution().to_vec();
            let tracks = eq.start(&mut dae, t0, &start.q, &start.qdot, &sol, &independent, &given)?;
            eq.push(&mut out.results, &dae, t0, &start.q, &start.qdot, &sol, &tracks)?;
            Ok(Some((eq, tracks)))
        }
    });
    let (mut stats, outcome) = match pushed {
        Err(e) => (DynamicStats::default(), Err(e)),
        // Sensitivities are integrated by bdf and abam (analysis/run.rs refuses hht).
        Ok(Some((eq, tracks))) if settings.kind == IntegratorKind::Abam => {
            abam::integrate(&mut dae, &mut out, &settings, start, Some((eq, tracks)))
        }
        Ok(Some((eq, tracks))) => bdf::run_sensitive(&mut dae, &mut out, &settings, start, eq, tracks),
        Ok(None) => match settings.kind {
            IntegratorKind::Hht => hht::run(&mut dae, &mut out, &settings, start),
            IntegratorKind::Bdf => bdf::run(&mut dae, &mut out, &settings, start),
            IntegratorKind::Abam => abam::run(&mut dae, &mut out, &settings, start),
        },
    };
    let error = outcome.err();
    stats.jacobian_evaluations = dae.stats.jacobian_evaluations;
    stats.factorizations = dae.stats.factorizations;
    let mut results = out.results;
    let s = &mut results.summary;
    s.dof = Some(n - independent.len());
    s.integrator = Some(settings);
    s.redundant_rows = Some(redundant_rows);
    s.indeterminate_joints = Some(indeterminate);
    s.assembly = Some(assembly.report());
    let audit = &out.audit;
    s.residuals = Some(Residuals { max_position: audit.position.value, max_velocity: audit.velocity.value });
    if let Some(t) = stats.first_crossing {
        s.warnings.push(format!(
            "abam: near singular positions (Phi_q losing rank; the first at t = {t:.6} s) the error estimate at rtol {:e} was the round-off noise of the accelerations; bdf took the state across, in {} stretches",
            settings.rtol, stats.crossings
        ));
    }
    s.statistics = Some(Statistics::Dynamic(stats));
    results.insert_reaction_summary(model);
    // A run that ended is checked against what it promised: the system conserves energy when
    // nothing but gravity and undamped springs does work on it. A fixed step (the order tests')
    // promises nothing: no error test chose it.
    let error = error.or_else(|| {
        if settings.fixed_step.is_some() {
            return None;
        }
        let conservative =
            analysis.drivers.is_empty() && !dae.has_friction() && dae.forces.iter().all(|f| f.force.conservative());
        let warnings = &mut results.summary.warnings;
        promise::check_dynamic(audit, &settings, conservative, |r| dae.sys.row_name(r), warnings).err()
    });
    match error {
        None => Ok(results),
        Some(e) => Err(fail(results, e)),
    }
}

/// An integrator's outcome: its statistics, and the error that stopped it if one did.
pub type Outcome = (DynamicStats, Result<(), Error>);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::FactorError;
    use crate::model::MAX_STEPS;
    use crate::Model;

    /// Memory running out in a factorization is its own error, with its time, and the summary
    /// says when (it was a file error with no path, so Python raised `FileError`).
    #[test]
    fn out_of_memory_is_its_own_error() {
        let e = factor_error(FactorError::OutOfMemory, 0.25);
        assert!(matches!(e, Error::OutOfMemory { time, .. } if time == 0.25), "{e:?}");
        assert_eq!(e.to_string(), "out of memory while factorizing at t = 0.25 s");
        let model = Model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/fourbar.yaml")).unwrap();
        let summary = Results::of_model(&model).summary_json(Some(&e));
        assert_eq!(summary["error_time"], 0.25);
    }

    /// The quintic Hermite interpolant reproduces a quintic polynomial and its derivative
    /// exactly (to rounding), from values, first and second derivatives at both ends.
    #[test]
    fn hermite5_reproduces_quintics() {
        let p = |t: f64| [1.0 - 2.0 * t + 0.5 * t.powi(3) + 0.3 * t.powi(5), 3.0 * t * t - t.powi(4)];
        let dp = |t: f64| [-2.0 + 1.5 * t * t + 1.5 * t.powi(4), 6.0 * t - 4.0 * t.powi(3)];
        let ddp = |t: f64| [3.0 * t + 6.0 * t.powi(3), 6.0 - 12.0 * t * t];
        let (t0, h) = (0.4, 0.7);
        let (q0, v0, a0) = (p(t0), dp(t0), ddp(t0));
        let (q1, v1, a1) = (p(t0 + h), dp(t0 + h), ddp(t0 + h));
        for theta in [0.0, 0.13, 0.5, 0.77, 1.0] {
            let (mut q, mut v) = ([0.0; 2], [0.0; 2]);
            hermite5(theta, h, [&q0, &v0, &a0], [&q1, &v1, &a1], &mut q, &mut v);
            let (qe, ve) = (p(t0 + theta * h), dp(t0 + theta * h));
            for k in 0..2 {
                assert!((q[k] - qe[k]).abs() < 1e-14 && (v[k] - ve[k]).abs() < 1e-13, "{theta}: {q:?} {v:?}");
            }
        }
    }

    /// At the step budget the run said "loosen rtol/atol" whatever the cause. A slider-crank
    /// driven into its lock-up (the rod at right angles to the guide, crank at `asin(0.6)`) is a
    /// singular position: it is named as one. The same budget at a regular position (crank at
    /// 0.3 rad) still gives the tolerances to loosen.
    #[test]
    fn the_step_budget_names_a_singular_position() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/slider_crank_lockup.yaml");
        let model = Model::load(path).unwrap();
        let mut dae = Dae::new(&model, &[0], &[]).unwrap();
        let settings = IntegratorSettings::default();
        let theta = 0.6f64.asin();
        let (ax, ay) = (0.2 * theta.cos(), 0.2 * theta.sin());
        let lockup = [0.5 * ax, 0.5 * ay, theta, ax, 0.06, -std::f64::consts::FRAC_PI_2, ax, 0.0, 0.0];
        let e = min_step(&mut dae, &lockup, MAX_STEPS, theta, 1e-9, 2.0, &settings).unwrap_err();
        let message = e.to_string();
        assert!(matches!(e, Error::Singular { .. }), "{message}");
        assert!(message.contains("more than 5000000 steps") && !message.contains("loosen"), "{message}");

        let theta = 0.3f64;
        let (ax, ay) = (0.2 * theta.cos(), 0.2 * theta.sin());
        let beta = (-ay / 0.12).asin();
        let (bx, rod) = (ax + 0.12 * beta.cos(), [ax + 0.06 * beta.cos(), 0.5 * ay, beta]);
        let regular = [0.5 * ax, 0.5 * ay, theta, rod[0], rod[1], rod[2], bx, 0.0, 0.0];
        let e = min_step(&mut dae, &regular, MAX_STEPS, theta, 1e-3, 2.0, &settings).unwrap_err();
        assert!(matches!(e, Error::Integration { .. }) && e.to_string().contains("loosen rtol/atol"), "{e}");
        assert_eq!(min_step(&mut dae, &regular, 10, theta, 1e-3, 2.0, &settings).unwrap(), 16.0 * f64::EPSILON * 2.0);
    }
}
