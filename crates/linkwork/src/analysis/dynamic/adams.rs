//! Shampine and Gordon's variable-order, variable-step Adams-Bashforth-Moulton method for
//! `y' = f(t, y)` (STEP and INTRP; Shampine and Gordon 1975, "Computer Solution of Ordinary
//! Differential Equations: The Initial Value Problem", Freeman, chapters 4 to 10), the integrator
//! of `abam`. It knows no mechanics: the driver evaluates `y'`, gives the weighted error norm
//! (1 at the tolerance) and decides what a failed step means.
//!
//! Shampine and Gordon's STEP: Adams PECE in modified divided differences
//! (arrays `phi`, `psi`, `alpha`, `beta`, `sig`, `g`), with local extrapolation, error estimates
//! at orders `k - 2, k - 1, k` from the predictor-corrector difference and at `k + 1` after the
//! step, an order from 1 to `max_order` (default 12), and a step that doubles, stays, or shrinks
//! by a factor in `[0.5, 0.9]`. Steps start at order 1 and raise the order and double the step
//! every step ("phase 1") until the order is lowered or reaches the limit. The sums of the
//! predictor and the corrector are compensated for rounding (STEP's `phi(15)`, `phi(16)`).

/// Highest order of the Adams formulas: 12, as DE/STEP. Beyond it the coefficient arrays below
/// end, and higher orders gain nothing in double precision.
pub(super) const MAX_ORDER: usize = 12;
/// Shampine and Gordon's `gstr(k)`, the magnitudes of the error constants `gamma*_k` of the Adams
/// formulas of order `k` (1-based; entry 0 unused), used in the error estimates at other orders.
const GSTR: [f64; MAX_ORDER + 2] =
    [0.0, 0.5, 0.0833, 0.0417, 0.0264, 0.0188, 0.0143, 0.0114, 0.00936, 0.00789, 0.00679, 0.00592, 0.00524, 0.00468];
/// Half the tolerance, STEP's `p5eps`: the step-size rules aim at half the error the test allows.
const HALF_TOL: f64 = 0.5;

/// Shampine and Gordon's STEP and INTRP on `neq` equations. Arrays follow the book's 1-based
/// indices (entry 0 unused), so that each formula reads as printed.
pub(super) struct Adams {
    pub(super) neq: usize,
    /// Highest order allowed.
    kmax: usize,
    /// Independent variable at the last accepted step, and before the step being tried.
    pub(super) x: f64,
    xold: f64,
    /// (neq) solution at `x`, derivative of the last evaluation, predicted and corrected
    /// solutions of the step being tried.
    pub(super) y: Vec<f64>,
    pub(super) yp: Vec<f64>,
    pub(super) p: Vec<f64>,
    pub(super) yc: Vec<f64>,
    /// (neq) scratch: the difference `y'(p) - phi(1)` and an error vector.
    pub(super) d: Vec<f64>,
    tmp: Vec<f64>,
    /// (kmax + 3 columns of neq) modified divided differences `phi(., i)`.
    phi: Vec<Vec<f64>>,
    /// (neq) rounding errors of `y` and of the predictor (STEP's `phi(15)`, `phi(16)`), and of the
    /// corrected solution being tried.
    rnd_y: Vec<f64>,
    rnd_p: Vec<f64>,
    rnd_c: Vec<f64>,
    psi: [f64; MAX_ORDER + 2],
    alpha: [f64; MAX_ORDER + 2],
    beta: [f64; MAX_ORDER + 2],
    sig: [f64; MAX_ORDER + 2],
    v: [f64; MAX_ORDER + 2],
    w: [f64; MAX_ORDER + 2],
    g: [f64; MAX_ORDER + 2],
    /// Order of the step being tried, of the last accepted step, and the number of steps taken
    /// with the current step size.
    k: usize,
    pub(super) kold: usize,
    ns: usize,
    /// Size of the last accepted step (0 before the first).
    hold: f64,
    /// Raising the order and doubling the step every step.
    phase1: bool,
    /// Consecutive failures of the step being tried.
    ifail: usize,
    /// Error estimates of the attempt at orders `k - 1`, `k`, and the order it suggests.
    erkm1: f64,
    erk: f64,
    knew: usize,
}

