//! Linearisation about an equilibrium (or the initial state): natural frequencies, damping
//! ratios and mode shapes.
//!
//! Small motions `dq = N z` stay on the constraints to first order when the columns of `N`
//! span the null space of `Phi_q` (an orthonormal basis from the SVD). Projecting
//! `M dqddot + C dqdot + K dq = 0` onto them gives the reduced matrices
//!
//! ```text
//! M_r = N^T M N,   C_r = N^T C N,   K_r = N^T K N,
//! K = -d(Q - Phi_q^T lambda)/dq,    C = -dQ/dqdot
//! ```
//!
//! where the term `d(Phi_q^T lambda)/dq` carries the curvature of the constraints (a
//! pendulum's stiffness `m g / L` comes from it). Without damping and with a symmetric `K_r` the
//! modes come from the symmetric-definite problem `K_r v = omega^2 M_r v` (Cholesky of `M_r`, then
//! a symmetric eigensolver): the frequencies are accurate to rounding. Otherwise from the
//! eigenvalues `s` of the first-order form `[0, I; -M_r^-1 K_r, -M_r^-1 C_r]`: a complex pair
//! `s = -zeta omega_n +- i omega_n sqrt(1 - zeta^2)` is one mode, a real `s` a non-oscillating
//! one. Shapes are `N v` in body coordinates, scaled so that the largest component is 1.
//!
//! An eigenvalue with a positive real part is no vibration: the motion grows as `e^{Re s t}`.
//! Such a mode is reported as unstable ([`ModeKind::Divergence`] when `s` is real,
//! [`ModeKind::Flutter`] when it oscillates) with its growth rate, and no natural frequency or
//! damping ratio.

use super::dynamic::{factor_error, Dae};
use super::sensitivity::{mode_derivatives, EquilibriumSensitivity};
use super::setup::{coordinate_names, fail, held, unmet_freedom};
use super::statics::{solve, Statics, ZERO_STIFFNESS};
use super::{assemble_into, element_names, independent_rows, indeterminate_rows, Run};
use crate::error::Error;
use crate::linalg::dense::equilibrated;
use crate::model::spec::LinearisePoint;
use crate::model::{Analysis, Model};
use crate::results::{Failure, Mode, ModeKind, Results};
use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;

