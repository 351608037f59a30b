"""Dynamics from Python and the command line: overrides, reactions in the body frame, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import linkwork
import linkwork as linkwork_module
from conftest import EXAMPLES, ROOT, RunLinkwork, pendulum_with_torque


def test_overrides_change_the_run() -> None:
    model = linkwork.load(EXAMPLES / "double_pendulum.yaml")
    results = model.run("dynamics_hht", t_end=0.5, step=0.1, rtol=1e-7)
    assert len(results) == 6
    assert results.summary["integrator"]["kind"] == "hht"
    assert results.summary["integrator"]["rtol"] == 1e-7
    for name in ("O.fx", "O.fy", "O.torque", "kinetic_energy", "potential_energy", "tip_x"):
        assert name in results
    # An integrator the analysis does not name runs in its place: abam, whose steps are those of
    # the file's own abam analysis, and which partitions the coordinates (hht never does).
    other = model.run("dynamics_hht", integrator="abam", t_end=0.2, step=0.1)
    assert other.summary["integrator"]["kind"] == "abam"
    assert other.summary["statistics"] == model.run("dynamics_abam", t_end=0.2, step=0.1).summary["statistics"]
    assert other.summary["statistics"]["partitions"] >= 1
    assert model.run("dynamics_hht", t_end=0.2, step=0.1).summary["statistics"]["partitions"] == 0


def test_bad_override_is_a_model_error() -> None:
    model = linkwork.load(EXAMPLES / "double_pendulum.yaml")
    with pytest.raises(linkwork.ModelError) as info:
        model.run("dynamics_hht", rtol=0.0)
    assert info.value.problems[0][0] == "--rtol"
    with pytest.raises(linkwork.ModelError) as info:
        model.run("dynamics_hht", integrator="rk4")
    assert info.value.problems[0][0] == "--integrator"
    # A bool is an int to Python; True ran as rtol 1.0 before.
    with pytest.raises(linkwork.ModelError) as info:
        model.run("dynamics_hht", rtol=True)
    assert info.value.problems == [("--rtol", "expected a number, found True (a bool)")]
    # Text was a TypeError from the bindings (found by tests/test_properties.py).
    with pytest.raises(linkwork.ModelError) as info:
        model.run("dynamics_hht", step="0.1")  # type: ignore[arg-type]  # the wrong type is the test
    assert info.value.problems == [("--step", "expected a number, found '0.1' (str)")]


def test_reaction_in_the_body_frame_is_the_rotated_global_one() -> None:
    results = linkwork.load(EXAMPLES / "double_pendulum.yaml").run("dynamics_hht", t_end=0.5)
    fx, fy, torque = results.reaction("E")
    bx, by, btorque = results.reaction("E", frame="body")
    phi = results["upper.phi"]
    # Rotating back by +phi recovers the global components; the magnitude is unchanged.
    assert np.allclose(np.cos(phi) * bx - np.sin(phi) * by, fx, rtol=1e-12, atol=1e-12)
    assert np.allclose(np.hypot(bx, by), np.hypot(fx, fy), rtol=1e-12)
    assert np.array_equal(btorque, torque)
    with pytest.raises(ValueError):
        results.reaction("E", frame="local")


def test_cli_overrides_and_dynamic_summary(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = tmp_path / "dp"
    done = linkwork(
        "run", EXAMPLES / "double_pendulum.yaml", "-a", "dynamics_hht", "--t-end", "0.3", "--rtol", "1e-5", "-o", out
    )
    assert done.code == 0, done.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["integrator"]["rtol"] == 1e-5
    assert summary["output_points"] == 31
    assert "hht:" in done.stdout and "steps" in done.stdout
    bad = linkwork("run", EXAMPLES / "double_pendulum.yaml", "-a", "dynamics_hht", "--atol", "0")
    assert bad.code == 2
    assert "--atol" in bad.stderr
    kin = linkwork("run", EXAMPLES / "fourbar.yaml", "--integrator", "hht")
    assert kin.code == 2
    assert "only a dynamic analysis" in kin.stderr


SWITCHING_TORQUE = pendulum_with_torque("(t-0.5)/abs(t-0.5)", 0.1, name="flip")


def test_a_nan_torque_is_a_non_finite_error(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """0/0 at t = 0.5 s ran to the end with status ok and NaN in the results; now it stops there
    naming the force, exits 3 and keeps the rows before it."""
    path = tmp_path / "switch.yaml"
    path.write_text(SWITCHING_TORQUE)
    with pytest.raises(linkwork_module.NonFiniteError) as info:
        linkwork_module.load(path).run("dynamics")
    error = info.value
    assert isinstance(error, linkwork_module.SolverError)
    assert (error.element, error.expression, error.time) == ("forces.flip", "torque: (t-0.5)/abs(t-0.5)", 0.5)
    assert np.isnan(error.value)
    assert len(error.results) == 5 and np.isfinite(error.results["bar.alpha"]).all()
    out = tmp_path / "out"
    done = linkwork("run", path, "-o", out)
    assert done.code == 3, done.output
    assert "forces.flip is NaN at t = 0.5 s (torque: (t-0.5)/abs(t-0.5))" in done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["error_time"] == 0.5


STIFF_SPRING = (ROOT / "crates" / "linkwork" / "tests" / "models" / "stiff_spring.yaml").read_text()


def test_a_conservative_system_that_loses_its_energy_raises_accuracy_error() -> None:
    """A spring of 1e12 N/m under bdf at the default tolerances loses most of its energy in 1 ms:
    the run raises AccuracyError (a SolverError) with what was checked, its value and bound, the
    time, and every row in `results`, whose energies show the loss."""
    model = linkwork.from_yaml(STIFF_SPRING)
    with pytest.raises(linkwork.AccuracyError) as caught:
        model.run("free")
    error = caught.value
    assert isinstance(error, linkwork.SolverError)
    assert error.quantity == "energy drift" and error.value > error.bound == 0.5
    assert error.rows == [] and 0 < error.time <= 1e-3
    assert "use abam" in error.detail
    results = error.results
    assert len(results) == 11
    energy = results["kinetic_energy"] + results["potential_energy"]
    assert energy[-1] < 0.5 * energy[0]
    assert results.summary["status"] == "failed"
