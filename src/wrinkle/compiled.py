"""Compiled (Numba) versions of the hottest loops of an iteration, used when Numba is
installed (extra ``fast``); NumPy versions of the same formulas are the fallback.

- ``element_stiffness``: A0 (B^T D B + G (x) I3) of a block of triangles, the formula of
  ``wrinkle.element.element_stiffness`` (B of ``strain_displacement``), one element at a time,
  so that B and D B stay in registers instead of (m, 3, 9) temporaries.
- ``subtract_pressure_stiffness``: the follower pressure's load stiffness taken from the
  element matrices, the loop of ``wrinkle.loads.subtract_pressure_stiffness`` (54 entries per
  element) in one pass over them instead of 54 strided ones: 0.9 -> 0.13 ms per block of
  8,192 elements.
- ``nodal_forces``: the internal nodal forces A0 F N grad psi_k of
  ``wrinkle.element.nodal_forces``, one element at a time instead of some 50 NumPy passes
  over a block: 4.7 -> 0.6 ms for 10^5 elements.
- ``add_pressure_forces``: the follower pressure's nodal forces p c / 6
  (``wrinkle.loads.pressure_forces``) summed into the global vector in the order of
  ``np.bincount``, without the (n, 9) element forces: 5.9 -> 0.7 ms for 10^5 elements.
- ``wrinkled_tangent``: the consistent tangent of the wrinkled elements
  (``wrinkle.wrinkling.Wrinkling._wrinkled_tangent``, which takes the material's stress and
  tangent at C' as arguments and calls no material): 6.9 -> 1.5 ms for 60,000 elements.
- ``scatter_add``: data[positions[e, q]] += K[e, q] for every element entry, the sum that
  ``SparsityPattern.add_to_data`` forms with ``np.bincount``.

Measured by ``benchmarks/kernels.py`` (README, Performance), 10^5 / 10^6 elements: forces and
stiffness of all elements 0.109 -> 0.088 s / 1.55 -> 0.90 s (the wrinkling response around
them stays NumPy), block-wise assembly 0.035 -> 0.009 s / 0.27 -> 0.10 s; the last three by
``benchmarks/element_evaluation.py`` on the 10^5-element airbag. All give the NumPy results
to round-off (the last four bit for bit: same operations in the same order).

Numba is imported, and the kernels compiled (about 1 s, then cached on disk, ``cache=True``),
at their first use, and they are used from MIN_ELEMENTS elements on, where they save more than
that; WRINKLE_NUMBA=1 in the environment uses them on every mesh, WRINKLE_NUMBA=0 on none.
"""

from __future__ import annotations

import functools
import importlib.util
import os
from collections.abc import Callable

import numpy as np

__all__ = [
    "MIN_ELEMENTS",
    "add_pressure_forces",
    "element_stiffness",
    "enabled",
    "installed",
    "nodal_forces",
    "scatter_add",
    "subtract_pressure_stiffness",
]

MIN_ELEMENTS = 10_000


@functools.cache
def installed() -> bool:
    """Whether Numba can be imported."""
    return importlib.util.find_spec("numba") is not None


def enabled(n_elements: int) -> bool:
    """Whether the compiled kernels serve a mesh of n_elements: Numba installed, and
    WRINKLE_NUMBA "1", or unset (or "auto") and n_elements >= MIN_ELEMENTS; never if "0"."""
    setting = os.environ.get("WRINKLE_NUMBA", "auto")
    if setting == "0" or not installed():
        return False
    return setting == "1" or n_elements >= MIN_ELEMENTS


