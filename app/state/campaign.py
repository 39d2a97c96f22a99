"""State of the campaign card: the campaign file, the chosen case and how it is viewed.

Plain state (no file access), one :class:`CampaignState` per session, held by the session's
:class:`~app.state.DashboardState` as ``state.campaign``. The file and the case are in the
link, so a link opens the same campaign file on the same case and view; the folder the
files come from is the server's (``FBS_CAMPAIGN_DIR``), never the link's. The case table's
filters (kind, noise, target, status) are the card's own: they choose what the table lists,
not what a result is made of.
"""

from __future__ import annotations

import os
from pathlib import Path

import param

from fbs_core.vocabulary import DIRECTIONS

from ..schema import setting
from .params import Integer

__all__ = ["CAMPAIGN_DIR_ENV", "CampaignState", "campaign_dir"]

#: The environment variable naming the server's campaign folder.
CAMPAIGN_DIR_ENV = "FBS_CAMPAIGN_DIR"


def campaign_dir() -> Path | None:
    """The configured campaign directory (``$FBS_CAMPAIGN_DIR``), None when unset."""
    raw = os.environ.get(CAMPAIGN_DIR_ENV, "").strip()
    return Path(raw).resolve() if raw else None


class CampaignState(param.Parameterized):
    """The campaign file and case a session shows (one per session)."""

    directory = param.ClassSelector(
        metadata=setting(None, field="campaign_dir"),
        class_=Path,
        default=None,
        allow_None=True,
        precedence=-1,
        doc="The server's campaign folder (FBS_CAMPAIGN_DIR, None: not set); not a control "
        "and not in the link.",
    )
    file = param.String(
        metadata=setting("cfile", field="campaign_file"),
        default="",
        doc="Campaign result file of the folder ('': none opened).",
    )
    case = param.String(
        metadata=setting("ccase", field="campaign_case"),
        default="",
        doc="Case of the file shown ('': none).",
    )
    dof = param.Selector(
        metadata=setting("cdof", field="campaign_dof"),
        default="z",
        objects=list(DIRECTIONS),
        doc="Bushing DOF of the case's band, corridor or error map.",
    )
    max_over_dofs = param.Boolean(
        metadata=setting("cmax", field="campaign_max"),
        default=False,
        doc="A truncation case's error map as the maximum over the 6 DOFs.",
    )
    harmonic = Integer(
        metadata=setting("ch", field="campaign_harmonic"),
        default=0,
        bounds=(0, 7),
        doc="Harmonic the case table is filtered by and a variants case is shown at (0: "
        "all; a variants case then shows its first harmonic).",
    )
