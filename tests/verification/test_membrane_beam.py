"""Tests of the one-dimensional tension-field membrane beam (verification.references.membrane_beam).

Every closed form is checked against something computed another way: the section's force and
moment by quadrature of the stress, the curvature and the tip deflection as derivatives of the
complementary energy (finite differences of quadratures), the tip deflection by numerical
integration of curvature and shear strain, the shear flow from axial equilibrium by finite
differences, continuity at the onset and the slack limit; plus the finite-element helpers on
fields whose answer is known.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import quad

from verification.benchmarks.membrane_beam import compressed_edge_strain, sign_change
from verification.references.membrane_beam import MembraneBeam
from wrinkle.case import read_case_data
from wrinkle.mesh import rectangle

# deliberately unrelated numbers (consistent units), so that a dropped factor shows
L, H, P, ET, GT = 0.8, 0.15, 12.0, 3.0e4, 1.1e4
BEAM = MembraneBeam(L, H, P, ET, GT)
V_SLACK = P * H / (2 * L)
CASE = Path(__file__).resolve().parents[2] / "verification" / "cases" / "membrane_beam.toml"

# taut, at the onset, wrinkled, close to the slack limit
MOMENTS = [0.0, 0.1 * P * H, P * H / 6, 0.3 * P * H, 0.45 * P * H, 0.499 * P * H]


def stress_integral(weight, moment: float) -> float:
    """integral_0^h N(s) weight(s) ds by adaptive quadrature, split at the taut depth."""
    c = float(BEAM.taut_depth(moment))
    points = [c] if 0 < c < H else None
    return quad(
        lambda s: float(BEAM.axial_stress(s, moment)) * weight(s),
        0.0,
        H,
        points=points,
        epsabs=1e-14 * P * H,
        epsrel=1e-12,
        limit=200,
    )[0]


def complementary_energy_by_quadrature(moment: float) -> float:
    """u*(M) = integral N^2 / (2 E t) ds, from the stress alone."""
    c = float(BEAM.taut_depth(moment))
    points = [c] if 0 < c < H else None
    return quad(
        lambda s: float(BEAM.axial_stress(s, moment)) ** 2 / (2 * ET),
        0.0,
        H,
        points=points,
        epsabs=0,
        epsrel=1e-13,
        limit=200,
    )[0]


@pytest.mark.parametrize("moment", MOMENTS)
def test_stress_resultants_are_the_axial_force_and_the_moment(moment):
    assert stress_integral(lambda s: 1.0, moment) == pytest.approx(P, rel=1e-10)
    assert stress_integral(lambda s: 0.5 * H - s, moment) == pytest.approx(
        moment, rel=1e-10, abs=1e-12 * P * H
    )


@pytest.mark.parametrize("moment", MOMENTS)
def test_no_compression_and_zero_stress_beyond_the_taut_depth(moment):
    s = np.linspace(0.0, H, 2001)
    stress = BEAM.axial_stress(s, moment)
    assert np.all(stress >= -1e-12 * P / H)
    c = float(BEAM.taut_depth(moment))
    assert np.all(stress[s > c] == 0.0)


@pytest.mark.parametrize("moment", MOMENTS)
def test_plane_sections_and_tension_only_material(moment):
    """The strain is linear over the whole depth, N = E t max(strain, 0), and the curvature is
    minus its slope."""
    s = np.linspace(0.0, H, 41)
    strain = BEAM.axial_strain(s, moment)
    assert np.abs(np.diff(strain, 2)).max() <= 1e-12 * np.abs(strain).max()
    assert BEAM.axial_stress(s, moment) == pytest.approx(
        ET * np.maximum(strain, 0.0), rel=1e-12, abs=1e-12 * P / H
    )
    slope = (strain[-1] - strain[0]) / H
    assert -slope == pytest.approx(float(BEAM.curvature(moment)), rel=1e-10)


@pytest.mark.parametrize("moment", [0.05 * P * H, 0.2 * P * H, 0.3 * P * H, 0.45 * P * H])
def test_curvature_is_the_derivative_of_the_complementary_energy(moment):
    """kappa = du*/dM with u* by quadrature of N^2/(2 E t) and a central difference."""
    step = 1e-5 * P * H
    derivative = (
        complementary_energy_by_quadrature(moment + step)
        - complementary_energy_by_quadrature(moment - step)
    ) / (2 * step)
    assert derivative == pytest.approx(float(BEAM.curvature(moment)), rel=1e-7)
    assert float(BEAM.complementary_energy(moment)) == pytest.approx(
        complementary_energy_by_quadrature(moment), rel=1e-11
    )


def test_continuity_at_the_onset():
    onset = P * H / 6
    below, above = onset * (1 - 1e-9), onset * (1 + 1e-9)
    s = np.linspace(0.0, H, 11)
    assert BEAM.axial_stress(s, below) == pytest.approx(
        BEAM.axial_stress(s, above), rel=1e-7, abs=1e-7 * P / H
    )
    for name in ("curvature", "taut_depth", "complementary_energy"):
        assert float(getattr(BEAM, name)(below)) == pytest.approx(
            float(getattr(BEAM, name)(above)), rel=1e-7
        )
    assert float(BEAM.taut_depth(onset)) == pytest.approx(H, rel=1e-15)
    assert float(BEAM.axial_stress(H, onset)) == pytest.approx(0.0, abs=1e-12 * P / H)
    # at the root: the onset load, no wrinkles below it, a wrinkled zone just above it
    assert BEAM.onset_load == pytest.approx(V_SLACK / 3, rel=1e-15)
    assert float(BEAM.wrinkled_length(BEAM.onset_load * (1 - 1e-9))) == 0.0
    assert 0 < float(BEAM.wrinkled_length(BEAM.onset_load * (1 + 1e-6))) < 1e-5 * L
    f = np.array([1 / 3 - 1e-9, 1 / 3 + 1e-9])
    deflection = BEAM.tip_deflection(f * V_SLACK)
    assert deflection[0] == pytest.approx(deflection[1], rel=1e-7)


def test_the_slack_limit():
    """c -> 0 as M -> P h/2 (the whole force at the tension edge), the curvature grows like
    1/c^2, and the tip deflection like 2 P^3 / (9 E t V_slack^2 (1 - f)); at or beyond the
    limit the theory has no answer."""
    for gap in (1e-3, 1e-6):
        moment = 0.5 * P * H * (1 - gap)
        assert float(BEAM.taut_depth(moment)) == pytest.approx(1.5 * H * gap, rel=1e-6)
        # the stress resultant of the last sliver still passes through the tension edge
        assert stress_integral(lambda s: 0.5 * H - s, moment) == pytest.approx(moment, rel=1e-9)
    f = 1 - 1e-8
    assert (1 - f) * float(BEAM.tip_deflection(f * V_SLACK)) == pytest.approx(
        2 * P**3 / (9 * ET * V_SLACK**2), rel=1e-6
    )
    with pytest.raises(ValueError, match="slack"):
        BEAM.taut_depth(0.5 * P * H)
    with pytest.raises(ValueError, match="V_slack"):
        BEAM.tip_deflection(V_SLACK)
    with pytest.raises(ValueError):
        BEAM.curvature(-1e-9)


@pytest.mark.parametrize("fraction", [0.1, 1 / 3])
def test_taut_tip_deflection_is_the_linear_timoshenko_beam(fraction):
    V = fraction * V_SLACK
    bending_stiffness = ET * H**3 / 12
    expected = V * L**3 / (3 * bending_stiffness) + 6 * V * L / (5 * GT * H)
    assert float(BEAM.tip_deflection(V)) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("fraction", [0.2, 0.5, 0.8, 0.9, 0.99])
def test_tip_deflection_by_quadrature_of_curvature_and_shear_strain(fraction):
    """eq. (8) integrated numerically, against the closed form (9)."""
    V = fraction * V_SLACK
    x_w = float(BEAM.wrinkled_length(V))
    points = [x_w] if 0 < x_w < L else None

    def integral(function):
        return quad(function, 0.0, L, points=points, epsabs=0, epsrel=1e-12, limit=400)[0]

    bending = integral(lambda x: float(BEAM.curvature(BEAM.moment(x, V))) * (L - x))
    shear = integral(lambda x: float(BEAM.shear_strain(BEAM.moment(x, V), V)))
    assert float(BEAM.tip_deflection(V, shear=False)) == pytest.approx(bending, rel=1e-9)
    assert float(BEAM.tip_deflection(V)) == pytest.approx(bending + shear, rel=1e-9)


@pytest.mark.parametrize("fraction", [0.25, 0.6, 0.9])
def test_bending_deflection_is_the_derivative_of_the_complementary_energy(fraction):
    """Castigliano: w_L (bending) = d/dV integral_0^L u*(V (L - x)) dx, the energy by
    quadrature of N^2 / (2 E t) over the section and along the beam, a central difference in
    V."""

    def energy(V):
        x_w = float(BEAM.wrinkled_length(V))
        return quad(
            lambda x: complementary_energy_by_quadrature(float(BEAM.moment(x, V))),
            0.0,
            L,
            points=[x_w] if 0 < x_w < L else None,
            epsabs=0,
            epsrel=1e-12,
            limit=200,
        )[0]

    V = fraction * V_SLACK
    step = 1e-4 * V
    derivative = (energy(V + step) - energy(V - step)) / (2 * step)
    assert derivative == pytest.approx(float(BEAM.tip_deflection(V, shear=False)), rel=1e-6)


@pytest.mark.parametrize("fraction", [0.2, 0.6, 0.9])
def test_parabolic_shear_flow_balances_the_axial_stress(fraction):
    """dN_xy/ds = -dN/dx (finite difference in x) for N_xy = 6 V s (c - s)/c^3; it carries V,
    and its energy-consistent mean strain is the closed-form shear strain."""
    V = fraction * V_SLACK
    x = 0.25 * L
    M = float(BEAM.moment(x, V))
    c = float(BEAM.taut_depth(M))
    s = np.linspace(0.05, 0.95, 7) * c
    dx = 1e-6 * L
    dN_dx = (
        BEAM.axial_stress(s, BEAM.moment(x + dx, V)) - BEAM.axial_stress(s, BEAM.moment(x - dx, V))
    ) / (2 * dx)
    dNxy_ds = 6 * V * (c - 2 * s) / c**3
    assert dNxy_ds == pytest.approx(-dN_dx, rel=1e-6, abs=1e-8 * V / c**2)
    flow = quad(lambda t: 6 * V * t * (c - t) / c**3, 0.0, c, epsrel=1e-13)[0]
    assert flow == pytest.approx(V, rel=1e-12)
    mean_strain = (
        quad(lambda t: (6 * V * t * (c - t) / c**3) ** 2 / GT, 0.0, c, epsrel=1e-13)[0] / V
    )
    assert float(BEAM.shear_strain(M, V)) == pytest.approx(mean_strain, rel=1e-10)


@pytest.mark.parametrize("fraction", [0.5, 0.9])
def test_compressed_edge_strain_changes_sign_at_the_wrinkled_length(fraction):
    V = fraction * V_SLACK
    x_w = float(BEAM.wrinkled_length(V))
    assert x_w == pytest.approx(L - P * H / (6 * V), rel=1e-14)
    assert float(BEAM.moment(x_w, V)) == pytest.approx(P * H / 6, rel=1e-12)
    strain = BEAM.compressed_edge_strain(np.array([x_w - 1e-6 * L, x_w + 1e-6 * L]), V)
    assert strain[0] < 0 < strain[1]


@pytest.mark.parametrize("fraction", [0.4, 0.9])
def test_transverse_tension_keeps_the_taut_depth_taut(fraction):
    """At q = 8 V^2 / (3 P c) the root section is just taut: min over s of
    N_x q - N_xy^2 = 0 (brute force over the taut depth), negative for a smaller q."""
    V = fraction * V_SLACK
    q = float(BEAM.transverse_tension_needed(V))
    M = float(BEAM.moment(0.0, V))
    c = float(BEAM.taut_depth(M))
    s = np.linspace(0.0, c, 200001)
    N = BEAM.axial_stress(s, M)
    shear = 6 * V * s * (c - s) / c**3
    margin = N * q - shear**2
    assert margin.min() == pytest.approx(0.0, abs=1e-9 * (P / H) * q)
    assert (N * 0.99 * q - shear**2).min() < 0


def test_sign_change_interpolates_the_last_crossing():
    x = np.linspace(0.05, 0.95, 10)
    strain = 2.0 * (x - 0.37)
    assert sign_change(x, strain) == pytest.approx(0.37, rel=1e-12)
    noisy = strain.copy()
    noisy[0] = 0.01  # a stretched first segment at the root does not end the wrinkled zone
    assert sign_change(x, noisy) == pytest.approx(0.37, rel=1e-12)
    assert sign_change(x, np.abs(strain) + 1e-3) == 0.0
    assert sign_change(x, -np.abs(strain) - 1e-3) == x[-1]


def test_compressed_edge_strain_of_a_homogeneous_stretch():
    """u = (e x, -e y / 2) on a rectangle: every segment of the edge y = h has strain e."""
    mesh = rectangle(2.0, 0.5, 8, 3)
    e = 1e-3
    u = np.zeros_like(mesh.nodes)
    u[:, 0] = e * mesh.nodes[:, 0]
    u[:, 1] = -0.5 * e * mesh.nodes[:, 1]
    x, strain = compressed_edge_strain(SimpleNamespace(mesh=mesh), u.ravel(), 0.5)
    assert x == pytest.approx(np.linspace(0.125, 1.875, 8), rel=1e-14)
    assert strain == pytest.approx(np.full(8, e), rel=1e-12)


def test_case_file_tolerances_hold_a_model_difference_and_a_discretisation_part():
    """Each tolerance of the case file is at least its model-difference allowance, and the
    quick run's are no tighter than the full run's."""
    settings = read_case_data(CASE)["verification"]
    model, full, quick = (settings[k] for k in ("model_difference", "tolerance", "quick_tolerance"))
    assert len(full["deflection"]) == len(settings["deflection_checks"])
    for key in ("onset", "wrinkled_length"):
        assert model[key] <= full[key] <= quick[key]
    for m, f, q in zip(model["deflection"], full["deflection"], quick["deflection"]):
        assert m < f <= q
