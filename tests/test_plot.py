"""plot_results: the three pictures of a result directory, and the geometry behind them."""

from __future__ import annotations

import struct
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_output import sheared_square

import wrinkle
from wrinkle.materials import StVenantKirchhoff
from wrinkle.output import ResultWriter, save_results
from wrinkle.plot import _tension_lines, _view_axes, plot_results

pytest.importorskip("meshio")
pytest.importorskip("matplotlib")

PICTURES = ["state.png", "principal_stress.png", "load_displacement.png"]


@pytest.fixture(scope="module")
def solved():
    model = sheared_square()
    return model, model.solve(steps=2)


def png_size(path: Path) -> tuple[int, int]:
    """Width and height of a PNG file, from its signature and IHDR chunk."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", path
    assert data.endswith(b"IEND\xaeB`\x82"), path  # complete: ends with the IEND chunk
    return struct.unpack(">II", data[16:24])


def check_pictures(paths: list[Path], out: Path) -> None:
    assert paths == [out / name for name in PICTURES]
    for path in paths:
        width, height = png_size(path)
        assert 500 <= width <= 2500 and 300 <= height <= 2500, (path.name, width, height)
        assert path.stat().st_size > 10_000, path.name


def test_three_pictures_with_probes_and_units(solved, tmp_path):
    model, results = solved
    mesh = model.mesh
    save_results(
        results,
        tmp_path,
        probes={"top": mesh.node_sets["top"], "centre": [12]},
        units={"length": "m", "force": "N"},
    )
    check_pictures(plot_results(tmp_path), tmp_path)


def test_pictures_without_probes_or_units(solved, tmp_path):
    _, results = solved
    save_results(results, tmp_path)
    check_pictures(plot_results(tmp_path), tmp_path)


def test_pictures_of_a_run_that_stopped(solved, tmp_path):
    """After one step and no finish (summary "running"), the pictures show that step."""
    model, results = solved
    writer = ResultWriter(tmp_path, model, probes={"centre": [12]})
    writer.write_step(results.steps[0])
    check_pictures(plot_results(tmp_path), tmp_path)


def test_no_step_is_refused(solved, tmp_path):
    model, _ = solved
    ResultWriter(tmp_path, model)
    with pytest.raises(ValueError, match="no converged step"):
        plot_results(tmp_path)


def test_view_is_the_plane_of_the_two_largest_extents():
    rng = np.random.default_rng(1)
    points = rng.uniform(size=(50, 3)) * [2.0, 0.01, 1.0]  # a sheet in the xz-plane
    assert _view_axes(points) == (0, 2)
    assert _view_axes(points * [0.01, 100.0, 1.0]) == (1, 2)
    assert _view_axes(points[:, [0, 2, 1]]) == (0, 1)


def test_tension_lines_through_centroids_along_the_tension():
    """Each line is centred on its element's centroid, 0.7 sqrt(2 A) long, along the
    projected tension direction; on a fine mesh at most one line per sampling square."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    x = mesh.nodes * [1.0, 1.0, 0.0] + [0.0, 0.0, 0.3]
    tension = np.tile([0.6, 0.8, 0.0], (mesh.n_elements, 1))
    segments, sampled = _tension_lines(x, mesh.triangles, tension, (0, 1))
    assert not sampled and segments.shape == (mesh.n_elements, 2, 2)
    centroids = x[mesh.triangles].mean(axis=1)[:, :2]
    np.testing.assert_allclose(segments.mean(axis=1), centroids, atol=1e-15)
    chord = segments[:, 1] - segments[:, 0]
    np.testing.assert_allclose(chord, np.tile(0.7 * 0.25 * np.array([0.6, 0.8]), (32, 1)))

    fine = wrinkle.rectangle(2.0, 1.0, 100, 50)
    tension = np.tile([1.0, 0.0, 0.0], (fine.n_elements, 1))
    segments, sampled = _tension_lines(fine.nodes, fine.triangles, tension, (0, 1), lines_across=40)
    assert sampled and 20 * 40 <= segments.shape[0] <= 21 * 41
    np.testing.assert_allclose(np.ptp(segments[:, :, 0], axis=1), 0.7 * 2.0 / 40)


def test_ten_thousand_elements_in_about_a_second(tmp_path):
    """A 10^4-element result (a made-up smooth displacement, evaluated as a step) plots in
    about a second once matplotlib and meshio are imported."""
    from wrinkle.results import StepResult

    mesh = wrinkle.rectangle(2.0, 1.0, 100, 50)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0))
    X = mesh.nodes
    u = np.column_stack(
        [
            0.2 * X[:, 1],
            0.03 * np.sin(3 * X[:, 0]) * X[:, 1],
            0.02 * np.sin(np.pi * X[:, 0]) * np.sin(np.pi * X[:, 1]),
        ]
    )
    writer = ResultWriter(tmp_path, model, probes={"top": mesh.node_sets["top"]})
    writer.write_step(StepResult(1.0, u.ravel(), 1, 0.0, np.zeros(model.n_dofs), (0, 0, 0)))
    writer.finish(True, "made up")
    plot_results(tmp_path)  # imports and font cache
    start = time.perf_counter()
    check_pictures(plot_results(tmp_path), tmp_path)
    assert time.perf_counter() - start < 5.0  # about 1 s on 2 cores; generous for CI


def test_pictures_leave_the_backend_alone(solved, tmp_path):
    """Drawing uses matplotlib.figure.Figure, not pyplot: a backend the user chose (here
    "svg") is still the backend afterwards, and no pyplot figure is left open."""
    import matplotlib

    before = matplotlib.get_backend()
    matplotlib.use("svg")
    try:
        import wrinkle.plot

        _, results = solved
        save_results(results, tmp_path)
        wrinkle.plot.plot_results(tmp_path)
        figure = wrinkle.plot.new_figure(figsize=(2, 2))
        figure.subplots().plot([0, 1], [0, 1])
        figure.savefig(tmp_path / "line.png")
        assert matplotlib.get_backend() == "svg"
        assert matplotlib.rcParams["backend"] == "svg"
        if "matplotlib.pyplot" in sys.modules:
            assert not sys.modules["matplotlib.pyplot"].get_fignums()
    finally:
        matplotlib.use(before)
