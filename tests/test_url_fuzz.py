"""Every URL key a page reads holds hostile values: the page opens (issue 28, findings 2, 5).

The keys are recorded from a page build (``url_fuzz.page_keys``) and checked against the
lists in ``app/``; the values are ``url_fuzz.FUZZ`` (markup, ``javascript:``, quotes,
NaN, infinities, huge and negative numbers, control and other scripts' characters, a
crafted pin ...), plus keys given twice and 200 KB values. Each page builds with the
reference models plotted, every setting is its default or what the value means for it (read
by hand, ``url_fuzz.parsed``), the settings kept as text answer for themselves (a malformed
pin named, the link notice as text), and no value reaches the page as markup.

This file imports only names that existed before the fixes (``create_app``, ``close_page``,
``ANALYSIS_TABS``), so it runs unchanged on the code before them (docs/deployment.md,
the audit of issue 28). Served and in chromium: tests/browser/test_server_attacks.py.
"""

from __future__ import annotations

import urllib.parse

import pytest
from url_fuzz import (
    ELEMENTS,
    FREE_TEXT,
    FUZZ,
    model_html,
    page_keys,
    parsed,
    served_location,
)

from app.state.analysis import ANALYSIS_TABS

#: The published result of the store (app.store.TABLE) each Analysis tab shows first.
SHOWN_FIRST = {
    "contributions": "contributions",
    "phase": "phase",
    "speed": "speed_map",
    "compare": "compare",
    "modes": "participation",
    "selection": "selected_modes",
}

# ---- every key of the link hostile, the Analysis card on each tab ---------------------------


def test_every_key_the_page_reads_is_one_setting(monkeypatch):
    """The fuzz below sends what a page build itself syncs with the URL (recorded, not
    listed): every state group of the page is among it, no key names two settings, and
    they are the keys ``app.state.URL_KEYS`` and ``app.page.layout.PAGE_URL_KEYS`` list."""
    from app.page.layout import PageState
    from app.state import DashboardState
    from app.state.analysis import AnalysisState

    rec = page_keys(monkeypatch)
    groups = {type(obj) for obj, _ in rec.synced}
    state = DashboardState()
    wanted = {type(getattr(state, g)) for g in ("case", "noise", "truncation", "analysis")}
    assert wanted | {PageState, AnalysisState} <= groups
    assert len(rec.keys) == len(set(rec.keys)) >= 25, rec.keys
    # the same keys as the lists in app/ declare (a key synced elsewhere would be recorded)
    from app.page.layout import PAGE_URL_KEYS
    from app.state import URL_KEYS

    declared = [k for group in URL_KEYS.values() for k in group.values()]
    assert sorted(rec.keys) == sorted(declared + list(PAGE_URL_KEYS.values()))


def _check_settings(rec, value: str, skip: tuple[str, ...] = ()) -> None:
    """Every setting the page read from a link whose keys all held ``value``: its default,
    or what ``value`` means for it read by hand (``url_fuzz.parsed``)."""
    for obj, names in rec.synced:
        for p in names:
            if p in skip:
                continue
            got, default = getattr(obj, p), obj.param[p].default
            if p in FREE_TEXT:
                assert got in (default, value), (p, value[:40], got)
            else:
                want = parsed(value, obj.param[p])
                assert got == default or (want is not None and got == want), (
                    p,
                    value[:40],
                    got,
                )


def _check_page(page, rec, value: str) -> str:
    """The page built: the reference models plotted, the settings kept as text answered
    for (a malformed pin named, the link notice shown as text), no markup of ``value``;
    returns the page's HTML."""
    from bokeh.document import Document

    from app.page.layout import PageState

    doc = Document()
    for obj in page.main:
        doc.add_root(obj.get_root(doc))
    names = {m.name: m for m in doc.models if type(m).__name__ == "ColumnDataSource"}
    assert len(names["mobility.reference"].data["freq"]) > 0, value[:40]
    text = model_html(doc.models)
    found = ELEMENTS.search(text)
    assert found is None, (value[:40], found)
    if page.state.analysis.pins:
        assert "malformed pin" in page.results.message, value[:40]
    data = next(o for o, _ in rec.synced if isinstance(o, PageState)).data
    if data.strip():
        assert "This link was made with uploaded data" in text, value[:40]
    return text


