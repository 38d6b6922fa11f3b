"""Sparse linear solvers for the regularised iterations: (K + shift I) du = r.

The matrices come from one fixed sparsity pattern (``wrinkle.assembly``): structurally
symmetric, constrained rows and columns replaced by the identity (their zeros still stored;
the solvers hand a back-end the free block alone, ``FreeBlock``). Each back-end keeps what does
not change between iterations (the fill-reducing ordering and symbolic factorisation, the
positions of the diagonal) and factorises only the values again.

- ``superlu``: SciPy's SuperLU, always available; real or complex; the fallback.
- ``pardiso``: Intel MKL PARDISO through ``pypardiso`` (extra ``fast``), real matrices, nested
  dissection ordering, two threads; the ordering is reused while the pattern is unchanged.
  A symmetric matrix is factorised as symmetric indefinite (LDL^T of its upper triangle): on the
  airbag's tangent 0.5-0.9 of the time and 0.6 of the memory of the LU used otherwise
  (``benchmarks/linear_solvers.py``).
- ``cholmod``: CHOLMOD supernodal Cholesky through ``scikit-sparse`` (installed separately,
  against the system's SuiteSparse), symmetric positive definite matrices only (an
  indefinite K + shift I is reported as singular, so the regulariser grows until it is
  positive definite).
- ``amg``: conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid
  (``pyamg``, installed separately), symmetric positive definite matrices only; an
  iterative, inexact solve.

``make_linear_solver("auto", n_dofs)`` takes PARDISO when it is installed, from 2,000
unknowns for the solvers' factorisations (many of one pattern) and from 20,000 for a matrix
factorised once; SuperLU otherwise.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import logging
import os
from collections.abc import Callable
from typing import cast

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from wrinkle import compiled

__all__ = [
    "AUTO_PARDISO_DOFS",
    "AUTO_PARDISO_ONE_OFF_DOFS",
    "INSTALL_HINTS",
    "LINEAR_SOLVERS",
    "AlgebraicMultigrid",
    "Cholmod",
    "FreeBlock",
    "Matrix",
    "MatrixSum",
    "Pardiso",
    "SuperLU",
    "SymmetryCheck",
    "as_csr",
    "diagonal_positions",
    "make_linear_solver",
    "upper_triangle_positions",
    "with_values",
]

logger = logging.getLogger("wrinkle.solver")

Solve = Callable[[np.ndarray], np.ndarray]
# benchmarks/linear_solvers.py: PARDISO's refactorisation (its ordering reused) beats SuperLU's
# factorisation above AUTO_PARDISO_DOFS unknowns; for a matrix factorised once, its first
# factorisation only above AUTO_PARDISO_ONE_OFF_DOFS (and SuperLU reports an exactly singular
# matrix, which PARDISO's pivot perturbation may not)
AUTO_PARDISO_DOFS = 2_000
AUTO_PARDISO_ONE_OFF_DOFS = 20_000


class MatrixSum:
    """A = K + factor M + shift D: K a CSR matrix, M (nnz,) the values of a symmetric matrix
    on K's pattern, D the diagonal entries flagged in ``shifted`` (nnz,) bool; formed only
    where a back-end reads it: the solvers' K + theta M (``wrinkle.solvers.newton``). A
    back-end takes the free block or the upper triangle of A; summing only those entries in
    the pass that gathers them (``values``) writes and reads again none of the (nnz,) sum,
    and gives the entries bit for bit as the sum formed in full (K + factor M first, the
    shift added after). Has the pattern attributes of a CSR matrix (``shape``, ``indptr``,
    ``indices``, ``nnz``, ``has_sorted_indices``, ``dtype``); ``tocsr()`` forms all of A,
    for the back-ends that need it."""

    def __init__(
        self, K: sp.csr_matrix, M: np.ndarray, factor: float, shifted: np.ndarray, shift: float
    ):
        if not M.shape == shifted.shape == K.data.shape:
            raise ValueError(
                f"MatrixSum: {M.shape} values of M and {shifted.shape} flags against "
                f"{K.data.shape} values of K"
            )
        self.K, self.M, self.factor = K, M, float(factor)
        self.shifted, self.shift = shifted, float(shift)
        self.shape = K.shape
        self.indptr, self.indices = K.indptr, K.indices
        self.nnz = K.nnz
        self.has_sorted_indices = K.has_sorted_indices
        self.dtype = np.result_type(K.data, M)

    def values(self, positions: np.ndarray) -> np.ndarray:
        """A.data[positions], (k,): in one parallel pass where the compiled kernels serve A's
        size."""
        if compiled.serves_matrix(self.shape[0]):
            return compiled.sum_take(self._terms(), positions)
        values = self.K.data[positions] + self.factor * self.M[positions]
        values[self.shifted[positions]] += self.shift
        return values

    def any_nonzero(self, positions: np.ndarray) -> bool:
        """np.any(A.data[positions]), without the copies where the kernels serve."""
        if compiled.serves_matrix(self.shape[0]):
            return compiled.sum_any_nonzero(self._terms(), positions)
        return bool(np.any(self.values(positions)))

    def _terms(self) -> compiled.SumTerms:
        return self.K.data, self.M, self.factor, self.shifted, self.shift

    def tocsr(self) -> sp.csr_matrix:
        """All of A, on K's pattern (shared)."""
        data = self.K.data + self.factor * self.M
        data[self.shifted] += self.shift
        return with_values(self.K, data)

    def toarray(self) -> np.ndarray:
        """A as a dense array."""
        return self.tocsr().toarray()


