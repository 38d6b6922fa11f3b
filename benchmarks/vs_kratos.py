"""wrinkle against Kratos Multiphysics on the inflated square airbag (examples/airbag.toml).

For each mesh of n x n squares (2 n^2 triangles) both codes solve the same problem on the same
mesh: wrinkle through ``benchmarks/scale.py --one airbag n`` and Kratos 10.4
(MembraneElement3D3N, WrinklingLinear2DLaw, follower SurfaceLoadCondition3D3N) through
``benchmarks/kratos_airbag.py``, run with the Python of a separate virtual environment
(--kratos-venv; created, and the Kratos wheels pip-installed there, when missing: Kratos is
never a dependency of wrinkle). The mesh, held dofs and centre node come from wrinkle's own
model of the case and go to Kratos in an .npz, so the triangles and their orientation are
identical.

Each run is one whole process timed by the wall clock around the subprocess (interpreter
start, imports, set-up and solve; the median of --repeats runs), with OMP_NUM_THREADS and the
BLAS thread counts set to --threads in both (default 1: on a shared machine Kratos' OpenMP
loops slow down by orders of magnitude when another job holds the cores).

What Kratos needs to converge (kratos_airbag.py has the details and the trials): Newton from
the flat sheet meets a singular matrix, so the pressure is first ramped up with an artificial
prestress and seam springs, then these are removed (weak springs stay at the seam) and the
full pressure is solved to wrinkle's tolerance. Kratos' wrinkling tangent leaves out the change
of the wrinkle direction, so that last Newton iteration converges only linearly: most of
Kratos' iterations are there. The default law is the wrinkling one; with --law auto a wrinkling
run that does not converge is repeated with the plain LinearElasticPlaneStress2DLaw (no
wrinkling), and the table says which law gave the row.

Deflections differ for two reasons. The seam springs Kratos keeps bias its answer (the row
gives the largest spring force left): on n = 16 Kratos' spring-free solution (kratos_airbag.py
--release-steps 3) matches wrinkle's 216.952 mm to 1e-4 mm, with the springs it is 216.49 mm.
And the n = 32 mesh has several stable equilibria (positive definite tangent on the free
dofs, symmetric part): 216.28, 216.60 and 217.23 mm, which wrinkle reaches from the flat sheet
depending on its Newton settings (the default now gives 216.28 mm), and 217.23 mm, of the
lowest potential energy found, also from Kratos' final shape; Kratos' path leads near it.

Convergence: both stop when |r| <= 1e-8 max(|f_ext|, |reactions|) on the free dofs (wrinkle
each iteration; Kratos through ResidualCriteria's absolute norm with that scale taken at the
start of its final step). The ratio is wrinkle's wall time over Kratos'.

    python benchmarks/vs_kratos.py --sizes 16 32 --csv vs_kratos.csv
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
from table import write_csv

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "examples" / "airbag.toml"
KRATOS_SCRIPT = Path(__file__).resolve().parent / "kratos_airbag.py"
KRATOS_PACKAGES = [
    "KratosMultiphysics==10.4.*",
    "KratosStructuralMechanicsApplication==10.4.*",
    "KratosConstitutiveLawsApplication==10.4.*",
    "numpy",
]
KRATOS_IMPORTS = (
    "import KratosMultiphysics, KratosMultiphysics.StructuralMechanicsApplication, "
    "KratosMultiphysics.ConstitutiveLawsApplication, "
    "KratosMultiphysics.LinearSolversApplication, numpy"
)
FIELDS = [
    "n",
    "elements",
    "unknowns",
    "wrinkle_iterations",
    "wrinkle_s",
    "wrinkle_mm",
    "wrinkle_converged",
    "kratos_law",
    "kratos_iterations",
    "kratos_s",
    "kratos_mm",
    "kratos_converged",
    "ratio",
    "kratos_minus_wrinkle_mm",
    "wrinkle_solve_s",
    "kratos_solve_s",
    "wrinkle_ms_per_iteration",
    "kratos_ms_per_iteration",
    "kratos_ramp_iterations",
    "kratos_release_iterations",
    "kratos_spring_force_n",
    "kratos_linear_solver",
    "kratos_error",
    "kratos_path",
    "threads",
]


def kratos_python(venv: Path) -> Path:
    """The Python of the Kratos environment ``venv``, made and filled first if needed."""
    python = venv / "bin" / "python"
    if not python.exists():
        print(f"creating the Kratos environment {venv}", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    found = subprocess.run([str(python), "-c", KRATOS_IMPORTS], capture_output=True, check=False)
    if found.returncode:
        print(f"installing {' '.join(KRATOS_PACKAGES)} into {venv}", flush=True)
        subprocess.run(
            [str(python), "-m", "pip", "install", "--quiet", *KRATOS_PACKAGES], check=True
        )
    return python


def write_problem(n: int, directory: Path) -> Path:
    """The airbag on n x n squares as wrinkle builds it, written for kratos_airbag.py: nodes
    (n_nodes, 3) m, triangles (n_el, 3) in wrinkle's node order, held (n_nodes, 3) bool,
    centre node, E (Pa), nu, thickness (m), pressure (Pa), the case's solver tolerance."""
    from wrinkle.case import read_case

    case = tomllib.loads(CASE.read_text())
    material, (load,) = case["material"], case["load"]
    if material["model"] != "svk" or load["kind"] != "pressure":
        raise ValueError(f"{CASE} is no longer an St Venant-Kirchhoff sheet under one pressure")
    wrinkle_case = read_case(CASE, overrides={"mesh": {"rectangle": {"nx": n, "ny": n}}})
    model = wrinkle_case.model
    path = directory / f"airbag_{n}.npz"
    np.savez(
        path,
        nodes=model.mesh.nodes,
        triangles=model.mesh.triangles,
        held=model.constrained.reshape(-1, 3),
        centre=wrinkle_case.probes["centre"],
        young_modulus=material["E"],
        poisson_ratio=material["nu"],
        thickness=material["thickness"],
        pressure=load["value"],
        tolerance=case["solver"]["tolerance"],
    )
    return path


