//! Python bindings of the Linkwork engine: thin wrappers, numpy out, every engine error mapped to
//! its own Python exception in one exhaustive `match` ([`errors::to_pyerr`]).
//!
//! The Python package `linkwork` (in `python/linkwork/`) is the public interface; this module,
//! `linkwork._linkwork`, is its native half and holds no logic of its own.

mod errors;
mod json;

use errors::{guard, to_pyerr};
use linkwork::analysis::check;
use linkwork::progress::{Progress, StopToken};
use linkwork::results::stream::RowSink;
use linkwork::{Error, Results, RunOptions, Sink};
use numpy::ndarray::{Array2, Array3, ShapeBuilder};
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::mpsc::RecvTimeoutError;
use std::sync::Arc;
use std::time::Duration;

/// How often a run's thread of Python wakes to handle signals and report progress: Ctrl-C
/// stops a run within this and one step of the analysis (the aim is 0.2 s), and a progress bar
/// moves 20 times a second, which a person sees as smooth. Each wake takes the GIL for
/// microseconds.
const POLL: Duration = Duration::from_millis(50);

/// Run `work` on a thread of its own with the GIL released. This thread wakes every [`POLL`] to
/// let Python handle its signals (Ctrl-C) and to call `report`; the first exception from either
/// stops `stop` (the work ends at its next step) and is returned beside the work's outcome.
fn watched<T: Send>(
    py: Python<'_>,
    stop: &StopToken,
    work: impl FnOnce() -> T + Send,
    mut report: impl FnMut(Python<'_>) -> PyResult<()> + Send,
) -> (PyResult<T>, Option<PyErr>) {
    let mut stopped_by: Option<PyErr> = None;
    let outcome = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = std::sync::mpsc::channel();
            let worker = scope.spawn(move || {
                let outcome = guard(work);
                // The receiver waits below for as long as this thread runs.
                let _ = done.send(());
                outcome
            });
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(POLL) {
                if stopped_by.is_some() {
                    continue;
                }
                Python::attach(|py| {
                    if let Err(e) = py.check_signals().and_then(|()| report(py)) {
                        stop.stop();
                        stopped_by = Some(e);
                    }
                });
            }
            worker.join().unwrap_or_else(|_| Err(errors::internal("the analysis thread panicked")))
        })
    });
    (outcome, stopped_by)
}

/// A compiled mechanism (immutable).
#[pyclass(name = "PyModel", module = "linkwork._linkwork", frozen)]
struct PyModel {
    model: linkwork::Model,
}

#[pymethods]
impl PyModel {
    /// Read and compile a model file, with parameter values `(name, text)` over the file's.
    /// Raises `ModelError` listing every problem, or `FileError`.
    #[staticmethod]
    #[pyo3(signature = (path, parameters=Vec::new()))]
    fn load(py: Python<'_>, path: PathBuf, parameters: Vec<(String, String)>) -> PyResult<PyModel> {
        let model = py.detach(|| guard(|| linkwork::Model::load_with(&path, &parameters)))?;
        model.map(|model| PyModel { model }).map_err(|e| to_pyerr(py, e, None))
    }

    /// Compile a model from the text of a model file, with parameter values `(name, text)` over
    /// the file's; a table's `file:` is read from `folder` (default: the working folder).
    #[staticmethod]
    #[pyo3(signature = (text, parameters=Vec::new(), folder=PathBuf::new()))]
    fn from_yaml(py: Python<'_>, text: &str, parameters: Vec<(String, String)>, folder: PathBuf) -> PyResult<PyModel> {
        let model = py.detach(|| guard(|| linkwork::Model::from_yaml_in(text, &parameters, folder)))?;
        model.map(|model| PyModel { model }).map_err(|e| to_pyerr(py, e, None))
    }

    /// The same model file with parameter values `(name, text)` over this model's.
    fn with_parameters(&self, py: Python<'_>, values: Vec<(String, String)>) -> PyResult<PyModel> {
        let model = py.detach(|| guard(|| self.model.with_parameters(&values)))?;
        model.map(|model| PyModel { model }).map_err(|e| to_pyerr(py, e, None))
    }

