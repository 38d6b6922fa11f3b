"""Compiled kernels (``wrinkle.compiled``, Numba) against the NumPy formulas they replace: the
element stiffness against ``element.element_stiffness`` with ``strain_displacement``, the
scatter against ``np.bincount``, the pressure stiffness against
``loads.subtract_pressure_stiffness``, the nodal forces against ``element.nodal_forces``, the
pressure forces against ``loads.pressure_forces`` summed by ``np.bincount``, the wrinkled
tangent against ``Wrinkling._wrinkled_tangent`` (these four bit for bit), a whole evaluation
of the airbag (forces, stiffness, energy) with and without them, and the rule that chooses
them. Skipped where Numba is not installed, except the rule."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wrinkle import compiled
from wrinkle.assembly import SparsityPattern, chunk_colouring
from wrinkle.case import read_case
from wrinkle.element import (
    element_stiffness,
    nodal_forces,
    strain_displacement,
    unit_tension_stiffness,
)
from wrinkle.kinematics import deformation_gradient, element_coordinates, right_cauchy_green
from wrinkle.loads import pressure_forces, pressure_volume, subtract_pressure_stiffness
from wrinkle.materials import StVenantKirchhoff
from wrinkle.mesh import rectangle
from wrinkle.wrinkling import Wrinkling, WrinklingError

needs_numba = pytest.mark.skipif(not compiled.installed(), reason="numba not installed")
AIRBAG = Path(__file__).resolve().parents[1] / "examples" / "airbag.toml"


def random_element_data(m: int, seed: int = 0):
    """area (m,), F (m, 3, 2), shape gradients (m, 3, 2), an unsymmetric tangent (m, 3, 3),
    a symmetric stress (m, 2, 2), all random."""
    rng = np.random.default_rng(seed)
    stress = rng.normal(size=(m, 2, 2))
    return (
        rng.uniform(0.1, 1.0, m),
        rng.normal(size=(m, 3, 2)),
        rng.normal(size=(m, 3, 2)),
        rng.normal(size=(m, 3, 3)),
        stress + stress.transpose(0, 2, 1),
    )


def bulged_airbag(n: int, bending: bool = False):
    """The airbag on n x n squares with a bulged, drawn-in state u (taut, wrinkled and slack
    elements), for evaluations."""
    overrides = {"mesh": {"rectangle": {"nx": n, "ny": n}}, "material": {"bending": bending}}
    model = read_case(AIRBAG, overrides=overrides).model
    X = model.mesh.nodes
    side = X[:, 0].max()
    bulge = 0.05 * np.cos(0.5 * np.pi * X[:, 0] / side) * np.cos(0.5 * np.pi * X[:, 1] / side)
    u = np.column_stack([-0.01 * X[:, 0], -0.005 * X[:, 1] ** 2, bulge]).ravel()
    u[model.constrained] = 0.0
    return model, u


@needs_numba
def test_element_stiffness_equals_numpy_formula():
    area, F, grad, tangent, stress = random_element_data(257)
    expected = element_stiffness(area, strain_displacement(F, grad), tangent, grad, stress)
    out = np.full((257, 9, 9), np.nan)
    compiled.element_stiffness(area, F, grad, tangent, stress, out)
    np.testing.assert_allclose(out, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


@needs_numba
@pytest.mark.parametrize("index_type", [np.int32, np.int64])
def test_scatter_sums_repeated_positions_like_bincount(index_type):
    rng = np.random.default_rng(2)
    positions = rng.integers(0, 300, size=(50, 81)).astype(index_type)  # many repeats
    matrices = rng.normal(size=(50, 9, 9))
    data = rng.normal(size=300)
    expected = data + np.bincount(positions.ravel(), matrices.ravel(), minlength=300)
    compiled.scatter_add(data, positions, matrices)
    np.testing.assert_allclose(data, expected, rtol=1e-13, atol=1e-12)


def test_used_on_large_meshes_unless_switched(monkeypatch):
    monkeypatch.delenv("WRINKLE_NUMBA", raising=False)
    assert not compiled.enabled(compiled.MIN_ELEMENTS - 1)
    assert compiled.enabled(compiled.MIN_ELEMENTS) == compiled.installed()
    monkeypatch.setenv("WRINKLE_NUMBA", "1")
    assert compiled.enabled(10) == compiled.installed()
    monkeypatch.setenv("WRINKLE_NUMBA", "0")
    assert not compiled.enabled(10**6)


@needs_numba
@pytest.mark.parametrize("n, bending", [(8, False), (40, False), (40, True)])
def test_airbag_evaluation_same_with_and_without_compiled_kernels(monkeypatch, n, bending):
    """Forces, assembled stiffness and energy of the airbag partly inflated (taut, wrinkled
    and slack elements, follower pressure; with the bending stiffness too) agree to
    round-off; on 8 x 8 squares the compiled assembly has one chunk of elements, on 40 x 40
    (3,200 triangles) four, in colours."""
    model, u = bulged_airbag(n, bending)
    evaluations = {}
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)  # the kernels are chosen by the system
        model.assign_material(model.materials[0])  # a change: the model is discretised anew
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
    np.testing.assert_array_equal(K.indices, K_numpy.indices)
    np.testing.assert_allclose(
        K.data, K_numpy.data, rtol=0, atol=1e-12 * np.abs(K_numpy.data).max()
    )
    assert compiled_ev.energy == pytest.approx(numpy_ev.energy, rel=1e-13)


@needs_numba
def test_pressure_stiffness_equals_numpy_loop():
    rng = np.random.default_rng(5)
    x, pressure = rng.normal(size=(33, 3, 3)), rng.uniform(0.5, 2.0, 33)
    K = rng.normal(size=(33, 9, 9))
    expected = K.copy()
    subtract_pressure_stiffness(expected, x, pressure)
    compiled.subtract_pressure_stiffness(K, x, pressure)
    np.testing.assert_array_equal(K, expected)


@needs_numba
def test_nodal_forces_equal_numpy_loop():
    area, F, grad, _, stress = random_element_data(257, seed=3)
    expected = nodal_forces(area, F, grad, stress, np.empty((257, 9)))
    out = np.full((257, 9), np.nan)
    compiled.nodal_forces(area, F, grad, stress, out)
    np.testing.assert_array_equal(out, expected)


@needs_numba
def test_pressure_forces_summed_like_bincount():
    rng = np.random.default_rng(9)
    x, pressure = rng.normal(size=(40, 3, 3)), rng.uniform(0.5, 2.0, 40)
    dofs = (3 * rng.integers(0, 12, size=(40, 3))[:, :, None] + np.arange(3)).reshape(40, 9)
    f, _ = pressure_forces(x, pressure, stiffness=False)
    expected = np.zeros(36) + np.bincount(dofs.ravel(), f.ravel(), minlength=36)
    forces = np.zeros(36)
    compiled.add_pressure_forces(forces, dofs, x, pressure)
    np.testing.assert_array_equal(forces, expected)


@needs_numba
def test_wrinkled_tangent_equals_numpy_formula():
    rng = np.random.default_rng(4)
    phi = rng.uniform(0.0, np.pi, 101)
    b = rng.uniform(0.0, 0.1, 101)
    _, _, _, D, stress = random_element_data(101, seed=6)
    wrinkling = Wrinkling(StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0))
    arguments = (np.cos(phi), np.sin(phi), b, stress, D)
    np.testing.assert_array_equal(
        compiled.wrinkled_tangent(*arguments), wrinkling._wrinkled_tangent(*arguments)
    )


def svk_batch(m: int, seed: int = 0) -> np.ndarray:
    """Right Cauchy-Green tensors C (m, 2, 2) of taut, wrinkled and slack elements: random
    deformations, some at round-off from the reference, some crushed across, one not finite."""
    rng = np.random.default_rng(seed)
    F = np.eye(3, 2)[None] + 0.3 * rng.standard_normal((m, 3, 2))
    F[: m // 10] = np.eye(3, 2)[None] + 1e-9 * rng.standard_normal((m // 10, 3, 2))
    F[m // 10 : m // 5, :, 1] *= 0.01
    C = np.einsum("nia,nib->nab", F, F)
    C[-1] = np.nan
    return C


SVK_LAWS = {
    "isotropic": StVenantKirchhoff.isotropic(E=588e6, nu=0.4, thickness=6e-4),
    "transversely isotropic": StVenantKirchhoff.transversely_isotropic(
        E_L=3e9, E_T=1e9, nu_LT=0.3, nu_TT=0.4, G_LT=0.5e9, thickness=1e-4
    ),
    # some of its wrinkled elements end Newton's iterations on an inadmissible root, which
    # the kernel leaves to the NumPy code's angle search
    "strongly anisotropic": StVenantKirchhoff.transversely_isotropic(
        E_L=1e2, E_T=1.0, nu_LT=0.9, nu_TT=0.2, G_LT=0.05, thickness=1.0
    ),
}
RESPONSE_FIELDS = ("stress", "tangent", "thickness", "wrinkle_angle", "wrinkle_parameter", "energy")


@needs_numba
@pytest.mark.parametrize("law", list(SVK_LAWS))
@pytest.mark.parametrize("tangent", [True, False])
def test_svk_response_kernel_equals_numpy(law, tangent):
    """The whole St Venant-Kirchhoff response by one kernel (``compiled.svk_wrinkling``) gives
    the NumPy code's states, and its stresses, tangents, thicknesses, wrinkle angles and
    parameters and energies to round-off, on all three states and a non-finite C."""
    wrinkling = Wrinkling(SVK_LAWS[law])
    C = svk_batch(4000)
    expected = wrinkling.response(C, tangent=tangent)
    result = wrinkling.response(C, tangent=tangent, compiled=True)
    np.testing.assert_array_equal(result.state, expected.state)
    assert np.all(np.bincount(expected.state[:-1]) > 100)  # taut, wrinkled and slack
    *_, left = compiled.svk_wrinkling(
        C,
        wrinkling._linear_law,
        wrinkling.tolerance,
        wrinkling.stress_noise,
        wrinkling.reference_stiffness,
        1e3,
        40,
        tangent,
    )
    assert left.any() == (law == "strongly anisotropic")
    for name in RESPONSE_FIELDS:
        got, want = getattr(result, name), getattr(expected, name)
        if not tangent and name == "tangent":
            assert got is None and want is None
            continue
        finite = np.isfinite(want)
        np.testing.assert_array_equal(np.isfinite(got), finite, err_msg=name)
        scale = np.abs(want[finite]).max()
        np.testing.assert_allclose(
            got[finite], want[finite], rtol=0, atol=1e-14 * scale, err_msg=name
        )


@needs_numba
def test_svk_kernel_leaves_unsolved_elements_to_numpy(monkeypatch):
    """An element whose Newton iterations do not converge in the kernel (here: none are
    allowed) is flagged and solved by the NumPy code, with its angle search: the wrinkled
    elements then equal the NumPy response bit for bit."""
    wrinkling = Wrinkling(SVK_LAWS["isotropic"])
    C = svk_batch(1000, seed=1)
    law = wrinkling._linear_law
    assert law is not None
    *_, fallback = compiled.svk_wrinkling(C, law, 1e-13, 0.0, 1.0, 1e3, 0, True)
    expected = wrinkling.response(C)
    np.testing.assert_array_equal(fallback, expected.state == 1)
    kernel = compiled.svk_wrinkling
    monkeypatch.setattr(
        compiled, "svk_wrinkling", lambda C, law, *a: kernel(C, law, *a[:4], 0, a[5])
    )
    result = wrinkling.response(C, compiled=True)
    wrinkled = expected.state == 1
    for name in RESPONSE_FIELDS:
        np.testing.assert_array_equal(
            getattr(result, name)[wrinkled], getattr(expected, name)[wrinkled], err_msg=name
        )


@needs_numba
def test_svk_kernel_failure_names_the_elements_of_the_batch(monkeypatch):
    """A WrinklingError of the NumPy code on the elements the kernel left names them by
    their rows in the whole batch."""
    wrinkling = Wrinkling(SVK_LAWS["isotropic"])
    C = svk_batch(500, seed=2)
    kernel = compiled.svk_wrinkling
    monkeypatch.setattr(
        compiled, "svk_wrinkling", lambda C, law, *a: kernel(C, law, *a[:4], 0, a[5])
    )

    def fail(self, C, plain_stress, plain_tangent=None):
        raise WrinklingError(np.array([1, 2]))

    wrinkled = np.flatnonzero(wrinkling.response(C).state == 1)
    monkeypatch.setattr(Wrinkling, "_solve_conditions", fail)
    with pytest.raises(WrinklingError) as error:
        wrinkling.response(C, compiled=True)
    np.testing.assert_array_equal(error.value.elements, wrinkled[[1, 2]])


def test_only_a_plain_svk_law_has_its_response_compiled():
    """A prestressed St Venant-Kirchhoff law (its own stress-free state) and any other law
    keep the NumPy response with the compiled wrinkled tangent."""
    from wrinkle.materials import NeoHookean, Prestressed

    svk = SVK_LAWS["isotropic"]
    assert Wrinkling(svk)._linear_law is not None
    assert Wrinkling(Prestressed(svk, [1e3, 1e3, 0.0]))._linear_law is None
    assert Wrinkling(NeoHookean(mu=1e6, thickness=1e-3))._linear_law is None


@needs_numba
def test_asymmetry_equals_numpy_norms():
    """|A - A^T| and |A| in one pass equal NumPy's norms of the same values to round-off."""
    rng = np.random.default_rng(11)
    data = rng.normal(size=10_001)
    transpose = rng.permutation(10_001)
    difference, norm = compiled.asymmetry(data, transpose)
    assert difference == pytest.approx(np.linalg.norm(data - data[transpose]), rel=1e-12)
    assert norm == pytest.approx(np.linalg.norm(data), rel=1e-12)


