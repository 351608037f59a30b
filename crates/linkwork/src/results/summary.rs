//! The summary of a run, typed: what `summary.json` says besides the status.
//!
//! Every summary has the common header: the model's `model`, `bodies`, `coordinates`, `joints`;
//! the analysis' `analysis`, `type`, `active_drivers`, `settings` (absent when the run named no
//! analysis of the model); `output_points` and `warnings` (a list, empty when there is nothing
//! to say). The analysis adds what it found, each fact under one key with one shape whichever
//! analysis writes it:
//!
//! | key | written by | what |
//! |---|---|---|
//! | `dof` | every analysis that got as far as the rank of `Phi_q` | degrees of freedom the joints and active drivers leave |
//! | `redundant_rows` | every analysis that got as far as the rank of `Phi_q` | rows that repeat earlier ones, `[{"element", "equation"}]` |
//! | `indeterminate_joints` | inverse, static, modes, dynamic | joints whose reactions the equations leave open |
//! | `assembly` | kinematic, inverse, dynamic | `iterations`, `residual`, `velocity_residual` at the start |
//! | `statistics` | kinematic, inverse, static, dynamic | what the solver did ([`Statistics`]) |
//! | `integrator`, `residuals` | dynamic | the integrator's settings; the largest constraint residuals at output |
//! | `stable`, `index`, `min_reduced_stiffness` | static (`stable` also modes) | the equilibrium's stability |
//! | `about`, `modes` | modes | the state linearised about; the modes ([`Mode`]) |
//! | `reaction_bodies`, `peaks` | inverse, static, dynamic | each joint's first body; the largest reactions and efforts ([`Peak`]) |
//! | `summaries` | every analysis whose output spans time (not modes, nor static at one time), when the model has summaries and the run ended well | each summary's value by name (`model.yaml`'s `summaries:`, [`crate::expr::functional`]) |
//! | `sensitivities` | a run asked for sensitivities that ended well | each summary's and peak's derivative with respect to each parameter asked for ([`Summary::sensitivities`]) |
//!
//! An analysis that fails writes what it found before the failure, but no `summaries`: a
//! whole-run quantity over part of the run would be another quantity under the same name.

use crate::error::RowName;
use crate::model::spec::{AnalysisKind, LinearisePoint};
use crate::model::structure::{Branch, BranchChange};
use crate::model::{IntegratorSettings, SolverSettings};
use indexmap::IndexMap;
use serde::Serialize;
use std::collections::BTreeMap;

