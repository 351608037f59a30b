"""Progress and interruption: Ctrl-C stops a run or a sweep within 0.2 s and keeps its results,
in Python and on the command line; other Python threads run while the engine does; the progress
bar shows on a terminal and nowhere else.

The long run is the IFToMM N-four-bar (123 bodies) run to 1000 s, which takes minutes: every test
stops it long before its end.
"""

from __future__ import annotations

import _thread
import fcntl
import json
import os
import pty
import select
import signal
import struct
import subprocess
import termios
import threading
import time
from pathlib import Path

import pandas as pd
import pytest

import linkwork
from conftest import EXAMPLES, linkwork_command

LONG = EXAMPLES / "iftomm_a02_nfourbar.yaml"
LONG_END = 1000.0

# A sweep of many short runs: the parametrised slider-crank's kinematics (under a millisecond a
# variant) for 20,000 crank radii takes about 10 s on one thread; every test stops it long before.
SWEEP_MODEL = EXAMPLES / "slider_crank_param.yaml"
SWEEP_VARIANTS = 20_000
SWEEP_GRID = f"r=0.05:0.15:{SWEEP_VARIANTS}"
SWEEP_OUTPUT = "stroke=max(slider.x) - min(slider.x)"

# A shell without job control starts a background command with SIGINT ignored (POSIX), Python
# then leaves it ignored, and so does every command it starts: Ctrl-C would reach nothing (a CI run
# launched with `nohup ... &` failed every test here, each run going on to its end). These tests
# send Ctrl-C to see what the engine does with it, so they give the test process Python's own
# handler (its children, started by exec, then get the default disposition and install theirs).
signal.signal(signal.SIGINT, signal.default_int_handler)

# How soon a run must stop after Ctrl-C, s. The engine looks every 50 ms and stops at its next step (about a
# millisecond here), so this leaves three quarters of it to a loaded machine.
STOP_WITHIN = 0.2


def test_ctrl_c_in_python_stops_the_run_within_0_2_s_with_its_results() -> None:
    model = linkwork.load(LONG)
    sent: list[float] = []
    ticks = 0
    running = threading.Event()

    def other_thread() -> None:
        nonlocal ticks
        while not running.is_set():
            ticks += 1
            time.sleep(0.001)

    def ctrl_c() -> None:
        sent.append(time.monotonic())
        _thread.interrupt_main()  # what a SIGINT does to the main thread

    counter = threading.Thread(target=other_thread)
    timer = threading.Timer(0.5, ctrl_c)
    counter.start()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as caught:
            model.run("dynamics", t_end=LONG_END)
        stopped = time.monotonic()
    finally:
        timer.cancel()
        running.set()
        counter.join()
    assert sent and stopped - sent[0] < STOP_WITHIN, f"stopped {stopped - sent[0]:.3f} s after Ctrl-C"
    # The other thread kept going while the engine ran (the GIL was released): it ticks about
    # every millisecond, so half a second gives hundreds.
    assert ticks > 100
    partial = caught.value.results  # type: ignore[attr-defined]
    assert isinstance(partial, linkwork.Results)
    assert 1 < len(partial) and partial.time[-1] < LONG_END
    assert partial.summary["status"] == "interrupted"
    assert partial.summary["error_time"] >= partial.time[-1]


def test_progress_is_reported_and_an_exception_from_it_stops_the_run() -> None:
    model = linkwork.load(LONG)
    seen: list[tuple[float, float, float, int]] = []

    class Enough(Exception):
        pass

    def progress(t: float, t_start: float, t_end: float, steps: int) -> None:
        seen.append((t, t_start, t_end, steps))
        if len(seen) == 5:
            raise Enough

    with pytest.raises(Enough):
        model.run("dynamics", t_end=LONG_END, progress=progress)
    assert len(seen) == 5
    assert all((t0, t1) == (0.0, LONG_END) for _, t0, t1, _ in seen)
    times = [t for t, *_ in seen]
    steps = [n for *_, n in seen]
    assert times == sorted(times) and times[-1] > 0.0
    assert steps == sorted(steps) and steps[-1] > 0


def test_a_short_run_with_progress_reports_nothing_after_its_end() -> None:
    seen: list[float] = []
    results = linkwork.load(EXAMPLES / "quick_return_a.yaml").run(progress=lambda t, *_: seen.append(t))
    assert results.ok
    assert all(0.0 <= t <= results.time[-1] for t in seen)


