"""Nonlinear solvers: quadratic convergence of the default, robustness with slack regions,
agreement of the two methods, the energy principle for reactions, and clear failure."""

import numpy as np
import pytest

import wrinkle
from wrinkle.materials import StVenantKirchhoff
from wrinkle.solvers import ConvergenceError, make_solver, solve_step, tangent_prediction
from wrinkle.wrinkling import TAUT

ANISOTROPIC = StVenantKirchhoff.transversely_isotropic(
    E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1 / 2.6, thickness=1.0
)
# top-edge displacement making the whole membrane taut, or mostly wrinkled
TOP_DISPLACEMENT = {"taut": (0.05, 0.1, 0.0), "wrinkled": (0.2, 0.02, 0.0)}
# (with the fibres at 0.5 rad the "taut" case still has a few wrinkled elements)


def sheet_model(top_displacement, nx=6):
    mesh = wrinkle.rectangle(1.0, 1.0, nx, nx)
    model = wrinkle.Model(mesh, ANISOTROPIC, fibre_angle=0.5)  # fibres off-axis
    model.fix(mesh.node_sets["bottom"])
    model.prescribe(mesh.node_sets["top"], top_displacement)
    return model


def solve_history(model, method="newton", tolerance=1e-13, max_iterations=None):
    """Solve from the undeformed sheet with the supports moved (no tangent prediction)."""
    solver = make_solver(method, tolerance=tolerance, max_iterations=max_iterations)
    problem = model.discretise().at(1.0)
    solved = solver.solve(problem, problem.prescribed.copy())
    return solved.u, solved


@pytest.mark.parametrize("state", ["taut", "wrinkled"])
def test_newton_converges_quadratically(state):
    """|r_k+1| / |r_k|^2 stays bounded once the iteration is close (consistent tangent).
    A tangent that misses the variation of the wrinkle direction converges only linearly."""
    model = sheet_model(TOP_DISPLACEMENT[state])
    _, solved = solve_history(model)
    taut, wrinkled, slack = solved.evaluation.states
    if state == "taut":
        assert taut > 0.7 * model.mesh.n_elements and slack == 0
    else:
        assert wrinkled > 0.8 * model.mesh.n_elements
    # relative to the forces the sheet carries (the convergence test's scale may be the
    # larger force scale of the prescribed motion, which would shift the ratios below)
    scale = np.linalg.norm(solved.evaluation.reactions)
    r = np.array(solved.residual_norms) / scale
    # pairs close to the solution, the second still above the round-off of the wrinkling
    # solve (relative 1e-13 in the stresses)
    close = [k for k in range(len(r) - 1) if r[k] < 1e-2 and r[k + 1] > 1e-11]
    assert len(close) >= 1, r
    ratios = [r[k + 1] / r[k] ** 2 for k in close]
    assert max(ratios) < 1e3, (r, ratios)
    assert solved.iterations <= 15


