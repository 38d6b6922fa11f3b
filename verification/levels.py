"""Mesh levels of a benchmark's case file: the case read with its mesh generator's divisions
replaced, for a mesh-convergence study."""

from __future__ import annotations

import os
from typing import Any

from wrinkle.case import Case, merged, read_case, read_case_data

__all__ = ["mesh_generator", "mesh_level"]


def mesh_generator(case: str | os.PathLike) -> str:
    """The name of the generator of the case file's [mesh] table ("rectangle", "annulus",
    "sphere", ...); ValueError naming the file if the mesh is not generated."""
    mesh = read_case_data(case).get("mesh")
    generators = [
        key
        for key, value in (mesh.items() if isinstance(mesh, dict) else ())
        if key != "units" and isinstance(value, dict)
    ]
    if len(generators) != 1:
        raise ValueError(
            f"{case}: [mesh]: a mesh-convergence study needs a mesh generator "
            "such as 'rectangle = {width, height, nx, ny}'"
        )
    return generators[0]


def mesh_level(
    case: str | os.PathLike, overrides: dict[str, Any] | None = None, **divisions: int
) -> Case:
    """The case file read (``read_case``) with its [mesh] generator's ``divisions`` replaced
    (e.g. ``nx=8, ny=8`` for a rectangle, ``n=16`` for a sphere) and the other tables of
    ``overrides`` merged over the file's."""
    level = {"mesh": {mesh_generator(case): divisions}}
    return read_case(case, merged(overrides, level) if overrides else level)
