"""The quarter airbag of examples/airbag.toml solved by Kratos Multiphysics (run by vs_kratos.py).

Runs with the Python of a separate environment holding KratosMultiphysics,
KratosStructuralMechanicsApplication, KratosConstitutiveLawsApplication and numpy (Kratos is
never a dependency of wrinkle). Reads the problem that vs_kratos.py wrote (an .npz: wrinkle's
nodes, triangles with their orientation, held dofs, centre node, material and pressure) and
prints one JSON line: law, converged, Newton iterations, centre deflection (mm), times (s).

    python kratos_airbag.py airbag_32.npz --law wrinkling

Kratos model (units N, m, Pa):
- MembraneElement3D3N: total-Lagrangian constant-strain triangle, Green-Lagrange strain,
  thickness THICKNESS. Law WrinklingLinear2DLaw wrapping LinearElasticPlaneStress2DLaw (its one
  sub-property), or the plain LinearElasticPlaneStress2DLaw (no wrinkling, compression allowed).
  The linear plane-stress law in Green-Lagrange strain is wrinkle's St Venant-Kirchhoff with
  S33 = 0, so with wrinkling both codes discretise the same model.
- SurfaceLoadCondition3D3N with NEGATIVE_FACE_PRESSURE = p: a follower pressure along
  (x2 - x1) x (x3 - x1), with its load stiffness; wrinkle's triangles are counter-clockwise
  seen from +z, so the sheet inflates towards +z as in wrinkle.
- Held dofs exactly as wrinkle's (symmetry ux = 0 on x = 0, uy = 0 on y = 0; seam uz = 0).
- ResidualBasedNewtonRaphsonStrategy (or LineSearchStrategy with --line-search),
  ResidualBasedIncrementalUpdateStaticScheme, ResidualBasedBlockBuilderAndSolver, a direct
  sparse solver of Kratos' factory: Eigen's "sparse_lu" (LinearSolversApplication), the fastest
  the wheels offer here (n = 32: 91 ms per Newton iteration against 110 for the core's
  "skyline_lu_factorization" and 2.5 s for "sparse_qr"; no Pardiso, CHOLMOD or UMFPACK).

The flat, unstressed sheet has no out-of-plane stiffness and slack elements of the wrinkling
law have no stiffness at all, so Newton from the flat sheet meets a singular matrix (Eigen's
"THE MATRIX IS STRUCTURALLY SINGULAR"). What Kratos needs here (the defaults, tried on n = 16
and 32):
1. ramp: an isotropic PK2 prestress PRESTRESS_VECTOR = (s0, s0, 0), s0 = 1e5 Pa, in every
   membrane, and in-plane springs of 1e3 N/m (NodalConcentratedElement3D1N) on the seam nodes,
   which are free in-plane and which the prestress would otherwise pull inwards; the pressure
   rises in 2 equal steps, each solved loosely (residual down by 1e-2). In trials on n = 16,
   one step, no seam springs, or s0 = 1e4 or 1e6 Pa met a singular matrix.
2. release: prestress off, seam springs weakened to 1 N/m and anchored at the shape the ramp
   ended with, full pressure, solved to wrinkle's criterion. The springs stay: without them
   (or with 1e-2 or 0.1 N/m) the seam ends (a, 0) and (0, a), nodes of one triangle only, lose
   all stiffness when that triangle turns slack, and on n = 32 the iteration diverges. They
   bias the answer (the output gives the largest spring force left, N; the seam moves some
   100 mm inwards). With --release-steps m > 1 the springs are re-anchored at the start of
   each of m steps (a proximal-point iteration: at the end they are nearly unloaded), all but
   the last solved loosely: on n = 16 that gives the spring-free answer within 1e-4 mm, on
   n = 32 it stalls (m = 2) or diverges (m = 3) within 5,000 iterations.
3. springs of E t on every held dof: held dofs do not move, so these change no result, only
   the diagonal that Kratos' block builder keeps for a held dof (the assembled one: zero, and
   the matrix singular, when all the node's triangles are slack).
Kratos' LineSearchStrategy (--line-search) made things worse: singular matrices in the ramp and
the release. WrinklingLinear2DLaw takes the wrinkle direction from the trial stress and leaves
its change out of the tangent, so Newton converges only linearly (the residual falls by about
1.5 % per iteration on n = 16, 0.5 % on n = 32): most iterations are in the release.

Convergence of the last step: Kratos' ResidualCriteria(relative, absolute) stops when
|r| / |r0| <= relative or |r| / n_free <= absolute, r the residual on the free dofs and r0 its
value at the start of the step. Here relative = tolerance and absolute = tolerance * scale /
n_free with scale = max(|f_ext|, |reactions|) at the start of the step (f_ext: the pressure
forces on all dofs at that shape; reactions on the held dofs), so the test is
|r| <= tolerance * max(|f_ext|, |reactions|): wrinkle's criterion, with the scale frozen at the
start of the step instead of updated every iteration. Loose steps use relative only.

Kratos' OpenMP loops use OMP_NUM_THREADS threads; on a machine whose cores are busy with other
work they slow down by orders of magnitude, so vs_kratos.py sets 1 by default.
"""

