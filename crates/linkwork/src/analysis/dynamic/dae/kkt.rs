//! The scaled Newton (KKT) matrix `K(c_v, c_q)` of the module docs: its pattern, filling,
//! factors and solves, the projection matrix of the stabilised index-2 formulation, and the
//! accelerations and multipliers of a state.

use super::Dae;
use crate::error::Error;
use crate::linalg::{FactorError, Pattern, SparseLu};

/// The scaled Newton matrix: pattern, position maps and factors.
#[derive(Debug)]
pub(super) struct Kkt {
    pub(super) lu: SparseLu,
    /// (n + m) value position of each diagonal entry.
    diag: Vec<usize>,
    /// (Jacobian entries) value positions of `Phi_q[r, c]` (row `n + r`) and of its transpose.
    pub(super) jac: Vec<(usize, usize)>,
    /// (forces) value positions of each force's `(w x w)` block, row-major.
    pub(super) forces: Vec<Vec<usize>>,
}

impl Kkt {
    pub(super) fn new(
        n: usize,
        m: usize,
        entries: &[(usize, usize)],
        force_cols: &[&[usize]],
    ) -> Result<Kkt, FactorError> {
        let dim = n + m;
        // `(row, column)` of every structural entry, in this order: the diagonal, each entry of
        // `Phi_q` (row `n + r`) and its transpose, each force's block row by row.
        let diag = (0..dim).map(|k| (k, k));
        let jac = entries.iter().flat_map(|&(r, c)| [(n + r, c), (c, n + r)]);
        let forces =
            force_cols.iter().flat_map(|cols| cols.iter().flat_map(move |&r| cols.iter().map(move |&c| (r, c))));
        let pattern = Pattern::new(dim, dim, diag.chain(jac).chain(forces).map(Some));
        let (diag, rest) = pattern.map.split_at(dim);
        let (jac, mut rest) = rest.split_at(2 * entries.len());
        let jac = jac.chunks(2).map(|p| (p[0], p[1])).collect();
        let forces = force_cols
            .iter()
            .map(|cols| {
                let (block, tail) = rest.split_at(cols.len() * cols.len());
                rest = tail;
                block.to_vec()
            })
            .collect();
        let diag = diag.to_vec();
        let lu = SparseLu::new(pattern)?;
        Ok(Kkt { lu, diag, jac, forces })
    }

    /// Set the values to `[M, Phi_q^T; Phi_q, -eps I]`.
    fn fill(&mut self, mass: &[f64], eps: f64, jac: &[f64]) {
        let n = mass.len();
        let (_, values) = self.lu.pattern_and_values();
        values.fill(0.0);
        for (k, &p) in self.diag.iter().enumerate() {
            values[p] = if k < n { mass[k] } else { -eps };
        }
        for (&(lower, upper), &v) in self.jac.iter().zip(jac) {
            values[lower] += v;
            values[upper] += v;
        }
    }
}

