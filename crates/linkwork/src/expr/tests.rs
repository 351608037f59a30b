//! Tests of parsing, evaluation and derivatives.

use super::*;
use std::f64::consts::{E, LN_2, PI};

/// Resolver for one-letter test variables: `x`/`t` -> 0, `y` -> 1, `z` -> 2,
/// `a` -> 0, `b` -> 1, `c` -> 2, and the crank coordinates.
fn test_resolve(name: &str) -> Result<usize, String> {
    match name {
        "x" | "t" | "a" | "crank.x" => Ok(0),
        "y" | "b" | "crank.y" => Ok(1),
        "z" | "c" | "crank.phi" => Ok(2),
        _ => Err("expected <body>.x, <body>.y, <body>.phi or t".to_string()),
    }
}

fn parse(src: &str) -> Expr {
    Expr::parse(src, &mut test_resolve).unwrap_or_else(|e| panic!("{src}: {e}"))
}

fn parse_err(src: &str) -> ExprError {
    match Expr::parse(src, &mut test_resolve) {
        Ok(e) => panic!("{src}: expected an error, got {e:?}"),
        Err(e) => e,
    }
}

fn val(src: &str) -> f64 {
    parse(src).eval::<f64>(&[0.0; 3])
}

/// `|a - b| <= tol * (1 + |b|)`: relative for large values, absolute near zero.
fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[track_caller]
fn assert_close(what: &str, a: f64, b: f64, tol: f64) {
    assert!(close(a, b, tol), "{what}: got {a:e}, expected {b:e} (tol {tol:e})");
}

// ---------------------------------------------------------------- values

#[test]
fn numbers_and_constants() {
    assert_eq!(val("2"), 2.0);
    assert_eq!(val("0.5"), 0.5);
    assert_eq!(val(".5"), 0.5);
    assert_eq!(val("1."), 1.0);
    assert_eq!(val("1e-3"), 1e-3);
    assert_eq!(val("2.5E+2"), 250.0);
    assert_eq!(val("6.1506"), 6.1506);
    assert_eq!(val("pi"), PI);
    assert_eq!(val("e"), E);
    assert_eq!(val("  \t2\n"), 2.0);
}

#[test]
fn precedence_and_associativity() {
    assert_eq!(val("2^3^2"), 512.0);
    assert_eq!(val("2**3**2"), 512.0);
    assert_eq!(val("(2^3)^2"), 64.0);
    assert_eq!(val("-2^2"), -4.0);
    assert_eq!(val("(-2)^2"), 4.0);
    assert_eq!(val("2*3+4"), 10.0);
    assert_eq!(val("2+3*4"), 14.0);
    assert_eq!(val("(1+2)*3"), 9.0);
    assert_eq!(val("8/4/2"), 1.0);
    assert_eq!(val("8-4-2"), 2.0);
    assert_eq!(val("2^-1"), 0.5);
    assert_eq!(val("2*-3"), -6.0);
    assert_eq!(val("--3"), 3.0);
    assert_eq!(val("+-+3"), -3.0);
    assert_eq!(val("-3^2*2"), -18.0);
    assert_eq!(val("2^3*2"), 16.0);
    assert_eq!(val("2 ^ 2 ^ -1"), 2f64.sqrt());
    assert_eq!(val("2^-2*3"), 0.75);
    assert_eq!(val("2^-2^2"), 1.0 / 16.0);
    assert_eq!(val("2^(1+1)^2"), 16.0);
    assert_eq!(val("2*3^2"), 18.0);
    assert_eq!(val("-(1+2)*3"), -9.0);
    assert_eq!(val("1 - -1"), 2.0);
    assert_eq!(val("8/2*4"), 16.0);
    assert_eq!(val("1-2+3-4"), -2.0);
    assert_eq!(val("2*3-4/2+1"), 5.0);
    assert_eq!(val("((2))"), 2.0);
    assert_eq!(parse("-x*y").eval(&[2.0, 3.0]), -6.0);
    assert_eq!(parse("-x^2").eval(&[3.0]), -9.0);
    assert_eq!(parse("x*-y^2").eval(&[2.0, 3.0]), -18.0);
}

#[test]
fn function_values() {
    let cases: &[(&str, f64)] = &[
        ("sin(0.5)", 0.5f64.sin()),
        ("cos(0.5)", 0.5f64.cos()),
        ("tan(0.5)", 0.5f64.tan()),
        ("asin(0.5)", 0.5f64.asin()),
        ("acos(0.5)", 0.5f64.acos()),
        ("atan(0.5)", 0.5f64.atan()),
        ("atan2(1, -1)", 0.75 * PI),
        ("sinh(0.5)", 0.5f64.sinh()),
        ("cosh(0.5)", 0.5f64.cosh()),
        ("tanh(0.5)", 0.5f64.tanh()),
        ("exp(0.5)", 0.5f64.exp()),
        ("log(e)", 1.0),
        ("log(0.5)", -LN_2),
        ("sqrt(2)", 2f64.sqrt()),
        ("abs(-3)", 3.0),
        ("min(2, -3)", -3.0),
        ("max(2, -3)", 2.0),
        ("sign(-0.2)", -1.0),
        ("sign(0)", 0.0),
        ("sign(7)", 1.0),
        ("pow(2, 10)", 1024.0),
        ("pow(4, 0.5)", 2.0),
        ("sin (pi/2)", 1.0),
        ("atan2(1 + 1, 2*1)", PI / 4.0),
        ("max(min(1, 2), 0)", 1.0),
        ("pow(2, 1 + 1)^2", 16.0),
        ("min(-(2 + 1), sin(0)) * 2", -6.0),
        ("2 * sqrt(exp(log(4)))", 4.0),
    ];
    for &(src, expected) in cases {
        assert_close(src, val(src), expected, 1e-15);
    }
}

#[test]
fn variables_and_slots() {
    let e = parse("crank.x^2 + crank.y^2 - 0.5625");
    assert_eq!(e.slots(), &[0, 1]);
    assert!(!e.is_constant());
    assert_eq!(e.constant_value(), None);
    assert_close("circle", e.eval(&[0.6, 0.45]), 0.0, 1e-15);
    assert_eq!(e.source(), "crank.x^2 + crank.y^2 - 0.5625");
    assert_eq!(e.to_string(), "crank.x^2 + crank.y^2 - 0.5625");

    // slots are sorted and distinct whatever the order of appearance
    let e = parse("z * x + z - y*x");
    assert_eq!(e.slots(), &[0, 1, 2]);
    assert_eq!(e.eval(&[2.0, 3.0, 5.0]), 5.0 * 2.0 + 5.0 - 3.0 * 2.0);

    // arbitrary (sparse) slot numbers from the resolver
    let e = Expr::parse("q.x * 2 + r.phi", &mut |n| match n {
        "q.x" => Ok(7),
        "r.phi" => Ok(3),
        _ => Err(String::new()),
    })
    .unwrap();
    assert_eq!(e.slots(), &[3, 7]);
    let mut vars = [0.0; 8];
    vars[7] = 1.5;
    vars[3] = 0.25;
    assert_eq!(e.eval(&vars), 3.25);
}

#[test]
fn constants_fold() {
    let e = parse("2*pi*(1 + 3^2) - sqrt(16)");
    assert!(e.is_constant());
    assert_eq!(e.slots(), &[] as &[usize]);
    assert_eq!(e.constant_value(), Some(2.0 * PI * 10.0 - 4.0));
    // a constant can be evaluated with no variables at all, over every scalar type
    assert_eq!(e.eval::<f64>(&[]), 2.0 * PI * 10.0 - 4.0);
    assert_eq!(e.eval::<Dual>(&[]), Dual::new(2.0 * PI * 10.0 - 4.0, 0.0));
    let h = e.eval::<HyperDual>(&[]);
    assert_eq!((h.e1, h.e2, h.e12), (0.0, 0.0, 0.0));
    // folding never drops a variable
    let e = parse("0*x");
    assert_eq!(e.slots(), &[0]);
    assert_eq!(e.eval(&[Dual::variable(3.0)]), Dual::new(0.0, 0.0));
}

#[test]
fn resolver_is_not_called_for_builtins() {
    let mut seen = Vec::new();
    let e = Expr::parse("pi*e + sin(t) + atan2(t, 1) + t", &mut |n| {
        seen.push(n.to_string());
        Ok(0)
    })
    .unwrap();
    assert_eq!(seen, ["t", "t", "t"]);
    assert_eq!(e.slots(), &[0]);
    // dotted names are never constants or functions
    let e = Expr::parse("pi.x + e.y", &mut |n| match n {
        "pi.x" => Ok(0),
        "e.y" => Ok(1),
        _ => Err(String::new()),
    })
    .unwrap();
    assert_eq!(e.eval(&[1.0, 2.0]), 3.0);
}

#[test]
fn dual_values_are_bit_identical_to_f64() {
    // The value part of every scalar type is computed with the same floating-point
    // operations, so results agree exactly (not just to rounding).
    let srcs = [
        "exp(-x^2)*cos(3*x) + atan2(x, 0.3) - log(1 + x^2)/sqrt(2 + x)",
        "x^x + 2^x + pow(x, 2.5) + min(x, 0.4) * max(x, tanh(x)) + abs(x - 1) * sign(x)",
        "asin(x/2) + acos(x/3) + atan(x) + sinh(x) / cosh(x) + tan(x) / (1 + x)",
    ];
    for src in srcs {
        let e = parse(src);
        for x in [0.1, 0.35, 0.8, 1.3] {
            let f = e.eval(&[x]);
            assert_eq!(e.eval(&[Dual::variable(x)]).v, f, "{src}");
            assert_eq!(e.eval(&[HyperDual::variable(x)]).v, f, "{src}");
        }
    }
}

