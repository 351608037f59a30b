"""Sweeps: an analysis run for every combination of parameter values, each run reduced to a few
outputs, in parallel in the engine (``linkwork::sweep``, one thread a core, the GIL released).

An output is an expression of aggregations of the run's result columns
(``max(slider.x) - min(slider.x)``, ``peak(motor.effort)``, ``at(0.5, crank.phi)``;
docs/python.md, "Sweeps").
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from .model import Model, _parameter_texts

if TYPE_CHECKING:
    import pandas

STATUS = "status"
"""The column that says how a variant ended: ``ok``, or ``<ErrorClass>: <message>``."""


def sweep(
    model: Model | str | os.PathLike[str],
    analysis: str,
    grid: Mapping[str, Sequence[float | str]],
    outputs: Mapping[str, str],
    workers: int | None = None,
) -> pandas.DataFrame:
    """Run ``analysis`` of ``model`` for every combination of the values in ``grid`` (a parameter's
    name to its values: numbers in SI, or strings with units) and reduce each run to ``outputs`` (a
    name to an expression). ``workers`` threads (default: every core).

    One row per variant, in the order of ``itertools.product`` over ``grid``: the parameters'
    values (SI), ``status``, and each output, missing (``<NA>``) where the variant failed. A
    failed variant is a row, not the end of the sweep.
    """
    try:
        import pandas as pd
    except ImportError as error:  # pragma: no cover - the test extra installs it
        raise ImportError("sweep() needs pandas: pip install 'linkwork[sweep]'") from error
    if not isinstance(model, Model):
        model = Model.load(model)
    names = list(grid)
    combinations = list(itertools.product(*(grid[name] for name in names)))
    variants = [_parameter_texts(dict(zip(names, values))) for values in combinations]
    rows = model._native.sweep(analysis, variants, list(outputs.items()), workers)
    table: dict[str, object] = {}
    for k, name in enumerate(names):
        # The SI value the engine read: a bare number is itself; a value with a unit, converted.
        table[name] = [_si(model, name, values[k]) for values in combinations]
    table[STATUS] = [status for status, _ in rows]
    for j, name in enumerate(outputs):
        table[name] = pd.array([None if values is None else values[j] for _, values in rows], dtype="Float64")
    return pd.DataFrame(table)


def _si(model: Model, name: str, value: float | str) -> float:
    """A grid value in SI, as the engine reads it."""
    if isinstance(value, str):
        return model.with_parameters(**{name: value}).parameters[name]
    return float(value)


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
