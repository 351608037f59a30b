"""Tables through the Python API: a model file whose table is a CSV file beside it, pickled (as a
Dask worker receives it) and written to an output folder that runs again; a table built with the
Mechanism builder. The numbers themselves are checked in crates/linkwork/tests/tables.rs."""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import numpy as np
import pytest

import linkwork

ROOT = Path(__file__).resolve().parent.parent
CAM = ROOT / "examples" / "cam_table.yaml"


def test_a_models_table_file_is_read_beside_it_and_travels_with_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    model = linkwork.load("examples/cam_table.yaml")  # a relative path: its folder is made absolute
    results = model.run("motion")
    lift = results["follower.y"] - 0.05
    # The measure and the joint read the same table.
    np.testing.assert_allclose(results["lift_mm"], 1000 * lift, rtol=0, atol=1e-9)
    assert lift.max() > 0.0199
    # Unpickled elsewhere (another working folder), the model still finds its file.
    monkeypatch.chdir(tmp_path)
    again = pickle.loads(pickle.dumps(model)).run("motion")
    np.testing.assert_array_equal(again["follower.y"], results["follower.y"])
    # The output folder holds the table at the path model.yaml names, so it runs again there.
    out = tmp_path / "out"
    results.write(out, report=False)
    assert (out / "data" / "cam_lift.csv").read_bytes() == (ROOT / "examples" / "data" / "cam_lift.csv").read_bytes()
    rerun = linkwork.load(out / "model.yaml").run("motion")
    np.testing.assert_array_equal(rerun["follower.y"], results["follower.y"])


def test_the_builder_writes_a_table_that_drives() -> None:
    m = linkwork.Mechanism("turned by a table")
    crank = m.body("crank", mass=1.0, inertia=0.1, position=(0, 0))
    m.revolute("pin", crank, "ground", at=(0, 0))
    # Four points on theta = t^3: not-a-knot interpolation reproduces a cubic exactly.
    times = [0.0, 0.4, 1.1, 2.0]
    m.table("history", times, [t**3 for t in times])
    m.driver("turn", "angle", body=crank, function="spline(history, t)")
    m.analysis("run", "kinematic", drivers=["turn"], t_end=2.0, step=0.1)
    # "y" is quoted: YAML 1.1 reads a bare y as true.
    assert "  history: {x: [0.0, 0.4, 1.1, 2.0], \"y\": [0.0, 0.06400000000000002, 1.3310000000000004, 8.0]}" in m.to_yaml()
    r = m.build().run("run")
    t = r.time
    # The spline's own rounding on values up to 8 rad (the slopes come from a linear solve).
    np.testing.assert_allclose(r["crank.phi"], t**3, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["crank.omega"], 3 * t**2, rtol=0, atol=1e-11)
    np.testing.assert_allclose(r["crank.alpha"], 6 * t, rtol=0, atol=1e-10)
    assert math.isclose(float(r["crank.phi"][-1]), 8.0, abs_tol=1e-12)


def test_a_bad_table_is_refused_naming_its_field() -> None:
    m = linkwork.Mechanism()
    crank = m.body("crank", mass=1.0, inertia=0.1, position=(0, 0))
    m.revolute("pin", crank, "ground", at=(0, 0))
    m.table("history", [0.0, 1.0, 1.0], [0.0, 1.0, 2.0], method="akima")
    try:
        m.build()
    except linkwork.ModelError as e:
        assert "tables.history.x: x must increase strictly: x[2] = 1 follows x[1] = 1" in str(e)
    else:
        raise AssertionError("a table whose x does not increase compiled")
