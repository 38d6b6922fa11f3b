"""Reading meshes through meshio, the polar generators, mesh_size and element sets."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from wrinkle.mesh import Mesh, annulus, disk, mesh_size, read_mesh, rectangle

meshio = pytest.importorskip("meshio")


def signed_areas(mesh: Mesh) -> np.ndarray:
    """z component of (x2 - x1) x (x3 - x1) / 2: positive for counter-clockwise triangles."""
    X = mesh.nodes[mesh.triangles]
    return 0.5 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])[:, 2]


# -- read_mesh -------------------------------------------------------------------------------

# two unit squares side by side: triangles on the left, one quad on the right
POINTS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0], [2.0, 1.0]])


def write(tmp_path, name, points, cells, **kwargs):
    path = tmp_path / name
    meshio.write(
        path,
        meshio.Mesh(points, cells, **kwargs),
        **({"file_format": "gmsh22", "binary": False} if name.endswith(".msh") else {}),
    )
    return path


def test_vtu_triangles_2d_points(tmp_path):
    path = write(tmp_path, "plate.vtu", POINTS[:4], [("triangle", [[0, 1, 2], [0, 2, 3]])])
    mesh = read_mesh(path)
    assert mesh.nodes.shape == (4, 3)
    assert np.array_equal(mesh.nodes[:, :2], POINTS[:4])
    assert np.all(mesh.nodes[:, 2] == 0.0)
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert mesh.node_sets == {} and mesh.element_sets == {}


def test_quads_are_split_along_first_diagonal(tmp_path):
    points = np.column_stack([POINTS, np.zeros(6)])
    path = write(
        tmp_path,
        "mixed.vtu",
        points,
        [("triangle", [[0, 1, 2], [0, 2, 3]]), ("quad", [[1, 4, 5, 2]])],
    )
    mesh = read_mesh(path)
    # quad (a, b, c, d) -> (a, b, c), (a, c, d), after the triangles of the earlier block
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]]
    assert np.all(signed_areas(mesh) > 0)  # orientation kept
    assert signed_areas(mesh).sum() == pytest.approx(2.0, rel=1e-14)


GMSH_POINTS = np.column_stack([POINTS, np.zeros(6)])
GMSH_CELLS = [
    ("vertex", np.array([[0]])),
    ("line", np.array([[0, 3]])),
    ("line", np.array([[4, 5]])),
    ("triangle", np.array([[0, 1, 2], [0, 2, 3]])),
    ("quad", np.array([[1, 4, 5, 2]])),
]
GMSH_PHYSICAL = [np.array([5]), np.array([1]), np.array([2]), np.array([10, 10]), np.array([11])]
GMSH_FIELDS = {  # name: (physical tag, dimension); tag 1 would clash without the dimension
    "corner": np.array([5, 0]),
    "left": np.array([1, 1]),
    "right": np.array([2, 1]),
    "plate": np.array([10, 2]),
    "patch": np.array([11, 2]),
    "clash": np.array([1, 2]),
}


def write_gmsh_groups(tmp_path):
    """The gmsh 2.2 file of GMSH_POINTS and GMSH_CELLS with their physical groups."""
    return write(
        tmp_path,
        "groups.msh",
        GMSH_POINTS,
        GMSH_CELLS,
        cell_data={"gmsh:physical": GMSH_PHYSICAL, "gmsh:geometrical": GMSH_PHYSICAL},
        field_data=GMSH_FIELDS,
    )


def test_gmsh22_physical_groups(tmp_path):
    path = write_gmsh_groups(tmp_path)
    mesh = read_mesh(path)
    assert mesh.n_nodes == 6 and mesh.n_elements == 4
    sets = {name: nodes.tolist() for name, nodes in mesh.node_sets.items()}
    assert sets == {
        "corner": [0],
        "left": [0, 3],
        "right": [4, 5],
        "plate": [0, 1, 2, 3],
        "patch": [1, 2, 4, 5],
        "clash": [],
    }
    elements = {name: e.tolist() for name, e in mesh.element_sets.items()}
    assert elements == {"plate": [0, 1], "patch": [2, 3]}  # the quad's two triangles


# gmsh 4.1 as gmsh writes it: physical tags on the entities; node 5 belongs to no element
GMSH41 = """$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
0 1 "origin"
1 2 "bottom"
2 3 "plate"
$EndPhysicalNames
$Entities
2 1 1 0
1 0 0 0 1 1
2 1 0 0 0
1 0 0 0 1 0 0 1 2 2 1 -2
1 0 0 0 1 1 0 1 3 1 1
$EndEntities
$Nodes
1 5 1 5
2 1 0 5
1
2
3
4
5
0 0 0
5 5 0
1 0 0
1 1 0
0 1 0
$EndNodes
$Elements
3 4 1 4
0 1 15 1
1 1
1 1 1 1
2 1 3
2 1 2 2
3 1 3 4
4 1 4 5
$EndElements
"""


def test_gmsh41_physical_groups_and_unused_node_dropped(tmp_path):
    path = tmp_path / "square.msh"
    path.write_text(GMSH41)
    mesh = read_mesh(path)
    # the file's second node (5, 5, 0) is used by no element: dropped, the others renumbered
    assert mesh.nodes.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert {name: n.tolist() for name, n in mesh.node_sets.items()} == {
        "origin": [0],
        "bottom": [0, 1],
        "plate": [0, 1, 2, 3],
    }
    assert {name: e.tolist() for name, e in mesh.element_sets.items()} == {"plate": [0, 1]}


def test_abaqus_node_and_element_sets(tmp_path):
    points = np.column_stack([POINTS, np.zeros(6)])
    cells = [("triangle", np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]]))]
    path = write(
        tmp_path,
        "plate.inp",
        points,
        cells,
        point_sets={"clamp": np.array([0, 3])},
        cell_sets={"right_half": [np.array([2, 3])]},
    )
    mesh = read_mesh(path)
    assert mesh.node_sets["clamp"].tolist() == [0, 3]
    assert mesh.node_sets["right_half"].tolist() == [1, 2, 4, 5]
    assert mesh.element_sets["right_half"].tolist() == [2, 3]


def test_unused_node_is_dropped_and_sets_renumbered(tmp_path):
    points = np.array([[9.0, 9.0, 0.0], *GMSH_POINTS[:4]])  # point 0 is used by no element
    path = write(tmp_path, "extra.vtu", points, [("triangle", [[1, 2, 3], [1, 3, 4]])])
    mesh = read_mesh(path)
    assert mesh.n_nodes == 4
    assert np.array_equal(mesh.nodes, GMSH_POINTS[:4])
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]


@pytest.mark.parametrize(
    "cells, message",
    [
        (
            # node 4 at (2, 0) lies on the line 0-1 (ordered 1, 0 as its neighbour needs)
            [("triangle", [[0, 1, 2], [1, 0, 4]])],
            r"element 1 \(nodes \[1, 0, 4\]\) has zero area",
        ),
        ([("triangle", [[0, 1, 2], [0, 2, 3], [2, 0, 1]])], r"elements \[0, 2\] are duplicates"),
        ([("triangle", [[0, 1, 2], [3, 3, 1]])], r"element 1 repeats a node"),
        ([("line", [[0, 1], [1, 2]])], r"no triangles in the mesh \(cell types: line\)"),
        (
            [("triangle6", [[0, 1, 2, 3, 4, 5]])],
            r"cell type 'triangle6' is not supported; mesh with linear elements",
        ),
        ([("tetra", [[0, 1, 2, 3]])], r"cell type 'tetra' is not supported"),
    ],
    ids=["zero_area", "duplicate", "repeated_node", "no_triangles", "triangle6", "tetra"],
)
def test_bad_mesh_file_is_named(tmp_path, cells, message):
    points = np.column_stack([POINTS, np.zeros(6)])
    path = write(tmp_path, "bad.vtu", points, cells)
    with pytest.raises(ValueError, match=r"^mesh file .*bad\.vtu: " + message) as error:
        read_mesh(path)
    assert "\n" not in str(error.value)


def test_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"mesh file .*nowhere\.msh: no such file"):
        read_mesh(tmp_path / "nowhere.msh")


@pytest.mark.parametrize(
    "name, text, reason",
    [
        ("garbage.msh", "$MeshFormat\nthis is not a mesh\n", "not a valid ansys or gmsh file"),
        ("plate.xyz", "1 2 3\n", "Could not deduce file format"),
    ],
    ids=["corrupt", "unknown_format"],
)
def test_unreadable_file(tmp_path, capfd, name, text, reason):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(
        ValueError, match=rf"^mesh file .*{name}: cannot read it \({reason}"
    ) as error:
        read_mesh(path)  # meshio alone would print and call sys.exit(1) for the corrupt file
    assert "\n" not in str(error.value)
    assert capfd.readouterr() == ("", "")


# -- polar generators --------------------------------------------------------------------------


def inscribed_polygon_area(radius: float, n: int) -> float:
    return n / 2 * radius**2 * math.sin(2 * math.pi / n)


@pytest.mark.parametrize("n_radial, n_circumferential", [(1, 3), (3, 8), (5, 64)])
def test_disk(n_radial, n_circumferential):
    R = 1.7
    mesh = disk(R, n_radial, n_circumferential)
    assert mesh.n_nodes == 1 + n_radial * n_circumferential
    assert mesh.n_elements == (2 * n_radial - 1) * n_circumferential
    assert np.array_equal(mesh.nodes[0], [0.0, 0.0, 0.0])  # the centre is one node
    assert np.all(mesh.nodes[:, 2] == 0.0)
    area = signed_areas(mesh)
    assert np.all(area > 0)  # counter-clockwise seen from +z
    assert area.sum() == pytest.approx(inscribed_polygon_area(R, n_circumferential), rel=1e-13)
    assert np.array_equal(np.unique(mesh.triangles), np.arange(mesh.n_nodes))
    r = np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1])
    assert set(mesh.node_sets) == {"outer"}
    assert np.array_equal(mesh.node_sets["outer"], np.flatnonzero(np.isclose(r, R)))
    # radii of the circles: i R / n_radial
    assert np.allclose(np.unique(np.round(r, 12)), R * np.arange(n_radial + 1) / n_radial)


@pytest.mark.parametrize("n_radial, n_circumferential", [(1, 3), (2, 12), (4, 100)])
def test_annulus(n_radial, n_circumferential):
    a, b = 0.4, 1.3
    mesh = annulus(a, b, n_radial, n_circumferential)
    assert mesh.n_nodes == (n_radial + 1) * n_circumferential
    assert mesh.n_elements == 2 * n_radial * n_circumferential
    area = signed_areas(mesh)
    assert np.all(area > 0)
    expected = inscribed_polygon_area(b, n_circumferential) - inscribed_polygon_area(
        a, n_circumferential
    )
    assert area.sum() == pytest.approx(expected, rel=1e-13)
    r = np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1])
    assert set(mesh.node_sets) == {"inner", "outer"}
    assert np.array_equal(mesh.node_sets["inner"], np.flatnonzero(np.isclose(r, a)))
    assert np.array_equal(mesh.node_sets["outer"], np.flatnonzero(np.isclose(r, b)))
    assert mesh.node_sets["inner"].size == mesh.node_sets["outer"].size == n_circumferential


def test_polygon_area_converges_to_circle():
    """Area error of the inscribed polygon: pi R^2 - area = pi R^2 (2 pi^2 / 3) / n^2 + ..."""
    a, b = 0.5, 1.0
    errors = []
    for n in (16, 32, 64):
        area = signed_areas(annulus(a, b, 2, n)).sum()
        errors.append(math.pi * (b**2 - a**2) - area)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=1e-2)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=1e-2)
    assert errors[2] == pytest.approx(
        math.pi * (b**2 - a**2) * 2 * math.pi**2 / 3 / 64**2, rel=1e-2
    )


@pytest.mark.parametrize(
    "generator, args, message",
    [
        (disk, (0.0, 2, 8), r"disk: radius must be a finite number > 0, got 0.0"),
        (disk, (float("nan"), 2, 8), r"disk: radius must be a finite number > 0"),
        (disk, (1.0, 0, 8), r"disk: n_radial must be an integer >= 1, got 0"),
        (disk, (1.0, 2, 2), r"disk: n_circumferential must be an integer >= 3, got 2"),
        (disk, (1.0, 2.5, 8), r"disk: n_radial must be an integer >= 1, got 2.5"),
        (annulus, (0.0, 1.0, 2, 8), r"annulus: inner_radius must be > 0 \(use disk"),
        (annulus, (-0.1, 1.0, 2, 8), r"annulus: inner_radius must be a finite number >= 0"),
        (annulus, (1.0, 1.0, 2, 8), r"annulus: inner_radius must be < outer_radius"),
        (annulus, (0.5, 1.0, 2, 1), r"annulus: n_circumferential must be an integer >= 3"),
        (annulus, (0.5, "1", 2, 8), r"annulus: outer_radius must be a finite number > 0"),
    ],
)
def test_polar_generators_reject_bad_arguments(generator, args, message):
    with pytest.raises(ValueError, match=message):
        generator(*args)


# -- mesh_size and element sets ----------------------------------------------------------------


def test_mesh_size_is_mean_edge_length():
    # 1 x 1 square in two triangles: four sides of 1 and one diagonal of sqrt(2)
    assert mesh_size(rectangle(1.0, 1.0, 1, 1)) == pytest.approx((4 + math.sqrt(2)) / 5)
    h = mesh_size(rectangle(2.0, 1.0, 4, 2))  # 0.5 squares: 22 sides, 8 diagonals
    assert h == pytest.approx((22 * 0.5 + 8 * 0.5 * math.sqrt(2)) / 30)


NODES = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])


def test_element_sets_stored_as_int64():
    mesh = Mesh(NODES, [[0, 1, 2], [0, 2, 3]], element_sets={"all": [0, 1], "none": []})
    assert mesh.element_sets["all"].dtype == np.int64
    assert mesh.element_sets["none"].size == 0
    assert Mesh(NODES, [[0, 1, 2]]).element_sets == {}


@pytest.mark.parametrize(
    "node_sets, element_sets, message",
    [
        ({}, {"patch": [0, 2]}, r"element set 'patch' refers to element 2 outside 0..1"),
        ({}, {"patch": [-1]}, r"element set 'patch' refers to element -1"),
        ({}, {"patch": [0.0]}, r"element set 'patch' must hold integer element indices"),
        ({}, {"patch": [[0, 1]]}, r"element set 'patch' must be a flat list"),
        ({"edge": [0, 4]}, {}, r"node set 'edge' refers to node 4 outside 0..3"),
    ],
)
def test_sets_are_checked(node_sets, element_sets, message):
    with pytest.raises(ValueError, match=message):
        Mesh(NODES, [[0, 1, 2], [0, 2, 3]], node_sets, element_sets)


def test_without_meshio_the_message_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "meshio", None)  # import meshio fails
    with pytest.raises(
        ImportError,
        match=r"meshio, which reads meshes and writes results, is missing: pip install meshio",
    ):
        read_mesh(tmp_path / "plate.msh")


# -- gmsh element data ($ElementData), read by element tag ----------------------------------

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "fibre_field"


def example_fibre(mesh: Mesh) -> np.ndarray:
    """The fibre field make_mesh.py writes, at the centroids of ``mesh``'s triangles, (n, 3)."""
    width = 0.2  # make_mesh.WIDTH
    x = mesh.nodes[mesh.triangles].mean(axis=1)[:, 0]
    angle = 0.25 * np.pi * x / width
    return np.column_stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)])


