"""The control panel: widgets generated from the state parameters.

Typed numbers are checked against their parameter's bounds: a value outside them is not
silently ignored but answered with a message under the field (and a notification), and the
field goes back to the value in force.
"""

from __future__ import annotations

import html

import panel as pn
import param
from panel.viewable import Viewer

import fbs_core

from ..bands import served
from ..panel_private import respond_at_once
from ..state import DashboardState

#: Typed numeric controls: key -> (widget class, label, extra widget arguments).
_TYPED = {
    "truncation.threshold": ("slider", "Error threshold (%)", {"format": "0.0"}),
    "truncation.f_max": ("slider", "Upper frequency for suggestion (Hz)", {"format": "0"}),
    "noise.noise": ("slider", "Noise level p (%)", {"format": "0.0"}),
    "noise.rounds": ("int", "Rounds R", {"step": 1000}),
    "noise.seed": ("int", "Seed", {}),
    "noise.single_round": ("int", "Single round #", {}),
}


def _fmt(x) -> str:
    if isinstance(x, int) or float(x).is_integer():
        return f"{int(x):,}"
    return f"{x:g}"


def out_of_bounds(obj: param.Parameterized, name: str, value, label: str = "") -> str:
    """The message for ``value`` typed for ``obj.name`` ("" when the parameter takes it)."""
    p = obj.param[name]
    label = label or p.label or name
    if value is None:
        return f"{label}: type a number; still {_fmt(getattr(obj, name))}."
    lo, hi = p.bounds if p.bounds is not None else (None, None)
    if isinstance(p, param.Integer) and not float(value).is_integer():
        return f"{label}: a whole number please (typed {value:g}); still {getattr(obj, name)}."
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        return (
            f"{label}: {_fmt(value)} is outside the allowed range {_fmt(lo)} to {_fmt(hi)}; "
            f"still {_fmt(getattr(obj, name))} in use."
        )
    return ""


def _put_back(w: pn.widgets.Widget, obj: param.Parameterized, name: str) -> None:
    w.value = getattr(obj, name)


def _harmonic_html(k: int) -> str:
    return html.escape(harmonic_text(k))


def harmonic_text(k: int) -> str:
    """Wavelength, speed range and frequency band of harmonic case ``k``."""
    h = fbs_core.harmonic(int(k))
    lo, hi = h.freq_range
    return (
        f"Harmonic {h.k}: road wavelength {h.wavelength:g} m, "
        f"{h.speed_range[0]:g}-{h.speed_range[1]:g} km/h, band {lo:.1f}-{hi:.1f} Hz"
    )


