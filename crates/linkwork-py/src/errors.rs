//! The Python exception tree and the one place that maps engine errors onto it.
//!
//! ```text
//! LinkworkError
//! ├── ModelError          problems: list[(path, message)]
//! ├── AssemblyError       joints, row, residual, iterations, hint, results
//! ├── SolverError         time, joints, rows, results; itself for joint friction that did not
//! │                       converge (detail)
//! │   ├── SingularError       detail
//! │   ├── ConvergenceError    row, residual, iterations, substep
//! │   │   └── EquilibriumError    coordinates, index; row, residual, iterations, load_fraction or cause
//! │   ├── IntegrationError    step, cause
//! │   ├── NonFiniteError      element, expression, value (NaN, infinity, without bound, or a
//! │   │                       driver's jump)
//! │   ├── AccuracyError       quantity, value, bound, detail (a run that broke what it promised)
//! │   └── OutOfMemoryError    (also a MemoryError) memory ran out in a factorization
//! ├── FileError           path (also an OSError)
//! └── InternalError       a panic inside the engine: a bug, reported instead of crashing
//! ```
//!
//! Every exception's message is the engine's own (`Display`), so Python and the engine say the
//! same thing. `results` is the output computed before the failure (`None` outside `run`).

use crate::PyResults;
use linkwork::{Error, Unbalanced};
use pyo3::exceptions::{PyException, PyMemoryError, PyOSError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};
use pyo3::BoundObject;
use std::panic::{catch_unwind, AssertUnwindSafe};

pyo3::create_exception!(linkwork, LinkworkError, PyException, "Base class of every Linkwork error.");
pyo3::create_exception!(
    linkwork,
    ModelError,
    LinkworkError,
    "The model is invalid. `problems` lists every problem as `(path, message)`, the path being a dotted path into the model file such as `joints.B.body_j`."
);
pyo3::create_exception!(
    linkwork,
    AssemblyError,
    LinkworkError,
    "The initial guess could not be moved onto the constraints. `row` is the joint equation with the largest residual, `joints` its joint, `hint` what to try."
);
pyo3::create_exception!(
    linkwork,
    SolverError,
    LinkworkError,
    "An analysis failed at time `time` (s) in the joints `joints` (rows `rows`). `results` holds the output computed before the failure."
);
pyo3::create_exception!(
    linkwork,
    SingularError,
    SolverError,
    "The constraint Jacobian became singular: a dead centre, lock-up or lost degree of freedom. `detail` gives the numbers behind the verdict."
);
pyo3::create_exception!(
    linkwork,
    ConvergenceError,
    SolverError,
    "Newton's method on the positions did not converge, even with the smallest sub-step."
);
pyo3::create_exception!(
    linkwork,
    EquilibriumError,
    ConvergenceError,
    "A static analysis (or a modes analysis about the equilibrium) found no stable equilibrium at time `time`. `coordinates` names the body coordinates involved. Either the solver stopped short of any equilibrium (`row`: the equation with the largest residual, `residual`, `iterations`, `load_fraction`: the fraction of the applied load reached), or it found none stable (`cause` says why; `index` is the number of unstable directions of the last equilibrium reached, `None` when the loads drive the mechanism without end and no equilibrium exists)."
);
pyo3::create_exception!(
    linkwork,
    IntegrationError,
    SolverError,
    "A dynamic integrator could not continue (repeated Newton or error-test failures down to the smallest step). `step` is the step that last failed, `cause` what failed."
);
pyo3::create_exception!(
    linkwork,
    AccuracyError,
    SolverError,
    "A run that ended broke what it promised: a constraint residual at an output beyond what its tolerances allow (`rows` the row, `time` the output), or a conservative system's energy drifting by more than half of the energy of its motion. `quantity` names what was checked, `value` its value, `bound` the largest allowed, `detail` why and what to do; `results` holds every row computed."
);
pyo3::create_exception!(
    linkwork,
    NonFiniteError,
    SolverError,
    "An element evaluated to NaN or infinity at time `time`, or a driver's motion grew without bound near it: `element` is its path in the model file (`forces.drag`, `drivers.motor`), `expression` its expressions, `value` what it gave (for a driver without bound, its rate). No such number is written as a result."
);
pyo3::create_exception!(
    linkwork,
    InternalError,
    LinkworkError,
    "The engine panicked: a bug in Linkwork. Please report it with the model that caused it."
);

