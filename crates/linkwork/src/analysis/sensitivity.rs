//! Design sensitivities of a kinematic analysis: the derivatives of every column with respect to
//! the parameters asked, at each output time, by implicit differentiation of the constraint
//! equations with the factorization the analysis already has (docs/sensitivities.md).
//!
//! With `p` a parameter and every element's `Phi(q, t; d(p), p) = 0` along the motion, the
//! position, velocity and acceleration equations differentiated with respect to `p` are
//!
//! ```text
//! Phi_q q_p     = -(Phi_p)                                   (position)
//! Phi_q qdot_p  = -(d/dp (Phi_q qdot - nu))  with qdot_p = 0  (velocity)
//! Phi_q qddot_p = -(d/dp (Phi_q qddot - gamma)) with qddot_p = 0   (acceleration)
//! ```
//!
//! Each right-hand side is one part of `Phi` evaluated over [`Tri`] numbers seeded with the
//! time direction twice (`e1`, `e2`: `q` along `qdot`, `e12` along `qddot`, `t` along 1) and the
//! parameter's direction (`e3`: `q` along `q_p`, `e13` and `e23` along `qdot_p`, `e123` along
//! `qddot_p`; each element's numbers and the parameters along their gradients): its `e3`, `e13`
//! and `e123` parts, each evaluated with the unknown of its level zero. The square system of
//! the independent rows is the one the analysis solves; rows it found redundant hold
//! implicitly. The measures follow from one more evaluation over the same numbers.

use crate::constraints::{At, Constraint};
use crate::error::{Error, Problem};
use crate::expr::{Scalar, Tri};
use crate::linalg::SparseLu;
use crate::model::{Analysis, Model};
use crate::results::Results;

/// One element of the system with its numbers and their gradients.
struct Seeded<'m> {
    /// Its name, for messages.
    name: &'m str,
    /// Its type in the model file, for messages.
    kind: &'static str,
    constraint: &'m dyn Constraint,
    /// Its first row in the system.
    row: usize,
    /// Its numbers ([`Constraint::data`]) and, for each, the gradient over the parameters.
    data: Vec<f64>,
    grads: &'m [Vec<f64>],
}

/// The sensitivities of a kinematic analysis: its elements, the parameters asked, and the
/// buffers of one output time.
pub(crate) struct Sensitivity<'m> {
    model: &'m Model,
    /// The parameters asked: indices (file order) and names.
    asked: Vec<usize>,
    names: Vec<String>,
    elements: Vec<Seeded<'m>>,
    /// (m) the system's rows over `Tri`.
    full: Vec<Tri>,
    /// (n) coordinates over `Tri`.
    q: Vec<Tri>,
    /// (parameters) over `Tri`, and the element's numbers.
    params: Vec<Tri>,
    data: Vec<Tri>,
    /// (n) a right-hand side in the independent rows.
    rhs: Vec<f64>,
    /// (n) `q_p`, `qdot_p`, `qddot_p` of the parameter being solved for.
    dq: [Vec<f64>; 3],
    /// (parameters) each one's row of derivatives of every column.
    rows: Vec<Vec<f64>>,
}

/// A number that depends on the parameters only, `v` with derivative `g` along the parameter.
fn fixed(v: f64, g: f64) -> Tri {
    Tri::trajectory([v, 0.0, 0.0], [g, 0.0, 0.0])
}

