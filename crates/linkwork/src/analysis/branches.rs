//! Assembly on the branch the designer means, and the part of the mechanism to blame at a
//! singular position.
//!
//! Each dyad ([`crate::model::structure`]) is kept on its target side of the line `E -> D`: the
//! side declared in `branches:`, else the side the drawing (the initial guess) puts it on. A dyad
//! that Newton assembled on the other side is reflected in its line and assembled again from
//! there; one that still cannot be put on its side is an assembly error naming it.
//!
//! At a singular position the driven Jacobian, with rows and columns in the order of the groups,
//! is block lower-triangular: it is singular exactly when the square block of one group is. The
//! group whose block has the smallest ratio of singular values is the one that locks.

use super::assembly::assemble_or_best;
use super::{assemble, Assembly, Start, SINGULAR_RATIO_KINEMATIC};
use crate::constraints::ConfigBuf;
use crate::error::{Error, Result, RowName};
use crate::linalg::dense::{equilibrated, smallest_singular};
use crate::model::spec::{BranchMode, Side};
use crate::model::structure::{self, side_name, Branch, Dyad};
use crate::model::{Analysis, Model};
use crate::results::Summary;
use crate::system::System;
use faer::Mat;

/// Assemble as [`assemble`] does, then keep every dyad of the `drivers`' groups on its target
/// side. Returns the assembly, each dyad's [`Branch`], and the warnings: a declared side the
/// drawing disagrees with, a dyad left on the other side of its drawing. With `branch: strict`
/// each of these is an [`Error::Branch`] instead.
pub fn assemble_on_branches(
    model: &Model,
    drivers: &[usize],
    sys: &mut System<'_>,
    start: &Start<'_>,
) -> Result<(Assembly, Vec<Branch>, Vec<String>)> {
    let (q0, t) = (start.q, start.t);
    let dyads = structure::dyads(model, drivers);
    let strict = model.branch_mode == BranchMode::Strict;
    let mut warnings = Vec::new();
    for (dyad, declared) in &dyads {
        let (Some(want), Some(drawn)) = (declared, dyad.drawn_side(q0)) else { continue };
        if *want != drawn {
            let [e, f, d] = dyad.names(model);
            let what = format!(
                "branches.{f}: the drawing puts joint {f} {} of the line {e} -> {d}, and the file declares {}",
                drawn.name(),
                want.name()
            );
            if strict {
                return Err(Error::Branch {
                    time: t,
                    joint: f.to_string(),
                    detail: format!("{what} (branch: strict)"),
                });
            }
            warnings.push(format!("{what}: assembled on the declared side"));
        }
    }
    let target: Vec<Option<Side>> = dyads.iter().map(|(d, declared)| declared.or_else(|| d.drawn_side(q0))).collect();
    let mut assembly = match assemble_or_best(sys, start).map_err(|stopped| *stopped) {
        Ok(a) => a,
        Err((Error::Assembly { time, iterations, residual, row, hint }, best, assembled)) => {
            // Positions that hold at a singular position whose velocities cannot: a start at a
            // dead centre, not drivers that conflict.
            if let Some(e) = assembled.then(|| singular_start(model, drivers, sys, &best, t)).flatten() {
                return Err(e);
            }
            let hint = match cannot_close(model, drivers, &best) {
                Some(why) => format!("{why}; {hint}"),
                None => hint,
            };
            return Err(Error::Assembly { time, iterations, residual, row, hint });
        }
        Err((e, _, _)) => return Err(e),
    };
    // Each round reflects every dyad off its side; a reflection can only disturb the dyads placed
    // after it, so one round per dyad is enough.
    for _ in 0..dyads.len() {
        let off: Vec<&Dyad> = dyads
            .iter()
            .zip(&target)
            .filter(|((d, _), want)| want.is_some() && d.side(&assembly.q) != **want)
            .map(|((d, _), _)| d)
            .collect();
        if off.is_empty() {
            break;
        }
        let mut reflected = assembly.q.clone();
        for dyad in &off {
            reflected = dyad.reflected(&reflected);
        }
        let Ok(again) = assemble(sys, &Start { q: &reflected, ..*start }) else { break };
        assembly = again;
    }
    assembly.change = assembly.q.iter().zip(q0).map(|(a, b)| a - b).collect();
    for ((dyad, declared), want) in dyads.iter().zip(&target) {
        let Some(want) = want else { continue };
        let got = dyad.side(&assembly.q);
        if got == Some(*want) {
            continue;
        }
        let [e, f, d] = dyad.names(model);
        let [b1, b2] = dyad.bodies.map(|b| model.bodies[b].name.as_str());
        let whose = if declared.is_some() { "declared" } else { "drawn" };
        let what = format!(
            "the dyad of joint {f} (bodies {b1} and {b2}) cannot be assembled with {f} {} of the line {e} -> {d} ({whose}); it assembles {}",
            want.name(),
            side_name(got)
        );
        if declared.is_some() || strict {
            return Err(Error::Branch { time: t, joint: f.to_string(), detail: what });
        }
        warnings.push(what);
    }
    let branches = dyads.iter().map(|(d, declared)| Branch::of(model, d, *declared, q0, &assembly.q)).collect();
    Ok((assembly, branches, warnings))
}

