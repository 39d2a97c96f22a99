"""The results of the Modes and Selection tabs, each a pure function of one
snapshot.

Which tire modes matter (:func:`participation_result`: the ranking of the tire's stored
mode pairs for the harmonic, the bushing DOF and the band), what the chosen one looks like
(:func:`mode_shape_result`: the deformed belt over one period), the Campbell diagram that
follows the belt waves (:func:`waves_result`, solved once per tire for every session on
a thread of its own, each waiting session told how it moves: :func:`waves_wait`), the
modes a case needs chosen by importance beside table 5.1's lowest ``N``
(:func:`selected_modes_result`) and the truncation of the chassis side
(:func:`chassis_truncation_result`). The numbers are the core's (:mod:`app.results.modes_compute`);
docs/modes.md derives them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

import fbs_core
from fbs_core.analysis import KINDS
from fbs_core.errors import FBSError
from fbs_core.vocabulary import percent

from .. import compute
from . import modes_compute as mc
from .base import Result, Snapshot, csv_name
from .main import res_part, residual_meta

__all__ = [
    "MEASURES",
    "TOP_BARS",
    "chassis_truncation_result",
    "mode_shape_result",
    "nearest_bar",
    "nearest_branch",
    "participation_ahead",
    "participation_result",
    "selected_modes_result",
    "waves_result",
    "waves_wait",
]

#: What each ranking measure is (CSV header, axis label).
MEASURES = {
    "loo": "leave-one-out error over the band (eq. 5.1, both paths)",
    "loo_floating": "leave-one-out error, largest over the floating band's centres",
    "share": "band share of the direct contribution (signed; ranked by magnitude)",
    "level": "relative RMS level of the direct contribution",
    "loo_direct": "leave-one-out error of the direct path alone",
}
#: Bars drawn (the CSV holds every mode).
TOP_BARS = 20
#: Frames of the mode shape drawn in the report's strip.
STRIP_FRAMES = 6


def _unavailable(s: Snapshot, view: str, name: str, why: str) -> Result:
    """A result that says why the view has nothing to show (its draw holds no data)."""
    return Result(
        columns={},
        meta={"view": view, "not available": why, "models": s.models.describe()},
        filename=csv_name(s, name, "unavailable"),
        caption=f"**Not available**: {why}",
        draw={"ready": False, "message": why},
    )


def _band_text(band: tuple[float, float]) -> str:
    return f"{band[0]:g}-{band[1]:g} Hz"


def _mode_text(p, i: int) -> str:
    if p.first_order[i]:
        return f"mode {int(p.modes[i])} (tread {p.kind[i]}, no vibration)"
    return f"mode {int(p.modes[i])} ({p.mode_freq[i]:.1f} Hz at {p.mode_speed[i]:.0f} km/h)"


def _first_order_text(p, j: int, measure: str) -> str:
    """The first-order pairs (no vibration: not ranked) with their measure, one line."""
    parts = []
    for i in np.flatnonzero(np.asarray(p.first_order, bool)):
        v = percent(float(np.asarray(getattr(p, measure), float)[i, j]))
        parts.append(f"mode {int(p.modes[i])} tread {p.kind[i]} {measure} {v:.0f} %")
    return "; ".join(parts)


# -- the ranking ------------------------------------------------------------------------------
def participation_result(s: Snapshot) -> Result:
    view = "participation of the tire modes in the bushing response"
    try:
        p = mc.participation(s.harmonic, s.f_max, s.coupling, s.models)
    except (FBSError, AttributeError, TypeError) as e:
        return _unavailable(s, view, "participation", f"the tire's per-mode terms: {e}")
    out = f"bushing:{s.dof}"
    j = p.dofs.index(out)
    # the vibration modes are ranked; the tread's first-order states (sliding, relaxation:
    # real poles, no oscillation, in the synthesis at every N) follow, unranked
    vib = p.ranking(s.mode_rank, out, vibration=True)
    first = np.flatnonzero(np.asarray(p.first_order, bool))
    order = np.concatenate([vib, first]).astype(int)
    pct = {k: percent(np.asarray(getattr(p, k), float)[order, j]) for k in MEASURES}
    kind_code = {"vibration": 0.0, "sliding": 1.0, "relaxation": 2.0}
    cols = {
        "rank": np.concatenate(
            [np.arange(1, vib.size + 1, dtype=float), np.full(first.size, np.nan)]
        ),
        "mode": p.modes[order].astype(float),
        "freq_Hz": np.where(p.first_order[order], np.nan, p.mode_freq[order]),
        "speed_kmh": np.where(p.first_order[order], np.nan, p.mode_speed[order]),
        "slip_state": np.array([kind_code[p.kind[i]] for i in order]),
        **{f"{k}_pct": v for k, v in pct.items()},
    }
    top = vib[:TOP_BARS]
    value = pct[s.mode_rank][: top.size]
    if s.mode_rank == "share":
        value = np.abs(value)
    band = _band_text(p.band)
    unranked = _first_order_text(p, j, s.mode_rank)
    meta = {
        "view": view,
        "harmonic": s.harmonic,
        "band": f"{band} (the harmonic's band up to f_max = {s.f_max:g} Hz)",
        "response DOF": out,
        "coupling": s.coupling,
        "ranked by": MEASURES[s.mode_rank],
        "mode": "stored mode pair of the tire model (members 2m and 2m + 1; docs/modes.md)",
        "share": "sum Re(c_r conj(v_e*)) / sum |v_e*|^2 over the band (adds up to 100 %)",
        "slip_state": "0 a vibration mode (ranked); 1 "
        + KINDS["sliding"]
        + "; 2 "
        + KINDS["relaxation"]
        + " (first-order states, in the synthesis at every N: "
        "listed after the ranking, unranked, without frequency or speed)",
        **{f"rank {r + 1}": _mode_text(p, int(i)) for r, i in enumerate(vib[:8])},
        "not ranked (no vibration)": unranked or "none",
        "models": s.models.describe(),
    }
    return Result(
        columns=cols,
        meta=meta,
        filename=csv_name(
            s,
            "participation",
            f"h{s.harmonic}",
            band.replace(" ", ""),
            s.dof,
            s.coupling,
            s.mode_rank,
        ),  # fmt: skip
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {out} &middot; {band} &middot; {s.coupling} "
            f"&middot; vibration modes ranked by {s.mode_rank}: first "
            f"**{_mode_text(p, int(vib[0]))}** &middot; **click a bar**: its shape"
            + (f" &middot; not ranked, no vibration: {unranked}" if unranked else "")
        ),
        draw={
            "ready": True,
            "mode": [int(m) for m in p.modes[top]],
            "label": [f"m{int(m)}" for m in p.modes[top]],
            "value": np.asarray(value, float),
            "freq": [f"{p.mode_freq[i]:.1f} Hz" for i in top],
            "speed": np.asarray(p.mode_speed[top], float),
            "share": pct["share"][: top.size],
            "loo": pct["loo"][: top.size],
            "y_label": f"{s.mode_rank} (%)",
            "unranked": (
                f"Not ranked (first-order slip states, no vibration; in every N): {unranked}"
                if unranked
                else ""
            ),
        },
        core={"participation": p},
    )


#: Shapes of the first bars computed ahead (a click on them finds its shape).
AHEAD_SHAPES = 8


def participation_ahead(old: Snapshot | None, new: Snapshot) -> Callable[[], None] | None:
    """Computed ahead once a ranking is published: the shapes of its first
    :data:`AHEAD_SHAPES` bars (what a click draws), then the rankings of the neighbouring
    harmonics (the harmonic slider moves a step at a time). Nothing when the ranking is
    unavailable."""

    def work() -> None:
        try:
            p = mc.participation(new.harmonic, new.f_max, new.coupling, new.models)
            for i in p.ranking(new.mode_rank, f"bushing:{new.dof}", vibration=True)[:AHEAD_SHAPES]:
                mc.shape(int(p.modes[i]), round(float(p.mode_speed[i]), 1), new.models)
            for k in (new.harmonic + 1, new.harmonic - 1):
                if 1 <= k <= 7:
                    mc.participation(k, new.f_max, new.coupling, new.models)
        except (FBSError, AttributeError, TypeError):
            return  # the results say why

    return work


def nearest_bar(draw: dict, x: float) -> int | None:
    """The bar (its position) under a click at ``x`` (bars at 0, 1, ...; None: none)."""
    n = len(draw.get("mode", ()))
    i = int(round(float(x)))
    return i if n and 0 <= i < n and abs(x - i) <= 0.5 else None


# -- the shape ----------------------------------------------------------------------------------
def _chosen(s: Snapshot) -> tuple[int, float, str]:
    """The mode, speed and how they were chosen (the link's, or the ranking's first)."""
    mode, speed, how = s.mode_pick, s.mode_speed, "picked"
    if mode < 0 or speed <= 0:
        p = mc.participation(s.harmonic, s.f_max, s.coupling, s.models)
        if mode < 0:
            i = int(p.ranking(s.mode_rank, f"bushing:{s.dof}", vibration=True)[0])
            mode = int(p.modes[i])
            how = (
                f"first of the ranking by {s.mode_rank} (harmonic {s.harmonic}, bushing:{s.dof}, "
                f"{_band_text(p.band)}, {s.coupling})"
            )
        if speed <= 0:
            pos = np.flatnonzero(p.modes == mode)
            if not pos.size:
                raise FBSError(f"mode {mode} is not a stored pair of the tire")
            speed = float(p.mode_speed[pos[0]])
            how += f"; speed where the harmonic {s.harmonic} line meets it"
    return int(mode), float(speed), how


def _plane(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wheel-plane coordinates (x forward, z up) of points ``(..., 3)``."""
    return a[..., 0], a[..., 2]


