"""Static plots of a snapshot with matplotlib (no browser, no pyplot state).

Each ``draw_*`` returns ``draw(fig, rect)``, which adds its axes inside
``rect = (left, bottom, width, height)`` (figure fraction) with the legend below the axes,
outside the data. :func:`standalone` puts a title block above one plot (a saved image says
what it shows); :func:`render` writes a figure as SVG, PNG or PDF bytes.

Figures are built from :class:`matplotlib.figure.Figure` directly (no pyplot, so no global
figure registry); rendering takes a lock because the SVG/PDF font settings are read from
matplotlib's global rcParams.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import matplotlib
import numpy as np
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from numpy.typing import ArrayLike

from fbs_core.units import frf_unit, output_kind
from fbs_core.vocabulary import magnitude_db, percent

from .colormap import LINE_STYLES, ErrorColorScale, threshold_contour
from .data import ReportData, present
from .titles import TitleBlock

#: A plot's region of a figure: ``(left, bottom, width, height)`` in figure fraction.
type Rect = tuple[float, float, float, float]
#: What every ``draw_*`` returns: ``draw(fig, rect)`` adds the plot's axes inside ``rect``.
type Draw = Callable[[Figure, Rect], None]


@dataclass(frozen=True)
class FigureBlock:
    """A plot: its title block and a function drawing it into a matplotlib figure region.

    ``draw(fig, rect)`` adds axes inside ``rect = (left, bottom, width, height)`` (figure
    fraction), legends included; ``aspect`` is the height / width ratio it wants.
    """

    key: str
    title: TitleBlock
    draw: Draw
    aspect: float = 0.55
    stem: str = ""


__all__ = [
    "COLORS",
    "level_unit",
    "draw_coupled",
    "draw_truncation",
    "draw_band",
    "draw_eigen",
    "draw_curves",
    "draw_strip",
    "draw_title_block",
    "standalone",
    "render",
]

COLORS = {
    "reference": "#1f2937",
    "truncated": "#d9480f",
    "band": "#a5d8ff",
    "percentile": "#4dabf7",
    "round": "#e8590c",
}
_SPEED_COLORS = ("#74c0fc", "#1c7ed6", "#0b3d91")
_RENDER_LOCK = threading.Lock()

#: The ``gid`` of a text meant as mathtext (the method's equations). Every other text of a
#: report figure is shown as written (see :func:`literal_text`).
MATH_GID = "mathtext"


def drawing_settings() -> Any:
    """matplotlib's settings under which every report figure is saved: no LaTeX run on
    any text, glyphs as paths in SVG, fonts embedded as TrueType in PDF."""
    return matplotlib.rc_context({"text.usetex": False, "svg.fonttype": "path", "pdf.fonttype": 42})


def literal_text(fig: Figure) -> Figure:
    """Every text of ``fig`` but the equations (:data:`MATH_GID`) and the axes' own tick
    labels shown as written (``parse_math`` off), and ``fig`` returned.

    File names, DOF labels and case names come from users: matplotlib would parse a
    ``$...$`` in them as mathtext (an unknown command raises ValueError, a deep nest a
    RecursionError, ``$x$`` silently becomes an italic x). Tick labels and offsets are
    written by matplotlib's formatters (no user text) and keep their mathtext (``10^2``).
    Calling it again changes nothing.
    """
    own: set[int] = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            own.add(id(axis.offsetText))
            for tick in (*axis.get_major_ticks(), *axis.get_minor_ticks()):
                own.update((id(tick.label1), id(tick.label2)))
    for t in fig.findobj(Text):
        if t.get_gid() != MATH_GID and id(t) not in own:
            t.set_parse_math(False)
    return fig


#: Font sizes (pt) of tick labels, axis labels and legends.
TICK_PT, LABEL_PT, LEGEND_PT = 9.0, 10.0, 9.0
_DASH: dict[str, Any] = {"solid": "-", "dashed": (0, (6, 3)), "dotted": (0, (1.5, 2.5))}


def level_unit(dof: str) -> str:
    """Unit of a bushing velocity level per road amplitude (``bushing:rz`` -> rad/s)."""
    d = dof.split(":")[-1]
    return f"dB re 1 {frf_unit(output_kind(f'bushing:{d}'), 'road', 'mobility')}"


def _axes(fig: Figure, rect: Rect, legend_rows: int = 1, right: float = 0.0) -> Axes:
    """Axes inside ``rect`` leaving room for tick labels and a legend below."""
    left, bottom, width, height = rect
    h_in = fig.get_figheight() * height
    w_in = fig.get_figwidth() * width
    pad_l, pad_r = 0.75 / w_in, (0.1 + right) / w_in
    pad_b = (0.55 + 0.24 * legend_rows) / h_in
    pad_t = 0.08 / h_in
    ax = fig.add_axes(
        (
            left + pad_l * width,
            bottom + pad_b * height,
            width * (1 - pad_l - pad_r),
            height * (1 - pad_b - pad_t),
        )
    )
    ax.tick_params(labelsize=TICK_PT)
    ax.grid(True, color="#dee2e6", linewidth=0.6)
    return ax


def _legend_below(ax: Axes, handles: list[Any], rect: Rect, ncol: int = 3) -> None:
    """The legend under the axes, at the bottom of the plot's region (outside the data)."""
    left, bottom, width, _ = rect
    fig: Any = ax.figure  # no overload of the stubs of Figure.legend matches this call
    fig.legend(
        handles=handles,
        loc="lower center",
        bbox_to_anchor=(left + width / 2, bottom + 0.02 / fig.get_figheight()),
        bbox_transform=fig.transFigure,
        ncol=ncol,
        fontsize=LEGEND_PT,
        frameon=False,
        handlelength=2.6,
    )