/// Relative margin by which `|ED|` must pass a dyad's reach (`|EF| + |FD|`, or `||EF| - |FD||`)
/// at Newton's best positions for the dyad to be named as unable to close: least squares leaves
/// the stretched dyad just past its reach, by far more than round-off and far less than this.
const REACH_MARGIN: f64 = 1e-6;

/// The first dyad, in the order of the groups, whose end pins are out of its reach at the
/// positions `q` where assembly stopped: `cannot close: ...` in words.
fn cannot_close(model: &Model, drivers: &[usize], q: &[f64]) -> Option<String> {
    structure::groups(model, drivers).iter().filter_map(|g| g.dyad.as_ref()).find_map(|dyad| {
        let [e, f, d] = dyad.names(model);
        let [b1, b2] = dyad.bodies.map(|b| model.bodies[b].name.as_str());
        let [l1, l2, ed] = dyad.lengths(q);
        let (sum, diff) = (l1 + l2, (l1 - l2).abs());
        let show = |x: f64| model.display.show("length", x);
        if ed > sum * (1.0 + REACH_MARGIN) {
            Some(format!(
                "cannot close: the dyad {e}-{f}-{d} (links {b1} and {b2}) is too short, |{e}{d}| = {} > |{e}{f}| + |{f}{d}| = {} + {} = {}",
                show(ed),
                show(l1),
                show(l2),
                show(sum)
            ))
        } else if ed < diff * (1.0 - REACH_MARGIN) {
            Some(format!(
                "cannot close: the dyad {e}-{f}-{d} (links {b1} and {b2}) cannot fold so far, |{e}{d}| = {} < ||{e}{f}| - |{f}{d}|| = {}",
                show(ed),
                show(diff)
            ))
        } else {
            None
        }
    })
}

/// Assemble the model's guess at time `t` as [`assemble_on_branches`] does, with `analysis`'s
/// drivers and tolerance, and every dyad's branch and the warnings written into `summary`.
pub(crate) fn assemble_into(
    model: &Model,
    analysis: &Analysis,
    sys: &mut System<'_>,
    given: &[bool],
    t: f64,
    summary: &mut Summary,
) -> Result<Assembly> {
    let tolerance = analysis.settings.tolerance;
    let start = Start { q: &model.q0(), qdot: &model.qdot0(), given, t, tolerance };
    let (assembly, branches, mut warnings) = assemble_on_branches(model, &analysis.drivers, sys, &start)?;
    summary.branches = Some(branches);
    summary.warnings.append(&mut warnings);
    Ok(assembly)
}

