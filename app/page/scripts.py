"""Small behaviours of the page in the browser, installed once per document.

- **A checkbox's label toggles it.** Panel draws a checkbox as an ``input`` followed by a
  ``div.bk-label`` (no ``<label>`` element), so a click on the words did nothing. One click
  listener of the document (the event's composed path reaches into the widgets' shadow
  roots) clicks the box when its label is clicked: every checkbox of the page, built now or
  later, with the box's own change event (so Panel sees a normal change).
- **Tooltips stay inside the window.** Bokeh places a widget's description tooltip to the
  right of its icon (and a plot's hover tooltip next to the cursor), so near the window's
  right edge at 1280x720 it ran off screen. Every tooltip element (found as the mouse moves:
  Bokeh makes them on their first hover) is watched, and whenever Bokeh places it (its
  style changes) it is moved back inside the window.

Installed with Bokeh's public ``DocumentReady`` event (:func:`install`); the scripts use
only the DOM's public API and the class names Bokeh gives its elements.
"""

from __future__ import annotations

from bokeh.events import DocumentReady
from bokeh.models import CustomJS

__all__ = ["CHECKBOX_LABEL_JS", "TOOLTIP_INSIDE_JS", "install"]

CHECKBOX_LABEL_JS = """
if (!window.fbsCheckboxLabels) {
  window.fbsCheckboxLabels = true;
  document.addEventListener('click', (e) => {
    const first = e.composedPath()[0];
    if (!(first instanceof Element)) return;
    const label = first.closest('.bk-label');
    if (!label) return;
    const box = label.previousElementSibling;
    if (box && box.tagName === 'INPUT' && box.type === 'checkbox' && !box.disabled) box.click();
  }, true);
}
"""

TOOLTIP_INSIDE_JS = """
if (!window.fbsTooltipsInside) {
  window.fbsTooltipsInside = true;
  const margin = 4;
  const seen = new WeakSet();
  const inside = (tip) => {
    if (!tip.isConnected) return;
    const r = tip.getBoundingClientRect();
    if (r.width === 0 || r.height === 0) return;
    const W = window.innerWidth, H = window.innerHeight;
    let dx = 0, dy = 0;
    if (r.right > W - margin) dx = W - margin - r.right;
    if (r.left + dx < margin) dx = margin - r.left;
    if (r.bottom > H - margin) dy = H - margin - r.bottom;
    if (r.top + dy < margin) dy = margin - r.top;
    if (dx || dy) {
      const cs = getComputedStyle(tip);
      // moved over what it describes: it must not take the pointer from it (or it hides)
      tip.style.pointerEvents = 'none';
      tip.style.left = (parseFloat(cs.left) + dx) + 'px';
      tip.style.top = (parseFloat(cs.top) + dy) + 'px';
    }
  };
  const collect = (root) => {
    for (const el of root.querySelectorAll('*')) {
      if (el.classList.contains('bk-Tooltip') && !seen.has(el)) {
        seen.add(el);  // placed again by Bokeh (its style changes): moved inside again
        new MutationObserver(() => inside(el)).observe(
          el, {attributes: true, attributeFilter: ['style', 'class']});
        inside(el);
      }
      if (el.shadowRoot) collect(el.shadowRoot);
    }
  };
  let last = 0;
  let queued = false;
  const look = () => {  // tooltips are made on their first hover: look for new ones
    queued = false;
    if (Date.now() - last < 200) return;
    last = Date.now();
    collect(document);
  };
  const later = () => { if (!queued) { queued = true; requestAnimationFrame(look); } };
  window.addEventListener('mousemove', later, true);
  window.addEventListener('pointerover', later, true);
}
"""


def install(doc) -> None:
    """Install the page's scripts on the Bokeh document ``doc`` (runs once it is ready)."""
    if doc is None:
        return
    doc.js_on_event(DocumentReady, CustomJS(code=CHECKBOX_LABEL_JS + TOOLTIP_INSIDE_JS))
