"""lptrack's trackers and the registry that names them.

Importing this package registers every tracker; :func:`create_tracker` builds one by name.
"""

from .base import (Similarity, SimilarityTracker, Tracker, TrackState, create_tracker, register, tracker_class,
                   tracker_names)
from . import thesis  # noqa: F401  (registers fixed, diffdecomp, update, occlusion)
from . import spatial  # noqa: F401  (registers spatial)
from . import lpcf  # noqa: F401  (registers lpcf, experimental)
from . import opencv  # noqa: F401  (registers the OpenCV peers cv-mil, cv-kcf, cv-csrt)

#: The tracker ``lptrack run`` uses when none is named.
DEFAULT_TRACKER = "fixed"

__all__ = ["DEFAULT_TRACKER", "Tracker", "TrackState", "Similarity", "SimilarityTracker", "create_tracker", "register",
           "tracker_class", "tracker_names"]
