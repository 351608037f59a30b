"""The command line's contract: files written, exit codes 0 / 2 / 3, and what it prints."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from conftest import EXAMPLES, ROOT, RunLinkwork, patch, run_process

QUANTITIES = ["x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha"]


def read_csv(path: Path) -> tuple[list[str], list[list[float]]]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) for v in row] for row in rows[1:]]


def test_run_writes_results_and_summary(linkwork: RunLinkwork, tmp_path: Path) -> None:
    done = linkwork("run", EXAMPLES / "quick_return_a.yaml")
    assert done.code == 0, done.output
    out = tmp_path / "out" / "quick_return_a"
    header, rows = read_csv(out / "results.csv")
    bodies = ["crank", "rocker", "slider_b", "link", "slider_d"]
    assert header == ["time"] + [f"{b}.{q}" for b in bodies for q in QUANTITIES]
    assert len(rows) == 41  # 0 to 2 s every 0.05 s
    assert rows[0][0] == 0.0 and rows[-1][0] == 2.0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert summary["analysis"] == "kinematics"
    assert summary["output_points"] == 41
    # The short summary names the analysis, the size of the run and where the files went.
    assert "kinematics" in done.stdout
    assert "41 output points" in done.stdout
    assert "out/quick_return_a/results.csv" in done.stdout
    assert done.stderr == ""


def test_run_with_analysis_and_out(linkwork: RunLinkwork, tmp_path: Path) -> None:
    done = linkwork("run", EXAMPLES / "fourbar.yaml", "--analysis", "kinematics", "--out", tmp_path / "here")
    assert done.code == 0, done.output
    assert (tmp_path / "here" / "results.csv").is_file()
    assert json.loads((tmp_path / "here" / "summary.json").read_text())["status"] == "ok"


def test_a_tolerance_below_round_off_is_a_warning_not_a_failure(linkwork: RunLinkwork, tmp_path: Path) -> None:
    done = linkwork(
        "run",
        EXAMPLES / "iftomm_a01_pendulum.yaml",
        "--integrator",
        "hht",
        "--rtol",
        "1e-17",
        "--t-end",
        "0.1",
        "--out",
        tmp_path / "o",
    )
    assert done.code == 0, done.output
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert len(summary["warnings"]) == 1 and "solver.rtol 1e-17" in summary["warnings"][0]
    assert "warning: solver.rtol 1e-17 is below what round-off allows" in done.stdout


def test_unknown_analysis_is_a_model_error(linkwork: RunLinkwork) -> None:
    done = linkwork("run", EXAMPLES / "fourbar.yaml", "--analysis", "dynamics")
    assert done.code == 2
    assert "analyses.dynamics: no analysis named 'dynamics'" in done.stderr
    assert "kinematics" in done.stderr  # the ones there are


def test_missing_model_file_exits_2_without_traceback(linkwork: RunLinkwork, tmp_path: Path) -> None:
    for command in ["run", "check"]:
        done = linkwork(command, tmp_path / "nowhere.yaml")
        assert done.code == 2, done.output
        assert "nowhere.yaml" in done.stderr
        assert "No such file" in done.stderr
        assert "Traceback" not in done.output


def test_folder_instead_of_model_file_exits_2(linkwork: RunLinkwork, tmp_path: Path) -> None:
    done = linkwork("run", tmp_path)
    assert done.code == 2
    assert "Traceback" not in done.output


def test_unwritable_output_folder_exits_2(linkwork: RunLinkwork, tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    done = linkwork("run", EXAMPLES / "fourbar.yaml", "--out", blocker / "out")
    assert done.code == 2, done.output
    assert "Traceback" not in done.output


def test_usage_errors_exit_2(linkwork: RunLinkwork) -> None:
    assert linkwork().code == 2
    assert linkwork("fly", "model.yaml").code == 2
    assert linkwork("run").code == 2


def test_version(linkwork: RunLinkwork) -> None:
    import linkwork as package

    done = linkwork("--version")
    assert done.code == 0
    assert package.__version__ in done.output


def test_schema(linkwork: RunLinkwork) -> None:
    done = linkwork("schema")
    assert done.code == 0
    schema = json.loads(done.stdout)
    assert {"bodies", "joints", "drivers", "analyses"} <= set(schema["properties"])


def test_lock_up_exits_3_and_keeps_partial_results(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """The slider-crank whose rod is shorter than its crank locks up at theta = asin(0.6) =
    0.6435 rad = t (see the example's comment)."""
    done = linkwork("run", EXAMPLES / "slider_crank_lockup.yaml")
    assert done.code == 3, done.output
    assert "Traceback" not in done.output
    # When: the time, as printed by the engine and by the command line.
    assert re.search(r"t = 0\.6435\d* s", done.stderr), done.stderr
    # Where: the joints involved.
    joints = re.search(r"in joint\(s\) ([\w, ]+)", done.stderr)
    assert joints, done.stderr
    assert {"A", "B", "guide"} <= set(joints.group(1).split(", "))
    # The results until then are kept, and the summary says the run failed.
    out = tmp_path / "out" / "slider_crank_lockup"
    header, rows = read_csv(out / "results.csv")
    assert header[:4] == ["time", "crank.x", "crank.y", "crank.phi"]
    assert 10 <= len(rows) <= 13  # 0 to 0.6 s every 0.05 s
    assert rows[-1][0] < 0.6436
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert summary["error_time"] == pytest.approx(0.6435, abs=1e-3)
    assert {"A", "B", "guide"} <= set(summary["error_elements"])
    assert "singular" in summary["error"]
    assert str(len(rows)) in done.stderr and "partial results" in done.stderr


def test_check_text(linkwork: RunLinkwork) -> None:
    done = linkwork("check", EXAMPLES / "quick_return_a.yaml")
    assert done.code == 0, done.output
    text = done.stdout
    assert "crank, rocker, slider_b, link, slider_d" in text
    assert "15 coordinates" in text
    mechanism, analysis = text.split("analysis 'kinematics'")
    assert re.search(r"equations\s+14\b", mechanism)
    assert re.search(r"degrees of freedom\s+1\b", mechanism)
    assert re.search(r"Gruebler count\s+1\b", mechanism)
    assert re.search(r"redundant rows\s+none", mechanism)
    assert re.search(r"assembly\s+residual", mechanism)
    # The crank angle is given (held), so the largest change from the guess is elsewhere.
    largest = re.search(r"change from guess\s+largest (\w+\.\w+) ([-+][\d.e+-]+)", mechanism)
    assert largest and largest.group(1) != "crank.phi", mechanism
    assert re.search(r"crank\s+[-+][\d.e+-]+\s+[-+][\d.e+-]+\s+\+0\.000e\+00", mechanism), mechanism
    assert "crank_drive" in analysis
    assert re.search(r"degrees of freedom\s+0\b", analysis)
    assert re.search(r"equations\s+15\b", analysis)


def test_check_names_redundant_rows_by_joint_and_equation(linkwork: RunLinkwork) -> None:
    done = linkwork("check", EXAMPLES / "parallelogram.yaml")
    assert done.code == 0, done.output
    assert re.search(r"redundant rows\s+1", done.stdout)
    assert "joint coupler_3, equation y" in done.stdout
    assert re.search(r"Gruebler count\s+0\b", done.stdout)
    assert re.search(r"degrees of freedom\s+1\b", done.stdout)


def test_check_lists_what_was_placed_from_global_coordinates(linkwork: RunLinkwork) -> None:
    done = linkwork("check", EXAMPLES / "fourbar_placed.yaml")
    assert done.code == 0, done.output
    placed = done.stdout.split("placed from global coordinates", 1)[1].split("\n\n", 1)[0]
    # The crank's A is 0.05 m along +x from its centre M; the pin O2 on ground is the global origin.
    assert re.search(r"bodies\.crank\.points\.A\s+\[0\.05, 0\]", placed), placed
    assert re.search(r"joints\.O2\.point_j\s+\[0, 0\]", placed), placed
    assert len(placed.strip().splitlines()) == 1 + 9 + 8
    report = json.loads(linkwork("check", EXAMPLES / "fourbar_placed.yaml", "--json").stdout)
    assert report["placed"]["bodies.rocker.points.O4"][0] == pytest.approx(0.015625, abs=1e-15)
    # A model placed in body frames places nothing, and says nothing about it.
    assert "placed from" not in linkwork("check", EXAMPLES / "fourbar.yaml").stdout


def test_check_lists_the_analyses_in_file_order(linkwork: RunLinkwork) -> None:
    # The file's order (tests/test_api.py checks Model.analyses gives it), which sorting would change.
    order = ["kinematics", "dynamics", "dynamics_loaded", "inverse"]
    assert order != sorted(order)
    text = linkwork("check", EXAMPLES / "quick_return_a.yaml").stdout
    assert re.findall(r"analysis '(\w+)'", text) == order
    report = json.loads(linkwork("check", EXAMPLES / "quick_return_a.yaml", "--json").stdout)
    assert list(report["analyses"]) == order


def test_check_json(linkwork: RunLinkwork) -> None:
    done = linkwork("check", EXAMPLES / "parallelogram.yaml", "--json")
    assert done.code == 0, done.output
    report = json.loads(done.stdout)
    mechanism = report["mechanism"]
    assert (mechanism["gruebler_dof"], mechanism["dof"]) == (0, 1)
    assert mechanism["redundant"] == [{"element": "coupler_3", "equation": "y"}]
    assert len(mechanism["assembly"]["change"]) == report["coordinates"] == 12
    assert report["analyses"]["kinematics"]["dof"] == 0


def test_readme_quick_start(tmp_path: Path) -> None:
    """The README's quick start is exactly two commands: the first installs and runs the
    quick-return example (its `linkwork` part is run here, from a folder holding the examples),
    the second installs and runs every test (the command `.ci/run` runs)."""
    readme = (ROOT / "README.md").read_text()
    quick_start = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    (block,) = re.findall(r"```sh\n(.*?)```", quick_start, flags=re.S)
    first, second = block.strip().splitlines()
    install, run = (part.strip() for part in first.split("&&"))
    assert install == "pip install ."
    command = run.split()
    assert command[:2] == ["linkwork", "run"] and "examples/quick_return_a.yaml" in command
    assert "cargo test" in second and "pytest" in second
    (tmp_path / "examples").symlink_to(EXAMPLES)
    done = run_process(command[1:], tmp_path)
    assert done.code == 0, (command, done.output)
    assert (tmp_path / "out" / "quick_return_a" / "results.csv").is_file()
    assert (tmp_path / "out" / "quick_return_a" / "summary.json").is_file()


def test_readme_python_snippet(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    readme = (ROOT / "README.md").read_text()
    (snippet,) = re.findall(r"```python\n(.*?)```", readme, flags=re.S)
    (tmp_path / "examples").symlink_to(EXAMPLES)
    monkeypatch.chdir(tmp_path)
    exec(compile(snippet, "README.md", "exec"), {})
    assert capsys.readouterr().out.splitlines()[0] == "1"
    assert (tmp_path / "out" / "quick_return_a" / "results.csv").is_file()


def test_internal_error_exits_1(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from linkwork import Model, _linkwork, cli

    def explode(path: str, parameters: object = None) -> None:
        _linkwork._panic_for_tests()

    monkeypatch.setattr(Model, "load", staticmethod(explode))
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", str(EXAMPLES / "fourbar.yaml")]) == 1
    err = capsys.readouterr().err
    assert "internal error" in err and "please report it" in err


RUNAWAY_DRIVER = """
name: crank driven by 1/(t-1)
bodies:
  crank: {mass: 1, inertia: 0.1, position: [0.5, 0], angle: 0, points: {O: [-0.5, 0]}}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
drivers:
  motor: {type: angle, body: crank, function: "1/(t-1)"}
analyses:
  kinematics: {type: kinematic, drivers: [motor], t_end: 2, step: 0.01}
"""


def test_a_runaway_driver_exits_3_naming_it(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """The driver 1/(t-1) hung the kinematic analysis, writing nothing; it now stops at the
    output before t = 1 s, names the driver and its function, and keeps the rows before it."""
    model = tmp_path / "runaway.yaml"
    model.write_text(RUNAWAY_DRIVER)
    out = tmp_path / "out"
    done = linkwork("run", model, "-o", out)
    assert done.code == 3, done.output
    assert "drivers.motor is inf at t = 1 s (1/(t-1))" in done.stderr
    header, rows = read_csv(out / "results.csv")
    assert len(rows) == 100 and rows[-1][0] == pytest.approx(0.99)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["error_time"] == 1.0


def test_a_failure_time_reads_the_same_in_every_line(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """A failure just after the start was printed as `t = 0.000000 s` in the error and
    `t = 1.49e-10 s` in the line after it. Both lines now write the time alike (Python's `.9g`),
    here for a driver that is NaN past 1e-9 s."""
    model = tmp_path / "soon.yaml"
    model.write_text(patch(RUNAWAY_DRIVER, 'function: "1/(t-1)"', 'function: "sqrt(1e-9-t)"'))
    done = linkwork("run", model, "-o", tmp_path / "out")
    assert done.code == 3, done.output
    times = re.findall(r"at t = (\S+) s", done.stderr)
    assert len(times) == 2 and times[0] == times[1], done.stderr
    assert 0 < float(times[0]) < 2e-9 and "e-" in times[0], done.stderr



def test_meaningless_tolerances_are_refused_at_the_option(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """`--rtol 1e300` ran the double pendulum to a pin 1,168 m off its anchor with exit 0 and
    status ok; a tolerance above 1e-2 is now a model error at the option, and nothing runs."""
    for option in ("--rtol", "--atol"):
        done = linkwork("run", EXAMPLES / "double_pendulum.yaml", option, "1e300", "-o", tmp_path / option)
        assert done.code == 2, done.output
        assert f"{option}: expected at most 1e-2, found 1e300" in done.stderr
        assert not (tmp_path / option / "results.csv").exists()


def test_kinematics_at_a_huge_time_exits_3_saying_why(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """The slider-crank started at t = 1e12 s ended ok with a joint open by centimetres; it now
    fails at its first output naming the row, the time and the round-off that caused it."""
    model = tmp_path / "late.yaml"
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    model.write_text(patch(text, "t_end: 2.0,", "t_start: 1.0e12, t_end: 1000000000000.5,"))
    out = tmp_path / "out"
    done = linkwork("run", model, "-o", out)
    assert done.code == 3, done.output
    # The row with the largest residual: a joint of the crank's loop (A or B, as round-off falls).
    named = re.search(r"position residual \S+ at t = 1e\+12 s in (\w+)\.[xy]", done.stderr)
    assert named is not None and named[1] in ("A", "B"), done.stderr
    assert "start the analysis near t = 0" in done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["error_time"] == 1e12
    assert summary["error_elements"] == [named[1]]


def test_check_states_every_dyads_branch_in_the_display_units(linkwork: RunLinkwork) -> None:
    """examples/sixbar_leg.yaml: each dyad's side of its line, drawn and declared, and the change
    from the guess in the model's display units (mm, deg)."""
    done = linkwork("check", EXAMPLES / "sixbar_leg.yaml")
    assert done.code == 0, done.output
    assert re.search(r"branch F\s+right of C -> D \(drawn right, declared right; bodies linkf, foot\)", done.stdout)
    assert re.search(r"branch B\s+left of A -> Q \(drawn left, declared left; bodies coupler, rocker\)", done.stdout)
    assert re.search(r"x \(mm\)\s+y \(mm\)\s+phi \(deg\)", done.stdout), done.stdout
    largest = re.search(r"change from guess\s+largest (\w+\.\w+) ([-+][\d.e+-]+) (\w+)", done.stdout)
    assert largest and largest.group(3) == ("deg" if largest.group(1).endswith(".phi") else "mm"), done.stdout
