"""The band's status line (issue 29): a convergence measure that raising R can meet, and a
band that was computed before said so.

The measure (``ScatterBand.percentile_confidence_db``) is the 95 % confidence half-width of the
central band's edges from order statistics. Truth: independent replications (other seeds)
against a band of many more rounds, whose percentiles stand for the true ones; and the
``1 / sqrt(R)`` law of the binomial rank. The extreme edges (minimum and maximum over the
rounds) that the line judged before do not settle: shown here too.
"""

from __future__ import annotations

import numpy as np
import pytest

from app import compute
from app.runtime import bands
from fbs_core.studies.scatter import EDGES_JUDGED_WITHIN_DB
from fbs_core.vocabulary import magnitude_db

H, N = 1, 50  # harmonic 1: 78 lines, the quickest band


def _band(rounds: int, seed: int):
    return compute.band(H, N, "6dof", 10.0, "both", False, rounds, seed)


@pytest.fixture(scope="module")
def truth():
    """A band of 40,000 rounds: its percentiles stand for the true quantiles (their own
    confidence half-width is about a sixth of a 1,000-round band's)."""
    return _band(40_000, 999)


def test_the_confidence_intervals_cover_the_true_edges(truth):
    rounds, seeds = 1000, range(20)
    q = list(np.asarray(truth.q, float))
    ref = magnitude_db(np.abs(truth.reference))
    keep = ref >= ref.max(axis=0) - EDGES_JUDGED_WITHIN_DB
    hits, total = 0, 0
    for seed in seeds:
        b = _band(rounds, seed)
        for edge in (5.0, 95.0):
            true = magnitude_db(truth.percentiles[q.index(edge)])
            low, high = b.percentile_interval_db(edge)
            inside = (low <= true) & (true <= high)
            hits += int(inside[keep].sum())
            total += int(keep.sum())
    coverage = hits / total
    # 95 % intervals: about 95 % of (seed, line, DOF, edge) cover the truth (the lines of
    # one band are correlated: a loose window)
    assert 0.85 <= coverage <= 0.995, coverage


def _half_widths(b, edge=5.0):
    low, high = b.percentile_interval_db(edge)
    return (high - low) / 2


def test_four_times_the_rounds_halve_the_intervals():
    a, b = _half_widths(_band(2000, 3)), _half_widths(_band(8000, 3))
    ratio = float(np.median(a / b))  # the law per line; the largest line is noisier
    assert 1.6 <= ratio <= 2.5, ratio
    assert _band(8000, 3).percentile_confidence_db() < _band(2000, 3).percentile_confidence_db()


def test_the_extreme_edges_do_not_settle():
    """Why the line no longer judges the band by its minimum and maximum: their change over
    the last half of the rounds does not fall as rounds are added."""
    a = _band(1000, 3).convergence.step_change_db[-1]
    b = _band(4000, 3).convergence.step_change_db[-1]
    assert b > 0.5 * a, (a, b)


def test_the_line_says_what_it_measures_and_how_long_it_took():
    res = _band(1000, 5)
    key = compute.band_key(H, N, "6dof", 10.0, "both", False, 1000, 5)
    when = compute.band_computed(key)
    assert when is not None and when.seconds is not None and when.seconds > 0
    # asked just before it was ready: computed for this request
    fresh = bands.done_text(res, 2.0, key, now=when.ready + 0.01)
    assert fresh.startswith("1,000 rounds in 2.00 s") and "computed before" not in fresh
    conf = res.percentile_confidence_db()
    assert f"5-95 % band edges within ±{conf:.2f} dB (95 % confidence" in fresh
    assert "within 30 dB of the peak" in fresh
    # asked long after: a band computed before says so, with the time it took then
    cached = bands.done_text(res, 0.001, key, now=when.ready + 60.0)
    assert f"1,000 rounds computed before, in {when.seconds:.2f} s" in cached
    assert "in 0.00 s" not in cached
