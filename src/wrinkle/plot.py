"""Pictures with matplotlib (an optional dependency: pip install "wrinkle[plot]").

The figures are ``matplotlib.figure.Figure`` objects made without pyplot (``new_figure``), so
drawing them neither selects nor switches matplotlib's backend: an interactive session keeps
its own.
"""

from __future__ import annotations

import csv
import json
import os
import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from wrinkle.model import Model

__all__ = [
    "AXIS_NAMES",
    "STATE_COLOURS",
    "colour_cycle",
    "new_figure",
    "plot_convergence",
    "plot_results",
    "plot_state_map",
]

_NO_MATPLOTLIB = 'pictures need matplotlib; install it with pip install "wrinkle[plot]"'


def new_figure(**kwargs: Any) -> Figure:
    """A ``matplotlib.figure.Figure(**kwargs)`` (figsize, layout, ...), made without pyplot:
    no backend is selected or switched, and nothing keeps the figure alive once it is saved
    (``fig.savefig(path)``). Raises ImportError with the install command if matplotlib is
    missing."""
    try:
        from matplotlib.figure import Figure
    except ImportError:  # pragma: no cover - depends on the installation
        raise ImportError(_NO_MATPLOTLIB) from None
    return Figure(**kwargs)


def colour_cycle() -> list[str]:
    """The colours of matplotlib's current property cycle (rcParams "axes.prop_cycle")."""
    try:
        from matplotlib import rcParams
    except ImportError:  # pragma: no cover - depends on the installation
        raise ImportError(_NO_MATPLOTLIB) from None
    return list(rcParams["axes.prop_cycle"].by_key()["color"])


STATE_COLOURS = {"taut": "#3a78b5", "wrinkled": "#f5a623", "slack": "#cfcfcf"}
AXIS_NAMES = "xyz"


def _unit(units: dict, quantity: str) -> str:
    """Unit of "length", "force" or "stress" (force per length unless given) from the
    summary's units, or "" if not known."""
    if quantity == "stress" and "stress" not in units and "force" in units and "length" in units:
        return f"{units['force']}/{units['length']}"
    return units.get(quantity, "")


def _with_unit(label: str, unit: str) -> str:
    return f"{label} ({unit})" if unit else label


