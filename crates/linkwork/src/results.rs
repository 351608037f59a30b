//! Columnar time series of an analysis and their files: `results.csv` (a `time` column, then
//! `<body>.x, .y, .phi, .vx, .vy, .omega, .ax, .ay, .alpha` per body, SI units, angles unwrapped;
//! for dynamics every joint's `<joint>.fx, .fy, .torque`, every active driver's
//! `<driver>.effort`, the energies and constraint residuals; then one column per measure) and
//! `summary.json` ([`Summary`], with `output_points`, `status` and the error if there is one:
//! the same header and the same shape of each fact for every analysis, see [`summary`]), which
//! holds the model's summaries, functionals of the columns
//! ([`functional`](crate::expr::functional)) evaluated once a run ends well.

pub mod columns;
pub mod stream;
pub mod summary;

pub use summary::{
    AnalysisHeader, AssemblyReport, DynamicStats, EquilibriumReport, KinematicStats, Mode, ModeKind, Peak, Reactions,
    Residuals, StaticStats, Statistics, Summary,
};

use crate::error::{Error, Problem};
use crate::expr::functional::{EvalError, Functional, TIME};
use crate::expr::{Dual, Scalar};
use crate::model::spec::{BranchMode, OutputsSpec};
use crate::model::structure::BranchWatch;
use crate::model::{Analysis, Model};
use indexmap::IndexMap;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The quantities written per body, in column order.
pub const BODY_QUANTITIES: [&str; 9] = ["x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha"];

pub use crate::model::REACTION_QUANTITIES;

/// The column of a joint with friction, `<joint>.friction`: its friction on its first body, the
/// torque of a revolute joint (N m) or the force along the axis of a translational one (N).
pub const FRICTION_QUANTITY: &str = "friction";

/// Results of one analysis: one column per quantity, one row per output time.
#[derive(Debug)]
pub struct Results {
    /// (rows) output times, s.
    pub time: Vec<f64>,
    /// Column names, without `time`.
    pub names: Vec<String>,
    /// (columns x rows) values, column by column.
    pub columns: Vec<Vec<f64>>,
    /// Everything `summary.json` says besides `output_points`, the status and the error.
    pub summary: Summary,
    /// The derivatives of the columns with respect to the parameters the run was asked for
    /// ([`crate::analysis::RunOptions::sensitivities`]); `None` when it was asked for none.
    pub sensitivities: Option<Sensitivities>,
    /// The analysis's choice of columns, applied once they are all named ([`Results::reserve`]
    /// or the first [`Results::push`]).
    selection: Selection,
    /// The running peaks of the reactions and efforts ([`Results::insert_reaction_summary`]).
    peaks: Peaks,
    /// The model's summaries and the columns they read ([`Results::summarise`]).
    summaries: Summaries,
    /// (9 bodies + extra columns) the row being pushed, every column.
    row: Vec<f64>,
    /// (3 bodies) the positions of the first output point.
    first_positions: Vec<f64>,
    /// The rows of a streamed run that its sink has, and how many are held for it ([`stream`]).
    streamed: Option<Streamed>,
    /// Whether [`Results::start`] ran.
    started: bool,
    /// The dyads' branches from one output to the next.
    branches: BranchWatch,
    /// Whether a change of branch fails the run (`branch: strict`).
    strict_branches: bool,
    /// Why the rows do not fit in memory ([`Results::reserve`]): the first push fails with it.
    refused: Option<String>,
}

/// The derivatives of a run's columns with respect to parameters (design sensitivities,
/// docs/sensitivities.md), at the run's output times.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Sensitivities {
    /// The parameters, by name, in the order asked.
    pub parameters: Vec<String>,
    /// The columns that have derivatives (names of [`Results::names`], in their order).
    pub names: Vec<String>,
    /// (parameters x names x rows) `d column / d parameter`, SI per SI unit of the parameter.
    pub values: Vec<Vec<Vec<f64>>>,
}

impl Sensitivities {
    /// The name of the derivative of `column` with respect to `parameter`, in
    /// `sensitivities.csv` and in Python: `d(<column>)/d(<parameter>)`.
    pub fn column_name(column: &str, parameter: &str) -> String {
        format!("d({column})/d({parameter})")
    }

    /// Every derivative's name ([`Sensitivities::column_name`]), parameter by parameter and each
    /// parameter's columns in their order: the header of `sensitivities.csv` after `time`.
    pub fn header(&self) -> Vec<String> {
        self.parameters.iter().flat_map(|p| self.names.iter().map(move |c| Sensitivities::column_name(c, p))).collect()
    }

    /// Every derivative's rows, in the order of [`Sensitivities::header`].
    pub fn columns(&self) -> Vec<&[f64]> {
        self.values.iter().flatten().map(Vec::as_slice).collect()
    }
}

/// The rows of a streamed run ([`stream`]): those its sink has, and how many are held before the
/// next chunk goes to it.
#[derive(Debug, Clone, Copy)]
struct Streamed {
    /// Rows already given to the sink.
    sent: usize,
    /// Bytes of output values the sink takes a chunk ([`stream::RowSink::chunk_bytes`]).
    chunk_bytes: usize,
    /// Rows a chunk, once every column is named ([`Results::start`]).
    chunk: usize,
}

/// What a run whose results do not fit in memory is told to do.
const REMEDY: &str = "stream the rows to a file (linkwork run --stream, or stream= in Python) or keep fewer columns (the analysis's outputs:)";

