"""A closed tube (``[mesh] cylinder``) under internal pressure: an isotropic material needs no
fibre direction (the end caps are perpendicular to the default x), an anisotropic one without
a projectable direction is refused where it is read, naming the key to set.

Closed form of a thin closed tube of radius R under pressure p, away from its ends: hoop
resultant N_theta = p R, axial resultant N_x = p R / 2. The mesh's wall is the prism on the
inscribed polygon of n sides; by equilibrium of a node of the polygon (two sides of length
2 R sin(pi/n), each carrying p times its length) and of a cut through the tube (the cap force
p n/2 sin(2 pi/n) R^2 over the perimeter 2 n R sin(pi/n)), that faceted tube carries exactly
cos(pi/n) times both values (1.9 % less for n = 16). What remains is the disturbance of the
caps (they bulge and wrinkle; mid-length is two radii from them) and the change of geometry,
of the order of the strain p R / (E t) = 1e-4: well within 0.5 % of the polygon's values.
The ring means are compared (element by element the axial resultant scatters with the
direction of the triangles' diagonals; the mean over a ring is what equilibrium fixes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import wrinkle
from wrinkle import Model
from wrinkle.case import CaseError
from wrinkle.materials import StVenantKirchhoff
from wrinkle.post import element_report

RADIUS, LENGTH, N_CIRCUMFERENTIAL, N_AXIAL, N_CAP = 0.1, 0.4, 16, 8, 3
E, NU, THICKNESS, PRESSURE = 1e6, 0.3, 1e-3, 1.0  # strain p R / (E t) = 1e-4

MESH = (
    f"cylinder = {{radius = {RADIUS}, length = {LENGTH}, "
    f"n_circumferential = {N_CIRCUMFERENTIAL}, n_axial = {N_AXIAL}, n_cap = {N_CAP}}}"
)
# the rigid-body motions held without restraining the free expansion of the tube: the root
# cap's centre, the tip cap's centre across the axis, and z on the half-line y > 0, z = 0
SUPPORTS = f"""
[[support]]
nodes = "x == 0 and y == 0 and z == 0"
fix = ["x", "y", "z"]

[[support]]
nodes = "x == {LENGTH} and y == 0 and z == 0"
fix = ["y", "z"]

[[support]]
nodes = "x == 0 and z == 0 and y > 0"
fix = ["z"]

[[load]]
kind = "pressure"
value = {PRESSURE}

[solver]
steps = 2
"""


def write_case(tmp_path: Path, material: str) -> Path:
    path = tmp_path / "tube.toml"
    path.write_text(
        f'title = "pressurised tube"\n\n[mesh]\n{MESH}\n\n[material]\n{material}\n' + SUPPORTS
    )
    return path


ISOTROPIC = f'model = "svk"\nE = {E}\nnu = {NU}\nthickness = {THICKNESS}'
ANISOTROPIC = (
    f'model = "svk-transverse"\nE_L = {5 * E}\nE_T = {E}\nnu_LT = 0.3\n'
    f"nu_TT = 0.3\nG_LT = {E / 2.6}\nthickness = {THICKNESS}"
)


def test_isotropic_tube_without_direction_solves_to_the_closed_form(tmp_path):
    case = wrinkle.read_case(write_case(tmp_path, ISOTROPIC))
    model = case.model
    geometry = model.discretise().geometry
    frame, normal = geometry.frame, geometry.normal
    assert np.allclose(np.einsum("nai,nbi->nab", frame, frame), np.eye(2), atol=1e-14)
    assert np.allclose(np.einsum("nai,ni->na", frame, normal), 0.0, atol=1e-14)
    wall = model.mesh.element_sets["wall"]
    assert np.allclose(frame[wall, 0], [1.0, 0.0, 0.0])  # the default direction, projectable
    for cap in ("root_cap", "tip_cap"):  # one frame for all elements of a flat cap
        caps = model.mesh.element_sets[cap]
        assert np.allclose(frame[caps, 0], [0.0, 1.0, 0.0])

    results = case.solve()
    assert results.final.load_factor == pytest.approx(1.0)
    report = element_report(model, results.final.displacement)
    centroid = model.mesh.nodes[model.mesh.triangles].mean(axis=1)
    mid = wall[np.abs(centroid[wall, 0] - LENGTH / 2) < LENGTH / N_AXIAL]
    assert mid.size == 2 * 2 * N_CIRCUMFERENTIAL  # the two rings of elements at mid-length
    axial = report.stress[mid, 0, 0].mean()  # A1 = x on the wall, A2 round the tube
    hoop = report.stress[mid, 1, 1].mean()
    facets = np.cos(np.pi / N_CIRCUMFERENTIAL)
    assert hoop == pytest.approx(facets * PRESSURE * RADIUS, rel=5e-3)
    assert axial == pytest.approx(facets * PRESSURE * RADIUS / 2, rel=5e-3)
    assert hoop == pytest.approx(PRESSURE * RADIUS, rel=2.5e-2)
    assert axial == pytest.approx(PRESSURE * RADIUS / 2, rel=2.5e-2)


def test_anisotropic_tube_without_direction_fails_when_read(tmp_path):
    path = write_case(tmp_path, ANISOTROPIC)
    with pytest.raises(CaseError) as error:
        wrinkle.read_case(path)
    message = str(error.value)
    assert message.startswith(f"{path}: [material]: ")
    assert "perpendicular to element" in message and "direction = [dx, dy, dz]" in message
    assert "\n" not in message
    # a direction with a component in every element's plane is accepted
    fixed = ANISOTROPIC + "\ndirection = [1.0, 1.0, 1.0]"
    wrinkle.read_case(write_case(tmp_path, fixed)).model.discretise()


def test_assign_material_checks_the_fibre_frame_of_its_elements():
    mesh = wrinkle.cylinder(RADIUS, LENGTH, N_CIRCUMFERENTIAL, N_AXIAL, N_CAP)
    anisotropic = StVenantKirchhoff.transversely_isotropic(
        E_L=5 * E, E_T=E, nu_LT=0.3, nu_TT=0.3, G_LT=E / 2.6, thickness=THICKNESS
    )
    isotropic = StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS)
    first_cap_element = int(mesh.element_sets["root_cap"][0])
    with pytest.raises(ValueError, match=f"perpendicular to element {first_cap_element} "):
        Model(mesh, anisotropic)
    # the wall takes the anisotropic material along x, the caps an isotropic one
    model = Model(mesh)
    model.assign_material(anisotropic, "wall")
    model.assign_material(isotropic, "root_cap")
    model.assign_material(isotropic, "tip_cap")
    frame = model.discretise().geometry.frame
    assert np.allclose(np.einsum("nai,nbi->nab", frame, frame), np.eye(2), atol=1e-14)
    # an element number in the message is the mesh's, also for a region
    with pytest.raises(ValueError, match=f"perpendicular to element {first_cap_element + 1} "):
        model.assign_material(anisotropic, mesh.element_sets["root_cap"][1:])
