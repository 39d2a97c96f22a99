"""The control panel: widgets bound to the state parameters (:mod:`app.views.bind`).

Typed numbers are plain text fields read by :func:`app.views.typed.parse_number` (``1e5``,
``1.5``, ``5,5``): a text that is not a number of the field's kind, or a value outside the
parameter's bounds, is answered with a message under the field (and a notification) that
names the field and what it takes, and the field (and its slider) go back to the value in
force.
"""

from __future__ import annotations

import html

import panel as pn
import param
from panel.viewable import Viewer

import fbs_core

from ..runtime.draw import on_document, served_document
from ..state import MODE_COUNTS, VEHICLE_ROUNDS, DashboardState
from .bind import control
from .layout import font
from .live import LiveText
from .typed import NumberField, refusal

#: Typed numeric controls: key -> (label, with a slider).
_TYPED = {
    "truncation.threshold": ("Error threshold (%)", True),
    "truncation.f_max": ("Upper frequency for suggestion (Hz)", True),
    "noise.noise": ("Noise level p (%)", True),
    "noise.rounds": ("Rounds R", False),
    "noise.seed": ("Seed", False),
    "noise.single_round": ("Single round #", False),
    "plot.cursor1": ("Cursor 1 (Hz, 0: off)", False),
    "plot.cursor2": ("Cursor 2 (Hz, 0: off)", False),
}


