"""lptrack: follow a circle or ellipse through a video with log-polar phase correlation.

Public names: the ROI type and parser, the tracker interface and registry, :func:`track_video` (results per
frame) and :func:`run_video` (what ``lptrack run`` does: annotated video and CSV).
"""

import importlib

from .errors import (FrameRangeError, GroundTruthError, InputError, LptrackError, NotStartedError, OutputError,
                     RoiError, UsageError, VideoError)

#: Public names imported on first use (PEP 562): ``import logpolar_track`` (and so the ``lptrack`` script, see
#: :mod:`logpolar_track.__main__`) does not wait for NumPy and OpenCV, and a Ctrl-C during those imports can be
#: handled.
_LAZY = {"Ellipse": "geometry", "parse_roi": "geometry", "Tracker": "trackers", "TrackState": "trackers",
         "create_tracker": "trackers", "tracker_names": "trackers", "track_video": "pipeline",
         "run_video": "pipeline"}

__all__ = ["Ellipse", "parse_roi", "Tracker", "TrackState", "create_tracker", "tracker_names", "track_video",
           "run_video", "LptrackError", "RoiError", "VideoError", "InputError", "OutputError", "UsageError",
           "NotStartedError", "FrameRangeError", "GroundTruthError", "__version__"]


def __getattr__(name: str):
    if name == "__version__":
        # Looked up on first use too: importlib.metadata takes 30 ms to import, before the script can catch Ctrl-C.
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("logpolar-track")
        except PackageNotFoundError:  # running from a source tree that was not installed
            value = "0+unknown"
        globals()[name] = value
        return value
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
