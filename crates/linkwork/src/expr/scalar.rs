//! Number types for forward-mode automatic differentiation.
//!
//! An [`Expr`](super::Expr) is evaluated generically over a [`Scalar`]. Six
//! implementations are provided:
//!
//! * [`f64`]: the plain value;
//! * [`Dual`]: value plus one directional derivative (`v + d ε`, `ε² = 0`);
//! * [`HyperDual`]: value, two first directional derivatives and the mixed second
//!   derivative (`v + e1 ε1 + e2 ε2 + e12 ε1ε2`, `ε1² = ε2² = 0`);
//! * [`Tri`]: value, three first directional derivatives and every mixed part of them
//!   (`e12`, `e13`, `e23`, `e123`), for design sensitivities: seeded with `ε1`, `ε2` along time
//!   and `ε3` along a parameter, it gives the parameter derivative of a function, of its time
//!   rate and of its second time derivative in one evaluation;
//! * [`TimeTri`]: `Tri` with its first two directions one (time), its six distinct parts alone;
//! * [`Quad`]: four directions and every mixed part of them (16 parts), the [`Nestable`] step
//!   above [`Tri`]: the derivative of a function with respect to its own argument at an argument
//!   that carries `Tri`'s derivatives (a cam's surface normal at a contact point that moves).
//!
//! Seeding the inputs of a function `f` with `x = (x0, a, b, 0)` gives a result whose
//! `e12` component is `aᵀ H b` (`H` the Hessian of `f` at `x0`); with `a = b` this is
//! the second directional derivative, so a time function seeded with `(t, 1, 1, 0)`
//! yields `(f, f', f'')` exactly.
//!
//! Every elementary function is implemented once, as a default method of [`Scalar`],
//! from its value and first four derivatives ([`Scalar::lift_fourth`] and
//! [`Scalar::lift2_fourth`]): for a nilpotent increment `d` (`d⁵ = 0` in every type here),
//! `f(v + d) = f + f' d + f'' d²/2 + f''' d³/6 + f'''' d⁴/24` exactly. The third derivatives are
//! computed only for a type of [`ORDER`](Scalar::ORDER) 3 or more, the fourth only for
//! [`Quad`] (`ORDER` 4); the others pass 0, which they ignore, so `f64`, `Dual` and `HyperDual`
//! do exactly the work they did before `Tri` existed, and `Tri` the work it did before `Quad`. The value
//! component is always computed with exactly the same floating-point operations as the plain
//! `f64` evaluation, so every type's evaluation returns bit-identical values.
//!
//! The two-argument functions (`atan2`, `hypot`) give their third and fourth partial derivatives
//! in closed form; `pow` with a moving exponent is `exp(b ln a)`, exact through the one-argument rules.

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

/// `asin'''(v)` from `f1 = asin'(v) = 1 / sqrt(1 - v²)`: `f1³ (1 + 3 v² f1²)`; odd in `f1`, so with
/// `f1 = acos'(v) = -asin'(v)` it is `acos'''(v)`.
fn asin_third(v: f64, _f0: f64, f1: f64, _f2: f64) -> f64 {
    f1 * f1 * f1 * (1.0 + 3.0 * v * v * f1 * f1)
}

/// `asin''''(v)` from `f1 = asin'(v)`: the derivative of `f1³ + 3 v² f1⁵` with `f1' = v f1³`,
/// `v f1⁵ (9 + 15 v² f1²)`; odd in `f1`, so with `f1 = acos'(v)` it is `acos''''(v)`.
fn asin_fourth(v: f64, [_, f1, _, _]: [f64; 4]) -> f64 {
    v * f1.powi(5) * (9.0 + 15.0 * v * v * f1 * f1)
}

