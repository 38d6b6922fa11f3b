"""The interface every membrane material follows.

A material works on a batch of in-plane right Cauchy-Green tensors ``C`` shaped ``(n, 2, 2)``,
written in the material frame (axis 1 = fibre direction, axis 2 in the membrane plane,
axis 3 = membrane normal). Plane stress (S33 = S13 = S23 = 0) is solved inside the material,
so everything it returns is already the membrane response:

- ``energy(C)``: strain energy per unit reference area, ``w = D0 * Psi``, shape ``(n,)``;
- ``response(C)``: the membrane stress resultant ``N = 2 dw/dC`` (second Piola-Kirchhoff stress
  times reference thickness, force per unit reference length), its tangent ``dN/dE`` in Voigt
  form and the current thickness.

Voigt order for the membrane is (11, 22, 12) with the engineering shear strain 2*E12, so
``dN_voigt = tangent @ dE_voigt`` with ``dE_voigt = (dE11, dE22, 2 dE12)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = [
    "Material",
    "MembraneResponse",
    "as_cauchy_green_batch",
    "green_lagrange_voigt",
    "rotate_voigt_tangent",
    "tangent_of",
    "tangent_is_isotropic",
    "tangent_to_voigt",
    "tensor_from_voigt_stress",
    "voigt_stress",
]


@dataclass
class MembraneResponse:
    """Plane-stress membrane response of a batch of material points.

    stress: (n, 2, 2) second Piola-Kirchhoff stress resultant N = D0 S, force per unit
        reference length, material frame.
    tangent: (n, 3, 3) dN/dE in Voigt order (11, 22, 12), engineering shear; None if not asked.
    thickness: (n,) current thickness D, same length unit as the reference thickness.
    """

    stress: np.ndarray
    tangent: np.ndarray | None
    thickness: np.ndarray


class _WithTangent(Protocol):
    tangent: np.ndarray | None


def tangent_of(response: _WithTangent) -> np.ndarray:
    """The tangent (n, 3, 3) of a response that was asked for it (ValueError if it has none)."""
    if response.tangent is None:
        raise ValueError("the material response was evaluated without its tangent")
    return response.tangent


@runtime_checkable
class Material(Protocol):
    """A hyperelastic membrane material evaluated on batches (see module docstring)."""

    thickness: float

    @property
    def is_isotropic(self) -> bool:
        """Whether the in-plane response is invariant under rotation about the normal (then
        the element's fibre direction changes no result and may be left unset)."""
        ...

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Strain energy per unit reference area, (n,), for C shaped (n, 2, 2)."""
        ...

    def response(self, C: np.ndarray, tangent: bool = True) -> MembraneResponse:
        """Stress resultant, tangent and thickness for C shaped (n, 2, 2)."""
        ...


def rotate_voigt_tangent(tangent: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) membrane tangent, Voigt (11, 22, 12) with engineering shear, written in a frame
    turned by ``angle`` (radians) about the normal: T Q T^T with the stress rotation T."""
    c, s = np.cos(angle), np.sin(angle)
    T = np.array(
        [[c * c, s * s, 2 * c * s], [s * s, c * c, -2 * c * s], [-c * s, c * s, c * c - s * s]]
    )
    return T @ tangent @ T.T


def tangent_is_isotropic(tangent: np.ndarray, rtol: float = 1e-12) -> bool:
    """Whether the (3, 3) membrane tangent (Voigt (11, 22, 12)) is unchanged, to ``rtol``
    times its largest entry, by rotations of 30 and 45 degrees about the normal. The
    anisotropic parts of a plane tangent turn by 2 and 4 times the angle, so invariance under
    either rotation already means invariance under every rotation."""
    scale = np.max(np.abs(tangent))
    return all(
        np.max(np.abs(rotate_voigt_tangent(tangent, np.radians(degrees)) - tangent)) <= rtol * scale
        for degrees in (30.0, 45.0)
    )


def voigt_stress(N: np.ndarray) -> np.ndarray:
    """(n, 2, 2) symmetric tensor -> (n, 3) Voigt vector (11, 22, 12)."""
    return np.stack([N[:, 0, 0], N[:, 1, 1], N[:, 0, 1]], axis=-1)


def tensor_from_voigt_stress(s: np.ndarray) -> np.ndarray:
    """(n, 3) Voigt vector (11, 22, 12) -> (n, 2, 2) symmetric tensor."""
    out = np.empty(s.shape[:-1] + (2, 2))
    out[..., 0, 0] = s[..., 0]
    out[..., 1, 1] = s[..., 1]
    out[..., 0, 1] = s[..., 2]
    out[..., 1, 0] = s[..., 2]
    return out


def green_lagrange_voigt(C: np.ndarray) -> np.ndarray:
    """Green-Lagrange strain (C - I)/2 of (n, 2, 2) C as (n, 3) Voigt (E11, E22, 2 E12)."""
    return np.stack([0.5 * (C[:, 0, 0] - 1.0), 0.5 * (C[:, 1, 1] - 1.0), C[:, 0, 1]], axis=-1)


def as_cauchy_green_batch(C: np.ndarray, owner: str = "material") -> np.ndarray:
    """Check and return a batch of in-plane right Cauchy-Green tensors as float (n, 2, 2).

    Only C[:, 0, 0], C[:, 1, 1] and C[:, 0, 1] are read by the materials (C is taken symmetric).
    ``owner`` names the caller in the error message.
    """
    C = np.asarray(C, dtype=float)
    if C.ndim != 3 or C.shape[1:] != (2, 2):
        raise ValueError(f"{owner}: C must have shape (n, 2, 2), got {C.shape}")
    return C


def tangent_to_voigt(CC: np.ndarray) -> np.ndarray:
    """(n, 2, 2, 2, 2) tangent dN_ab/dE_cd (minor symmetric) -> (n, 3, 3) Voigt (11, 22, 12).

    With the engineering shear 2 dE12 as the third strain entry, the Voigt entries are simply
    ``T[i, j] = CC[a_i, b_i, a_j, b_j]`` with pairs (0, 0), (1, 1), (0, 1).
    """
    a = np.array([0, 1, 0])
    b = np.array([0, 1, 1])
    return CC[:, a[:, None], b[:, None], a[None, :], b[None, :]]
