"""Print the coupled peaks at the bushing for every harmonic case (compare thesis appendix A).

Usage::

    .venv/bin/python scripts/print_bushing_peaks.py [--coupling 6dof|5dof] [--n-modes N]
                                                   [--df 0.25] [--top 3]

For each harmonic case 1..7 and each bushing DOF (x, y, z in m/s; rx, ry, rz in
rad/s, per metre of road amplitude of the patch load), the strongest local maxima
of ``|v_e*|`` (thesis eq. 4.1) inside the harmonic's band are listed as
``frequency Hz / level dB`` with the level ``20 log10 |v|`` re 1 m/s (1 rad/s)
per unit input, strongest first. The band's maximum is listed when the response
has no interior peak (monotonic over the band).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.signal import find_peaks

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fbs_core import bushing_response, harmonic  # noqa: E402


def peaks(freq: np.ndarray, v: np.ndarray, top: int) -> list[tuple[float, float]]:
    """Strongest ``top`` local maxima of ``|v|`` as (Hz, dB), strongest first."""
    a = np.abs(v)
    idx = find_peaks(a)[0]
    if idx.size == 0:
        idx = np.array([int(np.argmax(a))])
    idx = idx[np.argsort(a[idx])[::-1][:top]]
    return [(float(freq[i]), float(20 * np.log10(a[i]))) for i in idx]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--coupling", default="6dof", choices=["6dof", "5dof"])
    ap.add_argument("--n-modes", type=int, default=None, help="tire modes kept (default all)")
    ap.add_argument("--df", type=float, default=0.25, help="frequency step in Hz")
    ap.add_argument("--top", type=int, default=3, help="peaks listed per DOF")
    args = ap.parse_args(argv)
    print(
        f"coupled response at the bushing, {args.coupling} coupling, "
        f"{'all' if args.n_modes is None else args.n_modes} tire modes; "
        "levels in dB re 1 m/s (rad/s) per m of road amplitude"
    )
    for k in range(1, 8):
        h = harmonic(k)
        f = h.frequencies(df=args.df)
        v = bushing_response(k, n_modes=args.n_modes, freq=f, coupling=args.coupling)
        lo, hi = h.freq_range
        print(f"\n{h.name} (lambda = {h.wavelength:g} m, {lo:.1f}-{hi:.1f} Hz)")
        for i, dof in enumerate(v.outputs):
            cells = "  ".join(
                f"{fr:6.1f} Hz {db:7.1f} dB" for fr, db in peaks(v.freq, v.data[:, i, 0], args.top)
            )
            print(f"  {dof:<11} {cells}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
