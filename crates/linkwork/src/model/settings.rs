//! The compiled form of an analysis' `solver:` section: the settings of the position solver and
//! of the dynamic integrators, each default with its reason.

use super::spec::{Formulation, IntegratorKind};

/// Settings of the position solver, with the reason for each default.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SolverSettings {
    /// Newton has converged when the max-norm of `Phi` is below this, m or rad. Default `1e-12`:
    /// about 1000 ulps of a metre-sized mechanism, so that positions are good to about ten digits
    /// after the Jacobian's amplification, and still reachable in double precision.
    pub tolerance: f64,
    /// Newton iterations per attempt before a sub-step is halved. Default 12: from a
    /// second-order predictor Newton needs 2 to 4; more means the step left the branch.
    pub max_iterations: usize,
    /// Largest rotation of any body within one sub-step, rad. Default 0.35: the predictor's error
    /// is then about `0.35^3 / 6 ~ 7e-3` rad, well inside Newton's region of convergence, so the
    /// solution cannot jump to the other assembly branch; 0.2 cost 40% more time on the
    /// quick-return benchmark with the same results (`docs/performance.md`).
    pub max_rotation: f64,
    /// Smallest sub-step, as a fraction of the output step, before the analysis gives up.
    /// Default `1e-8` (27 halvings): a mechanism that needs more is at a singular position, and
    /// stopping this close to it makes the singular value that proves it small (`~sqrt(1e-8)`).
    pub min_substep: f64,
    /// 1-norm condition estimate of the driven Jacobian above which a position counts as
    /// singular. Default `1e10`: velocities and accelerations would lose more than ten of
    /// sixteen digits.
    pub singular_condition: f64,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            tolerance: 1e-12,
            max_iterations: 12,
            max_rotation: 0.35,
            min_substep: 1e-8,
            singular_condition: 1e10,
        }
    }
}

/// The most steps one analysis may take before it stops with an error, so that no input can keep
/// the program busy for hours: 5 million steps of a small model take about a minute.
pub const MAX_STEPS: usize = 5_000_000;

/// Settings of a dynamic analysis' integrator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct IntegratorSettings {
    /// Which integrator. Default `bdf`, as Adams' GSTIFF.
    pub kind: IntegratorKind,
    /// Relative local error tolerance per step. Default `1e-6`: six digits on every position and
    /// velocity per step, tighter than drawings and measurements, loose enough that a step of
    /// a machine cycle needs tens, not thousands, of steps.
    pub rtol: f64,
    /// Absolute local error tolerance per step, in m, rad, m/s and rad/s. Default `1e-6`: a
    /// micrometre on a metre-sized machine; it governs coordinates that pass through zero.
    pub atol: f64,
    /// First step, s. Default: the time in which the state changes by about 1% (Hairer,
    /// Norsett and Wanner's starting step, computed by the integrators at the start), shrunk by
    /// the error test if too large.
    pub initial_step: Option<f64>,
    /// Largest step, s. Default: the run's length. The output step does not limit it: each
    /// integrator interpolates at its own order between its steps, so a fine output grid costs
    /// output evaluations, not steps. Set it to resolve short events (a pulse of force) that the
    /// error test could step over.
    pub max_step: Option<f64>,
    /// Highest order of `bdf` (1 to 6, default 6: BDF is zero-stable to order 6; DASSL stops at
    /// 5, whose error on a lightly damped oscillation is an amplitude loss that shifts the period
    /// of a nonlinear one, while order 6's is a phase error; docs/integrators.md) and of `abam`
    /// (1 to 12, default 12, as Shampine and Gordon's DE).
    pub max_order: Option<usize>,
    /// HHT numerical damping, in [-1/3, 0]. Default `-0.3`, as Adams HHT: strong damping of the
    /// highest frequencies (spectral radius at infinity 0.54), little of the resolved ones.
    pub alpha: f64,
    /// The equations `bdf` discretises. Default SI2 (stabilised index 2, as Adams SI2): its error
    /// test controls the velocities, whose local errors, uncontrolled in index 3, add up to a
    /// global position error 1e4 times the tolerance (docs/integrators.md).
    pub formulation: Formulation,
    /// A constant step with no error test, for measuring a method's order of convergence in
    /// the tests; not a model-file setting (a constant step gives no control of the error).
    #[serde(skip)]
    pub(crate) fixed_step: Option<f64>,
    /// The step budget: the most steps the run may take before it stops with an error. Default
    /// [`MAX_STEPS`], minutes of CPU at most. Not a model-file setting: a caller that must
    /// have an answer sooner lowers it (the fuzz target, `fuzz/`, to keep an execution short).
    #[serde(skip)]
    pub max_steps: usize,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        IntegratorSettings {
            kind: IntegratorKind::Bdf,
            rtol: 1e-6,
            atol: 1e-6,
            initial_step: None,
            max_step: None,
            max_order: None,
            alpha: -0.3,
            formulation: Formulation::Si2,
            fixed_step: None,
            max_steps: MAX_STEPS,
        }
    }
}

impl IntegratorSettings {
    /// The highest order for this integrator.
    pub fn order_limit(&self) -> usize {
        match (self.kind, self.max_order) {
            (_, Some(k)) => k,
            (IntegratorKind::Abam, None) => 12,
            _ => 6,
        }
    }
    /// The largest order the integrator supports.
    pub fn order_bound(kind: IntegratorKind) -> usize {
        match kind {
            IntegratorKind::Bdf => 6,
            IntegratorKind::Abam => 12,
            IntegratorKind::Hht => 2,
        }
    }
}