// ---------------------------------------------------------------- derivatives

/// A one-variable test case: source in `x`, the points to check, and the closed-form
/// value, first, second and third derivative.
struct Case {
    src: &'static str,
    points: &'static [f64],
    f: fn(f64) -> f64,
    d1: fn(f64) -> f64,
    d2: fn(f64) -> f64,
    d3: fn(f64) -> f64,
}

/// The motion laws' cases below: `law(x, 0.2, 1, 1.2, 3)`, so `u = x - 0.2` and the rise is 2.
fn rise(x: f64, s: fn(f64) -> f64) -> f64 {
    let u = x - 0.2;
    if u <= 0.0 {
        1.0
    } else if u >= 1.0 {
        3.0
    } else {
        1.0 + 2.0 * s(u)
    }
}

/// A derivative of a rise, 0 outside it.
fn rise_rate(x: f64, s: fn(f64) -> f64) -> f64 {
    let u = x - 0.2;
    if u <= 0.0 || u >= 1.0 {
        0.0
    } else {
        2.0 * s(u)
    }
}

/// The modified trapezoid's acceleration by its definition (Rothbart): sine ramps of period
/// 1/2 to and from the constant levels `+-A`, `A = 8 pi / (2 + pi)`.
fn trapezoid_acceleration(u: f64) -> f64 {
    let a = 8.0 * PI / (2.0 + PI);
    match u {
        u if u <= 0.125 => a * (4.0 * PI * u).sin(),
        u if u <= 0.375 => a,
        u if u <= 0.625 => a * (4.0 * PI * (u - 0.375)).cos(),
        u if u <= 0.875 => -a,
        u => -a * (4.0 * PI * (u - 0.875)).cos(),
    }
}

/// The modified trapezoid's jerk: the derivative of [`trapezoid_acceleration`] on each piece.
fn trapezoid_jerk(u: f64) -> f64 {
    let a = 8.0 * PI / (2.0 + PI);
    match u {
        u if u <= 0.125 => 4.0 * PI * a * (4.0 * PI * u).cos(),
        u if u <= 0.375 => 0.0,
        u if u <= 0.625 => -4.0 * PI * a * (4.0 * PI * (u - 0.375)).sin(),
        u if u <= 0.875 => 0.0,
        u => 4.0 * PI * a * (4.0 * PI * (u - 0.875)).sin(),
    }
}

