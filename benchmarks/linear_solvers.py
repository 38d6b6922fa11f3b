"""Sparse linear solvers on the matrices wrinkle's Newton iteration really produces.

The matrix is the tangent K + theta I of the quarter airbag (examples/airbag.toml, follower
pressure, taut, wrinkled and slack elements) at a realistic deformed state: the converged
displacement of a 32 x 32 mesh interpolated onto the finer mesh. theta is Newton's first
regularisation (1e-8 of the mean diagonal stiffness). For each back-end of
``wrinkle.solvers.linear``: the first factorisation (ordering included), a refactorisation
with new values on the same pattern (what every further Newton iteration costs), one solve,
the relative residual |A x - b| / |b| and the growth of the resident set while the factor is
held. The airbag's tangent is symmetric (the solver detects it): each back-end is told so, and
PARDISO is also timed as if it were not ("pardiso/LU", its general LU, the only mode before
symmetric matrices took the LDL^T path). Medians of --repeat runs. Prints a table and writes it
as CSV.

    python benchmarks/linear_solvers.py --sizes 32 100 316 --repeat 3
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from table import write_csv

from wrinkle.case import read_case
from wrinkle.solvers.linear import LINEAR_SOLVERS, diagonal_positions, make_linear_solver

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "examples" / "airbag.toml"


def resident_mb() -> float:
    """Current resident set of this process, MB (Linux /proc)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096 / 2**20


def coarse_solution(n: int = 32):
    """Converged airbag displacements on an n x n grid of squares, as an interpolant of
    (X, Y) giving (ux, uy, uz)."""
    model = read_case(CASE, overrides={"mesh": {"rectangle": {"nx": n, "ny": n}}}).model
    u = model.solve(tolerance=1e-8).final.displacement.reshape(-1, 3)
    side = model.mesh.nodes[:, 0].max()
    grid = np.linspace(0.0, side, n + 1)
    # rectangle() numbers nodes row by row: x fastest
    values = u.reshape(n + 1, n + 1, 3)  # [j (y), i (x), component]
    return RegularGridInterpolator((grid, grid), values)


def airbag_matrix(n: int, interpolant, bending: bool = False):
    """Shifted tangent A (CSR), right-hand side b and symmetry flag of the n x n airbag; with
    ``bending``, of the airbag with the sheet's bending stiffness (``[material] bending``),
    whose matrix couples each node with its neighbours' neighbours too."""
    overrides = {"mesh": {"rectangle": {"nx": n, "ny": n}}, "material": {"bending": bending}}
    model = read_case(CASE, overrides=overrides).model
    X = model.mesh.nodes
    u = interpolant(np.column_stack([X[:, 1], X[:, 0]])).ravel()
    problem = model.discretise().at(1.0)
    evaluation = problem.evaluate(u)
    K = evaluation.stiffness
    diagonal = diagonal_positions(K)
    free = problem.free
    theta = 1e-8 * float(np.abs(K.data[diagonal][free]).mean())
    A = K.copy()
    A.data[diagonal[free]] += theta
    asymmetry = abs(A - A.T).max() / abs(A).max()
    return A, evaluation.residual, asymmetry < 1e-10, model.mesh.n_elements


def measure(name: str, A, b, symmetric: bool, repeat: int) -> dict:
    """Timings of back-end ``name`` ("pardiso/LU": PARDISO told the matrix is general)."""
    if name == "pardiso/LU":
        symmetric = False
    first, again, solves, residuals, memory = [], [], [], [], []
    for _ in range(repeat):
        gc.collect()
        backend = make_linear_solver(name.split("/")[0], A.shape[0])
        before = resident_mb()
        start = time.perf_counter()
        solve = backend.factorise(A, symmetric)
        first.append(time.perf_counter() - start)
        if solve is None:
            return {"solver": name, "status": "singular or not positive definite"}
        memory.append(resident_mb() - before)
        B = A.copy()
        B.data *= 1.0 + 1e-6  # new values, same pattern: a later Newton iteration
        start = time.perf_counter()
        solve = backend.factorise(B, symmetric)
        again.append(time.perf_counter() - start)
        start = time.perf_counter()
        x = solve(b)
        solves.append(time.perf_counter() - start)
        residuals.append(float(np.linalg.norm(B @ x - b) / np.linalg.norm(b)))
        del solve, backend
    return {
        "solver": name,
        "status": "ok",
        "first_factorisation_s": statistics.median(first),
        "refactorisation_s": statistics.median(again),
        "solve_s": statistics.median(solves),
        "relative_residual": max(residuals),
        "factor_memory_mb": statistics.median(memory),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=[32, 100, 316],
        help="squares per side of the airbag mesh (2 n^2 triangles)",
    )
    parser.add_argument("--solvers", nargs="+", default=[*LINEAR_SOLVERS, "pardiso/LU"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--bending", action="store_true", help="the airbag with bending")
    parser.add_argument("--csv", default="linear_solvers.csv")
    args = parser.parse_args()
    interpolant = coarse_solution()
    rows = []
    header = (
        f"{'elements':>9} {'unknowns':>9} {'solver':>10} {'1st fact. s':>11} "
        f"{'refact. s':>10} {'solve s':>8} {'rel. resid.':>11} {'factor MB':>9}"
    )
    print(header)
    for n in args.sizes:
        A, b, symmetric, n_elements = airbag_matrix(n, interpolant, args.bending)
        for name in args.solvers:
            try:
                row = measure(name, A, b, symmetric, args.repeat)
            except ImportError as error:
                row = {"solver": name, "status": f"not installed: {error}"}
            row.update(elements=n_elements, unknowns=A.shape[0], symmetric=symmetric)
            rows.append(row)
            if row["status"] != "ok":
                print(f"{n_elements:9d} {A.shape[0]:9d} {name:>10} {row['status']}")
                continue
            print(
                f"{n_elements:9d} {A.shape[0]:9d} {name:>10} {row['first_factorisation_s']:11.3f} "
                f"{row['refactorisation_s']:10.3f} {row['solve_s']:8.3f} "
                f"{row['relative_residual']:11.1e} {row['factor_memory_mb']:9.0f}",
                flush=True,
            )
    keys = [
        "elements",
        "unknowns",
        "symmetric",
        "solver",
        "status",
        "first_factorisation_s",
        "refactorisation_s",
        "solve_s",
        "relative_residual",
        "factor_memory_mb",
    ]
    write_csv(args.csv, rows, keys)


if __name__ == "__main__":
    main()
