"""What the setup of one mesh level costs before its first iteration: the parts that grow
with the mesh and are paid once per level (a nested solve pays them on every level).

On the quarter airbag of examples/airbag.toml with bending on n x n squares (2 n^2
elements), the script times, each as the median of ``--repeat`` calls after a first one
(the first also loads the compiled kernels):

- ``mesh``: ``Mesh(nodes, triangles)``, whose checks find duplicate and inverted elements;
- ``boundary edges``: ``wrinkle.loads.boundary_edges`` of every triangle, which the
  pressure's closure test (``DiscreteSystem.volume_closure``) runs;
- ``sparsity pattern``: ``wrinkle.assembly.SparsityPattern`` of the mesh and the bending
  energy's node pairs, the CSR pattern of every matrix of the level;
- ``step metric``: ``DiscreteSystem.step_metric()``, the unit-tension Laplacian that the
  solver's metric and the prescribed motion's force scale are made of;
- ``case to first problem``: the case read, its model discretised (patterns, geometry,
  bending hinges), the checks that it can be resolved (``check_resolvable``, which
  evaluates the reference state) and the first step's problem (``DiscreteSystem.at``),
  all made anew at each call.

Times in milliseconds. Run it on two source trees in turns to compare:

    python benchmarks/in_turns.py --trees ../before/src src --rounds 3 --match "  " -- \\
        benchmarks/setup_parts.py --sizes 224 704
"""

from __future__ import annotations

import argparse
from pathlib import Path

from timing import median_ms

from wrinkle import Mesh
from wrinkle.assembly import SparsityPattern
from wrinkle.bending import Bending
from wrinkle.case import read_case
from wrinkle.loads import boundary_edges

AIRBAG = Path(__file__).resolve().parents[1] / "examples" / "airbag.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[224, 704])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    parts = ["mesh", "boundary edges", "sparsity pattern", "step metric", "case to first problem"]
    print(f"{'elements':>9} " + " ".join(f"{part:>22}" for part in parts) + "   (ms)")
    for n in args.sizes:
        overrides = {"mesh": {"rectangle": {"nx": n, "ny": n}}, "material": {"bending": True}}
        model = read_case(AIRBAG, overrides=overrides).model
        nodes, triangles = model.mesh.nodes, model.mesh.triangles
        system = model.discretise()
        pairs = Bending(model.mesh, 1.0).coupled_pairs()  # the nodes the hinges couple

        def case_to_problem(overrides: dict = overrides) -> None:
            system = read_case(AIRBAG, overrides=overrides).model.discretise()
            system.check_resolvable()
            system.at(1.0)

        times = [
            median_ms(lambda n=nodes, t=triangles: Mesh(n, t), args.repeat),
            median_ms(lambda t=triangles: boundary_edges(t), args.repeat),
            median_ms(
                lambda t=triangles, m=nodes.shape[0], p=pairs: SparsityPattern(t, m, p),
                args.repeat,
            ),
            median_ms(system.step_metric, args.repeat),
            median_ms(case_to_problem, args.repeat),
        ]
        print(f"{triangles.shape[0]:>9} " + " ".join(f"{t:>22.1f}" for t in times))


if __name__ == "__main__":
    main()
