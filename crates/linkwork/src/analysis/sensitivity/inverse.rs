//! Design sensitivities of an inverse dynamic analysis: the derivatives of the multipliers, and
//! from them of the reactions, the efforts, the energies and powers and the measures, at each
//! output time (docs/sensitivities.md, "Inverse dynamics").
//!
//! The motion's derivatives `q_p`, `qdot_p`, `qddot_p` are the kinematic analysis's
//! ([`Sensitivity::motion`]). Differentiating `Phi_q^T lambda = Q - M qddot` with respect to `p`:
//!
//! ```text
//! Phi_q^T lambda_p = Q_p - M_p qddot - M qddot_p - (Phi_q)_p^T lambda = b_p
//! ```
//!
//! with `Q_p` total (gravity through the masses, the forces through their coordinates, numbers
//! and parameters: [`Dae::add_load_along`]), `M_p` along the masses' gradients
//! ([`Dae::add_mass_along`]) and `(Phi_q)_p` the total derivative of the Jacobian along `q_p`,
//! the elements' numbers and the parameters: each element's rows over [`HyperDual`] numbers,
//! one direction a coordinate of the element, the other the parameter. The analysis takes the
//! minimum-norm `lambda = A^+ b` of `A = Phi_q^T` (full row rank); its derivative is
//!
//! ```text
//! lambda_p = A^+ (b_p - (Phi_q)_p^T lambda) + (I - A^+ A) (Phi_q)_p y,   Phi_q y = lambda
//! ```
//!
//! (the derivative of the pseudo-inverse of a matrix of constant full row rank); the second term
//! is zero without redundant rows (`m = n`, where `A^+ A = I`), and is computed only with them,
//! as `z - A^+ (Phi_q^T z)` with `z = (Phi_q)_p y`. Without redundant rows `Phi_q` is square and
//! regular and `A^+ b_p` is one transposed solve with the kinematic analysis's factorization;
//! with them every solve is the analysis's own minimum-norm solve in the row space it has
//! already factored.

use super::friction::FrictionAlong;
use super::{by_column, Level, Seeded, Sensitivity};
use crate::analysis::dynamic::Dae;
use crate::analysis::measure_reactions;
use crate::constraints::{lever, reaction_about, At, POINT, POINT_I};
use crate::error::{Error, Problem};
use crate::expr::{Dual, HyperDual, Scalar};
use crate::linalg::rows::RowSpace;
use crate::linalg::SparseLu;
use crate::model::Analysis;

/// Where an output time's values are, for its derivatives: the time, the motion, the
/// multipliers and the reactions row of [`Dae::reactions`].
pub(crate) struct InverseAt<'a> {
    /// The time and `(q, qdot, qddot)`.
    pub t: f64,
    pub x: (&'a [f64], &'a [f64], &'a [f64]),
    /// `(m)` the multipliers.
    pub lambda: &'a [f64],
    /// The reactions and efforts, [`Dae::reactions`]' row.
    pub react: &'a [f64],
}

/// The buffers of an inverse analysis's sensitivities.
pub(crate) struct InverseSensitivity {
    /// Each element's Jacobian block (rows x columns, row-major, elements in the system's order)
    /// and its derivative along the parameter.
    block: Vec<f64>,
    dblock: Vec<f64>,
    /// (m) `-d(Phi_t)/dp` of the drivers' rows (`nu_p`; zero on the joints').
    dnu: Vec<f64>,
    /// (n) scratch: the right-hand side, the forces' derivative, `M_p` times a vector.
    rhs: Vec<f64>,
    forces: Vec<f64>,
    scratch: Vec<f64>,
    /// (m) scratch: `(Phi_q)_p y` with redundant rows, and the derivatives of the reactions
    /// row in the measures' layout.
    z: Vec<f64>,
    react: Vec<f64>,
    measured: Vec<f64>,
    nu: Vec<f64>,
    /// The analysis's drivers (indices into the model's), for the measures' reactions row.
    drivers: Vec<usize>,
}

/// The error at `path` for something asked to have design sensitivities that has none yet.
fn unsupported(path: String, what: &str) -> Error {
    Error::Model(vec![Problem::new(
        path,
        format!("{what} has no design sensitivities yet (asked for with `sensitivities`)"),
    )])
}

