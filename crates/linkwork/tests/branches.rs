//! Assembly branches and the part of a mechanism that locks, against closed forms: the six-bar leg
//! of `examples/sixbar_leg.yaml` drawn on either side of its foot's dyad, with and without
//! `branches:`; and the lock-up time and the dyad named at it on three mechanisms.

mod common;

use common::{example_text, patch};
use linkwork::model::spec::Side;
use linkwork::model::structure;
use linkwork::{Error, Model};
use std::f64::consts::PI;

/// The crank's speed in the six-bar, rad/s (60 rpm).
const SPEED: f64 = 2.0 * PI;
/// The six-bar's dimensions, m: `r, ab, bq, ac, bc, cf, fd, fg, dg`, and its ground pivots.
const LEG: [f64; 9] = [0.015, 0.05, 0.04, 0.035, 0.03, 0.04, 0.037, 0.04, 0.055];
const O: [f64; 2] = [0.0, 0.0];
const Q: [f64; 2] = [0.045, 0.0];
const D: [f64; 2] = [0.01, -0.055];

/// The point at distances `a` from `p` and `b` from `q`, left of `p -> q` (`left`) or right.
fn circles(p: [f64; 2], a: f64, q: [f64; 2], b: f64, left: bool) -> Option<[f64; 2]> {
    let (ux, uy) = (q[0] - p[0], q[1] - p[1]);
    let d = ux.hypot(uy);
    let x = (a * a - b * b + d * d) / (2.0 * d);
    let h2 = a * a - x * x;
    if h2 < 0.0 {
        return None;
    }
    let h = if left { h2.sqrt() } else { -h2.sqrt() };
    Some([p[0] + (x * ux - h * uy) / d, p[1] + (x * uy + h * ux) / d])
}

/// The leg's pins `C` and the foot point `G` at crank angle `theta`, crank `r`, the foot's dyad on
/// its right side (as declared); `None` past a lock-up. Closed form: each pin the intersection of
/// two circles on its side.
fn leg(theta: f64, r: f64) -> Option<([f64; 2], [f64; 2])> {
    let [_, _, _, _, _, cf, fd, fg, dg] = LEG;
    let c = coupler_point(theta, r);
    let f = circles(c, cf, D, fd, false)?;
    let g = circles(f, fg, D, dg, false)?;
    Some((c, g))
}

/// The coupler's point `C` at crank angle `theta`, crank `r` (its four-bar a crank-rocker: it
/// always closes).
fn coupler_point(theta: f64, r: f64) -> [f64; 2] {
    let [_, ab, bq, ac, bc, ..] = LEG;
    let a = [O[0] + r * theta.cos(), O[1] + r * theta.sin()];
    let b = circles(a, ab, Q, bq, true).expect("a crank-rocker");
    circles(a, ac, b, bc, false).expect("a triangle")
}

/// The six-bar's text with the guesses of the foot's dyad (link `linkf`, foot) drawn on the other
/// side of the line C -> D: F mirrored, so that link CF points at -110.5 degrees and the foot at
/// 48.5 degrees instead of -130.6 and 70.4.
fn drawn_wrong(text: &str) -> String {
    let text = patch(text, "angle: -130 deg, points: {C:", "angle: -110.5 deg, points: {C:");
    patch(&text, "angle: 70 deg, points: {D:", "angle: 48.5 deg, points: {D:")
}