/// A number type that expressions can be evaluated over.
///
/// Implementors supply the arithmetic operators, the comparison of every part (`==`: equal
/// values and derivative parts), [`constant`](Scalar::constant),
/// [`value`](Scalar::value) and the two chain-rule primitives
/// [`lift`](Scalar::lift) / [`lift2`](Scalar::lift2); every elementary function has a
/// default implementation in terms of those.
pub trait Scalar:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Highest derivative order carried by the type (0 for `f64`, 1 for [`Dual`],
    /// 2 for [`HyperDual`], 3 for [`Tri`], 4 for [`Quad`]). The default methods skip computing derivative
    /// factors that the type would discard.
    const ORDER: u8;

    /// A constant (all derivative parts zero).
    fn constant(v: f64) -> Self;

    /// The value (real) part.
    fn value(self) -> f64;

    /// Applies a scalar function `f` to `self` by the chain rule, given
    /// `f0 = f(v)`, `f1 = f'(v)`, `f2 = f''(v)` and `f3 = f'''(v)` at `v = self.value()`
    /// (callers pass `f3 = 0` to a type of [`ORDER`](Scalar::ORDER) below 3, which ignores it).
    fn lift(self, f0: f64, f1: f64, f2: f64, f3: f64) -> Self;

    /// Applies a two-argument function `f(u, w)` (with `u = self`, `w = other`) by the
    /// chain rule, given its value `f0`, gradient `grad = [f_u, f_w]`, Hessian
    /// entries `hess = [f_uu, f_uw, f_ww]` and third partials `third = [f_uuu, f_uuw, f_uww,
    /// f_www]` (zeros for a type of [`ORDER`](Scalar::ORDER) below 3, which ignores them).
    fn lift2(self, other: Self, f0: f64, grad: [f64; 2], hess: [f64; 3], third: [f64; 4]) -> Self;

    /// [`Scalar::lift`] with the fourth derivative `f[4] = f''''(v)` too (`f = [f0, f1, f2, f3,
    /// f4]`), which only a type of [`ORDER`](Scalar::ORDER) 4 reads: the others take `lift`.
    #[inline]
    fn lift_fourth(self, f: [f64; 5]) -> Self {
        self.lift(f[0], f[1], f[2], f[3])
    }

    /// [`Scalar::lift2`] with the fourth partials `fourth = [f_uuuu, f_uuuw, f_uuww, f_uwww,
    /// f_wwww]` too, which only a type of [`ORDER`](Scalar::ORDER) 4 reads: the others take
    /// `lift2`.
    #[inline]
    fn lift2_fourth(
        self,
        other: Self,
        f0: f64,
        grad: [f64; 2],
        hess: [f64; 3],
        third: [f64; 4],
        fourth: [f64; 5],
    ) -> Self {
        let _ = fourth;
        self.lift2(other, f0, grad, hess, third)
    }

    /// `f(self)` by the chain rule, with `f0 = f(v)` at `v = self.value()`,
    /// `(f'(v), f''(v)) = derivatives(v, f0)`, which a type without derivatives (`ORDER` 0)
    /// does not evaluate, `f'''(v) = third(v, f0, f'(v), f''(v))`, which only a type of
    /// `ORDER` 3 or more evaluates, and `f''''(v) = fourth(v, [f0, f', f'', f'''])`, which only
    /// a type of `ORDER` 4 evaluates.
    #[inline]
    fn apply(
        self,
        f: impl FnOnce(f64) -> f64,
        derivatives: impl FnOnce(f64, f64) -> (f64, f64),
        third: impl FnOnce(f64, f64, f64, f64) -> f64,
        fourth: impl FnOnce(f64, [f64; 4]) -> f64,
    ) -> Self {
        let v = self.value();
        let f0 = f(v);
        if Self::ORDER == 0 {
            return Self::constant(f0);
        }
        let (f1, f2) = derivatives(v, f0);
        let f3 = if Self::ORDER >= 3 { third(v, f0, f1, f2) } else { 0.0 };
        if Self::ORDER >= 4 {
            return self.lift_fourth([f0, f1, f2, f3, fourth(v, [f0, f1, f2, f3])]);
        }
        self.lift(f0, f1, f2, f3)
    }

    /// Sine.
    fn sin(self) -> Self {
        self.apply(f64::sin, |v, s| (v.cos(), -s), |_, _, c, _| -c, |_, f| f[0])
    }

    /// Cosine.
    fn cos(self) -> Self {
        self.apply(f64::cos, |v, c| (-v.sin(), -c), |_, _, minus_sin, _| -minus_sin, |_, f| f[0])
    }

    /// Tangent.
    fn tan(self) -> Self {
        self.apply(
            f64::tan,
            |_, t| {
                let sec2 = 1.0 + t * t;
                (sec2, 2.0 * t * sec2)
            },
            // (2 t sec²)' = 2 sec⁴ + 4 t² sec²
            |_, t, sec2, _| 2.0 * sec2 * (sec2 + 2.0 * t * t),
            // (2 sec⁴ + 4 t² sec²)' = 16 t sec⁴ + 8 t³ sec²
            |_, [t, sec2, _, _]| 8.0 * t * sec2 * (2.0 * sec2 + t * t),
        )
    }

    /// Arc sine (NaN outside `[-1, 1]`; infinite derivative at `±1`).
    fn asin(self) -> Self {
        self.apply(
            f64::asin,
            |v, _| {
                let f1 = 1.0 / (1.0 - v * v).sqrt();
                (f1, v * f1 * f1 * f1)
            },
            asin_third,
            asin_fourth,
        )
    }

    /// Arc cosine (NaN outside `[-1, 1]`; infinite derivative at `±1`).
    fn acos(self) -> Self {
        self.apply(
            f64::acos,
            |v, _| {
                let f1 = 1.0 / (1.0 - v * v).sqrt();
                (-f1, -v * f1 * f1 * f1)
            },
            // acos = pi/2 - asin, and asin_third and asin_fourth are odd in f1.
            asin_third,
            asin_fourth,
        )
    }

    /// Arc tangent.
    fn atan(self) -> Self {
        self.apply(
            f64::atan,
            |v, _| {
                let f1 = 1.0 / (1.0 + v * v);
                (f1, -2.0 * v * f1 * f1)
            },
            // (-2 v f1²)' = -2 f1² - 4 v f1 f1' = f1² (8 v² f1 - 2)
            |v, _, f1, _| f1 * f1 * (8.0 * v * v * f1 - 2.0),
            // (8 v² f1³ - 2 f1²)' with f1' = -2 v f1²: 24 v f1³ - 48 v³ f1⁴
            |v, [_, f1, _, _]| 24.0 * v * f1 * f1 * f1 * (1.0 - 2.0 * v * v * f1),
        )
    }

    /// Hyperbolic sine.
    fn sinh(self) -> Self {
        self.apply(f64::sinh, |v, s| (v.cosh(), s), |_, _, c, _| c, |_, f| f[0])
    }

    /// Hyperbolic cosine.
    fn cosh(self) -> Self {
        self.apply(f64::cosh, |v, c| (v.sinh(), c), |_, _, s, _| s, |_, f| f[0])
    }

    /// Hyperbolic tangent.
    fn tanh(self) -> Self {
        self.apply(
            f64::tanh,
            |_, t| {
                let sech2 = 1.0 - t * t;
                (sech2, -2.0 * t * sech2)
            },
            // (-2 t sech²)' = -2 sech⁴ + 4 t² sech²
            |_, t, sech2, _| sech2 * (4.0 * t * t - 2.0 * sech2),
            // (4 t² sech² - 2 sech⁴)' = 16 t sech⁴ - 8 t³ sech²
            |_, [t, sech2, _, _]| 8.0 * t * sech2 * (2.0 * sech2 - t * t),
        )
    }

    /// Exponential `e^self`.
    fn exp(self) -> Self {
        self.apply(f64::exp, |_, x| (x, x), |_, x, _, _| x, |_, f| f[0])
    }

    /// Natural logarithm (NaN for negative values, `-inf` at 0).
    fn ln(self) -> Self {
        self.apply(
            f64::ln,
            |v, _| {
                let r = 1.0 / v;
                (r, -r * r)
            },
            |_, _, r, _| 2.0 * r * r * r,
            |_, [_, r, _, _]| -6.0 * r * r * r * r,
        )
    }

    /// Square root (NaN for negative values, infinite derivative at 0).
    fn sqrt(self) -> Self {
        self.apply(
            f64::sqrt,
            |v, r| {
                let f1 = 0.5 / r;
                (f1, -0.5 * f1 / v)
            },
            // (-v^(-3/2) / 4)' = (3/8) v^(-5/2) = -1.5 f'' / v
            |v, _, _, f2| -1.5 * f2 / v,
            // ((3/8) v^(-5/2))' = -2.5 f''' / v
            |v, [_, _, _, f3]| -2.5 * f3 / v,
        )
    }

    /// Absolute value. The derivative is taken as `sign(v)`, i.e. 0 at `v = 0`.
    fn abs(self) -> Self {
        self.apply(f64::abs, |v, _| (sign_of(v), 0.0), |_, _, _, _| 0.0, |_, _| 0.0)
    }

    /// Sign: `1`, `-1`, or `0` at zero (unlike [`f64::signum`]); derivative 0.
    fn sign(self) -> Self {
        self.apply(sign_of, |_, _| (0.0, 0.0), |_, _, _, _| 0.0, |_, _| 0.0)
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
            |v, _, _, _| {
                let nf = f64::from(n);
                if (0..=2).contains(&n) {
                    0.0
                } else {
                    nf * (nf - 1.0) * (nf - 2.0) * v.powi(n.saturating_sub(3))
                }
            },
            |v, _| {
                let nf = f64::from(n);
                if (0..=3).contains(&n) {
                    0.0
                } else {
                    nf * (nf - 1.0) * (nf - 2.0) * (nf - 3.0) * v.powi(n.saturating_sub(4))
                }
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
            |v, _, _, _| {
                if c == 0.0 || c == 1.0 || c == 2.0 {
                    0.0
                } else {
                    c * (c - 1.0) * (c - 2.0) * v.powf(c - 3.0)
                }
            },
            |v, _| {
                if c == 0.0 || c == 1.0 || c == 2.0 || c == 3.0 {
                    0.0
                } else {
                    c * (c - 1.0) * (c - 2.0) * (c - 3.0) * v.powf(c - 4.0)
                }
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
        // atan2 = Im log(x + i y), so its third partials are Im(i^k 2 / z³) with k the number of
        // y's: with p + i q = conj(z)³, f_yyy = -2p, f_yyx = -2q, f_yxx = 2p, f_xxx = 2q, over r⁶.
        let third = if Self::ORDER >= 3 {
            let r6 = r4 * r2;
            let p = 2.0 * (xv * xv * xv - 3.0 * xv * yv * yv) / r6;
            let q = 2.0 * (yv * yv * yv - 3.0 * xv * xv * yv) / r6;
            [-p, -q, p, q]
        } else {
            [0.0; 4]
        };
        // The fourth partials are Im(i^k (-6) / z⁴): with P + i Q = -6 conj(z)⁴ / r⁸, f_yyyy = Q,
        // f_yyyx = -P, f_yyxx = -Q, f_yxxx = P, f_xxxx = Q.
        let fourth = if Self::ORDER >= 4 {
            let r8 = r4 * r4;
            let (x2, y2) = (xv * xv, yv * yv);
            let p = -6.0 * ((x2 - y2) * (x2 - y2) - 4.0 * x2 * y2) / r8;
            let q = 24.0 * xv * yv * (x2 - y2) / r8;
            [q, -p, -q, p, q]
        } else {
            [0.0; 5]
        };
        self.lift2_fourth(x, f0, [gy, gx], [hyy, hxy, hxx], third, fourth)
    }

    /// `sqrt(self^2 + y^2)` without overflow or underflow on the way ([`f64::hypot`]). At the
    /// origin, where it has no derivative, the derivatives are taken as 0 (as `abs'(0)`).
    fn hypot(self, y: Self) -> Self {
        let (a, b) = (self.value(), y.value());
        let r = a.hypot(b);
        if Self::ORDER == 0 || r == 0.0 {
            return self.lift2_fourth(y, r, [0.0; 2], [0.0; 3], [0.0; 4], [0.0; 5]);
        }
        let (ua, ub) = (a / r, b / r);
        // The derivatives of the Hessian (b², -ab, a²) / r³ (r² = a² + b²).
        let third = if Self::ORDER >= 3 {
            let r2 = r * r;
            [
                -3.0 * ua * ub * ub / r2,
                ub * (2.0 * ua * ua - ub * ub) / r2,
                ua * (2.0 * ub * ub - ua * ua) / r2,
                -3.0 * ua * ua * ub / r2,
            ]
        } else {
            [0.0; 4]
        };
        // And of those: (12 ua² ub² - 3 ub⁴, 9 ua ub³ - 6 ua³ ub, 2 ua⁴ - 11 ua² ub² + 2 ub⁴, ...)
        // / r³, the last two the first two with a and b exchanged.
        let fourth = if Self::ORDER >= 4 {
            let (a2, b2, r3) = (ua * ua, ub * ub, r * r * r);
            [
                3.0 * b2 * (4.0 * a2 - b2) / r3,
                3.0 * ua * ub * (3.0 * b2 - 2.0 * a2) / r3,
                (2.0 * a2 * a2 - 11.0 * a2 * b2 + 2.0 * b2 * b2) / r3,
                3.0 * ua * ub * (3.0 * a2 - 2.0 * b2) / r3,
                3.0 * a2 * (4.0 * b2 - a2) / r3,
            ]
        } else {
            [0.0; 5]
        };
        self.lift2_fourth(y, r, [ua, ub], [ub * ub / r, -ua * ub / r, ua * ua / r], third, fourth)
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
    fn lift(self, f0: f64, _f1: f64, _f2: f64, _f3: f64) -> Self {
        f0
    }

    #[inline]
    fn lift2(self, _other: Self, f0: f64, _grad: [f64; 2], _hess: [f64; 3], _third: [f64; 4]) -> Self {
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
    fn lift(self, f0: f64, f1: f64, _f2: f64, _f3: f64) -> Self {
        Dual::new(f0, scale(f1, self.d))
    }

    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], _hess: [f64; 3], _third: [f64; 4]) -> Self {
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
    fn lift(self, f0: f64, f1: f64, f2: f64, _f3: f64) -> Self {
        HyperDual::new(f0, scale(f1, self.e1), scale(f1, self.e2), scale(f1, self.e12) + scale(f2, self.e1 * self.e2))
    }

    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], h: [f64; 3], _third: [f64; 4]) -> Self {
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

/// `+` and `-` of a number type part by part, through its `zip`.
macro_rules! sum_part_by_part {
    ($T:ty) => {
        impl Add for $T {
            type Output = $T;
            #[inline]
            fn add(self, o: $T) -> $T {
                self.zip(o, |a, b| a + b)
            }
        }

        impl Sub for $T {
            type Output = $T;
            #[inline]
            fn sub(self, o: $T) -> $T {
                self.zip(o, |a, b| a - b)
            }
        }
    };
}

/// A number with three nilpotent directions and all their mixed parts:
/// `v + e1 ε1 + e2 ε2 + e3 ε3 + e12 ε1ε2 + e13 ε1ε3 + e23 ε2ε3 + e123 ε1ε2ε3`, with
/// `ε1² = ε2² = ε3² = 0`.
///
/// Seeding every input `x_i` with first-order parts `(a_i, b_i, c_i)` (and zero mixed parts)
/// and evaluating `f` gives `e1 = ∇f·a`, `e12 = D²f[a, b]`, `e123 = D³f[a, b, c]`, and so on
/// for every subset of the directions, all exact to rounding. Design sensitivities seed
/// `ε1 = ε2` along time and `ε3` along one parameter ([`Tri::trajectory`]): then `e3` is the
/// parameter derivative of `f`, `e13` that of its time rate and `e123` that of its second time
/// derivative (`e1` and `e12` are the time rate and the second time derivative themselves).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tri {
    /// Value.
    pub v: f64,
    /// First derivative along the first direction.
    pub e1: f64,
    /// First derivative along the second direction.
    pub e2: f64,
    /// First derivative along the third direction.
    pub e3: f64,
    /// Mixed second derivative along the first and second directions.
    pub e12: f64,
    /// Mixed second derivative along the first and third directions.
    pub e13: f64,
    /// Mixed second derivative along the second and third directions.
    pub e23: f64,
    /// Mixed third derivative along all three directions.
    pub e123: f64,
}

impl Tri {
    /// A number from its parts, grouped by order: the value, the first-order parts
    /// `[e1, e2, e3]`, the second-order parts `[e12, e13, e23]` and `e123`.
    #[inline]
    pub const fn new(v: f64, first: [f64; 3], second: [f64; 3], e123: f64) -> Self {
        let [e1, e2, e3] = first;
        let [e12, e13, e23] = second;
        Tri { v, e1, e2, e3, e12, e13, e23, e123 }
    }

    /// A quantity `x(t, p)` at a time and a parameter value, seeded with `ε1 = ε2` along time
    /// and `ε3` along the parameter: `time = [x, dx/dt, d²x/dt²]` and `parameter = [dx/dp,
    /// d²x/dt dp, d³x/dt² dp]`. Time itself is `trajectory([t, 1, 0], [0; 3])`; a parameter
    /// (or a number that depends on parameters only) with derivative `g` along the parameter
    /// is `trajectory([p, 0, 0], [g, 0, 0])`.
    #[inline]
    pub const fn trajectory(time: [f64; 3], parameter: [f64; 3]) -> Self {
        let [x, x_t, x_tt] = time;
        let [x_p, x_tp, x_ttp] = parameter;
        Tri::new(x, [x_t, x_t, x_p], [x_tt, x_tp, x_tp], x_ttp)
    }

    /// The parts in the order of [`Tri::new`], flattened: `[v, e1, e2, e3, e12, e13, e23, e123]`.
    #[inline]
    pub const fn parts(self) -> [f64; 8] {
        [self.v, self.e1, self.e2, self.e3, self.e12, self.e13, self.e23, self.e123]
    }

    /// Part by part, `f` of the two numbers' parts.
    #[inline]
    fn zip(self, o: Tri, f: impl Fn(f64, f64) -> f64) -> Tri {
        Tri {
            v: f(self.v, o.v),
            e1: f(self.e1, o.e1),
            e2: f(self.e2, o.e2),
            e3: f(self.e3, o.e3),
            e12: f(self.e12, o.e12),
            e13: f(self.e13, o.e13),
            e23: f(self.e23, o.e23),
            e123: f(self.e123, o.e123),
        }
    }
}

sum_part_by_part!(Tri);

impl Mul for Tri {
    type Output = Tri;
    #[inline]
    fn mul(self, o: Tri) -> Tri {
        let a = self;
        Tri {
            v: a.v * o.v,
            e1: a.v * o.e1 + a.e1 * o.v,
            e2: a.v * o.e2 + a.e2 * o.v,
            e3: a.v * o.e3 + a.e3 * o.v,
            e12: a.v * o.e12 + a.e1 * o.e2 + a.e2 * o.e1 + a.e12 * o.v,
            e13: a.v * o.e13 + a.e1 * o.e3 + a.e3 * o.e1 + a.e13 * o.v,
            e23: a.v * o.e23 + a.e2 * o.e3 + a.e3 * o.e2 + a.e23 * o.v,
            e123: a.v * o.e123
                + a.e1 * o.e23
                + a.e2 * o.e13
                + a.e3 * o.e12
                + a.e12 * o.e3
                + a.e13 * o.e2
                + a.e23 * o.e1
                + a.e123 * o.v,
        }
    }
}

impl Div for Tri {
    type Output = Tri;
    #[inline]
    fn div(self, o: Tri) -> Tri {
        // Solve self = q * o for q part by part, lowest order first.
        let a = self;
        let v = a.v / o.v;
        let e1 = (a.e1 - v * o.e1) / o.v;
        let e2 = (a.e2 - v * o.e2) / o.v;
        let e3 = (a.e3 - v * o.e3) / o.v;
        let e12 = (a.e12 - v * o.e12 - e1 * o.e2 - e2 * o.e1) / o.v;
        let e13 = (a.e13 - v * o.e13 - e1 * o.e3 - e3 * o.e1) / o.v;
        let e23 = (a.e23 - v * o.e23 - e2 * o.e3 - e3 * o.e2) / o.v;
        let e123 =
            (a.e123 - v * o.e123 - e1 * o.e23 - e2 * o.e13 - e3 * o.e12 - e12 * o.e3 - e13 * o.e2 - e23 * o.e1) / o.v;
        Tri { v, e1, e2, e3, e12, e13, e23, e123 }
    }
}

impl Neg for Tri {
    type Output = Tri;
    #[inline]
    fn neg(self) -> Tri {
        let a = self;
        Tri::new(-a.v, [-a.e1, -a.e2, -a.e3], [-a.e12, -a.e13, -a.e23], -a.e123)
    }
}

impl Scalar for Tri {
    const ORDER: u8 = 3;

    #[inline]
    fn constant(v: f64) -> Self {
        Tri::new(v, [0.0; 3], [0.0; 3], 0.0)
    }

    #[inline]
    fn value(self) -> f64 {
        self.v
    }

    /// `f(v + d) = f0 + f1 d + f2 d²/2 + f3 d³/6` with `d` the nilpotent part of `self`.
    #[inline]
    fn lift(self, f0: f64, f1: f64, f2: f64, f3: f64) -> Self {
        let x = self;
        Tri {
            v: f0,
            e1: scale(f1, x.e1),
            e2: scale(f1, x.e2),
            e3: scale(f1, x.e3),
            e12: scale(f1, x.e12) + scale(f2, x.e1 * x.e2),
            e13: scale(f1, x.e13) + scale(f2, x.e1 * x.e3),
            e23: scale(f1, x.e23) + scale(f2, x.e2 * x.e3),
            e123: scale(f1, x.e123)
                + scale(f2, x.e1 * x.e23 + x.e2 * x.e13 + x.e3 * x.e12)
                + scale(f3, x.e1 * x.e2 * x.e3),
        }
    }

    /// The Taylor expansion of `f(u, w)` to third order in the nilpotent parts of `u` and `w`:
    /// each part of the result is the gradient on that part of the inputs, plus the Hessian on
    /// each split of its directions into two, plus the third derivative on `(ε1, ε2, ε3)`. The
    /// sums run in [`HyperDual`]'s order, so that with `ε3` unseeded the parts `v, e1, e2, e12`
    /// are bit-identical to a `HyperDual` evaluation.
    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], h: [f64; 3], t: [f64; 4]) -> Self {
        let (u, w) = (self, o);
        // An input's part along some directions, as the pair (u's, w's).
        let [d1, d2, d3] = [[u.e1, w.e1], [u.e2, w.e2], [u.e3, w.e3]];
        let [d12, d13, d23] = [[u.e12, w.e12], [u.e13, w.e13], [u.e23, w.e23]];
        let grad = |a: [f64; 2]| scale(g[0], a[0]) + scale(g[1], a[1]);
        // `sum` plus the Hessian on the directions of `a` and `b`.
        let hess = |sum: f64, a: [f64; 2], b: [f64; 2]| {
            sum + scale(h[0], a[0] * b[0]) + scale(h[1], a[0] * b[1] + a[1] * b[0]) + scale(h[2], a[1] * b[1])
        };
        let (a, b, c) = (d1, d2, d3);
        let third = scale(t[0], a[0] * b[0] * c[0])
            + scale(t[1], a[0] * b[0] * c[1] + a[0] * b[1] * c[0] + a[1] * b[0] * c[0])
            + scale(t[2], a[0] * b[1] * c[1] + a[1] * b[0] * c[1] + a[1] * b[1] * c[0])
            + scale(t[3], a[1] * b[1] * c[1]);
        Tri {
            v: f0,
            e1: grad(d1),
            e2: grad(d2),
            e3: grad(d3),
            e12: hess(grad(d12), d1, d2),
            e13: hess(grad(d13), d1, d3),
            e23: hess(grad(d23), d2, d3),
            e123: hess(hess(hess(grad([u.e123, w.e123]), d1, d23), d2, d13), d3, d12) + third,
        }
    }
}

