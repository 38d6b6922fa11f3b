"""Paths steered by a scalar equation (issue 20, items 2-4): enclosed-volume control, arc
length, gas loads and a stop at a probe's displacement (``wrinkle.solvers.bordered``,
``control``, ``arc_length``, ``wrinkle.gas``).

References: the closed form of the neo-Hookean balloon p(lambda) = (2 mu T / R)(1/lambda -
1/lambda^7) (Adkins & Rivlin 1952; verification/references/sphere.py) on the faceted octant,
p_h = (R / R_eff) p at lambda = (V / V0)^(1/3) (the energy principle for a uniform inflation
of the facets); the gas law p V^gamma = const; finite differences of the enclosed volume and
of the gas's potential."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from verification.references.sphere import LIMIT_STRETCH, InflatedSphere, effective_radius
from wrinkle.case import read_case
from wrinkle.cli import main
from wrinkle.gas import Gas
from wrinkle.solvers import ConvergenceError, control
from wrinkle.solvers.settings import SolverSettings

ROOT = Path(__file__).resolve().parents[1]
SPHERE = ROOT / "verification" / "cases" / "sphere.toml"
AIRBAG = ROOT / "examples" / "airbag.toml"
REFERENCE = InflatedSphere(radius=0.1, thickness=1e-3, mu=4e5)  # the case's R, T, mu


def balloon(n: int = 8, load: dict | None = None, **solver):
    """The sphere case's octant with n divisions, its load replaced by ``load`` (default a
    pressure of 1 N/m², the unit of the unknown pressure) and [solver] keys added."""
    return read_case(
        SPHERE,
        {
            "mesh": {"sphere": {"radius": 0.1, "n": n}},
            "load": [load or {"kind": "pressure", "value": 1.0}],
            "probe": [{"name": "pole", "nodes": "x == 0 and y == 0"}],
            "solver": solver,
        },
    )


def stretch_and_error(case, results):
    """(lambda, relative pressure error against p_h) of every converged step."""
    volume0 = case.model.discretise().reference_volume
    ratio = 0.1 / effective_radius(case.model.mesh)
    stretch = np.array([(s.enclosed_volume / volume0) ** (1 / 3) for s in results.steps])
    pressure = np.array([s.pressure for s in results.steps])
    return stretch, pressure / (ratio * REFERENCE.pressure(stretch)) - 1.0


def test_volume_control_follows_the_balloon_through_its_limit_point():
    """From V0 to 27 V0 (stretch 3) in 26 steps on 64 elements: every point, rising and
    falling, within 3e-4 of p_h (measured 1.1e-4), the pressure's maximum among them next
    to lambda = 7^(1/6), every element taut."""
    case = balloon(control="volume", volume_ratio=27.0, steps=26)
    results = case.solve()
    stretch, error = stretch_and_error(case, results)
    assert results.final.load_factor == 1.0 and stretch[-1] == pytest.approx(3.0, rel=1e-9)
    assert np.max(np.abs(error)) < 3e-4
    top = int(np.argmax([s.pressure for s in results.steps]))
    assert 0 < top < len(stretch) - 1
    assert stretch[top - 1] < LIMIT_STRETCH < stretch[top + 1]
    assert all(s.states == (case.model.mesh.n_elements, 0, 0) for s in results.steps)
    assert max(s.iterations for s in results.steps[1:]) <= 4  # Newton's, quadratically


def test_arc_length_passes_the_limit_and_lands_on_the_stop():
    """Arc length with the stop at the pole's displacement 2 R: the load factor rises, then
    falls; every point above lambda = 1.1 within 3e-4 of p_h; the last exactly at the
    stop."""
    case = balloon(
        load={"kind": "pressure", "value": 5000.0},
        control="arc-length",
        steps=50,
        stop={"probe": "pole", "displacement": 0.2},
    )
    results = case.solve()
    stretch, error = stretch_and_error(case, results)
    factors = np.array([s.load_factor for s in results.steps])
    top = int(np.argmax(factors))
    assert 0 < top < factors.size - 1 and factors[-1] < factors[top]
    # at small strains the octant's slightly uneven stretch is a larger share of lambda - 1
    # (sphere benchmark: 6e-3 at lambda = 1.01 on n = 16): 4.4e-3 at lambda = 1.002 here
    assert np.max(np.abs(error[stretch > 1.1])) < 3e-4
    assert np.max(np.abs(error)) < 6e-3
    pole = results.final.displacement.reshape(-1, 3)[case.probes["pole"]].mean(axis=0)
    assert np.linalg.norm(pole) == pytest.approx(0.2, rel=1e-8)
    assert results.end.message.startswith("reached the stop")


def test_arc_length_below_the_limit_ends_on_load_controls_answer():
    """4,000 N/m² (below the maximum): arc length ends at load factor 1 where load control
    does, to the solver's tolerance."""
    load = {"kind": "pressure", "value": 4000.0}
    by_arc = balloon(load=load, control="arc-length", steps=4).solve()
    by_load = balloon(load=load, steps=4).solve()
    assert by_arc.final.load_factor == 1.0
    np.testing.assert_allclose(
        by_arc.final.displacement, by_load.final.displacement, atol=1e-8 * 0.1
    )


