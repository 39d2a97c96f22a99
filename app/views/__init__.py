"""The dashboard's views (``pn.viewable.Viewer`` subclasses)."""

from .controls import Controls
from .mobility import MobilityView, UncoupledView
from .scatter import ScatterBandView
from .truncation import EigenView, SuggestedModesView, TruncationView
from .upload import UploadView

__all__ = [
    "Controls",
    "EigenView",
    "MobilityView",
    "ScatterBandView",
    "SuggestedModesView",
    "TruncationView",
    "UncoupledView",
    "UploadView",
]