/// The group of `sys`'s mechanism (joints and the active `drivers`) that is singular at `q`: its
/// rows, and what it is in words (for a dyad, its links' lengths against `|ED|`). `None` when the
/// structure is not known (a model too large, a single group) or no group's block is singular
/// to `ratio` (the ratio of singular values below which the whole is singular).
pub fn blame(
    model: &Model,
    drivers: &[usize],
    sys: &mut System<'_>,
    q: &[f64],
    t: f64,
) -> Option<(Vec<RowName>, String)> {
    let groups = structure::groups(model, drivers);
    if groups.len() < 2 || groups.iter().any(|g| g.free > 0) {
        return None;
    }
    let jac = {
        let mut jac = Mat::zeros(sys.m, sys.n);
        sys.jacobian_dense(&ConfigBuf::new(q).view(), t, jac.as_mut());
        jac
    };
    // Each element's rows in `sys`: joints first, then the active drivers in their order.
    let joints = model.joints.len();
    let rows_of = |element: usize| -> Vec<usize> {
        let position = if element < joints {
            element
        } else {
            joints + drivers.iter().position(|&d| joints + d == element).unwrap_or(usize::MAX - joints)
        };
        sys.elements().nth(position).map(|(_, r)| r.collect()).unwrap_or_default()
    };
    let (mut worst, mut worst_ratio) = (None, f64::INFINITY);
    for g in &groups {
        let rows: Vec<usize> = g.elements.iter().flat_map(|&e| rows_of(e)).collect();
        let cols: Vec<usize> = g.bodies.iter().flat_map(|&b| 3 * b..3 * b + 3).collect();
        let block = Mat::from_fn(rows.len(), cols.len(), |i, j| jac[(rows[i], cols[j])]);
        // Scaled as the whole's ratio is (`super::scaled_row_space`), so that the two compare.
        let block = equilibrated(block.as_ref(), &super::column_scales(sys, cols.iter().copied()));
        let (ratio, local) = smallest_singular(block.as_ref());
        if ratio < worst_ratio {
            worst_ratio = ratio;
            worst = Some((g, local.into_iter().map(|i| sys.row_name(rows[i])).collect::<Vec<_>>()));
        }
    }
    // Only a block singular as the whole is: otherwise the structure does not explain it.
    let (group, rows) = worst.filter(|_| worst_ratio < SINGULAR_RATIO_KINEMATIC)?;
    let bodies: Vec<&str> = group.bodies.iter().map(|&b| model.bodies[b].name.as_str()).collect();
    let words = match &group.dyad {
        Some(dyad) => {
            let [e, f, d] = dyad.names(model);
            format!("in the dyad {e}-{f}-{d} (bodies {}): {}", bodies.join(", "), dyad.toggle(model, q))
        }
        None => {
            let mut names: Vec<&str> = rows.iter().map(|r| r.element.as_str()).collect();
            names.dedup();
            format!(
                "in the group of bodies {} (joints {}): its own Jacobian's smallest/largest singular value is {worst_ratio:.3e}",
                bodies.join(", "),
                names.join(", ")
            )
        }
    };
    Some((rows, words))
}

/// A fully driven start (as many equations as coordinates, or more) at a singular position of
/// the group that [`blame`] names: an [`Error::Singular`] at `t` saying so, where the rank alone
/// would say a driver is missing or two drivers conflict. `None` when no group is singular.
pub(crate) fn singular_start(
    model: &Model,
    drivers: &[usize],
    sys: &mut System<'_>,
    q: &[f64],
    t: f64,
) -> Option<Error> {
    if sys.m < sys.n {
        return None;
    }
    let (rows, words) = blame(model, drivers, sys, q, t)?;
    Some(Error::Singular {
        time: t,
        rows,
        detail: format!(
            "the start is a dead centre or lock-up {words}: the driven Jacobian loses rank there, so the drivers \
             cannot move the mechanism from it; start the drivers from another position"
        ),
    })
}
