"""The report of a fit: fit.json, fit_curves.csv (``write_report``) and the picture fit.png
(``write_picture``, with matplotlib).

fit.json: "parameters" (path -> value), "intervals" (path -> [low, high], the 95 %
confidence interval, or null), "converged"; with "start", "standard_errors", "correlation"
({"parameters": [...], "matrix": [[...]]}), "cost" and "start_cost" (1/2 sum r^2),
"rms" (experiment -> RMS of its relative residuals), "gradients" (path -> "adjoint" or
"finite-difference"), "evaluations", "jacobians", "iterations" (Newton), "seconds",
"message", "interval_note". fit_curves.csv: a row per experiment, point and quantity with
the measured value and the model's at the start and at the solution.
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from wrinkle.identification.fit import FitResult

__all__ = ["CURVE_COLUMNS", "write_picture", "write_report"]

CURVE_COLUMNS = ("experiment", "quantity", "x", "load_factor", "measured", "start", "fitted")


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _summary(result: FitResult) -> dict[str, Any]:
    problem = result.problem
    paths = [p.path for p in problem.parameters]
    return {
        "parameters": result.parameters,
        "intervals": result.intervals,
        "converged": result.converged,
        "start": problem.start,
        "standard_errors": result.standard_errors,
        "correlation": {
            "parameters": paths,
            "matrix": [[_finite(v) for v in row] for row in result.correlation],
        },
        "cost": result.cost,
        "start_cost": result.start_cost,
        "rms": result.rms,
        "gradients": result.gradients,
        "evaluations": result.evaluations,
        "jacobians": result.jacobians,
        "iterations": result.iterations,
        "seconds": round(result.seconds, 3),
        "message": result.message,
        "interval_note": result.interval_note,
        "experiments": {
            e.name: {"case": str(e.case), "data": str(e.data), "points": int(e.x.size)}
            for e in problem.experiments
        },
    }


def _write_curves(result: FitResult, path: Path) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(CURVE_COLUMNS)
        for e, start, fitted in zip(
            result.problem.experiments, result.start_curves, result.curves, strict=True
        ):
            for k, name in enumerate(e.quantities):
                for i in range(e.x.size):
                    writer.writerow(
                        [
                            e.name,
                            name,
                            repr(float(e.x[i])),
                            repr(float(e.load_factors[i])),
                            repr(float(e.measured[i, k])),
                            repr(float(start[i, k])),
                            repr(float(fitted[i, k])),
                        ]
                    )


def _picture(result: FitResult, path: Path) -> None:
    """A panel per experiment and measured column: the measured points (markers), the
    model at the start (dashed) and at the solution (line), against the load column."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [
        (e, k, start, fitted)
        for e, start, fitted in zip(
            result.problem.experiments, result.start_curves, result.curves, strict=True
        )
        for k in range(len(e.quantities))
    ]
    across = min(len(panels), 4)
    down = -(-len(panels) // across)
    figure, axes = plt.subplots(
        down, across, figsize=(3.6 * across, 3.0 * down + 0.6), squeeze=False
    )
    for axis in axes.ravel()[len(panels) :]:
        axis.set_visible(False)
    for axis, (e, k, start, fitted) in zip(axes.ravel(), panels, strict=False):
        axis.plot(e.x, e.measured[:, k], "o", color="black", markersize=4, label="measured")
        axis.plot(e.x, start[:, k], "--", color="tab:gray", label="start")
        axis.plot(e.x, fitted[:, k], "-", color="tab:red", label="fitted")
        axis.set_title(f"{e.name}: {e.columns[k]}", fontsize=9)
        axis.set_xlabel(e.x_name, fontsize=8)
        axis.tick_params(labelsize=7)
        axis.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    found = [f"{p} = {v:.5g}" for p, v in result.parameters.items()]
    lines = [", ".join(found[i : i + 3]) for i in range(0, len(found), 3)]
    figure.suptitle("fitted: " + "\n".join(lines), fontsize=9)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


def write_report(result: FitResult, out: str | os.PathLike) -> list[Path]:
    """Write fit.json and fit_curves.csv into ``out`` (the paths written); the picture is
    ``write_picture``'s."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    summary = folder / "fit.json"
    summary.write_text(json.dumps(_summary(result), indent=2, allow_nan=False) + "\n")
    curves = folder / "fit_curves.csv"
    _write_curves(result, curves)
    return [summary, curves]


def write_picture(result: FitResult, out: str | os.PathLike) -> Path | None:
    """Draw fit.png into ``out`` (its path; None where a solution curve is not finite, when
    the fit ended at a point whose solve failed). ImportError without matplotlib."""
    if not all(np.all(np.isfinite(c)) for c in result.curves):
        return None
    path = Path(out) / "fit.png"
    _picture(result, path)
    return path
