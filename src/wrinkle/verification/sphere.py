r"""Inflated thin spherical membrane of incompressible neo-Hookean rubber: the closed-form
pressure-stretch curve and the gallery benchmark.

**The problem.** A spherical membrane of reference radius R and reference thickness T, made of
incompressible neo-Hookean material with shear modulus mu (strain energy per unit reference
volume W = mu/2 (lambda_1^2 + lambda_2^2 + lambda_3^2 - 3)), is inflated by an internal
pressure p (force per unit current area). By symmetry it stays spherical, with current radius
r = lambda R: every point is stretched equibiaxially by lambda in the membrane's plane.

**Kinematics.** Principal stretches lambda_1 = lambda_2 = lambda in the plane;
incompressibility lambda_1 lambda_2 lambda_3 = 1 gives the stretch across the thickness
lambda_3 = lambda^-2, so the current thickness is

    t = T / lambda^2.                                                                    (1)

**Stress.** With plane stress sigma_3 = 0 fixing the hydrostatic pressure of the
incompressible material, the in-plane Cauchy stress is
sigma = lambda dW/dlambda (equibiaxial, W(lambda) = mu/2 (2 lambda^2 + lambda^-4 - 3)):

    sigma = mu (lambda^2 - lambda^-4),                                                   (2)

and the membrane tension (Cauchy stress resultant, force per unit current length)

    N = sigma t = mu T (1 - lambda^-6).                                                  (3)

**Equilibrium (Laplace's law).** Half the sphere: the pressure on the equatorial disk,
p pi r^2, is carried by the tension on the equator, N 2 pi r, so p = 2 N / r = 2 sigma t / r:

    p(lambda) = (2 mu T / R) (lambda^-1 - lambda^-7).                                    (4)

The same follows from the energy principle p = dW_total/dV with the total strain energy
W_total = 4 pi R^2 T W(lambda) and the enclosed volume V = 4/3 pi R^3 lambda^3 (the unit tests
check (4) that way).

**Limit point.** dp/dlambda = (2 mu T / R)(7 lambda^-8 - lambda^-2) vanishes at

    lambda_max = 7^(1/6) = 1.38309,    p_max = (2 mu T / R) (6/7) 7^(-1/6) = 0.61973 (2 mu T / R).  (5)

Below lambda_max the pressure rises with the stretch; beyond it the sphere is unstable under
pressure control (the familiar balloon "snap"). On the rising branch the stretch at a given
pressure p <= p_max is the root of (4) in [1, lambda_max]; ``InflatedSphere.stretch`` finds it
by bisection to the floating-point resolution (the semi-analytical reference of the
benchmark).

Sources: J. E. Adkins and R. S. Rivlin, "Large elastic deformations of isotropic materials IX.
The deformation of thin shells", Phil. Trans. R. Soc. Lond. A 244 (1952) 505-531 (inflation of
a thin spherical shell of neo-Hookean and Mooney material); L. R. G. Treloar, The Physics of
Rubber Elasticity, 3rd ed., Clarendon Press, Oxford, 1975 (inflation of a spherical balloon,
with the maximum of the pressure at lambda = 7^(1/6) for the neo-Hookean solid);
R. W. Ogden, Non-linear Elastic Deformations, Ellis Horwood, 1984 (Dover reprint 1997)
(inflation of a spherical membrane).

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

from wrinkle.case import read_case, read_case_data
from wrinkle.mesh import Mesh, mesh_size
from wrinkle.model import Model
from wrinkle.results import element_report
from wrinkle.verification.gallery import Benchmark, Check, Convergence, Outcome

LIMIT_STRETCH = 7.0 ** (1.0 / 6.0)  # eq. (5): the maximum of p(lambda)

_BISECTIONS = 80  # halves [1, 7^(1/6)] down to below the spacing of doubles near 1.4


@dataclass(frozen=True)
class InflatedSphere:
    """Thin spherical membrane of incompressible neo-Hookean material under internal pressure
    (module docstring, eqs. (1)-(5)).

    mu: shear modulus (force/area); thickness: reference thickness T (length); radius:
    reference radius R (length). Consistent units; pressures are force/area, tensions
    force/length. Stretch arguments are arrays (or scalars) lambda >= 1.
    """

    mu: float
    thickness: float
    radius: float

    def __post_init__(self):
        for name in ("mu", "thickness", "radius"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"InflatedSphere: {name} must be finite and > 0, got {value!r}")

    @property
    def pressure_scale(self) -> float:
        """2 mu T / R (force/area), the factor of eq. (4)."""
        return 2.0 * self.mu * self.thickness / self.radius

    def pressure(self, stretch):
        """Eq. (4): p = (2 mu T / R)(lambda^-1 - lambda^-7), force/area, shaped like stretch."""
        stretch = np.asarray(stretch, dtype=float)
        return self.pressure_scale * (1.0 / stretch - stretch**-7)

    def cauchy_stress(self, stretch):
        """Eq. (2): in-plane Cauchy stress sigma = mu (lambda^2 - lambda^-4), force/area."""
        stretch = np.asarray(stretch, dtype=float)
        return self.mu * (stretch**2 - stretch**-4)

    def current_thickness(self, stretch):
        """Eq. (1): t = T / lambda^2, length."""
        return self.thickness / np.asarray(stretch, dtype=float) ** 2

    def tension(self, stretch):
        """Eq. (3): membrane tension N = sigma t = mu T (1 - lambda^-6), force per unit
        current length (equal in every in-plane direction)."""
        stretch = np.asarray(stretch, dtype=float)
        return self.mu * self.thickness * (1.0 - stretch**-6)

    @property
    def limit_pressure(self) -> float:
        """Eq. (5): the largest pressure the sphere carries, p(7^(1/6)), force/area."""
        return float(self.pressure(LIMIT_STRETCH))

    def stretch(self, pressure):
        """The stretch 1 <= lambda <= 7^(1/6) of the rising branch at which eq. (4) gives
        ``pressure`` (force/area, array or scalar, 0 <= p <= p_max), by bisection to the
        resolution of doubles (p is increasing on that interval). ValueError for a pressure
        outside [0, p_max]."""
        pressure = np.asarray(pressure, dtype=float)
        limit = self.limit_pressure
        bad = ~((pressure >= 0.0) & (pressure <= limit))
        if np.any(bad):
            raise ValueError(
                f"InflatedSphere.stretch: pressure {pressure[bad].ravel()[0]!r} is outside "
                f"0 .. p_max = {limit!r} (no equilibrium on the rising branch)"
            )
        low = np.ones_like(pressure)
        high = np.full_like(pressure, LIMIT_STRETCH)
        for _ in range(_BISECTIONS):
            middle = 0.5 * (low + high)
            below = self.pressure(middle) < pressure
            low = np.where(below, middle, low)
            high = np.where(below, high, middle)
        return 0.5 * (low + high)


def effective_radius(mesh: Mesh) -> float:
    """3 V / A of a faceted octant (or any surface closed by planes through the origin):
    V the volume of the cones from the origin over its triangles, sum X1 . (X2 x X3) / 6, A
    its area. For the sphere |X| = R this is R; for the inscribed polyhedron it is smaller by a
    relative amount of order (h/R)^2 (length)."""
    X = mesh.nodes[mesh.triangles]
    normal = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    volume = np.einsum("ni,ni->", normal, X[:, 0]) / 6.0
    area = 0.5 * np.linalg.norm(normal, axis=1).sum()
    return float(3.0 * volume / area)


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
    if (not isinstance(material, dict) or material.get("model") != "neo-hookean"
            or "lmbda" in material):
        fail("[material]: the sphere benchmark needs one incompressible 'neo-hookean' material")
    pressures = [load.get("value") for load in data.get("load", [])
                 if load.get("kind") == "pressure"]
    if len(pressures) != 1 or len(data.get("load", [])) != 1:
        fail("[[load]]: the sphere benchmark needs exactly one load, a 'pressure'")
    verification = data.get("verification")
    if not isinstance(verification, dict) or not {"quick", "full"} <= set(verification):
        fail("[verification]: tables [verification.quick] and [verification.full] missing")
    sphere = InflatedSphere(float(material["mu"]), float(material["thickness"]),
                            float(generator["radius"]))
    units = mesh.get("units", {})
    return _Setup(sphere, float(pressures[0]), verification,
                  units if isinstance(units, dict) else {})


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
    model = read_case(case, overrides={"mesh": {"sphere": {"n": n}}})
    radius = setup.sphere.radius
    X = model.mesh.nodes
    results = model.solve()
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
    return _Level(n, model, mesh_size(model.mesh), effective_radius(model.mesh), factors,
                  factors * setup.pressure, np.array(stretches), np.array(scatters), tensions,
                  int(not_taut), results.final.displacement)


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
        np.argmax(np.abs(finest.tension[-1].ravel() - reference_tension))]
    steps = finest.load_factor.size
    checks = [
        Check(f"stretch lambda = mean |x| / R at p = {setup.pressure:.6g} {pressure_unit}, "
              f"n = {finest.n}", reference_stretch, _SOURCE + ", root of p(lambda) = p",
              finest.stretch[-1], tolerance["stretch"]),
        Check(f"pressure at wrinkle's stretch lambda = {finest.stretch[worst_step]:.6f}, the "
              f"worst of {steps} load steps ({pressure_unit})",
              float(sphere.pressure(finest.stretch[worst_step])), _SOURCE,
              finest.pressure[worst_step], tolerance["pressure"]),
        Check(f"RMS scatter of |x| / R over the nodes, relative to the mean, n = {finest.n}",
              0.0, "a sphere: every node at the same radius", finest.scatter[-1],
              tolerance["scatter"], relative=False),
        Check(f"membrane tension, worst element and direction, n = {finest.n}"
              + (f" ({stress_unit})" if stress_unit else ""), reference_tension,
              "eq. (3), N = mu T (1 - lambda^-6)", float(worst_tension), tolerance["tension"]),
        Check(f"elements not taut, all {steps} load steps", 0.0,
              "equibiaxial tension everywhere", float(finest.not_taut), 0.0, relative=False),
    ]
    sizes = [level.size for level in levels]
    convergence = [
        Convergence("stretch at the final pressure, relative error", sizes,
                    [stretch_error(level) for level in levels], 2.0),
        Convergence("RMS scatter of the nodal radii / mean radius", sizes,
                    [level.scatter[-1] for level in levels], 2.0),
        Convergence("membrane tension of the worst element, relative error", sizes,
                    [tension_error(level) for level in levels], 2.0),
    ]

    from wrinkle.plot import plot_convergence, plot_state_map

    length_unit = setup.units.get("length", "")
    figures = [
        _plot_pressure_stretch(sphere, setup.pressure, levels, pressure_unit, length_unit,
                               out / "pressure_stretch.png"),
        plot_state_map(finest.model, finest.final_displacement, out / "state_map.png",
                       f"Inflated neo-Hookean sphere, octant n = {finest.n}, "
                       f"p = {setup.pressure:.6g} {pressure_unit}", length_unit),
        plot_convergence(convergence, out / "convergence.png",
                         "Inflated neo-Hookean sphere: errors against mesh size h"
                         + (f" ({length_unit})" if length_unit else "")),
    ]
    text = _text(setup, levels, reference_stretch, convergence, quick)
    return Outcome(checks, figures, text, convergence)


def _pressure_unit(units: dict) -> str:
    force, length = units.get("force", ""), units.get("length", "")
    return f"{force}/{length}²" if force and length else ""


def _plot_pressure_stretch(sphere: InflatedSphere, pressure: float, levels: list[_Level],
                           pressure_unit: str, length_unit: str, path: Path) -> Path:
    """Left: eq. (4) with its limit point and the finite-element (stretch, pressure) of every
    load step on every mesh. Right: the relative pressure error at wrinkle's stretch per step
    and mesh, falling as (h/R)^2."""
    from wrinkle.plot import _pyplot

    plt = _pyplot()
    unit = f" ({pressure_unit})" if pressure_unit else ""
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.0, 4.8), layout="constrained")
    stretch = np.linspace(1.0, 2.0, 401)
    left.plot(stretch, sphere.pressure(stretch), "-", color="0.2", lw=1.5,
              label=r"closed form $p = (2\mu T/R)(\lambda^{-1} - \lambda^{-7})$")
    left.plot([LIMIT_STRETCH], [sphere.limit_pressure], "D", color="C3", ms=7,
              label=rf"limit point $\lambda = 7^{{1/6}}$ = {LIMIT_STRETCH:.4f}, "
                    f"p = {sphere.limit_pressure:.5g}")
    left.axhline(pressure, color="0.5", ls=":", lw=1.0,
                 label=f"applied pressure {pressure:.6g} (load control)")
    markers = "osv^D<>"
    for k, level in enumerate(levels):
        filled = level is levels[-1]
        left.plot(level.stretch, level.pressure, markers[k % len(markers)], color=f"C{k}",
                  ms=6, mfc=None if filled else "none",
                  label=f"wrinkle, n = {level.n} ({level.model.mesh.n_elements} elements)")
        right.semilogy(level.stretch, np.abs(level.pressure / sphere.pressure(level.stretch)
                                             - 1.0),
                       markers[k % len(markers)] + "-", color=f"C{k}", ms=5,
                       label=f"n = {level.n}, h/R = {level.size / sphere.radius:.3g}")
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
    right.set_title("Relative pressure error at wrinkle's stretch, every load step",
                    fontsize=10)
    length = f" {length_unit}" if length_unit else ""
    modulus = f" {pressure_unit}" if pressure_unit else ""
    fig.suptitle(f"Inflated neo-Hookean sphere: R = {sphere.radius:g}{length}, T = "
                 f"{sphere.thickness:g}{length}, mu = {sphere.mu:g}{modulus} (one octant, "
                 "symmetry planes)", fontsize=11)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def _text(setup: _Setup, levels: list[_Level], reference_stretch: float,
          convergence: list[Convergence], quick: bool) -> str:
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
    taut = ("all elements are taut at every step" if finest.not_taut == 0 else
            f"{finest.not_taut} element-steps are NOT taut (the exact state is taut)")
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
        f"`wrinkle.verification.sphere`; unit-tested against p = dW/dV of the sphere's strain "
        f"energy and against `wrinkle.material_response`). The pressure has its maximum "
        f"p_max = {sphere.limit_pressure:.6g} at lambda = 7^(1/6) = {LIMIT_STRETCH:.4f}; the "
        f"applied pressure is {100 * ratio:.1f} % of it, so plain load control stays on the "
        f"rising, stable branch (the limit point itself would need arc-length control, which "
        f"wrinkle does not have). The reference stretch at the applied pressure is the root of "
        f"p(lambda) = p on [1, 7^(1/6)], lambda = {reference_stretch:.12f}, found by bisection "
        f"to round-off.\n\n"
        f"wrinkle's stretch (mean of |x|/R over the nodes) on n = {finest.n} is "
        f"{finest.stretch[-1]:.6f}, {error:+.2e} relative; {taut} and the nodes lie on one sphere to an RMS scatter of {finest.scatter[-1]:.1e}. "
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