/// `int_0^u w(u, v) a(v) dv` by Simpson's rule on each smooth piece of the acceleration (10,000
/// panels of at most `2.5e-5`: error about `1e-16`): the velocity (`w = 1`) and the rise
/// (`w = u - v`, Cauchy's formula for the double integral), independent of the closed forms.
fn trapezoid_integral(u: f64, weight: fn(f64, f64) -> f64) -> f64 {
    let mut total = 0.0;
    for piece in [0.0, 0.125, 0.375, 0.625, 0.875, 1.0].windows(2) {
        let (a, b) = (piece[0].min(u), piece[1].min(u));
        if b <= a {
            continue;
        }
        let panels = 10_000;
        let h = (b - a) / panels as f64;
        let f = |v: f64| weight(u, v) * trapezoid_acceleration(v);
        let mut sum = f(a) + f(b);
        for i in 1..panels {
            sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        total += sum * h / 3.0;
    }
    total
}

fn cases() -> Vec<Case> {
    fn sq(x: f64) -> f64 {
        x * x
    }
    vec![
        // hypot(x, 2x - 1) = sqrt(5x^2 - 4x + 1): f' = (5x - 2) / r, f'' = 1 / r^3.
        Case {
            src: "hypot(x, 2*x - 1)",
            points: &[-1.5, 0.1, 0.7, 3.0],
            f: |x| (5.0 * x * x - 4.0 * x + 1.0).sqrt(),
            d1: |x| (5.0 * x - 2.0) / (5.0 * x * x - 4.0 * x + 1.0).sqrt(),
            d2: |x| (5.0 * x * x - 4.0 * x + 1.0).powf(-1.5),
            d3: |x| -1.5 * (10.0 * x - 4.0) * (5.0 * x * x - 4.0 * x + 1.0).powf(-2.5),
        },
        // Motion laws (closed forms of the normalized rise s(u) and its derivatives; the
        // modified trapezoid's from its acceleration's definition, integrated numerically).
        // Points before, inside and after the rise, away from its ends and from the
        // trapezoid's joints at u = 1/8, 3/8, 5/8, 7/8.
        Case {
            src: "step(x, 0.2, 1, 1.2, 3)",
            points: &[0.0, 0.5, 0.9, 1.5],
            f: |x| rise(x, |u| u * u * (3.0 - 2.0 * u)),
            d1: |x| rise_rate(x, |u| 6.0 * u - 6.0 * u * u),
            d2: |x| rise_rate(x, |u| 6.0 - 12.0 * u),
            d3: |x| rise_rate(x, |_| -12.0),
        },
        Case {
            src: "step5(x, 0.2, 1, 1.2, 3) + poly345(x, 0.2, 1, 1.2, 3)",
            points: &[0.0, 0.5, 0.9, 1.5],
            f: |x| 2.0 * rise(x, |u| u.powi(3) * (10.0 - 15.0 * u + 6.0 * u * u)),
            d1: |x| 2.0 * rise_rate(x, |u| 30.0 * u * u - 60.0 * u.powi(3) + 30.0 * u.powi(4)),
            d2: |x| 2.0 * rise_rate(x, |u| 60.0 * u - 180.0 * u * u + 120.0 * u.powi(3)),
            d3: |x| 2.0 * rise_rate(x, |u| 60.0 - 360.0 * u + 360.0 * u * u),
        },
        Case {
            src: "cycloidal(x, 0.2, 1, 1.2, 3)",
            points: &[0.0, 0.5, 0.9, 1.5],
            f: |x| rise(x, |u| u - (2.0 * PI * u).sin() / (2.0 * PI)),
            d1: |x| rise_rate(x, |u| 1.0 - (2.0 * PI * u).cos()),
            d2: |x| rise_rate(x, |u| 2.0 * PI * (2.0 * PI * u).sin()),
            d3: |x| rise_rate(x, |u| 4.0 * PI * PI * (2.0 * PI * u).cos()),
        },
        Case {
            src: "harmonic(x, 0.2, 1, 1.2, 3)",
            points: &[0.0, 0.5, 0.9, 1.5],
            f: |x| rise(x, |u| (1.0 - (PI * u).cos()) / 2.0),
            d1: |x| rise_rate(x, |u| PI * (PI * u).sin() / 2.0),
            d2: |x| rise_rate(x, |u| PI * PI * (PI * u).cos() / 2.0),
            d3: |x| rise_rate(x, |u| -PI * PI * PI * (PI * u).sin() / 2.0),
        },
        Case {
            src: "modified_trapezoid(x, 0.2, 1, 1.2, 3)",
            points: &[0.0, 0.25, 0.4, 0.6, 0.7, 0.9, 1.0, 1.15, 1.5],
            f: |x| rise(x, |u| trapezoid_integral(u, |u, v| u - v)),
            d1: |x| rise_rate(x, |u| trapezoid_integral(u, |_, _| 1.0)),
            d2: |x| rise_rate(x, trapezoid_acceleration),
            d3: |x| rise_rate(x, trapezoid_jerk),
        },
        Case {
            src: "if(x >= 0.5, 3*x, x^2) + if(x < 0.5, 1, 0)",
            points: &[0.2, 0.9],
            f: |x| if x >= 0.5 { 3.0 * x } else { x * x + 1.0 },
            d1: |x| if x >= 0.5 { 3.0 } else { 2.0 * x },
            d2: |x| if x >= 0.5 { 0.0 } else { 2.0 },
            d3: |_| 0.0,
        },
        Case {
            src: "sin(x)",
            points: &[-2.0, 0.0, 0.7, 3.0],
            f: f64::sin,
            d1: f64::cos,
            d2: |x| -x.sin(),
            d3: |x| -x.cos(),
        },
        Case {
            src: "sin(4*x)",
            points: &[-0.3, 0.0, 0.9],
            f: |x| (4.0 * x).sin(),
            d1: |x| 4.0 * (4.0 * x).cos(),
            d2: |x| -16.0 * (4.0 * x).sin(),
            d3: |x| -64.0 * (4.0 * x).cos(),
        },
        Case {
            src: "cos(x)",
            points: &[-2.0, 0.0, 0.7, 3.0],
            f: f64::cos,
            d1: |x| -x.sin(),
            d2: |x| -x.cos(),
            d3: f64::sin,
        },
        Case {
            src: "tan(x)",
            points: &[-1.0, 0.0, 0.3, 1.2],
            f: f64::tan,
            d1: |x| 1.0 / sq(x.cos()),
            d2: |x| 2.0 * x.tan() / sq(x.cos()),
            d3: |x| 2.0 / sq(sq(x.cos())) + 4.0 * sq(x.tan()) / sq(x.cos()),
        },
        Case {
            src: "asin(x)",
            points: &[-0.7, 0.0, 0.2, 0.9],
            f: f64::asin,
            d1: |x| 1.0 / (1.0 - x * x).sqrt(),
            d2: |x| x / (1.0 - x * x).powf(1.5),
            d3: |x| (1.0 + 2.0 * x * x) / (1.0 - x * x).powf(2.5),
        },
        Case {
            src: "acos(x)",
            points: &[-0.7, 0.0, 0.2, 0.9],
            f: f64::acos,
            d1: |x| -1.0 / (1.0 - x * x).sqrt(),
            d2: |x| -x / (1.0 - x * x).powf(1.5),
            d3: |x| -(1.0 + 2.0 * x * x) / (1.0 - x * x).powf(2.5),
        },
        Case {
            src: "atan(x)",
            points: &[-3.0, 0.0, 0.5, 2.0],
            f: f64::atan,
            d1: |x| 1.0 / (1.0 + x * x),
            d2: |x| -2.0 * x / sq(1.0 + x * x),
            d3: |x| (6.0 * x * x - 2.0) / (1.0 + x * x).powi(3),
        },
        Case {
            // d/dy atan2(y, 2) = 2/(4 + y^2)
            src: "atan2(x, 2)",
            points: &[-3.0, 0.0, 0.5, 2.0],
            f: |x| x.atan2(2.0),
            d1: |x| 2.0 / (4.0 + x * x),
            d2: |x| -4.0 * x / sq(4.0 + x * x),
            d3: |x| (12.0 * x * x - 16.0) / (4.0 + x * x).powi(3),
        },
        Case {
            // d/dx atan2(1, x) = -1/(1 + x^2), valid in every quadrant
            src: "atan2(1, x)",
            points: &[-3.0, -0.5, 0.0, 2.0],
            f: |x| 1f64.atan2(x),
            d1: |x| -1.0 / (1.0 + x * x),
            d2: |x| 2.0 * x / sq(1.0 + x * x),
            d3: |x| (2.0 - 6.0 * x * x) / (1.0 + x * x).powi(3),
        },
        Case { src: "sinh(x)", points: &[-2.0, 0.0, 1.5], f: f64::sinh, d1: f64::cosh, d2: f64::sinh, d3: f64::cosh },
        Case { src: "cosh(x)", points: &[-2.0, 0.0, 1.5], f: f64::cosh, d1: f64::sinh, d2: f64::cosh, d3: f64::sinh },
        Case {
            src: "tanh(x)",
            points: &[-2.0, 0.0, 0.4, 1.5],
            f: f64::tanh,
            d1: |x| 1.0 / sq(x.cosh()),
            d2: |x| -2.0 * x.tanh() / sq(x.cosh()),
            d3: |x| -2.0 / sq(sq(x.cosh())) + 4.0 * sq(x.tanh()) / sq(x.cosh()),
        },
        Case { src: "exp(x)", points: &[-2.0, 0.0, 1.5], f: f64::exp, d1: f64::exp, d2: f64::exp, d3: f64::exp },
        Case {
            src: "log(x)",
            points: &[0.3, 1.0, 1.7, 5.0],
            f: f64::ln,
            d1: |x| 1.0 / x,
            d2: |x| -1.0 / (x * x),
            d3: |x| 2.0 / (x * x * x),
        },
        Case {
            src: "sqrt(x)",
            points: &[0.3, 1.0, 4.0],
            f: f64::sqrt,
            d1: |x| 0.5 / x.sqrt(),
            d2: |x| -0.25 / (x * x.sqrt()),
            d3: |x| 0.375 / (x * x * x.sqrt()),
        },
        Case { src: "abs(x)", points: &[-1.3, 0.7], f: f64::abs, d1: f64::signum, d2: |_| 0.0, d3: |_| 0.0 },
        Case { src: "sign(x)", points: &[-1.3, 0.7], f: f64::signum, d1: |_| 0.0, d2: |_| 0.0, d3: |_| 0.0 },
        Case {
            // selects x below 0.5, 1 - x above
            src: "min(x, 1 - x)",
            points: &[0.2, 0.8],
            f: |x| x.min(1.0 - x),
            d1: |x| if x < 0.5 { 1.0 } else { -1.0 },
            d2: |_| 0.0,
            d3: |_| 0.0,
        },
        Case {
            // selects x^2 outside [0, 1], x inside
            src: "max(x^2, x)",
            points: &[-0.5, 0.5, 2.0],
            f: |x| (x * x).max(x),
            d1: |x| if x * x > x { 2.0 * x } else { 1.0 },
            d2: |x| if x * x > x { 2.0 } else { 0.0 },
            d3: |_| 0.0,
        },
        Case {
            // the operator and the function, each x^3
            src: "x^3 + pow(x, 3)",
            points: &[-1.5, 0.0, 0.5, 2.0],
            f: |x| 2.0 * x * x * x,
            d1: |x| 6.0 * x * x,
            d2: |x| 12.0 * x,
            d3: |_| 12.0,
        },
        Case {
            src: "x^-2",
            points: &[-1.5, 0.5, 2.0],
            f: |x| 1.0 / (x * x),
            d1: |x| -2.0 / (x * x * x),
            d2: |x| 6.0 / (x * x * x * x),
            d3: |x| -24.0 / x.powi(5),
        },
        Case {
            src: "x^2.5",
            points: &[0.0, 0.5, 2.0],
            f: |x| x.powf(2.5),
            d1: |x| 2.5 * x.powf(1.5),
            d2: |x| 3.75 * x.sqrt(),
            d3: |x| 1.875 / x.sqrt(),
        },
        Case {
            src: "2^x",
            points: &[-1.0, 0.0, 1.5],
            f: |x| 2f64.powf(x),
            d1: |x| 2f64.powf(x) * LN_2,
            d2: |x| 2f64.powf(x) * LN_2 * LN_2,
            d3: |x| 2f64.powf(x) * LN_2 * LN_2 * LN_2,
        },
        Case {
            // general power with non-constant base and exponent
            src: "x^x",
            points: &[0.5, 1.0, 1.5],
            f: |x| x.powf(x),
            d1: |x| x.powf(x) * (x.ln() + 1.0),
            d2: |x| x.powf(x) * (sq(x.ln() + 1.0) + 1.0 / x),
            d3: |x| {
                let g = x.ln() + 1.0;
                x.powf(x) * (g * g * g + 3.0 * g / x - 1.0 / (x * x))
            },
        },
        Case {
            src: "pow(x, 1 + x)",
            points: &[0.5, 1.5],
            f: |x| x.powf(1.0 + x),
            // d/dx exp((1+x) ln x) = x^(1+x) (ln x + (1+x)/x)
            d1: |x| x.powf(1.0 + x) * (x.ln() + (1.0 + x) / x),
            d2: |x| {
                let g = x.ln() + (1.0 + x) / x;
                let dg = 1.0 / x - 1.0 / (x * x);
                x.powf(1.0 + x) * (g * g + dg)
            },
            d3: |x| {
                // f = exp(h), h = (1 + x) ln x: f''' = f (h'^3 + 3 h' h'' + h''')
                let g = x.ln() + (1.0 + x) / x;
                let dg = 1.0 / x - 1.0 / (x * x);
                let ddg = -1.0 / (x * x) + 2.0 / (x * x * x);
                x.powf(1.0 + x) * (g * g * g + 3.0 * g * dg + ddg)
            },
        },
        Case {
            src: "x / (1 + x^2)",
            points: &[-2.0, 0.0, 1.5],
            f: |x| x / (1.0 + x * x),
            d1: |x| (1.0 - x * x) / sq(1.0 + x * x),
            d2: |x| 2.0 * x * (x * x - 3.0) / (1.0 + x * x).powi(3),
            d3: |x| -6.0 * (x.powi(4) - 6.0 * x * x + 1.0) / (1.0 + x * x).powi(4),
        },
        Case {
            src: "exp(-x^2)*cos(3*x)",
            points: &[-1.0, 0.0, 0.4],
            f: |x| (-x * x).exp() * (3.0 * x).cos(),
            d1: |x| {
                let (g, c, s) = ((-x * x).exp(), (3.0 * x).cos(), (3.0 * x).sin());
                g * (-2.0 * x * c - 3.0 * s)
            },
            d2: |x| {
                let (g, c, s) = ((-x * x).exp(), (3.0 * x).cos(), (3.0 * x).sin());
                g * ((4.0 * x * x - 11.0) * c + 12.0 * x * s)
            },
            d3: |x| {
                let (g, c, s) = ((-x * x).exp(), (3.0 * x).cos(), (3.0 * x).sin());
                g * ((66.0 * x - 8.0 * x * x * x) * c + (45.0 - 36.0 * x * x) * s)
            },
        },
    ]
}

#[test]
fn every_builtin_function_is_covered_by_the_derivative_cases() {
    let all = cases();
    for &(name, _, _) in parse::FUNCTIONS {
        let call = format!("{name}(");
        assert!(all.iter().any(|c| c.src.contains(&call)), "no derivative test for '{name}'");
    }
}

#[test]
fn derivatives_match_closed_forms() {
    // Tolerance 1e-12 (relative, absolute near 0): AD is exact up to rounding, and
    // the closed forms are evaluated with a differently ordered handful of operations (a few
    // dozen roundings of 1.1e-16 each, amplified by at most the size of the terms over the
    // result's, which the points keep below a few hundred).
    for c in cases() {
        let e = parse(c.src);
        for &x in c.points {
            let what = format!("{} at x = {x}", c.src);
            let (f, d1, d2) = ((c.f)(x), (c.d1)(x), (c.d2)(x));
            assert_close(&format!("{what}: f64 value"), e.eval(&[x]), f, 1e-12);

            let d = e.eval(&[Dual::variable(x)]);
            assert_close(&format!("{what}: Dual value"), d.v, f, 1e-12);
            assert_close(&format!("{what}: Dual f'"), d.d, d1, 1e-12);

            let h = e.eval(&[HyperDual::variable(x)]);
            assert_close(&format!("{what}: HyperDual value"), h.v, f, 1e-12);
            assert_close(&format!("{what}: HyperDual e1"), h.e1, d1, 1e-12);
            assert_close(&format!("{what}: HyperDual e2"), h.e2, d1, 1e-12);
            assert_close(&format!("{what}: HyperDual f''"), h.e12, d2, 1e-12);

            // Different seeds a, b give a*f', b*f' and a*b*f''.
            let h = e.eval(&[HyperDual::seed(x, 2.0, -0.5)]);
            assert_close(&format!("{what}: seeded e1"), h.e1, 2.0 * d1, 1e-12);
            assert_close(&format!("{what}: seeded e2"), h.e2, -0.5 * d1, 1e-12);
            assert_close(&format!("{what}: seeded e12"), h.e12, -d2, 1e-12);

            // Seeds a, b, c give every part: the first derivative times one seed, the second
            // times two, the third times all three.
            let (a, b, c, d3) = (2.0, -0.5, 1.5, (c.d3)(x));
            let r = e.eval(&[Tri::new(x, [a, b, c], [0.0; 3], 0.0)]);
            let expected = [f, a * d1, b * d1, c * d1, a * b * d2, a * c * d2, b * c * d2, a * b * c * d3];
            for ((part, got), want) in
                ["v", "e1", "e2", "e3", "e12", "e13", "e23", "e123"].iter().zip(r.parts()).zip(expected)
            {
                if want.is_finite() {
                    assert_close(&format!("{what}: Tri {part}"), got, want, 1e-12);
                } else {
                    // x^2.5's third derivative at 0
                    assert_eq!(got, want, "{what}: Tri {part}");
                }
            }
        }
    }
}

#[test]
fn derivatives_match_finite_differences() {
    // Independent check using only plain f64 evaluations.
    //  f'  ~ (f(x+h) - f(x-h)) / 2h, h = 1e-5: truncation h^2 |f'''| / 6 ~ 2e-11 |f'''|,
    //       rounding ~ eps |f| / h ~ 2e-11 |f|  -> tolerance 1e-7 (relative/absolute).
    //  f'' ~ (f(x+h) - 2 f(x) + f(x-h)) / h^2, h = 1e-4: truncation h^2 |f''''| / 12
    //       ~ 1e-9 |f''''|, rounding ~ 4 eps |f| / h^2 ~ 1e-7 |f| -> tolerance 1e-5
    //       relative to 1 + |f''| + |f| (the rounding term scales with |f|).
    // Points where the function has a kink (abs, sign, min, max) are kept at a
    // distance > h from it.
    for c in cases() {
        let e = parse(c.src);
        let f = |x: f64| e.eval(&[x]);
        for &x in c.points {
            let what = format!("{} at x = {x}", c.src);
            let h = e.eval(&[HyperDual::variable(x)]);
            if c.src.contains("^2.5") && x == 0.0 {
                continue; // x^2.5 is not defined for x < 0
            }
            let h1 = 1e-5;
            let fd1 = (f(x + h1) - f(x - h1)) / (2.0 * h1);
            assert_close(&format!("{what}: f' vs FD"), h.e1, fd1, 1e-7);
            let h2 = 1e-4;
            let fd2 = (f(x + h2) - 2.0 * f(x) + f(x - h2)) / (h2 * h2);
            let scale = 1.0 + h.e12.abs() + h.v.abs();
            assert!((h.e12 - fd2).abs() <= 1e-5 * scale, "{what}: f'' = {:e} vs FD {fd2:e}", h.e12);
        }
    }
}

#[test]
fn integer_powers_exact_at_zero() {
    for src in ["x^2", "x**2", "pow(x, 2)", "x^(1+1)", "x*x"] {
        let h = parse(src).eval(&[HyperDual::variable(0.0)]);
        assert_eq!((h.v, h.e1, h.e12), (0.0, 0.0, 2.0), "{src}");
        let d = parse(src).eval(&[Dual::variable(0.0)]);
        assert_eq!((d.v, d.d), (0.0, 0.0), "{src}");
    }
    let h = parse("x^3").eval(&[HyperDual::variable(0.0)]);
    assert_eq!((h.v, h.e1, h.e12), (0.0, 0.0, 0.0));
    let h = parse("x^1").eval(&[HyperDual::variable(0.0)]);
    assert_eq!((h.v, h.e1, h.e12), (0.0, 1.0, 0.0));
    let h = parse("x^0").eval(&[HyperDual::variable(0.0)]);
    assert_eq!((h.v, h.e1, h.e12), (1.0, 0.0, 0.0));
    // negative bases with integer exponents are fine
    let h = parse("x^3").eval(&[HyperDual::variable(-2.0)]);
    assert_eq!((h.v, h.e1, h.e12), (-8.0, 12.0, -12.0));
    // exponents that are large integers still use the integer rule
    let h = parse("x^1000").eval(&[HyperDual::variable(-1.0)]);
    assert_eq!((h.v, h.e1, h.e12), (1.0, -1000.0, 999000.0));
}

// ---------------------------------------------------------------- TimeFunction

#[test]
fn time_function_linear() {
    let f = TimeFunction::parse("6.1506 + 2*pi*t").unwrap();
    assert!(!f.is_constant());
    for t in [0.0, 0.25, 1.5, -3.0] {
        let (v, dv, ddv) = f.eval(t);
        // same operation order as the folded bytecode: 6.1506 + (2π)·t
        assert_eq!(v, 6.1506 + 2.0 * PI * t);
        assert_eq!(dv, 2.0 * PI);
        assert_eq!(ddv, 0.0);
        assert_eq!(f.value(t), v);
    }
    assert_eq!(f.source(), "6.1506 + 2*pi*t");
    assert_eq!(f.to_string(), "6.1506 + 2*pi*t");
}

#[test]
fn time_function_sine() {
    let f: TimeFunction = "0.3*sin(4*t)".parse().unwrap();
    for t in [0.0, 0.1, 0.7, 2.0] {
        let (v, dv, ddv) = f.eval(t);
        assert_eq!(v, 0.3 * (4.0 * t).sin());
        assert_close("f'", dv, 1.2 * (4.0 * t).cos(), 1e-15);
        assert_close("f''", ddv, -4.8 * (4.0 * t).sin(), 1e-15);
    }
    assert_eq!(f.eval(0.0).0, 0.0);
    assert_eq!(f.eval(0.0).1, 1.2);
}

#[test]
fn time_function_constant_and_errors() {
    let f = TimeFunction::parse("2*pi").unwrap();
    assert!(f.is_constant());
    assert_eq!(f.eval(5.0), (2.0 * PI, 0.0, 0.0));
    assert_eq!(f.expr().constant_value(), Some(2.0 * PI));

    let err = TimeFunction::parse("2*crank.x").unwrap_err();
    assert_eq!(err.offset, 2);
    assert_eq!(err.to_string(), "unknown name 'crank.x' (only t (time) may appear in a driver function) at column 3");
}

// ---------------------------------------------------------------- gradient, directional2

#[test]
fn gradient_and_directional_of_circle() {
    let e = parse("crank.x^2 + crank.y^2 - 0.5625");
    let x = [0.6, 0.45, 9.0]; // slot 2 is unused by e
    let mut grad = [f64::NAN; 3];
    let mut work = [Dual::default(); 3];
    gradient(&e, &x, &mut grad, &mut work);
    // ∇ = (2x, 2y, 0)
    assert_eq!(grad, [1.2, 0.9, 0.0]);

    // H = diag(2, 2): dirᵀ H dir = 2 (d0² + d1²)
    let dir = [1.0, -2.0, 5.0];
    let mut hwork = [HyperDual::default(); 3];
    let (v, d1, d2) = directional2(&e, &x, &dir, &mut hwork);
    assert_close("value", v, 0.0, 1e-15);
    assert_close("∇·dir", d1, 1.2 - 1.8, 1e-15);
    assert_eq!(d2, 2.0 * (1.0 + 4.0));

    let mut sparse = [0.0; 2];
    let value = gradient_sparse(&e, &x, &mut sparse, &mut work);
    assert_eq!(sparse, [1.2, 0.9]);
    assert_eq!(value, e.eval(&x));
}

#[test]
fn gradient_and_directional_with_cross_terms() {
    let e = parse("a*b*sin(c)");
    let (a, b, c) = (1.3, -0.7, 0.9);
    let x = [a, b, c];
    let (s, co) = (c.sin(), c.cos());
    let mut grad = [0.0; 3];
    let mut work = [Dual::default(); 3];
    gradient(&e, &x, &mut grad, &mut work);
    let expected = [b * s, a * s, a * b * co];
    for (i, (g, x)) in grad.iter().zip(expected).enumerate() {
        assert_close(&format!("grad[{i}]"), *g, x, 1e-15);
    }

    // Hessian by hand:
    // [[0,        sin c,    b cos c],
    //  [sin c,    0,        a cos c],
    //  [b cos c,  a cos c,  -a b sin c]]
    let hess = [[0.0, s, b * co], [s, 0.0, a * co], [b * co, a * co, -a * b * s]];
    let mut hwork = [HyperDual::default(); 3];
    for dir in [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [0.3, -1.2, 2.0]] {
        let quad: f64 =
            (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| dir[i] * hess[i][j] * dir[j]).sum();
        let lin: f64 = (0..3).map(|i| expected[i] * dir[i]).sum();
        let (v, d1, d2) = directional2(&e, &x, &dir, &mut hwork);
        assert_close("value", v, a * b * s, 1e-15);
        assert_close(&format!("∇·{dir:?}"), d1, lin, 1e-14);
        assert_close(&format!("{dir:?}ᵀH{dir:?}"), d2, quad, 1e-14);
    }

    let mut sparse = [0.0; 3];
    let value = gradient_sparse(&e, &x, &mut sparse, &mut work);
    assert_eq!(sparse, grad);
    assert_eq!(value, a * b * s);
}

#[test]
fn atan2_gradient_and_hessian() {
    // θ = atan2(y, x): ∇ = (-y, x)/r² in (x, y) order; H = [[2xy, y²-x²], [y²-x², -2xy]]/r⁴
    let e = parse("atan2(y, x)");
    let (x0, y0) = (-0.8, 0.6);
    let r2: f64 = x0 * x0 + y0 * y0;
    let mut grad = [0.0; 2];
    gradient(&e, &[x0, y0], &mut grad, &mut [Dual::default(); 2]);
    assert_close("θ_x", grad[0], -y0 / r2, 1e-15);
    assert_close("θ_y", grad[1], x0 / r2, 1e-15);
    let h = [[2.0 * x0 * y0, y0 * y0 - x0 * x0], [y0 * y0 - x0 * x0, -2.0 * x0 * y0]];
    let dir = [0.5, 2.0];
    let quad = (dir[0] * dir[0] * h[0][0] + 2.0 * dir[0] * dir[1] * h[0][1] + dir[1] * dir[1] * h[1][1]) / (r2 * r2);
    let (_, _, d2) = directional2(&e, &[x0, y0], &dir, &mut [HyperDual::default(); 2]);
    assert_close("dirᵀHdir", d2, quad, 1e-14);
}

#[test]
fn constant_expression_gradient() {
    let e = parse("3 + 4");
    let mut grad = [1.0; 2];
    gradient(&e, &[1.0, 2.0], &mut grad, &mut [Dual::default(); 2]);
    assert_eq!(grad, [0.0, 0.0]);
    assert_eq!(gradient_sparse(&e, &[], &mut [], &mut []), 7.0);
    assert_eq!(directional2(&e, &[], &[], &mut []), (7.0, 0.0, 0.0));
}

// ---------------------------------------------------------------- errors

#[track_caller]
fn check_err(src: &str, offset: usize, message_part: &str) {
    let e = parse_err(src);
    assert_eq!(e.offset, offset, "{src}: {e}");
    assert!(e.message.contains(message_part), "{src}: message {:?} does not contain {message_part:?}", e.message);
}

/// Malformed expressions: the source, the byte offset the error points at, and words its
/// message must contain.
const ERRORS: &[(&str, usize, &str)] = &[
    // unexpected characters
    ("2 # 3", 2, "unexpected character '#'"),
    ("t × 2", 2, "unexpected character '×'"),
    ("x; y", 1, "unexpected character ';'"),
    ("crank.x = 1", 8, "unexpected character '='"),
    // unbalanced parentheses
    ("(1 + 2", 0, "unbalanced parentheses: '(' is never closed"),
    ("2 * ((x)", 4, "never closed"),
    ("1 + 2)", 5, "')' has no matching '('"),
    ("sin(x", 3, "never closed"),
    ("atan2(x, y", 5, "never closed"),
    ("(1 2)", 3, "expected ')' or an operator, found number '2'"),
    ("sin(x y)", 6, "expected ',' or ')' in the arguments of 'sin'"),
    // a missing operand
    ("1 +", 3, "missing operand"),
    ("1 + * 2", 4, "found '*'"),
    ("2 ^", 3, "found end of input"),
    ("2 **", 4, "missing operand"),
    ("-", 1, "missing operand"),
    ("()", 1, "found ')'"),
    ("atan2(1, )", 9, "missing operand"),
    ("* 2", 0, "missing operand"),
    // input after a complete expression
    ("1 2", 2, "unexpected number '2' after a complete expression"),
    ("2t", 1, "unexpected name 't' after a complete expression"),
    ("2 (y)", 2, "unexpected '('"),
    // a name directly followed by '(' is a function call
    ("x (y)", 0, "unknown function 'x'"),
    ("1.5.3", 3, "unexpected number '.3'"),
    ("1, 2", 1, "unexpected ','"),
    ("(1, 2)", 2, "expected ')' or an operator, found ','"),
    ("min((1, 2), 3)", 6, "expected ')' or an operator, found ','"),
    ("min(1 + 2 3)", 10, "expected ',' or ')' in the arguments of 'min'"),
    // unknown functions
    ("foo(1)", 0, "unknown function 'foo'"),
    ("2*crank.x(1)", 2, "unknown function 'crank.x'"),
    ("ln(2)", 0, "unknown function 'ln'"),
    ("1 + pi(2)", 4, "unknown function 'pi'"),
    ("sin + 1", 0, "function 'sin' needs its arguments in parentheses"),
    // the wrong number of arguments
    ("atan2(1)", 0, "function 'atan2' takes 2 arguments, found 1"),
    ("x + sin(1, 2)", 4, "function 'sin' takes 1 argument, found 2"),
    ("sin()", 0, "takes 1 argument, found 0"),
    ("pow(2)", 0, "takes 2 arguments, found 1"),
    ("min(1, 2, 3)", 0, "takes 2 arguments, found 3"),
    // an empty expression
    ("", 0, "empty expression"),
    ("   \n", 0, "empty expression"),
    // malformed names and numbers
    ("1e", 0, "malformed number"),
    ("2 + 1e+x", 4, "exponent has no digits"),
    ("1e999", 0, "out of range"),
    ("crank.", 6, "expected a letter or '_' after '.'"),
    ("crank.1", 6, "expected a letter or '_' after '.'"),
    ("a.b.c", 3, "only one '.'"),
];

#[test]
fn errors_point_at_the_mistake_and_name_it() {
    for &(src, offset, words) in ERRORS {
        check_err(src, offset, words);
    }
}

#[test]
fn error_unknown_name() {
    let e = parse_err("2*rokcer.x");
    assert_eq!(e.offset, 2);
    assert_eq!(e.column(), 3);
    assert_eq!(e.to_string(), "unknown name 'rokcer.x' (expected <body>.x, <body>.y, <body>.phi or t) at column 3");
    // without a hint
    let e = Expr::parse("1 + q", &mut |_| Err(String::new())).unwrap_err();
    assert_eq!(e.to_string(), "unknown name 'q' at column 5");
    assert_eq!(e, ExprError::new("unknown name 'q'", 4));
}

#[test]
fn error_snippet() {
    let src = "2*rokcer.x";
    let e = parse_err(src);
    assert_eq!(e.snippet(src), "2*rokcer.x\n  ^");
    let src = "x +\n  × 2";
    let e = parse_err(src);
    assert_eq!(e.snippet(src), "  × 2\n  ^");
    // offset at the end
    let e = parse_err("1 +");
    assert_eq!(e.snippet("1 +"), "1 +\n   ^");
}

#[test]
fn nesting_limit() {
    // exactly at the limit: deep but fine, evaluated over every scalar type
    let n = MAX_DEPTH;
    let src = format!("{}x{}", "(".repeat(n), ")".repeat(n));
    let e = parse(&src);
    assert_eq!(e.eval(&[Dual::variable(2.0)]), Dual::new(2.0, 1.0));
    let src = format!("{}x", "-".repeat(n));
    assert_eq!(parse(&src).eval(&[3.0]), 3.0);
    let src = format!("{}x{}", "sin(".repeat(n), ")".repeat(n));
    assert!(parse(&src).eval(&[HyperDual::variable(0.5)]).v > 0.0);
    // one more level is an error, reported where the extra level opens
    let src = format!("{}x{}", "(".repeat(n + 1), ")".repeat(n + 1));
    check_err(&src, n, "expression nested too deeply");
    let src = format!("{}x", "-".repeat(n + 1));
    check_err(&src, n, "expression nested too deeply");
    // levels of different kinds add up: 100 parentheses + 100 minus signs + 1 call
    let src = format!("{}{}sin(x){}", "(".repeat(100), "-".repeat(100), ")".repeat(100));
    check_err(&src, 200, "expression nested too deeply");
    // ... and closing a level frees it again
    let half = "(".repeat(150) + "x" + &")".repeat(150);
    assert_eq!(parse(&format!("{half} + {half}")).eval(&[2.0]), 4.0);

    // a deep product needs a large evaluation stack: x*(x*(x*...)) = x^k
    let k = 150;
    let src = format!("{}x{}", "x*(".repeat(k - 1), ")".repeat(k - 1));
    let e = parse(&src);
    let h = e.eval(&[HyperDual::variable(1.01)]);
    let kf = k as f64;
    assert_close("x^k", h.v, 1.01f64.powi(k as i32), 1e-12);
    assert_close("d x^k", h.e1, kf * 1.01f64.powi(k as i32 - 1), 1e-12);
    assert_close("dd x^k", h.e12, kf * (kf - 1.0) * 1.01f64.powi(k as i32 - 2), 1e-12);

    // far beyond the limit: an error, not a stack overflow or a hang
    for src in [
        format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000)),
        format!("{}1", "-".repeat(100_000)),
        format!("2{}", "^2".repeat(100_000)),
        format!("{}1{}", "sin(".repeat(100_000), ")".repeat(100_000)),
        "(".repeat(100_000),
    ] {
        let e = parse_err(&src);
        assert!(e.message.contains("nested too deeply"), "{e}");
        assert!(e.offset < 1000);
    }
}