impl Dae<'_> {
    /// Fill and factorise `K(c_v, c_q)` at `(q, qdot, t)`, with `Phi_q` from the last
    /// [`Dae::positions`] (which must be at `q`). With joint friction `Q_f(q, qdot, lambda)` the
    /// matrix is that of the residual with friction: `Phi_q^T - dQ_f/dlambda` in the upper right
    /// block and `-c_v dQ_f/dqdot` beside the forces' (the multiplier derivative is the same in
    /// every integrator's scaling, as `Phi_q^T` is; `dQ_f/dq` is left out as `(Phi_q^T lambda)_q`
    /// is, see the module docs). `lambda = multipliers / per`: the multipliers of the iterate.
    #[allow(clippy::too_many_arguments)]
    pub fn factor(
        &mut self,
        q: &[f64],
        qdot: &[f64],
        t: f64,
        c_v: f64,
        c_q: f64,
        multipliers: &[f64],
        per: f64,
    ) -> Result<(), FactorError> {
        self.stats.jacobian_evaluations += 1;
        self.kkt.fill(&self.mass, self.eps, &self.jac);
        if c_v != 0.0 || c_q != 0.0 {
            for k in 0..self.forces.len() {
                let w = self.force_derivatives(k, q, qdot, t);
                let (_, values) = self.kkt.lu.pattern_and_values();
                let (dx, dv) = (&self.work.fdx[..w * w], &self.work.fdv[..w * w]);
                for ((&p, &a), &b) in self.kkt.forces[k].iter().zip(dx).zip(dv) {
                    values[p] -= c_q * a + c_v * b;
                }
            }
        }
        for (k, slot) in self.friction.iter().enumerate() {
            let (w, rows) = (slot.columns.len(), slot.rows.len());
            let (by_l, by_v) = self.slot_derivatives(k, q, qdot, multipliers, per);
            let (_, values) = self.kkt.lu.pattern_and_values();
            // The block's entry (r, c) is Phi_q[r, c]; its transpose sits at (c, n + r).
            for (e, &(_, upper)) in self.kkt.jac[slot.block.clone()].iter().enumerate() {
                let (r, c) = (e / w, e % w);
                values[upper] -= by_l[c * rows + r];
            }
            for (&p, &b) in self.kkt.forces[self.forces.len() + k].iter().zip(&by_v[..w * w]) {
                values[p] -= c_v * b;
            }
        }
        self.stats.factorizations += 1;
        self.kkt.lu.factor()
    }

    /// Factorise `[M, Phi_q^T; Phi_q, -eps I]` (the mass-orthogonal projection of the stabilised
    /// index-2 formulation), a second matrix beside the Newton matrix, with `Phi_q` from the last
    /// [`Dae::positions`].
    pub fn factor_mass(&mut self) -> Result<(), FactorError> {
        let mut kkt = match self.kkt_mass.take() {
            Some(k) => k,
            None => Kkt::new(self.n, self.m, &self.entries, &[])?,
        };
        kkt.fill(&self.mass, self.eps, &self.jac);
        self.stats.factorizations += 1;
        let result = kkt.lu.factor();
        self.kkt_mass = Some(kkt);
        result
    }

    /// Solve with the last [`Dae::factor_mass`], in place, `rhs: (n + m)`.
    pub fn solve_mass(&mut self, rhs: &mut [f64]) {
        if let Some(kkt) = self.kkt_mass.as_mut() {
            kkt.lu.solve(rhs);
        }
    }

    /// Solve with the last factorization, in place, `rhs: (n + m)`.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        self.kkt.lu.solve(rhs);
    }

    /// 1-norm condition estimate of the last factorization.
    pub fn condition(&mut self) -> f64 {
        self.kkt.lu.condition_estimate()
    }

    /// `(q, qdot, t) => (qddot, lambda)` from `[M, Phi_q^T; Phi_q, 0] [qddot; lambda] = [Q; gamma]`,
    /// `out: (n + m)`, with two steps of iterative refinement that remove the regularisation's
    /// effect. Evaluates positions at `q` and factorises.
    ///
    /// With joint friction `Q` holds `Q_f(lambda)`, and the system is nonlinear (through the
    /// reactions' magnitudes): Newton's method from `lambda = 0`, the matrix refreshed at each
    /// iterate ([`Dae::factor`]), until the multipliers change by less than `FRICTION_RTOL` of the
    /// largest (`Dae::friction_change`); [`Error::Friction`] naming the joint whose friction
    /// still changed most after `NEWTON_FRICTION_ITERATIONS`.
    pub fn accelerations(&mut self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) -> Result<(), Error> {
        self.positions(q, t);
        out.fill(0.0);
        let mut r = std::mem::take(&mut self.rhs);
        let outcome = if self.friction.is_empty() {
            self.refine(q, qdot, t, out, &mut r)
        } else {
            self.friction_newton(q, qdot, t, out, &mut r)
        };
        self.rhs = r;
        outcome
    }

    /// The frictionless [`Dae::accelerations`]: one factorization, three solves.
    fn refine(&mut self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64], r: &mut [f64]) -> Result<(), Error> {
        self.factor(q, qdot, t, 0.0, 0.0, &[], 1.0).map_err(|e| super::super::factor_error(e, t))?;
        for _ in 0..3 {
            self.residual(q, qdot, t, out, r);
            self.solve(r);
            for (o, d) in out.iter_mut().zip(r.iter()) {
                *o += d;
            }
        }
        Ok(())
    }

    /// `out (n + m) = [Q + Q_f - M qddot - Phi_q^T lambda; gamma - Phi_q qddot]` for
    /// `sol = [qddot; lambda]`, positions as at the last [`Dae::positions`].
    pub fn residual(&mut self, q: &[f64], qdot: &[f64], t: f64, sol: &[f64], out: &mut [f64]) {
        let n = self.n;
        let (a, l) = sol.split_at(n);
        let (f, g) = out.split_at_mut(n);
        self.load(q, qdot, t, f);
        self.add_friction(q, qdot, l, 1.0, f, None);
        for k in 0..n {
            f[k] -= self.mass[k] * a[k];
        }
        for (&(r, c), &v) in self.entries.iter().zip(&self.jac) {
            f[c] -= v * l[r];
        }
        self.gamma(q, qdot, t, g);
        for (&(r, c), &v) in self.entries.iter().zip(&self.jac) {
            g[r] -= v * a[c];
        }
    }
}