/// What a run found, for `summary.json` (`Results::summary_json` adds `output_points`, `status`
/// and the error). Optional parts are left out of the file when absent.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Summary {
    /// Name of the model.
    pub model: String,
    /// Number of moving bodies.
    pub bodies: usize,
    /// Number of coordinates, three per body.
    pub coordinates: usize,
    /// The joints, in file order.
    pub joints: Vec<String>,
    /// The parameters' values used, SI (empty when the file has none).
    pub parameters: IndexMap<String, f64>,
    /// The analysis run; `None` when the run named no analysis of the model.
    #[serde(flatten)]
    pub analysis: Option<AnalysisHeader>,
    /// Degrees of freedom the joints and active drivers leave: the coordinates less the rank of
    /// `Phi_q` at the start (a modes analysis: at the state it linearises about; 0 for a kinematic
    /// or inverse analysis, which needs a fully driven model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dof: Option<usize>,
    /// Messages about the run (tolerances below what the arithmetic reaches, `abam`'s
    /// crossings); empty when there is nothing to say.
    pub warnings: Vec<String>,
    /// Rows of `Phi_q` that repeat earlier rows, where [`Summary::dof`] is counted: they hold
    /// implicitly (a kinematic, inverse or dynamic analysis leaves them out of its solve).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub redundant_rows: Option<Vec<RowName>>,
    /// Joints (and drivers) whose share of the reactions the equations leave open (redundant
    /// supports): their reactions are the minimum-norm ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indeterminate_joints: Option<Vec<String>>,
    /// The assembly at the start time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub assembly: Option<AssemblyReport>,
    /// The assembly mode of every dyad at the start (docs/model-format.md, "Branches").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branches: Option<Vec<Branch>>,
    /// Each change of a dyad's branch during the run (through a toggle position), with its time.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub branch_changes: Vec<BranchChange>,
    /// What the solver did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistics: Option<Statistics>,
    /// The integrator's settings (dynamic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<IntegratorSettings>,
    /// The largest constraint residuals at an output point (dynamic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals: Option<Residuals>,
    /// Whether the state is a stable equilibrium (static: every equilibrium written; modes: no
    /// mode grows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stable: Option<bool>,
    /// The equilibrium's index and stiffness (static).
    #[serde(flatten)]
    pub equilibrium: Option<EquilibriumReport>,
    /// The state a modes analysis linearised about.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub about: Option<LinearisePoint>,
    /// The modes of a modes analysis: the unstable ones first, fastest growing first; then the
    /// others, lowest frequency first.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<Vec<Mode>>,
    /// The bodies reactions act on and the peaks of the reactions and efforts (inverse, static,
    /// dynamic).
    #[serde(flatten)]
    pub reactions: Option<Reactions>,
    /// The model's summaries by name, each a finite number: written by a run that ended well and
    /// whose output spans time (`None` otherwise, or when the model has none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summaries: Option<IndexMap<String, f64>>,
    /// The derivatives of the summaries and the peaks with respect to the parameters a run was
    /// asked for ([`crate::Results::sensitivities`]): summary or peak name, then parameter, then
    /// the derivative, SI per SI unit of the parameter. Each summary and peak whose columns all
    /// have derivatives, with each parameter along which its derivative is a finite number (a
    /// column's largest value at a row has the derivative of that row, the first of those that
    /// reach it: [`crate::expr::functional`]). `None` when no sensitivities were asked for, or the
    /// run did not end well.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensitivities: Option<IndexMap<String, IndexMap<String, f64>>>,
}

/// The analysis a summary is of.
#[derive(Debug, Clone, Serialize)]
pub struct AnalysisHeader {
    /// Its name in the model file.
    pub analysis: String,
    /// Its kind.
    #[serde(rename = "type")]
    pub kind: AnalysisKind,
    /// The drivers it holds, in file order.
    pub active_drivers: Vec<String>,
    /// Its position solver's settings.
    pub settings: SolverSettings,
}

/// How the assembly at the start went.
#[derive(Debug, Clone, Serialize)]
pub struct AssemblyReport {
    /// Newton iterations taken.
    pub iterations: usize,
    /// Max-norm of `Phi` at the assembled position.
    pub residual: f64,
    /// Max-norm of `Phi_q qdot - nu` there.
    pub velocity_residual: f64,
}

/// The largest constraint residuals at an output point of a dynamic analysis.
#[derive(Debug, Clone, Serialize)]
pub struct Residuals {
    /// Largest `|Phi|`, m or rad.
    pub max_position: f64,
    /// Largest `|Phi_q qdot - nu|`, m/s or rad/s.
    pub max_velocity: f64,
}

/// A static equilibrium's stability, beside [`Summary::stable`].
#[derive(Debug, Clone, Serialize)]
pub struct EquilibriumReport {
    /// The number of unstable directions of the equilibrium reached: 0 when every equilibrium
    /// written is stable; that of the unstable one a failed run stopped at (`None` when the loads
    /// had no equilibrium).
    pub index: Option<usize>,
    /// Smallest eigenvalue of the reduced tangent stiffness over the equilibria written (`None`
    /// when none was).
    pub min_reduced_stiffness: Option<f64>,
}

/// Which body each joint's reaction acts on, and the peaks of the reactions and efforts.
#[derive(Debug, Clone, Serialize)]
pub struct Reactions {
    /// For each joint the body its reaction acts on (its first, `ground` for the ground), for
    /// reactions in that body's frame.
    pub reaction_bodies: BTreeMap<String, String>,
    /// For every joint the largest resultant force `<joint>.force` (`|(fx, fy)|`) and the largest
    /// `<joint>.torque`, for every active driver the largest `<driver>.effort`.
    pub peaks: BTreeMap<String, Peak>,
}

/// The largest absolute value of a column and when.
#[derive(Debug, Clone, Serialize)]
pub struct Peak {
    /// Largest absolute value, N or N m.
    pub max_abs: f64,
    /// Its time, s (the last, if it is reached more than once); `None` without an output point.
    pub time: Option<f64>,
}

