"""The modules a page imports on first use, imported with the app.

A page's Markdown texts load Panel's Markdown libraries, its tables pandas and narwhals
(Panel's Tabulator), its studies numba, and its Analysis card the modules of its views,
each on first use (and numba registers its implementations on its first kernel).
The server imports the modules an app script imports before its port
opens (``docker/fbs_server.py``, ``preload_imports``), this one included: without it, the
first page requested after a start imported them itself (0.4 s of imports on an idle
machine, 0.7 s while the server's own proof of the app ran beside it).
"""

from __future__ import annotations

import contextlib
import importlib

import numba  # noqa: F401
from numba.core.registry import cpu_target

from app.views import (  # noqa: F401
    analysis_compare,
    analysis_contrib,
    analysis_modes,
    analysis_phase,
    analysis_speed,
)
from fbs_core.tire import quality  # noqa: F401

#: Panel's own dependencies that Panel imports when a pane first renders (left out
#: quietly if a Panel version no longer uses one).
PANEL_LAZY = ("markdown", "markdown_it", "narwhals.stable.v1", "pandas")

for _name in PANEL_LAZY:
    with contextlib.suppress(ImportError):
        importlib.import_module(_name)

# numba registers its implementations (numpy functions, random generators, typed
# containers, ...) when its first kernel is compiled or loaded from its cache: 0.3 s of
# imports, paid by the first page's first study (holding the GIL) unless done here
cpu_target.target_context.refresh()


def warm_before_serving() -> None:
    """What a first page computes, computed before the server's port opens (the server
    calls this after preloading the app's imports, ``docker/fbs_server.py``): the default
    page's results - the reference models loaded, their first error map and responses,
    the kernels loaded from numba's cache. A page requested the moment the port opened
    computed them itself (0.5-0.7 s of CPU more than a later page: 2.1-2.5 s to its first
    plot instead of 1.6-1.8 s). They are the shared results every page reads
    (``app.compute``), so computing them here changes no number."""
    from app.state import DashboardState
    from app.store import Results

    Results(DashboardState()).close()
