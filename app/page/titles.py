"""Title blocks of the live views and the page's link, from the snapshot a result was made of.

The views draw their title block (:class:`app.page.bokeh.TitleBlockModels`) from the
settings a result was computed for: :func:`view_title` takes the result's snapshot
(:class:`app.results.Snapshot`), the page URL and the N-axis scale.
"""

from __future__ import annotations

import datetime as dt
import weakref
from collections.abc import Mapping
from typing import Any

import param

import fbs_core

from ..public_url import public_link
from ..report.data import ReportData
from ..report.session import provenance_of, settings_of
from ..report.titles import TitleBlock, compact_title, file_stem

__all__ = [
    "VIEW_OF_KEY",
    "VIEW_ID_KEY",
    "ViewLinks",
    "VIEW_LINKS",
    "link_of",
    "page_address",
    "page_url",
    "short_link",
    "short_query",
    "state_query",
    "title_snapshot",
    "view_title",
]

#: LiveView key -> title-block view.
VIEW_OF_KEY = {
    "mobility": "coupled-response",
    "truncation": "truncation-map",
    "scatter": "scatter-band",
    "eigen": "eigenfrequency",
    "uncoupled": "uncoupled",
    "suggested": "suggested-modes",
    "compare": "compare",
    "contributions": "contributions",
    "phase": "phase",
    "campbell": "campbell",
    "speedmap": "speed-map",
    "wheels": "wheel-contributions",
    "participation": "participation",
    "modeshape": "mode-shape",
    "waves": "waves",
    "selected": "selected-modes",
    "chassistrunc": "chassis-truncation",
}


def _n_total(models: Any) -> int | None:
    tire = None if models is None else getattr(models, "tire", None)
    try:
        return int((tire or fbs_core.reference_tire()).n_modes)
    except Exception:  # a tire without a count: the title omits "of N"
        return None


def title_snapshot(
    s: Any, url: str = "", n_axis: str = "linear", created: dt.datetime | None = None
) -> ReportData:
    """Results-free report data of a session snapshot ``s`` (for titles and names)."""
    models = getattr(s, "models", None)
    return ReportData(
        settings=settings_of(s, n_axis),
        provenance=provenance_of(models),
        url=url if url.startswith(("http://", "https://")) else "",
        created=created or dt.datetime.now(dt.UTC),
        n_modes_total=_n_total(models),
    )


def view_title(
    key: str, s: Any, url: str | None = None, n_axis: str = "linear", link: Any = None
) -> tuple[TitleBlock, str]:
    """``(title block, file stem)`` of the live view ``key`` for the session snapshot ``s``.

    ``url`` None: the short link (:func:`short_link`) of the snapshot ``link`` (default
    ``s``) on the served page's address, so that the link names the settings of a state,
    never the page's URL of a moment later or earlier."""
    if url is None:
        of = s if link is None else link
        layout = title_layout(of)
        url = short_link(page_address(), state_query(of, layout))
        n_axis = layout["naxis"]
    snap = title_snapshot(s, url, n_axis)
    view = VIEW_OF_KEY[key]
    return compact_title(snap, view), file_stem(snap, view)


def _url_defaults() -> dict[str, object]:
    """Default value of every URL query key of the page (state and layout)."""
    from ..state import SCHEMA

    return {st.url: st.default for st in SCHEMA.settings if st.url}


def _is_default(value: Any, default: object) -> bool:
    if isinstance(default, bool) or isinstance(value, bool):
        return str(value).lower() == str(default).lower()
    if isinstance(default, (int, float)):
        try:
            return float(value) == float(default)
        except (TypeError, ValueError):
            return False
    return str(value) == str(default)


def short_query(query: Mapping[str, Any]) -> dict[str, Any]:
    """``query`` without the pairs that hold the default value (the page applies those
    anyway): a link that reproduces the same state, short enough for a title block."""
    defaults = _url_defaults()
    return {k: v for k, v in query.items() if not (k in defaults and _is_default(v, defaults[k]))}


def page_url() -> str:
    """The served page's URL that reproduces its state: the address and the query values
    that differ from the defaults (``""`` when not served).

    With ``FBS_PUBLIC_URL`` set (:mod:`app.public_url`), the address starts with it instead
    of the one in the browser's location bar, so the link opens for its recipient.
    """
    import panel as pn

    loc = pn.state.location
    if loc is None or not loc.href:
        return ""
    return link_of(loc.href, loc.query_params)


def link_of(href: str, query: Mapping[str, Any]) -> str:
    """The link of a page at ``href`` with the ``query`` values: the public base URL in
    front (when set), the query values that differ from the defaults."""
    import urllib.parse

    # the address without its query and fragment, every character a report would refuse
    # (quotes, angle brackets, spaces: a crafted link's path or #fragment) percent-encoded
    href = urllib.parse.quote(href.split("#")[0].split("?")[0], safe=":/%@-._~!$&()*+,;=")
    href = public_link(href)
    query = short_query(query)
    return href + ("?" + urllib.parse.urlencode(query) if query else "")


