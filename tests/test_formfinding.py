"""Form finding (issue 21, item 3; ``wrinkle.formfinding``), against closed forms: the
catenoid's neck radius, the edge cable's arc of radius T / n, the flat sheet that is its own
form; the shape does not depend on the elastic stiffness; the outer iterations do not grow
with the mesh; a model without a form is refused in one line."""

import json
import math
from pathlib import Path

import meshio
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

from wrinkle import Model, StVenantKirchhoff, rectangle
from wrinkle.case import read_case
from wrinkle.cli import main
from wrinkle.formfinding import FormFindingError, find_form, form_residual
from wrinkle.materials import Prestressed
from wrinkle.mesh import Mesh, read_mesh

N = 100.0  # prestress, N/m


def sheet(E: float = 1e6) -> Prestressed:
    return Prestressed(StVenantKirchhoff.isotropic(E=E, nu=0.3, thickness=1e-3), N)


def tube(radius: float, height: float, n_around: int, n_along: int) -> Mesh:
    """An open tube about z, -height/2 <= z <= height/2: (n_along + 1) rings of n_around
    nodes, each quadrilateral split into two triangles."""
    i, j = np.meshgrid(np.arange(n_along + 1), np.arange(n_around), indexing="ij")
    angle = 2 * np.pi * j / n_around
    nodes = np.stack(
        [radius * np.cos(angle), radius * np.sin(angle), height * (i / n_along - 0.5)], axis=-1
    ).reshape(-1, 3)
    a, b = (k.ravel() for k in np.meshgrid(np.arange(n_along), np.arange(n_around), indexing="ij"))

    def node(ring, k):
        return ring * n_around + k % n_around

    first = np.stack([node(a, b), node(a, b + 1), node(a + 1, b + 1)], axis=1)
    second = np.stack([node(a, b), node(a + 1, b + 1), node(a + 1, b)], axis=1)
    return Mesh(nodes, np.concatenate([first, second]))


def catenoid_neck(radius: float, height: float) -> float:
    """The neck radius r0 of the catenoid r = r0 cosh(z / r0) through two coaxial rings of
    radius R at z = +-h/2: the stable (larger) root of h/2 = r0 arccosh(R / r0). A soap film,
    the surface of zero mean curvature, is the form of an isotropic prestress; among the
    surfaces of revolution r(z) they are the catenaries (Euler-Lagrange of int r sqrt(1 + r'^2))."""

    def slope(r: float) -> float:  # d/dr of r arccosh(R / r); zero at the fold of the roots
        ratio = radius / r
        return math.acosh(ratio) - ratio / math.sqrt(ratio**2 - 1.0)

    turn = brentq(slope, 1e-6 * radius, radius * (1 - 1e-12))
    return brentq(lambda r: r * math.acosh(radius / r) - height / 2, turn, radius * (1 - 1e-15))