/// Every exception class, base classes before their subclasses, with the attributes it adds to
/// those of its base and their Python types: what [`build`] sets on an instance. The native
/// module exports it as `ERROR_ATTRIBUTES`; the exception lists of the Python package (the stub
/// `_linkwork.pyi`, `errors.py`, the README's table) are generated from it and from the classes
/// themselves (`python -m linkwork._generate`).
const ATTRIBUTES: &[(&str, &[(&str, &str)])] = &[
    ("LinkworkError", &[]),
    ("ModelError", &[("problems", "list[tuple[str, str]]")]),
    (
        "AssemblyError",
        &[
            ("time", "float"),
            ("joints", "list[str]"),
            ("row", "str"),
            ("residual", "float"),
            ("iterations", "int"),
            ("hint", "str"),
            ("results", "Any"),
        ],
    ),
    ("SolverError", &[("time", "float"), ("joints", "list[str]"), ("rows", "list[str]"), ("results", "Any")]),
    ("SingularError", &[("detail", "str")]),
    ("ConvergenceError", &[("row", "str"), ("residual", "float"), ("iterations", "int"), ("substep", "float")]),
    (
        "EquilibriumError",
        &[("coordinates", "list[str]"), ("index", "int | None"), ("load_fraction", "float"), ("cause", "str")],
    ),
    ("IntegrationError", &[("step", "float"), ("cause", "str")]),
    ("NonFiniteError", &[("element", "str"), ("expression", "str"), ("value", "float")]),
    ("AccuracyError", &[("quantity", "str"), ("value", "float"), ("bound", "float"), ("detail", "str")]),
    (OUT_OF_MEMORY_ERROR, &[]),
    (FILE_ERROR, &[("path", "str")]),
    ("InternalError", &[]),
];

/// Name of the exception that is both a `LinkworkError` and an `OSError`.
const FILE_ERROR: &str = "FileError";

/// Name of the exception that is both a `SolverError` and a `MemoryError`.
const OUT_OF_MEMORY_ERROR: &str = "OutOfMemoryError";

/// Add the exception classes to the module, and their attributes as `ERROR_ATTRIBUTES`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ERROR_ATTRIBUTES", ATTRIBUTES.to_vec())?;
    m.add("LinkworkError", py.get_type::<LinkworkError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("AssemblyError", py.get_type::<AssemblyError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("SingularError", py.get_type::<SingularError>())?;
    m.add("ConvergenceError", py.get_type::<ConvergenceError>())?;
    m.add("EquilibriumError", py.get_type::<EquilibriumError>())?;
    m.add("IntegrationError", py.get_type::<IntegrationError>())?;
    m.add("NonFiniteError", py.get_type::<NonFiniteError>())?;
    m.add("AccuracyError", py.get_type::<AccuracyError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    // Two bases, so that `except OSError` catches a missing model file as well, and `except
    // MemoryError` memory running out in an analysis: built with `type(name, bases, namespace)`,
    // as a `class` statement would.
    let two_bases = |name: &str, doc: &str, bases: [Bound<'_, PyType>; 2]| -> PyResult<()> {
        let namespace = PyDict::new(py);
        namespace.set_item("__module__", "linkwork")?;
        namespace.set_item("__doc__", doc)?;
        let class = py.get_type::<PyType>().call1((name, PyTuple::new(py, bases)?, namespace))?;
        m.add(name, class)
    };
    two_bases(
        FILE_ERROR,
        "A file could not be read or written. `path` names it.",
        [py.get_type::<LinkworkError>(), py.get_type::<PyOSError>()],
    )?;
    two_bases(
        OUT_OF_MEMORY_ERROR,
        "Memory ran out in a sparse factorization at time `time`: the model is too large for this machine. `results` holds the output computed before it.",
        [py.get_type::<SolverError>(), py.get_type::<PyMemoryError>()],
    )
}

/// Run `f`, turning a panic into `InternalError` so that it never reaches Python as a
/// `PanicException` (which `except Exception` does not catch). Needs no GIL.
pub fn guard<T>(f: impl FnOnce() -> T) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        internal(&what)
    })
}

/// An `InternalError` saying what went wrong.
pub fn internal(what: &str) -> PyErr {
    InternalError::new_err(format!(
        "internal error in the Linkwork engine (a bug; please report it with the model that caused it): {what}"
    ))
}

/// The Python exception for an engine error, with its context as attributes. `partial` (the
/// results before a failed analysis) becomes the `results` attribute where the error has one.
pub fn to_pyerr(py: Python<'_>, error: Error, partial: Option<PyResults>) -> PyErr {
    match build(py, &error, partial) {
        Ok(err) => err,
        // Setting an attribute failed (out of memory): the message alone still says what happened.
        Err(_) => LinkworkError::new_err(error.to_string()),
    }
}

/// The attributes an exception carries, in the order they are set.
struct Attributes<'py> {
    py: Python<'py>,
    list: Vec<(&'static str, Bound<'py, PyAny>)>,
}

impl<'py> Attributes<'py> {
    fn new(py: Python<'py>) -> Self {
        Attributes { py, list: Vec::new() }
    }

    /// Add `name = value`.
    fn with(mut self, name: &'static str, value: impl IntoPyObject<'py>) -> PyResult<Self> {
        let value = value.into_pyobject(self.py).map_err(Into::into)?.into_bound().into_any();
        self.list.push((name, value));
        Ok(self)
    }

