"""Every parser runs in the sandbox, under its limits (issue 20.3, 20.4, 12).

CSV and UFF used to be parsed in the server process, without time or memory limits;
the sandbox let a small compressed file send hundreds of MB back into the server.
"""

from __future__ import annotations

import io

import h5py
import numpy as np
import pytest

import fbs_core as fc
from fbs_core.errors import DataFormatError
from fbs_core.io import load_frf, save_frf
from fbs_core.io._sandbox import MAX_RESULT_BYTES, parse_isolated


def _wide(n_lines: int) -> bytes:
    Y = fc.FRF(
        np.arange(1, n_lines + 1) * 0.5,
        np.ones((n_lines, 12, 6)) * 1e-3,
        fc.node_labels("s") + fc.node_labels("b"),
        fc.node_labels("s"),
    )
    return save_frf(Y, format="csv"), save_frf(Y, format="uff")


@pytest.mark.parametrize("fmt", ["csv", "uff"])
def test_text_parsers_obey_the_time_limit(fmt):
    csv_raw, uff_raw = _wide(4000)
    raw = csv_raw if fmt == "csv" else uff_raw
    # the same file loads with the default limit ...
    assert load_frf(raw, filename=f"a.{fmt}").frf.shape == (4000, 12, 6)
    # ... and is stopped by the sandbox when the limit is too short for it
    with pytest.raises(DataFormatError, match="did not finish within"):
        load_frf(raw, filename=f"a.{fmt}", timeout=1e-3)


def test_csv_errors_come_from_the_sandbox_with_line_and_column():
    raw = save_frf(fc.FRF([1.0, 2.0, 3.0], np.ones((3, 1, 1)), ["a:z"], ["b:z"]), format="csv")
    text = raw.decode().splitlines()
    text[-2] = text[-2].replace("1.0", "abc", 1)
    n = len(text) - 1  # 1-based line number of the edited row
    with pytest.raises(DataFormatError, match=f"line {n} column 2: 'abc' is not a number"):
        load_frf("\n".join(text).encode(), filename="x.csv")
    text[-2] = text[-2] + ",5"
    with pytest.raises(DataFormatError, match=f"line {n}: 4 fields, the header has 3"):
        load_frf("\n".join(text).encode(), filename="x.csv")


def _zeros_h5(n: int) -> bytes:
    """A tiny file announcing ``n`` doubles (a compressed chunked dataset never written)."""
    b = io.BytesIO()
    with h5py.File(b, "w") as h:
        g = h.create_group("frf")
        g.create_dataset("freq", data=np.arange(1.0, 3.0))
        g.create_dataset(
            "data", shape=(n,), dtype=float, chunks=(min(n, 1 << 16),), compression="gzip"
        )
        g.attrs["quantity"] = "mobility"
    return b.getvalue()


def test_a_small_file_cannot_send_more_than_the_bound_back():
    raw = _zeros_h5(40_000_000)  # 320 MB of zeros announced
    assert len(raw) < 2_000_000
    assert 40_000_000 * 8 > MAX_RESULT_BYTES
    with pytest.raises(DataFormatError, match="more than 256 MiB of numbers"):
        load_frf(raw, filename="zeros.h5")
    # the bound is a parameter; below it the same kind of file is read
    meta, arrays = parse_isolated("hdf5", _zeros_h5(1000), "t", max_result_bytes=1 << 20)
    assert sum(a.size for a in arrays) == 1002
    with pytest.raises(DataFormatError, match="more than 1 MiB"):
        parse_isolated("hdf5", _zeros_h5(200_000), "t", max_result_bytes=1 << 20)


def test_a_compressed_mat_file_is_bounded_before_it_is_inflated():
    import scipy.io

    b = io.BytesIO()
    scipy.io.savemat(b, {"H": np.zeros((300_000,)), "freq": np.arange(2.0)}, do_compression=True)
    raw = b.getvalue()
    assert len(raw) < 10_000
    with pytest.raises(DataFormatError, match="more than 1 MiB"):
        parse_isolated("mat5", raw, "t", max_result_bytes=1 << 20)


def test_the_reply_arrives_intact_and_writable():
    Y = fc.FRF(
        [1.0, 2.0],
        (np.arange(8).reshape(2, 2, 2) + 1j).astype(complex),
        ["a:x", "a:y"],
        ["b:x", "b:y"],
    )
    for fmt, name in (("csv", "y.csv"), ("uff", "y.uff"), ("hdf5", "y.h5"), ("mat", "y.mat")):
        r = load_frf(save_frf(Y, format=fmt), filename=name)
        assert r.frf.allclose(Y, rtol=1e-12), fmt
