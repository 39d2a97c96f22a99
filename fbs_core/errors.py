"""Domain exceptions of :mod:`fbs_core`.

Every exception subclasses the built-in it refines, so ``except ValueError`` (or
``KeyError``, ``numpy.linalg.LinAlgError``) in user code keeps working, in the
manner of python-control's ``control/exception.py``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "FBSError",
    "DOFError",
    "FrequencyGridError",
    "QuantityError",
    "SingularInterfaceError",
    "DataFormatError",
    "HarmonicError",
    "CouplingOptionError",
    "OperatingPointError",
    "ModeCountError",
    "ModalError",
    "CampaignError",
    "ClusterUnavailable",
    "InsecureScheduler",
    "ForeignDataError",
    "ParameterError",
    "GeometryError",
    "StudyCancelled",
]


class FBSError(ValueError):
    """Base class of all errors raised by ``fbs_core`` for bad input."""


class DOFError(FBSError, KeyError):
    """An unknown, duplicated or malformed DOF label."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class FrequencyGridError(FBSError):
    """Frequency grids that are invalid or do not match."""


class QuantityError(FBSError):
    """An unknown FRF quantity or an impossible conversion between quantities."""


class SingularInterfaceError(FBSError, np.linalg.LinAlgError):
    """The interface matrix to be inverted is singular or too ill-conditioned."""


class DataFormatError(FBSError):
    """A file or array that is not what it claims to be."""


class HarmonicError(FBSError):
    """An unknown harmonic excitation case."""


class CouplingOptionError(FBSError):
    """An unknown coupling option."""


class OperatingPointError(FBSError):
    """A speed outside the operating points of the modal model."""


class ModeCountError(FBSError):
    """A number of retained modes that is not an even count in the allowed range."""


class ModalError(FBSError):
    """A modal problem that violates the assumptions (e.g. overdamped modes)."""


class CampaignError(FBSError):
    """A campaign file or result file that cannot be used (bad key, value or mismatch)."""


class ClusterUnavailable(CampaignError):
    """A Dask cluster cannot compute a study now (no workers, scheduler gone, block lost).

    Raised by :func:`fbs_core.campaign.cluster.scatter_band_on`; the caller computes the
    study in its own process instead.
    """


class InsecureScheduler(CampaignError):
    """A scheduler address this package does not join (plain TCP off the loopback, or TLS
    without certificates); raised by :mod:`fbs_core.campaign.security`."""


class ForeignDataError(DataFormatError):
    """An HDF5 file that links to, or maps data from, outside itself
    (:mod:`fbs_core.hdf5_guard`)."""


class ParameterError(FBSError):
    """An unknown model parameter, a bad range or an unphysical value (fbs_core.variants)."""


class GeometryError(FBSError):
    """Positions or directions of measured channels that are missing, not unit vectors, or
    that cannot observe the six DOFs of a virtual point (fbs_core.vpt)."""


class StudyCancelled(Exception):  # noqa: N818  (a signal, not an error of the input)
    """A long study stopped because its ``cancel`` callable returned True.

    Not an :class:`FBSError`: nothing was wrong with the input; the caller asked to stop
    (for example a dashboard session whose settings changed while the study ran).
    """
