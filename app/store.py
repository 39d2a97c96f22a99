"""One session's results, declared as a table, computed and published by one store.

Every number the page shows, exports and reports is a published result of the session's
:class:`Results`. Each result is one :class:`Row` of :data:`TABLE`:

- its **name** (the parameter of :class:`Results` it is published as),
- the **snapshot fields it depends on** (settings of the state, and the published band or
  pins it is made of),
- the **pure function of one** :class:`~app.results.Snapshot` that makes it
  (:mod:`app.results`),
- **when** it is computed: always, only while its tab of the Analysis card (or the
  uncoupled subsystems) is shown, or on a thread of its own (the scatter band), and the
  part done later in the background (the column with residuals of the suggested modes,
  the coupled modes near the peaks) or ahead (the speed map of the next N).

The store derives its watchers from the table: a change of a state field recomputes the
rows that depend on it (and the rows made of those), nothing else. "Does this output
depend on that setting?" is answered by reading one row (:func:`depends`), and
``tests/test_app_consistency.py`` walks the table and changes every field.

Guarantees (docs/architecture.md, "The dashboard: data flow and concurrency"):

- **newest state lands last**: a change's results are computed from one snapshot read
  inside the session's lock and published before it is released; control changes arrive
  on several worker threads in any order, whichever publishes last read the state last. A
  row whose fields changed again meanwhile is left to the pass of that newer change;
- **what the user looks at first**: in a pass the rows of the shown analysis tab come
  first (after the results they are made of), so that view is computed and drawn before
  the main views;
- **not published twice**: a row is published only when the values it depends on changed
  (the row's key), so a view is not redrawn for the same inputs;
- **the band on its own thread** (:mod:`app.runtime.bands`): one live band per session,
  turns between sessions, one run shared by the sessions asking for the same band;
- **background work bounded** (:mod:`app.runtime.background`): at most one task per
  session and row waits, a newer one replaces it, one thread of the process runs them;
- **a closed page** computes and publishes nothing more.
"""

from __future__ import annotations

import dataclasses
import functools
import threading
import time
import weakref
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import panel as pn
import param

from fbs_core.analysis import add_pin, pin_state, remove_pin
from fbs_core.errors import FBSError

from . import compute
from .results import (
    FIELDS,
    Band,
    BandStatus,
    Result,
    Snapshot,
    analysis,
    campaign_rows,
    main,
    modes,
    pins,
    response_plot,
    review,
    vehicle,
)
from .results import modes_compute as mc
from .results.base import VEHICLE_FIELDS, progress_status
from .results.vpt import ROLES as VPT_ROLES
from .results.vpt import consistency_results
from .runtime import background, bands, uploads
from .runtime.activity import ACTIVITIES
from .runtime.draw import served
from .state import MODE_COUNTS, DashboardState
from .state.pins import check_pin_name, encode_pins

__all__ = ["ALWAYS", "LIVE", "TABLE", "Results", "Row", "depends"]

#: When a row is computed: on every change of what it depends on.
ALWAYS = "always"
#: ... only while the uncoupled subsystems are shown.
SHOWN_UNCOUPLED = "while the uncoupled subsystems are shown"
#: ... only while the first-order band is overlaid on the scatter band.
SHOWN_FIRST_ORDER = "while the first-order band is shown"
#: The state field that switches each of those on.
_SHOWN_BY = {SHOWN_UNCOUPLED: "show_uncoupled", SHOWN_FIRST_ORDER: "first_order"}
#: ... on a thread of its own (the scatter band), not when the store is made.
OWN_THREAD = "on a thread of its own"
#: ... only in vehicle scope (the whole car).
IN_VEHICLE = "in vehicle scope"
_TAB = "while the Analysis tab is shown: "


def while_tab(tab: str) -> str:
    """When a row is computed: only while ``tab`` of the Analysis card is shown."""
    return _TAB + tab


