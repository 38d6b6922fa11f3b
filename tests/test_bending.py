"""The bending energy of the mean surface (wrinkle.bending): the bending energy of a sheet
rolled into a cylinder (closed form, any direction on the mesh), rigid motions free, forces
and tangent as derivatives of the energy, the Navier solution of a simply supported plate, and
the model and case-file interfaces."""

from pathlib import Path

import numpy as np
import pytest

from wrinkle import Model, StVenantKirchhoff
from wrinkle.bending import Bending, bending_stiffness, plate_bending_stiffness
from wrinkle.case import CaseError, read_case
from wrinkle.mesh import Mesh, boundary_nodes, disk, rectangle, sphere

ROOT = Path(__file__).resolve().parents[1]


def rolled(mesh: Mesh, radius: float, angle: float) -> np.ndarray:
    """Displacements (n_dofs,) that roll the flat mesh onto a cylinder of ``radius`` whose
    axis lies in the plane at ``angle`` to y: an isometry, with curvatures 1/radius and 0."""
    across = np.array([np.cos(angle), np.sin(angle), 0.0])
    along = np.array([-np.sin(angle), np.cos(angle), 0.0])
    s, w = mesh.nodes @ across, mesh.nodes @ along
    x = (
        np.outer(radius * np.sin(s / radius), across)
        + np.outer(w, along)
        + np.outer(radius * (1 - np.cos(s / radius)), [0.0, 0.0, 1.0])
    )
    return (x - mesh.nodes).ravel()


def interior_area(mesh: Mesh) -> float:
    """Sum of the lumped areas (a third of each adjacent triangle) of the interior nodes."""
    p = mesh.nodes[mesh.triangles]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    nodal = np.bincount(mesh.triangles.ravel(), np.repeat(area / 3, 3), minlength=mesh.n_nodes)
    return float(nodal[~boundary_nodes(mesh)].sum())


@pytest.mark.parametrize("angle", [0.0, 0.4, np.pi / 4])
def test_rolled_sheet_has_the_cylinders_bending_energy(angle):
    """W = (D/2) (1/R)^2 times the area the interior nodes stand for, whatever the direction
    of the axis on the structured mesh; the error falls with the mesh (the cotangent Laplacian
    of a smooth field is second-order accurate)."""
    radius, D = 2.0, 3.0
    errors = []
    for n in (16, 32):
        mesh = rectangle(1.0, 1.0, n, n)
        energy = Bending(mesh, D).energy(rolled(mesh, radius, angle))
        expected = 0.5 * D / radius**2 * interior_area(mesh)
        errors.append(abs(energy / expected - 1))
    assert errors[1] < 2e-3
    assert errors[1] < 0.5 * errors[0]


def test_unstructured_disk_rolled():
    mesh = disk(1.0, 16, 64)
    energy = Bending(mesh, 1.0).energy(rolled(mesh, 3.0, 0.3))
    assert energy == pytest.approx(0.5 / 9.0 * interior_area(mesh), rel=2e-2)


def test_rigid_motions_and_stretches_cost_nothing():
    """Every affine map of a flat sheet, a large rotation included, has zero bending energy."""
    mesh = disk(1.0, 6, 24)
    bending = Bending(mesh, 1.0)
    c, s = np.cos(1.0), np.sin(1.0)
    rotation = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.array(
        [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    )
    stretch = np.diag([1.3, 0.8, 1.0]) + np.array([[0, 0.2, 0], [0, 0, 0], [0.1, 0, 0]])
    scale = bending.energy(rolled(mesh, 1.0, 0.0))
    for linear in (rotation, stretch):
        u = (mesh.nodes @ linear.T + [0.3, -1.0, 2.0] - mesh.nodes).ravel()
        assert abs(bending.energy(u)) < 1e-9 * scale  # round-off of u^T Q u


def test_forces_are_the_energy_gradient():
    mesh = disk(1.0, 4, 16)
    bending = Bending(mesh, 2.5)
    rng = np.random.default_rng(3)
    u, direction = rng.normal(size=(2, 3 * mesh.n_nodes)) * 0.1
    h = 1e-6
    slope = (bending.energy(u + h * direction) - bending.energy(u - h * direction)) / (2 * h)
    assert bending.forces(u) @ direction == pytest.approx(slope, rel=1e-7)


def test_model_tangent_is_the_derivative_of_the_residual():
    """Membrane, bending and a follower pressure together: the assembled tangent against a
    central difference of the residual, and the energy's slope against the residual."""
    mesh = rectangle(1.0, 1.0, 4, 4)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=100.0, nu=0.3, thickness=0.05))
    model.add_bending(2.0)
    model.add_pressure(3.0)
    model.fix("x == 0 or x == 1 or y == 0 or y == 1", "z")
    model.fix("x == 0 and y == 0", ["x", "y"])
    model.fix("x == 1 and y == 0", ["y"])
    system = model.discretise()
    rng = np.random.default_rng(7)
    u = 0.05 * rng.normal(size=model.n_dofs) * ~model.constrained
    u[2::3] += 0.1 * np.sin(np.pi * mesh.nodes[:, 0]) * np.sin(np.pi * mesh.nodes[:, 1])
    ev = system.evaluate(u)
    free = ~model.constrained
    h = 1e-7
    direction = rng.normal(size=model.n_dofs) * free
    plus, minus = system.evaluate(u + h * direction), system.evaluate(u - h * direction)
    assert plus.states == minus.states == ev.states
    derivative = -(plus.residual - minus.residual) / (2 * h)  # residual = f - f*
    assert np.allclose((ev.tangent @ direction)[free], derivative[free], rtol=1e-5, atol=1e-7)
    slope = (plus.energy - minus.energy) / (2 * h)
    assert -ev.residual @ direction == pytest.approx(slope, rel=1e-6)


