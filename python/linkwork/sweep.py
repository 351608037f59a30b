"""Sweeps: an analysis run for many values of a model's parameters (a full grid, or a Latin
hypercube sample of ranges), each run reduced to a few outputs; in parallel in the engine
(``linkwork::sweep``, one thread a core, the GIL released) or in chunks on a Dask cluster.

An output is an expression of aggregations of the run's result columns
(``max(slider.x) - min(slider.x)``, ``peak(motor.effort)``, ``at(0.5, crank.phi)``;
docs/python.md, "Sweeps").
"""

from __future__ import annotations

import itertools
import math
import os
import secrets
import sys
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

from . import _linkwork
from .errors import model_error
from .model import Model, ProgressBar, _parameter_texts
from .units import UNKNOWN, Units, system

if TYPE_CHECKING:
    import pandas

STATUS = "status"
"""The column that says how a variant ended: ``ok``, or ``<ErrorClass>: <message>``."""

NOT_RUN = "KeyboardInterrupt: interrupted before it ran"
"""The status of a variant of an interrupted sweep on a cluster that had not run."""

CHUNKS_PER_THREAD = 4
"""On a cluster, the variants go out in this many chunks per worker thread: enough that a
thread which drew cheap variants takes another chunk while the others finish, few enough that
the scheduler's cost per task (about a millisecond) stays small beside a chunk's runs."""

MAX_VARIANTS = 1_000_000
"""The most variants a sweep may have (a grid's combinations, a sample's points). A variant
compiles and runs the model, a millisecond at the very least, so a million is a quarter of an
hour on the cores of a large machine and the table a few hundred MB: past it a typo (a COUNT of
1000000000) would fill the memory with the variants' values before the first one ran."""

Row = tuple[str, "list[float] | None"]


def check_count(count: int, what: str) -> None:
    """``ValueError`` naming ``what`` (``--grid``, ``sample``) when ``count`` variants are more
    than :data:`MAX_VARIANTS`: checked before any is made."""
    if count > MAX_VARIANTS:
        raise ValueError(f"{what}: {count} variants; a sweep may have at most {MAX_VARIANTS:,} (run it in parts)")


def name_problem(name: str, parameters: Iterable[str]) -> str | None:
    """What is wrong with an output called ``name`` among a model's ``parameters``, if anything: a
    sweep's table has a column of each parameter swept and ``status``, and an output's column
    of the same name would overwrite it (the parameter column held the outputs)."""
    if name == STATUS:
        return f"'{name}' is already the column of each variant's status; choose another name"
    if name in parameters:
        return f"'{name}' is already the parameter parameters.{name} (a column of the table when swept); choose another name"
    return None


def workers_to_use(workers: int | None, what: str = "workers") -> int | None:
    """``workers`` threads, at most this process's cores (with a warning above: more threads than
    cores only contend, and 100,000 of them ran for minutes); ``ValueError`` below 1."""
    if workers is None:
        return None
    if workers < 1:
        raise ValueError(f"{what}: expected a count of threads of at least 1, got {workers}")
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if workers > cores:
        warnings.warn(f"{what}: {workers} threads asked for, this machine has {cores} cores; using {cores}", stacklevel=3)
        return cores
    return workers