/// Largest distance of the run's foot point from the closed form, m.
fn foot_error(model: &Model) -> f64 {
    let results = model.run("kinematics", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let (t, x, y) =
        (results.column("time").unwrap(), results.column("foot_x").unwrap(), results.column("foot_y").unwrap());
    let mut worst = 0.0f64;
    for k in 0..t.len() {
        let (_, g) = leg(SPEED * t[k], LEG[0]).expect("the nominal leg never locks");
        worst = worst.max((x[k] - g[0]).hypot(y[k] - g[1]));
    }
    worst
}

#[test]
fn the_six_bar_is_two_dyads_after_its_crank() {
    let model = Model::from_yaml(&example_text("sixbar_leg.yaml")).unwrap();
    let motor = [0];
    let groups = structure::groups(&model, &motor);
    let bodies: Vec<Vec<&str>> =
        groups.iter().map(|g| g.bodies.iter().map(|&b| model.bodies[b].name.as_str()).collect()).collect();
    assert_eq!(bodies, [vec!["crank"], vec!["coupler", "rocker"], vec!["linkf", "foot"]]);
    let dyads: Vec<[&str; 3]> = groups.iter().filter_map(|g| g.dyad.as_ref()).map(|d| d.names(&model)).collect();
    assert_eq!(dyads, [["A", "B", "Q"], ["C", "F", "D"]]);
    // The mechanism alone (no driver): the crank is taken as the input link, one freedom left.
    let free: Vec<usize> = structure::groups(&model, &[]).iter().map(|g| g.free).collect();
    assert_eq!(free, [1, 0, 0]);
}

#[test]
fn a_leg_drawn_right_runs_on_its_branch_without_a_warning() {
    // Without `branches:` the drawing alone decides, and it is on the declared sides.
    let text = example_text("sixbar_leg.yaml");
    let text = patch(&text, "branches:\n  B: {line: [A, Q], side: left}\n  F: {line: [C, D], side: right}\n", "");
    let model = Model::from_yaml(&text).unwrap();
    let results = model.run("kinematics", &Default::default()).unwrap();
    assert!(results.summary.warnings.is_empty(), "{:?}", results.summary.warnings);
    let branches = results.summary.branches.clone().unwrap();
    let f = branches.iter().find(|b| b.joint == "F").unwrap();
    assert_eq!((f.side, f.drawn, f.declared), (Some(Side::Right), Some(Side::Right), None));
    assert_eq!(f.line, ["C".to_string(), "D".to_string()]);
    // Newton's tolerance is 1e-12 m; the closed form's circles amplify it by at most a few.
    let error = foot_error(&model);
    assert!(error < 1e-11, "foot point {error:e} m from the closed form");
}

#[test]
fn a_leg_drawn_on_the_wrong_side_is_stated_and_a_declared_branch_wins() {
    let text = example_text("sixbar_leg.yaml");
    let undeclared = patch(
        &drawn_wrong(&text),
        "branches:\n  B: {line: [A, Q], side: left}\n  F: {line: [C, D], side: right}\n",
        "",
    );
    // Undeclared: assembled where it is drawn, F left of C -> D, and `check` says so.
    let model = Model::from_yaml(&undeclared).unwrap();
    let report = linkwork::analysis::check(&model).unwrap();
    let f = report.analyses["kinematics"]
        .system
        .as_ref()
        .unwrap()
        .branches
        .iter()
        .find(|b| b.joint == "F")
        .unwrap()
        .clone();
    assert_eq!((f.side, f.drawn), (Some(Side::Left), Some(Side::Left)));
    // The folded leg's foot is far from the designed path (tens of millimetres).
    assert!(foot_error(&model) > 1e-2);
    // Declared: the right mechanism, to the closed form, with a warning that the drawing disagrees.
    let model = Model::from_yaml(&drawn_wrong(&text)).unwrap();
    let results = model.run("kinematics", &Default::default()).unwrap();
    let warning = results.summary.warnings.iter().find(|w| w.starts_with("branches.F")).expect("a warning");
    assert!(warning.contains("the drawing puts joint F left of the line C -> D"), "{warning}");
    let f = results.summary.branches.clone().unwrap().into_iter().find(|b| b.joint == "F").unwrap();
    assert_eq!((f.side, f.drawn, f.declared), (Some(Side::Right), Some(Side::Left), Some(Side::Right)));
    let error = foot_error(&model);
    assert!(error < 1e-11, "foot point {error:e} m from the closed form");
    // Strict: the disagreement is a branch error naming the dyad's joint, the sides and the mode.
    let strict = Model::from_yaml(&format!("{}\nbranch: strict\n", drawn_wrong(&text))).unwrap();
    match strict.run("kinematics", &Default::default()).map_err(|f| f.error) {
        Err(Error::Branch { joint, detail, time }) => {
            assert_eq!((joint.as_str(), time), ("F", 0.0));
            assert!(detail.contains("left of the line C -> D") && detail.contains("branch: strict"), "{detail}");
        }
        other => panic!("expected a branch error, found {other:?}"),
    }
}

#[test]
fn a_branch_naming_joints_that_make_no_dyad_is_a_model_error() {
    let text = example_text("sixbar_leg.yaml");
    for (line, expected) in [
        ("F: {line: [C, Z], side: right}", "branches.F.line[1]: unknown joint 'Z'"),
        ("F: {line: [C, O], side: right}", "branches.F: joints 'C' and 'O' must each pin one of the bodies"),
        ("O: {line: [C, D], side: right}", "branches.O: joint 'O' joins a body to ground"),
    ] {
        let bad = patch(&text, "F: {line: [C, D], side: right}", line);
        match Model::from_yaml(&bad) {
            Err(Error::Model(problems)) => {
                assert!(problems.iter().any(|p| p.to_string().starts_with(expected)), "{problems:?}")
            }
            other => panic!("{line}: expected a model error, found {other:?}"),
        }
    }
}

/// The first root after 0 of `f`, by bisection from a bracket `[a, b]` to round-off.
fn root(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    assert!(f(a) < 0.0 && f(b) > 0.0, "not a bracket");
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) < 0.0 {
            a = m
        } else {
            b = m
        }
    }
    0.5 * (a + b)
}

