"""Gallery benchmark 1: the paper's shear-stretch test for f = 1, 2, 5.

Roddeman et al. (1987), Part II, section 4, Figs. 6-7 (docs/method.md section 8;
``examples/paper_test.py``, whose sequence ``verification.paper_test`` this benchmark runs): the
boundary of a unit square follows x = X + gamma Y, y = (1 + v) Y (shear first, then each
stretch). The deformation is homogeneous, so the constant-strain element reproduces it on any
mesh: the top-edge forces F1, F2 must equal the homogeneous solution, computed independently
by minimising the relaxed energy at one material point (``verification.references.relax``),
to round-off, and so must the state (taut or wrinkled) at every v.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from verification.levels import mesh_level
from verification.paper_test import analytic_curves, plot_shear_stretch, shear_stretch_sequence
from verification.references.shear_stretch import homogeneous_edge_forces
from verification.report import Benchmark, Check, Convergence, Outcome
from wrinkle.case import read_case
from wrinkle.model import Model
from wrinkle.plot import plot_convergence, plot_state_map
from wrinkle.solvers import make_solver
from wrinkle.solvers.stepping import solve_step

__all__ = ["BENCHMARK", "run"]

SOURCE = "homogeneous solution (relaxed energy, Pipkin 1986)"


def _model(case: Path, f: float, n: int) -> Model:
    return mesh_level(case, {"material": {"E_L": f}}, nx=n, ny=n).model


def run(case: Path, out: Path, quick: bool) -> Outcome:
    """Every f on the case's mesh and the refined meshes; checks, figures and text."""
    settings = read_case(case).verification
    anisotropy = [float(f) for f in settings["anisotropy"]]
    shear = float(settings["shear"])
    stretches = np.linspace(0.0, 0.1, int(settings["stretches"]))
    meshes = settings["quick_meshes" if quick else "meshes"]
    tolerance = float(settings["force_tolerance"])
    solver = make_solver("newton", tolerance=1e-12, max_iterations=100)
    references = {}  # the homogeneous solution of each f, the same on every mesh
    for f in anisotropy:
        material = _model(case, f, meshes[0]).materials[0].material
        references[f] = [homogeneous_edge_forces(material, shear, v) for v in stretches]
    rows = {
        (f, n): shear_stretch_sequence(
            _model(case, f, n), f, stretches, shear, solver, references[f]
        )
        for n in meshes
        for f in anisotropy
    }
    coarse = meshes[0]
    checks = []
    for f in anisotropy:
        paper = rows[(f, coarse)]
        checks.append(
            Check(
                f"F1, F2 largest relative error over {len(paper)} stretches, f = {f:g}",
                0.0,
                SOURCE,
                max(r.relative_error for r in paper),
                tolerance,
                relative=False,
            )
        )
        checks.append(
            Check(
                f"stretches whose state differs from the homogeneous one, f = {f:g}",
                0.0,
                SOURCE,
                float(sum(r.state != r.state_analytic for r in paper)),
                0.0,
                relative=False,
            )
        )
    sizes = [1.0 / n for n in meshes]
    errors = [max(r.relative_error for f in anisotropy for r in rows[(f, n)]) for n in meshes]
    checks.append(
        Check(
            f"F1, F2 largest relative error, all f, {meshes[-1]} x {meshes[-1]} mesh",
            0.0,
            SOURCE,
            errors[-1],
            tolerance,
            relative=False,
        )
    )
    study = Convergence("F1, F2 relative error (exact on every mesh)", sizes, errors, 0.0)
    figures = [out / "shear_stretch.png", out / "state_map.png", out / "convergence.png"]
    paper_mesh = [r for f in anisotropy for r in rows[(f, coarse)]]
    plot_shear_stretch(paper_mesh, figures[0], shear, analytic_curves(paper_mesh, shear))
    f_map = anisotropy[-1]
    wrinkled = next(r.v for r in rows[(f_map, coarse)] if r.state == "wrinkled")
    model = _model(case, f_map, meshes[-1])
    X = model.mesh.nodes
    prescribed = np.column_stack([shear * X[:, 1], wrinkled * X[:, 1], 0 * X[:, 1]]).ravel()
    u = solve_step(model.discretise().at(1.0, prescribed), np.zeros(model.n_dofs), solver).u
    plot_state_map(model, u, figures[1], f"Shear-stretch test, f = {f_map:g}, v = {wrinkled:g}")
    plot_convergence([study], figures[2], "Shear-stretch test: error against mesh size")
    changes = {
        f: next((r.v for r in rows[(f, coarse)] if r.state == "taut"), np.nan) for f in anisotropy
    }
    text = (
        f"The paper's test on the paper's {coarse} x {coarse} mesh (and on "
        f"{', '.join(f'{n} x {n}' for n in meshes[1:])} meshes), f = "
        f"{', '.join(f'{f:g}' for f in anisotropy)}, shear {shear:g} then stretch v = 0 .. 0.1 "
        f"in {len(stretches) - 1} steps. The reference is the homogeneous solution from an "
        "independent minimisation of the relaxed energy at one material point "
        "(`verification.references.relax`), which shares no code with the element's wrinkling "
        "routine. The deformation is homogeneous, so the constant-strain triangle is exact on "
        "every mesh: the errors stay at round-off (the convergence plot is flat, expected "
        "order 0), and the tolerance only allows for round-off. The first taut stretch is "
        + ", ".join(f"v = {v:g} (f = {f:g})" for f, v in changes.items())
        + "; below it the sheet is wrinkled."
    )
    return Outcome(checks, figures, text, [study])


BENCHMARK = Benchmark("shear_stretch", "Shear-stretch test (Roddeman et al. 1987, Figs. 6-7)", run)