/// A [`Tri`] whose first two directions are one (`ε1 = ε2`, so `e1 = e2` and `e13 = e23`),
/// stored once: `v + e1 (ε1 + ε2) + e3 ε3 + e12 ε1ε2 + e13 (ε1ε3 + ε2ε3) + e123 ε1ε2ε3`.
///
/// Design sensitivities seed time along both of `Tri`'s first directions and a parameter along
/// the third ([`Tri::trajectory`]); products and functions keep that symmetry, so two of `Tri`'s
/// eight parts repeat two others. This type carries the six distinct ones and computes each
/// with the operations `Tri` uses for it, in the same order (a repeated product is the same
/// product, computed once): every part equals `Tri`'s bit for bit, for less work.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TimeTri {
    /// Value.
    pub v: f64,
    /// First derivative along the first (and second) direction.
    pub e1: f64,
    /// First derivative along the third direction.
    pub e3: f64,
    /// Mixed second derivative along the first and second directions.
    pub e12: f64,
    /// Mixed second derivative along the first (or second) and third directions.
    pub e13: f64,
    /// Mixed third derivative along all three directions.
    pub e123: f64,
}

impl TimeTri {
    /// [`Tri::trajectory`]: `time = [x, dx/dt, d²x/dt²]`, `parameter = [dx/dp, d²x/dt dp,
    /// d³x/dt² dp]`.
    #[inline]
    pub const fn trajectory(time: [f64; 3], parameter: [f64; 3]) -> Self {
        let [v, e1, e12] = time;
        let [e3, e13, e123] = parameter;
        TimeTri { v, e1, e3, e12, e13, e123 }
    }

