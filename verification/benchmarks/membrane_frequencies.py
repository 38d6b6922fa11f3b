"""Gallery benchmark: natural frequencies of prestressed rectangular and circular membranes.

A flat membrane under the uniform isotropic prestress n (force per length), mass rho t per
unit area, held along its edges. A small transverse deflection w(x, y, t) changes the
membrane's strains only at second order, so only the prestress resists it, and its balance
is the wave equation n (w_xx + w_yy) = rho t w_tt with w = 0 on the edge (the in-plane
motions, resisted by E t >> n, are far higher).

Rectangle a x b: separation, w = sin(m pi x / a) sin(k pi y / b) sin(omega t), gives
omega^2 = (n / (rho t)) pi^2 ((m/a)^2 + (k/b)^2), so

    f_mk = 1/2 sqrt(n / (rho t)) sqrt((m/a)^2 + (k/b)^2),    m, k = 1, 2, ...

Disk of radius R: in polar coordinates w = J_j(z r / R) cos(j theta) sin(omega t), and
w(R) = 0 makes z a zero of the Bessel function J_j:

    f = z_jk / (2 pi R) sqrt(n / (rho t)),    each j >= 1 twice (cos and sin).

The benchmark computes the lowest modes of the prestressed state (``wrinkle.modes``: the
tangent with the prestress's geometric stiffness, shift-invert Lanczos) with the consistent
and the lumped mass on each rectangle mesh, checks the lowest within 0.5 % on the finest
(issue 21) and the errors falling at second order, and the disk's against the Bessel zeros.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.special import jn_zeros

from verification.levels import mesh_level
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import Case, read_case_data
from wrinkle.modes import Modes, natural_modes
from wrinkle.plot import new_figure

__all__ = ["BENCHMARK", "disk_frequencies", "rectangle_frequencies", "run"]

SOURCE = "f_mk = ½ √(n/ρt) √((m/a)² + (k/b)²)"
BESSEL = "z_jk / (2πR) √(n/ρt), zeros of J_j"
MASSES = ("consistent", "lumped")


def wave_speed(material: dict) -> float:
    """sqrt(n / (rho t)) (length / time) of the case's [material] table."""
    return math.sqrt(
        float(material["prestress"]) / (float(material["density"]) * float(material["thickness"]))
    )


def rectangle_frequencies(a: float, b: float, speed: float, count: int) -> np.ndarray:
    """The ``count`` lowest f_mk (1/time), ascending (module docstring)."""
    terms = math.ceil(count * max(a, b) / min(a, b)) + count
    m, k = np.meshgrid(np.arange(1, terms + 1), np.arange(1, terms + 1))
    return np.sort(0.5 * speed * np.hypot(m / a, k / b).ravel())[:count]


def disk_frequencies(radius: float, speed: float, count: int) -> np.ndarray:
    """The ``count`` lowest z_jk / (2 pi R) * speed (1/time), ascending, j >= 1 twice."""
    zeros = [z for j in range(count + 1) for z in jn_zeros(j, count) for _ in range(1 + (j > 0))]
    return np.sort(zeros)[:count] * speed / (2 * math.pi * radius)