#[test]
fn parsing_does_not_recurse() {
    // The parser keeps its own stack, so even the deepest accepted input parses on a
    // thread with a tiny call stack (a recursive-descent parser would need ~1 MB in a
    // debug build for 200 levels).
    let handle = std::thread::Builder::new()
        .stack_size(64 * 1024)
        .spawn(|| {
            let n = MAX_DEPTH;
            let deep = format!("{}t{}", "sin(".repeat(n), ")".repeat(n));
            let ok = TimeFunction::parse(&deep).is_ok();
            let too_deep = format!("{}t{}", "(".repeat(100_000), ")".repeat(100_000));
            ok && TimeFunction::parse(&too_deep).is_err()
        })
        .unwrap();
    assert!(handle.join().unwrap());
}

#[test]
fn long_flat_expressions_are_fine() {
    // long left-associative chains are parsed iteratively, without deep recursion
    let src = vec!["x"; 100_000].join(" + ");
    let e = parse(&src);
    assert_eq!(e.eval(&[Dual::variable(1.0)]), Dual::new(100_000.0, 100_000.0));
    let src = vec!["1"; 100_000].join(" * ");
    assert_eq!(parse(&src).constant_value(), Some(1.0));
}

#[test]
fn garbage_input_never_panics() {
    // Deterministic pseudo-random strings over the language's alphabet plus junk.
    let alphabet: Vec<char> = "0123456789.eE+-*/^(),xyzt pisncoqrtabgmw_.×#\n".chars().collect();
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut ok = 0;
    for _ in 0..20_000 {
        let len = (next() % 24) as usize;
        let s: String = (0..len).map(|_| alphabet[(next() % alphabet.len() as u64) as usize]).collect();
        match Expr::parse(&s, &mut test_resolve) {
            Ok(e) => {
                ok += 1;
                let _ = e.eval(&[HyperDual::variable(0.3); 3]);
            }
            Err(err) => {
                assert!(err.offset <= s.len(), "{s:?}: {err}");
                assert!(s.is_char_boundary(err.offset), "{s:?}: {err}");
                let _ = err.snippet(&s);
            }
        }
    }
    assert!(ok > 0);
}

