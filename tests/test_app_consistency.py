"""One source of truth (issue 27): every field of a session's state against every output.

For each field of the state (the case, the noise study, the truncation study, the Analysis
card's settings, the pins, the uploaded models, the campaign card's file and case) the field
is changed and every output of
the session is read again: the published results (their CSV columns, the data they draw,
their CSV header, file name, caption and plot title block) and the report (its data,
tables, settings table, file name and title block). Then

- an output that is *not declared* to depend on the field keeps its numbers bit for bit
  and its description word for word;
- an output *declared* to depend on it names the new value in its description (title
  block, CSV header, report settings table, file name) when anything of it changed, and
  for the fields of the case its file name changes whenever its exported data do;
- the same quantity shown in two places is the same number: the Compare tab's current
  curve, a pin's current curve, the phase view's coupled curves, the contributions' total
  and the report's coupled response are the coupled-response view's; the report's error
  map, suggested N, band and eigenfrequencies are those of their views.

Truth: what is declared is read from the store's table (:data:`app.store.TABLE`, and for
the report the settings it names), what is shown from the outputs; the cross-checks
compare two outputs, never an output with itself.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import fbs_core
from app.datasource import Models
from app.page.titles import view_title
from app.report import report_content
from app.report.session import depends as report_depends
from app.report.session import report_data
from app.results import FIELDS, Result
from app.review import EMPTY_REVIEW, Review
from app.store import TABLE, Results, depends
from fbs_core.campaign import parse_campaign, run_campaign
from fbs_core.targets import Target
from fbs_core.tire import TireModel

CREATED = dt.datetime(2026, 1, 2, tzinfo=dt.UTC)

#: The base state: two pins (the base itself and a 5-DOF coupling) for the comparison.
BASE = {
    "harmonic": 3,
    "n_modes": 60,
    "dof": "z",
    "coupling": "6dof",
    "residual": False,
    "show_uncoupled": True,
    "spindle_input": "z",
    "noise": 10.0,
    "target": "both",
    "frequency_dependent": False,
    "rounds": 40,
    "seed": 5,
    "single_round": 2,
    "percentile": 90,
    "first_order": True,
    "threshold": 20.0,
    "f_max": 160.0,
    "map_mode": "selected DOF",
    "frf": "coupled",
    "phase_mode": "bode",
    "log_freq": False,
    "cursor1": 30.0,
    "cursor2": 55.0,
    "picked_speed": 0.0,
    "picked_freq": 0.0,
    "contrib_mode": "lines",
    "compare_to": "",
    "overlay": [],
    "level_scale": "dB",
    "mcursor1": 30.0,
    "mcursor2": 45.0,
    "snap": False,
    "scope": "corner",
    "wheels": ["fl", "fr", "rl", "rr"],
    "tracks": "in phase",
    "coherence": 0.5,
    "point": "bushing_rl",
    "mode_pick": -1,
    "mode_speed": 0.0,
    "mode_rank": "loo",
    "waves_all": False,
}
#: The campaign file of the walk's session (two scatter cases, one truncation case).
CAMPAIGN_TOML = """
[campaign]
name = "walk"
seed = 3
output = "{out}"
[scatter]
harmonics = [1]
noise = [0.05, 0.1]
targets = ["both"]
frequency_dependent = [false]
rounds = 50
[truncation]
harmonics = [1]
n_modes = {{ from = 10, to = 30, step = 10 }}
thresholds = [0.2]
f_max = [130.0]
couplings = ["6dof"]
"""
#: Its cases' names (the walk shows the first and changes to the second).
CAMPAIGN_CASES = [
    c.name for c in parse_campaign(CAMPAIGN_TOML.format(out="walk.h5"), Path(".")).band_cases
]
#: The base state of the walk in vehicle scope (issue 31): the car, its rear-left bushing.
BASE_VEHICLE = {**BASE, "scope": "vehicle"}

#: Views with a title block on the page: published result -> the view's key.
TITLED = {
    "response": "mobility",
    "error_map": "truncation",
    "band_curves": "scatter",
    "eigen": "eigen",
    "uncoupled": "uncoupled",
    "compare": "compare",
    "contributions": "contributions",
    "phase": "phase",
    "campbell": "campbell",
    "speed_map": "speedmap",
    "wheel_contributions": "wheels",
    "participation": "participation",
    "mode_shape": "modeshape",
    "waves": "waves",
    "selected_modes": "selected",
    "chassis_truncation": "chassistrunc",
}
#: The tabs of the Analysis card (their results are computed while shown).
TABS = sorted({row.tab for row in TABLE if row.tab})
#: Fields of the case: an output whose exported data change with one of them says so in its
#: file name (two files of other numbers never share a name).
CASE = (
    "harmonic", "n_modes", "dof", "coupling", "residual", "models",
    "scope", "wheels", "tracks", "coherence", "point",
)  # fmt: skip
#: What a result draws that is not a result: the time its computation took.
NOT_RESULTS = ("seconds",)


def small_tire() -> TireModel:
    """The reference tire cut to its first 120 modes (an upload that is cheap to study)."""
    t = fbs_core.reference_tire()
    m = slice(0, 120)
    return TireModel(
        t.speeds, t.poles[:, m], t.psi[:, m], t.chi[:, m], t.wavelengths,
        t.participation[:, :, m], meta={"source": "test"},
    )  # fmt: skip


UPLOAD = Models(tire=small_tire(), key="tire=consistency120", tire_name="tire120.h5")
#: A review with one typed target (the verdict of the reference against it).
REVIEW = Review(None, (Target.segments("bushing:z", [(20.0, -20.0), (90.0, -30.0)]),))


# -- one session and what it shows ------------------------------------------------------------
@dataclasses.dataclass
class Output:
    numbers: list  # arrays and texts, in a fixed order
    data: list  # what is exported (the CSV columns; the report's data)
    description: list[str]  # lines: CSV header, file name, caption, title block
    filename: str


def _numbers(x: Any, out: list) -> None:
    """The numbers in ``x`` (arrays, numbers, nested dicts / sequences), in a fixed order."""
    if isinstance(x, np.ndarray):
        if x.dtype.kind in "biufc":
            out.append(np.array(x))
        elif x.dtype.kind == "O":
            for v in x.ravel():
                _numbers(v, out)
    elif isinstance(x, bool | int | float | complex | np.number):
        out.append(np.asarray(x))
    elif isinstance(x, dict):
        for k in sorted(x, key=str):
            _numbers(x[k], out)
    elif isinstance(x, list | tuple):
        for v in x:
            _numbers(v, out)


class Session:
    """A session's store (no server: everything computed in place) and its outputs."""

    def __init__(self, base: dict = BASE):
        self.base = base
        self.store = Results(background=False)
        self.set(**dict(base))
        self.store.request_band(wait=True)
        self.pin("p1")
        self.set(coupling="5dof")
        self.pin("p2")
        self.set(coupling="6dof")

    @property
    def state(self):
        return self.store.state

    def set(self, **fields) -> None:
        for name, value in fields.items():
            group, p = FIELDS[name]
            setattr(getattr(self.state, group), p, value)

    def get(self, name: str):
        group, p = FIELDS[name]
        return getattr(getattr(self.state, group), p)

    def pin(self, name: str) -> None:
        self.store.pin(name)
        assert self.store.message == "", self.store.message

    # -- what is declared ----------------------------------------------------------------------
    def declared(self, name: str) -> set[str]:
        """The state fields output ``name`` is declared to depend on (the store's table)."""
        name = name.split("-")[0]
        if name != "report":
            return set(depends(name))
        out: set[str] = set()  # the report of each tab (as _report_output reads it)
        for tab in ("", *TABS):
            self.state.analysis.tab = tab
            out |= report_depends(self.store)
        self.state.analysis.tab = ""
        return out

    # -- what is shown ---------------------------------------------------------------------------
    def results(self) -> dict[str, Result]:
        """Every published result that is current, each tab's on its tab."""
        out: dict[str, Any] = {}
        for tab in ("", *TABS):
            self.state.analysis.tab = tab
            out.update(self.store.current()[1])
        self.state.analysis.tab = ""
        res: dict[str, Result] = {}
        for name, value in out.items():
            if isinstance(value, Result):
                res[name] = value
            elif name == "pinned":
                res.update({f"pinned-{i + 1}": r for i, r in enumerate(value)})
        return res

    def outputs(self) -> dict[str, Output]:
        res = self.results()
        out = {name: _result_output(name, r) for name, r in res.items()}
        out["report"] = _report_output(self)
        return out


