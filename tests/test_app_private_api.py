"""The app uses only public mechanisms of Panel, Bokeh and BokehJS, except in one isolated
module (``app/panel_private.py``), whose private use fails a test here when it disappears.

Scanned: every module of ``app``, the browser tests and the dashboard benchmarks. Flagged:
an attribute ``x._name`` on anything but ``self``/``cls``, ``getattr(x, "_name")`` and
friends, imports of private names or modules of Panel/Bokeh, and ``._name`` inside the
JavaScript strings that run in the page.
"""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path

import panel as pn
import pytest

ROOT = Path(__file__).resolve().parents[1]
ISOLATED = ROOT / "app" / "panel_private.py"
SCANNED = sorted(
    [p for p in (ROOT / "app").rglob("*.py") if p != ISOLATED]
    + list((ROOT / "tests" / "browser").glob("*.py"))
    + [ROOT / "bench" / n for n in ("bench_dashboard.py", "load_test.py", "load_clients.py")]
)
JS_PRIVATE = re.compile(r"\.\s*_[A-Za-z]\w*")


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def violations(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    # names bound to the project's own modules: their private names are the project's
    own_modules = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (
            node.level > 0 or (node.module or "").split(".")[0] in ("app", "fbs_core")
        ):
            own_modules |= {a.asname or a.name for a in node.names}
        elif isinstance(node, ast.Import):
            own_modules |= {
                a.asname or a.name for a in node.names if a.name.split(".")[0] in ("app",)
            }
    out = []
    for node in ast.walk(tree):
        where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Attribute) and _private(node.attr):
            own = isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")
            own |= (
                isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name)
                and node.value.func.id == "super"
            )
            own |= isinstance(node.value, ast.Name) and node.value.id in own_modules
            if not own:
                out.append(f"{where} attribute .{node.attr}")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            if node.func.id in ("getattr", "setattr", "hasattr", "delattr") and len(node.args) > 1:
                arg = node.args[1]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    if _private(arg.value):
                        out.append(f"{where} {node.func.id}(..., {arg.value!r})")
        elif isinstance(node, ast.ImportFrom) and node.module:
            parts = node.module.split(".")
            if parts[0] in ("panel", "bokeh"):
                if any(_private(p) for p in parts) or parts[:2] == ["panel", "models"]:
                    out.append(f"{where} import from {node.module}")
                out += [f"{where} import {a.name}" for a in node.names if _private(a.name)]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if "=>" in node.value or "function" in node.value or "Bokeh." in node.value:
                for m in JS_PRIVATE.findall(node.value):
                    out.append(f"{where} JavaScript {m.strip()}")
    return out


@pytest.mark.parametrize("path", SCANNED, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_attribute_of_panel_bokeh_or_bokehjs(path):
    assert violations(path) == []


def test_the_scan_finds_what_it_must():
    """The checker itself: each kind of private use is caught (it can fail)."""
    bad = ROOT / "tests" / "_private_sample.py"
    bad.write_text(
        "import panel as pn\n"
        "from panel.models.markup import HTML\n"
        "from panel.io.document import _cleanup_doc\n"
        "w = pn.widgets.IntSlider()\n"
        "w._debounce = 5\n"
        "ok = pn.state._unblocked(None)\n"
        "x = getattr(doc, '_pending_writes', None)\n"
        "JS = '() => [...Bokeh.documents[0]._all_models.values()]'\n"
        "self_ok = self._mine\n"
        "from . import figures\n"
        "own_ok = figures._LOCK\n"
    )
    try:
        found = violations(bad)
    finally:
        bad.unlink()
    joined = "\n".join(found)
    for what in (
        "import from panel.models.markup",
        "import _cleanup_doc",
        "attribute ._debounce",
        "attribute ._unblocked",
        "getattr(..., '_pending_writes')",
        "JavaScript ._all_models",
    ):
        assert what in joined
    assert "_mine" not in joined and "_LOCK" not in joined


def test_the_isolated_private_use_still_exists_in_panel():
    """``app/panel_private.py`` sets ``Widget._debounce``: Panel must still have it and read
    it where it schedules a browser change (else the setting silently does nothing)."""
    from app.panel_private import DEBOUNCE_MS, respond_at_once

    assert isinstance(pn.widgets.IntSlider._debounce, int)
    from panel.reactive import Syncable

    assert "self._debounce" in inspect.getsource(Syncable)
    w = pn.widgets.EditableFloatSlider(start=0, end=1)
    respond_at_once(w)
    assert all(x._debounce == DEBOUNCE_MS for x in w.select(pn.widgets.Widget))
