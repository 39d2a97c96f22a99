"""Connections the server keeps open: bounded per client and in all, refused quietly.

Without limits, a client that opens connections and never finishes their headers
(slowloris) holds them for ever: 3,500 such connections take the server's file
descriptors from 13 to 3,512 and ``/liveness`` from milliseconds to 4.6-6 s, and near the
process's open-file limit Tornado's ``accept()`` fails with EMFILE in a busy loop (90,424
tracebacks in 25 s). So:

- a request's headers must arrive within ``FBS_HEADER_TIMEOUT_S`` of the connection's
  start or of the previous request on it (Tornado's ``idle_connection_timeout``, which is
  also the header deadline), and its body within ``FBS_BODY_TIMEOUT_S``;
- a client (one address; a trusted reverse proxy counts in the total only) may hold
  ``FBS_MAX_CONNECTIONS_PER_CLIENT`` connections, all clients together
  ``FBS_MAX_CONNECTIONS`` (never more than the open-file limit leaves room for: the limit
  minus :data:`FD_RESERVE` for the app's files, pipes and sandbox);
- a connection beyond a cap is answered ``503`` with ``Retry-After`` and closed at once;
- ``accept()`` failing for lack of file descriptors stops accepting for
  :data:`ACCEPT_PAUSE_S` instead of spinning;
- each kind of refusal is logged once per :data:`LOG_INTERVAL_S` with its count.

:class:`ConnectionLimits` decides; ``server_private.accept_connections`` puts it in front
of the HTTP server's accept loop.
"""

from __future__ import annotations

import errno
import ipaddress
import logging
import resource
import socket
import time
from collections.abc import Callable, Iterable

log = logging.getLogger("tire_fbs.server")

#: Open connections of one client at most (a browser tab: a websocket and up to 6 HTTP).
MAX_CONNECTIONS_PER_CLIENT = 64
#: Open connections of all clients together at most.
MAX_CONNECTIONS = 1000
#: File descriptors kept free of connections (app files, pipes, the parser sandbox).
FD_RESERVE = 256
#: Seconds a request's headers may take (from the connection's start or the last request).
HEADER_TIMEOUT_S = 10.0
#: Seconds a request's body may take.
BODY_TIMEOUT_S = 30.0
#: Seconds between two log lines of the same kind of refusal.
LOG_INTERVAL_S = 10.0
#: Seconds the server stops accepting after ``accept()`` ran out of file descriptors.
ACCEPT_PAUSE_S = 1.0
#: What a refused connection reads before it is closed.
REFUSAL = (
    b"HTTP/1.1 503 Service Unavailable\r\nRetry-After: 10\r\nContent-Length: 0\r\n"
    b"Connection: close\r\n\r\n"
)


