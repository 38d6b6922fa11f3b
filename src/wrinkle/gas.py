"""An enclosed amount of gas as a load: its pressure follows the volume the membrane encloses.

The gas obeys the polytropic law p V^gamma = K (gamma = 1: isothermal, Boyle's law; gamma =
1.4: adiabatic air), with p its absolute pressure; the membrane carries the gauge pressure
p - p_ambient. The gas is given either

- sealed at the absolute pressure ``p0`` in the reference volume V_ref the membrane encloses
  (a balloon or tube tied off): K = p0 V_ref^gamma; or
- by its ``amount``, the product p V it has at the ambient pressure (the volume of free air
  pumped in, times p_ambient), for a membrane that starts with no volume (a flat airbag):
  the state (p_ambient, amount / p_ambient) lies on the adiabat, K = p_ambient (amount /
  p_ambient)^gamma.

Along a path the load factor t pumps the gas in: K(t) = p_t V_t^gamma with
p_t = p_ambient + t (p0 - p_ambient), V_t = V_ref (sealed), or p_t = p_ambient,
V_t = t amount / p_ambient (amount); at t = 0 the gas is at the ambient pressure in the
reference state. The gas's volume at the gauge pressure mu is

    V_gas(t, mu) = (K(t) / (mu + p_ambient))^(1/gamma),
    dV_gas/dmu = -V_gas / (gamma (mu + p_ambient)),

and the equilibrium is where the membrane's enclosed volume equals it
(``wrinkle.solvers.control``): the intersection of the gas law and the membrane's
pressure-volume curve. Units: pressures in the model's stress units, volumes its length
cubed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Gas"]


@dataclass(frozen=True)
class Gas:
    """A polytropic gas load (module docstring). ambient: absolute pressure outside (> 0);
    gamma: polytropic exponent (>= 1; 1 isothermal); p0: initial absolute pressure, or
    amount: p V at the ambient pressure (exactly one of the two, > 0). Raises ValueError
    naming the bad field."""

    ambient: float
    gamma: float = 1.0
    p0: float | None = None
    amount: float | None = None

    def __post_init__(self) -> None:
        for name in ("ambient", "gamma"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"gas: '{name}' must be a finite number > 0, got {value!r}")
        if self.gamma < 1.0:
            raise ValueError(f"gas: 'gamma' must be >= 1 (1: isothermal), got {self.gamma!r}")
        if (self.p0 is None) == (self.amount is None):
            raise ValueError("gas: give exactly one of 'p0' (initial pressure) and 'amount'")
        name = "p0" if self.p0 is not None else "amount"
        value = getattr(self, name)
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise ValueError(f"gas: '{name}' must be a finite number > 0, got {value!r}")

    def constant(self, t: float, reference_volume: float) -> float:
        """K(t) of p V^gamma = K at load factor t; reference_volume: V_ref (> 0 with p0)."""
        if self.p0 is not None:
            return (self.ambient + t * (self.p0 - self.ambient)) * reference_volume**self.gamma
        amount = t * float(self.amount or 0.0)
        return self.ambient * (amount / self.ambient) ** self.gamma

    def volume(self, t: float, reference_volume: float, gauge: float) -> tuple[float, float]:
        """V_gas at load factor t and gauge pressure ``gauge`` (> -ambient), and its
        derivative in the gauge pressure."""
        absolute = gauge + self.ambient
        volume = (self.constant(t, reference_volume) / absolute) ** (1.0 / self.gamma)
        return volume, -volume / (self.gamma * absolute)

    def energy(self, t: float, reference_volume: float, volume: float) -> float:
        """The potential of the gauge pressure at load factor t in the volume ``volume``
        (> 0), G(V) = -integral (K v^-gamma - p_ambient) dv up to a constant:
        -K ln V + p_ambient V (gamma = 1), K V^(1 - gamma) / (gamma - 1) + p_ambient V
        (gamma > 1); dG/dV is minus the gauge pressure."""
        constant = self.constant(t, reference_volume)
        if self.gamma == 1.0:
            return -constant * math.log(volume) + self.ambient * volume
        return constant * volume ** (1.0 - self.gamma) / (self.gamma - 1.0) + (
            self.ambient * volume
        )

    def pressure(self, t: float, reference_volume: float, volume: float) -> float:
        """The gauge pressure of the gas at load factor t in the volume ``volume`` (> 0)."""
        return self.constant(t, reference_volume) / volume**self.gamma - self.ambient
