//! Number types for forward-mode automatic differentiation.
//!
//! An [`Expr`](super::Expr) is evaluated generically over a [`Scalar`]. Three
//! implementations are provided:
//!
//! * [`f64`]: the plain value;
//! * [`Dual`]: value plus one directional derivative (`v + d ε`, `ε² = 0`);
//! * [`HyperDual`]: value, two first directional derivatives and the mixed second
//!   derivative (`v + e1 ε1 + e2 ε2 + e12 ε1ε2`, `ε1² = ε2² = 0`).
//!
//! Seeding the inputs of a function `f` with `x = (x0, a, b, 0)` gives a result whose
//! `e12` component is `aᵀ H b` (`H` the Hessian of `f` at `x0`); with `a = b` this is
//! the second directional derivative, so a time function seeded with `(t, 1, 1, 0)`
//! yields `(f, f', f'')` exactly.
//!
//! Every elementary function is implemented once, as a default method of [`Scalar`],
//! from its value and first two derivatives ([`Scalar::lift`] and [`Scalar::lift2`]).
//! The value component is always computed with exactly the same floating-point
//! operations as the plain `f64` evaluation, so `Dual` and `HyperDual` evaluations
//! return bit-identical values.

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// `f * d`, except that a zero seed `d` gives zero even when `f` is infinite or NaN.
///
/// A zero seed component means "this input does not move along the direction", so
/// the contribution is zero whatever the (possibly singular) partial derivative is.
/// Without this rule `a * sqrt(b)` at `b = 0` would have a NaN derivative along `a`.
#[inline]
fn scale(f: f64, d: f64) -> f64 {
    if d == 0.0 {
        0.0
    } else {
        f * d
    }
}

/// The sign of `v`: `1`, `-1`, `0` for zero (of either sign), NaN for NaN.
#[inline]
fn sign_of(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else if v == 0.0 {
        0.0
    } else {
        f64::NAN
    }
}

