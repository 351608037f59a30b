"""The ``linkwork`` command line.

::

    linkwork run MODEL [--analysis NAME] [--out DIR]   run an analysis, write results.csv, summary.json,
        [--no-report]                                  model.yaml and report.html (not with --no-report)
        [--integrator bdf|hht|abam] [--rtol R] [--atol A] [--t-end T] [--step H]
                                                       change the analysis for this run
        [--stream [csv|parquet]]                       write the rows as they are computed
        [--units si|display]                           results.csv in SI (default) or the display units
        [--sensitivities NAME,NAME... | all]           also sensitivities.csv: the derivatives of every
                                                       column (and in summary.json of every summary)
                                                       with respect to those parameters (kinematic)
    linkwork report DIR                                rebuild DIR/report.html from the files of a run
    linkwork sweep MODEL --output NAME=EXPR ...         an analysis over many parameter values, reduced to
        (--grid NAME=START:STOP:COUNT ... |             outputs: DIR/sweep.parquet, one row a variant
         --sample N --range NAME=LOW:HIGH ... [--seed S])
        [--workers K | --dask ADDRESS] [--set NAME=VALUE] [--units si|display] [--gradients]
    linkwork tolerance MODEL --output NAME=EXPR ...     the spread of outputs over the parameters' tolerances:
        [--analysis NAME] [--samples N] [--seed S]      linear (gradients) beside Monte Carlo, printed and in
        [--workers K | --dask ADDRESS] [--out DIR]      DIR/tolerance.json and DIR/report.html
    linkwork check MODEL [--json]                      degrees of freedom, redundant rows, assembly
    linkwork schema                                    the JSON Schema of model files

A parameter's value from outside (--set, --grid, --range) is a number with a unit (``m="16 mm"``)
or a bare number, which is SI whatever unit the file writes it in; a bare number more than 100
times from the file's value is warned of (``--set m=16`` for ``m: 15 mm`` is 16 m). The output
shows the units of the model's ``display:`` section; the files stay SI unless ``--units display``
is given (``summary.json`` gives the unit of every column of ``results.csv``, the Parquet file of
a sweep of each of its columns).

Exit status: 0 success; 2 an invalid model, a file that cannot be read or written, or a bad command
line (every problem is printed as ``path: message``); 3 a solver failure (what failed, when, in
which joints; the results computed until then are still written); 130 interrupted by Ctrl-C (the
results until then are written, ``"status": "interrupted"``), 143 by SIGTERM and 129 by SIGHUP
(the same way); 1 an internal error (a bug).

An output folder is written whole (:mod:`linkwork.folder`): claimed before the run (a folder that
cannot be written, or that another run is writing, fails at once), written in a staging folder
beside it, then swapped into place in one step.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from . import _linkwork, folder, page
from .errors import AssemblyError, FileError, LinkworkError, ModelError, SolverError, model_error
from .model import Model
from .report import from_folder
from .results import Results
from .summary import Summary, branch_lines
from .sweep import STATUS, check_count, grid_values, name_problem, range_values, sweep, workers_to_use
from .tolerance import SAMPLES, table_lines, tolerance
from .units import SYSTEMS, Units

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_MODEL = 2
EXIT_SOLVER = 3
# 128 + SIGINT, as a shell reports a process that Ctrl-C ended.
EXIT_INTERRUPTED = 130

# Signals that stop a command as Ctrl-C does: a service manager's or `kill`'s request to end
# (SIGTERM), and a closed terminal (SIGHUP).
STOP_SIGNALS = ("SIGTERM", "SIGHUP")

# Seconds to wait for a Dask scheduler to answer: a scheduler on a network answers in
# milliseconds; a wrong address should fail while the user is still looking.
DASK_CONNECT_TIMEOUT = 10

# The coordinates of one body, in the engine's order.
COORDINATES = ("x", "y", "phi")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); return the exit status."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, or a usage error (status 2)
        return exit_.code if isinstance(exit_.code, int) else EXIT_MODEL
    handled = _handle_signals()
    try:
        status: int = args.command(args)
        return status
    except ModelError as error:
        _print_problems(error, getattr(args, "model", None))
        return exit_status(error)
    except (SolverError, AssemblyError) as error:  # from `check`: `run` handles its own
        _print_failure(error)
        return exit_status(error)
    # A file the command reads or writes (named by the system's message), a bad option, a bug.
    except (LinkworkError, OSError, OptionError) as error:
        _err(f"error: {error}")
        return exit_status(error)
    except KeyboardInterrupt as interrupt:
        _err(_what(interrupt))
        return exit_status(interrupt)
    finally:
        for signum, handler in handled.items():
            signal.signal(signum, handler)


def exit_status(error: BaseException) -> int:
    """The exit status of a command that raised ``error``: 2 for an invalid model, a file that
    cannot be read or written, or a bad option; 3 for a solver failure (an analysis's, or an
    assembly's); 130 for Ctrl-C, 143 and 129 for SIGTERM and SIGHUP; 1 for an internal error,
    and for a kind of :class:`LinkworkError` this command line does not know yet."""
    if isinstance(error, KeyboardInterrupt):
        return _interrupted(error)
    if isinstance(error, (SolverError, AssemblyError)):
        return EXIT_SOLVER
    if isinstance(error, (ModelError, OptionError)):
        return EXIT_MODEL
    # FileError is an OSError; an internal error is none.
    if isinstance(error, OSError):
        return EXIT_MODEL
    return EXIT_INTERNAL


class Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised where Ctrl-C raises ``KeyboardInterrupt`` so that a run stops
    the same way (its results until then written, ``"status": "interrupted"``)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _stop(signum: int, _frame: object) -> None:
    raise Stopped(signum)


def _handle_signals() -> dict[int, Any]:
    """Handle SIGTERM and SIGHUP (where the system has them) as Ctrl-C for the length of a
    command; the handlers before, to put back. Only the main thread may set handlers: called
    from another (an embedding program's), nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    before = {}
    for name in STOP_SIGNALS:
        signum = getattr(signal, name, None)
        if signum is not None:
            before[signum] = signal.signal(signum, _stop)
    return before


def _what(interrupt: KeyboardInterrupt) -> str:
    """``interrupted``, and by which signal when it was not Ctrl-C."""
    return f"interrupted by {interrupt}" if isinstance(interrupt, Stopped) else "interrupted"


def _interrupted(interrupt: KeyboardInterrupt) -> int:
    """The exit status of a command stopped by ``interrupt``: 130 for Ctrl-C, 128 + the
    signal's number for SIGTERM (143) and SIGHUP (129), as a shell reports a process they end."""
    return 128 + interrupt.signum if isinstance(interrupt, Stopped) else EXIT_INTERRUPTED


class OptionError(Exception):
    """A command-line option that cannot be used, said in one line naming it (exit 2)."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{option}: {message}")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="linkwork",
        description="Planar multibody kinematics: check and run mechanism models.",
        epilog="Exit status: 0 success, 2 invalid model or file, 3 solver failure, 130 interrupted, 1 internal error.",
    )
    parser.add_argument("--version", action="version", version=f"linkwork {_linkwork.__version__}")
    commands = parser.add_subparsers(title="commands", required=True, metavar="COMMAND")

    run = commands.add_parser(
        "run",
        help="run an analysis and write results.csv, summary.json, model.yaml and report.html",
        description="Run an analysis of MODEL and write results.csv, summary.json, model.yaml (the model as run) "
        "and report.html (the animated mechanism and its plots, opens offline) into the output folder.",
    )
    run.add_argument("model", metavar="MODEL", help="model file (YAML)")
    run.add_argument("--analysis", "-a", metavar="NAME", help="analysis to run (default: the first in the file)")
    run.add_argument("--out", "-o", metavar="DIR", type=Path, help="output folder (default: out/<model file stem>/)")
    run.add_argument("--integrator", choices=("bdf", "hht", "abam"), help="integrator of a dynamic analysis")
    run.add_argument("--rtol", type=float, metavar="R", help="relative error tolerance of a dynamic analysis")
    run.add_argument("--atol", type=float, metavar="A", help="absolute error tolerance of a dynamic analysis")
    run.add_argument("--t-end", type=float, metavar="T", help="end time, s")
    run.add_argument("--step", type=float, metavar="H", help="output step, s")
    _add_set(run)
    run.add_argument(
        "--stream",
        nargs="?",
        const="csv",
        choices=("csv", "parquet"),
        help="write results.csv (or results.parquet) as the rows are computed, holding only a chunk of them "
        "in memory (for long runs of large models; the report reads the file back)",
    )
    _add_units(run, "results.csv (not with --stream, whose rows are written SI as they are computed)")
    run.add_argument(
        "--sensitivities",
        type=_sensitivities,
        metavar="NAME,NAME...|all",
        help="also write sensitivities.csv (sensitivities.parquet with --stream parquet): time, then "
        "d(<column>)/d(<parameter>) for these parameters (all: every one), SI per SI; summary.json gets the "
        "summaries' derivatives under sensitivities (every analysis type; dynamic ones integrated by bdf or abam)",
    )
    run.add_argument("--no-report", action="store_true", help="do not write report.html")
    run.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    run.set_defaults(command=_run)

    report = commands.add_parser(
        "report",
        help="rebuild report.html from a results folder",
        description="Rebuild DIR/report.html from the files `linkwork run` wrote into DIR: model.yaml, "
        "results.csv and summary.json.",
    )
    report.add_argument("folder", metavar="DIR", type=Path, help="a folder written by `linkwork run`")
    report.set_defaults(command=_report)

    sweep = commands.add_parser(
        "sweep",
        help="run an analysis over many parameter values and write sweep.parquet",
        description="Run an analysis of MODEL for every combination of the --grid values (or for --sample "
        "points of a Latin hypercube over the --range intervals), reduce each run to the --output expressions, "
        "and write DIR/sweep.parquet: one row per variant with its parameters (SI; --units display: in the display "
        "units), its status (ok, or the "
        "error class and message) and its outputs. The variants run on this machine's cores, or on a Dask "
        "cluster (--dask). A bare number is SI; give a unit on both ends to sweep in it. Exit status 3 when "
        "every variant fails.",
    )
    sweep.add_argument("model", metavar="MODEL", help="model file (YAML)")
    sweep.add_argument("--analysis", "-a", metavar="NAME", help="analysis to run (default: the first in the file)")
    _repeatable(
        sweep, "--grid", _grid, "NAME=START:STOP:COUNT",
        "COUNT evenly spaced values of the parameter NAME, ends included: numbers (SI) or both ends with a unit "
        "(m='12 mm:18 mm:7'); repeatable (all combinations)",
    )
    sweep.add_argument("--sample", type=int, metavar="N", help="N points of a Latin hypercube over the --range intervals")
    _repeatable(
        sweep, "--range", _range, "NAME=LOW:HIGH",
        "the interval of the parameter NAME for --sample: numbers (SI) or both ends with a unit (m='12 mm:18 mm'); "
        "repeatable",
    )
    sweep.add_argument("--seed", type=int, metavar="S", help="seed of the --sample (default: a fresh one, printed)")
    _repeatable(
        sweep, "--output", _output, "NAME=EXPR",
        f"an output: an expression of the aggregations {', '.join(_linkwork.AGGREGATIONS)} (at(time, ...)) "
        "of result columns (SI), such as stroke='max(slider.x) - min(slider.x)'; repeatable",
        required=True,
    )
    sweep.add_argument("--out", "-o", metavar="DIR", type=Path, help="output folder (default: out/<model file stem>_sweep/)")
    sweep.add_argument("--workers", "-j", type=int, metavar="K", help="threads (default: every core)")
    sweep.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run on the Dask cluster whose scheduler is at ADDRESS (tcp://host:8786; pip install 'linkwork[dask]')",
    )
    _add_set(sweep)
    _add_units(sweep, "the parameters' columns of sweep.parquet (its outputs stay SI)")
    sweep.add_argument(
        "--gradients",
        action="store_true",
        help="also each output's derivative with respect to every parameter of the model at each variant, "
        "columns d(<output>)/d(<parameter>), SI per SI (analyses with sensitivities)",
    )
    sweep.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    sweep.set_defaults(command=_sweep)

    tol = commands.add_parser(
        "tolerance",
        help="the spread of outputs over the parameters' tolerances, linear and Monte Carlo",
        description="For each --output of an analysis of MODEL, over the parameters the model file gives a "
        "tolerance (r: 150 mm ± 0.1 mm): its nominal value, its gradient, its linear worst case and root sum "
        "of squares, each parameter's share, and a Monte Carlo check (--samples variants drawn from the "
        "parameters' distributions on the sweep engine) with its confidence intervals. Printed, and written "
        "to DIR/tolerance.json and DIR/report.html.",
    )
    tol.add_argument("model", metavar="MODEL", help="model file (YAML)")
    tol.add_argument("--analysis", "-a", metavar="NAME", help="analysis to run (default: the first in the file)")
    _repeatable(
        tol, "--output", _output, "NAME=EXPR",
        "an output: a summary of the model by name (stroke=stroke) or an expression of aggregations of result "
        "columns as --output of sweep; repeatable",
        required=True,
    )
    tol.add_argument(
        "--samples", type=int, default=SAMPLES, metavar="N",
        help=f"Monte Carlo samples (default {SAMPLES:,}; 0: the linear analysis alone)",
    )
    tol.add_argument("--seed", type=int, metavar="S", help="seed of the samples (default: a fresh one, printed)")
    tol.add_argument("--out", "-o", metavar="DIR", type=Path, help="output folder (default: out/<model file stem>_tolerance/)")
    tol.add_argument("--workers", "-j", type=int, metavar="K", help="threads (default: every core)")
    tol.add_argument("--dask", metavar="ADDRESS", help="run the samples on the Dask cluster whose scheduler is at ADDRESS")
    _add_set(tol)
    tol.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    tol.set_defaults(command=_tolerance)

    check = commands.add_parser(
        "check",
        help="degrees of freedom, redundant constraints and assembly",
        description="Check MODEL: degrees of freedom (Gruebler and from the rank of the Jacobian), "
        "redundant rows by joint and equation, and assembly of the initial guess, for the mechanism "
        "alone and for each analysis with its drivers.",
    )
    check.add_argument("model", metavar="MODEL", help="model file (YAML)")
    check.add_argument("--json", action="store_true", help="print the report as JSON")
    check.set_defaults(command=_check)

    schema = commands.add_parser("schema", help="print the JSON Schema of model files")
    schema.set_defaults(command=_schema)
    return parser


# --- run -----------------------------------------------------------------------------------------


def _repeatable(
    command: argparse.ArgumentParser, flag: str, kind: Callable[[str], Any], metavar: str, help: str, required: bool = False
) -> None:
    """The option ``flag`` of ``command``, given any number of times: the list of its values, each
    read by ``kind``."""
    command.add_argument(flag, action="append", default=[], type=kind, metavar=metavar, help=help, required=required)


def _add_set(command: argparse.ArgumentParser) -> None:
    _repeatable(
        command, "--set", _setting, "NAME=VALUE",
        "a parameter's value over the file's: a number with a unit (L='300 mm'), or a bare number, SI whatever "
        "unit the file uses (r=0.12), warned of when more than 100 times from the file's value; repeatable",
    )


def _add_units(command: argparse.ArgumentParser, what: str) -> None:
    command.add_argument(
        "--units",
        choices=SYSTEMS,
        default="si",
        help=f"the units of {what}: si (default), or display, those of the model's display: section; "
        "the units of every column are written beside it",
    )


def _setting(text: str) -> tuple[str, str]:
    """A ``--set NAME=VALUE`` option: the value's text as given (the engine reads a bare number
    as SI and converts one with a unit)."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, such as r=0.12 or L='300 mm', got '{text}'")
    return name.strip(), value.strip()