impl InverseSensitivity {
    /// The buffers for `s`'s elements on `dae`; an error at `sensitivities`' cause when
    /// something in the analysis has no derivatives yet: an active force whose load or potential
    /// has none (at the force).
    pub(crate) fn new(s: &Sensitivity<'_>, dae: &Dae<'_>, analysis: &Analysis) -> Result<InverseSensitivity, Error> {
        let model = dae.model;
        let (n, m) = (dae.n, dae.m);
        let q = model.q0();
        let zero = vec![0.0; n];
        let mut out = vec![0.0; n];
        for &p in &s.asked {
            dae.add_forces_along((&q, &zero, analysis.t_start), (&zero, &zero), p, &mut out)
                .map_err(|name| unsupported(format!("forces.{name}"), "this force"))?;
            let potential = |name: String| unsupported(format!("forces.{name}"), "this force's potential energy");
            dae.potential_energy_along(&q, &zero, p).map_err(potential)?;
        }
        let entries: usize = s.elements.iter().map(|e| e.constraint.rows() * e.constraint.columns().len()).sum();
        Ok(InverseSensitivity {
            block: vec![0.0; entries],
            dblock: vec![0.0; entries],
            dnu: vec![0.0; m],
            rhs: vec![0.0; n],
            forces: vec![0.0; n],
            scratch: vec![0.0; n],
            z: vec![0.0; m],
            react: Vec::new(),
            measured: Vec::new(),
            nu: vec![0.0; m],
            drivers: analysis.drivers.clone(),
        })
    }

