"""A Campbell diagram that follows the waves: branches tracked by their belt shape.

:func:`fbs_core.analysis.campbell` draws the modal model's own tracked modes; that
tracking (made when the model was built, :func:`fbs_core.tire.track_modes`) pairs the
modes of neighbouring operating points by MAC *and* frequency distance and orders the
identities by their speed-averaged frequency, which is what the interpolation needs but
not what a wave does: measured against the ring's closed form, those branches do not
follow the forward waves of orders 4-8 (docs/modes.md). With the tire's matrices the
branches can follow the physics instead. :func:`wave_campbell`

* solves the tire's complex modes at every speed (``tire.system(v)``, dense, cached);
* splits every mode's shape (mass-weighted ``|x|^2``) over its **characters**: each
  belt family and ring order, divided into its forward and backward wave by the
  travelling index of the order's ``cos`` / ``sin`` pair (forward part
  ``(1 - tau) / 2``), and the six hub DOFs (:func:`fbs_core.tire.belt.order_content`).
  There are as many characters as DOFs with mass, so as many as vibration modes;
* gives every character one mode at every speed, the one-to-one assignment of largest
  total content: a branch *is* a wave ("ip n=4 forward"), whichever mode carries it,
  so it keeps its label through crossings and veerings by construction. (Tracking
  modes from speed to speed by the MAC of their full shapes was tried first: on the
  loaded tire the shapes of the dense belt modes mix at almost every 2.5 km/h step,
  and the tracked chains lost the forward waves of orders 2-5.);
* shows veering honestly: the carrier's share of its character (``purity``; 1 for a
  pure wave, about 0.5 in the middle of a veering) and the MAC of the carriers of
  consecutive speeds (``mac``: near 1 when the same physical mode carried the wave,
  small where the wave passed to another mode; ``veering`` flags ``mac < veer_mac``);
* gives the ring's closed form beside every in-plane (``ip``) wave of order >= 2
  (:func:`fbs_core.tire.ring_closed_form`, Huang & Soedel 1987);
* and a readable default selection (:meth:`WaveCampbell.selection`): the branches
  inside a harmonic's band, of the orders that carry the response first.

Tests: with the tire's additions switched off (the in-plane ring alone, rim fixed, no
road, undamped) the tracked branches are the closed form; on the loaded reference tire
every ring order 2..8 has a forward and a backward branch near it (docs/modes.md).
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import linear_sum_assignment

from .._typing import FloatArray, IntArray
from ..errors import FBSError
from ..harmonics import HARMONICS
from ..harmonics import harmonic as _harmonic
from ..tire.belt import belt_coordinates, order_content
from ..tire.params import FAMILIES, TireParameters
from ..tire.ring import build_tire_system, patch_load, ring_closed_form
from ..vocabulary import DIRECTIONS

__all__ = ["WaveCampbell", "wave_campbell", "HUB_CONDITIONS", "STORED_FILE", "save_waves"]

#: ``progress(done, total)``: the speeds solved so far (it may raise to stop the solve).
Progress = Callable[[int, int], None]

#: Tracked results kept per process (by model, speeds, hub and ``veer_mac``).
CACHE_SIZE = 4

#: The reference tire's tracked branches, stored (``scripts/build_reference_waves.py``):
#: the 43 dense solves take 12 s on an idle core and many minutes on a busy one, and the
#: result is the same for every session and every start of the server.
STORED_FILE = Path(__file__).resolve().parents[2] / "data" / "reference_waves.npz"

#: Version of the tracking's numbers: a stored result of another version is not used
#: (raise it whenever a change of this module changes what :func:`_track` returns).
TRACKING_VERSION = 1

#: How the hub is held: ``"free"`` (the tire on the road, as coupled) or ``"fixed"``
#: (the rim clamped: the "rim-fixed" belt modes of MF-Swift and the ring's closed form).
HUB_CONDITIONS = ("free", "fixed")


@dataclass(frozen=True, eq=False)
class WaveCampbell:
    """Tire eigenfrequencies versus speed, branches tracked by shape and labelled.

    Attributes
    ----------
    speeds : ndarray, shape (n_v,)
        Speeds in km/h.
    freq, damping : ndarray, shape (n_v, n_b)
        Eigenfrequency (Hz) and damping ratio of every branch (NaN where it does not
        exist: a branch born or ended where the number of vibration modes changes).
    mac : ndarray, shape (n_v - 1, n_b)
        MAC (mass weighted, full shapes) between the modes carrying the branch at speeds
        ``i`` and ``i + 1``.
    veer_mac : float
        Steps with ``mac < veer_mac`` are flagged (:attr:`veering`).
    family : ndarray of str, shape (n_b,)
        Belt family of the wave (``ip``, ``op``, ``w1`` ... ``w6``; :data:`FAMILIES`), or
        ``hub:x`` ... ``hub:rz`` for the six hub characters.
    order : ndarray of int, shape (n_b,)
        Ring order ``n`` (-1 for the hub characters).
    share : ndarray, shape (n_b,)
        Mean purity over the speeds.
    purity : ndarray, shape (n_v, n_b)
        Share of the branch's character in the mode that carries it (1: a pure wave).
    direction : ndarray of str, shape (n_b,)
        ``"forward"`` (with the spin), ``"backward"`` or ``"standing"`` (order 0, hub).
    travelling : ndarray, shape (n_v, n_b)
        Travelling index of the branch's order in its carrier (-1 forward, +1 backward).
    order_at : ndarray of int, shape (n_v, n_b)
        The carrier's own dominant order (where a branch is carried by a mixed mode).
    closed_form : ndarray, shape (n_v, n_b)
        The ring's closed-form frequency of an ``ip`` branch of order >= 2 in its
        direction (NaN for the others).
    excitation : ndarray, shape (n_v, n_b, n_h)
        How strongly each harmonic's patch load drives the branch's mode at the hub at
        resonance, ``|omega_r| |psi_hub,r| |chi_r^T f_h| / |Re lambda_r|`` (m/s per m
        of road; 0 with the hub fixed).
    stored : ndarray of int, shape (n_v, n_b)
        The modal model's stored pair that is this branch's mode at speed ``i`` (the
        same pole), where the speed is an operating point of the model; else -1.
    hub : str
        ``"free"`` or ``"fixed"``.
    """

    speeds: FloatArray
    freq: FloatArray
    damping: FloatArray
    mac: FloatArray
    veer_mac: float
    family: Any
    order: IntArray
    share: FloatArray
    purity: FloatArray
    direction: Any
    travelling: FloatArray
    order_at: IntArray
    closed_form: FloatArray
    excitation: FloatArray
    stored: IntArray
    hub: str

    def __post_init__(self) -> None:
        # results are shared (cached per model): read-only
        for val in vars(self).values():
            if isinstance(val, np.ndarray):
                val.setflags(write=False)

    @property
    def veering(self) -> Any:
        """Steps (n_v - 1, n_b) where the tracked shape did not survive: ``mac < veer_mac``."""
        return self.mac < self.veer_mac

    def labels(self) -> tuple[str, ...]:
        """``"ip n=4 forward"`` (or ``"hub:z"``) per branch."""
        return tuple(
            str(f) if n < 0 else f"{f} n={int(n)} {d}"
            for f, n, d in zip(self.family, self.order, self.direction, strict=True)
        )

    def find(self, family: str, order: int, direction: str) -> int:
        """The branch of a wave, e.g. ``find("ip", 4, "forward")``.

        Raises
        ------
        FBSError
            When the wave is not among the branches (e.g. above ``fmax``).
        """
        sel = np.flatnonzero(
            (self.family == family) & (self.order == int(order)) & (self.direction == direction)
        )
        if not sel.size:
            raise FBSError(f"no branch {family} n={order} {direction}; see labels()")
        return int(sel[0])

    def in_band(self, harmonic: int) -> Any:
        """Branches (n_b,) that come inside the harmonic's frequency band at a speed of its
        speed range."""
        h = _harmonic(harmonic)
        lo, hi = h.freq_range
        sv = (self.speeds >= h.speed_range[0] - 1e-9) & (self.speeds <= h.speed_range[1] + 1e-9)
        F = self.freq[sv]
        return np.any((F >= lo) & (F <= hi), axis=0)

    def order_weight(self, harmonic: int) -> dict[tuple[str, int], float]:
        """How much each (family, order) carries of the harmonic's hub excitation inside
        its band: the sum of its branches' largest excitation, largest first."""
        h = _harmonic(harmonic)
        k = h.k - 1
        band = self.in_band(harmonic)
        ex = np.nan_to_num(self.excitation[:, :, k]).max(axis=0) * band
        w: dict[tuple[str, int], float] = {}
        for f, n, e in zip(self.family, self.order, ex, strict=True):
            w[(str(f), int(n))] = w.get((str(f), int(n)), 0.0) + float(e)
        return dict(sorted(w.items(), key=lambda kv: -kv[1]))

    def selection(self, harmonic: int, n_orders: int = 4, top: int = 16) -> IntArray:
        """A readable default: the branches inside the harmonic's band whose (family,
        order) is among the ``n_orders`` that carry most of its hub excitation, the most
        excited first, at most ``top``; the rest on demand (all branches are there).

        Raises
        ------
        FBSError
            For ``n_orders`` or ``top`` below 1.
        """
        if n_orders < 1 or top < 1:
            raise FBSError(f"n_orders and top must be >= 1, got {n_orders}, {top}")
        h = _harmonic(harmonic)
        w = self.order_weight(h.k)
        carry = [fo for fo, x in list(w.items())[:n_orders] if x > 0]
        band = self.in_band(h.k)
        ex = np.nan_to_num(self.excitation[:, :, h.k - 1]).max(axis=0)
        ok = band & np.array(
            [(str(f), int(n)) in carry for f, n in zip(self.family, self.order, strict=True)]
        )
        sel = np.flatnonzero(ok)
        out: IntArray = sel[np.argsort(-ex[sel], kind="stable")][:top]
        return out

    def export_mapping(self) -> dict[str, Any]:
        """The data as a mapping for :func:`fbs_core.io.export_result` (arrays with axes)."""
        return {
            "freq": (("speed_kmh", "branch"), self.freq),
            "damping": (("speed_kmh", "branch"), self.damping),
            "mac_step": (("step", "branch"), self.mac),
            "closed_form": (("speed_kmh", "branch"), self.closed_form),
            "purity": (("speed_kmh", "branch"), self.purity),
            "family": (("branch",), np.asarray(self.family, dtype=str)),
            "order": (("branch",), self.order),
            "direction": (("branch",), np.asarray(self.direction, dtype=str)),
            "coords": {
                "speed_kmh": self.speeds,
                "branch": np.arange(self.order.size),
                "step": np.arange(self.speeds.size - 1),
            },
            "metadata": {"hub": self.hub, "veer_mac": self.veer_mac},
        }


