"""Compiled (Numba) versions of the hottest loops of an iteration, used when Numba is
installed (extra ``fast``); NumPy versions of the same formulas are the fallback.

- ``svk_wrinkling``: the whole relaxed response of a St Venant-Kirchhoff law
  (``wrinkle.wrinkling.Wrinkling.response``: the states, the wrinkling conditions solved by
  Newton's method from the same first guess, the tests of the solution, the modified state's
  stress, thickness, energy and consistent tangent), one element at a time in parallel; the
  same states, the values to round-off. The
  rare element it does not resolve is left to the NumPy code, with its angle search and
  ``_refine``. Measured in a solve by ``benchmarks/rectangle_speed.py`` (docs/performance.md,
  "OpenBLAS's threads").
- ``element_stiffness``: A0 (B^T D B + G (x) I3) of a block of triangles, the formula of
  ``wrinkle.element.element_stiffness`` (B of ``strain_displacement``), one element at a time,
  so that B and D B stay in registers instead of (m, 3, 9) temporaries; in parallel over
  chunks of 256 elements.
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
- ``asymmetry``: |A - A^T| and |A| of the symmetry check of a matrix with follower loads
  (``wrinkle.solvers.linear.SymmetryCheck``) in one parallel pass over its values.
- ``assemble_stiffness``: the element matrices (``element_stiffness`` minus the pressure
  stiffness) formed and added into the CSR data at once, without an (m, 9, 9) array, in
  parallel over chunks of elements that share no node (``wrinkle.assembly.chunk_colouring``),
  leaving out the rows and columns of constrained components that the caller zeroes: what
  a solve's evaluation does (``wrinkle.system.StepProblem.evaluate``); the element stiffness
  and its serial scatter took 25 ms of an evaluation of the 320 x 160 sheared rectangle,
  this 7.5 ms (docs/notes/2026-12-evaluation-speed.md).
- ``assemble_vector``: the element forces summed into the global vector over the same
  coloured chunks, in parallel (``SparsityPattern.assemble_vector``); ``assemble_laplacian``:
  the step metric (``DiscreteSystem.step_metric``) added over them likewise.
- ``deformation_gradient`` (F and C in one pass) and ``element_coordinates``: the NumPy
  formulas element by element in parallel, bit for bit; ``pressure_work``: the pressure's
  work p V (``wrinkle.loads.pressure_volume``) summed in parallel.
- ``put``, ``take``, ``any_nonzero``, ``sum_take``, ``sum_any_nonzero`` and
  ``add_unique``: the passes over a matrix's values between an evaluation and a
  factorisation (constrained rows zeroed, the free block and the upper triangle of K + theta
  M taken in the pass that sums them, the constant bending stiffness added), in parallel and
  without NumPy's temporaries; ``transpose_positions``: where each entry's transpose is
  stored, for the symmetry check.

Measured by ``benchmarks/kernels.py`` (README, Performance), 10^5 / 10^6 elements, before
``svk_wrinkling`` and the parallel loops: forces and stiffness of all elements 0.109 -> 0.088
s / 1.55 -> 0.90 s (the wrinkling response around them NumPy then), block-wise assembly 0.035
-> 0.009 s / 0.27 -> 0.10 s; ``add_pressure_forces``, ``wrinkled_tangent`` and
``scatter_add`` by ``benchmarks/element_evaluation.py`` on the 10^5-element airbag. All give
the NumPy results to round-off; ``nodal_forces``, ``subtract_pressure_stiffness``,
``add_pressure_forces`` and ``wrinkled_tangent`` bit for bit (the same operations in the
same order). ``svk_wrinkling`` follows the NumPy code's formulas step by step, but its
sums of squares and Numba's ``arctan2`` differ from NumPy's in the last bit.

``svk_wrinkling``, ``element_stiffness``, ``nodal_forces``, ``asymmetry``,
``assemble_stiffness`` and the kernels after it run on all of Numba's threads (one a core,
or ``NUMBA_NUM_THREADS``), the others on one. The parallel loops gain only where nothing
else keeps the cores busy: during a solve, OpenBLAS's idle threads are kept from
spinning (``wrinkle.threads``).

Numba is imported, and the kernels compiled (a few seconds, then cached on disk,
``cache=True``), at their first use, and they are used from MIN_ELEMENTS elements on, where
they save more than that; WRINKLE_NUMBA=1 in the environment uses them on every mesh,
WRINKLE_NUMBA=0 on none.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = [
    "MIN_ELEMENTS",
    "asymmetry",
    "add_pressure_forces",
    "add_unique",
    "assemble_laplacian",
    "assemble_stiffness",
    "assemble_vector",
    "deformation_gradient",
    "element_coordinates",
    "element_stiffness",
    "enabled",
    "installed",
    "nodal_forces",
    "pressure_work",
    "put",
    "serves_matrix",
    "sum_any_nonzero",
    "sum_take",
    "take",
    "transpose_positions",
    "any_nonzero",
    "scatter_add",
    "subtract_pressure_stiffness",
    "svk_wrinkling",
]

MIN_ELEMENTS = 10_000
# elements per task of the kernels that run in parallel over chunks
_CHUNK = 256

# numba.prange once the kernels are compiled (``_compiled``); the loops over elements that
# use it run on all of Numba's threads
prange = range


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


def serves_matrix(n_unknowns: int) -> bool:
    """Whether the compiled kernels serve the matrices of n_unknowns unknowns: those of a
    mesh of about 2/3 as many triangles (3 unknowns a node, twice as many triangles as
    nodes; ``enabled``)."""
    return enabled(2 * n_unknowns // 3)


def _element_stiffness(area, F, shape_gradient, tangent, stress, out):
    """out[e] = A0 (B^T D B + G (x) I3) for each element e; shapes as ``element_stiffness``.
    In parallel over chunks of _CHUNK elements, each with its own B and D B."""
    n = area.shape[0]
    for chunk in prange((n + _CHUNK - 1) // _CHUNK):
        B = np.empty((3, 9))
        DB = np.empty((3, 9))
        G = np.empty((3, 3))
        for e in range(chunk * _CHUNK, min(n, (chunk + 1) * _CHUNK)):
            _element_stiffness_at(e, area, F, shape_gradient, tangent, stress, B, DB, G, out[e])


def _element_stiffness_at(e, area, F, shape_gradient, tangent, stress, B, DB, G, out):
    """out (9, 9) = element e's matrix of ``_element_stiffness``, with B and DB (3, 9) and
    G (3, 3) as scratch."""
    _strain_factors_at(e, area, F, shape_gradient, tangent, B, DB)
    for r in range(9):
        b0, b1, b2 = B[0, r], B[1, r], B[2, r]
        for c in range(9):
            out[r, c] = b0 * DB[0, c] + b1 * DB[1, c] + b2 * DB[2, c]
    _geometric_factors_at(e, area, shape_gradient, stress, G)
    for k in range(3):
        for m in range(3):
            for i in range(3):
                out[3 * k + i, 3 * m + i] += G[k, m]


def _geometric_factors_at(e, area, shape_gradient, stress, G):
    """G (3, 3) of element e, written into G: G_kl = grad psi_k . A0 N grad psi_l, its
    geometric (initial-stress) matrix being G (x) I3. Inlined by Numba where it is called
    (``_make_kernels``)."""
    a = area[e]
    N00, N11, N01 = a * stress[e, 0, 0], a * stress[e, 1, 1], a * stress[e, 0, 1]
    for k in range(3):
        v0 = N00 * shape_gradient[e, k, 0] + N01 * shape_gradient[e, k, 1]
        v1 = N01 * shape_gradient[e, k, 0] + N11 * shape_gradient[e, k, 1]
        for m in range(3):
            G[k, m] = shape_gradient[e, m, 0] * v0 + shape_gradient[e, m, 1] * v1


def _strain_factors_at(e, area, F, shape_gradient, tangent, B, DB):
    """B and DB = A0 D B (3, 9) of element e, written into B and DB: entry (r, c) of the
    material part of its matrix (``_element_stiffness``) is B[:, r] . DB[:, c]. Inlined
    by Numba where it is called (``_make_kernels``)."""
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


def _subtract_pressure_stiffness(K, x, pressure):
    """K[e] -= d f / d u of the follower pressure, in place; the loop of
    ``wrinkle.loads.subtract_pressure_stiffness``, one element at a time."""
    for e in range(K.shape[0]):
        _subtract_pressure_at(K[e], x, e, pressure[e])


def _subtract_pressure_at(K, x, e, pressure):
    """K (9, 9) -= d f / d u of the follower pressure on element e, x (m, 3 nodes, 3)."""
    q = pressure / 6.0
    for l in range(3):  # w_l = x_(l+2) - x_(l+1), nodes counted mod 3
        a0 = q * (x[e, (l + 2) % 3, 0] - x[e, (l + 1) % 3, 0])
        a1 = q * (x[e, (l + 2) % 3, 1] - x[e, (l + 1) % 3, 1])
        a2 = q * (x[e, (l + 2) % 3, 2] - x[e, (l + 1) % 3, 2])
        c = 3 * l
        for r in range(0, 9, 3):
            K[r, c + 1] += a2
            K[r, c + 2] -= a1
            K[r + 1, c] -= a2
            K[r + 1, c + 2] += a0
            K[r + 2, c] += a1
            K[r + 2, c + 1] -= a0


def _assemble_stiffness(
    data, base, step, area, F, shape_gradient, tangent, stress, x, pressure, pressed, colouring,
    kept,
):  # fmt: skip
    """data[p] += K_e[r, c] for every element e and every entry r = 3 k + i, c = 3 l + j
    with kept[e, r] and kept[e, c], at p = base[e, 3 k + l] + step[e, k] i + j (the compact
    positions of ``wrinkle.assembly.SparsityPattern``); K_e its matrix of
    ``_element_stiffness`` minus, where
    pressure[e] != 0, the follower pressure's load stiffness (``_subtract_pressure_at``),
    formed and added at once (no (m, 9, 9) array). colouring = (chunk_start, chunk_order,
    colour_start): the chunks of elements chunk_start[k]:chunk_start[k + 1] listed colour by
    colour, chunk_order[colour_start[c]:colour_start[c + 1]] those of colour c, which share
    no node: each colour's chunks are added in parallel, the colours one after the other.
    pressed: whether any pressure is not zero; if not, each element's kept entries alone are
    formed, to the same bits."""
    chunk_start, chunk_order, colour_start = colouring
    for colour in range(colour_start.size - 1):
        for k in prange(colour_start[colour], colour_start[colour + 1]):
            chunk = chunk_order[k]
            B = np.empty((3, 9))
            DB = np.empty((3, 9))
            G = np.empty((3, 3))
            K = np.empty((9, 9))
            if pressed:  # each element's whole matrix, its pressure stiffness subtracted
                for e in range(chunk_start[chunk], chunk_start[chunk + 1]):
                    _element_stiffness_at(e, area, F, shape_gradient, tangent, stress, B, DB, G, K)
                    if pressure[e] != 0.0:
                        _subtract_pressure_at(K, x, e, pressure[e])
                    for k in range(3):
                        for i in range(3):
                            r = 3 * k + i
                            if kept[e, r]:
                                row = step[e, k] * i
                                for l in range(3):
                                    p = base[e, 3 * k + l] + row
                                    for j in range(3):
                                        if kept[e, 3 * l + j]:
                                            data[p + j] += K[r, 3 * l + j]
                continue
            # no pressure: only the kept entries formed, each as _element_stiffness_at forms
            # it (the rectangle, every z held, keeps 36 of 81)
            for e in range(chunk_start[chunk], chunk_start[chunk + 1]):
                _strain_factors_at(e, area, F, shape_gradient, tangent, B, DB)
                _geometric_factors_at(e, area, shape_gradient, stress, G)
                for k in range(3):
                    for i in range(3):
                        r = 3 * k + i
                        if kept[e, r]:
                            row = step[e, k] * i
                            b0, b1, b2 = B[0, r], B[1, r], B[2, r]
                            for l in range(3):
                                p = base[e, 3 * k + l] + row
                                for j in range(3):
                                    c = 3 * l + j
                                    if kept[e, c]:
                                        value = b0 * DB[0, c] + b1 * DB[1, c] + b2 * DB[2, c]
                                        if i == j:
                                            value += G[k, l]
                                        data[p + j] += value


def _assemble_laplacian(data, base, step, area, shape_gradient, colouring):
    """data[p] += area[e] grad psi_k . grad psi_l at the diagonal entries (3 k + i, 3 l + i)
    of every element's node-pair blocks, p = base[e, 3 k + l] + (step[e, k] + 1) i: the
    assembled A0 (grad psi_k . grad psi_l) I3 of ``wrinkle.element.unit_tension_stiffness``
    (its other entries are zero), over coloured chunks as ``_assemble_stiffness``."""
    chunk_start, chunk_order, colour_start = colouring
    for colour in range(colour_start.size - 1):
        for c in prange(colour_start[colour], colour_start[colour + 1]):
            chunk = chunk_order[c]
            for e in range(chunk_start[chunk], chunk_start[chunk + 1]):
                a = area[e]
                for k in range(3):
                    g0, g1 = shape_gradient[e, k, 0], shape_gradient[e, k, 1]
                    stride = step[e, k] + 1
                    for l in range(3):
                        value = a * (g0 * shape_gradient[e, l, 0] + g1 * shape_gradient[e, l, 1])
                        p = base[e, 3 * k + l]
                        for i in range(3):
                            data[p + stride * i] += value


def _assemble_vector(out, dofs, values, colouring):
    """out[dofs[e, q]] += values[e, q] for every element e, (m, 9) each, in place: the chunks
    of elements of one colour (``_assemble_stiffness``) in parallel, the colours in turn."""
    chunk_start, chunk_order, colour_start = colouring
    for colour in range(colour_start.size - 1):
        for k in prange(colour_start[colour], colour_start[colour + 1]):
            chunk = chunk_order[k]
            for e in range(chunk_start[chunk], chunk_start[chunk + 1]):
                for q in range(dofs.shape[1]):
                    out[dofs[e, q]] += values[e, q]


def _pressure_work(x, pressure):
    """sum_e pressure[e] x1 . (x2 x x3) / 6 over the triangles x (m, 3 nodes, 3): the work
    p V of ``wrinkle.loads.pressure_volume``; in parallel."""
    total = 0.0
    for e in prange(x.shape[0]):
        c0 = x[e, 1, 1] * x[e, 2, 2] - x[e, 1, 2] * x[e, 2, 1]
        c1 = x[e, 1, 2] * x[e, 2, 0] - x[e, 1, 0] * x[e, 2, 2]
        c2 = x[e, 1, 0] * x[e, 2, 1] - x[e, 1, 1] * x[e, 2, 0]
        total += pressure[e] * ((x[e, 0, 0] * c0 + x[e, 0, 1] * c1 + x[e, 0, 2] * c2) / 6.0)
    return total


def _deformation_gradient(x, shape_gradient, F, C):
    """F (m, 3, 2) and C = F^T F (m, 2, 2) from the node coordinates x (m, 3 nodes, 3) by the
    formulas of ``wrinkle.kinematics.deformation_gradient`` and ``right_cauchy_green``, in
    their order of operations; in parallel."""
    for e in prange(x.shape[0]):
        for i in range(3):
            x1 = x[e, 0, i]
            edge2, edge3 = x[e, 1, i] - x1, x[e, 2, i] - x1
            for a in range(2):
                F[e, i, a] = edge2 * shape_gradient[e, 1, a] + edge3 * shape_gradient[e, 2, a]
        C[e, 0, 0] = F[e, 0, 0] * F[e, 0, 0] + F[e, 1, 0] * F[e, 1, 0] + F[e, 2, 0] * F[e, 2, 0]
        C[e, 1, 1] = F[e, 0, 1] * F[e, 0, 1] + F[e, 1, 1] * F[e, 1, 1] + F[e, 2, 1] * F[e, 2, 1]
        C[e, 0, 1] = F[e, 0, 0] * F[e, 0, 1] + F[e, 1, 0] * F[e, 1, 1] + F[e, 2, 0] * F[e, 2, 1]
        C[e, 1, 0] = C[e, 0, 1]


def _element_coordinates(nodes, u, triangles, x):
    """x[e, k] = nodes[triangles[e, k]] + u[triangles[e, k]], (m, 3, 3); in parallel."""
    for e in prange(triangles.shape[0]):
        for k in range(3):
            node = triangles[e, k]
            for i in range(3):
                x[e, k, i] = nodes[node, i] + u[node, i]


def _put(data, positions, value):
    """data[positions] = value, in parallel."""
    for j in prange(positions.shape[0]):
        data[positions[j]] = value


def _add_unique(data, positions, values):
    """data[positions] += values for positions without repeats, in parallel."""
    for j in prange(positions.shape[0]):
        data[positions[j]] += values[j]


def _take(data, positions, out):
    """out = data[positions], in parallel."""
    for j in prange(positions.shape[0]):
        out[j] = data[positions[j]]


def _any_nonzero(data, positions):
    """Whether data[positions] has an entry that is not zero (NaN counts), in parallel."""
    count = 0
    for j in prange(positions.shape[0]):
        if data[positions[j]] != 0.0:
            count += 1
    return count > 0


def _sum_take(data, other, factor, flagged, shift, positions, out):
    """out = data[positions] + factor other[positions], plus shift where flagged[positions];
    in parallel."""
    for j in prange(positions.shape[0]):
        p = positions[j]
        value = data[p] + factor * other[p]
        if flagged[p]:
            value += shift
        out[j] = value


def _sum_any_nonzero(data, other, factor, flagged, shift, positions):
    """Whether the values of ``_sum_take`` at positions have an entry that is not zero (NaN
    counts), in parallel."""
    count = 0
    for j in prange(positions.shape[0]):
        p = positions[j]
        value = data[p] + factor * other[p]
        if flagged[p]:
            value += shift
        if value != 0.0:
            count += 1
    return count > 0


def _transpose_positions(indptr, indices, out):
    """out[p] = the position of entry (j, i) for each entry p = (i, j) of a CSR pattern with
    sorted indices, by bisection in row j; -1 where (j, i) is not stored. In parallel."""
    for i in prange(indptr.shape[0] - 1):
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            low, high = indptr[j], indptr[j + 1]
            while low < high:
                middle = (low + high) // 2
                if indices[middle] < i:
                    low = middle + 1
                else:
                    high = middle
            out[p] = low if low < indptr[j + 1] and indices[low] == i else -1


def _nodal_forces(area, F, shape_gradient, stress, out):
    """out[e, 3 k + i] = (A0 F N grad psi_k)_i for each element e; shapes as
    ``wrinkle.element.nodal_forces``; in parallel."""
    for e in prange(area.shape[0]):
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


def _wrinkled_tangent_at(c, s, b, s0, s1, s2, D, out):
    """out (3, 3) = the consistent dN/dE of one wrinkled element, the formula of
    ``wrinkle.wrinkling.Wrinkling._wrinkled_tangent`` in the same order of operations:
    w = (c, s), b, the Voigt stress (s0, s1, s2) and D (3, 3) of the law at C'."""
    cc, ss, cs = c * c, s * s, c * s
    m0, m1 = 0.5 * cc, 0.5 * ss
    bcs = b * cs
    bdm2 = b * (cc - ss)
    # the columns D M = [D b m', D m] and the rows of W D, each as a 3-tuple
    DM0 = (
        bcs * (D[0, 1] - D[0, 0]) + D[0, 2] * bdm2,
        bcs * (D[1, 1] - D[1, 0]) + D[1, 2] * bdm2,
        bcs * (D[2, 1] - D[2, 0]) + D[2, 2] * bdm2,
    )
    DM1 = (
        D[0, 0] * m0 + D[0, 1] * m1 + D[0, 2] * cs,
        D[1, 0] * m0 + D[1, 1] * m1 + D[1, 2] * cs,
        D[2, 0] * m0 + D[2, 1] * m1 + D[2, 2] * cs,
    )
    WD0 = (c * D[0, 0] + s * D[2, 0], c * D[0, 1] + s * D[2, 1], c * D[0, 2] + s * D[2, 2])
    WD1 = (s * D[1, 0] + c * D[2, 0], s * D[1, 1] + c * D[2, 1], s * D[1, 2] + c * D[2, 2])
    J00 = c * DM0[0] + s * DM0[2] + (c * s2 - s * s0)
    J01 = c * DM1[0] + s * DM1[2]
    J10 = s * DM0[1] + c * DM0[2] + (c * s1 - s * s2)
    J11 = s * DM1[1] + c * DM1[2]
    inverse_det = 1.0 / (J00 * J11 - J01 * J10)
    P0 = (
        (J11 * WD0[0] - J01 * WD1[0]) * inverse_det,
        (J11 * WD0[1] - J01 * WD1[1]) * inverse_det,
        (J11 * WD0[2] - J01 * WD1[2]) * inverse_det,
    )
    P1 = (
        (J00 * WD1[0] - J10 * WD0[0]) * inverse_det,
        (J00 * WD1[1] - J10 * WD0[1]) * inverse_det,
        (J00 * WD1[2] - J10 * WD0[2]) * inverse_det,
    )
    for i in range(3):
        for j in range(i, 3):
            value = 0.5 * (
                (D[i, j] - (DM0[i] * P0[j] + DM1[i] * P1[j]))
                + (D[j, i] - (DM0[j] * P0[i] + DM1[j] * P1[i]))
            )
            out[i, j] = value
            out[j, i] = value


