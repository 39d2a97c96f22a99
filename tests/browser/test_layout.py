"""The page's layout in the meeting room (issue 29), measured in chromium at 1280x720,
1366x768 and 1920x1080: element rectangles after what a user does (cards opened by a click
on their header, tabs by a click, the presentation view by its button), type sizes, typed
numbers, the band's progress bar. Screenshots of every state go to
``tests/browser/artifacts/`` (git-ignored) for a person to look at.
"""

from __future__ import annotations

from urllib.parse import parse_qs, urlparse

import pytest

from .conftest import open_dashboard, set_model_value, source, wait_band_idle, wait_loaded
from .layout_util import (
    SIZES,
    layout_problems,
    plots,
    scroll_to,
    shot,
    small_text,
    wait_stable,
)

pytestmark = pytest.mark.browser

#: The Analysis card's tabs: label -> a source its view fills.
TABS = {
    "Compare": "compare.curve0",
    "Phase and peaks": "phase.a",
    "Across speed": "speedmap.image",
    "Contributions": "contributions.lines",
}


def _page(browser, size):
    ctx = browser.new_context(viewport={"width": size[0], "height": size[1]})
    page = ctx.new_page()
    page.errors = []
    page.on("console", lambda m: m.type == "error" and page.errors.append(m.text))
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    return ctx, page


def _tag(size) -> str:
    return f"{size[0]}x{size[1]}"


def _check(page, size, state: str, problems: list) -> None:
    wait_stable(page)
    problems += [f"{state}: {p}" for p in layout_problems(page, size[0])]


def _collapsed_cards(page) -> list[str]:
    """The first own css class of every collapsed card of the page."""
    return page.evaluate(
        """() => [...Bokeh.documents[0].all_models].filter(
             m => m.type.endsWith("Card") && m.collapsed && m.css_classes.length > 0)
           .map(m => m.css_classes.filter(c => c !== 'card' && c !== 'fbs-card')[0])"""
    )


@pytest.mark.parametrize("size", SIZES, ids=_tag)
def test_every_card_opened_by_a_click_keeps_to_itself(browser, dashboard, size):
    """No two cards overlap, every plot lies inside its card and the window's width,
    after the user opens every card and every tab by clicking them."""
    ctx, page = _page(browser, size)
    start = len(dashboard.log)
    open_dashboard(page, dashboard.url + "?rounds=1000")
    problems: list[str] = []
    _check(page, size, "page loaded", problems)
    shot(page, f"layout_{_tag(size)}_loaded")
    page.locator(".ctl-case-show_uncoupled input").click()
    wait_loaded(page, ["uncoupled.tire_reference", "uncoupled.chassis"])
    closed = _collapsed_cards(page)
    assert "analysis-card" in closed and "landmarks-card" in closed, closed
    for cls in closed:
        header = page.locator(f".{cls} .card-header").first
        scroll_to(page, page.locator(f".{cls}"))
        header.click()
        if cls == "analysis-card":
            # something shows at once: the views take seconds to build the first time
            page.locator(".analysis-building, .analysis-tabs").first.wait_for(
                state="visible", timeout=5_000
            )
            page.locator(".analysis-tabs .bk-tab").first.wait_for(timeout=120_000)
    _check(page, size, "every card open", problems)
    for tab, name in TABS.items():
        page.locator(".analysis-tabs .bk-tab", has_text=tab).first.click()
        wait_loaded(page, [name], timeout=120_000)
        scroll_to(page, page.locator(".analysis-card"))
        _check(page, size, f"tab {tab}", problems)
        shot(page, f"layout_{_tag(size)}_tab_{tab.split()[0].lower()}")
        if tab == "Compare":  # the pin's name field takes a click and a name
            box = page.locator(".ctl-analysis-pin_name input").first
            box.click(timeout=20_000)
            box.fill("baseline")
            box.press("Enter")
            page.wait_for_function(
                """() => [...Bokeh.documents[0].all_models].some(m => m.css_classes
                     && m.css_classes.includes('ctl-analysis-pin_name')
                     && m.value === 'baseline')"""
            )
            page.locator(".ctl-analysis-pin button").first.click()
            page.wait_for_function(
                """() => [...Bokeh.documents[0].all_models].some(m => m.type === 'Legend'
                     && m.items.some(i => i.label && i.label.value === 'baseline'))""",
                timeout=60_000,
            )
            band_labels = """() => [...Bokeh.documents[0].all_models].filter(m => m.type
                     === 'Figure' && m.name === 'compare.band').flatMap(f => [...f.below,
                     ...f.center].filter(r => r.type === 'Legend').flatMap(l => l.items)
                     .filter(i => i.visible).map(i => i.label.value))"""
            # the band plot's legend follows its own draw (after the curves' plot)
            page.wait_for_function(f"() => ({band_labels})().includes('baseline')", timeout=60_000)
            labels = page.evaluate(band_labels)
            assert "baseline" in labels and not any(x.startswith("pin ") for x in labels), labels
            _check(page, size, "tab Compare, one pin", problems)
            shot(page, f"layout_{_tag(size)}_tab_compare_pinned")
    assert not problems, "\n".join(problems)
    assert not page.errors, page.errors
    overridden = [ln for ln in dashboard.log[start:] if "overridden" in ln]
    assert not overridden, overridden[:3]
    ctx.close()


