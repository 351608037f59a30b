//! Cam given by its working surface: a roller (radius `r`) whose centre `P` is held tangent to a
//! closed curve `p(u)` fixed in the cam, on the curve's outside; with `r = 0`, a knife edge on the
//! curve (a point-on-curve joint). One row.
//!
//! ```text
//! d     = A_i^T (r_j + A_j s'_j - r_i) - s'_i        (P relative to the cam's centre C, cam frame)
//! u*    = argmin_u |d - p(u)|                        (the nearest point of the curve to P)
//! n     = sigma R(-90) p'(u*) / |p'(u*)|             (the outward unit normal; sigma = +1 for a
//!                                                     counter-clockwise curve, -1 clockwise)
//! Phi   = n . (d - p(u*)) - r                        (the signed distance from the curve, less r)
//! ```
//!
//! At `u*` the stationarity condition `g(u, d) = (p(u) - d) . p'(u) = 0` holds, so `d - p = rho n`
//! with `rho = n . (d - p)`. By the envelope theorem the gradient of `Phi` in `d` is `n`: the terms
//! in `du*/dd` carry `n' . (d - p) - n . p' = 0` (`n'` is along the tangent, `d - p` along `n`).
//! So, with `d_q`, `d' = d_q qdot` and `d_qq[qdot, qdot]` from dual and hyper-dual numbers through
//! the bodies' rotations (exact, as in cam.rs),
//!
//! ```text
//! Phi_q = n^T d_q                                                   (1 x 6)
//! g_u   = |p'|^2 + (p - d) . p'' = |p'|^2 (1 + rho kappa)           (> 0: a strict minimum)
//! du*/dt = p' . d' / g_u                                             (implicit differentiation of g = 0)
//! dn/du = sigma R(-90) (p'' - t (t . p'')) / |p'|,   t = p' / |p'|
//! gamma = -(n . d_qq[qdot, qdot] + (du*/dt) (dn/du) . d')
//! nu    = 0
//! ```
//!
//! `Phi_tt = n . d'' + d'^T H d'`, `H = (dn/du) (du*/dd)^T` the Hessian of the signed distance in
//! `d`; `gamma` is `-Phi_tt` less its part in `qddot`, `n . d_q qddot`. `kappa` is the curve's
//! curvature, positive where it is convex: `1 + rho kappa <= 0` on a concave part whose radius of
//! curvature is at most the roller's is an undercut, where the roller cannot touch the surface.
//! Only `p`, `p'` and `p''` are needed.
//!
//! `u*` is found without state: the curve's samples (computed once) give the basins of the
//! distance's local minima; each that could hold the nearest point is refined by Newton's method
//! on `g(u) = 0`, kept inside a bracket where `g` changes sign (bisection when a Newton step
//! leaves it). Where the nearest point is not unique (two points equally near, within
//! [`TIE`] of the curve's size) or not a strict minimum, the row is NaN and an analysis stops
//! there, naming the joint and the time ([`Constraint::non_finite_cause`]).
//! Norton, Design of Machinery, chapter 8 (roller followers, undercutting).
//!
//! Design sensitivities (docs/sensitivities.md): the joint's numbers are its two points and the
//! roller's radius, and the curve's expressions read the parameters as inputs. The row over a
//! number type `S` that carries derivatives ([`Constraint::phi_tri`] and its kin) finds `u*` in
//! `f64` as above, lifts it onto `S` by `S::ORDER` chord steps `u <- u - g(u, d) / g_u` in `S`
//! arithmetic (`g_u` the `f64` value's; each step makes one more order of derivatives exact), and
//! evaluates `n . (d - p(u*)) - r` over `S`: `p'` at a `u` that carries `S`'s derivatives is one
//! evaluation over a number type with one more direction ([`Nestable`]). The pressure angle
//! takes the same lifted normal.

use super::{dot, slot2, Anchor, At, BodyIx, CamFrame, Config, Constraint};
use crate::expr::{Dual, Expr, HyperDual, Nestable, Scalar, Spline, TimeTri, Tri};
use std::f64::consts::PI;
use std::sync::Arc;

/// Two candidate nearest points whose distances differ by less than this fraction of the curve's
/// size are the same distance: the position solver holds a constraint to 1e-10 (absolute) on
/// mechanisms of size ~0.1 to 1 m, so distances closer than 1e-9 of the size cannot be told apart.
const TIE: f64 = 1e-9;

/// The samples of a curve given by expressions: 2048 resolve features down to 1/2048 of the
/// curve's period (0.18 degrees of a polar cam), far finer than any cam's flank, and a search
/// over them costs some microseconds per evaluation.
const EXPRESSION_SAMPLES: usize = 2048;

/// The samples per piece of a point table: the squared distance to a cubic piece is a polynomial
/// of degree 6 in the parameter, with at most three minima, which four samples separate.
const SAMPLES_PER_PIECE: usize = 4;

/// A tangent shorter than this fraction of the curve's mean speed `L / period` is taken as zero:
/// the normal there is the direction of a vector that round-off dominates.
const STALL: f64 = 1e-6;

/// The most Newton (or bisection) steps one refinement takes: bisection alone halves the bracket
/// (one sample spacing, some 1e-3 of the period) 60 times, below round-off; Newton ends in a few.
const MAX_STEPS: usize = 100;

/// How the curve is given, in the cam's frame about its centre.
#[derive(Debug, Clone)]
enum Shape {
    /// `(x(u), y(u))`, each an expression whose slot 0 is `u`.
    Parametric { x: Expr, y: Expr },
    /// `R(psi) (cos psi, sin psi)`, `R` an expression whose slot 0 is `psi`.
    Polar { radius: Expr },
    /// Periodic cubic splines `x(s)`, `y(s)` of the chord length `s` from the first point.
    Points { x: Arc<Spline>, y: Arc<Spline> },
}

/// A closed curve `p(u)`, `u` in `[start, start + period)`, in the cam's frame about its centre.
#[derive(Debug, Clone)]
pub struct Curve {
    shape: Shape,
    start: f64,
    period: f64,
}

/// What is wrong with a curve or a roller on it: the field of the joint it concerns (`profile`,
/// `profile.period`, `surface_radius`, `roller_radius`) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveError {
    /// The field, relative to the joint.
    pub field: &'static str,
    /// The reason.
    pub message: String,
}

impl CurveError {
    fn new(field: &'static str, message: String) -> CurveError {
        CurveError { field, message }
    }
}

