"""What ``summary.json`` says of a run (:class:`Summary`), and its dyads' assembly modes in words."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Generic, TypeVar, cast, overload

_T = TypeVar("_T")


class _Key(Generic[_T]):
    """A read-only attribute of :class:`Summary`: its key of the same name, ``None`` when absent."""

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    @overload
    def __get__(self, summary: None, owner: type) -> _Key[_T]: ...
    @overload
    def __get__(self, summary: Summary, owner: type) -> _T: ...
    def __get__(self, summary: Summary | None, owner: type) -> _Key[_T] | _T:
        if summary is None:
            return self
        # Declared per key: optional where a summary may lack the key, so that absent is None.
        return cast(_T, summary.get(self._name))


class Summary(dict[str, Any]):
    """What ``summary.json`` says: a dict, as read from the file, whose keys are also attributes.

    ``summary["dof"]`` and ``summary.dof`` are the same value; an attribute whose key this summary
    does not have (``modes`` of a kinematic analysis, ``dof`` of a run that failed before it was
    known) is ``None``. Every summary has the model's ``model``, ``bodies``, ``coordinates``,
    ``joints``, and ``output_points``, ``warnings`` and ``status``; every analysis adds
    ``analysis``, ``type``, ``active_drivers``, ``settings``, and once it has the rank of the
    constraint Jacobian ``dof`` and ``redundant_rows``. ``docs/model-format.md`` lists the rest.
    """

    __slots__ = ()

    model: _Key[str] = _Key()
    """Name of the model."""
    bodies: _Key[int] = _Key()
    """Number of moving bodies."""
    coordinates: _Key[int] = _Key()
    """Number of coordinates, three per body."""
    joints: _Key[list[str]] = _Key()
    """The joints, in file order."""
    parameters: _Key[dict[str, float]] = _Key()
    """The parameters' values used, SI, by name (empty when the file has none)."""
    output_points: _Key[int] = _Key()
    """Number of output points written."""
    warnings: _Key[list[str]] = _Key()
    """Messages about the run; empty when there is nothing to say."""
    status: _Key[str] = _Key()
    """``"ok"``; ``"failed"`` when the run stopped at an error; ``"interrupted"`` when Ctrl-C stopped it."""
    error: _Key[str | None] = _Key()
    """The error's message, when the run failed."""
    error_elements: _Key[list[str] | None] = _Key()
    """The joints and drivers the error names, when the run failed."""
    error_time: _Key[float | None] = _Key()
    """When the error happened, s, when it happened at a time."""
    analysis: _Key[str | None] = _Key()
    """Name of the analysis run (``None`` when the run named none of the model's)."""
    active_drivers: _Key[list[str] | None] = _Key()
    """The drivers the analysis holds."""
    settings: _Key[dict[str, Any] | None] = _Key()
    """The position solver's settings."""
    dof: _Key[int | None] = _Key()
    """Degrees of freedom the joints and active drivers leave."""
    redundant_rows: _Key[list[dict[str, str]] | None] = _Key()
    """Rows that repeat earlier ones (they hold implicitly), each ``{"element": ..., "equation": ...}``."""
    branches: _Key[list[dict[str, Any]] | None] = _Key()
    """Each dyad's assembly mode: ``joint``, ``line``, ``bodies``, ``side``, ``drawn``, ``declared``."""
    branch_changes: _Key[list[dict[str, Any]] | None] = _Key()
    """Each change of a dyad's branch during the run: ``joint``, ``line``, ``time``, ``from``, ``to``."""
    indeterminate_joints: _Key[list[str] | None] = _Key()
    """Joints whose share of the reactions the equations leave open (minimum-norm reactions)."""
    assembly: _Key[dict[str, Any] | None] = _Key()
    """The assembly at the start: ``iterations``, ``residual``, ``velocity_residual``."""
    statistics: _Key[dict[str, Any] | None] = _Key()
    """What the solver did (its keys depend on the analysis' type)."""
    integrator: _Key[dict[str, Any] | None] = _Key()
    """The integrator's settings (dynamic)."""
    residuals: _Key[dict[str, float] | None] = _Key()
    """The largest constraint residuals at output, ``max_position`` and ``max_velocity`` (dynamic)."""
    stable: _Key[bool | None] = _Key()
    """Whether the state is a stable equilibrium (static, modes)."""
    index: _Key[int | None] = _Key()
    """Unstable directions of the equilibrium reached (static; ``None`` also when there was none)."""
    min_reduced_stiffness: _Key[float | None] = _Key()
    """Smallest eigenvalue of the reduced tangent stiffness over the equilibria written (static)."""
    about: _Key[str | None] = _Key()
    """The state a modes analysis linearised about."""
    modes: _Key[list[dict[str, Any]] | None] = _Key()
    """The modes of a modes analysis (see :attr:`Results.modes`)."""
    reaction_bodies: _Key[dict[str, str] | None] = _Key()
    """The body each joint's reaction acts on (inverse, static, dynamic)."""
    peaks: _Key[dict[str, dict[str, Any]] | None] = _Key()
    """Per joint and active driver the largest reaction or effort ``max_abs`` and its ``time``."""
    summaries: _Key[dict[str, float] | None] = _Key()
    """The model's summaries (its ``summaries:``, whole-run quantities) by name: in a run that ended
    well and whose output spans time, when the model has any (see :attr:`Results.summaries`)."""
    sensitivities: _Key[dict[str, dict[str, float]] | None] = _Key()
    """The derivatives of the summaries and peaks with respect to the parameters the run was asked
    for (``Model.run(..., sensitivities=...)``): name, then parameter, then the derivative, SI per
    SI unit of the parameter (see :meth:`Results.sensitivity`)."""
    unit_system: _Key[str | None] = _Key()
    """The units ``results.csv`` is written in: ``"si"``, or ``"display"`` (the model's
    ``display:`` section, ``Results.write(units="display")``); ``"si"`` in
    :attr:`Results.summary`, whose columns are SI (``None`` in a folder written before units were
    recorded: SI)."""
    units: _Key[dict[str, str] | None] = _Key()
    """Each column of ``results.csv`` (``time`` first) with its unit as written there (``SI``: a
    column whose quantity is not known, as computed)."""
    # Last: in the class body `type` is this attribute from here on.
    type: _Key[str | None] = _Key()
    """The analysis' type: ``kinematic``, ``inverse``, ``static``, ``modes`` or ``dynamic``."""


def branch_words(branch: Mapping[str, Any]) -> str:
    """A dyad's assembly mode in words, from an entry of a summary's or a check's ``branches``:
    ``right of C -> D (drawn right, declared right; bodies linkf, foot)``."""
    e, d = branch["line"]
    side = f"{branch['side']} of" if branch["side"] else "on"
    notes = [f"drawn {branch['drawn']}" if branch["drawn"] else "drawn on the line"]
    if branch["declared"]:
        notes.append(f"declared {branch['declared']}")
    return f"{side} {e} -> {d} ({', '.join(notes)}; bodies {', '.join(branch['bodies'])})"


def branch_lines(branches: Sequence[Mapping[str, Any]]) -> list[str]:
    """Each dyad's assembly mode, a line each: ``branch F  right of C -> D (...)``."""
    return [f"branch {b['joint']:<11} {branch_words(b)}" for b in branches]
