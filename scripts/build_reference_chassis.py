"""Tune the reference chassis to the thesis' eigenfrequencies and write data/reference_chassis.h5.

Usage::

    .venv/bin/python scripts/build_reference_chassis.py           # check + write the file
    .venv/bin/python scripts/build_reference_chassis.py --tune    # re-run the tuning

The three target modes of thesis fig. 4.2 (14, 37, 47 Hz) are carrier modes on
the link bushing: fore-aft (x), lateral (y) and pitch about the axle (ry). Each
is governed mainly by one link stiffness, so the tuning is a fixed-point
iteration ``k <- k (f_target / f)^2`` on (k_x, k_y, k_ry), with the modes
identified by the carrier's kinetic energy per direction. The printed values are
then frozen as the defaults of :class:`fbs_core.chassis.ChassisParameters`.
The file format is described in docs/chassis-model.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fbs_core.chassis import (  # noqa: E402
    BUSHING,
    SPINDLE,
    ChassisModel,
    ChassisParameters,
)
from fbs_core.io.hdf5 import write_model_hdf5  # noqa: E402

COORDINATES = "ISO 8855 vehicle axes: x forward, y left, z up; origin at the subframe centre"
TARGETS = {"x": 14.0, "y": 37.0, "ry": 47.0}
LINK_INDEX = {"x": (0,), "y": (1, 3, 5), "ry": (4,)}  # lateral mode: k_y, k_rx, k_rz


def tune(p: ChassisParameters, iters: int = 20) -> ChassisParameters:
    for _ in range(iters):
        f = ChassisModel(p).eigenfrequencies()[1:4]  # modes 2-4: above the 6 Hz bounce
        k = list(p.link_stiffness)
        for fr, (d, target) in zip(f, TARGETS.items(), strict=True):
            for i in LINK_INDEX[d]:
                k[i] *= (target / fr) ** 2
        p = dataclasses.replace(p, link_stiffness=tuple(float(f"{v:.4g}") for v in k))
    return p


def write_h5(ch: ChassisModel, path: Path, freq: np.ndarray) -> None:
    """The project's HDF5 FRF layout (``fbs_core.io.hdf5``: root attributes and
    ``/frf``) plus the model itself: ``/parameters``, ``/system`` (sparse M, K)
    and ``/modes``."""
    meta = {
        "model": "reference rear-corner chassis",
        "coordinates": COORDINATES,
        "script": "scripts/build_reference_chassis.py",
    }
    Y = ch.mobility(freq)
    write_model_hdf5(path, Y, meta, "reference chassis", ch.system(), ("M", "K"))
    with h5py.File(path, "a") as h:
        g = h.create_group("parameters")
        for key, val in dataclasses.asdict(ch.params).items():
            g.attrs[key] = np.asarray(val, float)
        g = h.create_group("modes")
        g["eigenvalues"] = ch.eigenvalues()
        g["frequency_hz"] = ch.eigenfrequencies()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tune", action="store_true", help="re-run the tuning and print values")
    ap.add_argument("--out", type=Path, default=ROOT / "data" / "reference_chassis.h5")
    args = ap.parse_args(argv)
    p = ChassisParameters()
    if args.tune:
        p = tune(p)
        print("tuned link_stiffness =", p.link_stiffness)
    ch = ChassisModel(p)
    for fr, (d, target) in zip(ch.eigenfrequencies()[1:4], TARGETS.items(), strict=True):
        print(f"carrier mode {d:>2}: {fr:7.3f} Hz (target {target:g})")
    f = ch.eigenfrequencies()
    print("eigenfrequencies below 600 Hz:", np.array2string(f[f < 600], precision=1))
    freq = np.arange(1.0, 600.0 + 1e-9, 1.0)
    write_h5(ch, args.out, freq)
    print(
        f"wrote {args.out} ({len(SPINDLE + BUSHING)} outputs x {len(SPINDLE)} inputs, "
        f"{freq.size} lines {freq[0]:g}-{freq[-1]:g} Hz)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
