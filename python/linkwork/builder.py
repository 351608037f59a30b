"""A model built in Python, by name, as a model file would write it.

::

    m = linkwork.Mechanism("four-bar")
    crank = m.body("crank", mass=0.5, inertia=5e-4, position="M",
                   points_global={"O2": (0, 0), "A": (0.1, 0), "M": (0.05, 0)})
    m.revolute("O2", crank, "ground", at=(0, 0))
    ...
    m.driver("motor", "angle", body=crank, function="2*t")
    m.analysis("kinematics", "kinematic", drivers=["motor"], t_end=6.3, step=0.02)
    results = m.build().run()
    print(m.to_yaml())

Every entry is what the model file holds (docs/model-format.md): a number is SI, or text with a
unit (``"40 mm"``) or an expression of the parameters (``"r/2"``); a point is ``(x, y)`` (a named
point may be placed from others instead: ``"body.B"``, or :class:`ByLengths`); a body is
its name or the :class:`Body` that :meth:`Mechanism.body` returns. The typed methods cover every
joint, driver and force type (generated from the schema of model files: ``_entries.py``) and the
standard measures (and :meth:`Mechanism.summary` a whole-run quantity);
:meth:`Mechanism.joint`, :meth:`driver`, :meth:`force`, :meth:`measure` and :meth:`analysis` take
any type with its fields as keywords, so the builder
expresses whatever the file format does.
The engine checks the model when it is built (:meth:`Mechanism.build`), each problem at its path
in the file (``joints.A.body_j: unknown body 'coupler'``); the builder itself refuses only what
a file could not hold: a name used twice, a number that is not finite, a value of no YAML kind.

:meth:`Mechanism.to_yaml` writes the model file (with ruamel.yaml): ``linkwork.from_yaml(m.to_yaml())``
is the model :meth:`Mechanism.build` gives (every number written in the shortest form that reads
back to the same double).
"""

from __future__ import annotations

import io
import math
import numbers
import sys
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Union

from ruamel.yaml import YAML
from ruamel.yaml.comments import CommentedMap, CommentedSeq
from ruamel.yaml.nodes import ScalarNode
from ruamel.yaml.representer import BaseRepresenter

from ._entries import ByLengths, Entries, Number, Point
from .model import Model

NamedPoint = Union[Point, str, ByLengths]
"""A named point of a body or of ground: ``(x, y)``; ``"body.B"``, where that point of another body
(or of ground) is; or :class:`ByLengths`."""


_SECTIONS = (
    "name", "gravity", "parameters", "display", "tables", "ground", "bodies", "joints", "drivers", "forces",
    "measures", "paths", "summaries", "branches", "branch", "analyses",
)
_NAMED = (
    "parameters", "tables", "bodies", "joints", "drivers", "forces", "measures", "summaries", "branches", "analyses",
)
# Bodies, joints, drivers, forces and measures share one space of names (they label the results'
# columns); parameters, summaries and analyses have their own.
_SHARED = ("bodies", "joints", "drivers", "forces", "measures")


class Body(str):
    """A body's name, as :meth:`Mechanism.body` returns it: pass it wherever a body is named."""


