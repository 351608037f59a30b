"""Tolerance analysis: how much an output of a run varies when the parameters that carry a
tolerance in the model file (``r: 150 mm ± 0.1 mm``) vary within it, two ways side by side.

- **Linear**, from one run with sensitivities: the output's gradient ``g_i`` with respect to
  each toleranced parameter, its worst case ``sum |g_i| t_i`` (every parameter at the end of its
  tolerance that moves the output the same way) and its statistical spread, the root sum of
  squares ``sqrt(sum (g_i sigma_i)^2)``, each parameter's share of that variance
  ``(g_i sigma_i)^2 / sum``.
- **Monte Carlo**, on the sweep engine (every core, or a Dask cluster): ``samples`` variants
  drawn from the parameters' distributions (seeded: the same seed draws the same variants),
  each run and reduced to the outputs; their mean, standard deviation with its confidence
  interval, and range.

The parameters without a tolerance are held at their values. docs/sensitivities.md,
"Tolerances", gives the equations and what each number means.
"""

from __future__ import annotations

import html
import json
import math
import os
import secrets
import statistics
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import _linkwork, folder, page
from .errors import SolverError, model_error
from .figures import tolerance_figures
from .folder import write_text
from .model import Model
from .sweep import STATUS, gradient_parameters, name_problem, sweep

CONFIDENCE = 0.95
"""The confidence of the Monte Carlo intervals: the usual 95%."""

SAMPLES = 10_000
"""Monte Carlo samples by default: the standard deviation's 95% interval is then about ±1.4% of
it (for a normal output), fine enough to tell a linear spread that is off by a few percent."""


@dataclass(frozen=True)
class MonteCarlo:
    """The Monte Carlo spread of one output."""

    samples: int
    """The variants that ran well (those that failed are counted in ``failed``)."""
    failed: int
    """The variants that failed (their status in the sweep's table)."""
    mean: float
    """The sample mean."""
    mean_interval: tuple[float, float]
    """Its confidence interval: ``mean ± z s / sqrt(n)``."""
    std: float
    """The sample standard deviation ``s`` (``n - 1`` in the denominator)."""
    std_interval: tuple[float, float]
    """Its confidence interval: the large-sample interval of the variance with the sample's
    kurtosis, on the log scale (``s^2 exp(± z se / s^2)``, ``se^2 = (m4 - s^4 (n - 3) / (n - 1)) / n``,
    ``m4`` the fourth central moment; Bonett, 2006, without his small-sample correction), so that
    it holds for outputs that are not normal (a uniform parameter's)."""
    min: float
    """The smallest sample."""
    max: float
    """The largest sample."""


@dataclass(frozen=True)
class OutputTolerance:
    """The tolerance analysis of one output."""

    expression: str
    """The output as given: an expression of aggregations of result columns, or a summary's name."""
    nominal: float
    """Its value with every parameter at its value."""
    gradient: dict[str, float]
    """Its derivative with respect to each toleranced parameter, SI per SI."""
    worst_case: float
    """The linear worst case ``sum |g_i| t_i``: the output lies in ``nominal ± worst_case`` to
    first order."""
    rss: float
    """The linear statistical spread, a standard deviation: ``sqrt(sum (g_i sigma_i)^2)``."""
    shares: dict[str, float]
    """Each parameter's share of the linear variance, ``(g_i sigma_i)^2 / rss^2`` (they add to 1;
    all 0 when the output does not move)."""
    monte_carlo: MonteCarlo | None
    """The Monte Carlo check (``None`` when asked for no samples)."""

    @property
    def agrees(self) -> bool | None:
        """Whether the linear spread lies within the Monte Carlo standard deviation's confidence
        interval (``None`` without a Monte Carlo check)."""
        if self.monte_carlo is None:
            return None
        low, high = self.monte_carlo.std_interval
        return low <= self.rss <= high


@dataclass(frozen=True)
class ToleranceAnalysis:
    """What :func:`tolerance` finds: the parameters' tolerances and each output's analysis."""

    model: str
    """The model's name."""
    analysis: str
    """The analysis run."""
    parameters: dict[str, dict[str, Any]]
    """Each toleranced parameter: its ``value``, ``tolerance``, ``distribution`` and ``sigma``
    (SI), and the ``unit`` the file writes it in (``None``: SI)."""
    outputs: dict[str, OutputTolerance]
    """Each output's analysis, by name."""
    seed: int
    """The seed of the Monte Carlo samples (the same seed draws the same samples)."""
    confidence: float
    """The confidence of the Monte Carlo intervals."""
    samples: Any = None
    """The Monte Carlo variants as the sweep's table (``pandas.DataFrame``: the parameters drawn,
    ``status``, the outputs), ``None`` without a Monte Carlo check."""

    def write(self, out: str | os.PathLike[str]) -> list[str]:
        """Write the folder ``out``: ``tolerance.json`` and ``report.html`` (:func:`write`)."""
        return write(self, out)

    def to_dict(self) -> dict[str, Any]:
        """Everything but the samples, as ``tolerance.json`` holds it (JSON's types)."""
        data = {k: v for k, v in asdict(self).items() if k != "samples"}
        for name, output in self.outputs.items():
            data["outputs"][name]["agrees"] = output.agrees
        return data


