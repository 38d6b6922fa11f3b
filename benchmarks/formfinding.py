"""Form finding at scale (issue 21, item 3): the four-point sail on meshes of 10^3 to 10^5
elements.

A 10 m square sail, corners (0, 0) and (10, 10) held at z = 0 and (10, 0), (0, 10) raised
3 m, prestress 2 kN/m (PVC-polyester, E = 600 MPa, t = 1 mm), edge cables of 20 kN
(EA = 10 MN), form-found by ``wrinkle.formfinding.find_form`` (updated reference strategy,
tolerance 1e-6 of the sail's size). For each mesh: the outer iterations (one factorisation of
the scalar matrix L_k each), the wall time (median of --repeats), the time per iteration per
element, the centre's height (1.5 m by the sail's symmetry), and the largest difference of
the found shape from the same sail with E 1000 times larger (the form depends on the
prestress alone).

    python benchmarks/formfinding.py [--sizes 16 32 64 128 224] [--repeats 3] [--csv PATH]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

import numpy as np
from table import write_csv

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.formfinding import FormFinding, find_form
from wrinkle.materials import Prestressed

SIDE, RISE, PRESTRESS, CABLE = 10.0, 3.0, 2000.0, 2e4  # m, m, N/m, N


def sail(n: int, E: float = 6e8) -> Model:
    """The four-point sail on an n x n mesh (2 n^2 triangles) with Young's modulus E."""
    model = Model(
        rectangle(SIDE, SIDE, n, n),
        Prestressed(StVenantKirchhoff.isotropic(E=E, nu=0.3, thickness=1e-3), PRESTRESS),
    )
    for selector in ("y == 0", "y == 10", "x == 0", "x == 10"):
        model.add_cables(selector, EA=1e7, prestress=CABLE, label=selector)
    model.fix("x == 0 and y == 0 or x == 10 and y == 10")
    model.prescribe("x == 10 and y == 0 or x == 0 and y == 10", [0.0, 0.0, RISE])
    return model


def centre_height(form: FormFinding) -> float:
    """z of the found node nearest the plan centre (m)."""
    centre = np.argmin(np.linalg.norm(form.mesh.nodes[:, :2] - SIDE / 2, axis=1))
    return float(form.nodes[centre, 2])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64, 128, 224])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--csv", help="also write the table as CSV")
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {time.strftime('%Y-%m-%d')}")
    header = (
        f"{'elements':>9} {'iterations':>10} {'converged':>9} {'time s':>7} "
        f"{'us/el/it':>8} {'centre z m':>11} {'|x(E) - x(1000E)| m':>20}"
    )
    print(header)
    rows = []
    for n in args.sizes:
        times, form = [], None
        for _ in range(args.repeats):
            model = sail(n)
            start = time.perf_counter()
            form = find_form(model)
            times.append(time.perf_counter() - start)
        assert form is not None
        stiff = find_form(sail(n, E=6e11))
        row = {
            "elements": 2 * n * n,
            "iterations": form.iterations,
            "converged": form.converged,
            "seconds": statistics.median(times),
            "centre_z": centre_height(form),
            "stiffness_difference": float(np.abs(form.nodes - stiff.nodes).max()),
        }
        row["us_per_element_iteration"] = (
            1e6 * row["seconds"] / (row["elements"] * row["iterations"])
        )
        rows.append(row)
        print(
            f"{row['elements']:>9,} {row['iterations']:>10} {str(row['converged']):>9} "
            f"{row['seconds']:>7.2f} {row['us_per_element_iteration']:>8.2f} "
            f"{row['centre_z']:>11.6f} {row['stiffness_difference']:>20.1e}",
            flush=True,
        )
    if args.csv:
        write_csv(args.csv, rows, list(rows[0]))


if __name__ == "__main__":
    main()
