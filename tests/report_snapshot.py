"""A small real snapshot for the report tests (harmonic 1, N = 20, 300 noise rounds)."""

from __future__ import annotations

import datetime as dt

import numpy as np

import fbs_core
from app.report import DataFile, Provenance, ReportData
from fbs_core import studies

K, N = 1, 20
URL = "http://localhost:5006/main?h=1&N=20&dof=z&thr=20&fmax=40"
SETTINGS = dict(
    harmonic=K,
    n_modes=N,
    dof="z",
    coupling="6dof",
    threshold=20.0,
    f_max=40.0,
    map_mode="selected DOF",
    noise=10.0,
    target="both",
    frequency_dependent=False,
    rounds=300,
    seed=3,
    single_round=7,
    percentile=90,
)


def results() -> dict:
    m = studies.truncation_map(K, n_modes=np.arange(10, 400, 10))
    return dict(
        reference=fbs_core.bushing_response(K),
        truncated=fbs_core.bushing_response(K, n_modes=N),
        truncation=m,
        suggested=studies.suggest_modes(0.2, 40.0, maps=[m], dof="bushing:z"),
        band=studies.scatter_band(
            K, noise=0.1, rounds=300, seed=3, n_modes=N, percentiles=(5.0, 95.0)
        ),
        eigen=studies.mode_frequencies((20.0, 80.0, 120.0)),
    )


def snapshot(results: dict) -> ReportData:
    prov = Provenance(
        chassis=DataFile("chassis", "rear corner <v2>.uff", "0123abcd4567"),
        notes=("chassis: accelerance converted to mobility",),
    )
    return ReportData(
        settings=SETTINGS,
        provenance=prov,
        url=URL,
        created=dt.datetime(2026, 12, 1, 20, 15, tzinfo=dt.UTC),
        **results,
    )