def timed_runs(command: list[str], repeats: int, time_limit: float, env: dict) -> dict:
    """Run ``command`` ``repeats`` times: the JSON row its last run printed last, plus
    "wall_s" (median wall time, s), or {"error": ...} when a run fails or passes the limit."""
    walls, row = [], {}
    for _ in range(repeats):
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command, capture_output=True, text=True, timeout=time_limit, env=env, check=False
            )
        except subprocess.TimeoutExpired:
            return {"error": f"over the time limit of {time_limit:.0f} s", "wall_s": time_limit}
        walls.append(time.perf_counter() - start)
        lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
        if done.returncode != 0 or not lines:
            return {
                "error": (done.stderr or done.stdout).strip()[-500:] or "no output",
                "wall_s": walls[-1],
            }
        row = json.loads(lines[-1])
    row["wall_s"] = statistics.median(walls)
    return row


def compare(n: int, problem: Path, python: Path, args, env: dict) -> dict:
    """One row of the table: wrinkle and Kratos on the n x n airbag."""
    wrinkle = timed_runs(
        [sys.executable, str(ROOT / "benchmarks" / "scale.py"), "--one", "airbag", str(n)],
        args.repeats,
        args.time_limit,
        env,
    )
    kratos_command = [str(python), str(KRATOS_SCRIPT), str(problem), *args.kratos_options]
    laws = ["wrinkling", "linear"] if args.law == "auto" else [args.law]
    for law in laws:
        kratos = timed_runs(kratos_command + ["--law", law], args.repeats, args.time_limit, env)
        kratos.setdefault("law", law)
        if kratos.get("converged"):
            break
    converged = bool(kratos.get("converged"))
    row = {
        "n": n,
        "elements": 2 * n * n,
        "unknowns": kratos.get("unknowns"),
        "threads": args.threads,
        "kratos_law": kratos["law"],
        "kratos_converged": converged,
        "kratos_s": kratos["wall_s"],
        "kratos_error": kratos.get("error", ""),
        "kratos_linear_solver": kratos.get("linear_solver", ""),
    }
    if "error" in wrinkle:
        print(f"n = {n}: wrinkle failed: {wrinkle['error']}", flush=True)
    else:
        row.update(
            {
                "unknowns": wrinkle["unknowns"],
                "wrinkle_iterations": wrinkle["iterations"],
                "wrinkle_s": wrinkle["wall_s"],
                "wrinkle_mm": wrinkle["result"],
                "wrinkle_solve_s": wrinkle["total_s"],
                "wrinkle_ms_per_iteration": 1e3 * wrinkle["total_s"] / wrinkle["iterations"],
                "wrinkle_converged": wrinkle.get("converged", True),
            }
        )
        if not row["wrinkle_converged"]:
            print(f"n = {n}: wrinkle did not converge", flush=True)
    if "iterations" in kratos:
        row.update(
            {
                "kratos_iterations": kratos["iterations"],
                "kratos_mm": kratos["deflection_mm"],
                "kratos_solve_s": kratos["solve_s"],
                "kratos_ramp_iterations": kratos["ramp_iterations"],
                "kratos_release_iterations": kratos["release_iterations"],
                "kratos_spring_force_n": kratos["spring_force_n"],
                "kratos_ms_per_iteration": 1e3 * kratos["solve_s"] / max(kratos["iterations"], 1),
            }
        )
    if "ramp_steps" in kratos:
        row["kratos_path"] = (
            f"ramp: {kratos['ramp_steps']} steps, prestress {kratos['prestress_pa']:g} Pa, "
            f"seam springs {kratos['seam_spring_n_per_m']:g} N/m, {kratos.get('ramp_iterations')}"
            f" iterations; release: {kratos['release_steps']} step(s), seam springs "
            f"{kratos['release_spring_n_per_m']:g} N/m, {kratos.get('release_iterations')} "
            f"iterations, largest spring force left {kratos.get('spring_force_n', 0.0):.2g} N; "
            f"{kratos['linear_solver']}"
        )
    if converged and row.get("wrinkle_converged"):
        row["ratio"] = row["wrinkle_s"] / row["kratos_s"]
        row["kratos_minus_wrinkle_mm"] = row["kratos_mm"] - row["wrinkle_mm"]
    return row


