"""Gallery benchmark 2: simple shear of a membrane at small strain.

Mansfield (The Bending and Stretching of Plates, 2nd ed. 1989, ch. 9) and Wong & Pellegrino
(J. Mech. Mater. Struct. 1, 2006, 3-25): every edge of a sheet follows x = X + gamma Y, y = Y,
and the whole sheet wrinkles with the uniaxial tension N1 = E t gamma / 2 at 45 degrees. The
closed form and the exact finite-strain homogeneous solution, with the derivation, are in
``verification.references.simple_shear``; this module solves the case file on each mesh of its
[verification] table and compares.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.references.simple_shear import exact_homogeneous, tension_field
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import read_case, read_case_data
from wrinkle.plot import new_figure, plot_convergence, plot_state_map
from wrinkle.post import element_report
from wrinkle.wrinkling import WRINKLED

__all__ = ["BENCHMARK", "run"]

SOURCE = "Mansfield 1989; Wong & Pellegrino 2006"


def _solve(case: Path, nx: int):
    level = mesh_level(case, nx=nx, ny=max(nx // 2, 1))
    u = level.solve().final.displacement
    return level.model, u


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Solve the sheared rectangle on each mesh and compare with the tension-field solution."""
    own = read_case(case)
    settings = own.verification
    gamma = float(settings["shear"])
    material = own.model.materials[0].material
    table = read_case_data(case)["material"]
    E, thickness = float(table["E"]), float(table["thickness"])
    closed = tension_field(E, thickness, gamma)
    exact = exact_homogeneous(material, gamma)
    meshes = settings["quick_meshes" if quick else "meshes"]
    errors, sizes = [], []
    for nx in meshes:
        model, u = _solve(case, nx)
        report = element_report(model, u)
        N1 = report.principal_stress[:, 1]
        errors.append(float(np.abs(N1 / exact["N1"] - 1.0).max()))
        sizes.append(1.0 / nx)
    width = float(np.ptp(model.mesh.nodes[:, 0]))
    top = model.mesh.node_sets["top"]
    reactions = model.discretise().reactions(u, 1.0).reshape(-1, 3)
    N_xy = float(reactions[top, 0].sum()) / width
    t = report.tension_direction
    angle = np.degrees(np.arctan2(t[:, 1], t[:, 0])) % 180.0
    not_wrinkled = int(np.count_nonzero(report.state != WRINKLED))
    tol, tol_angle = float(settings["stress_tolerance"]), float(settings["angle_tolerance"])
    checks = [
        Check("N1, smallest element (N/m)", closed["N1"], SOURCE, float(N1.min()), tol),
        Check("N1, largest element (N/m)", closed["N1"], SOURCE, float(N1.max()), tol),
        Check("N_xy from the top-edge reaction (N/m)", closed["N_xy"], SOURCE, N_xy, tol),
        Check(
            "tension angle, farthest element from 45 (deg)",
            closed["angle"],
            SOURCE,
            float(angle[np.argmax(np.abs(angle - 45.0))]),
            tol_angle,
            relative=False,
        ),
        Check("elements not wrinkled", 0.0, SOURCE, float(not_wrinkled), 0.0, relative=False),
        Check(
            "N1 against the exact homogeneous solution, largest relative error",
            0.0,
            "relaxed energy (finite strain)",
            errors[-1],
            float(settings["exact_tolerance"]),
            relative=False,
        ),
    ]
    study = Convergence(
        "N1 relative error against the exact homogeneous solution", sizes, errors, 0.0
    )
    figures = [out / "stress_profile.png", out / "state_map.png", out / "convergence.png"]
    _plot_profile(model, report, closed, exact, E * thickness * gamma, figures[0])
    plot_state_map(model, u, figures[1], f"Simple shear, gamma = {gamma:g}", "m")
    plot_convergence([study], figures[2], "Simple shear: error against mesh size")
    text = (
        f"A {width:g} m x {np.ptp(model.mesh.nodes[:, 1]):g} m sheet (E = {E:g} N/m², "
        f"t = {thickness:g} m, ν = 0.3) with every edge node on x = X + γY, γ = {gamma:g}, "
        "held in its plane. Small-strain tension-field theory: the minor principal stress of "
        "the taut solution, -Etγ/(2(1+ν)), is compressive, so the whole sheet wrinkles and "
        "carries uniaxial tension N1 = Etγ/2 at 45°, with N_xx = N_yy = N_xy = Etγ/4. The "
        "finite-element solution is homogeneous (every element wrinkled, the same stress) "
        "and equals the exact finite-strain homogeneous solution, computed independently "
        f"from the relaxed energy, to {errors[-1]:.1e} on every mesh (flat convergence plot, "
        f"expected order 0). That solution has N1 = {exact['N1']:.6g} N/m, "
        f"{exact['N1'] / closed['N1'] - 1:.2e} above the small-strain formula (about 1.5γ), "
        f"and its tension at {exact['angle']:.4f}°: the tolerances (2γ relative, 0.05°) are "
        "set just above this difference of the two theories, not from the finite elements."
    )
    return Outcome(checks, figures, text, [study])


def _plot_profile(model, report, closed: dict, exact: dict, scale: float, path: Path) -> None:
    """N1, N_xx, N_yy, N_xy of every element (over its centroid's x) against the closed form
    and the exact homogeneous solution, all divided by E t gamma."""
    centroid_x = model.mesh.nodes[model.mesh.triangles, 0].mean(axis=1)
    N1 = report.principal_stress[:, 1]
    t = report.tension_direction
    components = {
        "N1": N1,
        "N_xx": N1 * t[:, 0] ** 2,
        "N_yy": N1 * t[:, 1] ** 2,
        "N_xy": N1 * t[:, 0] * t[:, 1],
    }
    closed_values = {
        "N1": closed["N1"],
        "N_xx": closed["N_xy"],
        "N_yy": closed["N_xy"],
        "N_xy": closed["N_xy"],
    }
    fig = new_figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.subplots()
    for (name, values), marker in zip(components.items(), "os^v"):
        line = ax.plot(
            centroid_x, values / scale, marker, ms=4, ls="none", label=f"{name}, elements"
        )[0]
        ax.axhline(closed_values[name] / scale, color=line.get_color(), lw=1.0)
    ax.axhline(
        exact["N1"] / scale, color="0.3", ls=":", lw=1.0, label="N1, exact finite-strain solution"
    )
    ax.plot([], [], color="0.3", lw=1.0, label="closed form (lines)")
    ax.set_xlabel("element centroid x (m)")
    ax.set_ylabel(r"stress resultant / $E t \gamma$")
    ax.set_title(
        "Simple shear: element stresses against the tension-field solution\n"
        "N1 = Etγ/2, N_xx = N_yy = N_xy = Etγ/4",
        fontsize=10,
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="center right")
    fig.savefig(path, dpi=150)


BENCHMARK = Benchmark(
    "simple_shear", "Simple shear at small strain (Mansfield; Wong & Pellegrino 2006)", run
)
