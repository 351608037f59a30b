"""Units end to end (docs/model-format.md, "Parameters and units" and "Display units"): values
with units from every way in, the rule for a bare number, a model's `display:` section in what
is printed and plotted while the files stay SI, and a sweep's exit status."""

from __future__ import annotations

import csv
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import linkwork
from linkwork import figures, page, report
from conftest import EXAMPLES, RunLinkwork, patch
from linkwork.sweep import grid_values, range_values

MODEL = EXAMPLES / "slider_crank_param.yaml"
TEXT = MODEL.read_text()
OUTPUT = "stroke=max(slider.x) - min(slider.x)"


def test_set_with_a_unit_prints_it_and_runs_the_value(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = linkwork("run", MODEL, "--set", "r=120 mm", "-a", "kinematics", "--out", "a", "--no-report", "-q")
    assert out.code == 0, out.stderr
    assert "parameters set: r = 120 mm (given 120 mm)" in out.stdout
    rows = list(csv.DictReader((tmp_path / "a" / "results.csv").read_text().splitlines()))
    x = [float(row["slider.x"]) for row in rows]
    # The stroke of a centred slider-crank is 2 r, SI in the file: 0.24 m (the kinematics hold
    # the loop to 1e-10 m, far below this 1e-9).
    assert abs(max(x) - min(x) - 0.24) < 1e-9


def test_a_bare_number_is_si_and_one_far_from_the_files_value_is_warned_of(linkwork: RunLinkwork) -> None:
    # r: 100 mm in the file; 0.12 is SI (120 mm), 1.2 times it: no warning.
    out = linkwork("run", MODEL, "--set", "r=0.12", "-a", "kinematics", "--no-report", "-q")
    assert out.code == 0 and "warning: parameters.r" not in out.stderr, out.stderr
    assert "r = 120 mm (given 0.12)" in out.stdout
    # L: 300 mm; 300 is 300 m, 1000 times the file's value: run as SI, and said.
    out = linkwork("run", MODEL, "--set", "L=300", "-a", "kinematics", "--no-report", "-q")
    assert "warning: parameters.L: the bare number 300 is read as SI, 300 m, 1000 times the file's value 300 mm" in out.stderr
    assert "write L='300 mm' to give it in mm" in out.stderr
    assert "L = 300000 mm (given 300)" in out.stdout


def test_python_warns_of_a_far_bare_number_and_takes_units() -> None:
    model = linkwork.load(MODEL)
    with pytest.warns(UserWarning, match="parameters.r: the bare number 50.0 is read as SI, 50.0 m, 500 times"):
        far = model.with_parameters(r=50)
    assert far.parameters["r"] == 50.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert model.with_parameters(r="12 cm").parameters["r"] == pytest.approx(0.12, rel=1e-15)
        assert model.with_parameters(r=0.12).parameters["r"] == 0.12


def test_grid_and_range_take_units_on_both_ends() -> None:
    name, values = grid_values("r=12 mm:18 mm:7")
    assert name == "r" and values == [f"{v!r} mm" for v in (12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 18.0)]
    # A unit per end, converted to the first's: 1.8 cm is 18 mm.
    assert grid_values("r=12 mm:1.8 cm:2")[1] == ["12.0 mm", f"{1.8 * 0.01 / 0.001!r} mm"]
    assert grid_values("r=0.1:0.2:3")[1] == [0.1, 0.15000000000000002, 0.2]
    assert range_values("r=50 mm:150 mm") == ("r", ("50.0 mm", "150.0 mm"))
    for bad, says in (("r=12 mm:0.018:3", "a unit on one end only"), ("r=12 furlong:1 m:2", "unknown unit 'furlong'")):
        with pytest.raises(ValueError, match=says):
            grid_values(bad)


def test_a_grid_with_units_sweeps_in_si(linkwork: RunLinkwork, tmp_path: Path) -> None:
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    out = linkwork("sweep", MODEL, "--grid", "r=80 mm:120 mm:3", "--output", OUTPUT, "--out", "s", "-q")
    assert out.code == 0, out.stderr
    table = pd.read_parquet(tmp_path / "s" / "sweep.parquet")
    # The parameter column is SI, and says so; the stroke is 2 r (to the loop's 1e-9 m).
    assert table["r"].tolist() == pytest.approx([0.08, 0.1, 0.12], rel=1e-15)
    assert np.allclose(table["stroke"].astype(float), 2 * table["r"], atol=1e-9, rtol=0)
    assert table.attrs["units"] == {"r": "m", "stroke": "SI"}


def test_a_sample_over_a_range_with_units_stays_in_it() -> None:
    pytest.importorskip("pandas")
    table = linkwork.sweep(MODEL, "kinematics", outputs=dict([OUTPUT.split("=", 1)]), sample=4,
                           ranges={"r": ("80 mm", "120 mm")}, seed=3, workers=1)
    assert ((table["r"] >= 0.08) & (table["r"] <= 0.12)).all() and (table["status"] == "ok").all()


def test_a_sweep_in_which_every_variant_fails_exits_3_and_some_failing_exit_0(linkwork: RunLinkwork) -> None:
    pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    # r = 12 m and 18 m on a 300 mm rod: no variant assembles through the turn.
    out = linkwork("sweep", MODEL, "--grid", "r=12:18:2", "--output", OUTPUT, "--out", "s", "-q")
    assert out.code == 3, out.stderr
    assert "0 ok, 2 failed" in out.stdout and "error: every variant failed" in out.stderr
    assert "warning: parameters.r: the bare number 12.0 is read as SI" in out.stderr
    out = linkwork("sweep", MODEL, "--grid", "r=100 mm:400 mm:2", "--output", OUTPUT, "--out", "t", "-q")
    assert out.code == 0, out.stderr
    assert "1 ok, 1 failed" in out.stdout and "warning: 1 of 2 variants failed" in out.stderr


def test_sweep_help_lists_every_aggregation(linkwork: RunLinkwork) -> None:
    out = linkwork("sweep", "--help")
    text = " ".join(out.stdout.split())
    for aggregation in ("max", "min", "peak", "integral", "mean", "rms", "initial", "final", "at"):
        assert f"{aggregation}," in text or f"{aggregation} (" in text, aggregation


def test_a_display_model_prints_and_plots_in_its_units_while_the_files_stay_si(
    linkwork: RunLinkwork, tmp_path: Path
) -> None:
    out = linkwork("run", MODEL, "-a", "inverse", "--out", "a", "--no-report", "-q")
    assert out.code == 0, out.stderr
    assert "shown in the model's display units (length mm, angle deg" in out.stdout
    assert "N m at t = " in out.stdout
    rows = list(csv.DictReader((tmp_path / "a" / "results.csv").read_text().splitlines()))
    # results.csv stays SI: the crank turns once, 2 pi rad (not 360), the stroke is 0.2 m.
    assert abs(float(rows[-1]["crank.phi"]) - 2 * math.pi) < 1e-9
    x = [float(r["slider.x"]) for r in rows]
    assert abs(max(x) - min(x) - 0.2) < 1e-9


def test_a_display_model_plots_in_its_units() -> None:
    run = linkwork.load(MODEL).run("inverse")._run()
    fig = figures.line_figure(run, ["crank.phi"])
    assert fig["layout"]["yaxis"]["title"]["text"] == "deg"
    # The plotted angle is the SI column in degrees (to the 6 digits the report draws).
    plotted = np.array(fig["data"][0]["y"], dtype=float)
    assert plotted[-1] == pytest.approx(360.0, rel=1e-6)
    fig = figures.line_figure(run, ["slider.x"])
    assert fig["layout"]["yaxis"]["title"]["text"] == "mm"
    assert max(fig["data"][0]["y"]) == pytest.approx(400.0, rel=1e-6)
    mechanism = figures.mechanism_figure(run)
    assert mechanism["layout"]["xaxis"]["title"]["text"] == "x (mm)"
    # The slider's block is drawn about its x: in mm, some point of the picture is near 400.
    xs = [x for trace in mechanism["data"] for x in trace.get("x", []) if x is not None]
    assert max(xs) > 350


def test_the_report_tables_say_their_units() -> None:
    run = linkwork.load(MODEL).run("inverse")._run()
    html = page.summary_html(run.summary, run.units)
    assert " N m at t = " in html and " N at t = " in html


def test_e_may_name_a_parameter_unless_the_file_uses_eulers_number() -> None:
    text = patch(TEXT, "  r: 100 mm ± 0.1 mm\n", "  e: 100 mm\n  r: e\n")
    assert linkwork.from_yaml(text).parameters["r"] == pytest.approx(0.1, rel=1e-15)
    text = patch(TEXT, "  r: 100 mm ± 0.1 mm\n", "  k: 2*e\n  e: 100 mm\n  r: e\n")
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(text)
    [(path, message)] = [p for p in error.value.problems if p[0] == "parameters.e"]
    assert "parameters.k before it uses e as Euler's number" in message and "rename this parameter" in message


def test_a_display_section_with_a_wrong_unit_is_named() -> None:
    text = patch(TEXT, "display: {length: mm, angle: deg}", "display: {length: deg, speed: mm/s}")
    with pytest.raises(linkwork.ModelError) as error:
        linkwork.from_yaml(text)
    problems = dict(error.value.problems)
    assert problems["display.length"] == "'deg' is an angle, expected a length"
    assert problems["display.speed"].startswith("unknown quantity; expected one of length, angle")


# --- files in display units (--units display) ------------------------------------------------

# The model with a measure of a known quantity (a point's x, a length) and one of none (an
# expression: written as computed, "SI").
MEASURED = patch(TEXT, "analyses:\n", 'measures:\n  tip_x: {body: crank, point: A, component: x}\n  twice: "2 * slider.x"\nanalyses:\n')


def _table(folder: Path) -> tuple[list[str], np.ndarray]:
    rows = list(csv.reader((folder / "results.csv").read_text().splitlines()))
    return rows[0], np.array(rows[1:], dtype=float)


def _summary(folder: Path) -> dict[str, object]:
    import json

    summary: dict[str, object] = json.loads((folder / "summary.json").read_text())
    return summary


def test_display_files_are_the_si_files_divided_by_each_units_factor(tmp_path: Path) -> None:
    results = linkwork.from_yaml(MEASURED).run("inverse")
    results.write(tmp_path / "si", report=False)
    results.write(tmp_path / "display", report=False, units="display")
    header, si = _table(tmp_path / "si")
    shown_header, shown = _table(tmp_path / "display")
    assert shown_header == header == list(results)
    si_summary, summary = _summary(tmp_path / "si"), _summary(tmp_path / "display")
    assert si_summary["unit_system"] == "si" and summary["unit_system"] == "display"
    si_units, units = si_summary["units"], summary["units"]
    assert isinstance(si_units, dict) and isinstance(units, dict)
    # Every column of the file, in its order, has its unit; chosen by the engine's quantity of
    # the column and the model's display: {length: mm, angle: deg}, the rest SI.
    assert list(units) == list(si_units) == header
    expected = {"time": ("s", "s"), "slider.x": ("m", "mm"), "crank.phi": ("rad", "deg"),
                "crank.omega": ("rad/s", "deg/s"), "slider.ax": ("m/s^2", "mm/s^2"),
                "motor.effort": ("N m", "N m"), "B.fx": ("N", "N"), "tip_x": ("m", "mm"), "twice": ("SI", "SI")}
    for column, (in_si, in_display) in expected.items():
        assert (si_units[column], units[column]) == (in_si, in_display), column
    # Each display column is the SI column divided by its unit's factor to SI, as the engine
    # reads that unit: the division and the shortest round-trip text of each double are exact to
    # half an ulp each, far inside 1e-12 relative (zeros stay zeros: no absolute slack).
    for k, column in enumerate(header):
        factor = 1.0 if units[column] == "SI" else linkwork._linkwork.unit(units[column])
        assert np.allclose(shown[:, k] * factor, si[:, k], rtol=1e-12, atol=0), column
    # Against the closed form: the crank turns once, 360 deg; the stroke is 2 r = 200 mm.
    assert shown[-1, header.index("crank.phi")] == pytest.approx(360.0, rel=1e-9)
    x = shown[:, header.index("slider.x")]
    assert abs(x.max() - x.min() - 200.0) < 1e-6
    # summary.json's own numbers stay SI whatever the table's units.
    parameters = summary["parameters"]
    assert parameters == si_summary["parameters"] and isinstance(parameters, dict) and parameters["r"] == 0.1


def test_a_folder_written_in_display_units_reports_as_the_si_one(linkwork: RunLinkwork, tmp_path: Path) -> None:
    model = tmp_path / "measured.yaml"
    model.write_text(MEASURED)
    for units in ("si", "display"):
        out = linkwork("run", model, "-a", "inverse", "--out", units, "--units", units, "--no-report", "-q")
        assert out.code == 0, out.stderr
    assert "results.csv is in them too" in out.stdout
    out = linkwork("report", "display")
    assert out.code == 0, out.stderr
    assert (tmp_path / "display" / "report.html").exists()
    si, shown = report.from_folder(tmp_path / "si"), report.from_folder(tmp_path / "display")
    # Read back to SI by the units summary.json records: each value divided, written, read and
    # multiplied again, within a few ulps (1e-12 relative).
    assert np.allclose(shown.time, si.time, rtol=1e-12, atol=0)
    assert list(shown.columns) == list(si.columns)
    for name, values in si.columns.items():
        assert np.allclose(shown.columns[name], values, rtol=1e-12, atol=0), name
    # The report of either folder shows the display units.
    assert shown.units.column_unit("crank.phi") == "deg"


def test_a_display_table_without_its_units_is_refused(tmp_path: Path) -> None:
    import json

    linkwork.from_yaml(TEXT).run("kinematics").write(tmp_path, report=False, units="display")
    summary = _summary(tmp_path)
    units = summary["units"]
    assert isinstance(units, dict)
    del units["slider.x"]
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(linkwork.FileError, match=r"units: no unit for the column\(s\) slider.x of results.csv"):
        report.from_folder(tmp_path)
    units["slider.x"] = "furlong"
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(linkwork.FileError, match=r"summary.json: units.slider.x: .*furlong"):
        report.from_folder(tmp_path)


def test_units_must_be_si_or_display(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = linkwork("run", MODEL, "-a", "kinematics", "--units", "mm", "--no-report", "-q")
    assert out.code == 2 and "--units: invalid choice: 'mm'" in out.stderr and "display" in out.stderr
    out = linkwork("run", MODEL, "-a", "kinematics", "--units", "display", "--stream", "--no-report", "-q")
    assert out.code == 2 and "--units: display cannot be used with --stream" in out.stderr
    assert not (tmp_path / "out").exists()


def test_python_takes_units_si_or_display(tmp_path: Path) -> None:
    results = linkwork.from_yaml(TEXT).run("kinematics")
    with pytest.raises(ValueError, match="units: expected 'si' or 'display', got 'SI'"):
        results.write(tmp_path / "a", units="SI")
    streamed = linkwork.from_yaml(TEXT).run("kinematics", stream=tmp_path / "rows.csv")
    with pytest.raises(ValueError, match="cannot be written for a streamed run"):
        streamed.write(tmp_path / "b", units="display")
    pytest.importorskip("pandas")
    with pytest.raises(ValueError, match="units: expected 'si' or 'display', got 'deg'"):
        linkwork.sweep(MODEL, "kinematics", {"r": [0.1]}, dict([OUTPUT.split("=", 1)]), units="deg")


def test_a_sweep_in_display_units(linkwork: RunLinkwork, tmp_path: Path) -> None:
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    for units in ("si", "display"):
        out = linkwork("sweep", MODEL, "--grid", "r=80 mm:120 mm:3", "--output", OUTPUT, "--out", units, "--units", units, "-q")
        assert out.code == 0, out.stderr
    si, shown = (pd.read_parquet(tmp_path / units / "sweep.parquet") for units in ("si", "display"))
    # The table says its units, in the Parquet file's metadata: the parameter in the display
    # section's mm, the output as computed (SI, the stroke in m).
    assert shown.attrs["units"] == {"r": "mm", "stroke": "SI"} and shown.attrs["unit_system"] == "display"
    assert si.attrs["units"] == {"r": "m", "stroke": "SI"} and si.attrs["unit_system"] == "si"
    # 80, 100, 120 mm: each SI value divided by 1e-3 (exact to an ulp or two, 1e-12 relative).
    assert np.allclose(shown["r"], [80.0, 100.0, 120.0], rtol=1e-12, atol=0)
    assert np.allclose(shown["r"] * 1e-3, si["r"], rtol=1e-12, atol=0)
    assert shown["stroke"].astype(float).tolist() == si["stroke"].astype(float).tolist()
