"""Contact through the Python API: examples/bouncing_disc.yaml's dynamic analysis and its contact
columns, the same disc built with the builder (generic `force` and typed `contact`), and bad input
refused naming its field (docs/model-format.md, "Contact")."""

from __future__ import annotations

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES

G = 9.81


def test_the_example_bounces() -> None:
    """The disc falls 0.45 m onto the floor: it meets it at `sqrt(2 g 0.45) = 2.971` m/s (free
    fall, exact to the integrator's tolerance: 1e-6), rebounds slower (damping 0.05 s/m: a
    restitution near 0.91, checked against an RK4 solution in crates/linkwork/tests/contact.rs),
    and the contact columns are consistent: a normal force only while penetrating, never negative."""
    results = linkwork.load(EXAMPLES / "bouncing_disc.yaml").run("dynamics")
    y, vy = results["disc.y"], results["disc.vy"]
    fn, depth = results["bounce.fn"], results["bounce.penetration"]
    assert np.all(np.isfinite(results["bounce.ft"]))
    assert np.all(fn >= 0.0) and np.all(depth >= 0.0)
    assert np.all((fn > 0.0) == (depth > 0.0))
    free = (depth == 0.0) & (y > 0.052)
    t = results.time

    def speed(rows: np.ndarray) -> np.ndarray:
        """The speed at the floor, exact in free flight."""
        return np.asarray(np.sqrt(vy[rows] ** 2 + 2.0 * G * (y[rows] - 0.05)))

    before, after = speed(free & (t < 0.3))[-1], speed(free & (t > 0.31) & (t < 0.8))[0]
    assert abs(before - np.sqrt(2.0 * G * 0.45)) < 1e-6
    assert 0.85 < after / before < 0.95
    assert fn.max() > 100.0 * G  # an impact, not a resting load


def disc(m: linkwork.Mechanism) -> None:
    m.body("disc", mass=1.0, inertia=0.00125, position=(0.0, 0.5))
    m.analysis("drop", "dynamic", t_end=0.5, step=0.001)


def test_the_builder_makes_the_same_contact() -> None:
    """The generic `force(name, "contact", ...)` and the typed `contact(...)` give the example's
    results (the same model, so the same numbers to the last bit)."""
    fields = dict(
        body_i="ground",
        shape_i={"segment": [(-1.0, 0.0), (1.0, 0.0)]},
        body_j="disc",
        shape_j={"circle": {"centre": (0.0, 0.0), "radius": 0.05}},
        stiffness=1e6,
        exponent=1.5,
        damping=0.05,
        friction={"mu": 0.3},
    )
    generic = linkwork.Mechanism("disc", gravity=(0.0, -G))
    disc(generic)
    generic.force("bounce", "contact", **fields)
    typed = linkwork.Mechanism("disc", gravity=(0.0, -G))
    disc(typed)
    typed.contact("bounce", **fields)  # type: ignore[arg-type]
    a, b = generic.build().run("drop"), typed.build().run("drop")
    np.testing.assert_array_equal(a["bounce.fn"], b["bounce.fn"])
    assert a["bounce.fn"].max() > 0.0


@pytest.mark.parametrize(
    ("field", "value", "path"),
    [
        ("stiffness", -1.0, "forces.bounce.stiffness"),
        ("shape_j", {"circle": {"radius": 0.0}}, "forces.bounce.shape_j.circle.radius"),
        ("body_j", "wheel", "forces.bounce.body_j"),
        ("shape_j", {"segment": [(0.0, 0.0), (1.0, 0.0)]}, "forces.bounce.shape_j"),
    ],
)
def test_bad_contacts_name_their_field(field: str, value: object, path: str) -> None:
    fields: dict[str, object] = dict(
        body_i="ground",
        shape_i={"segment": [(-1.0, 0.0), (1.0, 0.0)]},
        body_j="disc",
        shape_j={"circle": {"radius": 0.05}},
        stiffness=1e6,
    )
    fields[field] = value
    m = linkwork.Mechanism("disc", gravity=(0.0, -G))
    disc(m)
    m.force("bounce", "contact", **fields)
    with pytest.raises(linkwork.LinkworkError, match=path.replace(".", r"\.")):
        m.build()


@pytest.mark.parametrize("analysis", ["dynamics_hht", "dynamics_abam"])
def test_every_integrator_sees_the_first_impact(analysis: str) -> None:
    """hht and abam locate the first contact as bdf does: the free-flight speed before and after
    the first impact agree with bdf's to 1e-5 m/s (the example runs each at rtol 1e-8; they agree
    with an RK4 solution to 2.4e-5 m/s in crates/linkwork/tests/contact.rs)."""
    model = linkwork.load(EXAMPLES / "bouncing_disc.yaml")

    def speeds(results: linkwork.Results) -> tuple[float, float]:
        y, vy, depth, t = results["disc.y"], results["disc.vy"], results["bounce.penetration"], results.time
        free = (depth == 0.0) & (y > 0.052)
        before, after = np.flatnonzero(free & (t < 0.3))[-1], np.flatnonzero(free & (t > 0.31) & (t < 0.8))[0]

        def floor_speed(k: int) -> float:
            return float(np.sqrt(vy[k] ** 2 + 2.0 * G * (y[k] - 0.05)))

        return floor_speed(before), floor_speed(after)

    want, got = speeds(model.run("dynamics")), speeds(model.run(analysis))
    assert abs(got[0] - want[0]) < 1e-5 and abs(got[1] - want[1]) < 1e-5, (got, want)
