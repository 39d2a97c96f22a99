"""Candidates of a review and the adequacy of their deliveries.

Truth: SHA-256 computed here with hashlib from the bytes, the reference tire's own
operating points and mode count, and tables of suggested modes written by hand.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

import fbs_core as fc
from fbs_core.candidates import (
    MAX_CANDIDATES,
    REFERENCE_DIGEST,
    Candidate,
    CandidateSet,
    file_digest,
)
from fbs_core.delivery import assess_delivery
from fbs_core.errors import FBSError
from fbs_core.studies import SuggestedModes
from fbs_core.tire import TireModel

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tire():
    return fc.reference_tire()


def cand(tire, k: int, **kw) -> Candidate:
    return Candidate(f"tire {k}", f"{k:024x}", tire, supplier=f"S{k}", **kw)


def test_the_limit_is_at_least_six_and_beyond_it_a_message(tire):
    assert MAX_CANDIDATES >= 6
    s = CandidateSet()
    for k in range(MAX_CANDIDATES):
        s = s.add(cand(tire, k))
    assert len(s) == MAX_CANDIDATES
    with pytest.raises(FBSError, match=f"already holds {MAX_CANDIDATES} candidates"):
        s.add(cand(tire, 99))
    assert len(s) == MAX_CANDIDATES and "tire 99" not in s  # nothing changed
    with pytest.raises(FBSError, match=f"at most {MAX_CANDIDATES}"):
        CandidateSet([cand(tire, k) for k in range(MAX_CANDIDATES + 1)])


def test_colour_slots_stay_with_their_candidate(tire):
    s = CandidateSet().add(cand(tire, 0)).add(cand(tire, 1)).add(cand(tire, 2))
    assert [s.slot(n) for n in s.names] == [0, 1, 2]
    s2 = s.remove("tire 1").add(cand(tire, 3))
    assert s2.slot("tire 0") == 0 and s2.slot("tire 2") == 2
    assert s2.slot("tire 3") == 1  # the lowest free slot
    assert s.slot("tire 1") == 1  # the old set is unchanged


def test_current_candidate_and_refusals(tire):
    s = CandidateSet([cand(tire, 0), cand(tire, 1)])
    assert s.current.name == "tire 0"
    s = s.with_current(f"{1:024x}")
    assert s.current.name == "tire 1"
    assert s.remove("tire 1").current.name == "tire 0"
    assert s.add(cand(tire, 2), current=True).current.name == "tire 2"
    with pytest.raises(FBSError, match="digest '000000000000000000000000'"):
        s.add(Candidate("another name", f"{0:024x}", tire))
    with pytest.raises(FBSError, match="name 'tire 0'"):
        s.add(Candidate("tire 0", "feed", tire))
    with pytest.raises(FBSError, match=r"unknown candidate 'nope'; candidates: tire 0 \("):
        s.with_current("nope")
    with pytest.raises(FBSError, match="name must not be empty"):
        Candidate("  ", "x", tire)
    with pytest.raises(FBSError, match="modal tire model"):
        Candidate("a", "x", object())
    r = s.renamed("tire 0", supplier="Supplier X", version="v2")
    assert r.get("tire 0").supplier == "Supplier X" and s.get("tire 0").supplier == "S0"
    with pytest.raises(FBSError, match="cannot change digest"):
        s.renamed("tire 0", digest="x")


def test_the_digest_is_sha256_of_the_bytes_and_the_settings():
    data = b"\x89HDF tire bytes"
    want = hashlib.sha256(data + b"[]").hexdigest()[:24]  # no settings: repr([])
    assert file_digest(data) == want
    assert file_digest(data, a=1) == hashlib.sha256(data + b"[('a', 1)]").hexdigest()[:24]


def test_a_candidate_from_the_shipped_tire_file_and_a_damaged_one(tire):
    raw = (ROOT / "data" / "reference_tire.h5").read_bytes()
    c = Candidate.from_file(raw, "reference_tire.h5", supplier="tire-fbs", version="1")
    assert c.digest == hashlib.sha256(raw + b"[]").hexdigest()[:24]
    assert c.model.n_modes == tire.n_modes and c.name == "reference_tire.h5"
    assert c.notes == ()  # 400 modes: no note
    with pytest.raises(fc.DataFormatError, match="broken.h5"):
        Candidate.from_file(b"not an hdf5 file at all", "broken.h5")
    ref = Candidate.reference()
    assert ref.digest == REFERENCE_DIGEST and ref.is_reference and ref.model is tire


def _table(hs, n, threshold=0.2, f_max=160.0) -> SuggestedModes:
    hs = tuple(hs)
    return SuggestedModes(
        hs,
        np.asarray(n, int),
        np.full(len(hs), np.nan),
        np.array([fc.harmonic(k).freq_range for k in hs]),
        threshold,
        f_max,
        80.0,
        None,
        (),
    )


def test_delivery_modes_against_table_5_1(tire):
    c = Candidate.reference()
    ok = assess_delivery(c, _table((1, 4), (120, 200)))
    assert ok.converged and ok.enough_modes and ok.adequate and ok.uncovered == ()
    assert ok.n_modes == 400 and ok.speeds == (20.0, 120.0)
    short = assess_delivery(c, _table((1, 4), (120, 400)))
    assert not short.converged and not short.adequate
    assert any("harmonic(s) 4" in w for w in short.warnings)
    need = assess_delivery(c, _table((1, 4), (120, 200)), required=_table((1, 4), (100, 420)))
    assert need.converged and not need.enough_modes
    assert any("asks for 420" in w for w in need.warnings)
    with pytest.raises(FBSError, match="one meeting"):
        assess_delivery(c, _table((1,), (100,)), required=_table((1,), (100,), threshold=0.1))


def test_delivery_speeds_must_cover_every_harmonic(tire):
    keep = tire.speeds >= 40.0  # 40-120 km/h: the harmonics need 30-120
    part = TireModel(
        tire.speeds[keep],
        tire.poles[keep],
        tire.psi[keep],
        tire.chi[keep],
        tire.wavelengths,
        tire.participation[keep],
    )
    d = assess_delivery(Candidate("slow", "abc", part), _table((2, 5), (100, 100)))
    assert d.uncovered == (2, 5) and not d.adequate and d.converged
    assert any("30-120 km/h needed, the delivery covers 40-120" in w for w in d.warnings)