def _system(source: Any, speed: float, hub: str) -> tuple[Any, Any, Any, tuple[str, ...]]:
    if isinstance(source, TireParameters):
        s = build_tire_system(speed, source)
    else:
        s = source.system(speed)
    M, C, K = (np.real(np.asarray(a)) for a in (s.M, s.C, s.K))
    dofs = tuple(s.dofs)
    if hub == "fixed":
        M, C, K = (a[6:, 6:] for a in (M, C, K))
        dofs = dofs[6:]
    return M, C, K, dofs


def _params(source: Any) -> TireParameters:
    if isinstance(source, TireParameters):
        return source
    p = getattr(source, "params", None)
    if p is None:
        raise FBSError(
            "wave_campbell needs the tire's matrices: a model with physical parameters "
            "(a supplier's modal model has only its hub DOFs; use fbs_core.campbell)"
        )
    assert isinstance(p, TireParameters)
    return p


def _characters(content: FloatArray, trav: FloatArray, hub_share: FloatArray) -> FloatArray:
    """How much of every character each mode has, shape (n_m, n_char).

    Characters: every belt family and order split into its forward and backward wave
    (``(1 - tau) / 2`` and ``(1 + tau) / 2`` of the order's content; order 0 standing),
    in the order of :func:`_character_labels`, then the six hub DOFs. Each row sums to 1
    (a mode's mass-weighted ``|x|^2`` split over where it sits)."""
    n_m, n_f, n_o = content.shape
    belt = 1.0 - hub_share.sum(axis=1, keepdims=True)  # (n_m, 1)
    fw = content * (1 - trav) / 2
    bw = content * (1 + trav) / 2
    fw[:, :, 0] = content[:, :, 0]  # order 0: no travelling pair
    bw[:, :, 0] = 0.0
    waves = np.stack([fw, bw], axis=-1).reshape(n_m, -1) * belt  # (f, n, dir) flattened
    out: FloatArray = np.concatenate([waves, hub_share], axis=1)
    return out


