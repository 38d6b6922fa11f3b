"""Mesh sequencing (wrinkle.sequencing, [solver] nested): the finest mesh started from the
coarser meshes' solution reaches the same equilibrium as from the flat sheet, to the
convergence test, in fewer iterations; bad requests are refused."""

from pathlib import Path

import numpy as np
import pytest

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.case import CaseError, read_case
from wrinkle.refinement import refine
from wrinkle.sequencing import NestedStart
from wrinkle.solvers import SolverSettings

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"


def airbag(nested: bool, nx: int = 16, levels: int = 2):
    return read_case(
        AIRBAG,
        {
            "mesh": {"rectangle": {"nx": nx, "ny": nx}, "refine": levels},
            "material": {"bending": True},
            "solver": {"nested": nested},
        },
    )


@pytest.mark.slow
def test_nested_airbag_reaches_the_same_equilibrium_in_fewer_iterations():
    """The bending airbag on 512 -> 2,048 -> 8,192 elements: the fine mesh from the coarse
    solution ends where it ends from the flat sheet (same tolerance, 1e-8 of the force
    scale) and takes fewer iterations (measured: 11 against 25)."""
    flat, nested = airbag(False), airbag(True)
    assert [m.mesh.n_elements for m in nested.coarse] == [512, 2048]
    assert flat.coarse == []
    from_flat, from_coarse = flat.solve().final, nested.solve().final
    assert from_coarse.iterations < from_flat.iterations
    centre = nested.probes["centre"]
    w_flat = from_flat.displacement.reshape(-1, 3)[centre, 2].mean()
    w_nested = from_coarse.displacement.reshape(-1, 3)[centre, 2].mean()
    assert w_nested == pytest.approx(w_flat, abs=1e-7)  # of 0.216 m


def test_start_is_the_coarse_solution_interpolated():
    """A sheet stretched by a prescribed edge displacement: the coarse solution, linear in
    the coordinates, interpolates exactly, so the fine mesh starts in balance."""
    material = StVenantKirchhoff.isotropic(E=100.0, nu=0.3, thickness=0.1)

    def stretched(mesh):
        model = Model(mesh, material)
        model.fix("x == 0", "x")
        model.fix("y == 0", "y")
        model.fix("z == 0", "z")
        model.prescribe("x == 1", (0.1, np.nan, np.nan))
        return model

    coarse_mesh = rectangle(1.0, 1.0, 2, 2)
    fine = stretched(refine(coarse_mesh).mesh)
    start = NestedStart([stretched(coarse_mesh)], fine, SolverSettings(tolerance=1e-10))
    guess = start(1.0)
    evaluation = fine.discretise().evaluate(guess)
    assert evaluation.residual_norm <= 1e-9 * evaluation.force_scale
    results = fine.solve(SolverSettings(tolerance=1e-10, nested=True), coarse=start.coarse)
    assert results.final.iterations == 0


def test_a_coarse_level_that_fails_is_not_used():
    case = airbag(True, nx=8, levels=1)
    start = NestedStart(case.coarse, case.model, case.settings.replace(max_iterations=1))
    assert start(1.0) is None


def test_bad_requests_are_refused():
    with pytest.raises(CaseError, match=r"\[solver\].*nested.*refine >= 1"):
        read_case(AIRBAG, {"solver": {"nested": True}})
    with pytest.raises(CaseError, match=r"\[solver\].*'nested' must be true or false"):
        read_case(AIRBAG, {"solver": {"nested": "yes"}})
    case = airbag(True, nx=8, levels=1)
    with pytest.raises(ValueError, match="nested needs the models of the coarser meshes"):
        case.model.solve(case.settings)
    other = read_case(AIRBAG, {"mesh": {"rectangle": {"nx": 9, "ny": 9}}})
    with pytest.raises(ValueError, match="is not the mesh of level 0 refined once"):
        NestedStart([other.model], case.model, case.settings)
    with pytest.raises(ValueError, match="at least one coarser model"):
        NestedStart([], case.model, case.settings)
