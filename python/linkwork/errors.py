"""The exceptions Linkwork raises.

::

    LinkworkError
    ├── ModelError          problems: list of (path, message), e.g. ("joints.B.body_j", "unknown body 'rokcer' ...")
    ├── AssemblyError       joints, row, residual, iterations, hint, results
    ├── SolverError         time (s), joints, rows, results (the output computed before the failure);
    │                       raised itself, with detail, when a joint's friction and its reactions do not converge,
    │                       or a dyad cannot keep its branch (a declared one, branch: strict, a sweep's variant)
    │   ├── SingularError       detail: a dead centre, lock-up or lost degree of freedom
    │   ├── ConvergenceError    row, residual, iterations, substep
    │   │   └── EquilibriumError    coordinates, index: no stable static equilibrium (stopped short: row,
    │   │                           residual, iterations, load_fraction; none stable or none at all: cause)
    │   ├── IntegrationError    step, cause: a dynamic integrator could not continue
    │   ├── NonFiniteError      element, expression, value: an element gave NaN or infinity, or a driver ran away or jumped
    │   ├── AccuracyError       quantity, value, bound, detail: a run broke what it promised (a constraint
    │   │                       residual at an output, a conservative system's energy)
    │   └── OutOfMemoryError    memory ran out in a factorization; also a MemoryError
    ├── FileError           path; also an OSError
    └── InternalError       the engine panicked: a bug, reported instead of crashing

The classes are defined by the native module, which maps each engine error to one of them; the
message of each is the engine's own.
"""

from __future__ import annotations

from ._linkwork import (
    AccuracyError,
    AssemblyError,
    ConvergenceError,
    EquilibriumError,
    FileError,
    IntegrationError,
    InternalError,
    LinkworkError,
    ModelError,
    NonFiniteError,
    OutOfMemoryError,
    SingularError,
    SolverError,
)

__all__ = [
    "AccuracyError",
    "AssemblyError",
    "ConvergenceError",
    "EquilibriumError",
    "FileError",
    "IntegrationError",
    "InternalError",
    "LinkworkError",
    "ModelError",
    "NonFiniteError",
    "OutOfMemoryError",
    "SingularError",
    "SolverError",
    "model_error",
]


def model_error(path: str, message: str) -> ModelError:
    """A :class:`ModelError` with one problem, worded as the engine words its own."""
    error = ModelError(f"the model has 1 problem(s):\n  {path}: {message}")
    error.problems = [(path, message)]
    return error