@dataclass(frozen=True)
class Row:
    """One published result: its name, what it depends on, how and when it is made.

    Attributes
    ----------
    name : str
        The parameter of :class:`Results` it is published as.
    depends : tuple of str
        Fields of :class:`~app.results.Snapshot` (settings, or the published ``band`` /
        ``pins``) and names of rows it is made of.
    make : callable or None
        ``make(snapshot) -> value``, pure (None: the scatter band, see :meth:`Results.
        request_band`).
    when : str
        :data:`ALWAYS`, :data:`SHOWN_UNCOUPLED`, :data:`SHOWN_FIRST_ORDER`, :func:`while_tab`
        or :data:`OWN_THREAD`.
    slow : callable, optional
        ``slow(snapshot) -> work | None``: what the value still lacks (``make`` uses what
        is computed), done on the background worker (in place without a server), after
        which the row is published again.
    waited : bool
        The user waits for ``slow``'s work (a file they chose is read): it runs at the
        server's priority (:data:`app.runtime.background.AHEAD`), not behind the work
        nobody waits for at a lower one.
    ahead : callable, optional
        ``ahead(previous, snapshot) -> work | None``: computed ahead of the next change
        (``previous``: the snapshot of the value published before, None the first time).
    wait : callable, optional
        ``wait(snapshot, listener_key, told)``: asks for work shared by the sessions that
        the value waits for (:mod:`app.runtime.shared_jobs`); ``told(status)`` is called as
        it moves on, and the row is published again each time (its progress, its end or
        its failure). ``told`` None: computed in place (no server). While the published
        value is pending (``draw["pending"]``) every pass that looks at the row makes it
        again and asks again (a lost job is started again: a tab switch is a retry).
    kind : type
        The published value's type (:class:`~app.results.Result`, a tuple of them, ...).
    problem : bool
        A :class:`~fbs_core.errors.FBSError` of ``make`` is shown as the store's
        ``message`` and the value stays as it was (a malformed link).
    doc : str
    """

    name: str
    depends: tuple[str, ...]
    make: Callable[[Snapshot], Any] | None
    when: str = ALWAYS
    slow: Callable[[Snapshot], Callable[[], Any] | None] | None = None
    ahead: Callable[[Snapshot, Snapshot], Callable[[], Any] | None] | None = None
    kind: type = Result
    problem: bool = False
    doc: str = ""
    vehicle_only: tuple[str, ...] = ()
    wait: Callable[..., None] | None = None
    waited: bool = False

    @property
    def tab(self) -> str | None:
        """The Analysis tab the row is computed on (None: not a tab's row)."""
        return self.when[len(_TAB) :] if self.when.startswith(_TAB) else None

    @property
    def triggers(self) -> tuple[str, ...]:
        """The snapshot fields whose change makes the store look at this row."""
        flag = _SHOWN_BY.get(self.when)
        extra = (
            ("tab",)
            if self.tab
            else (flag,)
            if flag
            else ("scope",)
            if self.when == IN_VEHICLE
            else ()
        )
        return self.depends + extra

    def shown(self, s: Snapshot) -> bool:
        """Whether the row is computed in the state ``s``."""
        if self.tab is not None:
            return s.tab == self.tab
        if self.when == IN_VEHICLE:
            return s.vehicle
        flag = _SHOWN_BY.get(self.when)
        return bool(getattr(s, flag)) if flag else True

    def key(self, s: Snapshot) -> tuple:
        """The values of ``s`` the row is made of (published again only when they change):
        in corner scope the fields of the car (and ``vehicle_only``) count as None, so a
        corner's result is not made again when they change; the coherence value counts only
        with the relation 'coherence'."""
        return tuple(_value(s, f, self.vehicle_only) for f in self.depends)

    def parameter(self) -> param.Parameter:
        if self.kind is tuple:
            return param.Parameter(default=(), doc=self.doc)
        return param.ClassSelector(class_=self.kind, allow_None=True, doc=self.doc)


def _value(s: Snapshot, f: str, vehicle_only: tuple[str, ...] = ()) -> Any:
    """A snapshot field as a row's key holds it (see :meth:`Row.key`)."""
    if f in VEHICLE_FIELDS or f in vehicle_only:
        if not s.vehicle or (f == "coherence" and s.tracks != "coherence"):
            return None
    return getattr(s, f)


def scoped(corner: Callable[[Snapshot], Any], car: Callable[[Snapshot], Any]):
    """A maker of the corner's result in corner scope and of the car's in vehicle scope."""

    def make(s: Snapshot) -> Any:
        return car(s) if s.vehicle else corner(s)

    make.__name__ = f"{getattr(corner, '__name__', 'make')}_scoped"
    return make


#: The case of a coupled response.
CASE = ("harmonic", "n_modes", "dof", "coupling", "residual", "models")
#: The whole car's fields (vehicle scope).
VEHICLE = ("scope", *VEHICLE_FIELDS)
#: The noise study's own settings of a scatter band.
NOISE_STUDY = ("noise", "target", "frequency_dependent", "rounds", "seed")
#: The settings of a scatter band (its cache key).
BAND = ("harmonic", "n_modes", "coupling", "models", *NOISE_STUDY, *VEHICLE)
#: The FRFs of the phase view.
PHASE = (*CASE, "spindle_input", "frf")
#: The participation of the tire modes: the harmonic's band up to f_max, every mode.
MODES = ("harmonic", "dof", "coupling", "f_max", "models", "mode_rank")
#: The criterion of table 5.1 and of the selections.
CRITERION = ("harmonic", "coupling", "residual", "models", "map_mode", "dof", "threshold", "f_max")