/// Run a modes analysis.
pub(crate) fn run_modes(model: &Model, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
    let t = analysis.t_start;
    let mut dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => return Err(fail(Results::new(model, analysis), factor_error(e, t))),
    };
    let n = dae.n;
    let mut results = run.results(model, analysis);
    if let Err(e) = super::dense_size(analysis, dae.m, n) {
        return Err(fail(results, e));
    }
    results.add_columns(model.measures.iter().map(|m| m.name.clone()));
    let path = format!("analyses.{}", analysis.name);
    let equilibrium = analysis.about == LinearisePoint::Equilibrium;
    // The initial state keeps what the user gave, as dynamics does; an equilibrium moves it.
    let given = held(model, !equilibrium);
    let assembly = match assemble_into(model, analysis, &mut dae.sys, &given, t, &mut results.summary) {
        Ok(a) => a,
        Err(e) => return Err(fail(results, e)),
    };
    let mass = dae.mass.clone();
    let m = dae.m;
    let mut st = Statics::new(&mut dae, analysis.settings.tolerance, &assembly.q, t);
    let (q, qdot, lambda) = if equilibrium {
        match solve(&mut st, analysis, &assembly.q, t, true) {
            Ok(eq) => (eq.q, vec![0.0; n], eq.lambda),
            Err(e) => return Err(fail(results, e)),
        }
    } else {
        let mut sol = vec![0.0; n + m];
        if let Err(e) = st.dae.accelerations(&assembly.q, &assembly.qdot, t, &mut sol) {
            return Err(fail(results, e));
        }
        (assembly.q.clone(), assembly.qdot.clone(), sol[n..].to_vec())
    };
    let (k, c) = st.tangent(&q, &qdot, &lambda, t);
    let (kr, basis) = st.reduced(k.as_ref(), &q, t);
    let f = basis.ncols();
    if let Some(message) = unmet_freedom(model, analysis, m, n - f) {
        return Err(fail(results, Error::Model(vec![crate::Problem::new(format!("{path}.drivers"), message)])));
    }
    let m_n = Mat::from_fn(n, f, |i, j| mass[i] * basis[(i, j)]);
    let mr = basis.transpose() * &m_n;
    let cr = basis.transpose() * &c * &basis;
    let names = coordinate_names(model);
    let kscale = (0..f).flat_map(|i| (0..f).map(move |j| (i, j))).map(|(i, j)| kr[(i, j)].abs()).fold(0.0, f64::max);
    let symmetric = (0..f).all(|i| (0..i).all(|j| (kr[(i, j)] - kr[(j, i)]).abs() <= 1e-8 * kscale));
    let undamped = (0..f).all(|i| (0..f).all(|j| cr[(i, j)] == 0.0));
    let modes = if undamped && symmetric {
        undamped_modes(&mr, &kr, &basis, &names)
    } else {
        state_space_modes(&mr, &kr, &cr, &basis, &names)
    };
    let Some(mut modes) = modes else {
        let error = Error::Singular {
            time: t,
            rows: vec![],
            detail: "the eigenvalue solver failed on the reduced matrices (a non-finite entry)".into(),
        };
        return Err(fail(results, error));
    };
    // The unstable modes first, fastest growing first; then the others, lowest frequency first.
    modes.sort_by(|a, b| match (a.growth_rate, b.growth_rate) {
        (Some(x), Some(y)) => y.total_cmp(&x),
        (Some(_), None) => std::cmp::Ordering::Less,
        (None, Some(_)) => std::cmp::Ordering::Greater,
        (None, None) => a.frequency.unwrap_or(0.0).total_cmp(&b.frequency.unwrap_or(0.0)),
    });
    let stable = modes.iter().all(|m| m.growth_rate.is_none());
    let zero = vec![0.0; n];
    let extra: Vec<f64> = model.measures.iter().map(|m| m.value(&q, &qdot, &zero, &[], t)).collect();
    if let Err(e) = run.push(&mut results, t, &q, &qdot, &zero, &extra) {
        return Err(fail(results, e));
    }
    if !run.sensitivities.is_empty() {
        let mut derivatives = || {
            if !(undamped && symmetric) {
                let message = "the modes of a mechanism with damping or a non-symmetric stiffness (solved in state space) have no design sensitivities yet";
                return Err(Error::Model(vec![crate::Problem::new(path.clone(), message)]));
            }
            let mut s = EquilibriumSensitivity::new(model, analysis, &run.sensitivities, st.dae, &q, t)?;
            let (k, jac) = st.sensitivities(&mut s, &mut results, (&q, &lambda, t), None)?;
            mode_derivatives(&mut s, st.dae, (k.as_ref(), jac.as_ref()), (&q, &lambda, t), &modes, &names)
        };
        match derivatives() {
            Ok(d) => results.summary.sensitivities = Some(d),
            Err(e) => return Err(fail(results, e)),
        }
    }
    st.dae.positions(&q, t);
    let mut jac = Mat::<f64>::zeros(st.dae.m, n);
    st.dae.jacobian_dense(jac.as_mut());
    // Scaled to be free of units, as every rank test (`super::scaled_row_space`).
    let jac = equilibrated(jac.as_ref(), &super::column_scales(&st.dae.sys, 0..n));
    let s = &mut results.summary;
    s.dof = Some(f);
    s.redundant_rows = Some(independent_rows(jac.as_ref()).1.iter().map(|&r| st.dae.sys.row_name(r)).collect());
    s.about = Some(analysis.about);
    s.stable = Some(stable);
    s.modes = Some(modes);
    s.indeterminate_joints = Some(element_names(&st.dae.sys, &indeterminate_rows(jac.as_ref())));
    Ok(results)
}

/// Modes of `K_r v = omega^2 M_r v` (symmetric `K_r`, SPD `M_r`), through the Cholesky factor
/// `M_r = L L^T` and the symmetric eigenproblem of `L^-1 K_r L^-T`.
fn undamped_modes(mr: &Mat<f64>, kr: &Mat<f64>, basis: &Mat<f64>, names: &[String]) -> Option<Vec<Mode>> {
    let f = mr.nrows();
    let llt = mr.llt(faer::Side::Lower).ok()?;
    let l = llt.L().to_owned();
    let linv = l.as_ref().partial_piv_lu().inverse();
    let ks = Mat::from_fn(f, f, |i, j| 0.5 * (kr[(i, j)] + kr[(j, i)]));
    let s = &linv * &ks * linv.transpose();
    let s = Mat::from_fn(f, f, |i, j| 0.5 * (s[(i, j)] + s[(j, i)]));
    let eig = s.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (w2, u) = (eig.S().column_vector(), eig.U());
    // v = L^-T u: the modal coordinates, then N v the body coordinates.
    let v = linv.transpose() * u;
    let zero = zero_rate((0..f).map(|k| w2[k].abs().sqrt()).fold(0.0, f64::max));
    let modes = (0..f)
        .map(|k| {
            let lam: f64 = w2[k];
            let eigenvalue = if lam >= 0.0 { [0.0, lam.sqrt()] } else { [(-lam).sqrt(), 0.0] };
            let shape: Vec<f64> = (0..basis.nrows()).map(|i| (0..f).map(|j| basis[(i, j)] * v[(j, k)]).sum()).collect();
            mode(eigenvalue, &shape, &vec![0.0; shape.len()], names, zero)
        })
        .collect();
    Some(modes)
}

