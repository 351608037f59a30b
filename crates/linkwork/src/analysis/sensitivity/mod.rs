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
//! Each right-hand side is one part of `Phi` evaluated over numbers seeded with the time
//! direction (`q` along `qdot`, and `qddot` for the second derivative; `t` along 1) and the
//! parameter's direction (`q` along `q_p`, `qdot_p`, `qddot_p`; each element's numbers and the
//! parameters along their gradients), each evaluated with the unknown of its level zero: the
//! [`Dual`] part along the parameter at the position level, the [`HyperDual`] mixed part of time
//! and parameter at the velocity level, and the [`Tri`] part `e123` (time twice, then the
//! parameter) at the acceleration level. Each level uses the cheapest type that carries its part. The square system of
//! the independent rows is the one the analysis solves; rows it found redundant hold
//! implicitly. The measures follow from one more evaluation over the same numbers.

mod friction;
mod inverse;

pub(crate) use inverse::{InverseAt, InverseSensitivity};

use crate::constraints::{At, Constraint};
use crate::error::{Error, Problem};
use crate::expr::{Dual, HyperDual, Scalar, Tri};
use crate::linalg::SparseLu;
use crate::model::{Analysis, Model};
use crate::results::Results;

mod dynamic;
mod modes;
mod statics;

pub(crate) use dynamic::{DynamicSensitivity, Track};
pub(crate) use modes::mode_derivatives;
pub(crate) use statics::EquilibriumSensitivity;

/// The model error of an element at `path` (`what` it is) that has no design sensitivities yet.
fn unsupported(path: String, what: &str) -> Error {
    Error::Model(vec![Problem::new(
        path,
        format!("{what} has no design sensitivities yet (asked for with `sensitivities`)"),
    )])
}

