"""Natural frequencies (``wrinkle.modes``, issue 21 item 4), each against an independent
reference: exact integrals of the mass, the tensioned rectangle's and disk's frequencies,
the eigen-residual of the inflated airbag, synthetic spectra for the inertia logic."""

import json
import math
from pathlib import Path

import meshio
import numpy as np
import pytest
import scipy.linalg as la
import scipy.sparse as sp
from scipy.special import jn_zeros

from wrinkle import Model, StVenantKirchhoff, disk, rectangle
from wrinkle.case import read_case
from wrinkle.cli import main
from wrinkle.modes import (
    DENSE_LIMIT,
    consistent_mass,
    lumped_mass,
    natural_modes,
    solve_eigenproblem,
)
from wrinkle.solvers.stability import UNSTABLE

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

E, NU, THICKNESS, DENSITY = 1e6, 0.3, 1e-3, 1000.0  # Pa, -, m, kg/m^3: SI, so f in Hz
STRETCH = 1.01  # the uniform biaxial stretch of the edges


def membrane_tension(stretch: float = STRETCH) -> float:
    """Cauchy tension N (N per current metre) of the St Venant-Kirchhoff sheet under the
    equal biaxial stretch lambda: Green strain (lambda^2 - 1)/2 each way, S = E t / (1 - nu)
    times it (force per reference length), and N = F S F^T / det F = lambda^2 S / lambda^2
    = S."""
    return E * THICKNESS / (1.0 - NU) * (stretch**2 - 1.0) / 2.0


def stretched(mesh, boundary: np.ndarray, stretch: float = STRETCH) -> Model:
    """The sheet with density, its boundary nodes moved to lambda X (all components held)."""
    model = Model(
        mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS), density=DENSITY
    )
    X = mesh.nodes[boundary]
    displacement = np.zeros((boundary.size, 3))
    displacement[:, :2] = (stretch - 1.0) * X[:, :2]
    model.prescribe(boundary, displacement)
    return model


# -- mass -------------------------------------------------------------------------------
def test_mass_sums_to_the_total_mass_in_each_direction():
    """1^T M_c 1 per component = 1^T M_l 1 = sum rho t A0 (the disk's inscribed polygon's
    area from its formula), on a mesh of unequal triangles."""
    mesh = disk(0.8, 5, 13)
    model = Model(
        mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS), density=DENSITY
    )
    system = model.discretise()
    mu = model.mass_per_area()
    total = DENSITY * THICKNESS * 13 / 2 * math.sin(2 * math.pi / 13) * 0.8**2
    M = consistent_mass(system.pattern, system.geometry.area, mu)
    lumped = lumped_mass(system.pattern, system.geometry.area, mu)
    for component in range(3):
        ones = np.zeros(system.n_dofs)
        ones[component::3] = 1.0
        assert ones @ M @ ones == pytest.approx(total, rel=1e-12)
        assert ones @ (lumped * ones) == pytest.approx(total, rel=1e-12)
        other = np.zeros(system.n_dofs)
        other[(component + 1) % 3 :: 3] = 1.0
        assert ones @ M @ other == 0.0  # no coupling between components
    assert abs(M - M.T).max() == 0.0


def test_consistent_mass_is_exact_for_a_linear_field_and_lumped_is_not():
    """On the patch [0, 2] x [0, 1]: u^T M_c u = rho t int u^2 dA exactly for the linear
    field u = 1 + x + 2 y (the integral by its polynomial moments), while the lumped mass
    gives more (M_l - M_c is per element rho t A / 12 times a graph Laplacian, positive
    semidefinite) and the same for a constant."""
    mesh = rectangle(2.0, 1.0, 3, 2)
    model = Model(
        mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS), density=DENSITY
    )
    system = model.discretise()
    mu = model.mass_per_area()
    M = consistent_mass(system.pattern, system.geometry.area, mu)
    lumped = lumped_mass(system.pattern, system.geometry.area, mu)
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    u = np.zeros(system.n_dofs)
    u[1::3] = 1.0 + x + 2.0 * y
    # int (1 + x + 2y)^2 over [0,2]x[0,1] = int 1 + x^2 + 4y^2 + 2x + 4y + 4xy
    moments = 2.0 + 8.0 / 3.0 + 4.0 * 2.0 / 3.0 + 2.0 * 2.0 + 4.0 * 1.0 + 4.0 * 2.0 * 0.5
    exact = DENSITY * THICKNESS * moments
    assert u @ M @ u == pytest.approx(exact, rel=1e-12)
    assert u @ (lumped * u) > exact * (1 + 1e-3)
    constant = np.zeros(system.n_dofs)
    constant[1::3] = 3.0
    assert constant @ (lumped * constant) == pytest.approx(constant @ M @ constant, rel=1e-12)


