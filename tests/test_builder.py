"""The Python builder (`linkwork.Mechanism`): a model built by name is the model its file
describes, `to_yaml()` writes that file exactly, and bad input is refused naming the field."""

from __future__ import annotations

import numpy as np
import pytest

import linkwork
from conftest import EXAMPLES, ROOT


def placed_four_bar() -> linkwork.Mechanism:
    """examples/fourbar_placed.yaml, built in Python."""
    m = linkwork.Mechanism("Grashof four-bar, placed in the drawing's frame")
    m.parameter("bx", "0.26875 m")
    m.parameter("by", "sqrt(0.3^2 - (bx - 0.1)^2)")
    crank = m.body("crank", mass=0.5, inertia=0.0005, position="M",
                   points_global={"O2": (0, 0), "A": (0.1, 0), "M": (0.05, 0)})
    coupler = m.body("coupler", mass=1.0, inertia=0.0075, position="M",
                     points_global={"A": (0.1, 0), "B": ("bx", "by"), "M": ("(0.1 + bx)/2", "by/2")})
    rocker = m.body("rocker", mass=0.8, inertia=0.004, position="M",
                    points_global={"O4": (0.3, 0), "B": ("bx", "by"), "M": ("(0.3 + bx)/2", "by/2")})
    m.revolute("O2", crank, "ground", at=(0, 0))
    m.revolute("A", crank, coupler, at=(0.1, 0))
    m.revolute("B", coupler, rocker, at=("bx", "by"))
    m.revolute("O4", rocker, "ground", at=(0.3, 0))
    m.driver("motor", "angle", body=crank, function="2*t")
    m.analysis("kinematics", "kinematic", drivers=["motor"], t_end=6.3, step=0.02)
    return m


def test_a_built_model_runs_as_its_file_does() -> None:
    built = placed_four_bar().build().run()
    loaded = linkwork.load(EXAMPLES / "fourbar_placed.yaml").run()
    assert built.columns == loaded.columns
    assert np.array_equal(built.values, loaded.values) and np.array_equal(built.time, loaded.time)


def test_a_built_slider_crank_runs_as_the_example() -> None:
    """examples/slider_crank.yaml in body frames, with the typed joints and a gravity, a force
    and an inverse analysis added to both: every analysis gives the file's results, bit for bit."""
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    for old, new in [
        ("name: slider-crank\n", "name: slider-crank\ngravity: [0, -9.81]\n"),
        ("drivers:\n", "forces:\n  push: {type: force, body: slider, fx: -20}\ndrivers:\n"),
    ]:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    text += "  inverse: {type: inverse, drivers: [motor], t_end: 1.0, step: 0.01}\n"
    loaded = linkwork.from_yaml(text)

    m = linkwork.Mechanism("slider-crank", gravity=(0, -9.81))
    crank = m.body("crank", mass=1.0, inertia=0.001, position=(0.05, 0.001), angle=0.0,
                   points={"O": (-0.05, 0), "A": (0.05, 0)})
    rod = m.body("rod", mass=2.0, inertia=0.015, position=(0.25, -0.002), angle=0.01,
                 points={"A": (-0.15, 0), "B": (0.15, 0)})
    slider = m.body("slider", mass=1.0, inertia=0.001, position=(0.4, 0.0), angle=0.0)
    m.revolute("O", crank, "ground", point_i="O", point_j=(0, 0))
    m.revolute("A", crank, rod, point_i="A", point_j="A")
    m.revolute("B", rod, slider, point_i="B", point_j=(0, 0))
    m.translational("guide", "ground", slider, point_i=(0, 0), axis_i=(1, 0), point_j=(0, 0), axis_j=(1, 0))
    m.force("push", "force", body=slider, fx=-20)
    m.driver("motor", "angle", body=crank, function="2*pi*t")
    m.analysis("kinematics", "kinematic", drivers=["motor"], t_end=2.0, step=0.01)
    m.analysis("inverse", "inverse", drivers=["motor"], t_end=1.0, step=0.01)
    built = m.build()
    assert built.analyses == loaded.analyses == ["kinematics", "inverse"]
    for analysis in built.analyses:
        a, b = built.run(analysis), loaded.run(analysis)
        assert a.columns == b.columns and np.array_equal(a.values, b.values), analysis


