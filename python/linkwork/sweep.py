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
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

from .model import Model, ProgressBar, _parameter_texts

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

Row = tuple[str, "list[float] | None"]


def sweep(
    model: Model | str | os.PathLike[str],
    analysis: str,
    grid: Mapping[str, Sequence[float | str]] | None = None,
    outputs: Mapping[str, str] | None = None,
    *,
    sample: int | None = None,
    ranges: Mapping[str, tuple[float, float]] | None = None,
    seed: int | None = None,
    workers: int | None = None,
    client: Any = None,
    progress: bool | Callable[[int, int], object] = False,
) -> pandas.DataFrame:
    """Run ``analysis`` of ``model`` for many values of its parameters and reduce each run to
    ``outputs`` (a name to an expression).

    The variants are either every combination of the values in ``grid`` (a parameter's name to
    its values: numbers in SI, or strings with units), in the order of ``itertools.product``, or
    ``sample`` points of a Latin hypercube over ``ranges`` (a name to ``(low, high)``, SI) drawn
    with ``seed`` (a fresh one when ``None``; the table's ``attrs["seed"]`` says which).

    They run on ``workers`` threads of this machine (default: every core), or, given a Dask
    ``client`` (``distributed.Client``), in chunks on its workers. ``progress=True`` shows a
    bar of the variants finished (tqdm, on stderr); a callable is called instead as
    ``progress(finished, total)``.

    One row per variant: the parameters' values (SI), ``status``, and each output, missing
    (``<NA>``) where the variant failed. A failed variant is a row, not the end of the sweep.
    Ctrl-C stops the sweep (within 0.2 s on this machine) and raises ``KeyboardInterrupt`` with
    ``table``: every row, those not finished with a ``KeyboardInterrupt: ...`` status. An
    exception raised by ``progress`` stops it the same way and is raised with ``table``.
    """
    try:
        import pandas as pd
    except ImportError as error:  # pragma: no cover - the test extra installs it
        raise ImportError("sweep() needs pandas: pip install 'linkwork[sweep]'") from error
    if not isinstance(model, Model):
        model = Model.load(model)
    attrs: dict[str, int] = {}
    if grid is not None and (sample is not None or ranges is not None):
        raise ValueError("give either grid, or sample with ranges, not both")
    if grid is not None:
        names = list(grid)
        combinations: list[tuple[float | str, ...]] = list(itertools.product(*(grid[name] for name in names)))
    elif sample is not None and ranges is not None:
        attrs["seed"] = seed = secrets.randbits(63) if seed is None else seed
        columns = latin_hypercube(ranges, sample, seed)
        names = list(columns)
        combinations = list(zip(*columns.values())) if names else [() for _ in range(sample)]
    else:
        raise ValueError("give grid (values of each parameter), or sample (a count) with ranges")
    variants = [_parameter_texts(dict(zip(names, values))) for values in combinations]
    output_list = list((outputs or {}).items())
    # The analysis and the outputs checked here, before any variant runs (ModelError).
    model._native.sweep(analysis, [], output_list, 1)

    bar = _VariantBar(len(variants)) if progress is True else None
    report = bar.update if bar is not None else progress if callable(progress) else None

    # The SI value the engine reads of each grid value: a bare number is itself; a value with a
    # unit is converted, once for each distinct one (it compiles the model).
    si = {(name, v): _si(model, name, v) for k, name in enumerate(names) for v in {c[k] for c in combinations}}

    def table(rows: list[Row]) -> pandas.DataFrame:
        data: dict[str, object] = {}
        for k, name in enumerate(names):
            data[name] = [si[name, values[k]] for values in combinations]
        data[STATUS] = [status for status, _ in rows]
        for j, (name, _) in enumerate(output_list):
            data[name] = pd.array([None if values is None else values[j] for _, values in rows], dtype="Float64")
        frame = pd.DataFrame(data)
        frame.attrs.update(attrs)
        return frame

    try:
        if client is None:
            total = len(variants)
            native = None if report is None else (lambda finished: report(finished, total))
            rows = model._native.sweep(analysis, variants, output_list, workers, native)
        else:
            rows = _on_cluster(client, model, analysis, variants, output_list, report)
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
) -> list[Row]:
    """The rows of ``variants`` run in chunks on the Dask ``client``'s workers, in order."""
    from distributed import as_completed

    threads = max(sum(client.nthreads().values()), 1)
    size = max(math.ceil(len(variants) / (CHUNKS_PER_THREAD * threads)), 1)
    starts = range(0, len(variants), size)
    # The model goes to each worker once (pickled as its text, compiled there).
    [remote] = client.scatter([model], broadcast=True)
    futures = {client.submit(_chunk, remote, analysis, variants[s : s + size], outputs, pure=False): s for s in starts}
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


