"""Fuzzing the importers: random bytes, truncated files and mutated valid files end in
the project's own error type (an FBSError subclass), never another exception, a crash
of the test process or a hang.

The MATLAB and HDF5 parsers run in a sandbox process (crashes and hangs of the HDF5
library and of scipy's MAT reader on such inputs are real: a few thousand mutations
find them); a parse that takes longer than ``TIMEOUT`` is killed and reported.
"""

from __future__ import annotations

import os
from datetime import timedelta
from functools import cache

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from fbs_core import FRF
from fbs_core.errors import FBSError
from fbs_core.io import import_tire_model, load_frf, save_frf
from fbs_core.io.modal import write_tire_mat

TIMEOUT = 3.0
#: examples per test; raise for a longer campaign: FBS_FUZZ_EXAMPLES=2000 pytest ...
EXAMPLES = int(os.environ.get("FBS_FUZZ_EXAMPLES", "20"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=timedelta(seconds=2 * TIMEOUT + 5),
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def _frf() -> FRF:
    f = np.arange(1, 9) * 2.0
    w = 2 * np.pi * f
    H = 1j * w / (2e4 - w**2 + 4j * w)
    return FRF(
        f,
        H[:, None, None] * np.array([[[1.0, 0.5], [0.5, 2.0]]]),
        ["spindle:z", "bushing:x"],
        ["spindle:z", "patch"],
        "mobility",
    )


@cache
def seeds() -> dict[str, tuple[bytes, str]]:
    import tempfile
    from pathlib import Path

    from test_io_modal import small_tire

    from fbs_core.tire import storage

    with tempfile.TemporaryDirectory() as d:
        tire_h5 = storage.save_tire_model(small_tire(), Path(d) / "t.h5").read_bytes()
    Y = _frf()
    return {
        "uff": (save_frf(Y, format="uff"), "f.uff"),
        "uff58b": (save_frf(Y, format="uff", binary=True), "f.uff"),
        "mat5": (save_frf(Y, format="mat"), "f.mat"),
        "mat73": (save_frf(Y, format="mat", mat_version="7.3"), "f.mat"),
        "csv": (save_frf(Y, format="csv"), "f.csv"),
        "hdf5": (save_frf(Y, format="hdf5"), "f.h5"),
        "tire": (write_tire_mat(small_tire(), version="5"), "t.mat"),
        "tire73": (write_tire_mat(small_tire(), version="7.3"), "t.mat"),
        "tire_h5": (tire_h5, "t.h5"),
    }


def run(kind: str, raw: bytes) -> None:
    """Import; success or an FBSError are fine, anything else fails the test."""
    name = seeds()[kind][1]
    try:
        if kind.startswith("tire"):
            import_tire_model(raw, filename=name, timeout=TIMEOUT)
        else:
            load_frf(raw, filename=name, timeout=TIMEOUT)
    except FBSError as e:
        assert str(e)  # a message for the user


KINDS = ["uff", "uff58b", "mat5", "mat73", "csv", "hdf5", "tire", "tire73", "tire_h5"]


@pytest.mark.parametrize("kind", KINDS)
def test_seeds_are_valid(kind):
    run(kind, seeds()[kind][0])


@pytest.mark.parametrize("kind", KINDS)
@FUZZ
@given(data=st.data())
def test_random_bytes(kind, data):
    raw = data.draw(
        st.one_of(
            st.binary(min_size=1, max_size=3000),
            # random bytes behind a valid signature, so the content sniffing lets them through
            st.binary(max_size=3000).map(lambda b: seeds()[kind][0][:128] + b),
        )
    )
    run(kind, raw)


@pytest.mark.parametrize("kind", KINDS)
@FUZZ
@given(data=st.data())
def test_truncated(kind, data):
    raw = seeds()[kind][0]
    n = data.draw(st.integers(1, len(raw) - 1))
    run(kind, raw[:n])


@pytest.mark.parametrize("kind", KINDS)
@FUZZ
@given(data=st.data())
def test_mutated(kind, data):
    raw = bytearray(seeds()[kind][0])
    edits = data.draw(
        st.lists(
            st.tuples(st.integers(0, len(raw) - 1), st.integers(0, 255)), min_size=1, max_size=12
        )
    )
    for pos, byte in edits:
        raw[pos] = byte
    if data.draw(st.booleans()):  # text formats: also swap in characters that matter
        text_edits = data.draw(
            st.lists(
                st.tuples(st.integers(0, len(raw) - 1), st.sampled_from(b"-+.eE0159 ,;\n#:/()NnI")),
                max_size=6,
            )
        )
        for pos, byte in text_edits:
            raw[pos] = byte
    run(kind, bytes(raw))


@FUZZ
@given(
    text=st.text(
        alphabet=st.sampled_from("mMnNsSkgGu/()^*.-+ 0123456789µ²radHzc:xyzw"), max_size=30
    )
)
def test_header_texts(text):
    """Units, labels and frequency units from file headers: own errors only."""
    from fbs_core.errors import DOFError, FrequencyGridError, QuantityError
    from fbs_core.io.checks import frequency_from_units, normalize_label, parse_units

    try:
        u = parse_units(text)
        assert u is None or u.length > 0 and u.force > 0
    except QuantityError:
        pass
    try:
        normalize_label(text)
    except DOFError:
        pass
    try:
        frequency_from_units(np.ones(2), text, "t")
    except FrequencyGridError:
        pass


# -- structure-aware fuzzing: well-formed files with hostile contents ---------------------
LABELS = st.sampled_from(
    [
        "spindle:z",
        "spindle:RX",
        "bushing:-x",
        "hub:tz",
        "patch",
        "1:z",
        "hub:w",
        "",
        "a b:x",
        "x:y:z",
        "hub:",
        ":z",
        "spindle:z",
    ]
)
FINITE = st.floats(-1e6, 1e6)
NUMBERS = st.one_of(
    FINITE,
    FINITE,
    FINITE,
    st.integers(-3, 3).map(float),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
)


def grid(data, n):
    """Mostly a valid grid, sometimes anything."""
    if data.draw(st.integers(0, 3)):
        return list(np.cumsum(data.draw(st.lists(st.floats(0.01, 100.0), min_size=n, max_size=n))))
    return data.draw(st.lists(NUMBERS, min_size=n, max_size=n))


HEADER_VALUES = st.sampled_from(
    [
        "mobility",
        "receptance",
        "accelerance",
        "velocity",
        "",
        "m/N",
        "m/(N s)",
        "mm/s/N",
        "N/m",
        "g/N",
        "kg",
        "V/V",
        "re-im",
        "mag-phase",
        "deg",
        "rad",
        "Hz",
        "rad/s",
        "rpm",
    ]
)


@FUZZ
@given(data=st.data())
def test_structured_csv(data):
    outs = data.draw(st.lists(LABELS, min_size=1, max_size=3))
    ins = data.draw(st.lists(LABELS, min_size=1, max_size=2))
    n = data.draw(st.integers(0, 5))
    head = [
        f"# {k}: {data.draw(HEADER_VALUES)}"
        for k in data.draw(
            st.lists(
                st.sampled_from(
                    ["quantity", "units", "layout", "phase_unit", "freq_unit", "other"]
                ),
                max_size=4,
            )
        )
    ]
    parts = data.draw(
        st.sampled_from([("Re", "Im"), ("Mag", "Phase"), ("Re", "Im"), ("Re", "Phase")])
    )
    cols = ["freq [Hz]"] + [f"{p}({o} / {i})" for o in outs for i in ins for p in parts]
    f = grid(data, n)
    num = data.draw(st.sampled_from([FINITE, FINITE, NUMBERS]))
    rows = [
        ",".join([repr(float(f[r]))] + [repr(data.draw(num)) for _ in cols[1:]]) for r in range(n)
    ]
    text = "\n".join(head + [",".join(cols)] + rows)
    try:
        load_frf(
            text.encode(),
            filename="s.csv",
            quantity=data.draw(st.sampled_from([None, "mobility", "accelerance"])),
        )
        event("loaded")
    except FBSError as e:
        event(type(e).__name__)
        assert str(e)


@FUZZ
@given(data=st.data())
def test_structured_mat(data):
    import io

    import scipy.io

    nf = data.draw(st.integers(1, 4))
    shape = data.draw(
        st.one_of(
            st.lists(st.integers(1, 3), min_size=1, max_size=4),
            st.tuples(st.just(nf), st.integers(1, 3), st.just(1)),
        )
    )
    v = {
        "freq": np.array(grid(data, nf)),
        data.draw(st.sampled_from(["H", "Y", "G"])): np.array(
            data.draw(
                st.lists(
                    data.draw(st.sampled_from([FINITE, FINITE, NUMBERS])),
                    min_size=int(np.prod(shape)),
                    max_size=int(np.prod(shape)),
                )
            )
        ).reshape(shape)
        * data.draw(st.sampled_from([1.0, 1.0 + 0.5j])),
        "outputs": np.array(data.draw(st.lists(LABELS, min_size=1, max_size=3))),
        "inputs": data.draw(LABELS),
    }
    for key in data.draw(st.lists(st.sampled_from(["quantity", "units", "freq_unit"]), max_size=3)):
        v[key] = data.draw(HEADER_VALUES)
    b = io.BytesIO()
    scipy.io.savemat(b, v)
    try:
        load_frf(b.getvalue(), filename="s.mat", timeout=TIMEOUT)
        event("loaded")
    except FBSError as e:
        event(type(e).__name__)
        assert str(e)
