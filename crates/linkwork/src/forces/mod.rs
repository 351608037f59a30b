//! Applied forces and force elements: one file per family, all behind the [`Force`] trait.
//!
//! A force element acts on, and may depend on, a few coordinates: its `columns()`. Given
//! `x = q[columns]`, `v = qdot[columns]` and `t`, it returns its generalised force
//! `Q_e (columns)`: for a force `f` at a point `P` of body `i`, `Q_i = (f, (A_i s'_P) x f)`
//! (Haug 1989 section 6.2; Nikravesh 2018 chapter 10). The laws are written once, generically
//! over [`Scalar`], so the same code gives the value (`f64`) and, over [`Dual`] numbers, the exact
//! derivatives `dQ/dq` and `dQ/dqdot` the implicit integrators need (no finite differences).
//!
//! Gravity is not an element: it is constant, `Q_i = (m_i g, 0)`, added by the dynamics.

mod contact;
mod point;
mod registry;
mod schema;
mod spring;
mod state_expr;

pub use contact::{CircleShape, Contact, ContactFriction, ContactSpec, ContactState, Shape, ShapeSpec};
pub use point::{ForceFrame, PointForce, PointLoad, Torque, TorqueSpec};
pub use registry::ForceSpec;
pub(crate) use schema::ForceContext;
pub use schema::Quantity;
pub use spring::{RotationalSpringDamper, RotationalSpringDamperSpec, SpringDamper, SpringDamperSpec};
pub use state_expr::{Load, StateExpr, StateVar};

use crate::expr::{Dual, HyperDual, Scalar};
use std::fmt::Debug;

/// A force law written once over any [`Scalar`]; [`Force`] follows from it.
pub trait ForceLaw: Debug + Send + Sync {
    /// Global indices into `q` of the coordinates the force depends on or acts on.
    fn columns(&self) -> &[usize];
    /// `(x, v, t) => Q_e`: the generalised force on `columns()`, `x = q[columns]`,
    /// `v = qdot[columns]`, `out: (columns)`.
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]);
    /// `x => V`: potential energy of the conservative part of the force (springs), J. The work of
    /// the rest is counted as non-conservative.
    fn potential<S: Scalar>(&self, x: &[S]) -> S;
    /// The expressions the force evaluates, as `(field, source)` (for messages); none by default.
    fn expressions(&self) -> Vec<(&'static str, &str)> {
        Vec::new()
    }
    /// Whether the force is conservative: all its work is the change of [`ForceLaw::potential`]
    /// (an undamped spring without actuator). No by default.
    fn conservative(&self) -> bool {
        false
    }
    /// The contact this force is, if it is one (for its events and output columns).
    fn contact(&self) -> Option<&Contact> {
        None
    }
    /// Whether it is a load applied as such to one body (a force or torque), rather than a force
    /// element between bodies (a mechanical advantage reads only those). No by default.
    fn applied(&self) -> bool {
        false
    }
    /// The numbers of the force a parameter can move, named after their model-file fields
    /// (`stiffness`, `point_i[0]`, ...), in the order [`ForceLaw::load_data`] reads them. None
    /// by default.
    fn data(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// `Q_e` as [`ForceLaw::load`], with the force's numbers `data` ([`ForceLaw::data`] order)
    /// and the model's parameters `params` as inputs too, for design sensitivities
    /// (docs/sensitivities.md). `false`, and `out` untouched, when the force has no derivatives
    /// with respect to its data yet (the default).
    fn load_data<S: Scalar>(&self, _x: &[S], _v: &[S], _t: f64, _data: &[S], _params: &[S], _out: &mut [S]) -> bool {
        false
    }
    /// [`ForceLaw::potential`] with the force's numbers `data` ([`ForceLaw::data`] order) and
    /// the model's parameters `params` as inputs too, for the potential energy's design
    /// sensitivity. `None` when the force has no such derivatives yet (the default).
    fn potential_data<S: Scalar>(&self, _x: &[S], _data: &[S], _params: &[S]) -> Option<S> {
        None
    }
}

