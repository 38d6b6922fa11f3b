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
import sys
from typing import Any

__all__ = ["blas_threads"]

# threadpoolctl's controller of the OpenBLAS libraries loaded, and the number of modules
# imported when it was made: scanning the loaded libraries costs about 1 ms, so it is made
# again only after new imports (one of them may have loaded another OpenBLAS)
_openblas: Any = None
_modules_at_scan = -1


def _openblas_controller() -> Any:
    """The OpenBLAS libraries in this process (threadpoolctl's ``ThreadpoolController``
    selected by internal_api "openblas", whatever their file names), or None without
    threadpoolctl."""
    global _openblas, _modules_at_scan
    if len(sys.modules) != _modules_at_scan:
        _modules_at_scan = len(sys.modules)
        try:
            from threadpoolctl import ThreadpoolController  # type: ignore[import-untyped, import-not-found, unused-ignore]
        except ImportError:
            _openblas = None
        else:
            _openblas = ThreadpoolController().select(internal_api="openblas")
    return _openblas


def blas_threads(limit: int | None) -> contextlib.AbstractContextManager:
    """A context in which every loaded OpenBLAS (NumPy's, SciPy's) uses at most ``limit``
    threads, restored on leaving; nothing for limit None, without threadpoolctl or without
    OpenBLAS. The setting is process-wide: solves run at once in threads of one process share
    it."""
    if limit is None:
        return contextlib.nullcontext()
    controller = _openblas_controller()
    if controller is None or not controller.lib_controllers:
        return contextlib.nullcontext()
    return controller.limit(limits=limit)