def _sensitivities(text: str) -> list[str] | bool:
    """A ``--sensitivities`` option: ``all`` (every parameter), or parameter names separated
    by commas (the engine checks them)."""
    if text.strip() == "all":
        return True
    names = [name.strip() for name in text.split(",")]
    if not all(names):
        raise argparse.ArgumentTypeError(f"expected NAME,NAME... (parameters of the model) or all, got '{text}'")
    return names


def _load(path: str, given: list[tuple[str, str]]) -> Model:
    """The model at ``path`` with the values ``given`` over its parameters, each of them printed
    (the header of a run or a sweep) with its unit, and any warning about them."""
    with warnings.catch_warnings():
        # Printed here, in the run's words, rather than as Python warnings.
        warnings.simplefilter("ignore")
        model = Model.load(path, dict(given))
    if given:
        units = dict(model._native.parameter_units)
        shown = []
        for name, text in dict(given).items():
            value = model.parameters[name]
            unit = units.get(name)
            in_unit = f"{value:.6g} SI" if unit is None else f"{value / _linkwork.unit(unit):.6g} {unit}"
            shown.append(f"{name} = {in_unit} (given {text})")
        print(f"parameters set: {'; '.join(shown)}")
    for warning in model._native.warnings:
        _err(f"warning: {warning}")
    return model


