//! Test harness shared by every force: exact derivatives (dual numbers) against central finite
//! differences of the load, the conservative part against the potential's gradient, and the
//! load over the force's data and the parameters (design sensitivities) against the load and
//! central finite differences.

use super::{derivatives, potential_rate, DualWork, Force, ForceLaw, Load, StateExpr, StateVar};
/// The generator the joints' harness shares, for the forces' tests.
pub use crate::constraints::testing::Lcg;
use crate::expr::tests::Params;
use crate::expr::{Dual, Expr, HyperDual, Scalar};

/// A load from `src` over names `b<k>.<x|y|phi|vx|vy|omega>` (body `k` owns `q[3k..3k+3]`) and
/// `t`, for `bodies` bodies.
pub fn expression(src: &str, bodies: usize) -> Load {
    expression_with(src, bodies, &[])
}

/// As [`expression`], with the model's parameters `params` (`(name, value)`, file order) as
/// names too.
pub fn expression_with(src: &str, bodies: usize, params: &[(&'static str, f64)]) -> Load {
    let mut vars: Vec<StateVar> = Vec::new();
    let expr = Expr::parse_with(src, &Params(params.to_vec()), &mut |name| {
        let var = if name == "t" {
            StateVar::Time
        } else {
            let (b, c) = name.split_once('.').ok_or("expected b<k>.<quantity>")?;
            let k: usize = b[1..].parse().map_err(|_| "bad body")?;
            if k >= bodies {
                return Err("no such body".into());
            }
            let names = ["x", "y", "phi", "vx", "vy", "omega"];
            let q = names.iter().position(|n| *n == c).ok_or("bad quantity")?;
            if q < 3 {
                StateVar::Position(3 * k + q)
            } else {
                StateVar::Velocity(3 * k + q - 3)
            }
        };
        Ok(vars.iter().position(|v| *v == var).unwrap_or_else(|| {
            vars.push(var);
            vars.len() - 1
        }))
    })
    .unwrap();
    Load::Expression(StateExpr::try_new(expr, vars).unwrap())
}

/// Check the dual-number derivatives of `f` against central differences of its load at random
/// local states (`n` only bounds the coordinates named in the test), and `potential_rate` against
/// a central difference of the potential along the velocity.
///
/// Step `1e-6` on values of order one: truncation `~h^2 ~ 1e-12`, rounding `~eps/h ~ 1e-10`
/// relative to the load's size, so `1e-7` relative leaves a wide margin.
pub fn check_derivatives(f: &dyn Force, n: usize, seed: u64) {
    let w = f.columns().len();
    assert!(f.columns().iter().all(|&c| c < n), "columns {:?} within {n}", f.columns());
    let mut rng = Lcg::new(seed);
    let mut work = DualWork::new(w);
    for _ in 0..5 {
        let x = rng.vec(w, -1.5, 1.5);
        let v = rng.vec(w, -2.0, 2.0);
        let t = rng.uniform(0.0, 2.0);
        let (mut dx, mut dv) = (vec![0.0; w * w], vec![0.0; w * w]);
        derivatives(f, &x, &v, t, &mut dx, &mut dv, &mut work);
        let h = 1e-6;
        let (mut fp, mut fm) = (vec![0.0; w], vec![0.0; w]);
        let mut base = vec![0.0; w];
        f.load(&x, &v, t, &mut base);
        let scale = 1.0 + base.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (which, an) in [(0, &dx), (1, &dv)] {
            for c in 0..w {
                let (mut xp, mut xm, mut vp, mut vm) = (x.clone(), x.clone(), v.clone(), v.clone());
                if which == 0 {
                    xp[c] += h;
                    xm[c] -= h;
                } else {
                    vp[c] += h;
                    vm[c] -= h;
                }
                f.load(&xp, &vp, t, &mut fp);
                f.load(&xm, &vm, t, &mut fm);
                for r in 0..w {
                    let fd = (fp[r] - fm[r]) / (2.0 * h);
                    let a = an[r * w + c];
                    assert!(
                        (fd - a).abs() < 1e-7 * scale * 10.0,
                        "{f:?}: d Q[{r}] / d {}[{c}]: dual {a} vs fd {fd}",
                        ["x", "v"][which]
                    );
                }
            }
        }
        let xp: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + h * b).collect();
        let xm: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a - h * b).collect();
        let fd = (f.potential(&xp) - f.potential(&xm)) / (2.0 * h);
        let an = potential_rate(f, &x, &v, &mut work);
        assert!((fd - an).abs() < 1e-6 * (1.0 + an.abs()), "{f:?}: dV/dt dual {an} vs fd {fd}");
    }
}

