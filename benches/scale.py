"""Scale: the IFToMM N-four-bar (examples/nfourbar.py) from N = 10 to 10,000 bodies' worth of
loops: `linkwork check`'s wall time, and the dynamic analysis (`bdf`, rtol 1e-6) CPU time per
step and peak memory, each in a fresh process.

    python benches/scale.py [N ...]
    python benches/scale.py --stream [N ...]

Default N: 10 100 1000 10000. The motion is 10 s for N up to 1000 (through the flat singular
positions, twice a revolution) and 1 s for N = 10,000, whose results are held in memory. With
--stream every run is 10 s and streams all its results to a CSV file (in a temporary folder) as
they are computed. docs/performance.md, "Scale", records the figures.
"""

from __future__ import annotations

import importlib
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The child: run the analysis of the model file argv[1] to argv[2] s and print its figures; with
# argv[3], streamed to that CSV file (whose B0_y column is then read line by line, after the peak
# memory is taken). Without it the results are not written: the run is measured, not the CSV.
CHILD = """
import csv, json, resource, sys, time
import numpy as np
import linkwork
model = linkwork.load(sys.argv[1])
stream = sys.argv[3] if len(sys.argv) > 3 else None
start = time.process_time()
results = model.run("dynamics", integrator="bdf", rtol=1e-6, t_end=float(sys.argv[2]), stream=stream)
cpu = time.process_time() - start
stats = results.summary["statistics"]
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
if stream is None:
    b0y = results["B0_y"]
else:
    csv.field_size_limit(1 << 30)
    with open(stream, newline="") as file:
        rows = csv.reader(file)
        k = next(rows).index("B0_y")
        b0y = np.array([float(row[k]) for row in rows])
crossings = int(((b0y[:-1] * b0y[1:]) < 0).sum())
print(json.dumps({"cpu": cpu, "steps": stats["steps"], "peak_mb": peak, "crossings": crossings,
                  "status": results.summary["status"], "rows": len(b0y)}))
"""


def main() -> None:
    streamed = "--stream" in sys.argv[1:]
    sizes = [int(a) for a in sys.argv[1:] if a != "--stream"] or [10, 100, 1000, 10000]
    sys.path.insert(0, str(ROOT / "examples"))
    # By name at run time: examples/ is a folder of scripts, not a package the type check sees.
    nfourbar = importlib.import_module("nfourbar")

    linkwork = [sys.executable, "-m", "linkwork"]
    print("| N | coordinates | `linkwork check` | motion | CPU | steps | CPU per step | peak memory | flat positions passed |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as folder:
        for n in sizes:
            path = Path(folder) / f"nfourbar_{n}.yaml"
            path.write_text(nfourbar.model(n))
            start = time.perf_counter()
            subprocess.run([*linkwork, "check", str(path)], check=True, capture_output=True)
            check = time.perf_counter() - start
            t_end = 10.0 if n <= 1000 or streamed else 1.0
            stream = [str(Path(folder) / "results.csv")] if streamed else []
            child = [sys.executable, "-c", CHILD, str(path), str(t_end), *stream]
            done = subprocess.run(child, check=True, capture_output=True, text=True)
            r = json.loads(done.stdout)
            if streamed:
                size = Path(stream[0]).stat().st_size
                Path(stream[0]).unlink()
                print(f"N = {n:,}: {r['rows']} rows streamed, {size / 1e9:.2f} GB of CSV", file=sys.stderr)
            print(
                f"| {n:,} | {6 * n + 3:,} | {check:.2f} s | {t_end:g} s | {r['cpu']:.2f} s | {r['steps']} | "
                f"{1e3 * r['cpu'] / r['steps']:.2f} ms | {r['peak_mb']:.0f} MB | {r['crossings']} ({r['status']}) |",
                flush=True,
            )


if __name__ == "__main__":
    main()
