"""A session never stops answering: work it waits for ends, fails with a message on the
page, or is started again (a review meeting's session said "solving the tire..." for 25
minutes and answered no upload).

The failure modes are injected into the real sessions (:class:`app.store.Results` with
work on threads, as when served) through the one call the waves' view makes into the
core, ``wave_campbell``: a computation that raises, one whose thread is lost, one that
takes long, the background worker busy with another session's long work; and a pass that
computes for long after an upload. Each test waits for the page's state with a generous
deadline (never a fixed sleep) and checks what the session shows then.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
from server_util import wait_for

import fbs_core
from app.datasource import Models
from app.page.chrome import busy_indicator
from app.results import modes_compute as mc
from app.runtime import background
from app.runtime.uploads import UploadQueue
from app.store import Results
from fbs_core.io import save_frf

WAIT_S = 120
GRID = np.arange(13.0, 422.01, 0.5)


@pytest.fixture(scope="module")
def truth():
    """The reference tire's waves (the core's own result)."""
    return fbs_core.analysis.wave_campbell()


class Waves:
    """``wave_campbell`` that waits for ``release``, then fails as told or answers."""

    def __init__(self, truth, fail=()):
        self.truth = truth
        self.fail = list(fail)  # what the calls raise in turn (None: answer)
        self.calls = 0
        self.started = threading.Event()
        self.release = threading.Event()

    def __call__(self, tire=None, *args, progress=None, **kw):
        self.calls += 1
        self.started.set()
        assert self.release.wait(WAIT_S)
        err = self.fail.pop(0) if self.fail else None
        if err is not None:
            raise err
        return self.truth


_n = iter(range(1_000_000))


def _models() -> Models:
    """A tire token of its own (nothing cached for it), the reference tire's matrices."""
    k = next(_n)
    return Models(tire=fbs_core.reference_tire(), key=f"tire=waits-{k}", tire_name=f"w{k}.h5")


def _session(models: Models) -> Results:
    st = Results(background=True)
    st.state.case.models = models
    st.state.analysis.tab = "modes"
    return st


def _ready(st: Results) -> bool:
    r = st.waves
    return r is not None and bool(r.draw.get("ready"))


def _says(st: Results, text: str) -> bool:
    r = st.waves
    return r is not None and text in r.caption


@pytest.fixture
def sessions():
    made: list[Results] = []
    yield made
    for st in made:
        st.close()


def test_every_waiting_session_gets_the_result_while_the_background_worker_is_busy(
    monkeypatch, truth, sessions
):
    """Two sessions wait for the same tire's waves while the background worker is held by
    another session's long work: the waves do not queue behind it, and the end reaches
    both sessions (the second asked while the first's computation ran)."""
    fake = Waves(truth)
    monkeypatch.setattr(mc, "wave_campbell", fake)
    release_bg = threading.Event()
    started_bg = threading.Event()

    def long_work():
        started_bg.set()
        release_bg.wait(4 * WAIT_S)  # longer than any wait of the test

    background.BACKGROUND.submit(("another session", "long work"), long_work)
    try:
        assert started_bg.wait(WAIT_S)
        m = _models()
        a = _session(m)
        sessions.append(a)
        b = _session(m)
        sessions.append(b)
        assert not _ready(a) and not _ready(b)
        fake.release.set()
        wait_for(lambda: _ready(a) and _ready(b), WAIT_S, what="both sessions drawing the waves")
        assert fake.calls == 1  # computed once for both
        np.testing.assert_array_equal(a.waves.draw["speeds"], truth.speeds)
        assert a.waves.draw["label"] == b.waves.draw["label"]
    finally:
        release_bg.set()


def test_a_failed_computation_is_shown_to_every_waiter_and_tried_again(
    monkeypatch, truth, sessions
):
    fake = Waves(truth, fail=[RuntimeError("the eigenvalue solver did not converge")])
    monkeypatch.setattr(mc, "wave_campbell", fake)
    m = _models()
    a, b = _session(m), _session(m)
    sessions += [a, b]
    fake.release.set()
    for st in (a, b):
        wait_for(
            lambda st=st: _says(st, "did not converge"),
            WAIT_S,
            what="the failure on the page",
        )
        assert not st.waves.draw["ready"] and "try again" in st.waves.caption
    # the failure is kept a while (no retry loop), then a visit of the tab tries again
    mc.WAVES.failed_ttl = 0.0
    try:
        a.state.analysis.tab = "phase"
        a.state.analysis.tab = "modes"
        wait_for(lambda: _ready(a), WAIT_S, what="the retried waves drawn")
        assert fake.calls == 2
    finally:
        mc.WAVES.failed_ttl = 30.0


