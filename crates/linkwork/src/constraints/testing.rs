//! Test harness shared by every joint: analytic Jacobian, `nu` and `gamma` against central finite
//! differences of `Phi` (an independent computation from the residual alone), and the generic `Phi`
//! of design sensitivities against `phi`, the Jacobian, `nu`, `gamma` and finite differences in
//! the element's data.

use super::{At, ConfigBuf, Constraint, GenericPhi};
use crate::expr::{HyperDual, Nestable, Scalar, Tri};

/// An element whose generic `Phi` the checks below evaluate (over `f64` and hyper-dual numbers):
/// every [`GenericPhi`] element, and one whose rows need [`Nestable`] numbers (a cam's working
/// surface), which implements it by hand.
pub trait Checked: Constraint {
    /// `Phi` at `at` with the element's data `data`: `out: (rows)`.
    fn phi_checked<S: Nestable>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]);
}

impl<C: GenericPhi + Constraint> Checked for C {
    fn phi_checked<S: Nestable>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        self.phi_generic(at, data, out);
    }
}

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
    random_states(bodies, seed, accept, |q, qdot, t| check_fd(c, q, qdot, t));
}

/// Call `check(q, qdot, t)` at 20 random states of a system with `bodies` bodies (`q` in
/// `[-2, 2)`, `qdot` in `[-3, 3)`, `t` in `[0, 2)`) where `accept(q)` holds.
fn random_states(
    bodies: usize,
    seed: u64,
    accept: &dyn Fn(&[f64]) -> bool,
    mut check: impl FnMut(&[f64], &[f64], f64),
) {
    let mut rng = Lcg::new(seed);
    let mut checked = 0;
    while checked < 20 {
        let q = rng.vec(3 * bodies, -2.0, 2.0);
        let qdot = rng.vec(3 * bodies, -3.0, 3.0);
        let t = rng.uniform(0.0, 2.0);
        if accept(&q) {
            check(&q, &qdot, t);
            checked += 1;
        }
    }
}

/// `phi_generic` of `c` over hyper-dual numbers at `q` and `t` seeded by `seed(k, value)` for
/// `q[k]` and `seed(n, t)` for the time, with `data` seeded by `seed_data(k, value)`.
fn generic_at<C: Checked>(
    c: &C,
    q: &[f64],
    t: f64,
    seed: &dyn Fn(usize, f64) -> HyperDual,
    seed_data: &dyn Fn(usize, f64) -> HyperDual,
) -> Vec<HyperDual> {
    let qs: Vec<HyperDual> = q.iter().enumerate().map(|(k, &v)| seed(k, v)).collect();
    let data: Vec<HyperDual> = c.data().iter().enumerate().map(|(k, &(_, v))| seed_data(k, v)).collect();
    let mut out = vec![HyperDual::constant(f64::NAN); c.rows()];
    c.phi_checked(&At { q: &qs, t: seed(q.len(), t), params: &[] }, &data, &mut out);
    out
}

/// `phi_generic::<f64>` of `c` at `q` and `t` with the data `data`.
fn generic_f64<C: Checked>(c: &C, q: &[f64], t: f64, data: &[f64]) -> Vec<f64> {
    let mut out = vec![f64::NAN; c.rows()];
    c.phi_checked(&At { q, t, params: &[] }, data, &mut out);
    out
}

