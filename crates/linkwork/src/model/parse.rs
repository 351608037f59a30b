//! YAML text => [`ModelSpec`], collecting every structural problem with its path.
//!
//! The text is first read as a generic YAML value (a syntax error stops here, with its line and
//! column); each entry of each section is then deserialized on its own, so that one bad joint does
//! not hide the problems of the next.

use super::params;
use super::spec::{
    AnalysisSpec, BodySpec, BranchMode, BranchSpec, DriverSpec, ForceSpec, GroundSpec, JointSpec, MeasureSpec,
    ModelSpec, PointMeasure, StandardMeasure, TableSpec, Tagged,
};
use super::units::Display;
use crate::error::Problem;
use indexmap::IndexMap;
use serde::de::DeserializeOwned;
use serde_yaml_ng::Value;

/// The fields of the struct `T` as serde reads them (the sections of a model file for
/// [`ModelSpec`]): what `T::deserialize` hands a deserializer, which reads no further.
fn fields<T: DeserializeOwned>() -> &'static [&'static str] {
    struct Fields<'a>(&'a mut &'static [&'static str]);
    impl<'de> serde::Deserializer<'de> for Fields<'_> {
        type Error = serde::de::value::Error;
        fn deserialize_any<V: serde::de::Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(serde::de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: serde::de::Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = fields;
            Err(serde::de::Error::custom("only the fields are asked for"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option unit
            unit_struct newtype_struct seq tuple tuple_struct map enum identifier ignored_any
        }
    }
    let mut fields: &'static [&'static str] = &[];
    // Always an error: the deserializer stops once it has the fields.
    let _ = T::deserialize(Fields(&mut fields));
    fields
}

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
    /// The unit the file writes each parameter in, for those it writes with one (`r: mm`).
    pub parameter_units: IndexMap<String, String>,
    /// Warnings about the values given from outside, each `parameters.<name>: ...`.
    pub warnings: Vec<String>,
    /// The tolerance of each parameter the file gives one, in file order.
    pub tolerances: IndexMap<String, params::Tolerance>,
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
    parse_partial_with(text, &[])
}

/// As [`parse_partial`], with parameter values given from outside (`(name, text)`) over the
/// file's (docs/model-format.md, "Parameters and units").
pub fn parse_partial_with(text: &str, set: &[(String, String)]) -> Result<Parsed, Vec<Problem>> {
    parse_document_with(parse_document(text)?, set)
}

/// The YAML document of a model file's text, before any of it is read as a model: what
/// [`parse_document_with`] reads, so that a text compiled many times (a sweep) is parsed once.
pub(crate) fn parse_document(text: &str) -> Result<Value, Vec<Problem>> {
    if text.len() as u64 > MAX_MODEL_BYTES {
        let message = format!("the model is {}; {}", size(text.len() as u64), LIMIT);
        return Err(vec![Problem::new("", message)]);
    }
    if let Some((line, column)) = too_deep(text) {
        let message = format!(
            "YAML syntax error at line {line}, column {column}: collections nested more than {MAX_DEPTH} deep; a model nests a few levels"
        );
        return Err(vec![Problem::new("", message)]);
    }
    serde_yaml_ng::from_str(text).map_err(|e| {
        let msg = match (e.location(), duplicate(text, &e.to_string())) {
            (_, Some((line, column, message))) => {
                format!("YAML syntax error at line {line}, column {column}: {message}")
            }
            (Some(l), None) => format!("YAML syntax error at line {}, column {}: {e}", l.line(), l.column()),
            (None, None) => format!("YAML syntax error: {e}"),
        };
        vec![Problem::new("", msg)]
    })
}

/// The largest model file: 4 MiB. The largest realistic model is far smaller (a chain of 1,000
/// bodies with its joints is about 0.2 MB, an inline table of 100,000 points 2.4 MB; larger
/// tables go in CSV files, `tables:` with `file:`). The bound keeps the parse short enough that
/// Ctrl-C need not interrupt it: the worst text allowed (4 MiB of flow mappings nested 16
/// deep) takes about two seconds, and 16 MiB of them nested 60 deep took 14 s
/// (docs/model-format.md, "Limits"); a larger text, or a device such as `/dev/zero`, would take
/// the memory rather than be a model.
pub(crate) const MAX_MODEL_BYTES: u64 = 4 << 20;