def sweep(
    model: Model | str | os.PathLike[str],
    analysis: str,
    grid: Mapping[str, Sequence[float | str]] | None = None,
    outputs: Mapping[str, str] | None = None,
    *,
    sample: int | None = None,
    ranges: Mapping[str, tuple[float | str, float | str]] | None = None,
    seed: int | None = None,
    workers: int | None = None,
    client: Any = None,
    progress: bool | Callable[[int, int], object] = False,
    units: str = "si",
    gradients: bool | Sequence[str] = False,
    points: Mapping[str, Sequence[float | str]] | None = None,
) -> pandas.DataFrame:
    """Run ``analysis`` of ``model`` for many values of its parameters and reduce each run to
    ``outputs`` (a name to an expression).

    The variants are either every combination of the values in ``grid`` (a parameter's name to
    its values: numbers in SI, or strings with units), in the order of ``itertools.product``, or
    ``sample`` points of a Latin hypercube over ``ranges`` (a name to ``(low, high)``, numbers in
    SI or both strings with units, ``("12 mm", "18 mm")``) drawn with ``seed`` (a fresh one when
    ``None``; the table's ``attrs["seed"]`` says which), or given ``points`` (a name to its
    values, all of one length: the k-th variant takes the k-th value of each; what
    :func:`linkwork.tolerance` draws).

    They run on ``workers`` threads of this machine (default: every core), or, given a Dask
    ``client`` (``distributed.Client``), in chunks on its workers. ``progress=True`` shows a
    bar of the variants finished (tqdm, on stderr); a callable is called instead as
    ``progress(finished, total)``.

    One row per variant: the parameters' values, ``status``, and each output, missing
    (``<NA>``) where the variant failed; ``attrs["units"]`` gives each column's unit and
    ``attrs["unit_system"]`` the ``units`` asked for. With ``units="si"`` the parameters are SI;
    with ``units="display"`` a parameter written with a unit of a result quantity (a length, an
    angle ...) is in the unit the model's ``display:`` section shows that quantity in. Outputs
    are ``SI`` either way, as computed from SI columns. Both attrs are kept in a Parquet file
    (``to_parquet``). A failed variant is a row, not the end of the sweep.
    Ctrl-C stops the sweep (within 0.2 s on this machine) and raises ``KeyboardInterrupt`` with
    ``table``: every row, those not finished with a ``KeyboardInterrupt: ...`` status. An
    exception raised by ``progress`` stops it the same way and is raised with ``table``.

    ``gradients=True`` (every parameter of the model) or a list of parameters adds, after the
    outputs, each output's derivative with respect to each of them at every variant, a column
    ``d(<output>)/d(<parameter>)`` (SI per SI unit of the parameter): each run is asked for its
    sensitivities and the output differentiated as a summary is (docs/sensitivities.md,
    "Sweeps with gradients"). An output may also be a model's summary by name (``stroke``).

    Refused before any variant is made: more than :data:`MAX_VARIANTS` variants, or ``workers``
    below 1 (``ValueError``); an output named ``status`` or as a parameter of the model
    (``ModelError`` at ``outputs.<name>``). More ``workers`` than cores use the cores, with a
    ``UserWarning``.
    """
    try:
        import pandas as pd
    except ImportError as error:  # pragma: no cover - the test extra installs it
        raise ImportError("sweep() needs pandas: pip install 'linkwork[sweep]'") from error
    display = system(units)
    if not isinstance(model, Model):
        model = Model.load(model)
    attrs: dict[str, object] = {}
    if sum((grid is not None, sample is not None or ranges is not None, points is not None)) > 1:
        raise ValueError("give either grid, or sample with ranges, or points, not more than one")
    output_list = list((outputs or {}).items())
    for name, _ in output_list:
        problem = name_problem(name, model.parameters)
        if problem is not None:
            raise model_error(f"outputs.{name}", problem)
    workers = workers_to_use(workers)
    if grid is not None:
        names = list(grid)
        check_count(math.prod(len(grid[name]) for name in names), "grid")
        combinations: list[tuple[float | str, ...]] = list(itertools.product(*(grid[name] for name in names)))
    elif sample is not None and ranges is not None:
        attrs["seed"] = seed = secrets.randbits(63) if seed is None else seed
        intervals = {name: interval(name, low, high) for name, (low, high) in ranges.items()}
        columns = latin_hypercube({name: (low, high) for name, (low, high, _) in intervals.items()}, sample, seed)
        names = list(columns)
        # Drawn in the unit the range is written in, and given in it, so the engine checks it.
        texts = {n: [v if intervals[n][2] is None else f"{v!r} {intervals[n][2]}" for v in vs] for n, vs in columns.items()}
        combinations = list(zip(*texts.values())) if names else [() for _ in range(sample)]
    elif points is not None:
        names = list(points)
        if len({len(values) for values in points.values()}) > 1:
            raise ValueError("points: every parameter needs as many values as the others")
        check_count(len(next(iter(points.values()), ())), "points")
        combinations = list(zip(*points.values()))
    else:
        raise ValueError("give grid (values of each parameter), sample (a count) with ranges, or points")
    variants = [_parameter_texts(dict(zip(names, values))) for values in combinations]
    # The analysis and the outputs checked here, before any variant runs (ModelError).
    model._native.sweep(analysis, [], output_list, 1)
    wrt = gradient_parameters(model, analysis, gradients)

    bar = _VariantBar(len(variants)) if progress is True else None
    report = bar.update if bar is not None else progress if callable(progress) else None

    # The SI value the engine reads of each value: a bare number is itself; a value with a unit
    # is converted. The first value of each parameter read once here: a wrong dimension is a
    # ModelError, and a bare number far from the file's value a UserWarning, before any run.
    for k, name in enumerate(names):
        first = next((c[k] for c in combinations if isinstance(c[k], str)), combinations[0][k] if combinations else None)
        if first is not None:
            model.with_parameters(**{name: first})
    si = {(name, v): _si(model, name, v) for k, name in enumerate(names) for v in {c[k] for c in combinations}}
    shown = Units.of_parameters(model, names, display=display)
    attrs["unit_system"] = units
    derivative_names = [_linkwork.sensitivity_name(o, p) for o, _ in output_list for p in wrt]
    attrs["units"] = shown.column_units(names) | dict.fromkeys([*dict(output_list), *derivative_names], UNKNOWN)

    def table(rows: list[Row]) -> pandas.DataFrame:
        data: dict[str, object] = {}
        for k, name in enumerate(names):
            data[name] = shown.shown(name, [si[name, values[k]] for values in combinations])
        data[STATUS] = [status for status, _ in rows]
        for j, name in enumerate([*dict(output_list), *derivative_names]):
            data[name] = pd.array([None if values is None else values[j] for _, values in rows], dtype="Float64")
        frame = pd.DataFrame(data)
        frame.attrs.update(attrs)
        return frame

    try:
        if client is None:
            total = len(variants)
            native = None if report is None else (lambda finished: report(finished, total))
            rows = model._native.sweep(analysis, variants, output_list, workers, native, wrt)
        else:
            rows = _on_cluster(client, model, analysis, variants, output_list, report, wrt)
    except BaseException as stopped:  # Ctrl-C, or an exception from `progress`
        partial = getattr(stopped, "rows", None)
        if isinstance(partial, list):
            stopped.table = table(partial)  # type: ignore[attr-defined]
        raise
    finally:
        if bar is not None:
            bar.close()
    return table(rows)


