//! Static equilibrium, single or quasi-static: the stable one, a minimum of the potential energy.
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
//! `|R_force / F|^2 + |Phi / 1 m|^2` (`F` the largest load) keeps it from overshooting.
//!
//! Newton finds the stationary point of the potential nearest the guess, which may be a maximum
//! or a saddle; from a guess where the mechanism has no stiffness (a pendulum held level) it
//! finds nothing. The tangent stiffness reduced to the free directions, `K_r = N^T K N` with `N`
//! an orthonormal basis of the null space of `Phi_q` (with the least-squares multipliers, the
//! Hessian of the potential on the constraint manifold), decides what to do next:
//!
//! - an equilibrium with `K_r` positive definite is a minimum: the answer;
//! - otherwise a **descent** marches downhill along the most negative curvature (or a flat
//!   direction the loads act along, or the loads themselves), projecting each step back onto
//!   `Phi = 0`, until the load along the path turns against it (the path's minimum); Newton
//!   starts again from there. At most [`MAX_DESCENTS`] times;
//! - an equilibrium with a zero eigenvalue is a degree of freedom nothing holds (a model error);
//! - a descent that never turns is a load with no equilibrium (a torque larger than the weight
//!   can hold): [`Error::NoEquilibrium`].
//!
//! Load stepping is the last resort when Newton and the descents do not converge: the applied
//! loads (gravity, forces, torques; not the spring-dampers) are stepped up from zero, each step
//! starting from the equilibrium of the previous.
//!
//! A quasi-static analysis (`t_end > t_start`) repeats this at each output time, starting from
//! the previous equilibrium: the equilibrium of a mechanism driven slowly enough that inertia and
//! damping do not matter.

use super::dynamic::{factor_error, Dae};
use super::sensitivity::EquilibriumSensitivity;
use super::setup::{coordinate_name, fail, held, output_times};
use super::{assemble, assemble_into, element_names, independent_rows, indeterminate_rows, residual_floor, Run, Start};
use crate::constraints::ConfigBuf;
use crate::error::{Error, Unbalanced};
use crate::linalg::dense::{equilibrated, min_norm_solve, null_space};
use crate::model::{Analysis, Model};
use crate::results::{EquilibriumReport, Failure, Results, StaticStats, Statistics};
use faer::{Mat, MatMut, MatRef};

/// Newton iterations per equilibrium (or load step) before it counts as not converging.
/// Default 50: with the exact tangent Newton needs 3 to 8 from a fair guess; the line search
/// may add a few dozen on a far one, and load stepping takes over beyond that.
pub const MAX_ITERATIONS: usize = 50;

/// Force balance tolerance, relative to the largest load `F`: `1e-10`, ten digits of the
/// reactions, above the rounding of `Phi_q^T lambda` (`~1e-15 F` times the Jacobian's size).
pub const FORCE_TOLERANCE: f64 = 1e-10;

/// Smallest load increment of load stepping, as a fraction of the full load, before giving up.
pub const MIN_LOAD_STEP: f64 = 1e-3;

/// An eigenvalue of the reduced stiffness counts as zero below this fraction of the largest:
/// `1e-9`, twenty-five times the relative error of the geometric stiffness's central difference
/// (`~4e-11`), and far below any ratio of stiffnesses within one mechanism. Below `-1e-9` it is an
/// unstable direction.
pub const ZERO_STIFFNESS: f64 = 1e-9;

/// Descents (each a march downhill, then Newton) per equilibrium before the solver gives up.
/// Each ends lower in potential energy than it started, and a saddle needs one per unstable
/// direction: 8 covers mechanisms with that many unstable directions at once, more than any
/// test or example needs (one or two).
pub const MAX_DESCENTS: usize = 8;

/// First step of a descent: `0.01` rad of rotation, or 1% of the mechanism's size in
/// translation (whichever coordinate moves most), so that a shallow well just beside the
/// saddle being left is not stepped over.
pub const DESCENT_FIRST_STEP: f64 = 1e-2;

/// Largest step of a descent (the first doubles up to it): `0.25` rad or a quarter of the
/// mechanism's size, inside the kinematic solver's `max_rotation` (0.35 rad), so that projecting
/// the tangent step back onto the constraints stays on the assembly branch.
pub const DESCENT_MAX_STEP: f64 = 0.25;

