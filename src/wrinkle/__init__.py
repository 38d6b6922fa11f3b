"""wrinkle: finite-element analysis of thin membranes that wrinkle.

The method is Roddeman, Drukker, Oomens & Janssen, "The Wrinkling of Thin Membranes, Part II:
Numerical Analysis", J. Appl. Mech. 54 (1987) 888-892 (docs/method.md).
"""

from importlib.metadata import PackageNotFoundError, version

from wrinkle.case import Case, CaseError, read_case
from wrinkle.materials import MooneyRivlin, NeoHookean, Ogden, Prestressed, StVenantKirchhoff
from wrinkle.mesh import Mesh, annulus, cylinder, disk, read_mesh, rectangle, sphere
from wrinkle.model import Model
from wrinkle.post import element_report, material_response
from wrinkle.reader import ResultsFolder, open_results
from wrinkle.refinement import refine, refined
from wrinkle.results import Results, StepResult
from wrinkle.selectors import select_nodes
from wrinkle.solvers import ConvergenceError, SolverSettings
from wrinkle.transfer import PointTransfer
from wrinkle.wrinkling import Wrinkling

try:
    __version__ = version("wrinkle")
except PackageNotFoundError:  # pragma: no cover - running from a source tree not installed
    __version__ = "unknown"

__all__ = [
    "Case",
    "CaseError",
    "ConvergenceError",
    "Mesh",
    "Model",
    "MooneyRivlin",
    "NeoHookean",
    "Ogden",
    "PointTransfer",
    "Prestressed",
    "Results",
    "ResultsFolder",
    "SolverSettings",
    "StVenantKirchhoff",
    "StepResult",
    "Wrinkling",
    "__version__",
    "annulus",
    "cylinder",
    "disk",
    "element_report",
    "material_response",
    "open_results",
    "read_case",
    "read_mesh",
    "rectangle",
    "refine",
    "refined",
    "select_nodes",
    "sphere",
]