/// The memory this process may still take, bytes: the kernel's estimate of what can be allocated
/// without swapping (`MemAvailable`), or less when the process's control group has a limit
/// (`memory.max` less `memory.current`, cgroup v2). `None` where neither can be read (not
/// Linux): then only a failed allocation stops the run ([`Results::push`]).
fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kb.checked_mul(1024)
    });
    let number =
        |file: &str| std::fs::read_to_string(format!("/sys/fs/cgroup/{file}")).ok()?.trim().parse::<u64>().ok();
    // `memory.max` is "max" (no number) without a limit.
    let cgroup = number("memory.max").map(|max| max.saturating_sub(number("memory.current").unwrap_or(0)));
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Why `rows` of `columns` numbers, with `copies` columns of `all_rows` numbers (the summaries'
/// copies), do not fit in `available` bytes, if they do not. The rows are held twice at the peak
/// of a run from Python (the engine's columns and the numpy matrix made of them), so the bound is
/// half of what is available.
fn too_large(rows: usize, columns: usize, all_rows: usize, copies: usize, available: Option<u64>) -> Option<String> {
    let bytes = 8.0 * (rows as f64 * columns as f64 + all_rows as f64 * copies as f64);
    let available = available? as f64;
    let gb = |b: f64| format!("{:.2} GB", b / 1e9);
    (bytes > available / 2.0).then(|| {
        format!(
            "for the results: {rows} output points x {columns} columns x 8 bytes = {}, more than half the {} of memory available (Python copies them once); {REMEDY}",
            gb(bytes),
            gb(available)
        )
    })
}

/// The largest reaction of each joint and effort of each active driver, kept as rows are pushed
/// (so that a streamed run, which keeps no column, has them too).
#[derive(Debug, Clone, Default)]
enum Peaks {
    /// Nothing to watch (results of no analysis).
    #[default]
    None,
    /// The joints and the active drivers' effort columns, to be found among the columns.
    Pending { joints: Vec<String>, efforts: Vec<String> },
    /// Each peak's key in the summary, the row positions of its one or two components (two: the
    /// resultant of a force), and the largest value so far with its time.
    Watching(Vec<(String, [usize; 2], Peak)>),
}

/// The model's summaries (`summaries:` of the model file) as the run goes.
#[derive(Debug, Clone, Default)]
enum Summaries {
    /// None to evaluate: the model has none, or the analysis' output spans no time (`modes`, a
    /// `static` analysis at one time).
    #[default]
    None,
    /// The summaries of an analysis over `[t_start, t_end]`, to be checked once every column is
    /// named; `gradients`: each parameter's derivative with respect to each (the model's
    /// [`crate::model::DataGradients::params`]), for the summaries' derivatives.
    Pending { span: [f64; 2], functionals: IndexMap<String, Functional>, gradients: Vec<Vec<f64>> },
    /// Checked: the summaries, and a copy of each column they read that the results do not
    /// keep (every one of a streamed run, `time` included; those `outputs` leaves out), with its
    /// position in the row pushed (`None`: the time).
    Reading {
        span: [f64; 2],
        functionals: IndexMap<String, Functional>,
        copies: Vec<(String, Option<usize>, Vec<f64>)>,
        gradients: Vec<Vec<f64>>,
    },
    /// One reads a column that does not exist, or an `at` time outside the span: the error the
    /// first push returns.
    Failed(Error),
}

/// Which columns of the rows pushed are kept.
#[derive(Debug, Clone, Default)]
enum Selection {
    /// Every column.
    #[default]
    All,
    /// The analysis `.0` keeps the columns `.1`, to be applied.
    Pending(String, OutputsSpec),
    /// Applied: every column's name as pushed, and whether it is kept.
    Applied { names: Vec<String>, keep: Vec<bool> },
    /// A column it names does not exist: the error the first push returns.
    Failed(Error),
}

/// A failed analysis: the error and every result computed before it.
#[derive(Debug)]
pub struct Failure {
    /// What went wrong, where and when.
    pub error: Error,
    /// Output points up to the last good one.
    pub results: Results,
}

impl Results {
    /// Empty results with the columns of `model` for `analysis`.
    pub fn new(model: &Model, analysis: &Analysis) -> Results {
        let mut results = Results::of_model(model);
        results.peaks = Peaks::Pending {
            joints: model.joints.iter().map(|j| j.name.clone()).collect(),
            efforts: analysis.drivers.iter().map(|&d| format!("{}.effort", model.drivers[d].name)).collect(),
        };
        if let Some(outputs) = &analysis.outputs {
            results.selection = Selection::Pending(analysis.name.clone(), outputs.clone());
        }
        if analysis.t_end > analysis.t_start && !model.summaries.is_empty() {
            let span = [analysis.t_start, analysis.t_end];
            let gradients = model.gradients.params.clone();
            results.summaries = Summaries::Pending { span, functionals: model.summaries.clone(), gradients };
        }
        results.summary.analysis = Some(AnalysisHeader {
            analysis: analysis.name.clone(),
            kind: analysis.kind,
            active_drivers: analysis.drivers.iter().map(|&d| model.drivers[d].name.clone()).collect(),
            settings: analysis.settings,
        });
        results.branches = BranchWatch::new(model, &analysis.drivers);
        results.strict_branches = model.branch_mode == BranchMode::Strict;
        results
    }

    /// Empty results with the columns of `model` and the model's part of the summary (its name,
    /// bodies, coordinates and joints): what a run that names no analysis of it leaves.
    pub fn of_model(model: &Model) -> Results {
        let names: Vec<String> =
            model.bodies.iter().flat_map(|b| BODY_QUANTITIES.iter().map(move |q| format!("{}.{q}", b.name))).collect();
        let summary = Summary {
            model: model.name.clone(),
            bodies: model.bodies.len(),
            coordinates: model.n(),
            joints: model.joints.iter().map(|j| j.name.clone()).collect(),
            parameters: model.parameters.clone(),
            // A doubtful value given from outside stays on the run's record.
            warnings: model.warnings.clone(),
            ..Summary::default()
        };
        Results::with_columns(names, summary)
    }

    /// Empty results with the columns `names` and `summary`.
    fn with_columns(names: Vec<String>, summary: Summary) -> Results {
        Results {
            time: Vec::new(),
            columns: vec![Vec::new(); names.len()],
            names,
            summary,
            sensitivities: None,
            selection: Selection::All,
            peaks: Peaks::None,
            summaries: Summaries::None,
            row: Vec::new(),
            first_positions: Vec::new(),
            streamed: None,
            started: false,
            branches: BranchWatch::default(),
            strict_branches: false,
            refused: None,
        }
    }

    /// Number of output points (those streamed to a file included).
    pub fn len(&self) -> usize {
        self.time.len() + self.streamed.map_or(0, |s| s.sent)
    }

    /// True when no output point was computed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the rows went to a file as they were computed (then `time` and `columns` hold
    /// none of them; [`Results::len`] counts them).
    pub fn is_streamed(&self) -> bool {
        self.streamed.is_some()
    }

    /// The rows of these results go to a sink ([`stream`]) that takes `chunk_bytes` of output
    /// values a chunk: only a chunk's rows are held ([`Results::reserve`]), and the summaries
    /// copy every column they read. Before the first [`Results::reserve`] or [`Results::push`].
    pub(crate) fn stream_in_chunks(&mut self, chunk_bytes: usize) {
        debug_assert!(!self.started, "streamed from the first row");
        self.streamed = Some(Streamed { sent: 0, chunk_bytes, chunk: 1 });
    }

    /// Whether a streamed run holds a whole chunk, for its sink ([`stream::Stream::flush`]).
    pub(crate) fn chunk_full(&self) -> bool {
        self.streamed.is_some_and(|s| self.time.len() >= s.chunk)
    }

    /// The rows held went to the sink: counted, and emptied.
    fn rows_sent(&mut self) {
        if let Some(s) = &mut self.streamed {
            s.sent += self.time.len();
        }
        self.time.clear();
        self.columns.iter_mut().for_each(Vec::clear);
    }

    /// The positions `(x, y, phi)` of every body at the first output point, if there is one.
    pub fn first_positions(&self) -> Option<&[f64]> {
        (!self.first_positions.is_empty()).then_some(self.first_positions.as_slice())
    }

    /// Append columns after the body quantities (filled by the `extra` values of
    /// [`Results::push`], in order).
    pub(crate) fn add_columns(&mut self, names: impl IntoIterator<Item = String>) {
        for n in names {
            self.names.push(n);
            self.columns.push(Vec::new());
        }
    }

    /// Room for the run's `rows` output points (a chunk's at most, when streamed), estimated
    /// first against the memory available ([`too_large`]): results that would not fit, or room
    /// that cannot be had, are the [`Error::OutOfMemory`] the first push returns, before the run
    /// has taken the memory (a 3-body model's 10 million points are 2.2 GB; one of 48 million
    /// aborted the process).
    pub(crate) fn reserve(&mut self, rows: usize) {
        self.start();
        let held = self.streamed.map_or(rows, |s| rows.min(s.chunk));
        let copies = match &self.summaries {
            Summaries::Reading { copies, .. } => copies.len(),
            _ => 0,
        };
        self.refused = too_large(held, self.columns.len() + 1, rows, copies, available_memory()).or_else(|| {
            let room = self
                .time
                .try_reserve(held)
                .and_then(|()| self.columns.iter_mut().try_for_each(|c| c.try_reserve(held)));
            room.err().map(|_| {
                format!("reserving room for {held} output points of {} columns; {REMEDY}", self.columns.len() + 1)
            })
        });
    }

    /// Room for one more row in every column kept (and each summary's copy), grown as `push`
    /// would but failing rather than aborting the process when the memory is gone.
    fn room_for_a_row(&mut self) -> Result<(), std::collections::TryReserveError> {
        self.time.try_reserve(1)?;
        self.columns.iter_mut().try_for_each(|c| c.try_reserve(1))?;
        if let Summaries::Reading { copies, .. } = &mut self.summaries {
            copies.iter_mut().try_for_each(|(_, _, values)| values.try_reserve(1))?;
        }
        Ok(())
    }

    /// Append an output point from `q`, `qdot`, `qddot` (each `(n)`) and the values of the
    /// columns after the body quantities, `extra`; or, when one of them is not finite, append
    /// nothing and name its column: no NaN or infinity leaves as a result, whatever the analysis
    /// (each analysis first looks for the element to blame; this is the net under all of them).
    pub(crate) fn push(&mut self, t: f64, q: &[f64], qdot: &[f64], qddot: &[f64], extra: &[f64]) -> Result<(), Error> {
        self.start();
        let bodies = q.len() / 3;
        // In column order: each body's `x, y, phi, vx, vy, omega, ax, ay, alpha`, then `extra`.
        self.row.clear();
        self.row.extend(
            (0..bodies)
                .flat_map(|b| [q, qdot, qddot].into_iter().flat_map(move |v| [v[3 * b], v[3 * b + 1], v[3 * b + 2]]))
                .chain(extra.iter().copied()),
        );
        if let Summaries::Failed(e) = &self.summaries {
            return Err(e.clone());
        }
        if let Some(what) = &self.refused {
            return Err(Error::OutOfMemory { time: t, what: what.clone() });
        }
        if self.room_for_a_row().is_err() {
            let what =
                format!("storing output point {} of {} columns; {REMEDY}", self.len() + 1, self.columns.len() + 1);
            return Err(Error::OutOfMemory { time: t, what });
        }
        let (names, keep) = match &self.selection {
            Selection::Failed(e) => return Err(e.clone()),
            Selection::Applied { names, keep } => (names, Some(keep)),
            _ => (&self.names, None),
        };
        debug_assert_eq!(names.len(), self.row.len(), "one extra value per extra column");
        if let Some((k, &value)) = self.row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            let element = names[k].clone();
            return Err(Error::NonFinite { time: t, element, expression: String::new(), value });
        }
        if let Some(change) = self.branches.push(t, q) {
            if self.strict_branches {
                return Err(change.error("branch: strict"));
            }
            // One warning a dyad (a change point's mechanism passes it every turn); every change
            // is in `branch_changes`.
            if !self.summary.branch_changes.iter().any(|c| c.joint == change.joint) {
                self.summary.warnings.push(change.message());
            }
            self.summary.branch_changes.push(change);
        }
        if self.is_empty() {
            self.first_positions = (0..bodies).flat_map(|b| [q[3 * b], q[3 * b + 1], q[3 * b + 2]]).collect();
        }
        if let Peaks::Watching(peaks) = &mut self.peaks {
            for (_, [a, b], peak) in peaks {
                let v = if *b == usize::MAX { self.row[*a].abs() } else { self.row[*a].hypot(self.row[*b]) };
                if v >= peak.max_abs || peak.time.is_none() {
                    *peak = Peak { max_abs: v, time: Some(t) };
                }
            }
        }
        if let Summaries::Reading { copies, .. } = &mut self.summaries {
            for (_, position, values) in copies {
                values.push(position.map_or(t, |k| self.row[k]));
            }
        }
        self.time.push(t);
        match keep {
            Some(keep) => {
                let kept = self.row.iter().zip(keep).filter(|(_, &k)| k).map(|(v, _)| v);
                self.columns.iter_mut().zip(kept).for_each(|(c, &v)| c.push(v));
            }
            None => self.columns.iter_mut().zip(&self.row).for_each(|(c, &v)| c.push(v)),
        }
        Ok(())
    }

    /// The derivatives of the row just pushed ([`Results::push`]) with respect to `parameters`
    /// (names): `rows[k]`, for `parameters[k]`, in the row's layout (every column before the
    /// choice of columns: each body's quantities, then the extra columns). The first call names
    /// [`Results::sensitivities`]; a derivative that is not finite is an error at `t`.
    pub(crate) fn push_sensitivities(&mut self, t: f64, parameters: &[String], rows: &[Vec<f64>]) -> Result<(), Error> {
        self.push_sensitivities_of(t, parameters, None, rows)
    }

    /// [`Results::push_sensitivities`] for an analysis some of whose columns have no derivatives:
    /// `differentiated` (in the row's layout, `None` for every column) tells which do; the others
    /// are not written (their entries of `rows` are not read) and [`Sensitivities::names`] leaves
    /// them out.
    pub(crate) fn push_sensitivities_of(
        &mut self,
        t: f64,
        parameters: &[String],
        differentiated: Option<&[bool]>,
        rows: &[Vec<f64>],
    ) -> Result<(), Error> {
        let (names, keep) = match &self.selection {
            Selection::Applied { names, keep } => (names, Some(keep)),
            _ => (&self.names, None),
        };
        let has = |k: usize| differentiated.is_none_or(|d| d[k]);
        let wanted = |k: usize| keep.is_none_or(|keep| keep[k]) && has(k);
        for (p, row) in parameters.iter().zip(rows) {
            debug_assert_eq!(names.len(), row.len(), "one derivative per column");
            if let Some((k, &value)) = row.iter().enumerate().find(|&(k, v)| has(k) && !v.is_finite()) {
                let element = format!("d({})/d({p})", names[k]);
                return Err(Error::NonFinite { time: t, element, expression: String::new(), value });
            }
        }
        // Room for as many points as the values have (`Results::reserve`), which each column
        // would otherwise grow to by reallocations.
        let room = self.time.capacity();
        let sensitivities = self.sensitivities.get_or_insert_with(|| {
            let names: Vec<String> =
                names.iter().enumerate().filter(|&(k, _)| wanted(k)).map(|(_, n)| n.clone()).collect();
            let columns = || names.iter().map(|_| Vec::with_capacity(room)).collect();
            Sensitivities {
                parameters: parameters.to_vec(),
                values: parameters.iter().map(|_| columns()).collect(),
                names,
            }
        });
        for (columns, row) in sensitivities.values.iter_mut().zip(rows) {
            let kept = row.iter().enumerate().filter(|&(k, _)| wanted(k)).map(|(_, v)| v);
            columns.iter_mut().zip(kept).for_each(|(c, &v)| c.push(v));
        }
        Ok(())
    }

    /// Once every column is named (the first [`Results::reserve`] or [`Results::push`]): apply
    /// the choice of columns, find the peaks' columns, and size a streamed run's chunks.
    fn start(&mut self) {
        if self.started {
            return;
        }
        self.started = true;
        self.select();
        self.watch_peaks();
        if let Some(s) = &mut self.streamed {
            s.chunk = (s.chunk_bytes / (8 * (self.columns.len() + 1))).max(1);
        }
        self.read_summaries();
    }

    /// Check the summaries against the columns (every column of the row pushed, those `outputs`
    /// leaves out included) and the span, and choose the columns to copy as rows are pushed: a
    /// column one reads that does not exist, or an `at` time outside the span, is a problem at
    /// `summaries.<name>` that the first push returns.
    fn read_summaries(&mut self) {
        let Summaries::Pending { span, functionals, gradients } = std::mem::take(&mut self.summaries) else { return };
        let (names, keep) = match &self.selection {
            Selection::Applied { names, keep } => (names, Some(keep)),
            _ => (&self.names, None),
        };
        let position: std::collections::HashMap<&str, usize> =
            names.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
        let columns = match &self.summary.analysis {
            Some(a) => format!(
                "a column of the {} analysis '{}' (a name in its results.csv) or time",
                a.kind.name(),
                a.analysis
            ),
            None => "a column of results.csv or time".to_string(),
        };
        for (name, f) in &functionals {
            if let Err(message) = f.check(&|c| position.contains_key(c), span, &columns) {
                self.summaries =
                    Summaries::Failed(Error::Model(vec![Problem::new(format!("summaries.{name}"), message)]));
                return;
            }
        }
        let streamed = self.streamed.is_some();
        let mut read: Vec<&str> = if streamed { vec![TIME] } else { Vec::new() };
        for c in functionals.values().flat_map(Functional::columns) {
            if !read.contains(&c) {
                read.push(c);
            }
        }
        let copies = read
            .into_iter()
            .filter_map(|c| {
                // Every column but the time is in the row: the check above found it there.
                let at = if c == TIME { None } else { Some(*position.get(c)?) };
                let kept = !streamed && at.is_none_or(|k| keep.is_none_or(|keep| keep[k]));
                (!kept).then(|| (c.to_string(), at, Vec::new()))
            })
            .collect();
        self.summaries = Summaries::Reading { span, functionals, copies, gradients };
    }

    /// Evaluate the model's summaries over the rows of a run that ended well, into the summary
    /// (`summaries`, by name); nothing when there are none to evaluate. A value that is not a
    /// finite number (an argument's at a row, or the whole expression's: a division by zero) is
    /// an [`Error::NonFinite`] at `summaries.<name>`, at the row's time or the end of the run,
    /// and no summary is written. A run with [`Results::sensitivities`] also writes the
    /// summaries' and the peaks' derivatives ([`Summary::sensitivities`]).
    pub(crate) fn summarise(&mut self) -> Result<(), Error> {
        let summaries = std::mem::take(&mut self.summaries);
        // The analysis's own derivatives (a modes analysis's modes) first.
        let mut derivatives = self.summary.sensitivities.take().unwrap_or_default();
        if let Summaries::Reading { span, functionals, copies, gradients } = &summaries {
            let copy = |name: &str| copies.iter().find(|(n, _, _)| n == name).map(|(_, _, v)| v.as_slice());
            let time = copy(TIME).unwrap_or(&self.time);
            let column = |name: &str| copy(name).or_else(|| self.column(name));
            let values = functionals
                .iter()
                .map(|(name, f)| {
                    let element = format!("summaries.{name}");
                    let value = f.eval(time, &column).map_err(|e| match e {
                        EvalError::NonFinite { value, what, time: at } => {
                            Error::NonFinite { time: at.unwrap_or(span[1]), element, expression: what, value }
                        }
                        EvalError::Missing(message) => Error::Model(vec![Problem::new(element, message)]),
                    })?;
                    Ok((name.clone(), value))
                })
                .collect::<Result<IndexMap<String, f64>, Error>>()?;
            if let Some(s) = &self.sensitivities {
                for (name, f) in functionals {
                    let by_parameter = self.by_parameter(s, |derivative, p| {
                        // Each named value's derivative: the parameters' gradients (NaN, and so
                        // left out, where the model has none).
                        let value = |n: &str| {
                            let k = self.summary.parameters.get_index_of(n);
                            k.and_then(|k| gradients.get(k)?.get(p).copied()).unwrap_or(f64::NAN)
                        };
                        f.derivative(time, &column, derivative, &value).ok()
                    });
                    derivatives.insert(name.clone(), by_parameter);
                }
            }
            self.summary.summaries = Some(values);
        }
        if let Some(s) = &self.sensitivities {
            if let (Peaks::Watching(watching), Some(reactions)) = (&self.peaks, &self.summary.reactions) {
                let names = match &self.selection {
                    Selection::Applied { names, .. } => names,
                    _ => &self.names,
                };
                for (key, positions, _) in watching {
                    let components: Vec<&str> =
                        positions.iter().filter(|&&k| k != usize::MAX).map(|&k| names[k].as_str()).collect();
                    let row =
                        reactions.peaks.get(key).and_then(|peak| self.time.iter().position(|&t| Some(t) == peak.time));
                    let by_parameter = self.by_parameter(s, |derivative, _| {
                        let row = row?;
                        let mut parts =
                            components.iter().map(|c| Some(Dual::new(self.column(c)?[row], derivative(c)?[row])));
                        let first = parts.next()??;
                        match parts.next() {
                            Some(second) => Some(first.hypot(second?).d),
                            None => Some(first.abs().d),
                        }
                    });
                    derivatives.insert(key.clone(), by_parameter);
                }
            }
        }
        if self.sensitivities.is_some() {
            derivatives.retain(|_, by_parameter| !by_parameter.is_empty());
            self.summary.sensitivities = Some(derivatives);
        }
        Ok(())
    }

    /// A quantity's derivative with respect to each parameter of `s` that `derivative` gives as
    /// a finite number, by the parameter's name; `derivative` is called with the columns'
    /// derivatives along the parameter (by column name) and the parameter's index among the
    /// model's parameters (file order).
    fn by_parameter<'s>(
        &self,
        s: &'s Sensitivities,
        derivative: impl Fn(&dyn Fn(&str) -> Option<&'s [f64]>, usize) -> Option<f64>,
    ) -> IndexMap<String, f64> {
        let column: std::collections::HashMap<&str, usize> =
            s.names.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
        s.parameters
            .iter()
            .zip(&s.values)
            .filter_map(|(name, values)| {
                let p = self.summary.parameters.get_index_of(name)?;
                let d = derivative(&|c: &str| column.get(c).map(|&k| values[k].as_slice()), p)?;
                d.is_finite().then(|| (name.clone(), d))
            })
            .collect()
    }

    /// Find the columns of the peaks to watch among those kept: each joint's `fx, fy, torque`
    /// (when all three are kept) and each active driver's effort.
    fn watch_peaks(&mut self) {
        if !matches!(self.peaks, Peaks::Pending { .. }) {
            return;
        }
        let Peaks::Pending { joints, efforts } = std::mem::take(&mut self.peaks) else { unreachable!("matched above") };
        self.select();
        let (names, keep) = match &self.selection {
            Selection::Applied { names, keep } => (names, Some(keep)),
            _ => (&self.names, None),
        };
        let position: std::collections::HashMap<&str, usize> = names
            .iter()
            .enumerate()
            .filter(|&(k, _)| keep.is_none_or(|keep| keep[k]))
            .map(|(k, n)| (n.as_str(), k))
            .collect();
        let find = |name: String| position.get(name.as_str()).copied();
        let none = Peak { max_abs: 0.0, time: None };
        let mut watching = Vec::new();
        for j in &joints {
            let (Some(fx), Some(fy), Some(m)) =
                (find(format!("{j}.fx")), find(format!("{j}.fy")), find(format!("{j}.torque")))
            else {
                continue;
            };
            watching.push((format!("{j}.force"), [fx, fy], none.clone()));
            watching.push((format!("{j}.torque"), [m, usize::MAX], none.clone()));
        }
        for e in efforts {
            if let Some(k) = find(e.clone()) {
                watching.push((e, [k, usize::MAX], none.clone()));
            }
        }
        self.peaks = Peaks::Watching(watching);
    }

    /// Apply a pending choice of columns, once every column is named: keep each body's nine
    /// columns, each joint's reactions and each column the analysis's `outputs` name; a named
    /// column that does not exist fails the first push, at `analyses.<name>.outputs.columns[k]`.
    fn select(&mut self) {
        if !matches!(self.selection, Selection::Pending(..)) {
            return;
        }
        let Selection::Pending(analysis, outputs) = std::mem::take(&mut self.selection) else {
            unreachable!("matched above")
        };
        let bodies: std::collections::HashSet<&str> = outputs.bodies.iter().map(String::as_str).collect();
        let joints: std::collections::HashSet<&str> = outputs.joints.iter().map(String::as_str).collect();
        let columns: std::collections::HashSet<&str> = outputs.columns.iter().map(String::as_str).collect();
        let known: std::collections::HashSet<&str> = self.names.iter().map(String::as_str).collect();
        if let Some((k, missing)) = outputs.columns.iter().enumerate().find(|(_, c)| !known.contains(c.as_str())) {
            let problem = Problem::new(
                format!("analyses.{analysis}.outputs.columns[{k}]"),
                format!("no result column '{missing}' in this analysis (bodies and joints go in outputs.bodies and outputs.joints)"),
            );
            self.selection = Selection::Failed(Error::Model(vec![problem]));
            return;
        }
        let keep: Vec<bool> = self
            .names
            .iter()
            .map(|name| {
                columns.contains(name.as_str())
                    || name.rsplit_once('.').is_some_and(|(owner, quantity)| {
                        (bodies.contains(owner) && BODY_QUANTITIES.contains(&quantity))
                            || (joints.contains(owner)
                                && (REACTION_QUANTITIES.contains(&quantity) || quantity == FRICTION_QUANTITY))
                    })
            })
            .collect();
        let all = std::mem::take(&mut self.names);
        let columns = std::mem::take(&mut self.columns);
        for ((name, column), &k) in all.iter().zip(columns).zip(&keep) {
            if k {
                self.names.push(name.clone());
                self.columns.push(column);
            }
        }
        self.selection = Selection::Applied { names: all, keep };
    }

    /// Add to the summary of an analysis with reactions: `reaction_bodies` (the body each joint's
    /// reaction acts on, its first, for reactions in that body's frame) and `peaks` (for every
    /// joint the largest resultant force `|(fx, fy)|` and the largest `|torque|`, for every
    /// active driver the largest `|effort|`, each with its time, for sizing bearings and motors).
    pub(crate) fn insert_reaction_summary(&mut self, model: &Model) {
        let reaction_bodies = model
            .joints
            .iter()
            .map(|j| {
                let body = j.constraint.anchor().i.0.map_or("ground", |k| model.bodies[k / 3].name.as_str());
                (j.name.clone(), body.to_string())
            })
            .collect();
        self.watch_peaks();
        let peaks = match &self.peaks {
            Peaks::Watching(watching) => watching.iter().map(|(key, _, peak)| (key.clone(), peak.clone())).collect(),
            _ => BTreeMap::new(),
        };
        self.summary.reactions = Some(Reactions { reaction_bodies, peaks });
    }

    /// Every column after `time` by its name: for looking up many columns, where
    /// [`Results::column`] searches the names each time (a thousand-body chain has 18,000).
    pub fn columns_by_name(&self) -> std::collections::HashMap<&str, &[f64]> {
        self.names.iter().zip(&self.columns).map(|(n, c)| (n.as_str(), c.as_slice())).collect()
    }

    /// The column called `name` (`time` included).
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        if name == "time" {
            return Some(&self.time);
        }
        self.names.iter().position(|n| n == name).map(|k| self.columns[k].as_slice())
    }

    /// Write `results.csv` at `path`: a header, then one line per output time; numbers in the
    /// shortest form that reads back to the same double. Written whole, then renamed into place, as
    /// [`Results::write`] does.
    pub fn write_csv(&self, path: &Path) -> Result<(), Error> {
        self.stage_csv(path)?.commit()
    }

    fn stage_csv(&self, path: &Path) -> Result<Staged, Error> {
        Staged::write(path, |w| {
            stream::write_header(w, &self.names)?;
            stream::write_rows(w, &self.time, &self.columns)
        })
    }

    /// The summary as JSON: [`Results::summary`] with `output_points`, `status` ("ok",
    /// "failed", or "interrupted" when the run was asked to stop) and, if there is one, the error (`error`, its message; `error_elements`, the
    /// joints and drivers it names; `error_time` when it happened at a time).
    pub fn summary_json(&self, error: Option<&Error>) -> Value {
        /// What `summary.json` holds: the summary, then what the run's outcome adds.
        #[derive(Serialize)]
        struct Written<'a> {
            #[serde(flatten)]
            summary: &'a Summary,
            output_points: usize,
            status: &'static str,
            #[serde(skip_serializing_if = "Option::is_none")]
            error: Option<String>,
            #[serde(skip_serializing_if = "Option::is_none")]
            error_elements: Option<Vec<String>>,
            #[serde(skip_serializing_if = "Option::is_none")]
            error_time: Option<f64>,
        }
        let error_time = match error {
            Some(
                Error::Singular { time, .. }
                | Error::Convergence { time, .. }
                | Error::Friction { time, .. }
                | Error::Branch { time, .. }
                | Error::Equilibrium { time, .. }
                | Error::NoEquilibrium { time, .. }
                | Error::Assembly { time, .. }
                | Error::Integration { time, .. }
                | Error::NonFinite { time, .. }
                | Error::Unbounded { time, .. }
                | Error::Jump { time, .. }
                | Error::OutOfMemory { time, .. }
                | Error::Accuracy { time, .. }
                | Error::Interrupted { time },
            ) => Some(*time),
            _ => None,
        };
        let written = Written {
            summary: &self.summary,
            output_points: self.len(),
            status: match error {
                None => "ok",
                Some(Error::Interrupted { .. }) => "interrupted",
                Some(_) => "failed",
            },
            error: error.map(|e| e.to_string()),
            error_elements: error.map(Error::elements),
            error_time,
        };
        // Plain data (strings, counts, finite or `None` numbers; a non-finite one is written as
        // null): serializing it cannot fail.
        serde_json::to_value(written).unwrap_or_default()
    }

    /// Write `modes.csv` of a modes analysis at `path`: one line per mode, `mode, kind, frequency,
    /// damped_frequency, damping_ratio, growth_rate` (-, Hz, Hz, 1, 1/s; empty where the mode has
    /// none: no frequency or damping ratio for an unstable mode, no growth rate for a stable
    /// one), then the shape's `<body>.x, .y, .phi`. Nothing for another analysis. Written whole,
    /// then renamed into place, as [`Results::write`] does.
    pub fn write_modes_csv(&self, path: &Path) -> Result<(), Error> {
        self.stage_modes_csv(path)?.map_or(Ok(()), Staged::commit)
    }

    fn stage_modes_csv(&self, path: &Path) -> Result<Option<Staged>, Error> {
        let Some(modes) = &self.summary.modes else { return Ok(None) };
        // The shape's coordinates in the order of the columns (bodies in file order).
        let shape = modes.first().map(|m| &m.shape);
        let coords: Vec<&String> = self.names.iter().filter(|n| shape.is_some_and(|s| s.contains_key(*n))).collect();
        // Empty where the mode has no such number, or (as null in `summary.json`) it is not finite.
        let num = |v: Option<f64>| v.filter(|x| x.is_finite()).map(|x| format!("{x:?}")).unwrap_or_default();
        Staged::write(path, |w| {
            write!(w, "mode,kind,frequency,damped_frequency,damping_ratio,growth_rate")?;
            for c in &coords {
                write!(w, ",{c}")?;
            }
            writeln!(w)?;
            for (k, m) in modes.iter().enumerate() {
                // The kind as `summary.json` spells it.
                let kind = serde_json::to_value(m.kind).unwrap_or_default();
                write!(w, "{},{}", k + 1, kind.as_str().unwrap_or_default())?;
                for value in [m.frequency, Some(m.damped_frequency), m.damping_ratio, m.growth_rate] {
                    write!(w, ",{}", num(value))?;
                }
                for c in &coords {
                    write!(w, ",{}", num(m.shape.get(c.as_str()).copied()))?;
                }
                writeln!(w)?;
            }
            Ok(())
        })
        .map(Some)
    }

    /// Write `sensitivities.csv` at `path` when the run has [`Results::sensitivities`] and
    /// holds its rows: a header (`time`, then [`Sensitivities::header`]), then one line per
    /// output time that has derivatives, numbers as in `results.csv`. Nothing otherwise (a streamed run's rows are
    /// in its file: its caller writes them beside it). Written whole, then renamed into place,
    /// as [`Results::write`] does.
    pub fn write_sensitivities_csv(&self, path: &Path) -> Result<(), Error> {
        self.stage_sensitivities_csv(path)?.map_or(Ok(()), Staged::commit)
    }

    fn stage_sensitivities_csv(&self, path: &Path) -> Result<Option<Staged>, Error> {
        let Some(s) = self.sensitivities.as_ref().filter(|_| !self.is_streamed()) else { return Ok(None) };
        let columns = s.columns();
        // The rows that have derivatives: every row of a run that ended well; a failed run's
        // derivatives may stop short of its last row.
        let rows = columns.iter().map(|c| c.len()).fold(self.time.len(), usize::min);
        Staged::write(path, |w| {
            stream::write_header(w, &s.header())?;
            stream::write_rows(w, &self.time[..rows], &columns)
        })
        .map(Some)
    }

    /// Write `results.csv` and `summary.json` into `dir` (created if missing), `modes.csv`
    /// for a modes analysis and `sensitivities.csv` for a run with sensitivities. Every file is
    /// written in full under a temporary name first, and only then are they renamed over the
    /// old ones: a run that dies or fails to write leaves the previous files, never a truncated
    /// one.
    pub fn write(&self, dir: &Path, error: Option<&Error>) -> Result<(), Error> {
        let io = |e: std::io::Error| Error::Io { path: dir.display().to_string(), message: e.to_string() };
        std::fs::create_dir_all(dir).map_err(io)?;
        // A streamed run's rows are in the file it streamed to.
        let csv = if self.is_streamed() { None } else { Some(self.stage_csv(&dir.join("results.csv"))?) };
        let modes = self.stage_modes_csv(&dir.join("modes.csv"))?;
        let sensitivities = self.stage_sensitivities_csv(&dir.join("sensitivities.csv"))?;
        let text = serde_json::to_string_pretty(&self.summary_json(error)).unwrap_or_default();
        let summary = Staged::write(&dir.join("summary.json"), |w| writeln!(w, "{text}"))?;
        csv.map_or(Ok(()), Staged::commit)?;
        modes.map_or(Ok(()), Staged::commit)?;
        sensitivities.map_or(Ok(()), Staged::commit)?;
        summary.commit()
    }
}