/// For a force with no damping or actuator, the load is `-grad V`: checked against the potential's
/// dual-number gradient at random states to 1e-12 relative (two exact computations).
pub fn check_conservative(f: &dyn Force, seed: u64) {
    let w = f.columns().len();
    let mut rng = Lcg::new(seed);
    let mut work = DualWork::new(w);
    for _ in 0..5 {
        let x = rng.vec(w, -1.5, 1.5);
        let mut load = vec![0.0; w];
        f.load(&x, &vec![0.0; w], 0.0, &mut load);
        for c in 0..w {
            let mut e = vec![0.0; w];
            e[c] = 1.0;
            let grad = potential_rate(f, &x, &e, &mut work);
            assert!((load[c] + grad).abs() < 1e-12 * (1.0 + grad.abs()), "{f:?}: Q[{c}] {} vs -dV {grad}", load[c]);
        }
    }
}

/// `load_data` of `f` over `S` at `(x, v, t)` with the data and parameters seeded by `seed`
/// (`seed(k, value)` for datum `k`, `seed(data.len() + k, value)` for parameter `k`), and `x`,
/// `v` by `seed_state` (`seed_state(k, value)` for `x[k]`, `seed_state(w + k, value)` for
/// `v[k]`).
fn data_at<F: ForceLaw, S: Scalar>(
    f: &F,
    (x, v, t): (&[f64], &[f64], f64),
    (data, params): (&[f64], &[f64]),
    seed_state: &dyn Fn(usize, f64) -> S,
    seed: &dyn Fn(usize, f64) -> S,
) -> Vec<S> {
    let w = x.len();
    let xs: Vec<S> = x.iter().enumerate().map(|(k, &a)| seed_state(k, a)).collect();
    let vs: Vec<S> = v.iter().enumerate().map(|(k, &a)| seed_state(w + k, a)).collect();
    let ds: Vec<S> = data.iter().enumerate().map(|(k, &a)| seed(k, a)).collect();
    let ps: Vec<S> = params.iter().enumerate().map(|(k, &a)| seed(data.len() + k, a)).collect();
    let mut out = vec![S::constant(f64::NAN); w];
    assert!(f.load_data(&xs, &vs, t, &ds, &ps, &mut out), "answers: {f:?} has no load over its data");
    out
}

/// The inputs of a force's load over its data, each as one vector: the coordinates `x`, the
/// velocities `v`, the data and the parameters.
type Inputs = [Vec<f64>; 4];

/// Which of [`Inputs`] the flat index `k` falls in, and the index within it.
fn which(inputs: &Inputs, mut k: usize) -> (usize, usize) {
    for (g, part) in inputs.iter().enumerate() {
        if k < part.len() {
            return (g, k);
        }
        k -= part.len();
    }
    panic!("input {k} past the end")
}

