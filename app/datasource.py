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

Checks beyond those of :mod:`fbs_core.io` (every view must run on the models):

- chassis: six spindle DOFs (inputs and outputs) and all six bushing outputs
  (``fbs_core.io.prepare_chassis`` / ``require_dofs``); lines on every harmonic's analysis
  grid, either present in the file or, only when the user ticks it, interpolated
  (``FRF.interpolate``, linear in real and imaginary part, never extrapolated);
- tire: hub DOFs ``hub:x`` ... ``hub:rz``, at least 20 complex modes, the patch
  participation and operating points of all seven harmonic cases and the speeds of the
  eigenfrequency view;
- the pair: the interface matrix ``Y_jj^A + Y_jj^E`` (eq. 2.44) well conditioned on every
  harmonic's grid (``fbs_core.io.interface_check``).

A refused upload leaves the state as it was and says why in :attr:`DataSource.error`.
"""

from __future__ import annotations

import hashlib
import threading

import numpy as np
import param

import fbs_core
from fbs_core.dofs import parse_label
from fbs_core.errors import DOFError, FBSError, FrequencyGridError
from fbs_core.frf import FRF

__all__ = [
    "CHASSIS_ACCEPT",
    "EIGEN_SPEEDS",
    "HARMONICS",
    "TIRE_ACCEPT",
    "DataSource",
    "FRFChassis",
    "Models",
    "REFERENCE",
]

DIRECTIONS = ("x", "y", "z", "rx", "ry", "rz")
SPINDLE = tuple(f"spindle:{d}" for d in DIRECTIONS)
BUSHING = tuple(f"bushing:{d}" for d in DIRECTIONS)
HUB = tuple(f"hub:{d}" for d in DIRECTIONS)
#: Harmonic cases every view may ask for.
HARMONICS = tuple(range(1, 8))
#: Speeds of the eigenfrequency view (thesis fig. 5.8), km/h.
EIGEN_SPEEDS = (20.0, 80.0, 120.0)
#: Smallest number of complex tire modes accepted (a truncation map needs N = 10 < total).
MIN_TIRE_MODES = 20
#: File endings offered by the upload widgets.
CHASSIS_ACCEPT = ".uff,.unv,.uf,.58,.mat,.csv,.txt,.h5,.hdf5,.hdf"
TIRE_ACCEPT = ".h5,.hdf5,.hdf,.mat"


def _grid(k: int) -> np.ndarray:
    return np.asarray(fbs_core.harmonic(k).frequencies(), float)


class FRFChassis:
    """A chassis given by a measured or computed mobility FRF, used like ``ChassisModel``.

    Parameters
    ----------
    frf : FRF
        Mobility with inputs ``spindle:*`` and outputs ``spindle:*`` and ``bushing:*``
        (as returned by :func:`fbs_core.io.prepare_chassis`).
    interpolate : bool
        Lines the file does not hold are interpolated with :meth:`FRF.interpolate`
        (chosen explicitly by the user); otherwise such a request is refused.
    """

    def __init__(self, frf: FRF, interpolate: bool = False) -> None:
        self.frf = frf
        self.interpolate = bool(interpolate)

    def __repr__(self) -> str:
        return f"FRFChassis({self.frf!r}, interpolate={self.interpolate})"

    def _on(self, freq: np.ndarray) -> FRF:
        F = self.frf.freq
        f = np.asarray(freq, float)
        tol = 1e-9 * np.maximum(1.0, np.abs(f))
        idx = np.clip(np.searchsorted(F, f - tol), 0, F.size - 1)
        hit = np.abs(F[idx] - f) <= tol
        if hit.all():
            return self.frf.isel(freq=idx)
        if self.interpolate:
            return self.frf.interpolate(f)
        miss = f[~hit]
        raise FrequencyGridError(
            f"the chassis FRF ({F.size} lines, {F[0]:g}-{F[-1]:g} Hz) has no line at "
            f"{miss.size} of the {f.size} analysis frequencies {f[0]:g}-{f[-1]:g} Hz "
            f"(first: {miss[0]:g} Hz); tick 'interpolate onto the analysis grid' to "
            "interpolate it explicitly (linear in real and imaginary part)"
        )

    def mobility(self, freq, outputs=None, inputs=None, quantity: str = "mobility") -> FRF:
        """The FRF on ``freq`` (Hz), same signature as ``ChassisModel.mobility``."""
        Y = self._on(freq)
        Y = Y.sel(
            outputs=SPINDLE + BUSHING if outputs is None else list(outputs),
            inputs=SPINDLE if inputs is None else list(inputs),
        )
        return Y if quantity == Y.quantity else Y.to(quantity)


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


def check_tire(tire) -> list[str]:
    """Refuse a tire model some view cannot run on; returns notes.

    Raises
    ------
    FBSError
        Naming the missing hub DOFs, modes, wavelengths or operating points.
    """
    if tuple(tire.hub_dofs) != HUB:
        raise FBSError(
            f"the tire's hub DOFs must be {', '.join(HUB)}, got {', '.join(tire.hub_dofs)}"
        )
    if tire.n_modes < MIN_TIRE_MODES:
        raise FBSError(
            f"the tire model has {tire.n_modes} complex modes; the truncation study "
            f"needs at least {MIN_TIRE_MODES}"
        )
    for k in HARMONICS:
        f = _grid(k)
        try:
            tire.truncations(f[[0, -1]], fbs_core.harmonic(k), [tire.n_modes])
        except FBSError as e:
            raise type(e)(f"harmonic {k}: {e}") from None
    for v in EIGEN_SPEEDS:
        try:
            tire.eigenfrequencies(v)
        except FBSError as e:
            raise type(e)(f"eigenfrequency view (fig. 5.8, {v:g} km/h): {e}") from None
    notes = []
    if tire.n_modes < 400:
        notes.append(f"{tire.n_modes} complex modes: a chosen N above that uses all modes")
    return notes


def check_pair(tire, chassis) -> None:
    """Every harmonic grid is available and the interface (eq. 2.44) is well conditioned."""
    from fbs_core.io import interface_check

    tire = fbs_core.reference_tire() if tire is None else tire
    chassis = fbs_core.reference_chassis() if chassis is None else chassis
    pairs = list(zip(HUB, SPINDLE, strict=True))
    for k in HARMONICS:
        f = _grid(k)
        try:
            Yjj = tire.truncations(f, fbs_core.harmonic(k), [tire.n_modes])[0][0]
            YA = FRF(f, Yjj, HUB, HUB, "mobility")
            YE = chassis.mobility(f, outputs=SPINDLE, inputs=SPINDLE)
            interface_check(YA, YE, interface=pairs)
        except FBSError as e:
            raise type(e)(f"harmonic {k} ({f[0]:g}-{f[-1]:g} Hz): {e}") from None


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

    def __init__(self, **params):
        super().__init__(**params)
        self._tire_key = self._chassis_key = ""
        self._last_chassis: tuple[bytes, str] | None = None
        self._last_settings: tuple[str, str, bool] | None = None
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

    def _settings(self) -> tuple[str, str, bool]:
        return (self.spindle, self.bushing, bool(self.interpolate))

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
        self._last_settings = (sp, bu, interp)
        try:
            chassis, summary, key = self._read_chassis(bytes(data), name, sp, bu, interp)
            check_pair(self.models.tire, chassis)
        except FBSError as e:
            self.error = f"{name}: {e}"
            return False
        self._chassis_key = key
        m = self.models
        with param.parameterized.batch_call_watchers(self):
            self.param.update(
                spindle=sp, bushing=bu, interpolate=interp, error="", chassis_summary=summary
            )
            self.models = _models(m.tire, self._tire_key, m.tire_name, chassis, key, name)
        return True

    def _read_chassis(self, data, name, spindle, bushing, interpolate):
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
        res = load_frf(data, filename=name, nodes=nodes or None)
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
            Y = chassis._on(_grid(k))  # FrequencyGridError unless present / interpolated
            used.append(not np.isin(Y.freq, frf.freq).all())
        if any(used):
            notes.append(
                "interpolated onto the analysis grids of harmonics "
                + ", ".join(str(k) for k, u in zip(HARMONICS, used, strict=True) if u)
                + " (linear in real and imaginary part)"
            )
        summary = res.summary + ("\nchassis: " + "; ".join(notes) if notes else "")
        key = _digest(data, spindle=spindle, bushing=bushing, interpolate=interpolate)
        return chassis, summary, key

    def load_tire(self, data: bytes, filename: str | None = None) -> bool:
        """Read a modal tire model upload (project HDF5 format or MATLAB).

        Returns True when it is now the session's tire; else ``error`` says why and
        nothing else changed.
        """
        with self._lock:
            return self._load_tire(data, filename)

    def _load_tire(self, data: bytes, filename: str | None) -> bool:
        from fbs_core.io import load_tire_model

        name = filename or "upload"
        try:
            res = load_tire_model(bytes(data), filename=name)
            notes = check_tire(res.model)
            check_pair(res.model, self.models.chassis)
        except FBSError as e:
            self.error = f"{name}: {e}"
            return False
        key = _digest(bytes(data))
        self._tire_key = key
        m = self.models
        summary = res.summary + ("\nnotes: " + "; ".join(notes) if notes else "")
        with param.parameterized.batch_call_watchers(self):
            self.param.update(error="", tire_summary=summary)
            self.models = _models(
                res.model, key, name, m.chassis, self._chassis_key, m.chassis_name
            )
        return True

    def reset(self) -> None:
        """Back to the shipped reference tire and chassis."""
        with self._lock:
            self._last_chassis = self._last_settings = None
            self._tire_key = self._chassis_key = ""
            with param.parameterized.batch_call_watchers(self):
                self.param.update(error="", tire_summary="", chassis_summary="")
                self.models = REFERENCE

    def describe(self) -> str:
        """One line: which models the views use."""
        return self.models.describe()