/// A number type that expressions can be evaluated over.
///
/// Implementors supply the arithmetic operators, [`constant`](Scalar::constant),
/// [`value`](Scalar::value) and the two chain-rule primitives
/// [`lift`](Scalar::lift) / [`lift2`](Scalar::lift2); every elementary function has a
/// default implementation in terms of those.
pub trait Scalar:
    Copy + Debug + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// Highest derivative order carried by the type (0 for `f64`, 1 for [`Dual`],
    /// 2 for [`HyperDual`]). The default methods skip computing derivative factors
    /// that the type would discard.
    const ORDER: u8;

    /// A constant (all derivative parts zero).
    fn constant(v: f64) -> Self;

    /// The value (real) part.
    fn value(self) -> f64;

    /// Applies a scalar function `f` to `self` by the chain rule, given
    /// `f0 = f(v)`, `f1 = f'(v)` and `f2 = f''(v)` at `v = self.value()`.
    fn lift(self, f0: f64, f1: f64, f2: f64) -> Self;

    /// Applies a two-argument function `f(u, w)` (with `u = self`, `w = other`) by the
    /// chain rule, given its value `f0`, gradient `grad = [f_u, f_w]` and Hessian
    /// entries `hess = [f_uu, f_uw, f_ww]`.
    fn lift2(self, other: Self, f0: f64, grad: [f64; 2], hess: [f64; 3]) -> Self;

    /// `f(self)` by the chain rule, with `f0 = f(v)` at `v = self.value()` and
    /// `(f'(v), f''(v)) = derivatives(v, f0)`, which a type without derivatives (`ORDER` 0)
    /// does not evaluate.
    #[inline]
    fn apply(self, f: impl FnOnce(f64) -> f64, derivatives: impl FnOnce(f64, f64) -> (f64, f64)) -> Self {
        let v = self.value();
        let f0 = f(v);
        if Self::ORDER == 0 {
            return Self::constant(f0);
        }
        let (f1, f2) = derivatives(v, f0);
        self.lift(f0, f1, f2)
    }

    /// Sine.
    fn sin(self) -> Self {
        self.apply(f64::sin, |v, s| (v.cos(), -s))
    }

    /// Cosine.
    fn cos(self) -> Self {
        self.apply(f64::cos, |v, c| (-v.sin(), -c))
    }

    /// Tangent.
    fn tan(self) -> Self {
        self.apply(f64::tan, |_, t| {
            let sec2 = 1.0 + t * t;
            (sec2, 2.0 * t * sec2)
        })
    }

    /// Arc sine (NaN outside `[-1, 1]`; infinite derivative at `±1`).
    fn asin(self) -> Self {
        self.apply(f64::asin, |v, _| {
            let f1 = 1.0 / (1.0 - v * v).sqrt();
            (f1, v * f1 * f1 * f1)
        })
    }

    /// Arc cosine (NaN outside `[-1, 1]`; infinite derivative at `±1`).
    fn acos(self) -> Self {
        self.apply(f64::acos, |v, _| {
            let f1 = 1.0 / (1.0 - v * v).sqrt();
            (-f1, -v * f1 * f1 * f1)
        })
    }

    /// Arc tangent.
    fn atan(self) -> Self {
        self.apply(f64::atan, |v, _| {
            let f1 = 1.0 / (1.0 + v * v);
            (f1, -2.0 * v * f1 * f1)
        })
    }

    /// Hyperbolic sine.
    fn sinh(self) -> Self {
        self.apply(f64::sinh, |v, s| (v.cosh(), s))
    }

    /// Hyperbolic cosine.
    fn cosh(self) -> Self {
        self.apply(f64::cosh, |v, c| (v.sinh(), c))
    }

    /// Hyperbolic tangent.
    fn tanh(self) -> Self {
        self.apply(f64::tanh, |_, t| {
            let sech2 = 1.0 - t * t;
            (sech2, -2.0 * t * sech2)
        })
    }

    /// Exponential `e^self`.
    fn exp(self) -> Self {
        self.apply(f64::exp, |_, x| (x, x))
    }

    /// Natural logarithm (NaN for negative values, `-inf` at 0).
    fn ln(self) -> Self {
        self.apply(f64::ln, |v, _| {
            let r = 1.0 / v;
            (r, -r * r)
        })
    }

    /// Square root (NaN for negative values, infinite derivative at 0).
    fn sqrt(self) -> Self {
        self.apply(f64::sqrt, |v, r| {
            let f1 = 0.5 / r;
            (f1, -0.5 * f1 / v)
        })
    }

    /// Absolute value. The derivative is taken as `sign(v)`, i.e. 0 at `v = 0`.
    fn abs(self) -> Self {
        self.apply(f64::abs, |v, _| (sign_of(v), 0.0))
    }

    /// Sign: `1`, `-1`, or `0` at zero (unlike [`f64::signum`]); derivative 0.
    fn sign(self) -> Self {
        self.apply(sign_of, |_, _| (0.0, 0.0))
    }

    /// Integer power `self^n`, exact at `self = 0` for `n >= 0` (e.g. `x^2` at 0 has
    /// value 0, first derivative 0 and second derivative 2).
    fn powi(self, n: i32) -> Self {
        self.apply(
            |v| v.powi(n),
            |v, _| {
                let nf = f64::from(n);
                // The factors n and n(n-1) vanish for n = 0 and n = 1; skip the power then so
                // that 0 * inf cannot produce NaN at v = 0.
                let f1 = if n == 0 { 0.0 } else { nf * v.powi(n.saturating_sub(1)) };
                let f2 = if n == 0 || n == 1 { 0.0 } else { nf * (nf - 1.0) * v.powi(n.saturating_sub(2)) };
                (f1, f2)
            },
        )
    }

    /// Power with a constant real exponent `self^c` (NaN for negative `self` unless
    /// `c` is an integer; exact at 0 for `c = 0` and `c = 1`).
    fn powf(self, c: f64) -> Self {
        self.apply(
            |v| v.powf(c),
            |v, _| {
                let f1 = if c == 0.0 { 0.0 } else { c * v.powf(c - 1.0) };
                let f2 = if c == 0.0 || c == 1.0 { 0.0 } else { c * (c - 1.0) * v.powf(c - 2.0) };
                (f1, f2)
            },
        )
    }

    /// General power `self^b = exp(b ln self)`, for a non-constant exponent.
    /// Defined for `self > 0` (and value-only at `self = 0`).
    fn pow(self, b: Self) -> Self {
        (b * self.ln()).exp()
    }

    /// Four-quadrant arc tangent of `self / x` (`self` is `y`).
    fn atan2(self, x: Self) -> Self {
        let (yv, xv) = (self.value(), x.value());
        let f0 = yv.atan2(xv);
        if Self::ORDER == 0 {
            return Self::constant(f0);
        }
        let r2 = xv * xv + yv * yv;
        let r4 = r2 * r2;
        let gy = xv / r2;
        let gx = -yv / r2;
        let hyy = -2.0 * xv * yv / r4;
        let hxy = (yv * yv - xv * xv) / r4;
        let hxx = 2.0 * xv * yv / r4;
        self.lift2(x, f0, [gy, gx], [hyy, hxy, hxx])
    }

    /// `sqrt(self^2 + y^2)` without overflow or underflow on the way ([`f64::hypot`]). At the
    /// origin, where it has no derivative, the derivatives are taken as 0 (as `abs'(0)`).
    fn hypot(self, y: Self) -> Self {
        let (a, b) = (self.value(), y.value());
        let r = a.hypot(b);
        if Self::ORDER == 0 || r == 0.0 {
            return self.lift2(y, r, [0.0; 2], [0.0; 3]);
        }
        let (ua, ub) = (a / r, b / r);
        self.lift2(y, r, [ua, ub], [ub * ub / r, -ua * ub / r, ua * ua / r])
    }

    /// The smaller argument (with its derivatives); `self` on ties. A NaN argument is
    /// ignored, like [`f64::min`].
    fn min(self, other: Self) -> Self {
        let (a, b) = (self.value(), other.value());
        if a <= b || b.is_nan() {
            self
        } else {
            other
        }
    }

    /// The larger argument (with its derivatives); `self` on ties. A NaN argument is
    /// ignored, like [`f64::max`].
    fn max(self, other: Self) -> Self {
        let (a, b) = (self.value(), other.value());
        if a >= b || b.is_nan() {
            self
        } else {
            other
        }
    }
}

