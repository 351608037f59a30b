//! The entry point of every analysis, [`Model::run`]: the analysis a model names, with the
//! changes of one run ([`Overrides`]) checked as the model file's own entries are, dispatched by
//! its type with what the run was given ([`RunOptions`]: a watcher, a stop token, a sink), and
//! the warnings about its tolerances added to its summary.

use super::{dynamic, run_inverse, run_kinematic, run_modes, run_static, tolerance_warnings};
use crate::error::{Error, Problem};
use crate::model::spec::{AnalysisKind, AnalysisSpec, IntegratorKind, LinearisePoint, SolverSpec};
use crate::model::{revise, Analysis, Model};
use crate::progress::{Progress, StopToken};
use crate::results::stream::{CsvSink, RowSink, Stream};
use crate::results::{Failure, Results};
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

/// Changes to an analysis for one run (the command line's `--integrator`, `--rtol`, `--atol`,
/// `--t-end` and `--step`); `None` keeps the file's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// The integrator of a dynamic analysis.
    pub integrator: Option<IntegratorKind>,
    /// Relative tolerance of a dynamic analysis.
    pub rtol: Option<f64>,
    /// Absolute tolerance of a dynamic analysis.
    pub atol: Option<f64>,
    /// End time, s.
    pub t_end: Option<f64>,
    /// Output step, s.
    pub step: Option<f64>,
}

impl Overrides {
    /// `analysis` with these changes, written into its entry of the model file and checked as
    /// the file's own entries are; or every problem, each at the option that set its field.
    fn apply(&self, analysis: &Analysis) -> Result<Analysis, Error> {
        let changes = AnalysisSpec {
            kind: analysis.kind,
            drivers: None,
            forces: None,
            t_start: analysis.t_start,
            t_end: self.t_end,
            step: self.step,
            about: None,
            integrator: self.integrator,
            solver: SolverSpec { rtol: self.rtol, atol: self.atol, ..Default::default() },
            outputs: None,
        };
        revise(analysis, &changes)
            .map_err(|problems| Error::Model(problems.into_iter().map(|p| self.at_option(&analysis.name, p)).collect()))
    }

    /// A problem with a field of the analysis `name`, at the option that set the field.
    fn at_option(&self, name: &str, problem: Problem) -> Problem {
        let field = problem.path.strip_prefix(&format!("analyses.{name}.")).unwrap_or_default();
        let option = match field {
            "t_end" => "--t-end",
            // The output grid: the step if it was given, else the end time that the file's step
            // no longer fits (the file's own grid was checked when it compiled).
            "step" if self.step.is_none() && self.t_end.is_some() => "--t-end",
            "step" => "--step",
            "integrator" => "--integrator",
            "solver.rtol" => "--rtol",
            "solver.atol" => "--atol",
            _ => return problem,
        };
        Problem { path: option.into(), ..problem }
    }
}

/// What one run of an analysis is given besides its name ([`Model::run`]).
#[derive(Debug, Default)]
pub struct RunOptions {
    /// Changes to the analysis for this run.
    pub overrides: Overrides,
    /// Where the run reports its times (read by another thread: a progress bar); `None`: no one
    /// watches.
    pub progress: Option<Arc<Progress>>,
    /// The request to stop the run, which it reads at every output time and step attempt (a
    /// clone of it is kept by whoever may stop it: Ctrl-C).
    pub stop: StopToken,
    /// Where the rows go.
    pub sink: Sink,
    /// The parameters (names of the model's `parameters:`) to differentiate every column with
    /// respect to ([`crate::results::Sensitivities`]); empty: none.
    pub sensitivities: Vec<String>,
}

impl From<Overrides> for RunOptions {
    /// A run with `overrides`, unwatched, its rows in memory.
    fn from(overrides: Overrides) -> RunOptions {
        RunOptions { overrides, ..RunOptions::default() }
    }
}

/// Where the rows of a run go.
#[derive(Default)]
pub enum Sink {
    /// Into the results returned, in memory.
    #[default]
    Memory,
    /// To a sink as they are computed ([`crate::results::stream`]: CSV, or the Python package's
    /// Parquet): the results returned hold none of them (their summary is complete). After a
    /// failure the sink has every row up to it. A sink that cannot be written fails the run
    /// with [`Error::Io`] naming its file. A run holds the lock for its length.
    Stream(Mutex<Box<dyn RowSink>>),
}

