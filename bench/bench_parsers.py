"""Parse cost of the text importers (issue 20.1 / 20.3 / 12): linear time, bounded memory.

Prints, for the code of the working tree it is run from:

* CSV files of 10k / 20k / 40k column pairs (outputs x one input, 4 lines): parse time
  and the ratio to the 10k file (2.0 and 4.0 for a linear reader);
* CSV files of 75k / 150k / 300k lines (one column pair; 300k lines is the 6.4 MB file of
  the attack suite): the same;
* UFF files of 1k / 2k / 4k dataset-58 records: the same;
* a 2.8 MB UFF file of ``-1`` lines (refused; the time it takes);
* a ~300 KB compressed MAT file of 300 MB of zeros (refused by the sandbox's bound on
  what may come back): time and the calling process' peak memory;
* a ~100 MiB CSV (12 outputs x 6 inputs, re-im): parse time and the peak resident
  memory of the process that called ``load_frf`` (the server), in a fresh interpreter,
  next to its memory after the imports.

Run: ``.venv/bin/python bench/bench_parsers.py`` (``--quick`` skips the 100 MiB file).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def wide_csv(n_pairs: int) -> bytes:
    head = "# quantity: mobility\n# units: m/(N s)\nfreq [Hz]," + ",".join(
        f"Re(n{k}:z / s:z),Im(n{k}:z / s:z)" for k in range(n_pairs)
    )
    rows = [",".join([f"{f:.1f}"] + ["1e-3"] * (2 * n_pairs)) for f in (1.0, 2.0, 3.0, 4.0)]
    return (head + "\n" + "\n".join(rows) + "\n").encode()


def tall_csv(n_rows: int) -> bytes:
    """One column pair, ``n_rows`` lines (300,000 lines: the attack suite's 6.4 MB file)."""
    head = "# quantity: mobility\n# units: m/(N s)\nfreq [Hz],Re(n0:z / s:z),Im(n0:z / s:z)\n"
    body = "\n".join(f"{1.0 + k * 0.5},1.0e-3,1.0e-3" for k in range(n_rows))
    return (head + body + "\n").encode()


def many_records_uff(n_rec: int) -> bytes:
    import fbs_core as fc
    from fbs_core.io import save_frf

    f = np.arange(1, 9) * 1.0
    Y = fc.FRF(f, np.ones((8, n_rec, 1)) * 1e-3, [f"{k + 1}:z" for k in range(n_rec)], ["0:z"])
    return save_frf(Y, format="uff")


def timed(fn, repeat=3):
    """Best wall time and best CPU time of this process (the sandbox's CPU not included;
    on a loaded machine the CPU time shows the scaling more clearly)."""
    best, cpu = np.inf, np.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return best, cpu


def scaling(title, make, sizes, filename):
    from fbs_core.io import load_frf

    print(title)
    base = None
    for n in sizes:
        raw = make(n)
        t, c = timed(lambda raw=raw: load_frf(raw, filename=filename), repeat=2)
        base = base or (t, c)
        print(
            f"  {n:>6}: {len(raw) / 1e6:6.2f} MB  wall {t:7.3f} s (ratio {t / base[0]:4.1f})"
            f"  CPU here {c:6.3f} s (ratio {c / base[1]:4.1f})"
        )


_PEAK = r"""
import json, resource, sys, time
from fbs_core.io import load_frf
import fbs_core.io.csv, fbs_core.io.uff, fbs_core.io.matlab, fbs_core.io.hdf5
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t0 = time.perf_counter()
r = load_frf(sys.argv[1])
t = time.perf_counter() - t0
me = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(dict(t=t, self_mb=me, base_mb=base, shape=list(r.frf.shape))))
"""


def big_csv(path: Path, target_bytes: int = 100 * 2**20 - 4096) -> None:
    import fbs_core as fc

    outs = fc.node_labels("spindle") + fc.node_labels("bushing")
    ins = fc.node_labels("spindle")
    cols = ["freq [Hz]"] + [f"{p}({o} / {i})" for o in outs for i in ins for p in ("Re", "Im")]
    rng = np.random.default_rng(0)
    block = rng.normal(size=(1000, len(cols) - 1)) * 1e-4
    with path.open("w") as fh:
        fh.write("# quantity: mobility\n# units: m/(N s)\n" + ",".join(cols) + "\n")
        k, size = 0, fh.tell()
        rows = [",".join(f"{x:.9e}" for x in row) for row in block]
        while True:
            line = f"{(k + 1) * 0.01:.2f}," + rows[k % len(rows)] + "\n"
            if size + len(line) > target_bytes:
                break
            fh.write(line)
            size += len(line)
            k += 1


_MAKE_BOMB = r"""
import sys, numpy as np, scipy.io
scipy.io.savemat(sys.argv[1], {"H": np.zeros(37_500_000), "freq": np.arange(2.0)},
                 do_compression=True)
"""

_BOMB = r"""
import json, resource, sys, time
from fbs_core.errors import FBSError
from fbs_core.io import load_frf
import fbs_core.io.matlab
raw = open(sys.argv[1], "rb").read()
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t0 = time.perf_counter()
try:
    load_frf(raw, filename="bomb.mat")
    msg = "accepted?!"
except FBSError as e:
    msg = str(e)
t = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(dict(size=len(raw), t=t, base=base, peak=peak, msg=msg[:110])))
"""


def bomb(d: str) -> None:
    """A small compressed MAT file of 300 MB of zeros (issue 20.4)."""
    p = Path(d) / "bomb.mat"
    subprocess.run([sys.executable, "-c", _MAKE_BOMB, str(p)], check=True)
    out = subprocess.run(
        [sys.executable, "-c", _BOMB, str(p)], capture_output=True, text=True, check=True
    )
    r = json.loads(out.stdout.strip().splitlines()[-1])
    print(
        f"MAT of {r['size'] / 1e3:.0f} KB holding 300 MB of zeros: {r['t']:.2f} s, calling "
        f"process peak RSS {r['peak']:.0f} MB ({r['base']:.0f} MB before): {r['msg']}"
    )


def main() -> None:
    quick = "--quick" in sys.argv
    scaling(
        "CSV, column pairs (outputs x 1 input, 4 lines):",
        wide_csv,
        (10_000, 20_000, 40_000),
        "wide.csv",
    )
    scaling(
        "CSV, lines (one column pair):",
        tall_csv,
        (75_000, 150_000, 300_000),
        "tall.csv",
    )
    scaling("UFF 58, records (8 lines each):", many_records_uff, (1000, 2000, 4000), "many.uff")
    from fbs_core.errors import FBSError
    from fbs_core.io import load_frf

    minus = b"    -1\n" * 400_000
    t0 = time.perf_counter()
    try:
        load_frf(minus, filename="minus.uff")
        msg = "accepted?!"
    except FBSError as e:
        msg = str(e)[:90]
    print(
        f"UFF of {len(minus) / 1e6:.1f} MB of '-1' lines: {time.perf_counter() - t0:.3f} s: {msg}"
    )
    if quick:
        return
    with tempfile.TemporaryDirectory() as d:
        bomb(d)
        p = Path(d) / "big.csv"
        big_csv(p)
        out = subprocess.run(
            [sys.executable, "-c", _PEAK, str(p)], capture_output=True, text=True, check=True
        )
        r = json.loads(out.stdout.strip().splitlines()[-1])
        print(
            f"CSV of {p.stat().st_size / 2**20:.0f} MiB, FRF {r['shape']}: {r['t']:.1f} s; peak "
            f"RSS of the calling process {r['self_mb']:.0f} MB ({r['base_mb']:.0f} MB after "
            "the imports; the numbers are parsed in the sandbox process)"
        )


if __name__ == "__main__":
    main()
