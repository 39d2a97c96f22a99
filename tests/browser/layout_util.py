"""Measuring the page in chromium: element rectangles, plot canvases and legends, title
lines, type sizes (issue 29).

Everything is measured in the page, through the DOM (``getBoundingClientRect`` across the
components' shadow roots) and BokehJS's public view API (``Bokeh.index.find_one(model)``:
a plot's view, its frame and the bounding box of a legend on the canvas). Screenshots of
each state go to ``tests/browser/artifacts/`` (git-ignored) for a person to look at.
"""

from __future__ import annotations

from pathlib import Path

ARTIFACTS = Path(__file__).parent / "artifacts"
#: The smallest plot area (px each way) that still reads as a plot (the compare tab's were
#: about 30 px high at 1366 px wide).
MIN_FRAME = 100
#: The window sizes of the meeting room (projectors) and of a desktop screen.
SIZES = [(1280, 720), (1366, 768), (1920, 1080)]


def shot(page, name: str) -> Path:
    """A screenshot of the window as it is now (tests/browser/artifacts/<name>.png)."""
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    print(f"screenshot: {path}")
    return path


def scroll_to(page, locator) -> None:
    """Scroll the page's main area so that ``locator``'s element starts at its top."""
    locator.first.evaluate("e => e.scrollIntoView({block: 'start'})")
    page.wait_for_function("() => new Promise(r => requestAnimationFrame(() => r(true)))")


#: All elements of the page, through the shadow roots of the components (JS helper).
JS_WALK = """
function fbsWalk(root, out) {
  for (const el of root.querySelectorAll('*')) {
    out.push(el);
    if (el.shadowRoot) fbsWalk(el.shadowRoot, out);
  }
  return out;
}
function fbsRect(el) {
  const r = el.getBoundingClientRect();
  return {left: r.left, top: r.top, right: r.right, bottom: r.bottom,
          width: r.width, height: r.height};
}
function fbsShown(el) {
  const r = el.getBoundingClientRect();
  if (r.width < 1 || r.height < 1) return false;
  for (let e = el; e; e = e.parentElement || (e.getRootNode && e.getRootNode().host)) {
    const s = getComputedStyle(e);
    if (s.display === 'none' || s.visibility === 'hidden' || s.opacity === '0') return false;
  }
  return true;
}
"""

#: Cards of the page (Panel's Card layouts), with their titles and rectangles.
JS_CARDS = (
    "() => {"
    + JS_WALK
    + """
  return fbsWalk(document, []).filter(
      el => el.classList && el.classList.contains('bk-panel-models-layout-Card')
            && fbsShown(el)
    ).map(el => {
      const t = el.shadowRoot && el.shadowRoot.querySelector('.card-title');
      return {title: t ? t.textContent.trim() : '', classes: [...el.classList],
              rect: fbsRect(el)};
    });
}"""
)

#: The page's plots: canvas rectangle (page coordinates), legends (page coordinates) and
#: the title lines (text, font size, left end and measured width on the canvas).
JS_PLOTS = """
() => {
  const ctx = document.createElement('canvas').getContext('2d');
  const out = [];
  for (const p of [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure')) {
    const v = Bokeh.index.find_one(p);
    if (v == null) continue;
    const r = v.el.getBoundingClientRect();
    if (r.width < 1 || r.height < 1 || !p.visible) continue;
    const shown = m => m.visible !== false;
    const legends = [...p.center, ...p.below, ...p.right, ...p.above, ...p.left].filter(
        m => m.type === 'Legend' && shown(m) && m.items.some(i => i.visible !== false)
    ).map(l => {
      const b = Bokeh.index.find_one(l).bbox;
      return {left: r.left + b.left, top: r.top + b.top, right: r.left + b.right,
              bottom: r.top + b.bottom, width: b.width, height: b.height};
    }).filter(b => b.width >= 1 && b.height >= 1);  // a legend not drawn (yet)
    const bars = [...p.right, ...p.left, ...p.below, ...p.above].filter(
        m => m.type === 'ColorBar' && shown(m)).map(m => {
      const b = Bokeh.index.find_one(m).bbox;
      return {left: r.left + b.left, top: r.top + b.top, right: r.left + b.right,
              bottom: r.top + b.bottom, width: b.width, height: b.height};
    }).filter(b => b.width >= 1 && b.height >= 1);
    const titles = p.above.filter(m => m.type === 'Title' && shown(m) && m.text).map(t => {
      ctx.font = `${t.text_font_style} ${t.text_font_size} ${t.text_font}`;
      return {text: t.text, size: t.text_font_size, left: v.frame.bbox.left,
              width: ctx.measureText(t.text).width};
    });
    let card = v.el;  // the card the plot is in
    while (card && !(card.classList && card.classList.contains('bk-panel-models-layout-Card')))
      card = card.parentElement || (card.getRootNode && card.getRootNode().host);
    const cr = card ? card.getBoundingClientRect() : null;
    out.push({name: p.name || p.id, canvas: {left: r.left, top: r.top, right: r.right,
              bottom: r.bottom, width: r.width, height: r.height},
              card: cr ? {left: cr.left, top: cr.top, right: cr.right, bottom: cr.bottom,
                          width: cr.width, height: cr.height} : null,
              frame: {width: v.frame.bbox.width, height: v.frame.bbox.height},
              legends, bars, titles});
  }
  return out;
}
"""

