"""Issue 18's cases solved by the solver of the day the issue was filed and by the present
one, in turns in one run, each solve in its own process with PYTHONPATH set to its tree.

The solver of that day is commit 7aa4a5b (1 December 2026, the last commit before the work
of issue 18): check it out beside this one, ``git worktree add ../filed 7aa4a5b``, and pass
its ``src``. Both trees read the same case files, those of this checkout. Each case is solved
with the tree's default settings; a case may also be given settings the old tree does not
have (the sheet's bending stiffness, mesh sequencing), as its own row, run by the present
tree alone. A run that does not finish within ``--time-limit`` seconds is stopped and
reported so.

Prints, for each case and tree: elements, converged or not (or why it could not run), the
load levels, the Newton iterations (on the finest mesh where the solve is nested), the
factorisations of the whole run (the old tree does not count them), wall time, the peak
resident set and the result (airbag: centre deflection; rectangle and fan: the moved edge's
or node's reaction; slack start: the largest distance from the flat start's solution). Then a
Markdown table. Writes it as CSV.

    git worktree add ../filed 7aa4a5b
    python benchmarks/side_by_side.py --filed ../filed/src              # the suite's cases
    python benchmarks/side_by_side.py --filed ../filed/src --large      # and 10^5, 10^6
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from hard_cases import AIRBAG, FAN, GMSH_AIRBAG, RECTANGLE, ROOT, SQUARE, pushed_supports, shrunk
from table import write_csv

HERE = Path(__file__).resolve().parent
BENDING_NESTED = {"material": {"bending": True}, "solver": {"nested": True}}
FIELDS = [
    "case",
    "tree",
    "elements",
    "converged",
    "levels",
    "iterations",
    "factorisations",
    "time_s",
    "peak_mb",
    "result",
]


def square_mesh(n: int, refine: int = 0) -> dict[str, Any]:
    """[mesh] overrides: n x n squares (2 n^2 triangles), refined ``refine`` times."""
    mesh: dict[str, Any] = {"rectangle": {"nx": n, "ny": n}}
    return {"mesh": {**mesh, "refine": refine} if refine else mesh}


def cases(large: bool, scratch: Path) -> list[dict[str, Any]]:
    """Each case: name, case file, overrides, what to report, the start, and ``new_only``
    where its settings did not exist when the issue was filed."""
    airbag = {"path": str(AIRBAG), "result": "centre"}
    runs: list[dict[str, Any]] = [
        {"name": "airbag 32x32, 1 step", **airbag, "overrides": {}},
        {"name": "airbag 32x32, 5 steps", **airbag, "overrides": {"solver": {"steps": 5}}},
        {
            "name": "airbag gmsh 2,538, 5 steps",
            "path": str(GMSH_AIRBAG),
            "result": "centre",
            "overrides": {"solver": {"steps": 5}},
        },
        {
            "name": "airbag 32x32, 10 Pa",
            **airbag,
            "overrides": {"load": [{"kind": "pressure", "value": 10.0}]},
        },
        {
            "name": "sheared rectangle 320x160",
            "path": str(RECTANGLE),
            "result": "reaction top",
            "overrides": {"mesh": {"rectangle": {"nx": 320, "ny": 160}}},
        },
        {
            "name": "pushed node 32x32",
            "path": str(FAN),
            "result": "reaction pulled",
            "overrides": {**square_mesh(32), "support": pushed_supports([0.0, -0.1, 0.0])},
        },
        {
            "name": "slack start 32x32",
            "path": str(SQUARE),
            "result": "distance",
            "start": "shrunk",
            "overrides": {**square_mesh(32), "solver": {"steps": 1, "tolerance": 1e-10}},
        },
    ]
    if large:
        from gmsh_airbag import write_airbag_mesh  # needs the mesh extra

        fine = scratch / "airbag-gmsh-224.msh"
        coarse = scratch / "airbag-gmsh-56.msh"
        write_airbag_mesh(2 * 224 * 224, fine)
        write_airbag_mesh(2 * 56 * 56, coarse)
        runs += [
            {"name": "airbag 224x224", **airbag, "overrides": square_mesh(224)},
            {
                "name": "airbag 56x56 refined twice, bending, nested",
                **airbag,
                "overrides": {**square_mesh(56, 2), **BENDING_NESTED},
                "new_only": True,
            },
            {
                "name": "airbag gmsh 10^5",
                "path": str(GMSH_AIRBAG),
                "result": "centre",
                "overrides": {"mesh": {"file": str(fine)}},
            },
            {
                "name": "airbag gmsh 10^5/16 refined twice, bending, nested",
                "path": str(GMSH_AIRBAG),
                "result": "centre",
                "overrides": {"mesh": {"file": str(coarse), "refine": 2}, **BENDING_NESTED},
                "new_only": True,
            },
            {
                "name": "airbag 44x44 refined 4 times, bending, nested",
                **airbag,
                "overrides": {**square_mesh(44, 4), **BENDING_NESTED},
                "new_only": True,
            },
        ]
    return runs


def solve(spec: dict[str, Any]) -> dict[str, Any]:
    """Solve one case in this process with the tree on sys.path; its row (the elements are
    printed as a row of their own first, for a run that is stopped). Uses only what both
    trees have: read_case with overrides, Case.solve, Model.solve(u0=), Results.steps."""
    import numpy as np

    import wrinkle
    from wrinkle.case import read_case
    from wrinkle.solvers import ConvergenceError

    print("ROW " + json.dumps({"package": str(Path(wrinkle.__file__).resolve())}), flush=True)
    try:
        case = read_case(spec["path"], overrides=spec["overrides"])
    except ValueError as error:  # a key the tree does not know
        return {"converged": "cannot run", "result": str(error)[:90]}
    model = case.model
    print("ROW " + json.dumps({"elements": model.mesh.n_elements}), flush=True)
    u0 = shrunk(case) if spec.get("start") == "shrunk" else None  # every element slack
    start, reason = time.perf_counter(), ""
    try:
        results = case.solve() if u0 is None else model.solve(case.settings, u0=u0)
        converged = "yes"
    except ConvergenceError as error:
        results, converged = error.results, "NO"
        reason = str(error).split(": ", 1)[-1][:90]
    except Exception as error:  # anything else ends the run: say what
        return {"converged": "error", "result": f"{type(error).__name__}: {error}"[:90]}
    seconds = time.perf_counter() - start
    row = {
        "elements": model.mesh.n_elements,
        "converged": converged,
        "levels": len(results.steps),
        "iterations": sum(step.iterations for step in results.steps),
        "factorisations": getattr(results, "factorisations", ""),
        "time_s": f"{seconds:.1f}",
        "peak_mb": f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f}",
        "result": reason,
    }
    if converged == "yes":
        u = results.final.displacement
        kind = spec["result"]
        if kind == "centre":
            centre = case.probes["centre"]
            row["result"] = f"centre {1e3 * float(u.reshape(-1, 3)[centre, 2].mean()):.3f} mm"
        elif kind.startswith("reaction"):
            label = kind.split()[1]
            force = model.support_reactions(results.final.reactions)[label]
            row["result"] = f"{label} [{force[0]:.6g}, {force[1]:.6g}] N"
        else:
            flat = model.solve(case.settings).final.displacement
            row["result"] = f"max |u - u_flat start| {np.abs(u - flat).max():.1e}"
    return row


def peak_mb(pid: int) -> str:
    """The peak resident set of a running process, MiB (Linux /proc), or "" if unknown."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return f"{int(line.split()[1]) / 1024:.0f}"
    except OSError:
        pass
    return ""


