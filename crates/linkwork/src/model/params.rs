//! A model file's `parameters:` and the numbers written with units or as expressions of them.
//!
//! The section maps names to values in order: a number (SI), a number with a unit
//! ([`super::units`]), or an expression of the parameters written before it. Every numeric field
//! of the file may then be written the same way (`mass: "2.5 kg"`, `inertia: "m * L^2 / 12"`,
//! `A: ["L/2", 0]`); [`resolve`] replaces each by its SI number before the entries are read, and
//! checks a unit's dimension against the field's ([`field`]). Expressions of time and the state
//! (drivers, forces, measures, expression joints) keep their text and see the parameters as
//! named numbers when they are compiled ([`crate::expr::Expr::parse_with`]).
//!
//! Each parameter and each field written as an expression of them also gets its derivatives
//! with respect to every parameter ([`Gradients`]), with the expressions' dual numbers: what
//! design sensitivities start from (docs/model-format.md, "Derivatives with respect to
//! parameters").

use super::units::{quantity, si_unit, unit_text, Dim};
use crate::error::Problem;
use crate::expr::{gradient, Dual, Expr, Names};
use serde_yaml_ng::{Mapping, Value};
use std::collections::HashMap;

/// A parameter: its name, its value in SI, the dimension of the unit it was written with
/// (`None` for a bare number or an expression, whose dimension is not inferred), the unit the
/// file writes it in (`mm` for `r: 100 mm`), a warning about the value given from outside, and
/// its derivative with respect to each parameter (file order): `--set`'s, which replaces the
/// expression of the parameter set, so `d p_j / d p_k = [j == k] + sum_i (d f_j / d p_i) (d p_i
/// / d p_k)` over the parameters `p_i` that `p_j`'s expression `f_j` uses (none for a number, or
/// a value given from outside).
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub value: f64,
    pub dim: Option<Dim>,
    pub unit: Option<String>,
    pub warning: Option<String>,
    pub gradient: Vec<f64>,
    /// Its tolerance, when the file gives one (`r: 150 mm ± 0.1 mm`); a value given from
    /// outside keeps the file's tolerance.
    pub tolerance: Option<Tolerance>,
}

/// How a toleranced parameter is spread about its value: tolerance analysis draws from it and
/// takes its standard deviation (docs/model-format.md, "Tolerances").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Distribution {
    /// Normal, the tolerance three standard deviations: the usual reading of a process
    /// tolerance (99.73% of the parts inside it).
    #[default]
    Normal,
    /// Uniform over the value plus or minus the tolerance (every part inside it).
    Uniform,
}

impl Distribution {
    /// Its name as a model file writes it.
    pub fn name(self) -> &'static str {
        match self {
            Distribution::Normal => "normal",
            Distribution::Uniform => "uniform",
        }
    }
}

/// A parameter's tolerance: the largest deviation from its value (SI, non-negative) and how the
/// deviations are spread.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// The tolerance `t`, SI: the value lies in `value ± t`.
    pub value: f64,
    /// How deviations are spread over it.
    pub distribution: Distribution,
}

impl Tolerance {
    /// The standard deviation of the parameter: `t / 3` for a normal spread (the tolerance is
    /// three standard deviations), `t / sqrt(3)` for a uniform one over `± t`.
    pub fn sigma(&self) -> f64 {
        match self.distribution {
            Distribution::Normal => self.value / 3.0,
            Distribution::Uniform => self.value / 3f64.sqrt(),
        }
    }
}

/// The JSON Schema of a parameter as a model file writes it (`ModelSpec::parameters`, whose Rust
/// type holds the SI values read): a value, or a mapping of a value with its tolerance; the short
/// form `150 mm ± 0.1 mm` is a string, a value to the schema. Its numbers are written `number`:
/// [`crate::Model::json_schema`] widens every number to a string too, as everywhere.
pub(crate) fn written_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
    schemars::json_schema!({
        "type": "object",
        "additionalProperties": {
            "anyOf": [
                {
                    "description": "A number (SI), a number with a unit, an expression of the parameters before it, \
                        or any of these followed by ± (or +-) and a tolerance: `150 mm ± 0.1 mm`.",
                    "type": "number"
                },
                {
                    "description": "A value with its tolerance.",
                    "type": "object",
                    "additionalProperties": false,
                    "required": ["value", "tolerance"],
                    "properties": {
                        "value": {"description": "The value, as a parameter is written.", "type": "number"},
                        "tolerance": {
                            "description": "The largest deviation from the value, non-negative, in the value's \
                                dimension (with a unit when the value has one).",
                            "type": "number"
                        },
                        "distribution": {
                            "description": "How deviations are spread: normal (default; the tolerance is three \
                                standard deviations) or uniform (over plus or minus the tolerance).",
                            "enum": ["normal", "uniform"]
                        }
                    }
                }
            ]
        }
    })
}

/// The derivatives of a model file's numbers with respect to its parameters (each vector: one
/// entry per parameter, file order, SI per SI unit), as reading the file finds them: what the
/// compiler builds [`super::DataGradients`] from. Empty for a file without parameters.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Gradients {
    /// Each parameter's, with respect to each ([`Parameter::gradient`]).
    pub params: Vec<Vec<f64>>,
    /// Each field written as an expression of the parameters, by its path
    /// (`bodies.crank.points.A[0]`, `joints.A.length`); a field not here (a number, or a number
    /// with a unit) has derivatives zero.
    pub fields: HashMap<String, Vec<f64>>,
}