/// An applied force or force element, object-safe (see [`ForceLaw`]).
pub trait Force: Debug + Send + Sync {
    /// Global indices into `q` of the coordinates the force depends on or acts on.
    fn columns(&self) -> &[usize];
    /// `(x, v, t) => Q_e`, `out: (columns)`.
    fn load(&self, x: &[f64], v: &[f64], t: f64, out: &mut [f64]);
    /// The same over dual numbers, for exact derivatives.
    fn load_dual(&self, x: &[Dual], v: &[Dual], t: f64, out: &mut [Dual]);
    /// Potential energy, J.
    fn potential(&self, x: &[f64]) -> f64;
    /// Potential energy over dual numbers: its `d` part is `dV/dx . dx`.
    fn potential_dual(&self, x: &[Dual]) -> Dual;
    /// The expressions the force evaluates, as `(field, source)` (for messages).
    fn expressions(&self) -> Vec<(&'static str, &str)>;
    /// The contact this force is, if it is one.
    fn contact(&self) -> Option<&Contact>;
    /// Whether all its work is the change of its potential.
    fn conservative(&self) -> bool;
    /// Whether it is a load applied as such to one body ([`ForceLaw::applied`]).
    fn applied(&self) -> bool;
    /// The numbers a parameter can move ([`ForceLaw::data`]).
    fn data(&self) -> Vec<(&'static str, f64)>;
    /// [`ForceLaw::load_data`] over dual numbers: first derivatives along one direction of the
    /// coordinates, the data and the parameters.
    fn load_data_dual(&self, x: &[Dual], v: &[Dual], t: f64, data: &[Dual], params: &[Dual], out: &mut [Dual]) -> bool;
    /// [`ForceLaw::load_data`] over hyper-dual numbers: second derivatives, mixed in two
    /// directions (the stiffness's derivative along a parameter).
    fn load_data_hyper(
        &self,
        x: &[HyperDual],
        v: &[HyperDual],
        t: f64,
        data: &[HyperDual],
        params: &[HyperDual],
        out: &mut [HyperDual],
    ) -> bool;
    /// [`ForceLaw::potential_data`] over dual numbers: its derivative along one direction of the
    /// coordinates, the data and the parameters.
    fn potential_data_dual(&self, x: &[Dual], data: &[Dual], params: &[Dual]) -> Option<Dual>;
}

impl<T: ForceLaw> Force for T {
    fn columns(&self) -> &[usize] {
        ForceLaw::columns(self)
    }
    fn load(&self, x: &[f64], v: &[f64], t: f64, out: &mut [f64]) {
        ForceLaw::load(self, x, v, t, out)
    }
    fn load_dual(&self, x: &[Dual], v: &[Dual], t: f64, out: &mut [Dual]) {
        ForceLaw::load(self, x, v, t, out)
    }
    fn potential(&self, x: &[f64]) -> f64 {
        ForceLaw::potential(self, x)
    }
    fn potential_dual(&self, x: &[Dual]) -> Dual {
        ForceLaw::potential(self, x)
    }
    fn expressions(&self) -> Vec<(&'static str, &str)> {
        ForceLaw::expressions(self)
    }
    fn contact(&self) -> Option<&Contact> {
        ForceLaw::contact(self)
    }
    fn conservative(&self) -> bool {
        ForceLaw::conservative(self)
    }
    fn applied(&self) -> bool {
        ForceLaw::applied(self)
    }
    fn data(&self) -> Vec<(&'static str, f64)> {
        ForceLaw::data(self)
    }
    fn load_data_dual(&self, x: &[Dual], v: &[Dual], t: f64, data: &[Dual], params: &[Dual], out: &mut [Dual]) -> bool {
        ForceLaw::load_data(self, x, v, t, data, params, out)
    }
    fn load_data_hyper(
        &self,
        x: &[HyperDual],
        v: &[HyperDual],
        t: f64,
        data: &[HyperDual],
        params: &[HyperDual],
        out: &mut [HyperDual],
    ) -> bool {
        ForceLaw::load_data(self, x, v, t, data, params, out)
    }
    fn potential_data_dual(&self, x: &[Dual], data: &[Dual], params: &[Dual]) -> Option<Dual> {
        ForceLaw::potential_data(self, x, data, params)
    }
}

/// Where a body's `(x, y, phi)` sit among a force's local columns (`None` for ground).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Local(pub Option<usize>);

impl Local {
    /// `(x, y, phi)` of the body from the local values (zeros for ground).
    #[inline]
    pub fn pose<S: Scalar>(self, x: &[S]) -> [S; 3] {
        match self.0 {
            Some(k) => [x[k], x[k + 1], x[k + 2]],
            None => [S::constant(0.0); 3],
        }
    }
    /// Add `(fx, fy, torque)` to the body's local entries of `out` (nothing for ground).
    #[inline]
    pub fn add<S: Scalar>(self, out: &mut [S], q: [S; 3]) {
        if let Some(k) = self.0 {
            for (o, v) in out[k..k + 3].iter_mut().zip(q) {
                *o = *o + v;
            }
        }
    }
}

/// `A(phi) s'` for a scalar angle: a body-frame vector in the global frame.
#[inline]
pub(crate) fn rotate<S: Scalar>(phi: S, s: [S; 2]) -> [S; 2] {
    let (c, sn) = (phi.cos(), phi.sin());
    [c * s[0] - sn * s[1], sn * s[0] + c * s[1]]
}

/// A force's numbers ([`ForceLaw::data`] order) read one after the other by
/// [`ForceLaw::load_data`].
pub(crate) struct Data<'a, S> {
    data: &'a [S],
    at: usize,
}

impl<'a, S: Scalar> Data<'a, S> {
    /// The numbers `data`, from the first.
    pub fn new(data: &'a [S]) -> Data<'a, S> {
        Data { data, at: 0 }
    }
    /// The next number.
    #[inline]
    pub fn next(&mut self) -> S {
        self.at += 1;
        self.data[self.at - 1]
    }
    /// The next two numbers (a vector's components).
    #[inline]
    pub fn pair(&mut self) -> [S; 2] {
        [self.next(), self.next()]
    }
    /// The next `n` numbers.
    pub fn take(&mut self, n: usize) -> &'a [S] {
        self.at += n;
        &self.data[self.at - n..self.at]
    }
    /// All the numbers (for [`crate::element::Source::value`], which reads the last).
    pub fn all(&self) -> &'a [S] {
        self.data
    }
}