def test_gmsh_fibre_field_example_is_read_by_element_tag():
    path = EXAMPLE / "sheet.msh"
    assert path.stat().st_size < 200_000 and b"$ElementData" in path.read_bytes()
    mesh = read_mesh(path)
    assert set(mesh.cell_data) == {"fibre"}
    assert mesh.cell_data["fibre"].shape == (mesh.n_elements, 3)
    assert np.allclose(mesh.cell_data["fibre"], example_fibre(mesh), rtol=0, atol=1e-12)
    # the boundary lines still make the node sets, the surface the element set
    assert {"left", "right", "bottom", "top", "hole", "sheet"} <= set(mesh.node_sets)
    assert mesh.element_sets["sheet"].size == mesh.n_elements
    assert np.allclose(mesh.nodes[mesh.node_sets["left"], 0], 0.0)


def test_gmsh_fibre_field_example_runs():
    import wrinkle

    case = wrinkle.read_case(EXAMPLE / "sheet.toml")
    frame = case.model.discretise().geometry.frame
    assert np.allclose(frame[:, 0], example_fibre(case.model.mesh), atol=1e-12)  # A1 = fibre
    results = case.solve()
    assert results.final.load_factor == pytest.approx(1.0)


def _element_data_section(name: str, rows: list[tuple[int, list[float]]]) -> str:
    lines = [
        "$ElementData",
        "1",
        f'"{name}"',
        "1",
        "0.0",
        "3",
        "0",
        str(len(rows[0][1])),
        str(len(rows)),
    ]
    lines += [f"{tag} " + " ".join(repr(v) for v in values) for tag, values in rows]
    return "\n".join(lines + ["$EndElementData"]) + "\n"


