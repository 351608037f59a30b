"""Design sensitivities from Python and the command line (docs/sensitivities.md): the slider-crank
of ``examples/slider_crank_param.yaml`` with summaries added, its derivatives against central
differences of whole runs and against the stroke's closed form, the files the command line
writes, display units, and the errors."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork

# Summaries added to the example's `stroke` (closed form d/dr = 2, d/dL = 0), which ends the
# file: an integral-based one, and one that reads a parameter and a value between rows.
SUMMARIES = """  speed_rms: "rms(slider.vx)"
  late: "at(0.3021, slider.x) - r"
"""


def model_text() -> str:
    text = (EXAMPLES / "slider_crank_param.yaml").read_text()
    assert text.rstrip().splitlines()[-1].startswith("  stroke:"), "the example no longer ends with its summaries"
    return text + SUMMARIES


@pytest.fixture(scope="module")
def model() -> linkwork.Model:
    return linkwork.from_yaml(model_text())


@pytest.fixture(scope="module")
def results(model: linkwork.Model) -> linkwork.Results:
    return model.run("kinematics", sensitivities=["r", "L"])


def quantities(results: linkwork.Results) -> dict[str, np.ndarray]:
    """What is compared: the slider's and the rod's positions and the crank's speed (columns),
    and every summary (as a one-element array)."""
    columns = {name: np.array(results[name]) for name in ("slider.x", "rod.phi", "slider.vx", "rod.alpha")}
    return columns | {name: np.array([value]) for name, value in results.summaries.items()}


@pytest.mark.parametrize("parameter", ["r", "L"])
def test_derivatives_match_differences_of_whole_runs(
    model: linkwork.Model, results: linkwork.Results, parameter: str
) -> None:
    """Each derivative against central differences of whole runs with the parameter set
    (``with_parameters``, as ``--set`` does) at ``p -+ h`` and ``p -+ h/2``, Richardson-
    extrapolated: ``(4 D(h/2) - D(h)) / 3``, truncation ``O(h^4)``. ``h`` is 1e-3 of the parameter:
    the positions are converged to about 1e-12 of the mechanism's size, so a difference's round-off
    is about 1e-12 / 1e-3 = 1e-9 of a column's scale and the truncation (1e-3)^4 = 1e-12, both below
    the tolerance, 1e-7 of the quantity's largest derivative or 1e-10 absolute (for one that the
    parameter does not move). The output times are the same in every run (``t_end`` depends on
    the speed only)."""
    assert_matches_differences(model, "kinematics", results, parameter, quantities)


def assert_matches_differences(
    model: linkwork.Model,
    analysis: str,
    results: linkwork.Results,
    parameter: str,
    quantities: Callable[[linkwork.Results], dict[str, np.ndarray]],
) -> None:
    """Each of the ``quantities`` of ``results`` (a run of ``analysis`` with sensitivities),
    differentiated with respect to ``parameter``, against the Richardson-extrapolated central
    differences of whole runs of ``test_derivatives_match_differences_of_whole_runs``."""
    value = model.parameters[parameter]
    h = 1e-3 * value

    def run(p: float) -> dict[str, np.ndarray]:
        return quantities(model.with_parameters(**{parameter: p}).run(analysis))

    def differences(step: float) -> dict[str, np.ndarray]:
        up, down = run(value + step), run(value - step)
        return {name: (up[name] - down[name]) / (2 * step) for name in up}

    coarse, fine = differences(h), differences(h / 2)
    for name, exact_si in quantities(results).items():
        exact = (
            results.sensitivity(name, parameter)
            if name in results.columns
            else np.array([results.sensitivity(name, parameter)])
        )
        approx = (4 * fine[name] - coarse[name]) / 3
        scale = np.max(np.abs(exact))
        error = np.max(np.abs(exact - approx))
        assert error <= 1e-7 * scale + 1e-10, f"d({name})/d({parameter}): error {error:.2e} of {scale:.2e}"
        assert exact_si.shape == approx.shape


@pytest.mark.parametrize("parameter", ["r", "rho"])
def test_inverse_derivatives_match_differences_of_whole_runs(model: linkwork.Model, parameter: str) -> None:
    """The inverse analysis of the same slider-crank: the motor's effort and two pins'
    reactions, from Python, against the same differences (the multipliers are as converged as
    the positions, so the same tolerance holds); the effort's peak has its derivative in the
    summary."""

    def efforts(results: linkwork.Results) -> dict[str, np.ndarray]:
        return {name: np.array(results[name]) for name in ("motor.effort", "O.fx", "A.fy")}

    results = model.run("inverse", sensitivities=[parameter])
    assert results.summary.sensitivities is not None and "motor.effort" in results.summary.sensitivities
    assert_matches_differences(model, "inverse", results, parameter, efforts)


def test_the_stroke_has_its_closed_form_derivatives(results: linkwork.Results) -> None:
    """The stroke of a centred slider-crank is 2 r: the rows at crank angles 0 and pi (t = 0 and
    0.5 s are rows) give d/dr = 2 and d/dL = 0, to round-off (1e-12)."""
    assert abs(float(results.sensitivity("stroke", "r")) - 2.0) < 1e-12
    assert abs(float(results.sensitivity("stroke", "L"))) < 1e-12
    # `late` reads r itself: d/dr is the slider's derivative at 0.3021 s (between rows) less 1.
    assert results.summary.sensitivities is not None
    assert set(results.summary.sensitivities) == {"stroke", "speed_rms", "late"}


def test_the_frame_and_the_arrays_agree(results: linkwork.Results, model: linkwork.Model) -> None:
    frame = results.sensitivities
    assert frame is not None
    columns = [name for name in results.columns]
    assert list(frame.columns) == ["time"] + [f"d({c})/d({p})" for p in ("r", "L") for c in columns]
    assert np.array_equal(frame["time"], results.time)
    assert np.array_equal(frame["d(slider.x)/d(L)"], results.sensitivity("slider.x", "L"))
    # True: every parameter, in file order.
    everything = model.run("kinematics", sensitivities=True).sensitivities
    assert everything is not None
    assert [c for c in everything.columns if c.startswith("d(slider.x)/")] == [
        f"d(slider.x)/d({p})" for p in model.parameters
    ]
    assert model.run("kinematics").sensitivities is None


def test_display_units(results: linkwork.Results) -> None:
    """``display: {length: mm, angle: deg}`` and ``r: 100 mm``: a length per r is mm per mm (the
    SI value), an angle per r is degrees per mm, a summary (no known unit) is SI per mm."""
    si = results.sensitivity("slider.x", "r")
    assert np.allclose(results.sensitivity("slider.x", "r", units="display"), si, rtol=1e-15, atol=0)
    angle = results.sensitivity("rod.phi", "r")
    assert np.allclose(results.sensitivity("rod.phi", "r", units="display"), angle * 180 / math.pi / 1000, rtol=1e-14)
    assert math.isclose(results.sensitivity("stroke", "r", units="display"), 2e-3, rel_tol=1e-12)


def test_the_command_line_writes_the_files(linkwork: RunLinkwork, tmp_path: Path, results: linkwork.Results) -> None:
    path = tmp_path / "crank.yaml"
    path.write_text(model_text())
    done = linkwork("run", path, "--analysis", "kinematics", "--sensitivities", "r,L", "--no-report")
    assert done.code == 0, done.output
    out = tmp_path / "out" / "crank"
    assert "sensitivities.csv" in done.stdout
    with (out / "sensitivities.csv").open() as f:
        rows = list(csv.reader(f))
    frame = results.sensitivities
    assert frame is not None
    assert rows[0] == list(frame.columns)
    assert np.array_equal(np.array(rows[1:], dtype=float), frame.to_numpy())
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sensitivities"] == results.summary.sensitivities
    # Without the option: neither the file nor the key, and the folder is replaced as a run's.
    done = linkwork("run", path, "--no-report")
    assert done.code == 0, done.output
    assert not (out / "sensitivities.csv").exists()
    assert "sensitivities" not in json.loads((out / "summary.json").read_text())


def test_bad_names_are_one_line_errors(linkwork: RunLinkwork, tmp_path: Path, model: linkwork.Model) -> None:
    done = linkwork("run", EXAMPLES / "slider_crank_param.yaml", "--sensitivities", "r,stroke")
    assert done.code == 2, done.output
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --sensitivities: ") and "'stroke'" in lines[0], lines
    assert "r, L, speed" in lines[0]  # the parameters there are
    # A dynamic analysis integrated by hht has none (bdf and abam have): the error names the option.
    done = linkwork("run", EXAMPLES / "quick_return_a.yaml", "--analysis", "dynamics", "--integrator", "hht",
                    "--sensitivities", "all")
    assert done.code == 2 and "\n--integrator: " in done.stderr and "use bdf or abam" in done.stderr, done.output
    done = linkwork("run", EXAMPLES / "slider_crank_param.yaml", "--sensitivities", "r,,L")
    assert done.code == 2 and "--sensitivities" in done.stderr, done.output
    assert not (tmp_path / "out" / "slider_crank_param" / "sensitivities.csv").exists()


def test_python_errors(model: linkwork.Model, results: linkwork.Results) -> None:
    with pytest.raises(linkwork.ModelError) as unknown:
        model.run("kinematics", sensitivities=["radius"])
    assert unknown.value.problems[0][0] == "sensitivities" and "radius" in unknown.value.problems[0][1]
    with pytest.raises(linkwork.ModelError, match="list of parameter names"):
        model.run("kinematics", sensitivities="r")  # a str is a sequence of names to a type checker
    with pytest.raises(ValueError, match="no sensitivities"):
        model.run("kinematics").sensitivity("slider.x", "r")
    with pytest.raises(KeyError, match="speed"):
        results.sensitivity("slider.x", "speed")
    with pytest.raises(KeyError, match="slider.q"):
        results.sensitivity("slider.q", "r")
    with pytest.raises(ValueError, match="units"):
        results.sensitivity("slider.x", "r", units="imperial")
