"""The hard cases of the load path (issue 18), with default settings, side by side with the
same cases without the look-ahead of a failed first step (``[solver] look_ahead = false``,
the path follower before it) or, with ``--compare regrow_after``, without the regrowth of cut
increments (``[solver] regrow_after = 0``), or, with ``--compare end_rounds``, with the limit
of 100 iterations set (``[solver] max_iterations = 100``: no more iterations for the end of the
path from the flat sheet, the step controller's rule 7), in turns in one run.

The cases (case files in benchmarks/hard_cases/ and examples/):
- the quarter airbag of examples/airbag.toml from the flat sheet, at full pressure and ramped
  in 2, 5, 10 and 20 steps, on its structured 32 x 32 mesh (2,048 triangles) and on the gmsh
  mesh of 2,538 triangles (airbag_gmsh.toml, made by benchmarks/gmsh_airbag.py);
- the same airbag at 10 Pa, with and without the sheet's bending stiffness (32 x 32, or the
  meshes of ``--small-pressure``);
- the sheared rectangle with free sides (sheared_rectangle.toml), 40 x 20 up;
- the pulled-node fan (pulled_node.toml), the same node pushed (the load reversed: the sheet
  round the node goes slack), and pulled then pushed in one run (two analysis steps);
- a fully slack start: the shear-stretch square of examples/shear_stretch.toml solved from a
  state shrunk 10 % about its centre (every element slack), against the flat start;
- the same airbag inflated by an amount of gas (examples/airbag_gas.toml: the gas that is at
  5 kPa in the pressure's solution) and by volume control to that volume (0.015615 m^3), in
  1 and 5 steps, on structured meshes (``--gas``) and on the gmsh mesh.

For each: elements, settings, converged or not, converged load levels, Newton iterations of
the converged levels, factorisations of the whole run (failed steps included), wall time and
the result (airbag: centre deflection; rectangle and fan: the moved edge's or node's reaction;
slack start: the largest nodal distance from the flat start's solution). Prints a table and
writes it as CSV.

    python benchmarks/hard_cases.py                 # every case, both settings (~5 min)
    python benchmarks/hard_cases.py --only airbag --no-compare
    python benchmarks/hard_cases.py --rectangle 40 80 160 --fan 8 32 64
    python benchmarks/hard_cases.py --compare regrow_after
    python benchmarks/hard_cases.py --compare end_rounds --only "10 Pa" --small-pressure 16 32
    python benchmarks/hard_cases.py --compare end_rounds --only gas volume --gas 32 64
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from table import write_csv

from wrinkle.case import Case, read_case
from wrinkle.results import Results
from wrinkle.solvers import ConvergenceError

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent / "hard_cases"
AIRBAG = ROOT / "examples" / "airbag.toml"
GMSH_AIRBAG = HERE / "airbag_gmsh.toml"
RECTANGLE = HERE / "sheared_rectangle.toml"
FAN = HERE / "pulled_node.toml"
SQUARE = ROOT / "examples" / "shear_stretch.toml"
GAS = {"kind": "gas", "amount": 1639.6, "ambient": 1.0e5, "gamma": 1.0}  # airbag_gas.toml
VOLUME = 0.015615  # m^3, the airbag's at 5 kPa
FIELDS = [
    "case",
    "elements",
    "settings",
    "converged",
    "levels",
    "iterations",
    "factorisations",
    "time_s",
    "result",
]


@dataclass
class HardCase:
    """One run: a case file with overrides, how to start it and what to report."""

    name: str
    path: Path
    overrides: dict[str, Any] = field(default_factory=dict)
    result: Callable[[Case, Results], str] = lambda case, results: ""
    start: Callable[[Case], np.ndarray] | None = None  # u0 (n_dofs,), None: the flat sheet


def centre_mm(case: Case, results: Results) -> str:
    node = case.probes["centre"][0]
    return f"centre {1e3 * results.final.displacement.reshape(-1, 3)[node, 2]:.3f} mm"


def reaction_of(label: str) -> Callable[[Case, Results], str]:
    def result(case: Case, results: Results) -> str:
        reaction = case.model.support_reactions(results.final.reactions)[label]
        return f"{label} reaction [{reaction[0]:.4g}, {reaction[1]:.4g}] N"

    return result


def shrunk(case: Case) -> np.ndarray:
    """Every node moved 10 % towards the centre (0.5, 0.5): every element slack."""
    X = case.model.mesh.nodes
    u0 = np.zeros_like(X)
    u0[:, :2] = -0.1 * (X[:, :2] - 0.5)
    return u0.ravel()


def distance_from_flat_start(case: Case, results: Results) -> str:
    flat = case.model.solve(case.settings).final.displacement
    return f"max |u - u_flat start| {np.abs(results.final.displacement - flat).max():.1e}"


def pushed_supports(pulled: list[float]) -> list[dict[str, Any]]:
    return [
        {"label": "bottom", "nodes": "y == 0", "fix": ["x", "y", "z"]},
        {"label": "pulled", "nodes": "x == 0.5 and y == 1", "displacement": pulled},
        {"label": "plane", "nodes": "z == 0", "fix": ["z"]},
    ]


def reversed_supports() -> dict[str, Any]:
    """The fan's node pulled 0.1 out, then pushed to 0.1 into the sheet, in one run: two
    supports of the node, each growing in its own analysis step."""
    supports = pushed_supports([0.0, 0.1, 0.0])
    supports[1]["label"] = "pull"
    push = {**supports[1], "label": "push", "displacement": [0.0, -0.1, 0.0]}
    return {
        "support": [*supports[:2], push, supports[2]],
        "step": [
            {"name": "pull", "supports": ["pull"], "steps": 2},
            {"name": "push", "supports": ["push"], "steps": 4},
        ],
    }


def cases(args: argparse.Namespace) -> list[HardCase]:
    runs = []
    for path, label in ((AIRBAG, "airbag 32x32"), (GMSH_AIRBAG, "airbag gmsh")):
        for steps in args.steps:
            runs.append(
                HardCase(f"{label}, steps={steps}", path, {"solver": {"steps": steps}}, centre_mm)
            )
    for n in args.small_pressure:
        for bending in (False, True):
            runs.append(
                HardCase(
                    f"airbag {n}x{n}, 10 Pa{', bending' if bending else ''}",
                    AIRBAG,
                    {
                        "mesh": {"rectangle": {"nx": n, "ny": n}},
                        "load": [{"kind": "pressure", "value": 10.0}],
                        "material": {"bending": bending},
                    },
                    centre_mm,
                )
            )
    for n in args.rectangle:
        mesh = {"mesh": {"rectangle": {"nx": n, "ny": n // 2}}}
        runs.append(
            HardCase(f"sheared rectangle {n}x{n // 2}", RECTANGLE, mesh, reaction_of("top"))
        )
    for n in args.fan:
        mesh = {"rectangle": {"nx": n, "ny": n}}
        runs.append(HardCase(f"pulled node {n}x{n}", FAN, {"mesh": mesh}, reaction_of("pulled")))
        runs.append(
            HardCase(
                f"pushed node {n}x{n}",
                FAN,
                {"mesh": mesh, "support": pushed_supports([0.0, -0.1, 0.0])},
                reaction_of("pulled"),
            )
        )
        runs.append(
            HardCase(
                f"pulled, then pushed {n}x{n}",
                FAN,
                {"mesh": mesh, **reversed_supports()},
                reaction_of("push"),
            )
        )
    for n in args.slack:
        runs.append(
            HardCase(
                f"slack start {n}x{n}",
                SQUARE,
                {
                    "mesh": {"rectangle": {"nx": n, "ny": n}},
                    "solver": {"steps": 1, "tolerance": 1e-10},
                },
                distance_from_flat_start,
                shrunk,
            )
        )
    meshes = [({"mesh": {"rectangle": {"nx": n, "ny": n}}}, AIRBAG, f"{n}x{n}") for n in args.gas]
    for mesh, path, label in [*meshes, ({}, GMSH_AIRBAG, "gmsh")]:
        for steps in (1, 5):
            runs.append(
                HardCase(
                    f"airbag {label}, gas, steps={steps}",
                    path,
                    {**mesh, "load": [GAS], "solver": {"steps": steps}},
                    centre_mm,
                )
            )
            runs.append(
                HardCase(
                    f"airbag {label}, volume, steps={steps}",
                    path,
                    {**mesh, "solver": {"steps": steps, "control": "volume", "volume": VOLUME}},
                    centre_mm,
                )
            )
    if args.only:
        runs = [run for run in runs if any(word in run.name for word in args.only)]
    return runs


# what each case is run with besides the defaults (--compare): a label and [solver] keys
COMPARED = {
    "look_ahead": ("look_ahead = false", {"look_ahead": False}),
    "regrow_after": ("regrow_after = 0", {"regrow_after": 0}),
    # a limit set in the case holds everywhere: the controller before its rule 7
    "end_rounds": ("max_iterations = 100", {"max_iterations": 100}),
}


def run(hard: HardCase, label: str = "default", solver: dict | None = None) -> dict[str, Any]:
    overrides = {
        key: dict(value) if isinstance(value, dict) else value
        for key, value in hard.overrides.items()
    }
    overrides["solver"] = {**overrides.get("solver", {}), **(solver or {})}
    case = read_case(hard.path, overrides=overrides)
    u0 = hard.start(case) if hard.start is not None else None
    start = time.perf_counter()
    try:
        if case.steps:  # analysis steps ([[step]]), each from the end of the last
            results = case.solve()
        else:
            results = case.model.solve(case.settings, u0=u0)
        converged, result = True, ""
    except ConvergenceError as error:
        results, converged = error.results, False
        result = str(error).split(": ", 1)[-1][:70]
    seconds = time.perf_counter() - start
    if converged:
        result = hard.result(case, results)
    return {
        "case": hard.name,
        "elements": case.model.mesh.n_elements,
        "settings": label,
        "converged": "yes" if converged else "NO",
        "levels": len(results.steps),
        "iterations": sum(step.iterations for step in results.steps),
        "factorisations": results.factorisations,
        "time_s": f"{seconds:.1f}",
        "result": result,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, nargs="+", default=[1, 2, 5, 10, 20])
    parser.add_argument("--small-pressure", type=int, nargs="+", default=[32], metavar="N")
    parser.add_argument("--rectangle", type=int, nargs="+", default=[40, 80])
    parser.add_argument("--fan", type=int, nargs="+", default=[8, 32])
    parser.add_argument("--slack", type=int, nargs="+", default=[8, 32])
    parser.add_argument("--gas", type=int, nargs="+", default=[32], metavar="N")
    parser.add_argument("--only", nargs="+", help="cases whose name contains one of these")
    parser.add_argument("--no-compare", action="store_true", help="default settings only")
    parser.add_argument(
        "--compare",
        choices=list(COMPARED),
        default="look_ahead",
        help="the setting each case is also run without, in turn with the defaults",
    )
    parser.add_argument("--csv", default="hard_cases.csv")
    args = parser.parse_args()
    settings = [("default", {})] + ([] if args.no_compare else [COMPARED[args.compare]])
    rows = []
    for hard in cases(args):
        for label, solver in settings:
            row = run(hard, label, solver)
            rows.append(row)
            print(" | ".join(str(row[name]) for name in FIELDS), flush=True)
    print()
    print("| " + " | ".join(FIELDS) + " |")
    print("|" + " --- |" * len(FIELDS))
    for row in rows:
        print("| " + " | ".join(str(row[name]) for name in FIELDS) + " |")
    write_csv(args.csv, rows, FIELDS)


if __name__ == "__main__":
    main()