def _on_cluster(
    client: Any,
    model: Model,
    analysis: str,
    variants: list[list[tuple[str, str]]],
    outputs: list[tuple[str, str]],
    report: Callable[[int, int], object] | None,
    gradients: list[str],
) -> list[Row]:
    """The rows of ``variants`` run in chunks on the Dask ``client``'s workers, in order."""
    from distributed import as_completed

    threads = max(sum(client.nthreads().values()), 1)
    size = max(math.ceil(len(variants) / (CHUNKS_PER_THREAD * threads)), 1)
    starts = range(0, len(variants), size)
    # The model goes to each worker once (pickled as its text, compiled there).
    [remote] = client.scatter([model], broadcast=True)
    futures = {
        client.submit(_chunk, remote, analysis, variants[s : s + size], outputs, gradients, pure=False): s for s in starts
    }
    rows: list[Row | None] = [None] * len(variants)
    finished = 0
    try:
        for future in as_completed(futures):
            start = futures[future]
            chunk: list[Row] = future.result()
            rows[start : start + len(chunk)] = chunk
            finished += len(chunk)
            if report is not None:
                report(finished, len(variants))
    except KeyboardInterrupt as interrupt:
        client.cancel(list(futures))
        interrupt.rows = [(NOT_RUN, None) if row is None else row for row in rows]  # type: ignore[attr-defined]
        raise
    return [row for row in rows if row is not None]


def _chunk(
    model: Model, analysis: str, variants: list[list[tuple[str, str]]], outputs: list[tuple[str, str]], gradients: list[str]
) -> list[Row]:
    """One chunk of a sweep on a Dask worker: its variants on one thread (the worker's other
    threads run other chunks)."""
    return model._native.sweep(analysis, variants, outputs, 1, None, gradients)


def gradient_parameters(model: Model, analysis: str, gradients: bool | Sequence[str]) -> list[str]:
    """The parameters a sweep's outputs are differentiated with respect to: none (``False``),
    every one of the model (``True``), or those named. Checked by one nominal run with those
    sensitivities, before any variant runs: a name the model does not define, or an analysis
    whose type has no sensitivities, is the ``ModelError`` of that run."""
    if gradients is False:
        return []
    wrt = list(model.parameters) if gradients is True else list(gradients)
    if not wrt:
        raise model_error("gradients", "the model has no parameters to differentiate with respect to")
    model.run(analysis, sensitivities=wrt)
    return wrt


class _VariantBar:
    """A tqdm bar on stderr over a sweep's variants, shown after half a second as a run's."""

    def __init__(self, total: int) -> None:
        self._bar: tqdm[Any] = tqdm(total=total, unit="variant", delay=ProgressBar.DELAY, file=sys.stderr)

    def update(self, finished: int, total: int) -> None:
        self._bar.update(finished - self._bar.n)

    def close(self) -> None:
        self._bar.close()


