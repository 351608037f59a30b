"""Sweep throughput: runs per second for 1,000 variants of the parametrised slider-crank's
kinematic and inverse analyses (crank radius r from 50 to 150 mm), with 1 and 2 worker threads.

    python benches/sweep_throughput.py

Each figure is the best of three sweeps (wall time, the whole sweep: compiling each variant from
the file's text, running it and reducing it to its output). docs/performance.md records them.
"""

from __future__ import annotations

import time
from pathlib import Path

import linkwork

MODEL = Path(__file__).resolve().parent.parent / "examples" / "slider_crank_param.yaml"
VARIANTS = 1000


def main() -> None:
    model = linkwork.load(MODEL)
    radii = [0.05 + 0.1 * k / (VARIANTS - 1) for k in range(VARIANTS)]
    outputs = {"stroke": "max(slider.x) - min(slider.x)", "torque": "peak(motor.effort)"}
    for analysis in ("kinematics", "inverse"):
        used = outputs if analysis == "inverse" else {"stroke": outputs["stroke"]}
        for workers in (1, 2):
            best = float("inf")
            for _ in range(3):
                start = time.perf_counter()
                table = linkwork.sweep(model, analysis, grid={"r": radii}, outputs=used, workers=workers)
                best = min(best, time.perf_counter() - start)
            ok = int((table["status"] == "ok").sum())
            print(f"{analysis:10s} workers={workers}: {VARIANTS / best:7.0f} runs/s ({best:.2f} s, {ok} ok)")


if __name__ == "__main__":
    main()