def test_to_yaml_writes_every_number_and_text_exactly() -> None:
    m = linkwork.Mechanism('a "quoted" name: é, [x]')
    m.parameter("r", 0.1 + 0.2)
    m.parameter("tiny", 1e-300)
    m.parameter("length", "300 mm")
    bar = m.body("bar", mass=np.float64(2.5), inertia="r^2", position=np.array([1.0, 2.0]))
    m.revolute("pin", bar, "ground", point_i=(0, 0), point_j=(1, 2))
    model = m.build()
    assert model.name == 'a "quoted" name: é, [x]'
    assert model.parameters == {"r": 0.30000000000000004, "tiny": 1e-300, "length": 0.3}
    assert "r: 0.30000000000000004" in m.to_yaml()
    # Characters YAML refuses unescaped in quotes (DEL, C1 controls, a byte-order mark).
    odd = linkwork.Mechanism("a\x7fb\x85c\x9fd\ufeffe")
    odd.body("bar", mass=1, inertia=1, position=(0, 0))
    assert odd.build().name == "a\x7fb\x85c\x9fd\ufeffe"
    # A word YAML would read as a boolean stays text.
    word = linkwork.Mechanism("yes")
    word.body("no", mass=1, inertia=1, position=(0, 0))
    assert word.build().name == "yes" and word.build().bodies == ["no"]


def test_bad_input_is_refused_naming_the_field() -> None:
    m = linkwork.Mechanism()
    m.body("crank", mass=1, inertia=0.1, position=(0, 0))
    with pytest.raises(ValueError, match=r"joints\.crank: the name is already used in bodies"):
        m.revolute("crank", "crank", "ground", at=(0, 0))
    with pytest.raises(ValueError, match=r"bodies\.rod\.mass: expected a finite number, found nan"):
        m.body("rod", mass=float("nan"), inertia=0.1, position=(0, 0))
    with pytest.raises(ValueError, match=r"bodies\.rod\.points\.A\[0\]: expected a number, text"):
        m.body("rod", mass=1, inertia=0.1, position=(0, 0), points={"A": (object(), 0)})  # type: ignore[dict-item]
    # What only the engine can judge is a ModelError at the path in the file.
    m.revolute("O", "crank", "coupler", at=(0, 0))
    with pytest.raises(linkwork.ModelError) as error:
        m.build()
    assert any(path == "joints.O.body_j" and "unknown body 'coupler'" in message for path, message in error.value.problems)


def measured_four_bar() -> linkwork.Mechanism:
    """examples/fourbar_measures.yaml, built in Python with the typed measures."""
    m = linkwork.Mechanism("four-bar with measures")
    for name, value in [("a", 0.1), ("b", 0.3), ("c", 0.25), ("d", 0.3), ("rho", 5), ("load", 1.5)]:
        m.parameter(name, value)
    crank = m.body("crank", mass="rho*a", inertia="rho*a^3/12", position=("a/2", 0), angle=0,
                   points={"O2": ("-a/2", 0), "A": ("a/2", 0)})
    coupler = m.body("coupler", mass="rho*b", inertia="rho*b^3/12", position=(0.18, 0.13), angle=0.95,
                     points={"A": ("-b/2", 0), "B": ("b/2", 0)})
    rocker = m.body("rocker", mass="rho*c", inertia="rho*c^3/12", position=(0.29, 0.12), angle=1.7,
                    points={"O4": ("-c/2", 0), "B": ("c/2", 0)})
    m.ground_point("O2", (0, 0))
    m.ground_point("O4", ("d", 0))
    m.revolute("O2", crank, "ground", point_i="O2", point_j="O2")
    m.revolute("A", crank, coupler, point_i="A", point_j="A")
    m.revolute("B", coupler, rocker, point_i="B", point_j="B")
    m.revolute("O4", rocker, "ground", point_i="O4", point_j="O4")
    m.driver("motor", "angle", body=crank, function="2*t")
    m.force("brake", "torque", body=rocker, torque="-load")
    m.transmission_angle("mu", joint="B", coupler_joint="A", rocker_joint="O4")
    m.velocity_ratio("vr", input=crank, output=rocker)
    m.mechanical_advantage("ma", input="motor", output="brake")
    m.measure("B_load", "sqrt(B.fx^2 + B.fy^2)")
    m.measure("motor_power", "motor.effort * crank.omega")
    m.analysis("inverse", "inverse", drivers=["motor"], t_end=3.14, step=0.01)
    return m