def _wrinkled_tangent(c, s, b, stress, D, out):
    """out[e] = the consistent dN/dE of wrinkled element e (``_wrinkled_tangent_at``)."""
    for e in range(c.shape[0]):
        _wrinkled_tangent_at(
            c[e], s[e], b[e], stress[e, 0, 0], stress[e, 1, 1], stress[e, 0, 1], D[e], out[e]
        )


def _scatter_add(data, positions, values):
    """data[positions[e, q]] += values[e, q], (m, 81) each, in place."""
    for e in range(positions.shape[0]):
        for q in range(positions.shape[1]):
            data[positions[e, q]] += values[e, q]


def _svk_state_at(e, s0, s1, s2, e0, e1, e2, Q, R, D0, stress, thickness, energy):
    """Element e's stress N = (s0, s1, s2) (Voigt), thickness D0 sqrt(1 + 2 E33) with
    E33 = R . e and energy D0/2 e . Q e at the Voigt strain e = (e0, e1, e2) of a St
    Venant-Kirchhoff law (``wrinkle.materials.svk``), written into the output arrays."""
    stress[e, 0, 0], stress[e, 1, 1] = s0, s1
    stress[e, 0, 1] = stress[e, 1, 0] = s2
    E33 = R[0] * e0 + R[1] * e1 + R[2] * e2
    thickness[e] = D0 * np.sqrt(max(1.0 + 2.0 * E33, 2.2250738585072014e-308))
    energy[e] = (0.5 * D0) * (
        e0 * (Q[0, 0] * e0 + 2.0 * (Q[0, 1] * e1 + Q[0, 2] * e2))
        + e1 * (Q[1, 1] * e1 + 2.0 * Q[1, 2] * e2)
        + Q[2, 2] * (e2 * e2)
    )


