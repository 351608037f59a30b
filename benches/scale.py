"""Scale: the IFToMM N-four-bar (examples/nfourbar.py) from N = 10 to 10,000 bodies' worth of
loops: `linkwork check`'s wall time, and the dynamic analysis (`bdf`, rtol 1e-6) CPU time per
step and peak memory, each in a fresh process.

    python benches/scale.py [N ...]

Default N: 10 100 1000 10000. The motion is 10 s for N up to 1000 (through the flat singular
positions, twice a revolution) and 1 s for N = 10,000. docs/performance.md, "Scale", records the
figures.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The child: run the analysis of the model file argv[1] to argv[2] s and print its figures. The
# results are not written: the run is measured, not the CSV of 30,000 columns.
CHILD = """
import json, resource, sys, time
import linkwork
model = linkwork.load(sys.argv[1])
start = time.process_time()
results = model.run("dynamics", integrator="bdf", rtol=1e-6, t_end=float(sys.argv[2]))
cpu = time.process_time() - start
stats = results.summary["statistics"]
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
b0y = results["B0_y"]
crossings = int(((b0y[:-1] * b0y[1:]) < 0).sum())
print(json.dumps({"cpu": cpu, "steps": stats["steps"], "peak_mb": peak, "crossings": crossings,
                  "status": results.summary["status"]}))
"""


def main() -> None:
    sizes = [int(a) for a in sys.argv[1:]] or [10, 100, 1000, 10000]
    sys.path.insert(0, str(ROOT / "examples"))
    import nfourbar

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
            t_end = 10.0 if n <= 1000 else 1.0
            done = subprocess.run([sys.executable, "-c", CHILD, str(path), str(t_end)], check=True, capture_output=True, text=True)
            r = json.loads(done.stdout)
            print(
                f"| {n:,} | {6 * n + 3:,} | {check:.2f} s | {t_end:g} s | {r['cpu']:.2f} s | {r['steps']} | "
                f"{1e3 * r['cpu'] / r['steps']:.2f} ms | {r['peak_mb']:.0f} MB | {r['crossings']} ({r['status']}) |",
                flush=True,
            )


if __name__ == "__main__":
    main()
