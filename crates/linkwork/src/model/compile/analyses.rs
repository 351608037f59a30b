//! Analyses: each entry's kind, time span, output step, active drivers and forces, and its
//! solver and integrator settings, checked; and an analysis revised by a run's overrides.

use super::*;

/// The most output points one analysis may ask for; more would exhaust memory rather than finish.
const MAX_OUTPUT_POINTS: f64 = 1e7;

/// The loosest `rtol` and `atol` a dynamic analysis accepts: `1e-2`. The error test lets each
/// step err by about the tolerance, relative to the state (`rtol`) or in its units (`atol`: m,
/// rad, m/s); above a percent the steps' errors are as large as the motion over a few dozen
/// steps (the double pendulum at `0.1` ends with a pin 4 cm off its anchor, at `1e300` 1,168 m
/// off, and both passed), and no check after the run could tell such results from an answer.
pub const MAX_INTEGRATOR_TOLERANCE: f64 = 1e-2;

impl Cx<'_> {
    /// Every analysis of the file, each checked against its kind.
    pub(super) fn analyses(&mut self) -> IndexMap<String, Analysis> {
        let spec = self.spec;
        let mut out = IndexMap::new();
        for (name, a) in &spec.analyses {
            let path = format!("analyses.{name}");
            let driver_names: Vec<&str> = spec.drivers.keys().map(String::as_str).collect();
            let drivers = self.selection(&path, "drivers", "driver", &driver_names, a.drivers.as_deref());
            let force_names: Vec<&str> = spec.forces.keys().map(String::as_str).collect();
            let forces = self.selection(&path, "forces", "force", &force_names, a.forces.as_deref());
            let timing = timing(&mut self.problems, name, a, &Fallback::file());
            if a.kind != AnalysisKind::Modes && a.about.is_some() {
                self.problem(format!("{path}.about"), "only a modes analysis has a point to linearise about");
                continue;
            }
            if let Some(o) = &a.outputs {
                let path = format!("{path}.outputs");
                let body_names: Vec<&str> = spec.bodies.keys().map(String::as_str).collect();
                self.selection(&path, "bodies", "body", &body_names, Some(&o.bodies));
                let joint_names: Vec<&str> = spec.joints.keys().map(String::as_str).collect();
                self.selection(&path, "joints", "joint", &joint_names, Some(&o.joints));
            }
            let Some(Timing { t_start, t_end, step, settings, integrator }) = timing else { continue };
            out.insert(
                name.clone(),
                Analysis {
                    name: name.clone(),
                    kind: a.kind,
                    drivers,
                    forces,
                    t_start,
                    t_end,
                    step,
                    settings,
                    integrator,
                    about: a.about.unwrap_or_default(),
                    outputs: a.outputs.clone(),
                },
            );
        }
        out
    }

    /// The indices into `known` (the model's `section`: drivers or forces) of the names an
    /// analysis at `path` lists, every one when it lists none; each unknown name is a problem at
    /// `<path>.<section>[k]` (a name whose own entry is broken was reported there already).
    pub(super) fn selection(
        &mut self,
        path: &str,
        section: &str,
        what: &str,
        known: &[&str],
        list: Option<&[String]>,
    ) -> Vec<usize> {
        let Some(list) = list else { return (0..known.len()).collect() };
        list.iter()
            .enumerate()
            .filter_map(|(k, d)| match known.iter().position(|&n| n == d) {
                Some(i) => Some(i),
                None if self.broken.contains(&format!("{section}.{d}")) => None,
                None => {
                    let message = if known.is_empty() {
                        format!("unknown {what} '{d}'; the model has no {section}")
                    } else {
                        format!("unknown {what} '{d}'; the model's {section} are: {}", known.join(", "))
                    };
                    self.problem(format!("{path}.{section}[{k}]"), message);
                    None
                }
            })
            .collect()
    }
}

