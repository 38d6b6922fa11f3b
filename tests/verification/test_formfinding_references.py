"""The closed forms of the catenoid, cable-arc and membrane-frequency benchmarks, checked
independently: the catenoid's first integral by finite differences, the circle fit on exact
points, the frequencies from their own definitions."""

import math

import numpy as np
import pytest
from scipy.special import jv

from verification.benchmarks.cable_arc import fitted_circle
from verification.benchmarks.membrane_frequencies import disk_frequencies, rectangle_frequencies
from verification.references.catenoid import neck_radius, profile


@pytest.mark.parametrize("span", [0.2, 1.0, 1.3])
def test_catenoid_meets_the_rings_and_has_zero_mean_curvature(span):
    """r(0) = r(h) = R; the first integral r / sqrt(1 + r'^2) = r0 holds (r' by central
    differences); it is the larger root, where r arccosh(R / r) falls with r."""
    R = 1.0
    r0 = neck_radius(R, span)
    assert profile(np.array([0.0, span]), R, span) == pytest.approx([R, R], rel=1e-12)
    x = np.linspace(0.05, span - 0.05, 9) * 1.0
    step = 1e-6
    slope = (profile(x + step, R, span) - profile(x - step, R, span)) / (2 * step)
    np.testing.assert_allclose(profile(x, R, span) / np.sqrt(1 + slope**2), r0, rtol=1e-8)

    def half_span(r):
        return r * math.acosh(R / r)

    assert half_span(r0 * (1 + 1e-6)) < half_span(r0) < half_span(r0 * (1 - 1e-6))


def test_catenoid_refuses_a_span_too_long():
    with pytest.raises(ValueError, match="no catenoid"):
        neck_radius(1.0, 1.4)


def test_circle_fit_is_exact_on_points_of_a_circle():
    angles = np.linspace(0.3, 1.2, 7)
    points = np.stack([2.0 + 0.7 * np.cos(angles), -1.0 + 0.7 * np.sin(angles)], axis=1)
    centre, radius = fitted_circle(points)
    np.testing.assert_allclose(centre, [2.0, -1.0], atol=1e-12)
    assert radius == pytest.approx(0.7, rel=1e-12)


def test_rectangle_frequencies_are_the_sorted_f_mk():
    """a = 1, b = 0.5, speed 2: f = sqrt(m^2 + 4 k^2), the lowest five by hand:
    (1,1) sqrt5, (2,1) sqrt8, (3,1) sqrt13, (1,2) sqrt17, (4,1) sqrt20."""
    expected = np.sqrt([5.0, 8.0, 13.0, 17.0, 20.0])
    np.testing.assert_allclose(rectangle_frequencies(1.0, 0.5, 2.0, 5), expected, rtol=1e-14)


def test_disk_frequencies_are_zeros_of_bessel_functions_with_multiplicity():
    """Each z = 2 pi R f / speed is a zero of some J_j; the order j01, j11 (x2), j21 (x2),
    j02, j31 (x2)."""
    f = disk_frequencies(0.5, 3.0, 8)
    z = 2 * math.pi * 0.5 * f / 3.0
    orders = [0, 1, 1, 2, 2, 0, 3, 3]
    np.testing.assert_allclose([jv(j, zz) for j, zz in zip(orders, z, strict=True)], 0, atol=1e-12)
    assert np.all(np.diff(z) >= 0)