def _character_labels(n_f: int, n_o: int) -> tuple[list[str], list[int], list[str]]:
    fam, order, direction = [], [], []
    for f in range(n_f):
        for n in range(n_o):
            for d in ("forward", "backward"):
                fam.append(FAMILIES[f])
                order.append(n)
                direction.append("standing" if n == 0 else d)
    for d in DIRECTIONS:
        fam.append(f"hub:{d}")
        order.append(-1)
        direction.append("standing")
    return fam, order, direction


def _track(
    source: Any,
    speeds: tuple[float, ...],
    hub: str,
    veer_mac: float,
    progress: Progress | None = None,
) -> WaveCampbell:
    """The tracked branches: one dense complex-mode solve per speed (``progress(i, n)``
    after each), then the characters assigned; see the module notes."""
    from ..tire import complex_modes

    params = _params(source)
    wl = np.array([h.wavelength for h in HARMONICS])
    loads = None
    rows = []
    prev = None
    for i_v, v in enumerate(speeds):
        if progress is not None:
            progress(i_v, len(speeds))
        M, C, K, dofs = _system(source, float(v), hub)
        md = complex_modes(M, C, K)
        pos = np.flatnonzero(md.poles[0::2].imag > 0)  # vibration modes only
        lam = md.poles[0::2][pos]
        psi = md.psi[:, 0::2][:, pos]
        chi = md.chi[:, 0::2][:, pos]
        w = np.clip(np.diag(M), 0.0, None)
        if hub == "fixed":  # the belt alone: no hub rows
            full, wf = np.vstack([np.zeros((6, psi.shape[1])), psi]), np.r_[np.zeros(6), w]
            coords = belt_coordinates(_HUB + dofs)
        else:
            full, wf, coords = psi, w, belt_coordinates(dofs)
        content, trav = order_content(full, coords, wf)
        e = wf[:, None] * np.abs(full) ** 2
        hub_share = (e[coords.hub] / np.maximum(e.sum(axis=0), 1e-300)).T  # (n_m, 6)
        chars = _characters(content, trav, hub_share)
        if loads is None:
            loads = np.array([patch_load(float(x), params) for x in wl])  # (n_h, n_dof)
        if hub == "fixed":
            ex = np.zeros((lam.size, wl.size))
        else:
            amp = np.abs(lam) * np.linalg.norm(psi[:6], axis=0) / np.abs(lam.real)
            ex = (amp[None, :] * np.abs(loads @ chi)).T  # (n_m, n_h)
        stored = np.full(lam.size, -1)
        if not isinstance(source, TireParameters) and hub == "free":
            hit = np.flatnonzero(np.isclose(np.asarray(source.speeds), v, rtol=0, atol=1e-9))
            if hit.size:
                model = np.asarray(source.poles)[hit[0], 0::2]
                osc = np.flatnonzero(model.imag > 0)
                r, c = linear_sum_assignment(np.abs(model[osc][:, None] - lam[None, :]))
                stored[c] = osc[r]
        # every mode carries one character, every character at most one mode: the
        # assignment of largest total content (a wave keeps its label through veerings)
        mode_of, char_of = linear_sum_assignment(-chars)
        carrier = np.full(chars.shape[1], -1)
        carrier[char_of] = mode_of
        mac = np.full(chars.shape[1], np.nan)
        if prev is not None:
            p_psi, p_w, p_car = prev
            ok = (carrier >= 0) & (p_car >= 0)
            a = p_psi[:, p_car[ok]] * np.sqrt(p_w)[:, None]
            b = psi[:, carrier[ok]] * np.sqrt(w)[:, None]
            num = np.abs(np.sum(a.conj() * b, axis=0)) ** 2
            mac[ok] = num / ((np.abs(a) ** 2).sum(0) * (np.abs(b) ** 2).sum(0))
        rows.append((lam, chars, trav, content, ex, stored, carrier, mac))
        prev = (psi, w, carrier)
    if progress is not None:
        progress(len(speeds), len(speeds))
    n_v, n_c = len(speeds), rows[0][1].shape[1]
    n_f, n_o = rows[0][3].shape[1:]
    fam, order, direction = _character_labels(n_f, n_o)
    freq = np.full((n_v, n_c), np.nan)
    damp = np.full((n_v, n_c), np.nan)
    purity = np.zeros((n_v, n_c))
    tau = np.full((n_v, n_c), np.nan)
    exc = np.full((n_v, n_c, wl.size), np.nan)
    sto = np.full((n_v, n_c), -1)
    mac = np.full((n_v - 1, n_c), np.nan)
    order_at = np.full((n_v, n_c), -1)
    for i, (lam, chars, trav, content, ex, stored, carrier, m) in enumerate(rows):
        ok = carrier >= 0
        k = carrier[ok]
        freq[i, ok] = lam[k].imag / (2 * np.pi)
        damp[i, ok] = -lam[k].real / np.abs(lam[k])
        purity[i, ok] = chars[k, np.flatnonzero(ok)]
        exc[i, ok] = ex[k]
        sto[i, ok] = stored[k]
        order_at[i, ok] = np.unravel_index(np.argmax(content[k].reshape(k.size, -1), axis=1),
                                           (n_f, n_o))[1]  # fmt: skip
        belt = np.flatnonzero(ok[: 2 * n_f * n_o])
        f_i, n_i = belt // (2 * n_o), (belt // 2) % n_o
        tau[i, belt] = trav[carrier[belt], f_i, n_i]
        if i:
            mac[i - 1] = m
    cf = np.full((n_v, n_c), np.nan)
    for br in range(n_c):
        if fam[br] == "ip" and order[br] >= 2:
            fw = [ring_closed_form(order[br], float(v), params) for v in speeds]
            cf[:, br] = [x[0] if direction[br] == "forward" else x[1] for x in fw]
    exists = np.isfinite(freq).any(axis=0)
    keep = np.flatnonzero(exists)
    return _subset(
        WaveCampbell(
            speeds=np.array(speeds),
            freq=freq,
            damping=damp,
            mac=mac,
            veer_mac=float(veer_mac),
            family=np.array(fam, dtype=str),
            order=np.array(order, np.intp),
            share=purity.sum(axis=0) / np.maximum(np.isfinite(freq).sum(axis=0), 1),
            purity=purity,
            direction=np.array(direction, dtype=str),
            travelling=tau,
            order_at=order_at.astype(np.intp),
            closed_form=cf,
            excitation=exc,
            stored=sto.astype(np.intp),
            hub=hub,
        ),
        keep,
    )