def _labels(ax: Axes, x: str, y: str) -> None:
    ax.set_xlabel(x, fontsize=LABEL_PT)
    ax.set_ylabel(y, fontsize=LABEL_PT)


def draw_coupled(snap: ReportData) -> Draw:
    """Coupled response v_e* (eq. 4.1) in dB: all modes and N modes."""
    dof, n = snap.response_dof, snap.settings["n_modes"]

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect)
        handles: list[Any] = []
        for frf, label, color, style in (
            (snap.reference, "all tire modes", COLORS["reference"], "-"),
            (snap.truncated, f"N = {n} modes", COLORS["truncated"], "--"),
        ):
            if frf is None:
                continue
            sel = frf.sel(outputs=dof)
            (ln,) = ax.plot(
                sel.freq, magnitude_db(sel.data[:, 0, 0]), style, color=color, lw=1.6, label=label
            )
            handles.append(ln)
        _labels(ax, "Frequency (Hz)", f"Level at {dof} ({level_unit(dof)})")
        _legend_below(ax, handles, rect, ncol=2)

    return draw


def _halo_line(ax: Axes, draw: Callable[..., Any], style_key: str, **kw: Any) -> Any:
    color, dash, width, halo = LINE_STYLES[style_key]
    effects = [patheffects.Stroke(linewidth=width + 2.5, foreground=halo), patheffects.Normal()]
    return draw(color=color, linestyle=_DASH[dash], linewidth=width, path_effects=effects, **kw)