def shuffled_mesh_triangles(n: int, seed: int) -> tuple[np.ndarray, int]:
    """The triangles of an n x n square mesh, in random order with each one's nodes turned
    at random (so that chunks of consecutive elements are scattered over the mesh), and the
    node count."""
    mesh = rectangle(1.0, 1.0, n, n)
    rng = np.random.default_rng(seed)
    triangles = mesh.triangles[rng.permutation(mesh.n_elements)]
    turns = rng.integers(0, 3, triangles.shape[0])
    rows = np.arange(triangles.shape[0])[:, None]
    return triangles[rows, (np.arange(3) + turns[:, None]) % 3], mesh.n_nodes


def square_mesh_triangles(shuffled: bool, seed: int) -> tuple[np.ndarray, int]:
    """The triangles of a 24 x 24 square mesh and its node count, shuffled
    (``shuffled_mesh_triangles``) or as generated."""
    if shuffled:
        return shuffled_mesh_triangles(24, seed)
    mesh = rectangle(1.0, 1.0, 24, 24)
    return mesh.triangles, mesh.n_nodes


@pytest.mark.parametrize("shuffled", [False, True])
def test_chunk_colouring_puts_no_shared_node_in_one_colour(shuffled):
    """Every chunk once; chunks of one colour share no node; a mesh numbered row by row
    needs few colours, a shuffled one more."""
    if shuffled:
        triangles, n_nodes = shuffled_mesh_triangles(40, seed=3)
    else:
        mesh = rectangle(1.0, 1.0, 40, 40)
        triangles, n_nodes = mesh.triangles, mesh.n_nodes
    chunk_start, chunk_order, colour_start = chunk_colouring(triangles, n_nodes, chunk=100)
    n_chunks = chunk_start.size - 1
    assert chunk_start[0] == 0 and chunk_start[-1] == triangles.shape[0]
    assert np.all(np.diff(chunk_start) > 0)
    np.testing.assert_array_equal(np.sort(chunk_order), np.arange(n_chunks))
    for colour in range(colour_start.size - 1):
        nodes = [
            np.unique(triangles[chunk_start[k] : chunk_start[k + 1]])
            for k in chunk_order[colour_start[colour] : colour_start[colour + 1]]
        ]
        every = np.concatenate(nodes)
        assert np.unique(every).size == every.size, f"colour {colour} shares a node"
    colours = colour_start.size - 1
    assert colours <= (n_chunks if shuffled else 4), colours


