"""plot_results: the pictures of a result directory, and the geometry behind them (the
symmetry planes, the mirrored 3-D shape, the height-map rule, the load axis)."""

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
from wrinkle.plot import (
    _decimate,
    _tension_lines,
    _view_axes,
    height_map_axes,
    plot_results,
    symmetry_planes,
    whole_membrane,
)

pytest.importorskip("meshio")
pytest.importorskip("matplotlib")

PICTURES = [
    "state.png",
    "principal_stress.png",
    "load_displacement.png",
    "shape_3d.png",
    "stress_3d.png",
    "convergence.png",
]


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


def check_pictures(paths: list[Path], out: Path, names: list[str] = PICTURES) -> None:
    assert paths == [out / name for name in names]
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
    names = [*PICTURES[:-1], "height.png", PICTURES[-1]]  # it rises out of its plane a little
    check_pictures(plot_results(tmp_path), tmp_path, names)
    assert time.perf_counter() - start < 15.0  # about 5 s on 2 cores; generous for CI


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


# -- the three cases of issue 22: the airbag, the inflated cylinder, the Kapton sheet ----------

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "airbag": ("examples/airbag.toml", {"mesh": {"rectangle": {"nx": 8, "ny": 8}}}),
    "cylinder": (
        "verification/cases/inflated_cylinder.toml",
        {"mesh": {"cylinder": {"n_circumferential": 16, "n_axial": 30, "n_cap": 3}}},
    ),
    "kapton": ("examples/kapton.toml", {"mesh": {"rectangle": {"nx": 24, "ny": 8}}}),
    "tissue": ("examples/tissue.toml", {"mesh": {"rectangle": {"nx": 10, "ny": 5}}}),
}
CASE_PICTURES = {
    "airbag": ["pressure_volume.png", "shape_3d.png", "stress_3d.png", "height.png"],
    "cylinder": ["pressure_volume.png", "shape_3d.png", "stress_3d.png", "fibres.png"],
    "kapton": ["shape_3d.png", "stress_3d.png"],
    "tissue": ["shape_3d.png", "stress_3d.png", "fibres.png"],
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each case run coarse into a folder of its own (not yet plotted)."""
    folders = {}
    for name, (path, overrides) in CASES.items():
        out = tmp_path_factory.mktemp(name)
        wrinkle.read_case(ROOT / path, overrides).run(out)
        folders[name] = out
    return folders


def last_step(out: Path):
    import meshio

    return meshio.read(sorted(out.glob("step_*.vtu"))[-1])


@pytest.mark.parametrize("name", list(CASES))
def test_the_pictures_of_each_case(runs, name):
    """The airbag has the height map (nearly flat), the tube and the tissue their fibres (the
    material axes vary or are not x), the Kapton sheet neither (flat, fibres along x)."""
    out = runs[name]
    names = [*PICTURES[:3], *CASE_PICTURES[name], "convergence.png"]
    check_pictures(plot_results(out), out, names)


def test_the_quarter_airbag_is_shown_whole(runs):
    """Symmetry planes x = 0 and y = 0, and the seams' plane z = 0 (held in z only): the 9 x 9
    nodes of the quarter sheet become the 17 x 17 of the whole sheet, twice (both sheets of
    the airbag) less the 64 seam nodes they share; 8 times the 128 triangles."""
    step = last_step(runs["airbag"])
    triangles = step.cells_dict["triangle"]
    planes = symmetry_planes(
        step.points, step.point_data["displacement"], step.point_data["reaction"], triangles
    )
    assert planes == [(0, 0.0), (1, 0.0), (2, 0.0)]
    shape = whole_membrane(step)
    assert shape.x.shape[0] == 2 * 17 * 17 - 64 and shape.triangles.shape[0] == 8 * 128
    assert not shape.decimated
    np.testing.assert_allclose(shape.x.min(axis=0), -shape.x.max(axis=0), atol=1e-12)
    # across the plan only (the height map): the top sheet, 17 x 17 nodes
    assert whole_membrane(step, exclude_axis=2).x.shape[0] == 17 * 17
    # each face's element, and its tension direction mirrored onto it
    assert set(shape.element) == set(range(128))
    assert np.array_equal(np.unique(shape.signs, axis=0).shape, (8, 3))


@pytest.mark.parametrize("name", ["cylinder", "kapton", "tissue"])
def test_no_mirror_without_symmetry_supports(runs, name):
    """The tube's root cap is held in x but lies in the plane x = 0 (not an edge on it); the
    sheets' edges are clamped or pulled (reactions along the edge): nothing is mirrored."""
    step = last_step(runs[name])
    shape = whole_membrane(step)
    assert shape.planes == [] and shape.x.shape[0] == step.points.shape[0]


def test_a_roller_edge_that_does_not_move_is_needed():
    """An edge at the smallest x that is neither held (no reaction) nor still is no plane."""
    mesh = wrinkle.rectangle(1.0, 1.0, 2, 2)
    u = np.zeros_like(mesh.nodes)
    reaction = np.zeros_like(mesh.nodes)
    left = mesh.nodes[:, 0] == 0
    reaction[left, 0] = -1.0
    assert symmetry_planes(mesh.nodes, u, reaction, mesh.triangles) == [(0, 0.0)]
    reaction[left, 1] = 0.5  # a clamped edge: reactions along it too
    assert symmetry_planes(mesh.nodes, u, reaction, mesh.triangles) == []
    reaction[left, 1] = 0.0
    u[left, 0] = 1e-3  # it moved: not held normal to the plane
    assert symmetry_planes(mesh.nodes, u, reaction, mesh.triangles) == []


def test_height_map_rule():
    """A sheet that rises by less than half its smaller extent gets a height map; one that
    stays in its plane, one that rises more, and a curved reference do not."""
    mesh = wrinkle.rectangle(2.0, 1.0, 8, 4)
    X = mesh.nodes
    bump = np.sin(np.pi * X[:, 0] / 2.0) * np.sin(np.pi * X[:, 1])
    assert height_map_axes(X, X + np.outer(0.3 * bump, [0, 0, 1])) == (0, 1, 2)
    assert height_map_axes(X, X) is None
    assert height_map_axes(X, X + np.outer(0.8 * bump, [0, 0, 1])) is None
    curved = X + np.outer(bump, [0, 0, 1])
    assert height_map_axes(curved, curved) is None


def test_large_meshes_are_drawn_coarsened(runs, monkeypatch):
    """Past FACE_BUDGET faces the 3-D shape is a vertex-clustered copy with about that many
    faces, whose mirrored halves still meet on the symmetry planes."""
    import wrinkle.plot

    fine = wrinkle.rectangle(2.0, 1.0, 200, 100)
    x, X, faces, kept = _decimate(fine.nodes, fine.nodes, fine.triangles, 4000, [], 1e-12)
    assert 2000 <= faces.shape[0] <= 6000 and kept.shape == (faces.shape[0],)
    assert np.all(fine.triangles.shape[0] > kept)
    monkeypatch.setattr(wrinkle.plot, "FACE_BUDGET", 400)
    shape = whole_membrane(last_step(runs["airbag"]))
    assert shape.decimated and shape.triangles.shape[0] <= 8 * 400 // 8 * 1.5
    for axis in range(3):  # the halves share the nodes on each plane
        on = np.abs(shape.x[:, axis]) <= 1e-12
        assert np.count_nonzero(on) >= 3


def test_load_axis_choices(runs, capsys):
    from wrinkle.cli import main

    out = runs["airbag"]
    for load in ("pressure", "load_factor", "seam", "seam_Fz"):
        assert main(["plot", str(out), "--load", load]) == 0
    capsys.readouterr()
    assert main(["plot", str(runs["kapton"]), "--load", "pressure"]) == 2
    error = capsys.readouterr().err.strip()
    assert "\n" not in error and "'pressure'" in error and "'top edge'" in error
    with pytest.raises(ValueError, match="'nowhere': not a load"):
        plot_results(out, load="nowhere")


def test_show_without_pyvista_says_how_to_install(runs, capsys, monkeypatch):
    from wrinkle.cli import main

    monkeypatch.setitem(sys.modules, "pyvista", None)  # import pyvista raises ImportError
    assert main(["show", str(runs["airbag"])]) == 2
    error = capsys.readouterr().err.strip()
    assert "\n" not in error and 'pip install "wrinkle[viz]"' in error
