"""Progress and interruption: Ctrl-C stops a run within 0.2 s and keeps its results, in Python
and on the command line; other Python threads run while the engine does; the progress bar shows
on a terminal and nowhere else.

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

import pytest

import linkwork
from conftest import EXAMPLES, linkwork_command

LONG = EXAMPLES / "iftomm_a02_nfourbar.yaml"
LONG_END = 1000.0

# The bar for Ctrl-C. The engine looks every 50 ms and stops at its next step (about a
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
    try:
        wait_for_rows(process, 2.0)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    return process.returncode, stderr


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
def test_the_progress_bar_shows_on_a_terminal_unless_quiet(tmp_path: Path, quiet: bool) -> None:
    master, slave = pty.openpty()
    # A terminal 100 columns wide, as a window is (a new pseudo-terminal has none, and tqdm
    # draws a bar as wide as the terminal).
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    args = [*linkwork_command(), "run", str(LONG), "-a", "dynamics", "--t-end", str(LONG_END), "--out", str(tmp_path)]
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
    shown = "steps/s" in screen and f"of {LONG_END:.4g} s" in screen
    assert shown != quiet, screen


def test_no_progress_bar_when_stderr_is_not_a_terminal(tmp_path: Path) -> None:
    code, stderr = interrupt_long_run(tmp_path)
    assert code == 130, stderr.decode()
    assert "steps/s" not in stderr.decode()
