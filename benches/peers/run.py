"""Linkwork against Exudyn on the same problems: error against a stated reference, CPU time,
steps and Newton iterations of each engine, Linkwork at the loosest tolerance whose error is at
most Exudyn's.

    pip install -e '.[bench]'
    python benches/peers/run.py                  # every problem, N = 10, 100, 1000, 10000
    python benches/peers/run.py --quick          # the small problems, one repeat
    python benches/peers/run.py --problems nfourbar --n 10,100 --timeout 120 --no-write

Each engine's round on each problem is a subprocess (benches/peers/case.py) stopped after
--timeout seconds and reported as a timeout. The two engines take turns, --rounds times
(Exudyn, then Linkwork at the settings its first round chose, and again), each round with its
share of the timed runs, and each engine's CPU time is the least over all its rounds: the
noise of a shared machine comes in spells of seconds, and turns let both engines meet the same
spells. The table, with the machine and the versions, goes
between `<!-- peers:begin -->` and `<!-- peers:end -->` in docs/performance.md (section
"Against Exudyn", added at the end the first time), and the N-four-bar's cost against N to
docs/peers-nfourbar.svg.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

import case  # noqa: E402
import problems  # noqa: E402

# One engine's round (or rounds) on one case: case.py's JSON, or {"status": ...} when it failed.
Result = dict[str, Any]
# A row of the table: the problem, Exudyn's result and Linkwork's.
Row = tuple[problems.Problem, Result, Result]

ROOT = problems.ROOT
DOC = ROOT / "docs" / "performance.md"
PLOT = ROOT / "docs" / "peers-nfourbar.svg"
BEGIN, END = "<!-- peers:begin -->", "<!-- peers:end -->"
CASE = Path(__file__).resolve().parent / "case.py"
FULL_N = (10, 100, 1000, 10000)
QUICK = ("pendulum", "slider-crank", "quick-return", "andrews", "nfourbar")
QUICK_N = (10, 100)
# Each case runs on one thread: NumPy's OpenBLAS threads (started by the error's computation)
# otherwise wait by spinning, which `time.process_time()` counts as the engine's CPU (3% of the
# samples of a loop of Linkwork runs). Exudyn's solver is serial by default (`numberOfThreads`
# 1), Linkwork's is serial.
SERIAL = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
# Exudyn's spectral radius where its default (0.9) fails: the issue that set this benchmark
# found Exudyn "needs rho 0.6 to pass the flat positions" of the N-four-bar, and at N = 10,000
# the default stops at the first (t = 0.7231 s); 0.6 passes it.
FALLBACK_RHO = 0.6


def run_case(args: list[str], timeout: float) -> Result:
    """case.py with `args` in a subprocess: its JSON, or `{"status": ...}` on a timeout or failure."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "case.json"
        try:
            done = subprocess.run(
                [sys.executable, str(CASE), *args, "--out", str(out)],
                capture_output=True,
                text=True,
                timeout=timeout,
                env={**os.environ, **SERIAL},
            )
        except subprocess.TimeoutExpired:
            return {"status": f"timeout (> {timeout:g} s)"}
        if done.returncode != 0:
            lines = done.stderr.strip().splitlines() or [f"exit status {done.returncode}"]
            return {"status": f"failed: {textwrap.shorten(lines[-1], 240)}"}
        return {"status": "ok", **json.loads(out.read_text())}


def merge(first: Result, later: Result) -> Result:
    """One engine's result over its rounds: the first round's, with the least CPU time and the
    runs of all (for Linkwork, of each candidate, the cheaper one then chosen again)."""
    if first["status"] != "ok":
        return first
    if later["status"] != "ok":
        # Kept, and said: the table's row and the findings name a round that did not finish.
        return {**first, "later": [*first.get("later", []), later["status"]]}
    if first["engine"] == "exudyn":
        return {**first, "cpu": min(first["cpu"], later["cpu"]), "runs": first["runs"] + later["runs"]}
    by = {(c["integrator"], c["tol"]): c for c in later["candidates"]}
    candidates = []
    for c in first["candidates"]:
        o = by[(c["integrator"], c["tol"])]
        candidates.append({**c, "cpu": min(c["cpu"], o["cpu"]), "runs": c["runs"] + o["runs"]})
    return {**first, "candidates": candidates, **case.cheapest(candidates)}


