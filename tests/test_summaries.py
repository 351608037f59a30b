"""Summaries (a model's `summaries:`, whole-run numbers, docs/model-format.md "Summaries") through
Python, the builder, the command line and the report: the same values everywhere, and each
problem at `summaries.<name>`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, WriteModel, patch
from linkwork import page, report

WHEEL = """
parameters: {w: 3}
bodies:
  wheel: {mass: 1, inertia: 0.1, position: [0, 0], points: {O: [0, 0]}}
joints:
  O: {type: revolute, body_i: wheel, point_i: O, body_j: ground, point_j: [0, 0]}
drivers:
  motor: {type: angle, body: wheel, function: "w*t"}
measures:
  p: "t^3 - t"
summaries:
  turned: "final(wheel.phi) / w"
  cubic: "integral(p)"
analyses:
  kinematics: {type: kinematic, t_end: 2, step: 0.1}
"""
"""A wheel turned at 3 rad/s for 2 s with the measure `p = t^3 - t`: `turned` is 2, and `cubic`
the integral of `p` over [0, 2], 2, exact for a cubic (the spline reproduces it)."""


def test_summaries_are_a_dict_by_name_in_results_and_summary() -> None:
    results = linkwork.from_yaml(WHEEL).run()
    assert results.summaries == pytest.approx({"cubic": 2.0, "turned": 2.0}, abs=1e-12)
    assert results.summary.summaries == results.summaries == results.summary["summaries"]
    html = results._repr_html_()
    assert "<h3>Summaries</h3>" in html and "cubic" in html


def test_a_model_without_summaries_or_a_span_has_none() -> None:
    assert linkwork.load(EXAMPLES / "fourbar.yaml").run().summaries == {}
    text = (EXAMPLES / "hanging_fourbar.yaml").read_text() + 'summaries:\n  top: "max(crank.phi)"\n'
    model = linkwork.from_yaml(text)
    for analysis in ("rest", "vibration"):
        results = model.run(analysis)
        assert results.summaries == {} and results.summary.summaries is None, analysis


def test_the_builder_writes_summaries_and_reads_them_back() -> None:
    """`Mechanism.summary` adds an entry of `summaries:`; `to_yaml()` writes it, and
    `linkwork.from_yaml(m.to_yaml())` gives the same values as the file's model, bit for bit."""
    m = linkwork.Mechanism()
    m.parameter("w", 3)
    wheel = m.body("wheel", mass=1, inertia=0.1, position=(0, 0), points={"O": (0, 0)})
    m.revolute("O", wheel, "ground", point_i="O", point_j=(0, 0))
    m.driver("motor", "angle", body=wheel, function="w*t")
    m.measure("p", "t^3 - t")
    m.summary("turned", "final(wheel.phi) / w")
    m.summary("cubic", "integral(p)")
    m.analysis("kinematics", "kinematic", t_end=2, step=0.1)
    text = m.to_yaml()
    assert "summaries:\n  turned: final(wheel.phi) / w\n  cubic: integral(p)\n" in text
    built = linkwork.from_yaml(text).run()
    assert built.summaries == linkwork.from_yaml(WHEEL).run().summaries
    with pytest.raises(ValueError, match="summaries.cubic: the name is already used in summaries"):
        m.summary("cubic", "max(p)")
    # Summaries have names of their own: a measure's name is free for a summary.
    m.summary("p", "max(p)")
    assert m.build().run().summaries["p"] == pytest.approx(6.0, abs=1e-12)


def test_each_problem_names_its_summary(write_model: WriteModel) -> None:
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(WHEEL.replace('"integral(p)"', '"p + integral(p)"'))
    assert "'p' outside an aggregation" in dict(error.value.problems)["summaries.cubic"]
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(WHEEL.replace('"integral(p)"', '"integral(motor.effort)"')).run()
    message = dict(error.value.problems)["summaries.cubic"]
    assert "no result column 'motor.effort'" in message and "kinematic analysis 'kinematics'" in message
    with pytest.raises(linkwork.NonFiniteError) as failure:
        linkwork.from_yaml(WHEEL.replace('"integral(p)"', '"integral(p) / initial(time)"')).run()
    assert failure.value.element == "summaries.cubic" and failure.value.value == float("inf")
    assert "initial(time) = 0" in str(failure.value)
    partial = failure.value.results
    assert len(partial) == 21 and partial.summaries == {} and partial.summary.status == "failed"


def test_run_prints_and_writes_the_summaries_and_the_report_shows_them(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = tmp_path / "friction"
    done = linkwork("run", EXAMPLES / "slider_crank_friction.yaml", "--out", out)
    assert done.code == 0, done.output
    summary = json.loads((out / "summary.json").read_text())
    efficiency = summary["summaries"]["efficiency"]
    assert f"summary {'efficiency':<21} {efficiency:.6g}" in done.stdout
    written = (out / "report.html").read_text()
    assert "<h3>Summaries</h3>" in written and f"<td>{efficiency:.6g}</td>" in written
    # The rebuilt report reads them from summary.json.
    assert "<h3>Summaries</h3>" in page.page(report.from_folder(out), "")


def test_a_summary_that_is_not_finite_exits_3_and_keeps_the_rows(
    linkwork: RunLinkwork, write_model: WriteModel, tmp_path: Path
) -> None:
    path = write_model(patch(WHEEL, '"integral(p)"', '"integral(p) / initial(time)"'))
    done = linkwork("run", path, "--out", tmp_path / "o")
    assert done.code == 3, done.output
    assert "summaries.cubic is inf at t = 2 s" in done.stderr
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["output_points"] == 21 and "summaries" not in summary