/// Check the load of `f` over its data and the model's parameters `params` (file order,
/// [`ForceLaw::load_data`]) at 5 random local states (`x` in `[-1.5, 1.5)`, `v` in `[-2, 2)`,
/// `t` in `[0, 2)`). Each failure's message starts with the name of the check that failed.
///
/// - `value`: over `f64` (and the value part over dual numbers) with the data's own values it
///   is [`ForceLaw::load`], to `1e-13` of the load's scale `1 + max |Q|`: the same arithmetic but
///   for a constant taken from the initial configuration, recomputed from the data.
/// - `x`, `v`, `data`, `params`: its dual-number derivative along each coordinate, velocity,
///   datum and parameter against a central difference of `load_data::<f64>` with that input
///   moved by `h = 1e-6` of its size (at least `1e-6`): truncation `h^2 |Q'''| / 6 ~ 1e-13` and
///   round-off `eps |Q| / h ~ 1e-10` relative to the scale, so `1e-7` of the scale leaves a wide
///   margin, and a wrong sign or a missing term fails.
/// - `mixed`: its hyper-dual mixed part along each coordinate and each datum or parameter (the
///   stiffness's derivative along a parameter) against the central difference, over the datum
///   or parameter, of the dual derivative along the coordinate: the same step, to `1e-6` of the
///   scale `1 + max |d2 Q|` (a difference of exact derivatives: truncation and round-off only).
/// - `potential`: where the force gives its potential over its data
///   ([`ForceLaw::potential_data`]), over `f64` it is [`ForceLaw::potential`] to `1e-13` of
///   `1 + |V|`, and its dual derivative along each coordinate, datum and parameter agrees with
///   a central difference of it (the step and tolerance of `x`, `v`, `data`, `params`).
pub fn check_data<F: ForceLaw>(f: &F, params: &[f64], seed: u64) {
    const NAMES: [&str; 4] = ["x", "v", "data", "params"];
    let w = f.columns().len();
    let data: Vec<f64> = f.data().iter().map(|&(_, v)| v).collect();
    let mut rng = Lcg::new(seed);
    for _ in 0..5 {
        let (x, v, t) = (rng.vec(w, -1.5, 1.5), rng.vec(w, -2.0, 2.0), rng.uniform(0.0, 2.0));
        let base: Inputs = [x, v, data.clone(), params.to_vec()];
        let all = base.iter().map(Vec::len).sum::<usize>();
        let first = 2 * w;
        let mut load = vec![0.0; w];
        f.load(&base[0], &base[1], t, &mut load);
        let scale = 1.0 + load.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let unit = |on: usize, at: usize| if on == at { 1.0 } else { 0.0 };
        // Over `S`, with the state seeded by `state(k, value)` and the numbers by
        // `numbers(2 w + k, value)`: one flat numbering of all inputs.
        let eval = |inputs: &Inputs, state: &dyn Fn(usize, f64) -> Dual, numbers: &dyn Fn(usize, f64) -> Dual| {
            let numbers = |k: usize, a: f64| numbers(first + k, a);
            data_at(f, (&inputs[0], &inputs[1], t), (&inputs[2], &inputs[3]), state, &numbers)
        };
        let plain = |inputs: &Inputs| {
            let none = |_: usize, a: f64| a;
            data_at(f, (&inputs[0], &inputs[1], t), (&inputs[2], &inputs[3]), &none, &none)
        };
        // The dual derivative along input `k` at `inputs`.
        let along = |k: usize, inputs: &Inputs| {
            eval(inputs, &|j, a| Dual::new(a, unit(j, k)), &|j, a| Dual::new(a, unit(j, k)))
        };
        let moved = |k: usize, by: f64| {
            let mut inputs = base.clone();
            let (g, j) = which(&inputs, k);
            inputs[g][j] += by;
            inputs
        };
        let step = |k: usize| {
            let (g, j) = which(&base, k);
            1e-6 * base[g][j].abs().max(1.0)
        };

        let own = plain(&base);
        let constant = |_: usize, a: f64| Dual::constant(a);
        let dual = eval(&base, &constant, &constant);
        for r in 0..w {
            let tol = 1e-13 * scale;
            assert!(
                (own[r] - load[r]).abs() <= tol,
                "value: {f:?}: Q[{r}] over its data {} vs load {}",
                own[r],
                load[r]
            );
            assert!((dual[r].v - load[r]).abs() <= tol, "value: {f:?}: Q[{r}] over dual numbers {:?}", dual[r]);
        }
        for k in 0..all {
            let (g, j) = which(&base, k);
            let an = along(k, &base);
            let h = step(k);
            let (fp, fm) = (plain(&moved(k, h)), plain(&moved(k, -h)));
            for r in 0..w {
                let fd = (fp[r] - fm[r]) / (2.0 * h);
                let message =
                    format!("{}: {f:?}: d Q[{r}] / d {}[{j}]: dual {} vs fd {fd}", NAMES[g], NAMES[g], an[r].d);
                assert!((an[r].d - fd).abs() <= 1e-7 * scale, "{message}");
            }
        }
        for c in 0..w {
            for k in first..all {
                let state = |j: usize, a: f64| HyperDual::seed(a, unit(j, c), 0.0);
                let numbers = |j: usize, a: f64| HyperDual::seed(a, 0.0, unit(first + j, k));
                let hyper = data_at(f, (&base[0], &base[1], t), (&base[2], &base[3]), &state, &numbers);
                let h = step(k);
                let (fp, fm) = (along(c, &moved(k, h)), along(c, &moved(k, -h)));
                let big = 1.0 + hyper.iter().fold(0.0f64, |a, q| a.max(q.e12.abs()));
                for r in 0..w {
                    let fd = (fp[r].d - fm[r].d) / (2.0 * h);
                    let (g, j) = which(&base, k);
                    assert!(
                        (hyper[r].e12 - fd).abs() <= 1e-6 * big.max(scale),
                        "mixed: {f:?}: d2 Q[{r}] / d x[{c}] d {}[{j}]: hyper-dual {} vs fd {fd}",
                        NAMES[g],
                        hyper[r].e12
                    );
                }
            }
        }
        check_potential_data(f, &base, step);
    }
}

