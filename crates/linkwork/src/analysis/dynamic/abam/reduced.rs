//! The accelerations in the independent coordinates: with few of them, the equations of motion
//! projected on the motions the constraints allow, solved with the factors of the dependent
//! block ([`Split::reduced_accelerations`]), instead of the augmented system.

use super::Split;
use crate::error::Error;

/// Most independent coordinates for which an evaluation solves the accelerations in them
/// ([`Split::reduced_accelerations`]: `p + 2` solves with the factors of `B` and a `p x p`
/// Cholesky) instead of factoring the `(n + m)` augmented matrix, and the error norm is a
/// `2n x 2p` map built once an attempt ([`Split::norm`]). The reduced solve costs about `p` times
/// a solve with `B`, the augmented one a factorization of twice `B`'s order and three solves: on
/// the quick-return (`p = 1`, order 14 against 29) an evaluation's linear algebra falls from
/// about 6 to 2 us. At 8 the reduced solve's `p` solves still cost less than the factorization;
/// mechanisms of many degrees of freedom keep the augmented solve.
pub(super) const REDUCED_MAX: usize = 8;

/// Scratch of the reduced solve.
pub(super) struct ReducedSolve {
    /// (n) the load, (m) `gamma`, (r) `B^-1 gamma`, (p p) the reduced mass matrix (row-major),
    /// (p) its right-hand side and solution.
    load: Vec<f64>,
    gamma: Vec<f64>,
    particular: Vec<f64>,
    mass: Vec<f64>,
    rhs: Vec<f64>,
}

impl ReducedSolve {
    /// Empty; sized by [`ReducedSolve::resize`].
    pub(super) fn new() -> ReducedSolve {
        ReducedSolve { load: vec![], gamma: vec![], particular: vec![], mass: vec![], rhs: vec![] }
    }

    /// Sizes for `n` coordinates, `m` rows, `r` dependent and `p` independent coordinates.
    pub(super) fn resize(&mut self, n: usize, m: usize, r: usize, p: usize) {
        self.particular.resize(r, 0.0);
        self.load.resize(n, 0.0);
        self.gamma.resize(m, 0.0);
        self.mass.resize(p * p, 0.0);
        self.rhs.resize(p, 0.0);
    }
}

impl Split<'_, '_> {
    /// `sol = [qddot; lambda]` at the last evaluation `(q, v, t)`, with `B` factored at `q`:
    /// [`Split::reduced_accelerations`] when the partition allows (the multipliers only when
    /// asked: they are read from the accepted states and the output times alone), else the
    /// augmented system.
    pub(super) fn accelerations(&mut self, t: f64, multipliers: bool) -> Result<(), Error> {
        if !(self.part.reduced && self.reduced_accelerations(t, multipliers)) {
            self.dae.accelerations(&self.q, &self.v, t, &mut self.sol)?;
        }
        Ok(())
    }

    /// `sol = [qddot; lambda]` at the last evaluation `(q, v, t)` in the independent
    /// coordinates, with `B` factored at `q` (the embedding of Wehage and Haug's partition):
    /// with `S = B^-1 Phi_q[rows, I]` (`Blocks::sensitivities`, `p` solves, kept when fresh)
    /// and `w = B^-1 gamma`, the accelerations
    /// meeting the constraints are `qddot_D = w - S qddot_I`, and `Z = [I; -S]` spans the
    /// motions they allow, so `Z^T (M qddot - Q) = 0` is
    ///
    /// ```text
    /// (M_I + S^T M_D S) qddot_I = Q_I - S^T (Q_D - M_D w)        (p x p, positive definite)
    /// B^T lambda = (Q - M qddot)_D                                (the multipliers)
    /// ```
    ///
    /// The multipliers only when `multipliers` (else `sol`'s are left as they were).
    /// The same solution as the augmented system's (`Dae::accelerations`) to its regularisation
    /// `eps` (`1e-10` relative) for the rows without redundancy that this is used with. False
    /// when the reduced mass matrix is not positive definite to rounding (a coordinate with no
    /// mass): the caller solves the augmented system.
    fn reduced_accelerations(&mut self, t: f64, multipliers: bool) -> bool {
        let (n, p, r) = (self.dae.n, self.part.ind.len(), self.part.dep.len());
        if !self.blocks.sens_fresh {
            self.blocks.sensitivities(self.dae.jacobian_entries().1);
        }
        let Some(block) = self.blocks.current.as_mut() else { return false };
        self.dae.load(&self.q, &self.v, t, &mut self.reduced_work.load);
        self.dae.gamma(&self.q, &self.v, t, &mut self.reduced_work.gamma);
        let mass = &self.dae.mass;
        for (w, &row) in self.reduced_work.particular.iter_mut().zip(&self.part.rows) {
            *w = self.reduced_work.gamma[row];
        }
        block.lu.solve(&mut self.reduced_work.particular);
        // The reduced mass matrix (row-major) and right-hand side.
        for (i, &ci) in self.part.ind.iter().enumerate() {
            let si = &self.blocks.sens[i * r..(i + 1) * r];
            let mut rhs = self.reduced_work.load[ci];
            for (k, &c) in self.part.dep.iter().enumerate() {
                rhs -= si[k] * (self.reduced_work.load[c] - mass[c] * self.reduced_work.particular[k]);
            }
            self.reduced_work.rhs[i] = rhs;
            for j in 0..=i {
                let sj = &self.blocks.sens[j * r..(j + 1) * r];
                let mut mij = if i == j { mass[ci] } else { 0.0 };
                for (k, &c) in self.part.dep.iter().enumerate() {
                    mij += mass[c] * si[k] * sj[k];
                }
                self.reduced_work.mass[i * p + j] = mij;
                self.reduced_work.mass[j * p + i] = mij;
            }
        }
        if !crate::linalg::dense::cholesky_solve_small(&mut self.reduced_work.mass, p, &mut self.reduced_work.rhs) {
            return false;
        }
        let (a, lambda) = self.sol.split_at_mut(n);
        for (&c, &x) in self.part.ind.iter().zip(&self.reduced_work.rhs) {
            a[c] = x;
        }
        for (k, &c) in self.part.dep.iter().enumerate() {
            a[c] = self.reduced_work.particular[k]
                - (0..p).map(|j| self.blocks.sens[j * r + k] * self.reduced_work.rhs[j]).sum::<f64>();
        }
        if multipliers {
            // (Q - M qddot)_D, then B^T lambda_rows = it; every row is a pivot row here.
            for (x, &c) in self.reduced_work.particular.iter_mut().zip(&self.part.dep) {
                *x = self.reduced_work.load[c] - mass[c] * a[c];
            }
            block.lu.solve_transpose(&mut self.reduced_work.particular);
            for (&row, &x) in self.part.rows.iter().zip(&self.reduced_work.particular) {
                lambda[row] = x;
            }
        }
        true
    }
}
