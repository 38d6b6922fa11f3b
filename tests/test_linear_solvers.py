"""Linear back-ends (``wrinkle.solvers.linear``): each solves the shifted tangent to round-off
and gives the same nonlinear solution as SuperLU. Back-ends that are not installed (the extra
``fast``) are skipped."""

from __future__ import annotations

import builtins
import os
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from wrinkle.case import CaseError, read_case
from wrinkle.solvers import make_solver
from wrinkle.solvers.base import shifted
from wrinkle.solvers.linear import (
    AUTO_PARDISO_DOFS,
    AUTO_PARDISO_ONE_OFF_DOFS,
    LINEAR_SOLVERS,
    FreeBlock,
    MatrixSum,
    Pardiso,
    SuperLU,
    SymmetryCheck,
    diagonal_positions,
    make_linear_solver,
    upper_triangle_positions,
)
from wrinkle.solvers.newton import RegularisedNewton

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
AIRBAG = EXAMPLES / "airbag.toml"
SHEAR_STRETCH = EXAMPLES / "shear_stretch.toml"


def installed(name: str) -> bool:
    try:
        make_linear_solver(name)
    except ImportError:
        return False
    return True


BACKENDS = [
    pytest.param(
        name, marks=pytest.mark.skipif(not installed(name), reason=f"{name} not installed")
    )
    for name in LINEAR_SOLVERS
]


def spd_matrix(n: int = 60, seed: int = 3) -> sp.csr_matrix:
    """A sparse symmetric positive definite matrix with a full diagonal: a 1-D Laplacian plus a
    symmetric random coupling, shifted by its Gershgorin bound."""
    rng = np.random.default_rng(seed)
    coupling = sp.random(n, n, density=0.05, random_state=rng)
    A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n)) + coupling + coupling.T
    A = A + sp.diags(np.abs(A).sum(axis=1).A1)
    A = A.tocsr()
    A.sort_indices()
    return A


def rows_of(A: sp.csr_matrix) -> np.ndarray:
    """The row of each stored entry of A, (nnz,)."""
    return np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))


def test_shifted_adds_on_free_diagonal_only():
    A = spd_matrix()
    free = np.arange(A.shape[0]) % 4 != 0
    expected = A + sp.diags(np.where(free, 0.25, 0.0))
    result = shifted(A, 0.25, free)
    assert (abs(result - expected)).max() == 0.0
    assert result.nnz == A.nnz  # same pattern, no new entries
    complex_result = shifted(A, -0.5j, free, diagonal_positions(A))
    np.testing.assert_array_equal(complex_result.diagonal().imag, np.where(free, -0.5, 0.0))


def test_diagonal_positions_and_a_missing_diagonal():
    A = spd_matrix()
    np.testing.assert_array_equal(A.data[diagonal_positions(A)], A.diagonal())
    B = sp.csr_matrix(np.array([[0.0, 1.0], [1.0, 2.0]]))
    with pytest.raises(ValueError, match="lacks diagonal entries"):
        diagonal_positions(B)


@pytest.mark.parametrize("name", BACKENDS)
def test_backend_solves_to_round_off(name):
    A = spd_matrix()
    b = np.random.default_rng(1).normal(size=A.shape[0])
    backend = make_linear_solver(name, A.shape[0])
    for scale in (1.0, 1.5):  # a second factorisation reuses the ordering
        B = A.copy()
        B.data *= scale
        x = backend.factorise(B, True)(b)
        assert np.linalg.norm(B @ x - b) <= 1e-9 * np.linalg.norm(b)


