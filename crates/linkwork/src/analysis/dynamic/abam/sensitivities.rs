//! Design sensitivities integrated with the state by `abam` (docs/sensitivities.md, "Dynamic
//! analyses with abam").
//!
//! For each parameter `p`, the independent parts `(s_I, s_v,I)` of `s = dq/dp` and
//! `s_v = dqdot/dp` are more components of the Adams method's `y`, after the state's `(q_I, v_I)`:
//! they are predicted, corrected, error-tested, interpolated and carried across a re-partition by
//! the same formulas and steps. Their derivative at an evaluation of the state `(t, q, v)`:
//!
//! ```text
//! B s_D  = -(Phi_q[rows, I] s_I + Phi_p)[rows]                       (position level)
//! B s_vD = -(d/dp (Phi_q qdot - nu))[rows]    at s_vD = 0            (velocity level)
//! [M, Phi_q^T; Phi_q, 0] [s_a; s_lambda] = [dQ - M_p qddot - (d/dp Phi_q)^T lambda;
//!                                           -d/dp (Phi_q qddot - gamma)]
//! y'_p = (s_v,I, s_a,I)
//! ```
//!
//! with `B = Phi_q[rows, D]` the partition's dependent block factored at `q`, the right-hand sides
//! from [`DynamicSensitivity::constraints_along`] and the last system solved by
//! [`DynamicSensitivity::accelerations`] with the augmented factorization at the state.

use super::super::adams::MAX_ORDER;
use super::super::{hermite5, Output};
use super::split::Split;
use crate::analysis::sensitivity::{DynamicSensitivity, Track};
use crate::error::Error;

/// The sensitivities of every parameter asked, at the last evaluation and the accepted states.
pub(super) struct Sensitivities<'e, 'm> {
    /// The sensitivity equations.
    eq: &'e mut DynamicSensitivity<'m>,
    /// The relative tolerance, and each parameter's absolute one, IDAS's `atolS = atol / |p|`
    /// (as bdf's: a sensitivity times its parameter's size is the change of the state for a
    /// relative change of 1 of the parameter).
    rtol: f64,
    atol: Vec<f64>,
    /// Each parameter's derivatives at the last evaluation, at the last accepted state and at
    /// the one before it.
    now: Vec<Track>,
    accepted: Vec<Track>,
    previous: Vec<Track>,
    /// Each parameter's `(s_v, s_a)` at the last `MAX_ORDER + 1` accepted states, a ring (`past_at`
    /// the newest; the state's ring, `Accepted::past`, is recorded at the same states), with
    /// their times.
    past_t: Vec<f64>,
    past: Vec<Vec<(Vec<f64>, Vec<f64>)>>,
    past_at: usize,
    /// Each parameter's reciprocal error weights of `s` and `s_v` at the accepted state.
    wq: Vec<Vec<f64>>,
    wv: Vec<Vec<f64>>,
    /// (n + m) `[qddot; lambda]` of the augmented solve at the last evaluation.
    sol: Vec<f64>,
    /// (m) scratch.
    rows: Vec<f64>,
}

impl<'e, 'm> Sensitivities<'e, 'm> {
    /// The sensitivities `tracks` at the start (`t`; [`DynamicSensitivity::start`]) of the
    /// equations `eq`, at the tolerances `rtol`, `atol`, for `m` constraint rows.
    pub(super) fn new(
        eq: &'e mut DynamicSensitivity<'m>,
        tracks: Vec<Track>,
        t: f64,
        (rtol, atol): (f64, f64),
        m: usize,
    ) -> Sensitivities<'e, 'm> {
        let n = tracks.first().map_or(0, |tr| tr.q.len());
        let count = tracks.len();
        let atol = (0..count).map(|k| atol / eq.size(k)).collect();
        let past = tracks.iter().map(|tr| (tr.v.clone(), tr.a.clone())).collect::<Vec<_>>();
        let mut sens = Sensitivities {
            eq,
            rtol,
            atol,
            now: tracks.clone(),
            previous: tracks.clone(),
            accepted: tracks,
            past_t: vec![t; MAX_ORDER + 1],
            past: vec![past; MAX_ORDER + 1],
            past_at: 0,
            wq: vec![vec![0.0; n]; count],
            wv: vec![vec![0.0; n]; count],
            sol: vec![0.0; n + m],
            rows: vec![0.0; m],
        };
        sens.weights();
        sens
    }