/// What an analysis' solver did: the same keys under `statistics` as each solver's own struct.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Statistics {
    /// A kinematic or inverse analysis.
    Kinematic(KinematicStats),
    /// A static analysis.
    Static(StaticStats),
    /// A dynamic analysis.
    Dynamic(DynamicStats),
}

/// What the kinematic solver did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct KinematicStats {
    /// Output points written (including the initial one).
    pub output_points: usize,
    /// Accepted sub-steps.
    pub substeps: usize,
    /// Rejected sub-steps (Newton failure or branch jump), each followed by halving.
    pub rejected_substeps: usize,
    /// Newton iterations in all attempts.
    pub newton_iterations: usize,
    /// Numeric LU factorizations.
    pub factorizations: usize,
    /// Largest `|Phi|` accepted at an output point.
    pub max_residual: f64,
    /// Largest 1-norm condition estimate of the driven Jacobian at an output point.
    pub max_condition: f64,
    /// Assembly at the start time.
    pub assembly_iterations: usize,
    /// Largest change assembly made to the initial guess.
    pub assembly_max_change: f64,
}

/// What the static solver did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StaticStats {
    /// Newton iterations in all equilibria and load steps.
    pub iterations: usize,
    /// Load steps taken where Newton and the descents did not converge (0: none needed).
    pub load_steps: usize,
    /// Descents from a point that was not a stable equilibrium (0: Newton went straight to one).
    pub descents: usize,
    /// Largest force residual `|Q - Phi_q^T lambda|` at a written equilibrium, N or N m.
    pub force_residual: f64,
    /// Largest constraint residual `|Phi|` at a written equilibrium, m or rad.
    pub position_residual: f64,
    /// The largest load `F` the force tolerance is relative to.
    pub load_scale: f64,
}

/// What an integrator did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct DynamicStats {
    /// Accepted steps.
    pub steps: usize,
    /// Steps rejected by the error test.
    pub rejected_steps: usize,
    /// Steps rejected because Newton's method did not converge.
    pub newton_failures: usize,
    /// Newton iterations in all attempts.
    pub newton_iterations: usize,
    /// Evaluations of the Newton matrix (`jacobian_evaluations` of the linear algebra).
    pub jacobian_evaluations: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Smallest and largest accepted step, s.
    pub smallest_step: f64,
    /// Largest accepted step, s.
    pub largest_step: f64,
    /// Highest order used (`bdf`, `abam`; 2 for `hht`).
    pub max_order_used: usize,
    /// Independent coordinates used by `abam`: the first choice and each change of it.
    pub partitions: usize,
    /// Stretches `abam` handed to `bdf` across a singular position, where its error estimate is
    /// the round-off noise of the accelerations.
    pub crossings: usize,
    /// Start of the first such stretch, s.
    pub first_crossing: Option<f64>,
}

/// What a mode's motion does, from its eigenvalue `s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModeKind {
    /// An oscillation that does not grow: `Im s > 0`, `Re s <= 0`.
    Vibration,
    /// A motion that dies away without oscillating (overdamped): `s` real and negative.
    Decay,
    /// No stiffness and no damping along it: `s = 0`, the mechanism drifts.
    Neutral,
    /// Unstable: the mechanism falls away without oscillating, `s` real and positive.
    Divergence,
    /// Unstable: an oscillation that grows, `Re s > 0`, `Im s > 0`.
    Flutter,
}

/// One mode of the linearised mechanism.
#[derive(Debug, Clone, Serialize)]
pub struct Mode {
    /// What the motion does.
    pub kind: ModeKind,
    /// Undamped natural frequency `|s| / 2 pi`, Hz (`None` for an unstable mode).
    pub frequency: Option<f64>,
    /// Damped frequency `Im s / 2 pi`, Hz (0 for a non-oscillating mode).
    pub damped_frequency: f64,
    /// Damping ratio `-Re s / |s|` (`None` for a neutral or an unstable mode).
    pub damping_ratio: Option<f64>,
    /// Growth rate `Re s` of an unstable mode, 1/s: the motion grows as `e^{rate t}` (`None`
    /// for a stable mode).
    pub growth_rate: Option<f64>,
    /// The eigenvalue `s = [Re, Im]` (with `Im >= 0`), 1/s.
    pub eigenvalue: [f64; 2],
    /// The shape: each coordinate `<body>.x, .y, .phi`'s share, the largest 1 (the real part
    /// after turning the complex shape so that its largest component is real).
    pub shape: BTreeMap<String, f64>,
}

