"""The Exudyn twin of a Linkwork model's dynamic analysis, built from the model itself.

Every body becomes an Exudyn `NodeRigidBody2D` + `ObjectRigidBody2D` (x, y, phi of its centre
of mass) started from the state Linkwork assembles for the analysis (`Model.check()`: positions
and velocities that satisfy the joints to rounding), or, with `assembled=False`, from the state
the file writes when that is consistent as written; so both engines integrate the same initial
value problem. Joints, their points resolved by Linkwork (`Model.drawing()`, parameters and named
points substituted), and masses, gravity and forces from the model file:

| Linkwork | Exudyn |
| --- | --- |
| `revolute` | `RevoluteJoint2D` between two `MarkerBodyPosition` |
| `translational` | `PrismaticJoint2D` between two `MarkerBodyRigid`, `axisMarker0` = `axis_i`, `normalMarker1` = `axis_j` turned by 90 degrees, `constrainRotation` |
| gravity | `LoadMassProportional` on every body |
| `torque` (a number) | `LoadTorqueVector` |
| `force` (numbers, global frame) | `LoadForceVector` |
| `spring_damper` (numbers) | `ObjectConnectorSpringDamper` |

Anything else (drivers, other joints, forces that are expressions) raises `NotImplementedError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import exudyn as exu
import exudyn.itemInterface as ei
import numpy as np
import yaml

if TYPE_CHECKING:
    import linkwork


def _number(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise NotImplementedError(f"{where}: {value!r} is not a number (expressions and units are not translated)")
    return float(value)


def _point(value: Sequence[object], where: str) -> list[float]:
    return [_number(value[0], where), _number(value[1], where), 0.0]


class ExudynModel:
    """An assembled Exudyn system of one dynamic analysis of a Linkwork `model`, with sensors on
    the x, y and phi of each of `bodies`, written every `output_step` seconds."""

    def __init__(
        self,
        model: linkwork.Model,
        analysis: str,
        bodies: Sequence[str],
        output_step: float,
        t_end: float,
        step: float,
        sparse: bool,
        assembled: bool = True,
    ) -> None:
        doc = yaml.safe_load(model.source)
        if doc["analyses"][analysis].get("drivers", list(doc.get("drivers", {}))):
            raise NotImplementedError(f"analysis {analysis}: drivers are not translated")
        state = self._assembled(model, analysis) if assembled else self._written(doc)
        drawing = model.drawing()
        points = {b["name"]: {**b["points"], **b["joint_points"]} for b in drawing["bodies"]}
        points["ground"] = {name: _point(p, f"ground.points.{name}") for name, p in doc.get("ground", {}).get("points", {}).items()}
        gravity = doc.get("gravity", [0, 0])

        self.sc = exu.SystemContainer()
        mbs = self.mbs = self.sc.AddSystem()
        self.objects = {"ground": mbs.AddObject(ei.ObjectGround())}
        self.angles: dict[str, float] = {}
        for name in model.bodies:
            spec = doc["bodies"][name]
            q = [state[f"{name}.{c}"][0] for c in ("x", "y", "phi")]
            v = [state[f"{name}.{c}"][1] for c in ("x", "y", "phi")]
            node = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=q, initialVelocities=v))
            body = mbs.AddObject(
                ei.ObjectRigidBody2D(
                    nodeNumber=node,
                    mass=_number(spec["mass"], f"bodies.{name}.mass"),
                    inertia=_number(spec["inertia"], f"bodies.{name}.inertia"),
                )
            )
            self.objects[name] = body
            self.angles[name] = q[2]
            if gravity[0] or gravity[1]:
                marker = mbs.AddMarker(ei.MarkerBodyMass(bodyNumber=body))
                mbs.AddLoad(ei.LoadMassProportional(markerNumber=marker, loadVector=_point(gravity, "gravity")))

        for joint in drawing["joints"]:
            name, kind = joint["name"], joint["type"]
            bi, bj = joint["body_i"], joint["body_j"]
            if kind == "revolute":
                markers = [self._marker(bi, joint["p"]), self._marker(bj, joint["q"])]
                mbs.AddObject(ei.ObjectJointRevolute2D(markerNumbers=markers))
            elif kind == "translational":
                spec = doc["joints"][name]
                ai = _point(spec.get("axis_i", [1, 0]), f"joints.{name}.axis_i")
                aj = _point(spec.get("axis_j", [1, 0]), f"joints.{name}.axis_j")
                markers = [self._marker(bi, joint["p"], rigid=True), self._marker(bj, joint["q"], rigid=True)]
                mbs.AddObject(
                    ei.ObjectJointPrismatic2D(
                        markerNumbers=markers, axisMarker0=ai, normalMarker1=[-aj[1], aj[0], 0.0], constrainRotation=True
                    )
                )
            else:
                raise NotImplementedError(f"joint {name}: type {kind} is not translated")

        forces = doc.get("forces", {})
        for name in doc["analyses"][analysis].get("forces", list(forces)):
            spec, where = forces[name], f"forces.{name}"
            kind = spec["type"]
            if kind == "torque":
                marker = self._marker(spec["body"], [0, 0], rigid=True)
                mbs.AddLoad(ei.LoadTorqueVector(markerNumber=marker, loadVector=[0, 0, _number(spec["torque"], where)]))
            elif kind == "force" and spec.get("frame", "global") == "global":
                marker = self._marker(spec["body"], self._resolve(spec["body"], spec.get("point", [0, 0]), points, where))
                load = [_number(spec.get("fx", 0), where), _number(spec.get("fy", 0), where), 0.0]
                mbs.AddLoad(ei.LoadForceVector(markerNumber=marker, loadVector=load))
            elif kind == "spring_damper" and "actuator" not in spec and "free_length" in spec:
                markers = [
                    self._marker(spec["body_i"], self._resolve(spec["body_i"], spec["point_i"], points, where)),
                    self._marker(spec["body_j"], self._resolve(spec["body_j"], spec["point_j"], points, where)),
                ]
                mbs.AddObject(
                    ei.ObjectConnectorSpringDamper(
                        markerNumbers=markers,
                        stiffness=_number(spec["stiffness"], where),
                        damping=_number(spec.get("damping", 0), where),
                        referenceLength=_number(spec["free_length"], where),
                    )
                )
            else:
                raise NotImplementedError(f"{where}: this {kind} is not translated")

        self.sensors: dict[str, tuple[Any, Any]] = {}
        for name in bodies:
            body = self.objects[name]
            position = mbs.AddSensor(ei.SensorBody(bodyNumber=body, storeInternal=True, outputVariableType=exu.OutputVariableType.Position))
            rotation = mbs.AddSensor(ei.SensorBody(bodyNumber=body, storeInternal=True, outputVariableType=exu.OutputVariableType.Rotation))
            self.sensors[name] = (position, rotation)

        s = self.settings = exu.SimulationSettings()
        s.timeIntegration.endTime = t_end
        s.timeIntegration.numberOfSteps = int(round(t_end / step))
        s.timeIntegration.verboseMode = 0
        s.solution.file.write = False
        s.solution.sensors.writePeriod = output_step
        if sparse:
            s.linearSolver.solverType = exu.LinearSolverType.EigenSparse

    @staticmethod
    def _assembled(model: linkwork.Model, analysis: str) -> dict[str, tuple[float, float]]:
        """Each coordinate's (position, velocity) as Linkwork assembles them for `analysis`."""
        check = model.check()
        assembly = check["analyses"][analysis]["assembly"]
        return dict(zip(check["coordinate_names"], zip(assembly["q"], assembly["qdot"], strict=True), strict=True))

    @staticmethod
    def _written(doc: dict[str, Any]) -> dict[str, tuple[float, float]]:
        """Each coordinate's (position, velocity) as the file writes them: for a file whose state
        is consistent as written (the N-four-bar's generator writes it exactly), where
        `Model.check()` would cost more than the runs (its rank test is dense)."""
        state: dict[str, tuple[float, float]] = {}
        for name, spec in doc["bodies"].items():
            position, velocity = spec.get("position", [0, 0]), spec.get("velocity", [0, 0])
            state[f"{name}.x"] = (_number(position[0], name), _number(velocity[0], name))
            state[f"{name}.y"] = (_number(position[1], name), _number(velocity[1], name))
            state[f"{name}.phi"] = (_number(spec.get("angle", 0), name), _number(spec.get("omega", 0), name))
        return state

    def _marker(self, body: str, point: Sequence[object], rigid: bool = False) -> Any:
        kind = ei.MarkerBodyRigid if rigid else ei.MarkerBodyPosition
        return self.mbs.AddMarker(kind(bodyNumber=self.objects[body], localPosition=_point(point, f"{body} point")))

    @staticmethod
    def _resolve(
        body: str, point: str | Sequence[object], points: dict[str, dict[str, list[float]]], where: str
    ) -> list[float]:
        return points[body][point] if isinstance(point, str) else _point(point, where)

    def solve(self) -> Any:
        """Assemble and integrate with the generalised-alpha solver (Exudyn's default settings
        but the step, end time and linear solver); the solver's iteration data."""
        self.mbs.Assemble()
        try:
            self.mbs.SolveDynamic(self.settings)
        except exu.SolverError:
            it = self.mbs.sys["dynamicSolver"].it
            raise RuntimeError(
                f"SolveDynamic failed at t = {it.currentTime:.4g} s, its step cut to {it.currentStepSize:.0e} s"
            ) from None
        return self.mbs.sys["dynamicSolver"].it

    def columns(self) -> dict[str, np.ndarray]:
        """The output times and each sensed body's `x`, `y`, `phi` columns (the rotation sensor
        gives the angle turned from the reference, so the initial angle is added)."""
        out: dict[str, np.ndarray] = {}
        for name, (position, rotation) in self.sensors.items():
            p, r = np.asarray(self.mbs.GetSensorStoredData(position)), np.asarray(self.mbs.GetSensorStoredData(rotation))
            out["time"] = p[:, 0]
            out[f"{name}.x"], out[f"{name}.y"], out[f"{name}.phi"] = p[:, 1], p[:, 2], self.angles[name] + r[:, 1]
        return out
