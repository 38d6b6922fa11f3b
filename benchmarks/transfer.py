"""The cost of moving a nodal field between two meshes of one surface (wrinkle.transfer).

For about 10^5 and 10^6 fine nodes, on three pairs of meshes with about a quarter as many
coarse nodes: the airbag's quarter sheet on independent gmsh meshes (benchmarks/gmsh_airbag.py,
the mesh extra; skipped without gmsh), two structured meshes of the unit square that are not
nested (diagonals the other way, n and 2n - 1 squares a side), and two octants of the unit
sphere (``wrinkle.mesh.sphere``, n and 2n - 1), a curved surface. Each row: the time to build
the ``PointTransfer`` (the search and the sparse matrix; the meshes are made before the
clock), the time of one ``prolong`` of a displacement field (n_coarse_nodes, 3), the largest
distance of a fine node from the coarse surface, and the peak resident set of the process so
far. Each size runs in its own process.

    python benchmarks/transfer.py --sizes 1e5 1e6
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PAIRS = ["gmsh airbag", "square", "sphere"]


def meshes(pair: str, nodes: float, scratch: Path):
    """The coarse and fine meshes of ``pair`` for about ``nodes`` fine nodes."""
    from wrinkle.mesh import read_mesh, rectangle, sphere

    if pair == "gmsh airbag":
        from gmsh_airbag import write_airbag_mesh

        write_airbag_mesh(round(nodes / 2), scratch / "coarse.msh", seed=2)
        write_airbag_mesh(round(2 * nodes), scratch / "fine.msh", seed=1)
        return read_mesh(scratch / "coarse.msh"), read_mesh(scratch / "fine.msh")
    n = round(math.sqrt(nodes) / 2) if pair == "square" else round(math.sqrt(2 * nodes) / 2)
    if pair == "square":
        return rectangle(1.0, 1.0, n, n), rectangle(1.0, 1.0, 2 * n - 1, 2 * n - 1, "left")
    return sphere(1.0, n), sphere(1.0, 2 * n - 1)


def measure(pair: str, nodes: float) -> dict:
    import numpy as np

    from wrinkle.transfer import PointTransfer

    with tempfile.TemporaryDirectory(prefix="transfer-") as scratch:
        coarse, fine = meshes(pair, nodes, Path(scratch))
    start = time.perf_counter()
    transfer = PointTransfer(coarse, fine)
    build = time.perf_counter() - start
    values = np.random.default_rng(0).normal(size=(coarse.n_nodes, 3))
    start = time.perf_counter()
    transfer.prolong(values)
    prolong = time.perf_counter() - start
    return {
        "pair": pair,
        "coarse_nodes": coarse.n_nodes,
        "fine_nodes": fine.n_nodes,
        "build_s": build,
        "prolong_s": prolong,
        "largest_gap": float(transfer.distance.max()),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[1e5, 1e6])
    parser.add_argument("--pairs", nargs="+", default=PAIRS, choices=PAIRS)
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.one[0], float(args.one[1]))))
        return
    print(
        f"{'pair':>12} {'coarse nodes':>12} {'fine nodes':>11} {'build s':>8} {'prolong s':>9} "
        f"{'largest gap':>11} {'peak MB':>8}"
    )
    for nodes in args.sizes:
        for pair in args.pairs:
            command = [sys.executable, __file__, "--one", pair, str(nodes)]
            done = subprocess.run(command, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                print(f"{pair:>12} {nodes:.0e}: failed\n{done.stderr.strip()[-1000:]}")
                continue
            row = json.loads(done.stdout.strip().splitlines()[-1])
            print(
                f"{row['pair']:>12} {row['coarse_nodes']:12,} {row['fine_nodes']:11,} "
                f"{row['build_s']:8.2f} {row['prolong_s']:9.3f} {row['largest_gap']:11.2e} "
                f"{row['peak_rss_mb']:8.0f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