_HUB: tuple[str, ...] = ("hub:x", "hub:y", "hub:z", "hub:rx", "hub:ry", "hub:rz")


def wave_campbell(
    tire: Any = None,
    speeds: npt.ArrayLike | None = None,
    *,
    params: TireParameters | None = None,
    hub: str = "free",
    fmax: float | None = 450.0,
    veer_mac: float = 0.8,
    progress: Progress | None = None,
) -> WaveCampbell:
    """Campbell diagram whose branches follow the belt waves (module notes).

    Parameters
    ----------
    tire : TireModel, optional
        A model with physical parameters (default the reference tire); its operating
        points are the default speeds, and its stored modes are matched to the branches
        there (:attr:`WaveCampbell.stored`).
    speeds : array_like, shape (n_v,), optional
        Increasing speeds in km/h (>= 2).
    params : TireParameters, optional
        Keyword only: build the tire from these parameters instead of a model (then
        ``speeds`` is required).
    hub : {"free", "fixed"}
        The tire on the road with its hub free (as coupled), or the rim clamped.
    fmax : float or None
        Keep the branches that come below ``fmax`` Hz somewhere (None: all).
    veer_mac : float
        MAC below which a tracked step is flagged as veering.
    progress : callable, optional
        ``progress(done, total)`` as the speeds are solved (not called for a result
        cached or stored); an exception it raises stops the solve and is raised here.

    Returns
    -------
    WaveCampbell
        Cached per model, speeds, hub and ``veer_mac`` (one dense complex-mode solve per
        speed: about 0.2 s each on an idle core); the reference tire's is read from
        :data:`STORED_FILE` when it was stored for the same model, speeds, hub and
        ``veer_mac`` (:func:`content_key`).

    Raises
    ------
    FBSError
        For bad speeds, hub, ``fmax`` or ``veer_mac``, or a model without parameters.
    """
    if hub not in HUB_CONDITIONS:
        raise FBSError(f"unknown hub condition {hub!r}; allowed: {', '.join(HUB_CONDITIONS)}")
    if not 0.0 < veer_mac < 1.0:
        raise FBSError(f"veer_mac must lie between 0 and 1, got {veer_mac!r}")
    if fmax is not None and not (np.isfinite(fmax) and fmax > 0):
        raise FBSError(f"fmax must be a positive frequency in Hz or None, got {fmax!r}")
    source: Any
    if params is not None:
        source = params
        if speeds is None:
            raise FBSError("speeds are required with params= (there are no operating points)")
    else:
        if tire is None:
            from .. import reference_tire

            tire = reference_tire()
        _params(tire)
        source = tire
    v = np.asarray(tire.speeds if speeds is None else speeds, float).ravel()
    if v.size < 2 or np.any(np.diff(v) <= 0) or not np.all(np.isfinite(v)):
        raise FBSError(f"speeds must be >= 2 increasing values in km/h, got {v.tolist()}")
    cb = _tracked(source, tuple(float(x) for x in v), hub, float(veer_mac), progress)
    if fmax is None:
        return cb
    keep = np.flatnonzero(
        np.nanmin(np.where(np.isfinite(cb.freq), cb.freq, np.inf), axis=0) <= fmax
    )
    return _subset(cb, keep)


