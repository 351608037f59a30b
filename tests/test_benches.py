"""The scripts of benches/, each run once in a child process at a small setting (a smoke run, not
a measurement: no time is compared with a number), and its output checked against what the
script claims to measure: the rows it prints, and a figure of each that can be known without
the engine (a count of coordinates, of steps, of crossings, an error against an exact solution).
"""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from types import ModuleType

import numpy as np
import pytest

from conftest import ROOT

BENCHES = ROOT / "benches"


def run_script(*args: str) -> str:
    """`python benches/ARGS...` from the repository root (where the scripts' relative paths
    start); its standard output, after checking that it exited with status 0."""
    done = subprocess.run(
        [sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=300, check=False
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def table_rows(output: str) -> list[list[str]]:
    """The cells of each row of the Markdown tables in `output`: lines that start with `|`, but
    a header (the line above a `| ---` rule) and the rule."""
    lines = output.splitlines()
    rows = []
    for k, line in enumerate(lines):
        header = k + 1 < len(lines) and lines[k + 1].startswith("| ---")
        if line.startswith("|") and not line.startswith("| ---") and not header:
            rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
    return rows


def positive(text: str) -> float:
    """`text` as a number (commas and a trailing unit dropped), checked finite and positive."""
    value = float(text.replace(",", "").split()[0])
    assert math.isfinite(value) and value > 0, text
    return value


def load_peers_module(name: str) -> ModuleType:
    """benches/peers/NAME.py, imported from its file (the folder is scripts, not a package)."""
    spec = importlib.util.spec_from_file_location(name, BENCHES / "peers" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_equilibrium_timing_prints_a_row_per_case() -> None:
    # Rows only: the header is in docs/equilibrium.md, which holds the table.
    rows = table_rows(run_script("benches/equilibrium_timing.py"))
    assert [(r[0], r[1]) for r in rows] == [
        ("quick_return_a.yaml", "kinematics"),
        ("quick_return_a.yaml", "inverse"),
        ("quick_return_b.yaml", "inverse"),
        ("ellipse_trammel.yaml", "equilibrium"),
    ]
    for row in rows:
        positive(row[2])
        positive(row[3])
    # A static equilibrium is one state: one row of results.
    assert rows[3][2] == "1"


def test_scale_at_n_10_passes_the_flat_positions_the_reference_passes() -> None:
    n = 10
    [row] = table_rows(run_script("benches/scale.py", str(n)))
    # 2N + 1 bodies (examples/nfourbar.py: N + 1 rockers, N couplers), three coordinates each.
    assert row[0] == "10" and row[1] == f"{3 * (2 * n + 1)}"
    for cell in (row[2], row[4], row[5], row[6], row[7]):
        positive(cell)
    assert row[3] == "10 s"
    # B0 = (cos psi, sin psi): the chain lies flat where sin(psi) changes sign between two
    # output times (every 0.01 s, the model's step), with psi from the one-degree-of-freedom
    # equation by RK4 (benches/peers/references.py, about 1e-13 rad): the same count, unless a
    # crossing fell within an output step of a sample, which it does not here (it would change
    # the count by one, not pass silently).
    references = load_peers_module("references")
    times = np.linspace(0.0, 10.0, 1001)
    b0y = np.sin(references.nfourbar_psi(n, times))
    crossings = int(((b0y[:-1] * b0y[1:]) < 0).sum())
    assert crossings > 0
    assert row[8] == f"{crossings} (ok)"


def test_sweep_throughput_runs_every_variant_of_every_case() -> None:
    variants = 20
    lines = run_script("benches/sweep_throughput.py", "--variants", str(variants), "--repeats", "1").splitlines()
    cases = [
        ("quick_return_a.yaml", "kinematics"),
        ("quick_return_a.yaml", "dynamics"),
        ("slider_crank_param.yaml", "kinematics"),
        ("slider_crank_param.yaml", "inverse"),
    ]
    assert len(lines) == 2 * len(cases)
    for line, (file, analysis, workers) in zip(lines, [(*c, w) for c in cases for w in (1, 2)], strict=True):
        head, figures = line.split(":", 1)
        assert head.split() == [file, analysis, f"workers={workers}"]
        rate, seconds = positive(figures.split("runs/s")[0]), float(figures.split("(")[1].split()[0])
        # The rate is the variants over the sweep's time, which is printed to 0.01 s (and the
        # rate to 1 run/s): within that rounding.
        assert seconds >= 0
        assert variants / (seconds + 0.005) - 0.5 <= rate
        if seconds > 0.005:
            assert rate <= variants / (seconds - 0.005) + 0.5
        # Every variant of the grid (crank lengths the mechanism assembles at) finished.
        assert figures.rstrip().endswith(f"{variants} ok)")


def test_peers_scan_error_falls_with_the_tolerance() -> None:
    output = run_script(
        "benches/peers/scan.py", "pendulum", "--integrators", "bdf", "--tolerances", "1e-4,1e-7", "--repeats", "1"
    )
    errors = [float(line.split("error")[1].split()[0]) for line in output.splitlines()[1:]]
    assert len(errors) == 2 and all(math.isfinite(e) and e > 0 for e in errors)
    # Against the exact solution (Jacobi's sn): a thousand times tighter a tolerance, a smaller
    # error.
    assert errors[1] < errors[0]


def test_peers_run_on_the_pendulum_matches_exudyn_and_writes_nothing() -> None:
    doc = (ROOT / "docs" / "performance.md").read_bytes()
    output = run_script(
        "benches/peers/run.py", "--problems", "pendulum", "--rounds", "1", "--repeats", "1", "--budget", "0",
        "--timeout", "120", "--no-write",
    )
    assert (ROOT / "docs" / "performance.md").read_bytes() == doc
    exudyn, linkwork = table_rows(output)
    assert exudyn[0].startswith("pendulum") and exudyn[2] == "Exudyn" and linkwork[2] == "Linkwork"
    # Columns: settings, error, CPU s, steps, Newton iterations, ratio.
    assert exudyn[3] == "generalised-alpha, h = 0.001"
    # 10 s at the fixed step 1e-3 s.
    assert exudyn[6] == "10,000"
    exudyn_error, linkwork_error = positive(exudyn[4]), positive(linkwork[4])
    # Against the exact solution of a 1 m pendulum: a second-order method at 1e-3 s is far
    # inside 1 cm; a wrong reference or twin would be off by the order of the length.
    assert exudyn_error < 1e-2
    # Linkwork at the loosest tolerance that reached Exudyn's error (and said so otherwise).
    assert "no tolerance tried" not in linkwork[3]
    assert linkwork_error <= exudyn_error
    ratio = positive(linkwork[8])
    # The ratio of the CPU times, from the unrounded ones (printed to 3 digits; the ratio to 0.1).
    assert ratio == pytest.approx(positive(exudyn[5]) / positive(linkwork[5]), rel=0.01, abs=0.05)

