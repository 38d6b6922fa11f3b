"""Parameter studies (issue 23, items 1 and 2): ``wrinkle study``, its designs, its table,
its engines (this process, local processes, a Dask cluster the test starts itself) and its
bad input. The numbers are checked against the variants solved one by one, and against a
scaling law: with the motion prescribed, an St Venant-Kirchhoff sheet's reactions are
proportional to E (the same deformation, stresses times E)."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest
from conftest import sheet_case

from wrinkle.case import read_case, read_case_data
from wrinkle.cli import main
from wrinkle.studies import StudyError, read_study, run_study, write_table
from wrinkle.studies.design import set_path, variant_overrides

SHEET = sheet_case(nx=4, top="[0.05, 0.02, 0.0]", steps=1)
TWO_MATERIALS = """
[mesh]
rectangle = {width = 1.0, height = 1.0, nx = 2, ny = 2}

[[material]]
model = "svk"
E = 1.0
nu = 0.3
thickness = 1.0

[[material]]
model = "svk"
E = 2.0
nu = 0.3
thickness = 1.0

[[load]]
kind = "pressure"
value = 1.0

[[load]]
kind = "pressure"
value = 2.0
"""


def study_file(folder: Path, body: str, case: str = SHEET) -> Path:
    (folder / "sheet.toml").write_text(case)
    path = folder / "study.toml"
    path.write_text('case = "sheet.toml"\n' + body)
    return path


def test_dotted_paths_address_tables_and_arrays_of_tables(tmp_path):
    """material.E in a single [material], load.2.value in [[load]], material.2.E, a key
    added where the table has none; what a path cannot address is named."""
    data = read_case_data(study_file(tmp_path, "", SHEET).with_name("sheet.toml"))
    set_path(data, "material.E", 2000.0)
    set_path(data, "material.angle", 30.0)
    assert data["material"]["E"] == 2000.0 and data["material"]["angle"] == 30.0
    path = tmp_path / "two.toml"
    path.write_text(TWO_MATERIALS)
    two = read_case_data(path)
    set_path(two, "load.2.value", 5.0)
    set_path(two, "material.2.E", 7.0)
    assert [t["value"] for t in two["load"]] == [1.0, 5.0]
    assert [t["E"] for t in two["material"]] == [1.0, 7.0]
    with pytest.raises(ValueError, match="'load' has 2 table.*there is no 3"):
        set_path(two, "load.3.value", 1.0)
    with pytest.raises(ValueError, match="'material' has 2 tables: give the number"):
        set_path(two, "material.E", 1.0)
    with pytest.raises(ValueError, match="'mesh.rectangle' is a table or a list"):
        set_path(two, "mesh.rectangle", 1.0)
    with pytest.raises(ValueError, match="the case has no 'solver'"):
        set_path(two, "solver.foo.bar", 1.0)
    overrides = variant_overrides(two, {"load.1.value": 3.0})
    assert set(overrides) == {"load"} and overrides["load"][0]["value"] == 3.0
    assert two["load"][0]["value"] == 1.0  # the base data unchanged


def test_designs_grid_list_and_latin_hypercube(tmp_path):
    """A grid is every combination; a list pairs the values; a Latin hypercube puts one
    sample in each of the n equal intervals of every parameter's bounds."""
    grid = read_study(
        study_file(
            tmp_path,
            '[[parameter]]\npath = "material.E"\nvalues = [1000.0, 2000.0]\n'
            '[[parameter]]\npath = "material.nu"\nrange = [0.1, 0.3, 3]\n',
        )
    )
    assert len(grid.variants) == 6
    assert grid.variants[1] == {"material.E": 1000.0, "material.nu": pytest.approx(0.2)}
    paired = read_study(
        study_file(
            tmp_path,
            'design = "list"\n[[parameter]]\npath = "material.E"\nvalues = [1000.0, 2000.0]\n'
            '[[parameter]]\npath = "material.nu"\nvalues = [0.2, 0.3]\n',
        )
    )
    assert paired.variants == (
        {"material.E": 1000.0, "material.nu": 0.2},
        {"material.E": 2000.0, "material.nu": 0.3},
    )
    n = 16
    cube = read_study(
        study_file(
            tmp_path,
            f'design = "latin-hypercube"\nsamples = {n}\nseed = 3\n'
            '[[parameter]]\npath = "material.E"\nbounds = [1000.0, 3000.0]\n'
            '[[parameter]]\npath = "material.nu"\nbounds = [0.1, 0.4]\n',
        )
    )
    for path, (low, high) in (("material.E", (1000.0, 3000.0)), ("material.nu", (0.1, 0.4))):
        values = np.array([v[path] for v in cube.variants])
        bins = np.floor((values - low) / (high - low) * n).astype(int)
        assert sorted(bins) == list(range(n))  # one sample per interval


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('[[parameter]]\npath = "material.foo"\nvalues = [1.0]\n', "unknown key 'foo'"),
        ('[[parameter]]\npath = "material.E"\nvalues = [-1.0]\n', "material.E' = -1"),
        ('[[parameter]]\npath = "support.9.x"\nvalues = [1.0]\n', "there is no 9"),
        ('[[parameter]]\npath = "material.E"\nrange = [1.0, 2.0]\n', "'range' must be"),
        ('[[parameter]]\npath = "material.E"\nvalues = "1"\n', "'values' must be a list"),
        ('[[parameter]]\npath = "material.E"\n', "give one of 'values'"),
        ('design = "lhs"\n[[parameter]]\npath = "material.E"\nvalues = [1.0]\n', "'design'"),
        (
            'design = "latin-hypercube"\n[[parameter]]\npath = "material.E"\nvalues = [1.0]\n',
            "needs 'bounds'",
        ),
        ('colect = ["x"]\n[[parameter]]\npath = "material.E"\nvalues = [1.0]\n', "'colect'"),
        ("", "at least one parameter"),
        (
            'collect = ["top_Fq"]\n[[parameter]]\npath = "material.E"\nvalues = [1.0]\n',
            "'top_Fq' is not a quantity of this case.*top_Fx",
        ),
    ],
)
def test_bad_study_files_are_one_line_naming_the_key(tmp_path, body, message):
    path = study_file(tmp_path, body)
    with pytest.raises(StudyError, match=message) as error:
        read_study(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)
    assert main(["study", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2


def rows_of(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_a_study_in_this_process_has_the_one_by_one_numbers(tmp_path, monkeypatch):
    """Three values of E and one the material refuses: the valid variants' reactions equal
    those of the cases solved one by one, and scale with E; the refused one is a row with
    status "error" and its message, and the study goes on; a second run takes the finished
    variants up from their folders instead of solving them again."""
    path = study_file(
        tmp_path,
        'collect = ["top_Fx", "top_Fy", "strain_energy"]\n'
        '[[parameter]]\npath = "material.E"\nvalues = [1000.0, 2000.0, 4000.0]\n',
    )
    study = read_study(path)
    study = type(study)(**{**study.__dict__, "variants": (*study.variants, {"material.E": -5.0})})
    rows = run_study(study, tmp_path / "out", workers=1)
    assert [row["status"] for row in rows] == ["converged"] * 3 + ["error"]
    assert "E" in rows[3]["message"] and "top_Fx" not in rows[3]
    base = tmp_path / "sheet.toml"
    direct = read_case(base, {"material": {**read_case_data(base)["material"], "E": 2000.0}})
    reference = direct.model.support_reactions(direct.solve().final.reactions)["top"]
    assert rows[1]["top_Fx"] == pytest.approx(reference[0], rel=1e-12)
    assert rows[1]["top_Fy"] == pytest.approx(reference[1], rel=1e-12)
    for row, factor in zip(rows[:3], (1.0, 2.0, 4.0)):
        assert row["top_Fx"] == pytest.approx(factor * rows[0]["top_Fx"], rel=1e-8)
    write_table(rows, tmp_path / "out", ["material.E"], study.collect)
    table = rows_of(tmp_path / "out" / "study.csv")
    assert list(table[0]) == [
        "variant",
        "material.E",
        "top_Fx",
        "top_Fy",
        "strain_energy",
        "status",
        "message",
        "seconds",
        "folder",
    ]
    assert table[3]["status"] == "error" and table[3]["top_Fx"] == ""
    assert float(table[1]["top_Fx"]) == rows[1]["top_Fx"]
    pq = pytest.importorskip("pyarrow.parquet")
    parquet = pq.read_table(tmp_path / "out" / "study.parquet").to_pydict()
    assert parquet["top_Fx"][:3] == [row["top_Fx"] for row in rows[:3]]
    assert parquet["top_Fx"][3] is None and parquet["status"][3] == "error"
    summary = json.loads((tmp_path / "out" / "variants" / "0002" / "summary.json").read_text())
    assert summary["converged"]

    def refuse(task):
        raise AssertionError(f"variant {task.number} solved again")

    monkeypatch.setattr("wrinkle.studies.run.run_variant", refuse)
    again = run_study(study, tmp_path / "out", workers=1)
    assert [row["top_Fx"] for row in again[:3]] == [row["top_Fx"] for row in rows[:3]]


def test_a_study_on_a_dask_cluster_the_test_starts(tmp_path):
    """A distributed.LocalCluster of two worker processes, addressed as a user's cluster
    would be (--scheduler): the same rows as in this process."""
    distributed = pytest.importorskip("distributed")
    path = study_file(
        tmp_path,
        'collect = ["top_Fx"]\n[[parameter]]\npath = "material.E"\nvalues = [1000.0, 3000.0]\n',
    )
    study = read_study(path)
    here = run_study(study, tmp_path / "here", workers=1)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        remote = run_study(study, tmp_path / "remote", scheduler=cluster.scheduler_address)
    assert [row["top_Fx"] for row in remote] == [row["top_Fx"] for row in here]
    assert [row["status"] for row in remote] == ["converged", "converged"]


def _worker_settings() -> tuple[str | None, bool, str | None]:
    import dask

    return (
        os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        dask.config.get("distributed.worker.profile.enabled"),
        os.environ.get("OPENBLAS_NUM_THREADS"),
    )


def test_the_local_cluster_s_workers_keep_glibc_s_memory_threshold(monkeypatch):
    """wrinkle's own local cluster starts its workers without Dask's
    MALLOC_TRIM_THRESHOLD_ = 65536 (35 % slower airbag variants, docs/studies.md) and
    without the stack profiler, single-threaded, even where a Dask cluster started before
    left the variable in this process's environment; the environment is restored."""
    pytest.importorskip("distributed")
    from wrinkle.studies.run import dask_client

    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "65536")
    client = dask_client(None, 1, required=True)
    try:
        settings = list(client.run(_worker_settings).values())
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    assert settings == [(None, False, "1")]
    assert os.environ["MALLOC_TRIM_THRESHOLD_"] == "65536"


def test_a_study_in_local_processes_without_dask(tmp_path):
    """The pool of local processes (what runs where Dask is not installed)."""
    path = study_file(
        tmp_path,
        'collect = ["top_Fx"]\n[[parameter]]\npath = "material.E"\nvalues = [1000.0, 3000.0]\n',
    )
    rows = run_study(read_study(path), tmp_path / "out", workers=2, engine="processes")
    assert rows[1]["top_Fx"] == pytest.approx(3.0 * rows[0]["top_Fx"], rel=1e-8)


def test_the_study_command(tmp_path, capsys):
    """wrinkle study: study.csv, a folder per variant and a picture per quantity; exit 1 and
    one line when a variant does not answer (the table has it); exit 2 for a scheduler that
    does not answer."""
    path = study_file(  # the top edge's x motion: an element of an array, from 1
        tmp_path,
        'collect = ["top_Fx", "wrinkled_area"]\n'
        '[[parameter]]\npath = "support.2.displacement.1"\nvalues = [0.02, 0.05]\n',
    )
    out = tmp_path / "out"
    assert main(["study", str(path), "--out", str(out), "--workers", "1", "-q"]) == 0
    table = rows_of(out / "study.csv")
    assert [row["status"] for row in table] == ["converged", "converged"]
    base = read_case(tmp_path / "sheet.toml")  # its top edge moves 0.05 along x
    reference = base.model.support_reactions(base.solve().final.reactions)["top"]
    assert float(table[1]["top_Fx"]) == pytest.approx(reference[0], rel=1e-12)
    assert float(table[0]["top_Fx"]) != pytest.approx(reference[0], rel=1e-3)
    assert (out / "variants" / "0001" / "summary.json").is_file()
    assert {p.name for p in (out / "pictures").iterdir()} == {"top_Fx.png", "wrinkled_area.png"}
    failing = study_file(
        tmp_path,
        '[[parameter]]\npath = "solver.max_iterations"\nvalues = [1, 100]\n',
        SHEET.replace("steps = 1", "steps = 1\ntolerance = 1e-12\nmin_step = 0.5"),
    )
    capsys.readouterr()
    assert main(["study", str(failing), "--out", str(tmp_path / "f"), "--workers", "1", "-q"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "1 of 2 variants did not answer" in err[0]
    assert [row["status"] for row in rows_of(tmp_path / "f" / "study.csv")] == [
        "not converged",
        "converged",
    ]
    pytest.importorskip("distributed")
    code = main(
        ["study", str(path), "--out", str(tmp_path / "s"), "--scheduler", "tcp://127.0.0.1:9"]
    )
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no Dask scheduler answers" in err[0]


def test_the_example_study_reads():
    """examples/studies/fibre_angles.toml: 7 angles x 3 moduli of the tissue example."""
    study = read_study(Path(__file__).resolve().parents[1] / "examples/studies/fibre_angles.toml")
    assert len(study.variants) == 21
    assert study.variants[-1] == {"material.angle": 90.0, "material.E_L": 70.0}


def test_a_study_run_again_after_its_case_changed_solves_again(tmp_path):
    """The finished variants are taken up only while their input is the same: after the
    base case changes (the top edge moved twice as far), the study solves them again."""
    path = study_file(
        tmp_path, 'collect = ["top_Fx"]\n[[parameter]]\npath = "material.E"\nvalues = [1000.0]\n'
    )
    first = run_study(read_study(path), tmp_path / "out", workers=1)
    (tmp_path / "sheet.toml").write_text(SHEET.replace("[0.05, 0.02, 0.0]", "[0.1, 0.02, 0.0]"))
    again = run_study(read_study(path), tmp_path / "out", workers=1)
    assert again[0]["top_Fx"] != pytest.approx(first[0]["top_Fx"], rel=1e-3)
    base = read_case(tmp_path / "sheet.toml")
    reference = base.model.support_reactions(base.solve().final.reactions)["top"][0]
    assert again[0]["top_Fx"] == pytest.approx(reference, rel=1e-12)