def _read_history(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    values = np.array([[float(v) for v in row] for row in rows[1:]]).reshape(-1, len(header))
    return header, values


def _stop_note(message: str, width: int | None = None) -> str:
    """Note for a run that did not converge: "still running" or "stopped", with the message
    wrapped to ``width`` characters if given (it is always in summary.json)."""
    if message == "running":
        return "still running"
    if width is None:
        return "stopped before load factor 1"
    return textwrap.fill("stopped: " + message, width)


def _view_axes(x: np.ndarray) -> tuple[int, int]:
    """The two coordinate axes with the largest extents of the points x (n, 3), in order."""
    extent = x.max(axis=0) - x.min(axis=0)
    return tuple(sorted(np.argsort(extent)[-2:].tolist()))


def _tension_lines(
    x: np.ndarray,
    triangles: np.ndarray,
    tension: np.ndarray,
    axes: tuple[int, int],
    lines_across: int = 45,
) -> tuple[np.ndarray, bool]:
    """Tension-field line segments (k, 2, 2) in the view plane ``axes`` through the centroids
    of the wrinkled elements ``triangles`` (k, 3) of the deformed mesh x (n, 3), along their
    tension directions (k, 3), 0.7 of the element size sqrt(2 A) long.

    Where the elements are smaller than 1/``lines_across`` of the view, the lines would merge
    into a texture: then one element per square of that size is drawn (the one nearest the
    square's centre) with a line 0.7 of the square long; the flag returned says so.
    """
    corners = x[triangles]  # (k, 3, 3)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    size = np.sqrt(np.linalg.norm(normal, axis=1))  # sqrt(2 A): the side of a half square
    centre = corners.mean(axis=1)[:, axes]
    direction = tension[:, axes]
    low = x[:, axes].min(axis=0)
    square = np.ptp(x[:, axes], axis=0).max() / lines_across
    sampled = triangles.shape[0] > 0 and float(np.median(size)) < square
    if sampled:
        key = np.floor((centre - low) / square).astype(np.int64)
        distance = np.linalg.norm(centre - low - (key + 0.5) * square, axis=1)
        order = np.lexsort((distance, key[:, 1], key[:, 0]))
        _, first = np.unique(key[order], axis=0, return_index=True)
        keep = order[first]
        centre, direction = centre[keep], direction[keep]
        size = np.full(keep.size, square)
    half = 0.35 * size[:, None] * direction
    return np.stack([centre - half, centre + half], axis=1), sampled


def plot_results(out_dir: str | os.PathLike) -> list[Path]:
    """Pictures of the results that ``wrinkle.output.ResultWriter`` wrote into ``out_dir``.

    Reads the last step's .vtu, summary.json and history.csv and writes into ``out_dir``:
    ``state.png``, the deformed membrane (reference + displacement, true scale) projected onto
    the plane of the two coordinate axes along which it extends most (named on the axes),
    elements coloured taut / wrinkled / slack, with a tension-field line through the centroid
    of every wrinkled element along its tension direction (0.7 of the element size; one per
    small square of the view on fine meshes); ``principal_stress.png``, the major principal
    Cauchy stress resultant (force per current length) on the same view;
    ``load_displacement.png``, the mean displacement of each probe (magnitude and components)
    against the load factor, or the largest nodal displacement if there are no probes; and,
    where the history has the columns ``pressure`` and ``enclosed_volume`` (a closed
    membrane under pressure), ``pressure_volume.png``, the pressure against the enclosed
    volume of each step, with the reference state. Returns the paths of the files. Raises
    ValueError if no step has been written.
    """
    from wrinkle.mesh import meshio_read, require_meshio
    from wrinkle.output import (
        CURVE_PICTURE,
        HISTORY,
        STATE_PICTURE,
        STRESS_PICTURE,
        SUMMARY,
        VOLUME_PICTURE,
    )

    require_meshio()
    out_dir = Path(out_dir)
    summary = _read_summary(out_dir / SUMMARY)
    # the last step whose .vtu is readable; the damaged ones after it are reported at the end
    damaged: list[str] = []
    for last in reversed(summary["steps"]):
        try:
            vtu = meshio_read(out_dir / last["file"], str(out_dir / last["file"]))
            cell = {name: vtu.cell_data_dict[name]["triangle"] for name in vtu.cell_data}
            displacement = vtu.point_data["displacement"]
            break
        except (ValueError, KeyError) as error:
            reason = str(error) if isinstance(error, ValueError) else f"no {error} data"
            damaged.append(
                reason if str(out_dir) in reason else f"{out_dir / last['file']}: {reason}"
            )
    else:
        raise ValueError(f"no readable step to plot: {damaged[0]}")
    units = summary.get("units") or {}
    x = vtu.points + displacement
    view = _View(x, vtu.cells_dict["triangle"], _unit(units, "length"))
    where = f"load factor {last['load_factor']:.4g}"
    if not summary["converged"]:
        where += " (" + _stop_note(summary["message"]) + ")"
    where += f"\ndeformed membrane {view.name}"
    paths = [
        _plot_states(view, cell, where, out_dir / STATE_PICTURE),
        _plot_major_stress(view, cell, where, _unit(units, "stress"), out_dir / STRESS_PICTURE),
        _plot_load_displacement(
            summary, out_dir / HISTORY, _unit(units, "length"), out_dir / CURVE_PICTURE
        ),
    ]
    volume = _plot_pressure_volume(summary, out_dir / HISTORY, units, out_dir / VOLUME_PICTURE)
    if volume is not None:
        paths.append(volume)
    if damaged:
        raise DamagedResults(
            f"{damaged[0]}; drew load factor {last['load_factor']:.4g}, the last readable step",
            paths,
        )
    return paths


class DamagedResults(ValueError):
    """Some results files could not be read; ``paths`` are the pictures drawn from the
    readable ones."""

    def __init__(self, message: str, paths: list[Path]):
        super().__init__(message)
        self.paths = paths


def _read_summary(path: Path) -> dict:
    """summary.json with its converged steps; ValueError naming the file if it is missing,
    not valid JSON, or lacks the steps."""
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ValueError(f"{path}: not found (is this a folder written by wrinkle run?)") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"{path}: damaged, not readable as JSON ({error})") from None
    steps = summary.get("steps") if isinstance(summary, dict) else None
    if not isinstance(steps, list) or not all(isinstance(step, dict) for step in steps):
        raise ValueError(f"{path}: damaged, it has no list of steps")
    if not steps:
        raise ValueError(f"{path}: no converged step to plot")
    if not all({"file", "load_factor"} <= set(step) for step in steps):
        raise ValueError(f"{path}: damaged, a step lacks its file or load factor")
    for key in ("converged", "message"):
        summary.setdefault(key, False if key == "converged" else "")
    return summary