def _element_stiffness(area, F, shape_gradient, tangent, stress, out):
    """out[e] = A0 (B^T D B + G (x) I3) for each element e; shapes as ``element_stiffness``."""
    B = np.empty((3, 9))
    DB = np.empty((3, 9))
    for e in range(area.shape[0]):
        a = area[e]
        for k in range(3):  # B of wrinkle.element.strain_displacement
            g0, g1 = shape_gradient[e, k, 0], shape_gradient[e, k, 1]
            for i in range(3):
                F0, F1 = F[e, i, 0], F[e, i, 1]
                B[0, 3 * k + i] = g0 * F0
                B[1, 3 * k + i] = g1 * F1
                B[2, 3 * k + i] = g1 * F0 + g0 * F1
        # the row's factors are read into scalars first: the compiler then keeps them in
        # registers over the loop on c (twice as fast as indexing B and D inside it)
        for r in range(3):  # A0 D B
            t0, t1, t2 = tangent[e, r, 0], tangent[e, r, 1], tangent[e, r, 2]
            for c in range(9):
                DB[r, c] = a * (t0 * B[0, c] + t1 * B[1, c] + t2 * B[2, c])
        for r in range(9):
            b0, b1, b2 = B[0, r], B[1, r], B[2, r]
            for c in range(9):
                out[e, r, c] = b0 * DB[0, c] + b1 * DB[1, c] + b2 * DB[2, c]
        N00, N11, N01 = a * stress[e, 0, 0], a * stress[e, 1, 1], a * stress[e, 0, 1]
        for k in range(3):  # geometric part, G_kl = grad psi_k . A0 N grad psi_l
            v0 = N00 * shape_gradient[e, k, 0] + N01 * shape_gradient[e, k, 1]
            v1 = N01 * shape_gradient[e, k, 0] + N11 * shape_gradient[e, k, 1]
            for m in range(3):
                G = shape_gradient[e, m, 0] * v0 + shape_gradient[e, m, 1] * v1
                for i in range(3):
                    out[e, 3 * k + i, 3 * m + i] += G


def _subtract_pressure_stiffness(K, x, pressure):
    """K[e] -= d f / d u of the follower pressure, in place; the loop of
    ``wrinkle.loads.subtract_pressure_stiffness``, one element at a time."""
    for e in range(K.shape[0]):
        q = pressure[e] / 6.0
        for l in range(3):  # w_l = x_(l+2) - x_(l+1), nodes counted mod 3
            a0 = q * (x[e, (l + 2) % 3, 0] - x[e, (l + 1) % 3, 0])
            a1 = q * (x[e, (l + 2) % 3, 1] - x[e, (l + 1) % 3, 1])
            a2 = q * (x[e, (l + 2) % 3, 2] - x[e, (l + 1) % 3, 2])
            c = 3 * l
            for r in range(0, 9, 3):
                K[e, r, c + 1] += a2
                K[e, r, c + 2] -= a1
                K[e, r + 1, c] -= a2
                K[e, r + 1, c + 2] += a0
                K[e, r + 2, c] += a1
                K[e, r + 2, c + 1] -= a0


def _nodal_forces(area, F, shape_gradient, stress, out):
    """out[e, 3 k + i] = (A0 F N grad psi_k)_i for each element e; shapes as
    ``wrinkle.element.nodal_forces``."""
    for e in range(area.shape[0]):
        a = area[e]
        N00, N11, N01 = a * stress[e, 0, 0], a * stress[e, 1, 1], a * stress[e, 0, 1]
        for i in range(3):
            F0, F1 = F[e, i, 0], F[e, i, 1]
            P0 = F0 * N00 + F1 * N01  # row i of A0 F N
            P1 = F0 * N01 + F1 * N11
            for k in range(3):
                out[e, 3 * k + i] = P0 * shape_gradient[e, k, 0] + P1 * shape_gradient[e, k, 1]


