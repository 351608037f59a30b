//! Test harness shared by every force: exact derivatives (dual numbers) against central finite
//! differences of the load, and the conservative part against the potential's gradient.

use super::{derivatives, potential_rate, DualWork, Force, Load, StateExpr, StateVar};
use crate::constraints::testing::Lcg;
use crate::expr::Expr;

/// A load from `src` over names `b<k>.<x|y|phi|vx|vy|omega>` (body `k` owns `q[3k..3k+3]`) and
/// `t`, for `bodies` bodies.
pub fn expression(src: &str, bodies: usize) -> Load {
    let mut vars: Vec<StateVar> = Vec::new();
    let expr = Expr::parse(src, &mut |name| {
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
