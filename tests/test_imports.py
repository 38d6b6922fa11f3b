"""The package's layers: no import cycle (counting imports inside functions, not those only
for type checkers), every module imports on its own in a fresh interpreter, nothing imports
the verification gallery, and every module declares ``__all__``."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import wrinkle

PACKAGE = Path(wrinkle.__file__).parent
MODULES = sorted(
    "wrinkle." + ".".join(path.relative_to(PACKAGE).with_suffix("").parts).removesuffix(".__init__")
    for path in PACKAGE.rglob("*.py")
)
MODULES = [name.removesuffix(".__init__") for name in MODULES]


def _module_path(name: str) -> Path:
    parts = name.split(".")[1:]
    path = PACKAGE.joinpath(*parts)
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def _type_checking_only(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def _imports(name: str) -> set[str]:
    """wrinkle modules that ``name`` imports at run time (at top level or in a function)."""
    tree = ast.parse(_module_path(name).read_text())
    skipped = {
        id(n) for block in ast.walk(tree) if _type_checking_only(block) for n in ast.walk(block)
    }
    found = set()
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            candidates = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        else:
            continue
        found |= {c for c in candidates if c in MODULES and c != name}
    return found


def test_no_import_cycle():
    graph = {name: _imports(name) for name in MODULES}
    # a package's __init__ imports its submodules: an edge from a submodule to its own
    # package is how Python imports it, not a cycle of the code
    for name, targets in graph.items():
        graph[name] = {t for t in targets if not name.startswith(t + ".")}
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        path.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 1:
                cycle = path[path.index(target) :] + [target]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if target not in state:
                visit(target)
        path.pop()
        state[node] = 2

    for name in MODULES:
        if name not in state:
            visit(name)


@pytest.mark.parametrize("name", MODULES)
def test_each_module_imports_alone(name):
    code = f"import sys, {name}; assert not any(m.startswith('verification') for m in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("name", MODULES)
def test_module_declares_all(name):
    tree = ast.parse(_module_path(name).read_text())
    names = {
        t.id
        for node in tree.body
        if isinstance(node, ast.Assign | ast.AnnAssign)
        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
        if isinstance(t, ast.Name)
    }
    assert "__all__" in names, f"{name} has no __all__"
