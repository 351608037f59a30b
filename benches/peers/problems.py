"""The problems of benches/peers: each a Linkwork model file and dynamic analysis, the span and
output times both engines write, Exudyn's steps, and the reference its error is measured against.

`PROBLEMS` names them for `run.py --problems`; `problem(key, n)` builds one (`n` for the
N-four-bar). `error(problem, model, columns)` measures a run, given its output times
(`columns["time"]`) and the x, y and phi of the problem's `bodies`.
"""

from __future__ import annotations

import importlib.util
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml

import references

if TYPE_CHECKING:
    import linkwork

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Problem:
    key: str
    label: str
    text: str
    analysis: str
    t_end: float
    output_step: float
    exudyn_steps: tuple[float, ...]
    bodies: tuple[str, ...]
    reference: str
    unit: str
    # Exudyn's sparse linear solver (EigenSparse) instead of its default dense one.
    sparse: bool = False
    # Exudyn starts from Linkwork's assembled state (else from the state the file writes).
    assembled: bool = True
    n: int = 0


def _nfourbar_text(n: int) -> str:
    """examples/nfourbar.py's model of the N-four-bar (what `python examples/nfourbar.py N` prints)."""
    spec = importlib.util.spec_from_file_location("nfourbar", EXAMPLES / "nfourbar.py")
    assert spec is not None and spec.loader is not None, "examples/nfourbar.py is a Python file"
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return str(module.model(n))


PENDULUM_REFERENCE = "exact: Jacobi's sn (the mass's x, y)"
ONE_DOF_REFERENCE = "quadrature of its energy equation (every body's x, y, phi)"
NFOURBAR_REFERENCE = "its one-degree-of-freedom equation, RK4 at 1e-4 s (B0's x, y)"
ANDREWS_REFERENCE = "converged end state at 0.03 s (the 7 angles, relative)"


def problem(key: str, n: int = 0) -> Problem:
    """The problem called `key` (`n`: the N-four-bar's loops)."""
    a01 = (EXAMPLES / "iftomm_a01_pendulum.yaml").read_text()
    quick_return = (EXAMPLES / "quick_return_a.yaml").read_text()
    if key == "pendulum":
        return Problem(key, "pendulum (A01 model), 10 s", a01, "dynamics", 10.0, 0.01, (1e-3,), ("P1",), PENDULUM_REFERENCE, "m")
    if key == "a01":
        return Problem(key, "IFToMM A01 pendulum, 2000 s", a01, "dynamics", 2000.0, 0.01, (1e-3,), ("P1",), PENDULUM_REFERENCE, "m")
    if key == "slider-crank":
        text = (HERE / "slider_crank_coasting.yaml").read_text()
        bodies: tuple[str, ...] = ("crank", "rod", "slider")
        return Problem(key, "slider-crank, coasting, 2 s", text, "dynamics", 2.0, 0.01, (1e-3,), bodies, ONE_DOF_REFERENCE, "m, rad")
    if key in ("quick-return", "quick-return-loaded"):
        bodies = ("crank", "rocker", "slider_b", "link", "slider_d")
        if key == "quick-return":
            return Problem(key, "quick-return A, coasting, 2 s", quick_return, "dynamics", 2.0, 0.01, (1e-3,), bodies, ONE_DOF_REFERENCE, "m, rad")
        # The torque spins the crank up to about 110 rad/s, 0.1 rad per step of 1e-3 s: Exudyn
        # runs at 1e-4 s as well.
        label = "quick-return A, crank torque, 2 s"
        return Problem(
            key, label, quick_return, "dynamics_loaded", 2.0, 0.01, (1e-3, 1e-4), bodies, ONE_DOF_REFERENCE, "m, rad"
        )
    if key == "andrews":
        text = (EXAMPLES / "andrews.yaml").read_text()
        bodies = tuple(f"body{k}" for k in range(1, 8))
        # Its stiff spring and 2.5 crank turns in 0.03 s: Exudyn at 1e-5 s and 1e-6 s (30 steps
        # of 1e-3 s would not resolve it).
        return Problem(key, "Andrews' squeezer, 0.03 s", text, "dynamics", 0.03, 0.001, (1e-5, 1e-6), bodies, ANDREWS_REFERENCE, "relative")
    if key == "a02":
        text = (EXAMPLES / "iftomm_a02_nfourbar.yaml").read_text()
        label = "IFToMM A02 N-four-bar, N = 40, 20 s"
        return Problem(key, label, text, "dynamics", 20.0, 0.01, (1e-3,), ("r0",), NFOURBAR_REFERENCE, "m", sparse=True, assembled=False, n=40)
    if key == "nfourbar":
        label = f"N-four-bar, N = {n}, 1 s"
        return Problem(
            key, label, _nfourbar_text(n), "dynamics", 1.0, 0.01, (1e-3,), ("r0",), NFOURBAR_REFERENCE, "m",
            sparse=True, assembled=False, n=n,
        )
    raise KeyError(key)


PROBLEMS = ("pendulum", "a01", "slider-crank", "quick-return", "quick-return-loaded", "andrews", "a02", "nfourbar")


def _one_dof(problem: Problem, model: linkwork.Model) -> references.OneDof:
    """The quadrature reference of a crank-turned mechanism: its masses from the file, the
    crank's given speed, and the constant crank torque when the analysis applies one."""
    doc = yaml.safe_load(problem.text)
    masses = {b: (float(doc["bodies"][b]["mass"]), float(doc["bodies"][b]["inertia"])) for b in problem.bodies}
    forces = doc.get("forces", {})
    active = doc["analyses"][problem.analysis].get("forces", list(forces))
    torque = sum(float(forces[f]["torque"]) for f in active if forces[f]["type"] == "torque")
    for f in active:
        if forces[f]["type"] != "torque" and any(float(forces[f].get(c, 0)) for c in ("fx", "fy")):
            raise ValueError(f"force {f} is not in the quadrature reference")
    omega0 = float(doc["bodies"]["crank"]["omega"])
    return references.OneDof(model, "kinematics", "crank", masses, omega0, torque)


def error(problem: Problem, model: linkwork.Model, columns: dict[str, np.ndarray]) -> float:
    """The run's error against the problem's reference (unit: `problem.unit`)."""
    time = np.asarray(columns["time"])
    if problem.key in ("pendulum", "a01"):
        x, y = references.pendulum_a01(time)
        return float(max(np.max(np.abs(columns["P1.x"] - x)), np.max(np.abs(columns["P1.y"] - y))))
    if problem.key in ("slider-crank", "quick-return", "quick-return-loaded"):
        return _one_dof(problem, model).error(time, columns)
    if problem.key in ("a02", "nfourbar"):
        psi = references.nfourbar_psi(problem.n, time)
        phi = columns["r0.phi"]
        bx, by = columns["r0.x"] + 0.5 * np.cos(phi), columns["r0.y"] + 0.5 * np.sin(phi)
        return float(max(np.max(np.abs(bx - np.cos(psi))), np.max(np.abs(by - np.sin(psi)))))
    if problem.key == "andrews":
        if not math.isclose(time[-1], problem.t_end, rel_tol=1e-9):
            raise ValueError(f"the run ends at {time[-1]}, not {problem.t_end}")
        worst = 0.0
        for name, (body, relative_to) in references.ANDREWS_ANGLES.items():
            angle = columns[f"{body}.phi"][-1] - (columns[f"{relative_to}.phi"][-1] if relative_to else 0.0)
            want = references.ANDREWS_END[name]
            worst = max(worst, abs((angle - want) / want))
        return worst
    raise KeyError(problem.key)