Matrix = sp.csr_matrix | MatrixSum


def with_values(K: sp.csr_matrix, data: np.ndarray) -> sp.csr_matrix:
    """A CSR matrix on K's pattern (shared, not copied) with the values data (nnz,); K's
    sorted-indices flag carried over (``wrinkle.assembly.SparsityPattern.matrix`` sets it),
    so that SciPy does not check the indices of each new matrix again."""
    matrix = sp.csr_matrix((data, K.indices, K.indptr), shape=K.shape)
    matrix.has_sorted_indices = K.has_sorted_indices
    return matrix


def as_csr(A: Matrix) -> sp.csr_matrix:
    """A itself if it is a CSR matrix, else all of the ``MatrixSum``."""
    return A.tocsr() if isinstance(A, MatrixSum) else A


class _FreedWithTheObject:
    """A back-end whose factors are Python objects, freed when they are dropped."""

    def release(self) -> None:
        """Nothing to do (``Pardiso.release`` has work to do)."""


class SuperLU(_FreedWithTheObject):
    """SciPy's SuperLU with a symmetric-mode ordering (the pattern is structurally symmetric)
    and diagonal pivots only (``diag_pivot_thresh = 0``): the regularised matrices need no
    row exchanges, and with threshold pivoting a membrane that is stress-free out of its plane
    (a flat sheet under pressure, an unstressed curved shell) made SuperLU abandon the
    fill-reducing ordering: 60-80 s instead of 0.2 s per factorisation for the flat 64 x 64
    airbag (benchmarks/linear_solvers.py). An exactly zero pivot reports the matrix singular
    and the nonlinear solver raises the regularisation."""

    name = "superlu"

    @staticmethod
    def _lu(A: Matrix) -> spla.SuperLU | None:
        """The factorisation of the class docstring; None if A is exactly singular."""
        try:
            return spla.splu(
                as_csr(A).tocsc(),
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
        except RuntimeError as error:  # "Factor is exactly singular"
            logger.debug("factorisation failed: %s", error)
            return None

    def factorise(self, A: Matrix, symmetric: bool) -> Solve | None:
        """LU of A (real or complex); None if it is exactly singular."""
        lu = self._lu(A)
        return None if lu is None else lu.solve

    def negative_pivots(self, A: sp.csr_matrix) -> int | None:
        """The number of negative eigenvalues of the symmetric matrix A (its inertia, by
        Sylvester's law from the pivots of the symmetric factorisation P A P^T = L D L^T
        that diagonal pivoting with one ordering of rows and columns gives); None if A is
        singular or the pivots left the diagonal."""
        return self.factorise_with_inertia(A)[1]

    def factorise_with_inertia(self, A: sp.csr_matrix) -> tuple[Solve | None, int | None]:
        """One factorisation of the symmetric A: its solve (None if singular) and its number
        of negative eigenvalues (``negative_pivots``; None where unknown)."""
        lu = self._lu(A)
        if lu is None:
            return None, None
        if not np.array_equal(lu.perm_r, lu.perm_c):
            return lu.solve, None
        return lu.solve, int(np.count_nonzero(lu.U.diagonal() < 0.0))


def _same_memory(array: np.ndarray, other: np.ndarray | None) -> bool:
    """Whether array is other or a view of the same memory with the same layout."""
    if other is None:
        return False
    if array is other:
        return True
    return (
        array.shape == other.shape
        and array.dtype == other.dtype
        and array.strides == other.strides
        and array.__array_interface__["data"][0] == other.__array_interface__["data"][0]
    )


class _PatternCache:
    """Remembers the pattern (indptr, indices) whose ordering a back-end has analysed."""

    def __init__(self) -> None:
        self._indptr: np.ndarray | None = None
        self._indices: np.ndarray | None = None
        self._source_indptr: np.ndarray | None = None
        self._source_indices: np.ndarray | None = None

    def same(self, A: sp.csr_matrix | sp.csc_matrix | MatrixSum) -> bool:
        # the model's pattern arrays are never changed in place: the same memory, the same
        # pattern. SciPy's constructor hands each new matrix views of the arrays it is given,
        # so the test is on the memory, not the objects (comparing the arrays took 0.5 s of
        # the 320 x 160 rectangle's 13 s); the arrays kept here keep that memory in use
        if _same_memory(A.indptr, self._source_indptr) and _same_memory(
            A.indices, self._source_indices
        ):
            return True
        self._source_indptr, self._source_indices = A.indptr, A.indices
        if (
            self._indptr is not None
            and self._indices is not None
            and self._indptr.shape == A.indptr.shape
            and self._indices.shape == A.indices.shape
            and np.array_equal(self._indptr, A.indptr)
            and np.array_equal(self._indices, A.indices)
        ):
            return True
        self._indptr, self._indices = A.indptr.copy(), A.indices.copy()
        return False

    def known(self) -> bool:
        """Whether a pattern has been seen (and analysed)."""
        return self._indptr is not None


class SymmetryCheck:
    """Whether matrices on one structurally symmetric CSR pattern (sorted indices) are
    symmetric: the position in ``data`` of each entry's transpose, found once per pattern;
    the norms by the compiled ``wrinkle.compiled.asymmetry`` where the kernels serve a mesh
    of about as many triangles (``compiled.enabled``)."""

    def __init__(self):
        self._pattern = _PatternCache()
        self._transpose = None

    def __call__(self, A: Matrix, relative_tolerance: float = 1e-12) -> bool:
        """|A - A^T| <= relative_tolerance |A| (Frobenius norms); False for a pattern that
        is not structurally symmetric."""
        if isinstance(A, MatrixSum):
            A = A.K  # its M is symmetric
        if not self._pattern.same(A):
            self._transpose = _transpose_positions(A)
        if self._transpose is None:
            return False
        # one pass, no temporaries, where the kernels serve the mesh
        if compiled.serves_matrix(A.shape[0]):
            difference, norm = compiled.asymmetry(A.data, self._transpose)
        else:
            difference = float(np.linalg.norm(A.data - A.data[self._transpose]))
            norm = float(np.linalg.norm(A.data))
        return difference <= relative_tolerance * norm


def _transpose_positions(A: sp.csr_matrix) -> np.ndarray | None:
    """The position in A.data of each entry's transpose, (nnz,); None if A's pattern is not
    structurally symmetric. By bisection in each row where the compiled kernels serve A's
    size and its indices are sorted (``compiled.transpose_positions``), else by SciPy's
    transpose of the entries' numbers."""
    if compiled.serves_matrix(A.shape[0]) and A.has_sorted_indices:
        positions = compiled.transpose_positions(A.indptr, A.indices)
        return positions if A.nnz == 0 or positions.min() >= 0 else None
    nnz = A.nnz
    index = np.int32 if nnz < np.iinfo(np.int32).max else np.int64
    numbers = cast("npt.NDArray[np.int64]", np.arange(1, nnz + 1, dtype=index))
    transposed = sp.csr_matrix((numbers, A.indices, A.indptr), shape=A.shape).T.tocsr()
    transposed.sort_indices()
    same = np.array_equal(transposed.indptr, A.indptr) and np.array_equal(
        transposed.indices, A.indices
    )
    return transposed.data - 1 if same else None


class FreeBlock:
    """The free-free block A_ff of matrices on one pattern whose constrained rows and columns
    hold nothing but their diagonal: the solvers' K + theta M, whose constrained entries are
    zeroed and whose constrained diagonal stays one. A x = b is then A_ff x_f = b_f with
    x_c = b_c / A_cc. A back-end given all of A would order and factorise the constrained
    entries' stored zeros as if they were stiffness: on the sheared rectangle at 320 x 160,
    whose z components are all held (155,043 unknowns, 102,078 free), half the stored entries
    are such zeros and PARDISO's Cholesky took 0.19 s against 0.076 s for A_ff
    (docs/notes/2026-12-rectangle-speed.md). The positions of A_ff in A.data are found once
    per pattern and set of free components; the block's index arrays are kept, so a back-end
    sees the same pattern each time (after comparing the arrays) and reuses its ordering.

    Only where the entries outside A_ff are at least MIN_SHARE of the stored ones: the
    positions and each block's copy of the values cost memory, 82 MB more at the peak of the
    100,352-element nested airbag with bending (held at its seams and symmetry lines: under 1 %
    of the entries), and saved no time there (28.8 s against 29.9 and 28.1 s for the whole
    matrix, in turns, another job running; benchmarks/scale.py --whole-matrix)."""

    MIN_SHARE = 0.1

    def __init__(self) -> None:
        self._pattern = _PatternCache()
        self._free: np.ndarray | None = None
        # positions in A.data of A_ff, of the other off-diagonal entries and of the held
        # diagonal; A_ff's indptr and indices (None: A lacks a held diagonal entry)
        self._layout: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None
        self._layout = None

    def _prepare(self, A: Matrix, free: np.ndarray) -> None:
        """Find the positions for A's pattern and ``free``."""
        self._layout = None
        rows = _row_indices(A)
        columns = A.indices
        kept = free[rows] & free[columns]
        on_diagonal = rows == columns
        held_diagonal = np.flatnonzero(on_diagonal & ~free[rows])
        if held_diagonal.size != np.count_nonzero(~free):
            return
        kept_count = int(np.count_nonzero(kept))
        if A.nnz - kept_count < self.MIN_SHARE * A.nnz:
            return
        index = np.int32 if A.nnz < np.iinfo(np.int32).max else np.int64
        number = np.cumsum(free) - 1  # the free components' numbers in A_ff
        positions = np.flatnonzero(kept).astype(index)
        counts = np.bincount(number[rows[positions]], minlength=int(np.count_nonzero(free)))
        indptr = np.concatenate(([0], np.cumsum(counts))).astype(A.indptr.dtype)
        indices = number[columns[positions]].astype(A.indices.dtype)
        off = np.flatnonzero(~kept & ~on_diagonal).astype(index)
        self._layout = (positions, off, held_diagonal.astype(index), indptr, indices)

    def split(self, A: Matrix, free: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray] | None:
        """(A_ff, A's held diagonal) if A has the structure of the class docstring (sorted
        indices; free (n,) bool, at least one component held), else None."""
        # the entries outside A_ff are at most twice those of the held rows (the pattern is
        # structurally symmetric): where that is too few, nothing is kept of A, not even its
        # pattern (a copy of the indices: 0.2 GB on the 10^6-element airbag with bending)
        if 2 * int(np.diff(A.indptr)[~free].sum()) < self.MIN_SHARE * A.nnz:
            return None
        if not A.has_sorted_indices:
            return None
        if (
            not self._pattern.same(A)
            or self._free is None
            or self._free.shape != free.shape
            or not np.array_equal(self._free, free)
        ):
            self._free = free.copy()
            self._prepare(A, free)
        if self._layout is None:
            return None
        positions, off, held_diagonal, indptr, indices = self._layout
        if _any_nonzero(A, off):
            return None
        held = _take(A, held_diagonal)
        if not np.all(held != 0):
            return None
        n = indptr.size - 1
        block = sp.csr_matrix((_take(A, positions), indices, indptr), shape=(n, n))
        block.has_sorted_indices = True
        return block, held


def _take(A: Matrix, positions: np.ndarray) -> np.ndarray:
    """A.data[positions]; in parallel where the compiled kernels serve A's size."""
    if isinstance(A, MatrixSum):
        return A.values(positions)
    if compiled.serves_matrix(A.shape[0]) and not np.iscomplexobj(A.data):
        return compiled.take(A.data, positions)
    return A.data[positions]


def _any_nonzero(A: Matrix, positions: np.ndarray) -> bool:
    """np.any(A.data[positions]); in parallel, without the copy, where the compiled kernels
    serve A's size."""
    if isinstance(A, MatrixSum):
        return A.any_nonzero(positions)
    if compiled.serves_matrix(A.shape[0]) and not np.iscomplexobj(A.data):
        return compiled.any_nonzero(A.data, positions)
    return bool(np.any(A.data[positions]))


def upper_triangle_positions(A: Matrix):
    """(positions in A.data, indptr, indices) of the upper triangle of A, diagonal included,
    as a CSR pattern; A has sorted indices."""
    n = A.shape[0]
    rows = _row_indices(A)
    positions = np.flatnonzero(A.indices >= rows)
    indptr = np.concatenate(([0], np.cumsum(np.bincount(rows[positions], minlength=n))))
    return positions, indptr.astype(A.indptr.dtype), A.indices[positions]


def _locate_mkl_runtime() -> None:
    """Set PYPARDISO_MKL_RT, unless set, to MKL's runtime library in the file list of the
    installed ``mkl`` package: pypardiso otherwise looks for it with ``find_library`` and then
    searches the whole lib directory of the environment, at import and for every solver it
    makes (about 1 s each in a large environment)."""
    if "PYPARDISO_MKL_RT" in os.environ:
        return
    try:
        files = importlib.metadata.distribution("mkl").files or []
    except importlib.metadata.PackageNotFoundError:
        return
    libraries = sorted((str(f.locate()) for f in files if f.name.startswith("libmkl_rt")), key=len)
    found = [path for path in libraries if os.path.exists(path)]
    if found:
        os.environ["PYPARDISO_MKL_RT"] = found[0]


def _no_spin_wait() -> None:
    """Set KMP_BLOCKTIME=0, unless set: the OpenMP threads of MKL (Intel's runtime) then sleep
    as soon as a PARDISO call returns instead of spinning for 200 ms, which on a 2-core
    machine took a core from the element evaluation and the NumPy work between the solves
    (airbag, 32,768 elements, 122 iterations, two runs each in turns: elements 7.3 / 5.4 ->
    3.8 / 4.2 s, rest 5.1 / 5.6 -> 1.4 / 1.6 s, linear solves unchanged; README, Performance).
    Read by the runtime when it starts, so set before pypardiso loads MKL."""
    os.environ.setdefault("KMP_BLOCKTIME", "0")


class Pardiso:
    """MKL PARDISO: real symmetric indefinite (matrix type -2, upper triangle) when the caller
    says the matrix is symmetric, else real structurally symmetric (type 1); each type's
    ordering and symbolic factorisation are reused while the pattern is unchanged."""

    name = "pardiso"
    #: the most iterative-refinement steps of each solve (MKL's iparm(8)); None keeps MKL's
    #: default of two, 0 (the default) refines only after a factorisation that perturbed
    #: pivots. A solve then costs 0.06 s instead of 0.09-0.13 s (148,428 unknowns,
    #: benchmarks/modes.py), its residual 1.3e-14 instead of 7.5e-15; on the sheared
    #: rectangle's K + theta M (155,043 unknowns) 0.045 s instead of 0.14 s, relative
    #: residual 3e-13 (docs/notes/2026-12-rectangle-speed.md).
    refinement: int | None = 0
    #: try a Cholesky factorisation (matrix type 2) of a symmetric matrix first, and the
    #: symmetric indefinite one only if it fails (the matrix is not positive definite); after
    #: a failure, the next CHOLESKY_PAUSE symmetric matrices go straight to LDL^T (twice as
    #: many after each further failure). On the
    #: sheared rectangle's K + theta M (155,043 unknowns) Cholesky took 0.39-0.47 s against
    #: 0.54-0.71 s (docs/notes/2026-12-rectangle-speed.md).
    cholesky: bool = True
    CHOLESKY_PAUSE = 8

    def __init__(self):
        _locate_mkl_runtime()
        _no_spin_wait()
        import pypardiso

        self._solvers = {mtype: pypardiso.PyPardisoSolver(mtype=mtype) for mtype in (1, -2, 2)}
        self._analysed = {mtype: _PatternCache() for mtype in (1, -2, 2)}
        self._cholesky_pause = 0
        self._cholesky_failures = 0
        # upper_triangle_positions of the pattern in _upper_pattern
        self._upper: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._upper_pattern = _PatternCache()
        # the 1-based int32 index arrays of the last pattern given to PARDISO, and that
        # pattern's arrays (kept, so that their memory identifies it)
        self._one_based: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._fallback = SuperLU()

    def _call(self, solver, M: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        """x from MKL's pardiso in the solver's present phase for the CSR matrix M (float64,
        sorted indices, no empty row) and right-hand sides b (n, k), Fortran order:
        pypardiso's call, except that M's index arrays are converted to 1-based int32 once
        per pattern instead of at every call (two (nnz,) arrays, 232 MB at 10^6 elements
        with bending, allocated and filled again for each factorisation and each solve).
        PyPardisoError if PARDISO reports an error."""
        from pypardiso.pardiso_wrapper import PyPardisoError

        known = self._one_based
        if (
            known is None
            or not _same_memory(M.indptr, known[0])
            or not _same_memory(M.indices, known[1])
        ):
            ia = M.indptr.astype(np.int32) + 1
            ja = M.indices.astype(np.int32) + 1
            known = self._one_based = (M.indptr, M.indices, ia, ja)
        ia, ja = known[2], known[3]
        data = np.ascontiguousarray(M.data, dtype=np.float64)
        x = np.zeros_like(b)
        error = ctypes.c_int32(0)
        int_p, double_p = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
        solver._mkl_pardiso(
            solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])),
            ctypes.byref(ctypes.c_int32(1)),  # maxfct
            ctypes.byref(ctypes.c_int32(1)),  # mnum
            ctypes.byref(ctypes.c_int32(solver.mtype)),
            ctypes.byref(ctypes.c_int32(solver.phase)),
            ctypes.byref(ctypes.c_int32(M.shape[0])),
            data.ctypes.data_as(double_p),
            ia.ctypes.data_as(int_p),
            ja.ctypes.data_as(int_p),
            solver.perm.ctypes.data_as(int_p),
            ctypes.byref(ctypes.c_int32(b.shape[1])),  # nrhs
            solver.iparm.ctypes.data_as(int_p),
            ctypes.byref(ctypes.c_int32(solver.msglvl)),
            b.ctypes.data_as(double_p),
            x.ctypes.data_as(double_p),
            ctypes.byref(error),
        )
        if error.value != 0:
            raise PyPardisoError(error.value)
        return np.ascontiguousarray(x)

    def release(self) -> None:
        """Free MKL's memory of both matrix types (pypardiso's solvers do not when they are
        dropped); the next factorisation starts with a new ordering."""
        for mtype, solver in self._solvers.items():
            if self._analysed[mtype].known():
                solver.free_memory(everything=True)
            self._analysed[mtype] = _PatternCache()

    def factorise(self, A: Matrix, symmetric: bool, definite: bool = True) -> Solve | None:
        """A solve function for A, or None if it is singular. definite=False: a symmetric A
        is factorised as indefinite at once (``cholesky``; its inertia is then known)."""
        if np.issubdtype(A.dtype, np.complexfloating):
            return self._fallback.factorise(A, symmetric)
        A = A if A.has_sorted_indices else as_csr(A).sorted_indices()
        M, mtype = A, 1
        if symmetric:
            upper = self._upper
            if not self._upper_pattern.same(A) or upper is None:
                upper = self._upper = upper_triangle_positions(A)
            positions, indptr, indices = upper
            M, mtype = sp.csr_matrix((_take(A, positions), indices, indptr), shape=A.shape), -2
            if definite and self.cholesky:
                if self._cholesky_pause > 0:
                    self._cholesky_pause -= 1
                else:
                    solve = self._factorise(A, M, 2)
                    if solve is not None:
                        return solve
                    self._cholesky_failures += 1
                    self._cholesky_pause = self.CHOLESKY_PAUSE << min(self._cholesky_failures, 10)
        return self._factorise(A, as_csr(M), mtype)

    def _factorise(self, A: Matrix, M: sp.csr_matrix, mtype: int) -> Solve | None:
        """Factorise M (A's upper triangle for the symmetric types) as PARDISO's mtype."""
        from pypardiso.pardiso_wrapper import PyPardisoError

        solver = self._solvers[mtype]
        rhs = np.zeros((A.shape[0], 1))
        try:
            if not self._analysed[mtype].same(A):
                solver.set_phase(11)  # ordering and symbolic factorisation
                self._call(solver, M, rhs)
            solver.set_phase(22)  # numerical factorisation only
            self._call(solver, M, rhs)
        except PyPardisoError as error:
            logger.debug("PARDISO factorisation failed: %s", error)
            self._analysed[mtype] = _PatternCache()
            return None

        def solve(b: np.ndarray) -> np.ndarray:
            solver.set_phase(33)
            if self.refinement is not None:
                solver.iparm[7] = self.refinement
            return self._call(solver, M, np.asfortranarray(b[:, None], dtype=np.float64))[:, 0]

        return solve

    def negative_pivots(self, A: sp.csr_matrix) -> int | None:
        """The number of negative eigenvalues of the symmetric matrix A: the inertia that
        PARDISO's symmetric indefinite factorisation reports (iparm(23)); None if it fails."""
        return self.factorise_with_inertia(A)[1]

    def factorise_with_inertia(self, A: sp.csr_matrix) -> tuple[Solve | None, int | None]:
        """One symmetric indefinite factorisation of A: its solve (None if it fails) and its
        number of negative eigenvalues (``negative_pivots``)."""
        solve = self.factorise(A, symmetric=True, definite=False)
        if solve is None:
            return None, None
        return solve, int(self._solvers[-2].iparm[22])


