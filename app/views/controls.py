"""The control panel: widgets generated from the state parameters."""

from __future__ import annotations

import panel as pn
import param
from panel.viewable import Viewer

from ..panel_private import respond_at_once
from ..state import DashboardState


class Controls(Viewer):
    """All controls of the dashboard, grouped by concern."""

    state = param.ClassSelector(class_=DashboardState)

    def __init__(self, **params):
        super().__init__(**params)
        self._widgets: dict[str, pn.widgets.Widget] | None = None

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
                "truncation.threshold": W.EditableFloatSlider.from_param(
                    t.param.threshold, name="Error threshold (%)", format="0.0"
                ),
                "truncation.f_max": W.EditableFloatSlider.from_param(
                    t.param.f_max, name="Upper frequency for suggestion (Hz)", format="0"
                ),
                "truncation.map_mode": W.RadioButtonGroup.from_param(
                    t.param.map_mode, name="Error map of"
                ),
                "noise.noise": W.EditableFloatSlider.from_param(
                    n.param.noise, name="Noise level p (%)", format="0.0"
                ),
                "noise.target": W.RadioButtonGroup.from_param(n.param.target, name="Noise in"),
                "noise.frequency_dependent": W.Checkbox.from_param(
                    n.param.frequency_dependent,
                    name="Frequency-dependent noise (new S at every line)",
                ),
                "noise.rounds": W.IntInput.from_param(n.param.rounds, name="Rounds R", step=1000),
                "noise.seed": W.IntInput.from_param(n.param.seed, name="Seed"),
                "noise.single_round": W.IntInput.from_param(
                    n.param.single_round, name="Single round #"
                ),
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
        label = pn.pane.Markdown
        return pn.Column(
            label("#### Case", margin=(0, 5)),
            w["case.harmonic"],
            w["case.n_modes"],
            label("Response DOF at the bushing", margin=(0, 10)),
            w["case.dof"],
            label("Hub coupling: 6 DOFs (braked) / 5 DOFs (spin free)", margin=(0, 10)),
            w["case.coupling"],
            w["case.show_uncoupled"],
            pn.layout.Divider(),
            label("#### Truncation study", margin=(0, 5)),
            w["truncation.threshold"],
            w["truncation.f_max"],
            label("Error map of", margin=(0, 10)),
            w["truncation.map_mode"],
            pn.layout.Divider(),
            label("#### Noise study", margin=(0, 5)),
            w["noise.noise"],
            label("Noise in", margin=(0, 10)),
            w["noise.target"],
            w["noise.frequency_dependent"],
            pn.Row(w["noise.rounds"], w["noise.seed"]),
            pn.Row(w["noise.single_round"]),
            w["noise.percentile"],
            sizing_mode="stretch_width",
        )