def machine() -> dict[str, Any]:
    """CPU model and cores, and the versions that ran."""
    model = "unknown CPU"
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(
        ["git", "-C", str(ROOT), "status", "--porcelain", "--", "crates", "python"], capture_output=True, text=True
    ).stdout.strip()
    return {
        "cpu": model,
        "cores": os.cpu_count(),
        "linkwork": importlib.metadata.version("linkwork"),
        "commit": commit + (" with local changes to crates/ or python/" if dirty else ""),
        "exudyn": importlib.metadata.version("exudyn"),
        "python": platform.python_version(),
        "date": datetime.date.today().isoformat(),
    }


def number(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}" if x >= 1e-3 else f"{x:.{digits - 1}e}"


def table(rows: list[Row]) -> str:
    lines = [
        "| problem | reference | engine | settings | error | CPU s | steps | Newton iterations | Exudyn CPU / Linkwork CPU |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for problem, exudyn, linkwork in rows:
        first = f"{problem.label} | {problem.reference}"
        for engine, r in (("Exudyn", exudyn), ("Linkwork", linkwork)):
            if r["status"] != "ok":
                lines.append(f"| {first} | {engine} | {r.get('settings', '')} | {r['status']} | | | | |")
            else:
                settings = r["settings"]
                if r.get("later"):
                    settings += f" ({len(r['later'])} later round(s) did not finish: see below)"
                if engine == "Linkwork" and not r["met"]:
                    settings += " (no tolerance tried reached Exudyn's error)"
                elif engine == "Linkwork" and exudyn["status"] != "ok":
                    settings += " (no Exudyn error to match)"
                ratio = ""
                if engine == "Linkwork" and exudyn["status"] == "ok":
                    ratio = f"{exudyn['cpu'] / r['cpu']:.1f}"
                error = f"{r['error']:.2e} {problem.unit}"
                lines.append(
                    f"| {first} | {engine} | {settings} | {error} | {number(r['cpu'])} | {r['steps']:,} | {r['newton']:,} | {ratio} |"
                )
            first = " | "
    return "\n".join(lines)


def findings(rows: list[Row]) -> str:
    """What the table says about the 10-times aim, read from it."""
    slower: list[str] = []
    short: list[str] = []
    timeouts: list[str] = []
    ratios: list[tuple[float, str]] = []
    for problem, exudyn, linkwork in rows:
        name = f"{problem.label} ({exudyn.get('settings', 'Exudyn')})"
        for engine, r in (("Exudyn", exudyn), ("Linkwork", linkwork)):
            if r["status"] != "ok":
                timeouts.append(f"{engine} on {name}: {r['status']}")
            for status in r.get("later", []):
                timeouts.append(f"{engine} on {name}, a later round: {status}")
        if exudyn["status"] == "ok" and linkwork["status"] == "ok":
            ratio = exudyn["cpu"] / linkwork["cpu"]
            ratios.append((ratio, name))
            if ratio < 1:
                slower.append(f"{name}: {ratio:.2f}")
            elif ratio < 10:
                short.append(f"{name}: {ratio:.1f}")
    out = []
    if ratios and not short and not slower:
        least, name = min(ratios)
        out.append(
            f"- Linkwork is at least 10 times faster than Exudyn on every problem both engines finished "
            f"({len(ratios)} rows; the least, {least:.1f} times, on {name})."
        )
    if short:
        out.append("- Linkwork is faster, but **not 10 times faster**, on " + "; ".join(short) + ".")
    if slower:
        out.append("- Linkwork is **slower** than Exudyn on " + "; ".join(slower) + ".")
    if timeouts:
        out.append("- Not measured within the time limit, or failed: " + "; ".join(timeouts) + ".")
    return "\n".join(out)


def plot(rows: list[Row]) -> None:
    """CPU seconds per simulated second against N for the N-four-bar, both engines (SVG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.hashsalt"] = "linkwork-peers"
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    missing: list[str] = []
    for engine, marker in (("Exudyn", "s"), ("Linkwork", "o")):
        points: list[tuple[int, float]] = []
        for problem, exudyn, linkwork in rows:
            r = exudyn if engine == "Exudyn" else linkwork
            if problem.key != "nfourbar":
                continue
            if r["status"] == "ok":
                points.append((problem.n, r["cpu"] / problem.t_end))
            else:
                missing.append(f"{engine} N = {problem.n}: {r['status'].split(':')[0]}")
        if points:
            ax.loglog(*zip(*points), marker=marker, label=engine)
    ax.set_xlabel("N (four-bar loops: 2N + 1 bodies)")
    ax.set_ylabel("CPU s per simulated second")
    span = next(row[0].t_end for row in rows if row[0].key == "nfourbar")
    ax.set_title(f"N-four-bar, {span:g} s simulated, Linkwork at Exudyn's error or better", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    if missing:
        fig.text(0.01, 0.01, "\n".join(textwrap.wrap("not shown (see the table): " + "; ".join(missing), 110)), fontsize=7)
    fig.tight_layout(rect=(0, 0.06 if missing else 0, 1, 1))
    fig.savefig(PLOT, format="svg", metadata={"Date": None})
    plt.close(fig)


def section(
    rows: list[Row], info: dict[str, Any], command: str, with_plot: bool, repeats: int, budget: float, rounds: int
) -> str:
    exudyn_steps = sorted({r[1]["step"] for r in rows if r[1]["status"] == "ok"})
    lines = [
        f"Measured {info['date']} with `{command}` on {info['cpu']} ({info['cores']} cores): Linkwork "
        f"{info['linkwork']} at commit `{info['commit']}`, Exudyn {info['exudyn']}, Python {info['python']}.",
        "",
        "The same problems in both engines (`benches/peers/`): each Linkwork model file, and its Exudyn twin built "
        "from it by `benches/peers/exudyn_model.py` (`NodeRigidBody2D` bodies, `RevoluteJoint2D`, `PrismaticJoint2D`, "
        "mass-proportional gravity, torque and force loads, `ConnectorSpringDamper`), started from the same consistent "
        "state. Both write the same output times (every 0.01 s; Andrews every 0.001 s), and the error is measured there.",
        "",
        "- **Exudyn**: `SolveDynamic` with its defaults (generalised-alpha, index 3, spectral radius 0.9, modified "
        "Newton at relative tolerance 1e-8) at the fixed step h of the table"
        + (f" ({', '.join(f'{h:g}' for h in exudyn_steps)} s)" if exudyn_steps else "")
        + f", and where that fails, once more at spectral radius {FALLBACK_RHO:g} (as its settings then say)"
        + "; its dense LU (the default) for the small models, `EigenSparse` for the N-four-bar. Steps: "
        "`it.currentStepIndex - 1`; Newton iterations: `it.newtonStepsCount`.",
        "- **Linkwork**: for `bdf` and `abam`, the loosest `rtol = atol` of 1e-4, 1e-5, ..., 1e-12 whose error is at "
        "most Exudyn's; both are timed, and the cheaper is shown. Steps and Newton iterations: "
        "`results.summary.statistics`.",
        f"- **CPU s**: `time.process_time()` (one thread), the least of the timed runs (noise only adds time). The "
        f"engines take turns on each case, {rounds} rounds of Exudyn then Linkwork, each round at least "
        f"{-(-repeats // rounds)} run(s) and {budget / rounds:g} s of CPU (for Linkwork, each candidate setting), so "
        "that both meet the same spells of a shared machine's noise. A 1 ms case gets hundreds of runs a round where "
        "a 100 ms one gets ten, and Linkwork's time is the least over its candidates too; noise only adds time, so "
        "more runs find the quiet ones sooner but not a time below the run's own; Linkwork's `Model.run()` (assembly, "
        "integration, every output column), Exudyn's `Assemble()` + `SolveDynamic()` (with the sensors of the compared "
        "outputs); building the model is not timed in either.",
        "- **References** (the error is the largest over the output times unless said otherwise):",
        "  - pendulum, A01: the exact solution in Jacobi's `sn`; the mass's x, y (m).",
        "  - slider-crank, quick-return A (free and under its constant crank torque): the one-degree-of-freedom "
        "energy equation `I(theta) theta'^2 / 2 = E0 + T (theta - theta0)` by quadrature, `I(theta)` and the body "
        "positions from the model's kinematic analysis (Linkwork's position solver at 1e-12, no integrator); every "
        "body's x, y (m) and phi (rad).",
        "  - N-four-bar and A02: every rocker at the angle of the one-degree-of-freedom equation "
        "`((N + 1)/3 + N) psi'' = -g ((N + 1)/2 + N) cos psi`, RK4 at 1e-4 s (error about 1e-13); point B0's x, y (m).",
        "  - Andrews: its end state at 0.03 s from the test set's own equations by SciPy's DOP853 "
        "(`benches/andrews_reference.py`, good to about 11.5 digits); the largest relative error of the seven "
        "angles at 0.03 s.",
        "",
        table(rows),
        "",
        findings(rows),
    ]
    if with_plot:
        lines += ["", "![CPU s per simulated second against N, N-four-bar](peers-nfourbar.svg)"]
    return "\n".join(lines)


def write(text: str) -> None:
    doc = DOC.read_text()
    if BEGIN not in doc:
        doc = doc.rstrip("\n") + f"\n\n## Against Exudyn\n\n{BEGIN}\n{END}\n"
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(f"{head}{BEGIN}\n{text}\n{END}{tail}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)} (N = 10, 100), one repeat")
    parser.add_argument("--problems", help=f"comma-separated, of {', '.join(problems.PROBLEMS)}")
    parser.add_argument("--n", help="the N-four-bar's N, comma-separated (default 10,100,1000,10000)")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds for each engine's round on each problem")
    parser.add_argument("--rounds", type=int, help="turns of the two engines on each case (default 3, --quick 1)")
    parser.add_argument("--repeats", type=int, help="timed runs per case at least (default 3, --quick 1)")
    parser.add_argument(
        "--budget", type=float, help="CPU seconds of timed runs per engine and case at least (default 3, --quick 0)"
    )
    parser.add_argument("--no-write", action="store_true", help="print the table only")
    args = parser.parse_args(argv)
    keys = args.problems.split(",") if args.problems else list(QUICK if args.quick else problems.PROBLEMS)
    for key in keys:
        if key not in problems.PROBLEMS:
            parser.error(f"unknown problem {key!r}")
    ns = [int(n) for n in args.n.split(",")] if args.n else list(QUICK_N if args.quick else FULL_N)
    repeats = args.repeats or (1 if args.quick else 3)
    budget = args.budget if args.budget is not None else (0.0 if args.quick else 3.0)
    rounds = args.rounds or (1 if args.quick else 3)
    if rounds < 1:
        parser.error("--rounds must be at least 1")
    command = " ".join(["python benches/peers/run.py", *(argv if argv is not None else sys.argv[1:])])

    rows: list[Row] = []
    for key in keys:
        for n in ns if key == "nfourbar" else [0]:
            problem = problems.problem(key, n)
            share = ["--repeats", str(-(-repeats // rounds)), "--budget", repr(budget / rounds)]
            base = [problem.key, "--n", str(n), *share]
            for step in problem.exudyn_steps:
                # An engine that failed or timed out in the first round is not run again.
                exudyn: Result | None = None
                linkwork: Result | None = None
                rho: list[str] = []
                for k in range(rounds):
                    if exudyn is None or exudyn["status"] == "ok":
                        print(f"{problem.label}: Exudyn h = {step:g}, round {k + 1} ...", flush=True)
                        e = run_case(["exudyn", *base, "--step", repr(step), *rho], args.timeout)
                        if exudyn is None and "SolveDynamic failed" in e["status"] and not rho:
                            # Once, with the spectral radius that passes the flat positions.
                            failure, rho = e["status"], ["--rho", repr(FALLBACK_RHO)]
                            print(f"  {failure}; again with spectral radius {FALLBACK_RHO:g} ...", flush=True)
                            e = run_case(["exudyn", *base, "--step", repr(step), *rho], args.timeout)
                            if e["status"] == "ok":
                                e["settings"] += f" (0.9 {failure})"
                            else:
                                e["settings"] = f"generalised-alpha, h = {step:g}, spectral radius {FALLBACK_RHO:g}"
                                e["status"] = f"{failure}; at spectral radius {FALLBACK_RHO:g}: {e['status']}"
                        exudyn = e if exudyn is None else merge(exudyn, e)
                        print(f"  {e['status']} {e.get('error', '')} {e.get('cpu', '')}", flush=True)
                    if linkwork is None:
                        chosen = ["--target", repr(exudyn["error"])] if exudyn["status"] == "ok" else []
                    elif linkwork["status"] == "ok":
                        chosen = ["--candidates", ",".join(f"{c['integrator']}:{c['tol']!r}" for c in linkwork["candidates"])]
                    else:
                        continue
                    print(f"{problem.label}: Linkwork, round {k + 1} ...", flush=True)
                    w = run_case(["linkwork", *base, *chosen], args.timeout)
                    linkwork = w if linkwork is None else merge(linkwork, w)
                    print(f"  {w['status']} {w.get('settings', '')} {w.get('error', '')} {w.get('cpu', '')}", flush=True)
                assert exudyn is not None and linkwork is not None, "each engine ran in the first round"
                exudyn.setdefault("settings", f"generalised-alpha, h = {step:g}")
                exudyn.setdefault("step", step)
                rows.append((problem, exudyn, linkwork))

    with_plot = "nfourbar" in keys
    text = section(rows, machine(), command, with_plot, repeats, budget, rounds)
    print(text)
    if not args.no_write:
        if with_plot:
            plot(rows)
        write(text)
        print(f"written to {DOC}" + (f" and {PLOT}" if with_plot else ""))


if __name__ == "__main__":
    main()