def test_gmsh22_element_data_in_any_order_with_quads_and_lines(tmp_path):
    path = write_gmsh_groups(tmp_path)
    # meshio numbers the elements 1..6 in order: vertex, two lines, two triangles, the quad
    rows = [(6, [0.0, 1.0, 0.0]), (2, [9.0, 9.0, 9.0]), (5, [1.0, 1.0, 0.0]), (4, [1.0, 0.0, 0.0])]
    scalar = [(4, [0.5]), (5, [0.25]), (6, [2.0])]
    path.write_text(
        path.read_text()
        + _element_data_section("fibre", rows)
        + _element_data_section("weight", scalar)
    )
    mesh = read_mesh(path)
    assert mesh.n_elements == 4 and mesh.element_sets["patch"].tolist() == [2, 3]
    assert mesh.cell_data["fibre"].tolist() == [[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 1, 0]]
    assert mesh.cell_data["weight"].tolist() == [0.5, 0.25, 2.0, 2.0]  # one component: (n,)


def test_gmsh41_element_data_missing_triangle_is_named(tmp_path):
    path = tmp_path / "square.msh"
    # element 1 is the point, 2 the line, 3 and 4 the triangles
    path.write_text(GMSH41 + _element_data_section("fibre", [(3, [1.0, 0.0, 0.0])]))
    with pytest.raises(ValueError) as error:
        read_mesh(path)
    message = str(error.value)
    assert message == (
        f"mesh file {path}: gmsh element data 'fibre' has no value for the "
        "triangle with element tag 4: give every triangle of the mesh a value"
    )
    path.write_text(
        GMSH41
        + _element_data_section(
            "fibre", [(4, [0.0, 1.0, 0.0]), (2, [0.0, 0.0, 1.0]), (3, [1.0, 0.0, 0.0])]
        )
    )
    assert read_mesh(path).cell_data["fibre"].tolist() == [[1, 0, 0], [0, 1, 0]]