def start_long_run(out: Path, stderr: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [*linkwork_command(), "run", str(LONG), "--analysis", "dynamics", "--t-end", str(LONG_END), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=stderr,
    )


def wait_for_rows(process: subprocess.Popen[bytes], seconds: float) -> None:
    """Let the run get going (the interpreter starts, the model compiles, steps are taken)."""
    time.sleep(seconds)
    assert process.poll() is None, "the long run ended by itself"


def interrupt_long_run(out: Path) -> tuple[int, bytes]:
    """Start the long run writing into `out`, send it Ctrl-C after 2 s; its exit status and
    stderr."""
    process = start_long_run(out, subprocess.PIPE)
    stderr = ctrl_c(process)
    return process.returncode, stderr


def ctrl_c(process: subprocess.Popen[bytes]) -> bytes:
    """Send `process` Ctrl-C once it has run 2 s; its stderr, once it has ended (killed if it
    has not within 120 s)."""
    try:
        wait_for_rows(process, 2.0)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    return stderr


def test_ctrl_c_on_the_command_line_writes_the_partial_results_and_exits_130(tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, stderr = interrupt_long_run(out)
    assert code == 130, stderr.decode()
    assert "interrupted" in stderr.decode()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    rows = (out / "results.csv").read_text().splitlines()
    assert len(rows) > 2
    assert float(rows[-1].split(",")[0]) < LONG_END
    assert (out / "report.html").exists() and (out / "model.yaml").exists()


def read_terminal(fd: int, process: subprocess.Popen[bytes]) -> str:
    """Everything written to the terminal `fd` until `process` ends."""
    chunks: list[bytes] = []
    while True:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            try:
                data = os.read(fd, 65536)
            except OSError:  # the other end closed
                break
            if not data:
                break
            chunks.append(data)
        elif process.poll() is not None:
            break
    return b"".join(chunks).decode(errors="replace")


@pytest.mark.parametrize("quiet", [False, True])
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_the_progress_bar_shows_on_a_terminal_unless_quiet(tmp_path: Path, quiet: bool, command: str) -> None:
    master, slave = pty.openpty()
    # A terminal 100 columns wide, as a window is (a new pseudo-terminal has none, and tqdm
    # draws a bar as wide as the terminal).
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    if command == "run":
        args = [*linkwork_command(), "run", str(LONG), "-a", "dynamics", "--t-end", str(LONG_END)]
        bar = ["steps/s", f"of {LONG_END:.4g} s"]
    else:
        args = [*linkwork_command(), "sweep", str(SWEEP_MODEL), "--grid", SWEEP_GRID, "--output", SWEEP_OUTPUT, "-j", "1"]
        bar = ["variant/s", f"/{SWEEP_VARIANTS}"]
    args += ["--out", str(tmp_path)]
    process = subprocess.Popen([*args, *(["--quiet"] if quiet else [])], stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    try:
        wait_for_rows(process, 2.5)
        process.send_signal(signal.SIGINT)
        screen = read_terminal(master, process)
        process.wait(timeout=120)
    finally:
        process.kill()
        os.close(master)
    assert process.returncode == 130
    shown = all(text in screen for text in bar)
    assert shown != quiet, screen


def test_no_progress_bar_when_stderr_is_not_a_terminal(tmp_path: Path) -> None:
    code, stderr = interrupt_long_run(tmp_path)
    assert code == 130, stderr.decode()
    assert "steps/s" not in stderr.decode()



def long_sweep(**options: object) -> pd.DataFrame:
    radii = [0.05 + 0.1 * k / (SWEEP_VARIANTS - 1) for k in range(SWEEP_VARIANTS)]
    return linkwork.sweep(
        SWEEP_MODEL, "kinematics", grid={"r": radii}, outputs=dict([SWEEP_OUTPUT.split("=", 1)]), workers=1,
        **options,  # type: ignore[arg-type]
    )


def interrupted_rows(table: pd.DataFrame) -> pd.Series[bool]:
    return table["status"].str.startswith("KeyboardInterrupt")


def test_ctrl_c_stops_a_sweep_within_0_2_s_with_every_row() -> None:
    sent: list[float] = []

    def ctrl_c() -> None:
        sent.append(time.monotonic())
        _thread.interrupt_main()

    timer = threading.Timer(0.5, ctrl_c)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as caught:
            long_sweep()
        stopped = time.monotonic()
    finally:
        timer.cancel()
    assert sent and stopped - sent[0] < STOP_WITHIN, f"stopped {stopped - sent[0]:.3f} s after Ctrl-C"
    table = caught.value.table  # type: ignore[attr-defined]
    assert len(table) == SWEEP_VARIANTS
    done = table[~interrupted_rows(table)]
    # The variants finished before Ctrl-C are whole rows; the others have no outputs.
    assert 0 < len(done) < SWEEP_VARIANTS and (done["status"] == "ok").all()
    assert table["stroke"][interrupted_rows(table)].isna().all()


def test_a_sweep_reports_the_variants_finished_and_an_exception_from_progress_stops_it() -> None:
    seen: list[tuple[int, int]] = []

    class Enough(Exception):
        pass

    def progress(finished: int, total: int) -> None:
        seen.append((finished, total))
        if len(seen) == 3:
            raise Enough

    with pytest.raises(Enough) as caught:
        long_sweep(progress=progress)
    assert len(seen) == 3 and all(total == SWEEP_VARIANTS for _, total in seen)
    finished = [f for f, _ in seen]
    assert finished == sorted(finished) and 0 < finished[-1] < SWEEP_VARIANTS
    table = caught.value.table  # type: ignore[attr-defined]
    assert (~interrupted_rows(table)).sum() >= finished[-1]


def test_ctrl_c_on_a_cli_sweep_writes_the_rows_and_exits_130(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["sweep", str(SWEEP_MODEL), "-a", "kinematics", "--grid", SWEEP_GRID, "--output", SWEEP_OUTPUT, "-j", "1"]
    process = subprocess.Popen([*linkwork_command(), *args, "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    stderr = ctrl_c(process)
    assert process.returncode == 130, stderr.decode()
    assert "interrupted:" in stderr.decode() and "variants finished" in stderr.decode()
    table = pd.read_parquet(out / "sweep.parquet")
    assert len(table) == SWEEP_VARIANTS
    assert 0 < (~interrupted_rows(table)).sum() < SWEEP_VARIANTS
