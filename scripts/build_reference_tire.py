"""Regenerate the shipped reference tire model ``data/reference_tire.h5``.

Usage (from the repository root)::

    .venv/bin/python scripts/build_reference_tire.py [--out data/reference_tire.h5]

Builds the physical tire (``fbs_core.tire.ring``) at 20, 40, ..., 120 km/h,
computes its complex modes, tracks them across the speeds and stores the
supplier-style modal model (``docs/tire-model.md``).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

# one BLAS thread: the dense 400 x 400 eigenproblems run faster than with
# oversubscribed threads on a shared machine (set before numpy is imported)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from fbs_core.tire.build import build_modal_model  # noqa: E402
from fbs_core.tire.storage import DATA_FILE, save_tire_model  # noqa: E402

DESCRIPTION = (
    "Reference rolling tire (205/60 R15 class) built from physics by tire-fbs: rotating belt "
    "on an elastic sidewall foundation (in-plane ring, lateral ring, tilt and width-wise "
    "families), rigid rim with hub at its centre, contact patch springs; complex modes at "
    "20-120 km/h. See docs/tire-model.md."
)


def main(argv=None) -> Path:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DATA_FILE, help="output HDF5 file")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    model = build_modal_model()
    path = save_tire_model(model, args.out, DESCRIPTION)
    print(
        f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB, {model.n_modes} complex modes at "
        f"{', '.join(f'{v:g}' for v in model.speeds)} km/h) in {time.perf_counter() - t0:.1f} s"
    )
    print(
        "tracking between operating points: median MAC",
        ", ".join(f"{m:.2f}" for m in model.meta["mac_median"]),
        "; share with MAC > 0.9",
        ", ".join(f"{m:.2f}" for m in model.meta["mac_share_above_0.9"]),
    )
    return path


if __name__ == "__main__":
    main()
