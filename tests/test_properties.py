"""Property tests of the Python API with Hypothesis: whatever a user passes, the answer is a result
whose numbers are finite, or a `LinkworkError` that names the field; never another exception.

The example budget is fixed (`max_examples` below, a few seconds in all) so that CI stays short;
`HYPOTHESIS_PROFILE=long` runs 50 times as many (docs/reliability.md records such a run).
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import linkwork
from conftest import EXAMPLES

# CI: enough examples to reach each kind of value the strategies draw (bools, NaN, infinities,
# zero and negative numbers, text) several times; `long` for a run recorded in the docs.
settings.register_profile(
    "ci", max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("long", max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

G = 9.81

PENDULUM = """
gravity: [0, -{g}]
bodies:
  bar: {{mass: {mass}, inertia: {inertia}, position: [{half}, 0], angle: 0, points: {{O: [-{half}, 0]}}}}
joints:
  O: {{type: revolute, body_i: bar, point_i: O, body_j: ground, point_j: [0, 0]}}
analyses:
  swing: {{type: dynamic, integrator: abam, t_end: 0.3, step: 0.01, solver: {{rtol: 1e-10, atol: 1e-10}}}}
  rest: {{type: static}}
"""

# Any value a user may write where a number is expected: numbers of every size and sign, the
# non-finite ones, bools, text and nothing.
Drawn = float | int | str | None
anything: st.SearchStrategy[Drawn] = st.one_of(
    # The hostile values by name: at the CI budget (60 examples) the float strategy alone drew no
    # NaN.
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -1.0, True, False, "", "1", None]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.booleans(),
    st.text(max_size=8),
    st.none(),
)


def all_finite(results: linkwork.Results) -> bool:
    return all(np.isfinite(results[name]).all() for name in results.columns)


@given(
    mass=st.floats(min_value=1e-3, max_value=1e3),
    length=st.floats(min_value=1e-2, max_value=1e2),
    shape=st.floats(min_value=0.0, max_value=1.0),
)
def test_a_pendulum_of_any_size_keeps_its_energy(mass: float, length: float, shape: float) -> None:
    """A pendulum released horizontally, of any mass and length, and any inertia from a point mass
    (0) to a thin rod's (`m L^2 / 12`): the energy computed here from the result columns
    (`m (vx^2 + vy^2) / 2 + J omega^2 / 2 + m g y`) stays at its start value. `abam` at `1e-10`
    keeps the positions and velocities to about `1e-9` relative over 0.3 s, so the energy holds
    to about `1e-8` of `m g L`; `1e-6` leaves room for the error growing with the swing."""
    half = length / 2
    inertia = shape * mass * length**2 / 12
    model = linkwork.from_yaml(PENDULUM.format(g=G, mass=mass, inertia=inertia, half=half))
    r = model.run("swing")
    assert all_finite(r)
    vx, vy, omega, y = r["bar.vx"], r["bar.vy"], r["bar.omega"], r["bar.y"]
    energy = 0.5 * mass * (vx**2 + vy**2) + 0.5 * inertia * omega**2 + mass * G * y
    scale = mass * G * length
    assert np.max(np.abs(energy - energy[0])) <= 1e-6 * scale
    # Independent too: the pin stays at the origin (the bar's point O is `half` behind its centre).
    pin_x = r["bar.x"] - half * np.cos(r["bar.phi"])
    pin_y = y - half * np.sin(r["bar.phi"])
    assert np.max(np.hypot(pin_x, pin_y)) <= 1e-9 * max(1.0, length)


@given(field=st.sampled_from(["mass", "inertia", "half"]), value=anything)
def test_a_bad_number_is_refused_naming_its_field(field: str, value: Drawn) -> None:
    """Any value in a pendulum's mass, inertia or point: the model loads and runs with finite
    results, or the error is a `LinkworkError` (never a `TypeError`, `ValueError` or a panic);
    a value that is not a number is refused as a `ModelError` naming `bodies.bar`."""
    values: dict[str, Drawn] = {"mass": 1.0, "inertia": 0.1, "half": 0.5}
    values[field] = value
    text = PENDULUM.format(g=G, **{k: _yaml(v) for k, v in values.items()})
    try:
        model = linkwork.from_yaml(text)
        # The static analysis: it is as quick for a bar of 1e-300 m as of 1 m, where the swing of a
        # bar that short is 1e150 periods a second, which the integrator's step budget stops only
        # after minutes.
        r = model.run("rest")
    except linkwork.ModelError as error:
        # The field, or the analysis a usable number makes impossible (a massless bar has nothing
        # for gravity to load: `analyses.rest` names the free coordinates).
        # Text with a control character makes the file itself invalid YAML, which the reader
        # names by its position.
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        named = ("bodies.bar", "analyses.rest") if number else ("bodies.bar", "YAML syntax error")
        assert any(n in str(error) for n in named), str(error)
        return
    except linkwork.LinkworkError:
        return
    assert all_finite(r)


@given(option=st.sampled_from(["rtol", "atol", "t_end", "step"]), value=anything)
def test_a_bad_override_is_refused_naming_it(option: str, value: Drawn) -> None:
    """Any value passed to `Model.run` as a tolerance, end time or step: a run with finite results,
    or a `ModelError` that names the option (`--rtol`, ...); a solver error is allowed for values
    that are numbers. Never a `TypeError` or an `OverflowError`."""
    # A run the user asked to be long is long, not hung: an end time up to 1e5 s or a step down to
    # 1e-5 s is up to 1e7 output rows of integration (minutes), so these numbers are left out; the
    # larger and smaller ones, which the 1e7-row limit refuses, are kept.
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        assume(not (option == "t_end" and 0.1 < value <= 1e5))
        assume(not (option == "step" and 0 < value < 1e-5))
    model = linkwork.load(EXAMPLES / "double_pendulum.yaml")
    name = model.analyses[0]
    # Values of any type, on purpose: what `run` does with a type its signature does not take is
    # what is tested.
    overrides: dict[str, Any] = {option: value}
    if option != "t_end":
        overrides["t_end"] = 0.05
    try:
        r = model.run(name, **overrides)
    except linkwork.ModelError as error:
        assert f"--{option.replace('_', '-')}" in str(error), str(error)
        return
    except linkwork.SolverError:
        assert isinstance(value, (int, float)) and not isinstance(value, bool)
        return
    assert all_finite(r)


@given(data=st.data())
@settings(suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
def test_an_edited_example_loads_or_says_why(data: st.DataObject) -> None:
    """An example with a few characters replaced, inserted or deleted anywhere: it loads (and its
    check runs), or the error is a `LinkworkError`; never another exception."""
    path = data.draw(st.sampled_from(sorted(EXAMPLES.glob("*.yaml"))))
    text = path.read_text()
    for _ in range(data.draw(st.integers(min_value=1, max_value=4))):
        at = data.draw(st.integers(min_value=0, max_value=len(text)))
        cut = data.draw(st.integers(min_value=0, max_value=3))
        insert = data.draw(st.text(alphabet="0123456789.-e:[]{},# abtxyz\n", max_size=4))
        text = text[:at] + insert + text[at + cut :]
    try:
        model = linkwork.from_yaml(text)
        model.check()
    except linkwork.LinkworkError:
        pass


def _yaml(value: object) -> str:
    """A Python value as YAML text (floats in full, so that NaN and infinities read as YAML's)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return str(value)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), True, "1"])
def test_the_strategies_reach_the_hostile_values(value: Drawn) -> None:
    """The drawn values include each kind the properties are about (a strategy that never drew a
    NaN would let the properties pass without testing it)."""
    found: list[Drawn] = []

    @given(anything)
    # The `ci` profile's budget: what each property test draws in CI.
    @settings(max_examples=60, derandomize=True, database=None)
    def collect(v: Drawn) -> None:
        found.append(v)

    collect()
    same = [v for v in found if type(v) is type(value)]
    floats = [v for v in same if isinstance(v, float)]
    if isinstance(value, float) and math.isnan(value):
        assert any(math.isnan(v) for v in floats)
    elif isinstance(value, float):
        assert any(math.isinf(v) for v in floats)
    else:
        assert same