/// The numbers of one level of the sensitivity equations: how a coordinate, the time and a
/// number that depends on the parameters only are seeded, the element's rows over them, and
/// the part of a row that is the level's right-hand side.
trait Level: Scalar {
    /// A coordinate `x = [q, qdot, qddot]` with its derivatives `d = [q_p, qdot_p, qddot_p]`
    /// along the parameter.
    fn coordinate(x: [f64; 3], d: [f64; 3]) -> Self;
    /// The time `t`, moving along the time direction.
    fn time(t: f64) -> Self;
    /// A number `v` that depends on the parameters only, with derivative `g` along the one.
    fn fixed(v: f64, g: f64) -> Self;
    /// The part of a row that the level solves for.
    fn part(self) -> f64;
    /// `c`'s rows over these numbers ([`Constraint::phi_tri`] and its kin).
    fn rows(c: &dyn Constraint, at: &At<'_, Self>, data: &[Self], out: &mut [Self]) -> bool;
}

/// Position level: the derivative along the parameter alone.
impl Level for Dual {
    fn coordinate(x: [f64; 3], d: [f64; 3]) -> Dual {
        Dual::new(x[0], d[0])
    }
    fn time(t: f64) -> Dual {
        Dual::new(t, 0.0)
    }
    fn fixed(v: f64, g: f64) -> Dual {
        Dual::new(v, g)
    }
    fn part(self) -> f64 {
        self.d
    }
    fn rows(c: &dyn Constraint, at: &At<'_, Dual>, data: &[Dual], out: &mut [Dual]) -> bool {
        c.phi_dual(at, data, out)
    }
}

/// Velocity level: time in the first direction, the parameter in the second, their mixed part.
impl Level for HyperDual {
    fn coordinate(x: [f64; 3], d: [f64; 3]) -> HyperDual {
        HyperDual::new(x[0], x[1], d[0], d[1])
    }
    fn time(t: f64) -> HyperDual {
        HyperDual::new(t, 1.0, 0.0, 0.0)
    }
    fn fixed(v: f64, g: f64) -> HyperDual {
        HyperDual::new(v, 0.0, g, 0.0)
    }
    fn part(self) -> f64 {
        self.e12
    }
    fn rows(c: &dyn Constraint, at: &At<'_, HyperDual>, data: &[HyperDual], out: &mut [HyperDual]) -> bool {
        c.phi_hyper(at, data, out)
    }
}

/// Acceleration level: time twice, then the parameter ([`Tri::trajectory`]), the part `e123`.
impl Level for Tri {
    fn coordinate(x: [f64; 3], d: [f64; 3]) -> Tri {
        Tri::trajectory(x, d)
    }
    fn time(t: f64) -> Tri {
        Tri::trajectory([t, 1.0, 0.0], [0.0; 3])
    }
    fn fixed(v: f64, g: f64) -> Tri {
        Tri::trajectory([v, 0.0, 0.0], [g, 0.0, 0.0])
    }
    fn part(self) -> f64 {
        self.e123
    }
    fn rows(c: &dyn Constraint, at: &At<'_, Tri>, data: &[Tri], out: &mut [Tri]) -> bool {
        c.phi_tri(at, data, out)
    }
}

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

/// The buffers of one level: the coordinates, parameters, an element's numbers and the rows.
struct Buffers<S> {
    q: Vec<S>,
    params: Vec<S>,
    data: Vec<S>,
    full: Vec<S>,
}

impl<S: Level> Buffers<S> {
    fn new(n: usize, parameters: usize, m: usize) -> Buffers<S> {
        let zero = S::constant(0.0);
        Buffers { q: vec![zero; n], params: vec![zero; parameters], data: Vec::new(), full: vec![zero; m] }
    }
}

/// The sensitivities of a kinematic analysis: its elements, the parameters asked, and the
/// buffers of one output time.
pub(crate) struct Sensitivity<'m> {
    model: &'m Model,
    /// The parameters asked: indices (file order) and names.
    asked: Vec<usize>,
    names: Vec<String>,
    elements: Vec<Seeded<'m>>,
    /// Each measure's numbers ([`crate::model::MeasureKind::data`]), read once.
    measure_data: Vec<Vec<f64>>,
    position: Buffers<Dual>,
    velocity: Buffers<HyperDual>,
    acceleration: Buffers<Tri>,
    /// (n) a right-hand side in the independent rows.
    rhs: Vec<f64>,
    /// (n) `q_p`, `qdot_p`, `qddot_p` of the parameter being solved for.
    dq: [Vec<f64>; 3],
    /// (parameters) each one's row of derivatives of every column.
    rows: Vec<Vec<f64>>,
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
        let (n, count) = (model.n(), model.parameters.len());
        let names = asked.iter().map(|&k| model.parameters.get_index(k).map_or_else(String::new, |(p, _)| p.clone()));
        let sensitivity = Sensitivity {
            model,
            asked: asked.to_vec(),
            names: names.collect(),
            elements,
            measure_data: model.measures.iter().map(|m| m.kind.data().iter().map(|&(_, v)| v).collect()).collect(),
            position: Buffers::new(n, count, row),
            velocity: Buffers::new(n, count, row),
            acceleration: Buffers::new(n, count, row),
            rhs: vec![0.0; n],
            dq: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            rows: vec![Vec::new(); asked.len()],
        };
        sensitivity.supported()?;
        Ok(sensitivity)
    }

    /// An error naming the first element or measure that has no derivatives yet.
    fn supported(&self) -> Result<(), Error> {
        let unsupported = |path: String, what: &str| Err(unsupported(path, what));
        let b = &self.position;
        let at = At { q: &b.q, t: Dual::constant(0.0), params: &b.params };
        let mut out = b.full.clone();
        for e in &self.elements {
            let data: Vec<Dual> = e.data.iter().map(|&v| Dual::constant(v)).collect();
            if !e.constraint.phi_dual(&at, &data, &mut out[e.row..]) {
                let (section, what) =
                    if e.constraint.driven().is_some() { ("drivers", "driver") } else { ("joints", "joint") };
                return unsupported(format!("{section}.{}", e.name), &format!("the {} {what}", e.kind));
            }
        }
        for m in &self.model.measures {
            let data: Vec<Dual> = m.kind.data().iter().map(|&(_, v)| Dual::constant(v)).collect();
            if m.value_generic(&b.q, &b.q, &b.q, &[], Dual::constant(0.0), &data, &b.params).is_none() {
                return unsupported(format!("measures.{}", m.name), "this measure");
            }
        }
        Ok(())
    }

    /// The derivatives of every column at the output `(t, q, qdot, qddot)`, with `lu` the
    /// factorization of `Phi_q`'s independent `rows` there, pushed into `results`: for each
    /// parameter asked, `q_p`, `qdot_p` and `qddot_p` ([`Sensitivity::motion`]), each body's
    /// quantities from them, then what `extra(self, p, lu, row)` appends for the analysis's own
    /// columns (the measures, [`Sensitivity::measures`], and an inverse analysis's reactions).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        results: &mut Results,
        lu: &mut SparseLu,
        rows: &[usize],
        t: f64,
        x: (&[f64], &[f64], &[f64]),
        mut extra: impl FnMut(&mut Sensitivity<'m>, usize, &mut SparseLu, &mut Vec<f64>) -> Result<(), Error>,
    ) -> Result<(), Error> {
        for k in 0..self.asked.len() {
            let p = self.asked[k];
            self.dq.iter_mut().for_each(|d| d.fill(0.0));
            let mut rhs = std::mem::take(&mut self.rhs);
            level(&mut self.position, &self.elements, self.model, p, t, x, &self.dq, rows, &mut rhs);
            lu.solve(&mut rhs);
            self.dq[0].copy_from_slice(&rhs);
            level(&mut self.velocity, &self.elements, self.model, p, t, x, &self.dq, rows, &mut rhs);
            lu.solve(&mut rhs);
            self.dq[1].copy_from_slice(&rhs);
            level(&mut self.acceleration, &self.elements, self.model, p, t, x, &self.dq, rows, &mut rhs);
            lu.solve(&mut rhs);
            self.dq[2].copy_from_slice(&rhs);
            self.rhs = rhs;
            let mut row = std::mem::take(&mut self.rows[k]);
            row.clear();
            self.bodies(&mut row);
            let outcome = extra(self, p, lu, &mut row);
            self.rows[k] = row;
            outcome?;
        }
        results.push_sensitivities(t, &self.names, &self.rows)
    }

    /// Each body's `x, y, phi`, their rates and accelerations (the results' order), from the
    /// motion's derivatives ([`Sensitivity::motion`]), appended to `row`.
    fn bodies(&self, row: &mut Vec<f64>) {
        let [dq, dv, da] = &self.dq;
        let bodies = dq.len() / 3;
        row.extend(
            (0..bodies)
                .flat_map(|b| [dq, dv, da].into_iter().flat_map(move |v| [v[3 * b], v[3 * b + 1], v[3 * b + 2]])),
        );
    }

    /// The derivatives of every body's quantities, then of the measures that read no reactions,
    /// with respect to parameter `p` at `(t, x)`, from the motion's ([`Sensitivity::motion`],
    /// set by the caller).
    pub(crate) fn columns(&mut self, p: usize, t: f64, x: (&[f64], &[f64], &[f64])) -> Vec<f64> {
        let mut row = Vec::new();
        self.bodies(&mut row);
        self.measures(p, t, x, &[], &mut row);
        row
    }

    /// `[q_p, qdot_p, qddot_p]` of the parameter being pushed ([`Sensitivity::push`]).
    pub(crate) fn motion(&self) -> &[Vec<f64>; 3] {
        &self.dq
    }

    /// The derivatives of the measures with respect to parameter `p` at `(t, q, qdot, qddot)`,
    /// from the motion's ([`Sensitivity::motion`]) and the reactions row `reactions` (values
    /// along their derivatives; empty in an analysis that has none), appended to `row`.
    pub(crate) fn measures(
        &mut self,
        p: usize,
        t: f64,
        (q, qdot, qddot): (&[f64], &[f64], &[f64]),
        reactions: &[Dual],
        row: &mut Vec<f64>,
    ) {
        let [dq, dv, da] = &self.dq;
        let along = |x: &[f64], d: &[f64]| -> Vec<Dual> { x.iter().zip(d).map(|(&v, &e)| Dual::new(v, e)).collect() };
        let (q, qdot, qddot) = (along(q, dq), along(qdot, dv), along(qddot, da));
        let b = &mut self.position;
        seed_parameters(&mut b.params, self.model, p);
        let measures = self.model.measures.iter().zip(&self.measure_data).zip(&self.model.gradients.measures);
        for ((m, data), grads) in measures {
            b.data.clear();
            b.data.extend(data.iter().zip(grads).map(|(&v, g)| Dual::new(v, g[p])));
            let value = m.value_generic(&q, &qdot, &qddot, reactions, Dual::constant(t), &b.data, &b.params);
            row.push(value.map_or(f64::NAN, |v| v.d));
        }
    }
}

