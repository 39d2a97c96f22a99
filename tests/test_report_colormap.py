"""The truncation map's colour scale and threshold contour (app.report.colormap)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_hex, to_rgb

from app.report import ErrorColorScale, ReportError, contour_columns, threshold_contour
from app.report.colormap import ABOVE_COLOR, BELOW_PALETTE, LINE_STYLES, relative_luminance


def test_colours_split_at_the_threshold():
    s = ErrorColorScale(20.0)
    e = np.array([0.0, 5.0, 19.0, 19.999999, 20.0, 20.000001, 50.0, 1e4])
    c = s.colors(e)
    assert list(c[:4]) != [ABOVE_COLOR] * 4
    assert all(x in BELOW_PALETTE for x in c[:4])
    assert list(c[4:]) == [ABOVE_COLOR] * 4
    assert c[0] == BELOW_PALETTE[0] and c[3] == BELOW_PALETTE[-1]
    assert s.at_or_above(e).tolist() == [False] * 4 + [True] * 4


def test_below_scale_is_sequential_and_above_stands_apart():
    lum = [relative_luminance(c) for c in BELOW_PALETTE]
    assert all(a > b for a, b in zip(lum, lum[1:], strict=False)), "pale to dark"
    above = np.array(to_rgb(ABOVE_COLOR))
    # the red is far from every blue of the scale (RGB distance), including the darkest
    dist = [np.linalg.norm(above - np.array(to_rgb(c))) for c in BELOW_PALETTE]
    assert min(dist) > 0.6
    # red has more red than blue, every scale colour more blue than red
    assert above[0] > above[2]
    assert all(to_rgb(c)[2] >= to_rgb(c)[0] for c in BELOW_PALETTE)


def test_matplotlib_mapping_equals_the_colours():
    s = ErrorColorScale(17.5)
    cmap, norm = s.matplotlib()
    e = np.concatenate([np.linspace(-1, 40, 4001), [17.5, np.nextafter(17.5, 0)]])
    mpl = [to_hex(c) for c in cmap(norm(e))]
    assert mpl == list(s.colors(e))


def test_bokeh_mapper_puts_the_threshold_above():
    s = ErrorColorScale(20.0)
    m = s.bokeh_mapper()
    assert m.high < 20.0 and np.nextafter(m.high, np.inf) == 20.0
    assert m.high_color == ABOVE_COLOR and list(m.palette) == list(BELOW_PALETTE)
    assert m.low == 0.0


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan"), float("inf"), True, "20"])
def test_scale_refuses_bad_threshold(bad):
    with pytest.raises(ReportError, match="threshold must be a positive number"):
        ErrorColorScale(bad)


def test_line_styles_stand_out_on_pale_dark_and_red():
    for colour, _, _, halo in LINE_STYLES.values():
        # line or halo differs strongly in luminance from each background
        for bg in (BELOW_PALETTE[0], BELOW_PALETTE[-1], ABOVE_COLOR):
            contrast = max(
                abs(relative_luminance(colour) - relative_luminance(bg)),
                abs(relative_luminance(halo) - relative_luminance(bg)),
            )
            assert contrast > 0.25, (colour, bg)


def test_contour_of_a_plane_is_its_exact_line():
    # error = 2 f + 0.5 N: the 100 contour is the line N = 200 - 4 f, exact under linear
    # interpolation
    f = np.linspace(10.0, 60.0, 51)
    n = np.arange(10.0, 401.0, 10.0)
    err = 2 * f[None, :] + 0.5 * n[:, None]
    lines = threshold_contour(f, n, err, 100.0)
    assert len(lines) == 1
    pts = lines[0]
    np.testing.assert_allclose(2 * pts[:, 0] + 0.5 * pts[:, 1], 100.0, rtol=0, atol=1e-9)
    # it runs from the bottom edge (N = 10, f = 47.5) to the left edge (f = 10, N = 160)
    ends = {tuple(np.round(pts[0], 9)), tuple(np.round(pts[-1], 9))}
    assert ends == {(47.5, 10.0), (10.0, 160.0)}


def test_contour_of_a_cone_is_a_closed_circle():
    x = np.linspace(0.0, 100.0, 201)
    y = np.linspace(0.0, 400.0, 401)
    xx, yy = np.meshgrid(x, y)
    r = np.hypot(xx - 50.0, (yy - 200.0) / 4)  # circle of radius 20 in (x, y / 4)
    lines = threshold_contour(x, y, r, 20.0)
    assert len(lines) == 1
    pts = lines[0]
    np.testing.assert_array_equal(pts[0], pts[-1])  # closed
    rad = np.hypot(pts[:, 0] - 50.0, (pts[:, 1] - 200.0) / 4)
    np.testing.assert_allclose(rad, 20.0, atol=0.05)
    area = 0.5 * abs(np.sum(pts[:-1, 0] * pts[1:, 1] - pts[1:, 0] * pts[:-1, 1])) / 4
    assert area == pytest.approx(np.pi * 20.0**2, rel=2e-3)


def test_contour_empty_when_not_crossed_and_split_by_gaps():
    x, y = np.arange(5.0), np.arange(4.0)
    assert threshold_contour(x, y, np.full((4, 5), 3.0), 20.0) == []
    z = np.tile(np.array([0.0, 30.0, np.nan, 0.0, 30.0]), (4, 1))
    lines = threshold_contour(x, y, z, 20.0)
    # two separate vertical segments, at x = 2/3 and x = 3 + 2/3; none across the gap
    xs = sorted(round(float(ln[:, 0].mean()), 9) for ln in lines)
    assert xs == [round(2 / 3, 9), round(3 + 2 / 3, 9)]
    cols = contour_columns(lines)
    assert len(cols["xs"]) == len(cols["ys"]) == 2


def test_contour_refuses_bad_grids():
    with pytest.raises(ReportError, match="ascending"):
        threshold_contour([1, 1, 2], [1, 2], np.zeros((2, 3)), 1.0)
    with pytest.raises(ReportError, match="expected \\(n_y, n_x\\) = \\(2, 3\\)"):
        threshold_contour([1, 2, 3], [1, 2], np.zeros((3, 2)), 1.0)


def test_log_rows_put_each_count_where_a_log_axis_shows_it():
    from app.report.colormap import log_rows

    n = np.arange(10.0, 400.0, 10.0)
    err = np.repeat(n[:, None], 3, axis=1)  # each row holds its own N
    low, high, img = log_rows(n, err, 512)
    assert (low, high) == (5.0, 395.0)
    # row i covers [e_i, e_i+1] of a log-uniform partition: its value is the N whose cell
    # [N - 5, N + 5] holds the row's geometric centre
    edges = np.exp(np.linspace(np.log(5.0), np.log(395.0), 513))
    mid = np.sqrt(edges[:-1] * edges[1:])
    expected = 10.0 * np.clip(np.round(mid / 10.0), 1, 39)
    np.testing.assert_array_equal(img[:, 0], expected)
    # low counts get more rows than high ones (a log axis spreads them)
    rows_per_n = {v: int(np.sum(img[:, 0] == v)) for v in (10.0, 390.0)}
    assert rows_per_n[10.0] > 10 * rows_per_n[390.0] > 0
    with pytest.raises(ReportError, match="uniformly spaced"):
        log_rows([10, 20, 40], np.zeros((3, 2)))
