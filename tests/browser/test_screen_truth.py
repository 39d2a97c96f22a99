"""What the screen says is what was computed: a person's quick interactions, then every
shown value against the session's state and every plot against the core's numbers.

The page's state is read from its URL (written from the state, ``app.page.titles.PageLink``)
and decoded in the test process into a ``DashboardState``; then

* every control's widget (its Bokeh model, and the N slider's label as drawn) shows it;
* every title block's link opens that state (a view id ``?v=`` is opened in a second page
  of the same browser), and its "N = ..." and "Harmonic k" name it;
* the coupled response holds ``fbs_core.bushing_response`` of that state, and the error
  map ``app.compute.error_map_data`` of it.

The random walk of 200 quick interactions that ends in these checks is
``test_walk_screen_truth``.
"""

from __future__ import annotations

import re
import time
import urllib.parse
from pathlib import Path

import numpy as np
import pytest
from panel.io.location import Location

import fbs_core
from app import compute
from app.main import sync_url
from app.page.layout import PageState
from app.page.titles import VIEW_ID_KEY, state_query
from app.state import DashboardState

from .conftest import open_dashboard, source, wait_band_idle

pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).parent / "artifacts"

#: What the page shows of its controls and title blocks (the Bokeh document, and the N
#: slider's label as drawn, through the components' shadow roots).
JS_SHOWN = """
() => {
  const ms = [...Bokeh.documents[0].all_models];
  const widgets = {};
  for (const m of ms) {
    if (!m.css_classes) continue;
    for (const c of m.css_classes) {
      if (!c.startsWith('ctl-')) continue;
      if (!('value' in m || 'active' in m)) continue;
      widgets[c] = {
        value: 'value' in m ? m.value : null,
        active: 'active' in m ? m.active : null,
        labels: 'labels' in m ? m.labels : null,
      };
    }
  }
  function deep(root, out) {
    for (const el of root.querySelectorAll('*')) {
      if (el.shadowRoot) deep(el.shadowRoot, out);
      if (el.classList && el.classList.contains('ctl-case-n_modes')) out.push(el);
    }
    return out;
  }
  function text(el) {
    // the slider's own title line when it has one (its handle's tooltip repeats the value)
    let t = '', title = '';
    const walk = (n) => {
      if (n.nodeName === 'STYLE') return;
      if (n.classList && n.classList.contains('bk-slider-title')) title += n.textContent + ' ';
      if (n.nodeType === 3) t += n.textContent;
      if (n.shadowRoot) walk(n.shadowRoot);
      for (const c of n.childNodes || []) walk(c);
    };
    walk(el);
    return title || t;
  }
  const nText = deep(document, []).map(text).join(' ');
  // what is on the page: the title blocks and legends of the plots laid out now (a plot in
  // an analysis tab not shown is not on the screen; it is drawn again when its tab opens)
  function displayed(fig) {
    const v = Bokeh.index.find_one(fig);
    if (v == null || !fig.visible) return false;
    const r = v.el.getBoundingClientRect();
    if (r.width < 1 || r.height < 1) return false;
    for (let e = v.el; e; e = e.parentElement || (e.getRootNode && e.getRootNode().host)) {
      const st = getComputedStyle(e);
      if (st.display === 'none' || st.visibility === 'hidden') return false;
    }
    return true;
  }
  const figs = ms.filter(m => m.type === 'Figure' && displayed(m));
  const parts = figs.flatMap(f => [f.title, ...f.above, ...f.below, ...f.left, ...f.right,
                                   ...f.center]).filter(m => m != null);
  const titles = parts.filter(m => m.type === 'Title' && m.visible && m.text).map(m => m.text);
  const legends = parts.filter(m => m.type === 'Legend').flatMap(l => l.items).map(m => {
      const l = m.label; return l && typeof l === 'object' && 'value' in l ? l.value : String(l);
  });
  const progress = ms.filter(m => m.css_classes && m.css_classes.includes('scatter-progress'))
      .some(m => m.active === true);
  return {widgets, nText, titles, legends, search: window.location.search, progress};
}
"""


def shown(page) -> dict:
    return page.evaluate(JS_SHOWN)


def wait_quiet(page, still_s: float = 4.0, timeout_s: float = 240.0) -> dict:
    """Wait until what the page shows has not changed for ``still_s`` seconds (and no band
    is computing); returns it."""
    end = time.monotonic() + timeout_s
    last, since = None, time.monotonic()
    while time.monotonic() < end:
        now = shown(page)
        now.pop("progress_seen", None)
        key = repr(now)
        if key != last:
            last, since = key, time.monotonic()
        elif time.monotonic() - since >= still_s and not now["progress"]:
            return now
        page.wait_for_timeout(300)
    raise AssertionError(f"the page did not become quiet in {timeout_s:g} s")