def _first_row_problems(page, size) -> list[str]:
    out = []
    first = {p["name"]: p for p in plots(page)}
    for name in ("mobility.figure", "truncation.figure"):
        p = first.get(name)
        if p is None:
            out.append(f"{name} not shown")
            continue
        bottoms = [p["canvas"]["bottom"], *[lg["bottom"] for lg in p["legends"]]]
        if max(bottoms) > size[1] + 0.5:
            out.append(f"{name} (with its legend) ends at {max(bottoms):.0f} of {size[1]}")
        if p["frame"]["height"] < 200:
            out.append(f"{name}: a plot of {p['frame']['height']:.0f} px")
    return out


def _presentation_checks(page, size, state: str) -> list[str]:
    wait_stable(page)
    out = [f"{state}: {p}" for p in layout_problems(page, size[0])]
    out += [f"{state}: {p}" for p in _first_row_problems(page, size)]
    out += [f"{state}: {t['px']:.1f} px: {t['text']!r}" for t in small_text(page, 16)]
    return out


@pytest.mark.parametrize("size", SIZES, ids=_tag)
def test_presentation_view_by_its_button(browser, dashboard, size):
    """The Presentation button: the sidebar collapses (and the link says so), every text is
    at least 16 px, the first row's plots with their legends are on the first screen, and
    a link of the view shows the same."""
    ctx, page = _page(browser, size)
    open_dashboard(page, dashboard.url + "?rounds=1000")
    # (the URL changes with it: the click does not wait for what Playwright counts as a
    # navigation)
    page.locator(".ctl-page-view button", has_text="Presentation").click(no_wait_after=True)
    _wait_query(page, "view=present")  # (a loaded machine: the browser answers slowly too)
    page.wait_for_function(
        "() => document.getElementById('sidebar').getBoundingClientRect().width < 1",
        timeout=120_000,
    )
    page.wait_for_function(  # the error map restyled too (the server's answer)
        """() => [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure'
             && m.name === 'truncation.figure').every(f => f.left.every(
             a => a.major_label_text_font_size === '16px'))""",
        timeout=120_000,
    )
    _wait_query(page, "view=present")
    problems = _presentation_checks(page, size, "Presentation button")
    shot(page, f"present_{_tag(size)}_button")
    # the Analysis card in the presentation view, opened by a click, every tab
    scroll_to(page, page.locator(".analysis-card"))
    page.locator(".analysis-card .card-header").first.click()
    page.locator(".analysis-tabs .bk-tab").first.wait_for(timeout=120_000)  # built
    for tab, name in TABS.items():
        page.locator(".analysis-tabs .bk-tab", has_text=tab).first.click()
        wait_loaded(page, [name], timeout=120_000)
        scroll_to(page, page.locator(".analysis-card"))
        wait_stable(page)
        problems += [f"tab {tab}: {p}" for p in layout_problems(page, size[0])]
        problems += [f"tab {tab}: {t['px']:.1f} px: {t['text']!r}" for t in small_text(page, 16)]
        shot(page, f"present_{_tag(size)}_tab_{tab.split()[0].lower()}")
    # a link of the presentation view, opened anew
    other = ctx.new_page()
    open_dashboard(other, page.url)
    other.wait_for_function(
        "() => document.getElementById('sidebar').getBoundingClientRect().width < 1",
        timeout=120_000,
    )
    problems += _presentation_checks(other, size, "link")
    shot(other, f"present_{_tag(size)}_link")
    assert not problems, "\n".join(problems)
    ctx.close()


