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
//!
//! The parts: this file holds the equations' buffers and the constraints at a point
//! (`Dae::positions` and what reads it); `kkt.rs` the Newton matrix, its factors and the
//! accelerations; `loads.rs` the applied forces, contacts, energies and powers; `friction.rs`
//! the joints' friction.

mod friction;
mod kkt;
mod loads;

use crate::constraints::{reaction, Config};
use crate::error::Error;
use crate::linalg::FactorError;
use crate::model::{ForceElement, Model};
use crate::system::System;
use faer::MatMut;
use friction::FrictionSlot;
use kkt::Kkt;
use loads::ForceWork;

pub(crate) use friction::{FRICTION_RTOL, NEWTON_FRICTION_ITERATIONS};

/// Regularisation of the constraint block, relative to `1 / max mass` (see the module docs).
pub const EPS_REL: f64 = 1e-10;

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
    /// Force scratch.
    work: ForceWork,
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
            work: ForceWork::new(w),
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

    /// Kinetic energy `qdot^T M qdot / 2`, J.
    pub fn kinetic_energy(&self, qdot: &[f64]) -> f64 {
        0.5 * self.mass.iter().zip(qdot).map(|(m, v)| m * v * v).sum::<f64>()
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
