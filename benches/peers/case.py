"""One engine on one problem of benches/peers, run by run.py in a subprocess of its own (so that a
time limit can stop it) and written as JSON to --out.

    python benches/peers/case.py exudyn PROBLEM [--n N] --step H [--rho R] [--repeats 3] [--budget 2] --out FILE
    python benches/peers/case.py linkwork PROBLEM [--n N] [--target ERROR] [--repeats 3] [--budget 2] --out FILE
    python benches/peers/case.py linkwork PROBLEM [--n N] --candidates bdf:1e-4,abam:1e-5 [...] --out FILE

exudyn: the problem's Exudyn twin (exudyn_model.py) with the generalised-alpha solver at the
fixed step H (and spectral radius R, Exudyn's 0.9 by default); CPU time of `Assemble()` +
`SolveDynamic()`, model building excluded.

linkwork: the loosest `rtol = atol` of 1e-4, 1e-5, ..., 1e-12 whose error is at most --target
(Exudyn's), for `bdf` and for `abam`; each is timed, and the cheaper is reported (a single run of
the search is too noisy to choose by). With --candidates, those settings are timed and no search
is made (run.py's later rounds).
Without a target, `bdf` at 1e-8. CPU time of `Model.run()` (assembly, integration and every
output column), the file's parsing excluded.

CPU time is `time.process_time()` (all threads), the least of the timed runs, for both engines:
the noise of a shared machine only adds time, so the least is the estimate that repeats (as
`timeit` advises). The runs go on until they have taken --budget seconds of CPU, and at least
--repeats of them (as `timeit`'s autorange, by time): on this 2-core machine the noise comes in
spells of seconds, in which a 10 ms case ran 1.5 times slower in every one of 30 runs, so a fixed
count of short runs can fall entirely within one. Both engines get the same budget.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import problems  # noqa: E402

if TYPE_CHECKING:
    import linkwork

T = TypeVar("T")

TOLERANCES = [10.0**-k for k in range(4, 13)]
INTEGRATORS = ("bdf", "abam")
UNMATCHED = ("bdf", 1e-8)


def timed(run: Callable[[], tuple[float, T]], repeats: int, budget: float) -> tuple[list[float], T]:
    """CPU seconds of each call of `run` (which returns its own): at least `repeats` calls, and
    more until they add up to `budget` seconds. The last call's other results come back too."""
    cpus: list[float] = []
    while True:
        cpu, last = run()
        cpus.append(cpu)
        if len(cpus) >= repeats and sum(cpus) >= budget:
            return cpus, last


def exudyn_case(problem: problems.Problem, step: float, rho: float | None, repeats: int, budget: float) -> dict[str, Any]:
    import linkwork
    from exudyn_model import ExudynModel

    model = linkwork.from_yaml(problem.text)
    twin = ExudynModel(
        model, problem.analysis, problem.bodies, problem.output_step, problem.t_end, step, problem.sparse, problem.assembled
    )
    settings = f"generalised-alpha, h = {step:g}"
    if rho is not None:
        twin.settings.timeIntegration.generalizedAlpha.spectralRadius = rho
        settings += f", spectral radius {rho:g}"

    def run() -> tuple[float, Any]:
        start = time.process_time()
        it = twin.solve()
        return time.process_time() - start, it

    cpus, it = timed(run, repeats, budget)
    columns = twin.columns()
    if not np.isclose(columns["time"][-1], problem.t_end):
        raise RuntimeError(f"Exudyn stopped at t = {columns['time'][-1]}")
    return {
        "engine": "exudyn",
        "settings": settings,
        "step": step,
        "error": problems.error(problem, model, columns),
        "cpu": min(cpus),
        "runs": len(cpus),
        "steps": it.currentStepIndex - 1,
        "newton": it.newtonStepsCount,
    }


def linkwork_run(
    problem: problems.Problem, model: linkwork.Model, integrator: str, tol: float
) -> tuple[float, float, dict[str, Any]]:
    """One run: its error, CPU seconds and summary statistics (a failed run raises)."""
    cpu, r = linkwork_timed(problem, model, integrator, tol)
    return linkwork_error(problem, model, r), cpu, statistics(r)


def statistics(r: linkwork.Results) -> dict[str, Any]:
    """The integrator's statistics of a dynamic run (its summary holds them; a kinematic one's
    does not, and no problem here is kinematic)."""
    stats = r.summary.statistics
    if stats is None:
        raise RuntimeError("the run has no integrator statistics: its analysis is not dynamic")
    return dict(stats)


