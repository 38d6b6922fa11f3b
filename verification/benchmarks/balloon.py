r"""Gallery benchmark: a neo-Hookean balloon inflated past its limit point, by enclosed-volume
control and by arc length, and inflated by a sealed gas, against the closed form
``verification.references.sphere.InflatedSphere``.

**The benchmark.** The octant of ``verification/cases/balloon.toml`` (symmetry supports on
x = 0, y = 0, z = 0; incompressible neo-Hookean) is inflated

1. by volume control (the case's own ``[solver]``): the enclosed volume from V0 to 27 V0,
   the pressure the unknown;
2. by arc length (``control = "arc-length"``), the pressure the load factor times the load's
   value, until the pole's displacement reaches 2 R (``stop``); and to a pressure above the
   maximum, which the path must fail to reach, naming the peak it located;
3. by a sealed gas (``[[load]] kind = "gas"``), isothermal and adiabatic, whose equilibria lie
   past the limit point (isothermal) and before it (adiabatic);
4. made of Mooney-Rivlin rubber (C01/C10 = 0.1) by volume control to 64 V0, whose pressure has
   a maximum and a minimum (``verification.references.mooney_rivlin_sphere``), and of Ogden's
   three-term fit of Treloar's rubber by volume control to 27 V0
   (``verification.references.ogden_sphere``).

**The reference.** The faceted octant's enclosed volume is V = lambda^3 V0 for a uniform
inflation x = lambda X of its facets, and its volume-to-area ratio that of a sphere of radius
R_eff = 3 V0 / A0 (``effective_radius``), so the energy principle p = dW/dV gives the
closed form of the faceted balloon

    p_h(lambda) = (R / R_eff) (2 mu T / R) (lambda^-1 - lambda^-7),   lambda = (V / V0)^(1/3),

with its maximum at lambda = 7^(1/6), p_max,h = (R / R_eff) p_max (eq. (5) of the reference
module); wrinkle's stretch is measured by the volume it reports (``enclosed_volume``). Every
converged point of both paths is compared with p_h, on both sides of the limit point. The
limit point of the finite-element model is located by maximising its pressure over the
volume (bounded golden-section search, ``scipy.optimize.minimize_scalar``, each evaluation a
volume-controlled solve from the nearest converged state). A gas sealed at p0 in V0 with the
ambient pressure p_a balances where p0 lambda^(-3 gamma) - p_a = p_h(lambda) (root by
``scipy.optimize.brentq``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from verification.levels import mesh_level
from verification.references.mooney_rivlin_sphere import MooneyRivlinSphere
from verification.references.ogden_sphere import TRELOAR, OgdenSphere
from verification.references.sphere import LIMIT_STRETCH, InflatedSphere, effective_radius
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import Case, read_case_data
from wrinkle.materials import MooneyRivlin, Ogden
from wrinkle.mesh import mesh_size
from wrinkle.plot import new_figure
from wrinkle.results import Results
from wrinkle.solvers import ConvergenceError
from wrinkle.solvers.bordered import solve_bordered
from wrinkle.solvers.control import EnclosedVolume, PressureFamily, VolumeLagrangian

__all__ = ["BENCHMARK", "run"]

_SOURCE = "eq. (4), Adkins & Rivlin 1952, of the faceted octant"
AMBIENT = 1.0e5  # N/m^2, the gas's surroundings
GASES = (("isothermal", 3.0e5, 1.0), ("adiabatic", 1.2e5, 1.4))  # name, p0, gamma
# C01 / C10 = 0.1: the pressure rises, falls and rises again (maximum at lambda = 1.4761,
# minimum at 3.1426, verification.references.mooney_rivlin_sphere)
MOONEY_RIVLIN = {"C10": 2.0e5, "C01": 2.0e4, "thickness": 1.0e-3}
OVER_LOAD = 6000.0  # N/m^2, above the balloon's maximum: arc length must name the peak
OGDEN_THICKNESS = 1.0e-3  # m, with Ogden's three-term fit of Treloar's rubber (TRELOAR)


@dataclass
class _Level:
    """One mesh level: n, h, R_eff, V0; (stretch, pressure) of every converged point of the
    volume-controlled and arc-length paths; the limit point found (stretch, pressure); the
    gases' stretches; the count of element-steps not taut."""

    n: int
    size: float
    effective_radius: float
    volume0: float
    volume_curve: tuple[np.ndarray, np.ndarray]
    arc_curve: tuple[np.ndarray, np.ndarray]
    limit: tuple[float, float]
    gas_stretch: dict[str, float]
    not_taut: int
    rubber_curve: tuple[np.ndarray, np.ndarray]
    rubber_maximum: tuple[float, float]
    rubber_minimum: tuple[float, float]
    ogden_curve: tuple[np.ndarray, np.ndarray]
    arc_limit: float


