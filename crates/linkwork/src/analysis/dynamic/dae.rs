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

use crate::constraints::{reaction, Config, Friction};
use crate::error::{Error, RowName};
use crate::expr::Dual;
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

/// The most Newton iterations [`Dae::accelerations`] (and the inverse analysis' Newton on the
/// multipliers) takes when joints have friction: 30. The
/// friction depends on the reactions only through their magnitudes, so Newton converges
/// quadratically once the reactions' directions settle, in the three solves of the frictionless
/// refinement or a few more. A reaction near zero (a pin unloaded while the mechanism moves)
/// turns its direction fast, which costs a few more; 30 leaves room for those and still fails fast
/// where there is no solution.
pub(crate) const NEWTON_FRICTION_ITERATIONS: usize = 30;

/// An iteration on the multipliers with joint friction (Newton on the accelerations, and on the
/// inverse analysis's friction rows) has converged when its last correction of the multipliers is below this
/// fraction of the largest multiplier: `1e-10`. Once the friction holds still the rest is linear
/// and the correction is the refinement's, which the frictionless solve stops after three solves,
/// each shrinking it by the regularisation's `~1e-10`; `1e-10` is a hundred to ten thousand times
/// the round-off of the multipliers (`1e-16` times the condition, `1e2` to `1e4` on the examples),
/// and far below the accuracy to which any coefficient of friction is known. Measured against the
/// largest multiplier (forces and torques alike, for a mechanism of metres), not each its own, so
/// that the round-off of a joint that carries nothing does not count as a change.
pub(crate) const FRICTION_RTOL: f64 = 1e-10;

/// One joint's friction and where its rows, Jacobian block and columns sit.
#[derive(Debug)]
struct FrictionSlot<'m> {
    friction: &'m Friction,
    /// The joint's name, for messages.
    name: &'m str,
    /// Its rows in `lambda`.
    rows: std::ops::Range<usize>,
    /// Its Jacobian block among the Jacobian's values.
    block: std::ops::Range<usize>,
    /// Its columns (those of its constraint).
    columns: &'m [usize],
}

