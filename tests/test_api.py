"""The Python API: models, results as numpy arrays and data frames, files, exceptions."""

from __future__ import annotations

import csv
import json
import math
import pickle
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES

QUANTITIES = ["x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha"]


@pytest.fixture(scope="module")
def model_a() -> linkwork.Model:
    return linkwork.load(EXAMPLES / "quick_return_a.yaml")


@pytest.fixture(scope="module")
def results_a(model_a: linkwork.Model) -> linkwork.Results:
    return model_a.run()


def test_model_names(model_a: linkwork.Model) -> None:
    assert model_a.name == "quick-return mechanism (model A, two sliders)"
    assert model_a.bodies == ["crank", "rocker", "slider_b", "link", "slider_d"]
    assert model_a.joints == ["O", "A", "B", "B_slot", "C", "D", "D_guide"]
    assert model_a.drivers == ["crank_drive"]
    assert model_a.analyses == ["kinematics", "dynamics", "dynamics_loaded", "inverse"]
    assert "quick_return_a.yaml" in repr(model_a)


def test_model_is_made_by_load_or_from_yaml() -> None:
    with pytest.raises(TypeError, match="linkwork.load"):
        linkwork.Model()
    text = (EXAMPLES / "fourbar.yaml").read_text()
    assert linkwork.from_yaml(text).bodies == linkwork.Model.from_yaml(text).bodies == ["crank", "coupler", "rocker"]


def test_results_columns_follow_the_contract(model_a: linkwork.Model, results_a: linkwork.Results) -> None:
    expected = [f"{b}.{q}" for b in model_a.bodies for q in QUANTITIES]
    assert results_a.columns == expected
    assert results_a.values.shape == (41, len(expected))
    assert len(results_a) == 41
    np.testing.assert_allclose(results_a.time, np.arange(41) * 0.05, rtol=0, atol=1e-12)
    assert results_a["time"] is results_a.time
    for name in expected:
        column = results_a[name]
        assert column.shape == (41,) and column.dtype == np.float64
        assert name in results_a
    assert "time" in results_a and "crank.theta" not in results_a


def test_iterating_results_gives_the_column_names(results_a: linkwork.Results) -> None:
    """`list(results)` raised `KeyError: 'no column 0'` (Python fell back on `__getitem__(0)`);
    it gives the header of results.csv, so that every name it gives is a column."""
    assert list(results_a) == ["time", *results_a.columns]
    table = {name: results_a[name] for name in results_a}
    assert table["time"] is results_a.time
    np.testing.assert_array_equal(table["rocker.phi"], results_a["rocker.phi"])


def test_results_values_are_the_engines(results_a: linkwork.Results) -> None:
    # The crank angle is the driver's function exactly: 6.1506 + 2 pi t.
    np.testing.assert_allclose(results_a["crank.phi"], 6.1506 + 2 * math.pi * results_a.time, rtol=0, atol=1e-12)
    np.testing.assert_allclose(results_a["crank.omega"], 2 * math.pi, rtol=0, atol=1e-12)
    # Angles are unwrapped: the crank's goes past 2 pi without folding back.
    assert np.all(np.diff(results_a["crank.phi"]) > 0)
    # slider_d stays on its guide y = 2.
    np.testing.assert_allclose(results_a["slider_d.y"], 2.0, rtol=0, atol=1e-11)


