"""Coupling benchmark (issue 2): two subsystems of 60 DOFs, 6 interface DOFs, 2000 lines.

Measured side by side in one run (best of several repeats, the machines are noisy):

1. the LM-FBS recipe as pyFBS' examples write it, ``Y - Y B^T pinv(B Y B^T) B Y``
   with a dense Boolean ``B`` and ``np.linalg.pinv``;
2. this project's ``fbs_core.couple_lm`` (labelled API, signed pairs, batched solve);
3. the eq. 4.1 fast path ``fbs_core.couple_response`` (response at 6 receiver DOFs for
   one load), which is what the tire-chassis prediction needs.

All three give the same numbers (checked here). Run: ``.venv/bin/python bench/bench_coupling.py``
"""

from __future__ import annotations

import time

import numpy as np

import fbs_core as fc

N_FREQ, N_DOF, N_J = 2000, 60, 6


def make(rng, name):
    """A random, well-conditioned FRF matrix of a 60-DOF subsystem (6 interface DOFs)."""
    labels = [f"{name}{i // 6}:{d}" for i, d in zip(range(N_DOF), fc.DIRECTIONS * 10, strict=True)]
    A = rng.normal(size=(N_FREQ, N_DOF, N_DOF)) + 1j * rng.normal(size=(N_FREQ, N_DOF, N_DOF))
    data = A @ np.conj(np.swapaxes(A, 1, 2)) / N_DOF + np.eye(N_DOF)
    return fc.FRF(np.linspace(1, 500, N_FREQ), data, labels, labels)


def recipe(Ya, Yb, ja, jb):
    """pyFBS example style: block-diagonal Y, dense B, pinv, per the LM-FBS formula."""
    Y = np.zeros((N_FREQ, 2 * N_DOF, 2 * N_DOF), complex)
    Y[:, :N_DOF, :N_DOF] = Ya
    Y[:, N_DOF:, N_DOF:] = Yb
    B = np.zeros((N_J, 2 * N_DOF))
    B[np.arange(N_J), ja] = 1
    B[np.arange(N_J), N_DOF + np.asarray(jb)] = -1
    return Y - Y @ B.T @ np.linalg.pinv(B @ Y @ B.T) @ B @ Y


def best(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main():
    rng = np.random.default_rng(0)
    A, B = make(rng, "a"), make(rng, "b")
    ja = list(range(54, 60))
    jb = list(range(0, 6))
    conns = [(f"A/{A.outputs[i]}", f"B/{B.outputs[k]}") for i, k in zip(ja, jb, strict=True)]

    t_recipe, Y_recipe = best(lambda: recipe(A.data, B.data, ja, jb), repeat=3)
    t_lm, Y_lm = best(lambda: fc.couple_lm({"A": A, "B": B}, conns), repeat=3)

    # eq. 4.1: tire-side load at A's DOF 0, response at B's DOFs 6..11
    ia = [A.outputs[i] for i in ja]
    ib = [B.outputs[k] for k in jb]
    e = list(B.outputs[6:12])
    Yej, YjjA, YjjE = B.sel(outputs=e, inputs=ib), A.sel(ia, ia), B.sel(ib, ib)
    vj = A.sel(outputs=ia, inputs=[A.outputs[0]])
    t_fast, v = best(
        lambda: fc.couple_response(Yej, YjjA, YjjE, vj, interface=list(zip(ia, ib, strict=True)))
    )
    t_fast_nocheck, _ = best(
        lambda: fc.couple_response(
            Yej, YjjA, YjjE, vj, interface=list(zip(ia, ib, strict=True)), max_cond=None
        )
    )

    # same numbers three ways
    ref = Y_recipe[:, N_DOF + 6 : N_DOF + 12, 0]
    err_lm = np.max(np.abs(Y_lm.data - Y_recipe)) / np.max(np.abs(Y_recipe))
    err_fast = np.max(np.abs(v.data[:, :, 0] - ref)) / np.max(np.abs(ref))
    print(f"subsystems: 2 x {N_DOF} DOFs, {N_J} interface DOFs, {N_FREQ} lines")
    print(f"LM-FBS recipe (pinv, dense B)      : {t_recipe * 1e3:9.1f} ms")
    print(
        f"fbs_core.couple_lm                 : {t_lm * 1e3:9.1f} ms   "
        f"ratio recipe/couple_lm = {t_recipe / t_lm:6.1f}x   max rel diff {err_lm:.1e}"
    )
    print(
        f"fbs_core.couple_response (eq. 4.1) : {t_fast * 1e3:9.1f} ms   "
        f"ratio recipe/fast = {t_recipe / t_fast:6.0f}x   "
        f"couple_lm/fast = {t_lm / t_fast:5.0f}x   max rel diff {err_fast:.1e}"
    )
    print(
        f"  (without the per-line condition check: {t_fast_nocheck * 1e3:.1f} ms, "
        f"recipe/fast = {t_recipe / t_fast_nocheck:.0f}x)"
    )
    print("targets: fast path >= 20x faster than the recipe; couple_lm no slower than it")


if __name__ == "__main__":
    main()