def _si(model: Model, name: str, value: float | str) -> float:
    """A grid value in SI, as the engine reads it: a number with a unit converted, an
    expression of other parameters evaluated by the engine."""
    if isinstance(value, str):
        read = _linkwork.quantity(value)
        return read[0] if read is not None else model.with_parameters(**{name: value}).parameters[name]
    return float(value)


def _end(text: str) -> tuple[float, str | None]:
    """One end of a ``--grid`` or ``--range``: the number as written and its unit (``None`` for a
    bare number, SI). ``ValueError`` for anything else."""
    try:
        read = _linkwork.quantity(text)
    except ValueError as error:
        raise ValueError(f"'{text.strip()}': {error}") from None
    if read is None:
        return float(text), None
    unit = read[1]
    return float(text.strip()[: -len(unit)]), unit


def interval(name: str, low: float | str, high: float | str) -> tuple[float, float, str | None]:
    """The ends of a grid's or a range's interval as numbers in one unit, and that unit (``None``:
    SI numbers): ``("12 mm", "1.8 cm")`` is ``(12, 18, "mm")``. A unit on one end only is
    refused (a bare number is SI, so ``12:18 mm`` would run from 12 m)."""
    (a, unit_a), (b, unit_b) = (_end(v) if isinstance(v, str) else (float(v), None) for v in (low, high))
    if (unit_a is None) != (unit_b is None):
        raise ValueError(f"{name}: a unit on one end only; write it on both, such as {name}=12 mm:18 mm")
    if unit_a is not None and unit_b is not None and unit_b != unit_a:
        b = b * _linkwork.unit(unit_b) / _linkwork.unit(unit_a)
    return a, b, unit_a


def latin_hypercube(ranges: Mapping[str, tuple[float, float]], count: int, seed: int) -> dict[str, list[float]]:
    """``count`` points of a Latin hypercube over ``ranges`` (a name to ``(low, high)``): each
    range cut into ``count`` equal strata with one point in each, at a uniformly random place in
    it, and the strata of the parameters paired by independent random permutations (McKay,
    Beckman and Conover, 1979). numpy's default generator (PCG64) seeded with ``seed``: the same
    seed gives the same points."""
    if count < 1:
        raise ValueError(f"sample: expected a count of at least 1, got {count}")
    check_count(count, "sample")
    for name, (low, high) in ranges.items():
        _check_range(name, low, high)
    rng = np.random.default_rng(seed)
    points = {}
    for name, (low, high) in ranges.items():
        u = (rng.permutation(count) + rng.random(count)) / count
        points[name] = [float(v) for v in low + u * (high - low)]
    return points


def grid_values(text: str) -> tuple[str, list[float | str]]:
    """``NAME=START:STOP:COUNT`` as the name and ``COUNT`` evenly spaced values from ``START`` to
    ``STOP`` (both included): numbers (SI), or, where the ends carry a unit
    (``m=12 mm:18 mm:7``), numbers with that unit."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or not name.strip() or len(parts) != 3:
            raise ValueError
        count = int(parts[2])
        if count < 1:
            raise ValueError
        start, stop, unit = interval(name.strip(), parts[0], parts[1])
    except ValueError as error:
        why = f" ({error})" if str(error) else ""
        raise ValueError(
            f"expected NAME=START:STOP:COUNT (COUNT >= 1), such as r=0.05:0.15:5 or r=50 mm:150 mm:5, got '{text}'{why}"
        ) from None
    check_count(count, f"{name.strip()}: COUNT")
    # START + k (STOP - START) / (COUNT - 1): the ends are exactly START and STOP.
    values = [start + k * (stop - start) / (count - 1) if 0 < k < count - 1 else (start, stop)[k > 0] for k in range(count)]
    return name.strip(), [v if unit is None else f"{v!r} {unit}" for v in values]


def range_values(text: str) -> tuple[str, tuple[float | str, float | str]]:
    """``NAME=LOW:HIGH`` as the name and ``(LOW, HIGH)``: numbers (SI), or both with a unit."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or not name.strip() or len(parts) != 2:
            raise ValueError
        low, high, unit = interval(name.strip(), parts[0], parts[1])
    except ValueError as error:
        why = f" ({error})" if str(error) else ""
        raise ValueError(f"expected NAME=LOW:HIGH, such as r=0.05:0.15 or r=50 mm:150 mm, got '{text}'{why}") from None
    _check_range(name.strip(), low, high)
    if unit is None:
        return name.strip(), (low, high)
    return name.strip(), (f"{low!r} {unit}", f"{high!r} {unit}")


def _check_range(name: str, low: float, high: float) -> None:
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise ValueError(f"range {name}: expected finite LOW <= HIGH, got {low}:{high}")