def test_results_are_read_only(results_a: linkwork.Results) -> None:
    with pytest.raises(ValueError, match="read-only"):
        results_a["rocker.phi"][0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        results_a.time[0] = 1.0


def test_unknown_column(results_a: linkwork.Results) -> None:
    # The closest names (difflib's): the body's own columns.
    with pytest.raises(KeyError, match="no column 'rocker.theta'; did you mean 'rocker[.]"):
        results_a["rocker.theta"]
    with pytest.raises(KeyError, match="no column 'nope'; there are time, crank.x"):
        results_a["nope"]


def test_summary(results_a: linkwork.Results) -> None:
    summary = results_a.summary
    assert summary["status"] == "ok"
    assert summary["analysis"] == "kinematics"
    assert summary["output_points"] == 41
    assert summary["coordinates"] == 15
    assert results_a.ok
    assert "41 points" in repr(results_a)


def test_summary_keys_are_attributes(model_a: linkwork.Model, results_a: linkwork.Results) -> None:
    """The summary is the dict of summary.json, and each key is also a typed attribute: the same
    header and the same shape of each fact (``dof``, ``redundant_rows``) for every analysis."""
    summary = results_a.summary
    assert isinstance(summary, linkwork.Summary) and isinstance(summary, dict)
    assert summary.status == "ok" and summary.error is None and summary.error_time is None
    assert (summary.model, summary.analysis, summary.type) == (model_a.name, "kinematics", "kinematic")
    assert (summary.bodies, summary.coordinates, summary.joints) == (5, 15, model_a.joints)
    assert summary.active_drivers == ["crank_drive"] and summary.output_points == 41
    assert summary.dof == 0 and summary.redundant_rows == [] and summary.warnings == []
    assert summary.statistics is not None and summary.statistics["max_condition"] < 1e3
    assert summary.modes is None and summary.peaks is None and summary.stable is None
    assert {key: getattr(summary, key) for key in summary} == dict(summary)
    runs = [("dynamics", "dynamic", 1, "O.force"), ("inverse", "inverse", 0, "crank_drive.effort")]
    for name, kind, dof, peak in runs:
        other = model_a.run(name, t_end=0.2).summary
        assert (other.type, other.dof, other.redundant_rows) == (kind, dof, [])
        assert other.peaks is not None and other.peaks[peak]["max_abs"] > 0
        assert other.reaction_bodies is not None and other.reaction_bodies["O"] == "crank"
    integrator = model_a.run("dynamics", t_end=0.2).summary.integrator
    assert integrator is not None and integrator["kind"] == "bdf"


def test_summary_of_a_static_and_a_modes_analysis() -> None:
    hanging = linkwork.load(EXAMPLES / "hanging_fourbar.yaml")
    rest = hanging.run("rest").summary
    assert rest.type == "static" and rest.stable is True and rest.index == 0 and rest.dof == 1
    assert rest.min_reduced_stiffness is not None and rest.min_reduced_stiffness > 0
    vibration = hanging.run("vibration").summary
    assert vibration.type == "modes" and vibration.about == "equilibrium" and vibration.dof == 1
    assert vibration.modes is not None and vibration.modes[0]["kind"] == "vibration"
    assert vibration.redundant_rows == [] and vibration.statistics is None


def test_to_pandas(results_a: linkwork.Results) -> None:
    pd = pytest.importorskip("pandas")
    frame = results_a.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert frame.index.name == "time"
    assert list(frame.columns) == results_a.columns
    np.testing.assert_array_equal(frame.index.to_numpy(), results_a.time)
    np.testing.assert_array_equal(frame["link.vx"].to_numpy(), results_a["link.vx"])
    # The frame is the user's own: changing it leaves the results alone.
    frame.iloc[0, 0] = 123.0
    assert results_a.values[0, 0] != 123.0
    # reset_index() gives the layout of results.csv.
    assert list(frame.reset_index().columns) == ["time", *results_a.columns]


def test_write_matches_the_arrays(results_a: linkwork.Results, tmp_path: Path) -> None:
    results_a.write(tmp_path / "a")
    with (tmp_path / "a" / "results.csv").open(newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["time", *results_a.columns]
    table = np.array([[float(v) for v in row] for row in rows[1:]])
    # The CSV holds every double exactly (shortest round-trip form).
    np.testing.assert_array_equal(table[:, 0], results_a.time)
    np.testing.assert_array_equal(table[:, 1:], results_a.values)
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary == results_a.summary


def test_models_a_and_b_agree() -> None:
    """Model A (5 bodies, two sliders) and model B (3 bodies, pin-in-slot joints) describe the
    same crank, rocker and link motion with different equations. Tolerance 1e-10 (relative above
    magnitude 1): each is solved to |Phi| <= 1e-12 and the Jacobian amplifies that by at most ~300
    (the largest condition estimate the runs report)."""
    a = linkwork.load(EXAMPLES / "quick_return_a.yaml").run("kinematics")
    b = linkwork.load(EXAMPLES / "quick_return_b.yaml").run("kinematics")
    np.testing.assert_array_equal(a.time, b.time)
    compared = 0
    for body in ["crank", "rocker", "link"]:
        for q in QUANTITIES:
            name = f"{body}.{q}"
            np.testing.assert_allclose(a[name], b[name], rtol=1e-10, atol=1e-10, err_msg=name)
            compared += 1
    assert compared == 27
    assert a.summary["statistics"]["max_condition"] < 1e3
    # The mechanism really moves: the rocker swings by more than half a radian.
    assert np.ptp(a["rocker.phi"]) > 0.5


def test_check(model_a: linkwork.Model) -> None:
    report = model_a.check()
    assert report["bodies"] == model_a.bodies
    assert report["coordinates"] == 15
    mechanism = report["mechanism"]
    assert (mechanism["equations"], mechanism["rank"], mechanism["dof"], mechanism["gruebler_dof"]) == (14, 14, 1, 1)
    assert mechanism["redundant"] == []
    assert mechanism["drivers"] == []
    assembly = mechanism["assembly"]
    assert assembly["residual"] <= 1e-12
    assert len(assembly["q"]) == len(assembly["change"]) == 15
    assert assembly["change"][2] == 0.0  # the crank angle is given: held
    driven = report["analyses"]["kinematics"]
    assert driven["drivers"] == ["crank_drive"]
    assert (driven["equations"], driven["dof"]) == (15, 0)


def test_schema() -> None:
    schema = linkwork.schema()
    assert schema["type"] == "object"
    assert {"bodies", "joints", "drivers", "analyses"} <= set(schema["properties"])


def test_version() -> None:
    assert isinstance(linkwork.__version__, str) and linkwork.__version__.count(".") == 2


def test_dir_shows_only_the_public_api() -> None:
    assert dir(linkwork) == sorted(linkwork.__all__)
    assert not {"json", "os", "annotations", "report", "results", "_linkwork"} & set(dir(linkwork))
    # Each name it shows is there, and the submodules stay importable.
    assert all(hasattr(linkwork, name) for name in dir(linkwork))
    from linkwork import page

    assert callable(page.page)


# --- exceptions ----------------------------------------------------------------------------------


def test_exception_tree() -> None:
    assert issubclass(linkwork.ModelError, linkwork.LinkworkError)
    assert issubclass(linkwork.AssemblyError, linkwork.LinkworkError)
    assert issubclass(linkwork.SolverError, linkwork.LinkworkError)
    assert issubclass(linkwork.SingularError, linkwork.SolverError)
    assert issubclass(linkwork.ConvergenceError, linkwork.SolverError)
    assert issubclass(linkwork.InternalError, linkwork.LinkworkError)
    assert issubclass(linkwork.FileError, linkwork.LinkworkError)
    assert issubclass(linkwork.FileError, OSError)
    assert issubclass(linkwork.LinkworkError, Exception)
    assert linkwork.ModelError.__module__ == "linkwork"
    assert linkwork.errors.SingularError is linkwork.SingularError


def test_model_error_lists_problems() -> None:
    text = """
bodies:
  crank: {mass: 1, inertia: 1, position: [0, 0], angle: 0}
joints:
  B: {type: revolute, body_i: crank, point_i: [0, 0], body_j: rokcer, point_j: [0, 0]}
  C: {type: revolute, body_i: crank, point_i: tip, body_j: ground, point_j: [0, 0]}
"""
    with pytest.raises(linkwork.ModelError) as caught:
        linkwork.from_yaml(text)
    paths = [path for path, _ in caught.value.problems]
    assert "joints.B.body_j" in paths
    assert "joints.C.point_i" in paths
    assert len(caught.value.problems) == 2
    assert "joints.B.body_j: unknown body 'rokcer'" in str(caught.value)


def test_missing_file_is_a_file_error(tmp_path: Path) -> None:
    missing = tmp_path / "missing.yaml"
    with pytest.raises(linkwork.FileError) as caught:
        linkwork.load(missing)
    assert caught.value.path == str(missing)
    with pytest.raises(OSError):
        linkwork.load(missing)


def test_run_unknown_analysis(model_a: linkwork.Model) -> None:
    with pytest.raises(linkwork.ModelError, match="no analysis named 'nope'") as caught:
        model_a.run("nope")
    assert caught.value.problems[0][0] == "analyses.nope"


def test_run_without_analyses() -> None:
    text = (EXAMPLES / "fourbar.yaml").read_text().split("analyses:")[0]
    model = linkwork.from_yaml(text)
    assert model.analyses == []
    with pytest.raises(linkwork.ModelError, match="names no analyses") as caught:
        model.run()
    assert caught.value.problems[0][0] == "analyses"


def test_singular_error_carries_partial_results() -> None:
    model = linkwork.load(EXAMPLES / "slider_crank_lockup.yaml")
    with pytest.raises(linkwork.SingularError) as caught:
        model.run()
    error = caught.value
    assert isinstance(error, linkwork.SolverError)
    assert error.time == pytest.approx(math.asin(0.6), abs=1e-3)
    assert {"A", "B", "guide"} <= set(error.joints)
    assert all("." in row for row in error.rows)
    assert error.detail
    partial = error.results
    assert isinstance(partial, linkwork.Results)
    assert not partial.ok
    assert 0 < len(partial) <= 13 and partial.time[-1] < error.time
    assert partial.summary["status"] == "failed"
    assert partial.summary["error_time"] == error.time
    failed = partial.summary
    assert (failed.status, failed.error_time, failed.output_points) == ("failed", error.time, len(partial))
    assert failed.error is not None and "singular" in failed.error
    assert failed.error_elements is not None and {"A", "B", "guide"} <= set(failed.error_elements)
    # Until the lock-up the crank follows its driver, theta = t.
    np.testing.assert_allclose(partial["crank.phi"], partial.time, rtol=0, atol=1e-12)


def test_assembly_error() -> None:
    """A link too short to close the loop: the guess cannot be assembled."""
    text = """
bodies:
  crank: {mass: 1, inertia: 1, position: [0.5, 0], angle: 0, points: {O: [-0.5, 0], A: [0.5, 0]}}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
  reach: {type: distance, body_i: crank, point_i: A, body_j: ground, point_j: [5, 0], length: 1}
drivers:
  motor: {type: angle, body: crank, function: "t"}
analyses:
  kinematics: {type: kinematic, drivers: [motor], t_end: 1, step: 0.1}
"""
    model = linkwork.from_yaml(text)
    with pytest.raises(linkwork.AssemblyError) as caught:
        model.run()
    error = caught.value
    assert error.joints and error.row.split(".")[0] in error.joints
    assert error.residual > 1e-3
    assert error.hint
    assert isinstance(error.results, linkwork.Results) and len(error.results) == 0
    with pytest.raises(linkwork.AssemblyError):
        model.check()


def test_exceptions_pickle() -> None:
    with pytest.raises(linkwork.ModelError) as caught:
        linkwork.from_yaml("bodies: {}\n")
    again = pickle.loads(pickle.dumps(caught.value))
    assert type(again) is linkwork.ModelError
    assert again.problems == caught.value.problems


def test_a_panic_becomes_internal_error() -> None:
    """A panic in the engine is a bug, but it must reach Python as an ordinary exception, never as
    pyo3's PanicException (a BaseException) or a crash."""
    with pytest.raises(linkwork.InternalError, match="internal error in the Linkwork engine .*deliberate panic"):
        linkwork._linkwork._panic_for_tests()


def test_outputs_keep_the_columns_named_and_the_report_draws_the_bodies_kept(tmp_path: Path) -> None:
    text = (EXAMPLES / "quick_return_a.yaml").read_text()
    line = "  kinematics: {type: kinematic, drivers: [crank_drive], t_end: 2.0, step: 0.05}"
    assert text.count(line) == 1
    chosen = text.replace(
        line, line[:-1] + ", outputs: {bodies: [crank, rocker], joints: [A], columns: [slider_d.x]}}"
    )
    some = linkwork.from_yaml(chosen).run("kinematics")
    every = linkwork.load(EXAMPLES / "quick_return_a.yaml").run("kinematics")
    assert set(some.columns) == {
        *(f"{b}.{q}" for b in ("crank", "rocker") for q in ("x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha")),
        "slider_d.x",
    }, "a kinematic analysis has no reactions: A's columns are not there to keep"
    for name in some.columns:
        assert some[name].tolist() == every[name].tolist(), name
    some.write(tmp_path / "out")
    header = (tmp_path / "out" / "results.csv").read_text().splitlines()[0].split(",")
    assert header == ["time", *some.columns]
    # The report draws the crank and the rocker, and the joints between them and the ground.
    run = some._run()
    assert [b["name"] for b in run.drawing["bodies"]] == ["crank", "rocker"]
    assert [j["name"] for j in run.drawing["joints"]] == ["O", "A"]
    assert (tmp_path / "out" / "report.html").stat().st_size > 0