impl Curve {
    /// The curve `(x(u), y(u))` of period `period`, `u` slot 0 of both expressions.
    ///
    /// # Errors
    ///
    /// An expression names a slot other than 0, or `period` is not positive and finite.
    pub fn parametric(x: Expr, y: Expr, period: f64) -> Result<Curve, CurveError> {
        if x.slots().iter().chain(y.slots()).any(|&s| s != 0) {
            return Err(CurveError::new("profile", "the profile may name only u, parameters and tables".into()));
        }
        if !(period.is_finite() && period > 0.0) {
            return Err(CurveError::new("profile.period", format!("expected a positive number, found {period}")));
        }
        Ok(Curve { shape: Shape::Parametric { x, y }, start: 0.0, period })
    }

    /// The polar curve `R(psi) (cos psi, sin psi)`, `psi` slot 0 of `radius`, taken in
    /// `[-pi, pi)` as the pitch-curve cam takes it (`atan2`).
    ///
    /// # Errors
    ///
    /// `radius` names a slot other than 0.
    pub fn polar(radius: Expr) -> Result<Curve, CurveError> {
        if radius.slots().iter().any(|&s| s != 0) {
            return Err(CurveError::new(
                "surface_radius",
                "the radius may name only psi, parameters and tables".into(),
            ));
        }
        Ok(Curve { shape: Shape::Polar { radius }, start: -PI, period: 2.0 * PI })
    }

    /// The closed curve through `points` in order (the last joined to the first; a last point
    /// equal to the first is dropped), interpolated by periodic cubic splines over the chord
    /// length.
    ///
    /// # Errors
    ///
    /// Fewer than three points, a number that is not finite, or two consecutive points equal.
    pub fn points(points: &[[f64; 2]]) -> Result<Curve, CurveError> {
        let err = |m: String| Err(CurveError::new("profile", m));
        if let Some(k) = points.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return err(format!("point {k} is not finite"));
        }
        let n = if points.len() > 1 && points.first() == points.last() { points.len() - 1 } else { points.len() };
        if n < 3 {
            return err(format!("{n} distinct points given; a closed curve needs at least 3"));
        }
        let mut s = vec![0.0];
        for k in 0..n {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let chord = (b[0] - a[0]).hypot(b[1] - a[1]);
            if chord == 0.0 {
                return err(format!("points {k} and {} are equal; expected distinct consecutive points", (k + 1) % n));
            }
            s.push(s[k] + chord);
        }
        let column = |c: usize| (0..=n).map(|k| points[k % n][c]).collect::<Vec<f64>>();
        let spline = |c: usize| {
            Spline::new(s.clone(), column(c), crate::expr::spline::Method::Periodic)
                .map(Arc::new)
                .map_err(|e| CurveError::new("profile", e.message))
        };
        let (x, y) = (spline(0)?, spline(1)?);
        Ok(Curve { shape: Shape::Points { x, y }, start: 0.0, period: s[n] })
    }

    /// The number of samples the nearest-point search starts from.
    fn samples(&self) -> usize {
        match &self.shape {
            Shape::Points { x, .. } => EXPRESSION_SAMPLES.max(SAMPLES_PER_PIECE * x.pieces()),
            _ => EXPRESSION_SAMPLES,
        }
    }

    /// `(p, p', p'')` at `u` taken as is (no wrapping into the period).
    fn raw(&self, u: f64) -> [[f64; 2]; 3] {
        let h = |v: HyperDual| [v.v, v.e1, v.e12];
        let (x, y) = match &self.shape {
            Shape::Parametric { x, y } => {
                let u = [HyperDual::variable(u)];
                (h(x.eval(&u)), h(y.eval(&u)))
            }
            Shape::Polar { radius } => {
                let psi = HyperDual::variable(u);
                let r = radius.eval(&[psi]);
                (h(r * psi.cos()), h(r * psi.sin()))
            }
            Shape::Points { x, y } => {
                let (x, y) = (x.eval(u), y.eval(u));
                ([x.0, x.1, x.2], [y.0, y.1, y.2])
            }
        };
        [[x[0], y[0]], [x[1], y[1]], [x[2], y[2]]]
    }

    /// `u` wrapped into `[start, start + period)`.
    fn wrap(&self, u: f64) -> f64 {
        self.start + (u - self.start).rem_euclid(self.period)
    }

    /// `(p, p', p'')` at `u`, wrapped into `[start, start + period)`.
    fn at(&self, u: f64) -> [[f64; 2]; 3] {
        self.raw(self.wrap(u))
    }

    /// `p(u)` over any [`Scalar`], `u` taken as is and the expressions reading the model's
    /// parameters `params` ([`Expr::eval_params`]): [`Curve::raw`]'s point with every derivative
    /// that `u` and `params` carry (a point table's splines hold numbers, not parameters).
    fn point<S: Scalar>(&self, u: S, params: &[S]) -> [S; 2] {
        match &self.shape {
            Shape::Parametric { x, y } => [x.eval_params(&[u], params), y.eval_params(&[u], params)],
            Shape::Polar { radius } => {
                let r = radius.eval_params(&[u], params);
                [r * u.cos(), r * u.sin()]
            }
            Shape::Points { x, y } => [x.lifted(u), y.lifted(u)],
        }
    }

    /// `p'(u)` over a [`Nestable`] type, `up` the parameters raised to its [`Nestable::Up`]: one
    /// evaluation of [`Curve::point`] with `u` moving along the new direction.
    fn tangent<S: Nestable>(&self, u: S, up: &[S::Up]) -> [S; 2] {
        self.point(u.seed(1.0), up).map(S::slope)
    }
}

/// The outward unit normal `sigma R(-90) t / |t|` of a curve whose tangent is `t`.
#[inline]
fn normal<S: Scalar>(sigma: f64, t: [S; 2]) -> [S; 2] {
    let (speed, sigma) = (t[0].hypot(t[1]), S::constant(sigma));
    [sigma * t[1] / speed, -sigma * t[0] / speed]
}

/// The nearest point of the curve to the roller's centre.
#[derive(Debug, Clone, Copy)]
struct Contact {
    /// Its parameter `u*`.
    u: f64,
    /// `(p, p', p'')` there.
    p: [[f64; 2]; 3],
    /// The outward unit normal.
    n: [f64; 2],
    /// `g_u = |p'|^2 + (p - d) . p''`, positive.
    g_u: f64,
}