    /// Run `analysis` for each of `variants` (parameter values `(name, text)`) on `workers`
    /// threads (every core when `None`), reducing each run to `outputs` (`(name, expression)`).
    /// One `(status, values)` a variant, in order: `("ok", [...])`, or `("<ErrorClass>: <message>",
    /// None)`. A bad output expression raises `ModelError` at `outputs.<name>`.
    ///
    /// Watched as [`PyModel::run`]: `progress(finished)` is called with the variants finished;
    /// Ctrl-C (or an exception from `progress`) ends the variants not finished as interrupted
    /// and raises, with the rows as the attribute `rows`.
    ///
    /// With `gradients` (names of parameters) each row's values are followed by each output's
    /// derivatives with respect to them, output by output (`linkwork::sweep::sweep_with_gradients`).
    #[pyo3(signature = (analysis, variants, outputs, workers=None, progress=None, gradients=Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn sweep(
        &self,
        py: Python<'_>,
        analysis: &str,
        variants: Vec<Vec<(String, String)>>,
        outputs: Vec<(String, String)>,
        workers: Option<usize>,
        progress: Option<Py<PyAny>>,
        gradients: Vec<String>,
    ) -> PyResult<Vec<(String, Option<Vec<f64>>)>> {
        let parsed: Vec<linkwork::sweep::Output> = outputs
            .iter()
            .map(|(name, source)| {
                linkwork::sweep::Output::parse(name, source).map_err(|message| {
                    let problem = linkwork::Problem::new(format!("outputs.{name}"), message);
                    to_pyerr(py, linkwork::Error::Model(vec![problem]), None)
                })
            })
            .collect::<PyResult<_>>()?;
        let (watch, stop) = (Progress::new(), StopToken::new());
        let (outcome, stopped_by) = watched(
            py,
            &stop,
            || {
                let sweep = linkwork::sweep::sweep_with_gradients;
                sweep(&self.model, analysis, &variants, &parsed, &gradients, workers, &watch, &stop)
            },
            |py| match &progress {
                Some(f) => f.call1(py, (watch.finished(),)).map(drop),
                None => Ok(()),
            },
        );
        let mut classes = std::collections::HashMap::new();
        let rows: Vec<_> = outcome?
            .map_err(|e| to_pyerr(py, e, None))?
            .into_iter()
            .map(|row| match row {
                Ok(values) => ("ok".to_string(), Some(values)),
                // A variant that cannot keep the nominal model's branches: its own status, so that
                // a table of them is read at a glance.
                Err(error @ linkwork::Error::Branch { .. }) => (format!("other branch: {error}"), None),
                Err(error) => {
                    let message = error.to_string();
                    // The class of each kind of error found once: making an exception takes tens
                    // of microseconds, and a stopped sweep has a row for every variant not run.
                    let class = classes.entry(std::mem::discriminant(&error)).or_insert_with(|| {
                        let class = to_pyerr(py, error, None).get_type(py).name().map(|n| n.to_string());
                        class.unwrap_or_else(|_| "LinkworkError".into())
                    });
                    (format!("{class}: {message}"), None)
                }
            })
            .collect();
        match stopped_by {
            Some(e) => {
                e.value(py).setattr("rows", rows)?;
                Err(e)
            }
            None => Ok(rows),
        }
    }

    /// The parameters' values used, SI, in file order.
    #[getter]
    fn parameters(&self) -> Vec<(String, f64)> {
        self.model.parameters.iter().map(|(n, v)| (n.clone(), *v)).collect()
    }

    /// The unit the file writes each parameter in, for those it writes with one (`(name, unit)`).
    #[getter]
    fn parameter_units(&self) -> Vec<(String, String)> {
        self.model.parameter_units.iter().map(|(n, u)| (n.clone(), u.clone())).collect()
    }

    /// The tolerance of each parameter the file gives one, in file order: `(name, tolerance
    /// (SI), distribution ("normal" or "uniform"), standard deviation (SI))`.
    #[getter]
    fn tolerances(&self) -> Vec<(String, f64, &'static str, f64)> {
        self.model.tolerances.iter().map(|(n, t)| (n.clone(), t.value, t.distribution.name(), t.sigma())).collect()
    }

    /// Warnings about the parameter values given from outside, each `parameters.<name>: ...`.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.model.warnings.clone()
    }

    /// The units results are shown in (the file's `display:` section, SI without one): each
    /// quantity's `(quantity, unit, factor to SI)`.
    #[getter]
    fn display(&self) -> Vec<(String, String, f64)> {
        self.model.display.units.iter().map(|(q, u, f)| (q.to_string(), u.clone(), *f)).collect()
    }

    /// The quantity of each result column of `names` (`length`, `angle`, `force` ...; `None` for
    /// a pure number or a column whose quantity is not known).
    fn column_quantities(&self, names: Vec<String>) -> Vec<Option<String>> {
        names.iter().map(|n| self.model.column_quantity(n).map(str::to_string)).collect()
    }

    /// The parameter values given over the file's (`(name, text)`), as `from_yaml` takes them.
    #[getter]
    fn set(&self) -> Vec<(String, String)> {
        self.model.set.clone()
    }

    /// The folder a table's `file:` is read from (empty: the working folder).
    #[getter]
    fn folder(&self) -> PathBuf {
        self.model.folder.clone()
    }

    /// Each table's `file:` as written, in file order.
    #[getter]
    fn table_files(&self) -> Vec<String> {
        self.model.table_files.clone()
    }

    /// Title of the model.
    #[getter]
    fn name(&self) -> &str {
        &self.model.name
    }

    /// The text of the model file.
    #[getter]
    fn source(&self) -> &str {
        &self.model.source
    }

    /// Names of the moving bodies, in file order.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.model.bodies.iter().map(|b| b.name.clone()).collect()
    }

    /// Names of the joints, in file order.
    #[getter]
    fn joints(&self) -> Vec<String> {
        self.model.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// Names of the drivers, in file order.
    #[getter]
    fn drivers(&self) -> Vec<String> {
        self.model.drivers.iter().map(|d| d.name.clone()).collect()
    }

    /// Names of the analyses, in file order.
    #[getter]
    fn analyses(&self) -> Vec<String> {
        self.model.analyses.keys().cloned().collect()
    }

    /// Degrees of freedom, redundant rows and assembly, for the mechanism alone and for each
    /// analysis with its drivers, as the engine's `CheckReport` in plain Python objects.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = py.detach(|| guard(|| check(&self.model)))?.map_err(|e| to_pyerr(py, e, None))?;
        let value = serde_json::to_value(&report).map_err(|e| errors::internal(&e.to_string()))?;
        json::to_py(py, &value)
    }

    /// The picture of the mechanism, as the engine's `Drawing` in plain Python objects: each
    /// body's points in its frame, each joint's bodies, points and shape.
    fn drawing<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value = serde_json::to_value(self.model.drawing()).map_err(|e| errors::internal(&e.to_string()))?;
        json::to_py(py, &value)
    }

    /// Run the analysis called `analysis`, with optional changes for this run (`integrator`:
    /// "bdf", "hht" or "abam"; tolerances; end time and output step). A failure raises the
    /// matching exception, whose `results` attribute holds the output computed before it.
    ///
    /// The analysis runs on a thread of its own, with the GIL released; this thread wakes every
    /// [`POLL`] to let Python handle its signals (Ctrl-C stops the run at its next step and
    /// raises `KeyboardInterrupt` with `results`) and to call `progress(time, t_start, t_end,
    /// steps)` if given (an exception from it stops the run and is raised).
    ///
    /// `stream`: the rows go, as they are computed, to the CSV file at this path (a `str`), or
    /// to an object with `begin(names)`, `write(time, values)`, `finish()` and `path` (the
    /// Python package's Parquet writer); the results returned then hold no row.
    #[pyo3(signature = (analysis, integrator=None, rtol=None, atol=None, t_end=None, step=None, progress=None, stream=None, sensitivities=Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        py: Python<'_>,
        analysis: &str,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        t_end: Option<f64>,
        step: Option<f64>,
        progress: Option<Py<PyAny>>,
        stream: Option<Bound<'_, PyAny>>,
        sensitivities: Vec<String>,
    ) -> PyResult<PyResults> {
        use linkwork::analysis::dynamic::IntegratorKind;
        let sink = match stream {
            None => Sink::Memory,
            Some(s) => match s.extract::<PathBuf>() {
                Ok(path) => Sink::csv(&path),
                Err(_) => {
                    let path = s.getattr("path")?.str()?.to_string();
                    Sink::stream(Box::new(PySink { sink: s.unbind(), path }))
                }
            },
        };
        let integrator = match integrator.map(|name| (name, IntegratorKind::from_name(name))) {
            None => None,
            Some((_, Some(kind))) => Some(kind),
            Some((other, None)) => {
                let (last, rest) = IntegratorKind::NAMES.split_last().expect("there are integrators");
                let expected = format!("{} or {last}", rest.join(", "));
                let problem = linkwork::Problem::new(
                    "--integrator",
                    format!("unknown integrator '{other}'; expected {expected}"),
                );
                return Err(to_pyerr(py, Error::Model(vec![problem]), None));
            }
        };
        let overrides = linkwork::Overrides { integrator, rtol, atol, t_end, step };
        let watch = Progress::new();
        let options =
            RunOptions { overrides, progress: Some(Arc::clone(&watch)), stop: StopToken::new(), sink, sensitivities };
        let (outcome, stopped_by) = watched(
            py,
            &options.stop,
            || self.model.run(analysis, &options),
            |py| match &progress {
                Some(f) => {
                    let (t0, t1) = watch.span();
                    f.call1(py, (watch.time(), t0, t1, watch.steps())).map(drop)
                }
                None => Ok(()),
            },
        );
        match outcome? {
            Ok(results) => Ok(PyResults { results, error: None }),
            Err(failure) => {
                let linkwork::Failure { error, results } = *failure;
                let partial = PyResults { results, error: Some(error.clone()) };
                match (stopped_by, &error) {
                    (Some(e), Error::Interrupted { .. }) => {
                        e.value(py).setattr("results", Py::new(py, partial)?)?;
                        Err(e)
                    }
                    _ => Err(to_pyerr(py, error, Some(partial))),
                }
            }
        }
    }
}