def test_arc_length_above_the_largest_load_says_what_the_largest_was():
    """5,500 N/m² exceeds the maximum, so no point of the path reaches load factor 1: the
    path fails naming the largest load it carried, the peak found between converged points,
    within 2e-4 of the facets' p_max (the faceted closed form's uniform inflation; measured
    1e-4)."""
    case = balloon(load={"kind": "pressure", "value": 5500.0}, control="arc-length", steps=5)
    with pytest.raises(ConvergenceError, match="load factor 1 not reached") as caught:
        case.solve()
    highest = float(str(caught.value).split("was ")[1].split(" ")[0])
    limit = REFERENCE.limit_pressure * 0.1 / effective_radius(case.model.mesh)
    assert highest * 5500.0 == pytest.approx(limit, rel=2e-4)


def test_arc_length_reaches_a_load_just_below_the_peak():
    """4,997 N/m², 0.25 % below the facets' maximum (5,009 N/m² on 64 elements): the path's
    converged points pass the peak without one above the load, the peak between them is
    found, and the path ends at load factor 1 on the rising branch, at the closed form's
    stretch (within the faceting, 6e-4)."""
    case = balloon(load={"kind": "pressure", "value": 4997.0}, control="arc-length", steps=20)
    results = case.solve()
    assert results.final.load_factor == 1.0
    volume0 = case.model.discretise().reference_volume
    stretch = (results.final.enclosed_volume / volume0) ** (1 / 3)
    ratio = 0.1 / effective_radius(case.model.mesh)
    assert stretch < LIMIT_STRETCH
    assert ratio * REFERENCE.pressure(stretch) == pytest.approx(4997.0, rel=5e-4)


def test_arc_length_on_the_wrinkled_airbag():
    """The quarter airbag (16 x 16 squares) by arc length from the flat sheet: the first step
    under load control, then wrinkled states with the follower pressure's stiffness, to load
    factor 1 within 1 mm of load control's centre deflection (its near-equal equilibria)."""
    mesh = {"rectangle": {"nx": 16, "ny": 16}}
    by_load = read_case(AIRBAG, {"mesh": mesh}).solve().final
    arc = read_case(AIRBAG, {"mesh": mesh, "solver": {"control": "arc-length", "steps": 4}})
    results = arc.solve()
    assert results.final.load_factor == 1.0 and len(results) > 2
    assert any(step.states[1] > 0 for step in results.steps)
    centre = arc.probes["centre"]
    z_arc = results.final.displacement.reshape(-1, 3)[centre, 2].mean()
    z_load = by_load.displacement.reshape(-1, 3)[centre, 2].mean()
    assert abs(z_arc - z_load) < 1e-3


@pytest.mark.parametrize("p0, gamma", [(3.0e5, 1.0), (1.2e5, 1.4)])
def test_a_sealed_gas_balances_where_its_law_meets_the_balloons_curve(p0, gamma):
    """p0 lambda^(-3 gamma) - p_a = p_h(lambda): the stretch within 1e-6 (measured 2e-7 at
    n = 16). The isothermal gas at 3e5 balances past the limit point."""
    gas = {"kind": "gas", "p0": p0, "ambient": 1.0e5, "gamma": gamma}
    case = balloon(n=16, load=gas, steps=4)
    final = case.solve().final
    volume0 = case.model.discretise().reference_volume
    ratio = 0.1 / effective_radius(case.model.mesh)

    def out_of_balance(lam):
        return p0 * lam ** (-3 * gamma) - 1.0e5 - ratio * REFERENCE.pressure(lam)

    expected = brentq(out_of_balance, 1.0, 3.0, xtol=1e-14)
    assert (final.enclosed_volume / volume0) ** (1 / 3) == pytest.approx(expected, rel=1e-6)
    lam = (final.enclosed_volume / volume0) ** (1 / 3)  # the gas at its law, to round-off
    assert final.pressure == pytest.approx(p0 * lam ** (-3 * gamma) - 1e5, rel=1e-9)