def tolerance(
    model: Model | str | os.PathLike[str],
    analysis: str,
    outputs: Mapping[str, str],
    *,
    samples: int = SAMPLES,
    seed: int | None = None,
    workers: int | None = None,
    client: Any = None,
    progress: bool | Callable[[int, int], object] = False,
    confidence: float = CONFIDENCE,
) -> ToleranceAnalysis:
    """The tolerance analysis of ``outputs`` (a name to an expression as :func:`linkwork.sweep`
    takes it, or the name of one of the model's summaries) of ``analysis`` of ``model``, over the
    parameters the model file gives a tolerance: linear (worst case, root sum of squares, shares)
    from one run with sensitivities, and a Monte Carlo check of ``samples`` variants (0: none)
    drawn with ``seed`` (a fresh one when ``None``) on ``workers`` threads or a Dask ``client``,
    as :func:`linkwork.sweep` runs them.

    Raises ``ModelError`` when no parameter has a tolerance, for an output named as a parameter
    or ``status``, and for an analysis without sensitivities; ``SolverError`` when the nominal
    run fails, or fewer than 2 Monte Carlo samples run well; ``ValueError`` for ``samples`` below 0 or a ``confidence`` outside (0, 1).
    """
    if not isinstance(model, Model):
        model = Model.load(model)
    if samples < 0:
        raise ValueError(f"samples: expected a count of at least 0, got {samples}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence: expected a number between 0 and 1, got {confidence}")
    tolerances = model.tolerances
    if not tolerances:
        raise model_error("parameters", "no parameter has a tolerance; give one as r: 150 mm ± 0.1 mm (docs/model-format.md)")
    output_list = list(outputs.items())
    for name, _ in output_list:
        problem = name_problem(name, model.parameters)
        if problem is not None:
            raise model_error(f"outputs.{name}", problem)
    names = list(tolerances)
    values = model.parameters
    gradient_parameters(model, analysis, names)
    [(status, row)] = model._native.sweep(analysis, [[]], output_list, 1, None, names)
    if row is None:
        kind, _, message = status.partition(": ")
        if kind == "ModelError":
            raise model_error("outputs", message)
        raise SolverError(f"the nominal run failed: {status}")
    seed = secrets.randbits(63) if seed is None else seed
    table = None
    if samples:
        rng = np.random.default_rng(seed)
        drawn = {}
        for name, t in tolerances.items():
            spread = rng.standard_normal(samples) * t.sigma if t.distribution == "normal" else rng.uniform(-t.value, t.value, samples)
            drawn[name] = [float(v) for v in values[name] + spread]
        table = sweep(model, analysis, outputs=dict(output_list), points=drawn, workers=workers, client=client, progress=progress)
    units = dict(model._native.parameter_units)
    parameters = {
        name: {"value": values[name], "tolerance": t.value, "distribution": t.distribution, "sigma": t.sigma, "unit": units.get(name)}
        for name, t in tolerances.items()
    }
    z = statistics.NormalDist().inv_cdf(0.5 + confidence / 2)
    analysed = {}
    for j, (name, expression) in enumerate(output_list):
        gradient = dict(zip(names, row[len(output_list) + j * len(names) : len(output_list) + (j + 1) * len(names)], strict=True))
        worst = sum(abs(gradient[p]) * t.value for p, t in tolerances.items())
        variances = {p: (gradient[p] * t.sigma) ** 2 for p, t in tolerances.items()}
        total = sum(variances.values())
        shares = {p: v / total if total > 0 else 0.0 for p, v in variances.items()}
        mc = None if table is None else _monte_carlo(table, name, z)
        analysed[name] = OutputTolerance(expression, row[j], gradient, worst, math.sqrt(total), shares, mc)
    return ToleranceAnalysis(model.name, analysis, parameters, analysed, seed, confidence, table)


