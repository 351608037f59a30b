//! Checks and failures: redundant rows named, a lock-up reported with time and joints and the
//! results before it kept, and a model that is not fully driven refused.

mod common;

use common::{example, run};
use linkwork::analysis::check;
use linkwork::{Error, Model};

/// A parallelogram with a third parallel link: Gruebler says 0, the rank says 1, and one row of
/// the third link's joints is redundant. The kinematic analysis still runs, and the coupler stays
/// parallel to the ground (its angle is 0 throughout).
#[test]
fn redundant_parallelogram() {
    let model = Model::load(example("parallelogram.yaml")).unwrap();
    let report = check(&model).unwrap();
    let mech = &report.mechanism;
    assert_eq!(mech.gruebler_dof, 0);
    assert_eq!(mech.dof, 1);
    assert_eq!(mech.redundant.len(), 1, "{:?}", mech.redundant);
    assert!(["ground_3", "coupler_3"].contains(&mech.redundant[0].element.as_str()), "{:?}", mech.redundant);
    let driven = report.analyses["kinematics"].system.as_ref().expect("assembles with its driver");
    assert_eq!((driven.dof, driven.redundant.len()), (0, 1));

    let (_, r) = run("parallelogram.yaml", "kinematics");
    assert_eq!(r.len(), 41);
    let coupler = r.column("coupler.phi").unwrap();
    assert!(coupler.iter().all(|p| p.abs() < 1e-11), "coupler turned");
    // All three cranks turn together, so the redundant link's pins stay together.
    for name in ["crank_2.phi", "crank_3.phi"] {
        let (a, b) = (r.column("crank_1.phi").unwrap(), r.column(name).unwrap());
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-10), "{name}");
    }
    let stats = &r.summary["statistics"]["redundant_rows"];
    assert_eq!(stats.as_array().map(|a| a.len()), Some(1));
}

/// The rod (0.12 m) is shorter than the crank (0.2 m): lock-up at theta = asin(0.6), t = 0.6435 s.
#[test]
fn lockup_is_reported_with_time_joints_and_partial_results() {
    let model = Model::load(example("slider_crank_lockup.yaml")).unwrap();
    let failure = model.run("kinematics").expect_err("the mechanism locks up");
    let t_lock = 0.6f64.asin();
    match &failure.error {
        Error::Singular { time, rows, .. } => {
            assert!(*time < t_lock && t_lock - time < 1e-4, "stopped at {time}, lock-up at {t_lock}");
            assert!(!rows.is_empty());
            let joints = failure.error.elements();
            assert!(joints.iter().any(|j| ["A", "B", "guide"].contains(&j.as_str())), "{joints:?}");
        }
        other => panic!("expected a singular position, got {other}"),
    }
    // Every output time before the lock-up, and none after.
    let r = &failure.results;
    assert_eq!(r.len(), 13, "t = 0, 0.05, ..., 0.6");
    assert!((r.time.last().unwrap() - 0.6).abs() < 1e-12);
    let msg = failure.error.to_string();
    assert!(msg.contains("t = 0.64") && msg.contains("singular"), "{msg}");
}

/// Without its driver the quick-return mechanism keeps one degree of freedom: a kinematic
/// analysis is refused with a model error naming the analysis and how many drivers are missing.
#[test]
fn kinematic_analysis_needs_a_fully_driven_model() {
    let text = std::fs::read_to_string(example("quick_return_b.yaml"))
        .unwrap()
        .replace("drivers: [crank_drive]", "drivers: []");
    let model = Model::from_yaml(&text).unwrap();
    let failure = model.run("kinematics").expect_err("not fully driven");
    match &failure.error {
        Error::Model(problems) => {
            assert_eq!(problems.len(), 1);
            assert_eq!(problems[0].path, "analyses.kinematics.drivers");
            assert!(problems[0].message.contains("add 1 driver"), "{}", problems[0].message);
        }
        other => panic!("expected a model error, got {other}"),
    }
}

/// An analysis whose drivers cannot be met does not sink the report: the mechanism alone and the
/// other analyses are still checked.
#[test]
fn an_analysis_that_cannot_assemble_is_reported_in_its_entry() {
    let text = std::fs::read_to_string(example("quick_return_b.yaml")).unwrap().replace(
        "analyses:\n",
        "  too_far: {type: angle, body: rocker, function: \"9\"}\nanalyses:\n  clash: {type: kinematic, drivers: [crank_drive, too_far], t_end: 1, step: 0.1}\n",
    );
    let model = Model::from_yaml(&text).unwrap();
    let report = check(&model).unwrap();
    assert_eq!(report.mechanism.dof, 1);
    let clash = &report.analyses["clash"];
    assert!(clash.system.is_none());
    assert!(clash.error.as_deref().unwrap_or_default().contains("assembly at t = 0 s failed"), "{:?}", clash.error);
    assert_eq!(report.analyses["kinematics"].system.as_ref().map(|s| s.dof), Some(0));
    assert_eq!(report.coordinate_names[..3], ["crank.x", "crank.y", "crank.phi"]);
}
