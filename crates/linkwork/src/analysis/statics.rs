//! Static equilibrium, single or quasi-static.
//!
//! With the velocities zero, the equations of motion leave
//!
//! ```text
//! R(q, lambda) = [ Q(q, 0, t) - Phi_q^T lambda ] = 0         (n)
//!                [ Phi(q, t)                   ]             (m)
//! ```
//!
//! solved by Newton's method on `(q, lambda)` with the matrix
//!
//! ```text
//! [ -K    -Phi_q^T ]      K = -d(Q - Phi_q^T lambda)/dq   (the tangent stiffness)
//! [ Phi_q  0       ]
//! ```
//!
//! `dQ/dq` is exact (dual numbers, as in dynamics); the geometric part `d(Phi_q^T lambda)/dq`
//! is a central difference of the analytic Jacobian (the joints have no coded second
//! derivatives), relative error about `1e-10`, which changes Newton's rate, never the residual
//! it converges to. Each Newton step is the minimum-norm solution of the linear system (SVD), so
//! redundant rows and unloaded directions do not stop it; a backtracking line search on
//! `|R_force / F|^2 + |Phi / 1 m|^2` (`F` the largest load) keeps it from overshooting. When Newton
//! does not converge from the assembled guess, the applied loads (gravity, forces, torques; not
//! the spring-dampers) are stepped up from zero, each step starting from the equilibrium of the
//! previous.
//!
//! After convergence the tangent stiffness reduced to the free directions,
//! `K_r = N^T K N` with `N` a basis of the null space of `Phi_q`, decides: singular means a
//! degree of freedom that no load or spring holds (an error: the equilibrium is not determined),
//! an eigenvalue below zero means an unstable equilibrium (reported as `stable: false`).
//!
//! A quasi-static analysis (`t_end > t_start`) repeats this at each output time, starting from
//! the previous equilibrium: the equilibrium of a mechanism driven slowly enough that inertia and
//! damping do not matter.

use super::dynamic::{factor_error, Dae};
use super::{assemble, element_names, indeterminate_rows, min_norm_solve, residual_floor, RANK_TOLERANCE};
use crate::error::{Error, RowName};
use crate::model::{Analysis, Model};
use crate::results::{Failure, Results};
use faer::{Mat, MatMut, MatRef};
use serde_json::json;

/// Newton iterations per equilibrium (or load step) before it counts as not converging.
/// Default 50: with the exact tangent Newton needs 3 to 8 from a fair guess; the line search
/// may add a few dozen on a far one, and load stepping takes over beyond that.
pub const MAX_ITERATIONS: usize = 50;

/// Force balance tolerance, relative to the largest load `F`: `1e-10`, ten digits of the
/// reactions, above the rounding of `Phi_q^T lambda` (`~1e-15 F` times the Jacobian's size).
pub const FORCE_TOLERANCE: f64 = 1e-10;

/// Smallest load increment of load stepping, as a fraction of the full load, before giving up.
pub const MIN_LOAD_STEP: f64 = 1e-3;

/// What the static solver did, for `summary.json`.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StaticStats {
    /// Newton iterations in all equilibria and load steps.
    pub iterations: usize,
    /// Load steps taken where Newton did not converge directly (0: none needed).
    pub load_steps: usize,
    /// Largest force residual `|Q - Phi_q^T lambda|` at a written equilibrium, N or N m.
    pub force_residual: f64,
    /// Largest constraint residual `|Phi|` at a written equilibrium, m or rad.
    pub position_residual: f64,
    /// The largest load `F` the force tolerance is relative to.
    pub load_scale: f64,
}

/// Why an equilibrium iteration stopped short.
struct NotConverged {
    force: f64,
    position: f64,
    row: RowName,
    load_fraction: f64,
}

