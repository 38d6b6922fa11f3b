"""Uniform refinement (wrinkle.refinement): counts, areas and orientation, the named sets and
cell data carried along, exact interpolation of linear fields, and a refined case solved to
the closed form it had before."""

from pathlib import Path

import numpy as np
import pytest

from wrinkle.case import CaseError, read_case
from wrinkle.mesh import Mesh, disk, rectangle
from wrinkle.refinement import MAX_REFINED_ELEMENTS, refine, refined

ROOT = Path(__file__).resolve().parents[1]


def signed_areas(mesh: Mesh) -> np.ndarray:
    p = mesh.nodes[mesh.triangles]
    return 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]


@pytest.mark.parametrize("mesh", [rectangle(1.0, 2.0, 3, 2), disk(1.0, 3, 12)])
def test_counts_areas_and_orientation(mesh):
    fine = refine(mesh).mesh
    n_edges = (3 * mesh.n_elements + np.count_nonzero(_boundary_edges(mesh))) // 2
    assert fine.n_elements == 4 * mesh.n_elements
    assert fine.n_nodes == mesh.n_nodes + n_edges
    assert np.array_equal(fine.nodes[: mesh.n_nodes], mesh.nodes)  # coarse numbers kept
    coarse, children = signed_areas(mesh), signed_areas(fine).reshape(-1, 4)
    assert np.all(children > 0)  # counter-clockwise, as the parents
    assert np.allclose(children, coarse[:, None] / 4)  # midpoint split: four equal areas


def _boundary_edges(mesh: Mesh) -> np.ndarray:
    pairs = np.sort(mesh.triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    _, counts = np.unique(pairs, axis=0, return_counts=True)
    return counts == 1


def test_sets_and_cell_data_follow():
    mesh = rectangle(1.0, 1.0, 2, 2)
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    mesh.node_sets["seam"] = np.flatnonzero((x == 1.0) | (y == 1.0))  # two lines, a corner
    mesh.node_sets["region"] = np.flatnonzero(x <= 0.5)  # interior nodes too
    mesh.element_sets["first"] = np.array([0, 3])
    mesh.cell_data["angle"] = np.arange(mesh.n_elements, dtype=float)
    fine = refine(mesh).mesh
    fx, fy = fine.nodes[:, 0], fine.nodes[:, 1]
    # exactly the nodes on the two lines: the midpoint of the corner's diagonal is not added
    assert set(fine.node_sets["seam"]) == set(np.flatnonzero((fx == 1.0) | (fy == 1.0)))
    assert set(fine.node_sets["right"]) == set(np.flatnonzero(fx == 1.0))
    assert set(fine.node_sets["region"]) == set(np.flatnonzero(fx <= 0.5))
    assert fine.element_sets["first"].tolist() == [0, 1, 2, 3, 12, 13, 14, 15]
    assert np.array_equal(fine.cell_data["angle"], np.repeat(np.arange(8.0), 4))


def test_prolong_is_exact_for_linear_fields():
    mesh = disk(1.0, 2, 8)
    refinement = refine(mesh)
    field = mesh.nodes @ np.array([[1.0, -2.0], [0.5, 3.0], [0.0, 0.0]]) + [0.25, -1.0]
    fine_field = refinement.mesh.nodes @ np.array([[1.0, -2.0], [0.5, 3.0], [0.0, 0.0]])
    assert np.allclose(refinement.prolong(field), fine_field + [0.25, -1.0], atol=1e-14)


def test_refined_times_and_limits():
    mesh = rectangle(1.0, 1.0, 1, 1)
    assert refined(mesh, 0) is mesh
    assert refined(mesh, 3).n_elements == 2 * 4**3
    with pytest.raises(ValueError, match="at most"):
        refined(mesh, 20)
    with pytest.raises(ValueError, match=">= 0"):
        refined(mesh, -1)
    assert MAX_REFINED_ELEMENTS >= 10**6


def test_case_key(tmp_path):
    """[mesh] refine on the shear-stretch square (examples/shear_stretch.toml): the refined
    mesh has 4^k times the elements, and the homogeneous deformation's edge force F1 is the
    one the coarse mesh gives (the field is uniform, so every mesh is exact)."""
    source = ROOT / "examples" / "shear_stretch.toml"
    coarse = read_case(source)
    fine = read_case(source, {"mesh": {"refine": 2}})
    assert fine.model.mesh.n_elements == 16 * coarse.model.mesh.n_elements
    for key, where in [(-1, ">= 0"), (1.5, "integer"), (True, "integer")]:
        with pytest.raises(CaseError, match=rf"\[mesh\].*refine.*{where}"):
            read_case(source, {"mesh": {"refine": key}})
    reaction = {}
    for name, case in [("coarse", coarse), ("fine", fine)]:
        results = case.solve()
        reaction[name] = results.final.reactions.reshape(-1, 3)
    top = {
        name: case.model.mesh.nodes[:, 1] == case.model.mesh.nodes[:, 1].max()
        for name, case in [("coarse", coarse), ("fine", fine)]
    }
    f_coarse = reaction["coarse"][top["coarse"], 0].sum()
    f_fine = reaction["fine"][top["fine"], 0].sum()
    assert f_fine == pytest.approx(f_coarse, rel=1e-9)
