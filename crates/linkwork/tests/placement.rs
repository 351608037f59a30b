//! Placement in the drawing's frame: bodies given by their points' global positions
//! (`points_global`, `position: <point>`, `angle` 0 by default) and joints by a global point and
//! direction (`at`, `axis`), and points placed by lengths (`{from: [B, C], distances: [d, e],
//! side}`). Checked against a second formulation of the same mechanism in body frames, against
//! the rotation and the law of cosines written out, and for the problems of bad input.

mod common;

use linkwork::Model;

/// The problems loading `text` reports, each as `(path, message)`.
fn problems(text: &str) -> Vec<(String, String)> {
    common::model_problems(text).into_iter().map(|p| (p.path, p.message)).collect()
}

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
    let (p, r) = (
        placed.run("kinematics", &Default::default()).unwrap(),
        reference.run("kinematics", &Default::default()).unwrap(),
    );
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

/// A six-bar leg of Jansen's kind, its two ternary links placed by their link lengths (the file
/// says more; tests/test_builder.py builds the same model in Python).
const LEG: &str = include_str!("models/jansen_leg.yaml");

/// The third corner of a triangle by the law of cosines in angles: `P = B + d (cos(theta +-
/// beta), sin(theta +- beta))`, `theta` the direction of BC, `beta = acos((d^2 + |BC|^2 - e^2) /
/// (2 d |BC|))` the angle at B, counter-clockwise (+) on the left of B -> C.
fn law_of_cosines(b: [f64; 2], c: [f64; 2], d: f64, e: f64, left: bool) -> [f64; 2] {
    let bc = (c[0] - b[0]).hypot(c[1] - b[1]);
    let theta = (c[1] - b[1]).atan2(c[0] - b[0]);
    let beta = ((d * d + bc * bc - e * e) / (2.0 * d * bc)).acos();
    let angle = if left { theta + beta } else { theta - beta };
    [b[0] + d * angle.cos(), b[1] + d * angle.sin()]
}

/// Each point of the leg placed by lengths is where the law of cosines puts it, worked out here
/// corner after corner, to 1e-12 m (both are exact to a few roundings of
/// 0.1 m, ~1e-17 m). The ternary links' frames are parallel to the global one at their pivots
/// `D` and `H`, so a body-frame point is its global one less the pivot. The mechanism assembles
/// where it is drawn (the drawing is exact: 1e-12 m, the position solver's tolerance) and turns
/// a full turn.
#[test]
fn a_leg_placed_by_lengths_is_where_the_law_of_cosines_puts_it() {
    let model = Model::from_yaml(LEG).unwrap_or_else(|e| panic!("{e}"));
    let mm = 1e-3;
    let [a, l, m, j, b, c, d, ee, f, g, h, i, k] =
        [38.0, 7.8, 15.0, 50.0, 41.5, 39.3, 40.1, 55.8, 39.4, 36.7, 65.7, 49.0, 61.9].map(|v| v * mm);
    let (dd, aa) = ([-a, -l], [m, 0.0]);
    let e_ = law_of_cosines(dd, aa, b, j, true);
    let f_ = law_of_cosines(dd, e_, d, ee, true);
    let h_ = law_of_cosines(dd, aa, c, k, false);
    let g_ = law_of_cosines(h_, f_, i, f, true);
    let p_ = law_of_cosines(h_, g_, h, g, true);
    let local = |p: [f64; 2], o: [f64; 2]| [p[0] - o[0], p[1] - o[1]];
    let expect = [
        ("bodies.upper.points.E", local(e_, dd)),
        ("bodies.upper.points.F", local(f_, dd)),
        ("bodies.leg.points.H", [0.0, 0.0]),
        ("bodies.leg.points.G", local(g_, h_)),
        ("bodies.leg.points.P", local(p_, h_)),
        ("bodies.upper.points.D", [0.0, 0.0]),
        ("bodies.crank.points.O", [0.0, 0.0]),
    ];
    for (path, want) in expect {
        let got = model.placed[path];
        assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12, "{path}: {got:?} vs {want:?}");
    }
    let leg = &model.bodies[2];
    assert!((leg.q0[0] - h_[0]).abs() < 1e-12 && (leg.q0[1] - h_[1]).abs() < 1e-12, "{:?} vs {h_:?}", leg.q0);
    let run = model.run("kinematics", &Default::default()).unwrap_or_else(|e| panic!("{e:?}"));
    for (column, want) in [("leg.x", h_[0]), ("leg.y", h_[1]), ("leg.phi", 0.0), ("upper.phi", 0.0)] {
        let got = run.column(column).unwrap()[0];
        assert!((got - want).abs() < 1e-12, "{column} at the start: {got} vs {want}");
    }
    assert_eq!(run.len(), 101, "the whole turn");
}