/// The singular error of `model`'s kinematics, as `(time, joints, detail)`.
fn lock(model: &Model) -> (f64, Vec<String>, String) {
    match model.run("kinematics", &Default::default()).map_err(|f| f.error) {
        Err(Error::Singular { time, rows, detail }) => {
            let mut joints: Vec<String> = rows.iter().map(|r| r.element.clone()).collect();
            joints.dedup();
            (time, joints, detail)
        }
        other => panic!("expected a singular position, found {other:?}"),
    }
}

#[test]
fn a_leg_that_locks_names_its_foot_dyad_at_the_exact_time() {
    // A 20 mm crank: the foot's dyad cannot close for crank angles from 5.955 to 0.309 rad, so
    // the crank starts at 0.5 rad and the leg locks on its way round.
    let text = patch(&example_text("sixbar_leg.yaml"), "r: 15 mm ", "r: 20 mm ");
    let text = patch(&text, "function: \"speed*t\"", "function: \"speed*t + 0.5\"");
    let model = Model::from_yaml(&text).unwrap();
    let (time, joints, detail) = lock(&model);
    // Closed form: |CD| = cf + fd, the foot's dyad stretched.
    let [_, _, _, _, _, cf, fd, ..] = LEG;
    let stretch = |t: f64| {
        let c = coupler_point(SPEED * t + 0.5, 0.020);
        (c[0] - D[0]).hypot(c[1] - D[1]) - (cf + fd)
    };
    let exact = root(stretch, 0.0, 0.9);
    // The solver stops at the last position it assembles, within its smallest sub-step (1e-8 of
    // the 10 ms output step) before the exact time.
    assert!((time - exact).abs() < 1e-9, "lock-up at {time} s, exact {exact} s");
    for j in ["C", "F", "D"] {
        assert!(joints.iter().any(|n| n == j), "{joints:?}");
    }
    assert!(!joints.iter().any(|n| n == "A" || n == "O"), "the crank's loop is not to blame: {joints:?}");
    assert!(
        detail.starts_with(
            // In the model's display units (mm): at the lock-up |CD| = cf + fd = 77 mm.
            "in the dyad C-F-D (bodies linkf, foot): links linkf and foot are collinear at joint F (stretched): |CD| = 77.0000 mm against |CF| + |FD| = 40.0000 mm + 37.0000 mm = 77.0000 mm"
        ),
        "{detail}"
    );
}

#[test]
fn a_slider_crank_that_locks_names_its_rod_and_slider() {
    // Rod 0.06 m on a crank of 0.1 m: it locks where r sin(theta) = L, theta = asin(0.6).
    let model = Model::from_yaml(&example_text("slider_crank_lockup.yaml")).unwrap();
    let (time, joints, detail) = lock(&model);
    assert!((time - 0.6f64.asin()).abs() < 1e-9, "lock-up at {time} s");
    assert!(detail.starts_with("in the group of bodies rod, slider"), "{detail}");
    assert!(!joints.iter().any(|n| n == "O"), "{joints:?}");
}

