//! The noise test: whether a failed error estimate is the round-off noise of a singular
//! position ([`Split::noise_dominates`]), which no step resolves.

use super::Split;

/// A failed error estimate within this many times the noise sampled at the same point
/// ([`Split::noise_dominates`]) is that noise: a single sample of a random quantity may fall a
/// few times below its spread (on A02 at `1e-13`, approaching a flat position, the first noisy
/// estimates were 1.5 to 3.5 times the sample), while an estimate of truncation error stands
/// orders of magnitude above it (the sample is `1e-16` relative away from singular positions).
const NOISE_MARGIN: f64 = 8.0;

/// The state [`Split::noise_dominates`] restores (positions, velocities, solution, factored
/// entries) and its sample of the noise: kept here so that a step allocates nothing.
pub(super) struct NoiseSample {
    saved: [Vec<f64>; 4],
    sample: Vec<f64>,
}

impl NoiseSample {
    /// Empty buffers.
    pub(super) fn new() -> NoiseSample {
        NoiseSample { saved: [vec![], vec![], vec![], vec![]], sample: vec![] }
    }
}

impl Split<'_, '_> {
    /// Whether the error estimate `d` (the difference of `y'` at the prediction from its
    /// extrapolation) of the last evaluation, at `t`, is round-off noise: at most
    /// [`NOISE_MARGIN`] times the change of `y'` that one more Newton correction of the dependent
    /// positions makes (fresh factors of `B` at the evaluation's positions, `v_D` and the
    /// accelerations solved again there).
    ///
    /// Near a singular position (`Phi_q` losing rank, as A02's flat chain, where every choice of
    /// `B` is singular) the constraints fix `q_D` only to the round-off of `Phi` times
    /// `|B^-1|`, and the accelerations vary across that band as `1 / sigma_min(B)^2`: at
    /// `t = 2.68716 s` on A02 Newton, run to its fixed point from six starts, stalls with
    /// corrections of `1e-11` m and accelerations `2e-2` m/s^2 apart. One more correction moves
    /// `q_D` within that band; the change it makes is a sample of the noise. The last evaluation's
    /// state, the factors of `B` and the positions are restored, so that the steps that follow are
    /// those without the sample (the factors to rounding: they are made again from the same
    /// values, in the pivot order the small LU keeps, which the sample may have changed).
    pub(super) fn noise_dominates(&mut self, t: f64, d: &[f64]) -> bool {
        if self.part.dep.is_empty() || !t.is_finite() {
            return false;
        }
        let p = self.part.ind.len();
        let ok_before = self.blocks.factored_ok;
        let [mut q0, mut v0, mut s0, mut factored] = std::mem::take(&mut self.noise.saved);
        for (to, from) in
            [(&mut q0, &self.q), (&mut v0, &self.v), (&mut s0, &self.sol), (&mut factored, &self.blocks.factored)]
        {
            to.clear();
            to.extend_from_slice(from);
        }
        self.dae.positions(&self.q, t);
        for (b, &row) in self.blocks.rhs.iter_mut().zip(&self.part.rows) {
            *b = -self.dae.phi[row];
        }
        let mut ok = self.factor();
        if ok {
            self.blocks.solve();
            for (&c, dc) in self.part.dep.iter().zip(&self.blocks.rhs) {
                self.q[c] += dc;
            }
            self.dae.positions(&self.q, t);
            ok = self.factor();
        }
        if ok {
            // Phi_q v = nu with the fresh factors: two corrections reach round-off (the first
            // from velocities that met the constraints at a point round-off away).
            self.dae.nu(&self.q, t, &mut self.nu);
            for _ in 0..2 {
                self.dae.jv(&self.v, &mut self.phiv);
                for (b, &row) in self.blocks.rhs.iter_mut().zip(&self.part.rows) {
                    *b = self.nu[row] - self.phiv[row];
                }
                self.blocks.solve();
                for (&c, dc) in self.part.dep.iter().zip(&self.blocks.rhs) {
                    self.v[c] += dc;
                }
            }
            ok = self.accelerations(t, false).is_ok();
            // `sens` is now the sample's: the map and the influence must not take it for the
            // evaluation's.
            self.blocks.sens_fresh = false;
        }
        let mut sample = std::mem::take(&mut self.noise.sample);
        sample.clear();
        sample.resize(2 * p, 0.0);
        for (j, &c) in self.part.ind.iter().enumerate() {
            sample[p + j] = self.sol[c] - s0[c];
        }
        ok = ok && sample.iter().all(|x| x.is_finite());
        self.q.copy_from_slice(&q0);
        self.v.copy_from_slice(&v0);
        self.sol.copy_from_slice(&s0);
        if let Some(b) = self.blocks.current.as_mut() {
            b.factor(&factored);
        }
        std::mem::swap(&mut self.blocks.factored, &mut factored);
        self.blocks.factored_ok = ok_before;
        self.dae.positions(&self.q, t);
        let dominates = ok && self.norm(d) <= NOISE_MARGIN * self.norm(&sample);
        self.noise.saved = [q0, v0, s0, factored];
        self.noise.sample = sample;
        dominates
    }
}