impl Gradients {
    /// How many parameters the derivatives are taken with respect to.
    pub fn count(&self) -> usize {
        self.params.len()
    }

    /// The derivatives of the field at `path` (zero when it is not an expression).
    pub fn field(&self, path: &str) -> Vec<f64> {
        self.fields.get(path).cloned().unwrap_or_else(|| vec![0.0; self.count()])
    }
}

/// The parameters as variables of an expression (each a slot of its own), so that it can be
/// differentiated with respect to them: a parameter called `e` is the parameter, not Euler's
/// number, as when its value is folded in.
struct Variables<'a>(&'a [Parameter]);

impl Names for Variables<'_> {
    fn constant(&self, _: &str) -> Option<f64> {
        None
    }

    fn shadows(&self, name: &str) -> bool {
        self.0.iter().any(|p| p.name == name)
    }
}

/// The derivatives, `count` of them, of the value `text` with respect to each parameter, when it
/// is an expression of `params`: `sum_i (d f / d p_i) (d p_i / d p_k)`, one [`Dual`] pass a
/// parameter it names. `None` for a number or a number with a unit (derivatives zero). An
/// expression naming more parameters than an expression has slots (64) cannot be differentiated
/// and gets not-a-number derivatives, never zeros.
fn derivatives(text: &str, params: &[Parameter], count: usize) -> Option<Vec<f64>> {
    if params.is_empty() || quantity(text).is_some() {
        return None;
    }
    // The parameter each slot stands for, in the order the expression names them.
    let mut used: Vec<usize> = Vec::new();
    let parsed = Expr::parse_with(text, &Variables(params), &mut |name| {
        let k = params.iter().position(|p| p.name == name).ok_or_else(String::new)?;
        Ok(used.iter().position(|&u| u == k).unwrap_or_else(|| {
            used.push(k);
            used.len() - 1
        }))
    });
    let Ok(expr) = parsed else { return Some(vec![f64::NAN; count]) };
    if used.is_empty() {
        return None;
    }
    let x: Vec<f64> = used.iter().map(|&k| params[k].value).collect();
    let (mut partial, mut work) = (vec![0.0; used.len()], vec![Dual::default(); used.len()]);
    gradient(&expr, &x, &mut partial, &mut work);
    let mut total = vec![0.0; count];
    for (&k, df) in used.iter().zip(&partial) {
        for (t, dp) in total.iter_mut().zip(&params[k].gradient) {
            *t += df * dp;
        }
    }
    Some(total)
}

/// Names a parameter may not take: time, and pi. Euler's number `e` may be a parameter's name
/// when nothing in the parameters before it uses `e` (it then means the parameter everywhere).
const RESERVED: &[&str] = &["t", "pi"];

/// A bare number given from outside for a parameter the file writes with a unit is SI; more than
/// this factor from the file's value (either way) it is most likely meant in the file's unit
/// (`--set r=120` for `r: 100 mm`, a factor of 1200), and a warning says so. A real change of
/// design is rarely a hundredfold; mm against m is a thousandfold.
const FAR_FACTOR: f64 = 100.0;

/// The value of a parameter list (names in `params`) as an expression's named constant.
pub fn lookup(params: &[Parameter]) -> impl Fn(&str) -> Option<f64> + '_ {
    move |name| params.iter().find(|p| p.name == name).map(|p| p.value)
}

