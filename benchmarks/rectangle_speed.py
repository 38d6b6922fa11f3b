"""The sheared rectangle (benchmarks/hard_cases/sheared_rectangle.toml) with the solver's cost
settings of before and after the speed work of issue 18's rectangle, in turns in one run, on
meshes nx x nx/2.

"old" (before exp18): PARDISO's LDL^T for every symmetric matrix, two steps of iterative
refinement per solve, shortened (backtracked) steps evaluated without the stiffness first,
the whole matrix factorised.
"whole" (exp18, 3 December 2026): a Cholesky factorisation tried first
(``Pardiso.cholesky``), no refinement unless pivots were perturbed (``Pardiso.refinement =
0``), shortened steps evaluated with the stiffness at once
(``RegularisedNewton.backtrack_stiffness``), the whole matrix factorised.
"block" (4 December 2026): as "whole", with only the free block factorised
(``RegularisedSolver.free_block``, ``wrinkle.solvers.linear.FreeBlock``).
"blas": as "block", with OpenBLAS on one thread during the solve.
"new" (the defaults since the parallel kernels, 4 December 2026): as "block", with OpenBLAS
on one thread during the solve (``RegularisedSolver.blas_threads``, ``wrinkle.threads``) and
the St Venant-Kirchhoff wrinkling response in one parallel Numba kernel
(``Wrinkling.compiled_linear_law``, ``wrinkle.compiled.svk_wrinkling``; the element stiffness
kernel runs in parallel in every setting).

Prints, for each mesh and setting, the median over the rounds of the wall time and of the
seconds per part (element evaluation, assembly, linear solves, rest), the iterations and
factorisations of each round, and the top edge's reaction; with --reference, the reaction
of a solve to tolerance 1e-8 on the same mesh (new settings).

    python benchmarks/rectangle_speed.py                       # 80, 160, 320; 1 round
    python benchmarks/rectangle_speed.py --sizes 320 --rounds 3 --reference
    python benchmarks/rectangle_speed.py --settings old whole block new
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from wrinkle.case import read_case
from wrinkle.solvers import base, linear, newton
from wrinkle.wrinkling import Wrinkling

CASE = Path(__file__).parent / "hard_cases" / "sheared_rectangle.toml"
PARTS = ("element evaluation", "assembly", "linear solves", "rest")
_BEFORE = {"blas_threads": None, "compiled_law": False}
_WHOLE = {"cholesky": True, "refinement": 0, "backtrack_stiffness": True, "free": False}
_BLOCK = _WHOLE | {"free": True}
SETTINGS = {
    "old": {"cholesky": False, "refinement": None, "backtrack_stiffness": False, "free": False}
    | _BEFORE,
    "whole": _WHOLE | _BEFORE,
    "block": _BLOCK | _BEFORE,
    "blas": _BLOCK | {"blas_threads": 1, "compiled_law": False},
    "new": _BLOCK | {"blas_threads": 1, "compiled_law": True},
}


def apply(setting: dict) -> None:
    linear.Pardiso.cholesky = setting["cholesky"]
    linear.Pardiso.refinement = setting["refinement"]
    newton.RegularisedNewton.backtrack_stiffness = setting["backtrack_stiffness"]
    base.RegularisedSolver.free_block = setting["free"]
    base.RegularisedSolver.blas_threads = setting["blas_threads"]
    Wrinkling.compiled_linear_law = setting["compiled_law"]


def solve(nx: int, setting: dict, tolerance: float | None = None) -> dict:
    apply(setting)
    overrides: dict = {"mesh": {"rectangle": {"nx": nx, "ny": nx // 2}}}
    if tolerance is not None:  # the reference: more iterations than the default 100
        overrides["solver"] = {"tolerance": tolerance, "max_iterations": 400}
    case = read_case(CASE, overrides)
    start = time.perf_counter()
    results = case.solve()
    wall = time.perf_counter() - start
    top = case.model.support_reactions(results.final.reactions)["top"]
    return {
        "iterations": results.final.iterations,
        "factorisations": results.factorisations,
        "wall": wall,
        **{part: results.timings[part] for part in PARTS},
        "top": (float(top[0]), float(top[1])),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[80, 160, 320])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--reference", action="store_true", help="also solve to 1e-8")
    parser.add_argument(
        "--settings", nargs="+", default=["block", "new"], choices=list(SETTINGS), help="in turns"
    )
    args = parser.parse_args()
    header = (
        f"{'mesh':>9} {'setting':>7} {'iterations':>12} {'factorisations':>15} {'wall s':>7} "
        + " ".join(f"{p[:8]:>8}" for p in PARTS)
        + "  top reaction (N)"
    )
    rows = []
    for nx in args.sizes:
        runs: dict[str, list[dict]] = {name: [] for name in args.settings}
        for _ in range(args.rounds):
            for name in args.settings:
                runs[name].append(solve(nx, SETTINGS[name]))
        for name, results in runs.items():
            median = {k: statistics.median(r[k] for r in results) for k in ("wall", *PARTS)}
            top = results[-1]["top"]
            rows.append(
                f"{nx}x{nx // 2:<5} {name:>7} "
                f"{'/'.join(str(r['iterations']) for r in results):>12} "
                f"{'/'.join(str(r['factorisations']) for r in results):>15} "
                f"{median['wall']:7.1f} "
                + " ".join(f"{median[p]:8.1f}" for p in PARTS)
                + f"  ({top[0]:.4f}, {top[1]:.4f})"
            )
        first, last = args.settings[0], args.settings[-1]
        ratio = statistics.median(r["wall"] for r in runs[last]) / statistics.median(
            r["wall"] for r in runs[first]
        )
        rows.append(f"{nx}x{nx // 2:<5} {last}/{first} wall {ratio:.2f}")
        print(*rows[-len(args.settings) - 1 :], sep="\n", flush=True)
        if args.reference:
            ref = solve(nx, SETTINGS["new"], tolerance=1e-8)
            rows.append(
                f"{nx}x{nx // 2:<5} tolerance 1e-8: {ref['iterations']} iterations, "
                f"top ({ref['top'][0]:.4f}, {ref['top'][1]:.4f})"
            )
        print(header, *rows, sep="\n", flush=True)
        print()


if __name__ == "__main__":
    main()