    /// The derivatives with respect to parameter `p` of the inverse analysis's columns after the
    /// bodies' at `at` (the reactions and efforts, the energies and powers, the measures),
    /// appended to `row`; `dae` at `at`'s positions, `space` the row space of `Phi_q` there and
    /// `lu` the kinematic analysis's factorization of its independent rows (all of them when
    /// none is redundant, in order).
    pub(crate) fn push(
        &mut self,
        s: &mut Sensitivity<'_>,
        dae: &mut Dae<'_>,
        (space, lu): (&mut RowSpace, &mut SparseLu),
        at: &InverseAt<'_>,
        p: usize,
        row: &mut Vec<f64>,
    ) -> Result<(), Error> {
        let (t, (q, qdot, qddot), lambda) = (at.t, at.x, at.lambda);
        let (n, m) = (dae.n, dae.m);
        let [dq, dv, da] = s.motion().clone();
        self.jacobian_along(s, p, t, q, &dq);
        // b_p = Q_p - M_p qddot - M qddot_p - (Phi_q)_p^T lambda.
        self.forces.fill(0.0);
        let force = |name: String| unsupported(format!("forces.{name}"), "this force");
        dae.add_forces_along((q, qdot, t), (&dq, &dv), p, &mut self.forces).map_err(force)?;
        self.rhs.copy_from_slice(&self.forces);
        dae.add_gravity_along(p, &mut self.rhs);
        self.scratch.fill(0.0);
        dae.add_mass_along(p, qddot, &mut self.scratch);
        for (k, b) in self.rhs.iter_mut().enumerate() {
            *b -= self.scratch[k] + dae.mass[k] * da[k];
        }
        let rhs = &mut self.rhs;
        for_blocks(&s.elements, &self.dblock, |cols, rows, block| {
            for (r, row) in rows.enumerate() {
                for (ci, &c) in cols.iter().enumerate() {
                    rhs[c] -= block[r * cols.len() + ci] * lambda[row];
                }
            }
        });
        // Joint friction's derivative at the multipliers held; its part through them follows
        // the solve.
        let friction = dae
            .has_friction()
            .then(|| FrictionAlong::new(s.model, p, (q, &dq), (qdot, &dv), (&self.block, &self.dblock)));
        if let Some(f) = &friction {
            f.add_held(dae, lambda, &mut self.rhs);
        }
        let solve_failed = || Error::Singular {
            time: t,
            rows: vec![],
            detail: "the singular value decomposition of the constraint Jacobian failed (a non-finite entry)".into(),
        };
        // With redundant rows: z = (Phi_q)_p y, and b_p - Phi_q^T z.
        let redundant = m > n;
        if redundant {
            let y = space.min_norm_solve(lambda).ok_or_else(solve_failed)?;
            let z = &mut self.z;
            for_blocks(&s.elements, &self.dblock, |cols, rows, block| {
                for (r, row) in rows.enumerate() {
                    z[row] = cols.iter().enumerate().map(|(ci, &c)| block[r * cols.len() + ci] * y[c]).sum::<f64>();
                }
            });
            self.scratch.fill(0.0);
            dae.add_jt(&self.z, &mut self.scratch);
            self.rhs.iter_mut().zip(&self.scratch).for_each(|(b, a)| *b -= a);
        }
        let dlambda = if redundant {
            let mut dlambda = space.min_norm_transpose_solve(&self.rhs).ok_or_else(solve_failed)?;
            dlambda.iter_mut().zip(&self.z).for_each(|(l, z)| *l += z);
            dlambda
        } else {
            // Square and regular: the one solution, with the kinematic analysis's factors.
            let mut dlambda = self.rhs.clone();
            lu.solve_transpose(&mut dlambda);
            dlambda
        };
        let mut dlambda = dlambda;
        if friction.is_some() {
            let transpose_solve = |x: &[f64]| {
                if redundant {
                    space.min_norm_transpose_solve(x).ok_or_else(solve_failed)
                } else {
                    let mut y = x.to_vec();
                    lu.solve_transpose(&mut y);
                    Ok(y)
                }
            };
            FrictionAlong::through_multipliers(dae, (q, qdot, lambda), &mut dlambda, transpose_solve)?;
        }
        // The reactions and efforts, in the layout of [`Dae::reactions`].
        let qd: Vec<Dual> = q.iter().zip(&dq).map(|(&v, &d)| Dual::new(v, d)).collect();
        self.react.clear();
        let joints = s.model.joints.len();
        let mut offset = 0;
        for (k, e) in s.elements.iter().enumerate() {
            let c = e.constraint;
            let (cols, rows) = (c.columns(), e.row..e.row + c.rows());
            let size = rows.len() * cols.len();
            let (block, dblock) = (&self.block[offset..offset + size], &self.dblock[offset..offset + size]);
            offset += size;
            if k >= joints {
                self.react.push(-dlambda[e.row]);
                continue;
            }
            let l: Vec<Dual> = rows.clone().map(|r| Dual::new(lambda[r], dlambda[r])).collect();
            let anchor = c.anchor();
            let point = anchor_point(e, anchor.point, p);
            let (f, torque) =
                reaction_about(anchor, cols, |i| Dual::new(block[i], dblock[i]), &l, lever(anchor, point, &qd));
            self.react.extend([f[0].d, f[1].d, torque.d]);
        }
        if let Some(f) = &friction {
            f.values(dae, lambda, &dlambda, &mut self.react);
        }
        row.extend_from_slice(&self.react);
        // The energies and powers (INVERSE_COLUMNS).
        self.scratch.fill(0.0);
        dae.add_mass_along(p, qdot, &mut self.scratch);
        let kinetic: f64 = (0..n).map(|k| 0.5 * self.scratch[k] * qdot[k] + dae.mass[k] * qdot[k] * dv[k]).sum();
        let potential = dae
            .potential_energy_along(q, &dq, p)
            .map_err(|name| unsupported(format!("forces.{name}"), "this force's potential energy"))?;
        let first_driver = s.elements.get(joints).map_or(m, |e| e.row);
        dae.nu(q, t, &mut self.nu);
        let driver: f64 = -(first_driver..m).map(|r| dlambda[r] * self.nu[r] + lambda[r] * self.dnu[r]).sum::<f64>();
        let applied = if dae.forces.is_empty() {
            0.0
        } else {
            // The forces' load is the total less gravity's.
            dae.load(q, qdot, t, &mut self.scratch);
            let forces = self.scratch.iter().zip(dae.gravity_load()).map(|(a, g)| a - g);
            self.forces.iter().zip(qdot).map(|(f, v)| f * v).sum::<f64>()
                + forces.zip(&dv).map(|(f, d)| f * d).sum::<f64>()
        };
        row.extend([kinetic, potential, driver, applied]);
        // The measures, with the reactions row along its derivatives.
        if !s.model.measures.is_empty() {
            measure_reactions(s.model, &self.drivers, &self.react, &mut self.measured);
            let mut values = Vec::new();
            measure_reactions(s.model, &self.drivers, at.react, &mut values);
            let reactions: Vec<Dual> = values.iter().zip(&self.measured).map(|(&v, &d)| Dual::new(v, d)).collect();
            s.measures(p, t, at.x, &reactions, row);
        }
        Ok(())
    }

