"""The report: one self-contained HTML page with the animated mechanism, plots linked to its time,
the summary and the failure if there was one.

The page embeds plotly's JavaScript (from the ``plotly`` package) and its figures
(:mod:`linkwork.figures`), gzipped, so that it opens offline and makes no network request (the
browser unpacks them with its own ``DecompressionStream``: Chromium 80, Firefox 113, Safari 16.4
and later).
"""

from __future__ import annotations

import base64
import functools
import gzip
import html
import json
from collections.abc import Sequence
from typing import Any

import numpy as np

from .folder import write_text
from .figures import (
    Run, _frame_rows, _num, _text, constant_summaries, driver_coordinate, mechanism_figure, mode_figures, paths_figure, plots, sensitivity_figures,
)
from .summary import Summary, branch_words
from .units import UNKNOWN, Units


# --- the page ------------------------------------------------------------------------------------


def _table(rows: Sequence[tuple[str, Any]]) -> str:
    cells = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(_text(v))}</td></tr>" for k, v in rows)
    return f"<table>{cells}</table>"


def failure_html(summary: Summary) -> str:
    """The failure, if the run failed, and the warnings, as HTML."""
    s = summary
    parts = []
    status = s.status or "ok"
    if status != "ok":
        where = f" at t = {s.error_time:.9g} s" if s.error_time is not None else ""
        elements = s.error_elements or []
        in_ = f" (in {', '.join(elements)})" if elements else ""
        parts.append(
            f'<div class="failure"><b>The run {html.escape(str(status))}{html.escape(where)}{html.escape(in_)}.</b> '
            f"{html.escape(s.error or '')}<br>These are the partial results computed until then.</div>"
        )
    for w in s.warnings or []:
        parts.append(f'<div class="warning">{html.escape(str(w))}</div>')
    return "\n".join(parts)


def summaries_html(summary: Summary) -> str:
    """The model's summaries (whole-run quantities) as a table; nothing when the run has none."""
    values = summary.summaries or {}
    # A summary is an expression of its own: its value is as computed, from SI columns.
    return "<h3>Summaries</h3>" + _table([(f"{k} ({UNKNOWN})", v) for k, v in values.items()]) if values else ""


def summary_html(summary: Summary, units: Units | None = None) -> str:
    """The model summary and the solver statistics, as HTML."""
    s = summary
    parts = []
    head = [(k, s[k]) for k in ("model", "analysis", "type", "bodies", "coordinates", "dof", "output_points",
                                 "active_drivers", "redundant_rows", "indeterminate_joints", "stable") if k in s]
    if "assembly" in s:
        head.append(("assembly", s["assembly"]))
    parts.append("<h3>Model</h3>" + _table(head))
    if s.branches:
        parts.append("<h3>Branches</h3>" + _table([(b["joint"], branch_words(b)) for b in s.branches]))
    stats = s.statistics
    if isinstance(stats, dict) and stats:
        parts.append("<h3>Solver statistics</h3>" + _table(list(stats.items())))
    peaks = s.peaks
    if isinstance(peaks, dict) and peaks:
        units = units or Units.si()
        rows = []
        for k, v in peaks.items():
            # A torque that stays zero (a pin's) is left out: it says nothing.
            if k.endswith(".torque") and v.get("max_abs") == 0.0:
                continue
            # A joint's peak is that of its force's resultant, a driver's of its effort column.
            column = f"{k.removesuffix('.force')}.fx" if k.endswith(".force") else k
            time = "" if v.get("time") is None else f" at t = {units.value('time', v['time']):.6g} {units.unit('time')}"
            rows.append((k, f"{units.shown(column, v.get('max_abs', 0.0)):.6g} {units.column_unit(column)}{time}"))
        parts.append("<h3>Peaks</h3>" + _table(rows))
    return "\n".join(parts)


