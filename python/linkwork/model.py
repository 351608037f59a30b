"""A compiled mechanism: its names, its checks, and its analyses."""

from __future__ import annotations

import numbers
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from tqdm import tqdm

from . import _linkwork, figures
from . import stream as stream_
from .errors import AssemblyError, SolverError, model_error
from .results import Results


class ProgressBar:
    """A tqdm bar on stderr over a run's simulated time: the time reached of the total, steps a
    second and the time left. Shown only after half a second, so short runs print nothing."""

    #: Seconds before the bar shows: a run shorter than this needs no bar.
    DELAY = 0.5

    def __init__(self) -> None:
        self._bar: tqdm[Any] | None = None
        self._start = time.monotonic()

    def update(self, t: float, t_start: float, t_end: float, steps: int) -> None:
        """The run is at time ``t`` of ``[t_start, t_end]`` after ``steps`` steps."""
        if self._bar is None:
            total = max(t_end - t_start, 0.0)
            self._bar = tqdm(
                total=total, unit="s", unit_scale=False, delay=self.DELAY, file=sys.stderr,
                bar_format="{l_bar}{bar}| t = {n:.4g} of {total:.4g} s [{elapsed}<{remaining}{postfix}]",
            )
        rate = steps / max(time.monotonic() - self._start, 1e-9)
        self._bar.set_postfix_str(f"{rate:,.0f} steps/s", refresh=False)
        self._bar.update(max(t - t_start, 0.0) - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


@dataclass(frozen=True)
class Tolerance:
    """A parameter's tolerance (docs/model-format.md, "Tolerances")."""

    value: float
    """The largest deviation from the parameter's value, SI."""
    distribution: str
    """``"normal"`` (the tolerance is three standard deviations) or ``"uniform"`` (over plus or
    minus the tolerance)."""
    sigma: float
    """The standard deviation, SI: ``value / 3`` (normal) or ``value / sqrt(3)`` (uniform)."""


def _parameter_texts(values: Mapping[str, float | str]) -> list[tuple[str, str]]:
    """Parameter values as the engine reads them: a number as its shortest exact text (SI), a
    string as written (a number with a unit, or an expression of earlier parameters)."""
    texts = []
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise TypeError(f"parameter {name}: expected a number or a string such as '300 mm', got {value!r}")
        texts.append((name, value if isinstance(value, str) else repr(float(value))))
    return texts


def _warned(native: _linkwork.PyModel) -> _linkwork.PyModel:
    """``native``, once its warnings about the parameter values given are issued as
    ``UserWarning`` (to the caller of the public function)."""
    for message in native.warnings:
        warnings.warn(message, UserWarning, stacklevel=3)
    return native


class Model:
    """A mechanism read from a model file, compiled and immutable.

    Make one with :func:`linkwork.load` (a file) or :func:`linkwork.from_yaml` (its text).
    """

    __slots__ = ("_native", "path")

    _native: _linkwork.PyModel
    path: str | None
    """The file the model was read from, if any."""

    def __init__(self, *_args: object, **_kwargs: object) -> None:
        raise TypeError("use linkwork.load(path) or linkwork.from_yaml(text) to make a Model")

    @classmethod
    def _wrap(cls, native: _linkwork.PyModel, path: str | None = None) -> Model:
        self = object.__new__(cls)
        self._native = native
        self.path = path
        return self

    @classmethod
    def load(cls, path: str | os.PathLike[str], parameters: Mapping[str, float | str] | None = None) -> Model:
        """Read and compile the model file at ``path`` (same as :func:`linkwork.load`)."""
        native = _linkwork.PyModel.load(os.fspath(path), _parameter_texts(parameters or {}))
        return cls._wrap(_warned(native), path=os.fspath(path))

    @classmethod
    def from_yaml(cls, text: str, parameters: Mapping[str, float | str] | None = None) -> Model:
        """Compile a model from the text of a model file (same as :func:`linkwork.from_yaml`)."""
        return cls._wrap(_warned(_linkwork.PyModel.from_yaml(text, _parameter_texts(parameters or {}))))

    def with_parameters(self, **values: float | str) -> Model:
        """A new model: the same file with ``values`` over its parameters (a number is SI, a
        string may carry a unit: ``model.with_parameters(r=0.12, L="300 mm")``). Parameters
        computed from others follow them; values given before and not named again stay. A bare
        number more than 100 times from the value the file writes with a unit (``m=16`` for
        ``m: 15 mm``) gives a ``UserWarning``."""
        return self._wrap(_warned(self._native.with_parameters(_parameter_texts(values))), path=self.path)

    @property
    def parameters(self) -> dict[str, float]:
        """The parameters' values used, SI, in file order (``parameters:`` with any values
        given over them)."""
        return dict(self._native.parameters)

    @property
    def tolerances(self) -> dict[str, Tolerance]:
        """The tolerance of each parameter the file gives one (``r: 150 mm ± 0.1 mm``), SI, in
        file order; parameters without one are not listed. A value given over the file's keeps
        the file's tolerance."""
        return {name: Tolerance(value, distribution, sigma) for name, value, distribution, sigma in self._native.tolerances}

    @property
    def source(self) -> str:
        """The text of the model file: what ``model.yaml`` in an output folder holds."""
        return self._native.source

    @property
    def name(self) -> str:
        """The model's title (``name:`` in the file)."""
        return self._native.name

    @property
    def bodies(self) -> list[str]:
        """Names of the moving bodies, in file order (ground is not one of them)."""
        return self._native.bodies

    @property
    def joints(self) -> list[str]:
        """Names of the joints, in file order."""
        return self._native.joints

    @property
    def drivers(self) -> list[str]:
        """Names of the drivers, in file order."""
        return self._native.drivers

    @property
    def analyses(self) -> list[str]:
        """Names of the analyses, in file order; :meth:`run` runs the first by default."""
        return self._native.analyses

    def check(self) -> dict[str, Any]:
        """Degrees of freedom, redundant constraints and assembly of the mechanism.

        Returns a dict with ``model``, ``bodies``, ``coordinates``, ``mechanism`` (the joints
        alone, with the coordinates the file marks as given held), ``coordinate_names`` and
        ``analyses`` (a dict by analysis name, in file order, each with its drivers active, its ``kind``, a
        ``warning`` when it cannot run as set up, and an ``error`` instead of the system fields
        when it cannot be assembled). Each system has ``drivers``,
        ``equations``, ``gruebler_dof``, ``rank``, ``dof``, ``redundant`` (a list of
        ``{"element", "equation"}``) and ``assembly`` (``q``, ``qdot``, ``iterations``,
        ``residual``, ``velocity_residual`` and ``change``, the assembled position minus the
        guess, per coordinate in the order ``<body>.x, <body>.y, <body>.phi``).

        Raises :class:`AssemblyError` if the mechanism alone cannot be assembled.
        """
        report: dict[str, Any] = self._native.check()
        # The engine's map arrives sorted by name: the analyses in file order, as the file has them.
        report["analyses"] = {name: report["analyses"][name] for name in self.analyses}
        return report

    def drawing(self) -> dict[str, Any]:
        """The picture of the mechanism: ``bodies`` (each with ``name``, its named ``points`` and
        its ``joint_points``, in its own frame, m) and ``joints`` (each with ``name``, ``type``,
        ``body_i``, ``p``, ``body_j``, ``q`` and its ``shape``: ``pin``, ``slide`` with ``axis``
        and ``offset``, ``rod``, ``gears`` with ``r_i``, ``r_j`` and ``internal``, ``disc`` with
        ``axis`` and ``radius``, or ``held``), ``paths`` (the points whose paths are drawn: the
        file's ``paths:``, else its point measures' points; each with ``name``, ``body`` and
        ``point``) and ``drivers`` (each driver's coordinate: ``name``, ``type``, ``body_i``,
        ``p``, ``body_j``, ``q``)."""
        return self._native.drawing()

    def draw(self) -> Any:
        """The assembled pose of the mechanism alone (its joints, no drivers), with the initial
        guess of the file faded beside it, as a ``plotly`` figure (shown by a notebook)."""
        assembly = self.check()["mechanism"]["assembly"]
        names = assembly_coordinates(self.bodies)
        assembled = dict(zip(names, assembly["q"], strict=True))
        guess = {n: q - dq for (n, q), dq in zip(assembled.items(), assembly["change"], strict=True)}
        return figures.figure(figures.pose_figure(self.drawing(), [("initial guess", guess, 0.3), ("assembled", assembled, 1.0)]))

    def run(
        self,
        analysis: str | None = None,
        *,
        integrator: str | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        t_end: float | None = None,
        step: float | None = None,
        progress: bool | Callable[[float, float, float, int], object] = False,
        stream: str | os.PathLike[str] | None = None,
        sensitivities: Sequence[str] | bool | None = None,
    ) -> Results:
        """Run the analysis called ``analysis`` (default: the first one in the file).

        The keyword arguments change the analysis for this run only: ``integrator`` (``"bdf"``,
        ``"hht"`` or ``"abam"``), the tolerances ``rtol`` and ``atol`` (dynamic analyses), the end
        time ``t_end`` and the output step ``step`` (s). A bad value raises :class:`ModelError`.

        ``progress=True`` shows a progress bar (tqdm, on stderr): simulated time reached of the
        total, steps a second, time left. A callable is called instead, about 20 times a second,
        as ``progress(time, t_start, t_end, steps)``; an exception it raises stops the run and is
        raised.

        ``stream``: a path ending in ``.csv`` or ``.parquet`` that the rows are written to as
        they are computed, so that memory holds a chunk of rows (about 16 MB) rather than the
        run; the file is that of ``results.csv`` (CSV) or the same columns (Parquet, needs
        pyarrow). The results returned then hold no row (:attr:`Results.streamed_to`). After a
        failure the file has every row up to it.

        ``sensitivities``: the parameters (names of the file's ``parameters:``) to differentiate
        every column, summary and peak with respect to, or ``True`` for every parameter (file
        order): exact derivatives at the same output times, SI per SI unit of the parameter
        (:attr:`Results.sensitivities`, :meth:`Results.sensitivity`; docs/sensitivities.md).
        Kinematic analyses have them; a name that is no parameter, or another analysis, raises
        :class:`ModelError` at ``sensitivities``.

        On a solver failure the exception (:class:`SolverError`, :class:`AssemblyError`) has
        ``results``: the :class:`Results` computed before the failure. Ctrl-C stops the run at
        its next step (within 0.2 s) and raises ``KeyboardInterrupt`` with ``results`` too.
        """
        if analysis is None:
            if not self.analyses:
                raise model_error(
                    "analyses",
                    "the model names no analyses; add one, e.g. "
                    "`kinematics: {type: kinematic, drivers: [motor], t_end: 1, step: 0.01}`",
                )
            analysis = self.analyses[0]
        options = {"--rtol": rtol, "--atol": atol, "--t-end": t_end, "--step": step}
        for option, value in options.items():
            # A bool is an int to Python, and True would run as 1.0: refused, as a file refuses it.
            if isinstance(value, bool):
                raise model_error(option, f"expected a number, found {value} (a bool)")
            if value is not None and not isinstance(value, numbers.Real):
                raise model_error(option, f"expected a number, found {value!r} ({type(value).__name__})")
        sink: str | stream_.ParquetSink | None = None
        if stream is not None:
            try:
                sink = stream_.sink(stream)
            except ValueError as error:
                raise model_error("stream", str(error)) from None
        streamed_to = Path(stream) if stream is not None else None
        parameters = self._sensitivities(sensitivities)
        bar = ProgressBar() if progress is True else None
        report = bar.update if bar is not None else progress if callable(progress) else None
        try:
            native = self._native.run(analysis, integrator, rtol, atol, t_end, step, report, sink, parameters)
            return Results(native, self, streamed_to)
        except (SolverError, AssemblyError, KeyboardInterrupt) as error:
            partial = getattr(error, "results", None)
            if isinstance(partial, _linkwork.PyResults):
                error.results = Results(partial, self, streamed_to)  # type: ignore[union-attr]
            raise
        finally:
            if bar is not None:
                bar.close()

    def _sensitivities(self, asked: Sequence[str] | bool | None) -> list[str]:
        """The parameters ``Model.run(sensitivities=asked)`` asks for: ``True`` every one, in file
        order; ``None`` or ``False`` none; else the names given (the engine checks them)."""
        if asked is None or asked is False:
            return []
        if asked is True:
            return list(self.parameters)
        if not isinstance(asked, (list, tuple)) or not all(isinstance(name, str) for name in asked):
            raise model_error(
                "sensitivities", f"expected a list of parameter names or True, found {asked!r} ({type(asked).__name__})"
            )
        return list(asked)

    def __reduce__(self) -> tuple[Callable[[str, list[tuple[str, str]], str | None, str], Model], tuple[object, ...]]:
        """Pickled as its file's text, the parameter values given over it and the folder its
        tables' files are read from, and compiled again where it is unpickled (a Dask worker,
        another process)."""
        return (_compiled, (self.source, self._native.set, self.path, os.fspath(self._native.folder)))

    def __repr__(self) -> str:
        source = f" from {self.path!r}" if self.path else ""
        return (
            f"<linkwork.Model {self.name!r}{source}: {len(self.bodies)} bodies, "
            f"{len(self.joints)} joints, {len(self.drivers)} drivers, analyses {self.analyses}>"
        )


def _compiled(source: str, given: list[tuple[str, str]], path: str | None, folder: str) -> Model:
    """The model of ``source`` with the parameter values ``given``, its tables' files in
    ``folder``: an unpickled Model."""
    return Model._wrap(_linkwork.PyModel.from_yaml(source, given, folder), path=path)


def assembly_coordinates(bodies: list[str]) -> list[str]:
    """The names of the coordinates in the engine's order: ``<body>.x, <body>.y, <body>.phi``."""
    return [f"{b}.{c}" for b in bodies for c in ("x", "y", "phi")]
