"""Inverse dynamics, statics and modes from Python and the command line."""

from __future__ import annotations

import csv
import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, WriteModel, patch

# (mass, inertia) of each body, as in the model files.
BODIES: dict[str, dict[str, tuple[float, float]]] = {
    "a": {"crank": (1000, 2000), "rocker": (100, 100), "slider_b": (5, 0.05), "link": (30, 10), "slider_d": (20, 1.5)},
    "b": {"crank": (1000, 2000), "rocker": (100, 100), "link": (30, 10)},
}


@pytest.mark.parametrize("variant", ["a", "b"])
def test_quick_return_inverse_balances_power(variant: str) -> None:
    """The crank torque's power equals the rate of change of kinetic energy (no gravity, no load),
    computed from the body columns alone: `dT/dt = sum m v.a + J omega alpha`. Tolerance 1e-8 of
    the largest power: the multipliers solve a linear system exactly, the rest is rounding."""
    results = linkwork.load(EXAMPLES / f"quick_return_{variant}.yaml").run("inverse")
    assert len(results) == 41
    dt = sum(
        m * (results[f"{b}.vx"] * results[f"{b}.ax"] + results[f"{b}.vy"] * results[f"{b}.ay"])
        + j * results[f"{b}.omega"] * results[f"{b}.alpha"]
        for b, (m, j) in BODIES[variant].items()
    )
    motor = results["crank_drive.effort"] * results["crank.omega"]
    scale = np.abs(motor).max()
    assert np.abs(motor - dt).max() < 1e-8 * scale
    assert np.allclose(results["crank.omega"], 2 * np.pi, rtol=0, atol=1e-9)
    peak = results.summary["peaks"]["crank_drive.effort"]
    assert peak["max_abs"] == np.abs(results["crank_drive.effort"]).max()


def test_quick_return_models_share_the_motion_not_the_torque() -> None:
    """A and B move alike under the same driver (their kinematics agree), but A's sliders carry
    mass, so A needs more torque: the torques differ exactly by the sliders' power over omega."""
    a = linkwork.load(EXAMPLES / "quick_return_a.yaml").run("inverse")
    b = linkwork.load(EXAMPLES / "quick_return_b.yaml").run("inverse")
    assert np.abs(a["rocker.phi"] - b["rocker.phi"]).max() < 1e-9
    sliders = sum(
        m * (a[f"{s}.vx"] * a[f"{s}.ax"] + a[f"{s}.vy"] * a[f"{s}.ay"]) + j * a[f"{s}.omega"] * a[f"{s}.alpha"]
        for s, (m, j) in (("slider_b", (5, 0.05)), ("slider_d", (20, 1.5)))
    )
    difference = (a["crank_drive.effort"] - b["crank_drive.effort"]) * 2 * np.pi
    assert np.abs(difference - sliders).max() < 1e-8 * np.abs(a["crank_drive.effort"]).max() * 2 * np.pi


