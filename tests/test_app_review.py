"""The review in a session: candidates, targets and the published verdict.

Truth: the verdict the session publishes is compared with one built here from the core
directly (``fbs_core.bushing_response`` of each candidate tire, all modes, on the
harmonic's own grid, judged by :func:`fbs_core.verdict.verdict`): a second path past the
app's caches and truncation maps. The targets are made from those direct responses with a
known margin or exceedance, so the expected statuses and dB figures are known by
construction, not read back from the app.
"""

from __future__ import annotations

import numpy as np
import pytest

import fbs_core
from app.datasource import REFERENCE, DataSource
from app.state import DashboardState
from app.store import Results
from fbs_core.candidates import MAX_CANDIDATES, Candidate, CandidateSet
from fbs_core.targets import Target, response_level
from fbs_core.tire import TireModel
from fbs_core.tire.storage import save_tire_model
from fbs_core.verdict import verdict

H = 3  # the harmonic the targets are written for


def _tire(scale: float = 1.0, n_modes: int | None = None, tag: str = "t") -> TireModel:
    """The reference tire with its poles scaled (another tire's resonances) or cut."""
    t = fbs_core.reference_tire()
    m = slice(None) if n_modes is None else slice(0, n_modes)
    return TireModel(
        t.speeds, t.poles[:, m] * scale, t.psi[:, m], t.chi[:, m], t.wavelengths,
        t.participation[:, :, m], meta={"source": tag},
    )  # fmt: skip


def _bytes(tmp_path, model: TireModel, name: str) -> bytes:
    return save_tire_model(model, tmp_path / name).read_bytes()


@pytest.fixture(scope="module")
def tires():
    return {"soft.h5": _tire(0.97, tag="soft"), "stiff.h5": _tire(1.04, tag="stiff")}


def _direct(model: TireModel | None, k: int) -> fbs_core.FRF:
    """The all-modes bushing response of the core, on the harmonic's own grid."""
    kw = {} if model is None else {"tire": model}
    return fbs_core.bushing_response(k, **kw)


def _target_csv(level_db: float, f: np.ndarray, dof: str = "bushing:z", k: int = H) -> bytes:
    text = (
        "# tire-fbs target\n# quantity: mobility\n# scale: dB\n"
        f"# harmonic: {k}\nfreq [Hz],{dof}\n{float(f[0])!r},{float(level_db)!r}\n"
        f"{float(f[-1])!r},{float(level_db)!r}\n"
    )
    return text.encode()


def _session(tmp_path, tires) -> tuple[DashboardState, Results]:
    st = DashboardState()
    store = Results(st)
    for name, model in tires.items():
        assert st.data.load_tire(_bytes(tmp_path, model, name), name), st.data.error
    return st, store


def test_uploads_become_candidates_and_the_current_one_is_the_sessions_tire(tmp_path, tires):
    st, _store = _session(tmp_path, tires)
    ds = st.data
    cands = ds.review.candidates
    assert cands.names == ("reference", "soft.h5", "stiff.h5")
    assert cands.current.name == "stiff.h5" and ds.models.tire is cands.current.model
    np.testing.assert_array_equal(ds.models.tire.poles, tires["stiff.h5"].poles)
    # the same file again is not a new candidate: it becomes current
    assert ds.load_tire(_bytes(tmp_path, tires["soft.h5"], "soft.h5"), "again.h5"), ds.error
    assert ds.review.candidates.names == cands.names
    assert ds.models.tire is ds.review.candidates.get("soft.h5").model
    # choosing the reference: the session's models are the reference's
    assert ds.select_candidate("reference")
    assert ds.models is REFERENCE and st.case.models is REFERENCE
    assert st.case.review == ds.review
    # colours stay with their candidate when another leaves
    slot = ds.review.candidates.slot("stiff.h5")
    assert ds.remove_candidate("soft.h5")
    assert ds.review.candidates.names == ("reference", "stiff.h5")
    assert ds.review.candidates.slot("stiff.h5") == slot
    assert ds.describe_candidate("stiff.h5", name="Supplier Y", supplier="Y", version="2")
    c = ds.review.candidates.get("Supplier Y")
    assert (c.supplier, c.version) == ("Y", "2")


