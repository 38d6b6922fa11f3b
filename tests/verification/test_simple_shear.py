"""Simple shear: the small-strain tension-field closed form against the exact homogeneous
solution from the relaxed energy (an independent minimisation), and the reason it wrinkles."""

from __future__ import annotations

import numpy as np
import pytest

from verification.references.simple_shear import exact_homogeneous, tension_field
from wrinkle.materials import StVenantKirchhoff

E, NU, THICKNESS = 2.5e9, 0.3, 25e-6


@pytest.fixture(scope="module")
def material():
    return StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS)


@pytest.mark.parametrize("gamma", [1e-3, 1e-4])
def test_closed_form_is_the_small_strain_limit(material, gamma):
    """N1 and N_xy of the exact solution exceed the closed form by 1.5 gamma (relative), to
    O(gamma^2); the tension direction is tilted from 45 degrees by gamma / 4 radians."""
    closed = tension_field(E, THICKNESS, gamma)
    exact = exact_homogeneous(material, gamma)
    assert exact["state"] == "wrinkled"
    for key in ("N1", "N_xy"):
        excess = exact[key] / closed[key] - 1.0
        assert excess == pytest.approx(1.5 * gamma, rel=10 * gamma)
    assert abs(exact["angle"] - 45.0) == pytest.approx(np.degrees(gamma) / 4.0, rel=10 * gamma)


def test_uniaxial_tension_field_has_equal_components():
    """Uniaxial N1 at 45 degrees: N_xx = N_yy = N_xy = N1 / 2 (Mohr's circle through 0)."""
    closed = tension_field(E, THICKNESS, 1e-3)
    assert closed["N_xy"] == pytest.approx(closed["N1"] / 2.0, rel=1e-15)
    assert closed["angle"] == 45.0


def test_the_taut_solution_would_be_compressed(material):
    """Without wrinkling (the plain material) the minor principal stress of simple shear is
    -E t gamma / (2 (1 + nu)) to O(gamma^2): compressive, hence the tension field."""
    gamma = 1e-4
    F = np.array([[1.0, gamma], [0.0, 1.0]])
    C = F.T @ F
    stress = material.response(C[None], tangent=False).stress[0]
    minor = np.linalg.eigvalsh(F @ stress @ F.T)[0]
    expected = -E * THICKNESS * gamma / (2.0 * (1.0 + NU))
    assert minor == pytest.approx(expected, rel=5 * gamma)