def _title(name: str, r: Result) -> list[str]:
    """The title block the view of result ``name`` draws (of the result's snapshot), as
    :func:`app.page.titles.view_title` makes it, without the time of day (no setting: a
    walk that crosses a minute would see it change)."""
    if name not in TITLED:
        return []
    tb, stem = view_title(TITLED[name], r.snapshot)
    # the time of day is not a setting (a walk on a busy machine crosses minutes)
    lines = [re.sub(r"\d\d:\d\d UTC", "hh:mm UTC", line) for line in tb.lines]
    return [tb.what, *lines, stem]


def _result_output(name: str, r: Result) -> Output:
    desc = [f"{k}: {v}" for k, v in r.meta.items()] + [r.filename, r.caption]
    data: list = []
    _numbers(dict(r.columns), data)
    nums = list(data)
    _numbers({k: v for k, v in r.draw.items() if k not in NOT_RESULTS}, nums)
    return Output(nums, data, desc + _title(name.split("-")[0], r), r.filename)


def _report(session: Session):
    """The report of every tab's results (each report holds the shown tab's)."""
    return report_data(session.store, url="http://localhost:5006/main", created=CREATED)


def _report_output(session: Session) -> Output:
    nums: list = []
    desc: list[str] = []
    stem = ""
    for tab in ("", *TABS):
        session.state.analysis.tab = tab
        snap = _report(session)
        rep = report_content(snap)
        for x in (snap.reference, snap.truncated):
            if x is not None:
                nums.append(np.asarray(x.data))
        if rep.verdict is not None:  # the review's verdict: its tables name the targets
            for t in (*rep.verdict.tables, *rep.verdict.long_tables):
                nums.append(np.array([c for row in t.rows for c in row], dtype=object))
                desc += [" | ".join(row) for row in t.rows]
        for sec in rep.sections:
            for t in sec.tables:
                nums.append(np.array([c for row in t.rows for c in row], dtype=object))
            for p in sec.paragraphs:
                nums.append(np.array([p], dtype=object))
        for ex in snap.extra:
            desc += [f"{ex.key}: {k}: {v}" for k, v in ex.rows]
            if ex.freq is not None:
                nums += [np.asarray(ex.freq)] + [np.asarray(c) for c in ex.curves.values()]
        desc += [" | ".join(row) for row in rep.settings.rows]
        desc += [" | ".join(row) for row in rep.provenance.rows]
        desc += [rep.stem, rep.title, rep.title_block.what, *rep.title_block.lines]
        stem = rep.stem
    session.state.analysis.tab = ""
    return Output(nums, nums, desc, stem)


