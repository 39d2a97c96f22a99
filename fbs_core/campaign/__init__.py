"""Sensitivity campaigns on Dask distributed (thesis chapter 5 at the scale of a review).

A campaign file (TOML, ``campaigns/example.toml``) lists the case matrix: harmonics, noise
levels, targets, frequency dependence, rounds (noise scatter bands, thesis 5.2), mode-count
ranges (truncation maps and suggested modes, thesis 5.1), tire and chassis variants by file,
6 or 5 DOF couplings, the outputs and the seed. :func:`run_campaign` splits it into tasks,
runs them on a ``dask.distributed`` cluster (a LocalCluster by default, an existing one with
``FBS_DASK_SCHEDULER=tcp://host:8786``) and writes one HDF5 file with the provenance of every
case; a rerun computes only what is missing. :func:`open_campaign` browses the file.

Command line::

    python -m fbs_core.campaign run campaigns/example.toml [--workers 2] [--scheduler ADDR]
    python -m fbs_core.campaign summary example.h5

Example
-------
>>> from fbs_core.campaign import load_campaign, run_campaign, open_campaign
>>> report = run_campaign(load_campaign("campaigns/example.toml"))   # doctest: +SKIP
>>> res = open_campaign(report.output)                                 # doctest: +SKIP
>>> band = res.band(res.find(harmonic=4, noise=0.1, target="both")[0].name)  # doctest: +SKIP
"""

from .browse import CampaignResult, CaseEntry, TruncationEntry, open_campaign
from .fields import case_seed
from .run import SCHEDULER_ENV, RunReport, Task, group_blocks, make_client, plan, run_campaign
from .spec import (
    BandCase,
    Campaign,
    CampaignError,
    TruncationCase,
    load_campaign,
    parse_campaign,
)
from .store import CampaignStore

__all__ = [
    "BandCase",
    "Campaign",
    "CampaignError",
    "CampaignResult",
    "CampaignStore",
    "CaseEntry",
    "RunReport",
    "SCHEDULER_ENV",
    "Task",
    "TruncationCase",
    "TruncationEntry",
    "case_seed",
    "load_campaign",
    "make_client",
    "open_campaign",
    "parse_campaign",
    "plan",
    "group_blocks",
    "run_campaign",
]