# -- the tensioned rectangle -------------------------------------------------------------
A0, B0 = 1.0, 0.7  # reference sides, m


def rectangle_frequencies(count: int) -> np.ndarray:
    """f_mn = 1/2 sqrt(N / rho_a) sqrt((m/a)^2 + (n/b)^2), the lowest ``count``.

    The sheet is stretched by lambda each way into the flat rectangle a = lambda a0,
    b = lambda b0 under the uniform isotropic tension N (per current length,
    ``membrane_tension``); mass conservation gives the mass per current area
    rho_a = rho t0 / lambda^2. A small deflection w(x, y, t) of the flat taut state changes
    the strains only at second order, so only the tension resists it: the linearised
    balance in the current configuration is N (w_xx + w_yy) = rho_a w_tt, with w = 0 on the
    held edges. Separation, w = sin(m pi x / a) sin(n pi y / b) sin(omega t), gives
    omega^2 = (N / rho_a) pi^2 ((m/a)^2 + (n/b)^2) and f = omega / 2 pi the formula above.
    (The discrete K's geometric part int_A0 S grad0 w . grad0 w with S = N per reference
    length here is the same operator pulled back: the sides and the density scale alike.)
    """
    N = membrane_tension()
    rho_a = DENSITY * THICKNESS / STRETCH**2
    a, b = STRETCH * A0, STRETCH * B0
    values = sorted(
        0.5 * math.sqrt(N / rho_a) * math.hypot(m / a, n / b)
        for m in range(1, 8)
        for n in range(1, 8)
    )
    return np.array(values[:count])


def rectangle_modes(nx: int, mass: str):
    mesh = rectangle(A0, B0, nx, round(B0 * nx))
    X = mesh.nodes
    edge = np.isclose(X[:, 0], 0) | np.isclose(X[:, 0], A0) | np.isclose(X[:, 1], 0)
    edge |= np.isclose(X[:, 1], B0)
    model = stretched(mesh, np.flatnonzero(edge))
    results = model.solve(steps=1)
    return model, results, results.modes(6, mass=mass)


@pytest.fixture(scope="module")
def rectangle_errors():
    """Relative errors of the first six frequencies, {mass: (3 meshes, 6)}, and the modes of
    the finest meshes."""
    reference = rectangle_frequencies(6)
    errors, finest = {}, {}
    for mass in ("consistent", "lumped"):
        rows = []
        for nx in (20, 40, 80):
            model, results, modes = rectangle_modes(nx, mass)
            rows.append(modes.frequencies / reference - 1.0)
        errors[mass] = np.array(rows)
        finest[mass] = (model, results, modes)
    return errors, finest


def test_rectangle_frequencies_within_half_a_percent_on_the_finest_mesh(rectangle_errors):
    errors, _ = rectangle_errors
    for mass in ("consistent", "lumped"):
        assert np.abs(errors[mass][-1]).max() < 5e-3, (mass, errors[mass][-1])


def test_rectangle_frequencies_converge_at_second_order(rectangle_errors):
    """Halving h divides each error by 4: order log2(e_h / e_h/2) in [1.8, 2.2] for both
    masses; the consistent mass bounds each frequency from above, the lumped one (here)
    from below, with about a third of the error."""
    errors, _ = rectangle_errors
    for mass in ("consistent", "lumped"):
        e = np.abs(errors[mass])
        order = np.log2(e[:-1] / e[1:])
        assert np.all((order > 1.8) & (order < 2.2)), (mass, order)
    assert np.all(errors["consistent"] > 0)
    assert np.all(errors["lumped"] < 0)