/// What a model file larger than [`MAX_MODEL_BYTES`] is told.
pub(crate) const LIMIT: &str =
    "a model file may be at most 4 MiB (put large tables in CSV files: `tables:` with `file:`)";

/// `bytes` in MB, for the messages.
pub(crate) fn size(bytes: u64) -> String {
    format!("{:.1} MB", bytes as f64 / 1e6)
}

/// The deepest nesting of collections a model file may have: a model nests six levels at most
/// (the file's mapping, `analyses`, an analysis, `outputs`, `columns`, its list; a table's
/// `[[x, y], ...]`). serde_yaml_ng refuses more than 128, but only once libyaml has read the
/// whole text, in time quadratic in the depth of flow collections (a 400 KB file of
/// `{a: {a: ...` took 87 s); the time to parse a text of the largest size allowed grows with the
/// depth allowed ([`MAX_MODEL_BYTES`]).
const MAX_DEPTH: usize = 16;

/// The line and column (from 1) of the first collection of `text` nested deeper than
/// [`MAX_DEPTH`], if there is one. libyaml's events are read one at a time and the reading stops
/// there; its scanner looks at most 1024 characters ahead, so this takes time linear in the
/// text. A syntax error stops it too: the parse that follows reports it.
fn too_deep(text: &str) -> Option<(usize, usize)> {
    let mut parser = Box::new(std::mem::MaybeUninit::<unsafe_libyaml::yaml_parser_t>::uninit());
    let parser = parser.as_mut_ptr();
    // SAFETY: as serde_yaml_ng drives the same parser (its libyaml::parser): the parser is
    // initialized before any other call and deleted once, stays in its box (libyaml keeps
    // pointers into it), and reads `text`, which outlives it; each event is deleted after it is
    // read, and only events the parser returned with success are read.
    unsafe {
        if unsafe_libyaml::yaml_parser_initialize(parser).fail {
            return None;
        }
        unsafe_libyaml::yaml_parser_set_encoding(parser, unsafe_libyaml::YAML_UTF8_ENCODING);
        unsafe_libyaml::yaml_parser_set_input_string(parser, text.as_ptr(), text.len() as u64);
        let mut depth = 0usize;
        let mut found = None;
        loop {
            let mut event = std::mem::MaybeUninit::<unsafe_libyaml::yaml_event_t>::uninit();
            if unsafe_libyaml::yaml_parser_parse(parser, event.as_mut_ptr()).fail {
                break;
            }
            let event = event.as_mut_ptr();
            let kind = (*event).type_;
            match kind {
                unsafe_libyaml::YAML_SEQUENCE_START_EVENT | unsafe_libyaml::YAML_MAPPING_START_EVENT => depth += 1,
                unsafe_libyaml::YAML_SEQUENCE_END_EVENT | unsafe_libyaml::YAML_MAPPING_END_EVENT => {
                    depth = depth.saturating_sub(1)
                }
                _ => {}
            }
            if depth > MAX_DEPTH {
                let mark = (*event).start_mark;
                found = Some((mark.line as usize + 1, mark.column as usize + 1));
            }
            unsafe_libyaml::yaml_event_delete(event);
            if found.is_some() || kind == unsafe_libyaml::YAML_STREAM_END_EVENT {
                break;
            }
        }
        unsafe_libyaml::yaml_parser_delete(parser);
        found
    }
}

