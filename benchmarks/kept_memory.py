"""Solves with their freed memory kept (``wrinkle.memory``, the default since 6 December 2026)
and with the allocator as the process has it, in turns, each solve in its own process (the
allocator's settings last for a process).

Problems: the sheared rectangle (benchmarks/hard_cases/sheared_rectangle.toml) on nx x nx/2
squares, and the airbags of benchmarks/scale.py (``airbag``, ``airbag_nested``, ...) on its
n x n meshes. Prints, for each problem and setting, each round's wall time, the median of the
seconds per part (element evaluation, assembly, linear solves, rest), the share outside the
linear solves, the peak resident set, the iterations and factorisations, and the result (the
rectangle: its top edge's reaction; an airbag: the centre deflection); then the ratio of the
median wall times, kept over system.

    python benchmarks/kept_memory.py --problems rectangle:320 airbag_nested:224 --rounds 3
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

PARTS = ("element evaluation", "assembly", "linear solves", "rest")
RECTANGLE = Path(__file__).parent / "hard_cases" / "sheared_rectangle.toml"
SETTINGS = ("system", "kept")


def solve(problem: str, n: int, keep: bool) -> dict:
    """One solve in this process, with (keep) or without the kept memory; its numbers."""
    import tempfile

    import wrinkle.memory
    from wrinkle.case import read_case

    wrinkle.memory.enabled = keep
    with tempfile.TemporaryDirectory(prefix="kept-memory-") as scratch:
        if problem == "rectangle":
            case = read_case(RECTANGLE, {"mesh": {"rectangle": {"nx": n, "ny": n // 2}}})
        else:
            from scale import CASE_FILES, CASES, mesh_overrides

            name, overrides = CASES[problem]
            mesh = mesh_overrides(problem, n, Path(scratch))
            case = read_case(CASE_FILES[name], overrides={**overrides, "mesh": mesh})
        start = time.perf_counter()
        results = case.solve()
        wall = time.perf_counter() - start
    u = results.final.displacement.reshape(-1, 3)
    if problem == "rectangle":
        top = case.model.support_reactions(results.final.reactions)["top"]
        result = f"top ({top[0]:.4f}, {top[1]:.4f}) N"
    else:
        result = f"centre {1e3 * float(u[case.probes['centre'], 2].mean()):.3f} mm"
    timings = results.timings
    return {
        "elements": case.model.mesh.n_elements,
        "iterations": results.final.iterations,
        "factorisations": results.factorisations,
        "wall": wall,
        "outside": (timings["total"] - timings["linear solves"]) / timings["total"],
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "result": result,
        **{part: timings[part] for part in PARTS},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--problems",
        nargs="+",
        default=["rectangle:320"],
        help="problem:size, rectangle (nx) or a problem of benchmarks/scale.py (n)",
    )
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--one", nargs=3, metavar=("PROBLEM", "SIZE", "SETTING"), help="(child)")
    args = parser.parse_args()
    if args.one:
        problem, size, setting = args.one
        print(json.dumps(solve(problem, int(size), setting == "kept")))
        return
    print(
        f"{'problem':>20} {'setting':>7} {'elements':>9} {'wall s (rounds)':>24} "
        + " ".join(f"{p[:8]:>8}" for p in PARTS)
        + f" {'outside':>8} {'peak MB':>8} {'its/fact':>9}  result"
    )
    for item in args.problems:
        problem, size = item.split(":")
        runs: dict[str, list[dict]] = {name: [] for name in SETTINGS}
        for _ in range(args.rounds):
            for name in SETTINGS:
                done = subprocess.run(
                    [sys.executable, __file__, "--one", problem, size, name],
                    capture_output=True,
                    text=True,
                    check=True,
                )
                runs[name].append(json.loads(done.stdout.strip().splitlines()[-1]))
        for name, rows in runs.items():
            median = {k: statistics.median(r[k] for r in rows) for k in (*PARTS, "outside")}
            walls = ", ".join(f"{r['wall']:.1f}" for r in rows)
            counts = "/".join(sorted({f"{r['iterations']}/{r['factorisations']}" for r in rows}))
            print(
                f"{item:>20} {name:>7} {rows[0]['elements']:>9} {walls:>24} "
                + " ".join(f"{median[p]:8.2f}" for p in PARTS)
                + f" {100 * median['outside']:7.1f}% {max(r['peak_mb'] for r in rows):8.0f}"
                + f" {counts:>9}  {rows[-1]['result']}"
            )
        ratio = statistics.median(r["wall"] for r in runs["kept"]) / statistics.median(
            r["wall"] for r in runs["system"]
        )
        print(f"{item:>20} kept/system wall {ratio:.2f}", flush=True)


if __name__ == "__main__":
    main()