def test_the_verdict_is_the_cores_of_the_direct_responses(tmp_path, tires):
    st, store = _session(tmp_path, tires)
    f = fbs_core.harmonic(H).frequencies()
    soft = response_level(_direct(tires["soft.h5"], H).sel(outputs="bushing:z"))[:, 0]
    stiff = response_level(_direct(tires["stiff.h5"], H).sel(outputs="bushing:z"))[:, 0]
    # a flat target 1.5 dB above the soft tire's highest level on this harmonic: the soft
    # tire passes with a 1.5 dB margin; the stiff one's level is known too
    level = 20 * np.log10(soft.max()) + 1.5
    assert st.data.load_targets(_target_csv(level, f), "target.csv"), st.data.error
    r = store.verdict
    v = r.core["verdict"]
    row = v.row("soft.h5", H, "bushing:z")
    assert row.status == "pass"
    assert row.margin_db == pytest.approx(1.5, abs=1e-6)
    row_y = v.row("stiff.h5", H, "bushing:z")
    expect = 20 * np.log10(stiff.max()) - level
    assert row_y.worst_db == pytest.approx(expect, abs=1e-6)
    assert row_y.status == ("fail" if expect > 0 else "pass")
    # the whole table: the core's verdict of the direct responses
    cands = CandidateSet([Candidate.reference(), *(Candidate(n, n, m) for n, m in tires.items())])
    direct = verdict(
        {(c.name, k): _direct(None if c.is_reference else c.model, k) for c in cands for k in (H,)},
        st.data.review.targets,
        candidates=cands,
    )
    got = {(x.candidate, x.harmonic, x.dof): x for x in v.rows}
    assert len(got) == len(direct.rows) == 3
    for x in direct.rows:
        y = got[(x.candidate, x.harmonic, x.dof)]
        assert y.status == x.status
        assert y.worst_db == pytest.approx(x.worst_db, abs=1e-6)
        assert y.freq == x.freq
    assert [s.candidate for s in v.ranking] == [s.candidate for s in direct.ranking]
    # the delivery of each candidate is beside it, and the CSV has all three tables
    assert [d.candidate for d in v.deliveries] == ["reference", "soft.h5", "stiff.h5"]
    csv = v.to_csv().decode()
    assert "# table: verdict" in csv and "# table: ranking" in csv and "# table: delivery" in csv


def test_the_incumbent_rule_judges_the_others_against_it(tmp_path, tires):
    st, store = _session(tmp_path, tires)
    assert st.data.set_incumbent("reference", 0.0), st.data.error
    v = store.verdict.core["verdict"]
    # the incumbent against itself: level equal to target everywhere passes with margin 0
    for x in v.rows:
        if x.candidate == "reference":
            assert x.status == "pass" and x.margin_db == pytest.approx(0.0, abs=1e-9)
    # a candidate against the incumbent: the largest level difference of the direct paths
    k = 5
    ref = response_level(_direct(None, k).sel(outputs="bushing:x"))[:, 0]
    soft = response_level(_direct(tires["soft.h5"], k).sel(outputs="bushing:x"))[:, 0]
    expect = float(np.max(20 * np.log10(soft) - 20 * np.log10(ref)))
    assert v.row("soft.h5", k, "bushing:x").worst_db == pytest.approx(expect, abs=1e-6)


@pytest.mark.parametrize(
    ("text", "name", "words"),
    [
        (b"# quantity: mobility\nfreq [Hz],bushing:q\n10,1e-3\n100,1e-3\n", "t.csv", "bushing:q"),
        (b"# quantity: mobility\nfreq [Hz],hub:z\n10,1e-3\n100,1e-3\n", "t.csv", "hub:z"),
        (b"# quantity: mobility\nfreq [Hz],bushing:z\n10,nan\n100,1e-3\n", "t.csv", "line"),
        (b"# units: N/m\nfreq [Hz],bushing:z\n10,1e-3\n100,1e-3\n", "t.csv", "N/m"),
        (b"# quantity: mobility\nfreq [Hz],bushing:z\n100,1e-3\n10,1e-3\n", "t.csv", "line"),
        (b"freq,bushing:z\n10,1\n", "t.xlsx", ".xlsx"),
    ],
)
def test_a_bad_target_file_is_named_and_changes_nothing(text, name, words):
    ds = DataSource()
    assert ds.add_target(Target.segments("bushing:y", [(10.0, -20.0), (100.0, -30.0)]))
    before = ds.review
    assert not ds.load_targets(text, name)
    assert name in ds.error and words in ds.error, ds.error
    assert ds.review is before