/// One level of the sensitivity equations of parameter `p` at `(t, x)` in the numbers of `b`:
/// every element's rows with the coordinates seeded with `dq` (the unknown of the level and
/// those after it zero), the level's part of the independent `rows` negated into `rhs`.
#[allow(clippy::too_many_arguments)]
fn level<S: Level>(
    b: &mut Buffers<S>,
    elements: &[Seeded<'_>],
    model: &Model,
    p: usize,
    t: f64,
    (q, qdot, qddot): (&[f64], &[f64], &[f64]),
    dq: &[Vec<f64>; 3],
    rows: &[usize],
    rhs: &mut [f64],
) {
    let seed = |i: usize| S::coordinate([q[i], qdot[i], qddot[i]], [dq[0][i], dq[1][i], dq[2][i]]);
    over(b, elements, model, p, S::time(t), seed);
    for (r, &row) in rhs.iter_mut().zip(rows) {
        *r = -b.full[row].part();
    }
}

/// Every element's rows over the numbers `S` into `b.full`, with coordinate `i` seeded
/// `seed(i)`, the time `t`, the elements' numbers and the parameters along parameter `p`'s
/// direction ([`Level::fixed`]); returns the rows.
fn over<'b, S: Level>(
    b: &'b mut Buffers<S>,
    elements: &[Seeded<'_>],
    model: &Model,
    p: usize,
    t: S,
    seed: impl Fn(usize) -> S,
) -> &'b [S] {
    for (i, x) in b.q.iter_mut().enumerate() {
        *x = seed(i);
    }
    seed_parameters(&mut b.params, model, p);
    let at = At { q: &b.q, t, params: &b.params };
    for e in elements {
        b.data.clear();
        b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| S::fixed(v, g[p])));
        let supported = S::rows(e.constraint, &at, &b.data, &mut b.full[e.row..]);
        debug_assert!(supported, "{} was checked to have derivatives", e.name);
    }
    &b.full
}