def test_the_collapsed_sidebar_is_in_the_link(browser, dashboard):
    size = (1366, 768)
    ctx, page = _page(browser, size)
    open_dashboard(page, dashboard.url + "?rounds=1000")
    page.locator(".ctl-page-sidebar button").click(no_wait_after=True)
    _wait_query(page, "sidebar=closed")
    page.wait_for_function(
        "() => document.getElementById('sidebar').getBoundingClientRect().width < 1"
    )
    wait_stable(page)
    assert not layout_problems(page, size[0])
    other = ctx.new_page()
    open_dashboard(other, page.url)
    assert other.evaluate("document.getElementById('sidebar').getBoundingClientRect().width") < 1
    other.locator(".ctl-page-sidebar button").click(no_wait_after=True)  # and back
    other.wait_for_function(
        "() => document.getElementById('sidebar').getBoundingClientRect().width > 300"
    )
    _wait_query(other, "sidebar=closed", present=False)
    ctx.close()


def _wait_query(page, part: str, present: bool = True) -> None:
    """Wait until the page's URL query holds ``part`` (or no longer does)."""
    page.wait_for_function(
        "([part, present]) => location.search.includes(part) === present",
        arg=[part, present],
        timeout=120_000,
    )


def _query(page) -> dict[str, str]:
    return {k: v[-1] for k, v in parse_qs(urlparse(page.url).query).items()}


#: Typed fields: css class -> (its label, URL key, value in force on the page opened, what
#: 1e5 / 1.5 / 5,5 / abc mean within the field's bounds (None: refused)).
TYPED = {
    "ctl-noise-rounds": ("Rounds R", "rounds", 1000, (100_000, None, None, None)),
    "ctl-noise-seed": ("Seed", "seed", 0, (100_000, None, None, None)),
    "ctl-noise-single_round": ("Single round #", "round", 0, (None, None, None, None)),
    "ctl-noise-noise": ("Noise level p", "noise", 10, (None, 1.5, 5.5, None)),
    "ctl-truncation-threshold": ("Error threshold", "thr", 20, (None, 1.5, 5.5, None)),
    "ctl-truncation-f_max": ("Upper frequency", "fmax", 160, (None, 1.5, 5.5, None)),
    "ctl-analysis-cursor1": ("Cursor 1", "c1", 0, (None, 1.5, 5.5, None)),
}


