"""Results of one analysis: time series as numpy arrays, a data frame, and the files."""

from __future__ import annotations

import dataclasses
import difflib
import json
import os
import shutil
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _linkwork, figures, folder, page, stream
from .figures import Run, _Poses
from .summary import Summary
from .units import Units, system

if TYPE_CHECKING:
    import pandas

    # Only named in annotations: a model makes its results, not the other way round.
    from .model import Model


class Results:
    """Output of one analysis, complete or up to a failure.

    ``results["rocker.phi"]`` is one column (a read-only numpy array, one value per output time);
    the columns are named ``<body>.x, .y, .phi, .vx, .vy, .omega, .ax, .ay, .alpha`` per body,
    in SI units, angles unwrapped; a dynamic analysis adds ``<joint>.fx, .fy, .torque``,
    ``<driver>.effort``, ``kinetic_energy``, ``potential_energy``, ``nonconservative_work``,
    ``position_residual`` and ``velocity_residual``; an inverse analysis the reactions, efforts,
    ``kinetic_energy``, ``potential_energy``, ``driver_power`` and ``applied_power``; a static
    analysis the reactions, efforts and ``potential_energy``; measures come last, by name.
    ``results["time"]`` is the output times; iterating gives the names, ``"time"`` first. A modes analysis has one row (the state it
    linearised about) and its modes in :attr:`modes`.
    """

    __slots__ = ("_columns", "_index", "_native", "_time", "_values", "model", "streamed_to")

    model: Model
    """The model that was run."""

    streamed_to: Path | None
    """The file the rows went to as they were computed (``Model.run(stream=...)``), else
    ``None``. A streamed run's results hold no row: :attr:`time` and :attr:`values` are empty,
    ``summary.output_points`` counts the rows in the file, and :func:`linkwork.stream.read`
    reads them back."""

    def __init__(self, native: _linkwork.PyResults, model: Model, streamed_to: Path | None = None) -> None:
        self._native = native
        self.model = model
        self.streamed_to = streamed_to if native.streamed else None
        self._columns: list[str] = native.names
        self._index = {name: k for k, name in enumerate(self._columns)}
        # Copied out of the engine once; read-only so that every view stays true to the run.
        self._time: np.ndarray = native.time
        self._values: np.ndarray = native.values
        self._time.flags.writeable = False
        self._values.flags.writeable = False

    @property
    def time(self) -> np.ndarray:
        """(rows) output times, s."""
        return self._time

    @property
    def columns(self) -> list[str]:
        """Names of the columns after ``time``, in the order of ``results.csv``."""
        return list(self._columns)

    @property
    def values(self) -> np.ndarray:
        """(rows x columns) every column but ``time``, in the order of :attr:`columns`."""
        return self._values

    @property
    def summary(self) -> Summary:
        """What ``summary.json`` says, as a dict whose keys are also attributes (:class:`Summary`):
        sizes, solver statistics, ``status`` and any error, and the units of the columns (SI)."""
        return Summary(self._native.summary | self._units_keys(Units.of(self.model, self._columns, display=False), "si"))

    def _units_keys(self, units: Units, system: str) -> dict[str, Any]:
        """``summary.json``'s ``unit_system`` and ``units`` for the columns written in ``units``."""
        return {"unit_system": system, "units": units.column_units(self)}

    @property
    def ok(self) -> bool:
        """True when the analysis reached its end time."""
        return self._native.ok

    @property
    def modes(self) -> list[dict[str, Any]]:
        """The modes of a modes analysis (empty for other analyses): the unstable ones first, fastest
        growing first, then the others, lowest frequency first. Each a dict with ``kind``
        (``"vibration"``, ``"decay"``, ``"neutral"``, or unstable: ``"divergence"``, ``"flutter"``),
        ``frequency`` (undamped natural frequency, Hz; ``None`` for an unstable mode),
        ``damped_frequency`` (Hz), ``damping_ratio`` (``None`` for a neutral or unstable mode),
        ``growth_rate`` (``Re s``, 1/s, of an unstable mode: it grows as ``exp(rate t)``; ``None``
        otherwise), ``eigenvalue`` (``[re, im]``, 1/s) and ``shape`` (``{"<body>.x": ...}``, the
        largest component 1). ``summary.stable`` is false when any mode is unstable."""
        return self.summary.modes or []

    @property
    def summaries(self) -> dict[str, float]:
        """The model's summaries (its ``summaries:`` section, or :meth:`Mechanism.summary`) by name
        (in alphabetical order, as ``summary.json`` writes its keys): whole-run quantities such as ``integral(pump_power) / integral(motor_power)``,
        each a finite number (docs/model-format.md, "Summaries"). Empty when the model has none, or
        the analysis' output spans no time (``modes``; ``static`` at one time). A run that fails
        has none: its error's ``results`` hold the rows computed, not their summaries."""
        return self.summary.summaries or {}

    def __getitem__(self, name: str) -> np.ndarray:
        """The column called ``name`` (``"time"`` included), as a read-only numpy array. A name
        that is no column raises a :class:`KeyError` naming the closest columns."""
        if name == "time":
            return self._time
        try:
            return self._values[:, self._index[name]]
        except KeyError:
            raise KeyError(_unknown("column", name, ["time", *self._columns])) from None

    def __contains__(self, name: object) -> bool:
        return name == "time" or name in self._index

    def __iter__(self) -> Iterator[str]:
        """The column names, ``"time"`` first and then :attr:`columns`: the header of ``results.csv``."""
        return iter(["time", *self._columns])

    def __len__(self) -> int:
        """Number of output points held (none for a streamed run: ``summary.output_points``
        counts the rows in its file)."""
        return len(self._time)

    def reaction(self, joint: str, frame: str = "global") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(fx, fy, torque)`` of ``joint`` (dynamic, inverse and static analyses): the force it exerts on its first
        body and the moment about the joint's point on that body. ``frame="global"`` gives the
        columns ``<joint>.fx``, ``.fy``; ``frame="body"`` resolves the force in the first body's
        frame (rotated by ``-phi`` of that body; ground's frame is the global one).
        """
        if frame not in ("global", "body"):
            raise ValueError(f"frame must be 'global' or 'body', not {frame!r}")
        fx, fy, torque = (self[f"{joint}.{q}"] for q in ("fx", "fy", "torque"))
        if frame == "global":
            return fx, fy, torque
        body = (self.summary.reaction_bodies or {}).get(joint)
        if body is None or body == "ground":
            return fx, fy, torque
        phi = self[f"{body}.phi"]
        c, s = np.cos(phi), np.sin(phi)
        return c * fx + s * fy, -s * fx + c * fy, torque

    def to_pandas(self) -> pandas.DataFrame:
        """A DataFrame indexed by ``time``, one column per quantity (needs pandas:
        ``pip install linkwork[pandas]``). ``.reset_index()`` gives the layout of ``results.csv``."""
        pd = _pandas("to_pandas()")
        index = pd.Index(self._time.copy(), name="time")
        table: pandas.DataFrame = pd.DataFrame(self._values.copy(), index=index, columns=list(self._columns))
        return table

    @property
    def sensitivities(self) -> pandas.DataFrame | None:
        """The derivatives of the columns with respect to the parameters the run was asked for
        (``Model.run(..., sensitivities=...)``), as ``sensitivities.csv`` holds them: ``time``,
        then ``d(<column>)/d(<parameter>)`` for each parameter in the order asked and each column
        that has derivatives in the order of :attr:`columns`, at the output times (fixed: a
        derivative is taken on the same times), SI per SI unit of the parameter (needs pandas).
        ``None`` when the run asked for none. :meth:`sensitivity` gives one, in display units
        too, and the summaries'."""
        native = self._native.sensitivities
        if native is None:
            return None
        pd = _pandas("sensitivities")
        parameters, names, values = native
        time = self._time if self.streamed_to is None else stream.read(self.streamed_to)[0]
        frame: dict[str, np.ndarray] = {"time": time[: values.shape[2]]}
        for p, parameter in enumerate(parameters):
            for c, name in enumerate(names):
                frame[_linkwork.sensitivity_name(name, parameter)] = values[p, c]
        table: pandas.DataFrame = pd.DataFrame(frame)
        return table

    def sensitivity(self, name: str, parameter: str, units: str = "si") -> np.ndarray | float:
        """The derivative of ``name`` with respect to ``parameter`` (one the run was asked for):
        an array (one value per output time) for a column, a float for a summary or a peak
        (``summary.json``'s ``sensitivities``). ``units="si"``: SI per SI unit of the parameter;
        ``"display"``: in the column's display unit per the parameter's (the model's
        ``display:`` section; a parameter written in ``mm``, a length, is per mm), a quantity
        of no known unit (a summary, an expression measure, a parameter written as a bare number)
        staying SI. A run that asked for no sensitivities raises ``ValueError``; a name or
        parameter without a derivative ``KeyError``, naming those that have one."""
        display = system(units)
        native = self._native.sensitivities
        if native is None:
            raise ValueError("the run asked for no sensitivities: Model.run(..., sensitivities=['r', ...] or True)")
        parameters, names, values = native
        if parameter not in parameters:
            raise KeyError(_unknown("parameter the run was asked for", parameter, parameters))
        by_name: dict[str, dict[str, float]] = self.summary.sensitivities or {}
        value: np.ndarray | float
        if name in names:
            value = values[parameters.index(parameter), names.index(name)]
        elif parameter in by_name.get(name, {}):
            value = float(by_name[name][parameter])
        else:
            raise KeyError(_unknown(f"derivative with respect to {parameter!r} of", name, [*names, *by_name]))
        if not display:
            return value
        shown = Units.of(self.model, [name]).shown(name, value) / Units.of_parameters(self.model, [parameter]).shown(parameter, 1.0)
        return shown if isinstance(value, np.ndarray) else float(shown)

    def write(self, out_dir: str | os.PathLike[str], report: bool = True, units: str = "si") -> None:
        """Write ``results.csv``, ``summary.json`` (and ``modes.csv`` for a modes analysis,
        ``sensitivities.csv`` for a run with :attr:`sensitivities`) and ``model.yaml`` (the model
        file as run) into ``out_dir`` (created if missing), in the engine's format, and
        ``report.html`` unless ``report`` is false: the same files as ``linkwork run``. The rows
        of a streamed run are its file, copied there as ``results.csv`` or ``results.parquet``
        unless it is already that file (its sensitivities, if any, go beside it in the same
        format); its report reads them back.

        The folder is written whole (:mod:`linkwork.folder`): the files go into a staging
        folder beside ``out_dir``, which then replaces ``out_dir`` in one step, so that
        ``out_dir`` holds these files or the previous ones, never a mix (a report of another
        run, or none left from one). A folder another run is writing, one that cannot be
        written, or one holding files no run writes (which replacing it would delete) is a
        :class:`FileError`, as is any error writing the files (the previous folder stays).

        ``units="si"`` writes ``results.csv`` in SI; ``units="display"`` in the units of the
        model's ``display:`` section (``linkwork run --units display``; not for a streamed run,
        whose rows went to their file SI as they were computed: a ``ValueError``). Either way
        ``summary.json`` says which (``unit_system``) and gives every column's unit as written
        (``units``); its own numbers stay SI."""
        display = system(units)
        if display and self.streamed_to is not None:
            raise ValueError(
                "units: 'display' cannot be written for a streamed run: its rows went to "
                f"{self.streamed_to} in SI as they were computed; write it with units='si'"
            )
        with folder.writing(out_dir, folder.run_files(self.model._native.table_files)) as out:
            self._native.write(os.fspath(out))
            table_units = Units.of(self.model, self._columns, display=display)
            if self.streamed_to is not None:
                table = out / f"results{self.streamed_to.suffix}"
                if not table.exists() or not table.samefile(self.streamed_to):
                    shutil.copyfile(self.streamed_to, table)
                self._write_streamed_sensitivities(out / f"sensitivities{self.streamed_to.suffix}")
            elif display:
                folder.write_text(out / "results.csv", self._csv(table_units))
            # The engine's summary.json, with the units of the table beside it.
            written = out / "summary.json"
            summary = json.loads(written.read_text(encoding="utf-8"))
            summary |= self._units_keys(table_units, units)
            # Its keys in alphabetical order, as the engine writes them; the units in column order.
            folder.write_text(written, json.dumps(dict(sorted(summary.items())), indent=2) + "\n")
            folder.write_text(out / "model.yaml", self.model.source)
            self._copy_tables(out)
            # Last: a report only beside the files it shows.
            if report:
                page.write(out / "report.html", self._run())

    def _write_streamed_sensitivities(self, path: Path) -> None:
        """Write the sensitivities of a streamed run, if it has any, at ``path``: CSV (each
        number in the shortest form that reads back to the same double, as the engine writes
        them) or Parquet, as its rows were streamed."""
        frame = self.sensitivities
        if frame is None:
            return
        if path.suffix == ".parquet":
            frame.to_parquet(path, index=False)
        else:
            folder.write_text(path, frame.to_csv(index=False, lineterminator="\n"))

    def _csv(self, units: Units) -> str:
        """The text of ``results.csv`` with every column in ``units``: the engine's layout, each
        number in the shortest form that reads back to the same double, as the engine writes them."""
        names = list(self)
        shown = np.column_stack([units.shown(name, self[name]) for name in names]) if len(self) else np.empty((0, len(names)))
        lines = [",".join(names), *(",".join(map(repr, row)) for row in shown.tolist())]
        return "\n".join(lines) + "\n"

    def _copy_tables(self, out_dir: Path) -> None:
        """Copy each table's file that the model names by a path inside its folder to the same
        path inside ``out_dir``, so that ``model.yaml`` there runs again (the report is rebuilt
        from it). A table named by an absolute path is read where it is; one outside the model's
        folder (``../data.csv``) is not copied, and the folder's ``model.yaml`` finds it only
        where it was found."""
        model_folder = Path(self.model._native.folder)
        for name in self.model._native.table_files:
            if not folder.inside(name):
                continue
            source, copy = model_folder / name, out_dir / name
            copy.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, copy)

    def _run(self) -> Run:
        units = Units.of(self.model, self._columns)
        tolerances = {name: t.value for name, t in self.model.tolerances.items()}
        if self.streamed_to is not None:
            time, columns = stream.read(self.streamed_to)
            return Run(self.model.drawing(), time, columns, self.summary, units=units, tolerances=tolerances)
        columns = {name: self._values[:, k] for k, name in enumerate(self._columns)}
        return Run(self.model.drawing(), self._time, columns, self.summary, units=units, tolerances=tolerances)

    def path(self, body: str, point: str | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(x, y)``, global frame, m, of a point of a moving body at every output time:
        ``path("foot", "G")`` or ``path("foot.G")`` for the named point ``G`` of the body
        ``foot``; ``path("foot")`` for its centre of mass (the columns ``foot.x``, ``foot.y``).
        Computed from the body's columns ``x``, ``y``, ``phi``, as the report draws it. An
        unknown body or point raises a :class:`KeyError` naming the closest ones."""
        if point is None and "." in body:
            body, point = body.split(".", 1)
        drawn = {b["name"]: b for b in self.model.drawing()["bodies"]}
        if body not in drawn:
            raise KeyError(_unknown("moving body", body, list(drawn)))
        points: dict[str, list[float]] = drawn[body]["points"]
        if point is not None and point not in points:
            raise KeyError(_unknown("point", point, list(points), f" of body {body!r}"))
        for c in ("x", "y", "phi"):
            self[f"{body}.{c}"]  # a KeyError when the analysis' outputs left the body out
        poses = _Poses(self._run(), np.arange(len(self)))
        return poses.point(body, points[point] if point is not None else (0.0, 0.0))

    def _series(self, name: str) -> np.ndarray:
        """The column ``name``, or the coordinate ``<body>.<point>.x`` (``.y``) of a point's
        :meth:`path`."""
        if name in self:
            return self[name]
        head, _, coordinate = name.rpartition(".")
        if coordinate in ("x", "y") and head.count(".") == 1:
            return self.path(head)["xy".index(coordinate)]
        return self[name]  # a KeyError naming the closest columns

    def plot(self, *columns: str, x: str = "time", y: str | Sequence[str] | None = None) -> Any:
        """A ``plotly`` figure of ``columns`` (or ``y``: a name or a list of names; default:
        every body's angle) against ``x`` (default ``time``): any column against any other, such
        as a torque against the crank's angle (``x="crank.phi", y="motor.effort"``). A name is
        a column, ``time``, or a point's coordinate ``<body>.<point>.x`` or ``.y`` (its
        :meth:`path`). ``x`` and one ``y`` that are the ``x`` and ``y`` of the same point
        (``x="foot.x", y="foot.y"``, ``x="foot.G.x", y="foot.G.y"``) plot its path, with equal
        scales on both axes. Values are in the units of the model's ``display:`` section (SI
        without one); the axes and the legend say which."""
        if columns and y is not None:
            raise TypeError("plot() takes the curves either as positional names or as y=, not both")
        names = [y] if isinstance(y, str) else list(y if y is not None else columns)
        names = names or [f"{b}.phi" for b in self.model.bodies]
        series = {name: self._series(name) for name in [x, *names] if name != "time"}
        run = self._run()
        run = dataclasses.replace(run, columns={**run.columns, **series})
        fig = figures.line_figure(run, names, x=x)
        if len(names) == 1 and x.endswith(".x") and names[0] == x[:-2] + ".y":
            fig["layout"]["yaxis"].update(scaleanchor="x", scaleratio=1)
        return figures.figure(fig)

    def animate(self) -> Any:
        """The mechanism moving through the results, with play, pause and a time slider, as a
        ``plotly`` figure (shown by a notebook)."""
        if not len(self):
            raise ValueError("no output point was computed: there is no pose to draw")
        return figures.figure(figures.mechanism_figure(self._run()))

    def _repr_html_(self) -> str:
        return page.compact_html(self.summary, len(self), self._time)

    def __repr__(self) -> str:
        summary = self.summary
        if self.streamed_to is not None:
            return (
                f"<linkwork.Results {summary.analysis or ''!r} ({summary.status}): {summary.output_points} points "
                f"streamed to {self.streamed_to}, {len(self._columns)} columns>"
            )
        span = f"t = {self._time[0]:g} .. {self._time[-1]:g} s" if len(self) else "no output"
        return (
            f"<linkwork.Results {summary.analysis or ''!r} ({summary.status}): {len(self)} points, {span}, "
            f"{len(self._columns)} columns>"
        )


def _pandas(what: str) -> Any:
    """The pandas module, which ``what`` needs; an ``ImportError`` saying how to install it."""
    try:
        import pandas as pd
    except ImportError as error:
        raise ImportError(f"{what} needs pandas: pip install 'linkwork[pandas]'") from error
    return pd


def _unknown(what: str, name: str, known: Sequence[str], where: str = "") -> str:
    """The message for a ``name`` that is none of ``known`` (``what``, ``where``: "no point 'Q'
    of body 'coupler'"): the closest of them when some are close, else all of them."""
    # difflib's default cutoff, a similarity of 0.6: a typo or a missing letter ("rocker.ph") is
    # close, another quantity of another body mostly not.
    close = difflib.get_close_matches(name, known, n=3)
    if close:
        return f"no {what} {name!r}{where}; did you mean {' or '.join(repr(c) for c in close)}?"
    return f"no {what} {name!r}{where}; there are {', '.join(known) or 'none'}"