def test_the_candidate_limit_is_a_message(tmp_path):
    ds = DataSource()
    small = _tire(n_modes=60)
    for i in range(MAX_CANDIDATES - 1):  # the reference is the first
        small = TireModel(
            small.speeds, small.poles, small.psi, small.chi, small.wavelengths,
            small.participation, meta={"source": f"c{i}"},
        )  # fmt: skip
        assert ds.load_tire(_bytes(tmp_path, small, f"c{i}.h5"), f"c{i}.h5"), ds.error
    before = (ds.review, ds.models)
    extra = TireModel(
        small.speeds, small.poles, small.psi, small.chi, small.wavelengths,
        small.participation, meta={"source": "one too many"},
    )  # fmt: skip
    assert not ds.load_tire(_bytes(tmp_path, extra, "extra.h5"), "extra.h5")
    assert f"at most {MAX_CANDIDATES}" in ds.error or f"holds {MAX_CANDIDATES}" in ds.error
    assert (ds.review, ds.models) == before


def test_a_pin_of_a_loaded_candidate_is_never_lost(tmp_path, tires):
    st, store = _session(tmp_path, tires)
    st.case.n_modes = 60
    store.pin("p1")  # of the stiff tire (current)
    assert st.data.select_candidate("soft.h5")
    store.pin("p2")
    assert st.data.select_candidate("reference")
    notes = {p.settings.name: p.note for p in store.pins}
    assert "not loaded" not in notes["p1"] and "not loaded" not in notes["p2"], notes
    # removing a candidate loses its pins' data (said), never the others'
    assert st.data.remove_candidate("stiff.h5")
    notes = {p.settings.name: p.note for p in store.pins}
    assert "not loaded" in notes["p1"] and "not loaded" not in notes["p2"], notes


def test_typed_points_are_parsed_and_bad_ones_named():
    from app.views.review import parse_points

    assert parse_points("20:-20, 200:-30") == [(20.0, -20.0), (200.0, -30.0)]
    assert parse_points("20=-20; 1e2 : -25") == [(20.0, -20.0), (100.0, -25.0)]
    for bad, word in (("20", "20"), ("20:-20", "two points"), ("a:1, 2:3", "a:1")):
        with pytest.raises(fbs_core.FBSError, match=word):
            parse_points(bad)


def test_the_reports_first_section_is_the_verdict(tmp_path, tires):
    from app.report.html import build_html
    from app.report.session import report_data

    st, store = _session(tmp_path, tires)
    assert st.data.set_incumbent("reference", 1.0), st.data.error
    _name, text = build_html(report_data(store, url="http://localhost:5006/main"))
    assert 0 < text.index('id="verdict"') < text.index('id="summary"')
    v = store.verdict.core["verdict"]
    for s in v.ranking:  # every candidate ranked in the report, in the verdict's order
        assert f"<td>{s.candidate}</td>" in text
    assert text.count("<td>fail</td>") + text.count("<td>pass</td>") >= len(v.rows)


def test_the_cards_controls_change_the_review(tmp_path, tires):
    """The card without a server: its widgets' callbacks reach the data source."""
    from app.views.review import ReviewView

    st, store = _session(tmp_path, tires)
    view = ReviewView(store=store)
    view.__panel__()
    assert view.current.options == ["reference", "soft.h5", "stiff.h5"]
    assert view.current.value == "stiff.h5"
    view.current.value = "soft.h5"
    assert st.data.review.candidates.current.name == "soft.h5"
    view.cand_supplier.value = "X"
    view.describe.clicks += 1
    assert st.data.review.candidates.get("soft.h5").supplier == "X"
    view.seg_points.value = "20:-20, 90:-25"
    view.seg_harmonic.value = "4"
    view.seg_add.clicks += 1
    (t,) = st.data.review.targets
    assert (t.dof, t.harmonic, list(t.freq)) == ("bushing:z", 4, [20.0, 90.0])
    assert "Ranking" in view.verdict_text.text and "soft.h5" in view.verdict_text.text
    view.seg_points.value = "20"
    view.seg_add.clicks += 1
    assert "typed target" in st.data.error and len(st.data.review.targets) == 1
    view.incumbent.value = "reference"
    view.margin.value = 2.0
    view.use_incumbent.clicks += 1
    assert st.data.review.incumbent.margin_db == 2.0
    view.clear.clicks += 1
    assert st.data.review.targets == () and st.data.review.incumbent is not None
    view.current.value = "stiff.h5"
    view.remove.clicks += 1
    assert st.data.review.candidates.names == ("reference", "soft.h5")
    st.noise.rounds = 50  # the band switch: a band per candidate and harmonic
    view.band_switch.value = True
    assert st.noise.verdict_band and "with the noise band" in store.verdict.caption
    st.noise.verdict_band = False
    assert view.band_switch.value is False


