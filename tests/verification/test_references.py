"""Tests of the independent wrinkling reference (relaxed energy) and the shear-stretch solution."""

from __future__ import annotations

import numpy as np
import pytest

from verification.references import (
    homogeneous_edge_forces,
    relax,
    shear_stretch_curves,
    shifted_energy,
)
from wrinkle.materials import NeoHookean, StVenantKirchhoff

E, NU, T = 1.0, 0.3, 1.0


@pytest.fixture(scope="module")
def isotropic() -> StVenantKirchhoff:
    return StVenantKirchhoff.isotropic(E, NU, T)


@pytest.fixture(scope="module")
def fibre() -> StVenantKirchhoff:
    """Transversely isotropic, fibre (axis 1) five times stiffer."""
    return StVenantKirchhoff.transversely_isotropic(
        E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=0.5, thickness=T
    )


def rotation(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def same_line(phi: float, psi: float) -> float:
    """Distance between two undirected directions given by angles (|sin of the difference|)."""
    return abs(np.sin(phi - psi))


def test_gradient_of_shifted_energy_matches_finite_differences(fibre):
    C = np.array([[1.1, 0.05], [0.05, 0.9]])
    params = np.array([0.2, -0.1, 0.15])
    _, gradient = shifted_energy(fibre, C, params)
    h = 1e-6
    finite = [
        (shifted_energy(fibre, C, params + h * e)[0] - shifted_energy(fibre, C, params - h * e)[0])
        / (2 * h)
        for e in np.eye(3)
    ]
    np.testing.assert_allclose(gradient, finite, rtol=1e-8, atol=1e-11)


def test_uniaxial_stretch_is_wrinkled_with_uniaxial_stress(isotropic):
    F = np.diag([1.1, 0.95])
    state = relax(isotropic, F.T @ F)
    E11 = (1.1**2 - 1.0) / 2.0
    assert state.state == "wrinkled"
    np.testing.assert_allclose(
        state.stress, [[E * T * E11, 0.0], [0.0, 0.0]], rtol=1e-13, atol=1e-15
    )
    assert state.energy == pytest.approx(E * T * E11**2 / 2.0, rel=1e-13)
    assert same_line(state.wrinkle_angle, np.pi / 2) < 1e-13
    assert state.b > 0.0
    assert state.residual < 1e-14
    # the wrinkled, stress-free direction carries the lateral contraction -nu E11
    assert 0.5 * (0.95**2 + state.b - 1.0) == pytest.approx(-NU * E11, rel=1e-12)


def test_biaxial_compression_is_slack(isotropic):
    F = np.diag([0.9, 0.95])
    state = relax(isotropic, F.T @ F)
    assert state.state == "slack"
    assert state.energy == 0.0
    np.testing.assert_array_equal(state.stress, np.zeros((2, 2)))
    np.testing.assert_allclose(F.T @ F + state.A, np.eye(2), atol=1e-15)


def test_equibiaxial_stretch_is_taut_and_equals_plain_stress(isotropic):
    C = 1.05**2 * np.eye(2)
    state = relax(isotropic, C)
    assert state.state == "taut"
    np.testing.assert_array_equal(state.A, np.zeros((2, 2)))
    np.testing.assert_allclose(state.stress, isotropic.response(C[None]).stress[0], rtol=1e-15)
    assert state.energy == pytest.approx(isotropic.energy(C[None])[0], rel=1e-15)


@pytest.mark.parametrize("angle", [0.3, -0.7, 1.2, np.pi / 4])
def test_rotated_uniaxial_stretch(isotropic, angle):
    """Rotating the reference frame by R: C -> R C R^T, N -> R N R^T for an isotropic law."""
    R = rotation(angle)
    F = np.diag([1.1, 0.95]) @ R.T
    C = F.T @ F
    state = relax(isotropic, C)
    E11 = (1.1**2 - 1.0) / 2.0
    expected = R @ np.diag([E * T * E11, 0.0]) @ R.T
    assert state.state == "wrinkled"
    np.testing.assert_allclose(state.stress, expected, rtol=0.0, atol=1e-14)
    minor = np.linalg.eigh(C)[1][:, 0]
    assert same_line(state.wrinkle_angle, np.arctan2(minor[1], minor[0])) < 1e-12
    assert same_line(state.wrinkle_angle, angle + np.pi / 2) < 1e-12


def test_envelope_theorem_for_anisotropic_wrinkling(fibre):
    """stress = 2 dw_rel/dC, by central differences, fibre off-axis by 30 degrees."""
    R = rotation(np.radians(30.0))
    C0 = np.diag([1.1**2, 0.95**2])
    C = R @ C0 @ R.T
    state = relax(fibre, C)
    assert state.state == "wrinkled"
    assert state.residual < 1e-13
    w = np.array([np.cos(state.wrinkle_angle), np.sin(state.wrinkle_angle)])
    np.testing.assert_allclose(state.stress @ w, 0.0, atol=1e-13)
    # anisotropy turns the wrinkles away from the principal directions of C
    minor = np.linalg.eigh(C)[1][:, 0]
    assert same_line(state.wrinkle_angle, np.arctan2(minor[1], minor[0])) > 1e-2

    h = 1e-5
    derivative = np.empty((2, 2))
    for i, j in [(0, 0), (1, 1), (0, 1)]:
        dC = np.zeros((2, 2))
        dC[i, j] = dC[j, i] = h
        slope = (relax(fibre, C + dC).energy - relax(fibre, C - dC).energy) / (2 * h)
        # a symmetric perturbation of the off-diagonal moves C12 and C21 together
        derivative[i, j] = derivative[j, i] = 2.0 * slope if i == j else slope
    assert np.linalg.norm(derivative - state.stress) < 1e-6 * np.linalg.norm(state.stress)


def test_relaxed_energy_is_not_beaten_by_random_wrinkling_strains(fibre):
    R = rotation(0.4)
    C = R @ np.diag([1.15**2, 0.9**2]) @ R.T
    state = relax(fibre, C)
    rng = np.random.default_rng(1)
    L = 0.3 * rng.standard_normal((2000, 2, 2))
    trial = fibre.energy(C + state.A + L @ np.swapaxes(L, 1, 2))  # A* + PSD
    trial_rank_one = fibre.energy(C + np.einsum("ni,nj->nij", L[:, 0], L[:, 0]))
    assert state.energy <= trial.min()
    assert state.energy <= trial_rank_one.min()
    assert state.energy < fibre.energy(C[None])[0]


@pytest.mark.parametrize("stretch", [1.05, 1.4])
def test_incompressible_neo_hookean_uniaxial_closed_form(stretch):
    """Wrinkled: N22 = 0 gives c2 = c1^(-1/2), N11 = mu t (1 - c1^(-3/2)),
    w = mu t/2 (c1 + 2 c1^(-1/2) - 3)."""
    mu, t = 2.0, 0.5
    material = NeoHookean(mu, t)
    c1 = stretch**2
    c2 = 0.8 * c1**-0.5  # laterally shorter than the free contraction: wrinkles
    state = relax(material, np.diag([c1, c2]))
    assert state.state == "wrinkled"
    np.testing.assert_allclose(
        state.stress, [[mu * t * (1.0 - c1**-1.5), 0.0], [0.0, 0.0]], rtol=1e-13, atol=1e-14
    )
    assert state.energy == pytest.approx(0.5 * mu * t * (c1 + 2 * c1**-0.5 - 3.0), rel=1e-12)
    assert c2 + state.b == pytest.approx(c1**-0.5, rel=1e-12)


def test_compressible_neo_hookean_wrinkled_state_is_stationary():
    material = NeoHookean(1.0, 1.0, lmbda=2.0)
    F = np.array([[1.2, 0.3], [0.0, 0.9]])
    state = relax(material, F.T @ F)
    assert state.state == "wrinkled"
    assert state.residual < 1e-14
    w = np.array([np.cos(state.wrinkle_angle), np.sin(state.wrinkle_angle)])
    np.testing.assert_allclose(
        material.response((F.T @ F + state.A)[None]).stress[0] @ w, 0.0, atol=1e-14
    )
    assert np.linalg.eigvalsh(state.stress)[1] > 0.0


def test_shear_stretch_states(isotropic):
    _, _, sheared = homogeneous_edge_forces(isotropic, gamma=0.1, v=0.0)
    _, _, stretched = homogeneous_edge_forces(isotropic, gamma=0.1, v=0.1)
    assert sheared.state == "wrinkled"
    assert stretched.state == "taut"


def test_shear_stretch_taut_forces_are_plain_first_piola_kirchhoff(isotropic):
    length, gamma, v = 2.0, 0.1, 0.3
    F1, F2, state = homogeneous_edge_forces(isotropic, gamma, v, length)
    F = np.array([[1.0, gamma], [0.0, 1.0 + v / length]])
    N = isotropic.response((F.T @ F)[None]).stress[0]
    assert state.state == "taut"
    np.testing.assert_allclose([F1, F2], length * F @ N[:, 1], rtol=1e-15)


def test_shear_stretch_forces_are_continuous_in_v(isotropic):
    gamma = 0.1
    curves = shear_stretch_curves(isotropic, gamma, np.linspace(0.0, 0.1, 11))
    assert curves.state[0] == "wrinkled" and curves.state[-1] == "taut"
    assert np.all(np.diff(curves.F2) > 0.0)
    # bisection on the wrinkled -> taut transition, then no jump across it
    lo, hi = 0.0, 0.1
    while hi - lo > 1e-7:
        mid = 0.5 * (lo + hi)
        if homogeneous_edge_forces(isotropic, gamma, mid)[2].state == "taut":
            hi = mid
        else:
            lo = mid
    below = homogeneous_edge_forces(isotropic, gamma, lo)
    above = homogeneous_edge_forces(isotropic, gamma, hi)
    assert below[2].state == "wrinkled" and above[2].state == "taut"
    assert abs(above[0] - below[0]) < 1e-6
    assert abs(above[1] - below[1]) < 1e-6
    # and the wrinkle tension goes smoothly to zero: b -> 0 at the transition
    assert below[2].b < 1e-5


@pytest.mark.parametrize("offset", [1e-9, -1e-9])
def test_state_is_exact_next_to_the_taut_wrinkled_boundary(fibre, offset):
    """On the boundary N22 = 0 (E22 = -Q12/Q22 E11); below it wrinkles with b = -2 offset."""
    Q = fibre.plane_stress_stiffness
    E11 = 0.05
    E22 = -Q[0, 1] / Q[1, 1] * E11 + offset
    state = relax(fibre, np.diag([1.0 + 2.0 * E11, 1.0 + 2.0 * E22]))
    if offset > 0:
        assert state.state == "taut"
    else:
        assert state.state == "wrinkled"
        assert state.b == pytest.approx(-2.0 * offset, rel=1e-6)


@pytest.mark.parametrize("offset", [1e-10, -1e-10])
def test_state_is_exact_next_to_the_wrinkled_slack_boundary(fibre, offset):
    R = rotation(0.3)
    state = relax(fibre, R @ np.diag([1.0 + offset, 0.9]) @ R.T)
    assert state.state == ("wrinkled" if offset > 0 else "slack")