class Cholmod(_FreedWithTheObject):
    """CHOLMOD Cholesky of a symmetric positive definite matrix; symbolic analysis reused."""

    name = "cholmod"

    def __init__(self):
        from sksparse import cholmod

        self._cholmod = cholmod
        self._factor = None
        self._pattern = _PatternCache()
        self._fallback = SuperLU()

    def factorise(self, A: Matrix, symmetric: bool) -> Solve | None:
        A = as_csr(A)
        if not symmetric or np.iscomplexobj(A.data):
            return self._fallback.factorise(A, symmetric)
        A_csc = A.tocsc()  # the same matrix for a symmetric one, in CHOLMOD's format
        try:
            if self._factor is None or not self._pattern.same(A_csc):
                self._factor = self._cholmod.analyze(A_csc, mode="supernodal")
            self._factor.cholesky_inplace(A_csc)
        except self._cholmod.CholmodNotPositiveDefiniteError:
            return None
        return self._factor.solve_A


class AlgebraicMultigrid(_FreedWithTheObject):
    """Conjugate gradients with a smoothed-aggregation AMG preconditioner (pyamg)."""

    name = "amg"

    relative_tolerance = 1e-10
    max_iterations = 2000

    def __init__(self):
        import pyamg

        self._pyamg = pyamg
        self._fallback = SuperLU()

    def factorise(self, A: Matrix, symmetric: bool) -> Solve | None:
        A = as_csr(A)
        if not symmetric or np.iscomplexobj(A.data):
            return self._fallback.factorise(A, symmetric)
        hierarchy = self._pyamg.smoothed_aggregation_solver(A, symmetry="symmetric")
        preconditioner = hierarchy.aspreconditioner(cycle="V")

        def solve(b: np.ndarray) -> np.ndarray:
            x, info = spla.cg(
                A, b, rtol=self.relative_tolerance, maxiter=self.max_iterations, M=preconditioner
            )
            if info != 0:
                logger.debug("AMG-CG did not converge (info %d)", info)
                return np.full_like(b, np.nan)  # the nonlinear solver rejects the step
            return x

        return solve