/// Steps per descent: 200, that is 50 rad (eight turns of a crank, whose potential repeats every
/// turn) or fifty times the mechanism's size at the largest step. A load that drives the
/// mechanism that far downhill without the slope turning has no equilibrium along the way.
pub const MAX_DESCENT_STEPS: usize = 200;

/// Why an equilibrium iteration stopped short.
struct NotConverged {
    force: f64,
    position: f64,
    equation: Unbalanced,
    load_fraction: f64,
}

/// Where the search for a stable equilibrium stopped.
enum Reached {
    /// At an unstable equilibrium: its index and the coordinates of its most unstable direction.
    Unstable(usize, Vec<String>),
    /// Short of an equilibrium.
    Short(NotConverged),
}

/// A descent that never turned: the loads drive the mechanism without end.
struct Runaway {
    /// Distance marched, rad (or mechanism sizes).
    travel: f64,
    /// The loads' work per unit of travel at the end, J per rad (or per mechanism size).
    push: f64,
    /// The coordinates that move.
    coordinates: Vec<String>,
}

/// The reduced stiffness at a point, decomposed, with the load along each of its directions.
struct Curvature {
    /// (f) eigenvalues of the symmetric part of `K_r`, ascending, N m / rad or N / m.
    values: Vec<f64>,
    /// (n x f) their eigenvectors in body coordinates, `N u`, orthonormal.
    vectors: Mat<f64>,
    /// (f) the unbalanced load `Q - Phi_q^T lambda` along each eigenvector.
    loads: Vec<f64>,
}

impl Curvature {
    /// The size below which an eigenvalue counts as zero.
    fn zero(&self) -> f64 {
        ZERO_STIFFNESS * self.values.iter().fold(0.0f64, |a, s| a.max(s.abs()))
    }

    /// The index: how many directions are unstable (eigenvalues below zero).
    fn index(&self) -> usize {
        let zero = self.zero();
        self.values.iter().filter(|&&s| s < -zero).count()
    }

    /// The direction without stiffness, if there is one (every one when all eigenvalues are zero).
    fn flat(&self) -> Option<usize> {
        let zero = self.zero();
        (0..self.values.len())
            .min_by(|&a, &b| self.values[a].abs().total_cmp(&self.values[b].abs()))
            .filter(|&k| self.values[k].abs() <= zero)
    }

    /// Eigenvector `k` in body coordinates `(n)`, times `sign`.
    fn vector(&self, k: usize, sign: f64) -> Vec<f64> {
        (0..self.vectors.nrows()).map(|i| sign * self.vectors[(i, k)]).collect()
    }

    /// The direction `(n)` of a descent, signed so that the load does work along it: the most
    /// negative curvature; else the flat direction the load acts along most (more than `tol`);
    /// else the load itself (steepest descent on the manifold). `None` when no load above `tol`
    /// acts along any free direction.
    fn descent(&self, tol: f64) -> Option<Vec<f64>> {
        let zero = self.zero();
        let f = self.values.len();
        let pick = if self.values[0] < -zero {
            Some(0)
        } else {
            (0..f)
                .filter(|&k| self.values[k] <= zero && self.loads[k].abs() > tol)
                .max_by(|&a, &b| self.loads[a].abs().total_cmp(&self.loads[b].abs()))
        };
        if let Some(k) = pick {
            return Some(self.vector(k, if self.loads[k] < 0.0 { -1.0 } else { 1.0 }));
        }
        if self.loads.iter().all(|l| l.abs() <= tol) {
            return None;
        }
        Some((0..self.vectors.nrows()).map(|i| (0..f).map(|k| self.vectors[(i, k)] * self.loads[k]).sum()).collect())
    }
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
    /// The mechanism's size, m: the unit of a translation in a descent step.
    size: f64,
    pub stats: StaticStats,
}

impl<'a, 'm> Statics<'a, 'm> {
    /// The solver of `dae`'s equilibria, with the load scale taken at the guess `(q, t)`.
    pub fn new(dae: &'a mut Dae<'m>, tolerance: f64, q: &[f64], t: f64) -> Self {
        let (n, m) = (dae.n, dae.m);
        let scale = load_scale(dae, q, t);
        let size = mechanism_size(dae.model);
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
            size,
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
            newton_matrix(k.as_ref(), self.jac.as_ref(), self.big.as_mut());
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
        let equation = if worst >= n {
            Unbalanced::Row(self.dae.sys.row_name(worst - n))
        } else {
            Unbalanced::Coordinate(coordinate_name(self.dae.model, worst))
        };
        Err(NotConverged { force: force / self.scale, position, equation, load_fraction: self.dae.external_scale })
    }

