"""No internal reference ("issue 14") reaches the interface: every string the page, its help,
its tooltips (parameter docs), the report and the core's messages can show is scanned.

Scanned: every string constant of ``app`` and ``fbs_core`` that is not a docstring (captions,
titles, labels, parameter docs shown as tooltips, metadata, error messages), the help page
(``app/page/help.md``) and the data files the page reads (``data/*.json``). Docstrings and
comments are for developers and are not scanned.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INTERNAL = re.compile(r"\bissues? ?#?\d+", re.IGNORECASE)


def _strings(path: Path):
    """(line, text) of every string constant of ``path`` that is not a docstring."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    docs = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docs.add(id(body[0].value))
    for node in ast.walk(tree):
        # (the literal parts of f-strings are constants of their own)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            yield node.lineno, node.value


def test_no_user_visible_text_names_an_internal_issue():
    found = []
    for package in ("app", "fbs_core"):
        for path in sorted((ROOT / package).rglob("*.py")):
            for line, text in _strings(path):
                if INTERNAL.search(text):
                    found.append(f"{path.relative_to(ROOT)}:{line}: {text[:80]!r}")
    texts = [ROOT / "app" / "page" / "help.md", *sorted((ROOT / "data").glob("*.json"))]
    for path in texts:
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if INTERNAL.search(line):
                found.append(f"{path.relative_to(ROOT)}:{i}: {line[:80]!r}")
    assert not found, "internal issue references in the interface:\n" + "\n".join(found)


def test_the_scan_finds_what_it_looks_for(tmp_path):
    """The scan itself: a caption naming an issue is found, a docstring is not."""
    p = tmp_path / "m.py"
    p.write_text(
        '"""Module (issue 3)."""\n'
        'def f():\n    """Doc (issue 4)."""\n    return "Landmarks (issue 14)"\n'
        'x = f"Corridor (Issue 32) {1}"\n'
    )
    hits = [t for _, t in _strings(p) if INTERNAL.search(t)]
    assert sorted(hits) == ["Corridor (Issue 32) ", "Landmarks (issue 14)"]
