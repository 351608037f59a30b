"""The exceptions Linkwork raises: every one a :class:`LinkworkError`.

The classes are defined by the native module (``crates/linkwork-py/src/errors.rs``), which maps
each engine error to one of them; the message of each is the engine's own, its docstring says
when it is raised, and the README's table ("Errors in Python") gives each with its base classes,
its attributes and the exit status of the command line.
"""

from __future__ import annotations

# generated: exception names
from ._linkwork import (
    AccuracyError, AssemblyError, ConvergenceError, EquilibriumError, FileError, IntegrationError,
    InternalError, LinkworkError, ModelError, NonFiniteError, OutOfMemoryError, SingularError,
    SolverError,
)

__all__ = [
    'AccuracyError', 'AssemblyError', 'ConvergenceError', 'EquilibriumError', 'FileError',
    'IntegrationError', 'InternalError', 'LinkworkError', 'ModelError', 'NonFiniteError',
    'OutOfMemoryError', 'SingularError', 'SolverError',
]
# end generated: exception names


def model_error(path: str, message: str) -> ModelError:
    """A :class:`ModelError` with one problem, worded as the engine words its own."""
    error = ModelError(f"the model has 1 problem(s):\n  {path}: {message}")
    error.problems = [(path, message)]
    return error