/// What is wrong with output every `h` s (positive) from `t0` to `t1` (not before it), if
/// anything: more than [`MAX_OUTPUT_POINTS`] points, or a step longer than a span that is not
/// empty, which would silently give only the span's two ends.
fn output_step_problem(t0: f64, t1: f64, h: f64) -> Option<String> {
    let span = t1 - t0;
    if span / h > MAX_OUTPUT_POINTS {
        Some(format!("{} output points requested; at most {MAX_OUTPUT_POINTS:e} are allowed", (span / h).ceil()))
    } else if span > 0.0 && h > span {
        Some(format!(
            "the output step ({h} s) is longer than the analysis ({span} s from t_start to t_end), which would give \
             only its two ends; expected at most {span} s"
        ))
    } else {
        None
    }
}

/// What is wrong with stepping by `step` s at the time `t`, if anything: doubles there lie
/// farther apart than half the step, so output times `t_start + k step` (or sub-steps) round to
/// one another and a step can come out as zero. Half: a step must change `t` by at least two
/// units of its spacing for the rounded steps to stay within a factor of two of the one asked.
pub(crate) fn time_round_off(t: f64, step: f64) -> Option<String> {
    let spacing = f64::from_bits(t.abs().to_bits() + 1) - t.abs();
    (spacing > 0.5 * step).then(|| {
        format!(
            "time round-off at t = {} s: double precision spaces times there {spacing:.3e} s apart, too coarse for \
             steps of {step:e} s; keep the analysis's times nearer 0 (shift the drivers' time origin)",
            crate::error::seconds(&t)
        )
    })
}

/// The analysis `base` of a compiled model with the fields `changes` gives: an entry of the model
/// file's `analyses:` of `base`'s type and start, whose `t_end`, `step`, `integrator` and `solver`
/// are read (its `drivers`, `forces` and `about` are not). Checked as the file's own entries
/// are, each problem at its path in the file (`analyses.<name>.t_end`). Another integrator
/// returns the settings that belong to `base`'s (`max_order`, `alpha`, `formulation`) to their
/// defaults; the tolerances, steps and step budget carry over.
pub(crate) fn revise(base: &Analysis, changes: &AnalysisSpec) -> Result<Analysis, Vec<Problem>> {
    debug_assert!(changes.kind == base.kind && changes.t_start == base.t_start, "a change of type or start");
    let mut integrator = base.integrator;
    if let Some(kind) = changes.integrator.filter(|&k| k != base.integrator.kind) {
        let d = IntegratorSettings::default();
        integrator = IntegratorSettings {
            kind,
            max_order: d.max_order,
            alpha: d.alpha,
            formulation: d.formulation,
            fixed_step: d.fixed_step,
            ..base.integrator
        };
    }
    let fallback = Fallback { t_end: Some(base.t_end), step: Some(base.step), settings: base.settings, integrator };
    let mut problems = Vec::new();
    match timing(&mut problems, &base.name, changes, &fallback) {
        Some(Timing { t_start, t_end, step, settings, integrator }) if problems.is_empty() => {
            Ok(Analysis { t_start, t_end, step, settings, integrator, ..base.clone() })
        }
        _ => Err(problems),
    }
}

/// What an analysis has where its entry leaves a field out: the engine's defaults for an entry
/// of a model file (which must give `t_end` and `step`), the compiled analysis for
/// [`revise`].
struct Fallback {
    t_end: Option<f64>,
    step: Option<f64>,
    settings: SolverSettings,
    integrator: IntegratorSettings,
}

impl Fallback {
    /// What a model file leaves out of an analysis: no step, no end, the default settings.
    fn file() -> Fallback {
        Fallback {
            t_end: None,
            step: None,
            settings: SolverSettings::default(),
            integrator: IntegratorSettings::default(),
        }
    }
}

/// The times and solver settings of a compiled analysis.
struct Timing {
    t_start: f64,
    t_end: f64,
    step: f64,
    settings: SolverSettings,
    integrator: IntegratorSettings,
}

