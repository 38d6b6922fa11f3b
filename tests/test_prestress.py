"""Tests of the membrane prestress (wrinkle.materials.prestress) and of the state criterion
that measures slackness from the stress-free state (wrinkle.wrinkling).

References: central finite differences of the energy and of the stress (the helpers of
test_materials), the plain law (zero prestress), the closed form of St Venant-Kirchhoff with
its reference strain shifted, the relaxed energy minimised by a generic optimiser
(verification.references.relaxed_energy, which shares no code with wrinkle.wrinkling), and the
closed-form onset of wrinkling of a prestressed square compressed in one direction.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SQUARE_CASE
from test_materials import fd_stress, fd_tangent
from test_wrinkling import _points_in_state

from verification.references.relaxed_energy import relax, stress_free_state
from wrinkle import Model, compiled, element_report, material_response, read_case, rectangle
from wrinkle.materials import NeoHookean, Prestressed, StVenantKirchhoff
from wrinkle.wrinkling import SLACK, TAUT, WRINKLED, Wrinkling

E, NU, T = 2.0, 0.3, 0.5
SVK = StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=T)

# prestresses of a few per cent of the stiffness E t: the random deformations of
# test_wrinkling (stretches 0.85 to 1.2) then reach every state
PRESTRESSED = {
    "svk-isotropic": lambda: Prestressed(SVK, 0.02),
    "svk-transverse-anisotropic": lambda: Prestressed(
        StVenantKirchhoff.transversely_isotropic(
            E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1 / 2.6, thickness=1.0
        ),
        [0.06, 0.02, 0.01],
    ),
    "neo-hookean-anisotropic": lambda: Prestressed(
        NeoHookean(mu=1.0, thickness=1.0, lmbda=3.0), [0.03, 0.05, -0.01]
    ),
}
STATES = {"taut": TAUT, "wrinkled": WRINKLED, "slack": SLACK}


def _C(F: np.ndarray) -> np.ndarray:
    return np.einsum("nki,nkj->nij", F, F)


def _steady(wrinkling: Wrinkling, C: np.ndarray, state: int, h: float = 1e-5) -> np.ndarray:
    """The rows of C (n, 2, 2) whose state stays ``state`` for every step of +-h (and 2h) in
    each component: there the finite differences see one smooth branch."""
    keep = wrinkling.response(C, tangent=False).state == state
    for i, j in ((0, 0), (1, 1), (0, 1)):
        dC = np.zeros((2, 2))
        dC[i, j] = dC[j, i] = 2 * h
        for sign in (1, -1):
            keep &= wrinkling.response(C + sign * dC, tangent=False).state == state
    return C[keep]


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("name", PRESTRESSED)
def test_stress_is_energy_gradient_and_tangent_is_stress_derivative(name, state):
    """Through the tension-field wrapper: N = 2 dw_rel/dC and dN/dE by central differences,
    relative 1e-7 (of the largest entry), in each state."""
    material = PRESTRESSED[name]()
    wrinkling = Wrinkling(material)
    C = _steady(wrinkling, _C(_points_in_state(material, STATES[state], n=10)), STATES[state])
    assert C.shape[0] >= 6
    r = wrinkling.response(C)
    scale = max(np.abs(r.stress).max(), 1e-3 * np.abs(r.tangent).max(), 1e-300)
    np.testing.assert_allclose(fd_stress(wrinkling, C), r.stress, rtol=0, atol=1e-7 * scale)
    tangent_scale = max(np.abs(r.tangent).max(), 1e-3 * wrinkling.reference_stiffness)
    np.testing.assert_allclose(
        fd_tangent(wrinkling, C), r.tangent, rtol=0, atol=1e-7 * tangent_scale
    )


@pytest.mark.parametrize("name", PRESTRESSED)
def test_wrinkled_and_slack_states_minimise_the_relaxed_energy(name):
    """Independent reference: min over A >= 0 of w(C + A) by a generic minimiser, with the
    stress-free state found by minimising w itself (not by Prestressed's Newton)."""
    material = PRESTRESSED[name]()
    C0 = stress_free_state(material)
    np.testing.assert_allclose(material.stress_free_state, C0, atol=1e-8)
    for state in ("wrinkled", "slack"):
        F = _points_in_state(material, STATES[state], n=3)
        for C in _C(F):
            point = material_response(material, np.linalg.cholesky(C).T)
            reference = relax(material, C, stress_free=C0)
            assert point.state == reference.state == state
            scale = np.abs(material.prestress).max()
            np.testing.assert_allclose(point.stress, reference.stress, atol=1e-8 * scale)
            assert point.energy == pytest.approx(reference.energy, rel=1e-9)


@pytest.mark.parametrize("prestress", [0.0, [0.0, 0.0, 0.0]])
@pytest.mark.parametrize(
    "material",
    [SVK, NeoHookean(mu=1.0, thickness=1.0, lmbda=3.0)],
    ids=["svk", "neo-hookean"],
)
def test_zero_prestress_is_the_plain_material(material, prestress):
    prestressed = Prestressed(material, prestress)
    assert prestressed.is_isotropic == material.is_isotropic
    F = np.eye(2) + 0.25 * np.random.default_rng(3).uniform(-1, 1, size=(200, 2, 2))
    C = _C(F)
    plain, wrapped = Wrinkling(material).response(C), Wrinkling(prestressed).response(C)
    assert set(plain.state) == {TAUT, WRINKLED, SLACK}
    np.testing.assert_array_equal(wrapped.state, plain.state)
    for field in ("stress", "tangent", "thickness", "energy", "wrinkle_angle"):
        np.testing.assert_allclose(
            getattr(wrapped, field), getattr(plain, field), rtol=1e-14, atol=1e-15
        )


def test_svk_isotropic_prestress_is_a_shifted_reference_strain():
    """St Venant-Kirchhoff, N0 = n I: N = t Q (E - E0) with E0 = -n (1 - nu)/(E t) (1, 1, 0)
    (Q (1, 1, 0) = E/(1 - nu) (1, 1, 0)), so N(C) = N_svk(C - 2 E0), the stress-free state is
    C0 = (1 - 2 n (1 - nu)/(E t)) I and w = w_svk(C - 2 E0) - w_svk(I - 2 E0), whose slack
    value is -n^2 (1 - nu)/(E t)."""
    n = 0.03
    material = Prestressed(SVK, n)
    shift = 2 * n * (1 - NU) / (E * T)  # -2 E0
    C = _C(np.eye(2) + 0.2 * np.random.default_rng(4).uniform(-1, 1, size=(50, 2, 2)))
    r, shifted = material.response(C), SVK.response(C + shift * np.eye(2))
    np.testing.assert_allclose(r.stress, shifted.stress, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(r.tangent, shifted.tangent)
    np.testing.assert_allclose(
        material.energy(C),
        SVK.energy(C + shift * np.eye(2)) - SVK.energy((1 + shift) * np.eye(2)[None]),
        rtol=0,
        atol=1e-15,
    )
    np.testing.assert_allclose(material.stress_free_state, (1 - shift) * np.eye(2), atol=1e-15)
    wrinkling = Wrinkling(material)
    assert wrinkling.slack_energy == pytest.approx(-(n**2) * (1 - NU) / (E * T), rel=1e-12)
    # slackness is measured from C0, not from C = I: between C0 and I the prestressed sheet
    # is taut (N = n/2 I) where the plain one is slack; below C0 both are slack; and with one
    # stretch above C0 it wrinkles, where the plain sheet (both stretches below 1) is slack
    cases = {
        "between": ((1 - 0.5 * shift) * np.eye(2), "taut", "slack"),
        "below": ((1 - 1.5 * shift) * np.eye(2), "slack", "slack"),
        "one above": (np.diag([1 - 0.5 * shift, 1 - 2 * shift]), "wrinkled", "slack"),
    }
    for C_case, prestressed_state, plain_state in cases.values():
        assert material_response(material, np.sqrt(C_case)).state == prestressed_state
        assert material_response(SVK, np.sqrt(C_case)).state == plain_state
    between = material_response(material, np.sqrt(cases["between"][0]))
    np.testing.assert_allclose(between.stress, 0.5 * n * np.eye(2), rtol=1e-12)


def test_prestress_tensor_is_in_the_material_frame():
    """[n11, n22, n12] is the stress in the material frame: turning the frame by 90 degrees
    swaps n11 and n22, and an anisotropic prestress makes the material anisotropic."""
    a = Prestressed(SVK, [0.05, 0.01, 0.0])
    b = Prestressed(SVK, [0.01, 0.05, 0.0])
    assert not a.is_isotropic and Prestressed(SVK, [0.02, 0.02, 0.0]).is_isotropic
    F = np.diag([1.0, 0.995])
    swap = np.array([[0.0, 1.0], [1.0, 0.0]])
    np.testing.assert_allclose(
        material_response(a, F).stress,
        swap @ material_response(b, swap @ F @ swap).stress @ swap,
        atol=1e-15,
    )


@pytest.mark.parametrize(
    "prestress, message",
    [
        (-1.0, ">= 0"),
        ([0.1, -0.01, 0.0], "positive semidefinite"),
        ([0.1, 0.1, 0.2], "positive semidefinite"),
        ([0.1, 0.1], "n11, n22, n12"),
        (float("nan"), "finite"),
        (E * T, "no stress-free state"),  # SVK: C0 = (1 - 2 n (1 - nu)/(E t)) I < 0
    ],
)
def test_bad_prestress_raises(prestress, message):
    with pytest.raises(ValueError, match=message):
        Prestressed(SVK, prestress)


# ------------------------------------------------------------------ the prestressed square
SHEET = StVenantKirchhoff.isotropic(E=1000.0, nu=0.3, thickness=0.01)  # E t = 10 N/m


def _square(prestress, shortening: float, fibre=(1.0, 0.0, 0.0), nx: int = 6) -> Model:
    """A unit square, prestressed, its edges x = 0 and x = 1 moved towards each other by
    ``shortening`` (the edge x = 1 by -shortening along x, x = 0 held), the edges y = 0 and
    y = 1 held in y and free to slide in x, all edges held in z."""
    model = Model(rectangle(1.0, 1.0, nx, nx))
    model.assign_material(Prestressed(SHEET, prestress), fibre_direction=fibre)
    free = np.nan
    model.prescribe("x == 0", [0.0, free, 0.0])
    model.prescribe("x == 1", [-shortening, free, 0.0])
    model.prescribe("y == 0 or y == 1", [free, 0.0, 0.0])
    return model


def test_prestressed_square_at_zero_load_is_taut_with_the_prestress():
    n = 0.05
    model = _square(n, 0.0)
    report = element_report(model, np.zeros(model.n_dofs))
    assert np.all(report.state == TAUT)
    noise = 64 * np.finfo(float).eps * model.materials[0].reference_stiffness
    np.testing.assert_allclose(
        report.stress, np.broadcast_to(n * np.eye(2), report.stress.shape), rtol=0, atol=noise
    )
    # uniform stress: the interior nodes balance, the held edges take n per unit length
    system = model.discretise()
    forces = system.internal_forces(np.zeros(model.n_dofs))
    scale = n * 1.0  # the edge force, N
    np.testing.assert_allclose(forces[~model.constrained], 0.0, atol=1e-14 * scale)
    right = model.mesh.nodes[:, 0] == 1.0
    assert forces.reshape(-1, 3)[right, 0].sum() == pytest.approx(n, rel=1e-13)


@pytest.mark.parametrize(
    "prestress, fibre, n_xx, n_yy",
    [
        (0.05, (1.0, 0.0, 0.0), 0.05, 0.05),
        # anisotropic, fibres along y: material axis 1 = y, so N_xx = n22 and N_yy = n11
        ([0.04, 0.07, 0.0], (0.0, 1.0, 0.0), 0.07, 0.04),
    ],
    ids=["isotropic", "anisotropic-fibres-along-y"],
)
def test_prestressed_square_wrinkles_where_the_load_cancels_the_prestress(
    prestress, fibre, n_xx, n_yy
):
    """The square of ``_square`` deforms homogeneously, F = diag(lambda, 1) with
    lambda = 1 - shortening. Taut, SVK: N_xx = n_xx + k E_xx, N_yy = n_yy + k nu E_xx with
    k = E t/(1 - nu^2), E_xx = (lambda^2 - 1)/2, E_yy = 0. N_xx vanishes, and the square
    wrinkles (N_yy stays > 0), at E_xx = -n_xx/k:

        shortening_c = 1 - sqrt(1 - 2 n_xx (1 - nu^2)/(E t)).

    Past it the tension field is N_xx = 0, N_yy = n_yy - nu n_xx (the relaxed E_xx keeps
    N_xx = 0 at -n_xx/k). Checked: every element taut at 0.995 shortening_c, every element
    wrinkled at 1.005 (the onset within 0.5 %), with these stresses."""
    k = 1000.0 * 0.01 / (1 - 0.3**2)
    critical = 1 - np.sqrt(1 - 2 * n_xx / k)
    swap = fibre[1] == 1.0  # material frame (y, x)
    for factor, state in ((0.995, TAUT), (1.005, WRINKLED)):
        model = _square(prestress, factor * critical, fibre)
        u = model.solve(steps=2, tolerance=1e-12).final.displacement
        report = element_report(model, u)
        assert np.all(report.state == state)
        stress = report.stress[:, ::-1, ::-1] if swap else report.stress  # -> global x, y
        stretch = 1 - factor * critical
        strain = 0.5 * (stretch**2 - 1)
        if state == TAUT:
            expected = [n_xx + k * strain, n_yy + k * 0.3 * strain]
        else:
            expected = [0.0, n_yy - 0.3 * n_xx]
        np.testing.assert_allclose(stress[:, 0, 0], expected[0], atol=1e-8 * n_xx)
        np.testing.assert_allclose(stress[:, 1, 1], expected[1], rtol=1e-8)
        np.testing.assert_allclose(stress[:, 0, 1], 0.0, atol=1e-8 * n_xx)


@pytest.mark.parametrize(
    "value, expected",
    [("2.5", 2.5 * np.eye(2)), ("[3.0, 1.0, 0.5]", np.array([[3.0, 0.5], [0.5, 1.0]]))],
)
def test_case_file_prestress_per_region(tmp_path, value, expected):
    """``prestress`` of a [material] table wraps its law in Prestressed, in each region."""
    path = tmp_path / "case.toml"
    path.write_text(SQUARE_CASE.replace("nu = 0.3", f"nu = 0.3\nprestress = {value}"))
    material = read_case(path).model.materials[0].material
    assert isinstance(material, Prestressed)
    np.testing.assert_array_equal(material.prestress, expected)
    assert isinstance(material.material, StVenantKirchhoff)


@pytest.mark.skipif(not compiled.installed(), reason="numba not installed")
def test_prestressed_square_same_with_and_without_compiled_kernels(monkeypatch):
    """The Numba kernels take the stress and tangent as arrays, so they serve Prestressed as
    any material: forces, stiffness and energy of a square with taut, wrinkled and slack
    elements (shortened more and more along x and y towards x = 1, and twisted out of
    plane) agree to round-off."""
    model = _square([0.05, 0.02, 0.01], 0.0, fibre=(1.0, 1.0, 0.0), nx=8)
    X = model.mesh.nodes
    u = np.column_stack(
        [-0.008 * X[:, 0] ** 2, -0.008 * X[:, 1] ** 2 * X[:, 0], 0.002 * X[:, 0] * X[:, 1]]
    ).ravel()
    evaluations = {}
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)
        model.assign_material(model.materials[0])  # discretised anew with the kernel set
        assert model.discretise().compiled == (switch == "1")
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
    np.testing.assert_allclose(
        K.data, K_numpy.data, rtol=0, atol=1e-12 * np.abs(K_numpy.data).max()
    )
    assert compiled_ev.energy == pytest.approx(numpy_ev.energy, rel=1e-13)