def test_rectangle_modes_are_deflections_and_mass_orthonormal(rectangle_errors):
    """The six lowest are out-of-plane (the in-plane ones are far stiffer); Phi^T M Phi = I
    with the matrix built again; Phi^T K Phi = diag(omega^2) from the solver's tangent."""
    _, finest = rectangle_errors
    model, results, modes = finest["consistent"]
    system = model.discretise()
    shapes = modes.shapes.reshape(6, -1, 3)
    assert np.all(
        np.linalg.norm(shapes[:, :, 2], axis=1) > 0.999 * np.linalg.norm(modes.shapes, axis=1)
    )
    M = consistent_mass(system.pattern, system.geometry.area, model.mass_per_area())
    Phi = modes.shapes.T
    np.testing.assert_allclose(Phi.T @ M @ Phi, np.eye(6), atol=1e-9)
    K = system.at(1.0).evaluate(results.final.displacement).tangent
    free = ~system.constrained
    K_ff = K[free][:, free]
    P = Phi[free]
    np.testing.assert_allclose(
        P.T @ K_ff @ P, np.diag(modes.eigenvalues), atol=1e-7 * modes.eigenvalues.max()
    )


# -- the tensioned disk -------------------------------------------------------------------
def test_disk_frequencies_are_the_zeros_of_the_bessel_functions():
    """The disk of radius R stretched to a = lambda R: f = j_nk / (2 pi a) sqrt(N / rho_a),
    j_nk the k-th zero of J_n (the same balance as the rectangle's in polar coordinates,
    w = J_n(j_nk r / a) cos n theta; n >= 1 twice). First six: j_01, j_11 (2), j_21 (2),
    j_02; within 1 % on a 16-ring, 64-sector mesh (the polygon's area is 0.16 % short)."""
    R = 0.5
    mesh = disk(R, 16, 64)
    model = stretched(mesh, mesh.node_sets["outer"])
    modes = model.solve(steps=1).modes(6)
    zeros = [
        jn_zeros(0, 2)[0],
        *[jn_zeros(1, 1)[0]] * 2,
        *[jn_zeros(2, 1)[0]] * 2,
        jn_zeros(0, 2)[1],
    ]
    rho_a = DENSITY * THICKNESS / STRETCH**2
    reference = (
        np.array(zeros) / (2 * math.pi * STRETCH * R) * math.sqrt(membrane_tension() / rho_a)
    )
    np.testing.assert_allclose(modes.frequencies, reference, rtol=1e-2)


# -- the inflated airbag ------------------------------------------------------------------
def eigen_residual(model, results, modes, mass: str = "consistent") -> np.ndarray:
    """|K phi - omega^2 M phi| / |K phi| per mode, from the tangent and mass made again."""
    system = model.discretise()
    final = results.final
    K = system.at(final.load_factor).evaluate(final.displacement).tangent
    M = consistent_mass(system.pattern, system.geometry.area, model.mass_per_area())
    if mass == "lumped":
        M = sp.diags(lumped_mass(system.pattern, system.geometry.area, model.mass_per_area()))
    free = ~system.constrained
    Phi = modes.shapes.T[free]
    stiffness = K[free][:, free] @ Phi
    return np.linalg.norm(
        stiffness - (M[free][:, free] @ Phi) * modes.eigenvalues, axis=0
    ) / np.linalg.norm(stiffness, axis=0)


@pytest.mark.parametrize(
    "overrides",
    [
        {"mesh": {"rectangle": {"nx": 16, "ny": 16}}},
        {"material": {"density": 1000.0, "bending": True}},
    ],
    ids=["16x16", "32x32 with bending"],
)
def test_airbag_frequencies_are_finite_and_positive(overrides):
    """The inflated airbag (follower pressure, partly wrinkled, its tangent with the
    pressure's stiffness): ten finite positive frequencies, each an eigenpair of K and M to
    1e-8, where the state is stable (see the next test for the example as it stands)."""
    case = read_case(EXAMPLES / "airbag.toml", {"material": {"density": 1000.0}} | overrides)
    results = case.solve()
    assert results.final.states[1] > 0  # partly wrinkled
    modes = results.modes(10)
    assert np.all(np.isfinite(modes.frequencies)) and np.all(modes.frequencies > 0)
    assert np.all(np.diff(modes.frequencies) >= 0)
    assert eigen_residual(case.model, results, modes).max() < 1e-8