def test_simply_supported_plate_matches_navier():
    """A simply supported square plate under a uniform pressure small enough that the sheet
    works in bending alone (deflection 10^-3 of the thickness): centre deflection
    w = alpha p a^4 / D with Navier's double series alpha = 16 / pi^6 sum over odd m, n of
    (-1)^((m + n) / 2 - 1) / (m n (m^2 + n^2)^2) = 0.0040624 (Timoshenko & Woinowsky-Krieger,
    Theory of Plates and Shells, 1959, section 30 and table 8: 0.00406). Measured: -4.5e-4,
    -1.1e-4, -2.9e-5 on 16, 32, 64 squares a side (second order)."""
    odd = np.arange(1, 400, 2)
    m, n = np.meshgrid(odd, odd)
    signs = (-1.0) ** ((m + n) // 2 - 1)
    alpha = 16 / np.pi**6 * np.sum(signs / (m * n * (m**2 + n**2) ** 2))
    assert alpha == pytest.approx(0.00406, abs=5e-6)
    a, E, nu, t = 1.0, 1e6, 0.3, 0.01
    D = plate_bending_stiffness(E, nu, t)
    p = 1e-3 * t * D / (alpha * a**4)
    mesh = rectangle(a, a, 32, 32)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=t))
    model.add_bending()
    model.add_pressure(p)
    model.fix("x == 0 or x == 1 or y == 0 or y == 1", ["x", "y", "z"])
    results = model.solve(tolerance=1e-10)
    centre = np.flatnonzero((mesh.nodes[:, 0] == 0.5) & (mesh.nodes[:, 1] == 0.5))
    w = results.final.displacement.reshape(-1, 3)[centre, 2].item()
    assert w == pytest.approx(alpha * p * a**4 / D, rel=2e-4)
    # the supports carry the load
    assert results.final.reactions[2::3].sum() == pytest.approx(-p * a**2, rel=1e-6)


def test_bending_stiffness_of_the_materials():
    svk = StVenantKirchhoff.isotropic(E=588e6, nu=0.4, thickness=0.6e-3)
    assert bending_stiffness(svk) == pytest.approx(plate_bending_stiffness(588e6, 0.4, 0.6e-3))


def test_bad_requests_are_refused():
    with pytest.raises(ValueError, match="flat reference meshes only"):
        Model(sphere(1.0, 4)).add_bending(1.0)
    model = Model(rectangle(1.0, 1.0, 2, 2))
    with pytest.raises(ValueError, match="element 0 has no material"):
        model.add_bending()
    with pytest.raises(ValueError, match="finite and >= 0"):
        model.add_bending(-1.0)


def test_case_key(tmp_path):
    source = ROOT / "examples" / "airbag.toml"
    case = read_case(source, {"material": {"bending": True}})
    assert np.allclose(case.model.bending, plate_bending_stiffness(588e6, 0.4, 0.6e-3))
    assert np.allclose(read_case(source, {"material": {"bending": 0.5}}).model.bending, 0.5)
    assert not np.any(read_case(source, {"material": {"bending": False}}).model.bending)
    for value, message in [(-1.0, ">= 0"), ("yes", "true, false or a number")]:
        with pytest.raises(CaseError, match=rf"\[material\].*bending.*{message}"):
            read_case(source, {"material": {"bending": value}})
    sphere_case = ROOT / "verification" / "cases" / "sphere.toml"
    with pytest.raises(CaseError, match=r"\[material\].*flat reference meshes only"):
        read_case(sphere_case, {"material": {"bending": True}})


@pytest.mark.slow
def test_airbag_with_bending():
    """The airbag of examples/airbag.toml with the sheet's own bending stiffness, from the
    flat sheet: fewer iterations than without (measured 24 against 32 on 2,048 elements) and
    a centre deflection that moves by less than the spread of the membrane's equilibria
    (1 mm on this mesh, docs/notes/2026-12-airbag-iteration-growth.md)."""
    source = ROOT / "examples" / "airbag.toml"
    membrane = read_case(source).solve().final
    case = read_case(source, {"material": {"bending": True}})
    bent = case.solve().final
    centre = case.probes["centre"]
    assert bent.iterations < membrane.iterations
    w = {
        k: s.displacement.reshape(-1, 3)[centre, 2].mean()
        for k, s in [("m", membrane), ("b", bent)]
    }
    assert abs(w["b"] - w["m"]) < 1e-3