def test_catenoid_neck_converges_to_the_closed_form():
    """R = 1, h = 1 (r0 = 0.84834): the neck's error falls with the mesh at about second
    order and is within 0.1 % on the finest mesh."""
    r0 = catenoid_neck(1.0, 1.0)
    errors = []
    for n_around in (32, 64):
        mesh = tube(1.0, 1.0, n_around, n_around // 6 * 2)
        model = Model(mesh, sheet())
        model.fix("z == -0.5 or z == 0.5")
        form = find_form(model)
        neck = np.isclose(mesh.nodes[:, 2], 0.0)
        radius = np.hypot(form.nodes[neck, 0], form.nodes[neck, 1])
        errors.append(abs(radius.mean() / r0 - 1.0))
        assert form.converged and form.iterations < 40
    assert errors[-1] < 1e-3, errors
    assert errors[0] / errors[1] > 3.0, errors


def cable_arc_model(E: float = 1e6, n: int = 16) -> Model:
    """A 1 m square with isotropic prestress 20 N/m, held along x = 0 and x = 1, its edges
    y = 0 and y = 1 free but for a cable of force T = 20 N each."""
    model = Model(rectangle(1.0, 1.0, n, n), Prestressed(sheet(E).material, 20.0))
    model.fix("x == 0 or x == 1")
    model.add_cables("y == 0", EA=1e4, prestress=20.0, label="south")
    model.add_cables("y == 1", EA=1e4, prestress=20.0, label="north")
    return model


def test_edge_cable_is_an_arc_of_radius_T_over_n():
    """A cable of constant force T bounding a membrane of isotropic prestress n: its balance
    across the cable, T / rho = n, makes a circular arc of radius rho = T / n. With
    T = 20 N and n = 20 N/m, rho = 1 m through the held corners (0, 0) and (1, 0), bulging
    inwards with the sag rho - sqrt(rho^2 - 1/4) = 1 - sqrt(3)/2 at mid-span."""
    model = cable_arc_model(n=24)
    form = find_form(model)
    south = np.flatnonzero(np.isclose(model.mesh.nodes[:, 1], 0.0))
    x, y = form.nodes[south, 0], form.nodes[south, 1]
    assert np.allclose(form.nodes[:, 2], 0.0)
    # the circle through the points: x^2 + y^2 + D x + E y + F = 0 by least squares
    A = np.stack([x, y, np.ones_like(x)], axis=1)
    D, E_, F = np.linalg.lstsq(A, -(x**2 + y**2), rcond=None)[0]
    rho = math.sqrt(D**2 / 4 + E_**2 / 4 - F)
    assert rho == pytest.approx(1.0, rel=1e-2)
    assert y.max() == pytest.approx(1.0 - math.sqrt(3.0) / 2.0, rel=1e-2)


def test_the_shape_does_not_depend_on_the_elastic_stiffness():
    """The strategy uses the prestress alone: two sheets 1000 times apart in E have the
    same form to round-off."""
    soft = find_form(cable_arc_model(E=1e6)).nodes
    stiff = find_form(cable_arc_model(E=1e9)).nodes
    assert np.abs(soft - stiff).max() < 1e-12


def test_a_flat_prestressed_sheet_is_its_own_form():
    """A constant stress balances in any flat triangulation: held all round, the square is
    its form in one iteration, residual at round-off."""
    model = Model(rectangle(1.0, 0.6, 7, 5), sheet())
    model.fix("x == 0 or x == 1 or y == 0 or y == 0.6")
    form = find_form(model)
    assert form.iterations == 1
    assert np.abs(form.nodes - model.mesh.nodes).max() < 1e-13
    assert form_residual(model, form.nodes)[0] < 1e-12


def sail(n: int) -> Model:
    """A four-point sail: a 10 m square, corners (10, 0) and (0, 10) raised 3 m, edge
    cables of 20 kN, prestress 2 kN/m."""
    model = Model(
        rectangle(10.0, 10.0, n, n),
        Prestressed(StVenantKirchhoff.isotropic(E=6e8, nu=0.3, thickness=1e-3), 2000.0),
    )
    for selector in ("y == 0", "y == 10", "x == 0", "x == 10"):
        model.add_cables(selector, EA=1e7, prestress=2e4, label=selector)
    model.fix("x == 0 and y == 0 or x == 10 and y == 10")
    model.prescribe("x == 10 and y == 0 or x == 0 and y == 10", [0.0, 0.0, 3.0])
    return model


def test_sail_iterations_do_not_grow_with_the_mesh():
    """The outer iterations are the same on 512 and 8,192 elements, and the centre's height,
    1.5 m by the sail's symmetry (a saddle through the corners' mid-height), converges."""
    counts, centres = [], []
    for n in (16, 64):
        form = find_form(sail(n))
        counts.append(form.iterations)
        centre = np.argmin(np.linalg.norm(form.mesh.nodes[:, :2] - [5.0, 5.0], axis=1))
        centres.append(form.nodes[centre, 2])
    assert counts[0] == counts[1] and counts[0] < 30
    assert abs(centres[1] - 1.5) < abs(centres[0] - 1.5) < 1e-2


def test_node_matrix_sums_element_and_pair_entries():
    """``SparsityPattern.node_matrix`` against a COO sum of the same entries."""
    model = Model(rectangle(1.0, 1.0, 3, 2), sheet())
    pattern = model.pattern()
    rng = np.random.default_rng(1)
    triangles = model.mesh.triangles
    element = rng.standard_normal((len(triangles), 3, 3))
    pairs = np.array([[0, 1], [1, 0], [4, 4]])
    values = rng.standard_normal(3)
    got = pattern.node_matrix(element, pairs, values).toarray()
    rows = np.repeat(triangles, 3, axis=1).ravel()
    cols = np.tile(triangles, (1, 3)).ravel()
    n = model.mesh.n_nodes
    want = sp.coo_matrix((element.ravel(), (rows, cols)), shape=(n, n)).toarray()
    want += sp.coo_matrix((values, (pairs[:, 0], pairs[:, 1])), shape=(n, n)).toarray()
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m: None, "neither held nor on a cable"),
        (
            lambda m: m.add_cables("y == 0", EA=1.0) or m.add_cables("y == 1", EA=1.0),
            "needs a prestress force on every cable",
        ),
    ],
)
def test_a_model_without_a_form_is_refused(change, message):
    model = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    model.fix("x == 0 or x == 1")
    change(model)
    with pytest.raises(ValueError, match=message):
        find_form(model)