from __future__ import annotations

import argparse
import json
import time

import KratosMultiphysics as KM
import KratosMultiphysics.ConstitutiveLawsApplication as CLA
import KratosMultiphysics.LinearSolversApplication  # registers sparse_lu
import KratosMultiphysics.StructuralMechanicsApplication as SMA
import numpy as np

DISPLACEMENTS = (KM.DISPLACEMENT_X, KM.DISPLACEMENT_Y, KM.DISPLACEMENT_Z)
REACTIONS = (KM.REACTION_X, KM.REACTION_Y, KM.REACTION_Z)


class Airbag:
    """The Kratos model part of the quarter airbag with its stabilisation switches."""

    def __init__(self, problem: dict, law: str, prestress: float, seam_spring: float):
        self.problem = problem
        self.model = KM.Model()
        part = self.part = self.model.CreateModelPart("airbag")
        part.ProcessInfo[KM.DOMAIN_SIZE] = 3
        for variable in (KM.DISPLACEMENT, KM.REACTION, KM.VOLUME_ACCELERATION):
            part.AddNodalSolutionStepVariable(variable)  # springs check VOLUME_ACCELERATION
        nodes, held = problem["nodes"], problem["held"]
        for index, (x, y, z) in enumerate(nodes):
            part.CreateNewNode(index + 1, float(x), float(y), float(z))
        for displacement, reaction in zip(DISPLACEMENTS, REACTIONS):
            KM.VariableUtils().AddDof(displacement, reaction, part)
        for index, node in enumerate(self.nodes()):
            for component in np.flatnonzero(held[index]):
                node.Fix(DISPLACEMENTS[component])

        self.membrane = part.GetProperties()[1]
        self.membrane.SetValue(KM.THICKNESS, float(problem["thickness"]))
        self.membrane.SetValue(KM.YOUNG_MODULUS, float(problem["young_modulus"]))
        self.membrane.SetValue(KM.POISSON_RATIO, float(problem["poisson_ratio"]))
        self.membrane.SetValue(KM.DENSITY, 1.0)  # unused in statics; the element asks for it
        if law == "wrinkling":
            self.membrane.SetValue(KM.CONSTITUTIVE_LAW, CLA.WrinklingLinear2DLaw())
            base = KM.Properties(2)
            base.SetValue(KM.CONSTITUTIVE_LAW, SMA.LinearElasticPlaneStress2DLaw())
            self.membrane.AddSubProperties(base)
        elif law == "linear":
            self.membrane.SetValue(KM.CONSTITUTIVE_LAW, SMA.LinearElasticPlaneStress2DLaw())
        else:
            raise ValueError(f"law must be 'wrinkling' or 'linear', got {law!r}")
        self.set_prestress(prestress)

        self.pressure_loads = []
        for number, triangle in enumerate(problem["triangles"], start=1):
            ids = [int(node) + 1 for node in triangle]
            part.CreateNewElement("MembraneElement3D3N", number, ids, self.membrane)
            self.pressure_loads.append(
                part.CreateNewCondition("SurfaceLoadCondition3D3N", number, ids, self.membrane)
            )

        # a spring element and a point load on every node with a held dof (seam, symmetry)
        self.spring_nodes = np.flatnonzero(held.any(axis=1))
        self.spring_anchor = np.zeros((len(self.spring_nodes), 3))  # m
        self.spring_stiffness = np.zeros((len(self.spring_nodes), 3))  # N/m
        spring_properties = part.GetProperties()[3]
        first = len(problem["triangles"]) + 1
        self.springs, self.spring_preloads = [], []
        for number, node in enumerate(self.spring_nodes, start=first):
            self.springs.append(
                part.CreateNewElement(
                    "NodalConcentratedElement3D1N", number, [int(node) + 1], spring_properties
                )
            )
            self.spring_preloads.append(
                part.CreateNewCondition(
                    "PointLoadCondition3D1N", number, [int(node) + 1], spring_properties
                )
            )
        self.set_seam_spring(seam_spring)

    def nodes(self):
        """Kratos nodes in wrinkle's order."""
        return [self.part.GetNode(index + 1) for index in range(len(self.problem["nodes"]))]

    def set_prestress(self, value: float) -> None:
        """Isotropic PK2 prestress (Pa) added to every membrane's stress."""
        self.membrane.SetValue(SMA.PRESTRESS_VECTOR, KM.Vector([value, value, 0.0]))

    def set_seam_spring(self, stiffness: float) -> None:
        """Spring stiffness ``stiffness`` (N/m) on the free (in-plane) dofs of the seam nodes,
        and E t on every held dof. Held dofs do not move, so the latter change nothing but the
        diagonal that Kratos' block builder keeps for a held dof: the assembled one, zero if
        the node's only triangle is slack (a singular matrix otherwise, at the seam's ends
        (a, 0) and (0, a))."""
        held = self.problem["held"][self.spring_nodes]
        seam = held[:, 2]
        membrane_scale = float(self.problem["young_modulus"]) * float(self.problem["thickness"])
        self.spring_stiffness = np.where(
            held, membrane_scale, np.where(seam[:, None], stiffness, 0.0)
        )
        self._apply_springs()

    def anchor_springs(self) -> None:
        """Anchor the springs at the nodes' current displacements: from here on they resist
        only further motion, and a converged sequence of such steps leaves them unloaded."""
        self.spring_anchor = self.displacement()[self.spring_nodes]
        self._apply_springs()

    def _apply_springs(self) -> None:
        """Spring force k (u - anchor): Kratos 10.4's NodalConcentratedElement pulls towards
        the initial position, k u (it ignores NODAL_INITIAL_DISPLACEMENT), so a point load
        k anchor on the same node moves the anchor."""
        for spring, preload, stiffness, anchor in zip(
            self.springs, self.spring_preloads, self.spring_stiffness, self.spring_anchor
        ):
            spring.SetValue(SMA.NODAL_DISPLACEMENT_STIFFNESS, KM.Array3(list(stiffness)))
            preload.SetValue(SMA.POINT_LOAD, KM.Array3(list(stiffness * anchor)))

    def spring_force(self) -> float:
        """Largest spring force (N) on a free dof at the current displacements."""
        free = ~self.problem["held"][self.spring_nodes]
        stretch = self.displacement()[self.spring_nodes] - self.spring_anchor
        return float(np.max(np.abs(self.spring_stiffness * stretch)[free], initial=0.0))

    def set_pressure(self, value: float) -> None:
        """Follower pressure (Pa) on every triangle, inflating towards +z."""
        for condition in self.pressure_loads:
            condition.SetValue(KM.NEGATIVE_FACE_PRESSURE, value)

    def displacement(self) -> np.ndarray:
        """Nodal displacements (n_nodes, 3), m."""
        return np.array(
            [[node.GetSolutionStepValue(d) for d in DISPLACEMENTS] for node in self.nodes()]
        )

    def force_scale(self, pressure: float) -> float:
        """max(|f_ext|, |reactions|) (N) at the current shape: f_ext the consistent pressure
        forces p A n / 3 on all dofs, reactions those Kratos computed on the held dofs."""
        x = self.problem["nodes"] + self.displacement()
        triangles = self.problem["triangles"]
        corners = x[triangles]
        area_vectors = 0.5 * np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        external = np.zeros_like(x)
        for k in range(3):
            np.add.at(external, triangles[:, k], pressure * area_vectors / 3.0)
        held = self.problem["held"]
        reactions = np.array(
            [[node.GetSolutionStepValue(r) for r in REACTIONS] for node in self.nodes()]
        )[held]
        return max(float(np.linalg.norm(external)), float(np.linalg.norm(reactions)))


