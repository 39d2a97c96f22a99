"""Plausibility table of the reference tire against the thesis' tire and published data.

Usage (from the repository root)::

    .venv/bin/python scripts/print_tire_table.py

Prints the targets of ``../shared/design/reference-models.md`` sections 2.2-2.3
next to what the shipped model (``data/reference_tire.h5``) and its physical
matrices give. The same targets are asserted, with tolerances, in
``tests/test_tire_physics.py``.
"""

from __future__ import annotations

import dataclasses
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402

from fbs_core import harmonic, reference_tire  # noqa: E402
from fbs_core.tire import HUB_DOFS, ring_closed_form, system_matrices  # noqa: E402
from fbs_core.tire.modes import complex_modes  # noqa: E402
from fbs_core.tire.ring import belt_labels  # noqa: E402

THESIS_TABLE_5_1 = {10: 20, 20: 90, 40: 144, 70: 236, 130: 347, 270: 511, 340: 573}


def peaks(f, a, prominence_db=1.0):
    """Maxima of the level that stand out by ``prominence_db`` (and the lesser bumps)."""
    from scipy.signal import find_peaks

    i, p = find_peaks(20 * np.log10(a), prominence=0.0)
    prom = p["prominences"]
    bumps = [(f[k], x) for k, x in zip(i, prom, strict=True) if x < prominence_db]
    return f[i[prom >= prominence_db]], bumps


