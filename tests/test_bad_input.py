"""The bad-input table (issue 19): each input below ends `wrinkle run` with exit status 2 and
one line on stderr that names the culprit, nothing on stdout, no traceback and no warning.
The reference of each row is its own input: the key, table, node or file it must name."""

import pytest
from conftest import SQUARE_CASE

from wrinkle.cli import main

TABLES = (
    SQUARE_CASE
    + """
[[support]]
nodes = "z == 0"
fix = ["z"]
"""
)


def replace(old, new):
    def edit(text):
        assert old in text, old
        return text.replace(old, new, 1)

    return edit


def top(line):
    """A top-level key: before the first table."""
    return lambda text: line + "\n" + text


def append(block):
    return lambda text: text + "\n" + block + "\n"


def drop(table_start, table_end):
    """Remove the text from table_start up to (not including) table_end."""

    def edit(text):
        i = text.index(table_start)
        j = text.index(table_end, i + 1) if table_end else len(text)
        return text[:i] + text[j:]

    return edit


def chain(*edits):
    def edit(text):
        for one in edits:
            text = one(text)
        return text

    return edit


DEEP = "(" * 120 + "y == 0" + ")" * 120
BAD = [
    # wrong types of arrays of tables (the reader iterated them unchecked: TypeError)
    (
        "support = [1, 2]",
        chain(drop("[[support]]", None), top("support = [1, 2]")),
        "[[support]] 1: must be a table",
    ),
    (
        "support a number",
        chain(drop("[[support]]", None), top("support = 3")),
        "[[support]]: must be [[support]] tables",
    ),
    (
        "load a table",
        append('[load]\nkind = "pressure"\nvalue = 1.0'),
        "[[load]]: must be [[load]] tables",
    ),
    ("probe = true", top("probe = true"), "[[probe]]: must be [[probe]] tables"),
    ("probe list of lists", top("probe = [[1, 2]]"), "[[probe]] 1: must be a table"),
    (
        "material = []",
        chain(drop("[material]", "[[support]]"), top("material = []")),
        "[material]: at least one material",
    ),
    (
        "material a string",
        chain(drop("[material]", "[[support]]"), top('material = "svk"')),
        "[[material]]: must be [material] or [[material]] tables",
    ),
    (
        "two probes one name",
        append('[[probe]]\nname = "a"\nnodes = "y == 1"\n[[probe]]\nname = "a"\nnodes = "y == 0"'),
        "probe name 'a' is used twice",
    ),
    # non-finite and out-of-range numbers
    (
        "inf traction",
        append('[[load]]\nkind = "edge"\nnodes = "y == 1"\ntraction = [inf, 0.0, 0.0]'),
        "'traction' must be finite",
    ),
    (
        "nan traction",
        append('[[load]]\nkind = "edge"\nnodes = "y == 1"\ntraction = [nan, 0.0, 0.0]'),
        "'traction' must be finite",
    ),
    (
        "nan acceleration",
        append('[[load]]\nkind = "gravity"\nacceleration = [0.0, nan, 0.0]\ndensity = 1.0'),
        "'acceleration' must be finite",
    ),
    (
        "inf displacement",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = [0.0, inf, 0.0]"),
        "'displacement' must be finite",
    ),
    ("inf E", replace("E = 1000.0", "E = inf"), "'E' must be finite"),
    ("nan pressure", append('[[load]]\nkind = "pressure"\nvalue = nan'), "'value' must be finite"),
    (
        "tolerance 10",
        append("[solver]\ntolerance = 10.0"),
        "solver tolerance must be a number in (0, 0.01]",
    ),
    (
        "tolerance 1",
        append("[solver]\ntolerance = 1.0"),
        "solver tolerance must be a number in (0, 0.01]",
    ),
    (
        "min_step 5",
        append("[solver]\nmin_step = 5.0"),
        "solver min_step must be a number in (0, 1]",
    ),
    (
        "steps 1e9",
        append("[solver]\nsteps = 1000000000"),
        "solver steps must be an integer in [1, 10000]",
    ),
    ("look_ahead 1", append("[solver]\nlook_ahead = 1"), "'look_ahead' must be true or false"),
    # scales double precision cannot resolve
    ("E 1e-300", replace("E = 1000.0", "E = 1e-300"), "material 1: its stiffness"),
    (
        "E 1e308",
        replace("E = 1000.0", "E = 1e308"),
        "[material]: StVenantKirchhoff: stiffness must be finite and below",
    ),
    ("thickness 1e-320", replace("thickness = 0.01", "thickness = 1e-320"), "stiffness"),
    (
        "displacement 1e200",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = [0.0, 1e200, 0.0]"),
        "a prescribed displacement of 1e+200",
    ),
    (
        "displacement 1e-13",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = [0.0, 1e-13, 0.0]"),
        "the loads are too small for the sheet's stiffness",
    ),
    (
        "pressure 1e300",
        chain(
            replace(
                'nodes = "y == 1"\ndisplacement = [0.05, 0.02, 0.0]',
                'nodes = "y == 1"\nfix = ["x", "y", "z"]',
            ),
            append('[[load]]\nkind = "pressure"\nvalue = 1e300'),
        ),
        "the loads are too large",
    ),
    # absurd sizes, refused before anything is allocated
    ("nx 1e9", replace("nx = 2, ny = 2", "nx = 1000000000, ny = 10"), "gives 2e+10 elements"),
    (
        "sphere n 1e6",
        replace(
            "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}",
            "sphere = {radius = 1.0, n = 1000000}",
        ),
        "sphere: n = 1000000 gives 1e+12 elements",
    ),
    ("refine 12", replace("nx = 2, ny = 2}", "nx = 2, ny = 2}\nrefine = 12"), "[mesh]"),
    # selectors nested beyond Python's recursion (RecursionError before)
    ("deep selector", replace('nodes = "y == 0"', f'nodes = "{DEEP}"'), "nested too deeply"),
    (
        "long selector",
        replace('nodes = "y == 0"', 'nodes = "y == ' + "+".join(["0"] * 1500) + '"'),
        "chains too many operators",
    ),
    (
        "long expression",
        replace(
            "displacement = [0.05, 0.02, 0.0]",
            'displacement = [0.0, "' + "+".join(["0.0001 * x"] * 1500) + '", 0.0]',
        ),
        "chains too many operators",
    ),
    # unknown or misspelt keys, missing tables
    ("unknown top key", top("colour = 1"), "unknown key 'colour'"),
    ("unknown solver key", append("[solver]\nstep = 3"), "unknown key 'step'"),
    ("unknown material model", replace('model = "svk"', 'model = "rubber"'), "[material]"),
    ("no support", drop("[[support]]", None), "[[support]]: at least one support"),
    ("no mesh", drop("[mesh]", "[material]"), "mesh"),
    (
        "selector matches nothing",
        replace('nodes = "y == 0"', 'nodes = "y == 5"'),
        "matches no node",
    ),
    (
        "rigid-body motion",
        chain(drop("[[support]]", None), append('[[support]]\nnodes = "y == 0"\nfix = ["z"]')),
        "rigid-body motion is unrestrained",
    ),
    ("bad TOML", append("this is not toml"), "not valid TOML"),
]


