"""Native half of the linkwork package (PyO3). Use the `linkwork` package, not this module."""

from typing import Any

import numpy as np

__version__: str

class PyModel:
    @staticmethod
    def load(path: str) -> PyModel: ...
    @staticmethod
    def from_yaml(text: str) -> PyModel: ...
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
    def run(self, analysis: str) -> PyResults: ...

class PyResults:
    @property
    def names(self) -> list[str]: ...
    @property
    def time(self) -> np.ndarray: ...
    @property
    def values(self) -> np.ndarray: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def ok(self) -> bool: ...
    def write(self, directory: str) -> None: ...

def schema() -> str: ...

class LinkworkError(Exception): ...

class ModelError(LinkworkError):
    problems: list[tuple[str, str]]

class AssemblyError(LinkworkError):
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

class FileError(LinkworkError, OSError):
    path: str

class InternalError(LinkworkError): ...