#[test]
fn a_non_grashof_four_bar_names_its_coupler_and_rocker_dyad() {
    // A triple rocker (crank 0.2, coupler 0.15, rocker 0.2, ground 0.3 m), its crank driven up
    // from 60 degrees: its reach ends where the coupler and the rocker are stretched in line,
    // |A O4| = 0.15 + 0.2 = 0.35 m, with |A O4|^2 = 0.2^2 + 0.3^2 - 0.12 cos(theta).
    let text = r#"
name: triple rocker
ground:
  points: {O2: [0, 0], O4: [0.3, 0]}
bodies:
  crank: {mass: 1, inertia: 0.01, position: [0.05, 0.0866], angle: 60 deg, points: {O2: [-0.1, 0], A: [0.1, 0]}}
  coupler: {mass: 1, inertia: 0.01, position: [0.1743, 0.1833], angle: 7.7 deg, points: {A: [-0.075, 0], B: [0.075, 0]}}
  rocker: {mass: 1, inertia: 0.01, position: [0.2743, 0.0966], angle: 104.9 deg, points: {O4: [-0.1, 0], B: [0.1, 0]}}
joints:
  O2: {type: revolute, body_i: crank, point_i: O2, body_j: ground, point_j: O2}
  A: {type: revolute, body_i: crank, point_i: A, body_j: coupler, point_j: A}
  B: {type: revolute, body_i: coupler, point_i: B, body_j: rocker, point_j: B}
  O4: {type: revolute, body_i: rocker, point_i: O4, body_j: ground, point_j: O4}
drivers:
  motor: {type: angle, body: crank, function: "pi/3 + t"}
analyses:
  kinematics: {type: kinematic, drivers: [motor], t_end: 2, step: 0.01}
"#;
    let model = Model::from_yaml(text).unwrap();
    let (time, joints, detail) = lock(&model);
    let reach = |t: f64| (0.04 + 0.09 - 0.12 * (PI / 3.0 + t).cos()).sqrt() - 0.35;
    let exact = root(reach, 0.0, 1.0);
    assert!((time - exact).abs() < 1e-9, "lock-up at {time} s, exact {exact} s");
    assert!(detail.starts_with("in the dyad A-B-O4 (bodies coupler, rocker): links coupler and rocker are collinear at joint B (stretched)"), "{detail}");
    assert!(!joints.iter().any(|n| n == "O2"), "{joints:?}");
}

#[test]
fn a_dyad_too_short_to_close_is_named_by_assembly() {
    // A link CF of 20 mm: |CD| = 75.7 mm at the start, beyond |CF| + |FD| = 57 mm.
    let text = patch(&example_text("sixbar_leg.yaml"), "cf: 40 mm ", "cf: 20 mm ");
    let model = Model::from_yaml(&text).unwrap();
    match model.run("kinematics", &Default::default()).map_err(|f| f.error) {
        Err(Error::Assembly { hint, .. }) => assert!(
            hint.starts_with("cannot close: the dyad C-F-D (links linkf and foot) is too short, |CD| = 75.6655 mm > |CF| + |FD| = 20.0000 mm + 37.0000 mm = 57.0000 mm"),
            "{hint}"
        ),
        other => panic!("expected an assembly error, found {other:?}"),
    }
}