def test_a_cable_too_weak_for_its_span_is_said_in_one_line():
    """T / n = 0.2 m is less than half the 1 m chord: no arc spans it, the shape
    collapses, and the error says so (with the last shape)."""
    model = Model(rectangle(1.0, 1.0, 8, 8), sheet())
    model.fix("x == 0 or x == 1")
    model.add_cables("y == 0", EA=1e4, prestress=20.0)
    model.add_cables("y == 1", EA=1e4, prestress=20.0)
    with pytest.raises(FormFindingError, match="no form exists") as failure:
        find_form(model)
    assert failure.value.form.iterations >= 1


def test_form_finding_needs_a_prestress_and_supports():
    plain = Model(rectangle(1.0, 1.0, 4, 4), sheet().material)
    plain.fix("x == 0 or x == 1 or y == 0 or y == 1")
    with pytest.raises(ValueError, match="positive definite prestress on every element"):
        find_form(plain)
    loose = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    with pytest.raises(ValueError, match="form finding needs supports"):
        find_form(loose)


# -- case files and the command line ---------------------------------------------------------
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SAIL_CASE = """
[mesh]
rectangle = {width = 10.0, height = 10.0, nx = 12, ny = 12}
[material]
model = "svk"
E = 6e8
nu = 0.3
thickness = 1e-3
prestress = 4000.0
[[support]]
nodes = "x == 0 and y == 0 or x == 10 and y == 10"
fix = ["x", "y", "z"]
[[support]]
nodes = "x == 10 and y == 0 or x == 0 and y == 10"
displacement = [0.0, 0.0, 3.0]
[[cable]]
nodes = "y == 0"
EA = 1e7
prestress = 4e4
label = "south"
[[cable]]
nodes = "y == 10"
EA = 1e7
prestress = 4e4
[[cable]]
nodes = "x == 0"
EA = 1e7
prestress = 4e4
[[cable]]
nodes = "x == 10"
EA = 1e7
prestress = 4e4
label = "east"
[[probe]]
name = "centre"
nodes = "x == 5 and y == 5"
"""
LOAD = '\n[[load]]\nkind = "pressure"\nvalue = -500.0\n[solver]\nsteps = 4\n'