/// The row for a roller of radius `roller` on the closed curve of a cam; see the module's text.
#[derive(Clone)]
pub struct CamProfile {
    at: CamFrame,
    curve: Curve,
    roller: f64,
    /// `+1` when the curve runs counter-clockwise, `-1` clockwise.
    sigma: f64,
    /// The curve at `u_k = start + k step`, `k < samples`.
    samples: Vec<[f64; 2]>,
    step: f64,
    /// The most a sample can be farther from a point than its basin's nearest point: a sample
    /// spacing times the largest sampled speed `|p'|`, doubled for the speed between samples.
    reach: f64,
    /// The diagonal of the curve's bounding box, m.
    size: f64,
    columns: Vec<usize>,
}

/// Its fields but the samples (thousands of points), which only their number stands for.
impl std::fmt::Debug for CamProfile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CamProfile")
            .field("at", &self.at)
            .field("curve", &self.curve)
            .field("roller", &self.roller)
            .field("sigma", &self.sigma)
            .field("samples", &self.samples.len())
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

/// `(a - b)`.
#[inline]
fn sub<S: Scalar>(a: [S; 2], b: [S; 2]) -> [S; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// `a x b`.
#[inline]
fn cross<S: Scalar>(a: [S; 2], b: [S; 2]) -> S {
    a[0] * b[1] - a[1] * b[0]
}

impl CamProfile {
    /// The row for the cam `i` (centre `si`, its frame) whose working surface is `curve` (about
    /// the centre, cam frame) and the roller of radius `roller` centred at `sj` of body `j`.
    ///
    /// # Errors
    ///
    /// The curve is not finite, its tangent vanishes, it does not close (an expression's value or
    /// slope differs at the two ends of its period), it encloses no area, or the roller is larger
    /// than the radius of curvature of a concave part (an undercut), each with its field.
    pub fn try_new(
        [(i, si), (j, sj)]: [(BodyIx, [f64; 2]); 2],
        curve: Curve,
        roller: f64,
    ) -> Result<CamProfile, CurveError> {
        let field = match curve.shape {
            Shape::Polar { .. } => "surface_radius",
            _ => "profile",
        };
        let m = curve.samples();
        let step = curve.period / m as f64;
        let full: Vec<[[f64; 2]; 3]> = (0..m).map(|k| curve.raw(curve.start + k as f64 * step)).collect();
        let show = |u: f64, p: [f64; 2]| format!("u = {u:.6} ({:.6e}, {:.6e})", p[0], p[1]);
        if let Some(k) = full.iter().position(|s| s.iter().flatten().any(|v| !v.is_finite())) {
            let u = curve.start + k as f64 * step;
            return Err(CurveError::new(field, format!("the curve or its derivatives are not finite at u = {u}")));
        }
        let samples: Vec<[f64; 2]> = full.iter().map(|s| s[0]).collect();
        let length: f64 = (0..m).map(|k| sub(samples[(k + 1) % m], samples[k])).map(|v| v[0].hypot(v[1])).sum();
        let speed = |k: usize| full[k][1][0].hypot(full[k][1][1]);
        let slowest = (0..m).min_by(|&a, &b| speed(a).total_cmp(&speed(b))).unwrap_or(0);
        // Every sample is finite (checked above), so the comparisons below are not with NaN.
        if speed(slowest) <= STALL * length / curve.period {
            let at = show(curve.start + slowest as f64 * step, samples[slowest]);
            return Err(CurveError::new(
                field,
                format!("the curve's tangent vanishes at {at}: its normal is undefined"),
            ));
        }
        let (lo, hi) = samples.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        });
        let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        if !matches!(curve.shape, Shape::Points { .. }) {
            // The two ends of the period must meet, and so must the tangents (else the normal
            // jumps there): to TIE of the size, and STALL of the mean speed.
            let (a, b) = (curve.raw(curve.start), curve.raw(curve.start + curve.period));
            let (gap, kink) = (sub(b[0], a[0]), sub(b[1], a[1]));
            let close_field = if field == "profile" { "profile.period" } else { field };
            if gap[0].hypot(gap[1]) > TIE * size || kink[0].hypot(kink[1]) > STALL * length / curve.period {
                let message = format!(
                    "the curve does not close: at u = {} it is at ({:e}, {:e}) with slope ({:e}, {:e}), at u = {} at \
                     ({:e}, {:e}) with slope ({:e}, {:e}); expected a closed, smooth curve over one period",
                    curve.start,
                    a[0][0],
                    a[0][1],
                    a[1][0],
                    a[1][1],
                    curve.start + curve.period,
                    b[0][0],
                    b[0][1],
                    b[1][0],
                    b[1][1]
                );
                return Err(CurveError::new(close_field, message));
            }
        }
        // Twice the signed area by the shoelace formula over the samples.
        let area: f64 = (0..m).map(|k| cross(samples[k], samples[(k + 1) % m])).sum::<f64>() / 2.0;
        if area.abs() <= TIE * size * size {
            return Err(CurveError::new(field, "the curve encloses no area: it has no outside".into()));
        }
        let sigma = area.signum();
        if roller > 0.0 {
            // kappa = sigma (p' x p'') / |p'|^3, positive where convex.
            let curvature = |k: usize| sigma * cross(full[k][1], full[k][2]) / speed(k).powi(3);
            let sharpest = (0..m).min_by(|&a, &b| curvature(a).total_cmp(&curvature(b))).unwrap_or(0);
            let kappa = curvature(sharpest);
            if 1.0 + roller * kappa <= 0.0 {
                let at = show(curve.start + sharpest as f64 * step, samples[sharpest]);
                let message = format!(
                    "the roller (radius {roller} m) is larger than the working surface's concave radius of \
                     curvature {:e} m at {at}: it cannot touch the surface there (an undercut)",
                    -1.0 / kappa
                );
                return Err(CurveError::new("roller_radius", message));
            }
        }
        let fastest = (0..m).map(speed).fold(0.0, f64::max);
        let at = CamFrame { i, si, j, sj };
        let reach = 2.0 * step * fastest;
        Ok(CamProfile { at, curve, roller, sigma, samples, step, reach, size, columns: at.columns() })
    }

    /// `g(u) = (p(u) - d) . p'(u)` and `g_u = |p'|^2 + (p - d) . p''` at `u`, with the curve there.
    #[inline]
    fn stationarity(&self, u: f64, d: [f64; 2]) -> (f64, f64, [[f64; 2]; 3]) {
        let p = self.curve.at(u);
        let r = sub(p[0], d);
        (dot(r, p[1]), dot(p[1], p[1]) + dot(r, p[2]), p)
    }

    /// The local minimum of `|p(u) - d|` in the basin of sample `k`: Newton's method on `g = 0`
    /// inside a bracket where `g` goes from negative to positive, bisecting when a step leaves
    /// it. `None` when no bracket is found within the samples or the steps do not settle.
    fn refine(&self, k: usize, d: [f64; 2]) -> Option<Contact> {
        let u0 = self.curve.start + k as f64 * self.step;
        let g = |u: f64| self.stationarity(u, d).0;
        // Widen the bracket a sample at a time down the slope of the distance (g = half its
        // derivative), at most once round the curve.
        let (mut a, mut b) = (u0 - self.step, u0 + self.step);
        let (mut ga, mut gb) = (g(a), g(b));
        let mut widened = 0;
        while ga > 0.0 && widened < self.samples.len() {
            (b, gb) = (a, ga);
            a -= self.step;
            ga = g(a);
            widened += 1;
        }
        while gb < 0.0 && widened < self.samples.len() {
            (a, ga) = (b, gb);
            b += self.step;
            gb = g(b);
            widened += 1;
        }
        if !(ga <= 0.0 && gb >= 0.0) {
            return None;
        }
        let mut u = if u0 > a && u0 < b { u0 } else { 0.5 * (a + b) };
        // Round-off in g is some eps |p'| |p - d|; a step below 4 eps of the parameter's range is
        // at the resolution of u itself.
        let resolution = 4.0 * f64::EPSILON * (self.curve.start.abs() + self.curve.period + u.abs());
        for _ in 0..MAX_STEPS {
            let (gu, dgu, p) = self.stationarity(u, d);
            let newton = u - gu / dgu;
            if gu == 0.0 || (dgu > 0.0 && (newton - u).abs() <= resolution) || b - a <= resolution {
                return Some(Contact { u, p, n: normal(self.sigma, p[1]), g_u: dgu });
            }
            if gu < 0.0 {
                a = u;
            } else {
                b = u;
            }
            u = if dgu > 0.0 && newton > a && newton < b { newton } else { 0.5 * (a + b) };
        }
        None
    }

    /// Calls `f(k, |p_k - d|^2)` for every sample `k` nearer to `d` than both its neighbours
    /// (ties broken towards the later one): each starts a basin of the distance. One pass, each
    /// squared distance computed once (a hypot per sample would be most of the search's cost).
    fn basins(&self, d: [f64; 2], mut f: impl FnMut(usize, f64)) {
        let m = self.samples.len();
        let dist = |k: usize| {
            let v = sub(self.samples[k], d);
            v[0] * v[0] + v[1] * v[1]
        };
        let (first, mut before, mut here) = (dist(0), dist(m - 1), dist(0));
        for k in 0..m {
            let after = if k + 1 == m { first } else { dist(k + 1) };
            if here <= before && here < after {
                f(k, here);
            }
            (before, here) = (here, after);
        }
    }

    /// The nearest point of the curve to `d`, if it is unique and a strict minimum.
    fn nearest(&self, d: [f64; 2]) -> Option<Contact> {
        // The nearest sample's basin is refined first; another's only if its sample is within a
        // sample's reach of the best point found (else it cannot hold a nearer point, nor one as
        // near). Two passes, so that nothing is allocated.
        let mut first: Option<(usize, f64)> = None;
        self.basins(d, |k, here| {
            if first.is_none_or(|(_, f)| here < f) {
                first = Some((k, here));
            }
        });
        let (first, _) = first?;
        let start = self.refine(first, d)?;
        let gap = |c: &Contact| {
            let v = sub(d, c.p[0]);
            v[0].hypot(v[1])
        };
        let (mut best, mut nearest) = (gap(&start), start);
        let mut second = f64::INFINITY;
        let mut failed = false;
        self.basins(d, |k, here| {
            if failed || k == first || here.sqrt() - self.reach > best + TIE * self.size {
                return;
            }
            let Some(c) = self.refine(k, d) else {
                failed = true;
                return;
            };
            let here = gap(&c);
            let w = sub(c.p[0], nearest.p[0]);
            // The same point reached from another sample is no rival: two distinct minima of the
            // distance are at least some sample spacings apart, far more than 1e-6 of the size.
            if w[0].hypot(w[1]) <= 1e3 * TIE * self.size {
                return;
            }
            if here < best {
                second = best;
                (best, nearest) = (here, c);
            } else {
                second = second.min(here);
            }
        });
        if failed {
            return None;
        }
        (second - best > TIE * self.size && nearest.g_u > 0.0).then_some(nearest)
    }

    /// `Phi = n . (d - p(u*)) - r`, with `n` and `p(u*)` those of the nearest point to `d` at `q`
    /// (constants), `d` seeded by `seed`: the derivatives are those of `n . d`.
    #[inline]
    fn residual<S: Scalar>(&self, c: &Contact, q: &[f64], seed: &impl Fn(usize, f64) -> S) -> S {
        let [dx, dy] = self.at.offset(q, seed);
        let k = S::constant;
        k(c.n[0]) * (dx - k(c.p[0][0])) + k(c.n[1]) * (dy - k(c.p[0][1])) - k(self.roller)
    }

    /// The nearest point to the roller's centre at `q`.
    fn contact(&self, q: &[f64]) -> Option<Contact> {
        self.nearest(self.at.offset(q, &|_, v| v))
    }

    /// The nearest point to the roller's centre `d` moving at `rate` (cam frame), and how fast
    /// it runs along the curve: `du*/dt = p' . d' / g_u`, from differentiating
    /// `(p(u*) - d) . p'(u*) = 0` in time.
    fn moving_contact(&self, d: [f64; 2], rate: [f64; 2]) -> Option<(Contact, f64)> {
        let c = self.nearest(d)?;
        Some((c, dot(c.p[1], rate) / c.g_u))
    }

    /// Where the roller touches the surface at `(q, qdot)` and how fast the contact runs along
    /// it: `(u*, du*/dt)`, the curve's parameter and its rate; `None` where the nearest point is
    /// not unique or not regular.
    pub fn contact_rate(&self, q: &[f64], qdot: &[f64]) -> Option<(f64, f64)> {
        let [dx, dy] = self.at.offset(q, &|c, v| Dual { v, d: qdot[c] });
        self.moving_contact([dx.v, dy.v], [dx.d, dy.d]).map(|(c, u_rate)| (c.u, u_rate))
    }

    /// The pressure angle of a radial follower (moving along the line from the cam's centre to
    /// the roller's centre): the angle between that line and the contact normal, signed positive
    /// while the cam pushes the follower outward, as [`super::Cam::pressure_angle`]. NaN where
    /// the nearest point is not unique or not regular.
    pub fn pressure_angle(&self, q: &[f64], qdot: &[f64]) -> f64 {
        let (d, sense) = self.moving(q, qdot);
        let Some(c) = self.nearest(d) else { return f64::NAN };
        (-sense * cross(d, c.n)).atan2(dot(d, c.n))
    }

    /// The roller's centre `d` at `(q, qdot)` and the sense of its motion round the cam: `1`
    /// while its polar angle `psi` rises, else `-1`.
    fn moving(&self, q: &[f64], qdot: &[f64]) -> ([f64; 2], f64) {
        let [dx, dy] = self.at.offset(q, &|c, v| Dual { v, d: qdot[c] });
        let d = [dx.v, dy.v];
        // dpsi/dt = (d x d') / |d|^2: only its sign is needed.
        let psi_rate = cross(d, [dx.d, dy.d]);
        // At rest the cam is taken as turning counter-clockwise (psi falling), as for a pitch curve.
        (d, if psi_rate > 0.0 { 1.0 } else { -1.0 })
    }

    /// [`CamProfile::pressure_angle`] over a number type that carries derivatives, with the cam's
    /// numbers `data` ([`Constraint::data`]) and the parameters `params`; the sense is that of
    /// the values.
    pub(crate) fn pressure_angle_generic<S: Nestable>(&self, q: &[S], qdot: &[S], data: &[S], params: &[S]) -> S {
        let values = |x: &[S]| x.iter().map(|v| v.value()).collect::<Vec<f64>>();
        let (_, sense) = self.moving(&values(q), &values(qdot));
        let d = self.at.offset_generic(q, slot2(data, 0), slot2(data, 2));
        match self.lifted_contact(d, params) {
            Some((_, n)) => (S::constant(-sense) * cross(d, n)).atan2(dot(d, n)),
            None => S::constant(f64::NAN),
        }
    }

    /// The nearest point `p(u*)` to `d` and the normal `n(u*)` there over a number type that
    /// carries derivatives, the curve's expressions reading `params`. `u*` is found in `f64`
    /// ([`CamProfile::nearest`]), then lifted onto the derivatives of `d` and `params` by
    /// [`Scalar::ORDER`] chord steps on `g(u) = (p(u) - d) . p'(u) = 0`, `u <- u - g(u) / g_u`
    /// with `g_u` the `f64` value's: if `u` is exact to order `k - 1`, its error `e` is of order
    /// `k`, and the step leaves `e (1 - g_u(u*) / g_u) + O(e^2)`, where `1 - g_u(u*) / g_u` has
    /// no value part: of order `k + 1`. So the steps make every order the type carries exact.
    /// `None` where the nearest point is not unique or not regular.
    fn lifted_contact<S: Nestable>(&self, d: [S; 2], params: &[S]) -> Option<([S; 2], [S; 2])> {
        let c = self.nearest(d.map(S::value))?;
        let up: Vec<S::Up> = params.iter().map(|p| p.seed(0.0)).collect();
        let mut u = S::constant(self.curve.wrap(c.u));
        for _ in 0..S::ORDER {
            let g = dot(sub(self.curve.point(u, params), d), self.curve.tangent(u, &up));
            u = u - g / S::constant(c.g_u);
        }
        Some((self.curve.point(u, params), normal(self.sigma, self.curve.tangent(u, &up))))
    }

    /// `Phi = n . (d - p(u*)) - r` over a number type that carries derivatives, with the cam's
    /// numbers `data` ([`Constraint::data`]): [`Constraint::phi_tri`] and its kin.
    fn phi_nested<S: Nestable>(&self, at: &At<'_, S>, data: &[S]) -> S {
        let d = self.at.offset_generic(at.q, slot2(data, 0), slot2(data, 2));
        match self.lifted_contact(d, at.params) {
            Some((p, n)) => dot(n, sub(d, p)) - data[4],
            None => S::constant(f64::NAN),
        }
    }
}