#: Every result of a session (in the order a change publishes them, after those of the
#: shown analysis tab and after the results they are made of).
TABLE: tuple[Row, ...] = (
    Row(
        "pins",
        ("pin_text", "models", "review"),
        pins.build_pins,
        kind=tuple,
        problem=True,
        doc="The pinned baselines (app.results.pins.Pin), from the pins of the link.",
    ),
    Row(
        "response",
        (*CASE, *VEHICLE),
        scoped(main.response_result, vehicle.response_result),
        problem=True,
        doc="Coupled response v_e* (eq. 4.1): the corner's at the bushing, or the car's at "
        "the response point.",
    ),
    Row(
        "response_plot",
        (*CASE, "overlay", "level_scale", "mcursor1", "mcursor2", "snap"),
        response_plot.response_plot_result,
        doc="The response plot's overlaid DOFs, level axis and cursor readout.",
    ),
    Row(
        "error_map",
        (*CASE, "map_mode", "threshold", "f_max", *VEHICLE),
        scoped(main.error_map_result, vehicle.error_map_result),
        problem=True,
        doc="Truncation error map (eq. 5.1); the car's needs a coherent road.",
    ),
    Row(
        "suggested",
        ("coupling", "dof", "residual", "models", "map_mode", "threshold", "f_max", "harmonic")
        + VEHICLE,
        scoped(main.suggested_result, vehicle.suggested_result),
        slow=lambda s: None if s.vehicle else main.residual_work(s),
        problem=True,
        vehicle_only=("harmonic",),
        doc="Suggested modes (table 5.1), plain and with residuals; the car's from the maps "
        "computed so far.",
    ),
    Row("eigen", ("n_modes", "models"), main.eigen_result, doc="Eigenfrequency vs N (fig. 5.8)."),
    Row(
        "tire_quality",
        ("models",),
        main.tire_quality_result,
        doc="Leave-one-out interpolation error and speed coverage of the tire.",
    ),
    Row(
        "uncoupled",
        ("harmonic", "n_modes", "dof", "spindle_input", "models"),
        main.uncoupled_result,
        when=SHOWN_UNCOUPLED,
        doc="Uncoupled tire and chassis (None until shown).",
    ),
    Row(
        "band_curves",
        ("band", "dof", "percentile", "single_round"),
        main.band_result,
        doc="The band's curves at the selected DOF.",
    ),
    Row(
        "wheel_contributions",
        (*CASE, *VEHICLE),
        vehicle.wheels_result,
        when=IN_VEHICLE,
        doc="The contribution of each wheel's road to the car's response (vehicle scope).",
    ),
    Row(
        "first_order",
        ("band", "dof", "percentile"),
        main.first_order_result,
        when=SHOWN_FIRST_ORDER,
        doc="The first-order band of the scatter band's settings (its overlay; None until shown).",
    ),
    Row(
        "pinned",
        ("pins", *CASE),
        pins.pinned_result,
        kind=tuple,
        doc="Each pin against the current state (a tuple of Result; the report shows each).",
    ),
    Row(
        "pick",
        ("picked_speed", "picked_freq"),
        analysis.pick_result,
        doc="The picked speed and frequency.",
    ),
    Row(
        "contributions",
        (*CASE, "contrib_mode"),
        analysis.contributions_result,
        when=while_tab("contributions"),
        doc="Contributions of the interface forces (eq. 4.1 term by term).",
    ),
    Row(
        "phase",
        (*PHASE, "phase_mode", "log_freq", "cursor1", "cursor2"),
        analysis.phase_result,
        when=while_tab("phase"),
        doc="Bode or real/imaginary view with peaks and delta cursors.",
    ),
    Row(
        "peak_modes",
        PHASE,
        analysis.peak_modes_result,
        when=while_tab("phase"),
        slow=analysis.peak_modes_work,
        doc="The phase view's peak labels with the coupled modes nearby.",
    ),
    Row(
        "speed_map",
        ("harmonic", "n_modes", "dof", "coupling", "models"),
        analysis.speed_map_result,
        when=while_tab("speed"),
        ahead=lambda old, new: (
            None if old is None else analysis.speed_map_ahead(old, new, MODE_COUNTS)
        ),
        doc="Bushing level over speed and frequency.",
    ),
    Row(
        "campbell",
        ("harmonic", "models"),
        analysis.campbell_result,
        when=while_tab("speed"),
        doc="Campbell diagram of the tire with the order lines (after the speed map: on a "
        "change of harmonic only its thick line moves).",
    ),
    Row(
        "compare",
        (*CASE, "pins", "compare_to", "band", "percentile", "map_mode", *NOISE_STUDY, *VEHICLE),
        pins.compare_result,
        when=while_tab("compare"),
        doc="The current state against the pins.",
    ),
    Row(
        "participation",
        MODES,
        modes.participation_result,
        when=while_tab("modes"),
        ahead=modes.participation_ahead,
        doc="Ranking of the tire modes in the bushing response (docs/modes.md, section 1).",
    ),
    Row(
        "mode_shape",
        (*MODES, "mode_pick", "mode_speed"),
        modes.mode_shape_result,
        when=while_tab("modes"),
        doc="The picked tire mode (or the ranking's first) as the deformed belt.",
    ),
    Row(
        "waves",
        ("harmonic", "models", "waves_all"),
        modes.waves_result,
        when=while_tab("modes"),
        wait=modes.waves_wait,
        doc="Campbell diagram of the belt waves (solved once per tire for every session).",
    ),
    Row(
        "selected_modes",
        CRITERION,
        modes.selected_modes_result,
        when=while_tab("selection"),
        doc="The modes the case needs chosen by importance, beside table 5.1's lowest N.",
    ),
    Row(
        "chassis_truncation",
        CRITERION,
        modes.chassis_truncation_result,
        when=while_tab("selection"),
        doc="Eq. 5.1 truncation of the chassis side (the tire exact).",
    ),
    Row(
        "verdict",
        review.VERDICT_DEPENDS,
        review.verdict_result,
        slow=review.verdict_work,
        doc="The review's verdict: every candidate tire against the targets, ranked.",
    ),
    Row(
        "review_curves",
        review.CURVES_DEPENDS,
        review.review_curves_result,
        slow=review.curves_work,
        doc="The other candidates' responses and the target on the coupled-response plot.",
    ),
    Row(
        "review_bands",
        review.BANDS_DEPENDS,
        review.review_bands_result,
        slow=review.bands_work,
        doc="The other candidates' scatter bands (the page's band settings) on the band plot.",
    ),
    Row(
        "campaign_cases",
        campaign_rows.CASES_DEPENDS,
        campaign_rows.cases_result,
        slow=campaign_rows.open_work,
        waited=True,
        doc="The campaign file's case table (None until a file is chosen; the file read "
        "in the background).",
    ),
    Row(
        "campaign",
        campaign_rows.CASE_DEPENDS,
        campaign_rows.case_result,
        slow=campaign_rows.open_work,
        waited=True,
        doc="The chosen case of the campaign file: its band, corridor or error map, with "
        "its provenance (None until a case is chosen).",
    ),
    # last: its thread starts once the pass's other results are out (it publishes later)
    Row("band", BAND, None, when=OWN_THREAD, kind=Band, doc="The latest scatter band."),
)
ROWS = {row.name: row for row in TABLE}
#: The fields of the state (the rest of a snapshot's fields are published results).
STATE_FIELDS = frozenset(FIELDS)


