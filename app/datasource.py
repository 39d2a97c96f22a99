"""Per-session data source: the shipped reference models or the session's own uploads.

A :class:`DataSource` belongs to one browser session (it lives in that session's
:class:`~app.state.DashboardState`; nothing here is module-level state), so an upload never
reaches another session. Uploads are read only through :mod:`fbs_core.io`, which writes
nothing but private temporary files: the shipped reference data (``data/``) are never
touched.

The current pair of models is a :class:`Models` token: immutable, hashable by a digest of
the uploaded bytes and the import settings, so the cached computations of
:mod:`app.compute` can key on it (two sessions that upload the same file share results;
different uploads never do).

The checks are the core's (every view must run on the models):

- chassis: six spindle DOFs (inputs and outputs) and all six bushing outputs
  (``fbs_core.io.prepare_chassis`` / ``require_dofs``); lines on every harmonic's analysis
  grid, either present in the file or, only when the user ticks it, interpolated
  (:class:`fbs_core.FRFChassis`: linear in real and imaginary part, never extrapolated);
- tire: :func:`fbs_core.io.checks.check_tire` (hub DOFs, at least 20 complex modes, the
  operating points of all seven harmonic cases and of the eigenfrequency view);
- a measured chassis (sensors and impacts around the knuckle, with a geometry upload):
  :func:`fbs_core.io.load_measured_chassis` (the channels' positions and directions, six
  DOFs observable) turns it into the spindle chassis above, with its consistency
  (docs/vpt.md);
- the pair: :func:`fbs_core.io.checks.check_pair` (the interface matrix
  ``Y_jj^A + Y_jj^E``, eq. 2.44, well conditioned on every harmonic's grid).

A refused upload leaves the state as it was and says why in :attr:`DataSource.error`.
"""

from __future__ import annotations

import hashlib
import threading

import param

from fbs_core.candidates import Candidate, CandidateSet
from fbs_core.chassis import FRFChassis
from fbs_core.dofs import parse_label
from fbs_core.errors import DOFError, FBSError
from fbs_core.harmonics import harmonic
from fbs_core.io.checks import check_pair, check_tire
from fbs_core.targets import IncumbentTarget, Target, read_targets
from fbs_core.vehicle import RESPONSE_NODES
from fbs_core.vocabulary import DIRECTIONS, EIGEN_SPEEDS, HARMONIC_CASES

from .review import EMPTY_REVIEW, LINK_DIGEST, LinkReview, Review, read_review_link

__all__ = [
    "CHASSIS_ACCEPT",
    "GEOMETRY_ACCEPT",
    "EIGEN_SPEEDS",
    "HARMONICS",
    "TARGET_ACCEPT",
    "TIRE_ACCEPT",
    "DataSource",
    "FRFChassis",
    "Models",
    "REFERENCE",
    "candidate_models",
]

BUSHING = tuple(f"bushing:{d}" for d in DIRECTIONS)
#: The car's response DOFs (vehicle scope): each response point's six.
CAR_DOFS = tuple(f"{p}:{d}" for p in RESPONSE_NODES for d in DIRECTIONS)
#: The DOFs a target may be for: the corner's bushing, and the car's response points.
TARGET_DOFS = BUSHING + CAR_DOFS
#: Harmonic cases every view may ask for.
HARMONICS = HARMONIC_CASES
#: File endings offered by the upload widgets.
CHASSIS_ACCEPT = ".uff,.unv,.uf,.58,.mat,.csv,.txt,.h5,.hdf5,.hdf"
GEOMETRY_ACCEPT = ".uff,.unv,.uf,.csv,.txt,.h5,.hdf5,.hdf"
TIRE_ACCEPT = ".h5,.hdf5,.hdf,.mat"
TARGET_ACCEPT = ".csv,.txt,.uff,.unv,.uf,.58"


