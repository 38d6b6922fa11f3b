"""ResultWriter and save_results: ParaView files, summary.json and history.csv, written
atomically step by step. Every field read back is compared with the solution it came from and
with an independent quantity (internal forces at the supports, equilibrium, the wrinkling
conditions)."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

import wrinkle
from wrinkle.materials import StVenantKirchhoff
from wrinkle.model import Results
from wrinkle.output import ResultWriter, save_results
from wrinkle.post import element_report

meshio = pytest.importorskip("meshio")

UNITS = {"length": "m", "force": "N"}
WRITTEN = {"history.csv", "results.pvd", "summary.json"}


def sheared_square() -> wrinkle.Model:
    """Unit square, 4 x 4 squares; bottom clamped, top moved (0.2, 0.02, 0): all wrinkled."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["bottom"], label="bottom")
    model.prescribe(mesh.node_sets["top"], (0.2, 0.02, 0.0), label="top")
    return model


def probes_of(model) -> dict[str, np.ndarray]:
    return {"top": model.mesh.node_sets["top"], "centre": np.array([12])}


@pytest.fixture(scope="module")
def solved():
    model = sheared_square()
    results = model.solve(steps=2)
    assert [s.load_factor for s in results.steps] == [0.5, 1.0]
    assert results.final.states[1] > 0  # it wrinkles
    return model, results


@pytest.fixture(scope="module")
def written(solved, tmp_path_factory):
    """Steps written one by one as they would be during the solve, then finish."""
    model, results = solved
    out = tmp_path_factory.mktemp("results")
    writer = ResultWriter(out, model, probes=probes_of(model), units=UNITS, case="square.toml")
    paths = [writer.write_step(step) for step in results.steps]
    assert paths == [out / "step_0001.vtu", out / "step_0002.vtu"]
    writer.finish(True, "converged")
    return out