impl Sink {
    /// The rows to the CSV file at `path` ([`CsvSink`]), made anew by each run.
    pub fn csv(path: &Path) -> Sink {
        Sink::stream(Box::new(CsvSink::at(path)))
    }

    /// The rows to `sink`.
    pub fn stream(sink: Box<dyn RowSink>) -> Sink {
        Sink::Stream(Mutex::new(sink))
    }
}

impl std::fmt::Debug for Sink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Sink::Memory => f.write_str("Memory"),
            Sink::Stream(sink) => {
                let path = sink.lock().unwrap_or_else(PoisonError::into_inner).path();
                f.debug_tuple("Stream").field(&path).finish()
            }
        }
    }
}

/// A run as its analysis sees it: the watcher it reports each time it reaches to, the token it
/// stops at, and the sink its rows go to (none: they stay in its results).
#[derive(Debug, Default)]
pub(crate) struct Run<'a> {
    progress: Option<Arc<Progress>>,
    stop: StopToken,
    stream: Option<Stream<'a>>,
    /// The parameters (indices in file order) whose derivatives the run computes.
    pub(crate) sensitivities: Vec<usize>,
}

impl Run<'_> {
    /// Empty results with the columns of `model` for `analysis`, streamed when the run has a
    /// sink: those the analysis pushes its rows to ([`Run::push`]).
    pub(crate) fn results(&self, model: &Model, analysis: &Analysis) -> Results {
        let mut results = Results::new(model, analysis);
        if let Some(stream) = &self.stream {
            results.stream_in_chunks(stream.chunk_bytes());
        }
        results
    }

    /// The run reached time `t` (an output time or an integrator's step attempt): reported to
    /// its watcher, and [`Error::Interrupted`] there if it has been asked to stop.
    pub(crate) fn reached(&self, t: f64) -> Result<(), Error> {
        if let Some(p) = &self.progress {
            p.reached(t);
        }
        if self.stop.stopped() {
            Err(Error::Interrupted { time: t })
        } else {
            Ok(())
        }
    }

    /// Append an output point to `results` ([`Results::push`]), give the sink a chunk once one
    /// is full, and report its time ([`Run::reached`]): the run may stop there, with the row
    /// kept.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        results: &mut Results,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
        extra: &[f64],
    ) -> Result<(), Error> {
        results.push(t, q, qdot, qddot, extra)?;
        if let Some(stream) = &mut self.stream {
            if results.chunk_full() {
                stream.flush(results)?;
            }
        }
        self.reached(t)
    }
}

impl Model {
    /// Run the analysis called `name` with `options`: its changes, watcher, stop token and
    /// sink. On failure the [`Failure`] holds the results up to it (and a sink the rows).
    pub fn run(&self, name: &str, options: &RunOptions) -> Result<Results, Box<Failure>> {
        // An analysis that does not exist, or changes it cannot take, are refused before the
        // sink is touched: the file a user named is not emptied for a typo.
        let analysis = match self.analysis(name) {
            Ok(a) => options
                .overrides
                .apply(a)
                .map_err(|error| Box::new(Failure { error, results: Results::new(self, a) }))?,
            Err(error) => return Err(Box::new(Failure { error, results: Results::of_model(self) })),
        };
        let sensitivities = match self.sensitivity_parameters(
            &analysis,
            &options.sensitivities,
            options.overrides.integrator.is_some(),
        ) {
            Ok(k) => k,
            Err(error) => return Err(Box::new(Failure { error, results: Results::new(self, &analysis) })),
        };
        let mut sink = match &options.sink {
            Sink::Memory => None,
            Sink::Stream(sink) => Some(sink.lock().unwrap_or_else(PoisonError::into_inner)),
        };
        let mut run = Run {
            progress: options.progress.clone(),
            stop: options.stop.clone(),
            stream: sink.as_deref_mut().map(|s| Stream::new(s.as_mut())),
            sensitivities,
        };
        let mut outcome = self.run_analysis(&analysis, &mut run);
        let Some(stream) = run.stream else { return outcome };
        let results = match &mut outcome {
            Ok(r) => r,
            Err(f) => &mut f.results,
        };
        match (stream.finish(results), outcome) {
            (Err(error), Ok(results)) => Err(Box::new(Failure { error, results })),
            (_, outcome) => outcome,
        }
    }

