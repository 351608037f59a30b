//! The JSON Schema shipped in `docs/model.schema.json` is the one the Rust types generate
//! (`linkwork schema` prints it). Regenerate with `LINKWORK_BLESS=1 cargo test --test schema`.

mod common;

use indexmap::IndexMap;
use linkwork::model::parse_spec;
use linkwork::model::spec::{AnalysisKind, DriverSpec, ForceSpec, IntegratorKind, JointSpec};
use linkwork::{Error, Model, Overrides};
use serde::de::DeserializeOwned;
use serde::Serialize;

#[test]
fn shipped_schema_is_current() {
    let path = format!("{}/../../docs/model.schema.json", env!("CARGO_MANIFEST_DIR"));
    let schema = Model::json_schema() + "\n";
    if std::env::var_os("LINKWORK_BLESS").is_some() {
        std::fs::write(&path, &schema).unwrap();
    }
    let shipped = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(shipped == schema, "docs/model.schema.json is stale: run LINKWORK_BLESS=1 cargo test --test schema");
}

/// Every model file in `examples/` loads (it reads, validates and compiles) and runs every
/// analysis it declares without an error; a failure names the file and the analysis. Dynamic
/// analyses run their first ten output steps only (their whole runs, up to 20 s of the N-four-bar,
/// take minutes in a debug build; `examples_dynamics.rs` checks them against references), the
/// others in full. The one example that stops by design, `slider_crank_lockup.yaml` (its driven
/// rod meets a dead centre), must stop with `Singular`.
#[test]
fn every_example_loads_and_runs() {
    let dir = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|entry| entry.expect("a directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "yaml"))
        .collect();
    files.sort();
    assert!(files.iter().any(|p| p.ends_with("quick_return_a.yaml")), "{dir} holds the examples");
    let mut failures = Vec::new();
    for path in &files {
        let file = path.file_name().expect("a file name").to_string_lossy().into_owned();
        let model = match Model::load(path) {
            Ok(model) => model,
            Err(e) => {
                failures.push(format!("{file}: {e}"));
                continue;
            }
        };
        for (name, analysis) in &model.analyses {
            let overrides = match analysis.kind {
                AnalysisKind::Dynamic => Overrides {
                    t_end: Some(analysis.t_end.min(analysis.t_start + 10.0 * analysis.step)),
                    ..Default::default()
                },
                _ => Overrides::default(),
            };
            let outcome = model.run(name, &overrides.clone().into()).map_err(|f| f.error);
            match (file.as_str(), outcome) {
                ("slider_crank_lockup.yaml", Err(Error::Singular { .. })) => {}
                ("slider_crank_lockup.yaml", Ok(_)) => {
                    failures.push(format!("{file} {name}: ran past its dead centre"))
                }
                (_, Ok(_)) => {}
                (_, Err(e)) => failures.push(format!("{file} {name}: {e}")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Each kind of joint, driver and force once, under its own name, with the fields it needs to be
/// read (the bodies need not exist: the text is only read, not compiled).
const EVERY_KIND: &str = r#"
bodies: {}
joints:
  revolute: {type: revolute, body_i: a, point_i: [0, 0], body_j: b, point_j: [0, 0]}
  translational: {type: translational, body_i: a, point_i: [0, 0], axis_i: [1, 0], body_j: b, point_j: [0, 0], axis_j: [1, 0]}
  point_on_line: {type: point_on_line, body_i: a, point_i: [0, 0], axis_i: [1, 0], body_j: b, point_j: [0, 0]}
  revolute_translational: {type: revolute_translational, body_i: a, point_i: [0, 0], axis_i: [1, 0], body_j: b, point_j: [0, 0]}
  distance: {type: distance, body_i: a, point_i: [0, 0], body_j: b, point_j: [1, 0]}
  absolute_x: {type: absolute_x, body: a}
  absolute_y: {type: absolute_y, body: a}
  absolute_angle: {type: absolute_angle, body: a}
  gear: {type: gear, body_i: a, point_i: [0, 0], radius_i: 1, body_j: b, point_j: [0, 0], radius_j: 2}
  rack_pinion: {type: rack_pinion, body_i: a, point_i: [0, 0], radius: 1, body_j: b, point_j: [0, 0], axis_j: [1, 0]}
  rolling_disc: {type: rolling_disc, body_i: a, point_i: [0, 0], radius: 1, body_j: b, point_j: [0, 0], axis_j: [1, 0]}
  expression: {type: expression, expression: "a.x"}
  cam: {type: cam, body_i: a, body_j: b, point_j: [0, 0], radius: "1 + 0.1*cos(psi)"}
  belt: {type: belt, body_i: a, radius_i: 1, body_j: b, radius_j: 2}
drivers:
  angle: {type: angle, body: a, function: t}
  relative_angle: {type: relative_angle, body_i: a, body_j: b, function: t}
  distance: {type: distance, body_i: a, point_i: [0, 0], body_j: b, point_j: [1, 0], function: t}
  x: {type: x, body: a, function: t}
  y: {type: y, body: a, function: t}
forces:
  force: {type: force, body: a}
  torque: {type: torque, body: a, torque: 1}
  spring_damper: {type: spring_damper, body_i: a, point_i: [0, 0], body_j: b, point_j: [1, 0]}
  rotational_spring_damper: {type: rotational_spring_damper, body_i: a, body_j: b}
  contact: {type: contact, body_i: a, shape_i: {circle: {radius: 1}}, body_j: b, shape_j: {segment: [[0, 0], [1, 0]]}, stiffness: 1}
"#;

/// The names `schema`'s definition `def` gives its variants (`"const"`, of the `type` of a tagged
/// enum's variants).
fn schema_names(schema: &serde_json::Value, def: &str) -> Vec<String> {
    let variants = schema["$defs"][def]["oneOf"].as_array().unwrap_or_else(|| panic!("{def} has no oneOf"));
    let name = |v: &serde_json::Value| v.get("const").unwrap_or(&v["properties"]["type"]["const"]).clone();
    variants.iter().map(|v| name(v).as_str().unwrap_or_else(|| panic!("{def}: {v}")).to_string()).collect()
}

/// The one list of a section's type names (`NAMES`, which the parser offers and `name()` reads)
/// is serde's: each entry read by the parser, by its type name, is the variant serde reads from
/// the same text, serializes back under that name, and the schema (from serde's attributes)
/// lists the same names in the same order.
fn tagged_names_are_serdes<T: Serialize + DeserializeOwned>(
    def: &str,
    entries: &IndexMap<String, T>,
    names: &[&str],
    name: impl Fn(&T) -> &'static str,
) {
    let listed: Vec<&str> = entries.keys().map(String::as_str).collect();
    assert_eq!(listed, names, "{def}: EVERY_KIND names each type once, in the order of NAMES");
    for (key, entry) in entries {
        assert_eq!(name(entry), key, "{def}: the parser read `type: {key}` as another kind");
        let value = serde_json::to_value(entry).unwrap();
        assert_eq!(value["type"], key.as_str(), "{def}: serde writes `type: {key}` otherwise");
        let again: T = serde_json::from_value(value).unwrap_or_else(|e| panic!("{def}: serde cannot read {key}: {e}"));
        assert_eq!(name(&again), key, "{def}: serde reads `type: {key}` as another kind");
    }
    let schema: serde_json::Value = serde_json::from_str(&Model::json_schema()).unwrap();
    assert_eq!(schema_names(&schema, def), names, "{def}: the schema's names");
}

#[test]
fn type_names_are_serdes() {
    let spec = parse_spec(EVERY_KIND).unwrap_or_else(|p| panic!("{p:#?}"));
    tagged_names_are_serdes("JointSpec", &spec.joints, JointSpec::NAMES, JointSpec::name);
    tagged_names_are_serdes("DriverSpec", &spec.drivers, DriverSpec::NAMES, DriverSpec::name);
    tagged_names_are_serdes("ForceSpec", &spec.forces, ForceSpec::NAMES, ForceSpec::name);
}

/// The same for the names of integrators and analysis types: each reads, by serde and by
/// `from_name`, as the variant that `name()` calls by it and serializes as it, and the schema
/// lists them.
#[test]
fn integrator_and_analysis_names_are_serdes() {
    fn check<T: Serialize + DeserializeOwned>(
        def: &str,
        names: &[&str],
        name: impl Fn(&T) -> &'static str,
        from_name: impl Fn(&str) -> Option<T>,
    ) {
        for &n in names {
            let kind: T =
                serde_json::from_value(n.into()).unwrap_or_else(|e| panic!("{def}: serde cannot read {n}: {e}"));
            assert_eq!(name(&kind), n, "{def}: serde reads {n} as another kind");
            assert_eq!(serde_json::to_value(&kind).unwrap(), n, "{def}: serde writes {n} otherwise");
            let named = from_name(n).unwrap_or_else(|| panic!("{def}: from_name does not know {n}"));
            assert_eq!(name(&named), n, "{def}: from_name reads {n} as another kind");
        }
        assert!(from_name("bogus").is_none(), "{def}: from_name knows `bogus`");
        let schema: serde_json::Value = serde_json::from_str(&Model::json_schema()).unwrap();
        assert_eq!(schema_names(&schema, def), names, "{def}: the schema's names");
    }
    check("IntegratorKind", IntegratorKind::NAMES, IntegratorKind::name, IntegratorKind::from_name);
    check("AnalysisKind", AnalysisKind::NAMES, AnalysisKind::name, AnalysisKind::from_name);
}

/// An unknown section is named with the sections there are (read from the model's own fields).
#[test]
fn an_unknown_section_lists_the_sections() {
    let Err(problems) = parse_spec("bodies: {}\nbogus: 1\n") else { panic!("`bogus` was read") };
    let sections =
        "name, parameters, display, description, gravity, ground, bodies, joints, drivers, forces, measures, paths, summaries, tables, branches, branch, analyses";
    assert_eq!(problems[0].to_string(), format!("bogus: unknown section; expected one of {sections}"));
}
