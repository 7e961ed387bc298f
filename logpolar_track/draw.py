"""Drawing a tracked state on a copy of a frame: outline, a radius line that turns with the object, a readout.

Pure drawing: takes a frame and a :class:`~logpolar_track.trackers.base.TrackState`, returns a new annotated
BGR image and never modifies its input. Knows nothing about trackers, files or the CLI.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .images import check_frame, to_bgr
from .trackers.base import TrackState

#: BGR colours: green while tracked (and at init), red when lost.
TRACKED_COLOUR = (0, 220, 0)
LOST_COLOUR = (0, 0, 255)

_SHIFT = 4  # fractional bits for sub-pixel drawing (cv2 ``shift``): coordinates are multiplied by 16
_LIMIT = 1 << 26  # keep fixed-point coordinates far from int32 overflow when a state wanders off-frame


def _fixed(value: float) -> int:
    """Pixel coordinate -> OpenCV fixed-point integer with :data:`_SHIFT` fractional bits."""
    scaled = value * (1 << _SHIFT)
    if not math.isfinite(scaled):
        return 0
    return int(round(min(max(scaled, -_LIMIT), _LIMIT)))


def readout_text(state: TrackState, *, frame_index: int | None = None, status: str = "tracked") -> str:
    """The one-line readout drawn on a frame: frame, scale, rotation (deg CCW), score, and LOST if lost."""
    parts = [] if frame_index is None else [f"frame {frame_index}"]
    parts.append(f"scale {state.scale:.3f}")
    if state.rotation_deg is not None:
        parts.append(f"rot {state.rotation_deg:+.1f} deg")
    parts.append(f"score {state.score:.2f}")
    if status == "lost":
        parts.append("LOST")
    return "  ".join(parts)


def draw_state(frame: np.ndarray, state: TrackState, *, frame_index: int | None = None,
               status: str = "tracked", colour: tuple[int, int, int] = TRACKED_COLOUR,
               lost_colour: tuple[int, int, int] = LOST_COLOUR, thickness: int | None = None,
               text: bool = True, in_place: bool = False) -> np.ndarray:
    """An annotated copy of ``frame`` showing ``state`` (or ``frame`` itself, annotated, if ``in_place``).

    Draws the ellipse outline, a line from the centre to the end of axis ``a`` (it turns with the object,
    so rotation is visible) and, if ``text``, a readout of frame, scale, rotation and score in the top-left
    corner. Lost frames use ``lost_colour``.

    Parameters
    ----------
    frame : ndarray
        BGR (H, W, 3), grey or BGRA image, uint8 or float32 from 0 to 255 (as a tracker takes it); not modified
        unless ``in_place`` (and it is BGR uint8).
    state : TrackState
        Ellipse in pixels (x right, y down), angle in degrees counter-clockwise on screen.
    frame_index : int, optional
        Shown in the readout.
    status : str
        ``init``, ``tracked`` or ``lost``.
    colour, lost_colour : tuple of int
        BGR colours for tracked/init and lost frames.
    thickness : int, optional
        Line thickness in pixels; default scales with the frame size (1 px up to ~500 px frames).
    text : bool
        Draw the readout.
    in_place : bool
        Draw on a BGR ``frame`` itself instead of a copy (a video writer's loop saves one frame of memory,
        which matters at 4K).

    Returns
    -------
    ndarray
        BGR uint8 image of the same height and width: new, or ``frame`` if drawn in place.

    Notes
    -----
    OpenCV's ``ellipse`` angle is measured clockwise on screen (y down), lptrack's counter-clockwise, hence
    the negated angle.
    """
    check_frame(frame)
    bgr = to_bgr(frame)
    out = bgr if bgr is not frame or in_place else frame.copy()
    height, width = out.shape[:2]
    size = min(height, width)
    line = thickness if thickness is not None else max(1, int(round(size / 480)))
    col = tuple(int(c) for c in (lost_colour if status == "lost" else colour))
    e = state.ellipse
    centre = (_fixed(e.cx), _fixed(e.cy))
    axes = (_fixed(max(e.a, 0.0)), _fixed(max(e.b, 0.0)))
    cv2.ellipse(out, centre, axes, -e.angle_deg, 0.0, 360.0, col, line, cv2.LINE_AA, _SHIFT)
    tip = e.axis_end()
    cv2.line(out, centre, (_fixed(tip[0]), _fixed(tip[1])), col, line, cv2.LINE_AA, _SHIFT)
    cv2.circle(out, centre, _fixed(max(1.5, line)), col, -1, cv2.LINE_AA, _SHIFT)
    if text:
        _draw_readout(out, readout_text(state, frame_index=frame_index, status=status), col, size)
    return out


def _draw_readout(image: np.ndarray, label: str, colour, size: int) -> None:
    """Label in the top-left corner on a dark strip, legible on any background."""
    font = cv2.FONT_HERSHEY_SIMPLEX
    font_scale = max(0.3, size / 960)
    weight = max(1, int(round(size / 480)))
    (tw, th), base = cv2.getTextSize(label, font, font_scale, weight)
    pad = max(2, int(round(th / 3)))
    x0, y0 = 0, 0
    x1, y1 = min(image.shape[1], tw + 2 * pad), min(image.shape[0], th + base + 2 * pad)
    # Darken rather than paint black so the frame under the strip stays faintly visible.
    image[y0:y1, x0:x1] = (image[y0:y1, x0:x1] * 0.35).astype(np.uint8)
    cv2.putText(image, label, (pad, pad + th), font, font_scale, colour, weight, cv2.LINE_AA)