/// Buffers of the static solver.
pub(crate) struct Statics<'a, 'm> {
    pub dae: &'a mut Dae<'m>,
    n: usize,
    m: usize,
    zero: Vec<f64>,
    load: Vec<f64>,
    jt: Vec<f64>,
    jac: Mat<f64>,
    dq: Mat<f64>,
    dv: Mat<f64>,
    geo: Mat<f64>,
    big: Mat<f64>,
    residual: Vec<f64>,
    trial: Vec<f64>,
    /// The largest load, for the force tolerance and the merit function.
    scale: f64,
    tolerance: f64,
    pub stats: StaticStats,
}

impl<'a, 'm> Statics<'a, 'm> {
    /// The solver of `dae`'s equilibria, with the load scale taken at the guess `(q, t)`.
    pub fn new(dae: &'a mut Dae<'m>, tolerance: f64, q: &[f64], t: f64) -> Self {
        let (n, m) = (dae.n, dae.m);
        let scale = load_scale(dae, q, t);
        Statics {
            dae,
            n,
            m,
            zero: vec![0.0; n],
            load: vec![0.0; n],
            jt: vec![0.0; n],
            jac: Mat::zeros(m, n),
            dq: Mat::zeros(n, n),
            dv: Mat::zeros(n, n),
            geo: Mat::zeros(n, n),
            big: Mat::zeros(n + m, n + m),
            residual: vec![0.0; n + m],
            trial: vec![0.0; n + m],
            scale,
            tolerance,
            stats: StaticStats { load_scale: scale, ..StaticStats::default() },
        }
    }

    /// `R(x)` into `self.residual` for `x = [q; lambda]`; returns `(max |force|, max |Phi|)`.
    fn residual_at(&mut self, x: &[f64], t: f64) -> (f64, f64) {
        let (n, m) = (self.n, self.m);
        let (q, lambda) = x.split_at(n);
        self.dae.positions(q, t);
        self.dae.load(q, &self.zero, t, &mut self.load);
        self.jt.fill(0.0);
        self.dae.add_jt(lambda, &mut self.jt);
        for k in 0..n {
            self.residual[k] = self.load[k] - self.jt[k];
        }
        self.residual[n..n + m].copy_from_slice(&self.dae.phi);
        (max_abs(&self.residual[..n]), max_abs(&self.residual[n..]))
    }

    fn merit(&self) -> f64 {
        let n = self.n;
        let f: f64 = self.residual[..n].iter().map(|r| (r / self.scale).powi(2)).sum();
        f + self.residual[n..].iter().map(|r| r * r).sum::<f64>()
    }

    /// The tangent stiffness `K = -d(Q - Phi_q^T lambda)/dq` and damping `C = -dQ/dqdot` at
    /// `(q, qdot, lambda, t)`, `(n x n)` each. Leaves the positions evaluated at `q`.
    pub fn tangent(&mut self, q: &[f64], qdot: &[f64], lambda: &[f64], t: f64) -> (Mat<f64>, Mat<f64>) {
        self.dae.positions(q, t);
        self.dae.load_jacobians(q, qdot, t, self.dq.as_mut(), self.dv.as_mut());
        geometric_stiffness(self.dae, q, lambda, t, self.geo.as_mut());
        let k = Mat::from_fn(self.n, self.n, |i, j| self.geo[(i, j)] - self.dq[(i, j)]);
        let c = Mat::from_fn(self.n, self.n, |i, j| -self.dv[(i, j)]);
        (k, c)
    }