/// Check the generic `Phi` of `c` (design sensitivities, [`GenericPhi`]) at `(q, qdot, t)`. Each
/// failure's message starts with the name of the check that failed.
///
/// - `phi`: over `f64` with `data()`'s values it equals `phi`, to `1e-15` relative to the size of
///   the row's terms, taken as `(1 + m)^2` with `m` the largest input (rows are at most quadratic in
///   lengths: `d . d - L^2`), since it is the same arithmetic up to the order of a few operations;
///   and `phi_tri` computes it (its value part, to the same tolerance).
/// - `jacobian`: its first-order part along each unit vector of `q` is the Jacobian's column (zero
///   off `columns()`), `1e-13` on the same scale: two exact derivatives of one function, differing
///   only by round-off.
/// - `velocity`, `acceleration`: with `q` moving along `qdot` and `t` along 1 in both directions,
///   the first-order part is `Phi_q qdot - nu` and the mixed part `-gamma` (the second derivative
///   along the motion), `1e-12` relative to `1 + |gamma| (1 + m)` (more operations, still exact).
/// - `data`: its first-order part along each data slot against a central difference of
///   `phi_generic::<f64>` with the slot moved by `h = 1e-6` relative: truncation
///   `h^2 |Phi'''| / 6 ~ 1e-12` and round-off `eps |Phi| / h ~ 1e-10 (1 + m)^2`, so `1e-8`
///   relative to the same scale leaves a wide margin, and a wrong sign or a missing term fails.
pub fn check_generic<C: Checked>(c: &C, q: &[f64], qdot: &[f64], t: f64) {
    let m = c.rows();
    let data: Vec<f64> = c.data().iter().map(|&(_, v)| v).collect();
    let big = q.iter().chain(&data).chain([&t]).fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = (1.0 + big) * (1.0 + big);

    let (mut phi, generic) = (vec![0.0; m], generic_f64(c, q, t, &data));
    c.phi_at(q, t, &mut phi);
    let qt: Vec<Tri> = q.iter().map(|&v| Tri::constant(v)).collect();
    let dt: Vec<Tri> = data.iter().map(|&v| Tri::constant(v)).collect();
    let mut tri = vec![Tri::constant(f64::NAN); m];
    assert!(c.phi_tri(&At { q: &qt, t: Tri::constant(t), params: &[] }, &dt, &mut tri), "phi: {c:?} has no phi_tri");
    for r in 0..m {
        let tol = 1e-15 * scale;
        assert!((generic[r] - phi[r]).abs() <= tol, "phi: {c:?}: row {r} generic {} vs phi {}", generic[r], phi[r]);
        assert!((tri[r].value() - phi[r]).abs() <= tol, "phi: {c:?}: row {r} phi_tri {:?} vs phi {}", tri[r], phi[r]);
    }

    let cols = c.columns();
    let w = cols.len();
    let mut jac = vec![0.0; m * w];
    c.jacobian_at(q, t, &mut jac);
    let constant = |_: usize, v: f64| HyperDual::constant(v);
    for col in 0..q.len() {
        let out = generic_at(c, q, t, &|k, v| HyperDual::seed(v, if k == col { 1.0 } else { 0.0 }, 0.0), &constant);
        let at = cols.iter().position(|&k| k == col);
        for (r, o) in out.iter().enumerate() {
            let want = at.map_or(0.0, |k| jac[r * w + k]);
            assert!((o.e1 - want).abs() <= 1e-13 * scale, "jacobian: {c:?}: row {r} col {col} {} vs {want}", o.e1);
        }
    }

    let (mut nu, mut gamma) = (vec![0.0; m], vec![0.0; m]);
    c.nu_at(q, t, &mut nu);
    c.gamma_at(q, qdot, t, &mut gamma);
    let along = |k: usize, v: f64| {
        let dir = qdot.get(k).copied().unwrap_or(1.0);
        HyperDual::seed(v, dir, dir)
    };
    let out = generic_at(c, q, t, &along, &constant);
    for r in 0..m {
        let rate = (0..w).map(|k| jac[r * w + k] * qdot[cols[k]]).sum::<f64>() - nu[r];
        let tol = 1e-12 * (1.0 + gamma[r].abs()) * (1.0 + big);
        assert!((out[r].e1 - rate).abs() <= tol, "velocity: {c:?}: row {r} {} vs Phi_q qdot - nu {rate}", out[r].e1);
        assert!(
            (out[r].e12 + gamma[r]).abs() <= tol,
            "acceleration: {c:?}: row {r} {} vs -gamma {}",
            out[r].e12,
            -gamma[r]
        );
    }

    let names = c.data();
    for (k, (name, v)) in names.iter().enumerate() {
        let out = generic_at(c, q, t, &constant, &|j, x| HyperDual::seed(x, if j == k { 1.0 } else { 0.0 }, 0.0));
        let h = 1e-6 * v.abs().max(1.0);
        let (mut up, mut down) = (data.clone(), data.clone());
        up[k] += h;
        down[k] -= h;
        let (fp, fm) = (generic_f64(c, q, t, &up), generic_f64(c, q, t, &down));
        for r in 0..m {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            assert!((out[r].e1 - fd).abs() <= 1e-8 * scale, "data: {c:?}: row {r} d/d {name} {} vs fd {fd}", out[r].e1);
        }
    }
}