def assemble(data, pattern, element_data, x, pressure, colouring, kept) -> None:
    """``compiled.assemble_stiffness`` into data on pattern's positions; element_data =
    (area, F, grad, tangent, stress) as ``random_element_data`` gives them."""
    area, F, grad, tangent, stress = element_data
    positions = (pattern.element_block_base, pattern.element_row_step)
    compiled.assemble_stiffness(
        data, positions, area, F, grad, tangent, stress, x, pressure, colouring, kept
    )


@needs_numba
@pytest.mark.parametrize("shuffled", [False, True])
def test_assembled_stiffness_equals_element_matrices_scattered(shuffled):
    """The fused, coloured assembly equals the element matrices of ``element_stiffness``
    minus the pressure stiffness, scattered by np.bincount, on the kept rows and columns;
    the other entries are left as they were."""
    triangles, n_nodes = square_mesh_triangles(shuffled, seed=5)
    m = triangles.shape[0]
    pattern = SparsityPattern(triangles, n_nodes)
    area, F, grad, tangent, stress = random_element_data(m, seed=7)
    rng = np.random.default_rng(8)
    x = rng.normal(size=(m, 3, 3))
    pressure = np.where(rng.random(m) < 0.5, 0.0, rng.normal(size=m))
    free = rng.random(pattern.n_dofs) < 0.8
    kept = free[pattern.element_dofs]
    K = element_stiffness(area, strain_displacement(F, grad), tangent, grad, stress)
    subtract_pressure_stiffness(K, x, pressure)
    K = K * (kept[:, :, None] & kept[:, None, :])
    before = rng.normal(size=pattern.nnz)
    expected = before + pattern.assemble_data(K)
    data = before.copy()
    colouring = chunk_colouring(triangles, n_nodes, chunk=64)
    assemble(data, pattern, (area, F, grad, tangent, stress), x, pressure, colouring, kept)
    np.testing.assert_allclose(data, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


@needs_numba
@pytest.mark.parametrize("pressed", [False, True])
def test_assembled_entries_are_the_element_kernels_bit_for_bit(pressed):
    """On triangles that share no node each stored entry receives one element's value: the
    assembly's entries, formed only where kept (no element pressurised) or from the whole
    matrix (some are), are those of ``compiled.element_stiffness`` minus the pressure's
    load stiffness to the last bit."""
    m = 300
    triangles = np.arange(3 * m).reshape(m, 3)
    pattern = SparsityPattern(triangles, 3 * m)
    area, F, grad, tangent, stress = random_element_data(m, seed=17)
    rng = np.random.default_rng(18)
    x = rng.normal(size=(m, 3, 3))
    pressure = np.where(rng.random(m) < 0.5, 0.0, rng.normal(size=m)) * pressed
    kept = (rng.random(pattern.n_dofs) < 0.7)[pattern.element_dofs]
    K = np.empty((m, 9, 9))
    compiled.element_stiffness(area, F, grad, tangent, stress, K)
    compiled.subtract_pressure_stiffness(K, x, pressure)
    before = rng.normal(size=pattern.nnz)
    data = before.copy()
    colouring = chunk_colouring(triangles, 3 * m, chunk=64)
    assemble(data, pattern, (area, F, grad, tangent, stress), x, pressure, colouring, kept)
    mask = kept[:, :, None] & kept[:, None, :]
    expected = before + pattern.assemble_data(np.where(mask, K, 0.0))
    np.testing.assert_array_equal(data, expected)
    untouched = pattern.assemble_data(mask.astype(float)) == 0.0
    np.testing.assert_array_equal(data[untouched], before[untouched])


@needs_numba
def test_strain_and_coordinate_kernels_equal_numpy_bit_for_bit():
    """F, C and the element coordinates of the compiled kernels are NumPy's exactly."""
    triangles, n_nodes = shuffled_mesh_triangles(12, seed=9)
    rng = np.random.default_rng(10)
    nodes, u = rng.normal(size=(n_nodes, 3)), rng.normal(size=(n_nodes, 3))
    x = compiled.element_coordinates(nodes, u, triangles)
    np.testing.assert_array_equal(x, element_coordinates(nodes + u, triangles))
    grad = rng.normal(size=(triangles.shape[0], 3, 2))
    F, C = compiled.deformation_gradient(x, grad)
    F_numpy = deformation_gradient(x, grad)
    np.testing.assert_array_equal(F, F_numpy)
    np.testing.assert_array_equal(C, right_cauchy_green(F_numpy))


@needs_numba
def test_gather_scatter_and_shift_kernels_equal_numpy():
    """put, take, any_nonzero, add_unique and the gathered sums of two value arrays equal
    their NumPy forms exactly."""
    rng = np.random.default_rng(12)
    data = rng.normal(size=1000)
    positions = rng.choice(1000, 300, replace=False)
    np.testing.assert_array_equal(compiled.take(data, positions), data[positions])
    changed = data.copy()
    compiled.put(changed, positions, 0.0)
    expected = data.copy()
    expected[positions] = 0.0
    np.testing.assert_array_equal(changed, expected)
    assert not compiled.any_nonzero(changed, positions)
    changed[positions[7]] = np.nan
    assert compiled.any_nonzero(changed, positions)
    assert compiled.any_nonzero(data, positions)
    added = data.copy()
    compiled.add_unique(added, positions, np.arange(300.0))
    expected = data.copy()
    expected[positions] += np.arange(300.0)
    np.testing.assert_array_equal(added, expected)
    other = rng.normal(size=1000)
    flagged = np.zeros(1000, dtype=bool)
    flagged[positions[::3]] = True
    expected = data + 0.37 * other
    expected[flagged] += 2.5
    np.testing.assert_array_equal(
        compiled.sum_take((data, other, 0.37, flagged, 2.5), positions), expected[positions]
    )
    cancelling = data.copy()
    cancelling[positions] = -0.5 * other[positions]
    cancelling[flagged] -= 2.5
    assert not compiled.sum_any_nonzero((cancelling, other, 0.5, flagged, 2.5), positions)
    assert compiled.sum_any_nonzero((cancelling, other, 0.5, flagged, 2.0), positions)
    cancelling[positions[4]] = np.nan
    assert compiled.sum_any_nonzero((cancelling, other, 0.5, flagged, 2.5), positions)
    with pytest.raises(ValueError, match="values"):
        compiled.sum_take((data, other[:-1], 0.37, flagged, 2.5), positions)


@needs_numba
@pytest.mark.parametrize("shuffled", [False, True])
def test_transpose_positions_find_each_entrys_transpose(shuffled):
    """Each entry's transpose found by bisection is where SciPy's transpose puts it, on the
    pattern of a mesh's stiffness (shuffled or not); a pattern lacking one transpose gives
    -1 there and nowhere else."""
    triangles, n_nodes = square_mesh_triangles(shuffled, seed=4)
    pattern = SparsityPattern(triangles, n_nodes)
    A = pattern.matrix(np.arange(1.0, pattern.nnz + 1))
    transpose = compiled.transpose_positions(A.indptr, A.indices)
    expected = A.T.tocsr()
    expected.sort_indices()
    np.testing.assert_array_equal(A.data[transpose], expected.data)
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    np.testing.assert_array_equal(rows[transpose], A.indices)
    # drop the entry (0, 3): its transpose (3, 0) then has none
    lower = A.tolil()
    lower[0, 3] = 0.0
    lower = lower.tocsr()
    lower.eliminate_zeros()
    lower.sort_indices()
    missing = compiled.transpose_positions(lower.indptr, lower.indices)
    rows = np.repeat(np.arange(lower.shape[0]), np.diff(lower.indptr))
    np.testing.assert_array_equal(
        np.flatnonzero(missing < 0), np.flatnonzero((rows == 3) & (lower.indices == 0))
    )


@needs_numba
def test_evaluation_keeping_constraints_or_lifted_same_with_and_without_kernels(monkeypatch):
    """The tangent with its constrained rows and columns kept (the sensitivities) and the
    residual linearised at a lift of the prescribed components are the NumPy ones: there
    the compiled assembly adds every row and column, not only the free ones."""
    model = read_case(AIRBAG, overrides={"mesh": {"rectangle": {"nx": 24, "ny": 24}}}).model
    X = model.mesh.nodes
    u = np.column_stack([-0.01 * X[:, 0], -0.005 * X[:, 1], 0.02 * X[:, 0] * X[:, 1]]).ravel()
    u[model.constrained] = 0.0
    lift = np.where(model.constrained, 1e-3, 0.0)
    results = {}
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)
        model.assign_material(model.materials[0])
        problem = model.discretise().at(1.0)
        results[switch] = (
            problem.evaluate(u, keep_constrained=True).stiffness,
            problem.evaluate(u, lift=lift).residual,
        )
    (K_numpy, r_numpy), (K, r) = results["0"], results["1"]
    assert np.any(K_numpy.data[model.discretise().pattern.constraint_positions(model.constrained)])
    np.testing.assert_allclose(K.data, K_numpy.data, rtol=0, atol=1e-12 * abs(K_numpy.data).max())
    np.testing.assert_allclose(r, r_numpy, rtol=0, atol=1e-12 * np.abs(r_numpy).max())