    /// Newton from `x = [q; lambda]` at `t` and the current load scale; `x` is the last iterate
    /// either way.
    fn newton(&mut self, x: &mut [f64], t: f64) -> Result<(), NotConverged> {
        let (n, m) = (self.n, self.m);
        let dim = n + m;
        let zero = vec![0.0; n];
        let (mut force, mut position) = self.residual_at(x, t);
        for _ in 0..MAX_ITERATIONS {
            if force <= FORCE_TOLERANCE * self.scale && position <= self.tolerance.max(residual_floor(&x[..n])) {
                return Ok(());
            }
            let (k, _) = self.tangent(&x[..n], &zero, &x[n..], t);
            self.dae.jacobian_dense(self.jac.as_mut());
            self.big.fill(0.0);
            for i in 0..n {
                for j in 0..n {
                    self.big[(i, j)] = -k[(i, j)];
                }
            }
            for r in 0..m {
                for c in 0..n {
                    self.big[(n + r, c)] = self.jac[(r, c)];
                    self.big[(c, n + r)] = -self.jac[(r, c)];
                }
            }
            // `self.residual` still holds R(x): the tangent leaves it alone and restores the
            // positions at x.
            let rhs: Vec<f64> = self.residual.iter().map(|r| -r).collect();
            let Some(step) = min_norm_solve(self.big.as_ref(), &rhs) else { break };
            self.stats.iterations += 1;
            let phi0 = self.merit();
            let mut alpha = 1.0;
            loop {
                for k in 0..dim {
                    self.trial[k] = x[k] + alpha * step[k];
                }
                let trial = std::mem::take(&mut self.trial);
                let (f, p) = self.residual_at(&trial, t);
                self.trial = trial;
                let phi = self.merit();
                if phi.is_finite() && (phi <= (1.0 - 1e-4 * alpha) * phi0 || alpha < 1.0 / 1024.0) {
                    x.copy_from_slice(&self.trial);
                    (force, position) = (f, p);
                    break;
                }
                alpha *= 0.5;
            }
            if alpha < 1.0 / 1024.0 {
                break;
            }
        }
        let (force, position) = self.residual_at(x, t);
        if force <= FORCE_TOLERANCE * self.scale && position <= self.tolerance.max(residual_floor(&x[..n])) {
            return Ok(());
        }
        let worst = (0..dim)
            .map(|k| if k < n { self.residual[k].abs() / self.scale } else { self.residual[k].abs() })
            .enumerate()
            .fold((0, -1.0), |(bk, bv), (k, v)| if v > bv { (k, v) } else { (bk, bv) })
            .0;
        let row = if worst >= n {
            self.dae.sys.row_name(worst - n)
        } else {
            let names = ["x", "y", "phi"];
            RowName { element: self.dae.model.bodies[worst / 3].name.clone(), equation: names[worst % 3].into() }
        };
        Err(NotConverged { force: force / self.scale, position, row, load_fraction: 0.0 })
    }

    /// The equilibrium at `t` from `x`: Newton at full load, and load stepping from zero load
    /// when that fails.
    fn equilibrium(&mut self, x: &mut [f64], t: f64, allow_stepping: bool) -> Result<(), NotConverged> {
        let start = x.to_vec();
        self.dae.external_scale = 1.0;
        let direct = self.newton(x, t);
        if direct.is_ok() || !allow_stepping {
            return direct.map_err(|e| NotConverged { load_fraction: 1.0, ..e });
        }
        x.copy_from_slice(&start);
        self.step_load(x, t)
    }

    /// Load stepping from `x`: the applied loads scaled from zero to full, each step from the
    /// equilibrium of the last; `x` ends at the last equilibrium found.
    fn step_load(&mut self, x: &mut [f64], t: f64) -> Result<(), NotConverged> {
        let (mut done, mut inc) = (0.0f64, 0.25f64);
        let mut last = x.to_vec();
        while done < 1.0 {
            let s = (done + inc).min(1.0);
            self.dae.external_scale = s;
            self.stats.load_steps += 1;
            match self.newton(x, t) {
                Ok(()) => {
                    done = s;
                    last.copy_from_slice(x);
                    inc *= 1.5;
                }
                Err(e) => {
                    x.copy_from_slice(&last);
                    inc *= 0.5;
                    if inc < MIN_LOAD_STEP {
                        self.dae.external_scale = 1.0;
                        return Err(NotConverged { load_fraction: done, ..e });
                    }
                }
            }
        }
        self.dae.external_scale = 1.0;
        Ok(())
    }