/// `a x b`, the z component.
#[inline]
pub(crate) fn cross<S: Scalar>(a: [S; 2], b: [S; 2]) -> S {
    a[0] * b[1] - a[1] * b[0]
}

/// The local columns of a force on bodies `bodies` (global offsets of their `x`, `None` for
/// ground) followed by the columns of its expressions not already among them; returns the
/// columns and each body's local offset.
pub(crate) fn layout(bodies: &[Option<usize>], loads: &mut [&mut Load]) -> (Vec<usize>, Vec<Local>) {
    let mut columns = Vec::new();
    let locals = bodies
        .iter()
        .map(|b| {
            Local(b.map(|g| {
                let at = columns.len();
                columns.extend([g, g + 1, g + 2]);
                at
            }))
        })
        .collect();
    for l in loads.iter_mut() {
        l.localize(&mut columns);
    }
    (columns, locals)
}

/// Work space of [`derivatives`] for forces of up to `width` columns.
#[derive(Debug, Clone)]
pub struct DualWork {
    x: Vec<Dual>,
    v: Vec<Dual>,
    out: Vec<Dual>,
}

impl DualWork {
    /// Buffers for forces with at most `width` columns.
    pub fn new(width: usize) -> DualWork {
        let z = Dual::new(0.0, 0.0);
        DualWork { x: vec![z; width], v: vec![z; width], out: vec![z; width] }
    }
}

/// `(x, v, t) => (dQ_e/dx, dQ_e/dv)` exactly, one dual pass per column and per velocity;
/// `dx`, `dv`: `(w x w)` row-major with `w = columns().len()`, entry `[r * w + c]` the derivative
/// of `Q_e[r]` by local column `c`.
pub fn derivatives(f: &dyn Force, x: &[f64], v: &[f64], t: f64, dx: &mut [f64], dv: &mut [f64], work: &mut DualWork) {
    let w = x.len();
    let (xd, vd, out) = (&mut work.x[..w], &mut work.v[..w], &mut work.out[..w]);
    for k in 0..w {
        xd[k] = Dual::new(x[k], 0.0);
        vd[k] = Dual::new(v[k], 0.0);
    }
    for c in 0..w {
        xd[c].d = 1.0;
        f.load_dual(xd, vd, t, out);
        xd[c].d = 0.0;
        for r in 0..w {
            dx[r * w + c] = out[r].d;
        }
        vd[c].d = 1.0;
        f.load_dual(xd, vd, t, out);
        vd[c].d = 0.0;
        for r in 0..w {
            dv[r * w + c] = out[r].d;
        }
    }
}

/// `dV/dt = dV/dx . v` of the force's potential, by one dual pass.
pub fn potential_rate(f: &dyn Force, x: &[f64], v: &[f64], work: &mut DualWork) -> f64 {
    let w = x.len();
    let xd = &mut work.x[..w];
    for k in 0..w {
        xd[k] = Dual::new(x[k], v[k]);
    }
    f.potential_dual(xd).d
}

#[cfg(test)]
pub(crate) mod testing;
