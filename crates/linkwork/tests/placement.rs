//! Placement in the drawing's frame: bodies given by their points' global positions
//! (`points_global`, `position: <point>`, `angle` 0 by default) and joints by a global point and
//! direction (`at`, `axis`). Checked against a second formulation of the same mechanism in body
//! frames, against the rotation written out, and for the problems of bad input.

use linkwork::{Error, Model};

fn example(name: &str) -> Model {
    Model::load(format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap_or_else(|e| panic!("{e}"))
}

/// `examples/fourbar_placed.yaml` is `fourbar.yaml` drawn in global coordinates. Both assemble
/// to the same mechanism, so every body's centre follows the same path (to `1e-12` m: the
/// position solver's tolerance is `1e-12`), and each body's angle differs by a constant, the
/// angle of its body frame in `fourbar.yaml` at the start (its frame here is parallel to the
/// global one then).
#[test]
fn a_placed_four_bar_moves_as_the_one_in_body_frames() {
    let (placed, reference) = (example("fourbar_placed.yaml"), example("fourbar.yaml"));
    let (p, r) = (placed.run("kinematics").unwrap(), reference.run("kinematics").unwrap());
    assert_eq!(p.len(), r.len());
    for body in ["crank", "coupler", "rocker"] {
        for c in ["x", "y", "vx", "vy"] {
            let (a, b) = (p.column(&format!("{body}.{c}")).unwrap(), r.column(&format!("{body}.{c}")).unwrap());
            let worst = a.iter().zip(b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-11, "{body}.{c}: {worst:e}");
        }
        let (a, b) = (p.column(&format!("{body}.phi")).unwrap(), r.column(&format!("{body}.phi")).unwrap());
        let offset = b[0] - a[0];
        let worst = a.iter().zip(b).map(|(a, b)| (b - a - offset).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-11, "{body}.phi - constant: {worst:e}");
    }
    // The placed points, as `linkwork check` lists them: A is 0.05 m along the crank's x from its
    // centre; the rocker's O4 is half the rocker from its centre, towards (0.3, 0).
    assert_eq!(placed.placed["bodies.crank.points.A"], [0.05, 0.0]);
    let o4 = placed.placed["bodies.rocker.points.O4"];
    assert!((o4[0].hypot(o4[1]) - 0.125).abs() < 1e-15, "{o4:?}");
    assert_eq!(placed.placed["joints.O2.point_j"], [0.0, 0.0], "ground's frame is the global one");
    assert_eq!(placed.placed.len(), 9 + 8, "3 points per body, 2 per joint");
}

/// A slider on a guide at 30 degrees, placed by a global point and direction, on a body turned
/// by 0.4 rad: each body-frame point and axis is `R(-phi) (g - r)` and `R(-phi) a`, written out.
#[test]
fn a_joint_at_a_global_point_and_direction_is_turned_into_each_body() {
    let text = "
bodies:
  block: {mass: 1, inertia: 0.01, position: [1, 0.5], angle: 0.4}
joints:
  guide: {type: translational, body_i: ground, body_j: block, at: [1.2, 0.6], axis: [0.8660254037844387, 0.5]}
";
    let model = Model::from_yaml(text).unwrap();
    let (s, c) = 0.4f64.sin_cos();
    let (dx, dy) = (0.2, 0.1);
    let expect = [
        ("joints.guide.point_i", [1.2, 0.6]),
        ("joints.guide.point_j", [c * dx + s * dy, -s * dx + c * dy]),
        ("joints.guide.axis_i", [0.8660254037844387, 0.5]),
        ("joints.guide.axis_j", [c * 0.8660254037844387 + s * 0.5, -s * 0.8660254037844387 + c * 0.5]),
    ];
    for (path, want) in expect {
        let got = model.placed[path];
        assert!((got[0] - want[0]).abs() < 1e-15 && (got[1] - want[1]).abs() < 1e-15, "{path}: {got:?} vs {want:?}");
    }
}

/// Bad placements are problems at their paths, each saying what to write.
#[test]
fn bad_placements_name_the_field() {
    let problems = |text: &str| -> Vec<(String, String)> {
        match Model::from_yaml(text) {
            Err(Error::Model(p)) => p.into_iter().map(|p| (p.path, p.message)).collect(),
            other => panic!("expected problems, got {other:?}"),
        }
    };
    let base = "
bodies:
  bar: {mass: 1, inertia: 0.1, position: POSITION, points: {A: [0.5, 0]}, points_global: GLOBAL}
joints:
  pin: JOINT
";
    let model = |position: &str, global: &str, joint: &str| {
        base.replace("POSITION", position).replace("GLOBAL", global).replace("JOINT", joint)
    };
    let pin = "{type: revolute, body_i: bar, body_j: ground, at: [0, 0]}";
    let cases = [
        (model("M", "{O: [0, 0]}", pin), "bodies.bar.position", "unknown point 'M'"),
        (model("[0, 0]", "{A: [1, 0]}", pin), "bodies.bar.points_global.A", "also in points"),
        (
            model("[0, 0]", "{}", "{type: revolute, body_i: bar, point_i: A, body_j: ground, at: [0, 0]}"),
            "joints.pin.at",
            "not both",
        ),
        (
            model("[0, 0]", "{}", "{type: revolute, body_i: bar, point_i: A, body_j: ground}"),
            "joints.pin.point_j",
            "at: [x, y]",
        ),
        (
            model("[0, 0]", "{}", "{type: translational, body_i: bar, body_j: ground, at: [0, 0], axis_i: [1, 0]}"),
            "joints.pin.axis_j",
            "axis: [x, y]",
        ),
        (
            model("[0, 0]", "{}", "{type: point_on_line, body_i: bar, body_j: ground, at: [0, 0], axis: [0, 0]}"),
            "joints.pin.axis",
            "zero-length axis",
        ),
    ];
    // A joint whose points cannot be placed still has its bodies checked.
    let typo = problems(&model("[0, 0]", "{}", "{type: revolute, body_i: bra, body_j: ground}"));
    for (path, part) in [("joints.pin.point_i", "missing"), ("joints.pin.body_i", "unknown body 'bra'")] {
        assert!(typo.iter().any(|(p, m)| p == path && m.contains(part)), "{path}: {typo:?}");
    }
    // A centre named after a point whose value is not finite: one problem, at the point.
    let bad = problems(&model("O", "{O: [.inf, 0]}", pin));
    assert_eq!(bad.iter().filter(|(p, _)| p.starts_with("bodies.bar")).count(), 1, "{bad:?}");
    assert!(bad.iter().any(|(p, _)| p == "bodies.bar.points_global.O[0]"), "{bad:?}");
    for (text, path, part) in cases {
        let found = problems(&text);
        assert!(
            found.iter().any(|(p, m)| p == path && m.contains(part)),
            "expected {path}: ...{part}..., found {found:?}"
        );
    }
}
