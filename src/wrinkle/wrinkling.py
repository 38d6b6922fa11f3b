"""Tension-field wrapper around any membrane material: taut, wrinkled and slack elements.

Roddeman et al. (1987) replace, where the membrane would be compressed, the real deformation F
by the modified deformation F' = (I + beta n1 (x) n1) F (Part II, eq. 12) and fix the wrinkle
direction n1 and the wrinkling strain beta by the conditions that the stress carries nothing
across the wrinkles (Part II, eqs. 31-33). We use the equivalent reference-plane form of
docs/method.md section 4: with w = F^T n1 / |F^T n1| (unit, reference plane) and
b = ((1 + beta)^2 - 1) |F^T n1|^2,

    C' = F'^T F' = C + b w (x) w,        N(C') w = 0,        b >= 0,

two equations for the angle phi of w in the material frame and for b; plane stress (the third
condition, eq. 33) is solved inside the material. The stress that enters the nodal forces is
N(C') itself (the first Piola-Kirchhoff stress is F N(C'), see docs/method.md eq. 11), which is also
the gradient of Pipkin's relaxed energy w(C + b w (x) w).

The consistent tangent follows from the implicit function theorem on the two conditions
(the reference-plane counterpart of Part II, eqs. 34-35): with Voigt strain e' = e + b m(phi),
m = (w1^2/2, w2^2/2, w1 w2), g(e, phi, b) = W(phi) s(e') = N(C') w,

    J = dg/d(phi, b) = [W D' b m' + V s', W D' m],
    dN/dE = D' - D' [b m', m] J^-1 W D'.

States (Part II, section 3; docs/method.md section 5): taut if both principal stresses of the plain
law are >= 0, else wrinkled if the major principal Green-Lagrange strain measured from the
material's stress-free state C0 is > 0, else slack. C0 = I for an ordinary material; a
prestressed one (``wrinkle.materials.Prestressed``) gives its own ``stress_free_state``. With
C0 = L L^T (Cholesky), that strain is (L^-1 C L^-T - I)/2, and "not > 0" means C0 - C is
positive semidefinite: then C + A = C0 with A = C0 - C >= 0 reaches the stress-free state, the
minimum of the relaxed energy min over A >= 0 of w(C + A), so the element carries nothing
(Pipkin 1986). Slack elements get the energy and thickness of C0.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from wrinkle import compiled as kernels
from wrinkle.materials.base import Material, as_cauchy_green_batch, tangent_of
from wrinkle.materials.svk import StVenantKirchhoff

__all__ = [
    "SLACK",
    "STATE_NAMES",
    "TAUT",
    "WRINKLED",
    "Wrinkling",
    "WrinklingError",
    "WrinklingResponse",
]

TAUT, WRINKLED, SLACK = 0, 1, 2
STATE_NAMES = ("taut", "wrinkled", "slack")

_NEWTON_ITERATIONS = 40
_GRID_ANGLES = 72


# ``_compressed``: a wrinkled solution whose residual is within this many times the wrinkling
# tolerance of its own stress is kept as it is
_REFINE_SLACK = 1e3


class WrinklingError(RuntimeError):
    """The wrinkling conditions could not be solved for some elements."""

    def __init__(self, elements: np.ndarray):
        self.elements = elements
        super().__init__(
            f"wrinkling conditions not solved for {elements.size} element(s), "
            f"first: {elements[:5].tolist()}"
        )


@dataclass
class WrinklingResponse:
    """Membrane response with wrinkling, for a batch of n elements (material frame).

    state: (n,) int8, TAUT = 0, WRINKLED = 1, SLACK = 2.
    stress: (n, 2, 2) stress resultant N (force per unit reference length) that enters the
        nodal forces: plain law if taut, N(C + b w w) if wrinkled, zero if slack.
    tangent: (n, 3, 3) consistent dN/dE, Voigt (11, 22, 12); None unless asked for.
    thickness: (n,) current thickness D (for slack elements: that of the stress-free state,
        the reference thickness of an ordinary material).
    wrinkle_angle: (n,) angle phi of the reference wrinkle direction w = (cos phi, sin phi),
        radians, material frame; 0 where not wrinkled.
    wrinkle_parameter: (n,) b >= 0 of C' = C + b w (x) w; 0 where not wrinkled.
    energy: (n,) relaxed strain energy per unit reference area (for slack elements: that of
        the stress-free state, zero for an ordinary material).
    """

    state: np.ndarray
    stress: np.ndarray
    tangent: np.ndarray | None
    thickness: np.ndarray
    wrinkle_angle: np.ndarray
    wrinkle_parameter: np.ndarray
    energy: np.ndarray


def _row_norms(A: np.ndarray) -> np.ndarray:
    """Euclidean norm of each row of A (m, k), (m,) (faster than np.linalg.norm(A, axis=1))."""
    return np.sqrt(np.einsum("ij,ij->i", A, A))


def _symmetric_eigenvalues(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minor and major eigenvalues of symmetric (n, 2, 2) tensors."""
    mean = 0.5 * (T[:, 0, 0] + T[:, 1, 1])
    radius = np.hypot(0.5 * (T[:, 0, 0] - T[:, 1, 1]), T[:, 0, 1])
    return mean - radius, mean + radius