    /// The number of Adams components of the state and of the sensitivities together, for `p`
    /// independent coordinates: `2 p` for each.
    pub(super) fn width(sens: Option<&Self>, p: usize) -> usize {
        2 * p * (1 + sens.map_or(0, |z| z.accepted.len()))
    }

    /// The reciprocal error weights of each parameter at the accepted state.
    fn weights(&mut self) {
        for (k, tr) in self.accepted.iter().enumerate() {
            let atol = self.atol[k];
            for (w, x) in self.wq[k].iter_mut().zip(&tr.q) {
                *w = 1.0 / (atol + self.rtol * x.abs());
            }
            for (w, x) in self.wv[k].iter_mut().zip(&tr.v) {
                *w = 1.0 / (atol + self.rtol * x.abs());
            }
        }
    }

    /// The sensitivities' part (after the state's `2 p`) of `(y, y')` at the accepted state in
    /// the independent coordinates `ind`.
    pub(super) fn state(&self, ind: &[usize], y: &mut [f64], yp: &mut [f64]) {
        let p = ind.len();
        for (k, tr) in self.accepted.iter().enumerate() {
            let at = 2 * p * (1 + k);
            for (j, &c) in ind.iter().enumerate() {
                (y[at + j], y[at + p + j]) = (tr.q[c], tr.v[c]);
                (yp[at + j], yp[at + p + j]) = (tr.v[c], tr.a[c]);
            }
        }
    }

    /// The sensitivities' part of `y'` at the `j`-th accepted state back (0: the last), which is
    /// at `t`, in the independent coordinates `ind` ([`Split::past`] for the state's).
    pub(super) fn past(&self, j: usize, t: f64, ind: &[usize], out: &mut [f64]) {
        let len = self.past_t.len();
        let at = (self.past_at + len - j) % len;
        debug_assert!((self.past_t[at] - t).abs() <= 1e-9 * t.abs().max(1.0), "sensitivities {j} back");
        let p = ind.len();
        for (k, (v, a)) in self.past[at].iter().enumerate() {
            let base = 2 * p * (1 + k);
            for (i, &c) in ind.iter().enumerate() {
                (out[base + i], out[base + p + i]) = (v[c], a[c]);
            }
        }
    }

    /// The sensitivities' part of `y'` at the last evaluation `(t, q, v)` of `split`, which has
    /// just written the state's part: each parameter's full `s`, `s_v`, `s_a` and `s_lambda`
    /// into `now` from the independent parts in `y` (module doc). False when the dependent block
    /// is singular at `q` or a derivative is not finite.
    pub(super) fn derivatives(
        &mut self,
        split: &mut Split<'_, '_>,
        t: f64,
        y: &[f64],
        yp: &mut [f64],
    ) -> Result<bool, Error> {
        // The augmented factorization and `[qddot; lambda]` at the state (the reduced solve, when
        // the evaluation made it, leaves the first unmade and a prediction's multipliers
        // unsolved); positions evaluated at `q`, then `B` factored there (kept when it is).
        split.dae.accelerations(&split.q, &split.v, t, &mut self.sol)?;
        if !split.factor() {
            return Ok(false);
        }
        let (ind, dep, rows) = (&split.part.ind, &split.part.dep, &split.part.rows);
        let p = ind.len();
        for (k, tr) in self.now.iter_mut().enumerate() {
            let at = 2 * p * (1 + k);
            // s: the independent part from y, the dependent from the position level.
            tr.q.fill(0.0);
            for (j, &c) in ind.iter().enumerate() {
                tr.q[c] = y[at + j];
            }
            self.eq.constraints_along(k, t, &split.q, &tr.q, None, &mut self.rows);
            for (b, &row) in split.blocks.rhs.iter_mut().zip(rows) {
                *b = -self.rows[row];
            }
            split.blocks.solve();
            for (&c, &d) in dep.iter().zip(&split.blocks.rhs) {
                tr.q[c] = d;
            }
            // s_v: the same from the velocity level, which is linear in s_v with the matrix Phi_q.
            tr.v.fill(0.0);
            for (j, &c) in ind.iter().enumerate() {
                tr.v[c] = y[at + p + j];
            }
            self.eq.constraints_along(k, t, &split.q, &tr.q, Some((&split.v, &tr.v)), &mut self.rows);
            for (b, &row) in split.blocks.rhs.iter_mut().zip(rows) {
                *b = -self.rows[row];
            }
            split.blocks.solve();
            for (&c, &d) in dep.iter().zip(&split.blocks.rhs) {
                tr.v[c] = d;
            }
            self.eq.accelerations(split.dae, k, t, &split.q, &split.v, &self.sol, tr);
            for (j, &c) in ind.iter().enumerate() {
                (yp[at + j], yp[at + p + j]) = (tr.v[c], tr.a[c]);
            }
        }
        Ok(yp[2 * p..].iter().all(|x| x.is_finite()))
    }

