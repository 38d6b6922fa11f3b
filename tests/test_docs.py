"""Every code snippet of the README and the docs runs as written: the ```python blocks of a
page run in order in one namespace, in a folder holding a copy of examples/ (so that
"examples/airbag.toml" is found and written results land in a temporary place); every
```toml block is valid TOML, and a whole case (with [mesh] and [material]) reads."""

import os
import re
import shutil
import tomllib
from pathlib import Path

import matplotlib
import pytest

import wrinkle

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
PAGES = [page for page in PAGES if page.name != "verification.md"]  # generated, no snippets
BLOCK = re.compile(r"^```(\w+)[^\n]*\n(.*?)^```", re.MULTILINE | re.DOTALL)


def blocks(page: Path, language: str) -> list[str]:
    return [code for kind, code in BLOCK.findall(page.read_text()) if kind == language]


def page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


@pytest.fixture
def in_sandbox(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    matplotlib.use("Agg")
    return tmp_path


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p, "python")], ids=page_id)
def test_python_snippets_run(page, in_sandbox):
    namespace: dict = {"__name__": "__docs__"}
    for index, code in enumerate(blocks(page, "python")):
        try:
            exec(compile(code, f"{page.name}, python block {index + 1}", "exec"), namespace)
        except Exception as error:  # name the block that failed
            raise AssertionError(f"{page_id(page)}, python block {index + 1}: {error!r}") from error


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p, "toml")], ids=page_id)
def test_toml_snippets_are_valid(page, in_sandbox):
    for index, code in enumerate(blocks(page, "toml")):
        where = f"{page_id(page)}, toml block {index + 1}"
        try:
            data = tomllib.loads(code)
        except tomllib.TOMLDecodeError as error:
            raise AssertionError(f"{where}: {error}") from error
        if {"mesh", "material"} <= set(data) and "file" not in data["mesh"]:
            case = in_sandbox / f"snippet_{index + 1}.toml"
            case.write_text(code)
            wrinkle.read_case(case)  # a CaseError names the key


def test_pages_are_found():
    assert len(PAGES) >= 5 and all(page.is_file() for page in PAGES)
    assert os.path.basename(PAGES[0]) == "README.md"
