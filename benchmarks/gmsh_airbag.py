"""Unstructured gmsh meshes of the quarter airbag of examples/airbag.toml, for the hard cases.

The square 0 <= x, y <= a (a = 0.6 m x sqrt(2) / 2, the quarter of the airbag's top sheet
between its centre and its seams) meshed by gmsh's Frontal-Delaunay algorithm with a uniform
target size chosen for about ``elements`` triangles, written as a gmsh 4.1 .msh file with the
physical groups the case files name: lines "symmetry_x" (x = 0), "symmetry_y" (y = 0) and
"seam" (x = a or y = a), surface "sheet". Needs the gmsh Python package (the ``mesh`` extra).

    python benchmarks/gmsh_airbag.py 2400 tests/data/airbag_gmsh_2400.msh
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

SIDE = 0.6 * math.sqrt(2.0) / 2.0  # m, the quarter sheet's side (examples/airbag.toml)


def write_airbag_mesh(elements: int, path: Path, seed: int = 1) -> int:
    """Mesh the quarter airbag with about ``elements`` triangles and write it to ``path``;
    returns the number of triangles. The target size h follows from the area of an
    equilateral triangle, sqrt(3)/4 h^2, times ``elements`` = SIDE^2."""
    import gmsh

    size = SIDE / math.sqrt(math.sqrt(3.0) / 4.0 * elements)
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay
        gmsh.option.setNumber("Mesh.RandomSeed", seed)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.model.add("airbag")
        corners = [(0.0, 0.0), (SIDE, 0.0), (SIDE, SIDE), (0.0, SIDE)]
        points = [gmsh.model.geo.addPoint(x, y, 0.0, size) for x, y in corners]
        lines = [gmsh.model.geo.addLine(points[k], points[(k + 1) % 4]) for k in range(4)]
        loop = gmsh.model.geo.addCurveLoop(lines)
        surface = gmsh.model.geo.addPlaneSurface([loop])
        gmsh.model.geo.synchronize()
        gmsh.model.addPhysicalGroup(1, [lines[0]], name="symmetry_y")  # y = 0
        gmsh.model.addPhysicalGroup(1, [lines[3]], name="symmetry_x")  # x = 0
        gmsh.model.addPhysicalGroup(1, [lines[1], lines[2]], name="seam")
        gmsh.model.addPhysicalGroup(2, [surface], name="sheet")
        gmsh.model.mesh.generate(2)
        types, tags, _ = gmsh.model.mesh.getElements(2)
        count = sum(len(t) for t in tags)
        path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("elements", type=int, help="about this many triangles")
    parser.add_argument("path", type=Path, help="the .msh file to write")
    args = parser.parse_args()
    count = write_airbag_mesh(args.elements, args.path)
    print(f"{args.path}: {count} triangles")


if __name__ == "__main__":
    main()