def test_airbag_example_reports_its_near_zero_negative_modes():
    """The example as it stands (32 x 32, no bending) balances in a state whose tangent has
    eigenvalues slightly below zero (wrinkled elements near the seam, whose zero stiffness
    across the wrinkles meets the pressure's negative stiffness; the 16 x 16 and 64 x 64
    meshes and bending have none): far above the instability threshold, so reported as
    negative frequencies, each still an eigenpair to 1e-8."""
    case = read_case(EXAMPLES / "airbag.toml", {"material": {"density": 1000.0}})
    results = case.solve()
    modes = results.modes(10)
    system = case.model.discretise()
    K = system.at(1.0).evaluate(results.final.displacement).tangent
    free = ~system.constrained
    scale = np.mean(np.abs(K.diagonal()[free])) / np.mean(
        consistent_mass(
            system.pattern, system.geometry.area, case.model.mass_per_area()
        ).diagonal()[free]
    )
    assert np.all(np.isfinite(modes.frequencies))
    assert modes.eigenvalues.min() > -UNSTABLE * scale
    assert np.all(np.diff(modes.frequencies) >= 0)
    assert eigen_residual(case.model, results, modes).max() < 1e-8


# -- the eigensolver on synthetic spectra -------------------------------------------------
def diagonal_problem(values: np.ndarray):
    n = values.size
    return sp.diags(values).tocsr(), sp.identity(n, format="csr")


def test_the_lowest_are_found_below_the_shift_too():
    """K = diag(-2.5, 1, 2, ..., 999), M = I: shift-invert about zero alone would give 1, 2,
    3; the inertia of K - sigma M counts the one below, a fourth is asked for, and it is
    found: -2.5, 1, 2."""
    K, M = diagonal_problem(np.concatenate([[-2.5], np.arange(1.0, 1000.0)]))
    values, vectors, _ = solve_eigenproblem(K, M, 3, symmetric=True)
    np.testing.assert_allclose(values, [-2.5, 1.0, 2.0])
    np.testing.assert_allclose(np.abs(vectors[[0, 1, 2], [0, 1, 2]]), 1.0)


@pytest.mark.parametrize("linear_solver", ["superlu", "pardiso"])
def test_shift_invert_at_its_tolerance_equals_the_dense_solution(linear_solver):
    """The tensioned 24 x 16 rectangle (1,035 free components, above DENSE_LIMIT, so
    shift-invert Lanczos at ARPACK's tolerance TOLERANCE, and PARDISO without iterative
    refinement): its ten lowest eigenvalues equal dense ``scipy.linalg.eigh``'s to 1e-10,
    each vector an eigenpair to 1e-9 (|K phi - lambda M phi| / |K phi|), M-normalised."""
    if linear_solver == "pardiso":
        pytest.importorskip("pypardiso")
    mesh = rectangle(1.0, 0.7, 24, 16)
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    edge = np.isclose(x, 0) | np.isclose(x, 1) | np.isclose(y, 0) | np.isclose(y, 0.7)
    model = stretched(mesh, np.flatnonzero(edge))
    u = model.solve(steps=1).final.displacement
    system = model.discretise()
    free = ~system.constrained
    K = system.at(1.0).evaluate(u).tangent[free][:, free].tocsr()
    M = consistent_mass(system.pattern, system.geometry.area, model.mass_per_area())
    M = M[free][:, free].tocsr()
    assert K.shape[0] > DENSE_LIMIT
    values, vectors, _ = solve_eigenproblem(K, M, 10, True, linear_solver=linear_solver)
    reference = la.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, 9])
    np.testing.assert_allclose(values, reference, rtol=1e-10)
    stiffness = K @ vectors
    residual = np.linalg.norm(stiffness - (M @ vectors) * values, axis=0)
    assert np.all(residual < 1e-9 * np.linalg.norm(stiffness, axis=0))
    np.testing.assert_allclose(np.einsum("ik,ik->k", vectors, M @ vectors), 1.0, rtol=1e-12)


