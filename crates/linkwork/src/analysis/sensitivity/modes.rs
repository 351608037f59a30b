//! Design sensitivities of the modes about an equilibrium: docs/sensitivities.md, "Modes".
//!
//! An undamped mode of the linearised mechanism is an eigenpair of the bordered problem in
//! body coordinates (its reduction to the null space of `Phi_q` is the problem the analysis
//! solves, `K_r v = omega^2 M_r v`, with `x = N v`):
//!
//! ```text
//! [ K - sigma M   Phi_q^T ] [ x  ]
//! [ Phi_q         0       ] [ mu ] = 0,        sigma = omega^2
//! ```
//!
//! symmetric, so the left eigenvector is the right one and
//!
//! ```text
//! sigma_p = (x^T (K_p - sigma M_p) x + 2 mu^T (Phi_q)_p x) / (x^T M x)
//! ```
//!
//! with every derivative total along the parameter: through the equilibrium's `q_p` and
//! `lambda_p` ([`EquilibriumSensitivity`]), the elements' numbers, the forces' numbers, the
//! masses and the parameters. `x^T K_p x` is `d/dp (x^T H x)` of the Hessian `H` of
//! `lambda^T Phi` (the part `e123` of `lambda^T Phi` over [`TimeTri`] numbers seeded `q + (e1 + e2) x
//! + e3 q_p`, `lambda + e3 lambda_p`) less `x^T (Q_q)_p x` ([`Dae::add_load_jacobians_along`]);
//! `mu^T (Phi_q)_p x` the mixed part of `mu^T Phi` over [`HyperDual`] numbers seeded
//! `q + e1 x + e2 q_p`; `x^T M_p x` from [`Dae::add_mass_along`]. The damping `C = -Q_qdot` is
//! zero at the mode (else the analysis solves the state-space problem, not differentiated
//! yet), but a parameter may move it: the damping ratio's derivative is then
//! `x^T C_p x / (2 omega x^T M x)`.

use super::over;
use super::statics::EquilibriumSensitivity;
use crate::analysis::dynamic::Dae;
use crate::error::Error;
use crate::expr::{HyperDual, Scalar, TimeTri};
use crate::linalg::dense::min_norm_solve;
use crate::results::{Mode, ModeKind};
use faer::MatRef;
use indexmap::IndexMap;
use std::f64::consts::PI;

/// The derivatives of each undamped mode of `modes` (the analysis's order, shapes by the
/// coordinate `names`) about the equilibrium `(q, lambda)` at `t`, with `k` the tangent
/// stiffness there and `jac = Phi_q`, with respect to each parameter of `eq` (solved there):
/// `modes.<number>.<quantity>` (number from 1, as `modes.csv`) for the frequency, the damped
/// frequency and the damping ratio of a vibration and the growth rate of a divergence, then by
/// parameter name. A neutral mode (no frequency to move) has none. `Err` names a force without
/// derivatives.
pub(crate) fn mode_derivatives(
    eq: &mut EquilibriumSensitivity<'_>,
    dae: &Dae<'_>,
    (k, jac): (MatRef<'_, f64>, MatRef<'_, f64>),
    (q, lambda, t): (&[f64], &[f64], f64),
    modes: &[Mode],
    names: &[String],
) -> Result<IndexMap<String, IndexMap<String, f64>>, Error> {
    let n = q.len();
    let zero = vec![0.0; n];
    let mut derivatives = IndexMap::new();
    for (number, mode) in modes.iter().enumerate() {
        if !matches!(mode.kind, ModeKind::Vibration | ModeKind::Divergence) {
            continue;
        }
        let x: Vec<f64> = names.iter().map(|c| mode.shape.get(c).copied().unwrap_or(0.0)).collect();
        let [re, im] = mode.eigenvalue;
        let sigma = im * im - re * re;
        let mx: Vec<f64> = x.iter().zip(&dae.mass).map(|(x, m)| x * m).collect();
        let norm = dot(&x, &mx);
        // mu: Phi_q^T mu = -(K - sigma M) x, which lies in the row space of Phi_q.
        let residual: Vec<f64> =
            (0..n).map(|i| sigma * mx[i] - (0..n).map(|j| k[(i, j)] * x[j]).sum::<f64>()).collect();
        let mu = min_norm_solve(jac.transpose(), &residual).unwrap_or_else(|| vec![f64::NAN; jac.nrows()]);
        let mut by = [(); 4].map(|_| IndexMap::new());
        for j in 0..eq.base.asked.len() {
            let (p, dq, dl) = (eq.base.asked[j], &eq.dq[j], &eq.dlambda[j]);
            let b = &mut eq.base;
            let tri = |i: usize| TimeTri::trajectory([q[i], x[i], 0.0], [dq[i], 0.0, 0.0]);
            let rows = over(&mut b.acceleration, &b.elements, b.model, p, TimeTri::constant(t), tri);
            let weight = |r: usize| TimeTri::trajectory([lambda[r], 0.0, 0.0], [dl[r], 0.0, 0.0]);
            let geometric = rows.iter().enumerate().fold(TimeTri::constant(0.0), |a, (r, &v)| a + weight(r) * v).e123;
            let hyper = |i: usize| HyperDual::new(q[i], x[i], dq[i], 0.0);
            let rows = over(&mut b.velocity, &b.elements, b.model, p, HyperDual::constant(t), hyper);
            let borders: f64 = rows.iter().zip(&mu).map(|(r, m)| r.e12 * m).sum();
            let mut along = vec![0.0; n];
            let state = (q, zero.as_slice(), t);
            dae.add_load_jacobians_along(state, (&x, &zero), dq, &zero, p, &mut along)
                .map_err(|name| super::statics::unsupported_force(b.model, &name))?;
            let stiffness = geometric - dot(&x, &along);
            along.fill(0.0);
            dae.add_load_jacobians_along(state, (&zero, &x), dq, &zero, p, &mut along)
                .map_err(|name| super::statics::unsupported_force(b.model, &name))?;
            let damping = -dot(&x, &along);
            along.fill(0.0);
            dae.add_mass_along(p, &x, &mut along);
            let mass = dot(&x, &along);
            let d_sigma = (stiffness - sigma * mass + 2.0 * borders) / norm;
            let name = &b.names[j];
            if mode.kind == ModeKind::Vibration {
                let omega = sigma.sqrt();
                let frequency = d_sigma / (2.0 * omega) / (2.0 * PI);
                by[0].insert(name.clone(), frequency);
                by[1].insert(name.clone(), frequency);
                by[2].insert(name.clone(), damping / (2.0 * omega * norm));
            } else {
                by[3].insert(name.clone(), -d_sigma / (2.0 * (-sigma).sqrt()));
            }
        }
        for (quantity, values) in ["frequency", "damped_frequency", "damping_ratio", "growth_rate"].iter().zip(by) {
            if !values.is_empty() {
                derivatives.insert(format!("modes.{}.{quantity}", number + 1), values);
            }
        }
    }
    Ok(derivatives)
}

/// `a . b`.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}
