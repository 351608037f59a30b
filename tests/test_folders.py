"""Whole output folders: a run's folder holds one run's files, the new run's or the
previous one's, whatever stops it; a stream never truncates the previous results and a killed one
opens; a second run into a folder refuses; a folder that cannot be written fails before the run;
SIGTERM and SIGHUP stop a run as Ctrl-C does; every file error exits 2 with one line."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, RunLinkwork, WriteModel, linkwork_command, pendulum_with_torque
from linkwork import folder, stream

QUICK_RETURN = EXAMPLES / "quick_return_a.yaml"
MODES = EXAMPLES / "hanging_fourbar.yaml"
# The long run of tests/test_interrupt.py: minutes to its end, stopped long before.
LONG = EXAMPLES / "iftomm_a02_nfourbar.yaml"
LONG_RUN = ["run", str(LONG), "-a", "dynamics", "--t-end", "1000"]

# A torque that is NaN past t = 0.503 s: the run fails there (exit 3) after its first rows.
NAN_TORQUE = pendulum_with_torque("sqrt(0.503-t)", 0.01)

# How long a test waits for a child process to reach a state it polls for (the interpreter
# starts, the model compiles, the first chunk is written): far above the second it takes.
PATIENCE = 60.0


def files(out: Path) -> dict[str, bytes]:
    """Every file in ``out`` by its path inside it, with its bytes."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


