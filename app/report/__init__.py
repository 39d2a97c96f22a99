"""Reports of a dashboard state: title blocks, file names, a self-contained HTML file and a PDF.

Input is a plain :class:`ReportData` (settings, data provenance, the core's result objects, the
page URL, the date); everything here is a pure function of it and draws without a browser.
"""

from .colormap import ErrorColorScale, contour_columns, threshold_contour
from .content import plot_file, report_content
from .data import DataFile, Provenance, ReportData, ReportError
from .html import build_html
from .pdf import build_pdf
from .titles import TitleBlock, file_stem, harmonic_description, title_block

__all__ = [
    "DataFile",
    "ErrorColorScale",
    "Provenance",
    "ReportError",
    "ReportData",
    "TitleBlock",
    "build_html",
    "build_pdf",
    "contour_columns",
    "file_stem",
    "harmonic_description",
    "plot_file",
    "report_content",
    "threshold_contour",
    "title_block",
]