def decoded(search: str) -> tuple[DashboardState, PageState]:
    """The state and layout a link's query opens (the page's own reader)."""
    s, page = DashboardState(), PageState()
    sync_url(s, Location(search=search), page=page)
    return s, page


def canonical(search: str) -> dict[str, str]:
    """The settings of a query (defaults dropped, one spelling per value)."""
    return state_query(decoded(search)[0])


def _label_of(labels: list[str], active) -> str:
    return labels[active] if isinstance(active, int) and 0 <= active < len(labels) else ""


def widget_problems(seen: dict, s: DashboardState, layout: PageState) -> list[str]:
    """Every control whose widget does not show the value of ``s``."""
    w = seen["widgets"]
    out = []

    def check(key: str, got, want) -> None:
        if got != want:
            out.append(f"{key}: shows {got!r}, state {want!r}")

    c, n, t, p = s.case, s.noise, s.truncation, s.plot
    check("harmonic", w["ctl-case-harmonic"]["value"], c.harmonic)
    check("N slider", w["ctl-case-n_modes"]["value"], c.n_modes)
    label = re.findall(r"N:\s*(\d+)", seen["nText"])
    check("N label", [int(x) for x in label][-1:] or None, [c.n_modes])
    radios = {
        "ctl-case-dof": c.dof,
        "ctl-case-coupling": c.coupling,
        "ctl-truncation-map_mode": t.map_mode,
        "ctl-plot-level_scale": p.level_scale,
        "ctl-noise-target": n.target,
        "ctl-case-scope": c.scope.capitalize(),
        "ctl-page-view": {"normal": "Normal view", "present": "Presentation"}[layout.view],
    }
    for cls, want in radios.items():
        m = w[cls]
        check(cls, _label_of(m["labels"], m["active"]), want)
    for cls, want in {
        "ctl-case-residual": c.residual,
        "ctl-case-show_uncoupled": c.show_uncoupled,
        "ctl-plot-snap": p.snap,
        "ctl-noise-frequency_dependent": n.frequency_dependent,
        "ctl-noise-first_order": n.first_order,
    }.items():
        check(cls, bool(w[cls]["active"]), want)
    m = w["ctl-plot-overlay"]
    check("overlay", sorted(m["labels"][i] for i in m["active"]), sorted(p.overlay))
    for cls, want in {
        "ctl-truncation-threshold": t.threshold,
        "ctl-truncation-f_max": t.f_max,
        "ctl-noise-noise": n.noise,
        "ctl-noise-rounds": n.rounds,
        "ctl-noise-seed": n.seed,
    }.items():
        check(cls, float(w[cls]["value"]), float(want))
        if f"{cls}-slider|Slider" in w:
            check(cls + " slider", float(w[f"{cls}-slider"]["value"]), float(want))
    check("percentile", str(w["ctl-noise-percentile"]["value"]), str(n.percentile))
    return out


def title_problems(seen: dict, s: DashboardState, opener) -> list[str]:
    """Every title block (and legend) that names another state than ``s``."""
    out = []
    want = state_query(s)
    links = sorted({ln for t in seen["titles"] for ln in t.splitlines() if ln.startswith("http")})
    if not links:
        out.append("no title block carries a link")
    for link in links:
        query = urllib.parse.urlsplit(link).query
        if f"{VIEW_ID_KEY}=" in query:
            query = opener(link)
        got = canonical("?" + query.lstrip("?"))
        if got != want:
            out.append(f"title link {link} opens {got}, the page's state is {want}")
    for t in seen["titles"]:
        for n in re.findall(r"\bN = (\d+) of", t):
            if int(n) != s.case.n_modes:
                out.append(f"a title says N = {n}, the state {s.case.n_modes}: {t[:80]!r}")
        for h in re.findall(r"\bHarmonic (\d)\b", t):
            if int(h) != s.case.harmonic:
                out.append(f"a title says harmonic {h}, the state {s.case.harmonic}")
    for label in seen["legends"]:
        for n in re.findall(r"\bN = (\d+)\b", label or ""):
            if int(n) != s.case.n_modes:
                out.append(f"a legend says N = {n}, the state {s.case.n_modes}")
    return out


