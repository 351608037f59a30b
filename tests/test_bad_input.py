"""Bad model files: `linkwork run` exits 2 and prints every problem as `path: message`, the path
pointing into the file. Each file is small and differs from a good slider-crank in one place."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import RunLinkwork, WriteModel, patch

# A centred slider-crank that runs; each case below breaks one thing in it.
GOOD = """\
bodies:
  crank: {mass: 1, inertia: 0.001, position: [0.05, 0], angle: 0, points: {O: [-0.05, 0], A: [0.05, 0]}}
  rod: {mass: 2, inertia: 0.015, position: [0.25, 0], angle: 0, points: {A: [-0.15, 0], B: [0.15, 0]}}
  slider: {mass: 1, inertia: 0.001, position: [0.4, 0], angle: 0}
joints:
  O: {type: revolute, body_i: crank, point_i: O, body_j: ground, point_j: [0, 0]}
  A: {type: revolute, body_i: crank, point_i: A, body_j: rod, point_j: A}
  B: {type: revolute, body_i: rod, point_i: B, body_j: slider, point_j: [0, 0]}
  guide: {type: translational, body_i: ground, point_i: [0, 0], axis_i: [1, 0], body_j: slider, point_j: [0, 0], axis_j: [1, 0]}
drivers:
  motor: {type: angle, body: crank, function: "2*pi*t"}
analyses:
  kin: {type: kinematic, drivers: [motor], t_end: 0.5, step: 0.1}
"""


def broken(old: str, new: str) -> str:
    return patch(GOOD, old, new)


# (id, model text, path, words the message must contain)
CASES = [
    (
        "unknown body",
        broken("body_j: rod, point_j: A", "body_j: rokcer, point_j: A"),
        "joints.A.body_j",
        "unknown body 'rokcer'",
    ),
    (
        "missing field",
        broken("rod: {mass: 2, inertia: 0.015,", "rod: {mass: 2,"),
        "bodies.rod",
        "missing field `inertia`",
    ),
    (
        "duplicate name",
        broken("  B: {type: revolute", "  rod: {type: revolute"),
        "joints.rod",
        "duplicate name: 'rod' is already used in bodies",
    ),
    (
        "zero-length axis",
        broken("axis_i: [1, 0]", "axis_i: [0, 0]"),
        "joints.guide.axis_i",
        "zero-length axis",
    ),
    (
        "not a number (.nan)",
        broken("inertia: 0.015", "inertia: .nan"),
        "bodies.rod.inertia",
        "finite",
    ),
    (
        "infinite (.inf)",
        broken("position: [0.4, 0]", "position: [.inf, 0]"),
        "bodies.slider.position[0]",
        "finite",
    ),
    (
        "not numeric",
        broken("position: [0.4, 0]", "position: [0.4, zero]"),
        "bodies.slider.position[1]",
        "unknown name 'zero' (expected a number, a number with a unit, or an expression of parameters)",
    ),
    (
        "expression does not parse",
        broken('function: "2*pi*t"', 'function: "2*pi*(t"'),
        "drivers.motor.function",
        "cannot read the function",
    ),
    (
        "expression with an unknown name",
        broken('function: "2*pi*t"', 'function: "2*pi*time"'),
        "drivers.motor.function",
        "unknown name 'time'",
    ),
    (
        "unknown driver",
        broken("drivers: [motor]", "drivers: [motr]"),
        "analyses.kin.drivers[0]",
        "unknown driver 'motr'",
    ),
    (
        "unknown joint type",
        broken("type: translational", "type: prismatic"),
        "joints.guide.type",
        "unknown type `prismatic`",
    ),
    (
        "not fully driven",
        broken("drivers: [motor]", "drivers: []"),
        "analyses.kin.drivers",
        "add 1 driver(s)",
    ),
]


@pytest.mark.parametrize(("text", "path", "words"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_one_problem(linkwork: RunLinkwork, write_model: WriteModel, text: str, path: str, words: str) -> None:
    done = linkwork("run", write_model(text))
    assert done.code == 2, done.output
    assert "Traceback" not in done.output
    lines = done.stderr.splitlines()
    assert any(line.startswith(f"{path}: ") and words in line for line in lines), done.stderr


def test_the_good_model_runs(linkwork: RunLinkwork, write_model: WriteModel) -> None:
    """The cases above fail because of what they change, not because of the rest."""
    assert linkwork("run", write_model(GOOD)).code == 0


def test_not_fully_driven_says_how_many_drivers_are_missing(linkwork: RunLinkwork, write_model: WriteModel) -> None:
    text = broken("drivers: [motor]", "drivers: []")
    done = linkwork("run", write_model(text))
    assert done.code == 2
    assert re.search(r"analyses\.kin\.drivers: .*1 degree\(s\) of freedom remain.*add 1 driver\(s\)", done.stderr)


# Every problem of this file must be listed, each once, with its path.
SEVERAL = """\
bodies:
  crank: {mass: 1, inertia: .nan, position: [0, 0], angle: 0}
  rocker: {mass: 1, inertia: 1, position: [0, 0], angle: 0, colour: red}
  link: {mass: 1, position: [0, 0], angle: 0}
  slider: {mass: 1, inertia: 1, position: [0, "abc"], angle: 0}
