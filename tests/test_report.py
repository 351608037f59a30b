"""The report in a real browser: every analysis of every example writes a `report.html` that opens
offline in headless Chromium (Debian's, driven by Playwright), makes no network request, logs no
console error, has data in every plot and an animation that moves.

The browser is Debian's `chromium` (`.ci/run` installs it). Where it is missing these tests skip,
unless `LINKWORK_BROWSER_TESTS=required` (set by `.ci/run`), where they fail instead.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import linkwork
from linkwork import figures

from conftest import EXAMPLES, RunLinkwork

REQUIRED = os.environ.get("LINKWORK_BROWSER_TESTS") == "required"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")

EXAMPLE_RUNS = [
    pytest.param(path, name, id=f"{path.stem}-{name}")
    for path in sorted(EXAMPLES.glob("*.yaml"))
    for name in linkwork.load(path).analyses
]

# Plots with data per report, at least: the quick-return's kinematics has four (positions,
# velocities, accelerations and more), and every analysis type must show as many.
MIN_PLOTS = 4


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Headless Chromium, once for the module."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        if REQUIRED:
            raise
        pytest.skip("playwright is not installed (pip install '.[test]')")
    if CHROMIUM is None:
        if REQUIRED:
            pytest.fail("no chromium on PATH (apt-get install chromium)")
        pytest.skip("no chromium on PATH (apt-get install chromium)")
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield chromium
        chromium.close()


def open_report(browser: Any, path: Path) -> tuple[Any, list[str], list[str]]:
    """Open `path`; return the page once its plots are drawn, every URL it requested and every
    console error or page error."""
    page = browser.new_page(viewport={"width": 1300, "height": 900})
    requests: list[str] = []
    errors: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.on("console", lambda m: errors.append(m.text) if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    page.wait_for_selector("body[data-ready=true]", timeout=60_000)
    return page, requests, errors


def points_per_plot(page: Any) -> dict[str, int]:
    """For every plot on the page, the number of finite values it draws."""
    counts: dict[str, int] = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('.js-plotly-plot')].map(div => [div.id,
            div.data.reduce((n, t) => n + (t.y || []).filter(v => v !== null && Number.isFinite(v)).length, 0)]))"""
    )
    return counts


def mechanism_x(page: Any, div: str = "mechanism") -> list[Any]:
    """The x values of every trace drawn in the mechanism's plot now."""
    values: list[Any] = page.evaluate(f"() => document.getElementById('{div}').data.map(t => t.x)")
    return values


@pytest.mark.parametrize(("path", "analysis"), EXAMPLE_RUNS)
def test_every_example_report_opens_offline_with_plots_and_a_moving_mechanism(
    path: Path, analysis: str, tmp_path: Path, browser: Any
) -> None:
    model = linkwork.load(path)
    try:
        results = model.run(analysis)
    except (linkwork.SolverError, linkwork.AssemblyError) as error:  # the lock-up example fails by design
        assert isinstance(error.results, linkwork.Results)
        results = error.results
    results.write(tmp_path)
    page, requests, errors = open_report(browser, tmp_path / "report.html")
    try:
        assert requests == [(tmp_path / "report.html").as_uri()], "the page asked for more than itself"
        assert errors == []
        counts = points_per_plot(page)
        plots = {k: n for k, n in counts.items() if k.startswith("plot")}
        # Torques that are all zero (a mechanism of pins) have no plot: one fewer for a static
        # analysis, whose other plots are its coordinates, energy, forces and efforts.
        torques = [c for c in results.columns if c.endswith(".torque")]
        no_torque_plot = bool(torques) and not any(np.any(results[c]) for c in torques)
        assert len(plots) >= MIN_PLOTS - no_torque_plot, counts
        assert all(n > 0 for n in plots.values()), counts
        drawn = [k for k in counts if k == "mechanism" or k.startswith("mode")]
        assert drawn, "no mechanism drawn"
        # A mode moves through its period; a run through its rows (a static equilibrium at one
        # time is one pose).
        animated = [k for k in drawn if k.startswith("mode") or len(results) > 1]
        for div in animated:
            frames = page.evaluate(f"() => document.getElementById('{div}')._transitionData._frames.length")
            assert frames > 1, f"{div}: a single frame does not move"
            before = mechanism_x(page, div)
            # Move the time slider to 37 % of the way, through its own method, as a drag would (not
            # to the end or the middle: a crank turning whole turns is back where it started).
            page.evaluate(
                f"""() => {{ const d = document.getElementById('{div}'); const steps = d.layout.sliders[0].steps;
                    const step = steps[Math.floor(0.37 * steps.length)];
                    return Plotly.animate(d, step.args[0], step.args[1]); }}"""
            )
            assert mechanism_x(page, div) != before, f"{div}: a frame within draws the first one's pose"
        if "mechanism" in counts and len(results) > 1:
            # Played, the animation moves on by itself, and the plots' time line follows.
            page.evaluate("() => Plotly.animate('mechanism', ['0'], {mode: 'immediate', frame: {duration: 0}})")
            start = mechanism_x(page)
            page.get_by_text("▶ play").click()
            page.wait_for_timeout(400)
            assert mechanism_x(page) != start, "play did not move the mechanism"
            line = page.evaluate("() => document.getElementById('plot0').layout.shapes[0].x0")
            assert line > results.time[0]
        page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
    finally:
        page.close()


