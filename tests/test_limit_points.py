"""No state past a limit point of the load is an answer (issue 20, item 1): the neo-Hookean
balloon above its largest pressure, whose closed form is Adkins & Rivlin's p(lambda) (see
verification/references/sphere.py), under load control ends with ConvergenceError and the
message "limit point passed near load factor ...", never with a crushed, collapsed or unstable
state reported as converged."""

import json
from pathlib import Path

import numpy as np
import pytest

from verification.references.sphere import InflatedSphere, effective_radius
from wrinkle.case import read_case
from wrinkle.cli import main
from wrinkle.solvers import ConvergenceError
from wrinkle.solvers.stepping import LIMIT_SLOPE, PathSlope

ROOT = Path(__file__).resolve().parents[1]
SPHERE = ROOT / "verification" / "cases" / "sphere.toml"
REFERENCE = InflatedSphere(radius=0.1, thickness=1e-3, mu=4e5)  # the case's R, T, mu


def balloon(pressure: float, steps: int, n: int = 4):
    return read_case(
        SPHERE,
        {
            "mesh": {"sphere": {"radius": 0.1, "n": n}},
            "load": [{"kind": "pressure", "value": float(pressure)}],
            "solver": {"steps": steps},
        },
    )


def mesh_limit_pressure(case) -> float:
    """The faceted octant's largest pressure: (R / R_eff) p_max (the reference's docstring)."""
    return REFERENCE.limit_pressure * 0.1 / effective_radius(case.model.mesh)


def test_a_crushed_or_collapsed_state_is_inadmissible():
    """The octant crushed to its centre (area ratio 1e-12) and flattened onto z = 0 (volume
    ratio 1e-8, its elements not collapsed) are refused; the reference state is not."""
    case = balloon(1000.0, 1)
    system = case.model.discretise()
    X = case.model.mesh.nodes
    assert system.inadmissible(system.element_coordinates(np.zeros(X.size))) is None
    crushed = system.element_coordinates((X * 1e-6 - X).ravel())
    assert "collapsed" in system.inadmissible(crushed)
    flat = X * [1.0, 1.0, 1e-8]
    message = system.inadmissible(system.element_coordinates((flat - X).ravel()))
    assert message is not None and "volume" in message


def test_a_state_stretched_beyond_any_membrane_shows_divergence():
    """An iterate with an element stretched to more than MAX_AREA_RATIO (1e6) times its
    reference area shows a diverging solve: the octant scaled 1,001 times (area ratio
    1.002e6) does, 999 times (0.998e6) and the reference state do not. The shortcut for small
    motions (``_free_motion``) is a bound, checked against the areas themselves on motions
    from well below to well above it."""
    from wrinkle.system import MAX_AREA_RATIO

    case = balloon(1000.0, 1)
    system = case.model.discretise()
    X = case.model.mesh.nodes
    assert system.diverging(np.zeros(X.size)) is None
    assert system.diverging((X * 998.0).ravel()) is None
    message = system.diverging((X * 1000.0).ravel())
    assert message is not None and "times its reference area" in message
    bound = system._free_motion
    assert 0.0 < bound < 1000.0 * np.abs(X).max()
    rng = np.random.default_rng(3)
    for scale in (0.5, 1.0, 2.0, 20.0):
        u = rng.uniform(-1.0, 1.0, X.size) * scale * bound
        x = system.element_coordinates(u)
        edges = x[:, :2] - x[:, 2:3]
        ratio = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1) / (
            2.0 * system.geometry.area
        )
        assert (system.diverging(u) is not None) == bool(ratio.max() > MAX_AREA_RATIO)
        if np.abs(u).max() <= bound:
            assert ratio.max() <= MAX_AREA_RATIO


def test_a_solve_above_the_limit_stops_as_soon_as_it_diverges():
    """1.3 times the limit pressure on the 64-element octant in one step, no cut-back: the
    balloon inflates without bound, and the solve stops at the first iterate with an element
    stretched beyond any membrane (14 iterations) instead of spending the 400 iterations of
    the end of the path from the reference state (0.8 s before, 6 December 2026); the
    message does not give the hint for a small pressure on a flat sheet."""
    case = read_case(
        SPHERE,
        {
            "mesh": {"sphere": {"radius": 0.1, "n": 8}},
            "load": [{"kind": "pressure", "value": 1.3 * REFERENCE.limit_pressure}],
            "solver": {"steps": 1, "min_step": 1.0},
        },
    )
    with pytest.raises(ConvergenceError, match="the solve diverges: element") as caught:
        case.solve()
    assert len(caught.value.history) < 100
    assert "harder the smaller" not in str(caught.value)  # no small pressure's hint