def _svk_wrinkling(
    C, DQ, Q, R, D0, tolerance, noise, reference_stiffness, refine_slack, iterations_limit,
    with_tangent, state, stress, tangent, thickness, phi_out, b_out, energy, fallback,
):  # fmt: skip
    """The whole relaxed response of ``wrinkle.wrinkling.Wrinkling.response`` for a St
    Venant-Kirchhoff law (N = DQ e, DQ = D0 Q; E33 = R . e), one element at a time, in
    parallel: the classification, the plain response of taut and slack elements and, for the
    wrinkled ones, the first guess, the Newton iterations on N(C + b w (x) w) w = 0, the
    admissibility and ``_compressed`` tests, the modified state and its consistent tangent,
    step by step as the NumPy code (to round-off: sums and arctan2 differ in the last bit).
    An element whose Newton iterations fail or
    whose solution is not admissible or compressed gets fallback[e] = True and is left for
    the NumPy code (its angle search and ``_refine``)."""
    eps64 = 64.0 * 2.220446049250313e-16
    dq_norm = 0.0
    for i in range(3):
        for j in range(3):
            dq_norm += DQ[i, j] * DQ[i, j]
    dq_norm = np.sqrt(dq_norm)
    D00, D01, D02 = DQ[0, 0], DQ[0, 1], DQ[0, 2]
    D10, D11, D12 = DQ[1, 0], DQ[1, 1], DQ[1, 2]
    D20, D21, D22 = DQ[2, 0], DQ[2, 1], DQ[2, 2]
    for e in prange(C.shape[0]):
        C00, C11, C01 = C[e, 0, 0], C[e, 1, 1], C[e, 0, 1]
        e0, e1, e2 = 0.5 * (C00 - 1.0), 0.5 * (C11 - 1.0), C01
        S0 = D00 * e0 + D01 * e1 + D02 * e2
        S1 = D10 * e0 + D11 * e1 + D12 * e2
        S2 = D20 * e0 + D21 * e1 + D22 * e2
        fallback[e] = False
        minor = 0.5 * (S0 + S1) - np.hypot(0.5 * (S0 - S1), S2)
        if not minor < -noise:  # taut (also where C is not finite, as in the NumPy code)
            state[e] = 0
            _svk_state_at(e, S0, S1, S2, e0, e1, e2, Q, R, D0, stress, thickness, energy)
            phi_out[e] = 0.0
            b_out[e] = 0.0
            if with_tangent:
                for i in range(3):
                    for j in range(3):
                        tangent[e, i, j] = DQ[i, j]
            continue
        major = 0.5 * (C00 + C11) + np.hypot(0.5 * (C00 - C11), C01)
        if major <= 1.0 + eps64:  # slack
            state[e] = 2
            stress[e, 0, 0] = stress[e, 1, 1] = stress[e, 0, 1] = stress[e, 1, 0] = 0.0
            thickness[e] = D0
            energy[e] = 0.0
            phi_out[e] = 0.0
            b_out[e] = 0.0
            if with_tangent:
                for i in range(3):
                    for j in range(3):
                        tangent[e, i, j] = 0.0
            continue
        state[e] = 1
        g_tolerance = max(tolerance * np.sqrt(S0 * S0 + S1 * S1 + 2.0 * (S2 * S2)), eps64 * dq_norm)
        # first guess (``_solve_conditions``): the minor direction of the plain stress, of C
        # where both plain principal stresses are compressive; b linearised at b = 0
        if S0 + S1 < 0.0 and S0 * S1 - S2 * S2 > 0.0:
            phi = 0.5 * np.arctan2(2.0 * C01, C00 - C11) + 0.5 * np.pi
        else:
            phi = 0.5 * np.arctan2(2.0 * S2, S0 - S1) + 0.5 * np.pi
        c, s = np.cos(phi), np.sin(phi)
        m0, m1, m2 = 0.5 * c * c, 0.5 * s * s, c * s
        slope = m0 * S0 + m1 * S1 + m2 * S2
        curvature = (
            m0 * (D00 * m0 + D01 * m1 + D02 * m2)
            + m1 * (D10 * m0 + D11 * m1 + D12 * m2)
            + m2 * (D20 * m0 + D21 * m1 + D22 * m2)
        )
        b = max(-slope / curvature, 0.0)
        converged = False
        for _ in range(iterations_limit):  # ``_newton``, ``_residual_and_jacobian``
            # c, s = cos(phi), sin(phi): of the first guess, then of each new phi below
            cc, ss, cs = c * c, s * s, c * s
            m0, m1 = 0.5 * cc, 0.5 * ss
            p0 = 0.5 * ((2.0 * (e0 + b * m0) + 1.0) - 1.0)
            p1 = 0.5 * ((2.0 * (e1 + b * m1) + 1.0) - 1.0)
            p2 = e2 + b * cs
            s0 = D00 * p0 + D01 * p1 + D02 * p2
            s1 = D10 * p0 + D11 * p1 + D12 * p2
            s2 = D20 * p0 + D21 * p1 + D22 * p2
            g0 = c * s0 + s * s2
            g1 = s * s1 + c * s2
            a0 = c * D00 + s * D20
            a1 = c * D01 + s * D21
            a2 = c * D02 + s * D22
            d0 = s * D10 + c * D20
            d1 = s * D11 + c * D21
            d2 = s * D12 + c * D22
            bcs = b * cs
            bdm2 = b * (cc - ss)
            J00 = bcs * (a1 - a0) + a2 * bdm2 + (c * s2 - s * s0)
            J10 = bcs * (d1 - d0) + d2 * bdm2 + (c * s1 - s * s2)
            J01 = a0 * m0 + a1 * m1 + a2 * cs
            J11 = d0 * m0 + d1 * m1 + d2 * cs
            det = J00 * J11 - J01 * J10
            step_phi = (J01 * g1 - J11 * g0) / det
            step_b = (J10 * g0 - J00 * g1) / det
            if not (np.isfinite(step_phi) and np.isfinite(step_b)):
                break
            phi += step_phi
            b += step_b
            if (abs(step_phi) <= 1e-14 and abs(step_b) <= 1e-14 * (1.0 + abs(b))) or np.sqrt(
                g0 * g0 + g1 * g1
            ) <= g_tolerance:
                converged = True
                break
            c, s = np.cos(phi), np.sin(phi)
        if not converged:
            fallback[e] = True
            continue
        # ``_admissible``: b >= 0, non-negative tension, |g| within 10 tolerances
        c, s = np.cos(phi), np.sin(phi)
        cs = c * s
        p0 = 0.5 * ((2.0 * (e0 + b * (0.5 * (c * c))) + 1.0) - 1.0)
        p1 = 0.5 * ((2.0 * (e1 + b * (0.5 * (s * s))) + 1.0) - 1.0)
        p2 = e2 + b * cs
        s0 = D00 * p0 + D01 * p1 + D02 * p2
        s1 = D10 * p0 + D11 * p1 + D12 * p2
        s2 = D20 * p0 + D21 * p1 + D22 * p2
        g0, g1 = c * s0 + s * s2, s * s1 + c * s2
        if not (
            b >= -1e-12
            and s0 + s1 >= -g_tolerance
            and np.sqrt(g0 * g0 + g1 * g1) <= 10.0 * g_tolerance
        ):
            fallback[e] = True
            continue
        turned = np.fmod(phi, np.pi)  # np.mod(phi, pi)
        if turned < 0.0:
            turned += np.pi
        if turned != phi:
            c, s = np.cos(turned), np.sin(turned)
        b = max(b, 0.0)
        bc, bs = b * c, b * s
        p0 = 0.5 * ((C00 + bc * c) - 1.0)  # the modified state C' = C + b w (x) w
        p1 = 0.5 * ((C11 + bs * s) - 1.0)
        p2 = C01 + bc * s
        s0 = D00 * p0 + D01 * p1 + D02 * p2
        s1 = D10 * p0 + D11 * p1 + D12 * p2
        s2 = D20 * p0 + D21 * p1 + D22 * p2
        # ``_compressed``
        g0, g1 = c * s0 + s * s2, s * s1 + c * s2
        allowed = min(
            max(
                refine_slack * tolerance * np.sqrt(s0 * s0 + s1 * s1 + 2.0 * (s2 * s2)),
                eps64 * reference_stiffness,
            ),
            g_tolerance,
        )
        if np.sqrt(g0 * g0 + g1 * g1) > allowed or s0 + s1 < -allowed:
            fallback[e] = True
            continue
        _svk_state_at(e, s0, s1, s2, p0, p1, p2, Q, R, D0, stress, thickness, energy)
        phi_out[e] = turned
        b_out[e] = b
        if with_tangent:
            _wrinkled_tangent_at(c, s, b, s0, s1, s2, DQ, tangent[e])


