//! The active constraints of one analysis stacked into one system: `Phi (m)`, `Phi_q (m x n)`,
//! `nu (m)`, `gamma (m)`. Rows are ordered joints first, then active drivers, each element's rows
//! in its own order.

use crate::constraints::{Config, Constraint};
use crate::error::{Error, RowName};
use crate::linalg::{ColMatrix, Pattern};
use crate::model::{Element, Model};
use faer::MatMut;

/// The model's length scale `L`, m: the largest distance of a named point from its body's
/// centre of mass (the lever arms that make the angle columns of `Phi_q`), else, for a model
/// without points, the largest distance of a body's guessed position from the origin, else 1.
/// It scales with the model: every length multiplied by `s` multiplies it by `s`.
pub fn length_scale(model: &Model) -> f64 {
    let largest = |v: &mut dyn Iterator<Item = [f64; 2]>| v.map(|p| p[0].hypot(p[1])).fold(0.0f64, f64::max);
    let arms = largest(&mut model.bodies.iter().flat_map(|b| b.points.values().copied()));
    let positions = largest(&mut model.bodies.iter().map(|b| [b.q0[0], b.q0[1]]));
    [arms, positions].into_iter().find(|&l| l > 0.0 && l.is_finite()).unwrap_or(1.0)
}

/// Stacked constraints of an analysis. Evaluation allocates nothing.
#[derive(Debug)]
pub struct System<'m> {
    elements: Vec<&'m Element>,
    /// How many of `elements` are joints (the rest are drivers).
    joints: usize,
    /// (elements + 1) first row of each element; the last entry is `m`.
    offsets: Vec<usize>,
    /// Number of coordinates.
    pub n: usize,
    /// Number of equations.
    pub m: usize,
    /// The model's length scale, m ([`length_scale`]).
    pub length: f64,
    /// (max rows x width) one element's Jacobian block.
    block: Vec<f64>,
}

impl<'m> System<'m> {
    /// The model's joints and the drivers with the given indices.
    pub fn new(model: &'m Model, drivers: &[usize]) -> System<'m> {
        let elements: Vec<&Element> = model.joints.iter().chain(drivers.iter().map(|&d| &model.drivers[d])).collect();
        let mut offsets = vec![0];
        let mut big = 0;
        for e in &elements {
            let c = &e.constraint;
            offsets.push(offsets.last().copied().unwrap_or(0) + c.rows());
            big = big.max(c.rows() * c.columns().len());
        }
        let m = offsets[elements.len()];
        System {
            elements,
            joints: model.joints.len(),
            offsets,
            n: model.n(),
            m,
            length: length_scale(model),
            block: vec![0.0; big],
        }
    }

    fn constraints(&self) -> impl Iterator<Item = (&dyn Constraint, std::ops::Range<usize>)> + '_ {
        self.elements.iter().zip(self.offsets.windows(2)).map(|(e, w)| (e.constraint.as_ref(), w[0]..w[1]))
    }

    /// `(q, t) => Phi`, `out: (m)`.
    pub fn phi(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        for (c, r) in self.constraints() {
            c.phi(q, t, &mut out[r]);
        }
    }

    /// `(q, t) => nu = -Phi_t`, `out: (m)`.
    pub fn nu(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        for (c, r) in self.constraints() {
            c.nu(q, t, &mut out[r]);
        }
    }

    /// `(q, qdot, t) => gamma`, `out: (m)`.
    pub fn gamma(&self, q: &Config<'_>, qdot: &[f64], t: f64, out: &mut [f64]) {
        for (c, r) in self.constraints() {
            c.gamma(q, qdot, t, &mut out[r]);
        }
    }

    /// `(q, t) => Phi_q` as a dense `(m x n)` matrix.
    pub fn jacobian_dense(&mut self, q: &Config<'_>, t: f64, mut out: MatMut<'_, f64>) {
        out.fill(0.0);
        let Self { elements, offsets, block, .. } = self;
        for (e, w) in elements.iter().zip(offsets.windows(2)) {
            let c = e.constraint.as_ref();
            let cols = c.columns();
            let block = &mut block[..c.rows() * cols.len()];
            c.jacobian(q, t, block);
            for (r, row) in (w[0]..w[1]).enumerate() {
                for (k, &col) in cols.iter().enumerate() {
                    out[(row, col)] += block[r * cols.len() + k];
                }
            }
        }
    }