@pytest.mark.parametrize("kernels", ["0", "1"])
def test_symmetry_check_and_upper_triangle(kernels, monkeypatch):
    """The same verdicts with NumPy's norms and with the compiled ``asymmetry``."""
    monkeypatch.setenv("WRINKLE_NUMBA", kernels)
    A = spd_matrix()
    check = SymmetryCheck()
    assert check(A)
    B = A.copy()
    off_diagonal = np.flatnonzero(rows_of(B) != B.indices)[0]
    B.data[off_diagonal] *= 1.0 + 1e-15  # round-off: still symmetric
    assert check(B)
    B.data[off_diagonal] *= 1.0 + 1e-6
    assert not check(B)
    lopsided = sp.csr_matrix(np.array([[2.0, 1.0], [0.0, 2.0]]))  # (0, 1) stored, (1, 0) not
    assert not SymmetryCheck()(lopsided)
    positions, indptr, indices = upper_triangle_positions(A)
    upper = sp.csr_matrix((A.data[positions], indices, indptr), shape=A.shape)
    assert abs(upper - sp.triu(A)).max() == 0.0


class _Recorder:
    """A linear back-end that records the symmetry it is told and solves with SuperLU."""

    def __init__(self):
        self.told = []

    def factorise(self, A, symmetric):
        self.told.append(symmetric)
        return SuperLU().factorise(A, symmetric)


def test_a_symmetric_tangent_goes_to_the_back_end_as_symmetric():
    """The assembled tangent of the airbag under follower pressure is symmetric (the Hessian
    of the energy with the pressure potential -p V), although its problem cannot promise it:
    the solver checks and tells the back-end; a non-symmetric matrix stays non-symmetric."""
    model = read_case(AIRBAG, {"mesh": {"rectangle": {"nx": 8, "ny": 8}}}).model
    problem = model.discretise().at(1.0)
    X = model.mesh.nodes
    side = X[:, 0].max()
    u = np.zeros(X.size)
    u[2::3] = 0.1 * np.cos(0.5 * np.pi * X[:, 0] / side) * np.cos(0.5 * np.pi * X[:, 1] / side)
    u += 1e-3 * np.random.default_rng(0).normal(size=u.size)
    evaluation = problem.evaluate(np.where(problem.free, u, 0.0))
    assert not evaluation.symmetric
    K = evaluation.stiffness
    assert np.abs((K - K.T).data).max() <= 1e-12 * np.abs(K.data).max()
    solver = RegularisedNewton()  # any solver: factorise is the common one
    solver.linear = _Recorder()
    solver.factorise(K, False)
    skewed = K.copy()
    rows = rows_of(K)
    upper = (skewed.indices > rows) & (np.abs(skewed.data) > 1e-3 * np.abs(K.data).max())
    skewed.data[upper] *= 1.01  # the upper triangle's larger entries only
    solver.factorise(skewed, False)
    assert solver.linear.told == [True, False]


@pytest.mark.skipif(not installed("pardiso"), reason="pardiso not installed")
def test_pardiso_symmetric_indefinite_and_general_on_one_pattern():
    """PARDISO factorises a symmetric indefinite matrix from its upper triangle, a general
    one by LU, and goes back and forth between them on the same pattern."""
    A = spd_matrix()
    A.setdiag(A.diagonal() - 0.6 * A.diagonal().mean())
    assert np.linalg.eigvalsh(A.toarray()).min() < 0.0 < np.linalg.eigvalsh(A.toarray()).max()
    general = A.copy()
    general.data *= np.random.default_rng(2).uniform(0.9, 1.1, size=A.nnz)
    b = np.random.default_rng(1).normal(size=A.shape[0])
    backend = make_linear_solver("pardiso")
    for matrix, symmetric in ((A, True), (general, False), (2.0 * A, True)):
        x = backend.factorise(matrix, symmetric)(b)
        assert np.linalg.norm(matrix @ x - b) <= 1e-9 * np.linalg.norm(b)


