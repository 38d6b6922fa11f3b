"""The tension-field solution of the annulus with a rotated hub
(verification.references.annulus_hub).

Every test checks the closed forms against something they were not built from: equilibrium
and the kinematic conditions by finite differences of the fields, Hooke's law, the boundary and
interface conditions, the energy principle (Castigliano: dPi/dphi = T), the onset from the Lamé
stresses, homogeneity, and the helpers of the finite-element comparison on synthetic data.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from verification.benchmarks.annulus_hub import fe_onset_torque, fe_wrinkle_radius
from verification.references.annulus_hub import HubAnnulus

# the benchmark's numbers: a = 0.1 m, b = 5 a, nu = 0.3, E t = 1.5e5 N/m, N0 = 1.5 N/m
PROBLEM = HubAnnulus(0.1, 0.5, 0.3, 1.5e5, 1.5)
A_HUB, B_EDGE, NU, Y, N0 = 0.1, 0.5, 0.3, 1.5e5, 1.5
STEP = 1e-7  # finite-difference step (m); the fields vary on the scale of a = 0.1 m


def derivative(f, r):
    """Central difference of f (vectorised in r) at r."""
    return (f(r + STEP) - f(r - STEP)) / (2.0 * STEP)


def radii(solution, count=400):
    """Radii in (a, b) that keep clear of the hub, the edge and the wrinkle radius."""
    r = np.linspace(A_HUB, B_EDGE, count)[1:-1]
    return r[np.abs(r - solution.wrinkle_radius) > 10 * STEP]


@pytest.fixture(scope="module", params=[1.5, 3.0, 5.0])
def wrinkled(request):
    return PROBLEM.solve(request.param * PROBLEM.onset_torque)


def test_onset_is_where_the_lame_minor_stress_at_the_hub_vanishes():
    # Lamé with u(a) = 0, N_r(b) = N0, written out independently of the class
    kappa = (1 - NU) / (1 + NU)
    A = N0 / (1 + kappa * A_HUB**2 / B_EDGE**2)
    B = kappa * A * A_HUB**2
    for factor, sign in ((1 - 1e-6, 1.0), (1 + 1e-6, -1.0)):
        shear = factor * PROBLEM.onset_torque / (2 * math.pi * A_HUB**2)
        N_r, N_theta = A + B / A_HUB**2, A - B / A_HUB**2
        minor = 0.5 * (N_r + N_theta) - math.hypot(0.5 * (N_r - N_theta), shear)
        assert sign * minor > 0
    # eq. (2) in numbers: T_onset / (N0 a^2) = 4 pi sqrt(nu)/(1 + nu)/(1 + kappa/25)
    assert PROBLEM.onset_torque / (N0 * A_HUB**2) == pytest.approx(5.1828950688663, rel=1e-12)


def test_below_onset_the_solution_is_lame_plus_linear_torsion():
    T = 0.6 * PROBLEM.onset_torque
    solution = PROBLEM.solve(T)
    assert not solution.wrinkled and solution.wrinkle_radius == A_HUB
    r = radii(solution)
    stress = solution.stress(r)
    A, B = PROBLEM.lame_constants
    np.testing.assert_allclose(stress[:, 0], A + B / r**2, rtol=1e-14)
    np.testing.assert_allclose(stress[:, 2], T / (2 * math.pi * r**2), rtol=1e-14)
    # eq. (1): the classical torsion of a membrane ring
    phi = (1 + NU) * T / (2 * math.pi * Y) * (1 / A_HUB**2 - 1 / B_EDGE**2)
    assert solution.rotation == pytest.approx(phi, rel=1e-13)
    assert PROBLEM.solve_rotation(phi).torque == pytest.approx(T, rel=1e-12)


def test_equilibrium_residuals_vanish(wrinkled):
    r = radii(wrinkled)
    stress = wrinkled.stress(r)

    def radial_force(x):
        return x * wrinkled.stress(x)[:, 0]

    def moment(x):
        return x**2 * wrinkled.stress(x)[:, 2]

    scale = np.max(np.abs(stress))
    assert np.max(np.abs(derivative(radial_force, r) - stress[:, 1])) < 1e-6 * scale
    assert np.max(np.abs(derivative(moment, r))) < 1e-6 * scale * A_HUB


def test_fields_are_continuous_at_the_wrinkle_radius(wrinkled):
    R = wrinkled.wrinkle_radius
    assert A_HUB < R < B_EDGE
    side = np.array([R * (1 - 1e-10), R * (1 + 1e-10)])
    stress = wrinkled.stress(side)
    np.testing.assert_allclose(stress[0], stress[1], rtol=1e-7)
    u = wrinkled.radial_displacement(side)
    assert abs(u[0] - u[1]) < 1e-7 * np.max(np.abs(wrinkled.radial_displacement(radii(wrinkled))))
    w = wrinkled.rotation_of(side)
    assert abs(w[0] - w[1]) < 1e-7 * wrinkled.rotation
    # the taut side's minor principal stress is zero at R (eq. 6)
    N_r, N_theta, N_rtheta = stress[1]
    assert N_r * N_theta - N_rtheta**2 == pytest.approx(0.0, abs=1e-6 * N_r**2)


def test_boundary_conditions_and_root_accuracy(wrinkled):
    assert wrinkled.radial_displacement(A_HUB)[0] == pytest.approx(0.0, abs=1e-22)
    assert wrinkled.rotation_of(A_HUB)[0] == pytest.approx(0.0, abs=1e-20)
    assert wrinkled.stress(B_EDGE)[0, 0] == pytest.approx(N0, rel=1e-10)
    assert wrinkled.rotation_of(B_EDGE)[0] == pytest.approx(wrinkled.rotation, rel=1e-14)
    g = PROBLEM.continuity_residual(wrinkled.line_radius, wrinkled.wrinkle_radius)
    assert abs(g) < 1e-10 * A_HUB**2
    assert PROBLEM.torque_at(wrinkled.wrinkle_radius) == pytest.approx(wrinkled.torque, rel=1e-10)


def test_wrinkled_zone_is_a_tension_field_along_lines_tangent_to_rho(wrinkled):
    r = radii(wrinkled)
    inside = r[r < wrinkled.wrinkle_radius]
    N_r, N_theta, N_rtheta = wrinkled.stress(inside).T
    # rank one (uniaxial), tension, direction at asin(rho/r) to the radius
    np.testing.assert_allclose(N_r * N_theta, N_rtheta**2, rtol=1e-12)
    assert np.all(N_r > 0) and np.all(N_theta > 0)
    psi = np.arcsin(wrinkled.line_radius / inside)
    np.testing.assert_allclose(N_rtheta / N_r, np.tan(psi), rtol=1e-12)
    assert 0 < wrinkled.line_radius < A_HUB


def test_displacements_satisfy_the_kinematics_of_both_zones(wrinkled):
    """Strains by finite differences of the displacement fields: along the tension lines
    elastic and principal (e_tt = sigma/Y, e_tn = 0) with over-contraction beta >= 0 across
    them; Hooke's law in the taut zone."""
    r = radii(wrinkled)
    e_r = derivative(wrinkled.radial_displacement, r)
    e_theta = wrinkled.radial_displacement(r) / r
    gamma = r * derivative(wrinkled.rotation_of, r)
    N_r, N_theta, N_rtheta = wrinkled.stress(r).T
    scale = np.max(N_r + N_theta) / Y
    inside = r < wrinkled.wrinkle_radius
    psi = np.arcsin(wrinkled.line_radius / r[inside])
    c, s = np.cos(psi), np.sin(psi)
    er, et, g = e_r[inside], e_theta[inside], gamma[inside]
    sigma = N_r[inside] + N_theta[inside]
    e_tt = er * c**2 + et * s**2 + g * s * c
    e_tn = (et - er) * s * c + 0.5 * g * (c**2 - s**2)
    e_nn = er * s**2 + et * c**2 - g * s * c
    assert np.max(np.abs(e_tt - sigma / Y)) < 1e-6 * scale
    assert np.max(np.abs(e_tn)) < 1e-6 * scale
    beta = -NU * sigma / Y - e_nn
    assert np.all(beta > 0)
    np.testing.assert_allclose(wrinkled.overcontraction(r[inside]), beta, atol=1e-6 * scale)
    near = wrinkled.wrinkle_radius * (1 - np.array([1e-3, 1e-4]))
    assert np.all(wrinkled.overcontraction(near) < 2e-2 * np.max(beta))
    outside = ~inside
    D = Y / (1 - NU**2)
    np.testing.assert_allclose(
        N_r[outside], D * (e_r + NU * e_theta)[outside], atol=1e-6 * scale * Y
    )
    np.testing.assert_allclose(
        N_theta[outside], D * (e_theta + NU * e_r)[outside], atol=1e-6 * scale * Y
    )
    np.testing.assert_allclose(
        N_rtheta[outside], Y / (2 * (1 + NU)) * gamma[outside], atol=1e-6 * scale * Y
    )


