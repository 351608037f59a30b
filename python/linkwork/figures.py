"""The figures of a run: the animated mechanism, the paths of its points, plots of its columns
and of its modes, as plain plotly dicts (``{"data": [...], "layout": {...}, "frames": [...]}``).

They are built here without plotly's Python validation, so that the report's page
(:mod:`linkwork.page`) embeds them as JSON and :meth:`linkwork.Results.plot` and
:meth:`linkwork.Results.animate` hand the same figures to ``plotly.graph_objects.Figure``. What
is drawn is decimated so that a figure stays light on long runs (:data:`MAX_FRAMES`,
:data:`MAX_PLOT_POINTS`); the data files are never decimated.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _linkwork
from .summary import Summary
from .units import UNKNOWN, Units

#: Animation frames drawn at most: 30 frames a second for 10 s of playback. Each frame carries every
#: moving trace, so the page grows with the frames; more than a few hundred only make the slider
#: finer than a pointer can set.
MAX_FRAMES = 300

#: Points drawn per curve at most: the minimum and the maximum of each of 1000 buckets, so that
#: every peak of a long run stays visible on a plot a screen wide (1000 to 2000 pixels).
MAX_PLOT_POINTS = 2000

#: Curves a plot draws at most: a legend of more cannot be read, and a model of 100 bodies would
#: otherwise draw 900 curves of positions; every column is in ``results.csv``.
MAX_CURVES = 12

#: Points of each path of a named point: a smooth curve at any zoom a screen allows.
MAX_PATH_POINTS = 1000

#: Constant columns a plot names under its title, at most: two lines of a plot's width.
MAX_CONSTANTS = 4

#: Significant digits of the numbers drawn: a hundredth of a pixel on a 4000-pixel-wide plot.
DIGITS = 6

# Colours: one per body (plotly's default qualitative palette), then the fixed parts.
PALETTE = ("#636efa", "#ef553b", "#00cc96", "#ab63fa", "#ffa15a", "#19d3f3", "#ff6692", "#b6e880", "#ff97ff", "#fecb52")
GROUND = "#555555"
INK = "#222222"

#: The columns of each body, in the order of ``results.csv`` (the engine's).
BODY_QUANTITIES = tuple(_linkwork.BODY_QUANTITIES)

#: The columns an analysis adds that belong to no body, joint or driver (the engine's).
ENGINE_COLUMNS = tuple(_linkwork.ENGINE_COLUMNS)


@dataclass(frozen=True)
class Run:
    """What a report is made of: the model's drawing, the result columns and the summary."""

    drawing: Mapping[str, Any]
    time: np.ndarray
    columns: Mapping[str, np.ndarray]
    summary: Summary
    title: str = ""
    #: The units the report shows (the model's ``display:`` section), for its axes and tables.
    units: Units = field(default_factory=Units.si)
    #: The tolerance of each parameter that has one, SI (``Model.tolerances``): what the
    #: sensitivity panel scales a derivative by.
    tolerances: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # An analysis that keeps only some columns (`outputs:`) draws the bodies whose
        # positions it kept, and the joints between them and the ground.
        kept = {
            b["name"] for b in self.drawing["bodies"] if all(f"{b['name']}.{c}" in self.columns for c in ("x", "y", "phi"))
        }
        if len(kept) < len(self.drawing["bodies"]):
            on = kept | {"ground"}
            drawing = {
                **self.drawing,
                "bodies": [b for b in self.drawing["bodies"] if b["name"] in kept],
                "joints": [j for j in self.drawing["joints"] if j["body_i"] in on and j["body_j"] in on],
            }
            object.__setattr__(self, "drawing", drawing)


# --- numbers -------------------------------------------------------------------------------------


def _text(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ", ".join(_text(x) for x in v) if v else "none"
    if isinstance(v, dict):
        return "; ".join(f"{k}: {_text(x)}" for k, x in v.items()) if v else "none"
    return "none" if v is None else str(v)


def _num(values: Any) -> list[float | None]:
    """Values rounded to :data:`DIGITS` significant digits, non-finite ones as gaps (``None``)."""
    out: list[float | None] = []
    for v in np.asarray(values, dtype=float).ravel():
        out.append(float(f"{v:.{DIGITS}g}") if math.isfinite(v) else None)
    return out


def _frame_rows(n: int) -> np.ndarray:
    """At most :data:`MAX_FRAMES` row indices, evenly spread, the first and last included."""
    if n <= MAX_FRAMES:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, MAX_FRAMES).round().astype(int))


