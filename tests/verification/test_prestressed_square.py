"""The closed-form onset of the prestressed-square benchmark against the material law."""

import numpy as np
import pytest

from verification.benchmarks.prestressed_square import onset_shortening
from wrinkle.materials import Prestressed, StVenantKirchhoff


@pytest.mark.parametrize("n", [0.1, 10.0, 500.0])
def test_onset_cancels_the_prestress_along_x(n):
    """At F = diag(1 - d_c/L, 1) the prestressed law's N_xx is zero and N_yy = n (1 - nu)."""
    E, nu, t, L = 2.5e9, 0.3, 25e-6, 2.0
    material = Prestressed(StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=t), n)
    d = onset_shortening(E, nu, t, n, L)
    C = np.diag([(1 - d / L) ** 2, 1.0])[None]
    N = material.response(C).stress[0]
    assert abs(N[0, 0]) < 1e-12 * E * t
    assert N[1, 1] == pytest.approx(n * (1 - nu), rel=1e-9)
