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
//! and parameter at the velocity level, and the [`TimeTri`] part `e123` (time twice, then the
//! parameter) at the acceleration level. Each level uses the cheapest type that carries its part. The square system of
//! the independent rows is the one the analysis solves; rows it found redundant hold
//! implicitly. The measures follow from one more evaluation over the same numbers.
//!
//! The position level evaluates only the elements the parameter moves (the others' rows do not
//! move at fixed coordinates). With several parameters the upper two levels split into a share
//! linear in the lower levels' unknowns, by the time derivatives of `Phi_q` made once per output
//! point, and a share of the elements' numbers and parameters ([`Rates`]).

mod friction;
mod inverse;

pub(crate) use inverse::{InverseAt, InverseSensitivity};

use crate::constraints::{At, Constraint};
use crate::error::{Error, Problem};
use crate::expr::{Dual, HyperDual, Scalar, TimeTri};
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

/// Acceleration level: time twice, then the parameter ([`TimeTri::trajectory`]), the part
/// `e123`: [`crate::expr::Tri`]'s parts with its two time directions stored once.
impl Level for TimeTri {
    fn coordinate(x: [f64; 3], d: [f64; 3]) -> TimeTri {
        TimeTri::trajectory(x, d)
    }
    fn time(t: f64) -> TimeTri {
        TimeTri::trajectory([t, 1.0, 0.0], [0.0; 3])
    }
    fn fixed(v: f64, g: f64) -> TimeTri {
        TimeTri::trajectory([v, 0.0, 0.0], [g, 0.0, 0.0])
    }
    fn part(self) -> f64 {
        self.e123
    }
    fn rows(c: &dyn Constraint, at: &At<'_, TimeTri>, data: &[TimeTri], out: &mut [TimeTri]) -> bool {
        c.phi_time_tri(at, data, out)
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
    /// For each parameter of the model, whether it moves the element's rows at fixed
    /// coordinates and time: through its numbers or the parameters its rows read
    /// ([`Constraint::parameters`]; every parameter when they are not known).
    moves: Vec<bool>,
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
    acceleration: Buffers<TimeTri>,
    /// (n) the motion and its derivatives along the parameter, as the measures read them.
    along: [Vec<Dual>; 3],
    /// (n) a right-hand side in the independent rows.
    rhs: Vec<f64>,
    /// (n) `q_p`, `qdot_p`, `qddot_p` of the parameter being solved for.
    dq: [Vec<f64>; 3],
    /// (parameters) each one's row of derivatives of every column.
    rows: Vec<Vec<f64>>,
    /// The coordinates' share of the velocity and acceleration levels as matrices, when that is
    /// cheaper than each parameter's evaluation of every element ([`Sensitivity::push`]).
    rates: Option<Rates>,
}

/// The velocity and acceleration levels' right-hand sides split in two: the coordinates' share,
/// linear in the lower levels' unknowns,
///
/// ```text
/// d/dp (Phi_q qdot - nu)     = Phidot_q q_p + (the data's share)
/// d/dp (Phi_q qddot - gamma) = Phiddot_q q_p + 2 Phidot_q qdot_p + (the data's share)
/// ```
///
/// (`Phidot_q`, `Phiddot_q` the first and second time derivatives of `Phi_q` along the motion:
/// the derivatives of the two residuals with respect to `q` and `qdot`), made once per output
/// point for every parameter, and the share of each element's numbers and parameters, from one
/// evaluation of the elements the parameter moves.
struct Rates {
    /// Each element's block of `Phidot_q` and of `Phiddot_q` (rows x columns, row-major,
    /// elements in the system's order).
    rate: Vec<f64>,
    curvature: Vec<f64>,
    /// (m) the data's share of the three levels (`Phi_p` and its two time derivatives).
    parts: [Vec<f64>; 3],
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
        let count = model.parameters.len();
        for (element, grads) in joints.chain(drivers) {
            let data: Vec<f64> = element.constraint.data().iter().map(|&(_, v)| v).collect();
            let read = element.constraint.parameters();
            let moves = (0..count)
                .map(|p| {
                    grads.iter().any(|g| g[p] != 0.0)
                        || read.is_none_or(|read| read.iter().any(|&j| model.gradients.params[j][p] != 0.0))
                })
                .collect();
            elements.push(Seeded {
                name: &element.name,
                kind: element.kind,
                constraint: element.constraint.as_ref(),
                row,
                data,
                grads,
                moves,
            });
            row += element.constraint.rows();
        }
        let n = model.n();
        let names = asked.iter().map(|&k| model.parameters.get_index(k).map_or_else(String::new, |(p, _)| p.clone()));
        let mut sensitivity = Sensitivity {
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
            along: [Vec::new(), Vec::new(), Vec::new()],
            rates: None,
            rows: vec![Vec::new(); asked.len()],
        };
        sensitivity.supported()?;
        let entries: usize =
            sensitivity.elements.iter().map(|e| e.constraint.rows() * e.constraint.columns().len()).sum();
        if by_rates(&sensitivity.elements, asked) {
            let zero = || vec![0.0; entries];
            let parts = [vec![0.0; row], vec![0.0; row], vec![0.0; row]];
            sensitivity.rates = Some(Rates { rate: zero(), curvature: zero(), parts });
        }
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
        if let Some(rates) = &mut self.rates {
            rates.at(&mut self.acceleration, &self.elements, self.model, t, x);
        }
        for k in 0..self.asked.len() {
            let p = self.asked[k];
            self.dq.iter_mut().for_each(|d| d.fill(0.0));
            let mut rhs = std::mem::take(&mut self.rhs);
            if let Some(rates) = &mut self.rates {
                rates.levels(&mut self.acceleration, &self.elements, self.model, p, t, x, rows, lu, &mut self.dq);
            } else {
                position(&mut self.position, &self.elements, self.model, p, t, x.0, rows, &mut rhs);
                lu.solve(&mut rhs);
                self.dq[0].copy_from_slice(&rhs);
                level(&mut self.velocity, &self.elements, self.model, p, t, x, &self.dq, rows, &mut rhs);
                lu.solve(&mut rhs);
                self.dq[1].copy_from_slice(&rhs);
                level(&mut self.acceleration, &self.elements, self.model, p, t, x, &self.dq, rows, &mut rhs);
                lu.solve(&mut rhs);
                self.dq[2].copy_from_slice(&rhs);
            }
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
        row.reserve(3 * dq.len());
        for ((q, v), a) in dq.chunks_exact(3).zip(dv.chunks_exact(3)).zip(da.chunks_exact(3)) {
            row.extend_from_slice(q);
            row.extend_from_slice(v);
            row.extend_from_slice(a);
        }
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
        if self.model.measures.is_empty() {
            return;
        }
        for ((along, x), d) in self.along.iter_mut().zip([q, qdot, qddot]).zip(&self.dq) {
            along.clear();
            along.extend(x.iter().zip(d).map(|(&v, &e)| Dual::new(v, e)));
        }
        let [q, qdot, qddot] = &self.along;
        let b = &mut self.position;
        seed_parameters(&mut b.params, self.model, p);
        let measures = self.model.measures.iter().zip(&self.measure_data).zip(&self.model.gradients.measures);
        for ((m, data), grads) in measures {
            b.data.clear();
            b.data.extend(data.iter().zip(grads).map(|(&v, g)| Dual::new(v, g[p])));
            let value = m.value_generic(q, qdot, qddot, reactions, Dual::constant(t), &b.data, &b.params);
            row.push(value.d);
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

/// The position level of parameter `p` at `(t, q)` (`-Phi_p` of the independent `rows` into
/// `rhs`): the rows over [`Dual`] numbers of the elements the parameter moves, zero elsewhere.
#[allow(clippy::too_many_arguments)]
fn position(
    b: &mut Buffers<Dual>,
    elements: &[Seeded<'_>],
    model: &Model,
    p: usize,
    t: f64,
    q: &[f64],
    rows: &[usize],
    rhs: &mut [f64],
) {
    for (x, &v) in b.q.iter_mut().zip(q) {
        *x = Dual::constant(v);
    }
    seed_parameters(&mut b.params, model, p);
    let at = At { q: &b.q, t: Dual::constant(t), params: &b.params };
    for e in elements {
        let out = &mut b.full[e.row..e.row + e.constraint.rows()];
        if e.moves[p] {
            b.data.clear();
            b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| Dual::fixed(v, g[p])));
            let supported = e.constraint.phi_dual(&at, &b.data, out);
            debug_assert!(supported, "{} was checked to have derivatives", e.name);
        } else {
            out.fill(Dual::constant(0.0));
        }
    }
    for (r, &row) in rhs.iter_mut().zip(rows) {
        *r = -b.full[row].d;
    }
}

/// Whether the coordinates' share of the velocity and acceleration levels goes by matrices
/// ([`Rates`]) for the parameters `asked`: they take, per output point, one [`TimeTri`]
/// evaluation of each element per column it has; without them each parameter takes two
/// evaluations of every element (a [`HyperDual`] and a [`TimeTri`] one, counted alike: both are
/// dominated by the same functions of the same coordinates). Either way each parameter takes
/// one more evaluation of the elements it moves (the position level, or the data's share), left
/// out of the comparison. On the quick-return (34 columns, 8 elements) the matrices serve from
/// 3 parameters on.
fn by_rates(elements: &[Seeded<'_>], asked: &[usize]) -> bool {
    let columns: usize = elements.iter().map(|e| e.constraint.columns().len()).sum();
    columns < 2 * elements.len() * asked.len()
}

impl Rates {
    /// `Phidot_q` and `Phiddot_q` at the output `(t, q, qdot, qddot)`: each element's rows over
    /// [`TimeTri`] numbers, the time along the motion and the third direction one of its
    /// columns (a unit step held in time), whose parts `e13` and `e123` are that column of the
    /// two matrices.
    fn at(
        &mut self,
        b: &mut Buffers<TimeTri>,
        elements: &[Seeded<'_>],
        model: &Model,
        t: f64,
        (q, qdot, qddot): (&[f64], &[f64], &[f64]),
    ) {
        for (i, x) in b.q.iter_mut().enumerate() {
            *x = TimeTri::trajectory([q[i], qdot[i], qddot[i]], [0.0; 3]);
        }
        for (x, &v) in b.params.iter_mut().zip(model.parameters.values()) {
            *x = TimeTri::constant(v);
        }
        let mut offset = 0;
        for e in elements {
            let c = e.constraint;
            let (columns, rows) = (c.columns(), c.rows());
            b.data.clear();
            b.data.extend(e.data.iter().map(|&v| TimeTri::constant(v)));
            for (ci, &column) in columns.iter().enumerate() {
                b.q[column].e3 = 1.0;
                let at = At { q: &b.q, t: TimeTri::time(t), params: &b.params };
                let supported = c.phi_time_tri(&at, &b.data, &mut b.full[e.row..e.row + rows]);
                debug_assert!(supported, "{} was checked to have derivatives", e.name);
                b.q[column].e3 = 0.0;
                for (r, x) in b.full[e.row..e.row + rows].iter().enumerate() {
                    self.rate[offset + r * columns.len() + ci] = x.e13;
                    self.curvature[offset + r * columns.len() + ci] = x.e123;
                }
            }
            offset += rows * columns.len();
        }
    }

    /// `dq = [q_p, qdot_p, qddot_p]` of parameter `p` at `(t, x)` (`lu` the factorization of the
    /// independent `rows` of `Phi_q`): the data's share of the three levels from one
    /// [`TimeTri`] evaluation of each element the parameter moves (the coordinates along time
    /// only; its parts `e3`, `e13`, `e123`), the coordinates' share from the matrices
    /// ([`Rates::at`]), one solve per level.
    #[allow(clippy::too_many_arguments)]
    fn levels(
        &mut self,
        b: &mut Buffers<TimeTri>,
        elements: &[Seeded<'_>],
        model: &Model,
        p: usize,
        t: f64,
        (q, qdot, qddot): (&[f64], &[f64], &[f64]),
        rows: &[usize],
        lu: &mut SparseLu,
        dq: &mut [Vec<f64>; 3],
    ) {
        for (i, x) in b.q.iter_mut().enumerate() {
            *x = TimeTri::trajectory([q[i], qdot[i], qddot[i]], [0.0; 3]);
        }
        seed_parameters(&mut b.params, model, p);
        let at = At { q: &b.q, t: TimeTri::time(t), params: &b.params };
        for e in elements {
            let range = e.row..e.row + e.constraint.rows();
            if e.moves[p] {
                b.data.clear();
                b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| TimeTri::fixed(v, g[p])));
                let supported = e.constraint.phi_time_tri(&at, &b.data, &mut b.full[range.clone()]);
                debug_assert!(supported, "{} was checked to have derivatives", e.name);
                for (r, x) in range.zip(&b.full[e.row..]) {
                    [self.parts[0][r], self.parts[1][r], self.parts[2][r]] = [x.e3, x.e13, x.e123];
                }
            } else {
                self.parts.iter_mut().for_each(|part| part[range.clone()].fill(0.0));
            }
        }
        // Position: -Phi_p. Velocity: -(Phidot_q q_p + its data share). Acceleration:
        // -(Phiddot_q q_p + 2 Phidot_q qdot_p + its data share).
        let [position, velocity, acceleration] = &mut self.parts;
        solve_level(position, rows, lu, &mut dq[0]);
        for_blocks(elements, |cols, range, offset| {
            for (r, row) in range.enumerate() {
                let at = offset + r * cols.len();
                let (rate, curvature) = (&self.rate[at..at + cols.len()], &self.curvature[at..at + cols.len()]);
                velocity[row] += cols.iter().zip(rate).map(|(&c, a)| a * dq[0][c]).sum::<f64>();
                acceleration[row] += cols.iter().zip(curvature).map(|(&c, a)| a * dq[0][c]).sum::<f64>();
            }
        });
        solve_level(velocity, rows, lu, &mut dq[1]);
        for_blocks(elements, |cols, range, offset| {
            for (r, row) in range.enumerate() {
                let rate = &self.rate[offset + r * cols.len()..offset + (r + 1) * cols.len()];
                acceleration[row] += 2.0 * cols.iter().zip(rate).map(|(&c, a)| a * dq[1][c]).sum::<f64>();
            }
        });
        solve_level(acceleration, rows, lu, &mut dq[2]);
    }
}

/// `x` solving `Phi_q x = -part` on the independent `rows` (`lu` their factorization).
fn solve_level(part: &[f64], rows: &[usize], lu: &mut SparseLu, x: &mut [f64]) {
    for (x, &row) in x.iter_mut().zip(rows) {
        *x = -part[row];
    }
    lu.solve(x);
}

/// `f(columns, rows, offset)` for each element: its columns, its rows in the system and the
/// offset of its block among the elements' blocks (rows x columns each, one after the other).
fn for_blocks(elements: &[Seeded<'_>], mut f: impl FnMut(&[usize], std::ops::Range<usize>, usize)) {
    let mut offset = 0;
    for e in elements {
        let c = e.constraint;
        f(c.columns(), e.row..e.row + c.rows(), offset);
        offset += c.rows() * c.columns().len();
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
/// along `dq`, each element's numbers and the parameters along their gradients) times `w`, over
/// `elements` (index and element: all of them, or those that move with `p` when `dq` is zero).
/// The mixed part of row `r` in [`by_column`] is `d/dp Phi_q[r, column]`. One evaluation per
/// column of each element for every pair, exact.
#[allow(clippy::too_many_arguments)]
fn add_jacobian_transpose_along<'e, 'm: 'e>(
    b: &mut Buffers<HyperDual>,
    elements: impl IntoIterator<Item = (usize, &'e Seeded<'m>)>,
    model: &Model,
    p: usize,
    t: f64,
    q: &[f64],
    dq: &[f64],
    pairs: &mut [(&[f64], &mut [f64])],
) {
    by_column(b, elements, model, p, t, (q, dq), |_, e, c, rows| {
        let column = e.constraint.columns()[c];
        for (w, out) in pairs.iter_mut() {
            out[column] += rows.iter().zip(&w[e.row..]).map(|(h, w)| w * h.e12).sum::<f64>();
        }
    });
}

/// Each of `elements`' rows (index and element) over hyper-dual numbers, once per column the
/// element touches: the first direction the unit coordinate of that column, the second parameter
/// `p`'s (the coordinates along `dq`, the element's numbers and the parameters along their
/// gradients), at the fixed time `t`; `f(element index, element, local column, rows)`. The one
/// per-column pass of the dynamic, static and inverse sensitivities: the mixed part of a row is
/// the derivative of its Jacobian entry along the parameter, the first part the entry.
fn by_column<'e, 'm: 'e>(
    b: &mut Buffers<HyperDual>,
    elements: impl IntoIterator<Item = (usize, &'e Seeded<'m>)>,
    model: &Model,
    p: usize,
    t: f64,
    (q, dq): (&[f64], &[f64]),
    mut f: impl FnMut(usize, &Seeded<'_>, usize, &[HyperDual]),
) {
    for (x, (&v, &d)) in b.q.iter_mut().zip(q.iter().zip(dq)) {
        *x = HyperDual::new(v, 0.0, d, 0.0);
    }
    seed_parameters(&mut b.params, model, p);
    for (k, e) in elements {
        b.data.clear();
        b.data.extend(e.data.iter().zip(e.grads).map(|(&v, g)| HyperDual::fixed(v, g[p])));
        let rows = e.constraint.rows();
        for (c, &column) in e.constraint.columns().iter().enumerate() {
            b.q[column].e1 = 1.0;
            let at = At { q: &b.q, t: HyperDual::constant(t), params: &b.params };
            let supported = e.constraint.phi_hyper(&at, &b.data, &mut b.full[e.row..]);
            debug_assert!(supported, "{} was checked to have derivatives", e.name);
            b.q[column].e1 = 0.0;
            f(k, e, c, &b.full[e.row..e.row + rows]);
        }
    }
}

/// The Hessians of `w^T Phi` over each element's columns at `(q, t)` (every number at its value),
/// for the row weights `w (m)` of `weights` (at most two): the geometric stiffness
/// `d(Phi_q^T w)/dq` element by element. Each element's rows over hyper-dual numbers seeded with
/// two unit coordinates of its columns, once per pair `c <= d` (the Hessian is symmetric);
/// `f(element index, c, d, [w_1^T Phi_cd, w_2^T Phi_cd])` with `c`, `d` local columns.
fn hessians(
    b: &mut Buffers<HyperDual>,
    elements: &[Seeded<'_>],
    model: &Model,
    t: f64,
    q: &[f64],
    weights: &[&[f64]],
    mut f: impl FnMut(usize, usize, usize, [f64; 2]),
) {
    debug_assert!(weights.len() <= 2, "at most two weights");
    for (x, &v) in b.q.iter_mut().zip(q) {
        *x = HyperDual::constant(v);
    }
    for (x, &v) in b.params.iter_mut().zip(model.parameters.values()) {
        *x = HyperDual::constant(v);
    }
    for (k, e) in elements.iter().enumerate() {
        b.data.clear();
        b.data.extend(e.data.iter().map(|&v| HyperDual::constant(v)));
        let (rows, columns) = (e.row..e.row + e.constraint.rows(), e.constraint.columns());
        for (c, &i) in columns.iter().enumerate() {
            for (d, &j) in columns.iter().enumerate().skip(c) {
                b.q[i].e1 = 1.0;
                b.q[j].e2 = 1.0;
                let at = At { q: &b.q, t: HyperDual::constant(t), params: &b.params };
                let supported = e.constraint.phi_hyper(&at, &b.data, &mut b.full[e.row..]);
                debug_assert!(supported, "{} was checked to have derivatives", e.name);
                b.q[i].e1 = 0.0;
                b.q[j].e2 = 0.0;
                let mut values = [0.0; 2];
                for (value, w) in values.iter_mut().zip(weights) {
                    *value = rows.clone().map(|r| w[r] * b.full[r].e12).sum::<f64>();
                }
                f(k, c, d, values);
            }
        }
    }
}
