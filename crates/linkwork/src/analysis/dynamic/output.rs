//! Output of a dynamic analysis at the requested times, shared by every integrator.
//!
//! An integrator steps at its own pace; after each accepted step it hands every output time the
//! step covered to [`Output::push`], with positions and velocities from its own interpolant.
//! At each output time the accelerations and multipliers are then computed from the state,
//! `[M, Phi_q^T; Phi_q, 0] [qddot; lambda] = [Q; gamma]`, so that reactions, driver efforts and
//! accelerations are those of the state written, whatever the integrator. The work of the
//! non-conservative forces is integrated over the accepted steps by the trapezoidal rule
//! ([`Output::advance_work`]) and interpolated linearly to the output times.

use super::dae::Dae;
use crate::analysis::promise::Audit;
use crate::analysis::Run;
use crate::error::Error;
use crate::linalg::FactorError;
use crate::model::{Analysis, Model};
use crate::results::Results;

pub use crate::model::{CONTACT_QUANTITIES, ENERGY_COLUMNS};

/// The requested output times and the results written so far, as the run `run` is given.
#[derive(Debug)]
pub struct Output<'r, 'a> {
    /// Output times, ascending.
    times: Vec<f64>,
    /// Index of the next time to write.
    next: usize,
    /// Output step, s.
    h: f64,
    /// The results.
    pub results: Results,
    /// The run: its rows' sink, its watcher and its stop token.
    run: &'r mut Run<'a>,
    /// Indices into the model's drivers of the active ones.
    drivers: Vec<usize>,
    /// `(t, W)` at the last two accepted steps, and the power at the last.
    work_prev: (f64, f64),
    work_last: (f64, f64),
    power_last: f64,
    /// Scratch: `(n + m)` solution, two `(m)` rows, reactions row, the reactions row measures
    /// read, output row.
    sol: Vec<f64>,
    rows: Vec<f64>,
    rows2: Vec<f64>,
    react: Vec<f64>,
    reactions: Vec<f64>,
    row: Vec<f64>,
    /// What the outputs showed: residuals, sizes, energy ([`crate::analysis::promise`]).
    pub audit: Audit,
}

impl<'r, 'a> Output<'r, 'a> {
    /// Empty results with the columns of a dynamic analysis, run as `run`.
    pub(crate) fn new(model: &Model, analysis: &Analysis, n: usize, m: usize, run: &'r mut Run<'a>) -> Output<'r, 'a> {
        let mut results = run.results(model, analysis);
        let mut names = crate::analysis::reaction_columns(model, analysis);
        names.extend(ENERGY_COLUMNS.map(String::from));
        names.extend(model.measures.iter().map(|m| m.name.clone()));
        for &k in &analysis.forces {
            let f = &model.forces[k];
            if f.force.contact().is_some() {
                names.extend(CONTACT_QUANTITIES.map(|q| format!("{}.{q}", f.name)));
            }
        }
        results.add_columns(names);
        let (h, t0) = (analysis.step, analysis.t_start);
        let times = crate::analysis::setup::output_times(analysis);
        results.reserve(times.len());
        Output {
            times,
            next: 0,
            h,
            results,
            run,
            drivers: analysis.drivers.clone(),
            work_prev: (t0, 0.0),
            work_last: (t0, 0.0),
            power_last: 0.0,
            sol: vec![0.0; n + m],
            rows: vec![0.0; m],
            rows2: vec![0.0; m],
            react: Vec::new(),
            reactions: Vec::new(),
            row: Vec::new(),
            audit: Audit::default(),
        }
    }

    /// The output step, s.
    pub fn step(&self) -> f64 {
        self.h
    }

    /// The end time.
    pub fn t_end(&self) -> f64 {
        self.times[self.times.len() - 1]
    }

    /// The integrator attempts a step from `t` ([`Run::reached`]): reported, and
    /// [`Error::Interrupted`] if the run has been asked to stop.
    pub(crate) fn attempt(&self, t: f64) -> Result<(), Error> {
        self.run.reached(t)
    }

    /// The next output time if it is not after `t` (with a margin of `1e-9` output steps for
    /// rounding), else `None`.
    pub fn due(&self, t: f64) -> Option<f64> {
        self.times.get(self.next).copied().filter(|&to| to <= t + 1e-9 * self.h)
    }

