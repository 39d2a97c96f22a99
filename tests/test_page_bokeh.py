"""Bokeh helpers of app.report: title block models, presentation style, error-map layers."""

from __future__ import annotations

import numpy as np
import pytest
from bokeh.models import SaveTool
from bokeh.plotting import figure
from test_report_titles import snap

from app.page.bokeh import STYLES, ErrorMapLayers, TitleBlockModels, style_figure, wrap_line
from app.report import file_stem, threshold_contour, title_block


def _words(lines) -> list[str]:
    """The words of title-block lines (wrapped or joined with ' | ': the same words)."""
    return [w for w in " ".join(lines).split() if w != "|"]


def _px(size: str) -> float:
    return float(size[:-2]) * (4 / 3 if size.endswith("pt") else 1.0)


def test_title_block_models_show_the_block_and_name_the_saved_file():
    fig = figure(tools="pan,save")
    s = snap(url="http://localhost:5006/main?h=4")
    tb = title_block(s, "scatter-band")
    tbm = TitleBlockModels(fig, lines=1 + len(tb.lines))  # room for every line
    tbm.update(tb, file_stem(s, "scatter-band"))
    assert tbm.heading.text == tb.what
    shown = [t.text for t in tbm.titles if t.visible]
    # a long line may be wrapped over two models (issue 29): every word, in order
    assert _words(shown) == _words(tb.lines)
    assert fig.select_one(SaveTool).filename == file_stem(s, "scatter-band")
    # the heading is outermost, then the lines in order towards the plot
    above = [r for r in fig.above if r in (tbm.heading, *tbm.titles)]
    assert above[-1] is tbm.heading and above[0] is tbm.titles[-1]
    short = title_block(s, "eigenfrequency")
    tbm.update(short)
    shown = [t.text for t in tbm.titles if t.visible]
    assert _words(shown) == _words(short.lines)
    # fewer models than lines (a live plot's compact block): nothing is lost, the lines
    # beyond the count are joined into the last one
    small = TitleBlockModels(figure(tools="save"), lines=len(tb.lines))
    small.update(tb)
    shown = [t.text for t in small.titles if t.visible]
    assert _words(shown) == _words(tb.lines)


@pytest.mark.parametrize("mode", ["normal", "present"])
def test_style_moves_legends_outside_and_sizes_type(mode):
    fig = figure()
    fig.line([0, 1], [0, 1], legend_label="a")
    fig.line([0, 1], [1, 0], legend_label="b")
    style_figure(fig, mode)
    leg = fig.legend[0]
    assert leg not in fig.center and leg in fig.right
    assert fig.xaxis[0].major_label_text_font_size == STYLES[mode]["tick"]
    assert leg.label_text_font_size == STYLES[mode]["legend"]
    if mode == "present":
        assert _px(STYLES[mode]["tick"]) >= 14 and _px(STYLES[mode]["legend"]) >= 16  # 12 pt
    with pytest.raises(ValueError, match="allowed: normal, present"):
        style_figure(fig, "huge")


def test_error_map_layers_follow_threshold_and_map():
    fig = figure()
    f = np.linspace(10.0, 60.0, 51)
    n = np.arange(10.0, 401.0, 10.0)
    err = 2 * f[None, :] + 0.5 * n[:, None]
    layers = ErrorMapLayers(fig, 20.0)
    layers.update(f, n, err, 100.0)
    assert layers.mapper.high < 100.0 and np.nextafter(layers.mapper.high, np.inf) == 100.0
    (line,) = threshold_contour(f, n, err, 100.0)
    np.testing.assert_array_equal(layers.contour.data["xs"][0], line[:, 0])
    layers.update(f, n, err, 1e6)  # not crossed: no contour
    assert layers.contour.data["xs"] == []


@pytest.mark.parametrize(
    "text",
    [
        "a" * 90 + "&",  # a piece longer than the width, then its separator at the end
        "&" * 200,
        "x | " * 40,
        " | ".join(["k=" + "v" * 70 + "&" + "w" * 70] * 3),
        "pins=" + "~".join(["p" * 30] * 9) + " | link: /main?" + "&".join(["key=val"] * 30),
    ],
)
def test_wrap_line_ends_and_keeps_every_line_within_the_width(text):
    # the vehicle scope's title block once recursed without end on a piece that ended in
    # its separator (the page's draws failed with RecursionError)
    rng = np.random.default_rng(len(text))
    for width in (8, 40, 77):
        lines = wrap_line(text, width)
        assert all(len(line) <= width for line in lines)
        # nothing is lost: the characters other than blanks come back in order
        assert "".join(lines).replace(" ", "") == text.replace(" ", "")
    alphabet = list("ab &|~")
    for _ in range(200):
        t = "".join(rng.choice(alphabet, size=int(rng.integers(0, 300))))
        lines = wrap_line(t, 20)
        assert all(len(line) <= 20 for line in lines)
        assert "".join(lines).replace(" ", "") == t.replace(" ", "")