def _run(args: argparse.Namespace) -> int:
    model = _load(args.model, args.set)
    out: Path = args.out if args.out is not None else Path("out") / Path(args.model).stem
    if args.stream == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise model_error("--stream", "parquet needs pyarrow: pip install 'linkwork[parquet]'") from None
    if args.stream and args.units != "si":
        raise model_error("--units", "display cannot be used with --stream: the rows are written SI as they are computed")
    # Before the run: a folder that cannot be written, or that another run is writing, fails now.
    claimed = folder.claim(out, folder.run_files(model._native.table_files))
    try:
        return _run_into(args, model, out, claimed.staging)
    finally:
        claimed.release()


def _run_into(args: argparse.Namespace, model: Model, out: Path, staging: Path | None) -> int:
    """Run and write into ``out``, claimed with its ``staging`` folder: a stream goes there, and
    the results (whole, partial, or none) replace the folder at the end."""
    stream = staging / f"results.{args.stream}" if args.stream and staging is not None else None
    try:
        results = model.run(
            args.analysis,
            integrator=args.integrator,
            rtol=args.rtol,
            atol=args.atol,
            t_end=args.t_end,
            step=args.step,
            # On a terminal only: a bar in a log file is noise.
            progress=sys.stderr.isatty() and not args.quiet,
            stream=stream,
            sensitivities=args.sensitivities,
        )
    except ModelError as error:
        # The engine names the field of Model.run; here it is this option.
        problems: list[tuple[str, str]] = getattr(error, "problems", [])
        if problems and all(path == "sensitivities" for path, _ in problems):
            raise OptionError("--sensitivities", "; ".join(message for _, message in problems)) from None
        raise
    except KeyboardInterrupt as interrupt:
        partial = getattr(interrupt, "results", None)
        if not isinstance(partial, Results):
            raise
        partial.write(out, report=not args.no_report, units=args.units)
        _err(f"{_what(interrupt)}: partial results ({_span(partial)}) written to {_folder(out)} (status: interrupted)")
        return _interrupted(interrupt)
    except (SolverError, AssemblyError) as error:
        _print_failure(error)
        partial = error.results
        if isinstance(partial, Results):
            try:
                partial.write(out, report=not args.no_report, units=args.units)
            except FileError as write_error:
                _err(f"error: the partial results could not be written: {write_error}")
                return EXIT_SOLVER
            _err(f"partial results ({_span(partial)}) written to {_folder(out)} (status: failed)")
        return EXIT_SOLVER
    results.write(out, report=not args.no_report, units=args.units)
    _print_summary(results, args.units)
    files = [stream.name if stream is not None else "results.csv", "summary.json", *(["modes.csv"] if results.modes else []), "model.yaml"]
    if results.summary.sensitivities is not None:
        files.insert(1, f"sensitivities{stream.suffix if stream is not None else '.csv'}")
    files += [] if args.no_report else ["report.html"]
    print(f"wrote {_folder(out)}{', '.join(files[:-1])} and {files[-1]}")
    return EXIT_OK