    /// `(q, t) => (lambda (m), g (n))`: the least-squares multipliers of `Phi_q^T lambda = Q` and
    /// the load they leave unbalanced, `g = Q - Phi_q^T lambda`, which lies in the null space of
    /// `Phi_q` (minus the gradient of the potential on the constraints). Leaves the positions and
    /// `self.jac` evaluated at `q`.
    fn balance(&mut self, q: &[f64], t: f64) -> (Vec<f64>, Vec<f64>) {
        self.dae.positions(q, t);
        self.dae.load(q, &self.zero, t, &mut self.load);
        self.dae.jacobian_dense(self.jac.as_mut());
        let lambda = min_norm_solve(self.jac.transpose(), &self.load).unwrap_or_else(|| vec![0.0; self.m]);
        self.jt.fill(0.0);
        self.dae.add_jt(&lambda, &mut self.jt);
        let g = self.load.iter().zip(&self.jt).map(|(l, r)| l - r).collect();
        (lambda, g)
    }

    /// The reduced stiffness at `q (n)` with its least-squares multipliers, decomposed; `None`
    /// without free directions or when the eigensolver fails (a non-finite entry).
    fn curvature(&mut self, q: &[f64], t: f64) -> Option<Curvature> {
        let (lambda, g) = self.balance(q, t);
        let zero = vec![0.0; self.n];
        let (k, _) = self.tangent(q, &zero, &lambda, t);
        let (kr, basis) = self.reduced(k.as_ref(), q, t);
        let f = kr.nrows();
        if f == 0 {
            return None;
        }
        let sym = Mat::from_fn(f, f, |i, j| 0.5 * (kr[(i, j)] + kr[(j, i)]));
        let eig = sym.self_adjoint_eigen(faer::Side::Lower).ok()?;
        let s = eig.S().column_vector();
        let vectors = &basis * eig.U();
        let loads = (0..f).map(|k| (0..self.n).map(|i| vectors[(i, k)] * g[i]).sum()).collect();
        Some(Curvature { values: (0..f).map(|k| s[k]).collect(), vectors, loads })
    }

    /// The size of a step along `d (n)` in descent units: the largest rotation (rad) or
    /// translation over the mechanism's size.
    fn step_size(&self, d: &[f64]) -> f64 {
        d.iter().enumerate().fold(0.0f64, |a, (k, v)| a.max(if k % 3 == 2 { v.abs() } else { v.abs() / self.size }))
    }