/// Evaluate the `parameters:` section in order, with `overrides` (name, text) replacing the file's
/// values: a bare number given from outside is SI whatever unit the file used; one with a unit is
/// converted and must have the file's dimension. Problems are pushed with their paths.
pub fn evaluate(
    section: Option<&Value>,
    overrides: &[(String, String)],
    problems: &mut Vec<Problem>,
) -> Vec<Parameter> {
    let mut params: Vec<Parameter> = Vec::new();
    let entries = match section {
        None | Some(Value::Null) => Mapping::new(),
        Some(Value::Mapping(m)) => m.clone(),
        Some(_) => {
            problems.push(Problem::new("parameters", "expected a mapping from names to values"));
            Mapping::new()
        }
    };
    let names: Vec<String> = entries.keys().filter_map(|k| k.as_str().map(str::to_string)).collect();
    // The parameters that use Euler's number `e` (any before a parameter called `e`).
    let mut euler_users: Vec<String> = Vec::new();
    for (name, _) in overrides {
        if !names.contains(name) {
            let known = if names.is_empty() { "none".to_string() } else { names.join(", ") };
            problems.push(Problem::new(
                format!("parameters.{name}"),
                format!("unknown parameter; the model file defines: {known}"),
            ));
        }
    }
    for (key, value) in &entries {
        let Some(name) = key.as_str() else {
            problems.push(Problem::new("parameters", "parameter names must be strings"));
            continue;
        };
        let path = format!("parameters.{name}");
        let identifier = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !identifier || RESERVED.contains(&name) {
            problems.push(Problem::new(
                &path,
                "a parameter's name must be an identifier (letters, digits, _) other than t and pi",
            ));
            continue;
        }
        if name == "e" {
            if let Some(user) = euler_users.first() {
                problems.push(Problem::new(
                    &path,
                    format!(
                        "parameters.{} before it uses e as Euler's number, and a parameter e would mean it \
                         there too; rename this parameter (e_ or ecc, say) or write exp(1) for Euler's number",
                        user
                    ),
                ));
                continue;
            }
        }
        let given = overrides.iter().rev().find(|(n, _)| n == name).map(|(_, text)| text.as_str());
        let euler = std::cell::Cell::new(false);
        let Some((value, tolerance)) = toleranced(value, &path, problems) else {
            params.push(Parameter {
                name: name.to_string(),
                value: f64::NAN,
                dim: None,
                unit: None,
                warning: None,
                gradient: vec![0.0; names.len()],
                tolerance: None,
            });
            continue;
        };
        let value = &value;
        // The unit the file writes the value in: its own (`100 mm`), or that of the one
        // parameter it names (`L2: L`).
        let unit = match value.as_str().map(str::trim) {
            Some(text) => unit_text(text)
                .map(str::to_string)
                .or_else(|| params.iter().find(|p| p.name == text).and_then(|p| p.unit.clone())),
            None => None,
        };
        // Room for every parameter the section may define; cut to those defined at the end.
        let mut gradient = match (given, value.as_str()) {
            (None, Some(text)) => derivatives(text, &params, names.len()),
            _ => None,
        }
        .unwrap_or_else(|| vec![0.0; names.len()]);
        gradient[params.len()] += 1.0;
        let (value, dim, warning) = match parameter(value, given, &params, name, &names, &euler) {
            Ok(v) => v,
            Err(e) => {
                // Kept as not a number, so that what uses it is not reported again.
                if !e.is_empty() {
                    problems.push(Problem::new(&path, e));
                }
                (f64::NAN, None, None)
            }
        };
        if euler.get() {
            euler_users.push(name.to_string());
        }
        let warning = warning.map(|w| format!("{path}: {w}"));
        let tolerance = tolerance.and_then(|(text, distribution)| {
            let read = number(&text, &params, name, &names, &std::cell::Cell::new(false))
                .and_then(|(t, d)| tolerance_value(t, d, dim, &text, unit.as_deref()));
            read.map(|value| Tolerance { value, distribution })
                .map_err(|e| problems.push(Problem::new(format!("{path}.tolerance"), e)))
                .ok()
        });
        params.push(Parameter { name: name.to_string(), value, dim, unit, warning, gradient, tolerance });
    }
    let count = params.len();
    for p in &mut params {
        p.gradient.truncate(count);
    }
    params
}

/// A parameter's entry split into its value and, when it has one, its tolerance as written and
/// its distribution: a mapping `{value, tolerance, distribution}`, or a string with `±` (or
/// `+-`) between the value and the tolerance. `None`, with the problem pushed at its path, for a
/// mapping that is not of that shape.
fn toleranced(
    value: &Value,
    path: &str,
    problems: &mut Vec<Problem>,
) -> Option<(Value, Option<(Value, Distribution)>)> {
    match value {
        Value::String(text) => {
            let split = text.split_once('±').or_else(|| text.split_once("+-"));
            Some(match split {
                Some((v, t)) => (
                    Value::String(v.trim().to_string()),
                    Some((Value::String(t.trim().to_string()), Distribution::Normal)),
                ),
                None => (value.clone(), None),
            })
        }
        Value::Mapping(map) => {
            let mut bad = false;
            for key in map.keys() {
                if !matches!(key.as_str(), Some("value" | "tolerance" | "distribution")) {
                    let key = key.as_str().map_or_else(|| format!("{key:?}"), str::to_string);
                    problems.push(Problem::new(
                        format!("{path}.{key}"),
                        "unknown field; a parameter's mapping has value, tolerance and distribution",
                    ));
                    bad = true;
                }
            }
            let distribution = match map.get("distribution").map(|d| d.as_str()) {
                None => Distribution::Normal,
                Some(Some("normal")) => Distribution::Normal,
                Some(Some("uniform")) => Distribution::Uniform,
                Some(_) => {
                    problems.push(Problem::new(format!("{path}.distribution"), "expected normal or uniform"));
                    bad = true;
                    Distribution::Normal
                }
            };
            let (Some(v), Some(t)) = (map.get("value"), map.get("tolerance")) else {
                problems.push(Problem::new(path, "a parameter written as a mapping needs value and tolerance"));
                return None;
            };
            (!bad).then(|| (v.clone(), Some((t.clone(), distribution))))
        }
        _ => Some((value.clone(), None)),
    }
}

/// A tolerance `t` read with dimension `dim` (`None`: a bare number or an expression) for a
/// parameter of dimension `of`, written `text`, whose value the file writes in `unit`: SI,
/// finite and non-negative, in the parameter's dimension; a bare number for a parameter written
/// with a unit is refused (SI or the value's unit? it must say).
fn tolerance_value(t: f64, dim: Option<Dim>, of: Option<Dim>, text: &Value, unit: Option<&str>) -> Result<f64, String> {
    let bare = matches!(text, Value::Number(_)) || text.as_str().is_some_and(|s| s.trim().parse::<f64>().is_ok());
    if let (Some(d), Some(f)) = (dim, of) {
        if d != f {
            return Err(format!("is {d}, expected {f} (the parameter's dimension)"));
        }
    }
    if let (true, Some(unit)) = (bare, unit.filter(|_| of.is_some())) {
        return Err(format!(
            "write the tolerance with its unit (as the value, in {unit}, say '{} {unit}')",
            text_of(text)
        ));
    }
    if !t.is_finite() || t < 0.0 {
        return Err(format!("{t}: expected a non-negative tolerance in the parameter's unit"));
    }
    Ok(t)
}