/// A Python object the rows of a streamed run go to (`begin(names)`, `write(time, values)`,
/// `finish()`), called from the run's thread with the GIL taken for each call; an exception it
/// raises fails the run as a file that cannot be written does.
struct PySink {
    sink: Py<PyAny>,
    path: String,
}

impl PySink {
    fn call(&self, f: impl FnOnce(Python<'_>, &Py<PyAny>) -> PyResult<Py<PyAny>>) -> std::io::Result<()> {
        Python::attach(|py| f(py, &self.sink).map(drop).map_err(|e| std::io::Error::other(e.to_string())))
    }
}

impl RowSink for PySink {
    fn begin(&mut self, names: &[String]) -> std::io::Result<()> {
        self.call(|py, s| s.call_method1(py, "begin", (names.to_vec(),)))
    }

    fn write(&mut self, time: &[f64], columns: &[Vec<f64>]) -> std::io::Result<()> {
        self.call(|py, s| {
            let values = column_matrix(py, time.len(), columns)?;
            s.call_method1(py, "write", (PyArray1::from_slice(py, time), values))
        })
    }

    fn finish(&mut self) -> std::io::Result<()> {
        self.call(|py, s| s.call_method0(py, "finish"))
    }

    fn path(&self) -> String {
        self.path.clone()
    }
}

/// `(rows x columns)` in Fortran order, so that each column is contiguous.
fn column_matrix<'py>(py: Python<'py>, rows: usize, columns: &[Vec<f64>]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = columns.iter().flatten().copied().collect();
    let array = Array2::from_shape_vec((rows, columns.len()).f(), flat)
        .map_err(|e| errors::internal(&format!("results columns of unequal length: {e}")))?;
    Ok(PyArray2::from_owned_array(py, array))
}

