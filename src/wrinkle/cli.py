"""Command line: ``wrinkle demo --out DIR``."""

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
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(message)s"
    )
    try:
        return args.run(args)
    except ConvergenceError as error:
        print(f"wrinkle: not converged: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
