"""Timing of the element kernels and of the assembly, on one core.

For structured rectangle meshes of about 1e4, 1e5 and 1e6 triangles under a deformation that
leaves part of the membrane taut, part wrinkled and part slack, the script times

1. ``MembraneElements.evaluate``: nodal forces and stiffness of all elements, with wrinkling;
2. the same, forces only (``stiffness=False``);
3. assembly of the element stiffness data (block by block, ``add_to_data``, as a solve does)
   and of the force vector through ``SparsityPattern``;
4. construction of the ``SparsityPattern`` (done once per model),

and prints the medians of ``--repeat`` runs (wall clock, and user CPU time, which is less
sensitive to the load of a shared machine), the time per element and the peak resident memory.
Each mesh size runs in a fresh subprocess, so that the peak RSS belongs to that size alone,
once with the NumPy kernels and once with the compiled ones (``wrinkle.compiled``, Numba;
WRINKLE_NUMBA=0 / 1) if Numba is installed; compilation happens in the warm-up run, untimed.

NumPy runs single-threaded: OMP_NUM_THREADS, OPENBLAS_NUM_THREADS and MKL_NUM_THREADS are set to
1 before NumPy is imported (here and in the subprocesses).

Usage::

    python benchmarks/kernels.py --sizes 1e4 1e5 1e6 --repeat 3 --material ti
    python benchmarks/kernels.py --kernels numpy      # NumPy only
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

from wrinkle import compiled
from wrinkle.assembly import SparsityPattern
from wrinkle.element import KERNEL_BLOCK, MembraneElements
from wrinkle.kinematics import element_coordinates, reference_geometry
from wrinkle.materials import NeoHookean, StVenantKirchhoff
from wrinkle.mesh import Mesh, rectangle
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling

MATERIALS = {
    "ti": "StVenantKirchhoff.transversely_isotropic(E_L=5, E_T=1, nu_LT=0.3, nu_TT=0.3, "
    "G_LT=1/2.6, thickness=1)",
    "iso": "StVenantKirchhoff.isotropic(E=1, nu=0.3, thickness=1)",
    "neo": "NeoHookean(mu=1/2.6, thickness=1) (incompressible)",
    "neo-c": "NeoHookean(mu=1/2.6, thickness=1, lmbda=0.577) (compressible, lambda of nu=0.3)",
}


def make_material(name: str):
    """The membrane material called ``name`` in MATERIALS."""
    if name == "ti":
        return StVenantKirchhoff.transversely_isotropic(
            E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=1.0
        )
    if name == "iso":
        return StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0)
    if name == "neo":
        return NeoHookean(mu=1.0 / 2.6, thickness=1.0)
    if name == "neo-c":
        return NeoHookean(mu=1.0 / 2.6, thickness=1.0, lmbda=0.3 / (1.3 * 0.4))
    raise ValueError(f"unknown material {name!r}; choose from {sorted(MATERIALS)}")


def benchmark_mesh(n_elements: float) -> Mesh:
    """Unit square split into about ``n_elements`` triangles (2 per square of an m x m grid)."""
    m = max(1, round(np.sqrt(float(n_elements) / 2.0)))
    return rectangle(1.0, 1.0, m, m)


def benchmark_deformation(nodes: np.ndarray) -> np.ndarray:
    """Current node positions, (n_nodes, 3), of the benchmark deformation.

    x = 0.9 X + 0.12 X^2 + 0.05 Y, y = 0.9 Y + 0.12 Y^2, z = 0.03 sin(pi X) sin(pi Y):
    stretches from 0.9 (compressed) to 1.14 along each axis, a simple shear, and a bulge. The
    corner near the origin is slack, the opposite one taut, the rest mostly wrinkled.
    """
    X, Y = nodes[:, 0], nodes[:, 1]
    return np.column_stack(
        [
            0.9 * X + 0.12 * X * X + 0.05 * Y,
            0.9 * Y + 0.12 * Y * Y,
            0.03 * np.sin(np.pi * X) * np.sin(np.pi * Y),
        ]
    )


def benchmark_case(n_elements: float, material: str = "ti"):
    """(mesh, MembraneElements, current element coordinates (n, 3, 3)) of one benchmark size."""
    mesh = benchmark_mesh(n_elements)
    geometry = reference_geometry(mesh.nodes, mesh.triangles)
    elements = MembraneElements(
        geometry, Wrinkling(make_material(material)), compiled=compiled.enabled(mesh.n_elements)
    )
    x_elements = element_coordinates(benchmark_deformation(mesh.nodes), mesh.triangles)
    return mesh, elements, x_elements


def _median_time(function, repeat: int) -> tuple[float, float]:
    """Median wall-clock and median user-CPU seconds of ``repeat`` calls of ``function``.

    User time leaves out the kernel's work (zeroing fresh pages for the large outputs) and time
    spent waiting for the core, both of which vary with the load of a shared machine.
    """
    wall, user = [], []
    for _ in range(repeat):
        user_start = resource.getrusage(resource.RUSAGE_SELF).ru_utime
        start = time.perf_counter()
        function()
        wall.append(time.perf_counter() - start)
        user.append(resource.getrusage(resource.RUSAGE_SELF).ru_utime - user_start)
    return float(np.median(wall)), float(np.median(user))


def run_size(n_elements: float, material: str, repeat: int) -> dict:
    """Timings (seconds, medians), state counts and peak RSS (MB) for one mesh size."""
    mesh, elements, x_elements = benchmark_case(n_elements, material)
    result = elements.evaluate(x_elements)  # warm-up; also gives the states
    state = result.response.state
    counts = {
        name: int(np.count_nonzero(state == s))
        for name, s in (("taut", TAUT), ("wrinkled", WRINKLED), ("slack", SLACK))
    }
    forces, stiffness = result.forces, result.stiffness
    del result

    holder = {}

    def evaluate_all():
        holder.clear()  # free the previous result before computing the next
        holder["result"] = elements.evaluate(x_elements, stiffness=True)

    def evaluate_forces():
        holder.clear()
        holder["result"] = elements.evaluate(x_elements, stiffness=False)

    t_evaluate, user_evaluate = _median_time(evaluate_all, repeat)
    t_forces, user_forces = _median_time(evaluate_forces, repeat)
    holder.clear()

    start = time.perf_counter()
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
    t_pattern = time.perf_counter() - start

    def assemble():  # block by block, as StepProblem.evaluate assembles
        data = np.zeros(pattern.nnz)
        for start in range(0, mesh.n_elements, KERNEL_BLOCK):
            block = slice(start, min(start + KERNEL_BLOCK, mesh.n_elements))
            pattern.add_to_data(data, block, stiffness[block], compiled=elements.compiled)
        holder["data"] = data
        holder["vector"] = pattern.assemble_vector(forces)

    assemble()  # warm-up (compiles the scatter)
    t_assemble, _ = _median_time(assemble, repeat)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB
    return {
        "elements": int(mesh.n_elements),
        "kernels": "numba" if compiled.enabled(mesh.n_elements) else "numpy",
        **counts,
        "evaluate": t_evaluate,
        "evaluate_user": user_evaluate,
        "forces": t_forces,
        "forces_user": user_forces,
        "assemble": t_assemble,
        "pattern": t_pattern,
        "peak_rss_mb": peak_mb,
    }


def _parse_size(text: str) -> float:
    value = float(text)
    if not value >= 2:
        raise argparse.ArgumentTypeError(f"size must be >= 2 elements, got {text}")
    return value


def print_table(rows: list[dict], material: str, repeat: int) -> None:
    print(f"material: {material}: {MATERIALS[material]}")
    print(
        f"numpy {np.__version__}, single-threaded (OMP_NUM_THREADS=OPENBLAS_NUM_THREADS="
        f"MKL_NUM_THREADS=1), median of {repeat} run(s); one subprocess per size and kernels"
    )
    if compiled.installed():
        from importlib.metadata import version

        print(f"numba {version('numba')} (kernels 'numba': wrinkle.compiled, on every size)")
    print(
        "(1) evaluate forces + stiffness with wrinkling, (2) forces only, "
        "(3) assemble stiffness data + force vector, (4) build SparsityPattern (once);"
    )
    print("wall-clock seconds, microseconds per element, and user-CPU seconds ('user')")
    header = (
        f"{'elements':>9} {'kernels':>7} {'taut':>8} {'wrinkled':>8} {'slack':>8} | "
        f"{'(1) K+f s':>9} {'us/el':>6} {'user':>6} | {'(2) f s':>8} {'us/el':>6} {'user':>6} | "
        f"{'(3) asm s':>9} {'us/el':>6} | {'(4) patt s':>10} | {'peak RSS MB':>11}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        n = r["elements"]
        print(
            f"{n:>9d} {r['kernels']:>7} {r['taut']:>8d} {r['wrinkled']:>8d} {r['slack']:>8d} | "
            f"{r['evaluate']:>9.4f} {1e6 * r['evaluate'] / n:>6.2f} {r['evaluate_user']:>6.2f} | "
            f"{r['forces']:>8.4f} {1e6 * r['forces'] / n:>6.2f} {r['forces_user']:>6.2f} | "
            f"{r['assemble']:>9.4f} {1e6 * r['assemble'] / n:>6.2f} | "
            f"{r['pattern']:>10.4f} | {r['peak_rss_mb']:>11.0f}"
        )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes",
        nargs="+",
        type=_parse_size,
        default=[1e4, 1e5, 1e6],
        help="approximate numbers of triangles (default: 1e4 1e5 1e6)",
    )
    parser.add_argument(
        "--repeat", type=int, default=3, help="runs per timing; the median is reported (default: 3)"
    )
    parser.add_argument(
        "--material",
        choices=sorted(MATERIALS),
        default="ti",
        help="ti: transversely isotropic St Venant-Kirchhoff (default); "
        "iso: isotropic St Venant-Kirchhoff; neo / neo-c: incompressible / "
        "compressible neo-Hookean",
    )
    parser.add_argument(
        "--kernels",
        nargs="+",
        choices=["numpy", "numba"],
        default=["numpy", "numba"] if compiled.installed() else ["numpy"],
        help="element and scatter kernels to time (default: both if Numba is installed)",
    )
    parser.add_argument("--json", action="store_true", help="print the rows as JSON as well")
    parser.add_argument("--single", type=_parse_size, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be >= 1")

    if args.single is not None:  # worker: one size, JSON on stdout
        print(json.dumps(run_size(args.single, args.material, args.repeat)))
        return

    if "numba" in args.kernels and not compiled.installed():
        parser.error("--kernels numba: numba is not installed (pip install numba)")
    rows = []
    for size, kernels in ((size, kernels) for size in args.sizes for kernels in args.kernels):
        command = [
            sys.executable,
            os.path.abspath(__file__),
            "--single",
            repr(size),
            "--repeat",
            str(args.repeat),
            "--material",
            args.material,
        ]
        environment = {**os.environ, "WRINKLE_NUMBA": "1" if kernels == "numba" else "0"}
        completed = subprocess.run(
            command, capture_output=True, text=True, check=False, env=environment
        )
        if completed.returncode != 0:
            sys.stderr.write(completed.stderr)
            raise SystemExit(f"benchmark of size {size:g} ({kernels}) failed")
        rows.append(json.loads(completed.stdout.strip().splitlines()[-1]))
    print_table(rows, args.material, args.repeat)
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