def test_a_flat_airbag_inflated_by_an_amount_of_gas_and_by_its_volume(tmp_path):
    """The quarter airbag from the flat sheet (16 x 16 squares), first inflated at 5 kPa
    under load control; then by the gas amount that is at that pressure in that volume
    (isothermal, ambient 1e5), and by that volume under volume control: each ends within
    1 % of 5 kPa (the sheet's near-equal equilibria differ by that much), the gas at its own
    law to round-off."""
    mesh = {"rectangle": {"nx": 16, "ny": 16}}
    by_load = read_case(AIRBAG, {"mesh": mesh}).solve().final
    volume = by_load.enclosed_volume
    amount = (by_load.pressure + 1.0e5) * volume
    gas = {"kind": "gas", "amount": amount, "ambient": 1.0e5}
    by_gas = read_case(AIRBAG, {"mesh": mesh, "load": [gas]}).solve().final
    assert by_gas.pressure == pytest.approx(5000.0, rel=1e-2)
    assert by_gas.pressure == pytest.approx(amount / by_gas.enclosed_volume - 1e5, rel=1e-9)
    controlled = read_case(
        AIRBAG, {"mesh": mesh, "solver": {"control": "volume", "volume": volume}}
    )
    by_volume = controlled.solve().final
    assert by_volume.enclosed_volume == pytest.approx(volume, rel=1e-7)
    assert by_volume.pressure == pytest.approx(5000.0, rel=1e-2)


class InflatedFromFlat:
    """A volume or gas path whose bordered solves (``control.solve_bordered``, replaced by
    ``solve``) converge in 5 iterations below path parameter 0.9 (the gas does not yet
    fill the sheet: a slack state) and need ``needed`` from any start above it, as the
    inflation that forms the folds does. ``default``: the solver's limit is the method's
    own (100). Records (path parameter, limit) of each solve."""

    n_dofs = 3
    tolerance, max_iterations, method = 1e-8, 100, "newton"

    def __init__(self, needed, default=True):
        self.needed, self.limit_is_default, self.calls = needed, default, []

    def at(self, t, pressure_factor=0.0):
        return type("Problem", (), {"free": np.ones(self.n_dofs, dtype=bool)})()

    def solve(self, family, constraint, u0, mu0, solver, share, merit, iterations=None):
        limit = self.max_iterations if iterations is None else iterations
        self.calls.append((round(family.t, 12), limit))
        needed = 5 if family.t < 0.9 else self.needed
        if needed > limit:
            raise ConvergenceError(f"not converged in {limit} iterations", [])
        solved = type("Solved", (), {})()
        solved.u, solved.mu, solved.iterations = np.full(self.n_dofs, family.t), 0.0, needed
        return solved

    def follow(self, monkeypatch, **settings):
        monkeypatch.setattr(control, "solve_bordered", self.solve)
        admits_all = type("Constraint", (), {"admits": lambda self, mu: True})()
        controller = SolverSettings(**settings).controller()
        control.follow_volume_path(
            self, self, controller, lambda t: (admits_all, None), lambda *step: None
        )


def test_a_volume_path_gives_the_inflation_the_creep_budget(monkeypatch):
    """Worked by hand, an inflation needing 250 iterations (rules 7 and 9 of the step
    controller): in one step, from the flat sheet, the end of the path is solved once with
    4 x 100; in 5 steps the slack levels 0.2 to 0.8 take 5 iterations each, and the step to
    1, which fails with 100, is tried again at once with 400 instead of being cut back into
    the regime where the gas starts to press. Once a level: needing 500, the retry fails
    too and the step is cut back with 100 a solve. A limit set by the user holds everywhere:
    neither the solve from rest nor the failed step is given more."""
    path = InflatedFromFlat(250)
    path.follow(monkeypatch, steps=1)
    assert path.calls == [(1.0, 400)]
    path = InflatedFromFlat(250)
    path.follow(monkeypatch, steps=5)
    assert path.calls == [(0.2, 100), (0.4, 100), (0.6, 100), (0.8, 100), (1.0, 100), (1.0, 400)]
    path = InflatedFromFlat(500)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        path.follow(monkeypatch, steps=5, min_step=0.1)
    assert path.calls[4:] == [(1.0, 100), (1.0, 400), (0.9, 100)]
    path = InflatedFromFlat(250, default=False)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        path.follow(monkeypatch, steps=1, min_step=1.0)
    assert path.calls == [(1.0, 100)]
    path = InflatedFromFlat(250, default=False)
    with pytest.raises(ConvergenceError, match="not converged in 100"):
        path.follow(monkeypatch, steps=5, min_step=0.2)
    assert path.calls[4:] == [(1.0, 100)]