#: Text smaller than ``min`` px: DOM text shown in the window's width, and the type of
#: the canvas texts of the plots shown (ticks, axis labels, titles, legends, colour bars,
#: labels).
JS_SMALL_TEXT = (
    "(min) => {"
    + JS_WALK
    + """
  const px = s => {
    if (s == null) return null;
    if (typeof s === 'object') s = s.value;
    if (typeof s !== 'string') return null;
    const x = parseFloat(s);
    return s.endsWith('pt') ? x * 4 / 3 : s.endsWith('em') ? x * 16 : x;
  };
  const small = [];
  for (const el of fbsWalk(document, [])) {
    const own = [...el.childNodes].filter(
        n => n.nodeType === 3 && n.textContent.trim().length > 0);
    if (!own.length || !fbsShown(el)) continue;
    const r = el.getBoundingClientRect();
    if (r.right <= 0 || r.left >= innerWidth) continue;
    const f = parseFloat(getComputedStyle(el).fontSize);
    if (f < min - 0.01)
      small.push({text: own[0].textContent.trim().slice(0, 60), px: f, tag: el.tagName});
  }
  for (const p of [...Bokeh.documents[0].all_models].filter(m => m.type === 'Figure')) {
    const v = Bokeh.index.find_one(p);
    if (v == null || !p.visible) continue;
    const r = v.el.getBoundingClientRect();
    if (r.width < 1 || r.height < 1) continue;
    const parts = [...p.left, ...p.right, ...p.above, ...p.below, ...p.center];
    for (const m of parts) {
      if (m.visible === false) continue;
      const sizes = [];
      if (m.type.endsWith('Axis')) {
        sizes.push(['tick', m.major_label_text_font_size]);
        if (m.axis_label) sizes.push(['axis label', m.axis_label_text_font_size]);
      } else if (m.type === 'Title' && m.text) {
        sizes.push(['title ' + m.text.slice(0, 30), m.text_font_size]);
      } else if (m.type === 'Legend') {
        sizes.push(['legend', m.label_text_font_size]);
      } else if (m.type === 'ColorBar') {
        sizes.push(['colour bar', m.major_label_text_font_size]);
        if (m.title) sizes.push(['colour bar title', m.title_text_font_size]);
      } else if (m.type === 'LabelSet' || m.type === 'Label') {
        sizes.push(['label', m.text_font_size]);
      }
      for (const [what, s] of sizes) {
        const x = px(s);
        if (x !== null && x < min - 0.01) small.push({text: `${p.name}: ${what}`, px: x});
      }
    }
    if (p.title && p.title.visible !== false && p.title.text) {
      const x = px(p.title.text_font_size);
      if (x !== null && x < min - 0.01) small.push({text: `${p.name}: title`, px: x});
    }
  }
  return small;
}"""
)


def cards(page) -> list[dict]:
    """The cards shown: title, classes and rectangle."""
    return page.evaluate(JS_CARDS)


def plots(page) -> list[dict]:
    """The plots shown: canvas, frame, legends and title lines."""
    return page.evaluate(JS_PLOTS)


def small_text(page, min_px: float) -> list[dict]:
    """Texts shown whose type is smaller than ``min_px``."""
    return page.evaluate(JS_SMALL_TEXT, min_px)


def overlaps(rects: list[dict], tol: float = 0.5) -> list[tuple[int, int]]:
    """Pairs of rectangles that overlap (by more than ``tol`` px), neither inside the other."""

    def inside(a, b):
        return (
            a["left"] >= b["left"] - tol
            and a["right"] <= b["right"] + tol
            and a["top"] >= b["top"] - tol
            and a["bottom"] <= b["bottom"] + tol
        )

    out = []
    for i, a in enumerate(rects):
        for j in range(i + 1, len(rects)):
            b = rects[j]
            w = min(a["right"], b["right"]) - max(a["left"], b["left"])
            h = min(a["bottom"], b["bottom"]) - max(a["top"], b["top"])
            if w > tol and h > tol and not inside(a, b) and not inside(b, a):
                out.append((i, j))
    return out