def read_summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def read_history(out: Path) -> list[dict[str, str]]:
    with open(out / "history.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def collection(out: Path) -> list[tuple[float, str]]:
    root = ElementTree.parse(out / "results.pvd").getroot()
    assert root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def test_files_and_nothing_else(written):
    names = {p.name for p in written.iterdir()}
    assert names == WRITTEN | {"step_0001.vtu", "step_0002.vtu"}  # no temporary files left


def test_vtu_fields_hold_the_solution(solved, written):
    model, results = solved
    mesh = model.mesh
    m = mesh.n_elements
    for index, step in enumerate(results.steps, start=1):
        vtu = meshio.read(written / f"step_{index:04d}.vtu")
        np.testing.assert_array_equal(vtu.points, mesh.nodes)  # reference configuration
        np.testing.assert_array_equal(vtu.cells_dict["triangle"], mesh.triangles)
        u = vtu.point_data["displacement"]
        np.testing.assert_array_equal(u, step.displacement.reshape(-1, 3))
        np.testing.assert_allclose(
            u[mesh.node_sets["top"]], np.tile([0.2, 0.02, 0.0], (5, 1)) * step.load_factor
        )
        cell = {name: vtu.cell_data_dict[name]["triangle"] for name in vtu.cell_data}
        shapes = {name: value.shape for name, value in cell.items()}
        assert shapes == {
            "state": (m,),
            "tension_direction": (m, 3),
            "wrinkle_direction": (m, 3),
            "principal_stress": (m, 2),
            "principal_stress_major": (m,),
            "principal_stress_minor": (m,),
            "stress": (m, 9),
            "strain": (m, 9),
            "fibre_direction": (m, 3),
            "wrinkling_strain": (m,),
            "thickness": (m,),
        }
        assert np.issubdtype(cell["state"].dtype, np.integer)
        report = element_report(model, step.displacement)
        np.testing.assert_array_equal(cell["state"], report.state)
        for name in ("tension_direction", "wrinkle_direction", "principal_stress", "thickness"):
            np.testing.assert_allclose(cell[name], getattr(report, name), rtol=1e-15)
        np.testing.assert_array_equal(cell["principal_stress_major"], report.principal_stress[:, 1])
        np.testing.assert_array_equal(cell["principal_stress_minor"], report.principal_stress[:, 0])
        # the stress tensor: symmetric, in the current plane (no normal part), its in-plane
        # eigenvalues the principal stresses (two of the three; the third, along the
        # normal, zero)
        sigma = cell["stress"].reshape(m, 3, 3)
        np.testing.assert_allclose(sigma, sigma.transpose(0, 2, 1), atol=1e-14)
        values = np.linalg.eigvalsh(sigma)
        expected = np.sort(np.column_stack([report.principal_stress, np.zeros(m)]), axis=1)
        scale = np.abs(report.principal_stress).max()
        np.testing.assert_allclose(values, expected, atol=1e-10 * scale)
        # the strain: (C - I)/2 pulled back; its trace is (tr C - 2)/2 = (|F|^2 - 2)/2
        E = cell["strain"].reshape(m, 3, 3)
        x = mesh.nodes + u
        system = model.discretise()
        G = system.geometry.shape_gradient
        F = np.einsum("nki,nka->nia", x[mesh.triangles], G)
        np.testing.assert_allclose(
            np.trace(E, axis1=1, axis2=2), (np.sum(F**2, axis=(1, 2)) - 2) / 2, atol=1e-12
        )
        np.testing.assert_allclose(cell["fibre_direction"], np.tile([1.0, 0, 0], (m, 1)))
        # the nodal stress: an area-weighted mean of the elements' at the node
        nodal = vtu.point_data["stress_nodal"].reshape(-1, 3, 3)
        corner = 0  # one element (or two) at the corner: a weighted mean of theirs
        at_corner = np.flatnonzero(np.any(mesh.triangles == corner, axis=1))
        area = report.area[at_corner]
        np.testing.assert_allclose(
            nodal[corner], np.einsum("n,nij->ij", area, sigma[at_corner]) / area.sum(), rtol=1e-12
        )
        counts = tuple(int(np.count_nonzero(cell["state"] == k)) for k in range(3))
        assert counts == tuple(step.states)
        # the wrinkling conditions: uniaxial tension along a unit tension direction,
        # perpendicular to the wrinkle direction, shortened by beta > 0 across it
        wrinkled = cell["state"] == 1
        t, w = cell["tension_direction"][wrinkled], cell["wrinkle_direction"][wrinkled]
        np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, rtol=1e-12)
        np.testing.assert_allclose(np.einsum("ni,ni->n", t, w), 0.0, atol=1e-12)
        minor, major = cell["principal_stress"][wrinkled].T
        assert np.all(major > 0) and np.all(np.abs(minor) <= 1e-8 * major)
        assert np.all(cell["wrinkling_strain"][wrinkled] > 0)
        assert np.all(cell["thickness"] > 0)


def test_reactions_are_the_support_forces(solved, written):
    """Point data "reaction" is zero off the supports; its sum over the top edge is the top's
    internal force and balances the bottom's (no applied loads)."""
    model, results = solved
    top, bottom = model.mesh.node_sets["top"], model.mesh.node_sets["bottom"]
    summary = read_summary(written)
    for index, step in enumerate(results.steps, start=1):
        reaction = meshio.read(written / f"step_{index:04d}.vtu").point_data["reaction"]
        off_support = np.ones(model.mesh.n_nodes, dtype=bool)
        off_support[np.concatenate([top, bottom])] = False
        assert not np.any(reaction[off_support])
        internal = model.discretise().internal_forces(step.displacement).reshape(-1, 3)
        top_force = reaction[top].sum(axis=0)
        np.testing.assert_allclose(top_force, internal[top].sum(axis=0), rtol=1e-12)
        np.testing.assert_allclose(
            top_force + reaction[bottom].sum(axis=0), 0.0, atol=1e-8 * np.linalg.norm(top_force)
        )
        assert np.linalg.norm(top_force) > 0
        reported = summary["steps"][index - 1]["reactions"]
        assert set(reported) == {"bottom", "top"}
        np.testing.assert_allclose(reported["top"], top_force, rtol=1e-14)
        np.testing.assert_allclose(reported["bottom"], reaction[bottom].sum(axis=0), rtol=1e-14)


