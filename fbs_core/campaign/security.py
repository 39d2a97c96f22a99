"""Trust between this package's clients and a Dask cluster: TLS with mutual authentication.

A Dask client unpickles what the workers send back, and a scheduler runs what its clients
send: whoever can talk to a scheduler's port can run code in every client and worker. So

* a scheduler at ``tls://host:port`` is joined with the certificates in the directory
  ``$FBS_DASK_TLS_DIR`` (:data:`CA_FILE`, :data:`CERT_FILE`, :data:`KEY_FILE`): the client
  checks the scheduler's certificate against the CA and shows its own, signed by the same
  CA (the scheduler started with ``--tls-ca-file`` refuses a client without one);
* a plain ``tcp://`` address (or one without a scheme, or another unencrypted protocol) is
  joined only on the loopback interface (``127.0.0.0/8``, ``::1``, ``localhost``); anywhere
  else it is refused (:class:`InsecureScheduler`) unless ``$FBS_DASK_ALLOW_PLAIN`` is ``1``
  (a network that is private by other means: the operator says so explicitly).

:func:`make_certificates` makes the certificates of a deployment: a CA, used once to sign
one node certificate and then forgotten (its key is not written), and the node certificate
and key that the scheduler, the workers and the clients all present. ``python -m
fbs_core.campaign.security init DIR`` makes them at a deployment's first start (the compose
file does, on its volume) and leaves existing ones alone.
"""

from __future__ import annotations

import argparse
import datetime as dt
import ipaddress
import os
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import InsecureScheduler

__all__ = [
    "ALLOW_PLAIN_ENV",
    "CA_FILE",
    "CERT_FILE",
    "InsecureScheduler",
    "KEY_FILE",
    "TLS_DIR_ENV",
    "connect",
    "is_loopback",
    "make_certificates",
    "security_for",
]

#: Directory of the certificates (:data:`CA_FILE`, :data:`CERT_FILE`, :data:`KEY_FILE`).
TLS_DIR_ENV = "FBS_DASK_TLS_DIR"
#: ``1`` allows a plain-TCP scheduler outside the loopback interface.
ALLOW_PLAIN_ENV = "FBS_DASK_ALLOW_PLAIN"
CA_FILE, CERT_FILE, KEY_FILE = "ca.pem", "node.pem", "node-key.pem"
#: Life of the certificates made by :func:`make_certificates` (days).
VALID_DAYS = 3650


def _split(addr: str) -> tuple[str, str]:
    """``(scheme, host)`` of a Dask address (``tcp`` when it names none)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    scheme, loc = parse_address(addr.strip(), strict=False)
    if scheme == "inproc":
        return scheme, ""
    try:
        host = str(parse_host_port(loc)[0])
    except ValueError:
        host = loc
    return scheme, host.strip("[]")


def is_loopback(host: str) -> bool:
    """Whether ``host`` names the loopback interface."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _allowed(env: Mapping[str, str]) -> bool:
    return env.get(ALLOW_PLAIN_ENV, "").strip().lower() in ("1", "true", "yes")


def security_for(addr: str, env: Mapping[str, str] | None = None) -> Any:
    """The ``distributed.Security`` to join the scheduler at ``addr`` with, or None for a
    plain connection that is allowed (see the module's docstring).

    Raises
    ------
    InsecureScheduler
        For plain TCP outside the loopback without ``FBS_DASK_ALLOW_PLAIN=1``, and for
        ``tls://`` without ``FBS_DASK_TLS_DIR`` or with certificate files missing.
    """
    env = os.environ if env is None else env
    scheme, host = _split(addr)
    if scheme == "inproc":
        return None
    if scheme != "tls":
        if is_loopback(host) or _allowed(env):
            return None
        raise InsecureScheduler(
            f"the Dask scheduler {addr} is not on the loopback interface and its connection "
            f"is not encrypted: results come back unpickled, so whoever can reach it can run "
            f"code here. Use tls:// with {TLS_DIR_ENV}, or set {ALLOW_PLAIN_ENV}=1 for a "
            "network that is private by other means"
        )
    folder = env.get(TLS_DIR_ENV, "").strip()
    if not folder:
        raise InsecureScheduler(
            f"the Dask scheduler {addr} uses TLS: set {TLS_DIR_ENV} to the directory of "
            f"{CA_FILE}, {CERT_FILE} and {KEY_FILE}"
        )
    files = [Path(folder) / f for f in (CA_FILE, CERT_FILE, KEY_FILE)]
    missing = [f.name for f in files if not f.is_file()]
    if missing:
        raise InsecureScheduler(f"{TLS_DIR_ENV}={folder} lacks {', '.join(missing)}")
    from distributed import Security

    ca, cert, key = (str(f) for f in files)
    return Security(
        tls_ca_file=ca,
        tls_client_cert=cert,
        tls_client_key=key,
        require_encryption=True,
    )