    /// The elements (joints, then active drivers) with their rows.
    pub fn elements(&self) -> impl Iterator<Item = (&'m Element, std::ops::Range<usize>)> + '_ {
        self.elements.iter().zip(self.offsets.windows(2)).map(|(e, w)| (*e, w[0]..w[1]))
    }

    /// `(row, column)` of every entry of every element's Jacobian block, in block order (element
    /// by element, each block row-major over its `columns()`): the layout of
    /// [`System::jacobian_values`].
    pub fn entries(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (c, rows) in self.constraints() {
            for row in rows {
                out.extend(c.columns().iter().map(|&col| (row, col)));
            }
        }
        out
    }

    /// `(q, t) => Phi_q` as the values of [`System::entries`], `out: (entries)`.
    pub fn jacobian_values(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        let mut k = 0;
        for (c, _) in self.constraints() {
            let len = c.rows() * c.columns().len();
            c.jacobian(q, t, &mut out[k..k + len]);
            k += len;
        }
    }

    /// The index in `elements` of the element that owns row `row`.
    fn element_of(&self, row: usize) -> usize {
        self.offsets.partition_point(|&o| o <= row) - 1
    }

    /// The joint (or driver) and equation of row `row`.
    pub fn row_name(&self, row: usize) -> RowName {
        let k = self.element_of(row);
        let c = &self.elements[k].constraint;
        RowName { element: self.elements[k].name.clone(), equation: c.row_names()[row - self.offsets[k]].to_string() }
    }

    /// The element of the first row of `v (m)` (a value of `Phi`, `nu` or `gamma` at `t`) that is
    /// not finite, as an [`Error::NonFinite`] naming its path in the model file (`drivers.motor`)
    /// and its function of time.
    pub fn non_finite(&self, v: &[f64], t: f64) -> Option<Error> {
        let row = v.iter().position(|x| !x.is_finite())?;
        let k = self.element_of(row);
        let e = self.elements[k];
        let section = if k < self.joints { "joints" } else { "drivers" };
        let expression = match (e.constraint.time_function(), e.constraint.non_finite_cause()) {
            (Some(f), _) => f.source().to_string(),
            (None, Some(cause)) => cause.to_string(),
            (None, None) => String::new(),
        };
        Some(Error::NonFinite { time: t, element: format!("{section}.{}", e.name), expression, value: v[row] })
    }

    /// The compressed-column pattern of the rows `selected` (ascending) of `Phi_q`, renumbered
    /// `0..selected.len()`; its map goes from each entry of each element's Jacobian block (in
    /// block order, as [`System::entries`]) to its value, for [`System::fill_jacobian`].
    pub fn pattern(&self, selected: &[usize]) -> Pattern {
        let mut local = vec![None; self.m];
        for (k, &r) in selected.iter().enumerate() {
            local[r] = Some(k);
        }
        let entries = self.entries().into_iter().map(|(row, col)| local[row].map(|r| (r, col)));
        Pattern::new(selected.len(), self.n, entries)
    }

    /// `(q, t) => Phi_q`, every row, compressed by columns; its pattern is built anew each call
    /// (for the setup of an analysis and its diagnoses, not for its steps).
    pub fn jacobian(&mut self, q: &Config<'_>, t: f64) -> ColMatrix {
        let all: Vec<usize> = (0..self.m).collect();
        let pattern = self.pattern(&all);
        let mut values = vec![0.0; pattern.row_idx.len()];
        self.fill_jacobian(&pattern, q, t, &mut values);
        ColMatrix::new(&pattern, values)
    }

    /// `(q, t) => Phi_q` values in `pattern` (from [`System::pattern`]), `values: (nnz)`.
    pub fn fill_jacobian(&mut self, pattern: &Pattern, q: &Config<'_>, t: f64, values: &mut [f64]) {
        values.fill(0.0);
        let mut k = 0;
        let Self { elements, block, .. } = self;
        for e in elements.iter() {
            let c = e.constraint.as_ref();
            let len = c.rows() * c.columns().len();
            let block = &mut block[..len];
            c.jacobian(q, t, block);
            for (&pos, &v) in pattern.map[k..k + len].iter().zip(block.iter()) {
                if pos != usize::MAX {
                    values[pos] += v;
                }
            }
            k += len;
        }
    }

    /// The row with the largest absolute value of `v (m)`, and that value.
    pub fn worst_row(&self, v: &[f64]) -> (RowName, f64) {
        let (k, x) = v
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |(bk, bx), (k, x)| if x.abs() > bx { (k, x.abs()) } else { (bk, bx) });
        (self.row_name(k), x)
    }
}
