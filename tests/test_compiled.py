"""Compiled kernels (``wrinkle.compiled``, Numba) against the NumPy formulas they replace: the
element stiffness against ``element.element_stiffness`` with ``strain_displacement``, the
scatter against ``np.bincount``, the pressure stiffness against
``loads.subtract_pressure_stiffness``, the nodal forces against ``element.nodal_forces``, the
pressure forces against ``loads.pressure_forces`` summed by ``np.bincount``, the wrinkled
tangent against ``Wrinkling._wrinkled_tangent`` (these four bit for bit), a whole evaluation
of the airbag (forces, stiffness, energy) with and without them, and the rule that chooses
them. Skipped where Numba is not installed, except the rule."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wrinkle import compiled
from wrinkle.case import read_case
from wrinkle.element import element_stiffness, nodal_forces, strain_displacement
from wrinkle.loads import pressure_forces, subtract_pressure_stiffness
from wrinkle.materials import StVenantKirchhoff
from wrinkle.wrinkling import Wrinkling

needs_numba = pytest.mark.skipif(not compiled.installed(), reason="numba not installed")
AIRBAG = Path(__file__).resolve().parents[1] / "examples" / "airbag.toml"


def random_element_data(m: int, seed: int = 0):
    """area (m,), F (m, 3, 2), shape gradients (m, 3, 2), an unsymmetric tangent (m, 3, 3),
    a symmetric stress (m, 2, 2), all random."""
    rng = np.random.default_rng(seed)
    stress = rng.normal(size=(m, 2, 2))
    return (
        rng.uniform(0.1, 1.0, m),
        rng.normal(size=(m, 3, 2)),
        rng.normal(size=(m, 3, 2)),
        rng.normal(size=(m, 3, 3)),
        stress + stress.transpose(0, 2, 1),
    )


@needs_numba
def test_element_stiffness_equals_numpy_formula():
    area, F, grad, tangent, stress = random_element_data(257)
    expected = element_stiffness(area, strain_displacement(F, grad), tangent, grad, stress)
    out = np.full((257, 9, 9), np.nan)
    compiled.element_stiffness(area, F, grad, tangent, stress, out)
    np.testing.assert_allclose(out, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


@needs_numba
@pytest.mark.parametrize("index_type", [np.int32, np.int64])
def test_scatter_sums_repeated_positions_like_bincount(index_type):
    rng = np.random.default_rng(2)
    positions = rng.integers(0, 300, size=(50, 81)).astype(index_type)  # many repeats
    matrices = rng.normal(size=(50, 9, 9))
    data = rng.normal(size=300)
    expected = data + np.bincount(positions.ravel(), matrices.ravel(), minlength=300)
    compiled.scatter_add(data, positions, matrices)
    np.testing.assert_allclose(data, expected, rtol=1e-13, atol=1e-12)


def test_used_on_large_meshes_unless_switched(monkeypatch):
    monkeypatch.delenv("WRINKLE_NUMBA", raising=False)
    assert not compiled.enabled(compiled.MIN_ELEMENTS - 1)
    assert compiled.enabled(compiled.MIN_ELEMENTS) == compiled.installed()
    monkeypatch.setenv("WRINKLE_NUMBA", "1")
    assert compiled.enabled(10) == compiled.installed()
    monkeypatch.setenv("WRINKLE_NUMBA", "0")
    assert not compiled.enabled(10**6)


@needs_numba
def test_airbag_evaluation_same_with_and_without_compiled_kernels(monkeypatch):
    """Forces, assembled stiffness and energy of the airbag partly inflated (taut, wrinkled
    and slack elements, follower pressure) agree to round-off."""
    model = read_case(AIRBAG, overrides={"mesh": {"rectangle": {"nx": 8, "ny": 8}}}).model
    X = model.mesh.nodes
    side = X[:, 0].max()
    bulge = 0.05 * np.cos(0.5 * np.pi * X[:, 0] / side) * np.cos(0.5 * np.pi * X[:, 1] / side)
    u = np.column_stack([-0.01 * X[:, 0], -0.005 * X[:, 1] ** 2, bulge]).ravel()
    u[model.constrained] = 0.0
    evaluations = {}
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)  # the kernels are chosen by the system
        model.assign_material(model.materials[0])  # a change: the model is discretised anew
        evaluations[switch] = model.discretise().at(1.0).evaluate(u)
    numpy_ev, compiled_ev = evaluations["0"], evaluations["1"]
    taut, wrinkled, slack = compiled_ev.states
    assert taut > 0 and wrinkled > 0 and slack > 0, compiled_ev.states
    np.testing.assert_allclose(
        compiled_ev.residual,
        numpy_ev.residual,
        rtol=0,
        atol=1e-12 * np.abs(numpy_ev.residual).max(),
    )
    K, K_numpy = compiled_ev.stiffness, numpy_ev.stiffness
    np.testing.assert_array_equal(K.indices, K_numpy.indices)
    np.testing.assert_allclose(
        K.data, K_numpy.data, rtol=0, atol=1e-12 * np.abs(K_numpy.data).max()
    )
    assert compiled_ev.energy == pytest.approx(numpy_ev.energy, rel=1e-13)


@needs_numba
def test_pressure_stiffness_equals_numpy_loop():
    rng = np.random.default_rng(5)
    x, pressure = rng.normal(size=(33, 3, 3)), rng.uniform(0.5, 2.0, 33)
    K = rng.normal(size=(33, 9, 9))
    expected = K.copy()
    subtract_pressure_stiffness(expected, x, pressure)
    compiled.subtract_pressure_stiffness(K, x, pressure)
    np.testing.assert_array_equal(K, expected)


@needs_numba
def test_nodal_forces_equal_numpy_loop():
    area, F, grad, _, stress = random_element_data(257, seed=3)
    expected = nodal_forces(area, F, grad, stress, np.empty((257, 9)))
    out = np.full((257, 9), np.nan)
    compiled.nodal_forces(area, F, grad, stress, out)
    np.testing.assert_array_equal(out, expected)


@needs_numba
def test_pressure_forces_summed_like_bincount():
    rng = np.random.default_rng(9)
    x, pressure = rng.normal(size=(40, 3, 3)), rng.uniform(0.5, 2.0, 40)
    dofs = (3 * rng.integers(0, 12, size=(40, 3))[:, :, None] + np.arange(3)).reshape(40, 9)
    f, _ = pressure_forces(x, pressure, stiffness=False)
    expected = np.zeros(36) + np.bincount(dofs.ravel(), f.ravel(), minlength=36)
    forces = np.zeros(36)
    compiled.add_pressure_forces(forces, dofs, x, pressure)
    np.testing.assert_array_equal(forces, expected)


@needs_numba
def test_wrinkled_tangent_equals_numpy_formula():
    rng = np.random.default_rng(4)
    phi = rng.uniform(0.0, np.pi, 101)
    b = rng.uniform(0.0, 0.1, 101)
    _, _, _, D, stress = random_element_data(101, seed=6)
    wrinkling = Wrinkling(StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0))
    arguments = (np.cos(phi), np.sin(phi), b, stress, D)
    np.testing.assert_array_equal(
        compiled.wrinkled_tangent(*arguments), wrinkling._wrinkled_tangent(*arguments)
    )
