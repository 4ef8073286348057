"""The layout's rules, checked on the source: who may import whom, no import cycles, the
core names no client, and a generous module-size ceiling.

``springfem`` (the core) imports none of the other packages; ``springmodel``,
``reference_fem`` and the model plug-in ``corotational`` import only the core and never each
other; ``studies`` may import all.
Imports count wherever they are: at module level, inside functions, and in the doctests of
docstrings (a doctest is code the module's documentation runs).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("springfem", "springmodel", "reference_fem", "corotational", "peers", "studies")
ALLOWED = {
    "springfem": {"springfem"},
    "springmodel": {"springfem", "springmodel"},
    "reference_fem": {"springfem", "reference_fem"},
    "corotational": {"springfem", "corotational"},
    "peers": {"springfem", "peers"},
    "studies": set(PACKAGES),
}
#: A module this long is a smell worth a look (one idea per module), not a target.
CEILING = 600
#: The command-line package: nothing outside it imports it.
CLI = "studies.cli"


def _modules(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def _name(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _trees(path: Path) -> list[ast.AST]:
    """The module's syntax tree and those of its doctest lines (``>>> import ...``)."""
    src = path.read_text(encoding="utf-8")
    trees = [ast.parse(src)]
    for line in re.findall(r"^\s*>>> ((?:from|import) .*)$", src, re.M):
        try:
            trees.append(ast.parse(line.strip()))
        except SyntaxError:  # a continued statement: its first line alone does not parse
            pass
    return trees


def _imports(path: Path, modules: set[str], root: Path = ROOT) -> set[str]:
    """The project modules ``path`` imports (absolute or relative, any depth, doctests)."""
    me = _name(path, root)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found = set()

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    for tree in _trees(path):
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                # "from pkg import sub" imports the submodule when there is one
                targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod
                           for a in node.names]  # fmt: skip
            else:
                continue
            for t in targets:
                r = resolve(t)
                if r is not None and r != me:
                    found.add(r)
    return found


def _graph() -> dict[str, set[str]]:
    paths = [p for pkg in PACKAGES for p in _modules(pkg)]
    modules = {_name(p) for p in paths}
    return {_name(p): _imports(p, modules) for p in paths}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
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


def test_the_scan_sees_every_kind_of_import(tmp_path):
    pkg = tmp_path / "springfem"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text(
        '"""Doc.\n\n>>> from springfem.c import x\n"""\nimport os\nfrom . import b\n'
        "def g():\n    from .d import y\n"
    )
    for m in ("b", "c", "d"):
        (pkg / f"{m}.py").write_text("")
    modules = {"springfem", "springfem.a", "springfem.b", "springfem.c", "springfem.d"}
    found = _imports(pkg / "a.py", modules, root=tmp_path)
    assert found == {"springfem.b", "springfem.c", "springfem.d"}


def test_the_cycle_finder_finds_cycles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert _cycles(g) == [["a", "b", "c"]]


@pytest.mark.parametrize("package", PACKAGES)
def test_import_rules(package):
    graph = _graph()
    bad = {
        m: sorted({t.split(".")[0] for t in targets} - ALLOWED[package])
        for m, targets in graph.items()
        if m.split(".")[0] == package
    }
    assert {k: v for k, v in bad.items() if v} == {}


def test_no_import_cycles():
    assert _cycles(_graph()) == []


def test_nothing_imports_the_command_line():
    graph = _graph()
    users = {m for m, targets in graph.items() if any(t.startswith(CLI) for t in targets)}
    assert {m for m in users if not m.startswith(CLI)} == set()


def test_the_core_names_no_client():
    """The core's code (not its prose) never names the packages built on it: models register
    their scene sections and kernel packages themselves (entry points in pyproject.toml)."""
    clients = ("springmodel", "reference_fem", "corotational", "studies")
    named = []
    for p in _modules("springfem"):
        tree = ast.parse(p.read_text(encoding="utf-8"))
        docstrings = {
            id(n.body[0].value)
            for n in ast.walk(tree)
            if isinstance(n, ast.Module | ast.FunctionDef | ast.ClassDef | ast.AsyncFunctionDef)
            and n.body
            and isinstance(n.body[0], ast.Expr)
            and isinstance(n.body[0].value, ast.Constant)
        }
        for n in ast.walk(tree):
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docstrings:
                if any(re.search(rf"\b{c}\b", n.value) for c in clients):
                    named.append(f"{p.relative_to(ROOT)}:{n.lineno}")
    assert named == []


@pytest.mark.parametrize("package", PACKAGES)
def test_modules_stay_under_the_ceiling(package):
    too_long = {
        str(p.relative_to(ROOT)): n
        for p in _modules(package)
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > CEILING
    }
    assert too_long == {}
