"""Shared fixtures: every membrane material, with the fibre orientation it is tested in."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from wrinkle.materials import Material, MooneyRivlin, NeoHookean, Ogden, StVenantKirchhoff

REFERENCE_THICKNESS = 0.1


# a unit square on a 2 x 2 mesh, its bottom edge held and its top edge moved: the base that
# the case-file tests edit into bad inputs (test_cli, test_bad_input, test_properties)
SQUARE_CASE = """
[mesh]
rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}

[material]
model = "svk"
E = 1000.0
nu = 0.3
thickness = 0.01

[[support]]
nodes = "y == 0"
fix = ["x", "y", "z"]

[[support]]
nodes = "y == 1"
displacement = [0.05, 0.02, 0.0]
"""


def sheet_case(nx: int = 2, top: str = "[0.05, 0.02, 0.0]", steps: int = 1) -> str:
    """SQUARE_CASE's sheet on an nx x nx mesh, its supports labelled "bottom" and "top",
    the top edge moved by ``top``, in ``steps`` load steps."""
    case = SQUARE_CASE.replace("nx = 2, ny = 2", f"nx = {nx}, ny = {nx}")
    case = case.replace('nodes = "y == 0"', 'label = "bottom"\nnodes = "y == 0"')
    case = case.replace('nodes = "y == 1"', 'label = "top"\nnodes = "y == 1"')
    case = case.replace("displacement = [0.05, 0.02, 0.0]", f"displacement = {top}")
    return case + f"\n[solver]\nsteps = {steps}\n"


def random_spd_stiffness(seed: int = 5) -> np.ndarray:
    """A general 6x6 SPD stiffness H = A A^T + 2 I, A standard normal: it couples every
    in-plane and out-of-plane component (no material symmetry at all)."""
    A = np.random.default_rng(seed).normal(size=(6, 6))
    return A @ A.T + 2.0 * np.eye(6)


@dataclass(frozen=True)
class MaterialCase:
    """A material and the fibre orientation (direction projected on each element, then turned
    by ``fibre_angle`` radians about the normal) that the element tests use with it."""

    name: str
    material: Material
    fibre_direction: tuple[float, float, float]
    fibre_angle: float


def material_cases() -> list[MaterialCase]:
    D0 = REFERENCE_THICKNESS
    return [
        MaterialCase(
            "svk_isotropic",
            StVenantKirchhoff.isotropic(E=2.0, nu=0.3, thickness=D0),
            (1.0, 0.0, 0.0),
            0.0,
        ),
        MaterialCase(
            "svk_transversely_isotropic",
            StVenantKirchhoff.transversely_isotropic(
                E_L=5.0, E_T=1.0, nu_LT=0.3, nu_TT=0.3, G_LT=1.0 / 2.6, thickness=D0
            ),
            (1.0, 0.5, 0.2),
            0.4,  # off-axis fibres: about 0.86 rad from the x axis
        ),
        MaterialCase(
            "svk_general",
            StVenantKirchhoff(random_spd_stiffness(), thickness=D0),
            (0.3, 1.0, 0.0),
            -0.3,
        ),
        MaterialCase(
            "neo_hookean_incompressible", NeoHookean(mu=1.5, thickness=D0), (1.0, 0.0, 0.0), 0.0
        ),
        MaterialCase(
            "neo_hookean_compressible",
            NeoHookean(mu=1.5, thickness=D0, lmbda=4.0),
            (0.0, 1.0, 0.0),
            0.7,
        ),
        MaterialCase(
            "mooney_rivlin",
            MooneyRivlin(C10=0.6, C01=0.15, thickness=D0),
            (1.0, 0.0, 0.0),
            0.0,
        ),
        MaterialCase(
            "ogden",
            Ogden(mu=[0.63, 0.0012, -0.01], alpha=[1.3, 5.0, -2.0], thickness=D0),
            (0.0, 1.0, 0.0),
            0.3,
        ),
    ]


MATERIAL_CASES = material_cases()


@pytest.fixture(params=MATERIAL_CASES, ids=[case.name for case in MATERIAL_CASES])
def material_case(request) -> MaterialCase:
    """Each material of the package, in turn."""
    return request.param
