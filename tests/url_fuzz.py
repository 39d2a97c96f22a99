"""Hostile URL values and the URL keys a page reads, shared by the fuzz tests (issue 28).

``tests/test_url_safety.py`` builds pages in process with every key of the link holding a
hostile value, the Analysis card on each of its tabs; ``tests/browser/
test_server_attacks.py`` sends the same values to the server as the Docker image starts it.
The keys are not listed here: :func:`page_keys` records the keys that a page build itself
keeps in sync with the URL (every ``Location.sync`` of ``app.main.create_app``), so a key
added to the page is fuzzed without a change here.
"""

from __future__ import annotations

import html
import math
import re

import panel as pn
import param
from panel.io.location import Location

#: Values sent to every URL key at once (one page each): markup, script and ``javascript:``
#: links, quotes, Markdown links and images, numbers a parser takes but no control allows
#: (NaN, infinities, huge, negative), empty, control and bidi characters, other scripts,
#: digits of another script, 1000 characters, JSON, a crafted pin.
FUZZ = [
    "<img src=x onerror=fbsXss()>",
    "<script>fbsXss()</script>",
    "javascript:fbsXss()",
    "\"'><svg onload=fbsXss()>",
    "' onmouseover='fbsXss()",
    "[fbsxss](http://attacker.example/fbsxss)",
    "![fbsxss](http://attacker.example/fbsxss.png)",
    "[x](javascript:fbsXss())",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1",
    "-0.5",
    "99999999999999999999999",
    "",
    "\u202e\u0000\r\n",
    "\u00e9\u4e2d\U0001f600",
    "\uff11\uff12",  # fullwidth 12: Python's int() and float() read it as 12
    "A" * 1000,  # in ~40 keys: a 40 KB query (Tornado drops requests whose head > 64 KB)
    "true",
    "{}",
    "x~h99~N-5~dq~c7dof|y",
]
#: What a hostile value would have become if it reached a page as markup: an element of
#: it, or a link or image to the attacker or to script.
ELEMENTS = re.compile(
    r"<(img|script|svg)\b[^>]*fbsXss|<script>fbsXss|\son\w+='fbsXss|"
    r"(href|src)=[\"']?(http://attacker\.example|javascript:)",
    re.I,
)
#: String settings that keep a value as given and answer for it on the page: ``pins`` (a
#: message naming the malformed pin), ``data`` (the link notice, as text), ``compare_to``
#: (a pin's name: one not pinned compares with the first pin).
FREE_TEXT = {"pins", "compare_to", "data"}


def parsed(value: str, parameter: param.Parameter):
    """What ``value`` means for ``parameter`` read by hand (``None``: nothing it allows):
    ``true``/``false`` for a boolean, a finite number for a number, an allowed choice for a
    selector. The page must show this or the parameter's default."""
    if isinstance(parameter, param.Boolean):
        return {"true": True, "false": False}.get(value)
    if isinstance(parameter, param.Number):  # Integer too
        try:
            x = float(value)
        except ValueError:
            return None
        if not math.isfinite(x):
            return None
        if isinstance(parameter, param.Integer):
            return int(x) if x == int(x) else None
        return x
    if isinstance(parameter, param.Selector):
        for choice in parameter.objects:
            if str(choice) == value:
                return choice
        return None
    return value


class Recorded:
    """What a page build kept in sync with the URL: ``(parameterized, {parameter: key})``."""

    def __init__(self) -> None:
        self.synced: list[tuple[object, dict[str, str]]] = []

    @property
    def keys(self) -> list[str]:
        return [k for _, names in self.synced for k in names.values()]

    def key_of(self, cls: type, parameter: str) -> str:
        """The URL key of ``parameter`` of the synced object of class ``cls``."""
        for obj, names in self.synced:
            if isinstance(obj, cls) and parameter in names:
                return names[parameter]
        raise LookupError(f"{cls.__name__}.{parameter} is not in the URL")


def served_location(monkeypatch, query: str) -> Recorded:
    """Make ``pn.state.location`` a Location holding ``query`` (as in a served session) and
    record every object the page reads from its link while it is built (``Location.sync``
    or the page's own reader, ``app.page.titles.read_link``)."""
    import app.main
    from app.page import titles

    loc = Location(search="?" + query if query else "")
    rec = Recorded()
    original = Location.sync
    original_read = titles.read_link

    def sync(self, parameterized, parameters=None, on_error=None):
        names = parameters or [p for p in parameterized.param if p != "name"]
        if not isinstance(names, dict):
            names = dict(zip(names, names, strict=True))
        rec.synced.append((parameterized, dict(names)))
        return original(self, parameterized, parameters, on_error)

    def read_link(loc_, obj, keys, on_error=None):
        rec.synced.append((obj, dict(keys)))
        return original_read(loc_, obj, keys, on_error)

    monkeypatch.setattr(Location, "sync", sync)
    monkeypatch.setattr(app.main, "read_link", read_link)
    monkeypatch.setattr(type(pn.state), "location", property(lambda self: loc))
    return rec


def page_keys(monkeypatch) -> Recorded:
    """Every URL key a page of the dashboard reads, recorded from a page build."""
    from app.main import close_page, create_app

    with monkeypatch.context() as m:
        rec = served_location(m, "")
        close_page(create_app())
    return rec


def model_html(models) -> str:
    """The HTML that Bokeh models put into the page (their ``text``, which a model carries
    escaped once and the page decodes once)."""
    out = []
    for m in models:
        if "text" in m.properties():
            try:
                v = m.text
            except Exception:  # noqa: BLE001 (a property without a value)
                continue
            if isinstance(v, str):
                out.append(html.unescape(v))
    return "\n".join(out)