impl Adams {
    pub(super) fn new(kmax: usize) -> Adams {
        Adams {
            neq: 0,
            kmax,
            x: 0.0,
            xold: 0.0,
            y: vec![],
            yp: vec![],
            p: vec![],
            yc: vec![],
            d: vec![],
            tmp: vec![],
            phi: vec![vec![]; MAX_ORDER + 3],
            rnd_y: vec![],
            rnd_p: vec![],
            rnd_c: vec![],
            psi: [0.0; MAX_ORDER + 2],
            alpha: [0.0; MAX_ORDER + 2],
            beta: [0.0; MAX_ORDER + 2],
            sig: [0.0; MAX_ORDER + 2],
            v: [0.0; MAX_ORDER + 2],
            w: [0.0; MAX_ORDER + 2],
            g: [0.0; MAX_ORDER + 2],
            k: 1,
            kold: 0,
            ns: 0,
            hold: 0.0,
            phase1: true,
            ifail: 0,
            erkm1: 0.0,
            erk: 0.0,
            knew: 1,
        }
    }

    /// Size the arrays for `neq` equations (allocates only when it changes).
    pub(super) fn resize(&mut self, neq: usize) {
        self.neq = neq;
        let vectors = [&mut self.y, &mut self.yp, &mut self.p, &mut self.yc, &mut self.d];
        for a in vectors.into_iter().chain([&mut self.tmp, &mut self.rnd_y, &mut self.rnd_p, &mut self.rnd_c]) {
            a.resize(neq, 0.0);
        }
        for col in &mut self.phi {
            col.resize(neq, 0.0);
        }
    }

    /// Start (or restart) at `x` with the solution and derivative in `y`, `yp`: order 1,
    /// `phi(1) = y'`, phase 1 (STEP block 0).
    pub(super) fn restart(&mut self, x: f64) {
        self.x = x;
        self.phi[1].copy_from_slice(&self.yp);
        self.phi[2].fill(0.0);
        self.rnd_y.fill(0.0);
        self.rnd_p.fill(0.0);
        (self.k, self.kold, self.hold, self.phase1, self.ifail) = (1, 0, 0.0, true, 0);
    }

    /// Carry the method over to other variables at the last accepted point `x`, keeping its
    /// order, step and history instead of restarting at order 1: `y` holds their values at `x`,
    /// and `f(j, x_j, out)` writes their derivatives at the `j`-th accepted point back,
    /// `x_j = x - psi_j` (`j = 0 ..= kold`). The modified divided differences are those the
    /// method would hold had it integrated these variables all along: they depend on the
    /// variables only through those derivatives, `phi_{i+1} = psi_1 ... psi_i f[x_0, ..., x_i]`
    /// (Shampine and Gordon, chapter 5), and every coefficient (`psi`, `alpha`, `beta`, `sig`,
    /// `g`, `ns`) only on the points. Before the first step there is no history: a restart.
    pub(super) fn rebase(&mut self, f: &mut impl FnMut(usize, f64, &mut [f64])) {
        let k = self.kold;
        if k == 0 {
            self.restart(self.x);
            return;
        }
        // phi[j + 1] <- f at x_j, then divided differences in place (level by level, from the
        // oldest point down, so that phi[j] still holds the previous level).
        let offset = |j: usize| if j == 0 { 0.0 } else { self.psi[j] };
        for j in 0..=k {
            f(j, self.x - offset(j), &mut self.phi[j + 1]);
        }
        self.yp.copy_from_slice(&self.phi[1]);
        for level in 1..=k {
            for j in (level..=k).rev() {
                let width = offset(j) - offset(j - level);
                let (lo, hi) = self.phi.split_at_mut(j + 1);
                for (a, b) in hi[0].iter_mut().zip(&lo[j]) {
                    *a = (b - *a) / width;
                }
            }
        }
        let mut scale = 1.0;
        for i in 1..=k {
            scale *= self.psi[i];
            self.phi[i + 1].iter_mut().for_each(|x| *x *= scale);
        }
        self.rnd_y.fill(0.0);
    }

