"""CSV export of the analysis datasets with provenance.

Every dataset is turned into arrays with named axes and handed to the public
exporter :func:`fbs_core.io.export_result` (``# key: value`` metadata lines, one
long table per array), with the provenance (settings, source digests) added as
metadata.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import FBSError
from ..frf import FRF
from .peaks import Peak
from .views import Bode, Delta

__all__ = ["export_mapping", "to_csv"]


def export_mapping(dataset: Any) -> dict[str, Any]:
    """Arrays with axes (and coordinates, metadata) of an analysis dataset.

    Parameters
    ----------
    dataset : FRF, Bode, Delta, sequence of Peak, or an object with ``export_mapping()``
        (Contributions, Campbell, SpeedMap, LevelDifference, MapDifference, PinnedState).

    Returns
    -------
    dict
        A mapping accepted by :func:`fbs_core.io.export_result`.

    Raises
    ------
    FBSError
        For anything else.
    """
    if isinstance(dataset, FRF):
        return {"frf": dataset}
    if hasattr(dataset, "export_mapping"):
        return dict(dataset.export_mapping())
    if isinstance(dataset, Bode):
        dims = ("freq", "output", "input")
        return {
            "magnitude_db": (dims, dataset.magnitude_db),
            "phase_deg": (dims, dataset.phase_deg),
            "coords": {
                "freq": dataset.freq,
                "output": list(dataset.outputs),
                "input": list(dataset.inputs),
            },
            "metadata": {"ref": dataset.ref, "quantity": dataset.quantity},
        }
    if isinstance(dataset, Delta):
        return {
            "cursor_freq": (("cursor",), np.array([dataset.f1, dataset.f2])),
            "cursor_level_db": (("cursor",), np.array([dataset.level1, dataset.level2])),
            "coords": {"cursor": ["1", "2"]},
            "metadata": {"df_hz": dataset.df, "d_db": dataset.d_db},
        }
    if isinstance(dataset, list | tuple) and all(isinstance(p, Peak) for p in dataset):
        if not dataset:
            raise FBSError("no peaks to export")
        nan = float("nan")
        return {
            "freq": (("peak",), np.array([p.freq for p in dataset])),
            "level_db": (("peak",), np.array([p.level_db for p in dataset])),
            "prominence_db": (("peak",), np.array([p.prominence_db for p in dataset])),
            "speed_kmh": (
                ("peak",),
                np.array([nan if p.speed_kmh is None else p.speed_kmh for p in dataset]),
            ),
            "modes_hz": (
                ("peak",),
                np.array([" ".join(f"{m.freq:.3f}" for m in p.modes) for p in dataset], str),
            ),
            "modes_damping": (
                ("peak",),
                np.array([" ".join(f"{m.damping:.4f}" for m in p.modes) for p in dataset], str),
            ),
            "coords": {"peak": np.arange(len(dataset))},
        }
    raise FBSError(
        f"cannot export a {type(dataset).__name__}: expected an FRF or an analysis dataset"
    )


def to_csv(dataset: Any, provenance: Mapping[str, Any] | None = None) -> bytes:
    """CSV text of an analysis dataset with its provenance as metadata lines.

    Parameters
    ----------
    dataset
        See :func:`export_mapping`.
    provenance : mapping, optional
        Settings and source digests (e.g. ``PinnedState.provenance()``), written as
        ``# key: value`` lines next to the fbs_core version and the export time.

    Returns
    -------
    bytes
    """
    from ..io import export_result

    mapping = dict(export_mapping(dataset))
    meta = dict(mapping.pop("metadata", {}) or {})
    meta.update(dict(provenance or {}))
    kind = "Peaks" if isinstance(dataset, list | tuple) else type(dataset).__name__
    meta.setdefault("dataset", kind)
    return bytes(export_result(mapping, format="csv", metadata=meta))