/// Columns and rows of a friction joint, at most: a revolute or translational joint between two
/// bodies.
const FRICTION_WIDTH: usize = 6;
const FRICTION_ROWS: usize = 2;

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
    /// (n) the positions and the time of the last [`Dae::positions`]; a call at the same point
    /// finds its values there (NaN time when the buffers hold no full evaluation).
    at_q: Vec<f64>,
    at_t: f64,
    /// Scratch of [`Dae::jv_at`]: (bodies) rotations and (Jacobian entries) values at another
    /// point, so that the last [`Dae::positions`] stays.
    rot_at: Vec<[f64; 2]>,
    jac_at: Vec<f64>,
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
    /// The joints with friction (none in most models: then nothing is evaluated for it).
    friction: Vec<FrictionSlot<'m>>,
    /// Indices into `forces` of the contacts (none in most models: then no step is checked).
    contacts: Vec<usize>,
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
        let mut friction = Vec::new();
        let mut at = 0;
        for (e, rows) in sys.elements() {
            let c = e.constraint.as_ref();
            let len = rows.len() * c.columns().len();
            if let Some(f) = &e.friction {
                let (block, columns) = (at..at + len, c.columns());
                friction.push(FrictionSlot { friction: f, name: &e.name, rows, block, columns });
            }
            at += len;
        }
        // Each friction joint's velocity derivatives take a block of the Newton matrix, after the
        // forces' blocks (its multiplier derivatives sit on the transpose of its Jacobian block).
        let force_cols: Vec<&[usize]> =
            forces.iter().map(|f| f.force.columns()).chain(friction.iter().map(|f| f.columns)).collect();
        let applied = forces.iter().map(|f| f.applied).collect();
        let contacts = (0..forces.len()).filter(|&k| forces[k].force.contact().is_some()).collect();
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
            jac_at: vec![0.0; entries.len()],
            entries,
            phi: vec![0.0; m],
            rot: vec![[1.0, 0.0]; n / 3],
            at_q: vec![0.0; n],
            at_t: f64::NAN,
            rot_at: vec![[1.0, 0.0]; n / 3],
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
            friction,
            contacts,
        })
    }

    /// `(q, t) => (Phi, Phi_q)` into [`Dae::phi`] and the Jacobian buffer; every other evaluation
    /// at `q` (`nu`, `gamma`, products with `Phi_q`, the Newton matrix) uses these.
    /// A call at the point of the last one returns at once: integrators ask for the same point
    /// from several places (the work of an accepted step, an error norm after the evaluation).
    pub fn positions(&mut self, q: &[f64], t: f64) {
        if t == self.at_t && q == self.at_q.as_slice() {
            return;
        }
        Config::rotations(q, &mut self.rot);
        let c = Config::new(q, &self.rot);
        self.sys.phi(&c, t, &mut self.phi);
        self.sys.jacobian_values(&c, t, &mut self.jac);
        self.at_q.copy_from_slice(q);
        self.at_t = t;
    }

    /// `(q, t) => Phi` into [`Dae::phi`] alone, the Jacobian buffer left as it was: the residual
    /// of a Newton iteration whose matrix was factored elsewhere (a chord iteration), at about
    /// a third of [`Dae::positions`]' cost. Evaluations that read `Phi_q` at `q` (`nu`, `gamma`,
    /// products with `Phi_q`, [`Dae::jacobian_entries`]) need a [`Dae::positions`] first.
    pub fn constraints_only(&mut self, q: &[f64], t: f64) {
        Config::rotations(q, &mut self.rot);
        self.sys.phi(&Config::new(q, &self.rot), t, &mut self.phi);
        self.at_t = f64::NAN;
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

    /// The positions of the last [`Dae::positions`]: where [`Dae::jacobian_entries`] holds
    /// `Phi_q`.
    pub fn jacobian_point(&self) -> &[f64] {
        &self.at_q
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
        jacobian_times(&self.entries, &self.jac, v, out);
    }

    /// `out (m) = Phi_q(q, t) v` at another point than the last [`Dae::positions`], which it
    /// leaves as it was (for a difference quotient of `Phi_q v`).
    pub fn jv_at(&mut self, q: &[f64], t: f64, v: &[f64], out: &mut [f64]) {
        Config::rotations(q, &mut self.rot_at);
        self.sys.jacobian_values(&Config::new(q, &self.rot_at), t, &mut self.jac_at);
        jacobian_times(&self.entries, &self.jac_at, v, out);
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
                let (dx, dv) = (&self.fdx[..w * w], &self.fdv[..w * w]);
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

    /// Whether a joint has friction.
    pub fn has_friction(&self) -> bool {
        !self.friction.is_empty()
    }

    /// The multipliers' rows and the coordinates' columns that joint friction involves, each
    /// ascending without repeats: `Q_f` is zero off `columns` and depends on `lambda` only
    /// through `rows`.
    pub(crate) fn friction_support(&self) -> (Vec<usize>, Vec<usize>) {
        let mut rows: Vec<usize> = self.friction.iter().flat_map(|s| s.rows.clone()).collect();
        let mut columns: Vec<usize> = self.friction.iter().flat_map(|s| s.columns.iter().copied()).collect();
        for v in [&mut rows, &mut columns] {
            v.sort_unstable();
            v.dedup();
        }
        (rows, columns)
    }

    /// `out (n x rows.len())`, column-major, `= dQ_f / dlambda[rows]`: the exact derivatives of
    /// the joints' friction by the multipliers of `rows` ([`Dae::friction_support`]'s), positions
    /// as at the last [`Dae::positions`].
    pub(crate) fn friction_by_multipliers(
        &self,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        rows: &[usize],
        out: &mut [f64],
    ) {
        let n = self.n;
        out.fill(0.0);
        for (k, slot) in self.friction.iter().enumerate() {
            let count = slot.rows.len();
            let (by_l, _) = self.slot_derivatives(k, q, qdot, multipliers, 1.0);
            for (r, row) in slot.rows.clone().enumerate() {
                let Ok(j) = rows.binary_search(&row) else { continue };
                for (c, &col) in slot.columns.iter().enumerate() {
                    out[j * n + col] += by_l[c * count + r];
                }
            }
        }
    }

    /// The exact derivatives of slot `k`'s friction ([`Friction::derivatives`]) with the
    /// multipliers `multipliers / per`: by its multipliers `(columns x rows)` and by its
    /// velocities `(columns x columns)`, row-major.
    fn slot_derivatives(
        &self,
        k: usize,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        per: f64,
    ) -> ([f64; FRICTION_WIDTH * FRICTION_ROWS], [f64; FRICTION_WIDTH * FRICTION_WIDTH]) {
        let slot = &self.friction[k];
        let (w, rows) = (slot.columns.len(), slot.rows.len());
        let (mut v, mut lambda) = ([0.0; FRICTION_WIDTH], [0.0; FRICTION_ROWS]);
        gather(qdot, slot.columns, &mut v[..w]);
        for (l, &x) in lambda.iter_mut().zip(&multipliers[slot.rows.clone()]) {
            *l = x / per;
        }
        let (mut by_l, mut by_v) = ([0.0; FRICTION_WIDTH * FRICTION_ROWS], [0.0; FRICTION_WIDTH * FRICTION_WIDTH]);
        let mut work = [Dual::new(0.0, 0.0); 2 * FRICTION_WIDTH + FRICTION_ROWS];
        let config = Config::new(q, &self.rot);
        let block = &self.jac[slot.block.clone()];
        let lambda = &lambda[..rows];
        slot.friction.derivatives(&config, slot.columns, block, &v[..w], lambda, &mut by_l, &mut by_v, &mut work);
        (by_l, by_v)
    }

    /// `out (n) += Q_f(q, qdot, multipliers / per)`: the joints' friction ([`Friction`]) with the
    /// multipliers `multipliers / per` (`per`: `1 + alpha` where an integrator's unknowns are
    /// `(1 + alpha) lambda`, else 1); positions as at the last [`Dae::positions`]. Each joint's
    /// friction (on its first body: N m or N) goes to `values` when it is given.
    pub fn add_friction(
        &self,
        q: &[f64],
        qdot: &[f64],
        multipliers: &[f64],
        per: f64,
        out: &mut [f64],
        mut values: Option<&mut Vec<f64>>,
    ) {
        for (k, slot) in self.friction.iter().enumerate() {
            let (mut lambda, mut load) = ([0.0; FRICTION_ROWS], [0.0; FRICTION_WIDTH]);
            for (l, &x) in lambda.iter_mut().zip(&multipliers[slot.rows.clone()]) {
                *l = x / per;
            }
            let value = self.slot_friction(k, q, qdot, &lambda, &mut load);
            for (&c, &f) in slot.columns.iter().zip(&load) {
                out[c] += f;
            }
            if let Some(values) = values.as_mut() {
                values.push(value);
            }
        }
    }

    /// The friction of slot `k` with its multipliers `lambda` (its rows'): `Q_f` on its columns
    /// into `load`, and its value.
    fn slot_friction(&self, k: usize, q: &[f64], qdot: &[f64], lambda: &[f64], load: &mut [f64]) -> f64 {
        let slot = &self.friction[k];
        let w = slot.columns.len();
        let mut v = [0.0; FRICTION_WIDTH];
        gather(qdot, slot.columns, &mut v[..w]);
        let block = &self.jac[slot.block.clone()];
        let config = Config::new(q, &self.rot);
        slot.friction.load(&config, slot.columns, block, &v[..w], &lambda[..slot.rows.len()], &mut load[..w])
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
        self.factor(q, qdot, t, 0.0, 0.0, &[], 1.0).map_err(|e| super::factor_error(e, t))?;
        for _ in 0..3 {
            self.residual(q, qdot, t, out, r);
            self.solve(r);
            for (o, d) in out.iter_mut().zip(r.iter()) {
                *o += d;
            }
        }
        Ok(())
    }

    /// [`Dae::accelerations`] with joint friction: Newton on `(qddot, lambda)`, at least the three
    /// solves of the frictionless refinement.
    fn friction_newton(
        &mut self,
        q: &[f64],
        qdot: &[f64],
        t: f64,
        out: &mut [f64],
        r: &mut [f64],
    ) -> Result<(), Error> {
        let n = self.n;
        let mut worst = (0, f64::INFINITY);
        for it in 0..NEWTON_FRICTION_ITERATIONS {
            self.residual(q, qdot, t, out, r);
            self.factor(q, qdot, t, 0.0, 0.0, &out[n..], 1.0).map_err(|e| super::factor_error(e, t))?;
            self.solve(r);
            for (o, d) in out.iter_mut().zip(r.iter()) {
                *o += d;
            }
            worst = self.friction_change(q, qdot, &r[n..], &out[n..]);
            if it >= 2 && worst.1 <= FRICTION_RTOL {
                return Ok(());
            }
        }
        Err(self.friction_error(worst, t, NEWTON_FRICTION_ITERATIONS, "the accelerations and reactions"))
    }

    /// How far an iteration that changed the multipliers by `delta (m)` to `lambda (m)` is from
    /// converged: the largest change relative to the largest multiplier (0 when both are 0); and
    /// the friction joint whose friction force changed most with it (its generalised force's
    /// largest entry, N or N m), to blame if it does not converge.
    pub(crate) fn friction_change(&self, q: &[f64], qdot: &[f64], delta: &[f64], lambda: &[f64]) -> (usize, f64) {
        let size = lambda.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let largest = delta.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let relative = if largest == 0.0 { 0.0 } else { largest / size };
        let change = |k: usize| {
            let rows = self.friction[k].rows.clone();
            let (mut after, mut before) = ([0.0; FRICTION_ROWS], [0.0; FRICTION_ROWS]);
            for (r, row) in rows.enumerate() {
                after[r] = lambda[row];
                before[r] = lambda[row] - delta[row];
            }
            let (mut a, mut b) = ([0.0; FRICTION_WIDTH], [0.0; FRICTION_WIDTH]);
            self.slot_friction(k, q, qdot, &after, &mut a);
            self.slot_friction(k, q, qdot, &before, &mut b);
            a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        let changes: Vec<f64> = (0..self.friction.len()).map(change).collect();
        let blamed = (0..changes.len()).fold(0, |b, k| if changes[k] > changes[b] { k } else { b });
        (blamed, relative)
    }

    /// [`Error::Friction`] at the friction joint `k` of [`Dae::friction_change`], whose `what`
    /// still changed by `change` of the largest multiplier after `iterations` iterations at `t`.
    pub(crate) fn friction_error(&self, (k, change): (usize, f64), t: f64, iterations: usize, what: &str) -> Error {
        let slot = &self.friction[k];
        Error::Friction {
            time: t,
            row: RowName { element: slot.name.to_string(), equation: "friction".into() },
            detail: format!(
                "{what} and the friction that depends on them did not converge in {iterations} iterations (the \
                 multipliers still changed by {change:.3e} of the largest): the friction may lock the mechanism here \
                 (a self-locking position, where no finite effort moves it), or the coefficient is too large for \
                 this geometry"
            ),
        }
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

    /// Kinetic energy `qdot^T M qdot / 2`, J.
    pub fn kinetic_energy(&self, qdot: &[f64]) -> f64 {
        0.5 * self.mass.iter().zip(qdot).map(|(m, v)| m * v * v).sum::<f64>()
    }

    /// Whether a contact is active.
    pub fn has_contacts(&self) -> bool {
        !self.contacts.is_empty()
    }

    /// For a step from `q0` to `q1`: the fraction of it to retry with when it carries a contact
    /// from separation past its `max_penetration` or further than its smallest radius
    /// ([`crate::forces::Contact::event`]; the smallest fraction of all contacts), `None` when the
    /// step may stand (always, without contacts).
    pub fn contact_event(&mut self, q0: &[f64], q1: &[f64]) -> Option<f64> {
        let mut fraction: Option<f64> = None;
        for &k in &self.contacts {
            let f = self.forces[k].force.as_ref();
            let Some(contact) = f.contact() else { continue };
            let cols = f.columns();
            let w = cols.len();
            gather(q0, cols, &mut self.fx[..w]);
            gather(q1, cols, &mut self.fv[..w]);
            if let Some(r) = contact.event(&self.fx[..w], &self.fv[..w]) {
                fraction = Some(fraction.map_or(r, |g| g.min(r)));
            }
        }
        fraction
    }

    /// `(normal force, friction, penetration)` of each active contact at `(q, qdot)`
    /// ([`crate::forces::Contact::state`]), into `out`.
    pub fn contact_states(&mut self, q: &[f64], qdot: &[f64], out: &mut Vec<f64>) {
        for &k in &self.contacts {
            let f = self.forces[k].force.as_ref();
            let Some(contact) = f.contact() else { continue };
            let cols = f.columns();
            let w = cols.len();
            gather(q, cols, &mut self.fx[..w]);
            gather(qdot, cols, &mut self.fv[..w]);
            let s = contact.state(&self.fx[..w], &self.fv[..w]);
            out.extend([s.normal, s.friction, s.penetration]);
        }
    }

    /// Potential energy of gravity and of the active springs and contacts, J (zero at the origin
    /// and at each spring's free length).
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
        p + self.driver_power(q, t, lambda, nu) + self.friction_power(q, qdot, lambda)
    }

    /// Power of the joints' friction `Q_f . qdot` (at most zero), W; positions as at the last
    /// [`Dae::positions`].
    pub fn friction_power(&self, q: &[f64], qdot: &[f64], lambda: &[f64]) -> f64 {
        if self.friction.is_empty() {
            return 0.0;
        }
        let mut load = vec![0.0; self.n];
        self.add_friction(q, qdot, lambda, 1.0, &mut load, None);
        load.iter().zip(qdot).map(|(f, v)| f * v).sum()
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
    /// the joint's point, [`reaction`]) and each active driver's effort `-lambda` (the generalised
    /// force it applies in the direction that increases its coordinate), from the multipliers
    /// `lambda: (m)` at `q` (positions as at the last [`Dae::positions`]); then the friction of
    /// each joint that has one at `(q, qdot)` ([`Dae::add_friction`]). `out` gets `3` values per
    /// joint, one per driver, one per friction joint.
    pub fn reactions(&self, q: &[f64], qdot: &[f64], lambda: &[f64], out: &mut Vec<f64>) {
        out.clear();
        let joints = self.model.joints.len();
        let config = Config::new(q, &self.rot);
        let mut k = 0;
        for (idx, (e, rows)) in self.sys.elements().enumerate() {
            let c = e.constraint.as_ref();
            let block = &self.jac[k..k + rows.len() * c.columns().len()];
            k += block.len();
            if idx >= joints {
                out.push(-lambda[rows.start]);
                continue;
            }
            let (f, torque) = reaction(c.anchor(), c.columns(), block, &lambda[rows], &config);
            out.extend([f[0], f[1], torque]);
        }
        if !self.friction.is_empty() {
            let mut load = vec![0.0; self.n];
            self.add_friction(q, qdot, lambda, 1.0, &mut load, Some(out));
        }
    }
}

/// `out (m) = J v` for the Jacobian entries `(row, column)` with values `values`.
fn jacobian_times(entries: &[(usize, usize)], values: &[f64], v: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for (&(r, c), &x) in entries.iter().zip(values) {
        out[r] += x * v[c];
    }
}

/// `out[k] = v[cols[k]]`.
#[inline]
fn gather(v: &[f64], cols: &[usize], out: &mut [f64]) {
    for (o, &c) in out.iter_mut().zip(cols) {
        *o = v[c];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Newton matrix with joint friction is the Jacobian of the residual: with positions held
    /// and `qdot = v0 + c_v qddot` (a step of `c_v`), `K(c_v, 0) x` is minus the derivative of
    /// `[Q + Q_f - M qddot - Phi_q^T lambda]` along `x = (x_a, x_lambda)`, and `Phi_q x_a - eps x_lambda`
    /// below. Checked by solving with `K` the right-hand side built from central differences of
    /// the residual: it gives back `x` to `1e-6` relative (steps of `1e-6` on inputs of order 1 and
    /// multipliers of order 100: truncation `~1e-12`, round-off `~1e-16 / 1e-6` of forces of order
    /// 100, `1e-8`, amplified by the matrix's condition), where a misplaced or mis-scaled friction
    /// entry (the derivatives are `mu r` to `mu` times the reaction's) errs by `1e-3` or more.
    #[test]
    fn newton_matrix_with_friction_is_the_residuals_jacobian() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/slider_crank_friction.yaml");
        let model = Model::load(path).unwrap();
        let mut dae = Dae::new(&model, &[0], &[0]).unwrap();
        let (n, m) = (dae.n, dae.m);
        let q = [0.0435, 0.0246, 0.6, 0.2334, 0.0246, -0.165, 0.385, 0.0, 0.0];
        let v0 = [-0.3, 0.4, 6.3, -0.5, 0.3, -2.0, -0.6, 0.0, 0.0];
        let mut rng = crate::constraints::testing::Lcg::new(5);
        let a = rng.vec(n, -5.0, 5.0);
        let lambda = rng.vec(m, -100.0, 100.0);
        let x = rng.vec(n + m, -1.0, 1.0);
        let c_v = 0.01;
        dae.positions(&q, 0.3);
        let residual = |dae: &mut Dae<'_>, s: f64| {
            let aa: Vec<f64> = (0..n).map(|k| a[k] + s * x[k]).collect();
            let ll: Vec<f64> = (0..m).map(|k| lambda[k] + s * x[n + k]).collect();
            let v: Vec<f64> = (0..n).map(|k| v0[k] + c_v * aa[k]).collect();
            let mut sol = aa.clone();
            sol.extend(&ll);
            let mut out = vec![0.0; n + m];
            dae.residual(&q, &v, 0.3, &sol, &mut out);
            out
        };
        let h = 1e-6;
        let (plus, minus) = (residual(&mut dae, h), residual(&mut dae, -h));
        let mut rhs: Vec<f64> = (0..n).map(|k| -(plus[k] - minus[k]) / (2.0 * h)).collect();
        let mut jx = vec![0.0; m];
        dae.jv(&x[..n], &mut jx);
        rhs.extend((0..m).map(|r| jx[r] - dae.eps * x[n + r]));
        let v: Vec<f64> = (0..n).map(|k| v0[k] + c_v * a[k]).collect();
        dae.factor(&q, &v, 0.3, c_v, 0.0, &lambda, 1.0).unwrap();
        dae.solve(&mut rhs);
        let worst = rhs.iter().zip(&x).fold(0.0f64, |w, (y, e)| w.max((y - e).abs()));
        assert!(worst < 1e-6, "{worst:e}: {rhs:?} vs {x:?}");
        // Without the friction's entries the same check fails: they matter at this state.
        dae.factor(&q, &v, 0.3, c_v, 0.0, &vec![0.0; m], 1.0).unwrap();
        let mut again: Vec<f64> = (0..n).map(|k| -(plus[k] - minus[k]) / (2.0 * h)).collect();
        again.extend((0..m).map(|r| jx[r] - dae.eps * x[n + r]));
        dae.solve(&mut again);
        let off = again.iter().zip(&x).fold(0.0f64, |w, (y, e)| w.max((y - e).abs()));
        assert!(off > 1e-3, "{off:e}");
    }

    /// The evaluations a Newton iteration and the error map use at other points leave the last
    /// [`Dae::positions`] as it was, and a repeated call at the same point is the same values:
    /// `jv_at` at `q2` is the directional derivative of `Phi` along `v` there (central differences
    /// of `constraints_only` with `h = 1e-6`: truncation `~1e-12`, round-off `~1e-16 / 1e-6`;
    /// bound `1e-8` of its size), the buffers at `q` are bit for bit those before it, and
    /// `positions(q)` after `constraints_only(q2)` evaluates again (the memo is not stale).
    #[test]
    fn other_points_leave_the_positions_and_jv_at_is_the_derivative() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/quick_return_a.yaml");
        let model = Model::load(path).unwrap();
        let mut dae = Dae::new(&model, &[], &[]).unwrap();
        let (n, m) = (dae.n, dae.m);
        let mut rng = crate::constraints::testing::Lcg::new(3);
        let q = model.q0();
        let q2: Vec<f64> = q.iter().map(|x| x + rng.uniform(-0.1, 0.1)).collect();
        let v = rng.vec(n, -1.0, 1.0);
        let t = 0.2;
        dae.positions(&q, t);
        let (phi0, jac0) = (dae.phi.clone(), dae.jac.clone());
        let mut jv2 = vec![0.0; m];
        dae.jv_at(&q2, t, &v, &mut jv2);
        assert_eq!((&dae.phi, &dae.jac), (&phi0, &jac0), "jv_at changed the positions' buffers");
        let h = 1e-6;
        let mut phi_at = |s: f64| {
            let x: Vec<f64> = q2.iter().zip(&v).map(|(a, b)| a + s * b).collect();
            dae.constraints_only(&x, t);
            dae.phi.clone()
        };
        let (plus, minus) = (phi_at(h), phi_at(-h));
        let size = jv2.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let worst = (0..m).map(|r| ((plus[r] - minus[r]) / (2.0 * h) - jv2[r]).abs()).fold(0.0, f64::max);
        assert!(size > 0.1 && worst <= 1e-8 * size, "{worst:e} of {size:e}");
        // The buffers now hold Phi at another point; positions(q) must evaluate again.
        dae.positions(&q, t);
        assert_eq!((&dae.phi, &dae.jac), (&phi0, &jac0), "positions(q) after constraints_only");
    }
}
