"""Deprecated: the names of 0.x's ``logpolar_track.look``, whose jobs now live each in its own module.

Kept so that code written against it still imports; it warns once (``DeprecationWarning``) and will go. Import from
the modules instead: :mod:`logpolar_track.video` (``Frame``, ``read_frame``, ``count_frames``),
:mod:`logpolar_track.draw` (``draw_grid``, ``draw_roi``), :mod:`logpolar_track.outputs` (``write_png``,
``check_image_suffix``), :mod:`logpolar_track.frame_png`, :mod:`logpolar_track.roi_fit`, :mod:`logpolar_track.plot`,
:mod:`logpolar_track.contact_sheet`, :mod:`logpolar_track.pipeline` (``find_video_for_csv``,
``describe_video_search``) and :mod:`logpolar_track.evaluate` (``read_run_csv``, ``RunTable``).
"""

import warnings

from .contact_sheet import SHEET_ROWS, sheet_geometry, sheet_indices, write_contact_sheet  # noqa: F401
from .draw import GRID_COLOUR, ROI_COLOUR, draw_grid, draw_roi  # noqa: F401
from .evaluate import RunTable, read_run_csv  # noqa: F401
from .frame_png import default_frame_png, write_frame_png  # noqa: F401
from .outputs import check_image_suffix, write_png  # noqa: F401
from .pipeline import describe_video_search, find_video_for_csv  # noqa: F401
from .plot import PLOT_DPI, PLOT_HINT, PLOT_SIZE_IN, PLOT_SUFFIXES, matplotlib_hint, plot_track  # noqa: F401
from .roi_fit import BOX_SYNTAX, POINTS_SYNTAX, ROUND_TOLERANCE, roi_from_box, roi_from_points  # noqa: F401
from .video import Frame, count_frames, read_frame  # noqa: F401

warnings.warn("logpolar_track.look is deprecated: its names live in logpolar_track.video, .draw, .outputs, "
              ".frame_png, .roi_fit, .plot, .contact_sheet, .pipeline and .evaluate (see its docstring)",
              DeprecationWarning, stacklevel=2)