    /// The same number as a [`Tri`].
    #[inline]
    pub const fn tri(self) -> Tri {
        Tri::new(self.v, [self.e1, self.e1, self.e3], [self.e12, self.e13, self.e13], self.e123)
    }

    /// Part by part, `f` of the two numbers' parts.
    #[inline]
    fn zip(self, o: TimeTri, f: impl Fn(f64, f64) -> f64) -> TimeTri {
        TimeTri {
            v: f(self.v, o.v),
            e1: f(self.e1, o.e1),
            e3: f(self.e3, o.e3),
            e12: f(self.e12, o.e12),
            e13: f(self.e13, o.e13),
            e123: f(self.e123, o.e123),
        }
    }
}

sum_part_by_part!(TimeTri);

/// [`Tri`]'s product with `e2 = e1`, `e23 = e13`.
impl Mul for TimeTri {
    type Output = TimeTri;
    #[inline]
    fn mul(self, o: TimeTri) -> TimeTri {
        let a = self;
        let (a1b1, a1b13, a13b1) = (a.e1 * o.e1, a.e1 * o.e13, a.e13 * o.e1);
        TimeTri {
            v: a.v * o.v,
            e1: a.v * o.e1 + a.e1 * o.v,
            e3: a.v * o.e3 + a.e3 * o.v,
            e12: a.v * o.e12 + a1b1 + a1b1 + a.e12 * o.v,
            e13: a.v * o.e13 + a.e1 * o.e3 + a.e3 * o.e1 + a.e13 * o.v,
            e123: a.v * o.e123 + a1b13 + a1b13 + a.e3 * o.e12 + a.e12 * o.e3 + a13b1 + a13b1 + a.e123 * o.v,
        }
    }
}

