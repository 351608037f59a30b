//! Tabulated functions: a piecewise cubic through points `(x_i, y_i)` with `x` strictly
//! increasing, for `spline(name, x)` in expressions.
//!
//! Each piece is the cubic Hermite interpolant of its two points and the slopes `m_i` there:
//! on `x_i <= x <= x_i+1`, with `h = x_i+1 - x_i`, `d = (y_i+1 - y_i) / h` and `u = x - x_i`,
//!
//! ```text
//! s(x) = y_i + m_i u + c_i u^2 + e_i u^3,  c_i = (3 d - 2 m_i - m_i+1) / h,  e_i = (m_i + m_i+1 - 2 d) / h^2
//! ```
//!
//! The methods differ in the slopes:
//!
//! * [`Method::NotAKnot`] (the default): the interpolating cubic spline, `s''` continuous, with
//!   the not-a-knot end conditions (`s'''` continuous at the second and the last but one point,
//!   de Boor, *A Practical Guide to Splines*, ch. IV; MATLAB's `spline`, SciPy's
//!   `CubicSpline`). The slopes solve `h_i m_i-1 + 2 (h_i-1 + h_i) m_i + h_i-1 m_i+1 =
//!   3 (h_i d_i-1 + h_i-1 d_i)` inside. Two points give the line, three the parabola through
//!   them. It reproduces any cubic exactly.
//! * [`Method::Periodic`]: the same equations taken around the period `x_n-1 - x_0` (the first
//!   and last `y` must be equal); `s`, `s'` and `s''` are periodic and continuous.
//! * [`Method::Akima`]: Akima's slopes (J. ACM 17, 1970), as Adams' AKISPL: each a weighted
//!   mean of the neighbouring chords' slopes, so a table with a sharp corner does not ring.
//!   `s'` is continuous, `s''` only within each piece.
//!
//! Outside `[x_0, x_n-1]` a periodic table repeats. Any other continues as the straight line
//! of its end value and end slope (`s''` = 0 there): values stay bounded by the data's trend,
//! where continuing an end cubic would grow as the cube of the distance.

use super::Scalar;
use crate::linalg::{Pattern, SparseLu};

/// How the slopes at the points are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// The cubic spline with not-a-knot end conditions.
    #[default]
    NotAKnot,
    /// The periodic cubic spline.
    Periodic,
    /// Akima's slopes (Adams' AKISPL).
    Akima,
}

/// What is wrong with a table's points: the column (`"x"`, `"y"`, or `""` for the table as a
/// whole), the index of the point concerned, if one, and the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct TableError {
    /// `"x"`, `"y"` or `""`.
    pub column: &'static str,
    /// The point concerned.
    pub index: Option<usize>,
    /// The reason.
    pub message: String,
}

impl TableError {
    fn new(column: &'static str, index: Option<usize>, message: String) -> Self {
        TableError { column, index, message }
    }
}

/// A tabulated function of one variable, with exact first, second and third derivatives.
#[derive(Debug, Clone, PartialEq)]
pub struct Spline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// The slope at each point.
    m: Vec<f64>,
    periodic: bool,
}

impl Spline {
    /// The interpolant of `(x[i], y[i])` by `method`.
    ///
    /// # Errors
    ///
    /// What is wrong with the data: fewer than two points (three when periodic), `x` and `y` of
    /// different lengths, a number that is not finite, `x` not strictly increasing (naming the
    /// first index where it is not), or a periodic table whose first and last `y` differ.
    pub fn new(x: Vec<f64>, y: Vec<f64>, method: Method) -> Result<Spline, TableError> {
        let periodic = method == Method::Periodic;
        let least = if periodic { 3 } else { 2 };
        if x.len() != y.len() {
            let message = format!("x has {} values and y {}; expected as many of each", x.len(), y.len());
            return Err(TableError::new("", None, message));
        }
        if x.len() < least {
            return Err(TableError::new("", None, format!("{} points given; expected at least {least}", x.len())));
        }
        if let Some(i) = x.iter().chain(&y).position(|v| !v.is_finite()) {
            let (axis, i) = if i < x.len() { ("x", i) } else { ("y", i - x.len()) };
            return Err(TableError::new(axis, Some(i), format!("{axis}[{i}] is not a finite number")));
        }
        if let Some(i) = x.windows(2).position(|w| w[1] <= w[0]) {
            let message = format!("x must increase strictly: x[{}] = {} follows x[{i}] = {}", i + 1, x[i + 1], x[i]);
            return Err(TableError::new("x", Some(i + 1), message));
        }
        let last = y.len() - 1;
        if periodic && y[0] != y[last] {
            let message = format!("a periodic table ends where it starts: y[0] = {} but y[{last}] = {}", y[0], y[last]);
            return Err(TableError::new("y", Some(last), message));
        }
        let m = match method {
            Method::NotAKnot => not_a_knot(&x, &y),
            Method::Periodic => periodic_slopes(&x, &y),
            Method::Akima => Ok(akima(&x, &y)),
        }
        .map_err(|message| TableError::new("x", None, message))?;
        Ok(Spline { x, y, m, periodic })
    }