def test_a_gas_sealed_in_no_volume_is_refused():
    """p0 names a gas sealed in the reference volume: on the flat airbag there is none, and
    the message says to give the amount instead."""
    gas = {"kind": "gas", "p0": 1.05e5, "ambient": 1.0e5}
    case = read_case(AIRBAG, {"mesh": {"rectangle": {"nx": 4, "ny": 4}}, "load": [gas]})
    with pytest.raises(ValueError, match="'p0' needs a membrane that encloses a positive"):
        case.solve()


def test_the_volume_gradient_is_the_derivative_of_the_volume():
    """d V / d u against central differences on a random state of the octant, zero at the
    supported components."""
    case = balloon(n=4)
    system = case.model.discretise()
    rng = np.random.default_rng(3)
    u = np.where(system.constrained, 0.0, 0.01 * rng.normal(size=system.n_dofs))
    gradient = system.volume_gradient(u)
    assert not np.any(gradient[system.constrained])
    step = 1e-6
    for dof in rng.choice(np.flatnonzero(~system.constrained), 10, replace=False):
        e = np.zeros_like(u)
        e[dof] = step
        fd = (system.enclosed_volume(u + e) - system.enclosed_volume(u - e)) / (2 * step)
        assert gradient[dof] == pytest.approx(fd, rel=1e-7, abs=1e-12)


@pytest.mark.parametrize("kind", ["volume", "gas"])
def test_the_merits_derivative_along_a_step_is_its_rate_of_change(kind):
    """``Merit.derivative`` of volume control's augmented Lagrangian and of a gas load's
    energy, the measure of their changes near convergence, against central differences of
    the merits themselves along a random step (du, dmu) from a random state near the
    inflated 8 x 8 airbag's (the gas's pressure projected at every point), with the
    constraint and merit the model makes for the case."""
    mesh = {"rectangle": {"nx": 8, "ny": 8}}
    inflated = read_case(AIRBAG, {"mesh": mesh}).solve().final
    volume = inflated.enclosed_volume
    if kind == "volume":
        overrides = {"solver": {"control": "volume", "volume": 1.02 * volume}}
    else:
        gas = {"kind": "gas", "amount": 1.06e5 * volume, "ambient": 1.0e5}
        overrides = {"load": [gas]}
    case = read_case(AIRBAG, {"mesh": mesh, **overrides})
    system = case.model.discretise()
    constraint, merit = case.model._volume_constraints(system, case.settings, "test")(1.0)
    if kind == "volume":
        merit.rho = 3.0e4  # (as a solve may have made it)
    rng = np.random.default_rng(5)
    noise = 1e-3 * rng.normal(size=system.n_dofs)
    u = np.where(system.constrained, 0.0, inflated.displacement + noise)
    du = np.where(system.constrained, 0.0, rng.normal(size=system.n_dofs))
    mu, dmu = (0.9, 0.3) if kind == "volume" else (0.0, 0.0)

    def at(s):
        point = u + s * du
        factor = merit.project(point, mu + s * dmu)
        ev = system.at(1.0, pressure_factor=factor).evaluate(point, stiffness=False)
        lin = constraint(point, factor)
        return merit.value(ev, point, factor, lin.value), ev, lin

    _, ev, lin = at(0.0)
    h = 1e-6
    rate = (at(h)[0] - at(-h)[0]) / (2 * h)
    assert merit.derivative(ev, lin, du, dmu) == pytest.approx(rate, rel=1e-5)


def test_closure_by_symmetry_planes_and_held_edges():
    """The octant and the airbag are closed (symmetry planes through the origin, seams held
    in z); the airbag without its x = 0 support, or lifted off the origin, is not."""
    assert balloon(n=4).model.discretise().volume_closure() is None
    airbag = read_case(AIRBAG, {"mesh": {"rectangle": {"nx": 4, "ny": 4}}})
    assert airbag.model.discretise().volume_closure() is None
    model = airbag.model
    free = model.constrained.reshape(-1, 3)
    free[model.mesh.nodes[:, 0] == 0.0, 0] = False
    model.constrained = free.ravel()
    model._changed()
    assert "encloses no volume" in model.discretise().volume_closure()


