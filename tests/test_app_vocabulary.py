"""The app spells the core's vocabulary nowhere of its own (issue 27): the six directions,
the couplings, the dB conversion and the read-only copy come from
``fbs_core.vocabulary``; the app's dB is ``magnitude_db`` only."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _words(node) -> set:
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return {e.value for e in node.elts if isinstance(e, ast.Constant)}
    return set()


def _doc(expr: ast.Expr) -> bool:
    return isinstance(expr.value, ast.Constant) and isinstance(expr.value.value, str)


def spelled(tree: ast.AST) -> list[tuple[int, str]]:
    found = []
    for node in ast.walk(tree):
        words = _words(node)
        if {"rx", "ry", "rz"} <= words or words == {"x", "y", "z"}:
            found.append((node.lineno, "directions (vocabulary.DIRECTIONS)"))
        if {"6dof", "5dof"} <= words:
            found.append((node.lineno, "couplings (vocabulary.COUPLINGS)"))
        if isinstance(node, ast.Call) and "log10" in ast.unparse(node.func):
            found.append((node.lineno, "dB (vocabulary.magnitude_db)"))
        if isinstance(node, ast.alias) and node.name == "magnitude_db" and node.asname:
            found.append((getattr(node, "lineno", 0), f"magnitude_db as {node.asname}"))
        if isinstance(node, ast.FunctionDef) and "setflags(write=False)" in ast.unparse(node):
            found.append((node.lineno, "read-only copy (vocabulary.readonly)"))
        if isinstance(node, ast.FunctionDef):  # a function that only renames magnitude_db
            body = [b for b in node.body if not (isinstance(b, ast.Expr) and _doc(b))]
            if (
                len(body) == 1
                and isinstance(body[0], ast.Return)
                and isinstance(body[0].value, ast.Call)
                and ast.unparse(body[0].value.func).endswith("magnitude_db")
            ):
                found.append((node.lineno, f"dB renamed {node.name} (vocabulary.magnitude_db)"))
    return found


def test_the_app_spells_the_vocabulary_only_through_fbs_core():
    found = [
        f"{path.relative_to(ROOT)}:{line} {what}"
        for path in sorted((ROOT / "app").rglob("*.py"))
        for line, what in spelled(ast.parse(path.read_text()))
    ]
    assert found == []


def test_the_scan_finds_what_it_must():
    sample = (
        "DOFS = ('x', 'y', 'z', 'rx', 'ry', 'rz')\n"
        "C = ['6dof', '5dof']\n"
        "def db(v):\n    return 20 * np.log10(abs(v))\n"
        "from fbs_core.vocabulary import magnitude_db as _db\n"
        "def ro(a):\n    a = a.copy(); a.setflags(write=False); return a\n"
        "def level(x):\n    'the level'\n    return magnitude_db(x)\n"
    )
    kinds = {what.split(" ")[0] for _, what in spelled(ast.parse(sample))}
    assert kinds == {"directions", "couplings", "dB", "magnitude_db", "read-only"}
