//! Design sensitivities of joint friction in an inverse analysis (docs/sensitivities.md,
//! "Inverse dynamics"): the derivative of the multipliers that solve, with friction,
//!
//! ```text
//! Phi_q^T lambda = rhs + Q_f(q, qdot, lambda; d)
//! ```
//!
//! (`analysis/inverse.rs`, `with_friction`), and of each joint's friction. Differentiating with
//! respect to a parameter `p`,
//!
//! ```text
//! (Phi_q^T - dQ_f/dlambda) lambda_p = b_p + (Q_f)_p
//! ```
//!
//! with `b_p` the frictionless right-hand side of [`super::InverseSensitivity`] and `(Q_f)_p`
//! the friction's derivative at fixed multipliers: along `q_p` (the poses and the joint's
//! Jacobian block, with its derivative), `qdot_p` and the friction's numbers (its coefficient,
//! transition velocity, radius or block length, and a slider's line: [`crate::constraints::Friction::data`]), one
//! [`Dual`] evaluation of [`crate::constraints::Friction::load_data`] per joint. The value path solves
//! `lambda = A^+ (rhs + Q_f)`, and `Q_f` depends on `lambda` only through the friction joints'
//! rows `z`, so with `l0` the derivative the frictionless solve gives with `(Q_f)_p` in its
//! right-hand side and `W = A^+ dQ_f/dz` (one solve per friction row, the same `A^+`),
//!
//! ```text
//! lambda_p = l0 + W z_p,      (I - W[z]) z_p = l0[z]
//! ```
//!
//! a small dense system, the matrix of the value path's Newton iteration at its solution.
//! `dQ_f/dz` is [`Dae::friction_by_multipliers`], exact. Each friction's own derivative is one
//! more evaluation with the multipliers along `lambda_p`.

use crate::analysis::dynamic::Dae;
use crate::error::Error;
use crate::expr::{Dual, Scalar};
use crate::model::Model;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// The joints' friction along one parameter at one output time: the coordinates along `q_p`,
/// the velocities along `qdot_p`, the Jacobian's values along their derivatives (the elements'
/// blocks one after the other, as [`Dae`] keeps them) and the friction's numbers along their
/// gradients.
pub(super) struct FrictionAlong<'a> {
    model: &'a Model,
    p: usize,
    q: Vec<Dual>,
    qdot: (&'a [f64], &'a [f64]),
    block: (&'a [f64], &'a [f64]),
}

impl<'a> FrictionAlong<'a> {
    /// Along parameter `p` of `model`: `(q, q_p)`, `(qdot, qdot_p)`, and the Jacobian's values
    /// with their derivatives.
    pub(super) fn new(
        model: &'a Model,
        p: usize,
        (q, dq): (&[f64], &[f64]),
        qdot: (&'a [f64], &'a [f64]),
        block: (&'a [f64], &'a [f64]),
    ) -> FrictionAlong<'a> {
        let q = q.iter().zip(dq).map(|(&v, &d)| Dual::new(v, d)).collect();
        FrictionAlong { model, p, q, qdot, block }
    }

    /// `f(columns, Q_f, value)` for each joint with friction (the model's order), over [`Dual`]
    /// numbers: the multipliers `lambda` along `dlambda` (held where `None`), everything else
    /// along the parameter.
    fn each(&self, dae: &Dae<'_>, lambda: &[f64], dlambda: Option<&[f64]>, mut f: impl FnMut(&[usize], &[Dual], Dual)) {
        let grads = &self.model.gradients.friction;
        let joints = self.model.joints.iter().zip(grads).filter(|(j, _)| j.friction.is_some());
        let ((qdot, dv), (values, derivatives)) = (self.qdot, self.block);
        let mut out = Vec::new();
        for ((friction, rows, block, columns), (_, grads)) in dae.friction_joints().zip(joints) {
            let data: Vec<Dual> =
                friction.data().iter().zip(grads).map(|(&(_, v), g)| Dual::new(v, g[self.p])).collect();
            let v: Vec<Dual> = columns.iter().map(|&c| Dual::new(qdot[c], dv[c])).collect();
            let l: Vec<Dual> = rows.map(|r| Dual::new(lambda[r], dlambda.map_or(0.0, |d| d[r]))).collect();
            out.clear();
            out.resize(columns.len(), Dual::constant(0.0));
            let at = |k: usize| Dual::new(values[block.start + k], derivatives[block.start + k]);
            let value = friction.load_data(&self.q, columns, at, &v, &l, &data, &mut out);
            f(columns, &out, value);
        }
    }

    /// `out (n) += (Q_f)_p`: the friction's derivative at the multipliers `lambda` held.
    pub(super) fn add_held(&self, dae: &Dae<'_>, lambda: &[f64], out: &mut [f64]) {
        self.each(dae, lambda, None, |columns, load, _| {
            for (&c, f) in columns.iter().zip(load) {
                out[c] += f.d;
            }
        });
    }

    /// `dlambda (m)`, given as `l0` (the solve of the right-hand side with [`FrictionAlong::add_held`]
    /// in it), made `lambda_p`: `l0 + W z_p` with `(I - W[z]) z_p = l0[z]`, `W = A^+ dQ_f/dz`
    /// at `(q, qdot, lambda)` (positions as at the last [`Dae::positions`]), `transpose_solve`
    /// the analysis's `A^+`.
    pub(super) fn through_multipliers(
        dae: &Dae<'_>,
        (q, qdot, lambda): (&[f64], &[f64], &[f64]),
        dlambda: &mut [f64],
        mut transpose_solve: impl FnMut(&[f64]) -> Result<Vec<f64>, Error>,
    ) -> Result<(), Error> {
        let n = dae.n;
        let (rows, _) = dae.friction_support();
        let mut by = vec![0.0; n * rows.len()];
        dae.friction_by_multipliers(q, qdot, lambda, &rows, &mut by);
        let w = by.chunks_exact(n).map(&mut transpose_solve).collect::<Result<Vec<_>, _>>()?;
        let matrix = Mat::<f64>::from_fn(rows.len(), rows.len(), |i, k| f64::from(u8::from(i == k)) - w[k][rows[i]]);
        let z = matrix.partial_piv_lu().solve(Mat::<f64>::from_fn(rows.len(), 1, |i, _| dlambda[rows[i]]));
        for (k, wk) in w.iter().enumerate() {
            dlambda.iter_mut().zip(wk).for_each(|(l, x)| *l += x * z[(k, 0)]);
        }
        Ok(())
    }

    /// Each joint's friction's derivative (the `<joint>.friction` columns, the model's order),
    /// the multipliers along `dlambda`, appended to `out`.
    pub(super) fn values(&self, dae: &Dae<'_>, lambda: &[f64], dlambda: &[f64], out: &mut Vec<f64>) {
        self.each(dae, lambda, Some(dlambda), |_, _, value| out.push(value.d));
    }
}
