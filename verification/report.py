"""The verification gallery's framework: checks, convergence studies, the report.

Each benchmark is a module of ``verification.benchmarks`` with a ``BENCHMARK`` (a
``Benchmark``): it reads its case file ``<cases>/<name>.toml``, solves it (on coarse meshes
when ``quick``), compares with its analytical or published reference and returns an
``Outcome``: checks (one table row each), figures and a paragraph of text. ``run_gallery``
runs the benchmarks it is given (``python -m verification`` gives them all, in the order of
its registry) and writes ``report.md``; a benchmark that raises is reported as failed with
its error. This module imports no benchmark.
"""

from __future__ import annotations

import logging
import math
import os
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "Benchmark",
    "Check",
    "Convergence",
    "Entry",
    "Outcome",
    "run_gallery",
    "write_report",
]

logger = logging.getLogger("wrinkle")


@dataclass
class Check:
    """One compared quantity: wrinkle's ``value`` against ``reference`` from ``source``.

    The error is |value - reference| / |reference| when ``relative``, else |value - reference|
    (in the quantity's unit); the check passes when the error is at most ``tolerance``.
    """

    quantity: str
    reference: float
    source: str
    value: float
    tolerance: float
    relative: bool = True

    @property
    def error(self) -> float:
        difference = abs(self.value - self.reference)
        if not self.relative:
            return float(difference)
        return float(difference / abs(self.reference)) if self.reference != 0 else math.inf

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.value)) and self.error <= self.tolerance

    @classmethod
    def none_of(cls, quantity: str, count: int, source: str) -> Check:
        """A count that must be zero (elements not taut, say), checked exactly."""
        return cls(quantity, 0.0, source, float(count), 0.0, relative=False)


@dataclass
class Convergence:
    """Errors of ``quantity`` on meshes of decreasing size h (a length), and the order the
    discretisation should show. ``observed_order`` is the least-squares slope of log(error)
    against log(h)."""

    quantity: str
    sizes: Sequence[float]
    errors: Sequence[float]
    expected_order: float

    @property
    def observed_order(self) -> float:
        h, e = np.asarray(self.sizes, float), np.abs(np.asarray(self.errors, float))
        keep = (h > 0) & (e > 0)
        if np.count_nonzero(keep) < 2:
            return math.nan
        return float(np.polyfit(np.log(h[keep]), np.log(e[keep]), 1)[0])


@dataclass
class Outcome:
    """What one benchmark returns: table rows, figure paths (inside the output directory),
    a markdown paragraph (set-up, reference, discussion) and mesh-convergence studies."""

    checks: list[Check]
    figures: list[Path] = field(default_factory=list)
    text: str = ""
    convergence: list[Convergence] = field(default_factory=list)


@dataclass(frozen=True)
class Benchmark:
    """A gallery entry: ``run(case, out, quick)`` solves the case file ``case`` and writes its
    figures into the directory ``out``."""

    name: str
    title: str
    run: Callable[[Path, Path, bool], Outcome]


@dataclass
class Entry:
    """A benchmark as run: its outcome (None if it raised), the error text, the wall time."""

    benchmark: Benchmark
    outcome: Outcome | None
    error: str
    seconds: float

    @property
    def passed(self) -> bool:
        return (
            self.outcome is not None
            and all(c.passed for c in self.outcome.checks)
            and bool(self.outcome.checks)
        )