def _subset(cb: WaveCampbell, keep: Sequence[int] | IntArray) -> WaveCampbell:
    k = np.asarray(keep, int)
    return WaveCampbell(
        speeds=cb.speeds,
        freq=cb.freq[:, k],
        damping=cb.damping[:, k],
        mac=cb.mac[:, k],
        veer_mac=cb.veer_mac,
        family=cb.family[k],
        order=cb.order[k],
        share=cb.share[k],
        purity=cb.purity[:, k],
        direction=cb.direction[k],
        travelling=cb.travelling[:, k],
        order_at=cb.order_at[:, k],
        closed_form=cb.closed_form[:, k],
        excitation=cb.excitation[:, k],
        stored=cb.stored[:, k],
        hub=cb.hub,
    )


_cache: OrderedDict[tuple[Any, ...], WaveCampbell] = OrderedDict()
_cache_lock = threading.Lock()


def _tracked(
    source: Any,
    speeds: tuple[float, ...],
    hub: str,
    veer_mac: float,
    progress: Progress | None,
) -> WaveCampbell:
    """:func:`_track` cached per process, or the stored result when it is the same."""
    key = (source, speeds, hub, veer_mac)
    with _cache_lock:
        cb = _cache.get(key)
        if cb is not None:
            _cache.move_to_end(key)
            return cb
    cb = load_stored(source, speeds, hub, veer_mac)
    if cb is None:
        cb = _track(source, speeds, hub, veer_mac, progress)
    with _cache_lock:
        _cache[key] = cb
        while len(_cache) > CACHE_SIZE:
            _cache.popitem(last=False)
    return cb