def test_every_typed_field_reads_or_refuses_with_a_message(browser, dashboard):
    """``1e5``, ``1.5``, ``5,5`` and ``abc`` in every typed field: the value a person means
    (in the link), or a message naming the field, with the value in force kept."""
    size = (1366, 768)
    ctx, page = _page(browser, size)
    open_dashboard(page, dashboard.url + "?rounds=1000&atab=phase")
    wait_loaded(page, ["phase.a"], timeout=120_000)
    problems = []
    for cls, (label, key, start, wants) in TYPED.items():
        in_force = start
        for text, want in zip(("1e5", "1.5", "5,5", "abc"), wants, strict=True):
            box = page.locator(f".{cls} input").first
            box.fill(text)
            box.press("Enter")
            if want is None:
                # a message naming the field and what was typed, and the value in force
                msg = (
                    page.locator(f".ctl-message-{cls[4:]}", has_text=label)
                    .filter(has_text=text)
                    .filter(has_text="still")
                )
                try:
                    msg.first.wait_for(state="visible", timeout=60_000)
                except Exception:
                    problems.append(f"{cls} {text!r}: no message; link {_query(page).get(key)}")
                    continue
                got = float(_query(page).get(key, in_force))
                if got != in_force:
                    problems.append(f"{cls} {text!r}: refused, yet {key}={got}")
            else:
                try:
                    page.wait_for_function(
                        """([key, want]) => {
                             const v = new URLSearchParams(location.search).get(key);
                             return v !== null && parseFloat(v) === want; }""",
                        arg=[key, want],
                        timeout=60_000,
                    )
                    in_force = want
                except Exception:
                    problems.append(f"{cls} {text!r}: {key}={_query(page).get(key)}, not {want}")
                # the slider (if any) shows the value in force
                if page.locator(f".{cls}-slider").count():
                    try:
                        page.wait_for_function(
                            """([cls, want]) => [...Bokeh.documents[0].all_models].filter(
                                 m => m.css_classes && m.css_classes.includes(cls))
                                 .every(m => m.value === want)""",
                            arg=[f"{cls}-slider", in_force],
                            timeout=60_000,
                        )
                    except Exception:
                        problems.append(f"{cls} {text!r}: slider not at {in_force}")
            # once the page is quiet the field shows the value in force (as a person sees
            # it before typing the next value)
            try:
                page.wait_for_function(
                    """([cls, want]) => [...Bokeh.documents[0].all_models].filter(
                         m => m.css_classes && m.css_classes.includes(cls) && 'value' in m)
                         .every(m => /^-?[0-9]+([.][0-9]*)?$/.test(String(m.value).trim())
                                     && parseFloat(m.value) === want)""",
                    arg=[cls, in_force],
                    timeout=60_000,
                )
            except Exception:
                problems.append(f"{cls} {text!r}: the field does not show {in_force}")
        shot(page, f"typed_{cls[4:]}")
    assert not problems, "\n".join(problems)
    ctx.close()


def test_a_refused_threshold_keeps_the_slider_on_the_value_in_force(browser, dashboard):
    ctx, page = _page(browser, (1280, 720))
    open_dashboard(page, dashboard.url + "?rounds=1000&thr=12")
    box = page.locator(".ctl-truncation-threshold input").first
    box.fill("0")
    box.press("Enter")
    page.locator(".ctl-message-truncation-threshold").first.wait_for(state="visible")
    # once the page is quiet (app.views.bind: the settle), the field and the slider show
    # the value in force again
    values = """() => [...Bokeh.documents[0].all_models].filter(m => m.css_classes && 'value' in m
             && m.css_classes.some(c => c.startsWith('ctl-truncation-threshold')))
             .map(m => m.value)"""
    try:
        page.wait_for_function(
            f"() => {{ const v = ({values})(); return v.length > 1 && v.every(x => +x === 12); }}",
            timeout=60_000,
        )
    except Exception:
        shown = page.evaluate(values)
        raise AssertionError(f"the threshold's widgets show {shown}, not 12") from None
    shot(page, "typed_threshold_refused")
    ctx.close()


def test_the_progress_bar_shows_on_the_default_page(browser, dashboard):
    """A page opened with its band ready (the default settings, computed by the page
    before) shows the bar of its next band."""
    ctx, page = _page(browser, (1280, 720))
    open_dashboard(page, dashboard.url)
    wait_band_idle(page)
    again = ctx.new_page()  # the band of these settings is cached now
    open_dashboard(again, dashboard.url)
    wait_band_idle(again)
    scroll_to(again, again.locator(".scatter-progress"))
    bar = again.locator(".scatter-progress progress").first  # the bar inside the widget
    assert bar.evaluate("e => getComputedStyle(e).visibility") == "hidden"  # idle
    set_model_value(again, "ctl-case-harmonic", 7, "Slider")  # 633 lines: seconds
    again.locator(".scatter-status", has_text="Computing").first.wait_for(timeout=60_000)
    bar.wait_for(state="visible", timeout=60_000)  # drawn: not visibility hidden
    shot(again, "band_progress_default_page")
    wait_band_idle(again)
    bar.wait_for(state="hidden")
    again.locator(".scatter-status", has_text="5-95 % band edges within").first.wait_for()
    assert source(again, "scatter.minmax") is not None
    ctx.close()
