"""Gallery benchmark: an edge cable of a prestressed membrane forms a circular arc.

A flat membrane under the isotropic prestress n (force per length) is bounded by a cable of
constant force T between two held points. Across the cable, at a point where its curvature
is 1/rho, the cable pushes on the membrane with T / rho per unit length (a string's balance
under a distributed load); the membrane pulls back with n, whatever the direction of the
cable, because an isotropic stress has the same normal traction on every line. So
T / rho = n all along: the cable is a circular arc of radius

    rho = T / n,

and a chord c between the held points sags into the membrane by
s = rho - sqrt(rho^2 - c^2 / 4). The membrane itself stays flat (every force lies in its
plane). The benchmark form-finds the case (``wrinkle.formfinding``) on each mesh and fits a
circle to each cable's found nodes by least squares (x^2 + y^2 + D x + E y + F = 0, linear
in D, E, F): the radius within 1 % (issue 21), the mid-span sag, the flat sheet.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import read_case_data
from wrinkle.plot import new_figure

__all__ = ["BENCHMARK", "fitted_circle", "run"]

SOURCE = "rho = T / n (module docstring)"


def fitted_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """The least-squares circle through the points (m, 2): centre (2,) and radius, from
    x^2 + y^2 + D x + E y + F = 0 (centre (-D/2, -E/2), radius sqrt(D^2/4 + E^2/4 - F))."""
    x, y = points.T
    A = np.stack([x, y, np.ones_like(x)], axis=1)
    D, E, F = np.linalg.lstsq(A, -(x**2 + y**2), rcond=None)[0]
    return np.array([-D / 2, -E / 2]), math.sqrt(D**2 / 4 + E**2 / 4 - F)


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Form-find the corded square on each mesh and compare its cables with the arc T / n."""
    table = read_case_data(case)
    settings = table["verification"]
    n = float(table["material"]["prestress"])
    forces = {cable["label"]: float(cable["prestress"]) for cable in table["cable"]}
    if len(set(forces.values())) != 1:
        raise ValueError(f"{case}: the benchmark takes cables of one force")
    T = next(iter(forces.values()))
    rho = T / n
    width = float(table["mesh"]["rectangle"]["width"])
    height = float(table["mesh"]["rectangle"]["height"])
    sag = rho - math.sqrt(rho**2 - width**2 / 4)
    levels = []
    for nx in settings["quick_meshes" if quick else "meshes"]:
        level = mesh_level(case, nx=nx, ny=nx)
        form = level.find_form()
        X = level.model.mesh.nodes
        radii, sags, arcs = [], [], []
        for edge_y, inwards in ((0.0, 1.0), (height, -1.0)):
            on = np.flatnonzero(np.isclose(X[:, 1], edge_y))
            on = on[np.argsort(X[on, 0])]
            points = form.nodes[on, :2]
            radii.append(fitted_circle(points)[1])
            middle = on[np.argmin(np.abs(X[on, 0] - width / 2))]
            sags.append(inwards * (form.nodes[middle, 1] - edge_y))
            arcs.append(points)
        levels.append(
            {
                "nx": nx,
                "form": form,
                "radius": radii[int(np.argmax(np.abs(np.array(radii) - rho)))],
                "sag": sags[int(np.argmax(np.abs(np.array(sags) - sag)))],
                "flat": float(np.abs(form.nodes[:, 2]).max()),
                "arcs": arcs,
            }
        )
    finest = levels[-1]
    sizes = [width / level["nx"] for level in levels]
    radius_errors = [level["radius"] / rho - 1.0 for level in levels]
    convergence = [
        Convergence("cable radius, farthest cable, relative error", sizes, radius_errors, 2.0)
    ]
    tol = float(settings["radius_tolerance"])
    checks = [
        Check("arc radius, farthest cable, finest mesh (m)", rho, SOURCE, finest["radius"], tol),
        Check("mid-span sag, farthest cable, finest mesh (m)", sag, SOURCE, finest["sag"], tol),
        Check(
            "largest out-of-plane position, finest mesh (m)",
            0.0,
            "forces in the plane",
            finest["flat"],
            1e-12,
            relative=False,
        ),
        Check(
            "order of the radius's error in h",
            2.0,
            "linear triangles",
            convergence[0].observed_order,
            0.25,
        ),
        Check.none_of(
            "meshes on which form finding did not converge",
            sum(not level["form"].converged for level in levels),
            "the [formfinding] tolerance",
        ),
    ]
    figure = out / "arcs.png"
    _plot(levels, rho, width, height, figure)
    meshes = ", ".join(f"{level['nx']}²" for level in levels)
    text = (
        f"A {width:g} m × {height:g} m membrane under the isotropic prestress n = {n:g} N/m, "
        f"held along x = 0 and x = {width:g}, its two free edges bounded by cables of force "
        f"T = {T:g} N, is form-found (`wrinkle.formfinding`). Across a cable of curvature "
        "1/ρ the balance is T/ρ = n, so each cable is a circular arc of radius ρ = T/n = "
        f"{rho:g} m through the held corners, sagging by ρ − √(ρ² − c²/4) = {sag:.6f} m at "
        f"mid-span. On the meshes {meshes} the least-squares circle through each cable's "
        f"nodes has a radius within {max(abs(e) for e in radius_errors):.1e} of T/n "
        f"({abs(radius_errors[-1]):.1e} on the finest), and the sheet stays flat."
    )
    return Outcome(checks, [figure], text, convergence)


def _plot(levels: list[dict], rho: float, width: float, height: float, path: Path) -> None:
    """The found cables of the coarsest and finest meshes with the arcs of radius T / n."""
    fig = new_figure(figsize=(5.0, 5.0), layout="constrained")
    ax = fig.subplots()
    half = math.asin(width / (2 * rho))
    angles = np.linspace(-half, half, 200)
    centre_y = math.sqrt(rho**2 - width**2 / 4)
    for edge_y, sign in ((0.0, 1.0), (height, -1.0)):
        x = width / 2 + rho * np.sin(angles)
        y = edge_y + sign * (rho * np.cos(angles) - centre_y)
        ax.plot(x, y, color="k", lw=1.0, label="arc T/n" if edge_y == 0 else None)
    for level, marker, colour in ((levels[0], "o", "C0"), (levels[-1], ".", "C1")):
        for k, arc in enumerate(level["arcs"]):
            label = f"{level['nx']}² mesh" if k == 0 else None
            ax.plot(*arc.T, marker, color=colour, ms=3, label=label)
    ax.plot([0, 0], [0, height], color="0.5", lw=3)
    ax.plot([width, width], [0, height], color="0.5", lw=3, label="held edges")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("Edge cables: circular arcs of radius T/n", fontsize=10)
    ax.legend(fontsize=8, loc="center")
    ax.grid(True, alpha=0.3)
    fig.savefig(path, dpi=150)


BENCHMARK = Benchmark("cable_arc", "Edge cables: arcs of radius T/n", run)