/// As [`parse_partial_with`], from the file's YAML document ([`parse_document`]).
pub(crate) fn parse_document_with(root: Value, set: &[(String, String)]) -> Result<Parsed, Vec<Problem>> {
    let Value::Mapping(mut map) = root else {
        return Err(vec![Problem::new("", "expected a mapping with sections bodies, joints, drivers, analyses")]);
    };
    let mut problems = Vec::new();
    let parameters = params::evaluate(map.get("parameters"), set, &mut problems);
    let written = params::resolve(&mut map, &parameters, &mut problems);
    let gradients =
        params::Gradients { params: parameters.iter().map(|p| p.gradient.clone()).collect(), fields: written };
    let of_numbers = problems.len();
    let parameter_units = parameters.iter().filter_map(|p| Some((p.name.clone(), p.unit.clone()?))).collect();
    let warnings = parameters.iter().filter_map(|p| p.warning.clone()).collect();
    let tolerances = parameters.iter().filter_map(|p| Some((p.name.clone(), p.tolerance?))).collect();
    let parameters = parameters.into_iter().map(|p| (p.name, p.value)).collect();
    let sections = fields::<ModelSpec>();
    for key in map.keys() {
        match key.as_str() {
            Some(k) if sections.contains(&k) => {}
            Some(k) => {
                problems.push(Problem::new(k, format!("unknown section; expected one of {}", sections.join(", "))))
            }
            None => problems.push(Problem::new("", format!("section names must be strings, found {}", describe(key)))),
        }
    }
    let get = |k: &str| map.get(k).filter(|v| !v.is_null());
    let name = get("name").and_then(|v| entry::<String>("name", v, &mut problems));
    let description = get("description").and_then(|v| entry::<String>("description", v, &mut problems));
    let gravity = get("gravity").and_then(|v| entry::<[f64; 2]>("gravity", v, &mut problems));
    let ground = get("ground").and_then(|v| entry::<GroundSpec>("ground", v, &mut problems));
    let display = get("display").and_then(|v| entry::<IndexMap<String, String>>("display", v, &mut problems));
    if let Some(Err(more)) = display.as_ref().map(Display::read) {
        problems.extend(more);
    }
    if get("bodies").is_none() {
        problems.push(Problem::new("bodies", "missing section: at least one moving body is required"));
    }
    let mut broken = Vec::new();
    let bodies = section("bodies", get("bodies"), &mut problems, &mut broken, entry::<BodySpec>);
    let joints = section("joints", get("joints"), &mut problems, &mut broken, joint);
    let drivers = section("drivers", get("drivers"), &mut problems, &mut broken, tagged::<DriverSpec>());
    let forces = section("forces", get("forces"), &mut problems, &mut broken, tagged::<ForceSpec>());
    let measures = section("measures", get("measures"), &mut problems, &mut broken, measure);
    let summaries = section("summaries", get("summaries"), &mut problems, &mut broken, summary);
    let paths = get("paths").and_then(|v| entry::<Vec<String>>("paths", v, &mut problems)).unwrap_or_default();
    let tables = section("tables", get("tables"), &mut problems, &mut broken, entry::<TableSpec>);
    let analyses = section("analyses", get("analyses"), &mut problems, &mut broken, entry::<AnalysisSpec>);
    let branches = section("branches", get("branches"), &mut problems, &mut broken, entry::<BranchSpec>);
    let branch = get("branch").and_then(|v| entry::<BranchMode>("branch", v, &mut problems));
    // One problem a field: a number that could not be read is not reported again as a string
    // where a number was expected, nor a field that uses a parameter that could not be read (its
    // place held by an empty message) at all.
    let (read, rest) = problems.split_at(of_numbers);
    let rest: Vec<Problem> = rest.iter().filter(|p| !read.iter().any(|r| r.path == p.path)).cloned().collect();
    problems.truncate(of_numbers);
    problems.retain(|p| !p.message.is_empty());
    problems.extend(rest);
    let spec = ModelSpec {
        name,
        parameters,
        display: display.unwrap_or_default(),
        description,
        gravity,
        ground,
        bodies,
        joints,
        drivers,
        forces,
        measures,
        paths,
        summaries,
        tables,
        branches,
        branch,
        analyses,
        gradients,
    };
    Ok(Parsed { spec, problems, broken, parameter_units, warnings, tolerances })
}

