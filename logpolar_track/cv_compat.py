"""What differs between the OpenCV releases lptrack supports (opencv-python-headless 4.8 to 5.x)."""

from __future__ import annotations

import cv2

# cv::utils::logging::LogLevel: the same numbers in 4.x and 5.x (SILENT 0, FATAL 1, ERROR 2, WARNING 3, ...).
LOG_LEVEL_ERROR = 2


def set_log_level(level: int) -> None:
    """OpenCV's own log level: ``cv2.utils.logging`` in 5.x, ``cv2.setLogLevel`` in 4.x (which has no module)."""
    logging = getattr(cv2.utils, "logging", None)
    if logging is not None:
        logging.setLogLevel(level)
    else:
        cv2.setLogLevel(level)


def get_log_level() -> int:
    logging = getattr(cv2.utils, "logging", None)
    return int(logging.getLogLevel() if logging is not None else cv2.getLogLevel())
