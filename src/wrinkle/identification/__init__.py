"""Material identification: a least-squares fit of case parameters to measured curves, its
gradients by the adjoint method on the converged states (docs/fit.md)."""

from wrinkle.identification.fit import FitResult, run_fit
from wrinkle.identification.problem import FitError, FitProblem, read_fit
from wrinkle.identification.report import write_picture, write_report

__all__ = [
    "FitError",
    "FitProblem",
    "FitResult",
    "read_fit",
    "run_fit",
    "write_picture",
    "write_report",
]
