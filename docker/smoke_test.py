"""Browser smoke test of a served dashboard (run by scripts/docker_proof.sh).

Opens the page in chromium with playwright, logs in first when credentials are given, and
checks that

1. the page renders: a Bokeh document arrives, no Python traceback is shown, and at least
   one plot has data (a non-empty ``ColumnDataSource``);
2. a control change updates a plot: once the plot data are stable, the first slider of the
   page is moved one step with the keyboard (as a user would), the slider's model value
   changes and so do the plot data in ``Bokeh.documents[0]``.

With ``--expect-login`` it first checks that the page without credentials shows the login
form and no Bokeh document. Exit status 0 on success, 1 on failure (with the reason).

Usage: python docker/smoke_test.py URL [--user U --password=P] [--expect-login]
(``--password=P``: a password may begin with "-")
"""

from __future__ import annotations

import argparse
import os
import sys
import time

#: Digest of the plot data shown (data sources reachable from the document roots; replaced
#: ones may linger in all_models): per source, the number of values and a weighted sum of
#: the finite numbers and their squares, sorted (model ids differ between sessions).
DIGEST_JS = """() => {
  const doc = Bokeh.documents[0], shown = new Set();
  for (const root of doc.roots()) {
    shown.add(root);
    for (const m of root.references()) shown.add(m);
  }
  const out = [];
  for (const m of shown) {
    if (m.type !== 'ColumnDataSource') continue;
    const cols = m.data instanceof Map ? [...m.data.entries()] : Object.entries(m.data);
    let n = 0, s = 0;
    for (const [name, col] of cols) {
      if (col == null || col.length === undefined || typeof col === 'string') continue;
      n += col.length;
      for (let i = 0; i < col.length; i++) {
        const v = col[i];
        if (typeof v === 'number' && Number.isFinite(v)) s += v * Math.sqrt(i + 2) + v * v;
      }
    }
    out.push(n + ':' + s.toPrecision(10));
  }
  return out.sort().join('|');
}"""

HAS_PLOT_DATA_JS = """() => window.Bokeh && Bokeh.documents.length > 0 &&
  [...Bokeh.documents[0].all_models].some(m => m.type === 'ColumnDataSource' &&
    Object.values(m.data instanceof Map ? Object.fromEntries(m.data) : m.data)
      .some(c => c && c.length > 0))"""

SLIDER_VALUES_JS = """() => [...Bokeh.documents[0].all_models]
  .filter(m => m.type === 'Slider' || m.type === 'IntSlider' || m.type.endsWith('Slider'))
  .map(m => m.value)"""


def chromium_args() -> dict:
    """Launch arguments: the system chromium when present, else playwright's own."""
    for path in ("/usr/bin/chromium", "/usr/bin/chromium-browser"):
        if os.path.exists(path):
            return {
                "executable_path": path,
                "args": ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
            }
    return {}


def login(page, url: str, user: str, password: str, timeout_ms: float) -> None:
    """Fill Panel's login form (the page ``url`` redirects to) and submit it."""
    page.goto(url, timeout=timeout_ms)
    page.fill("input[name=username]", user)
    page.fill("input[name=password]", password)
    with page.expect_navigation(timeout=timeout_ms):
        page.locator("button[type=submit], input[type=submit]").first.click()


def wait_stable(page, timeout_s: float, quiet_s: float = 1.5) -> str:
    """Wait until the plot data digest has not changed for ``quiet_s`` seconds."""
    end = time.monotonic() + timeout_s
    last, since = page.evaluate(DIGEST_JS), time.monotonic()
    while time.monotonic() < end:
        page.wait_for_timeout(250)
        now = page.evaluate(DIGEST_JS)
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            return last
    raise AssertionError(f"plot data still changing after {timeout_s:.0f} s")


def run(
    url: str, user: str | None, password: str | None, expect_login: bool, timeout_s: float
) -> dict[str, float]:
    from playwright.sync_api import sync_playwright

    ms = timeout_s * 1000
    timings: dict[str, float] = {}
    with sync_playwright() as p:
        browser = p.chromium.launch(**chromium_args())
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            errors: list[str] = []
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            if expect_login:
                page.goto(url, timeout=ms)
                if page.locator("input[name=password]").count() != 1:
                    raise AssertionError(f"no login form at {url} without credentials")
                if page.evaluate("() => !!(window.Bokeh && Bokeh.documents.length)"):
                    raise AssertionError("a Bokeh document was served without credentials")
                print("smoke: without credentials -> login form, no Bokeh document")
            t0 = time.monotonic()
            if user is not None:
                login(page, url, user, password or "", ms)
            else:
                page.goto(url, timeout=ms)
            page.wait_for_function(HAS_PLOT_DATA_JS, timeout=ms)
            timings["page render (s)"] = time.monotonic() - t0
            if page.get_by_text("Traceback (most recent call last)").count():
                raise AssertionError("the page shows a Python traceback")
            n_sliders = page.locator(".noUi-handle").count()
            if n_sliders == 0:
                raise AssertionError("no slider on the page to change")
            before = wait_stable(page, timeout_s)
            values = page.evaluate(SLIDER_VALUES_JS)
            # the harmonic's slider: it changes every view (a slider of the vehicle scope,
            # e.g. the tracks' coherence, changes nothing in the corner scope a page opens in)
            harmonic = page.locator(".ctl-case-harmonic .noUi-handle")
            handle = harmonic.first if harmonic.count() else page.locator(".noUi-handle").first
            handle.focus()
            t1 = time.monotonic()
            handle.press("ArrowRight")
            page.wait_for_function(f"() => ({DIGEST_JS})() !== {before!r}", timeout=ms, polling=50)
            timings["control change -> plot data updated (ms)"] = (time.monotonic() - t1) * 1e3
            after_values = page.evaluate(SLIDER_VALUES_JS)
            if after_values == values:
                raise AssertionError(f"slider values unchanged: {values}")
            if errors:
                raise AssertionError(f"JavaScript errors in the page: {errors[:3]}")
            print(f"smoke: slider values {values} -> {after_values}; plot data changed")
        finally:
            browser.close()
    return timings


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("url")
    ap.add_argument("--user")
    ap.add_argument("--password")
    ap.add_argument(
        "--expect-login",
        action="store_true",
        help="check first that the page without credentials is the login form",
    )
    ap.add_argument("--timeout", type=float, default=90.0, help="seconds per wait (90)")
    args = ap.parse_args(argv)
    try:
        timings = run(args.url, args.user, args.password, args.expect_login, args.timeout)
    except Exception as exc:  # report any failure as the test's verdict
        print(f"smoke: FAILED: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    for name, value in timings.items():
        print(f"smoke: {name}: {value:.1f}")
    print("smoke: OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
