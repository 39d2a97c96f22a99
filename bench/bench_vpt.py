"""Speed of the virtual point transformation: 9 sensor channels x 12 impacts on 2,000 lines.

Prints the time of :func:`fbs_core.vpt.virtual_point` (transformations, the 6 x 6 FRF, the
bushing transfers and all consistency indicators) and of its array kernel alone, best of
``--repeat`` runs, beside the target 0.5 s. Random FRFs: the cost does not depend on the
values.

    python bench/bench_vpt.py [--lines 2000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

import fbs_core as fc
from fbs_core.chassis import BUSHING
from fbs_core.vpt import transformation, virtual_point, vpt_kernel
from fbs_core.vpt import validation as val

TARGET_S = 0.5


def best(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    lay = val.knuckle_layout()
    ns, ni = len(lay.sensors), len(lay.impacts)
    rng = np.random.default_rng(0)
    shape = (args.lines, ns + len(BUSHING), ni)
    data = rng.normal(size=shape) + 1j * rng.normal(size=shape)
    f = np.linspace(2.0, 2000.0, args.lines)
    Y = fc.FRF(f, data, list(lay.sensors.labels) + list(BUSHING), lay.impacts.labels, "accelerance")
    Tu, Tf = transformation(lay.modes("sensors")), transformation(lay.modes("impacts"))
    t_all = best(lambda: virtual_point(Y, lay), args.repeat)
    t_kernel = best(lambda: vpt_kernel(data[:, :ns], Tu, Tf), args.repeat)
    print(
        f"VPT of {ns} sensor channels x {ni} impacts (+ {len(BUSHING)} bushing channels) on "
        f"{args.lines} lines, best of {args.repeat}:"
    )
    print(
        f"  virtual_point (checks, 6x6, transfers, consistency) {t_all * 1e3:8.1f} ms   "
        f"target < {TARGET_S * 1e3:.0f} ms  {'ok' if t_all < TARGET_S else 'SLOWER'}"
    )
    print(f"  vpt_kernel alone (T_u Y T_f^T)                      {t_kernel * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
