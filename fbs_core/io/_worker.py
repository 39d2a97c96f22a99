"""Sandboxed parser process for untrusted binary files (MATLAB v5, HDF5, MATLAB v7.3).

The HDF5 C library and scipy's MAT-file reader crash (segfault, abort) or hang on
some malformed files; a fuzzing run of a few thousand mutated files finds such
inputs within seconds. This script therefore runs as a separate interpreter
(``python _worker.py``) that imports only numpy, scipy.io and h5py, never
``fbs_core``. For every request it forks a child that parses the bytes under a
memory limit; the worker kills the child after the timeout and reports crashes,
so the calling process never dies with the parser.

Protocol on stdin / stdout (all integers unsigned 64-bit little endian):

- request: ``kind`` (8 ASCII bytes: ``mat5``, ``hdf5``, ``uff``, ``csv`` or ``table``, space
  padded),
  ``timeout_ms``, ``mem_bytes``, ``max_reply`` (largest total size of the arrays that may
  come back), ``n``, then ``n`` bytes of file content;
- reply: ``status`` (0 ok, 1 refused, 2 crash, 3 timeout, 4 library error), ``n``, then ``n``
  bytes: for status 0 an encoded dump (see :func:`encode`), else a UTF-8 message.

A dump is a JSON header (length-prefixed) that lists the dtype and shape of every array,
followed by the arrays' raw bytes; only numeric dtypes are accepted, nothing is ever
unpickled, and the receiver reads the bytes straight into arrays it allocated
(:func:`fbs_core.io._sandbox.parse_isolated`), one copy.

The text formats (UFF, CSV) are parsed by :mod:`fbs_core.io._textparse`, loaded by path
(it imports only numpy and the standard library).
"""

from __future__ import annotations

import sys

if __name__ == "__main__":  # never import this package's modules (csv.py!) by accident
    _here = __file__.rsplit("/", 1)[0]
    sys.path[:] = [p for p in sys.path if p not in ("", ".", _here)]

import io  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import select  # noqa: E402
import signal  # noqa: E402
import struct  # noqa: E402
import time  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from types import ModuleType  # noqa: E402
from typing import IO, Any  # noqa: E402

import numpy as np  # noqa: E402

_U64 = struct.Struct("<Q")
_NUMERIC_KINDS = "biufc"
#: Groups and datasets of an HDF5 file read at most.
MAX_OBJECTS = 20_000
#: Deepest nesting of HDF5 groups read (HDF5's own visit takes minutes on 3,000 levels).
MAX_DEPTH = 64


class ParseError(Exception):
    """A well-formed refusal with a message for the user."""


# -- encoding ------------------------------------------------------------------------
def encode(meta: dict[str, Any], arrays: list[np.ndarray]) -> bytes:
    """JSON header (with dtype and shape of every array) + the arrays' raw bytes."""
    arrays = [np.ascontiguousarray(a) for a in arrays]
    for a in arrays:
        if a.dtype.kind not in _NUMERIC_KINDS or a.dtype.hasobject:
            raise ParseError(f"unsupported array type {a.dtype}")
    meta = dict(meta, _arrays=[{"dtype": a.dtype.str, "shape": list(a.shape)} for a in arrays])
    head = json.dumps(meta).encode()
    return _U64.pack(len(head)) + head + b"".join(a.tobytes() for a in arrays)


def array_specs(meta: dict[str, Any]) -> list[tuple[np.dtype[Any], tuple[int, ...]]]:
    """Checked dtypes and shapes of the arrays announced by a dump's header."""
    specs = []
    for e in meta.pop("_arrays"):
        dt = np.dtype(str(e["dtype"]))
        shape = tuple(int(x) for x in e["shape"])
        if dt.kind not in _NUMERIC_KINDS or dt.hasobject or any(x < 0 for x in shape):
            raise ValueError(f"unsupported array {e!r}")
        specs.append((dt, shape))
    return specs