def test_the_response_plot_draws_the_other_candidates_and_the_target(tmp_path, tires):
    from app.views.mobility import MobilityView

    st, store = _session(tmp_path, tires)  # the stiff tire is current
    st.case.param.update(harmonic=H, dof="z")
    f = fbs_core.harmonic(H).frequencies()
    assert st.data.add_target(
        Target.segments("bushing:z", [(f[0], -10.0), (f[-1], 10.0)], axis="linear")
    )
    view = MobilityView(store=store)
    view.__panel__()
    d = store.review_curves.draw
    assert [c["name"] for c in d["curves"]] == ["reference", "soft.h5"]
    cands = st.data.review.candidates
    for c in d["curves"]:
        model = None if c["name"] == "reference" else tires[c["name"]]
        h = _direct(model, H).sel(outputs="bushing:z").data[:, 0, 0]
        np.testing.assert_allclose(c["y"], 20 * np.log10(np.abs(h)), atol=1e-6)
        # drawn in the candidate's colour slot, on the plot's own source
        src = next(m for m in view._fig.select({"name": f"mobility.candidate{c['slot']}"}))
        np.testing.assert_allclose(src.data["level"], c["y"])
        assert c["slot"] == cands.slot(c["name"])
    # the target: straight in dB over frequency between its two points
    np.testing.assert_allclose(d["target"], -10.0 + 20.0 * (f - f[0]) / (f[-1] - f[0]), atol=1e-9)
    tsrc = next(m for m in view._fig.select({"name": "mobility.target"}))
    np.testing.assert_allclose(tsrc.data["level"], d["target"])
    # another DOF without a target: no target line drawn
    st.case.dof = "x"
    assert store.review_curves.draw["target"] is None
    assert not view._target_item.visible


def test_the_link_restores_the_review_where_its_files_are_loaded(tmp_path, tires):
    from app.review import read_review_link, review_link

    st, store = _session(tmp_path, tires)
    ds = st.data
    f = fbs_core.harmonic(H).frequencies()
    assert ds.load_targets(_target_csv(-3.25, f), "target.csv"), ds.error
    assert ds.add_target(Target.segments("bushing:x", [(20.0, -20.1), (90.0, -30.7)]))
    assert ds.set_incumbent("soft.h5", 1.5) and ds.select_candidate("soft.h5")
    text = review_link(ds.review)
    before = store.verdict.core["verdict"]

    # a new session opens the link: targets and the rule's wish at once, the files pending
    st2 = DashboardState()
    store2 = Results(st2)
    assert st2.data.apply_link(text), st2.data.error
    got = {(t.dof, t.harmonic): t for t in st2.data.review.targets}
    for t in ds.review.targets:  # exact levels, not rounded
        g = got[(t.dof, t.harmonic)]
        assert (g.axis, g.quantity) == (t.axis, t.quantity)
        np.testing.assert_array_equal(g.freq, t.freq)
        np.testing.assert_array_equal(g.level_db, t.level_db)
    want = st2.data.pending
    assert len(want.candidates) == 2 and want.current and want.incumbent[1] == 1.5
    # the link keeps asking for them
    assert read_review_link(review_link(st2.data.review, want)).candidates == want.candidates
    # the files uploaded in the other order: once all are there, the link's order and
    # colours are restored, and its current candidate stays current
    for name in ("stiff.h5", "soft.h5"):
        assert st2.data.load_tire(_bytes(tmp_path, tires[name], name), name), st2.data.error
    assert st2.data.pending is None
    r2 = st2.data.review
    assert r2.candidates.names == ds.review.candidates.names
    assert [r2.candidates.slot(n) for n in r2.candidates.names] == [
        ds.review.candidates.slot(n) for n in ds.review.candidates.names
    ]
    assert review_link(r2) == text
    assert r2.candidates.current.name == "soft.h5" and r2.incumbent.candidate == "soft.h5"
    after = store2.verdict.core["verdict"]
    rows = {(x.candidate, x.harmonic, x.dof): x for x in after.rows}
    assert len(rows) == len(before.rows)
    for y in before.rows:  # (the candidates in the order their files came)
        x = rows[(y.candidate, y.harmonic, y.dof)]
        assert x.status == y.status
        assert x.worst_db == pytest.approx(y.worst_db, abs=1e-9, nan_ok=True)


