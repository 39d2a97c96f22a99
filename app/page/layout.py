"""Page layout state kept in the link: presentation view, data card, N-axis scale, uploads.

``?view=present`` is the presentation view for a projector (data card collapsed, larger type,
legends outside the plots); ``card=closed`` keeps the data card collapsed; ``naxis=log`` draws
the error map's N axis logarithmically; ``data=chassis:<digest>`` names the uploads a link
needs (the page says so when the session lacks them).
"""

from __future__ import annotations

import param

from ..schema import setting, url_keys_of

__all__ = [
    "PageState",
    "PAGE_URL_KEYS",
    "PAGE_CSS",
    "CARD_CSS",
    "PRESENT_CLASS",
    "NORMAL_CLASS",
    "VIEW_SWITCH_JS",
    "BAR_WIDTHS",
    "bar_stylesheet",
    "present_css",
]


class PageState(param.Parameterized):
    """How the page is laid out (not what it computes)."""

    view: param.Selector[str] = param.Selector(
        metadata=setting("view"),
        default="normal",
        objects=["normal", "present"],
        doc="normal, or present: the presentation view for a projector.",
    )
    data_card: param.Selector[str] = param.Selector(
        metadata=setting("card"),
        default="open",
        objects=["open", "closed"],
        doc="The 'Your data' card open or collapsed.",
    )
    n_axis: param.Selector[str] = param.Selector(
        metadata=setting("naxis", "scale of the N axis of the error map"),
        default="linear",
        objects=["linear", "log"],
        doc="Scale of the error map's N axis.",
    )
    data = param.String(
        metadata=setting("data"),
        default="",
        doc="The uploads the page's results need (empty: the reference models).",
    )
    review = param.String(
        metadata=setting("review"),
        default="",
        doc="The review: candidates' digests, the current one, the incumbent rule and the "
        "targets (app.review.review_link; empty: no review).",
    )
    sidebar: param.Selector[str] = param.Selector(
        metadata=setting("sidebar"),
        default="auto",
        objects=["auto", "open", "closed"],
        doc="The controls' sidebar: auto (open in the normal view, collapsed in the "
        "presentation view), or as the user left it.",
    )

    @property
    def sidebar_collapsed(self) -> bool:
        """Whether the sidebar is collapsed."""
        return bool(self.sidebar == "closed" or (self.sidebar == "auto" and self.view == "present"))


#: URL query keys of the page state.
PAGE_URL_KEYS = url_keys_of(PageState)

#: Larger type of the controls and cards in the presentation view: the page's font size
#: and Bokeh's font-size variable, which the widgets and cards inside their shadow roots
#: inherit (a document-level selector such as ``.card-title`` does not reach them).
PRESENT_RULE = "font-size: 17px; --bokeh-font-size: 17px;"
#: Classes of ``<body>`` set by the page's view switch in the browser (no reload needed).
PRESENT_CLASS, NORMAL_CLASS = "fbs-present", "fbs-normal"


#: Widths (px) of the page bar's buttons in the normal and the presentation view's type, as
#: wide as their labels: sidebar switch, help, view switch, N axis switch, each report button.
BAR_WIDTHS = {
    "normal": {"sidebar": 100, "help": 70, "view": 220, "naxis": 150, "report": 140},
    "present": {"sidebar": 115, "help": 80, "view": 285, "naxis": 190, "report": 165},
}


def _bar_vars(view: str) -> str:
    return " ".join(f"--fbs-bar-{k}: {w}px;" for k, w in BAR_WIDTHS[view].items())


def bar_stylesheet(part: str, times: int = 1, plus: int = 0) -> str:
    """Stylesheet of a page-bar element ``part`` (a key of :data:`BAR_WIDTHS`): its width
    follows the view from the page's CSS variables (``times`` such widths plus ``plus`` px).

    The switch changes the variables on ``<body>``: one layout of the page in the browser. Set
    as each widget's width from the server, every width laid the whole page out again
    (~0.25 s each in chromium, a dozen per switch).
    """
    w = f"calc({times} * var(--fbs-bar-{part}) + {plus}px)"
    return f":host {{ width: {w} !important; min-width: {w} !important; }}"


def present_css(loaded_present: bool) -> str:
    """CSS of the presentation view's larger type and page-bar widths.

    The view switch toggles :data:`PRESENT_CLASS` / :data:`NORMAL_CLASS` on ``<body>``
    (a JavaScript callback of the switch), so the type follows the switch at once. A page
    loaded with ``view=present`` has neither class yet: its rules also apply to a body
    that is not marked normal.
    """
    prefixes = [f"body.{PRESENT_CLASS}"]
    if loaded_present:
        prefixes.append(f"body:not(.{NORMAL_CLASS})")
    rule = f"{PRESENT_RULE} {_bar_vars('present')}"
    normal = f":root {{ {_bar_vars('normal')} }}\n"
    return normal + "".join(f"{p} {{ {rule} }}\n" for p in prefixes)


#: JavaScript of the view switch (a RadioButtonGroup: ``active`` 1 is the presentation).
VIEW_SWITCH_JS = (
    "const on = cb_obj.active === 1;"
    f"document.body.classList.toggle('{PRESENT_CLASS}', on);"
    f"document.body.classList.toggle('{NORMAL_CLASS}', !on);"
)

#: Page-wide CSS (both views): an idle progress bar is not a text field.
PAGE_CSS = """
.page-bar { align-items: center; }
"""

#: Stylesheet of every card (inside its shadow root): a visible collapse control.
CARD_CSS = """
.card-button {
  width: 24px !important; height: 24px !important; min-width: 24px;
  border: 1px solid #495057 !important; border-radius: 4px; background: #ffffff !important;
  color: #212529; margin-right: 0.6em !important; display: inline-flex;
  align-items: center; justify-content: center;
}
.card-button svg { width: 16px; height: 16px; stroke: #212529; }
"""
