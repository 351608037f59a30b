"""Fault injection: `linkwork run` killed (kill -9) at random moments, into a folder holding a
previous complete run, in memory and streamed to CSV and to Parquet. After every kill the folder
holds one run's complete files, the previous run's or the new one's (byte for byte those of two
reference runs), and every stream file left beside it opens.

The normal run kills 12 times (a few seconds a kill: the interpreter starts each time);
``LINKWORK_FAULTS=long`` kills 120 times, the figures docs/reliability.md records.
``LINKWORK_FAULTS_SEED`` repeats a run's moments (each failure names its seed).
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import time
from collections import Counter
from pathlib import Path

from conftest import EXAMPLES, linkwork_command
from linkwork import stream

MODEL = EXAMPLES / "quick_return_a.yaml"
PREVIOUS = ["-a", "kinematics"]
# The new run: reactions and efforts, its report included (the slowest file to write).
NEW = ["-a", "inverse"]
MODES = {"memory": [], "csv": ["--stream", "csv"], "parquet": ["--stream", "parquet"]}
# The kill moments span this many times the reference run's length.
SPAN = 1.3
KILLS = 120 if os.environ.get("LINKWORK_FAULTS") == "long" else 12


def files(out: Path) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def run(out: Path, args: list[str]) -> float:
    """Run into ``out``; the seconds it took, start to end."""
    started = time.monotonic()
    subprocess.run([*linkwork_command(), "run", str(MODEL), *args, "--out", str(out)], check=True, capture_output=True)
    return time.monotonic() - started


def test_kill_9_at_random_moments_leaves_one_runs_files(tmp_path: Path) -> None:
    seed = int(os.environ.get("LINKWORK_FAULTS_SEED", random.randrange(2**32)))
    rng = random.Random(seed)
    previous = tmp_path / "previous"
    run(previous, PREVIOUS)
    reference = {mode: files(previous) for mode in MODES}
    took = {}
    for mode, extra in MODES.items():
        took[mode] = run(tmp_path / mode, [*NEW, *extra])
        reference[mode] = files(tmp_path / mode)
        # The same run twice writes the same bytes: a folder can be told from the other by them.
        run(tmp_path / mode, [*NEW, *extra])
        assert files(tmp_path / mode) == reference[mode], mode
    old = files(previous)
    outcomes: Counter[str] = Counter()
    opened = 0
    for k in range(KILLS):
        mode = list(MODES)[k % len(MODES)]
        out = tmp_path / f"kill{k}"
        shutil.copytree(previous, out)
        process = subprocess.Popen(
            [*linkwork_command(), "run", str(MODEL), *NEW, *MODES[mode], "--out", str(out)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
        # A moment from the start to past the run's usual end: its last tenth writes the files,
        # and a loaded machine is slower than the reference run was.
        time.sleep(rng.uniform(0.0, SPAN * took[mode]))
        process.kill()
        ended = process.wait()
        found = files(out)
        where = f"kill {k} ({mode}, seed {seed}, exit {ended})"
        assert found in (old, reference[mode]), f"{where}: {sorted(found)} is neither run's folder"
        how = "killed" if ended == -signal.SIGKILL else "ended before the kill"
        outcomes[f"{mode}: {'new' if found == reference[mode] else 'previous'}, {how}"] += 1
        for staging in tmp_path.glob(f".{out.name}.linkwork-*"):
            for table in ("results.csv", "results.parquet"):
                # A Parquet stream's first chunk; the folder of chunks may be made but still empty.
                if (staging / table).exists() or list(stream.parts(staging / table).glob("0*.parquet")):
                    time_, columns = stream.read(staging / table)  # raises if it does not open
                    assert len(columns) > 0, where
                    opened += 1
        shutil.rmtree(out, ignore_errors=True)
    print(f"\n{KILLS} kills (seed {seed}): {dict(sorted(outcomes.items()))}; {opened} stream files left by a kill, all opened")
    assert sum(outcomes.values()) == KILLS
    if KILLS >= 100:
        # Long mode: the moments spread over the run and past it, so each mode was killed
        # before its swap and seen after it.
        for m in MODES:
            assert outcomes[f"{m}: previous, killed"], outcomes
            assert any(k.startswith(f"{m}: new") for k in outcomes), outcomes

