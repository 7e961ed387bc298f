"""Frames as trackers take them: what an image must be (:func:`check_frame`), its layout, and the conversions
every part of lptrack shares (to grey for the trackers, to BGR for drawing and OpenCV's trackers).

A frame is ``(H, W)`` or ``(H, W, 1)`` grey, ``(H, W, 3)`` BGR or ``(H, W, 4)`` BGRA, uint8 as OpenCV decodes it,
or float32 with values from 0 to 255.
"""

from __future__ import annotations

import cv2
import numpy as np

from .errors import UsageError


def to_gray(frame: np.ndarray, dtype=np.float32) -> np.ndarray:
    """A grey (``(H, W)`` or ``(H, W, 1)``), BGR or BGRA frame (uint8, or float32 from 0 to 255) as a grey image
    (0 to 255) of ``dtype``; the input is not modified. A float frame's values are first taken within 0 to 255,
    channel by channel (:func:`within_0_255`).

    ``dtype=np.uint8`` keeps OpenCV's grey conversion as it is (a quarter of the memory of float32, which
    matters at 4K). A crop (a strided view) is copied first: converting strided rows of a frame that is not in
    cache is 1.5x slower than copying them and converting the copy.
    """
    if frame.ndim == 3 and frame.shape[2] == 1:
        frame = frame[:, :, 0]
    given = frame
    if frame.dtype != np.uint8:
        frame = within_0_255(frame)
    if frame.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if frame.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        return cv2.cvtColor(np.ascontiguousarray(frame), code).astype(dtype, copy=False)
    return frame.astype(dtype, copy=frame is given)


def to_bgr(frame: np.ndarray) -> np.ndarray:
    """A grey, BGR or BGRA frame (uint8, or float32 from 0 to 255) as a 3-channel uint8 BGR image: grey expanded,
    alpha dropped, a float frame's values rounded within 0 to 255. The frame itself if it is one already; otherwise
    a new array (the input is not modified)."""
    if frame.dtype != np.uint8:
        frame = np.rint(within_0_255(frame)).astype(np.uint8)
    if frame.ndim == 3 and frame.shape[2] == 1:
        frame = frame[:, :, 0]
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return frame


def within_0_255(frame: np.ndarray) -> np.ndarray:
    """A float frame (any channels) with every value in 0 to 255: beyond it clipped, NaN 0, infinities 0 or 255
    (a computation gone wrong upstream; NaN reached lpcf's features as a garbage bin index). A new array."""
    return np.clip(np.nan_to_num(frame, nan=0.0, posinf=255.0, neginf=0.0), 0.0, 255.0)


_CHANNEL_NAMES = {1: "grey", 3: "BGR", 4: "BGRA"}


def frame_layout(frame: np.ndarray) -> tuple[int, np.dtype]:
    """``(channels, dtype)`` of an image: 1 for ``(H, W)`` and ``(H, W, 1)`` grey, 3 for BGR, 4 for BGRA."""
    return (frame.shape[2] if frame.ndim == 3 else 1), frame.dtype


def check_frame(frame: np.ndarray, size: tuple[int, int] | None = None,
                layout: tuple[int, np.dtype] | None = None) -> None:
    """Raise :class:`UsageError` unless ``frame`` is an image a tracker takes, of ``size`` ``(width, height)``
    (pixels) and :func:`frame_layout` ``layout`` if given: what every tracker's ``update`` needs (a frame of
    another size mid-stream would be tracked in the wrong place, and one of other channels or element type
    against models built from colour or from the first frame's range).

    An image is ``(H, W)`` or ``(H, W, 1)`` grey, ``(H, W, 3)`` BGR or ``(H, W, 4)`` BGRA, not empty, of uint8 (as
    ``cv2.VideoCapture`` and ``cv2.imread`` give) or float32 with values from 0 to 255. Other element types are
    refused rather than guessed at: a float image from 0 to 1 (scikit-image's convention) would track on a
    different scale of contrast, and OpenCV's trackers take neither float64 nor 16-bit images.
    """
    if frame.ndim not in (2, 3) or (frame.ndim == 3 and frame.shape[2] not in (1, 3, 4)) or frame.size == 0:
        raise UsageError(f"a frame must be an (H, W) grey or (H, W, 3) colour image (or 1 or 4 channels), got "
                         f"shape {frame.shape}")
    if frame.dtype != np.uint8 and frame.dtype != np.float32:
        if np.issubdtype(frame.dtype, np.floating):
            how = "frame.astype(np.float32) for values 0 to 255, (frame * 255).clip(0, 255).astype(np.uint8) for 0 to 1"
        elif frame.dtype == np.uint16:
            how = ("(frame >> 8).astype(np.uint8) (one scale for every frame of a video: cv2.normalize's NORM_MINMAX "
                   "would rescale each frame on its own)")
        else:
            how = "one scale for the whole video into 0 to 255, then .astype(np.uint8)"
        raise UsageError(f"a frame must be uint8 (or float32 with values 0 to 255), got {frame.dtype}; convert it "
                         f"first, e.g. {how}")
    if size is not None and (frame.shape[1], frame.shape[0]) != size:
        raise UsageError(f"every frame must have the size of the first ({size[0]}x{size[1]} pixels), got "
                         f"{frame.shape[1]}x{frame.shape[0]}")
    if layout is not None and frame_layout(frame) != layout:
        raise UsageError(f"every frame must be laid out as the first ({_layout_name(*layout)}), got "
                         f"{_layout_name(*frame_layout(frame))}; convert the frames alike")


def _layout_name(channels: int, dtype) -> str:
    return f"{_CHANNEL_NAMES[channels]} {np.dtype(dtype).name}"