// ---------------------------------------------------------------- motion laws and comparisons

/// Each law's largest normalized acceleration, the figure cam designers compare them by (Norton,
/// *Cam Design and Manufacturing Handbook*, table 3-2: 6 for the cubic, 5.777 for 3-4-5 (exactly
/// `10/sqrt(3)`), 2 pi for the cycloidal, pi^2/2 for the harmonic, 4.888 for the modified
/// trapezoid), sampled at 100,001 points; and
/// every law rises from 0 to 1, through 1/2 at the middle.
#[test]
fn motion_laws_have_their_textbook_peaks() {
    let peaks = [
        ("step", 6.0),
        ("step5", 10.0 / 3f64.sqrt()),
        ("poly345", 10.0 / 3f64.sqrt()),
        ("cycloidal", 2.0 * PI),
        ("harmonic", PI * PI / 2.0),
        ("modified_trapezoid", 8.0 * PI / (2.0 + PI)),
    ];
    for (law, peak) in peaks {
        let e = parse(&format!("{law}(x, 0, 0, 1, 1)"));
        let largest = (0..=100_000)
            .map(|k| e.eval(&[HyperDual::variable(k as f64 / 100_000.0)]).e12.abs())
            .fold(0.0f64, f64::max);
        // The cubic's peak is at its ends, where its acceleration falls at 12 per unit: the
        // samples nearest them, 1e-5 inside, see 6 (1 - 2e-5). The others' peaks are flat.
        let tol = if law == "step" { 3e-5 } else { 1e-8 };
        assert_close(&format!("{law}: peak acceleration"), largest, peak, tol);
        assert_close(&format!("{law}(0.5)"), e.eval(&[0.5]), 0.5, 1e-15);
        assert_eq!((e.eval(&[-1.0]), e.eval(&[0.0]), e.eval(&[1.0]), e.eval(&[2.0])), (0.0, 0.0, 1.0, 1.0), "{law}");
    }
    // A law with no rise (x1 <= x0) is NaN, which an analysis names as non-finite.
    assert!(val("step(0.5, 1, 0, 1, 2)").is_nan() && val("cycloidal(0.5, 2, 0, 1, 2)").is_nan());
    // Its ends may be expressions: d/dh1 of step at u = 1/2 is s(1/2) = 1/2.
    let e = parse("step(0.5, 0, 0, 1, x)");
    assert_close("d step / d h1", e.eval(&[Dual::variable(3.0)]).d, 0.5, 1e-15);
}