def test_collection_lists_steps_in_order(solved, written):
    _, results = solved
    assert collection(written) == [
        (s.load_factor, f"step_{i:04d}.vtu") for i, s in enumerate(results.steps, start=1)
    ]


def test_summary(solved, written):
    _, results = solved
    summary = read_summary(written)
    assert summary["converged"] is True and summary["message"] == "converged"
    assert summary["units"] == UNITS and summary["case"] == "square.toml"
    assert 0 < summary["wall_time"] < 60
    assert len(summary["steps"]) == len(results.steps)
    for index, (entry, step) in enumerate(zip(summary["steps"], results.steps), start=1):
        assert entry["step"] == index and entry["file"] == f"step_{index:04d}.vtu"
        assert entry["load_factor"] == step.load_factor
        assert entry["iterations"] == step.iterations
        assert entry["residual"] == step.residual
        assert entry["states"] == dict(zip(("taut", "wrinkled", "slack"), step.states))
        largest = np.linalg.norm(step.displacement.reshape(-1, 3), axis=1).max()
        assert entry["max_displacement"] == pytest.approx(largest, rel=1e-15)
        # the largest displacement is the top edge's, (0.2, 0.02, 0) at full load
        assert entry["max_displacement"] == pytest.approx(step.load_factor * np.hypot(0.2, 0.02))


def test_history(solved, written):
    model, results = solved
    with open(written / "history.csv", newline="") as handle:
        header = next(csv.reader(handle))
    assert header == [
        "step",
        "load_factor",
        "iterations",
        "residual",
        "taut",
        "wrinkled",
        "slack",
        "strain_energy",
        "external_work",
        "taut_area",
        "wrinkled_area",
        "slack_area",
        "max_principal_stress",
        "bottom_Fx",
        "bottom_Fy",
        "bottom_Fz",
        "top_Fx",
        "top_Fy",
        "top_Fz",
        "top_ux",
        "top_uy",
        "top_uz",
        "centre_ux",
        "centre_uy",
        "centre_uz",
    ]
    rows = read_history(written)
    summary = read_summary(written)
    assert len(rows) == len(results.steps)
    for index, (row, step, entry) in enumerate(zip(rows, results.steps, summary["steps"]), 1):
        assert int(row["step"]) == index
        assert float(row["load_factor"]) == step.load_factor
        assert int(row["iterations"]) == step.iterations
        assert float(row["residual"]) == step.residual
        assert [int(row[k]) for k in ("taut", "wrinkled", "slack")] == list(step.states)
        for label in ("bottom", "top"):
            force = [float(row[f"{label}_F{c}"]) for c in "xyz"]
            assert force == entry["reactions"][label]  # full precision in both files
        for key in ("strain_energy", "external_work"):
            assert float(row[key]) == entry[key]
        for state in ("taut", "wrinkled", "slack"):
            assert float(row[f"{state}_area"]) == entry["areas"][state]
        assert float(row["max_principal_stress"]) == entry["max_principal_stress"]["value"]
        u = step.displacement.reshape(-1, 3)
        for probe, nodes in probes_of(model).items():
            mean = [float(row[f"{probe}_u{c}"]) for c in "xyz"]
            np.testing.assert_allclose(mean, u[nodes].mean(axis=0), rtol=1e-15, atol=1e-300)
        top_mean = [float(row[f"top_u{c}"]) for c in "xyz"]
        np.testing.assert_allclose(top_mean, np.array([0.2, 0.02, 0.0]) * step.load_factor)


def test_interrupted_run_leaves_readable_files(solved, tmp_path):
    """One step written and no finish (a crash or Ctrl-C after it): everything that is there
    is complete and the summary says the run did not end."""
    model, results = solved
    writer = ResultWriter(tmp_path, model, probes=probes_of(model))
    writer.write_step(results.steps[0])
    del writer
    assert {p.name for p in tmp_path.iterdir()} == WRITTEN | {"step_0001.vtu"}
    summary = read_summary(tmp_path)
    assert summary["converged"] is False and summary["message"] == "running"
    assert [s["load_factor"] for s in summary["steps"]] == [0.5]
    assert collection(tmp_path) == [(0.5, "step_0001.vtu")]
    assert [float(r["load_factor"]) for r in read_history(tmp_path)] == [0.5]
    vtu = meshio.read(tmp_path / "step_0001.vtu")
    np.testing.assert_array_equal(
        vtu.point_data["displacement"], results.steps[0].displacement.reshape(-1, 3)
    )


