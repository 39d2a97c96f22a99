"""Import / export speed of fbs_core.io (issue 8), figures printed per format.

A chassis-sized FRF: 12 outputs x 6 inputs x 2000 lines (spindle and bushing, as the
thesis' chassis model), written and read back in every format; plus the fixed cost of
one sandboxed parse (fork of the worker) on a tiny MAT-file.

Run: ``.venv/bin/python bench/bench_io.py``
"""

from __future__ import annotations

import time

import numpy as np

import fbs_core as fc
from fbs_core.io import load_frf, save_frf

N_FREQ = 2000


def chassis_like() -> fc.FRF:
    rng = np.random.default_rng(0)
    outs = fc.node_labels("spindle") + fc.node_labels("bushing")
    ins = fc.node_labels("spindle")
    f = np.arange(1, N_FREQ + 1) * 0.25
    d = rng.normal(size=(N_FREQ, 12, 6)) + 1j * rng.normal(size=(N_FREQ, 12, 6))
    return fc.FRF(f, d * 1e-4, outs, ins, "mobility")


def best(fn, repeat=3):
    t = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        t.append(time.perf_counter() - t0)
    return min(t), out


def main() -> None:
    Y = chassis_like()
    load_frf(save_frf(Y, format="mat"), filename="warm.mat")  # start the sandbox worker
    print(f"FRF {Y.shape[1]} x {Y.shape[2]} x {N_FREQ} lines")
    print(f"{'format':<14}{'size MiB':>10}{'write s':>10}{'read s':>10}  same")
    cases = [
        ("uff", {}, "uff"),
        ("uff 58b", {"binary": True}, "uff"),
        ("mat v5", {}, "mat"),
        ("mat v7.3", {"mat_version": "7.3"}, "mat"),
        ("csv", {}, "csv"),
        ("hdf5", {}, "h5"),
    ]
    for name, kw, end in cases:
        fmt = {"uff": "uff", "mat": "mat", "csv": "csv", "h5": "hdf5"}[end]
        tw, raw = best(lambda fmt=fmt, kw=kw: save_frf(Y, format=fmt, **kw))
        tr, r = best(lambda raw=raw, end=end: load_frf(raw, filename=f"x.{end}"))
        same = r.frf.allclose(Y, rtol=1e-10)
        print(f"{name:<14}{len(raw) / 2**20:>10.2f}{tw:>10.3f}{tr:>10.3f}  {same}")
    tiny = save_frf(fc.FRF([1.0, 2.0], np.ones((2, 1, 1)), ["a:x"], ["a:x"]), format="mat")
    t, _ = best(lambda: load_frf(tiny, filename="t.mat"), repeat=20)
    print(f"sandboxed parse of a tiny MAT-file (fork + IPC): {1e3 * t:.1f} ms")


if __name__ == "__main__":
    main()