def _plot_rows(y: np.ndarray) -> np.ndarray:
    """Rows to draw of the curve ``y``: all of them when few, else the minimum and maximum of each
    of ``MAX_PLOT_POINTS / 2`` buckets (in time order), the first and last rows included."""
    n = len(y)
    if n <= MAX_PLOT_POINTS:
        return np.arange(n)
    edges = np.linspace(0, n, MAX_PLOT_POINTS // 2 + 1).astype(int)
    keep = {0, n - 1}
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b > a:
            chunk = np.where(np.isfinite(y[a:b]), y[a:b], 0.0)
            keep.update((a + int(np.argmin(chunk)), a + int(np.argmax(chunk))))
    return np.array(sorted(keep))


# --- the mechanism -------------------------------------------------------------------------------


def _hull(points: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The convex hull, counter-clockwise (Andrew's monotone chain), of distinct points."""
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    upper: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


class _Poses:
    """Global positions of body points over the frames drawn."""

    def __init__(self, run: Run, rows: np.ndarray) -> None:
        self.rows = rows
        self.frame = {}
        for body in run.drawing["bodies"]:
            name = body["name"]
            x, y, phi = (np.asarray(run.columns[f"{name}.{c}"], dtype=float)[rows] for c in ("x", "y", "phi"))
            self.frame[name] = (x, y, np.cos(phi), np.sin(phi))

    def point(self, body: str, s: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """(frames) global x and y of the point ``s`` of ``body`` (``s`` itself on ground)."""
        if body == "ground":
            k = len(self.rows)
            return np.full(k, float(s[0])), np.full(k, float(s[1]))
        x, y, c, sn = self.frame[body]
        return x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]

    def direction(self, body: str, v: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """(frames) the body-frame direction ``v`` in the global frame."""
        if body == "ground":
            k = len(self.rows)
            return np.full(k, float(v[0])), np.full(k, float(v[1]))
        _, _, c, sn = self.frame[body]
        return c * v[0] - sn * v[1], sn * v[0] + c * v[1]


class _Paths:
    """One line trace made of many pieces (separated by gaps), each piece a few points that move
    from frame to frame."""

    def __init__(self) -> None:
        self.pieces: list[tuple[np.ndarray, np.ndarray]] = []  # each (points x frames) x and y
        self.text: list[str] = []

    def add(self, xs: Sequence[np.ndarray], ys: Sequence[np.ndarray], label: str = "") -> None:
        """A piece through the points ``(xs[k], ys[k])``, each ``(frames)``."""
        self.pieces.append((np.array(xs, dtype=float), np.array(ys, dtype=float)))
        self.text.extend([label] * (len(xs) + 1))

    def __bool__(self) -> bool:
        return bool(self.pieces)

    def at(self, f: int) -> tuple[list[float | None], list[float | None]]:
        """The trace's x and y at frame ``f``, the pieces separated by gaps."""
        x: list[float | None] = []
        y: list[float | None] = []
        for px, py in self.pieces:
            x += [*_num(px[:, f]), None]
            y += [*_num(py[:, f]), None]
        return x, y


def _faded(colour: str) -> str:
    """``#rrggbb`` as a third-opaque ``rgba(...)``: a body's fill under its outline."""
    r, g, b = (int(colour[k : k + 2], 16) for k in (1, 3, 5))
    return f"rgba({r},{g},{b},0.33)"


def _circle(
    cx: np.ndarray, cy: np.ndarray, r: float, turn: tuple[np.ndarray, np.ndarray], sides: int = 36
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Points of a circle of radius ``r`` about ``(cx, cy)`` (each ``(frames)``), then a spoke to
    ``turn`` (the direction of angle 0 of the body it turns with), so that rotation shows."""
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    for k in range(sides + 1):
        a = 2 * math.pi * k / sides
        xs.append(cx + r * math.cos(a))
        ys.append(cy + r * math.sin(a))
    xs += [cx, cx + r * turn[0]]
    ys += [cy, cy + r * turn[1]]
    return xs, ys


def _path_rows(n: int) -> np.ndarray:
    """At most :data:`MAX_PATH_POINTS` of ``n`` rows, evenly spread, the first and last included."""
    return np.unique(np.linspace(0, n - 1, min(n, MAX_PATH_POINTS)).round().astype(int))


def named_paths(run: Run, rows: np.ndarray) -> list[tuple[str, int, np.ndarray, np.ndarray]]:
    """The paths the model names (``Model.drawing()["paths"]``) whose bodies the run kept: each
    ``(name, body's colour index, x, y)`` over ``rows``."""
    index = {b["name"]: k for k, b in enumerate(run.drawing["bodies"])}
    poses = _Poses(run, rows)
    return [(p["name"], index[p["body"]], *poses.point(p["body"], p["point"]))
            for p in run.drawing["paths"] if p["body"] in index]


def paths_figure(run: Run) -> dict[str, Any] | None:
    """The paths the model names, solid, on equal axes, with each point's place at the
    mechanism's frames in ``marks`` (the page moves the last trace's markers there); ``None``
    when the model names none."""
    frames = _frame_rows(len(run.time))
    # In the display's length unit, as the mechanism's own axes are.
    k, unit = run.units.value("length", 1.0), run.units.unit("length")
    now = [(name, b, np.asarray(x) * k, np.asarray(y) * k) for name, b, x, y in named_paths(run, frames)]
    if not now:
        return None
    data: list[dict[str, Any]] = [
        {"type": "scatter", "mode": "lines", "name": name, "x": _num(np.asarray(x) * k), "y": _num(np.asarray(y) * k),
         "line": {"color": PALETTE[b % len(PALETTE)], "width": 2}}
        for name, b, x, y in named_paths(run, _path_rows(len(run.time)))
    ]
    data.append({"type": "scatter", "mode": "markers", "name": "now", "text": [p[0] for p in now], "hoverinfo": "text",
                 "x": _num([x[0] for _, _, x, _ in now]), "y": _num([y[0] for _, _, _, y in now]),
                 "marker": {"symbol": "circle", "size": 10, "color": [PALETTE[b % len(PALETTE)] for _, b, _, _ in now],
                            "line": {"color": INK, "width": 1.5}}, "showlegend": False})
    layout = _plot_layout("paths of the named points", f"x ({unit})", f"y ({unit})")
    layout["xaxis"].update(constrain="domain", zeroline=False)
    layout["yaxis"].update(scaleanchor="x", scaleratio=1, constrain="domain", zeroline=False)
    layout["height"] = 520
    marks = {"x": [_num([x[f] for _, _, x, _ in now]) for f in range(len(frames))],
             "y": [_num([y[f] for _, _, _, y in now]) for f in range(len(frames))]}
    return {"data": data, "layout": layout, "marks": marks}


def driver_coordinate(run: Run) -> tuple[str, np.ndarray] | None:
    """The coordinate of the first of the analysis' active drivers that moves (a crank's angle),
    with its label, at every row: what the plots are also drawn against. ``None`` when no active
    driver moves (a dynamic analysis, a driver holding a coordinate fixed) or the analysis' outputs
    left its bodies out."""
    if len(run.time) < 2:
        return None
    kept = {b["name"] for b in run.drawing["bodies"]}
    poses = _Poses(run, np.arange(len(run.time)))

    def angle(body: str) -> np.ndarray:
        return np.asarray(run.columns[f"{body}.phi"], dtype=float) if body in kept else np.zeros(len(run.time))

    for d in run.drawing["drivers"]:
        kind, bi, bj = d["type"], d["body_i"], d["body_j"]
        if d["name"] not in (run.summary.active_drivers or []) or not {bi, bj} <= kept | {"ground"}:
            continue
        units = run.units
        if kind in ("angle", "relative_angle"):
            value = (angle(bi) - angle(bj)) * units.value("angle", 1.0)
            label = f"angle of {bi}" + (f" relative to {bj}" if kind == "relative_angle" else "") + f" ({units.unit('angle')})"
        elif kind == "distance":
            (px, py), (qx, qy) = poses.point(bi, d["p"]), poses.point(bj, d["q"])
            value = np.hypot(qx - px, qy - py) * units.value("length", 1.0)
            label = f"distance from {bi} to {bj} ({units.unit('length')})"
        else:
            value = poses.point(bi, d["p"])["xy".index(kind)] * units.value("length", 1.0)
            label = f"{kind} of the driven point of {bi} ({units.unit('length')})"
        finite = value[np.isfinite(value)]
        if len(finite) and np.ptp(finite) > 0.0:
            return f"{label}, driver {d['name']}", value
    return None


def mechanism_figure(run: Run, rows: np.ndarray | None = None, times: np.ndarray | None = None) -> dict[str, Any]:
    """The animated mechanism over ``rows`` of the run (default: every frame up to
    :data:`MAX_FRAMES`), with play, pause, speeds and a time slider; ``times`` labels the frames
    (default: the rows' times)."""
    rows = _frame_rows(len(run.time)) if rows is None else rows
    own_times = times is None
    times = np.asarray(run.time, dtype=float)[rows] if times is None else times
    frames = len(rows)
    poses = _Poses(run, rows)
    bodies = run.drawing["bodies"]
    joints = run.drawing["joints"]

    # The scale of the picture: the extent of every point over the motion.
    every: list[tuple[np.ndarray, np.ndarray]] = []
    for body in bodies:
        for s in [*body["points"].values(), *body["joint_points"].values(), (0.0, 0.0)]:
            every.append(poses.point(body["name"], s))
    for j in joints:
        for side, s in (("body_i", "p"), ("body_j", "q")):
            if j[side] == "ground":
                every.append(poses.point("ground", j[s]))
    xs_all = np.concatenate([p[0] for p in every]) if every else np.zeros(1)
    ys_all = np.concatenate([p[1] for p in every]) if every else np.zeros(1)
    size = max(float(np.ptp(xs_all)), float(np.ptp(ys_all)), 1e-9)
    # Half the side of a slider block (and the scale of pins' hatching): small beside the picture
    # and beside a typical link (the median length of the bodies with two points), but never
    # below a hundredth of the picture, where it could no longer be seen.
    lengths = [
        max(math.dist(a, b) for a in pts for b in pts)
        for pts in ([*body["points"].values(), *body["joint_points"].values()] for body in bodies)
        if len(pts) > 1
    ]
    block = min(0.03 * size, max(0.12 * float(np.median(lengths)), 0.01 * size)) if lengths else 0.03 * size

    static: list[dict[str, Any]] = []
    moving: list[dict[str, Any]] = []
    per_frame: list[list[dict[str, Any]]] = [[] for _ in range(frames)]

    def animate(trace: dict[str, Any], xy: Callable[[int], tuple[list[float | None], list[float | None]]]) -> None:
        x0, y0 = xy(0)
        moving.append({**trace, "x": x0, "y": y0})
        for f in range(frames):
            x, y = xy(f)
            per_frame[f].append({"x": x, "y": y})

    # The paths the file names (`paths:`, or its point measures' points), solid, each with its
    # point marked where it is now. Without any, the paths of the named points (coupler curves),
    # faint, of the MAX_CURVES points that travel furthest.
    named = named_paths(run, rows)
    if named:
        for name, b, x, y in named_paths(run, _path_rows(len(run.time))):
            static.append(
                {
                    "type": "scatter", "mode": "lines", "x": _num(x), "y": _num(y),
                    "line": {"color": PALETTE[b % len(PALETTE)], "width": 2},
                    "name": f"{name} path", "hoverinfo": "name", "showlegend": False,
                }
            )
        marks = (np.array([x for _, _, x, _ in named]), np.array([y for _, _, _, y in named]))
        animate({"type": "scatter", "mode": "markers", "name": "path points", "text": [p[0] for p in named],
                 "hoverinfo": "text", "marker": {"symbol": "x-thin", "size": 11, "line": {"color": INK, "width": 2}},
                 "showlegend": False}, lambda f: (_num(marks[0][:, f]), _num(marks[1][:, f])))
    else:
        all_poses = _Poses(run, _path_rows(len(run.time)))
        paths: list[tuple[float, int, str, np.ndarray, np.ndarray]] = []
        for b, body in enumerate(bodies):
            for name, s in body["points"].items():
                x, y = all_poses.point(body["name"], s)
                length = float(np.nansum(np.hypot(np.diff(x), np.diff(y))))
                if length > 0.0:
                    paths.append((length, b, f"{body['name']}.{name}", x, y))
        for _, b, name, x, y in sorted(paths, key=lambda p: -p[0])[:MAX_CURVES]:
            static.append(
                {
                    "type": "scatter", "mode": "lines", "x": _num(x), "y": _num(y),
                    "line": {"color": PALETTE[b % len(PALETTE)], "width": 1, "dash": "dot"},
                    "opacity": 0.5, "name": f"{name} path", "hoverinfo": "name", "showlegend": False,
                }
            )

    # Ground: a hatched base under each ground point of a pin, and fixed guides.
    hatch = _Paths()
    for j in joints:
        for side, s in (("body_i", "p"), ("body_j", "q")):
            if j[side] == "ground" and j["shape"] == "pin":
                gx, gy = float(j[s][0]), float(j[s][1])
                w = 1.6 * block
                hatch.add([np.array([gx - w]), np.array([gx + w])], [np.array([gy - block]), np.array([gy - block])], j["name"])
                hatch.add([np.array([gx - 0.6 * w]), np.array([gx]), np.array([gx + 0.6 * w])],
                          [np.array([gy - block]), np.array([gy]), np.array([gy - block])], j["name"])
                for k in range(5):
                    hx = gx - w + k * w / 2
                    hatch.add([np.array([hx]), np.array([hx - 0.5 * block])],
                              [np.array([gy - block]), np.array([gy - 1.6 * block])], j["name"])
    if hatch:
        hatch_x, hatch_y = hatch.at(0)
        static.append({"type": "scatter", "mode": "lines", "x": hatch_x, "y": hatch_y, "line": {"color": GROUND, "width": 1.5},
                       "name": "ground", "text": hatch.text, "hoverinfo": "text", "showlegend": False})

    # Guides: the line along which a block slides (or a disc rolls), over the stretch the block
    # travels on it, plus two block lengths either side. A translational joint's block is the body
    # with fewer points (a slider, not the arm it slides on), whichever of the two the file named
    # first; a pin-in-slot's slot is body i's line, and its pin body j's point.
    npoints: dict[str, float] = {b["name"]: len(b["points"]) + len(b["joint_points"]) for b in bodies}
    npoints["ground"] = math.inf
    guides = _Paths()
    blocks: list[tuple[str, str, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]] = []
    for j in joints:
        if j["shape"] not in ("slide", "disc"):
            continue
        ux, uy = poses.direction(j["body_i"], j["axis"])
        line_side, moving_side = ("body_i", "p"), ("body_j", "q")
        if j["type"] == "translational" and npoints[j["body_i"]] < npoints[j["body_j"]]:
            line_side, moving_side = moving_side, line_side
        px, py = poses.point(j[line_side[0]], j[line_side[1]])
        qx, qy = poses.point(j[moving_side[0]], j[moving_side[1]])
        along = (qx - px) * ux + (qy - py) * uy
        reach = 2 * block + (j["radius"] if j["shape"] == "disc" else 0.0)
        lo, hi = float(np.min(along)) - reach, float(np.max(along)) + reach
        # The guide moves with its body: the stretch is measured along it, so it is the same in
        # the body's frame at every frame.
        guides.add([px + lo * ux, px + hi * ux], [py + lo * uy, py + hi * uy], j["name"])
        if j["type"] == "translational":
            blocks.append((j["name"], j[moving_side[0]], qx, qy, (ux, uy)))

    # Bodies: the outline through their points, a bar for two, a block for one.
    for b, body in enumerate(bodies):
        local = [(float(s[0]), float(s[1])) for s in [*body["points"].values(), *body["joint_points"].values()]]
        if len(set(local)) == 1 and local[0] != (0.0, 0.0):
            local.append((0.0, 0.0))  # a pendulum's pivot and its mass centre: a bar between them
        outline = _hull(local) if local else []
        if len(outline) <= 1:
            cx, cy = outline[0] if outline else (0.0, 0.0)
            outline = [(cx - block, cy - block), (cx + block, cy - block), (cx + block, cy + block), (cx - block, cy + block)]
        closed = outline + outline[:1] if len(outline) > 2 else outline
        pts = [poses.point(body["name"], s) for s in closed]
        colour = PALETTE[b % len(PALETTE)]
        trace = {
            "type": "scatter", "mode": "lines", "name": body["name"], "hoverinfo": "name",
            "line": {"color": colour, "width": 6 if len(outline) == 2 else 2},
            "fill": "toself" if len(outline) > 2 else "none", "fillcolor": _faded(colour),
        }
        outline_path = _Paths()
        outline_path.add([x for x, _ in pts], [y for _, y in pts], body["name"])
        animate(trace, outline_path.at)

    # Joint pieces drawn as lines: rods, gears' pitch circles, discs, slider blocks.
    lines = _Paths()
    pins: list[tuple[str, np.ndarray, np.ndarray]] = []
    held: list[tuple[str, np.ndarray, np.ndarray]] = []
    for j in joints:
        shape, bi, bj = j["shape"], j["body_i"], j["body_j"]
        px, py = poses.point(bi, j["p"])
        qx, qy = poses.point(bj, j["q"])
        if shape == "pin":
            pins.append((j["name"], px, py))
        elif shape == "rod":
            lines.add([px, qx], [py, qy], j["name"])
            pins += [(j["name"], px, py), (j["name"], qx, qy)]
        elif shape == "slide" and j["type"] != "translational":
            pins.append((j["name"], qx, qy))
        elif shape == "gears":
            lines.add(*_circle(px, py, j["r_i"], poses.direction(bi, (1.0, 0.0))), j["name"])
            lines.add(*_circle(qx, qy, j["r_j"], poses.direction(bj, (1.0, 0.0))), j["name"])
        elif shape == "disc":
            lines.add(*_circle(qx, qy, j["radius"], poses.direction(bj, (1.0, 0.0))), j["name"])
        elif shape == "held":
            held.append((j["name"], px, py))
    # A block where the sliding body has an outline of its own (a slider body is its own block).
    for name, body, bx, by, (ux, uy) in blocks:
        if body != "ground" and npoints[body] > 1:
            corners = [(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)]
            lines.add([bx + block * (a * ux - c * uy) for a, c in corners],
                      [by + block * (a * uy + c * ux) for a, c in corners], name)
    # Reactions of a static analysis: each joint's force on its first body as an arrow at its
    # point there, the largest a sixth of the picture long.
    arrows: list[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    if run.summary.type == "static":
        on = run.summary.reaction_bodies or {}
        for j in joints:
            fx, fy = run.columns.get(f"{j['name']}.fx"), run.columns.get(f"{j['name']}.fy")
            if fx is None or fy is None or j["name"] not in on:
                continue
            body_key, point_key = ("body_i", "p") if on[j["name"]] == j["body_i"] else ("body_j", "q")
            ax, ay = poses.point(j[body_key], j[point_key])
            arrows.append((j["name"], ax, ay, np.asarray(fx, dtype=float)[rows], np.asarray(fy, dtype=float)[rows]))
    largest = max((float(np.max(np.hypot(fx, fy))) for *_, fx, fy in arrows), default=0.0)
    if largest > 0.0:
        scale = size / 6 / largest
        reactions = _Paths()
        for name, ax, ay, fx, fy in arrows:
            reactions.add([ax, ax + scale * fx], [ay, ay + scale * fy], name)
        animate({"type": "scatter", "mode": "lines+markers", "name": "reactions", "text": reactions.text,
                 "hoverinfo": "text", "line": {"color": "#d62728", "width": 2},
                 "marker": {"symbol": "arrow", "angleref": "previous", "size": [0, 12, 0] * len(arrows), "color": "#d62728"},
                 "showlegend": True}, reactions.at)
    if guides:
        animate({"type": "scatter", "mode": "lines", "name": "guides", "text": guides.text, "hoverinfo": "text",
                 "line": {"color": GROUND, "width": 1.5, "dash": "dash"}, "showlegend": False}, guides.at)
    if lines:
        animate({"type": "scatter", "mode": "lines", "name": "joints", "text": lines.text, "hoverinfo": "text",
                 "line": {"color": INK, "width": 2}, "showlegend": False}, lines.at)
    for label, points, marker in (
        ("pins", pins, {"symbol": "circle", "size": 10, "color": "white", "line": {"color": INK, "width": 2}}),
        ("held", held, {"symbol": "triangle-up", "size": 12, "color": GROUND}),
    ):
        if points:
            names = [n for n, _, _ in points]
            px = np.array([x for _, x, _ in points])  # (points x frames)
            py = np.array([y for _, _, y in points])

            def at(f: int, px: np.ndarray = px, py: np.ndarray = py) -> tuple[list[float | None], list[float | None]]:
                return _num(px[:, f]), _num(py[:, f])

            animate({"type": "scatter", "mode": "markers", "name": label, "text": names, "hoverinfo": "text",
                     "marker": marker, "showlegend": False}, at)

    # Fixed axes around the whole motion, equal scales.
    pad = 0.08 * size
    x_range = [float(np.min(xs_all)) - pad, float(np.max(xs_all)) + pad]
    y_range = [float(np.min(ys_all)) - pad - 1.6 * block, float(np.max(ys_all)) + pad]
    data = static + moving
    moving_index = list(range(len(static), len(data)))
    names = [str(k) for k in range(frames)]
    frame_list = [{"name": names[f], "data": per_frame[f], "traces": moving_index} for f in range(frames)]
    span = float(times[-1] - times[0]) if frames > 1 else 0.0
    # ms a frame: real time, but at most 50 frames a second (what a screen shows smoothly) and at
    # least 10 (a long run, 2000 s of a pendulum, then plays in 30 s rather than in 2000).
    real_time = min(max(20.0, 1000.0 * span / max(frames - 1, 1)), 100.0)

    def play(duration: float) -> list[Any]:
        return [None, {"frame": {"duration": duration, "redraw": False}, "fromcurrent": True,
                       "transition": {"duration": 0}, "mode": "immediate"}]

    layout: dict[str, Any] = {
        # Equal scales on ranges that hold the motion: the plot's area shrinks to their shape
        # (constrain "domain") rather than one range growing to fill the page's width.
        "xaxis": {"range": x_range, "title": {"text": "x (m)"}, "zeroline": False, "constrain": "domain"},
        "yaxis": {"range": y_range, "title": {"text": "y (m)"}, "scaleanchor": "x", "scaleratio": 1, "zeroline": False,
                  "constrain": "domain"},
        "margin": {"l": 60, "r": 20, "t": 30, "b": 40},
        "hovermode": "closest",
        "legend": {"orientation": "h", "y": 1.02, "yanchor": "bottom"},
        # Bodies are named on hover; a legend of more than a dozen hides the picture.
        "showlegend": len(bodies) <= MAX_CURVES,
        "height": 520,
    }
    if frames > 1:
        # The slider's labels to the decimals that tell one frame from the next (0.02 s apart:
        # 0.28, 0.3; 1/30 s apart: 0.03, 0.07), not the frames' times to round-off.
        spacing = float(np.min(np.diff(times)))
        decimals = max(0, math.ceil(-math.log10(spacing))) if spacing > 0 else DIGITS
        layout["updatemenus"] = [
            {
                "type": "buttons", "direction": "left", "x": 0.0, "y": -0.12, "xanchor": "left", "yanchor": "top",
                "showactive": False, "pad": {"r": 6, "t": 6},
                "buttons": [
                    {"label": "▶ play", "method": "animate", "args": play(real_time)},
                    {"label": "❚❚ pause", "method": "animate",
                     "args": [[None], {"frame": {"duration": 0, "redraw": False}, "mode": "immediate",
                                       "transition": {"duration": 0}}]},
                    {"label": "¼×", "method": "animate", "args": play(4 * real_time)},
                    {"label": "4×", "method": "animate", "args": play(real_time / 4)},
                ],
            }
        ]
        layout["sliders"] = [
            {
                "active": 0, "x": 0.32, "len": 0.68, "y": -0.12, "yanchor": "top", "pad": {"t": 6},
                "currentvalue": {"prefix": "t = ", "suffix": " s", "visible": True},
                "steps": [
                    {"label": f"{times[f]:.{decimals}f}", "method": "animate",
                     "args": [[names[f]], {"mode": "immediate", "frame": {"duration": 0, "redraw": False},
                                           "transition": {"duration": 0}}]}
                    for f in range(frames)
                ],
            }
        ]
        layout["margin"]["b"] = 110
        layout["height"] = 600
    return _shown({"data": data, "layout": layout, "frames": frame_list, "times": _num(times)}, run.units, own_times)


def _shown(fig: dict[str, Any], units: Units, own_times: bool) -> dict[str, Any]:
    """The mechanism figure ``fig``, drawn in metres and seconds, in the length and time units
    ``units`` shows: every trace's and frame's points, the axes' ranges and titles, and the
    slider's times when they are the run's (``own_times``; a mode's are phases)."""
    length, time = units.unit("length"), units.unit("time")
    to_length, to_time = units.value("length", 1.0), units.value("time", 1.0)

    def scaled(values: Any, factor: float) -> Any:
        return [None if v is None else float(f"{v * factor:.{DIGITS}g}") for v in values]

    if to_length != 1.0:
        for trace in [*fig["data"], *(t for frame in fig["frames"] for t in frame["data"])]:
            for axis in ("x", "y"):
                if axis in trace:
                    trace[axis] = scaled(trace[axis], to_length)
        for axis in ("xaxis", "yaxis"):
            if "range" in fig["layout"][axis]:
                fig["layout"][axis]["range"] = scaled(fig["layout"][axis]["range"], to_length)
    for axis in ("x", "y"):
        fig["layout"][f"{axis}axis"]["title"] = {"text": f"{axis} ({length})"}
    if not own_times:
        return fig
    fig["times"] = scaled(fig["times"], to_time)
    fig["time_unit"] = time
    for slider in fig["layout"].get("sliders", []):
        slider["currentvalue"]["suffix"] = f" {time}"
        for step, t in zip(slider["steps"], fig["times"], strict=True):
            step["label"] = f"{t:.4g}"
    return fig


# --- plots ---------------------------------------------------------------------------------------


def line_figure(
    run: Run, columns: Sequence[str], title: str = "", ylabel: str = "", log: bool = False, x: str = "time",
    against: tuple[str, np.ndarray] | None = None,
) -> dict[str, Any]:
    """A plot of ``columns`` against the column ``x`` (default: time), each curve decimated to
    :data:`MAX_PLOT_POINTS`, in the units the run shows. With ``against`` (a label and a value
    per row: the driver's coordinate), each trace's times are its ``customdata`` and the figure's
    ``against`` holds the label and each trace's x values against that coordinate, for the page
    to switch to."""
    units = run.units
    t = units.shown("time", run.time)
    xs = t if x == "time" else units.shown(x, run.columns[x])
    # Each curve names its unit where the plot's curves are not all in one.
    mixed = len({units.column_unit(c) for c in columns}) > 1
    data = []
    other: list[list[float | None]] = []
    for name in columns:
        y = units.shown(name, run.columns[name])
        if log:
            y = np.abs(y)
        rows = _plot_rows(y)
        trace = {"type": "scatter", "mode": "lines" if len(t) > 1 else "markers",
                 "name": units.label(name) if mixed else name, "x": _num(xs[rows]), "y": _num(y[rows])}
        if against is not None:
            trace["customdata"] = _num(t[rows])
            other.append(_num(against[1][rows]))
        data.append(trace)
    xlabel = f"time ({units.unit('time')})" if x == "time" else units.label(x)
    fig: dict[str, Any] = {"data": data, "layout": _plot_layout(title, xlabel, _axis_label(units, columns, ylabel), log)}
    if against is not None:
        fig["against"] = {"label": against[0], "x": other}
    return fig


def bar_figure(run: Run, columns: Sequence[str], title: str = "", ylabel: str = "") -> dict[str, Any]:
    """The last row's values of ``columns``, one bar each: a run of one state (a static
    equilibrium, the state modes are taken about) has nothing to draw against time."""
    values = [float(run.units.shown(c, run.columns[c])[-1]) for c in columns]
    mixed = len({run.units.column_unit(c) for c in columns}) > 1
    data = [{"type": "bar", "x": [run.units.label(c) if mixed else c for c in columns], "y": _num(values), "name": title}]
    return {"data": data, "layout": _plot_layout(title, "", _axis_label(run.units, columns, ylabel))}


def _axis_label(units: Units, columns: Sequence[str], fallback: str) -> str:
    """The units of ``columns``, each once in order (``mm, deg``); ``fallback`` when the
    quantity of none of them is known."""
    shown = list(dict.fromkeys(units.column_unit(c) for c in columns))
    return fallback if shown == [UNKNOWN] and fallback else ", ".join(shown)


def _plot_layout(title: str, xlabel: str, ylabel: str, log: bool = False) -> dict[str, Any]:
    # The title at the left, above the plot, its words in parentheses in the subtitle under it:
    # the toolbar (plotly's modebar) is at the right, where a long title would run under it.
    head, _, rest = title.partition(" (")
    subtitle = rest[:-1] if rest.endswith(")") else ""
    return {
        "title": {"text": head if subtitle else title, "x": 0, "xref": "paper", "xanchor": "left",
                  "subtitle": {"text": subtitle}},
        "height": 340, "margin": {"l": 60, "r": 20, "t": 70 if subtitle else 50, "b": 40},
        "xaxis": {"title": {"text": xlabel}}, "yaxis": {"title": {"text": ylabel}, "type": "log" if log else "linear"},
        "legend": {"font": {"size": 10}},
    }


def mode_plots(modes: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The modes side by side: eigenvalues in the complex plane, frequencies, damping ratios and
    shapes."""
    labels = [f"mode {k}" for k in range(1, len(modes) + 1)]
    eig = {"type": "scatter", "mode": "markers+text", "text": labels, "textposition": "top center",
           "x": _num([m["eigenvalue"][0] for m in modes]), "y": _num([m["eigenvalue"][1] for m in modes]),
           "marker": {"size": 10}, "name": "eigenvalues"}
    out = [{"data": [eig], "layout": _plot_layout("eigenvalues s = σ + iω", "σ (1/s)", "ω (rad/s)")}]
    for key, title, unit in (("frequency", "undamped natural frequencies", "Hz"), ("damping_ratio", "damping ratios", "1")):
        values = [m.get(key) for m in modes]
        out.append({"data": [{"type": "bar", "x": labels, "y": _num([np.nan if v is None else v for v in values]),
                              "name": title}], "layout": _plot_layout(title, "", unit)})
    coords = list(modes[0].get("shape") or {}) if modes else []
    shapes = [{"type": "bar", "name": label, "x": coords, "y": _num([m["shape"][c] for c in coords])}
              for label, m in zip(labels, modes, strict=True)]
    layout = _plot_layout("mode shapes (largest component 1)", "", "1")
    layout["barmode"] = "group"
    out.append({"data": shapes, "layout": layout})
    return out


def _body_columns(run: Run, quantities: Sequence[str]) -> list[str]:
    return [f"{b['name']}.{q}" for b in run.drawing["bodies"] for q in quantities if f"{b['name']}.{q}" in run.columns]


def plots(run: Run, against: tuple[str, np.ndarray] | None = None) -> list[dict[str, Any]]:
    """The plots suited to the run's analysis, each with data; those against time also hold
    their curves against ``against`` (:func:`driver_coordinate`), for the page to switch to."""
    kind = run.summary.type or ""
    cols = run.columns
    out: list[dict[str, Any]] = []

    used: set[str] = set()
    one_state = len(run.time) == 1

    def spread(c: str, log: bool) -> float:
        """How much a curve varies (on a log plot: how far it reaches)."""
        y = np.asarray(cols[c], dtype=float)
        y = y[np.isfinite(y)]
        return float(np.max(np.abs(y), initial=0.0)) if log else float(np.ptp(y)) if len(y) else 0.0

    def add(columns: Sequence[str], title: str, ylabel: str, log: bool = False) -> None:
        columns = [c for c in columns if c in cols]
        used.update(columns)
        # A torque that is zero throughout (a pin's) says nothing.
        columns = [c for c in columns if not (c.endswith(".torque") and not np.any(np.asarray(cols[c], dtype=float)))]
        # Constant columns are named under the title, with their value, rather than drawn (unless
        # every one is): a flat line in the legend reads as one more curve to look for.
        constant = [] if one_state else [c for c in columns if spread(c, False) == 0.0]
        if constant and len(constant) < len(columns):
            columns = [c for c in columns if c not in constant]
        notes = []
        if len(columns) > MAX_CURVES:
            kept = set(sorted(columns, key=lambda c: spread(c, log), reverse=True)[:MAX_CURVES])
            notes.append(f"the {MAX_CURVES} of {len(columns)} that vary most")
            columns = [c for c in columns if c in kept]
        if constant:
            values = ", ".join(
                f"{c} = {_text(float(run.units.shown(c, cols[c])[0]))} {run.units.column_unit(c)}" for c in constant[:MAX_CONSTANTS]
            )
            more = f" and {len(constant) - MAX_CONSTANTS} more" if len(constant) > MAX_CONSTANTS else ""
            notes.append(f"constant: {html.escape(values)}{more}")
        if not columns:
            return
        if one_state:
            fig = bar_figure(run, columns, title, ylabel)
        else:
            fig = line_figure(run, columns, title, ylabel, log, against=against)
        if constant and len(constant) == len(columns):
            for trace in fig["data"]:
                trace["showlegend"] = False
        if notes:
            # Under the title, in plotly's subtitle: a title runs no further right, under the toolbar.
            subtitle = fig["layout"]["title"]["subtitle"]
            subtitle["text"] = "; ".join([subtitle["text"], *notes] if subtitle["text"] else notes)
            fig["layout"]["margin"]["t"] = 70
        out.append(fig)

    if kind == "modes":
        out += mode_plots(run.summary.modes or [])
        add(_body_columns(run, ["x", "y", "phi"]), "the state linearised about", "m, rad")
        return out

    if kind in ("kinematic", "dynamic", "inverse"):
        add(_body_columns(run, ["phi"]), "angles", "rad")
        add(_body_columns(run, ["x", "y"]), "positions", "m")
        add(_body_columns(run, ["omega"]), "angular velocities", "rad/s")
        add(_body_columns(run, ["vx", "vy"]), "velocities", "m/s")
        add(_body_columns(run, ["alpha"]), "angular accelerations", "rad/s²")
        add(_body_columns(run, ["ax", "ay"]), "accelerations", "m/s²")
    if kind == "dynamic":
        add(["kinetic_energy", "potential_energy", "nonconservative_work"], "energies", "J")
        add(["position_residual", "velocity_residual"], "constraint residuals", "m, m/s (absolute)", log=True)
    if kind == "inverse":
        add(["kinetic_energy", "potential_energy", "driver_power", "applied_power"], "energy and power", "J, W")
    if kind == "static":
        add(_body_columns(run, ["x", "y", "phi"]), "equilibrium coordinates", "m, rad")
        add(["potential_energy"], "potential energy", "J")
    bodies = set(_body_columns(run, BODY_QUANTITIES))
    reaction = [c for c in cols if c not in bodies and c.rsplit(".", 1)[-1] in ("fx", "fy")]
    add(sorted(reaction, key=lambda c: c.endswith(".fy")), "joint reaction forces (global frame, on the first body)", "N")
    add([c for c in cols if c not in bodies and c.endswith(".torque")], "joint reaction torques", "N m")
    add([c for c in cols if c not in bodies and c.endswith(".effort")], "driver efforts", "N or N m")
    friction = "joint friction (on the first body: torque of a pin, force along a slider)"
    add([c for c in cols if c not in bodies and c.endswith(".friction")], friction, "N m or N")
    # Measures come after every column the engine names itself.
    engine = bodies | set(ENGINE_COLUMNS) | used
    add([c for c in cols if c not in engine], "measures", "")
    return out


# --- sensitivities -------------------------------------------------------------------------------


def sensitivity_figures(run: Run) -> list[dict[str, Any]]:
    """The sensitivity panel of a run asked for sensitivities: for each summary (and peak) with
    derivatives, a bar a parameter of its derivative times the parameter's tolerance when it
    has one, else times its size (its value's magnitude; 1 SI unit for a parameter of value 0):
    what the summary changes by when the parameter moves by that much, to first order. Largest
    magnitude first, horizontal bars read top down. A summary whose derivatives are all zero
    (:func:`constant_summaries`) has no figure."""
    by_summary = run.summary.sensitivities or {}
    values = run.summary.parameters or {}
    out = []
    constant = set(constant_summaries(run))
    for name, by_parameter in by_summary.items():
        if name in constant:
            continue
        scaled = []
        for parameter, derivative in by_parameter.items():
            if parameter in run.tolerances:
                scale, by = run.tolerances[parameter], "tolerance"
            else:
                scale = abs(values.get(parameter, 0.0)) or 1.0
                by = "value" if values.get(parameter) else "1 SI unit"
            scaled.append((f"{parameter} (× {by} {scale:.4g})", derivative * scale))
        scaled.sort(key=lambda item: -abs(item[1]))
        bar = {"type": "bar", "orientation": "h", "y": [label for label, _ in scaled], "x": _num([v for _, v in scaled]),
               "name": name}
        layout = _plot_layout(f"{name} (its derivative times each parameter's tolerance or size)", f"change of {name} (SI)", "")
        # The parameters are categories (`_plot_layout`'s linear axis would place no bar at all),
        # their labels long: the margin grows to hold them.
        layout["yaxis"].update(type="category", autorange="reversed", automargin=True)
        layout["height"] = max(200, 90 + 28 * len(scaled))
        out.append({"data": [bar], "layout": layout})
    return out


def constant_summaries(run: Run) -> list[str]:
    """The summaries whose derivative with respect to every parameter asked is exactly zero (a pin's
    reaction torque, a quantity no parameter moves): the sensitivity panel names them in a line
    rather than drawing empty charts."""
    by_summary = run.summary.sensitivities or {}
    return [name for name, by_parameter in by_summary.items() if all(v == 0.0 for v in by_parameter.values())]


def tolerance_figures(
    name: str, nominal: float, rss: float, shares: Mapping[str, float], samples: np.ndarray | None
) -> list[dict[str, Any]]:
    """The figures of an output's tolerance analysis: the histogram of its Monte Carlo samples
    (as a density) under the normal density of the linear analysis (mean ``nominal``, standard
    deviation ``rss``), when there are samples; and each parameter's share of the linear
    variance, largest first."""
    out = []
    if samples is not None and len(samples):
        hist = {"type": "histogram", "x": _num(samples), "histnorm": "probability density", "name": "Monte Carlo",
                "opacity": 0.6}
        low, high = float(np.min(samples)), float(np.max(samples))
        if rss > 0:
            low, high = min(low, nominal - 4 * rss), max(high, nominal + 4 * rss)
        x = np.linspace(low, high, 200)
        density = np.exp(-0.5 * ((x - nominal) / rss) ** 2) / (rss * math.sqrt(2 * math.pi)) if rss > 0 else np.zeros_like(x)
        line = {"type": "scatter", "mode": "lines", "x": _num(x), "y": _num(density), "name": "linear (normal, RSS)"}
        out.append({"data": [hist, line], "layout": _plot_layout(f"{name} (Monte Carlo samples and the linear spread)", f"{name} (SI)", "density")})
    ranked = sorted(shares.items(), key=lambda item: -item[1])
    bar = {"type": "bar", "x": [p for p, _ in ranked], "y": _num([100 * v for _, v in ranked]), "name": "share"}
    out.append({"data": [bar], "layout": _plot_layout(f"{name}: each parameter's share of the variance (linear)", "", "%")})
    return out


# --- modes ---------------------------------------------------------------------------------------


def mode_figures(run: Run) -> list[tuple[str, dict[str, Any]]]:
    """Each mode's shape animated about the state linearised about: one period in 40 frames, the
    largest displacement a tenth of the mechanism's size."""
    modes = run.summary.modes or []
    if not modes:
        return []
    base = {name: np.asarray(col, dtype=float)[:1] for name, col in run.columns.items()}
    positions = [np.asarray(base[f"{b['name']}.{c}"])[0] for b in run.drawing["bodies"] for c in ("x", "y")]
    size = max(max(positions) - min(positions), 1e-3) if positions else 1.0
    out = []
    phases = np.linspace(0.0, 2 * math.pi, 41)
    for k, mode in enumerate(modes, start=1):
        shape = mode.get("shape") or {}
        largest = max((abs(v) for v in shape.values()), default=0.0) or 1.0
        amplitude = 0.1 * size / largest
        columns = dict(run.columns)
        for name, value in shape.items():
            columns[name] = base[name][0] + amplitude * value * np.sin(phases)
        for name in base:
            if name not in shape and name.split(".")[-1] in ("x", "y", "phi"):
                columns[name] = np.full(len(phases), base[name][0])
        moving = Run(run.drawing, phases, columns, run.summary, units=run.units)
        fig = mechanism_figure(moving, rows=np.arange(len(phases)), times=phases)
        fig["layout"]["sliders"][0]["currentvalue"] = {"prefix": "phase ", "suffix": " rad", "visible": True}
        freq = mode.get("frequency")
        damping = mode.get("damping_ratio")
        label = f"mode {k}: {mode.get('kind', '')}"
        if freq is not None:
            label += f", {freq:.6g} Hz"
        if damping is not None:
            label += f", damping ratio {damping:.3g}"
        if mode.get("growth_rate") is not None:
            label += f", growth rate {mode['growth_rate']:.6g} 1/s"
        out.append((label, fig))
    return out


def figure(fig: Mapping[str, Any]) -> Any:
    """A ``plotly.graph_objects.Figure`` of one of the figures made here."""
    import plotly.graph_objects as go

    return go.Figure(data=fig["data"], layout=fig["layout"], frames=fig.get("frames"))


def pose_figure(drawing: Mapping[str, Any], poses: Sequence[tuple[str, Mapping[str, float], float]]) -> dict[str, Any]:
    """The mechanism in each of ``poses`` (``(label, {"<body>.x": .., ...}, opacity)``), drawn over
    one another."""
    data: list[dict[str, Any]] = []
    layout: dict[str, Any] = {}
    for label, q, opacity in poses:
        columns = {name: np.array([value]) for name, value in q.items()}
        fig = mechanism_figure(Run(drawing, np.zeros(1), columns, Summary()))
        for trace in fig["data"]:
            if trace["name"].endswith(" path"):
                continue
            data.append({**trace, "opacity": opacity, "name": f"{trace['name']} ({label})",
                         "legendgroup": label, "showlegend": trace.get("showlegend", True)})
        layout = fig["layout"]
    for axis in ("xaxis", "yaxis"):
        layout[axis].pop("range", None)
    return {"data": data, "layout": layout}
