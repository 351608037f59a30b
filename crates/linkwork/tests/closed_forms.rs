//! Kinematic analysis against closed forms. Tolerance 1e-10 (relative above magnitude 1): Newton
//! stops at |Phi| <= 1e-12 and these Jacobians amplify that by at most ~100, so the positions are
//! good to ~1e-10 or better, and velocities and accelerations come from exact linear solves at
//! those positions.

mod common;

use common::{c, check_coordinate, run, sq};
use linkwork::expr::{HyperDual, Scalar};
use std::f64::consts::PI;

const TOL: f64 = 1e-10;

/// Centred slider-crank, r = 0.1, L = 0.3, theta = 2 pi t:
/// `sin(beta) = -r sin(theta) / L`, `x_B = r cos(theta) + L cos(beta)`.
#[test]
fn slider_crank_matches_closed_form() {
    let (_, r) = run("slider_crank.yaml", "kinematics");
    assert_eq!(r.len(), 201);
    let (rc, l) = (0.1, 0.3);
    let theta = |t: HyperDual| t * c(2.0 * PI);
    let beta = move |t: HyperDual| (theta(t).sin() * c(-rc / l)).asin();
    let slider_x = move |t: HyperDual| theta(t).cos() * c(rc) + beta(t).cos() * c(l);
    check_coordinate(&r, "slider", "x", slider_x, TOL);
    check_coordinate(&r, "slider", "y", |_| c(0.0), TOL);
    check_coordinate(&r, "slider", "phi", |_| c(0.0), TOL);
    check_coordinate(&r, "rod", "phi", beta, TOL);
    // The rod's centre: crank pin plus half the rod.
    check_coordinate(&r, "rod", "x", move |t| theta(t).cos() * c(rc) + beta(t).cos() * c(l / 2.0), TOL);
    check_coordinate(&r, "rod", "y", move |t| theta(t).sin() * c(rc) + beta(t).sin() * c(l / 2.0), TOL);
    check_coordinate(&r, "crank", "phi", theta, TOL);
    check_coordinate(&r, "crank", "x", move |t| theta(t).cos() * c(rc / 2.0), TOL);
}

/// Grashof crank-rocker: a = 0.1, b = 0.3, c = 0.25, d = 0.3, theta2 = 2t. Open assembly:
/// `theta3 = atan2(O4 - A) + acos((b^2 + |O4 - A|^2 - c^2) / (2 b |O4 - A|))`,
/// `theta4 = atan2(B - O4)` (Norton, Design of Machinery, section 4.5).
#[test]
fn fourbar_matches_closed_form() {
    let (_, r) = run("fourbar.yaml", "kinematics");
    let (a, b, cc, d) = (0.1, 0.3, 0.25, 0.3);
    let theta2 = |t: HyperDual| t * c(2.0);
    let pin_a = move |t: HyperDual| (theta2(t).cos() * c(a), theta2(t).sin() * c(a));
    let theta3 = move |t: HyperDual| {
        let (ax, ay) = pin_a(t);
        let (dx, dy) = (c::<HyperDual>(d) - ax, -ay);
        let delta = (sq(dx) + sq(dy)).sqrt();
        dy.atan2(dx) + ((c::<HyperDual>(b * b - cc * cc) + sq(delta)) / (delta * c(2.0 * b))).acos()
    };
    let pin_b = move |t: HyperDual| {
        let (ax, ay) = pin_a(t);
        (ax + theta3(t).cos() * c(b), ay + theta3(t).sin() * c(b))
    };
    let theta4 = move |t: HyperDual| {
        let (bx, by) = pin_b(t);
        by.atan2(bx - c(d))
    };
    check_coordinate(&r, "coupler", "phi", theta3, TOL);
    check_coordinate(&r, "rocker", "phi", theta4, TOL);
    check_coordinate(&r, "crank", "phi", theta2, TOL);
    check_coordinate(&r, "coupler", "x", move |t| pin_a(t).0 + theta3(t).cos() * c(b / 2.0), TOL);
    check_coordinate(&r, "coupler", "y", move |t| pin_a(t).1 + theta3(t).sin() * c(b / 2.0), TOL);
    check_coordinate(&r, "rocker", "x", move |t| theta4(t).cos() * c(cc / 2.0) + c(d), TOL);
    check_coordinate(&r, "rocker", "y", move |t| theta4(t).sin() * c(cc / 2.0), TOL);
}

/// Ellipse trammel, psi = 0.3 + 1.5 t + 0.2 sin 3t: A = (cos psi, 0), B = (0, -sin psi), bar
/// centre (cos psi / 2, -sin psi / 2); the bar point P = (0.25, 0) traces an ellipse of semi-axes
/// 0.75 and 0.25.
#[test]
fn ellipse_trammel_matches_closed_form() {
    let (_, r) = run("ellipse_trammel.yaml", "kinematics");
    let psi = |t: HyperDual| c::<HyperDual>(0.3) + t * c(1.5) + (t * c(3.0)).sin() * c(0.2);
    check_coordinate(&r, "slider_a", "x", move |t| psi(t).cos(), TOL);
    check_coordinate(&r, "slider_b", "y", move |t| -psi(t).sin(), TOL);
    check_coordinate(&r, "bar", "x", move |t| psi(t).cos() * c(0.5), TOL);
    check_coordinate(&r, "bar", "y", move |t| psi(t).sin() * c(-0.5), TOL);
    check_coordinate(&r, "bar", "phi", psi, TOL);
    let (x, y, phi) = (r.column("bar.x").unwrap(), r.column("bar.y").unwrap(), r.column("bar.phi").unwrap());
    for k in 0..r.len() {
        let (px, py) = (x[k] + 0.25 * phi[k].cos(), y[k] + 0.25 * phi[k].sin());
        let e = (px / 0.75).powi(2) + (py / 0.25).powi(2) - 1.0;
        assert!(e.abs() < 1e-10, "P off the ellipse by {e} at t = {}", r.time[k]);
    }
}

/// Angles are unwrapped: the crank of the four-bar turns two full turns and its angle grows
/// past 2 pi instead of folding back.
#[test]
fn angles_are_unwrapped() {
    let (_, r) = run("fourbar.yaml", "kinematics");
    let phi = r.column("crank.phi").unwrap();
    assert!(*phi.last().unwrap() > 4.0 * PI - 0.1, "crank angle at the end: {}", phi.last().unwrap());
    assert!(phi.windows(2).all(|w| (w[1] - w[0]).abs() < 0.5), "a jump in crank.phi");
}
