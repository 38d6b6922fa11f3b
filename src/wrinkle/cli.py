"""Command line: ``wrinkle run CASE --out DIR``, ``wrinkle plot DIR``, ``wrinkle demo``,
``wrinkle verify --out DIR [--quick]``.

Exit status: 0 done; 1 a load step did not converge (every converged step is on disk), or a
verification benchmark failed;
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
    from wrinkle.progress import Progress

    case = read_case(args.case)
    progress = Progress(quiet=args.quiet)
    try:
        case.run(args.out, on_step=progress.step)
    except ConvergenceError as error:
        progress.close()
        print(f"wrinkle: {args.case}: not converged: {error}", file=sys.stderr)
        print(f"wrinkle: the converged steps are in {args.out}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        progress.close()
        print(f"wrinkle: interrupted; the converged steps are in {args.out}", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"wrote {args.out}/results.pvd, summary.json, history.csv")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from wrinkle.plot import plot_results

    for path in plot_results(Path(args.directory)):
        print(f"wrote {path}")
    return 0


def _verify(args: argparse.Namespace) -> int:
    from wrinkle.verification.gallery import run_gallery

    def report(entry):
        if args.quiet:
            return
        outcome = entry.outcome
        if outcome is None:
            print(f"{entry.benchmark.name:>18}: FAILED to run ({entry.error})", flush=True)
            return
        failed = [c.quantity for c in outcome.checks if not c.passed]
        verdict = "pass" if entry.passed else f"FAIL ({'; '.join(failed) or 'no checks'})"
        print(f"{entry.benchmark.name:>18}: {verdict}, {len(outcome.checks)} checks, "
              f"{entry.seconds:.1f} s", flush=True)

    path = Path(args.report) if args.report else Path(args.out) / "report.md"
    entries = run_gallery(Path(args.cases), Path(args.out), quick=args.quick, only=args.only,
                          on_entry=report, report=path)
    passed = sum(entry.passed for entry in entries)
    if not args.quiet:
        print(f"{passed} of {len(entries)} benchmarks pass; wrote {path}")
    return 0 if passed == len(entries) else 1


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
    verify = sub.add_parser(
        "verify", help="run the verification gallery and write DIR/report.md"
    )
    verify.add_argument("--out", default="verification", help="output directory")
    verify.add_argument("--quick", action="store_true", help="coarse meshes (minutes, not tens)")
    verify.add_argument("--cases", default="examples/verification",
                        help="folder of the benchmark case files")
    verify.add_argument("--only", action="append", default=[], metavar="NAME",
                        help="run only this benchmark (may be repeated)")
    verify.add_argument("--report", help="where to write the report (default DIR/report.md)")
    verify.add_argument("-q", "--quiet", action="store_true", help="no per-benchmark lines")
    verify.set_defaults(run=_verify)
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