def test_the_standard_measures_built_run_as_the_example() -> None:
    """The typed measures write the file's entries (those of the generic `measure(type=...)`),
    and the model runs as examples/fourbar_measures.yaml, bit for bit, with its masses and
    massless."""
    m = measured_four_bar()
    measures = m.to_dict()["measures"]
    assert measures["mu"] == {"type": "transmission_angle", "joint": "B", "coupler_joint": "A", "rocker_joint": "O4"}
    assert measures["vr"] == {"type": "velocity_ratio", "input": "crank", "output": "rocker"}
    assert measures["ma"] == {"type": "mechanical_advantage", "input": "motor", "output": "brake"}
    for parameters in [None, {"rho": 0}]:
        built = m.build(parameters).run("inverse")
        loaded = linkwork.load(EXAMPLES / "fourbar_measures.yaml", parameters=parameters).run("inverse")
        assert built.columns == loaded.columns and built.columns[-5:] == ["mu", "vr", "ma", "B_load", "motor_power"]
        assert np.array_equal(built.values, loaded.values), parameters
    # A bad name in a typed measure is the engine's problem, at its field.
    bad = linkwork.Mechanism()
    bad.body("crank", mass=1, inertia=0.1, position=(0, 0))
    bad.velocity_ratio("vr", input="crank", output="rockr")
    with pytest.raises(linkwork.ModelError) as error:
        bad.build()
    assert any(path == "measures.vr.output" and "unknown body 'rockr'" in message for path, message in error.value.problems)