impl Scalar for f64 {
    const ORDER: u8 = 0;

    #[inline]
    fn constant(v: f64) -> Self {
        v
    }

    #[inline]
    fn value(self) -> f64 {
        self
    }

    #[inline]
    fn lift(self, f0: f64, _f1: f64, _f2: f64) -> Self {
        f0
    }

    #[inline]
    fn lift2(self, _other: Self, f0: f64, _grad: [f64; 2], _hess: [f64; 3]) -> Self {
        f0
    }
}

/// A dual number `v + d ε` with `ε² = 0`: a value and one directional derivative.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Dual {
    /// Value.
    pub v: f64,
    /// Derivative along the seeded direction.
    pub d: f64,
}

impl Dual {
    /// A dual number with value `v` and derivative part `d`.
    #[inline]
    pub const fn new(v: f64, d: f64) -> Self {
        Dual { v, d }
    }

    /// The independent variable at `v` (derivative part 1).
    #[inline]
    pub const fn variable(v: f64) -> Self {
        Dual { v, d: 1.0 }
    }
}

impl Add for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, o: Dual) -> Dual {
        Dual::new(self.v + o.v, self.d + o.d)
    }
}

impl Sub for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, o: Dual) -> Dual {
        Dual::new(self.v - o.v, self.d - o.d)
    }
}

impl Mul for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, o: Dual) -> Dual {
        Dual::new(self.v * o.v, self.v * o.d + self.d * o.v)
    }
}

impl Div for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, o: Dual) -> Dual {
        let q = self.v / o.v;
        Dual::new(q, (self.d - q * o.d) / o.v)
    }
}

impl Neg for Dual {
    type Output = Dual;
    #[inline]
    fn neg(self) -> Dual {
        Dual::new(-self.v, -self.d)
    }
}

impl Scalar for Dual {
    const ORDER: u8 = 1;

    #[inline]
    fn constant(v: f64) -> Self {
        Dual::new(v, 0.0)
    }

    #[inline]
    fn value(self) -> f64 {
        self.v
    }

    #[inline]
    fn lift(self, f0: f64, f1: f64, _f2: f64) -> Self {
        Dual::new(f0, scale(f1, self.d))
    }

    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], _hess: [f64; 3]) -> Self {
        Dual::new(f0, scale(g[0], self.d) + scale(g[1], o.d))
    }
}

/// A hyper-dual number `v + e1 ε1 + e2 ε2 + e12 ε1ε2` with `ε1² = ε2² = 0`.
///
/// Seeding every input `x_i` as `(x_i, a_i, b_i, 0)` and evaluating `f` gives
/// `(f, ∇f·a, ∇f·b, aᵀ H b)`, all exact to rounding.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HyperDual {
    /// Value.
    pub v: f64,
    /// First derivative along the first seed direction `a`.
    pub e1: f64,
    /// First derivative along the second seed direction `b`.
    pub e2: f64,
    /// Mixed second derivative `aᵀ H b`.
    pub e12: f64,
}