def _report(args: argparse.Namespace) -> int:
    path: Path = args.folder
    # Held while the report is built: a run replacing the folder meanwhile would get a report of
    # the files before it.
    claimed = folder.claim(path, stage=False)
    try:
        page.write(path / "report.html", from_folder(path))
    except OSError as error:
        if isinstance(error, FileError):
            raise
        raise FileError(f"{path / 'report.html'}: cannot be written: {error.strerror or error}") from error
    finally:
        claimed.release()
    print(f"wrote {path / 'report.html'}")
    return EXIT_OK


def _print_summary(results: Results, written: str) -> None:
    s = results.summary
    stats = s.statistics or {}
    units = Units.of(results.model, results.columns)
    print(f"{s.model}: analysis '{s.analysis}' ({s.type})")
    drivers = ", ".join(s.active_drivers or []) or "none"
    print(f"  {s.bodies} bodies, {s.coordinates} coordinates; drivers: {drivers}")
    for line in branch_lines(s.branches or []):
        print(f"  {line}")
    print(f"  {_span(results, units)}")
    if not units.is_si():
        shown = ", ".join(f"{q} {units.unit(q)}" for q in ("length", "angle", "time", "force", "torque"))
        files = "results.csv is in them too" if written == "display" else "the files are SI"
        print(f"  shown in the model's display units ({shown}); {files}")
    if stats and s.type == "dynamic":
        integrator = s.integrator or {}
        print(
            f"  {integrator['kind']}: {stats['steps']} steps "
            f"({stats['rejected_steps']} rejected by the error test, "
            f"{stats['newton_failures']} by Newton), {stats['newton_iterations']} Newton iterations, "
            f"{stats['factorizations']} factorizations"
        )
        residuals = s.residuals or {}
        print(
            f"  largest constraint residuals at output: position {_num(residuals['max_position'])}, "
            f"velocity {_num(residuals['max_velocity'])}"
        )
    elif s.type == "static":
        print(
            f"  {stats['iterations']} Newton iterations, {stats['descents']} descent(s), "
            f"{stats['load_steps']} load steps; "
            f"largest residuals: force {_num(stats['force_residual'])}, "
            f"position {_num(stats['position_residual'])}; stable: {s.stable} (index {s.index})"
        )
    elif s.type == "modes":
        print(f"  {s.dof} degree(s) of freedom, linearised about the {s.about} state")
        if s.stable is False:
            print(f"  UNSTABLE: the {s.about} state is not a stable equilibrium; its unstable modes come first")
        for k, mode in enumerate(results.modes, 1):
            print(f"  mode {k}: {_describe_mode(mode)}")
    elif stats:
        print(
            f"  {stats['substeps']} sub-steps ({stats['rejected_substeps']} rejected), "
            f"{stats['newton_iterations']} Newton iterations, "
            f"{stats['factorizations']} factorizations"
        )
        print(
            f"  largest residual {_num(stats['max_residual'])}, "
            f"largest condition estimate {_num(stats['max_condition'])}"
        )
        redundant = [f"{r['element']}.{r['equation']}" for r in s.redundant_rows or []]
        if redundant:
            print(f"  redundant rows (hold implicitly): {', '.join(redundant)}")
    for name, value in results.summaries.items():
        print(f"  summary {name:<21} {value:.6g} (SI)")
    _print_peaks(s, units, results.model._native.warnings)