def run_gallery(
    benchmarks: Sequence[Benchmark],
    cases: Path,
    out: Path,
    quick: bool = False,
    only: Sequence[str] = (),
    on_entry: Callable[[Entry], None] | None = None,
    report: Path | None = None,
) -> list[Entry]:
    """Run the ``benchmarks`` (those named in ``only``, or all, in their order) from the case
    files in ``cases``, write each one's figures into ``out/<name>/`` and the report into
    ``report`` (default ``out/report.md``; its figure links are relative to its folder).
    Raises ValueError for a name in ``only`` that is not a benchmark, or a missing case
    file, before anything runs."""
    cases, out = Path(cases), Path(out)
    report = Path(report) if report is not None else out / "report.md"
    chosen = list(benchmarks)
    names = [b.name for b in chosen]
    unknown = sorted(set(only) - set(names))
    if unknown:
        raise ValueError(f"unknown benchmark '{unknown[0]}' (one of {', '.join(names)})")
    if only:
        chosen = [b for b in chosen if b.name in only]
    for benchmark in chosen:
        case = cases / f"{benchmark.name}.toml"
        if not case.is_file():
            raise ValueError(f"{case}: case file of benchmark '{benchmark.name}' not found")
    out.mkdir(parents=True, exist_ok=True)
    entries = []
    for benchmark in chosen:
        folder = out / benchmark.name
        folder.mkdir(exist_ok=True)
        start = time.perf_counter()
        try:
            outcome, error = benchmark.run(cases / f"{benchmark.name}.toml", folder, quick), ""
        except Exception as exc:  # a failed benchmark is a failed row, not a crashed gallery
            logger.debug("benchmark %s failed", benchmark.name, exc_info=True)
            outcome = None
            error = f"{type(exc).__name__}: {exc}"
            logger.warning("%s", "".join(traceback.format_exception_only(exc)).strip())
        entry = Entry(benchmark, outcome, error, time.perf_counter() - start)
        entries.append(entry)
        if on_entry is not None:
            on_entry(entry)
    report.parent.mkdir(parents=True, exist_ok=True)
    write_report(entries, report, quick)
    return entries


def _number(value: float) -> str:
    if not np.isfinite(value):
        return str(value)
    return f"{value:.4g}"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def write_report(entries: list[Entry], path: Path, quick: bool) -> None:
    """The markdown report: one table of every check, then a section per benchmark with its
    text, its mesh-convergence table and its figures (linked relative to ``path``)."""
    passed = sum(e.passed for e in entries)
    lines = [
        "# wrinkle verification report",
        "",
        (
            f"{'Quick run (coarse meshes)' if quick else 'Full run'}: {passed} of "
            f"{len(entries)} benchmarks pass. Regenerate with "
            f"`python -m verification --out DIR{' --quick' if quick else ''}`."
        ),
        "",
        "| benchmark | quantity | reference | source | wrinkle | error | tolerance | result |",
        "|---|---|---:|---|---:|---:|---:|---|",
    ]
    for entry in entries:
        title = _cell(entry.benchmark.title)
        if entry.outcome is None:
            lines.append(f"| {title} | (did not run) | | | | | | FAIL: {_cell(entry.error)} |")
            continue
        if not entry.outcome.checks:
            lines.append(f"| {title} | (no checks) | | | | | | FAIL |")
        for check in entry.outcome.checks:
            error = f"{check.error:.2e}" if check.relative else _number(check.error)
            tolerance = f"{check.tolerance:.2e}" if check.relative else _number(check.tolerance)
            kind = "" if check.relative else " (abs.)"
            lines.append(
                f"| {title} | {_cell(check.quantity)} | {_number(check.reference)} | "
                f"{_cell(check.source)} | {_number(check.value)} | {error}{kind} | "
                f"{tolerance} | {'pass' if check.passed else 'FAIL'} |"
            )
    for index, entry in enumerate(entries, start=1):
        lines += [
            "",
            f"## {index}. {entry.benchmark.title}",
            "",
            (
                f"Case file: `verification/cases/{entry.benchmark.name}.toml`; "
                f"run time {entry.seconds:.1f} s."
            ),
            "",
        ]
        if entry.outcome is None:
            lines += [f"**Did not run:** {entry.error}", ""]
            continue
        if entry.outcome.text:
            lines += [entry.outcome.text.strip(), ""]
        for study in entry.outcome.convergence:
            lines += [
                (
                    f"Mesh convergence of {study.quantity}: observed order "
                    f"{study.observed_order:.2f} (expected {study.expected_order:g})."
                ),
                "",
                "| mesh size h | error |",
                "|---:|---:|",
            ]
            lines += [f"| {h:.4g} | {e:.3e} |" for h, e in zip(study.sizes, study.errors)]
            lines.append("")
        for figure in entry.outcome.figures:
            relative = Path(os.path.relpath(Path(figure).resolve(), path.parent.resolve()))
            lines += [f"![{relative.stem}]({relative.as_posix()})", ""]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