def linkwork_timed(
    problem: problems.Problem, model: linkwork.Model, integrator: str, tol: float
) -> tuple[float, linkwork.Results]:
    """One run: its CPU seconds and results."""
    start = time.process_time()
    r = model.run(problem.analysis, integrator=integrator, rtol=tol, atol=tol, t_end=problem.t_end, step=problem.output_step)
    return time.process_time() - start, r


def linkwork_error(problem: problems.Problem, model: linkwork.Model, r: linkwork.Results) -> float:
    """A run's error against the problem's reference (the references cost more than a run)."""
    columns = {"time": np.asarray(r.time)}
    for body in problem.bodies:
        for c in ("x", "y", "phi"):
            columns[f"{body}.{c}"] = np.asarray(r[f"{body}.{c}"])
    return problems.error(problem, model, columns)


def linkwork_case(
    problem: problems.Problem,
    target: float | None,
    repeats: int,
    budget: float,
    candidates: list[tuple[str, float]] | None = None,
) -> dict[str, Any]:
    import linkwork

    model = linkwork.from_yaml(problem.text)
    tried: list[tuple[str, float, float | str]] = []
    met = True
    if candidates:
        return best_candidate(problem, model, candidates, repeats, budget, met, tried)
    candidates = []
    if target is None:
        candidates.append(UNMATCHED)
    else:
        for integrator in INTEGRATORS:
            for tol in TOLERANCES:
                try:
                    err, _, _ = linkwork_run(problem, model, integrator, tol)
                except linkwork.LinkworkError as failure:
                    tried.append((integrator, tol, f"{type(failure).__name__}: {failure}"))
                    continue
                tried.append((integrator, tol, err))
                if err <= target:
                    candidates.append((integrator, tol))
                    break
    met = bool(candidates)
    if not met:
        # No tolerance reached the target: the smallest error found is shown, and said so.
        finished = [(i, t, e) for i, t, e in tried if not isinstance(e, str)]
        if not finished:
            raise RuntimeError(f"no Linkwork run finished: {tried}")
        best = min(finished, key=lambda t: t[2])
        candidates.append((best[0], best[1]))
    return best_candidate(problem, model, candidates, repeats, budget, met, tried)


def best_candidate(
    problem: problems.Problem,
    model: linkwork.Model,
    candidates: list[tuple[str, float]],
    repeats: int,
    budget: float,
    met: bool,
    tried: list[tuple[str, float, float | str]],
) -> dict[str, Any]:
    """Each of the `(integrator, tol)` candidates timed; the cheaper one's result, with all of
    them under "candidates" (so that run.py can take the least over its rounds)."""
    measured: list[dict[str, Any]] = []
    for integrator, tol in candidates:
        cpus, r = timed(functools.partial(linkwork_timed, problem, model, integrator, tol), repeats, budget)
        stats = statistics(r)
        measured.append(
            {
                "integrator": integrator,
                "tol": tol,
                "error": linkwork_error(problem, model, r),
                "cpu": min(cpus),
                "runs": len(cpus),
                "steps": stats["steps"],
                "newton": stats["newton_iterations"],
            }
        )
    return {"engine": "linkwork", "met": met, "tried": tried, "candidates": measured, **cheapest(measured)}


def cheapest(measured: list[dict[str, Any]]) -> dict[str, Any]:
    """The candidate of least CPU, as the result's settings, error, CPU and counts."""
    best = min(measured, key=lambda c: c["cpu"])
    return {**best, "settings": f"{best['integrator']}, rtol = atol = {best['tol']:.0e}"}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("engine", choices=["exudyn", "linkwork"])
    parser.add_argument("problem", choices=problems.PROBLEMS)
    parser.add_argument("--n", type=int, default=0)
    parser.add_argument("--step", type=float)
    parser.add_argument("--rho", type=float, help="exudyn: the generalised-alpha spectral radius (default 0.9)")
    parser.add_argument("--target", type=float)
    parser.add_argument("--repeats", type=int, default=3, help="timed runs at least")
    parser.add_argument("--budget", type=float, default=2.0, help="CPU seconds of timed runs at least")
    parser.add_argument("--candidates", help="linkwork: INTEGRATOR:TOL,... to time, without the search")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    problem = problems.problem(args.problem, args.n)
    if args.engine == "exudyn":
        result = exudyn_case(problem, args.step, args.rho, args.repeats, args.budget)
    else:
        candidates = None
        if args.candidates:
            candidates = [(c.split(":")[0], float(c.split(":")[1])) for c in args.candidates.split(",")]
        result = linkwork_case(problem, args.target, args.repeats, args.budget, candidates)
    args.out.write_text(json.dumps(result))


if __name__ == "__main__":
    main()
