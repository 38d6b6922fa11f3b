"""The paper's test problem: a square membrane sheared, then stretched (docs/method.md section 8).

Roddeman et al. (1987), Part II, section 4 and Figs. 6-7: the square 0 <= X, Y <= L (L = 1,
thickness 1) meshed with 3 x 3 squares split in two (18 elements, 16 nodes). The 12 boundary
nodes follow x = X + gamma Y, y = (1 + v/L) Y, z = Z with gamma = 0.1 held and v/L from 0 to 0.1;
the 4 interior nodes are free and start undeformed. Material: transversely isotropic
St. Venant-Kirchhoff with E_L = f, E_T = 1, nu_LT = nu_TT = 0.3, G_LT = 1/2.6, fibre along X.
F1, F2 are the x and y sums of the reactions of the top-edge nodes (corners included).
The finite-element values are compared with the homogeneous solution computed independently by
``verification.references.shear_stretch`` (relaxed-energy minimisation at one material point).

This module holds the sequence itself, shared by the paper's test (``examples/paper_test.py``,
on the paper's mesh) and the gallery's benchmark (``verification.benchmarks.shear_stretch``,
on refined meshes too), and the figure of both.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from verification.references.shear_stretch import (
    ShearStretchCurves,
    homogeneous_edge_forces,
    shear_stretch_curves,
)
from wrinkle.materials import StVenantKirchhoff
from wrinkle.model import Model
from wrinkle.plot import colour_cycle, new_figure
from wrinkle.solvers import make_solver
from wrinkle.solvers.stepping import solve_step
from wrinkle.wrinkling import STATE_NAMES

__all__ = [
    "ANISOTROPY",
    "SHEAR",
    "STRETCHES",
    "ShearStretchRow",
    "analytic_curves",
    "paper_material",
    "plot_shear_stretch",
    "shear_stretch_sequence",
]

logger = logging.getLogger("wrinkle")

ANISOTROPY = (1.0, 2.0, 5.0)
SHEAR = 0.1
STRETCHES = tuple(np.round(np.arange(21) * 0.005, 10))


def paper_material(f: float) -> StVenantKirchhoff:
    """Transversely isotropic law of the paper's test with anisotropy f (f = 1 isotropic)."""
    return StVenantKirchhoff.transversely_isotropic(
        E_L=f, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=1.0
    )


@dataclass
class ShearStretchRow:
    """One (f, v) point: finite-element and analytic edge forces, state, solver effort."""

    f: float
    v: float
    F1: float
    F2: float
    F1_analytic: float
    F2_analytic: float
    state: str
    state_analytic: str
    iterations: int
    interior_error: float  # max |x - x_homogeneous| of the free nodes (length)

    @property
    def relative_error(self) -> float:
        scale = np.hypot(self.F1_analytic, self.F2_analytic)
        return max(abs(self.F1 - self.F1_analytic), abs(self.F2 - self.F2_analytic)) / scale


def shear_stretch_sequence(
    model: Model,
    f: float,
    stretches=STRETCHES,
    shear: float = SHEAR,
    solver=None,
    references=None,
) -> list[ShearStretchRow]:
    """The paper's sequence on ``model`` (a unit square whose boundary nodes, and only they,
    are constrained; one material): shear first, then each stretch v started from the
    previous solution. One row per v, compared with the homogeneous solution: ``references``,
    the (F1, F2, RelaxedState) of each v from ``homogeneous_edge_forces``, computed if None."""
    mesh = model.mesh
    X = mesh.nodes
    top = mesh.node_sets["top"]
    interior = np.flatnonzero(~model.constrained.reshape(-1, 3).any(axis=1))
    solver = solver or make_solver("newton", tolerance=1e-12, max_iterations=100)
    system = model.discretise()
    material = system.groups[0][1].material.material
    if references is None:
        references = [homogeneous_edge_forces(material, shear, v) for v in stretches]
    rows = []
    u = np.zeros(model.n_dofs)
    for v, (F1_ref, F2_ref, reference) in zip(stretches, references):
        homogeneous = np.column_stack([shear * X[:, 1], v * X[:, 1], np.zeros(mesh.n_nodes)])
        solved = solve_step(system.at(1.0, homogeneous.ravel()), u, solver)
        u = solved.u
        internal = system.internal_forces(u).reshape(-1, 3)
        F1, F2 = internal[top, 0].sum(), internal[top, 1].sum()
        states = np.unique(system.evaluate_elements(u, stiffness=False).response.state)
        state = STATE_NAMES[states[0]] if states.size == 1 else "mixed"
        error = np.abs(u.reshape(-1, 3)[interior] - homogeneous[interior]).max(initial=0.0)
        rows.append(
            ShearStretchRow(
                float(f),
                float(v),
                float(F1),
                float(F2),
                F1_ref,
                F2_ref,
                state,
                reference.state,
                solved.iterations,
                float(error),
            )
        )
        logger.info(
            "f = %g, v = %.3f: F1 = %.10f, F2 = %.10f (%s, %d iterations)",
            f,
            v,
            F1,
            F2,
            state,
            solved.iterations,
        )
    return rows