/// Check that the derivative of `c`'s generic `Phi` along each data slot is that of the element
/// built anew with the number moved (what setting a parameter and compiling again does, constants
/// from the initial configuration included): central differences of `phi` of `build(data +- h)`
/// at random states (`q0` held inside `build`), with the step and tolerance of
/// [`check_generic`]'s data check, for the same reasons.
pub fn check_rebuilt<C: Checked>(c: &C, build: &dyn Fn(&[f64]) -> C, bodies: usize, seed: u64) {
    let data: Vec<f64> = c.data().iter().map(|&(_, v)| v).collect();
    random_states(bodies, seed, &|_| true, |q, _, t| {
        let big = q.iter().chain(&data).chain([&t]).fold(0.0f64, |a, v| a.max(v.abs()));
        let constant = |_: usize, v: f64| HyperDual::constant(v);
        for (k, (name, v)) in c.data().iter().enumerate() {
            let out = generic_at(c, q, t, &constant, &|j, x| HyperDual::seed(x, if j == k { 1.0 } else { 0.0 }, 0.0));
            let h = 1e-6 * v.abs().max(1.0);
            let (mut up, mut down) = (data.clone(), data.clone());
            up[k] += h;
            down[k] -= h;
            let (mut fp, mut fm) = (vec![0.0; c.rows()], vec![0.0; c.rows()]);
            build(&up).phi_at(q, t, &mut fp);
            build(&down).phi_at(q, t, &mut fm);
            for r in 0..c.rows() {
                let fd = (fp[r] - fm[r]) / (2.0 * h);
                let tol = 1e-8 * (1.0 + big) * (1.0 + big);
                assert!((out[r].e1 - fd).abs() <= tol, "rebuilt: {c:?}: row {r} d/d {name} {} vs fd {fd}", out[r].e1);
            }
        }
    });
}

/// Each of `c`'s data names is a field of its model-file entry `T` ([`assert_fields`]).
pub fn assert_data_fields<T: schemars::JsonSchema>(c: &dyn Constraint) {
    assert_fields::<T>(&c.data(), &format!("{c:?}"));
}

