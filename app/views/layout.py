"""Sizes of the page's rows and the CSS that follows the window and the presentation view.

The plots' heights follow the browser window, between a floor and a ceiling, through CSS
custom properties set on ``<body>``: a custom property is inherited into every component's
shadow root, so one rule sizes every plot row, and a window resize or the presentation
switch re-lays out the page in the browser without a message to the server (no re-layout
storm: the server sends nothing, and Bokeh re-lays out each plot once per resize).

A box whose height comes from CSS has ``sizing_mode="stretch_width"`` and no height of its
own; its content stretches into it. Panel's layouts would infer a ``stretch_both`` sizing of
such a box from its content (a column of stretching plots); in a page column of no fixed
height a ``stretch_both`` box is given no height at all (its flex basis is 0): that was
how the Analysis card once had height 0. So the page sets
``pn.config.respect_explicit_sizing`` (:data:`PANEL_CONFIG`): a sizing mode stated on a
layout is the one it gets, and Panel has nothing to warn about.

``--fbs-plot-h`` is the height of a plot card's content (header row, title block, plot,
legend): ``clamp(floor, 100vh - what is above the first row, ceiling)``, so the first row
fills the first screen. A view of several plots above each other (the Analysis card's)
is a multiple of it (:func:`plot_rows`).

The presentation view (``body.fbs-present``, :func:`layout_css`) also sets
``--fbs-min-font`` (16 px: the smallest type on a projector) and hides the rows that repeat
the title block (``--fbs-caption-display``: the captions and CSV buttons of the plots).
"""

from __future__ import annotations

import panel as pn

__all__ = [
    "CAPTION_ROW_CSS",
    "HIDE_TEMPLATE_TOGGLE_CSS",
    "MIN_FONT",
    "PANEL_CONFIG",
    "PLOT_HEIGHT",
    "PRESENT_PLOT_HEIGHT",
    "SIDEBAR_JS",
    "VIEW_SIDEBAR_JS",
    "font",
    "layout_css",
    "plot_rows",
    "sidebar_toggle",
    "sized",
    "weight",
]

#: Panel settings of the page (see the module's text).
PANEL_CONFIG = {"respect_explicit_sizing": True}

#: CSS height of a plot card's content, normal view: (floor, window height minus, ceiling)
#: in px (what is above the first row's content: the header, the page bar, a card header).
PLOT_HEIGHT = (470, 175, 980)
#: The same in the presentation view (larger type: taller page bar and card headers).
PRESENT_PLOT_HEIGHT = (420, 195, 980)

#: The smallest type of the presentation view (px), for the projector.
MIN_FONT = 16

#: Classes of ``<body>`` (set by the view switch in the browser; see app.report.page).
PRESENT_CLASS, NORMAL_CLASS = "fbs-present", "fbs-normal"


def _clamp(floor: int, minus: int, ceiling: int) -> str:
    return f"clamp({floor}px, calc(100vh - {minus}px), {ceiling}px)"


def _rule(present: bool) -> str:
    plot = PRESENT_PLOT_HEIGHT if present else PLOT_HEIGHT
    return (
        f"--fbs-plot-h: {_clamp(*plot)}; "
        f"--fbs-min-font: {MIN_FONT if present else 0}px; "
        f"--fbs-caption-display: {'none' if present else 'flex'};"
    )


def layout_css(loaded_present: bool) -> str:
    """The page's CSS of the row heights, normal and presentation view.

    The view switch toggles the classes of ``<body>`` at once; a page loaded with
    ``view=present`` has neither class yet, so its presentation rule also applies to a body
    not marked normal (as the type sizes of :func:`app.report.page.present_css`).
    """
    present = [f"body.{PRESENT_CLASS}"]
    if loaded_present:
        present.append(f"body:not(.{NORMAL_CLASS})")
    # the buttons' type is 0.8 rem (Panel's Bootstrap design): the root's type makes it 16 px
    root = ", ".join(f":root:has({p})" for p in present)
    return (
        f"body {{ {_rule(False)} }}\n"
        + "".join(f"{p} {{ {_rule(True)} }}\n" for p in present)
        + f"{root} {{ font-size: {MIN_FONT / 0.8:g}px; }}\n"
    )


