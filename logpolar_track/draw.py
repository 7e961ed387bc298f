"""Drawing on a copy of a frame: a tracked state (outline, a radius line that turns with the object, a readout),
a labelled pixel grid, a candidate ROI.

Pure drawing: :func:`draw_state` takes a frame and a :class:`~logpolar_track.trackers.base.TrackState`,
:func:`draw_grid` a frame (grid lines and their coordinates, so ``cx,cy,r`` can be read off in any image viewer),
:func:`draw_roi` a frame and a ROI (as ``lptrack run`` draws a state); each returns a new annotated BGR image and
never modifies its input (:func:`put_label` writes a label on the image it is given). Knows nothing about trackers,
files or the CLI. Pixels with the origin at the top-left corner, x right, y down; angles in degrees
counter-clockwise as seen on screen.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .errors import UsageError
from .geometry import Ellipse, as_ellipse
from .images import check_frame, to_bgr
from .trackers.base import TrackState

#: BGR colours: green while tracked (and at init), red when lost.
TRACKED_COLOUR = (0, 220, 0)
LOST_COLOUR = (0, 0, 255)
#: BGR colour of the grid lines drawn by :func:`draw_grid` (cyan: rare in natural images, legible on both
#: dark and light backgrounds).
GRID_COLOUR = (255, 255, 0)
#: BGR colour of a candidate ROI drawn by :func:`draw_roi` (magenta, unlike the green/red of a run).
ROI_COLOUR = (255, 0, 255)
#: Font of every text drawn on a frame.
LABEL_FONT = cv2.FONT_HERSHEY_SIMPLEX

_SHIFT = 4  # fractional bits for sub-pixel drawing (cv2 ``shift``): coordinates are multiplied by 16
_LIMIT = 1 << 26  # keep fixed-point coordinates far from int32 overflow when a state wanders off-frame


def _fixed(value: float) -> int:
    """Pixel coordinate -> OpenCV fixed-point integer with :data:`_SHIFT` fractional bits."""
    scaled = value * (1 << _SHIFT)
    if not math.isfinite(scaled):
        return 0
    return int(round(min(max(scaled, -_LIMIT), _LIMIT)))


def signed(value: float, decimals: int) -> str:
    """``value`` with a sign and fixed ``decimals``; a value that rounds to zero is ``+0``, never ``-0``."""
    return f"{round(value, decimals) + 0.0:+.{decimals}f}"


def readout_text(state: TrackState, *, frame_index: int | None = None, status: str = "tracked") -> str:
    """The one-line readout drawn on a frame: frame, scale, rotation (deg CCW), score, and LOST if lost."""
    parts = [] if frame_index is None else [f"frame {frame_index}"]
    parts.append(f"scale {state.scale:.3f}")
    if state.rotation_deg is not None:
        parts.append(f"rot {signed(state.rotation_deg, 1)} deg")
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
    font = LABEL_FONT
    font_scale = max(0.3, size / 960)
    weight = max(1, int(round(size / 480)))
    (tw, th), base = cv2.getTextSize(label, font, font_scale, weight)
    pad = max(2, int(round(th / 3)))
    x0, y0 = 0, 0
    x1, y1 = min(image.shape[1], tw + 2 * pad), min(image.shape[0], th + base + 2 * pad)
    # Darken rather than paint black so the frame under the strip stays faintly visible.
    image[y0:y1, x0:x1] = (image[y0:y1, x0:x1] * 0.35).astype(np.uint8)
    cv2.putText(image, label, (pad, pad + th), font, font_scale, colour, weight, cv2.LINE_AA)


def put_label(image: np.ndarray, text: str, org: tuple[int, int], colour, *, scale: float = 0.4,
              anchor: str = "tl", pad: int = 2) -> tuple[int, int, int, int]:
    """Write ``text`` on ``image`` itself, on a darkened box kept within the image; ``org`` is the box's corner
    named by ``anchor`` (t/b + l/r), in pixels. Returns the box ``(x, y, w, h)``."""
    (tw, th), base = cv2.getTextSize(text, LABEL_FONT, scale, 1)
    w, h = tw + 2 * pad, th + base + 2 * pad
    x = org[0] - (w if "r" in anchor else 0)
    y = org[1] - (h if "b" in anchor else 0)
    x = int(min(max(x, 0), max(image.shape[1] - w, 0)))
    y = int(min(max(y, 0), max(image.shape[0] - h, 0)))
    roi = image[y:y + h, x:x + w]
    # Darken rather than paint black so what lies under the label stays faintly visible.
    roi[:] = (roi * 0.25).astype(np.uint8)
    cv2.putText(image, text, (x + pad, y + pad + th), LABEL_FONT, scale, colour, 1, cv2.LINE_AA)
    return x, y, w, h


def draw_grid(image: np.ndarray, spacing: int = 50, *, colour=GRID_COLOUR, caption: str | None = None) -> np.ndarray:
    """A copy of ``image`` with pixel grid lines every ``spacing`` px, their coordinates, and the frame size.

    Parameters
    ----------
    image : ndarray
        BGR, grey or BGRA, uint8 or float32 from 0 to 255 (a frame as a tracker takes it); not modified.
    spacing : int
        Grid step in pixels; lines at x = spacing, 2*spacing, ... and likewise y. 0 draws no lines (the size
        caption still appears).
    colour : tuple of int
        BGR colour of the lines and labels.
    caption : str, optional
        Text for the bottom-right corner; default ``"<width>x<height> px"``.

    Returns
    -------
    ndarray
        BGR uint8 image of the same size: pixel (x, y) of the result is pixel (x, y) of the frame, so a
        viewer's cursor position reads video coordinates directly.

    Notes
    -----
    Each line is one pixel wide, exactly on column ``x`` (row ``y``). The x coordinates are written along
    the top edge just right of their line, the y coordinates along the left edge just below theirs; when the
    lines are closer than a label is wide, only every k-th line is labelled (always the multiples of the
    same k, so labels stay on round numbers).
    """
    image = np.asarray(image)
    check_frame(image)
    out = to_bgr(image)
    out = out.copy() if out is image else out
    height, width = out.shape[:2]
    spacing = int(spacing)
    if spacing < 0:
        raise UsageError(f"grid spacing must be >= 0 pixels, got {spacing}")
    colour = tuple(int(c) for c in colour)
    if spacing:
        xs = np.arange(spacing, width, spacing)
        ys = np.arange(spacing, height, spacing)
        out[:, xs] = colour
        out[ys, :] = colour
        (label_w, label_h), base = cv2.getTextSize(str(max(width, height)), LABEL_FONT, 0.4, 1)
        every = max(1, math.ceil((label_w + 8) / spacing))
        every_y = max(1, math.ceil((label_h + base + 6) / spacing))
        for x in xs:
            if (x // spacing) % every == 0:
                put_label(out, str(int(x)), (int(x) + 2, 0), colour)
        for y in ys:
            if (y // spacing) % every_y == 0:
                put_label(out, str(int(y)), (0, int(y) + 2), colour)
    size_text = f"{width}x{height} px"
    text, scale = caption or size_text, 0.4
    # On a small frame shrink the caption, then fall back to the size alone, rather than cut it off.
    while cv2.getTextSize(text, LABEL_FONT, scale, 1)[0][0] + 4 > width:
        if scale > 0.3:
            scale = 0.3
        elif text != size_text:
            text, scale = size_text, 0.4
        else:
            break
    put_label(out, text, (width, height), colour, scale=scale, anchor="br")
    return out


def draw_roi(image: np.ndarray, roi: Ellipse, *, colour=ROI_COLOUR, label: bool = True) -> np.ndarray:
    """A copy of ``image`` with ``roi`` drawn as ``lptrack run`` draws a state: outline, centre, axis-a line.

    ``roi`` is an :class:`~logpolar_track.geometry.Ellipse`, a ``--roi`` string or its numbers; ``image`` a frame as
    :func:`draw_grid` takes it. The ROI's ``--roi`` spec is written next to it when ``label`` is true.
    """
    roi = as_ellipse(roi)
    state = TrackState(roi, 1.0, 0.0, 1.0)
    out = draw_state(image, state, colour=colour, text=False)
    if label:
        x0, y0, w, h = roi.bounding_box()
        put_label(out, f"ROI {roi.to_spec()}", (int(round(x0)), int(round(y0 + h)) + 3), colour)
    return out