def _potential(rotation: float) -> float:
    """Pi(phi) = U - N0 2 pi b u_r(b): strain energy from the stresses (complementary form,
    uniaxial sigma^2 / 2Y where wrinkled) minus the work of the dead edge tension."""
    solution = PROBLEM.solve_rotation(rotation)

    def energy_density(r):
        N_r, N_theta, N_rtheta = solution.stress(r)[0]
        if r < solution.wrinkle_radius:
            return (N_r + N_theta) ** 2 / (2 * Y) * 2 * math.pi * r
        return (
            (N_r**2 + N_theta**2 - 2 * NU * N_r * N_theta + 2 * (1 + NU) * N_rtheta**2)
            / (2 * Y)
            * 2
            * math.pi
            * r
        )

    R = solution.wrinkle_radius
    energy = sum(
        quad(energy_density, lo, hi, epsabs=0, epsrel=1e-13, limit=200)[0]
        for lo, hi in ((A_HUB, R), (R, B_EDGE))
        if hi > lo
    )
    return energy - N0 * 2 * math.pi * B_EDGE * solution.radial_displacement(B_EDGE)[0]


@pytest.mark.parametrize("multiple", [0.5, 2.0, 4.0])
def test_torque_is_the_derivative_of_the_potential_with_respect_to_the_rotation(multiple):
    solution = PROBLEM.solve(multiple * PROBLEM.onset_torque)
    h = 1e-4 * solution.rotation
    slope = (_potential(solution.rotation + h) - _potential(solution.rotation - h)) / (2 * h)
    assert slope == pytest.approx(solution.torque, rel=1e-6)


