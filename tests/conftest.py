"""Shared helpers: where the examples are, and the command line run two ways (a child process
running the installed package, and `linkwork.cli.main` in this process)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import pytest

from linkwork import cli

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


def pendulum_with_torque(torque: str, step: float, name: str = "kick") -> str:
    """A 1 m bar pinned at its end, under gravity and the torque `torque` (an expression of t),
    run 1 s by `dynamics` with output step `step`: the model of the non-finite-value tests (the
    file the Rust tests load too)."""
    text = patch(
        (ROOT / "crates" / "linkwork" / "tests" / "models" / "pendulum_torque.yaml").read_text(),
        'kick: {type: torque, body: bar, torque: "0"}',
        f'{name}: {{type: torque, body: bar, torque: "{torque}"}}',
    )
    return patch(text, "step: 0.01}", f"step: {step}}}")


def patch(text: str, old: str, new: str) -> str:
    """`text` with `old` replaced by `new`; fails unless `old` occurs exactly once, so that a test
    whose file changed under it fails instead of running the file unchanged."""
    count = text.count(old)
    assert count == 1, f"{old!r} occurs {count} times in the text to patch, not once"
    return text.replace(old, new)


@dataclass
class Outcome:
    """What a run of the command line did."""

    code: int
    stdout: str
    stderr: str

    @property
    def output(self) -> str:
        return self.stdout + self.stderr


class RunLinkwork(Protocol):
    """The `linkwork` fixture: `linkwork ARGS`, run the way the test's parameter says."""

    def __call__(self, *args: str | Path) -> Outcome: ...


class WriteModel(Protocol):
    """The `write_model` fixture: write a model file and return its path."""

    def __call__(self, text: str, name: str = "model.yaml") -> Path: ...


def linkwork_command() -> list[str]:
    """The installed `linkwork` console script, else `python -m linkwork`."""
    script = Path(sys.executable).with_name("linkwork")
    if script.exists():
        return [str(script)]
    found = shutil.which("linkwork")
    return [found] if found else [sys.executable, "-m", "linkwork"]


def run_process(args: list[str], cwd: Path) -> Outcome:
    """`linkwork ARGS` in a child process, in `cwd`."""
    done = subprocess.run(
        [*linkwork_command(), *args], cwd=cwd, capture_output=True, text=True, timeout=300, check=False
    )
    return Outcome(done.returncode, done.stdout, done.stderr)


@pytest.fixture(params=["process", "main"])
def linkwork(
    request: pytest.FixtureRequest,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> RunLinkwork:
    """Run `linkwork ARGS` with `tmp_path` as the working folder, as a child process or through
    `linkwork.cli.main([...])`; the test runs once each way."""

    def invoke(*args: str | Path) -> Outcome:
        argv = [str(a) for a in args]
        if request.param == "process":
            return run_process(argv, tmp_path)
        monkeypatch.chdir(tmp_path)
        capsys.readouterr()
        code = cli.main(argv)
        captured = capsys.readouterr()
        return Outcome(code, captured.out, captured.err)

    return invoke


@pytest.fixture
def write_model(tmp_path: Path) -> WriteModel:
    """Write a model file (dedented) into `tmp_path` and return its path."""

    def write(text: str, name: str = "model.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write
