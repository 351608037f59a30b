//! Design sensitivities of a dynamic analysis: the equations the integrator differentiates
//! along a parameter, the sensitivities at the start, and the derivatives of the columns at an
//! output time (docs/sensitivities.md, "Dynamic analyses").
//!
//! Along a run, `M qddot + Phi_q^T lambda = Q(q, qdot, t)` and `Phi(q, t) = 0` hold with every
//! number moving with the parameters. Their derivatives along parameter `p`, with
//! `s = dq/dp` and its time derivatives and `s_lambda = dlambda/dp`, are
//!
//! ```text
//! M s_a + Phi_q^T s_lambda = dQ - M_p qddot - (d/dp Phi_q)^T lambda
//! Phi_q s + Phi_p = 0
//! ```
//!
//! where `dQ` is the total derivative of the loads along `(s, s_v)` and the data
//! ([`Dae::add_load_along`]), `M_p` the mass matrix's ([`Dae::add_mass_along`]), and
//! `d/dp Phi_q` the Jacobian's along `s` and the elements' numbers (`HyperDual` evaluations of each
//! element's rows). The integrator differentiates its own discretisation of these (bdf.rs); this
//! file gives each term, the start's sensitivities (those of the assembly: the given coordinates
//! held) and the columns' derivatives at an output time, where the accelerations and multipliers
//! follow from the state as the run's own (`[M, Phi_q^T; Phi_q, 0]` with the factorization the
//! output has just made).

use super::{add_jacobian_transpose_along, hessians, level, Buffers, Sensitivity};
use crate::analysis::dynamic::Dae;
use crate::error::{Error, Problem};
use crate::expr::{Dual, HyperDual, TimeTri};
use crate::model::{Analysis, Model};
use crate::results::Results;
use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;

/// The derivatives along one parameter of the state at one time: positions, velocities,
/// accelerations and multipliers.
#[derive(Debug, Clone)]
pub(crate) struct Track {
    /// (n) `dq/dp`.
    pub q: Vec<f64>,
    /// (n) `dqdot/dp`.
    pub v: Vec<f64>,
    /// (n) `dqddot/dp`.
    pub a: Vec<f64>,
    /// (m) `dlambda/dp`.
    pub lambda: Vec<f64>,
}

/// The parts of `(d/dp Phi_q)^T w` at one step's converged state, for `w` the multipliers
/// `lambda` and the projection's `mu` (SI2): linear in the sensitivities `s`, it is
/// `K_w s + (Phi_q^T w)_p`, with `K_w = (w^T Phi)_qq` the geometric stiffness, the same for every
/// parameter and iteration, and the second part evaluated once per parameter, over the elements
/// whose numbers move with it.
struct StepParts {
    /// Each element's `K_lambda` and `K_mu` blocks (columns x columns, row-major, elements in the
    /// system's order), and each element's first entry in them.
    stiffness: [Vec<f64>; 2],
    offsets: Vec<usize>,
    /// (parameters asked) the elements whose rows move with the parameter at fixed coordinates
    /// (their numbers do, or they read the parameters).
    moving: Vec<Vec<usize>>,
    /// (parameters asked) `(Phi_q^T lambda)_p` and `(Phi_q^T mu)_p`, `(n)` each.
    fixed: Vec<[Vec<f64>; 2]>,
    /// (n) zeros: the coordinates held for `fixed`.
    zero: Vec<f64>,
}

