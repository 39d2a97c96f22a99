"""Dask trust: a scheduler is joined over TLS with mutual authentication, or in plain TCP
on the loopback interface only (unless the operator says otherwise).

Results come back from Dask workers unpickled: whoever reaches a scheduler can run code in
its clients. Checked here: the refusal logic on its own, the dashboard's client refusing a
plain remote scheduler before any connection, a TLS round trip with a scheduler and a
worker on the loopback interface using certificates made by
:func:`fbs_core.campaign.security.make_certificates` (and that scheduler refusing a plain
client, a client without a certificate and one with a certificate of another CA), and the
compose file starting its cluster with TLS.
"""

from __future__ import annotations

import stat
from pathlib import Path

import pytest

from fbs_core.campaign.security import (
    ALLOW_PLAIN_ENV,
    TLS_DIR_ENV,
    InsecureScheduler,
    connect,
    make_certificates,
    security_for,
)

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    "addr",
    ["tcp://127.0.0.1:8786", "localhost:8786", "tcp://[::1]:8786", "127.3.4.5:1", "inproc://x/1/2"],
)
def test_plain_tcp_on_the_loopback_is_allowed(addr):
    assert security_for(addr, {}) is None


@pytest.mark.parametrize(
    "addr",
    ["tcp://10.1.2.3:8786", "scheduler:8786", "tcp://dask.example.org:8786", "ucx://10.0.0.1:1"],
)
def test_plain_tcp_elsewhere_is_refused_unless_allowed(addr):
    with pytest.raises(InsecureScheduler, match=ALLOW_PLAIN_ENV):
        security_for(addr, {})
    assert security_for(addr, {ALLOW_PLAIN_ENV: "1"}) is None


def test_tls_needs_the_certificates(tmp_path):
    with pytest.raises(InsecureScheduler, match=TLS_DIR_ENV):
        security_for("tls://scheduler:8786", {})
    with pytest.raises(InsecureScheduler, match="lacks ca.pem, node.pem, node-key.pem"):
        security_for("tls://scheduler:8786", {TLS_DIR_ENV: str(tmp_path)})
    ca, cert, key = make_certificates(tmp_path)
    sec = security_for("tls://scheduler:8786", {TLS_DIR_ENV: str(tmp_path)})
    assert sec.require_encryption and sec.tls_ca_file == str(ca)
    assert sec.tls_client_cert == str(cert) and sec.tls_client_key == str(key)
    assert stat.S_IMODE(key.stat().st_mode) == 0o600
    before = [p.read_bytes() for p in (ca, cert, key)]
    make_certificates(tmp_path)  # existing certificates are kept
    assert [p.read_bytes() for p in (ca, cert, key)] == before


def test_the_dashboard_refuses_a_plain_remote_scheduler_before_connecting(monkeypatch):
    from app.runtime import offload

    monkeypatch.setenv("FBS_DASK_SCHEDULER", "tcp://192.0.2.1:8786")  # TEST-NET: never answers
    monkeypatch.delenv(ALLOW_PLAIN_ENV, raising=False)
    offload.reset()
    try:
        with pytest.raises(offload.Unavailable, match=ALLOW_PLAIN_ENV):
            offload.client()
        # backed off: the band is computed here, the scheduler is not tried again at once
        with pytest.raises(offload.Unavailable, match="failed recently"):
            offload.client()
    finally:
        offload.reset()


@pytest.fixture
def tls_cluster(tmp_path):
    from distributed import LocalCluster, Security

    ca, cert, key = (str(p) for p in make_certificates(tmp_path / "certs"))
    sec = Security(
        tls_ca_file=ca,
        tls_scheduler_cert=cert,
        tls_scheduler_key=key,
        tls_worker_cert=cert,
        tls_worker_key=key,
        tls_client_cert=cert,
        tls_client_key=key,
        require_encryption=True,
    )
    cluster = LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        protocol="tls://",
        host="127.0.0.1",
        security=sec,
        dashboard_address=None,
    )
    try:
        yield cluster, tmp_path / "certs"
    finally:
        cluster.close()


def _refused(addr, security=None) -> bool:
    from distributed import Client

    try:
        c = Client(addr, timeout="5s", security=security, set_as_default=False)
    except (OSError, TimeoutError):
        return True
    c.close()
    return False


def _tls_refused(addr: str, ca: str, cert: str | None = None, key: str | None = None) -> bool:
    """Whether the scheduler ends a raw TLS connection that trusts the CA and shows
    ``cert`` (none by default): TLS 1.3 ends it with an alert at the first read. A connection
    it keeps (it waits for a Dask message) is read until the timeout: not refused."""
    import socket
    import ssl

    host, port = addr.removeprefix("tls://").rsplit(":", 1)
    ctx = ssl.create_default_context(cafile=ca)
    ctx.check_hostname = False
    if cert:
        ctx.load_cert_chain(cert, key)
    try:
        with socket.create_connection((host, int(port)), 5) as raw:
            with ctx.wrap_socket(raw) as t:
                t.settimeout(5)
                t.sendall(b"\0" * 16)
                return t.recv(1) == b""
    except (ssl.SSLError, ConnectionError):
        return True
    except TimeoutError:
        return False


def test_tls_round_trip_and_the_scheduler_refuses_plain_and_unknown_clients(
    tls_cluster, tmp_path, monkeypatch
):
    from distributed import Security

    cluster, certs = tls_cluster
    addr = cluster.scheduler_address
    assert addr.startswith("tls://127.0.0.1:")
    monkeypatch.setenv(TLS_DIR_ENV, str(certs))
    c = connect(addr, "30s", set_as_default=False)
    try:
        assert c.submit(pow, 2, 10, pure=False).result(timeout=60) == 1024
        assert c.gather(c.map(lambda x: x * x, range(5))) == [0, 1, 4, 9, 16]
    finally:
        c.close()
    assert _refused(addr.replace("tls://", "tcp://"))  # a plain client
    ca = str(certs / "ca.pem")
    assert _tls_refused(addr, ca)  # no certificate
    assert not _tls_refused(addr, ca, str(certs / "node.pem"), str(certs / "node-key.pem"))
    other_ca, other_cert, other_key = (str(p) for p in make_certificates(tmp_path / "other"))
    stranger = Security(
        tls_ca_file=ca, tls_client_cert=other_cert, tls_client_key=other_key,
        require_encryption=True,
    )  # fmt: skip
    assert _refused(addr, stranger)  # a certificate of another CA


def test_the_compose_cluster_runs_with_tls_by_default():
    import yaml

    services = yaml.safe_load((ROOT / "docker" / "compose.yaml").read_text())["services"]
    sched = " ".join(services["scheduler"]["entrypoint"])
    assert "--protocol tls" in sched and "--tls-ca-file" in sched and "--tls-cert" in sched
    for name in ("worker-1", "worker-2"):
        cmd = " ".join(services[name]["entrypoint"])
        assert "tls://scheduler:8786" in cmd and "--tls-ca-file" in cmd and "--tls-key" in cmd
    env = services["dashboard"]["environment"]
    assert env["FBS_DASK_SCHEDULER"].startswith("tls://") and env[TLS_DIR_ENV]
    assert ALLOW_PLAIN_ENV not in env