def test_a_built_slider_crank_with_friction_runs_as_the_example() -> None:
    """examples/slider_crank_friction.yaml built with `friction=` on the revolute and translational
    joints and its summaries: the inverse analysis gives the file's results, bit for bit, friction
    columns and summaries included; bad friction is refused at its path in the model."""
    m = linkwork.Mechanism("slider-crank with joint friction", gravity=(0, -9.81))
    m.parameter("damping", 200)
    crank = m.body("crank", mass=1.0, inertia=0.001, position=(0.05, 0.001), angle=0.0,
                   points={"O": (-0.05, 0), "A": (0.05, 0)})
    rod = m.body("rod", mass=2.0, inertia=0.015, position=(0.25, -0.002), angle=0.01,
                 points={"A": (-0.15, 0), "B": (0.15, 0)})
    slider = m.body("slider", mass=1.0, inertia=0.001, position=(0.4, 0.0), angle=0.0)
    pin: linkwork.PinFriction = {"mu": 0.1, "radius": "10 mm"}
    m.revolute("O", crank, "ground", point_i="O", point_j=(0, 0), friction=pin)
    m.revolute("A", crank, rod, point_i="A", point_j="A", friction=pin)
    m.revolute("B", rod, slider, point_i="B", point_j=(0, 0), friction=pin)
    m.translational("guide", "ground", slider, point_i=(0, 0), axis_i=(1, 0), point_j=(0, 0), axis_j=(1, 0),
                    friction={"mu": 0.15, "length": "50 mm"})
    m.driver("motor", "angle", body=crank, function="2*pi*t")
    m.force("pump", "force", body=slider, fx="-damping*slider.vx")
    m.measure("motor_power", "motor.effort * crank.omega")
    m.measure("pump_power", "damping * slider.vx^2")
    m.summary("efficiency", "integral(pump_power) / integral(motor_power)")
    m.summary("motor_work", "integral(motor_power)")
    m.summary("pump_work", "integral(pump_power)")
    m.summary(
        "friction_work",
        "-integral(O.friction * crank.omega + A.friction * (crank.omega - rod.omega)"
        " + B.friction * (rod.omega - slider.omega) - guide.friction * slider.vx)",
    )
    m.summary("peak_torque", "max(abs(motor.effort))")
    m.analysis("inverse", "inverse", drivers=["motor"], forces=["pump"], t_end=1.0, step=0.001)
    built = m.build().run("inverse")
    loaded = linkwork.load(EXAMPLES / "slider_crank_friction.yaml").run("inverse")
    assert built.columns == loaded.columns
    assert np.array_equal(built.values, loaded.values)
    assert built.summaries == loaded.summaries and len(built.summaries) == 5
    assert {"O.friction", "A.friction", "B.friction", "guide.friction"} <= set(built.columns)

    bad = linkwork.Mechanism()
    bad.body("wheel", mass=1, inertia=0.1, position=(0, 0))
    bad.revolute("O", "wheel", "ground", at=(0, 0), friction={"mu": -0.1, "radius": 0})
    with pytest.raises(linkwork.ModelError) as error:
        bad.build()
    problems = dict(error.value.problems)
    assert "coefficient of friction >= 0, found -0.1" in problems["joints.O.friction.mu"]
    assert "positive number, found 0" in problems["joints.O.friction.radius"]


def test_a_built_cam_runs_as_the_example() -> None:
    """examples/cam_roller.yaml built with the typed `cam` joint and `pressure_angle` measure:
    both analyses give the file's results, bit for bit; a radius naming anything but psi,
    parameters and tables is refused at its field."""
    m = linkwork.Mechanism("disc cam with a radial roller follower", gravity=(0, -9.81))
    m.parameter("base", "50 mm")
    m.parameter("lift", "20 mm")
    cam = m.body("cam", mass=1.2, inertia=0.002, position=(0, 0))
    follower = m.body("follower", mass=0.3, inertia=0.0001, position=(0, "base"))
    m.revolute("bearing", "ground", cam, at=(0, 0))
    m.translational("guide", "ground", follower, at=(0, "base"), axis=(0, 1))
    radius = "base + cycloidal(pi/2 - psi, 0, 0, 2*pi/3, lift) + cycloidal(pi/2 - psi, pi, lift, 3*pi/2, 0) - lift"
    m.cam("contact", cam, follower, point_j=(0, 0), radius=radius, roller_radius="10 mm")
    m.driver("motor", "angle", body=cam, function="2*pi*t")
    m.pressure_angle("pressure_angle", joint="contact")
    m.analysis("motion", "kinematic", drivers=["motor"], t_end=1.5, step="1/360")
    m.analysis("drive", "inverse", drivers=["motor"], t_end=1.5, step="1/360")
    assert m.to_dict()["measures"]["pressure_angle"] == {"type": "pressure_angle", "joint": "contact"}
    built, loaded = m.build(), linkwork.load(EXAMPLES / "cam_roller.yaml")
    assert built.analyses == loaded.analyses == ["motion", "drive"]
    for analysis in built.analyses:
        a, b = built.run(analysis), loaded.run(analysis)
        assert a.columns == b.columns and "pressure_angle" in a.columns
        assert np.array_equal(a.values, b.values) and np.array_equal(a.time, b.time), analysis

    bad = linkwork.Mechanism()
    bad.body("disc", mass=1, inertia=0.1, position=(0, 0))
    bad.body("roller", mass=1, inertia=0.1, position=(0, 0.05))
    bad.cam("contact", "disc", "roller", point_j=(0, 0), radius="0.05 + disc.phi")
    with pytest.raises(linkwork.ModelError) as error:
        bad.build()
    problems = dict(error.value.problems)
    assert "expected psi" in problems["joints.contact.radius"]


