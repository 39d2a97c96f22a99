"""Compare fbs_core's virtual point transformation with pyFBS's ``VPT`` on the same inputs.

pyFBS is not a dependency of this project and is never imported by it: it lives in a
separate virtual environment (default ``/work/pyfbs-venv``; make one with
``python3 -m venv DIR && DIR/bin/pip install pyFBS``). This script writes the inputs
(positions, directions, the virtual point, the measured FRFs, weights) to a temporary
``.npz`` file, runs that environment's interpreter on a small script that feeds them to
``pyFBS.VPT`` (pandas tables in pyFBS's layout) and writes its ``apply_vpt`` result back to
an ``.npz``, and prints the largest difference beside the limit 1e-8 (relative to the
largest entry), for equal weights and for per-channel weights.

pyFBS's force weighting matrix enters its ``T_f`` inverted (``T_f = W^-1 R_f (R_f^T W^-1
R_f)^-1``); the same weights are passed to fbs_core as ``1 / w``.

    python bench/compare_vpt_pyfbs.py [--venv /work/pyfbs-venv]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from fbs_core.vpt import validation as val
from fbs_core.vpt import virtual_point

LIMIT = 1e-8

#: Runs in the other environment: plain numpy arrays in, pyFBS's result out (no pickles).
PYFBS_SCRIPT = r"""
import sys
import numpy as np
import pandas as pd
try:
    import pyfbs as pyFBS  # 1.0 and later
    VPT = pyFBS.interface.VPT if hasattr(pyFBS, "interface") else pyFBS.VPT
except ImportError:  # older releases
    import pyFBS
    VPT = pyFBS.VPT

src, dst = sys.argv[1], sys.argv[2]
z = np.load(src, allow_pickle=False)

def table(pos, dirs, names, group, quantity):
    return pd.DataFrame({
        "Name": names, "Description": names, "Quantity": quantity, "Grouping": group,
        "Position_1": pos[:, 0], "Position_2": pos[:, 1], "Position_3": pos[:, 2],
        "Direction_1": dirs[:, 0], "Direction_2": dirs[:, 1], "Direction_3": dirs[:, 2],
    })

ns, ni, nb = len(z["s_pos"]), len(z["i_pos"]), int(z["n_transfer"])
chn = table(
    np.vstack([z["s_pos"], np.zeros((nb, 3))]), np.vstack([z["s_dir"], np.zeros((nb, 3))]),
    [f"s{k}" for k in range(ns + nb)], [1] * ns + [2] * nb, "Acceleration",
)
imp = table(z["i_pos"], z["i_dir"], [f"i{k}" for k in range(ni)], [1] * ni, "Force")
o = np.tile(z["origin"], (6, 1))
vp_chn = table(o, np.zeros((6, 3)), ["ux", "uy", "uz", "rx", "ry", "rz"], [1] * 6, "Acceleration")
vp_imp = table(o, np.zeros((6, 3)), ["fx", "fy", "fz", "mx", "my", "mz"], [1] * 6, "Force")
try:  # the distribution's release (the package's own __version__ may lag behind it)
    from importlib.metadata import version
    release = version("pyFBS")
except Exception:
    release = getattr(pyFBS, "__version__", "?")
out = {"version": np.array([ord(c) for c in release])}
for case in ("equal", "weighted"):
    wu = z["wu"] if case == "weighted" else None
    wf = z["wf_pyfbs"] if case == "weighted" else None
    vpt = VPT(chn, imp, vp_chn, vp_imp, wu=wu, wf=wf)
    vpt.apply_vpt(z["freq"], z["Y"])
    out[case] = vpt.frf
np.savez(dst, **out)
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--venv", default="/work/pyfbs-venv", help="pyFBS's virtual environment")
    args = ap.parse_args()
    python = Path(args.venv) / "bin" / "python"
    if not python.exists():
        sys.exit(f"no interpreter at {python}: make the environment with pip install pyFBS")
    f = np.arange(2.0, 450.1, 4.0)
    m = val.knuckle_measurement(f, quantity="accelerance")
    lay = m.layout
    rng = np.random.default_rng(0)
    wu = rng.uniform(0.5, 2.0, len(lay.sensors))
    wf = rng.uniform(0.5, 2.0, len(lay.impacts))
    ours = {
        "equal": virtual_point(m.measured, lay),
        "weighted": virtual_point(m.measured, lay, sensor_weights=wu, impact_weights=1.0 / wf),
    }
    with tempfile.TemporaryDirectory() as tmp:
        src, dst, script = Path(tmp, "in.npz"), Path(tmp, "out.npz"), Path(tmp, "run.py")
        script.write_text(PYFBS_SCRIPT)
        np.savez(
            src,
            s_pos=lay.sensors.positions,
            s_dir=lay.sensors.directions,
            i_pos=lay.impacts.positions,
            i_dir=lay.impacts.directions,
            origin=lay.origin,
            freq=f,
            Y=m.measured.data,  # sensor channels, then the bushing transfers
            n_transfer=np.array(len(m.measured.outputs) - len(lay.sensors)),
            wu=np.diag(wu),
            wf_pyfbs=np.diag(wf),
        )
        subprocess.run([str(python), str(script), str(src), str(dst)], check=True, cwd=tmp)
        with np.load(dst, allow_pickle=False) as z:
            theirs = {k: z[k] for k in ("equal", "weighted")}
            version = "".join(chr(c) for c in z["version"])
    print(
        f"pyFBS {version} VPT vs fbs_core.vpt.virtual_point, {f.size} lines, "
        f"{len(lay.sensors)} sensors x {len(lay.impacts)} impacts + 6 bushing channels"
    )
    worst = 0.0
    for case, r in ours.items():
        a, b = r.frf.data, theirs[case]
        if a.shape != b.shape:
            sys.exit(f"{case}: shapes differ, fbs_core {a.shape}, pyFBS {b.shape}")
        d = float(np.abs(a - b).max() / np.abs(b).max())
        # each FRF against its own peak: the small cross terms too
        d_each = float((np.abs(a - b).max(0) / np.abs(b).max(0)).max())
        worst = max(worst, d, d_each)
        ok = "ok" if max(d, d_each) < LIMIT else "FAILS"
        print(
            f"  {case:<9} max |fbs_core - pyFBS|: / largest entry {d:.2e}, / each FRF's "
            f"peak {d_each:.2e}   limit {LIMIT:.0e}  {ok}"
        )
    sys.exit(0 if worst < LIMIT else 1)


if __name__ == "__main__":
    main()