@pytest.mark.parametrize("name, edit, fragment", BAD, ids=[row[0] for row in BAD])
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, name, edit, fragment):
    path = tmp_path / "case.toml"
    path.write_text(edit(TABLES))
    status = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    captured = capsys.readouterr()
    assert status == 2, (name, captured.err)
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith(f"wrinkle: {path}: "), lines[0]
    assert fragment in lines[0], lines[0]


def test_the_base_case_is_good(tmp_path, capsys):
    """The table's edits are what makes each case bad: the base case solves."""
    path = tmp_path / "case.toml"
    path.write_text(TABLES)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0


def test_a_byte_order_mark_is_read(tmp_path, capsys):
    path = tmp_path / "case.toml"
    path.write_bytes(b"\xef\xbb\xbf" + TABLES.encode())
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0


@pytest.mark.parametrize("what", ["folder as case", "file as --out"])
def test_paths_of_the_wrong_kind(tmp_path, capsys, what):
    case = tmp_path / "case.toml"
    case.write_text(TABLES)
    if what == "folder as case":
        arguments, fragment = ["run", str(tmp_path), "--out", str(tmp_path / "o")], "is a folder"
    else:
        (tmp_path / "taken").write_text("")
        arguments, fragment = ["run", str(case), "--out", str(tmp_path / "taken")], "is a file"
    assert main(arguments) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err, err


@pytest.fixture
def results(tmp_path, capsys):
    """A folder of three converged steps of the base case."""
    path = tmp_path / "case.toml"
    path.write_text(TABLES + "\n[solver]\nsteps = 3\n")
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    capsys.readouterr()
    return tmp_path / "out"


@pytest.mark.parametrize(
    "damage, fragment, drawn",
    [
        (lambda out: (out / "step_0003.vtu").unlink(), "step_0003.vtu: cannot read it", True),
        (
            lambda out: (out / "step_0003.vtu").write_text("garbage"),
            "step_0003.vtu: cannot read it (not a valid vtu file)",
            True,
        ),
        (
            lambda out: (out / "summary.json").write_text((out / "summary.json").read_text()[:100]),
            "summary.json: damaged, not readable as JSON",
            False,
        ),
        (lambda out: (out / "summary.json").unlink(), "summary.json: not found", False),
    ],
    ids=["last vtu deleted", "garbage vtu", "truncated summary", "no summary"],
)
def test_plot_on_damaged_results(results, capsys, damage, fragment, drawn):
    """One line naming the file, exit status 2, and the readable steps still drawn (meshio
    printed its own error and called sys.exit(1) on a garbage .vtu, a traceback on a deleted
    one)."""
    pytest.importorskip("matplotlib")
    damage(results)
    status = main(["plot", str(results)])
    captured = capsys.readouterr()
    assert status == 2
    lines = captured.err.splitlines()
    assert len(lines) == 1 and fragment in lines[0], captured.err
    assert ("wrote" in captured.out) == drawn, captured.out
    if drawn:
        assert "drew load factor 0.6667, the last readable step" in lines[0]
        assert (results / "state.png").is_file()