def draw_truncation(snap: ReportData, n_suggested: int | None = None) -> Draw:
    """Error map (eq. 5.1) with the threshold scale, contour, chosen and suggested N."""
    m, s = present(snap.truncation, "truncation map"), snap.settings
    dof = snap.map_dof
    err = percent(np.asarray(m.max_error if dof is None else m.dof_error(dof), float))
    thr, fmax = float(s["threshold"]), float(s["f_max"])
    scale = ErrorColorScale(thr)

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect, legend_rows=2, right=0.9)
        ax.grid(False)
        cmap, norm = scale.matplotlib()
        x, y = np.asarray(m.centres, float), np.asarray(m.n_modes, float)
        mesh = ax.pcolormesh(
            x, y, np.ma.masked_invalid(err), cmap=cmap, norm=norm, shading="nearest"
        )
        mesh.set_rasterized(True)  # one image instead of a path per cell (SVG/PDF size)
        above = scale.at_or_above(err)
        if above.any():
            hatch = np.ma.masked_where(~above, np.ones_like(err))
            hatched = ax.pcolor(
                x,
                y,
                hatch,
                shading="nearest",
                facecolor="none",
                edgecolor=(1, 1, 1, 0.55),
                hatch="///",
                linewidth=0.0,
            )
            hatched.set_rasterized(True)
        handles: list[Any] = [Patch(facecolor=scale.above, edgecolor="white", hatch="///")]
        handles[0].set_label(f"error >= {thr:g} %")
        for line in threshold_contour(x, y, err, thr):
            xy = (line[:, 0], line[:, 1])
            _halo_line(ax, lambda xy=xy, **kw: ax.plot(*xy, **kw), "threshold contour")
        handles.append(_legend_line("threshold contour", f"{thr:g} % contour"))
        _halo_line(ax, lambda **kw: ax.axhline(s["n_modes"], **kw), "chosen N")
        handles.append(_legend_line("chosen N", f"chosen N = {s['n_modes']}"))
        if n_suggested:
            _halo_line(ax, lambda **kw: ax.axhline(n_suggested, **kw), "suggested N")
            handles.append(_legend_line("suggested N", f"suggested N = {n_suggested}"))
        if x[0] <= fmax <= x[-1]:
            _halo_line(ax, lambda **kw: ax.axvline(fmax, **kw), "f_max")
            handles.append(_legend_line("f_max", f"f_max = {fmax:g} Hz"))
        if s.get("n_axis") == "log":
            ax.set_yscale("log")
        ax.set_xlim(x[0] - 0.5 * (x[1] - x[0]), x[-1] + 0.5 * (x[1] - x[0]))
        _labels(ax, "Centre frequency (Hz)", "Retained modes N")
        cb = fig.colorbar(mesh, ax=ax, pad=0.02, fraction=0.05, extend="max")
        cb.set_label(f"Error (%), red: >= {thr:g} %", fontsize=LABEL_PT)
        cb.set_ticks(np.linspace(0.0, thr, 5).tolist())
        cb.ax.tick_params(labelsize=TICK_PT)
        _legend_below(ax, handles, rect, ncol=3)

    return draw


def _legend_line(key: str, label: str) -> Line2D:
    color, dash, width, halo = LINE_STYLES[key]
    effects = [patheffects.Stroke(linewidth=width + 2.5, foreground=halo), patheffects.Normal()]
    return Line2D(
        [], [], color=color, linestyle=_DASH[dash], linewidth=width, path_effects=effects,
        label=label,
    )  # fmt: skip


def draw_band(snap: ReportData) -> Draw:
    """Scatter band: min-max corridor, central percentile band, reference, one round."""
    b, s = present(snap.band, "scatter band"), snap.settings
    dof = snap.response_dof
    j = b.dofs.index(dof)
    w = s["percentile"]
    q = [float(v) for v in b.q]
    lo, hi = (100 - w) / 2, (100 + w) / 2

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect, legend_rows=2)
        f = np.asarray(b.freq, float)
        low, high = b.percentiles[q.index(lo), :, j], b.percentiles[q.index(hi), :, j]
        h = [
            ax.fill_between(
                f,
                magnitude_db(b.minimum[:, j]),
                magnitude_db(b.maximum[:, j]),
                color=COLORS["band"],
                lw=0,
                label=f"min-max over R = {s['rounds']:,} rounds",
            ),
            ax.fill_between(
                f,
                magnitude_db(low),
                magnitude_db(high),
                color=COLORS["percentile"],
                lw=0,
                label=f"{w} % central band ({lo:g}-{hi:g} %)",
            ),
        ]
        (r,) = ax.plot(f, magnitude_db(b.reference[:, j]), color=COLORS["reference"], lw=1.6)
        r.set_label("unpolluted reference")
        (one,) = ax.plot(
            f, magnitude_db(b.round(s["single_round"])[:, j]), color=COLORS["round"], lw=0.9
        )
        one.set_label(f"round #{s['single_round']}")
        _labels(ax, "Frequency (Hz)", f"Level at {dof} ({level_unit(dof)})")
        _legend_below(ax, [*h, r, one], rect, ncol=2)

    return draw