/// A YAML scalar's text (a number or a string) for a message.
fn text_of(value: &Value) -> String {
    match value {
        Value::String(s) => s.trim().to_string(),
        Value::Number(n) => n.to_string(),
        other => format!("{other:?}"),
    }
}

/// One parameter's value and dimension: the file's `value`, or `given` from outside over it (a
/// bare number SI with the file's dimension; with a unit, of the file's dimension), and a warning
/// when a bare number is far from the value the file writes with a unit ([`FAR_FACTOR`]).
/// `euler` is set when the file's value uses Euler's number `e`.
fn parameter(
    value: &Value,
    given: Option<&str>,
    params: &[Parameter],
    name: &str,
    names: &[String],
    euler: &std::cell::Cell<bool>,
) -> Result<(f64, Option<Dim>, Option<String>), String> {
    let (file, dim) = number(value, params, name, names, euler)?;
    let mut warning = None;
    let (v, d) = match given {
        None => (file, dim),
        Some(text) => match text.trim().parse::<f64>() {
            Ok(v) => {
                let ratio = (v / file).abs();
                if let (Some(d), Some(written)) = (dim, value.as_str().filter(|t| unit_text(t).is_some())) {
                    if ratio.is_finite() && ratio != 0.0 && !(1.0 / FAR_FACTOR..=FAR_FACTOR).contains(&ratio) {
                        let unit = unit_text(written).unwrap_or_default();
                        let far =
                            if ratio > 1.0 { format!("{ratio:.0} times") } else { format!("1/{:.0} of", 1.0 / ratio) };
                        let si = si_unit(d).map_or(String::new(), |u| format!(" {u}"));
                        let text = text.trim();
                        warning = Some(format!(
                            "the bare number {text} is read as SI, {text}{si}, {far} the file's value {}; \
                             write {name}='{text} {unit}' to give it in {unit}",
                            written.trim()
                        ));
                    }
                }
                (v, dim)
            }
            Err(_) => match number(&Value::String(text.to_string()), params, name, names, euler)? {
                (_, Some(d)) if dim.is_some_and(|f| f != d) => {
                    let expected = dim.map_or(String::new(), |f| f.to_string());
                    return Err(format!("'{text}' is {d}, expected {expected} (the dimension of the file's value)"));
                }
                (v, d) => (v, d.or(dim)),
            },
        },
    };
    if v.is_finite() {
        Ok((v, d, warning))
    } else {
        Err(format!("evaluates to {v}; expected a finite number"))
    }
}

/// A value written where a number goes: a number, a number with a unit, or an expression of the
/// parameters `params` (`own` is the parameter being defined, if any, for the message of a
/// cycle). The SI value and the unit's dimension; `euler` is set when it uses Euler's number `e`.
fn number(
    value: &Value,
    params: &[Parameter],
    own: &str,
    names: &[String],
    euler: &std::cell::Cell<bool>,
) -> Result<(f64, Option<Dim>), String> {
    match value {
        Value::Number(n) => n.as_f64().map(|v| (v, None)).ok_or_else(|| format!("expected a number, found {n}")),
        Value::String(text) => {
            if let Some(q) = quantity(text) {
                return q.map(|(v, d)| (v, Some(d)));
            }
            if let Some(message) = super::parse::too_large(text) {
                return Err(message);
            }
            let failed = std::cell::Cell::new(false);
            let known = |name: &str| {
                let v = lookup(params)(name);
                failed.set(failed.get() || v.is_some_and(f64::is_nan));
                euler.set(euler.get() || (name == "e" && v.is_none()));
                v
            };
            let expr = Expr::parse_with(text, &known, &mut |name| {
                Err(if name == own {
                    "a parameter cannot use itself".to_string()
                } else if names.iter().any(|n| n == name) {
                    "a parameter may use only those written before it, so a cycle is refused".to_string()
                } else if params.is_empty() {
                    "expected a number, a number with a unit, or an expression of parameters".to_string()
                } else {
                    let known: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
                    format!("expected a parameter: {}", known.join(", "))
                })
            })
            .map_err(|e| format!("'{text}': {e}"))?;
            let v = expr.constant_value().ok_or_else(|| format!("'{text}' is not a constant"))?;
            if failed.get() {
                // It uses a parameter that could not be read, whose problem is reported.
                return Err(String::new());
            }
            // A single name keeps its parameter's dimension: `mass: L` with L in mm is refused.
            let dim = params.iter().find(|p| p.name == text.trim()).and_then(|p| p.dim);
            Ok((v, dim))
        }
        other => Err(format!("expected a number, a number with a unit or an expression, found {other:?}")),
    }
}

/// What a numeric field holds: its dimension, or `Mixed` where one number stands for several
/// (a tolerance on metres and radians together), which takes a bare number or an expression only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Field {
    Dim(Dim),
    Mixed,
}

