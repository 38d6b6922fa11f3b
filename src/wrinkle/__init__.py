"""wrinkle: finite-element analysis of thin membranes that wrinkle.

The method is Roddeman, Drukker, Oomens & Janssen, "The Wrinkling of Thin Membranes, Part II:
Numerical Analysis", J. Appl. Mech. 54 (1987) 888-892.
"""

from wrinkle.case import read_case
from wrinkle.materials import NeoHookean, StVenantKirchhoff
from wrinkle.mesh import Mesh, annulus, cylinder, disk, read_mesh, rectangle, sphere
from wrinkle.model import Model, Results
from wrinkle.point import material_response
from wrinkle.solvers import ConvergenceError
from wrinkle.wrinkling import Wrinkling

__version__ = "0.1.0"

__all__ = [
    "ConvergenceError", "Mesh", "Model", "NeoHookean", "Results", "StVenantKirchhoff",
    "Wrinkling", "annulus", "cylinder", "disk", "material_response", "read_case", "read_mesh",
    "rectangle", "sphere",
]
