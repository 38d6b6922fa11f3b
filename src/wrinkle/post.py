"""What the analysis reports per element or material point: state, directions, wrinkling
strain, stresses (``element_report``, ``material_response``).

Directions follow the paper (Roddeman et al. 1987, Part II, section 2): the wrinkle direction
n1 is the direction across the wrinkles, in which the membrane is shortened by the wrinkling
strain beta (F' = (I + beta n1 (x) n1) F); the tension direction n2 is the direction of the
uniaxial tension, along the wrinkle crests. In the reference plane they are w (with
C' = C + b w (x) w) and v, w turned by 90 degrees; in the current configuration
n1 = F C^-1 w / |F C^-1 w| and n2 = F v / |F v|. The wrinkling strain is
beta = sqrt(1 + b w.C^-1.w) - 1, from b = ((1 + beta)^2 - 1) |F^T n1|^2 and
|F^T n1|^2 = 1 / (w.C^-1.w) (docs/method.md section 4).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import ArrayLike

from wrinkle.kinematics import right_cauchy_green
from wrinkle.materials.base import Material, tangent_of
from wrinkle.wrinkling import (
    SLACK,
    STATE_NAMES,
    TAUT,
    WRINKLED,
    Wrinkling,
    WrinklingError,
    WrinklingResponse,
)

if TYPE_CHECKING:
    from wrinkle.element import ElementResult
    from wrinkle.model import Model

__all__ = [
    "ElementReport",
    "PlaneQuantities",
    "PointResponse",
    "element_report",
    "material_response",
    "nodal_average",
    "plane_quantities",
    "support_moments",
    "support_reactions",
]


def _inverse2(C: np.ndarray) -> np.ndarray:
    det = C[:, 0, 0] * C[:, 1, 1] - C[:, 0, 1] * C[:, 1, 0]
    inv = np.empty_like(C)
    inv[:, 0, 0] = C[:, 1, 1]
    inv[:, 1, 1] = C[:, 0, 0]
    inv[:, 0, 1] = -C[:, 0, 1]
    inv[:, 1, 0] = -C[:, 1, 0]
    return inv / det[:, None, None]


@dataclass
class PlaneQuantities:
    """Reported quantities of n points in the material frame (2-D).

    tension_direction: (n, 2) reference direction of the (major) tension: v if wrinkled, the
        major principal stress direction if taut, zero if slack.
    wrinkle_direction: (n, 2) reference direction w across the wrinkles; zero unless wrinkled.
    wrinkling_strain: (n,) beta >= 0; zero unless wrinkled.
    principal_stress: (n, 2) minor and major principal Cauchy stress resultants, force per
        unit current length (eigenvalues of N C / sqrt(det C)).
    """

    tension_direction: np.ndarray
    wrinkle_direction: np.ndarray
    wrinkling_strain: np.ndarray
    principal_stress: np.ndarray


def plane_quantities(C: np.ndarray, response: WrinklingResponse) -> PlaneQuantities:
    """Directions, wrinkling strain and principal stresses from C (n, 2, 2) and the response."""
    state = response.state
    N = response.stress
    phi = response.wrinkle_angle
    w = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    v = np.stack([-np.sin(phi), np.cos(phi)], axis=-1)
    major = 0.5 * np.arctan2(2.0 * N[:, 0, 1], N[:, 0, 0] - N[:, 1, 1])
    tension = np.where(
        (state == TAUT)[:, None], np.stack([np.cos(major), np.sin(major)], axis=-1), v
    )
    tension[state == SLACK] = 0.0
    wrinkle = np.where((state == WRINKLED)[:, None], w, 0.0)
    C_inv = _inverse2(C)
    wCw = np.einsum("ni,nij,nj->n", w, C_inv, w)
    beta = np.where(state == WRINKLED, np.sqrt(1.0 + response.wrinkle_parameter * wCw) - 1.0, 0.0)
    NC = np.matmul(N, C)
    half_trace = 0.5 * (NC[:, 0, 0] + NC[:, 1, 1])
    det = NC[:, 0, 0] * NC[:, 1, 1] - NC[:, 0, 1] * NC[:, 1, 0]
    root = np.sqrt(np.maximum(half_trace**2 - det, 0.0))
    area_stretch = np.sqrt(C[:, 0, 0] * C[:, 1, 1] - C[:, 0, 1] ** 2)
    principal = np.stack([half_trace - root, half_trace + root], axis=-1) / area_stretch[:, None]
    return PlaneQuantities(tension, wrinkle, beta, principal)


@dataclass
class ElementReport:
    """Per-element results of a model at one configuration (n elements).

    state: (n,) 0 taut, 1 wrinkled, 2 slack; stress: (n, 2, 2) stress resultant N, material
    frame, force per unit reference length; principal_stress: (n, 2) Cauchy resultants, force
    per unit current length; thickness: (n,); wrinkling_strain: (n,) beta;
    tension_direction, wrinkle_direction: (n, 3) unit vectors in the current configuration
    (zero where not defined); reference_tension_direction, reference_wrinkle_direction: (n, 3)
    the same in the reference configuration; cauchy_stress: (n, 3, 3) the Cauchy stress
    resultant in global axes, force per unit current length, sigma = F N F^T / J (J = sqrt
    det C, the area ratio) where taut, s t (x) t along the current tension direction t where
    wrinkled (the tension field's uniaxial stress; F would add the wrinkles' lost length),
    zero where slack: its eigenvalues in the plane are ``principal_stress``; strain: (n, 3, 3)
    the Green-Lagrange strain (C - I) / 2 in global reference axes, A^T E A; fibre_direction:
    (n, 3) the material axis 1 in the reference; area: (n,) current area.
    """

    state: np.ndarray
    stress: np.ndarray
    principal_stress: np.ndarray
    thickness: np.ndarray
    wrinkling_strain: np.ndarray
    tension_direction: np.ndarray
    wrinkle_direction: np.ndarray
    reference_tension_direction: np.ndarray
    reference_wrinkle_direction: np.ndarray
    cauchy_stress: np.ndarray
    strain: np.ndarray
    fibre_direction: np.ndarray
    area: np.ndarray


def nodal_average(triangles: np.ndarray, values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted average at each node of per-element values (n, ...) over the elements that
    share it, weights (n,) (e.g. areas): (n_nodes, ...); zero at a node no element uses."""
    n_nodes = int(triangles.max()) + 1
    flat = np.asarray(values, dtype=float).reshape(len(values), -1)
    nodes = triangles.ravel()
    weight = np.repeat(np.asarray(weights, dtype=float), 3)
    total = np.bincount(nodes, weight, minlength=n_nodes)
    sums = np.stack(
        [
            np.bincount(nodes, weight * np.repeat(flat[:, k], 3), minlength=n_nodes)
            for k in range(flat.shape[1])
        ],
        axis=1,
    )
    average = sums / np.where(total > 0, total, 1.0)[:, None]
    return average.reshape(n_nodes, *np.shape(values)[1:])


