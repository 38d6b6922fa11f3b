r"""Gallery benchmark: an inflated thin spherical membrane of incompressible neo-Hookean
rubber, against the closed-form pressure-stretch curve
``verification.references.sphere.InflatedSphere`` (derivation, eqs. (1)-(5), and the sources
in that module's docstring).

**The benchmark.** One octant of the sphere (``wrinkle.mesh.sphere``) with symmetry supports on
the planes x = 0, y = 0, z = 0, incompressible neo-Hookean material, follower pressure
increased in load steps to the case file's pressure (p(1.3)). At each converged step the
stretch is measured as the mean of |x_i| / R over the nodes (their root-mean-square scatter
says how far the nodes are from one sphere) and compared with (4); the membrane tension of
every element with (3); and every element must stay taut. The finite-element octant is the
faceted polyhedron inscribed in the sphere: its volume-to-area ratio is that of a sphere of the
smaller radius R_eff = 3 V / A (``effective_radius``), so for a uniform inflation x = lambda X
of the facets the energy principle gives p = (R / R_eff) p(lambda). The finite-element sphere is
therefore slightly stiffer than the smooth one, with a relative error of order (h/R)^2.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.references.sphere import LIMIT_STRETCH, InflatedSphere, effective_radius
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import read_case_data
from wrinkle.mesh import mesh_size
from wrinkle.model import Model
from wrinkle.plot import new_figure, plot_convergence, plot_state_map
from wrinkle.post import element_report

__all__ = ["BENCHMARK", "run"]


# -- the gallery benchmark ---------------------------------------------------------------------

_SOURCE = "eq. (4), Adkins & Rivlin 1952"


@dataclass(frozen=True)
class _Setup:
    """What the case file gives: the analytical sphere, the applied pressure, the
    [verification] table, the length, force and stress units."""

    sphere: InflatedSphere
    pressure: float
    verification: dict
    units: dict


def _read_setup(case: Path) -> _Setup:
    """R from ``[mesh] sphere``, mu and T from an incompressible ``neo-hookean`` [material],
    p from the one ``pressure`` load; ValueError naming the file if the case is not of that
    form."""
    data = read_case_data(case)

    def fail(message: str):
        raise ValueError(f"{case}: {message}")

    mesh = data.get("mesh") if isinstance(data.get("mesh"), dict) else {}
    generator = mesh.get("sphere")
    if not isinstance(generator, dict) or "radius" not in generator:
        fail("[mesh]: the sphere benchmark needs 'sphere = {radius, n}'")
    material = data.get("material")
    if (
        not isinstance(material, dict)
        or material.get("model") != "neo-hookean"
        or "lmbda" in material
    ):
        fail("[material]: the sphere benchmark needs one incompressible 'neo-hookean' material")
    pressures = [
        load.get("value") for load in data.get("load", []) if load.get("kind") == "pressure"
    ]
    if len(pressures) != 1 or len(data.get("load", [])) != 1:
        fail("[[load]]: the sphere benchmark needs exactly one load, a 'pressure'")
    verification = data.get("verification")
    if not isinstance(verification, dict) or not {"quick", "full"} <= set(verification):
        fail("[verification]: tables [verification.quick] and [verification.full] missing")
    sphere = InflatedSphere(
        float(material["mu"]), float(material["thickness"]), float(generator["radius"])
    )
    units = mesh.get("units", {})
    return _Setup(
        sphere, float(pressures[0]), verification, units if isinstance(units, dict) else {}
    )


@dataclass
class _Level:
    """One mesh level solved: n, the model, its size h and effective radius 3V/A (length);
    per converged step (k,) the load factor, the applied pressure, the mean stretch
    mean |x_i| / R over the nodes and its RMS scatter relative to the mean, and the element
    tensions (principal Cauchy resultants, force per current length, (n_elements, 2) each);
    the number of element-steps not taut; the final displacements (n_dofs,)."""

    n: int
    model: Model
    size: float
    effective_radius: float
    load_factor: np.ndarray
    pressure: np.ndarray
    stretch: np.ndarray
    scatter: np.ndarray
    tension: list
    not_taut: int
    final_displacement: np.ndarray


def _solve_level(case: Path, setup: _Setup, n: int) -> _Level:
    """Solve the case on the octant mesh with n divisions per edge; measure every step."""
    level = mesh_level(case, n=n)
    model = level.model
    radius = setup.sphere.radius
    X = model.mesh.nodes
    results = level.solve()
    factors, stretches, scatters, tensions = [], [], [], []
    for step in results.steps:
        node_stretch = np.linalg.norm(X + step.displacement.reshape(-1, 3), axis=1) / radius
        mean = float(node_stretch.mean())
        factors.append(step.load_factor)
        stretches.append(mean)
        scatters.append(float(np.sqrt(np.mean((node_stretch / mean - 1.0) ** 2))))
        tensions.append(element_report(model, step.displacement).principal_stress)
    not_taut = sum(step.states[1] + step.states[2] for step in results.steps)
    factors = np.array(factors)
    return _Level(
        n,
        model,
        mesh_size(model.mesh),
        effective_radius(model.mesh),
        factors,
        factors * setup.pressure,
        np.array(stretches),
        np.array(scatters),
        tensions,
        int(not_taut),
        results.final.displacement,
    )


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Inflate the case's octant on every mesh level of [verification.quick] or
    [verification.full], compare with ``InflatedSphere`` and write three figures into
    ``out``."""
    case, out = Path(case), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    setup = _read_setup(case)
    sphere = setup.sphere
    level_table = setup.verification["quick" if quick else "full"]
    tolerance = level_table["tolerance"]
    meshes = [int(n) for n in level_table["n"]]
    levels = [_solve_level(case, setup, n) for n in meshes]
    finest = levels[-1]

    reference_stretch = float(sphere.stretch(setup.pressure))
    reference_tension = float(sphere.tension(reference_stretch))
    stress_unit = setup.units.get("stress", "")
    pressure_unit = _pressure_unit(setup.units)

    def stretch_error(level: _Level) -> float:
        return level.stretch[-1] / reference_stretch - 1.0

    def pressure_errors(level: _Level) -> np.ndarray:
        return level.pressure / sphere.pressure(level.stretch) - 1.0

    def tension_error(level: _Level) -> float:
        return float(np.max(np.abs(level.tension[-1] / reference_tension - 1.0)))

    worst_step = int(np.argmax(np.abs(pressure_errors(finest))))
    worst_tension = finest.tension[-1].ravel()[
        np.argmax(np.abs(finest.tension[-1].ravel() - reference_tension))
    ]
    steps = finest.load_factor.size
    checks = [
        Check(
            f"stretch lambda = mean |x| / R at p = {setup.pressure:.6g} {pressure_unit}, "
            f"n = {finest.n}",
            reference_stretch,
            _SOURCE + ", root of p(lambda) = p",
            finest.stretch[-1],
            tolerance["stretch"],
        ),
        Check(
            f"pressure at wrinkle's stretch lambda = {finest.stretch[worst_step]:.6f}, the "
            f"worst of {steps} load steps ({pressure_unit})",
            float(sphere.pressure(finest.stretch[worst_step])),
            _SOURCE,
            finest.pressure[worst_step],
            tolerance["pressure"],
        ),
        Check(
            f"RMS scatter of |x| / R over the nodes, relative to the mean, n = {finest.n}",
            0.0,
            "a sphere: every node at the same radius",
            finest.scatter[-1],
            tolerance["scatter"],
            relative=False,
        ),
        Check(
            f"membrane tension, worst element and direction, n = {finest.n}"
            + (f" ({stress_unit})" if stress_unit else ""),
            reference_tension,
            "eq. (3), N = mu T (1 - lambda^-6)",
            float(worst_tension),
            tolerance["tension"],
        ),
        Check.none_of(
            f"elements not taut, all {steps} load steps",
            finest.not_taut,
            "equibiaxial tension everywhere",
        ),
    ]
    sizes = [level.size for level in levels]
    convergence = [
        Convergence(
            "stretch at the final pressure, relative error",
            sizes,
            [stretch_error(level) for level in levels],
            2.0,
        ),
        Convergence(
            "RMS scatter of the nodal radii / mean radius",
            sizes,
            [level.scatter[-1] for level in levels],
            2.0,
        ),
        Convergence(
            "membrane tension of the worst element, relative error",
            sizes,
            [tension_error(level) for level in levels],
            2.0,
        ),
    ]

    length_unit = setup.units.get("length", "")
    figures = [
        _plot_pressure_stretch(
            sphere, setup.pressure, levels, pressure_unit, length_unit, out / "pressure_stretch.png"
        ),
        plot_state_map(
            finest.model,
            finest.final_displacement,
            out / "state_map.png",
            f"Inflated neo-Hookean sphere, octant n = {finest.n}, "
            f"p = {setup.pressure:.6g} {pressure_unit}",
            length_unit,
        ),
        plot_convergence(
            convergence,
            out / "convergence.png",
            "Inflated neo-Hookean sphere: errors against mesh size h"
            + (f" ({length_unit})" if length_unit else ""),
        ),
    ]
    text = _text(setup, levels, reference_stretch, convergence, quick)
    return Outcome(checks, figures, text, convergence)


