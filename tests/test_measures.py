"""Measures over the reaction and effort columns and the standard measures, through the Python
API: examples/fourbar_measures.yaml against the four-bar's closed forms (the same as
crates/linkwork/tests/measures.rs, with the tolerances argued there), and a measure an analysis
cannot compute refused at its path."""

from __future__ import annotations

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, patch

PATH = EXAMPLES / "fourbar_measures.yaml"
# The example's crank, coupler, rocker and ground, m, and its brake's load, N m.
A, B, C, D, LOAD = 0.1, 0.3, 0.25, 0.3, 1.5


def closed_position(theta2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The coupler's and the rocker's angles at crank angles ``theta2`` (open assembly): B where
    the circles about A (radius b) and O4 (radius c) meet, left of the line from A to O4."""
    ax, ay = A * np.cos(theta2), A * np.sin(theta2)
    ex, ey = D - ax, -ay
    e = np.hypot(ex, ey)
    ux, uy = ex / e, ey / e
    along = (B * B - C * C + e * e) / (2 * e)
    h = np.sqrt(B * B - along * along)
    bx, by = ax + along * ux - h * uy, ay + along * uy + h * ux
    return np.arctan2(by - ay, bx - ax), np.arctan2(by, bx - D)


def test_transmission_angle_and_velocity_ratio_match_the_closed_forms() -> None:
    """mu by the law of cosines (folded to the acute angle), vr by the four-bar's velocity
    formula; 1e-10 (measured 6e-12 rad and 4e-12)."""
    results = linkwork.load(PATH).run("inverse")
    theta2 = 2 * results.time
    gamma = np.arccos((B * B + C * C - A * A - D * D + 2 * A * D * np.cos(theta2)) / (2 * B * C))
    mu = np.minimum(gamma, np.pi - gamma)
    theta3, theta4 = closed_position(theta2)
    vr = A * np.sin(theta2 - theta3) / (C * np.sin(theta4 - theta3))
    assert np.any(gamma > np.pi / 2) and np.any(gamma < np.pi / 2), "the run crosses 90 degrees"
    assert np.max(np.abs(results["mu"] - mu)) <= 1e-10
    assert np.max(np.abs(results["vr"] - vr) / np.maximum(1, np.abs(vr))) <= 1e-10


def test_mechanical_advantage_is_the_inverse_velocity_ratio_when_massless() -> None:
    """With rho = 0 the motor's power is the brake's: ma = omega2 / omega4, to 1e-10 + 1e-11 |ma|
    relative (the positions' 1e-11 rad moves vr by as much absolute); the pin B, on a
    two-force coupler, carries load / (c |sin(theta4 - theta3)|)."""
    results = linkwork.load(PATH, parameters={"rho": 0}).run("inverse")
    theta2 = 2 * results.time
    theta3, theta4 = closed_position(theta2)
    inverse_vr = C * np.sin(theta4 - theta3) / (A * np.sin(theta2 - theta3))
    ma = results["ma"]
    assert np.all(np.abs(ma - inverse_vr) <= (1e-10 + 1e-11 * np.abs(inverse_vr)) * np.abs(inverse_vr))
    pin = LOAD / (C * np.abs(np.sin(theta4 - theta3)))
    assert np.max(np.abs(results["B_load"] - pin) / pin) <= 1e-10
    power = results["motor.effort"] * results["crank.omega"]
    assert np.array_equal(results["motor_power"], power)


def test_a_reaction_measure_in_a_kinematic_analysis_is_refused_at_its_path() -> None:
    text = patch(
        PATH.read_text(),
        "  inverse: {type: inverse,",
        "  kin: {type: kinematic, drivers: [motor], t_end: 1, step: 0.1}\n  inverse: {type: inverse,",
    )
    model = linkwork.from_yaml(text)
    with pytest.raises(linkwork.ModelError) as error:
        model.run("kin")
    problems = dict(error.value.problems)
    assert set(problems) == {"measures.ma", "measures.B_load", "measures.motor_power"}
    assert "it reads B.fx, a joint reaction or driver effort, which the kinematic analysis 'kin'" in problems[
        "measures.B_load"
    ]
    assert "expected an inverse, static or dynamic analysis" in problems["measures.B_load"]
    # Unknown names in a standard measure: each at its field.
    bad = patch(text, "input: motor, output: brake}", "input: motr, output: brake}")
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(bad)
    assert any(
        path == "measures.ma.input" and "unknown driver or torque 'motr'; expected one of: motor, brake" in message
        for path, message in error.value.problems
    )
