//! The error test's norm: an error estimate of the independent state `(q_I, v_I)` mapped to
//! the change of every position and velocity it makes, weighted by `atol + rtol |y_k|`, the
//! largest ([`Split::norm`]).

use super::accepted::Accepted;
use super::Split;

/// The error norm's tolerances, weights, and the map of an attempt.
pub(super) struct ErrorNorm {
    /// The relative and absolute tolerances.
    pub(super) rtol: f64,
    pub(super) atol: f64,
    /// (n) reciprocal error weights `1 / (atol + rtol |y|)` of positions and velocities at the
    /// accepted state (the norms multiply: a step asks for three to five).
    wq: Vec<f64>,
    wv: Vec<f64>,
    /// With at most [`super::reduced::REDUCED_MAX`] independent coordinates, the error map of
    /// this attempt: column `k` is the change `(dq_D, dv_D)` (2r) that a unit change of the
    /// `k`-th entry of `(q_I, v_I)` makes ([`Split::dependent_changes`]), built at the attempt's
    /// first [`Split::norm`] (`map_ready`).
    map: Vec<f64>,
    pub(super) map_ready: bool,
    /// Scratch of [`Split::norm`]: (2r) the dependent changes, (2p) a unit change.
    changes: Vec<f64>,
    unit: Vec<f64>,
}

impl ErrorNorm {
    /// The norm of the tolerances `rtol` and `atol` for `n` coordinates.
    pub(super) fn new(rtol: f64, atol: f64, n: usize) -> ErrorNorm {
        ErrorNorm {
            rtol,
            atol,
            wq: vec![0.0; n],
            wv: vec![0.0; n],
            map: vec![],
            map_ready: false,
            changes: vec![],
            unit: vec![],
        }
    }

    /// Sizes for `r` dependent and `p` independent coordinates; no map.
    pub(super) fn resize(&mut self, r: usize, p: usize) {
        self.map.resize(4 * r * p, 0.0);
        self.changes.resize(2 * r, 0.0);
        self.unit.resize(2 * p, 0.0);
        self.map_ready = false;
    }

    /// Reciprocal error weights of every position and velocity at the accepted state.
    pub(super) fn weights(&mut self, accepted: &Accepted) {
        for (w, x) in self.wq.iter_mut().zip(&accepted.qa) {
            *w = 1.0 / (self.atol + self.rtol * x.abs());
        }
        for (w, x) in self.wv.iter_mut().zip(&accepted.va) {
            *w = 1.0 / (self.atol + self.rtol * x.abs());
        }
    }
}

impl Split<'_, '_> {
    /// The error norm of a change `x = (dq_I, dv_I)` of the independent state at the last
    /// evaluation: the largest weighted change `|dy_k| / (atol + rtol |y_k|)` over all `2 n`
    /// positions and velocities, the dependent ones changed as [`Split::dependent_changes`] says.
    /// The largest, not the mean, because the amplified error sits in a few coordinates (the crank
    /// of a quick-return whose slider is independent), which a mean over all would dilute. With
    /// at most [`REDUCED_MAX`] independent coordinates the changes, linear in `x`, come from the
    /// attempt's map (`2p` columns built at its first norm; an attempt asks for three to five
    /// norms, each of which otherwise evaluates `Phi_q` twice).
    pub(super) fn norm(&mut self, x: &[f64]) -> f64 {
        let (wq, wv) = (std::mem::take(&mut self.error.wq), std::mem::take(&mut self.error.wv));
        let s = self.norm_weighted(x, &wq, &wv);
        (self.error.wq, self.error.wv) = (wq, wv);
        s
    }

