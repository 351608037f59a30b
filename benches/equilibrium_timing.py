"""CPU time of the inverse and static analyses beside the kinematic one (docs/equilibrium.md).

    pip install . && python benches/equilibrium_timing.py     # prints Markdown table rows

Best of five runs of `Model.run`, `time.process_time()`, from the repository root.
"""

import time, linkwork
def best(model, name, k=5):
    b = float("inf")
    for _ in range(k):
        s = time.process_time(); r = model.run(name); b = min(b, time.process_time() - s)
    return b * 1e3, r
for f, a in [("quick_return_a.yaml", "kinematics"), ("quick_return_a.yaml", "inverse"), ("quick_return_b.yaml", "inverse"), ("ellipse_trammel.yaml", "equilibrium")]:
    ms, r = best(linkwork.load(f"examples/{f}"), a)
    print(f"| {f} | {a} | {len(r)} | {ms:.2f} |")