def _describe_mode(mode: dict[str, Any]) -> str:
    """One mode in words: an unstable one by its growth rate, never as a frequency."""
    kind = mode.get("kind")
    rate = mode.get("growth_rate")
    if kind == "divergence":
        return f"unstable, divergence: grows as exp({rate:.6g} t) (growth rate {rate:.6g} 1/s)"
    if kind == "flutter":
        return (
            f"unstable, growing oscillation at {mode['damped_frequency']:.6g} Hz "
            f"(growth rate {rate:.6g} 1/s)"
        )
    if kind == "neutral":
        return "neutral: no stiffness or damping along it (0 Hz)"
    zeta = mode.get("damping_ratio")
    damping = "" if zeta is None else f", damping ratio {zeta:.4g}"
    return f"{mode['frequency']:.6g} Hz{damping}"


def _print_peaks(s: Summary, units: Units, printed: list[str]) -> None:
    """The largest driver efforts and joint forces (in ``units``), the joints whose shares are
    open, and the warnings not ``printed`` before the run."""
    peaks = s.peaks or {}
    efforts = [name for name in peaks if name.endswith(".effort")]
    forces = sorted((n for n in peaks if n.endswith(".force")), key=lambda n: -peaks[n]["max_abs"])
    for name in efforts + forces[:5]:
        peak = peaks[name]
        # A joint's peak is its force's resultant, of the quantity of its fx column.
        column = f"{name.removesuffix('.force')}.fx" if name.endswith(".force") else name
        value = float(units.shown(column, peak["max_abs"]))
        time = units.value("time", peak["time"] or 0.0)
        print(f"  peak {name:<24} {_num(value)} {units.column_unit(column)} at t = {time:g} {units.unit('time')}")
    if len(forces) > 5:
        print(f"  ({len(forces) - 5} more joints' peaks in summary.json)")
    indeterminate = s.indeterminate_joints or []
    if indeterminate:
        print(
            f"  indeterminate joints (redundant supports; minimum-norm reactions): {', '.join(indeterminate)}"
        )
    for warning in s.warnings:
        if warning not in printed:
            print(f"  warning: {warning}")