def test_a_formfinding_case_writes_the_form_and_loads_it(tmp_path):
    """`wrinkle run` with [formfinding]: the last step's points are the found form, which
    formfound.msh holds too; the summary reports the form finding. A second case on
    formfound.msh with the same prestress and cables (the two-case workflow) is balanced
    at zero load (no Newton iteration moves it beyond the form's sliding residual) and
    gives the one-case run's loaded state."""
    case = tmp_path / "sail.toml"
    case.write_text(SAIL_CASE + "[formfinding]\n" + LOAD)
    assert main(["run", str(case), "--out", str(tmp_path / "one"), "-q"]) == 0
    summary = json.loads((tmp_path / "one" / "summary.json").read_text())
    assert summary["formfinding"]["converged"] and summary["formfinding"]["loads"]
    assert summary["formfinding"]["mesh"] == "formfound.msh"
    found = read_mesh(tmp_path / "one" / "formfound.msh")
    last = meshio.read(tmp_path / "one" / summary["steps"][-1]["file"])
    np.testing.assert_array_equal(last.points, found.nodes)
    corner = np.flatnonzero(np.isclose(found.nodes[:, 0], 10) & np.isclose(found.nodes[:, 1], 0))
    assert found.nodes[corner, 2] == pytest.approx(3.0)  # the high point, raised
    one = np.loadtxt(tmp_path / "one" / "history.csv", delimiter=",", skiprows=1)[-1, -1]

    # the two-case workflow: the found mesh as the reference, the corners held where it has them
    second = SAIL_CASE.replace(
        "rectangle = {width = 10.0, height = 10.0, nx = 12, ny = 12}",
        f'file = "{(tmp_path / "one" / "formfound.msh").as_posix()}"',
    ).replace("displacement = [0.0, 0.0, 3.0]", 'fix = ["x", "y", "z"]')
    unloaded = tmp_path / "unloaded.toml"
    unloaded.write_text(second)
    at_rest = read_case(unloaded).solve()
    assert np.abs(at_rest.steps[-1].displacement).max() < 1e-4  # the sliding residual's relaxation
    loaded = tmp_path / "loaded.toml"
    loaded.write_text(second + LOAD)
    assert main(["run", str(loaded), "--out", str(tmp_path / "two"), "-q"]) == 0
    two = np.loadtxt(tmp_path / "two" / "history.csv", delimiter=",", skiprows=1)[-1, -1]
    assert one < -0.05  # the centre pushed down: -500 Pa acts against the normal (+z)
    assert two == pytest.approx(one, rel=1e-6)


