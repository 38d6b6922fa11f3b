"""The paper's test: a square membrane sheared, then stretched (Roddeman et al. 1987, Part II,
section 4, Figs. 6-7; docs/method.md section 8).

    python examples/paper_test.py --out DIR [--method newton|restricted-step]

The unit square (thickness 1) meshed with 3 x 3 squares split in two; its 12 boundary nodes
follow x = X + gamma Y, y = (1 + v) Y with the shear gamma = 0.1 applied first and then held
while v goes from 0 to 0.1 in steps of 0.005, each step started from the previous solution;
the 4 interior nodes are free. Transversely isotropic St. Venant-Kirchhoff, E_L = f, E_T = 1,
nu_LT = nu_TT = 0.3, G_LT = 1/2.6, fibres along X, for f = 1, 2, 5. F1, F2 are the sums of the
top-edge nodes' reactions along x and y; they are compared with the homogeneous solution,
computed independently by minimising the relaxed energy at one material point
(``verification.references.shear_stretch``), which they equal to round-off.

Prints one row per (f, v), writes DIR/shear_stretch.csv and DIR/shear_stretch.png (the two
panels of the paper's figures) and exits with status 0. It runs from a checkout: it imports the
sequence and the reference from the repository's ``verification`` package
(``verification.paper_test``), which the installed package does not contain. The proportional
path of the same square is the case file ``examples/shear_stretch.toml``.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout's verification

from verification.paper_test import (  # noqa: E402
    ANISOTROPY,
    SHEAR,
    STRETCHES,
    ShearStretchRow,
    analytic_curves,
    paper_material,
    plot_shear_stretch,
    shear_stretch_sequence,
)
from wrinkle.mesh import rectangle  # noqa: E402
from wrinkle.model import Model  # noqa: E402
from wrinkle.solvers import SOLVERS, make_solver  # noqa: E402

__all__ = ["STRETCHES", "main", "run_paper_test", "shear_stretch", "write_csv"]


def shear_stretch(
    anisotropy=ANISOTROPY,
    stretches=STRETCHES,
    shear: float = SHEAR,
    method: str = "newton",
    tolerance: float = 1e-12,
) -> list[ShearStretchRow]:
    """Run the test for every f in ``anisotropy`` on the paper's 3 x 3 mesh and return one row
    per (f, v)."""
    mesh = rectangle(1.0, 1.0, 3, 3)
    sides = ("left", "right", "bottom", "top")
    boundary = np.unique(np.concatenate([mesh.node_sets[s] for s in sides]))
    solver = make_solver(method, tolerance=tolerance, max_iterations=100)
    rows = []
    for f in anisotropy:
        model = Model(mesh, paper_material(f), fibre_direction=(1.0, 0.0, 0.0))
        model.prescribe(boundary, np.zeros(3))
        rows += shear_stretch_sequence(model, f, stretches, shear, solver)
    return rows


def write_csv(rows: list[ShearStretchRow], path: str | os.PathLike) -> None:
    """Write the rows as CSV with columns f, v, F1, F2, state, iterations and the references."""
    fields = [
        "f",
        "v",
        "F1",
        "F2",
        "state",
        "iterations",
        "F1_analytic",
        "F2_analytic",
        "state_analytic",
        "relative_error",
        "interior_error",
    ]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(fields)
        for r in rows:
            writer.writerow(
                [
                    r.f,
                    r.v,
                    f"{r.F1:.15g}",
                    f"{r.F2:.15g}",
                    r.state,
                    r.iterations,
                    f"{r.F1_analytic:.15g}",
                    f"{r.F2_analytic:.15g}",
                    r.state_analytic,
                    f"{r.relative_error:.3e}",
                    f"{r.interior_error:.3e}",
                ]
            )


def run_paper_test(out: str | os.PathLike, method: str = "newton") -> list[ShearStretchRow]:
    """Run the test and write ``out/shear_stretch.csv`` and ``out/shear_stretch.png``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = shear_stretch(method=method)
    write_csv(rows, out / "shear_stretch.csv")
    plot_shear_stretch(rows, out / "shear_stretch.png", SHEAR, analytic_curves(rows, SHEAR))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="paper_test.py",
        description="The paper's shear-stretch test (Roddeman et al. 1987, Figs. 6-7).",
    )
    parser.add_argument("--out", default="paper-test-results", help="output directory")
    parser.add_argument("--method", choices=sorted(SOLVERS), default="newton")
    args = parser.parse_args(argv)
    out = Path(args.out)
    rows = run_paper_test(out, method=args.method)
    worst = max(r.relative_error for r in rows)
    print(f"{'f':>4} {'v':>6} {'F1':>14} {'F2':>14} {'state':>9} {'iter':>4}")
    for r in rows:
        print(f"{r.f:4g} {r.v:6.3f} {r.F1:14.10f} {r.F2:14.10f} {r.state:>9} {r.iterations:4d}")
    print(f"largest relative difference from the analytic solution: {worst:.2e}")
    print(f"wrote {out / 'shear_stretch.csv'} and {out / 'shear_stretch.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
