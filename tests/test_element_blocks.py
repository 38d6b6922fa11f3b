"""Block-wise evaluation of large meshes and the safeguards of the wrinkling solver.

``MembraneElements.evaluate`` evaluates meshes larger than one block block by block; the
results must not depend on the blocks. The wrinkling solver's fallback (angle search, then
Newton) must give the same state as the first-guess Newton, and failures must name elements
of the mesh.
"""

from __future__ import annotations

import numpy as np
import pytest

import wrinkle.compiled
import wrinkle.element
import wrinkle.wrinkling
from wrinkle import NeoHookean, StVenantKirchhoff, rectangle
from wrinkle.element import MembraneElements
from wrinkle.kinematics import element_coordinates, reference_geometry
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling, WrinklingError

MATERIALS = {
    "svk-transverse": StVenantKirchhoff.transversely_isotropic(
        E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1 / 2.6, thickness=1.0
    ),
    "neo-hookean-compressible": NeoHookean(mu=1.0, thickness=1.0, lmbda=3.0),
}


def mixed_case(material, divisions: int = 12):
    """Elements and current coordinates of a sheared, unevenly stretched square: taut near
    one corner, slack near the opposite one, wrinkled in between."""
    mesh = rectangle(1.0, 1.0, divisions, divisions)
    X, Y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    x = np.column_stack(
        [
            0.9 * X + 0.12 * X * X + 0.05 * Y,
            0.9 * Y + 0.12 * Y * Y,
            0.03 * np.sin(np.pi * X) * np.sin(np.pi * Y),
        ]
    )
    geometry = reference_geometry(mesh.nodes, mesh.triangles, fibre_angle=0.3)
    return MembraneElements(geometry, Wrinkling(material)), element_coordinates(x, mesh.triangles)


def _compare(a, b):
    np.testing.assert_array_equal(a.response.state, b.response.state)
    for name in ("forces", "energy", "deformation_gradient"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-13, atol=1e-15)
    for name in ("stress", "thickness", "wrinkle_parameter", "energy"):
        np.testing.assert_allclose(
            getattr(a.response, name), getattr(b.response, name), rtol=1e-13, atol=1e-15
        )
    if a.stiffness is not None:
        np.testing.assert_allclose(a.stiffness, b.stiffness, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(a.response.tangent, b.response.tangent, rtol=1e-13, atol=1e-14)


@pytest.mark.parametrize("name", MATERIALS)
@pytest.mark.parametrize("stiffness", [True, False])
def test_blocks_do_not_change_results(monkeypatch, name, stiffness):
    elements, x = mixed_case(MATERIALS[name])
    whole = elements.evaluate(x, stiffness=stiffness)
    counts = np.bincount(whole.response.state, minlength=3)
    assert counts[TAUT] > 0 and counts[WRINKLED] > 0 and counts[SLACK] > 0
    monkeypatch.setattr(wrinkle.element, "_BLOCK", 50)
    monkeypatch.setattr(wrinkle.element, "KERNEL_BLOCK", 16)
    blocks = elements.evaluate(x, stiffness=stiffness)
    assert (blocks.stiffness is None) == (not stiffness)
    _compare(blocks, whole)


def test_fallback_finds_the_same_wrinkled_state(monkeypatch):
    """A deliberately wrong first guess (the direction of the largest plain stress) sends
    elements through the angle search; the result must not change."""
    elements, x = mixed_case(MATERIALS["svk-transverse"])
    reference = elements.evaluate(x)
    minor = wrinkle.wrinkling._minor_direction_angle
    monkeypatch.setattr(
        wrinkle.wrinkling, "_minor_direction_angle", lambda T: minor(T) + 0.5 * np.pi
    )
    searched = []
    search = Wrinkling._angle_search

    def counting_search(self, e, *args):
        searched.append(e[0].size)
        return search(self, e, *args)

    monkeypatch.setattr(Wrinkling, "_angle_search", counting_search)
    fallback = elements.evaluate(x)
    assert sum(searched) > 0
    np.testing.assert_array_equal(fallback.response.state, reference.response.state)
    np.testing.assert_allclose(fallback.forces, reference.forces, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fallback.stiffness, reference.stiffness, rtol=1e-8, atol=1e-10)


@pytest.mark.skipif(not wrinkle.compiled.installed(), reason="numba not installed")
@pytest.mark.parametrize("matrices", [True, False])
def test_compiled_response_runs_in_one_block(monkeypatch, matrices):
    """With the compiled St Venant-Kirchhoff response the elements are evaluated in one
    block whatever the block size (the kernels make no temporaries), to the NumPy results;
    without matrices the result holds the material tangent and no element matrices."""
    elements, x = mixed_case(MATERIALS["svk-transverse"])
    reference = elements.evaluate(x)
    monkeypatch.setattr(wrinkle.element, "_BLOCK", 50)
    monkeypatch.setattr(wrinkle.element, "KERNEL_BLOCK", 16)
    compiled = MembraneElements(elements.geometry, elements.material, compiled=True)
    batches = []
    response = Wrinkling.response

    def counted(self, C, **options):
        batches.append(C.shape[0])
        return response(self, C, **options)

    monkeypatch.setattr(Wrinkling, "response", counted)
    result = compiled.evaluate(x, matrices=matrices)
    assert batches[0] == x.shape[0]
    assert (result.stiffness is None) == (not matrices)
    np.testing.assert_array_equal(result.response.state, reference.response.state)
    scale = np.abs(reference.forces).max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(
        result.response.tangent, reference.response.tangent, rtol=1e-12, atol=1e-14
    )
    if matrices:
        np.testing.assert_allclose(result.stiffness, reference.stiffness, rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("block", [None, 50])
def test_unsolved_wrinkling_names_mesh_elements(monkeypatch, block):
    elements, x = mixed_case(MATERIALS["svk-transverse"])
    wrinkled = np.flatnonzero(elements.evaluate(x).response.state == WRINKLED)
    if block is not None:
        monkeypatch.setattr(wrinkle.element, "_BLOCK", block)
    monkeypatch.setattr(wrinkle.wrinkling, "_NEWTON_ITERATIONS", 0)  # nothing converges
    with pytest.raises(WrinklingError) as failure:
        elements.evaluate(x)
    np.testing.assert_array_equal(np.sort(failure.value.elements), wrinkled)


def test_empty_batch():
    r = Wrinkling(MATERIALS["svk-transverse"]).response(np.empty((0, 2, 2)))
    assert r.stress.shape == (0, 2, 2) and r.tangent.shape == (0, 3, 3)
    assert r.state.shape == r.energy.shape == (0,)