/// The kind of the numeric field `key` of an entry of `section` whose `type` is `kind`; `None` when
/// the field is not a number (a name, an expression of time and the state, a flag).
pub fn field(section: &str, kind: Option<&str>, key: &str) -> Option<Field> {
    use Field::{Dim as D, Mixed};
    Some(match (section, key) {
        (_, "points" | "position" | "point" | "point_i" | "point_j") => D(Dim::LENGTH),
        ("bodies", "mass") => D(Dim::MASS),
        ("bodies", "inertia") => D(Dim::INERTIA),
        ("bodies", "angle") => D(Dim::ANGLE),
        ("bodies", "velocity") => D(Dim::VELOCITY),
        ("bodies", "omega") => D(Dim::ANGULAR_VELOCITY),
        ("joints", "axis_i" | "axis_j" | "axis") => D(Dim::NONE),
        ("joints", "at") => D(Dim::LENGTH),
        // A cam's radius is an expression of the polar angle `psi`, read when the joint compiles.
        ("joints", "radius") if kind == Some("cam") => return None,
        ("joints", "offset" | "length" | "radius" | "radius_i" | "radius_j" | "roller_radius") => D(Dim::LENGTH),
        ("joints", "value") if kind == Some("absolute_angle") => D(Dim::ANGLE),
        ("joints", "value") => D(Dim::LENGTH),
        ("forces", "stiffness") if kind == Some("rotational_spring_damper") => D(Dim::ROTATIONAL_STIFFNESS),
        ("forces", "stiffness") => D(Dim::STIFFNESS),
        ("forces", "damping") if kind == Some("rotational_spring_damper") => D(Dim::ROTATIONAL_DAMPING),
        ("forces", "damping") => D(Dim::DAMPING),
        ("forces", "free_length") => D(Dim::LENGTH),
        ("forces", "free_angle") => D(Dim::ANGLE),
        ("analyses", "t_start" | "t_end" | "step") => D(Dim::TIME),
        ("solver", "max_rotation") => D(Dim::ANGLE),
        ("solver", "initial_step" | "max_step") => D(Dim::TIME),
        ("solver", "min_substep" | "singular_condition" | "rtol" | "alpha" | "max_iterations" | "max_order") => {
            D(Dim::NONE)
        }
        ("solver", "max_steps") => D(Dim::NONE),
        ("friction", "mu") => D(Dim::NONE),
        ("friction", "radius" | "length") => D(Dim::LENGTH),
        ("friction", "transition_velocity") => D(Dim::VELOCITY),
        ("solver", "tolerance" | "atol") => Mixed,
        _ => return None,
    })
}

/// Replace every number written with a unit or as an expression of `params` in the numeric fields
/// of the file's sections (`root`, the whole file) by its SI number; push a problem, with the
/// field's path, for each that cannot be read or has the wrong dimension. The derivatives of
/// each field written as an expression of the parameters, by path ([`Gradients::fields`]).
pub fn resolve(root: &mut Mapping, params: &[Parameter], problems: &mut Vec<Problem>) -> HashMap<String, Vec<f64>> {
    let mut at = Resolved { params, problems, gradients: HashMap::new() };
    if let Some(g) = root.get_mut("gravity") {
        numbers("gravity", g, Field::Dim(Dim::ACCELERATION), &mut at);
    }
    if let Some(Value::Mapping(ground)) = root.get_mut("ground") {
        entry("ground", "ground", None, ground, &mut at);
    }
    for section in ["bodies", "joints", "drivers", "forces", "measures", "analyses"] {
        let Some(Value::Mapping(entries)) = root.get_mut(section) else { continue };
        for (name, value) in entries.iter_mut() {
            let (Some(name), Value::Mapping(map)) = (name.as_str().map(str::to_string), value) else { continue };
            let kind = map.get("type").and_then(Value::as_str).map(str::to_string);
            entry(section, &format!("{section}.{name}"), kind.as_deref(), map, &mut at);
        }
    }
    at.gradients
}

/// What [`resolve`] reads the fields with, and what it finds: the parameters, the problems, and
/// each expression's derivatives by path.
struct Resolved<'a> {
    params: &'a [Parameter],
    problems: &'a mut Vec<Problem>,
    gradients: HashMap<String, Vec<f64>>,
}