    /// The number of pieces: one fewer than the points.
    pub fn pieces(&self) -> usize {
        self.x.len() - 1
    }

    /// `(s(x), s'(x), s''(x))`; NaN for a NaN `x`.
    #[inline]
    pub fn eval(&self, x: f64) -> (f64, f64, f64) {
        let (s0, s1, s2, _) = self.eval3(x);
        (s0, s1, s2)
    }

    /// `(s(x), s'(x), s''(x), s'''(x))`: the third derivative is the piece's (6 times its cubic
    /// coefficient; at a point between two pieces, the piece [`Spline::eval`] takes), 0 on the
    /// straight lines outside the table; NaN for a NaN `x`.
    #[inline]
    pub fn eval3(&self, x: f64) -> (f64, f64, f64, f64) {
        let (first, last) = (self.x[0], self.x[self.x.len() - 1]);
        let x = if self.periodic { first + (x - first).rem_euclid(last - first) } else { x };
        if x.is_nan() {
            return (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
        }
        let n = self.x.len();
        if x < first {
            return (self.y[0] + self.m[0] * (x - first), self.m[0], 0.0, 0.0);
        }
        if x > last {
            return (self.y[n - 1] + self.m[n - 1] * (x - last), self.m[n - 1], 0.0, 0.0);
        }
        // The piece whose start is the last point at or before x (the last piece at its end).
        let i = self.x.partition_point(|&xi| xi <= x).clamp(1, n - 1) - 1;
        let h = self.x[i + 1] - self.x[i];
        let d = (self.y[i + 1] - self.y[i]) / h;
        let (m0, m1) = (self.m[i], self.m[i + 1]);
        let c = (3.0 * d - 2.0 * m0 - m1) / h;
        let e = (m0 + m1 - 2.0 * d) / (h * h);
        let u = x - self.x[i];
        (self.y[i] + u * (m0 + u * (c + u * e)), m0 + u * (2.0 * c + 3.0 * u * e), 2.0 * c + 6.0 * u * e, 6.0 * e)
    }

    /// `s(x)` over any [`Scalar`]: the value and derivatives of the piece at `x`'s value lifted
    /// onto `x`'s derivatives (the third derivative for a type that carries it, and a fourth of 0:
    /// each piece is a cubic).
    #[inline]
    pub fn lifted<S: Scalar>(&self, x: S) -> S {
        if S::ORDER >= 3 {
            let (f0, f1, f2, f3) = self.eval3(x.value());
            x.lift_fourth([f0, f1, f2, f3, 0.0])
        } else {
            let (f0, f1, f2) = self.eval(x.value());
            x.lift(f0, f1, f2, 0.0)
        }
    }

    /// `integral s(x) dx` from the first point to the last, exact for the piecewise cubic: the
    /// integral of each piece's Hermite cubic is `h (y_i + y_i+1) / 2 + h^2 (m_i - m_i+1) / 12`,
    /// the trapezoidal rule and its end correction (Euler-Maclaurin's first term, with the
    /// spline's slopes).
    pub fn integral(&self) -> f64 {
        (1..self.x.len())
            .map(|i| {
                let h = self.x[i] - self.x[i - 1];
                h * (self.y[i - 1] + self.y[i]) / 2.0 + h * h * (self.m[i - 1] - self.m[i]) / 12.0
            })
            .sum()
    }
}

/// Chord lengths and slopes of consecutive points.
fn chords(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let d = y.windows(2).zip(&h).map(|(w, h)| (w[1] - w[0]) / h).collect();
    (h, d)
}

/// Solves the slope equations given as `(row, column, value)` entries and right-hand sides.
fn solve(order: usize, entries: &[(usize, usize, f64)], mut rhs: Vec<f64>) -> Result<Vec<f64>, String> {
    let pattern = Pattern::new(order, order, entries.iter().map(|&(r, c, _)| Some((r, c))));
    let singular = |_| "the spline's equations are singular".to_string();
    let mut lu = SparseLu::new(pattern).map_err(singular)?;
    let (pattern, values) = lu.pattern_and_values();
    values.fill(0.0);
    for (k, &(_, _, v)) in entries.iter().enumerate() {
        values[pattern.map[k]] += v;
    }
    lu.factor().map_err(singular)?;
    lu.solve(&mut rhs);
    if rhs.iter().all(|m| m.is_finite()) {
        Ok(rhs)
    } else {
        Err("the spline's slopes are not finite: the spacing of x is too uneven".into())
    }
}

/// The interior continuity equation of `s''` at point `i` (between pieces `a` and `b`) for the
/// slopes at columns `prev`, `i`, `next`.
fn continuity(
    i: usize,
    (prev, next): (usize, usize),
    (a, b): (usize, usize),
    h: &[f64],
    d: &[f64],
) -> ([(usize, usize, f64); 3], f64) {
    ([(i, prev, h[b]), (i, i, 2.0 * (h[a] + h[b])), (i, next, h[a])], 3.0 * (h[b] * d[a] + h[a] * d[b]))
}

/// The not-a-knot spline's slopes.
fn not_a_knot(x: &[f64], y: &[f64]) -> Result<Vec<f64>, String> {
    let (h, d) = chords(x, y);
    let n = x.len();
    match n {
        2 => return Ok(vec![d[0]; 2]),
        3 => {
            // The parabola through the three points: both end conditions say s''' = 0.
            let c2 = (d[1] - d[0]) / (h[0] + h[1]);
            return Ok(vec![d[0] - c2 * h[0], d[0] + c2 * h[0], d[1] + c2 * h[1]]);
        }
        _ => {}
    }
    let mut entries = Vec::with_capacity(3 * n);
    let mut rhs = vec![0.0; n];
    let (w0, wn) = (h[0] + h[1], h[n - 3] + h[n - 2]);
    entries.extend([(0, 0, h[1]), (0, 1, w0)]);
    rhs[0] = ((h[0] + 2.0 * w0) * h[1] * d[0] + h[0] * h[0] * d[1]) / w0;
    for (i, r) in rhs.iter_mut().enumerate().take(n - 1).skip(1) {
        let (row, value) = continuity(i, (i - 1, i + 1), (i - 1, i), &h, &d);
        entries.extend(row);
        *r = value;
    }
    entries.extend([(n - 1, n - 2, wn), (n - 1, n - 1, h[n - 3])]);
    rhs[n - 1] = (h[n - 2] * h[n - 2] * d[n - 3] + (2.0 * wn + h[n - 2]) * h[n - 3] * d[n - 2]) / wn;
    solve(n, &entries, rhs)
}

/// The periodic spline's slopes: the continuity equations around the period, the last point
/// the first again.
fn periodic_slopes(x: &[f64], y: &[f64]) -> Result<Vec<f64>, String> {
    let (h, d) = chords(x, y);
    let k = x.len() - 1;
    let mut entries = Vec::with_capacity(3 * k);
    let mut rhs = vec![0.0; k];
    for (i, r) in rhs.iter_mut().enumerate() {
        let before = (i + k - 1) % k;
        let (row, value) = continuity(i, (before, (i + 1) % k), (before, i), &h, &d);
        entries.extend(row);
        *r = value;
    }
    let mut m = solve(k, &entries, rhs)?;
    m.push(m[0]);
    Ok(m)
}

/// Akima's slopes, with his end rule: two chords are added at each end, continuing the chord
/// slopes' trend linearly (`d_-1 = 2 d_0 - d_1`, `d_-2 = 2 d_-1 - d_0`, and alike at the end;
/// a single chord is continued as itself).
fn akima(x: &[f64], y: &[f64]) -> Vec<f64> {
    let (_, d) = chords(x, y);
    let k = d.len();
    let (first, second) = (d[0], d[1.min(k - 1)]);
    let (last, before) = (d[k - 1], d[k.saturating_sub(2)]);
    let (l1, r1) = (2.0 * first - second, 2.0 * last - before);
    // e[j + 2] is the slope of chord j, for j from -2 to k + 1.
    let e: Vec<f64> =
        [2.0 * l1 - first, l1].into_iter().chain(d.iter().copied()).chain([r1, 2.0 * r1 - last]).collect();
    (0..x.len())
        .map(|i| {
            // Point i lies between chords i - 1 and i: e[i + 1] and e[i + 2].
            let (w1, w2) = ((e[i + 3] - e[i + 2]).abs(), (e[i + 1] - e[i]).abs());
            if w1 + w2 == 0.0 {
                (e[i + 1] + e[i + 2]) / 2.0
            } else {
                (w1 * e[i + 1] + w2 * e[i + 2]) / (w1 + w2)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of `s` and `s'` at `x` with step `h`.
    fn differences(s: &Spline, x: f64, h: f64) -> (f64, f64) {
        ((s.eval(x + h).0 - s.eval(x - h).0) / (2.0 * h), (s.eval(x + h).1 - s.eval(x - h).1) / (2.0 * h))
    }

    fn grid(n: usize, a: f64, b: f64) -> Vec<f64> {
        // Uneven on purpose: a smooth stretching of an even grid.
        (0..n)
            .map(|i| {
                let u = i as f64 / (n - 1) as f64;
                a + (b - a) * (u + 0.15 * (std::f64::consts::PI * u).sin() / std::f64::consts::PI)
            })
            .collect()
    }

    #[test]
    fn not_a_knot_reproduces_a_cubic() {
        // Not-a-knot interpolation is exact for cubics: the error is roundoff (values of
        // order 10, so 1e-12 is a few hundred ulps through the solve).
        let f = |x: f64| (2.0 - 3.0 * x + 0.5 * x * x - 0.25 * x * x * x, -3.0 + x - 0.75 * x * x, 1.0 - 1.5 * x);
        for n in [4, 5, 9, 30] {
            let x = grid(n, -1.0, 2.5);
            let y = x.iter().map(|&x| f(x).0).collect();
            let s = Spline::new(x, y, Method::NotAKnot).unwrap();
            for k in 0..=70 {
                let x = -1.0 + 3.5 * k as f64 / 70.0;
                let (v, d1, d2) = s.eval(x);
                let (fv, f1, f2) = f(x);
                assert!((v - fv).abs() < 1e-12 && (d1 - f1).abs() < 1e-11 && (d2 - f2).abs() < 1e-10, "n {n} x {x}");
            }
        }
    }

    #[test]
    fn three_points_give_their_parabola_and_two_their_line() {
        let s = Spline::new(vec![0.0, 1.0, 3.0], vec![1.0, 2.0, 10.0], Method::NotAKnot).unwrap();
        // y = 1 + 0 x + x^2 through (0, 1), (1, 2), (3, 10).
        for x in [0.0, 0.4, 1.0, 2.2, 3.0] {
            let (v, d1, d2) = s.eval(x);
            assert!((v - (1.0 + x * x)).abs() < 1e-14 && (d1 - 2.0 * x).abs() < 1e-13 && (d2 - 2.0).abs() < 1e-13);
        }
        let l = Spline::new(vec![1.0, 2.0], vec![3.0, 5.0], Method::NotAKnot).unwrap();
        assert_eq!(l.eval(1.5), (4.0, 2.0, 0.0));
    }

    #[test]
    fn converges_at_fourth_order_to_a_smooth_function() {
        // The cubic spline's error is O(h^4) in the value, O(h^3) in s' and O(h^2) in s''
        // (de Boor, ch. V): doubling the points must divide the errors by about 16, 8 and 4.
        // Judged at 2^3.5, 2^2.5 and 2^1.5 so that the asymptote need not be reached exactly.
        let errors = |n: usize, method: Method| {
            let x = grid(n, 0.0, 2.0 * std::f64::consts::PI);
            let mut y: Vec<f64> = x.iter().map(|x| x.sin()).collect();
            if method == Method::Periodic {
                // sin(2 pi) is -2.4e-16, not the 0 of sin(0): the table's period closes exactly.
                *y.last_mut().unwrap() = y[0];
            }
            let s = Spline::new(x, y, method).unwrap();
            (0..=400).fold([0.0f64; 3], |e, k| {
                let x = 2.0 * std::f64::consts::PI * k as f64 / 400.0;
                let (v, d1, d2) = s.eval(x);
                [e[0].max((v - x.sin()).abs()), e[1].max((d1 - x.cos()).abs()), e[2].max((d2 + x.sin()).abs())]
            })
        };
        for method in [Method::NotAKnot, Method::Periodic] {
            let (coarse, fine) = (errors(20, method), errors(39, method));
            for (k, order) in [4.0, 3.0, 2.0].into_iter().enumerate() {
                let ratio = coarse[k] / fine[k];
                assert!(ratio > 2f64.powf(order - 0.5), "{method:?} derivative {k}: ratio {ratio}");
            }
        }
    }

    #[test]
    fn the_integral_is_exact_for_a_cubic_and_fourth_order_for_a_smooth_function() {
        // Not-a-knot reproduces a cubic, so its integral is the cubic's to round-off: of
        // f = 2 - 3x + x^2/2 - x^3/4 from -1 to 2.5, F(2.5) - F(-1) with F = 2x - 3x^2/2 + x^3/6
        // - x^4/16 (values of order 10: 1e-12 is a few hundred ulps).
        let f = |x: f64| 2.0 - 3.0 * x + 0.5 * x * x - 0.25 * x * x * x;
        let antiderivative = |x: f64| 2.0 * x - 1.5 * x * x + x * x * x / 6.0 - x.powi(4) / 16.0;
        let exact = antiderivative(2.5) - antiderivative(-1.0);
        for n in [4, 9, 30] {
            let x = grid(n, -1.0, 2.5);
            let y: Vec<f64> = x.iter().map(|&x| f(x)).collect();
            let got = Spline::new(x, y, Method::NotAKnot).unwrap().integral();
            assert!((got - exact).abs() < 1e-12, "n {n}: {got} vs {exact}");
        }
        // The integral of sin over [0, 3] on uneven points errs as h^4: halving the steps divides
        // the error by about 16 (judged at 2^3.5, as above). Measured from 38 steps on: 14.8,
        // 15.7 (from 19 steps the error's terms still partly cancel: 11.2).
        let error = |n: usize| {
            let x = grid(n, 0.0, 3.0);
            let y = x.iter().map(|x| x.sin()).collect();
            (Spline::new(x, y, Method::NotAKnot).unwrap().integral() - (1.0 - 3f64.cos())).abs()
        };
        for (coarse, fine) in [(39, 77), (77, 153)] {
            let ratio = error(coarse) / error(fine);
            assert!(ratio > 2f64.powf(3.5), "{coarse} points: ratio {ratio}");
        }
    }

    #[test]
    fn periodic_repeats_with_continuous_derivatives_across_the_period() {
        let x = grid(12, 0.0, 2.0);
        let y: Vec<f64> = x.iter().map(|x| (std::f64::consts::PI * x).cos() + 0.3 * x * (2.0 - x)).collect();
        let s = Spline::new(x, y, Method::Periodic).unwrap();
        // Across the seam the derivatives agree to roundoff (values of order 10 for s'').
        let (a, b) = (s.eval(2.0 - 1e-13), s.eval(2.0 + 1e-13));
        assert!((a.0 - b.0).abs() < 1e-11 && (a.1 - b.1).abs() < 1e-10 && (a.2 - b.2).abs() < 1e-9, "{a:?} {b:?}");
        let (c, d) = (s.eval(0.37), s.eval(0.37 - 6.0));
        assert!((c.0 - d.0).abs() < 1e-14 && (c.1 - d.1).abs() < 1e-13 && (c.2 - d.2).abs() < 1e-12);
    }

    #[test]
    fn akima_is_exact_on_a_line_and_does_not_ring_at_a_corner() {
        let x = grid(8, 0.0, 7.0);
        let line: Vec<f64> = x.iter().map(|x| 2.0 * x - 1.0).collect();
        let s = Spline::new(x.clone(), line, Method::Akima).unwrap();
        for k in 0..=35 {
            let (v, d1, d2) = s.eval(0.2 * k as f64);
            assert!((v - (0.4 * k as f64 - 1.0)).abs() < 1e-13 && (d1 - 2.0).abs() < 1e-13 && d2.abs() < 1e-12);
        }
        // A ramp then flat: Akima's slopes are 0 on the flat part past the corner's neighbour,
        // so the interpolant stays flat there (a cubic spline overshoots and oscillates).
        let ramp: Vec<f64> = (0..8).map(|i| f64::from(i.min(3))).collect();
        let s = Spline::new((0..8).map(f64::from).collect(), ramp, Method::Akima).unwrap();
        for k in 0..=40 {
            let x = 4.0 + 0.1 * k as f64;
            assert_eq!(s.eval(x).0, 3.0, "x {x}");
        }
    }

    #[test]
    fn akima_end_slopes_follow_his_end_rule() {
        // Worked by hand from Akima (1970): chords 0, 1, 0; continued at each end as
        // d_-1 = 2 d_0 - d_1 = -1, d_-2 = 2 d_-1 - d_0 = -2 (and d_3 = -1, d_4 = -2). At point 0
        // the weights |d_1 - d_0| = |d_-1 - d_-2| = 1 give m_0 = (d_-1 + d_0) / 2 = -0.5; at
        // point 1, |d_2 - d_1| = |d_0 - d_-1| = 1 give m_1 = (d_0 + d_1) / 2 = 0.5; by symmetry
        // m_2 = 0.5 and m_3 = -0.5. Another end rule (a chord continued as itself) gives m_0 = 0.
        let s = Spline::new(vec![0.0, 1.0, 2.0, 3.0], vec![0.0, 0.0, 1.0, 1.0], Method::Akima).unwrap();
        for (x, m) in [(0.0, -0.5), (1.0, 0.5), (2.0, 0.5), (3.0, -0.5)] {
            assert!((s.eval(x).1 - m).abs() < 1e-15, "slope at {x}: {} vs {m}", s.eval(x).1);
        }
    }

    #[test]
    fn derivatives_match_finite_differences_for_every_method() {
        let x = grid(9, 0.0, 3.0);
        let mut y: Vec<f64> = x.iter().map(|x| (1.3 * x).sin() * x.exp() / 5.0).collect();
        y[8] = y[0];
        for method in [Method::NotAKnot, Method::Periodic, Method::Akima] {
            let s = Spline::new(x.clone(), y.clone(), method).unwrap();
            // Inside pieces (away from the points, where Akima's s'' jumps), at the ends' outside,
            // and across the period. Central differences with h = 1e-6 err by O(h^2 s''') ~ 1e-11
            // plus roundoff ~ 1e-16 / 1e-6 = 1e-10 relative to values of order 1-10.
            for probe in [-0.7, 0.13, 0.9, 1.71, 2.2, 2.95, 3.6] {
                let (_, d1, d2) = s.eval(probe);
                let (f1, f2) = differences(&s, probe, 1e-6);
                assert!((d1 - f1).abs() < 1e-8 && (d2 - f2).abs() < 1e-7, "{method:?} at {probe}");
            }
        }
    }

    #[test]
    fn outside_the_table_a_line_continues_the_ends() {
        // The line starts from the end point and the end slope; the cubic's value at the end
        // point is that point to the rounding of the slopes (a few units in the last place).
        let s = Spline::new(vec![0.0, 1.0, 2.0, 4.0], vec![0.0, 1.0, 0.0, 2.0], Method::NotAKnot).unwrap();
        let close = |(a, b, c): (f64, f64, f64), (x, y, z): (f64, f64, f64)| {
            (a - x).abs() <= 1e-14 * x.abs().max(1.0) && b == y && c == z
        };
        let (v, m, _) = s.eval(4.0);
        assert!(close(s.eval(5.5), (v + 1.5 * m, m, 0.0)), "{:?} against {:?}", s.eval(5.5), (v + 1.5 * m, m, 0.0));
        let (v, m, _) = s.eval(0.0);
        assert!(close(s.eval(-2.0), (v - 2.0 * m, m, 0.0)), "{:?} against {:?}", s.eval(-2.0), (v - 2.0 * m, m, 0.0));
        assert!(s.eval(f64::NAN).0.is_nan());
    }

    #[test]
    fn bad_tables_are_refused_with_the_reason() {
        let bad = |x: Vec<f64>, y: Vec<f64>, m| Spline::new(x, y, m).unwrap_err().message;
        assert!(bad(vec![0.0], vec![1.0], Method::NotAKnot).contains("at least 2"));
        assert!(bad(vec![0.0, 1.0], vec![1.0, 1.0], Method::Periodic).contains("at least 3"));
        assert!(bad(vec![0.0, 1.0, 2.0], vec![1.0, 2.0], Method::NotAKnot).contains("3 values and y 2"));
        assert!(bad(vec![0.0, 1.0, 1.0], vec![1.0, 2.0, 3.0], Method::Akima).contains("x[2] = 1 follows x[1] = 1"));
        assert!(bad(vec![0.0, 1.0, 2.0], vec![1.0, f64::NAN, 3.0], Method::Akima).contains("y[1]"));
        assert!(bad(vec![0.0, 1.0, 2.0], vec![1.0, 2.0, 3.0], Method::Periodic).contains("ends where it starts"));
    }
}
