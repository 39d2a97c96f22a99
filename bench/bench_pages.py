"""Memory of the server process over many page builds outside a browser session (issue 20.2).

Panel's ``--liveness`` check built one page of the app in a Bokeh document without a browser
session for every request, and ended it; the attack suite saw the server grow from 423 to
1073 MB over ~250 requests. This benchmark does the same in this process: it runs the app
script (``app/main.py``) into ``N`` new documents through Panel's app handler, ends each
document (Panel's clean-up, as its liveness handler did), collects garbage,
and prints the resident memory of the process and how many pages' results are still alive.

Run: ``.venv/bin/python bench/bench_pages.py [N]`` (default 12). To compare with older code,
run it with ``PYTHONPATH`` pointing at a checkout of that code.
"""

from __future__ import annotations

import gc
import os
import sys
import time
import weakref
from pathlib import Path

import app
import app.store


def rss_mb() -> float:
    """Current resident memory of this process (Linux)."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    from panel.command.serve import build_single_handler_applications
    from panel.io.document import _cleanup_doc

    made: list[weakref.ref] = []
    init = app.store.Results.__init__

    def tracked(self, *args, **kwargs):
        init(self, *args, **kwargs)
        made.append(weakref.ref(self))

    app.store.Results.__init__ = tracked
    script = Path(app.__file__).resolve().parent / "main.py"
    print(f"app script: {script}")
    handler = build_single_handler_applications([str(script)], {})["/main"]
    first = None
    for k in range(1, n + 1):
        t0 = time.perf_counter()
        doc = handler.create_document()
        _cleanup_doc(doc)  # as Panel's liveness handler did after each page
        del doc
        gc.collect()
        rss = rss_mb()
        first = first or rss
        alive = sum(r() is not None for r in made)
        print(
            f"page {k:3d}: built and ended in {time.perf_counter() - t0:5.1f} s; RSS {rss:7.1f} MB "
            f"(+{rss - first:6.1f} since page 1); pages alive after gc: {alive}",
            flush=True,
        )
    per_page = (rss_mb() - first) / max(n - 1, 1)
    print(f"growth per page after the first: {per_page:.1f} MB; pages alive: {alive} of {n}")


if __name__ == "__main__":
    main()
