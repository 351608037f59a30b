//! The project's worked example, modelled twice: model A (5 bodies, two sliders, 14 equations) and
//! model B (3 bodies, pin-in-slot joints, 8 equations) describe the same crank, rocker and link
//! motion through different equations, so their agreement checks both formulations.

mod common;

use common::{close, example, run};
use linkwork::analysis::check;
use linkwork::Model;

/// 1e-10 (relative above magnitude 1): each model is solved to |Phi| <= 1e-12 and its Jacobian
/// amplifies that by at most ~300 (the largest condition estimate the run reports).
#[test]
fn models_a_and_b_agree() {
    let (_, a) = run("quick_return_a.yaml", "kinematics");
    let (_, b) = run("quick_return_b.yaml", "kinematics");
    assert_eq!(a.len(), 41, "0 to 2 s every 0.05 s");
    assert_eq!(a.time, b.time);
    let mut compared = 0;
    for body in ["crank", "rocker", "link"] {
        for q in linkwork::results::BODY_QUANTITIES {
            let name = format!("{body}.{q}");
            let (ca, cb) = (a.column(&name).unwrap(), b.column(&name).unwrap());
            for k in 0..a.len() {
                assert!(close(ca[k], cb[k], 1e-10), "{name} at t = {}: A {} B {}", a.time[k], ca[k], cb[k]);
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 27);
    // The mechanism really moves: the rocker swings and the link's end sweeps the stroke.
    let rocker = a.column("rocker.phi").unwrap();
    let swing = rocker.iter().cloned().fold(f64::MIN, f64::max) - rocker.iter().cloned().fold(f64::MAX, f64::min);
    assert!(swing > 0.5, "rocker swing {swing}");
}

/// Model A's sliders follow model B's geometry: slider_d stays on y = 2 with the link's end, and
/// slider_b stays on the crank pin.
#[test]
fn sliders_follow_the_pins() {
    let (_, a) = run("quick_return_a.yaml", "kinematics");
    let y = a.column("slider_d.y").unwrap();
    assert!(y.iter().all(|v| (v - 2.0).abs() < 1e-11), "slider_d leaves its guide");
    let (cx, cy, cp) = (a.column("crank.x").unwrap(), a.column("crank.y").unwrap(), a.column("crank.phi").unwrap());
    let (bx, by) = (a.column("slider_b.x").unwrap(), a.column("slider_b.y").unwrap());
    for k in 0..a.len() {
        let (px, py) = (cx[k] - 0.75 * cp[k].cos(), cy[k] - 0.75 * cp[k].sin());
        assert!((px - bx[k]).abs() < 1e-11 && (py - by[k]).abs() < 1e-11);
    }
}

/// Crank angle: its assembled value plus 2 pi t, exactly as the driver says.
#[test]
fn crank_follows_its_driver() {
    let (_, a) = run("quick_return_a.yaml", "kinematics");
    let (phi, omega) = (a.column("crank.phi").unwrap(), a.column("crank.omega").unwrap());
    for (k, t) in a.time.iter().enumerate() {
        assert!((phi[k] - (6.1506 + 2.0 * std::f64::consts::PI * t)).abs() < 1e-12);
        assert!((omega[k] - 2.0 * std::f64::consts::PI).abs() < 1e-12);
    }
}

/// `linkwork check`: one degree of freedom without the driver, none with it, for both models;
/// Gruebler's count agrees (no redundancy).
#[test]
fn degrees_of_freedom() {
    for (file, equations) in [("quick_return_a.yaml", 14), ("quick_return_b.yaml", 8)] {
        let model = Model::load(example(file)).unwrap();
        let report = check(&model).unwrap();
        assert_eq!(report.mechanism.equations, equations, "{file}");
        assert_eq!(report.mechanism.dof, 1, "{file}");
        assert_eq!(report.mechanism.gruebler_dof, 1, "{file}");
        assert!(report.mechanism.redundant.is_empty(), "{file}");
        let driven = report.analyses["kinematics"].system.as_ref().expect("assembles with its driver");
        assert_eq!(driven.dof, 0, "{file}");
        assert!(report.analyses["kinematics"].warning.is_none());
        // Assembly held the crank angle and moved the rest onto the constraints.
        let a = &report.mechanism.assembly;
        assert!(a.residual <= 1e-12);
        assert_eq!(a.change[2], 0.0, "crank angle is given and must not move");
        assert!(a.change.iter().any(|c| c.abs() > 1e-4), "the rough guess needed correcting");
    }
}
