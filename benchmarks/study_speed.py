"""A parameter study on a local Dask cluster against the same variants one after the other in
one process (issue 23): wall time, the ratio, and whether every variant's numbers agree.

The study: the quarter airbag of examples/airbag.toml (32 x 32, 2,048 triangles) at N
pressures from 4 to 6 kPa (``load.1.value``), every quantity of its history collected. The
sequential run is ``run_study(..., engine="here")`` (this process, one variant after the
other); the cluster run a ``distributed.LocalCluster`` of ``--workers`` single-threaded
processes (``engine="dask"``), its start-up included. The two run in turns, ``--repeats``
times; the table gives each run and the median ratio.

    python benchmarks/study_speed.py                  # 200 variants, 2 workers, once
    python benchmarks/study_speed.py --variants 20 --repeats 2
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from wrinkle.studies import read_study, run_study

ROOT = Path(__file__).resolve().parents[1]


def study_file(folder: Path, variants: int) -> Path:
    path = folder / "study.toml"
    path.write_text(
        f'case = "{ROOT / "examples" / "airbag.toml"}"\n'
        f'[[parameter]]\npath = "load.1.value"\nrange = [4000.0, 6000.0, {variants}]\n'
    )
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=1)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        study = read_study(study_file(folder, args.variants))
        lines, ratios = [], []
        for repeat in range(args.repeats):
            timings = {}
            rows = {}
            for engine in ("here", "dask"):
                out = folder / f"{engine}_{repeat}"
                start = time.perf_counter()
                rows[engine] = run_study(study, out, workers=args.workers, engine=engine)
                timings[engine] = time.perf_counter() - start
            same = all(
                {k: v for k, v in a.items() if k not in ("seconds",)}
                == {k: v for k, v in b.items() if k not in ("seconds",)}
                for a, b in zip(rows["here"], rows["dask"], strict=True)
            )
            converged = sum(row["status"] == "converged" for row in rows["dask"])
            ratio = timings["dask"] / timings["here"]
            ratios.append(ratio)
            lines.append(
                f"| {repeat + 1} | {args.variants} | {timings['here']:.1f} | "
                f"{args.workers} | {timings['dask']:.1f} | {ratio:.2f} | {converged} | "
                f"{'yes' if same else 'NO'} |"
            )
        print(
            "| run | variants | one process (s) | workers | Dask LocalCluster (s) | ratio | "
            "converged | identical rows |"
        )
        print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
        print("\n".join(lines))
        print(f"\nmedian ratio {statistics.median(ratios):.2f} (target <= 0.6)")
        centre = [row.get("centre_uz", np.nan) for row in rows["dask"]]
        print(f"centre deflection {min(centre):.4f} .. {max(centre):.4f} m")


if __name__ == "__main__":
    main()
