"""Sessions of one server stay apart, seen through Bokeh's own websocket protocol.

Each session here is a Bokeh protocol client (``bench/load_clients.py``, the load test's
light client): it pulls its session's document, applies the server's patches to it and
sends slider changes as BokehJS does. The check is between independent sessions: a change
in one session never reaches another, and two sessions in the same state show the same
plot data (results shared between sessions by the server's cache are neither altered by
one session nor mixed up with another's).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from load_clients import BokehSession, column_digest  # noqa: E402

from .conftest import SOURCES  # noqa: E402

pytestmark = pytest.mark.browser

TIMEOUT_S = 90.0


def _all_plotted(sess: BokehSession) -> bool:
    """Every view's data are there (the scatter band arrives after the page has loaded)."""
    for name in SOURCES:
        src = sess.doc.get_model_by_name(name)
        if src is None or not any(len(col) for col in src.data.values()):
            return False
    return True


def _computing(sess: BokehSession) -> bool:
    """The page says a result is still being computed: on a fresh server the suggested-N
    table's column with residuals arrives seconds after the page (its caption says so)."""
    return any("being computed" in str(getattr(m, "text", "")) for m in sess.doc.models)


async def _opened(url: str) -> BokehSession:
    sess = BokehSession()
    await sess.open(url, TIMEOUT_S)
    for _ in range(int(TIMEOUT_S / 0.1)):
        if _all_plotted(sess) and not _computing(sess):
            break
        await asyncio.sleep(0.1)
    assert _all_plotted(sess), f"not every view got its data: {sess.errors}"
    assert not _computing(sess), "the page still says a result is being computed"
    assert await sess.settle(TIMEOUT_S, 1.0) is not None, "plot data never settled"
    return sess


async def _scenario(url: str, server_errors) -> None:
    a, b = await asyncio.gather(_opened(url), _opened(url))
    c = None
    try:
        assert (await a.slider_info("Harmonic"))["value"] == 1
        before_b = b.digest
        assert before_b == a.digest  # same state, same data

        assert await a.change("Harmonic", 5, TIMEOUT_S, 0.4) is not None
        after_a = await a.settle(TIMEOUT_S, 1.0)
        assert after_a != before_b, "harmonic 5 shows the data of harmonic 1"
        # b was left alone: its slider and its plot data are those it opened with
        assert await b.settle(TIMEOUT_S, 1.0) == before_b
        assert (await b.slider_info("Harmonic"))["value"] == 1

        # a fresh session moved to the same state shows exactly a's data
        c = await _opened(url)
        assert await c.change("Harmonic", 5, TIMEOUT_S, 0.4) is not None
        assert await c.settle(TIMEOUT_S, 1.0) == after_a
        # and b, moved there last, too; a is untouched by b's and c's changes
        assert await b.change("Harmonic", 5, TIMEOUT_S, 0.4) is not None
        assert await b.settle(TIMEOUT_S, 1.0) == after_a
        assert await a.settle(TIMEOUT_S, 1.0) == after_a
        assert column_digest(a.doc) == after_a  # the kept digest is the replica's
        for s in (a, b, c):
            assert s.errors == []
        # checked while the sessions are still open: a client going away can make the
        # server log a closed-socket write, which is not this test's concern
        assert server_errors() == []
    finally:
        for s in (a, b, c):
            if s is not None:
                await s.close()


def test_a_change_in_one_session_never_reaches_another(dashboard):
    earlier = len(dashboard.errors())  # the server is shared with the other browser tests

    def server_errors():
        return dashboard.errors()[earlier:]

    # its own event loop in its own thread: pytest-playwright's loop may be running here
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        pool.submit(asyncio.run, _scenario(dashboard.url, server_errors)).result()