/// The numeric fields of one entry (and of its `solver:`, `points:` and `points_global:` mappings:
/// a point's coordinates, or the `distances` of one placed by lengths).
fn entry(section: &str, path: &str, kind: Option<&str>, map: &mut Mapping, at: &mut Resolved) {
    for (key, value) in map.iter_mut() {
        let Some(key) = key.as_str() else { continue };
        let here = format!("{path}.{key}");
        match (key, value) {
            ("solver", Value::Mapping(solver)) => entry("solver", &here, None, solver, at),
            ("friction", Value::Mapping(friction)) => entry("friction", &here, None, friction, at),
            // A cam's profile: its period, and points given inline (lengths); `x` and `y` as text
            // are expressions of `u` or column names, read when the joint compiles.
            ("profile", Value::Mapping(profile)) => {
                for (key, value) in profile.iter_mut() {
                    let path = format!("{here}.{}", key.as_str().unwrap_or("?"));
                    match (key.as_str(), &value) {
                        (Some("period"), _) => numbers(&path, value, Field::Mixed, at),
                        (Some("x" | "y"), Value::Sequence(_)) => numbers(&path, value, Field::Dim(Dim::LENGTH), at),
                        _ => {}
                    }
                }
            }
            ("points" | "points_global", Value::Mapping(points)) => {
                for (point, v) in points.iter_mut() {
                    let path = format!("{here}.{}", point.as_str().unwrap_or("?"));
                    match v {
                        // A point placed by lengths: its two distances.
                        Value::Mapping(by) => {
                            if let Some(d) = by.get_mut("distances") {
                                numbers(&format!("{path}.distances"), d, Field::Dim(Dim::LENGTH), at);
                            }
                        }
                        // Where another point is (`body.B`): a name, not a number.
                        Value::String(_) => {}
                        _ => numbers(&path, v, Field::Dim(Dim::LENGTH), at),
                    }
                }
            }
            (_, value) => {
                if let Some(f) = field(section, kind, key) {
                    numbers(&here, value, f, at);
                }
            }
        }
    }
}

/// A numeric value, or a list of them (a point, an axis), at `path`: strings are read and
/// replaced (an expression's derivatives kept at `path`); numbers and anything else stay for the
/// schema to judge.
fn numbers(path: &str, value: &mut Value, f: Field, at: &mut Resolved) {
    match value {
        Value::Sequence(items) => {
            for (k, item) in items.iter_mut().enumerate() {
                numbers(&format!("{path}[{k}]"), item, f, at);
            }
        }
        Value::String(_) => {
            // A point given by name (`point_i: A`, `position: O`) is a name, not a number.
            if matches!(path.rsplit('.').next(), Some("point" | "point_i" | "point_j" | "position")) {
                return;
            }
            match number(value, at.params, "", &[], &std::cell::Cell::new(false)) {
                Ok((v, dim)) => {
                    let wrong = match (f, dim) {
                        (Field::Dim(want), Some(d)) if d != want => Some(format!("is {d}, expected {want}")),
                        (Field::Mixed, Some(d)) => Some(format!(
                            "is {d}; this setting applies to lengths and angles alike, so write a bare number (SI)"
                        )),
                        _ => None,
                    };
                    if let Some(w) = wrong {
                        let text = value.as_str().unwrap_or_default();
                        let unit = text.trim().trim_start_matches(|c: char| !c.is_ascii_alphabetic()).trim();
                        at.problems.push(Problem::new(path, format!("'{unit}' {w}")));
                    } else if !v.is_finite() {
                        at.problems.push(Problem::new(path, format!("evaluates to {v}; expected a finite number")));
                    } else {
                        let text = value.as_str().unwrap_or_default();
                        if let Some(d) = derivatives(text, at.params, at.params.len()) {
                            at.gradients.insert(path.to_string(), d);
                        }
                        *value = as_yaml(v);
                    }
                }
                // An empty message holds the place of a problem reported at a parameter.
                Err(e) => at.problems.push(Problem::new(path, e)),
            }
        }
        _ => {}
    }
}