/// A duplicate key's own line: the YAML parser's message (`<path>: duplicate entry with key "a"
/// at line 2 column 3`) gives the line of the mapping's first entry, where the key is first
/// written. The key is looked for again at the same column in the lines after it, as a block
/// mapping writes it; `(line, column, message)` of the second occurrence, `None` when the message
/// is not that or the key is not found so (a flow mapping `{a: 1, a: 2}`).
fn duplicate(text: &str, message: &str) -> Option<(usize, usize, String)> {
    let (head, rest) = message.split_once("duplicate entry with key \"")?;
    let (key, place) = rest.split_once("\" at line ")?;
    let (line, column) = place.split_once(" column ")?;
    let line = line.trim().parse::<usize>().ok()?.checked_sub(1)?;
    let column = column.trim().parse::<usize>().ok()?;
    let at = column.checked_sub(1)?;
    let written = |l: &str| {
        let (indent, entry) = (l.get(..at)?, l.get(at..)?);
        let keyed = entry.strip_prefix(key).or_else(|| entry.strip_prefix(&format!("\"{key}\"")))?;
        (indent.trim_start_matches([' ', '-']).is_empty() && keyed.trim_start().starts_with(':')).then_some(())
    };
    let first = text.lines().enumerate().skip(line).find(|(_, l)| written(l).is_some())?.0;
    let second = text.lines().enumerate().skip(first + 1).find(|(_, l)| written(l).is_some())?.0;
    Some((second + 1, column, format!("{head}duplicate entry with key \"{key}\" (the first at line {})", first + 1)))
}

/// Deserialize one value, recording a problem (with the path inside the value) on failure.
fn entry<T: DeserializeOwned>(path: &str, v: &Value, problems: &mut Vec<Problem>) -> Option<T> {
    match serde_path_to_error::deserialize::<_, T>(v.clone()) {
        Ok(t) => Some(t),
        Err(e) => {
            problems.push(located(path, e));
            None
        }
    }
}

/// A measure: an expression (a string), a standard quantity (a mapping with a `type`) or a point
/// component (a mapping without one), read by hand so that a bad field keeps its path.
fn measure(path: &str, v: &Value, problems: &mut Vec<Problem>) -> Option<MeasureSpec> {
    match v {
        Value::String(s) => Some(MeasureSpec::Expression(s.clone())),
        Value::Mapping(m) if m.contains_key("type") => {
            tagged::<StandardMeasure>()(path, v, problems).map(MeasureSpec::Standard)
        }
        Value::Mapping(_) => entry::<PointMeasure>(path, v, problems).map(MeasureSpec::Point),
        other => {
            problems.push(Problem::new(
                path,
                format!(
                    "expected an expression (a string), a mapping with body, point and component, or a mapping with a `type` ({}), found {}",
                    StandardMeasure::NAMES.join(", "),
                    describe(other)
                ),
            ));
            None
        }
    }
}

/// A summary: an expression (a string).
fn summary(path: &str, v: &Value, problems: &mut Vec<Problem>) -> Option<String> {
    if let Value::String(s) = v {
        return Some(s.clone());
    }
    let example = "\"integral(pump_power) / integral(motor_power)\"";
    problems.push(Problem::new(
        path,
        format!(
            "expected an expression of aggregations of result columns (a string), such as {example}, found {}",
            describe(v)
        ),
    ));
    None
}

/// The joint types that take a `friction:` mapping: those whose fields include one, read from
/// the registry's schema (so a new joint with friction needs no line here); built once.
fn friction_types() -> &'static [String] {
    static TYPES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    TYPES.get_or_init(|| {
        let schema = serde_json::to_value(schemars::schema_for!(JointSpec)).expect("a schema is JSON");
        let kinds = schema["oneOf"].as_array().into_iter().flatten();
        kinds
            .filter(|kind| kind["properties"].get("friction").is_some())
            .filter_map(|kind| kind["properties"]["type"]["const"].as_str().map(String::from))
            .collect()
    })
}