    /// Each element's Jacobian block and its derivative along parameter `p` at `(q, t)`, the
    /// coordinates moving along `dq` ([`InverseSensitivity::block`], `dblock`), and the
    /// drivers' `nu_p` ([`InverseSensitivity::dnu`]): per element, one [`HyperDual`]
    /// evaluation of its rows per column (the first direction that coordinate, the second the
    /// parameter), and for a driver one more with the first direction the time.
    fn jacobian_along(&mut self, s: &mut Sensitivity<'_>, p: usize, t: f64, q: &[f64], dq: &[f64]) {
        let Sensitivity { model, elements, velocity: b, .. } = s;
        let mut offsets = Vec::with_capacity(elements.len());
        elements.iter().fold(0, |offset, e| {
            offsets.push(offset);
            offset + e.constraint.rows() * e.constraint.columns().len()
        });
        let (block, dblock) = (&mut self.block, &mut self.dblock);
        by_column(b, elements.iter().enumerate(), model, p, t, (q, dq), |k, e, c, rows| {
            let width = e.constraint.columns().len();
            for (r, h) in rows.iter().enumerate() {
                block[offsets[k] + r * width + c] = h.e1;
                dblock[offsets[k] + r * width + c] = h.e12;
            }
        });
        // The drivers' rows once more with the first direction the time (`by_column` left the
        // coordinates and the parameters seeded along the parameter).
        for e in &elements[model.joints.len()..] {
            b.data.clear();
            b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| HyperDual::fixed(v, g[p])));
            let at = At { q: &b.q, t: HyperDual::new(t, 1.0, 0.0, 0.0), params: &b.params };
            e.constraint.phi_hyper(&at, &b.data, &mut b.full[e.row..]);
            for r in e.row..e.row + e.constraint.rows() {
                self.dnu[r] = -b.full[r].e12;
            }
        }
    }
}

/// `f(columns, rows, block)` for each element, with its part of `blocks` (the elements' Jacobian
/// blocks, or their derivatives, one after the other).
fn for_blocks(elements: &[Seeded<'_>], blocks: &[f64], mut f: impl FnMut(&[usize], std::ops::Range<usize>, &[f64])) {
    let mut offset = 0;
    for e in elements {
        let c = e.constraint;
        let size = c.rows() * c.columns().len();
        f(c.columns(), e.row..e.row + c.rows(), &blocks[offset..offset + size]);
        offset += size;
    }
}

/// The point of element `e` about which its reaction's moment is taken (`point`, its anchor's),
/// along its derivative with respect to parameter `p`: the element's `point_i` (or `point`, an
/// absolute joint's) when that is one of its numbers, as every joint with a point has it; held
/// otherwise (the origin of a belt's, an expression's or a relative angle's first body).
pub(super) fn anchor_point(e: &Seeded<'_>, point: [f64; 2], p: usize) -> [Dual; 2] {
    let names: Vec<&str> = e.constraint.data().iter().map(|&(name, _)| name).collect();
    let slot = names.iter().position(|&name| name == POINT_I[0] || name == POINT[0]);
    match slot {
        Some(k) => {
            debug_assert_eq!([e.data[k], e.data[k + 1]], point, "{}: the anchor is its point", e.name);
            [Dual::new(point[0], e.grads[k][p]), Dual::new(point[1], e.grads[k + 1][p])]
        }
        None => point.map(Dual::constant),
    }
}