class _View:
    """The deformed mesh x (n, 3), triangles (m, 3) seen along the axis of its smallest
    extent: ``axes`` the two coordinate axes drawn, ``xy`` (n, 2) the projected nodes."""

    def __init__(self, x: np.ndarray, triangles: np.ndarray, length_unit: str):
        self.x, self.triangles, self.length_unit = x, triangles, length_unit
        self.axes = _view_axes(x)
        self.xy = x[:, self.axes]
        self.fine = triangles.shape[0] > 3000  # no element edges: they would hide the colours
        a, b = (AXIS_NAMES[i] for i in self.axes)
        self.name = f"projected on the {a}{b}-plane (seen along {AXIS_NAMES[3 - sum(self.axes)]})"

    def figure(self, width: float = 7.5) -> tuple[Figure, Axes]:
        """A figure with one axes sized to the projected membrane, equal aspect, labelled."""
        xy = self.xy
        span = np.ptp(xy, axis=0)
        aspect = float(np.clip(span[1] / span[0], 0.25, 2.0)) if span[0] > 0 else 1.0
        fig = new_figure(figsize=(width, 1.3 + (width - 2.4) * aspect), layout="constrained")
        ax = fig.subplots()
        ax.set_aspect("equal")
        ax.set_xlabel(_with_unit(AXIS_NAMES[self.axes[0]], self.length_unit))
        ax.set_ylabel(_with_unit(AXIS_NAMES[self.axes[1]], self.length_unit))
        margin = 0.03 * max(span.max(), 1e-300)
        ax.set_xlim(xy[:, 0].min() - margin, xy[:, 0].max() + margin)
        ax.set_ylim(xy[:, 1].min() - margin, xy[:, 1].max() + margin)
        return fig, ax


def _plot_states(view: _View, cell: dict, where: str, path: Path) -> Path:
    """Elements coloured taut / wrinkled / slack, tension-field lines in the wrinkled ones."""
    from matplotlib.artist import Artist
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.colors import to_rgba_array
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fig, ax = view.figure(width=8.5)
    state = cell["state"].astype(int)
    colours = to_rgba_array(list(STATE_COLOURS.values()))
    ax.add_collection(
        PolyCollection(
            view.xy[view.triangles],
            facecolors=colours[np.clip(state, 0, 2)],
            edgecolors="face" if view.fine else "white",
            linewidths=0.2 if view.fine else 0.6,
        )
    )
    wrinkled = np.flatnonzero(state == list(STATE_COLOURS).index("wrinkled"))
    handles: list[Artist] = [
        Patch(facecolor=colour, edgecolor="0.4", label=f"{name} ({np.count_nonzero(state == k)})")
        for k, (name, colour) in enumerate(STATE_COLOURS.items())
    ]
    if wrinkled.size:
        segments, sampled = _tension_lines(
            view.x, view.triangles[wrinkled], cell["tension_direction"][wrinkled], view.axes
        )
        ax.add_collection(
            LineCollection(
                list(segments),
                colors="#202020",
                linewidths=0.8 if sampled else 1.2,
                capstyle="round",
            )
        )
        handles.append(
            Line2D(
                [],
                [],
                color="#202020",
                lw=1.2,
                label="tension lines" + (",\nsampled" if sampled else ""),
            )
        )
    ax.legend(
        handles=handles,
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        borderaxespad=0.0,
        title="elements",
    )
    ax.set_title(f"Taut, wrinkled and slack elements\n{where}", fontsize=10)
    fig.savefig(path, dpi=150)
    return path


