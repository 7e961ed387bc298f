"""lptrack's trackers and the registry that names them.

Importing this package registers every tracker; :func:`create_tracker` builds one by name.
"""

from .base import (Similarity, SimilarityTracker, Tracker, TrackState, create_tracker, register, tracker_class,
                   tracker_names)
from . import thesis  # noqa: F401  (registers fixed, diffdecomp, update, occlusion)
from . import spatial  # noqa: F401  (registers spatial)

__all__ = ["Tracker", "TrackState", "Similarity", "SimilarityTracker", "create_tracker", "register",
           "tracker_class", "tracker_names"]
