//! Bad input: every problem of a file is reported, each with its path in the file, and no input
//! panics or hangs.

mod common;

use common::{example, example_text, patch, problems};
use linkwork::{Error, Model};

/// Whether `list` has a problem at `path` (none: at the top) whose message contains `words`.
fn found(list: &[String], path: &str, words: &str) -> bool {
    let prefix = if path.is_empty() { String::new() } else { format!("{path}: ") };
    list.iter().any(|p| p.starts_with(&prefix) && p.contains(words))
}

fn has(list: &[String], path: &str, words: &str) {
    let prefix = if path.is_empty() { String::new() } else { format!("{path}: ") };
    assert!(found(list, path, words), "no '{prefix}...{words}...' in {list:#?}");
}

/// Each `(path, words)` of `expected` is in `list`, as [`has`] checks one; the message names
/// every one that is not.
fn has_each(list: &[String], expected: &[(&str, &str)]) {
    let missing: Vec<_> = expected.iter().filter(|(path, words)| !found(list, path, words)).collect();
    assert!(missing.is_empty(), "not found: {missing:#?}\nin {list:#?}");
}

const BAD: &str = r#"
bodies:
  crank: {mass: 1, inertia: .nan, position: [0, 0], angle: 0}
  rocker: {mass: 1, inertia: 1, position: [0, 0], angle: 0, colour: red}
  link: {mass: 1, position: [0, 0], angle: 0}
  slider: {mass: -2, inertia: 1, position: [0, "abc"], angle: 0}