def test_a_far_negative_eigenvalue_is_refused():
    """diag(-5, 1, ..., 999): the four nearest zero are 1 .. 4, and -5, which the inertia
    counts, is not among them."""
    K, M = diagonal_problem(np.concatenate([[-1e4], np.arange(1.0, 1000.0)]))
    with pytest.raises(ValueError, match="below the shift"):
        solve_eigenproblem(K, M, 3, symmetric=True)


def test_count_out_of_range_is_refused():
    """The 2 x 2 square with its boundary held has one free node: 1 .. 3 modes."""
    mesh = rectangle(1.0, 1.0, 2, 2)
    X = mesh.nodes
    inner = np.isclose(X[:, 0], 0.5) & np.isclose(X[:, 1], 0.5)
    model = stretched(mesh, np.flatnonzero(~inner))
    u = model.solve(steps=1).final.displacement
    assert len(natural_modes(model, u, 3)) == 3
    for count in (0, 4):
        with pytest.raises(ValueError, match=f"mode count {count} must be between 1 and"):
            natural_modes(model, u, count)


def test_a_model_without_density_is_refused():
    mesh = rectangle(1.0, 1.0, 2, 2)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS))
    model.fix("x == 0 or x == 1 or y == 0 or y == 1")
    with pytest.raises(ValueError, match="have no density, first: element 0"):
        natural_modes(model, np.zeros(model.n_dofs), 1)


# -- the case file and the command line ---------------------------------------------------
CASE = """
[mesh]
rectangle = {width = 1.0, height = 0.7, nx = 10, ny = 7}
units = {length = "m", force = "N"}

[material]
model = "svk"
E = 1e6
nu = 0.3
thickness = 1e-3
density = 1000.0

[[support]]
nodes = "x == 0 or x == 1 or y == 0 or y == 0.7"
displacement = ["0.01 * x", "0.01 * y", 0.0]

[solver]
steps = 1

[modes]
count = 6
"""


def test_modes_table_writes_frequencies_and_mode_files(tmp_path):
    """``[modes] count = 6``: summary.json "frequencies" ascending and equal to
    ``Results.modes``; mode_NN.vtu with a unit-amplitude "mode" field; modes.pvd lists them."""
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    frequencies = np.array(summary["frequencies"])
    assert frequencies.size == 6 and np.all(np.diff(frequencies) > 0)
    expected = read_case(path).solve().modes(6).frequencies
    np.testing.assert_allclose(frequencies, expected, rtol=1e-10)
    assert summary["modes"]["mass"] == "consistent"
    collection = (tmp_path / "out" / "modes.pvd").read_text()
    for index, name in enumerate(summary["modes"]["files"]):
        assert f'timestep="{index + 1}"' in collection and name in collection
        shape = meshio.read(tmp_path / "out" / name).point_data["mode"]
        assert np.linalg.norm(shape, axis=1).max() == pytest.approx(1.0)


def test_as_many_modes_as_free_components(tmp_path):
    """count = the free degrees of freedom (3 x 2 interior nodes, 18) is allowed and
    computed (densely): as many frequencies, all positive."""
    text = CASE.replace("nx = 10, ny = 7", "nx = 4, ny = 3").replace("count = 6", "count = 18")
    text = text.replace("height = 0.7", "height = 0.75").replace("y == 0.7", "y == 0.75")
    path = tmp_path / "case.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    frequencies = json.loads((tmp_path / "out" / "summary.json").read_text())["frequencies"]
    assert len(frequencies) == 18 and min(frequencies) > 0


