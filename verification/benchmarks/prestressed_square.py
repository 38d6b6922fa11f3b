"""Gallery benchmark: a prestressed square wrinkles where its load cancels the prestress.

A square sheet of isotropic St Venant-Kirchhoff material (E, nu, thickness t) carries the
prestress N0 = n I (issue 21). The edge x = 0 is held in x, the edge x = L moves by -d in x,
the edges y = 0 and y = L are held in y and slide in x, every edge is held in z. The
homogeneous state F = diag(lambda, 1), lambda = 1 - d/L, meets every support with zero shear
on the sliding edges, so it is the solution while taut. With k = E t/(1 - nu^2),
E_xx = (lambda^2 - 1)/2, E_yy = 0:

    N_xx = n + k E_xx,        N_yy = n + k nu E_xx.

N_xx vanishes, with N_yy = n (1 - nu) > 0, at E_xx = -n/k: the sheet turns from taut to
wrinkled at the shortening

    d_c = L (1 - sqrt(1 - 2 n (1 - nu^2)/(E t))),

and past it carries the tension field N_xx = 0, N_yy = n (1 - nu) (the relaxed E_xx stays at
-n/k). The benchmark finds the finite-element onset by bisection on d (every element taut
below, wrinkled above; where the states are mixed, N_xx is zero to the solution's round-off
and that shortening is the onset), checks it against d_c within 0.5 % (issue 21's gallery
check), and
checks the stresses at zero load (N = n I), just below and past the onset.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.report import Benchmark, Check, Outcome
from wrinkle.case import read_case_data
from wrinkle.model import Model
from wrinkle.plot import new_figure
from wrinkle.post import element_report
from wrinkle.wrinkling import TAUT, WRINKLED

__all__ = ["BENCHMARK", "onset_shortening", "run"]

SOURCE = "closed form (module docstring)"


def onset_shortening(E: float, nu: float, thickness: float, n: float, length: float) -> float:
    """d_c = L (1 - sqrt(1 - 2 n (1 - nu^2)/(E t))), length unit of L: the shortening at
    which N_xx = n + k E_xx vanishes (module docstring)."""
    return float(length * (1.0 - np.sqrt(1.0 - 2.0 * n * (1.0 - nu**2) / (E * thickness))))


def _farthest(values: np.ndarray, reference: float) -> float:
    """The entry of ``values`` farthest from ``reference``."""
    values = np.ravel(values)
    return float(values[np.argmax(np.abs(values - reference))])


def _solve(model: Model, right: np.ndarray, shortening: float):
    """Element report of ``model`` with the edge x = L moved by -shortening."""
    model.set_prescribed(right, [-shortening, np.nan, np.nan])
    return element_report(model, model.solve().final.displacement)


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Bisect the onset of wrinkling on each mesh and compare with the closed form."""
    table = read_case_data(case)
    settings = table["verification"]
    material = table["material"]
    E, nu, t, n = (float(material[key]) for key in ("E", "nu", "thickness", "prestress"))
    width = float(table["mesh"]["rectangle"]["width"])
    k = E * t / (1.0 - nu**2)
    critical = onset_shortening(E, nu, t, n, width)
    meshes = settings["quick_meshes" if quick else "meshes"]
    onsets = []
    for nx in meshes:
        model = mesh_level(case, nx=nx, ny=nx).model
        right = np.flatnonzero(np.isclose(model.mesh.nodes[:, 0], width))
        low, high = 0.4 * critical, 1.3 * critical  # d_c is no midpoint
        for _ in range(int(settings["bisections"])):
            middle = 0.5 * (low + high)
            states = _solve(model, right, middle).state
            if np.all(states == TAUT):
                low = middle
            elif np.all(states == WRINKLED):
                high = middle
            else:  # mixed: N_xx is at the round-off of the solution, this is the onset
                low = high = middle
                break
        onsets.append(0.5 * (low + high))
    zero = element_report(model, np.zeros(model.n_dofs))
    below = _solve(model, right, 0.995 * critical)
    past = _solve(model, right, 1.5 * critical)
    stretch = 1.0 - 0.995 * critical / width
    strain = 0.5 * (stretch**2 - 1.0)
    tol, tol_onset = float(settings["stress_tolerance"]), float(settings["onset_tolerance"])
    worst_onset = onsets[int(np.argmax(np.abs(np.array(onsets) / critical - 1.0)))]
    checks = [
        Check(
            "onset shortening, farthest mesh (mm)",
            1e3 * critical,
            SOURCE,
            1e3 * worst_onset,
            tol_onset,
        ),
        Check(
            "N_xx and N_yy at zero load, farthest element (N/m)",
            n,
            "the prestress",
            _farthest(zero.stress[:, [0, 1], [0, 1]], n),
            tol,
        ),
        Check(
            "elements taut at 0.995 d_c",
            float(model.mesh.n_elements),
            SOURCE,
            float(np.count_nonzero(below.state == TAUT)),
            0.0,
            relative=False,
        ),
        Check(
            "N_xx at 0.995 d_c, mean (N/m)",
            n + k * strain,
            SOURCE,
            float(below.stress[:, 0, 0].mean()),
            1e-6,
        ),
        Check(
            "elements wrinkled at 1.5 d_c",
            float(model.mesh.n_elements),
            SOURCE,
            float(np.count_nonzero(past.state == WRINKLED)),
            0.0,
            relative=False,
        ),
        Check(
            "N_yy past the onset, farthest element (N/m)",
            n * (1.0 - nu),
            SOURCE,
            _farthest(past.stress[:, 1, 1], n * (1.0 - nu)),
            tol,
        ),
        Check(
            "|N_xx| past the onset, largest (N/m)",
            0.0,
            SOURCE,
            float(np.abs(past.stress[:, 0, 0]).max()),
            tol * n,
            relative=False,
        ),
    ]
    figure = out / "stresses.png"
    _plot(model, right, n, nu, k, width, critical, figure)
    text = (
        f"A {width:g} m square sheet (E = {E:g} N/m², ν = {nu:g}, t = {t:g} m) prestressed to "
        f"n = {n:g} N/m in every direction, shortened along x with the edges y = 0 and y = "
        f"{width:g} held in y (sliding in x) and every edge held in z. Taut, N_xx = n + k E_xx "
        "and N_yy = n + kν E_xx with k = Et/(1 − ν²), E_yy = 0; N_xx reaches zero, and the "
        f"sheet wrinkles, at the shortening d_c = L(1 − √(1 − 2n(1 − ν²)/(Et))) = "
        f"{1e3 * critical:.6f} mm. The onset found by bisection ({settings['bisections']} "
        "halvings of [0.4, 1.3] d_c, every element taut below and wrinkled above) on the "
        f"meshes nx = {', '.join(str(m) for m in meshes)} is within "
        f"{max(abs(o / critical - 1) for o in onsets):.1e} of d_c (the bracket's half-width "
        f"is {0.45 / 2 ** int(settings['bisections']):.1e} d_c). At zero load N = n I, and past "
        "the onset the tension field N_xx = 0, N_yy = n(1 − ν)."
    )
    return Outcome(checks, [figure], text)