def _curve(results: Results, volume0: float) -> tuple[np.ndarray, np.ndarray]:
    stretch = [(step.enclosed_volume / volume0) ** (1.0 / 3.0) for step in results.steps]
    pressure = [step.pressure for step in results.steps]
    return np.array(stretch), np.array(pressure)


def _turning_point(
    case: Case, results: Results, volume0: float, sign: float = 1.0, after: int = 0
) -> tuple[float, float, int]:
    """(stretch, pressure, step) where the volume-controlled balloon's pressure is largest
    (sign 1) or smallest (sign -1) among the converged steps from ``after`` on: a bounded
    search over the volume between that step's neighbours, each pressure from a
    volume-controlled solve."""
    model, settings = case.model, case.settings
    system = model.discretise()
    solver = settings.solver()
    steps = results.steps
    k = after + int(np.argmax([sign * step.pressure for step in steps[after:]]))
    low = steps[max(k - 1, 0)].enclosed_volume
    high = steps[min(k + 1, len(steps) - 1)].enclosed_volume
    start = [steps[k].displacement, float(steps[k].pressure)]

    def minus_pressure(volume: float) -> float:
        constraint = EnclosedVolume(system, lambda mu: (volume, 0.0), volume)
        solved = solve_bordered(
            PressureFamily(system, 1.0),
            constraint,
            start[0],
            start[1],
            solver,
            merit=VolumeLagrangian(1.0, volume),
        )
        start[:] = [solved.u, solved.mu]
        return -sign * solved.mu

    found = minimize_scalar(
        minus_pressure, bounds=(low, high), method="bounded", options={"xatol": 1e-9 * high}
    )
    solver.release()
    return float((found.x / volume0) ** (1.0 / 3.0)), float(-sign * found.fun), k


