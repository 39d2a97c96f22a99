"""A link whose query cannot be read opens a page that names the key, never a broken page.

Panel reads every value of a served page's query the first time the page asks for its
location (``pn.state.location``), before the dashboard can look at it: a value of digits is
read with ``int()``, which refuses more than ``sys.get_int_max_str_digits()`` digits (4,300)
with a ``ValueError``, which would leave the page blank and a traceback in the server's
log. So the raw query of the request is checked first (:func:`unreadable_keys`), and a link with a
value that cannot be read opens :func:`unreadable_link_page` instead of the dashboard: a
message naming each such key and why, and a link to the same page without those keys.

Unreadable are: a value of digits longer than Python reads, a key or a value longer than
:data:`MAX_QUERY_CHARS` (no setting of the page holds more: eight pins are ~1,400
characters), and bytes that are not UTF-8 text. Nothing of the link is shown as markup.
"""

from __future__ import annotations

import html
import sys
import urllib.parse
from collections.abc import Mapping, Sequence

__all__ = [
    "MAX_QUERY_CHARS",
    "kept_query",
    "unreadable_keys",
    "unreadable_link_html",
    "unreadable_link_page",
]

#: Longest key or value of a link's query that the page reads (characters).
MAX_QUERY_CHARS = 4_000
#: Characters of a key that a message repeats at most (the rest: "...").
SHOWN_KEY_CHARS = 40


def _why(text: bytes) -> str | None:
    """Why a key or value of the query cannot be read, or None if it can."""
    try:
        value = text.decode("utf-8")
    except UnicodeDecodeError:
        return "is not UTF-8 text"
    limit = sys.get_int_max_str_digits()
    if value.isdigit() and limit and len(value) > limit:
        return f"has {len(value):,} digits (at most {limit:,} are read)"
    if len(value) > MAX_QUERY_CHARS:
        return f"has {len(value):,} characters (at most {MAX_QUERY_CHARS:,} are read)"
    return None


def _raw(key: str) -> bytes:
    """The bytes of a key as the request carried them (Tornado decodes keys as Latin-1)."""
    try:
        return key.encode("latin-1")
    except UnicodeEncodeError:
        return key.encode("utf-8", "surrogateescape")


def _text(key: str) -> str:
    """A key of the request as text (its UTF-8 bytes decoded; replacement characters for
    bytes that are not UTF-8)."""
    return _raw(key).decode("utf-8", "replace")


def shown_key(key: str) -> str:
    """A key as a message repeats it: quoted, at most :data:`SHOWN_KEY_CHARS` characters,
    control characters escaped (plain text: the caller escapes it for HTML)."""
    short = key[:SHOWN_KEY_CHARS]
    return repr(short)[:-1] + ("...'" if len(key) > SHOWN_KEY_CHARS else "'")


def unreadable_keys(arguments: Mapping[str, Sequence[bytes]]) -> dict[str, str]:
    """The keys of a request's query (``{key: [raw values]}``, as Tornado and
    ``pn.state.session_args`` give them: keys decoded as Latin-1, values as bytes) that
    cannot be read, each (as text) with the reason.

    Examples
    --------
    >>> unreadable_keys({"h": [b"9" * 5000], "N": [b"100"]})
    {'h': 'its value has 5,000 digits (at most 4,300 are read)'}
    """
    bad: dict[str, str] = {}
    for key, values in arguments.items():
        why = _why(_raw(key))
        if why is not None:
            bad[_text(key)] = f"the key {why}"
            continue
        for value in values:
            why = _why(bytes(value))
            if why is not None:
                bad[_text(key)] = f"{'its value' if len(values) == 1 else 'a value'} {why}"
                break
    return bad


def kept_query(arguments: Mapping[str, Sequence[bytes]], drop: Sequence[str]) -> str:
    """The query (``?...``, or "" when nothing is left) of ``arguments`` without the keys
    ``drop``, their values in the order given."""
    pairs = [
        (_text(key), bytes(v).decode("utf-8"))
        for key, values in arguments.items()
        if _text(key) not in drop
        for v in values
    ]
    return "?" + urllib.parse.urlencode(pairs) if pairs else ""


def unreadable_link_html(bad: Mapping[str, str], kept: str, path: str = "") -> str:
    """The message of :func:`unreadable_link_page` as HTML: the keys and reasons as escaped
    text, and a link to ``path`` with the query ``kept`` (:func:`kept_query`)."""
    items = "".join(
        f"<li><b>{html.escape(shown_key(k))}</b>: {html.escape(why)}</li>" for k, why in bad.items()
    )
    href = html.escape((path or "") + (kept or "?"), quote=True)
    which = "this key" if len(bad) == 1 else "these keys"
    return (
        '<div class="alert alert-warning unreadable-link" role="alert">'
        "<p>This link cannot be opened: the dashboard cannot read the value of "
        f"{which}.</p><ul>{items}</ul>"
        f'<p><a href="{href}">Open the dashboard without {which}</a> '
        "(the other settings of the link are kept).</p></div>"
    )


def unreadable_link_page(bad: Mapping[str, str], kept: str, path: str = ""):
    """A page (Panel column) saying which keys of the link cannot be read and why, with a
    link to the dashboard without them."""
    import panel as pn

    return pn.Column(
        pn.pane.HTML(
            "<h2>Tire-chassis FBS: bushing vibration dashboard</h2>", sizing_mode="stretch_width"
        ),
        pn.pane.HTML(
            unreadable_link_html(bad, kept, path),
            sizing_mode="stretch_width",
            css_classes=["unreadable-link"],
        ),
        sizing_mode="stretch_width",
        margin=(10, 20),
    )