impl HyperDual {
    /// A hyper-dual number from its four components.
    #[inline]
    pub const fn new(v: f64, e1: f64, e2: f64, e12: f64) -> Self {
        HyperDual { v, e1, e2, e12 }
    }

    /// An input seeded with directions `a` and `b`: `(v, a, b, 0)`.
    #[inline]
    pub const fn seed(v: f64, a: f64, b: f64) -> Self {
        HyperDual::new(v, a, b, 0.0)
    }

    /// The independent variable of a one-variable function, `(v, 1, 1, 0)`: the result
    /// of an evaluation then holds `(f, f', f', f'')`.
    #[inline]
    pub const fn variable(v: f64) -> Self {
        HyperDual::new(v, 1.0, 1.0, 0.0)
    }
}

impl Add for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn add(self, o: HyperDual) -> HyperDual {
        HyperDual::new(self.v + o.v, self.e1 + o.e1, self.e2 + o.e2, self.e12 + o.e12)
    }
}

impl Sub for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn sub(self, o: HyperDual) -> HyperDual {
        HyperDual::new(self.v - o.v, self.e1 - o.e1, self.e2 - o.e2, self.e12 - o.e12)
    }
}

impl Mul for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn mul(self, o: HyperDual) -> HyperDual {
        HyperDual::new(
            self.v * o.v,
            self.v * o.e1 + self.e1 * o.v,
            self.v * o.e2 + self.e2 * o.v,
            self.v * o.e12 + self.e1 * o.e2 + self.e2 * o.e1 + self.e12 * o.v,
        )
    }
}

impl Div for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn div(self, o: HyperDual) -> HyperDual {
        // Solve self = q * o for q component by component.
        let v = self.v / o.v;
        let e1 = (self.e1 - v * o.e1) / o.v;
        let e2 = (self.e2 - v * o.e2) / o.v;
        let e12 = (self.e12 - v * o.e12 - e1 * o.e2 - e2 * o.e1) / o.v;
        HyperDual::new(v, e1, e2, e12)
    }
}

impl Neg for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn neg(self) -> HyperDual {
        HyperDual::new(-self.v, -self.e1, -self.e2, -self.e12)
    }
}

impl Scalar for HyperDual {
    const ORDER: u8 = 2;

    #[inline]
    fn constant(v: f64) -> Self {
        HyperDual::new(v, 0.0, 0.0, 0.0)
    }

    #[inline]
    fn value(self) -> f64 {
        self.v
    }