class Mechanism(Entries):
    """A model under construction: bodies, joints, drivers, forces, measures, summaries and
    analyses, by name, in the order they are added (the order of the file, and of the results' columns)."""

    def __init__(self, name: str | None = None, *, gravity: Point | None = None) -> None:
        """``name``: the model's title. ``gravity``: ``(gx, gy)``, m/s^2 (default: none)."""
        self._doc: dict[str, Any] = {}
        if name is not None:
            self._doc["name"] = name
        if gravity is not None:
            self._doc["gravity"] = _value("gravity", gravity)

    # --- entries -------------------------------------------------------------------------------

    def parameter(self, name: str, value: Number) -> None:
        """A named value the model's numbers and expressions may use: SI, or text with a unit
        (``"120 mm"``) or an expression of earlier parameters."""
        self._add("parameters", name, _value(f"parameters.{name}", value))

    def ground_point(self, name: str, point: NamedPoint) -> None:
        """A named point of ground, global frame, m (or placed from other points,
        :data:`NamedPoint`)."""
        ground = self._doc.setdefault("ground", {"points": {}})
        if name in ground["points"]:
            raise ValueError(f"ground.points.{name}: the name is already used")
        ground["points"][name] = _value(f"ground.points.{name}", point)

    def body(
        self,
        name: str,
        *,
        mass: Number,
        inertia: Number,
        position: Point | str,
        angle: Number | None = None,
        points: Mapping[str, NamedPoint] | None = None,
        points_global: Mapping[str, NamedPoint] | None = None,
        velocity: Point | None = None,
        omega: Number | None = None,
        given: Iterable[str] | None = None,
    ) -> Body:
        """A rigid body, its frame at its centre of mass.

        ``mass`` kg; ``inertia`` kg m^2 about the centre of mass; ``position`` the centre's
        initial (guessed) global position, m, or the name of one of ``points_global``; ``angle``
        the frame's initial angle, rad (default 0: parallel to the global frame);
        ``points`` named points in the body frame, m; ``points_global`` named points where they
        are at the initial position, global frame, m (either may place a point from others:
        ``"body.B"``, where another body's point is, or :class:`ByLengths`, by its distances to
        two points); ``velocity`` m/s and ``omega`` rad/s
        initially (default 0); ``given`` the initial values assembly must hold (``"x"``, ``"y"``,
        ``"phi"``, ``"vx"``, ``"vy"``, ``"omega"``).
        """
        fields: dict[str, Any] = {"mass": mass, "inertia": inertia, "position": position, "angle": angle}
        fields.update(points=points, points_global=points_global, velocity=velocity, omega=omega)
        fields["given"] = list(given) if given is not None else None
        self._add("bodies", name, _entry(f"bodies.{name}", fields))
        return Body(name)

    def joint(self, name: str, type: str, **fields: Any) -> str:
        """A joint of any ``type`` of the model format, with its fields (docs/model-format.md,
        "Joints"): ``m.joint("g", "gear", body_i=a, point_i="O", radius_i=0.05, ...)``."""
        self._add("joints", name, _entry(f"joints.{name}", {"type": type, **fields}))
        return name

    def driver(self, name: str, type: str, **fields: Any) -> str:
        """A driver (``"angle"``, ``"relative_angle"``, ``"distance"``, ``"x"``, ``"y"``) with its
        fields: ``m.driver("motor", "angle", body=crank, function="2*pi*t")``; ``function`` an
        expression of ``t`` (motion laws included, docs/model-format.md)."""
        self._add("drivers", name, _entry(f"drivers.{name}", {"type": type, **fields}))
        return name

    def force(self, name: str, type: str, **fields: Any) -> str:
        """A force or force element (``"force"``, ``"torque"``, ``"spring_damper"``,
        ``"rotational_spring_damper"``, ``"contact"``) with its fields, N, N m, N/m, N s/m."""
        self._add("forces", name, _entry(f"forces.{name}", {"type": type, **fields}))
        return name

    def measure(self, name: str, expression: str | None = None, **fields: Any) -> str:
        """A named output: an expression (``"slider_d.x + 4"``; where the analysis has them it
        may read the reaction and effort columns, ``"sqrt(B.fx^2 + B.fy^2)"``), a body point's
        quantity (``body=, point=, component=``), or a standard measure by its ``type`` with its
        fields (``type="velocity_ratio", input=crank, output=rocker``; the typed methods below)."""
        if expression is not None and fields:
            raise ValueError(
                f"measures.{name}: give an expression or fields (body, point and component, or a type), not both"
            )
        value = _value(f"measures.{name}", expression) if expression is not None else _entry(f"measures.{name}", fields)
        self._add("measures", name, value)
        return name

    def summary(self, name: str, expression: str) -> str:
        """A whole-run quantity, one number in ``results.summaries`` and ``summary.json``: an
        expression of aggregations of the result columns over the run (``integral``, ``mean``,
        ``rms``, ``min``, ``max``, ``peak``, ``initial``, ``final``, ``at(time, f)``) and of parameters,
        such as ``m.summary("efficiency", "integral(pump_power) / integral(motor_power)")``
        (docs/model-format.md, "Summaries")."""
        self._add("summaries", name, _value(f"summaries.{name}", expression))
        return name

    def table(
        self,
        name: str,
        x: Sequence[float] | str,
        y: Sequence[float] | str,
        *,
        method: str | None = None,
        file: str | None = None,
    ) -> str:
        """A tabulated function for ``spline(name, x)`` in any expression (drivers, joints,
        forces, measures): the points ``x`` (strictly increasing) and ``y``, in whatever SI
        units they tabulate; or, with ``file`` (a CSV file whose first row names its columns,
        relative to the model file's folder, or to the working folder for :meth:`build`), the
        names of two of its columns. ``method``: ``"not_a_knot"`` (the default cubic spline),
        ``"periodic"`` (first and last ``y`` equal; repeats outside) or ``"akima"``."""
        fields = {"file": file, "x": x if isinstance(x, str) else list(x), "y": y if isinstance(y, str) else list(y)}
        self._add("tables", name, _entry(f"tables.{name}", {**fields, "method": method}))
        return name

    def transmission_angle(self, name: str, joint: str, coupler_joint: str, rocker_joint: str) -> str:
        """The transmission angle ``mu`` at the pin ``joint`` between a coupler and a rocker, rad,
        in ``[0, pi/2]``: the acute angle between the coupler's line (from ``joint`` to its other
        pin ``coupler_joint``) and the rocker's (from ``joint`` to its pivot ``rocker_joint``);
        three revolute joints. 90 degrees transmits best; the usual rule is ``mu >= 40``
        degrees."""
        return self.measure(
            name, type="transmission_angle", joint=joint, coupler_joint=coupler_joint, rocker_joint=rocker_joint
        )

    def velocity_ratio(self, name: str, input: str, output: str) -> str:
        """``omega_output / omega_input`` of two moving bodies (rad/s over rad/s), signed."""
        return self.measure(name, type="velocity_ratio", input=input, output=output)

    def mechanical_advantage(self, name: str, input: str, output: str) -> str:
        """``-F_output / F_input``: the load at the output over the effort at the input, each the
        name of a driver (its effort, N m or N) or of a ``torque`` force (N m), the torque or
        force applied to the mechanism there; ``omega_input / omega_output`` in a frictionless
        mechanism of negligible inertia. Needs an inverse, static or dynamic analysis."""
        return self.measure(name, type="mechanical_advantage", input=input, output=output)

    def pressure_angle(self, name: str, joint: str) -> str:
        """The pressure angle of the cam joint ``joint`` with a radial follower (moving along the
        line through the cam's centre), rad: the angle between the contact normal (the pitch
        curve's normal at the follower's point) and that line, ``atan(sign(dpsi/dt) R'(psi) /
        R(psi))`` on a polar pitch curve, positive while the cam pushes the follower out; for a
        cam given by its working surface as well. The usual rule is ``|phi| <= 30`` degrees."""
        return self.measure(name, type="pressure_angle", joint=joint)

    def branch(self, joint: str, line: tuple[str, str], side: str, *, strict: bool = False) -> None:
        """Declare the assembly mode of the dyad whose middle pin is ``joint``: ``side``
        (``"left"`` or ``"right"``) of the directed line from the joint ``line[0]`` to the joint
        ``line[1]``; assembled so whatever side the drawing puts it on, with a warning when they
        disagree. ``strict=True`` makes every disagreement an error (``branch: strict``, for the
        whole model)."""
        self._add("branches", joint, {"line": list(line), "side": side})
        if strict:
            self._doc["branch"] = "strict"

    def paths(self, *points: str) -> None:
        """The points whose paths the report draws: ``"<body>.<point>"``, or ``"<body>"`` for its
        centre of mass (default: the point measures' points)."""
        self._doc.setdefault("paths", []).extend(points)

    def display(self, **units: str) -> None:
        """The units results are shown in (the command line, the report, ``Results.plot``), by
        quantity: ``display(length="mm", angle="deg")``. Files stay SI."""
        self._doc.setdefault("display", {}).update(units)

    def analysis(self, name: str, type: str, **fields: Any) -> str:
        """An analysis (``"kinematic"``, ``"dynamic"``, ``"inverse"``, ``"static"``, ``"modes"``)
        with its fields: ``drivers``, ``forces``, ``t_end`` and ``step`` s, ``integrator``,
        ``solver`` settings, ``outputs``."""
        self._add("analyses", name, _entry(f"analyses.{name}", {"type": type, **fields}))
        return name

    # --- out -----------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The model file's document: sections in the file's order, entries in the order added."""
        return {key: self._doc[key] for key in _SECTIONS if key in self._doc}

    def to_yaml(self) -> str:
        """The model file, written by ruamel.yaml: one line per entry, as the examples are written."""
        document = CommentedMap()
        for key, value in self.to_dict().items():
            if key in _NAMED or key == "ground":
                document[key] = CommentedMap((name, _flow(entry)) for name, entry in value.items())
            else:
                document[key] = _flow(value)
        writer = YAML()
        # An entry on one line however long.
        writer.width = sys.maxsize
        writer.representer.add_representer(str, _text)
        text = io.StringIO()
        writer.dump(document, text)
        return text.getvalue()

    def build(self, parameters: Mapping[str, float | str] | None = None) -> Model:
        """The compiled model (as ``linkwork.from_yaml(self.to_yaml(), parameters)``); a
        :class:`linkwork.ModelError` lists every problem, each at its path in the file."""
        return Model.from_yaml(self.to_yaml(), parameters)

    def _add(self, section: str, name: str, value: Any) -> None:
        if not isinstance(name, str) or not name:
            raise ValueError(f"{section}: a name must be a non-empty string, found {name!r}")
        sections = _SHARED if section in _SHARED else (section,)
        used = next((s for s in sections if name in self._doc.get(s, {})), None)
        if used is not None:
            raise ValueError(f"{section}.{name}: the name is already used in {used}")
        self._doc.setdefault(section, {})[name] = value