    /// March downhill from `x = [q; lambda]` along `dir (n)`, a free direction the unbalanced
    /// load does work along: steps of `h` descent units (from [`DESCENT_FIRST_STEP`], doubling up
    /// to [`DESCENT_MAX_STEP`]), each projected back onto `Phi = 0` by assembly (least change),
    /// the direction carried along by projecting it onto each new null space. Stops at the first
    /// point where the load works against the direction (past the path's minimum of potential),
    /// or where the projection fails (Newton takes over there); `x` is left at the last point
    /// with its least-squares multipliers. Never more than [`MAX_DESCENT_STEPS`] steps.
    fn descend(&mut self, x: &mut [f64], t: f64, mut dir: Vec<f64>) -> Result<(), Runaway> {
        let n = self.n;
        let (hold, zero) = (vec![false; 2 * n], vec![0.0; n]);
        let (mut h, mut travel, mut push) = (DESCENT_FIRST_STEP, 0.0, 0.0);
        for _ in 0..MAX_DESCENT_STEPS {
            let size = self.step_size(&dir);
            if size == 0.0 {
                return Ok(());
            }
            let trial: Vec<f64> = x[..n].iter().zip(&dir).map(|(q, d)| q + h * d / size).collect();
            let start = Start { q: &trial, qdot: &zero, given: &hold, t, tolerance: self.tolerance };
            let Ok(moved) = assemble(&mut self.dae.sys, &start) else { return Ok(()) };
            travel += h;
            let (lambda, g) = self.balance(&moved.q, t);
            let basis = null_space(self.jac.as_ref());
            let along: Vec<f64> = (0..basis.ncols()).map(|j| (0..n).map(|i| basis[(i, j)] * dir[i]).sum()).collect();
            dir = (0..n).map(|i| (0..basis.ncols()).map(|j| basis[(i, j)] * along[j]).sum()).collect();
            x[..n].copy_from_slice(&moved.q);
            x[n..].copy_from_slice(&lambda);
            let unit = self.step_size(&dir);
            push = if unit > 0.0 { g.iter().zip(&dir).map(|(a, b)| a * b).sum::<f64>() / unit } else { 0.0 };
            if push < 0.0 || unit == 0.0 {
                return Ok(());
            }
            h = (2.0 * h).min(DESCENT_MAX_STEP);
        }
        Err(Runaway { travel, push, coordinates: coordinates_of(self.dae.model, &dir) })
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

    /// The design sensitivities `s` of the equilibrium `(q, lambda)` at `t`, solved for
    /// with the Newton matrix there (its geometric stiffness exact) and pushed into `results`
    /// (with `react`, a static analysis's row with these reactions; without, a modes
    /// analysis's); returns the tangent stiffness and `Phi_q` there.
    pub(crate) fn sensitivities(
        &mut self,
        s: &mut EquilibriumSensitivity<'_>,
        results: &mut Results,
        (q, lambda, t): (&[f64], &[f64], f64),
        react: Option<&[f64]>,
    ) -> Result<(Mat<f64>, Mat<f64>), Error> {
        self.dae.positions(q, t);
        self.dae.load_jacobians(q, &vec![0.0; self.n], t, self.dq.as_mut(), self.dv.as_mut());
        let geo = s.geometric_stiffness(q, lambda, t);
        let k = Mat::from_fn(self.n, self.n, |i, j| geo[(i, j)] - self.dq[(i, j)]);
        self.dae.jacobian_dense(self.jac.as_mut());
        s.solve(self.dae, (k.as_ref(), self.jac.as_ref()), q, lambda, t)?;
        s.push(results, self.dae, (q, lambda, t), react)?;
        Ok((k, self.jac.clone()))
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

/// `big ((n + m) x (n + m))`: the Newton matrix of the equilibrium `[-K, -Phi_q^T; Phi_q, 0]`
/// from the tangent stiffness `k (n x n)` and `jac = Phi_q (m x n)`, the derivative of
/// `R = [Q - Phi_q^T lambda; Phi]` with respect to `(q, lambda)`.
pub(crate) fn newton_matrix(k: MatRef<'_, f64>, jac: MatRef<'_, f64>, mut big: MatMut<'_, f64>) {
    let (m, n) = (jac.nrows(), jac.ncols());
    big.fill(0.0);
    for i in 0..n {
        for j in 0..n {
            big[(i, j)] = -k[(i, j)];
        }
    }
    for r in 0..m {
        for c in 0..n {
            big[(n + r, c)] = jac[(r, c)];
            big[(c, n + r)] = -jac[(r, c)];
        }
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

/// The coordinates with the largest share of the direction `v (n)`, as `body.x` names, for
/// messages.
pub(crate) fn coordinates_of(model: &Model, v: &[f64]) -> Vec<String> {
    let vmax = max_abs(v);
    (0..v.len()).filter(|&k| v[k].abs() >= 0.2 * vmax).map(|k| coordinate_name(model, k)).collect()
}

/// The mechanism's size, m: the largest distance from a body's centre of mass to one of its named
/// points, or 1 m when no body names one.
fn mechanism_size(model: &Model) -> f64 {
    let size = model.bodies.iter().flat_map(|b| b.points.values()).fold(0.0f64, |a, p| a.max(p[0].hypot(p[1])));
    if size > 0.0 {
        size
    } else {
        1.0
    }
}

/// The result of [`solve`]: a stable equilibrium and its multipliers.
pub(crate) struct Equilibrium {
    pub q: Vec<f64>,
    pub lambda: Vec<f64>,
    /// Smallest eigenvalue of the symmetric part of the reduced stiffness (N m / rad or N / m);
    /// `None` with no free directions.
    pub min_stiffness: Option<f64>,
}

/// The stable equilibrium of `dae` at `t` from the initial guess `q0`, for `analysis`, by the
/// method of the module documentation; `stepping` allows load stepping as the last resort.
pub(crate) fn solve(
    st: &mut Statics<'_, '_>,
    analysis: &Analysis,
    q0: &[f64],
    t: f64,
    stepping: bool,
) -> Result<Equilibrium, Error> {
    let n = st.n;
    let (lambda0, _) = st.balance(q0, t);
    let start: Vec<f64> = q0.iter().chain(&lambda0).copied().collect();
    let mut x = start.clone();
    st.dae.external_scale = 1.0;
    let mut outcome = st.newton(&mut x, t);
    let tol = FORCE_TOLERANCE * st.scale;
    let mut descents = 0;
    let reached = loop {
        let curvature = st.curvature(&x[..n], t);
        let reached = match outcome {
            Ok(()) => {
                let Some(c) = &curvature else { return Ok(found(&x, n, None)) };
                if let Some(k) = c.flat() {
                    let coordinates = coordinates_of(st.dae.model, &c.vector(k, 1.0));
                    return Err(free(analysis, t, &coordinates));
                }
                if c.index() == 0 {
                    return Ok(found(&x, n, Some(c.values[0])));
                }
                Reached::Unstable(c.index(), coordinates_of(st.dae.model, &c.vector(0, 1.0)))
            }
            Err(e) => Reached::Short(e),
        };
        let Some(dir) = curvature.and_then(|c| c.descent(tol)).filter(|_| descents < MAX_DESCENTS) else {
            break reached;
        };
        descents += 1;
        st.stats.descents += 1;
        if let Err(run) = st.descend(&mut x, t, dir) {
            let cause = format!(
                "none exists along the path the loads drive: they keep moving ({}) downhill, and after {:.1} rad of travel (a translation counts in units of the mechanism's size, {:.3} m) they still do {:.4} J per unit of travel with nothing to balance them",
                run.coordinates.join(", "),
                run.travel,
                st.size,
                run.push
            );
            return Err(Error::NoEquilibrium { time: t, coordinates: run.coordinates, index: None, cause });
        }
        outcome = st.newton(&mut x, t);
    };
    if stepping {
        let mut y = start;
        if st.step_load(&mut y, t).is_ok() {
            match st.curvature(&y[..n], t) {
                None => return Ok(found(&y, n, None)),
                Some(c) if c.flat().is_none() && c.index() == 0 => return Ok(found(&y, n, Some(c.values[0]))),
                Some(_) => {}
            }
        }
    }
    Err(match reached {
        Reached::Unstable(index, coordinates) => {
            let cause = format!(
                "each equilibrium reached is unstable; after {descents} descent(s) the last has {index} unstable direction(s), along ({})",
                coordinates.join(", ")
            );
            Error::NoEquilibrium { time: t, coordinates, index: Some(index), cause }
        }
        Reached::Short(e) => Error::Equilibrium {
            time: t,
            residual: e.force.max(e.position),
            equation: e.equation,
            iterations: st.stats.iterations,
            load_fraction: e.load_fraction,
        },
    })
}

/// The [`Equilibrium`] at `x = [q; lambda]`.
fn found(x: &[f64], n: usize, min_stiffness: Option<f64>) -> Equilibrium {
    Equilibrium { q: x[..n].to_vec(), lambda: x[n..].to_vec(), min_stiffness }
}

/// The model error of a degree of freedom that nothing holds at an equilibrium.
fn free(analysis: &Analysis, t: f64, coordinates: &[String]) -> Error {
    Error::Model(vec![crate::Problem::new(
        format!("analyses.{}", analysis.name),
        format!(
            "a {} analysis needs every degree of freedom held by a driver, a spring or a load that changes with position; at t = {} s the mechanism is free to move ({}) with nothing acting along it: drive it, add a spring, or load it",
            analysis.kind.name(),
            crate::error::seconds(&t),
            coordinates.join(", ")
        ),
    )])
}

/// Run a static (or quasi-static) analysis. On failure the equilibria found until then are
/// kept.
pub(crate) fn run_static(model: &Model, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
    let mut dae = match Dae::new(model, &analysis.drivers, &analysis.forces) {
        Ok(d) => d,
        Err(e) => return Err(fail(Results::new(model, analysis), factor_error(e, analysis.t_start))),
    };
    let n = dae.n;
    let mut results = run.results(model, analysis);
    if let Err(e) = super::dense_size(analysis, dae.m, n) {
        return Err(fail(results, e));
    }
    let mut names = super::reaction_columns(model, analysis);
    names.push("potential_energy".into());
    names.extend(model.measures.iter().map(|m| m.name.clone()));
    results.add_columns(names);
    let t0 = analysis.t_start;
    let times = output_times(analysis);
    let given = held(model, false);
    let assembly = match assemble_into(model, analysis, &mut dae.sys, &given, t0, &mut results.summary) {
        Ok(a) => a,
        Err(e) => return Err(fail(results, e)),
    };
    // The degrees of freedom and the redundant rows at the assembled start, as dynamics finds them.
    let mut jac = Mat::<f64>::zeros(dae.m, n);
    dae.sys.jacobian_dense(&ConfigBuf::new(&assembly.q).view(), t0, jac.as_mut());
    // Scaled to be free of units, as every rank test (`super::scaled_row_space`).
    let scales = super::column_scales(&dae.sys, 0..n);
    let (independent, redundant) = independent_rows(equilibrated(jac.as_ref(), &scales).as_ref());
    results.summary.dof = Some(n - independent.len());
    results.summary.redundant_rows = Some(redundant.iter().map(|&r| dae.sys.row_name(r)).collect());
    let mut sensitivity = match run.sensitivities.as_slice() {
        [] => None,
        asked => match EquilibriumSensitivity::new(model, analysis, asked, &dae, &assembly.q, t0) {
            Ok(s) => Some(s),
            Err(e) => return Err(fail(results, e)),
        },
    };
    let mut st = Statics::new(&mut dae, analysis.settings.tolerance, &assembly.q, t0);
    let zero = vec![0.0; n];
    let mut react = Vec::new();
    let mut reactions = Vec::new();
    let mut row = Vec::new();
    let mut q = assembly.q.clone();
    let mut min_stiffness: Option<f64> = None;
    let mut indeterminate: Option<Vec<String>> = None;
    let mut error = None;
    for (k, &t) in times.iter().enumerate() {
        match solve(&mut st, analysis, &q, t, k == 0) {
            Ok(eq) => {
                q.copy_from_slice(&eq.q);
                st.residual_at(&eq.q.iter().chain(&eq.lambda).copied().collect::<Vec<_>>(), t);
                st.stats.force_residual = st.stats.force_residual.max(max_abs(&st.residual[..n]));
                st.stats.position_residual = st.stats.position_residual.max(max_abs(&st.residual[n..]));
                if let Some(s) = eq.min_stiffness {
                    min_stiffness = Some(min_stiffness.map_or(s, |x: f64| x.min(s)));
                }
                if indeterminate.is_none() {
                    st.dae.jacobian_dense(st.jac.as_mut());
                    let scaled = equilibrated(st.jac.as_ref(), &scales);
                    indeterminate = Some(element_names(&st.dae.sys, &indeterminate_rows(scaled.as_ref())));
                }
                st.dae.reactions(&eq.q, &zero, &eq.lambda, &mut react);
                super::measure_reactions(model, &analysis.drivers, &react, &mut reactions);
                row.clear();
                row.extend_from_slice(&react);
                row.push(st.dae.potential_energy(&eq.q));
                row.extend(model.measures.iter().map(|me| me.value(&eq.q, &zero, &zero, &reactions, t)));
                if let Err(e) = run.push(&mut results, t, &eq.q, &zero, &zero, &row) {
                    error = Some(e);
                    break;
                }
                if let Some(s) = &mut sensitivity {
                    if let Err(e) = st.sensitivities(s, &mut results, (&eq.q, &eq.lambda, t), Some(&react)) {
                        error = Some(e);
                        break;
                    }
                }
            }
            Err(e) => {
                error = Some(e);
                break;
            }
        }
    }
    let stats = st.stats.clone();
    // Every equilibrium written is stable; a run that stopped for want of one says so, with the
    // index of the unstable equilibrium it reached (none when the loads had no equilibrium).
    let (stable, index) = match &error {
        Some(Error::NoEquilibrium { index, .. }) => (false, *index),
        _ => (true, Some(0)),
    };
    let s = &mut results.summary;
    s.statistics = Some(Statistics::Static(stats));
    s.stable = Some(stable);
    s.equilibrium = Some(EquilibriumReport { index, min_reduced_stiffness: min_stiffness });
    s.indeterminate_joints = Some(indeterminate.unwrap_or_default());
    results.insert_reaction_summary(model);
    match error {
        None => Ok(results),
        Some(e) => Err(fail(results, e)),
    }
}
