"""The compiled element work of one evaluation, warm: the St Venant-Kirchhoff wrinkling
response and the fused forming and adding of the element matrices
(``DiscreteSystem.assemble_stiffness``), each the median of ``--repeat`` calls after a first
one, ms. Meant to be run on two trees in turns (``in_turns.py``), since it times only the
code it imports.

- ``rectangle``: the sheared rectangle of benchmarks/hard_cases on nx x nx/2 squares, in a
  uniform simple shear u_x = 2 x 10^-3 y (every element wrinkled); every z component held,
  so only the free rows and columns are added (the solves' kept dofs);
- ``airbag``: the quarter airbag of examples/airbag.toml on n x n squares, in a bulge
  u_z = 0.1 (1 - (x/a)^2)(1 - (y/a)^2) m; every element pressurised, so each element's
  whole matrix is formed and its pressure stiffness subtracted.

Needs Numba (the ``fast`` extra).

    python benchmarks/in_turns.py --trees OLD/src src --rounds 3 --match ms -- \\
        benchmarks/stiffness_assembly.py --rectangle 320 --airbag 224
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ["WRINKLE_NUMBA"] = "1"

import numpy as np
from timing import median_ms

from wrinkle.case import read_case

ROOT = Path(__file__).resolve().parents[1]
# the airbag quarter's side, m (examples/airbag.toml)
SIDE = 0.42426406871192845


def shear(X: np.ndarray) -> np.ndarray:
    """Simple shear u_x = 2 x 10^-3 y at the nodes X (n, 3), (n, 3)."""
    return np.column_stack([2e-3 * X[:, 1], np.zeros(len(X)), np.zeros(len(X))])


def bulge(X: np.ndarray) -> np.ndarray:
    """u_z = 0.1 (1 - (x/a)^2)(1 - (y/a)^2) m at the nodes X (n, 3), (n, 3)."""
    w = 0.1 * (1 - (X[:, 0] / SIDE) ** 2) * (1 - (X[:, 1] / SIDE) ** 2)
    return np.column_stack([np.zeros(len(X)), np.zeros(len(X)), w])


def time_parts(name: str, path: Path, mesh: dict, displacement, repeat: int) -> None:
    """Print the response's and the assembly's medians at the state displacement(nodes)."""
    system = read_case(path, overrides={"mesh": {"rectangle": mesh}}).model.discretise()
    problem = system.at(1.0)
    u = displacement(system.mesh.nodes).ravel()
    x = system.element_coordinates(u)
    result = system.evaluate_elements(u, stiffness=True, x_elements=x, matrices=False)
    kept = problem._kept_dofs(False)
    data = np.zeros(system.pattern.nnz)

    def response() -> None:
        system.evaluate_elements(u, stiffness=True, x_elements=x, matrices=False)

    def assembly() -> None:
        system.assemble_stiffness(data, result, x, problem.pressures, kept)

    m = system.mesh.n_elements
    print(f"{name}, {m:,} elements, {np.mean(kept):.0%} of element dofs kept:")
    print(f"  elements (F, wrinkling response, forces) {median_ms(response, repeat):8.2f} ms")
    print(f"  element matrices formed and added        {median_ms(assembly, repeat):8.2f} ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rectangle", type=int, nargs="*", default=[320])
    parser.add_argument("--airbag", type=int, nargs="*", default=[224])
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    for n in args.rectangle:
        time_parts(
            f"rectangle {n} x {n // 2}",
            ROOT / "benchmarks" / "hard_cases" / "sheared_rectangle.toml",
            {"nx": n, "ny": n // 2},
            shear,
            args.repeat,
        )
    for n in args.airbag:
        time_parts(
            f"airbag {n} x {n}",
            ROOT / "examples" / "airbag.toml",
            {"nx": n, "ny": n},
            bulge,
            args.repeat,
        )


if __name__ == "__main__":
    main()
