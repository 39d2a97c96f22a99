"""Title blocks of the live views and the page's link, from the snapshot a result was made of.

The views draw their title block (:class:`app.page.bokeh.TitleBlockModels`) from the
settings a result was computed for: :func:`view_title` takes the result's snapshot
(:class:`app.results.Snapshot`), the page URL and the N-axis scale.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from typing import Any

import fbs_core

from ..public_url import public_link
from ..report.data import ReportData
from ..report.session import provenance_of, settings_of
from ..report.titles import TitleBlock, compact_title, file_stem

__all__ = ["VIEW_OF_KEY", "title_snapshot", "view_title", "link_of", "page_url", "short_query"]

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


def view_title(key: str, s: Any, url: str = "", n_axis: str = "linear") -> tuple[TitleBlock, str]:
    """``(title block, file stem)`` of the live view ``key`` for the session snapshot ``s``."""
    snap = title_snapshot(s, url, n_axis)
    view = VIEW_OF_KEY[key]
    return compact_title(snap, view), file_stem(snap, view)


def _url_defaults() -> dict[str, object]:
    """Default value of every URL query key of the page (state and layout)."""
    from ..state import URL_KEYS, DashboardState
    from .layout import PAGE_URL_KEYS, PageState

    out: dict[str, object] = {}
    for group, keys in URL_KEYS.items():
        cls = DashboardState.param[group].class_
        for name, key in keys.items():
            out[key] = cls.param[name].default
    for name, key in PAGE_URL_KEYS.items():
        out[key] = PageState.param[name].default
    return out


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