def _asymmetry(data, transpose):
    """(sum (data - data[transpose])^2, sum data^2) in one pass, in parallel: the squared
    Frobenius norms of A - A^T and of A for CSR values data whose transposes sit at the
    positions transpose."""
    difference = 0.0
    total = 0.0
    for i in prange(data.shape[0]):
        d = data[i] - data[transpose[i]]
        difference += d * d
        total += data[i] * data[i]
    return difference, total


_kernels: dict[str, Callable[..., None]] = {}
_making = threading.Lock()


def _compiled(name: str):
    """The Numba-compiled version of the loop ``name`` (compiled or loaded at the first call;
    one thread at a time makes them)."""
    if not _kernels:
        with _making:
            if not _kernels:
                _make_kernels()
    return _kernels[name]


def _make_kernels() -> None:
    """Fill ``_kernels``. The per-element helpers the kernels call are bound to their
    compiled versions first, so that the kernels compile against them."""
    import numba

    global prange, _wrinkled_tangent_at, _element_stiffness_at, _svk_state_at
    global _subtract_pressure_at, _strain_factors_at, _geometric_factors_at
    prange = numba.prange
    jit = numba.njit(cache=True, boundscheck=False)
    parallel = numba.njit(cache=True, boundscheck=False, parallel=True)
    # (py_func: the plain function, should the helpers have been compiled before)
    _wrinkled_tangent_at = jit(getattr(_wrinkled_tangent_at, "py_func", _wrinkled_tangent_at))
    # inlined in Numba's IR: as a call, the airbag's assembly took 15 % longer
    inlined = numba.njit(cache=True, boundscheck=False, inline="always")
    _strain_factors_at = inlined(getattr(_strain_factors_at, "py_func", _strain_factors_at))
    _geometric_factors_at = inlined(
        getattr(_geometric_factors_at, "py_func", _geometric_factors_at)
    )
    _element_stiffness_at = jit(getattr(_element_stiffness_at, "py_func", _element_stiffness_at))
    _svk_state_at = jit(getattr(_svk_state_at, "py_func", _svk_state_at))
    _subtract_pressure_at = jit(getattr(_subtract_pressure_at, "py_func", _subtract_pressure_at))
    kernels: dict[str, Callable[..., None]] = {
        "asymmetry": parallel(_asymmetry),
        "svk_wrinkling": numba.njit(
            cache=True, boundscheck=False, parallel=True, error_model="numpy"
        )(_svk_wrinkling),
        "element_stiffness": parallel(_element_stiffness),
        "subtract_pressure_stiffness": jit(_subtract_pressure_stiffness),
        "nodal_forces": parallel(_nodal_forces),
        "add_pressure_forces": jit(_add_pressure_forces),
        "wrinkled_tangent": jit(_wrinkled_tangent),
        "scatter_add": jit(_scatter_add),
        "assemble_stiffness": parallel(_assemble_stiffness),
        "deformation_gradient": parallel(_deformation_gradient),
        "element_coordinates": parallel(_element_coordinates),
        "put": parallel(_put),
        "assemble_vector": parallel(_assemble_vector),
        "assemble_laplacian": parallel(_assemble_laplacian),
        "pressure_work": parallel(_pressure_work),
        "take": parallel(_take),
        "add_unique": parallel(_add_unique),
        "any_nonzero": parallel(_any_nonzero),
        "sum_take": parallel(_sum_take),
        "sum_any_nonzero": parallel(_sum_any_nonzero),
        "transpose_positions": parallel(_transpose_positions),
    }
    _kernels.update(kernels)


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