def test_formfind_command_leaves_the_loads_out(tmp_path):
    """`wrinkle formfind` on the loaded case: one step at the form, displacement at the
    level of the sliding residual's relaxation, the summary saying the loads were left out."""
    case = tmp_path / "sail.toml"
    case.write_text(SAIL_CASE + LOAD)
    assert main(["formfind", str(case), "--out", str(tmp_path / "out"), "-q"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["formfinding"]["loads"] is False
    assert len(summary["steps"]) == 1
    assert summary["steps"][-1]["max_displacement"] < 1e-4
    assert (tmp_path / "out" / "formfound.msh").is_file()


def test_a_form_that_cannot_be_found_exits_1(tmp_path, capsys):
    case = tmp_path / "weak.toml"
    case.write_text(SAIL_CASE.replace("prestress = 4e4", "prestress = 1e3") + "[formfinding]\n")
    assert main(["run", str(case), "--out", str(tmp_path / "out"), "-q"]) == 1
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "no form exists" in error[0] and "weak.toml" in error[0]


def test_the_sunshield_example_has_ten_positive_frequencies(tmp_path):
    """examples/sunshield.toml: the flat form, its edge cords at 20 N, and ten natural
    frequencies, ascending and positive, with small eigen-residuals; the lowest near the
    first frequency of the held 2 m square's film, 1/2 sqrt(n / rho t) sqrt(2) / 2 = 5.93 Hz
    (a bound of sorts: the cut-in edges shrink the film, the cords add mass)."""
    assert main(["run", str(EXAMPLES / "sunshield.toml"), "--out", str(tmp_path), "-q"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    frequencies = np.array(summary["frequencies"])
    assert frequencies.size == 10 and np.all(np.diff(frequencies) >= 0) and frequencies[0] > 0
    assert max(summary["modes"]["residuals"]) < 1e-6
    reference = 0.5 * math.sqrt(10.0 / (1420.0 * 25e-6)) * math.sqrt(2.0) / 2.0
    assert 0.8 < frequencies[0] / reference < 1.3
    cords = summary["steps"][-1]["cables"]
    for cord in cords.values():
        assert cord["min_force"] == pytest.approx(20.0, rel=1e-3)
        assert cord["max_force"] == pytest.approx(20.0, rel=1e-3)


def test_a_symmetry_plane_holds_an_edge_and_a_plane_of_the_sheet_does_not():
    """An edge held across (x = 0 with u_x held: a symmetry plane) is a boundary of the
    form; held only in z, the plane of the flat sheet, it would shrink: refused."""
    model = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    model.fix("x == 1 or y == 0 or y == 1")
    model.fix("x == 0", components="x")
    assert find_form(model).converged
    flat = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    flat.fix("x == 1 or y == 0 or y == 1")
    flat.fix("x == 0", components="z")
    with pytest.raises(ValueError, match="neither held nor on a cable"):
        find_form(flat)


def test_pressure_on_a_sail_has_no_potential_and_on_a_held_sheet_has_one():
    """A follower pressure's work is path-independent (-p V) only on a surface whose
    boundary cannot sweep volume: on the sail, whose cable edges move, the solvers must not
    use an energy (``pressure_has_potential`` False, the energy NaN); held all round, they
    may."""
    model = sail(4)
    model.add_pressure(-100.0)
    system = model.discretise()
    assert not system.pressure_has_potential
    assert math.isnan(system.at(1.0).evaluate(np.zeros(model.n_dofs)).energy)
    held = Model(rectangle(1.0, 1.0, 4, 4), sheet())
    held.fix("x == 0 or x == 1 or y == 0 or y == 1")
    held.add_pressure(10.0)
    assert held.discretise().pressure_has_potential
    assert math.isfinite(held.discretise().at(1.0).evaluate(np.zeros(held.n_dofs)).energy)


def test_the_sail_example_is_form_found_and_carries_the_suction(tmp_path):
    """examples/sail.toml: the form found in fewer than 30 iterations, the suction carried
    with every element taut and the cables taut, the centre lifted, and the supports'
    reactions balancing the suction's resultant: a follower pressure p on the loaded surface
    pulls with p times its area vector, whose z part is its plan area, so
    sum Fz = -p A_plan (A_plan from the last step's points and displacements)."""
    assert main(["run", str(EXAMPLES / "sail.toml"), "--out", str(tmp_path), "-q"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["formfinding"]["converged"] and summary["formfinding"]["iterations"] < 30
    last = summary["steps"][-1]
    assert last["load_factor"] == 1.0
    assert last["states"]["wrinkled"] == 0 and last["states"]["slack"] == 0
    for cable in last["cables"].values():
        assert cable["slack_segments"] == 0
    history = np.genfromtxt(tmp_path / "history.csv", delimiter=",", names=True)
    assert history["centre_uz"][-1] > 0.05
    vtu = meshio.read(tmp_path / last["file"])
    x = vtu.points + vtu.point_data["displacement"]
    a, b, c = (x[vtu.cells_dict["triangle"][:, k]] for k in range(3))
    plan = 0.5 * np.cross(b - a, c - a)[:, 2].sum()
    reaction = history["low_points_Fz"][-1] + history["high_points_Fz"][-1]
    assert reaction == pytest.approx(-500.0 * plan, rel=1e-5)