/// Each of the data names `data` of `owner` (an element, for the message) is a field of its
/// model-file entry `T`, under which the model's compiler finds the number's gradient: the name
/// before `[` (`point_i[0]`), or a path into the entry's nested fields (`shape_j.circle.radius`,
/// `friction.mu`).
pub fn assert_fields<T: schemars::JsonSchema>(data: &[(&'static str, f64)], owner: &str) {
    let schema = serde_json::to_value(schemars::schema_for!(T)).expect("a schema is JSON");
    // A field's schema, through a reference to a definition or an optional's `anyOf`.
    fn resolve<'a>(schema: &'a serde_json::Value, mut node: &'a serde_json::Value) -> &'a serde_json::Value {
        loop {
            if let Some(r) = node.get("$ref").and_then(|r| r.as_str()) {
                node = schema.pointer(r.trim_start_matches('#')).expect("a reference within the schema");
            } else if let Some(first) = node.get("anyOf").and_then(|a| a.get(0)) {
                node = first;
            } else {
                return node;
            }
        }
    }
    for (name, _) in data {
        let mut node = Some(&schema);
        for part in name.split('.') {
            let field = part.split('[').next().unwrap_or(part);
            node = node.and_then(|n| resolve(&schema, n)["properties"].get(field));
        }
        assert!(node.is_some(), "{owner}: data {name} is not a field of {}", std::any::type_name::<T>());
    }
}

/// That `run`, a checker run on an element with `fault` planted, fails with a message that starts
/// with `check`, the name of the check that must catch it.
pub fn assert_fails(fault: &dyn std::fmt::Debug, check: &str, run: impl FnOnce() + std::panic::UnwindSafe) {
    let payload = std::panic::catch_unwind(run).expect_err("a planted fault must fail the check");
    let message = payload.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(message.starts_with(check), "{fault:?}: expected the {check} check to fail, got {message}");
}

/// Run [`check_generic`] at random states of a system with `bodies` bodies.
pub fn check_generic_random<C: Checked>(c: &C, bodies: usize, seed: u64) {
    check_generic_random_where(c, bodies, seed, &|_| true);
}

/// As [`check_generic_random`], skipping the states where `accept(q)` is false (see
/// [`check_fd_random_where`]).
pub fn check_generic_random_where<C: Checked>(c: &C, bodies: usize, seed: u64, accept: &dyn Fn(&[f64]) -> bool) {
    random_states(bodies, seed, accept, |q, qdot, t| check_generic(c, q, qdot, t));
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

/// The generic checker fails on each kind of wrong `Phi` it is meant to catch: a revolute joint
/// with one fault planted in its generic `Phi` at a time, each of which leaves some other check
/// passing, fails the check that names it.
mod planted {
    use super::*;
    use crate::constraints::{Anchor, BodyIx, Config, Revolute};

    /// What is planted in the revolute joint's generic `Phi`.
    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Fault {
        /// Row 1 off by `1e-9`.
        Value,
        /// `1e-3 (q[0] - q0[0])` added to row 0: its value is right, its `Phi_q` is not.
        Column,
        /// `1e-3 (t - t0)` added to row 0: a time dependence `nu` does not have.
        Rate,
        /// `1e-3 (t - t0)^2` added to row 0: a second time derivative `gamma` does not have.
        Curvature,
        /// `point_i[0]` enters with the wrong sign (its value unchanged).
        DataSign,
    }

    #[derive(Debug)]
    struct Planted(Revolute, Fault);

    impl Constraint for Planted {
        fn anchor(&self) -> Anchor {
            self.0.anchor()
        }
        fn row_names(&self) -> &[&'static str] {
            self.0.row_names()
        }
        fn columns(&self) -> &[usize] {
            self.0.columns()
        }
        fn phi(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
            self.0.phi(q, t, out)
        }
        fn jacobian(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
            self.0.jacobian(q, t, out)
        }
        fn gamma(&self, q: &Config<'_>, qdot: &[f64], t: f64, out: &mut [f64]) {
            self.0.gamma(q, qdot, t, out)
        }
        fn data(&self) -> Vec<(&'static str, f64)> {
            self.0.data()
        }
        fn phi_tri(&self, at: &At<'_, Tri>, data: &[Tri], out: &mut [Tri]) -> bool {
            self.phi_generic(at, data, out);
            true
        }
    }

    impl GenericPhi for Planted {
        fn parameters(&self) -> &[usize] {
            &[]
        }
        fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
            let mut data = data.to_vec();
            if self.1 == Fault::DataSign {
                data[0] = S::constant(2.0 * data[0].value()) - data[0];
            }
            self.0.phi_generic(at, &data, out);
            let moved = |x: S| x - S::constant(x.value());
            let k = S::constant(1e-3);
            match self.1 {
                Fault::Value => out[1] = out[1] + S::constant(1e-9),
                Fault::Column => out[0] = out[0] + k * moved(at.q[0]),
                Fault::Rate => out[0] = out[0] + k * moved(at.t),
                Fault::Curvature => out[0] = out[0] + k * moved(at.t) * moved(at.t),
                Fault::DataSign => {}
            }
        }
    }

    #[test]
    fn each_planted_fault_fails_its_check() {
        let joint = || Revolute::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-1.1, 0.4]);
        let (q, qdot) = (Lcg::new(3).vec(6, -2.0, 2.0), Lcg::new(4).vec(6, -3.0, 3.0));
        // The joint itself passes.
        check_generic(&joint(), &q, &qdot, 0.7);
        let cases = [
            (Fault::Value, "phi:"),
            (Fault::Column, "jacobian:"),
            (Fault::Rate, "velocity:"),
            (Fault::Curvature, "acceleration:"),
            (Fault::DataSign, "data:"),
        ];
        for (fault, check) in cases {
            let planted = Planted(joint(), fault);
            assert_fails(&fault, check, || check_generic(&planted, &q, &qdot, 0.7));
        }
    }
}
