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
    #[error("assembly at t = {when} s failed after {iterations} iterations: residual {residual:.3e} (largest in {row}); {hint}", when = seconds(.time))]
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
    #[error("singular position at t = {when} s: {detail}; rows involved: {}", join(.rows), when = seconds(.time))]
    Singular {
        /// Time of the last configuration examined.
        time: f64,
        /// The rows (joint and equation) that become dependent.
        rows: Vec<RowName>,
        /// Numbers behind the verdict (singular values, condition estimate).
        detail: String,
    },
    /// Newton's method on the positions did not converge, even with the smallest sub-step.
    #[error("position solution did not converge at t = {when} s: residual {residual:.3e} in {row} after {iterations} iterations with a sub-step of {substep:.3e} s", when = seconds(.time))]
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
    #[error("integration failed at t = {when} s with a step of {step:.3e} s: {cause}{}", rows_suffix(.rows), when = seconds(.time))]
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
    /// A joint's friction and the reactions it depends on (docs/model-format.md, "Joint friction")
    /// did not converge to a consistent solution.
    #[error("joint friction did not converge at t = {when} s in {row}: {detail}", when = seconds(.time))]
    Friction {
        /// Time of the failure.
        time: f64,
        /// The joint (equation `friction`) whose multipliers changed most in the last iteration.
        row: RowName,
        /// What did not converge, by how much, and what it may mean.
        detail: String,
    },
    /// A dyad left the branch it must keep: a declared branch that cannot be assembled, or a
    /// change of branch during a run that must keep one (`branch: strict`, a sweep's variants).
    #[error("branch of joint {joint} at t = {when} s: {detail}", when = seconds(.time))]
    Branch {
        /// When the dyad left its branch (the assembly's time, or when its middle pin crossed
        /// its line), s.
        time: f64,
        /// The dyad's middle pin.
        joint: String,
        /// What happened, in words.
        detail: String,
    },
    /// Static equilibrium was not found: Newton with a line search, descents and load stepping
    /// all stopped short of the tolerance.
    #[error("no static equilibrium found at t = {when} s: residual {residual:.3e} (largest in {equation}) after {iterations} Newton iterations, {:.1}% of the applied load reached", 100.0 * .load_fraction, when = seconds(.time))]
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
    #[error("no stable static equilibrium found at t = {when} s: {cause}", when = seconds(.time))]
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
    #[error("{element} is {value} at t = {when} s{}", expression_suffix(.expression), when = seconds(.time))]
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
        "{element} grows without bound near t = {when} s ({expression}): its rate reached {rate:.3e}, and {limit}", when = seconds(.time)
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
    /// A driver's prescribed position jumps: it changes within the smallest sub-step by far more
    /// than its rate explains, and no position of the mechanism can follow it.
    #[error(
        "{element} jumps by {jump:.3e} at t = {when} s ({expression}): its position changes within {step:.3e} s by far more than its rate explains, and no motion of the mechanism can follow; make it continuous (a ramp or a motion law instead of a step)", when = seconds(.time)
    )]
    Jump {
        /// Time after the jump, s.
        time: f64,
        /// The driver, as its path in the model file (`drivers.motor`).
        element: String,
        /// Its function of time.
        expression: String,
        /// Its change over the step (rad or m).
        jump: f64,
        /// The step, s.
        step: f64,
    },
    /// A run that ended, checked against what it promised (docs/integrators.md, "What a run
    /// promises"; docs/kinematics.md, "The residual at every output"): a constraint residual
    /// at an output beyond what the tolerances allow, or a conservative system's energy drifting
    /// by more than half of the energy of its motion. The results computed are kept.
    #[error("{quantity} {value:.3e} at t = {when} s{}, above {bound:.3e}: {detail}", in_rows(.rows), when = seconds(.time))]
    Accuracy {
        /// The output time where the quantity was largest, s.
        time: f64,
        /// What was checked: `position residual`, `velocity residual`, `energy drift`.
        quantity: &'static str,
        /// The constraint row with the largest residual (empty for the energy).
        rows: Vec<RowName>,
        /// Its value.
        value: f64,
        /// The largest value the check allows.
        bound: f64,
        /// Why the bound is what it is, what it means, and what to do.
        detail: String,
    },
    /// Memory ran out in a sparse factorization: the model is too large for this machine.
    #[error("out of memory {what} at t = {when} s", when = seconds(.time))]
    OutOfMemory {
        /// Time of the factorization, s.
        time: f64,
        /// Which factorization (`while factorizing`, `in the symbolic factorization`).
        what: String,
    },
    /// The run was asked to stop (Ctrl-C) and stopped at the next time it reached.
    #[error("interrupted at t = {when} s", when = seconds(.time))]
    Interrupted {
        /// The time it stopped at, s.
        time: f64,
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

/// A time for a message, in seconds, the same way everywhere (and as `linkwork`'s command line
/// prints it): up to 9 significant digits without trailing zeros, in exponent form below 1e-4 (a
/// failure just after the start is `1.49e-10`, not `0.000000`); C's and Python's `%.9g`.
pub fn seconds(t: &f64) -> String {
    let t = *t;
    if t == 0.0 || !t.is_finite() {
        return format!("{t}");
    }
    // C's rule: the exponent of the value rounded to 9 significant digits chooses the form.
    let text = format!("{t:.8e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    if !(-4..9).contains(&exponent) {
        let sign = if exponent < 0 { '-' } else { '+' };
        return format!("{}e{sign}{:02}", trim_zeros(mantissa), exponent.abs());
    }
    trim_zeros(&format!("{t:.*}", (8 - exponent) as usize)).to_string()
}

/// `text` without the trailing zeros of its fraction (and without a bare trailing point).
fn trim_zeros(text: &str) -> &str {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        text
    }
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
            Error::Singular { rows, .. } | Error::Integration { rows, .. } | Error::Accuracy { rows, .. } => {
                rows.iter().collect()
            }
            Error::Convergence { row, .. } | Error::Assembly { row, .. } | Error::Friction { row, .. } => vec![row],
            Error::Equilibrium { equation: Unbalanced::Row(row), .. } => vec![row],
            Error::Branch { joint, .. } => return vec![joint.clone()],
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

/// ` in <row>` after a quantity checked in constraint rows, or nothing.
fn in_rows(rows: &[RowName]) -> String {
    if rows.is_empty() {
        String::new()
    } else {
        format!(" in {}", join(rows))
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

#[cfg(test)]
mod tests {
    use super::seconds;

    /// The same text as Python's `f"{t:.9g}"` (the values printed by CPython 3.11).
    #[test]
    fn seconds_reads_as_python_g9() {
        let cases = [
            (0.0, "0"),
            (1.4901161193847656e-10, "1.49011612e-10"),
            (0.30000000000000004, "0.3"),
            (10.55, "10.55"),
            (0.7214, "0.7214"),
            (1e9, "1e+09"),
            (123456789.0, "123456789"),
            (0.0001, "0.0001"),
            (9.999999999e-5, "0.0001"),
            (2.5e-5, "2.5e-05"),
            (-0.25, "-0.25"),
        ];
        for (t, text) in cases {
            assert_eq!(seconds(&t), text, "{t:e}");
        }
    }
}
