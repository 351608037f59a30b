//! Typed errors that carry their context: the path in the model file, or the joint, row and time
//! of a solver failure. Expected numerical events (a singular Jacobian at a lock-up) are errors,
//! never panics.

use std::fmt;

/// One problem found in a model file: where (a dotted path into the file, such as
/// `joints.B.body_j`) and what was expected.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Problem {
    /// Dotted path of the offending field in the model file (empty for the whole file).
    pub path: String,
    /// What is wrong and what was expected.
    pub message: String,
}

impl Problem {
    /// A problem at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Problem {
        Problem { path: path.into(), message: message.into() }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

/// A constraint row, named by its joint (or driver) and equation, e.g. `B_slot.line`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct RowName {
    /// Name of the joint, driver or constraint in the model file.
    pub element: String,
    /// Name of the equation within it (`x`, `y`, `line`, `angle`, ...).
    pub equation: String,
}

impl fmt::Display for RowName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.element, self.equation)
    }
}

/// The equation a static solver left unbalanced: a constraint row, or the force balance of one
/// body coordinate (the loads along it that no reaction balances). A body is not a joint: only
/// a constraint row names one.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub enum Unbalanced {
    /// A constraint row of a joint or driver.
    Row(RowName),
    /// The force balance of a body coordinate, `<body>.x`, `.y` or `.phi`.
    Coordinate(String),
}

impl fmt::Display for Unbalanced {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unbalanced::Row(row) => write!(f, "{row}"),
            Unbalanced::Coordinate(c) => write!(f, "the force balance of {c}"),
        }
    }
}

