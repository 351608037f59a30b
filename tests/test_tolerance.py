"""Tolerances: a parameter's tolerance in the model file, the tolerance analysis (linear beside
Monte Carlo, `linkwork.tolerance` and `linkwork tolerance`) and sweeps with gradients.

The slider-crank's stroke is 2 r exactly (its crank angles include 0 and pi), so every number of
its linear analysis has a closed form: d stroke / d r = 2, d stroke / d L = 0, worst case 2 t_r,
root sum of squares 2 sigma_r, r's share 1; and its Monte Carlo samples are 2 r exactly, so
their spread is 2 sigma_r up to the sampling error, which the confidence interval bounds.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import linkwork
from linkwork.model import Tolerance

from conftest import EXAMPLES, RunLinkwork, patch

MODEL = EXAMPLES / "slider_crank_param.yaml"
TEXT = MODEL.read_text(encoding="utf-8")
STROKE = "max(slider.x) - min(slider.x)"
PARAMETERS = list(linkwork.load(MODEL).parameters)
T_R, T_L = 0.1e-3, 0.2e-3
# The derivatives are exact to rounding: the stroke's rows are those of the same angles for
# every parameter, so 1e-9 of the derivative's size leaves room for the run's convergence only.
EXACT = 1e-9


def test_the_example_gives_its_tolerances_and_a_value_given_keeps_them() -> None:
    model = linkwork.load(MODEL)
    assert model.tolerances == {
        "r": Tolerance(T_R, "normal", T_R / 3),
        "L": Tolerance(T_L, "normal", T_L / 3),
    }
    moved = model.with_parameters(r="120 mm")
    assert moved.parameters["r"] == pytest.approx(0.12, rel=1e-15) and moved.tolerances == model.tolerances
    uniform = linkwork.from_yaml(patch(TEXT, "r: 100 mm ± 0.1 mm", "r: {value: 100 mm, tolerance: 0.1 mm, distribution: uniform}"))
    assert uniform.tolerances["r"] == Tolerance(T_R, "uniform", T_R / math.sqrt(3))


def test_a_tolerance_leaves_the_run_bit_identical() -> None:
    plain = linkwork.from_yaml(patch(patch(TEXT, "r: 100 mm ± 0.1 mm", "r: 100 mm"), "L: 300 mm ± 0.2 mm", "L: 300 mm"))
    assert plain.tolerances == {}
    a, b = plain.run("kinematics"), linkwork.load(MODEL).run("kinematics")
    assert np.array_equal(a.values, b.values) and a.summaries == b.summaries


def test_a_bad_tolerance_names_its_field() -> None:
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(patch(TEXT, "r: 100 mm ± 0.1 mm", "r: 100 mm ± 0.1 kg"))
    assert ("parameters.r.tolerance", "'0.1 kg' is a mass, expected a length") in error.value.problems or any(
        path == "parameters.r.tolerance" and "mass" in message for path, message in error.value.problems
    ), error.value.problems


def test_the_stroke_has_the_closed_form_linear_spread_and_monte_carlo_agrees() -> None:
    """Done-when, with 2000 samples (the 10^4 case is run and recorded in docs/sensitivities.md)."""
    result = linkwork.tolerance(MODEL, "kinematics", {"stroke": "stroke", "expr": STROKE}, samples=2000, seed=7)
    for name in ("stroke", "expr"):
        o = result.outputs[name]
        assert o.nominal == pytest.approx(0.2, rel=1e-12)
        assert o.gradient["r"] == pytest.approx(2.0, rel=EXACT) and abs(o.gradient["L"]) < EXACT
        assert o.worst_case == pytest.approx(2 * T_R, rel=EXACT)
        assert o.rss == pytest.approx(2 * T_R / 3, rel=EXACT)
        assert o.shares["r"] == pytest.approx(1.0, abs=EXACT)
        mc = o.monte_carlo
        assert mc is not None and mc.samples == 2000 and mc.failed == 0
        low, high = mc.std_interval
        assert low < mc.std < high and o.agrees, (o.rss, mc)
        # The samples are 2 r: their mean is the nominal within its interval too.
        assert mc.mean_interval[0] < o.nominal < mc.mean_interval[1]
    # The samples drawn: r normal about its value, L too; the output 2 r of each.
    table = result.samples
    assert (np.abs(table["stroke"] - 2 * table["r"]) < 1e-12).all()
    assert np.std(table["L"]) == pytest.approx(T_L / 3, rel=0.1)


def test_a_uniform_tolerance_stays_inside_the_worst_case() -> None:
    text = patch(TEXT, "r: 100 mm ± 0.1 mm", "r: {value: 100 mm, tolerance: 0.1 mm, distribution: uniform}")
    result = linkwork.tolerance(linkwork.from_yaml(text), "kinematics", {"stroke": "stroke"}, samples=1000, seed=3)
    o = result.outputs["stroke"]
    assert o.rss == pytest.approx(2 * math.hypot(T_R / math.sqrt(3), 0.0), rel=EXACT)
    mc = o.monte_carlo
    assert mc is not None and o.agrees, (o.rss, mc)
    # Uniform over ± t: every sample within the linear worst case (the stroke is linear in r).
    assert o.nominal - o.worst_case - 1e-12 <= mc.min and mc.max <= o.nominal + o.worst_case + 1e-12


def test_the_same_seed_draws_the_same_samples() -> None:
    a = linkwork.tolerance(MODEL, "kinematics", {"stroke": "stroke"}, samples=50, seed=11)
    b = linkwork.tolerance(MODEL, "kinematics", {"stroke": "stroke"}, samples=50, seed=11, workers=1)
    assert a.samples.equals(b.samples) and a.to_dict() == b.to_dict()


def test_a_model_without_tolerances_is_refused() -> None:
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.tolerance(EXAMPLES / "fourbar.yaml", "kinematics", {"x": "max(time)"}, samples=0)
    assert error.value.problems[0][0] == "parameters"


def test_the_command_prints_the_table_and_writes_json_and_a_report(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = linkwork("tolerance", MODEL, "--output", "stroke=stroke", "--samples", "300", "--seed", "5", "--out", "tol")
    assert out.code == 0, out.output
    assert "standard deviation" in out.output and "(agree)" in out.output
    data = json.loads((tmp_path / "tol" / "tolerance.json").read_text())
    stroke = data["outputs"]["stroke"]
    assert stroke["rss"] == pytest.approx(2 * T_R / 3, rel=EXACT) and data["seed"] == 5
    assert stroke["monte_carlo"]["samples"] == 300 and data["parameters"]["r"]["unit"] == "mm"
    html = (tmp_path / "tol" / "report.html").read_text()
    assert html.startswith("<!DOCTYPE html>") and 'id="figure1"' in html
    bad = linkwork("tolerance", EXAMPLES / "fourbar.yaml", "--output", "x=max(time)", "--samples", "0", "--out", "t2")
    assert bad.code == 2 and "parameters: no parameter has a tolerance" in bad.output


# --- sweeps with gradients --------------------------------------------------------------------


def test_a_sweeps_gradients_match_central_differences_across_its_points() -> None:
    """`max(rod.phi)` is not linear in r: its gradient at the middle point against the central
    difference of the outer two, h = 1e-4 m (truncation (h/r)^2 ~ 1e-6 of it, rounding 1e-12)."""
    h = 1e-4
    table = linkwork.sweep(
        MODEL, "kinematics", {"r": [0.1 - h, 0.1, 0.1 + h]}, {"swing": "max(rod.phi)", "stroke": "stroke"}, gradients=["r", "L"]
    )
    central = (table["swing"][2] - table["swing"][0]) / (2 * h)
    assert table["d(swing)/d(r)"][1] == pytest.approx(central, rel=1e-5)
    assert list(table["d(stroke)/d(r)"]) == pytest.approx([2.0] * 3, rel=EXACT)
    # Against the run's own sensitivities at the middle point.
    results = linkwork.load(MODEL).run("kinematics", sensitivities=["L"])
    assert table["d(stroke)/d(L)"][1] == pytest.approx(results.sensitivity("stroke", "L"), abs=EXACT)
    assert table.attrs["units"]["d(swing)/d(L)"] == "SI"


def test_an_output_that_is_no_expression_nor_summary_is_refused_before_any_run() -> None:
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.sweep(MODEL, "kinematics", {"r": [0.1]}, {"x": "strok"})
    [(path, message)] = error.value.problems
    assert path == "outputs.x" and "nor a summary of the model (its summaries: stroke)" in message


def test_sweep_gradients_on_the_command_line(linkwork: RunLinkwork, tmp_path: Path) -> None:
    pd = pytest.importorskip("pandas")
    out = linkwork("sweep", MODEL, "--grid", "r=0.1:0.12:2", "--output", f"stroke={STROKE}", "--gradients", "--out", "s")
    assert out.code == 0, out.output
    table = pd.read_parquet(tmp_path / "s" / "sweep.parquet")
    assert list(table["d(stroke)/d(r)"]) == pytest.approx([2.0, 2.0], rel=EXACT)
    assert [c for c in table.columns if c.startswith("d(")] == [f"d(stroke)/d({p})" for p in PARAMETERS]