def _print_failure(error: SolverError | AssemblyError) -> None:
    _err(f"error: {error}")
    where = []
    time = getattr(error, "time", None)
    if time is not None:
        where.append(f"at t = {time:.9g} s")
    joints = getattr(error, "joints", None) or []
    if joints:
        where.append(f"in joint(s) {', '.join(joints)}")
    coordinates = getattr(error, "coordinates", None) or []
    if coordinates:
        where.append(f"along {', '.join(coordinates)}")
    if where:
        what = "assembly failed" if isinstance(error, AssemblyError) else "the analysis failed"
        _err(f"  {what} {' '.join(where)}")


def _span(results: Results, units: Units | None = None) -> str:
    if results.streamed_to is not None:
        # The rows are in the file, not in memory: their count is the summary's.
        return f"{results.summary.output_points} output points, streamed"
    if len(results) == 0:
        return "no output points"
    units = units or Units.si()
    t0, t1 = (units.value("time", t) for t in (results.time[0], results.time[-1]))
    return f"{len(results)} output points, t = {t0:g} .. {t1:g} {units.unit('time')}"


def _folder(path: Path) -> str:
    text = str(path)
    return text if text.endswith(("/", "\\")) else text + "/"


# --- sweep ---------------------------------------------------------------------------------------


def _grid(text: str) -> tuple[str, list[float | str]]:
    try:
        return grid_values(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _range(text: str) -> tuple[str, tuple[float | str, float | str]]:
    try:
        return range_values(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _output(text: str) -> tuple[str, str]:
    name, sep, expression = text.partition("=")
    if not sep or not name.strip() or not expression.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=EXPR, such as stroke='max(slider.x) - min(slider.x)', got '{text}'")
    return name.strip(), expression.strip()


def _sweep(args: argparse.Namespace) -> int:
    if bool(args.grid) == (args.sample is not None or bool(args.range)):
        _err("error: give --grid, or --sample with --range, not both")
        return EXIT_MODEL
    if (args.sample is None) != (not args.range) or (args.seed is not None and args.sample is None):
        _err("error: --sample, --range and --seed go together (--seed is optional)")
        return EXIT_MODEL
    # A name given twice would keep its last value (or column) without a word.
    for option, given in (("--grid", args.grid), ("--range", args.range), ("--output", args.output)):
        names = [name for name, _ in given]
        twice = next((name for k, name in enumerate(names) if name in names[:k]), None)
        if twice is not None:
            raise OptionError(option, f"'{twice}' is given twice; give each name once")
    try:
        # The count of variants before any is made (a COUNT of 1000000000 filled the memory).
        if args.grid:
            check_count(math.prod(len(values) for _, values in args.grid), "--grid")
        if args.sample is not None:
            check_count(args.sample, "--sample")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            workers = workers_to_use(args.workers, "--workers")
        for early in caught:
            _err(f"warning: {early.message}")
    except ValueError as error:
        raise OptionError(*str(error).split(": ", 1)) from None
    model = _load(args.model, args.set)
    for name, _ in args.output:
        problem = name_problem(name, model.parameters)
        if problem is not None:
            raise OptionError("--output", f"{name}: {problem}")
    analysis = args.analysis if args.analysis is not None else model.analyses[0]
    out: Path = args.out if args.out is not None else Path("out") / (Path(args.model).stem + "_sweep")
    # Before the sweep: a folder that cannot be written, or that another run is writing, fails now.
    claimed = folder.claim(out, folder.SWEEP_FILES)
    try:
        return _sweep_into(args, model, analysis, out, workers)
    finally:
        claimed.release()


def _sweep_into(args: argparse.Namespace, model: Model, analysis: str, out: Path, workers: int | None) -> int:
    """Run the sweep on ``workers`` threads and write ``out``'s sweep.parquet (the table until
    then when interrupted)."""
    client = _dask_client(args.dask) if args.dask is not None else None
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            table = sweep(
                model, analysis, dict(args.grid) if args.grid else None, dict(args.output),
                sample=args.sample, ranges=dict(args.range) if args.range else None, seed=args.seed,
                workers=workers, client=client, progress=sys.stderr.isatty() and not args.quiet,
                units=args.units, gradients=args.gradients,
            )
        for warning in dict.fromkeys(str(w.message) for w in caught):
            _err(f"warning: {warning}")
    except KeyboardInterrupt as interrupt:
        partial = getattr(interrupt, "table", None)
        if partial is None:
            raise
        with folder.writing(out, folder.SWEEP_FILES) as staging:
            partial.to_parquet(staging / "sweep.parquet", index=False)
        done = int((~partial[STATUS].str.startswith("KeyboardInterrupt")).sum())
        _err(f"{_what(interrupt)}: {done} of {len(partial)} variants finished, written to {out / 'sweep.parquet'}")
        return _interrupted(interrupt)
    finally:
        if client is not None:
            client.close()
    with folder.writing(out, folder.SWEEP_FILES) as staging:
        table.to_parquet(staging / "sweep.parquet", index=False)
    failed = table[STATUS] != "ok"
    print(f"{model.name}: analysis '{analysis}', {len(table)} variants, {len(table) - int(failed.sum())} ok, {int(failed.sum())} failed")
    if "seed" in table.attrs:
        print(f"Latin hypercube seed {table.attrs['seed']} (--seed {table.attrs['seed']} draws the same sample)")
    print(f"wrote {out / 'sweep.parquet'}")
    if len(table) and failed.all():
        _err(f"error: every variant failed; the first: {table[STATUS].iloc[0]}")
        return EXIT_SOLVER
    if failed.any():
        _err(f"warning: {int(failed.sum())} of {len(table)} variants failed (their status in the table)")
    return EXIT_OK


def _dask_client(address: str) -> Any:
    """A Dask client of the scheduler at ``address``."""
    try:
        from distributed import Client
    except ImportError:
        raise model_error("--dask", "needs Dask's distributed package: pip install 'linkwork[dask]'") from None
    try:
        return Client(address, timeout=DASK_CONNECT_TIMEOUT)
    except OSError as error:
        raise model_error("--dask", f"no Dask scheduler answered at {address}: {error}") from None
    except ValueError as error:  # not an address: "missing port number", "unknown address scheme"
        raise OptionError("--dask", f"expected the scheduler's address, such as tcp://host:8786: {error}") from None


# --- tolerance -----------------------------------------------------------------------------------


def _tolerance(args: argparse.Namespace) -> int:
    names = [name for name, _ in args.output]
    twice = next((name for k, name in enumerate(names) if name in names[:k]), None)
    if twice is not None:
        raise OptionError("--output", f"'{twice}' is given twice; give each name once")
    if args.samples < 0:
        raise OptionError("--samples", f"expected a count of at least 0, got {args.samples}")
    try:
        workers = workers_to_use(args.workers, "--workers")
    except ValueError as error:
        raise OptionError(*str(error).split(": ", 1)) from None
    model = _load(args.model, args.set)
    analysis = args.analysis if args.analysis is not None else model.analyses[0]
    out: Path = args.out if args.out is not None else Path("out") / (Path(args.model).stem + "_tolerance")
    claimed = folder.claim(out, folder.TOLERANCE_FILES)
    client = _dask_client(args.dask) if args.dask is not None else None
    try:
        result = tolerance(
            model, analysis, dict(args.output), samples=args.samples, seed=args.seed, workers=workers, client=client,
            progress=sys.stderr.isatty() and not args.quiet,
        )
        written = result.write(out)
    finally:
        if client is not None:
            client.close()
        claimed.release()
    print("\n".join(table_lines(result)))
    print(f"wrote {_folder(out)}{' and '.join(written)}")
    return EXIT_OK


# --- check ---------------------------------------------------------------------------------------


def _check(args: argparse.Namespace) -> int:
    model = Model.load(args.model)
    report = model.check()
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        print()
        return EXIT_OK
    bodies: list[str] = report["bodies"]
    units = Units.of(model, report["coordinate_names"])
    print(report["model"] or Path(args.model).name)
    print(f"bodies: {', '.join(bodies)} ({len(bodies)} bodies, {report['coordinates']} coordinates)")
    if report["placed"]:
        # Twelve digits: enough to paste back into the file, few enough to read.
        print("placed from global coordinates, in body frames (points in m, axes as directions):")
        for path, (x, y) in report["placed"].items():
            print(f"  {path:<32} [{x:.12g}, {y:.12g}]")
    print()
    _print_system("mechanism (joints only; coordinates marked given held)", report["mechanism"], bodies, units)
    for name, system in report["analyses"].items():
        print()
        if system["error"] is not None:
            print(f"analysis '{name}' ({system['kind']}): cannot be assembled: {system['error']}")
            continue
        drivers = ", ".join(system["drivers"]) or "no drivers"
        _print_system(f"analysis '{name}' ({system['kind']}; joints and {drivers})", system, bodies, units)
        if system["warning"] is not None:
            print(f"  warning              {system['warning']}")
    return EXIT_OK


def _print_system(title: str, system: dict[str, Any], bodies: list[str], units: Units) -> None:
    n = 3 * len(bodies)
    print(f"{title}:")
    print(f"  equations            {system['equations']}")
    print(f"  degrees of freedom   {system['dof']} (coordinates - rank of Phi_q = {n} - {system['rank']})")
    print(f"  Gruebler count       {system['gruebler_dof']} (coordinates - equations = {n} - {system['equations']})")
    redundant = system["redundant"]
    if redundant:
        print(f"  redundant rows       {len(redundant)}:")
        for row in redundant:
            print(f"    joint {row['element']}, equation {row['equation']}")
    else:
        print("  redundant rows       none")
    if system.get("indeterminate"):
        print(
            f"  indeterminate joints {', '.join(system['indeterminate'])} "
            "(reactions not unique; the minimum-norm ones are reported)"
        )
    assembly = system["assembly"]
    print(
        f"  assembly             residual {_num(assembly['residual'])} after {assembly['iterations']} "
        f"iteration(s); velocity residual {_num(assembly['velocity_residual'])}"
    )
    for line in branch_lines(system.get("branches", [])):
        print(f"  {line}")
    for warning in system.get("warnings", []):
        print(f"  warning: {warning}")
    change: list[float] = assembly["change"]
    names = [f"{b}.{c}" for b in bodies for c in COORDINATES]  # = report["coordinate_names"]
    if change:
        # In the model's display units, as every number the command line shows.
        shown = [float(units.shown(name, v)) for name, v in zip(names, change)]
        k = max(range(len(change)), key=lambda i: abs(change[i]))
        print(f"  change from guess    largest {names[k]} {shown[k]:+.6g} {units.column_unit(names[k])}")
        width = max(len(b) for b in bodies)
        length, angle = units.unit("length"), units.unit("angle")
        print(f"    {'':{width}}  {f'x ({length})':>11} {f'y ({length})':>11} {f'phi ({angle})':>11}")
        for i, body in enumerate(bodies):
            cells = " ".join(f"{v:+11.3e}" for v in shown[3 * i : 3 * i + 3])
            print(f"    {body:{width}}  {cells}")


# --- schema --------------------------------------------------------------------------------------


def _schema(_args: argparse.Namespace) -> int:
    print(_linkwork.schema())
    return EXIT_OK


# --- output --------------------------------------------------------------------------------------


def _print_problems(error: ModelError, model: str | None) -> None:
    problems: list[tuple[str, str]] = getattr(error, "problems", [])
    where = f" {model}" if model else ""
    _err(f"error: invalid model{where} ({len(problems)} problem{'s' if len(problems) != 1 else ''}):")
    for path, message in problems:
        _err(f"{path}: {message}" if path else message)


def _num(value: object) -> str:
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def _err(text: str) -> None:
    print(text, file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