def connect(addr: str, timeout: str | float, **kwargs: Any) -> Any:
    """A ``distributed.Client`` of the scheduler at ``addr``, with :func:`security_for`.

    Raises
    ------
    InsecureScheduler
        Before any connection is tried, for an address refused by :func:`security_for`.
    OSError, TimeoutError
        When the scheduler cannot be reached (or refuses the certificate).
    """
    from distributed import Client

    security = security_for(addr)
    return Client(addr, timeout=timeout, security=security, **kwargs)


def _write(path: Path, data: bytes, mode: int) -> None:
    """Write ``path`` whole or not at all (a temporary file renamed), with ``mode``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def make_certificates(
    directory: str | os.PathLike[str],
    names: Sequence[str] = ("scheduler", "localhost"),
    days: int = VALID_DAYS,
) -> tuple[Path, Path, Path]:
    """The paths of ``ca.pem``, ``node.pem`` and ``node-key.pem`` in ``directory``, made
    when any is missing (all three anew), else left as they are.

    The CA (EC P-256) signs one node certificate (EC P-256, for server and client
    authentication, ``names`` as DNS names plus ``127.0.0.1``) and its key is dropped: no
    further certificate can be issued with it. The node key is written with mode 0600.
    """
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    d = Path(directory)
    paths = (d / CA_FILE, d / CERT_FILE, d / KEY_FILE)
    if all(p.is_file() for p in paths):
        return paths
    d.mkdir(parents=True, exist_ok=True)
    now = dt.datetime.now(dt.UTC)
    start, end = now - dt.timedelta(minutes=5), now + dt.timedelta(days=days)

    def name(cn: str) -> x509.Name:
        return x509.Name(
            [
                x509.NameAttribute(NameOID.ORGANIZATION_NAME, "tire-fbs"),
                x509.NameAttribute(NameOID.COMMON_NAME, cn),
            ]
        )

    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = name("tire-fbs Dask CA")
    ca = (
        x509.CertificateBuilder()
        .subject_name(ca_name)
        .issuer_name(ca_name)
        .public_key(ca_key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=False,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                key_cert_sign=True,
                crl_sign=True,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .sign(ca_key, hashes.SHA256())
    )
    key = ec.generate_private_key(ec.SECP256R1())
    alt: list[x509.GeneralName] = [x509.DNSName(n) for n in names]
    alt.append(x509.IPAddress(ipaddress.ip_address("127.0.0.1")))
    node = (
        x509.CertificateBuilder()
        .subject_name(name("tire-fbs Dask node"))
        .issuer_name(ca_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(start)
        .not_valid_after(end)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.SubjectAlternativeName(alt), critical=False)
        .add_extension(
            x509.ExtendedKeyUsage(
                [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
            ),
            critical=False,
        )
        .sign(ca_key, hashes.SHA256())
    )
    pem = serialization.Encoding.PEM
    _write(paths[2], key.private_bytes(
        pem, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
    ), 0o600)  # fmt: skip
    _write(paths[1], node.public_bytes(pem), 0o644)
    _write(paths[0], ca.public_bytes(pem), 0o644)  # last: its presence says "complete"
    return paths


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m fbs_core.campaign.security init DIR [--owner UID:GID]``."""
    ap = argparse.ArgumentParser(prog="python -m fbs_core.campaign.security")
    sub = ap.add_subparsers(dest="command", required=True)
    init = sub.add_parser("init", help="make the certificates in DIR unless they exist")
    init.add_argument("directory")
    init.add_argument("--owner", help="UID:GID to give the files (when run as root)")
    args = ap.parse_args(argv)
    existed = all((Path(args.directory) / f).is_file() for f in (CA_FILE, CERT_FILE, KEY_FILE))
    paths = make_certificates(args.directory)
    if args.owner:
        uid, _, gid = args.owner.partition(":")
        for p in (Path(args.directory), *paths):
            os.chown(p, int(uid), int(gid or uid))
    print(f"Dask TLS certificates {'kept' if existed else 'made'} in {args.directory}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