def test_interruption_while_writing_keeps_the_previous_files(solved, tmp_path, monkeypatch):
    """Ctrl-C in the middle of writing the second .vtu: no partial file, no temporary file,
    and the other files still describe the first step."""
    model, results = solved
    writer = ResultWriter(tmp_path, model)
    writer.write_step(results.steps[0])
    before = {name: (tmp_path / name).read_bytes() for name in WRITTEN}

    def interrupted_write(path, mesh, file_format=None, **kwargs):
        Path(path).write_bytes(b'<?xml version="1.0"?><VTKFile')  # half a file
        raise KeyboardInterrupt

    monkeypatch.setattr(meshio, "write", interrupted_write)
    with pytest.raises(KeyboardInterrupt):
        writer.write_step(results.steps[1])
    assert {p.name for p in tmp_path.iterdir()} == WRITTEN | {"step_0001.vtu"}
    assert {name: (tmp_path / name).read_bytes() for name in WRITTEN} == before
    assert read_summary(tmp_path)["message"] == "running"


def test_files_exist_from_the_start_and_old_steps_are_removed(solved, written, tmp_path):
    """A new writer on a directory of an earlier run removes its step files and starts with
    an empty collection, history and a "running" summary."""
    model, _ = solved
    for path in written.iterdir():
        (tmp_path / path.name).write_bytes(path.read_bytes())
    (tmp_path / "notes.txt").write_text("mine")
    ResultWriter(tmp_path, model)
    assert {p.name for p in tmp_path.iterdir()} == WRITTEN | {"notes.txt"}
    assert read_summary(tmp_path)["steps"] == [] and collection(tmp_path) == []
    assert read_history(tmp_path) == []


def test_save_results_writes_every_step(solved, tmp_path, monkeypatch):
    model, results = solved
    out = save_results(results, tmp_path / "saved", probes=probes_of(model), units=UNITS)
    assert out == tmp_path / "saved"
    summary = read_summary(out)
    assert summary["converged"] is True
    assert [s["load_factor"] for s in summary["steps"]] == [0.5, 1.0]
    assert summary["units"] == UNITS and "case" not in summary
    assert [f for _, f in collection(out)] == ["step_0001.vtu", "step_0002.vtu"]
    # as the method Results.save
    monkeypatch.setattr(
        Results, "save", lambda self, d, **kw: save_results(self, d, **kw), raising=False
    )
    results.save(tmp_path / "method", units=UNITS)
    assert read_summary(tmp_path / "method")["steps"] == summary["steps"]


def test_save_results_of_a_stopped_run(solved, tmp_path):
    """Results that end before load factor 1 (those of a ConvergenceError) are not converged."""
    model, results = solved
    partial = Results(model)
    partial.steps = results.steps[:1]
    summary = read_summary(save_results(partial, tmp_path))
    assert summary["converged"] is False and "0.5" in summary["message"]
    assert len(summary["steps"]) == 1