#[test]
fn a_sweep_keeps_the_nominal_branches_whatever_a_variant_draws() {
    // The link CF's drawn angle a parameter: at -130 degrees F is drawn right of C -> D (the
    // nominal), at -110.5 degrees left. Without `branches:` a run of the second alone folds the leg.
    let text = patch(
        &example_text("sixbar_leg.yaml"),
        "branches:\n  B: {line: [A, Q], side: left}\n  F: {line: [C, D], side: right}\n",
        "",
    );
    let text = patch(&text, "  speed: 60 rpm\n", "  speed: 60 rpm\n  alpha: -130 deg\n");
    let text = patch(&text, "angle: -130 deg, points: {C:", "angle: alpha, points: {C:");
    let model = Model::from_yaml(&text).unwrap();
    let folded = model.with_parameters(&[("alpha".into(), "-110.5 deg".into())]).unwrap();
    let reach = |m: &Model| {
        let r = m.run("kinematics", &Default::default()).unwrap();
        r.column("foot_x").unwrap().iter().fold(f64::INFINITY, |a, &x| a.min(x))
    };
    let (nominal, alone) = (reach(&model), reach(&folded));
    assert!((nominal - alone).abs() > 1e-3, "the folded leg reaches as far: {nominal} against {alone}");
    let outputs = [linkwork::sweep::Output::parse("reach", "min(foot_x)").unwrap()];
    let variants: Vec<Vec<(String, String)>> =
        ["-130 deg", "-110.5 deg"].iter().map(|a| vec![("alpha".to_string(), a.to_string())]).collect();
    let rows = linkwork::sweep::sweep(
        &model,
        "kinematics",
        &variants,
        &outputs,
        Some(1),
        &linkwork::progress::Progress::new(),
        &linkwork::progress::StopToken::new(),
    )
    .unwrap();
    for row in &rows {
        let values = row.as_ref().unwrap_or_else(|e| panic!("{e}"));
        // The same mechanism on the same branch: the same Newton iterates to round-off.
        assert!((values[0] - nominal).abs() < 1e-12, "{} against {nominal}", values[0]);
    }
}

#[test]
fn a_change_of_branch_between_two_outputs_is_found_with_its_time() {
    let model = Model::from_yaml(&example_text("sixbar_leg.yaml")).unwrap();
    let report = linkwork::analysis::check(&model).unwrap();
    let q = report.analyses["kinematics"].system.as_ref().unwrap().assembly.q.clone();
    let foot = structure::dyads(&model, &[0]).into_iter().map(|(d, _)| d).find(|d| d.names(&model)[1] == "F").unwrap();
    // The foot's dyad mirrored in its line: its sine the same size, the other sign, so that the
    // line is crossed half way between the two outputs (linear interpolation of the sine).
    let mirrored = foot.reflected(&q);
    assert!((foot.sine(&mirrored) + foot.sine(&q)).abs() < 1e-12);
    let mut watch = structure::BranchWatch::new(&model, &[0]);
    assert_eq!(watch.push(0.5, &q), None);
    assert_eq!(watch.push(0.5, &q), None, "no change, no report");
    let change = watch.push(0.7, &mirrored).expect("a change of branch");
    assert_eq!((change.joint.as_str(), change.from, change.to), ("F", Side::Right, Side::Left));
    assert!((change.time - 0.6).abs() < 1e-12, "{}", change.time);
    assert!(
        change.message().starts_with("the dyad of joint F changed branch at t = 0.600000 s"),
        "{}",
        change.message()
    );
}

#[test]
fn a_parallelogram_passing_its_change_points_warns_once_and_sweeps_ok() {
    // At its flat positions the parallelogram's coupler and rocker pass through a line of pins
    // and carry on as a parallelogram: each pass is in `branch_changes`, one warning a dyad, and
    // a sweep's variants that pass where the nominal run passes are ok.
    let model = Model::from_yaml(&example_text("parallelogram.yaml")).unwrap();
    let name = model.analyses.keys().next().unwrap().clone();
    let results = model.run(&name, &Default::default()).unwrap();
    let changes = &results.summary.branch_changes;
    assert!(changes.len() >= 2, "{changes:?}");
    let warned = results.summary.warnings.iter().filter(|w| w.contains("changed branch")).count();
    let mut joints: Vec<&str> = changes.iter().map(|c| c.joint.as_str()).collect();
    joints.sort_unstable();
    joints.dedup();
    assert_eq!(warned, joints.len(), "{:?}", results.summary.warnings);
    let outputs = [linkwork::sweep::Output::parse("end", "final(time)").unwrap()];
    let rows = linkwork::sweep::sweep(
        &model,
        &name,
        &[vec![], vec![]],
        &outputs,
        Some(1),
        &linkwork::progress::Progress::new(),
        &linkwork::progress::StopToken::new(),
    )
    .unwrap();
    assert!(rows.iter().all(|r| r.is_ok()), "{rows:?}");
}