def test_cli_inverse_writes_reactions_and_crank_torque(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = linkwork("run", EXAMPLES / "quick_return_a.yaml", "--analysis", "inverse", "--out", "inv")
    assert out.code == 0, out.output
    assert "peak crank_drive.effort" in out.stdout
    with open(tmp_path / "inv" / "results.csv") as f:
        header = next(csv.reader(f))
    for joint in ("O", "A", "B", "B_slot", "C", "D", "D_guide"):
        for q in ("fx", "fy", "torque"):
            assert f"{joint}.{q}" in header
    assert "crank_drive.effort" in header
    summary = json.loads((tmp_path / "inv" / "summary.json").read_text())
    assert summary["type"] == "inverse" and summary["status"] == "ok"
    assert set(summary["peaks"]) >= {"crank_drive.effort", "O.force", "O.torque"}


def test_cli_static_and_modes(linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path) -> None:
    model = write_model(
        """
        gravity: [0, -9.81]
        bodies:
          bob: {mass: 2.0, inertia: 0.0, position: [0.3, -0.9], angle: 0.3, points: {P: [0, 1]}}
        joints:
          pivot: {type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}
        analyses:
          rest: {type: static}
          swing: {type: modes}
        """
    )
    out = linkwork("run", model, "--analysis", "rest", "--out", "rest")
    assert out.code == 0, out.output
    assert "stable: True" in out.stdout
    out = linkwork("run", model, "--analysis", "swing", "--out", "swing")
    assert out.code == 0, out.output
    assert "mode 1: 0.498" in out.stdout  # sqrt(9.81) / (2 pi) = 0.49849 Hz
    with open(tmp_path / "swing" / "modes.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1
    assert abs(float(rows[0]["frequency"]) - np.sqrt(9.81) / (2 * np.pi)) < 1e-9
    # The bob swings about the pivot 1 m above it: x and phi move alike, y not at all.
    assert abs(float(rows[0]["bob.phi"]) - float(rows[0]["bob.x"])) < 1e-12
    assert max(abs(float(rows[0]["bob.phi"])), abs(float(rows[0]["bob.x"]))) == 1.0
    assert abs(float(rows[0]["bob.y"])) < 1e-12


def test_results_modes_from_python() -> None:
    model = linkwork.Model.from_yaml(
        """
gravity: [0, 0]
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0.3, 0], angle: 0}
joints:
  guide: {type: translational, body_i: ground, point_i: [0, 0], axis_i: [1, 0], body_j: block, point_j: [0, 0], axis_j: [1, 0]}
forces:
  spring: {type: spring_damper, body_i: ground, point_i: [-1, 0], body_j: block, point_j: [0, 0], stiffness: 800, damping: 12, free_length: 1.2}
analyses:
  shake: {type: modes}
"""
    )
    results = model.run("shake")
    (mode,) = results.modes
    assert abs(mode["frequency"] * 2 * np.pi - 20.0) < 1e-9
    assert abs(mode["damping_ratio"] - 12 / (2 * 40)) < 1e-10
    assert mode["shape"]["block.x"] == 1.0


def test_static_free_mechanism_is_a_model_error(linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path) -> None:
    model = write_model(
        """
        gravity: [0, 0]
        bodies:
          wheel: {mass: 1, inertia: 0.1, position: [0, 0], angle: 0}
        joints:
          axle: {type: revolute, body_i: wheel, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
        analyses:
          rest: {type: static}
          inv: {type: inverse, t_end: 1, step: 0.1}
        """
    )
    out = linkwork("run", model, "--analysis", "rest")
    assert out.code == 2, out.output
    assert "analyses.rest" in out.stderr and "free to move (wheel.phi)" in out.stderr
    out = linkwork("run", model, "--analysis", "inv")
    assert out.code == 2, out.output
    assert "an inverse analysis needs a fully driven model" in out.stderr
    out = linkwork("check", model)
    assert "a static analysis needs every degree of freedom held" in out.stdout
    # A modes analysis about the equilibrium says it is one, not "a static analysis".
    (tmp_path / "vib.yaml").write_text(patch(model.read_text(), "inv: {type: inverse, t_end: 1, step: 0.1}", "vib: {type: modes}"))
    out = linkwork("run", tmp_path / "vib.yaml", "--analysis", "vib")
    assert out.code == 2, out.output
    assert "analyses.vib: a modes analysis needs every degree of freedom held" in out.stderr
    assert "a static analysis" not in out.stderr


def test_check_names_indeterminate_joints(linkwork: RunLinkwork) -> None:
    out = linkwork("check", EXAMPLES / "parallelogram.yaml")
    assert out.code == 0
    assert "indeterminate joints ground_1, coupler_1, ground_2, coupler_2, ground_3, coupler_3" in out.stdout


# A compound pendulum: mass M (kg), inertia JC about its centre of mass (kg m^2), pivot L (m)
# above the centre of mass in the body frame; RATE = sqrt(M g L / J_O), J_O = JC + M L^2, 1/s.
M, JC, L, G = 4.0, 0.3, 0.5, 9.81
RATE = float(np.sqrt(M * G * L / (JC + M * L * L)))


def pendulum(angle: float, extra: str = "", analyses: str = "") -> str:
    """The compound pendulum with its centre of mass placed at `angle` about the pivot (0, 0)."""
    x, y = float(L * np.sin(angle)), float(-L * np.cos(angle))
    return f"""
        gravity: [0, -{G}]
        bodies:
          bob: {{mass: {M}, inertia: {JC}, position: [{x!r}, {y!r}], angle: {angle!r}, points: {{P: [0, {L}]}}{extra}}}
        joints:
          pivot: {{type: revolute, body_i: bob, point_i: P, body_j: ground, point_j: [0, 0]}}
        analyses:
          {analyses}
        """


def twisted_pendulum() -> str:
    """The pendulum with a static analysis under a torque of 2 M g L, more than its weight can
    hold: it turns without end, and no equilibrium exists."""
    twist = f"        forces:\n          twist: {{type: torque, body: bob, torque: {2 * M * G * L}}}\n"
    return patch(pendulum(0.0, analyses="rest: {type: static}"), "        analyses:", f"{twist}        analyses:")


def test_cli_horizontal_pendulum_hangs_down_and_swings(linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path) -> None:
    """Released level, where its rod carries no tension and the guess has no stiffness, gravity
    still loads it: the static analysis hangs it straight down (closed form (0, -L), 1e-12 m) and
    the modes analysis finds sqrt(M g L / J_O) / (2 pi) Hz (1e-9 relative: the geometric
    stiffness's central difference). Both used to stop with "free to move"."""
    model = write_model(pendulum(np.pi / 2, analyses="rest: {type: static}\n          swing: {type: modes}"))
    out = linkwork("run", model, "--analysis", "rest", "--out", "rest")
    assert out.code == 0, out.output
    assert "stable: True (index 0)" in out.stdout
    with open(tmp_path / "rest" / "results.csv") as f:
        row = next(csv.DictReader(f))
    assert abs(float(row["bob.x"])) < 1e-12 and abs(float(row["bob.y"]) + L) < 1e-12
    summary = json.loads((tmp_path / "rest" / "summary.json").read_text())
    assert summary["stable"] is True and summary["index"] == 0 and summary["statistics"]["descents"] == 1
    out = linkwork("run", model, "--analysis", "swing", "--out", "swing")
    assert out.code == 0, out.output
    with open(tmp_path / "swing" / "modes.csv") as f:
        (mode,) = list(csv.DictReader(f))
    assert mode["kind"] == "vibration" and mode["growth_rate"] == ""
    assert abs(float(mode["frequency"]) - RATE / (2 * np.pi)) < 1e-9 * RATE


def test_cli_inverted_pendulum_modes_are_flagged_unstable(linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path) -> None:
    """Linearised where it stands upside down, the pendulum's one eigenvalue is +sqrt(M g L / J_O):
    a divergence, printed and written as unstable with its growth rate (closed form, 1e-9), never
    as a frequency with damping ratio -1."""
    model = write_model(pendulum(np.pi, ", given: [x, y, phi]", "here: {type: modes, about: initial}"))
    out = linkwork("run", model, "--out", "here")
    assert out.code == 0, out.output
    assert "UNSTABLE" in out.stdout and "mode 1: unstable, divergence" in out.stdout
    assert "damping ratio" not in out.stdout and " Hz" not in out.stdout
    summary = json.loads((tmp_path / "here" / "summary.json").read_text())
    assert summary["stable"] is False
    (mode,) = summary["modes"]
    assert mode["kind"] == "divergence" and mode["frequency"] is None and mode["damping_ratio"] is None
    assert abs(mode["growth_rate"] - RATE) < 1e-9 * RATE
    with open(tmp_path / "here" / "modes.csv") as f:
        (row,) = list(csv.DictReader(f))
    assert row["kind"] == "divergence" and row["frequency"] == "" and row["damping_ratio"] == ""
    assert abs(float(row["growth_rate"]) - RATE) < 1e-9 * RATE


def test_cli_torque_beyond_the_weight_has_no_equilibrium(linkwork: RunLinkwork, write_model: WriteModel) -> None:
    """A torque of 2 M g L turns the pendulum without end: the static analysis stops with exit 3
    and says that no equilibrium exists, naming the coordinate that turns and no joint."""
    model = write_model(twisted_pendulum())
    out = linkwork("run", model, "--out", "rest")
    assert out.code == 3, out.output
    assert "no stable static equilibrium found at t = 0" in out.stderr and "none exists" in out.stderr
    assert "bob.phi" in out.stderr and "in joint(s)" not in out.stderr


def test_no_equilibrium_is_an_equilibrium_error() -> None:
    """From Python the same failure is an EquilibriumError (a ConvergenceError, a SolverError),
    with the coordinates that move, no joints, `index` None (no equilibrium at all), and the
    summary of the partial results flagged not stable."""
    model = linkwork.Model.from_yaml(textwrap.dedent(twisted_pendulum()))
    with pytest.raises(linkwork.EquilibriumError) as caught:
        model.run("rest")
    error = caught.value
    assert isinstance(error, linkwork.ConvergenceError)
    assert error.index is None and "bob.phi" in error.coordinates and error.joints == []
    assert error.time == 0.0 and "none exists" in error.cause
    assert error.results.summary["stable"] is False


def test_hanging_fourbar_example_rests_stable_and_vibrates() -> None:
    """The example starts near its potential energy's maximum; the static analysis leaves it for
    the minimum (checked against the energy along the closed-loop path in the Rust tests), and the
    modes analysis about it finds one stable vibration."""
    model = linkwork.load(EXAMPLES / "hanging_fourbar.yaml")
    rest = model.run("rest")
    assert rest.summary["stable"] is True and rest.summary["index"] == 0
    assert rest.summary["statistics"]["descents"] == 1
    # The minimum, 4.57694 rad modulo a turn (angles are unwrapped); the maximum is at 1.550 rad.
    assert abs(np.remainder(rest["crank.phi"][0], 2 * np.pi) - 4.57694) < 1e-5
    vibration = model.run("vibration")
    (mode,) = vibration.modes
    assert vibration.summary["stable"] is True and mode["kind"] == "vibration" and mode["frequency"] > 0
