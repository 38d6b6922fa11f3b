"""The stopwatch of a solve: its parts add up to no more than the total, and each part of the
work (elements, assembly, linear solves) is counted."""

from __future__ import annotations

import time

import wrinkle
from wrinkle.materials import StVenantKirchhoff
from wrinkle.timing import ASSEMBLY, ELEMENTS, LINEAR, Stopwatch


def test_parts_accumulate_and_rest_is_the_remainder():
    watch = Stopwatch()
    for _ in range(3):
        with watch.part(ELEMENTS):
            time.sleep(0.002)
    summary = watch.summary()
    assert summary[ELEMENTS] >= 0.006
    assert summary[ASSEMBLY] == summary[LINEAR] == 0.0
    total = summary[ELEMENTS] + summary["rest"]
    assert abs(total - summary["total"]) <= 1e-9 * summary["total"] + 1e-12


def test_a_solve_reports_every_part():
    mesh = wrinkle.rectangle(1.0, 1.0, 8, 8)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["bottom"])
    model.prescribe(mesh.node_sets["top"], (0.05, 0.1, 0.0))
    results = model.solve(steps=2)
    timings = results.timings
    for part in (ELEMENTS, ASSEMBLY, LINEAR):
        assert timings[part] > 0.0, part
    parts = timings[ELEMENTS] + timings[ASSEMBLY] + timings[LINEAR] + timings["rest"]
    assert abs(parts - timings["total"]) <= 1e-9 * timings["total"]


def test_an_inner_part_counts_only_for_itself():
    watch = Stopwatch()
    with watch.part(ELEMENTS):
        time.sleep(0.01)
        with watch.part(ASSEMBLY):
            time.sleep(0.03)
    summary = watch.summary()
    assert summary[ASSEMBLY] >= 0.03
    assert 0.01 <= summary[ELEMENTS] < 0.03
