"""Tension-only cables (issue 21, item 2; ``wrinkle.cables``): the segment's forces are the
gradient of its energy and its tangent their derivative (central differences), a slack
segment carries nothing, the prestress is the force at the reference length; the cable's
edges are found along the mesh and an unconnected selection is refused; a strip pulled with
a cable along its edge carries the closed-form sum of the sheet's and the cable's forces."""

import json

import meshio
import numpy as np
import pytest

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.cables import Cables, cable_edges
from wrinkle.case import read_case
from wrinkle.cli import main


def two_segments(prestress: float = 0.0) -> tuple[Cables, np.ndarray]:
    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.5, 0.0]])
    edges = np.array([[0, 1], [1, 2]])
    length = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
    cables = Cables(
        edges, length, np.array([100.0, 100.0]), np.full(2, prestress), np.zeros(2, int), ("c",)
    )
    return cables, nodes


@pytest.mark.parametrize("prestress", [0.0, 7.0])
def test_forces_are_the_energys_gradient_and_the_tangent_their_derivative(prestress):
    """Both segments taut (stretched by a random motion): forces against central differences
    of the energy, the tangent against central differences of the forces, to 1e-7."""
    cables, nodes = two_segments(prestress)
    rng = np.random.default_rng(2)
    x = nodes * [1.05, 1.02, 1.0] + 0.01 * rng.normal(size=nodes.shape)
    state = cables.state(x)
    assert state.taut.all()
    h = 1e-6
    for dof in range(9):
        e = np.zeros(9)
        e[dof] = h
        up = cables.state(x + e.reshape(3, 3), tangent=False)
        down = cables.state(x - e.reshape(3, 3), tangent=False)
        assert state.forces[dof] == pytest.approx(
            (up.energy - down.energy) / (2 * h), rel=1e-7, abs=1e-9
        )
        column = (up.forces - down.forces) / (2 * h)
        assembled = np.zeros(9)
        for s, (a, b) in enumerate(cables.edges):
            dofs = np.r_[3 * a : 3 * a + 3, 3 * b : 3 * b + 3]
            if dof in dofs:
                assembled[dofs] += state.blocks[s][:, list(dofs).index(dof)]
        np.testing.assert_allclose(assembled, column, rtol=1e-6, atol=1e-6)


def test_a_shortened_segment_is_slack_and_the_prestress_is_the_force_at_rest():
    cables, nodes = two_segments(prestress=7.0)
    at_rest = cables.state(nodes)
    np.testing.assert_allclose(at_rest.axial, 7.0, rtol=1e-14)
    shortened = cables.state(nodes * [0.9, 0.9, 1.0])  # 10 % shorter: 7 - 100 * 0.1 < 0
    assert not shortened.taut.any()
    assert np.all(shortened.axial == 0.0) and np.all(shortened.blocks == 0.0)
    assert shortened.energy == 0.0 and not np.any(shortened.forces)


def test_cable_edges_follow_the_mesh_and_refuse_unconnected_nodes():
    mesh = rectangle(2.0, 1.0, 4, 2)
    bottom = np.flatnonzero(mesh.nodes[:, 1] == 0.0)
    edges = cable_edges(mesh.triangles, bottom, mesh.n_nodes)
    assert edges.shape == (4, 2)
    corners = np.flatnonzero(np.isin(mesh.nodes[:, 0], [0.0, 2.0]) & (mesh.nodes[:, 1] == 0.0))
    with pytest.raises(ValueError, match="not connected|share no element edge"):
        cable_edges(mesh.triangles, corners, mesh.n_nodes)
    left_and_right = np.flatnonzero(np.isin(mesh.nodes[:, 0], [0.0, 2.0]))
    with pytest.raises(ValueError, match="separate pieces"):
        cable_edges(mesh.triangles, left_and_right, mesh.n_nodes)


def strip(EA: float, prestress: float, stretch: float, nx: int = 8):
    """A strip 2 x 0.5 (SVK, E t = 1e3, nu = 0) with a cable along its edge y = 0.5, its end
    x = 0 held in x (and one node in y), x = 2 moved to the stretch; z held."""
    mesh = rectangle(2.0, 0.5, nx, 2)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=1e4, nu=0.0, thickness=0.1))
    model.fix("x == 0", "x", label="left")
    model.fix("x == 0 and y == 0", "y")
    model.fix("z == 0", "z")
    model.prescribe("x == 2", (2.0 * (stretch - 1.0), np.nan, np.nan), label="right")
    model.add_cables("y == 0.5", EA=EA, prestress=prestress, label="edge")
    return model


@pytest.mark.parametrize("EA, prestress", [(300.0, 0.0), (300.0, 20.0)])
def test_a_pulled_strip_carries_the_sheets_and_the_cables_forces(EA, prestress):
    """Uniaxial stretch lambda with nu = 0: the sheet's first Piola force E t W lambda
    (lambda^2 - 1) / 2 (St Venant-Kirchhoff, width W) plus the cable's N0 + EA (lambda - 1)
    is the reaction of the pulled end, to 1e-9; the cable is uniform and taut."""
    stretch = 1.1
    model = strip(EA, prestress, stretch)
    final = model.solve(steps=2, tolerance=1e-11).final
    reaction = model.support_reactions(final.reactions)["right"][0]
    sheet = 1e3 * 0.5 * stretch * (stretch**2 - 1.0) / 2.0
    cable = prestress + EA * (stretch - 1.0)
    assert reaction == pytest.approx(sheet + cable, rel=1e-9)
    state = model.discretise().cable_state(final.displacement)
    np.testing.assert_allclose(state.axial, cable, rtol=1e-9)
    assert state.taut.all()


CASE = """
[mesh]
rectangle = {width = 2.0, height = 0.5, nx = 8, ny = 2}

[material]
model = "svk"
E = 1.0e4
nu = 0.0
thickness = 0.1

[[support]]
label = "left"
nodes = "x == 0"
fix = ["x"]

[[support]]
nodes = "x == 0 and y == 0"
fix = ["y"]

[[support]]
nodes = "z == 0"
fix = ["z"]

[[support]]
label = "right"
nodes = "x == 2"
displacement = [0.2, "free", "free"]

[[cable]]
label = "edge"
nodes = "y == 0.5"
EA = 300.0
prestress = 20.0
"""


def test_a_case_with_a_cable_writes_its_forces(tmp_path, capsys):
    """[[cable]] in a case file: summary.json reports the cable's forces under "cables" and
    the .vtu holds the segments as line cells with their axial force."""
    path = tmp_path / "strip.toml"
    path.write_text(CASE)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    edge = summary["steps"][-1]["cables"]["edge"]
    assert edge["min_force"] == pytest.approx(20.0 + 300.0 * 0.1, rel=1e-6)
    assert edge["slack_segments"] == 0
    vtu = meshio.read(tmp_path / "out" / "step_0001.vtu")
    lines = vtu.cells_dict["line"]
    assert lines.shape == (8, 2)
    force = vtu.cell_data_dict["cable_force"]["line"]
    np.testing.assert_allclose(force, 50.0, rtol=1e-6)
    case = read_case(path)
    assert [cable.label for cable in case.model.cables] == ["edge"]
