"""Work-precision table of the dynamic integrators (docs/integrators.md).

For each model and integrator, runs the model's dynamic analysis at several tolerances and
reports the error against a tight-tolerance run of the same engine (the reference: bdf with
rtol = atol = 1e-11) and the CPU time (best of three runs). The reference's own accuracy is
estimated by its distance from a second one by a different method (abam at 1e-11), printed
under the table.

    python benches/work_precision.py            # prints a Markdown table

The error is the largest absolute difference over every output time of the columns listed per
model (positions, so that every integrator is judged on the same quantities).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import linkwork

ROOT = Path(__file__).resolve().parent.parent
CASES = [
    # (file, analysis, columns compared)
    ("andrews.yaml", "dynamics", ["beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"]),
    ("quick_return_a.yaml", "dynamics_loaded", ["crank.phi", "rocker.phi", "slider_d.x"]),
]
INTEGRATORS = ["bdf", "hht", "abam"]
TOLERANCES = [1e-4, 1e-6, 1e-8]


def timed(model: linkwork.Model, analysis: str, **kw: object) -> tuple[linkwork.Results, float]:
    best = float("inf")
    results = None
    for _ in range(3):
        start = time.process_time()
        results = model.run(analysis, **kw)
        best = min(best, time.process_time() - start)
    assert results is not None
    return results, best


def main() -> int:
    print("| model | integrator | rtol = atol | max error | CPU time (ms) | steps | factorizations |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    notes = []
    for file, analysis, columns in CASES:
        model = linkwork.load(ROOT / "examples" / file)
        reference = model.run(analysis, integrator="bdf", rtol=1e-11, atol=1e-11)
        ref = np.column_stack([reference[c] for c in columns])
        second = model.run(analysis, integrator="abam", rtol=1e-11, atol=1e-11)
        spread = float(np.max(np.abs(np.column_stack([second[c] for c in columns]) - ref)))
        notes.append(f"{file}: the references by bdf and abam at 1e-11 differ by {spread:.1e}")
        for integrator in INTEGRATORS:
            for tol in TOLERANCES:
                try:
                    results, cpu = timed(model, analysis, integrator=integrator, rtol=tol, atol=tol)
                except linkwork.SolverError as error:
                    print(f"| {file} | {integrator} | {tol:g} | failed: {error} | | | |")
                    continue
                got = np.column_stack([results[c] for c in columns])
                err = float(np.max(np.abs(got - ref)))
                stats = results.summary["statistics"]
                print(
                    f"| {file} | {integrator} | {tol:g} | {err:.2e} | {1e3 * cpu:.1f} | "
                    f"{stats['steps']} | {stats['factorizations']} |"
                )
    print()
    for note in notes:
        print(note)
    return 0


if __name__ == "__main__":
    sys.exit(main())