def test_a_lost_computation_is_started_again_without_the_user(monkeypatch, truth, sessions):
    """The thread computing the waves ends without finishing (here: SystemExit inside the
    solve): the computation is started again and the session gets the result."""
    fake = Waves(truth, fail=[SystemExit(1)])
    monkeypatch.setattr(mc, "wave_campbell", fake)
    a = _session(_models())
    sessions.append(a)
    fake.release.set()
    wait_for(lambda: _ready(a), WAIT_S, what="the waves after a lost computation")
    assert fake.calls == 2


def test_a_long_computation_says_why_the_view_waits(monkeypatch, truth, sessions):
    """Past its deadline the view says how long it has been and that the server is busy;
    the session answers meanwhile (another tab's result is published at once)."""
    fake = Waves(truth)
    monkeypatch.setattr(mc, "wave_campbell", fake)
    monkeypatch.setattr(mc.WAVES, "deadline_s", 0.5)
    a = _session(_models())
    sessions.append(a)
    try:
        wait_for(lambda: _says(a, "server is busy"), WAIT_S, what="the late note on the page")
        assert "s so far" in a.waves.caption
        a.state.case.dof = "y"  # the session answers while the waves are computed
        assert a.response.snapshot.dof == "y"
    finally:
        fake.release.set()
    wait_for(lambda: _ready(a), WAIT_S, what="the waves once the computation ends")


def test_a_long_pass_after_an_upload_does_not_hold_the_next_upload(monkeypatch, sessions):
    """A chassis upload while the Modes tab is shown starts a long pass (the participation
    of the new models; held here until released): the session's next upload is still read
    and answered (its error shown) meanwhile."""
    held, release = threading.Event(), threading.Event()
    real = mc.mode_participation

    def slow_participation(*args, **kw):
        held.set()
        assert release.wait(WAIT_S)
        return real(*args, **kw)

    st = Results(background=True)
    sessions.append(st)
    st.state.analysis.tab = "modes"  # the reference models' participation: not held
    monkeypatch.setattr(mc, "mode_participation", slow_participation)
    ds = st.state.data
    Y = fbs_core.reference_chassis().mobility(GRID)
    good = save_frf(Y.replace(data=Y.data * 1.5), format="mat")
    q = UploadQueue(threads=1)
    try:
        q.submit(ds, "chassis", lambda: ds.load_chassis(good, "c.mat"), lambda m: None)
        assert held.wait(WAIT_S), "the pass of the new chassis never started"
        q.submit(ds, "tire", lambda: ds.load_tire(b"", "empty.h5"), lambda m: None)
        wait_for(lambda: "empty.h5" in ds.error, WAIT_S / 2, what="the second upload answered")
    finally:
        release.set()
    wait_for(
        lambda: st.participation.snapshot.models.chassis_name == "c.mat",
        WAIT_S,
        what="the participation of the uploaded chassis",
    )
    assert st.participation.draw["ready"]


def test_long_work_shows_what_is_being_done_and_short_work_shows_nothing(monkeypatch, sessions):
    """A pass that computes for long (the participation of the Modes tab, held here) shows
    the busy indicator naming the work and its time, on the page's pane too; it is gone once
    the pass ends, and a short pass never shows it."""
    held, release = threading.Event(), threading.Event()
    real = mc.mode_participation

    def slow_participation(*args, **kw):
        held.set()
        assert release.wait(WAIT_S)
        return real(*args, **kw)

    st = Results(background=True)
    sessions.append(st)
    pane = busy_indicator(st)
    assert not pane.visible
    st.state.case.dof = "y"  # computed once: the next change back and forth is a look-up
    st.state.case.dof = "x"
    seen: list[str] = []
    st.param.watch(lambda e: seen.append(e.new), "working")
    st.state.case.dof = "y"  # a short pass
    assert seen == [] and st.working == ""
    monkeypatch.setattr(mc, "mode_participation", slow_participation)
    mc._participation.cache_clear()  # computed again: held
    t = threading.Thread(target=lambda: setattr(st.state.analysis, "tab", "modes"), daemon=True)
    t.start()
    try:
        assert held.wait(WAIT_S)
        wait_for(lambda: "Ranking the tire modes" in st.working, WAIT_S, what="the indicator")
        assert st.working.endswith(" s)")
        assert pane.visible and "Ranking the tire modes" in pane.object
        assert 'role="status"' in pane.object
    finally:
        release.set()
    t.join(WAIT_S)
    wait_for(lambda: st.working == "", WAIT_S, what="the indicator gone")
    assert not pane.visible
