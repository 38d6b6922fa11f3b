"""An interactive view of a results folder with pyvista (the optional ``viz`` extra:
pip install "wrinkle[viz]"); nothing else in wrinkle imports it."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["NO_PYVISTA", "show_results"]

NO_PYVISTA = 'wrinkle show needs pyvista; install it with pip install "wrinkle[viz]"'


def show_results(out_dir: str | os.PathLike) -> None:
    """Open a pyvista window on the last readable step of ``out_dir`` (a folder written by
    ``wrinkle run``): the membrane warped by its displacement (true scale), coloured by
    state (0 taut, 1 wrinkled, 2 slack), with the tension directions of the wrinkled
    elements as lines. Raises ImportError with the install command if pyvista is missing,
    ValueError for a folder without a readable step."""
    try:
        import pyvista
    except ImportError:
        raise ImportError(NO_PYVISTA) from None
    import numpy as np

    from wrinkle.output import SUMMARY
    from wrinkle.plot import STATE_COLOURS, _read_last_step, _read_summary

    out_dir = Path(out_dir)
    last, vtu, cell, _ = _read_last_step(out_dir, _read_summary(out_dir / SUMMARY))
    triangles = np.asarray(vtu.cells_dict["triangle"])
    faces = np.hstack([np.full((triangles.shape[0], 1), 3), triangles]).ravel()
    x = np.asarray(vtu.points) + np.asarray(vtu.point_data["displacement"])
    surface = pyvista.PolyData(x, faces)
    surface.cell_data["state"] = np.asarray(cell["state"], dtype=int)
    plotter = pyvista.Plotter(title=f"wrinkle: {out_dir}, load factor {last['load_factor']:.4g}")
    plotter.add_mesh(
        surface,
        scalars="state",
        cmap=list(STATE_COLOURS.values()),
        clim=(-0.5, 2.5),
        show_edges=triangles.shape[0] <= 20_000,
        scalar_bar_args={"title": "state: 0 taut, 1 wrinkled, 2 slack", "n_labels": 3},
    )
    wrinkled = np.flatnonzero(surface.cell_data["state"] == 1)
    if wrinkled.size:
        centres = x[triangles[wrinkled]].mean(axis=1)
        tension = np.asarray(cell["tension_direction"])[wrinkled]
        corners = x[triangles[wrinkled]]
        size = np.sqrt(
            np.linalg.norm(
                np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
            )
        )
        half = 0.35 * size[:, None] * tension
        ends = np.stack([centres - half, centres + half], axis=1).reshape(-1, 3)
        plotter.add_mesh(pyvista.line_segments_from_points(ends), color="black")
    plotter.show()
