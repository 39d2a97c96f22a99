"""Page builds bounded per user and in all, so that other sessions keep their latency.

A page of the dashboard is built on the server's event loop when it is requested (the app
script runs for ``GET /main``, or for a websocket that names a new session). Unbounded, a
logged-in user who reloads ``/main`` in a loop without ever opening its websocket makes
the loop build pages back to back: with two such loops another user's changes took p50
5.7 s / p95 17.9 s. So page builds draw on budgets of event-loop time (token buckets of
seconds): each user (one login, or one client address without a login) has
:data:`USER_BURST_S` seconds refilled at :data:`USER_SHARE` seconds per second, all users
together :data:`TOTAL_BURST_S` refilled at :data:`TOTAL_SHARE` (the rest of the loop stays
for the open sessions). A build is charged what it took, and the charge is given back when
the page's websocket opens: what is bounded is pages built and
never used, so a user opening and using pages (a browser, the test and load clients) is not
held back. A request while its budget is spent gets ``429`` (the user's) or ``503`` (all
users') with ``Retry-After`` and a light page that reloads itself then.
``server_private.bound_page_builds`` puts it in front of Panel's page, autoload and
websocket routes.
"""

from __future__ import annotations

import logging
import math
import threading
import time

log = logging.getLogger("tire_fbs.server")

#: Seconds of event-loop time per second that page builds of one user may take.
USER_SHARE = 0.2
#: Seconds of page builds a user may use at once (several tabs opened together).
USER_BURST_S = 4.0
#: Seconds of event-loop time per second that page builds of all users may take.
TOTAL_SHARE = 0.5
#: Seconds of page builds all users may use at once.
TOTAL_BURST_S = 8.0
#: Users (or addresses) whose budgets are kept; the oldest are forgotten beyond.
MAX_USERS = 10_000
#: Charges of a user's builds kept for giving back (the pages it may still open).
PENDING_PER_USER = 16

WAIT_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta http-equiv="refresh" content="{s}">
<title>tire-fbs: please wait</title></head>
<body style="font-family: sans-serif; margin: 2em">
<h2>Tire-chassis FBS dashboard</h2>
<p>{why} This page opens by itself in {s} s.</p></body></html>
"""


class Bucket:
    """Seconds available, refilled at ``rate`` per second up to ``burst`` (may go below
    zero: a build is charged what it took, after it)."""

    def __init__(self, rate: float, burst: float, now: float) -> None:
        self.rate, self.burst = float(rate), float(burst)
        self.level, self.t = float(burst), now

    def update(self, now: float) -> float:
        self.level = min(self.burst, self.level + (now - self.t) * self.rate)
        self.t = now
        return self.level

    def wait_s(self, now: float) -> float:
        """Seconds until the level is above zero again (0 when it is)."""
        level = self.update(now)
        return 0.0 if level > 0 else (-level + 1e-3) / self.rate


class PageBuilds:
    """Budgets of event-loop time for page builds, per user and in all.

    Parameters
    ----------
    user_share, user_burst_s, total_share, total_burst_s
        Refill rate (seconds per second) and capacity (seconds) of each user's budget and
        of the budget of all users.
    clock
        Monotonic seconds (tests pass their own).
    """

    def __init__(
        self,
        user_share: float = USER_SHARE,
        user_burst_s: float = USER_BURST_S,
        total_share: float = TOTAL_SHARE,
        total_burst_s: float = TOTAL_BURST_S,
        clock=time.monotonic,
    ) -> None:
        for name, v in (("user_share", user_share), ("total_share", total_share)):
            if not 0 < v <= 1:
                raise ValueError(f"{name} must be in (0, 1], got {v!r}")
        self.user_share, self.user_burst_s = float(user_share), float(user_burst_s)
        self.clock = clock
        self.total = Bucket(total_share, total_burst_s, clock())
        self.users: dict[str, Bucket] = {}
        self.lock = threading.Lock()
        self.pending: dict[str, list[float]] = {}  # charges not given back, oldest first
        self.refused = {"user": 0, "all": 0}

    def _user(self, key: str, now: float) -> Bucket:
        b = self.users.pop(key, None)
        if b is None:
            b = Bucket(self.user_share, self.user_burst_s, now)
            while len(self.users) >= MAX_USERS:
                self.users.pop(next(iter(self.users)))
        self.users[key] = b  # most recent last
        return b

    def check(self, key: str) -> tuple[str, float] | None:
        """None if ``key`` may build a page now, else (``"user"`` or ``"all"``, seconds
        to wait)."""
        with self.lock:
            now = self.clock()
            user = self._user(key, now).wait_s(now)
            if user > 0:
                self.refused["user"] += 1
                return "user", user
            total = self.total.wait_s(now)
            if total > 0:
                self.refused["all"] += 1
                return "all", total
            return None

    def charge(self, key: str, seconds: float) -> None:
        """A build of ``key`` took ``seconds`` (of both budgets)."""
        with self.lock:
            now = self.clock()
            self._user(key, now).update(now)
            self.total.update(now)
            self.users[key].level -= seconds
            self.total.level -= seconds
            charges = self.pending.setdefault(key, [])
            charges.append(seconds)
            del charges[:-PENDING_PER_USER]
            while len(self.pending) > MAX_USERS:
                self.pending.pop(next(iter(self.pending)))

    def refund(self, key: str) -> float:
        """A page built for ``key`` is in use (its websocket opened): the charge of the
        oldest of its builds not yet given back returns to both budgets (at most up to
        their capacity); the seconds given back."""
        with self.lock:
            charges = self.pending.get(key)
            if not charges:
                return 0.0
            seconds = charges.pop(0)
            now = self.clock()
            for b in (self._user(key, now), self.total):
                b.update(now)
                b.level = min(b.burst, b.level + seconds)
            return seconds

    @staticmethod
    def wait_page(kind: str, wait_s: float) -> tuple[int, int, str]:
        """(HTTP status, Retry-After seconds, HTML) of a refused page request."""
        s = max(1, math.ceil(wait_s))
        if kind == "user":
            why = "You opened many pages in a short time."
            return 429, s, WAIT_PAGE.format(s=s, why=why)
        why = "Many pages are being opened on this server."
        return 503, s, WAIT_PAGE.format(s=s, why=why)