class Models:
    """The tire and chassis of a session (``None`` = the shipped reference), immutable.

    Equal and hashed by ``key``, a digest of the uploaded bytes and import settings, so it
    can be part of a cache key.
    """

    __slots__ = ("tire", "chassis", "key", "tire_name", "chassis_name")

    def __init__(
        self,
        tire=None,
        chassis=None,
        key: str = "reference",
        tire_name: str = "",
        chassis_name: str = "",
    ) -> None:
        for name, val in (
            ("tire", tire),
            ("chassis", chassis),
            ("key", key),
            ("tire_name", tire_name),
            ("chassis_name", chassis_name),
        ):
            object.__setattr__(self, name, val)

    def __setattr__(self, name, value):
        raise AttributeError("Models is immutable")

    def __copy__(self) -> Models:
        return self

    def __deepcopy__(self, memo) -> Models:
        return self  # immutable: copies (param) share the models

    def __eq__(self, other) -> bool:
        return isinstance(other, Models) and other.key == self.key

    def __hash__(self) -> int:
        return hash(("Models", self.key))

    def __repr__(self) -> str:
        return f"Models({self.describe()})"

    @property
    def is_reference(self) -> bool:
        return self.tire is None and self.chassis is None

    @property
    def chassis_key(self) -> str:
        """The digest of the chassis upload ("" for the reference chassis)."""
        return self.key.partition(";chassis=")[2] if self.chassis is not None else ""

    def describe(self) -> str:
        t = f"uploaded tire {self.tire_name!r}" if self.tire is not None else "reference tire"
        c = (
            f"uploaded chassis {self.chassis_name!r}"
            if self.chassis is not None
            else "reference chassis"
        )
        return f"{t} + {c}"


#: The shipped reference models.
REFERENCE = Models()


def _models(tire, tire_key, tire_name, chassis, chassis_key, chassis_name) -> Models:
    if tire is None and chassis is None:
        return REFERENCE
    key = (
        f"tire={tire_key if tire is not None else 'reference'};"
        f"chassis={chassis_key if chassis is not None else 'reference'}"
    )
    return Models(
        tire,
        chassis,
        key,
        tire_name if tire is not None else "",
        chassis_name if chassis is not None else "",
    )


def candidate_models(models: Models, candidate: Candidate) -> Models:
    """The models of a review candidate with the chassis of ``models``."""
    ck = models.chassis_key
    if candidate.is_reference:
        return _models(None, "", "", models.chassis, ck, models.chassis_name)
    return _models(
        candidate.model, candidate.digest, candidate.name, models.chassis, ck, models.chassis_name
    )


def _settle(review: Review, want: LinkReview | None) -> tuple[Review, LinkReview | None]:
    """``review`` with what ``want`` asks that is loaded now (the current candidate, the
    incumbent), and what it still asks (None: nothing)."""
    if want is None:
        return review, None
    cands = review.candidates
    loaded = {d: c for c in (cands or ()) for d in (c.digest, c.digest[:12])}
    if cands is not None and want.current in loaded:
        review = review.with_candidates(cands.with_current(loaded[want.current].digest))
    inc = want.incumbent
    if inc is not None and (inc[0] in loaded or inc[0] == "reference"):
        name = loaded[inc[0]].name if inc[0] in loaded else "reference"
        review = review.with_incumbent(IncumbentTarget(name, inc[1]))
        inc = None
    rest = tuple(d for d in want.candidates if d not in loaded and d != "reference")
    order = want.order or want.candidates
    if not rest and cands is not None:
        review = review.with_candidates(_in_order(review.candidates or cands, order))
    # the link's current candidate stays asked for until every candidate is loaded (a later
    # upload would otherwise become current)
    current = "" if not rest else want.current
    if not rest and inc is None:
        return review, None
    return review, LinkReview(rest, current, inc, order=order)


def _in_order(cands: CandidateSet, order: tuple[str, ...]) -> CandidateSet:
    """The candidates in the link's order (by digest or its link prefix; others after, as
    they were), their colours in that order: the page of the link as it was shared."""
    by = {d: c for c in cands for d in (c.digest, c.digest[:LINK_DIGEST])}
    first = list({by[d].digest: by[d] for d in order if d in by}.values())
    seen = {c.digest for c in first}
    ordered = first + [c for c in cands if c.digest not in seen]
    if [c.digest for c in ordered] == list(cands.digests):
        return cands
    return CandidateSet(ordered, current=cands.current_digest)


def _unique(name: str, taken) -> str:
    """``name``, or ``name (2)``, ``name (3)``... if it is taken."""
    out, i = name, 1
    while out in taken:
        i += 1
        out = f"{name} ({i})"
    return out


def _digest(data: bytes, **settings) -> str:
    h = hashlib.sha256(data)
    h.update(repr(sorted(settings.items())).encode())
    return h.hexdigest()[:24]


