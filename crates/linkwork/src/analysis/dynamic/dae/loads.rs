//! The applied loads: gravity and the active force elements' generalised forces and exact
//! derivatives, the contacts' events and states, and the energies and powers of the forces
//! and drivers.

use super::{gather, Dae};
use crate::expr::{Dual, HyperDual, Scalar};
use crate::forces::{derivatives, potential_rate, DualWork, Force};
use faer::MatMut;

/// Scratch of one force's evaluation: its positions and velocities on its (at most `w`)
/// columns, its load, and its derivative blocks (`w x w`, row-major).
#[derive(Debug)]
pub(super) struct ForceWork {
    fx: Vec<f64>,
    fv: Vec<f64>,
    fq: Vec<f64>,
    /// The derivative blocks `dQ/dx` and `dQ/dv` of [`Dae::force_derivatives`].
    pub(super) fdx: Vec<f64>,
    pub(super) fdv: Vec<f64>,
    dual: DualWork,
}

impl ForceWork {
    /// Scratch for forces of at most `w` columns.
    pub(super) fn new(w: usize) -> ForceWork {
        ForceWork {
            fx: vec![0.0; w],
            fv: vec![0.0; w],
            fq: vec![0.0; w],
            fdx: vec![0.0; w * w],
            fdv: vec![0.0; w * w],
            dual: DualWork::new(w),
        }
    }

    /// `x` and `v` on the columns `cols` into the positions and velocities; returns their number.
    fn gather(&mut self, cols: &[usize], x: &[f64], v: &[f64]) -> usize {
        let w = cols.len();
        gather(x, cols, &mut self.fx[..w]);
        gather(v, cols, &mut self.fv[..w]);
        w
    }
}

/// The numbers a force's load is differentiated along a parameter in: a number that depends on
/// the parameters only, along the parameter's direction, and the force's load over them.
trait Along: Scalar {
    /// `v` with derivative `g` along the parameter.
    fn along(v: f64, g: f64) -> Self;
    /// The load of `f` over these numbers ([`Force::load_data_dual`] and its kin).
    fn load(f: &dyn Force, x: (&[Self], &[Self], f64), data: &[Self], params: &[Self], out: &mut [Self]) -> bool;
}

/// First derivatives along the parameter alone.
impl Along for Dual {
    fn along(v: f64, g: f64) -> Dual {
        Dual::new(v, g)
    }
    fn load(
        f: &dyn Force,
        (x, v, t): (&[Dual], &[Dual], f64),
        data: &[Dual],
        params: &[Dual],
        out: &mut [Dual],
    ) -> bool {
        f.load_data_dual(x, v, t, data, params, out)
    }
}

/// A direction of the coordinates first, the parameter's second.
impl Along for HyperDual {
    fn along(v: f64, g: f64) -> HyperDual {
        HyperDual::new(v, 0.0, g, 0.0)
    }
    fn load(
        f: &dyn Force,
        (x, v, t): (&[HyperDual], &[HyperDual], f64),
        data: &[HyperDual],
        params: &[HyperDual],
        out: &mut [HyperDual],
    ) -> bool {
        f.load_data_hyper(x, v, t, data, params, out)
    }
}

