//! YAML text => [`ModelSpec`], collecting every structural problem with its path.
//!
//! The text is first read as a generic YAML value (a syntax error stops here, with its line and
//! column); each entry of each section is then deserialized on its own, so that one bad joint does
//! not hide the problems of the next.

use super::spec::{AnalysisSpec, BodySpec, DriverSpec, GroundSpec, JointSpec, ModelSpec};
use crate::error::Problem;
use indexmap::IndexMap;
use serde::de::DeserializeOwned;
use serde_yaml_ng::Value;

const SECTIONS: [&str; 7] = ["name", "description", "ground", "bodies", "joints", "drivers", "analyses"];

/// A model file read as far as it could be: the entries that deserialized, the problems of the
/// others, and the names of those others (so that later checks do not call them unknown).
#[derive(Debug)]
pub struct Parsed {
    /// Every entry that deserialized.
    pub spec: ModelSpec,
    /// Structural problems (types, missing and unknown fields), with paths.
    pub problems: Vec<Problem>,
    /// `section.name` of each entry that did not deserialize.
    pub broken: Vec<String>,
}

/// Parse a model file's text. `Err` lists every problem found.
pub fn parse_spec(text: &str) -> Result<ModelSpec, Vec<Problem>> {
    let parsed = parse_partial(text)?;
    if parsed.problems.is_empty() {
        Ok(parsed.spec)
    } else {
        Err(parsed.problems)
    }
}

/// Parse as much of a model file as can be read; `Err` only when the text is not a YAML mapping.
pub fn parse_partial(text: &str) -> Result<Parsed, Vec<Problem>> {
    let root: Value = serde_yaml_ng::from_str(text).map_err(|e| {
        let msg = match e.location() {
            Some(l) => format!("YAML syntax error at line {}, column {}: {e}", l.line(), l.column()),
            None => format!("YAML syntax error: {e}"),
        };
        vec![Problem::new("", msg)]
    })?;
    let Value::Mapping(map) = root else {
        return Err(vec![Problem::new("", "expected a mapping with sections bodies, joints, drivers, analyses")]);
    };
    let mut problems = Vec::new();
    for key in map.keys() {
        match key.as_str() {
            Some(k) if SECTIONS.contains(&k) => {}
            Some(k) => {
                problems.push(Problem::new(k, format!("unknown section; expected one of {}", SECTIONS.join(", "))))
            }
            None => problems.push(Problem::new("", format!("section names must be strings, found {}", describe(key)))),
        }
    }
    let get = |k: &str| map.get(k).filter(|v| !v.is_null());
    let name = get("name").and_then(|v| entry::<String>("name", v, &mut problems));
    let description = get("description").and_then(|v| entry::<String>("description", v, &mut problems));
    let ground = get("ground").and_then(|v| entry::<GroundSpec>("ground", v, &mut problems));
    if get("bodies").is_none() {
        problems.push(Problem::new("bodies", "missing section: at least one moving body is required"));
    }
    let mut broken = Vec::new();
    let bodies = section::<BodySpec>("bodies", get("bodies"), &mut problems, &mut broken);
    let joints = section::<JointSpec>("joints", get("joints"), &mut problems, &mut broken);
    let drivers = section::<DriverSpec>("drivers", get("drivers"), &mut problems, &mut broken);
    let analyses = section::<AnalysisSpec>("analyses", get("analyses"), &mut problems, &mut broken);
    Ok(Parsed { spec: ModelSpec { name, description, ground, bodies, joints, drivers, analyses }, problems, broken })
}

/// Deserialize one value, recording a problem (with the path inside the value) on failure.
fn entry<T: DeserializeOwned>(path: &str, v: &Value, problems: &mut Vec<Problem>) -> Option<T> {
    match serde_path_to_error::deserialize::<_, T>(v.clone()) {
        Ok(t) => Some(t),
        Err(e) => {
            let inner = e.path().to_string();
            let full = if inner == "." || inner.is_empty() { path.to_string() } else { format!("{path}.{inner}") };
            problems.push(Problem::new(full, e.into_inner().to_string()));
            None
        }
    }
}

/// A section that maps names to entries; each entry is read on its own.
fn section<T: DeserializeOwned>(
    name: &str,
    v: Option<&Value>,
    problems: &mut Vec<Problem>,
    broken: &mut Vec<String>,
) -> IndexMap<String, T> {
    let mut out = IndexMap::new();
    let Some(v) = v else { return out };
    let Value::Mapping(map) = v else {
        problems.push(Problem::new(name, format!("expected a mapping from names to entries, found {}", describe(v))));
        return out;
    };
    for (k, v) in map {
        let Some(key) = k.as_str() else {
            problems.push(Problem::new(name, format!("names must be strings, found {}", describe(k))));
            continue;
        };
        match entry::<T>(&format!("{name}.{key}"), v, problems) {
            Some(t) => {
                out.insert(key.to_string(), t);
            }
            None => broken.push(format!("{name}.{key}")),
        }
    }
    out
}

fn describe(v: &Value) -> String {
    match v {
        Value::Null => "nothing".into(),
        Value::Bool(b) => format!("boolean {b}"),
        Value::Number(n) => format!("number {n}"),
        Value::String(s) => format!("string '{s}'"),
        Value::Sequence(_) => "a list".into(),
        Value::Mapping(_) => "a mapping".into(),
        Value::Tagged(t) => format!("tagged value {}", t.tag),
    }
}