def assemble_stiffness(
    data: np.ndarray,
    positions: tuple[np.ndarray, np.ndarray],
    area: np.ndarray,
    F: np.ndarray,
    shape_gradient: np.ndarray,
    tangent: np.ndarray,
    stress: np.ndarray,
    x: np.ndarray,
    pressure: np.ndarray,
    colouring: tuple[np.ndarray, np.ndarray, np.ndarray],
    kept: np.ndarray,
) -> None:
    """Add the tangent stiffness of m elements to the CSR data (nnz,) in place, formed and
    summed element by element in parallel without an (m, 9, 9) array: A0 (B^T D B + G (x) I3)
    of ``element_stiffness`` minus the follower pressure's load stiffness
    (``subtract_pressure_stiffness``) where the pressure is not zero. positions: the
    elements' CSR data indices in compact form, block bases (m, 9) and row steps (m, 3)
    (``SparsityPattern.element_block_base``, ``element_row_step``), area (m,), F and
    shape_gradient (m, 3, 2), tangent D (m, 3, 3), stress N (m, 2, 2), x (m, 3 nodes, 3)
    current coordinates, pressure (m,); colouring: chunks of elements that share no node
    (``wrinkle.assembly.chunk_colouring``); kept (m, 9) bool: the element degrees of freedom
    whose rows and columns are added (the others' entries are left as they are: a caller
    that zeroes the constrained rows and columns need not add them; without pressure the
    others are not even formed: 5.2-5.3 ms instead of 7.1-7.2 ms on the 320 x 160 sheared
    rectangle, benchmarks/stiffness_assembly.py). The sums differ from a serial scatter's only
    in their order (round-off)."""
    base, step = positions
    _compiled("assemble_stiffness")(
        data,
        np.ascontiguousarray(base),
        np.ascontiguousarray(step),
        np.ascontiguousarray(area),
        np.ascontiguousarray(F),
        np.ascontiguousarray(shape_gradient),
        np.ascontiguousarray(tangent),
        np.ascontiguousarray(stress),
        np.ascontiguousarray(x),
        np.ascontiguousarray(pressure, dtype=float),
        bool(np.any(pressure)),
        colouring,
        np.ascontiguousarray(kept, dtype=np.bool_),
    )


