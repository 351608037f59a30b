//! Sweeps: one analysis run for many values of a model's parameters, in parallel, each run
//! reduced to a few numbers by output expressions.
//!
//! An output is a [`Functional`] of the run's result columns (the aggregations and their
//! quadrature are described there): `max(slider.x) - min(slider.x)`, `peak(motor.effort)`,
//! `mean(motor.effort * crank.omega)`, `at(0.5, crank.phi)`. Outputs name no parameters (the
//! variants change them); a model's `summaries:` are functionals of the same kind, which may,
//! and an output may be one of them by name (`stroke`).
//!
//! With gradients ([`sweep_with_gradients`]) each run is asked for the sensitivities of its
//! columns, and each output's derivative with respect to each parameter follows from them as a
//! summary's does ([`Output::gradient`]).
//!
//! The sweep sits above `results`: it runs analyses ([`Model::run`]) on models made with
//! [`Model::with_parameters`] and reads their [`Results`]; nothing below imports it.

use crate::error::{Error, Problem};
use crate::expr::functional::Functional;
use crate::model::structure::Dyad;
use crate::progress::{Progress, StopToken};
use crate::{Model, Results, RunOptions};
use rayon::prelude::*;

/// An output of a sweep: a name and what it reads of a run.
#[derive(Debug, Clone)]
pub struct Output {
    /// The output's name (a column of the sweep's table).
    pub name: String,
    /// Its expression, or the model's summary it is.
    pub of: Of,
}

/// What an output reads of a run.
#[derive(Debug, Clone)]
pub enum Of {
    /// A functional of the result columns (boxed: it is large beside a name).
    Functional(Box<Functional>),
    /// The model's summary of this name (`summaries:`), as the run's summary has it.
    Summary(String),
}

impl Output {
    /// Read `source`, checking its shape (aggregations, their arguments, the expression around
    /// them); the column names are checked against each run's results. A bare name that is no
    /// functional is a summary's, checked against each run's summaries. `Err` says what is
    /// wrong, for the output `name`.
    pub fn parse(name: &str, source: &str) -> Result<Output, String> {
        let no_names = |_: &str| None;
        let of = match Functional::parse(source, &no_names) {
            Ok(functional) => Of::Functional(Box::new(functional)),
            Err(_) if crate::model::is_identifier(source.trim()) => Of::Summary(source.trim().to_string()),
            Err(e) => return Err(e),
        };
        Ok(Output { name: name.to_string(), of })
    }

    /// The output's value for one run's results. `Err` names an unknown column or summary, or a
    /// value that is not a finite number.
    pub fn evaluate(&self, results: &Results) -> Result<f64, String> {
        match &self.of {
            Of::Functional(f) => f.eval(&results.time, &|name| results.column(name)).map_err(|e| e.to_string()),
            Of::Summary(name) => results.summary.summaries.as_ref().and_then(|s| s.get(name).copied()).ok_or_else(|| {
                format!("'{name}' is neither an expression of aggregations of result columns nor a summary of the model")
            }),
        }
    }

    /// The output's derivative with respect to each parameter of the run's sensitivities
    /// ([`Results::sensitivities`], in their order): a functional's from its columns'
    /// derivatives ([`Functional::derivative`]: the rules at a largest row are the summaries'),
    /// a summary's as the run's summary has it. `Err` names what has no derivative (a column
    /// without derivatives, a run asked for none).
    pub fn gradient(&self, results: &Results) -> Result<Vec<f64>, String> {
        let s = results.sensitivities.as_ref().ok_or("the run has no sensitivities")?;
        let missing = |p: &str| format!("no derivative of output {} with respect to {p}", self.name);
        s.parameters
            .iter()
            .zip(&s.values)
            .map(|(p, values)| match &self.of {
                Of::Functional(f) => {
                    let derivative = |c: &str| s.names.iter().position(|n| n == c).map(|k| values[k].as_slice());
                    // Outputs name no parameters: no named value has a derivative.
                    f.derivative(&results.time, &|c| results.column(c), &derivative, &|_| f64::NAN)
                        .map_err(|e| format!("{}: {e}", missing(p)))
                }
                Of::Summary(name) => {
                    let d = results.summary.sensitivities.as_ref().and_then(|d| d.get(name)?.get(p).copied());
                    d.ok_or_else(|| missing(p))
                }
            })
            .collect()
    }
}

/// The outcome of one variant: its outputs in the order given, or the error that stopped it.
pub type Row = Result<Vec<f64>, Error>;