#[cfg(test)]
mod tests {
    use crate::Model;
    use serde_json::{json, Value};

    fn example(file: &str) -> String {
        std::fs::read_to_string(format!("{}/../../examples/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap()
    }

    /// `summary.json` of `analysis` of the model in `yaml`, failed or not.
    fn summary(yaml: &str, analysis: &str) -> Value {
        let model = Model::from_yaml(yaml).unwrap();
        match model.run(analysis, &Default::default()) {
            Ok(r) => r.summary_json(None),
            Err(f) => f.results.summary_json(Some(&f.error)),
        }
    }

    /// Every analysis, failed or not, writes the common header, and each fact in one shape at one
    /// place: `dof` a count, `redundant_rows` a list of `{element, equation}` at the top (for
    /// kinematics as for dynamics), `warnings` a list of strings.
    #[test]
    fn every_analysis_writes_the_header_and_each_fact_in_one_shape() {
        // The parallelogram's third link repeats a row: with a dynamic analysis beside its
        // kinematic one, both list it.
        let parallelogram =
            example("parallelogram.yaml") + "  dynamics: {type: dynamic, drivers: [], t_end: 0.1, step: 0.05}\n";
        let coupler_3_y = json!([{"element": "coupler_3", "equation": "y"}]);
        let header = [
            "model",
            "bodies",
            "coordinates",
            "joints",
            "parameters",
            "analysis",
            "type",
            "active_drivers",
            "settings",
            "output_points",
            "dof",
            "warnings",
            "redundant_rows",
            "status",
        ];
        for (yaml, analysis, kind, status, dof, redundant) in [
            (&parallelogram, "kinematics", "kinematic", "ok", 0, &coupler_3_y),
            (&parallelogram, "dynamics", "dynamic", "ok", 1, &coupler_3_y),
            (&example("quick_return_a.yaml"), "inverse", "inverse", "ok", 0, &json!([])),
            (&example("hanging_fourbar.yaml"), "rest", "static", "ok", 1, &json!([])),
            (&example("hanging_fourbar.yaml"), "vibration", "modes", "ok", 1, &json!([])),
            (&example("slider_crank_lockup.yaml"), "kinematics", "kinematic", "failed", 0, &json!([])),
        ] {
            let s = summary(yaml, analysis);
            for key in header {
                assert!(s.get(key).is_some(), "{analysis} ({kind}): no {key}: {s}");
            }
            assert_eq!((&s["type"], &s["status"]), (&json!(kind), &json!(status)), "{analysis}");
            assert_eq!(s["dof"], json!(dof), "{analysis} ({kind})");
            assert_eq!(&s["redundant_rows"], redundant, "{analysis} ({kind})");
            assert!(s["warnings"].as_array().is_some_and(|w| w.iter().all(Value::is_string)), "{analysis}");
            assert!(s["statistics"].get("redundant_rows").is_none(), "{analysis} ({kind}): one place");
        }
        let failed = summary(&example("slider_crank_lockup.yaml"), "kinematics");
        assert!(failed["error"].is_string() && failed["error_elements"].is_array() && failed["error_time"].is_f64());
    }

    /// A run that names no analysis of the model writes the model's header, no analysis' part.
    #[test]
    fn a_run_of_no_analysis_writes_the_model_header() {
        let s = summary(&example("fourbar.yaml"), "nonesuch");
        let keys: Vec<&str> = s.as_object().unwrap().keys().map(String::as_str).collect();
        let expected = [
            "bodies",
            "coordinates",
            "error",
            "error_elements",
            "joints",
            "model",
            "output_points",
            "parameters",
            "status",
            "warnings",
        ];
        assert_eq!(keys, expected);
        assert_eq!((&s["status"], &s["output_points"], &s["warnings"]), (&json!("failed"), &json!(0), &json!([])));
    }
}