@pytest.mark.parametrize(
    "text",
    ["c:abc$", "inc:abc:nan", "t:bushing:z:*:log:mobility:1:20_-20_30", "zz:1", "t:bushing:z"],
)
def test_a_crafted_review_link_is_named_and_changes_nothing(text):
    ds = DataSource()
    assert ds.add_target(Target.segments("bushing:y", [(10.0, -20.0), (100.0, -30.0)]))
    before = ds.review
    assert not ds.apply_link(text)
    assert "link" in ds.error and ds.review is before and ds.pending is None


def test_the_noise_band_judges_a_target_only_its_upper_edge_crosses():
    """A flat target between the nominal response's peak and the noise band's upper 95 %
    edge there: the nominal passes, the band does not. Truth: the core's own band of the
    same noise settings (same seed, so the same rounds) and the core's verdict of it."""
    from fbs_core.verdict import NoiseEdge

    st = DashboardState()
    store = Results(st)
    st.noise.param.update(noise=10.0, target="both", rounds=300, seed=7, percentile=90)
    nominal = _direct(None, H)
    band = fbs_core.scatter_band(
        H, noise=0.1, target="both", rounds=300, seed=7, n_modes=None, percentiles=(5.0, 95.0)
    )
    z = list(band.dofs).index("bushing:z")
    peak = 20 * np.log10(response_level(nominal.sel(outputs="bushing:z"))[:, 0].max())
    edge_peak = 20 * np.log10(band.percentiles[1][:, z].max())
    assert edge_peak > peak + 0.2  # 10 % noise lifts the 95 % edge above the nominal peak
    level = peak + (edge_peak - peak) / 2
    f = fbs_core.harmonic(H).frequencies()
    assert st.data.load_targets(_target_csv(level, f), "target.csv"), st.data.error
    row = store.verdict.core["verdict"].row("reference", H, "bushing:z")
    assert row.status == "pass"
    assert row.margin_db == pytest.approx((edge_peak - peak) / 2, abs=1e-6)
    st.noise.verdict_band = True
    r = store.verdict
    assert "noise band" in r.caption and "upper 95 % edge of 300 rounds" in r.meta["noise band"]
    v = r.core["verdict"]
    assert v.row("reference", H, "bushing:z").status == "fails within the noise band"
    direct = verdict(
        {("reference", H): nominal},
        st.data.review.targets,
        {("reference", H): NoiseEdge.of_band(band, 95.0)},
    )
    assert [(x.status, x.worst_db, x.freq) for x in v.rows] == [
        (x.status, pytest.approx(x.worst_db, abs=1e-6), x.freq) for x in direct.rows
    ]
    # another noise level is another band: more noise, a higher edge, still within the band
    st.noise.noise = 20.0
    assert store.verdict.meta["noise band"].startswith("upper 95 % edge of 300 rounds, noise 20")
    # off again: the nominal verdict
    st.noise.verdict_band = False
    assert store.verdict.core["verdict"].row("reference", H, "bushing:z").status == "pass"


def test_the_verdicts_bands_leave_the_pages_bands_in_the_cache(tmp_path, tires):
    """The verdict's noise band is a band per candidate and harmonic (here 3 x 7): it keeps
    their upper edges only, so the scatter bands the session's pages show stay cached (the
    process keeps :data:`app.compute.BAND_CACHE_SIZE`)."""
    from app import compute

    st, store = _session(tmp_path, tires)
    st.noise.param.update(noise=5.0, rounds=40, seed=11)
    st.case.param.update(harmonic=2, n_modes=40, dof="z")
    store.request_band(wait=True)
    before = list(compute._bands)
    assert before, "the page's band is cached"
    f = fbs_core.harmonic(H).frequencies()
    assert st.data.load_targets(_target_csv(0.0, f), "target.csv"), st.data.error
    st.noise.verdict_band = True
    r = store.verdict
    assert "noise band" in r.caption
    rows = r.core["verdict"].rows
    assert {x.candidate for x in rows} == {"reference", "soft.h5", "stiff.h5"}
    assert all(np.isfinite(x.band_worst_db) for x in rows)
    # every band the pages had is still cached, and none of the verdict's 21 was kept
    assert set(compute._bands) == set(before)


