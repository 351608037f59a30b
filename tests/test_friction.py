"""Joint friction through the Python API: examples/slider_crank_friction.yaml's inverse analysis,
its friction columns and its efficiency over one turn (the summary `efficiency`), against the
same ratio from the columns and the same mechanism without friction; friction on a joint type
that has none is refused naming the field."""

from __future__ import annotations

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES


def trapezoid(results: linkwork.Results, column: str) -> float:
    """`integral(column dt)` over the run by the trapezoidal rule."""
    t, y = results.time, results[column]
    return float(np.sum(0.5 * np.diff(t) * (y[1:] + y[:-1])))


def test_the_example_reports_its_friction_and_efficiency() -> None:
    """The summary `efficiency` is the ratio of the pump's work to the motor's over the turn: the
    trapezoidal rule over the columns gives it to 1e-6, and the motor's work (43 J) to 1e-5 J (the
    summary integrates through a cubic spline; the two differ by 7.6e-8 and 3.5e-6 J here, where
    the guide's friction reverses within a step of each dead centre, a near-step neither rule
    resolves: crates/linkwork/tests/friction.rs). `peak_torque` is the largest `|motor.effort|`
    at an output time, exactly. Without friction (every `mu` 0) it is 1 to
    `1e-8`: the energies return over a whole turn, and what is left is the multipliers' round-off
    (measured below 5e-10). The friction columns dissipate: the pins' torques oppose the relative
    rotation and the guide's force on ground follows the slider."""
    text = (EXAMPLES / "slider_crank_friction.yaml").read_text()
    results = linkwork.from_yaml(text).run("inverse")
    frame = results.to_pandas()  # indexed by time
    eta = results.summaries["efficiency"]
    assert results.summary.summaries == results.summaries
    assert abs(eta - trapezoid(results, "pump_power") / trapezoid(results, "motor_power")) < 1e-6
    assert abs(results.summaries["motor_work"] - trapezoid(results, "motor_power")) < 1e-5
    assert results.summaries["peak_torque"] == float(np.abs(results["motor.effort"]).max())
    frictionless = linkwork.from_yaml(text).with_parameters(mu_pin=0.0, mu_guide=0.0)
    assert frictionless.parameters["mu_pin"] == 0.0 and frictionless.parameters["mu_guide"] == 0.0
    eta_free = frictionless.run("inverse").summaries["efficiency"]
    assert abs(eta_free - 1.0) < 1e-8
    assert 0.5 < eta < eta_free - 0.01
    # The example's power measures are the engine's own powers: the pump's is what the load takes
    # (-applied_power), the motor's the driver's (rounding).
    np.testing.assert_allclose(results["pump_power"], -results["applied_power"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(results["motor_power"], results["driver_power"], rtol=1e-12, atol=1e-12)
    relative = {"O": frame["crank.omega"], "A": frame["crank.omega"] - frame["rod.omega"]}
    for joint, rate in relative.items():
        assert (frame[f"{joint}.friction"] * rate <= 0).all(), joint
    assert (frame["guide.friction"] * frame["slider.vx"] >= 0).all()


def test_friction_on_a_joint_without_a_friction_model_is_refused() -> None:
    """A distance joint has no friction model: its `friction:` is refused at its path, saying
    which joint types take one."""
    model = """
bodies:
  bar: {mass: 1, inertia: 0.1, position: [0.5, 0]}
joints:
  link: {type: distance, body_i: bar, point_i: [-0.5, 0], body_j: ground, point_j: [0, 0],
         friction: {mu: 0.1, radius: 0.01}}
"""
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(model)
    problems = dict(error.value.problems)
    assert "supported on revolute and translational joints" in problems["joints.link.friction"]