/// Everything that can go wrong, by kind.
#[derive(Debug, Clone, thiserror::Error)]
pub enum Error {
    /// The model file (or Python model) is invalid; every problem found is listed.
    #[error("{}", format_problems(.0))]
    Model(Vec<Problem>),
    /// The initial guess could not be moved onto `Phi = 0`.
    #[error("assembly at t = {time} s failed after {iterations} iterations: residual {residual:.3e} (largest in {row}); {hint}")]
    Assembly {
        /// Time at which the system was assembled (drivers are evaluated there).
        time: f64,
        /// Newton iterations taken.
        iterations: usize,
        /// Max-norm of `Phi` at the best point found.
        residual: f64,
        /// The row with the largest residual.
        row: RowName,
        /// What the user can do about it.
        hint: String,
    },
    /// The constraint Jacobian lost rank during an analysis: a dead centre, lock-up or a lost
    /// degree of freedom.
    #[error("singular position at t = {time:.6} s: {detail}; rows involved: {}", join(.rows))]
    Singular {
        /// Time of the last configuration examined.
        time: f64,
        /// The rows (joint and equation) that become dependent.
        rows: Vec<RowName>,
        /// Numbers behind the verdict (singular values, condition estimate).
        detail: String,
    },
    /// Newton's method on the positions did not converge, even with the smallest sub-step.
    #[error("position solution did not converge at t = {time:.6} s: residual {residual:.3e} in {row} after {iterations} iterations with a sub-step of {substep:.3e} s")]
    Convergence {
        /// Time the solver was trying to reach.
        time: f64,
        /// Max-norm of `Phi` at the last iterate.
        residual: f64,
        /// The row with the largest residual.
        row: RowName,
        /// Newton iterations in the last attempt.
        iterations: usize,
        /// The sub-step that last failed.
        substep: f64,
    },
    /// A dynamic integrator could not continue: the step size fell below its minimum after
    /// repeated Newton or error-test failures.
    #[error("integration failed at t = {time:.6} s with a step of {step:.3e} s: {cause}{}", rows_suffix(.rows))]
    Integration {
        /// Time reached (the last accepted step).
        time: f64,
        /// The step that last failed, s.
        step: f64,
        /// What failed (Newton's method, the error test) and the numbers behind it.
        cause: String,
        /// The rows with the largest residual or involved in a singularity, if known.
        rows: Vec<RowName>,
    },
    /// Static equilibrium was not found: Newton with a line search, descents and load stepping
    /// all stopped short of the tolerance.
    #[error("no static equilibrium found at t = {time:.6} s: residual {residual:.3e} (largest in {equation}) after {iterations} Newton iterations, {:.1}% of the applied load reached", 100.0 * .load_fraction)]
    Equilibrium {
        /// Time of the equilibrium sought.
        time: f64,
        /// Largest residual (force over the load scale, or `|Phi|`) at the last iterate.
        residual: f64,
        /// The equation with the largest residual.
        equation: Unbalanced,
        /// Newton iterations in all attempts.
        iterations: usize,
        /// The fraction of the applied loads at which the last equilibrium was found.
        load_fraction: f64,
    },
    /// No stable static equilibrium within reach of the guess: the loads drive the mechanism
    /// along a path without end (no equilibrium exists there), or every equilibrium the solver
    /// reached was unstable.
    #[error("no stable static equilibrium found at t = {time:.6} s: {cause}")]
    NoEquilibrium {
        /// Time of the equilibrium sought.
        time: f64,
        /// The body coordinates that move along the path (`bob.phi`).
        coordinates: Vec<String>,
        /// The number of unstable directions of the last equilibrium reached; `None` when the
        /// loads drove the mechanism without end.
        index: Option<usize>,
        /// What happened, with the numbers.
        cause: String,
    },
    /// An element of the model evaluated to a number that is not finite (NaN or infinite): the
    /// analysis stops there rather than write it.
    #[error("{element} is {value} at t = {time} s{}", expression_suffix(.expression))]
    NonFinite {
        /// Time of the evaluation, s.
        time: f64,
        /// The element, as its path in the model file (`forces.drag`), or what was computed
        /// (`accelerations`) when no element is to blame.
        element: String,
        /// Its expressions, `field: source` (`torque: (t-0.3)/abs(t-0.3)`), or empty.
        expression: String,
        /// The value it gave.
        value: f64,
    },
    /// A driver's motion grows without bound: the sub-steps that keep each body's rotation
    /// under `max_rotation` reached a limit (`limit`) while the Jacobian stayed regular.
    #[error(
        "{element} grows without bound near t = {time} s ({expression}): its rate reached {rate:.3e}, and {limit}"
    )]
    Unbounded {
        /// Time reached, s.
        time: f64,
        /// The driver, as its path in the model file (`drivers.motor`).
        element: String,
        /// Its function of time.
        expression: String,
        /// Its rate there (rad/s or m/s).
        rate: f64,
        /// The limit the sub-steps reached.
        limit: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What the operating system said.
        message: String,
    },
}

/// ` (expression)` after a non-finite value's element, or nothing.
fn expression_suffix(expression: &str) -> String {
    if expression.is_empty() {
        String::new()
    } else {
        format!(" ({expression})")
    }
}

impl Error {
    /// The joints (and drivers) named by a solver error, in order and without repeats.
    pub fn elements(&self) -> Vec<String> {
        let rows: Vec<&RowName> = match self {
            Error::Singular { rows, .. } | Error::Integration { rows, .. } => rows.iter().collect(),
            Error::Convergence { row, .. } | Error::Assembly { row, .. } => vec![row],
            Error::Equilibrium { equation: Unbalanced::Row(row), .. } => vec![row],
            _ => vec![],
        };
        let mut out: Vec<String> = Vec::new();
        for r in rows {
            if !out.contains(&r.element) {
                out.push(r.element.clone());
            }
        }
        out
    }
}

fn rows_suffix(rows: &[RowName]) -> String {
    if rows.is_empty() {
        String::new()
    } else {
        format!("; rows involved: {}", join(rows))
    }
}

fn join(rows: &[RowName]) -> String {
    rows.iter().map(|r| r.to_string()).collect::<Vec<_>>().join(", ")
}

fn format_problems(problems: &[Problem]) -> String {
    let mut s = format!("the model has {} problem(s):", problems.len());
    for p in problems {
        s.push_str("\n  ");
        s.push_str(&p.to_string());
    }
    s
}

/// Shorthand for results in this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
