//! The standard motion laws of cam and drive design, as expression functions
//! `law(x, x0, h0, x1, h1)`: `h0` up to `x0`, `h1` from `x1`, and between them
//! `h0 + (h1 - h0) s(u)` with `u = (x - x0) / (x1 - x0)` and `s` the law's normalized rise
//! (`s(0) = 0`, `s(1) = 1`, `s(1 - u) = 1 - s(u)`):
//!
//! | function | `s(u)` | `s'` at the ends | `s''` at the ends | peak `s''` |
//! | --- | --- | --- | --- | --- |
//! | `step` | `u^2 (3 - 2 u)` (Adams' STEP) | 0 | `+-6` (a jump) | 6 |
//! | `step5`, `poly345` | `u^3 (10 - 15 u + 6 u^2)` (Adams' STEP5, the 3-4-5 polynomial) | 0 | 0 | `10 / sqrt(3) = 5.774` |
//! | `cycloidal` | `u - sin(2 pi u) / (2 pi)` | 0 | 0 | `2 pi = 6.283` |
//! | `harmonic` | `(1 - cos(pi u)) / 2` | 0 | `+-pi^2 / 2` (a jump) | `pi^2 / 2 = 4.935` |
//! | `modified_trapezoid` | five pieces, below | 0 | 0 | `8 pi / (2 + pi) = 4.888` |
//!
//! The modified trapezoid's acceleration `s''` rises as `A sin(4 pi u)` to `A` at `u = 1/8`,
//! stays at `A` to `3/8`, falls as `A cos(4 pi (u - 3/8))` through 0 at `1/2` to `-A` at `5/8`,
//! stays there to `7/8` and returns as `-A cos(4 pi (u - 7/8))` to 0 at 1, with
//! `A = 8 pi / (2 + pi)` so that `s(1) = 1`. Integrated twice (`D = 2 pi (2 + pi)`):
//!
//! ```text
//! s = (4 pi u - sin 4 pi u) / D                                       0   <= u <= 1/8
//! s = ((4 pi u^2 + (2 - pi) u) / (2 + pi) - 1 / D + pi / (16 (2 + pi))    1/8 <= u <= 3/8
//! s = ((4 pi + 4 pi^2) u + sin 4 pi u - pi^2) / D                      3/8 <= u <= 5/8
//! s = (-4 pi u^2 + (2 + 7 pi) u) / (2 + pi) - 33 pi / (16 (2 + pi)) + 1 / D   5/8 <= u <= 7/8
//! s = (4 pi u - sin 4 pi u + 2 pi^2) / D                               7/8 <= u <= 1
//! ```
//!
//! Every argument may be an expression; the derivatives are exact (the formulas are evaluated
//! over the caller's [`Scalar`], so with respect to `x0`, `h0`, `x1` and `h1` too). At the ends
//! the constant side is taken: at `x = x0` the value is `h0` and its derivative in `x` is the
//! left one, 0. A law with `x1 <= x0` has no rise: its value is NaN, which an analysis reports
//! as a non-finite value naming the expression.

use super::scalar::Scalar;
use std::f64::consts::PI;

/// A motion law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// Adams' cubic STEP.
    Step,
    /// Adams' quintic STEP5, the 3-4-5 polynomial.
    Step5,
    /// The cycloidal law.
    Cycloidal,
    /// The simple harmonic law.
    Harmonic,
    /// The modified trapezoidal law.
    ModifiedTrapezoid,
}

impl Law {
    /// `law(x, x0, h0, x1, h1)`.
    pub fn apply<S: Scalar>(self, x: S, x0: S, h0: S, x1: S, h1: S) -> S {
        if x1.value() <= x0.value() || x1.value().is_nan() || x0.value().is_nan() {
            return S::constant(f64::NAN);
        }
        if x.value() <= x0.value() {
            return h0;
        }
        if x.value() >= x1.value() {
            return h1;
        }
        let u = (x - x0) / (x1 - x0);
        h0 + (h1 - h0) * self.rise(u)
    }

    /// The normalized rise `s(u)`, `0 < u < 1`.
    fn rise<S: Scalar>(self, u: S) -> S {
        let c = S::constant;
        match self {
            Law::Step => u * u * (c(3.0) - c(2.0) * u),
            Law::Step5 => u * u * u * (c(10.0) + u * (c(-15.0) + c(6.0) * u)),
            Law::Cycloidal => u - (c(2.0 * PI) * u).sin() / c(2.0 * PI),
            Law::Harmonic => (c(1.0) - (c(PI) * u).cos()) / c(2.0),
            Law::ModifiedTrapezoid => {
                let d = 2.0 * PI * (2.0 + PI);
                let k = 2.0 + PI;
                let sin4 = || (c(4.0 * PI) * u).sin();
                match u.value() {
                    v if v <= 0.125 => (c(4.0 * PI) * u - sin4()) / c(d),
                    v if v <= 0.375 => (c(4.0 * PI) * u * u + c(2.0 - PI) * u) / c(k) + c(PI / (16.0 * k) - 1.0 / d),
                    v if v <= 0.625 => (c(4.0 * PI + 4.0 * PI * PI) * u + sin4() - c(PI * PI)) / c(d),
                    v if v <= 0.875 => {
                        (c(-4.0 * PI) * u * u + c(2.0 + 7.0 * PI) * u) / c(k) + c(1.0 / d - 33.0 * PI / (16.0 * k))
                    }
                    _ => (c(4.0 * PI) * u - sin4() + c(2.0 * PI * PI)) / c(d),
                }
            }
        }
    }
}
