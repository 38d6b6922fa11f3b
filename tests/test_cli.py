"""The command line and case files: every example runs and checks a number; bad input gets a
one-line message and exit status 2; a solve that fails exits 1 with the converged steps on
disk."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
from conftest import SQUARE_CASE

from verification.paper_test import paper_material
from verification.references.relaxed_energy import relax
from verification.references.shear_stretch import homogeneous_edge_forces
from wrinkle.cli import main
from wrinkle.materials import StVenantKirchhoff

EXAMPLES = Path(__file__).parent.parent / "examples"
CELL_FIELDS = {"state", "tension_direction", "principal_stress", "wrinkling_strain", "thickness"}


def run_example(name, out):
    assert main(["run", str(EXAMPLES / f"{name}.toml"), "--out", str(out), "--quiet"]) == 0
    assert main(["plot", str(out)]) == 0
    for picture in ("state.png", "principal_stress.png", "load_displacement.png"):
        assert (out / picture).read_bytes().startswith(b"\x89PNG")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is True
    steps = sorted(out.glob("step_*.vtu"))
    assert len(steps) == len(summary["steps"])
    for path in steps:
        mesh = meshio.read(path)
        assert {"displacement", "reaction"} <= set(mesh.point_data)
        assert CELL_FIELDS <= set(mesh.cell_data)
    return summary, meshio.read(steps[-1])


def test_airbag_example(tmp_path):
    """Centre deflection within 3 % of the literature's 217 mm (Contri & Schrefler 1988)."""
    summary, last = run_example("airbag", tmp_path)
    centre = np.flatnonzero(np.all(np.isclose(last.points[:, :2], 0.0), axis=1))
    assert last.point_data["displacement"][centre, 2] == pytest.approx(0.217, rel=0.03)
    assert summary["steps"][-1]["states"]["wrinkled"] > 0


def test_shear_stretch_example(tmp_path):
    """Top-edge reactions equal the homogeneous solution (f = 5, gamma = 0.1, v = 0.1)."""
    _, last = run_example("shear_stretch", tmp_path)
    top = np.isclose(last.points[:, 1], 1.0)
    F1, F2 = last.point_data["reaction"][top, :2].sum(axis=0)
    F1_ref, F2_ref, _ = homogeneous_edge_forces(paper_material(5.0), 0.1, 0.1)
    assert F1 == pytest.approx(F1_ref, rel=1e-8)
    assert F2 == pytest.approx(F2_ref, rel=1e-8)


def test_kapton_example(tmp_path):
    """Away from the free ends the sheared strip is in the homogeneous tension-field state of
    x = X + gamma Y, y = (1 + eps) Y: major principal stress from the relaxed energy."""
    _, last = run_example("kapton", tmp_path)
    centroid = last.points[last.cells_dict["triangle"]].mean(axis=1)
    middle = (np.abs(centroid[:, 0] - 0.19) < 0.02) & (np.abs(centroid[:, 1] - 0.064) < 0.02)
    major = last.cell_data_dict["principal_stress"]["triangle"][middle, 1]
    F = np.array([[1.0, 1e-3 / 0.128], [0.0, 1.0 + 5e-5 / 0.128]])
    material = StVenantKirchhoff.isotropic(E=3.53e9, nu=0.3, thickness=25e-6)
    reference = relax(material, F.T @ F)
    assert reference.state == "wrinkled"
    C = F.T @ F
    expected = np.trace(reference.stress @ C) / np.sqrt(np.linalg.det(C))  # uniaxial
    assert major.mean() == pytest.approx(expected, rel=5e-3)


def test_tissue_example(tmp_path):
    """Global equilibrium of the pulled sheet, and wrinkles that follow neither the pull nor
    the fibres (anisotropy: the wrinkle direction is solved for)."""
    summary, last = run_example("tissue", tmp_path)
    reactions = summary["steps"][-1]["reactions"]
    held, pulled = np.array(reactions["held edge"]), np.array(reactions["pulled edge"])
    np.testing.assert_allclose(held + pulled, 0.0, atol=1e-5 * np.abs(pulled).max())
    assert pulled[0] > 0
    state = last.cell_data_dict["state"]["triangle"]
    tension = last.cell_data_dict["tension_direction"]["triangle"][state == 1]
    angle = np.degrees(np.arctan2(tension[:, 1], tension[:, 0])) % 180
    median = np.median(angle)
    assert 3 < median < 27 or 153 < median < 177, median


BASE_CASE = SQUARE_CASE

TRIANGLE_VTU = "triangles.vtu"


def _write_mesh(folder, points, triangles):
    meshio.write(folder / TRIANGLE_VTU, meshio.Mesh(points, [("triangle", triangles)]))


