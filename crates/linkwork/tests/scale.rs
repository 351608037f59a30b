//! Large mechanisms (docs/performance.md, "Scale"): the IFToMM N-four-bar, whose constraint
//! Jacobian goes to the sparse Gram factorization above `DENSE_MAX_ENTRIES`, checks, assembles
//! and runs as a small one does, its redundant and indeterminate rows named alike.

use linkwork::analysis::check;
use linkwork::linalg::rows::DENSE_MAX_ENTRIES;
use linkwork::Model;

/// The N-four-bar of `examples/nfourbar.py` (IFToMM A02: N + 1 vertical rockers of 1 m hinged at
/// x = 0..N, N horizontal couplers joining their tops, every bar 1 kg), with, when `extra`, a
/// third parallel rocker under the first coupler's centre: a redundant link, as in
/// `examples/parallelogram.yaml`.
fn nfourbar(n: usize, extra: bool) -> String {
    let mut text = String::from("name: N-four-bar\ngravity: [0, -9.81]\nbodies:\n");
    let bar = "mass: 1, inertia: 0.08333333333333333";
    for k in 0..=n {
        let given = if k == 0 { ", given: [phi, omega]" } else { "" };
        text += &format!(
            "  r{k}: {{{bar}, position: [{k}, 0.5], angle: 1.5707963267948966, velocity: [0.5, 0], omega: -1, points: {{A: [-0.5, 0], B: [0.5, 0]}}{given}}}\n"
        );
    }
    for k in 1..=n {
        text += &format!(
            "  c{k}: {{{bar}, position: [{}, 1], angle: 0, velocity: [1, 0], points: {{L: [-0.5, 0], R: [0.5, 0]}}}}\n",
            k as f64 - 0.5
        );
    }
    if extra {
        text += &format!("  e: {{{bar}, position: [0.5, 0.5], angle: 1.5707963267948966, velocity: [0.5, 0], omega: -1, points: {{A: [-0.5, 0], B: [0.5, 0]}}}}\n");
    }
    text += "joints:\n";
    for k in 0..=n {
        text += &format!("  A{k}: {{type: revolute, body_i: r{k}, point_i: A, body_j: ground, point_j: [{k}, 0]}}\n");
    }
    for k in 1..=n {
        text += &format!("  L{k}: {{type: revolute, body_i: c{k}, point_i: L, body_j: r{}, point_j: B}}\n", k - 1);
        text += &format!("  R{k}: {{type: revolute, body_i: c{k}, point_i: R, body_j: r{k}, point_j: B}}\n");
    }
    if extra {
        text += "  EA: {type: revolute, body_i: e, point_i: A, body_j: ground, point_j: [0.5, 0]}\n";
        text += "  EB: {type: revolute, body_i: e, point_i: B, body_j: c1, point_j: [0, 0]}\n";
    }
    text += "analyses:\n  dynamics: {type: dynamic, t_end: 0.5, step: 0.05}\n";
    text
}

fn entries(model: &Model) -> usize {
    // Equations (two a revolute joint) times coordinates.
    2 * model.joints.len() * model.n()
}

/// The small chain (N = 2) goes to the dense SVD and the large one (N = 60) to the Gram
/// factorization; both find one degree of freedom, name the same row of the extra rocker's
/// joint as redundant, and the same joints as sharing the load indeterminately.
#[test]
fn a_large_chain_names_its_redundant_link_as_a_small_one_does() {
    let (small, large) =
        (Model::from_yaml(&nfourbar(2, true)).unwrap(), Model::from_yaml(&nfourbar(60, true)).unwrap());
    assert!(entries(&small) <= DENSE_MAX_ENTRIES && entries(&large) > DENSE_MAX_ENTRIES);
    let (a, b) = (check(&small).unwrap().mechanism, check(&large).unwrap().mechanism);
    for m in [&a, &b] {
        assert_eq!((m.gruebler_dof, m.dof), (0, 1), "{m:?}");
        assert_eq!(m.redundant.len(), 1);
        assert_eq!(m.redundant[0].element, "EB");
    }
    assert_eq!(a.redundant[0].equation, b.redundant[0].equation);
    // The loop r0, c1, r1 with the extra rocker: its joints, and nothing of the rest of the chain.
    let mut loop_joints = a.indeterminate.clone();
    loop_joints.sort();
    let mut large_joints = b.indeterminate.clone();
    large_joints.sort();
    assert_eq!(loop_joints, large_joints);
    assert!(loop_joints.contains(&"EB".to_string()) && !loop_joints.contains(&"R2".to_string()), "{loop_joints:?}");
}

