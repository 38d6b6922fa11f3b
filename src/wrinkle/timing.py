"""Wall-clock time spent in the parts of a solve (element evaluation, assembly, linear solves)."""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import contextmanager

ELEMENTS = "element evaluation"
ASSEMBLY = "assembly"
LINEAR = "linear solves"


class Stopwatch:
    """Accumulates seconds per named part: ``with watch.part(ELEMENTS): ...``."""

    def __init__(self):
        self.seconds: dict[str, float] = defaultdict(float)
        self._start = time.perf_counter()

    @contextmanager
    def part(self, name: str):
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] += time.perf_counter() - start

    def summary(self) -> dict[str, float]:
        """Seconds in each part, "rest" (everything else) and "total" since creation."""
        total = time.perf_counter() - self._start
        parts = {name: self.seconds.get(name, 0.0) for name in (ELEMENTS, ASSEMBLY, LINEAR)}
        return {**parts, "rest": max(total - sum(parts.values()), 0.0), "total": total}