/// Run `analysis` for each of `variants` (parameter values, `(name, text)` as
/// [`Model::with_parameters`] takes them) on `workers` threads (all cores when `None`), each run
/// reduced to `outputs`. A variant that fails is an `Err` row, not the end of the sweep; an
/// output that cannot be evaluated on a run is a model error at `outputs.<name>`. Rows are in the
/// order of `variants` whatever the threads. `progress` counts the variants finished
/// ([`Progress::finished`]); once `stop` is stopped, the variants running end as
/// [`Error::Interrupted`] at their next step, and so does every later one at its first.
pub fn sweep(
    model: &Model,
    analysis: &str,
    variants: &[Vec<(String, String)>],
    outputs: &[Output],
    workers: Option<usize>,
    progress: &Progress,
    stop: &StopToken,
) -> Result<Vec<Row>, Error> {
    sweep_with_gradients(model, analysis, variants, outputs, &[], workers, progress, stop)
}

/// As [`sweep`], each row's outputs followed by their derivatives with respect to each of
/// `gradients` (names of the model's parameters), output by output ([`Output::gradient`]; each
/// run asked for those sensitivities). With `gradients` empty it is [`sweep`].
#[allow(clippy::too_many_arguments)]
pub fn sweep_with_gradients(
    model: &Model,
    analysis: &str,
    variants: &[Vec<(String, String)>],
    outputs: &[Output],
    gradients: &[String],
    workers: Option<usize>,
    progress: &Progress,
    stop: &StopToken,
) -> Result<Vec<Row>, Error> {
    // An output named as a summary the model does not have: refused before anything runs.
    for o in outputs {
        if let Of::Summary(name) = &o.of {
            if !model.summaries.contains_key(name) {
                let known: Vec<&str> = model.summaries.keys().map(String::as_str).collect();
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                let message = format!(
                    "'{name}' is neither an expression of aggregations of result columns nor a summary of the model \
                     (its summaries: {known})"
                );
                return Err(Error::Model(vec![Problem::new(format!("outputs.{}", o.name), message)]));
            }
        }
    }
    let t_start = model.analysis(analysis)?.t_start;
    // The file's text parsed once; each variant reads its parameters from the document.
    let document = model.document()?;
    // Every variant is assembled on the nominal model's branches and changes branch where the
    // nominal run does (a change point's mechanism passes its flat position every turn) and
    // nowhere else, so that a table never mixes assembly modes unseen (docs/model-format.md,
    // "Branches"). A nominal model that cannot be assembled leaves each variant its own
    // `branches:`; one that fails its run, its changes unchecked.
    let nominal = crate::analysis::assembled_branches(model, analysis);
    let nominal_changes: Option<Vec<String>> = model
        .run(analysis, &RunOptions::default())
        .ok()
        .map(|r| r.summary.branch_changes.iter().map(|c| c.joint.clone()).collect());
    let one = |values: &Vec<(String, String)>| -> Row {
        let run = || -> Row {
            // Stopped before this variant began: not compiled, not run.
            if stop.stopped() {
                return Err(Error::Interrupted { time: t_start });
            }
            let mut variant = model.with_parameters_in(&document, values)?;
            if !nominal.is_empty() {
                variant.branches = nominal
                    .iter()
                    .filter_map(|&(joints, side)| {
                        Some((Dyad::new(&variant.joints, &variant.bodies, joints).ok()?, side))
                    })
                    .collect();
            }
            let options = RunOptions { stop: stop.clone(), sensitivities: gradients.to_vec(), ..RunOptions::default() };
            let results = variant.run(analysis, &options).map_err(|f| f.error)?;
            if let Some(expected) = &nominal_changes {
                let changes = &results.summary.branch_changes;
                let same = |k: usize| changes.get(k).map(|c| &c.joint) == expected.get(k);
                if let Some(k) = (0..changes.len().max(expected.len())).find(|&k| !same(k)) {
                    return Err(match changes.get(k) {
                        Some(change) => change.error("a sweep keeps the nominal model's branches"),
                        None => Error::Branch {
                            time: t_start,
                            joint: expected[k].clone(),
                            detail: format!(
                                "the nominal run's dyad of joint {} changes branch, and this variant's does not",
                                expected[k]
                            ),
                        },
                    });
                }
            }
            let at = |o: &Output, e: String| Error::Model(vec![Problem::new(format!("outputs.{}", o.name), e)]);
            let mut row = outputs.iter().map(|o| o.evaluate(&results).map_err(|e| at(o, e))).collect::<Row>()?;
            if !gradients.is_empty() {
                for o in outputs {
                    row.extend(o.gradient(&results).map_err(|e| at(o, e))?);
                }
            }
            Ok(row)
        };
        let row = run();
        progress.finish_part();
        row
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(k) = workers {
        pool = pool.num_threads(k.max(1));
    }
    let pool = pool.build().map_err(|e| Error::Model(vec![Problem::new("workers", e.to_string())]))?;
    Ok(pool.install(|| variants.par_iter().map(one).collect()))
}