def _report_numbers(session: Session) -> dict[str, np.ndarray]:
    """The report's numbers of each shared quantity."""
    snap = _report(session)
    out = {}
    dof = snap.response_dof
    if snap.truncated is not None:
        out["truncated"] = snap.truncated.sel(outputs=dof).data[:, 0, 0]
        out["reference"] = snap.reference.sel(outputs=dof).data[:, 0, 0]
    if snap.truncation is not None:
        m = snap.truncation
        err = m.max_error if snap.map_dof is None else m.dof_error(snap.map_dof)
        out["error_pct"] = 100 * np.asarray(err, float)
    if snap.suggested is not None:
        out["suggested"] = np.asarray(snap.suggested.n_modes)
    if snap.band is not None:
        j = snap.band.dofs.index(dof)
        out["band_max"] = np.asarray(snap.band.maximum[:, j])
    if snap.eigen is not None:
        out["eigen_80"] = np.asarray(snap.eigen.frequency[list(snap.eigen.speeds).index(80.0)])
    return out


# -- the fields and their changes -------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Change:
    field: str
    apply: Callable[[Session], None]
    names: tuple[str, ...]  # how a description names the new value (one of them, regex)


def _to(field: str, value, *names: str) -> Change:
    return Change(field, lambda s: s.set(**{field: value}), names)


def _add_pin(s: Session) -> None:
    s.set(n_modes=90)
    s.pin("p3")
    s.set(n_modes=60)