BAD_INPUTS = [
    # (what, edit of the base case, message fragment)
    (
        "unknown key",
        lambda c: c.replace("nu = 0.3", "nu = 0.3\ncolour = 1"),
        "unknown key 'colour'",
    ),
    ("missing value", lambda c: c.replace("E = 1000.0\n", ""), "missing key 'E'"),
    ("wrong type", lambda c: c.replace("E = 1000.0", 'E = "stiff"'), "'E' must be a number"),
    (
        "negative thickness",
        lambda c: c.replace("thickness = 0.01", "thickness = -0.01"),
        "thickness must be finite and > 0",
    ),
    (
        "negative modulus",
        lambda c: c.replace("E = 1000.0", "E = -1000.0"),
        "E must be finite and > 0",
    ),
    (
        "mesh file missing",
        lambda c: c.replace(
            "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}", 'file = "nowhere.msh"'
        ),
        "nowhere.msh",
    ),
    (
        "degenerate element",
        lambda c: c.replace(
            "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}", f'file = "{TRIANGLE_VTU}"'
        ),
        "zero area",
    ),
    (
        "duplicate element",
        lambda c: c.replace(
            "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}", f'file = "{TRIANGLE_VTU}"'
        ),
        "duplicate",
    ),
    (
        "rigid-body motion",
        lambda c: c.replace('fix = ["x", "y", "z"]', 'fix = ["x", "y"]').replace(
            "displacement = [0.05, 0.02, 0.0]", 'displacement = [0.05, 0.02, "free"]'
        ),
        "do not prevent translation in z",
    ),
    (
        "rotation unrestrained",
        lambda c: c.replace('nodes = "y == 0"', 'nodes = "x == 0 and y == 0"').replace(
            "displacement = [0.05, 0.02, 0.0]", 'displacement = ["free", 0.02, "free"]'
        ),
        "and rotation about y",
    ),
    (
        "selector matches nothing",
        lambda c: c.replace('nodes = "y == 0"', 'nodes = "y == 5"'),
        "matches no node",
    ),
    ("bad selector", lambda c: c.replace('nodes = "y == 0"', 'nodes = "y === 0"'), "unexpected"),
    ("not TOML", lambda c: c + "\n[[[", "not valid TOML"),
]


@pytest.mark.parametrize("what, edit, fragment", BAD_INPUTS, ids=[b[0] for b in BAD_INPUTS])
def test_bad_input_gives_one_line_and_status_2(tmp_path, capsys, what, edit, fragment):
    if what == "degenerate element":
        points = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], dtype=float)
        # the collinear element ordered as its neighbour across the edge 0-1 needs
        _write_mesh(tmp_path, points, np.array([[0, 1, 3], [1, 0, 2]]))
    if what == "duplicate element":
        points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
        _write_mesh(tmp_path, points, np.array([[0, 1, 2], [1, 2, 0]]))
    case = tmp_path / "case.toml"
    case.write_text(edit(BASE_CASE))
    status = main(["run", str(case), "--out", str(tmp_path / "out"), "--quiet"])
    error = capsys.readouterr().err.strip()
    assert status == 2, error
    assert "\n" not in error and "Traceback" not in error
    assert fragment in error, error
    if what not in ("not TOML",):
        assert "case.toml" in error or TRIANGLE_VTU in error or "nowhere" in error, error


def test_failed_solve_exits_1_and_keeps_converged_steps(tmp_path, capsys):
    case = tmp_path / "case.toml"
    text = BASE_CASE + "\n[solver]\nsteps = 4\nmax_iterations = 3\nmin_step = 0.2\n"
    case.write_text(text.replace("[0.05, 0.02, 0.0]", "[0.3, 0.01, 0.0]"))
    out = tmp_path / "out"
    status = main(["run", str(case), "--out", str(out), "--quiet"])
    assert status == 1
    assert "not converged" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert len(sorted(out.glob("step_*.vtu"))) == len(summary["steps"])


def test_python_api_matches_case(tmp_path):
    """read_case gives the same model as writing it in Python; its [solver] table sets the
    defaults of solve(); Results.save writes the files."""
    import wrinkle

    case = tmp_path / "case.toml"
    case.write_text(BASE_CASE + "\n[solver]\nsteps = 3\n")
    from_case = wrinkle.read_case(case)
    results = from_case.solve()
    assert len(results.steps) == 3 and from_case.source == case
    mesh = wrinkle.rectangle(1.0, 1.0, 2, 2)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=1000.0, nu=0.3, thickness=0.01))
    model.fix(mesh.node_sets["bottom"])
    model.prescribe(mesh.node_sets["top"], (0.05, 0.02, 0.0))
    direct = model.solve(steps=3)
    np.testing.assert_allclose(results.final.displacement, direct.final.displacement, atol=1e-12)
    direct.save(tmp_path / "out")
    assert (tmp_path / "out" / "results.pvd").exists()
    shutil.rmtree(tmp_path / "out")