#: The query key of a view id (:class:`ViewLinks`): a short link's stand-in for its query.
VIEW_ID_KEY = "v"
#: Longest link written as its query in a title block (one line of 10 px type in a
#: half-width plot at 1280 px, ``app.page.bokeh.WRAP``); a longer one is written with a
#: view id.
SHORT_LINK_CHARS = 72


def _serialize(obj_cls: Any, name: str, value: Any) -> str:
    import json

    p = obj_cls.param[name]
    if isinstance(value, tuple):
        value = list(value)
    if (
        isinstance(p, param.Number)
        and not isinstance(p, param.Integer)
        and isinstance(value, int)
        and not isinstance(value, bool)
    ):
        # one spelling per value: a slider's whole number (an int from the browser) and the
        # same number typed (a float) are one setting, written as the float
        value = float(value)
    try:
        out = p.serialize(value)
    except Exception:
        out = value
    return out if isinstance(out, str) else json.dumps(out)


def state_query(
    s: Any, layout: Mapping[str, Any] | None = None, schema: Any = None
) -> dict[str, str]:
    """The URL query of the settings of ``s`` (a :class:`app.results.Snapshot`, or a
    ``DashboardState``) that differ from the defaults, written as the page writes its URL;
    ``layout``: page-layout keys (``naxis``, ``data``...) added when not at their default.
    ``schema``: the declared settings (default :data:`app.state.SCHEMA`).

    The same function writes the page's URL and every title block's link, so that a plot's
    link and the URL of the state it was drawn for are the same text."""
    from ..state import SCHEMA, DashboardState

    schema = SCHEMA if schema is None else schema
    layout = layout or {}
    query: dict[str, str] = {}
    for st in schema.settings:
        if not st.url:
            continue
        if st.field is None:  # the page's layout
            if st.url not in layout:
                continue
            value = layout[st.url]
        elif isinstance(s, DashboardState):
            value = getattr(getattr(s, st.group), st.name)
        else:
            value = getattr(s, st.field)
        text = _serialize(st.owner, st.name, value)
        if text != _serialize(st.owner, st.name, st.default):
            query[st.url] = str(text)
    return query


class ViewLinks:
    """View ids of long queries: a title block's link ``?v=<id>`` that the page opens as the
    query it stands for.

    The id is a digest of the query (the same state has the same id in every session); the
    table lives in the server's memory only, at most ``max_entries`` queries of at most
    ``max_chars`` characters (the oldest dropped first), and is read only by the page
    itself when it opens: a person who cannot open the page learns nothing from an id (no
    route of its own answers it).
    """

    def __init__(self, max_entries: int = 2048, max_chars: int = 8192) -> None:
        import collections
        import threading

        self.max_entries, self.max_chars = max_entries, max_chars
        self._table: collections.OrderedDict[str, str] = collections.OrderedDict()
        self._lock = threading.Lock()

    @staticmethod
    def id_of(query: str) -> str:
        """The view id of a query text (10 characters of its SHA-256, base 32)."""
        import base64
        import hashlib

        digest = hashlib.sha256(query.encode("utf-8")).digest()
        return base64.b32encode(digest).decode("ascii")[:10].lower()

    def add(self, query: str) -> str | None:
        """The id of ``query``, kept (None: too long to keep)."""
        if len(query) > self.max_chars:
            return None
        vid = self.id_of(query)
        with self._lock:
            self._table[vid] = query
            self._table.move_to_end(vid)
            while len(self._table) > self.max_entries:
                self._table.popitem(last=False)
        return vid

    def get(self, vid: str) -> str | None:
        """The query of view id ``vid`` (None: unknown, e.g. made before a restart)."""
        with self._lock:
            query = self._table.get(str(vid))
            if query is not None:
                self._table.move_to_end(str(vid))
            return query

    def __len__(self) -> int:
        return len(self._table)


#: The server's view ids.
VIEW_LINKS = ViewLinks()


def short_link(address: str, query: Mapping[str, str], links: ViewLinks = VIEW_LINKS) -> str:
    """The link of ``address`` with ``query``: the query itself when the link fits a title
    block's line (:data:`SHORT_LINK_CHARS`), else a view id (:class:`ViewLinks`); ``""``
    when there is no address (not served)."""
    import urllib.parse

    if not address:
        return ""
    text = urllib.parse.urlencode(dict(query))
    link = address + ("?" + text if text else "")
    if len(link) <= SHORT_LINK_CHARS:
        return link
    vid = links.add(text)
    return link if vid is None else f"{address}?{VIEW_ID_KEY}={vid}"


#: The layout state (``app.page.layout.PageState``) of each served page, by document.
PAGES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def title_layout(s: Any) -> dict[str, str]:
    """The page-layout keys of a title block's link for snapshot ``s``: the error map's N
    axis of the current page, the uploads ``s`` was made of."""
    import panel as pn

    from .chrome import data_key

    page = PAGES.get(pn.state.curdoc) if pn.state.curdoc is not None else None
    models = getattr(s, "models", None)
    return {
        "naxis": getattr(page, "n_axis", "linear"),
        "data": data_key(provenance_of(models)) if models is not None else "",
    }