def test_onset_limit():
    onset = PROBLEM.onset_torque
    previous = None
    for epsilon in (1e-3, 1e-5, 1e-7):
        solution = PROBLEM.solve(onset * (1 + epsilon))
        assert solution.wrinkle_radius - A_HUB < 50 * epsilon * A_HUB
        assert solution.line_radius == pytest.approx(
            A_HUB * math.sqrt(NU / (1 + NU)), rel=100 * epsilon
        )
        linear = solution.torque / PROBLEM.torsional_stiffness
        assert solution.rotation == pytest.approx(linear, rel=10 * epsilon)
        if previous is not None:
            assert solution.wrinkle_radius < previous
        previous = solution.wrinkle_radius
    # at the onset itself the wrinkled-zone formulas give the Lamé constants (eqs. 6 and 2)
    A, _ = PROBLEM.lame_constants
    rho = A_HUB * math.sqrt(NU / (1 + NU))
    c = math.sqrt(A_HUB**2 - rho**2)
    assert onset / (4 * math.pi * rho * c) == pytest.approx(A, rel=1e-13)
    assert PROBLEM.continuity_residual(rho, A_HUB) == pytest.approx(0.0, abs=1e-16)


def test_wrinkled_zone_grows_and_softens_the_membrane():
    torques = PROBLEM.onset_torque * np.array([1.2, 2.0, 3.0, 4.0, 5.0])
    solutions = [PROBLEM.solve(t) for t in torques]
    R = np.array([s.wrinkle_radius for s in solutions])
    phi = np.array([s.rotation for s in solutions])
    assert np.all(np.diff(R) > 0) and np.all(np.diff(phi) > 0)
    secant = torques / phi
    assert np.all(np.diff(secant) < 0) and secant[0] < PROBLEM.torsional_stiffness
    with pytest.raises(ValueError, match="outer edge"):
        PROBLEM.solve(1.01 * PROBLEM.largest_torque)