def data_problems(page, s: DashboardState) -> list[str]:
    """The coupled response and the error map against the core's numbers for ``s``."""
    c = s.case
    out = []
    want = fbs_core.bushing_response(
        c.harmonic, n_modes=c.n_modes, coupling=c.coupling, residual=c.residual
    )
    h = want.sel(outputs=f"bushing:{c.dof}").data[:, 0, 0]
    level = 20 * np.log10(np.abs(h)) if s.plot.level_scale == "dB" else np.abs(h)
    mob = source(page, "mobility.truncated")
    if mob is None or len(mob["freq"]) != len(want.freq):
        out.append("the coupled response is not on the state's frequency grid")
    elif not np.allclose(mob["level"], level, rtol=1e-9, atol=0):
        out.append("the coupled response is not bushing_response of the state")
    dof = c.dof if s.truncation.map_mode == "selected DOF" else None
    err = compute.error_map_data(c.harmonic, c.coupling, dof, residual=c.residual)["error_pct"]
    img = source(page, "truncation.map")
    if img is None or not np.allclose(img["image"], err.ravel(), rtol=1e-12, equal_nan=True):
        out.append("the error map is not that of the state")
    return out


@pytest.fixture
def truth_page(browser, dashboard):
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    page = context.new_page()
    open_dashboard(page, dashboard.url + "?rounds=400")
    wait_band_idle(page)

    def opener(link: str) -> str:
        """The query a view-id link opens in a page of its own."""
        other = context.new_page()
        try:
            other.goto(link, wait_until="commit", timeout=120_000)
            other.wait_for_function(
                "(k) => window.Bokeh && Bokeh.documents.length > 0 && "
                "!new URLSearchParams(window.location.search).has(k)",
                arg=VIEW_ID_KEY,
                timeout=120_000,
            )
            return other.evaluate("() => window.location.search")
        finally:
            other.close()

    page.opener = opener
    yield page
    context.close()


def check_truth(page) -> None:
    seen = wait_quiet(page)
    s, layout = decoded(seen["search"])
    problems = widget_problems(seen, s, layout)
    problems += title_problems(seen, s, page.opener)
    problems += data_problems(page, s)
    assert not problems, "\n".join(problems)


def _handle(page, cls: str):
    return page.locator(f".{cls} .noUi-handle").first


def press(page, cls: str, key: str, times: int, gap_ms: float) -> None:
    _handle(page, cls).focus()
    for _ in range(times):
        page.keyboard.press(key)
        if gap_ms:
            page.wait_for_timeout(gap_ms)


# -- item 1 and item 2, targeted -------------------------------------------------------------
def test_fast_arrow_presses_on_the_n_slider_end_where_the_plots_are(truth_page):
    page = truth_page
    for _ in range(3):
        before = decoded(shown(page)["search"])[0].case.n_modes
        press(page, "ctl-case-n_modes", "ArrowRight", 7, 30)  # a fast key repeat
        pressed = shown(page)["widgets"]["ctl-case-n_modes"]["value"]
        check_truth(page)
        after = decoded(shown(page)["search"])[0].case.n_modes
        # the slider shows the value in force, and the presses moved it (on a loaded machine
        # the server's answer to an early press may land between two later ones: a press
        # can be lost, the screen and the numbers still agree)
        assert after == pressed, (before, pressed, after)
        assert before < after <= min(before + 70, 400), (before, pressed, after)


def test_title_links_follow_a_harmonic_change_a_scope_change_and_a_wheel(truth_page):
    page = truth_page
    press(page, "ctl-case-harmonic", "ArrowRight", 3, 0)  # harmonic 4
    check_truth(page)
    # the car's first results take a while (the URL follows the state once they are made)
    page.locator(".ctl-case-scope").get_by_role("button", name="Vehicle", exact=True).click()
    page.wait_for_function("() => location.search.includes('scope=vehicle')", timeout=600_000)
    check_titles_only(page)
    page.locator(".ctl-case-wheels").get_by_role("button", name="FL", exact=True).click()
    page.wait_for_function("() => location.search.includes('wheels=')", timeout=300_000)
    seen = wait_quiet(page, timeout_s=300)
    s, _ = decoded(seen["search"])
    assert s.case.wheels == ["fr", "rl", "rr"]
    check_titles_only(page)


def check_titles_only(page) -> None:
    seen = wait_quiet(page)
    s, _ = decoded(seen["search"])
    problems = title_problems(seen, s, page.opener)
    assert not problems, "\n".join(problems)