def _plot_major_stress(view: _View, cell: dict, where: str, unit: str, path: Path) -> Path:
    """Map of the major principal stress; a concentration above 1.5 times the 98th
    percentile is clipped so that it does not wash out the rest (said in the title)."""
    fig, ax = view.figure()
    major = cell["principal_stress"][:, 1]
    top = float(np.percentile(major, 98))
    clipped = major.max() > 1.5 * top > 0
    image = ax.tripcolor(
        view.xy[:, 0],
        view.xy[:, 1],
        view.triangles,
        facecolors=major,
        cmap="viridis",
        vmin=min(0.0, float(major.min())),
        vmax=top if clipped else float(major.max()),
        edgecolors="face" if view.fine else "white",
        linewidth=0.2 if view.fine else 0.4,
    )
    bar = fig.colorbar(image, ax=ax, shrink=0.9, extend="max" if clipped else "neither")
    bar.set_label(_with_unit("major principal stress resultant", unit))
    note = ""
    if clipped:
        note = (
            f"\ncolours clipped at the 98th percentile, "
            f"maximum {major.max():.3g}{' ' + unit if unit else ''}"
        )
    ax.set_title(
        f"Major principal Cauchy stress resultant (force per current length)\n{where}{note}",
        fontsize=10,
    )
    fig.savefig(path, dpi=150)
    return path


def _plot_load_displacement(
    summary: dict, history_path: Path, length_unit: str, path: Path
) -> Path:
    """Probe displacements (or the largest displacement) against the load factor."""
    header, history = _read_history(history_path)
    load = history[:, header.index("load_factor")]
    probes = [name[:-3] for name in header if name.endswith("_ux")]
    if probes:
        fig = new_figure(figsize=(11, 4.5), layout="constrained")
        ax_magnitude, ax_parts = fig.subplots(1, 2)
        cycle = colour_cycle()
        for k, probe in enumerate(probes):
            colour = cycle[k % len(cycle)]
            u = history[:, [header.index(f"{probe}_u{c}") for c in AXIS_NAMES]]
            ax_magnitude.plot(
                load, np.linalg.norm(u, axis=1), "o-", color=colour, ms=4, label=probe
            )
            for c, style in zip(range(3), ("-", "--", ":")):
                ax_parts.plot(
                    load,
                    u[:, c],
                    style,
                    color=colour,
                    marker=".",
                    label=f"{probe}: u{AXIS_NAMES[c]}",
                )
        ax_magnitude.set_ylabel(_with_unit("|u|, mean over the probe's nodes", length_unit))
        ax_magnitude.set_title("Probe displacement magnitude")
        ax_parts.set_ylabel(_with_unit("u, mean over the probe's nodes", length_unit))
        ax_parts.set_title("Probe displacement components")
        ax_parts.axhline(0.0, color="0.6", lw=0.6)
        for ax in (ax_magnitude, ax_parts):
            ax.legend(fontsize=8, ncol=2 if len(probes) > 3 else 1)
        panels: tuple[Axes, ...] = (ax_magnitude, ax_parts)
    else:
        fig = new_figure(figsize=(6.5, 4.5), layout="constrained")
        ax = fig.subplots()
        ax.plot(
            [s["load_factor"] for s in summary["steps"]],
            [s["max_displacement"] for s in summary["steps"]],
            "o-",
            ms=4,
        )
        ax.set_ylabel(_with_unit("largest nodal displacement", length_unit))
        ax.set_title("Largest displacement")
        panels = (ax,)
    for ax in panels:
        ax.set_xlabel("load factor")
        ax.set_xlim(0.0, 1.03 * max(1.0, float(load.max(initial=0.0))))
        ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
        ax.grid(True, alpha=0.3)
    if not summary["converged"]:
        fig.suptitle(_stop_note(summary["message"], 120), fontsize=9, color="firebrick")
    fig.savefig(path, dpi=120)
    return path