    /// Coefficients `psi, alpha, beta, sig, g` of a step of size `h` (STEP block 1); those that
    /// only depend on unchanged steps are kept.
    pub(super) fn coefficients(&mut self, h: f64) {
        let k = self.k;
        let kp1 = k + 1;
        let (psi, alpha, beta, sig, v, w, g) =
            (&mut self.psi, &mut self.alpha, &mut self.beta, &mut self.sig, &mut self.v, &mut self.w, &mut self.g);
        (g[1], g[2], sig[1]) = (1.0, 0.5, 1.0);
        if h != self.hold {
            self.ns = 0;
        }
        if self.ns <= self.kold {
            self.ns += 1;
        }
        let ns = self.ns;
        if k < ns {
            return;
        }
        beta[ns] = 1.0;
        alpha[ns] = 1.0 / ns as f64;
        let mut temp1 = h * ns as f64;
        sig[ns + 1] = 1.0;
        for i in ns + 1..=k {
            let temp2 = psi[i - 1];
            psi[i - 1] = temp1;
            beta[i] = beta[i - 1] * psi[i - 1] / temp2;
            temp1 = temp2 + h;
            alpha[i] = h / temp1;
            sig[i + 1] = i as f64 * alpha[i] * sig[i];
        }
        psi[k] = temp1;
        if ns <= 1 {
            for iq in 1..=k {
                v[iq] = 1.0 / (iq * (iq + 1)) as f64;
                w[iq] = v[iq];
            }
        } else {
            if k > self.kold {
                // The order was raised: the diagonal part of v.
                v[k] = 1.0 / (k * kp1) as f64;
                for j in 1..=ns.saturating_sub(2) {
                    let i = k - j;
                    v[i] -= alpha[j + 1] * v[i + 1];
                }
            }
            for iq in 1..=kp1 - ns {
                v[iq] -= alpha[ns] * v[iq + 1];
            }
            w[1..=kp1 - ns].copy_from_slice(&v[1..=kp1 - ns]);
            g[ns + 1] = w[1];
        }
        for i in ns + 2..=kp1 {
            for iq in 1..=k + 2 - i {
                w[iq] -= alpha[i - 1] * w[iq + 1];
            }
            g[i] = w[1];
        }
    }

    /// Predict `p` at `x + h` and advance `x` (STEP block 2, first half).
    pub(super) fn predict(&mut self, h: f64) {
        let (k, ns) = (self.k, self.ns);
        self.knew = k;
        for i in ns + 1..=k {
            let b = self.beta[i];
            self.phi[i].iter_mut().for_each(|x| *x *= b);
        }
        let (head, tail) = self.phi.split_at_mut(k + 2);
        head[k + 1].swap_with_slice(&mut tail[0]);
        head[k + 1].fill(0.0);
        self.p.fill(0.0);
        for i in (1..=k).rev() {
            let (lo, hi) = self.phi.split_at_mut(i + 1);
            let gi = self.g[i];
            for l in 0..self.neq {
                self.p[l] += gi * lo[i][l];
                lo[i][l] += hi[0][l];
            }
        }
        for l in 0..self.neq {
            let tau = h * self.p[l] - self.rnd_y[l];
            self.p[l] = self.y[l] + tau;
            self.rnd_p[l] = (self.p[l] - self.y[l]) - tau;
        }
        self.xold = self.x;
        self.x += h;
    }

