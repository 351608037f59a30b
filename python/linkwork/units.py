"""The units results are shown in: a model's ``display:`` section (docs/model-format.md,
"Display units") applied to result columns, for the command line's output, the report and
:meth:`linkwork.Results.plot`, and to the files when they are asked for in it (``--units
display``, ``Results.write(units="display")``).

The engine decides what each column is (a length, an angle, a force ...) and reads every unit;
this module only divides by the factors it gives.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np

from . import _linkwork

if TYPE_CHECKING:
    from .model import Model

#: What a column whose quantity the engine does not know (an expression measure, a residual, a
#: pure number) is labelled with: its value is as computed, in SI units.
UNKNOWN = "SI"

#: The units files can be written in (``--units``): ``si``, or ``display``, the model's
#: ``display:`` section (SI for the quantities it does not name).
SYSTEMS = ("si", "display")


def system(units: str, field: str = "units") -> bool:
    """Whether ``units`` (one of :data:`SYSTEMS`) asks for the display units; a ``ValueError``
    naming ``field`` for anything else."""
    if units not in SYSTEMS:
        raise ValueError(f"{field}: expected 'si' or 'display', got {units!r}")
    return units == "display"


def to_si(unit: str, values: object) -> np.ndarray:
    """``values`` written in ``unit`` (as a file's units map says it, :data:`UNKNOWN` for a
    column left as computed) in SI. A unit that cannot be read is a ``ValueError`` saying why."""
    array = np.asarray(values, dtype=float)
    return array if unit == UNKNOWN else array * _linkwork.unit(unit)


class Units:
    """Each quantity's unit and factor to SI, and the quantity of each result column."""

    __slots__ = ("_quantities", "_shown")

    def __init__(self, shown: Mapping[str, tuple[str, float]], quantities: Mapping[str, str | None]) -> None:
        self._shown = dict(shown)
        self._quantities = dict(quantities)

    @classmethod
    def si(cls) -> Units:
        """SI, for no model: every quantity in its SI unit, no column's quantity known."""
        return cls({q: (u, 1.0) for q, u in _linkwork.si_units()}, {})

    @classmethod
    def of(cls, model: Model, columns: Iterable[str], display: bool = True) -> Units:
        """The units of ``model``'s ``display:`` section (SI when ``display`` is false) for its
        result ``columns`` (``time`` is always known)."""
        names = ["time", *columns]
        quantities = dict(zip(names, model._native.column_quantities(names), strict=True))
        if not display:
            return cls(cls.si()._shown, quantities)
        return cls({q: (u, f) for q, u, f in model._native.display}, quantities)

    @classmethod
    def of_parameters(cls, model: Model, names: Iterable[str], display: bool = True) -> Units:
        """The units of ``model``'s parameters ``names``, each of the quantity whose SI unit is that
        of the unit the file writes it in (``r: 100 mm`` a length; ``N m`` and ``J`` a torque, the
        first quantity of their dimension); a parameter written as a bare number, or in a unit of
        no result quantity (``kg m^2``, ``N/m``), has none and is shown as computed, SI."""
        # Reversed so that the first quantity of an SI unit is the one kept: torque before energy.
        by_si = {u: q for q, u in reversed(_linkwork.si_units())}
        written = dict(model._native.parameter_units)
        quantities = {n: by_si.get(_linkwork.si_unit(written[n]) or "") if n in written else None for n in names}
        return cls(cls.of(model, [], display)._shown, quantities)

    def unit(self, quantity: str) -> str:
        """The unit ``quantity`` (``"length"``, ``"angle"`` ...) is shown in."""
        return self._shown[quantity][0]

    def column_unit(self, column: str) -> str:
        """The unit the column ``column`` is shown in (:data:`UNKNOWN` when its quantity is not known)."""
        quantity = self._quantities.get(column)
        return UNKNOWN if quantity is None else self._shown[quantity][0]

    def shown(self, column: str, values: object) -> np.ndarray:
        """``values`` of ``column`` (SI) in the unit it is shown in."""
        quantity = self._quantities.get(column)
        array = np.asarray(values, dtype=float)
        return array if quantity is None else array / self._shown[quantity][1]

    def value(self, quantity: str, si: float) -> float:
        """One value of ``quantity`` (SI) in the unit it is shown in."""
        return si / self._shown[quantity][1]

    def column_units(self, columns: Iterable[str]) -> dict[str, str]:
        """Each of ``columns`` with its unit (:meth:`column_unit`): a file's units map."""
        return {column: self.column_unit(column) for column in columns}

    def label(self, column: str) -> str:
        """``column (unit)``: a column's name as a table or a legend says it."""
        return f"{column} ({self.column_unit(column)})"

    def is_si(self) -> bool:
        """Whether every quantity is shown in SI."""
        return all(f == 1.0 for _, f in self._shown.values())
