"""Pictures of a study: each quantity against each parameter (matplotlib, the plot extra)."""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from wrinkle.plot import new_figure

__all__ = ["PICTURE_FOLDER", "plot_study"]

PICTURE_FOLDER = "pictures"


def _file_name(quantity: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", quantity) + ".png"


def plot_study(
    rows: Sequence[dict[str, Any]],
    out: str | os.PathLike,
    parameters: Sequence[str],
    quantities: Sequence[str],
) -> list[Path]:
    """For each quantity, OUT/pictures/<quantity>.png: one panel per parameter, the converged
    variants' values of the quantity against the parameter's (a failed variant has none).
    Returns the paths written (none without converged variants)."""
    converged = [row for row in rows if row.get("status") == "converged"]
    folder = Path(out) / PICTURE_FOLDER
    written: list[Path] = []
    for quantity in quantities:
        points = [row for row in converged if isinstance(row.get(quantity), (int, float))]
        points = [row for row in points if math.isfinite(row[quantity])]
        if not points:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        count = len(parameters)
        fig = new_figure(figsize=(4.0 * count, 3.4), layout="constrained")
        axes = fig.subplots(1, count, squeeze=False)[0]
        for ax, parameter in zip(axes, parameters, strict=True):
            ax.plot(
                [row[parameter] for row in points], [row[quantity] for row in points], "o", ms=4
            )
            ax.set_xlabel(parameter)
            ax.grid(True, alpha=0.3)
        axes[0].set_ylabel(quantity)
        fig.suptitle(f"{quantity}: {len(points)} converged variant(s)", fontsize=10)
        path = folder / _file_name(quantity)
        fig.savefig(path, dpi=110)
        written.append(path)
    return written
