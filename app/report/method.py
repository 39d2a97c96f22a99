"""The method behind the dashboard, its equations and the thesis they come from.

Shared by the report (HTML and PDF) and the help page; equation numbers are the thesis'.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["THESIS", "Equation", "EQUATIONS", "METHOD_PARAGRAPHS", "UNITS"]

#: The full reference of the method.
THESIS = (
    'J. Rosholm and M. Westers, "Assembly of a tire and a vehicle model to predict '
    'vibrations at the bushings", MSc thesis, Chalmers University of Technology, 2018'
)


@dataclass(frozen=True)
class Equation:
    """One equation: thesis number, name, matplotlib mathtext, plain text and meaning."""

    number: str
    name: str
    mathtext: str
    plain: str
    meaning: str


EQUATIONS: tuple[Equation, ...] = (
    Equation(
        "2.44",
        "Receptance coupling (Frequency Based Substructuring)",
        r"$\mathbf{Y}^* = \mathrm{diag}(\mathbf{Y}^A, \mathbf{Y}^E)"
        r" - \mathbf{C}\,(\mathbf{Y}_{jj}^A + \mathbf{Y}_{jj}^E)^{-1}\,\mathbf{R},\quad"
        r"\mathbf{C} = [\mathbf{Y}_{aj}^A;\ \mathbf{Y}_{jj}^A;\ -\mathbf{Y}_{ej}^E],\ "
        r"\mathbf{R} = [\mathbf{Y}_{ja}^A,\ \mathbf{Y}_{jj}^A,\ -\mathbf{Y}_{je}^E]$",
        "Y* = diag(Y^A, Y^E) - [Y_aj^A; Y_jj^A; -Y_ej^E] (Y_jj^A + Y_jj^E)^-1 "
        "[Y_ja^A, Y_jj^A, -Y_je^E]",
        "The coupled mobility of tire A and chassis E joined rigidly at the hub DOFs j: one "
        "inversion of the size of the interface (6 x 6, or 5 x 5 with the spin released). "
        "No reciprocity is assumed (the rolling tire is not reciprocal).",
    ),
    Equation(
        "4.1",
        "Bushing response to the road wave",
        r"$\mathbf{v}_e^* = \mathbf{Y}_{ej}^E\,(\mathbf{Y}_{jj}^A + \mathbf{Y}_{jj}^E)^{-1}"
        r"\,\mathbf{Y}_{ja}^A\mathbf{F}_a$",
        "v_e* = Y_ej^E (Y_jj^A + Y_jj^E)^-1 Y_ja^A F_a",
        "Velocity at the bushing DOFs e. Y_ja^A F_a is the free hub velocity of the tire "
        "rolled over a road wave of 1 m amplitude, Y_jj^A the tire's hub mobility (modal "
        "sum of N modes), Y_jj^E and Y_ej^E the chassis mobilities at the spindle and from "
        "the spindle to the bushing.",
    ),
    Equation(
        "5.1",
        "Floating-band error of a truncated response",
        r"$\epsilon = \sum_{\omega \in B} \left|\,|v_T(\omega)|^2 - |v_M(\omega)|^2\right|"
        r"\ /\ \sum_{\omega \in B} |v_T(\omega)|^2$",
        "eps = sum_B | |v_T|^2 - |v_M|^2 | / sum_B |v_T|^2",
        "Power mismatch of the modified response v_M (N modes, or a noisy one) against the "
        "true response v_T (all modes) in a band B of 12 Hz that floats in 1 Hz steps; the "
        "error is mapped to the band's centre frequency. 0.2 = 20 %.",
    ),
    Equation(
        "5.2",
        "Noise in the tire",
        r"$\mathbf{v}_e^* = \mathbf{Y}_{ej}^E\,[\mathbf{S}\circ\mathbf{Y}_{jj}^A"
        r" + \mathbf{Y}_{jj}^E]^{-1}\,\mathbf{S}\circ(\mathbf{Y}_{ja}^A\mathbf{F}_a)$",
        "v_e* = Y_ej^E [S o Y_jj^A + Y_jj^E]^-1 S o (Y_ja^A F_a)",
        "S o Y: every element of Y multiplied by its own factor, uniform in [1 - p, 1 + p].",
    ),
    Equation(
        "5.3",
        "Noise in the chassis",
        r"$\mathbf{v}_e^* = \mathbf{S}\circ\mathbf{Y}_{ej}^E\,[\mathbf{Y}_{jj}^A"
        r" + \mathbf{S}\circ\mathbf{Y}_{jj}^E]^{-1}\,\mathbf{Y}_{ja}^A\mathbf{F}_a$",
        "v_e* = S o Y_ej^E [Y_jj^A + S o Y_jj^E]^-1 Y_ja^A F_a",
        "The chassis mobilities get the factors, the tire is exact.",
    ),
    Equation(
        "5.4",
        "Noise in tire and chassis",
        r"$\mathbf{v}_e^* = \mathbf{S}\circ\mathbf{Y}_{ej}^E\,[\mathbf{S}\circ\mathbf{Y}_{jj}^A"
        r" + \mathbf{S}\circ\mathbf{Y}_{jj}^E]^{-1}\,\mathbf{S}\circ(\mathbf{Y}_{ja}^A"
        r"\mathbf{F}_a)$",
        "v_e* = S o Y_ej^E [S o Y_jj^A + S o Y_jj^E]^-1 S o (Y_ja^A F_a)",
        "Each matrix gets its own independent factors. The band is the minimum and maximum "
        "of |v_e*| over R rounds at every line (the thesis used R = 10,000), with "
        "percentiles; one set of factors per round shifts whole curves, a new set at every "
        "line imitates measurement noise.",
    ),
)

METHOD_PARAGRAPHS: tuple[str, ...] = (
    "The tire (subsystem A, a modal model of a rolling tire with complex modes, in +/- "
    "pairs) and the rear-corner chassis (subsystem E, an FRF model) are joined at the six "
    "hub DOFs by Frequency Based Substructuring (receptance coupling, eq. 2.44). The road "
    "is a wave of one wavelength per harmonic case rolled over at 30-120 km/h, so each "
    "case excites a band f = v / lambda that spans a factor four; the tire is evaluated "
    "along that speed line. The response at the bushing follows from eq. 4.1.",
    "Truncation study (thesis 5.1): the tire's modal sum is cut after N modes (lowest "
    "first) and the response compared with the all-modes response by the floating-band "
    "error of eq. 5.1. The suggested N is the smallest from which the error stays below "
    "the threshold at all centres up to f_max (thesis table 5.1).",
    "Noise study (thesis 5.2): the FRFs of one or both subsystems are scaled element by "
    "element by random factors (eqs. 5.2-5.4) and the coupling repeated R times; the "
    "corridor shows how far measurement or model errors can move the prediction.",
)

#: Units of the levels shown.
UNITS: tuple[str, ...] = (
    "Levels: 20 log10 |v| in dB re 1 (m/s)/m for translations and re 1 (rad/s)/m for "
    "rotations: the tire's patch input is a road wave of 1 m amplitude.",
    "Chassis mobility: dB re 1 (m/s)/N (rad/(s N m) for rotations). Frequency in Hz, "
    "speed in km/h, errors in % (eq. 5.1 times 100).",
)
