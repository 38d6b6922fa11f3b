"""``python -m verification``: run the verification gallery and write its report.

    python -m verification [--out DIR] [--quick] [--only NAME ...] [--report PATH]
                           [--cases DIR] [-q] [-v]

Runs every benchmark of the registry below (or those named with ``--only``) from the case
files in ``--cases`` (default: ``verification/cases`` of this checkout, wherever the command is
run from), writes each one's figures into ``DIR/<name>/`` and the report into ``DIR/report.md``
(or ``--report``). ``--quick`` takes the coarse meshes of each case's [verification] table
(minutes, not tens). Exit status: 0 if every check of every benchmark passes, 1 otherwise, 2
for bad input (an unknown benchmark, a missing case file: one line, no traceback).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from verification.benchmarks import (
    airbag,
    annulus_hub,
    balloon,
    cable_arc,
    catenoid,
    inflated_cylinder,
    lame_annulus,
    membrane_beam,
    membrane_frequencies,
    prestressed_square,
    shear_stretch,
    simple_shear,
    sphere,
)
from verification.report import Benchmark, Entry, run_gallery

__all__ = ["CASES", "MODULES", "benchmarks", "main"]

CASES = Path(__file__).resolve().parent / "cases"

# the registry: the benchmarks in the order of the report
MODULES = (
    shear_stretch,
    simple_shear,
    annulus_hub,
    lame_annulus,
    membrane_beam,
    airbag,
    inflated_cylinder,
    sphere,
    balloon,
    prestressed_square,
    catenoid,
    cable_arc,
    membrane_frequencies,
)


def benchmarks() -> list[Benchmark]:
    """Every benchmark of the gallery, in the order of the report."""
    return [module.BENCHMARK for module in MODULES]


def _printer(quiet: bool):
    def report(entry: Entry) -> None:
        if quiet:
            return
        outcome = entry.outcome
        if outcome is None:
            print(f"{entry.benchmark.name:>18}: FAILED to run ({entry.error})", flush=True)
            return
        failed = [c.quantity for c in outcome.checks if not c.passed]
        verdict = "pass" if entry.passed else f"FAIL ({'; '.join(failed) or 'no checks'})"
        print(
            f"{entry.benchmark.name:>18}: {verdict}, {len(outcome.checks)} checks, "
            f"{entry.seconds:.1f} s",
            flush=True,
        )

    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m verification",
        description="Run wrinkle's verification gallery and write DIR/report.md.",
    )
    parser.add_argument("--out", default="verification-results", help="output directory")
    parser.add_argument("--quick", action="store_true", help="coarse meshes (minutes, not tens)")
    parser.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="NAME",
        help="run only this benchmark (may be repeated)",
    )
    parser.add_argument("--report", help="where to write the report (default DIR/report.md)")
    parser.add_argument(
        "--cases",
        default=str(CASES),
        help="folder of the benchmark case files (default: %(default)s)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no per-benchmark lines")
    parser.add_argument("-v", "--verbose", action="store_true", help="log every iteration")
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(message)s"
    )
    out = Path(args.out)
    path = Path(args.report) if args.report else out / "report.md"
    try:
        entries = run_gallery(
            benchmarks(),
            Path(args.cases),
            out,
            quick=args.quick,
            only=args.only,
            on_entry=_printer(args.quiet),
            report=path,
        )
    except (ValueError, OSError, ImportError) as error:  # bad input: one line, no traceback
        print(f"verification: {error}", file=sys.stderr)
        return 2
    passed = sum(entry.passed for entry in entries)
    if not args.quiet:
        print(f"{passed} of {len(entries)} benchmarks pass; wrote {path}")
    return 0 if passed == len(entries) else 1


if __name__ == "__main__":
    sys.exit(main())