/// A file written in full under a temporary name beside its destination (`.<name>.<pid>.tmp`,
/// in the same directory so that the rename cannot cross file systems), then renamed over it by
/// [`Staged::commit`]: a rename within a directory is atomic on POSIX file systems and on NTFS,
/// so readers see the old file or the complete new one. Dropped without a commit, the temporary
/// file is removed.
struct Staged {
    temp: PathBuf,
    path: PathBuf,
}

impl Staged {
    /// Write `body` to the temporary file of `path`, flushed and synced to disk.
    fn write(path: &Path, body: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>) -> Result<Staged, Error> {
        let io = |e: std::io::Error| Error::Io { path: path.display().to_string(), message: e.to_string() };
        let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
        let temp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
        let staged = Staged { temp, path: path.to_path_buf() };
        let mut w = BufWriter::new(File::create(&staged.temp).map_err(io)?);
        body(&mut w).map_err(io)?;
        w.into_inner().map_err(|e| io(e.into_error()))?.sync_all().map_err(io)?;
        Ok(staged)
    }

    /// Rename the temporary file over the destination.
    fn commit(self) -> Result<(), Error> {
        std::fs::rename(&self.temp, &self.path)
            .map_err(|e| Error::Io { path: self.path.display().to_string(), message: e.to_string() })
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        // After a commit there is nothing left to remove; otherwise best effort: a temporary
        // file that cannot be removed is left, named as such.
        let _ = std::fs::remove_file(&self.temp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn results(value: f64) -> Results {
        let mut r = Results::with_columns(vec!["a.x".into()], Summary::default());
        r.time = vec![0.0, 1.0];
        r.columns = vec![vec![value, value]];
        r
    }

    /// A one-body model whose parameter `p` (and `T = 3 p`) the synthetic rows of
    /// [`synthetic`] depend on, with summaries of every shape: a largest row less a parameter,
    /// an integral over a parameter, a value between rows at a parameter's time.
    const SYNTHETIC: &str = "parameters: {p: 0.7, T: 3 * p}
bodies:
  wheel: {mass: 1, inertia: 0.1, position: [0, 0], points: {O: [0, 0]}}
joints:
  O: {type: revolute, body_i: wheel, point_i: O, body_j: ground, point_j: [0, 0]}
drivers:
  motor: {type: angle, body: wheel, function: \"p*t\"}
measures:
  s: \"sin(3*t)\"
summaries:
  top: \"max(wheel.x) - p\"
  energy: \"integral(wheel.omega^2) / T\"
  late: \"at(T / 3, s * wheel.y)\"
  span: \"final(time) - initial(time)\"
analyses:
  kinematics: {type: kinematic, t_end: 2, step: 0.05}
";

    /// The results of `SYNTHETIC` with the parameters `set`, its rows made up as smooth functions
    /// of `p` and `t` (`x = sin(p t) + p t^2`, `y = exp(-p t)`, `omega = p`; the reactions
    /// `fx = p cos(p t)`, `fy = p^2 t`, `torque = p sin(2 t)`, the effort `p (t - 1)`, the
    /// measure `s = sin(3 t)`), with their exact derivatives along `p` and `T` as its
    /// sensitivities, and summarised.
    fn synthetic(set: &[(&str, f64)]) -> Results {
        let set: Vec<(String, String)> = set.iter().map(|(n, v)| (n.to_string(), format!("{v:?}"))).collect();
        let mut model = Model::from_yaml_with(SYNTHETIC, &set).unwrap();
        // d(p, T) / d(p, T): T follows p (3), unless T is given (then only itself moves).
        let given_t = set.iter().any(|(n, _)| n == "T");
        model.gradients.params = vec![vec![1.0, 0.0], vec![if given_t { 0.0 } else { 3.0 }, 1.0]];
        let p = model.parameters["p"];
        let analysis = model.analysis("kinematics").unwrap().clone();
        let mut r = Results::new(&model, &analysis);
        r.add_columns(["O.fx", "O.fy", "O.torque", "motor.effort", "s"].map(String::from));
        let names = ["wheel.x", "wheel.y", "wheel.omega", "O.fx", "O.fy", "O.torque", "motor.effort", "s"];
        let mut dp = vec![Vec::new(); names.len()];
        for k in 0..=40 {
            let t = 0.05 * f64::from(k);
            let q = [(p * t).sin() + p * t * t, (-p * t).exp(), p * t];
            let extra = [p * (p * t).cos(), p * p * t, p * (2.0 * t).sin(), p * (t - 1.0), (3.0 * t).sin()];
            r.push(t, &q, &[0.0, 0.0, p], &[0.0; 3], &extra).unwrap();
            let d = [
                t * (p * t).cos() + t * t,
                -t * (-p * t).exp(),
                1.0,
                (p * t).cos() - p * t * (p * t).sin(),
                2.0 * p * t,
                (2.0 * t).sin(),
                t - 1.0,
                0.0,
            ];
            dp.iter_mut().zip(d).for_each(|(c, v)| c.push(v));
        }
        let zeros = vec![vec![0.0; dp[0].len()]; names.len()];
        r.sensitivities = Some(Sensitivities {
            parameters: vec!["p".into(), "T".into()],
            names: names.map(String::from).to_vec(),
            values: vec![dp, zeros],
        });
        r.insert_reaction_summary(&model);
        r.summarise().unwrap();
        r
    }

    /// Each summary's and peak's derivative with respect to `p` and to `T` against central
    /// differences of the whole summarised results with the parameter set at `-+ h` (`T` given
    /// replaces its expression; `p` given moves `T` with it), on the same rows. Step `h = 1e-5`:
    /// the differences' error `h^2 f''' / 6 ~ 1e-10` (third derivatives of order 1-10) plus
    /// round-off `1e-16 |f| / h ~ 1e-11`; tolerance 1e-8 relative (absolute below 1). Every
    /// largest row stays where it is within `-+ h`. `span` reads only the (fixed) time: 0.
    #[test]
    fn summary_sensitivities_match_central_differences_of_the_summaries() {
        let r = synthetic(&[]);
        let derivatives = r.summary.sensitivities.as_ref().expect("sensitivities");
        let h = 1e-5;
        let mut compared = 0;
        for (parameter, value) in [("p", 0.7), ("T", 2.1)] {
            let (up, down) = (synthetic(&[(parameter, value + h)]), synthetic(&[(parameter, value - h)]));
            let quantities = |r: &Results| -> Vec<(String, f64)> {
                let peaks = r.summary.reactions.as_ref().unwrap().peaks.iter().map(|(k, p)| (k.clone(), p.max_abs));
                r.summary.summaries.clone().unwrap().into_iter().chain(peaks).collect()
            };
            for ((name, a), (_, b)) in quantities(&up).into_iter().zip(quantities(&down)) {
                let differences = (a - b) / (2.0 * h);
                let exact = derivatives[&name][parameter];
                let error = (exact - differences).abs() / exact.abs().max(1.0);
                assert!(error < 1e-8, "d {name} / d {parameter}: {exact} against {differences}");
                compared += 1;
            }
        }
        // 4 summaries and 3 peaks (O.force, O.torque, motor.effort), for each parameter.
        assert_eq!(compared, 14);
        assert_eq!(derivatives.len(), 7);
        let span = &derivatives["span"];
        assert_eq!((span["p"], span["T"]), (0.0, 0.0));
    }

    /// `sensitivities.csv`: `time`, then each derivative by parameter then column, every row,
    /// numbers as in `results.csv`; absent without sensitivities.
    #[test]
    fn sensitivities_are_written_beside_the_results() {
        let dir = std::env::temp_dir().join(format!("linkwork-sensitivities-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let r = synthetic(&[]);
        r.write(&dir, None).unwrap();
        let text = std::fs::read_to_string(dir.join("sensitivities.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 1 + 2 * 8);
        assert_eq!(&header[..3], ["time", "d(wheel.x)/d(p)", "d(wheel.y)/d(p)"]);
        assert_eq!(header[9], "d(wheel.x)/d(T)");
        let second: Vec<f64> = lines.nth(1).unwrap().split(',').map(|v| v.parse().unwrap()).collect();
        let s = r.sensitivities.as_ref().unwrap();
        assert_eq!((second[0], second[1], second[9]), (r.time[1], s.values[0][0][1], s.values[1][0][1]));
        assert_eq!(text.lines().count(), 1 + r.len());
        let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        assert!(summary.contains("\"sensitivities\""));
        std::fs::remove_dir_all(&dir).unwrap();
        results(1.0).write(&dir, None).unwrap();
        assert!(!dir.join("sensitivities.csv").exists());
        assert!(!std::fs::read_to_string(dir.join("summary.json")).unwrap().contains("sensitivities"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The estimate is the rows' bytes against half the memory available: 10 million points of
    /// 28 columns are 8 x 2.8e8 = 2.24 GB, refused with 4 GB available (2.24 > 2) and kept with
    /// 5 GB (2.24 < 2.5); a summary's copy of a column counts every row, also when streamed.
    #[test]
    fn the_results_are_estimated_against_the_memory_available() {
        let refused = too_large(10_000_000, 28, 10_000_000, 0, Some(4_000_000_000)).expect("refused");
        assert!(
            refused.contains("2.24 GB") && refused.contains("--stream") && refused.contains("outputs:"),
            "{refused}"
        );
        assert_eq!(too_large(10_000_000, 28, 10_000_000, 0, Some(5_000_000_000)), None);
        assert!(too_large(1_000, 28, 10_000_000, 32, Some(5_000_000_000)).is_some(), "32 copies of 1e7 rows: 2.56 GB");
        assert_eq!(too_large(10_000_000, 28, 10_000_000, 0, None), None, "unknown: left to the allocations");
    }

    /// Results that cannot fit are refused before the run takes the memory: the first push
    /// returns `OutOfMemory` naming the remedies (the reservation panicked, or aborted the
    /// process: "memory allocation of 384000128 bytes failed").
    #[test]
    fn results_too_large_for_memory_fail_the_first_push() {
        let names = BODY_QUANTITIES.iter().map(|q| format!("a.{q}")).collect();
        let mut r = Results::with_columns(names, Summary::default());
        r.reserve(usize::MAX / 64);
        let pushed = r.push(0.5, &[0.0; 3], &[0.0; 3], &[0.0; 3], &[]);
        let Err(Error::OutOfMemory { time, what }) = pushed else { panic!("expected OutOfMemory, got {pushed:?}") };
        assert_eq!(time, 0.5);
        assert!(what.contains("--stream") && what.contains("outputs:"), "{what}");
        assert!(r.is_empty());
    }

    /// A write that fails part-way (here: `summary.json`'s temporary name is taken by a
    /// directory) leaves the previous files whole and no temporary file behind.
    #[test]
    fn a_failed_write_leaves_the_previous_files() {
        let dir = std::env::temp_dir().join(format!("linkwork-staged-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        results(1.0).write(&dir, None).unwrap();
        let before = std::fs::read_to_string(dir.join("results.csv")).unwrap();
        assert_eq!(before, "time,a.x\n0.0,1.0\n1.0,1.0\n");
        let blocker = dir.join(format!(".summary.json.{}.tmp", std::process::id()));
        std::fs::create_dir(&blocker).unwrap();
        let failed = results(2.0).write(&dir, None);
        assert!(matches!(failed, Err(Error::Io { ref path, .. }) if path.ends_with("summary.json")), "{failed:?}");
        assert_eq!(std::fs::read_to_string(dir.join("results.csv")).unwrap(), before);
        assert!(std::fs::read_to_string(dir.join("summary.json")).unwrap().contains("\"status\": \"ok\""));
        std::fs::remove_dir(&blocker).unwrap();
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left.len(), 2, "only results.csv and summary.json: {left:?}");
        results(2.0).write(&dir, None).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("results.csv")).unwrap(), "time,a.x\n0.0,2.0\n1.0,2.0\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
