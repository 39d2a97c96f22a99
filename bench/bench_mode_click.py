"""A click on the participation ranking to the mode's shape drawn in the page (issue 30).

Usage: ``.venv/bin/python bench/bench_mode_click.py [--clicks 8]``. Prints figures;
asserts nothing. Target: the shape drawn < 200 ms after the click.

Serves the dashboard (``panel serve app/main.py``, as the browser tests), opens it in
chromium on the Modes tab, and clicks the bars of the ranking one after the other (each a
mode whose shape is not computed yet: the server solves the tire at that speed). In the
page, the time from the mouse-down (a listener on the document) to the change of the
frames' source (``modeshape.frames``: the server's patch of the new shape has arrived),
and to the first frame of it shown by the page's animation (``modeshape.ring``). Then
the same for clicks on bars already drawn once (the shape cached).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from playwright.sync_api import sync_playwright  # noqa: E402

from tests.browser.conftest import DashboardServer, chromium_launch_args, wait_loaded  # noqa: E402
from tests.browser.test_analysis import _screen  # noqa: E402

HOOK = """() => {
  const find = n => [...Bokeh.documents[0].all_models].filter(m => m.name === n)[0];
  window._fbsClick = null; window._fbsFrames = null; window._fbsShown = null;
  if (!window._fbsHooked) {
    window._fbsHooked = true;
    document.addEventListener('mousedown', () => {
      window._fbsClick = performance.now(); window._fbsFrames = null; window._fbsShown = null;
    }, true);
    find('modeshape.frames').change.connect(() => {
      if (window._fbsClick !== null && window._fbsFrames === null)
        window._fbsFrames = performance.now();
    });
    find('modeshape.ring').change.connect(() => {
      if (window._fbsFrames !== null && window._fbsShown === null)
        window._fbsShown = performance.now();
    });
  }
}"""


def click_bar(page, i: int, value: float) -> tuple[float, float]:
    page.evaluate(HOOK)
    x, y = _screen(page, "participation.figure", float(i), 0.5 * value)
    page.mouse.click(x, y)
    page.wait_for_function("() => window._fbsShown !== null", timeout=60_000)
    t = page.evaluate(
        "() => [window._fbsFrames - window._fbsClick, window._fbsShown - window._fbsClick]"
    )
    return float(t[0]), float(t[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clicks", type=int, default=8)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} (shared 2-core machine)")
    srv = DashboardServer(num_threads=4)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(**chromium_launch_args())
            page = browser.new_page(viewport={"width": 1600, "height": 1400})
            page.goto(srv.url + "?rounds=200&h=1&atab=modes", timeout=300_000, wait_until="commit")
            wait_loaded(page, ["participation.bars", "modeshape.frames"], timeout=300_000)
            values = page.evaluate(
                """() => Array.from([...Bokeh.documents[0].all_models].filter(
                     m => m.name === 'participation.bars')[0].data.value)"""
            )
            n = min(a.clicks, len(values) - 1)
            # the first bar is drawn with the page: click the others, then again
            for label, bars in (("new shape", range(1, n + 1)), ("drawn before", range(1, n + 1))):
                got = [click_bar(page, i, values[i]) for i in bars]
                frames = [g[0] for g in got]
                shown = [g[1] for g in got]
                med_f, med_s = statistics.median(frames), statistics.median(shown)
                print(
                    f"click -> {label:13s}: frames in the page median {med_f:6.1f} ms "
                    f"(max {max(frames):6.1f}), first frame shown median {med_s:6.1f} ms "
                    f"(max {max(shown):6.1f}); {len(got)} clicks   "
                    f"goal < 200 ms: {'met' if med_s < 200 else 'NOT met'}"
                )
            browser.close()
    finally:
        srv.stop()
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
