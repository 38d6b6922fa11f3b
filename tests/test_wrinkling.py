"""Material-point tests of the wrinkling wrapper (wrinkle.wrinkling, wrinkle.material_response).

References: the plain material law (taut), the paper's conditions on the Cauchy stress of the
modified deformation (Part II, eqs. 31-33), the minor principal direction of C (isotropy), and
the relaxed energy min over A >= 0 of w(C + A) computed by a generic minimiser in
verification.references (Pipkin 1986), which shares no code with wrinkle.wrinkling.
"""

import numpy as np
import pytest

from verification.references.relaxed_energy import relax
from wrinkle import material_response
from wrinkle.materials import NeoHookean, StVenantKirchhoff
from wrinkle.wrinkling import TAUT, WRINKLED, Wrinkling

RNG = np.random.default_rng(20261122)


def _random_spd_stiffness():
    rng = np.random.default_rng(7)
    A = rng.normal(size=(6, 6))
    return A @ A.T + 3.0 * np.eye(6)


MATERIALS = {
    "svk-isotropic": StVenantKirchhoff.isotropic(E=2.0, nu=0.3, thickness=0.5),
    "svk-transverse-f5": StVenantKirchhoff.transversely_isotropic(
        E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1 / 2.6, thickness=1.0
    ),
    "svk-general": StVenantKirchhoff(_random_spd_stiffness(), thickness=1.0),
    "neo-hookean": NeoHookean(mu=1.0, thickness=1.0),
    "neo-hookean-compressible": NeoHookean(mu=1.0, thickness=1.0, lmbda=3.0),
}
ISOTROPIC = ("svk-isotropic", "neo-hookean", "neo-hookean-compressible")


