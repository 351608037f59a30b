"""Parameters and units from Python and the command line (docs/model-format.md, "Parameters and
units"): values given from outside give what editing the file gives, bit for bit; a unit of the
wrong dimension is exit 2 naming the field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, WriteModel, patch

MODEL = EXAMPLES / "slider_crank_param.yaml"
TEXT = MODEL.read_text()
COLUMNS = ("slider.x", "rod.phi", "crank.omega", "slider.ax")


def same_results(a: linkwork.Results, b: linkwork.Results) -> None:
    """Equal bit for bit in time and in every compared column."""
    np.testing.assert_array_equal(a.time, b.time)
    for name in COLUMNS:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_load_and_with_parameters_equal_an_edited_file() -> None:
    edited = linkwork.from_yaml(patch(TEXT, "r: 100 mm", "r: 120 mm")).run("kinematics")
    by_load = linkwork.load(MODEL, parameters={"r": 0.12}).run("kinematics")
    by_unit = linkwork.load(MODEL).with_parameters(r="120 mm").run("kinematics")
    same_results(by_load, edited)
    same_results(by_unit, edited)
    model = linkwork.load(MODEL).with_parameters(r=0.12)
    assert model.parameters["r"] == 0.12
    assert model.parameters["m_crank"] == pytest.approx(5.0 * 0.12, rel=1e-15)
    assert by_load.summary.parameters == model.parameters


def test_the_stroke_is_twice_the_radius_for_each_radius() -> None:
    model = linkwork.load(MODEL)
    for r in (0.05, 0.075, 0.1, 0.125, 0.15):
        x = model.with_parameters(r=r).run("kinematics")["slider.x"]
        assert abs(float(x.max() - x.min()) - 2 * r) < 1e-9, r


def test_a_parameter_value_that_is_not_a_number_or_text_is_a_type_error() -> None:
    with pytest.raises(TypeError, match="parameter r"):
        linkwork.load(MODEL).with_parameters(r=True)


def test_an_unknown_parameter_is_named() -> None:
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.load(MODEL, parameters={"radius": 0.1})
    assert any(path == "parameters.radius" for path, _ in error.value.problems)


def test_set_on_the_command_line_equals_an_edited_file(linkwork: RunLinkwork, tmp_path: Path) -> None:
    edited = tmp_path / "edited.yaml"
    edited.write_text(patch(patch(TEXT, "r: 100 mm", "r: 120 mm"), "L: 300 mm", "L: 0.32"))
    a = linkwork("run", MODEL, "--set", "r=0.12", "--set", "L=320 mm", "--out", "a", "--no-report", "-q")
    b = linkwork("run", edited, "--out", "b", "--no-report", "-q")
    assert (a.code, b.code) == (0, 0), a.output + b.output
    assert (tmp_path / "a" / "results.csv").read_bytes() == (tmp_path / "b" / "results.csv").read_bytes()
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["parameters"]["r"] == 0.12
    assert summary["parameters"]["L"] == 0.32


def test_the_report_of_a_run_with_set_draws_the_mechanism_as_run(linkwork: RunLinkwork, tmp_path: Path) -> None:
    assert linkwork("run", MODEL, "--set", "r=0.12", "--out", "a", "-q").code == 0
    from linkwork import report

    run = report.from_folder(tmp_path / "a")
    crank = next(b for b in run.drawing["bodies"] if b["name"] == "crank")
    assert max(abs(p[0]) for p in crank["points"].values()) == pytest.approx(0.06, rel=1e-12)


def test_a_unit_of_the_wrong_dimension_is_exit_2_naming_the_field(
    linkwork: RunLinkwork, write_model: WriteModel
) -> None:
    path = write_model(patch(TEXT, "mass: m_crank", "mass: 40 mm"))
    out = linkwork("run", path, "-q", "--no-report")
    assert out.code == 2, out.output
    assert "bodies.crank.mass: 'mm' is a length, expected a mass" in out.output
    out = linkwork("run", MODEL, "--set", "r=2 kg", "-q", "--no-report")
    assert out.code == 2, out.output
    assert "parameters.r: '2 kg' is a mass, expected a length" in out.output


def test_a_set_without_a_value_is_a_usage_error(linkwork: RunLinkwork) -> None:
    out = linkwork("run", MODEL, "--set", "r")
    assert out.code == 2
    assert "expected NAME=VALUE" in out.output
