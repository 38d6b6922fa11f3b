"""The passes over a tangent's values between an evaluation and PARDISO, old way and new way
side by side, in one process: what each factorisation and solve of a Newton iteration pays
besides PARDISO's own work.

On two matrices of the solvers (the tangent at the reference state of the case's first load
step, its metric and free components):

- ``rectangle``: the sheared rectangle of benchmarks/hard_cases (every z held, so the
  back-end gets the free block), ``--rectangle`` squares along x;
- ``airbag``: the quarter airbag of examples/airbag.toml with bending on n x n squares
  (``--airbag``; nothing worth a free block is held, so PARDISO gets the upper triangle).

Each row is the median of ``--repeat`` calls after a first one, ms:

- ``transpose map``: the position of each entry's transpose (``SymmetryCheck``, once per
  pattern): SciPy's transpose of the entries' numbers, against the bisection kernel
  ``wrinkle.compiled.transpose_positions``;
- ``K + theta M to PARDISO``: the values PARDISO reads, formed as before 6 December 2026 (the
  whole sum K + theta M, then the free block's zero test and gather, then the upper
  triangle's gather) against a ``MatrixSum`` (the same values summed in the gathering
  pass); the two give the same bits, which the script checks;
- ``PARDISO solve``: one forward and back substitution with a factorisation of the upper
  triangle, through pypardiso's call (which converts the index arrays to 1-based int32 each
  time) against ``Pardiso._call`` (which converts them once per pattern).

Needs the ``fast`` extra (Numba and pypardiso).

    python benchmarks/matrix_passes.py --rectangle 320 --airbag 224
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from timing import median_ms

from wrinkle import compiled
from wrinkle.case import read_case
from wrinkle.solvers.base import Evaluation
from wrinkle.solvers.linear import (
    FreeBlock,
    MatrixSum,
    Pardiso,
    _take,
    upper_triangle_positions,
)
from wrinkle.solvers.newton import RegularisedNewton

ROOT = Path(__file__).resolve().parents[1]
RECTANGLE = ROOT / "benchmarks" / "hard_cases" / "sheared_rectangle.toml"
AIRBAG = ROOT / "examples" / "airbag.toml"
THETA = 1e-6


def reference_evaluation(path: Path, overrides: dict) -> tuple[Evaluation, np.ndarray]:
    """The evaluation of the case's first load step at the reference state, and its free
    components."""
    system = read_case(path, overrides=overrides).model.discretise()
    problem = system.at(1.0)
    return problem.evaluate(np.zeros(system.n_dofs)), ~system.constrained


def scipy_transpose(A: sp.csr_matrix) -> np.ndarray:
    """The transpose map as SymmetryCheck found it before: SciPy's transpose of the
    entries' numbers."""
    numbers = np.arange(1, A.nnz + 1, dtype=np.int32)
    transposed = sp.csr_matrix((numbers, A.indices, A.indptr), shape=A.shape).T.tocsr()
    transposed.sort_indices()
    return transposed.data - 1


def whole_sum_kernel() -> Callable:
    """The parallel kernel that formed all of K + theta M before (``shifted_sum``, removed
    from wrinkle.compiled): out = data + factor other, then out[diagonal] += shift."""
    import numba

    @numba.njit(parallel=True, boundscheck=False, cache=True)
    def shifted_sum(data, other, factor, diagonal, shift, out):
        for j in numba.prange(data.shape[0]):
            out[j] = data[j] + factor * other[j]
        for j in numba.prange(diagonal.shape[0]):
            out[diagonal[j]] += shift

    return shifted_sum


def rows(name: str, ev: Evaluation, free: np.ndarray, repeat: int) -> None:
    """Print the three rows of one matrix."""
    K = ev.tangent
    solver = RegularisedNewton()
    solver.initial_theta(K, free)
    summed = solver.regularised(ev, THETA, free)
    assert isinstance(summed, MatrixSum)
    split = FreeBlock().split(summed, free) is not None
    old_transpose = median_ms(lambda: scipy_transpose(K), repeat)
    new_transpose = median_ms(lambda: compiled.transpose_positions(K.indptr, K.indices), repeat)
    assert np.array_equal(scipy_transpose(K), compiled.transpose_positions(K.indptr, K.indices))

    old_blocks, new_blocks = FreeBlock(), FreeBlock()
    first = new_blocks.split(summed, free)[0] if split else summed
    upper_positions = upper_triangle_positions(first)[0]
    old_sum_kernel = whole_sum_kernel()

    def old_way() -> np.ndarray:
        data = np.empty_like(K.data)
        old_sum_kernel(K.data, summed.M, summed.factor, diagonal, summed.shift, data)
        whole = sp.csr_matrix((data, K.indices, K.indptr), shape=K.shape)
        whole.has_sorted_indices = True
        block = old_blocks.split(whole, free)[0] if split else whole
        return _take(block, upper_positions)

    def new_way() -> np.ndarray:
        block = new_blocks.split(summed, free)[0] if split else summed
        return _take(block, upper_positions)

    diagonal = np.flatnonzero(summed.shifted)
    assert np.array_equal(old_way(), new_way())
    old_sum, new_sum = median_ms(old_way, repeat), median_ms(new_way, repeat)

    pardiso = Pardiso()
    positions, indptr, indices = upper_triangle_positions(K)
    upper_K = sp.csr_matrix((summed.values(positions), indices, indptr), shape=K.shape)
    solver_2 = pardiso._solvers[-2]
    solver_2.set_phase(12)
    pardiso._call(solver_2, upper_K, np.zeros((K.shape[0], 1)))
    solver_2.set_phase(33)
    b = np.asfortranarray(np.random.default_rng(0).normal(size=(K.shape[0], 1)))
    old_solve = median_ms(lambda: solver_2._call_pardiso(upper_K, b), repeat)
    new_solve = median_ms(lambda: pardiso._call(solver_2, upper_K, b), repeat)
    assert np.allclose(solver_2._call_pardiso(upper_K, b), pardiso._call(solver_2, upper_K, b))
    pardiso.release()

    label = f"{name} ({K.shape[0]:,} unknowns, {K.nnz:,} entries{', free block' if split else ''})"
    print(label)
    for part, old, new in (
        ("transpose map", old_transpose, new_transpose),
        ("K + theta M to PARDISO", old_sum, new_sum),
        ("PARDISO solve", old_solve, new_solve),
    ):
        print(f"  {part:<24} {old:9.1f} {new:9.1f} {new / old:7.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rectangle", type=int, nargs="*", default=[320])
    parser.add_argument("--airbag", type=int, nargs="*", default=[224])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(f"  {'ms':<24} {'before':>9} {'after':>9} {'ratio':>7}")
    for n in args.rectangle:
        mesh = {"rectangle": {"nx": n, "ny": n // 2}}
        ev, free = reference_evaluation(RECTANGLE, {"mesh": mesh})
        rows(f"rectangle {n} x {n // 2}", ev, free, args.repeat)
    for n in args.airbag:
        overrides = {"mesh": {"rectangle": {"nx": n, "ny": n}}, "material": {"bending": True}}
        ev, free = reference_evaluation(AIRBAG, overrides)
        rows(f"airbag with bending, {2 * n * n:,} elements", ev, free, args.repeat)


if __name__ == "__main__":
    main()