def font(size: str) -> str:
    """A relative font size that is never below the presentation view's smallest type."""
    return f"max({size}, var(--fbs-min-font, 0px))"


#: Stylesheet of a row that repeats a plot's title block (caption and CSV button): not
#: shown in the presentation view.
CAPTION_ROW_CSS = ":host { display: var(--fbs-caption-display, flex); }"


def sized(*objs, row: str = "plot", height: str | None = None, **kw) -> pn.Column:
    """``objs`` in a box as wide as its container and of the CSS height of ``row``
    ("plot": the plot rows') or ``height`` (a CSS length); they stretch into it."""
    return pn.Column(
        *objs,
        sizing_mode="stretch_width",
        stylesheets=[f":host {{ height: {height or f'var(--fbs-{row}-h)'}; }}"],
        margin=0,
        **kw,
    )


def plot_rows(n: float) -> str:
    """The CSS height of ``n`` plot rows (a view of several plots above each other)."""
    return f"calc({n:g} * var(--fbs-plot-h))"


#: The page's own sidebar switch replaces the template's button (whose state the server
#: never learns, so it could not be kept in the link).
HIDE_TEMPLATE_TOGGLE_CSS = "#sidebar-toggle { display: none !important; }\n"


def _sidebar_js(show: str) -> str:
    """JavaScript that shows (``show`` true) or collapses the template's ``#sidebar`` at once
    in the browser (its Bootstrap collapse)."""
    return (
        f"const show = {show};"
        + """
const el = document.getElementById('sidebar');
if (el != null) {
  if (window.bootstrap && window.bootstrap.Collapse) {
    const c = window.bootstrap.Collapse.getOrCreateInstance(el, {toggle: false});
    if (show) { c.show(); } else { c.hide(); }
  } else {
    el.classList.toggle('show', show);
  }
}
"""
    )


#: JavaScript of the sidebar switch (a Toggle: ``active`` is "controls shown").
SIDEBAR_JS = _sidebar_js("cb_obj.active")
#: JavaScript of the view switch (``active`` 1: the presentation view): the sidebar
#: follows the view at once, before the server has answered.
VIEW_SIDEBAR_JS = _sidebar_js("cb_obj.active !== 1")


def sidebar_toggle(page) -> pn.widgets.Toggle:
    """The switch of the controls' sidebar, kept in the page state ``page`` (and the link).

    ``page.sidebar`` is "auto" (open in the normal view, collapsed in the presentation view)
    until the user sets it otherwise; a change of the view returns it to "auto".
    """
    toggle = pn.widgets.Toggle(
        label="Controls",
        value=not page.sidebar_collapsed,
        button_type="light",
        css_classes=["ctl-page-sidebar"],
        width=100,
    )
    toggle.jscallback(value=SIDEBAR_JS)

    def from_user(e):
        if e.new == (not page.sidebar_collapsed):
            return
        auto = page.view != "present"  # shown under "auto"
        page.sidebar = "auto" if e.new == auto else ("open" if e.new else "closed")

    def from_page(*_):
        if toggle.value != (not page.sidebar_collapsed):
            toggle.value = not page.sidebar_collapsed

    def view_changed(_e):
        page.sidebar = "auto"
        from_page()

    toggle.param.watch(from_user, "value")
    page.param.watch(from_page, "sidebar")
    page.param.watch(view_changed, "view")
    return toggle


def weight(fig, grow: float) -> None:
    """Give the Bokeh figure ``fig`` ``grow`` times the share of its column's height (the
    plot carrying a title block next to one without)."""
    fig.stylesheets = [*fig.stylesheets, f":host {{ flex-grow: {grow:g} !important; }}"]
