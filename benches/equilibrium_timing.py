"""CPU time of the inverse and static analyses beside the kinematic one (docs/equilibrium.md).

    pip install . && python benches/equilibrium_timing.py     # prints Markdown table rows

Best of five runs of `Model.run`, `time.process_time()`, from the repository root.
"""

from __future__ import annotations

import time

import linkwork


def best(model: linkwork.Model, name: str, k: int = 5) -> tuple[float, linkwork.Results]:
    """The least CPU milliseconds of `k` runs of the analysis `name`, and the last run's results."""
    b = float("inf")
    for _ in range(k):
        s = time.process_time()
        r = model.run(name)
        b = min(b, time.process_time() - s)
    return b * 1e3, r


def main() -> None:
    cases = [
        ("quick_return_a.yaml", "kinematics"),
        ("quick_return_a.yaml", "inverse"),
        ("quick_return_b.yaml", "inverse"),
        ("ellipse_trammel.yaml", "equilibrium"),
    ]
    for f, a in cases:
        ms, r = best(linkwork.load(f"examples/{f}"), a)
        print(f"| {f} | {a} | {len(r)} | {ms:.2f} |")


if __name__ == "__main__":
    main()
