"""The paper's test problem: a square membrane sheared, then stretched (METHOD.md section 8).

Roddeman et al. (1987), Part II, section 4 and Figs. 6-7: the square 0 <= X, Y <= L (L = 1,
thickness 1) meshed with 3 x 3 squares split in two (18 elements, 16 nodes). The 12 boundary
nodes follow x = X + gamma Y, y = (1 + v/L) Y, z = Z with gamma = 0.1 held and v/L from 0 to 0.1;
the 4 interior nodes are free and start undeformed. Material: transversely isotropic
St. Venant-Kirchhoff with E_L = f, E_T = 1, nu_LT = nu_TT = 0.3, G_LT = 1/2.6, fibre along X.
F1, F2 are the x and y sums of the reactions of the top-edge nodes (corners included).
The finite-element values are compared with the homogeneous solution computed independently by
``wrinkle.verification`` (relaxed-energy minimisation at one material point).
"""

from __future__ import annotations

import csv
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wrinkle.materials import StVenantKirchhoff
from wrinkle.mesh import rectangle
from wrinkle.model import Model
from wrinkle.solvers import make_solver
from wrinkle.verification.shear_stretch import homogeneous_edge_forces
from wrinkle.wrinkling import STATE_NAMES

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
    model: Model, f: float, stretches=STRETCHES, shear: float = SHEAR, solver=None,
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
    material = model.groups[0][1].material.material
    if references is None:
        references = [homogeneous_edge_forces(material, shear, v) for v in stretches]
    rows = []
    u = np.zeros(model.n_dofs)
    for v, (F1_ref, F2_ref, reference) in zip(stretches, references):
        homogeneous = np.column_stack([shear * X[:, 1], v * X[:, 1], np.zeros(mesh.n_nodes)])
        u, solved = model.solve_step(u, 1.0, solver, prescribed=homogeneous.ravel())
        internal = model.internal_forces(u).reshape(-1, 3)
        F1, F2 = internal[top, 0].sum(), internal[top, 1].sum()
        states = np.unique(model.evaluate_elements(u, stiffness=False).response.state)
        state = STATE_NAMES[states[0]] if states.size == 1 else "mixed"
        error = np.abs(u.reshape(-1, 3)[interior] - homogeneous[interior]).max(initial=0.0)
        rows.append(
            ShearStretchRow(
                float(f), float(v), float(F1), float(F2), F1_ref, F2_ref, state,
                reference.state, solved.iterations, float(error),
            )
        )
        logger.info(
            "f = %g, v = %.3f: F1 = %.10f, F2 = %.10f (%s, %d iterations)",
            f, v, F1, F2, state, solved.iterations,
        )
    return rows


def shear_stretch(
    anisotropy=ANISOTROPY,
    stretches=STRETCHES,
    shear: float = SHEAR,
    method: str = "newton",
    tolerance: float = 1e-12,
) -> list[ShearStretchRow]:
    """Run the test for every f in ``anisotropy`` on the paper's 3 x 3 mesh and return one row
    per (f, v)."""
    mesh = rectangle(1.0, 1.0, 3, 3)
    boundary = np.unique(np.concatenate([mesh.node_sets[s] for s in ("left", "right", "bottom", "top")]))
    solver = make_solver(method, tolerance=tolerance, max_iterations=100)
    rows = []
    for f in anisotropy:
        model = Model(mesh, paper_material(f), fibre_direction=(1.0, 0.0, 0.0))
        model.prescribe(boundary, np.zeros(3))
        rows += shear_stretch_sequence(model, f, stretches, shear, solver)
    return rows


def write_csv(rows: list[ShearStretchRow], path: Path) -> None:
    """Write the rows as CSV with columns f, v, F1, F2, state, iterations and the references."""
    fields = [
        "f", "v", "F1", "F2", "state", "iterations", "F1_analytic", "F2_analytic",
        "state_analytic", "relative_error", "interior_error",
    ]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(fields)
        for r in rows:
            writer.writerow(
                [r.f, r.v, f"{r.F1:.15g}", f"{r.F2:.15g}", r.state, r.iterations,
                 f"{r.F1_analytic:.15g}", f"{r.F2_analytic:.15g}", r.state_analytic,
                 f"{r.relative_error:.3e}", f"{r.interior_error:.3e}"]
            )


def run_demo(out: Path, method: str = "newton") -> list[ShearStretchRow]:
    """Run the test and write ``out/shear_stretch.csv`` and ``out/shear_stretch.png``."""
    from wrinkle.plot import plot_shear_stretch

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = shear_stretch(method=method)
    write_csv(rows, out / "shear_stretch.csv")
    plot_shear_stretch(rows, out / "shear_stretch.png", shear=SHEAR)
    return rows
