"""Timing a call for the benchmarks' tables (shared by the scripts in this folder)."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def median_ms(call: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``repeat`` calls after a first one (which may load or compile what
    the call needs), ms."""
    call()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))
