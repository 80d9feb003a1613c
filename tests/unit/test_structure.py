"""The package's plan: its modules import one another without a cycle (imports written inside
functions counted too), package-internal imports stand at the top of their files, and no
module holds two ideas' worth of lines.  Read from the source with ``ast``, nothing imported."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "pacto_ng"
#: the most package-internal imports that may be written inside functions
MAX_LOCAL_IMPORTS = 10
#: the most lines a module may have
MAX_LINES = 450
#: the most lines a function may have, from its ``def`` to its last line, docstring included
MAX_FUNCTION_LINES = 80


def _modules(package: Path = PACKAGE) -> dict[str, Path]:
    out = {}
    for path in package.rglob("*.py"):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _resolve(name: str, node: ast.ImportFrom, modules: dict) -> list[str]:
    """The package modules an ``from ... import ...`` names (a module, or a module and names
    from it; a name that is itself a submodule counts as that submodule)."""
    if node.level:
        package = name if modules[name].name == "__init__.py" else name.rpartition(".")[0]
        for _ in range(node.level - 1):
            package = package.rpartition(".")[0]
        base = f"{package}.{node.module}" if node.module else package
    else:
        base = node.module or ""
    found = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        found.append(sub if sub in modules else base)
    return [m for m in found if m in modules]


def _imports(modules: dict) -> dict[str, list[tuple[str, bool]]]:
    """Per module, the package modules it imports and whether inside a function (imports
    for type checkers only, under ``if TYPE_CHECKING:``, are not imports at run time)."""
    graph = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        edges = []
        local_nodes, typing_only = set(), set()
        for fn in ast.walk(tree):
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                local_nodes.update(id(n) for n in ast.walk(fn))
            elif isinstance(fn, ast.If) and "TYPE_CHECKING" in ast.unparse(fn.test):
                typing_only.update(id(n) for n in ast.walk(fn))  # never imported at run time
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            if isinstance(node, ast.ImportFrom):
                targets = _resolve(name, node, modules)
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name in modules]
            else:
                continue
            edges += [(t, id(node) in local_nodes) for t in targets if t != name]
        graph[name] = edges
    return graph


def _cycles(graph: dict) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w, _ in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


@pytest.fixture(scope="module")
def graph():
    return _imports(_modules())


def test_the_reader_finds_every_kind_of_import(tmp_path):
    """Relative imports of every depth, absolute ones, a submodule imported by name, an
    import inside a function, and one for type checkers only (not an import at run time)."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "from .a import A\n",
        "a.py": "from typing import TYPE_CHECKING\nfrom .sub import b\nif TYPE_CHECKING:\n"
                "    from .c import C\nA = 1\n",
        "c.py": "import pkg.a\n\ndef f():\n    from .sub.b import B\n    return B\nC = 1\n",
        "sub/__init__.py": "",
        "sub/b.py": "from ..c import C\nB = 1\n",
    }
    for name, text in files.items():
        (pkg / name).write_text(text)
    graph = _imports(_modules(pkg))
    assert sorted(graph["pkg"]) == [("pkg.a", False)]
    assert sorted(graph["pkg.a"]) == [("pkg.sub.b", False)]  # not pkg.c: type checking only
    assert sorted(graph["pkg.c"]) == [("pkg.a", False), ("pkg.sub.b", True)]
    assert sorted(graph["pkg.sub.b"]) == [("pkg.c", False)]
    assert _cycles(graph) == [["pkg.a", "pkg.c", "pkg.sub.b"]]


def test_no_import_cycle(graph):
    assert _cycles(graph) == []


def test_package_imports_stand_at_the_top(graph):
    local = sorted(f"{m} -> {t}" for m, edges in graph.items() for t, inside in edges if inside)
    assert len(local) <= MAX_LOCAL_IMPORTS, local


def test_no_module_over_the_line_limit():
    long = {str(p.relative_to(PACKAGE.parent)): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert long == {}


def test_no_function_over_the_line_limit():
    long = {}
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long[f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {node.name}"] = n
    assert long == {}


def test_every_subpackage_is_installed():
    """pyproject.toml lists its packages by hand: a subpackage missing there is absent from
    an installed (non-editable) pacto_ng, while the tests, run from the source tree, pass."""
    import tomllib

    listed = set(tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())
                 ["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(PACKAGE.parent).parts)
             for p in PACKAGE.rglob("__init__.py")}
    assert found <= listed, sorted(found - listed)


def _private_reads(tree) -> set[tuple[str, int]]:
    """``(name, line)`` of every ``obj._name`` read where ``obj`` is not ``self``/``cls``."""
    return {(node.attr, node.lineno) for node in ast.walk(tree)
            if isinstance(node, ast.Attribute) and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))}


def _own_names(tree) -> set[str]:
    """The names a module defines: functions, classes and ``self.X`` attributes it sets."""
    own = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            own.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            own.add(node.attr)
    return own


def test_the_reader_of_private_names_finds_one_read_across_modules():
    tree = ast.parse("class A:\n    def f(self, b):\n        self._x = 1\n"
                     "        return self._x + b._y + b._x\n")
    assert {name for name, _ in _private_reads(tree)} == {"_y", "_x"}
    assert {name for name, _ in _private_reads(tree)} - _own_names(tree) == {"_y"}


def test_no_private_name_is_read_across_modules():
    found = {}
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text())
        own = _own_names(tree)
        for name, line in _private_reads(tree):
            if name not in own:
                found[f"{path.relative_to(PACKAGE.parent)}:{line}"] = name
    assert found == {}


BLOCK_STORAGE = {"gfu", "gfx", "gfp", "fes"}  # the blocks' GridFunctions and spaces


def test_only_the_blocks_own_package_reads_their_storage():
    """Outside physics/, a block's fields are read through its public names (``mech.u``,
    ``mech.state_vector``, ``mech.ndof``, ``pressure_block.pressure``)."""
    found = {}
    for path in PACKAGE.rglob("*.py"):
        if path.parent.name == "physics":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Attribute) and node.attr in BLOCK_STORAGE
                    and not (isinstance(node.value, ast.Name) and node.value.id == "self")):
                found[f"{path.relative_to(PACKAGE.parent)}:{node.lineno}"] = ast.unparse(node)
    assert found == {}