    /// The indices of the parameters named `names` (file order of the names given), for the
    /// sensitivities of `analysis`: an error at the field `sensitivities` for a name the model
    /// does not define; at its integrator (`--integrator` when `overridden`) for a dynamic
    /// analysis integrated by a method that has none yet.
    fn sensitivity_parameters(
        &self,
        analysis: &Analysis,
        names: &[String],
        overridden: bool,
    ) -> Result<Vec<usize>, Error> {
        let problem = |message: String| Error::Model(vec![Problem::new("sensitivities", message)]);
        if names.is_empty() {
            return Ok(Vec::new());
        }
        // The dynamic sensitivities are integrated with the state by the BDF and ABAM integrators
        // (analysis/sensitivity/dynamic.rs, analysis/dynamic/abam/sensitivities.rs); every other
        // analysis type has its own.
        if analysis.kind == AnalysisKind::Dynamic && analysis.integrator.kind == IntegratorKind::Hht {
            let path =
                if overridden { "--integrator".into() } else { format!("analyses.{}.integrator", analysis.name) };
            return Err(Error::Model(vec![Problem::new(
                path,
                format!(
                    "integrator {} has no design sensitivities (asked for with `sensitivities`): use bdf or abam",
                    analysis.integrator.kind.name()
                ),
            )]));
        }
        if analysis.kind == AnalysisKind::Modes && analysis.about != LinearisePoint::Equilibrium {
            return Err(problem(format!(
                "analysis '{}' linearises about the initial state: design sensitivities of modes are computed about an equilibrium (`about: equilibrium`) so far",
                analysis.name
            )));
        }
        names
            .iter()
            .map(|name| {
                self.parameters.get_index_of(name).ok_or_else(|| {
                    let known: Vec<&str> = self.parameters.keys().map(String::as_str).collect();
                    let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                    problem(format!("unknown parameter '{name}'; the model file defines: {known}"))
                })
            })
            .collect()
    }

    /// Run `analysis` (with the run's changes applied) as `run`: dispatched by its type, its
    /// summaries evaluated and the warnings about its tolerances added.
    fn run_analysis(&self, analysis: &Analysis, run: &mut Run<'_>) -> Result<Results, Box<Failure>> {
        let unavailable = self.unavailable_measures(analysis);
        if !unavailable.is_empty() {
            return Err(Box::new(Failure { error: Error::Model(unavailable), results: Results::new(self, analysis) }));
        }
        if let Some(p) = &run.progress {
            p.begin(analysis.t_start, analysis.t_end);
        }
        let outcome = match analysis.kind {
            AnalysisKind::Kinematic => run_kinematic(self, analysis, run),
            AnalysisKind::Dynamic => dynamic::run_dynamic(self, analysis, run),
            AnalysisKind::Inverse => run_inverse(self, analysis, run),
            AnalysisKind::Static => run_static(self, analysis, run),
            AnalysisKind::Modes => run_modes(self, analysis, run),
        };
        // The summaries of a run that ended well; one that cannot be evaluated fails the run,
        // with every row kept.
        let mut outcome = outcome.and_then(|mut results| match results.summarise() {
            Ok(()) => Ok(results),
            Err(error) => Err(Box::new(Failure { error, results })),
        });
        let results = match &mut outcome {
            Ok(r) => r,
            Err(f) => &mut f.results,
        };
        // The first output's positions (the assembled start), else the file's guess.
        let q = results.first_positions().map_or_else(|| self.q0(), <[f64]>::to_vec);
        // The analysis's own warnings (a dynamic run's) follow the tolerances'.
        let mut warnings = tolerance_warnings(analysis, &q);
        warnings.append(&mut results.summary.warnings);
        results.summary.warnings = warnings;
        outcome
    }
}