def test_ctrl_c_ends_the_run_cleanly(tmp_path):
    """SIGINT (Ctrl-C) during a run: exit status 130, one line, summary.json valid and saying
    it was interrupted, every step it lists on disk."""
    import json
    import signal
    import subprocess
    import sys
    import time

    path = tmp_path / "case.toml"
    slow = TABLES.replace("nx = 2, ny = 2", "nx = 48, ny = 48")
    path.write_text(slow + "\n[solver]\nsteps = 200\ntolerance = 1e-10\n")
    out = tmp_path / "out"
    run = subprocess.Popen(
        [sys.executable, "-m", "wrinkle", "run", str(path), "--out", str(out), "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not (out / "step_0002.vtu").exists():
        assert run.poll() is None, run.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    run.send_signal(signal.SIGINT)
    stdout, stderr = run.communicate(timeout=60)
    assert run.returncode == 130, stderr
    assert stderr.count("\n") == 1 and "interrupted" in stderr, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and summary["message"] == "interrupted"
    assert summary["steps"] and all((out / step["file"]).is_file() for step in summary["steps"])


def test_a_new_run_leaves_nothing_of_an_old_one(results, capsys):
    """A rerun into a folder of three steps and pictures, with one step: only its own files."""
    pytest.importorskip("matplotlib")
    assert main(["plot", str(results)]) == 0
    case = results.parent / "case.toml"
    case.write_text(TABLES)
    assert main(["run", str(case), "--out", str(results), "--quiet"]) == 0
    names = sorted(path.name for path in results.iterdir())
    assert names == ["history.csv", "results.pvd", "step_0001.vtu", "summary.json"], names


def test_a_full_disk_mid_run_ends_with_one_line_and_status_1(tmp_path, capsys, monkeypatch):
    """The third step cannot be written (no space left on the device): exit status 1, one line
    naming the file, the two steps before it intact and readable."""
    import errno
    import os

    import wrinkle.output

    path = tmp_path / "case.toml"
    path.write_text(TABLES + "\n[solver]\nsteps = 4\n")
    if not os.path.exists("/proc/self"):
        pytest.skip("needs /proc to name the file being written")
    real_fsync = os.fsync

    def fsync(descriptor):
        if "step_0003.vtu" in os.readlink(f"/proc/self/fd/{descriptor}"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_fsync(descriptor)

    monkeypatch.setattr(wrinkle.output.os, "fsync", fsync)
    out = tmp_path / "out"
    status = main(["run", str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert status == 1
    assert err.count("\n") == 1 and "cannot write" in err and "step_0003.vtu" in err, err
    assert "No space left on device" in err
    steps = sorted(p.name for p in out.glob("step_*.vtu"))
    assert steps == ["step_0001.vtu", "step_0002.vtu"]
    assert not list(out.glob(".*.tmp"))
    from wrinkle.mesh import read_mesh

    assert read_mesh(out / "step_0002.vtu").n_elements == 8


R = "rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}"
MAT = 'model = "svk"\nE = 1000.0\nnu = 0.3\nthickness = 0.01'
FIRST = 'nodes = "y == 0"\nfix = ["x", "y", "z"]'
SECOND = 'nodes = "y == 1"\ndisplacement = [0.05, 0.02, 0.0]'
BAD_ANNULUS = (
    "annulus = {inner_radius = 2.0, outer_radius = 1.0, n_radial = 2, n_circumferential = 8}"
)
BAD_CYLINDER = (
    "cylinder = {radius = 1.0, length = 2.0, n_circumferential = 8, n_axial = 2, n_cap = -1}"
)
MOONEY = 'model = "mooney-rivlin"\nC10 = 100.0\nC01 = 10.0\nthickness = 0.01'
OGDEN = 'model = "ogden"\nmu = [300.0, -20.0]\nalpha = [2.0, -2.0]\nthickness = 0.01'
NO_E_T = (
    'model = "svk-transverse"\nE_L = 5.0\nnu_LT = 0.3\nnu_TT = 0.3\nG_LT = 0.4\nthickness = 0.01'
)
# each key of each table, given a wrong type or a value outside its meaning; the fragment
# is what the line must say (the key, and the table the reader names)
MORE = [
    # [mesh]
    (
        "mesh not a table",
        chain(drop("[mesh]", "[material]"), top("mesh = 3")),
        "[mesh]: must be a table",
    ),
    ("two mesh sources", replace(R, R + '\nfile = "a.msh"'), "give exactly one of 'file'"),
    ("no mesh source", replace(R, ""), "give exactly one of 'file'"),
    ("mesh file missing", replace(R, 'file = "nowhere.msh"'), "nowhere.msh"),
    ("width 0", replace("width = 1.0", "width = 0.0"), "width"),
    ("width text", replace("width = 1.0", 'width = "one"'), "width"),
    ("nx 0", replace("nx = 2", "nx = 0"), "nx"),
    ("nx float", replace("nx = 2", "nx = 2.5"), "nx"),
    ("rectangle unknown key", replace("ny = 2}", "ny = 2, nz = 3}"), "nz"),
    ("diagonal bad", replace("ny = 2}", 'ny = 2, diagonal = "up"}'), "diagonal"),
    (
        "disk radius negative",
        replace(R, "disk = {radius = -1.0, n_radial = 2, n_circumferential = 8}"),
        "radius",
    ),
    (
        "disk n_circumferential 2",
        replace(R, "disk = {radius = 1.0, n_radial = 2, n_circumferential = 2}"),
        "n_circumferential",
    ),
    (
        "annulus inner > outer",
        replace(
            R,
            BAD_ANNULUS,
        ),
        "annulus",
    ),
    ("sphere n 0", replace(R, "sphere = {radius = 1.0, n = 0}"), "'n' must be > 0"),
    (
        "cylinder n_cap -1",
        replace(
            R,
            BAD_CYLINDER,
        ),
        "n_cap",
    ),
    ("refine negative", replace(R, R + "\nrefine = -1"), "'refine'"),
    (
        "support moment_about short",
        replace(FIRST, FIRST + "\nmoment_about = [1.0, 2.0]"),
        "'moment_about' must be a list of 3",
    ),
    (
        "support moment_about text",
        replace(FIRST, FIRST + '\nmoment_about = ["a", 0.0, 0.0]'),
        "'moment_about' has a bad component",
    ),
    ("refine float", replace(R, R + "\nrefine = 1.5"), "'refine'"),
    ("units a number", replace(R, R + "\nunits = 3"), "'units' must be a string or a table"),
    (
        "levels a string",
        chain(replace(R, R + '\nlevels = "coarse.msh"'), append("[solver]\nnested = true")),
        "[mesh]: 'levels' must be a list of mesh files",
    ),
    (
        "levels of numbers",
        chain(replace(R, R + "\nlevels = [1, 2]"), append("[solver]\nnested = true")),
        "[mesh]: 'levels' must be a list of mesh files",
    ),
    (
        "levels with nested = false",
        chain(replace(R, R + '\nlevels = ["coarse.msh"]'), append("[solver]\nnested = false")),
        "[mesh]: 'levels' are the meshes of [solver] nested: set nested = true",
    ),
    (
        "level file missing",
        chain(replace(R, R + '\nlevels = ["nowhere.msh"]'), append("[solver]\nnested = true")),
        "[mesh]: levels[0]: mesh file",
    ),
    # [material]
    (
        "material not a table",
        chain(drop("[material]", "[[support]]"), top("material = 3")),
        "[[material]]",
    ),
    ("model missing", replace('model = "svk"\n', ""), "model"),
    ("model number", replace('model = "svk"', "model = 3"), "model"),
    ("E missing", replace("E = 1000.0\n", ""), "'E'"),
    ("E zero", replace("E = 1000.0", "E = 0.0"), "E"),
    ("E negative", replace("E = 1000.0", "E = -5.0"), "E"),
    ("E text", replace("E = 1000.0", 'E = "stiff"'), "'E'"),
    ("E boolean", replace("E = 1000.0", "E = true"), "'E'"),
    ("nu 0.5", replace("nu = 0.3", "nu = 0.5"), "nu"),
    ("nu -1.2", replace("nu = 0.3", "nu = -1.2"), "nu"),
    ("thickness 0", replace("thickness = 0.01", "thickness = 0.0"), "thickness"),
    ("thickness negative", replace("thickness = 0.01", "thickness = -0.01"), "thickness"),
    ("thickness missing", replace("thickness = 0.01\n", ""), "thickness"),
    ("material unknown key", replace("nu = 0.3", "nu = 0.3\ncolour = 1"), "colour"),
    ("neo-hookean without mu", replace(MAT, 'model = "neo-hookean"\nthickness = 0.01'), "mu"),
    (
        "neo-hookean mu negative",
        replace(MAT, 'model = "neo-hookean"\nmu = -1.0\nthickness = 0.01'),
        "mu",
    ),
    (
        "mooney-rivlin without C01",
        replace(MAT, 'model = "mooney-rivlin"\nC10 = 100.0\nthickness = 0.01'),
        "[material]: missing key 'C01'",
    ),
    (
        "mooney-rivlin C01 negative",
        replace(MAT, MOONEY.replace("C01 = 10.0", "C01 = -10.0")),
        "[material]: MooneyRivlin: C01 must be finite and >= 0",
    ),
    (
        "mooney-rivlin C10 zero",
        replace(MAT, MOONEY.replace("C10 = 100.0", "C10 = 0.0")),
        "[material]: MooneyRivlin: C10 must be finite and > 0",
    ),
    (
        "mooney-rivlin C10 a list",
        replace(MAT, MOONEY.replace("C10 = 100.0", "C10 = [100.0]")),
        "[material]: 'C10' must be a number",
    ),
    (
        "mooney-rivlin with lmbda",
        replace(MAT, MOONEY + "\nlmbda = 1.0"),
        "[material]: unknown key 'lmbda'",
    ),
    (
        "ogden mu a number",
        replace(MAT, OGDEN.replace("mu = [300.0, -20.0]", "mu = 300.0")),
        "[material]: 'mu' must be a non-empty list of numbers",
    ),
    (
        "ogden alpha empty",
        replace(MAT, OGDEN.replace("alpha = [2.0, -2.0]", "alpha = []")),
        "[material]: 'alpha' must be a non-empty list of numbers",
    ),
    (
        "ogden lists of different length",
        replace(MAT, OGDEN.replace("alpha = [2.0, -2.0]", "alpha = [2.0]")),
        "[material]: 'mu' and 'alpha' must have the same length, got 'mu' 2, 'alpha' 1",
    ),
    (
        "ogden alpha text",
        replace(MAT, OGDEN.replace("alpha = [2.0, -2.0]", 'alpha = [2.0, "two"]')),
        "[material]: 'alpha' has a bad entry 'two'",
    ),
    (
        "ogden mu boolean",
        replace(MAT, OGDEN.replace("mu = [300.0, -20.0]", "mu = [true, -20.0]")),
        "[material]: 'mu' has a bad entry True",
    ),
    (
        "ogden mu nan",
        replace(MAT, OGDEN.replace("mu = [300.0, -20.0]", "mu = [nan, -20.0]")),
        "[material]: 'mu' must be finite",
    ),
    (
        "ogden alpha zero",
        replace(MAT, OGDEN.replace("alpha = [2.0, -2.0]", "alpha = [2.0, 0.0]")),
        "[material]: Ogden: alpha must be finite and nonzero",
    ),
    (
        "ogden shear modulus negative",
        replace(MAT, OGDEN.replace("mu = [300.0, -20.0]", "mu = [-300.0, -20.0]")),
        "[material]: Ogden: mu and alpha: the shear modulus sum(mu_k alpha_k)/2 must be > 0",
    ),
    (
        "ogden shear modulus zero",
        replace(MAT, OGDEN.replace("mu = [300.0, -20.0]", "mu = [20.0, 20.0]")),
        "[material]: Ogden: mu and alpha: the shear modulus sum(mu_k alpha_k)/2 must be > 0",
    ),
    (
        "ogden without alpha",
        replace(MAT, 'model = "ogden"\nmu = [300.0]\nthickness = 0.01'),
        "[material]: missing key 'alpha'",
    ),
    (
        "transverse without E_T",
        replace(
            MAT,
            NO_E_T,
        ),
        "E_T",
    ),
    ("direction two numbers", replace("nu = 0.3", "nu = 0.3\ndirection = [1.0, 0.0]"), "direction"),
    ("direction zero", replace("nu = 0.3", "nu = 0.3\ndirection = [0.0, 0.0, 0.0]"), "direction"),
    ("direction unknown field", replace("nu = 0.3", 'nu = 0.3\ndirection = "fibres"'), "fibres"),
    (
        "direction nan",
        replace("nu = 0.3", "nu = 0.3\ndirection = [nan, 0.0, 0.0]"),
        "'direction' must be finite",
    ),
    ("bending text", replace("nu = 0.3", 'nu = 0.3\nbending = "yes"'), "bending"),
    ("bending negative", replace("nu = 0.3", "nu = 0.3\nbending = -1.0"), "bending"),
    ("region unknown", replace("nu = 0.3", 'nu = 0.3\nregion = "skin"'), "skin"),
    (
        "prestress negative",
        replace("nu = 0.3", "nu = 0.3\nprestress = -1.0"),
        "[material]: prestress must be >= 0",
    ),
    (
        "prestress tensor not positive semidefinite",
        replace("nu = 0.3", "nu = 0.3\nprestress = [1.0, 1.0, 2.0]"),
        "[material]: prestress [n11, n22, n12] = [1.0, 1.0, 2.0] must be positive semidefinite",
    ),
    (
        "prestress tensor compressive",
        replace("nu = 0.3", "nu = 0.3\nprestress = [1.0, -0.5, 0.0]"),
        "must be positive semidefinite",
    ),
    (
        "prestress two components",
        replace("nu = 0.3", "nu = 0.3\nprestress = [1.0, 1.0]"),
        "'prestress' must be a number or a list [n11, n22, n12]",
    ),
    ("prestress text", replace("nu = 0.3", 'nu = 0.3\nprestress = "high"'), "'prestress'"),
    ("prestress nan", replace("nu = 0.3", "nu = 0.3\nprestress = nan"), "'prestress' must be"),
    (
        "prestress beyond the material",
        replace("nu = 0.3", "nu = 0.3\nprestress = 10.0"),
        "no stress-free state",
    ),
    # [[support]]
    ("support without nodes", replace(FIRST, 'fix = ["x", "y", "z"]'), "nodes"),
    ("support without fix or displacement", replace(FIRST, 'nodes = "y == 0"'), "[[support]] 1"),
    ("fix unknown component", replace('fix = ["x", "y", "z"]', 'fix = ["x", "w"]'), "w"),
    ("fix a string", replace('fix = ["x", "y", "z"]', 'fix = "x"'), "fix"),
    (
        "displacement two values",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = [0.0, 0.1]"),
        "displacement",
    ),
    (
        "displacement a number",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = 0.1"),
        "displacement",
    ),
    (
        "displacement bad expression",
        replace("displacement = [0.05, 0.02, 0.0]", 'displacement = [0.0, "0.1 * q", 0.0]'),
        "q",
    ),
    (
        "displacement expression syntax",
        replace("displacement = [0.05, 0.02, 0.0]", 'displacement = [0.0, "0.1 *", 0.0]'),
        "expression",
    ),
    (
        "displacement boolean component",
        replace("displacement = [0.05, 0.02, 0.0]", "displacement = [0.0, true, 0.0]"),
        "displacement",
    ),
    ("support unknown key", replace(FIRST, FIRST + "\nspring = 1.0"), "spring"),
    ("selector syntax", replace('nodes = "y == 0"', 'nodes = "y == "'), "selector"),
    ("selector unknown name", replace('nodes = "y == 0"', 'nodes = "q == 0"'), "unknown name 'q'"),
    ("selector a number", replace('nodes = "y == 0"', 'nodes = "1.0"'), "not a condition"),
    ("selector not a string", replace('nodes = "y == 0"', "nodes = 3"), "nodes"),
    ("selector NaN", replace('nodes = "y == 0"', 'nodes = "sqrt(x - 2) == 0"'), "NaN"),
    ("support label number", replace(FIRST, FIRST + "\nlabel = 3"), "label"),
    # [[load]]
    ("load without kind", append("[[load]]\nvalue = 1.0"), "kind"),
    ("load unknown kind", append('[[load]]\nkind = "wind"\nvalue = 1.0'), "wind"),
    ("pressure without value", append('[[load]]\nkind = "pressure"'), "value"),
    ("pressure text value", append('[[load]]\nkind = "pressure"\nvalue = "high"'), "value"),
    (
        "pressure unknown key",
        append('[[load]]\nkind = "pressure"\nvalue = 1.0\nfollow = true'),
        "follow",
    ),
    (
        "pressure unknown region",
        append('[[load]]\nkind = "pressure"\nvalue = 1.0\nregion = "top"'),
        "region",
    ),
    ("edge without traction", append('[[load]]\nkind = "edge"\nnodes = "y == 1"'), "[[load]] 1"),
    (
        "edge traction two values",
        append('[[load]]\nkind = "edge"\nnodes = "y == 1"\ntraction = [1.0, 0.0]'),
        "traction",
    ),
    (
        "edge follow on traction",
        append(
            '[[load]]\nkind = "edge"\nnodes = "y == 1"\ntraction = [1.0, 0.0, 0.0]\nfollow = true'
        ),
        "follow",
    ),
    (
        "edge on interior nodes",
        append('[[load]]\nkind = "edge"\nnodes = "y == 0.5"\nnormal = 1.0'),
        "[[load]] 1",
    ),
    (
        "nodal force wrong length",
        append('[[load]]\nkind = "force"\nnodes = "y == 1"\nforce = [1.0]'),
        "force",
    ),
    (
        "gravity without density",
        append('[[load]]\nkind = "gravity"\nacceleration = [0.0, 0.0, -9.81]'),
        "density",
    ),
    (
        "gravity density negative",
        append('[[load]]\nkind = "gravity"\nacceleration = [0.0, 0.0, -9.81]\ndensity = -1.0'),
        "density",
    ),
    # [[probe]]
    ("probe without nodes", append('[[probe]]\nname = "a"'), "nodes"),
    ("probe unknown key", append('[[probe]]\nnodes = "y == 1"\ncolour = 1'), "colour"),
    ("probe name a number", append('[[probe]]\nname = 3\nnodes = "y == 1"'), "name"),
    ("probe matches no node", append('[[probe]]\nnodes = "y == 7"'), "matches no node"),
    # [solver]
    ("solver not a table", top("solver = 3"), "[solver]: must be a table"),
    ("method unknown", append('[solver]\nmethod = "lbfgs"'), "lbfgs"),
    ("method a number", append("[solver]\nmethod = 1"), "method"),
    ("linear_solver unknown", append('[solver]\nlinear_solver = "mumps"'), "mumps"),
    ("steps 0", append("[solver]\nsteps = 0"), "steps"),
    ("steps float", append("[solver]\nsteps = 2.5"), "steps"),
    ("max_iterations 0", append("[solver]\nmax_iterations = 0"), "max_iterations"),
    ("tolerance 0", append("[solver]\ntolerance = 0.0"), "tolerance"),
    ("tolerance text", append('[solver]\ntolerance = "tight"'), "tolerance"),
    ("cutback 1", append("[solver]\ncutback = 1.0"), "cutback"),
    ("growth 0.5", append("[solver]\ngrowth = 0.5"), "growth"),
    ("max_step 2", append("[solver]\nmax_step = 2.0"), "max_step"),
    ("max_step below min_step", append("[solver]\nmin_step = 0.5\nmax_step = 0.1"), "max_step"),
    ("target_iterations negative", append("[solver]\ntarget_iterations = -1"), "target_iterations"),
    ("regrow_after negative", append("[solver]\nregrow_after = -1"), "regrow_after"),
    ("nested without refine", append("[solver]\nnested = true"), "refine >= 1 or [mesh] levels"),
    ("nested text", append('[solver]\nnested = "yes"'), "nested"),
    ("convergence unknown", append('[solver]\nconvergence = "energy"'), "unknown convergence"),
    ("convergence a number", append("[solver]\nconvergence = 1"), "convergence"),
    ("accuracy without nested", append('[solver]\nconvergence = "accuracy"'), "nested = true"),
    (
        "accuracy with nested = false",
        append('[solver]\nconvergence = "accuracy"\nnested = false'),
        "nested = true",
    ),
    ("accuracy_energy 2", append("[solver]\naccuracy_energy = 2.0"), "accuracy_energy"),
    ("accuracy_change 0.5", append("[solver]\naccuracy_change = 0.5"), "accuracy_change"),
    ("accuracy_change 0", append("[solver]\naccuracy_change = 0.0"), "accuracy_change"),
    # path control (issue 20): volume control, arc length, gas, stop
    ("control unknown", append('[solver]\ncontrol = "riks"'), "unknown control 'riks'"),
    ("volume_ratio without control", append("[solver]\nvolume_ratio = 2.0"), "needs control"),
    ("volume control without a volume", append('[solver]\ncontrol = "volume"'), "volume_ratio"),
    (
        "volume_ratio zero",
        append('[solver]\ncontrol = "volume"\nvolume_ratio = 0.0'),
        "volume_ratio",
    ),
    (
        "volume control of a held volume",
        append(
            '[[load]]\nkind = "pressure"\nvalue = 1.0\n[solver]\ncontrol = "volume"\nvolume = 1.0'
        ),
        "the enclosed volume cannot change",
    ),
    (
        "volume control on an open membrane",
        chain(
            replace('nodes = "z == 0"\nfix = ["z"]', 'nodes = "x == 0.5"\nfix = ["z"]'),
            append(
                '[[load]]\nkind = "pressure"\nvalue = 1.0\n'
                + '[solver]\ncontrol = "volume"\nvolume = 1.0'
            ),
        ),
        "solver control = 'volume': 4 boundary edge(s)",
    ),
    (
        "arc length with prescribed motion",
        append('[[load]]\nkind = "pressure"\nvalue = 1.0\n' + '[solver]\ncontrol = "arc-length"'),
        "prescribes displacements",
    ),
    (
        "arc length with restricted-step",
        append('[solver]\ncontrol = "arc-length"\nmethod = "restricted-step"'),
        "use method = 'newton'",
    ),
    (
        "stop names no probe",
        append('[solver]\nstop = {probe = "tip", displacement = 0.1}'),
        "'stop' names probe 'tip'",
    ),
    ("stop a number", append("[solver]\nstop = 0.1"), "'stop' must be"),
    (
        "stop displacement negative",
        append(
            '[[probe]]\nname = "tip"\nnodes = "y == 1"\n'
            '[solver]\nstop = {probe = "tip", displacement = -1.0}'
        ),
        "'displacement' must be > 0",
    ),
    (
        "gas on an open membrane",
        chain(
            replace('nodes = "z == 0"\nfix = ["z"]', 'nodes = "x == 0.5"\nfix = ["z"]'),
            append('[[load]]\nkind = "gas"\np0 = 2e5\nambient = 1e5'),
        ),
        "[[load]] kind = 'gas': 4 boundary edge(s)",
    ),
    (
        "gas without ambient",
        append('[[load]]\nkind = "gas"\np0 = 2e5'),
        "missing key 'ambient'",
    ),
    (
        "gas with p0 and amount",
        append('[[load]]\nkind = "gas"\np0 = 2e5\namount = 1.0\nambient = 1e5'),
        "exactly one of 'p0'",
    ),
    (
        "gas gamma below 1",
        append('[[load]]\nkind = "gas"\np0 = 2e5\nambient = 1e5\ngamma = 0.5'),
        "'gamma' must be >= 1",
    ),
    (
        "gas and pressure",
        append(
            '[[load]]\nkind = "pressure"\nvalue = 1.0\n'
            + '[[load]]\nkind = "gas"\np0 = 2e5\nambient = 1e5'
        ),
        "at most one gas load",
    ),
    (
        "gas under volume control",
        append(
            '[[load]]\nkind = "gas"\np0 = 2e5\nambient = 1e5\n'
            '[solver]\ncontrol = "volume"\nvolume = 1.0'
        ),
        "a gas load is solved under control = 'load'",
    ),
    # cables (issue 21)
    (
        "cable on unconnected nodes",
        append('[[cable]]\nnodes = "y == 0 and x == 0 or y == 0 and x == 1"\nEA = 1.0'),
        "[[cable]] 1: the 2 selected node(s) share no element edge",
    ),
    (
        "cable in two pieces",
        append('[[cable]]\nnodes = "x == 0 or x == 1"\nEA = 1.0'),
        "the cable's nodes are not connected",
    ),
    ("cable EA zero", append('[[cable]]\nnodes = "y == 0"\nEA = 0.0'), "'EA' must be > 0"),
    (
        "cable mass negative",
        append('[[cable]]\nnodes = "y == 0"\nEA = 1.0\nmass_per_length = -1.0'),
        "'mass_per_length' must be >= 0",
    ),
    (
        "cable prestress negative",
        append('[[cable]]\nnodes = "y == 0"\nEA = 1.0\nprestress = -1.0'),
        "'prestress' must be >= 0",
    ),
    (
        "cable unknown key",
        append('[[cable]]\nnodes = "y == 0"\nEA = 1.0\nforce = 2.0'),
        "[[cable]] 1: unknown key 'force'",
    ),
    ("cable a number", top("cable = 3"), "[[cable]]: must be [[cable]] tables"),
    # [modes] (issue 21, item 4): the base case has 6 free components
    (
        "modes count above the free dofs",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\ndensity = 1000.0"),
            append("[modes]\ncount = 7"),
        ),
        "'count' = 7 is more than the model's 6 free degrees of freedom",
    ),
    (
        "modes count 0",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\ndensity = 1000.0"),
            append("[modes]\ncount = 0"),
        ),
        "[modes]: 'count' must be >= 1",
    ),
    (
        "modes count a float",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\ndensity = 1000.0"),
            append("[modes]\ncount = 2.5"),
        ),
        "[modes]: 'count' must be an integer",
    ),
    (
        "modes mass unknown",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\ndensity = 1000.0"),
            append('[modes]\ncount = 2\nmass = "heavy"'),
        ),
        "[modes]: unknown mass 'heavy'",
    ),
    (
        "modes shift negative",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\ndensity = 1000.0"),
            append("[modes]\ncount = 2\nshift = -1.0"),
        ),
        "[modes]: 'shift' must be >= 0",
    ),
    ("modes a number", top("modes = 3"), "[modes]: must be a table"),
    (
        "modes without a density",
        append("[modes]\ncount = 2"),
        "[modes]: the natural modes need the mass: give [material] density",
    ),
    (
        "density 0",
        replace("thickness = 0.01", "thickness = 0.01\ndensity = 0.0"),
        "[material]: 'density' must be > 0",
    ),
    (
        "density negative",
        replace("thickness = 0.01", "thickness = 0.01\ndensity = -1.0"),
        "[material]: 'density' must be > 0",
    ),
    (
        "density text",
        replace("thickness = 0.01", 'thickness = 0.01\ndensity = "heavy"'),
        "[material]: 'density' must be a number",
    ),
    # [formfinding] (issue 21, item 3): the base case's edges x = 0 and x = 1 are free
    ("formfinding a number", top("formfinding = 3"), "[formfinding]: must be a table"),
    (
        "formfinding tolerance 0",
        append("[formfinding]\ntolerance = 0.0"),
        "[formfinding]: 'tolerance' must be > 0",
    ),
    (
        "formfinding tolerance 1",
        append("[formfinding]\ntolerance = 1.0"),
        "[formfinding]: 'tolerance' must be < 1",
    ),
    (
        "formfinding max_iterations 0",
        append("[formfinding]\nmax_iterations = 0"),
        "[formfinding]: 'max_iterations' must be >= 1",
    ),
    (
        "formfinding unknown key",
        append("[formfinding]\nsteps = 3"),
        "[formfinding]: unknown key 'steps'",
    ),
    (
        "formfinding without prestress",
        append("[formfinding]"),
        "[formfinding]: form finding needs a positive definite prestress on every element",
    ),
    (
        "formfinding free edge",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\nprestress = 1.0"),
            append("[formfinding]"),
        ),
        "is neither held nor on a cable",
    ),
    (
        "formfinding cable without prestress",
        chain(
            replace("thickness = 0.01", "thickness = 0.01\nprestress = 1.0"),
            append('[[cable]]\nnodes = "x == 0"\nEA = 1.0\n[[cable]]\nnodes = "x == 1"\nEA = 1.0'),
            append("[formfinding]"),
        ),
        "needs a prestress force on every cable",
    ),
    (
        "formfinding without supports",
        chain(drop("[[support]]", None), append("[formfinding]")),
        "[[support]]: at least one support is needed",
    ),
    (
        "formfinding nested",
        chain(
            replace("nx = 2, ny = 2}", "nx = 2, ny = 2}\nrefine = 1"),
            append("[solver]\nnested = true\n[formfinding]"),
        ),
        "[formfinding]: a form-finding case is not nested",
    ),
    # top level
    ("title a number", top("title = 3"), "title"),
    ("verification a number", top("verification = 3"), "[verification]"),
]