def outside_width(plot: dict, width: float, tol: float = 0.5) -> list[str]:
    """What of ``plot`` (canvas, legends, title lines) lies outside ``[0, width]`` or, for
    legends and title lines, outside its own canvas."""
    out = []
    c = plot["canvas"]
    if c["left"] < -tol or c["right"] > width + tol:
        out.append(f"canvas {c['left']:.0f}-{c['right']:.0f} of {width}")
    for lg in plot["legends"]:
        if lg["left"] < c["left"] - tol or lg["right"] > min(c["right"], width) + tol:
            out.append(f"legend {lg['left']:.0f}-{lg['right']:.0f}, canvas to {c['right']:.0f}")
    for b in plot.get("bars", []):
        if b["left"] < c["left"] - tol or b["right"] > min(c["right"], width) + tol:
            out.append(f"colour bar {b['left']:.0f}-{b['right']:.0f}, canvas to {c['right']:.0f}")
    for t in plot["titles"]:
        if t["left"] + t["width"] > c["width"] + tol:
            out.append(f"title line cut: {t['text'][:50]!r} ({t['width']:.0f} px)")
    return out


#: Horizontal overflow of the page's main area and of the document (px; 0: none).
JS_OVERFLOW = """
() => {
  const m = document.getElementById('main');
  const d = document.scrollingElement;
  return {main: m ? m.scrollWidth - m.clientWidth : 0, document: d.scrollWidth - d.clientWidth};
}
"""

#: The page's controls shown (buttons, inputs, selects, through the shadow roots): their
#: text and rectangle.
JS_CONTROLS = """
() => {
  const out = [];
  const walk = (root) => { for (const el of root.querySelectorAll('*')) {
      if (el.shadowRoot) walk(el.shadowRoot);
      if (!['BUTTON', 'INPUT', 'SELECT', 'TEXTAREA'].includes(el.tagName)) continue;
      const r = el.getBoundingClientRect();
      const st = getComputedStyle(el);
      if (r.width < 1 || r.height < 1 || st.visibility === 'hidden' || st.display === 'none')
        continue;
      out.push({text: (el.innerText || el.value || el.tagName).slice(0, 30),
                rect: {left: r.left, right: r.right, top: r.top, bottom: r.bottom}});
  } };
  walk(document);
  return out;
}
"""


def intersect(a: dict, b: dict, tol: float = 0.5) -> bool:
    """Whether rectangles ``a`` and ``b`` share an area (more than ``tol`` px each way)."""
    w = min(a["right"], b["right"]) - max(a["left"], b["left"])
    h = min(a["bottom"], b["bottom"]) - max(a["top"], b["top"])
    return w > tol and h > tol


def inside(a: dict, b: dict, tol: float = 1.0) -> bool:
    """Whether rectangle ``a`` lies inside ``b``."""
    return (
        a["left"] >= b["left"] - tol
        and a["right"] <= b["right"] + tol
        and a["top"] >= b["top"] - tol
        and a["bottom"] <= b["bottom"] + tol
    )


def layout_problems(page, width: int) -> list[str]:
    """What is wrong with the page's layout now, in words (empty: nothing).

    Cards overlap; a card, a plot canvas, its legend or a title line reaches outside the
    window's width; a plot lies outside its own card or over another card, or its plot area
    is smaller than :data:`MIN_FRAME`; a control (button, input) lies over a plot; the main
    area scrolls sideways.
    """
    out = []
    cs = cards(page)
    for i, j in overlaps([c["rect"] for c in cs]):
        out.append(f"cards overlap: {cs[i]['title'][:40]!r} and {cs[j]['title'][:40]!r}")
    for c in cs:
        r = c["rect"]
        if r["left"] < -0.5 or r["right"] > width + 0.5:
            out.append(f"card {c['title'][:40]!r} spans {r['left']:.0f}-{r['right']:.0f}")
    for p in plots(page):
        out += [f"{p['name']}: {w}" for w in outside_width(p, width)]
        if p["frame"]["height"] < MIN_FRAME or p["frame"]["width"] < MIN_FRAME:
            out.append(f"{p['name']}: a plot area of {p['frame']} px")
        if p["card"] is not None and not inside(p["canvas"], p["card"]):
            out.append(f"{p['name']}: canvas {p['canvas']} outside its card {p['card']}")
        own = p["card"]
        for c in cs:
            r = c["rect"]
            if own is not None and (inside(r, own) or inside(own, r)):
                continue  # its own card (or a card around it)
            if intersect(p["canvas"], r):
                out.append(f"{p['name']}: canvas over the card {c['title'][:40]!r}")
    shown = plots(page)
    for c in page.evaluate(JS_CONTROLS):  # a control over a plot takes its clicks
        for p in shown:
            if intersect(c["rect"], p["canvas"], tol=2.0):
                out.append(f"the control {c['text']!r} lies over the plot {p['name']}")
    ov = page.evaluate(JS_OVERFLOW)
    if ov["main"] > 1 or ov["document"] > 1:
        out.append(f"the page scrolls sideways: {ov}")
    return out


def wait_stable(page, timeout: float = 30.0) -> None:
    """Wait until the cards and plots stop moving (two measures 250 ms apart agree)."""
    import time

    end = time.monotonic() + timeout
    last = None
    while time.monotonic() < end:
        now = (cards(page), [(p["name"], p["canvas"]) for p in plots(page)])
        if now == last:
            return
        last = now
        page.wait_for_timeout(250)  # a poll of the condition, not a fixed wait