def _plot(model, right, n, nu, k, width, critical, path: Path) -> None:
    """Mean N_xx and N_yy of the elements against the shortening, with the closed form."""
    shortenings = np.linspace(0.0, 2.0 * critical, 17)
    means = np.array(
        [_solve(model, right, d).stress.mean(axis=0)[[0, 1], [0, 1]] for d in shortenings]
    )
    dense = np.linspace(0.0, 2.0 * critical, 400)
    strain = 0.5 * ((1.0 - dense / width) ** 2 - 1.0)
    wrinkled = dense > critical
    closed_xx = np.where(wrinkled, 0.0, n + k * strain)
    closed_yy = np.where(wrinkled, n * (1.0 - nu), n + k * nu * strain)
    fig = new_figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.subplots()
    ax.plot(1e3 * dense, closed_xx, color="C0", lw=1.0, label="N_xx, closed form")
    ax.plot(1e3 * dense, closed_yy, color="C1", lw=1.0, label="N_yy, closed form")
    ax.plot(1e3 * shortenings, means[:, 0], "o", color="C0", ms=4, label="N_xx, elements")
    ax.plot(1e3 * shortenings, means[:, 1], "s", color="C1", ms=4, label="N_yy, elements")
    ax.axvline(1e3 * critical, color="0.5", ls=":", lw=1.0, label="onset d_c")
    ax.set_xlabel("shortening d (mm)")
    ax.set_ylabel("stress resultant (N/m)")
    ax.set_title("Prestressed square: taut, then wrinkled where N_xx reaches 0", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=150)


BENCHMARK = Benchmark(
    "prestressed_square", "Prestressed square: wrinkling where the load cancels the prestress", run
)