@needs_numba
def test_coloured_vector_assembly_and_pressure_work_equal_numpy():
    """The global vector summed over coloured chunks equals np.bincount's; the pressure's
    work equals p . pressure_volume; both to round-off (the order of the sums differs)."""
    triangles, n_nodes = shuffled_mesh_triangles(24, seed=13)
    pattern = SparsityPattern(triangles, n_nodes)
    rng = np.random.default_rng(14)
    values = rng.normal(size=(triangles.shape[0], 9))
    expected = pattern.assemble_vector(values)
    for colouring in (pattern.colouring, chunk_colouring(triangles, n_nodes, chunk=32)):
        summed = compiled.assemble_vector(pattern.n_dofs, pattern.element_dofs, values, colouring)
        np.testing.assert_allclose(summed, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    np.testing.assert_allclose(
        pattern.assemble_vector(values, compiled=True), expected, rtol=0, atol=1e-13
    )
    x = rng.normal(size=(500, 3, 3))
    pressure = rng.normal(size=500)
    assert compiled.pressure_work(x, pressure) == pytest.approx(
        float(pressure @ pressure_volume(x)), rel=1e-12
    )


@needs_numba
@pytest.mark.parametrize("bending", [False, True])
def test_deferred_stiffness_is_the_one_formed_at_once(monkeypatch, bending):
    """An evaluation with ``defer`` holds no stiffness but forms, when asked, exactly the
    tangent of the evaluation without it; its forces and energy are the same bits."""
    monkeypatch.setenv("WRINKLE_NUMBA", "1")
    model, u = bulged_airbag(24, bending)
    problem = model.discretise().at(1.0)
    now = problem.evaluate(u)
    later = problem.evaluate(u, defer=True)
    assert later.stiffness is None and later.later is not None
    np.testing.assert_array_equal(later.residual, now.residual)
    assert later.energy == now.energy
    formed = later.with_stiffness()
    assert formed.later is None and formed.with_stiffness() is formed
    np.testing.assert_array_equal(formed.stiffness.data, now.stiffness.data)
    np.testing.assert_array_equal(formed.stiffness.indices, now.stiffness.indices)
    assert now.with_stiffness() is now


@needs_numba
@pytest.mark.parametrize("bending", [False, True])
@pytest.mark.parametrize("defer", [False, True])
def test_constrained_rows_left_unwritten_are_zero_without_zeroing(monkeypatch, bending, defer):
    """Where the compiled assembly adds only the free rows and columns, the tangent's
    constrained rows and columns are not zeroed again: they are exactly those of the whole
    tangent (``keep_constrained``) with its constrained rows and columns zeroed and their
    diagonal one, bit for bit, its free entries too; with bending, which adds to them, they
    are zeroed as before."""
    monkeypatch.setenv("WRINKLE_NUMBA", "1")
    model, u = bulged_airbag(24, bending)
    problem = model.discretise().at(1.0)
    K = problem.evaluate(u, defer=defer).with_stiffness().stiffness
    whole = problem.evaluate(u, keep_constrained=True).stiffness
    pattern = model.discretise().pattern
    positions = pattern.constraint_positions(model.constrained)
    assert np.any(whole.data[positions])  # there is something to zero
    expected = whole.data.copy()
    expected[positions] = 0.0
    expected[pattern.diagonal[model.constrained]] = 1.0
    np.testing.assert_array_equal(K.data, expected)


@needs_numba
def test_stiffness_formed_at_once_where_it_cannot_be_deferred(monkeypatch):
    """With a lift or the constrained rows kept, and on the NumPy kernels, ``defer`` gives
    the stiffness at once."""
    model, u = bulged_airbag(8)
    lift = np.where(model.constrained, 1e-3, 0.0)
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)
        model.assign_material(model.materials[0])
        problem = model.discretise().at(1.0)
        assert problem.evaluate(u, defer=True, lift=lift).stiffness is not None
        assert problem.evaluate(u, defer=True, keep_constrained=True).stiffness is not None
        deferred = problem.evaluate(u, defer=True)
        assert (deferred.stiffness is None) == (switch == "1")