/// [`Tri`]'s quotient with `e2 = e1`, `e23 = e13`.
impl Div for TimeTri {
    type Output = TimeTri;
    #[inline]
    fn div(self, o: TimeTri) -> TimeTri {
        let a = self;
        let v = a.v / o.v;
        let e1 = (a.e1 - v * o.e1) / o.v;
        let e3 = (a.e3 - v * o.e3) / o.v;
        let e1b1 = e1 * o.e1;
        let e12 = (a.e12 - v * o.e12 - e1b1 - e1b1) / o.v;
        let e13 = (a.e13 - v * o.e13 - e1 * o.e3 - e3 * o.e1) / o.v;
        let (e1b13, e13b1) = (e1 * o.e13, e13 * o.e1);
        let e123 = (a.e123 - v * o.e123 - e1b13 - e1b13 - e3 * o.e12 - e12 * o.e3 - e13b1 - e13b1) / o.v;
        TimeTri { v, e1, e3, e12, e13, e123 }
    }
}

impl Neg for TimeTri {
    type Output = TimeTri;
    #[inline]
    fn neg(self) -> TimeTri {
        let a = self;
        TimeTri { v: -a.v, e1: -a.e1, e3: -a.e3, e12: -a.e12, e13: -a.e13, e123: -a.e123 }
    }
}

/// [`Tri`]'s rules with `e2 = e1`, `e23 = e13`, in its order.
impl Scalar for TimeTri {
    const ORDER: u8 = 3;

    #[inline]
    fn constant(v: f64) -> Self {
        TimeTri { v, ..TimeTri::default() }
    }

    #[inline]
    fn value(self) -> f64 {
        self.v
    }

    #[inline]
    fn lift(self, f0: f64, f1: f64, f2: f64, f3: f64) -> Self {
        let x = self;
        let x1x13 = x.e1 * x.e13;
        TimeTri {
            v: f0,
            e1: scale(f1, x.e1),
            e3: scale(f1, x.e3),
            e12: scale(f1, x.e12) + scale(f2, x.e1 * x.e1),
            e13: scale(f1, x.e13) + scale(f2, x.e1 * x.e3),
            e123: scale(f1, x.e123) + scale(f2, x1x13 + x1x13 + x.e3 * x.e12) + scale(f3, x.e1 * x.e1 * x.e3),
        }
    }

    #[inline]
    fn lift2(self, o: Self, f0: f64, g: [f64; 2], h: [f64; 3], t: [f64; 4]) -> Self {
        let (u, w) = (self, o);
        let [d1, d3] = [[u.e1, w.e1], [u.e3, w.e3]];
        let [d12, d13] = [[u.e12, w.e12], [u.e13, w.e13]];
        let grad = |a: [f64; 2]| scale(g[0], a[0]) + scale(g[1], a[1]);
        let hess = |sum: f64, a: [f64; 2], b: [f64; 2]| {
            sum + scale(h[0], a[0] * b[0]) + scale(h[1], a[0] * b[1] + a[1] * b[0]) + scale(h[2], a[1] * b[1])
        };
        let (a, c) = (d1, d3);
        let third = scale(t[0], a[0] * a[0] * c[0])
            + scale(t[1], a[0] * a[0] * c[1] + a[0] * a[1] * c[0] + a[1] * a[0] * c[0])
            + scale(t[2], a[0] * a[1] * c[1] + a[1] * a[0] * c[1] + a[1] * a[1] * c[0])
            + scale(t[3], a[1] * a[1] * c[1]);
        let e13 = hess(grad(d13), d1, d3);
        TimeTri {
            v: f0,
            e1: grad(d1),
            e3: grad(d3),
            e12: hess(grad(d12), d1, d1),
            e13,
            e123: hess(hess(hess(grad([u.e123, w.e123]), d1, d13), d1, d13), d3, d12) + third,
        }
    }
}

