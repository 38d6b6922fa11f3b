"""A parameter study on a local Dask cluster against the same variants one after the other in
one process (issue 23): wall time, the ratio, and whether every variant's numbers agree.

The study: the quarter airbag of examples/airbag.toml (32 x 32, 2,048 triangles) at N
pressures from 4 to 6 kPa (``load.1.value``), every quantity of its history collected. The
sequential run is ``run_study(..., engine="here")`` (this process, one variant after the
other); the cluster run a ``distributed.LocalCluster`` of ``--workers`` single-threaded
processes (``engine="dask"``), its start-up included. With ``--dask-defaults`` a third run
goes to a LocalCluster the script starts with Dask's own worker settings (given to the study
as ``--scheduler`` would be; its start-up not included): Dask's nanny sets
MALLOC_TRIM_THRESHOLD_ = 65536 and its workers sample their stacks every 10 ms, which
wrinkle's own local cluster does not (``wrinkle.studies.run.LOCAL_CLUSTER_CONFIG``). The runs
go in turns, ``--repeats`` times; the table gives each run and the median ratio.

    python benchmarks/study_speed.py                  # 200 variants, 2 workers, once
    python benchmarks/study_speed.py --variants 20 --repeats 2 --dask-defaults
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


def same_rows(a: list[dict], b: list[dict]) -> bool:
    """Whether two studies' rows agree in every column but the wall seconds."""
    return all(
        {k: v for k, v in x.items() if k != "seconds"}
        == {k: v for k, v in y.items() if k != "seconds"}
        for x, y in zip(a, b, strict=True)
    )


def with_dask_defaults(study, out: Path, workers: int) -> tuple[list[dict], float]:
    """The study on a LocalCluster of Dask's own worker settings (single-threaded
    processes), given to it as an existing cluster; the wall seconds exclude the start."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        start = time.perf_counter()
        rows = run_study(study, out, scheduler=cluster.scheduler_address)
        return rows, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--dask-defaults", action="store_true")
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
            defaults = ""
            if args.dask_defaults:
                plain, seconds = with_dask_defaults(
                    study, folder / f"defaults_{repeat}", args.workers
                )
                same = "yes" if same_rows(rows["here"], plain) else "NO"
                defaults = f" {seconds:.1f} ({seconds / timings['here']:.2f}, {same}) |"
            converged = sum(row["status"] == "converged" for row in rows["dask"])
            ratio = timings["dask"] / timings["here"]
            ratios.append(ratio)
            each = {e: statistics.mean(row["seconds"] for row in rows[e]) for e in rows}
            lines.append(
                f"| {repeat + 1} | {args.variants} | {timings['here']:.1f} "
                f"({each['here']:.2f}) | {args.workers} | {timings['dask']:.1f} "
                f"({each['dask']:.2f}) | {ratio:.2f} | {converged} | "
                f"{'yes' if same_rows(rows['here'], rows['dask']) else 'NO'} |{defaults}"
            )
        extra = " Dask's defaults (s, ratio, identical) |" if args.dask_defaults else ""
        print(
            "| run | variants | one process (s; per variant) | workers | Dask LocalCluster "
            "(s; per variant) | ratio | "
            f"converged | identical rows |{extra}"
        )
        print(
            "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |" + (" ---: |" * bool(extra))
        )
        print("\n".join(lines))
        print(f"\nmedian ratio {statistics.median(ratios):.2f} (target <= 0.6)")
        centre = [row.get("centre_uz", np.nan) for row in rows["dask"]]
        print(f"centre deflection {min(centre):.4f} .. {max(centre):.4f} m")


if __name__ == "__main__":
    main()
