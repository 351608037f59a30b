"""Sweeps from Python and the command line (docs/python.md, "Sweeps"): the parametrised
slider-crank's stroke is 2 r in every row of sweep.parquet; failed variants are rows; threads do
not change the table."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork
from linkwork.sweep import grid_values

MODEL = EXAMPLES / "slider_crank_param.yaml"
STROKE = "max(slider.x) - min(slider.x)"


def test_the_cli_sweep_writes_a_stroke_of_twice_the_radius(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = linkwork(
        "sweep", MODEL, "--analysis", "kinematics", "--grid", "r=0.05:0.15:5", "--output", f"stroke={STROKE}",
        "--out", "s",
    )
    assert out.code == 0, out.output
    table = pd.read_parquet(tmp_path / "s" / "sweep.parquet")
    assert list(table.columns) == ["r", "status", "stroke"]
    assert list(table["r"]) == [0.05, 0.075, 0.1, 0.125, 0.15]
    assert (table["status"] == "ok").all()
    # 1e-9 m: the kinematic solver's tolerance on Phi is 1e-10 and the dead centres are output times.
    assert ((table["stroke"] - 2 * table["r"]).abs() < 1e-9).all(), table


def test_a_failed_variant_is_a_row_with_its_error() -> None:
    table = linkwork.sweep(MODEL, "kinematics", grid={"r": [0.1, 0.35, "150 mm"]}, outputs={"s": "final(slider.x)"})
    assert list(table["r"]) == [0.1, 0.35, 0.15]
    assert table["status"][0] == "ok" and table["status"][2] == "ok"
    assert table["status"][1].split(":")[0] in {"AssemblyError", "SingularError", "ConvergenceError"}, table
    assert pd.isna(table["s"][1]) and not pd.isna(table["s"][0])


def test_every_combination_in_order_and_threads_do_not_change_it() -> None:
    grid = {"r": [0.08, 0.1, 0.12], "L": [0.3, 0.35]}
    outputs = {"stroke": STROKE, "torque": "peak(motor.effort)"}
    one = linkwork.sweep(MODEL, "inverse", grid=grid, outputs=outputs, workers=1)
    two = linkwork.sweep(linkwork.load(MODEL), "inverse", grid=grid, outputs=outputs, workers=2)
    pd.testing.assert_frame_equal(one, two)
    assert list(zip(one["r"], one["L"])) == [(r, L) for r in grid["r"] for L in grid["L"]]
    model = linkwork.load(MODEL)
    for k, (r, L) in enumerate(zip(one["r"], one["L"])):
        alone = model.with_parameters(r=r, L=L).run("inverse")
        assert one["torque"][k] == float(abs(alone["motor.effort"]).max())


def test_a_bad_output_is_exit_2_naming_it(linkwork: RunLinkwork) -> None:
    out = linkwork("sweep", MODEL, "--grid", "r=0.1:0.2:2", "--output", "s=slider.x + max(slider.x)")
    assert out.code == 2, out.output
    assert "outputs.s:" in out.output and "'slider.x' outside an aggregation" in out.output
    out = linkwork("sweep", MODEL, "--grid", "r=0.1:0.2", "--output", f"s={STROKE}")
    assert out.code == 2 and "NAME=START:STOP:COUNT" in out.output


def test_grid_values_include_both_ends() -> None:
    assert grid_values("r=0.05:0.15:5") == ("r", [0.05, 0.075, 0.1, 0.125, 0.15])
    assert grid_values("k=3:3:1") == ("k", [3.0])
    with pytest.raises(ValueError, match="COUNT >= 1"):
        grid_values("k=0:1:0")
