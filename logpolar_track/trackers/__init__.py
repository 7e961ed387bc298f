"""lptrack's trackers and the registry that names them.

Importing this package registers every tracker; :func:`create_tracker` builds one by name.
"""

from .base import (Similarity, SimilarityTracker, Tracker, TrackState, create_tracker, register, tracker_class,
                   tracker_names, tracker_parameters, tracker_params_from_text)
from . import thesis  # noqa: F401  (registers fixed, diffdecomp, update, occlusion)
from . import spatial  # noqa: F401  (registers spatial)
from . import lpcf  # noqa: F401  (registers lpcf, the default, and lpcf-masked)
from . import opencv  # noqa: F401  (registers the OpenCV peers cv-mil, cv-kcf, cv-csrt)

#: The tracker ``lptrack run`` uses when none is named: the best measured on sample_videos/ (mean IoU AUC 0.952 against
#: 0.819 for the best thesis tracker) and on the real sequences (0.527 against 0.327 for the best thesis tracker,
#: spatial; CSRT 0.402).
DEFAULT_TRACKER = "lpcf"

__all__ = ["DEFAULT_TRACKER", "Tracker", "TrackState", "Similarity", "SimilarityTracker", "create_tracker", "register",
           "tracker_class", "tracker_names", "tracker_parameters", "tracker_params_from_text"]