class Controls(Viewer):
    """All controls of the dashboard, grouped by concern."""

    state = param.ClassSelector(class_=DashboardState)

    def __init__(self, **params):
        super().__init__(**params)
        self._widgets: dict[str, pn.widgets.Widget] | None = None
        self.messages: dict[str, pn.pane.HTML] = {}

    def _typed(self, key: str) -> pn.widgets.Widget:
        """A numeric field whose value is checked here, not refused silently by the widget."""
        group, name = key.split(".")
        obj = getattr(self.state, group)
        kind, label, kw = _TYPED[key]
        p = obj.param[name]
        w: pn.widgets.Widget
        if kind == "slider":
            lo, hi = p.softbounds or p.bounds
            w = pn.widgets.EditableFloatSlider(
                label=label,
                value=getattr(obj, name),
                start=lo,
                end=hi,
                step=p.step or 0.1,
                fixed_start=None,
                fixed_end=None,
                **kw,
            )
        else:
            w = pn.widgets.IntInput(label=label, value=getattr(obj, name), **kw)
        msg = self.messages[key] = pn.pane.HTML(
            "",
            visible=False,
            css_classes=["ctl-message", f"ctl-message-{group}-{name}"],
            styles={"color": "#b02a37", "font-size": "0.9em", "font-weight": "bold"},
            margin=(0, 12),
            sizing_mode="stretch_width",
        )

        def typed(event):
            if event.new == getattr(obj, name):
                return  # the value in force (also the field put back after a message)
            text = out_of_bounds(obj, name, event.new, label)
            if text:
                msg.param.update(object=html.escape(text), visible=True)
                # the field shows the value in force again; when served, after Panel has
                # handled the browser's change (a change of the same property while it is
                # handled is not sent back)
                if served():
                    pn.state.execute(lambda: _put_back(w, obj, name), schedule=True)
                else:
                    _put_back(w, obj, name)
                if pn.state.notifications is not None:
                    pn.state.notifications.error(text, duration=8000)
                return
            if msg.visible:
                msg.param.update(object="", visible=False)
            setattr(obj, name, event.new)

        def follow(event):  # a link or another control changed the parameter
            if w.value != event.new:
                w.value = event.new

        w.param.watch(typed, "value")
        obj.param.watch(follow, name)
        return w

    def widgets(self) -> dict[str, pn.widgets.Widget]:
        """The widgets by ``"<group>.<parameter>"`` (built once, reused by the layout)."""
        if self._widgets is None:
            c, n, t = self.state.case, self.state.noise, self.state.truncation
            W = pn.widgets
            self._widgets = {
                "case.harmonic": W.IntSlider.from_param(
                    c.param.harmonic, name="Harmonic case", start=1, end=7, step=1
                ),
                "case.n_modes": W.DiscreteSlider.from_param(
                    c.param.n_modes, name="Retained tire modes N"
                ),
                "case.dof": W.RadioButtonGroup.from_param(
                    c.param.dof, name="Response DOF at the bushing"
                ),
                "case.coupling": W.RadioButtonGroup.from_param(
                    c.param.coupling, name="Hub coupling"
                ),
                "case.show_uncoupled": W.Checkbox.from_param(
                    c.param.show_uncoupled, name="Show uncoupled tire and chassis FRFs"
                ),
                "case.residual": W.Checkbox.from_param(
                    c.param.residual,
                    name="Residual compensation (modes left out: quasi-static part)",
                ),
                "truncation.threshold": self._typed("truncation.threshold"),
                "truncation.f_max": self._typed("truncation.f_max"),
                "truncation.map_mode": W.RadioButtonGroup.from_param(
                    t.param.map_mode, name="Error map of"
                ),
                "noise.noise": self._typed("noise.noise"),
                "noise.target": W.RadioButtonGroup.from_param(n.param.target, name="Noise in"),
                "noise.frequency_dependent": W.Checkbox.from_param(
                    n.param.frequency_dependent,
                    name="Frequency-dependent noise (new S at every line)",
                ),
                "noise.rounds": self._typed("noise.rounds"),
                "noise.seed": self._typed("noise.seed"),
                "noise.single_round": self._typed("noise.single_round"),
                "noise.percentile": W.Select.from_param(
                    n.param.percentile, name="Central percentile band (%)"
                ),
            }
            for key, w in self._widgets.items():
                w.css_classes = [*w.css_classes, "ctl-" + key.replace(".", "-")]
                respond_at_once(w)
        return self._widgets

    def __panel__(self):
        w = self.widgets()
        m = self.messages
        label = pn.pane.Markdown
        case = self.state.case
        info = pn.pane.HTML(
            pn.bind(_harmonic_html, case.param.harmonic),
            css_classes=["ctl-harmonic-info"],
            styles={"font-size": "0.9em", "color": "#343a40"},
            margin=(0, 12),
            sizing_mode="stretch_width",
        )
        return pn.Column(
            label("#### Case", margin=(0, 5)),
            w["case.harmonic"],
            info,
            w["case.n_modes"],
            label("Response DOF at the bushing", margin=(0, 10)),
            w["case.dof"],
            label("Hub coupling: 6 DOFs (braked) / 5 DOFs (spin free)", margin=(0, 10)),
            w["case.coupling"],
            w["case.show_uncoupled"],
            pn.layout.Divider(),
            label("#### Truncation study", margin=(0, 5)),
            w["truncation.threshold"],
            m["truncation.threshold"],
            w["truncation.f_max"],
            m["truncation.f_max"],
            label("Error map of", margin=(0, 10)),
            w["truncation.map_mode"],
            w["case.residual"],
            pn.layout.Divider(),
            label("#### Noise study", margin=(0, 5)),
            w["noise.noise"],
            m["noise.noise"],
            label("Noise in", margin=(0, 10)),
            w["noise.target"],
            w["noise.frequency_dependent"],
            pn.Row(w["noise.rounds"], w["noise.seed"]),
            m["noise.rounds"],
            m["noise.seed"],
            pn.Row(w["noise.single_round"]),
            m["noise.single_round"],
            w["noise.percentile"],
            sizing_mode="stretch_width",
        )
