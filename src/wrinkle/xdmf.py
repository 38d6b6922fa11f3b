"""XDMF time series for large meshes (``[output] format = "xdmf"``, issue 22 item 3).

The mesh is written once, ``mesh.h5`` (datasets ``/points`` (n_nodes, 3) and ``/triangles``
(n_elements, 3)); each converged step writes ``step_NNNN.h5`` with one dataset per field
(``/point/<name>``, ``/cell/<name>``; the symmetric stress and strain tensors as XDMF's
Tensor6, their six distinct components); ``results.xdmf`` (XDMF 3) lists the steps as a
temporal collection whose grids take the mesh's topology and geometry by XInclude, the
layout of meshio's ``TimeSeriesWriter`` (so meshio's ``TimeSeriesReader`` and ParaView's
XDMF3 readers read it). Each file is written to a temporary file and moved into place
(``wrinkle.output.atomic_write``'s pattern), and results.xdmf is rewritten after each step,
so a crash leaves every finished step readable: one HDF5 file per step, not one file
appended to, because an HDF5 file being written when the process dies may be unreadable as
a whole.

Needs h5py (``pip install "wrinkle[xdmf]"``).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import ModuleType
from xml.sax.saxutils import quoteattr

import numpy as np

__all__ = [
    "COLLECTION",
    "MESH_FILE",
    "layout",
    "packed",
    "read_layout",
    "read_step",
    "require_h5py",
    "write_collection",
    "write_mesh_file",
    "write_step_file",
]

COLLECTION = "results.xdmf"
MESH_FILE = "mesh.h5"
# HDF5's own deflate filter (zlib, as meshio's .vtu) after its byte shuffle, standard filters
# that ParaView's and every HDF5 reader read: a step takes about what the .vtu's fields take
COMPRESSION = {"compression": "gzip", "compression_opts": 1, "shuffle": True}
_NO_H5PY = 'format = "xdmf" needs h5py; install it with pip install "wrinkle[xdmf]"'


def require_h5py() -> ModuleType:
    """The h5py module; ImportError with the install command if it is missing."""
    try:
        import h5py  # type: ignore[import-untyped, import-not-found, unused-ignore]
    except ImportError:  # pragma: no cover - depends on the installation
        raise ImportError(_NO_H5PY) from None
    return h5py


def write_mesh_file(path: str | os.PathLike, nodes: np.ndarray, triangles: np.ndarray) -> None:
    """mesh.h5 at ``path``: /points (n_nodes, 3) float64, /triangles (n_elements, 3) int64."""
    h5py = require_h5py()
    with h5py.File(path, "w") as handle:
        handle.create_dataset("points", data=np.asarray(nodes, dtype=np.float64), **COMPRESSION)
        handle.create_dataset(
            "triangles", data=np.asarray(triangles, dtype=np.int64), **COMPRESSION
        )


# the upper triangle of a symmetric 3 x 3 tensor stored row by row (9 components), in XDMF's
# Tensor6 order xx, xy, xz, yy, yz, zz
_UPPER = np.array([0, 1, 2, 4, 5, 8])
_FULL = np.array([0, 1, 2, 1, 3, 4, 2, 4, 5])  # the 9 components from the 6


def packed(data: Mapping[str, np.ndarray], symmetric: Sequence[str]) -> dict[str, np.ndarray]:
    """The fields as stored: each named in ``symmetric`` (a symmetric tensor, (n, 9)) as its
    upper triangle (n, 6), XDMF's Tensor6; the others as they are."""
    return {
        name: np.asarray(values)[:, _UPPER] if name in symmetric else np.asarray(values)
        for name, values in data.items()
    }


def write_step_file(
    path: str | os.PathLike,
    point_data: Mapping[str, np.ndarray],
    cell_data: Mapping[str, np.ndarray],
    symmetric: Sequence[str] = (),
) -> None:
    """One step's fields at ``path``: /point/<name> (n_nodes, ...), /cell/<name>
    (n_elements, ...), in their own types; those named in ``symmetric`` as Tensor6
    (``packed``, marked by the dataset attribute "symmetric_tensor")."""
    h5py = require_h5py()
    with h5py.File(path, "w") as handle:
        for group, data in (("point", point_data), ("cell", cell_data)):
            folder = handle.create_group(group)
            for name, values in packed(data, symmetric).items():
                dataset = folder.create_dataset(
                    name, data=np.ascontiguousarray(values), **COMPRESSION
                )
                if name in symmetric:
                    dataset.attrs["symmetric_tensor"] = 1