@needs_numba
def test_solve_deferring_the_stiffness_takes_the_same_iterates(monkeypatch):
    """A Newton solve whose trial points defer their stiffness takes the same iterates, bit
    for bit, as one that forms it at every trial point, and assembles it only at the points
    it accepts (fewer times)."""
    from wrinkle.system import DiscreteSystem, StepProblem

    monkeypatch.setenv("WRINKLE_NUMBA", "1")
    assembled = []
    assemble = DiscreteSystem.assemble_stiffness

    def counted(self, *args):
        assembled.append(1)
        return assemble(self, *args)

    monkeypatch.setattr(DiscreteSystem, "assemble_stiffness", counted)
    runs = {}
    for defers in (False, True):
        monkeypatch.setattr(StepProblem, "defers_stiffness", defers)
        case = read_case(AIRBAG, overrides={"mesh": {"rectangle": {"nx": 16, "ny": 16}}})
        assembled.clear()
        results = case.model.solve(case.settings)
        runs[defers] = (results.final.iterations, results.final.displacement, len(assembled))
    (iterations, u, calls), (iterations_deferred, u_deferred, calls_deferred) = (
        runs[False],
        runs[True],
    )
    assert iterations_deferred == iterations
    np.testing.assert_array_equal(u_deferred, u)
    assert calls_deferred < calls


