"""Print the virtual point transformation's validation figures beside their limits.

The truth is the reference chassis with a flexible knuckle (``fbs_core.vpt.validation``):
its exact 6-DOF spindle FRFs beside the virtual point of 3 tri-axial sensors and 12 impacts
on the knuckle arms, noise-free and with the errors of a real test (each point off by 2 mm,
each direction by 2 degrees, 1 % complex noise on every measured FRF). docs/vpt.md quotes
these figures.

    python scripts/print_vpt_validation.py [--seeds 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import fbs_core as fc
from fbs_core.vpt import validation as val
from fbs_core.vpt import virtual_point

BAND = np.arange(2.0, 450.1, 2.0)
HARMONIC = 4
#: Tolerances of the coupled bushing response (harmonic 4, 6-DOF coupling) with the errors
#: of a real test: median over the lines of |level difference| per bushing DOF, and the
#: largest difference relative to each DOF's peak (docs/vpt.md, "What the errors do").
MEDIAN_DB_LIMIT = 3.0
PEAK_LIMIT = 0.75


def row(what: str, value: str, limit: str, ok: bool | None = None) -> None:
    mark = "" if ok is None else ("ok" if ok else "FAILS")
    print(f"  {what:<58} {value:>16}  {limit:<14} {mark}")


def rel_to_peak(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """max over lines |a - b| / max over lines |b|, per entry."""
    return np.abs(a - b).max(0) / np.abs(b).max(0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10, help="noisy measurements (default 10)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    f_flex = val.knuckle_flexible_mode()
    m = val.knuckle_measurement(BAND, quantity="accelerance")
    print(
        f"reference chassis + flexible knuckle ({val.arms_mass():.1f} kg of arms), "
        f"{len(m.layout.sensors)} sensor channels x {len(m.layout.impacts)} impacts, "
        f"{BAND.size} lines {BAND[0]:g}-{BAND[-1]:g} Hz"
    )
    print("\nnoise-free")
    row(
        "knuckle's first flexible mode (spindle clamped)",
        f"{f_flex:.0f} Hz",
        "> 450 Hz",
        f_flex > BAND[-1],
    )
    r = virtual_point(m.measured, m.layout)
    Y, E = r.frf.to("mobility").data, m.exact.to("mobility").data
    e = rel_to_peak(Y, E)
    row(
        "6x6 spindle mobility: max |error| / FRF's peak",
        f"{e[:6].max():.3%}",
        "< 1 %",
        e[:6].max() < 0.01,
    )
    # the same FRFs in the other quantities: each FRF's peak moves (accelerance peaks at
    # the top of the band, where the knuckle arms' local compliance grows), the VPT does not
    for q in ("receptance", "accelerance"):
        Yq, Eq = r.frf.to(q).data[:, :6], m.exact.to(q).data[:, :6]
        eq = rel_to_peak(Yq, Eq).max()
        ok = np.array(
            [rel_to_peak(Yq[: k + 1], Eq[: k + 1]).max() < 0.01 for k in range(BAND.size)]
        )
        upto = BAND[int(np.flatnonzero(ok).max())] if ok.any() else float("nan")  # widest band
        row(f"6x6 spindle {q}: max |error| / peak (< 1 % up to)", f"{eq:.2%} ({upto:g} Hz)", "")
    row(
        "spindle -> bushing transfers: max |error| / peak",
        f"{e[6:].max():.3%}",
        "< 1 %",
        e[6:].max() < 0.01,
    )
    cs = r.consistency
    so, io = cs.overall()
    w, wv = cs.worst()
    row("overall sensor / impact consistency (mean)", f"{so:.5f} / {io:.5f}", "-> 1")
    row(f"lowest specific consistency ({w})", f"{wv:.4f}", "-> 1")
    lev = max(r.sensor_leverage.items(), key=lambda kv: kv[1])
    row(
        f"highest sensor leverage ({lev[0]}: unchecked)",
        f"{lev[1]:.3f}",
        "< 0.9 wanted",
        lev[1] < 0.9,
    )

    fh = fc.harmonic(HARMONIC).frequencies()
    mh = val.knuckle_measurement(fh, quantity="accelerance")
    v_ex = fc.bushing_response(HARMONIC, chassis=fc.FRFChassis(mh.exact.to("mobility")))
    rh = virtual_point(mh.measured, mh.layout)
    v0 = fc.bushing_response(HARMONIC, chassis=fc.FRFChassis(rh.frf.to("mobility")))
    e0 = rel_to_peak(v0.data, v_ex.data).max()
    row(
        f"coupled bushing response (harmonic {HARMONIC}): max |error| / peak",
        f"{e0:.3%}",
        "< 1 %",
        e0 < 0.01,
    )

    print(f"\nwith a real test's errors: 2 mm, 2 deg, 1 % noise ({args.seeds} seeds)")
    cons, worst, vp, med_db, peak = [], [], [], [], []
    pk = np.abs(E[:, :6]).max(0)
    norm = np.sqrt(np.outer(np.diag(pk), np.diag(pk)))
    for s in range(args.seeds):
        lay = val.perturbed_layout(m.layout, 0.002, 2.0, seed=s)
        rs = virtual_point(val.noisy(m.measured, 0.01, seed=s), lay)
        cons.append(rs.consistency.overall())
        worst.append(rs.consistency.worst()[1])
        vp.append((np.abs(rs.frf.to("mobility").data[:, :6] - E[:, :6]).max(0) / norm).max())
        lay_h = val.perturbed_layout(mh.layout, 0.002, 2.0, seed=s)
        rsh = virtual_point(val.noisy(mh.measured, 0.01, seed=s), lay_h)
        v = fc.bushing_response(HARMONIC, chassis=fc.FRFChassis(rsh.frf.to("mobility")))
        db = np.abs(20 * np.log10(np.abs(v.data) / np.abs(v_ex.data)))[:, :, 0]
        med_db.append(np.median(db, axis=0))
        peak.append(rel_to_peak(v.data, v_ex.data)[:, 0])
    c = np.array(cons)
    row(
        "overall sensor / impact consistency (mean, worst seed)",
        f"{c[:, 0].min():.5f} / {c[:, 1].min():.5f}",
        f"< {so:.5f}",
        bool(c[:, 0].max() < so),
    )
    row(
        "lowest specific consistency (median over seeds)",
        f"{np.median(worst):.4f}",
        f"< {wv:.4f}",
        bool(np.median(worst) < wv),
    )
    row("6x6 mobility: max |error| / sqrt(peak_i peak_j) (median)", f"{np.median(vp):.2%}", "")
    mdb = np.array(med_db)
    row(
        "coupled response: median |dB| per DOF (worst DOF, seed)",
        f"{mdb.max():.2f} dB",
        f"< {MEDIAN_DB_LIMIT:g} dB",
        bool(mdb.max() < MEDIAN_DB_LIMIT),
    )
    pe = np.array(peak)
    row(
        "coupled response: max |error| / DOF's peak (median seed)",
        f"{np.median(pe.max(1)):.1%}",
        "",
    )
    row(
        "coupled response: max |error| / DOF's peak (worst seed)",
        f"{pe.max():.1%}",
        f"< {PEAK_LIMIT:.0%}",
        bool(pe.max() < PEAK_LIMIT),
    )
    print(f"\n({time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