def test_gas_law_energy_volume_and_pressure_agree():
    """G'(V) = -p_gauge(V) by central differences; volume(pressure(V)) = V; d V_gas / d p
    by differences; the amount form is at the ambient pressure in amount / p_a at t = 1."""
    for gas, reference in ((Gas(1e5, 1.4, p0=2e5), 0.01), (Gas(1e5, 1.0, amount=500.0), 0.0)):
        for volume in (0.004, 0.009):
            h = 1e-7 * volume
            dG = gas.energy(1.0, reference, volume + h) - gas.energy(1.0, reference, volume - h)
            assert dG / (2 * h) == pytest.approx(-gas.pressure(1.0, reference, volume), rel=1e-7)
            gauge = gas.pressure(1.0, reference, volume)
            back, slope = gas.volume(1.0, reference, gauge)
            assert back == pytest.approx(volume, rel=1e-12)
            dp = 1e-4 * (gauge + 1e5)
            fd = (
                gas.volume(1.0, reference, gauge + dp)[0]
                - gas.volume(1.0, reference, gauge - dp)[0]
            )
            assert slope == pytest.approx(fd / (2 * dp), rel=1e-6)
    assert Gas(1e5, 1.4, amount=500.0).volume(1.0, 0.0, 0.0)[0] == pytest.approx(500.0 / 1e5)


def test_history_and_summary_report_pressure_and_volume(tmp_path, capsys):
    """Volume control from the CLI: history.csv has the columns pressure and enclosed_volume
    (the issue's names), the summary says the path converged and reports both per step."""
    path = tmp_path / "balloon.toml"
    path.write_text(
        SPHERE.read_text()
        .replace("n = 32}", "n = 4}")
        .replace("value = 4878.915624412286", "value = 1.0")
        .replace("steps = 10", 'steps = 6\ncontrol = "volume"\nvolume_ratio = 8.0')
    )
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    with open(tmp_path / "out" / "history.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert {"pressure", "enclosed_volume"} <= set(rows[0])
    volumes = [float(row["enclosed_volume"]) for row in rows]
    assert volumes[-1] == pytest.approx(8.0 * volumes[0] / (1 + 7 / 6), rel=1e-8)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["converged"] and summary["message"] == "converged to path parameter 1"
    assert summary["steps"][-1]["pressure"] == pytest.approx(float(rows[-1]["pressure"]))


@pytest.mark.parametrize("name", ["balloon", "airbag_gas"])
def test_the_examples_run_and_draw_the_pressure_volume_picture(tmp_path, capsys, name):
    """examples/balloon.toml passes its maximum (4,970.7 N/m² on its facets, from the closed
    form) and comes down to p_h(3); examples/airbag_gas.toml settles within 1 % of 5 kPa, the
    pressure its amount of gas was chosen for."""
    out = tmp_path / name
    assert main(["run", str(ROOT / "examples" / f"{name}.toml"), "--out", str(out), "-q"]) == 0
    assert main(["plot", str(out)]) == 0
    assert (out / "pressure_volume.png").read_bytes().startswith(b"\x89PNG")
    with open(out / "history.csv", newline="") as handle:
        pressure = [float(row["pressure"]) for row in csv.DictReader(handle)]
    if name == "balloon":
        case = read_case(ROOT / "examples" / "balloon.toml")
        ratio = 0.1 / effective_radius(case.model.mesh)
        assert max(pressure) < ratio * REFERENCE.limit_pressure * (1 + 1e-6)
        assert max(pressure) > 0.99 * ratio * REFERENCE.limit_pressure
        assert pressure[-1] == pytest.approx(ratio * REFERENCE.pressure(3.0), rel=1e-4)
    else:
        assert pressure[-1] == pytest.approx(5000.0, rel=1e-2)


@pytest.mark.parametrize("control", ["load", "volume"])
def test_a_stop_lands_on_the_probes_displacement_under_load_and_volume_control(control):
    """stop = {pole, 0.01} (a stretch of about 1.1): the step that passes it is solved again
    for its unknown (the load factor, or the pressure) and the path ends there, on the closed
    form's curve: the pole exactly at the stop, the pressure at the volume's stretch within
    3e-4 of p_h."""
    solver = {"steps": 10, "stop": {"probe": "pole", "displacement": 0.01}}
    if control == "volume":
        case = balloon(control="volume", volume_ratio=8.0, **solver)
    else:
        case = balloon(load={"kind": "pressure", "value": 4500.0}, **solver)
    results = case.solve()
    assert results.end.message.startswith("reached the stop")
    pole = results.final.displacement.reshape(-1, 3)[case.probes["pole"]].mean(axis=0)
    assert np.linalg.norm(pole) == pytest.approx(0.01, rel=1e-8)
    assert results.final.load_factor < 1.0
    stretch, error = stretch_and_error(case, results)
    assert abs(error[-1]) < 3e-4 and 1.05 < stretch[-1] < 1.2