@pytest.mark.parametrize("method", ["newton", "restricted-step"])
def test_both_solvers_converge_from_undeformed_with_slack_regions(method):
    """A square pulled up at one node of its top edge, bottom edge held: a tension fan under
    the node, slack regions beside it. Both solvers start from the flat, undeformed sheet and
    take the full displacement in one step; the stiffness there is singular."""
    mesh = wrinkle.rectangle(1.0, 1.0, 8, 8)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0))
    model.fix(mesh.node_sets["bottom"])
    top = mesh.node_sets["top"]
    pulled = top[top.size // 2]
    model.prescribe([pulled], (0.0, 0.1, 0.0))
    u, solved = solve_history(model, method, tolerance=1e-8)
    _, wrinkled, slack = solved.evaluation.states
    assert slack > 0 and wrinkled > 0
    reaction = model.discretise().internal_forces(u).reshape(-1, 3)[pulled]
    # both methods reach the same equilibrium (reaction force of the pulled node, Newton's)
    np.testing.assert_allclose(reaction, [-0.00160206, 0.05511688, 0.0], rtol=1e-4, atol=1e-7)


def test_methods_agree_on_wrinkled_problem():
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    u_newton, _ = solve_history(model, "newton", tolerance=1e-11)
    u_restricted, _ = solve_history(model, "restricted-step", tolerance=1e-11)
    np.testing.assert_allclose(u_restricted, u_newton, atol=1e-9)


def test_reactions_are_derivative_of_energy():
    """Energy principle: at equilibrium, d(strain energy)/d(load factor) = R . u_prescribed."""
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    solver = make_solver("newton", tolerance=1e-13)
    energies = {}
    u = np.zeros(model.n_dofs)
    for factor in (0.999, 1.001, 1.0):
        solved = solve_step(model.discretise().at(factor), u, solver)
        u = solved.u
        energies[factor] = solved.evaluation.energy
    reactions = model.discretise().internal_forces(u)
    slope = (energies[1.001] - energies[0.999]) / 0.002
    assert slope == pytest.approx(reactions @ model.prescribed, rel=1e-5)


def test_unconverged_solve_raises():
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    with pytest.raises(ConvergenceError, match="not converged in 2 iterations"):
        solve_history(model, max_iterations=2)


def test_load_stepping_cuts_back_and_reports_failure():
    """A step that fails is halved down to min_step; then the error carries the steps done."""
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    with pytest.raises(ConvergenceError, match="minimum") as failure:
        model.solve(steps=1, max_iterations=1, min_step=0.2)
    assert len(failure.value.results) == 0
    results = model.solve(steps=4)
    assert [round(s.load_factor, 12) for s in results.steps] == [0.25, 0.5, 0.75, 1.0]
    assert results.final.states[1] > 0


def homogeneous_square(nx=6):
    """Unit square whose whole boundary follows x = X + 0.1 Y, y = 1.1 Y (the paper's
    shear-stretch path, f = 5, fibres along X): the solution is that homogeneous map at every
    load factor, linear in it (Roddeman et al. 1987, Part II, section 6)."""
    mesh = wrinkle.rectangle(1.0, 1.0, nx, nx)
    model = wrinkle.Model(mesh, ANISOTROPIC)
    X = mesh.nodes
    boundary = np.flatnonzero((X[:, 0] % 1.0 == 0.0) | (X[:, 1] % 1.0 == 0.0))
    model.prescribe(
        boundary,
        np.column_stack([0.1 * X[boundary, 1], 0.1 * X[boundary, 1], np.zeros(boundary.size)]),
    )
    homogeneous = np.column_stack([0.1 * X[:, 1], 0.1 * X[:, 1], np.zeros(len(X))]).ravel()
    return model, homogeneous


def test_load_steps_start_from_the_extrapolated_state():
    """On a path whose solution is linear in the load factor, the extrapolation of the first
    step (from the start at factor 0) is the solution of every later step: no iterations."""
    model, homogeneous = homogeneous_square()
    results = model.solve(steps=5, tolerance=1e-10)
    iterations = [step.iterations for step in results.steps]
    assert iterations[0] > 0 and iterations[1:] == [0, 0, 0, 0], iterations
    for step in results.steps:
        np.testing.assert_allclose(step.displacement, step.load_factor * homogeneous, atol=1e-10)


def test_a_worse_prediction_is_not_used():
    """solve_step keeps the plain start when the predicted state is further from balance."""
    model, homogeneous = homogeneous_square()
    solver = make_solver("newton", tolerance=1e-10)
    u_half = solve_step(model.discretise().at(0.5), np.zeros(model.n_dofs), solver).u
    problem = model.discretise().at(1.0)
    plain = solver.solve(problem, np.where(model.constrained, problem.prescribed, u_half))
    bad = u_half + np.random.default_rng(0).normal(scale=0.02, size=model.n_dofs)
    predicted = solve_step(problem, u_half, solver, predicted=bad)
    u = predicted.u
    assert predicted.iterations == plain.iterations > 0
    good = 2.0 * u_half
    extrapolated = solve_step(problem, u_half, solver, predicted=good)
    assert extrapolated.iterations == 0
    np.testing.assert_allclose(u, homogeneous, atol=1e-10)


def test_a_step_that_moves_supports_starts_from_the_tangent_prediction():
    """The prediction is the first Newton iteration from the undeformed square with the
    support increment spread through the elastic tangent: for the homogeneous path, whose
    boundary values are an affine map, the linear solution is that map (the patch test), and
    the path is linear in the load factor, so the prediction is the solution up to the
    solver's initial regularisation and the step needs at most one iteration."""
    model, homogeneous = homogeneous_square(nx=12)
    solver = make_solver("newton", tolerance=1e-10)
    zero = np.zeros(model.n_dofs)
    predicted = tangent_prediction(model.discretise().at(0.2), zero, solver)
    np.testing.assert_allclose(predicted, 0.2 * homogeneous, atol=1e-8)
    solved = solve_step(model.discretise().at(0.2), zero, solver)
    assert solved.iterations <= 1
    problem = model.discretise().at(0.2)  # from the moved supports alone it takes several
    plain = solver.solve(problem, problem.prescribed.copy())
    assert plain.iterations > solved.iterations + 2
    # nothing to predict where no support moves: the first iteration is the prediction
    assert tangent_prediction(model.discretise().at(0.2), predicted, solver) is None


def test_a_start_in_balance_costs_no_stiffness():
    """Given the evaluation at a start that is already in balance, the solver returns it
    without evaluating (and factorising) the stiffness; otherwise it evaluates the stiffness
    there once."""
    model, homogeneous = homogeneous_square()
    problem = model.discretise().at(1.0)
    calls = []
    evaluate = problem.evaluate
    problem.evaluate = lambda u, stiffness=True, **options: (
        calls.append(stiffness) or evaluate(u, stiffness, **options)
    )
    solver = make_solver("newton", tolerance=1e-10)
    balanced = problem.evaluate(homogeneous, stiffness=False)
    solved = solver.solve(problem, homogeneous, balanced)
    assert solved.iterations == 0 and calls == [False]
    off = homogeneous + np.where(model.constrained, 0.0, 1e-3)
    solved = solver.solve(problem, off, problem.evaluate(off, stiffness=False))
    assert solved.iterations > 0 and calls[1:3] == [False, True]
    np.testing.assert_allclose(solved.u, homogeneous, atol=1e-10)


def test_a_prediction_in_balance_costs_one_evaluation():
    """A load step given a prediction already in balance starts from it after one evaluation
    of the forces (none at the plain start, no stiffness); a prediction out of balance is
    compared with the plain start (two evaluations) and then solved from."""
    model, homogeneous = homogeneous_square()
    calls = []

    def counted_problem():
        problem = model.discretise().at(1.0)
        evaluate = problem.evaluate
        problem.evaluate = lambda u, stiffness=True, **options: (
            calls.append(stiffness) or evaluate(u, stiffness, **options)
        )
        return problem

    solver = make_solver("newton", tolerance=1e-10)
    solved = solve_step(counted_problem(), np.zeros(model.n_dofs), solver, predicted=homogeneous)
    u = solved.u
    assert solved.iterations == 0 and calls == [False]
    np.testing.assert_array_equal(u, homogeneous)
    calls.clear()
    off = homogeneous + np.where(model.constrained, 0.0, 1e-3)
    solved = solve_step(counted_problem(), np.zeros(model.n_dofs), solver, predicted=off)
    u = solved.u
    assert calls[:3] == [False, False, True] and solved.iterations > 0
    np.testing.assert_allclose(u, homogeneous, atol=1e-10)


def test_undeformed_elements_far_from_the_origin_are_taut():
    """Round-off in the deformation gradient does not grow with the coordinates over the
    element size: a fine mesh 10^4 element sizes from the origin, undeformed, is taut and
    stress-free everywhere (summing absolute coordinates gave noise of 10^4 eps in F)."""
    mesh = wrinkle.rectangle(1.0, 1.0, 60, 60)
    mesh.nodes[:, :2] += 300.0
    model = wrinkle.Model(mesh, ANISOTROPIC)
    result = model.discretise().evaluate_elements(np.zeros(model.n_dofs), stiffness=False)
    assert np.all(result.response.state == TAUT)
    C = np.einsum("nia,nib->nab", result.deformation_gradient, result.deformation_gradient)
    np.testing.assert_allclose(C, np.broadcast_to(np.eye(2), C.shape), atol=1e-13)


def test_unsupported_model_is_rejected():
    mesh = wrinkle.rectangle(1.0, 1.0, 2, 2)
    model = wrinkle.Model(mesh, ANISOTROPIC)
    model.fix(mesh.node_sets["bottom"], "xy")
    with pytest.raises(
        ValueError, match="do not prevent translation in z, rotation about x, rotation about y"
    ):
        model.solve()


def test_newton_regularises_in_the_unit_tension_metric():
    """The regularised matrix is K + theta (s_K / s_L) L + 1e-3 theta s_K I on the free dofs
    (s: mean free diagonals, L the model's unit-tension Laplacian), and leaves the constrained
    rows and columns as the identity; without a metric, K + theta s_K I."""
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    problem = model.discretise().at(1.0)
    u = np.where(model.constrained, problem.prescribed, 0.0)
    u[~model.constrained] = 1e-3 * np.sin(np.arange(np.count_nonzero(~model.constrained)))
    ev = problem.evaluate(u)
    free = problem.free
    K = ev.stiffness.toarray()
    L = model.discretise().pattern.matrix(model.discretise().step_metric()).toarray()
    s_K = np.mean(np.diag(K)[free])
    s_L = np.mean(np.diag(L)[free])
    theta = 0.37
    solver = make_solver("newton")
    solver.initial_theta(ev.stiffness, free)
    expected = K.copy()
    block = np.ix_(free, free)
    expected[block] += theta * (s_K / s_L) * L[block] + 1e-3 * theta * s_K * np.eye(free.sum())
    np.testing.assert_allclose(
        solver.regularised(ev, theta, free).toarray(), expected, rtol=1e-14, atol=1e-12 * s_K
    )
    ev.metric = None
    plain = K.copy()
    plain[block] += theta * s_K * np.eye(free.sum())
    solver.initial_theta(ev.stiffness, free)
    np.testing.assert_allclose(
        solver.regularised(ev, theta, free).toarray(), plain, rtol=1e-14, atol=1e-12 * s_K
    )


def test_step_metric_follows_the_supports():
    """Each step's metric is the unit-tension Laplacian with the constrained rows and columns
    zeroed, also after a support is added between solves (its cache is renewed)."""
    model = sheet_model(TOP_DISPLACEMENT["wrinkled"])
    model.solve()
    L = model.discretise().pattern.matrix(model.discretise().step_metric()).toarray()

    def expected():
        held = model.constrained
        zeroed = L.copy()
        zeroed[held, :] = 0.0
        zeroed[:, held] = 0.0
        return zeroed

    np.testing.assert_array_equal(
        model.discretise().pattern.matrix(model.discretise().at(1.0).metric).toarray(), expected()
    )
    held_before = np.count_nonzero(model.constrained)
    model.fix(np.flatnonzero(~model.constrained)[:3] // 3, "x")
    assert np.count_nonzero(model.constrained) > held_before
    np.testing.assert_array_equal(
        model.discretise().pattern.matrix(model.discretise().at(1.0).metric).toarray(), expected()
    )


class _Bowl:
    """Pi(u) = sum(sqrt(1 + u^2)) - f.u: convex, with a curvature that vanishes far out, so
    that a Newton step from near the bottom can overshoot far up the other side."""

    def __init__(self, f):
        self.f = np.asarray(f, dtype=float)
        self.free = np.ones(self.f.size, dtype=bool)

    def evaluate(self, u, stiffness=True):
        import scipy.sparse as sp

        from wrinkle.solvers import Evaluation

        root = np.sqrt(1.0 + u**2)
        K = sp.diags(root**-3).tocsr() if stiffness else None
        return Evaluation(
            self.f - u / root,
            float(np.sum(root) - self.f @ u),
            float(np.linalg.norm(self.f)),
            (u.size, 0, 0),
            K,
        )


def test_newton_backtracks_along_a_rejected_step():
    """A rejected Newton step is shortened to 0.3, then 0.1 of itself, the first that lowers
    the energy by at least 0.1 of the quadratic model's prediction being taken (no new
    factorisation); refused when no fraction does."""
    problem = _Bowl([0.2, -0.1])
    u = np.array([-3.0, 2.5])
    ev = problem.evaluate(u)
    solver = make_solver("newton")
    solver.initial_theta(ev.stiffness, problem.free)
    step, _ = solver.trial_step(ev, 1e-12, problem.free)
    assert solver._use_energy
    # the full step and 0.3 of it overshoot (energy up); 0.1 of it lowers the energy
    assert problem.evaluate(u + step).energy > ev.energy
    assert problem.evaluate(u + 0.3 * step).energy > ev.energy
    shorter, evaluation = solver.backtrack(problem, u, ev, step)
    np.testing.assert_allclose(shorter, u + 0.1 * step, rtol=1e-15)
    model = 0.1 * (ev.residual @ step) - 0.005 * step @ (ev.stiffness @ step)
    assert ev.energy - evaluation.energy >= 0.1 * model > 0
    assert evaluation.stiffness is not None
    assert solver.backtrack(problem, u, ev, -step) is None  # uphill: nothing acceptable
    # the whole solve converges to Pi's minimum, u = f / sqrt(1 - f^2)
    result = solver.solve(problem, u)
    np.testing.assert_allclose(result.u, problem.f / np.sqrt(1 - problem.f**2), rtol=1e-9)


class _DoubleWell:
    """Pi(u) = offset + sum((u^2 - 1)^2 / 4) - f.u: two wells per component, the hilltop
    between them near u = -f, where the tangent 3 u^2 - 1 is negative."""

    def __init__(self, f, offset):
        self.f = np.asarray(f, dtype=float)
        self.offset = offset
        self.free = np.ones(self.f.size, dtype=bool)

    def evaluate(self, u, stiffness=True):
        import scipy.sparse as sp

        from wrinkle.solvers import Evaluation

        K = sp.diags(3.0 * u**2 - 1.0).tocsr() if stiffness else None
        energy = self.offset + float(np.sum((u**2 - 1.0) ** 2) / 4.0 - self.f @ u)
        return Evaluation(self.f - (u**3 - u), energy, 1.0, (u.size, 0, 0), K)


@pytest.mark.parametrize("offset", [0.0, 1e12])
def test_newton_goes_down_from_a_hilltop_even_where_energy_changes_are_round_off(offset):
    """From near the hilltop of a double well, where Newton's step climbs to it (the energy
    model predicts an increase), Newton goes down into a well: a minimum of Pi, u^3 - u = f
    with 3 u^2 - 1 > 0. With offset 1e12 every change of Pi is below its round-off and the
    decrease is measured from the residuals (the trapezoidal rule). Before 6 December 2026
    both ended on the hilltop, a maximum of Pi (the merit |r|^2 took over there)."""
    problem = _DoubleWell([0.01, -0.02], offset)
    solver = make_solver("newton", tolerance=1e-10)
    result = solver.solve(problem, np.array([0.1, 0.05]))
    u = result.u
    np.testing.assert_allclose(u**3 - u, problem.f, atol=1e-10)
    assert np.all(3.0 * u**2 - 1.0 > 1.0)  # in a well, not on the hilltop (-1 there)
    # and the roots are the wells' bottoms, to the tolerance
    wells = [np.roots([1.0, 0.0, -1.0, -f]).real for f in problem.f]
    for value, roots in zip(u, wells, strict=True):
        assert np.min(np.abs(roots - value)) < 1e-9


class _Wells:
    """The bordered family R(u, mu) = mu f - (u^3 - u) of ``_DoubleWell`` (``solve_bordered``)."""

    def __init__(self, f, offset):
        self.f, self.offset = np.asarray(f, dtype=float), offset

    def at(self, mu):
        return _DoubleWell(mu * self.f, self.offset)

    def derivative(self, u):
        return self.f.copy()


class _UnitFactor:
    """c = mu - 1: the load factor held at 1."""

    scale = 1.0

    def admits(self, mu):
        return True

    def __call__(self, u, mu):
        from wrinkle.solvers.bordered import Linearised

        return Linearised(mu - 1.0, None, 1.0)


class _WellEnergy:
    """The double well's energy as a bordered solve's merit, with mu held (as ``GasEnergy``
    judges a gas load: the energy, its slope and derivative -R.du)."""

    def project(self, u, mu):
        return mu

    def value(self, ev, u, mu, c):
        return ev.energy

    def slope(self, ev, c, du, dmu, K_du):
        return -float(ev.residual @ du)

    def derivative(self, ev, lin, du, dmu):
        return -float(ev.residual @ du)


@pytest.mark.parametrize("offset", [0.0, 1e12])
def test_a_bordered_solve_goes_down_from_a_hilltop_even_where_merit_changes_are_round_off(
    offset,
):
    """The bordered solver of volume control and gas loads (``wrinkle.solvers.bordered``) on
    the double well, its merit the energy: from near the hilltop it ends in a well, also
    where every change of the merit is below its round-off (offset 1e12) and the change is
    measured from the forces by the trapezoidal rule. Before 6 December 2026 the residual
    merit judged those changes, and the solve ended on the hilltop, a maximum of the energy."""
    from wrinkle.solvers.bordered import solve_bordered

    family = _Wells([0.01, -0.02], offset)
    solver = make_solver("newton", tolerance=1e-10)
    result = solve_bordered(
        family, _UnitFactor(), np.array([0.1, 0.05]), 1.0, solver, merit=_WellEnergy()
    )
    u = result.u
    assert result.mu == 1.0
    np.testing.assert_allclose(u**3 - u, family.f, atol=1e-10)
    assert np.all(3.0 * u**2 - 1.0 > 1.0)  # in a well, not on the hilltop (-1 there)