def _rotation(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def _random_deformations(n, rng=RNG):
    """In-plane F = R diag(l1, l2) Q with stretches around 1, off-axis (random R, Q)."""
    out = []
    for _ in range(n):
        l1, l2 = rng.uniform(0.85, 1.2, size=2)
        out.append(
            _rotation(rng.uniform(0, np.pi)) @ np.diag([l1, l2]) @ _rotation(rng.uniform(0, np.pi))
        )
    return np.array(out)


def _points_in_state(material, state, n=8, rng=RNG):
    wrinkling = Wrinkling(material)
    F = _random_deformations(400, rng)
    C = np.einsum("nki,nkj->nij", F, F)
    r = wrinkling.response(C, tangent=False)
    chosen = np.flatnonzero(r.state == state)[:n]
    assert chosen.size == n, f"too few {state} points among the random deformations"
    return F[chosen]


@pytest.mark.parametrize("name", MATERIALS)
def test_taut_equals_plain_law(name):
    material = MATERIALS[name]
    for F in _points_in_state(material, TAUT, n=4):
        point = material_response(material, F)
        plain = material.response((F.T @ F)[None])
        assert point.state == "taut"
        np.testing.assert_allclose(point.stress, plain.stress[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(point.tangent, plain.tangent[0], rtol=0, atol=1e-13)
        assert np.all(np.linalg.eigvalsh(point.stress) >= 0)


@pytest.mark.parametrize("name", MATERIALS)
def test_slack_gives_zero_stress(name):
    material = MATERIALS[name]
    F = np.diag([0.97, 0.9]) @ _rotation(0.4)
    point = material_response(material, F)
    assert point.state == "slack"
    assert np.all(point.stress == 0) and np.all(point.tangent == 0)
    assert point.energy == 0
    assert point.thickness == material.thickness


@pytest.mark.parametrize("name", MATERIALS)
def test_wrinkled_state_satisfies_the_papers_conditions(name):
    """n1.(J sigma').n1 = n1.(J sigma').n2 = 0, n2.(J sigma').n2 >= 0 (Part II, eqs. 31-32)
    for J sigma' = F' S' F'^T with F' = (I + beta n1 n1) F, and F'^T F' = C + b w w."""
    material = MATERIALS[name]
    for F2 in _points_in_state(material, WRINKLED):
        F = np.vstack([F2, np.zeros(2)])  # (3, 2): the membrane in the plane z = 0
        point = material_response(material, F)
        assert point.state == "wrinkled"
        C = F.T @ F
        w = point.wrinkle_direction
        n1 = F @ np.linalg.solve(C, w)
        n1 /= np.linalg.norm(n1)
        n2 = F @ point.tension_direction
        n2 /= np.linalg.norm(n2)
        assert abs(n1 @ n2) < 1e-12
        beta = point.wrinkling_strain
        assert beta >= 0
        F_mod = (np.eye(3) + beta * np.outer(n1, n1)) @ F
        # the modified stretch tensor is C + b w w with b > 0 along the reported direction
        A = F_mod.T @ F_mod - C
        assert np.linalg.matrix_rank(A, tol=1e-12 * np.abs(A).max()) == 1
        np.testing.assert_allclose(A @ point.tension_direction, 0, atol=1e-13)
        # the stress is that of the plain law at the modified deformation
        plain = material.response((F_mod.T @ F_mod)[None])
        np.testing.assert_allclose(point.stress, plain.stress[0], atol=1e-13)
        kirchhoff = F_mod @ point.stress @ F_mod.T
        scale = np.abs(point.stress).max()
        assert abs(n1 @ kirchhoff @ n1) < 1e-12 * scale
        assert abs(n1 @ kirchhoff @ n2) < 1e-12 * scale
        assert n2 @ kirchhoff @ n2 > 0
        np.testing.assert_allclose(point.thickness, plain.thickness[0], rtol=1e-14)


@pytest.mark.parametrize("name", ["svk-isotropic", "svk-transverse-f5", "svk-general"])
def test_wrinkled_state_is_plane_stress_in_3d(name):
    """The 3-D St. Venant-Kirchhoff law at the modified in-plane strain E' with the
    out-of-plane strains that make S33 = S23 = S13 = 0 (eq. 33) gives the reported thickness and
    the reported membrane stress."""
    material = MATERIALS[name]
    H = material.stiffness
    inplane, outplane = [0, 1, 5], [2, 3, 4]
    for F in _points_in_state(material, WRINKLED, n=4):
        point = material_response(material, F)
        w = point.wrinkle_direction
        b = ((1 + point.wrinkling_strain) ** 2 - 1) / (w @ np.linalg.solve(F.T @ F, w))
        E = 0.5 * (F.T @ F + b * np.outer(w, w) - np.eye(2))
        strain = np.zeros(6)
        strain[inplane] = E[0, 0], E[1, 1], 2 * E[0, 1]
        strain[outplane] = np.linalg.solve(
            H[np.ix_(outplane, outplane)], -H[np.ix_(outplane, inplane)] @ strain[inplane]
        )
        S = H @ strain
        assert np.abs(S[outplane]).max() < 1e-12 * np.abs(S).max()
        assert point.thickness == pytest.approx(
            material.thickness * np.sqrt(1 + 2 * strain[2]), rel=1e-12
        )
        np.testing.assert_allclose(
            material.thickness * S[inplane], point.stress[[0, 1, 0], [0, 1, 1]], atol=1e-13
        )


@pytest.mark.parametrize("name", ISOTROPIC)
def test_isotropic_wrinkle_direction_is_minor_principal_direction_of_C(name):
    material = MATERIALS[name]
    for F in _points_in_state(material, WRINKLED):
        point = material_response(material, F)
        _, vectors = np.linalg.eigh(F.T @ F)
        assert abs(abs(vectors[:, 0] @ point.wrinkle_direction) - 1) < 1e-12


@pytest.mark.parametrize("name", MATERIALS)
def test_wrinkled_stress_is_gradient_of_relaxed_energy(name):
    """Independent reference: generic minimisation of w(C + A) over A >= 0, for random
    off-axis deformations; also 2 d w_rel / dC by central differences of that minimum."""
    material = MATERIALS[name]
    for F in _points_in_state(material, WRINKLED, n=5):
        C = F.T @ F
        point = material_response(material, F)
        reference = relax(material, C)
        assert reference.state == "wrinkled"
        scale = np.abs(reference.stress).max()
        np.testing.assert_allclose(point.stress, reference.stress, atol=1e-9 * scale)
        np.testing.assert_allclose(point.energy, reference.energy, rtol=1e-10)
    # finite differences of the minimised energy at the last point
    h = 1e-6
    for i, j in ((0, 0), (1, 1), (0, 1)):
        dC = np.zeros((2, 2))
        dC[i, j] = dC[j, i] = h
        slope = (relax(material, C + dC).energy - relax(material, C - dC).energy) / (2 * h)
        expected = slope if i == j else slope / 2  # dC01 and dC10 move together
        assert point.stress[i, j] == pytest.approx(2 * expected, rel=1e-6, abs=1e-8 * scale)


@pytest.mark.parametrize("name", MATERIALS)
def test_wrinkled_tangent_matches_finite_difference(name):
    material = MATERIALS[name]
    wrinkling = Wrinkling(material)
    F = _points_in_state(material, WRINKLED, n=10)
    C = np.einsum("nki,nkj->nij", F, F)
    r = wrinkling.response(C)
    h = 1e-7
    for k, (i, j) in enumerate(((0, 0), (1, 1), (0, 1))):
        dC = np.zeros((2, 2))
        dC[i, j] = dC[j, i] = 2 * h if i == j else h  # dE11 = h, or engineering 2 dE12 = h
        plus = wrinkling.response(C + dC, tangent=False)
        minus = wrinkling.response(C - dC, tangent=False)
        same = (plus.state == WRINKLED) & (minus.state == WRINKLED)
        assert same.sum() >= 8
        slope = (plus.stress - minus.stress)[same] / (2 * h)
        fd = np.stack([slope[:, 0, 0], slope[:, 1, 1], slope[:, 0, 1]], -1)
        np.testing.assert_allclose(
            r.tangent[same][:, :, k], fd, atol=1e-6 * np.abs(r.tangent).max()
        )
    np.testing.assert_allclose(r.tangent, r.tangent.transpose(0, 2, 1), atol=1e-12)


def test_criterion_follows_the_paper():
    """Taut when both principal stresses are >= 0, wrinkled when one is negative but a
    principal strain is positive, slack otherwise (Part II, section 3)."""
    material = MATERIALS["svk-isotropic"]
    assert material_response(material, np.diag([1.05, 1.05])).state == "taut"
    assert material_response(material, np.diag([1.05, 0.98])).state == "wrinkled"
    assert material_response(material, np.diag([0.99, 0.98])).state == "slack"
    assert material_response(material, np.eye(2)).state == "taut"


def test_uniaxial_closed_form():
    """Isotropic SVK pulled along x with lateral contraction beyond Poisson's: N11 = E t E11,
    the wrinkling strain restores the lateral length that uniaxial tension would give."""
    E, nu, t = 2.0, 0.3, 0.5
    material = StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=t)
    stretch, lateral = 1.1, 0.9
    point = material_response(material, np.diag([stretch, lateral]))
    E11 = 0.5 * (stretch**2 - 1)
    np.testing.assert_allclose(point.stress, [[E * t * E11, 0], [0, 0]], atol=1e-14)
    natural = np.sqrt(1 - 2 * nu * E11)  # lateral stretch of free uniaxial tension
    assert point.wrinkling_strain == pytest.approx(natural / lateral - 1, rel=1e-12)
    np.testing.assert_allclose(np.abs(point.tension_direction), [1, 0], atol=1e-14)
    # Cauchy resultant per unit current length of the mean (wrinkled) surface
    np.testing.assert_allclose(
        point.principal_stress, [0, E * t * E11 * stretch / lateral], rtol=1e-12, atol=1e-15
    )


def test_material_response_rejects_bad_input():
    material = MATERIALS["svk-isotropic"]
    with pytest.raises(ValueError, match="shaped"):
        material_response(material, np.eye(3))
    with pytest.raises(ValueError, match="singular"):
        material_response(material, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="finite"):
        material_response(material, np.array([[np.nan, 0], [0, 1]]))
