//! Scale-free numerics (docs/kinematics.md, "Scale"): a mechanism with every length multiplied
//! by `s` has the same degrees of freedom, runs the same analyses and gives the same positions
//! multiplied by `s`, from 1e-6 to 1e6, because every rank, singularity and convergence test
//! reads the constraint Jacobian and residual scaled by the model's length scale.

use linkwork::analysis::check;
use linkwork::Model;
use serde_yaml_ng::Value;

/// Multiply every number of the sequence `v` by `s`.
fn scale_points(v: &mut Value, s: f64) {
    if let Value::Sequence(seq) = v {
        for x in seq.iter_mut() {
            if let Some(f) = x.as_f64() {
                *x = Value::from(f * s);
            }
        }
    }
}

/// The model `text` with every length multiplied by `s`: body positions, points and the joints'
/// points given by coordinates; each inertia by `s^2` and each mass left, so that every body's
/// radius of gyration scales with it (the mass matrix stays that of the same bodies, scaled). A
/// kinematic analysis reads neither; the angles and the drivers' angles stay.
fn scaled(text: &str, s: f64) -> String {
    let mut doc: Value = serde_yaml_ng::from_str(text).unwrap();
    for (_, body) in doc["bodies"].as_mapping_mut().unwrap().iter_mut() {
        scale_points(&mut body["position"], s);
        if let Some(points) = body.get_mut("points").and_then(Value::as_mapping_mut) {
            points.iter_mut().for_each(|(_, p)| scale_points(p, s));
        }
        let i = body["inertia"].as_f64().unwrap();
        body["inertia"] = Value::from(i * s * s);
    }
    for (_, joint) in doc["joints"].as_mapping_mut().unwrap().iter_mut() {
        for key in ["point_i", "point_j"] {
            if let Some(p) = joint.get_mut(key) {
                scale_points(p, s);
            }
        }
    }
    serde_yaml_ng::to_string(&doc).unwrap()
}

/// `text` with its crank turning at 1 rev/s, a flywheel on an axle at the origin (free to turn:
/// only its inertia resists), and a dynamic analysis of the free mechanism (`free`, 0.05 s).
fn with_dynamics(text: &str) -> String {
    let mut doc: Value = serde_yaml_ng::from_str(text).unwrap();
    doc["bodies"]["crank"]["omega"] = Value::from(std::f64::consts::TAU);
    let wheel: Value = serde_yaml_ng::from_str("{mass: 1.0, inertia: 0.001, position: [0, 0], angle: 0}").unwrap();
    doc["bodies"].as_mapping_mut().unwrap().insert(Value::from("flywheel"), wheel);
    let axle: Value =
        serde_yaml_ng::from_str("{type: revolute, body_i: flywheel, point_i: [0, 0], body_j: ground, point_j: [0, 0]}")
            .unwrap();
    doc["joints"].as_mapping_mut().unwrap().insert(Value::from("axle"), axle);
    let free: Value = serde_yaml_ng::from_str("{type: dynamic, drivers: [], t_end: 0.05, step: 0.01}").unwrap();
    doc["analyses"].as_mapping_mut().unwrap().insert(Value::from("free"), free);
    serde_yaml_ng::to_string(&doc).unwrap()
}

/// The slider-crank example scaled by 1e-6, 1e-3, 1e3 and 1e6 (and 1e-4, 1e4: a 10 um and a
/// 4 km mechanism) against itself: one degree of freedom alone and none with its motor,
/// its kinematics runs to the end, and every output position equals the unscaled one times `s`
/// (angles equal) to 1e-12 of the largest position (angle) of the run. Rank, singularity and
/// residual tests in absolute units fail it: they refuse the model at 1e-6, 1e-4 and 1e4 ("1
/// degree(s) of freedom remain ... add 1 driver(s)"), fail its assembly at 1e6, and at 1e-3 move
/// the positions by 1.7e-10 (Newton stopping at 1e-12 m, a thousand times looser relative to the
/// model). Why 1e-12 holds: scaled
/// to be free of units, every decision of the solvers (ranks, stops, sub-steps) is the same at
/// every scale, so the runs do the same arithmetic on numbers that differ by the rounding of
/// `s` times the inputs (half a unit, `1.1e-16`), grown by the conditioning of the mechanism
/// (below 1e2 here) and the few hundred sub-steps; measured, they agree to `4e-16`.
#[test]
fn the_slider_crank_scaled_from_1e_6_to_1e6_has_the_same_freedom_and_positions() {
    let text =
        std::fs::read_to_string(format!("{}/../../examples/slider_crank.yaml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let reference = Model::from_yaml(&text).unwrap().run("kinematics", &Default::default()).unwrap();
    // The largest position (m) and angle (rad) of the run: "relative" is to the mechanism's size,
    // not to each coordinate (the slider's y is zero up to round-off).
    let size = |quantity: &str| {
        let names = reference.names.iter().filter(|n| n.ends_with(quantity));
        names.flat_map(|n| reference.column(n).unwrap()).fold(0.0f64, |a, x| a.max(x.abs()))
    };
    let (length, angle) = (size(".x").max(size(".y")), size(".phi"));
    for s in [1e-6, 1e-4, 1e-3, 1e3, 1e4, 1e6] {
        let model = Model::from_yaml(&scaled(&text, s)).unwrap();
        let report = check(&model).unwrap();
        let driven = report.analyses["kinematics"].system.as_ref().unwrap_or_else(|| panic!("scale {s:e}: {report:?}"));
        assert_eq!((report.mechanism.dof, driven.dof), (1, 0), "scale {s:e}");
        assert!(report.mechanism.redundant.is_empty() && driven.redundant.is_empty(), "scale {s:e}");
        let run = model.run("kinematics", &Default::default()).unwrap_or_else(|f| panic!("scale {s:e}: {}", f.error));
        assert_eq!(run.time, reference.time, "scale {s:e}");
        // Its dynamics runs too, with a flywheel: the massless-motion check compared inertias
        // (kg m^2) with masses (kg), so at 1e-6 the flywheel's inertia (1e-15 kg m^2) counted as
        // none and its free turning was refused as a motion no mass resists.
        let free = Model::from_yaml(&scaled(&with_dynamics(&text), s)).unwrap();
        let dynamics = free.run("free", &Default::default()).unwrap_or_else(|f| panic!("scale {s:e}: {}", f.error));
        assert_eq!(dynamics.summary.dof, Some(2), "scale {s:e}");
        for name in &reference.names {
            let Some(quantity) = [".x", ".y", ".phi"].into_iter().find(|q| name.ends_with(q)) else { continue };
            let (factor, size) = if quantity == ".phi" { (1.0, angle) } else { (s, length) };
            let (want, got) = (reference.column(name).unwrap(), run.column(name).unwrap());
            for (w, g) in want.iter().zip(got) {
                assert!((g / factor - w).abs() <= 1e-12 * size, "scale {s:e}, {name}: {} against {w}", g / factor);
            }
        }
    }
}