/// A number with four nilpotent directions and every mixed part of them: `parts[m]` is the part
/// along the directions whose bits `m` sets (bit `k` for `ε(k+1)`, `ε1² = ... = ε4² = 0`), so
/// `parts[0]` is the value, `parts[0b0011]` the mixed part along `ε1ε2` and `parts[0b1111]` the
/// fourth-order part along all four. Seeding every input `x_i` with first-order parts `(a_i, b_i,
/// c_i, d_i)` and evaluating `f` gives `parts[0b1111] = D⁴f[a, b, c, d]`, and so on for every
/// subset of the directions, all exact to rounding. It is the [`Nestable`] step above [`Tri`]
/// (`Tri`'s parts in the directions `ε1..ε3`, the new one `ε4`): the slope of a function at an
/// argument that carries `Tri`'s derivatives (a cam's surface normal at a moving contact point),
/// and nothing else; it is not nestable itself.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Quad {
    /// The parts, indexed by the set of their directions.
    pub parts: [f64; 16],
}

impl Quad {
    /// Part by part, `f` of the two numbers' parts.
    #[inline]
    fn zip(self, o: Quad, f: impl Fn(f64, f64) -> f64) -> Quad {
        Quad { parts: std::array::from_fn(|m| f(self.parts[m], o.parts[m])) }
    }

    /// `self` without its value: the nilpotent part.
    #[inline]
    fn increment(self) -> Quad {
        let mut d = self;
        d.parts[0] = 0.0;
        d
    }

    /// `constant + Σ_k scale(coefficients[k], terms[k])` part by part: a Taylor polynomial whose
    /// terms are products of increments, with [`scale`]'s rule (a part that does not move gives
    /// zero, whatever its coefficient).
    #[inline]
    fn taylor(constant: f64, terms: &[(f64, Quad)]) -> Quad {
        let mut out = Quad::constant(constant);
        for (m, o) in out.parts.iter_mut().enumerate().skip(1) {
            *o = terms.iter().map(|(c, t)| scale(*c, t.parts[m])).sum();
        }
        out
    }
}

/// The proper subsets `s` of `m` (`s ⊂ m`, `s ≠ m`), the empty one included.
#[inline]
fn proper_subsets(m: usize) -> impl Iterator<Item = usize> {
    // Counting down through the subsets of m: s - 1 masked by m is the next smaller one.
    std::iter::successors((m > 0).then(|| (m - 1) & m), move |&s| (s > 0).then(|| (s - 1) & m))
}

impl Add for Quad {
    type Output = Quad;
    #[inline]
    fn add(self, o: Quad) -> Quad {
        self.zip(o, |a, b| a + b)
    }
}

impl Sub for Quad {
    type Output = Quad;
    #[inline]
    fn sub(self, o: Quad) -> Quad {
        self.zip(o, |a, b| a - b)
    }
}

impl Mul for Quad {
    type Output = Quad;
    /// The part along `m` is the sum over the splits of `m` into two sets of the product of the
    /// factors' parts along them (Leibniz's rule).
    #[inline]
    fn mul(self, o: Quad) -> Quad {
        Quad {
            parts: std::array::from_fn(|m| {
                proper_subsets(m).map(|s| self.parts[s] * o.parts[m ^ s]).sum::<f64>() + self.parts[m] * o.parts[0]
            }),
        }
    }
}

impl Div for Quad {
    type Output = Quad;
    /// Solves `self = q * o` for `q` part by part, each set after its subsets (which are smaller
    /// numbers).
    #[inline]
    fn div(self, o: Quad) -> Quad {
        let mut q = Quad::default();
        for m in 0..16 {
            let known: f64 = proper_subsets(m).map(|s| q.parts[s] * o.parts[m ^ s]).sum();
            q.parts[m] = (self.parts[m] - known) / o.parts[0];
        }
        q
    }
}

impl Neg for Quad {
    type Output = Quad;
    #[inline]
    fn neg(self) -> Quad {
        Quad { parts: self.parts.map(|p| -p) }
    }
}

impl Scalar for Quad {
    const ORDER: u8 = 4;

    #[inline]
    fn constant(v: f64) -> Self {
        let mut parts = [0.0; 16];
        parts[0] = v;
        Quad { parts }
    }

    #[inline]
    fn value(self) -> f64 {
        self.parts[0]
    }

    /// Without the fourth derivative: a part that needs it (all four directions moving) is NaN,
    /// never a silent zero.
    #[inline]
    fn lift(self, f0: f64, f1: f64, f2: f64, f3: f64) -> Self {
        self.lift_fourth([f0, f1, f2, f3, f64::NAN])
    }

    /// As [`Quad::lift`]: the fourth-order part NaN where it moves.
    #[inline]
    fn lift2(self, o: Self, f0: f64, grad: [f64; 2], hess: [f64; 3], third: [f64; 4]) -> Self {
        self.lift2_fourth(o, f0, grad, hess, third, [f64::NAN; 5])
    }

    /// `f(v + d) = f0 + f1 d + f2 d²/2 + f3 d³/6 + f4 d⁴/24`, `d` the nilpotent part of `self`.
    #[inline]
    fn lift_fourth(self, f: [f64; 5]) -> Self {
        let d = self.increment();
        let d2 = d * d;
        let d3 = d2 * d;
        let terms = [(f[1], d), (f[2] / 2.0, d2), (f[3] / 6.0, d3), (f[4] / 24.0, d3 * d)];
        Quad::taylor(f[0], &terms)
    }

    /// The Taylor expansion of `f(u, w)` to fourth order in the nilpotent parts `du`, `dw`: the
    /// sum over `a + b <= 4` of `f_(a u's, b w's) du^a dw^b / (a! b!)`.
    #[inline]
    fn lift2_fourth(self, o: Self, f0: f64, g: [f64; 2], h: [f64; 3], t: [f64; 4], q: [f64; 5]) -> Self {
        let powers = |d: Quad| {
            let mut p = [Quad::constant(1.0), d, d, d, d];
            for k in 2..5 {
                p[k] = p[k - 1] * d;
            }
            p
        };
        let (pu, pw) = (powers(self.increment()), powers(o.increment()));
        let factorial = [1.0, 1.0, 2.0, 6.0, 24.0];
        let partials: [&[f64]; 4] = [&g, &h, &t, &q];
        // One term for each partial: 2 + 3 + 4 + 5.
        let mut terms = [(0.0, Quad::default()); 14];
        let by_order = partials
            .iter()
            .enumerate()
            .flat_map(|(k, by_w)| by_w.iter().enumerate().map(move |(b, &f)| (k + 1 - b, b, f)));
        for (term, (a, b, f)) in terms.iter_mut().zip(by_order) {
            *term = (f / (factorial[a] * factorial[b]), pu[a] * pw[b]);
        }
        Quad::taylor(f0, &terms)
    }
}

/// A number type that can carry one more direction: the derivative of a function with respect
/// to its own argument at an argument that already carries derivatives (a cam's slope `R'(psi)`
/// where `psi` moves with the coordinates and the parameters), exactly. The value is raised to
/// [`Nestable::Up`] with the new direction seeded ([`Nestable::seed`]), the function evaluated
/// there, and its part along the new direction read back as a number of this type
/// ([`Nestable::slope`]): `f'(x)` with every derivative `x` carries. `f64`, [`Dual`],
/// [`HyperDual`] and [`Tri`] are nestable; [`Quad`], the top, is not.
pub trait Nestable: Scalar {
    /// The type with one more direction.
    type Up: Scalar;
    /// `self` moving along the new direction at rate `rate`.
    fn seed(self, rate: f64) -> Self::Up;
    /// The part of `u` along the new direction, with every derivative of it along the old ones.
    fn slope(u: Self::Up) -> Self;
}