impl<'m> Sensitivity<'m> {
    /// The sensitivities of `analysis` of `model` with respect to the parameters `asked`
    /// (indices, file order). An element or measure with no derivatives yet is an error naming it.
    pub(crate) fn new(model: &'m Model, analysis: &Analysis, asked: &[usize]) -> Result<Sensitivity<'m>, Error> {
        let grads = &model.gradients;
        let joints = model.joints.iter().zip(&grads.joints);
        let drivers = analysis.drivers.iter().map(|&d| (&model.drivers[d], &grads.drivers[d]));
        let mut elements = Vec::new();
        let mut row = 0;
        for (element, grads) in joints.chain(drivers) {
            let data: Vec<f64> = element.constraint.data().iter().map(|&(_, v)| v).collect();
            elements.push(Seeded {
                name: &element.name,
                kind: element.kind,
                constraint: element.constraint.as_ref(),
                row,
                data,
                grads,
            });
            row += element.constraint.rows();
        }
        let n = model.n();
        let names = asked.iter().map(|&k| model.parameters.get_index(k).map_or_else(String::new, |(p, _)| p.clone()));
        let sensitivity = Sensitivity {
            model,
            asked: asked.to_vec(),
            names: names.collect(),
            elements,
            full: vec![Tri::constant(0.0); row],
            q: vec![Tri::constant(0.0); n],
            params: model.parameters.values().map(|&v| Tri::constant(v)).collect(),
            data: Vec::new(),
            rhs: vec![0.0; n],
            dq: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            rows: vec![Vec::new(); asked.len()],
        };
        sensitivity.supported()?;
        Ok(sensitivity)
    }

    /// An error naming the first element or measure that has no derivatives yet.
    fn supported(&self) -> Result<(), Error> {
        let unsupported = |path: String, what: &str| {
            Err(Error::Model(vec![Problem::new(
                path,
                format!("{what} has no design sensitivities yet (asked for with `sensitivities`)"),
            )]))
        };
        let n = self.model.n();
        let zero = vec![Tri::constant(0.0); n];
        let at = At { q: &zero, t: Tri::constant(0.0), params: &self.params };
        let mut out = vec![Tri::constant(0.0); self.full.len()];
        for e in &self.elements {
            let data: Vec<Tri> = e.data.iter().map(|&v| Tri::constant(v)).collect();
            if !e.constraint.phi_tri(&at, &data, &mut out[e.row..]) {
                let (section, what) = if e.constraint.driven().is_some() { ("drivers", "driver") } else { ("joints", "joint") };
                return unsupported(format!("{section}.{}", e.name), &format!("the {} {what}", e.kind));
            }
        }
        for m in &self.model.measures {
            let data: Vec<Tri> = m.kind.data().iter().map(|&(_, v)| Tri::constant(v)).collect();
            if m.value_generic(&zero, &zero, &zero, Tri::constant(0.0), &data, &self.params).is_none() {
                return unsupported(format!("measures.{}", m.name), "this measure");
            }
        }
        Ok(())
    }

    /// The derivatives of every column at the output `(t, q, qdot, qddot)`, with `lu` the
    /// factorization of `Phi_q`'s independent `rows` there, pushed into `results`.
    pub(crate) fn push(
        &mut self,
        results: &mut Results,
        lu: &mut SparseLu,
        rows: &[usize],
        t: f64,
        (q, qdot, qddot): (&[f64], &[f64], &[f64]),
    ) -> Result<(), Error> {
        for k in 0..self.asked.len() {
            let p = self.asked[k];
            for (x, g) in self.params.iter_mut().zip(&self.model.gradients.params) {
                *x = fixed(x.v, g[p]);
            }
            self.dq.iter_mut().for_each(|d| d.fill(0.0));
            for level in 0..3 {
                self.seed(q, qdot, qddot);
                self.evaluate(p, t);
                // The level's part of each independent row: e3, e13, e123.
                for (r, &row) in self.rhs.iter_mut().zip(rows) {
                    let x = self.full[row];
                    *r = -[x.e3, x.e13, x.e123][level];
                }
                lu.solve(&mut self.rhs);
                self.dq[level].copy_from_slice(&self.rhs);
            }
            self.rows[k] = self.columns(p, t, q, qdot, qddot);
        }
        results.push_sensitivities(t, &self.names, &self.rows)
    }

    /// The coordinates over `Tri` at `(q, qdot, qddot)` with the derivatives found so far.
    fn seed(&mut self, q: &[f64], qdot: &[f64], qddot: &[f64]) {
        let [dq, dv, da] = &self.dq;
        for (i, x) in self.q.iter_mut().enumerate() {
            *x = Tri::trajectory([q[i], qdot[i], qddot[i]], [dq[i], dv[i], da[i]]);
        }
    }

    /// Every element's rows at time `t` over the seeded coordinates, with the numbers seeded
    /// along parameter `p`.
    fn evaluate(&mut self, p: usize, t: f64) {
        let at = At { q: &self.q, t: Tri::trajectory([t, 1.0, 0.0], [0.0; 3]), params: &self.params };
        for e in &self.elements {
            self.data.clear();
            self.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| fixed(v, g[p])));
            e.constraint.phi_tri(&at, &self.data, &mut self.full[e.row..]);
        }
    }

    /// The derivatives of the columns (each body's quantities, then the measures) with respect
    /// to parameter `p`, from `q_p`, `qdot_p`, `qddot_p`.
    fn columns(&self, p: usize, t: f64, q: &[f64], qdot: &[f64], qddot: &[f64]) -> Vec<f64> {
        let [dq, dv, da] = &self.dq;
        let bodies = q.len() / 3;
        let mut row: Vec<f64> = (0..bodies)
            .flat_map(|b| [dq, dv, da].into_iter().flat_map(move |v| [v[3 * b], v[3 * b + 1], v[3 * b + 2]]))
            .collect();
        let along = |x: &[f64], d: &[f64]| -> Vec<Tri> {
            x.iter().zip(d).map(|(&v, &e)| fixed(v, e)).collect()
        };
        let (q, qdot, qddot) = (along(q, dq), along(qdot, dv), along(qddot, da));
        let time = Tri::constant(t);
        for (m, grads) in self.model.measures.iter().zip(&self.model.gradients.measures) {
            let data: Vec<f64> = m.kind.data().iter().map(|&(_, v)| v).collect();
            let data: Vec<Tri> = data.iter().zip(grads).map(|(&v, g)| fixed(v, g[p])).collect();
            let value = m.value_generic(&q, &qdot, &qddot, time, &data, &self.params);
            row.push(value.map_or(f64::NAN, |v| v.e3));
        }
        row
    }
}