@contextlib.contextmanager
def start(args: list[str], cwd: Path) -> Iterator[subprocess.Popen[bytes]]:
    """``linkwork ARGS`` running in ``cwd``, its stderr piped; killed (if still running) and
    its pipe closed at the end of the block."""
    process = subprocess.Popen([*linkwork_command(), *args], cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        yield process
    finally:
        process.kill()
        process.communicate()


def wait_until(test: object, process: subprocess.Popen[bytes]) -> None:
    """Poll ``test()`` (a callable) until it holds, while ``process`` runs."""
    deadline = time.monotonic() + PATIENCE
    while not test():  # type: ignore[operator]
        assert process.poll() is None, "the child process ended"
        assert time.monotonic() < deadline, "the child process never got there"
        time.sleep(0.02)


def staged(out: Path) -> list[Path]:
    """The staging folders beside ``out``."""
    return sorted(out.parent.glob(f".{out.name}.linkwork-*"))


def test_a_run_replaces_the_folder_whole(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """A kinematic run into a folder of a modes run leaves no modes.csv of the other; a run with
    --no-report leaves no report of the run before (it stayed beside the new results)."""
    assert linkwork("run", MODES, "-a", "vibration", "-o", "out").code == 0
    assert "modes.csv" in files(tmp_path / "out") and "report.html" in files(tmp_path / "out")
    done = linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", "out", "--no-report")
    assert done.code == 0, done.output
    assert sorted(files(tmp_path / "out")) == ["model.yaml", "results.csv", "summary.json"]
    assert not staged(tmp_path / "out") and not list(tmp_path.glob(".out.linkwork.lock"))


def test_results_write_replaces_the_folder_whole(tmp_path: Path) -> None:
    """The files of the run before go, and the folder's permissions stay."""
    out = tmp_path / "out"
    linkwork.load(QUICK_RETURN).run("kinematics").write(out)
    out.chmod(0o2775)
    linkwork.load(MODES).run("vibration").write(out, report=False)
    assert sorted(files(out)) == ["model.yaml", "modes.csv", "results.csv", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["type"] == "modes"
    assert out.stat().st_mode & 0o7777 == 0o2775


def test_a_folder_holding_other_files_is_refused_not_replaced(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    done = linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", "out")
    assert done.code == 2
    assert "holds notes.txt, which a run does not write" in one_line(done.stderr)
    assert files(out) == {"notes.txt": b"mine"}
    assert not staged(out)


def test_a_table_the_model_names_is_a_file_of_its_folder(tmp_path: Path) -> None:
    """A model's table copied into the folder (data/cam_lift.csv) belongs there: the next run
    replaces it; another file in its folder does not."""
    model = linkwork.load(EXAMPLES / "cam_table.yaml")
    results = model.run(model.analyses[0])
    results.write(tmp_path / "out", report=False)
    results.write(tmp_path / "out", report=False)
    assert "data/cam_lift.csv" in files(tmp_path / "out")
    (tmp_path / "out" / "data" / "other.csv").write_text("x\n")
    with pytest.raises(linkwork.FileError, match="holds data/other.csv"):
        results.write(tmp_path / "out", report=False)


def test_a_stream_never_truncates_the_previous_results_and_a_killed_one_opens(tmp_path: Path) -> None:
    """kill -9 while `--stream csv` writes: the folder keeps the previous run's results.csv
    whole (it was truncated on the first chunk), and the rows streamed until then, in the
    staging folder, read back."""
    out = tmp_path / "out"
    linkwork.load(QUICK_RETURN).run("kinematics").write(out, report=False)
    before = files(out)
    with start([*LONG_RUN, "--out", str(out), "--stream", "csv", "--no-report"], tmp_path) as process:
        wait_until(lambda: any((s / "results.csv").exists() and len(stream.read(s / "results.csv")[0]) for s in staged(out)), process)
        assert files(out) == before
    assert files(out) == before
    [left] = staged(out)
    time_, columns = stream.read(left / "results.csv")
    assert len(time_) > 0 and np.all(np.diff(time_) > 0) and "r1.phi" in columns


def test_a_killed_parquet_stream_opens(tmp_path: Path) -> None:
    """kill -9 while `--stream parquet` writes: its chunks read back (a Parquet file without
    its footer could not be read at all)."""
    out = tmp_path / "out"
    with start([*LONG_RUN, "--out", str(out), "--stream", "parquet", "--no-report"], tmp_path) as process:
        wait_until(lambda: any(len(list(stream.parts(s / "results.parquet").glob("0*1.parquet"))) for s in staged(out)), process)
    assert not out.exists()
    [left] = staged(out)
    time_, columns = stream.read(left / "results.parquet")
    assert len(time_) > 0 and np.all(np.diff(time_) > 0) and "r1.phi" in columns


def test_a_csv_line_cut_short_is_left_out(tmp_path: Path) -> None:
    path = tmp_path / "results.csv"
    path.write_text("time,a.x\n0.0,1.0\n0.1,2.0\n0.2,3")
    time_, columns = stream.read(path)
    assert time_.tolist() == [0.0, 0.1] and columns["a.x"].tolist() == [1.0, 2.0]
    path.write_text("time,a")
    with pytest.raises(ValueError, match="no header line"):
        stream.read(path)


def test_a_second_run_into_a_folder_refuses_naming_the_first(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with start([*LONG_RUN, "--out", str(out), "--no-report"], tmp_path) as first:
        wait_until(lambda: bool(staged(out)), first)
        second = subprocess.run(
            [*linkwork_command(), "run", str(QUICK_RETURN), "-a", "kinematics", "--out", str(out)],
            capture_output=True, text=True, timeout=PATIENCE,
        )
        assert second.returncode == 2
        line = one_line(second.stderr)
        assert f"another run is writing this output folder (pid {first.pid}: " in line
        assert "iftomm_a02_nfourbar.yaml" in line
        first.send_signal(signal.SIGINT)
        first.wait(timeout=PATIENCE)
    assert first.returncode == 130
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"


@pytest.fixture
def read_only(tmp_path: Path) -> Iterator[Path]:
    """A folder that cannot be written: by its mode, or (root writes whatever the mode says) a
    read-only file system mounted on it."""
    path = tmp_path / "ro"
    path.mkdir()
    if os.geteuid() != 0:
        path.chmod(0o555)
        yield path
        path.chmod(0o755)
        return
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(path)], capture_output=True).returncode:
        pytest.skip("root, and no read-only file system can be mounted here")
    yield path
    subprocess.run(["umount", str(path)], check=True)


def test_an_unwritable_folder_fails_before_the_run(linkwork: RunLinkwork, write_model: WriteModel, read_only: Path) -> None:
    """The model's run fails (exit 3) after computing; the folder is found unwritable first
    (it was found after the run: exit 3, "the partial results could not be written")."""
    done = linkwork("run", write_model(NAN_TORQUE), "--out", read_only / "out")
    assert done.code == 2, done.output
    assert "cannot write the output folder" in one_line(done.stderr)
    assert done.stdout == ""


def test_a_read_only_sweep_folder_exits_2_with_one_line(linkwork: RunLinkwork, read_only: Path) -> None:
    done = linkwork(
        "sweep", EXAMPLES / "slider_crank_param.yaml", "--grid", "r=0.05:0.15:3", "--output", "s=max(slider.x)",
        "--out", read_only / "sweep", "-j", "1",
    )
    assert done.code == 2, done.output
    assert "cannot write the output folder" in one_line(done.stderr)


def test_a_report_html_that_is_a_folder_exits_2_with_one_line(linkwork: RunLinkwork, tmp_path: Path) -> None:
    assert linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", "out", "--no-report").code == 0
    (tmp_path / "out" / "report.html").mkdir()
    done = linkwork("report", "out")
    assert done.code == 2
    assert "report.html" in one_line(done.stderr)


def test_an_error_writing_the_files_exits_2_and_keeps_the_previous_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Any OSError while the files are written (here the disk is full when the report is):
    exit 2, one line, the previous folder whole and nothing left beside it."""
    monkeypatch.chdir(tmp_path)
    assert linkwork.cli.main(["run", str(QUICK_RETURN), "-a", "kinematics", "-o", "out"]) == 0
    before = files(tmp_path / "out")

    def full(path: object, run: object) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(linkwork.page, "write", full)
    capsys.readouterr()
    assert linkwork.cli.main(["run", str(QUICK_RETURN), "-a", "dynamics", "-o", "out"]) == 2
    assert "No space left on device" in one_line(capsys.readouterr().err)
    assert files(tmp_path / "out") == before
    assert not staged(tmp_path / "out")


def test_a_full_disk_exits_2_and_keeps_the_previous_folder(linkwork: RunLinkwork, tmp_path: Path) -> None:
    """A file system of 1 MiB holding a run whose report (about 5 MB) does not fit."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(disk)], capture_output=True).returncode:
        pytest.skip("no small file system can be mounted here (needs root)")
    try:
        assert linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", disk / "out", "--no-report").code == 0
        before = files(disk / "out")
        done = linkwork("run", QUICK_RETURN, "-a", "kinematics", "-o", disk / "out")
        assert done.code == 2
        assert "No space left on device" in one_line(done.stderr)
        assert files(disk / "out") == before
        assert not staged(disk / "out")
    finally:
        subprocess.run(["umount", str(disk)], check=True)


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_sigterm_and_sighup_stop_a_run_as_ctrl_c_does(tmp_path: Path, signum: int, code: int) -> None:
    """The partial results written, status interrupted, exit 128 + the signal (SIGTERM wrote
    nothing)."""
    out = tmp_path / "out"
    with start([*LONG_RUN, "--out", str(out), "--no-report"], tmp_path) as process:
        wait_until(lambda: bool(staged(out)), process)
        time.sleep(1.0)  # a second of rows
        process.send_signal(signum)
        _, stderr = process.communicate(timeout=PATIENCE)
    assert process.returncode == code, stderr.decode()
    assert f"interrupted by {signal.Signals(signum).name}: partial results" in stderr.decode()
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert len(stream.read(out / "results.csv")[0]) > 1


def test_without_a_swap_of_two_folders_the_old_one_is_renamed_aside(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Where the system cannot swap two folders in one step, the previous folder is renamed
    aside, and a claim after a crash between the two renames puts it back."""
    monkeypatch.setattr(folder, "_exchange", lambda a, b: False)
    out = tmp_path / "out"
    results = linkwork.load(QUICK_RETURN).run("kinematics")
    results.write(out, report=False)
    results.write(out, report=False)
    before = files(out)
    assert sorted(before) == ["model.yaml", "results.csv", "summary.json"]
    assert not staged(out)
    out.rename(tmp_path / ".out.linkwork-1.old")  # what a kill between the renames leaves
    (tmp_path / ".out.linkwork-1").mkdir()
    folder.claim(out).release()
    assert files(out) == before and not staged(out)
