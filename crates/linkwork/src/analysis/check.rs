//! Checks of a mechanism: degrees of freedom from the numerical rank of `Phi_q` at the assembled
//! configuration (and Gruebler's count beside it), and the redundant rows by name.
//!
//! Rows are examined in model order (joints in file order, then drivers): a row that is a linear
//! combination of the rows before it is redundant. This names the later of two parallel links as
//! the redundant one, as a designer reading the file would.

use super::setup::{coordinate_names, held, unmet_freedom};
use super::{assemble_on_branches, Assembly, Start};
use crate::constraints::ConfigBuf;
use crate::error::{Result, RowName};
use crate::model::spec::AnalysisKind;
use crate::model::spec::Side;
use crate::model::structure::Branch;
use crate::model::Model;
use crate::system::System;
use indexmap::IndexMap;

/// Degrees of freedom and redundancy of one set of active constraints.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SystemCheck {
    /// Which drivers were active.
    pub drivers: Vec<String>,
    /// Number of equations `m`.
    pub equations: usize,
    /// Gruebler's count `n - m` (ignores redundancy).
    pub gruebler_dof: i64,
    /// Rank of `Phi_q` at the assembled configuration.
    pub rank: usize,
    /// Degrees of freedom `n - rank`.
    pub dof: usize,
    /// Rows that depend on earlier rows.
    pub redundant: Vec<RowName>,
    /// Joints (and drivers) whose share of a load rigid bodies do not determine: those with
    /// rows in a dependent set. Their reactions are the minimum-norm ones.
    pub indeterminate: Vec<String>,
    /// The assembled configuration.
    pub assembly: Assembly,
    /// The assembly mode of every dyad (docs/model-format.md, "Branches").
    pub branches: Vec<Branch>,
    /// What the assembly found to say: a drawing that disagrees with a declared branch.
    pub warnings: Vec<String>,
}

/// The check of one analysis: its system with the analysis's drivers, or why it could not be
/// assembled, and a warning when the analysis cannot run as set up.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AnalysisCheck {
    /// What the analysis computes.
    pub kind: AnalysisKind,
    /// The system with the analysis's drivers (absent when it could not be assembled).
    #[serde(flatten)]
    pub system: Option<SystemCheck>,
    /// Why the system could not be assembled.
    pub error: Option<String>,
    /// What stops the analysis from running, found without running it.
    pub warning: Option<String>,
}

/// Everything `linkwork check` reports.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CheckReport {
    /// Model title.
    pub model: String,
    /// Body names.
    pub bodies: Vec<String>,
    /// Number of coordinates `n = 3 bodies`.
    pub coordinates: usize,
    /// Name of each coordinate, `<body>.x`, `<body>.y`, `<body>.phi`, in the order of `q`.
    pub coordinate_names: Vec<String>,
    /// The mechanism alone (joints, no drivers).
    pub mechanism: SystemCheck,
    /// Each analysis by name, with its drivers.
    pub analyses: IndexMap<String, AnalysisCheck>,
    /// What the file placed from global coordinates, in body frames ([`Model::placed`]).
    pub placed: IndexMap<String, [f64; 2]>,
}

/// Assemble the model with the joints and the given drivers and examine its Jacobian there.
pub fn check_system(model: &Model, drivers: &[usize], hold_given: bool, t: f64) -> Result<SystemCheck> {
    let mut sys = System::new(model, drivers);
    let n = model.n();
    let given = held(model, hold_given);
    let tolerance = crate::model::SolverSettings::default().tolerance;
    let (assembly, branches, warnings) = assemble_on_branches(
        model,
        drivers,
        &mut sys,
        &Start { q: &model.q0(), qdot: &model.qdot0(), given: &given, t, tolerance },
    )?;
    let jac = sys.jacobian(&ConfigBuf::new(&assembly.q).view(), t);
    let mut rows = super::scaled_row_space(&sys, &jac, 0..n, t)?;
    let (keep, drop) = rows.independent_rows();
    Ok(SystemCheck {
        drivers: drivers.iter().map(|&d| model.drivers[d].name.clone()).collect(),
        equations: sys.m,
        gruebler_dof: n as i64 - sys.m as i64,
        rank: keep.len(),
        dof: n - keep.len(),
        redundant: drop.iter().map(|&r| sys.row_name(r)).collect(),
        indeterminate: super::element_names(&sys, &rows.dependent_rows()),
        assembly,
        branches,
        warnings,
    })
}