def _plot_pressure_volume(
    summary: dict, history_path: Path, units: dict, path: Path
) -> Path | None:
    """The pressure against the enclosed volume of every step, and the reference state (its
    volume at zero pressure) as a point of its own; None where the history has not both
    columns."""
    header, history = _read_history(history_path)
    if not {"pressure", "enclosed_volume"} <= set(header):
        return None
    pressure = history[:, header.index("pressure")]
    volume = history[:, header.index("enclosed_volume")]
    fig = new_figure(figsize=(6.5, 4.5), layout="constrained")
    ax = fig.subplots()
    ax.plot(volume, pressure, "o-", ms=4, label="converged steps")
    reference = summary.get("reference_volume")
    if isinstance(reference, int | float):  # not joined: the path between is not drawn
        ax.plot([reference], [0.0], "s", mfc="none", color="0.3", label="reference state")
        ax.legend(fontsize=8)
    length, force = _unit(units, "length"), _unit(units, "force")
    ax.set_xlabel(_with_unit("enclosed volume", f"{length}³" if length else ""))
    ax.set_ylabel(_with_unit("pressure", f"{force}/{length}²" if force and length else ""))
    ax.set_title("Pressure against enclosed volume")
    ax.grid(True, alpha=0.3)
    if not summary["converged"]:
        fig.suptitle(_stop_note(summary["message"], 120), fontsize=9, color="firebrick")
    fig.savefig(path, dpi=120)
    return path


def plot_state_map(
    model: Model, u: np.ndarray, path: str | os.PathLike, title: str, length_unit: str = ""
) -> Path:
    """``state.png``'s picture for a model in memory: taut / wrinkled / slack elements of
    ``model`` at displacements u (n_dofs,) with tension lines, written to ``path``."""
    from wrinkle.post import element_report

    report = element_report(model, u)
    x = model.mesh.nodes + np.asarray(u).reshape(-1, 3)
    view = _View(x, model.mesh.triangles, length_unit)
    cell = {"state": report.state, "tension_direction": report.tension_direction}
    return _plot_states(view, cell, f"{title}\ndeformed membrane {view.name}", Path(path))


def plot_convergence(studies, path: str | os.PathLike, title: str) -> Path:
    """Log-log errors against mesh size h for each mesh-convergence study in ``studies``
    (objects with ``quantity``, ``sizes``, ``errors``, ``expected_order`` and
    ``observed_order``), with a guide line of the expected order; written to ``path``."""
    fig = new_figure(figsize=(6.0, 4.5), layout="constrained")
    ax = fig.subplots()
    for study in studies:
        h = np.asarray(study.sizes, float)
        e = np.abs(np.asarray(study.errors, float))
        ax.loglog(h, e, "o-", label=f"{study.quantity} (order {study.observed_order:.2f})")
        guide = e[-1] * (h / h[-1]) ** study.expected_order
        ax.loglog(h, guide, "--", color="0.6", lw=1.0)
    if studies:
        ax.plot([], [], "--", color="0.6", label="expected order")
    ax.set_xlabel("mesh size h")
    ax.set_ylabel("error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=10)
    fig.savefig(path, dpi=150)
    return Path(path)