@pytest.mark.slow
def test_hostile_values_in_every_url_key_leave_the_page_whole(monkeypatch):
    """Every URL key the page reads holds the same hostile value (``url_fuzz.FUZZ``: markup,
    ``javascript:``, quotes, NaN, infinities, huge and negative numbers, empty, control and
    other scripts' characters, a crafted pin ...), the Analysis card on each of its tabs in
    turn ('': collapsed): the page builds with the reference models plotted and the tab's
    result computed, every setting is its default or what the value means for it, the
    settings kept as text are answered for, and no value reaches the page as markup."""
    from app.main import close_page, create_app
    from app.state.analysis import AnalysisState

    keys = page_keys(monkeypatch)
    tab_key = keys.key_of(AnalysisState, "tab")
    for i, value in enumerate(FUZZ):
        tab = ANALYSIS_TABS[i % len(ANALYSIS_TABS)]
        query = {k: value for k in keys.keys}
        if tab:
            query[tab_key] = tab
        with monkeypatch.context() as m:
            rec = served_location(m, urllib.parse.urlencode(query))
            page = create_app()
        try:
            assert page.state.analysis.tab == tab, value[:40]
            _check_settings(rec, value, skip=("tab",))
            if tab:
                result = getattr(page.results, SHOWN_FIRST[tab])
                assert result is not None or tab == "compare", (tab, value[:40])
            _check_page(page, rec, value)
        finally:
            close_page(page)


@pytest.mark.slow
def test_repeated_and_huge_url_keys(monkeypatch):
    """A key given twice takes its last value (Panel's reading): a valid value after a
    hostile one is kept, a hostile one after a valid one gives the default, never the
    hostile value; a 200 KB value in a key and numbers of 4,300 digits (in process: Tornado
    refuses a request head above 64 KB before the app sees it) give the default or a
    message, and the notice repeats at most a few hundred characters of the value."""
    from app.main import close_page, create_app
    from app.page.layout import PageState

    keys = page_keys(monkeypatch).keys
    hostile = "<script>fbsXss()</script>"
    valid = {"h": "3", "N": "100", "dof": "y", "noise": "5.0", "view": "present"}
    assert set(valid) <= set(keys)
    for order in ((hostile, "valid"), ("valid", hostile)):
        pairs = [(k, valid.get(k, hostile) if v == "valid" else v) for v in order for k in keys]
        with monkeypatch.context() as m:
            rec = served_location(m, urllib.parse.urlencode(pairs))
            page = create_app()
        try:
            s = page.state
            got = (s.case.harmonic, s.case.n_modes, s.case.dof, s.noise.noise)
            view = next(o for o, _ in rec.synced if isinstance(o, PageState)).view
            if order[-1] == "valid":
                assert (*got, view) == (3, 100, "y", 5.0, "present")
                _check_settings(rec, hostile, skip=("harmonic", "n_modes", "dof", "noise", "view"))
            else:
                assert (*got, view) == (1, 50, "z", 10.0, "normal")
                _check_settings(rec, hostile)
            _check_page(page, rec, hostile)
        finally:
            close_page(page)
    huge = {
        "pins": "x~h1|" * 40_000,
        "data": "tire:" + "<b>" * 70_000,
        "cmp": "y" * 200_000,
        # above 4,300 digits, Python's limit for int(): Panel's reading of the link raised
        # ValueError while the page was built (app.main.drop_unreadable_numbers drops them)
        "h": "9" * 5_000,
        "noise": "1" * 4_300,
        "N": "7" * 20_000,
        "seed": "-" + "9" * 5_000,
    }
    with monkeypatch.context() as m:
        rec = served_location(m, urllib.parse.urlencode(huge))
        page = create_app()
    try:
        s = page.state
        assert (s.case.harmonic, s.case.n_modes, s.noise.noise) == (1, 50, 10.0)
        assert "malformed pin" in page.results.message
        text = _check_page(page, rec, huge["data"])
        notice = text[text.index("This link was made") :]
        assert len(notice[: notice.index("</div>")]) < 1000
    finally:
        close_page(page)