    /// The error norm of the sensitivities' part `x` of a change of `y` at the last evaluation of
    /// `split`: each parameter's by [`Split::norm_weighted`] with its weights, the largest.
    pub(super) fn norm(&self, split: &mut Split<'_, '_>, x: &[f64]) -> f64 {
        let p = split.part.ind.len();
        x.chunks_exact(2 * p)
            .zip(self.wq.iter().zip(&self.wv))
            .map(|(x, (wq, wv))| split.norm_weighted(x, wq, wv))
            .fold(0.0, f64::max)
    }

    /// The last evaluation, at `t`, becomes the accepted state (as [`Split::commit`]).
    pub(super) fn commit(&mut self, t: f64) {
        std::mem::swap(&mut self.previous, &mut self.accepted);
        self.accepted.clone_from(&self.now);
        self.past_at = (self.past_at + 1) % self.past_t.len();
        self.past_t[self.past_at] = t;
        for ((v, a), tr) in self.past[self.past_at].iter_mut().zip(&self.accepted) {
            v.copy_from_slice(&tr.v);
            a.copy_from_slice(&tr.a);
        }
        self.weights();
    }

    /// Write the derivatives at the output time `t` whose state the last evaluation of `split`
    /// is (written by [`Output::push_solved`]).
    pub(super) fn push(&mut self, split: &mut Split<'_, '_>, out: &mut Output, t: f64) -> Result<(), Error> {
        self.eq.push(&mut out.results, split.dae, t, &split.q, &split.v, &self.sol, &self.now)
    }

    /// Write the derivatives at the output time `t` inside the last step whose state is the
    /// quintic Hermite interpolant of the step's ends (written by [`Output::push`], which has
    /// factored the augmented system there): `s` and `s_v` by the same interpolant of the
    /// sensitivities at the ends, `s_a` and `s_lambda` from them at the state.
    pub(super) fn push_interpolated(
        &mut self,
        split: &mut Split<'_, '_>,
        out: &mut Output,
        t: f64,
    ) -> Result<(), Error> {
        let (tp, ta) = (split.accepted.tp, split.accepted.ta);
        let sol = out.solution().to_vec();
        for (k, tr) in self.now.iter_mut().enumerate() {
            let (y0, y1) = (&self.previous[k], &self.accepted[k]);
            let h = ta - tp;
            hermite5((t - tp) / h, h, [&y0.q, &y0.v, &y0.a], [&y1.q, &y1.v, &y1.a], &mut tr.q, &mut tr.v);
            self.eq.accelerations(split.dae, k, t, &split.q, &split.v, &sol, tr);
        }
        self.eq.push(&mut out.results, split.dae, t, &split.q, &split.v, &sol, &self.now)
    }
}