/// The massless motion of a dynamic analysis ([`super::massless_motion`]) at its assembled `q`.
fn massless(model: &Model, drivers: &[usize], q: &[f64], t: f64) -> Option<String> {
    let mut sys = System::new(model, drivers);
    let jac = sys.jacobian(&ConfigBuf::new(q).view(), t);
    super::massless_motion(model, &jac).map(|p| p.to_string())
}

/// Check the mechanism alone (given coordinates held) and with each analysis's drivers. Fails
/// only when the mechanism alone cannot be assembled; an analysis that cannot is reported in its
/// entry.
pub fn check(model: &Model) -> Result<CheckReport> {
    let mechanism = check_system(model, &[], true, 0.0)?;
    let analyses = model
        .analyses
        .values()
        .map(|a| {
            let hold = holds_given(a);
            // The measures it cannot compute stop it as surely as a missing driver.
            let unavailable: Vec<String> = model.unavailable_measures(a).iter().map(|p| p.to_string()).collect();
            let measures = (!unavailable.is_empty()).then(|| unavailable.join("; "));
            let entry = match check_system(model, &a.drivers, hold, a.t_start) {
                Ok(system) => {
                    let warning = match a.kind {
                        AnalysisKind::Dynamic => massless(model, &a.drivers, &system.assembly.q, a.t_start),
                        // A rank short at a dead centre is the position's fault, not the drivers'.
                        _ if system.dof > 0 => {
                            let mut sys = System::new(model, &a.drivers);
                            super::singular_start(model, &a.drivers, &mut sys, &system.assembly.q, a.t_start)
                                .map(|e| e.to_string())
                                .or_else(|| unmet_freedom(model, a, system.equations, system.rank))
                        }
                        _ => unmet_freedom(model, a, system.equations, system.rank),
                    };
                    AnalysisCheck {
                        kind: a.kind,
                        system: Some(system),
                        error: None,
                        warning: joined(warning, measures),
                    }
                }
                Err(e) => AnalysisCheck { kind: a.kind, system: None, error: Some(e.to_string()), warning: measures },
            };
            (a.name.clone(), entry)
        })
        .collect();
    Ok(CheckReport {
        model: model.name.clone(),
        bodies: model.bodies.iter().map(|b| b.name.clone()).collect(),
        coordinates: model.n(),
        coordinate_names: coordinate_names(model),
        mechanism,
        analyses,
        placed: model.placed.clone(),
    })
}

/// Whether `analysis` assembles holding the given coordinates: dynamics does, as the mechanism
/// alone does, and so does a modes analysis about the initial state.
pub(crate) fn holds_given(analysis: &crate::model::Analysis) -> bool {
    analysis.kind == AnalysisKind::Dynamic
        || (analysis.kind == AnalysisKind::Modes && analysis.about == crate::model::spec::LinearisePoint::Initial)
}

/// The branches `model`'s analysis `name` assembles on: each dyad's joints `[E, F, D]` and the
/// side it is assembled on. Empty when it cannot be assembled (the variants of a sweep then
/// keep no branch of it).
pub fn assembled_branches(model: &Model, name: &str) -> Vec<([usize; 3], Side)> {
    let Ok(analysis) = model.analysis(name) else { return Vec::new() };
    let Ok(system) = check_system(model, &analysis.drivers, holds_given(analysis), analysis.t_start) else {
        return Vec::new();
    };
    let index = |j: &str| model.joints.iter().position(|e| e.name == j);
    system
        .branches
        .iter()
        .filter_map(|b| Some(([index(&b.line[0])?, index(&b.joint)?, index(&b.line[1])?], b.side?)))
        .collect()
}

/// Both warnings of an analysis, one after the other, or the one there is.
fn joined(a: Option<String>, b: Option<String>) -> Option<String> {
    match (a, b) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    }
}