def newton(
    airbag: Airbag,
    linear_solver,
    relative: float,
    absolute: float,
    max_iterations: int,
    line_search: bool,
):
    """A Kratos static Newton-Raphson strategy on the airbag's model part."""
    criterion = KM.ResidualCriteria(relative, absolute)
    scheme = KM.ResidualBasedIncrementalUpdateStaticScheme()
    builder = KM.ResidualBasedBlockBuilderAndSolver(linear_solver)
    kind = KM.LineSearchStrategy if line_search else KM.ResidualBasedNewtonRaphsonStrategy
    # max iterations, compute reactions, reform dofs each step, move mesh (follower pressure)
    strategy = kind(airbag.part, scheme, criterion, builder, max_iterations, True, False, True)
    strategy.SetEchoLevel(0)
    criterion.SetEchoLevel(1)  # prints the residual ratios with --verbose
    strategy.Initialize()
    return strategy


def solve_step(airbag: Airbag, strategy, time_value: float, pressure: float) -> tuple[bool, int]:
    """One load step at the given pressure (Pa): (converged, Newton iterations)."""
    part = airbag.part
    part.CloneTimeStep(time_value)
    part.ProcessInfo[KM.STEP] += 1
    airbag.set_pressure(pressure)
    strategy.InitializeSolutionStep()
    strategy.Predict()
    converged = strategy.SolveSolutionStep()
    strategy.FinalizeSolutionStep()
    return bool(converged), int(part.ProcessInfo[KM.NL_ITERATION_NUMBER])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", help=".npz written by vs_kratos.py")
    parser.add_argument("--law", choices=["wrinkling", "linear"], default="wrinkling")
    parser.add_argument(
        "--prestress", type=float, default=1e5, help="ramp prestress s0, Pa (0: none)"
    )
    parser.add_argument(
        "--seam-spring", type=float, default=1e3, help="ramp in-plane seam spring, N/m (0: none)"
    )
    parser.add_argument(
        "--release-spring",
        type=float,
        default=1.0,
        help="seam spring of the release steps, N/m, anchored at the shape each step starts from",
    )
    parser.add_argument(
        "--release-steps",
        type=int,
        default=1,
        help="release steps at full pressure; all but the last solved to --ramp-tolerance",
    )
    parser.add_argument("--ramp-steps", type=int, default=2)
    parser.add_argument(
        "--ramp-tolerance",
        type=float,
        default=1e-2,
        help="residual reduction of the loose steps (relative to their first)",
    )
    parser.add_argument(
        "--tolerance", type=float, help="of the last step (default: the problem file's, wrinkle's)"
    )
    parser.add_argument("--max-iterations", type=int, default=5000, help="per load step")
    parser.add_argument(
        "--line-search",
        choices=["none", "ramp", "release", "both"],
        default="none",
        help="Kratos' LineSearchStrategy in these stages",
    )
    parser.add_argument(
        "--linear-solver",
        default="sparse_lu",
        help="Kratos LinearSolverFactory name: sparse_lu, skyline_lu_factorization",
    )
    parser.add_argument("--verbose", action="store_true", help="Kratos' residual ratios")
    parser.add_argument("--save", help="write the final displacements (n_nodes, 3), m, here")
    args = parser.parse_args()

    if not args.verbose:
        KM.Logger.GetDefaultOutput().SetSeverity(KM.Logger.Severity.WARNING)
    start = time.perf_counter()
    with np.load(args.problem) as data:
        problem = {key: data[key] for key in data.files}
    pressure = float(problem["pressure"])
    if args.tolerance is None:
        args.tolerance = float(problem["tolerance"])
    airbag = Airbag(problem, args.law, args.prestress, args.seam_spring)
    linear_solver = KM.LinearSolverFactory().Create(
        KM.Parameters(json.dumps({"solver_type": args.linear_solver}))
    )
    n_free = int(np.count_nonzero(~problem["held"]))
    setup_s = time.perf_counter() - start

    row = {
        "law": args.law,
        "prestress_pa": args.prestress,
        "seam_spring_n_per_m": args.seam_spring,
        "ramp_steps": args.ramp_steps,
        "ramp_tolerance": args.ramp_tolerance,
        "release_spring_n_per_m": args.release_spring,
        "release_steps": args.release_steps,
        "tolerance": args.tolerance,
        "linear_solver": args.linear_solver,
        "line_search": args.line_search,
        "unknowns": n_free,
        "elements": len(problem["triangles"]),
    }
    # the solution path: (stage, prestress Pa, seam spring N/m, pressure Pa, final?)
    stabilised = args.prestress > 0.0 or args.seam_spring > 0.0
    steps = args.ramp_steps if stabilised else 0
    path = [
        ("ramp", args.prestress, args.seam_spring, pressure * step / steps, False)
        for step in range(1, steps + 1)
    ]
    path += [
        ("release", 0.0, args.release_spring, pressure, step == args.release_steps)
        for step in range(1, args.release_steps + 1)
    ]
    iterations = {"ramp": 0, "release": 0}
    converged, error = True, ""
    try:
        for step, (stage, prestress, spring, load, final) in enumerate(path, start=1):
            airbag.set_prestress(prestress)
            airbag.set_seam_spring(spring)
            if stage == "release":
                airbag.anchor_springs()
            if final:  # wrinkle's test, |r| <= tolerance * max(|f_ext|, |reactions|)
                relative = args.tolerance
                absolute = args.tolerance * airbag.force_scale(load) / n_free
            else:  # loose: relative to the step's first residual only
                relative, absolute = args.ramp_tolerance, 0.0
            strategy = newton(
                airbag,
                linear_solver,
                relative,
                absolute,
                args.max_iterations,
                args.line_search in (stage, "both"),
            )
            converged, count = solve_step(airbag, strategy, step, load)
            iterations[stage] += count
            if not converged:
                raise RuntimeError(
                    f"step {step} of {len(path)}: no convergence in {count} iterations"
                )
    except RuntimeError as failure:  # ours, or Kratos': singular matrix, ...
        if converged:  # Kratos stopped inside an iteration
            iterations[stage] += int(airbag.part.ProcessInfo[KM.NL_ITERATION_NUMBER])
        converged, error = False, f"{stage}: {str(failure).strip().splitlines()[0]}"
    solve_s = time.perf_counter() - start - setup_s

    centre = int(problem["centre"][0])
    row.update(
        {
            "converged": converged,
            "error": error,
            "iterations": iterations["ramp"] + iterations["release"],
            "ramp_iterations": iterations["ramp"],
            "release_iterations": iterations["release"],
            "deflection_mm": 1e3 * float(airbag.displacement()[centre, 2]),
            "spring_force_n": airbag.spring_force(),
            "setup_s": setup_s,
            "solve_s": solve_s,
        }
    )
    if args.save:
        np.save(args.save, airbag.displacement())
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
