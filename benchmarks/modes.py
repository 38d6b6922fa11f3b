"""Modal analysis against one factorisation of the same matrix (issue 21, item 4).

A rectangular membrane 1 x 0.7 m (E = 1 MPa, nu = 0.3, t = 1 mm, rho = 1000 kg/m^3) under
uniform tension, made by moving its edges to a 1 % biaxial stretch, meshed with about
--elements triangles. At the balanced state: the time and the growth of the peak resident
set of one factorisation of K_ff - sigma M_ff (sigma the default shift, ``wrinkle.modes``)
by each back-end, and of the shift-invert solve of the lowest --count modes
(``solve_eigenproblem``: that factorisation plus the Lanczos iterations, each one solve),
with the number of solves, as it is ("new": ARPACK at ``TOLERANCE``, PARDISO with
``PARDISO_REFINEMENT`` refinement steps, OpenBLAS on ``LANCZOS_BLAS_THREADS`` threads where
threadpoolctl is installed) and as it was ("old": ARPACK at machine precision, PARDISO's
default two refinement steps, OpenBLAS's threads as they are); and SciPy's own
shift-invert (``eigsh(sigma=...)``, its SuperLU of K - sigma M with SciPy's default
ordering) for comparison. Times and memory
are medians of --repeats runs, old and new in turns; the eigenvalues of old and new are
compared. The issue's target: at most five factorisations' worth of time and memory. Peak
memory from VmHWM (Linux /proc), reset before each measurement. Also checks the lowest
frequency against f_11 of the membrane.

    python benchmarks/modes.py --elements 100000 --count 10 --repeats 3
"""

from __future__ import annotations

import argparse
import gc
import math
import platform
import statistics
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla
from table import write_csv

import wrinkle.modes as modes_module
from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.modes import SHIFT, consistent_mass, solve_eigenproblem
from wrinkle.solvers.linear import make_linear_solver

E, NU, THICKNESS, DENSITY, STRETCH = 1e6, 0.3, 1e-3, 1000.0, 1.01
WIDTH, HEIGHT = 1.0, 0.7


def peak_reset() -> None:
    Path("/proc/self/clear_refs").write_text("5")


def peak_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return math.nan


def resident_mb() -> float:
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096 / 2**20


def measure(work):
    """(result, seconds, peak growth MB) of work()."""
    gc.collect()
    peak_reset()
    before = resident_mb()
    start = time.perf_counter()
    result = work()
    seconds = time.perf_counter() - start
    return result, seconds, peak_mb() - before


def membrane(elements: int):
    """The stretched membrane's free K_ff, M_ff and f_11 (Hz) on about ``elements``."""
    nx = round(math.sqrt(elements / (2 * HEIGHT / WIDTH)))
    mesh = rectangle(WIDTH, HEIGHT, nx, round(HEIGHT / WIDTH * nx))
    model = Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS))
    X = mesh.nodes
    edge = np.flatnonzero(
        np.isclose(X[:, 0], 0)
        | np.isclose(X[:, 0], WIDTH)
        | np.isclose(X[:, 1], 0)
        | np.isclose(X[:, 1], HEIGHT)
    )
    displacement = np.zeros((edge.size, 3))
    displacement[:, :2] = (STRETCH - 1.0) * X[edge, :2]
    model.prescribe(edge, displacement)
    u = model.solve(steps=1).final.displacement
    system = model.discretise()
    K = system.at(1.0).evaluate(u).tangent
    M = consistent_mass(
        system.pattern, system.geometry.area, np.full(mesh.n_elements, DENSITY * THICKNESS)
    )
    free = ~system.constrained
    tension = E * THICKNESS / (1 - NU) * (STRETCH**2 - 1) / 2
    rho_a = DENSITY * THICKNESS / STRETCH**2
    f11 = 0.5 * math.sqrt(tension / rho_a) * math.hypot(1 / WIDTH, 1 / HEIGHT) / STRETCH
    K_ff, M_ff = K[free][:, free].tocsr(), M[free][:, free].tocsr()
    return mesh.n_elements, K_ff, M_ff, f11


class CountingSolver:
    """A back-end that counts the solves of its factorisations."""

    def __init__(self, inner):
        self.inner, self.solves = inner, 0
        if hasattr(inner, "factorise_with_inertia"):
            self.factorise_with_inertia = self._with_inertia
        if hasattr(inner, "refinement"):  # PARDISO's, set by solve_eigenproblem
            self.refinement = inner.refinement

    def __setattr__(self, name, value):
        super().__setattr__(name, value)
        if name == "refinement":
            self.inner.refinement = value

    def _count(self, solve):
        def counted(b):
            self.solves += 1
            return solve(b)

        return counted

    def factorise(self, A, symmetric):
        return self._count(self.inner.factorise(A, symmetric))

    def _with_inertia(self, A):
        solve, below = self.inner.factorise_with_inertia(A)
        return self._count(solve), below

    def release(self):
        self.inner.release()


