"""Cams given by their working surface (`profile`, `surface_radius`): examples/cam_profile.yaml
built with the typed builder runs as its file does, its lifts follow the eccentric disc's
closed form, and bad profiles are refused naming their fields."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, ROOT

RC, ECC, ROLLER = 0.04, 0.01, 0.01


def eccentric_disc() -> linkwork.Mechanism:
    """examples/cam_profile.yaml, built in Python (its table by an absolute path: a built model's
    files are relative to the working folder)."""
    m = linkwork.Mechanism("eccentric disc cam given by its working surface", gravity=(0, -9.81))
    m.parameter("Rc", "40 mm")
    m.parameter("ecc", "10 mm")
    m.parameter("roller", "10 mm")
    cam = m.body("cam", mass=1.2, inertia=0.002, position=(0, 0))
    upper = m.body("upper", mass=0.3, inertia=0.0001, position=(0, "50 mm"))
    lower = m.body("lower", mass=0.3, inertia=0.0001, position=(0, "-50 mm"))
    m.revolute("bearing", "ground", cam, at=(0, 0))
    m.translational("upper_guide", "ground", upper, at=(0, "50 mm"), axis=(0, 1))
    m.translational("lower_guide", "ground", lower, at=(0, "-50 mm"), axis=(0, 1))
    m.cam("upper_contact", cam, upper, point_j=(0, 0), profile={"x": "ecc + Rc*cos(u)", "y": "Rc*sin(u)"},
          roller_radius="roller")
    table = str(EXAMPLES / "data" / "cam_disc.csv")
    m.cam("lower_contact", cam, lower, point_j=(0, 0), profile={"file": table, "x": "x", "y": "y"},
          roller_radius="roller")
    m.driver("motor", "angle", body=cam, function="2*pi*t")
    m.pressure_angle("pressure_angle", joint="upper_contact")
    m.analysis("motion", "kinematic", drivers=["motor"], t_end=1.5, step="1/360")
    m.analysis("drive", "inverse", drivers=["motor"], t_end=1.5, step="1/360")
    return m


def test_the_built_cam_runs_as_the_example_and_reads_back() -> None:
    m = eccentric_disc()
    assert m.to_dict()["joints"]["upper_contact"]["profile"] == {"x": "ecc + Rc*cos(u)", "y": "Rc*sin(u)"}
    built, loaded, again = m.build(), linkwork.load(EXAMPLES / "cam_profile.yaml"), linkwork.from_yaml(m.to_yaml())
    for analysis in ["motion", "drive"]:
        a, b, c = built.run(analysis), loaded.run(analysis), again.run(analysis)
        assert a.columns == b.columns == c.columns and "pressure_angle" in a.columns
        assert np.array_equal(a.values, b.values) and np.array_equal(a.values, c.values), analysis


def test_the_lifts_follow_the_eccentric_disc() -> None:
    r = linkwork.load(EXAMPLES / "cam_profile.yaml").run("motion")
    theta = 2 * math.pi * r.time

    def lift(a: np.ndarray) -> np.ndarray:
        return np.asarray(ECC * np.cos(a) + np.sqrt((RC + ROLLER) ** 2 - (ECC * np.sin(a)) ** 2))

    # The expressions to the position solver's tolerance; the 360-point table to its spline's
    # error, 1e-11 m (crates/linkwork/tests/cam.rs states both).
    assert np.max(np.abs(r["upper.y"] - lift(theta - math.pi / 2))) < 1e-9
    assert np.max(np.abs(r["lower.y"] + lift(theta + math.pi / 2))) < 2e-11
    want = -np.arcsin(ECC * np.sin(theta - math.pi / 2) / (RC + ROLLER))
    assert np.max(np.abs(r["pressure_angle"] - want)) < 1e-9


def test_a_polar_surface_and_inline_points_are_the_same_disc() -> None:
    """The disc centred on the pivot: a polar surface of constant radius, and its points inline,
    hold the roller's centre at Rc + r."""
    points: linkwork.CamProfile = {
        "x": [RC * math.cos(2 * math.pi * k / 90) for k in range(90)],
        "y": [RC * math.sin(2 * math.pi * k / 90) for k in range(90)],
    }
    for surface_radius, profile in [("Rc", None), (None, points)]:
        m = linkwork.Mechanism()
        m.parameter("Rc", RC)
        cam = m.body("cam", mass=1, inertia=0.01, position=(0, 0))
        follower = m.body("follower", mass=0.1, inertia=0.001, position=(0, 0.06))
        m.revolute("pin", "ground", cam, at=(0, 0))
        m.translational("guide", "ground", follower, at=(0, 0.06), axis=(0, 1))
        m.cam("contact", cam, follower, (0, 0), roller_radius=ROLLER, surface_radius=surface_radius, profile=profile)
        m.driver("motor", "angle", body=cam, function="t")
        m.analysis("motion", "kinematic", drivers=["motor"], t_end=1, step=0.1)
        r = linkwork.from_yaml(m.to_yaml()).run()
        # 90 points: the spline misses the circle by (2 pi / 90)^4 Rc / 384 = 2.5e-9 m.
        assert np.max(np.abs(r["follower.y"] - (RC + ROLLER))) < 3e-9, surface_radius


def test_bad_profiles_are_refused_at_their_fields() -> None:
    def problems(
        radius: str | None = None,
        surface_radius: str | None = None,
        profile: linkwork.CamProfile | None = None,
        roller_radius: float | None = None,
    ) -> dict[str, str]:
        m = linkwork.Mechanism()
        cam = m.body("cam", mass=1, inertia=0.01, position=(0, 0))
        follower = m.body("follower", mass=0.1, inertia=0.001, position=(0, 0.06))
        m.cam("contact", cam, follower, (0, 0), radius=radius, surface_radius=surface_radius, profile=profile,
              roller_radius=roller_radius)
        with pytest.raises(linkwork.ModelError) as error:
            m.build()
        return dict(error.value.problems)

    assert "give one of radius" in problems(radius="0.05", surface_radius="0.04")["joints.contact"]
    assert "expected u" in problems(profile={"x": "cos(u)", "y": "sin(psi)"})["joints.contact.profile.y"]
    closes = problems(profile={"x": "cos(u)", "y": "sin(u)", "period": 6})["joints.contact.profile.period"]
    assert "does not close" in closes
    undercut = problems(surface_radius="1 + 0.6*cos(psi)", roller_radius=0.85)["joints.contact.roller_radius"]
    assert "an undercut" in undercut
    assert "cannot read" in problems(profile={"file": "no-such.csv", "x": "x", "y": "y"})["joints.contact.profile.file"]


def test_a_profiles_file_travels_with_the_output_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The table of points is read beside the model file, and an output folder holds a copy at
    the path its model.yaml names, so that it runs again there."""
    monkeypatch.chdir(ROOT)
    results = linkwork.load("examples/cam_profile.yaml").run("motion")
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    results.write(out, report=False)
    assert (out / "data" / "cam_disc.csv").read_bytes() == (EXAMPLES / "data" / "cam_disc.csv").read_bytes()
    rerun = linkwork.load(out / "model.yaml").run("motion")
    np.testing.assert_array_equal(rerun["lower.y"], results["lower.y"])