# The leg of crates/linkwork/tests/placement.rs, which checks it against the law of cosines.
LEG = (ROOT / "crates" / "linkwork" / "tests" / "models" / "jansen_leg.yaml").read_text()


def test_a_leg_placed_by_lengths_builds_as_its_file() -> None:
    """The Jansen-style leg of docs/model-format.md ("Points placed by lengths", and
    crates/linkwork/tests/placement.rs, which checks it against the law of cosines), its ternary
    links placed by lengths with `ByLengths` and another body's point by `"body.B"`: the model the
    file gives, its drawing and its run bit for bit."""
    m = linkwork.Mechanism()
    for name, value in [("a", "38 mm"), ("l", "7.8 mm"), ("m", "15 mm"), ("j", "50 mm"), ("b", "41.5 mm"),
                        ("c", "39.3 mm"), ("d", "40.1 mm"), ("ee", "55.8 mm"), ("f", "39.4 mm"), ("g", "36.7 mm"),
                        ("h", "65.7 mm"), ("i", "49 mm"), ("k", "61.9 mm")]:
        m.parameter(name, value)
    m.ground_point("O", (0, 0))
    m.ground_point("D", ("-a", "-l"))

    def by(b: str, c: str, d: str, e: str, side: str) -> linkwork.ByLengths:
        return {"from": (b, c), "distances": (d, e), "side": side}

    crank = m.body("crank", mass=0.1, inertia=1e-5, position="O", points_global={"O": "ground.O", "A": ("m", 0)})
    upper = m.body("upper", mass=0.2, inertia=1e-4, position="D", points_global={
        "D": "ground.D", "E": by("D", "crank.A", "b", "j", "left"), "F": by("D", "E", "d", "ee", "left")})
    leg = m.body("leg", mass=0.3, inertia=2e-4, position="H", points_global={
        "H": by("ground.D", "crank.A", "c", "k", "right"), "G": by("H", "upper.F", "i", "f", "left"),
        "P": by("H", "G", "h", "g", "left")})
    m.revolute("O", crank, "ground", point_i="O", point_j="O")
    m.revolute("D", upper, "ground", point_i="D", point_j="D")
    m.distance("link_j", crank, "A", upper, "E", length="j")
    m.distance("link_k", crank, "A", leg, "H", length="k")
    m.distance("link_c", "ground", "D", leg, "H", length="c")
    m.distance("link_f", upper, "F", leg, "G", length="f")
    m.driver("motor", "angle", body=crank, function="2*pi*t")
    m.analysis("kinematics", "kinematic", drivers=["motor"], t_end=1, step=0.01)
    built, loaded = m.build(), linkwork.from_yaml(LEG)
    assert built.drawing() == loaded.drawing()
    a, b = built.run(), loaded.run()
    assert a.columns == b.columns and np.array_equal(a.values, b.values)


def test_an_impossible_triangle_is_a_model_error_naming_the_lengths() -> None:
    m = linkwork.Mechanism()
    m.body("foot", mass=1, inertia=0.1, position=(0, 0), points={
        "A": (0, 0), "B": (0.1, 0), "G": {"from": ("A", "B"), "distances": (0.03, "50 mm"), "side": "left"}})
    with pytest.raises(linkwork.ModelError) as error:
        m.build()
    assert error.value.problems == [(
        "bodies.foot.points.G.distances",
        "no triangle has the sides d = 0.03 m (to A), e = 0.05 m (to B) and |A B| = 0.1 m: d + e = 0.08 m is "
        "less than |A B|, so the two links cannot meet",
    )]