def test_the_report_marks_a_failed_run_and_draws_its_partial_results(tmp_path: Path, browser: Any) -> None:
    model = linkwork.load(EXAMPLES / "slider_crank_lockup.yaml")
    with pytest.raises(linkwork.SolverError) as caught:
        model.run()
    partial = caught.value.results
    assert isinstance(partial, linkwork.Results) and len(partial) > 1
    partial.write(tmp_path)
    page, _, errors = open_report(browser, tmp_path / "report.html")
    try:
        assert errors == []
        failure = page.inner_text(".failure")
        assert "partial results" in failure and f"{partial.summary['error_time']:.9g}" in failure
    finally:
        page.close()


def test_run_writes_the_report_and_the_model_and_report_rebuilds_it(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = tmp_path / "qr"
    done = linkwork("run", EXAMPLES / "quick_return_a.yaml", "--out", out)
    assert done.code == 0, done.output
    assert "report.html" in done.stdout
    assert (out / "model.yaml").read_text() == (EXAMPLES / "quick_return_a.yaml").read_text()
    first = (out / "report.html").read_bytes()
    (out / "report.html").unlink()
    rebuilt = linkwork("report", out)
    assert rebuilt.code == 0, rebuilt.output
    # The files hold every number exactly (shortest round-trip form), so the page is the same.
    assert (out / "report.html").read_bytes() == first


def test_no_report_skips_the_page(linkwork: RunLinkwork, tmp_path: Path) -> None:
    out = tmp_path / "qr"
    done = linkwork("run", EXAMPLES / "quick_return_a.yaml", "--out", out, "--no-report")
    assert done.code == 0, done.output
    assert not (out / "report.html").exists()
    assert (out / "model.yaml").exists()


def test_report_of_a_folder_that_is_not_a_run_names_the_folder(linkwork: RunLinkwork, tmp_path: Path) -> None:
    done = linkwork("report", tmp_path)
    assert done.code == 2
    assert str(tmp_path) in done.output and "not a results folder" in done.output


def test_the_report_decimates_what_it_draws_but_keeps_every_peak() -> None:
    """A long run draws at most MAX_FRAMES frames and MAX_PLOT_POINTS points a curve, and the
    largest and smallest values survive the decimation."""
    n = 100_001
    t = np.linspace(0.0, 10.0, n)
    y = np.sin(7 * t)
    y[12_345] = 5.0
    y[67_891] = -4.0
    rows = figures._plot_rows(y)
    assert len(rows) <= figures.MAX_PLOT_POINTS + 2
    assert {12_345, 67_891, 0, n - 1} <= set(rows.tolist())
    assert len(figures._frame_rows(n)) == figures.MAX_FRAMES


def test_results_plot_and_animate_give_figures() -> None:
    go = pytest.importorskip("plotly.graph_objects")
    results = linkwork.load(EXAMPLES / "quick_return_a.yaml").run()
    fig = results.plot("rocker.phi", "crank.phi")
    assert isinstance(fig, go.Figure)
    assert [t.name for t in fig.data] == ["rocker.phi", "crank.phi"]
    assert list(fig.data[0].y) == pytest.approx(results["rocker.phi"].tolist(), rel=1e-5)
    with pytest.raises(KeyError, match="no column 'nope'"):
        results.plot("nope")
    movie = results.animate()
    assert len(movie.frames) == len(results)
    assert "quick-return" in results._repr_html_()


def fourbar_coupler_point(theta2: np.ndarray, branch: float) -> tuple[np.ndarray, np.ndarray]:
    """The coupler point P of examples/fourbar.yaml in closed form, from the crank's angle: A on
    the crank's circle, B where the coupler's circle about A meets the rocker's about O4 (on the
    side ``branch`` of the line A -> O4, +1 left), P at (0.2, 0.1) from A along and across AB."""
    a, b, c, d = 0.1, 0.3, 0.25, 0.3
    ax, ay = a * np.cos(theta2), a * np.sin(theta2)
    ex, ey = d - ax, -ay
    e = np.hypot(ex, ey)
    along = (b**2 - c**2 + e**2) / (2 * e)
    across = branch * np.sqrt(b**2 - along**2)
    bx, by = ax + (along * ex - across * ey) / e, ay + (along * ey + across * ex) / e
    ux, uy = (bx - ax) / b, (by - ay) / b
    return ax + 0.2 * ux - 0.1 * uy, ay + 0.2 * uy + 0.1 * ux


def test_results_path_is_the_coupler_curve_and_plot_draws_any_column_against_another() -> None:
    go = pytest.importorskip("plotly.graph_objects")
    model = linkwork.load(EXAMPLES / "fourbar.yaml")
    results = model.run()
    x, y = results.path("coupler.P")
    assert np.array_equal(np.stack(results.path("coupler", "P")), np.stack((x, y)))
    # The coupler sits left of A -> O4 (above the ground link) as drawn; the kinematic solver
    # stops at 1e-12 m, 1e-9 leaves three orders for the Jacobian's amplification, and a wrong
    # point, frame or branch is off by centimetres.
    cx, cy = fourbar_coupler_point(results["crank.phi"], +1.0)
    assert np.max(np.hypot(x - cx, y - cy)) < 1e-9
    assert np.array_equal(np.stack(results.path("coupler")), np.stack((results["coupler.x"], results["coupler.y"])))

    fig = results.plot(x="coupler.P.x", y="coupler.P.y")
    assert isinstance(fig, go.Figure)
    assert fig.layout.yaxis.scaleanchor == "x", "a path is drawn on equal axes"
    # The figure's numbers are rounded to figures.DIGITS = 6 significant digits.
    assert list(fig.data[0].x) == pytest.approx(x.tolist(), rel=1e-5)
    assert list(fig.data[0].y) == pytest.approx(y.tolist(), rel=1e-5)
    body = results.plot(x="coupler.x", y="coupler.y")
    assert body.layout.yaxis.scaleanchor == "x" and list(body.data[0].y) == pytest.approx(results["coupler.y"].tolist(), rel=1e-5)
    against = results.plot(x="crank.phi", y=["rocker.omega", "coupler.omega"])
    assert against.layout.xaxis.title.text == "crank.phi (rad)" and against.layout.yaxis.scaleanchor is None
    assert [t.name for t in against.data] == ["rocker.omega", "coupler.omega"]
    assert list(against.data[0].x) == pytest.approx(results["crank.phi"].tolist(), rel=1e-5)
    with pytest.raises(TypeError, match="not both"):
        results.plot("rocker.phi", y="crank.phi")
    with pytest.raises(KeyError, match="no point 'Q' of body 'coupler'; there are A, B, P"):
        results.path("coupler.Q")
    with pytest.raises(KeyError, match="no moving body 'ground'"):
        results.path("ground.O2")
    with pytest.raises(KeyError, match="did you mean 'rocker.phi'"):
        results.plot(x="rocker.ph")


def test_an_unknown_column_names_the_closest() -> None:
    results = linkwork.load(EXAMPLES / "fourbar.yaml").run()
    with pytest.raises(KeyError, match="no column 'rocker.omga'; did you mean 'rocker.omega'"):
        results["rocker.omga"]
    # Nothing close: every column is named.
    with pytest.raises(KeyError, match="no column 'nope'; there are time, crank.x"):
        results["nope"]


def test_the_report_draws_the_named_paths_and_plots_against_the_crank_angle(tmp_path: Path, browser: Any) -> None:
    results = linkwork.load(EXAMPLES / "fourbar.yaml").run()
    results.write(tmp_path)
    page, _, errors = open_report(browser, tmp_path / "report.html")
    try:
        assert errors == []
        mechanism = page.evaluate("() => document.getElementById('mechanism').data.map(t => [t.name, t.line && t.line.dash])")
        assert ["coupler.P path", None] in mechanism, "the named path is drawn solid"
        assert not any(dash == "dot" for _, dash in mechanism), "no faint trail beside the named path"
        # The paths panel: the path, then the point's place now, which follows the slider.
        traces = page.evaluate("() => document.getElementById('paths').data.map(t => [t.name, t.x, t.y])")
        assert [t[0] for t in traces] == ["coupler.P", "now"]
        x, y = results.path("coupler.P")
        assert traces[1][1][0] == pytest.approx(x[0], rel=1e-5) and traces[1][2][0] == pytest.approx(y[0], rel=1e-5)
        frame = page.evaluate(
            """() => { const d = document.getElementById('mechanism'); const steps = d.layout.sliders[0].steps;
                const k = Math.floor(0.37 * steps.length); const step = steps[k];
                return Plotly.animate(d, step.args[0], step.args[1]).then(() => Number(step.args[0][0])); }"""
        )
        page.wait_for_timeout(200)
        row = int(figures._frame_rows(len(results))[frame])
        moved = page.evaluate("() => { const t = document.getElementById('paths').data[1]; return [t.x[0], t.y[0]]; }")
        assert moved == pytest.approx([x[row], y[row]], rel=1e-5)
        # Against the crank's angle: the x of every curve is crank.phi at its rows, and the time
        # line moves to the crank's angle now; back to time, the curves' x is time again.
        time_x = page.evaluate("() => document.getElementById('plot0').data[0].x")
        page.check("input[value=driver]")
        page.wait_for_timeout(200)
        plot = page.evaluate("() => { const d = document.getElementById('plot0'); return [d.data[0].x, d.data[0].customdata, d.layout.xaxis.title.text, d.layout.shapes[0].x0]; }")
        phi = np.interp(plot[1], results.time, results["crank.phi"])
        assert plot[0] == pytest.approx(phi.tolist(), rel=1e-5, abs=1e-9)
        assert plot[2] == "angle of crank (rad), driver motor"
        assert plot[3] == pytest.approx(results["crank.phi"][row], rel=1e-5)
        page.check("input[value=time]")
        page.wait_for_timeout(200)
        assert page.evaluate("() => document.getElementById('plot0').data[0].x") == time_x
        page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
    finally:
        page.close()


def test_the_report_draws_the_sensitivity_panel_scaled_by_tolerance_or_size(linkwork: RunLinkwork, tmp_path: Path, browser: Any) -> None:
    """`linkwork run --sensitivities all` on the slider-crank: the stroke (2 r) has one bar a
    parameter, largest first; r's is 2 times its tolerance (0.1 mm), L's 0 times its (the stroke
    does not depend on L), the speed's 0 times its value."""
    out = linkwork("run", EXAMPLES / "slider_crank_param.yaml", "--sensitivities", "all", "--out", "s")
    assert out.code == 0, out.output
    page, _, errors = open_report(browser, tmp_path / "s" / "report.html")
    try:
        assert errors == []
        bars = page.evaluate("() => document.getElementById('sensitivity0').data[0]")
        assert bars["y"][0].startswith("r (× tolerance 0.0001)") and bars["x"][0] == pytest.approx(2e-4, rel=1e-9)
        assert [abs(v) for v in bars["x"]] == sorted((abs(v) for v in bars["x"]), reverse=True)
        assert any(label.startswith("speed (× value") for label in bars["y"])
        # Drawn, not only given: one bar a parameter, each labelled on the axis.
        assert page.locator("#sensitivity0 .trace.bars .point").count() == len(bars["y"])
        ticks = page.locator("#sensitivity0 .ytick text").all_text_contents()
        assert sorted(ticks) == sorted(bars["y"])
        # Each label whole inside the figure (the margin holds it).
        left = page.evaluate("() => document.getElementById('sensitivity0').getBoundingClientRect().left")
        assert min(box["x"] for box in (t.bounding_box() for t in page.locator("#sensitivity0 .ytick text").all()) if box) >= left
    finally:
        page.close()
    # A summary no parameter moves (a pin's reaction torque, zero by construction) is named in a
    # line, not drawn as an empty chart; the others are drawn.
    out = linkwork("run", EXAMPLES / "quick_return_a.yaml", "--analysis", "inverse", "--sensitivities", "crank", "--out", "q")
    assert out.code == 0, out.output
    page, _, errors = open_report(browser, tmp_path / "q" / "report.html")
    try:
        assert errors == []
        line = page.locator("#constant-summaries").text_content() or ""
        assert "A.torque" in line and "A.force" not in line
        titles = page.evaluate("() => [...document.querySelectorAll('[id^=sensitivity]')].filter(e => e.data)"
                               ".map(e => e.layout.title.text)")
        assert "A.force" in titles and "A.torque" not in titles
    finally:
        page.close()
    # Without sensitivities there is no panel.
    assert linkwork("run", EXAMPLES / "slider_crank_param.yaml", "--out", "n").code == 0
    assert 'id="sensitivity0"' not in (tmp_path / "n" / "report.html").read_text()


def test_the_tolerance_report_draws_the_histogram_and_the_shares(linkwork: RunLinkwork, tmp_path: Path, browser: Any) -> None:
    out = linkwork("tolerance", EXAMPLES / "slider_crank_param.yaml", "--output", "stroke=stroke", "--samples", "200",
                   "--seed", "1", "--out", "t")
    assert out.code == 0, out.output
    page, requests, errors = open_report(browser, tmp_path / "t" / "report.html")
    try:
        assert errors == [] and all(r.startswith("file:") for r in requests)
        histogram = page.evaluate("() => document.getElementById('figure0').data.map(t => [t.type, (t.x || []).length])")
        assert histogram == [["histogram", 200], ["scatter", 200]]
        shares = page.evaluate("() => document.getElementById('figure1').data[0]")
        assert shares["x"][0] == "r" and shares["y"][0] == pytest.approx(100.0, rel=1e-9)
    finally:
        page.close()


def test_the_report_leaves_out_zero_torques_and_names_constant_columns(tmp_path: Path, browser: Any) -> None:
    results = linkwork.load(EXAMPLES / "fourbar_measures.yaml").run()
    assert np.all(results["O2.torque"] == 0.0), "a pin's reaction torque, the case left out"
    results.write(tmp_path)
    page, _, errors = open_report(browser, tmp_path / "report.html")
    try:
        assert errors == []
        names = page.evaluate("() => [...document.querySelectorAll('.js-plotly-plot')].flatMap(d => d.data.map(t => t.name))")
        assert not any(str(n).endswith(".torque") for n in names), names
        assert ".torque" not in page.inner_text("table:last-of-type")
        # crank.omega is 2 rad/s throughout: named under the title, not in the legend.
        notes = page.evaluate(
            "() => [...document.querySelectorAll('.plots .js-plotly-plot')].map(d => (d.layout.title.subtitle || {}).text)"
        )
        assert any("constant: crank.omega = 2" in str(t) for t in notes), notes
        # The title stays clear of the toolbar (plotly's modebar, top right), here and in every plot.
        for k in range(len(notes)):
            page.hover(f"#plot{k}")
            title, bar = (page.locator(f"#plot{k} {s}").bounding_box() for s in (".gtitle", ".modebar"))
            assert title is not None and bar is not None
            assert title["x"] + title["width"] < bar["x"] or title["y"] + title["height"] < bar["y"], k
        assert "crank.omega" not in names
    finally:
        page.close()


def test_model_draw_shows_the_assembled_pose_and_the_guess() -> None:
    model = linkwork.load(EXAMPLES / "quick_return_a.yaml")
    fig = model.draw()
    names = [t.name for t in fig.data]
    assert "crank (assembled)" in names and "crank (initial guess)" in names
    guess = next(t for t in fig.data if t.name == "crank (initial guess)")
    assert guess.opacity == pytest.approx(0.3)


def test_drawing_places_every_joint_on_its_bodies() -> None:
    """The drawing's joint points, put in place with the assembled coordinates, coincide for a pin
    and sit on the guide for a slide: the same geometry as the constraint equations."""
    model = linkwork.load(EXAMPLES / "quick_return_a.yaml")
    results = model.run()
    run = results._run()
    poses = figures._Poses(run, np.arange(len(results)))
    for joint in model.drawing()["joints"]:
        px, py = poses.point(joint["body_i"], joint["p"])
        qx, qy = poses.point(joint["body_j"], joint["q"])
        # The kinematic solver stops at 1e-12 m; 1e-9 leaves three orders for the Jacobian's
        # amplification, and a wrong point (a swapped body, a frame not applied) is off by metres.
        if joint["shape"] == "pin":
            assert np.max(np.hypot(qx - px, qy - py)) < 1e-9, joint["name"]
        elif joint["shape"] == "slide":
            ux, uy = poses.direction(joint["body_i"], joint["axis"])
            normal = -(qx - px) * uy + (qy - py) * ux
            assert np.max(np.abs(normal - joint["offset"])) < 1e-9, joint["name"]

