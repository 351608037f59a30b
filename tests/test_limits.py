"""A limit on every input, and names that cannot collide: a model file that is no regular file,
too large or nested too deep, a sweep's options (names given twice or already taken, counts of
variants and threads past their bounds, a Dask address that is none) and results too large for
memory each end with one line naming the file or the option, never a traceback, a hang or an
abort (docs/model-format.md, "Limits"; docs/reliability.md)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

import linkwork as lw
from conftest import EXAMPLES, RunLinkwork, linkwork_command, run_process
from linkwork.sweep import MAX_VARIANTS

MODEL = EXAMPLES / "slider_crank_param.yaml"
STROKE = "max(slider.x) - min(slider.x)"
SWEEP = ["sweep", str(MODEL), "--analysis", "kinematics"]


def one_error_line(out_text: str, words: str) -> None:
    """The output is one line, an error containing ``words`` (no traceback, no usage)."""
    lines = out_text.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and words in lines[0], out_text


# --- names ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--grid", "r=0.05:0.15:2", "--output", f"r={STROKE}"], "--output: r: 'r' is already the parameter parameters.r"),
        (["--grid", "r=0.05:0.15:2", "--output", f"status={STROKE}"], "--output: status: 'status' is already the column"),
        (["--grid", "r=0.05:0.15:2", "--output", f"s={STROKE}", "--output", "s=max(time)"], "--output: 's' is given twice"),
        (["--grid", "r=0.05:0.15:2", "--grid", "r=0.1:0.2:3", "--output", f"s={STROKE}"], "--grid: 'r' is given twice"),
        (
            ["--sample", "3", "--range", "r=0.05:0.15", "--range", "r=0.1:0.2", "--output", f"s={STROKE}"],
            "--range: 'r' is given twice",
        ),
    ],
    ids=["output-is-a-parameter", "output-is-status", "output-twice", "grid-twice", "range-twice"],
)
def test_a_sweep_name_taken_or_given_twice_is_one_line_naming_the_option(
    linkwork: RunLinkwork, options: list[str], words: str
) -> None:
    # It overwrote: the parameter column held the outputs, status turned into numbers, the last
    # of a repeated name was kept.
    out = linkwork(*SWEEP, *options)
    assert out.code == 2, out.output
    one_error_line(out.stderr, words)
    assert out.stdout == ""


def test_the_python_sweep_refuses_an_output_named_as_a_parameter() -> None:
    with pytest.raises(lw.ModelError, match=r"outputs\.r: 'r' is already the parameter parameters\.r") as caught:
        lw.sweep(MODEL, "kinematics", {"r": [0.05, 0.1]}, {"r": STROKE})
    assert caught.value.problems == [("outputs.r", caught.value.problems[0][1])]


def test_a_measure_named_as_a_built_in_column_is_exit_2_naming_both(linkwork: RunLinkwork, tmp_path: Path) -> None:
    text = MODEL.read_text() + "measures:\n  kinetic_energy: slider.x\n"
    (tmp_path / "m.yaml").write_text(text)
    out = linkwork("run", tmp_path / "m.yaml", "--no-report")
    assert out.code == 2, out.output
    assert "measures.kinetic_energy: 'kinetic_energy' is already the built-in column kinetic_energy" in out.stderr


# --- model files ---------------------------------------------------------------------------------


def test_a_device_is_refused_before_it_is_read(linkwork: RunLinkwork) -> None:
    # /dev/zero was read until the machine's memory was gone (24 GB).
    out = linkwork("check", "/dev/zero")
    assert out.code == 2, out.output
    one_error_line(out.stderr, "/dev/zero: not a regular file")
    with pytest.raises(lw.FileError, match="not a regular file"):
        lw.load("/dev/zero")


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path: Path) -> None:
    fifo = tmp_path / "model.yaml"
    os.mkfifo(fifo)
    # Opening it waited for a writer for ever; 60 s only bounds the test if that came back.
    done = subprocess.run(
        [*linkwork_command(), "run", str(fifo)], cwd=tmp_path, capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 2, done.stderr
    one_error_line(done.stderr, "model.yaml: not a regular file")


def test_a_model_file_larger_than_4_mib_is_refused_unread(linkwork: RunLinkwork, tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    with big.open("w") as f:
        f.write(MODEL.read_text())
        f.write(("# " + "x" * 1022 + "\n") * (4 * 1024 + 1))
    out = linkwork("check", big)
    assert out.code == 2, out.output
    one_error_line(out.stderr, "a model file may be at most 4 MiB")
    with pytest.raises(lw.ModelError, match="at most 4 MiB"):
        lw.Model.from_yaml(big.read_text())


@pytest.mark.parametrize("nesting", ["{a: ", "["], ids=["flow-mappings", "flow-sequences"])
def test_deep_nesting_is_refused_at_the_first_level_too_deep(linkwork: RunLinkwork, tmp_path: Path, nesting: str) -> None:
    # 400 KB: the YAML parser took 87 s over `{a: {a: ...` (quadratic in the depth), then said
    # "recursion limit exceeded" at column 513.
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: deep\nbodies: " + nesting * (400_000 // len(nesting)) + "\n")
    out = linkwork("check", deep)
    assert out.code == 2, out.output
    # The file's mapping is the first level, `bodies: ` is 8 columns: the 17th level opens after 15.
    column = 9 + 15 * len(nesting)
    assert f"YAML syntax error at line 2, column {column}: collections nested more than 16 deep" in out.stderr


def test_a_model_nested_16_deep_still_reads() -> None:
    # The limit is the depth of the parser's events: the file's mapping, then 15 lists.
    text = "bodies: {a: {mass: 1, inertia: 1, position: [0, 0], angle: 0}}\nx: " + "[" * 15 + "]" * 15 + "\n"
    with pytest.raises(lw.ModelError) as caught:
        lw.Model.from_yaml(text)
    assert caught.value.problems[0][0] == "x", caught.value.problems


# --- sweep options -------------------------------------------------------------------------------


@pytest.mark.parametrize("workers", ["-1", "0"])
def test_workers_below_one_is_one_line(linkwork: RunLinkwork, workers: str) -> None:
    # -1 was an OverflowError traceback (exit 1).
    out = linkwork(*SWEEP, "--grid", "r=0.05:0.15:2", "--output", f"s={STROKE}", "--workers", workers)
    assert out.code == 2, out.output
    one_error_line(out.stderr, f"--workers: expected a count of threads of at least 1, got {workers}")


def test_more_workers_than_cores_use_the_cores_with_a_warning(linkwork: RunLinkwork) -> None:
    # 100,000 threads ran for minutes.
    out = linkwork(*SWEEP, "--grid", "r=0.05:0.15:2", "--output", f"s={STROKE}", "--workers", "100000", "--out", "w")
    assert out.code == 0, out.output
    cores = len(os.sched_getaffinity(0))
    assert f"warning: --workers: 100000 threads asked for, this machine has {cores} cores; using {cores}" in out.stderr
    with pytest.raises(ValueError, match="workers: expected a count of threads of at least 1, got 0"):
        lw.sweep(MODEL, "kinematics", {"r": [0.05]}, {"s": STROKE}, workers=0)


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--grid", "r=0.05:0.15:1000000000"], f"r: COUNT: 1000000000 variants; a sweep may have at most {MAX_VARIANTS:,}"),
        (["--grid", "r=0.05:0.15:2000", "--grid", "L=0.3:0.4:1000"], f"--grid: 2000000 variants; a sweep may have at most {MAX_VARIANTS:,}"),
        (["--sample", "1000000000000", "--range", "r=0.05:0.15"], f"--sample: 1000000000000 variants; a sweep may have at most {MAX_VARIANTS:,}"),
    ],
    ids=["grid-count", "grid-product", "sample"],
)
def test_too_many_variants_are_refused_before_any_is_made(linkwork: RunLinkwork, options: list[str], words: str) -> None:
    # The grid grew to 4 GB before a variant ran; the sample asked numpy for 7 TiB.
    out = linkwork(*SWEEP, *options, "--output", f"s={STROKE}")
    assert out.code == 2, out.output
    assert words in out.stderr and "Traceback" not in out.output
    with pytest.raises(ValueError, match=f"sample: 1000000000000 variants; a sweep may have at most {MAX_VARIANTS:,}"):
        lw.sweep(MODEL, "kinematics", sample=10**12, ranges={"r": (0.05, 0.15)}, outputs={"s": STROKE})


def test_a_dask_address_that_is_none_is_one_line(tmp_path: Path) -> None:
    # It was a ValueError traceback, exit 1.
    out = run_process([*SWEEP, "--grid", "r=0.05:0.15:2", "--output", f"s={STROKE}", "--dask", "nonsense"], tmp_path)
    assert out.code == 2, out.output
    one_error_line(out.stderr, "--dask: expected the scheduler's address, such as tcp://host:8786")


# --- memory --------------------------------------------------------------------------------------


@pytest.mark.skipif(sys.platform != "linux", reason="the address space is held with RLIMIT_AS")
def test_results_without_room_are_exit_3_naming_the_remedies_not_an_abort(tmp_path: Path) -> None:
    # 10 million output points of 28 columns are 2.2 GB: with the address space held to 1.5 GB
    # the reservation fails, which aborted the process ("memory allocation of ... bytes failed",
    # SIGABRT, nothing written).
    limit = 1_500_000_000

    def hold() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    done = subprocess.run(
        [*linkwork_command(), "run", str(MODEL), "-a", "kinematics", "--t-end", "100", "--step", "1e-5", "--no-report"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300, check=False, preexec_fn=hold,
    )
    assert done.returncode == 3, (done.returncode, done.stderr)
    assert "out of memory reserving room for 10000001 output points" in done.stderr, done.stderr
    assert "--stream" in done.stderr and "outputs:" in done.stderr
    assert '"status": "failed"' in (tmp_path / "out" / "slider_crank_param" / "summary.json").read_text()