joints:
  B: {type: revolute, body_i: crank, point_i: [0, 0], body_j: rokcer, point_j: [0, 0]}
  S: {type: point_on_line, body_i: crank, point_i: [0, 0], axis_i: [0, 0], body_j: rocker, point_j: [1, 0]}
  crank: {type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
  E: {type: expression, expression: "crank.x^2 + rocker.z"}
  F: {type: expression, expression: "crank.x * (1 +"}
  P: {type: revolute, body_i: crank, point_i: tip, body_j: ground, point_j: [0, 0]}
  Q: {type: revolut, body_i: crank}
drivers:
  d: {type: angle, body: crank, function: "2*pi*q"}
analyses:
  kin: {type: kinematic, drivers: [d, e], t_end: 1, step: 0}
"#;

#[test]
fn every_problem_is_listed_with_its_path() {
    let p = problems(BAD);
    has_each(
        &p,
        &[
            ("bodies.crank.inertia", "finite"),
            ("bodies.rocker.colour", "unknown field"),
            ("bodies.link", "missing field `inertia`"),
            ("bodies.slider.position[1]", "unknown name 'abc'"),
            ("joints.B.body_j", "unknown body 'rokcer'"),
            ("joints.S.axis_i", "zero-length axis"),
            ("joints.crank", "duplicate name"),
            ("joints.E.expression", "unknown name 'rocker.z'"),
            ("joints.F.expression", "cannot read the expression"),
            ("joints.P.point_i", "unknown point 'tip'"),
            ("joints.Q.type", "unknown type `revolut`"),
            ("drivers.d.function", "unknown name 'q'"),
            ("analyses.kin.drivers[1]", "unknown driver 'e'"),
            ("analyses.kin.step", "positive"),
        ],
    );
    assert_eq!(p.len(), 14, "{p:#?}");
}

/// An analysis' `forces` list names forces of the model; an unknown name is reported at its
/// index with the names there are, and the known names around it are no problem.
#[test]
fn unknown_force_of_an_analysis_is_listed_with_its_path() {
    let text = r#"
bodies:
  crank: {mass: 1, inertia: 1, position: [0, 0], angle: 0}
joints:
  O: {type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
forces:
  motor: {type: torque, body: crank, torque: 1}
  push: {type: force, body: crank, fx: 2}
analyses:
  dyn: {type: dynamic, forces: [push, motr, motor], t_end: 1, step: 0.1}
"#;
    let p = problems(text);
    has(&p, "analyses.dyn.forces[1]", "unknown force 'motr'; the model's forces are: motor, push");
    assert_eq!(p.len(), 1, "{p:#?}");
    let none = patch(text, "forces: [push, motr, motor]", "forces: []");
    assert!(Model::from_yaml(&none).is_ok(), "an empty list is valid");
    let no_forces = text.split("forces:\n").next().unwrap().to_string()
        + "analyses:\n  dyn: {type: dynamic, forces: [motor], t_end: 1, step: 0.1}\n";
    has(&problems(&no_forces), "analyses.dyn.forces[0]", "the model has no forces");
}

#[test]
fn negative_mass_is_refused_once_the_body_reads() {
    let text = "bodies:\n  a: {mass: -2, inertia: -1, position: [0, 0], angle: 0}\n";
    let p = problems(text);
    has_each(&p, &[("bodies.a.mass", "mass >= 0"), ("bodies.a.inertia", ">= 0")]);
}

#[test]
fn a_number_too_large_for_a_double_is_out_of_range() {
    let p = problems(
        "bodies:\n  a: {mass: 1e400, inertia: 1, position: [0, 0], angle: 0}\n  b: {mass: 1, inertia: 1, position: [0, -2.5e309], angle: 0}\n",
    );
    has_each(
        &p,
        &[
            ("bodies.a.mass", "number 1e400 is out of range"),
            ("bodies.b.position[1]", "number -2.5e309 is out of range"),
        ],
    );
    // A word that is not a number is read as an expression of parameters, and said to be none.
    has(
        &problems("bodies:\n  a: {mass: heavy, inertia: 1, position: [0, 0], angle: 0}\n"),
        "bodies.a.mass",
        "unknown name 'heavy' (expected a number, a number with a unit, or an expression of parameters)",
    );
}

#[test]
fn syntax_errors_and_wrong_shapes() {
    has(&problems("bodies: [1, 2"), "", "YAML syntax error");
    has(&problems("- 1\n- 2\n"), "", "expected a mapping");
    has(&problems("bodies: {}\nbogus: 1\n"), "bogus", "unknown section");
    has(&problems("joints: {}\n"), "bodies", "missing section");
    has(&problems("bodies: 3\n"), "bodies", "expected a mapping");
    // A duplicate key is pointed at on its own line (serde's message gives the first one's).
    let twice = "bodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n  b: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n";
    has(
        &problems(twice),
        "",
        "YAML syntax error at line 4, column 3: bodies: duplicate entry with key \"a\" (the first at line 2)",
    );
    has(
        &problems("bodies:\n  ground: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n"),
        "bodies.ground",
        "fixed body",
    );
    has(
        &problems("bodies:\n  2a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n"),
        "bodies.2a",
        "not a valid name",
    );
}

/// Every prefix of every example, and every example with one character replaced, must give a
/// model or a model error: never a panic (a hang would time the test out).
#[test]
fn no_input_panics() {
    let files = ["quick_return_a.yaml", "quick_return_b.yaml", "fourbar.yaml", "parallelogram.yaml"];
    let mut tried = 0;
    for f in files {
        let text = example_text(f);
        for cut in (0..text.len()).step_by(11) {
            if text.is_char_boundary(cut) {
                let _ = Model::from_yaml(&text[..cut]);
                tried += 1;
            }
        }
        for (k, _) in text.char_indices().step_by(7) {
            for replacement in ["0", "-", ":", "[", "x", "9e999", " "] {
                let mut mutated = text.clone();
                mutated.replace_range(k..k + 1, replacement);
                if let Ok(model) = Model::from_yaml(&mutated) {
                    // A model that compiles must also run to an answer or a typed error.
                    let _ = model.run("kinematics", &Default::default());
                }
                tried += 1;
            }
        }
    }
    assert!(tried > 3000);
}

/// A point with the wrong shape names its field and says what a point is.
#[test]
fn bad_points_name_their_field() {
    let base = "bodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\njoints:\n  C: {type: revolute, body_i: a, point_i: [0, 0], body_j: ground, point_j: POINT}\n";
    let cases = [
        ("[0, 0, 0]", "joints.C.point_j", "invalid length 3"),
        ("[1]", "joints.C.point_j", "invalid length 1"),
        ("[x, 1]", "joints.C.point_j[0]", "unknown name 'x'"),
        ("{x: 1}", "joints.C.point_j", "a point: [x, y]"),
    ];
    for (point, path, words) in cases {
        has(&problems(&patch(base, "POINT", point)), path, words);
    }
}

/// A bad field inside a joint or driver keeps its full path, and a missing or unknown `type`
/// says which types exist.
#[test]
fn fields_of_joints_and_drivers_keep_their_paths() {
    let base = "bodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n  b: {mass: 1, inertia: 1, position: [1, 0], angle: 0}\n";
    let gear = "joints:\n  G: {type: gear, body_i: a, point_i: [0, 0], radius_i: big, body_j: b, point_j: [0, 0], radius_j: 1}\n";
    has(&problems(&(base.to_string() + gear)), "joints.G.radius_i", "unknown name 'big'");
    let extra =
        "joints:\n  R: {type: revolute, body_i: a, point_i: [0, 0], body_j: b, point_j: [0, 0], stiffness: 3}\n";
    has(&problems(&(base.to_string() + extra)), "joints.R.stiffness", "unknown field");
    let untyped = "joints:\n  R: {body_i: a}\n";
    has(
        &problems(&(base.to_string() + untyped)),
        "joints.R",
        "missing field `type`, expected one of: revolute, translational",
    );
    let driver = "drivers:\n  d: {type: angel, body: a, function: t}\n";
    has(
        &problems(&(base.to_string() + driver)),
        "drivers.d.type",
        "unknown type `angel`, expected one of: angle, relative_angle",
    );
    let fun = "drivers:\n  d: {type: x, body: a, point: [0, 0], function: 3}\n";
    has(&problems(&(base.to_string() + fun)), "drivers.d.function", "expected a string");
}

const BAD_DYNAMICS: &str = r#"
gravity: [0, "down"]
bodies:
  crank: {mass: -1, inertia: -0.5, position: [0, 0], angle: 0}
  rocker: {mass: 1, inertia: 1, position: [1, 0], angle: 0}
joints:
  O: {type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
forces:
  drag: {type: torque, body: crank, torque: "-2*crank.omgea"}
  push: {type: force, body: ground, fx: 1}
  spring: {type: spring_damper, body_i: crank, point_i: [0, 0], body_j: rocker, point_j: tip, stiffness: -3}
  twist: {type: rotational_spring_damper, body_i: crank, body_j: crank}
  what: {type: magnet, body: crank}
measures:
  stroke: "crank.x + rokcer.ax"
  tip: {body: crank, component: z}
analyses:
  dyn: {type: dynamic, integrator: hht, t_end: 1, step: 0.1, solver: {rtol: 0, atol: -1, alpha: 0.5, max_order: 3}}
  kin: {type: kinematic, integrator: bdf, t_end: 1, step: 0.1}
  abam: {type: dynamic, integrator: abam, t_end: 1, step: 0.1, solver: {alpha: -0.1, formulation: si2}}
  bdf7: {type: dynamic, t_end: 1, step: 0.1, solver: {max_order: 7}}
"#;

/// Bad inputs of a dynamic model (an unknown state name in a force expression, a
/// negative mass or inertia, a tolerance of zero) and their neighbours, each with its path.
#[test]
fn dynamics_problems_are_listed_with_their_paths() {
    let p = problems(BAD_DYNAMICS);
    has_each(
        &p,
        &[
            ("gravity[1]", "unknown name 'down'"),
            ("bodies.crank.mass", "mass >= 0"),
            ("bodies.crank.inertia", ">= 0"),
            ("forces.drag.torque", "unknown name 'crank.omgea'"),
            ("forces.push.body", "ground does not move"),
            ("forces.spring.point_j", "unknown point 'tip'"),
            ("forces.spring.stiffness", ">= 0"),
            ("forces.twist.body_j", "two different bodies"),
            ("forces.what.type", "unknown type `magnet`"),
            ("measures.stroke", "unknown name 'rokcer.ax'"),
            ("measures.tip.component", "unknown variant `z`"),
            ("analyses.dyn.solver.rtol", "positive"),
            ("analyses.dyn.solver.atol", "positive"),
            ("analyses.dyn.solver.alpha", "[-1/3, 0]"),
            ("analyses.dyn.solver.max_order", "fixed order"),
            ("analyses.kin.integrator", "only a dynamic analysis"),
            ("analyses.abam.solver.alpha", "hht only"),
            ("analyses.abam.solver.formulation", "bdf only"),
            // The integrator by its name in the file, not the engine's ("for Bdf" before).
            ("analyses.bdf7.solver.max_order", "expected 1 to 6 for bdf, found 7"),
        ],
    );
}

/// Ground where a moving body is needed, and one body at both ends of a joint or driver, are
/// refused at the field that names them, each entry with that one problem.
#[test]
fn ground_and_one_body_twice_are_refused() {
    let base = "bodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n";
    let (constrained, driven) =
        ("ground cannot be constrained; name a moving body", "ground cannot be driven; name a moving body");
    let twice = "a joint needs two different bodies, found 'a' twice";
    let cases = [
        ("joints:\n  ax: {type: absolute_x, body: ground}\n", "joints.ax.body", constrained),
        ("joints:\n  phi: {type: absolute_angle, body: ground}\n", "joints.phi.body", constrained),
        (
            "joints:\n  pin: {type: revolute, body_i: a, point_i: [0, 0], body_j: a, point_j: [1, 0]}\n",
            "joints.pin.body_j",
            twice,
        ),
        ("drivers:\n  turn: {type: angle, body: ground, function: t}\n", "drivers.turn.body", driven),
        ("drivers:\n  slide: {type: y, body: ground, function: t}\n", "drivers.slide.body", driven),
        ("drivers:\n  rel: {type: relative_angle, body_i: a, body_j: a, function: t}\n", "drivers.rel.body_j", twice),
    ];
    for (entry, path, words) in cases {
        let p = problems(&(base.to_string() + entry));
        has(&p, path, words);
        assert_eq!(p.len(), 1, "{p:#?}");
    }
}

/// Command-line overrides are checked like file values; the option is the path.
#[test]
fn overrides_are_checked() {
    let model = Model::load(example("double_pendulum.yaml")).unwrap();
    let bad = linkwork::Overrides { rtol: Some(0.0), t_end: Some(-1.0), ..Default::default() };
    let e = model.run("dynamics", &bad.clone().into()).unwrap_err().error;
    let Error::Model(p) = e else { panic!("expected a model error") };
    let p: Vec<String> = p.iter().map(|p| p.to_string()).collect();
    has_each(&p, &[("--rtol", "positive"), ("--t-end", "start")]);
    let kin = Model::load(example("fourbar.yaml")).unwrap();
    let e = kin.run("kinematics", &linkwork::Overrides { atol: Some(1e-3), ..Default::default() }.into()).unwrap_err();
    // In the model file's words, not the engine's type names ("is Kinematic" before).
    assert!(
        e.error.to_string().contains("--atol: only a dynamic analysis has an integrator; 'kinematics' is kinematic"),
        "{}",
        e.error
    );
    // A step longer than the run (which would give only its two ends) is refused, in the file
    // and as an override. The option blamed is the one given: the end time that the file's step
    // no longer fits, not `--step`, which the user did not pass.
    let short = linkwork::Overrides { t_end: Some(0.005), ..Default::default() };
    let e = kin.run("kinematics", &short.clone().into()).unwrap_err().error;
    assert!(e.to_string().contains("--t-end: the output step (0.02 s) is longer than the analysis (0.005 s"), "{e}");
    let long = linkwork::Overrides { t_end: Some(1e6), ..Default::default() };
    let e = kin.run("kinematics", &long.clone().into()).unwrap_err().error;
    assert!(e.to_string().contains("--t-end: 50000000 output points requested"), "{e}");
    let both = linkwork::Overrides { t_end: Some(1.0), step: Some(1e-8), ..Default::default() };
    let e = kin.run("kinematics", &both.clone().into()).unwrap_err().error;
    assert!(e.to_string().contains("--step: 100000000 output points requested"), "{e}");
}

#[test]
fn a_step_longer_than_the_run_is_refused() {
    let text = example_text("fourbar.yaml");
    let analyses = text.find("\nanalyses:").expect("fourbar.yaml has an analyses section");
    let long = format!("{}\nanalyses:\n  kin: {{type: kinematic, t_end: 0.3, step: 0.5}}\n", &text[..analyses]);
    has(&problems(&long), "analyses.kin.step", "the output step (0.5 s) is longer than the analysis (0.3 s");
}

/// A named ground point in a file with no `ground:` section is an unknown point, as it is when the
/// section lists others. Found by the fuzzer (`fuzz/`): the joint and the spring that named one
/// were dropped without a word, the rest compiled, and the dynamic analysis indexed the forces it
/// had selected by name past the end of the compiled ones, a panic.
#[test]
fn a_ground_point_without_a_ground_section_is_unknown() {
    let text = "bodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n\
                joints:\n  O: {type: revolute, body_i: a, point_i: [0, 0], body_j: ground, point_j: O}\n\
                forces:\n  \
                  drive: {type: torque, body: a, torque: 1}\n  \
                  spring: {type: spring_damper, body_i: a, point_i: [1, 0], body_j: ground, point_j: C, stiffness: 1}\n\
                analyses:\n  dynamics: {type: dynamic, t_end: 0.1, step: 0.01}\n";
    let list = problems(text);
    has(&list, "joints.O.point_j", "unknown point 'O' of body 'ground' (it has no named points)");
    has(&list, "forces.spring.point_j", "unknown point 'C' of body 'ground' (it has no named points)");
}

/// A `paths:` entry names a point of a moving body, `<body>.<point>` or `<body>`; an unknown body
/// or point, ground, a duplicate or an entry that is no string is a problem at the entry.
#[test]
fn a_bad_path_is_a_problem_at_its_entry() {
    let model = |paths: &str| {
        format!(
            "bodies:\n  crank: {{mass: 1, inertia: 1, position: [0, 0], angle: 0, points: {{A: [1, 0], B: [2, 0]}}}}\n\
             joints:\n  O: {{type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}}\n\
             paths: {paths}\n"
        )
    };
    let list = problems(&model("[crank.A, crank.Q, rocker.A, ground, crank.A]"));
    has_each(
        &list,
        &[
            ("paths[1]", "unknown point 'Q' of body 'crank' (it has A, B); expected <body>.<point>"),
            ("paths[2]", "unknown body 'rocker'"),
            ("paths[3]", "ground does not move"),
            ("paths[4]", "'crank.A' is already paths[0]"),
        ],
    );
    assert_eq!(list.len(), 4, "{list:#?}");
    has(&problems(&model("[crank.A, [1, 2]]")), "paths[1]", "expected a string");
    let paths = |text: &str| Model::from_yaml(text).unwrap_or_else(|e| panic!("{e}")).drawing().paths;
    let drawn = paths(&model("[crank.B, crank]"));
    let expected = [("crank.B", [2.0, 0.0]), ("crank", [0.0, 0.0])];
    assert_eq!(drawn.iter().map(|p| (p.name.as_str(), p.point)).collect::<Vec<_>>(), expected);
}

/// Without `paths:`, the paths are the point measures' points, each once, named by the point's
/// name where it has one (given by name or by its coordinates), else by its coordinates.
#[test]
fn the_paths_default_to_the_point_measures_points() {
    let text = "bodies:\n  crank: {mass: 1, inertia: 1, position: [0, 0], angle: 0, points: {A: [1, 0]}}\n\
                joints:\n  O: {type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}\n\
                measures:\n  \
                  ax: {body: crank, point: A, component: x}\n  \
                  ay: {body: crank, point: [1, 0], component: y}\n  \
                  tip: {body: crank, point: [0.5, 0.25], component: vx}\n  \
                  cx: {body: crank, component: x}\n  \
                  twice: \"2*crank.x\"\n";
    let drawing = Model::from_yaml(text).unwrap_or_else(|e| panic!("{e}")).drawing();
    let drawn: Vec<_> = drawing.paths.iter().map(|p| (p.name.as_str(), p.body.as_str(), p.point)).collect();
    let expected =
        [("crank.A", "crank", [1.0, 0.0]), ("crank [0.5, 0.25]", "crank", [0.5, 0.25]), ("crank", "crank", [0.0, 0.0])];
    assert_eq!(drawn, expected);
}

/// A measure named as a built-in column, as `status` or as a parameter is refused at it naming
/// the other: each name reads one thing (a measure `kinetic_energy` gave `results.csv` two
/// columns of that name, read differently by Python and by the summaries). One problem each; a
/// name of its own compiles, and a summary, whose names are its own, may take any of them.
#[test]
fn measure_names_cannot_collide() {
    let base = "parameters: {r: 2}\nbodies:\n  a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}\n";
    let cases = [
        (
            "measures:\n  kinetic_energy: a.x\n",
            "measures.kinetic_energy",
            "is already the built-in column kinetic_energy",
        ),
        ("measures:\n  time: a.x\n", "measures.time", "is already the built-in column time"),
        ("measures:\n  driver_power: a.x\n", "measures.driver_power", "is already the built-in column driver_power"),
        ("measures:\n  status: a.x\n", "measures.status", "is already the status of a run"),
        ("measures:\n  r: a.x\n", "measures.r", "is already the parameter parameters.r"),
    ];
    for (entry, path, words) in cases {
        let p = problems(&(base.to_string() + entry));
        has(&p, path, words);
        assert_eq!(p.len(), 1, "{p:#?}");
    }
    let own = "measures:\n  reach: a.x\nsummaries:\n  reach: max(reach)\n  time: max(time)\n  r: max(a.x)\n";
    Model::from_yaml(&(base.to_string() + own)).expect("names of their own compile");
}
