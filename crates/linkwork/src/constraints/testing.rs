//! Test harness shared by every joint: analytic Jacobian, `nu` and `gamma` against central finite
//! differences of `Phi` (an independent computation from the residual alone).

use super::{ConfigBuf, Constraint};

/// A small deterministic generator, so that failures reproduce.
pub struct Lcg(u64);

impl Lcg {
    pub fn new(seed: u64) -> Lcg {
        Lcg(seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407))
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (self.0 >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
}

/// Check `Phi_q`, `nu` and `gamma` of `c` against central differences of `Phi` at `(q, qdot, t)`.
///
/// Step `h = 1e-5`: central differences have truncation error `~h^2 |Phi'''| ~ 1e-10` and rounding
/// error `~eps |Phi| / h ~ 1e-11` for first derivatives, so `1e-7` absolute leaves a wide margin on
/// coordinates of order one. For `gamma` (a second difference, rounding `~eps/h^2`) the step is
/// `1e-4` and the tolerance `1e-5` (rounding `~1e-8`, truncation `~1e-8`).
pub fn check_fd(c: &dyn Constraint, q: &[f64], qdot: &[f64], t: f64) {
    let m = c.rows();
    let cols = c.columns().to_vec();
    let w = cols.len();
    assert_eq!(c.row_names().len(), m, "one name per row");
    let mut jac = vec![0.0; m * w];
    c.jacobian_at(q, t, &mut jac);
    let (mut fp, mut fm) = (vec![0.0; m], vec![0.0; m]);
    let h = 1e-5;
    for (k, &col) in cols.iter().enumerate() {
        let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
        qp[col] += h;
        qm[col] -= h;
        c.phi_at(&qp, t, &mut fp);
        c.phi_at(&qm, t, &mut fm);
        for r in 0..m {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let an = jac[r * w + k];
            assert!((fd - an).abs() < 1e-7, "{c:?}: Phi_q[{r}][col {col}] analytic {an} vs fd {fd}");
        }
    }
    // Columns not listed must not matter.
    for col in 0..q.len() {
        if cols.contains(&col) {
            continue;
        }
        let (mut qp, mut q0) = (q.to_vec(), vec![0.0; m]);
        qp[col] += 0.1;
        c.phi_at(&qp, t, &mut fp);
        c.phi_at(q, t, &mut q0);
        for r in 0..m {
            assert_eq!(fp[r], q0[r], "{c:?}: row {r} depends on unlisted column {col}");
        }
    }
    let mut nu = vec![0.0; m];
    c.nu_at(q, t, &mut nu);
    c.phi_at(q, t + h, &mut fp);
    c.phi_at(q, t - h, &mut fm);
    for r in 0..m {
        let fd = -(fp[r] - fm[r]) / (2.0 * h);
        assert!((fd - nu[r]).abs() < 1e-7, "{c:?}: nu[{r}] analytic {} vs fd {fd}", nu[r]);
    }
    // Along q(s) = q + s qdot, t(s) = t + s: d2 Phi / ds2 = -gamma.
    let mut gamma = vec![0.0; m];
    c.gamma_at(q, qdot, t, &mut gamma);
    let h2 = 1e-4;
    let qp: Vec<f64> = q.iter().zip(qdot).map(|(a, b)| a + h2 * b).collect();
    let qm: Vec<f64> = q.iter().zip(qdot).map(|(a, b)| a - h2 * b).collect();
    let mut f0 = vec![0.0; m];
    c.phi_at(&qp, t + h2, &mut fp);
    c.phi_at(&qm, t - h2, &mut fm);
    c.phi_at(q, t, &mut f0);
    for r in 0..m {
        let fd = -(fp[r] - 2.0 * f0[r] + fm[r]) / (h2 * h2);
        assert!((fd - gamma[r]).abs() < 1e-5, "{c:?}: gamma[{r}] analytic {} vs fd {fd}", gamma[r]);
    }
}

/// Run [`check_fd`] at several random states of a system with `bodies` bodies.
pub fn check_fd_random(c: &dyn Constraint, bodies: usize, seed: u64) {
    check_fd_random_where(c, bodies, seed, &|_| true);
}

/// As [`check_fd_random`], skipping the states where `accept(q)` is false: for rows with a
/// singularity (coincident points, coincident gear centres), whose derivatives grow without bound
/// near it, so that the fixed absolute tolerances of [`check_fd`] do not apply there.
pub fn check_fd_random_where(c: &dyn Constraint, bodies: usize, seed: u64, accept: &dyn Fn(&[f64]) -> bool) {
    let mut rng = Lcg::new(seed);
    let mut checked = 0;
    while checked < 20 {
        let q = rng.vec(3 * bodies, -2.0, 2.0);
        let qdot = rng.vec(3 * bodies, -3.0, 3.0);
        let t = rng.uniform(0.0, 2.0);
        if accept(&q) {
            check_fd(c, &q, &qdot, t);
            checked += 1;
        }
    }
}

/// `(Phi, Phi_q, gamma)` of `c` at `q`, `qdot` and `t = 0`, for a hand-derived check (`Phi`
/// starts as NaN, so that a row it does not write fails).
pub fn evaluate(c: &dyn Constraint, q: &[f64], qdot: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let rows = c.rows();
    let (mut phi, mut jac, mut gamma) = (vec![f64::NAN; rows], vec![0.0; rows * c.columns().len()], vec![0.0; rows]);
    c.phi_at(q, 0.0, &mut phi);
    c.jacobian_at(q, 0.0, &mut jac);
    c.gamma_at(q, qdot, 0.0, &mut gamma);
    (phi, jac, gamma)
}

/// Each entry of `got` within `tol` of `want`'s.
pub fn assert_close(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "{got:?} against {want:?}");
    for (a, b) in got.iter().zip(want) {
        assert!((a - b).abs() < tol, "{got:?} against {want:?}");
    }
}

/// Calls on a bare coordinate vector, for tests: computes the rotations and forwards.
pub trait OnSlice {
    fn phi_at(&self, q: &[f64], t: f64, out: &mut [f64]);
    fn jacobian_at(&self, q: &[f64], t: f64, out: &mut [f64]);
    fn nu_at(&self, q: &[f64], t: f64, out: &mut [f64]);
    fn gamma_at(&self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]);
}

impl<C: Constraint + ?Sized> OnSlice for C {
    fn phi_at(&self, q: &[f64], t: f64, out: &mut [f64]) {
        self.phi(&ConfigBuf::new(q).view(), t, out)
    }
    fn jacobian_at(&self, q: &[f64], t: f64, out: &mut [f64]) {
        self.jacobian(&ConfigBuf::new(q).view(), t, out)
    }
    fn nu_at(&self, q: &[f64], t: f64, out: &mut [f64]) {
        self.nu(&ConfigBuf::new(q).view(), t, out)
    }
    fn gamma_at(&self, q: &[f64], qdot: &[f64], t: f64, out: &mut [f64]) {
        self.gamma(&ConfigBuf::new(q).view(), qdot, t, out)
    }
}
