"""Sweep throughput: runs per second for 1,000 variants (by default) of an analysis, with 1 and 2 worker
threads, for the quick-return mechanism (crank length 1.35 to 1.65 m; its kinematic analysis and
its dynamic one, the free motion over 2 s with `bdf`) and the parametrised slider-crank (crank radius 50 to
150 mm; kinematic and inverse).

    python benches/sweep_throughput.py
    python benches/sweep_throughput.py --variants 20 --repeats 1    # a smoke run (tests/test_benches.py)

Each figure is the best of three sweeps (by default; wall time, the whole sweep: compiling each variant from
the file's text, running it and reducing it to its outputs). docs/performance.md records them.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import linkwork

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

# (model file, parameter, low, high, analysis, outputs)
CASES = [
    ("quick_return_a.yaml", "crank", 1.35, 1.65, "kinematics", {"stroke": "max(slider_d.x) - min(slider_d.x)"}),
    (
        "quick_return_a.yaml", "crank", 1.35, 1.65, "dynamics",
        {"omega": "peak(rocker.omega)", "load": "max(sqrt(A.fx^2 + A.fy^2))"},
    ),
    ("slider_crank_param.yaml", "r", 0.05, 0.15, "kinematics", {"stroke": "max(slider.x) - min(slider.x)"}),
    (
        "slider_crank_param.yaml", "r", 0.05, 0.15, "inverse",
        {"stroke": "max(slider.x) - min(slider.x)", "torque": "peak(motor.effort)"},
    ),
]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--variants", type=int, default=1000, help="variants per sweep (at least 2)")
    parser.add_argument("--repeats", type=int, default=3, help="sweeps per figure, the best taken")
    args = parser.parse_args(argv)
    if args.variants < 2 or args.repeats < 1:
        parser.error("--variants must be at least 2 (the grid's two ends) and --repeats at least 1")
    variants = args.variants
    for file, name, low, high, analysis, outputs in CASES:
        model = linkwork.load(EXAMPLES / file)
        values = [low + (high - low) * k / (variants - 1) for k in range(variants)]
        for workers in (1, 2):
            best = float("inf")
            for _ in range(args.repeats):
                start = time.perf_counter()
                table = linkwork.sweep(model, analysis, grid={name: values}, outputs=outputs, workers=workers)
                best = min(best, time.perf_counter() - start)
            ok = int((table["status"] == "ok").sum())
            print(f"{file:24s} {analysis:16s} workers={workers}: {variants / best:7.0f} runs/s ({best:.2f} s, {ok} ok)")


if __name__ == "__main__":
    main()