impl Nestable for f64 {
    type Up = Dual;
    #[inline]
    fn seed(self, rate: f64) -> Dual {
        Dual::new(self, rate)
    }
    #[inline]
    fn slope(u: Dual) -> f64 {
        u.d
    }
}

/// The old direction is `e2`, the new one `e1`.
impl Nestable for Dual {
    type Up = HyperDual;
    #[inline]
    fn seed(self, rate: f64) -> HyperDual {
        HyperDual::new(self.v, rate, self.d, 0.0)
    }
    #[inline]
    fn slope(u: HyperDual) -> Dual {
        Dual::new(u.e1, u.e12)
    }
}

/// The old directions are `ε1`, `ε2` and `ε3` (bits 0 to 2 of [`Quad::parts`]), the new one `ε4`
/// (bit 3).
/// As the [`Tri`] it is ([`TimeTri::tri`]): the slope's parts keep the symmetry of the first two
/// directions, so reading them back drops only repeated parts.
impl Nestable for TimeTri {
    type Up = Quad;
    #[inline]
    fn seed(self, rate: f64) -> Quad {
        self.tri().seed(rate)
    }
    #[inline]
    fn slope(u: Quad) -> TimeTri {
        let t = Tri::slope(u);
        TimeTri::trajectory([t.v, t.e1, t.e12], [t.e3, t.e13, t.e123])
    }
}

impl Nestable for Tri {
    type Up = Quad;
    #[inline]
    fn seed(self, rate: f64) -> Quad {
        let t = self;
        let mut parts = [0.0; 16];
        parts[..8].copy_from_slice(&[t.v, t.e1, t.e2, t.e12, t.e3, t.e13, t.e23, t.e123]);
        parts[8] = rate;
        Quad { parts }
    }
    #[inline]
    fn slope(u: Quad) -> Tri {
        let p = &u.parts[8..];
        Tri::new(p[0], [p[1], p[2], p[4]], [p[3], p[5], p[6]], p[7])
    }
}

