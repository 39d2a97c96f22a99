"""Typed numbers: read as a person means them, or refused with a message.

Bokeh's numeric fields drop the characters they do not expect while the user types, so
``1e5`` became 15, ``1.5`` became 15 in a whole-number field, ``5,5`` became 55 and ``abc``
was ignored, all without a word. A :class:`NumberField` is a plain text field
whose text is read here by :func:`parse_number`; what cannot be read, or lies outside the
parameter's bounds, is refused with a message under the field that names the field, what
was typed and what is allowed, and the field shows the value in force again. A field may
come with a slider (:class:`NumberField` ``slider=True``); the field, the slider and the
parameter always show the same value.
"""

from __future__ import annotations

import html
import re

import panel as pn
import param
from panel.viewable import Viewer

from .bind import Refused, bind
from .layout import font

__all__ = ["NumberField", "TypedInputError", "format_number", "parse_number", "refusal"]

#: A number as typed after the decimal mark is settled: digits with an optional point and
#: an optional exponent (no ``inf``, ``nan``, ``0x..``, ``1_000``).
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
#: Digits in groups of three separated by commas (``10,000``, ``1,000,000.5``).
_GROUPED = re.compile(r"[+-]?\d{1,3}(,\d{3})+(\.\d*)?")
#: Spaces a person puts between digit groups (``10 000``).
_SPACES = re.compile(r"(?<=\d)[ \u00a0\u202f](?=\d)")


class TypedInputError(ValueError):
    """A typed text that is not a number of the field's kind (the message says why)."""


def parse_number(text: str, integer: bool = False) -> float | int:
    """The number a person means by ``text``.

    A point or a comma is the decimal mark (``5,5`` is 5.5), an exponent is allowed
    (``1e5`` is 100000), spaces between digit groups are ignored. Commas between groups of
    three digits are thousands separators in a whole-number field (``10,000``); in a field
    of decimals such a text is ambiguous (``1,000``: 1000 or 1.0?) and refused.

    Parameters
    ----------
    text : str
        What was typed.
    integer : bool
        Whether the field takes whole numbers only.

    Returns
    -------
    int or float
        ``int`` when ``integer``.

    Raises
    ------
    TypedInputError
        For a text that is not a number, an ambiguous one, a non-finite one, or one with
        decimals in a whole-number field; the message says which.

    Examples
    --------
    >>> parse_number("1e5", integer=True), parse_number("5,5"), parse_number("10,000", True)
    (100000, 5.5, 10000)
    """
    raw = str(text).strip()
    if not raw:
        raise TypedInputError("nothing typed")
    t = _SPACES.sub("", raw)
    if "," in t:
        if _GROUPED.fullmatch(t):
            if not integer and "." not in t:
                raise TypedInputError(
                    f"{raw!r} is ambiguous (a comma can be a decimal mark or a thousands "
                    f"separator): type {t.replace(',', '')} or {t.replace(',', '.')}"
                )
            t = t.replace(",", "")
        elif t.count(",") == 1 and "." not in t:
            t = t.replace(",", ".")  # a decimal comma
        else:
            raise TypedInputError(f"{raw!r} is not a number (use one decimal mark)")
    if not _NUMBER.fullmatch(t):
        raise TypedInputError(f"{raw!r} is not a number")
    x = float(t)
    if x != x or x in (float("inf"), float("-inf")):
        raise TypedInputError(f"{raw!r} is too large")
    if integer:
        if not x.is_integer():
            raise TypedInputError(f"{raw!r} is not a whole number")
        return int(x)
    return x


def format_number(x) -> str:
    """A value as the field shows it (plain digits, so that it reads back unchanged)."""
    if isinstance(x, int) or float(x).is_integer():
        return str(int(x))
    return f"{x:g}"


def _grouped(x) -> str:
    if isinstance(x, int) or float(x).is_integer():
        return f"{int(x):,}"
    return f"{x:g}"


def allowed(p: param.Parameter, integer: bool) -> str:
    """What a field of parameter ``p`` takes, in words."""
    lo, hi = p.bounds if p.bounds is not None else (None, None)
    kind = "a whole number" if integer else "a number"
    if lo is not None and hi is not None:
        return f"{kind} from {_grouped(lo)} to {_grouped(hi)}"
    return kind


def refusal(obj: param.Parameterized, name: str, text: str, label: str = "") -> str:
    """The message for ``text`` typed for ``obj.name`` ("" when the parameter takes it)."""
    p = obj.param[name]
    label = label or p.label or name
    integer = isinstance(p, param.Integer)
    still = f"still {_grouped(getattr(obj, name))} in use"
    try:
        value = parse_number(text, integer)
    except TypedInputError as exc:
        hint = "" if integer else " (5.5 or 5,5)"
        return f"{label}: {exc}; type {allowed(p, integer)}{hint}; {still}."
    lo, hi = p.bounds if p.bounds is not None else (None, None)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        typed = str(text).strip()
        read = _grouped(value)
        if typed not in (read, format_number(value)):
            read = f"{typed} (= {read})"  # how it was read
        return (
            f"{label}: {read} is outside the allowed range {_grouped(lo)} to "
            f"{_grouped(hi)}; {still}."
        )
    return ""