/// Comparisons are the loosest operators (`t - 1 > 0` compares `t - 1`), give 1 or 0 with no
/// derivative, and fold when constant; `=` alone and `!` alone are errors that say what to write.
#[test]
fn comparisons() {
    for (src, want) in [
        ("1 + 2 > 2", 1.0),
        ("2 < 1", 0.0),
        ("1 <= 1", 1.0),
        ("1 >= 2", 0.0),
        ("2 == 2", 1.0),
        ("2 != 2", 0.0),
        ("-1 < 0", 1.0),
        ("2 * 3 > 5 + 0.5", 1.0),
    ] {
        assert_eq!(val(src), want, "{src}");
    }
    let e = parse("x - 1 > 0");
    assert_eq!((e.eval(&[0.5]), e.eval(&[1.5])), (0.0, 1.0));
    assert_eq!(e.eval(&[Dual::variable(1.5)]).d, 0.0);
    assert!(parse("1 < 2").is_constant());
    assert!(parse_err("x = 1").message.contains("'=='"), "{}", parse_err("x = 1").message);
    assert_eq!(parse_err("x ! 1").offset, 2);
    assert!(parse_err("if(x, 1)").message.contains("takes 3 arguments"));
}

// ---------------------------------------------------------------- tables

/// A model's names for the table tests: the parameter `k` and the tables `lift` and `ramp`.
struct Tables {
    lift: std::sync::Arc<Spline>,
    ramp: std::sync::Arc<Spline>,
}

impl Names for Tables {
    fn constant(&self, name: &str) -> Option<f64> {
        (name == "k").then_some(2.0)
    }

    fn table(&self, name: &str) -> Option<std::sync::Arc<Spline>> {
        match name {
            "lift" => Some(self.lift.clone()),
            "ramp" => Some(self.ramp.clone()),
            _ => None,
        }
    }
}

fn tables() -> Tables {
    use spline::Method;
    let x: Vec<f64> = (0..9).map(|i| 0.25 * f64::from(i)).collect();
    let y = x.iter().map(|x| (2.0 * x).sin()).collect();
    Tables {
        lift: std::sync::Arc::new(Spline::new(x, y, Method::NotAKnot).unwrap()),
        ramp: std::sync::Arc::new(Spline::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 1.0], Method::Akima).unwrap()),
    }
}

#[test]
fn spline_carries_the_tables_derivatives_through_the_chain_rule() {
    let names = tables();
    let e = Expr::parse_with("k * spline(lift, x^2) + spline(ramp, x) + spline(lift, 1)", &names, &mut test_resolve)
        .unwrap();
    // The constant call is folded, the table used twice is stored once.
    assert_eq!(e.tables.len(), 2);
    let (lift, ramp) = (&names.lift, &names.ramp);
    for x in [0.3, 0.8, 1.1, 1.6] {
        let (l, l1, l2) = lift.eval(x * x);
        let (r, r1, r2) = ramp.eval(x);
        // d/dx s(x^2) = 2x s'(x^2); d2/dx2 = 2 s' + 4x^2 s''.
        let f = 2.0 * l + r + lift.eval(1.0).0;
        let d1 = 2.0 * 2.0 * x * l1 + r1;
        let d2 = 2.0 * (2.0 * l1 + 4.0 * x * x * l2) + r2;
        let h = e.eval(&[HyperDual::variable(x)]);
        // Rounding only: the same numbers combined in another order.
        assert_close("value", h.v, f, 1e-14);
        assert_close("f'", h.e1, d1, 1e-13);
        assert_close("f''", h.e12, d2, 1e-13);
        assert_eq!(e.eval(&[x]), h.v);
    }
}

#[test]
fn spline_needs_a_known_table_by_name() {
    let names = tables();
    let err = |src: &str| Expr::parse_with(src, &names, &mut test_resolve).unwrap_err();
    let e = err("spline(cam, t)");
    assert_eq!((e.message.as_str(), e.offset), ("unknown table 'cam' (tables are defined under tables:)", 7));
    assert!(err("spline(2, t)").message.contains("expected a table's name as the first argument of 'spline'"));
    assert!(err("spline(lift t)").message.contains("expected ',' after the table's name"));
    assert!(err("spline(lift, t, 1)").message.contains("function 'spline' takes 2 arguments, found 3"));
    assert!(err("spline + 1").message.contains("function 'spline' needs its arguments"));
    // Without tables (a bare closure of names) every table is unknown.
    assert!(parse_err("spline(lift, t)").message.contains("unknown table 'lift'"));
}