@pytest.mark.parametrize("name, edit, fragment", MORE, ids=[row[0] for row in MORE])
def test_every_key_refuses_its_bad_values(tmp_path, capsys, name, edit, fragment):
    test_bad_input_exits_2_with_one_line(tmp_path, capsys, name, edit, fragment)


def nested_on(*files):
    return chain(
        replace(R, R + f"\nlevels = {list(files)!r}".replace("'", '"')),
        append("[solver]\nnested = true"),
    )


# [mesh] levels with mesh files beside the case (written by the test below): sheet-2.vtu,
# the unit square in 2 elements; sheet-4.vtu in 4; sheet-32.vtu in 32 (the case: 8); half.vtu,
# the half 0 <= x <= 0.5 of the square; garbage.vtu, not a mesh
LEVELS = [
    ("level finer than the case", nested_on("sheet-32.vtu"), "levels[0]: "),
    ("level finer than the case says so", nested_on("sheet-32.vtu"), "not fewer than the case's"),
    ("levels out of order", nested_on("sheet-4.vtu", "sheet-2.vtu"), "not fewer than sheet-2.vtu"),
    ("level unreadable", nested_on("garbage.vtu"), "levels[0]: mesh file"),
    (
        "physical group missing on a level",
        chain(nested_on("sheet-2.vtu"), replace('nodes = "y == 0"', 'nodes = "bottom"')),
        "unknown name 'bottom'",
    ),
    (
        "the level file named",
        chain(nested_on("sheet-2.vtu"), replace('nodes = "y == 0"', 'nodes = "bottom"')),
        "(on the mesh of [mesh] levels: ",
    ),
    ("level of another surface", nested_on("half.vtu"), "do not cover the same surface"),
    ("level of another surface named", nested_on("half.vtu"), "half.vtu, level 1: the case's"),
]