def test_the_other_candidates_bands_are_the_cores_bands_of_their_tires(tmp_path, tires):
    """The scatter plot's other candidates: each one's central band at the page's band
    settings. Truth: the core's scatter band of that tire (same seed: the same rounds)."""
    st, store = _session(tmp_path, tires)  # current: stiff.h5
    st.noise.param.update(noise=5.0, rounds=200, seed=3, percentile=80)
    st.case.param.update(harmonic=2, n_modes=60, dof="x")
    r = store.review_bands
    got = {c["name"]: c for c in r.draw["curves"]}
    assert set(got) == {"reference", "soft.h5"} and not r.draw["pending"]
    for name, model in (("reference", None), ("soft.h5", tires["soft.h5"])):
        kw = {} if model is None else {"tire": model}
        band = fbs_core.scatter_band(
            2, noise=0.05, rounds=200, seed=3, n_modes=60, percentiles=(10.0, 90.0), **kw
        )
        j = list(band.dofs).index("bushing:x")
        np.testing.assert_allclose(got[name]["low"], 20 * np.log10(band.percentiles[0][:, j]))
        np.testing.assert_allclose(got[name]["high"], 20 * np.log10(band.percentiles[1][:, j]))
        assert got[name]["slot"] == st.data.review.candidates.slot(name)
    assert r.meta["percentiles"] == "10-90" and "soft.h5" in r.meta["candidates"]
    # drawn on the band plot in each candidate's colour, beside the page's own band
    from app.views.scatter import ScatterBandView

    store.request_band(wait=True)
    view = ScatterBandView(store=store)
    view.__panel__()
    for c in got.values():
        src = next(m for m in view._fig.select({"name": f"scatter.candidate{c['slot']}"}))
        np.testing.assert_allclose(src.data["high"], c["high"])
        assert view._cand_items[c["slot"]].visible
    # the current candidate's band is the page's own, not drawn again
    st.data.select_candidate("soft.h5")
    assert {c["name"] for c in store.review_bands.draw["curves"]} == {"reference", "stiff.h5"}


def test_the_band_plot_draws_the_target_its_upper_edge_is_judged_against(tmp_path, tires):
    """The scatter-band plot draws the target of the shown DOF and harmonic (what the
    verdict's noise band is judged against): a typed target straight in dB, then the
    incumbent rule's line (its all-modes response + margin). Truth: the typed points, and
    the core's response of the incumbent's tire."""
    from app.views.scatter import ScatterBandView

    st, store = _session(tmp_path, tires)
    st.noise.param.update(rounds=30, seed=2)
    st.case.param.update(harmonic=H, n_modes=40, dof="y")
    f = fbs_core.harmonic(H).frequencies()
    assert st.data.add_target(
        Target.segments("bushing:y", [(f[0], -30.0), (f[-1], -10.0)], axis="linear")
    )
    store.request_band(wait=True)
    view = ScatterBandView(store=store)
    view.__panel__()
    want = -30.0 + 20.0 * (f - f[0]) / (f[-1] - f[0])
    np.testing.assert_allclose(store.review_bands.draw["target"], want, atol=1e-9)
    src = next(m for m in view._fig.select({"name": "scatter.target"}))
    np.testing.assert_allclose(src.data["level"], want, atol=1e-9)
    assert view._target_item.visible and "bushing:y" in view._target_item.label.value
    assert "bushing:y" in store.review_bands.meta["target line"]
    # another DOF without a target: the line goes
    st.case.dof = "z"
    store.request_band(wait=True)
    view.redraw()
    assert store.review_bands.draw["target"] is None and not view._target_item.visible
    # the incumbent rule: soft.h5's all-modes response + 2 dB at the shown DOF
    assert st.data.clear_targets() and st.data.set_incumbent("soft.h5", 2.0)
    inc = _direct(tires["soft.h5"], H).sel(outputs="bushing:z").data[:, 0, 0]
    got = store.review_bands.draw
    np.testing.assert_allclose(got["target"], 20 * np.log10(np.abs(inc)) + 2.0, atol=1e-6)
    assert "incumbent soft.h5 +2 dB" in got["target_label"]


