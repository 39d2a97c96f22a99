"""Cached calls into :mod:`fbs_core`, shaped for the views.

This is the only module of the app that calls the core library. Results are cached per
argument tuple (the core objects are immutable), so that a control change that only selects
(e.g. another response DOF) costs a dictionary lookup. The only arithmetic done here is the
conversion to dB for display (``20 log10 |v|``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

import fbs_core

__all__ = [
    "DB_FLOOR",
    "db",
    "frequencies",
    "coupled",
    "mobility_data",
    "uncoupled_data",
    "error_map",
    "error_map_data",
    "suggested_table",
    "eigen_curves",
    "band",
    "band_data",
    "single_round_data",
    "level_unit",
    "version",
]

#: Magnitudes are floored at this value before the dB conversion (avoids -inf at exact zeros).
DB_FLOOR = 1e-30
#: Operating speeds of the eigenfrequency plot (thesis fig. 5.8), km/h.
EIGEN_SPEEDS = (20.0, 80.0, 120.0)


def version() -> str:
    return str(getattr(fbs_core, "__version__", "unknown"))


def db(x: np.ndarray) -> np.ndarray:
    """``20 log10 |x|`` (dB re 1 unit), magnitudes floored at :data:`DB_FLOOR`."""
    return 20.0 * np.log10(np.maximum(np.abs(x), DB_FLOOR))


def level_unit(dof: str) -> str:
    """Display unit of the bushing velocity per unit patch load for a DOF direction."""
    return "dB re 1 (rad/s)/N" if dof.startswith("r") else "dB re 1 (m/s)/N"


@lru_cache(maxsize=8)
def frequencies(harmonic: int) -> np.ndarray:
    """The analysis grid of a harmonic case (Hz), read-only."""
    f = np.array(fbs_core.harmonic(harmonic).frequencies(), dtype=float)
    f.setflags(write=False)
    return f


@lru_cache(maxsize=1)
def _tire():
    return fbs_core.reference_tire()


@lru_cache(maxsize=1)
def _chassis():
    return fbs_core.reference_chassis()


@lru_cache(maxsize=256)
def coupled(harmonic: int, n_modes: int | None, coupling: str):
    """Bushing velocity v_e* (thesis eq. 4.1) as an FRF, all 6 bushing DOFs; cached."""
    return fbs_core.bushing_response(
        harmonic, n_modes=n_modes, freq=frequencies(harmonic), coupling=coupling
    )


def _column(frf, dof: str) -> np.ndarray:
    return frf.sel(outputs=dof).data[:, 0, 0]


def mobility_data(harmonic: int, n_modes: int, dof: str, coupling: str) -> dict:
    """Columns of the coupled-mobility view: reference (all modes) and truncated (N modes).

    Returns
    -------
    dict
        ``freq`` (Hz), ``reference`` and ``truncated`` (complex v_e*), ``reference_db`` and
        ``truncated_db`` (dB), each of shape ``(n_freq,)``.
    """
    ref = _column(coupled(harmonic, None, coupling), f"bushing:{dof}")
    trunc = _column(coupled(harmonic, int(n_modes), coupling), f"bushing:{dof}")
    return {
        "freq": frequencies(harmonic),
        "reference": ref,
        "truncated": trunc,
        "reference_db": db(ref),
        "truncated_db": db(trunc),
    }


@lru_cache(maxsize=64)
def _tire_hub(harmonic: int, n_modes: int | None):
    return _tire().patch_response(frequencies(harmonic), fbs_core.harmonic(harmonic), n_modes)


@lru_cache(maxsize=8)
def _chassis_frf(harmonic: int):
    return _chassis().mobility(frequencies(harmonic))


def uncoupled_data(harmonic: int, n_modes: int, dof: str, spindle_input: str) -> dict:
    """Uncoupled subsystems (thesis figs. 4.2-4.3 and 4.6-4.7).

    Returns
    -------
    dict
        ``freq``; ``tire_reference_db`` / ``tire_truncated_db``: free hub velocity
        ``Y_ja^A F_a`` at ``hub:<dof>`` with all / N modes; ``chassis_db``: chassis mobility
        ``Y_ej^E`` from ``spindle:<spindle_input>`` to ``bushing:<dof>``; complex columns
        ``tire_reference``, ``tire_truncated``, ``chassis``.
    """
    t_ref = _column(_tire_hub(harmonic, None), f"hub:{dof}")
    t_tr = _column(_tire_hub(harmonic, int(n_modes)), f"hub:{dof}")
    ch = _chassis_frf(harmonic).sel(
        outputs=f"bushing:{dof}", inputs=f"spindle:{spindle_input}"
    ).data[:, 0, 0]
    return {
        "freq": frequencies(harmonic),
        "tire_reference": t_ref,
        "tire_truncated": t_tr,
        "chassis": ch,
        "tire_reference_db": db(t_ref),
        "tire_truncated_db": db(t_tr),
        "chassis_db": db(ch),
    }


@lru_cache(maxsize=16)
def error_map(harmonic: int, coupling: str):
    """The truncation error map of a harmonic (thesis figs. 5.3, 5.6, 5.7); cached."""
    return fbs_core.truncation_map(harmonic, coupling=coupling)


def error_map_data(harmonic: int, coupling: str, dof: str | None) -> dict:
    """Error (in percent) over centre frequency and retained modes.

    ``dof=None`` gives the maximum over the 6 bushing DOFs (fig. 5.6).

    Returns
    -------
    dict
        ``centre_freq`` (n_fc,), ``n_modes`` (n_N,), ``error_pct`` (n_N, n_fc).
    """
    m = error_map(harmonic, coupling)
    if dof is None:
        err = m.max_error
    else:
        err = m.error[..., list(m.dofs).index(f"bushing:{dof}")]
    return {
        "centre_freq": np.asarray(m.centre_freq, float),
        "n_modes": np.asarray(m.n_modes, int),
        "error_pct": 100.0 * np.asarray(err, float),
    }


@lru_cache(maxsize=64)
def suggested_table(threshold_pct: float, f_max: float, coupling: str) -> dict:
    """Suggested number of modes for all seven harmonics (thesis table 5.1)."""
    s = fbs_core.suggest_modes(threshold=threshold_pct / 100.0, f_max=f_max, coupling=coupling)
    ks = [int(k) for k in s.harmonics]
    rng = [fbs_core.harmonic(k).freq_range for k in ks]
    return {
        "harmonic": np.array(ks),
        "f_low": np.array([r[0] for r in rng], float),
        "f_high": np.array([r[1] for r in rng], float),
        "n_modes": np.asarray(s.n_modes, int),
        "eigenfrequency": np.asarray(s.eigenfrequency, float),
    }


@lru_cache(maxsize=1)
def eigen_curves() -> dict:
    """Highest retained eigenfrequency versus N at 20, 80, 120 km/h (thesis fig. 5.8)."""
    tire = _tire()
    out = {}
    for v in EIGEN_SPEEDS:
        fn = np.asarray(tire.eigenfrequencies(v), float)
        out[f"f_{int(v)}"] = fn
    n = min(a.size for a in out.values())
    out = {k: a[:n] for k, a in out.items()}
    out["n_modes"] = 2 * np.arange(1, n + 1)
    return out


@lru_cache(maxsize=4)
def band(harmonic: int, n_modes: int | None, coupling: str, noise_pct: float, target: str,
         frequency_dependent: bool, rounds: int, seed: int):
    """The Monte-Carlo scatter band (thesis section 5.2); cached (a few results only)."""
    return fbs_core.scatter_band(
        harmonic, noise=noise_pct / 100.0, target=target, rounds=rounds,
        frequency_dependent=frequency_dependent, seed=seed, n_modes=n_modes, coupling=coupling,
    )


def band_data(result, dof: str, percentile: float = 90.0) -> dict:
    """Columns of the scatter-band view for one bushing DOF (dB and linear).

    ``percentile`` is the width of the central band in percent (90 -> 5 % to 95 %).
    """
    j = list(result.dofs).index(f"bushing:{dof}")
    ref = result.reference[:, j]
    cols = {
        "freq": np.asarray(result.freq, float),
        "reference": ref,
        "minimum": result.minimum[:, j],
        "maximum": result.maximum[:, j],
        "lower": result.lower[:, j],
        "upper": result.upper[:, j],
    }
    for k in ("reference", "minimum", "maximum", "lower", "upper"):
        cols[f"{k}_db"] = db(cols[k])
    return cols


def single_round_data(result, index: int, dof: str) -> dict:
    """One regenerated polluted round (figs. 5.10-5.11) for one bushing DOF."""
    j = list(result.dofs).index(f"bushing:{dof}")
    v = result.round(int(index))[:, j]
    return {"freq": np.asarray(result.freq, float), "round": v, "round_db": db(v)}
