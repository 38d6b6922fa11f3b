"""The accuracy stop (``[solver] convergence = "accuracy"``, wrinkle.solvers.stopping) side by side
with the residual test alone, on the nested cases of the hard-case suite, in turns in one run.

The cases, each solved level by level from a coarser mesh (``[solver] nested``, ``[mesh]
refine``) with the case's own tolerance:
- the quarter airbag of examples/airbag.toml (tolerance 1e-8) with the sheet's bending
  stiffness, from 32 squares a side refined once or twice and from 56 refined twice;
- the same airbag as a pure membrane, 32 refined once (the fold creep);
- the airbag on a gmsh mesh of about 2,048 triangles refined twice, with bending
  (benchmarks/hard_cases/airbag_gmsh.toml; needs the mesh extra: gmsh);
- the sheared rectangle with free sides (benchmarks/hard_cases/sheared_rectangle.toml), 40 x 20
  refined twice.

For each: elements, the stop, the test that ended the finest level, its iterations, the
factorisations of the whole run (every level), wall time, the result (airbag: centre
deflection; rectangle: the top edge's reaction) and its difference from the residual test's.
Prints a table and writes it as CSV.

    python benchmarks/accuracy_stop.py                # every case (~5 min)
    python benchmarks/accuracy_stop.py --only airbag_bending
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from table import write_csv

from wrinkle.case import Case, read_case
from wrinkle.results import Results

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent / "hard_cases"
SIDE = 0.42426406871192845  # the quarter airbag's side (m)
FIELDS = [
    "case",
    "elements",
    "convergence",
    "stopped_by",
    "iterations",
    "factorisations",
    "time_s",
    "result",
    "difference",
]


def centre_mm(case: Case, results: Results) -> float:
    """The airbag's centre deflection (mm)."""
    u = results.final.displacement.reshape(-1, 3)
    return float(u[case.probes["centre"], 2].mean() * 1e3)


def top_force(case: Case, results: Results) -> float:
    """The x reaction of the sheared rectangle's top edge (N)."""
    return float(case.model.support_reactions(results.final.reactions)["top"][0])


def airbag(n: int, refine: int, bending: bool) -> dict:
    return {
        "mesh": {"rectangle": {"width": SIDE, "height": SIDE, "nx": n, "ny": n}, "refine": refine},
        "material": {"bending": bending},
    }


def cases(scratch: Path) -> dict[str, tuple[Path, Callable[[], dict], Callable]]:
    """name: (case file, overrides (made when run), result)."""

    def gmsh_airbag() -> dict:
        from gmsh_airbag import write_airbag_mesh

        path = scratch / "airbag-32.msh"
        write_airbag_mesh(2 * 32 * 32, path)
        return {"mesh": {"file": str(path), "refine": 2}, "material": {"bending": True}}

    airbag_file = ROOT / "examples" / "airbag.toml"
    return {
        "airbag_bending 32 x 1": (airbag_file, lambda: airbag(32, 1, True), centre_mm),
        "airbag_bending 32 x 2": (airbag_file, lambda: airbag(32, 2, True), centre_mm),
        "airbag_bending 56 x 2": (airbag_file, lambda: airbag(56, 2, True), centre_mm),
        "airbag_membrane 32 x 1": (airbag_file, lambda: airbag(32, 1, False), centre_mm),
        "airbag_gmsh_bending 32 x 2": (HERE / "airbag_gmsh.toml", gmsh_airbag, centre_mm),
        "sheared_rectangle 40 x 2": (
            HERE / "sheared_rectangle.toml",
            lambda: {
                "mesh": {
                    "rectangle": {"width": 1.0, "height": 0.5, "nx": 40, "ny": 20},
                    "refine": 2,
                }
            },
            top_force,
        ),
    }


def run(file: Path, overrides: dict, stop: str, result: Callable) -> dict:
    solver = {"nested": True, "convergence": stop, "max_iterations": 400}
    case = read_case(file, overrides={**overrides, "solver": solver})
    start = time.perf_counter()
    results = case.solve()
    elapsed = time.perf_counter() - start
    final = results.final
    return {
        "elements": case.model.mesh.n_elements,
        "convergence": stop,
        "stopped_by": final.stopped_by,
        "iterations": final.iterations,
        "factorisations": results.factorisations,
        "time_s": round(elapsed, 1),
        "result": result(case, results),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", help="cases whose name starts with one of these")
    parser.add_argument("--csv", default="accuracy_stop.csv")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for name, (file, overrides, result) in cases(Path(scratch)).items():
            if args.only and not any(name.startswith(prefix) for prefix in args.only):
                continue
            made = overrides()
            reference = None
            for stop in ("residual", "accuracy"):
                row = {"case": name, **run(file, made, stop, result)}
                if reference is None:
                    reference = row["result"]
                row["difference"] = f"{row['result'] - reference:.2e}"
                row["result"] = f"{row['result']:.5f}"
                rows.append(row)
                print(" | ".join(str(row[f]) for f in FIELDS), flush=True)
    write_csv(args.csv, rows, FIELDS)
    widths = [max(len(f), *(len(str(r[f])) for r in rows)) for f in FIELDS]
    print()
    print(" | ".join(f.ljust(w) for f, w in zip(FIELDS, widths)))
    for r in rows:
        print(" | ".join(str(r[f]).ljust(w) for f, w in zip(FIELDS, widths)))


if __name__ == "__main__":
    main()