class NumberField(Viewer):
    """A typed number of ``obj.name`` (a text field read by :func:`parse_number`), with a
    message under it and, with ``slider``, a slider over the parameter's soft bounds.

    ``css_class`` marks the field (``<css_class>``), its slider (``<css_class>-slider``)
    and its message (``ctl-message-<suffix>``, ``suffix`` the class without ``ctl-``).
    """

    obj = param.ClassSelector(class_=param.Parameterized, doc="Owner of the parameter.")
    parameter = param.String(doc="Name of the parameter.")
    label = param.String(doc="The field's label (named in the messages).")
    slider = param.Boolean(default=False, doc="With a slider over the soft bounds.")
    css_class = param.String(doc="CSS class of the field.")
    width = param.Integer(default=90, doc="Width of the text field (px).")
    compact = param.Boolean(
        default=False,
        doc="Label and field only, as wide as they are (for a row of controls); the view "
        "places :attr:`message` itself.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        obj, name = self.obj, self.parameter
        p = obj.param[name]
        self._integer = isinstance(p, param.Integer)
        value = getattr(obj, name)
        self.text = pn.widgets.TextInput(
            value=format_number(value),
            width=self.width,
            css_classes=[self.css_class],
            margin=(2, 8),
        )
        suffix = self.css_class.removeprefix("ctl-")
        self.message = pn.pane.HTML(
            "",
            visible=False,
            css_classes=["ctl-message", f"ctl-message-{suffix}"],
            styles={"color": "#b02a37", "font-size": font("0.9em"), "font-weight": "bold"},
            margin=(0, 12),
            sizing_mode="stretch_width",
        )
        self.bar: pn.widgets.FloatSlider | None = None
        if self.slider:
            lo, hi = p.softbounds or p.bounds
            self.bar = pn.widgets.FloatSlider(
                start=lo,
                end=max(hi, value),
                step=p.step or 0.1,
                value=value,
                show_value=False,
                css_classes=[f"{self.css_class}-slider"],
                sizing_mode="stretch_width",
                margin=(0, 12),
            )
            bind(self.bar, obj, name, to_widget=self._on_bar, to_state=self._from_bar)
        # the field shows the value in force as plain digits; what it cannot take is refused
        # with the message under it (app.views.bind: the one link of widgets and state)
        bind(self.text, obj, name, to_widget=format_number, to_state=self._read, refused=self._tell)

    def _read(self, text: str) -> float | int:
        message = self.refusal_of(text)
        if message:
            raise Refused(message)
        return parse_number(text, self._integer)

    def _tell(self, message: str) -> None:
        """Show (or, with ``""``, clear) the message under the field."""
        if message:
            self.message.param.update(object=html.escape(message), visible=True)
            if pn.state.notifications is not None:
                pn.state.notifications.error(message, duration=8000)
        elif self.message.visible:
            self.message.param.update(object="", visible=False)

    def refusal_of(self, text: str) -> str:
        """The message for ``text`` typed in this field ("" when it is taken)."""
        return refusal(self.obj, self.parameter, text, self.label)

    def _on_bar(self, value: float) -> float:
        """The slider's position for ``value`` (its range widened to a typed value beyond it)."""
        bar = self.bar
        assert bar is not None
        if value > bar.end:
            bar.end = value
        if value < bar.start:
            bar.start = value
        return value

    def _from_bar(self, value: float) -> float | int:
        return int(round(value)) if self._integer else float(value)

    def __panel__(self):
        if self.compact:  # as wide as the label and the field: beside other controls
            width = 9 * len(self.label) + 10  # about 16 px type
            label = pn.pane.HTML(
                html.escape(self.label),
                margin=(6, 4, 0, 12),
                sizing_mode="fixed",
                width=width,
                height=30,
                css_classes=[f"{self.css_class}-label"],
            )
            return pn.Row(label, self.text, sizing_mode=None, width=width + 120)
        label = pn.pane.HTML(
            html.escape(self.label),
            margin=(6, 4, 0, 12),
            sizing_mode="stretch_width",
            css_classes=[f"{self.css_class}-label"],
        )
        parts = [pn.Row(label, self.text, sizing_mode="stretch_width")]
        if self.bar is not None:
            parts.append(self.bar)
        parts.append(self.message)
        return pn.Column(*parts, sizing_mode="stretch_width", margin=0)