/// The old directions are `e1` and `e2`, the new one `e3`.
impl Nestable for HyperDual {
    type Up = Tri;
    #[inline]
    fn seed(self, rate: f64) -> Tri {
        Tri::new(self.v, [self.e1, self.e2, rate], [self.e12, 0.0, 0.0], 0.0)
    }
    #[inline]
    fn slope(u: Tri) -> HyperDual {
        HyperDual::new(u.e3, u.e13, u.e23, u.e123)
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

    /// A number moving along all four directions at `rates`, from `v`.
    fn quad_along(v: f64, rates: [f64; 4]) -> Quad {
        let mut q = Quad::constant(v);
        for (k, r) in rates.into_iter().enumerate() {
            q.parts[1 << k] = r;
        }
        q
    }

    /// Products and quotients of numbers with four directions: `t⁵` and `1/t` at `t` moving
    /// along `(a, b, c, d)` have fourth-order parts `120 t abcd` and `24 abcd / t⁵` (the fourth
    /// derivative times the four rates), and dividing a product by a factor gives the other back,
    /// every part, to round-off (1e-13 relative).
    #[test]
    fn quad_arithmetic_rules() {
        let (x, rates) = (1.3, [0.7, -1.1, 0.4, 2.0]);
        let abcd: f64 = rates.iter().product();
        let t = quad_along(x, rates);
        let five = t * t * t * t * t;
        assert!(close(five.parts[15], 120.0 * x * abcd, 1e-14), "{five:?}");
        // The second-order part along ε1ε3: 20 t³ a c.
        assert!(close(five.parts[0b0101], 20.0 * x * x * x * rates[0] * rates[2], 1e-14), "{five:?}");
        let inverse = Quad::constant(1.0) / t;
        assert!(close(inverse.parts[15], 24.0 * abcd / x.powi(5), 1e-14), "{inverse:?}");
        let mut a = Quad::default();
        let mut b = Quad::default();
        for m in 0..16 {
            a.parts[m] = 0.3 + 0.1 * m as f64;
            b.parts[m] = 1.7 - 0.05 * (m * m) as f64;
        }
        let back = (a * b) / b;
        for m in 0..16 {
            assert!(close(back.parts[m], a.parts[m], 1e-13), "part {m}: {back:?} vs {a:?}");
        }
        assert_eq!((-a).parts[7], -a.parts[7]);
    }

    /// Each elementary function's fourth-order part against its third derivative (a [`Tri`]
    /// evaluation) differenced along the same line: for `f(x0 + s a)` (`a` the rates of its
    /// arguments), `d⁴f/ds⁴` is the fourth-order part of `f` at arguments moving at `a` along all
    /// four directions, and `d³f/ds³` the `e123` part at arguments moving at `a` along three.
    /// Central differences of steps `h = 1e-3` and `h/2`, Richardson-extrapolated: truncation
    /// `h⁴ |f⁽⁸⁾| / 30 ~ 1e-13` for these functions of order one, round-off `eps |f⁽³⁾| / h ~
    /// 1e-13`; to 1e-8 relative.
    #[test]
    fn quad_fourth_derivatives_match_differences_of_the_third() {
        type F = (&'static str, [f64; 2], [f64; 2], fn(&[Quad]) -> Quad, fn(&[Tri]) -> Tri);
        let cases: [F; 20] = [
            ("sin", [0.7, 0.0], [1.0, 0.0], |a| a[0].sin(), |a| a[0].sin()),
            ("cos", [0.7, 0.0], [1.0, 0.0], |a| a[0].cos(), |a| a[0].cos()),
            ("tan", [0.6, 0.0], [1.0, 0.0], |a| a[0].tan(), |a| a[0].tan()),
            ("asin", [0.4, 0.0], [1.0, 0.0], |a| a[0].asin(), |a| a[0].asin()),
            ("acos", [-0.3, 0.0], [1.0, 0.0], |a| a[0].acos(), |a| a[0].acos()),
            ("atan", [0.9, 0.0], [1.0, 0.0], |a| a[0].atan(), |a| a[0].atan()),
            ("sinh", [0.8, 0.0], [1.0, 0.0], |a| a[0].sinh(), |a| a[0].sinh()),
            ("cosh", [0.8, 0.0], [1.0, 0.0], |a| a[0].cosh(), |a| a[0].cosh()),
            ("tanh", [0.5, 0.0], [1.0, 0.0], |a| a[0].tanh(), |a| a[0].tanh()),
            ("exp", [0.3, 0.0], [1.0, 0.0], |a| a[0].exp(), |a| a[0].exp()),
            ("ln", [1.4, 0.0], [1.0, 0.0], |a| a[0].ln(), |a| a[0].ln()),
            ("sqrt", [1.4, 0.0], [1.0, 0.0], |a| a[0].sqrt(), |a| a[0].sqrt()),
            ("powi 5", [1.2, 0.0], [1.0, 0.0], |a| a[0].powi(5), |a| a[0].powi(5)),
            ("powi -2", [1.2, 0.0], [1.0, 0.0], |a| a[0].powi(-2), |a| a[0].powi(-2)),
            ("powf 2.5", [1.2, 0.0], [1.0, 0.0], |a| a[0].powf(2.5), |a| a[0].powf(2.5)),
            ("pow", [1.2, 0.8], [0.6, -0.9], |a| a[0].pow(a[1]), |a| a[0].pow(a[1])),
            ("atan2", [0.6, -0.8], [0.7, 0.5], |a| a[0].atan2(a[1]), |a| a[0].atan2(a[1])),
            ("atan2 on an axis", [0.0, 1.1], [1.0, 0.3], |a| a[0].atan2(a[1]), |a| a[0].atan2(a[1])),
            ("hypot", [0.6, -0.8], [0.7, 0.5], |a| a[0].hypot(a[1]), |a| a[0].hypot(a[1])),
            ("hypot on an axis", [0.0, 1.1], [1.0, 0.3], |a| a[0].hypot(a[1]), |a| a[0].hypot(a[1])),
        ];
        for (name, x0, a, quad, tri) in cases {
            let fourth = quad(&[0, 1].map(|k| quad_along(x0[k], [a[k]; 4]))).parts[15];
            let third = |s: f64| tri(&[0, 1].map(|k| Tri::new(x0[k] + s * a[k], [a[k]; 3], [0.0; 3], 0.0))).e123;
            let diff = |h: f64| (third(h) - third(-h)) / (2.0 * h);
            let h = 1e-3;
            let want = (4.0 * diff(h / 2.0) - diff(h)) / 3.0;
            assert!(close(fourth, want, 1e-8), "{name}: {fourth} vs differences {want}");
        }
    }

    /// `slope` of a function evaluated at a seeded argument is its derivative at the argument,
    /// with the argument's own derivatives: `f = sin(x^2)` at `x` moving along one, two or three
    /// directions (three: [`Quad`]), against the chain rule by hand (`f' = 2 x cos(x^2)`, `f'' = 2 cos(x^2) - 4 x^2
    /// sin(x^2)`, `f''' = -12 x sin(x^2) - 8 x^3 cos(x^2)`), to 1e-14 (round-off of a few
    /// operations).
    #[test]
    fn nested_slopes_carry_the_arguments_derivatives() {
        use super::Nestable;
        let x: f64 = 0.7;
        let (c, s) = ((x * x).cos(), (x * x).sin());
        let (f1, f2, f3) = (2.0 * x * c, 2.0 * c - 4.0 * x * x * s, -12.0 * x * s - 8.0 * x * x * x * c);
        let close = |a: f64, b: f64| assert!((a - b).abs() <= 1e-14 * (1.0 + b.abs()), "{a} vs {b}");
        let u = x.seed(1.0);
        close(f64::slope((u * u).sin()), f1);
        let u = Dual::new(x, 0.3).seed(1.0);
        let d = Dual::slope((u * u).sin());
        close(d.v, f1);
        close(d.d, f2 * 0.3);
        let u = HyperDual::new(x, 0.3, -0.5, 0.2).seed(1.0);
        let h = HyperDual::slope((u * u).sin());
        close(h.v, f1);
        close(h.e1, f2 * 0.3);
        close(h.e2, f2 * -0.5);
        close(h.e12, f3 * 0.3 * -0.5 + f2 * 0.2);
        // f'''' = -12 sin(x^2) - 48 x^2 cos(x^2) + 16 x^4 sin(x^2); the derivatives of f'(x) at x
        // moving along three directions, mixed parts included, by the chain rule.
        let f4 = -12.0 * s - 48.0 * x * x * c + 16.0 * x.powi(4) * s;
        let ([x1, x2, x3], [x12, x13, x23], x123) = ([0.3, -0.5, 0.8], [0.2, -0.1, 0.6], 0.4);
        let u = Tri::new(x, [x1, x2, x3], [x12, x13, x23], x123).seed(1.0);
        let t = Tri::slope((u * u).sin());
        close(t.v, f1);
        close(t.e3, f2 * x3);
        close(t.e13, f3 * x1 * x3 + f2 * x13);
        close(t.e23, f3 * x2 * x3 + f2 * x23);
        close(t.e123, f4 * x1 * x2 * x3 + f3 * (x1 * x23 + x2 * x13 + x3 * x12) + f2 * x123);
        // A `TimeTri` nests as the `Tri` it is (first two directions equal): its slope has the
        // same parts, exactly, and those parts follow the chain rule above with `x2 = x1`,
        // `x23 = x13`.
        let time = TimeTri::trajectory([x, x1, x12], [x3, x13, x123]);
        let u = time.seed(1.0);
        let nested = TimeTri::slope((u * u).sin());
        let tri = Tri::slope((time.tri().seed(1.0) * time.tri().seed(1.0)).sin());
        assert_eq!(nested.tri(), tri);
        close(nested.e13, f3 * x1 * x3 + f2 * x13);
        close(nested.e123, f4 * x1 * x1 * x3 + f3 * (x1 * x13 + x1 * x13 + x3 * x12) + f2 * x123);
    }
    /// A [`TimeTri`] is a [`Tri`] seeded with its first two directions equal, to the bit: every
    /// operation and elementary function (also the two-argument ones, and the quotient), applied
    /// to numbers seeded as design sensitivities seed them (each part nonzero, so that every
    /// product of the rules is exercised), gives the same parts in both types. The comparison is
    /// exact: the type is meant to repeat `Tri`'s arithmetic, not to approximate it.
    #[test]
    fn time_tri_is_tri_with_equal_time_directions() {
        fn all<S: Scalar>(x: S, y: S) -> Vec<S> {
            let one = S::constant(1.0);
            vec![
                x + y,
                x - y,
                x * y,
                x / y,
                -x,
                x.sin(),
                x.cos(),
                x.tan(),
                (x * S::constant(0.5)).asin(),
                (x * S::constant(0.5)).acos(),
                x.atan(),
                x.sinh(),
                x.cosh(),
                x.tanh(),
                x.exp(),
                x.ln(),
                x.sqrt(),
                (-x).abs(),
                x.powi(3),
                x.powf(2.5),
                x.pow(y),
                x.atan2(y),
                x.hypot(y),
                (x * y).sin() / (one + x.hypot(y)) - x.atan2(y * y).exp(),
            ]
        }
        let (x, y) = ([0.7, -0.4, 1.3], [0.2, 0.9, -0.6]);
        let (dx, dy) = ([0.5, 0.25, -1.1], [-0.3, 0.8, 0.45]);
        let tri = all(Tri::trajectory(x, dx), Tri::trajectory(y, dy));
        let time = all(TimeTri::trajectory(x, dx), TimeTri::trajectory(y, dy));
        for (k, (a, b)) in tri.iter().zip(&time).enumerate() {
            assert_eq!(a.parts().map(f64::to_bits), b.tri().parts().map(f64::to_bits), "function {k}: {a:?} vs {b:?}");
        }
    }
}