/// A number as YAML: whole numbers as integers, so that integer settings (`max_order`) read them.
fn as_yaml(v: f64) -> Value {
    // 2^53: the largest range in which every whole f64 is exact as an i64.
    if v.fract() == 0.0 && v.abs() < 9.007_199_254_740_992e15 {
        Value::Number((v as i64).into())
    } else {
        Value::Number(v.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(text: &str, overrides: &[(&str, &str)]) -> (Vec<Parameter>, Vec<Problem>) {
        let v: Value = serde_yaml_ng::from_str(text).unwrap();
        let o: Vec<(String, String)> = overrides.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        let mut problems = Vec::new();
        (evaluate(Some(&v), &o, &mut problems), problems)
    }

    #[test]
    fn parameters_read_numbers_units_and_earlier_parameters() {
        let (p, problems) = params("{r: 100 mm, L: 0.3, m: 2 kg, I: 'm * L^2 / 12', k: 2*r}", &[]);
        assert!(problems.is_empty(), "{problems:?}");
        let v: Vec<f64> = p.iter().map(|p| p.value).collect();
        assert_eq!(v, vec![0.1, 0.3, 2.0, 2.0 * 0.3 * 0.3 / 12.0, 0.2]);
        assert_eq!(p[0].dim, Some(Dim::LENGTH));
        assert_eq!(p[3].dim, None);
    }

    /// `m: rho * r`: d m / d r = rho, d m / d rho = r, d m / d m = 1 (set from outside, it
    /// replaces its expression); a parameter after it follows it, and `e` named as a parameter
    /// is differentiated as one. Exact: one dual-number product each.
    #[test]
    fn a_parameters_derivatives_follow_the_expressions_before_it() {
        let (p, problems) = params("{rho: 7800, r: 0.1, m: rho * r, w: '2 * m', e: 3 mm, f: e^2}", &[]);
        assert!(problems.is_empty(), "{problems:?}");
        let g: Vec<&[f64]> = p.iter().map(|p| p.gradient.as_slice()).collect();
        assert_eq!(g[0], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(g[2], [0.1, 7800.0, 1.0, 0.0, 0.0, 0.0]);
        assert_eq!(g[3], [0.2, 15600.0, 2.0, 1.0, 0.0, 0.0]);
        assert_eq!(g[5], [0.0, 0.0, 0.0, 0.0, 2.0 * 0.003, 1.0]);
        // Set from outside, m has no expression: its derivative is its own.
        let (p, _) = params("{rho: 7800, r: 0.1, m: rho * r, w: '2 * m'}", &[("m", "700")]);
        assert_eq!(
            (p[2].gradient.as_slice(), p[3].gradient.as_slice()),
            (&[0.0, 0.0, 1.0, 0.0][..], &[0.0, 0.0, 2.0, 1.0][..])
        );
    }

    #[test]
    fn a_later_parameter_itself_or_an_unknown_name_is_refused_with_its_path() {
        for (text, path, says) in [
            ("{a: 2*b, b: 1}", "parameters.a", "written before it"),
            ("{a: a + 1}", "parameters.a", "cannot use itself"),
            ("{a: 1, b: 2*c}", "parameters.b", "unknown name 'c'"),
            ("{t: 1}", "parameters.t", "other than t and pi"),
            ("{a: 1e308, b: a*10}", "parameters.b", "finite"),
            ("{a: 3 furlongs}", "parameters.a", "unknown unit"),
        ] {
            let (_, problems) = params(text, &[]);
            assert!(problems.iter().any(|p| p.path == path && p.message.contains(says)), "{text}: {problems:?}");
        }
    }

    #[test]
    fn overrides_are_si_or_converted_and_keep_the_dimension() {
        let (p, problems) = params("{r: 100 mm, d: 2*r}", &[("r", "0.12")]);
        assert!(problems.is_empty(), "{problems:?}");
        assert_eq!((p[0].value, p[1].value), (0.12, 0.24));
        let (p, _) = params("{r: 100 mm}", &[("r", "300 mm")]);
        assert!((p[0].value - 0.3).abs() < 1e-16);
        let (_, problems) = params("{r: 100 mm}", &[("r", "3 kg")]);
        assert!(problems[0].message.contains("is a mass, expected a length"), "{problems:?}");
        let (_, problems) = params("{r: 100 mm}", &[("s", "1")]);
        assert!(problems[0].path == "parameters.s" && problems[0].message.contains("defines: r"), "{problems:?}");
    }

    /// The rule for a bare number from outside: SI, with a warning beyond a factor of 100 from
    /// the value the file writes with a unit, and none within it, none for a value with a unit
    /// and none for a parameter the file writes bare.
    #[test]
    fn a_bare_number_is_si_and_far_from_the_files_value_is_warned_of() {
        let (p, problems) = params("{m: 15 mm, L: 0.3, a: 20 deg}", &[("m", "16"), ("L", "300"), ("a", "0.5")]);
        assert!(problems.is_empty(), "{problems:?}");
        assert_eq!(p[0].value, 16.0);
        assert_eq!(p[0].unit.as_deref(), Some("mm"));
        let w = p[0].warning.as_deref().expect("16 m is 1067 times 15 mm");
        assert!(w.contains("read as SI, 16 m, 1067 times the file's value 15 mm") && w.contains("m='16 mm'"), "{w}");
        // L is written bare (SI): 300 is what it says. 0.5 rad is 1.4 times 20 deg.
        assert_eq!((p[1].warning.as_ref(), p[2].warning.as_ref()), (None, None));
        let (p, _) = params("{m: 15 mm}", &[("m", "0.016"), ("m", "16 mm")]);
        assert!(p[0].warning.is_none() && (p[0].value - 0.016).abs() < 1e-17, "{p:?}");
        // Just inside and just outside the factor, both ways: 15 mm * 100 = 1.5 m.
        for (given, warned) in [("1.5", false), ("1.51", true), ("0.00015", false), ("0.000149", true)] {
            let (p, _) = params("{m: 15 mm}", &[("m", given)]);
            assert_eq!(p[0].warning.is_some(), warned, "{given}: {:?}", p[0].warning);
        }
        let (p, _) = params("{m: 15 mm}", &[("m", "0.0001")]);
        assert!(p[0].warning.as_deref().unwrap_or_default().contains("1/150 of the file's value"), "{p:?}");
    }

    #[test]
    fn e_is_a_parameter_unless_one_before_it_uses_eulers_number() {
        let (p, problems) = params("{e: 12 mm, d: 2*e}", &[]);
        assert!(problems.is_empty(), "{problems:?}");
        assert!((p[1].value - 0.024).abs() < 1e-17);
        let (p, problems) = params("{g: e^2}", &[]);
        assert!(problems.is_empty() && (p[0].value - std::f64::consts::E.powi(2)).abs() < 1e-15);
        let (_, problems) = params("{g: 2*e, e: 12 mm}", &[]);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0].path, "parameters.e");
        assert!(problems[0].message.contains("parameters.g before it uses e as Euler's number"), "{problems:?}");
        assert!(problems[0].message.contains("rename this parameter"), "{problems:?}");
        // A number's exponent is no use of e.
        let (_, problems) = params("{g: 3e2, e: 1}", &[]);
        assert!(problems.is_empty(), "{problems:?}");
    }

    #[test]
    fn fields_are_resolved_and_a_wrong_dimension_names_the_field() {
        let text = "{bodies: {crank: {mass: 40 mm, inertia: 'm*r^2', position: ['r/2', 0], points: {A: [r, 0]}}}}";
        let mut root: Mapping = serde_yaml_ng::from_str(text).unwrap();
        let (p, _) = params("{r: 100 mm, m: 2}", &[]);
        let mut problems = Vec::new();
        resolve(&mut root, &p, &mut problems);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0].path, "bodies.crank.mass");
        assert_eq!(problems[0].message, "'mm' is a length, expected a mass");
        let crank = &root["bodies"]["crank"];
        assert_eq!(crank["inertia"].as_f64(), Some(2.0 * 0.1 * 0.1));
        assert_eq!(crank["position"][0].as_f64(), Some(0.05));
        assert_eq!(crank["points"]["A"][0].as_f64(), Some(0.1));
    }

    /// Each field written as an expression keeps its derivatives by path; numbers and numbers
    /// with units keep none.
    #[test]
    fn an_expressions_derivatives_are_kept_at_its_path() {
        let text = "{bodies: {crank: {mass: 2 kg, inertia: 'm*r^2', position: ['r/2', 0], points: {A: [r, 0]}}}}";
        let mut root: Mapping = serde_yaml_ng::from_str(text).unwrap();
        let (p, _) = params("{r: 100 mm, m: 2}", &[]);
        let fields = resolve(&mut root, &p, &mut Vec::new());
        let mut paths: Vec<&str> = fields.keys().map(String::as_str).collect();
        paths.sort();
        assert_eq!(paths, ["bodies.crank.inertia", "bodies.crank.points.A[0]", "bodies.crank.position[0]"]);
        assert_eq!(fields["bodies.crank.inertia"], [2.0 * 2.0 * 0.1, 0.1 * 0.1]);
        assert_eq!(fields["bodies.crank.position[0]"], [0.5, 0.0]);
        assert_eq!(fields["bodies.crank.points.A[0]"], [1.0, 0.0]);
    }

    /// Both forms give the tolerance in SI with its distribution; the value reads as the plain
    /// parameter does, to the bit; a value given from outside keeps the file's tolerance.
    #[test]
    fn a_tolerance_is_read_in_both_forms_and_kept_by_a_value_given() {
        let text = "{r: 150 mm ± 0.1 mm, L: '300 mm +- 0.2 mm', w: {value: 2 rad/s, tolerance: 0.3 rad/s, distribution: uniform}, k: 2*r}";
        let (p, problems) = params(text, &[]);
        assert!(problems.is_empty(), "{problems:?}");
        let (plain, _) = params("{r: 150 mm, L: 300 mm, w: 2 rad/s, k: 2*r}", &[]);
        for (a, b) in p.iter().zip(&plain) {
            assert_eq!((a.value.to_bits(), &a.unit, &a.gradient), (b.value.to_bits(), &b.unit, &b.gradient));
        }
        let t: Vec<Option<Tolerance>> = p.iter().map(|p| p.tolerance).collect();
        assert_eq!(t[0], Some(Tolerance { value: 0.1e-3, distribution: Distribution::Normal }));
        assert_eq!(t[1].map(|t| t.value), Some(0.2e-3));
        assert_eq!(t[2], Some(Tolerance { value: 0.3, distribution: Distribution::Uniform }));
        assert_eq!(t[3], None);
        // sigma: t / 3 for a normal spread, t / sqrt(3) for a uniform one.
        assert_eq!(t[0].unwrap().sigma(), 0.1e-3 / 3.0);
        assert_eq!(t[2].unwrap().sigma(), 0.3 / 3f64.sqrt());
        let (p, problems) = params(text, &[("r", "160 mm")]);
        assert!(problems.is_empty(), "{problems:?}");
        assert!((p[0].value - 0.16).abs() < 1e-16 && p[0].tolerance == t[0], "{:?}", p[0]);
    }

    #[test]
    fn a_bad_tolerance_is_refused_at_its_path() {
        for (text, path, says) in [
            ("{r: 150 mm ± 0.1 kg}", "parameters.r.tolerance", "is a mass, expected a length"),
            ("{r: 150 mm ± -0.1 mm}", "parameters.r.tolerance", "non-negative"),
            ("{r: 150 mm ± 0.1}", "parameters.r.tolerance", "with its unit"),
            (
                "{r: {value: 150 mm, tolerance: 0.1 mm, distribution: flat}}",
                "parameters.r.distribution",
                "normal or uniform",
            ),
            ("{r: {value: 150 mm, tol: 0.1 mm}}", "parameters.r.tol", "unknown field"),
            ("{r: {value: 150 mm}}", "parameters.r", "needs value and tolerance"),
            ("{r: 150 mm ± x}", "parameters.r.tolerance", "unknown name 'x'"),
        ] {
            let (_, problems) = params(text, &[]);
            assert!(problems.iter().any(|p| p.path == path && p.message.contains(says)), "{text}: {problems:?}");
        }
        // A bare tolerance of a bare (SI) value is SI.
        let (p, problems) = params("{L: 0.3 ± 0.001}", &[]);
        assert!(problems.is_empty() && p[0].tolerance.map(|t| t.value) == Some(0.001), "{problems:?}");
    }
}
