"""Freed memory kept during a solve (``wrinkle.memory``): glibc's mmap and trim settings and
NumPy's huge-page advice set on entering, glibc's defaults and NumPy's advice restored on
leaving the outermost use, and the same numbers with and without."""

from __future__ import annotations

import platform

import numpy as np
import pytest

import wrinkle
from wrinkle import memory
from wrinkle.materials import StVenantKirchhoff
from wrinkle.model import Model
from wrinkle.solvers import bordered
from wrinkle.solvers.newton import RegularisedNewton


class FakeLibc:
    """Records the calls ``kept_memory`` makes to glibc."""

    def __init__(self):
        self.calls: list[tuple] = []

    def mallopt(self, parameter: int, value: int) -> int:
        self.calls.append(("mallopt", parameter, value))
        return 1

    def malloc_trim(self, pad: int) -> int:
        self.calls.append(("malloc_trim", pad))
        return 1


@pytest.fixture
def fakes(monkeypatch):
    """A recording glibc and a NumPy huge-page setting that starts on."""
    libc = FakeLibc()
    advice = {"on": True}

    def set_hugepage(enabled: bool) -> bool:
        before, advice["on"] = advice["on"], enabled
        return before

    monkeypatch.setattr(memory, "_glibc", lambda: libc)
    monkeypatch.setattr(memory, "_hugepage_setter", lambda: set_hugepage)
    return libc, advice


KEEP = [("mallopt", -4, 0), ("mallopt", -1, 1 << 30)]  # M_MMAP_MAX, M_TRIM_THRESHOLD
RESTORE = [("mallopt", -4, 65536), ("mallopt", -1, 128 * 1024), ("malloc_trim", 0)]
MATERIAL = StVenantKirchhoff.isotropic(E=1e3, nu=0.3, thickness=0.01)


def test_the_thresholds_are_set_inside_and_glibcs_defaults_restored_after(fakes):
    libc, advice = fakes
    with memory.kept_memory():
        assert libc.calls == KEEP
        assert advice["on"] is False
    assert libc.calls == KEEP + RESTORE
    assert advice["on"] is True


def test_nested_uses_apply_once_and_the_outermost_restores(fakes):
    libc, advice = fakes
    with memory.kept_memory():
        with memory.kept_memory():
            pass
        assert libc.calls == KEEP  # the inner one neither set nor restored anything
        assert advice["on"] is False
    assert libc.calls == KEEP + RESTORE
    assert advice["on"] is True


def test_a_failed_solve_restores_them_too(fakes):
    libc, advice = fakes
    with pytest.raises(RuntimeError), memory.kept_memory():
        raise RuntimeError("the solve failed")
    assert libc.calls == KEEP + RESTORE
    assert advice["on"] is True


def test_huge_page_advice_left_off_stays_off(fakes):
    libc, advice = fakes
    advice["on"] = False
    with memory.kept_memory():
        pass
    assert advice["on"] is False


def test_disabled_it_changes_nothing(fakes, monkeypatch):
    libc, advice = fakes
    monkeypatch.setattr(memory, "enabled", False)
    with memory.kept_memory():
        assert advice["on"] is True
    assert libc.calls == []


def test_without_glibc_only_numpys_advice_changes(fakes, monkeypatch):
    _, advice = fakes
    monkeypatch.setattr(memory, "_glibc", lambda: None)
    with memory.kept_memory():
        assert advice["on"] is False
    assert advice["on"] is True


def test_the_solvers_run_inside_it(fakes, monkeypatch):
    libc, _ = fakes
    seen = []
    monkeypatch.setattr(
        RegularisedNewton, "_solve", lambda self, *args: seen.append(list(libc.calls))
    )
    RegularisedNewton().solve("problem", np.zeros(2))
    monkeypatch.setattr(bordered, "_solve_bordered", lambda *args: seen.append(list(libc.calls)))
    bordered.solve_bordered(None, None, np.zeros(2), 0.0, RegularisedNewton())
    assert seen == [KEEP, KEEP + RESTORE + KEEP]


def square() -> Model:
    """A unit square held at its bottom edge, its top edge pulled and sheared: wrinkled."""
    model = Model(wrinkle.rectangle(1.0, 1.0, 6, 6), MATERIAL)
    model.fix("bottom")
    model.prescribe("top", (0.1, 0.05, 0.0))
    return model


def test_a_solve_gives_the_same_bits_and_leaves_numpys_advice_as_it_was(monkeypatch):
    if platform.system() != "Linux":
        pytest.skip("glibc's allocator: Linux")
    set_hugepage = memory._hugepage_setter()
    assert set_hugepage is not None
    before = set_hugepage(True)
    try:
        kept = square().solve(steps=2).final.displacement
        assert set_hugepage(True) is True  # restored after the solve
        monkeypatch.setattr(memory, "enabled", False)
        system = square().solve(steps=2).final.displacement
    finally:
        set_hugepage(before)
    assert np.array_equal(kept, system)
    assert np.abs(kept).max() > 0.01
