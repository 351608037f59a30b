"""Linkwork alone on one problem of benches/peers, over integrators and tolerances: the error
against the problem's reference, the CPU time (the least of --repeats runs) and the integrator's
statistics for each, one line each. For studying a row of the side-by-side table (run.py searches
only decades from 1e-4 down).

    python benches/peers/scan.py quick-return-loaded --integrators bdf,hht --tolerances 1e-3,3e-4,1e-4
    python benches/peers/scan.py nfourbar --n 100 --solver "formulation: index3"

--solver adds entries to the analysis' `solver:` settings (YAML flow-mapping entries).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import case  # noqa: E402
import problems  # noqa: E402


def with_solver(problem: problems.Problem, entries: str) -> str:
    """The problem's model text with `entries` in its analysis' `solver:` settings."""
    head = f"  {problem.analysis}:\n    type: dynamic\n"
    if head not in problem.text:
        raise SystemExit(f"scan.py: the analysis {problem.analysis} is not written as `{head.strip()}` in block form")
    return problem.text.replace(head, head + "    solver: {" + entries + "}\n", 1)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problem", choices=problems.PROBLEMS)
    parser.add_argument("--n", type=int, default=0)
    parser.add_argument("--integrators", default="bdf,hht,abam")
    parser.add_argument("--tolerances", default="1e-3,1e-4,1e-5,1e-6")
    parser.add_argument("--solver", default="")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    import linkwork

    problem = problems.problem(args.problem, args.n)
    model = linkwork.from_yaml(with_solver(problem, args.solver) if args.solver else problem.text)
    print(f"{problem.label}: error in {problem.unit}")
    for integrator in args.integrators.split(","):
        for tol in (float(x) for x in args.tolerances.split(",")):
            try:
                runs = [case.linkwork_run(problem, model, integrator, tol) for _ in range(args.repeats)]
            except linkwork.LinkworkError as failure:
                print(f"{integrator:5s} {tol:8.0e}  failed: {failure}")
                continue
            err, _, stats = runs[-1]
            cpu = min(r[1] for r in runs)
            print(
                f"{integrator:5s} {tol:8.0e}  error {err:.3e}  CPU {cpu * 1e3:8.2f} ms  steps {stats['steps']:6d}"
                f"  Newton {stats['newton_iterations']:6d}  factorizations {stats['factorizations']:6d}"
                f"  rejected {stats['rejected_steps']:5d}"
            )


if __name__ == "__main__":
    main()
