"""Sweeps from Python and the command line (docs/python.md, "Sweeps"): the parametrised
slider-crank's stroke is 2 r in every row of sweep.parquet; failed variants are rows; threads, a
Dask cluster of two processes and a Latin hypercube sample do not change the rows' values."""

from __future__ import annotations

import pickle
from pathlib import Path

import pandas as pd
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, run_process
from linkwork.sweep import grid_values, latin_hypercube

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


def test_a_latin_hypercube_has_one_point_in_each_stratum_and_its_seed_repeats_it() -> None:
    ranges = {"r": (0.05, 0.15), "L": (0.3, 0.4)}
    count = 50
    points = latin_hypercube(ranges, count, seed=7)
    for name, (low, high) in ranges.items():
        # The stratum of each point: (v - low) / (high - low) * count lies in [k, k + 1).
        strata = sorted(int((v - low) / (high - low) * count) for v in points[name])
        assert strata == list(range(count)), name
    assert latin_hypercube(ranges, count, seed=7) == points
    assert latin_hypercube(ranges, count, seed=8) != points
    # The pairing of strata is random: r and L are not drawn in the same order.
    order = sorted(range(count), key=lambda k: points["r"][k])
    assert [points["L"][k] for k in order] != sorted(points["L"])


def test_the_cli_samples_a_latin_hypercube_with_its_seed(linkwork: RunLinkwork, tmp_path: Path) -> None:
    args: list[str | Path] = ["sweep", MODEL, "-a", "kinematics", "--sample", "6", "--range", "r=0.05:0.15", "--range", "L=0.3:0.4"]
    out = linkwork(*args, "--seed", "11", "--output", f"stroke={STROKE}", "--out", "s")
    assert out.code == 0, out.output
    assert "seed 11" in out.output
    table = pd.read_parquet(tmp_path / "s" / "sweep.parquet")
    points = latin_hypercube({"r": (0.05, 0.15), "L": (0.3, 0.4)}, 6, seed=11)
    assert list(table["r"]) == points["r"] and list(table["L"]) == points["L"]
    assert (table["status"] == "ok").all()
    assert ((table["stroke"] - 2 * table["r"]).abs() < 1e-9).all(), table
    # Without --seed, a fresh one, printed so that the sample can be drawn again.
    out = linkwork(*args, "--output", f"stroke={STROKE}", "--out", "t")
    assert out.code == 0 and "--seed " in out.output
    seed = int(out.output.split("--seed ")[1].split()[0])
    again = pd.read_parquet(tmp_path / "t" / "sweep.parquet")
    assert list(again["r"]) == latin_hypercube({"r": (0.05, 0.15), "L": (0.3, 0.4)}, 6, seed=seed)["r"]


def test_the_variants_are_a_grid_or_a_sample_not_both(linkwork: RunLinkwork) -> None:
    both = linkwork("sweep", MODEL, "--grid", "r=0.1:0.2:2", "--sample", "3", "--range", "L=0.3:0.4", "--output", "s=max(t)")
    assert both.code == 2 and "not both" in both.output
    alone = linkwork("sweep", MODEL, "--sample", "3", "--output", "s=max(time)")
    assert alone.code == 2 and "go together" in alone.output
    backwards = linkwork("sweep", MODEL, "--sample", "3", "--range", "L=0.4:0.3", "--output", "s=max(time)")
    assert backwards.code == 2 and "LOW <= HIGH" in backwards.output


def test_a_dask_cluster_of_two_processes_gives_the_local_table_row_for_row(tmp_path: Path) -> None:
    from distributed import Client, LocalCluster

    grid: dict[str, list[float | str]] = {"r": [0.08, 0.1, 0.12, 0.35], "L": [0.3, 0.35, "400 mm"]}
    outputs = {"stroke": STROKE, "torque": "peak(motor.effort)"}
    local = linkwork.sweep(MODEL, "inverse", grid=grid, outputs=outputs)
    # r = 0.35 with L = 0.3 or 0.35 (a rod no longer than the crank) fails: failed rows travel too.
    assert (local["status"] != "ok").sum() == 2
    cli = ["sweep", str(MODEL), "-a", "inverse", "--grid", "r=0.05:0.15:5", "--output", f"stroke={STROKE}"]
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        remote = linkwork.sweep(MODEL, "inverse", grid=grid, outputs=outputs, client=client)
        on_cluster = run_process([*cli, "--dask", cluster.scheduler_address, "--out", "c"], tmp_path)
    pd.testing.assert_frame_equal(remote, local)
    assert on_cluster.code == 0, on_cluster.output
    here = run_process([*cli, "--out", "h"], tmp_path)
    pd.testing.assert_frame_equal(
        pd.read_parquet(tmp_path / "c" / "sweep.parquet"), pd.read_parquet(tmp_path / "h" / "sweep.parquet")
    )


def test_no_scheduler_at_the_address_is_exit_2_naming_dask(tmp_path: Path) -> None:
    # A port nothing listens on (the discard port, closed on any test machine).
    out = run_process(["sweep", str(MODEL), "--grid", "r=0.1:0.2:2", "--output", f"s={STROKE}",
                       "--dask", "tcp://127.0.0.1:9"], tmp_path)
    assert out.code == 2, out.output
    assert "--dask: no Dask scheduler answered at tcp://127.0.0.1:9" in out.output


def test_a_model_pickles_as_its_text_and_its_given_values() -> None:
    model = linkwork.load(MODEL, parameters={"r": "120 mm"})
    again = pickle.loads(pickle.dumps(model))
    assert again.parameters == model.parameters and again.path == model.path
    assert again.run("kinematics")["slider.x"].tolist() == model.run("kinematics")["slider.x"].tolist()