def draw_eigen(snap: ReportData) -> Draw:
    """Highest retained eigenfrequency versus N at the operating speeds (fig. 5.8)."""
    e, n = present(snap.eigen, "eigenfrequencies"), snap.settings["n_modes"]

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect)
        handles: list[Any] = []
        for v, row, c in zip(e.speeds, e.frequency, _SPEED_COLORS, strict=False):
            (ln,) = ax.plot(e.n_modes, row, color=c, lw=1.6, label=f"{v:g} km/h")
            handles.append(ln)
        handles.append(ax.axvline(n, color=COLORS["round"], lw=1.5, label=f"chosen N = {n}"))
        _labels(ax, "Retained modes N", "Highest retained eigenfrequency (Hz)")
        _legend_below(ax, handles, rect, ncol=4)

    return draw


_CURVE_COLORS = ("#1f2937", "#d9480f", "#1c7ed6", "#2f9e44", "#ae3ec9", "#f59f00")


def draw_curves(freq: ArrayLike, curves: Mapping[str, ArrayLike], y_label: str) -> Draw:
    """Curves in dB versus frequency (a section contributed by another view)."""

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect, legend_rows=1 + (len(curves) - 1) // 3)
        handles: list[Any] = []
        for i, (label, y) in enumerate(curves.items()):
            style = "-" if i < len(_CURVE_COLORS) else "--"
            (ln,) = ax.plot(
                freq, y, style, color=_CURVE_COLORS[i % len(_CURVE_COLORS)], lw=1.5, label=label
            )
            handles.append(ln)
        _labels(ax, "Frequency (Hz)", y_label)
        _legend_below(ax, handles, rect, ncol=min(3, max(1, len(handles))))

    return draw


def draw_lines(plot: Mapping[str, Any]) -> Draw:
    """Groups of lines over one x axis, one colour per group (the Campbell diagram's
    branches by direction and its order lines); the group ``plot["highlight"]`` thick and
    red, the group ``plot["muted"]`` dashed grey."""
    x = np.asarray(plot["x"], float)
    groups = dict(plot["groups"])

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect, legend_rows=1 + (len(groups) - 1) // 3)
        handles: list[Any] = []
        for i, (label, ys) in enumerate(groups.items()):
            color, lw, style = _CURVE_COLORS[i % len(_CURVE_COLORS)], 0.9, "-"
            if label == plot.get("highlight"):
                color, lw = "#c92a2a", 2.6
            elif label == plot.get("muted"):
                color, style = "#495057", "--"
            for k, y in enumerate(ys):
                (ln,) = ax.plot(x, y, style, color=color, lw=lw, label=label if k == 0 else None)
                if k == 0:
                    handles.append(ln)
        if plot.get("y_max") is not None:
            ax.set_ylim(0.0, float(plot["y_max"]))
        _labels(ax, str(plot.get("x_label", "")), str(plot.get("y_label", "")))
        _legend_below(ax, handles, rect, ncol=min(3, max(1, len(handles))))

    return draw


def draw_image(plot: Mapping[str, Any]) -> Draw:
    """A map ``z (n_x, n_y)`` over two axes with a colour bar (the speed map), and a line
    over it (the harmonic's line f = v / lambda) when given."""
    x, y = np.asarray(plot["x"], float), np.asarray(plot["y"], float)
    z = np.asarray(plot["z"], float)

    def draw(fig: Figure, rect: Rect) -> None:
        ax = _axes(fig, rect, legend_rows=0, right=1.0)
        mesh = ax.pcolormesh(x, y, z.T, shading="nearest", cmap="viridis", rasterized=True)
        if plot.get("line") is not None:
            lx, ly = plot["line"]
            ax.plot(lx, ly, "--", color="white", lw=1.6)
        ax.set_xlim(x.min(), x.max())
        ax.set_ylim(y.min(), y.max())
        _labels(ax, str(plot.get("x_label", "")), str(plot.get("y_label", "")))
        pos, w_in = ax.get_position(), fig.get_figwidth()
        cax = fig.add_axes((pos.x1 + 0.12 / w_in, pos.y0, 0.15 / w_in, pos.height))
        bar = fig.colorbar(mesh, cax=cax)
        bar.set_label(str(plot.get("z_label", "")), fontsize=TICK_PT)
        bar.ax.tick_params(labelsize=TICK_PT)

    return draw