STRIP_SUPPORTS = """
[[support]]
nodes = "x == 0"
fix = ["x", "z"]
[[support]]
nodes = "x == 0 and y == 0"
fix = ["y"]
[[support]]
nodes = "x == 2"
displacement = [0.01, "free", 0.0]
[[support]]
nodes = "x > 0 and x < 2"
fix = ["z"]
"""
STRIP_MATERIAL = """model = "svk-transverse"
E_L = 5.0
E_T = 1.0
nu_LT = 0.0
nu_TT = 0.0
G_LT = 0.4
thickness = 1.0
"""


@pytest.mark.parametrize("source", ["regions", "cell data"])
def test_fibre_directions_per_region_or_from_cell_data(tmp_path, source):
    """A strip pulled along x, fibres along x in its left half and along y in its right half,
    given by two [[material]] regions (physical groups of a gmsh file) or by per-element cell
    data of a .vtu file. The halves are in series with moduli E_L = 5 and E_T = 1 along x
    (nu = 0): the same force P = E l (l^2 - 1)/2 in both, stretches l adding up to 2.01."""
    from scipy.optimize import brentq

    import wrinkle

    mesh = wrinkle.rectangle(2.0, 1.0, 4, 2)
    left = mesh.nodes[mesh.triangles].mean(axis=1)[:, 0] < 1.0
    cells = [("triangle", mesh.triangles[left]), ("triangle", mesh.triangles[~left])]
    if source == "regions":
        tags = [np.full(left.sum(), 1), np.full((~left).sum(), 2)]
        meshio.write(
            tmp_path / "strip.msh",
            meshio.Mesh(
                mesh.nodes,
                cells,
                cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                field_data={"left": np.array([1, 2]), "right": np.array([2, 2])},
            ),
            file_format="gmsh22",
            binary=False,
        )
        materials = (
            f'[mesh]\nfile = "strip.msh"\n'
            f'[[material]]\nregion = "left"\ndirection = [1.0, 0.0, 0.0]\n'
            f"{STRIP_MATERIAL}"
            f'[[material]]\nregion = "right"\ndirection = [0.0, 1.0, 0.0]\n'
            f"{STRIP_MATERIAL}"
        )
    else:
        fibre = np.where(left[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        meshio.write(
            tmp_path / "strip.vtu",
            meshio.Mesh(mesh.nodes, cells, cell_data={"fibre": [fibre[left], fibre[~left]]}),
        )
        materials = f'[mesh]\nfile = "strip.vtu"\n[material]\ndirection = "fibre"\n{STRIP_MATERIAL}'
    case = tmp_path / "case.toml"
    case.write_text(materials + STRIP_SUPPORTS)
    model = wrinkle.read_case(case).model
    u = model.solve(tolerance=1e-12).final.displacement.reshape(-1, 3)
    middle = np.isclose(model.mesh.nodes[:, 0], 1.0)
    l1 = brentq(lambda a: 5 * a * (a**2 - 1) - (2.01 - a) * ((2.01 - a) ** 2 - 1), 1.0, 1.01)
    np.testing.assert_allclose(u[middle, 0], l1 - 1.0, rtol=1e-8)


def test_version_and_python_dash_m(capsys):
    """``wrinkle --version`` prints the installed version; ``python -m wrinkle`` is the same
    command line; the paper's test and the gallery are no commands of the installed program."""
    import wrinkle

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"wrinkle {wrinkle.__version__}"
    done = subprocess.run(
        [sys.executable, "-m", "wrinkle", "--version"], capture_output=True, text=True
    )
    assert done.returncode == 0 and done.stdout.strip() == f"wrinkle {wrinkle.__version__}"
    for removed in ("demo", "verify"):
        with pytest.raises(SystemExit) as stop:
            main([removed])
        assert stop.value.code == 2
    capsys.readouterr()


def test_a_run_with_no_converged_step_says_so(tmp_path, capsys):
    """The airbag (8 x 8) with 2 Newton iterations a step converges at no load level: exit
    status 1, the reason, and that the folder holds no step (not "the converged steps are
    in")."""
    airbag = Path(__file__).resolve().parents[1] / "examples" / "airbag.toml"
    text = airbag.read_text().replace("nx = 32, ny = 32", "nx = 8, ny = 8")
    text = text.replace("[solver]\n", "[solver]\nmax_iterations = 2\nmin_step = 0.3\n")
    assert "nx = 8, ny = 8" in text and "max_iterations = 2" in text
    case = tmp_path / "airbag.toml"
    case.write_text(text)
    code = main(["run", str(case), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 1 and "not converged" in err
    assert "no load step converged" in err and "the converged steps are in" not in err
