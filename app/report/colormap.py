"""Colour scale and threshold contour of the truncation error map (thesis figs. 5.3-5.7).

Below the threshold the error is drawn on a sequential light-to-dark blue scale (pale: small
error); at or above it in one contrasting red that no blue of the scale comes near, so that
19 % and 20 % at a 20 % threshold never look alike. The boundary itself is drawn as a contour
line of ``error == threshold`` (:func:`threshold_contour`), and lines drawn over the map
(chosen N, suggested N, f_max) use colours that stand out on both blue and red
(:data:`LINE_STYLES`). The same scale serves the live Bokeh map
(:meth:`ErrorColorScale.bokeh_mapper`) and the report's matplotlib figures
(:meth:`ErrorColorScale.matplotlib`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import contourpy
import numpy as np
from numpy.typing import ArrayLike

from .data import ReportError

if TYPE_CHECKING:
    from bokeh.models import LinearColorMapper
    from matplotlib.colors import BoundaryNorm, Colormap

__all__ = [
    "BELOW_PALETTE",
    "ABOVE_COLOR",
    "CONTOUR_COLOR",
    "LINE_STYLES",
    "ErrorColorScale",
    "threshold_contour",
    "contour_columns",
    "relative_luminance",
]

#: Sequential blues from pale (no error) to dark (just below the threshold): ColorBrewer
#: "Blues", 9 classes (Cynthia Brewer, colorbrewer2.org), lightness falling monotonically.
BELOW_PALETTE: tuple[str, ...] = (
    "#f7fbff",
    "#deebf7",
    "#c6dbef",
    "#9ecae1",
    "#6baed6",
    "#4292c6",
    "#2171b5",
    "#08519c",
    "#08306b",
)
#: Colour of errors at or above the threshold (a red: away from every blue of the scale,
#: and told from blue by the common colour-vision deficiencies).
ABOVE_COLOR = "#d62728"
#: Colour of the threshold contour line.
CONTOUR_COLOR = "#000000"
#: Lines over the map: legend label -> (colour, dash, width, halo colour). The plotting code
#: draws each line over a wider line in its halo colour, so that it stays visible on pale
#: blue, dark blue and red alike.
LINE_STYLES: dict[str, tuple[str, str, float, str]] = {
    "threshold contour": (CONTOUR_COLOR, "solid", 1.5, "#ffffff"),
    "chosen N": ("#f59f00", "solid", 3.0, "#000000"),
    "suggested N": ("#000000", "dashed", 2.0, "#ffffff"),
    "f_max": ("#000000", "dotted", 2.0, "#ffffff"),
}


def _rgb(color: str) -> np.ndarray:
    c = color.lstrip("#")
    if len(c) != 6:
        raise ReportError(f"colour must be '#rrggbb', got {color!r}")
    return np.array([int(c[i : i + 2], 16) / 255 for i in (0, 2, 4)])


def relative_luminance(color: str) -> float:
    """WCAG relative luminance of a ``#rrggbb`` colour (0 black .. 1 white)."""
    c = _rgb(color)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(lin @ np.array([0.2126, 0.7152, 0.0722]))


@dataclass(frozen=True)
class ErrorColorScale:
    """Error colours in percent: sequential below ``threshold``, one colour at or above.

    Parameters
    ----------
    threshold : float
        Error threshold in percent (> 0).
    palette : tuple of str
        Colours of ``[0, threshold)`` in equal steps, lightest first.
    above : str
        Colour of ``error >= threshold``.

    Examples
    --------
    >>> s = ErrorColorScale(20.0)
    >>> s.colors([0.0, 19.9, 20.0, 35.0]).tolist() == [BELOW_PALETTE[0], BELOW_PALETTE[-1],
    ...                                                 ABOVE_COLOR, ABOVE_COLOR]
    True
    """

    threshold: float
    palette: tuple[str, ...] = BELOW_PALETTE
    above: str = ABOVE_COLOR

    def __post_init__(self) -> None:
        t = self.threshold
        if isinstance(t, bool) or not isinstance(t, int | float) or not np.isfinite(t) or t <= 0:
            raise ReportError(f"threshold must be a positive number of percent, got {t!r}")
        if len(self.palette) < 2:
            raise ReportError("the palette needs at least two colours")
        if self.above in self.palette:
            raise ReportError(f"the above-threshold colour {self.above} is in the palette")
        object.__setattr__(self, "threshold", float(t))
        object.__setattr__(self, "palette", tuple(self.palette))

    @property
    def cap(self) -> float:
        """The largest value still below the threshold (the top of the sequential scale)."""
        return float(np.nextafter(self.threshold, -np.inf))

    def at_or_above(self, error: ArrayLike) -> np.ndarray:
        """Boolean mask of ``error >= threshold`` (NaN: False)."""
        e = np.asarray(error, float)
        with np.errstate(invalid="ignore"):
            return e >= self.threshold

    def colors(self, error: ArrayLike) -> np.ndarray:
        """The colour of each error value (``#rrggbb`` strings, same shape as ``error``).

        ``[0, threshold)`` is cut into ``len(palette)`` equal steps; negative values take the
        first colour; ``>= threshold`` takes :attr:`above`; NaN takes ``"#ffffff"``.
        """
        e = np.asarray(error, float)
        n = len(self.palette)
        with np.errstate(invalid="ignore"):
            idx = np.clip(np.floor(e / self.threshold * n), 0, n - 1)
        idx = np.where(np.isfinite(idx), idx, 0).astype(int)
        out = np.asarray(self.palette, dtype=object)[idx]
        out = np.where(self.at_or_above(e), self.above, out)
        return np.where(np.isnan(e), "#ffffff", out).astype(str)

    def bokeh_mapper(self, name: str | None = None) -> LinearColorMapper:
        """A Bokeh ``LinearColorMapper`` with the same mapping (``high_color`` = above).

        Bokeh maps values above ``high`` to ``high_color``; ``high`` is :attr:`cap`, so a
        value equal to the threshold is above it too.
        """
        from bokeh.models import LinearColorMapper

        return LinearColorMapper(
            palette=list(self.palette),
            low=0.0,
            high=self.cap,
            high_color=self.above,
            low_color=self.palette[0],
            nan_color="#ffffff",
            name=name,
        )

    def matplotlib(self) -> tuple[Colormap, BoundaryNorm]:
        """``(cmap, norm)`` for matplotlib: the same steps, :attr:`above` as the over colour."""
        from matplotlib.colors import BoundaryNorm, ListedColormap

        cmap = ListedColormap(list(self.palette)).with_extremes(
            over=self.above, under=self.palette[0], bad="#ffffff"
        )
        bounds = np.linspace(0.0, self.threshold, len(self.palette) + 1)
        return cmap, BoundaryNorm(bounds, cmap.N)