/// Modes from the eigenvalues of the first-order form `[0, I; -M_r^-1 K_r, -M_r^-1 C_r]`.
fn state_space_modes(
    mr: &Mat<f64>,
    kr: &Mat<f64>,
    cr: &Mat<f64>,
    basis: &Mat<f64>,
    names: &[String],
) -> Option<Vec<Mode>> {
    let f = mr.nrows();
    let minv = mr.as_ref().partial_piv_lu().inverse();
    let (a21, a22) = (-(&minv * kr), -(&minv * cr));
    let a = Mat::from_fn(2 * f, 2 * f, |i, j| match (i < f, j < f) {
        (true, true) => 0.0,
        (true, false) => f64::from(u8::from(j - f == i)),
        (false, true) => a21[(i - f, j)],
        (false, false) => a22[(i - f, j - f)],
    });
    let eig = a.eigen().ok()?;
    let (s, u) = (eig.S().column_vector(), eig.U());
    let zero = zero_rate((0..2 * f).map(|k| s[k].re.hypot(s[k].im)).fold(0.0, f64::max));
    let mut modes = Vec::new();
    for k in 0..2 * f {
        let (re, im) = (s[k].re, s[k].im);
        // One mode per complex pair (the member with Im > 0); every real eigenvalue on its own.
        if im < 0.0 && im.abs() > 1e-12 * re.hypot(im) {
            continue;
        }
        let im = if im.abs() <= 1e-12 * re.hypot(im) { 0.0 } else { im };
        let (sr, si): (Vec<f64>, Vec<f64>) = (0..basis.nrows())
            .map(|i| {
                (0..f)
                    .fold((0.0, 0.0), |(a, b), j| (a + basis[(i, j)] * u[(j, k)].re, b + basis[(i, j)] * u[(j, k)].im))
            })
            .unzip();
        modes.push(mode([re, im], &sr, &si, names, zero));
    }
    Some(modes)
}

/// The size below which a real part, or a whole eigenvalue, counts as zero, 1/s, given the
/// largest `|s|`: the square root of statics' [`ZERO_STIFFNESS`] times it, because `s` is the
/// square root of an eigenvalue of `M_r^-1 K_r`, and a stiffness counts as zero below
/// `ZERO_STIFFNESS` of the largest (about `3e-5`: an error of `1e-10` in `K_r` moves a zero `s` by
/// `1e-5` of the largest).
fn zero_rate(largest: f64) -> f64 {
    ZERO_STIFFNESS.sqrt() * largest
}

/// A [`Mode`] from its eigenvalue and complex shape `re + i im` in body coordinates; `zero`
/// from [`zero_rate`].
fn mode(eigenvalue: [f64; 2], re: &[f64], im: &[f64], names: &[String], zero: f64) -> Mode {
    let [sr, si] = eigenvalue;
    let omega = sr.hypot(si);
    let kind = match () {
        _ if omega <= zero => ModeKind::Neutral,
        _ if sr > zero && si > 0.0 => ModeKind::Flutter,
        _ if sr > zero => ModeKind::Divergence,
        _ if si > 0.0 => ModeKind::Vibration,
        _ => ModeKind::Decay,
    };
    let unstable = matches!(kind, ModeKind::Divergence | ModeKind::Flutter);
    // Turn the shape so that its largest component is real and positive, then scale it to 1.
    let big = (0..re.len()).max_by(|&a, &b| re[a].hypot(im[a]).total_cmp(&re[b].hypot(im[b]))).unwrap_or(0);
    let (br, bi) = (re[big], im[big]);
    let norm = br.hypot(bi);
    let shape = (0..re.len())
        .map(|i| {
            let v = match i {
                _ if norm == 0.0 => 0.0,
                _ if i == big => 1.0,
                _ => (re[i] * br + im[i] * bi) / (norm * norm),
            };
            (names[i].clone(), v)
        })
        .collect();
    let tau = 2.0 * std::f64::consts::PI;
    Mode {
        kind,
        frequency: match kind {
            ModeKind::Neutral => Some(0.0),
            _ if unstable => None,
            _ => Some(omega / tau),
        },
        damped_frequency: si / tau,
        // `0 - sr`, not `-sr`: an undamped mode's ratio is 0, not -0.
        damping_ratio: (matches!(kind, ModeKind::Vibration | ModeKind::Decay)).then(|| (0.0 - sr) / omega),
        growth_rate: unstable.then_some(sr),
        eigenvalue,
        shape,
    }
}
