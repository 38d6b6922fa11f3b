"""Pictures with matplotlib (an optional dependency: pip install "wrinkle[plot]").

The figures are ``matplotlib.figure.Figure`` objects made without pyplot (``new_figure``), so
drawing them neither selects nor switches matplotlib's backend: an interactive session keeps
its own.
"""

from __future__ import annotations

import csv
import os
import textwrap
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np

from wrinkle.reader import read_summary

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
    axes: tuple[int, ...],
    lines_across: int = 45,
) -> tuple[np.ndarray, bool]:
    """Tension-field line segments (k, 2, len(axes)) in the view plane ``axes`` (or in 3-D
    with axes (0, 1, 2)) through the centroids
    of the wrinkled elements ``triangles`` (k, 3) of the deformed mesh x (n, 3), along their
    tension directions (k, 3), 0.7 of the element size sqrt(2 A) long.

    Where the elements are smaller than 1/``lines_across`` of the view, the lines would merge
    into a texture: then one element per square (cube in 3-D) of that size is drawn (the one
    nearest the square's centre) with a line 0.7 of the square long; the flag returned says
    so.
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
        order = np.lexsort((distance, *key.T[::-1]))
        _, first = np.unique(key[order], axis=0, return_index=True)
        keep = order[first]
        centre, direction = centre[keep], direction[keep]
        size = np.full(keep.size, square)
    half = 0.35 * size[:, None] * direction
    return np.stack([centre - half, centre + half], axis=1), sampled


def plot_results(out_dir: str | os.PathLike, load: str | None = None) -> list[Path]:
    """Pictures of the results that ``wrinkle.output.ResultWriter`` wrote into ``out_dir``.

    Reads the last step's .vtu, summary.json and history.csv and writes into ``out_dir``:

    - ``state.png``, the deformed membrane (reference + displacement, true scale) projected
      onto the plane of the two coordinate axes along which it extends most (named on the
      axes), elements coloured taut / wrinkled / slack, with a tension-field line through the
      centroid of every wrinkled element along its tension direction (0.7 of the element
      size; one per small square of the view on fine meshes);
    - ``principal_stress.png``, the major principal Cauchy stress resultant (force per
      current length) on the same view;
    - ``load_displacement.png``, the mean displacement of each probe (magnitude and
      components), or the largest nodal displacement if there are no probes, against the
      load ``load``: "pressure", "load_factor", a support's label (the component of its
      reaction largest at the last step) or a history column such as "seam_Fz"; None: the
      pressure where the history has one, else the load factor. The reference state (zero
      load, zero displacement) is the curve's first point;
    - ``pressure_volume.png`` where the history has the columns ``pressure`` and
      ``enclosed_volume`` (a closed membrane under pressure): the pressure against the
      enclosed volume of each step, with the reference state;
    - ``shape_3d.png``: the deformed membrane in 3-D (orthographic, equal scales), mirrored
      about the symmetry planes that its supports define (``symmetry_planes``), elements
      coloured by state and shaded, tension lines on the wrinkled elements facing the viewer;
    - ``stress_3d.png``: the major principal stress resultant on the same 3-D shape, with a
      colour bar;
    - ``height.png`` for a nearly flat membrane (``height_map_axes``): filled contours of the
      out-of-plane displacement on the plan;
    - ``fibres.png`` where the material axis 1 (``fibre_direction``) is not the default x
      axis everywhere: the fibre directions in the reference configuration;
    - ``convergence.png``: the residual of every Newton iteration against the cumulative
      iteration number, log scale, the steps marked (summary's ``residual_history``).

    Meshes of more than 200,000 triangles are drawn in 3-D through a coarser copy made by
    vertex clustering (``_decimate``) so that a 10^6-element result draws in seconds.
    Returns the paths of the files written, in the order above. Raises ValueError if no step
    has been written or ``load`` names no load of the history.
    """
    from wrinkle.mesh import require_meshio
    from wrinkle.output import (
        CURVE_PICTURE,
        FIBRE_PICTURE,
        HEIGHT_PICTURE,
        HISTORY,
        NEWTON_PICTURE,
        SHAPE_PICTURE,
        STATE_PICTURE,
        STRESS_3D_PICTURE,
        STRESS_PICTURE,
        SUMMARY,
        VOLUME_PICTURE,
    )

    out_dir = Path(out_dir)
    summary = _read_summary(out_dir / SUMMARY)
    if not str(summary["steps"][-1]["file"]).endswith(".h5"):
        require_meshio()
    header, history = _read_history(out_dir / HISTORY)
    load_column = _load_column(header, history, load)  # a bad choice: before drawing
    last, vtu, cell, damaged = _read_last_step(out_dir, summary)
    displacement = vtu.point_data["displacement"]
    units = summary.get("units") or {}
    length_unit = _unit(units, "length")
    x = vtu.points + displacement
    view = _View(x, vtu.cells_dict["triangle"], length_unit)
    where = f"load factor {last['load_factor']:.4g}"
    if not summary["converged"]:
        where += " (" + _stop_note(summary["message"]) + ")"
    paths = [
        _plot_states(
            view, cell, where + f"\ndeformed membrane {view.name}", out_dir / STATE_PICTURE
        ),
        _plot_major_stress(
            view,
            cell,
            where + f"\ndeformed membrane {view.name}",
            _unit(units, "stress"),
            out_dir / STRESS_PICTURE,
        ),
        _plot_load_displacement(
            summary, header, history, load_column, units, out_dir / CURVE_PICTURE
        ),
    ]
    volume = _plot_pressure_volume(summary, out_dir / HISTORY, units, out_dir / VOLUME_PICTURE)
    if volume is not None:
        paths.append(volume)
    shape = whole_membrane(vtu)
    paths.append(_plot_shape_3d(shape, cell, where, length_unit, out_dir / SHAPE_PICTURE))
    paths.append(
        _plot_stress_3d(
            shape, cell, where, length_unit, _unit(units, "stress"), out_dir / STRESS_3D_PICTURE
        )
    )
    across = int(np.argmin(np.ptp(vtu.points, axis=0)))  # a plan's normal, if it has one
    if any(axis == across for axis, _ in shape.planes):  # mirrored only across the plan
        shape = whole_membrane(vtu, exclude_axis=across)
    height = _plot_height(shape, where, length_unit, out_dir / HEIGHT_PICTURE)
    if height is not None:
        paths.append(height)
    fibres = _plot_fibres(vtu, cell, length_unit, out_dir / FIBRE_PICTURE)
    if fibres is not None:
        paths.append(fibres)
    paths.append(_plot_newton_history(summary, out_dir / NEWTON_PICTURE))
    if damaged:
        raise DamagedResults(
            f"{damaged[0]}; drew load factor {last['load_factor']:.4g}, the last readable step",
            paths,
        )
    return paths


def _read_last_step(out_dir: Path, summary: dict) -> tuple[dict, Any, dict, list[str]]:
    """The last step of the summary whose file (.vtu, or .h5 of the xdmf format) is
    readable: (its summary entry, the step as an object with ``points``, ``point_data`` and
    ``cells_dict`` as a meshio mesh has them, its triangles' cell data {name: array}, the
    reasons the later steps could not be read). ValueError if none is readable."""
    from wrinkle.reader import ResultsFolder

    folder = ResultsFolder(out_dir, summary, {}, summary["steps"])
    damaged: list[str] = []
    for index in range(len(folder.steps) - 1, -1, -1):
        last = folder.steps[index]
        try:
            nodes, triangles, point, cell = folder.step_data(index)
            point["displacement"]
        except (ValueError, KeyError) as error:
            reason = str(error) if isinstance(error, ValueError) else f"no {error} data"
            damaged.append(
                reason if str(out_dir) in reason else f"{out_dir / last['file']}: {reason}"
            )
            continue
        step = SimpleNamespace(points=nodes, point_data=point, cells_dict={"triangle": triangles})
        return last, step, cell, damaged
    raise ValueError(f"no readable step to plot: {damaged[0]}")


class DamagedResults(ValueError):
    """Some results files could not be read; ``paths`` are the pictures drawn from the
    readable ones."""

    def __init__(self, message: str, paths: list[Path]):
        super().__init__(message)
        self.paths = paths


def _read_summary(path: Path) -> dict:
    """summary.json with its converged steps (``wrinkle.reader.read_summary``); ValueError
    naming the file if it is missing, damaged or lists no step."""
    summary = read_summary(path)
    if not summary["steps"]:
        raise ValueError(f"{path}: no converged step to plot")
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
        handles.append(_tension_handle(sampled, 1.2))
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


def _load_column(header: list[str], history: np.ndarray, load: str | None) -> tuple[str, str]:
    """The history column of the load asked for (``plot_results``' ``load``) and its kind
    ("load_factor", "pressure" or "force"). ValueError naming the choices for a bad one."""
    supports = list(dict.fromkeys(name[:-3] for name in header if name.endswith("_Fx")))
    has_pressure = "pressure" in header and bool(
        np.isfinite(history[:, header.index("pressure")]).any()
    )
    if load is None:  # a staged run's loads grow in turn: its total time by default
        load = "pressure" if has_pressure and "time" not in header else "load_factor"
    if load == "load_factor" and "time" in header:  # a staged run: its total time
        return "time", "load_factor"
    if load == "load_factor" or (load == "pressure" and has_pressure):
        return load, load
    if load in supports:
        last = history[-1] if history.shape[0] else np.zeros(len(header))
        parts = [f"{load}_F{c}" for c in AXIS_NAMES]
        largest = int(np.argmax([abs(last[header.index(part)]) for part in parts]))
        return parts[largest], "force"
    if load in header and load[-3:] in ("_Fx", "_Fy", "_Fz") and load[:-3] in supports:
        return load, "force"
    choices = ["load_factor", *(["pressure"] if has_pressure else []), *supports]
    raise ValueError(
        f"load {load!r}: not a load of this run; choose one of "
        + ", ".join(repr(choice) for choice in choices)
    )


def _load_label(column: str, kind: str, units: dict) -> str:
    length, force = _unit(units, "length"), _unit(units, "force")
    if kind == "pressure":
        return _with_unit("pressure", f"{force}/{length}²" if force and length else "")
    if kind == "force":
        return _with_unit(f"reaction {column[-2:]} of {column[:-3]!r}", force)
    if column == "time":
        return "analysis steps (step - 1 + load factor)"
    return "load factor"


def _plot_load_displacement(
    summary: dict,
    header: list[str],
    history: np.ndarray,
    load_column: tuple[str, str],
    units: dict,
    path: Path,
) -> Path:
    """Probe displacements (or the largest displacement) against the load chosen
    (``_load_column``), from the reference state (0, 0)."""
    length_unit = _unit(units, "length")
    column, kind = load_column
    load = np.concatenate([[0.0], history[:, header.index(column)]])
    probes = [name[:-3] for name in header if name.endswith("_ux")]
    if probes:
        fig = new_figure(figsize=(11, 4.5), layout="constrained")
        ax_magnitude, ax_parts = fig.subplots(1, 2)
        cycle = colour_cycle()
        for k, probe in enumerate(probes):
            colour = cycle[k % len(cycle)]
            u = history[:, [header.index(f"{probe}_u{c}") for c in AXIS_NAMES]]
            u = np.vstack([np.zeros(3), u])
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
        largest = [s.get("max_displacement", np.nan) for s in summary["steps"]]
        n = min(len(largest), load.size - 1)
        ax.plot(load[: n + 1], [0.0, *largest[:n]], "o-", ms=4)
        ax.set_ylabel(_with_unit("largest nodal displacement", length_unit))
        ax.set_title("Largest displacement")
        panels = (ax,)
    for ax in panels:
        ax.set_xlabel(_load_label(column, kind, units))
        if kind == "load_factor":
            ax.set_xlim(0.0, 1.03 * max(1.0, float(load.max(initial=0.0))))
        ax.axvline(0.0, color="0.6", lw=0.6)
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


# -- the membrane in 3-D ---------------------------------------------------------------

SYMMETRY_TOLERANCE = 1e-10  # of the membrane's size: a node on a plane, held normal to it
FACE_BUDGET = 200_000  # faces drawn in 3-D at most (after mirroring); more: vertex clustering
_ELEVATION, _AZIMUTH = 28.0, -60.0  # the 3-D view, degrees


def _free_edges(triangles: np.ndarray) -> np.ndarray:
    """The boundary edges (k, 2) of a triangle mesh (m, 3): those used by one triangle."""
    edges = np.sort(triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return unique[count == 1]


def symmetry_planes(
    points: np.ndarray, displacement: np.ndarray, reaction: np.ndarray, triangles: np.ndarray
) -> list[tuple[int, float]]:
    """The coordinate planes (axis 0, 1, 2 for x, y, z; coordinate c) that the supports make
    symmetry planes of a result: nodes (n, 3) ``points`` in the reference, ``displacement``
    and ``reaction`` (n, 3), ``triangles`` (m, 3).

    A results folder does not list its supports, and the case file it names may have moved or
    changed, so the planes are read from the step itself. A plane x_a = c (c the smallest or
    the largest deformed coordinate a: the membrane lies on one side of it) is a symmetry
    plane if the nodes on it (within ``SYMMETRY_TOLERANCE`` of the size, deformed) are

    - at least one boundary edge's two nodes, and all of them boundary nodes (on edges of one
      triangle): the membrane meets the plane along an edge, no part lies in the plane
      (a closed tube's end cap held in x is not a symmetry plane);
    - held normal to the plane: |u_a| within the same tolerance, and a normal reaction at one
      of them at least (above 1e-8 of the largest reaction; an edge that merely happens not
      to move is not taken);
    - free along the plane: no reaction tangential to it above 1e-8 of the largest reaction,
      except at two nodes at most (the ends of the edge, which other supports may hold): a
      clamped or pulled edge is not a symmetry plane.

    Such an edge is mechanically a symmetry plane: a membrane has no bending stiffness, so a
    roller that holds it normal to a plane is the symmetry condition, and the mirror image is
    an equilibrium state too. So the airbag's seams, held in z on the plane z = 0, make z = 0
    a symmetry plane as well as x = 0 and y = 0: the whole airbag, both sheets, is shown.
    Where both the smallest and the largest coordinate along an axis qualify, the membrane
    would repeat without end: neither is taken. Returns [] when unsure.
    """
    x = points + displacement
    if x.shape[0] == 0 or triangles.shape[0] == 0:
        return []
    size = float(np.ptp(x, axis=0).max())
    force_scale = float(np.abs(reaction).max(initial=0.0))
    if not (size > 0 and force_scale > 0 and np.isfinite(size + force_scale)):
        return []
    tolerance, small = SYMMETRY_TOLERANCE * size, 1e-8 * force_scale
    free = _free_edges(triangles)
    boundary = np.zeros(x.shape[0], bool)
    boundary[free.ravel()] = True
    planes = []
    for axis in range(3):
        found = []
        for c in sorted({float(x[:, axis].min()), float(x[:, axis].max())}):
            on = np.abs(x[:, axis] - c) <= tolerance
            if np.count_nonzero(on) < 2 or not boundary[on].all():
                continue
            if not on[free].all(axis=1).any() or on[triangles].all(axis=1).any():
                continue
            tangential = np.delete(np.abs(reaction[on]), axis, axis=1).max(axis=1)
            if (
                np.abs(displacement[on, axis]).max() <= tolerance
                and np.abs(reaction[on, axis]).max() > small
                and np.count_nonzero(tangential > small) <= 2
            ):
                found.append(c)
        if len(found) == 1:
            planes.append((axis, found[0]))
    return planes


def mirror(
    triangles: np.ndarray,
    planes: list[tuple[int, float]],
    positions: list[np.ndarray],
    tolerance: float,
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, np.ndarray]:
    """The mesh mirrored about each plane (axis, c) in turn: each of the ``positions`` (n, 3)
    reflected (x_a -> 2 c - x_a) and appended, the nodes of ``positions[0]`` within
    ``tolerance`` of the plane shared by both halves (not duplicated), the copy's triangles
    reversed (its normals the mirror images of the original's). Returns the positions (N, 3),
    the triangles (M, 3), the element each face comes from (M,) and the signs (M, 3) that
    mirror a vector of that element (a tension direction) onto the face. With k planes,
    M = 2^k m; on a 9 x 9-node quarter square mirrored about two of its edges N = 17 x 17."""
    element = np.arange(triangles.shape[0])
    signs = np.ones((triangles.shape[0], 3))
    for axis, c in planes:
        n = positions[0].shape[0]
        kept = np.abs(positions[0][:, axis] - c) > tolerance
        index = np.where(kept, n + np.cumsum(kept) - 1, np.arange(n))
        copies = []
        for p in positions:
            image = p[kept].copy()
            image[:, axis] = 2.0 * c - image[:, axis]
            copies.append(np.vstack([p, image]))
        positions = copies
        triangles = np.vstack([triangles, index[triangles][:, ::-1]])
        element = np.concatenate([element, element])
        flip = np.ones(3)
        flip[axis] = -1.0
        signs = np.vstack([signs, signs * flip])
    return positions, triangles, element, signs


class MembraneShape:
    """The deformed membrane as the 3-D pictures show it: ``x`` (N, 3) deformed and
    ``reference`` (N, 3) node positions, ``triangles`` (M, 3), ``element`` (M,) the result's
    element of each face, ``signs`` (M, 3) mirroring that element's vectors, ``planes`` the
    symmetry planes mirrored about (``symmetry_planes``), ``decimated`` whether a coarser
    copy stands for a mesh of more than ``FACE_BUDGET`` faces."""

    def __init__(self, x, reference, triangles, element, signs, planes, decimated):
        self.x, self.reference, self.triangles = x, reference, triangles
        self.element, self.signs, self.planes, self.decimated = element, signs, planes, decimated

    def planes_text(self) -> str:
        if not self.planes:
            return "no symmetry plane found: the model as computed"
        names = ", ".join(f"{AXIS_NAMES[a]} = {c:.4g}" for a, c in self.planes)
        return f"mirrored about the symmetry planes {names}"


def whole_membrane(vtu: Any, exclude_axis: int | None = None) -> MembraneShape:
    """The deformed membrane of a step (a meshio mesh with point data ``displacement`` and
    ``reaction``) mirrored about its symmetry planes (``symmetry_planes``; not the one
    normal to ``exclude_axis``). A mesh whose mirrored faces would exceed ``FACE_BUDGET`` is
    first coarsened by vertex clustering (``_decimate``)."""
    X = np.asarray(vtu.points, dtype=float)
    u = np.asarray(vtu.point_data["displacement"], dtype=float)
    reaction = vtu.point_data.get("reaction")
    reaction = np.zeros_like(u) if reaction is None else np.asarray(reaction, dtype=float)
    triangles = np.asarray(vtu.cells_dict["triangle"])
    planes = [p for p in symmetry_planes(X, u, reaction, triangles) if p[0] != exclude_axis]
    x = X + u
    tolerance = SYMMETRY_TOLERANCE * float(np.ptp(x, axis=0).max(initial=0.0))
    target = FACE_BUDGET // 2 ** len(planes)
    kept = np.arange(triangles.shape[0])
    decimated = triangles.shape[0] > target
    if decimated:
        x, X, triangles, kept = _decimate(x, X, triangles, target, planes, tolerance)
    (x, X), triangles, element, signs = mirror(triangles, planes, [x, X], tolerance)
    return MembraneShape(x, X, triangles, kept[element], signs, planes, decimated)


def _decimate(
    x: np.ndarray,
    reference: np.ndarray,
    triangles: np.ndarray,
    target: int,
    planes: list[tuple[int, float]],
    tolerance: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A coarser copy of the mesh with about ``target`` faces, by vertex clustering
    (Rossignac & Borrel 1993): the nodes in each cube of side h = sqrt(2 A / target)
    (A the deformed area) become one node at their mean; faces with two corners in one cube
    are dropped, and of faces with the same corners one is kept. A cluster that holds a node
    on a symmetry plane is put on the plane, so the mirrored halves still meet. Returns the
    deformed and reference nodes, the faces and the original face each one stands for."""
    corners = x[triangles]
    area = 0.5 * float(
        np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        ).sum()
    )
    side = np.sqrt(2.0 * area / max(target, 1)) if area > 0 else float(np.ptp(x, axis=0).max())
    key = np.floor((x - x.min(axis=0)) / side).astype(np.int64)
    _, cluster, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    cluster = cluster.ravel()

    def mean(p: np.ndarray) -> np.ndarray:
        sums = [np.bincount(cluster, p[:, j], count.size) for j in range(3)]
        return np.stack(sums, axis=1) / count[:, None]

    x_coarse, reference_coarse = mean(x), mean(reference)
    for axis, c in planes:
        on = np.bincount(cluster, np.abs(x[:, axis] - c) <= tolerance, count.size) > 0
        x_coarse[on, axis] = c
        reference_coarse[on, axis] = c
    faces = cluster[triangles]
    kept = np.flatnonzero(
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    )
    _, first = np.unique(np.sort(faces[kept], axis=1), axis=0, return_index=True)
    kept = kept[np.sort(first)]
    return x_coarse, reference_coarse, faces[kept], kept


def _normals(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit normals (m, 3) of the faces, oriented by the corners' order."""
    corners = x[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)


def _towards_viewer() -> np.ndarray:
    """Unit vector from the scene towards the camera of the 3-D view."""
    elevation, azimuth = np.radians(_ELEVATION), np.radians(_AZIMUTH)
    return np.array(
        [
            np.cos(elevation) * np.cos(azimuth),
            np.cos(elevation) * np.sin(azimuth),
            np.sin(elevation),
        ]
    )


def _shade(colours: np.ndarray, x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """RGBA face colours (m, 4) darkened by a light from above the camera (both sides lit)."""
    light = _towards_viewer() + np.array([0.0, 0.0, 0.8])
    light /= np.linalg.norm(light)
    brightness = 0.4 + 0.6 * np.abs(_normals(x, triangles) @ light)
    shaded = colours.copy()
    shaded[:, :3] *= brightness[:, None]
    return shaded


def _facing(x: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The faces (m,) bool that face the camera: the side the corners' order makes outer,
    or the other side if fewer than a quarter face it (a sheet oriented away)."""
    facing = _normals(x, triangles) @ _towards_viewer() > 0.0
    if np.count_nonzero(facing) < 0.25 * facing.size:
        facing = ~facing
    return facing


def _figure_3d(x: np.ndarray, length_unit: str, width: float = 8.5) -> tuple[Figure, Any]:
    """A figure with one 3-D axes holding the points x (n, 3) at equal scales, orthographic,
    seen from elevation 28 degrees, azimuth -60 degrees."""
    from matplotlib.ticker import MaxNLocator

    low, high = x.min(axis=0), x.max(axis=0)
    span = high - low
    floor = 0.02 * max(float(span.max()), 1e-300)
    middle = 0.5 * (low + high)
    span = np.maximum(span, floor)
    # the box on the screen (orthographic view; matplotlib scales the box to a diagonal of
    # sqrt(3) times zoom and draws it in a square of the axes' smaller side): the figure's
    # height and the zoom make it fill the axes
    azimuth = np.radians(_AZIMUTH)
    across = np.array([-np.sin(azimuth), np.cos(azimuth), 0.0])
    up = np.cross(_towards_viewer(), across)
    box = span * np.sqrt(3.0) / np.linalg.norm(span)
    corners = np.array(np.meshgrid([0, 1], [0, 1], [0, 1])).reshape(3, -1).T * box
    screen_width, screen_height = np.ptp(corners @ across), np.ptp(corners @ up)
    plot_width = width - 2.6  # the legend or the colour bar beside
    plot_height = plot_width * float(np.clip(screen_height / screen_width, 0.5, 1.0))
    square = min(plot_width, plot_height)
    zoom = 1.15 * min(plot_width / square / screen_width, plot_height / square / screen_height)
    fig = new_figure(figsize=(width, plot_height + 1.4), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    for k, name in enumerate(AXIS_NAMES):
        getattr(ax, f"set_{name}lim")(middle[k] - 0.5 * span[k], middle[k] + 0.5 * span[k])
        getattr(ax, f"set_{name}label")(_with_unit(name, length_unit), fontsize=9)
        bins = int(np.clip(round(7 * span[k] / span.max()), 1, 7))
        axis = getattr(ax, f"{name}axis")
        if high[k] - low[k] < floor:  # flat along it: one tick, at the membrane
            axis.set_ticks([middle[k]])
        else:
            axis.set_major_locator(MaxNLocator(bins + 1))
    ax.set_box_aspect(tuple(span / span.max()), zoom=float(np.clip(zoom, 0.6, 1.0)))
    ax.set_proj_type("ortho")
    ax.view_init(elev=_ELEVATION, azim=_AZIMUTH)
    ax.computed_zorder = False  # the lines are drawn on the faces, not sorted among them
    ax.tick_params(labelsize=7)
    return fig, ax


def _faces(shape: MembraneShape, colours: np.ndarray) -> Any:
    """The faces of the shape as a Poly3DCollection with the RGBA colours (m, 4), shaded,
    edges drawn where the faces are few enough to see them."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    few = shape.triangles.shape[0] <= 3000
    shaded = _shade(colours, shape.x, shape.triangles)
    return Poly3DCollection(
        shape.x[shape.triangles],
        facecolors=shaded,
        edgecolors=(1.0, 1.0, 1.0, 0.5) if few else shaded,
        linewidths=0.3 if few else 0.0,
        zorder=1,
    )


def _plot_shape_3d(
    shape: MembraneShape, cell: dict, where: str, length_unit: str, path: Path
) -> Path:
    """The deformed (mirrored) membrane in 3-D coloured by state, tension lines on the
    wrinkled faces that face the viewer."""
    from matplotlib.artist import Artist
    from matplotlib.colors import to_rgba_array
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    fig, ax = _figure_3d(shape.x, length_unit)
    state = np.clip(cell["state"].astype(int), 0, 2)
    face_state = state[shape.element]
    colours = to_rgba_array(list(STATE_COLOURS.values()))
    ax.add_collection3d(_faces(shape, colours[face_state]))
    handles: list[Artist] = [
        Patch(facecolor=colour, edgecolor="0.4", label=f"{name} ({np.count_nonzero(state == k)})")
        for k, (name, colour) in enumerate(STATE_COLOURS.items())
    ]
    wrinkled = np.flatnonzero((face_state == 1) & _facing(shape.x, shape.triangles))
    if wrinkled.size:
        tension = cell["tension_direction"][shape.element[wrinkled]] * shape.signs[wrinkled]
        segments, sampled = _tension_lines(
            shape.x, shape.triangles[wrinkled], tension, (0, 1, 2), lines_across=50
        )
        ax.add_collection3d(
            Line3DCollection(
                list(segments), colors="#202020", linewidths=0.7 if sampled else 1.0, zorder=2
            )
        )
        handles.append(_tension_handle(sampled, 1.0))
    fig.legend(
        handles=handles, loc="outside left upper", title="elements (of the model)", fontsize=8
    )
    note = "; drawn coarsened (vertex clustering)" if shape.decimated else ""
    ax.set_title(
        f"Taut, wrinkled and slack elements, deformed membrane in 3-D\n{where}\n"
        f"{shape.planes_text()}{note}",
        fontsize=10,
    )
    fig.savefig(path, dpi=150)
    return path


def _tension_handle(sampled: bool, width: float) -> Any:
    """The legend entry of the tension lines (line width ``width``, points)."""
    from matplotlib.lines import Line2D

    label = "tension lines" + (",\nsampled" if sampled else "")
    return Line2D([], [], color="#202020", lw=width, label=label)


def _stress_range(major: np.ndarray) -> tuple[float, float, bool]:
    """Colour range of the major principal stress: (low, high, clipped), clipped at the 98th
    percentile where the largest value is above 1.5 times it."""
    top = float(np.percentile(major, 98))
    clipped = bool(major.max() > 1.5 * top > 0)
    return min(0.0, float(major.min())), top if clipped else float(major.max()), clipped


def _plot_stress_3d(
    shape: MembraneShape, cell: dict, where: str, length_unit: str, unit: str, path: Path
) -> Path:
    """The major principal stress resultant on the deformed (mirrored) 3-D shape."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    fig, ax = _figure_3d(shape.x, length_unit, width=9.0)
    major = np.asarray(cell["principal_stress"])[:, 1]
    low, high, clipped = _stress_range(major)
    norm = Normalize(vmin=low, vmax=high if high > low else low + 1.0)
    cmap = colormaps["viridis"]
    ax.add_collection3d(_faces(shape, cmap(norm(major[shape.element]))))
    bar = fig.colorbar(
        ScalarMappable(norm=norm, cmap=cmap),
        ax=ax,
        shrink=0.7,
        extend="max" if clipped else "neither",
    )
    bar.set_label(_with_unit("major principal stress resultant", unit))
    note = ""
    if clipped:
        note = (
            f"; colours clipped at the 98th percentile, "
            f"maximum {major.max():.3g}{' ' + unit if unit else ''}"
        )
    ax.set_title(
        f"Major principal Cauchy stress resultant on the deformed membrane\n{where}\n"
        f"{shape.planes_text()}{note}",
        fontsize=10,
    )
    fig.savefig(path, dpi=150)
    return path


def height_map_axes(reference: np.ndarray, x: np.ndarray) -> tuple[int, int, int] | None:
    """(a, b, n): the plan axes a < b and the out-of-plane axis n of a nearly flat membrane
    with reference nodes ``reference`` and deformed nodes ``x`` (N, 3), or None. Nearly flat:
    the reference lies in a coordinate plane (its extent along n at most 1e-6 of the largest)
    and the deformed membrane rises across it by at most half its smaller extent along the
    plan axes, but by something (more than 1e-9 of its size): a height map of a sheet that
    stays in its plane would be one colour, and of a deep shape would hide its overhangs."""
    extent = np.ptp(reference, axis=0)
    n = int(np.argmin(extent))
    if not extent.max() > 0 or extent[n] > 1e-6 * extent.max():
        return None
    a, b = (k for k in range(3) if k != n)
    deformed = np.ptp(x, axis=0)
    rise = float(deformed[n])
    if rise <= 1e-9 * deformed.max() or rise > 0.5 * min(deformed[a], deformed[b]):
        return None
    return a, b, n


def _plot_height(shape: MembraneShape, where: str, length_unit: str, path: Path) -> Path | None:
    """Filled contours of the out-of-plane displacement on the plan of a nearly flat
    membrane (``height_map_axes``; ``shape`` mirrored only about planes across the plan);
    None (nothing written) for any other."""
    axes = height_map_axes(shape.reference, shape.x)
    if axes is None or any(axis == axes[2] for axis, _ in shape.planes):
        return None
    a, b, n = axes
    reference, triangles = shape.reference, shape.triangles
    height = shape.x[:, n] - reference[:, n]
    span = np.ptp(reference[:, [a, b]], axis=0)
    aspect = float(np.clip(span[1] / span[0], 0.25, 2.0)) if span[0] > 0 else 1.0
    fig = new_figure(figsize=(7.5, 1.4 + 5.1 * aspect), layout="constrained")
    ax = fig.subplots()
    ax.set_aspect("equal")
    from matplotlib.tri import Triangulation

    plan = Triangulation(reference[:, a], reference[:, b], triangles)
    levels = np.linspace(float(height.min()), float(height.max()), 15)
    image = ax.tricontourf(plan, height, levels=levels, cmap="cividis")
    ax.tricontour(
        plan,
        height,
        levels=levels,
        colors="0.15",
        linewidths=0.3,
    )
    bar = fig.colorbar(image, ax=ax, shrink=0.9)
    bar.set_label(_with_unit(f"out-of-plane displacement u{AXIS_NAMES[n]}", length_unit))
    ax.set_xlabel(_with_unit(AXIS_NAMES[a], length_unit))
    ax.set_ylabel(_with_unit(AXIS_NAMES[b], length_unit))
    planes = [(axis, c) for axis, c in shape.planes if axis in (a, b)]
    for axis, c in planes:
        line = ax.axvline if axis == a else ax.axhline
        line(c, color="white", lw=0.8, ls="--")
    mirrored = "; dashed: the symmetry planes mirrored about" if planes else ""
    ax.set_title(
        f"Height map: out-of-plane displacement on the reference {AXIS_NAMES[a]}"
        f"{AXIS_NAMES[b]}-plane\n{where}{mirrored}; largest "
        f"{float(np.abs(height).max()):.4g}{' ' + length_unit if length_unit else ''}",
        fontsize=10,
    )
    fig.savefig(path, dpi=150)
    return path


def _plot_fibres(vtu: Any, cell: dict, length_unit: str, path: Path) -> Path | None:
    """The fibre directions (material axis 1, ``fibre_direction``) in the reference
    configuration, where they are not the default x axis in every element; None (nothing
    written) where they are. A plane reference is drawn on its plan, the faces coloured by
    the fibres' angle; a curved one in 3-D, lines on the faces facing the viewer."""
    fibre = cell.get("fibre_direction")
    if fibre is None or np.allclose(fibre, [1.0, 0.0, 0.0], atol=1e-9):
        return None
    fibre = np.asarray(fibre, dtype=float)
    reference = np.asarray(vtu.points, dtype=float)
    triangles = np.asarray(vtu.cells_dict["triangle"])
    extent = np.ptp(reference, axis=0)
    n = int(np.argmin(extent))
    title = "Fibre directions (material axis 1) in the reference configuration"
    if extent[n] <= 1e-6 * extent.max():
        from matplotlib.collections import LineCollection

        a, b = (k for k in range(3) if k != n)
        view = _View(reference, triangles, length_unit)
        fig, ax = view.figure()
        angle = np.degrees(np.arctan2(fibre[:, b], fibre[:, a])) % 180.0
        image = ax.tripcolor(
            reference[:, a],
            reference[:, b],
            triangles,
            facecolors=angle,
            cmap="twilight",
            vmin=0.0,
            vmax=180.0,
            edgecolors="face",
            linewidth=0.2,
        )
        bar = fig.colorbar(image, ax=ax, shrink=0.9, ticks=[0, 45, 90, 135, 180])
        bar.set_label(f"fibre angle from {AXIS_NAMES[a]} (degrees)")
        segments, _ = _tension_lines(reference, triangles, fibre, (a, b), lines_across=40)
        ax.add_collection(LineCollection(list(segments), colors="black", linewidths=0.9))
    else:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection

        shape = MembraneShape(
            reference,
            reference,
            triangles,
            np.arange(triangles.shape[0]),
            np.ones((triangles.shape[0], 3)),
            [],
            False,
        )
        fig, ax = _figure_3d(reference, length_unit)
        ax.add_collection3d(_faces(shape, np.tile([0.85, 0.85, 0.85, 1.0], (len(triangles), 1))))
        front = np.flatnonzero(_facing(reference, triangles))
        segments, _ = _tension_lines(
            reference, triangles[front], fibre[front], (0, 1, 2), lines_across=50
        )
        ax.add_collection3d(
            Line3DCollection(list(segments), colors="black", linewidths=0.8, zorder=2)
        )
    ax.set_title(title + "\nas the material was given (not mirrored)", fontsize=10)
    fig.savefig(path, dpi=150)
    return path


def _plot_newton_history(summary: dict, path: Path) -> Path:
    """The residual of every Newton iteration (summary's per-step ``residual_history``;
    the step's last residual where a summary has none) against the cumulative iteration
    number, log scale, each step's iterations joined and the steps marked."""
    fig = new_figure(figsize=(8.0, 4.5), layout="constrained")
    ax = fig.subplots()
    force = _unit(summary.get("units") or {}, "force")
    start, steps = 0, summary["steps"]
    cycle = colour_cycle()[:2]
    for k, step in enumerate(steps):
        residuals = np.asarray(step.get("residual_history") or [], dtype=float)
        iterations = np.arange(start + 1, start + residuals.size + 1)
        if residuals.size == 0:  # an older summary: the converged residual only
            residuals = np.array([float(step.get("residual", np.nan))])
            iterations = np.array([start + max(int(step.get("iterations", 1)), 1)])
        residuals = np.where(residuals > 0, residuals, np.nan)
        ax.semilogy(iterations, residuals, "o-", ms=3, lw=1.0, color=cycle[k % len(cycle)])
        if k:
            ax.axvline(start + 0.5, color="0.75", lw=0.6, ls=":")
        if len(steps) <= 24:
            ax.annotate(
                f"{step['load_factor']:.3g}",
                (0.5 * (start + 1 + iterations[-1]), 1.0),
                xycoords=("data", "axes fraction"),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                va="bottom",
                fontsize=7,
                color="0.3",
            )
        start = int(iterations[-1])
    ax.set_xlabel("Newton iteration, counted over all steps")
    ax.set_ylabel(_with_unit("residual norm", force))
    ax.set_xlim(0.5, max(start, 1) + 0.5)
    ax.grid(True, which="both", alpha=0.25)
    labels = "; the steps' load factors above" if len(steps) <= 24 else ""
    ax.set_title(
        f"Convergence: residual of each iteration, {len(steps)} "
        f"step{'s' if len(steps) != 1 else ''}, {start} iterations{labels}",
        fontsize=10,
        pad=14,
    )
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
