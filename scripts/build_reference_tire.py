"""Regenerate the shipped reference tire model ``data/reference_tire.h5``.

Usage (from the repository root)::

    .venv/bin/python scripts/build_reference_tire.py [--out data/reference_tire.h5]

Builds the physical tire (``fbs_core.tire.ring``) at 20, 22.5, ..., 120 km/h,
computes its complex modes, tracks them across the speeds, adds the midpoint of
every interval where the interpolated model misses the direct solution by more
than 1 % (``fbs_core.tire.build.REFINE_TOL``) and stores the supplier-style modal
model (``docs/tire-model.md``).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

# one BLAS thread: the dense 400 x 400 eigenproblems run faster than with
# oversubscribed threads on a shared machine (set before numpy is imported)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fbs_core.tire.build import REFINE_TOL, build_modal_model  # noqa: E402
from fbs_core.tire.quality import interpolation_quality  # noqa: E402
from fbs_core.tire.storage import DATA_FILE, save_tire_model  # noqa: E402

DESCRIPTION = (
    "Reference rolling tire (205/60 R15 class) built from physics by tire-fbs: rotating belt "
    "on an elastic sidewall foundation (in-plane ring, lateral ring, tilt and width-wise "
    "families), rigid rim with hub at its centre, contact patch springs, linearised about "
    "the statically loaded tire (patch length and pressure of the static contact under the "
    "wheel load, hoop-force pre-stress); complex modes at "
    "every 2.5 km/h from 20 to 120 km/h, refined to 1.25 km/h where the interpolation between "
    "two points misses the direct solution by more than 1 %. See docs/tire-model.md."
)


def main(argv=None) -> Path:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DATA_FILE, help="output HDF5 file")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    model = build_modal_model(refine_tol=REFINE_TOL)
    # data-only estimate of the interpolation error between the operating points
    model.meta["interpolation_quality"] = interpolation_quality(model).to_dict()
    path = save_tire_model(model, args.out, DESCRIPTION)
    sp = model.speeds
    print(
        f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB, {model.n_modes} complex modes at "
        f"{sp.size} operating points {sp[0]:g}-{sp[-1]:g} km/h) in {time.perf_counter() - t0:.1f} s"
    )
    med = np.asarray(model.meta["mac_median"])
    share = np.asarray(model.meta["mac_share_above_0.9"])
    print(
        f"tracking between operating points: median MAC {med.min():.2f}-{med.max():.2f}, "
        f"share with MAC > 0.9 {share.min():.2f}-{share.max():.2f}"
    )
    ref = model.meta["refinement"]
    print(
        f"refinement: {len(ref['added_kmh'])} operating points added where the interpolation "
        f"missed the physics by > {ref['tol']:.0%} ({', '.join(f'{v:g}' for v in ref['added_kmh'])}"
        f" km/h); worst remaining {ref['worst_remaining']:.2%}"
    )
    q = model.meta["interpolation_quality"]["worst_db"]
    print(
        "leave-one-out interpolation error (worst dB per harmonic): "
        + ", ".join(f"{k}: {v}" for k, v in q.items())
    )
    return path


if __name__ == "__main__":
    main()
