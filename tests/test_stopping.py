"""The accuracy stop (wrinkle.solvers.stopping, [solver] convergence = "accuracy"): its estimates
against closed forms, the steps that never count, and on the nested hard cases a stop whose
answer is within its own bound of the answer converged to a tight residual."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from wrinkle.case import CaseError, read_case
from wrinkle.solvers import SolverSettings
from wrinkle.solvers.base import AcceptedStep, Evaluation
from wrinkle.solvers.stopping import AccuracyStop

ROOT = Path(__file__).resolve().parents[1]
AIRBAG = ROOT / "examples" / "airbag.toml"
RECTANGLE = ROOT / "benchmarks" / "hard_cases" / "sheared_rectangle.toml"


def evaluation(residual: float = 1e-6) -> Evaluation:
    return Evaluation(np.array([residual]), 0.0, 1.0, (1, 0, 0))


def fixed_quantities(values: list[float]):
    """Quantities that take the next of ``values`` at each call (scale 1)."""
    sequence = iter(values)

    def quantities(u, ev):
        return ["q"], np.array([next(sequence)]), np.array([1.0])

    return quantities


def steps(energies, full=True, rho=1.0):
    """AcceptedSteps with these energies (the first is the start)."""
    out = []
    for k, energy in enumerate(energies):
        good_full = full[k] if isinstance(full, list) else full
        out.append(
            AcceptedStep(
                energy,
                math.nan if k == 0 else 1.0,
                math.nan if k == 0 else rho,
                k > 0 and good_full,
                1e-14,
                np.zeros(3),
                evaluation(),
            )
        )
    return out


def geometric(limit: float, first_gap: float, q: float, n: int) -> list[float]:
    """Energies limit + first_gap q^k, k = 0 .. n-1: a sequence contracting by q."""
    return [limit + first_gap * q**k for k in range(n)]


def test_the_energy_gap_of_a_geometric_sequence_is_its_exact_remainder():
    """For energies E_k = E* + g q^k the estimate a_k q / (1 - q) is the sum of the rest of
    the series, E_k - E*, exactly."""
    limit, gap0, q = -10.0, 1.0, 0.3
    energies = geometric(limit, gap0, q, 6)
    stop = AccuracyStop(limit + 100.0, fixed_quantities([0.0] * 6), energy=1.0, change=1.0)
    reports = [stop(step) for step in steps(energies)]
    report = reports[-1]
    assert report is not None and report["rule"] == "accuracy"
    assert report["contraction"] == pytest.approx(q, rel=1e-9)
    assert report["energy_gap"] == pytest.approx(energies[-1] - limit, rel=1e-9)
    assert report["discretisation_error"] == pytest.approx((limit + 100.0 - energies[-1]) / 3)


def test_it_stops_only_when_the_gap_is_below_the_fraction_of_the_discretisation_error():
    """E_k - E* = 0.5^k; coarse energy E* + 3, so D is about 1: with eta = 0.01 the stop
    comes at the first k (after the window) with 0.5^k <= 0.01 (1 + ...), i.e. k = 7."""
    limit = 0.0
    energies = geometric(limit, 1.0, 0.5, 12)
    stop = AccuracyStop(limit + 3.0, fixed_quantities([0.0] * 12), energy=0.01, change=1.0)
    first = next(k for k, step in enumerate(steps(energies)) if stop(step) is not None)
    gaps = [e - limit for e in energies]
    discretisation = [(3.0 - e) / 3.0 for e in energies]
    expected = next(k for k in range(3, 12) if gaps[k] <= 0.01 * discretisation[k])
    assert first == expected == 7


@pytest.mark.parametrize(
    "full, rho",
    [
        ([True, True, True, False, True, True, True, True], 1.0),  # one shortened step
        (True, 0.6),  # every step's model only roughly right
    ],
)
def test_damped_and_shortened_steps_never_count(full, rho):
    """A window holding a step that was shortened (backtracked) or whose gain ratio was
    below 0.75 cannot stop, however small the gap: the 8 energies contract by 0.1."""
    energies = geometric(0.0, 1.0, 0.1, 8)
    stop = AccuracyStop(1e3, fixed_quantities([0.0] * 8), energy=1.0, change=1.0)
    results = [stop(step) for step in steps(energies, full=full, rho=rho)]
    if rho < 0.75:
        assert all(r is None for r in results)
    else:  # the shortened step (index 3) blocks the windows that hold it: steps 3 .. 5
        assert [r is None for r in results[3:6]] == [True, True, True]
        assert results[6] is not None


def test_a_creep_that_does_not_contract_never_stops():
    """Equal decreases (q = 1: a fold tip moving at a steady pace) give no finite gap."""
    energies = [-float(k) * 1e-9 for k in range(10)]
    stop = AccuracyStop(1.0, fixed_quantities([0.0] * 10), energy=1.0, change=1.0)
    assert all(stop(step) is None for step in steps(energies))


def test_a_quantity_still_moving_blocks_the_stop():
    """The energy has converged, but a probe moved 1e-3 (scale 1) in the last step: with
    q = 0.1 its remaining change is 1e-3 sqrt(q) / (1 - sqrt(q)) = 4.6e-4 > change 1e-4."""
    energies = geometric(0.0, 1.0, 0.1, 6)
    values = [0.0, 0.0, 0.0, 0.0, 0.0, 1e-3]
    stop = AccuracyStop(1e3, fixed_quantities(values), energy=1.0, change=1e-4)
    assert [stop(step) for step in steps(energies)][-1] is None
    stop = AccuracyStop(1e3, fixed_quantities(values), energy=1.0, change=5e-4)
    assert [stop(step) for step in steps(energies)][-1] is not None


def test_a_window_below_two_is_refused():
    with pytest.raises(ValueError, match="window"):
        AccuracyStop(0.0, fixed_quantities([]), window=1)


def test_the_accuracy_stop_needs_a_coarser_mesh():
    with pytest.raises(ValueError, match="nested"):
        SolverSettings(convergence="accuracy", nested=False)
    with pytest.raises(ValueError, match="convergence"):
        SolverSettings(convergence="energy", nested=True)
    with pytest.raises(ValueError, match="accuracy_change"):
        SolverSettings(convergence="accuracy", nested=True, accuracy_change=0.5)


def test_a_case_with_an_unknown_stop_names_the_key(tmp_path):
    with pytest.raises(CaseError, match=r"\[solver\].*unknown convergence 'energy'"):
        read_case(AIRBAG, {"solver": {"convergence": "energy"}})
    with pytest.raises(CaseError, match=r"\[solver\].*nested"):
        read_case(AIRBAG, {"solver": {"convergence": "accuracy"}})


def airbag(stop: str, bending: bool, tolerance: float = 1e-8):
    return read_case(
        AIRBAG,
        {
            "mesh": {"rectangle": {"nx": 16, "ny": 16}, "refine": 1},
            "material": {"bending": bending},
            "solver": {
                "nested": True,
                "convergence": stop,
                "tolerance": tolerance,
                "max_iterations": 300,
            },
        },
    )


def centre(case, results) -> float:
    return float(results.final.displacement.reshape(-1, 3)[case.probes["centre"], 2].mean())


@pytest.mark.parametrize("bending", [True, False])
def test_the_nested_airbag_never_stops_before_its_answer_is_within_the_bound(bending):
    """The airbag on 512 -> 2,048 elements, with its bending stiffness (quadratic Newton
    convergence) and as a pure membrane (the fold creep): the centre deflection where the
    accuracy stop ends (or the residual test, if first) is within accuracy_change (1e-4) of
    the largest displacement from the same solve converged to a residual of 1e-10, and the
    reactions within 1e-4 of their scale."""
    accurate = airbag("accuracy", bending)
    exact = airbag("residual", bending, tolerance=1e-10)
    stopped, reference = accurate.solve(), exact.solve()
    final, ref = stopped.final, reference.final
    assert final.stopped_by == "accuracy" and final.iterations < ref.iterations
    largest = np.linalg.norm(ref.displacement.reshape(-1, 3), axis=1).max()
    assert abs(centre(accurate, stopped) - centre(exact, reference)) <= 1e-4 * largest
    forces = accurate.model.support_reactions(final.reactions)
    for label, force in exact.model.support_reactions(ref.reactions).items():
        scale = max(np.linalg.norm(force), 1.0)
        assert np.abs(np.subtract(forces[label], force)).max() <= 1e-4 * scale


def test_the_sheared_rectangle_never_stops_before_its_reaction_is_within_the_bound():
    """The sheared rectangle with free sides, 40 x 20 refined once (3,200 elements), with a
    tolerance of 1e-8: the top edge's reaction where the solve ends is within 1e-4 of the
    one converged to 1e-9. (The accuracy stop does not end this solve: the nodes of the
    slack corners are still moving when the residual test is met.)"""

    def case(stop, tolerance):
        return read_case(
            RECTANGLE,
            {
                "mesh": {"rectangle": {"nx": 40, "ny": 20}, "refine": 1},
                "solver": {
                    "nested": True,
                    "convergence": stop,
                    "tolerance": tolerance,
                    "max_iterations": 300,
                },
            },
        )

    accurate, exact = case("accuracy", 1e-8), case("residual", 1e-9)
    stopped, reference = accurate.solve(), exact.solve()
    top = accurate.model.support_reactions(stopped.final.reactions)["top"]
    top_ref = exact.model.support_reactions(reference.final.reactions)["top"]
    assert np.abs(np.subtract(top, top_ref)).max() <= 1e-4 * np.linalg.norm(top_ref)


def test_the_summary_says_which_test_ended_each_step(tmp_path):
    """summary.json names the rule of each step and, for the accuracy stop, its numbers."""
    accurate = airbag("accuracy", True)
    accurate.run(tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    step = summary["steps"][-1]
    assert step["stopped_by"] in ("residual", "accuracy")
    if step["stopped_by"] == "accuracy":
        report = step["accuracy_stop"]
        assert report["energy_gap"] <= 0.1 * report["discretisation_error"]
        assert report["residual"] <= 1e-2
        assert set(report["remaining_change"]) >= {"centre_uz", "seam_Fz"}