def _solve_level(case_path: Path, n: int) -> _Level:
    case = mesh_level(case_path, n=n)
    mesh = case.model.mesh
    volume0 = case.model.discretise().reference_volume
    by_volume = case.solve()
    limit = _turning_point(case, by_volume, volume0)[:2]
    ogden = mesh_level(case_path, n=n)
    mu, alpha = zip(*TRELOAR, strict=True)
    ogden.model.assign_material(Ogden(mu=mu, alpha=alpha, thickness=OGDEN_THICKNESS))
    by_ogden = ogden.solve()
    rubber = mesh_level(case_path, {"solver": {"volume_ratio": 64.0}}, n=n)
    rubber.model.assign_material(MooneyRivlin(**MOONEY_RIVLIN))
    by_rubber = rubber.solve(steps=64)
    *maximum, top = _turning_point(rubber, by_rubber, volume0)
    *minimum, _ = _turning_point(rubber, by_rubber, volume0, -1.0, top)
    radius = float(np.linalg.norm(mesh.nodes, axis=1).max())
    # the load's value sets the first step, 1/50 of it: 100 N/m², a stretch of 1.002
    arc = mesh_level(case_path, {"load": [{"kind": "pressure", "value": 5000.0}]}, n=n)
    arc_settings = dataclasses.replace(
        arc.settings,
        control="arc-length",
        volume_ratio=None,
        stop=("pole", 2.0 * radius),
        steps=50,
    )
    by_arc = arc.model.solve(arc_settings, probes=arc.probes)
    # above the maximum without a stop: the path fails, and names the peak it passed
    over = mesh_level(case_path, {"load": [{"kind": "pressure", "value": OVER_LOAD}]}, n=n)
    over_settings = dataclasses.replace(
        over.settings, control="arc-length", volume_ratio=None, steps=20
    )
    try:
        over.model.solve(over_settings)
        arc_limit = np.nan  # a path that carried more than the maximum: the check fails
    except ConvergenceError as error:
        arc_limit = np.nan if error.limit_point is None else error.limit_point * OVER_LOAD
    gas_stretch = {}
    for name, p0, gamma in GASES:
        gas = mesh_level(
            case_path,
            {"load": [{"kind": "gas", "p0": p0, "ambient": AMBIENT, "gamma": gamma}]},
            n=n,
        )
        settings = dataclasses.replace(gas.settings, control="load", volume_ratio=None, steps=4)
        final = gas.model.solve(settings).final
        gas_stretch[name] = (final.enclosed_volume / volume0) ** (1.0 / 3.0)
    not_taut = sum(
        s.states[1] + s.states[2] for r in (by_volume, by_arc, by_rubber, by_ogden) for s in r.steps
    )
    return _Level(
        n,
        mesh_size(mesh),
        effective_radius(mesh),
        volume0,
        _curve(by_volume, volume0),
        _curve(by_arc, volume0),
        limit,
        gas_stretch,
        int(not_taut),
        _curve(by_rubber, volume0),
        (maximum[0], maximum[1]),
        (minimum[0], minimum[1]),
        _curve(by_ogden, volume0),
        arc_limit,
    )


def _sphere(case: Path) -> InflatedSphere:
    data = read_case_data(case)
    material = data["material"]
    return InflatedSphere(
        float(material["mu"]), float(material["thickness"]), float(data["mesh"]["sphere"]["radius"])
    )


