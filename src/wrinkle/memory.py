"""Memory for the arrays of a solve: freed pages kept for the next evaluation.

Each evaluation of a large mesh writes its results into new arrays: on the 320 x 160
rectangle (102,400 elements) some 60 MB (the element coordinates, F, C, stress, tangent,
element forces and the stiffness' 26 MB of values), some 8 GB over a solve. glibc's
allocator takes each array above its mmap threshold (128 KiB, raised up to 32 MiB as such
arrays are freed) from the system and gives it back when it is freed, and trims the heap
whenever its free top exceeds twice that threshold, so that the next evaluation faults in
and zeroes the same memory again. NumPy moreover advises huge pages (``madvise``) for arrays
of 4 MB and more, which splits the heap's mappings and makes each fault dearer where
transparent huge pages are on ``madvise``.

``kept_memory`` lets glibc map nothing with mmap (``M_MMAP_MAX`` = 0: every array comes from
the heap, whatever its size) and trim the heap only above 1 GiB of free top
(``M_TRIM_THRESHOLD``) for the time of a solve, and turns NumPy's huge-page advice off. On
leaving, glibc's defaults are set again (65,536 mappings, 128 KiB; its thresholds then stay
fixed instead of dynamic), the heap is trimmed (``malloc_trim``) and NumPy's advice is as it
was: the memory a solve no longer uses goes back to the system after it. On other C
libraries only NumPy's advice is changed. The numbers are the same to the bit; measured by
``benchmarks/kept_memory.py`` (docs/performance.md, "Freed memory kept").

The settings are process-wide: solves at once in threads of one process share them, and they
are restored when the last of them ends.
"""

from __future__ import annotations

import ctypes
import functools
import platform
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["kept_memory"]

# glibc's mallopt parameters (malloc.h), their defaults, and the trim threshold of a solve
_M_TRIM_THRESHOLD = -1
_M_MMAP_MAX = -4
_DEFAULT_TRIM_THRESHOLD = 128 * 1024
_DEFAULT_MMAP_MAX = 65536
_TRIM_THRESHOLD = 1 << 30

#: whether solves keep their memory (False: the allocator as the process has it; set by
#: ``benchmarks/kept_memory.py`` to compare)
enabled = True

_lock = threading.Lock()
_depth = 0  # solves inside kept_memory now
_restore: list[Callable[[], None]] = []  # what leaving the outermost does, in reverse


@functools.cache
def _glibc() -> Any:
    """The C library's handle where it is glibc (None otherwise, or where it cannot be
    loaded); found once."""
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        return None
    try:
        return ctypes.CDLL("libc.so.6")
    except OSError:
        return None


def _hugepage_setter() -> Callable[[bool], bool] | None:
    """NumPy's ``_set_madvise_hugepage`` (returns the setting before), None if it has none."""
    try:
        from numpy._core import multiarray
    except ImportError:  # NumPy 1
        from numpy.core import multiarray  # type: ignore[no-redef]
    return getattr(multiarray, "_set_madvise_hugepage", None)


def _enter() -> list[Callable[[], None]]:
    """Apply the settings of a solve; returns what restores them."""
    restore: list[Callable[[], None]] = []
    libc = _glibc()
    if libc is not None and libc.mallopt(_M_MMAP_MAX, 0):
        libc.mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD)

        def release() -> None:
            libc.mallopt(_M_MMAP_MAX, _DEFAULT_MMAP_MAX)
            libc.mallopt(_M_TRIM_THRESHOLD, _DEFAULT_TRIM_THRESHOLD)
            libc.malloc_trim(0)

        restore.append(release)
    set_hugepage = _hugepage_setter()
    if set_hugepage is not None:
        before = bool(set_hugepage(False))

        def advise() -> None:
            set_hugepage(before)

        restore.append(advise)
    return restore


@contextmanager
def kept_memory() -> Iterator[None]:
    """A context in which freed memory stays with the process (module docstring); nested and
    concurrent uses share one, applied by the first to enter (if ``enabled``) and restored
    by the last to leave."""
    global _depth
    with _lock:
        _depth += 1
        if _depth == 1 and enabled:
            _restore[:] = _enter()
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                for undo in reversed(_restore):
                    undo()
                _restore.clear()