// ---------------------------------------------------------------- Tri

/// A two-variable case: `f(x, y)` with its closed-form mixed derivatives `f_xy`, `f_xxy`, `f_xyy`.
struct Mixed {
    src: &'static str,
    points: &'static [(f64, f64)],
    f_xy: fn(f64, f64) -> f64,
    f_xxy: fn(f64, f64) -> f64,
    f_xyy: fn(f64, f64) -> f64,
}

#[test]
fn tri_mixed_parts_of_two_variable_functions_match_closed_forms() {
    // Seeding x along (1, 0, a) and y along (0, 1, b) gives e12 = f_xy and
    // e123 = a f_xxy + b f_xyy. Tolerance 1e-12 as in derivatives_match_closed_forms.
    let r2 = |x: f64, y: f64| x * x + y * y;
    let cases = [
        Mixed {
            // atan2 = Im log(x + i y)
            src: "atan2(y, x)",
            points: &[(1.0, 0.5), (-0.7, 1.3), (-2.0, -0.4), (0.3, -1.1)],
            f_xy: |x, y| (y * y - x * x) / (x * x + y * y).powi(2),
            f_xxy: |x, y| 2.0 * (x * x * x - 3.0 * x * y * y) / (x * x + y * y).powi(3),
            f_xyy: |x, y| -2.0 * (y * y * y - 3.0 * x * x * y) / (x * x + y * y).powi(3),
        },
        Mixed {
            src: "hypot(x, y)",
            points: &[(1.0, 0.5), (-0.7, 1.3), (-2.0, -0.4), (0.3, -1.1)],
            f_xy: |x, y| -x * y / (x * x + y * y).powf(1.5),
            f_xxy: |x, y| y * (2.0 * x * x - y * y) / (x * x + y * y).powf(2.5),
            f_xyy: |x, y| x * (2.0 * y * y - x * x) / (x * x + y * y).powf(2.5),
        },
        Mixed {
            // x^y: f_xy = x^(y-1) (1 + y ln x)
            src: "pow(x, y)",
            points: &[(1.5, 0.5), (0.7, 2.3), (2.0, -0.4)],
            f_xy: |x, y| x.powf(y - 1.0) * (1.0 + y * x.ln()),
            f_xxy: |x, y| x.powf(y - 2.0) * ((y - 1.0) * (1.0 + y * x.ln()) + y),
            f_xyy: |x, y| x.powf(y - 1.0) * x.ln() * (2.0 + y * x.ln()),
        },
        Mixed {
            src: "sin(x*y)",
            points: &[(1.5, 0.5), (-0.7, 2.3), (2.0, -0.4)],
            f_xy: |x, y| (x * y).cos() - x * y * (x * y).sin(),
            f_xxy: |x, y| -2.0 * y * (x * y).sin() - x * y * y * (x * y).cos(),
            f_xyy: |x, y| -2.0 * x * (x * y).sin() - x * x * y * (x * y).cos(),
        },
        Mixed {
            // x y / (x + y): f_xy = 2 x y / (x + y)^3, whose derivatives are below.
            src: "x*y / (x + y)",
            points: &[(1.5, 0.5), (0.7, 2.3)],
            f_xy: |x, y| 2.0 * x * y / (x + y).powi(3),
            f_xxy: |x, y| 2.0 * y * (y - 2.0 * x) / (x + y).powi(4),
            f_xyy: |x, y| 2.0 * x * (x - 2.0 * y) / (x + y).powi(4),
        },
    ];
    let (a, b) = (0.8, -1.3);
    for c in cases {
        let e = parse(c.src);
        for &(x, y) in c.points {
            let what = format!("{} at ({x}, {y}) (r^2 = {})", c.src, r2(x, y));
            let r = e.eval(&[Tri::new(x, [1.0, 0.0, a], [0.0; 3], 0.0), Tri::new(y, [0.0, 1.0, b], [0.0; 3], 0.0)]);
            assert_eq!(r.v, e.eval(&[x, y]), "{what}: value");
            assert_close(&format!("{what}: e12"), r.e12, (c.f_xy)(x, y), 1e-12);
            let want = a * (c.f_xxy)(x, y) + b * (c.f_xyy)(x, y);
            assert_close(&format!("{what}: e123"), r.e123, want, 1e-12);
        }
    }
}

#[test]
fn tri_without_its_third_direction_is_a_hyperdual_bit_for_bit() {
    // The same sums in the same order: Tri's (v, e1, e2, e12) are HyperDual's exactly, and its
    // e3, e13, e23, e123 are 0, for every function and operation.
    let srcs = [
        "exp(-x^2)*cos(3*y) + atan2(x, y) - log(1 + x^2)/sqrt(2 + y)",
        "x^y + 2^x + pow(x, 2.5) + min(x, y) * max(y, tanh(x)) + abs(x - 1) * sign(y) + hypot(y, x)",
        "asin(x/2) + acos(y/3) + atan(x) + sinh(x) / cosh(y) + tan(x) / (1 + y) + x^-3",
        "step(x, 0, 1, y, 3) * cycloidal(y, 0, 1, 2, x) - modified_trapezoid(x*y, -1, 0, 1, 2) + if(x > y, x, y)",
    ];
    for src in srcs {
        let e = parse(src);
        for (x, y) in [(0.1, 1.35), (0.35, 0.8), (0.8, 1.9), (1.3, 0.45)] {
            let h = e.eval(&[HyperDual::new(x, 0.7, -1.2, 0.3), HyperDual::new(y, -0.4, 0.9, 1.1)]);
            let r = e.eval(&[
                Tri::new(x, [0.7, -1.2, 0.0], [0.3, 0.0, 0.0], 0.0),
                Tri::new(y, [-0.4, 0.9, 0.0], [1.1, 0.0, 0.0], 0.0),
            ]);
            let what = format!("{src} at ({x}, {y})");
            assert_eq!([r.v, r.e1, r.e2, r.e12], [h.v, h.e1, h.e2, h.e12], "{what}");
            assert_eq!([r.e3, r.e13, r.e23, r.e123], [0.0; 4], "{what}");
        }
    }
}

