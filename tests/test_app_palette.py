"""The six hub terms' colours (issue 29: hub:x and hub:rz were two nearly equal blues) are
distinct to every reader: the smallest CIEDE2000 colour difference between two of them, for
normal vision and for simulated protanopia, deuteranopia and tritanopia.

Truth: the CIEDE2000 formula (Sharma, Wu and Dalal, Color Res. Appl. 30, 2005; checked on
their published pairs) and the colour-vision-deficiency model of Machado, Oliveira and
Fernandes (IEEE TVCG 15, 2009; severity 1.0, applied in linear sRGB).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from app.views.analysis_base import TERM_COLORS
from app.views.analysis_compare import CURVE_COLORS

#: Machado et al. 2009, severity 1.0 (linear RGB -> linear RGB).
CVD = {
    "normal vision": np.eye(3),
    "protanopia": np.array(
        [
            [0.152286, 1.052583, -0.204868],
            [0.114503, 0.786281, 0.099216],
            [-0.003882, -0.048116, 1.051998],
        ]
    ),
    "deuteranopia": np.array(
        [
            [0.367322, 0.860646, -0.227968],
            [0.280085, 0.672501, 0.047413],
            [-0.011820, 0.042940, 0.968881],
        ]
    ),
    "tritanopia": np.array(
        [
            [1.255528, -0.076749, -0.178779],
            [-0.078411, 0.930809, 0.147602],
            [0.004733, 0.691367, 0.303900],
        ]
    ),
}
#: Smallest difference between two terms' colours: clearly different colours for normal
#: vision, still told apart under each simulated deficiency.
MIN_NORMAL, MIN_CVD = 20.0, 10.0


def linear_rgb(color: str) -> np.ndarray:
    c = np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of a linear sRGB colour."""
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    t = m @ np.clip(rgb, 0.0, 1.0) / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def ciede2000(lab1, lab2) -> float:
    """CIEDE2000 colour difference (kL = kC = kH = 1)."""
    (L1, a1, b1), (L2, a2, b2) = lab1, lab2
    cbar = (np.hypot(a1, b1) + np.hypot(a2, b2)) / 2
    g = 0.5 * (1 - np.sqrt(cbar**7 / (cbar**7 + 25.0**7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1, c2 = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1 = np.degrees(np.arctan2(b1, a1p)) % 360
    h2 = np.degrees(np.arctan2(b2, a2p)) % 360
    dh = 0.0 if c1 * c2 == 0 else (h2 - h1 + 180) % 360 - 180
    dH = 2 * np.sqrt(c1 * c2) * np.sin(np.radians(dh / 2))
    lbar, cbarp = (L1 + L2) / 2, (c1 + c2) / 2
    if c1 * c2 == 0:
        hbar = h1 + h2
    elif abs(h1 - h2) <= 180:
        hbar = (h1 + h2) / 2
    else:
        hbar = (h1 + h2 + 360) / 2 if h1 + h2 < 360 else (h1 + h2 - 360) / 2
    t = (
        1
        - 0.17 * np.cos(np.radians(hbar - 30))
        + 0.24 * np.cos(np.radians(2 * hbar))
        + 0.32 * np.cos(np.radians(3 * hbar + 6))
        - 0.20 * np.cos(np.radians(4 * hbar - 63))
    )
    rc = 2 * np.sqrt(cbarp**7 / (cbarp**7 + 25.0**7))
    rt = -np.sin(np.radians(60 * np.exp(-(((hbar - 275) / 25) ** 2)))) * rc
    sl = 1 + 0.015 * (lbar - 50) ** 2 / np.sqrt(20 + (lbar - 50) ** 2)
    sc, sh = 1 + 0.045 * cbarp, 1 + 0.015 * cbarp * t
    dl, dc = (L2 - L1) / sl, (c2 - c1) / sc
    return float(np.sqrt(dl**2 + dc**2 + (dH / sh) ** 2 + rt * dc * (dH / sh)))


@pytest.mark.parametrize(
    "lab1, lab2, de",  # Sharma et al. 2005, table 1, pairs 1, 2 and 7
    [
        ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
        ((50.0, 3.1571, -77.2803), (50.0, 0.0, -82.7485), 2.8615),
        ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ],
)
def test_ciede2000_matches_the_published_pairs(lab1, lab2, de):
    assert ciede2000(lab1, lab2) == pytest.approx(de, abs=1e-4)


def smallest_difference(colors, vision: str) -> tuple[float, str, str]:
    labs = [lab(CVD[vision] @ linear_rgb(c)) for c in colors]
    return min(
        (ciede2000(labs[i], labs[j]), colors[i], colors[j])
        for i, j in itertools.combinations(range(len(colors)), 2)
    )


@pytest.mark.parametrize("vision", list(CVD))
def test_the_six_terms_are_told_apart(vision):
    assert len(set(TERM_COLORS)) == 6
    de, a, b = smallest_difference(TERM_COLORS, vision)
    assert de >= (MIN_NORMAL if vision == "normal vision" else MIN_CVD), (vision, a, b, de)


@pytest.mark.parametrize("vision", list(CVD))
def test_the_pins_are_told_apart_from_the_current_state(vision):
    de, a, b = smallest_difference(CURVE_COLORS, vision)
    assert de >= (MIN_NORMAL if vision == "normal vision" else MIN_CVD), (vision, a, b, de)


def test_the_former_palette_fails_the_measure():
    """The measure can fail: the palette of the issue (hub:x and hub:rz two blues)."""
    former = ("#1971c2", "#2b8a3e", "#e03131", "#f08c00", "#7048e8", "#0c8599")
    assert smallest_difference(former, "normal vision")[0] < MIN_NORMAL
    assert smallest_difference(former, "deuteranopia")[0] < MIN_CVD