def cell(row: dict, key: str, form: str, width: int) -> str:
    """``row[key]`` formatted, or blank when missing."""
    value = row.get(key)
    return (format(value, form) if value is not None else "").rjust(width)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=[16, 32],
        help="squares per side n (2 n^2 triangles); n = 32: 2,048 elements",
    )
    parser.add_argument("--csv", default="vs_kratos.csv")
    parser.add_argument(
        "--kratos-venv", type=Path, default=Path.home() / ".cache" / "wrinkle" / "kratos-venv"
    )
    parser.add_argument("--repeats", type=int, default=1, help="runs per code and mesh")
    parser.add_argument("--time-limit", type=float, default=1800.0, help="per run, s")
    parser.add_argument("--threads", type=int, default=1, help="OpenMP/BLAS threads, both codes")
    parser.add_argument(
        "--law",
        choices=["wrinkling", "linear", "auto"],
        default="wrinkling",
        help="Kratos law; auto: linear where wrinkling does not converge",
    )
    parser.add_argument(
        "--kratos-options",
        type=shlex.split,
        default=[],
        help='passed on to kratos_airbag.py, e.g. "--ramp-steps 5"',
    )
    args = parser.parse_args()

    python = kratos_python(args.kratos_venv)
    env = dict(os.environ)
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[name] = str(args.threads)
    header = (
        f"{'n':>4} {'elements':>8} {'unknowns':>8} | {'w iter':>6} {'w s':>7} "
        f"{'w mm':>9} | {'Kratos law':>10} {'K iter':>6} {'K s':>8} {'K mm':>9} "
        f"{'conv':>5} | {'w/K':>6}"
    )
    print(header, flush=True)
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for n in args.sizes:
            row = compare(n, write_problem(n, Path(scratch)), python, args, env)
            rows.append(row)
            print(
                f"{row['n']:4d} {row['elements']:8d} {cell(row, 'unknowns', 'd', 8)} | "
                f"{cell(row, 'wrinkle_iterations', 'd', 6)} {cell(row, 'wrinkle_s', '.2f', 7)} "
                f"{cell(row, 'wrinkle_mm', '.3f', 9)} | {row['kratos_law']:>10} "
                f"{cell(row, 'kratos_iterations', 'd', 6)} {cell(row, 'kratos_s', '.1f', 8)} "
                f"{cell(row if row['kratos_converged'] else {}, 'kratos_mm', '.3f', 9)} "
                f"{row['kratos_converged']!s:>5} | "
                f"{cell(row, 'ratio', '.4f', 6)}",
                flush=True,
            )
            if row.get("kratos_path"):
                print(f"     Kratos {row['kratos_path']}", flush=True)
            if row["kratos_error"]:
                print(f"     Kratos: {row['kratos_error']}", flush=True)
    write_csv(args.csv, rows, FIELDS)


if __name__ == "__main__":
    main()
