"""The verification gallery's framework (checks, convergence orders, report,
``python -m verification``) and the quick run of every benchmark, which must pass."""

from __future__ import annotations

import ast
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import verification.__main__ as gallery
from verification.__main__ import main
from verification.report import Benchmark, Check, Convergence, Outcome, run_gallery
from wrinkle.case import read_case

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "verification" / "cases"


def test_check_relative_and_absolute_errors():
    check = Check("deflection (mm)", 217.0, "paper", 216.0, tolerance=5e-3)
    assert check.error == pytest.approx(1.0 / 217.0, rel=1e-14)
    assert check.passed
    assert not Check("deflection (mm)", 217.0, "paper", 215.0, tolerance=5e-3).passed
    angle = Check("angle (deg)", 45.0, "closed form", 45.3, tolerance=0.5, relative=False)
    assert angle.error == pytest.approx(0.3, rel=1e-12) and angle.passed
    assert not Check("x", 1.0, "s", math.nan, tolerance=1.0).passed
    assert not Check("x", 0.0, "s", 1e-30, tolerance=1.0).passed  # relative to zero: inf


def test_observed_order_of_a_manufactured_sequence():
    h = np.array([0.4, 0.2, 0.1, 0.05])
    assert Convergence("e", h, 3.0 * h**2, 2).observed_order == pytest.approx(2.0, abs=1e-12)
    assert Convergence("e", h, 0.5 * h**1.5, 2).observed_order == pytest.approx(1.5, abs=1e-12)
    assert math.isnan(Convergence("e", [0.1], [1e-3], 2).observed_order)


def _fake_benchmarks(tmp_path: Path):
    def passing(case: Path, out: Path, quick: bool) -> Outcome:
        assert case.name == "good.toml" and quick
        figure = out / "curve.png"
        figure.write_bytes(b"png")
        study = Convergence("deflection", [0.2, 0.1], [4e-3, 1e-3], 2)
        return Outcome(
            [Check("deflection (mm)", 217.0, "Contri | Schrefler", 216.9, 1e-3)],
            [figure],
            "Set-up and discussion.",
            [study],
        )

    def failing(case: Path, out: Path, quick: bool) -> Outcome:
        return Outcome([Check("torque", 1.0, "closed form", 1.1, 1e-2)])

    def crashing(case: Path, out: Path, quick: bool) -> Outcome:
        raise RuntimeError("the hub came off")

    for name in ("good", "bad", "crash"):
        (tmp_path / f"{name}.toml").write_text("")
    return [
        Benchmark("good", "A good one", passing),
        Benchmark("bad", "A bad one", failing),
        Benchmark("crash", "A crashing one", crashing),
    ]


def test_report_has_every_row_section_and_figure(tmp_path):
    fakes = _fake_benchmarks(tmp_path)
    entries = run_gallery(fakes, tmp_path, tmp_path / "out", quick=True)
    assert [e.passed for e in entries] == [True, False, False]
    assert "RuntimeError: the hub came off" in entries[2].error
    report = (tmp_path / "out" / "report.md").read_text()
    assert "1 of 3 benchmarks pass" in report
    assert "| A good one | deflection (mm) | 217 | Contri \\| Schrefler | 216.9 |" in report
    assert "| A bad one | torque | 1 | closed form | 1.1 | 1.00e-01 | 1.00e-02 | FAIL |" in report
    assert "FAIL: RuntimeError: the hub came off" in report
    assert "observed order 2.00 (expected 2)" in report
    assert "![curve](good/curve.png)" in report
    assert "## 3. A crashing one" in report
    assert "Regenerate with `python -m verification --out DIR --quick`." in report
    assert "Case file: `verification/cases/good.toml`" in report


def test_gallery_command_exit_status(tmp_path, monkeypatch, capsys):
    fakes = _fake_benchmarks(tmp_path)
    monkeypatch.setattr(gallery, "benchmarks", lambda: fakes)
    out = tmp_path / "out"
    common = ["--quick", "--cases", str(tmp_path), "--out", str(out)]
    assert main(common + ["--only", "good"]) == 0
    assert "good: pass, 1 checks" in capsys.readouterr().out
    assert main(common) == 1
    assert "bad: FAIL (torque)" in capsys.readouterr().out
    assert main(common + ["--only", "good", "--report", str(tmp_path / "docs" / "v.md")]) == 0
    assert "![curve](../out/good/curve.png)" in (tmp_path / "docs" / "v.md").read_text()
    capsys.readouterr()
    assert main(common + ["--only", "nonesuch"]) == 2
    assert "unknown benchmark 'nonesuch'" in capsys.readouterr().err
    (tmp_path / "bad.toml").unlink()
    assert main(common) == 2
    assert "bad.toml: case file of benchmark 'bad' not found" in capsys.readouterr().err


def test_case_overrides_and_verification_table(tmp_path):
    case = tmp_path / "strip.toml"
    case.write_text(
        "[mesh]\nrectangle = {width = 2.0, height = 1.0, nx = 2, ny = 1}\n"
        '[material]\nmodel = "svk"\nE = 1.0\nnu = 0.3\nthickness = 0.1\n'
        '[[support]]\nnodes = "x == 0"\nfix = ["x", "y", "z"]\n'
        '[[support]]\nnodes = "x == 2"\nfix = ["z"]\n'
        "[verification]\nmeshes = [2, 4]\n"
    )
    model = read_case(case, overrides={"mesh": {"rectangle": {"nx": 4, "ny": 2}}})
    assert model.model.mesh.n_elements == 16
    assert model.verification == {"meshes": [2, 4]}
    assert read_case(case).model.mesh.n_elements == 4


def test_every_benchmark_has_a_case_file():
    names = [b.name for b in gallery.benchmarks()]
    assert len(names) == len(set(names)) == 13
    for name in names:
        assert (CASES / f"{name}.toml").is_file(), name


@pytest.mark.slow
def test_quick_gallery_passes(tmp_path, capsys):
    """``python -m verification --quick`` on the committed case files: every benchmark
    passes."""
    out = tmp_path / "verify"
    status = main(["--quick", "--cases", str(CASES), "--out", str(out)])
    printed = capsys.readouterr().out
    assert status == 0, printed
    report = (out / "report.md").read_text()
    assert "13 of 13 benchmarks pass" in report
    for line in report.splitlines():
        assert "FAIL" not in line, line
    for link in report.split("](")[1:]:
        assert (out / link.split(")")[0]).is_file()


def test_gallery_runs_from_outside_the_checkout(tmp_path):
    """``python -m verification`` finds its case files next to itself, not in the working
    directory: run from a folder outside the checkout, with only the checkout importable."""
    environment = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    done = subprocess.run(
        [sys.executable, "-m", "verification", "--quick", "--only", "simple_shear", "--out", "out"],
        cwd=tmp_path,
        env=environment,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 of 1 benchmarks pass" in (tmp_path / "out" / "report.md").read_text()
    assert gallery.CASES == ROOT / "verification" / "cases"
    bad = subprocess.run(
        [sys.executable, "-m", "verification", "--only", "nonesuch"],
        cwd=tmp_path,
        env=environment,
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr


def test_the_installed_package_imports_nothing_of_the_gallery():
    """No module of src/wrinkle imports ``verification`` (at top level or in a function)."""
    import wrinkle

    for path in Path(wrinkle.__file__).parent.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = (
                [alias.name for alias in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            assert not any(n.split(".")[0] == "verification" for n in names), path
