//! What the analyses set up alike: the names of the coordinates, the output times, the initial
//! values that assembly holds, what an analysis needs of the degrees of freedom its drivers
//! leave (told by `check` before a run, and by the analysis itself when it runs), and the
//! failure that keeps the results written before it.

use crate::error::Error;
use crate::model::spec::AnalysisKind;
use crate::model::{Analysis, Model};
use crate::results::{Failure, Results};

/// The failure of a run by `error`, with the `results` written before it.
pub(crate) fn fail(results: Results, error: Error) -> Box<Failure> {
    Box::new(Failure { error, results })
}

/// The name `<body>.x`, `.y` or `.phi` of coordinate `k`.
pub(crate) fn coordinate_name(model: &Model, k: usize) -> String {
    format!("{}.{}", model.bodies[k / 3].name, ["x", "y", "phi"][k % 3])
}

/// The name of each coordinate, in the order of `q`.
pub(crate) fn coordinate_names(model: &Model) -> Vec<String> {
    (0..model.n()).map(|k| coordinate_name(model, k)).collect()
}

/// The output times of `analysis`: `t_start` and every `step` after it up to `t_end`, then
/// `t_end` itself when the last falls short of it by more than `1e-9` of a step. The same
/// margin absorbs the rounding of `(t_end - t_start) / step` (`~1e-16` of it), so that a span of
/// whole steps ends on its last step, not on a sliver after it.
pub(crate) fn output_times(analysis: &Analysis) -> Vec<f64> {
    let (t0, h) = (analysis.t_start, analysis.step);
    let count = ((analysis.t_end - t0) / h + 1e-9).floor() as usize;
    let mut times: Vec<f64> = (0..=count).map(|k| t0 + k as f64 * h).collect();
    if analysis.t_end - times[count] > 1e-9 * h {
        times.push(analysis.t_end);
    }
    times
}

/// The reactions row measures read ([`crate::model::Measure::value`]) from `react`, the result
/// columns' (each joint's `fx, fy, torque`, then each active driver's effort): every driver of
/// the model in its place, NaN for those `drivers` does not hold (a measure that reads one is
/// refused before the run, [`Model::unavailable_measures`]). Nothing when the model has no
/// measures.
pub(crate) fn measure_reactions(model: &Model, drivers: &[usize], react: &[f64], out: &mut Vec<f64>) {
    out.clear();
    if model.measures.is_empty() {
        return;
    }
    let joints = 3 * model.joints.len();
    out.extend_from_slice(&react[..joints]);
    out.resize(joints + model.drivers.len(), f64::NAN);
    for (k, &d) in drivers.iter().enumerate() {
        out[joints + d] = react[joints + k];
    }
}

/// The initial values assembly holds `(2n)`: with `hold`, each body's `given` positions, then
/// its given velocities, as the user marked them; without, none (the drivers or the equilibrium
/// place every coordinate, with the least change from the guess).
pub(crate) fn held(model: &Model, hold: bool) -> Vec<bool> {
    if !hold {
        return vec![false; 2 * model.n()];
    }
    (0..2).flat_map(|half| model.bodies.iter().flat_map(move |b| b.given[3 * half..3 * half + 3].to_vec())).collect()
}

/// What stops `analysis` from running, from the `rank` of its `equations` rows of `Phi_q`:
/// a kinematic or inverse analysis needs a fully driven model, a static one a load where degrees
/// of freedom remain, a modes analysis a degree of freedom. `None` when the count allows it.
pub(crate) fn unmet_freedom(model: &Model, analysis: &Analysis, equations: usize, rank: usize) -> Option<String> {
    let n = model.n();
    let dof = n - rank;
    let loaded = model.gravity != [0.0, 0.0] || !analysis.forces.is_empty();
    match analysis.kind {
        AnalysisKind::Kinematic | AnalysisKind::Inverse if dof > 0 => {
            // With at least as many equations as coordinates, a rank drop may also be a start at
            // a dead centre: the rank alone cannot tell the two apart, so say both.
            let or_singular = if equations >= n {
                ", unless the start position is a singular one (a dead centre or lock-up, where the Jacobian loses rank)"
            } else {
                ""
            };
            Some(format!(
                "a{} {} analysis needs a fully driven model, but {dof} degree(s) of freedom remain with these drivers ({n} coordinates, {rank} independent equations): add {dof} driver(s){or_singular}",
                if analysis.kind == AnalysisKind::Inverse { "n" } else { "" },
                analysis.kind.name(),
            ))
        }
        AnalysisKind::Static if dof > 0 && !loaded => Some(format!(
            "a static analysis needs every degree of freedom held: {dof} remain with no gravity, force or spring to hold them"
        )),
        AnalysisKind::Modes if dof == 0 => {
            Some("a modes analysis needs a degree of freedom: the joints and drivers leave none; drop a driver".into())
        }
        _ => None,
    }
}