# -- cable mass ---------------------------------------------------------------------------
def test_cable_mass_sums_to_its_mass_and_integrates_a_linear_field_exactly():
    """The cables' mass (``Cables.mass_matrix``): 1^T M 1 per component = m L for both
    kinds; the consistent one gives int m u^2 ds exactly for a field linear along each
    segment (m L (ua^2 + ua ub + ub^2) / 3 per segment), the lumped one m L (ua^2 + ub^2) / 2."""
    mesh = rectangle(1.0, 0.5, 4, 2)
    model = Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=THICKNESS))
    model.add_cables("y == 0", EA=10.0, mass_per_length=0.3)
    cables = model.discretise().cables
    n_dofs = model.n_dofs
    u = np.zeros(n_dofs)
    u[2::3] = 1.0 + 2.0 * mesh.nodes[:, 0]  # z = 1 + 2x along the cable y = 0
    a, b = cables.edges[:, 0], cables.edges[:, 1]
    ua, ub = u[3 * a + 2], u[3 * b + 2]
    exact = float(np.sum(0.3 * cables.length * (ua**2 + ua * ub + ub**2) / 3.0))
    lumped_exact = float(np.sum(0.3 * cables.length * (ua**2 + ub**2) / 2.0))
    for kind, integral in (("consistent", exact), ("lumped", lumped_exact)):
        M = cables.mass_matrix(kind, n_dofs)
        for component in range(3):
            ones = np.zeros(n_dofs)
            ones[component::3] = 1.0
            assert ones @ M @ ones == pytest.approx(0.3 * 1.0, rel=1e-12)
        assert u @ M @ u == pytest.approx(integral, rel=1e-12)


def test_modes_carry_the_cable_mass():
    """A cable of mass m per length along the middle line y = b0/2 of the tensioned
    rectangle (EA tiny, so it adds mass and no stiffness): every mode solves
    K phi = omega^2 (M_sheet + M_cable) phi, its Rayleigh quotient with that mass is its
    omega^2, and the lowest frequency falls below the bare sheet's, by the energy bound
    (omega^2 <= phi0^T K phi0 / phi0^T M phi0 with the bare sheet's first mode phi0)."""
    mesh = rectangle(A0, B0, 20, 14)
    X = mesh.nodes
    edge = np.isclose(X[:, 0], 0) | np.isclose(X[:, 0], A0) | np.isclose(X[:, 1], 0)
    edge |= np.isclose(X[:, 1], B0)
    bare = stretched(mesh, np.flatnonzero(edge))
    results = bare.solve(steps=1)
    plain = results.modes(3)
    loaded = stretched(mesh, np.flatnonzero(edge))
    sheet_mass = DENSITY * THICKNESS * A0
    loaded.add_cables(f"y == {B0 / 2}", EA=1e-9, mass_per_length=sheet_mass)
    u = results.steps[-1].displacement
    heavy = natural_modes(loaded, u, 3)
    system = loaded.discretise()
    K = system.at(1.0).evaluate(u).tangent
    M = consistent_mass(system.pattern, system.geometry.area, loaded.mass_per_area())
    M = M + system.cables.mass_matrix("consistent", system.n_dofs)
    for value, shape in zip(heavy.eigenvalues, heavy.shapes, strict=True):
        assert shape @ K @ shape / (shape @ M @ shape) == pytest.approx(value, rel=1e-8)
    phi0 = plain.shapes[0]
    bound = phi0 @ K @ phi0 / (phi0 @ M @ phi0)
    assert heavy.eigenvalues[0] <= bound * (1 + 1e-9)
    assert heavy.frequencies[0] < 0.8 * plain.frequencies[0]


def test_modes_of_a_state_past_the_limit_point_exit_1(tmp_path, capsys):
    """The balloon example past its maximum pressure (volume control): under its pressure
    that state is unstable (the tangent with the follower pressure's stiffness has a negative
    eigenvalue, the reason the pressure falls), so it has no vibration about it. The run
    writes its steps and a summary saying so, and ends with one line and exit status 1."""
    text = (EXAMPLES / "balloon.toml").read_text()
    text = text.replace("[material]\n", "[material]\ndensity = 1000.0\n", 1)
    case = tmp_path / "balloon.toml"
    case.write_text(text + "\n[modes]\ncount = 3\n")
    assert main(["run", str(case), "--out", str(tmp_path / "out"), "-q"]) == 1
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "[modes]" in error[0] and "unstable" in error[0]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert "no modes" in summary["message"] and "frequencies" not in summary