CHANGES = [
    _to("harmonic", 5, r"\bh5\b", r"[Hh]armonic:? 5\b"),
    _to("n_modes", 90, r"\bN\s?=\s?90\b", r"\bN90\b", r"\bN[^:]*: 90\b"),
    _to("dof", "x", r"bushing(_rl)?[:_-]x\b", r"hub[:-]x\b", r"\bdof\b.*\bx\b"),
    _to("coupling", "5dof", r"5dof", r"5-DOF"),
    _to("residual", True, r"residual[^:]*: (on|yes)", r"\+ residual", r"with residuals?\b"),
    _to("spindle_input", "y", r"spindle:y\b", r"spindle_input.*\by\b"),
    _to("noise", 4.0, r"\bp\s?=\s?4\b", r"noise[^:]*: 4\b", r"\bp4\b", r"noise 4\b"),
    _to("target", "tire", r"target.*\btire\b", r"\bin the tire\b", r"on the tire\b", r"p10-tire"),
    _to("frequency_dependent", True, r"every line", r"frequency dependent: (True|yes)", r"fdep"),
    _to("rounds", 30, r"\bR\s?=\s?30\b", r"rounds: 30\b", r"\bR30\b"),
    _to("seed", 9, r"\bseed:? 9\b", r"seed9"),
    _to("single_round", 7, r"round[^:]*:? #?7\b", r"round_7"),
    _to("percentile", 80, r"\b10-90\b", r"\b80 %"),
    _to("first_order", False, r"first_order\b.*\bno\b"),
    _to("threshold", 12.0, r"\b12 %", r"thr12", r"threshold[^:]*: 12\b"),
    _to("f_max", 230.0, r"\b230 Hz", r"fmax230", r"f_max[^:]*: 230\b"),
    _to("map_mode", "max over 6 DOFs", r"max over (the )?6", r"maxdof", r"max6"),
    _to("frf", "tire", r"\btire free hub velocity", r"phase_tire"),
    _to("phase_mode", "real/imag", r"real/imag"),
    _to("log_freq", True, r"\blog"),
    _to("cursor1", 40.0, r"f1 = 40 Hz"),
    _to("cursor2", 60.0, r"f2 = 60 Hz"),
    _to("picked_speed", 70.0, r"70 km/h"),
    _to("picked_freq", 45.0, r"45 Hz"),
    _to("contrib_mode", "stacked", r"stacked"),
    _to("mode_pick", 7, r"[Mm]ode 7\b", r"pair 7\b", r"_m7_"),
    _to("mode_speed", 61.0, r"\b61 km/h", r"_v61\b"),
    _to("mode_rank", "level", r"\blevel\b"),
    _to("waves_all", True, r"every branch", r"_all\b"),
    Change("pin_text", _add_pin, (r"\bp3\b",)),
    _to("compare_to", "p2", r"'p2'"),
    _to("overlay", ["x", "rz"], r"overlaid[^:]*: bushing:x, bushing:rz"),
    _to("level_scale", "linear", r"level axis: linear"),
    _to("mcursor1", 40.0, r"f1 = 40 Hz"),
    _to("mcursor2", 60.0, r"f2 = 60 Hz"),
    _to("snap", True, r"snapped to the peak nearest"),
    # the campaign card's file and case (the session's folder: CAMPAIGN_TOML's files)
    _to("campaign_file", "other.h5", r"other\.h5"),
    _to("campaign_case", CAMPAIGN_CASES[1], re.escape(CAMPAIGN_CASES[1])),
    _to("campaign_dof", "x", r"bushing:x\b"),
    _to("campaign_max", True, r"max over DOFs"),
    _to("campaign_harmonic", 1, r"harmonic 1\b"),
    # last: the reference models restored after it are a new object (the title blocks name
    # the time the data were set)
    _to("models", UPLOAD, r"tire120\.h5", r"upload"),
    _to("review", REVIEW, r"bushing:z h\w+ segments", r"\| bushing:z \|.*\| segments$"),
    # the car's fields (issue 31): in corner scope they change nothing
    _to("scope", "vehicle", r"\bvehicle\b", r"\bcar\b"),
    _to("wheels", ["fl", "rl"], r"\bFL RL\b", r"wflrl"),
    _to("tracks", "anti-phase", r"anti-?phase"),
    _to("coherence", 0.2, r"coherence 0\.2\b", r"coh0\.2"),
    _to("point", "seat_fl", r"seat_fl"),
]
#: The walk in vehicle scope: the car's fields, and the case's on the car.
CHANGES_VEHICLE = [
    c for c in CHANGES if c.field in ("scope", "wheels", "tracks", "point", "n_modes", "dof")
]
CHANGES_VEHICLE[CHANGES_VEHICLE.index(next(c for c in CHANGES if c.field == "scope"))] = _to(
    "scope", "corner", r"\bcorner\b", r"bushing_response", r"\bbushing:z\b"
)
CHANGES_VEHICLE.append(
    Change(
        "coherence",
        lambda s: s.set(tracks="coherence", coherence=0.2),
        (r"coherence 0\.2\b", r"coh0\.2"),
    )
)