    /// Where Newton's method stopped: the equation with the largest residual (`row`), that
    /// `residual`, and the `iterations` spent.
    fn newton(self, row: String, residual: f64, iterations: usize) -> PyResult<Self> {
        self.with("row", row)?.with("residual", residual)?.with("iterations", iterations)
    }
}

fn build(py: Python<'_>, error: &Error, partial: Option<PyResults>) -> PyResult<PyErr> {
    let message = error.to_string();
    let results = match partial {
        Some(r) => Py::new(py, r)?.into_any(),
        None => py.None(),
    };
    let names = |rows: &[linkwork::RowName]| rows.iter().map(|r| r.to_string()).collect::<Vec<_>>();
    // What every failure of a run carries: when, and in which joints and rows.
    let failure = |time: f64, rows: Vec<String>| {
        Attributes::new(py).with("time", time)?.with("joints", error.elements())?.with("rows", rows)
    };
    let (err, attributes) = match error {
        Error::Model(problems) => {
            let list: Vec<(String, String)> = problems.iter().map(|p| (p.path.clone(), p.message.clone())).collect();
            (ModelError::new_err(message), Attributes::new(py).with("problems", list)?)
        }
        Error::Assembly { time, iterations, residual, row, hint } => (
            AssemblyError::new_err(message),
            Attributes::new(py)
                .with("time", time)?
                .with("joints", error.elements())?
                .newton(row.to_string(), *residual, *iterations)?
                .with("hint", hint)?,
        ),
        Error::Singular { time, rows, detail } => {
            (SingularError::new_err(message), failure(*time, names(rows))?.with("detail", detail)?)
        }
        Error::Convergence { time, residual, row, iterations, substep } => (
            ConvergenceError::new_err(message),
            failure(*time, vec![row.to_string()])?
                .newton(row.to_string(), *residual, *iterations)?
                .with("substep", substep)?,
        ),
        Error::Equilibrium { time, residual, equation, iterations, load_fraction } => {
            // A constraint row names its joint; a force balance names a body coordinate.
            let (rows, coordinates, row) = match equation {
                Unbalanced::Row(r) => (vec![r.to_string()], vec![], r.to_string()),
                Unbalanced::Coordinate(c) => (vec![], vec![c.clone()], c.clone()),
            };
            (
                EquilibriumError::new_err(message),
                failure(*time, rows)?
                    .with("coordinates", coordinates)?
                    .with("index", py.None())?
                    .newton(row, *residual, *iterations)?
                    .with("load_fraction", load_fraction)?,
            )
        }
        Error::NoEquilibrium { time, coordinates, index, cause } => (
            EquilibriumError::new_err(message),
            failure(*time, vec![])?.with("coordinates", coordinates)?.with("index", index)?.with("cause", cause)?,
        ),
        Error::Branch { time, joint, detail } => {
            (SolverError::new_err(message), failure(*time, vec![joint.clone()])?.with("detail", detail)?)
        }
        Error::Friction { time, row, detail } => {
            (SolverError::new_err(message), failure(*time, vec![row.to_string()])?.with("detail", detail)?)
        }
        Error::Integration { time, step, cause, rows } => {
            (IntegrationError::new_err(message), failure(*time, names(rows))?.with("step", step)?.with("cause", cause)?)
        }
        // A driver without bound gives its rate as the value, one that jumps its jump.
        Error::NonFinite { time, element, expression, value }
        | Error::Unbounded { time, element, expression, rate: value, .. }
        | Error::Jump { time, element, expression, jump: value, .. } => (
            NonFiniteError::new_err(message),
            failure(*time, vec![])?.with("element", element)?.with("expression", expression)?.with("value", value)?,
        ),
        Error::Accuracy { time, quantity, rows, value, bound, detail } => (
            AccuracyError::new_err(message),
            failure(*time, names(rows))?
                .with("quantity", quantity)?
                .with("value", value)?
                .with("bound", bound)?
                .with("detail", detail)?,
        ),
        Error::OutOfMemory { time, .. } => {
            let class = py.import("linkwork._linkwork")?.getattr(OUT_OF_MEMORY_ERROR)?;
            (PyErr::from_value(class.call1((message,))?), failure(*time, vec![])?)
        }
        // Stopped by the Python side, which raises its own exception (`KeyboardInterrupt`);
        // this is what an interruption raises when it comes from elsewhere.
        Error::Interrupted { time } => {
            (pyo3::exceptions::PyKeyboardInterrupt::new_err(message), Attributes::new(py).with("time", time)?)
        }
        Error::Io { path, .. } => {
            let class = py.import("linkwork._linkwork")?.getattr(FILE_ERROR)?;
            let err = PyErr::from_value(class.call1((message,))?);
            (err, Attributes::new(py).with("path", path)?)
        }
    };
    // Every error but a model's or a file's stops a run, and carries its results until then.
    let attributes = match error {
        Error::Model(_) | Error::Io { .. } => attributes,
        _ => attributes.with("results", results)?,
    };
    let value = err.value(py);
    for (name, v) in attributes.list {
        value.setattr(name, v)?;
    }
    Ok(err)
}
