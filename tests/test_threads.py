"""OpenBLAS on one thread during the solves (``wrinkle.threads``): the context limits every
loaded OpenBLAS and restores it, and the Newton-type solvers and the bordered solver run
inside it with their ``blas_threads``."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

from wrinkle.solvers import base as solver_base
from wrinkle.solvers import bordered
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.threads import blas_threads


def openblas_threads() -> list[int]:
    """The thread counts of the loaded OpenBLAS libraries (threadpoolctl)."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    return [
        info["num_threads"]
        for info in threadpoolctl.threadpool_info()
        if info["internal_api"] == "openblas"
    ]


def test_the_context_limits_openblas_and_restores_it():
    np.ones(3) @ np.ones(3)  # NumPy's BLAS is loaded
    before = openblas_threads()
    if not before:
        pytest.skip("NumPy's BLAS is not OpenBLAS")
    with blas_threads(1):
        assert openblas_threads() == [1] * len(before)
    assert openblas_threads() == before
    with blas_threads(None):
        assert openblas_threads() == before


@pytest.fixture
def recorded_limits(monkeypatch):
    """The limits the solvers enter ``blas_threads`` with, in order."""
    limits: list[int | None] = []

    def record(limit):
        limits.append(limit)
        return contextlib.nullcontext()

    monkeypatch.setattr(solver_base, "blas_threads", record)
    monkeypatch.setattr(bordered, "blas_threads", record)
    return limits


def test_a_solve_runs_with_openblas_on_one_thread(recorded_limits, monkeypatch):
    solver = RegularisedNewton()
    assert solver.blas_threads == 1
    monkeypatch.setattr(RegularisedNewton, "_solve", lambda self, *args: ("solved", args))
    assert solver.solve("problem", np.zeros(2))[0] == "solved"
    monkeypatch.setattr(bordered, "_solve_bordered", lambda *args: "bordered")
    assert bordered.solve_bordered(None, None, np.zeros(2), 0.0, solver) == "bordered"
    solver.blas_threads = None
    solver.solve("problem", np.zeros(2))
    assert recorded_limits == [1, 1, None]
