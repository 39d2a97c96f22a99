"""Speed of the whole car (issue 31) beside the single corner, measured side by side.

Run:  .venv/bin/python bench/bench_vehicle.py [--repeat 15] [--rounds 10000] [--band-repeat 3]

Targets: a vehicle response for one harmonic (all four wheels, 6-DOF coupling, all
tire modes) within 2x the single corner's bushing response; a scatter band of 10,000
rounds within 5x the corner's. Both sides run the same way in the same process, in
alternation (corner, car, corner, car, ...), so that the load of a shared machine
falls on both: medians and their ratio are printed, with the CPU time beside the wall
time.

- response: ``fbs_core.bushing_response(k, tire=...)`` (the tire given explicitly, so
  the result cache is bypassed and the tire is synthesised every call) against
  ``fbs_core.vehicle_response(k, tire=...)`` (one synthesis for the four wheels,
  the 24 x 24 interface solve, the road); the structures' FRFs are cached per grid on
  both sides (chassis and car), their first computation is printed apart;
- scatter band: ``fbs_core.scatter_band(4, rounds=R)`` (6 interface DOFs, the bushing's
  6 responses) against ``vehicle_scatter_band(4, rounds=R, outputs="bushing_rl")``
  (24 interface DOFs, the same 6 responses of the rear-left bushing), noise in both
  subsystems, frequency-independent; the same compiled kernel.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import fbs_core as fc  # noqa: E402
from fbs_core.vehicle import reference_vehicle, vehicle_response  # noqa: E402
from fbs_core.vehicle.studies import vehicle_scatter_band  # noqa: E402


def _timed(fn):
    t, c = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t, time.process_time() - c


def side_by_side(a, b, repeat):
    """Alternate ``a`` and ``b``; medians of wall and CPU time of each."""
    ta, tb = [], []
    for _ in range(repeat):
        ta.append(_timed(a))
        tb.append(_timed(b))
    return np.median(np.array(ta), axis=0), np.median(np.array(tb), axis=0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--rounds", type=int, default=10_000)
    ap.add_argument("--band-repeat", type=int, default=3)
    ap.add_argument("--harmonics", type=int, nargs="+", default=[1, 4, 7])
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    tire, chassis, car = fc.reference_tire(), fc.reference_chassis(), reference_vehicle()
    car.eigenvalues()
    print("\nfirst computation of the structures' FRFs on a harmonic's grid (then cached):")
    for k in args.harmonics:
        f = fc.harmonic(k).frequencies()
        wc, _ = _timed(lambda f=f: chassis.mobility(f))
        wv, _ = _timed(lambda k=k: vehicle_response(k, tire=tire))
        print(f"  case {k} ({f.size} lines): chassis {1e3 * wc:7.1f} ms, car {1e3 * wv:7.1f} ms")
    print(
        "\nresponse for one harmonic, 6-DOF, all tire modes (median of "
        f"{args.repeat}, wall / CPU ms): the corner's bushing (6 DOFs) beside the car's\n"
        "rear-left bushing (the same 6 DOFs, four wheels) and all its 60 response DOFs"
    )
    print(
        f"  {'case':>4s} {'lines':>5s} {'corner':>15s} {'car, 6 DOFs':>15s} {'ratio':>6s}"
        f"{'':>11s} {'car, 60 DOFs':>15s} {'ratio':>6s}"
    )
    for k in args.harmonics:
        f = fc.harmonic(k).frequencies()

        def corner(k=k):
            fc.bushing_response(k, tire=tire)

        def vehicle(k=k):
            vehicle_response(k, tire=tire, outputs="bushing_rl")

        def vehicle_all(k=k):
            vehicle_response(k, tire=tire)

        corner(), vehicle(), vehicle_all()
        (wa, ca), (wb, cb) = side_by_side(corner, vehicle, args.repeat)
        (wa2, ca2), (wc, cc) = side_by_side(corner, vehicle_all, args.repeat)
        print(
            f"  {k:>4d} {f.size:>5d} {1e3 * wa:7.1f} / {1e3 * ca:5.1f} "
            f"{1e3 * wb:7.1f} / {1e3 * cb:5.1f} {wb / wa:5.2f}x ({cb / ca:.2f}x CPU) "
            f"{1e3 * wc:7.1f} / {1e3 * cc:5.1f} {wc / wa2:5.2f}x ({cc / ca2:.2f}x CPU)"
        )
    R = args.rounds
    print(
        f"\nscatter band, case 4, {R:,} rounds, noise 10 % in both subsystems "
        f"(median of {args.band_repeat}, wall / CPU):"
    )
    fc.scatter_band(4, rounds=200, seed=99)
    vehicle_scatter_band(4, rounds=200, seed=99, outputs="bushing_rl")
    seeds = iter(range(1000))

    def band_corner():
        fc.scatter_band(4, rounds=R, seed=next(seeds))

    def band_vehicle():
        vehicle_scatter_band(4, rounds=R, seed=next(seeds), outputs="bushing_rl")

    (wa, ca), (wb, cb) = side_by_side(band_corner, band_vehicle, args.band_repeat)
    print(f"  corner (6 interface DOFs):  {wa:7.2f} s / {ca:7.2f} s CPU")
    print(f"  car (24 interface DOFs):    {wb:7.2f} s / {cb:7.2f} s CPU")
    print(
        f"  ratio {wb / wa:.2f}x wall, {cb / ca:.2f}x CPU (target 5x; the 24 x 24 LU of every "
        "round and line is 64x the flops of the corner's 6 x 6)"
    )
    print(f"\nload average {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
