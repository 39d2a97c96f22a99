"""Page layout state kept in the link: presentation view, data card, N-axis scale, uploads.

``?view=present`` is the presentation view for a projector (data card collapsed, larger type,
legends outside the plots); ``card=closed`` keeps the data card collapsed; ``naxis=log`` draws
the error map's N axis logarithmically; ``data=chassis:<digest>`` names the uploads a link
needs (the page says so when the session lacks them).
"""

from __future__ import annotations

import param

__all__ = [
    "PageState",
    "PAGE_URL_KEYS",
    "PAGE_CSS",
    "CARD_CSS",
    "PRESENT_CLASS",
    "NORMAL_CLASS",
    "VIEW_SWITCH_JS",
    "present_css",
]


class PageState(param.Parameterized):
    """How the page is laid out (not what it computes)."""

    view: param.Selector[str] = param.Selector(
        default="normal",
        objects=["normal", "present"],
        doc="normal, or present: the presentation view for a projector.",
    )
    data_card: param.Selector[str] = param.Selector(
        default="open", objects=["open", "closed"], doc="The 'Your data' card open or collapsed."
    )
    n_axis: param.Selector[str] = param.Selector(
        default="linear", objects=["linear", "log"], doc="Scale of the error map's N axis."
    )
    data = param.String(
        default="", doc="The uploads the page's results need (empty: the reference models)."
    )
    sidebar: param.Selector[str] = param.Selector(
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
PAGE_URL_KEYS = {
    "view": "view",
    "data_card": "card",
    "n_axis": "naxis",
    "data": "data",
    "sidebar": "sidebar",
}

#: Larger type of the controls and cards in the presentation view: the page's font size
#: and Bokeh's font-size variable, which the widgets and cards inside their shadow roots
#: inherit (a document-level selector such as ``.card-title`` does not reach them).
PRESENT_RULE = "font-size: 17px; --bokeh-font-size: 17px;"
#: Classes of ``<body>`` set by the page's view switch in the browser (no reload needed).
PRESENT_CLASS, NORMAL_CLASS = "fbs-present", "fbs-normal"


def present_css(loaded_present: bool) -> str:
    """CSS of the presentation view's larger type.

    The view switch toggles :data:`PRESENT_CLASS` / :data:`NORMAL_CLASS` on ``<body>``
    (a JavaScript callback of the switch), so the type follows the switch at once. A page
    loaded with ``view=present`` has neither class yet: its rules also apply to a body
    that is not marked normal.
    """
    prefixes = [f"body.{PRESENT_CLASS}"]
    if loaded_present:
        prefixes.append(f"body:not(.{NORMAL_CLASS})")
    return "".join(f"{p} {{ {PRESENT_RULE} }}\n" for p in prefixes)


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
