"""The packages' import graph has no cycle.

A cycle (``a`` imports ``b``, which imports ``a``, perhaps inside a function) means neither
module can be read, tested or moved without the other; it is how the house's rooms blur.
The graph is read from the source (``ast``): every import of ``fbs_core`` and ``app``,
at a module's top and inside functions, and the package ``__init__`` an import runs on the
way. Imports under ``if TYPE_CHECKING:`` are annotations, not dependencies at run time, and
are left out.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("fbs_core", "app")


def modules(root: Path = ROOT, packages=PACKAGES) -> dict[str, Path]:
    """Dotted name -> file of every module of the packages."""
    out = {}
    for pkg in packages:
        for p in sorted((root / pkg).rglob("*.py")):
            parts = p.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = p
    return out


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                skip.update(id(n) for n in ast.walk(sub))
    return skip


def _absolute(module: str, is_package: bool, level: int, name: str | None) -> str:
    if level == 0:
        return name or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([name] if name else []))


def import_graph(mods: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules of the packages it imports at run time."""
    graph: dict[str, set[str]] = defaultdict(set)

    def known(name: str) -> str:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name

    for mod, path in mods.items():
        tree = ast.parse(path.read_text(), str(path))
        skip = _type_checking_nodes(tree)
        is_package = path.name == "__init__.py"
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _absolute(mod, is_package, node.level, node.module)
                names = [base] + [f"{base}.{a.name}" for a in node.names]
            else:
                continue
            for name in names:
                target = known(name)
                # the target and the packages whose __init__ runs on the way to it
                parts = target.split(".")
                for k in range(1, len(parts) + 1):
                    t = ".".join(parts[:k])
                    own = mod == t or mod.startswith(t + ".")  # an ancestor of the importer
                    if t in mods and not own:
                        graph[mod].add(t)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
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
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_import_graph_has_no_cycle():
    graph = import_graph(modules())
    found = cycles(graph)
    words = [
        " <-> ".join(c) + ": " + "; ".join(f"{a} imports {sorted(graph[a] & set(c))}" for a in c)
        for c in found
    ]
    assert not found, "\n".join(words)


@pytest.mark.parametrize(
    "files, cyclic",
    [
        ({"a.py": "from . import b\n", "b.py": "def f():\n    from . import a\n"}, True),
        ({"a.py": "from . import b\n", "b.py": "import os\n"}, False),
        (
            {
                "a.py": "from . import b\n",
                "b.py": "from typing import TYPE_CHECKING\n"
                "if TYPE_CHECKING:\n    from . import a\n",
            },
            False,
        ),
        # importing c.x runs c's __init__, which imports a
        ({"a.py": "from .c import x\n", "c/__init__.py": "from .. import a\n", "c/x.py": ""}, True),
    ],
)
def test_the_check_finds_a_cycle_where_there_is_one(tmp_path, files, cyclic):
    pkg = tmp_path / "pkg"
    for name, text in {"__init__.py": "", **files}.items():
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_text(text)
    mods = modules(tmp_path, ("pkg",))
    assert bool(cycles(import_graph(mods))) is cyclic
