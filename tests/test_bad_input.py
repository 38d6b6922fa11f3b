"""The bad-input table (issue 19): each input below ends `wrinkle run` with exit status 2 and
one line on stderr that names the culprit, nothing on stdout, no traceback and no warning.
The reference of each row is its own input: the key, table, node or file it must name."""

import pytest

from wrinkle.cli import main

TABLES = """
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
displacement = [0.0, 0.1, 0.0]

[[support]]
nodes = "z == 0"
fix = ["z"]
"""


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
        replace("displacement = [0.0, 0.1, 0.0]", "displacement = [0.0, inf, 0.0]"),
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
        replace("displacement = [0.0, 0.1, 0.0]", "displacement = [0.0, 1e200, 0.0]"),
        "a prescribed displacement of 1e+200",
    ),
    (
        "displacement 1e-13",
        replace("displacement = [0.0, 0.1, 0.0]", "displacement = [0.0, 1e-13, 0.0]"),
        "the loads are too small for the sheet's stiffness",
    ),
    (
        "pressure 1e300",
        chain(
            replace(
                'nodes = "y == 1"\ndisplacement = [0.0, 0.1, 0.0]',
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
            "displacement = [0.0, 0.1, 0.0]",
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
