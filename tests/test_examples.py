"""The example generators: `examples/nfourbar.py` writes the committed N-four-bar model.

These tests need only the standard library and pytest (not the `linkwork` package), so they run
with `python -m pytest tests/test_examples.py --noconftest` where the package is not installed.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
GENERATOR = EXAMPLES / "nfourbar.py"


def generate(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(GENERATOR), *args], capture_output=True, text=True, check=False, timeout=60
    )


def test_generator_writes_the_committed_n40_file() -> None:
    out = generate("40")
    assert out.returncode == 0, out.stderr
    assert out.stdout == (EXAMPLES / "iftomm_a02_nfourbar.yaml").read_text()


def test_generator_counts_bodies_and_joints() -> None:
    for n in (1, 3, 7):
        text = generate(str(n)).stdout
        rockers = re.findall(r"^  r\d+: ", text, flags=re.M)
        couplers = re.findall(r"^  c\d+: ", text, flags=re.M)
        joints = re.findall(r"^  [ALR]\d+: \{type: revolute", text, flags=re.M)
        assert (len(rockers), len(couplers), len(joints)) == (n + 1, n, 3 * n + 1)
        # Only the first rocker holds its angle and speed in assembly.
        assert text.count("given: [phi, omega]") == 1


def test_generator_refuses_bad_arguments() -> None:
    for args in ((), ("0",), ("-3",), ("x",), ("2", "3")):
        out = generate(*args)
        assert out.returncode == 2 and "usage" in out.stderr and out.stdout == ""