/// A ternary link written in its own frame, D at its origin and E along its x axis, with the
/// third corner F by lengths and by the law of cosines written out as a designer did before
/// (`xF = (b^2 + d^2 - ee^2) / (2 b)`, `yF = sqrt(d^2 - xF^2)`): the same point to 1e-12 m
/// (a few roundings of 0.05 m apart).
#[test]
fn a_corner_by_lengths_in_a_body_frame_is_the_written_out_law_of_cosines() {
    let text = "
parameters: {b: 41.5 mm, d: 40.1 mm, ee: 55.8 mm, xF: (b^2 + d^2 - ee^2)/(2*b), yF: sqrt(d^2 - xF^2)}
bodies:
  upper:
    mass: 1
    inertia: 0.1
    position: [0.01, 0.02]
    angle: 0.7
    points: {D: [0, 0], E: [b, 0], F: {from: [D, E], distances: [d, ee], side: SIDE}, Fc: [xF, YF]}
";
    for (side, y) in [("left", "yF"), ("right", "-yF")] {
        let model = Model::from_yaml(&text.replace("SIDE", side).replace("YF", y)).unwrap_or_else(|e| panic!("{e}"));
        let points = &model.bodies[0].points;
        let (got, want) = (points["F"], points["Fc"]);
        assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12, "{side}: {got:?} vs {want:?}");
        assert_eq!(model.placed["bodies.upper.points.F"], got);
    }
}

/// Points that cannot be placed are problems at their fields, naming the points and the lengths:
/// an impossible triangle (too short, too long, a distance not above zero), two points at one
/// place, an unknown body or point in `from`, and a cycle, with its members.
#[test]
fn points_that_cannot_be_placed_name_the_field_and_the_lengths() {
    let base = "
ground:
  points: {O: [0, 0], Q: [0.1, 0]}
bodies:
  foot:
    mass: 1
    inertia: 0.1
    position: [0, 0]
    points: {A: [0, 0], B: [0.1, 0]}
    points_global: {G: G_IS}
";
    let cases = [
        (
            "{from: [A, B], distances: [0.03, 0.05], side: left}",
            "bodies.foot.points_global.G.distances",
            "d = 0.03 m (to A), e = 0.05 m (to B) and |A B| = 0.1 m: d + e = 0.08 m is less than |A B|",
        ),
        (
            "{from: [A, B], distances: [0.2, 0.05], side: left}",
            "bodies.foot.points_global.G.distances",
            "|d - e| = 0.15000000000000002 m is more than |A B|",
        ),
        (
            "{from: [A, ground.Q], distances: [0, 0.05], side: left}",
            "bodies.foot.points_global.G.distances",
            "expected two distances > 0, found d = 0 m (to A), e = 0.05 m (to ground.Q)",
        ),
        (
            "{from: [A, ground.O], distances: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.from",
            "A and ground.O are the same point",
        ),
        (
            "{from: [A, leg.B], distances: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.from[1]",
            "unknown body 'leg'",
        ),
        (
            "{from: [A, C], distances: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.from[1]",
            "unknown point 'C' of body 'foot' (it has A, B, G)",
        ),
        (
            "{from: [A, ground.C], distances: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.from[1]",
            "unknown point 'C' of body 'ground' (it has O, Q)",
        ),
        ("{from: [A, B], distances: [0.1, 0.1], side: up}", "bodies.foot.points_global.G.side", "unknown variant `up`"),
        (
            "{from: [A, B], distances: [0.1, '3 kg'], side: left}",
            "bodies.foot.points_global.G.distances[1]",
            "'kg' is a mass, expected a length",
        ),
        (
            "{from: [A, B], distance: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.distance",
            "unknown field `distance`",
        ),
        (
            "{from: [A, G], distances: [0.1, 0.1], side: left}",
            "bodies.foot.points_global.G.from",
            "placed from each other, foot.G -> foot.G",
        ),
        ("ground.Z", "bodies.foot.points_global.G", "unknown point 'Z' of body 'ground'"),
    ];
    for (g, path, part) in cases {
        let found = problems(&base.replace("G_IS", g));
        assert!(
            found.iter().any(|(p, m)| p == path && m.contains(part)),
            "{g}: expected {path}: ...{part}..., found {found:?}"
        );
        assert_eq!(found.len(), 1, "{g}: one problem, found {found:?}");
    }
    // A cycle through two bodies and a pose: the centre of `foot` is its point G, placed from
    // `shin`'s S, placed from `foot`'s A, which is in foot's frame, so needs its centre.
    let cycle = "
bodies:
  foot:
    {mass: 1, inertia: 0.1, position: G, points: {A: [0, 0]}, points_global: {G: {from: [shin.S, shin.T], distances: [0.1, 0.1], side: left}}}
  shin:
    {mass: 1, inertia: 0.1, position: [0, 0], points_global: {T: [0.1, 0], S: {from: [foot.A, T], distances: [0.1, 0.1], side: right}}}
";
    let found = problems(cycle);
    let message =
        "these points are placed from each other, foot.position -> foot.G -> shin.S -> foot.A -> foot.position";
    assert_eq!(
        found,
        vec![("bodies.foot.points_global.G.from".to_string(), format!("{message}: give one of them by coordinates"))]
    );
}