def _pressure_unit(units: dict) -> str:
    force, length = units.get("force", ""), units.get("length", "")
    return f"{force}/{length}²" if force and length else ""


def _plot_pressure_stretch(
    sphere: InflatedSphere,
    pressure: float,
    levels: list[_Level],
    pressure_unit: str,
    length_unit: str,
    path: Path,
) -> Path:
    """Left: eq. (4) with its limit point and the finite-element (stretch, pressure) of every
    load step on every mesh. Right: the relative pressure error at wrinkle's stretch per step
    and mesh, falling as (h/R)^2."""
    unit = f" ({pressure_unit})" if pressure_unit else ""
    fig = new_figure(figsize=(12.0, 4.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    stretch = np.linspace(1.0, 2.0, 401)
    left.plot(
        stretch,
        sphere.pressure(stretch),
        "-",
        color="0.2",
        lw=1.5,
        label=r"closed form $p = (2\mu T/R)(\lambda^{-1} - \lambda^{-7})$",
    )
    left.plot(
        [LIMIT_STRETCH],
        [sphere.limit_pressure],
        "D",
        color="C3",
        ms=7,
        label=rf"limit point $\lambda = 7^{{1/6}}$ = {LIMIT_STRETCH:.4f}, "
        f"p = {sphere.limit_pressure:.5g}",
    )
    left.axhline(
        pressure,
        color="0.5",
        ls=":",
        lw=1.0,
        label=f"applied pressure {pressure:.6g} (load control)",
    )
    markers = "osv^D<>"
    for k, level in enumerate(levels):
        filled = level is levels[-1]
        left.plot(
            level.stretch,
            level.pressure,
            markers[k % len(markers)],
            color=f"C{k}",
            ms=6,
            mfc=None if filled else "none",
            label=f"wrinkle, n = {level.n} ({level.model.mesh.n_elements} elements)",
        )
        right.semilogy(
            level.stretch,
            np.abs(level.pressure / sphere.pressure(level.stretch) - 1.0),
            markers[k % len(markers)] + "-",
            color=f"C{k}",
            ms=5,
            label=f"n = {level.n}, h/R = {level.size / sphere.radius:.3g}",
        )
    left.set_xlabel(r"stretch $\lambda$ = mean current radius / R")
    left.set_ylabel("internal pressure p" + unit)
    left.set_xlim(1.0, 2.0)
    left.set_ylim(bottom=0.0, top=1.12 * sphere.limit_pressure)
    left.grid(True, alpha=0.3)
    left.legend(fontsize=8, loc="lower right")
    left.set_title("Pressure against stretch", fontsize=10)
    right.set_xlabel(r"stretch $\lambda$ measured by wrinkle")
    right.set_ylabel(r"|p$_{applied}$ / p$_{closed\ form}(\lambda)$ - 1|")
    right.grid(True, which="both", alpha=0.3)
    right.legend(fontsize=8)
    right.set_title("Relative pressure error at wrinkle's stretch, every load step", fontsize=10)
    length = f" {length_unit}" if length_unit else ""
    modulus = f" {pressure_unit}" if pressure_unit else ""
    fig.suptitle(
        f"Inflated neo-Hookean sphere: R = {sphere.radius:g}{length}, T = "
        f"{sphere.thickness:g}{length}, mu = {sphere.mu:g}{modulus} (one octant, "
        "symmetry planes)",
        fontsize=11,
    )
    fig.savefig(path, dpi=150)
    return path


def _text(
    setup: _Setup,
    levels: list[_Level],
    reference_stretch: float,
    convergence: list[Convergence],
    quick: bool,
) -> str:
    sphere = setup.sphere
    finest = levels[-1]
    error = finest.stretch[-1] / reference_stretch - 1.0
    faceted = _faceted_stretch(sphere, setup.pressure, finest.effective_radius)
    faceted_error = faceted / reference_stretch - 1.0
    finest_ratio = sphere.radius / finest.effective_radius - 1.0
    pressure_error = finest.pressure / sphere.pressure(finest.stretch) - 1.0
    first_pressure_error, last_pressure_error = pressure_error[0], pressure_error[-1]
    relative_scatter = finest.scatter * finest.stretch / (finest.stretch - 1.0)
    first_scatter, last_scatter = relative_scatter[0], relative_scatter[-1]
    taut = (
        "all elements are taut at every step"
        if finest.not_taut == 0
        else f"{finest.not_taut} element-steps are NOT taut (the exact state is taut)"
    )
    orders = ", ".join(f"{c.quantity} {c.observed_order:.2f}" for c in convergence)
    meshes = ", ".join(str(level.n) for level in levels)
    ratio = setup.pressure / sphere.limit_pressure
    length = f" {setup.units['length']}" if setup.units.get("length") else ""
    modulus = f" {_pressure_unit(setup.units)}" if _pressure_unit(setup.units) else ""
    return (
        f"One octant of a spherical membrane (R = {sphere.radius:g}{length}, T = "
        f"{sphere.thickness:g}{length}, incompressible neo-Hookean, mu = {sphere.mu:g}"
        f"{modulus}) with symmetry supports on the planes x = 0, y = 0, z = 0 is inflated by "
        f"a follower pressure raised in {finest.load_factor.size} load steps to p = "
        f"{setup.pressure:.10g}{modulus}, the closed-form "
        f"pressure at lambda = 1.3. The mesh (``sphere`` generator) is an octahedron face cut "
        f"into n² triangles and projected onto the sphere, n = {meshes}"
        f"{' (quick run: coarse meshes)' if quick else ''}. Reference (Adkins & Rivlin 1952; "
        f"Treloar 1975; Ogden 1984): equibiaxial stretch lambda, current thickness "
        f"T/lambda², Cauchy stress mu (lambda² - lambda⁻⁴) and Laplace's law p = 2 sigma t / "
        f"r give p = (2 mu T / R)(lambda⁻¹ - lambda⁻⁷) (derivation in "
        f"`verification.references.sphere`; unit-tested against p = dW/dV of the sphere's strain "
        f"energy and against `wrinkle.material_response`). The pressure has its maximum "
        f"p_max = {sphere.limit_pressure:.6g} at lambda = 7^(1/6) = {LIMIT_STRETCH:.4f}; the "
        f"applied pressure is {100 * ratio:.1f} % of it, so plain load control stays on the "
        f"rising, stable branch (the limit point and the falling branch are the balloon "
        f"benchmark's, by volume control and arc length). The reference stretch at the applied "
        f"pressure is the root of p(lambda) = p on [1, 7^(1/6)], lambda = "
        f"{reference_stretch:.12f}, found by bisection to round-off.\n\n"
        f"wrinkle's stretch (mean of |x|/R over the nodes) on n = {finest.n} is "
        f"{finest.stretch[-1]:.6f}, {error:+.2e} relative; {taut} and the nodes lie on one "
        f"sphere to an RMS scatter of {finest.scatter[-1]:.1e}. "
        f"The finite-element sphere is slightly too stiff (its stretch is too small) because "
        f"the faceted octant inscribed in the sphere encloses less volume per unit area: its "
        f"effective radius 3V/A = {finest.effective_radius / sphere.radius:.6f} R, and a "
        f"uniform inflation of the facets needs p = (R / R_eff) p(lambda) by the energy "
        f"principle. That alone predicts a stretch error of {faceted_error:+.2e}, "
        f"{100 * faceted_error / error:.0f} % of the measured one; the rest comes from the "
        f"nodes moving off one sphere: the smallest radii are at the octant's corners and the "
        f"largest at the middle of its edges (in the whole sphere, the octahedron's vertices, "
        f"where four triangles meet instead of six, and its edges, across which the mesh "
        f"spacing has a kink). At the last load step the relative pressure error at wrinkle's "
        f"stretch, {last_pressure_error:+.2e}, is the facets' R / R_eff - 1 = "
        f"{finest_ratio:+.2e}; it is largest at the first step ({first_pressure_error:+.2e}), "
        f"where the deformation is least uniform: the RMS scatter of the nodal radii is "
        f"{100 * first_scatter:.2g} % of the mean radial displacement there and "
        f"{100 * last_scatter:.2g} % at the last step, the growing membrane tension evening "
        f"it out. "
        f"Both the geometric error and the "
        f"scatter are of order (h/R)²: observed orders {orders}. The worst element's tension "
        f"converges at a little less than 2 (local orders rising towards 2), again because of "
        f"the irregular vertices. Tolerances: about 1.4 times the errors measured on the "
        f"finest mesh of each run, whose (h/R)² behaviour the convergence study shows; they "
        f"are the discretisation error of the faceted geometry, not a model error."
    )


def _faceted_stretch(sphere: InflatedSphere, pressure: float, effective_radius: float) -> float:
    """Stretch of a uniformly inflated faceted sphere with effective radius R_eff = 3V/A:
    the root of (R / R_eff) p(lambda) = pressure, i.e. p(lambda) = pressure R_eff / R."""
    return float(sphere.stretch(pressure * effective_radius / sphere.radius))


BENCHMARK = Benchmark("sphere", "Inflated neo-Hookean sphere", run)