def _add_pressure_forces(forces, dofs, x, pressure):
    """forces[dofs[e, 3 k + i]] += p_e c_e[i] / 6 for k = 0, 1, 2, element by element, with
    c = (x2 - x1) x (x3 - x1) as ``wrinkle.kinematics.cross`` forms it."""
    for e in range(x.shape[0]):
        q = pressure[e] / 6.0
        a0, a1, a2 = x[e, 1, 0] - x[e, 0, 0], x[e, 1, 1] - x[e, 0, 1], x[e, 1, 2] - x[e, 0, 2]
        b0, b1, b2 = x[e, 2, 0] - x[e, 0, 0], x[e, 2, 1] - x[e, 0, 1], x[e, 2, 2] - x[e, 0, 2]
        f0 = q * (a1 * b2 - a2 * b1)
        f1 = q * (a2 * b0 - a0 * b2)
        f2 = q * (a0 * b1 - a1 * b0)
        for k in range(3):
            forces[dofs[e, 3 * k]] += f0
            forces[dofs[e, 3 * k + 1]] += f1
            forces[dofs[e, 3 * k + 2]] += f2


def _wrinkled_tangent(c, s, b, stress, D, out):
    """out[e] = the consistent dN/dE of wrinkled element e, the formula of
    ``wrinkle.wrinkling.Wrinkling._wrinkled_tangent`` in the same order of operations."""
    DM0 = np.empty(3)
    DM1 = np.empty(3)
    WD0 = np.empty(3)
    WD1 = np.empty(3)
    P0 = np.empty(3)
    P1 = np.empty(3)
    for e in range(c.shape[0]):
        ce, se, be = c[e], s[e], b[e]
        cc, ss, cs = ce * ce, se * se, ce * se
        m0, m1 = 0.5 * cc, 0.5 * ss
        bcs = be * cs
        bdm2 = be * (cc - ss)
        s0, s1, s2 = stress[e, 0, 0], stress[e, 1, 1], stress[e, 0, 1]
        for i in range(3):
            DM0[i] = bcs * (D[e, i, 1] - D[e, i, 0]) + D[e, i, 2] * bdm2
            DM1[i] = D[e, i, 0] * m0 + D[e, i, 1] * m1 + D[e, i, 2] * cs
            WD0[i] = ce * D[e, 0, i] + se * D[e, 2, i]
            WD1[i] = se * D[e, 1, i] + ce * D[e, 2, i]
        J00 = ce * DM0[0] + se * DM0[2] + (ce * s2 - se * s0)
        J01 = ce * DM1[0] + se * DM1[2]
        J10 = se * DM0[1] + ce * DM0[2] + (ce * s1 - se * s2)
        J11 = se * DM1[1] + ce * DM1[2]
        inverse_det = 1.0 / (J00 * J11 - J01 * J10)
        for j in range(3):
            P0[j] = (J11 * WD0[j] - J01 * WD1[j]) * inverse_det
            P1[j] = (J00 * WD1[j] - J10 * WD0[j]) * inverse_det
        for i in range(3):
            for j in range(i, 3):
                value = 0.5 * (
                    (D[e, i, j] - (DM0[i] * P0[j] + DM1[i] * P1[j]))
                    + (D[e, j, i] - (DM0[j] * P0[i] + DM1[j] * P1[i]))
                )
                out[e, i, j] = value
                out[e, j, i] = value


def _scatter_add(data, positions, values):
    """data[positions[e, q]] += values[e, q], (m, 81) each, in place."""
    for e in range(positions.shape[0]):
        for q in range(positions.shape[1]):
            data[positions[e, q]] += values[e, q]


_kernels: dict[str, Callable[..., None]] = {}


def _compiled(name: str):
    """The Numba-compiled version of the loop ``name`` (compiled or loaded at the first call)."""
    if not _kernels:
        import numba

        jit = numba.njit(cache=True, boundscheck=False)
        _kernels.update(
            element_stiffness=jit(_element_stiffness),
            subtract_pressure_stiffness=jit(_subtract_pressure_stiffness),
            nodal_forces=jit(_nodal_forces),
            add_pressure_forces=jit(_add_pressure_forces),
            wrinkled_tangent=jit(_wrinkled_tangent),
            scatter_add=jit(_scatter_add),
        )
    return _kernels[name]