def threshold_contour(
    x: ArrayLike, y: ArrayLike, error: ArrayLike, threshold: float
) -> list[np.ndarray]:
    """Polylines of ``error == threshold`` over a grid (the map's threshold boundary).

    Linear interpolation on the grid cells (marching squares, :mod:`contourpy`); exact where
    the error varies linearly within a cell.

    Parameters
    ----------
    x : array_like, shape (n_x,)
        Ascending grid of the columns (e.g. centre frequencies in Hz).
    y : array_like, shape (n_y,)
        Ascending grid of the rows (e.g. retained modes N).
    error : array_like, shape (n_y, n_x)
        Values on the grid (NaN: no value; the contour stops there).
    threshold : float
        Level of the contour.

    Returns
    -------
    list of ndarray, each of shape (n_points, 2)
        ``(x, y)`` points of each polyline; a closed one repeats its first point at the end.
        Empty when the error does not cross the threshold.

    Raises
    ------
    ReportError
        For grids that are not ascending 1-D, or an error of another shape.
    """
    xs, ys = np.asarray(x, float), np.asarray(y, float)
    z = np.asarray(error, float)
    for name, g in (("x", xs), ("y", ys)):
        if g.ndim != 1 or g.size < 2 or np.any(np.diff(g) <= 0) or not np.all(np.isfinite(g)):
            raise ReportError(f"{name} must be an ascending 1-D grid of at least 2 points")
    if z.shape != (ys.size, xs.size):
        raise ReportError(f"error has shape {z.shape}, expected (n_y, n_x) = {(ys.size, xs.size)}")
    if not np.isfinite(threshold):
        raise ReportError(f"threshold must be finite, got {threshold!r}")
    mask = ~np.isfinite(z)
    zz = np.ma.array(np.where(mask, 0.0, z), mask=mask) if mask.any() else z
    gen = contourpy.contour_generator(xs, ys, zz, line_type=contourpy.LineType.Separate)
    return [np.asarray(line, float) for line in gen.lines(float(threshold)) if len(line) > 1]


def contour_columns(lines: list[np.ndarray]) -> dict[str, list[list[float]]]:
    """``{"xs": [...], "ys": [...]}`` of the polylines, the columns of a Bokeh multi_line."""
    return {
        "xs": [ln[:, 0].tolist() for ln in lines],
        "ys": [ln[:, 1].tolist() for ln in lines],
    }


def log_rows(
    n_modes: ArrayLike, error: ArrayLike, n_rows: int = 256
) -> tuple[float, float, np.ndarray]:
    """The map's rows resampled for a logarithmic N axis (an image is stretched linearly
    between its edges on screen, so its rows must be uniform in log N).

    Row ``i`` of the result is the map row whose cell ``[N - dN/2, N + dN/2]`` holds the
    centre of the log-uniform row ``i`` between the outer cell edges.

    Parameters
    ----------
    n_modes : array_like, shape (n_N,)
        Ascending, uniformly spaced retained-mode counts.
    error : array_like, shape (n_N, n_c)
    n_rows : int
        Rows of the resampled image.

    Returns
    -------
    low, high : float
        The outer cell edges (the image spans ``[low, high]`` on the N axis).
    image : ndarray, shape (n_rows, n_c)

    Raises
    ------
    ReportError
        For counts that are not ascending and uniform, a first cell edge at or below 0, or
        an error of another shape.
    """
    n = np.asarray(n_modes, float)
    z = np.asarray(error, float)
    if n.ndim != 1 or n.size < 2 or np.any(np.diff(n) <= 0):
        raise ReportError("n_modes must be ascending with at least 2 counts")
    step = np.diff(n)
    if not np.allclose(step, step[0]):
        raise ReportError("n_modes must be uniformly spaced (e.g. 10, 20, ..., 390)")
    if z.ndim != 2 or z.shape[0] != n.size:
        raise ReportError(f"error has shape {z.shape}, expected ({n.size}, n_c)")
    if n_rows < n.size:
        raise ReportError(f"n_rows must be at least the number of counts ({n.size})")
    low, high = n[0] - step[0] / 2, n[-1] + step[0] / 2
    if low <= 0:
        raise ReportError(f"the first cell edge {low:g} must be > 0 on a log axis")
    edges = np.geomspace(low, high, n_rows + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    idx = np.clip(np.floor((centres - low) / step[0]).astype(int), 0, n.size - 1)
    return float(low), float(high), z[idx]
