"""A long scatter band can be stopped between its chunks of lines (``cancel=``)."""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from fbs_core.errors import StudyCancelled


def test_cancel_is_asked_before_every_chunk_and_stops_the_study():
    f = fbs_core.harmonic(1).frequencies()
    rounds = 400
    per_line = 8 * 6 * rounds
    chunk = 10  # lines per chunk
    # chunks bounded by memory only: the default duration bound (0.1 s) would make their
    # number depend on the machine's load
    kw = dict(rounds=rounds, seed=3, max_chunk_bytes=per_line * chunk, max_chunk_seconds=None)
    asked = []
    band = fbs_core.scatter_band(1, cancel=lambda: asked.append(1) and False, **kw)
    assert len(asked) == -(-f.size // chunk)  # one question per chunk
    plain = fbs_core.scatter_band(1, **kw)
    np.testing.assert_array_equal(band.maximum, plain.maximum)  # asking changes nothing
    np.testing.assert_array_equal(band.percentiles, plain.percentiles)

    calls = []

    def stop_at_third():
        calls.append(1)
        return len(calls) == 3

    with pytest.raises(StudyCancelled, match=f"after {2 * chunk} of {f.size} lines"):
        fbs_core.scatter_band(1, cancel=stop_at_third, **kw)
    assert len(calls) == 3  # nothing ran after the cancel
    assert not issubclass(StudyCancelled, fbs_core.FBSError)  # not an input error


def test_progress_reports_lines_done_of_the_total_after_every_chunk():
    f = fbs_core.harmonic(2).frequencies()
    rounds = 300
    chunk = 7
    kw = dict(rounds=rounds, seed=1, max_chunk_bytes=8 * 6 * rounds * chunk, max_chunk_seconds=None)
    seen = []
    band = fbs_core.scatter_band(2, progress=lambda done, total: seen.append((done, total)), **kw)
    n = f.size
    # before the first chunk, then after each chunk of `chunk` lines (the last one shorter)
    expected = [(0, n)] + [(min(n, k), n) for k in range(chunk, n + chunk, chunk)]
    assert seen == expected
    plain = fbs_core.scatter_band(2, **kw)
    np.testing.assert_array_equal(band.maximum, plain.maximum)  # reporting changes nothing