def element_stiffness(
    area: np.ndarray,
    F: np.ndarray,
    shape_gradient: np.ndarray,
    tangent: np.ndarray,
    stress: np.ndarray,
    out: np.ndarray,
) -> np.ndarray:
    """Consistent tangent stiffness A0 (B^T D B + G (x) I3) written into out, (m, 9, 9).

    area (m,), F (m, 3, 2), shape_gradient (m, 3, 2), tangent D (m, 3, 3) Voigt,
    stress N (m, 2, 2) resultant; the formula of ``wrinkle.element.element_stiffness``.
    """
    _compiled("element_stiffness")(
        np.ascontiguousarray(area),
        np.ascontiguousarray(F),
        np.ascontiguousarray(shape_gradient),
        np.ascontiguousarray(tangent),
        np.ascontiguousarray(stress),
        out,
    )
    return out


def subtract_pressure_stiffness(K: np.ndarray, x: np.ndarray, pressure: np.ndarray) -> None:
    """K -= the follower pressure's load stiffness in place, K (m, 9, 9), x (m, 3 nodes, 3),
    pressure (m,); the formula of ``wrinkle.loads.subtract_pressure_stiffness``."""
    _compiled("subtract_pressure_stiffness")(
        K, np.ascontiguousarray(x), np.ascontiguousarray(pressure, dtype=float)
    )


def nodal_forces(
    area: np.ndarray, F: np.ndarray, shape_gradient: np.ndarray, stress: np.ndarray, out: np.ndarray
) -> np.ndarray:
    """Internal nodal forces A0 F N grad psi_k written into out, (m, 9); area (m,),
    F (m, 3, 2), shape_gradient (m, 3, 2), stress N (m, 2, 2) resultant; the formula of
    ``wrinkle.element.nodal_forces``."""
    _compiled("nodal_forces")(
        np.ascontiguousarray(area),
        np.ascontiguousarray(F),
        np.ascontiguousarray(shape_gradient),
        np.ascontiguousarray(stress),
        out,
    )
    return out


def add_pressure_forces(
    forces: np.ndarray, dofs: np.ndarray, x: np.ndarray, pressure: np.ndarray
) -> None:
    """Add the follower pressure's nodal forces of m triangles to the global vector forces
    (n_dofs,) in place: dofs (m, 9) their degrees of freedom, x (m, 3 nodes, 3) current
    coordinates, pressure (m,); ``wrinkle.loads.pressure_forces`` summed by ``np.bincount``."""
    _compiled("add_pressure_forces")(
        forces,
        np.ascontiguousarray(dofs),
        np.ascontiguousarray(x),
        np.ascontiguousarray(pressure, dtype=float),
    )


def wrinkled_tangent(
    c: np.ndarray, s: np.ndarray, b: np.ndarray, stress: np.ndarray, D: np.ndarray
) -> np.ndarray:
    """Consistent tangent dN/dE of m wrinkled elements, (m, 3, 3): w = (c, s), b (m,) each,
    stress (m, 2, 2) and D (m, 3, 3) the law at C'; the formula of
    ``wrinkle.wrinkling.Wrinkling._wrinkled_tangent``."""
    out = np.empty((c.shape[0], 3, 3))
    _compiled("wrinkled_tangent")(
        np.ascontiguousarray(c),
        np.ascontiguousarray(s),
        np.ascontiguousarray(b),
        np.ascontiguousarray(stress),
        np.ascontiguousarray(D),
        out,
    )
    return out


def scatter_add(data: np.ndarray, positions: np.ndarray, matrices: np.ndarray) -> None:
    """data[positions[e, q]] += matrices[e].ravel()[q] in place; positions (m, 81) CSR data
    indices, matrices (m, 9, 9); repeated positions are summed."""
    values = np.ascontiguousarray(matrices).reshape(positions.shape[0], positions.shape[1])
    _compiled("scatter_add")(data, np.ascontiguousarray(positions), values)