def test_supports_with_one_label_are_reported_together(tmp_path):
    """Two supports named "top" (x, y prescribed; z fixed) give one reaction: the sum over
    the top edge."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["bottom"], label="bottom")
    top = mesh.node_sets["top"]
    model.prescribe(top, (0.2, 0.02, np.nan), label="top")
    model.fix(top, "z", label="top")
    step = model.solve(steps=1).final
    writer = ResultWriter(tmp_path, model)
    writer.write_step(step)
    header = writer.history_header()
    assert header.count("top_Fx") == 1 and header.count("bottom_Fx") == 1
    reported = read_summary(tmp_path)["steps"][0]["reactions"]
    np.testing.assert_allclose(
        reported["top"], step.reactions.reshape(-1, 3)[top].sum(axis=0), rtol=1e-14
    )


def test_a_support_reports_only_the_components_it_holds(tmp_path):
    """A support holding z of every node carries no in-plane reaction, even where other
    supports hold x or y of the same nodes; the summary agrees with Model.support_reactions
    and with equilibrium (the x reactions balance the applied unit traction). (With E t =
    0.1, ten times below the traction, the sheet's width collapsed to an area ratio of 1e-11,
    a state wrinkle now refuses: E t = 10 stretches it by a tenth.)"""
    mesh = wrinkle.rectangle(1.0, 1.0, 2, 2)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=100.0, nu=0.3, thickness=0.1))
    model.fix(mesh.node_sets["left"], "x", label="left x")
    model.fix(0, "y", label="corner y")
    model.fix(np.arange(mesh.n_nodes), "z", label="plane")
    model.add_edge_load(mesh.node_sets["right"], traction=(1.0, 0.0, 0.0))
    step = model.solve(tolerance=1e-10).final
    writer = ResultWriter(tmp_path, model)
    writer.write_step(step)
    reported = read_summary(tmp_path)["steps"][0]["reactions"]
    expected = model.support_reactions(step.reactions)
    for label in ("left x", "corner y", "plane"):
        np.testing.assert_allclose(reported[label], expected[label], atol=1e-12)
    np.testing.assert_allclose(reported["left x"], [-1.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(reported["plane"], [0.0, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    "probe, message",
    [(np.array([], dtype=int), "non-empty"), (np.array([0, 25]), "0..24"), ([0.5], "non-empty")],
)
def test_bad_probe_is_refused_by_name(solved, tmp_path, probe, message):
    model, _ = solved
    with pytest.raises(ValueError, match=f"probe 'tip'.*{message}"):
        ResultWriter(tmp_path, model, probes={"tip": probe})


def test_without_meshio_the_message_says_what_to_install(solved, tmp_path, monkeypatch):
    model, results = solved
    writer = ResultWriter(tmp_path, model)
    monkeypatch.setitem(sys.modules, "meshio", None)  # import meshio fails
    with pytest.raises(
        ImportError, match=r"meshio, which reads meshes and writes results, is missing"
    ):
        writer.write_step(results.steps[0])
    assert {p.name for p in tmp_path.iterdir()} == WRITTEN


def test_stress_of_a_taut_sheet_is_the_closed_form(tmp_path):
    """An equibiaxial stretch lambda of a St Venant-Kirchhoff sheet: the Cauchy stress
    resultant is N (e_x e_x + e_y e_y) with N = E t / (1 - nu) (lambda^2 - 1) / 2 (Green
    strain (lambda^2 - 1)/2 each way, S = E t / (1 - nu) times it per reference length, and
    sigma = F S F^T / J = lambda^2 S / lambda^2), at every element and node."""
    E, nu, t, stretch = 1000.0, 0.3, 0.01, 1.05
    mesh = wrinkle.rectangle(1.0, 1.0, 3, 3)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=nu, thickness=t))
    edge = np.flatnonzero(wrinkle.mesh.boundary_nodes(mesh))
    model.prescribe(
        edge, np.column_stack([(stretch - 1) * mesh.nodes[edge, :2], np.zeros(edge.size)])
    )
    results = model.solve(steps=1, tolerance=1e-11)
    writer = ResultWriter(tmp_path, model)
    writer.write_step(results.final)
    vtu = meshio.read(tmp_path / "step_0001.vtu")
    N = E * t / (1 - nu) * (stretch**2 - 1) / 2
    expected = np.diag([N, N, 0.0]).ravel()
    np.testing.assert_allclose(
        vtu.cell_data_dict["stress"]["triangle"], np.tile(expected, (18, 1)), atol=1e-9 * N
    )
    np.testing.assert_allclose(
        vtu.point_data["stress_nodal"], np.tile(expected, (16, 1)), atol=1e-9 * N
    )
    np.testing.assert_allclose(
        vtu.cell_data_dict["principal_stress_major"]["triangle"], N, rtol=1e-9
    )
    strain = (stretch**2 - 1) / 2
    np.testing.assert_allclose(
        vtu.cell_data_dict["strain"]["triangle"],
        np.tile(np.diag([strain, strain, 0]).ravel(), (18, 1)),
        atol=1e-12,
    )