_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
h3 { font-size: 1em; margin: 1em 0 0.3em; }
table { border-collapse: collapse; font-size: 0.9em; } th, td { padding: 2px 10px; border-bottom: 1px solid #ddd;
text-align: left; vertical-align: top; } th { font-weight: 600; white-space: nowrap; }
.failure { background: #fde8e8; border: 1px solid #e0a0a0; padding: 0.6em; margin: 0.6em 0; }
.warning { background: #fff6dc; border: 1px solid #e8d48a; padding: 0.6em; margin: 0.6em 0; }
.plots { display: grid; grid-template-columns: repeat(auto-fit, minmax(520px, 1fr)); gap: 20px 8px; }
#now { font-variant-numeric: tabular-nums; }
"""

# Every plot gets a vertical line at the animation's time (or at the driver's coordinate then, when
# the plots are drawn against it), the paths panel a marker at each point's place; clicking a
# plot moves the animation.
_UNPACK = """
// plotly's source and the figures are stored gzipped (base64): the page is a third of its size.
const unpack = id => {
  const bytes = Uint8Array.from(atob(document.getElementById(id).textContent), c => c.charCodeAt(0));
  return new Response(new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'))).text();
};
const figuresRead = unpack('plotly').then(source => {
  const library = document.createElement('script');
  library.textContent = source;
  document.head.appendChild(library);
  return unpack('figures');
}).then(text => JSON.parse(text));
const draw = (id, fig) => Plotly.newPlot(id, fig.data, fig.layout, {responsive: true, displaylogo: false})
    .then(() => fig.frames ? Plotly.addFrames(id, fig.frames) : null);
"""

FIGURES_SCRIPT = _UNPACK + """
figuresRead.then(figures => Promise.all(figures.map((fig, k) => draw('figure' + k, fig))))
  .then(() => { document.body.dataset.ready = 'true'; }).catch(error => console.error(error));
"""
"""The script of a page of figures alone (:func:`document` with a list of figures, each drawn into
the element ``figure<k>``)."""

_SCRIPT = _UNPACK + """
figuresRead.then(figures => {
  const mech = figures.mechanism;
  const times = mech ? mech.times : [];
  const timeUnit = mech ? mech.time_unit : 's';
  const plotIds = figures.plots.map((_, k) => 'plot' + k);
  // The plots' x: time, or the driver's coordinate (the radio buttons of #against).
  const timeX = figures.plots.map(fig => fig.data.map(t => t.x));
  let against = false;
  let frame = 0;
  const marker = x => ({shapes: [{type: 'line', xref: 'x', yref: 'paper', x0: x, x1: x, y0: 0, y1: 1,
                                  line: {color: '#888', width: 1, dash: 'dot'}}]});
  const setFrame = k => {
    frame = k;
    document.getElementById('now').textContent = 't = ' + times[k].toPrecision(6) + ' ' + timeUnit;
    figures.plots.forEach((fig, p) => Plotly.relayout(plotIds[p], marker(against && fig.against ? mech.against[k] : times[k])));
    const paths = figures.paths;
    if (paths) Plotly.restyle('paths', {x: [paths.marks.x[k]], y: [paths.marks.y[k]]}, [paths.data.length - 1]);
  };
  document.querySelectorAll('input[name=against]').forEach(input => input.addEventListener('change', () => {
    against = input.value === 'driver' && input.checked;
    figures.plots.forEach((fig, p) => {
      if (!fig.against) return;
      Plotly.restyle(plotIds[p], {x: against ? fig.against.x : timeX[p]});
      Plotly.relayout(plotIds[p], {'xaxis.title.text': against ? fig.against.label : 'time (' + timeUnit + ')', 'xaxis.autorange': true});
    });
    if (mech && times.length) setFrame(frame);
  }));
  const jobs = [];
  if (mech) jobs.push(draw('mechanism', mech));
  if (figures.paths) jobs.push(draw('paths', figures.paths));
  figures.plots.forEach((fig, k) => jobs.push(draw(plotIds[k], fig)));
  figures.modes.forEach((fig, k) => jobs.push(draw('mode' + k, fig)));
  figures.sensitivities.forEach((fig, k) => jobs.push(draw('sensitivity' + k, fig)));
  Promise.all(jobs).then(() => {
    if (!mech || times.length === 0) { document.body.dataset.ready = 'true'; return; }
    const div = document.getElementById('mechanism');
    div.on('plotly_animatingframe', e => setFrame(Number(e.name)));
    div.on('plotly_sliderchange', e => setFrame(Number(e.step.args[0][0])));
    const nearest = t => times.reduce((best, s, k) => Math.abs(s - t) < Math.abs(times[best] - t) ? k : best, 0);
    plotIds.forEach(id => document.getElementById(id).on('plotly_click', e => {
      // A curve's points carry their time when the plot can be drawn against the driver.
      const point = e.points[0];
      const k = nearest(point.customdata !== undefined ? point.customdata : point.x);
      Plotly.animate('mechanism', [String(k)], {mode: 'immediate', frame: {duration: 0, redraw: false},
                                                  transition: {duration: 0}});
      setFrame(k);
    }));
    setFrame(0);
    document.body.dataset.ready = 'true';
  });
}).catch(error => console.error(error));
"""


def page(run: Run, plotly_js: str) -> str:
    """The whole report as one HTML page, with ``plotly_js`` (the library's source, packed by
    :func:`_packed`) embedded."""
    s = run.summary
    modes = mode_figures(run) if s.type == "modes" else []
    mech = None if modes or not len(run.time) else mechanism_figure(run)
    paths = None if mech is None else paths_figure(run)
    coordinate = driver_coordinate(run)
    plot_list = plots(run, coordinate) if len(run.time) else []
    against = coordinate[0] if coordinate is not None and any("against" in fig for fig in plot_list) else None
    if mech is not None and coordinate is not None:
        # Where the time line goes on plots drawn against the driver's coordinate, frame by frame.
        mech["against"] = _num(coordinate[1][_frame_rows(len(run.time))])
    sensitivities = sensitivity_figures(run)
    figures = {"mechanism": mech, "paths": paths, "plots": plot_list, "modes": [fig for _, fig in modes],
               "sensitivities": sensitivities}
    title = run.title or f"{s.model}: {s.analysis or ''}"
    body = [f"<h1>{html.escape(title)}</h1>",
            f"<div>{html.escape(s.type or 'no')} analysis, status {html.escape(s.status or 'ok')}</div>",
            failure_html(s), summaries_html(s)]
    if mech is not None:
        body += ['<h2>The mechanism <span id="now"></span></h2>', '<div id="mechanism"></div>']
    elif not modes:
        body.append('<h2>The mechanism</h2><p>No output point was computed, so there is no pose to draw.</p><span id="now"></span>')
    else:
        body.append('<span id="now"></span>')
    if paths is not None:
        body.append('<h2>Paths</h2><div id="paths"></div>')
    for k, (label, _) in enumerate(modes):
        body += [f"<h2>{html.escape(label)}</h2>", f'<div id="mode{k}"></div>']
    if plot_list:
        hint = "<p>Click a plot to move the mechanism to that time.</p>" if mech is not None else ""
        body.append(f"<h2>Plots</h2>{hint}")
        if against is not None:
            body.append('<p id="against">Plot against <label><input type="radio" name="against" value="time" checked> '
                        f'time</label> <label><input type="radio" name="against" value="driver"> {html.escape(against)}'
                        "</label></p>")
        body.append('<div class="plots">' + "".join(f'<div id="plot{k}"></div>' for k in range(len(plot_list))) + "</div>")
    constant = constant_summaries(run)
    if sensitivities or constant:
        body.append('<h2 id="sensitivity-panel">Sensitivities</h2><p>Each summary\'s derivative with respect to each '
                    "parameter, times the parameter's tolerance where the model gives one, else its size: the change "
                    "of the summary, to first order, when the parameter moves by that much.</p>")
    if constant:
        body.append(f'<p id="constant-summaries">Zero with respect to every parameter: {html.escape(", ".join(constant))}.</p>')
    if sensitivities:
        body.append('<div class="plots">' + "".join(f'<div id="sensitivity{k}"></div>' for k in range(len(sensitivities))) + "</div>")
    body += ["<h2>Summary</h2>", summary_html(s, run.units)]
    return document(title, body, figures, plotly_js, _SCRIPT)


def document(title: str, body: Sequence[str], figures: Any, plotly_js: str, script: str) -> str:
    """A self-contained page: ``body`` (HTML parts) under ``title``, with plotly (``plotly_js``,
    packed) and ``figures`` (any JSON) embedded gzipped, and ``script`` (which starts from
    :data:`_UNPACK`'s ``figuresRead``) to draw them."""
    # `</` cannot appear inside a script element: escape it in the JSON.
    data = json.dumps(figures, separators=(",", ":"), allow_nan=False)
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>\n"
        + "\n".join(body)
        + f'\n<script type="application/gzip" id="plotly">{plotly_js}</script>'
        + f'\n<script type="application/gzip" id="figures">{_packed(data)}</script>'
        + f"\n<script>{script}</script>\n</body></html>\n"
    )


def _packed(text: str) -> str:
    """``text`` gzipped and in base64, as the page unpacks it (no time stamp: the same text gives
    the same page)."""
    return base64.b64encode(gzip.compress(text.encode(), compresslevel=9, mtime=0)).decode()


def compact_html(summary: Summary, rows: int, time: np.ndarray) -> str:
    """A few lines on a run, for a notebook: analysis, status, output span, warnings, error,
    summaries."""
    span = f"t = {time[0]:.6g} .. {time[-1]:.6g} s" if rows else "no output"
    head = f"<b>{html.escape(summary.model or '')}</b>: {html.escape(summary.analysis or '')} " + (
        f"({html.escape(summary.type or '')}), {html.escape(summary.status or 'ok')}, {rows} points, {span}"
    )
    return f"<div>{head}{failure_html(summary)}{summaries_html(summary)}</div>"


@functools.cache
def plotly_js() -> str:
    """plotly's JavaScript, from the ``plotly`` package, packed as the page stores it (once per
    process: packing takes a third of a second)."""
    from plotly.offline import get_plotlyjs

    source: str = get_plotlyjs()
    return _packed(source)


def write(path: Any, run: Run) -> None:
    """Write the report of ``run`` to ``path`` (whole, then renamed into place)."""
    write_text(path, page(run, plotly_js()))