def main():
    tire = reference_tire()
    p = tire.params
    print("Reference tire: plausibility table")
    print("=" * 78)

    print("\n1. Static stiffness on the road, hub DOF moved with the other 5 held (0 km/h)")
    # at standstill the tread sticks to the road (no slip states)
    stick = dataclasses.replace(p, slip_zones=0)
    _, _, _, K = system_matrices(0.0, stick)
    S = K[:6, :6] - K[:6, 6:] @ np.linalg.solve(K[6:, 6:], K[6:, :6])  # condensed hub stiffness
    for dof, target in (("hub:z", "200 kN/m"), ("hub:x", "300 kN/m"), ("hub:y", "100 kN/m")):
        i = HUB_DOFS.index(dof)
        print(f"   {dof:6s} {S[i, i] / 1e3:8.0f} kN/m      MF-Swift 205/60R15: {target}")
    i = HUB_DOFS.index("hub:rz")
    print(f"   hub:rz {S[i, i] / 1e3:8.1f} kN m/rad  MF-Swift 205/60R15: 5 kN m/rad")

    print("\n2. Rim-fixed ring (closed form, 0 km/h)        target (MF-Swift)")
    print(f"   wind-up n=0      {ring_closed_form(0, 0.0, p)[0]:6.1f} Hz            70 Hz")
    print(f"   translation n=1  {ring_closed_form(1, 0.0, p)[0]:6.1f} Hz            80 Hz")

    print("\n3. First belt radial modes (free hub on the road, 0 km/h)   target 80-100 Hz")
    M, _, _, K = system_matrices(0.0, stick)
    w2, phi = sla.eigh(K, M)
    labels = belt_labels(p)
    cols = 6 + np.flatnonzero(
        [lab.startswith("belt.ip.") and not lab.endswith("n00") for lab in labels]
    )
    e = phi**2 * np.diag(M)[:, None]
    share = e[cols].sum(0) / e.sum(0)
    f0 = np.sqrt(w2) / (2 * np.pi)
    print("   " + ", ".join(f"{x:.1f}" for x in f0[share > 0.5][:4]) + " Hz")

    print("\n4. Hub response to the patch load, case 1 (12.9-51.6 Hz)   target 17 and 38 Hz")
    f = np.arange(13.0, 51.5, 0.25)
    v = np.abs(tire.patch_response(f, 1).data[:, :, 0])
    for dof in ("hub:z", "hub:x", "hub:ry"):
        a = v[:, HUB_DOFS.index(dof)]
        pk, bumps = peaks(f, a)
        line = f"   {dof:6s} peaks (>= 1 dB prominence) at " + (
            ", ".join(f"{x:.2f}" for x in pk) + " Hz" if pk.size else "none"
        )
        if bumps:
            line += "; bumps " + ", ".join(f"{x:.2f} Hz ({p:.2f} dB)" for x, p in bumps)
        print(line)

    print("\n5. Modes (positive eigenfrequencies)          target: 200, ~150+ below 800 Hz")
    print("   speed   n   <160 Hz  <800 Hz  highest   damping ratio")
    for s in tire.speeds:
        fr = tire.eigenfrequencies(s)
        pol = tire.poles_at(s)[0::2]
        pol = pol[pol.imag > 0]  # oscillating modes (the slip states have real poles)
        z = -pol.real / np.abs(pol)
        print(
            f"   {s:5.0f} {fr.size:4d} {np.sum(fr < 160):7d} {np.sum(fr < 800):8d} "
            f"{fr[-1]:8.0f} Hz  {z.min():.3f}-{z.max():.3f}"
        )

    print("\n6. Eigenfrequency of the N-th complex mode at 80 km/h (thesis table 5.1 / fig 5.8)")
    # highest eigenfrequency among the first N modes in the model's order (the real
    # poles of the slip states come first and count as modes, as in the truncation study)
    run = np.maximum.accumulate(np.abs(tire.poles_at(80.0).imag)) / (2 * np.pi)
    for n, target in THESIS_TABLE_5_1.items():
        print(f"   N = {n:3d}: {run[n - 1]:6.0f} Hz    thesis {target:4d} Hz")
    print(f"   N = 400: {run[-1]:6.0f} Hz    thesis ~800-900 Hz")

    print("\n7. Forward / backward split of ring-dominated modes at 100 km/h vs closed form")
    from fbs_core.tire.ring import build_tire_system

    s = build_tire_system(100.0, p)
    md = complex_modes(s.M, s.C, s.K)
    fam = np.array([lab.split(".")[1] for lab in labels])
    order = np.array([int(lab.split(".")[2][1:3]) for lab in labels])
    e = np.abs(md.psi[:, 0::2]) ** 2 * np.diag(s.M)[:, None]
    e /= e.sum(0)
    print("   n   f+ model  f- model  split   | f+ ring  f- ring  split")
    for n in range(2, 9):
        sh = e[6 : 6 + len(labels)][(fam == "ip") & (order == n)].sum(0)
        cp, cm = ring_closed_form(n, 100.0, p)
        hi = md.frequencies > 0.5 * (cp + cm)
        fp = md.frequencies[hi][np.argmax(sh[hi])]
        fm = md.frequencies[~hi][np.argmax(sh[~hi])]
        print(f"   {n}  {fp:8.1f} {fm:9.1f} {fp - fm:7.1f}   | {cp:7.1f} {cm:8.1f} {cp - cm:6.1f}")

    print("\n8. Interpolation between operating points (hub mobility, 5-300 Hz, vs direct)")
    fm_ = np.arange(5.0, 300.0, 2.0)
    for sp in (30.0, 50.0, 90.0, 110.0):
        Y = tire.hub_mobility(fm_, sp).data
        Yd = tire.system(sp).frf(fm_, HUB_DOFS, HUB_DOFS).data
        err = np.linalg.norm(Y - Yd, axis=(1, 2)) / np.linalg.norm(Yd, axis=(1, 2))
        print(
            f"   {sp:5.0f} km/h: median {np.median(err):.3f}, 90th percentile "
            f"{np.percentile(err, 90):.3f} (relative Frobenius error per line)"
        )

    print("   patch response along the harmonic lines (every 8th line, vs direct solve):")
    for k in (1, 3, 5, 7):
        h = harmonic(k)
        fl = h.frequencies()[::8]
        vm = tire.patch_response(fl, h).data[:, :, 0]
        vd = np.array(
            [
                tire.system(sp)
                .frf([x], HUB_DOFS, [], loads={"p": tire.patch_load(sp, h.wavelength)})
                .data[0, :, 0]
                for x, sp in zip(fl, h.speed_at(fl), strict=True)
            ]
        )
        err = np.linalg.norm(vm - vd, axis=1) / np.linalg.norm(vd, axis=1)
        print(
            f"   case {k}: median {np.median(err):.3f}, 90th percentile "
            f"{np.percentile(err, 90):.3f}"
        )

    print("\n9. Tracking between operating points:", "median MAC", tire.meta.get("mac_median"))
    h = harmonic(1)
    print(
        f"\nHarmonic case 1: wavelength {h.wavelength} m, {h.freq_range[0]:.1f}-"
        f"{h.freq_range[1]:.1f} Hz"
    )


if __name__ == "__main__":
    main()