def run(spec: dict[str, Any], tree: str, time_limit: float) -> dict[str, Any]:
    """``solve`` in a process of its own on ``tree``; stopped after time_limit seconds."""
    env = {**os.environ, "PYTHONPATH": tree}
    child = subprocess.Popen(
        [sys.executable, __file__, "--child", json.dumps(spec)],
        env=env,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        out, _ = child.communicate(timeout=time_limit)
        row = {"converged": "failed", "result": "the process ended without a row"}
    except subprocess.TimeoutExpired:
        peak = peak_mb(child.pid)
        child.kill()
        out, _ = child.communicate()
        row = {"converged": "stopped", "time_s": f"> {time_limit:.0f}", "peak_mb": peak}
        row["result"] = f"not finished in {time_limit:.0f} s"
    for line in out.splitlines():  # the package, the elements once read, the whole row
        if line.startswith("ROW "):
            row.update(json.loads(line[4:]))
    package = Path(row.pop("package", ""))
    if Path(tree) not in package.parents:  # the installed package, not the tree's
        row = {"converged": "cannot run", "result": f"{tree} was not imported ({package})"}
    return {"case": spec["name"], "tree": tree, **row}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--filed", help="the src folder of the tree of 7aa4a5b")
    parser.add_argument("--present", default=str(ROOT / "src"), help="this tree's src")
    parser.add_argument("--large", action="store_true", help="the 10^5 and 10^6 meshes too")
    parser.add_argument("--only", nargs="+", help="cases whose name contains one of these")
    parser.add_argument("--time-limit", type=float, default=600.0, help="seconds per solve")
    parser.add_argument("--csv", default="side_by_side.csv")
    args = parser.parse_args()
    if args.child:
        print("ROW " + json.dumps(solve(json.loads(args.child))), flush=True)
        return
    if not args.filed:
        parser.error("--filed: the src folder of a checkout of 7aa4a5b is needed")
    args.filed, args.present = (str(Path(tree).resolve()) for tree in (args.filed, args.present))
    for tree in (args.filed, args.present):
        if not (Path(tree) / "wrinkle" / "__init__.py").is_file():
            parser.error(f"{tree}: not the src folder of a wrinkle tree")
    rows = []
    with tempfile.TemporaryDirectory(prefix="side-by-side-") as scratch:
        for spec in cases(args.large, Path(scratch)):
            if args.only and not any(word in spec["name"] for word in args.only):
                continue
            trees = [args.present] if spec.get("new_only") else [args.filed, args.present]
            for tree in trees:
                row = run(spec, tree, args.time_limit)
                row["tree"] = "present" if tree == args.present else "filed"
                rows.append(row)
                print(" | ".join(str(row.get(name, "")) for name in FIELDS), flush=True)
    print()
    print("| " + " | ".join(FIELDS) + " |")
    print("|" + " --- |" * len(FIELDS))
    for row in rows:
        cells = (str(row.get(name, "")).replace("|", "\\|") for name in FIELDS)
        print("| " + " | ".join(cells) + " |")
    write_csv(args.csv, rows, FIELDS)


if __name__ == "__main__":
    main()
