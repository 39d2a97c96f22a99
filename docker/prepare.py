"""Build steps of the Docker image that need Python (run by the Dockerfile).

``python prepare.py data SRC``
    Installs the shipped reference data (``SRC``: the repository's ``data/``) where the
    installed ``fbs_core`` reads it, then loads the reference tire and chassis models: the
    build fails if the image could not run on its reference data.
``python prepare.py warmup``
    Builds one dashboard page outside a server, so that numba compiles the kernels into
    ``NUMBA_CACHE_DIR`` at build time instead of during the first user's session. A failure
    is reported but does not fail the build (the proof's app check catches a broken app).
"""

from __future__ import annotations

import shutil
import sys
import time
import traceback
from pathlib import Path


def install_data(src: Path) -> None:
    import fbs_core
    from fbs_core.tire import storage

    data_file = getattr(storage, "DATA_FILE", None)
    if data_file is not None:
        dest = Path(data_file).parent
        if dest.resolve() != src.resolve():
            dest.mkdir(parents=True, exist_ok=True)
            for f in sorted(src.iterdir()):
                if f.is_file() and f.suffix in (".h5", ".json", ".csv", ".unv", ".uff", ".mat"):
                    shutil.copy2(f, dest / f.name)
                    print(f"reference data: {f.name} -> {dest}")
    tire = fbs_core.reference_tire()
    chassis = fbs_core.reference_chassis()
    print(f"reference models load: {type(tire).__name__}, {type(chassis).__name__}")


def warmup() -> None:
    t0 = time.perf_counter()
    try:
        from app.main import create_app

        create_app()
    except Exception:
        traceback.print_exc()
        print("warm-up FAILED (numba kernels compile at the first session instead)")
        return
    print(f"warm-up: one dashboard page built in {time.perf_counter() - t0:.1f} s")


def main(argv: list[str]) -> int:
    if argv[:1] == ["data"] and len(argv) == 2:
        install_data(Path(argv[1]))
    elif argv == ["warmup"]:
        warmup()
    else:
        print("usage: prepare.py data SRC | prepare.py warmup", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