/// The sensitivity equations of a dynamic analysis and their scratch.
pub(crate) struct DynamicSensitivity<'m> {
    /// The elements, the parameters asked and the kinematic levels' buffers.
    base: Sensitivity<'m>,
    /// The buffers of the Jacobian's derivative.
    jacobian: Buffers<HyperDual>,
    /// The step's parts of `(d/dp Phi_q)^T w` ([`DynamicSensitivity::prepare`]), or `None` when
    /// the derivative is evaluated whole in every iteration (the cheaper with few parameters).
    step: Option<StepParts>,
    /// Every constraint row, `0..m`.
    all: Vec<usize>,
    /// (n) scratch.
    work: Vec<f64>,
    /// (n + m) right-hand side, solution and residual scratch.
    rhs: Vec<f64>,
    x: Vec<f64>,
    r: Vec<f64>,
    /// (m) scratch.
    rows: Vec<f64>,
    /// Which columns of a result row have derivatives (in the row's layout).
    differentiated: Vec<bool>,
    /// Each active driver's effort column in the row and its multiplier's row.
    efforts: Vec<(usize, usize)>,
    /// The column of the kinetic energy (the potential energy's follows it).
    energies: usize,
    /// The first measure's column.
    measures: usize,
}

impl<'m> DynamicSensitivity<'m> {
    /// The sensitivities of the dynamic `analysis` of `model`, whose equations are `dae`, with
    /// respect to the parameters `asked` (indices, file order). An element, measure or force
    /// with no derivatives yet is an error naming it.
    pub(crate) fn new(
        model: &'m Model,
        analysis: &Analysis,
        asked: &[usize],
        dae: &Dae<'_>,
    ) -> Result<DynamicSensitivity<'m>, Error> {
        let base = Sensitivity::new(model, analysis, asked)?;
        let refuse = |path: String, what: &str| {
            Error::Model(vec![Problem::new(
                path,
                format!("{what} has no design sensitivities yet (asked for with `sensitivities`)"),
            )])
        };
        if let Some(j) = model.joints.iter().find(|j| j.friction.is_some()) {
            return Err(refuse(format!("joints.{}", j.name), "joint friction"));
        }
        // The reactions of a dynamic run have no derivatives yet, nor have the measures that
        // read them.
        if let Some(m) = model.measures.iter().find(|m| m.reads_beyond_motion()) {
            return Err(refuse(
                format!("measures.{}", m.name),
                "in a dynamic analysis, a measure that reads reactions or efforts",
            ));
        }
        let (n, m) = (dae.n, dae.m);
        let zero = vec![0.0; n];
        if let Err(name) = dae.add_load_along(&model.q0(), &zero, analysis.t_start, &zero, &zero, 0, &mut vec![0.0; n])
        {
            return Err(refuse(format!("forces.{name}"), "this force"));
        }
        // The row: each body's 9 quantities, each joint's reaction (3), each driver's effort,
        // the energies and residuals, the measures, each contact's quantities (3).
        let bodies = 9 * model.bodies.len();
        let joints = 3 * model.joints.len();
        let mut differentiated = vec![true; bodies];
        differentiated.extend(std::iter::repeat_n(false, joints));
        let efforts: Vec<(usize, usize)> =
            base.elements[model.joints.len()..].iter().enumerate().map(|(k, e)| (bodies + joints + k, e.row)).collect();
        differentiated.extend(std::iter::repeat_n(true, efforts.len()));
        let energies = differentiated.len();
        // Kinetic energy; potential energy when gravity is its only term (the forces' potentials
        // have no derivatives with respect to their numbers); the work and the residuals none.
        differentiated.extend([true, analysis.forces.is_empty(), false, false, false]);
        let measures = differentiated.len();
        differentiated.extend(std::iter::repeat_n(true, model.measures.len()));
        let contacts = analysis.forces.iter().filter(|&&k| model.forces[k].force.contact().is_some()).count();
        differentiated.extend(std::iter::repeat_n(false, 3 * contacts));
        // The geometric stiffness costs one evaluation per pair of an element's columns at each
        // step; the derivative whole, one per column per parameter and iteration, of which a step
        // takes at least two (no contraction is known before the second): the stiffness when it
        // is the cheaper.
        let columns = base.elements.iter().map(|e| e.constraint.columns().len());
        let (pairs, per_column) = columns.fold((0, 0), |(a, b), w| (a + w * (w + 1) / 2, b + w));
        let step = (2 * asked.len() * per_column >= pairs).then(|| {
            let mut offsets = Vec::with_capacity(base.elements.len());
            let size = base.elements.iter().fold(0, |offset, e| {
                offsets.push(offset);
                offset + e.constraint.columns().len().pow(2)
            });
            let moving = asked
                .iter()
                .map(|&p| (0..base.elements.len()).filter(|&k| base.elements[k].moves[p]).collect())
                .collect();
            StepParts {
                stiffness: [vec![0.0; size], vec![0.0; size]],
                offsets,
                moving,
                fixed: vec![[vec![0.0; n], vec![0.0; n]]; asked.len()],
                zero: vec![0.0; n],
            }
        });
        Ok(DynamicSensitivity {
            step,
            jacobian: Buffers::new(n, model.parameters.len(), m),
            base,
            all: (0..m).collect(),
            work: vec![0.0; n],
            rhs: vec![0.0; n + m],
            x: vec![0.0; n + m],
            r: vec![0.0; n + m],
            rows: vec![0.0; m],
            differentiated,
            efforts,
            energies,
            measures,
        })
    }

    /// The number of parameters asked.
    pub(crate) fn parameters(&self) -> usize {
        self.base.asked.len()
    }

    /// The index (file order) of parameter `k` (asked order).
    pub(crate) fn parameter(&self, k: usize) -> usize {
        self.base.asked[k]
    }

    /// The size of parameter `k` (asked order) for the sensitivities' absolute tolerance: its
    /// value, or 1 when it is zero.
    pub(crate) fn size(&self, k: usize) -> f64 {
        let v = self.base.model.parameters.get_index(self.base.asked[k]).map_or(1.0, |(_, &v)| v.abs());
        if v > 0.0 {
            v
        } else {
            1.0
        }
    }

    /// The sensitivities at the assembled start `(t, q, qdot)` with `sol = [qddot; lambda]` (the
    /// output there has just factored `[M, Phi_q^T; Phi_q, -eps]` at it): the assembly holds the
    /// `given` coordinates and velocities (2n), so their derivatives are zero and the others
    /// follow from the `independent` rows of the position and velocity equations. An error when
    /// the given ones do not determine the start (the assembly then takes the least change from
    /// the file's guess, which has no derivative along the parameters).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn start(
        &mut self,
        dae: &mut Dae<'_>,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        sol: &[f64],
        independent: &[usize],
        given: &[bool],
    ) -> Result<Vec<Track>, Error> {
        let (n, m) = (dae.n, dae.m);
        let mut jac = Mat::<f64>::zeros(m, n);
        dae.jacobian_dense(jac.as_mut());
        let mut tracks = Vec::new();
        let mut levels = [Mat::<f64>::zeros(n, n), Mat::<f64>::zeros(n, n)];
        for (half, a) in levels.iter_mut().enumerate() {
            let held: Vec<usize> = (0..n).filter(|&k| given[half * n + k]).collect();
            if independent.len() + held.len() != n {
                let what = ["coordinates", "velocities"][half];
                return Err(Error::Model(vec![Problem::new(
                    "sensitivities",
                    format!(
                        "the start of a dynamic analysis with sensitivities must be fixed by the given {what} (bodies' `given:`): {} degree(s) of freedom, {} given",
                        n - independent.len(),
                        held.len()
                    ),
                )]));
            }
            for (i, &r) in independent.iter().enumerate() {
                for c in 0..n {
                    a[(i, c)] = jac[(r, c)];
                }
            }
            for (i, &c) in held.iter().enumerate() {
                a[(independent.len() + i, c)] = 1.0;
            }
        }
        let [position, velocity] = levels.map(|a| a.partial_piv_lu());
        let x = (q, qdot, &sol[..n]);
        for k in 0..self.parameters() {
            let p = self.base.asked[k];
            let solve = |lu: &PartialPivLu<f64>, rhs: &[f64]| -> Vec<f64> {
                let b = Mat::from_fn(n, 1, |i, _| if i < rhs.len() { rhs[i] } else { 0.0 });
                let s = lu.solve(&b);
                (0..n).map(|i| s[(i, 0)]).collect()
            };
            let Sensitivity { model, elements, position: dual, velocity: hyper, dq, .. } = &mut self.base;
            dq.iter_mut().for_each(|d| d.fill(0.0));
            let mut rhs = vec![0.0; independent.len()];
            level(dual, elements, model, p, t, x, dq, independent, &mut rhs);
            let sq = solve(&position, &rhs);
            dq[0].copy_from_slice(&sq);
            level(hyper, elements, model, p, t, x, dq, independent, &mut rhs);
            let sv = solve(&velocity, &rhs);
            let mut track = Track { q: sq, v: sv, a: vec![0.0; n], lambda: vec![0.0; m] };
            if track.q.iter().chain(&track.v).any(|v| !v.is_finite()) {
                return Err(Error::Model(vec![Problem::new(
                    "sensitivities",
                    "the given coordinates and velocities do not fix the start: its derivatives are not determined",
                )]));
            }
            self.accelerations(dae, k, t, q, qdot, sol, &mut track);
            tracks.push(track);
        }
        Ok(tracks)
    }

    /// `track.a` and `track.lambda` from `track.q` and `track.v` at the state `(t, q, qdot)` with
    /// `sol = [qddot; lambda]`, for parameter `k` (asked order): the derivative of
    /// `[M, Phi_q^T; Phi_q, 0] [qddot; lambda] = [Q; gamma]`, solved with the factorization of
    /// `[M, Phi_q^T; Phi_q, -eps]` that [`Dae::accelerations`] has just made at that state, and
    /// the two steps of iterative refinement that remove the regularisation, as there.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn accelerations(
        &mut self,
        dae: &mut Dae<'_>,
        k: usize,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        sol: &[f64],
        track: &mut Track,
    ) {
        let n = dae.n;
        let (qddot, lambda) = sol.split_at(n);
        let mut rhs = std::mem::take(&mut self.rhs);
        rhs.fill(0.0);
        let (r1, r2) = rhs.split_at_mut(n);
        track.a.fill(0.0);
        self.dynamics_along(dae, k, t, (q, qdot, qddot), lambda, track, r1, None);
        let p = self.base.asked[k];
        let Sensitivity { model, elements, acceleration, dq, .. } = &mut self.base;
        dq[0].copy_from_slice(&track.q);
        dq[1].copy_from_slice(&track.v);
        dq[2].fill(0.0);
        level::<TimeTri>(acceleration, elements, model, p, t, (q, qdot, qddot), dq, &self.all, r2);
        self.x.fill(0.0);
        for _ in 0..3 {
            let (xa, xl) = self.x.split_at(n);
            self.r.copy_from_slice(&rhs);
            self.work.fill(0.0);
            dae.add_jt(xl, &mut self.work);
            dae.jv(xa, &mut self.rows);
            let (s1, s2) = self.r.split_at_mut(n);
            for i in 0..n {
                s1[i] -= dae.mass[i] * xa[i] + self.work[i];
            }
            s2.iter_mut().zip(&self.rows).for_each(|(s, j)| *s -= j);
            dae.solve(&mut self.r);
            self.x.iter_mut().zip(&self.r).for_each(|(x, d)| *x += d);
        }
        track.a.copy_from_slice(&self.x[..n]);
        track.lambda.copy_from_slice(&self.x[n..]);
        self.rhs = rhs;
    }

    /// `out (n) = d/dp (Q - M qddot - Phi_q^T lambda)` without the term `-Phi_q^T s_lambda`, for
    /// parameter `k` (asked order) at `(t, q, qdot, qddot)` with the multipliers `lambda`, the
    /// state moving along `track` (`q`, `v`, `a`): `dQ - M s_a - M_p qddot - (d/dp Phi_q)^T lambda`.
    /// With `projection = (mu, extra)`, also `extra (n) += (d/dp Phi_q)^T mu`, in the same
    /// evaluations (the projection of the stabilised index-2 formulation).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn dynamics_along(
        &mut self,
        dae: &Dae<'_>,
        k: usize,
        t: f64,
        state: (&[f64], &[f64], &[f64]),
        lambda: &[f64],
        track: &Track,
        out: &mut [f64],
        projection: Option<(&[f64], &mut [f64])>,
    ) {
        self.along(dae, k, t, state, lambda, track, out, projection, false);
    }

    /// The step's parts of `(d/dp Phi_q)^T w` at the converged state `(t, q)` with the
    /// multipliers `lambda` and (SI2) the projection's `mu`, when the run uses them
    /// ([`StepParts`]): every element's geometric stiffness for both, and each parameter's part at
    /// fixed coordinates over the elements that move with it.
    pub(crate) fn prepare(&mut self, t: f64, q: &[f64], lambda: &[f64], mu: Option<&[f64]>) {
        let Some(step) = self.step.as_mut() else { return };
        let b = &self.base;
        let weights = [lambda, mu.unwrap_or(lambda)];
        let StepParts { stiffness: [kl, km], offsets, moving, fixed, zero } = step;
        hessians(&mut self.jacobian, &b.elements, b.model, t, q, &weights, |e, c, d, [l, m]| {
            let width = b.elements[e].constraint.columns().len();
            for (block, value) in [(&mut *kl, l), (&mut *km, m)] {
                block[offsets[e] + c * width + d] = value;
                block[offsets[e] + d * width + c] = value;
            }
        });
        for (k, &p) in b.asked.iter().enumerate() {
            let [fl, fm] = &mut fixed[k];
            fl.fill(0.0);
            fm.fill(0.0);
            let elements = moving[k].iter().map(|&e| (e, &b.elements[e]));
            let mut pairs = [(lambda, &mut fl[..]), (weights[1], &mut fm[..])];
            add_jacobian_transpose_along(&mut self.jacobian, elements, b.model, p, t, q, zero, &mut pairs);
        }
    }

    /// [`DynamicSensitivity::dynamics_along`]; with `in_step`, at the state of the last
    /// [`DynamicSensitivity::prepare`] (its `t`, `q`, `lambda` and `mu`), `(d/dp Phi_q)^T w` from
    /// the step's parts when it made them: the same numbers to rounding.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn along(
        &mut self,
        dae: &Dae<'_>,
        k: usize,
        t: f64,
        (q, qdot, qddot): (&[f64], &[f64], &[f64]),
        lambda: &[f64],
        track: &Track,
        out: &mut [f64],
        projection: Option<(&[f64], &mut [f64])>,
        in_step: bool,
    ) {
        let p = self.base.asked[k];
        out.fill(0.0);
        let loads = dae.add_load_along(q, qdot, t, &track.q, &track.v, p, out);
        debug_assert!(loads.is_ok(), "every force was checked to have derivatives");
        self.work.fill(0.0);
        dae.add_mass_along(p, qddot, &mut self.work);
        let b = &self.base;
        match self.step.as_ref().filter(|_| in_step) {
            Some(step) => step.add_times(k, &b.elements, &track.q, &mut self.work, projection),
            None => {
                let mut pairs: Vec<(&[f64], &mut [f64])> = vec![(lambda, &mut self.work)];
                pairs.extend(projection);
                let elements = b.elements.iter().enumerate();
                add_jacobian_transpose_along(&mut self.jacobian, elements, b.model, p, t, q, &track.q, &mut pairs);
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            *o -= dae.mass[i] * track.a[i] + self.work[i];
        }
    }

    /// `out (m) = Phi_q dq + Phi_p` at `(t, q)` for parameter `k` (asked order): the derivative
    /// of the constraints along the parameter, the positions moving along `dq`; with
    /// `velocities = (qdot, dv)`, that of the velocity equations, `d/dp (Phi_q qdot - nu)`, the
    /// velocities moving along `dv`.
    pub(crate) fn constraints_along(
        &mut self,
        k: usize,
        t: f64,
        q: &[f64],
        dq: &[f64],
        velocities: Option<(&[f64], &[f64])>,
        out: &mut [f64],
    ) {
        let p = self.base.asked[k];
        let Sensitivity { model, elements, position, velocity, dq: seed, .. } = &mut self.base;
        seed[0].copy_from_slice(dq);
        match velocities {
            None => level::<Dual>(position, elements, model, p, t, (q, q, q), seed, &self.all, out),
            Some((qdot, dv)) => {
                seed[1].copy_from_slice(dv);
                level::<HyperDual>(velocity, elements, model, p, t, (q, qdot, q), seed, &self.all, out);
            }
        }
        out.iter_mut().for_each(|x| *x = -*x);
    }

    /// The derivatives of every column that has them at the output `(t, q, qdot)` with
    /// `sol = [qddot; lambda]`, each parameter's from its `tracks[k]`, pushed into `results`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        results: &mut Results,
        dae: &Dae<'_>,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        sol: &[f64],
        tracks: &[Track],
    ) -> Result<(), Error> {
        let n = dae.n;
        let model = self.base.model;
        let bodies = 9 * model.bodies.len();
        let mut rows = Vec::with_capacity(tracks.len());
        for (k, track) in tracks.iter().enumerate() {
            let p = self.base.asked[k];
            for (d, s) in self.base.dq.iter_mut().zip([&track.q, &track.v, &track.a]) {
                d.copy_from_slice(s);
            }
            let known = self.base.columns(p, t, (q, qdot, &sol[..n]));
            let mut row = vec![0.0; self.differentiated.len()];
            row[..bodies].copy_from_slice(&known[..bodies]);
            row[self.measures..self.measures + model.measures.len()].copy_from_slice(&known[bodies..]);
            for &(column, r) in &self.efforts {
                row[column] = -track.lambda[r];
            }
            // T = qdot^T M qdot / 2; V = -sum m g . r over the bodies.
            self.work.fill(0.0);
            dae.add_mass_along(p, qdot, &mut self.work);
            row[self.energies] =
                (0..n).map(|i| dae.mass[i] * qdot[i] * track.v[i] + 0.5 * qdot[i] * self.work[i]).sum();
            let grads = &model.gradients;
            row[self.energies + 1] = -model
                .bodies
                .iter()
                .zip(&grads.bodies)
                .enumerate()
                .map(|(b, (body, g))| {
                    (0..2)
                        .map(|c| {
                            let force = g[0][p] * model.gravity[c] + body.mass * grads.gravity[c][p];
                            force * q[3 * b + c] + body.mass * model.gravity[c] * track.q[3 * b + c]
                        })
                        .sum::<f64>()
                })
                .sum::<f64>();
            rows.push(row);
        }
        results.push_sensitivities_of(t, &self.base.names, Some(&self.differentiated), &rows)
    }
}

