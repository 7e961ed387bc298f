"""Exceptions raised by lptrack's library code.

The library raises; only :mod:`logpolar_track.cli` turns these into one line on stderr and an exit code.
Messages say what was expected, what was received and how to fix it. Where the fix is an option they name the
CLI's (``--overwrite``): each is the keyword argument of that name in Python (``overwrite=True``), so one message
serves both. The CLI is what most users meet; a second wording of every message would drift from the first.
:func:`is_real` and :func:`is_whole` are the tests of a number that the checks raising them share.
"""

import numbers


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 (``"1 frame"``, ``"20 frames"``), for messages."""
    return f"{n} {noun}" + ("" if n == 1 else "s")


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number for a check: a Python or NumPy int or float, not a bool (which Python
    counts as an int: ``True`` would pass as 1), a text, an array or None."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def is_whole(value: object) -> bool:
    """Whether ``value`` is a whole number for a check: a Python or NumPy int, not a bool, nor a float such as 1.5
    or 2.0 (frame numbers and counts; where a whole float is fine, test ``float.is_integer`` too)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


class LptrackError(Exception):
    """Base class of every error lptrack raises on purpose."""

    #: Exit code the CLI uses for this kind of error (1: runtime failure, 2: bad usage).
    exit_code = 1


class RoiError(LptrackError, ValueError):
    """A ROI specification is malformed or does not fit the frame."""

    exit_code = 2


class VideoError(LptrackError):
    """A video cannot be opened or read (missing, not a video, empty)."""

    exit_code = 1


class InputError(LptrackError):
    """An input file or folder other than a video (a dataset, a ground-truth file) is missing."""

    exit_code = 1


class OutputError(LptrackError):
    """An output cannot be written (folder missing or unwritable, file exists)."""

    exit_code = 1


class UsageError(LptrackError, ValueError):
    """An argument has a value lptrack does not accept (unknown tracker, bad option value)."""

    exit_code = 2


class NotStartedError(UsageError, RuntimeError):
    """A tracker was asked to update before it was started (``update`` before ``init``)."""

    exit_code = 2


class GroundTruthError(LptrackError):
    """A ground-truth file or a run's CSV cannot be read as such (missing, wrong columns, not numbers, off the
    CSV contract)."""

    exit_code = 1


class FrameRangeError(VideoError, UsageError):
    """A frame index or time given as an argument lies outside the video (bad usage for this video)."""

    exit_code = 2
