"""Tests of the batched membrane materials against finite differences and closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from wrinkle.materials import (
    Material,
    MooneyRivlin,
    NeoHookean,
    Ogden,
    StVenantKirchhoff,
    green_lagrange_voigt,
    voigt_stress,
)

D0 = 0.1


def random_spd_stiffness(seed: int = 3) -> np.ndarray:
    """A general 6x6 SPD stiffness: couples every in-plane and out-of-plane component."""
    A = np.random.default_rng(seed).normal(size=(6, 6))
    return A @ A.T + 2.0 * np.eye(6)


MATERIALS = {
    "svk_isotropic": lambda: StVenantKirchhoff.isotropic(E=2.0, nu=0.3, thickness=D0),
    "svk_transversely_isotropic": lambda: StVenantKirchhoff.transversely_isotropic(
        E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=D0
    ),
    "svk_general": lambda: StVenantKirchhoff(random_spd_stiffness(), thickness=D0),
    "nh_incompressible": lambda: NeoHookean(mu=1.5, thickness=D0),
    "nh_compressible": lambda: NeoHookean(mu=1.5, thickness=D0, lmbda=4.0),
    "mooney_rivlin": lambda: MooneyRivlin(C10=0.6, C01=0.15, thickness=D0),
    "ogden": lambda: Ogden(mu=[0.63, 0.0012, -0.01], alpha=[1.3, 5.0, -2.0], thickness=D0),
}


def random_C(n: int = 20, size: float = 0.25, seed: int = 0) -> np.ndarray:
    """C = F^T F with F near identity: a mix of stretch, compression and shear."""
    rng = np.random.default_rng(seed)
    F = np.eye(2) + size * rng.uniform(-1.0, 1.0, size=(n, 2, 2))
    return np.einsum("nka,nkb->nab", F, F)


# Symmetric unit perturbations of C and their Voigt strain counterparts.
C_DIRECTIONS = [
    np.array([[1.0, 0.0], [0.0, 0.0]]),
    np.array([[0.0, 0.0], [0.0, 1.0]]),
    np.array([[0.0, 1.0], [1.0, 0.0]]),
]


def fd_stress(material: Material, C: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """N from energy: N : dC = 2 dw, so N_11 = 2 dw/dC11, N_22 = 2 dw/dC22 and, perturbing
    C12 and C21 together by h, N_12 = dw/dh."""
    N = np.empty_like(C)
    for k, dC in enumerate(C_DIRECTIONS):
        dw = (material.energy(C + h * dC) - material.energy(C - h * dC)) / (2.0 * h)
        if k < 2:
            N[:, k, k] = 2.0 * dw
        else:
            N[:, 0, 1] = N[:, 1, 0] = dw
    return N


def fd_tangent(material: Material, C: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """dN_voigt/dE_voigt: a step h in E11 (E22) changes C11 (C22) by 2h; a step h in the
    engineering shear 2 E12 changes C12 = C21 by h."""
    T = np.empty((len(C), 3, 3))
    for j, dC in enumerate(C_DIRECTIONS):
        dC = 2.0 * dC if j < 2 else dC
        plus = voigt_stress(material.response(C + h * dC, tangent=False).stress)
        minus = voigt_stress(material.response(C - h * dC, tangent=False).stress)
        T[:, :, j] = (plus - minus) / (2.0 * h)
    return T


@pytest.fixture(params=sorted(MATERIALS))
def material(request: pytest.FixtureRequest) -> Material:
    return MATERIALS[request.param]()


# ---------------------------------------------------------------- consistency, every material
def test_is_material(material: Material) -> None:
    assert isinstance(material, Material)
    assert material.thickness == D0


def test_shapes_and_no_tangent(material: Material) -> None:
    C = random_C(7)
    r = material.response(C)
    assert r.stress.shape == (7, 2, 2)
    assert r.tangent.shape == (7, 3, 3)
    assert r.thickness.shape == (7,)
    assert material.energy(C).shape == (7,)
    r2 = material.response(C, tangent=False)
    assert r2.tangent is None
    np.testing.assert_array_equal(r2.stress, r.stress)
    np.testing.assert_array_equal(r2.thickness, r.thickness)


def test_undeformed_state_is_stress_free(material: Material) -> None:
    C = np.tile(np.eye(2), (3, 1, 1))
    r = material.response(C)
    np.testing.assert_allclose(r.stress, 0.0, atol=1e-14)
    np.testing.assert_allclose(r.thickness, D0, rtol=1e-14)
    np.testing.assert_allclose(material.energy(C), 0.0, atol=1e-15)


def test_stress_is_energy_derivative(material: Material) -> None:
    C = random_C()
    N = material.response(C).stress
    np.testing.assert_allclose(N, N.transpose(0, 2, 1), rtol=0, atol=0)
    scale = np.max(np.abs(N))
    np.testing.assert_allclose(fd_stress(material, C), N, rtol=1e-7, atol=1e-7 * scale)


def test_tangent_is_stress_derivative(material: Material) -> None:
    C = random_C()
    T = material.response(C).tangent
    scale = np.max(np.abs(T))
    np.testing.assert_allclose(fd_tangent(material, C), T, rtol=1e-6, atol=1e-6 * scale)


def test_tangent_is_symmetric_and_positive_near_identity(material: Material) -> None:
    T = material.response(random_C(size=0.05)).tangent
    np.testing.assert_allclose(T, T.transpose(0, 2, 1), rtol=1e-13, atol=1e-15)
    assert np.all(np.linalg.eigvalsh(T) > 0.0)


def test_energy_is_positive_away_from_identity(material: Material) -> None:
    assert np.all(material.energy(random_C()) > 0.0)


# ---------------------------------------------------------------- St Venant-Kirchhoff
def test_svk_isotropic_plane_stress_matrix() -> None:
    E, nu = 3.0, 0.27
    m = StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=D0)
    expected = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    np.testing.assert_allclose(m.plane_stress_stiffness, expected, rtol=1e-14)
    np.testing.assert_allclose(m.response(random_C(4)).tangent, np.tile(D0 * expected, (4, 1, 1)))


def test_svk_isotropic_uniaxial_stress() -> None:
    E, nu, eps = 3.0, 0.27, 0.02
    m = StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=D0)
    C = np.array([[[1 + 2 * eps, 0.0], [0.0, 1 - 2 * nu * eps]]])  # E11 = eps, E22 = -nu eps
    N = m.response(C).stress[0]
    np.testing.assert_allclose(N, [[E * D0 * eps, 0.0], [0.0, 0.0]], atol=1e-15)


def test_svk_isotropic_thickness() -> None:
    nu = 0.35
    m = StVenantKirchhoff.isotropic(E=1.0, nu=nu, thickness=D0)
    C = random_C()
    e = green_lagrange_voigt(C)
    E33 = -nu / (1 - nu) * (e[:, 0] + e[:, 1])
    np.testing.assert_allclose(m.response(C).thickness, D0 * np.sqrt(1 + 2 * E33), rtol=1e-14)


def test_svk_transversely_isotropic_compliance() -> None:
    """Uniaxial stress along L and along T recover E_L, nu_LT and E_T, nu_TL = nu_LT E_T/E_L;
    pure shear recovers G_LT."""
    E_L, E_T, nu_LT, nu_TT, G_LT = 5.0, 1.0, 0.3, 0.3, 1.0 / 2.6
    m = StVenantKirchhoff.transversely_isotropic(E_L, E_T, nu_LT, nu_TT, G_LT, thickness=D0)
    compliance = np.linalg.inv(m.plane_stress_stiffness)
    expected = np.array(
        [[1 / E_L, -nu_LT / E_L, 0.0], [-nu_LT / E_L, 1 / E_T, 0.0], [0.0, 0.0, 1 / G_LT]]
    )
    np.testing.assert_allclose(compliance, expected, rtol=1e-13, atol=1e-15)
    # out of plane: E33 = -(nu_LT/E_L) S11 - (nu_TT/E_T) S22
    S = np.array([0.01, 0.02, 0.005])
    e_i = compliance @ S
    E33 = m.out_of_plane_strain[0] @ e_i
    np.testing.assert_allclose(E33, -nu_LT / E_L * S[0] - nu_TT / E_T * S[1], rtol=1e-13)


def test_svk_general_condensation_against_full_3d_solve() -> None:
    """Independent of the condensation formula: solve the 6x6 system H E = S with the
    in-plane strains prescribed and S33 = S23 = S13 = 0, point by point."""
    H = random_spd_stiffness()
    m = StVenantKirchhoff(H, thickness=D0)
    C = random_C(5)
    r = m.response(C)
    for k, e_i in enumerate(green_lagrange_voigt(C)):
        # unknowns: E33, 2E23, 2E13 (strain) and S11, S22, S12 (stress)
        A = np.zeros((6, 6))
        rhs = np.zeros(6)
        known = {0: e_i[0], 1: e_i[1], 5: e_i[2]}
        unknown_strain = [2, 3, 4]
        for row in range(6):
            rhs[row] = -sum(H[row, j] * v for j, v in known.items())
            A[row, :3] = H[row, unknown_strain]
            if row in (0, 1, 5):
                A[row, 3 + [0, 1, 5].index(row)] = -1.0
        x = np.linalg.solve(A, rhs)
        S_in = x[3:]
        np.testing.assert_allclose(voigt_stress(r.stress)[k], D0 * S_in, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(r.thickness[k], D0 * np.sqrt(1 + 2 * x[0]), rtol=1e-12)


def test_svk_thickness_never_nan_at_absurd_strain() -> None:
    m = StVenantKirchhoff.isotropic(E=1.0, nu=0.45, thickness=D0)
    C = np.array([[[20.0, 0.0], [0.0, 20.0]]])  # E33 = -0.45/0.55 * 19 < -1/2
    D = m.response(C).thickness
    assert np.all(np.isfinite(D)) and np.all(D > 0.0) and D[0] < 1e-100


# ---------------------------------------------------------------- neo-Hookean
@pytest.mark.parametrize("stretch", [0.8, 1.0, 1.3, 2.5])
def test_nh_incompressible_equibiaxial(stretch: float) -> None:
    """Incompressible neo-Hookean, equibiaxial stretch l: Cauchy stress sigma = mu (l^2 - l^-4)
    (sigma33 = 0); S = F^-1 sigma F^-T = sigma/l^2 = mu (1 - l^-6); thickness D0/l^2."""
    mu = 1.7
    m = NeoHookean(mu=mu, thickness=D0)
    C = np.array([stretch**2 * np.eye(2)])
    r = m.response(C)
    sigma = mu * (stretch**2 - stretch**-4)
    np.testing.assert_allclose(r.stress[0], D0 * sigma / stretch**2 * np.eye(2), atol=1e-15)
    np.testing.assert_allclose(r.stress[0, 0, 0], mu * D0 * (1 - stretch**-6), rtol=1e-13)
    np.testing.assert_allclose(r.thickness, D0 / stretch**2, rtol=1e-14)


@pytest.mark.parametrize("stretch", [1.1, 2.0, 4.0])
def test_nh_incompressible_uniaxial(stretch: float) -> None:
    """Uniaxial tension: lateral stretch l^-1/2, Cauchy stress mu (l^2 - 1/l), S11 = sigma/l^2,
    N22 = 0, thickness D0 l^-1/2."""
    mu = 1.7
    m = NeoHookean(mu=mu, thickness=D0)
    C = np.array([np.diag([stretch**2, 1.0 / stretch])])
    r = m.response(C)
    sigma = mu * (stretch**2 - 1.0 / stretch)
    np.testing.assert_allclose(r.stress[0, 0, 0], D0 * sigma / stretch**2, rtol=1e-13)
    np.testing.assert_allclose(r.stress[0, 1, 1], 0.0, atol=1e-15)
    np.testing.assert_allclose(r.thickness, D0 / np.sqrt(stretch), rtol=1e-14)


def test_nh_nearly_incompressible_limit() -> None:
    """lmbda/mu = 1e5 is within ~1e-4 (relative) of the incompressible law, and the gap closes
    like mu/lmbda (ten times smaller than at lmbda/mu = 1e4)."""
    mu = 1.0
    C = random_C(size=0.25)
    r0 = NeoHookean(mu=mu, thickness=D0).response(C)
    w0 = NeoHookean(mu=mu, thickness=D0).energy(C)

    def gaps(lmbda: float) -> np.ndarray:
        m = NeoHookean(mu=mu, thickness=D0, lmbda=lmbda)
        r = m.response(C)
        return np.array(
            [
                np.abs(r.stress - r0.stress).max() / np.abs(r0.stress).max(),
                np.abs(r.thickness / r0.thickness - 1.0).max(),
                np.abs(r.tangent - r0.tangent).max() / np.abs(r0.tangent).max(),
                np.abs(m.energy(C) / w0 - 1.0).max(),
            ]
        )

    coarse, fine = gaps(1e4 * mu), gaps(1e5 * mu)
    assert np.all(fine < 3e-4)
    np.testing.assert_allclose(coarse / fine, 10.0, rtol=0.02)


def _nh_3d_second_piola_kirchhoff(mu: float, lmbda: float, C3: np.ndarray) -> np.ndarray:
    """S = mu (I - C^-1) + lmbda ln J C^-1 for full 3x3 C, (n, 3, 3), general linear algebra."""
    C3_inv = np.linalg.inv(C3)
    ln_J = 0.5 * np.log(np.linalg.det(C3))
    return mu * (np.eye(3) - C3_inv) + lmbda * ln_J[:, None, None] * C3_inv


@pytest.mark.parametrize("size", [0.25, 0.8])
def test_nh_compressible_plane_stress_in_3d(size: float) -> None:
    mu, lmbda = 1.5, 4.0
    m = NeoHookean(mu=mu, thickness=D0, lmbda=lmbda)
    C = random_C(size=size, seed=5)
    C = C[np.linalg.det(C) > 1e-3]
    r = m.response(C)
    C3 = np.zeros((len(C), 3, 3))
    C3[:, :2, :2] = C
    C3[:, 2, 2] = (r.thickness / D0) ** 2
    S = _nh_3d_second_piola_kirchhoff(mu, lmbda, C3)
    np.testing.assert_allclose(S[:, 2, 2], 0.0, atol=1e-13 * mu)
    np.testing.assert_allclose(S[:, :2, 2], 0.0, atol=1e-15)
    np.testing.assert_allclose(D0 * S[:, :2, :2], r.stress, rtol=1e-12, atol=1e-14)


def test_nh_compressible_energy_is_minimum_over_thickness() -> None:
    """Plane stress makes w(C) the minimum of D0 Psi(diag(C, C33)) over C33."""
    mu, lmbda = 1.5, 4.0
    m = NeoHookean(mu=mu, thickness=D0, lmbda=lmbda)
    C = random_C(5, size=0.5, seed=9)
    C33 = (m.response(C).thickness / D0) ** 2
    ln_det = np.log(np.linalg.det(C))

    def psi(c33: np.ndarray) -> np.ndarray:
        ln_J = 0.5 * (ln_det + np.log(c33))
        trace = C[:, 0, 0] + C[:, 1, 1] + c33
        return D0 * (0.5 * mu * (trace - 3) - mu * ln_J + 0.5 * lmbda * ln_J**2)

    w = m.energy(C)
    np.testing.assert_allclose(w, psi(C33), rtol=1e-14)
    for factor in (0.99, 1.01):
        assert np.all(psi(factor * C33) > w)


def test_nh_compressible_extreme_strains_converge() -> None:
    m = NeoHookean(mu=1.0, thickness=D0, lmbda=0.5)
    C = np.array([np.diag([1e4, 1e4]), np.diag([1e-4, 1e-4]), np.diag([1e3, 1e-3])])
    r = m.response(C)
    assert np.all(np.isfinite(r.stress)) and np.all(np.isfinite(r.tangent))
    C33 = (r.thickness / D0) ** 2
    ln_J = 0.5 * (np.log(np.linalg.det(C)) + np.log(C33))
    residual = (C33 - 1) + 0.5 * ln_J  # mu (C33 - 1) + lmbda ln J
    assert np.all(np.abs(residual) <= 1e-12 * np.maximum(1.0, C33))


@pytest.mark.parametrize("lmbda", [None, 2.0])
def test_nh_collapsed_element(lmbda: float | None) -> None:
    m = NeoHookean(mu=1.0, thickness=D0, lmbda=lmbda)
    C = np.array([np.eye(2), [[1.0, 1.0], [1.0, 1.0]], [[1.0, 2.0], [2.0, 1.0]]])
    w = m.energy(C)
    assert np.isfinite(w[0]) and np.all(np.isinf(w[1:]) & (w[1:] > 0))
    with pytest.raises(ValueError, match=r"det C .* at point 1"):
        m.response(C)


# ---------------------------------------------------------------- bad input
def _stiffness(kind: str) -> np.ndarray:
    H = random_spd_stiffness()
    if kind == "asymmetric":
        H[0, 1] += 0.1
    elif kind == "indefinite":
        H[2, 2] = -1.0
    elif kind == "nan":
        H[3, 3] = np.nan
    elif kind == "shape":
        H = H[:5, :5]
    return H


TI = {"E_L": 5.0, "E_T": 1.0, "nu_LT": 0.3, "nu_TT": 0.3, "G_LT": 0.4, "thickness": D0}

BAD_PARAMETERS = [
    (lambda: StVenantKirchhoff(_stiffness("shape"), D0), "stiffness must have shape"),
    (lambda: StVenantKirchhoff(_stiffness("nan"), D0), "stiffness must be finite"),
    (lambda: StVenantKirchhoff(_stiffness("asymmetric"), D0), "stiffness must be symmetric"),
    (lambda: StVenantKirchhoff(_stiffness("indefinite"), D0), "stiffness must be positive def"),
    (lambda: StVenantKirchhoff(np.zeros((6, 6)), D0), "stiffness must be positive def"),
    (lambda: StVenantKirchhoff(random_spd_stiffness(), 0.0), "thickness"),
    (lambda: StVenantKirchhoff(random_spd_stiffness(), np.inf), "thickness"),
    (lambda: StVenantKirchhoff.isotropic(E=0.0, nu=0.3, thickness=D0), "E must"),
    (lambda: StVenantKirchhoff.isotropic(E=np.nan, nu=0.3, thickness=D0), "E must"),
    (lambda: StVenantKirchhoff.isotropic(E=1.0, nu=0.5, thickness=D0), "nu must"),
    (lambda: StVenantKirchhoff.isotropic(E=1.0, nu=-1.0, thickness=D0), "nu must"),
    (lambda: StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=-1.0), "thickness"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "E_L": -5.0}), "E_L must"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "E_T": 0.0}), "E_T must"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "G_LT": 0.0}), "G_LT must"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "nu_TT": 1.0}), "nu_TT must"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "nu_LT": 1.6}), "nu_LT must"),
    (lambda: StVenantKirchhoff.transversely_isotropic(**{**TI, "thickness": 0}), "thickness"),
    (lambda: NeoHookean(mu=0.0, thickness=D0), "mu must"),
    (lambda: NeoHookean(mu=-1.0, thickness=D0, lmbda=1.0), "mu must"),
    (lambda: NeoHookean(mu=1.0, thickness=0.0), "thickness must"),
    (lambda: NeoHookean(mu=1.0, thickness=np.nan), "thickness must"),
    (lambda: NeoHookean(mu=1.0, thickness=D0, lmbda=0.0), "lmbda must"),
    (lambda: NeoHookean(mu=1.0, thickness=D0, lmbda=np.inf), "lmbda must"),
    (lambda: MooneyRivlin(C10=0.0, C01=0.1, thickness=D0), "C10 must"),
    (lambda: MooneyRivlin(C10=1.0, C01=-0.1, thickness=D0), "C01 must be finite and >= 0"),
    (lambda: MooneyRivlin(C10=1.0, C01=np.nan, thickness=D0), "C01 must"),
    (lambda: MooneyRivlin(C10=1.0, C01=0.0, thickness=0.0), "thickness must"),
    (lambda: Ogden(mu=[], alpha=[], thickness=D0), "mu must be a non-empty list"),
    (lambda: Ogden(mu=[1.0, 2.0], alpha=[2.0], thickness=D0), "mu and alpha must have the same"),
    (lambda: Ogden(mu=[np.inf], alpha=[2.0], thickness=D0), "mu must be finite"),
    (lambda: Ogden(mu=[1.0], alpha=[0.0], thickness=D0), "alpha must be finite and nonzero"),
    (lambda: Ogden(mu=[1.0], alpha=[-2.0], thickness=D0), "shear modulus .* must be > 0"),
    (lambda: Ogden(mu=[1.0, -1.0], alpha=[2.0, 2.0], thickness=D0), "mu and alpha: the shear"),
    (lambda: Ogden(mu=[1.0], alpha=[2.0], thickness=-1.0), "thickness must"),
]


@pytest.mark.parametrize("build, message", BAD_PARAMETERS)
def test_bad_parameters_raise(build, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()


@pytest.mark.parametrize("material_name", sorted(MATERIALS))
def test_bad_shape_of_C_raises(material_name: str) -> None:
    m = MATERIALS[material_name]()
    with pytest.raises(ValueError, match="shape"):
        m.response(np.eye(2))
    with pytest.raises(ValueError, match="shape"):
        m.energy(np.zeros((4, 3, 3)))


# -- is_isotropic: whether the fibre direction matters -------------------------------------

E_ISO, NU_ISO = 2.0, 0.3


def equal_moduli(nu_TT: float = NU_ISO, shear_factor: float = 1.0) -> StVenantKirchhoff:
    """Transversely isotropic law with E_L = E_T, G_LT = shear_factor E / (2 (1 + nu))."""
    return StVenantKirchhoff.transversely_isotropic(
        E_L=E_ISO,
        E_T=E_ISO,
        nu_LT=NU_ISO,
        nu_TT=nu_TT,
        G_LT=shear_factor * E_ISO / (2.0 * (1.0 + NU_ISO)),
        thickness=D0,
    )


@pytest.mark.parametrize(
    "build, expected",
    [
        (lambda: StVenantKirchhoff.isotropic(E=E_ISO, nu=NU_ISO, thickness=D0), True),
        # fibre five times stiffer than the cross direction
        (
            lambda: StVenantKirchhoff.transversely_isotropic(
                E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=D0
            ),
            False,
        ),
        # E_L = E_T and G = E / (2 (1 + nu)): isotropic in the plane, whatever nu_TT
        (lambda: equal_moduli(), True),
        (lambda: equal_moduli(nu_TT=0.1), True),
        # E_L = E_T but an inconsistent shear modulus: not isotropic
        (lambda: equal_moduli(shear_factor=1.01), False),
        (lambda: StVenantKirchhoff(random_spd_stiffness(), thickness=D0), False),
        (lambda: NeoHookean(mu=1.5, thickness=D0), True),
        (lambda: NeoHookean(mu=1.5, thickness=D0, lmbda=4.0), True),
        (lambda: MooneyRivlin(C10=0.6, C01=0.15, thickness=D0), True),
        (lambda: Ogden(mu=[0.63, 0.0012, -0.01], alpha=[1.3, 5.0, -2.0], thickness=D0), True),
    ],
    ids=[
        "svk-isotropic",
        "svk-transverse-f5",
        "svk-transverse-f1",
        "svk-transverse-f1-nuTT",
        "svk-transverse-f1-bad-shear",
        "svk-general",
        "nh-incompressible",
        "nh-compressible",
        "mooney-rivlin",
        "ogden",
    ],
)
def test_is_isotropic(build, expected: bool) -> None:
    material = build()
    assert material.is_isotropic is expected
    assert isinstance(material, Material)


def test_is_isotropic_is_read_only() -> None:
    material = StVenantKirchhoff.isotropic(E=E_ISO, nu=NU_ISO, thickness=D0)
    with pytest.raises(AttributeError):
        material.is_isotropic = False  # type: ignore[misc]


def test_isotropic_tangent_is_the_same_in_every_frame() -> None:
    """What is_isotropic promises: rotating C by any angle rotates N and nothing else."""
    from wrinkle.materials.base import rotate_voigt_tangent

    m = StVenantKirchhoff.transversely_isotropic(
        E_L=E_ISO,
        E_T=E_ISO,
        nu_LT=NU_ISO,
        nu_TT=NU_ISO,
        G_LT=E_ISO / (2.0 * (1.0 + NU_ISO)),
        thickness=D0,
    )
    Q = m.plane_stress_stiffness
    for angle in np.linspace(0.0, np.pi, 7):
        assert np.allclose(rotate_voigt_tangent(Q, angle), Q, rtol=0, atol=1e-13 * Q.max())
    # the rotation itself: a 90-degree turn swaps the axes of an orthotropic tangent
    f5 = StVenantKirchhoff.transversely_isotropic(
        E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=D0
    )
    turned = rotate_voigt_tangent(f5.plane_stress_stiffness, np.pi / 2)
    assert np.allclose(turned[[1, 0, 2]][:, [1, 0, 2]], f5.plane_stress_stiffness)