@pytest.mark.skipif(not installed("pardiso"), reason="pypardiso not installed")
def test_pardiso_converts_a_patterns_indices_once(monkeypatch):
    """PARDISO's 1-based index arrays are made once per pattern, not at each factorisation
    and solve, and are made again for another pattern; the solutions are pypardiso's own."""
    import pypardiso

    backend = make_linear_solver("pardiso")
    A = spd_matrix()
    b = np.random.default_rng(8).normal(size=A.shape[0])
    x = backend.factorise(A, True)(b)
    ia, ja = backend._one_based[2:]
    np.testing.assert_array_equal(ja - 1, upper_triangle_positions(A)[2])
    y = backend.factorise(3.0 * A, True)(b)  # the same pattern, other values
    assert backend._one_based[2] is ia and backend._one_based[3] is ja
    np.testing.assert_allclose(x, pypardiso.spsolve(A, b), rtol=1e-12)
    np.testing.assert_allclose(y, x / 3.0, rtol=1e-12)
    B = spd_matrix(seed=9)
    z = backend.factorise(B, False)(b)
    assert backend._one_based[2] is not ia
    np.testing.assert_array_equal(backend._one_based[3] - 1, B.indices)
    np.testing.assert_allclose(z, pypardiso.spsolve(B, b), rtol=1e-12)


@pytest.mark.skipif(not installed("pardiso"), reason="pypardiso not installed")
def test_pardiso_lets_the_mkl_threads_sleep(monkeypatch):
    """Making the PARDISO back-end sets KMP_BLOCKTIME=0 (MKL's threads sleep as soon as a
    call returns), unless the user has set it."""
    monkeypatch.delenv("KMP_BLOCKTIME", raising=False)
    make_linear_solver("pardiso")
    assert os.environ["KMP_BLOCKTIME"] == "0"
    monkeypatch.setenv("KMP_BLOCKTIME", "50")
    make_linear_solver("pardiso")
    assert os.environ["KMP_BLOCKTIME"] == "50"


def test_superlu_solves_complex_and_reports_singular():
    A = spd_matrix().astype(complex)
    A.setdiag(A.diagonal() - 1j)
    b = np.ones(A.shape[0], dtype=complex)
    x = SuperLU().factorise(A, True)(b)
    assert np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)
    singular = sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
    assert SuperLU().factorise(singular, True) is None