/// Output of one analysis (complete, or up to a failure).
#[pyclass(name = "PyResults", module = "linkwork._linkwork", frozen)]
struct PyResults {
    results: Results,
    /// Why the analysis stopped early, if it did.
    error: Option<Error>,
}

#[pymethods]
impl PyResults {
    /// Column names after `time`: `<body>.x, .y, .phi, .vx, .vy, .omega, .ax, .ay, .alpha` per
    /// body, then (dynamics) reactions, driver efforts, energies and residuals, then measures.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.results.names.clone()
    }

    /// (rows) output times, s.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.results.time)
    }

    /// (rows x columns) values in Fortran order, so that each column is contiguous.
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        column_matrix(py, self.results.time.len(), &self.results.columns)
    }

    /// True when the rows went to a file as they were computed (`time` and `values` hold none).
    #[getter]
    fn streamed(&self) -> bool {
        self.results.is_streamed()
    }

    /// `summary.json` as a dict: sizes, solver statistics, `status` and the error if any.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json::to_py(py, &self.results.summary_json(self.error.as_ref()))
    }

    /// The derivatives of the columns with respect to the parameters the run was asked for:
    /// `(parameters, names, values)`, `values` (parameters x names x rows, the rows that have
    /// derivatives), SI per SI unit of the parameter; `None` when it was asked for none.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn sensitivities<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Vec<String>, Vec<String>, Bound<'py, PyArray3<f64>>)>> {
        let Some(s) = &self.results.sensitivities else { return Ok(None) };
        // The rows every derivative has (a failed run's may stop a row short of its results').
        let columns = s.columns();
        let rows = columns.iter().map(|c| c.len()).min().unwrap_or(0);
        let flat: Vec<f64> = columns.iter().flat_map(|c| c[..rows].iter().copied()).collect();
        let values = Array3::from_shape_vec((s.parameters.len(), s.names.len(), rows), flat)
            .map_err(|e| errors::internal(&format!("sensitivities of unequal length: {e}")))?;
        Ok(Some((s.parameters.clone(), s.names.clone(), PyArray3::from_owned_array(py, values))))
    }

    /// True when the analysis ran to its end time.
    #[getter]
    fn ok(&self) -> bool {
        self.error.is_none()
    }

    /// Write `results.csv` and `summary.json` into `directory` (created if missing).
    fn write(&self, py: Python<'_>, directory: PathBuf) -> PyResult<()> {
        py.detach(|| guard(|| self.results.write(&directory, self.error.as_ref())))?.map_err(|e| to_pyerr(py, e, None))
    }
}