@needs_numba
@pytest.mark.parametrize("shuffled", [False, True])
def test_assembled_laplacian_equals_unit_tension_stiffness_scattered(shuffled):
    """The coloured, compiled unit-tension stiffness (the step metric's Laplacian) equals
    ``unit_tension_stiffness``'s element matrices scattered by np.bincount, added to what the
    data held."""
    triangles, n_nodes = square_mesh_triangles(shuffled, seed=9)
    m = triangles.shape[0]
    pattern = SparsityPattern(triangles, n_nodes)
    area, _, grad, _, _ = random_element_data(m, seed=10)
    before = np.random.default_rng(11).normal(size=pattern.nnz)
    expected = before + pattern.assemble_data(unit_tension_stiffness(area, grad))
    data = before.copy()
    compiled.assemble_laplacian(
        data,
        (pattern.element_block_base, pattern.element_row_step),
        area,
        grad,
        chunk_colouring(triangles, n_nodes, chunk=64),
    )
    np.testing.assert_allclose(data, expected, rtol=1e-14, atol=1e-14 * np.abs(expected).max())


@needs_numba
def test_step_metric_same_with_and_without_kernels(monkeypatch):
    """The model's step metric (and weighted by each element's tension) with the compiled
    kernels is the NumPy one."""
    model, _ = bulged_airbag(24)
    tension = np.linspace(1.0, 3.0, model.mesh.n_elements)
    metrics = {}
    for switch in ("0", "1"):
        monkeypatch.setenv("WRINKLE_NUMBA", switch)
        model.assign_material(model.materials[0])
        system = model.discretise()
        assert system.compiled == (switch == "1")
        metrics[switch] = (system.step_metric(), system.step_metric(tension))
    for numpy_metric, metric in zip(metrics["0"], metrics["1"], strict=True):
        scale = np.abs(numpy_metric).max()
        np.testing.assert_allclose(metric, numpy_metric, rtol=0, atol=1e-14 * scale)
