"""The accuracy stop: end a solve on a finer mesh once the iteration's remaining error is a
small fraction of the mesh's own (docs/solvers.md, "The accuracy stop").

In the spirit of Ern & Vohralik (SIAM J. Sci. Comput. 35, 2013: stop the linearisation when
its error estimate is below a fraction of the discretisation error estimate). On a level h of
a mesh sequence whose coarser level H converged at the same load with energy Pi_H:

- the discretisation error of the energy is estimated as D = (Pi_H - Pi_h(u_k)) / (r - 1),
  with r the ratio of the levels' element counts (4 for a refinement: D = (Pi_H - Pi_h) / 3),
  which is what it would be if the error fell like h^2 ~ 1 / (number of elements), the
  fastest linear elements allow (slower convergence makes the true error larger than D, so
  the rule errs on the side of going on; a level whose energy is not below the coarser one's,
  as independent meshes may give, has D <= 0 and never stops early);
- the energy still to be gained is estimated from the accepted steps' actual decreases
  a_j = Pi(u_(j-1)) - Pi(u_j): with q the largest ratio a_j / a_(j-1) over the last
  ``window`` steps, the rest of a sequence that contracts by q is G = a_k q / (1 - q);
- every displacement component, and each quantity of interest (a probe's mean
  displacement, a support's reaction), still to change is its last change times
  sqrt(q) / (1 - sqrt(q)), the energy gap shrinking like the square of the displacement
  error.

The solve stops at iterate k when the last ``window`` steps were all full steps whose gain
ratio was at least 0.75 (the quadratic model held: a damped or shortened step is short
because it was cut, not because the solve is done, and never counts), q < 1, G <= eta D,
the largest remaining change of a displacement component is at most ``change`` times the
largest component, every quantity's is at most ``change`` times its scale, and the residual
is below ``MAX_RESIDUAL`` of the force scale. The residual test ends the solve as usual if it
is met first. Watching every node, not only the probes, keeps a fold moving elsewhere in the
sheet from being stopped half-way (docs/notes/2026-12-solver-accuracy.md, section 1).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from wrinkle.solvers.base import AcceptedStep, Evaluation

__all__ = ["MAX_RESIDUAL", "AccuracyStop", "Quantities"]

# the largest residual, relative to the force scale, at which the accuracy stop may end a
# solve: the loosest tolerance a residual test accepts (``settings.MAX_TOLERANCE``)
MAX_RESIDUAL = 1e-2
_GOOD_GAIN = 0.75  # a step whose gain ratio is at least this followed its quadratic model

# quantities of an iterate: (names, values, scales), the scales in the values' units
Quantities = Callable[[np.ndarray, Evaluation], tuple[list[str], np.ndarray, np.ndarray]]


@dataclass
class AccuracyStop:
    """The accuracy stop of one solve (the module docstring).

    coarse_energy: Pi_H, the converged energy of the coarser level at the same load (J);
    quantities: the quantities of interest of an iterate (``Quantities``); energy: eta, the
    fraction of the discretisation error the energy still to be gained may be; change: the
    largest remaining change of a quantity, relative to its scale; window: the number of
    last steps that must all be good (>= 2); order_factor: r - 1, r the ratio of the
    levels' element counts (3 for a mesh refined once).
    """

    coarse_energy: float
    quantities: Quantities
    energy: float = 0.1
    change: float = 1e-4
    window: int = 3
    order_factor: float = 3.0
    _energies: list[float] = field(default_factory=list)
    _good: list[bool] = field(default_factory=list)
    _values: np.ndarray | None = None
    _u: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.window < 2:
            raise ValueError(f"accuracy stop: window must be >= 2, got {self.window}")
        if not self.order_factor > 0:
            raise ValueError(f"accuracy stop: order_factor must be > 0, got {self.order_factor}")

    def __call__(self, step: AcceptedStep) -> dict[str, Any] | None:
        """The report of the numbers decided on if the solve may stop at ``step``, else None
        (``wrinkle.solvers.base.StopRule``)."""
        names, values, scales = self.quantities(step.u, step.evaluation)
        previous, self._values = self._values, values
        u_before, self._u = self._u, step.u
        self._energies.append(step.energy)
        self._good.append(bool(step.full and step.rho >= _GOOD_GAIN))
        if previous is None or u_before is None or len(self._good) <= self.window:
            return None  # the start, or too few steps yet
        if not all(self._good[-self.window :]):
            return None
        energies = np.array(self._energies[-self.window - 1 :])
        if not (np.all(np.isfinite(energies)) and math.isfinite(self.coarse_energy)):
            return None  # no potential to measure the error by
        decreases = energies[:-1] - energies[1:]
        if not np.all(decreases > 0.0):
            return None
        q = float(np.max(decreases[1:] / decreases[:-1]))
        if q >= 1.0:
            return None
        gap = float(decreases[-1]) * q / (1.0 - q)
        discretisation = (self.coarse_energy - step.energy) / self.order_factor
        if not gap <= self.energy * discretisation:
            return None
        root = math.sqrt(q)
        tail = root / (1.0 - root)
        remaining = np.abs(values - previous) * tail
        if np.any(remaining > self.change * scales):
            return None
        moved = float(np.max(np.abs(step.u - u_before), initial=0.0)) * tail
        if not moved <= self.change * float(np.max(np.abs(step.u), initial=0.0)):
            return None
        ev = step.evaluation
        residual = ev.residual_norm / ev.force_scale if ev.force_scale > 0 else math.inf
        if not residual <= MAX_RESIDUAL:
            return None
        return {
            "rule": "accuracy",
            "residual": residual,
            "energy_gap": gap,
            "discretisation_error": discretisation,
            "contraction": q,
            "remaining_change": {
                "displacement": moved,
                **{n: float(r) for n, r in zip(names, remaining)},
            },
        }