    /// The tangent stiffness reduced to the free directions, `N^T K N`, and `N`, at `(q, lambda)`.
    pub fn reduced(&mut self, k: MatRef<'_, f64>, q: &[f64], t: f64) -> (Mat<f64>, Mat<f64>) {
        self.dae.positions(q, t);
        self.dae.jacobian_dense(self.jac.as_mut());
        let basis = null_space(self.jac.as_ref());
        let kr = basis.transpose() * k * &basis;
        (kr, basis)
    }
}

/// `out (n x n)`: `d(Phi_q^T lambda)/dq` at `(q, t)` by central differences of the analytic
/// Jacobian, step `6e-6 max(1, |q_k|)` (about the cube root of the unit round-off, which
/// balances the truncation and rounding errors at about `4e-11` relative). Leaves the positions
/// evaluated at `q`.
pub(crate) fn geometric_stiffness(dae: &mut Dae<'_>, q: &[f64], lambda: &[f64], t: f64, mut out: MatMut<'_, f64>) {
    let n = q.len();
    let mut x = q.to_vec();
    let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
    for k in 0..n {
        let h = 6e-6 * q[k].abs().max(1.0);
        x[k] = q[k] + h;
        dae.positions(&x, t);
        plus.fill(0.0);
        dae.add_jt(lambda, &mut plus);
        x[k] = q[k] - h;
        dae.positions(&x, t);
        minus.fill(0.0);
        dae.add_jt(lambda, &mut minus);
        x[k] = q[k];
        for i in 0..n {
            out[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    dae.positions(q, t);
}

/// An orthonormal basis `(n x f)` of the null space of `jac (m x n)` (right singular vectors of
/// the singular values below `RANK_TOLERANCE` times the largest).
pub(crate) fn null_space(jac: MatRef<'_, f64>) -> Mat<f64> {
    let (m, n) = (jac.nrows(), jac.ncols());
    if m == 0 {
        return Mat::identity(n, n);
    }
    let Ok(svd) = jac.svd() else { return Mat::zeros(n, 0) };
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|k| s[k]).fold(0.0f64, f64::max);
    let rank = (0..s.nrows()).filter(|&k| s[k] > RANK_TOLERANCE * smax).count();
    let v = svd.V();
    Mat::from_fn(n, n - rank, |i, j| v[(i, rank + j)])
}

/// The load scale `F` of the force tolerance: the largest generalised load at `q`, or the largest
/// weight, or the smallest positive number when nothing loads the mechanism.
fn load_scale(dae: &mut Dae<'_>, q: &[f64], t: f64) -> f64 {
    let n = q.len();
    let (mut load, zero) = (vec![0.0; n], vec![0.0; n]);
    dae.positions(q, t);
    dae.load(q, &zero, t, &mut load);
    let model = dae.model;
    let g = model.gravity[0].hypot(model.gravity[1]);
    let weight = model.bodies.iter().map(|b| b.mass * g).fold(0.0, f64::max);
    max_abs(&load).max(weight).max(f64::MIN_POSITIVE)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// The free directions' coordinates with the largest share of the null vector `v (n)`, as
/// `body.x` names, for error messages.
fn coordinates_of(model: &Model, v: &[f64]) -> Vec<String> {
    let vmax = max_abs(v);
    let names = ["x", "y", "phi"];
    (0..v.len())
        .filter(|&k| v[k].abs() >= 0.2 * vmax)
        .map(|k| format!("{}.{}", model.bodies[k / 3].name, names[k % 3]))
        .collect()
}

/// The result of [`solve`]: the equilibrium, its multipliers and its stability.
pub(crate) struct Equilibrium {
    pub q: Vec<f64>,
    pub lambda: Vec<f64>,
    /// Smallest eigenvalue of the symmetric part of the reduced stiffness (N m / rad or N / m);
    /// `None` with no free directions.
    pub min_stiffness: Option<f64>,
}

/// The equilibrium of `dae` at `t` from the initial guess `q0`, with the checks described in the
/// module documentation.
pub(crate) fn solve(
    st: &mut Statics<'_, '_>,
    path: &str,
    q0: &[f64],
    t: f64,
    stepping: bool,
) -> Result<Equilibrium, Error> {
    let (n, m) = (st.n, st.m);
    // Multipliers from the least-squares balance at the guess.
    st.dae.positions(q0, t);
    let (mut load, zero) = (vec![0.0; n], vec![0.0; n]);
    st.dae.load(q0, &zero, t, &mut load);
    st.dae.jacobian_dense(st.jac.as_mut());
    let lambda0 = min_norm_solve(st.jac.transpose(), &load).unwrap_or_else(|| vec![0.0; m]);
    let start: Vec<f64> = q0.iter().chain(&lambda0).copied().collect();
    let mut x = start.clone();
    let steps_before = st.stats.load_steps;
    let outcome = st.equilibrium(&mut x, t, stepping);
    let (mut min_stiffness, mut free) = stability(st, &x, t);
    // Newton finds the stationary point nearest the guess, which may be unstable (a load that
    // turns a link over the top); load stepping from the unloaded mechanism follows the branch
    // the loads bend it along. Prefer what it finds when it is stable.
    if outcome.is_ok() && stepping && st.stats.load_steps == steps_before && min_stiffness.is_some_and(|s| s < 0.0) {
        let mut y = start;
        if st.step_load(&mut y, t).is_ok() {
            let (s, f) = stability(st, &y, t);
            if s.is_some_and(|s| s > 0.0) && f.is_none() {
                (x, min_stiffness, free) = (y, s, f);
            }
        }
    }
    let (q, lambda) = x.split_at(n);
    match (outcome, free) {
        (Ok(()), None) => Ok(Equilibrium { q: q.to_vec(), lambda: lambda.to_vec(), min_stiffness }),
        (outcome, Some(coords)) => Err(Error::Model(vec![crate::Problem::new(
            path,
            format!(
                "a static analysis needs every degree of freedom held by a driver, a spring or a load that changes with position; at t = {t} s the mechanism is free to move ({}) with no stiffness against it{}: drive it, add a spring, or load it",
                coords.join(", "),
                if outcome.is_err() { ", so Newton found no equilibrium" } else { "" }
            ),
        )])),
        (Err(e), None) => Err(Error::Equilibrium {
            time: t,
            residual: e.force.max(e.position),
            row: e.row,
            iterations: st.stats.iterations,
            load_fraction: e.load_fraction,
        }),
    }
}

/// The smallest eigenvalue of the symmetric part of the reduced tangent stiffness at
/// `x = [q; lambda]` (`None` without free directions), and the coordinates of a direction without
/// stiffness if there is one.
fn stability(st: &mut Statics<'_, '_>, x: &[f64], t: f64) -> (Option<f64>, Option<Vec<String>>) {
    let n = st.n;
    let (q, lambda) = x.split_at(n);
    let zero = vec![0.0; n];
    let (k, _) = st.tangent(q, &zero, lambda, t);
    let (kr, basis) = st.reduced(k.as_ref(), q, t);
    let f = kr.nrows();
    if f == 0 {
        return (None, None);
    }
    let sym = Mat::from_fn(f, f, |i, j| 0.5 * (kr[(i, j)] + kr[(j, i)]));
    let Ok(eig) = sym.self_adjoint_eigen(faer::Side::Lower) else { return (None, None) };
    let s = eig.S().column_vector();
    let largest = (0..f).map(|i| s[i].abs()).fold(0.0f64, f64::max);
    // Zero relative to the largest eigenvalue; every eigenvalue zero is a free mechanism.
    let smallest = (0..f).min_by(|&a, &b| s[a].abs().total_cmp(&s[b].abs())).unwrap_or(0);
    let free = (largest == 0.0 || s[smallest].abs() <= 1e-9 * largest).then(|| {
        let u = eig.U();
        let v: Vec<f64> = (0..n).map(|i| (0..f).map(|j| basis[(i, j)] * u[(j, smallest)]).sum()).collect();
        coordinates_of(st.dae.model, &v)
    });
    (Some(s[0]), free)
}

/// Run a static (or quasi-static) analysis. On failure the equilibria found until then are
/// kept.
pub fn run_static(model: &Model, analysis: &Analysis) -> Result<Results, Box<Failure>> {
    let fail = |results: Results, error: Error| Box::new(Failure { error, results });
    let mut dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => return Err(fail(Results::new(model, analysis), factor_error(e, analysis.t_start))),
    };
    let n = dae.n;
    let mut results = Results::new(model, analysis);
    let mut names = super::reaction_columns(model, analysis);
    names.push("potential_energy".into());
    names.extend(model.measures.iter().map(|m| m.name.clone()));
    results.add_columns(names);
    let path = format!("analyses.{}", analysis.name);
    let t0 = analysis.t_start;
    let mut times = vec![t0];
    let count = ((analysis.t_end - t0) / analysis.step + 1e-9).floor() as usize;
    times.extend((1..=count).map(|k| t0 + k as f64 * analysis.step));
    if analysis.t_end - times[times.len() - 1] > 1e-9 * analysis.step {
        times.push(analysis.t_end);
    }
    let given = vec![false; 2 * n];
    let assembly = match assemble(&mut dae.sys, &model.q0(), &model.qdot0(), &given, t0, analysis.settings.tolerance) {
        Ok(a) => a,
        Err(e) => return Err(fail(results, e)),
    };
    let mut st = Statics::new(&mut dae, analysis.settings.tolerance, &assembly.q, t0);
    let zero = vec![0.0; n];
    let mut react = Vec::new();
    let mut row = Vec::new();
    let mut q = assembly.q.clone();
    let mut stable = true;
    let mut min_stiffness: Option<f64> = None;
    let mut indeterminate: Option<Vec<String>> = None;
    let mut error = None;
    for (k, &t) in times.iter().enumerate() {
        match solve(&mut st, &path, &q, t, k == 0) {
            Ok(eq) => {
                q.copy_from_slice(&eq.q);
                st.residual_at(&eq.q.iter().chain(&eq.lambda).copied().collect::<Vec<_>>(), t);
                st.stats.force_residual = st.stats.force_residual.max(max_abs(&st.residual[..n]));
                st.stats.position_residual = st.stats.position_residual.max(max_abs(&st.residual[n..]));
                if let Some(s) = eq.min_stiffness {
                    min_stiffness = Some(min_stiffness.map_or(s, |x: f64| x.min(s)));
                    stable &= s > 0.0;
                }
                if indeterminate.is_none() {
                    st.dae.jacobian_dense(st.jac.as_mut());
                    indeterminate = Some(element_names(&st.dae.sys, &indeterminate_rows(st.jac.as_ref())));
                }
                st.dae.reactions(&eq.q, &eq.lambda, &mut react);
                row.clear();
                row.extend_from_slice(&react);
                row.push(st.dae.potential_energy(&eq.q));
                row.extend(model.measures.iter().map(|me| me.value(&eq.q, &zero, &zero, t)));
                results.push(t, &eq.q, &zero, &zero, &row);
            }
            Err(e) => {
                error = Some(e);
                break;
            }
        }
    }
    let stats = st.stats.clone();
    let s = &mut results.summary;
    s.insert("output_points".into(), json!(results.time.len()));
    s.insert("statistics".into(), json!(stats));
    s.insert("stable".into(), json!(stable));
    s.insert("min_reduced_stiffness".into(), json!(min_stiffness));
    s.insert("indeterminate_joints".into(), json!(indeterminate.unwrap_or_default()));
    results.insert_reaction_summary(model, analysis);
    match error {
        None => Ok(results),
        Some(e) => Err(fail(results, e)),
    }
}