def _minor_direction_angle(T: np.ndarray) -> np.ndarray:
    """Angle (radians) of the eigenvector of the smaller eigenvalue of symmetric (n, 2, 2) T."""
    return 0.5 * np.arctan2(2.0 * T[:, 0, 1], T[:, 0, 0] - T[:, 1, 1]) + 0.5 * np.pi


def _cauchy_green(e0: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """C = I + 2E from the Voigt Green-Lagrange strain components E11, E22, 2 E12, each (n,),
    -> (n, 2, 2)."""
    C = np.empty(e0.shape + (2, 2))
    C[:, 0, 0] = 2.0 * e0 + 1.0
    C[:, 1, 1] = 2.0 * e1 + 1.0
    C[:, 0, 1] = e2
    C[:, 1, 0] = e2
    return C


def _modified_tensor(C: np.ndarray, c: np.ndarray, s: np.ndarray, b: np.ndarray) -> np.ndarray:
    """C' = C + b w (x) w, (n, 2, 2), w = (c, s) = (cos phi, sin phi), each (n,)."""
    bc, bs = b * c, b * s
    out = np.empty_like(C)
    out[:, 0, 0] = C[:, 0, 0] + bc * c
    out[:, 0, 1] = C[:, 0, 1] + bc * s
    out[:, 1, 0] = C[:, 1, 0] + bs * c
    out[:, 1, 1] = C[:, 1, 1] + bs * s
    return out


class Wrinkling:
    """Tension-field (wrinkling) wrapper around a membrane ``Material``.

    ``response(C)`` gives state, stress, consistent tangent and thickness of a batch of
    in-plane right Cauchy-Green tensors C, (n, 2, 2), material frame. A material with a
    ``stress_free_state`` C0 (2, 2) other than I (``Prestressed``) is slack where C0 - C is
    positive semidefinite (module docstring); ``slack_energy`` and ``slack_thickness`` are
    its energy and thickness at C0 (0 and the reference thickness for an ordinary material).
    """

    #: the whole response of a St Venant-Kirchhoff law by one compiled kernel where the
    #: element loops are compiled (False: only the wrinkled tangent, as before the parallel
    #: kernels of 4 December 2026)
    compiled_linear_law = True

    def __init__(self, material: Material, tolerance: float = 1e-13):
        self.material = material
        self.tolerance = tolerance
        # stress that round-off in E = (C - I)/2 alone produces: a principal stress above
        # -stress_noise is not a compression (else an undeformed membrane would wrinkle by noise)
        with np.errstate(all="ignore"):
            tangent = material.response(np.eye(2)[None]).tangent
        if tangent is None:
            raise ValueError("the material gives no tangent")
        if not np.all(np.isfinite(tangent)):
            raise ValueError(
                "the material's stiffness is not finite in double precision (check the units "
                "of its moduli and thickness)"
            )
        #: |dN/dE| of the material at C = I, force per length
        self.reference_stiffness = float(np.linalg.norm(tangent))
        self.stress_noise = 64.0 * np.finfo(float).eps * self.reference_stiffness
        # the stress-free state C0 (a prestressed material's; I otherwise): its Cholesky
        # factor L, L^-1, and the energy and thickness that slack elements take from it
        natural = getattr(material, "stress_free_state", None)
        self._natural_factor: np.ndarray | None = None
        self._natural_inverse: np.ndarray | None = None
        self.slack_energy = 0.0
        self.slack_thickness = float(material.thickness)
        if natural is not None:
            C0 = np.asarray(natural, dtype=float).reshape(1, 2, 2)
            self._natural_factor = np.linalg.cholesky(C0[0])
            self._natural_inverse = np.linalg.inv(self._natural_factor)
            self.slack_energy = float(material.energy(C0)[0])
            self.slack_thickness = float(material.response(C0, tangent=False).thickness[0])
        # a St Venant-Kirchhoff law (linear, no stress-free state of its own) has the whole
        # response compiled (``wrinkle.compiled.svk_wrinkling``): (D0 Q, Q, R, D0)
        self._linear_law: tuple | None = None
        if type(material) is StVenantKirchhoff and natural is None:
            Q = np.ascontiguousarray(material.plane_stress_stiffness)
            self._linear_law = (
                material.thickness * Q,
                Q,
                np.ascontiguousarray(material.out_of_plane_strain[0]),
                float(material.thickness),
            )

    @property
    def thickness(self) -> float:
        return self.material.thickness

    @property
    def is_isotropic(self) -> bool:
        """The material's ``is_isotropic`` (False for a material that does not say)."""
        return bool(getattr(self.material, "is_isotropic", False))

    def energy(self, C: np.ndarray) -> np.ndarray:
        """Relaxed strain energy per unit reference area, (n,)."""
        return self.response(C, tangent=False).energy

    def classify(self, C: np.ndarray, plain_stress: np.ndarray) -> np.ndarray:
        """Element states by the paper's criterion (docs/method.md section 5), the strain
        measured from the stress-free state, (n,) int8; stresses and strains at the level of
        round-off count as zero."""
        state = np.full(C.shape[0], TAUT, dtype=np.int8)
        minor_stress, _ = _symmetric_eigenvalues(plain_stress)
        _, major_stretch = _symmetric_eigenvalues(self._from_stress_free(C))
        compressed = minor_stress < -self.stress_noise
        state[compressed] = WRINKLED
        state[compressed & (major_stretch <= 1.0 + 64.0 * np.finfo(float).eps)] = SLACK
        return state

    def _from_stress_free(self, C: np.ndarray) -> np.ndarray:
        """C measured from the stress-free state C0 = L L^T: L^-1 C L^-T, (n, 2, 2) (C itself
        where C0 = I); its eigenvalues are the squared stretches from C0."""
        if self._natural_inverse is None:
            return C
        (a, _), (b, c) = self._natural_inverse
        out = np.empty_like(C)
        out[:, 0, 0] = a * a * C[:, 0, 0]
        out[:, 0, 1] = out[:, 1, 0] = a * (b * C[:, 0, 0] + c * C[:, 0, 1])
        out[:, 1, 1] = b * b * C[:, 0, 0] + 2.0 * b * c * C[:, 0, 1] + c * c * C[:, 1, 1]
        return out

    def _least_stretched_angle(self, C: np.ndarray) -> np.ndarray:
        """Angle (radians) of the reference direction w stretched least from the stress-free
        state, (n,): the minor principal direction of C where C0 = I, else L v for the minor
        eigenvector v of L^-1 C L^-T (so that C + b w (x) w is C0 + L (. + b' v (x) v) L^T)."""
        angle = _minor_direction_angle(self._from_stress_free(C))
        if self._natural_factor is None:
            return angle
        (l00, _), (l10, l11) = self._natural_factor
        c, s = np.cos(angle), np.sin(angle)
        return np.arctan2(l10 * c + l11 * s, l00 * c)

    def response(
        self, C: np.ndarray, tangent: bool = True, compiled: bool = False
    ) -> WrinklingResponse:
        """Relaxed response at C (n, 2, 2), material frame: state, stress, consistent tangent
        (if ``tangent``), thickness, wrinkle angle and parameter, energy. compiled: by the
        Numba kernels (the same formulas): the whole response of a St Venant-Kirchhoff law
        (``wrinkle.compiled.svk_wrinkling``; the elements it leaves, by the code below), the
        wrinkled elements' tangent of any other law."""
        if compiled and self.has_compiled_response:
            return self._compiled_response(C, tangent)
        n = C.shape[0]
        plain = self.material.response(C, tangent=tangent)
        state = self.classify(C, plain.stress)
        stress = plain.stress.copy()
        plain_tangent = tangent_of(plain) if tangent else None
        stiffness = None if plain_tangent is None else plain_tangent.copy()
        thickness = plain.thickness.copy()
        phi = np.zeros(n)
        b = np.zeros(n)

        # the plain energy is needed only where the element is taut
        energy = np.zeros(n)
        taut = state == TAUT
        energy[taut] = self.material.energy(C[taut])

        slack = state == SLACK
        stress[slack] = 0.0
        if stiffness is not None:
            stiffness[slack] = 0.0
        thickness[slack] = self.slack_thickness
        energy[slack] = self.slack_energy

        wrinkled = np.flatnonzero(state == WRINKLED)
        if wrinkled.size:
            Cw = C[wrinkled]
            plain_tangent_w = None if plain_tangent is None else plain_tangent[wrinkled]
            try:
                phi_w, b_w, (c_w, s_w), g_tolerance = self._solve_conditions(
                    Cw, plain.stress[wrinkled], plain_tangent_w
                )
                C_modified = _modified_tensor(Cw, c_w, s_w, b_w)
                modified = self.material.response(C_modified, tangent=tangent)
                loose = self._compressed(c_w, s_w, modified.stress, g_tolerance)
                if np.any(loose):  # rare: crushed states (``_refine``)
                    rows = np.flatnonzero(loose)
                    phi_r, b_r = phi_w[rows], b_w[rows]
                    Cr = Cw[rows]
                    e_rows = _voigt_strain(Cr)
                    tangent_r = (
                        tangent_of(self.material.response(Cr, tangent=True))
                        if plain_tangent_w is None
                        else plain_tangent_w[rows]
                    )
                    self._refine(
                        e_rows,
                        phi_r,
                        b_r,
                        g_tolerance[rows],
                        plain.stress[wrinkled][rows],
                        tangent_r,
                    )
                    phi_w[rows], b_w[rows] = np.mod(phi_r, np.pi), np.maximum(b_r, 0.0)
                    c_w[rows], s_w[rows] = np.cos(phi_w[rows]), np.sin(phi_w[rows])
                    C_modified = _modified_tensor(Cw, c_w, s_w, b_w)
                    modified = self.material.response(C_modified, tangent=tangent)
            except WrinklingError as error:  # rows of the wrinkled subset -> rows of C
                raise WrinklingError(wrinkled[error.elements]) from None
            stress[wrinkled] = modified.stress
            thickness[wrinkled] = modified.thickness
            energy[wrinkled] = self.material.energy(C_modified)
            phi[wrinkled] = phi_w
            b[wrinkled] = b_w
            if stiffness is not None:
                wrinkled_tangent = kernels.wrinkled_tangent if compiled else self._wrinkled_tangent
                stiffness[wrinkled] = wrinkled_tangent(
                    c_w, s_w, b_w, modified.stress, tangent_of(modified)
                )
        return WrinklingResponse(state, stress, stiffness, thickness, phi, b, energy)

    @property
    def has_compiled_response(self) -> bool:
        """Whether ``response(compiled=True)`` runs as one compiled kernel, element by element
        without temporaries (a plain St Venant-Kirchhoff law): a batch of any size then
        costs no more memory than its results."""
        return self.compiled_linear_law and self._linear_law is not None

    def _compiled_response(self, C: np.ndarray, tangent: bool) -> WrinklingResponse:
        """``response`` of a St Venant-Kirchhoff law by ``wrinkle.compiled.svk_wrinkling``;
        the wrinkled elements it leaves (Newton failed, or its solution inadmissible or
        compressed) by the NumPy code, with its angle search and ``_refine``."""
        law = self._linear_law
        assert law is not None
        C = as_cauchy_green_batch(C, "Wrinkling")
        *arrays, fallback = kernels.svk_wrinkling(
            C,
            law,
            self.tolerance,
            self.stress_noise,
            self.reference_stiffness,
            _REFINE_SLACK,
            _NEWTON_ITERATIONS,
            tangent,
        )
        result = WrinklingResponse(*arrays)
        rows = np.flatnonzero(fallback)
        if rows.size:
            try:
                rest = self.response(C[rows], tangent=tangent)
            except WrinklingError as error:
                raise WrinklingError(rows[error.elements]) from None
            for field in fields(result):
                array = getattr(result, field.name)
                if array is not None:
                    array[rows] = getattr(rest, field.name)
        return result

    # -- wrinkled state --------------------------------------------------------------------
    # Vectors and 2x2 / 3x3 matrices are handled as their (m,) component arrays: for batches
    # of tiny matrices, explicit multiply-adds are several times faster than einsum/matmul.
    # The wrinkle direction w = (c, s) = (cos phi, sin phi) is passed along with phi, so that
    # each angle's cosine and sine are computed once.
    def _modified_response(
        self, e: tuple, c: np.ndarray, s: np.ndarray, b: np.ndarray, tangent: bool
    ):
        """Material response at C' = C + b w (x) w from the Voigt strain e of C (components,
        each (m,)), w = (c, s), b (m,); also returns m = (w1^2/2, w2^2/2, w1 w2) and c^2, s^2
        as components."""
        cc, ss, cs = c * c, s * s, c * s
        m0, m1 = 0.5 * cc, 0.5 * ss  # m = (w1^2/2, w2^2/2, w1 w2), m2 = cs
        C = _cauchy_green(e[0] + b * m0, e[1] + b * m1, e[2] + b * cs)
        return self.material.response(C, tangent=tangent), (m0, m1, cs), (cc, ss)

    def _residual(self, e: tuple, c: np.ndarray, s: np.ndarray, b: np.ndarray):
        """g = N(C') w, as components (g0, g1), and the Voigt stress (s0, s1, s2) of C', all
        (m,); e, w = (c, s), b as ``_modified_response``."""
        modified, _, _ = self._modified_response(e, c, s, b, tangent=False)
        N = modified.stress
        s0, s1, s2 = N[:, 0, 0], N[:, 1, 1], N[:, 0, 1]
        return (c * s0 + s * s2, s * s1 + c * s2), (s0, s1, s2)  # W s

    def _residual_and_jacobian(self, e: tuple, c: np.ndarray, s: np.ndarray, b: np.ndarray):
        """g = N(C') w and J = dg/d(phi, b) of the module docstring, as components.

        e: Voigt strain components (E11, E22, 2 E12), each (m,); w = (c, s) = (cos phi,
        sin phi), b: (m,).
        Returns (g0, g1), (J00, J01, J10, J11) and the Voigt stress (s0, s1, s2) of C',
        all (m,).
        """
        modified, (m0, m1, cs), (cc, ss) = self._modified_response(e, c, s, b, tangent=True)
        N, D = modified.stress, modified.tangent
        s0, s1, s2 = N[:, 0, 0], N[:, 1, 1], N[:, 0, 1]
        g0 = c * s0 + s * s2  # W s
        g1 = s * s1 + c * s2
        # rows of W D: W = [[c, 0, s], [0, s, c]]
        D20, D21, D22 = D[:, 2, 0], D[:, 2, 1], D[:, 2, 2]
        a0 = c * D[:, 0, 0] + s * D20
        a1 = c * D[:, 0, 1] + s * D21
        a2 = c * D[:, 0, 2] + s * D22
        d0 = s * D[:, 1, 0] + c * D20
        d1 = s * D[:, 1, 1] + c * D21
        d2 = s * D[:, 1, 2] + c * D22
        # b m' = b (-cs, cs, cc - ss); V s = (c s2 - s s0, c s1 - s s2)
        bcs = b * cs
        bdm2 = b * (cc - ss)
        J00 = bcs * (a1 - a0) + a2 * bdm2 + (c * s2 - s * s0)
        J10 = bcs * (d1 - d0) + d2 * bdm2 + (c * s1 - s * s2)
        J01 = a0 * m0 + a1 * m1 + a2 * cs
        J11 = d0 * m0 + d1 * m1 + d2 * cs
        return (g0, g1), (J00, J01, J10, J11), (s0, s1, s2)

    def _newton(self, e, phi, b, g_tolerance, active, direction=None):
        """Newton iterations on the wrinkling conditions for rows ``active`` (in place);
        converged where |g| <= g_tolerance (m,) or the step is at round-off.

        direction: (cos phi, sin phi) of all rows at the start, if the caller has them.
        The iterations run on compact copies of the rows still active; a row's phi and b are
        written back when it leaves (converged, singular Jacobian or out of iterations).
        """
        converged = np.zeros(phi.shape[0], dtype=bool)
        idx = np.flatnonzero(active)
        if idx.size == phi.shape[0]:
            e_a, phi_a, b_a, tol_a = e, phi.copy(), b.copy(), g_tolerance
        else:
            e_a = tuple(component[idx] for component in e)
            phi_a, b_a, tol_a = phi[idx], b[idx], g_tolerance[idx]
            direction = None
        for _ in range(_NEWTON_ITERATIONS):
            if idx.size == 0:
                break
            c, s = (np.cos(phi_a), np.sin(phi_a)) if direction is None else direction
            direction = None
            (g0, g1), (J00, J01, J10, J11), _ = self._residual_and_jacobian(e_a, c, s, b_a)
            # J step = -g by Cramer's rule; a singular J gives a non-finite step
            with np.errstate(divide="ignore", invalid="ignore"):
                det = J00 * J11 - J01 * J10
                step_phi = (J01 * g1 - J11 * g0) / det
                step_b = (J10 * g0 - J00 * g1) / det
            ok = np.isfinite(step_phi) & np.isfinite(step_b)
            if ok.all():
                phi_a += step_phi
                b_a += step_b
            else:
                phi_a = np.where(ok, phi_a + step_phi, phi_a)
                b_a = np.where(ok, b_a + step_b, b_a)
            small = (np.abs(step_phi) <= 1e-14) & (np.abs(step_b) <= 1e-14 * (1.0 + np.abs(b_a)))
            small |= np.sqrt(g0 * g0 + g1 * g1) <= tol_a
            done = ok & small
            keep = ok & ~done
            if not keep.all():
                leaving = ~keep
                phi[idx[leaving]] = phi_a[leaving]
                b[idx[leaving]] = b_a[leaving]
                converged[idx[done]] = True
                idx = idx[keep]
                e_a = tuple(component[keep] for component in e_a)
                phi_a, b_a, tol_a = phi_a[keep], b_a[keep], tol_a[keep]
        phi[idx] = phi_a
        b[idx] = b_a
        return converged

    def _solve_conditions(
        self, C: np.ndarray, plain_stress: np.ndarray, plain_tangent: np.ndarray | None = None
    ):
        """Angle phi and parameter b of the wrinkled elements, (m,), (m,), and the direction
        (cos phi, sin phi), each (m,).

        plain_stress (m, 2, 2) and plain_tangent (m, 3, 3) are the plain law at C; the tangent
        is evaluated here if not given.
        """
        e = _voigt_strain(C)
        if plain_tangent is None:
            plain_tangent = tangent_of(self.material.response(C, tangent=True))
        # |g| can be no smaller than round-off in E = (C - I)/2 times the stiffness
        stiffness = _row_norms(plain_tangent.reshape(-1, 9))
        g_tolerance = np.maximum(
            self.tolerance * _row_norms(plain_stress.reshape(-1, 4)),
            64.0 * np.finfo(float).eps * stiffness,
        )
        # first guess: the direction of the most compressive plain stress (exact for isotropy),
        # and b from the normal condition w.N'.w = 0 linearised at b = 0. Where both plain
        # principal stresses are compressive, only the stretched direction of C can carry the
        # tension: start from the direction stretched least from the stress-free state (the
        # minor principal direction of C for an ordinary material) instead (from the stress
        # direction, Newton often ends on a compressive, inadmissible root there).
        phi = _minor_direction_angle(plain_stress)
        S00, S11, S01 = plain_stress[:, 0, 0], plain_stress[:, 1, 1], plain_stress[:, 0, 1]
        biaxial = np.flatnonzero((S00 + S11 < 0.0) & (S00 * S11 - S01 * S01 > 0.0))
        phi[biaxial] = self._least_stretched_angle(C[biaxial])
        c, s = np.cos(phi), np.sin(phi)
        b = _linearised_b(c, s, plain_stress, plain_tangent)
        converged = self._newton(e, phi, b, g_tolerance, np.ones(phi.shape, dtype=bool), (c, s))
        admissible, c, s = self._admissible(e, phi, b, g_tolerance)
        valid = converged & admissible
        if not np.all(valid):
            # safeguard: global search over the angle for the least relaxed energy, then Newton
            retry = np.flatnonzero(~valid)
            e_retry = tuple(component[retry] for component in e)
            phi[retry], b[retry] = self._angle_search(
                e_retry, plain_stress[retry], plain_tangent[retry]
            )
            converged = self._newton(e, phi, b, g_tolerance, ~valid)
            admissible, c[retry], s[retry] = self._admissible(
                e_retry, phi[retry], b[retry], g_tolerance[retry]
            )
            valid[retry] = converged[retry] & admissible
            if not np.all(valid):
                raise WrinklingError(np.flatnonzero(~valid))
        turned = np.mod(phi, np.pi)
        moved = np.flatnonzero(turned != phi)  # w -> -w: the direction is recomputed
        c[moved], s[moved] = np.cos(turned[moved]), np.sin(turned[moved])
        return turned, np.maximum(b, 0.0), (c, s), g_tolerance

    def _compressed(self, c, s, stress, g_tolerance):
        """Rows of a wrinkled solution, w = (c, s), stress N' (m, 2, 2) at C', whose |N' w| or
        compression across the tension exceeds _REFINE_SLACK times the tolerance relative to
        N' (and the round-off of the material's reference stiffness), at most the plain law's
        ``g_tolerance``, (m,) bool: where the first solve stopped short (``_refine``)."""
        s0, s1, s2 = stress[:, 0, 0], stress[:, 1, 1], stress[:, 0, 1]
        g0, g1 = c * s0 + s * s2, s * s1 + c * s2
        allowed = np.minimum(
            np.maximum(
                _REFINE_SLACK * self.tolerance * _row_norms(stress.reshape(-1, 4)),
                64.0 * np.finfo(float).eps * self.reference_stiffness,
            ),
            g_tolerance,
        )
        return (np.sqrt(g0 * g0 + g1 * g1) > allowed) | (s0 + s1 < -allowed)

    def _modified_tolerance(self, e, phi, b, g_tolerance):
        """The tolerance on |g| at the modified state C' = C + b w (x) w, (m,):
        max(tolerance |N'|, 64 eps |D'|), at most ``g_tolerance`` (the plain law's)."""
        modified, _, _ = self._modified_response(e, np.cos(phi), np.sin(phi), b, tangent=True)
        tolerance = np.maximum(
            self.tolerance * _row_norms(modified.stress.reshape(-1, 4)),
            64.0 * np.finfo(float).eps * _row_norms(modified.tangent.reshape(-1, 9)),
        )
        return np.minimum(tolerance, g_tolerance)

    def _unresolved(self, e, phi, b, tolerance):
        """Rows whose solution misses ``tolerance`` or is not admissible under it, (m,) bool."""
        c, s = np.cos(phi), np.sin(phi)
        (g0, g1), (s0, s1, _) = self._residual(e, c, s, b)
        return ~(
            (np.sqrt(g0 * g0 + g1 * g1) <= tolerance) & (s0 + s1 >= -tolerance) & (b >= -1e-12)
        )

    def _refine(self, e, phi, b, g_tolerance, plain_stress, plain_tangent):
        """Solve again (phi, b in place) where the solution misses the tolerance of the
        modified state (``_modified_tolerance``) or is inadmissible under it: Newton from it,
        then, where that fails, the angle search and Newton. The first tolerance is relative
        to the plain law at C, which for a crushed state (C22 -> 0) is orders of magnitude
        larger than the wrinkled stress: there it accepted a remaining compression across the
        wrinkles (the neo-Hookean sheet at F = diag(1.1, 0.01) stopped with N22 = -0.0015
        against N11 = 0.25, at F = diag(1.01, 1e-4) on a compressive root). WrinklingError
        where no admissible solution is found."""
        tolerance = self._modified_tolerance(e, phi, b, g_tolerance)
        rows = self._unresolved(e, phi, b, tolerance)
        if not np.any(rows):
            return
        self._newton(e, phi, b, tolerance, rows)
        tolerance = np.where(rows, self._modified_tolerance(e, phi, b, g_tolerance), tolerance)
        rows &= self._unresolved(e, phi, b, tolerance)
        if not np.any(rows):
            return
        retry = np.flatnonzero(rows)
        e_retry = tuple(component[retry] for component in e)
        phi[retry], b[retry] = self._angle_search(
            e_retry, plain_stress[retry], plain_tangent[retry]
        )
        tolerance[retry] = self._modified_tolerance(
            e_retry, phi[retry], b[retry], g_tolerance[retry]
        )
        self._newton(e, phi, b, tolerance, rows)
        tolerance[retry] = self._modified_tolerance(
            e_retry, phi[retry], b[retry], g_tolerance[retry]
        )
        failed = self._unresolved(e_retry, phi[retry], b[retry], tolerance[retry])
        if np.any(failed):
            raise WrinklingError(retry[failed])

    def _admissible(self, e, phi, b, g_tolerance):
        """b >= 0 and non-negative uniaxial tension at a solution, (m,) bool, and the
        direction (cos phi, sin phi) there, each (m,)."""
        c, s = np.cos(phi), np.sin(phi)
        (g0, g1), (s0, s1, _) = self._residual(e, c, s, b)
        tension = s0 + s1  # trace of the (rank-one) stress
        admissible = (
            (b >= -1e-12)
            & (tension >= -g_tolerance)
            & (np.sqrt(g0 * g0 + g1 * g1) <= 10.0 * g_tolerance)
        )
        return admissible, c, s

    def _angle_search(self, e: tuple, plain_stress: np.ndarray, plain_tangent: np.ndarray):
        """Least relaxed energy over a grid of angles (b by 1-D Newton per angle), (m,), (m,).

        e: strain components, each (m,); plain_stress (m, 2, 2), plain_tangent (m, 3, 3): the
        plain law at e.
        """
        n = e[0].shape[0]
        angles = np.linspace(0.0, np.pi, _GRID_ANGLES, endpoint=False)
        phi = np.tile(angles, n)
        e0, e1, e2 = (np.repeat(component, _GRID_ANGLES) for component in e)
        c, s = np.cos(phi), np.sin(phi)
        b = _linearised_b(
            c,
            s,
            np.repeat(plain_stress, _GRID_ANGLES, axis=0),
            np.repeat(plain_tangent, _GRID_ANGLES, axis=0),
        )
        m0, m1, m2 = 0.5 * c * c, 0.5 * s * s, c * s
        # 1-D Newton on the slope w.N'.w of the energy along b, clipped at b = 0; rows stop
        # once their update is at round-off
        idx = np.arange(b.size)
        for _ in range(30):
            bi = b[idx]
            mi0, mi1, mi2 = m0[idx], m1[idx], m2[idx]
            r = self.material.response(
                _cauchy_green(e0[idx] + bi * mi0, e1[idx] + bi * mi1, e2[idx] + bi * mi2),
                tangent=True,
            )
            slope, curvature = _directional_derivatives(mi0, mi1, mi2, r.stress, r.tangent)
            b_new = np.maximum(bi - slope / curvature, 0.0)
            b[idx] = b_new
            moving = ~(np.abs(b_new - bi) <= 4.0 * np.finfo(float).eps * (1.0 + np.abs(bi)))
            idx = idx[moving]
            if idx.size == 0:
                break
        energy = self.material.energy(_cauchy_green(e0 + b * m0, e1 + b * m1, e2 + b * m2))
        energy = energy.reshape(n, _GRID_ANGLES)
        best = np.argmin(energy, axis=1)
        rows = np.arange(n)
        return angles[best], b.reshape(n, _GRID_ANGLES)[rows, best]

    def _wrinkled_tangent(self, c, s, b, stress, D) -> np.ndarray:
        """Consistent dN/dE of wrinkled elements (module docstring), (m, 3, 3); w = (c, s) =
        (cos phi, sin phi), b (m,), stress (m, 2, 2) and D (m, 3, 3) the law at C'.

        With M = [b m', m] (3 x 2) and J = W D M + [V s, 0]:
        dN/dE = D - (D M) J^-1 (W D), symmetrised.
        """
        Dij = [[D[:, i, j] for j in range(3)] for i in range(3)]
        DM0, DM1, (J00, J01, J10, J11), inverse_det = _condition_jacobian(c, s, b, stress, Dij)
        # rows of W D
        WD0 = [c * Dij[0][j] + s * Dij[2][j] for j in range(3)]
        WD1 = [s * Dij[1][j] + c * Dij[2][j] for j in range(3)]
        # P = J^-1 W D, rows 0 and 1
        P0 = [(J11 * WD0[j] - J01 * WD1[j]) * inverse_det for j in range(3)]
        P1 = [(J00 * WD1[j] - J10 * WD0[j]) * inverse_det for j in range(3)]
        tangent = np.empty_like(D)
        for i in range(3):
            for j in range(i, 3):
                value = 0.5 * (
                    (Dij[i][j] - (DM0[i] * P0[j] + DM1[i] * P1[j]))
                    + (Dij[j][i] - (DM0[j] * P0[i] + DM1[j] * P1[i]))
                )
                tangent[:, i, j] = value
                if j != i:
                    tangent[:, j, i] = value
        return tangent

    # -- parameters of the law ---------------------------------------------------------------
    def parameter_derivative(
        self,
        C: np.ndarray,
        response: WrinklingResponse,
        plus: Material,
        minus: Material,
        step: float,
    ) -> np.ndarray:
        """dN/dp of the relaxed stress at fixed C (n, 2, 2), material frame, (n, 2, 2), for a
        parameter p of the plain law; plus and minus: the law at p + step and p - step;
        response: this wrapper's ``response`` at C (its states, wrinkle angles and parameters).

        With ds = (s(C; p + step) - s(C; p - step)) / (2 step) the law's own derivative
        (Voigt, exact to step^2): taut, ds at C; slack, zero; wrinkled, by the implicit
        function theorem on the conditions g = W s(e + b m; p) = 0 at the element's own phi
        and b, ds at C' = C + b w (x) w projected as the tangent is (module docstring):

            dN/dp = ds - D' M J^-1 W ds.

        No wrinkling condition is solved again (``response`` holds their solution).
        """
        out = np.zeros_like(C)
        taut = np.flatnonzero(response.state == TAUT)
        if taut.size:
            Ct = C[taut]
            out[taut] = (
                plus.response(Ct, tangent=False).stress - minus.response(Ct, tangent=False).stress
            ) / (2.0 * step)
        wrinkled = np.flatnonzero(response.state == WRINKLED)
        if wrinkled.size:
            phi, b = response.wrinkle_angle[wrinkled], response.wrinkle_parameter[wrinkled]
            c, s = np.cos(phi), np.sin(phi)
            Cw = _modified_tensor(C[wrinkled], c, s, b)
            modified = self.material.response(Cw, tangent=True)
            D = tangent_of(modified)
            Dij = [[D[:, i, j] for j in range(3)] for i in range(3)]
            DM0, DM1, (J00, J01, J10, J11), inverse_det = _condition_jacobian(
                c, s, b, modified.stress, Dij
            )
            dS = (
                plus.response(Cw, tangent=False).stress - minus.response(Cw, tangent=False).stress
            ) / (2.0 * step)
            ds = (dS[:, 0, 0], dS[:, 1, 1], dS[:, 0, 1])
            v0, v1 = c * ds[0] + s * ds[2], s * ds[1] + c * ds[2]  # W ds
            y0 = (J11 * v0 - J01 * v1) * inverse_det  # J^-1 W ds
            y1 = (J00 * v1 - J10 * v0) * inverse_det
            projected = [ds[i] - (DM0[i] * y0 + DM1[i] * y1) for i in range(3)]
            out[wrinkled, 0, 0] = projected[0]
            out[wrinkled, 1, 1] = projected[1]
            out[wrinkled, 0, 1] = out[wrinkled, 1, 0] = projected[2]
        return out


def _condition_jacobian(
    c: np.ndarray, s: np.ndarray, b: np.ndarray, stress: np.ndarray, Dij: list[list[np.ndarray]]
) -> tuple[
    list[np.ndarray],
    list[np.ndarray],
    tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    np.ndarray,
]:
    """The columns D M = [D b m', D m] (each three (m,) rows), J = W D M + [V s, 0] as
    (J00, J01, J10, J11) and 1 / det J of the wrinkling conditions (module docstring); w =
    (c, s), b (m,), stress (m, 2, 2) and Dij the entries of D (m, 3, 3) of the law at C'."""
    cc, ss, cs = c * c, s * s, c * s
    m0, m1 = 0.5 * cc, 0.5 * ss
    bcs = b * cs
    bdm2 = b * (cc - ss)
    s0, s1, s2 = stress[:, 0, 0], stress[:, 1, 1], stress[:, 0, 1]
    DM0 = [bcs * (Dij[i][1] - Dij[i][0]) + Dij[i][2] * bdm2 for i in range(3)]
    DM1 = [Dij[i][0] * m0 + Dij[i][1] * m1 + Dij[i][2] * cs for i in range(3)]
    J00 = c * DM0[0] + s * DM0[2] + (c * s2 - s * s0)
    J01 = c * DM1[0] + s * DM1[2]
    J10 = s * DM0[1] + c * DM0[2] + (c * s1 - s * s2)
    J11 = s * DM1[1] + c * DM1[2]
    return DM0, DM1, (J00, J01, J10, J11), 1.0 / (J00 * J11 - J01 * J10)


def _voigt_strain(C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Voigt components (E11, E22, 2 E12) of E = (C - I)/2, each (m,); C (m, 2, 2)."""
    return 0.5 * (C[:, 0, 0] - 1.0), 0.5 * (C[:, 1, 1] - 1.0), C[:, 0, 1]


def _directional_derivatives(m0, m1, m2, stress, D):
    """m.s and m.D m for Voigt m = (m0, m1, m2), (n,) each, stress (n, 2, 2), D (n, 3, 3)."""
    slope = m0 * stress[:, 0, 0] + m1 * stress[:, 1, 1] + m2 * stress[:, 0, 1]
    curvature = (
        m0 * (D[:, 0, 0] * m0 + D[:, 0, 1] * m1 + D[:, 0, 2] * m2)
        + m1 * (D[:, 1, 0] * m0 + D[:, 1, 1] * m1 + D[:, 1, 2] * m2)
        + m2 * (D[:, 2, 0] * m0 + D[:, 2, 1] * m1 + D[:, 2, 2] * m2)
    )
    return slope, curvature


def _linearised_b(c: np.ndarray, s: np.ndarray, stress: np.ndarray, D: np.ndarray) -> np.ndarray:
    """b solving w.N(e + b m).w = 0 to first order in b, clipped at 0, (m,); w = (c, s).

    stress (m, 2, 2) and D (m, 3, 3): the plain law at e.
    """
    slope, curvature = _directional_derivatives(0.5 * c * c, 0.5 * s * s, c * s, stress, D)
    return np.maximum(-slope / curvature, 0.0)
