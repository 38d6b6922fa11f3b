"""Nonlinear elimination (``[solver] elimination = true``, issue 18 item 3) against the default
Newton solver, in turns in one run, on the pure-membrane airbag of examples/airbag.toml from
the flat sheet (structured meshes n x n, and the gmsh mesh of
benchmarks/hard_cases/airbag_gmsh.toml) and on the sheared rectangle with free sides.

Prints, per case and setting: global Newton iterations, factorisations of the whole run
(the local ones included), the patches solved and their local iterations and factorisations,
the wall time, and the result (airbag: centre deflection, mm; rectangle: the top edge's
shear reaction, N). The elimination's settings (share, most, layers, iterations) are
``wrinkle.solvers.elimination.Elimination``'s defaults unless given.

    python benchmarks/elimination.py                      # airbag 16, 32, 64; gmsh; rectangle
    python benchmarks/elimination.py --airbag 32 64 96 --rounds 2
    python benchmarks/elimination.py --layers 4 --iterations 5
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from wrinkle.case import read_case
from wrinkle.solvers import settings as solver_settings
from wrinkle.solvers.elimination import Elimination

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"
GMSH_AIRBAG = Path(__file__).resolve().parent / "hard_cases" / "airbag_gmsh.toml"
RECTANGLE = Path(__file__).resolve().parent / "hard_cases" / "sheared_rectangle.toml"


def run(path: Path, overrides: dict, elimination: Elimination | None) -> dict:
    """One solve, with nonlinear elimination's settings ``elimination`` or without it."""
    overrides = overrides | {"solver": {"elimination": elimination is not None}}
    case = read_case(path, overrides)
    made = solver_settings.Elimination
    if elimination is not None:  # the settings make this one instead of the defaults
        solver_settings.Elimination = lambda: elimination  # type: ignore[assignment,misc]
    try:
        start = time.perf_counter()
        results = case.solve()
        wall = time.perf_counter() - start
    finally:
        solver_settings.Elimination = made  # type: ignore[misc]
    if "centre" in case.probes:
        node = case.probes["centre"][0]
        result = f"{1e3 * results.final.displacement.reshape(-1, 3)[node, 2]:.4f} mm"
    else:
        top = case.model.support_reactions(results.final.reactions)["top"]
        result = f"{float(top[0]):.5f} N"
    return {
        "iterations": results.final.iterations,
        "factorisations": results.factorisations,
        **{key.replace("_", " "): value for key, value in results.elimination.items()},
        "wall": wall,
        "result": result,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--airbag", type=int, nargs="*", default=[16, 32, 64])
    parser.add_argument("--gmsh", action=argparse.BooleanOptionalAction, default=True)
    parser.add_argument("--rectangle", type=int, nargs="*", default=[80])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--share", type=float, default=Elimination.share)
    parser.add_argument("--most", type=float, default=Elimination.most)
    parser.add_argument("--layers", type=int, default=Elimination.layers)
    parser.add_argument("--iterations", type=int, default=Elimination.iterations)
    args = parser.parse_args()
    chosen = Elimination(args.share, args.most, args.layers, args.iterations)
    cases: list[tuple[str, Path, dict]] = [
        (f"airbag {n} x {n}", AIRBAG, {"mesh": {"rectangle": {"nx": n, "ny": n}}})
        for n in args.airbag
    ]
    if args.gmsh:
        cases.append(("gmsh airbag", GMSH_AIRBAG, {}))
    cases += [
        (f"rectangle {n} x {n // 2}", RECTANGLE, {"mesh": {"rectangle": {"nx": n, "ny": n // 2}}})
        for n in args.rectangle
    ]
    print(
        f"elimination: share {chosen.share}, most {chosen.most}, layers {chosen.layers}, "
        f"iterations {chosen.iterations}"
    )
    header = (
        f"{'case':<20} {'setting':<11} {'iterations':>10} {'fact.':>7} {'patches':>7} "
        f"{'local its':>9} {'local fact.':>11} {'wall s':>7}  result"
    )
    print(header, flush=True)
    for name, path, overrides in cases:
        runs: dict[str, list[dict]] = {"newton": [], "elimination": []}
        for _ in range(args.rounds):
            runs["newton"].append(run(path, overrides, None))
            runs["elimination"].append(run(path, overrides, chosen))
        for setting, rows in runs.items():
            last = rows[-1]
            wall = statistics.median(r["wall"] for r in rows)
            print(
                f"{name:<20} {setting:<11} {last['iterations']:>10} {last['factorisations']:>7} "
                f"{last['patches']:>7} {last['local iterations']:>9} "
                f"{last['local factorisations']:>11} {wall:>7.1f}  {last['result']}",
                flush=True,
            )


if __name__ == "__main__":
    main()