def test_gmsh_element_data_of_the_example_shuffled_and_partitioned(tmp_path):
    """The values are found by element tag, not by position; a view split in two sections
    of one time step (as gmsh writes partitions) is one field; a later step replaces it."""
    text = (EXAMPLE / "sheet.msh").read_text()
    head, rest = text.split("$ElementData\n")
    body, tail = rest.split("$EndElementData\n")
    lines = body.splitlines()
    header, entries = lines[:9], lines[9:]
    order = np.random.default_rng(1).permutation(len(entries))
    shuffled = [entries[i] for i in order]
    half = len(shuffled) // 2

    def section(rows: list[str], step: int = 0) -> str:
        # header: 1 string tag (the name), 1 real tag (the time), 4 integer tags (time step,
        # components, entries, partition)
        return (
            "\n".join(
                [
                    "$ElementData",
                    *header[:5],
                    str(step),
                    header[6],
                    str(len(rows)),
                    header[8],
                    *rows,
                    "$EndElementData",
                ]
            )
            + "\n"
        )

    path = tmp_path / "sheet.msh"
    path.write_text(head + section(shuffled[:half]) + section(shuffled[half:]) + tail)
    mesh = read_mesh(path)
    assert np.allclose(mesh.cell_data["fibre"], example_fibre(mesh), atol=1e-12)
    turned = [" ".join([line.split()[0], "0.0", "1.0", "0.0"]) for line in entries]
    path.write_text(head + section(shuffled) + section(turned, step=1) + tail)
    assert np.all(read_mesh(path).cell_data["fibre"] == [0.0, 1.0, 0.0])
    # a value missing: the message names the field and the element tag
    missing = shuffled[0].split()[0]
    path.write_text(head + section(shuffled[1:]) + tail)
    with pytest.raises(
        ValueError, match=f"'fibre' has no value for the triangle with element tag {missing}:"
    ):
        read_mesh(path)
    # twice the same element
    path.write_text(head + section(shuffled + shuffled[:1]) + tail)
    with pytest.raises(ValueError, match=f"gives element tag {missing} more than one value"):
        read_mesh(path)


