//! The coordinate-partitioned state the integrator steps: the partition, its dependent block,
//! the accepted states, and the last evaluation, with the parts that work on them
//! (the Newton of `newton.rs`, the norm of `norm.rs`, the reduced solve of `reduced.rs`, the
//! noise test of `noise.rs`).

use super::super::{Dae, IntegratorSettings, Start};
use super::accepted::Accepted;
use super::block::Blocks;
use super::newton::Newton;
use super::noise::NoiseSample;
use super::norm::ErrorNorm;
use super::partition::Partition;
use super::reduced::ReducedSolve;
use crate::error::Error;

/// A choice of independent coordinates and the machinery that recovers the others.
pub(super) struct Split<'a, 'm> {
    pub(super) dae: &'a mut Dae<'m>,
    /// The partition, and its dependent block `B` with its factors.
    pub(super) part: Partition,
    pub(super) blocks: Blocks,
    /// The accepted states.
    pub(super) accepted: Accepted,
    /// The dependent-coordinate Newton, the error norm, the reduced solve and the noise test.
    pub(super) newton: Newton,
    pub(super) error: ErrorNorm,
    pub(super) reduced_work: ReducedSolve,
    pub(super) noise: NoiseSample,
    /// Time of the last evaluation that converged (NaN after a failure).
    pub(super) t_last: f64,
    /// (n) positions and velocities of the last evaluation.
    pub(super) q: Vec<f64>,
    pub(super) v: Vec<f64>,
    /// (n + m) `[qddot; lambda]` of the last evaluation with accelerations.
    pub(super) sol: Vec<f64>,
    /// (m) `nu`; (m) `Phi_q v`; (n) a change of the positions and the changed positions.
    pub(super) nu: Vec<f64>,
    pub(super) phiv: Vec<f64>,
    pub(super) dq: Vec<f64>,
    pub(super) qe: Vec<f64>,
}

impl<'a, 'm> Split<'a, 'm> {
    /// The machinery at the accepted state `start`, before any partition is chosen.
    pub(super) fn new(dae: &'a mut Dae<'m>, settings: &IntegratorSettings, start: Start) -> Split<'a, 'm> {
        let (n, m) = (dae.n, dae.m);
        let (q, v) = (start.q.clone(), start.qdot.clone());
        Split {
            dae,
            part: Partition::default(),
            blocks: Blocks::new(n),
            accepted: Accepted::new(start),
            newton: Newton::new(),
            error: ErrorNorm::new(settings.rtol, settings.atol, n),
            reduced_work: ReducedSolve::new(),
            noise: NoiseSample::new(),
            t_last: f64::NAN,
            q,
            v,
            sol: vec![0.0; n + m],
            nu: vec![0.0; m],
            phiv: vec![0.0; m],
            dq: vec![0.0; n],
            qe: vec![0.0; n],
        }
    }
}

impl Split<'_, '_> {
    /// Choose the partition at the accepted state `(qa, ta)`; true when the independent
    /// coordinates changed.
    pub(super) fn choose(&mut self) -> bool {
        let (m, n) = (self.dae.m, self.dae.n);
        self.dae.positions(&self.accepted.qa, self.accepted.ta);
        let friction = self.dae.has_friction();
        let (entries, jac) = self.dae.jacobian_entries();
        let changed = self.part.choose(entries, jac, (m, n), friction, &mut self.blocks);
        let (r, p) = (self.part.dep.len(), self.part.ind.len());
        self.blocks.resize(r, p);
        self.newton.resize(r);
        self.reduced_work.resize(n, m, r, p);
        self.error.resize(r, p);
        self.factor();
        self.part.influence0 = self.influence();
        self.part.influence1 = self.part.influence0;
        changed
    }

    /// `max |dq_D / dq_I|`, the largest entry of `-B^-1 Phi_q[rows, I]`, with `B` factored at
    /// the last [`Dae::positions`]: how strongly the independent coordinates move the others
    /// (0 when there are none).
    pub(super) fn influence(&mut self) -> f64 {
        if !self.blocks.sens_fresh {
            self.blocks.sensitivities(self.dae.jacobian_entries().1);
        }
        self.blocks.sens.iter().fold(0.0f64, |a, x| a.max(x.abs()))
    }

    /// Factor `B = Phi_q[rows, dep]` at the last [`Dae::positions`]; false when singular. The
    /// factors already made from the same values are kept (the accepted state is the corrector's
    /// evaluation, factored there).
    pub(super) fn factor(&mut self) -> bool {
        let (_, jac) = self.dae.jacobian_entries();
        if self.blocks.holds(jac) {
            return true;
        }
        let ok = self.blocks.factor(jac, self.dae.jacobian_point());
        self.dae.stats.factorizations += 1;
        ok
    }

    /// Resume at `(t, q, v)`, reached by another method: the accelerations and multipliers
    /// there, and that state as the accepted one (with no step before it).
    pub(super) fn resume(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), Error> {
        self.dae.accelerations(q, v, t, &mut self.sol)?;
        self.accepted.restart(t, q, v, &self.sol);
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        self.t_last = f64::NAN;
        Ok(())
    }

    /// The last evaluation (with accelerations) at `t` becomes the accepted state, and `B` is
    /// factored there (false when singular).
    pub(super) fn commit(&mut self, t: f64) -> bool {
        self.accepted.accept(t, &self.q, &self.v, &self.sol);
        self.factor()
    }

    /// `(v_I, qddot_I)` of the `j`-th accepted state back (0: the last), which is at `t`.
    pub(super) fn past(&self, j: usize, t: f64, out: &mut [f64]) {
        self.accepted.past(j, t, &self.part.ind, out);
    }

    /// `(y, y')` of the accepted state in the current coordinates.
    pub(super) fn state(&self, y: &mut [f64], yp: &mut [f64]) {
        self.accepted.state(&self.part.ind, y, yp);
    }
}