def draw_strip(strip: Mapping[str, Any]) -> Draw:
    """A mode shape as a static strip: frames of one period side by side, each the
    deformed centre line over the undeformed one, with one crest of the dominant order
    (``strip``: ``frames`` as (x, z) pairs, ``rest`` (x, z), ``crest`` (x, z) per frame,
    ``labels`` per frame)."""
    frames = list(strip["frames"])
    rx, rz = (np.asarray(a, float) for a in strip["rest"])

    def draw(fig: Figure, rect: Rect) -> None:
        left, bottom, width, height = rect
        n = max(len(frames), 1)
        w = width / n
        lim = 1.25 * float(np.max(np.hypot(rx, rz))) if rx.size else 1.0
        for k, (x, z) in enumerate(frames):
            ax = fig.add_axes((left + k * w + 0.005, bottom + 0.08 * height, w - 0.01,
                               0.84 * height))  # fmt: skip
            ax.plot(np.r_[rx, rx[:1]], np.r_[rz, rz[:1]], "--", color="#adb5bd", lw=0.8)
            x, z = np.asarray(x, float), np.asarray(z, float)
            ax.plot(np.r_[x, x[:1]], np.r_[z, z[:1]], "-", color=_CURVE_COLORS[0], lw=1.4)
            cx, cz = strip["crest"][k]
            ax.plot([cx], [cz], "o", color="#c2255c", ms=5)
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(str(strip["labels"][k]), fontsize=8)

    return draw


def draw_title_block(fig: Figure, tb: TitleBlock, top: float, left: float = 0.03) -> float:
    """Write a title block from ``top`` (figure fraction) down; returns the bottom."""
    h_in = fig.get_figheight()
    y = top
    for k, line in enumerate((tb.what, *tb.lines)):
        size = 11.0 if k == 0 else 8.5
        y -= (size * 1.45 / 72) / h_in
        fig.text(left, y, line, fontsize=size, weight="bold" if k == 0 else "normal")
    return y - 0.06 / h_in


def standalone(block: FigureBlock, width_in: float = 9.0, title: bool = True) -> Figure:
    """One plot as its own figure, with its title block above it when ``title``."""
    lines = 1 + len(block.title.lines) if title else 0
    tb_in = (11.0 * 1.45 + 8.5 * 1.45 * (lines - 1)) / 72 + 0.15 if title else 0.0
    plot_in = width_in * block.aspect
    fig = Figure(figsize=(width_in, plot_in + tb_in))
    bottom = plot_in / (plot_in + tb_in)
    if title:
        draw_title_block(fig, block.title, 1.0)
    block.draw(fig, (0.0, 0.0, 1.0, bottom))
    return fig


def render(fig: Figure, fmt: str, dpi: float = 110) -> bytes:
    """The figure as ``svg``, ``png`` or ``pdf`` bytes (glyphs as paths in SVG, fonts
    embedded as TrueType in PDF, so text extracts and nothing is fetched)."""
    if fmt not in ("svg", "png", "pdf"):
        raise ValueError(f"unknown figure format {fmt!r}; allowed: svg, png, pdf")
    buf = io.BytesIO()
    meta = {"svg": {"Date": None}, "png": {}, "pdf": {"CreationDate": None}}[fmt]
    with _RENDER_LOCK, drawing_settings():
        literal_text(fig).savefig(buf, format=fmt, dpi=dpi, metadata=meta)
    return buf.getvalue()
