"""Tune the reference car's body and write data/reference_vehicle.h5.

Usage::

    .venv/bin/python scripts/build_reference_vehicle.py           # check + write the file
    .venv/bin/python scripts/build_reference_vehicle.py --tune    # re-run the body tuning

The body grillage's effective sections are tuned so that the free trimmed body has
its first torsion mode at 30 Hz and its first vertical bending mode at 36 Hz (inside
the published ranges of mid-size cars, docs/vehicle-model.md): a fixed-point
iteration ``s <- s (f_target / f)^2`` on two factors, one on the vertical bending
``Iy`` of the longitudinal members (rails, sills, tunnel: bending), one on the
stiffness of the cross members and towers and the torsion constant ``J`` of all
members (torsion). The printed sections are then frozen as the defaults of
:class:`fbs_core.vehicle.BodyParameters`. The file format is described in
fbs_core/vehicle/storage.py and docs/vehicle-model.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fbs_core.vehicle import BodyParameters, VehicleModel, VehicleParameters  # noqa: E402
from fbs_core.vehicle.landmarks import body_torsion_bending  # noqa: E402
from fbs_core.vehicle.model import RESPONSES, SPINDLES  # noqa: E402
from fbs_core.vehicle.storage import FILE_GRID, write_vehicle_h5  # noqa: E402

TARGETS = {"torsion": 30.0, "bending": 36.0}


def scaled(p: BodyParameters, bend: float, tors: float) -> BodyParameters:
    def sc(t, iy=1.0, iz=1.0, j=1.0):
        return (
            t[0],
            float(f"{t[1] * iy:.4g}"),
            float(f"{t[2] * iz:.4g}"),
            float(f"{t[3] * j:.4g}"),
        )

    return dataclasses.replace(
        p,
        rail=sc(p.rail, bend, 1.0, tors),
        sill=sc(p.sill, bend, 1.0, tors),
        tunnel=sc(p.tunnel, bend, 1.0, tors),
        cross=sc(p.cross, tors, 1.0, tors),
        tower=sc(p.tower, tors, tors, tors),
    )


def tune(p: BodyParameters, iters: int = 8) -> BodyParameters:
    bend = tors = 1.0
    for _ in range(iters):
        ft, fb = body_torsion_bending(scaled(p, bend, tors))
        tors *= (TARGETS["torsion"] / ft) ** 2
        bend *= (TARGETS["bending"] / fb) ** 2
    return scaled(p, bend, tors)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tune", action="store_true", help="re-run the body tuning, print sections")
    ap.add_argument("--out", type=Path, default=ROOT / "data" / "reference_vehicle.h5")
    args = ap.parse_args(argv)
    body = BodyParameters()
    if args.tune:
        body = tune(body)
        for name in ("rail", "sill", "cross", "tunnel", "tower"):
            print(f"tuned {name} = {getattr(body, name)}")
    ft, fb = body_torsion_bending(body)
    print(
        f"trimmed body: torsion {ft:.2f} Hz (target {TARGETS['torsion']:g}), "
        f"bending {fb:.2f} Hz (target {TARGETS['bending']:g})"
    )
    car = VehicleModel(VehicleParameters(body=body))
    write_vehicle_h5(car, args.out)
    print(
        f"wrote {args.out} ({len(SPINDLES + RESPONSES)} outputs x {len(SPINDLES)} inputs, "
        f"{FILE_GRID.size} lines {FILE_GRID[0]:g}-{FILE_GRID[-1]:g} Hz; "
        f"{car.system().n} DOFs, wheelbase {car.wheelbase:.3f} m, track "
        f"{car.track[0]:.3f} / {car.track[1]:.3f} m)"
    )
    print("landmarks: .venv/bin/python scripts/print_vehicle_landmarks.py")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
