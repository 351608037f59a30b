//! Design sensitivities of a static equilibrium (and of the one a modes analysis is about):
//! docs/sensitivities.md, "Static equilibrium".
//!
//! At an equilibrium `(q, lambda)` of `R(q, lambda; p) = [Q(q; p) - Phi_q^T lambda; Phi(q; p)]
//! = 0`, the derivative with respect to a parameter `p` solves the Newton matrix's system at
//! convergence (the tangent stiffness `K = -d(Q - Phi_q^T lambda)/dq` of the static solver):
//!
//! ```text
//! [ -K     -Phi_q^T ] [ q_p      ]     [ Q_p - (Phi_q^T lambda)_p ]
//! [ Phi_q   0       ] [ lambda_p ] = - [ Phi_p                    ]
//! ```
//!
//! with the partial derivatives at fixed `q` and `lambda`: `Q_p` from
//! [`Dae::add_load_along`] (gravity through the masses and gravity, each force through its
//! numbers and the parameters), `Phi_p` the position level of a kinematic sensitivity (the
//! [`Dual`] part along the parameter), and `(Phi_q^T lambda)_p` the mixed part of `lambda^T Phi`
//! over [`HyperDual`](crate::expr::HyperDual) numbers seeded with a unit coordinate in one direction and the parameter
//! in the other, one evaluation of an element per column it touches. The reactions follow from
//! the same evaluations with the coordinates moving along `q_p` and the multipliers along
//! `lambda_p`.

use super::inverse::anchor_point;
use super::{by_column, hessians, level, unsupported, Sensitivity};
use crate::analysis::dynamic::Dae;
use crate::analysis::measure_reactions;
use crate::analysis::statics::newton_matrix;
use crate::constraints::{lever, reaction_about};
use crate::error::Error;
use crate::expr::{Dual, Scalar};
use crate::linalg::dense::min_norm_solve_columns;
use crate::model::{Analysis, Model};
use crate::results::Results;
use faer::{Mat, MatRef};

/// The sensitivities of the equilibria of an analysis: its elements and parameters
/// ([`Sensitivity`]) and, at the last equilibrium solved for ([`EquilibriumSensitivity::solve`]),
/// each parameter's `q_p` and `lambda_p`.
pub(crate) struct EquilibriumSensitivity<'m> {
    pub(super) base: Sensitivity<'m>,
    /// (parameters asked) `q_p`, `(n)` each.
    pub(super) dq: Vec<Vec<f64>>,
    /// (parameters asked) `lambda_p`, `(m)` each.
    pub(super) dlambda: Vec<Vec<f64>>,
    /// The analysis's drivers (indices into the model's), for the measures' reactions row.
    drivers: Vec<usize>,
}