def test_the_six_bar_leg_built_with_its_branches_paths_and_units_runs_as_its_file() -> None:
    """examples/sixbar_leg.yaml built in Python: its declared branches, paths and display units
    give the same run, summary branches and drawing as the file; a guess drawn on the other side
    of the foot's dyad is assembled on the declared side with the file's warning."""

    def leg(link_angle: str, foot_angle: str) -> linkwork.Mechanism:
        m = linkwork.Mechanism("six-bar leg")
        for name, value in [("r", "15 mm"), ("ab", "50 mm"), ("bq", "40 mm"), ("ac", "35 mm"), ("bc", "30 mm"),
                            ("cf", "40 mm"), ("fd", "37 mm"), ("fg", "40 mm"), ("dg", "55 mm"), ("speed", "60 rpm")]:
            m.parameter(name, value)
        m.ground_point("O", (0, 0))
        m.ground_point("Q", ("45 mm", 0))
        m.ground_point("D", ("10 mm", "-55 mm"))
        crank = m.body("crank", mass=0.05, inertia=1e-6, position=("r/2", 0), angle=0, points={"O": ("-r/2", 0), "A": ("r/2", 0)})
        coupler = m.body("coupler", mass=0.1, inertia=2e-5, position=("15 mm", 0), angle="53 deg", points={
            "A": (0, 0), "B": ("ab", 0), "C": {"from": ("A", "B"), "distances": ("ac", "bc"), "side": "right"}})
        rocker = m.body("rocker", mass=0.05, inertia=1e-5, position=("45 mm", 0), angle="90 deg", points={"Q": (0, 0), "B": ("bq", 0)})
        linkf = m.body("linkf", mass=0.05, inertia=1e-5, position=("48.5 mm", "10.2 mm"), angle=link_angle,
                       points={"C": (0, 0), "F": ("cf", 0)})
        foot = m.body("foot", mass=0.1, inertia=2e-5, position=("10 mm", "-55 mm"), angle=foot_angle, points={
            "D": (0, 0), "F": ("fd", 0), "G": {"from": ("F", "D"), "distances": ("fg", "dg"), "side": "right"}})
        for name, (bi, pi), (bj, pj) in [("O", (crank, "O"), ("ground", "O")), ("A", (crank, "A"), (coupler, "A")),
                                         ("B", (coupler, "B"), (rocker, "B")), ("Q", (rocker, "Q"), ("ground", "Q")),
                                         ("C", (coupler, "C"), (linkf, "C")), ("F", (linkf, "F"), (foot, "F")),
                                         ("D", (foot, "D"), ("ground", "D"))]:
            m.revolute(name, bi, bj, point_i=pi, point_j=pj)
        m.branch("B", ("A", "Q"), "left")
        m.branch("F", ("C", "D"), "right")
        m.driver("motor", "angle", body=crank, function="speed*t")
        m.paths("foot.G", "coupler.C")
        m.display(length="mm", angle="deg")
        m.measure("foot_x", body=foot, point="G", component="x")
        m.measure("foot_y", body=foot, point="G", component="y")
        m.analysis("kinematics", "kinematic", drivers=["motor"], t_end="2*pi/speed", step="10 ms")
        return m

    built, loaded = leg("-130 deg", "70 deg").build(), linkwork.load(EXAMPLES / "sixbar_leg.yaml")
    assert built.drawing() == loaded.drawing()
    a, b = built.run(), loaded.run()
    assert a.columns == b.columns and np.array_equal(a.values, b.values)
    assert a.summary.branches == b.summary.branches and not a.summary.warnings
    # Drawn on the other side of C -> D: the declared side, the same foot path, and the warning.
    wrong = leg("-110.5 deg", "48.5 deg").build().run()
    assert np.max(np.abs(wrong["foot_x"] - b["foot_x"])) < 1e-11
    assert any(w.startswith("branches.F: the drawing puts joint F left of the line C -> D") for w in wrong.summary.warnings)