@pytest.mark.parametrize("name, edit, fragment", LEVELS, ids=[row[0] for row in LEVELS])
def test_bad_levels(tmp_path, capsys, name, edit, fragment):
    import meshio

    from wrinkle import rectangle

    for file, mesh in [
        ("sheet-2.vtu", rectangle(1.0, 1.0, 1, 1)),
        ("sheet-4.vtu", rectangle(1.0, 1.0, 2, 1)),
        ("sheet-32.vtu", rectangle(1.0, 1.0, 4, 4)),
        ("half.vtu", rectangle(0.5, 1.0, 1, 1)),
    ]:
        meshio.write_points_cells(str(tmp_path / file), mesh.nodes, [("triangle", mesh.triangles)])
    (tmp_path / "garbage.vtu").write_text("garbage")
    test_bad_input_exits_2_with_one_line(tmp_path, capsys, name, edit, fragment)


def test_the_table_is_long_enough():
    """Issue 19 asks for at least 100 bad inputs in one table."""
    assert len(BAD) + len(MORE) >= 100


def test_kill_9_mid_run_leaves_every_file_readable(tmp_path):
    """SIGKILL at a random moment of a run: summary.json, history.csv and every step it lists
    are complete (each is written to a temporary file and moved into place)."""
    import csv
    import json
    import random
    import signal
    import subprocess
    import sys
    import time

    from wrinkle.mesh import read_mesh

    path = tmp_path / "case.toml"
    path.write_text(
        TABLES.replace("nx = 2, ny = 2", "nx = 40, ny = 40") + "\n[solver]\nsteps = 200\n"
    )
    out = tmp_path / "out"
    run = subprocess.Popen(
        [sys.executable, "-m", "wrinkle", "run", str(path), "--out", str(out), "--quiet"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    while not (out / "step_0001.vtu").exists():
        assert run.poll() is None and time.monotonic() < deadline
        time.sleep(0.02)
    time.sleep(random.Random(7).uniform(0.0, 0.5))
    run.send_signal(signal.SIGKILL)
    run.wait(timeout=60)
    summary = json.loads((out / "summary.json").read_text())
    for step in summary["steps"]:
        assert read_mesh(out / step["file"]).n_elements == 3200
    with open(out / "history.csv") as handle:
        rows = list(csv.reader(handle))
    assert len(rows) >= len(summary["steps"]) + 1  # a header, then a row per written step
