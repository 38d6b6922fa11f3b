"""Inputs that gave a wrong answer reported as converged, or a traceback, now refused with one
line (issue 19): each test here fails on the code before the fix. The references are closed
forms (the neo-Hookean sheet's uniaxial tension) or the input itself."""

import math
from pathlib import Path

import numpy as np
import pytest

import wrinkle
from wrinkle.case import CaseError, read_case
from wrinkle.cli import main
from wrinkle.materials import NeoHookean, StVenantKirchhoff
from wrinkle.solvers import SolverSettings
from wrinkle.solvers.base import Evaluation, is_converged

AIRBAG = (Path(__file__).resolve().parents[1] / "examples" / "airbag.toml").read_text()


def airbag(tmp_path, old, new):
    """examples/airbag.toml with the texts ``old`` replaced by ``new`` ("|" separates
    several)."""
    text = AIRBAG
    for before, after in zip(old.split("|"), new.split("|"), strict=True):
        assert before in text
        text = text.replace(before, after)
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


def run(path, capsys, tmp_path):
    status = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize(
    "old, new, fragment",
    [
        # 1e300 Pa: forces whose norm overflows; "converged" in 0 iterations before
        ("value = 5000.0", "value = 1e300", "the loads are too large"),
        # a millipascal on a sheet of E = 1e12: below the round-off of its forces; "converged"
        # in 0 iterations with zero displacement before
        (
            "E = 588e6|value = 5000.0",
            "E = 1e12|value = 1e-3",
            "the loads are too small for the sheet's stiffness",
        ),
        ("tolerance = 1e-8", "tolerance = 10.0", "solver tolerance must be a number in (0, 0.01]"),
        ("tolerance = 1e-8", "min_step = 5.0", "solver min_step must be a number in (0, 1]"),
        ("E = 588e6", "E = 1e-300", "material 1: its stiffness"),
    ],
    ids=["pressure 1e300", "millipascal on E 1e12", "tolerance 10", "min_step 5", "E 1e-300"],
)
def test_out_of_range_scales_exit_2_with_one_line(tmp_path, capsys, old, new, fragment):
    path = airbag(tmp_path, old, new)
    status, out, err = run(path, capsys, tmp_path)
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and fragment in err and str(path) in err, err


def test_an_infinite_traction_is_refused(tmp_path):
    path = airbag(
        tmp_path,
        '[[load]]\nkind = "pressure"\nvalue = 5000.0',
        '[[load]]\nkind = "edge"\nnodes = "x == 0.42426406871192845"\ntraction = [inf, 0.0, 0.0]',
    )
    with pytest.raises(CaseError, match=r"\[\[load\]\] 1.*'traction' must be finite"):
        read_case(path)


def test_the_convergence_test_can_fail_on_infinite_forces():
    """|r| <= tol * scale is true for an infinite scale; the test is now false there."""
    infinite = Evaluation(np.ones(3), 0.0, math.inf, (1, 0, 0), round_off=0.0)
    assert not is_converged(infinite, 1e-6)
    with np.errstate(over="ignore"):  # finite forces whose norm overflows
        overflowed = Evaluation(np.full(3, 1e300), 0.0, 1.0, (1, 0, 0), round_off=0.0)
        assert overflowed.residual_norm == math.inf
        assert not is_converged(overflowed, 1e-6)


def test_settings_refuse_a_tolerance_every_start_passes():
    with pytest.raises(ValueError, match="solver tolerance must be"):
        SolverSettings(tolerance=1.0)
    assert SolverSettings(tolerance=1e-2).tolerance == 1e-2  # Abaqus' 0.5 % is allowed


@pytest.mark.parametrize("stretch, across", [(1.1, 0.01), (1.3, 1e-3), (1.1, 0.5)])
def test_neo_hookean_wrinkled_under_strong_cross_compression_is_uniaxial(stretch, across):
    """An incompressible neo-Hookean sheet stretched by lambda and crushed across: wrinkled,
    uniaxial N11 = mu t (1 - lambda^-3) (the natural width lambda^-1/2), N22 = 0. At
    F = diag(1.1, 0.01) the solve stopped with N22 = -0.0015 before (tolerance relative to
    the crushed plain law)."""
    r = wrinkle.material_response(NeoHookean(mu=1.0, thickness=1.0), np.diag([stretch, across]))
    assert r.state == "wrinkled"
    np.testing.assert_allclose(r.stress, np.diag([1.0 - stretch**-3, 0.0]), atol=1e-12)
    assert r.principal_stress.min() >= -1e-12


def test_a_crushed_state_with_no_admissible_solution_is_a_value_error():
    """F = diag(1.01, 1e-4) gave principal stresses of -1e9 as "wrinkled"; now it says it
    cannot solve it (a trial iterate there is rejected by the solver)."""
    with pytest.raises(ValueError, match="no admissible solution"):
        wrinkle.material_response(NeoHookean(mu=1.0, thickness=1.0), np.diag([1.01, 1e-4]))


def test_a_rank_deficient_F_is_singular():
    """F = [[1, 1], [1, 1 + 1e-15]]: det C is 1e-30 > 0 by round-off; it returned taut with
    principal stresses [nan, inf]."""
    material = StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0)
    with pytest.raises(ValueError, match="F is singular"):
        wrinkle.material_response(material, [[1.0, 1.0], [1.0, 1.0 + 1e-15]])


def test_an_inverted_element_is_refused():
    """One clockwise triangle in a counter-clockwise mesh was accepted and, under pressure,
    pushed the other way."""
    mesh = wrinkle.rectangle(1.0, 1.0, 2, 2)
    triangles = mesh.triangles.copy()
    triangles[3] = triangles[3][[0, 2, 1]]
    with pytest.raises(ValueError, match=r"elements \[3, \d+\] are oriented oppositely"):
        wrinkle.Mesh(mesh.nodes, triangles)