impl StepParts {
    /// `out (n) += K_lambda s + (Phi_q^T lambda)_p` for parameter `k` (asked order), and with
    /// `projection = (_, extra)` `extra (n) += K_mu s + (Phi_q^T mu)_p`: `(d/dp Phi_q)^T w` along
    /// `s` and the parameter at the prepared state.
    fn add_times(
        &self,
        k: usize,
        elements: &[super::Seeded<'_>],
        s: &[f64],
        out: &mut [f64],
        projection: Option<(&[f64], &mut [f64])>,
    ) {
        let [kl, km] = &self.stiffness;
        let [fl, fm] = &self.fixed[k];
        let mut extra = projection.map(|(_, extra)| extra);
        for (e, &offset) in elements.iter().zip(&self.offsets) {
            let columns = e.constraint.columns();
            let width = columns.len();
            for (c, &i) in columns.iter().enumerate() {
                let row = offset + c * width..offset + (c + 1) * width;
                let times = |block: &[f64]| block[row.clone()].iter().zip(columns).map(|(h, &j)| h * s[j]).sum::<f64>();
                out[i] += times(kl);
                if let Some(extra) = extra.as_deref_mut() {
                    extra[i] += times(km);
                }
            }
        }
        out.iter_mut().zip(fl).for_each(|(o, f)| *o += f);
        if let Some(extra) = extra {
            extra.iter_mut().zip(fm).for_each(|(o, f)| *o += f);
        }
    }
}