def _gas_reference(sphere: InflatedSphere, ratio: float, p0: float, gamma: float) -> float:
    """The stretch where the gas sealed at p0 in V0 balances the faceted balloon."""

    def out_of_balance(stretch: float) -> float:
        return p0 * stretch ** (-3.0 * gamma) - AMBIENT - ratio * float(sphere.pressure(stretch))

    return float(brentq(out_of_balance, 1.0, 3.0, xtol=1e-14))


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Solve every mesh level of [verification.quick] or [verification.full] three ways,
    compare with the closed form and write the figures into ``out``."""
    case, out = Path(case), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sphere = _sphere(case)
    table = read_case_data(case)["verification"]["quick" if quick else "full"]
    tolerance = table["tolerance"]
    levels = [_solve_level(case, int(n)) for n in table["n"]]
    finest = levels[-1]
    ratio = sphere.radius / finest.effective_radius

    def worst(curve: tuple[np.ndarray, np.ndarray], level: _Level) -> tuple[float, float]:
        stretch, pressure = curve
        factor = sphere.radius / level.effective_radius
        errors = pressure / (factor * sphere.pressure(stretch)) - 1.0
        k = int(np.argmax(np.abs(errors)))
        return float(stretch[k]), float(errors[k])

    checks = []
    for label, curve in (
        ("volume control", finest.volume_curve),
        ("arc length", finest.arc_curve),
    ):
        stretch, error = worst(curve, finest)
        checks.append(
            Check(
                f"{label}: worst relative pressure error of {curve[0].size} points from "
                f"lambda = 1 to {curve[0].max():.3f} (at lambda = {stretch:.4f}), n = {finest.n}",
                0.0,
                _SOURCE,
                error,
                tolerance["pressure"],
                relative=False,
            )
        )
    checks += [
        Check(
            f"limit pressure (N/m²), n = {finest.n}",
            ratio * sphere.limit_pressure,
            "eq. (5), of the faceted octant",
            finest.limit[1],
            tolerance["limit_pressure"],
        ),
        Check(
            f"limit pressure (N/m²) by arc length to {OVER_LOAD:g} N/m² (the peak of the path, "
            f"which fails), n = {finest.n}",
            ratio * sphere.limit_pressure,
            "eq. (5), of the faceted octant",
            finest.arc_limit,
            tolerance["limit_pressure"],
        ),
        Check(
            f"limit stretch, n = {finest.n}",
            LIMIT_STRETCH,
            "eq. (5): 7^(1/6)",
            finest.limit[0],
            tolerance["limit_stretch"],
        ),
    ]
    rubber = MooneyRivlinSphere(
        MOONEY_RIVLIN["C10"], MOONEY_RIVLIN["C01"], MOONEY_RIVLIN["thickness"], sphere.radius
    )
    top, bottom = rubber.turning_points()
    assert top is not None and bottom is not None
    for label, reference, found in (
        ("maximum", top, finest.rubber_maximum),
        ("minimum", bottom, finest.rubber_minimum),
    ):
        checks += [
            Check(
                f"Mooney-Rivlin (C01/C10 = 0.1): stretch at the pressure's {label}, n = {finest.n}",
                reference,
                "eq. (3) of verification.references.mooney_rivlin_sphere, root",
                found[0],
                tolerance["limit_stretch"],
            ),
            Check(
                f"Mooney-Rivlin: pressure at its {label} (N/m²), n = {finest.n}",
                ratio * float(rubber.pressure(reference)),
                "eq. (2) there, of the faceted octant",
                found[1],
                tolerance["limit_pressure"],
            ),
        ]
    mu, alpha = zip(*TRELOAR, strict=True)
    ogden = OgdenSphere(mu, alpha, OGDEN_THICKNESS, sphere.radius)
    lam, p = finest.ogden_curve
    ogden_errors = p / (ratio * ogden.pressure(lam)) - 1.0
    worst = int(np.argmax(np.abs(ogden_errors)))
    checks.append(
        Check(
            f"Ogden (Treloar's rubber, 3 terms), volume control: worst relative pressure error of "
            f"{lam.size} points to lambda = {lam.max():.3f} (at lambda = {lam[worst]:.4f}), "
            f"n = {finest.n}",
            0.0,
            "eq. (1) of verification.references.ogden_sphere, of the faceted octant",
            float(ogden_errors[worst]),
            tolerance["pressure"],
            relative=False,
        )
    )
    for name, p0, gamma in GASES:
        checks.append(
            Check(
                f"stretch inflated by a gas sealed at {p0:.3g} N/m² ({name}, gamma = {gamma:g}), "
                f"n = {finest.n}",
                _gas_reference(sphere, ratio, p0, gamma),
                "p0 lambda^(-3 gamma) - p_a = p_h(lambda), root",
                finest.gas_stretch[name],
                tolerance["gas_stretch"],
            )
        )
    checks.append(
        Check.none_of(
            "element-steps not taut, every path", finest.not_taut, "equibiaxial tension everywhere"
        )
    )
    sizes = [level.size for level in levels]
    convergence = [
        Convergence(
            "limit pressure against the smooth sphere's, relative error",
            sizes,
            [level.limit[1] / sphere.limit_pressure - 1.0 for level in levels],
            2.0,
        )
    ]
    figures = [_plot(sphere, levels, out / "pressure_stretch.png")]
    text = _text(sphere, levels, quick)
    return Outcome(checks, figures, text, convergence)


def _plot(sphere: InflatedSphere, levels: list[_Level], path: Path) -> Path:
    """The closed form through its limit point, both paths and the gas equilibria on the
    finest mesh; the relative pressure errors of every point on every mesh."""
    finest = levels[-1]
    ratio = sphere.radius / finest.effective_radius
    fig = new_figure(figsize=(12.0, 4.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    stretch = np.linspace(1.0, 3.05, 500)
    left.plot(stretch, ratio * sphere.pressure(stretch), "-", color="0.2", label="closed form")
    left.plot(*finest.volume_curve, "o", mfc="none", color="C0", label="volume control")
    left.plot(*finest.arc_curve, "x", color="C1", label="arc length")
    left.plot([finest.limit[0]], [finest.limit[1]], "D", color="C3", label="limit point found")
    for k, (name, _, _) in enumerate(GASES):
        lam = finest.gas_stretch[name]
        left.plot(
            [lam], [ratio * sphere.pressure(lam)], "s", color=f"C{4 + k}", label=f"gas, {name}"
        )
    left.set_xlabel(r"stretch $\lambda = (V/V_0)^{1/3}$")
    left.set_ylabel("pressure (N/m²)")
    left.grid(True, alpha=0.3)
    left.legend(fontsize=8)
    left.set_title(f"Octant n = {finest.n}", fontsize=10)
    for k, level in enumerate(levels):
        factor = sphere.radius / level.effective_radius
        for curve, marker in ((level.volume_curve, "o"), (level.arc_curve, "x")):
            lam, p = curve
            right.semilogy(
                lam,
                np.abs(p / (factor * sphere.pressure(lam)) - 1.0) + 1e-16,
                marker,
                color=f"C{k}",
                ms=4,
                label=f"n = {level.n}" if marker == "o" else None,
            )
    right.set_xlabel(r"stretch $\lambda$")
    right.set_ylabel("|relative pressure error|")
    right.grid(True, which="both", alpha=0.3)
    right.legend(fontsize=8)
    right.set_title("Every converged point (o volume control, x arc length)", fontsize=10)
    fig.suptitle("Neo-Hookean balloon past its limit point", fontsize=11)
    fig.savefig(path, dpi=150)
    return path


def _text(sphere: InflatedSphere, levels: list[_Level], quick: bool) -> str:
    finest = levels[-1]
    points = finest.volume_curve[0].size + finest.arc_curve[0].size
    meshes = ", ".join(str(level.n) for level in levels)
    return (
        f"One octant of a spherical neo-Hookean membrane (R = {sphere.radius:g} m, T = "
        f"{sphere.thickness:g} m, mu = {sphere.mu:g} N/m²) on meshes n = {meshes}"
        f"{' (quick run)' if quick else ''} is inflated to three times its radius, past the "
        f"limit point lambda = 7^(1/6), by volume control ({finest.volume_curve[0].size} "
        f"steps) and by arc length with a stop at the pole's displacement 2 R "
        f"({finest.arc_curve[0].size} steps): {points} converged points on the finest mesh, "
        f"all compared with the closed form of the faceted octant. The limit point is found by "
        f"maximising the volume-controlled pressure over the volume: lambda = "
        f"{finest.limit[0]:.6f}, p = {finest.limit[1]:.6g} N/m². Two sealed gases, at "
        f"{GASES[0][1]:.3g} N/m² isothermal and {GASES[1][1]:.3g} N/m² adiabatic, with the "
        f"ambient pressure {AMBIENT:.3g} N/m², balance at lambda = "
        f"{finest.gas_stretch[GASES[0][0]]:.6f} (past the limit point: the gas's stiffness "
        f"makes the falling branch stable) and {finest.gas_stretch[GASES[1][0]]:.6f}. Under "
        "load control the same balloon cannot pass the limit point: the run stops with the "
        "limit-point message (benchmarks/limit_point_sweep.py)."
    )


BENCHMARK = Benchmark(
    "balloon",
    "Rubber balloons past their limit point: volume control, arc length, gas",
    run,
)