def _monte_carlo(table: Any, name: str, z: float) -> MonteCarlo:
    """The Monte Carlo statistics of the output ``name`` of the sweep's ``table`` (its rows that
    ran well), with intervals of ``z`` standard errors."""
    ok = table[STATUS] == "ok"
    x = table.loc[ok, name].to_numpy(dtype=float)
    n = len(x)
    if n < 2:
        first = next((status for status in table[STATUS] if status != "ok"), "none ran")
        raise SolverError(f"{n} of {len(table)} Monte Carlo samples ran well, fewer than the 2 a spread needs; the first failure: {first}")
    mean, s = float(x.mean()), float(x.std(ddof=1))
    half = z * s / math.sqrt(n)
    m4 = float(((x - mean) ** 4).mean())
    var = s * s
    se = math.sqrt(max(m4 - var * var * (n - 3) / (n - 1), 0.0) / n)
    factor = math.exp(z * se / var) if var > 0 else 1.0
    interval = (math.sqrt(var / factor), math.sqrt(var * factor))
    return MonteCarlo(n, int((~ok).sum()), mean, (mean - half, mean + half), s, interval, float(x.min()), float(x.max()))


def table_lines(result: ToleranceAnalysis) -> list[str]:
    """The analysis as text: the parameters' tolerances, then each output's linear and Monte
    Carlo numbers side by side and its parameters' shares (SI)."""
    lines = [f"{result.model}: analysis '{result.analysis}', tolerances of {len(result.parameters)} parameter(s)"]
    for name, p in result.parameters.items():
        unit = p["unit"]
        scale = 1.0 if unit is None else _linkwork.unit(unit)
        shown = "SI" if unit is None else unit
        lines.append(
            f"  {name:<12} {p['value'] / scale:.6g} ± {p['tolerance'] / scale:.6g} {shown} ({p['distribution']}, sigma {p['sigma'] / scale:.4g} {shown})"
        )
    level = f"{result.confidence:.0%}"
    for name, o in result.outputs.items():
        lines.append("")
        lines.append(f"{name} = {o.expression} (SI): nominal {o.nominal:.6g}")
        lines.append(f"  {'':<26}{'linear':>14}{'Monte Carlo':>14}   {level} interval")
        mc = o.monte_carlo
        if mc is None:
            lines.append(f"  {'standard deviation':<26}{o.rss:>14.6g}")
            lines.append(f"  {'worst case ±':<26}{o.worst_case:>14.6g}")
        else:
            lines.append(f"  {'mean':<26}{o.nominal:>14.6g}{mc.mean:>14.6g}   {mc.mean_interval[0]:.6g} .. {mc.mean_interval[1]:.6g}")
            verdict = "agree" if o.agrees else "DISAGREE"
            lines.append(
                f"  {'standard deviation':<26}{o.rss:>14.6g}{mc.std:>14.6g}   {mc.std_interval[0]:.6g} .. {mc.std_interval[1]:.6g} ({verdict})"
            )
            lines.append(f"  {'lowest (nominal - worst)':<26}{o.nominal - o.worst_case:>14.6g}{mc.min:>14.6g}")
            lines.append(f"  {'highest (nominal + worst)':<26}{o.nominal + o.worst_case:>14.6g}{mc.max:>14.6g}")
            lines.append(f"  {mc.samples} samples ran well, {mc.failed} failed; seed {result.seed}")
        lines.append(f"  {'parameter':<14}{'d/dp (SI)':>14}{'share':>9}")
        for parameter, share in sorted(o.shares.items(), key=lambda item: -item[1]):
            lines.append(f"  {parameter:<14}{o.gradient[parameter]:>14.6g}{share:>9.1%}")
    return lines


def write(result: ToleranceAnalysis, out: str | os.PathLike[str]) -> list[str]:
    """Write the folder ``out``: ``tolerance.json`` (:meth:`ToleranceAnalysis.to_dict`) and
    ``report.html`` (self-contained: the table, each output's histogram under its linear normal
    density and its parameters' shares), the folder written whole as a run's
    (:mod:`linkwork.folder`); the names written."""
    with folder.writing(out, folder.TOLERANCE_FILES) as staging:
        _write_into(result, staging)
    return ["tolerance.json", "report.html"]


def _write_into(result: ToleranceAnalysis, out: Path) -> None:
    write_text(out / "tolerance.json", json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
    figures = []
    for name, o in result.outputs.items():
        drawn = None if result.samples is None else result.samples.loc[result.samples[STATUS] == "ok", name].to_numpy(dtype=float)
        figures += tolerance_figures(name, o.nominal, o.rss, o.shares, drawn)
    title = f"{result.model}: tolerances, analysis {result.analysis}"
    body = [f"<h1>{html.escape(title)}</h1>", "<pre>" + html.escape("\n".join(table_lines(result))) + "</pre>"]
    body.append('<div class="plots">' + "".join(f'<div id="figure{k}"></div>' for k in range(len(figures))) + "</div>")
    write_text(out / "report.html", page.document(title, body, figures, page.plotly_js(), page.FIGURES_SCRIPT))