def open_file_limit() -> int:
    """The process's open-file limit, raised to its hard limit first (what an unprivileged
    process may do; the container's limit: ``ulimits`` in compose, ``docker run --ulimit``)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and soft < hard:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
            soft = hard
        except (ValueError, OSError):
            pass
    return soft if soft != resource.RLIM_INFINITY else 1 << 20


class QuietLog:
    """At most one log line per ``interval_s`` per kind, with the count since the last."""

    def __init__(self, interval_s: float = LOG_INTERVAL_S, clock=time.monotonic) -> None:
        self.interval_s = interval_s
        self.clock = clock
        self._last: dict[str, float] = {}
        self._count: dict[str, int] = {}

    def note(self, kind: str, text: str) -> bool:
        """Count one event of ``kind``; log ``text`` (with the count) if the interval since
        the last line of this kind is over. Whether a line was written."""
        self._count[kind] = self._count.get(kind, 0) + 1
        now = self.clock()
        if now - self._last.get(kind, -1e18) < self.interval_s:
            return False
        n = self._count.pop(kind)
        self._last[kind] = now
        log.warning("%s (%d in the last %.0f s)", text, n, self.interval_s)
        return True


class ConnectionLimits:
    """Open connections per client address and in all; admits or refuses a new one.

    Parameters
    ----------
    per_client, total
        Caps (connections). ``total`` is lowered to what the open-file limit leaves
        (``open_file_limit() - FD_RESERVE``, but not below 16).
    exempt
        Networks whose connections count in the total only (trusted reverse proxies:
        every client behind them shares their address).
    fd_limit
        The open-file limit (default :func:`open_file_limit`).
    """

    def __init__(
        self,
        per_client: int = MAX_CONNECTIONS_PER_CLIENT,
        total: int = MAX_CONNECTIONS,
        exempt: Iterable = (),
        fd_limit: int | None = None,
        quiet: QuietLog | None = None,
    ) -> None:
        if per_client < 1 or total < 1:
            raise ValueError("connection caps must be >= 1")
        limit = open_file_limit() if fd_limit is None else fd_limit
        self.per_client = int(per_client)
        self.total = min(int(total), max(16, limit - FD_RESERVE))
        self.exempt = tuple(exempt)
        self.quiet = quiet or QuietLog()
        self._open: dict[str, list[socket.socket]] = {}
        self._n = 0
        self.refused = 0

    def _is_exempt(self, host: str) -> bool:
        try:
            ip = ipaddress.ip_address(host)
        except ValueError:
            return False
        return any(ip in net for net in self.exempt)

    def _purge(self, host: str | None = None) -> None:
        """Forget the connections that have closed (a closed socket's fileno is -1)."""
        hosts = [host] if host is not None else list(self._open)
        for h in hosts:
            alive = [s for s in self._open.get(h, []) if s.fileno() != -1]
            self._n += len(alive) - len(self._open.get(h, []))
            if alive:
                self._open[h] = alive
            else:
                self._open.pop(h, None)

    def open_count(self, host: str | None = None) -> int:
        """Open connections of ``host`` (or of all)."""
        self._purge(host)
        return len(self._open.get(host, [])) if host is not None else self._n

    def admit(self, sock: socket.socket, address) -> bool:
        """Whether the new connection ``sock`` from ``address`` may be served; a refused
        one gets :data:`REFUSAL` (best effort) and is closed here."""
        host = str(address[0]) if isinstance(address, tuple) and address else "unix"
        self._purge(host)
        why = kind = ""
        if not self._is_exempt(host) and len(self._open.get(host, [])) >= self.per_client:
            kind = "per client"
            why = f"connections refused: client {host} holds {self.per_client}, its cap"
        elif self._n >= self.total:
            self._purge()
            if self._n >= self.total:
                kind = "in all"
                why = f"connections refused: {self.total} open, the cap of all clients"
        if why:
            self.refused += 1
            self.quiet.note(kind, why)
            try:
                sock.setblocking(False)
                sock.send(REFUSAL)
            except OSError:
                pass
            sock.close()
            return False
        self._open.setdefault(host, []).append(sock)
        self._n += 1
        return True


def accept_loop(
    sock: socket.socket,
    serve: Callable[[socket.socket, object], None],
    limits: ConnectionLimits,
    pause: Callable[[float], None],
    batch: int = 128,
) -> None:
    """Accept what is waiting on the listening ``sock`` (at most ``batch``), admitted ones
    handed to ``serve(connection, address)``. ``accept()`` out of file descriptors (EMFILE,
    ENFILE, ENOBUFS, ENOMEM) calls ``pause(ACCEPT_PAUSE_S)`` (stop accepting for that long)
    with one log line per interval, instead of failing again at once."""
    for _ in range(batch):
        try:
            connection, address = sock.accept()
        except BlockingIOError:
            return
        except ConnectionAbortedError:
            continue
        except OSError as exc:
            if exc.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
                limits.quiet.note(
                    "accept paused",
                    f"accept() failed ({errno.errorcode.get(exc.errno, exc.errno)}: no file "
                    f"descriptor left): not accepting for {ACCEPT_PAUSE_S:g} s",
                )
                pause(ACCEPT_PAUSE_S)
                return
            raise
        if limits.admit(connection, address):
            serve(connection, address)