    /// [`Split::norm`] with the reciprocal weights `wq` and `wv` (n each) of the positions and
    /// velocities: those of a parameter's sensitivities, whose changes the same map gives (the
    /// dependent sensitivities follow the independent ones through the same linearised
    /// constraints as the state's changes, abam/sensitivities.rs).
    pub(super) fn norm_weighted(&mut self, x: &[f64], wq: &[f64], wv: &[f64]) -> f64 {
        let (p, r) = (self.part.ind.len(), self.part.dep.len());
        let mut s = 0.0f64;
        for (j, &c) in self.part.ind.iter().enumerate() {
            s = s.max((x[j] * wq[c]).abs()).max((x[p + j] * wv[c]).abs());
        }
        if r == 0 {
            return s;
        }
        let mut changes = std::mem::take(&mut self.error.changes);
        if self.part.reduced {
            if !self.error.map_ready {
                let mut map = std::mem::take(&mut self.error.map);
                let mut unit = std::mem::take(&mut self.error.unit);
                for (k, column) in map.chunks_exact_mut(2 * r).enumerate() {
                    unit.fill(0.0);
                    unit[k] = 1.0;
                    if self.blocks.sens_fresh {
                        // `B^-1 Phi_q[rows, I]` of this evaluation is `sens`: a unit change of
                        // `q_I` moves `q_D` by minus its column, and of `v_I` moves `v_D` so.
                        let j = k % p;
                        let (dq, dv) = column.split_at_mut(r);
                        if k < p {
                            for (d, s) in dq.iter_mut().zip(&self.blocks.sens[j * r..(j + 1) * r]) {
                                *d = -s;
                            }
                            self.velocity_changes(&unit, dq, dv);
                        } else {
                            dq.fill(0.0);
                            for (d, s) in dv.iter_mut().zip(&self.blocks.sens[j * r..(j + 1) * r]) {
                                *d = -s;
                            }
                        }
                    } else {
                        self.dependent_changes(&unit, column);
                    }
                }
                (self.error.map, self.error.unit, self.error.map_ready) = (map, unit, true);
            }
            changes.fill(0.0);
            for (column, &xk) in self.error.map.chunks_exact(2 * r).zip(x) {
                for (c, m) in changes.iter_mut().zip(column) {
                    *c += m * xk;
                }
            }
        } else {
            self.dependent_changes(x, &mut changes);
        }
        let (dq, dv) = changes.split_at(r);
        for ((&c, a), b) in self.part.dep.iter().zip(dq).zip(dv) {
            s = s.max((a * wq[c]).abs()).max((b * wv[c]).abs());
        }
        self.error.changes = changes;
        s
    }

    /// The changes `out = (dq_D, dv_D)` (2r) of the dependent positions and velocities that a
    /// change `x = (dq_I, dv_I)` of the independent state makes at the last evaluation
    /// `(q, v, t)`, to first order through `Phi = 0` and `Phi_q v = nu` (`B` as factored,
    /// `Phi_q` at the evaluation):
    ///
    /// ```text
    /// dq_D = -B^-1 Phi_q[rows, I] dq_I
    /// dv_D = -B^-1 (Phi_q[rows, I] dv_I + d(Phi_q v)/dq dq)        (dq = (dq_I, dq_D))
    /// ```
    ///
    /// An error of the independent coordinates is an error of every coordinate they determine,
    /// amplified by `dq_D / dq_I`, which grows without bound near a fold (an independent
    /// coordinate at its extreme); there the velocities' dependence on the positions (the second
    /// term, `~ (dq_D / dq_I)^3 v_I`) dominates. The directional derivative of `Phi_q v` is a
    /// difference quotient over a relative change `sqrt(eps)` of the positions. Uses `dq`, `qe`
    /// as scratch.
    fn dependent_changes(&mut self, x: &[f64], out: &mut [f64]) {
        let (p, r) = (self.part.ind.len(), self.part.dep.len());
        self.blocks.times_independent(self.dae.jacobian_entries().1, &x[..p]);
        self.blocks.solve();
        let (dq, dv) = out.split_at_mut(r);
        for (o, d) in dq.iter_mut().zip(&self.blocks.rhs) {
            *o = -d;
        }
        self.velocity_changes(x, dq, dv);
    }

    /// `dv_D` (into `dv`) of [`Split::dependent_changes`] for the change `x = (dq_I, dv_I)`
    /// whose dependent positions change by `dq_D`.
    fn velocity_changes(&mut self, x: &[f64], dq_d: &[f64], dv: &mut [f64]) {
        let (n, p) = (self.dae.n, self.part.ind.len());
        let mut dq = std::mem::take(&mut self.dq);
        dq.fill(0.0);
        for (j, &c) in self.part.ind.iter().enumerate() {
            dq[c] = x[j];
        }
        for (&c, &d) in self.part.dep.iter().zip(dq_d) {
            dq[c] = d;
        }
        // d(Phi_q v)/dq dq by a difference quotient, then dv_D.
        let size = dq.iter().fold(0.0f64, |a, d| a.max(d.abs()));
        let t = self.t_last;
        self.blocks.times_independent(self.dae.jacobian_entries().1, &x[p..]);
        if size > 0.0 && t.is_finite() {
            let scale = self.q.iter().fold(1.0f64, |a, x| a.max(x.abs()));
            let e = f64::EPSILON.sqrt() * scale / size;
            for k in 0..n {
                self.qe[k] = self.q[k] + e * dq[k];
            }
            self.dae.positions(&self.q, t);
            self.dae.jv(&self.v, &mut self.nu);
            self.dae.jv_at(&self.qe, t, &self.v, &mut self.phiv);
            for (b, &row) in self.blocks.rhs.iter_mut().zip(&self.part.rows) {
                *b += (self.phiv[row] - self.nu[row]) / e;
            }
        }
        self.blocks.solve();
        for (o, d) in dv.iter_mut().zip(&self.blocks.rhs) {
            *o = -d;
        }
        self.dq = dq;
    }
}
