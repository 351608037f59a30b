"""The report of a run folder: the run that ``linkwork run`` wrote into a folder, read back from
its files, for ``linkwork report DIR`` to draw its page again (:mod:`linkwork.page`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from . import stream
from .errors import FileError
from .figures import Run
from .model import Model
from .summary import Summary
from .units import Units, to_si


def from_folder(folder: Any) -> Run:
    """The run whose files ``linkwork run`` wrote into ``folder``: ``model.yaml`` (for the
    drawing), ``results.csv`` (or ``results.parquet`` of a run streamed to Parquet) and
    ``summary.json``. A missing or unreadable file is a :class:`linkwork.FileError` naming it.
    A table written in other units than SI (``--units display``) is read back to SI by the
    units ``summary.json`` gives each column (``units``); one whose units it does not give is a
    :class:`linkwork.FileError` too."""
    folder = Path(folder)
    table = folder / "results.csv"
    if not table.exists() and (folder / "results.parquet").exists():
        table = folder / "results.parquet"
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        time, columns = stream.read(table)
    except (OSError, ValueError) as error:
        raise FileError(f"{folder}: not a results folder of `linkwork run`: {error}") from error
    # A folder without units (written before they were recorded) is SI.
    if summary.get("unit_system", "si") != "si":
        written: dict[str, str] = summary.get("units") or {}
        missing = [name for name in ["time", *columns] if name not in written]
        if missing:
            raise FileError(
                f"{folder / 'summary.json'}: units: no unit for the column(s) {', '.join(missing)} of "
                f"{table.name}, written in {summary['unit_system']!r} units: cannot read them back to SI"
            )
        converted = {}
        for name, values in {"time": time, **columns}.items():
            try:
                converted[name] = to_si(written[name], values)
            except ValueError as error:
                raise FileError(f"{folder / 'summary.json'}: units.{name}: {error}") from error
        time = converted.pop("time")
        columns = converted
    # The parameters the run used (SI, given over the file's by --set or with_parameters).
    model = Model.load(folder / "model.yaml", summary.get("parameters") or None)
    tolerances = {name: t.value for name, t in model.tolerances.items()}
    return Run(model.drawing(), time, columns, Summary(summary), units=Units.of(model, columns), tolerances=tolerances)
