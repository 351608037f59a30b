"""Native half of the linkwork package (PyO3). Use the `linkwork` package, not this module.

The types of what `crates/linkwork-py/src/` exports; `python -m mypy.stubtest linkwork._linkwork`
checks them against the built module (`.ci/run`).
"""

import os
import pathlib
from collections.abc import Callable, Sequence
from typing import Any, Protocol, final

import numpy as np
import numpy.typing as npt

# generated: names
__all__ = [
    'AGGREGATIONS', 'AccuracyError', 'AssemblyError', 'BODY_QUANTITIES', 'ConvergenceError',
    'ENGINE_COLUMNS', 'ERROR_ATTRIBUTES', 'EquilibriumError', 'FileError', 'IntegrationError',
    'InternalError', 'LinkworkError', 'ModelError', 'NonFiniteError', 'OutOfMemoryError', 'PyModel',
    'PyResults', 'SingularError', 'SolverError', '__version__', '_panic_for_tests', 'quantity',
    'schema', 'sensitivity_name', 'si_unit', 'si_units', 'unit',
]
# end generated: names

__version__: str

@final
class PyModel:
    @staticmethod
    def load(path: str, parameters: Sequence[tuple[str, str]] = ...) -> PyModel: ...
    @staticmethod
    def from_yaml(text: str, parameters: Sequence[tuple[str, str]] = ..., folder: str | os.PathLike[str] = ...) -> PyModel: ...
    def with_parameters(self, values: Sequence[tuple[str, str]]) -> PyModel: ...
    def sweep(
        self,
        analysis: str,
        variants: Sequence[Sequence[tuple[str, str]]],
        outputs: Sequence[tuple[str, str]],
        workers: int | None = None,
        progress: Callable[[int], object] | None = None,
        gradients: Sequence[str] = ...,
    ) -> list[tuple[str, list[float] | None]]: ...
    @property
    def parameters(self) -> list[tuple[str, float]]: ...
    @property
    def parameter_units(self) -> list[tuple[str, str]]: ...
    @property
    def tolerances(self) -> list[tuple[str, float, str, float]]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def display(self) -> list[tuple[str, str, float]]: ...
    def column_quantities(self, names: list[str]) -> list[str | None]: ...
    @property
    def set(self) -> list[tuple[str, str]]: ...
    @property
    def folder(self) -> pathlib.Path: ...
    @property
    def table_files(self) -> list[str]: ...
    @property
    def source(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def bodies(self) -> list[str]: ...
    @property
    def joints(self) -> list[str]: ...
    @property
    def drivers(self) -> list[str]: ...
    @property
    def analyses(self) -> list[str]: ...
    def check(self) -> dict[str, Any]: ...
    def drawing(self) -> dict[str, Any]: ...
    def run(
        self,
        analysis: str,
        integrator: str | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        t_end: float | None = None,
        step: float | None = None,
        progress: Callable[[float, float, float, int], object] | None = None,
        stream: str | _Sink | None = None,
        sensitivities: list[str] = ...,
    ) -> PyResults: ...

class _Sink(Protocol):
    """What a streamed run's rows go to (`linkwork.stream.ParquetSink`)."""

    path: str
    def begin(self, names: list[str]) -> None: ...
    def write(self, time: npt.NDArray[np.float64], values: npt.NDArray[np.float64]) -> None: ...
    def finish(self) -> None: ...

@final
class PyResults:
    @property
    def names(self) -> list[str]: ...
    @property
    def time(self) -> npt.NDArray[np.float64]: ...
    @property
    def values(self) -> npt.NDArray[np.float64]: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def ok(self) -> bool: ...
    @property
    def streamed(self) -> bool: ...
    @property
    def sensitivities(self) -> tuple[list[str], list[str], npt.NDArray[np.float64]] | None: ...
    def write(self, directory: str) -> None: ...

def schema() -> str: ...
def sensitivity_name(column: str, parameter: str) -> str: ...
def quantity(text: str) -> tuple[float, str] | None: ...
def unit(text: str) -> float: ...
AGGREGATIONS: list[str]
BODY_QUANTITIES: list[str]
ENGINE_COLUMNS: list[str]
ERROR_ATTRIBUTES: list[tuple[str, list[tuple[str, str]]]]

def si_unit(text: str) -> str | None: ...
def si_units() -> list[tuple[str, str]]: ...
def _panic_for_tests() -> None: ...

# The exceptions (generated from ERROR_ATTRIBUTES and the classes: `python -m linkwork._generate`).
# Their attributes are set on each instance when the engine raises it; `results` is a `PyResults`
# there, which `linkwork.Model.run` replaces with a `linkwork.Results`.

# generated: exceptions
class LinkworkError(Exception): ...

class ModelError(LinkworkError):
    problems: list[tuple[str, str]]

class AssemblyError(LinkworkError):
    time: float
    joints: list[str]
    row: str
    residual: float
    iterations: int
    hint: str
    results: Any

class SolverError(LinkworkError):
    time: float
    joints: list[str]
    rows: list[str]
    results: Any

class SingularError(SolverError):
    detail: str

class ConvergenceError(SolverError):
    row: str
    residual: float
    iterations: int
    substep: float

class EquilibriumError(ConvergenceError):
    coordinates: list[str]
    index: int | None
    load_fraction: float
    cause: str

class IntegrationError(SolverError):
    step: float
    cause: str

class NonFiniteError(SolverError):
    element: str
    expression: str
    value: float

class AccuracyError(SolverError):
    quantity: str
    value: float
    bound: float
    detail: str

class OutOfMemoryError(SolverError, MemoryError): ...

class FileError(LinkworkError, OSError):
    path: str

class InternalError(LinkworkError): ...
# end generated: exceptions
