"""The meeting room's random walk: 200 quick interactions (keys, clicks, drags, typed values,
tab switches, the presentation button) on one page, then every shown value and plot compared
with the published state (the checks of ``test_screen_truth``), at the three window sizes of
the meeting room, with a screenshot of each.

``FBS_TRUTH_SEED`` chooses the walk (default 41); the actions are logged to
``tests/browser/artifacts/screen_truth_<seed>.log`` and the screenshots written beside it
(``screen_truth_<seed>_<w>x<h>.png``), so a failure replays with the same seed.
"""

from __future__ import annotations

import os
import random
import time

from playwright.sync_api import Error as PlaywrightError

from .conftest import ARTIFACTS
from .layout_util import SIZES, layout_problems, wait_stable
from .test_screen_truth import _handle, check_truth, press, truth_page  # noqa: F401, F811

# -- the meeting room: 200 random quick interactions -----------------------------------------
RADIOS = {
    "ctl-case-dof": ["x", "y", "z", "rx", "ry", "rz"],
    "ctl-case-coupling": ["6dof", "5dof"],
    "ctl-truncation-map_mode": ["selected DOF", "max over 6 DOFs"],
    "ctl-plot-level_scale": ["dB", "linear"],
    "ctl-noise-target": ["both", "tire", "chassis"],
}
CHECKS = ["ctl-case-residual", "ctl-plot-snap", "ctl-noise-frequency_dependent"]
DRAGS = ["ctl-truncation-threshold-slider", "ctl-truncation-f_max-slider", "ctl-noise-noise-slider"]
TYPED = {
    "ctl-truncation-threshold": ["15", "7,5", "1e1", "abc", "5000", "30"],
    "ctl-truncation-f_max": ["140", "200", "1,000", "x", "120.5"],
}
TABS = ["Compare", "Phase and peaks", "Contributions"]
#: A click as a person's: where the element is, without waiting for the page to settle.
CLICK = {"force": True, "timeout": 20_000, "no_wait_after": True}
#: Longest wait for a control to be on the screen (the sidebar opens again after the view
#: switch; a person waits for it too).
SHOWN_S = 60.0
#: Whether the page shows the presentation view (its switch's model).
JS_PRESENT = """() => [...Bokeh.documents[0].all_models].some(
    m => m.css_classes && m.css_classes.includes('ctl-page-view') && m.active === 1)"""


def _click(locator) -> None:
    """Click ``locator`` once it is on the screen (the sidebar may be opening or closing after
    a view switch: the control is waited for, as a person does, then clicked at once)."""
    end = time.monotonic() + SHOWN_S
    while True:
        try:
            locator.wait_for(state="visible", timeout=max(1, end - time.monotonic()) * 1000)
            locator.click(**{**CLICK, "timeout": 5_000})
            return
        except PlaywrightError as exc:
            if time.monotonic() > end:
                raise AssertionError(f"not on the screen for {SHOWN_S:g} s: {locator}") from exc


def _act(page, rng: random.Random, log) -> None:
    kind = rng.choices(
        ["keys", "radio", "check", "overlay", "drag", "type", "tab", "present"],
        weights=[34, 20, 8, 8, 10, 8, 4, 2],
    )[0]
    present = page.evaluate(JS_PRESENT)
    hidden = not page.locator(".ctl-case-dof").first.is_visible()
    if (present or hidden) and kind not in ("tab", "present"):
        # the controls are hidden (presentation view, or the sidebar still closing/opening)
        kind = "present" if present else "wait"
    if kind == "wait":
        log("controls hidden: wait")
        page.wait_for_timeout(300)
        return
    if kind == "keys":
        cls = rng.choice(["ctl-case-n_modes", "ctl-case-n_modes", "ctl-case-harmonic"])
        key = rng.choice(["ArrowRight", "ArrowLeft"])
        times, gap = rng.randint(1, 6), rng.choice([0, 0, 30, 150, 300])
        log(f"keys {cls} {key} x{times} every {gap} ms")
        press(page, cls, key, times, gap)
    elif kind == "radio":
        cls = rng.choice(list(RADIOS))
        label = rng.choice(RADIOS[cls])
        log(f"click {cls} {label}")
        _click(page.locator(f".{cls}").get_by_role("button", name=label, exact=True))
    elif kind == "check":
        cls = rng.choice(CHECKS)
        log(f"toggle {cls}")
        _click(page.locator(f".{cls} input").first)
    elif kind == "overlay":
        label = rng.choice(["x", "y", "z", "rx", "ry", "rz"])
        log(f"overlay {label}")
        _click(page.locator(".ctl-plot-overlay").get_by_role("button", name=label, exact=True))
    elif kind == "drag":
        cls = rng.choice(DRAGS)
        dx = rng.randint(-120, 120)
        log(f"drag {cls} by {dx} px")
        handle = _handle(page, cls)
        handle.wait_for(state="visible", timeout=60_000)  # a slider always has its handle
        box = handle.bounding_box()
        if box is None:
            log("  (not on screen)")
            return
        x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x + dx, y, steps=rng.randint(2, 6))
        page.mouse.up()
    elif kind == "type":
        cls = rng.choice(list(TYPED))
        text = rng.choice(TYPED[cls])
        log(f"type {cls} {text!r}")
        box = page.locator(f".{cls} input").first
        box.wait_for(state="visible", timeout=SHOWN_S * 1000)
        box.fill(text)
        box.press("Enter")
    elif kind == "tab":
        name = rng.choice(TABS)
        log(f"analysis tab {name}")
        card = page.locator(".analysis-card").first
        if card.locator(".analysis-tabs").count() == 0:
            _click(card.locator(".card-button").first)  # opened once: tabs built
            page.locator(".analysis-tabs").first.wait_for(timeout=120_000)
        _click(page.locator(".analysis-tabs").get_by_text(name, exact=True).first)
    else:
        log("view " + ("Normal view" if present else "Presentation"))
        _click(page.locator(".ctl-page-view button").nth(0 if present else 1))
    if rng.random() < 0.5:
        page.wait_for_timeout(rng.choice([0, 20, 80, 200, 400]))


def test_200_random_quick_interactions(truth_page):  # noqa: F811 (the fixture)
    page = truth_page
    seed = int(os.environ.get("FBS_TRUTH_SEED", "41"))
    rng = random.Random(seed)
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / f"screen_truth_{seed}.log"
    lines: list[str] = []
    start = time.monotonic()

    def log(text: str) -> None:
        lines.append(f"{time.monotonic() - start:7.2f} s  #{len(lines)}  {text}")

    try:
        for _ in range(200):
            _act(page, rng, log)
        log("quiet?")
        check_truth(page)
        log("checked")
        # the same state at the meeting room's window sizes: shown values, layout, a screenshot
        for w, h in SIZES:
            page.set_viewport_size({"width": w, "height": h})
            wait_stable(page, timeout=120)
            check_truth(page)
            problems = layout_problems(page, w)
            shot = ARTIFACTS / f"screen_truth_{seed}_{w}x{h}.png"
            page.screenshot(path=str(shot))
            log(f"{w}x{h}: checked, screenshot {shot.name}")
            assert not problems, f"at {w}x{h}: " + "; ".join(problems)
    finally:
        path.write_text("\n".join(lines) + "\n")
        print(f"actions (seed {seed}): {path}")