def mode_shape_result(s: Snapshot) -> Result:
    view = "tire mode shape: the deformed belt over one period"
    try:
        mode, speed, how = _chosen(s)
        n_p = compute.tire_of(s.models).n_modes // 2
        if not 0 <= mode < n_p:
            raise FBSError(f"mode {mode} does not exist: the tire's pairs are 0..{n_p - 1}")
        t = mc.shape(mode, speed, s.models)
    except (FBSError, AttributeError, TypeError) as e:
        return _unavailable(s, view, "mode_shape", str(e))
    if t.kind != "vibration":
        return _no_vibration(s, view, mode, t)
    sh = t.shape
    ring = sh.ring  # (n_k, n_t, 3)
    n_k, n_t = ring.shape[:2]
    rx, rz = _plane(ring)
    rim_x, rim_z = _plane(sh.rim)
    rest = sh.rest_belt[:, sh.y.size // 2]
    qx, qz = _plane(rest)
    # one crest of the dominant order in every frame (on the deformed centre line)
    ci = np.argmin(np.abs(np.angle(np.exp(1j * (sh.theta[None, :] - sh.crest[:, None])))), axis=1)
    crest_x, crest_z = rx[np.arange(n_k), ci], rz[np.arange(n_k), ci]
    # the width shape across at the first frame's crest: radial displacement vs y
    sec = sh.section(float(sh.crest[0]))  # (n_k, n_y, 3)
    th = sh.theta[ci[0]]
    r_hat = np.array([qx[ci[0]], qz[ci[0]]]) / max(np.hypot(qx[ci[0]], qz[ci[0]]), 1e-300)
    rest_sec = sh.rest_belt[ci[0]]  # (n_y, 3)
    radial = (sec[..., 0] - rest_sec[:, 0]) * r_hat[0] + (sec[..., 2] - rest_sec[:, 2]) * r_hat[1]
    label = "first-order slip state" if t.freq == 0 else f"{t.freq:.2f} Hz"
    what = f"{t.family} n={t.order} {t.direction}"
    moves = {
        "forward": "the crest travels with the spin",
        "backward": "the crest travels against the spin",
        "standing": "standing: the crest stays",
    }[t.direction]
    kk, tt = np.meshgrid(np.arange(n_k), sh.theta, indexing="ij")
    return Result(
        columns={
            "frame": kk.ravel().astype(float),
            "phase_rad": np.repeat(sh.phase, n_t),
            "theta_rad": tt.ravel(),
            "ring_x_m": ring[..., 0].ravel(),
            "ring_y_m": ring[..., 1].ravel(),
            "ring_z_m": ring[..., 2].ravel(),
            "rest_x_m": np.tile(qx, n_k),
            "rest_z_m": np.tile(qz, n_k),
            "crest_rad": np.repeat(sh.crest, n_t),
        },
        meta={
            "view": view,
            "mode": f"stored pair {mode}",
            "chosen": how,
            "speed": f"{t.speed_kmh:g} km/h",
            "eigenfrequency": f"{label} (pole {t.pole.real:.3f} {t.pole.imag:+.3f}j rad/s; "
            f"modal model {t.model_pole.real:.3f} {t.model_pole.imag:+.3f}j)",
            "shape": f"{what}: {percent(t.share):.0f} % of the belt's motion in that order, "
            f"travelling index {t.travelling:+.2f} (-1 forward, +1 backward), "
            f"{percent(t.hub_share):.0f} % in the hub",
            "direction": moves,
            "drawn": f"{n_k} frames over one period, displacements scaled so the largest is "
            f"a tenth of the tire radius (display factor {sh.scale:.3g})",
            "axes": "wheel axes: x forward, y left, z up, from the wheel centre (m)",
            "models": s.models.describe(),
        },
        filename=csv_name(s, "mode_shape", f"m{mode}", f"v{t.speed_kmh:g}"),
        caption=(
            f"**Mode {mode}** at {t.speed_kmh:g} km/h: {label}, **{what}** "
            f"({percent(t.hub_share):.0f} % hub) &middot; {moves}"
        ),
        draw={
            "ready": True,
            "mode": mode,
            "speed": t.speed_kmh,
            "direction": t.direction,
            "frames_x": [rx[k] for k in range(n_k)],
            "frames_z": [rz[k] for k in range(n_k)],
            "rim_x": [rim_x[k] for k in range(n_k)],
            "rim_z": [rim_z[k] for k in range(n_k)],
            "crest_x": crest_x,
            "crest_z": crest_z,
            "rest_x": qx,
            "rest_z": qz,
            "section_y": sec[0, :, 1],
            "section": [radial[k] for k in range(n_k)],
            "section_theta": float(th),
            "title": f"mode {mode}, {label}, {what}",
            "strip": {
                "frames": [
                    (rx[k], rz[k])
                    for k in np.linspace(0, n_k, STRIP_FRAMES, endpoint=False).astype(int)
                ],
                "rest": (qx, qz),
                "crest": [
                    (float(crest_x[k]), float(crest_z[k]))
                    for k in np.linspace(0, n_k, STRIP_FRAMES, endpoint=False).astype(int)
                ],
                "labels": [
                    f"{360 * k / n_k:.0f} deg"
                    for k in np.linspace(0, n_k, STRIP_FRAMES, endpoint=False).astype(int)
                ],
            },
        },
        core={"shape": t},
    )


def _no_vibration(s: Snapshot, view: str, mode: int, t) -> Result:
    """A first-order pair picked: what it is instead of a shape (it has no period)."""
    lam = t.pole.real
    if t.kind == "sliding":
        what = (
            f"mode {mode} is the tread sliding, no vibration: two real poles at 0 "
            f"(x and y), the whole tire slides on its slip dampers as a rigid body (the "
            f"belt's deformation is {t.deformation:.0e} of its motion); in the synthesis "
            "a constant hub mobility (v / C_kappa fore-aft, v / C_alpha lateral), kept at "
            "every N"
        )
    else:
        what = (
            f"mode {mode} is the tread's relaxation, no vibration: real poles "
            f"({lam:.1f} 1/s at {t.speed_kmh:g} km/h, time constant "
            f"{1e3 / abs(lam):.0f} ms = relaxation length / speed); the tread's slip "
            "lags the belt without oscillating, kept at every N"
        )
    return Result(
        columns={},
        meta={
            "view": view,
            "mode": f"stored pair {mode}",
            "not a vibration": what,
            "models": s.models.describe(),
        },  # fmt: skip
        filename=csv_name(s, "mode_shape", f"m{mode}", "first_order"),
        caption=f"**Mode {mode}**: {what}",
        draw={
            "ready": False,
            "message": what,
            "mode": mode,
            "kind": t.kind,
            "title": f"mode {mode}: the tread's {t.kind}, no vibration (no shape to animate)",
        },
    )


# -- the Campbell diagram of the waves -----------------------------------------------------------
DIRECTION_COLORS = {"forward": "#e03131", "backward": "#1971c2", "standing": "#868e96"}


#: What the waves' view says while the tire is solved.
WAVES_WORK = "solving the tire's modes at its operating points"


def waves_result(s: Snapshot) -> Result:
    view = "Campbell diagram of the belt waves (branches tracked by shape)"
    st = mc.waves_status(s.models)
    if st is None or not st.finished:
        why = (
            f"{WAVES_WORK} (computed once for every session) ..."
            if st is None
            else st.describe(WAVES_WORK) + " ..."
        )
        r = _unavailable(s, view, "waves", why)
        draw = {"ready": False, "pending": True, "message": why, "late": bool(st and st.late)}
        return Result(r.columns, r.meta, r.filename, why, draw)
    if st.state == "failed":
        if st.message.startswith("the tire's matrices are needed"):
            return _unavailable(s, view, "waves", st.message)
        r = _unavailable(
            s, view, "waves", st.describe(WAVES_WORK) + "; open the tab again to try again"
        )
        # pending: a later visit of the tab makes it again and asks again (a retry)
        return dataclasses.replace(r, draw={**r.draw, "pending": True})
    cb = st.value
    h = fbs_core.harmonic(s.harmonic)
    default = cb.selection(s.harmonic)
    shown = np.arange(cb.order.size) if s.waves_all else default
    labels = cb.labels()
    v = np.asarray(cb.speeds, float)
    cols: dict[str, np.ndarray] = {"speed_kmh": v}
    for b in shown:
        name = labels[b].replace(" ", "_").replace("=", "").replace(":", "_")
        cols[f"{name}_Hz"] = cb.freq[:, b]
        if np.any(np.isfinite(cb.closed_form[:, b])):
            cols[f"{name}_closed_form_Hz"] = cb.closed_form[:, b]
    ex = np.nan_to_num(cb.excitation[:, :, s.harmonic - 1]).max(axis=0)
    weight = cb.order_weight(s.harmonic)
    carry = [f if n < 0 else f"{f} n={n}" for (f, n), w in list(weight.items())[:4] if w > 0]
    vx, vy = [], []
    for b in shown:  # veering steps: the wave passed to another mode
        for i in np.flatnonzero(cb.veering[:, b]):
            vx.append(0.5 * (v[i] + v[i + 1]))
            vy.append(0.5 * (cb.freq[i, b] + cb.freq[i + 1, b]))
    line_v = np.linspace(h.speed_range[0], h.speed_range[1], 2)
    which = (
        "every branch" if s.waves_all else "the branches in the band of the orders that carry it"
    )
    return Result(
        columns=cols,
        meta={
            "view": view,
            "harmonic": s.harmonic,
            "shown": f"{shown.size} of {cb.order.size} branches: {which}",
            "orders that carry the harmonic's hub excitation": ", ".join(carry) or "none",
            "branch": "a belt wave (family, ring order n, direction) or a hub character, "
            "carried at every speed by the mode with most of it (fbs_core.analysis.waves)",
            "veering": f"MAC between neighbouring speeds below {cb.veer_mac:g}: marked",
            "closed form": "the ring's closed form beside the in-plane waves of order >= 2",
            "models": s.models.describe(),
        },
        filename=csv_name(s, "waves", f"h{s.harmonic}", "all" if s.waves_all else "default"),
        caption=(
            f"**Harmonic {s.harmonic}**: {shown.size} of {cb.order.size} branches ({which}; "
            f"orders {', '.join(carry) or 'none'}) &middot; red forward, blue backward, grey "
            "standing &middot; o veering &middot; **click a branch**: its shape"
        ),
        draw={
            "ready": True,
            "xs": [v] * shown.size,
            "ys": [cb.freq[:, b] for b in shown],
            "label": [labels[b] for b in shown],
            "color": [DIRECTION_COLORS.get(str(cb.direction[b]), "#868e96") for b in shown],
            "width": [1.2 + 2.0 * float(ex[b] / max(ex[shown].max(), 1e-300)) for b in shown],
            "stored": cb.stored[:, shown],
            "speeds": v,
            "freq": cb.freq[:, shown],
            "veer_x": np.asarray(vx, float),
            "veer_y": np.asarray(vy, float),
            "line_v": line_v,
            "line_f": line_v / 3.6 / h.wavelength,
            "f_range": tuple(map(float, h.freq_range)),
        },
        core={"waves": cb, "shown": shown},
    )


def waves_wait(s: Snapshot, listener_key=None, told=None) -> None:
    """Ask for the waves of the session's tire, computed once for every session
    (:data:`app.results.modes_compute.WAVES`); ``told(status)`` as it moves on. Without a page to
    be told on (``told`` None: tests, exports) it is computed here."""
    if told is None:
        try:
            mc.waves(s.models)
        except FBSError:
            pass  # the result says why (mc.waves_status)
        return
    mc.request_waves(s.models, listener_key, told)


def nearest_branch(draw: dict, speed: float, freq: float, tol: float = 0.05):
    """The (stored pair, speed) of the branch nearest a click at ``(speed, freq)``: the
    branch's frequency at the nearest speed within ``tol`` (relative) of ``freq``, and the
    modal model's pair that carries it at the nearest operating point that has one;
    None when no branch is that near."""
    v = np.asarray(draw.get("speeds", ()), float)
    if not v.size or not np.isfinite(speed) or not np.isfinite(freq):
        return None
    i = int(np.argmin(np.abs(v - speed)))
    f = np.asarray(draw["freq"], float)[i]
    err = np.abs(f - freq) / max(abs(freq), 1e-9)
    err = np.where(np.isfinite(err), err, np.inf)
    if not err.size or err.min() > tol:
        return None
    b = int(np.argmin(err))
    stored = np.asarray(draw["stored"])[:, b]
    have = np.flatnonzero(stored >= 0)
    if not have.size:
        return None
    k = have[np.argmin(np.abs(v[have] - speed))]
    return int(stored[k]), float(np.clip(speed, v[0], v[-1]))


# -- the selected modes beside table 5.1 -------------------------------------------------------
ORDERINGS = {
    "lowest": "lowest N (table 5.1)",
    "loo_floating": "selected by leave-one-out error",
    "greedy": "selected by greedy elimination",
}


def _judged(s: Snapshot) -> str | None:
    """The bushing DOF the criterion judges (None: the largest error over the six)."""
    return None if s.map_dof is None else f"bushing:{s.map_dof}"


def _lowest(s: Snapshot) -> int:
    """Table 5.1's lowest N of the harmonic (the error map's suggestion)."""
    m = compute.error_map(s.harmonic, s.coupling, s.models, s.residual)
    return int(m.suggest(s.threshold / 100.0, s.f_max, _judged(s)))


def selected_modes_result(s: Snapshot) -> Result:
    view = "selected tire modes beside the lowest N (table 5.1)"
    judged = _judged(s) or "max over 6 DOFs"
    try:
        sel = {
            by: mc.selection(
                s.harmonic, s.threshold, s.f_max, by, s.residual, _judged(s), s.coupling, s.models
            )
            for by in mc.SELECTION_ORDERS
        }
        n_low = _lowest(s)
    except (FBSError, AttributeError, TypeError) as e:
        return _unavailable(s, view, "selected_modes", f"the tire's per-mode terms: {e}")
    tire = compute.tire_of(s.models)
    n_p = tire.n_modes // 2
    counts = [n_low] + [sel[b].n_modes for b in mc.SELECTION_ORDERS]
    first = [n_low] + [sel[b].n_first for b in mc.SELECTION_ORDERS]
    pairs = [np.arange(min(n_low // 2, n_p))] + [sel[b].selected for b in mc.SELECTION_ORDERS]
    # the highest eigenfrequency kept, at the band's top speed (thesis fig. 5.8's reading)
    h = fbs_core.harmonic(s.harmonic)
    f_op = np.abs(np.asarray(tire.poles_at(float(h.speed_range[1])))[0::2].imag) / (2 * np.pi)
    top = [float(f_op[p].max()) if p.size else np.nan for p in pairs]
    names = list(ORDERINGS.values())
    res = " + residual" if s.residual else ""

    def pair_text(p: np.ndarray) -> str:
        if not p.size:
            return "none"
        runs, start = [], int(p[0])
        for a, b in zip(p[:-1], p[1:], strict=True):
            if b != a + 1:
                runs.append(f"{start}-{int(a)}" if a != start else f"{start}")
                start = int(b)
        runs.append(f"{start}-{int(p[-1])}" if p[-1] != start else f"{start}")
        return ", ".join(runs)

    return Result(
        columns={
            "ordering": np.arange(len(names), dtype=float),
            "n_modes": np.asarray(counts, float),
            "n_first": np.asarray(first, float),
            "highest_kept_Hz": np.asarray(top, float),
        },
        meta={
            "view": view,
            "harmonic": s.harmonic,
            "criterion": f"eq. 5.1 below {s.threshold:g} % at every centre up to {s.f_max:g} Hz, "
            f"{judged}, counts in steps of 10 (table 5.1's rule)",
            "residual compensation": residual_meta(s.residual),
            "coupling": s.coupling,
            **{f"ordering {i}": n for i, n in enumerate(names)},
            **{f"pairs kept, {names[i]}": pair_text(p) for i, p in enumerate(pairs)},
            "n_first": "smallest count whose selection meets the criterion",
            "highest_kept_Hz": f"highest kept eigenfrequency at {h.speed_range[1]:g} km/h",
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            "selected_modes",
            f"h{s.harmonic}",
            f"thr{s.threshold:g}",
            f"fmax{s.f_max:g}",
            (s.map_dof or "max6").replace(":", "-"),
            res_part(s),
            s.coupling,
        ),  # fmt: skip
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {s.threshold:g} % to {s.f_max:g} Hz, {judged}"
            f"{res} &middot; {s.coupling} &middot; lowest N **{n_low}**, selected "
            + ", ".join(f"**{sel[b].n_modes}** ({b})" for b in mc.SELECTION_ORDERS)
        ),
        draw={
            "names": names,
            "n_modes": counts,
            "n_first": first,
            "top": top,
            "pairs": [pair_text(p) for p in pairs],
        },  # fmt: skip
        core={"selections": sel},
    )


# -- the chassis side ----------------------------------------------------------------------------
def chassis_truncation_result(s: Snapshot) -> Result:
    view = "truncation of the chassis side: eq. 5.1 with N chassis modes, the tire exact"
    try:
        m = mc.chassis_map(s.harmonic, s.residual, s.coupling, s.models)
        eig = compute.chassis_of(s.models).eigenfrequencies()
        n_tire = _lowest(s)
    except (FBSError, AttributeError, TypeError) as e:
        return _unavailable(s, view, "chassis_truncation", f"the chassis' FE model: {e}")
    err = m.max_error if s.map_dof is None else m.dof_error(f"bushing:{s.map_dof}")
    judged = np.asarray(m.centres) <= s.f_max + 1e-9
    worst = percent(err[:, judged].max(axis=1)) if judged.any() else np.zeros(len(m.n_modes))
    n = int(m.suggest(s.threshold / 100.0, s.f_max, _judged(s)))
    res = " + residual" if s.residual else ""
    judged_dof = _judged(s) or "max over 6 DOFs"
    return Result(
        columns={
            "n_chassis_modes": np.asarray(m.n_modes, float),
            "highest_kept_Hz": np.asarray(eig[np.asarray(m.n_modes) - 1], float),
            "largest_error_pct": np.asarray(worst, float),
        },
        meta={
            "view": view,
            "harmonic": s.harmonic,
            "criterion": f"eq. 5.1 below {s.threshold:g} % at every centre up to {s.f_max:g} Hz, "
            f"{judged_dof}",
            "residual compensation": (
                "on: the chassis modes left out enter with their static flexibility"
                if s.residual
                else "off"
            ),
            "coupling": s.coupling,
            "chassis modes needed": f"{n} of {m.n_modes_total} (highest kept {eig[n - 1]:.1f} Hz)",
            "tire modes needed (table 5.1)": str(n_tire),
            "models": s.models.describe(),
        },
        filename=csv_name(
            s,
            "chassis_truncation",
            f"h{s.harmonic}",
            f"thr{s.threshold:g}",
            f"fmax{s.f_max:g}",
            (s.map_dof or "max6").replace(":", "-"),
            res_part(s),
            s.coupling,
        ),  # fmt: skip
        caption=(
            f"**Harmonic {s.harmonic}** &middot; {s.threshold:g} % to {s.f_max:g} Hz, "
            f"{judged_dof}{res} &middot; {s.coupling} &middot; chassis modes needed **{n}** "
            f"of {m.n_modes_total} (to {eig[n - 1]:.0f} Hz) &middot; tire modes {n_tire}"
        ),
        draw={
            "ready": True,
            "n_modes": np.asarray(m.n_modes, float),
            "worst": np.asarray(worst, float),
            "threshold": s.threshold,
            "suggested": n,
        },
        core={"map": m},
    )