impl Constraint for CamProfile {
    fn anchor(&self) -> Anchor {
        self.at.anchor()
    }
    fn row_names(&self) -> &[&'static str] {
        &["surface contact"]
    }
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.contact(q).map_or(f64::NAN, |c| self.residual(&c, q, &|_, v| v));
    }
    fn jacobian(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let Some(c) = self.contact(q) else {
            out[..self.columns.len()].fill(f64::NAN);
            return;
        };
        for (o, &col) in out.iter_mut().zip(&self.columns) {
            *o = self.residual(&c, q, &|k, v| Dual { v, d: if k == col { 1.0 } else { 0.0 } }).d;
        }
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], _t: f64, out: &mut [f64]) {
        let [dx, dy] = self.at.offset(q, &|c, v| HyperDual::seed(v, qdot[c], qdot[c]));
        let (rate, free) = ([dx.e1, dy.e1], [dx.e12, dy.e12]);
        let Some((c, u_rate)) = self.moving_contact([dx.v, dy.v], rate) else {
            out[0] = f64::NAN;
            return;
        };
        let [_, p1, p2] = c.p;
        let speed = p1[0].hypot(p1[1]);
        let t = [p1[0] / speed, p1[1] / speed];
        let along = dot(t, p2);
        let bent = [p2[0] - t[0] * along, p2[1] - t[1] * along];
        let dn = [self.sigma * bent[1] / speed, -self.sigma * bent[0] / speed];
        out[0] = -(dot(c.n, free) + u_rate * dot(dn, rate));
    }
    fn non_finite_cause(&self) -> Option<&'static str> {
        Some(
            "the roller's centre has no unique, regular nearest point on the working surface: it touches the \
             surface at two points at once, or sits where the surface is concave with a radius of curvature \
             below the roller's (an undercut), or at the centre of a circular arc of it",
        )
    }
    /// `point_i`, `point_j` and `roller_radius`.
    fn data(&self) -> Vec<(&'static str, f64)> {
        [self.at.data(), vec![("roller_radius", self.roller)]].concat()
    }
    fn phi_tri(&self, at: &At<'_, Tri>, data: &[Tri], out: &mut [Tri]) -> bool {
        out[0] = self.phi_nested(at, data);
        true
    }
    fn phi_dual(&self, at: &At<'_, Dual>, data: &[Dual], out: &mut [Dual]) -> bool {
        out[0] = self.phi_nested(at, data);
        true
    }
    fn phi_hyper(&self, at: &At<'_, HyperDual>, data: &[HyperDual], out: &mut [HyperDual]) -> bool {
        out[0] = self.phi_nested(at, data);
        true
    }
    fn phi_time_tri(&self, at: &At<'_, TimeTri>, data: &[TimeTri], out: &mut [TimeTri]) -> bool {
        out[0] = self.phi_nested(at, data);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{assert_data_fields, check_fd, check_generic, Lcg, OnSlice};
    use crate::constraints::CamJoint;

    fn expr(src: &str, var: &str) -> Expr {
        Expr::parse(src, &mut |n| if n == var { Ok(0) } else { Err(format!("unknown {n}")) }).unwrap()
    }

    /// A convex cam: an ellipse with a third harmonic, about (0.1, -0.05), counter-clockwise.
    fn convex() -> Curve {
        Curve::parametric(expr("0.1 + 1.2*cos(u) + 0.05*cos(3*u)", "u"), expr("-0.05 + 0.8*sin(u)", "u"), 2.0 * PI)
            .unwrap()
    }

    /// [`convex`] as a table of 200 of its points.
    fn convex_table() -> Curve {
        let table: Vec<[f64; 2]> = (0..200)
            .map(|k| 2.0 * PI * k as f64 / 200.0)
            .map(|u| [0.1 + 1.2 * u.cos() + 0.05 * (3.0 * u).cos(), -0.05 + 0.8 * u.sin()])
            .collect();
        Curve::points(&table).unwrap()
    }

    /// A cam with a concave dimple: the limacon `R = 1 + 0.6 cos(psi)` is concave where
    /// `1.72 + 1.8 cos(psi) < 0` (the numerator of its curvature `(R^2 + 2 R'^2 - R R'') /
    /// (R^2 + R'^2)^(3/2)`), its radius of curvature there at least 0.8, at `psi = pi`.
    fn limacon() -> Curve {
        Curve::polar(expr("1 + 0.6*cos(psi)", "psi")).unwrap()
    }

    /// Random states of a moving cam (body 0) and follower (body 1) whose roller's centre is at
    /// least `margin` outside the convex curve and within 1.5 of it, where the fixed tolerances of
    /// `check_fd` hold (the nearest point moves slowly and the curvature terms are of order one).
    fn states(cam: &CamProfile, margin: f64, seed: u64, count: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
        let mut rng = Lcg::new(seed);
        let mut out = Vec::new();
        while out.len() < count {
            let q = rng.vec(6, -2.0, 2.0);
            let qdot = rng.vec(6, -3.0, 3.0);
            let mut phi = [0.0];
            cam.phi_at(&q, 0.0, &mut phi);
            let rho = phi[0] + cam.roller;
            if rho > margin && rho < 1.5 {
                out.push((q, qdot));
            }
        }
        out
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for (roller, seed) in [(0.3, 1), (0.0, 2)] {
            let cam =
                CamProfile::try_new([(BodyIx(Some(0)), [0.1, -0.2]), (BodyIx(Some(3)), [0.3, 0.1])], convex(), roller)
                    .unwrap();
            assert_eq!(cam.columns(), [0, 1, 2, 3, 4, 5]);
            for (q, qdot) in states(&cam, 0.2, seed, 20) {
                check_fd(&cam, &q, &qdot, 0.0);
            }
        }
        // A knife edge on the curve, near the concave flank of the limacon: the signed distance is
        // smooth through zero, on either side.
        let knife =
            CamProfile::try_new([(BodyIx::GROUND, [0.0, 0.0]), (BodyIx(Some(0)), [0.0, 0.0])], limacon(), 0.0).unwrap();
        for (psi, off) in [(PI - 0.1, 0.05), (PI, -0.05), (2.5, 0.0), (0.3, 0.02)] {
            let r = 1.0 + 0.6 * f64::cos(psi) + off;
            check_fd(&knife, &[r * psi.cos(), r * psi.sin(), 0.4], &[0.7, -1.1, 2.0], 0.0);
        }
    }

    /// The largest differences of `gamma` from `-(d/ds)(Phi_q qdot)` along `q(s) = q + s qdot`
    /// (central differences of step `h`), and of `du*/dt` from the central differences of the
    /// nearest point's parameter `u*(q(s))`, over `states`.
    fn trajectory_errors(cam: &CamProfile, states: &[(Vec<f64>, Vec<f64>)], h: f64) -> (f64, f64) {
        let at = |q: &[f64], qdot: &[f64], s: f64| -> Vec<f64> { q.iter().zip(qdot).map(|(a, b)| a + s * b).collect() };
        let rate = |q: &[f64], qdot: &[f64]| {
            let mut jac = [0.0; 6];
            cam.jacobian_at(q, 0.0, &mut jac);
            jac.iter().zip(qdot).map(|(a, b)| a * b).sum::<f64>()
        };
        let period = cam.curve.period;
        let (mut worst_gamma, mut worst_rate) = (0.0f64, 0.0f64);
        for (q, qdot) in states {
            let mut gamma = [0.0];
            cam.gamma_at(q, qdot, 0.0, &mut gamma);
            let fd = (rate(&at(q, qdot, h), qdot) - rate(&at(q, qdot, -h), qdot)) / (2.0 * h);
            worst_gamma = worst_gamma.max((gamma[0] + fd).abs());
            let (u, u_rate) = cam.contact_rate(q, qdot).unwrap();
            let (up, _) = cam.contact_rate(&at(q, qdot, h), qdot).unwrap();
            let (um, _) = cam.contact_rate(&at(q, qdot, -h), qdot).unwrap();
            // The parameters may lie a period apart across the curve's seam.
            let unwrap = |v: f64| u + (v - u + period / 2.0).rem_euclid(period) - period / 2.0;
            let fd = (unwrap(up) - unwrap(um)) / (2.0 * h);
            worst_rate = worst_rate.max((u_rate - fd).abs());
        }
        (worst_gamma, worst_rate)
    }

    /// `gamma = -(d/ds)(Phi_q qdot)` along `q(s) = q + s qdot`, and `du*/dt`, against central
    /// differences of step 1e-5: truncation `h^2 |f'''| / 6` with `f''' ~ |qdot|^3` times the
    /// curve's derivatives, some 1e3 for velocities up to 3 (~2e-8), rounding
    /// `eps |Phi_q qdot| / h ~ 1e-10`; to 1e-6. Measured: 1.5e-8 and 1.2e-9.
    #[test]
    fn gamma_and_the_contact_rate_match_differences_along_a_trajectory() {
        let cam = CamProfile::try_new([(BodyIx(Some(0)), [0.1, -0.2]), (BodyIx(Some(3)), [0.3, 0.1])], convex(), 0.3)
            .unwrap();
        let (gamma, rate) = trajectory_errors(&cam, &states(&cam, 0.2, 7, 30), 1e-5);
        eprintln!("expressions: gamma {gamma:.1e}, du*/dt {rate:.1e} off their differences");
        assert!(gamma < 1e-6, "gamma against differences of Phi_q qdot: {gamma:e}");
        assert!(rate < 1e-6, "du*/dt against differences of u*: {rate:e}");
    }

    /// The same curve as a table of 200 of its points: the Jacobian against central differences
    /// (as `check_fd`, 1e-7), and `gamma` and `du*/dt` along trajectories. The splines' `p'''`
    /// jumps at the points, so a difference that straddles one errs by some `h |jump|` rather than
    /// `h^2`: with `h = 1e-7` (rounding ~eps |Phi_q qdot| / h ~ 1e-8) that is below 1e-6.
    /// Measured: 4.4e-8 and 5.0e-9.
    #[test]
    fn a_point_tables_derivatives_match_differences() {
        let curve = convex_table();
        let cam =
            CamProfile::try_new([(BodyIx(Some(0)), [0.1, -0.2]), (BodyIx(Some(3)), [0.3, 0.1])], curve, 0.3).unwrap();
        let states = states(&cam, 0.2, 3, 30);
        let h = 1e-5;
        for (q, _) in &states {
            let mut jac = [0.0; 6];
            cam.jacobian_at(q, 0.0, &mut jac);
            for (k, &an) in jac.iter().enumerate() {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[k] += h;
                qm[k] -= h;
                let (mut fp, mut fm) = ([0.0], [0.0]);
                cam.phi_at(&qp, 0.0, &mut fp);
                cam.phi_at(&qm, 0.0, &mut fm);
                let fd = (fp[0] - fm[0]) / (2.0 * h);
                assert!((fd - an).abs() < 1e-7, "Phi_q[{k}] analytic {an} vs fd {fd}");
            }
        }
        let (gamma, rate) = trajectory_errors(&cam, &states, 1e-7);
        eprintln!("points: gamma {gamma:.1e}, du*/dt {rate:.1e} off their differences");
        assert!(gamma < 1e-6, "gamma against differences of Phi_q qdot: {gamma:e}");
        assert!(rate < 1e-6, "du*/dt against differences of u*: {rate:e}");
    }

    /// A circle of radius 2 about the cam's centre with a roller of 0.5: the row is the
    /// distance's, `|d| - 2.5`; at `d = (3, 4)` moving at `(1, 0)`, `Phi = 2.5`,
    /// `Phi_q = d/|d| = (0.6, 0.8)` and `gamma = -(1 - 0.36)/5` (cam.rs's hand-derived case). The
    /// circle clockwise gives the same row.
    #[test]
    fn hand_derived_circle_either_way_round() {
        for y in ["2*sin(u)", "-2*sin(u)"] {
            let circle = Curve::parametric(expr("2*cos(u)", "u"), expr(y, "u"), 2.0 * PI).unwrap();
            let cam =
                CamProfile::try_new([(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])], circle, 0.5).unwrap();
            let q = [3.0, 4.0, 0.7];
            let (mut phi, mut jac, mut g) = ([0.0], [0.0; 3], [0.0]);
            cam.phi_at(&q, 0.0, &mut phi);
            cam.jacobian_at(&q, 0.0, &mut jac);
            cam.gamma_at(&q, &[1.0, 0.0, 5.0], 0.0, &mut g);
            // The normal comes from the tangent at u*, found to round-off in u: a few ulps.
            assert!((phi[0] - 2.5).abs() < 1e-14, "{phi:?}");
            assert!((jac[0] - 0.6).abs() < 1e-14 && (jac[1] - 0.8).abs() < 1e-14 && jac[2].abs() < 1e-14, "{jac:?}");
            assert!((g[0] + 0.64 / 5.0).abs() < 1e-14, "{g:?}");
        }
    }

    /// A point table of the same circle: 360 points, then the same row to the spline's error.
    #[test]
    fn a_point_table_of_a_circle() {
        let pts: Vec<[f64; 2]> =
            (0..360).map(|k| (k as f64).to_radians()).map(|a| [2.0 * a.cos(), 2.0 * a.sin()]).collect();
        let cam = CamProfile::try_new(
            [(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])],
            Curve::points(&pts).unwrap(),
            0.5,
        )
        .unwrap();
        let mut worst = 0.0f64;
        for k in 0..1000 {
            let a = k as f64 * 0.00731;
            let mut phi = [0.0];
            cam.phi_at(&[4.0 * a.cos(), 4.0 * a.sin(), 0.0], 0.0, &mut phi);
            worst = worst.max((phi[0] - 1.5).abs());
        }
        // A periodic cubic spline through equally spaced samples of a sinusoid misses it by
        // h^4 |f''''| / 384 between the knots (de Boor's bound is 5/384): with h = 2 pi 2 / 360
        // and |f''''| = 1/2^3 in arc length, 4.8e-10, which is what is measured.
        assert!(worst < 5e-10, "{worst:e}");
    }

    #[test]
    fn the_nearest_point_is_refused_where_it_is_not_unique() {
        let circle = Curve::parametric(expr("2*cos(u)", "u"), expr("2*sin(u)", "u"), 2.0 * PI).unwrap();
        let cam = CamProfile::try_new([(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])], circle, 0.5).unwrap();
        let mut phi = [0.0];
        // At the circle's centre every point is nearest.
        cam.phi_at(&[0.0, 0.0, 0.0], 0.0, &mut phi);
        assert!(phi[0].is_nan(), "{phi:?}");
        // Inside an ellipse on its minor axis, both ends of the major axis are... not: the two
        // nearest points of the minor axis' ends are equally near from the centre.
        let ellipse = Curve::parametric(expr("2*cos(u)", "u"), expr("sin(u)", "u"), 2.0 * PI).unwrap();
        let cam = CamProfile::try_new([(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])], ellipse, 0.0).unwrap();
        cam.phi_at(&[0.0, 0.0, 0.0], 0.0, &mut phi);
        assert!(phi[0].is_nan(), "{phi:?}");
        cam.phi_at(&[0.0, 0.3, 0.0], 0.0, &mut phi);
        assert!((phi[0] + 0.7).abs() < 1e-14, "{phi:?}");
    }

    impl crate::constraints::testing::Checked for CamProfile {
        fn phi_checked<S: Nestable>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
            out[0] = self.phi_nested(at, data);
        }
    }

    /// The generic row (design sensitivities) by the joints' checker: over `f64` it is `phi`, its
    /// first-order parts the Jacobian, its second-order part along the motion `-gamma`, and its
    /// parts along the data (the two points and the roller's radius) central differences of it,
    /// on the expressions' curve and the point table's, with a roller and with a knife edge.
    #[test]
    fn the_generic_row_matches_phi_its_derivatives_and_differences_in_the_data() {
        for (curve, roller, seed) in [(convex(), 0.3, 21), (convex(), 0.0, 22), (convex_table(), 0.3, 23)] {
            let ends = [(BodyIx(Some(0)), [0.1, -0.2]), (BodyIx(Some(3)), [0.3, 0.1])];
            let cam = CamProfile::try_new(ends, curve, roller).unwrap();
            assert_data_fields::<CamJoint>(&cam);
            for (q, qdot) in states(&cam, 0.2, seed, 10) {
                check_generic(&cam, &q, &qdot, 0.0);
            }
        }
    }

    /// The model's parameters `a` (slot 0) and `R` (slot 1) at `values`, for expressions.
    struct Params([f64; 2]);

    impl crate::expr::Names for Params {
        fn constant(&self, name: &str) -> Option<f64> {
            self.parameter(name).map(|k| self.0[k])
        }
        fn parameter(&self, name: &str) -> Option<usize> {
            ["a", "R"].iter().position(|&n| n == name)
        }
    }

    /// A circle of radius `R` about `(a, 0.2)`, both parameters, a roller of radius `r` centred
    /// at `d = (x, y)` (the follower's coordinates; the cam is ground): `Phi = |d - c| - R - r`,
    /// the contact `p(u*) = c + R (d - c) / |d - c|` and the pressure angle `atan2(-sense d x n,
    /// d . n)`, `n = (d - c) / |d - c|`, in closed form over [`Tri`] numbers whose three
    /// directions move the coordinates, the parameters and the radius all at once (mixed parts
    /// included). The lifted `u*` must carry its derivatives to the third order for `p(u*)` to
    /// match in every part. Exact derivatives of the same function: to 1e-13 of the parts' size.
    #[test]
    fn a_parametric_circle_in_closed_form_to_the_third_order() {
        let values = [0.3, 1.5];
        let parse = |src: &str| {
            Expr::parse_with(src, &Params(values), &mut |n| if n == "u" { Ok(0) } else { Err(format!("unknown {n}")) })
                .unwrap()
        };
        let curve = Curve::parametric(parse("a + R*cos(u)"), parse("0.2 + R*sin(u)"), 2.0 * PI).unwrap();
        let roller = 0.25;
        let cam =
            CamProfile::try_new([(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])], curve, roller).unwrap();
        let tri = |v: f64, first: [f64; 3], second: [f64; 3], third: f64| Tri::new(v, first, second, third);
        let q = [
            tri(2.1, [0.4, -0.3, 0.2], [0.1, 0.05, -0.2], 0.3),
            tri(-1.2, [0.7, 0.5, -0.1], [-0.3, 0.2, 0.1], -0.1),
            tri(0.4, [1.0, 0.0, 0.0], [0.0; 3], 0.0),
        ];
        let params =
            [tri(values[0], [0.0, 0.2, 0.5], [0.0, 0.1, 0.0], 0.0), tri(values[1], [0.3, 0.0, -0.4], [0.0; 3], 0.2)];
        let data = [0.0, 0.0, 0.0, 0.0].map(Tri::constant);
        let data = [data[0], data[1], data[2], data[3], tri(roller, [0.0, 0.0, 1.0], [0.0; 3], 0.0)];
        let centre = [params[0], Tri::constant(0.2)];
        let rel = sub([q[0], q[1]], centre);
        let dist = rel[0].hypot(rel[1]);
        let n = [rel[0] / dist, rel[1] / dist];
        let close = |got: Tri, want: Tri, what: &str| {
            let size = want.parts().iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (k, (g, w)) in got.parts().iter().zip(want.parts()).enumerate() {
                assert!((g - w).abs() <= 1e-13 * size, "{what}: part {k}: {got:?} vs {want:?}");
            }
        };
        let mut out = [Tri::constant(f64::NAN)];
        assert!(cam.phi_tri(&At { q: &q, t: Tri::constant(0.0), params: &params }, &data, &mut out));
        close(out[0], dist - params[1] - data[4], "Phi");
        let (p, normal) = cam.lifted_contact([q[0], q[1]], &params).unwrap();
        for k in 0..2 {
            close(p[k], centre[k] + params[1] * n[k], "p(u*)");
            close(normal[k], n[k], "n(u*)");
        }
        // The follower moves with psi rising: sense 1.
        let qdot = [-1.0, 2.0, 0.0].map(Tri::constant);
        let angle = cam.pressure_angle_generic(&q, &qdot, &data, &params);
        let d = [q[0], q[1]];
        close(angle, (-cross(d, n)).atan2(dot(d, n)), "pressure angle");
        assert!((angle.v - cam.pressure_angle(&q.map(Tri::value), &qdot.map(Tri::value))).abs() < 1e-15);
    }

    #[test]
    fn bad_curves_are_refused_at_their_fields() {
        let make = |curve: Result<Curve, CurveError>, roller: f64| {
            curve
                .and_then(|c| CamProfile::try_new([(BodyIx::GROUND, [0.0; 2]), (BodyIx(Some(0)), [0.0; 2])], c, roller))
        };
        let cases: [(Result<Curve, CurveError>, f64, &str, &str); 7] = [
            (Ok(limacon()), 0.85, "roller_radius", "an undercut"),
            (Curve::parametric(expr("cos(u)", "u"), expr("sin(u)", "u"), 6.0), 0.0, "profile.period", "does not close"),
            (Curve::parametric(expr("sin(2*u)", "u"), expr("sin(u)", "u"), 2.0 * PI), 0.0, "profile", "no area"),
            (Curve::parametric(expr("cos(u)^3", "u"), expr("sin(u)^3", "u"), 2.0 * PI), 0.0, "profile", "vanishes"),
            (Curve::parametric(expr("cos(u)", "u"), expr("sin(u)", "u"), -1.0), 0.0, "profile.period", "positive"),
            (Curve::points(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), 0.0, "profile", "are equal"),
            (Curve::polar(expr("1 + 0.1*psi", "psi")), 0.0, "surface_radius", "does not close"),
        ];
        for (curve, roller, field, want) in cases {
            let e = make(curve, roller).unwrap_err();
            assert_eq!(e.field, field, "{e:?}");
            assert!(e.message.contains(want), "no '{want}' in {e:?}");
        }
        // A roller within the concave radius of curvature (0.8 at psi = pi) fits.
        assert!(make(Ok(limacon()), 0.75).is_ok());
    }
}
