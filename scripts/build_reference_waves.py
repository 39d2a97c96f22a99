"""Store the reference tire's belt-wave Campbell diagram (data/reference_waves.npz).

``fbs_core.analysis.wave_campbell()`` of the reference tire solves the tire's complex modes
at its 43 operating points (12 s on an idle core); the stored result is read instead when
it was made of the same tire, speeds, hub condition and tracking version (its content key).
Run again after rebuilding the reference tire or changing the tracking:

    python scripts/build_reference_waves.py
"""

from __future__ import annotations

import time

import fbs_core
from fbs_core.analysis import waves


def main() -> None:
    tire = fbs_core.reference_tire()
    speeds = tuple(float(v) for v in tire.speeds)
    t0 = time.perf_counter()
    cb = waves._track(tire, speeds, "free", 0.8)
    key = waves.content_key(tire, speeds, "free", 0.8)
    waves.save_waves(cb, waves.STORED_FILE, key)
    print(f"{cb.order.size} branches at {len(speeds)} speeds in {time.perf_counter() - t0:.1f} s")
    print(f"written {waves.STORED_FILE} (key {key[:12]})")


if __name__ == "__main__":
    main()