def _modes(case: Case, count: int, mass: str) -> Modes:
    """The lowest ``count`` modes of the case's prestressed, unloaded state."""
    return natural_modes(case.model, np.zeros(case.model.n_dofs), count, mass=mass)


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """The rectangle's frequencies on each mesh and both masses; the disk's on its case."""
    table = read_case_data(case)
    settings = table["verification"]
    count = int(settings["count"])
    a, b = (float(table["mesh"]["rectangle"][key]) for key in ("width", "height"))
    reference = rectangle_frequencies(a, b, wave_speed(table["material"]), count)
    meshes = settings["quick_meshes" if quick else "meshes"]
    found = {mass: [] for mass in MASSES}
    for nx in meshes:
        level = mesh_level(case, nx=nx, ny=round(b / a * nx))
        for mass in MASSES:
            found[mass].append(_modes(level, count, mass).frequencies)
    errors = {mass: np.array(found[mass]) / reference - 1.0 for mass in MASSES}
    disk_case = case.parent / settings["disk_case"]
    disk_table = read_case_data(disk_case)
    radius = float(disk_table["mesh"]["disk"]["outer_radius"])
    disk_reference = disk_frequencies(radius, wave_speed(disk_table["material"]), count)
    disk_meshes = settings["quick_disk_meshes" if quick else "disk_meshes"]
    disk_found = [
        _modes(mesh_level(disk_case, n_radial=k, n_circumferential=4 * k), count, "consistent")
        for k in disk_meshes
    ]
    disk_errors = np.array([modes.frequencies for modes in disk_found]) / disk_reference - 1.0
    disk, disk_error = disk_found[-1].frequencies, disk_errors[-1]
    sizes = [a / nx for nx in meshes]
    convergence = [
        Convergence(
            f"largest relative error of the {count} lowest, {mass} mass",
            sizes,
            np.abs(errors[mass]).max(axis=1),
            2.0,
        )
        for mass in MASSES
    ]
    convergence.append(
        Convergence(
            f"disk: largest relative error of the {count} lowest, consistent mass",
            [2 * math.pi * radius / (4 * k) for k in disk_meshes],
            np.abs(disk_errors).max(axis=1),
            2.0,
        )
    )
    tol = float(settings["frequency_tolerance"])
    checks = [
        Check(
            f"f_11 (Hz), finest mesh, {mass} mass",
            float(reference[0]),
            SOURCE,
            float(found[mass][-1][0]),
            tol,
        )
        for mass in MASSES
    ]
    for mass in MASSES:
        worst = int(np.argmax(np.abs(errors[mass][-1])))
        checks.append(
            Check(
                f"farthest of the {count} lowest (Hz), finest mesh, {mass} mass",
                float(reference[worst]),
                SOURCE,
                float(found[mass][-1][worst]),
                tol,
            )
        )
    checks += [
        Check(
            f"order of the error in h, {label}", 2.0, "linear triangles", study.observed_order, 0.25
        )
        for label, study in zip(
            ("rectangle, consistent mass", "rectangle, lumped mass", "disk, consistent mass"),
            convergence,
            strict=True,
        )
    ]
    checks.append(
        Check.none_of(
            "consistent-mass frequencies below the exact ones, all meshes",
            int(np.count_nonzero(errors["consistent"] < 0)),
            "Rayleigh-Ritz: a conforming mesh with the consistent mass bounds from above",
        )
    )
    worst = int(np.argmax(np.abs(disk_error)))
    checks += [
        Check(
            "disk f_01 (Hz)",
            float(disk_reference[0]),
            BESSEL,
            float(disk[0]),
            float(settings["disk_tolerance"]),
        ),
        Check(
            f"disk, farthest of the {count} lowest (Hz)",
            float(disk_reference[worst]),
            BESSEL,
            float(disk[worst]),
            float(settings["disk_tolerance"]),
        ),
    ]
    figure = out / "frequencies.png"
    _plot(sizes, errors, disk, disk_reference, figure)
    n = float(table["material"]["prestress"])
    text = (
        f"A {a:g} m × {b:g} m membrane (t = {float(table['material']['thickness']):g} m, "
        f"ρ = {float(table['material']['density']):g} kg/m³) under the isotropic prestress "
        f"n = {n:g} N/m, held along its edges, unloaded: its transverse vibrations obey the "
        "wave equation n ∇²w = ρt ẅ, so f_mk = ½ √(n/ρt) √((m/a)² + (k/b)²) "
        f"(f₁₁ = {reference[0]:.4f} Hz). The {count} lowest modes by `wrinkle.modes` "
        f"(shift-invert Lanczos on the prestressed tangent) on the meshes nx = "
        f"{', '.join(str(m) for m in meshes)}: with the consistent mass every frequency lies "
        f"above the exact one (a Rayleigh-Ritz bound), within "
        f"{np.abs(errors['consistent'][-1]).max():.1e} on the finest mesh; with the lumped "
        f"mass {_side(errors['lumped'])}, within {np.abs(errors['lumped'][-1]).max():.1e}; "
        "both converge at second order "
        f"({convergence[0].observed_order:.2f} and {convergence[1].observed_order:.2f}). "
        f"The disk of radius {radius:g} m ({disk_case.name}; "
        f"{', '.join(str(k) for k in disk_meshes)} rings of elements, four times as many "
        f"sectors) matches the Bessel zeros within {np.abs(disk_error).max():.1e} on the "
        f"finest mesh, converging at order {convergence[2].observed_order:.2f}."
    )
    return Outcome(checks, [figure], text, convergence)


def _side(errors: np.ndarray) -> str:
    """Where the frequencies lie against the exact ones: "below", "above" or "on both
    sides"."""
    if np.all(errors < 0):
        return "below"
    return "above" if np.all(errors > 0) else "on both sides"


def _plot(sizes, errors: dict, disk: np.ndarray, disk_reference: np.ndarray, path: Path):
    """Each frequency's error against h for both masses; the disk's frequencies against
    the Bessel zeros."""
    fig = new_figure(figsize=(9.0, 3.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    h = np.asarray(sizes)
    for mass, style in zip(MASSES, ("-", "--"), strict=True):
        for mode in range(errors[mass].shape[1]):
            left.loglog(
                h,
                np.abs(errors[mass][:, mode]),
                style,
                marker="o",
                ms=3,
                color=f"C{mode}",
                label=f"mode {mode + 1}" if mass == "consistent" else None,
            )
    worst = np.abs(errors["consistent"][-1]).max()
    left.loglog(h, worst * (h / h[-1]) ** 2, "k:", label="slope 2")
    left.set_xlabel("element size a / nx (m)")
    left.set_ylabel("|relative error|")
    left.set_title("Rectangle: consistent (—) and lumped (--) mass", fontsize=10)
    left.legend(fontsize=7)
    left.grid(True, which="both", alpha=0.3)
    index = np.arange(1, disk.size + 1)
    right.plot(index, disk_reference, "k_", ms=14, mew=1.5, label="Bessel zeros")
    right.plot(index, disk, "o", color="C3", ms=4, label="wrinkle")
    right.set_xlabel("mode")
    right.set_ylabel("frequency (Hz)")
    right.set_title("Disk: z_jk / (2πR) √(n/ρt)", fontsize=10)
    right.legend(fontsize=8)
    right.grid(True, alpha=0.3)
    fig.savefig(path, dpi=150)


BENCHMARK = Benchmark("membrane_frequencies", "Natural frequencies of prestressed membranes", run)