    #[inline]
    fn lift(self, f0: f64, f1: f64, f2: f64) -> Self {
        HyperDual::new(f0, scale(f1, self.e1), scale(f1, self.e2), scale(f1, self.e12) + scale(f2, self.e1 * self.e2))
    }

    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], h: [f64; 3]) -> Self {
        let (u, w) = (self, o);
        HyperDual::new(
            f0,
            scale(g[0], u.e1) + scale(g[1], w.e1),
            scale(g[0], u.e2) + scale(g[1], w.e2),
            scale(g[0], u.e12)
                + scale(g[1], w.e12)
                + scale(h[0], u.e1 * u.e2)
                + scale(h[1], u.e1 * w.e2 + w.e1 * u.e2)
                + scale(h[2], w.e1 * w.e2),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    #[test]
    fn dual_arithmetic_rules() {
        let x = Dual::new(3.0, 1.0);
        let y = Dual::new(2.0, -0.5);
        assert_eq!(x + y, Dual::new(5.0, 0.5));
        assert_eq!(x - y, Dual::new(1.0, 1.5));
        assert_eq!(x * y, Dual::new(6.0, 3.0 * -0.5 + 2.0));
        // d(x/y) = (x' y - x y') / y^2 = (2 + 1.5) / 4
        let q = x / y;
        assert_eq!(q.v, 1.5);
        assert!(close(q.d, 3.5 / 4.0, 1e-15));
        assert_eq!(-x, Dual::new(-3.0, -1.0));
        assert_eq!(<Dual as Scalar>::constant(4.0), Dual::new(4.0, 0.0));
        assert_eq!(Dual::variable(4.0), Dual::new(4.0, 1.0));
    }

    #[test]
    fn hyperdual_product_and_quotient_second_derivatives() {
        // f(t) = t^2 * (t + 1) -> f' = 3t^2 + 2t, f'' = 6t + 2
        let t = HyperDual::variable(1.5);
        let f = t * t * (t + HyperDual::constant(1.0));
        assert_eq!(f.v, 1.5 * 1.5 * 2.5);
        assert!(close(f.e1, 3.0 * 2.25 + 3.0, 1e-15));
        assert_eq!(f.e1, f.e2);
        assert!(close(f.e12, 6.0 * 1.5 + 2.0, 1e-15));
        // g(t) = 1 / t -> g' = -1/t^2, g'' = 2/t^3
        let g = HyperDual::constant(1.0) / t;
        assert!(close(g.v, 1.0 / 1.5, 1e-15));
        assert!(close(g.e1, -1.0 / 2.25, 1e-15));
        assert!(close(g.e12, 2.0 / 3.375, 1e-15));
        // h(t) = t / (t^2 + 1) -> h' = (1 - t^2)/(1 + t^2)^2, h'' = 2t(t^2 - 3)/(1 + t^2)^3
        let h = t / (t * t + HyperDual::constant(1.0));
        let d = 1.0 + 2.25;
        assert!(close(h.e1, (1.0 - 2.25) / (d * d), 1e-14));
        assert!(close(h.e12, 2.0 * 1.5 * (2.25 - 3.0) / (d * d * d), 1e-14));
    }

    #[test]
    fn hyperdual_mixed_partial_with_two_seeds() {
        // f(x, y) = x * y^2: f_xy = 2y; seeding x with a = 1 and y with b = 1 in the
        // other slot gives e12 = aᵀ H b = f_xy.
        let x = HyperDual::seed(2.0, 1.0, 0.0);
        let y = HyperDual::seed(3.0, 0.0, 1.0);
        let f = x * y * y;
        assert_eq!(f.v, 18.0);
        assert_eq!(f.e1, 9.0); // f_x = y^2
        assert_eq!(f.e2, 12.0); // f_y = 2xy
        assert_eq!(f.e12, 6.0); // f_xy = 2y
    }

    #[test]
    fn integer_powers_are_exact_at_zero() {
        let z = HyperDual::variable(0.0);
        assert_eq!(z.powi(0), HyperDual::new(1.0, 0.0, 0.0, 0.0));
        assert_eq!(z.powi(1), HyperDual::new(0.0, 1.0, 1.0, 0.0));
        assert_eq!(z.powi(2), HyperDual::new(0.0, 0.0, 0.0, 2.0));
        assert_eq!(z.powi(3), HyperDual::new(0.0, 0.0, 0.0, 0.0));
        assert_eq!(z.powf(2.0), HyperDual::new(0.0, 0.0, 0.0, 2.0));
        assert_eq!(z.powf(1.0), HyperDual::new(0.0, 1.0, 1.0, 0.0));
        // extreme exponents do not overflow the exponent arithmetic
        let one = HyperDual::variable(1.0);
        assert_eq!(one.powi(i32::MIN).v, 1.0);
    }

    #[test]
    fn zero_seed_masks_singular_partials() {
        // sqrt has an infinite derivative at 0; an input that does not move gives 0.
        let fixed = Dual::new(0.0, 0.0);
        assert_eq!(fixed.sqrt(), Dual::new(0.0, 0.0));
        let fixed = HyperDual::new(0.0, 0.0, 0.0, 0.0);
        assert_eq!(fixed.sqrt(), HyperDual::new(0.0, 0.0, 0.0, 0.0));
        // ... while a moving input reports the genuine infinity.
        assert_eq!(Dual::variable(0.0).sqrt().d, f64::INFINITY);
    }

    #[test]
    fn sign_abs_min_max() {
        assert_eq!(Scalar::sign(0.0_f64), 0.0);
        assert_eq!(Scalar::sign(-0.0_f64), 0.0);
        assert_eq!(Scalar::sign(-2.0_f64), -1.0);
        assert!(Scalar::sign(f64::NAN).is_nan());
        assert_eq!(Dual::variable(-2.0).abs(), Dual::new(2.0, -1.0));
        assert_eq!(Dual::variable(0.0).abs(), Dual::new(0.0, 0.0));
        let a = Dual::new(1.0, 5.0);
        let b = Dual::new(2.0, 7.0);
        assert_eq!(a.min(b), a);
        assert_eq!(a.max(b), b);
        assert_eq!(Scalar::min(1.0, f64::NAN), 1.0);
        assert_eq!(Scalar::max(f64::NAN, 1.0), 1.0);
    }
}
