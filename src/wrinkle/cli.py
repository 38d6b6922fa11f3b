"""Command line: ``wrinkle run CASE [--out DIR] [--restart] [-q]``, ``wrinkle formfind
CASE [--out DIR] [-q]``, ``wrinkle plot DIR [--load LOAD]``, ``wrinkle show DIR``,
``wrinkle study STUDY [--out DIR] [--scheduler ADDRESS] [--workers N] [-q]``, ``wrinkle
--version`` (also ``python -m wrinkle ...``).

``run`` solves a TOML case file and writes each converged step into DIR as it converges
(``wrinkle.case.Case.run``; with a [formfinding] table it form-finds first; ``--restart``
continues from the last converged step in DIR); ``formfind``
form-finds the case (its [formfinding] table, or the defaults) without its loads and writes
the found form into DIR, with ``formfound.msh``; ``plot`` draws the pictures of such a
directory (``wrinkle.plot.plot_results``; ``--load``: pressure, load_factor or a support's
label on the load axis of load_displacement.png); ``show`` opens an interactive view of the
last step (``wrinkle.show.show_results``, needs the ``viz`` extra, pyvista); ``study`` runs
the variants of a parameter study into DIR/study.csv, a folder per variant and pictures
(``wrinkle.studies``); ``-v`` before the command logs every iteration.

Exit status: 0 done; 1 a load step did not converge, no form was found, the last state has
no natural modes ([modes] on an unstable state), a variant of a study did not answer (the
study table has them all), or a results file could not be written
(every converged step written before is on disk); 2 bad input (a one-line message naming
the file, key, node or element, or a missing optional dependency); 130 interrupted.

The paper's test and the verification gallery are not commands of the installed program: they
live in the repository (``python examples/paper_test.py``, ``python -m verification``).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
import warnings
from pathlib import Path

import numpy as np

from wrinkle import __version__
from wrinkle.solvers import ConvergenceError, listening

__all__ = ["main"]


def _run(args: argparse.Namespace) -> int:
    from wrinkle.case import FORM_MESH, FormFindingSettings, NoModesError, read_case
    from wrinkle.formfinding import FormFindingError
    from wrinkle.output import ResultsWriteError
    from wrinkle.progress import Progress
    from wrinkle.reader import SUMMARY, open_results

    case = read_case(args.case)
    form_only = args.command == "formfind"
    if form_only and case.form_finding is None:
        case.form_finding = FormFindingSettings()
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: is a file, not a folder for the results")
    progress = Progress(quiet=args.quiet)
    progress.staged = bool(case.steps)
    try:
        restart = getattr(args, "restart", False)
        if restart and (out / SUMMARY).is_file():  # number the new steps after the old
            with contextlib.suppress(ValueError):
                progress.count = len(open_results(out))
        with listening(progress.iteration):
            case.run(args.out, on_step=progress.step, loads=not form_only, restart=restart)
    except (FormFindingError, NoModesError) as error:
        progress.close()
        print(f"wrinkle: {error}", file=sys.stderr)
        return 1
    except ConvergenceError as error:
        progress.close()
        print(f"wrinkle: {args.case}: not converged: {error}", file=sys.stderr)
        results = getattr(error, "results", None)
        if results is not None and not results.steps:
            print(f"wrinkle: no load step converged; {args.out} holds no step", file=sys.stderr)
        else:
            print(f"wrinkle: the converged steps are in {args.out}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        progress.close()
        print(f"wrinkle: interrupted; the converged steps are in {args.out}", file=sys.stderr)
        return 130
    except ResultsWriteError as error:
        progress.close()
        print(
            f"wrinkle: {args.case}: {error}; the steps written before it are in {args.out}",
            file=sys.stderr,
        )
        return 1
    if not args.quiet:
        found = f", {FORM_MESH}" if case.form_finding is not None else ""
        collection = "results.xdmf" if case.output.file_format == "xdmf" else "results.pvd"
        print(f"wrote {args.out}/{collection}, summary.json, history.csv{found}")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from wrinkle.plot import DamagedResults, plot_results

    try:
        paths = plot_results(Path(args.directory), load=args.load)
    except DamagedResults as damaged:  # the readable steps are drawn; say what is not
        for path in damaged.paths:
            print(f"wrote {path}")
        print(f"wrinkle: {damaged}", file=sys.stderr)
        return 2
    for path in paths:
        print(f"wrote {path}")
    return 0


def _study(args: argparse.Namespace) -> int:
    from wrinkle.studies import read_study, run_study, write_table
    from wrinkle.studies.table import TRAILING, columns

    study = read_study(args.study)
    paths = [parameter.path for parameter in study.parameters]
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: is a file, not a folder for the study")
    rows: dict[int, dict] = {}
    total = len(study.variants)

    def finished(row: dict) -> None:
        rows[int(row["variant"])] = row
        write_table([rows[k] for k in sorted(rows)], out, paths, study.collect)
        if not args.quiet:
            print(
                f"variant {int(row['variant']):4d}  ({len(rows)} of {total})  {row['status']}"
                f"  {float(row['seconds']):.1f} s",
                file=sys.stderr,
            )

    table = run_study(study, out, args.scheduler, args.workers, on_row=finished)
    write_table(table, out, paths, study.collect)
    names = columns(table, paths, study.collect)
    quantities = [name for name in names if name not in {"variant", *paths, *TRAILING}]
    try:
        from wrinkle.studies.pictures import plot_study

        plot_study(table, out, paths, quantities)
    except ImportError as error:  # matplotlib missing: the table stands
        print(f"wrinkle: no pictures: {error}", file=sys.stderr)
    failed = [row for row in table if row["status"] != "converged"]
    if not args.quiet:
        print(f"wrote {out}/study.csv: {total} variants, {len(failed)} failed", file=sys.stderr)
    if failed:
        first = failed[0]
        print(
            f"wrinkle: {len(failed)} of {total} variants did not answer, the first "
            f"(variant {first['variant']}): {first['status']}: {first['message']}",
            file=sys.stderr,
        )
        return 1
    return 0


def _fit(args: argparse.Namespace) -> int:
    from wrinkle.identification import read_fit, run_fit, write_picture, write_report
    from wrinkle.identification.fit import DaskEngine, LocalEngine

    problem = read_fit(args.fit)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: is a file, not a folder for the fit")
    engine: LocalEngine | DaskEngine = LocalEngine()
    if args.scheduler is not None or (args.workers or 1) > 1:
        from wrinkle.studies.run import dask_client

        client = dask_client(args.scheduler, args.workers or 1, required=True)
        engine = DaskEngine(client, owns_cluster=args.scheduler is None)

    def progress(row: dict) -> None:
        if not args.quiet:
            values = ", ".join(f"{k} = {v:.6g}" for k, v in row["parameters"].items())
            state = "  (a solve failed)" if row["failed"] else ""
            print(
                f"evaluation {row['evaluation']:3d}  cost {row['cost']:.4e}  {values}{state}",
                file=sys.stderr,
            )

    result = run_fit(problem, engine, on_evaluation=progress)
    write_report(result, out)
    try:
        write_picture(result, out)
    except ImportError as error:  # matplotlib missing: the numbers stand
        print(f"wrinkle: no picture: {error}", file=sys.stderr)
    if not args.quiet:
        print(f"wrote {out}/fit.json: {result.message}", file=sys.stderr)
    if not result.converged:
        print(f"wrinkle: the fit did not converge: {result.message}", file=sys.stderr)
        return 1
    return 0


def _show(args: argparse.Namespace) -> int:
    from wrinkle.show import show_results

    show_results(Path(args.directory))
    return 0


def _cluster_options(parser: argparse.ArgumentParser, scheduler: str, workers: str) -> None:
    """--scheduler, --workers and --quiet of the commands that may run on a Dask cluster."""
    parser.add_argument("--scheduler", default=None, help=scheduler)
    parser.add_argument("--workers", type=int, default=None, help=workers)
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress lines")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wrinkle", description="Finite-element analysis of wrinkling membranes."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every iteration")
    parser.add_argument("--version", action="version", version=f"wrinkle {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run the analysis described by a TOML case file")
    run.add_argument("case", help="case file (TOML)")
    run.add_argument("--out", default="results", help="output directory")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress display")
    run.add_argument(
        "--restart",
        action="store_true",
        help="continue from the last converged step in the output directory",
    )
    run.set_defaults(run=_run)
    formfind = sub.add_parser(
        "formfind", help="form-find a case file's prestressed membrane (without its loads)"
    )
    formfind.add_argument("case", help="case file (TOML)")
    formfind.add_argument("--out", default="results", help="output directory")
    formfind.add_argument("-q", "--quiet", action="store_true", help="no progress display")
    formfind.set_defaults(run=_run)
    plot = sub.add_parser("plot", help="pictures of the results in a directory")
    plot.add_argument("directory", help="directory written by wrinkle run")
    plot.add_argument(
        "--load",
        default=None,
        help="load axis of load_displacement.png: pressure, load_factor or a support's label "
        "(default: the pressure if the run has one, else the load factor)",
    )
    plot.set_defaults(run=_plot)
    study = sub.add_parser("study", help="run the variants of a parameter study (docs/studies.md)")
    study.add_argument("study", help="study file (TOML)")
    study.add_argument("--out", default="study", help="output directory")
    _cluster_options(
        study,
        "address of a Dask scheduler (tcp://HOST:PORT); default: a local cluster of the "
        "machine's cores (local processes without Dask)",
        "local worker processes (default: the cores)",
    )
    study.set_defaults(run=_study)
    fit = sub.add_parser("fit", help="identify case parameters from measured curves (docs/fit.md)")
    fit.add_argument("fit", help="fit file (TOML)")
    fit.add_argument("--out", default="fit", help="output directory")
    _cluster_options(
        fit,
        "address of a Dask scheduler (tcp://HOST:PORT) to solve the experiments on; "
        "default: this process",
        "a local Dask cluster of this many workers",
    )
    fit.set_defaults(run=_fit)
    show = sub.add_parser(
        "show", help="interactive view of the last step (needs pyvista: wrinkle[viz])"
    )
    show.add_argument("directory", help="directory written by wrinkle run")
    show.set_defaults(run=_show)
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(message)s"
    )
    try:
        # no numpy warning reaches the terminal: every result is checked for finite numbers
        # and an admissible state before it is accepted, and a failure says so in one line
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return args.run(args)
    except ConvergenceError as error:
        print(f"wrinkle: not converged: {error}", file=sys.stderr)
        return 1
    except (ValueError, OSError, ImportError) as error:  # bad input: one line, no traceback
        print(f"wrinkle: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
