"""Print the second virtual point's validation figures: the bushing's six DOFs from sensors
around it.

The truth is the reference chassis with a flexible knuckle (``fbs_core.vpt.validation``)
and three tri-axial sensors around the bushing, as the bushing node's rigid-body motion
(the exact case) or on three short stiff steel arms welded to it; the second virtual point
(``fbs_core.vpt.response_point``) against the FE model's own bushing DOFs, and the coupled
bushing response of the measured chassis (both virtual points) against the exact chassis',
noise-free and with the errors of a real test (2 mm, 2 degrees on every channel, 1 % complex
noise on every FRF). docs/vpt.md quotes these figures.

    python scripts/print_vpt_bushing.py [--seeds 30]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import fbs_core as fc
from fbs_core.chassis import BUSHING
from fbs_core.vpt import response_point, virtual_point
from fbs_core.vpt import validation as val

BAND = np.arange(2.0, 450.1, 2.0)
HARMONIC = 4


def row(what: str, value: str, limit: str = "") -> None:
    print(f"  {what:<62} {value:>22}  {limit}")


def rel_to_peak(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """max over lines |a - b| / max over lines |b|, per entry."""
    out: np.ndarray = np.abs(a - b).max(0) / np.abs(b).max(0)
    return out


def dofs(e: np.ndarray) -> str:
    return " ".join(f"{v:.2g}" for v in e)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10, help="noisy measurements (default 10)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    r0 = val.bushing_point()
    f1 = val.bushing_arms_flexible_mode()
    print(f"bushing sensors: 3 tri-axial, lever arms {val.BUSHING_ARMS} m; {BAND.size} lines")
    print("\nnoise-free, second virtual point vs the FE bushing DOFs (max |error| / peak,")
    print("per DOF x y z rx ry rz, worst impact)")
    for kind in ("rigid", "arms"):
        m = val.knuckle_measurement(BAND, "mobility", bushing=kind)
        assert m.bushing_sensors is not None and m.exact_bushing is not None
        rp = response_point(m.measured, m.bushing_sensors, r0, "bushing")
        e = rel_to_peak(rp.frf.sel(outputs=list(BUSHING)).data, m.exact_bushing.data).max(1)
        row(f"{kind}", dofs(e), f"max {e.max():.2e}")
        lev = max(rp.sensor_leverage.values())
        row(f"  {kind}: consistency overall (mean) / lowest channel", "", "")
        w = rp.consistency.worst()
        row("", f"{rp.consistency.overall()[0]:.6f} / {w[0]} {w[1]:.4f}", f"leverage {lev:.2f}")
    row(
        "arms' first flexible mode (bushing clamped)",
        f"{f1:.0f} Hz",
        f"(450/f1)^2 = {(BAND[-1] / f1) ** 2:.2%}",
    )

    mr = val.knuckle_measurement(BAND, "mobility", bushing="rigid")
    assert mr.bushing_sensors is not None and mr.exact_bushing is not None
    Er = mr.exact_bushing.data
    bound = val.bushing_error_bound(mr, 0.01, 0.002, 2.0)
    pk = np.abs(Er).max(0)
    print(f"\nrigid sensors with a real test's errors: 2 mm, 2 deg, 1 % noise ({args.seeds} seeds)")
    row("first-order bound / each FRF's peak (worst impact)", dofs((bound.max(0) / pk).max(1)))
    errs, ratio, cons, low = [], [], [], []
    for s in range(args.seeds):
        ch = val.perturbed_channels(mr.bushing_sensors, 0.002, 2.0, seed=s)
        rp = response_point(val.noisy(mr.measured, 0.01, s), ch, r0, "bushing")
        err = np.abs(rp.frf.sel(outputs=list(BUSHING)).data - Er)
        errs.append((err.max(0) / pk).max(1))
        ratio.append(float((err / bound).max()))
        cons.append(rp.consistency.overall()[0])
        low.append(rp.consistency.worst())
    e = np.array(errs)
    row("max |error| / each FRF's peak, median seed", dofs(np.median(e, 0)))
    row(
        "  range over seeds",
        " ".join(f"{a:.2g}-{b:.2g}" for a, b in zip(e.min(0), e.max(0), strict=True)),
    )
    row("largest error / bound (worst seed)", f"{max(ratio):.2f}", "< 1")
    lw = sorted(low, key=lambda t: t[1])
    row("consistency overall, range over seeds", f"{min(cons):.5f}-{max(cons):.5f}", "< 1")
    row("lowest channel, range over seeds", f"{lw[0][1]:.3f}-{lw[-1][1]:.3f} ({lw[0][0]})")

    f = fc.harmonic(HARMONIC).frequencies()
    m = val.knuckle_measurement(f, "accelerance", bushing="arms")
    assert m.bushing_sensors is not None
    E = m.exact.to("mobility")
    v_ex = fc.bushing_response(HARMONIC, chassis=fc.FRFChassis(E))
    peak = np.abs(v_ex.data).max(0)[:, 0]

    def coupled(meas: fc.FRF, lay: val.Layout, ch: val.Channels) -> np.ndarray:
        rp = response_point(meas, ch, r0, "bushing")
        vp = virtual_point(rp.frf, lay, transfers=list(BUSHING))
        v = fc.bushing_response(HARMONIC, chassis=fc.FRFChassis(vp.frf.to("mobility")))
        return v.data[:, :, 0]

    v0 = coupled(m.measured, m.layout, m.bushing_sensors)
    e0 = np.abs(v0 - v_ex.data[:, :, 0]).max(0) / peak
    print(f"\ncoupled bushing response, harmonic {HARMONIC}, arms: max |error| / DOF's peak")
    row("noise-free", dofs(e0), f"max {e0.max():.2%}")
    print(f"\nwith a real test's errors: 2 mm, 2 deg, 1 % noise ({args.seeds} seeds)")
    nk = len(m.layout.sensors)
    res: dict[str, list[np.ndarray]] = {"all": [], "knuckle": [], "bushing": [], "db": []}
    for s in range(args.seeds):
        noisy = val.noisy(m.measured, 0.01, s)
        lay = val.perturbed_layout(m.layout, 0.002, 2.0, seed=s)
        ch = val.perturbed_channels(m.bushing_sensors, 0.002, 2.0, seed=100 + s)
        va = coupled(noisy, lay, ch)
        res["all"].append(np.abs(va - v_ex.data[:, :, 0]).max(0) / peak)
        res["db"].append(
            np.median(np.abs(20 * np.log10(np.abs(va) / np.abs(v_ex.data[:, :, 0]))), 0)
        )
        dk = m.measured.data.copy()
        dk[:, :nk] = noisy.data[:, :nk]
        vk = coupled(m.measured.replace(data=dk), lay, m.bushing_sensors)
        res["knuckle"].append(np.abs(vk - v_ex.data[:, :, 0]).max(0) / peak)
        db = m.measured.data.copy()
        db[:, nk:] = noisy.data[:, nk:]
        vb = coupled(m.measured.replace(data=db), m.layout, ch)
        res["bushing"].append(np.abs(vb - v_ex.data[:, :, 0]).max(0) / peak)
    for k, what in (
        ("all", "all errors: max |error| / peak, median seed"),
        ("knuckle", "knuckle channels' errors only: same"),
        ("bushing", "bushing sensors' errors only: same"),
    ):
        a = np.array(res[k])
        row(what, dofs(np.median(a, 0)), "")
        row("  worst seed", dofs(a.max(0)), "")
    d = np.array(res["db"])
    row("all errors: median |dB| per DOF, worst seed", dofs(d.max(0)), "")
    print(f"\n{time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