@contextmanager
def settings(method: str):
    """``solve_eigenproblem`` as it is ("new") or as it was ("old")."""
    names = ("TOLERANCE", "PARDISO_REFINEMENT", "LANCZOS_BLAS_THREADS")
    saved = [getattr(modes_module, name) for name in names]
    if method == "old":
        for name, value in zip(names, (0.0, None, None), strict=True):
            setattr(modes_module, name, value)
    try:
        yield
    finally:
        for name, value in zip(names, saved, strict=True):
            setattr(modes_module, name, value)


def modal_run(name: str, method: str, K, M, count: int):
    """(eigenvalues, seconds, peak MB, solves) of one modal solve with back-end ``name``."""
    counting: list[CountingSolver] = []

    def counting_factory(requested: str, size: int) -> CountingSolver:
        counting.append(CountingSolver(make_linear_solver(name, size)))
        return counting[-1]

    original = modes_module.make_linear_solver
    modes_module.make_linear_solver = counting_factory
    try:
        with settings(method):
            (values, _, _), seconds, mb = measure(lambda: solve_eigenproblem(K, M, count, True))
    finally:
        modes_module.make_linear_solver = original
    return values, seconds, mb, counting[-1].solves


def backend_rows(name: str, K, M, sigma: float, count: int, f11: float, repeats: int):
    """One factorisation of K - sigma M and the old and new modal solves with back-end
    ``name``, medians of ``repeats`` runs each; [] if the back-end is not installed."""
    n = K.shape[0]
    try:
        make_linear_solver(name, n).release()
    except ImportError as error:
        print(f"{name}: not available ({error})")
        return []
    shifted = (K - sigma * M).tocsr()
    shifted.sort_indices()
    factor_times, factor_mbs = [], []
    for _ in range(repeats):
        linear = make_linear_solver(name, n)
        _, seconds, mb = measure(lambda linear=linear: linear.factorise(shifted, True))
        linear.release()
        factor_times.append(seconds)
        factor_mbs.append(mb)
    factor_time, factor_mb = statistics.median(factor_times), statistics.median(factor_mbs)
    runs: dict[str, list] = {"old": [], "new": []}
    for _ in range(repeats):
        for method in runs:
            runs[method].append(modal_run(name, method, K, M, count))
    old_values = runs["old"][0][0]
    rows = []
    for method, results in runs.items():
        values = results[0][0]
        modal_time = statistics.median(r[1] for r in results)
        modal_mb = statistics.median(r[2] for r in results)
        rows.append(
            {
                "method": f"{method} {name}",
                "factorisation_s": factor_time,
                "factorisation_MB": factor_mb,
                "modes_s": modal_time,
                "modes_MB": modal_mb,
                "solves": results[0][3],
                "time_ratio": modal_time / factor_time,
                "memory_ratio": modal_mb / factor_mb,
                "f1_error": math.sqrt(values[0]) / (2 * math.pi) / f11 - 1,
                "vs_old": float(np.max(np.abs(values - old_values) / np.abs(old_values))),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=100_000)
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--csv", help="also write the table as CSV")
    args = parser.parse_args()
    n_elements, K, M, f11 = membrane(args.elements)
    n = K.shape[0]
    sigma = -SHIFT * float(np.mean(np.abs(K.diagonal()))) / float(np.mean(M.diagonal()))
    print(
        f"{platform.processor() or platform.machine()}, {n_elements:,} elements, "
        f"{n:,} free components, {args.count} modes, sigma = {sigma:.3g} 1/s^2, "
        f"medians of {args.repeats}"
    )
    rows = [
        row
        for name in ("superlu", "pardiso")
        for row in backend_rows(name, K, M, sigma, args.count, f11, args.repeats)
    ]
    (values, _), modal_time, modal_mb = measure(
        lambda: spla.eigsh(K, args.count, M, sigma=sigma, which="LM")
    )
    reference = rows[0] if rows else None
    rows.append(
        {
            "method": "scipy eigsh(sigma)",
            "factorisation_s": math.nan,
            "factorisation_MB": math.nan,
            "modes_s": modal_time,
            "modes_MB": modal_mb,
            "solves": math.nan,
            "time_ratio": modal_time / reference["factorisation_s"] if reference else math.nan,
            "memory_ratio": modal_mb / reference["factorisation_MB"] if reference else math.nan,
            "f1_error": math.sqrt(min(values)) / (2 * math.pi) / f11 - 1,
            "vs_old": math.nan,
        }
    )
    header = (
        f"{'method':<20} {'factor s':>9} {'factor MB':>10} {'modes s':>8} {'modes MB':>9} "
        f"{'solves':>7} {'x time':>7} {'x memory':>9} {'f1 error':>9} {'vs old':>8}"
    )
    print(header)
    for row in rows:
        print(
            f"{row['method']:<20} {row['factorisation_s']:>9.2f} {row['factorisation_MB']:>10.0f} "
            f"{row['modes_s']:>8.2f} {row['modes_MB']:>9.0f} {row['solves']:>7} "
            f"{row['time_ratio']:>7.2f} {row['memory_ratio']:>9.2f} {row['f1_error']:>9.2e} "
            f"{row['vs_old']:>8.1e}"
        )
    if args.csv:
        write_csv(args.csv, rows, list(rows[0]))


if __name__ == "__main__":
    main()