def depends(name: str) -> frozenset[str]:
    """The state fields result ``name`` depends on, through the results it is made of (and
    the switch that shows it: a row shown while ``first_order`` is on depends on it)."""
    out: set[str] = set()
    todo, seen = [name], set()
    while todo:
        row = ROWS[todo.pop()]
        seen.add(row.name)
        flag = _SHOWN_BY.get(row.when)
        for f in (*row.depends, flag) if flag else row.depends:
            if f in STATE_FIELDS:
                out.add(f)
            elif f in ROWS and f not in seen:
                todo.append(f)
    return frozenset(out)


def _affected(fields: Iterable[str]) -> frozenset[str]:
    """The rows to look at when ``fields`` changed (and the rows made of those)."""
    return _affected_by(frozenset(fields))


@functools.lru_cache(maxsize=256)
def _affected_by(fields: frozenset[str]) -> frozenset[str]:
    out = {row.name for row in TABLE if fields & set(row.triggers)}
    grew = True
    while grew:
        more = {row.name for row in TABLE if set(row.depends) & out} - out
        grew = bool(more)
        out |= more
    return frozenset(out)


def _order(names: frozenset[str], s: Snapshot) -> list[Row]:
    """``names`` in the order of a pass: the shown tab's rows first, each after the rows
    of the pass it is made of."""
    first = sorted(
        (ROWS[n] for n in names),
        key=lambda r: (not (r.tab is not None and r.shown(s)), TABLE.index(r)),
    )
    out: list[Row] = []

    def visit(row: Row) -> None:
        if row in out:
            return
        for d in row.depends:  # (a band is published by its thread: not waited for)
            if d in names and ROWS[d].when != OWN_THREAD:
                visit(ROWS[d])
        out.append(row)

    for row in first:
        visit(row)
    return out


def _done_status(band: Band) -> BandStatus:
    return BandStatus(False, bands.done_text(band.result, band.seconds, band.settings.band_key()))


def _same_value(a: Any, b: Any) -> bool:
    a = tuple(a) if isinstance(a, list) else a
    b = tuple(b) if isinstance(b, list) else b
    try:
        return bool(a == b)
    except Exception:
        return False