def test_solution_is_homogeneous_in_edge_tension_and_torque():
    tripled = HubAnnulus(A_HUB, B_EDGE, NU, Y, 3 * N0)
    one = PROBLEM.solve(3.0 * PROBLEM.onset_torque)
    three = tripled.solve(3 * 3.0 * PROBLEM.onset_torque)
    assert three.wrinkle_radius == pytest.approx(one.wrinkle_radius, rel=1e-12)
    assert three.line_radius == pytest.approx(one.line_radius, rel=1e-12)
    assert three.rotation == pytest.approx(3 * one.rotation, rel=1e-12)
    r = np.linspace(A_HUB, B_EDGE, 50)
    np.testing.assert_allclose(three.stress(r), 3 * one.stress(r), rtol=1e-11)


def test_rotation_control_inverts_torque_control():
    solution = PROBLEM.solve(2.7 * PROBLEM.onset_torque)
    again = PROBLEM.solve_rotation(solution.rotation)
    assert again.torque == pytest.approx(solution.torque, rel=1e-10)
    assert again.wrinkle_radius == pytest.approx(solution.wrinkle_radius, rel=1e-10)


def test_bad_input_is_refused():
    with pytest.raises(ValueError):
        HubAnnulus(0.5, 0.1, NU, Y, N0)
    with pytest.raises(ValueError):
        HubAnnulus(A_HUB, B_EDGE, 0.0, Y, N0)
    with pytest.raises(ValueError):
        PROBLEM.solve(-1.0)


def test_fe_wrinkle_radius_interpolates_the_last_sign_change():
    r = np.linspace(1.0, 2.0, 11)
    assert fe_wrinkle_radius(r, r - 1.43, 1.0, 2.0) == pytest.approx(1.43, rel=1e-14)
    assert fe_wrinkle_radius(r, np.ones(11), 1.0, 2.0) == 1.0
    assert fe_wrinkle_radius(r, -np.ones(11), 1.0, 2.0) == 2.0
    # a kink at R = 1.43 between samples 0.1 apart (theta = 0.3 of the way), slopes 3 inside
    # and 1 outside: linear interpolation errs by h theta (1 - theta) (3 - 1) / (3 theta +
    # 1 - theta), which is O(h)
    kinked = np.where(r < 1.43, 3 * (r - 1.43), r - 1.43)
    error = 0.1 * 0.3 * 0.7 * 2 / (3 * 0.3 + 0.7)
    assert fe_wrinkle_radius(r, kinked, 1.0, 2.0) == pytest.approx(1.43 + error, rel=1e-12)


def test_fe_onset_torque_finds_the_first_element_to_wrinkle():
    class Taut:  # the two attributes fe_onset_torque reads
        def __init__(self, torque, stress):
            self.torque, self.element_stress = torque, stress

    # two elements, N_r and N_theta fixed, shear proportional to T: det = 0 at
    # T = sqrt(N_r N_theta) / k
    N_r, N_theta, k = np.array([2.0, 3.0]), np.array([1.0, 0.5]), np.array([0.5, 0.4])

    def state(T):
        return Taut(T, np.column_stack([N_r, N_theta, k * T]))

    expected = np.min(np.sqrt(N_r * N_theta) / k)
    assert fe_onset_torque(state(0.3), state(1.1)) == pytest.approx(expected, rel=1e-13)
