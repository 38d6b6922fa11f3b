"""Mesh sequencing (wrinkle.sequencing, [solver] nested): the finest mesh started from the
coarser meshes' solution reaches the same equilibrium as from the flat sheet, to the
convergence test, in fewer iterations, through meshes refined uniformly or through a list of
independent meshes ([mesh] levels, wrinkle.transfer); bad requests are refused."""

from pathlib import Path

import numpy as np
import pytest

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.case import CaseError, read_case
from wrinkle.mesh import Mesh, boundary_nodes
from wrinkle.refinement import Refinement, refine
from wrinkle.sequencing import NestedStart
from wrinkle.solvers import SolverSettings
from wrinkle.transfer import PointTransfer

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"


def airbag(nested: bool | None, nx: int = 16, levels: int = 2):
    """The bending airbag refined ``levels`` times, [solver] nested = ``nested`` (None: the
    default, "auto")."""
    return read_case(
        AIRBAG,
        {
            "mesh": {"rectangle": {"nx": nx, "ny": nx}, "refine": levels},
            "material": {"bending": True},
            "solver": {} if nested is None else {"nested": nested},
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
    with pytest.raises(CaseError, match=r"\[solver\].*'nested' must be true, false or"):
        read_case(AIRBAG, {"solver": {"nested": "yes"}})
    case = airbag(True, nx=8, levels=1)
    with pytest.raises(ValueError, match="nested needs the models of the coarser meshes"):
        case.model.solve(case.settings)
    finer = read_case(AIRBAG, {"mesh": {"rectangle": {"nx": 17, "ny": 17}}})
    with pytest.raises(ValueError, match=r"level 1 \(512 elements\) is not finer than level 0"):
        NestedStart([finer.model], case.model, case.settings)
    half = Model(rectangle(0.2, 0.43, 4, 8))  # half the airbag's quarter sheet
    with pytest.raises(ValueError, match="nested: the meshes do not cover the same surface: node"):
        NestedStart([half], case.model, case.settings)
    with pytest.raises(ValueError, match="at least one coarser model"):
        NestedStart([], case.model, case.settings)


def jittered(mesh: Mesh, seed: int) -> Mesh:
    """The mesh with its interior nodes moved at random by up to a fifth of a square: a mesh
    of the same sheet that shares no interior node with any other."""
    nodes = mesh.nodes.copy()
    inner = ~boundary_nodes(mesh)
    h = np.ptp(mesh.nodes[:, 0]) / np.sqrt(mesh.n_elements / 2)
    rng = np.random.default_rng(seed)
    nodes[inner, :2] += 0.2 * h * rng.uniform(-1.0, 1.0, (int(inner.sum()), 2))
    return Mesh(nodes, mesh.triangles)


def stretched_sheet(mesh: Mesh) -> Model:
    """The unit sheet pulled by 0.1 at x = 1, held at x = 0, y = 0, z = 0: a homogeneous
    stretch, linear in the coordinates."""
    model = Model(mesh, StVenantKirchhoff.isotropic(E=100.0, nu=0.3, thickness=0.1))
    model.fix("x == 0", "x")
    model.fix("y == 0", "y")
    model.fix("z == 0", "z")
    model.prescribe("x == 1", (0.1, np.nan, np.nan))
    return model


def test_a_linear_solution_passes_through_non_nested_levels_exactly():
    """Levels of 18 and 50 elements (structured, then jittered) and 128 elements refined once:
    the transfers are found by the meshes (point location, then the refinement), the
    homogeneous stretch of each level interpolates exactly, and the finest mesh starts in
    balance (0 iterations)."""
    meshes = [
        rectangle(1.0, 1.0, 3, 3),
        jittered(rectangle(1.0, 1.0, 5, 5, diagonal="left"), 1),
        jittered(rectangle(1.0, 1.0, 8, 8), 2),
    ]
    fine = stretched_sheet(refine(meshes[-1]).mesh)
    settings = SolverSettings(tolerance=1e-10, nested=True)
    start = NestedStart([stretched_sheet(mesh) for mesh in meshes], fine, settings)
    kinds = [type(transfer) for transfer in start.transfers]
    assert kinds == [PointTransfer, PointTransfer, Refinement]
    evaluation = fine.discretise().evaluate(start(1.0))
    assert evaluation.residual_norm <= 1e-9 * evaluation.force_scale
    assert fine.solve(settings, coarse=start.coarse).final.iterations == 0


def write_vtu(mesh: Mesh, path: Path) -> str:
    import meshio

    meshio.write_points_cells(str(path), mesh.nodes, [("triangle", mesh.triangles)])
    return path.name


def airbag_with_levels(tmp_path, counts):
    """Jittered n x n meshes of the quarter airbag's square written as .vtu files, one per
    n of counts, and a copy of the airbag case beside them: (file names, case path)."""
    side = 0.6 * np.sqrt(2.0) / 2.0
    files = [
        write_vtu(jittered(rectangle(side, side, n, n), n), tmp_path / f"level-{n}.vtu")
        for n in counts
    ]
    case = tmp_path / "airbag.toml"
    case.write_text(AIRBAG.read_text())
    return files, case


def test_airbag_through_levels_of_other_meshes_reaches_the_same_equilibrium(tmp_path):
    """The bending airbag on 512 elements, started from jittered meshes of 72 and 200
    elements ([mesh] levels, .vtu files beside the case): the same centre deflection as the
    solve from the flat sheet, to the convergence test (1e-8 of the force scale), in fewer
    iterations (measured: 11 against 21)."""
    files, case = airbag_with_levels(tmp_path, (6, 10))
    mesh = {"rectangle": {"nx": 16, "ny": 16}}
    flat = read_case(case, {"mesh": mesh, "material": {"bending": True}})
    nested = read_case(
        case,
        {
            "mesh": {**mesh, "levels": files},
            "material": {"bending": True},
            "solver": {"nested": True},
        },
    )
    assert [m.mesh.n_elements for m in nested.coarse] == [72, 200]
    from_flat, from_coarse = flat.solve().final, nested.solve().final
    assert from_coarse.iterations < from_flat.iterations
    centre = nested.probes["centre"]
    w_flat = from_flat.displacement.reshape(-1, 3)[centre, 2].mean()
    w_nested = from_coarse.displacement.reshape(-1, 3)[centre, 2].mean()
    assert w_flat == pytest.approx(0.216, abs=0.002)
    assert w_nested == pytest.approx(w_flat, abs=1e-7)


def test_levels_come_before_the_refined_meshes(tmp_path):
    """[mesh] levels with refine = 1: the coarse models are the levels' and then the base
    mesh's, coarsest first; the case's own is the base refined once."""
    files, case = airbag_with_levels(tmp_path, (2, 3))
    read = read_case(
        case,
        {
            "mesh": {"rectangle": {"nx": 4, "ny": 4}, "refine": 1, "levels": files},
            "solver": {"nested": True},
        },
    )
    assert [m.mesh.n_elements for m in read.coarse] == [8, 18, 32]
    assert read.model.mesh.n_elements == 128


@pytest.mark.parametrize(
    "bending, nested, expected",
    [(True, None, [32, 128]), (False, None, []), (True, False, []), (False, True, [32, 128])],
)
def test_nested_auto_nests_a_refined_sheet_with_bending(bending, nested, expected):
    """The default nested = "auto": a refined mesh is nested where the sheet has bending
    (the measured gain, docs/solvers.md), not for a pure membrane; true and false decide."""
    solver = {} if nested is None else {"nested": nested}
    case = read_case(
        AIRBAG,
        {
            "mesh": {"rectangle": {"nx": 4, "ny": 4}, "refine": 2},
            "material": {"bending": bending},
            "solver": solver,
        },
    )
    assert case.settings.nested == ("auto" if nested is None else nested)
    assert [model.mesh.n_elements for model in case.coarse] == expected


def test_nested_auto_is_the_same_solve_as_nested_true():
    """With bending and refine = 1 the default solves exactly as nested = true does."""
    auto, on = airbag(None, nx=8, levels=1), airbag(True, nx=8, levels=1)
    a, b = auto.solve().final, on.solve().final
    assert a.iterations == b.iterations
    np.testing.assert_allclose(a.displacement, b.displacement, rtol=0, atol=1e-12)
