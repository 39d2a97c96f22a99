"""How each result of a session is made: pure functions of one :class:`Snapshot`.

:mod:`app.store` declares the results (which snapshot fields each depends on, when it is
computed) and publishes them; the functions here make them: :mod:`~app.results.main` (the
main views), :mod:`~app.results.analysis` (the Analysis card), :mod:`~app.results.pins`
(pins and the comparison), :mod:`~app.results.campaign` (a campaign file's cases, made of
the opened file rather than of a snapshot). Each returns a :class:`Result`: the data and
their description (CSV header, file name, caption) from the same snapshot.
"""

from .base import (
    FIELDS,
    Band,
    BandStatus,
    Result,
    Snapshot,
    csv_name,
    duration_text,
    progress_status,
)

__all__ = [
    "FIELDS",
    "Band",
    "BandStatus",
    "Result",
    "Snapshot",
    "csv_name",
    "duration_text",
    "progress_status",
]