def decode(payload: bytes) -> tuple[dict[str, Any], list[np.ndarray]]:
    """Inverse of :func:`encode`."""
    (n,) = _U64.unpack_from(payload, 0)
    meta = json.loads(payload[8 : 8 + n].decode())
    pos = 8 + n
    arrays: list[np.ndarray] = []
    for dt, shape in array_specs(meta):
        size = dt.itemsize * int(np.prod(shape, dtype=np.int64))
        arrays.append(np.frombuffer(payload, dt, size // dt.itemsize, pos).reshape(shape).copy())
        pos += size
    return meta, arrays


def _jsonable(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.decode("utf-8", "replace")
    if isinstance(v, np.ndarray):
        if v.dtype.kind in "SO":
            return [_jsonable(x) for x in v.ravel().tolist()]
        if v.dtype.kind in _NUMERIC_KINDS and v.dtype.kind != "c":
            return v.tolist()
        if v.dtype.kind == "U":
            return v.tolist()
        return "<unsupported>"
    if isinstance(v, np.generic):
        return v.item() if v.dtype.kind in "biuf" else _jsonable(np.asarray(v))
    if isinstance(v, str | int | float | bool) or v is None:
        return v
    return "<unsupported>"


# -- MATLAB v5 -----------------------------------------------------------------------
_MAT_NUMERIC = {
    "double",
    "single",
    "int8",
    "uint8",
    "int16",
    "uint16",
    "int32",
    "uint32",
    "int64",
    "uint64",
    "logical",
}


def _strings(a: Any) -> list[str]:
    """Char array or cell array of char arrays -> list of str."""
    a = np.asarray(a)
    if a.dtype.kind == "U":
        return [str(s).rstrip() for s in a.ravel(order="F").tolist()] if a.ndim else [str(a)]
    if a.dtype == object:
        out = []
        for el in a.ravel(order="F"):
            el = np.asarray(el)
            if el.dtype.kind != "U" or el.size > 1:
                raise ParseError("a cell array may only hold character strings")
            out.append(str(el.ravel()[0]).rstrip() if el.size else "")
        return out
    raise ParseError("expected characters")


def _too_big(limit: int) -> ParseError:
    return ParseError(
        f"the file holds more than {limit / 2**20:.0f} MiB of numbers, more than this tool "
        "accepts from one file"
    )


def parse_mat5(raw: bytes, limit: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    import scipy.io

    info = scipy.io.whosmat(io.BytesIO(raw))
    variables: dict[str, dict[str, Any]] = {}
    arrays: list[np.ndarray] = []
    # announced sizes first (8 bytes per element), before anything is decompressed
    if sum(8 * int(np.prod(shape, dtype=np.int64)) for _, shape, _ in info) > limit:
        raise _too_big(limit)
    for name, _shape, cls in info:
        if cls not in _MAT_NUMERIC | {"char", "cell"}:
            raise ParseError(
                f"variable {name!r} is of MATLAB class {cls!r}; only numeric, logical, char "
                "and cell arrays of char are read (objects, function handles, structs, "
                "sparse and opaque classes are rejected)"
            )
    names = [n for n, _, _ in info]
    data = scipy.io.loadmat(
        io.BytesIO(raw),
        mat_dtype=False,
        squeeze_me=False,
        chars_as_strings=True,
        variable_names=names,
        verify_compressed_data_integrity=True,
    )
    if sum(v.nbytes for v in data.values() if isinstance(v, np.ndarray)) > limit:
        raise _too_big(limit)
    for name in names:
        v = data.get(name)
        if not isinstance(v, np.ndarray) or type(v) is not np.ndarray:
            raise ParseError(f"variable {name!r} is not a plain array")
        if v.dtype.kind in _NUMERIC_KINDS:
            variables[name] = {"array": len(arrays)}
            arrays.append(v)
        elif v.dtype.kind == "U" or v.dtype == object:
            try:
                variables[name] = {"strings": _strings(v)}
            except ParseError as e:
                raise ParseError(f"variable {name!r}: {e}") from None
        else:
            raise ParseError(f"variable {name!r} has unsupported type {v.dtype}")
    return {"format": "mat5", "variables": variables}, arrays


# -- HDF5 (and MATLAB v7.3) ------------------------------------------------------------
def _complex_fields(dt: np.dtype[Any]) -> tuple[str, str] | None:
    names = dt.names or ()
    for re, im in (("real", "imag"), ("r", "i"), ("re", "im")):
        if names == (re, im):
            return re, im
    return None


def parse_hdf5(raw: bytes, limit: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    import h5py

    datasets: dict[str, dict[str, Any]] = {}
    groups: dict[str, dict[str, Any]] = {}
    arrays: list[np.ndarray] = []
    total = [0]
    with h5py.File(io.BytesIO(raw), "r") as f:
        objects = list(_walk(f, h5py))  # links, nesting and count checked before reading

        def attrs_of(obj: Any) -> dict[str, Any]:
            out: dict[str, Any] = {}
            for k in list(obj.attrs.keys())[:200]:
                try:
                    out[k] = _jsonable(obj.attrs[k])
                except Exception:  # an attribute of an unsupported type
                    out[k] = "<unsupported>"
            return out

        def visit(name: str, obj: Any) -> None:
            path = "/" + name
            if isinstance(obj, h5py.Group):
                groups[path] = attrs_of(obj)
                return
            if not isinstance(obj, h5py.Dataset):
                raise ParseError(f"object {path!r} is of an unsupported kind")
            if obj.is_virtual or obj.external:
                raise ParseError(f"dataset {path!r} stores its data in other files; refused")
            dt = obj.dtype
            total[0] += int(obj.size or 0) * max(dt.itemsize, 8)
            if total[0] > limit:  # announced size, checked before the data are read
                raise _too_big(limit)
            entry: dict[str, Any] = {"attrs": attrs_of(obj), "shape": list(obj.shape)}
            if h5py.check_string_dtype(dt) is not None:
                a = obj[()]
                a = np.asarray(a, dtype=object)
                entry["strings"] = [
                    x.decode("utf-8", "replace") if isinstance(x, bytes) else str(x)
                    for x in a.ravel().tolist()
                ]
            elif h5py.check_ref_dtype(dt) is h5py.Reference:
                refs = np.asarray(obj[()], dtype=object)
                names = []
                for r in refs.ravel():
                    target = f[r] if r else None
                    names.append(None if target is None else target.name)
                entry["refs"] = names
            elif dt.kind in _NUMERIC_KINDS:
                a = np.asarray(obj[()])
                entry["array"] = len(arrays)
                arrays.append(a)
            elif dt.kind == "V" and (fields := _complex_fields(dt)):
                re, im = fields
                a = obj[()]
                c = np.asarray(a[re], dtype=float) + 1j * np.asarray(a[im], dtype=float)
                entry["array"] = len(arrays)
                arrays.append(c)
            else:
                raise ParseError(f"dataset {path!r} has an unsupported data type {dt}")
            datasets[path] = entry

        groups["/"] = attrs_of(f)
        for name, obj in objects:
            visit(name, obj)
    return {"format": "hdf5", "datasets": datasets, "groups": groups}, arrays


def _walk(root: Any, h5py: Any) -> Iterator[tuple[str, Any]]:
    """``(path, object)`` of every group and dataset under ``root``, in the order of h5py's
    ``visititems`` (names sorted at each level, parents first), through hard links only,
    at most :data:`MAX_OBJECTS` of them and :data:`MAX_DEPTH` levels deep.

    Each object is opened relative to its group: HDF5's own visit resolves every full
    path from the root, which took minutes for groups nested 3,000 deep.
    """
    count = 0
    stack: list[tuple[Any, str, Iterator[str]]] = [(root, "", iter(root))]
    while stack:
        group, prefix, names = stack[-1]
        name = next(names, None)
        if name is None:
            stack.pop()
            continue
        path = prefix + name
        count += 1
        if count > MAX_OBJECTS:
            raise ParseError(
                f"the file holds more than {MAX_OBJECTS:,} groups and datasets, the most this "
                "tool reads from one file"
            )
        link = group.get(name, getlink=True)
        if not isinstance(link, h5py.HardLink):
            raise ParseError(
                f"object {path!r} is a {type(link).__name__}; links to other objects or "
                "files are not followed"
            )
        obj = group[name]
        yield path, obj
        if isinstance(obj, h5py.Group):
            if len(stack) >= MAX_DEPTH:
                raise ParseError(
                    f"groups are nested more than {MAX_DEPTH} levels deep (at {path[:80]!r}"
                    f"{'...' if len(path) > 80 else ''}), deeper than this tool reads"
                )
            stack.append((obj, path + "/", iter(obj)))


_TEXT: list[ModuleType] = []


def _textparse() -> ModuleType:
    """:mod:`fbs_core.io._textparse`, loaded by path (never through ``fbs_core``)."""
    if not _TEXT:
        import importlib.util

        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_textparse.py")
        spec = importlib.util.spec_from_file_location("_fbs_textparse", path)
        assert spec is not None and spec.loader is not None  # a .py file path
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        _TEXT.append(mod)
    return _TEXT[0]


def parse_uff(raw: bytes, limit: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    out: tuple[dict[str, Any], list[np.ndarray]] = _textparse().parse_uff(
        raw, max_values=limit // 16
    )
    return out


def parse_csv(raw: bytes, limit: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    out: tuple[dict[str, Any], list[np.ndarray]] = _textparse().parse_csv(
        raw, max_values=limit // 8
    )
    return out


def parse_table(raw: bytes, limit: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    out: tuple[dict[str, Any], list[np.ndarray]] = _textparse().parse_table(
        raw, max_values=limit // 64
    )
    return out


HANDLERS = {
    "mat5": parse_mat5,
    "hdf5": parse_hdf5,
    "uff": parse_uff,
    "csv": parse_csv,
    "table": parse_table,
}


# -- process plumbing ------------------------------------------------------------------
def _read_exact(stream: IO[bytes], n: int) -> bytes:
    chunks: list[bytes] = []
    got = 0
    while got < n:
        b = stream.read(n - got)
        if not b:
            raise EOFError
        chunks.append(b)
        got += len(b)
    return b"".join(chunks)


def _limit_memory(mem_bytes: int) -> None:
    try:
        import resource

        with open("/proc/self/statm") as fh:
            vm = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        resource.setrlimit(resource.RLIMIT_AS, (vm + mem_bytes, vm + mem_bytes))
    except Exception:  # no /proc or no resource module: no limit
        pass


def _child(kind: str, raw: bytes, mem_bytes: int, limit: int, w: int) -> None:
    _limit_memory(mem_bytes)
    try:
        meta, arrays = HANDLERS[kind](raw, limit)
        if sum(a.nbytes for a in arrays) > limit:
            raise _too_big(limit)
        status, payload = 0, encode(meta, arrays)
    except ParseError as e:
        status, payload = 1, str(e).encode()
    except MemoryError:
        status, payload = 1, b"the file needs more memory to parse than allowed"
    except RecursionError:
        status, payload = 4, b"RecursionError: the file is nested too deeply"
    except Exception as e:  # any failure of the third-party parser
        if type(e).__name__ == "ParseError":  # the text parsers' refusals
            status, payload = 1, str(e)[:2000].encode("utf-8", "replace")
        else:
            msg = f"{type(e).__name__}: {e}"[:300]
            status, payload = 4, msg.encode("utf-8", "replace")
    with os.fdopen(w, "wb") as out:
        out.write(_U64.pack(status) + _U64.pack(len(payload)) + payload)


def _serve_one(
    kind: str, raw: bytes, timeout: float, mem_bytes: int, limit: int
) -> tuple[int, bytes]:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - runs in the forked child
        os.close(r)
        try:
            _child(kind, raw, mem_bytes, limit, w)
        finally:
            os._exit(0)
    os.close(w)
    buf = bytearray()
    deadline = time.monotonic() + timeout
    timed_out = False
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            timed_out = True
            break
        ready, _, _ = select.select([r, 0], [], [], left)
        if 0 in ready:
            # the parent sends nothing while a file is parsed: its end of the pipe closed
            # (the server ended, or cancelled this parse): the parse is not wanted any more
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os._exit(0)
        if not ready:
            continue
        chunk = os.read(r, 1 << 20)
        if not chunk:
            break
        buf += chunk
    os.close(r)
    if timed_out:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    if timed_out:
        return 3, f"the parser did not finish within {timeout:g} s".encode()
    if len(buf) < 16 and os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL:
        return 2, b"the parser was killed (out of memory)"
    if len(buf) >= 16:
        (st,) = _U64.unpack_from(buf, 0)
        (n,) = _U64.unpack_from(buf, 8)
        if len(buf) == 16 + n:
            return int(st), bytes(buf[16:])
    sig = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
    what = f"signal {sig}" if sig else f"exit status {os.WEXITSTATUS(status)}"
    return 2, f"the parser crashed ({what})".encode()


def main() -> None:
    # a lower CPU priority (``--nice N``): a parse takes the cores the server does not need
    if sys.argv[1:2] == ["--nice"]:
        try:
            os.nice(int(sys.argv[2]))
        except (OSError, ValueError, IndexError):
            pass
    import h5py  # noqa: F401  (preload, so forks are fast)
    import scipy.io  # noqa: F401

    _textparse()

    # the protocol owns the original stdout; anything a library prints goes nowhere
    stdout = os.fdopen(os.dup(1), "wb")
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    stdin = sys.stdin.buffer
    while True:
        try:
            kind = _read_exact(stdin, 8).decode().strip()
            timeout_ms, mem_bytes, limit, n = (
                _U64.unpack(_read_exact(stdin, 8))[0] for _ in range(4)
            )
            raw = _read_exact(stdin, n)
        except EOFError:
            return
        if kind not in HANDLERS:
            status, payload = 1, f"unknown request {kind!r}".encode()
        else:
            status, payload = _serve_one(kind, raw, timeout_ms / 1000.0, mem_bytes, limit)
        stdout.write(_U64.pack(status) + _U64.pack(len(payload)) + payload)
        stdout.flush()


if __name__ == "__main__":
    main()