def page_address() -> str:
    """The served page's address without its query (the public base URL in front when set,
    :mod:`app.public_url`); ``""`` when not served."""
    import urllib.parse

    import panel as pn

    loc = pn.state.location
    href = loc.href if loc is not None else ""
    if not href:
        doc = pn.state.curdoc
        ctx = getattr(doc, "session_context", None)
        request = getattr(ctx, "request", None)
        if request is None:
            return ""
        proto = getattr(request, "protocol", "http") or "http"
        host = (getattr(request, "headers", {}) or {}).get("Host", "")
        path = getattr(request, "path", "") or ""
        if not host:
            return ""
        href = f"{proto}://{host}{path}"
    href = urllib.parse.quote(href.split("#")[0].split("?")[0], safe=":/%@-._~!$&()*+,;=")
    return public_link(href)


def read_link(loc: Any, obj: Any, keys: Mapping[str, str], on_error: Any = None) -> None:
    """Apply the values of ``loc``'s query to ``obj`` (its parameters by their URL keys), as
    the page does once when it opens; a value a parameter refuses is left out
    (``on_error(values)`` applies the others one by one)."""
    query = loc.query_params
    values: dict[str, Any] = {}
    for name, key in keys.items():
        if key not in query:
            continue
        v = query[key]
        try:
            v = obj.param[name].deserialize(v)
        except Exception:  # a value that is no serialized form of the parameter: as read
            pass
        if not _equal(v, getattr(obj, name)):
            values[name] = v
    if not values:
        return
    try:
        obj.param.update(**values)
    except Exception:  # param's ValueError/TypeError: out of range, wrong type
        if on_error is not None:
            on_error(values)


def _equal(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except Exception:
        return False


def resolve_view_id(loc: Any, links: ViewLinks = VIEW_LINKS) -> str | None:
    """Replace a view id in ``loc``'s query by the query it stands for (the other keys of
    the link kept, e.g. ``view=present``); returns the id when it is unknown to this server
    (made before a restart: the page opens on the link's other keys)."""
    import urllib.parse

    query = dict(urllib.parse.parse_qsl((loc.search or "").lstrip("?"), keep_blank_values=True))
    vid = query.pop(VIEW_ID_KEY, None)
    if vid is None:
        return None
    stored = links.get(vid)
    merged = dict(urllib.parse.parse_qsl(stored or "", keep_blank_values=True))
    merged.update(query)
    loc.search = "?" + urllib.parse.urlencode(merged) if merged else ""
    return None if stored is not None else vid


class PageLink:
    """The page's URL, written from the state: after every change of a setting, the whole
    query of the settings in force (:func:`state_query`) on the page's draw queue, so that
    the last write is the newest state (Panel's own two-way sync wrote the changed key
    only, from the thread of the change, and read the URL back into the state: two
    changes on two threads lost one key or set the state back)."""

    def __init__(self, loc: Any, state: Any, page: Any = None) -> None:
        from ..runtime.draw import served_document

        self.loc, self.state, self.page = loc, state, page
        self._doc = served_document()
        self._pending = False
        import threading

        self._lock = threading.Lock()

    def layout(self) -> dict[str, Any]:
        """The page-layout keys of the URL (all of them, defaults dropped later)."""
        from .layout import PAGE_URL_KEYS

        if self.page is None:
            return {}
        return {key: getattr(self.page, name) for name, key in PAGE_URL_KEYS.items()}

    def query(self) -> str:
        """The query text of the state and layout now."""
        import urllib.parse

        q = state_query(self.state, self.layout())
        return "?" + urllib.parse.urlencode(q) if q else ""

    def watch(self) -> None:
        """Write the URL after every change of a setting of the link."""
        from ..state import URL_KEYS
        from .layout import PAGE_URL_KEYS

        for group, keys in URL_KEYS.items():
            getattr(self.state, group).param.watch(self.changed, list(keys))
        if self.page is not None:
            self.page.param.watch(self.changed, list(PAGE_URL_KEYS))

    def changed(self, *_: Any) -> None:
        from ..runtime.draw import on_document

        with self._lock:
            if self._pending:
                return
            self._pending = True
        on_document(self._doc, self.write)

    def write(self, force: bool = False) -> None:
        """Set the URL to the settings in force (where the page's models may change);
        ``force``: send it to the browser even when the server's copy holds it already (the
        browser showed another, e.g. a view id's link)."""
        with self._lock:
            self._pending = False
        text = self.query()
        if force and (self.loc.search or "") == text:
            self.loc.search = text + "&" if text else "?"  # a change the browser is sent
        if (self.loc.search or "") != text:
            self.loc.search = text

    def write_again(self) -> None:
        """:meth:`write` with ``force`` (where the page's models may change)."""
        from ..runtime.draw import on_document

        on_document(self._doc, lambda: self.write(force=True))
