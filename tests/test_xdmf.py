"""The XDMF time series (``[output] format = "xdmf"``, issue 22 item 3): read back by an
independent reader (meshio's TimeSeriesReader) it holds the same mesh and fields as the
.vtu files; the mesh is written once; the chosen fields alone are written; restart and
open_results work on it; bad [output] keys are one line, exit status 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import sheet_case

import wrinkle
from wrinkle.case import read_case
from wrinkle.cli import main

meshio = pytest.importorskip("meshio")
pytest.importorskip("h5py")

CASE = (
    sheet_case(nx=6, top="[0.2, 0.05, 0.0]", steps=3)
    + """
[[cable]]
nodes = "x == 0"
EA = 10.0
"""
)


def run(tmp_path: Path, name: str, output: str) -> Path:
    case = tmp_path / f"{name}.toml"
    case.write_text(CASE + output)
    out = tmp_path / name
    assert main(["run", str(case), "--out", str(out), "--quiet"]) == 0
    return out


def test_xdmf_holds_the_vtu_files_mesh_and_fields(tmp_path):
    vtu = run(tmp_path, "vtu", "")
    xdmf = run(tmp_path, "xdmf", '[output]\nformat = "xdmf"\n')
    names = sorted(p.name for p in xdmf.iterdir())
    assert names == sorted(
        ["history.csv", "mesh.h5", "results.xdmf", "summary.json"]
        + [f"step_{k:04d}.h5" for k in (1, 2, 3)]
    )
    with meshio.xdmf.TimeSeriesReader(xdmf / "results.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == 3
        steps = [reader.read_data(k) for k in range(3)]
    reference = wrinkle.open_results(vtu)
    np.testing.assert_array_equal(points, reference.mesh().nodes)
    np.testing.assert_array_equal(cells[0].data, reference.mesh().triangles)
    upper = [0, 1, 2, 4, 5, 8]  # the symmetric tensors as XDMF's Tensor6: xx xy xz yy yz zz

    def stored(name, values):
        return values[:, upper] if name in ("stress", "strain", "stress_nodal") else values

    for k, (time, point_data, cell_data) in enumerate(steps):
        assert time == reference.load_factors[k]
        fields = reference.fields(k)
        for name, values in point_data.items():
            np.testing.assert_array_equal(values, stored(name, fields[name]))
        for name, (values,) in cell_data.items():
            np.testing.assert_array_equal(values, stored(name, fields[name]))
        # read back by wrinkle, the tensors have their nine components again: symmetric
        again = wrinkle.open_results(xdmf).fields(k)
        for name in ("stress", "strain", "stress_nodal"):
            scale = np.abs(fields[name]).max()
            np.testing.assert_allclose(again[name], fields[name], rtol=0, atol=1e-14 * scale)
        assert set(point_data) | set(cell_data) == set(fields) - {"cable_force", "cable_taut"}
    # the mesh once: the step files hold no points or triangles
    h5py = pytest.importorskip("h5py")
    with h5py.File(xdmf / "step_0002.h5") as handle:
        assert set(handle) == {"point", "cell"}
        assert handle["point/displacement"].shape == (49, 3)


def test_single_precision_keeps_the_displacement_and_reactions_exact(tmp_path):
    """[output] precision = "single": the stresses to float32's 6e-8, the displacements
    and reactions bit for bit, in both formats."""
    exact = wrinkle.open_results(run(tmp_path, "double", ""))
    for fmt in ("vtu", "xdmf"):
        out = run(tmp_path, fmt, f'[output]\nformat = "{fmt}"\nprecision = "single"\n')
        fields = wrinkle.open_results(out).fields()
        reference = exact.fields()
        for name in ("displacement", "reaction"):
            assert fields[name].dtype == np.float64
            np.testing.assert_array_equal(fields[name], reference[name])
        assert fields["stress"].dtype == np.float32
        scale = np.abs(reference["stress"]).max()
        np.testing.assert_allclose(fields["stress"], reference["stress"], atol=1e-7 * scale)


def test_the_chosen_fields_alone_are_written_with_the_displacement(tmp_path):
    for fmt in ("vtu", "xdmf"):
        out = run(tmp_path, fmt, f'[output]\nformat = "{fmt}"\nfields = ["state", "stress"]\n')
        fields = wrinkle.open_results(out).fields()
        assert set(fields) == {"displacement", "state", "stress"}, fmt


def test_an_xdmf_run_restarts(tmp_path):
    """Stopped after a step and restarted: the same steps as the uninterrupted xdmf run,
    results.xdmf listing all three."""
    full = run(tmp_path, "full", '[output]\nformat = "xdmf"\n')
    path = tmp_path / "full.toml"
    count = [0]

    def stop(step):
        count[0] += 1
        if count[0] == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        read_case(path).run(tmp_path / "again", on_step=stop)
    read_case(path).run(tmp_path / "again", restart=True)
    again = wrinkle.open_results(tmp_path / "again")
    np.testing.assert_allclose(
        again.displacement(), wrinkle.open_results(full).displacement(), atol=1e-14
    )
    with meshio.xdmf.TimeSeriesReader(tmp_path / "again" / "results.xdmf") as reader:
        assert reader.num_steps == 3


@pytest.mark.parametrize(
    "output, message",
    [
        ('[output]\nformat = "hdf"\n', "unknown format 'hdf' (one of vtu, xdmf)"),
        ('[output]\nfields = ["stres"]\n', "unknown field 'stres'"),
        ('[output]\nfields = "stress"\n', "'fields' must be a list of field names"),
        ("[output]\nkind = 1\n", "unknown key 'kind'"),
        ('[output]\nprecision = "half"\n', "unknown precision 'half' (one of double, single)"),
    ],
)
def test_bad_output_keys_are_one_line_exit_2(tmp_path, capsys, output, message):
    case = tmp_path / "case.toml"
    case.write_text(CASE + output)
    assert main(["run", str(case), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "[output]" in err and len(err.splitlines()) == 1


def test_pictures_are_drawn_from_an_xdmf_folder(tmp_path):
    pytest.importorskip("matplotlib")
    from wrinkle.plot import plot_results

    out = run(tmp_path, "xdmf", '[output]\nformat = "xdmf"\n')
    names = {path.name for path in plot_results(out)}
    assert {"state.png", "shape_3d.png", "load_displacement.png"} <= names