/// The name of the derivative of `column` with respect to `parameter` (`d(<column>)/d(<parameter>)`),
/// as `sensitivities.csv` writes it.
#[pyfunction]
fn sensitivity_name(column: &str, parameter: &str) -> String {
    linkwork::Sensitivities::column_name(column, parameter)
}

/// The JSON Schema of model files, as JSON text.
#[pyfunction]
fn schema() -> PyResult<String> {
    guard(linkwork::Model::json_schema)
}

/// A number with a unit (`"12 mm"`) as `(value in SI, unit)`; `None` when `text` is not a number
/// followed by a unit. A unit that cannot be read raises `ValueError` saying why.
#[pyfunction]
fn quantity(text: &str) -> PyResult<Option<(f64, String)>> {
    match linkwork::model::units::quantity(text) {
        None => Ok(None),
        Some(Ok((value, _))) => {
            let unit = linkwork::model::units::unit_text(text).unwrap_or_default();
            Ok(Some((value, unit.to_string())))
        }
        Some(Err(e)) => Err(pyo3::exceptions::PyValueError::new_err(e)),
    }
}

/// Each quantity of results with its SI unit (`("length", "m")`, ...), as a model without a
/// `display:` section shows them.
#[pyfunction]
fn si_units() -> Vec<(String, String)> {
    linkwork::model::units::QUANTITIES.iter().map(|(q, _, u)| (q.to_string(), u.to_string())).collect()
}

/// The SI unit of the dimension of a unit (`"mm"`: `"m"`), `None` when results have no quantity
/// of it; `ValueError` saying why a unit cannot be read.
#[pyfunction]
fn si_unit(text: &str) -> PyResult<Option<&'static str>> {
    let (_, dim) = linkwork::model::units::unit(text).map_err(pyo3::exceptions::PyValueError::new_err)?;
    Ok(linkwork::model::units::si_unit(dim))
}

/// The factor to SI of a unit (`"mm"`: 0.001); `ValueError` saying why one cannot be read.
#[pyfunction]
fn unit(text: &str) -> PyResult<f64> {
    linkwork::model::units::unit(text).map(|(f, _)| f).map_err(pyo3::exceptions::PyValueError::new_err)
}

/// Panic inside the guard that wraps every engine call, so that tests can see the panic arrive as
/// `InternalError` rather than crash the interpreter.
#[pyfunction]
fn _panic_for_tests() -> PyResult<()> {
    guard(|| panic!("deliberate panic (linkwork._linkwork._panic_for_tests)"))
}

#[pymodule]
fn _linkwork(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyModel>()?;
    m.add_class::<PyResults>()?;
    m.add_function(wrap_pyfunction!(schema, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity_name, m)?)?;
    m.add_function(wrap_pyfunction!(quantity, m)?)?;
    m.add_function(wrap_pyfunction!(unit, m)?)?;
    m.add_function(wrap_pyfunction!(si_units, m)?)?;
    m.add_function(wrap_pyfunction!(si_unit, m)?)?;
    m.add("AGGREGATIONS", linkwork::expr::functional::AGGREGATIONS.to_vec())?;
    m.add("BODY_QUANTITIES", linkwork::results::BODY_QUANTITIES.to_vec())?;
    // The columns an analysis adds that belong to no body, joint or driver, each once: the
    // dynamic analyses' energies and residuals, then the inverse analysis's powers.
    let mut engine_columns = linkwork::analysis::dynamic::ENERGY_COLUMNS.to_vec();
    for column in linkwork::analysis::INVERSE_COLUMNS {
        if !engine_columns.contains(&column) {
            engine_columns.push(column);
        }
    }
    m.add("ENGINE_COLUMNS", engine_columns)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    errors::register(m)
}