def test_auto_and_unknown_names(monkeypatch):
    assert isinstance(make_linear_solver("auto", 100), SuperLU)
    # a matrix factorised once takes SuperLU up to the larger threshold
    assert isinstance(make_linear_solver("auto", AUTO_PARDISO_DOFS, one_off=True), SuperLU)
    if installed("pardiso"):
        assert isinstance(make_linear_solver("auto", AUTO_PARDISO_DOFS), Pardiso)
        assert isinstance(
            make_linear_solver("auto", AUTO_PARDISO_ONE_OFF_DOFS, one_off=True), Pardiso
        )
    with pytest.raises(ValueError, match="unknown linear solver 'umfpack'"):
        make_linear_solver("umfpack")
    with pytest.raises(ValueError, match="unknown linear solver"):
        make_solver("newton", linear_solver="umfpack")
    real_import = builtins.__import__

    def no_pypardiso(name, *args, **kwargs):
        if name.startswith("pypardiso"):
            raise ImportError("No module named 'pypardiso'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pypardiso)
    with pytest.raises(ImportError, match=r"needs pypardiso.*wrinkle\[fast\]"):
        make_linear_solver("pardiso")
    # "auto" never fails: without PARDISO a large problem falls back to SuperLU
    assert isinstance(make_linear_solver("auto", 10 * AUTO_PARDISO_DOFS), SuperLU)


@pytest.mark.parametrize(
    "name, module, install",
    [
        ("cholmod", "sksparse", r"libsuitesparse-dev\), then pip install scikit-sparse"),
        ("amg", "pyamg", r"pip install pyamg"),
    ],
)
def test_missing_backend_says_how_to_install_it(monkeypatch, name, module, install):
    """Neither scikit-sparse nor pyamg is in an extra: the message must not send the user to
    "wrinkle[fast]"."""
    real_import = builtins.__import__

    def without(imported, *args, **kwargs):
        if imported.split(".")[0] == module:
            raise ImportError(f"No module named '{module}'")
        return real_import(imported, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without)
    with pytest.raises(ImportError, match=install) as error:
        make_linear_solver(name)
    message = str(error.value)
    assert f"linear solver '{name}' needs " in message
    assert ("scikit-sparse" if name == "cholmod" else "pyamg") in message
    assert "wrinkle[" not in message and "\n" not in message


@pytest.mark.parametrize("name", BACKENDS)
@pytest.mark.parametrize("case", [AIRBAG, SHEAR_STRETCH], ids=["airbag", "shear_stretch"])
def test_same_solution_with_every_backend(name, case):
    """The inflated airbag (8 x 8 quarter mesh; follower pressure, a tangent found symmetric
    by the solver's check) and the shear-stretch square (12 x 12; symmetric, wrinkled) reach
    the same displacements with every back-end as with SuperLU. (A back-end that cannot
    factorise an indefinite tangent makes the regularisation grow, so the path may differ,
    not the solution.)"""
    overrides = {
        "mesh": {
            "rectangle": {"nx": 8 if case == AIRBAG else 12, "ny": 8 if case == AIRBAG else 12}
        }
    }
    reference = read_case(case, overrides).solve(linear_solver="superlu", tolerance=1e-10)
    result = read_case(case, overrides).solve(linear_solver=name, tolerance=1e-10)
    u, u_ref = result.final.displacement, reference.final.displacement
    assert np.abs(u - u_ref).max() <= 1e-7 * np.abs(u_ref).max()


def test_case_file_names_the_linear_solver(tmp_path):
    text = AIRBAG.read_text().replace(
        'method = "newton"', 'method = "newton"\nlinear_solver = "superlu"'
    )
    case = tmp_path / "airbag.toml"
    case.write_text(text)
    assert read_case(case).settings.linear_solver == "superlu"
    case.write_text(text.replace('"superlu"', '"mumps"'))
    with pytest.raises(CaseError, match=r"\[solver\]: unknown linear_solver 'mumps'"):
        read_case(case)


@pytest.mark.skipif(not installed("pardiso"), reason="pypardiso not installed")
def test_auto_takes_pardiso_above_its_size_and_reaches_the_superlu_solution():
    """The default back-end on a mesh above AUTO_PARDISO_DOFS unknowns (the shear-stretch
    square, 84 x 84 nodes) is PARDISO when installed, and the path reaches SuperLU's
    displacements (the homogeneous solution, to round-off)."""
    from wrinkle.solvers import follow_load_path

    overrides = {"mesh": {"rectangle": {"nx": 83, "ny": 83}}}
    displacements = {}
    for name in ("auto", "superlu"):
        case = read_case(SHEAR_STRETCH, overrides)
        system = case.model.discretise()
        assert system.n_dofs > AUTO_PARDISO_DOFS
        settings = case.settings.replace(linear_solver=name, tolerance=1e-10)
        solver = settings.solver()
        displacements[name] = follow_load_path(system, solver, settings.controller())
        assert type(solver.linear).__name__ == ("Pardiso" if name == "auto" else "SuperLU")
    u_ref = displacements["superlu"]
    assert np.abs(displacements["auto"] - u_ref).max() <= 1e-9 * np.abs(u_ref).max()


def held_rows_matrix(negative: bool = False) -> tuple[sp.csr_matrix, np.ndarray]:
    """spd_matrix with every third row and column held as the solvers hold them: entries
    zeroed but kept in the pattern, the diagonal one (minus one with negative=True, for the
    inertia). Shifted to be indefinite on the free block. Returns (A, free)."""
    A = spd_matrix()
    A.setdiag(A.diagonal() - 0.9 * A.diagonal().mean())
    n = A.shape[0]
    free = np.arange(n) % 3 != 1
    rows = rows_of(A)
    held = ~free[rows] | ~free[A.indices]
    A.data[held] = 0.0
    A.data[held & (rows == A.indices)] = -1.0 if negative else 1.0
    assert A.nnz == spd_matrix().nnz  # the zeros stay stored
    return A, free


class _Sizes(_Recorder):
    """A _Recorder that also records the size of each matrix it is given."""

    def __init__(self):
        super().__init__()
        self.sizes = []

    def factorise(self, A, symmetric):
        self.sizes.append(A.shape[0])
        return super().factorise(A, symmetric)


@pytest.mark.parametrize("name", BACKENDS)
@pytest.mark.parametrize("negative", [False, True])
def test_the_free_block_alone_is_factorised(name, negative):
    """A matrix whose held rows and columns carry only their diagonal is solved by
    factorising its free block (``FreeBlock``), with x = b / A_cc on the held components: the
    whole matrix's solution to round-off, its inertia (held diagonal of -1 included) exactly,
    on every back-end; real and complex."""
    A, free = held_rows_matrix(negative)
    b = np.random.default_rng(4).normal(size=A.shape[0])
    dense = A.toarray()
    solver = RegularisedNewton(linear_solver=name)
    block, held = FreeBlock().split(A, free)  # the path these solves take
    np.testing.assert_array_equal(block.toarray(), dense[np.ix_(free, free)])
    np.testing.assert_array_equal(held, np.diag(dense)[~free])
    if name not in ("cholmod", "amg"):  # symmetric positive definite only
        x = solver.factorise(A, True, free)(b)
        assert np.abs(x - np.linalg.solve(dense, b)).max() <= 1e-10 * np.abs(x).max()
        negative_count = int(np.count_nonzero(np.linalg.eigvalsh(dense) < 0.0))
        assert negative_count > 0
        assert solver.negative_eigenvalues(A, free) == negative_count
    spd = A.copy()
    spd.data[rows_of(A) == A.indices] += 5.0 * np.abs(A.data).max() * A.shape[0] ** 0.5
    spd.data[diagonal_positions(spd)[~free]] = 2.0
    x = solver.factorise(spd, True, free)(b)
    assert np.abs(spd @ x - b).max() <= 1e-8 * np.abs(b).max()
    np.testing.assert_allclose(x[~free], b[~free] / 2.0, rtol=1e-15)
    complex_A = shifted(A, -0.3j, free)
    complex_solve = RegularisedNewton(linear_solver="superlu").factorise(complex_A, True, free)
    z = complex_solve(b)
    assert np.abs(complex_A @ z - b).max() <= 1e-10 * np.abs(z).max()


@pytest.mark.parametrize("name", BACKENDS)
@pytest.mark.parametrize("kernels", ["0", "1"])
def test_a_matrix_sum_is_solved_as_the_matrix_it_stands_for(name, kernels, monkeypatch):
    """K + f M + s D handed over as a ``MatrixSum`` (its entries summed where a back-end
    reads them) gives the free block, held diagonal, symmetry verdict and solution of the
    matrix formed in full, bit for bit where it gathers, on every back-end, with and without
    the compiled kernels; a sum whose M couples a held row is not split."""
    monkeypatch.setenv("WRINKLE_NUMBA", kernels)
    K, free = held_rows_matrix()
    rows = rows_of(K)
    M = np.abs(K.data) * np.where(free[rows] & free[K.indices], 1.0, 0.0)  # symmetric, like K
    flags = np.zeros(K.nnz, dtype=bool)
    flags[diagonal_positions(K)[free]] = True
    A = MatrixSum(K, M, 0.25, flags, 0.125)
    formed = A.tocsr()
    expected = K.data + 0.25 * M
    expected[flags] += 0.125
    np.testing.assert_array_equal(formed.data, expected)
    block, held = FreeBlock().split(A, free)
    expected_block, expected_held = FreeBlock().split(formed, free)
    np.testing.assert_array_equal(block.toarray(), expected_block.toarray())
    np.testing.assert_array_equal(held, expected_held)
    assert SymmetryCheck()(A)
    b = np.random.default_rng(6).normal(size=K.shape[0])
    if name not in ("cholmod", "amg"):  # symmetric positive definite only
        x = RegularisedNewton(linear_solver=name).factorise(A, False, free)(b)
        x_formed = RegularisedNewton(linear_solver=name).factorise(formed, False, free)(b)
        np.testing.assert_array_equal(x, x_formed)
        assert np.abs(formed @ x - b).max() <= 1e-10 * np.abs(x).max()
        x_whole = RegularisedNewton(linear_solver=name).factorise(A, True)(b)
        assert np.abs(formed @ x_whole - b).max() <= 1e-10 * np.abs(x).max()
    lopsided = K.copy()
    lopsided.data[np.flatnonzero(rows < K.indices)[0]] += 1.0
    assert not SymmetryCheck()(MatrixSum(lopsided, M, 0.25, flags, 0.125))
    coupling = M.copy()  # M with an entry in a held row
    coupling[np.flatnonzero(~free[rows] & (rows != K.indices))[0]] = 1.0
    assert FreeBlock().split(MatrixSum(K, coupling, 0.25, flags, 0.125), free) is None
    with pytest.raises(ValueError, match="values of M"):
        MatrixSum(K, M[:-1], 0.25, flags, 0.125)


def test_only_a_matrix_with_bare_held_rows_is_split():
    """The back-end gets the free block where the held rows and columns are bare, and the
    whole matrix where one of them carries an entry off the diagonal, where nothing is held,
    where the held components' entries are too few to pay, or where the solver is told not to
    split; the solutions agree."""
    A, free = held_rows_matrix()
    b = np.random.default_rng(5).normal(size=A.shape[0])
    solver = RegularisedNewton()
    solver.linear = _Sizes()
    x_block = solver.factorise(A, True, free)(b)
    x_all = solver.factorise(A, True)(b)
    x_no_hold = solver.factorise(A, True, np.ones_like(free))(b)
    coupled = A.copy()
    rows = rows_of(A)
    coupled.data[np.flatnonzero(~free[rows] & (rows != A.indices))[0]] = 1e-3
    x_coupled = solver.factorise(coupled, False, free)(b)
    one_held = np.ones_like(free)
    one_held[np.flatnonzero(~free)[0]] = False  # its entries: below FreeBlock.MIN_SHARE
    x_one_held = solver.factorise(A, True, one_held)(b)
    solver.free_block = False
    solver.factorise(A, True, free)
    n = A.shape[0]
    assert solver.linear.sizes == [int(free.sum()), n, n, n, n, n]
    assert np.abs(A @ x_one_held - b).max() <= 1e-10 * np.abs(x_one_held).max()
    np.testing.assert_allclose(x_block, x_all, rtol=0, atol=1e-12 * np.abs(x_all).max())
    np.testing.assert_array_equal(x_no_hold, x_all)
    assert np.abs(coupled @ x_coupled - b).max() <= 1e-10 * np.abs(x_coupled).max()


def test_the_free_block_follows_the_pattern_and_refuses_coupled_held_entries():
    """One FreeBlock given matrices of two patterns with the same free components takes each
    one's own block; it gives no block where a free row carries an entry in a held column,
    where a held diagonal is zero, or where the indices are not sorted."""
    blocks = FreeBlock()
    A, free = held_rows_matrix()
    B = spd_matrix(seed=7)
    rows = rows_of(B)
    B.data[~free[rows] | ~free[B.indices]] = 0.0
    B.data[~free[rows] & (rows == B.indices)] = 3.0
    assert B.nnz != A.nnz
    for M in (A, B, A):
        block, held = blocks.split(M, free)
        np.testing.assert_array_equal(block.toarray(), M.toarray()[np.ix_(free, free)])
        np.testing.assert_array_equal(held, M.diagonal()[~free])
    column = A.copy()  # a free row's entry in a held column
    column.data[np.flatnonzero(free[rows_of(A)] & ~free[A.indices])[0]] = 1e-3
    assert blocks.split(column, free) is None
    zero = A.copy()
    zero.data[diagonal_positions(zero)[~free][0]] = 0.0
    assert blocks.split(zero, free) is None
    unsorted = sp.csr_matrix((A.data[::-1].copy(), A.indices[::-1].copy(), A.indptr), A.shape)
    unsorted.has_sorted_indices = False
    assert blocks.split(unsorted, free) is None


def test_the_same_solutions_from_the_free_block(monkeypatch):
    """The shear-stretch square (its boundary held) reaches the same homogeneous solution, and
    the sheared rectangle with free sides (every z held: a third of the unknowns) the same
    top-edge reaction in the same iterations, whether the held components' stored zeros are
    factorised or left out. (The rectangle's slack corners cost no energy: their nodes are
    not determined to round-off, so the displacements are not compared there.)"""
    rectangle = Path(__file__).resolve().parents[1] / "benchmarks" / "hard_cases"
    rectangle = rectangle / "sheared_rectangle.toml"
    runs = {}
    taken = []
    split_block = FreeBlock.split

    def counted(self, A, free):
        block = split_block(self, A, free)
        taken.append(block is not None)
        return block

    monkeypatch.setattr(FreeBlock, "split", counted)
    for split in (True, False):
        monkeypatch.setattr(RegularisedNewton, "free_block", split)
        square = read_case(SHEAR_STRETCH, {"mesh": {"rectangle": {"nx": 12, "ny": 12}}})
        sheet = read_case(rectangle, {"mesh": {"rectangle": {"nx": 16, "ny": 8}}})
        runs[split] = (square.solve(tolerance=1e-10), sheet, sheet.solve())
    (square, _, sheet), (square_ref, model, sheet_ref) = runs[True], runs[False]
    u, u_ref = square.final.displacement, square_ref.final.displacement
    assert np.abs(u - u_ref).max() <= 1e-9 * np.abs(u_ref).max()
    assert sheet.final.iterations == sheet_ref.final.iterations
    top, top_ref = (
        model.model.support_reactions(r.final.reactions)["top"] for r in (sheet, sheet_ref)
    )
    assert np.linalg.norm(np.subtract(top, top_ref)) <= 1e-6 * np.linalg.norm(top_ref)
    assert taken and all(taken)  # every factorisation with the split on took the block


def test_a_pattern_is_known_again_by_its_memory_and_by_its_contents(monkeypatch):
    """``_PatternCache.same``: matrices that SciPy builds on the same pattern arrays hold
    views of them, not the arrays themselves; they are known without comparing the arrays
    (the comparison is made to fail here). A copy of the pattern is known by comparison, a
    changed pattern is not. ``with_values`` carries the sorted-indices flag over, true or
    false."""
    from wrinkle.solvers import linear
    from wrinkle.solvers.base import with_values

    A = spd_matrix()
    cache = linear._PatternCache()
    assert not cache.same(A)
    B = sp.csr_matrix((2.0 * A.data, A.indices, A.indptr), shape=A.shape)
    assert B.indices is not A.indices  # a view: the objects differ
    with monkeypatch.context() as patch:
        patch.setattr(linear.np, "array_equal", lambda *args: pytest.fail("compared"))
        assert cache.same(B)
        assert cache.same(with_values(B, 3.0 * A.data))
    copied = sp.csr_matrix((A.data, A.indices.copy(), A.indptr.copy()), shape=A.shape)
    assert cache.same(copied)
    changed = A.copy()
    changed.indices[[0, 1]] = changed.indices[[1, 0]]
    assert not cache.same(changed)
    assert with_values(A, A.data).has_sorted_indices
    unsorted = sp.csr_matrix((A.data[::-1].copy(), A.indices[::-1].copy(), A.indptr), A.shape)
    assert not unsorted.has_sorted_indices
    assert not with_values(unsorted, unsorted.data).has_sorted_indices
