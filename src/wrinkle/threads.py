"""The threads of the numerical libraries under wrinkle: OpenBLAS limited where its threads
cost more than they give.

NumPy's and SciPy's OpenBLAS start a thread per core for a large enough product (a dot
product of two long vectors, a tall matrix times a vector) and keep those threads spinning
for a while after it, waiting for the next. On a machine with as many cores as those threads,
the spinning threads then take the cores away from MKL PARDISO's threads and from the Numba
kernels that run in parallel (``wrinkle.compiled``) until they fall asleep. wrinkle's own
BLAS calls are vector operations, which one thread does about as fast, so the solvers
(``wrinkle.solvers.base.RegularisedSolver.solve``) and the Lanczos iterations of the modal
solve (``wrinkle.modes``) run with OpenBLAS on one thread (threadpoolctl, where installed: the
extra ``fast``). MKL's and Numba's threads are left alone. Measured by
``benchmarks/rectangle_speed.py`` and ``benchmarks/modes.py`` (docs/performance.md).
"""

from __future__ import annotations

import contextlib

__all__ = ["blas_threads"]


def blas_threads(limit: int | None) -> contextlib.AbstractContextManager:
    """A context in which OpenBLAS (NumPy's and SciPy's) uses at most ``limit`` threads
    (threadpoolctl); nothing for limit None or without threadpoolctl."""
    if limit is None:
        return contextlib.nullcontext()
    try:
        from threadpoolctl import threadpool_limits  # type: ignore[import-untyped, import-not-found, unused-ignore]
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(limits={"libscipy_openblas": limit})
