//! Parameters and units in model files (docs/model-format.md, "Parameters and units"): the
//! parametrised slider-crank against its closed form and against the same model written in SI
//! numbers, the quick-return's stroke against its lengths, values given from outside against an
//! edited file, and the problems of bad values.

mod common;

use common::{example, example_text, patch};
use linkwork::{Error, Model, Results};

fn set(values: &[(&str, &str)]) -> Vec<(String, String)> {
    values.iter().map(|(n, v)| (n.to_string(), v.to_string())).collect()
}

fn column<'r>(r: &'r Results, name: &str) -> &'r [f64] {
    r.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

fn problems(e: Error) -> Vec<(String, String)> {
    match e {
        Error::Model(p) => p.into_iter().map(|p| (p.path, p.message)).collect(),
        other => panic!("expected a model error, got {other}"),
    }
}

/// The stroke is `2 r`, to 1e-9 m: the slider's x at the dead centres (crank angles 0 and pi,
/// both output times) is `L + r` and `L - r` up to the kinematic solver's tolerance (1e-10 on
/// `Phi`), for the file's r and for values given from outside.
#[test]
fn the_parametrised_slider_crank_strokes_twice_the_crank_radius() {
    let model = Model::load(example("slider_crank_param.yaml")).unwrap();
    assert_eq!(model.parameters["r"], 0.1);
    assert_eq!(model.parameters["L"], 0.3);
    for r in ["0.05", "75 mm", "0.1", "0.15"] {
        let m = model.with_parameters(&set(&[("r", r)])).unwrap();
        let radius = m.parameters["r"];
        let results = m.run("kinematics", &Default::default()).map_err(|f| f.error).unwrap();
        let x = column(&results, "slider.x");
        let (max, min) = (x.iter().copied().fold(f64::MIN, f64::max), x.iter().copied().fold(f64::MAX, f64::min));
        assert!((max - min - 2.0 * radius).abs() < 1e-9, "r = {r}: stroke {} against {}", max - min, 2.0 * radius);
        // One turn exactly: the crank ends where it started.
        let phi = column(&results, "crank.phi");
        assert!((phi[phi.len() - 1] - phi[0] - 2.0 * std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(results.summary.parameters["r"], radius);
    }
}

/// The parametrised file and the same mechanism written out in SI numbers give the same results
/// bit for bit: units and parameter expressions are read into the same numbers.
#[test]
fn parameters_and_units_read_into_the_numbers_written_out() {
    let param = Model::load(example("slider_crank_param.yaml")).unwrap();
    let (r, l, rho) = (0.1_f64, 0.3_f64, 5.0_f64);
    let written = format!(
        "name: x
bodies:
  crank: {{mass: {mc}, inertia: {ic}, position: [{hr}, 0.001], angle: 0, points: {{O: [{nhr}, 0], A: [{hr}, 0]}}}}
  rod: {{mass: {mr}, inertia: {ir}, position: [{rod_x}, -0.002], angle: {half_deg}, points: {{A: [{nhl}, 0], B: [{hl}, 0]}}}}
  slider: {{mass: 1, inertia: 0.001, position: [{slider_x}, 0], angle: 0}}
{joints}drivers:
  motor: {{type: angle, body: crank, function: \"{w}*t\"}}
analyses:
  kinematics: {{type: kinematic, drivers: [motor], t_end: 1.0, step: 0.005}}
",
        mc = rho * r,
        ic = (rho * r) * (r * r) / 12.0,
        hr = r / 2.0,
        nhr = -r / 2.0,
        mr = rho * l,
        ir = (rho * l) * (l * l) / 12.0,
        rod_x = r + l / 2.0,
        half_deg = 0.5 * std::f64::consts::PI / 180.0,
        nhl = -l / 2.0,
        hl = l / 2.0,
        slider_x = r + l,
        joints = common::SLIDER_CRANK_JOINTS,
        w = 2.0 * std::f64::consts::PI,
    );
    let plain = Model::from_yaml(&written).unwrap();
    for (a, b) in param.bodies.iter().zip(&plain.bodies) {
        assert_eq!((a.mass, a.inertia, a.q0), (b.mass, b.inertia, b.q0), "{}", a.name);
    }
    let (p, q) = (
        param.run("kinematics", &Default::default()).map_err(|f| f.error).unwrap(),
        plain.run("kinematics", &Default::default()).unwrap(),
    );
    assert_eq!(p.len(), q.len());
    for name in ["slider.x", "rod.phi", "crank.omega", "slider.ax"] {
        assert_eq!(column(&p, name), column(&q, name), "{name}");
    }
}

/// A value given from outside gives what editing the file gives, bit for bit, and parameters
/// computed from it follow.
#[test]
fn values_given_from_outside_equal_an_edited_file() {
    let text = example_text("slider_crank_param.yaml");
    let edited = Model::from_yaml(&patch(&text, "L: 300 mm", "L: 280 mm")).unwrap();
    let given = Model::from_yaml_with(&text, &set(&[("L", "0.28")])).unwrap();
    let by_unit =
        Model::load(example("slider_crank_param.yaml")).unwrap().with_parameters(&set(&[("L", "280 mm")])).unwrap();
    for m in [&given, &by_unit] {
        assert_eq!(m.parameters, edited.parameters);
        assert!((m.parameters["m_rod"] - 5.0 * 0.28).abs() < 1e-15);
        let (a, b) = (
            m.run("kinematics", &Default::default()).map_err(|f| f.error).unwrap(),
            edited.run("kinematics", &Default::default()).unwrap(),
        );
        for name in ["slider.x", "rod.phi", "slider.vx"] {
            assert_eq!(column(&a, name), column(&b, name), "{name}");
        }
    }
}

/// Each bad value names its field and what was expected.
#[test]
fn bad_parameters_and_units_name_their_fields() {
    let text = example_text("slider_crank_param.yaml");
    let cases: &[(&str, &str, &str, &str)] = &[
        ("mass: m_crank", "mass: 40 mm", "bodies.crank.mass", "'mm' is a length, expected a mass"),
        ("mass: m_crank", "mass: L", "bodies.crank.mass", "'L' is a length, expected a mass"),
        ("angle: 0 deg", "angle: 3 mm", "bodies.crank.angle", "is a length, expected an angle"),
        (
            "drivers: [motor], t_end: \"2*pi/speed\", step: 5 ms}\n  inverse",
            "drivers: [motor], t_end: \"2*pi/speed\", step: 5 kg}\n  inverse",
            "analyses.kinematics.step",
            "is a mass, expected a time",
        ),
        ("m_rod: rho * L", "m_rod: rho * Q", "parameters.m_rod", "unknown name 'Q'"),
        ("m_crank: rho * r", "m_crank: rho * m_rod", "parameters.m_crank", "written before it"),
        ("inertia: m_rod * L^2 / 12", "inertia: m_rod * K", "bodies.rod.inertia", "unknown name 'K'"),
        ("function: \"speed*t\"", "function: \"speedy*t\"", "drivers.motor", "unknown name 'speedy'"),
        ("rho: 5 kg/m", "rho: 5 kg/parsec", "parameters.rho", "unknown unit 'parsec'"),
    ];
    for &(from, to, path, says) in cases {
        let p = problems(Model::from_yaml(&patch(&text, from, to)).unwrap_err());
        assert!(p.iter().any(|(p, m)| p.starts_with(path) && m.contains(says)), "{to}: {p:?}");
        assert_eq!(p.len(), 1, "{to}: one problem, not its echoes: {p:?}");
    }
    // One problem: what uses r (m_crank, the crank's points, ...) is not reported again.
    let p = problems(Model::from_yaml_with(&text, &set(&[("r", "2 kg")])).unwrap_err());
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].0, "parameters.r");
    assert!(p[0].1.contains("is a mass, expected a length"), "{p:?}");
    let p = problems(Model::from_yaml_with(&text, &set(&[("radius", "0.1")])).unwrap_err());
    assert_eq!(p[0].0, "parameters.radius");
    assert!(p[0].1.contains("unknown parameter") && p[0].1.contains("r, L, speed"), "{p:?}");
}

/// The quick-return's lengths are parameters, and its slider D strokes as they say for every
/// crank length. The rocker swings by `asin(crank / pivots)` each side of upright (its slot is
/// then tangent to the crank circle); at rocker angle `theta` from upright, C is at
/// `(rocker sin, -pivots + rocker cos)` and D, on the guide at height `guide`, a link's length to
/// its left: `D.x = rocker sin - sqrt(link^2 - (guide + pivots - rocker cos)^2)`. The stroke is the
/// range of that over the swing, taken here on 200,001 angles (error ~1e-11 m). The run's
/// extremes fall between output times: with the output every 1e-4 s (the crank turns 6.3e-4 rad a
/// step) they are short by about `x'' (6.3e-4 / 2)^2 / 2`, under 1e-6 m.
#[test]
fn the_quick_return_strokes_as_its_lengths_say() {
    let model = Model::load(example("quick_return_a.yaml")).unwrap();
    let fine = linkwork::Overrides { step: Some(1e-4), t_end: Some(1.0), ..Default::default() };
    for crank in ["1.35", "1.5", "1650 mm"] {
        let m = model.with_parameters(&set(&[("crank", crank)])).unwrap();
        let p = &m.parameters;
        let results = m.run("kinematics", &fine.clone().into()).map_err(|f| f.error).unwrap();
        let x = column(&results, "slider_d.x");
        let range =
            |x: &mut dyn Iterator<Item = f64>| x.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let (min, max) = range(&mut x.iter().copied());
        let swing = (p["crank"] / p["pivots"]).asin();
        let d_x = |theta: f64| {
            let height = p["guide"] + p["pivots"] - p["rocker"] * theta.cos();
            p["rocker"] * theta.sin() - (p["link"].powi(2) - height.powi(2)).sqrt()
        };
        let (lo, hi) = range(&mut (0..=200_000).map(|k| d_x(swing * (k as f64 / 100_000.0 - 1.0))));
        let stroke = hi - lo;
        assert!((max - min - stroke).abs() < 1e-6, "crank {crank}: stroke {} against {stroke}", max - min);
    }
}