/// The times and solver settings of the analysis `name` from its entry `a`, each field it
/// leaves out taken from `base`; `None` after a problem (every one is added to `problems`, at
/// `analyses.<name>.<field>`).
fn timing(problems: &mut Vec<Problem>, name: &str, a: &AnalysisSpec, base: &Fallback) -> Option<Timing> {
    let path = format!("analyses.{name}");
    let t0 = finite(problems, &format!("{path}.t_start"), a.t_start);
    let span = span(problems, &path, a, base, t0);
    let settings = solver_settings(problems, &format!("{path}.solver"), &a.solver, &base.settings);
    let integrator = integrator(problems, &path, name, a, &base.integrator);
    let (t0, (t1, h)) = (t0?, span?);
    if t1 < t0 {
        problems.push(Problem::new(format!("{path}.t_end"), format!("t_end ({t1}) is before t_start ({t0})")));
        return None;
    }
    if let Some(message) = output_step_problem(t0, t1, h) {
        problems.push(Problem::new(format!("{path}.step"), message));
        return None;
    }
    let far = if t0.abs() >= t1.abs() { t0 } else { t1 };
    if let Some(message) = time_round_off(far, h).filter(|_| t1 > t0) {
        let field = if 2.0 * t0.abs() >= t1.abs() { "t_start" } else { "t_end" };
        problems.push(Problem::new(format!("{path}.{field}"), message));
        return None;
    }
    Some(Timing { t_start: t0, t_end: t1, step: h, settings: settings?, integrator: integrator? })
}

/// `(t_end, step)` of the analysis at `path`: both required (unless `base` has them), except
/// that `static` defaults to one equilibrium at `t_start` and `modes` is at `t_start` and takes
/// neither.
fn span(
    problems: &mut Vec<Problem>,
    path: &str,
    a: &AnalysisSpec,
    base: &Fallback,
    t0: Option<f64>,
) -> Option<(f64, f64)> {
    let kind = a.kind;
    if kind == AnalysisKind::Modes {
        for (field, given) in [("t_end", a.t_end.is_some()), ("step", a.step.is_some())] {
            if given {
                problems.push(Problem::new(
                    format!("{path}.{field}"),
                    "a modes analysis is at one time (t_start); remove t_end and step",
                ));
            }
        }
        return if a.t_end.is_some() || a.step.is_some() { None } else { Some((t0?, 1.0)) };
    }
    let t1 = match (a.t_end, base.t_end) {
        (Some(t), _) => finite(problems, &format!("{path}.t_end"), t),
        (None, Some(t)) => Some(t),
        (None, None) if kind == AnalysisKind::Static && a.step.is_none() => return Some((t0?, 1.0)),
        (None, None) => {
            problems.push(Problem::new(
                format!("{path}.t_end"),
                format!("required: the end time of the {} analysis, s", kind.name()),
            ));
            None
        }
    };
    let h = match (a.step, base.step) {
        (Some(h), _) => positive(problems, &format!("{path}.step"), h),
        (None, Some(h)) => Some(h),
        (None, None) => {
            problems.push(Problem::new(format!("{path}.step"), "required: the output step, s"));
            None
        }
    };
    Some((t1?, h?))
}