def parse_node(text: str, role: str) -> tuple[str, int | None]:
    """A node given by the user: a name (``"knuckle"``) or a UFF / numeric node number.

    Returns ``(name, number)``: ``number`` is the int for numeric input, else None.
    """
    t = str(text).strip()
    if not t:
        raise FBSError(f"give the {role} node: a node name or a node number")
    if t.isdigit():
        return t, int(t)
    if ":" in t or any(c.isspace() for c in t):
        raise FBSError(
            f"the {role} node must be one node name or number without a direction, got {t!r}"
        )
    return t, None


#: The quantity choice "as the file says".
FROM_FILE = "as the file says"
QUANTITIES = ("receptance", "mobility", "accelerance")


def quantity_hint(message: str) -> str:
    """The core's "pass quantity=..." (a Python hint) as what to do on the page."""
    return message.replace(
        "pass quantity=...",
        "choose what it holds under 'Quantity' (receptance, mobility or accelerance)",
    )


class DataSource(param.Parameterized):
    """The models of one session: the shipped reference or the session's uploads.

    ``models`` changes only when an upload passed every check (or on :meth:`reset`);
    ``error`` holds the message of the last refused upload ("" after a success).
    """

    models = param.ClassSelector(
        class_=Models,
        default=REFERENCE,
        instantiate=False,
        doc="The current tire and chassis (a hashable token).",
    )
    tire_summary = param.String(default="", doc="What was read from the tire upload.")
    chassis_summary = param.String(default="", doc="What was read from the chassis upload.")
    geometry_summary = param.String(
        default="", doc="What was read from the geometry upload (a measured chassis)."
    )
    vpt = param.Parameter(
        default=None,
        doc="The virtual point transformation of a measured chassis in use "
        "(fbs_core.vpt.VirtualPoint), else None.",
    )
    bushing_vp = param.Parameter(
        default=None,
        doc="The second virtual point of a measured chassis whose bushing DOFs come from "
        "sensors around it (fbs_core.vpt.ResponsePoint), else None.",
    )
    review = param.ClassSelector(
        class_=Review,
        default=EMPTY_REVIEW,
        instantiate=False,
        doc="The review: tire candidates (the reference and every tire uploaded), targets "
        "and the incumbent rule (app/review.py).",
    )
    pending = param.ClassSelector(
        class_=LinkReview,
        default=None,
        allow_None=True,
        doc="What the page's link asked of the review that this session has not loaded yet "
        "(candidates whose files are not uploaded; the current one and the incumbent among "
        "them): restored as their files are uploaded.",
    )
    error = param.String(default="", doc="Why the last upload was refused ('' if it was not).")
    spindle = param.String(
        default="spindle", doc="Spindle node of the chassis file (name, or node number)."
    )
    bushing = param.String(
        default="bushing", doc="Bushing node of the chassis file (name, or node number)."
    )
    interpolate = param.Boolean(
        default=False,
        doc="Interpolate the chassis FRF onto the "
        "analysis grids when the file lacks their lines (explicit).",
    )
    quantity = param.Selector(
        default=FROM_FILE,
        objects=[FROM_FILE, *QUANTITIES],
        doc="What the chassis FRF holds when its file does not say (receptance, mobility or "
        "accelerance); checked against the file when it does.",
    )

    def __init__(self, **params):
        super().__init__(**params)
        self._tire_key = self._chassis_key = ""
        self._last_chassis: tuple[bytes, str] | None = None
        self._geometry: tuple[bytes, str] | None = None
        self._last_settings: tuple[str, str, bool, str] | None = None
        # uploads of one session are read one at a time (a click and a settings change
        # arrive on different worker threads: the last read must see the last settings)
        self._lock = threading.RLock()

    # -- uploads -------------------------------------------------------------------------
    def load_chassis(
        self,
        data: bytes | None = None,
        filename: str | None = None,
        *,
        spindle: str | None = None,
        bushing: str | None = None,
        interpolate: bool | None = None,
    ) -> bool:
        """Read a chassis FRF upload; ``data=None`` re-reads the last one (new settings).

        Returns True when it is now the session's chassis; else ``error`` says why and
        nothing else changed.
        """
        with self._lock:
            return self._load_chassis(data, filename, spindle, bushing, interpolate)

    def reread_if_changed(self) -> bool | None:
        """Re-read the last chassis upload if the node names or the interpolation choice
        differ from those of its last reading (None: nothing to do)."""
        with self._lock:
            if self._last_chassis is None or self._settings() == self._last_settings:
                return None
            return self._load_chassis(None, None, None, None, None)

    def load_geometry(self, data: bytes, filename: str | None = None) -> bool:
        """Read a geometry upload (positions and directions of a measured set's channels).

        From then on a chassis upload is a measured set around the knuckle, transformed to
        the spindle (the virtual point, named by the spindle field); the last chassis
        upload is read again that way. A refused geometry changes nothing.
        """
        from fbs_core.io import load_geometry

        with self._lock:
            name = filename or "upload"
            try:
                geo = load_geometry(bytes(data), filename=name)
            except FBSError as e:
                self.error = f"{name}: {e}"
                return False
            old = self._geometry
            self._geometry = (bytes(data), name)
            if self._last_chassis is not None and not self._load_chassis(
                None, None, None, None, None
            ):
                self._geometry = old  # the chassis as it was: nothing changed
                return False
            self.param.update(
                error="",
                geometry_summary=f"geometry {name!r}: {len(geo.channels)} channels, "
                f"{len(geo.points)} points ({', '.join(sorted(geo.points)[:6])})",
            )
            return True

    def _settings(self) -> tuple[str, str, bool, str]:
        return (self.spindle, self.bushing, bool(self.interpolate), self.quantity)

    def _load_chassis(self, data, filename, spindle, bushing, interpolate) -> bool:
        if data is None:
            if self._last_chassis is None:
                self.error = "no chassis file uploaded yet"
                return False
            data, filename = self._last_chassis
        sp = self.spindle if spindle is None else spindle
        bu = self.bushing if bushing is None else bushing
        interp = self.interpolate if interpolate is None else bool(interpolate)
        name = filename or "upload"
        self._last_chassis = (bytes(data), name)  # settings can be changed and re-read
        self._last_settings = (sp, bu, interp, self.quantity)
        q = None if self.quantity == FROM_FILE else self.quantity
        try:
            if self._geometry is None:
                chassis, summary, key = self._read_chassis(bytes(data), name, sp, bu, interp, q)
                vpt = bvp = None
            else:
                chassis, summary, key, vpt, bvp = self._read_measured(
                    bytes(data), name, sp, bu, interp, q
                )
            check_pair(self.models.tire, chassis)
        except FBSError as e:
            self.error = quantity_hint(f"{name}: {e}")
            return False
        self._chassis_key = key
        m = self.models
        with param.parameterized.batch_call_watchers(self):
            self.param.update(
                spindle=sp,
                bushing=bu,
                interpolate=interp,
                error="",
                chassis_summary=summary,
                vpt=vpt,
                bushing_vp=bvp,
            )
            self.models = _models(m.tire, self._tire_key, m.tire_name, chassis, key, name)
        return True

    def _read_chassis(self, data, name, spindle, bushing, interpolate, quantity=None):
        from fbs_core.io import load_frf, prepare_chassis, require_dofs

        sp_name, sp_num = parse_node(spindle, "spindle")
        bu_name, bu_num = parse_node(bushing, "bushing")
        nodes = {}
        if sp_num is not None:
            nodes[sp_num] = sp_name = "spindle"
        if bu_num is not None:
            nodes[bu_num] = bu_name = "bushing"
        if sp_num is not None and sp_num == bu_num:
            raise FBSError(f"the spindle and the bushing must be different nodes, got {sp_num}")
        res = load_frf(data, filename=name, nodes=nodes or None, quantity=quantity)
        present = sorted({parse_label(x)[0] for x in res.frf.outputs + res.frf.inputs})
        for role, node, given in (("spindle", sp_name, spindle), ("bushing", bu_name, bushing)):
            if node not in present:
                raise DOFError(
                    f"no {role} node {given.strip()!r} in the file; its nodes: "
                    f"{', '.join(present)}; give the {role} node by name or number"
                )
        frf, notes = prepare_chassis(res.frf, spindle=sp_name, bushing=bu_name)
        require_dofs(
            frf, outputs=BUSHING, what="the chassis FRF (every view offers the six bushing DOFs)"
        )
        chassis = FRFChassis(frf, interpolate=interpolate)
        used = []
        for k in HARMONICS:
            f = harmonic(k).frequencies()
            chassis.on_grid(f)  # FrequencyGridError unless present / interpolated
            used.append(chassis.needs_interpolation(f))
        if any(used):
            notes.append(
                "interpolated onto the analysis grids of harmonics "
                + ", ".join(str(k) for k, u in zip(HARMONICS, used, strict=True) if u)
                + " (linear in real and imaginary part)"
            )
        summary = res.summary + ("\nchassis: " + "; ".join(notes) if notes else "")
        chosen = {"quantity": quantity} if quantity else {}  # digests of files that say it
        key = _digest(data, spindle=spindle, bushing=bushing, interpolate=interpolate, **chosen)
        return chassis, summary, key

    def _read_measured(self, data, name, spindle, bushing, interpolate, quantity=None):
        """A measured set and the geometry upload -> the spindle chassis (docs/vpt.md)."""
        from fbs_core.io import load_measured_chassis

        assert self._geometry is not None
        geo, geo_name = self._geometry
        sp_name, _ = parse_node(spindle, "spindle (the virtual point of the geometry)")
        bu_name, bu_num = parse_node(bushing, "bushing")
        nodes = {bu_num: "bushing"} if bu_num is not None else None
        mc = load_measured_chassis(
            data,
            geo,
            frf_filename=name,
            geometry_filename=geo_name,
            nodes=nodes,
            origin=sp_name,
            bushing="bushing" if bu_num is not None else bu_name,
            quantity=quantity,
            interpolate=interpolate,
        )
        chassis = mc.chassis
        used = []
        for k in HARMONICS:
            f = harmonic(k).frequencies()
            chassis.on_grid(f)  # FrequencyGridError unless present / interpolated
            used.append(chassis.needs_interpolation(f))
        summary = mc.summary
        if any(used):
            summary += "\nchassis: interpolated onto the analysis grids of harmonics " + ", ".join(
                str(k) for k, u in zip(HARMONICS, used, strict=True) if u
            )
        chosen = {"quantity": quantity} if quantity else {}
        key = _digest(
            data + b"\0geometry\0" + geo,
            spindle=spindle,
            bushing=bushing,
            interpolate=interpolate,
            **chosen,
        )
        return chassis, summary, key, mc.vpt, mc.bushing_vp

    def load_tire(self, data: bytes, filename: str | None = None) -> bool:
        """Read a modal tire model upload (project HDF5 format or MATLAB).

        Returns True when it is now the session's tire; else ``error`` says why and
        nothing else changed.
        """
        with self._lock:
            return self._load_tire(data, filename)

    def _load_tire(self, data: bytes, filename: str | None) -> bool:
        from fbs_core.io import import_tire_model

        name = filename or "upload"
        try:
            res = import_tire_model(bytes(data), filename=name)
            notes = check_tire(res.model)
            check_pair(res.model, self.models.chassis)
        except FBSError as e:
            self.error = f"{name}: {e}"
            return False
        key = _digest(bytes(data))
        review = self.review
        cands = review.candidates or CandidateSet([Candidate.reference()])
        if key in cands.digests:  # the same file again: it becomes the current tire
            cands = cands.with_current(key)
        else:
            try:
                cand = Candidate(_unique(name, cands.names), key, res.model, notes=tuple(notes))
                cands = cands.add(cand, current=True)
            except FBSError as e:
                self.error = f"{name}: {e}"
                return False
        summary = res.summary + ("\nnotes: " + "; ".join(notes) if notes else "")
        review, pending = _settle(review.with_candidates(cands), self.pending)
        self._use_candidates(review, summary)
        self.pending = pending
        return True

    def apply_link(self, text: str) -> bool:
        """Restore the review a link names (:func:`app.review.review_link`): its targets and
        incumbent rule at once, its candidates as their files are uploaded (``pending``).
        A malformed value is the ``error`` and changes nothing."""
        if not text:
            return True
        with self._lock:
            try:
                want = read_review_link(text)
                review = self.review
                if want.targets:
                    review = review.without_targets().with_targets(want.targets)
                review, pending = _settle(review, want)
            except FBSError as e:
                self.error = f"link: {e}"
                return False
            if review.candidates is not self.review.candidates:
                self._use_candidates(review)
            else:
                self.param.update(error="", review=review)
            self.pending = pending
            return True

    def _use_candidates(self, review: Review, tire_summary: str | None = None) -> None:
        """Make ``review`` the session's and its current candidate the session's tire."""
        cands = review.candidates
        cur = None if cands is None else cands.current
        models = candidate_models(self.models, cur or Candidate.reference())
        self._tire_key = "" if cur is None or cur.is_reference else cur.digest
        changes: dict = {"error": "", "review": review}
        if tire_summary is not None:
            changes["tire_summary"] = tire_summary
        elif cur is not None:
            changes["tire_summary"] = f"candidate {cur.name!r}: {cur.model.n_modes} modes" + (
                "\nnotes: " + "; ".join(cur.notes) if cur.notes else ""
            )
        with param.parameterized.batch_call_watchers(self):
            self.param.update(changes)
            self.models = models

    # -- the review: candidates, targets -----------------------------------------------------
    def _change_review(self, what: str, change) -> bool:
        """Apply ``change(review) -> review``; an FBSError is the message, nothing changes."""
        with self._lock:
            try:
                review = change(self.review)
            except FBSError as e:
                self.error = f"{what}: {e}"
                return False
            if review.candidates is self.review.candidates:
                self.param.update(error="", review=review)
            else:
                self._use_candidates(review)
            return True

    def select_candidate(self, candidate: str) -> bool:
        """Make a candidate (name or digest) the current tire of the detail views."""

        def change(r: Review) -> Review:
            if r.candidates is None:
                r.digest_of(candidate)  # only the reference: raises for any other
                return r
            return r.with_candidates(r.candidates.with_current(candidate))

        done = self._change_review("current candidate", change)
        if done and self.pending is not None and self.pending.current:  # the user's choice
            self.pending = LinkReview(self.pending.candidates, "", self.pending.incumbent)
        return done

    def remove_candidate(self, candidate: str) -> bool:
        """Remove a candidate (name or digest); the last one is kept."""

        def change(r: Review) -> Review:
            if r.candidates is None or len(r.candidates) <= 1:
                raise FBSError("the session needs one tire: the last candidate stays")
            return r.with_candidates(r.candidates.remove(candidate))

        return self._change_review(f"removing {candidate!r}", change)

    def describe_candidate(self, candidate: str, **fields: str) -> bool:
        """Change a candidate's name, supplier, size or version."""

        def change(r: Review) -> Review:
            cands = r.candidates or CandidateSet([Candidate.reference()])
            new = cands.renamed(candidate, **fields)
            out = r.with_candidates(new)
            old = cands.get(candidate)
            inc = r.incumbent
            if inc is not None and inc.candidate in (old.name, old.digest):  # follows a rename
                out = out.with_incumbent(
                    IncumbentTarget(new.get(old.digest).name, inc.margin_db, inc.dofs)
                )
            return out

        return self._change_review(f"candidate {candidate!r}", change)

    def load_targets(self, data: bytes, filename: str | None = None) -> bool:
        """Read target curves (target CSV or UFF 58, :func:`fbs_core.targets.read_targets`)
        for the bushing DOFs (corner scope) or the car's response points (vehicle scope,
        e.g. ``seat_fl:z``); each replaces a target of the same DOF and harmonic."""
        name = filename or "upload"

        def change(r: Review) -> Review:
            targets = read_targets(bytes(data), filename=name, dofs=TARGET_DOFS)
            if not targets:
                raise FBSError("the file holds no target")
            return r.with_targets(targets)

        return self._change_review(name, change)

    def add_target(self, target: Target) -> bool:
        """Add one target (e.g. straight segments typed on the page)."""
        return self._change_review(f"target of {target.dof}", lambda r: r.with_targets((target,)))

    def clear_targets(self) -> bool:
        """Remove every target curve (the incumbent rule stays)."""
        return self._change_review("targets", lambda r: r.without_targets())

    def set_incumbent(self, candidate: str | None, margin_db: float = 0.0) -> bool:
        """Judge against "the incumbent + margin dB" (None: no incumbent rule)."""

        def change(r: Review) -> Review:
            if candidate is None:
                return r.with_incumbent(None)
            name = r.candidates.get(candidate).name if r.candidates is not None else candidate
            return r.with_incumbent(IncumbentTarget(name, margin_db))

        return self._change_review("incumbent", change)

    def reset(self) -> None:
        """Back to the shipped reference tire and chassis."""
        with self._lock:
            self._last_chassis = self._last_settings = None
            self._geometry = None
            self._tire_key = self._chassis_key = ""
            review = self.review
            keep = Review(None, review.targets)  # the targets stay, the uploads go
            with param.parameterized.batch_call_watchers(self):
                self.param.update(
                    error="",
                    tire_summary="",
                    chassis_summary="",
                    geometry_summary="",
                    vpt=None,
                    bushing_vp=None,
                    review=keep,
                )
                self.models = REFERENCE

    def describe(self) -> str:
        """One line: which models the views use."""
        return self.models.describe()
