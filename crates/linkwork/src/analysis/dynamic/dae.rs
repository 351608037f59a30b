//! The equations of motion of one dynamic analysis, evaluated into buffers allocated once:
//!
//! ```text
//! M qddot + Phi_q^T lambda = Q(q, qdot, t)      (n)   M = diag(m, m, J) per body, constant
//! Phi(q, t) = 0                                 (m)   joints and active drivers
//! ```
//!
//! and the one sparse matrix every implicit integrator factorises, the scaled Newton (KKT)
//! matrix
//!
//! ```text
//! K(c_v, c_q) = [ M - c_v Q_qdot - c_q Q_q    Phi_q^T ]     (n + m) x (n + m)
//!               [ Phi_q                       -eps I  ]
//! ```
//!
//! An integrator whose velocities and accelerations depend on the position iterate through
//! `dqdot/dq = g` and `dqddot/dq = b` writes its Newton step in the unknowns
//! `(b dq, lambda / b)`; the rows then have the sizes of `M` and of `Phi_q`, independent of the
//! step, with `c_v = g / b` and `c_q = 1 / b` (Bottasso, Bauchau and Cardona 2007; Negrut et al.
//! 2007 section 3). The term `(Phi_q^T lambda)_q` is left out of the Newton matrix: the residual
//! stays exact, so only the convergence rate changes, and it needs second derivatives of every
//! joint.
//!
//! `eps` (`EPS_REL / max mass`) is a regularisation far below the Schur complement
//! `Phi_q M^-1 Phi_q^T` of a regular position, so it changes nothing there (a Newton contraction of
//! `~1e-10`), while at a singular position (a flat N-four-bar, redundant rows) the matrix stays
//! invertible and the multipliers take the bounded, minimum-norm-like values of the augmented
//! Lagrangian method (Bayo and Ledesma 1996): the matrix is the saddle-point form of
//! `M + Phi_q^T Phi_q / eps`.

use crate::constraints::{Anchor, BodyIx, Config};
use crate::error::Error;
use crate::forces::{derivatives, potential_rate, DualWork};
use crate::linalg::{FactorError, Pattern, SparseLu};
use crate::model::{ForceElement, Model};
use crate::system::System;
use faer::MatMut;

/// Regularisation of the constraint block, relative to `1 / max mass` (see the module docs).
pub const EPS_REL: f64 = 1e-10;

/// The scaled Newton matrix: pattern, position maps and factors.
#[derive(Debug)]
struct Kkt {
    lu: SparseLu,
    /// (n + m) value position of each diagonal entry.
    diag: Vec<usize>,
    /// (Jacobian entries) value positions of `Phi_q[r, c]` (row `n + r`) and of its transpose.
    jac: Vec<(usize, usize)>,
    /// (forces) value positions of each force's `(w x w)` block, row-major.
    forces: Vec<Vec<usize>>,
}

impl Kkt {
    fn new(n: usize, m: usize, entries: &[(usize, usize)], force_cols: &[&[usize]]) -> Result<Kkt, FactorError> {
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

/// Counters of the work the linear algebra did.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct LinearStats {
    /// Evaluations of the Newton matrix (constraint Jacobian and force derivatives).
    pub jacobian_evaluations: usize,
    /// Numeric factorizations of the Newton matrix.
    pub factorizations: usize,
}

/// The equations of motion of one analysis, with every buffer they need.
#[derive(Debug)]
pub struct Dae<'m> {
    /// The model.
    pub model: &'m Model,
    /// Joints and active drivers.
    pub sys: System<'m>,
    /// Number of coordinates.
    pub n: usize,
    /// Number of constraint rows.
    pub m: usize,
    /// (n) the diagonal of `M`.
    pub mass: Vec<f64>,
    /// (n) gravity's generalised force `(m g, 0)` per body.
    gravity: Vec<f64>,
    /// The forces active in the analysis (the only ones that load the mechanism).
    pub forces: Vec<&'m ForceElement>,
    /// (Jacobian entries) `(row, column)` of each entry of `Phi_q`.
    entries: Vec<(usize, usize)>,
    /// (Jacobian entries) `Phi_q` at the last [`Dae::positions`].
    jac: Vec<f64>,
    /// (m) `Phi` at the last [`Dae::positions`].
    pub phi: Vec<f64>,
    /// (bodies) `(cos, sin)` of each angle at the last [`Dae::positions`].
    rot: Vec<[f64; 2]>,
    /// `-eps` on the constraint diagonal of the Newton matrix.
    eps: f64,
    kkt: Kkt,
    /// The projection matrix of the stabilised index-2 formulation, built at its first use.
    kkt_mass: Option<Kkt>,
    /// Force scratch: local positions, velocities, loads, and derivative blocks.
    fx: Vec<f64>,
    fv: Vec<f64>,
    fq: Vec<f64>,
    fdx: Vec<f64>,
    fdv: Vec<f64>,
    dual: DualWork,
    /// (n + m) right-hand side scratch.
    rhs: Vec<f64>,
    /// Factor on gravity and on the applied forces and torques (not on the spring-dampers), for
    /// the load stepping of static equilibrium. 1 everywhere else.
    pub external_scale: f64,
    /// (forces) whether each force is an applied load (scaled by `external_scale`) rather than a
    /// spring-damper between bodies.
    applied: Vec<bool>,
    /// Work counters.
    pub stats: LinearStats,
}