def _entry(path: str, fields: Mapping[str, Any]) -> dict[str, Any]:
    """An entry's fields, those left at ``None`` out, each checked (``path.field``)."""
    return {key: _value(f"{path}.{key}", v) for key, v in fields.items() if v is not None}


def _value(path: str, value: Any) -> Any:
    """``value`` as the file holds it (tuples as lists, numpy numbers as Python ones), or a
    ``ValueError`` naming ``path`` for what no file could hold."""
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, str):
        return str(value)  # a Body as the text it is
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"{path}: expected a finite number, found {v}")
        return v
    if isinstance(value, Mapping):
        return {str(k): _value(f"{path}.{k}", v) for k, v in value.items()}
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else value
        return [_value(f"{path}[{k}]", v) for k, v in enumerate(items)]
    raise ValueError(f"{path}: expected a number, text, a list or a mapping, found {type(value).__name__}")


# Words YAML 1.1 reads as booleans, in any case: text in YAML 1.2 (ruamel.yaml's and the engine's),
# but some readers still apply 1.1, so they are written in quotes.
_YAML_WORDS = {"true", "false", "null", "yes", "no", "on", "off", "y", "n"}


def _text(representer: BaseRepresenter, text: str) -> ScalarNode:
    """Text as ruamel.yaml writes it, in double quotes where YAML 1.1 would read a boolean."""
    style = '"' if text.lower() in _YAML_WORDS else None
    return representer.represent_scalar("tag:yaml.org,2002:str", text, style=style)


def _flow(value: Any) -> Any:
    """``value`` (as :func:`_value` leaves it) with its mappings and lists in YAML's flow style:
    ``{a: 1}``, ``[1, 2]``; numbers in their shortest exact form (``repr``)."""
    if isinstance(value, Mapping):
        mapping = CommentedMap((k, _flow(v)) for k, v in value.items())
        mapping.fa.set_flow_style()
        return mapping
    if isinstance(value, list):
        sequence = CommentedSeq(_flow(v) for v in value)
        sequence.fa.set_flow_style()
        return sequence
    return value