def read_step(
    folder: Path, step_file: str
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """(nodes, triangles, point data, cell data) of a step written by ``write_step_file``
    in ``folder`` (with its mesh.h5), symmetric tensors back to their 9 components;
    ValueError naming the file if one cannot be read."""
    h5py = require_h5py()
    arrays: list[dict[str, np.ndarray]] = []
    for name in (MESH_FILE, step_file):
        path = folder / name
        try:
            with h5py.File(path, "r") as handle:
                if name == MESH_FILE:
                    arrays.append({key: handle[key][()] for key in ("points", "triangles")})
                else:
                    for group in ("point", "cell"):
                        arrays.append(
                            {
                                key: value[()][:, _FULL]
                                if value.attrs.get("symmetric_tensor")
                                else value[()]
                                for key, value in handle[group].items()
                            }
                        )
        except (OSError, KeyError) as error:
            raise ValueError(f"{path}: cannot read it ({error})") from None
    mesh, point, cell = arrays
    return mesh["points"], mesh["triangles"], point, cell


def layout(
    point_data: Mapping[str, np.ndarray], cell_data: Mapping[str, np.ndarray]
) -> list[tuple[str, str, tuple[int, ...], np.dtype]]:
    """What results.xdmf needs of a step's fields: (group "point" or "cell", name, shape,
    dtype) each, without the arrays."""
    return [
        (group, name, np.shape(values), np.asarray(values).dtype)
        for group, data in (("point", point_data), ("cell", cell_data))
        for name, values in data.items()
    ]


def read_layout(path: str | os.PathLike) -> list[tuple[str, str, tuple[int, ...], np.dtype]]:
    """The ``layout`` of a step file written by ``write_step_file`` (its datasets' shapes
    and types, no data read); ValueError naming the file if it cannot be read."""
    h5py = require_h5py()
    try:
        with h5py.File(path, "r") as handle:
            return [
                (group, name, tuple(data.shape), data.dtype)
                for group in ("point", "cell")
                for name, data in handle[group].items()
            ]
    except (OSError, KeyError) as error:
        raise ValueError(f"{path}: cannot read it ({error})") from None


def _attribute(shape: tuple[int, ...]) -> str:
    """The XDMF AttributeType of a field of this shape: Scalar (n,), Vector (n, 3), Tensor6
    (n, 6, the upper triangle of a symmetric tensor), Tensor (n, 9), else Matrix."""
    if len(shape) == 1:
        return "Scalar"
    return {3: "Vector", 6: "Tensor6", 9: "Tensor"}.get(shape[1], "Matrix")


def _data_item(shape: tuple[int, ...], dtype: np.dtype, reference: str) -> str:
    kind = "Int" if np.issubdtype(dtype, np.integer) else "Float"
    dimensions = " ".join(str(d) for d in shape)
    return (
        f'<DataItem DataType="{kind}" Dimensions="{dimensions}" Format="HDF" '
        f'Precision="{np.dtype(dtype).itemsize}">{reference}</DataItem>'
    )


def write_collection(
    path: str | os.PathLike,
    n_nodes: int,
    n_elements: int,
    steps: list[tuple[float, str, list[tuple[str, str, tuple[int, ...], np.dtype]]]],
    write_text: Callable[[Path, str], None],
) -> None:
    """results.xdmf at ``path`` listing ``steps`` (time = load factor, the step's .h5 file
    name, its fields' ``layout``), written by ``write_text(path, text)`` (atomically)."""
    integer, real = np.dtype(np.int64), np.dtype(np.float64)
    lines = [
        '<?xml version="1.0"?>',
        '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2003/XInclude">',
        "  <Domain>",
        '    <Grid Name="mesh" GridType="Uniform">',
        f'      <Topology TopologyType="Triangle" NumberOfElements="{n_elements}">',
        f"        {_data_item((n_elements, 3), integer, f'{MESH_FILE}:/triangles')}",
        "      </Topology>",
        '      <Geometry GeometryType="XYZ">',
        f"        {_data_item((n_nodes, 3), real, f'{MESH_FILE}:/points')}",
        "      </Geometry>",
        "    </Grid>",
        '    <Grid Name="steps" GridType="Collection" CollectionType="Temporal">',
    ]
    include = (
        '<xi:include xpointer="xpointer(//Grid[@Name=&quot;mesh&quot;]/*[self::Topology or '
        'self::Geometry])"/>'
    )
    centres = {"point": "Node", "cell": "Cell"}
    for time, name, fields in steps:
        lines += [f"      <Grid Name={quoteattr(name)}>", f"        {include}"]
        lines.append(f'        <Time Value="{time!r}"/>')
        for group, field, shape, dtype in fields:
            lines += [
                f"        <Attribute Name={quoteattr(field)} "
                f'AttributeType="{_attribute(shape)}" Center="{centres[group]}">',
                f"          {_data_item(shape, dtype, f'{name}:/{group}/{field}')}",
                "        </Attribute>",
            ]
        lines.append("      </Grid>")
    lines += ["    </Grid>", "  </Domain>", "</Xdmf>", ""]
    write_text(Path(path), "\n".join(lines))
