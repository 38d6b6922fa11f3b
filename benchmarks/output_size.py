"""Results files at scale (issue 22, item 3): the size on disk and the write time of one
step's results, as .vtu (the mesh in every step) and as the XDMF time series (the mesh
written once in mesh.h5, each step's fields in step_NNNN.h5), all fields and a few.

A square sheet of --elements triangles (St Venant-Kirchhoff, E t = 1 kN/m) clamped round its
edge, displaced by the smooth field u = a (sin(pi x) sin(pi y), sin(2 pi x) sin(pi y),
4 sin(pi x) sin(pi y)) with a = 1 % of its side: every element differs from its neighbours,
as in a solved state, so the files compress as real results do. Its reactions are those of
that field (``DiscreteSystem.reactions``). Each format writes --steps steps into its own
folder; the table gives the median of the steps' sizes and write times (the per-step write
is ``ResultWriter.write_step``, its element evaluation included), the mesh file once, the
whole run's folder and its ratio to the .vtu run's with all fields; also in single
precision (``[output] precision = "single"``: all but the displacement and reactions).

    python benchmarks/output_size.py --elements 100000 1000000
"""

from __future__ import annotations

import argparse
import platform
import shutil
import statistics
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from table import write_csv

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.output import ResultWriter

FEW = ("state", "principal_stress_major", "principal_stress_minor", "tension_direction")


def sheet(elements: int) -> tuple[Model, SimpleNamespace]:
    """The clamped sheet on about ``elements`` triangles and one step of the smooth field."""
    n = max(2, round(np.sqrt(elements / 2)))
    mesh = rectangle(1.0, 1.0, n, n)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=1e5, nu=0.3, thickness=0.01))
    model.fix("x == 0 or x == 1 or y == 0 or y == 1")
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    bump = np.sin(np.pi * x) * np.sin(np.pi * y)
    u = 0.01 * np.stack([bump, np.sin(2 * np.pi * x) * np.sin(np.pi * y), 4 * bump], axis=1)
    u = u.reshape(-1)
    reactions = model.discretise().reactions(u, 1.0)
    step = SimpleNamespace(
        load_factor=1.0,
        displacement=u,
        iterations=1,
        residual=0.0,
        reactions=reactions,
        states=(mesh.n_elements, 0, 0),
    )
    return model, step


def measure(
    model: Model, step, file_format: str, fields, precision: str, steps: int, folder: Path
) -> dict:
    """Write ``steps`` steps into ``folder``: the median size (MB) and time of a step, the
    mesh file's size and the whole folder's."""
    writer = ResultWriter(
        folder, model, file_format=file_format, fields=fields, precision=precision
    )
    sizes, times = [], []
    for _ in range(steps):
        start = time.perf_counter()
        path = writer.write_step(step)
        times.append(time.perf_counter() - start)
        sizes.append(path.stat().st_size / 1e6)
    writer.finish(True, "done")
    mesh_file = folder / "mesh.h5"
    return {
        "step_MB": statistics.median(sizes),
        "write_s": statistics.median(times),
        "mesh_MB": mesh_file.stat().st_size / 1e6 if mesh_file.is_file() else 0.0,
        "run_MB": sum(path.stat().st_size for path in folder.iterdir()) / 1e6,
    }


CHOICES = (  # format, fields, their label, precision; the first is the baseline
    ("vtu", None, "all", "double"),
    ("xdmf", None, "all", "double"),
    ("xdmf", None, "all", "single"),
    ("vtu", FEW, "four", "double"),
    ("xdmf", FEW, "four", "double"),
    ("xdmf", FEW, "four", "single"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=float, nargs="+", default=[1e5, 1e6])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--csv", help="also write the table as CSV")
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {time.strftime('%Y-%m-%d')}")
    print(
        f"{'elements':>10} {'format':>6} {'fields':>6} {'precision':>9} {'MB a step':>10} "
        f"{'s a step':>9} {'mesh MB once':>13} {'MB the run':>11} {'of vtu':>7}"
    )
    rows = []
    for elements in args.elements:
        model, step = sheet(int(elements))
        baseline = None
        for file_format, fields, label, precision in CHOICES:
            folder = Path(tempfile.mkdtemp(prefix="wrinkle-output-"))
            try:
                row = measure(model, step, file_format, fields, precision, args.steps, folder)
            finally:
                shutil.rmtree(folder)
            baseline = baseline or row["run_MB"]
            row.update(
                elements=model.mesh.n_elements,
                format=file_format,
                fields=label,
                precision=precision,
                of_vtu=row["run_MB"] / baseline,
            )
            rows.append(row)
            print(
                f"{row['elements']:>10,} {file_format:>6} {label:>6} {precision:>9} "
                f"{row['step_MB']:>10.1f} {row['write_s']:>9.2f} {row['mesh_MB']:>13.1f} "
                f"{row['run_MB']:>11.1f} {row['of_vtu']:>7.2f}",
                flush=True,
            )
    if args.csv:
        write_csv(args.csv, rows, list(rows[0]))


if __name__ == "__main__":
    main()