    /// Start the work integral at `t0` with the power at the initial state.
    pub fn start_work(&mut self, dae: &mut Dae<'_>, t: f64, q: &[f64], qdot: &[f64], lambda: &[f64]) {
        dae.positions(q, t);
        self.power_last = dae.nonconservative_power(q, qdot, t, lambda, &mut self.rows);
        self.work_prev = (t, 0.0);
        self.work_last = (t, 0.0);
    }

    /// Advance the work integral over an accepted step to `t` (trapezoidal rule). `lambda`: the
    /// integrator's multipliers at `t` (only the drivers' rows are used).
    pub fn advance_work(&mut self, dae: &mut Dae<'_>, t: f64, q: &[f64], qdot: &[f64], lambda: &[f64]) {
        dae.positions(q, t);
        let p = dae.nonconservative_power(q, qdot, t, lambda, &mut self.rows);
        let (t0, w0) = self.work_last;
        self.work_prev = self.work_last;
        self.work_last = (t, w0 + 0.5 * (t - t0) * (self.power_last + p));
        self.power_last = p;
    }

    fn work_at(&self, t: f64) -> f64 {
        let ((t0, w0), (t1, w1)) = (self.work_prev, self.work_last);
        if t1 > t0 {
            w0 + (w1 - w0) * (t - t0) / (t1 - t0)
        } else {
            w1
        }
    }

    /// Write the next output time `t` from the state `(q, qdot)`.
    pub fn push(&mut self, dae: &mut Dae<'_>, t: f64, q: &[f64], qdot: &[f64]) -> Result<(), Error> {
        let mut sol = std::mem::take(&mut self.sol);
        let written = dae.accelerations(q, qdot, t, &mut sol).and_then(|_| self.push_solved(dae, t, q, qdot, &sol));
        self.sol = sol;
        written
    }

    /// `[qddot; lambda]` of the last output time written ([`Output::push`]).
    pub fn solution(&self) -> &[f64] {
        &self.sol
    }

    /// Write the next output time `t` from the state `(q, qdot)` and its `sol = [qddot; lambda]`
    /// (`n + m`), which the integrator solved at `(q, qdot, t)` with [`Dae::positions`] there.
    pub fn push_solved(
        &mut self,
        dae: &mut Dae<'_>,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        sol: &[f64],
    ) -> Result<(), Error> {
        let n = dae.n;
        let (qddot, lambda) = sol.split_at(n);
        dae.reactions(q, qdot, lambda, &mut self.react);
        crate::analysis::measure_reactions(dae.model, &self.drivers, &self.react, &mut self.reactions);
        let (mut position_residual, mut velocity_residual) = (0.0f64, 0.0f64);
        dae.jv(qdot, &mut self.rows);
        dae.nu(q, t, &mut self.rows2);
        for (r, ((p, v), nu)) in dae.phi.iter().zip(&self.rows).zip(&self.rows2).enumerate() {
            self.audit.position.see(p.abs(), t, r);
            self.audit.velocity.see((v - nu).abs(), t, r);
            position_residual = position_residual.max(p.abs());
            velocity_residual = velocity_residual.max((v - nu).abs());
        }
        let kinetic = dae.kinetic_energy(qdot);
        let potential = dae.potential_energy(q);
        self.audit.see(t, q, qdot, kinetic, potential);
        self.row.clear();
        self.row.extend_from_slice(&self.react);
        self.row.extend([kinetic, potential, self.work_at(t), position_residual, velocity_residual]);
        for m in &dae.model.measures {
            self.row.push(m.value(q, qdot, qddot, &self.reactions, t));
        }
        if dae.has_contacts() {
            dae.contact_states(q, qdot, &mut self.row);
        }
        // No non-finite number leaves as a result: the row's own check finds the first, and the
        // analysis stops naming the element that gave it rather than the column.
        self.run.push(&mut self.results, t, q, qdot, qddot, &self.row).map_err(|e| match e {
            Error::NonFinite { value, .. } => dae.non_finite(q, qdot, qddot, &self.reactions, t, value),
            other => other,
        })?;
        self.next += 1;
        Ok(())
    }
}

/// A factorization failure at time `t` as an error.
pub fn factor_error(e: FactorError, t: f64) -> Error {
    match e {
        FactorError::StructurallySingular { column } => Error::Singular {
            time: t,
            rows: vec![],
            detail: format!(
                "the equations of motion do not determine coordinate {column}: a body with no mass or inertia in a direction no joint fixes"
            ),
        },
        FactorError::OutOfMemory => Error::OutOfMemory { time: t, what: "while factorizing".into() },
    }
}