@pytest.mark.parametrize("steps", [1, 10])
def test_the_balloon_above_its_limit_ends_at_the_limit_with_the_message(steps):
    """5,500 Pa on the 64-element octant (limit 5,009 Pa from the closed form on its
    facets): the path ends with ConvergenceError whose limit point is within 0.5 % of the
    closed form's load factor, never with the crushed sphere."""
    case = balloon(5500.0, steps, n=8)
    with pytest.raises(ConvergenceError, match="limit point passed near load factor") as caught:
        case.solve()
    error = caught.value
    expected = mesh_limit_pressure(case) / 5500.0
    assert error.limit_point == pytest.approx(expected, rel=5e-3)
    assert error.limit_point <= expected * (1 + 1e-3)  # never past it
    assert "pressure 50" in str(error)


def test_a_pressure_sweep_never_ends_in_a_wrong_answer():
    """Issue 20's sweep, thinned to 6 pressures from 0.95 to 1.5 p_max (the full 20 are
    benchmarks/limit_point_sweep.py), in 1 and 20 steps, on the 16-element octant. Each
    either converges on the rising branch, with the stretch of the closed form on the facets
    to 1 %, or fails with the limit-point message at the limit."""
    outcomes = set()
    for steps in (1, 20):
        for pressure in np.linspace(0.95, 1.5, 6) * REFERENCE.limit_pressure:
            case = balloon(pressure, steps)
            limit = mesh_limit_pressure(case)
            try:
                results = case.solve()
            except ConvergenceError as error:
                assert "limit point passed" in str(error)
                assert error.limit_point * pressure == pytest.approx(limit, rel=1e-2)
                outcomes.add("limit")
                continue
            assert pressure <= limit * (1 + 1e-9)
            x = case.model.mesh.nodes + results.final.displacement.reshape(-1, 3)
            stretch = np.linalg.norm(x, axis=1).mean() / 0.1
            faceted = pressure * effective_radius(case.model.mesh) / 0.1
            assert stretch == pytest.approx(REFERENCE.stretch(faceted), rel=1e-2)
            outcomes.add("converged")
    assert outcomes == {"limit", "converged"}


def test_the_command_line_exits_1_with_one_line_and_the_steps_on_disk(tmp_path, capsys):
    case_file = tmp_path / "balloon.toml"
    text = SPHERE.read_text().replace("value = 4878.915624412286", "value = 5500.0")
    case_file.write_text(text.replace("n = 32", "n = 8"))
    status = main(["run", str(case_file), "--out", str(tmp_path / "out"), "-q"])
    assert status == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert "limit point passed near load factor" in lines[0]  # then where the steps are
    assert len(lines) == 2 and "converged steps" in lines[1]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["converged"] is False and len(summary["steps"]) >= 9
    assert all(step["max_displacement"] < 0.1 for step in summary["steps"])  # none crushed


def test_the_slope_falls_to_zero_at_a_limit_and_a_jump_is_caught():
    """A path lambda(s) = 2 s - s^2 (limit at s = 1) sampled at s_k: the relative slope
    dlambda / ds = 2 - 2 s ... falls below LIMIT_SLOPE near s = 1; a step that moves 100
    times further for the same load is a jump."""
    u0 = np.zeros(3)
    slope = PathSlope(u0)
    for s in (0.1, 0.3, 0.5, 0.7, 0.9, 0.97, 0.99):
        slope.record(2 * s - s * s, np.array([s, 0.0, 0.0]))
    assert slope.relative[-1] < LIMIT_SLOPE and slope.limit_point() is not None
    steady = PathSlope(u0)
    for k in range(1, 5):
        steady.record(0.1 * k, np.array([0.1 * k, 0.0, 0.0]))
    assert steady.limit_point() is None
    assert steady.jump(0.5, np.array([10.0, 0.0, 0.0])) is not None
    assert steady.jump(0.5, np.array([0.5, 0.0, 0.0])) is None


def test_an_unstable_state_found_in_one_step_is_not_an_answer():
    """7,293.26 Pa (1.471 p_max) in one step on the 64-element octant: Newton balanced it at
    twelve times the radius, a polyhedral state whose tangent has eigenvalues down to -0.06
    of its mean diagonal (measured), and reported it as converged before the stability test
    (``wrinkle.solvers.stability``). Now the path is cut back and ends at the limit."""
    case = balloon(7293.260657274794, 1, n=8)
    assert case.model.discretise().encloses_volume
    with pytest.raises(ConvergenceError, match="limit point passed") as caught:
        case.solve()
    assert caught.value.limit_point * 7293.260657274794 == pytest.approx(
        mesh_limit_pressure(case), rel=5e-3
    )


def test_a_flat_sheet_inflated_is_not_checked_for_stability():
    """The airbag starts flat: it encloses no volume, has no limit point under pressure, and
    costs no factorisation for the check (its wrinkled equilibria have eigenvalues of
    -1e-5 of the mean diagonal, the near-zero modes of the folds)."""
    airbag = read_case(ROOT / "examples" / "airbag.toml", {"mesh": {"rectangle": {"nx": 8}}})
    assert not airbag.model.discretise().encloses_volume