/// The `potential` check of [`check_data`] at the inputs `base` (the velocities unused), with
/// the difference step `step(k)` of flat input `k`.
fn check_potential_data<F: ForceLaw>(f: &F, base: &Inputs, step: impl Fn(usize) -> f64) {
    let w = base[0].len();
    let at = |inputs: &Inputs, k: usize| -> Option<Dual> {
        let seed = |j: usize, a: f64| Dual::new(a, if j == k { 1.0 } else { 0.0 });
        let x: Vec<Dual> = inputs[0].iter().enumerate().map(|(j, &a)| seed(j, a)).collect();
        let data: Vec<Dual> = inputs[2].iter().enumerate().map(|(j, &a)| seed(2 * w + j, a)).collect();
        let offset = 2 * w + inputs[2].len();
        let params: Vec<Dual> = inputs[3].iter().enumerate().map(|(j, &a)| seed(offset + j, a)).collect();
        f.potential_data(&x, &data, &params)
    };
    let Some(value) = at(base, usize::MAX) else { return };
    let own = f.potential(&base[0]);
    assert!((value.v - own).abs() <= 1e-13 * (1.0 + own.abs()), "potential: {f:?}: over its data {} vs {own}", value.v);
    let all = base.iter().map(Vec::len).sum::<usize>();
    for k in (0..all).filter(|&k| !(w..2 * w).contains(&k)) {
        let (g, j) = which(base, k);
        let h = step(k);
        let moved = |by: f64| {
            let mut inputs = base.clone();
            inputs[g][j] += by;
            at(&inputs, usize::MAX).map_or(f64::NAN, |v| v.v)
        };
        let fd = (moved(h) - moved(-h)) / (2.0 * h);
        let exact = at(base, k).map_or(f64::NAN, |v| v.d);
        assert!(
            (exact - fd).abs() <= 1e-7 * (1.0 + own.abs()),
            "potential: {f:?}: d V / d input {k}: dual {exact} vs fd {fd}"
        );
    }
}

/// Each of `f`'s data names is a field of its model-file entry `T`
/// ([`crate::constraints::testing::assert_fields`]).
pub fn assert_data_fields<T: schemars::JsonSchema>(f: &dyn Force) {
    crate::constraints::testing::assert_fields::<T>(&f.data(), &format!("{f:?}"));
}

/// The data checker fails on each kind of wrong load over the data it is meant to catch: a
/// spring-damper with one fault planted in its load over the data at a time, each of which
/// leaves the other checks passing, fails the check that names it.
mod planted {
    use super::*;
    use crate::constraints::testing::assert_fails;
    use crate::forces::SpringDamper;

    /// What is planted in the spring-damper's load over its data.
    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Fault {
        /// `Q[0]` off by `1e-6`.
        Value,
        /// `(v[0] - v0[0])` added to `Q[0]`: its value is right, its derivative along `v` is not.
        Velocity,
        /// The stiffness enters with the wrong sign (its value unchanged).
        DataSign,
        /// The parameter read as a constant: its derivative is lost.
        Parameter,
        /// `(x[0] - x0[0]) (k - k0)` added to `Q[0]`: every first derivative is right, the mixed
        /// one along `x[0]` and the stiffness is not.
        Mixed,
    }

    #[derive(Debug)]
    struct Planted(SpringDamper, Fault);

    impl ForceLaw for Planted {
        fn columns(&self) -> &[usize] {
            ForceLaw::columns(&self.0)
        }
        fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
            ForceLaw::load(&self.0, x, v, t, out)
        }
        fn potential<S: Scalar>(&self, x: &[S]) -> S {
            ForceLaw::potential(&self.0, x)
        }
        fn data(&self) -> Vec<(&'static str, f64)> {
            ForceLaw::data(&self.0)
        }
        fn load_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &[S], params: &[S], out: &mut [S]) -> bool {
            let stiffness = ForceLaw::data(&self.0).iter().position(|d| d.0 == "stiffness").expect("a stiffness");
            let (mut data, mut params) = (data.to_vec(), params.to_vec());
            match self.1 {
                Fault::DataSign => data[stiffness] = S::constant(2.0 * data[stiffness].value()) - data[stiffness],
                Fault::Parameter => params[0] = S::constant(params[0].value()),
                _ => {}
            }
            ForceLaw::load_data(&self.0, x, v, t, &data, &params, out);
            let moved = |a: S| a - S::constant(a.value());
            match self.1 {
                Fault::Value => out[0] = out[0] + S::constant(1e-6),
                Fault::Velocity => out[0] = out[0] + moved(v[0]),
                Fault::Mixed => out[0] = out[0] + moved(x[0]) * moved(data[stiffness]),
                Fault::DataSign | Fault::Parameter => {}
            }
            true
        }
    }

    #[test]
    fn each_planted_fault_fails_its_check() {
        let params = [("c0", 1.5)];
        let spring = || {
            let act = expression_with("c0*(2 + sin(t)) + 0.5*b0.vx", 2, &params);
            SpringDamper::new(Some(0), [0.2, 0.1], Some(3), [-0.3, 0.4], 40.0, 2.5, 0.7, act)
        };
        // The spring itself passes.
        check_data(&spring(), &[1.5], 61);
        let cases = [
            (Fault::Value, "value:"),
            (Fault::Velocity, "v:"),
            (Fault::DataSign, "data:"),
            (Fault::Parameter, "params:"),
            (Fault::Mixed, "mixed:"),
        ];
        for (fault, check) in cases {
            let planted = Planted(spring(), fault);
            assert_fails(&fault, check, || check_data(&planted, &[1.5], 61));
        }
    }
}