    /// Local error estimates with `yp` evaluated at the prediction; the error of the step (STEP
    /// block 2, second half). Also chooses whether to lower the order. `norm` is the weighted
    /// norm of a change of `y` (1 at the tolerance).
    pub(super) fn error_test(&mut self, h: f64, norm: &mut impl FnMut(&[f64]) -> f64) -> f64 {
        let k = self.k;
        for l in 0..self.neq {
            self.d[l] = self.yp[l] - self.phi[1][l];
        }
        let mut tmp = std::mem::take(&mut self.tmp);
        let mut shifted = |phi: &[f64]| {
            for l in 0..tmp.len() {
                tmp[l] = phi[l] + self.d[l];
            }
            norm(&tmp)
        };
        let absh = h.abs();
        let (mut erkm2, mut erkm1) = (0.0, 0.0);
        if k >= 3 {
            erkm2 = absh * self.sig[k - 1] * GSTR[k - 2] * shifted(&self.phi[k - 1]);
        }
        if k >= 2 {
            erkm1 = absh * self.sig[k] * GSTR[k - 1] * shifted(&self.phi[k]);
        }
        self.tmp = tmp;
        let root = absh * norm(&self.d);
        let err = root * (self.g[k] - self.g[k + 1]);
        self.erk = root * self.sig[k + 1] * GSTR[k];
        self.erkm1 = erkm1;
        self.knew = k;
        if (k >= 3 && erkm1.max(erkm2) <= self.erk) || (k == 2 && erkm1 <= 0.5 * self.erk) {
            self.knew = k - 1;
        }
        err
    }

    /// Undo the attempt and return the step to try next (STEP block 3): half the step, order 1
    /// at the third consecutive failure, the optimal step after that.
    pub(super) fn reject(&mut self, h: f64) -> f64 {
        let k = self.k;
        self.phase1 = false;
        self.x = self.xold;
        for i in 1..=k {
            let b = 1.0 / self.beta[i];
            let (lo, hi) = self.phi.split_at_mut(i + 1);
            for l in 0..self.neq {
                lo[i][l] = b * (lo[i][l] - hi[0][l]);
            }
        }
        for i in 2..=k {
            self.psi[i - 1] = self.psi[i] - h;
        }
        self.ifail += 1;
        let mut factor = 0.5;
        if self.ifail > 3 && HALF_TOL < 0.25 * self.erk {
            factor = (HALF_TOL / self.erk).sqrt();
        }
        if self.ifail >= 3 {
            self.knew = 1;
        }
        self.k = self.knew;
        factor * h
    }

    /// The corrected solution `yc` from `yp` at the prediction (STEP block 4, first part).
    pub(super) fn correct(&mut self, h: f64) {
        let c = h * self.g[self.k + 1];
        for l in 0..self.neq {
            let rho = c * (self.yp[l] - self.phi[1][l]) - self.rnd_p[l];
            self.yc[l] = self.p[l] + rho;
            self.rnd_c[l] = (self.yc[l] - self.p[l]) - rho;
        }
    }

    /// Accept the step with `yp` evaluated at `yc`: update the differences, choose the order and
    /// return the next step (STEP block 4).
    pub(super) fn accept(&mut self, h: f64, norm: &mut impl FnMut(&[f64]) -> f64) -> f64 {
        let k = self.k;
        let (kp1, kp2) = (k + 1, k + 2);
        (self.kold, self.hold, self.ifail) = (k, h, 0);
        std::mem::swap(&mut self.y, &mut self.yc);
        std::mem::swap(&mut self.rnd_y, &mut self.rnd_c);
        for l in 0..self.neq {
            let d = self.yp[l] - self.phi[1][l];
            self.phi[kp1][l] = d;
            self.phi[kp2][l] = d - self.phi[kp2][l];
        }
        for i in 1..=k {
            let (lo, hi) = self.phi.split_at_mut(kp1);
            for l in 0..self.neq {
                lo[i][l] += hi[0][l];
            }
        }
        if self.knew + 1 == k || k == self.kmax {
            self.phase1 = false;
        }
        let absh = h.abs();
        let raise = k < self.kmax;
        let mut erk = self.erk;
        if self.phase1 {
            if raise {
                self.k = kp1;
                erk = 0.0;
            }
        } else if self.knew + 1 == k {
            self.k = k - 1;
            erk = self.erkm1;
        } else if kp1 <= self.ns {
            let erkp1 = absh * GSTR[kp1] * norm(&self.phi[kp2]);
            if k == 1 {
                if erkp1 < 0.5 * erk && raise {
                    self.k = kp1;
                    erk = erkp1;
                }
            } else if self.erkm1 <= erk.min(erkp1) {
                self.k = k - 1;
                erk = self.erkm1;
            } else if erkp1 < erk && raise {
                self.k = kp1;
                erk = erkp1;
            }
        }
        if self.phase1 || HALF_TOL >= erk * 2f64.powi(self.k as i32 + 1) {
            2.0 * h
        } else if HALF_TOL >= erk {
            h
        } else {
            let r = (HALF_TOL / erk).powf(1.0 / (self.k + 1) as f64);
            absh * r.clamp(0.5, 0.9)
        }
    }