def out_of_bounds(obj: param.Parameterized, name: str, value, label: str = "") -> str:
    """The message for ``value`` typed for ``obj.name`` ("" when the parameter takes it)."""
    return refusal(obj, name, str(value), label)


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
        self._fields: dict[str, NumberField] = {}
        self._messages: dict[str, pn.pane.HTML] = {}
        #: The harmonic's wavelength, speeds and band under its slider (once laid out).
        self.harmonic_info: LiveText | None = None

    @property
    def fields(self) -> dict[str, NumberField]:
        """The typed numbers by ``"<group>.<parameter>"`` (text field, slider, message)."""
        self.widgets()
        return self._fields

    @property
    def messages(self) -> dict[str, pn.pane.HTML]:
        """The message under each typed number."""
        self.widgets()
        return self._messages

    def _typed(self, key: str) -> NumberField:
        """A typed number of the state (a text field read here, and maybe a slider)."""
        group, name = key.split(".")
        label, slider = _TYPED[key]
        field = NumberField(
            obj=getattr(self.state, group),
            parameter=name,
            label=label,
            slider=slider,
            css_class="ctl-" + key.replace(".", "-"),
        )
        self._fields[key] = field
        self._messages[key] = field.message
        return field

    def widgets(self) -> dict[str, pn.widgets.Widget]:
        """The widgets by ``"<group>.<parameter>"`` (built once, reused by the layout); a
        typed number's widget is its text field (its slider: ``fields[key].bar``)."""
        if self._widgets is None:
            c, n, t = self.state.case, self.state.noise, self.state.truncation
            p = self.state.plot
            W = pn.widgets
            self._widgets = {
                "case.scope": control(
                    W.RadioButtonGroup,
                    c.param.scope,
                    name="Scope",
                    options={"Corner": "corner", "Vehicle": "vehicle"},
                ),
                "case.wheels": control(
                    W.CheckButtonGroup,
                    c.param.wheels,
                    name="Road input on the wheels",
                    options={"FL": "fl", "FR": "fr", "RL": "rl", "RR": "rr"},
                    to_widget=list,
                ),
                "case.tracks": control(W.RadioButtonGroup, c.param.tracks, name="Tracks"),
                "case.coherence": control(
                    W.FloatSlider, c.param.coherence, name="Coherence of the tracks"
                ),
                "case.point": control(W.Select, c.param.point, name="Response point"),
                "case.harmonic": control(
                    W.IntSlider, c.param.harmonic, name="Harmonic case", start=1, end=7, step=1
                ),
                # a plain slider over the counts (10 to 400 in steps of 10) that draws its own
                # label in the browser: one writer of what it shows
                "case.n_modes": control(
                    W.IntSlider,
                    c.param.n_modes,
                    name="Retained tire modes N",
                    start=MODE_COUNTS[0],
                    end=MODE_COUNTS[-1],
                    step=MODE_COUNTS[1] - MODE_COUNTS[0],
                ),
                "case.dof": control(
                    W.RadioButtonGroup, c.param.dof, name="Response DOF at the bushing"
                ),
                "case.coupling": control(W.RadioButtonGroup, c.param.coupling, name="Hub coupling"),
                "case.show_uncoupled": control(
                    W.Checkbox, c.param.show_uncoupled, name="Show uncoupled tire and chassis FRFs"
                ),
                "case.residual": control(
                    W.Checkbox,
                    c.param.residual,
                    name="Residual compensation (modes left out: quasi-static part)",
                ),
                "plot.overlay": control(
                    W.CheckButtonGroup, p.param.overlay, name="Overlay bushing DOFs", to_widget=list
                ),
                "plot.level_scale": control(
                    W.RadioButtonGroup, p.param.level_scale, name="Level axis"
                ),
                "plot.cursor1": self._typed("plot.cursor1").text,
                "plot.cursor2": self._typed("plot.cursor2").text,
                "plot.snap": control(
                    W.Checkbox, p.param.snap, name="Cursors snap to the nearest peak"
                ),
                "truncation.threshold": self._typed("truncation.threshold").text,
                "truncation.f_max": self._typed("truncation.f_max").text,
                "truncation.map_mode": control(
                    W.RadioButtonGroup, t.param.map_mode, name="Error map of"
                ),
                "noise.noise": self._typed("noise.noise").text,
                "noise.target": control(W.RadioButtonGroup, n.param.target, name="Noise in"),
                "noise.frequency_dependent": control(
                    W.Checkbox,
                    n.param.frequency_dependent,
                    name="Frequency-dependent noise (new S at every line)",
                ),
                "noise.rounds": self._typed("noise.rounds").text,
                "noise.seed": self._typed("noise.seed").text,
                "noise.single_round": self._typed("noise.single_round").text,
                "noise.percentile": control(
                    W.Select, n.param.percentile, name="Central percentile band (%)"
                ),
                "noise.first_order": control(
                    W.Checkbox,
                    n.param.first_order,
                    name="First-order band overlay (linearised, docs/corridor.md)",
                ),
            }
            for key, w in self._widgets.items():
                if key in self._fields:  # classed and quickened by its NumberField
                    continue
                w.css_classes = [*w.css_classes, "ctl-" + key.replace(".", "-")]
        return self._widgets

    def __panel__(self):
        w: dict[str, object] = {**self.widgets(), **self.fields}
        label = pn.pane.Markdown
        case = self.state.case
        # set in place on the page's draw queue: a pane bound to the harmonic re-sent its
        # whole model (new stylesheets: the document's model graph walked, ~45 ms on the
        # event loop per change, which held every session's draws back when 20 sessions
        # changed the harmonic at once: bench/load_test.py)
        info = self.harmonic_info = LiveText(
            _harmonic_html(case.harmonic),
            css_classes=["ctl-harmonic-info"],
            styles={"font-size": font("0.9em"), "color": "#343a40"},
            margin=(0, 12),
        )
        doc = served_document()

        def show() -> None:
            info.text = _harmonic_html(case.harmonic)  # the harmonic in force when drawn

        case.param.watch(lambda _e: on_document(doc, show), "harmonic")
        vehicle = case.param.scope.rx.pipe(lambda v: v == "vehicle")
        car = pn.Column(
            label(
                "The reference car, the tire on all four wheels; the rear wheels meet the "
                "road a wheelbase after the front ones",
                margin=(0, 10),
                styles={"font-size": "0.85em"},
            ),
            label("Road input on the wheels", margin=(0, 10)),
            w["case.wheels"],
            label("Right track against the left", margin=(0, 10)),
            w["case.tracks"],
            pn.Column(w["case.coherence"], visible=case.param.tracks.rx() == "coherence"),
            w["case.point"],
            visible=vehicle,
            css_classes=["ctl-vehicle"],
            sizing_mode="stretch_width",
        )
        rounds_note = label(
            f"Vehicle scope: the band starts at {VEHICLE_ROUNDS:,} rounds (a car's round "
            "solves the 24-DOF interface of four wheels: about 33x a corner's); the map and "
            "the band need tracks in phase or in anti-phase",
            margin=(0, 10),
            styles={"font-size": "0.85em"},
            visible=vehicle,
            css_classes=["ctl-vehicle-rounds"],
        )
        return pn.Column(
            label("#### Scope", margin=(0, 5)),
            w["case.scope"],
            car,
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
            label("#### Response plot", margin=(0, 5)),
            label("Overlay bushing DOFs (with N modes)", margin=(0, 10)),
            w["plot.overlay"],
            label("Level axis", margin=(0, 10)),
            w["plot.level_scale"],
            label("Cursors: type a frequency or click the plot", margin=(0, 10)),
            pn.Row(w["plot.cursor1"], w["plot.cursor2"], sizing_mode="stretch_width"),
            w["plot.snap"],
            pn.layout.Divider(),
            label("#### Truncation study", margin=(0, 5)),
            w["truncation.threshold"],
            w["truncation.f_max"],
            label("Error map of", margin=(0, 10)),
            w["truncation.map_mode"],
            w["case.residual"],
            pn.layout.Divider(),
            label("#### Noise study", margin=(0, 5)),
            w["noise.noise"],
            label("Noise in", margin=(0, 10)),
            w["noise.target"],
            w["noise.frequency_dependent"],
            rounds_note,
            w["noise.rounds"],
            w["noise.seed"],
            w["noise.single_round"],
            w["noise.percentile"],
            w["noise.first_order"],
            sizing_mode="stretch_width",
        )