/// The integrator of the analysis `name` at `path` and its settings, each left out taken from
/// `base`: only a dynamic analysis names one or gives its settings, each given tolerance and
/// step must be positive (a tolerance at most [`MAX_INTEGRATOR_TOLERANCE`]), and each setting
/// must belong to the integrator.
fn integrator(
    problems: &mut Vec<Problem>,
    path: &str,
    name: &str,
    a: &AnalysisSpec,
    base: &IntegratorSettings,
) -> Option<IntegratorSettings> {
    let s = &a.solver;
    let spath = format!("{path}.solver");
    if a.kind != AnalysisKind::Dynamic {
        let given = [
            (format!("{path}.integrator"), a.integrator.is_some()),
            (format!("{spath}.rtol"), s.rtol.is_some()),
            (format!("{spath}.atol"), s.atol.is_some()),
            (format!("{spath}.initial_step"), s.initial_step.is_some()),
            (format!("{spath}.max_step"), s.max_step.is_some()),
            (format!("{spath}.max_order"), s.max_order.is_some()),
            (format!("{spath}.alpha"), s.alpha.is_some()),
            (format!("{spath}.formulation"), s.formulation.is_some()),
        ];
        let mut ok = true;
        for (field, _) in given.into_iter().filter(|(_, given)| *given) {
            let message = format!("only a dynamic analysis has an integrator; '{name}' is {}", a.kind.name());
            problems.push(Problem::new(field, message));
            ok = false;
        }
        return ok.then_some(*base);
    }
    let kind = a.integrator.unwrap_or(base.kind);
    let mut ok = true;
    let mut pos = |problems: &mut Vec<Problem>, field: &str, v: Option<f64>| -> Option<f64> {
        let path = format!("{spath}.{field}");
        let r = positive(problems, &path, v?);
        let r = if matches!(field, "rtol" | "atol") { r.and_then(|v| tolerance_bound(problems, &path, v)) } else { r };
        ok &= r.is_some();
        r
    };
    let rtol = pos(problems, "rtol", s.rtol).unwrap_or(base.rtol);
    let atol = pos(problems, "atol", s.atol).unwrap_or(base.atol);
    let initial_step = pos(problems, "initial_step", s.initial_step).or(base.initial_step);
    let max_step = pos(problems, "max_step", s.max_step).or(base.max_step);
    let bound = IntegratorSettings::order_bound(kind);
    if let Some(k) = s.max_order {
        if kind == IntegratorKind::Hht {
            problems.push(Problem::new(
                format!("{spath}.max_order"),
                "hht has a fixed order (2); max_order is for bdf and abam",
            ));
            ok = false;
        } else if k == 0 || k > bound {
            problems.push(Problem::new(
                format!("{spath}.max_order"),
                format!("expected 1 to {bound} for {}, found {k}", kind.name()),
            ));
            ok = false;
        }
    }
    let alpha = match s.alpha {
        Some(al) if kind != IntegratorKind::Hht => {
            problems.push(Problem::new(format!("{spath}.alpha"), format!("alpha ({al}) is a setting of hht only")));
            ok = false;
            base.alpha
        }
        Some(al) if !(-1.0 / 3.0 - 1e-12..=0.0).contains(&al) => {
            problems.push(Problem::new(format!("{spath}.alpha"), format!("expected alpha in [-1/3, 0], found {al}")));
            ok = false;
            base.alpha
        }
        Some(al) => al,
        None => base.alpha,
    };
    if s.formulation.is_some() && kind != IntegratorKind::Bdf {
        problems.push(Problem::new(format!("{spath}.formulation"), "formulation is a setting of bdf only"));
        ok = false;
    }
    ok.then_some(IntegratorSettings {
        kind,
        rtol,
        atol,
        initial_step,
        max_step,
        max_order: s.max_order.or(base.max_order),
        alpha,
        formulation: s.formulation.unwrap_or(base.formulation),
        ..*base
    })
}

/// The position solver's settings at `path`, each left out taken from `base`.
fn solver_settings(
    problems: &mut Vec<Problem>,
    path: &str,
    s: &SolverSpec,
    base: &SolverSettings,
) -> Option<SolverSettings> {
    let mut ok = true;
    let mut pos = |problems: &mut Vec<Problem>, field: &str, v: Option<f64>, default: f64| -> f64 {
        match v {
            Some(v) => positive(problems, &format!("{path}.{field}"), v).unwrap_or_else(|| {
                ok = false;
                default
            }),
            None => default,
        }
    };
    let tolerance = pos(problems, "tolerance", s.tolerance, base.tolerance);
    let max_rotation = pos(problems, "max_rotation", s.max_rotation, base.max_rotation);
    let min_substep = pos(problems, "min_substep", s.min_substep, base.min_substep);
    let singular_condition = pos(problems, "singular_condition", s.singular_condition, base.singular_condition);
    let max_iterations = s.max_iterations.unwrap_or(base.max_iterations);
    if max_iterations == 0 || max_iterations > 1000 {
        problems.push(Problem::new(
            format!("{path}.max_iterations"),
            format!("expected 1 to 1000 iterations, found {max_iterations}"),
        ));
        ok = false;
    }
    if min_substep >= 1.0 {
        problems.push(Problem::new(format!("{path}.min_substep"), "expected a fraction of the output step below 1"));
        ok = false;
    }
    ok.then_some(SolverSettings { tolerance, max_iterations, max_rotation, min_substep, singular_condition })
}