impl<'m> EquilibriumSensitivity<'m> {
    /// The sensitivities of the equilibria of `analysis` of `model` (equations `dae`) with
    /// respect to the parameters `asked` (indices, file order), checked at the guess `(q, t)`:
    /// an element, measure or force with no derivatives yet is an error naming it.
    pub(crate) fn new(
        model: &'m Model,
        analysis: &Analysis,
        asked: &[usize],
        dae: &Dae<'m>,
        q: &[f64],
        t: f64,
    ) -> Result<EquilibriumSensitivity<'m>, Error> {
        let base = Sensitivity::new(model, analysis, asked)?;
        let zero = vec![0.0; q.len()];
        let mut load = zero.clone();
        for &p in asked {
            dae.add_load_along(q, &zero, t, &zero, &zero, p, &mut load)
                .map_err(|name| unsupported_force(model, &name))?;
            let potential = |name: String| unsupported(format!("forces.{name}"), "this force's potential energy");
            dae.potential_energy_along(q, &zero, p).map_err(potential)?;
        }
        Ok(EquilibriumSensitivity { base, dq: Vec::new(), dlambda: Vec::new(), drivers: analysis.drivers.clone() })
    }

    /// The geometric stiffness `d(Phi_q^T lambda)/dq` at `(q, lambda, t)`, `(n x n)`, exact: the
    /// Hessian of `lambda^T Phi` ([`hessians`]: each element's rows over hyper-dual numbers seeded
    /// with two unit coordinates of its columns; the static solver's Newton matrix takes a central
    /// difference of `Phi_q` instead, `crate::analysis::statics::geometric_stiffness`).
    pub(crate) fn geometric_stiffness(&mut self, q: &[f64], lambda: &[f64], t: f64) -> Mat<f64> {
        let (model, b) = (self.base.model, &mut self.base.velocity);
        let elements = &self.base.elements;
        let mut h = Mat::zeros(q.len(), q.len());
        hessians(b, elements, model, t, q, &[lambda], |k, c, d, [value, _]| {
            let columns = elements[k].constraint.columns();
            let (i, j) = (columns[c], columns[d]);
            h[(i, j)] += value;
            if c != d {
                h[(j, i)] += value;
            }
        });
        h
    }

    /// `q_p` and `lambda_p` of every parameter asked at the equilibrium `(q, lambda)` at `t`,
    /// with `k` the tangent stiffness there (with the exact
    /// [`EquilibriumSensitivity::geometric_stiffness`]) and `jac = Phi_q`: one minimum-norm solve
    /// (SVD) of the Newton matrix for all the parameters, as the static solver's Newton step
    /// (redundant rows and their multipliers as it treats them).
    pub(crate) fn solve(
        &mut self,
        dae: &Dae<'_>,
        (k, jac): (MatRef<'_, f64>, MatRef<'_, f64>),
        q: &[f64],
        lambda: &[f64],
        t: f64,
    ) -> Result<(), Error> {
        let (m, n) = (jac.nrows(), jac.ncols());
        let mut big = Mat::zeros(n + m, n + m);
        newton_matrix(k, jac, big.as_mut());
        let b = &mut self.base;
        let (zero, all) = (vec![0.0; n], (0..m).collect::<Vec<usize>>());
        b.dq.iter_mut().for_each(|d| d.fill(0.0));
        let mut rhs = Mat::zeros(n + m, b.asked.len());
        let (mut force, mut phi) = (vec![0.0; n], vec![0.0; m]);
        for (j, &p) in b.asked.iter().enumerate() {
            force.fill(0.0);
            dae.add_load_along(q, &zero, t, &zero, &zero, p, &mut force)
                .map_err(|name| unsupported_force(b.model, &name))?;
            by_column(&mut b.velocity, b.elements.iter().enumerate(), b.model, p, t, (q, &zero), |_, e, c, rows| {
                let mixed: f64 = rows.iter().zip(&lambda[e.row..]).map(|(r, l)| r.e12 * l).sum();
                force[e.constraint.columns()[c]] -= mixed;
            });
            // `level` gives `-Phi_p` (the coordinates' derivatives zero).
            level(&mut b.position, &b.elements, b.model, p, t, (q, &zero, &zero), &b.dq, &all, &mut phi);
            (0..n).for_each(|i| rhs[(i, j)] = -force[i]);
            (0..m).for_each(|r| rhs[(n + r, j)] = phi[r]);
        }
        let x = min_norm_solve_columns(big.as_ref(), rhs.as_ref()).ok_or_else(|| Error::Singular {
            time: t,
            rows: vec![],
            detail:
                "the SVD of the equilibrium's Newton matrix failed (a non-finite entry) in its design sensitivities"
                    .into(),
        })?;
        let count = b.asked.len();
        self.dq = (0..count).map(|j| (0..n).map(|i| x[(i, j)]).collect()).collect();
        self.dlambda = (0..count).map(|j| (0..m).map(|r| x[(n + r, j)]).collect()).collect();
        Ok(())
    }

    /// The derivatives of the row just pushed at the equilibrium `(q, lambda)` at `t` (after
    /// [`EquilibriumSensitivity::solve`] there), pushed into `results`: each body's columns
    /// (the velocities and accelerations zero), then with `react` (a static analysis: its
    /// reactions row, [`Dae::reactions`]) each joint's reaction, each driver's effort, each
    /// joint's friction and the potential energy, then the measures.
    pub(crate) fn push(
        &mut self,
        results: &mut Results,
        dae: &Dae<'_>,
        (q, lambda, t): (&[f64], &[f64], f64),
        react: Option<&[f64]>,
    ) -> Result<(), Error> {
        let n = q.len();
        let zero = vec![0.0; n];
        for j in 0..self.base.asked.len() {
            let p = self.base.asked[j];
            let mut row: Vec<f64> =
                (0..n / 3).flat_map(|b| [&self.dq[j][3 * b..3 * b + 3], &zero[..3], &zero[..3]].concat()).collect();
            let mut reactions = Vec::new();
            if let Some(react) = react {
                let derivatives = self.reactions(q, lambda, t, j);
                row.extend_from_slice(&derivatives);
                // Each joint's friction: none at rest (`tanh(0) = 0`), and with the velocities'
                // derivatives zero none along any parameter.
                row.extend(self.base.model.joints.iter().filter(|j| j.friction.is_some()).map(|_| 0.0));
                let potential = dae.potential_energy_along(q, &self.dq[j], p);
                row.push(
                    potential.map_err(|name| unsupported(format!("forces.{name}"), "this force's potential energy"))?,
                );
                let (mut values, mut along) = (Vec::new(), Vec::new());
                measure_reactions(self.base.model, &self.drivers, react, &mut values);
                measure_reactions(self.base.model, &self.drivers, &derivatives, &mut along);
                reactions = values.iter().zip(&along).map(|(&v, &d)| Dual::new(v, d)).collect();
            }
            self.base.dq[0].copy_from_slice(&self.dq[j]);
            self.base.dq[1].fill(0.0);
            self.base.dq[2].fill(0.0);
            self.base.measures(p, t, (q, &zero, &zero), &reactions, &mut row);
            self.base.rows[j] = row;
        }
        results.push_sensitivities(t, &self.base.names, &self.base.rows)
    }

    /// The derivatives along the `j`-th parameter asked of each joint's reaction `(fx, fy,
    /// torque)` and each driver's effort ([`Dae::reactions`]) at `(q, lambda)`: the generalised
    /// reaction `-Phi_q^T lambda` on each column of a joint differentiated along `q_p`, `lambda_p`
    /// and the joint's numbers (one hyper-dual evaluation per column), the lever of its moment
    /// along the body's turn and its anchor point's gradient.
    fn reactions(&mut self, q: &[f64], lambda: &[f64], t: f64, j: usize) -> Vec<f64> {
        let b = &mut self.base;
        let p = b.asked[j];
        let (dq, dl) = (&self.dq[j], &self.dlambda[j]);
        let joints = b.model.joints.len();
        // Each joint's Jacobian block (rows x columns, row-major) along its derivative.
        let mut blocks: Vec<Vec<Dual>> = b.elements[..joints]
            .iter()
            .map(|e| vec![Dual::constant(0.0); e.constraint.rows() * e.constraint.columns().len()])
            .collect();
        by_column(&mut b.velocity, b.elements[..joints].iter().enumerate(), b.model, p, t, (q, dq), |k, e, c, rows| {
            let w = e.constraint.columns().len();
            for (r, h) in rows.iter().enumerate() {
                blocks[k][r * w + c] = Dual::new(h.e1, h.e12);
            }
        });
        let qd: Vec<Dual> = q.iter().zip(dq).map(|(&v, &d)| Dual::new(v, d)).collect();
        let mut out = Vec::with_capacity(3 * joints + b.elements.len() - joints);
        for (e, block) in b.elements.iter().zip(&blocks) {
            let rows = e.row..e.row + e.constraint.rows();
            let l: Vec<Dual> = rows.map(|r| Dual::new(lambda[r], dl[r])).collect();
            let anchor = e.constraint.anchor();
            let point = anchor_point(e, anchor.point, p);
            let columns = e.constraint.columns();
            let (f, m) = reaction_about(anchor, columns, |i| block[i], &l, lever(anchor, point, &qd));
            out.extend([f[0].d, f[1].d, m.d]);
        }
        out.extend(b.elements[joints..].iter().map(|e| -dl[e.row]));
        out
    }
}

/// The model error of the force `name` that has no derivatives with respect to its numbers yet.
pub(super) fn unsupported_force(model: &Model, name: &str) -> Error {
    let kind = model.forces.iter().find(|f| f.name == name).map_or("", |f| f.kind);
    unsupported(format!("forces.{name}"), &format!("the {kind} force"))
}