def test_gmsh_element_data_in_a_binary_file_says_save_as_ascii(tmp_path):
    text = (EXAMPLE / "sheet.msh").read_text().replace("4.1 0 8", "4.1 1 8", 1)
    path = tmp_path / "sheet.msh"
    path.write_text(text)
    with pytest.raises(ValueError) as error:
        read_mesh(path)
    assert str(error.value) == (
        f"mesh file {path}: gmsh element data ($ElementData) is read from ASCII .msh files "
        "only: save the mesh as ASCII (gmsh option Mesh.Binary = 0)"
    )


def test_case_reads_a_gmsh_fibre_field_by_name(tmp_path):
    import wrinkle

    path = tmp_path / "case.toml"
    text = (EXAMPLE / "sheet.toml").read_text()
    path.write_text(
        text.replace('file = "sheet.msh"', f'file = "{EXAMPLE / "sheet.msh"}"').replace(
            'direction = "fibre"', 'direction = "fibres"'
        )
    )
    with pytest.raises(
        wrinkle.case.CaseError,
        match=r"\[material\]: 'direction' names cell "
        r"data 'fibres'.*fibre \(\d+, 3\)",
    ):
        wrinkle.read_case(path)


def test_write_mesh_round_trips_nodes_elements_sets_and_cell_data(tmp_path):
    """``write_mesh`` (gmsh 2.2 ASCII) read back by ``read_mesh``: the nodes and triangles
    in order, every node set and element set as the same nodes and elements, the cell data
    to the last digit."""
    import numpy as np

    from wrinkle.mesh import Mesh, cylinder, read_mesh, write_mesh

    base = cylinder(1.0, 2.0, 12, 4, 2)
    rng = np.random.default_rng(3)
    mesh = Mesh(
        base.nodes + 0.01,
        base.triangles,
        {**base.node_sets, "x == 0 and r > 0.5": np.array([0, 3, 5])},
        base.element_sets,
        {"fibre": rng.random((base.n_elements, 3)), "t": rng.random(base.n_elements)},
    )
    back = read_mesh(write_mesh(mesh, tmp_path / "found.msh"))
    np.testing.assert_array_equal(back.nodes, mesh.nodes)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    for name, nodes in mesh.node_sets.items():
        np.testing.assert_array_equal(back.node_sets[name], np.sort(nodes))
    for name, elements in mesh.element_sets.items():
        np.testing.assert_array_equal(back.element_sets[name], np.sort(elements))
    for name, values in mesh.cell_data.items():
        np.testing.assert_array_equal(back.cell_data[name], values)