/// The model's parameters over `S`, each along its derivative with respect to parameter `p`
/// (the `--set` chain rule, [`crate::model::DataGradients::params`]).
fn seed_parameters<S: Level>(params: &mut [S], model: &Model, p: usize) {
    for ((x, g), &v) in params.iter_mut().zip(&model.gradients.params).zip(model.parameters.values()) {
        *x = S::fixed(v, g[p]);
    }
}

/// `out (n) += (d/dp Phi_q)^T w` at `(t, q)` for each pair `(w, out)` of `pairs` (rows'
/// weights `w (m)`): the derivative of the Jacobian along parameter `p` (the coordinates moving
/// along `dq`, each element's numbers and the parameters along their gradients) times `w`. Each
/// element's rows over [`HyperDual`] numbers, the first direction along one of its columns, the
/// second along the parameter: the mixed part of row `r` is `d/dp Phi_q[r, column]`. One
/// evaluation per column of each element for every pair, exact.
#[allow(clippy::too_many_arguments)]
fn add_jacobian_transpose_along(
    b: &mut Buffers<HyperDual>,
    elements: &[Seeded<'_>],
    model: &Model,
    p: usize,
    t: f64,
    q: &[f64],
    dq: &[f64],
    pairs: &mut [(&[f64], &mut [f64])],
) {
    for ((x, &v), &d) in b.q.iter_mut().zip(q).zip(dq) {
        *x = HyperDual::new(v, 0.0, d, 0.0);
    }
    seed_parameters(&mut b.params, model, p);
    let time = HyperDual::new(t, 0.0, 0.0, 0.0);
    for e in elements {
        b.data.clear();
        b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| HyperDual::fixed(v, g[p])));
        let rows = e.row..e.row + e.constraint.rows();
        for &column in e.constraint.columns() {
            b.q[column].e1 = 1.0;
            let at = At { q: &b.q, t: time, params: &b.params };
            let supported = e.constraint.phi_hyper(&at, &b.data, &mut b.full[e.row..]);
            debug_assert!(supported, "{} was checked to have derivatives", e.name);
            b.q[column].e1 = 0.0;
            for (w, out) in pairs.iter_mut() {
                out[column] += rows.clone().map(|r| w[r] * b.full[r].e12).sum::<f64>();
            }
        }
    }
}