def _same(a: list, b: list) -> bool:
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if x.shape != y.shape or x.dtype.kind != y.dtype.kind:
            return False
        if x.dtype.kind == "O":
            if list(x.ravel()) != list(y.ravel()):
                return False
        elif not np.array_equal(x, y, equal_nan=True):
            return False
    return True


def _names(lines: list[str], patterns: tuple[str, ...]) -> bool:
    return any(re.search(p, line) for line in lines for p in patterns)


@pytest.fixture(scope="module")
def campaign_folder(tmp_path_factory) -> Path:
    """A campaign folder with the walk's campaign file and a copy of it."""
    d = tmp_path_factory.mktemp("walk")
    camp = parse_campaign(CAMPAIGN_TOML.format(out=(d / "walk.h5").as_posix()), d)
    assert run_campaign(camp).status == "complete"
    shutil.copy(d / "walk.h5", d / "other.h5")
    return d.resolve()


@pytest.fixture(scope="module")
def session(campaign_folder):
    campaign = {
        "campaign_dir": campaign_folder,
        "campaign_file": "walk.h5",
        "campaign_case": CAMPAIGN_CASES[0],
        "campaign_dof": "z",
        "campaign_max": False,
        "campaign_harmonic": 0,
    }
    return Session({**BASE, **campaign})


@pytest.fixture(scope="module")
def base(session):
    return session.outputs()


def _restore(session: Session) -> None:
    session.set(**{k: v for k, v in session.base.items() if session.get(k) != v})
    session.set(models=Models(), review=EMPTY_REVIEW)
    if len(session.store.pins) > 2:
        session.store.unpin("p3")


@pytest.mark.parametrize("change", CHANGES, ids=[c.field for c in CHANGES])
def test_every_output_follows_every_field_or_declares_that_it_does_not(session, base, change):
    _walk(session, base, change)


@pytest.fixture(scope="module")
def vehicle_session():
    return Session(BASE_VEHICLE)


@pytest.fixture(scope="module")
def vehicle_base(vehicle_session):
    return vehicle_session.outputs()


@pytest.mark.parametrize("change", CHANGES_VEHICLE, ids=[c.field for c in CHANGES_VEHICLE])
def test_in_vehicle_scope_every_output_follows_every_field_or_declares_it_does_not(
    vehicle_session, vehicle_base, change
):
    _walk(vehicle_session, vehicle_base, change)


def _walk(session: Session, base: dict, change: Change) -> None:
    problems = []
    try:
        change.apply(session)
        after = session.outputs()
        for name in sorted(set(base) | set(after)):
            declared = change.field in session.declared(name)
            if name not in base or name not in after:  # a new pin, or one less
                shown = after.get(name)
                if (
                    not declared
                    or shown is not None
                    and not _names(shown.description, change.names)
                ):
                    problems.append(f"{name}: shown in one state only")
                continue
            old, new = base[name], after[name]
            same_numbers = _same(old.numbers, new.numbers)
            changed = [line for line in new.description if line not in old.description]
            if not declared:
                if not same_numbers:
                    problems.append(f"{name}: numbers changed, not declared to depend on it")
                elif changed:
                    problems.append(f"{name}: description changed ({changed[:2]}), not declared")
                continue
            if (changed or not same_numbers) and not _names(changed, change.names):
                problems.append(
                    f"{name}: its numbers or description changed with {change.field}, its "
                    f"description does not name the new value (changed lines: {changed[:3]})"
                )
            same_data = _same(old.data, new.data)
            if change.field in CASE and not same_data and new.filename == old.filename:
                problems.append(f"{name}: other numbers under the same file name {new.filename}")
        problems += _cross_check(session, after)
    finally:
        _restore(session)
    assert not problems, f"changing {change.field}:\n  " + "\n  ".join(problems)