impl<'m> Dae<'m> {
    /// The equations of `model` with the active drivers `drivers` and the active forces `forces`
    /// (indices into the model's drivers and forces).
    pub fn new(model: &'m Model, drivers: &[usize], forces: &[usize]) -> Result<Dae<'m>, FactorError> {
        let sys = System::new(model, drivers);
        let (n, m) = (sys.n, sys.m);
        let mass: Vec<f64> = model.bodies.iter().flat_map(|b| [b.mass, b.mass, b.inertia]).collect();
        let gravity: Vec<f64> =
            model.bodies.iter().flat_map(|b| [b.mass * model.gravity[0], b.mass * model.gravity[1], 0.0]).collect();
        let entries = sys.entries();
        let forces: Vec<&ForceElement> = forces.iter().map(|&k| &model.forces[k]).collect();
        let force_cols: Vec<&[usize]> = forces.iter().map(|f| f.force.columns()).collect();
        let applied = forces.iter().map(|f| f.applied).collect();
        let kkt = Kkt::new(n, m, &entries, &force_cols)?;
        let w = force_cols.iter().map(|c| c.len()).max().unwrap_or(0);
        let max_mass = mass.iter().fold(0.0f64, |a, &b| a.max(b));
        let eps = if max_mass > 0.0 { EPS_REL / max_mass } else { EPS_REL };
        Ok(Dae {
            model,
            n,
            m,
            mass,
            gravity,
            forces,
            jac: vec![0.0; entries.len()],
            entries,
            phi: vec![0.0; m],
            rot: vec![[1.0, 0.0]; n / 3],
            eps,
            kkt,
            kkt_mass: None,
            fx: vec![0.0; w],
            fv: vec![0.0; w],
            fq: vec![0.0; w],
            fdx: vec![0.0; w * w],
            fdv: vec![0.0; w * w],
            dual: DualWork::new(w),
            rhs: vec![0.0; n + m],
            sys,
            external_scale: 1.0,
            applied,
            stats: LinearStats::default(),
        })
    }

    /// `(q, t) => (Phi, Phi_q)` into [`Dae::phi`] and the Jacobian buffer; every other evaluation
    /// at `q` (`nu`, `gamma`, products with `Phi_q`, the Newton matrix) uses these.
    pub fn positions(&mut self, q: &[f64], t: f64) {
        Config::rotations(q, &mut self.rot);
        let c = Config::new(q, &self.rot);
        self.sys.phi(&c, t, &mut self.phi);
        self.sys.jacobian_values(&c, t, &mut self.jac);
    }

    /// `(q, t) => nu = -Phi_t`, `out: (m)`; `q` as at the last [`Dae::positions`].
    pub fn nu(&self, q: &[f64], t: f64, out: &mut [f64]) {
        self.sys.nu(&Config::new(q, &self.rot), t, out);
    }

    /// `(q, qdot, t) => gamma`, `out: (m)`; `q` as at the last [`Dae::positions`].
    pub fn gamma(&self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) {
        self.sys.gamma(&Config::new(q, &self.rot), qdot, t, out);
    }

    /// `out (n) += Phi_q^T lambda`, with `lambda: (m)`.
    pub fn add_jt(&self, lambda: &[f64], out: &mut [f64]) {
        for (&(r, c), &v) in self.entries.iter().zip(&self.jac) {
            out[c] += v * lambda[r];
        }
    }

    /// `(row, column)` of each entry of `Phi_q` (each pair once), and the entries' values at the
    /// last [`Dae::positions`]: `Phi_q` in coordinate form, for solvers of its sparse blocks.
    pub fn jacobian_entries(&self) -> (&[(usize, usize)], &[f64]) {
        (&self.entries, &self.jac)
    }

    /// `out (m x n) = Phi_q`, dense, from the last [`Dae::positions`].
    pub fn jacobian_dense(&self, mut out: MatMut<'_, f64>) {
        out.fill(0.0);
        for (&(r, c), &v) in self.entries.iter().zip(&self.jac) {
            out[(r, c)] += v;
        }
    }

    /// `out (m) = Phi_q v`, with `v: (n)`.
    pub fn jv(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (&(r, c), &x) in self.entries.iter().zip(&self.jac) {
            out[r] += x * v[c];
        }
    }

    /// `(q, qdot, t) => Q`, `out: (n)`: gravity plus every active force.
    /// Why a state's derived values are not finite: the first active force, then the first
    /// measure, that evaluates to a non-finite number at `(q, qdot, qddot, t)` with the
    /// reactions row `reactions` ([`crate::model::Measure::value`]); else the equations of
    /// motion, with `value`, the first non-finite number found.
    pub fn non_finite(&self, q: &[f64], qdot: &[f64], qddot: &[f64], reactions: &[f64], t: f64, value: f64) -> Error {
        let error =
            |element: String, expression: String, value: f64| Error::NonFinite { time: t, element, expression, value };
        for f in &self.forces {
            if let Some(v) = f.non_finite(q, qdot, t) {
                return error(format!("forces.{}", f.name), f.expressions(), v);
            }
        }
        for m in &self.model.measures {
            let v = m.value(q, qdot, qddot, reactions, t);
            if !v.is_finite() {
                return error(format!("measures.{}", m.name), m.expression().to_string(), v);
            }
        }
        error("the solution of the equations of motion".into(), String::new(), value)
    }

    pub fn load(&mut self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) {
        let s = self.external_scale;
        for (o, g) in out.iter_mut().zip(&self.gravity) {
            *o = s * g;
        }
        for (f, &applied) in self.forces.iter().zip(&self.applied) {
            let cols = f.force.columns();
            let w = cols.len();
            gather(q, cols, &mut self.fx[..w]);
            gather(qdot, cols, &mut self.fv[..w]);
            f.force.load(&self.fx[..w], &self.fv[..w], t, &mut self.fq[..w]);
            let scale = if applied { s } else { 1.0 };
            for (&c, &v) in cols.iter().zip(&self.fq[..w]) {
                out[c] += scale * v;
            }
        }
    }

    /// `dq (n x n) = dQ/dq` and `dv (n x n) = dQ/dqdot` at `(q, qdot, t)`, dense, exact (dual
    /// numbers), with [`Dae::external_scale`] applied as in [`Dae::load`].
    pub fn load_jacobians(
        &mut self,
        q: &[f64],
        qdot: &[f64],
        t: f64,
        mut dq: MatMut<'_, f64>,
        mut dv: MatMut<'_, f64>,
    ) {
        dq.fill(0.0);
        dv.fill(0.0);
        for k in 0..self.forces.len() {
            let w = self.force_derivatives(k, q, qdot, t);
            let cols = self.forces[k].force.columns();
            let scale = if self.applied[k] { self.external_scale } else { 1.0 };
            for (ri, &r) in cols.iter().enumerate() {
                for (ci, &c) in cols.iter().enumerate() {
                    dq[(r, c)] += scale * self.fdx[ri * w + ci];
                    dv[(r, c)] += scale * self.fdv[ri * w + ci];
                }
            }
        }
    }

    /// `dQ/dx` and `dQ/dv` of the `k`-th force on its `w` columns at `(q, qdot, t)`, exact (dual
    /// numbers), into `fdx` and `fdv` (`w x w`, row-major); returns `w`.
    fn force_derivatives(&mut self, k: usize, q: &[f64], qdot: &[f64], t: f64) -> usize {
        let f = self.forces[k].force.as_ref();
        let cols = f.columns();
        let w = cols.len();
        gather(q, cols, &mut self.fx[..w]);
        gather(qdot, cols, &mut self.fv[..w]);
        let (dx, dv) = (&mut self.fdx[..w * w], &mut self.fdv[..w * w]);
        derivatives(f, &self.fx[..w], &self.fv[..w], t, dx, dv, &mut self.dual);
        w
    }

    /// Fill and factorise `K(c_v, c_q)` at `(q, qdot, t)`, with `Phi_q` from the last
    /// [`Dae::positions`] (which must be at `q`).
    pub fn factor(&mut self, q: &[f64], qdot: &[f64], t: f64, c_v: f64, c_q: f64) -> Result<(), FactorError> {
        self.stats.jacobian_evaluations += 1;
        self.kkt.fill(&self.mass, self.eps, &self.jac);
        if c_v != 0.0 || c_q != 0.0 {
            for k in 0..self.forces.len() {
                let w = self.force_derivatives(k, q, qdot, t);
                let (_, values) = self.kkt.lu.pattern_and_values();
                let (dx, dv) = (&self.fdx[..w * w], &self.fdv[..w * w]);
                for ((&p, &a), &b) in self.kkt.forces[k].iter().zip(dx).zip(dv) {
                    values[p] -= c_q * a + c_v * b;
                }
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
    pub fn accelerations(&mut self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) -> Result<(), FactorError> {
        self.positions(q, t);
        self.factor(q, qdot, t, 0.0, 0.0)?;
        out.fill(0.0);
        let mut r = std::mem::take(&mut self.rhs);
        for _ in 0..3 {
            self.residual(q, qdot, t, out, &mut r);
            self.solve(&mut r);
            for (o, d) in out.iter_mut().zip(&r) {
                *o += d;
            }
        }
        self.rhs = r;
        Ok(())
    }

    /// `out (n + m) = [Q - M qddot - Phi_q^T lambda; gamma - Phi_q qddot]` for
    /// `sol = [qddot; lambda]`, positions as at the last [`Dae::positions`].
    pub fn residual(&mut self, q: &[f64], qdot: &[f64], t: f64, sol: &[f64], out: &mut [f64]) {
        let n = self.n;
        let (a, l) = sol.split_at(n);
        let (f, g) = out.split_at_mut(n);
        self.load(q, qdot, t, f);
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

    /// Kinetic energy `qdot^T M qdot / 2`, J.
    pub fn kinetic_energy(&self, qdot: &[f64]) -> f64 {
        0.5 * self.mass.iter().zip(qdot).map(|(m, v)| m * v * v).sum::<f64>()
    }

    /// Potential energy of gravity and of the active springs, J (zero at the origin and at each
    /// spring's free length).
    pub fn potential_energy(&mut self, q: &[f64]) -> f64 {
        let mut v = -self.gravity.iter().zip(q).map(|(g, x)| g * x).sum::<f64>();
        for f in &self.forces {
            let cols = f.force.columns();
            let w = cols.len();
            gather(q, cols, &mut self.fx[..w]);
            v += f.force.potential(&self.fx[..w]);
        }
        v
    }

    /// Power of the non-conservative forces, W: every active force's power `Q_e . qdot` plus the rate
    /// of its potential (which cancels the conservative part), plus the drivers' power
    /// `-lambda_d^T Phi_q,d qdot = -lambda_d^T nu_d`. `lambda: (m)`; positions as at the last
    /// [`Dae::positions`].
    pub fn nonconservative_power(&mut self, q: &[f64], qdot: &[f64], t: f64, lambda: &[f64], nu: &mut [f64]) -> f64 {
        let mut p = self.applied_power(q, qdot, t);
        for f in &self.forces {
            let cols = f.force.columns();
            let w = cols.len();
            gather(q, cols, &mut self.fx[..w]);
            gather(qdot, cols, &mut self.fv[..w]);
            p += potential_rate(f.force.as_ref(), &self.fx[..w], &self.fv[..w], &mut self.dual);
        }
        p + self.driver_power(q, t, lambda, nu)
    }

    /// Power of the active forces (not gravity) `Q_e . qdot`, W.
    pub fn applied_power(&mut self, q: &[f64], qdot: &[f64], t: f64) -> f64 {
        let mut p = 0.0;
        for f in &self.forces {
            let cols = f.force.columns();
            let w = cols.len();
            gather(q, cols, &mut self.fx[..w]);
            gather(qdot, cols, &mut self.fv[..w]);
            f.force.load(&self.fx[..w], &self.fv[..w], t, &mut self.fq[..w]);
            p += self.fq[..w].iter().zip(&self.fv[..w]).map(|(a, b)| a * b).sum::<f64>();
        }
        p
    }

    /// Power of the active drivers, `-lambda_d^T nu_d` (each effort times its driver's rate), W;
    /// `nu: (m)` scratch, positions as at the last [`Dae::positions`].
    pub fn driver_power(&self, q: &[f64], t: f64, lambda: &[f64], nu: &mut [f64]) -> f64 {
        let joints = self.model.joints.iter().map(|j| j.constraint.rows()).sum::<usize>();
        if joints == self.m {
            return 0.0;
        }
        self.nu(q, t, nu);
        -lambda[joints..].iter().zip(&nu[joints..]).map(|(l, v)| l * v).sum::<f64>()
    }

    /// Each joint's reaction on its first body `(fx, fy, torque)` (global frame; torque about
    /// the joint's point) and each active driver's effort `-lambda` (the generalised force it
    /// applies in the direction that increases its coordinate), from the multipliers
    /// `lambda: (m)` at `q` (positions as at the last [`Dae::positions`]). `out` gets `3` values
    /// per joint, then one per driver.
    pub fn reactions(&self, q: &[f64], lambda: &[f64], out: &mut Vec<f64>) {
        out.clear();
        let joints = self.model.joints.len();
        let mut k = 0;
        for (idx, (e, rows)) in self.sys.elements().enumerate() {
            let c = e.constraint.as_ref();
            let cols = c.columns();
            let w = cols.len();
            let block = &self.jac[k..k + rows.len() * w];
            k += rows.len() * w;
            if idx >= joints {
                out.push(-lambda[rows.start]);
                continue;
            }
            // g = -Phi_q,e^T lambda_e on the element's columns: the generalised reaction.
            let generalised = |body: BodyIx| -> [f64; 3] {
                let mut g = [0.0; 3];
                let Some(b) = body.0 else { return g };
                for (ci, &col) in cols.iter().enumerate() {
                    if (b..b + 3).contains(&col) {
                        g[col - b] =
                            -rows.clone().enumerate().map(|(ri, r)| block[ri * w + ci] * lambda[r]).sum::<f64>();
                    }
                }
                g
            };
            let Anchor { i, j, point } = c.anchor();
            let (f, torque) = match i.0 {
                Some(b) => {
                    let [fx, fy, m] = generalised(i);
                    // Moment about P = moment about the centre of mass - (A s'_P) x f.
                    let [cs, sn] = self.rot[b / 3];
                    let a = [cs * point[0] - sn * point[1], sn * point[0] + cs * point[1]];
                    ([fx, fy], m - (a[0] * fy - a[1] * fx))
                }
                None => {
                    // On ground: the opposite of the reaction on body j, its moment taken about P.
                    let [fx, fy, m] = generalised(j);
                    let rj = j.coords(q);
                    let d = [rj[0] - point[0], rj[1] - point[1]];
                    ([-fx, -fy], -(m + d[0] * fy - d[1] * fx))
                }
            };
            out.extend([f[0], f[1], torque]);
        }
    }
}

/// `out[k] = v[cols[k]]`.
#[inline]
fn gather(v: &[f64], cols: &[usize], out: &mut [f64]) {
    for (o, &c) in out.iter_mut().zip(cols) {
        *o = v[c];
    }
}