def assemble_laplacian(
    data: np.ndarray,
    positions: tuple[np.ndarray, np.ndarray],
    area: np.ndarray,
    shape_gradient: np.ndarray,
    colouring: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Add the unit-tension stiffness A0 (grad psi_k . grad psi_l) I3 of m elements
    (``wrinkle.element.unit_tension_stiffness``: a Laplacian on each displacement component)
    to the CSR data (nnz,) in place, in parallel over coloured chunks of elements and without
    an (m, 9, 9) array; positions, colouring as ``assemble_stiffness``; area (m,) m^2 (times
    a tension where the caller weights the elements), shape_gradient (m, 3, 2) 1/m. The sums
    differ from a serial scatter's only in their order (round-off)."""
    base, step = positions
    _compiled("assemble_laplacian")(
        data,
        np.ascontiguousarray(base),
        np.ascontiguousarray(step),
        np.ascontiguousarray(area, dtype=float),
        np.ascontiguousarray(shape_gradient, dtype=float),
        colouring,
    )


def assemble_vector(
    n: int,
    dofs: np.ndarray,
    values: np.ndarray,
    colouring: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> np.ndarray:
    """The (n,) global vector of the element vectors values (m, 9) at the degrees of freedom
    dofs (m, 9), summed in parallel over chunks of elements that share no node (colouring:
    ``wrinkle.assembly.chunk_colouring``); np.bincount's sums up to their order."""
    out = np.zeros(n)
    _compiled("assemble_vector")(
        out, np.ascontiguousarray(dofs), np.ascontiguousarray(values, dtype=float), colouring
    )
    return out


def pressure_work(x: np.ndarray, pressure: np.ndarray) -> float:
    """sum pressure . ``wrinkle.loads.pressure_volume``(x) for triangles x (m, 3 nodes, 3)
    and pressure (m,), in parallel without temporaries (its sums in another order)."""
    return float(
        _compiled("pressure_work")(
            np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(pressure, dtype=float)
        )
    )


def deformation_gradient(
    x: np.ndarray, shape_gradient: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """F (m, 3, 2) and C = F^T F (m, 2, 2) of m triangles from their current node
    coordinates x (m, 3 nodes, 3) and shape_gradient (m, 3, 2), in parallel; the values of
    ``wrinkle.kinematics.deformation_gradient`` and ``right_cauchy_green``, bit for bit."""
    m = x.shape[0]
    F, C = np.empty((m, 3, 2)), np.empty((m, 2, 2))
    _compiled("deformation_gradient")(
        np.ascontiguousarray(x), np.ascontiguousarray(shape_gradient), F, C
    )
    return F, C


def element_coordinates(nodes: np.ndarray, u: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Current node coordinates of each triangle, (m, 3 nodes, 3): nodes (n, 3) + u (n, 3) at
    triangles (m, 3), in parallel (``wrinkle.kinematics.element_coordinates``)."""
    x = np.empty((triangles.shape[0], 3, 3))
    _compiled("element_coordinates")(
        np.ascontiguousarray(nodes, dtype=float),
        np.ascontiguousarray(u, dtype=float),
        np.ascontiguousarray(triangles),
        x,
    )
    return x


def put(data: np.ndarray, positions: np.ndarray, value: float) -> None:
    """data[positions] = value in place, in parallel; positions (k,) integers within data
    (not checked: the kernels run without bounds checks)."""
    _compiled("put")(data, np.ascontiguousarray(positions), float(value))


def add_unique(data: np.ndarray, positions: np.ndarray, values: np.ndarray) -> None:
    """data[positions] += values in place, in parallel: NumPy's fancy-indexed add, for
    positions (k,) that hold no index twice (a repeat would race); values (k,)."""
    _compiled("add_unique")(
        data, np.ascontiguousarray(positions), np.ascontiguousarray(values, dtype=float)
    )


def take(data: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """data[positions], (k,), in parallel; data (n,) float, positions (k,) integers within
    data (not checked)."""
    out = np.empty(positions.shape[0])
    _compiled("take")(np.ascontiguousarray(data, dtype=float), np.ascontiguousarray(positions), out)
    return out


def any_nonzero(data: np.ndarray, positions: np.ndarray) -> bool:
    """np.any(data[positions]) without the (k,) copy, in parallel."""
    return bool(
        _compiled("any_nonzero")(
            np.ascontiguousarray(data, dtype=float), np.ascontiguousarray(positions)
        )
    )


SumTerms = tuple[np.ndarray, np.ndarray, float, np.ndarray, float]
"""(data, other, factor, flagged, shift): the values data + factor other, then + shift where
flagged, of ``sum_take`` and ``sum_any_nonzero``; data, other (nnz,) float, flagged (nnz,)
bool."""


def sum_take(terms: SumTerms, positions: np.ndarray) -> np.ndarray:
    """The values of ``terms`` at positions, (k,), in one parallel pass without the (nnz,)
    sum, bit for bit as NumPy forms the sum: the values of K + theta M that a back-end reads
    (``wrinkle.solvers.linear.MatrixSum``); positions (k,) integers within nnz (not
    checked)."""
    out = np.empty(positions.shape[0])
    _compiled("sum_take")(*_sum_arguments(terms, positions), out)
    return out


def sum_any_nonzero(terms: SumTerms, positions: np.ndarray) -> bool:
    """np.any(``sum_take``(terms, positions)) without the copies, in parallel."""
    return bool(_compiled("sum_any_nonzero")(*_sum_arguments(terms, positions)))


def _sum_arguments(terms: SumTerms, positions: np.ndarray) -> tuple:
    """The arguments of the sum kernels, contiguous; ValueError unless the three (nnz,)
    arrays have one shape (the kernels run without bounds checks)."""
    data, other, factor, flagged, shift = terms
    if not data.shape == other.shape == flagged.shape:
        raise ValueError(
            f"sum of {data.shape} values and {other.shape} values, {flagged.shape} flags"
        )
    return (
        np.ascontiguousarray(data, dtype=float),
        np.ascontiguousarray(other, dtype=float),
        float(factor),
        np.ascontiguousarray(flagged),
        float(shift),
        np.ascontiguousarray(positions),
    )


def transpose_positions(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The position of each entry's transpose in a CSR pattern with sorted indices, (nnz,),
    -1 where the transpose is not stored; in parallel, by bisection within each row: the
    transpose map of ``wrinkle.solvers.linear.SymmetryCheck`` without SciPy's conversion to
    CSC and back and its (nnz,) temporaries (24 ms against 29 ms warm at 5.9 x 10^6 entries,
    benchmarks/matrix_passes.py)."""
    index = np.int32 if indices.shape[0] < np.iinfo(np.int32).max else np.int64
    out = np.empty(indices.shape[0], dtype=index)
    _compiled("transpose_positions")(
        np.ascontiguousarray(indptr), np.ascontiguousarray(indices), out
    )
    return out


def svk_wrinkling(
    C: np.ndarray,
    law: tuple[np.ndarray, np.ndarray, np.ndarray, float],
    tolerance: float,
    noise: float,
    reference_stiffness: float,
    refine_slack: float,
    iterations: int,
    tangent: bool,
) -> tuple[Any, ...]:
    """The relaxed response of a St Venant-Kirchhoff law at C (m, 2, 2), material frame, in
    parallel (``wrinkle.wrinkling.Wrinkling.response``): law = (D0 Q, Q, R, D0) with Q (3, 3)
    the plane-stress stiffness, R (3,) the row of E33 and D0 the thickness. Returns state
    (m,) int8, stress (m, 2, 2), tangent (m, 3, 3) or None, thickness, wrinkle angle and
    parameter, energy per unit reference area, each (m,), and fallback (m,) bool: the wrinkled
    elements this kernel did not resolve, whose other entries are undefined."""
    m = C.shape[0]
    DQ, Q, R, D0 = law
    state = np.empty(m, dtype=np.int8)
    stress = np.empty((m, 2, 2))
    out_tangent = np.empty((m, 3, 3) if tangent else (1, 3, 3))
    thickness, phi, b, energy = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    fallback = np.empty(m, dtype=np.bool_)
    _compiled("svk_wrinkling")(
        np.ascontiguousarray(C, dtype=float),
        DQ,
        Q,
        R,
        D0,
        tolerance,
        noise,
        reference_stiffness,
        refine_slack,
        iterations,
        tangent,
        state,
        stress,
        out_tangent,
        thickness,
        phi,
        b,
        energy,
        fallback,
    )
    return state, stress, out_tangent if tangent else None, thickness, phi, b, energy, fallback


def asymmetry(data: np.ndarray, transpose: np.ndarray) -> tuple[float, float]:
    """|A - A^T|_F and |A|_F of a real matrix on a structurally symmetric CSR pattern from its
    values data (nnz,) and the position in data of each entry's transpose (nnz,)
    (``wrinkle.solvers.linear.SymmetryCheck``), without the (nnz,) temporaries of NumPy."""
    difference, total = _compiled("asymmetry")(
        np.ascontiguousarray(data, dtype=float), np.ascontiguousarray(transpose)
    )
    return float(np.sqrt(difference)), float(np.sqrt(total))