def test_in_vehicle_scope_the_other_candidates_bands_are_the_cars(tmp_path, tires):
    """The car's scatter plot draws the other candidates' bands of the car with their tire
    on the four wheels, at the page's point and road. Truth: the core's car band of that
    tire (same seed: the same draws); on an incoherent road none (as the page's band)."""
    from fbs_core.vehicle import vehicle_scatter_band

    st, store = _session(tmp_path, tires)  # current: stiff.h5
    st.noise.param.update(noise=5.0, rounds=60, seed=4, percentile=90)
    st.case.param.update(
        scope="vehicle", harmonic=3, n_modes=80, point="seat_rl", dof="z", tracks="anti-phase",
        wheels=["fl", "rl"],
    )  # fmt: skip
    r = store.review_bands
    got = {c["name"]: c for c in r.draw["curves"]}
    assert set(got) == {"reference", "soft.h5"} and not r.draw["pending"]
    for name, model in (("reference", None), ("soft.h5", tires["soft.h5"])):
        kw = {} if model is None else {"tire": model}
        band = vehicle_scatter_band(
            3, noise=0.05, rounds=60, seed=4, n_modes=80, outputs="seat_rl",
            tracks="anti-phase", wheels=("fl", "rl"), percentiles=(5.0, 95.0), **kw,
        )  # fmt: skip
        j = list(band.dofs).index("seat_rl:z")
        np.testing.assert_allclose(got[name]["low"], 20 * np.log10(band.percentiles[0][:, j]))
        np.testing.assert_allclose(got[name]["high"], 20 * np.log10(band.percentiles[1][:, j]))
    assert r.meta["response DOF"] == "seat_rl:z" and r.meta["response point"] == "seat_rl"
    assert "_car_" in r.filename
    # drawn on the car's band plot beside the page's own band
    from app.views.scatter import ScatterBandView

    store.request_band(wait=True)
    view = ScatterBandView(store=store)
    view.__panel__()
    for c in got.values():
        src = next(m for m in view._fig.select({"name": f"scatter.candidate{c['slot']}"}))
        np.testing.assert_allclose(src.data["high"], c["high"])
        assert view._cand_items[c["slot"]].visible
    # an incoherent road has no car band: none drawn
    st.case.param.update(tracks="coherence", coherence=0.4)
    assert store.review_bands.draw["curves"] == []


def test_a_link_whose_current_tire_is_the_reference_keeps_it_current(tmp_path, tires):
    from app.review import review_link

    st, _store = _session(tmp_path, tires)
    assert st.data.select_candidate("reference")
    text = review_link(st.data.review)
    st2 = DashboardState()
    Results(st2)
    assert st2.data.apply_link(text), st2.data.error
    for name in ("stiff.h5", "soft.h5"):  # each upload would become current by itself
        assert st2.data.load_tire(_bytes(tmp_path, tires[name], name), name), st2.data.error
        assert st2.data.review.candidates.current.name == "reference"
    assert st2.data.pending is None and review_link(st2.data.review) == text
    assert st2.data.models.is_reference  # the session's tire is the current candidate's


def test_in_vehicle_scope_the_other_candidates_are_the_cars_with_their_tires(tmp_path, tires):
    """The coupled-response plot of the car draws the other candidates at the page's point,
    DOF and road. Truth: the core's car response with each tire on its four wheels."""
    from fbs_core.vehicle import vehicle_response

    st, store = _session(tmp_path, tires)  # current: stiff.h5
    st.case.param.update(
        scope="vehicle", harmonic=1, point="bushing_rr", dof="y", tracks="anti-phase",
        wheels=["fl", "rr"],
    )  # fmt: skip
    d = store.review_curves.draw
    assert [c["name"] for c in d["curves"]] == ["reference", "soft.h5"] and not d["pending"]
    for c in d["curves"]:
        kw = {} if c["name"] == "reference" else {"tire": tires[c["name"]]}
        want = vehicle_response(
            1, None, fbs_core.harmonic(1).frequencies(), tracks="anti-phase",
            wheels=("fl", "rr"), outputs="bushing_rr", **kw,
        )  # fmt: skip
        e = list(want.response.outputs).index("bushing_rr:y")
        np.testing.assert_allclose(c["y"], 20 * np.log10(want.level[:, e]), atol=1e-9)
    assert store.review_curves.meta["response DOF"] == "bushing_rr:y"
    # another point: the candidates follow it
    st.case.point = "seat_fl"
    assert store.review_curves.meta["response point"] == "seat_fl"
