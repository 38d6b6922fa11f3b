"""Nonlinear solvers: the default regularised Newton and the paper's restricted step."""

from wrinkle.solvers.base import ConvergenceError, Evaluation, SolverResult
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.restricted_step import RestrictedStep

SOLVERS = {"newton": RegularisedNewton, "restricted-step": RestrictedStep}


def make_solver(method: str = "newton", tolerance: float = 1e-6, max_iterations: int | None = None):
    """Solver by name: "newton" (default) or "restricted-step"; max_iterations None takes the
    method's default (100 for Newton, 300 for the slower restricted step)."""
    try:
        cls = SOLVERS[method]
    except KeyError:
        raise ValueError(
            f"unknown solver method {method!r}; choose one of {sorted(SOLVERS)}"
        ) from None
    if max_iterations is None:
        max_iterations = cls.default_max_iterations
    return cls(tolerance=tolerance, max_iterations=max_iterations)


__all__ = [
    "SOLVERS",
    "ConvergenceError",
    "Evaluation",
    "RegularisedNewton",
    "RestrictedStep",
    "SolverResult",
    "make_solver",
]