#: Every :class:`Results` not yet freed (a page's store lives as long as its page).
LIVE: weakref.WeakSet[Results] = weakref.WeakSet()


class Results(param.Parameterized):
    """The published results of one browser session (see the module docstring); one
    parameter per row of :data:`TABLE`, added below the class."""

    state = param.ClassSelector(class_=DashboardState, instantiate=False, constant=True)
    band_status = param.ClassSelector(class_=BandStatus, doc="Band computation status.")
    message = param.String(default="", doc="The last pin action's or link's problem ('' if none).")
    outside = param.Dict(
        default={},
        doc="Results of views that are no row of the table, as they show them now (a "
        "measured chassis' consistency: it is the upload's, not the state's): name -> "
        "Result; the report shows each as a section of its own.",
    )
    closed = param.Boolean(default=False, doc="The session has ended: nothing is drawn.")
    published = param.Parameter(
        default=None,
        doc="The settings (a Snapshot without band and pins) of the last pass: the state "
        "the page's results are of, whose link every title block carries.",
    )
    working = param.String(
        default="",
        doc="What the session computes now when it takes long, and for how long ('' when "
        "nothing long runs): the page's busy indicator (app.runtime.activity).",
    )
    background = param.Boolean(
        default=None,
        allow_None=True,
        doc="Longer work on threads of its own (None: when the page is served).",
    )

    def __init__(self, state: DashboardState | None = None, **params):
        LIVE.add(self)
        self._lock = threading.RLock()
        self._band_job: bands.Job | None = None
        self._keys: dict[str, tuple] = {}  # the key of each published row
        self._made: dict[str, Snapshot] = {}  # the snapshot of each published row
        params["state"] = state if state is not None else DashboardState()
        params.setdefault("band_status", BandStatus())
        super().__init__(**params)
        # the watchers, derived from the table: one per group of the state
        watched = {f for row in TABLE for f in row.triggers if f in STATE_FIELDS}
        by_group: dict[str, dict[str, str]] = {}
        for f in watched:
            group, name = FIELDS[f]
            by_group.setdefault(group, {})[name] = f
        for group, names in by_group.items():
            getattr(self.state, group).param.watch(
                lambda *events, names=names: self._changed({names[e.name] for e in events}),
                list(names),
            )
        # a measured chassis' consistency: in the report beside the rows (no row: it is the
        # upload's, not the state's)
        self.state.data.param.watch(lambda _e: self._show_vpt(), "vpt")
        self._show_vpt()
        self._update(frozenset(row.name for row in TABLE if row.when != OWN_THREAD))

    def _show_vpt(self) -> None:
        made = consistency_results(self.state.data.vpt)
        for role in VPT_ROLES:
            self.show_outside(f"vpt_{role}", made.get(f"vpt_{role}"))

    @property
    def threaded(self) -> bool:
        """Whether longer work goes to threads of its own: ``background``, or when it is
        None, whether the page is served (no server: tests, exports compute in place)."""
        return served() if self.background is None else bool(self.background)

    @property
    def lock(self) -> threading.RLock:
        """The session's lock."""
        return self._lock

    def snapshot(self) -> Snapshot:
        """The current state as plain values, with the published band and pins."""
        return Snapshot.of(self.state, self.band, self.pins)

    # -- publishing ------------------------------------------------------------------------
    def _changed(self, fields: set[str]) -> None:
        names = _affected(fields)
        if uploads.on_upload_thread():  # an upload's reading thread only reads
            doc = pn.state.curdoc

            def run() -> None:
                pn.state.curdoc = doc  # drawn by the session's loop, as from the upload
                try:
                    self._update(names)
                finally:
                    pn.state.curdoc = None

            threading.Thread(target=run, name="fbs-upload-pass", daemon=True).start()
            return
        self._update(names)

    def _update(self, names: frozenset[str]) -> None:
        """One pass: the rows ``names`` from one snapshot, under the session's lock."""
        with self._lock:
            if self.closed:
                return
            s = self.snapshot()
            token = ACTIVITIES.begin(self, "Updating the views")
            try:
                for row in _order(names, s):
                    if row.when == OWN_THREAD:
                        if self._current(row, s):
                            self._start_band(s)
                            s = s.replace(band=self.band)  # published meanwhile without a server
                        continue
                    ACTIVITIES.update(token, _working_text(row, s))
                    s = self._publish(row, s)
            finally:
                ACTIVITIES.end(token)
            now = self.snapshot().settings()
            if now != self.published:
                self.published = now

    def link_snapshot(self, name: str, r: Result) -> Snapshot | None:
        """The settings whose link the title block of result ``r`` (of row ``name``)
        carries: the published state's when ``r`` is of its values (every field it depends
        on), else ``r``'s own (a band still computing shows the one it was made of)."""
        pub, own = self.published, r.snapshot
        if own is None or pub is None or name not in ROWS:
            return own
        fields = depends(name)
        if all(_same_value(getattr(own, f), getattr(pub, f)) for f in fields):
            return pub
        return own

    def _current(self, row: Row, s: Snapshot) -> bool:
        """False when a field of ``row`` changed again since ``s`` was read: the pass of
        that newer change (waiting for the lock) publishes it."""
        state = self.state
        for f in row.depends:
            where = FIELDS.get(f)
            if where is None:
                continue
            now = getattr(getattr(state, where[0]), where[1])
            if (tuple(now) if isinstance(now, list) else now) != getattr(s, f):  # (a list: a tuple)
                return False
        return True

    def _publish(self, row: Row, s: Snapshot, force: bool = False, told: bool = False) -> Snapshot:
        """Publish ``row`` made of ``s`` (when shown, current and not published for the same
        key already); the snapshot with the new value when it is an input of other rows."""
        if not row.shown(s) or not self._current(row, s):
            return s
        key = row.key(s)
        if (
            not force
            and self._keys.get(row.name, None) == key
            and row.name in self._made
            and not self._pending(row)
        ):
            return s
        assert row.make is not None
        if row.wait is not None and not told:
            if self.threaded:
                row.wait(s, (self, row.name), lambda _st, row=row, key=key: self._told(row, key))
            else:
                row.wait(s)  # no server: computed here
        work = row.slow(s) if row.slow is not None else None
        if work is not None and not self.threaded:  # no server: all of it now
            _drain(work())
            work = None
        try:
            value = row.make(s)
        except FBSError as e:
            if not row.problem:
                raise
            self.message = str(e)
            return s
        if isinstance(value, Result):
            made = s.settings()
            if made.vehicle and "scope" not in row.triggers:
                made = made.replace(scope="corner")  # a corner's result (the Analysis card)
            value = dataclasses.replace(value, key=key, snapshot=value.snapshot or made)
        before = self._made.get(row.name)
        self._keys[row.name], self._made[row.name] = key, s.settings()
        setattr(self, row.name, value)
        if work is not None:
            self._later(row, key, work)
        if row.ahead is not None and self.threaded:
            ahead = row.ahead(before, s)
            if ahead is not None:
                self._ahead(row, key, ahead)
        return s.replace(**{row.name: value}) if row.name in ("pins", "band") else s

    def _pending(self, row: Row) -> bool:
        """Whether ``row`` waits for shared work and its published value is pending."""
        if row.wait is None:
            return False
        value = getattr(self, row.name)
        return isinstance(value, Result) and bool(value.draw.get("pending"))

    #: Longest a note of shared work waits for the session's lock before it is tried again
    #: later (s): the notifier's threads serve every session.
    TOLD_LOCK_S = 2.0

    def _told(self, row: Row, key: tuple) -> None:
        """Shared work ``row`` waits for moved on (progress, end, failure): publish the row
        again (on the notifier's thread; a busy lock is tried again a moment later)."""
        if self._stale(row, key):
            return
        if not self._lock.acquire(timeout=self.TOLD_LOCK_S):
            t = threading.Timer(self.TOLD_LOCK_S, self._told, (row, key))
            t.daemon = True
            t.start()
            return
        try:
            if not self._stale(row, key):
                self._publish(row, self.snapshot(), force=True, told=True)
        finally:
            self._lock.release()

    def _stale(self, row: Row, key: tuple) -> bool:
        return self.closed or self._keys.get(row.name) != key

    def _later(self, row: Row, key: tuple, work: Callable[[], Any]) -> None:
        """``work`` on the background worker (a step at a time, dropped once the row moved
        on), then ``row`` published again with what it computed."""

        def task() -> Iterator[None]:
            steps = work()
            for _ in steps if isinstance(steps, Iterator) else ():
                if self._stale(row, key):
                    return
                yield
            with self._lock:
                if not self._stale(row, key):
                    self._publish(row, self.snapshot(), force=True)

        worker = background.AHEAD if row.waited else background.BACKGROUND

        def submit() -> None:
            worker.submit((self, row.name), task)

        if served() and not pn.state.loaded:  # after the page is sent: its build stays as fast
            pn.state.onload(submit)
        else:
            submit()

    def _ahead(self, row: Row, key: tuple, work: Callable[[], Any]) -> None:
        """``work`` computed ahead (nothing once the row moved on)."""
        background.AHEAD.submit((self, row.name), lambda: None if self._stale(row, key) else work())

    def current(self, looked_at: bool = False) -> tuple[Snapshot, dict[str, Any]]:
        """The snapshot and the published results that are of it (shown and made of its
        values): what the page shows.

        ``looked_at``: also the results of Analysis tabs not shown now that the session
        computed for these very values (a tab the user looked at, then closed or left for
        another): what the report holds.
        """
        with self._lock:
            s = self.snapshot()
            out = {}
            for row in TABLE:
                value = getattr(self, row.name)
                shown = row.shown(s) or (looked_at and row.tab is not None)
                if row.make is None or value is None or value == () or not shown:
                    continue
                if self._keys.get(row.name) == row.key(s):
                    out[row.name] = value
            return s, out

    def show_outside(self, name: str, result: Result | None) -> None:
        """Publish what a view outside the table shows now (None: it shows nothing)."""
        with self._lock:
            out = {k: v for k, v in self.outside.items() if k != name}
            if result is not None:
                out[name] = result
            self.outside = out

    # -- the scatter band: long, off the session's threads --------------------------------
    def request_band(self, *, wait: bool | None = None) -> None:
        """Compute the band of the current settings (cancelling one still running).

        ``wait=True`` computes it in the calling thread (no server: tests, exports, the
        warm-up); by default it runs in the background when the page is served.
        """
        with self._lock:
            if self.closed:
                return
            self._start_band(self.snapshot(), wait)

    def _start_band(self, s: Snapshot, wait: bool | None = None) -> None:
        key = s.band_key()
        running = self._band_job
        if running is not None and running.key == key:
            return  # already on its way
        if running is not None:
            running.cancel()
            self._band_job = None
        if self.band is not None and self.band.settings.band_key() == key:
            self.band_status = _done_status(self.band)  # back to the shown band
            return
        job = self._band_job = bands.Job(key, owner=self, on_progress=self._band_progress)
        self.band_status = progress_status(s.rounds, 0, 0, None)
        if wait is None:
            wait = not self.threaded
        if wait:
            bands.run(job, self._band_done, s.settings())
        else:
            bands.start(job, self._band_done, s.settings())

    #: Shortest interval between two progress updates of the page (s).
    PROGRESS_INTERVAL = 0.4

    def _band_progress(self, job: bands.Job) -> None:
        """The kernel finished a chunk of ``job``: publish done/total and the time left
        (at most every PROGRESS_INTERVAL seconds; short bands finish before the first)."""
        now = time.perf_counter()
        last = getattr(job, "published", job.started)
        if job.done < job.total and now - last < self.PROGRESS_INTERVAL:
            return
        job.published = now
        with self._lock:
            if job is not self._band_job or job.cancelled or self.closed:
                return
            rounds = job.key.rounds
            self.band_status = progress_status(rounds, job.done, job.total, job.seconds_left())

    def cancel_band(self) -> None:
        """Stop the running band (the cancel button); the band on the page stays, marked as
        not of the current settings."""
        with self._lock:
            job = self._band_job
            if job is None:
                return
            job.cancel()
            self._band_job = None
            shown = "" if self.band is None else " The plot shows the band of earlier settings."
            self.band_status = BandStatus(
                False,
                f"Cancelled after {job.done} of {job.total} frequency lines.{shown} "
                "Change a noise setting to compute again.",
            )

    def _band_done(self, job: bands.Job, settings: Snapshot, res, seconds: float, error) -> None:
        with self._lock:
            if job is not self._band_job or job.cancelled or self.closed:
                return  # superseded: a newer job publishes
            self._band_job = None
            if error is not None:
                self.band_status = BandStatus(False, f"Scatter band failed: {error}")
                return
            self.band = Band(res, settings, seconds)
            self._update(_affected({"band"}))  # the results made of it, then its status
            self.band_status = _done_status(self.band)

    def band_now(self) -> Band | None:
        """The band of the current settings, computed here if needed (None if it failed)."""
        self.request_band(wait=True)
        return self.band

    def pick_peak_round(self, freq: float) -> None:
        """Show the round with the highest level at the line nearest ``freq`` (Hz)."""
        band = self.band
        if band is None:
            return
        self.state.noise.single_round = compute.peak_round(
            band.result, float(freq), self.state.case.dof, "max"
        )

    # -- pins ----------------------------------------------------------------------------------
    def pin(self, name: str) -> None:
        """Pin the current state as ``name`` (up to four; a taken name is refused)."""
        with self._lock:
            try:
                name = check_pin_name(name)
                ps = pins.pin_settings(name, self.snapshot())
                add_pin(self.pins, pin_state(name, {}))  # the core's rules: unique, at most 4
            except FBSError as e:
                self.message = str(e)
                return
            self.message = ""
            self.state.analysis.pins = encode_pins([p.settings for p in self.pins] + [ps])

    def unpin(self, name: str) -> None:
        """Remove the pin named ``name``."""
        with self._lock:
            try:
                remove_pin([p.data or pin_state(p.name, {}) for p in self.pins], name)
            except FBSError as e:
                self.message = str(e)
                return
            self.message = ""
            a = self.state.analysis
            a.pins = encode_pins([p.settings for p in self.pins if p.name != name])
            if a.compare_to == name:
                a.compare_to = ""

    # -- picking ---------------------------------------------------------------------------------
    def pick_point(self, speed_kmh: float | None, freq: float | None) -> None:
        """Pick a speed (km/h) and a frequency (Hz) for the other views (None: unchanged)."""
        upd = {}
        if speed_kmh is not None and np.isfinite(speed_kmh):
            upd["picked_speed"] = float(np.clip(round(speed_kmh, 2), 0.0, 300.0))
        if freq is not None and np.isfinite(freq):
            upd["picked_freq"] = float(np.clip(round(freq, 2), 0.0, 1000.0))
        if upd:
            self.state.analysis.param.update(**upd)

    def pick_campbell(self, speed_kmh: float, freq: float, tol: float = 0.03) -> None:
        """A click in the Campbell diagram: pick the point; if it lies on the order line of
        a harmonic case inside that case's speed range (within ``tol`` relative frequency),
        also choose that harmonic (its bushing response is the other views' subject)."""
        self.pick_point(speed_kmh, freq)
        r = self.campbell
        if r is None:
            return
        d = r.draw
        k = analysis.nearest_order_line(d["wavelength"], d["speed_range"], speed_kmh, freq, tol)
        if k is not None:
            self.state.case.harmonic = k

    def pick_mode_bar(self, x: float) -> None:
        """A click on the participation ranking at ``x``: draw that bar's mode, at the speed
        where the harmonic line meets it (``mode`` / ``mv`` in the URL)."""
        r = self.participation
        if r is None or not r.draw.get("ready"):
            return
        i = modes.nearest_bar(r.draw, x)
        if i is not None:
            speed = round(float(r.draw["speed"][i]), 1)
            self.state.analysis.param.update(mode_pick=int(r.draw["mode"][i]), mode_speed=speed)

    def pick_wave(self, speed_kmh: float, freq: float) -> None:
        """A click in the Campbell diagram of the waves: draw the mode that carries the
        branch nearest ``(speed_kmh, freq)`` at that speed (nothing when no branch is near)."""
        r = self.waves
        if r is None or not r.draw.get("ready"):
            return
        hit = modes.nearest_branch(r.draw, speed_kmh, freq)
        if hit is not None:
            self.state.analysis.param.update(mode_pick=hit[0], mode_speed=round(hit[1], 1))

    def close(self) -> None:
        """The session ended: cancel its band and its waiting work, publish nothing more."""
        with self._lock:
            self.closed = True
            if self._band_job is not None:
                self._band_job.cancel()
                self._band_job = None
        background.BACKGROUND.cancel(self)
        background.AHEAD.cancel(self)
        mc.WAVES.cancel_listeners(self)