def _unit(vectors: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(vectors, axis=1)
    return vectors / np.where(length > 0, length, 1.0)[:, None]


def element_report(
    model: Model, u: np.ndarray, elements: ElementResult | None = None
) -> ElementReport:
    """Per-element results of ``model`` at displacements u, (n_dofs,); elements: the
    ``evaluate_elements(u, stiffness=False)`` of its discrete system, if the caller has it."""
    system = model.discretise()
    result = system.evaluate_elements(u, stiffness=False) if elements is None else elements
    F = result.deformation_gradient
    C = right_cauchy_green(F)
    q = plane_quantities(C, result.response)
    frame = system.geometry.frame  # (n, 2, 3)
    reference_tension = np.einsum("na,nai->ni", q.tension_direction, frame)
    reference_wrinkle = np.einsum("na,nai->ni", q.wrinkle_direction, frame)
    tension = _unit(np.einsum("nia,na->ni", F, q.tension_direction))
    wrinkle_plane = np.einsum("nab,nb->na", _inverse2(C), q.wrinkle_direction)
    wrinkle = _unit(np.einsum("nia,na->ni", F, wrinkle_plane))
    r = result.response
    area_ratio = np.sqrt(np.maximum(C[:, 0, 0] * C[:, 1, 1] - C[:, 0, 1] ** 2, 0.0))
    taut_stress = (
        np.einsum("nia,nab,njb->nij", F, r.stress, F)
        / np.where(area_ratio > 0, area_ratio, 1.0)[:, None, None]
    )
    field = q.principal_stress[:, 1, None, None] * tension[:, :, None] * tension[:, None, :]
    cauchy = np.where((r.state == TAUT)[:, None, None], taut_stress, field)
    cauchy[r.state == SLACK] = 0.0
    strain = np.einsum("nai,nab,nbj->nij", frame, 0.5 * (C - np.eye(2)), frame)
    return ElementReport(
        r.state,
        r.stress,
        q.principal_stress,
        r.thickness,
        q.wrinkling_strain,
        tension,
        wrinkle,
        reference_tension,
        reference_wrinkle,
        cauchy,
        strain,
        frame[:, 0].copy(),
        system.geometry.area * area_ratio,
    )


@dataclass
class PointResponse:
    """Response of one material point, material frame (axis 1 = fibre).

    state: "taut", "wrinkled" or "slack".
    stress: (2, 2) second Piola-Kirchhoff stress resultant N, force per unit reference length.
    tangent: (3, 3) consistent dN/dE, Voigt (11, 22, 12) with engineering shear.
    thickness: current thickness D.
    energy: relaxed strain energy per unit reference area.
    tension_direction, wrinkle_direction: (2,) reference unit vectors (zero where undefined).
    wrinkling_strain: beta of F' = (I + beta n1 (x) n1) F (Part II, eq. 12); 0 unless wrinkled.
    principal_stress: (2,) minor and major Cauchy stress resultants, force per current length.
    """

    state: str
    stress: np.ndarray
    tangent: np.ndarray
    thickness: float
    energy: float
    tension_direction: np.ndarray
    wrinkle_direction: np.ndarray
    wrinkling_strain: float
    principal_stress: np.ndarray


SINGULAR_RATIO = 1e-14  # material_response: det C / (tr C)^2 of a singular F


def material_response(material: Material | Wrinkling, F: ArrayLike) -> PointResponse:
    """Wrinkling response of ``material`` to the in-plane deformation gradient F.

    F: (2, 2) in-plane deformation gradient, or (3, 2) with the images of the material axes as
    columns, in the material frame (axis 1 = fibre direction). The material is wrapped in
    ``Wrinkling`` unless it already is one.
    """
    F = np.asarray(F, dtype=float)
    if F.shape not in ((2, 2), (3, 2)):
        raise ValueError(f"material_response: F must be shaped (2, 2) or (3, 2), got {F.shape}")
    if not np.all(np.isfinite(F)):
        raise ValueError("material_response: F must be finite")
    with np.errstate(all="ignore"):  # extreme F: every number is checked below instead
        return _material_response(material, F)


def _material_response(material: Material | Wrinkling, F: np.ndarray) -> PointResponse:
    """``material_response`` of a checked F, (2, 2) or (3, 2)."""
    C = (F.T @ F)[None]
    # singular to round-off: det C at most 1e-14 (tr C)^2 (a stretch ratio below about 1e-7)
    if not np.linalg.det(C[0]) > SINGULAR_RATIO * np.trace(C[0]) ** 2:
        raise ValueError("material_response: F is singular (the material point is collapsed)")
    wrinkling = material if isinstance(material, Wrinkling) else Wrinkling(material)
    try:
        r = wrinkling.response(C, tangent=True)
    except WrinklingError:
        raise ValueError(
            "material_response: the wrinkling conditions have no admissible solution found at "
            "this F (a state crushed across the tension)"
        ) from None
    q = plane_quantities(C, r)
    numbers = (r.stress, tangent_of(r), r.thickness, r.energy, q.principal_stress)
    if not all(np.all(np.isfinite(value)) for value in numbers if value is not None):
        raise ValueError("material_response: the response at this F is not finite")
    return PointResponse(
        state=STATE_NAMES[int(r.state[0])],
        stress=r.stress[0],
        tangent=tangent_of(r)[0],
        thickness=float(r.thickness[0]),
        energy=float(r.energy[0]),
        tension_direction=q.tension_direction[0],
        wrinkle_direction=q.wrinkle_direction[0],
        wrinkling_strain=float(q.wrinkling_strain[0]),
        principal_stress=q.principal_stress[0],
    )


class HeldDofs(Protocol):
    """A support as reactions are summed over it: a label and the dofs (k,) it holds."""

    label: str
    dofs: np.ndarray


def support_reactions(
    supports: Sequence[HeldDofs], reactions: np.ndarray
) -> dict[str, list[float]]:
    """Sum of the reactions (n_dofs,) over the dofs each support holds (supports with the
    same label together, a component they share counted once): label -> [Fx, Fy, Fz]."""
    held: dict[str, list[np.ndarray]] = {}
    for support in supports:
        held.setdefault(str(support.label), []).append(np.asarray(support.dofs).ravel())
    out = {}
    for label, dofs_list in held.items():
        dofs = np.unique(np.concatenate(dofs_list)).astype(np.int64)
        out[label] = np.bincount(dofs % 3, reactions[dofs], minlength=3).tolist()
    return out


def support_moments(
    supports: Sequence[HeldDofs], reactions: np.ndarray, positions: np.ndarray
) -> dict[str, list[float]]:
    """The moment sum (x_i - p) x R_i of each support's reactions (n_dofs,) about its point
    p (``moment_about``), with x_i the current positions (n_nodes, 3) of its nodes and R_i
    the reaction components it holds (as ``support_reactions``): label -> [Mx, My, Mz]
    (force x length), for the supports that name a point; supports sharing a label share
    the first point given."""
    held: dict[str, list[np.ndarray]] = {}
    points: dict[str, np.ndarray] = {}
    for support in supports:
        point = getattr(support, "moment_about", None)
        label = str(support.label)
        held.setdefault(label, []).append(np.asarray(support.dofs).ravel())
        if point is not None:
            points.setdefault(label, np.asarray(point, dtype=float))
    out = {}
    for label, point in points.items():
        dofs = np.unique(np.concatenate(held[label])).astype(np.int64)
        force = np.zeros((positions.shape[0], 3))
        force.reshape(-1)[dofs] = reactions[dofs]
        nodes = np.unique(dofs // 3)
        arm = positions[nodes] - point
        out[label] = np.cross(arm, force[nodes]).sum(axis=0).tolist()
    return out
