"""Tests of the Lamé annulus reference (verification.references.lame_annulus).

Every closed form is checked against something computed another way: equilibrium by finite
differences, the relaxed (tension-field) constitutive law applied to the closed-form
displacement, the principle of virtual work by quadrature, the matching conditions solved
numerically with SciPy, and limits (onset, infinite sheet).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq, fsolve

from verification.benchmarks.lame_annulus import (
    RingFields,
    fe_wrinkle_radius,
    graded_quarter_annulus,
    ring_radii,
)
from verification.references.lame_annulus import LameAnnulus, onset_ratio, wrinkle_radius
from wrinkle.case import read_case_data

R_IN, R_OUT, T_OUT = 1.0, 10.0, 1.0
Y, NU = 2.0e3, 0.34  # stretching stiffness E t and Poisson's ratio for the displacements
CASE = Path(__file__).resolve().parents[2] / "verification" / "cases" / "lame_annulus.toml"

# below the onset (taut), just above it, and well beyond (tau_c = 200/101 = 1.980)
RATIOS = [0.6, 1.5, 2.0, 3.0, 5.0, 9.5]


def annulus(ratio: float, inner: float = R_IN, outer: float = R_OUT) -> LameAnnulus:
    return LameAnnulus(inner, outer, ratio * T_OUT, T_OUT)


def radii_away_from(L: float, count: int = 41) -> np.ndarray:
    """Radii spread over the sheet, none within 1e-3 of the wrinkle radius L."""
    r = np.geomspace(R_IN * 1.01, R_OUT * 0.99, count)
    return r[np.abs(r - L) > 1e-3 * L]


@pytest.mark.parametrize("ratio", RATIOS)
def test_equilibrium_by_finite_differences(ratio):
    """d(r N_r)/dr = N_theta, eq. (1), by central differences in both zones."""
    sheet = annulus(ratio)
    r = radii_away_from(sheet.wrinkle_radius)
    step = 1e-5 * r
    derivative = (
        (r + step) * sheet.radial_stress(r + step) - (r - step) * sheet.radial_stress(r - step)
    ) / (2 * step)
    np.testing.assert_allclose(derivative, sheet.hoop_stress(r), rtol=1e-7, atol=1e-8 * T_OUT)


@pytest.mark.parametrize("ratio", RATIOS)
def test_edge_tractions(ratio):
    sheet = annulus(ratio)
    assert float(sheet.radial_stress(R_IN)) == pytest.approx(ratio * T_OUT, rel=1e-13)
    assert float(sheet.radial_stress(R_OUT)) == pytest.approx(T_OUT, rel=1e-13)


@pytest.mark.parametrize("ratio", [2.0, 3.0, 5.0, 9.5])
def test_continuity_at_the_wrinkle_radius(ratio):
    """N_r, N_theta (= 0), u and the wrinkling strain (= 0) are continuous at L, and the
    indicator g = N_theta/Y - w has the same slope on both sides (eq. 11)."""
    sheet = annulus(ratio)
    L = sheet.wrinkle_radius
    inside, outside = L * (1 - 1e-9), L * (1 + 1e-9)
    for field in (sheet.radial_stress, sheet.hoop_stress):
        assert float(field(inside)) == pytest.approx(float(field(outside)), abs=1e-7 * T_OUT)
    assert float(sheet.hoop_stress(outside)) == pytest.approx(0.0, abs=1e-7 * T_OUT)
    u_in = float(sheet.radial_displacement(inside, Y, NU))
    u_out = float(sheet.radial_displacement(outside, Y, NU))
    assert u_in == pytest.approx(u_out, rel=1e-7)
    assert float(sheet.wrinkling_strain(inside, Y)) == pytest.approx(0.0, abs=1e-12)

    def g(r):
        return sheet.hoop_stress(r) / Y - sheet.wrinkling_strain(r, Y)

    h = 1e-4 * L
    slope_in = float(g(L - h) - g(L - 2 * h)) / h
    slope_out = float(g(L + 2 * h) - g(L + h)) / h
    expected = ratio * T_OUT * R_IN / (Y * L**2)
    assert slope_in == pytest.approx(expected, rel=1e-3)
    assert slope_out == pytest.approx(expected, rel=1e-3)


def test_onset_ratio_and_limit():
    """Below the onset the Lamé hoop stress at the hole is positive, above it negative;
    L -> R_in as tau -> tau_c from above, linearly."""
    tau_c = onset_ratio(R_IN, R_OUT)
    assert tau_c == pytest.approx(200.0 / 101.0, rel=1e-15)

    def lame_hoop_at_hole(tau):  # eq. (3), the taut solution, whatever the sign
        A = (T_OUT * R_OUT**2 - tau * T_OUT * R_IN**2) / (R_OUT**2 - R_IN**2)
        B = (tau - 1.0) * T_OUT * R_IN**2 * R_OUT**2 / (R_OUT**2 - R_IN**2)
        return A - B / R_IN**2

    assert brentq(lame_hoop_at_hole, 1.0, 3.0, xtol=1e-14) == pytest.approx(tau_c, rel=1e-12)
    assert not annulus(tau_c * (1 - 1e-9)).wrinkled
    assert annulus(tau_c * (1 + 1e-9)).wrinkled
    excess = np.array([1e-3, 1e-4, 1e-5])
    growth = (wrinkle_radius(R_IN, R_OUT, tau_c * (1 + excess)) - R_IN) / excess
    assert np.all(growth > 0)
    assert growth[-1] == pytest.approx(growth[-2], rel=1e-3)  # linear near the onset
    assert wrinkle_radius(R_IN, R_OUT, 0.9 * tau_c) == R_IN


@pytest.mark.parametrize("ratio", [2.0, 2.5, 3.5, 5.0, 8.0, 9.9])
def test_matching_conditions_solved_numerically(ratio):
    """A, B, L from a SciPy solve of the three matching conditions (to 1e-10) equal the
    closed form (8): N_r(L) = T_in R_in / L, N_theta(L) = 0, N_r(R_out) = T_out."""
    t_in = ratio * T_OUT

    def conditions(x):
        A, B, L = x
        return [A + B / L**2 - t_in * R_IN / L, A - B / L**2, A + B / R_OUT**2 - T_OUT]

    guess = [T_OUT, T_OUT, 0.5 * ratio * R_IN]
    A, B, L = fsolve(conditions, guess, xtol=1e-13)
    assert np.max(np.abs(conditions([A, B, L]))) < 1e-10
    sheet = annulus(ratio)
    assert sheet.wrinkle_radius == pytest.approx(L, rel=1e-10)
    assert sheet.lame_constants[0] == pytest.approx(A, rel=1e-10)
    assert sheet.lame_constants[1] == pytest.approx(B, rel=1e-10)

    # and the same L by bracketing the outer traction as a function of L
    def outer_traction_error(L):
        A = t_in * R_IN / (2 * L)
        return A * (1 + L**2 / R_OUT**2) - T_OUT

    root = brentq(outer_traction_error, R_IN, R_OUT, xtol=1e-15, rtol=1e-15)
    assert sheet.wrinkle_radius == pytest.approx(root, rel=1e-10)


def test_infinite_sheet_limit():
    """L -> tau R_in / 2 as R_out -> infinity."""
    for ratio in (2.5, 5.0):
        L = wrinkle_radius(R_IN, 1e6 * R_IN, ratio)
        assert L == pytest.approx(ratio * R_IN / 2, rel=1e-10)


def relaxed_stress(strain_r, strain_t):
    """Tension-field stress of a linear isotropic membrane whose principal strains lie along r
    and theta, written here independently of the module: taut (plane stress) if both stresses
    are >= 0; otherwise uniaxial along the direction of the larger strain if that strain is
    positive (wrinkled); otherwise zero (slack)."""
    c = Y / (1 - NU**2)
    n_r, n_t = c * (strain_r + NU * strain_t), c * (strain_t + NU * strain_r)
    taut = (n_r >= 0) & (n_t >= 0)
    along_r = ~taut & (strain_r >= strain_t) & (strain_r > 0)
    along_t = ~taut & (strain_t > strain_r) & (strain_t > 0)
    radial = np.where(taut, n_r, np.where(along_r, Y * strain_r, 0.0))
    hoop = np.where(taut, n_t, np.where(along_t, Y * strain_t, 0.0))
    return radial, hoop


@pytest.mark.parametrize("ratio", RATIOS)
def test_displacement_gives_the_stress_through_the_relaxed_law(ratio):
    """Strains of the closed-form u (u' by central differences, u/r), through the relaxed
    constitutive law, give the closed-form stresses; where wrinkled, the mean surface is
    shorter in the hoop direction than the elastic hoop strain by the wrinkling strain."""
    sheet = annulus(ratio)
    r = radii_away_from(sheet.wrinkle_radius)
    step = 1e-6 * r
    u = sheet.radial_displacement(r, Y, NU)
    strain_r = (
        sheet.radial_displacement(r + step, Y, NU) - sheet.radial_displacement(r - step, Y, NU)
    ) / (2 * step)
    strain_t = u / r
    n_r, n_t = relaxed_stress(strain_r, strain_t)
    scale = ratio * T_OUT
    np.testing.assert_allclose(n_r, sheet.radial_stress(r), rtol=1e-6, atol=1e-7 * scale)
    np.testing.assert_allclose(n_t, sheet.hoop_stress(r), atol=1e-6 * scale)
    wrinkled = r < sheet.wrinkle_radius
    elastic_hoop = -NU * sheet.radial_stress(r) / Y
    np.testing.assert_allclose(
        (elastic_hoop - strain_t)[wrinkled], sheet.wrinkling_strain(r, Y)[wrinkled], rtol=1e-9
    )
    assert np.all(sheet.wrinkling_strain(r, Y)[~wrinkled] == 0)
    assert np.all(sheet.wrinkling_strain(r, Y)[wrinkled] > 0)


@pytest.mark.parametrize("ratio", [1.5, 5.0])
@pytest.mark.parametrize("power", [-2, 0, 1, 3])
def test_virtual_work(ratio, power):
    """For the virtual displacement du = r^k: integral of (N_r du' + N_theta du/r) 2 pi r dr
    equals the work of the edge tractions, 2 pi (R_out T_out du(R_out) - R_in T_in du(R_in))
    (T_in pulls the hole's edge towards the centre)."""
    sheet = annulus(ratio)

    def integrand(r):
        du, dstrain = r**power, power * r ** (power - 1)
        return (
            2
            * np.pi
            * r
            * (float(sheet.radial_stress(r)) * dstrain + float(sheet.hoop_stress(r)) * du / r)
        )

    breaks = [sheet.wrinkle_radius] if sheet.wrinkled else None
    internal, _ = quad(integrand, R_IN, R_OUT, points=breaks, epsabs=0, epsrel=1e-12, limit=200)
    external = 2 * np.pi * (R_OUT * T_OUT * R_OUT**power - R_IN * ratio * T_OUT * R_IN**power)
    assert internal == pytest.approx(external, rel=1e-9, abs=1e-9 * abs(external) + 1e-12)


def test_bad_ratios_are_refused():
    with pytest.raises(ValueError, match="exceeds R_out/R_in"):
        annulus(10.5)
    with pytest.raises(ValueError, match="must be > 0"):
        wrinkle_radius(R_IN, R_OUT, 0.0)
    with pytest.raises(ValueError, match="outside"):
        annulus(3.0).radial_stress(0.5 * R_IN)


def test_graded_quarter_annulus():
    """Circles at r_i = R_in (R_out/R_in)^(i/n); counter-clockwise triangles whose areas sum
    to a quarter of the ring between the inscribed polygons; the symmetry edges on the axes."""
    n_radial, n_circumferential = 6, 5
    mesh = graded_quarter_annulus(R_IN, R_OUT, n_radial, n_circumferential)
    X = mesh.nodes
    r = np.hypot(X[:, 0], X[:, 1])
    radii = ring_radii(R_IN, R_OUT, n_radial)
    np.testing.assert_allclose(np.unique(np.round(r, 12)), radii, rtol=1e-12)
    np.testing.assert_allclose(radii[1:] / radii[:-1], 10 ** (1 / n_radial), rtol=1e-13)
    edges = X[mesh.triangles]
    twice_area = np.cross(edges[:, 1] - edges[:, 0], edges[:, 2] - edges[:, 0])[:, 2]
    assert np.all(twice_area > 0)
    polygon = n_circumferential * np.sin(0.5 * np.pi / n_circumferential) / 2  # per unit r^2
    assert twice_area.sum() / 2 == pytest.approx(polygon * (R_OUT**2 - R_IN**2), rel=1e-12)
    assert np.all(X[mesh.node_sets["x0"], 0] == 0.0)
    assert np.all(X[mesh.node_sets["y0"], 1] == 0.0)
    np.testing.assert_allclose(r[mesh.node_sets["inner"]], R_IN, rtol=1e-14)
    np.testing.assert_allclose(r[mesh.node_sets["outer"]], R_OUT, rtol=1e-14)


def test_wrinkle_radius_from_ring_means():
    """The sign change of g = N_theta/Y - beta is found by linear interpolation between ring
    radii (exact for a g linear in r), extrapolated below the first ring, and R_in when g
    never changes sign."""
    radius = np.array([1.1, 1.3, 1.5, 1.7, 1.9])

    def fields(g):
        hoop = np.maximum(g, 0.0) * Y
        beta = np.maximum(-g, 0.0)
        empty = np.zeros(1)
        return RingFields(
            empty, empty, empty, empty, empty, radius, np.ones(5), hoop, beta, empty, empty
        )

    assert fe_wrinkle_radius(fields(0.3 * (radius - 1.42)), Y, R_IN) == pytest.approx(1.42)
    assert fe_wrinkle_radius(fields(0.3 * (radius - 1.05)), Y, R_IN) == pytest.approx(1.05)
    assert fe_wrinkle_radius(fields(0.3 * (radius - 0.8)), Y, R_IN) == R_IN
    assert fe_wrinkle_radius(fields(1.0 - 0.1 * radius), Y, R_IN) == R_IN


def test_case_file_matches_the_problem():
    """The gallery's case: R_out/R_in = 10, T_in/T_out = 5 (the ratio of the issue), every
    tolerance stated for the quick and the full run, and the checked ratios beyond onset."""
    data = read_case_data(CASE)
    annulus_table = data["mesh"]["annulus"]
    assert annulus_table["outer_radius"] / annulus_table["inner_radius"] == 10
    tensions = sorted(load["normal"] for load in data["load"])
    assert tensions[1] / tensions[0] == 5
    settings = data["verification"]
    assert set(settings["tolerance"]) == set(settings["quick_tolerance"])
    tau_c = onset_ratio(annulus_table["inner_radius"], annulus_table["outer_radius"])
    assert all(tau_c < t <= 5 for t in settings["check_ratios"])
    assert sum(t < tau_c for t in settings["ratios"]) >= 2  # for the finite-element onset
