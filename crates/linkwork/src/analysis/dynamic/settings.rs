//! Settings of the dynamic integrators, each default with its reason.

pub use crate::model::spec::{Formulation, IntegratorKind};

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
    /// Norsett and Wanner's starting step, [`super::step_bounds`]), shrunk by the error test if
    /// too large.
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
    /// [`super::MAX_STEPS`], minutes of CPU at most. Not a model-file setting: a caller that must
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
            max_steps: super::MAX_STEPS,
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
