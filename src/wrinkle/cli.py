"""Command line: ``wrinkle run CASE --out DIR``, ``wrinkle plot DIR``, ``wrinkle demo``.

Exit status: 0 done; 1 a load step did not converge (every converged step is on disk);
2 bad input (a one-line message naming the file, key, node or element).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from wrinkle.solvers import SOLVERS, ConvergenceError


def _demo(args: argparse.Namespace) -> int:
    from wrinkle.demo import run_demo

    rows = run_demo(Path(args.out), method=args.method)
    worst = max(r.relative_error for r in rows)
    print(f"{'f':>4} {'v':>6} {'F1':>14} {'F2':>14} {'state':>9} {'iter':>4}")
    for r in rows:
        print(f"{r.f:4g} {r.v:6.3f} {r.F1:14.10f} {r.F2:14.10f} {r.state:>9} {r.iterations:4d}")
    print(f"largest relative difference from the analytic solution: {worst:.2e}")
    print(f"wrote {Path(args.out) / 'shear_stretch.csv'} and {Path(args.out) / 'shear_stretch.png'}")
    return 0


def _run(args: argparse.Namespace) -> int:
    from wrinkle.case import read_case
    from wrinkle.output import ResultWriter
    from wrinkle.progress import Progress

    model = read_case(args.case)
    writer = ResultWriter(args.out, model, probes=model.probes, units=model.units,
                          case=args.case)
    progress = Progress(quiet=args.quiet)

    def on_step(step):
        writer.write_step(step)
        progress.step(step)

    try:
        model.solve(on_step=on_step)
    except ConvergenceError as error:
        progress.close()
        writer.finish(False, f"not converged: {error}")
        print(f"wrinkle: {args.case}: not converged: {error}", file=sys.stderr)
        print(f"wrinkle: the converged steps are in {args.out}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        progress.close()
        writer.finish(False, "interrupted")
        print(f"wrinkle: interrupted; the converged steps are in {args.out}", file=sys.stderr)
        return 130
    writer.finish(True, "converged to load factor 1")
    if not args.quiet:
        print(f"wrote {args.out}/results.pvd, summary.json, history.csv")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from wrinkle.plot import plot_results

    for path in plot_results(Path(args.directory)):
        print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wrinkle", description="Finite-element analysis of wrinkling membranes."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every iteration")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser(
        "demo", help="the paper's shear-stretch test (Roddeman et al. 1987, Figs. 6-7)"
    )
    demo.add_argument("--out", default="demo-results", help="output directory")
    demo.add_argument("--method", choices=sorted(SOLVERS), default="newton")
    demo.set_defaults(run=_demo)
    run = sub.add_parser("run", help="run the analysis described by a TOML case file")
    run.add_argument("case", help="case file (TOML)")
    run.add_argument("--out", default="results", help="output directory")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress display")
    run.set_defaults(run=_run)
    plot = sub.add_parser("plot", help="pictures of the results in a directory")
    plot.add_argument("directory", help="directory written by wrinkle run")
    plot.set_defaults(run=_plot)
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(message)s"
    )
    try:
        return args.run(args)
    except ConvergenceError as error:
        print(f"wrinkle: not converged: {error}", file=sys.stderr)
        return 1
    except (ValueError, OSError, ImportError) as error:  # bad input: one line, no traceback
        print(f"wrinkle: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
