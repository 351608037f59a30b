"""Results streamed to a file as they are computed (`Model.run(stream=...)`, `linkwork run
--stream`): the file holds what a run in memory writes, the results hold no row, a failed run's
file has its rows up to the failure, and the report reads the file back."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, WriteModel, pendulum_with_torque
from linkwork import stream

QUICK_RETURN = EXAMPLES / "quick_return_a.yaml"

# A torque that is NaN past t = 0.503 s: every integrator stops there, after the rows 0 .. 0.5 s.
NAN_TORQUE = pendulum_with_torque("sqrt(0.503-t)", 0.01)


@pytest.mark.parametrize("analysis", ["kinematics", "dynamics_loaded", "inverse"])
def test_a_csv_stream_is_the_results_csv_of_a_run_in_memory(analysis: str, tmp_path: Path) -> None:
    model = linkwork.Model.load(QUICK_RETURN)
    held = model.run(analysis)
    held.write(tmp_path / "held", report=False)
    streamed = model.run(analysis, stream=tmp_path / "rows.csv")
    assert (tmp_path / "rows.csv").read_bytes() == (tmp_path / "held" / "results.csv").read_bytes()
    assert streamed.streamed_to == tmp_path / "rows.csv"
    assert len(streamed) == 0 and streamed.values.shape == (0, len(held.columns))
    assert streamed.columns == held.columns
    assert streamed.summary == held.summary
    assert streamed.summary.output_points == len(held) == 41


def test_a_parquet_stream_has_the_columns_of_a_run_in_memory(tmp_path: Path) -> None:
    model = linkwork.Model.load(QUICK_RETURN)
    held = model.run("dynamics_loaded")
    streamed = model.run("dynamics_loaded", stream=tmp_path / "rows.parquet")
    time, columns = stream.read(tmp_path / "rows.parquet")
    assert np.array_equal(time, held.time)
    assert list(columns) == held.columns
    for name in held.columns:
        assert np.array_equal(columns[name], held[name]), name
    # Written out: the Parquet file beside summary.json, and a report `linkwork report` rebuilds.
    streamed.write(tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "model.yaml",
        "report.html",
        "results.parquet",
        "summary.json",
    ]
    run = linkwork.report.from_folder(tmp_path / "out")
    assert np.array_equal(run.time, held.time)


def test_a_parquet_stream_replaces_an_earlier_csv(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """A folder that held a run's results.csv gets a streamed run's results.parquet: the old CSV
    goes, so that the report (and `linkwork report`) read the new rows."""
    assert linkwork("run", QUICK_RETURN, "-a", "dynamics", "-o", "out", "--no-report").code == 0
    done = linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", "out", "--stream", "parquet")
    assert done.code == 0, done.output
    assert "41 output points, streamed" in done.stdout
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "model.yaml",
        "report.html",
        "results.parquet",
        "summary.json",
    ]
    assert linkwork("report", "out").code == 0


def test_a_failed_streamed_run_keeps_its_rows(write_model: WriteModel, tmp_path: Path) -> None:
    model = linkwork.Model.load(write_model(NAN_TORQUE))
    with pytest.raises(linkwork.NonFiniteError) as held:
        model.run("dynamics")
    with pytest.raises(linkwork.NonFiniteError) as streamed:
        model.run("dynamics", stream=tmp_path / "rows.csv")
    assert str(streamed.value) == str(held.value)
    assert streamed.value.results.summary.output_points == 51
    time, columns = stream.read(tmp_path / "rows.csv")
    assert np.array_equal(time, held.value.results.time)
    assert np.array_equal(columns["bar.phi"], held.value.results["bar.phi"])


def test_a_stream_to_another_kind_of_file_is_refused(tmp_path: Path) -> None:
    model = linkwork.Model.load(QUICK_RETURN)
    with pytest.raises(linkwork.ModelError) as error:
        model.run("kinematics", stream=tmp_path / "rows.txt")
    assert error.value.problems == [("stream", f"expected a path ending in .csv or .parquet, got '{tmp_path / 'rows.txt'}'")]


def test_run_stream_writes_the_files_of_a_run_in_memory(linkwork: RunLinkwork, tmp_path: Path) -> None:
    held = linkwork("run", QUICK_RETURN, "-a", "dynamics_loaded", "-o", "held")
    streamed = linkwork("run", QUICK_RETURN, "-a", "dynamics_loaded", "-o", "streamed", "--stream")
    assert held.code == streamed.code == 0, streamed.output
    for name in ("results.csv", "summary.json", "model.yaml"):
        assert (tmp_path / "streamed" / name).read_bytes() == (tmp_path / "held" / name).read_bytes(), name
    assert (tmp_path / "streamed" / "report.html").stat().st_size > 100_000
    assert "streamed/results.csv" in streamed.stdout


def test_run_stream_of_a_failed_run_keeps_its_rows(
    linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path
) -> None:
    done = linkwork("run", write_model(NAN_TORQUE), "-o", "out", "--stream", "parquet", "--no-report")
    assert done.code == 3, done.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (summary["status"], summary["output_points"]) == ("failed", 51)
    time, _ = stream.read(tmp_path / "out" / "results.parquet")
    assert len(time) == 51 and time[-1] == pytest.approx(0.5)