impl Dae<'_> {
    /// `(q, qdot, t) => Q`, `out: (n)`: gravity plus every active force.
    pub fn load(&mut self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) {
        let s = self.external_scale;
        for (o, g) in out.iter_mut().zip(&self.gravity) {
            *o = s * g;
        }
        for (f, &applied) in self.forces.iter().zip(&self.applied) {
            let cols = f.force.columns();
            let w = self.work.gather(cols, q, qdot);
            f.force.load(&self.work.fx[..w], &self.work.fv[..w], t, &mut self.work.fq[..w]);
            let scale = if applied { s } else { 1.0 };
            for (&c, &v) in cols.iter().zip(&self.work.fq[..w]) {
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
                    dq[(r, c)] += scale * self.work.fdx[ri * w + ci];
                    dv[(r, c)] += scale * self.work.fdv[ri * w + ci];
                }
            }
        }
    }

    /// `dQ/dx` and `dQ/dv` of the `k`-th force on its `w` columns at `(q, qdot, t)`, exact (dual
    /// numbers), into `fdx` and `fdv` (`w x w`, row-major); returns `w`.
    pub(super) fn force_derivatives(&mut self, k: usize, q: &[f64], qdot: &[f64], t: f64) -> usize {
        let f = self.forces[k].force.as_ref();
        let cols = f.columns();
        let w = self.work.gather(cols, q, qdot);
        let (dx, dv) = (&mut self.work.fdx[..w * w], &mut self.work.fdv[..w * w]);
        derivatives(f, &self.work.fx[..w], &self.work.fv[..w], t, dx, dv, &mut self.work.dual);
        w
    }

    /// `dQ/dp`, the derivative of [`Dae::load`] with respect to parameter `p` (file order),
    /// added to `out: (n)`: with the coordinates and velocities moving along `dq` and `dv` (their
    /// derivatives with respect to `p`), gravity's through each body's mass and gravity itself
    /// ([`Dae::add_gravity_along`]), each active force's through its coordinates, its numbers and
    /// the parameters its expressions read ([`Dae::add_forces_along`]). `Err` names the first
    /// force that has no derivatives with respect to its numbers yet (docs/sensitivities.md).
    #[allow(clippy::too_many_arguments)]
    pub fn add_load_along(
        &self,
        q: &[f64],
        qdot: &[f64],
        t: f64,
        dq: &[f64],
        dv: &[f64],
        p: usize,
        out: &mut [f64],
    ) -> Result<(), String> {
        self.add_gravity_along(p, out);
        self.add_forces_along((q, qdot, t), (dq, dv), p, out)
    }

    /// The derivative of gravity's generalised force with respect to parameter `p` (file
    /// order), through each body's mass and gravity itself, added to `out: (n)`.
    pub fn add_gravity_along(&self, p: usize, out: &mut [f64]) {
        let s = self.external_scale;
        for (o, g) in out.chunks_exact_mut(3).zip(self.gravity_along(p)) {
            o[0] += s * g[0];
            o[1] += s * g[1];
        }
    }

    /// Each body's `d(m g)/dp`, gravity's force on it differentiated with respect to parameter
    /// `p` through its mass and gravity itself.
    fn gravity_along(&self, p: usize) -> impl Iterator<Item = [f64; 2]> + '_ {
        let (model, grads) = (self.model, &self.model.gradients);
        model
            .bodies
            .iter()
            .zip(&grads.bodies)
            .map(move |(b, g)| [0, 1].map(|k| g[0][p] * model.gravity[k] + b.mass * grads.gravity[k][p]))
    }

    /// The derivative of [`Dae::potential_energy`] with respect to parameter `p`, with the
    /// coordinates moving along `dq`: gravity's through the masses, gravity and the coordinates,
    /// each active force's through its coordinates and its numbers
    /// ([`crate::forces::ForceLaw::potential_data`]). `Err` names the first force whose
    /// potential a parameter moves through its numbers and that has no such derivatives yet (a
    /// contact). An applied force or torque has no potential.
    pub fn potential_energy_along(&self, q: &[f64], dq: &[f64], p: usize) -> Result<f64, String> {
        let mut v = 0.0;
        for (g, x) in self.gravity_along(p).zip(q.chunks_exact(3)) {
            v -= g[0] * x[0] + g[1] * x[1];
        }
        v -= self.gravity.iter().zip(dq).map(|(g, d)| g * d).sum::<f64>();
        let (model, grads) = (self.model, &self.model.gradients);
        let params: Vec<Dual> =
            model.parameters.values().zip(&grads.params).map(|(&v, g)| Dual::new(v, g[p])).collect();
        for f in &self.forces {
            if f.force.applied() {
                continue;
            }
            let k = self.model.forces.iter().position(|e| std::ptr::eq(e, *f)).expect("an active force is the model's");
            let data: Vec<Dual> =
                f.force.data().iter().zip(&grads.forces[k]).map(|(&(_, v), g)| Dual::new(v, g[p])).collect();
            let x: Vec<Dual> = f.force.columns().iter().map(|&c| Dual::new(q[c], dq[c])).collect();
            v += match f.force.potential_data_dual(&x, &data, &params) {
                Some(potential) => potential.d,
                None if data.iter().all(|d| d.d == 0.0) => f.force.potential_dual(&x).d,
                None => return Err(f.name.clone()),
            };
        }
        Ok(v)
    }

    /// The derivative of the active forces' generalised force (the part of [`Dae::load`] that
    /// is not gravity) with respect to parameter `p`, added to `out: (n)`: each force's through
    /// its coordinates at `(q, qdot, t)` (moving along `dq`, velocities along `dv`), its numbers
    /// ([`crate::forces::Force::data`], along their gradients) and the parameters its
    /// expressions read; one dual pass per force, exact. `Err` names the first force that has
    /// no derivatives with respect to its numbers yet.
    pub fn add_forces_along(
        &self,
        (q, qdot, t): (&[f64], &[f64], f64),
        (dq, dv): (&[f64], &[f64]),
        p: usize,
        out: &mut [f64],
    ) -> Result<(), String> {
        let x = |c: usize| Dual::new(q[c], dq[c]);
        let v = |c: usize| Dual::new(qdot[c], dv[c]);
        self.forces_along(t, p, x, v, |c, l: Dual| out[c] += l.d)
    }

    /// `d/dp (Q_q a + Q_qdot b)`: the derivative with respect to parameter `p` (file order) of
    /// the loads' derivative along the direction `(a, b)` of the coordinates and velocities,
    /// added to `out: (n)`, with the coordinates and velocities moving along `dq` and `dv` (their
    /// derivatives with respect to `p`): the stiffness's and damping's derivatives along a
    /// parameter that a sensitivity of modes needs. Gravity depends on neither; each active
    /// force gives it from one hyper-dual pass (the first direction `(a, b)`, the second the
    /// parameter's), exact. `Err` names the first force without derivatives with respect to its
    /// numbers, as [`Dae::add_load_along`].
    pub fn add_load_jacobians_along(
        &self,
        (q, qdot, t): (&[f64], &[f64], f64),
        (a, b): (&[f64], &[f64]),
        dq: &[f64],
        dv: &[f64],
        p: usize,
        out: &mut [f64],
    ) -> Result<(), String> {
        let x = |c: usize| HyperDual::new(q[c], a[c], dq[c], 0.0);
        let v = |c: usize| HyperDual::new(qdot[c], b[c], dv[c], 0.0);
        self.forces_along(t, p, x, v, |c, l: HyperDual| out[c] += l.e12)
    }

    /// Every active force's load over the numbers `S` ([`Along`]) at the coordinates `x(column)`
    /// and velocities `v(column)`, its numbers and the parameters along their derivatives with
    /// respect to parameter `p`, each entry scaled as in [`Dae::load`] and given to
    /// `add(column, load)`. `Err` names the first force without derivatives.
    fn forces_along<S: Along>(
        &self,
        t: f64,
        p: usize,
        x: impl Fn(usize) -> S,
        v: impl Fn(usize) -> S,
        mut add: impl FnMut(usize, S),
    ) -> Result<(), String> {
        if self.forces.is_empty() {
            return Ok(());
        }
        let (model, s) = (self.model, self.external_scale);
        let grads = &model.gradients;
        let params: Vec<S> = model.parameters.values().zip(&grads.params).map(|(&v, g)| S::along(v, g[p])).collect();
        for (f, &applied) in self.forces.iter().zip(&self.applied) {
            let k = model.forces.iter().position(|e| std::ptr::eq(e, *f)).expect("an active force is the model's");
            let data: Vec<S> =
                f.force.data().iter().zip(&grads.forces[k]).map(|(&(_, v), g)| S::along(v, g[p])).collect();
            let cols = f.force.columns();
            let x: Vec<S> = cols.iter().map(|&c| x(c)).collect();
            let v: Vec<S> = cols.iter().map(|&c| v(c)).collect();
            let mut load = vec![S::constant(0.0); cols.len()];
            if !S::load(f.force.as_ref(), (&x, &v, t), &data, &params, &mut load) {
                return Err(f.name.clone());
            }
            let scale = S::constant(if applied { s } else { 1.0 });
            for (&c, &l) in cols.iter().zip(&load) {
                add(c, scale * l);
            }
        }
        Ok(())
    }

    /// Gravity's generalised force `(m g, 0)` per body, `(n)`, before [`Dae::external_scale`].
    pub fn gravity_load(&self) -> &[f64] {
        &self.gravity
    }

    /// `dM/dp a`, the derivative of the mass matrix with respect to parameter `p` (file order)
    /// times `a: (n)`, added to `out: (n)`: each body's mass and moment of inertia along their
    /// gradients.
    pub fn add_mass_along(&self, p: usize, a: &[f64], out: &mut [f64]) {
        let bodies = &self.model.gradients.bodies;
        for ((o, a), g) in out.chunks_exact_mut(3).zip(a.chunks_exact(3)).zip(bodies) {
            o[0] += g[0][p] * a[0];
            o[1] += g[0][p] * a[1];
            o[2] += g[1][p] * a[2];
        }
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
            let w = self.work.gather(cols, q0, q1);
            if let Some(r) = contact.event(&self.work.fx[..w], &self.work.fv[..w]) {
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
            let w = self.work.gather(cols, q, qdot);
            let s = contact.state(&self.work.fx[..w], &self.work.fv[..w]);
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
            gather(q, cols, &mut self.work.fx[..w]);
            v += f.force.potential(&self.work.fx[..w]);
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
            let w = self.work.gather(cols, q, qdot);
            p += potential_rate(f.force.as_ref(), &self.work.fx[..w], &self.work.fv[..w], &mut self.work.dual);
        }
        p + self.driver_power(q, t, lambda, nu) + self.friction_power(q, qdot, lambda)
    }

    /// Power of the active forces (not gravity) `Q_e . qdot`, W.
    pub fn applied_power(&mut self, q: &[f64], qdot: &[f64], t: f64) -> f64 {
        let mut p = 0.0;
        for f in &self.forces {
            let cols = f.force.columns();
            let w = self.work.gather(cols, q, qdot);
            f.force.load(&self.work.fx[..w], &self.work.fv[..w], t, &mut self.work.fq[..w]);
            p += self.work.fq[..w].iter().zip(&self.work.fv[..w]).map(|(a, b)| a * b).sum::<f64>();
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
}
