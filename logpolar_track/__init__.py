"""lptrack: follow a circle or ellipse through a video with log-polar phase correlation.

Public names: the ROI type and parser, the tracker interface and registry, and :func:`track_video`.
"""

from importlib.metadata import PackageNotFoundError, version

from .errors import LptrackError, OutputError, RoiError, UsageError, VideoError
from .geometry import Ellipse, parse_roi
from .trackers import Tracker, TrackState, create_tracker, tracker_names

try:
    __version__ = version("logpolar-track")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0+unknown"

__all__ = ["Ellipse", "parse_roi", "Tracker", "TrackState", "create_tracker", "tracker_names",
           "LptrackError", "RoiError", "VideoError", "OutputError", "UsageError", "__version__"]