LINEAR_SOLVERS = {
    "superlu": SuperLU,
    "pardiso": Pardiso,
    "cholmod": Cholmod,
    "amg": AlgebraicMultigrid,
}
#: How to install the package each optional back-end needs, for the messages.
INSTALL_HINTS = {
    "pardiso": 'pypardiso: install it with pip install "wrinkle[fast]" (x86-64 only)',
    "cholmod": (
        "scikit-sparse, which is built against the system's SuiteSparse: install that first "
        "(Debian/Ubuntu: apt install libsuitesparse-dev), then pip install scikit-sparse"
    ),
    "amg": "pyamg: install it with pip install pyamg",
}


def make_linear_solver(name: str = "auto", n_dofs: int = 0, one_off: bool = False):
    """The back-end called ``name`` (one of LINEAR_SOLVERS, or "auto": PARDISO from
    AUTO_PARDISO_DOFS unknowns if pypardiso is installed, or from AUTO_PARDISO_ONE_OFF_DOFS
    for a caller that factorises one matrix and no more of its pattern (``one_off``), else
    SuperLU). ValueError for an unknown name; ImportError saying how to install a back-end
    that is not installed."""
    if name == "auto":
        if n_dofs >= (AUTO_PARDISO_ONE_OFF_DOFS if one_off else AUTO_PARDISO_DOFS):
            try:
                return Pardiso()
            except (ImportError, OSError) as error:  # the extra is optional: fall back
                logger.debug("PARDISO unavailable (%s); using SuperLU", error)
        return SuperLU()
    if name not in LINEAR_SOLVERS:
        raise ValueError(
            f"unknown linear solver '{name}' (one of auto, {', '.join(LINEAR_SOLVERS)})"
        )
    try:
        return LINEAR_SOLVERS[name]()
    except (ImportError, OSError) as error:
        raise ImportError(f"linear solver '{name}' needs {INSTALL_HINTS[name]} ({error})") from None


def diagonal_positions(A: sp.csr_matrix) -> np.ndarray:
    """Index into A.data of each diagonal entry (n,); every diagonal entry must be stored."""
    positions = np.flatnonzero(_row_indices(A) == A.indices)
    if positions.size != A.shape[0]:
        raise ValueError("the sparsity pattern lacks diagonal entries")
    return positions


def _row_indices(A: Matrix) -> np.ndarray:
    """Row of each stored entry of the CSR matrix A, (nnz,)."""
    return np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
