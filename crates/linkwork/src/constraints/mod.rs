//! The joint library: one file per joint family, all behind the [`Constraint`] trait.
//!
//! Each constraint contributes `rows()` equations `Phi(q, t) = 0` to the system and supplies, for the
//! columns of `q` it touches, its analytic Jacobian block `Phi_q`, the velocity right-hand side
//! `nu = -Phi_t` and the acceleration right-hand side
//! `gamma = -(Phi_q qdot)_q qdot - 2 Phi_qt qdot - Phi_tt` (Haug 1989, sections 3.3 and 3.4;
//! Nikravesh 2018, chapter 7).
//!
//! Body coordinates: body `k` (ground excluded) owns `q[3k..3k+3] = (x, y, phi)`, the position of
//! its centre of mass and the angle of its frame. A point `P` fixed on body `i` is
//! `r_P = r_i + A(phi_i) s'_P` with `A(phi) = [[cos, -sin], [sin, cos]]`.

mod absolute;
mod distance;
mod driver;
mod expression;
mod gear;
mod point_line;
mod revolute;
mod rolling;
mod translational;

pub use absolute::{Absolute, AbsoluteKind};
pub use distance::Distance;
pub use driver::{Driver, DriverKind};
pub use expression::GeneralConstraint;
pub use gear::{GearKind, GearPair};
pub use point_line::PointOnLine;
pub use revolute::Revolute;
pub use rolling::{RackPinion, RollingDisc};
pub use translational::Translational;

use std::fmt::Debug;

/// One joint, driver or general constraint: a block of rows of `Phi(q, t) = 0`.
///
/// Implementations are immutable after construction and allocate nothing in these methods, which
/// the analysis loops call at every iteration.
pub trait Constraint: Debug + Send + Sync {
    /// Number of equations this constraint adds.
    fn rows(&self) -> usize;
    /// A short name for each row, used when a row is reported as redundant or singular.
    fn row_names(&self) -> &[&'static str];
    /// Global indices into `q` of the coordinates the rows depend on (its Jacobian columns).
    fn columns(&self) -> &[usize];
    /// `(q, t) => Phi`, `out: (rows)`.
    fn phi(&self, q: &[f64], t: f64, out: &mut [f64]);
    /// `(q, t) => Phi_q` restricted to `columns()`, `out: (rows x columns().len())`, row-major.
    fn jacobian(&self, q: &[f64], t: f64, out: &mut [f64]);
    /// `(q, t) => nu = -Phi_t`, `out: (rows)`.
    fn nu(&self, q: &[f64], t: f64, out: &mut [f64]);
    /// `(q, qdot, t) => gamma`, `out: (rows)`.
    fn gamma(&self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]);
}

/// Where a body's coordinates sit in `q`: the index of its `x` (`y` and `phi` follow), or `None`
/// for ground, which has no coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodyIx(pub Option<usize>);

impl BodyIx {
    /// Ground.
    pub const GROUND: BodyIx = BodyIx(None);

    /// `(x, y, phi)` of the body from a coordinate vector (zeros for ground).
    #[inline]
    pub fn coords(self, q: &[f64]) -> [f64; 3] {
        match self.0 {
            Some(k) => [q[k], q[k + 1], q[k + 2]],
            None => [0.0; 3],
        }
    }
}

/// The pose of a body frame: origin and rotation `A(phi)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub x: f64,
    pub y: f64,
    pub phi: f64,
    pub c: f64,
    pub s: f64,
}

impl Frame {
    #[inline]
    pub fn of(body: BodyIx, q: &[f64]) -> Frame {
        let [x, y, phi] = body.coords(q);
        let (s, c) = phi.sin_cos();
        Frame { x, y, phi, c, s }
    }
    /// `A s'`: a body-frame vector in the global frame.
    #[inline]
    pub fn rotate(&self, v: [f64; 2]) -> [f64; 2] {
        [self.c * v[0] - self.s * v[1], self.s * v[0] + self.c * v[1]]
    }
    /// `B s' = dA/dphi s' = R90 A s'`.
    #[inline]
    pub fn rotate_d(&self, v: [f64; 2]) -> [f64; 2] {
        [-self.s * v[0] - self.c * v[1], self.c * v[0] - self.s * v[1]]
    }
    /// `r + A s'`: a body point in the global frame.
    #[inline]
    pub fn point(&self, v: [f64; 2]) -> [f64; 2] {
        let a = self.rotate(v);
        [self.x + a[0], self.y + a[1]]
    }
}

/// `R90 v`: `v` turned by +90 degrees.
#[inline]
pub(crate) fn perp(v: [f64; 2]) -> [f64; 2] {
    [-v[1], v[0]]
}

#[inline]
pub(crate) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The two bodies of a joint and the Jacobian columns they own.
///
/// Joint code computes full `1 x 3` Jacobian blocks for both bodies; [`Pair::scatter`] keeps the
/// blocks of bodies that have coordinates, in the order of [`Pair::columns`].
#[derive(Debug, Clone)]
pub(crate) struct Pair {
    pub i: BodyIx,
    pub j: BodyIx,
    columns: Vec<usize>,
}

impl Pair {
    pub fn new(i: BodyIx, j: BodyIx) -> Pair {
        let columns = [i, j]
            .iter()
            .filter_map(|b| b.0)
            .flat_map(|k| [k, k + 1, k + 2])
            .collect();
        Pair { i, j, columns }
    }
    pub fn columns(&self) -> &[usize] {
        &self.columns
    }
    /// Write one Jacobian row from the blocks of body i and body j into `out` (the row's slice).
    #[inline]
    pub fn scatter(&self, row_i: [f64; 3], row_j: [f64; 3], out: &mut [f64]) {
        let mut k = 0;
        if self.i.0.is_some() {
            out[..3].copy_from_slice(&row_i);
            k = 3;
        }
        if self.j.0.is_some() {
            out[k..k + 3].copy_from_slice(&row_j);
        }
    }
    /// Number of Jacobian columns (0, 3 or 6).
    #[inline]
    pub fn width(&self) -> usize {
        self.columns.len()
    }
}

#[cfg(test)]
pub(crate) mod testing;