/// A large chain runs its dynamics with the redundant link (the Gram factorization gives the
/// setup its independent rows), keeps its constraints and its energy (no force but gravity):
/// the same bound as `free_dynamics_keeps_its_energy` on the small examples.
#[test]
fn a_large_chain_with_a_redundant_link_runs_and_keeps_its_energy() {
    let model = Model::from_yaml(&nfourbar(60, true)).unwrap();
    let r = model.run("dynamics", &Default::default()).unwrap();
    assert_eq!(r.summary.redundant_rows.as_ref().map(Vec::len), Some(1));
    let (kinetic, potential) = (r.column("kinetic_energy").unwrap(), r.column("potential_energy").unwrap());
    let total: Vec<f64> = kinetic.iter().zip(potential).map(|(k, p)| k + p).collect();
    let drift = total.iter().map(|e| (e - total[0]).abs()).fold(0.0f64, f64::max);
    // rtol 1e-6 of an energy of ~100 J over 0.5 s.
    assert!(drift < 1e-3 * total[0].abs().max(1.0), "energy drift {drift} of {}", total[0]);
}

/// `outputs:` keeps `time` and the columns it names (a body's nine, a joint's reactions, any
/// other by name), each equal bit for bit to the same column of a run that keeps all; a name
/// that is not there is a model error at its path.
#[test]
fn outputs_keep_the_columns_named() {
    let full_text = nfourbar(60, false);
    let chosen = full_text.replace(
        "dynamics: {type: dynamic, t_end: 0.5, step: 0.05}",
        "dynamics: {type: dynamic, t_end: 0.5, step: 0.05, outputs: {bodies: [c60], joints: [A0], columns: [kinetic_energy, r1.phi]}}",
    );
    assert_ne!(chosen, full_text, "the analysis line was found");
    let (all, some) = (Model::from_yaml(&full_text).unwrap(), Model::from_yaml(&chosen).unwrap());
    let (all, some) =
        (all.run("dynamics", &Default::default()).unwrap(), some.run("dynamics", &Default::default()).unwrap());
    let mut expected: Vec<String> = linkwork::results::BODY_QUANTITIES.iter().map(|q| format!("c60.{q}")).collect();
    expected.extend(["r1.phi".to_string()]);
    expected.extend(["A0.fx", "A0.fy", "A0.torque", "kinetic_energy"].map(String::from));
    let mut names = some.names.clone();
    names.sort();
    expected.sort();
    assert_eq!(names, expected);
    assert_eq!(some.time, all.time);
    for name in &some.names {
        assert_eq!(some.column(name), all.column(name), "{name}");
    }
    let unknown = chosen.replace("columns: [kinetic_energy, r1.phi]", "columns: [kinetic_energy, r1.psi]");
    let error = Model::from_yaml(&unknown).unwrap().run("dynamics", &Default::default()).unwrap_err().error;
    assert!(error.to_string().contains("analyses.dynamics.outputs.columns[1]: no result column 'r1.psi'"), "{error}");
    let unknown_body = chosen.replace("bodies: [c60]", "bodies: [c61]");
    let error = Model::from_yaml(&unknown_body).unwrap_err();
    assert!(error.to_string().contains("analyses.dynamics.outputs.bodies[0]: unknown body 'c61'"), "{error}");
}

/// A static or modes analysis of a chain too large for their dense solvers is refused up front
/// with the reason, at the analysis's type, not run for hours nor failed in an allocation.
#[test]
fn static_and_modes_analyses_refuse_a_chain_too_large_for_them() {
    let text = nfourbar(400, false).replace(
        "  dynamics: {type: dynamic, t_end: 0.5, step: 0.05}\n",
        "  dynamics: {type: dynamic, t_end: 0.5, step: 0.05}\n  rest: {type: static, forces: []}\n  vibration: {type: modes}\n",
    );
    let model = Model::from_yaml(&text).unwrap();
    for name in ["rest", "vibration"] {
        let error = model.run(name, &Default::default()).unwrap_err().error;
        assert!(
            error.to_string().contains(&format!("analyses.{name}.type: a "))
                && error.to_string().contains("2402 x 2403"),
            "{error}"
        );
    }
}
