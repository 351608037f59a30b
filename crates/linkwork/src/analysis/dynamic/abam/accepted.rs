//! The accepted states the integrator keeps: the last two (the ends of the last step, which
//! start Newton's iterations and interpolate inside the step) and the velocities and
//! accelerations of the last `MAX_ORDER + 1`, with which a re-partition carries the Adams
//! history over ([`super::super::adams::Adams::rebase`]).

use super::super::adams::MAX_ORDER;
use super::super::{hermite5, Start};

/// The last two accepted states and a ring of the derivatives of the recent ones.
pub(super) struct Accepted {
    /// The accepted state before the last: time, (n) positions, velocities, accelerations.
    pub(super) tp: f64,
    pub(super) qp: Vec<f64>,
    pub(super) vp: Vec<f64>,
    pub(super) ap: Vec<f64>,
    /// The last accepted state: time, (n) positions, velocities, accelerations, (m) multipliers.
    pub(super) ta: f64,
    pub(super) qa: Vec<f64>,
    pub(super) va: Vec<f64>,
    pub(super) aa: Vec<f64>,
    pub(super) la: Vec<f64>,
    /// The velocities and accelerations of the last `MAX_ORDER + 1` accepted states, a ring
    /// (`past_at` the newest), with their times.
    past_t: Vec<f64>,
    past_v: Vec<Vec<f64>>,
    past_a: Vec<Vec<f64>>,
    past_at: usize,
}

impl Accepted {
    /// `start` as the accepted state, with no step before it.
    pub(super) fn new(start: Start) -> Accepted {
        let Start { t, q, qdot, qddot, lambda } = start;
        let n = q.len();
        let mut accepted = Accepted {
            tp: t,
            qp: q.clone(),
            vp: qdot.clone(),
            ap: qddot.clone(),
            ta: t,
            qa: q,
            va: qdot,
            aa: qddot,
            la: lambda,
            past_t: vec![t; MAX_ORDER + 1],
            past_v: vec![vec![0.0; n]; MAX_ORDER + 1],
            past_a: vec![vec![0.0; n]; MAX_ORDER + 1],
            past_at: 0,
        };
        accepted.record();
        accepted
    }

    /// `(t, q, v)` with `sol = [qddot; lambda]` becomes the accepted state, the last one the
    /// state before it.
    pub(super) fn accept(&mut self, t: f64, q: &[f64], v: &[f64], sol: &[f64]) {
        let n = q.len();
        self.tp = self.ta;
        std::mem::swap(&mut self.qp, &mut self.qa);
        std::mem::swap(&mut self.vp, &mut self.va);
        std::mem::swap(&mut self.ap, &mut self.aa);
        self.ta = t;
        self.qa.copy_from_slice(q);
        self.va.copy_from_slice(v);
        self.aa.copy_from_slice(&sol[..n]);
        self.la.copy_from_slice(&sol[n..]);
        self.record();
    }

    /// `(t, q, v)` with `sol = [qddot; lambda]` becomes the accepted state, with no step before
    /// it (reached by another method).
    pub(super) fn restart(&mut self, t: f64, q: &[f64], v: &[f64], sol: &[f64]) {
        let n = q.len();
        self.ta = t;
        self.qa.copy_from_slice(q);
        self.va.copy_from_slice(v);
        self.aa.copy_from_slice(&sol[..n]);
        self.la.copy_from_slice(&sol[n..]);
        self.tp = t;
        self.qp.copy_from_slice(q);
        self.vp.copy_from_slice(v);
        self.ap.copy_from_slice(&sol[..n]);
        self.record();
    }

    /// The accepted state's time, velocities and accelerations become the newest of the ring.
    fn record(&mut self) {
        self.past_at = (self.past_at + 1) % self.past_t.len();
        self.past_t[self.past_at] = self.ta;
        self.past_v[self.past_at].copy_from_slice(&self.va);
        self.past_a[self.past_at].copy_from_slice(&self.aa);
    }

    /// `(v_I, qddot_I)` of the `j`-th accepted state back (0: the last), which is at `t`, for the
    /// independent coordinates `ind`.
    pub(super) fn past(&self, j: usize, t: f64, ind: &[usize], out: &mut [f64]) {
        let len = self.past_t.len();
        let at = (self.past_at + len - j) % len;
        debug_assert!(
            (self.past_t[at] - t).abs() <= 1e-9 * t.abs().max(1.0),
            "state {j} back at {} not {t}",
            self.past_t[at]
        );
        let p = ind.len();
        for (k, &c) in ind.iter().enumerate() {
            (out[k], out[p + k]) = (self.past_v[at][c], self.past_a[at][c]);
        }
    }

    /// `(y, y')` of the accepted state in the independent coordinates `ind`.
    pub(super) fn state(&self, ind: &[usize], y: &mut [f64], yp: &mut [f64]) {
        let p = ind.len();
        for (j, &c) in ind.iter().enumerate() {
            (y[j], y[p + j]) = (self.qa[c], self.va[c]);
            (yp[j], yp[p + j]) = (self.va[c], self.aa[c]);
        }
    }

    /// The positions and velocities at `t` of the quintic Hermite interpolant of the last step's
    /// ends, into `q` and `v` (the last step of positive length).
    pub(super) fn interpolate(&self, t: f64, q: &mut [f64], v: &mut [f64]) {
        let h = self.ta - self.tp;
        let (y0, y1) = ([&self.qp[..], &self.vp[..], &self.ap[..]], [&self.qa[..], &self.va[..], &self.aa[..]]);
        hermite5((t - self.tp) / h, h, y0, y1, q, v);
    }
}