#[test]
fn tri_trajectory_seeds_time_twice_and_the_parameter_once() {
    let r = Tri::trajectory([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]);
    assert_eq!(r.parts(), [1.0, 2.0, 2.0, 4.0, 3.0, 5.0, 5.0, 6.0]);
    // x(t, p) = p t^2 at t = 2, p = 3: x_t = 2 p t, x_tt = 2 p, x_p = t^2, x_tp = 2 t, x_ttp = 2.
    let (t, p) = (Tri::trajectory([2.0, 1.0, 0.0], [0.0; 3]), Tri::trajectory([3.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    assert_eq!(p * t * t, Tri::trajectory([12.0, 12.0, 6.0], [4.0, 4.0, 2.0]));
}

#[test]
fn a_spline_through_a_cubic_has_the_cubics_third_derivative() {
    // The not-a-knot spline reproduces a cubic exactly, so spline(c, x) over Tri has the
    // cubic's derivatives: p = 2x^3 - x^2 + 3x, p''' = 12. Inside the table the third derivative
    // is the piece's (12 to rounding); outside, on the straight continuation, 0.
    let x: Vec<f64> = vec![-1.0, -0.3, 0.4, 1.0, 1.7, 2.5];
    let p = |x: f64| 2.0 * x * x * x - x * x + 3.0 * x;
    let y = x.iter().map(|&x| p(x)).collect();
    let table = std::sync::Arc::new(Spline::new(x, y, spline::Method::NotAKnot).unwrap());
    struct One(std::sync::Arc<Spline>);
    impl Names for One {
        fn constant(&self, _: &str) -> Option<f64> {
            None
        }
        fn table(&self, _: &str) -> Option<std::sync::Arc<Spline>> {
            Some(self.0.clone())
        }
    }
    let e = Expr::parse_with("spline(c, x)", &One(table), &mut test_resolve).unwrap();
    let (a, b, c) = (2.0, -0.5, 1.5);
    for x in [-0.8, 0.1, 0.9, 2.2] {
        let r = e.eval(&[Tri::new(x, [a, b, c], [0.0; 3], 0.0)]);
        assert_close(&format!("value at {x}"), r.v, p(x), 1e-12);
        assert_close(&format!("e13 at {x}"), r.e13, a * c * (12.0 * x - 2.0), 1e-11);
        assert_close(&format!("e123 at {x}"), r.e123, a * b * c * 12.0, 1e-10);
    }
    let outside = e.eval(&[Tri::new(3.0, [a, b, c], [0.0; 3], 0.0)]);
    assert_eq!((outside.e13, outside.e123), (0.0, 0.0));
}

// ---------------------------------------------------------------- parameters

/// A model's parameters for the tests: `(name, value)` in file order, each a parameter (also
/// the force elements' tests').
pub(crate) struct Params(pub(crate) Vec<(&'static str, f64)>);

impl Names for Params {
    fn constant(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
    }

    fn parameter(&self, name: &str) -> Option<usize> {
        self.0.iter().position(|(n, _)| *n == name)
    }
}

impl Params {
    /// The values in file order.
    fn values(&self) -> Vec<f64> {
        self.0.iter().map(|&(_, v)| v).collect()
    }

    /// The same parameters with `name` at `value`.
    fn with(&self, name: &str, value: f64) -> Params {
        Params(self.0.iter().map(|&(n, v)| (n, if n == name { value } else { v })).collect())
    }
}

#[test]
fn a_time_function_gives_its_parameter_derivatives_and_theirs_in_time_from_one_tri_evaluation() {
    // f = A sin(w t): with e1 = e2 along t and e3 along w,
    // e3 = f_w = A t cos(w t), e13 = f_tw = A cos(w t) - A w t sin(w t),
    // e123 = f_ttw = -2 A w sin(w t) - A w^2 t cos(w t). Tolerance 1e-12 as for the functions.
    let (a, w) = (0.7, 3.1);
    let names = Params(vec![("A", a), ("w", w)]);
    let f = TimeFunction::parse_with("A*sin(w*t)", &names).unwrap();
    assert_eq!(f.expr().parameters(), &[0, 1]);
    for t in [0.0, 0.4, 1.3, -2.2] {
        let params = [Tri::constant(a), Tri::trajectory([w, 0.0, 0.0], [1.0, 0.0, 0.0])];
        let r = f.eval_params(Tri::trajectory([t, 1.0, 0.0], [0.0; 3]), &params);
        let (s, c) = ((w * t).sin(), (w * t).cos());
        let what = format!("A sin(w t) at t = {t}");
        assert_eq!(r.v, f.value(t), "{what}: value");
        assert_close(&format!("{what}: f_t"), r.e1, a * w * c, 1e-12);
        assert_close(&format!("{what}: f_tt"), r.e12, -a * w * w * s, 1e-12);
        assert_close(&format!("{what}: f_w"), r.e3, a * t * c, 1e-12);
        assert_close(&format!("{what}: f_tw"), r.e13, a * c - a * w * t * s, 1e-12);
        assert_eq!(r.e13, r.e23, "{what}: e13 and e23 both seed time once and w once");
        assert_close(&format!("{what}: f_ttw"), r.e123, -2.0 * a * w * s - a * w * w * t * c, 1e-12);
        // Along A instead: f is linear in A.
        let params = [Tri::trajectory([a, 0.0, 0.0], [1.0, 0.0, 0.0]), Tri::constant(w)];
        let r = f.eval_params(Tri::trajectory([t, 1.0, 0.0], [0.0; 3]), &params);
        assert_close(&format!("{what}: f_A"), r.e3, s, 1e-12);
        assert_close(&format!("{what}: f_ttA"), r.e123, -w * w * s, 1e-12);
    }
}

/// Expressions in which parameters fold with numbers and with each other in every way the
/// compiler folds: arithmetic, functions, powers (a parameter as the base, as the exponent, and
/// an exponent of 1), motion laws, comparisons and tables.
const FOLDED: [&str; 6] = [
    "2*pi*w*t + (w*2 + 1)^2 * x - sin(w/3)",
    "x^n + n^2 * t + x^(n - 2) + t^(n/3)",
    "cycloidal(w, 0, 1, 5, h) * x + step(x, 0, h, w, 2*h)",
    "if(w > 3, w*x, x/w) + (h < w) * t + min(w, h) * max(h*x, t)",
    "spline(lift, w/4) * x + spline(lift, h*x)",
    "atan2(h, w) * x + hypot(w, h*t) + pow(x, w - h)",
];

/// The parameters of [`FOLDED`], in file order.
fn folded_params() -> Params {
    Params(vec![("w", 3.1), ("n", 3.0), ("h", 0.6)])
}

/// [`folded_params`] and the table `lift` of [`tables`].
struct ParamsAndTables(Params, Tables);

impl Names for ParamsAndTables {
    fn constant(&self, name: &str) -> Option<f64> {
        self.0.constant(name)
    }

    fn parameter(&self, name: &str) -> Option<usize> {
        self.0.parameter(name)
    }

    fn table(&self, name: &str) -> Option<std::sync::Arc<Spline>> {
        self.1.table(name)
    }
}

/// `vars`: `x` is slot 0 and `t` slot 1.
fn x_and_t(name: &str) -> Result<usize, String> {
    match name {
        "x" => Ok(0),
        "t" => Ok(1),
        _ => Err("expected x or t".into()),
    }
}

#[test]
fn parameter_derivatives_match_finite_differences_of_reparsed_expressions() {
    // Independent of the side program: each expression parsed again with one parameter moved
    // by +-h (h = 1e-6 relative) and evaluated plainly, a central difference. Its truncation is
    // h^2 |f'''| / 6 ~ 1e-12 and its rounding eps |f| / h ~ 1e-10 (relative to the values here,
    // all below 100): tolerance 1e-8, relative to 1 + |f_p|.
    let base = folded_params();
    for src in FOLDED {
        let names = ParamsAndTables(folded_params(), tables());
        let e = Expr::parse_with(src, &names, &mut x_and_t).unwrap();
        for (x, t) in [(0.7, 0.3), (1.4, 1.1)] {
            for (k, &(name, p)) in base.0.iter().enumerate() {
                let params: Vec<Dual> = base
                    .values()
                    .iter()
                    .enumerate()
                    .map(|(j, &v)| Dual::new(v, if j == k { 1.0 } else { 0.0 }))
                    .collect();
                let r = e.eval_params(&[Dual::constant(x), Dual::constant(t)], &params);
                let h = 1e-6 * p;
                let at = |v: f64| {
                    let names = ParamsAndTables(base.with(name, v), tables());
                    Expr::parse_with(src, &names, &mut x_and_t).unwrap().eval(&[x, t])
                };
                let fd = (at(p + h) - at(p - h)) / (2.0 * h);
                assert_close(&format!("{src}: d/d{name} at x = {x}, t = {t}"), r.d, fd, 1e-8);
            }
        }
    }
}

#[test]
fn plain_evaluation_is_unchanged_by_parameters_and_the_side_program_agrees_to_the_bit() {
    // The folded program is the same whether the names are parameters or plain values, and the
    // side program at the parameters' values gives the folded value exactly, over every type.
    let plain = folded_params();
    let values = plain.values();
    let as_values = |name: &str| plain.constant(name);
    for src in FOLDED {
        let with = Expr::parse_with(src, &ParamsAndTables(folded_params(), tables()), &mut x_and_t).unwrap();
        struct ValuesAndTables<'a>(&'a dyn Fn(&str) -> Option<f64>, Tables);
        impl Names for ValuesAndTables<'_> {
            fn constant(&self, name: &str) -> Option<f64> {
                (self.0)(name)
            }
            fn table(&self, name: &str) -> Option<std::sync::Arc<Spline>> {
                self.1.table(name)
            }
        }
        let without = Expr::parse_with(src, &ValuesAndTables(&as_values, tables()), &mut x_and_t).unwrap();
        assert_eq!(with.code, without.code, "{src}");
        assert!(without.parameters().is_empty() && without.side.is_none(), "{src}");
        assert!(!with.parameters().is_empty(), "{src}");
        // Positive bases: where a power's base is negative and its exponent moves, the
        // derivative along the exponent (and so the whole number) is NaN.
        for (x, t) in [(0.7, 0.3), (1.4, 1.1), (2.3, 0.4)] {
            let f = with.eval(&[x, t]);
            assert_eq!(with.eval_params(&[x, t], &values).to_bits(), f.to_bits(), "{src}");
            let seeded: Vec<Tri> = values.iter().map(|&v| Tri::new(v, [0.0, 0.0, 1.0], [0.0; 3], 0.0)).collect();
            let r = with.eval_params(&[Tri::new(x, [1.0, 1.0, 0.0], [0.0; 3], 0.0), Tri::constant(t)], &seeded);
            assert_eq!(r.v.to_bits(), f.to_bits(), "{src}");
            // Unseeded parameters: the side program's derivatives are the folded program's.
            let h = with.eval(&[HyperDual::variable(x), HyperDual::constant(t)]);
            let hp: Vec<HyperDual> = values.iter().map(|&v| HyperDual::constant(v)).collect();
            assert_eq!(with.eval_params(&[HyperDual::variable(x), HyperDual::constant(t)], &hp), h, "{src}");
        }
    }
}

#[test]
fn a_parameter_exponent_keeps_the_integer_power_rule_and_moves_where_the_base_is_positive() {
    let names = Params(vec![("n", 2.0)]);
    let e = Expr::parse_with("x^n", &names, &mut x_and_t).unwrap();
    // A negative base with an integer exponent: the folded rule x^2, exact.
    let r = e.eval_params(&[Dual::variable(-1.5)], &[Dual::constant(2.0)]);
    assert_eq!((r.v, r.d), (2.25, -3.0));
    // Along n at x > 0: d/dn x^n = x^n ln x; d2/dx dn = x^(n-1) (1 + n ln x).
    let x = 1.7;
    let r = e.eval_params(&[HyperDual::seed(x, 1.0, 0.0)], &[HyperDual::seed(2.0, 0.0, 1.0)]);
    assert_eq!(r.v, x * x);
    assert_close("x^n: d/dn", r.e2, x * x * x.ln(), 1e-12);
    assert_close("x^n: d2/dx dn", r.e12, x * (1.0 + 2.0 * x.ln()), 1e-12);
}

#[test]
fn an_expression_without_parameters_evaluates_the_same_with_them() {
    let e = parse("sin(x) * y");
    assert!(e.parameters().is_empty());
    let r = e.eval_params(&[Dual::variable(0.4), Dual::constant(2.0)], &[]);
    assert_eq!(r, e.eval(&[Dual::variable(0.4), Dual::constant(2.0)]));
}
