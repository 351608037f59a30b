//! The entry point of every analysis: the analysis a model names, with the changes of one run
//! ([`Overrides`]) checked as the model file's own entries are, dispatched by its type, and the
//! warnings about its tolerances added to its summary.

use super::{dynamic, run_inverse, run_kinematic, run_modes, run_static, tolerance_warnings};
use crate::error::{Error, Problem};
use crate::model::spec::{AnalysisKind, AnalysisSpec, IntegratorKind, SolverSpec};
use crate::model::{revise, Analysis, Model};
use crate::progress::{self, Progress};
use crate::results::stream::{self, RowSink};
use crate::results::{Failure, Results};
use std::sync::Arc;

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

impl Model {
    /// Run the analysis called `name`.
    pub fn run(&self, name: &str) -> Result<Results, Box<Failure>> {
        self.run_with(name, &Overrides::default())
    }

    /// Run the analysis called `name` with `overrides` applied.
    pub fn run_with(&self, name: &str, overrides: &Overrides) -> Result<Results, Box<Failure>> {
        self.run_watched(name, overrides, &Progress::new())
    }

    /// Run the analysis called `name` with `overrides` applied, reporting to `progress` (which
    /// another thread reads, and may stop the run through).
    pub fn run_watched(
        &self,
        name: &str,
        overrides: &Overrides,
        progress: &Arc<Progress>,
    ) -> Result<Results, Box<Failure>> {
        let analysis = match self.analysis(name) {
            Ok(a) => overrides.apply(a).map_err(|error| Box::new(Failure { error, results: Results::new(self, a) }))?,
            Err(error) => return Err(Box::new(Failure { error, results: Results::of_model(self) })),
        };
        let unavailable = self.unavailable_measures(&analysis);
        if !unavailable.is_empty() {
            return Err(Box::new(Failure { error: Error::Model(unavailable), results: Results::new(self, &analysis) }));
        }
        progress.begin(analysis.t_start, analysis.t_end);
        let outcome = progress::scope(progress, || match analysis.kind {
            AnalysisKind::Kinematic => run_kinematic(self, &analysis),
            AnalysisKind::Dynamic => dynamic::run_dynamic(self, &analysis),
            AnalysisKind::Inverse => run_inverse(self, &analysis),
            AnalysisKind::Static => run_static(self, &analysis),
            AnalysisKind::Modes => run_modes(self, &analysis),
        });
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
        let mut warnings = tolerance_warnings(&analysis, &q);
        warnings.append(&mut results.summary.warnings);
        results.summary.warnings = warnings;
        outcome
    }

    /// Run as [`Model::run_watched`] does, with the rows going to `sink` as they are computed
    /// ([`stream`]): the results returned hold none of them (their summary is complete). After a
    /// failure the sink has every row up to it. A sink that cannot be written fails the run
    /// with [`Error::Io`] naming its file.
    pub fn run_streamed(
        &self,
        name: &str,
        overrides: &Overrides,
        progress: &Arc<Progress>,
        sink: Box<dyn RowSink>,
    ) -> Result<Results, Box<Failure>> {
        // An analysis that does not exist, or changes it cannot take, are refused before the
        // sink is touched: the file a user named is not emptied for a typo.
        if self.analysis(name).and_then(|a| overrides.apply(a)).is_err() {
            return self.run_watched(name, overrides, progress);
        }
        let (mut outcome, unclaimed) = stream::scope(sink, || self.run_watched(name, overrides, progress));
        let results = match &mut outcome {
            Ok(r) => r,
            Err(f) => &mut f.results,
        };
        match (results.finish_stream(unclaimed), outcome) {
            (Err(error), Ok(results)) => Err(Box::new(Failure { error, results })),
            (_, outcome) => outcome,
        }
    }
}
