"""lptrack: follow a circle or ellipse through a video with log-polar phase correlation.

Public names: the ROI type and parser, the tracker interface and registry, :func:`track_video` (results per
frame) and :func:`run_video` (what ``lptrack run`` does: annotated video and CSV).
"""

from importlib.metadata import PackageNotFoundError, version

from .errors import LptrackError, OutputError, RoiError, UsageError, VideoError
from .geometry import Ellipse, parse_roi
from .trackers import Tracker, TrackState, create_tracker, tracker_names
from .pipeline import run_video, track_video

try:
    __version__ = version("logpolar-track")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0+unknown"

__all__ = ["Ellipse", "parse_roi", "Tracker", "TrackState", "create_tracker", "tracker_names", "track_video",
           "run_video", "LptrackError", "RoiError", "VideoError", "OutputError", "UsageError", "__version__"]