joints:
  B: {type: revolute, body_i: crank, point_i: [0, 0], body_j: rokcer, point_j: [0, 0]}
  S: {type: point_on_line, body_i: crank, point_i: [0, 0], axis_i: [0, 0], body_j: rocker, point_j: [1, 0]}
  crank: {type: revolute, body_i: crank, point_i: [0, 0], body_j: ground, point_j: [0, 0]}
  F: {type: expression, expression: "crank.x * (1 +"}
drivers:
  d: {type: angle, body: crank, function: "2*pi*q"}
analyses:
  kin: {type: kinematic, drivers: [d, e], t_end: 1, step: 0}
"""

SEVERAL_PROBLEMS = [
    ("bodies.crank.inertia", "finite"),
    ("bodies.rocker.colour", "unknown field `colour`"),
    ("bodies.link", "missing field `inertia`"),
    ("bodies.slider.position[1]", "unknown name 'abc'"),
    ("joints.B.body_j", "unknown body 'rokcer'"),
    ("joints.S.axis_i", "zero-length axis"),
    ("joints.crank", "duplicate name"),
    ("joints.F.expression", "cannot read the expression"),
    ("drivers.d.function", "unknown name 'q'"),
    ("analyses.kin.drivers[1]", "unknown driver 'e'"),
    ("analyses.kin.step", "positive"),
]


@pytest.mark.parametrize("command", ["run", "check"])
def test_every_problem_is_listed(linkwork: RunLinkwork, write_model: WriteModel, command: str) -> None:
    done = linkwork(command, write_model(SEVERAL))
    assert done.code == 2, done.output
    lines = done.stderr.splitlines()
    header, problems = lines[0], lines[1:]
    assert header.startswith("error:") and f"({len(SEVERAL_PROBLEMS)} problems)" in header, header
    for path, words in SEVERAL_PROBLEMS:
        found = [line for line in problems if line.startswith(f"{path}: ") and words in line]
        assert len(found) == 1, f"{path}: ...{words}... not listed once in\n{done.stderr}"
    assert len(problems) == len(SEVERAL_PROBLEMS), done.stderr


def test_unknown_body_message(linkwork: RunLinkwork, write_model: WriteModel) -> None:
    """The message the brief quotes, word for word."""
    text = broken("body_j: rod, point_j: A", "body_j: rokcer, point_j: A")
    done = linkwork("check", write_model(text))
    assert done.code == 2
    assert "joints.A.body_j: unknown body 'rokcer'" in done.stderr


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("bodies: [1, 2", "YAML syntax error"),
        ("- 1\n- 2\n", "expected a mapping"),
        ("", "bodies"),
    ],
    ids=["syntax", "not a mapping", "empty"],
)
def test_files_that_are_not_models(linkwork: RunLinkwork, write_model: WriteModel, text: str, words: str) -> None:
    done = linkwork("run", write_model(text))
    assert done.code == 2, done.output
    assert words in done.stderr
    assert "Traceback" not in done.output
