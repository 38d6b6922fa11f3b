"""Nonlinear solvers (the default regularised Newton and the paper's restricted step), their
settings, and the load-path followers."""

from wrinkle.solvers.base import (
    ConvergenceError,
    Evaluation,
    IterationListener,
    SolverResult,
    listening,
)
from wrinkle.solvers.linear import LINEAR_SOLVERS
from wrinkle.solvers.newton import RegularisedNewton
from wrinkle.solvers.restricted_step import RestrictedStep
from wrinkle.solvers.settings import SOLVERS, SolverSettings, make_solver
from wrinkle.solvers.stepping import (
    StepController,
    follow_load_path,
    solve_step,
    tangent_prediction,
)
from wrinkle.solvers.stopping import AccuracyStop

__all__ = [
    "LINEAR_SOLVERS",
    "AccuracyStop",
    "SOLVERS",
    "ConvergenceError",
    "Evaluation",
    "IterationListener",
    "RegularisedNewton",
    "RestrictedStep",
    "SolverResult",
    "SolverSettings",
    "StepController",
    "follow_load_path",
    "listening",
    "make_solver",
    "solve_step",
    "tangent_prediction",
]