    /// The solution and its derivative at `xout` from the interpolating polynomial of the last
    /// accepted step (INTRP).
    pub(super) fn interpolate(&self, xout: f64, yout: &mut [f64], ypout: &mut [f64]) {
        let hi = xout - self.x;
        let ki = self.kold + 1;
        let mut g = [0.0; MAX_ORDER + 2];
        let mut rho = [0.0; MAX_ORDER + 2];
        let mut w = [0.0; MAX_ORDER + 2];
        for (i, wi) in w.iter_mut().enumerate().take(ki + 1).skip(1) {
            *wi = 1.0 / i as f64;
        }
        (g[1], rho[1]) = (1.0, 1.0);
        let mut term = 0.0;
        for j in 2..=ki {
            let psijm1 = self.psi[j - 1];
            let gamma = (hi + term) / psijm1;
            let eta = hi / psijm1;
            for i in 1..=ki + 1 - j {
                w[i] = gamma * w[i] - eta * w[i + 1];
            }
            g[j] = w[1];
            rho[j] = gamma * rho[j - 1];
            term = psijm1;
        }
        yout.fill(0.0);
        ypout.fill(0.0);
        for i in (1..=ki).rev() {
            for l in 0..self.neq {
                yout[l] += g[i] * self.phi[i][l];
                ypout[l] += rho[i] * self.phi[i][l];
            }
        }
        for l in 0..self.neq {
            yout[l] = self.y[l] + hi * yout[l];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integrators' error norm ([`super::super::wrms`]) at `rtol = atol = tol` against the
    /// solution `y`.
    fn weighted(y: &[f64], tol: f64) -> impl FnMut(&[f64]) -> f64 {
        let y = y.to_vec();
        move |x: &[f64]| super::super::wrms(x.iter().copied().zip(y.iter().copied()), x.len(), tol, tol)
    }

    /// The Adams core of order up to `kmax` at `t = 0` on `y' = f(t, y)` from `y0`.
    fn start(f: &impl Fn(f64, &[f64], &mut [f64]), y0: &[f64], kmax: usize) -> Adams {
        let mut ad = Adams::new(kmax);
        ad.resize(y0.len());
        ad.y.copy_from_slice(y0);
        f(0.0, y0, &mut ad.yp);
        ad.restart(0.0);
        ad
    }

    /// One attempt at a step `h` on `y' = f(t, y)` at the tolerance `tol`, as the driver makes
    /// it: `Ok` with the next step when it is accepted, `Err` with the smaller step to retry when
    /// it is rejected.
    fn step(ad: &mut Adams, f: &impl Fn(f64, &[f64], &mut [f64]), h: f64, tol: f64) -> Result<f64, f64> {
        let mut norm = weighted(&ad.y, tol);
        ad.coefficients(h);
        ad.predict(h);
        f(ad.x, &ad.p, &mut ad.yp);
        if ad.error_test(h, &mut norm) > 1.0 {
            return Err(ad.reject(h));
        }
        ad.correct(h);
        f(ad.x, &ad.yc, &mut ad.yp);
        Ok(ad.accept(h, &mut norm))
    }

    /// Integrate `y' = f(t, y)` with the Adams core alone, as the driver does; returns
    /// `(y at t_end, accepted steps, highest order)`.
    fn integrate(
        f: impl Fn(f64, &[f64], &mut [f64]),
        y0: &[f64],
        t_end: f64,
        tol: f64,
        kmax: usize,
    ) -> (Vec<f64>, usize, usize) {
        let mut ad = start(&f, y0, kmax);
        let (mut h, mut steps, mut top) = (1e-3, 0, 0);
        while ad.x < t_end - 1e-12 {
            if ad.x + h > t_end {
                h = t_end - ad.x;
            }
            match step(&mut ad, &f, h, tol) {
                Ok(next) => {
                    h = next;
                    steps += 1;
                    top = top.max(ad.kold);
                }
                Err(smaller) => h = smaller,
            }
        }
        (ad.y.clone(), steps, top)
    }

    fn oscillator(_: f64, y: &[f64], yp: &mut [f64]) {
        yp[0] = y[1];
        yp[1] = -y[0];
    }

    /// The harmonic oscillator over five periods: the error falls with the tolerance, the order
    /// rises to the limit at tight tolerances, and a tighter tolerance costs few more steps (a
    /// high-order method).
    #[test]
    fn adams_core_converges_on_the_oscillator() {
        let t_end = 10.0 * std::f64::consts::PI;
        let mut last = (f64::INFINITY, 0);
        for tol in [1e-4, 1e-7, 1e-10] {
            let (y, steps, top) = integrate(oscillator, &[1.0, 0.0], t_end, tol, MAX_ORDER);
            let error = ((y[0] - 1.0).powi(2) + y[1].powi(2)).sqrt();
            eprintln!("tol {tol:e}: error {error:.2e}, {steps} steps, highest order {top}");
            assert!(error < 100.0 * tol, "tol {tol}: error {error:e}");
            assert!(error < last.0 / 30.0, "tol {tol}: error {error:e} after {:e}", last.0);
            if tol < 1e-9 {
                assert!(top >= 8, "order {top}");
                assert!(steps < 4 * last.1, "steps {steps} after {}", last.1);
            }
            last = (error, steps);
        }
    }

    /// With the order limited to 1 the method is Euler's with local extrapolation (order 2
    /// locally): many more steps at the same tolerance than at order 12.
    #[test]
    fn order_limit_is_respected() {
        let (_, steps1, top1) = integrate(oscillator, &[1.0, 0.0], 6.0, 1e-6, 1);
        let (_, steps12, top12) = integrate(oscillator, &[1.0, 0.0], 6.0, 1e-6, MAX_ORDER);
        assert_eq!(top1, 1);
        assert!(top12 > 4);
        assert!(steps1 > 10 * steps12, "{steps1} {steps12}");
    }

    /// Observed order at a fixed order limit `k`: the local error of order `k` is controlled to
    /// the tolerance, `C h^(k+1) = tol`, so the steps over an interval grow as `tol^(-1/(k+1))`.
    /// The exponent measured over four decades of tolerance on five periods of the oscillator
    /// (from `1e-6` for orders 1 and 2, from `1e-8` for 3, where the steps are in the asymptotic
    /// range) must be within 15% of `1/(k+1)` (the error per step is controlled, not the global
    /// error, so the step count is the sharp measure of the order). Measured: 0.455, 0.316,
    /// 0.242. Order 4 measures 0.166 against 0.2 and is not asserted: at `1e-8 .. 1e-12` its
    /// steps are not yet in the range where one error term dominates.
    #[test]
    fn steps_follow_the_order() {
        let t_end = 10.0 * std::f64::consts::PI;
        for (k, tol) in [(1, 1e-6), (2, 1e-6), (3, 1e-8)] {
            let (_, coarse, _) = integrate(oscillator, &[1.0, 0.0], t_end, tol, k);
            let (_, fine, _) = integrate(oscillator, &[1.0, 0.0], t_end, tol * 1e-4, k);
            let exponent = (fine as f64 / coarse as f64).ln() / 1e4f64.ln();
            let theory = 1.0 / (k as f64 + 1.0);
            eprintln!("order {k}: {coarse} and {fine} steps, exponent {exponent:.3} (theory {theory:.3})");
            assert!((exponent - theory).abs() < 0.15 * theory, "order {k}: exponent {exponent}, theory {theory}");
        }
    }

    /// `rebase` rebuilds the differences the method keeps from the derivatives at its past
    /// points alone: after 40 steps of varying size and order on the oscillator, the rebuilt
    /// `phi_1 .. phi_{k+1}` match the kept ones to rounding (1e-12 of the largest, a difference
    /// of order 12 over steps of 0.1 loses about 8 bits), and the run continued from either
    /// state ends at the same solution to 1e-12.
    #[test]
    fn rebase_rebuilds_the_differences() {
        let tol = 1e-10;
        // The same 40 steps twice (the method is deterministic): one run kept, one rebased.
        let run = || {
            let mut ad = start(&oscillator, &[1.0, 0.0], MAX_ORDER);
            let mut history = vec![(0.0, ad.yp.clone())];
            let mut h = 1e-3;
            for _ in 0..40 {
                match step(&mut ad, &oscillator, h, tol) {
                    Ok(next) => {
                        h = next;
                        history.push((ad.x, ad.yp.clone()));
                    }
                    Err(smaller) => h = smaller,
                }
            }
            (ad, history, h)
        };
        let (mut ad, _, h) = run();
        let (mut twin, history, _) = run();
        let k = ad.kold;
        assert!(k >= 6, "order {k}");
        let kept: Vec<Vec<f64>> = ad.phi[1..=k + 1].to_vec();
        twin.phi[1..=k + 1].iter_mut().for_each(|p| p.fill(f64::NAN));
        twin.yp.fill(f64::NAN);
        twin.rebase(&mut |j, x, out: &mut [f64]| {
            let (at, f) = &history[history.len() - 1 - j];
            assert!((at - x).abs() < 1e-12, "point {j}: {at} against {x}");
            out.copy_from_slice(f);
        });
        let big = kept.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
        for (i, (a, b)) in kept.iter().zip(&twin.phi[1..=k + 1]).enumerate() {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= 1e-12 * big, "phi_{}: {x:e} against {y:e}", i + 1);
            }
        }
        let (mut h1, mut h2) = (h, h);
        for (run, h) in [(&mut ad, &mut h1), (&mut twin, &mut h2)] {
            while run.x < 3.0 {
                *h = h.min(3.0 - run.x);
                match step(run, &oscillator, *h, tol) {
                    Ok(next) | Err(next) => *h = next,
                }
            }
        }
        assert!((ad.y[0] - twin.y[0]).abs() < 1e-12 && (ad.y[1] - twin.y[1]).abs() < 1e-12, "{:?} {:?}", ad.y, twin.y);
    }

    /// INTRP reproduces the solution inside the last step to the tolerance, and its end exactly.
    #[test]
    fn interpolation_follows_the_solution() {
        let mut ad = start(&oscillator, &[1.0, 0.0], MAX_ORDER);
        let mut h = 1e-3;
        let (mut yo, mut ypo) = ([0.0; 2], [0.0; 2]);
        let mut worst = 0.0f64;
        while ad.x < 3.0 {
            match step(&mut ad, &oscillator, h, 1e-9) {
                Ok(next) => h = next,
                Err(smaller) => {
                    h = smaller;
                    continue;
                }
            }
            ad.interpolate(ad.x, &mut yo, &mut ypo);
            assert_eq!(yo, [ad.y[0], ad.y[1]]);
            let tm = ad.x - 0.5 * ad.hold;
            ad.interpolate(tm, &mut yo, &mut ypo);
            worst = worst.max((yo[0] - tm.cos()).abs()).max((ypo[0] + tm.sin()).abs());
        }
        assert!(worst < 1e-7, "{worst:e}");
    }
}
