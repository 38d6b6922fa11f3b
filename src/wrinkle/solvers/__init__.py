"""Nonlinear solvers: the default regularised Newton and the paper's restricted step."""

from wrinkle.solvers.base import ConvergenceError, Evaluation, SolverResult
from wrinkle.solvers.linear import LINEAR_SOLVERS
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.restricted_step import RestrictedStep

SOLVERS = {"newton": RegularisedNewton, "restricted-step": RestrictedStep}


def make_solver(method: str = "newton", tolerance: float = 1e-6, max_iterations: int | None = None,
                linear_solver: str = "auto"):
    """Solver by name: "newton" (default) or "restricted-step"; max_iterations None takes the
    method's default (100 for Newton, 300 for the slower restricted step); linear_solver one of
    ``wrinkle.solvers.linear.LINEAR_SOLVERS`` or "auto"."""
    try:
        cls = SOLVERS[method]
    except KeyError:
        raise ValueError(
            f"unknown solver method {method!r}; choose one of {sorted(SOLVERS)}"
        ) from None
    if max_iterations is None:
        max_iterations = cls.default_max_iterations
    if linear_solver != "auto" and linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"unknown linear solver {linear_solver!r}; choose auto or one of "
            f"{sorted(LINEAR_SOLVERS)}"
        )
    return cls(tolerance=tolerance, max_iterations=max_iterations, linear_solver=linear_solver)


__all__ = [
    "LINEAR_SOLVERS",
    "SOLVERS",
    "ConvergenceError",
    "Evaluation",
    "RegularisedNewton",
    "RestrictedStep",
    "SolverResult",
    "make_solver",
]