def analytic_curves(
    rows: Sequence[ShearStretchRow], shear: float, points: int = 81
) -> dict[float, ShearStretchCurves]:
    """The homogeneous solution of each anisotropy f of ``rows`` (with ``paper_material``)
    on ``points`` stretches spread over the rows' range of v: the lines of
    ``plot_shear_stretch``."""
    curves = {}
    for f in sorted({r.f for r in rows}):
        v = np.array([r.v for r in rows if r.f == f])
        fine = np.linspace(v.min(), v.max(), points)
        curves[f] = shear_stretch_curves(paper_material(f), shear, fine)
    return curves


def plot_shear_stretch(
    rows: Sequence[ShearStretchRow],
    path: str | os.PathLike,
    shear: float,
    curves: Mapping[float, ShearStretchCurves],
) -> Path:
    """Two panels like the paper's Figs. 6 and 7: F1(v) and F2(v) for each anisotropy f.

    Lines: the independent homogeneous solution, ``curves[f]`` (``analytic_curves``);
    markers: finite-element results (filled where the elements are wrinkled, open where
    taut); a dotted line marks the taut/wrinkled change of the homogeneous solution.
    """
    fig = new_figure(figsize=(11, 4.5), layout="constrained")
    axes = fig.subplots(1, 2)
    anisotropies = sorted({r.f for r in rows})
    for colour, f in zip(colour_cycle(), anisotropies):
        mine = [r for r in rows if r.f == f]
        v = np.array([r.v for r in mine])
        reference = curves[f]
        fine = reference.v
        change = [
            0.5 * (fine[i] + fine[i + 1])
            for i in range(fine.size - 1)
            if reference.state[i] != reference.state[i + 1]
        ]
        for ax, name, analytic in ((axes[0], "F1", reference.F1), (axes[1], "F2", reference.F2)):
            ax.plot(fine, analytic, "-", color=colour, lw=1.2, label=f"analytic, f = {f:g}")
            values = np.array([getattr(r, name) for r in mine])
            wrinkled = np.array([r.state == "wrinkled" for r in mine])
            ax.plot(
                v[wrinkled],
                values[wrinkled],
                "o",
                color=colour,
                ms=5,
                label=f"FE wrinkled, f = {f:g}",
            )
            ax.plot(
                v[~wrinkled],
                values[~wrinkled],
                "o",
                mfc="none",
                color=colour,
                ms=5,
                label=f"FE taut, f = {f:g}",
            )
            for x in change:
                ax.axvline(x, color=colour, ls=":", lw=1)
    for ax, name, what in (
        (axes[0], "F1", "along the shear (x)"),
        (axes[1], "F2", "along the stretch (y)"),
    ):
        ax.set_xlabel("stretching distance v (length units, L = 1)")
        ax.set_ylabel(f"{name}: top-edge force {what} (force units)")
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"Shear force, gamma = {shear:g} held (cf. paper Fig. 6)")
    axes[1].set_title("Stretching force (cf. paper Fig. 7)")
    axes[1].legend(fontsize=7, ncol=3, loc="upper left")
    fig.savefig(path, dpi=120)
    return Path(path)