/// `v`, an integrator's tolerance at `path`, if at most [`MAX_INTEGRATOR_TOLERANCE`].
fn tolerance_bound(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    if v <= MAX_INTEGRATOR_TOLERANCE {
        return Some(v);
    }
    problems.push(Problem::new(
        path,
        format!(
            "expected at most {MAX_INTEGRATOR_TOLERANCE:e}, found {v:e}: a looser tolerance lets each step err by more \
             than a percent of the motion, and the results mean nothing"
        ),
    ));
    None
}

#[cfg(test)]
mod tests {
    use crate::model::Model;
    use crate::Error;

    /// A pendulum with the analyses `analyses` (YAML flow mappings, one a line).
    fn pendulum(analyses: &str) -> Result<Model, Error> {
        Model::from_yaml(&format!(
            "bodies:\n  p: {{mass: 1, inertia: 0.1, position: [1, 0], angle: 0, points: {{o: [-1, 0]}}}}\n\
             joints:\n  o: {{type: revolute, body_i: p, point_i: o, body_j: ground, point_j: [0, 0]}}\n\
             analyses:\n{analyses}"
        ))
    }

    fn problems(analyses: &str) -> Vec<String> {
        match pendulum(analyses) {
            Err(Error::Model(p)) => p.iter().map(|p| p.to_string()).collect(),
            other => panic!("expected a model error, found {other:?}"),
        }
    }

    /// The settings of an integrator belong to a dynamic analysis, as the integrator does (a
    /// kinematic analysis ignored an `rtol` before, while it refused an `integrator`).
    #[test]
    fn dynamics_settings_belong_to_a_dynamic_analysis() {
        let p = problems("  s: {type: static, integrator: hht, solver: {rtol: 1e-3, formulation: index3}}\n");
        let only = "only a dynamic analysis has an integrator; 's' is static";
        for field in ["analyses.s.integrator", "analyses.s.solver.rtol", "analyses.s.solver.formulation"] {
            assert!(p.contains(&format!("{field}: {only}")), "{field}: {p:?}");
        }
        assert_eq!(p.len(), 3, "{p:?}");
    }

    /// An `rtol` below what round-off resolves is raised to it with a warning when the analysis
    /// runs, in the file as in an override (the file refused one below `1e-14` before).
    #[test]
    fn a_tolerance_below_round_off_compiles() {
        let model = pendulum("  d: {type: dynamic, t_end: 1, step: 0.1, solver: {rtol: 1e-16}}\n").unwrap();
        assert_eq!(model.analyses["d"].integrator.rtol, 1e-16);
    }

    /// Every problem of an analysis is reported, not only the first: a bad tolerance does not
    /// hide an end time before the start.
    #[test]
    fn every_problem_of_an_analysis_is_reported() {
        let p = problems("  d: {type: dynamic, t_start: 1, t_end: 0.5, step: 0.1, solver: {atol: 0}}\n");
        assert!(p.iter().any(|p| p == "analyses.d.t_end: t_end (0.5) is before t_start (1)"), "{p:?}");
        assert!(p.iter().any(|p| p == "analyses.d.solver.atol: expected a positive number, found 0"), "{p:?}");
    }
}