def _chunk(model: Model, analysis: str, variants: list[list[tuple[str, str]]], outputs: list[tuple[str, str]]) -> list[Row]:
    """One chunk of a sweep on a Dask worker: its variants on one thread (the worker's other
    threads run other chunks)."""
    return model._native.sweep(analysis, variants, outputs, 1)


class _VariantBar:
    """A tqdm bar on stderr over a sweep's variants, shown after half a second as a run's."""

    def __init__(self, total: int) -> None:
        self._bar: tqdm[Any] = tqdm(total=total, unit="variant", delay=ProgressBar.DELAY, file=sys.stderr)

    def update(self, finished: int, total: int) -> None:
        self._bar.update(finished - self._bar.n)

    def close(self) -> None:
        self._bar.close()


def _si(model: Model, name: str, value: float | str) -> float:
    """A grid value in SI, as the engine reads it."""
    if isinstance(value, str):
        return model.with_parameters(**{name: value}).parameters[name]
    return float(value)


def latin_hypercube(ranges: Mapping[str, tuple[float, float]], count: int, seed: int) -> dict[str, list[float]]:
    """``count`` points of a Latin hypercube over ``ranges`` (a name to ``(low, high)``): each
    range cut into ``count`` equal strata with one point in each, at a uniformly random place in
    it, and the strata of the parameters paired by independent random permutations (McKay,
    Beckman and Conover, 1979). numpy's default generator (PCG64) seeded with ``seed``: the same
    seed gives the same points."""
    if count < 1:
        raise ValueError(f"sample: expected a count of at least 1, got {count}")
    for name, (low, high) in ranges.items():
        _check_range(name, low, high)
    rng = np.random.default_rng(seed)
    points = {}
    for name, (low, high) in ranges.items():
        u = (rng.permutation(count) + rng.random(count)) / count
        points[name] = [float(v) for v in low + u * (high - low)]
    return points


def grid_values(text: str) -> tuple[str, list[float]]:
    """``NAME=START:STOP:COUNT`` as the name and ``COUNT`` evenly spaced values from ``START`` to
    ``STOP`` (both included)."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or not name.strip() or len(parts) != 3:
            raise ValueError
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
        if count < 1:
            raise ValueError
    except ValueError:
        raise ValueError(f"expected NAME=START:STOP:COUNT (COUNT >= 1), such as r=0.05:0.15:5, got '{text}'") from None
    if count == 1:
        return name.strip(), [start]
    # START + k (STOP - START) / (COUNT - 1): the ends are exactly START and STOP.
    return name.strip(), [start + k * (stop - start) / (count - 1) if k < count - 1 else stop for k in range(count)]


def range_values(text: str) -> tuple[str, tuple[float, float]]:
    """``NAME=LOW:HIGH`` as the name and ``(LOW, HIGH)``."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or not name.strip() or len(parts) != 2:
            raise ValueError
        low, high = float(parts[0]), float(parts[1])
    except ValueError:
        raise ValueError(f"expected NAME=LOW:HIGH, such as r=0.05:0.15, got '{text}'") from None
    _check_range(name.strip(), low, high)
    return name.strip(), (low, high)


def _check_range(name: str, low: float, high: float) -> None:
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise ValueError(f"range {name}: expected finite LOW <= HIGH, got {low}:{high}")