/// A joint: a [`tagged`] entry, whose `friction:` on a type that has none is reported as that
/// rather than as an unknown field (the rest of the joint is read without it).
fn joint(path: &str, v: &Value, problems: &mut Vec<Problem>) -> Option<JointSpec> {
    if let (Value::Mapping(map), Some(kind)) = (v, v.get("type").and_then(Value::as_str)) {
        if map.contains_key("friction") && !friction_types().iter().any(|t| t == kind) {
            problems.push(Problem::new(
                format!("{path}.friction"),
                format!(
                    "a {kind} joint has no friction model; friction is supported on {} joints",
                    friction_types().join(" and ")
                ),
            ));
            let mut rest = map.clone();
            rest.remove("friction");
            return tagged::<JointSpec>()(path, &Value::Mapping(rest), problems);
        }
    }
    tagged::<JointSpec>()(path, v, problems)
}

/// An entry of a section whose entries name their kind in `type`: the kind read here and the
/// rest by [`Tagged::read`], which keeps the path of a bad field (`joints.G.radius_i`, not
/// `joints.G`).
fn tagged<T: Tagged>() -> impl Fn(&str, &Value, &mut Vec<Problem>) -> Option<T> {
    |path, v, problems| {
        let expected = || format!("expected one of: {}", T::TYPES.join(", "));
        let Value::Mapping(map) = v else {
            problems.push(Problem::new(
                path,
                format!("expected a mapping with a `type` ({}), found {}", expected(), describe(v)),
            ));
            return None;
        };
        let kind = match map.get("type") {
            Some(Value::String(k)) => k.clone(),
            Some(other) => {
                problems.push(Problem::new(
                    format!("{path}.type"),
                    format!("expected a type name ({}), found {}", expected(), describe(other)),
                ));
                return None;
            }
            None => {
                problems.push(Problem::new(path, format!("missing field `type`, {}", expected())));
                return None;
            }
        };
        let mut rest = map.clone();
        rest.remove("type");
        let mut track = serde_path_to_error::Track::new();
        match T::read(&kind, serde_path_to_error::Deserializer::new(Value::Mapping(rest), &mut track)) {
            None => {
                problems.push(Problem::new(format!("{path}.type"), format!("unknown type `{kind}`, {}", expected())));
                None
            }
            Some(Ok(t)) => Some(t),
            Some(Err(e)) => {
                problems.push(located(path, serde_path_to_error::Error::new(track.path(), e)));
                None
            }
        }
    }
}

/// A problem at `path` plus the path serde tracked inside the value.
fn located(path: &str, e: serde_path_to_error::Error<serde_yaml_ng::Error>) -> Problem {
    let inner = e.path().to_string();
    let full = if inner == "." || inner.is_empty() {
        path.to_string()
    } else if inner.starts_with('[') {
        format!("{path}{inner}")
    } else {
        format!("{path}.{inner}")
    };
    Problem::new(full, out_of_range(e.into_inner().to_string()))
}

/// The message for a number too large for a double. YAML reads `1e400` as a float, which
/// overflows, and the parser then keeps it as the string "1e400": serde's message would say
/// "invalid type: string", blaming the user's type rather than the size.
fn out_of_range(message: String) -> String {
    let number = message.strip_prefix("invalid type: string \"").and_then(|rest| rest.split_once('"')).map(|(t, _)| t);
    number.and_then(too_large).unwrap_or(message)
}

/// "number 1e400 is out of range ..." when `text` is a number written out that a double cannot
/// hold (not `inf`, which is a name).
pub(super) fn too_large(text: &str) -> Option<String> {
    let text = text.trim();
    let written = text.starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c))
        && !text.to_ascii_lowercase().contains("inf")
        && text.parse::<f64>().is_ok_and(f64::is_infinite);
    written.then(|| format!("number {text} is out of range: a double holds sizes up to 1.8e308"))
}

/// A section that maps names to entries; each entry is read on its own by `read`.
fn section<T>(
    name: &str,
    v: Option<&Value>,
    problems: &mut Vec<Problem>,
    broken: &mut Vec<String>,
    read: impl Fn(&str, &Value, &mut Vec<Problem>) -> Option<T>,
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
        match read(&format!("{name}.{key}"), v, problems) {
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