def content_key(source: Any, speeds: Sequence[float], hub: str, veer_mac: float) -> str:
    """A digest of everything :func:`_track` reads: the tire's physical parameters, its
    stored poles (matched to the branches), the speeds, the hub condition, ``veer_mac``
    and :data:`TRACKING_VERSION`."""
    h = hashlib.sha256()
    params = _params(source)
    h.update(repr(params).encode())
    h.update(np.asarray(speeds, float).tobytes())
    if not isinstance(source, TireParameters):
        h.update(np.ascontiguousarray(np.asarray(source.poles, complex)).tobytes())
        h.update(np.asarray(source.speeds, float).tobytes())
    h.update(f"{hub}|{float(veer_mac)!r}|{TRACKING_VERSION}".encode())
    return h.hexdigest()


def save_waves(cb: WaveCampbell, path: str | Path, key: str) -> None:
    """Write a tracked result and its :func:`content_key` to ``path`` (``.npz``: plain
    arrays, no pickles)."""
    arrays: dict[str, Any] = {"content_key": np.array(key)}
    for f in fields(cb):
        arrays[f.name] = np.asarray(getattr(cb, f.name))
    np.savez_compressed(Path(path), **arrays)


def load_stored(
    source: Any, speeds: Sequence[float], hub: str, veer_mac: float, path: Path | None = None
) -> WaveCampbell | None:
    """The stored result (:data:`STORED_FILE`) when it was made of the same content
    (:func:`content_key`), else None."""
    path = STORED_FILE if path is None else path
    if not path.is_file():
        return None
    key = content_key(source, speeds, hub, veer_mac)
    with np.load(path, allow_pickle=False) as z:
        if str(z["content_key"]) != key:
            return None
        kw: dict[str, Any] = {}
        for f in fields(WaveCampbell):
            a = z[f.name]
            if f.name == "veer_mac":
                kw[f.name] = float(a)
            elif f.name == "hub":
                kw[f.name] = str(a)
            else:
                kw[f.name] = np.array(a)
    return WaveCampbell(**kw)