def _close(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.allclose(a, b, rtol=1e-12, atol=0, equal_nan=True)


def _cross_check(session: Session, outputs: dict) -> list[str]:
    """The same quantity in two places is the same number (the coupled-response view's)."""
    res = session.results()
    resp = res["response"].columns
    level, ref = resp["truncated_dB"], resp["reference_dB"]
    bad = []
    if session.get("scope") == "vehicle":  # the car's views (the Analysis card: the corner)
        w = res.get("wheel_contributions")
        if w is None or not _close(w.columns["total_dB"], level):
            bad.append("wheel contributions: their total is not the coupled response shown")
        rep = _report_numbers(session)
        comp = [c for c in resp if c.startswith("truncated_") and c != "truncated_dB"]
        if "truncated" in rep and len(comp) == 1 and not _close(rep["truncated"], resp[comp[0]]):
            bad.append("report: its coupled response is not the one shown")
        if "error_pct" in rep and not _close(
            rep["error_pct"], res["error_map"].draw["map"]["error_pct"]
        ):
            bad.append("report: its error map is not the one shown")
        return bad
    cmp_ = res.get("compare")
    if cmp_ is not None and not _close(cmp_.draw["curves"][0]["level"], level):
        bad.append("compare: its current curve is not the coupled response shown")
    for k, r in enumerate(res[n] for n in res if n.startswith("pinned-")):
        if "current_dB" in r.columns and not _close(r.columns["current_dB"], level):
            bad.append(f"pin {k + 1}: its current curve is not the coupled response shown")
    ph = res.get("phase")
    if ph is not None and session.get("frf") == "coupled":
        c = ph.draw["curves"]
        if not (_close(c["N modes"]["level"], level) and _close(c["all modes"]["level"], ref)):
            bad.append("phase: its coupled curves are not the coupled response shown")
    co = res.get("contributions")
    if co is not None and not _close(co.columns["total_dB"], level):
        bad.append("contributions: their total is not the coupled response shown")
    rep = _report_numbers(session)
    if "truncated" in rep and not (
        _close(rep["truncated"], resp["truncated"]) and _close(rep["reference"], resp["reference"])
    ):
        bad.append("report: its coupled response is not the one shown")
    if "error_pct" in rep:
        shown = res["error_map"].draw["map"]["error_pct"]
        if not _close(rep["error_pct"], shown):
            bad.append("report: its error map is not the one shown")
    if "suggested" in rep:
        tab = res["suggested"].draw
        shown = tab["table_residual" if tab.get("residual") else "table"]["n_modes"]
        if not _close(rep["suggested"], shown):
            bad.append("report: its suggested N are not the ones shown")
    if "band_max" in rep:
        shown = res["band_curves"].columns["maximum_dB"]
        if not _close(20 * np.log10(rep["band_max"]), shown):
            bad.append("report: its band is not the one shown")
    if "eigen_80" in rep and not _close(rep["eigen_80"], res["eigen"].columns["f_80kmh_Hz"]):
        bad.append("report: its eigenfrequencies are not the ones shown")
    tab = res["suggested"].draw
    shown = tab["table_residual" if tab.get("residual") else "table"]
    k = list(shown["harmonic"]).index(session.get("harmonic"))
    if res["error_map"].draw["suggested_n"] != shown["n_modes"][k]:
        bad.append("error map: its suggested N is not the one the table shows")
    sel = res.get("selected_modes")  # table 5.1's lowest N beside the selections
    if (
        sel is not None
        and "n_modes" in sel.columns
        and sel.columns["n_modes"][0] != shown["n_modes"][k]
    ):
        bad.append("selected modes: the lowest N is not the one table 5.1 shows")
    ch = res.get("chassis_truncation")
    if ch is not None and "tire modes needed (table 5.1)" in ch.meta:
        if int(ch.meta["tire modes needed (table 5.1)"]) != shown["n_modes"][k]:
            bad.append("chassis truncation: the tire's N is not the one table 5.1 shows")
    part, shape = res.get("participation"), res.get("mode_shape")
    if (
        part is not None
        and shape is not None
        and shape.draw.get("ready")
        and session.get("mode_pick") < 0
        and shape.draw["mode"] != part.columns["mode"][0]
    ):
        bad.append("mode shape: not the first mode of the ranking shown")
    return bad


def test_every_result_of_the_table_is_an_output_of_the_test(session, base, vehicle_base):
    """The walk covers every published result (a row the test misses fails here; the
    car's per-wheel view in the walk of vehicle scope)."""
    names = {n.split("-")[0] for n in (*base, *vehicle_base)} | {"pins", "band"}
    assert names >= {row.name for row in TABLE}, {row.name for row in TABLE} - names
