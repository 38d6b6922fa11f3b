"""Make ``sheet.msh``: a rectangular sheet with a hole, meshed in triangles by gmsh, carrying a
fibre direction per triangle as gmsh element data (a ``$ElementData`` view named "fibre").

Run with the gmsh Python API (``pip install gmsh``) from this folder:

    python make_mesh.py

The sheet is 0.2 m x 0.1 m with a central hole of radius 0.02 m. Physical groups: the
surface "sheet" and the boundary lines "left", "right", "bottom", "top" and "hole". The
fibres turn with the distance from the left edge: at a triangle's centroid (x, y),
``fibre_direction(x, y) = (cos a, sin a, 0)`` with ``a = pi/4 * x / WIDTH``, from along x at
the left edge to 45 degrees at the right edge. The file is gmsh's ASCII format 4.1, the mesh
followed by the view (wrinkle reads the view by the triangles' element tags).
"""

from __future__ import annotations

import math

import gmsh

WIDTH, HEIGHT, HOLE_RADIUS, SIZE = 0.2, 0.1, 0.02, 0.01  # m


def fibre_direction(x: float, y: float) -> tuple[float, float, float]:
    """The fibre direction (unit, in the sheet's plane) at the point (x, y), m."""
    angle = 0.25 * math.pi * x / WIDTH
    return (math.cos(angle), math.sin(angle), 0.0)


def _side(x: float, y: float) -> str:
    """The physical group of the boundary line whose centre is at (x, y), m."""
    for name, on_it in (
        ("left", x < 1e-9),
        ("right", x > WIDTH - 1e-9),
        ("bottom", y < 1e-9),
        ("top", y > HEIGHT - 1e-9),
    ):
        if on_it:
            return name
    return "hole"


def main(path: str = "sheet.msh") -> None:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("sheet")
        occ = gmsh.model.occ
        rectangle = occ.addRectangle(0.0, 0.0, 0.0, WIDTH, HEIGHT)
        hole = occ.addDisk(WIDTH / 2, HEIGHT / 2, 0.0, HOLE_RADIUS, HOLE_RADIUS)
        (surface,), _ = occ.cut([(2, rectangle)], [(2, hole)])
        occ.synchronize()
        lines: dict[str, list[int]] = {"left": [], "right": [], "bottom": [], "top": [], "hole": []}
        for _, line in gmsh.model.getBoundary([surface], oriented=False):
            x, y, _ = gmsh.model.occ.getCenterOfMass(1, line)
            name = _side(x, y)
            lines[name].append(line)
        for name, tags in lines.items():
            gmsh.model.addPhysicalGroup(1, tags, name=name)
        gmsh.model.addPhysicalGroup(2, [surface[1]], name="sheet")
        gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE)
        gmsh.option.setNumber("Mesh.MeshSizeMin", SIZE)
        gmsh.model.mesh.generate(2)

        # one fibre vector per triangle, at its centroid
        types, element_tags, _ = gmsh.model.mesh.getElements(2, surface[1])
        triangles = list(element_tags[list(types).index(2)])
        data = []
        for tag in triangles:
            _, corners, _, _ = gmsh.model.mesh.getElement(tag)
            points = [gmsh.model.mesh.getNode(node)[0] for node in corners]
            x = sum(p[0] for p in points) / 3.0
            y = sum(p[1] for p in points) / 3.0
            data.append(list(fibre_direction(x, y)))
        view = gmsh.view.add("fibre")
        gmsh.view.addModelData(view, 0, "sheet", "ElementData", triangles, data, numComponents=3)

        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("PostProcessing.SaveMesh", 0)  # the mesh is written once
        gmsh.option.setNumber("PostProcessing.SaveInterpolationMatrices", 0)
        gmsh.write(path)
        gmsh.view.write(view, path, append=True)
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