for _row in TABLE:  # one parameter per row of the table
    Results.param.add_parameter(_row.name, _row.parameter())


#: What the busy indicator says while a row is made (its name when missing here).
WORKING_WORDS = {
    "pins": "reading the pins",
    "response": "computing the coupled response",
    "response_plot": "drawing the response plot",
    "error_map": "computing the truncation error map",
    "suggested": "computing the suggested modes",
    "eigen": "computing the eigenfrequencies",
    "tire_quality": "checking the tire model",
    "uncoupled": "computing the uncoupled tire and chassis",
    "band_curves": "reading the scatter band",
    "wheel_contributions": "computing each wheel's contribution",
    "first_order": "computing the first-order band",
    "pinned": "comparing the pins",
    "pick": "reading the picked point",
    "contributions": "computing the contributions",
    "phase": "computing the phase view",
    "peak_modes": "finding the peaks' modes",
    "speed_map": "computing the speed map",
    "campbell": "computing the Campbell diagram",
    "compare": "comparing with the pins",
    "participation": "ranking the tire modes",
    "mode_shape": "computing the mode shape",
    "waves": "looking up the belt waves",
    "selected_modes": "selecting the modes",
    "chassis_truncation": "computing the chassis truncation",
    "campaign_cases": "listing the campaign's cases",
    "campaign": "reading the campaign case",
}


def _working_text(row: Row, s: Snapshot) -> str:
    """What the busy indicator says while ``row`` is made."""
    what = WORKING_WORDS.get(row.name, f"computing {row.name}")
    where = " of the whole car" if s.vehicle and "scope" in row.triggers else ""
    return what[:1].upper() + what[1:] + where


def _drain(steps: Any) -> None:
    """Run background work to its end here (a generator: all of its steps)."""
    for _ in steps if isinstance(steps, Iterator) else ():
        pass
