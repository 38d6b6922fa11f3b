"""Gallery benchmark: the catenoid, the form of an isotropic prestress between two rings.

An open tube of radius R and length h (``cylinder`` with n_cap = 0) is held at its two end
circles and form-found (``wrinkle.formfinding``, the updated reference strategy) under the
isotropic prestress n. The form is the catenoid r(x) = r_0 cosh((x - h/2) / r_0) with
h / 2 = r_0 arccosh(R / r_0) (``verification.references.catenoid``, where the closed form
is derived). The benchmark form-finds the case on each mesh of [verification] and checks,
on the finest, the neck radius within 0.1 % (issue 21) and every node's radius against the
profile, and on all of them the neck's error falling at second order with the element size.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.references.catenoid import neck_radius, profile
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import read_case_data
from wrinkle.formfinding import FormFinding
from wrinkle.plot import new_figure

__all__ = ["BENCHMARK", "run"]

SOURCE = "h/2 = r0 arccosh(R/r0) (verification.references.catenoid)"


def _axial_divisions(n_circumferential: int) -> int:
    """n_axial: about n_circumferential / 3, even, so that a ring of nodes lies at the neck."""
    return max(2, 2 * round(n_circumferential / 6))


def _radii(form: FormFinding) -> tuple[np.ndarray, np.ndarray]:
    """The found nodes' axial positions x and distances from the axis, (n_nodes,) each."""
    x, y, z = form.nodes.T
    return x, np.hypot(y, z)


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Form-find the tube on each mesh and compare with the catenoid."""
    table = read_case_data(case)
    settings = table["verification"]
    tube = table["mesh"]["cylinder"]
    R, h = float(tube["radius"]), float(tube["length"])
    r0 = neck_radius(R, h)
    levels = []
    for n in settings["quick_meshes" if quick else "meshes"]:
        level = mesh_level(case, n_circumferential=n, n_axial=_axial_divisions(n), n_cap=0)
        form = level.find_form()
        x, radius = _radii(form)
        neck = np.isclose(level.model.mesh.nodes[:, 0], h / 2)
        levels.append(
            {
                "n": n,
                "elements": level.model.mesh.n_elements,
                "form": form,
                "neck": float(radius[neck].mean()),
                "profile": float(np.abs(radius - profile(x, R, h)).max() / r0),
            }
        )
    finest = levels[-1]
    sizes = [2 * math.pi * R / level["n"] for level in levels]
    neck_errors = [level["neck"] / r0 - 1.0 for level in levels]
    convergence = [
        Convergence("neck radius, relative error", sizes, neck_errors, 2.0),
        Convergence(
            "largest radial error of the nodes / r0", sizes, [lv["profile"] for lv in levels], 2.0
        ),
    ]
    order = convergence[0].observed_order
    checks = [
        Check(
            "neck radius r0, finest mesh (m)",
            r0,
            SOURCE,
            finest["neck"],
            float(settings["neck_tolerance"]),
        ),
        Check(
            "largest radial error of the nodes / r0, finest mesh",
            0.0,
            "r0 cosh((x - h/2)/r0)",
            finest["profile"],
            float(settings["profile_tolerance"]),
            relative=False,
        ),
        Check("order of the neck's error in h", 2.0, "linear triangles", order, 0.25),
        Check.none_of(
            "meshes on which form finding did not converge",
            sum(not level["form"].converged for level in levels),
            "the [formfinding] tolerance",
        ),
    ]
    figure = out / "profile.png"
    _plot(levels, R, h, r0, figure)
    meshes = ", ".join(f"{lv['n']} ({lv['elements']:,} elements)" for lv in levels)
    iterations = ", ".join(str(level["form"].iterations) for level in levels)
    text = (
        f"An open tube of radius R = {R:g} m and length h = {h:g} m, held at its two end "
        f"circles, is form-found under the isotropic prestress n = "
        f"{float(table['material']['prestress']):g} N/m (updated reference strategy, "
        "`wrinkle.formfinding`). Its form is the catenoid r(x) = r₀ cosh((x − h/2)/r₀), a "
        "surface of zero mean curvature, with the neck radius r₀ from h/2 = r₀ arccosh(R/r₀): "
        f"r₀ = {r0:.6f} m. Meshes: {meshes} around × about a third as many along; the form "
        f"was found in {iterations} iterations. The neck's error is {abs(neck_errors[-1]):.1e} "
        f"on the finest mesh and falls at order {order:.2f} in the element size; the "
        "inscribed polygons of the rings and of every circle of nodes make the discrete form "
        "a little narrower than the catenoid."
    )
    return Outcome(checks, [figure], text, convergence)


def _plot(levels: list[dict], R: float, h: float, r0: float, path: Path) -> None:
    """The found radii against x on the coarsest and finest meshes, with the catenoid, and
    the neck's error against the element size."""
    fig = new_figure(figsize=(9.0, 3.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    dense = np.linspace(0.0, h, 200)
    left.plot(dense, profile(dense, R, h), color="k", lw=1.0, label="catenoid")
    for level, marker in ((levels[0], "o"), (levels[-1], ".")):
        x, radius = _radii(level["form"])
        left.plot(x, radius, marker, ms=3, alpha=0.6, label=f"{level['n']} around")
    left.set_xlabel("x (m)")
    left.set_ylabel("distance from the axis (m)")
    left.set_title("Found form against r0 cosh((x - h/2)/r0)", fontsize=10)
    left.legend(fontsize=8)
    left.grid(True, alpha=0.3)
    sizes = np.array([2 * math.pi * R / level["n"] for level in levels])
    errors = np.array([abs(level["neck"] / r0 - 1.0) for level in levels])
    right.loglog(sizes, errors, "o-", label="neck radius")
    right.loglog(sizes, errors[-1] * (sizes / sizes[-1]) ** 2, "k:", label="slope 2")
    right.set_xlabel("element size 2πR / n (m)")
    right.set_ylabel("relative error of r0")
    right.set_title("Neck radius: second order", fontsize=10)
    right.legend(fontsize=8)
    right.grid(True, which="both", alpha=0.3)
    fig.savefig(path, dpi=150)


BENCHMARK = Benchmark("catenoid", "Catenoid: the form of an isotropic prestress", run)
