"""The paper's test problem (Roddeman et al. 1987, Part II, Figs. 6-7; docs/method.md section 8),
``examples/paper_test.py``: finite-element edge forces against the homogeneous solution
computed independently by verification.references (relaxed-energy minimisation at one material
point)."""

import csv
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "examples" / "paper_test.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("paper_test_example", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


paper_test = _load_example()
STRETCHES, shear_stretch, main = paper_test.STRETCHES, paper_test.shear_stretch, paper_test.main


@pytest.fixture(scope="module")
def rows():
    return shear_stretch()


def test_edge_forces_equal_the_homogeneous_solution(rows):
    assert len(rows) == 3 * 21
    for r in rows:
        assert r.F1 == pytest.approx(r.F1_analytic, rel=1e-8), (r.f, r.v)
        assert r.F2 == pytest.approx(r.F2_analytic, rel=1e-8), (r.f, r.v)
        assert r.state == r.state_analytic
        assert r.interior_error < 1e-10  # the free nodes reach the homogeneous positions


def test_states_change_from_wrinkled_to_taut(rows):
    """Sheared alone, the square wrinkles; stretching makes it taut (the paper's Figs. 6-7)."""
    for f in (1.0, 2.0, 5.0):
        states = [r.state for r in rows if r.f == f]
        assert states[0] == "wrinkled" and states[-1] == "taut"
        change = states.index("taut")
        assert all(s == "wrinkled" for s in states[:change])
        assert all(s == "taut" for s in states[change:])


def test_anisotropy_matters(rows):
    """At v = 0 a stiffer fibre along the shear raises F1 and lowers F2 (the wrinkle
    direction is not the principal strain direction for f > 1)."""
    first = {r.f: r for r in rows if r.v == 0.0}
    assert first[1.0].F1 < first[2.0].F1 < first[5.0].F1
    assert first[1.0].F2 > first[2.0].F2 > first[5.0].F2


def test_restricted_step_reproduces_the_test():
    for r in shear_stretch(anisotropy=(5.0,), stretches=STRETCHES[::4], method="restricted-step"):
        assert r.F1 == pytest.approx(r.F1_analytic, rel=1e-8)
        assert r.F2 == pytest.approx(r.F2_analytic, rel=1e-8)


def test_paper_test_writes_csv_and_picture(tmp_path, capsys):
    assert main(["--out", str(tmp_path)]) == 0
    with open(tmp_path / "shear_stretch.csv") as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == 63
    assert {"f", "v", "F1", "F2", "state", "iterations"} <= set(table[0])
    errors = np.array([float(row["relative_error"]) for row in table])
    assert errors.max() < 1e-8
    png = (tmp_path / "shear_stretch.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 20_000
    assert "largest relative difference" in capsys.readouterr().out


def test_paper_test_runs_as_a_script_from_anywhere(tmp_path):
    """``python examples/paper_test.py`` finds the checkout's verification package itself."""
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--help"],
        cwd=tmp_path,
        env=environment,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert "--method" in done.stdout
