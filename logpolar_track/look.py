"""Looking at a video before a run and at a track after it, without a GUI.

Before a run (headless OpenCV has no ``selectROI``), the user needs the pixel coordinates of the object:

* :func:`read_frame` -- exactly the N-th decoded frame of a video (or the frame at a time);
* :func:`draw_grid` -- a labelled pixel grid and the frame size, so ``cx,cy,r`` can be read off in any image
  viewer (the picture keeps the frame's own pixel size, so a viewer's cursor position *is* the video
  coordinate);
* :func:`draw_roi` -- a candidate ROI drawn on a frame (outline and axis line, as ``lptrack run`` draws it);
* :func:`roi_from_box` / :func:`roi_from_points` -- what image tools give (a box, points clicked on the
  outline) turned into a ROI in ``--roi`` syntax.

After a run:

* :func:`read_run_csv` -- a run CSV checked against the contract (:data:`~logpolar_track.results.COLUMNS`): the
  reader ``lptrack eval`` uses too (:func:`logpolar_track.evaluate.read_run_csv`, here by that name as well);
* :func:`plot_track` -- a matplotlib figure (optional extra ``plot``): centre path over the first frame,
  scale, rotation and score against time, and with ground truth its overlay and the errors;
* :func:`write_contact_sheet` -- a grid of evenly spaced annotated frames (pure OpenCV, one pass over the
  video).

Conventions are lptrack's: pixels with the origin at the top-left corner, x right, y down; angles in degrees
counter-clockwise as seen on screen. Library functions raise :class:`~logpolar_track.errors.LptrackError`
subclasses; they never print.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from .datasets import load_ground_truth
from .draw import LOST_COLOUR, TRACKED_COLOUR, draw_state
from .errors import FrameRangeError, OutputError, RoiError, UsageError, VideoError, counted, is_real
from .evaluate import RunTable, read_run_csv, rotation_errors, scale_errors, score_track
from .geometry import Ellipse, as_ellipse, check_roi_fits, ellipse_in_box, parse_numbers
from .images import check_frame, to_bgr
from .results import FrameResult
from .trackers.base import TrackState
from .outputs import check_output_path, written_into_place
from .video import VIDEO_EXTENSIONS, VideoReader, check_frame_number, guess_image_sequence, video_stem

#: BGR colour of the grid lines drawn by :func:`draw_grid` (cyan: rare in natural images, legible on both
#: dark and light backgrounds).
GRID_COLOUR = (255, 255, 0)
#: BGR colour of a candidate ROI drawn by :func:`draw_roi` (magenta, unlike the green/red of a run).
ROI_COLOUR = (255, 0, 255)
#: Default relative tolerance under which a fitted ellipse is reported as a circle: ``(a - b) / a``.
ROUND_TOLERANCE = 0.02
#: What :func:`roi_from_box` and :func:`roi_from_points` take as text, for messages.
BOX_SYNTAX = "x,y,w,h (top-left corner and size in pixels; ';' separates too)"
POINTS_SYNTAX = "x1,y1,x2,y2,... (pixels on the object's outline; 'x1,y1;x2,y2;...' too)"
#: Hint shown when matplotlib is missing.
PLOT_HINT = "pip install matplotlib"

_FONT = cv2.FONT_HERSHEY_SIMPLEX


# ----------------------------------------------------------------------------------------------------------
# Frames
# ----------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Frame:
    """One decoded frame and where it is in its video.

    Attributes
    ----------
    image : ndarray
        BGR uint8, shape (height, width, 3), as OpenCV decodes it.
    index : int
        Frame index in the file (0 = first frame).
    time_s : float
        Nominal time ``index / fps`` in seconds.
    fps : float
        Frame rate the container reports (25 if it reports none; then ``fps_guessed``).
    fps_guessed : bool
    path : Path
    """

    image: np.ndarray
    index: int
    time_s: float
    fps: float
    fps_guessed: bool
    path: Path

    @property
    def width(self) -> int:
        return int(self.image.shape[1])

    @property
    def height(self) -> int:
        return int(self.image.shape[0])


def count_frames(path) -> int:
    """Number of frames of ``path``, by decoding it completely (exact; container counts can be wrong). Frames that
    could not be decoded in a damaged stretch count, as they keep their numbers (:class:`VideoReader`)."""
    with VideoReader(path) as reader:
        last = -1
        for last, _, _ in reader:
            pass
        return last + 1


def read_frame(path, index: int | None = None, *, time_s: float | None = None, fps: float | None = None) -> Frame:
    """Exactly the ``index``-th decoded frame of a video (or the frame shown at ``time_s`` seconds).

    Parameters
    ----------
    path : str or Path
        Video file, or an image sequence's pattern (``frames/%04d.png``).
    index : int, optional
        Frame index, 0 = first frame of the file. Default 0.
    time_s : float, optional
        Instead of ``index``: time in seconds; the frame whose time, as a run's CSV gives it (``index / fps``, or
        a varying frame rate's timestamps), is nearest, or the last frame for a time within its time on screen.
    fps : float, optional
        Frames per second instead of the video's own (an image sequence has none), as ``lptrack run --fps``.

    Returns
    -------
    Frame

    Raises
    ------
    VideoError
        Missing or unreadable video.
    UsageError
        Negative index or time, both given, or a frame past the end (the message gives the valid range).

    Notes
    -----
    The frames before ``index`` are decoded and dropped (``VideoReader(start_frame=...)``), never skipped
    with ``CAP_PROP_POS_FRAMES``, whose seeking lands on a nearby key frame with some codecs: the result is
    the same pixels as reading the video from the start, at the cost of decoding ``index`` frames
    (~2,000 frames/s for 640x480 mp4v).
    """
    if index is not None and time_s is not None:
        raise UsageError("give a frame index or a time, not both")
    path = Path(path)
    if time_s is not None:
        if not (is_real(time_s) and math.isfinite(time_s) and time_s >= 0):
            raise UsageError(f"time must be a number of seconds >= 0, got {time_s!r}")
        return _frame_at_time(path, time_s, fps)
    index = 0 if index is None else index
    check_frame_number(index, "frame index")  # 1.5 was frame 1, '3' frame 3
    index = int(index)
    try:
        reader = VideoReader(path, start_frame=index, read_ahead=1, fps=fps)
    except VideoError:
        if index == 0:
            raise
        n = count_frames(path)  # raises the video's own error if it is unreadable
        if index < n:  # the video became unreadable half-way: say so rather than blame the index
            raise
        raise FrameRangeError(f"frame {index} lies past the end of '{path}', which has {counted(n, 'frame')}: "
                              f"give a frame from 0 to {n - 1}") from None
    with reader:
        _, time_s, image = next(iter(reader))  # its time as a run's CSV gives it (a varying rate's timestamp)
        return Frame(image.copy(), index, time_s, reader.fps, reader.fps_guessed, path)


def _frame_at_time(path: Path, time_s: float, fps: float | None) -> Frame:
    """The frame whose time (as a run's CSV gives it: ``index / fps``, or a varying rate's timestamp) is nearest
    ``time_s`` (of two as near, the later), or the last frame for a time within its time on screen."""
    with VideoReader(path, fps=fps) as reader:
        previous = None
        for index, time_i, image in reader:
            if time_i >= time_s:
                # Within a microsecond is a tie: 0.06 s at 25 fps is as near frame 1 (0.04) as frame 2 (0.08), but
                # 0.06 - 0.04 comes out below 0.08 - 0.06 in floating point, and the earlier frame was taken.
                if previous is not None and (time_i - time_s) - (time_s - previous[1]) > 1e-6:
                    index, time_i, image = previous
                return Frame(image.copy(), index, time_i, reader.fps, reader.fps_guessed, path)
            previous = index, time_i, image
        index, time_i, image = previous
        end = time_i + 1.0 / reader.fps  # the last frame shows until then
        if time_s < end:
            return Frame(image.copy(), index, time_i, reader.fps, reader.fps_guessed, path)
        n = index + 1
        raise FrameRangeError(f"time {time_s:g} s lies past the end of '{path}', which has {counted(n, 'frame')} "
                              f"(at {reader.fps:g} fps): give a time before {end:.3f} s or a frame from 0 to "
                              f"{n - 1}")


def _label(image: np.ndarray, text: str, org: tuple[int, int], colour, *, scale: float = 0.4,
           anchor: str = "tl", pad: int = 2) -> tuple[int, int, int, int]:
    """Text on a dark box; ``org`` is the box's corner named by ``anchor`` (t/b + l/r). Returns the box."""
    (tw, th), base = cv2.getTextSize(text, _FONT, scale, 1)
    w, h = tw + 2 * pad, th + base + 2 * pad
    x = org[0] - (w if "r" in anchor else 0)
    y = org[1] - (h if "b" in anchor else 0)
    x = int(min(max(x, 0), max(image.shape[1] - w, 0)))
    y = int(min(max(y, 0), max(image.shape[0] - h, 0)))
    roi = image[y:y + h, x:x + w]
    # Darken rather than paint black so what lies under the label stays faintly visible.
    roi[:] = (roi * 0.25).astype(np.uint8)
    cv2.putText(image, text, (x + pad, y + pad + th), _FONT, scale, colour, 1, cv2.LINE_AA)
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
        (label_w, label_h), base = cv2.getTextSize(str(max(width, height)), _FONT, 0.4, 1)
        every = max(1, math.ceil((label_w + 8) / spacing))
        every_y = max(1, math.ceil((label_h + base + 6) / spacing))
        for x in xs:
            if (x // spacing) % every == 0:
                _label(out, str(int(x)), (int(x) + 2, 0), colour)
        for y in ys:
            if (y // spacing) % every_y == 0:
                _label(out, str(int(y)), (0, int(y) + 2), colour)
    size_text = f"{width}x{height} px"
    text, scale = caption or size_text, 0.4
    # On a small frame shrink the caption, then fall back to the size alone, rather than cut it off.
    while cv2.getTextSize(text, _FONT, scale, 1)[0][0] + 4 > width:
        if scale > 0.3:
            scale = 0.3
        elif text != size_text:
            text, scale = size_text, 0.4
        else:
            break
    _label(out, text, (width, height), colour, scale=scale, anchor="br")
    return out


def draw_roi(image: np.ndarray, roi: Ellipse, *, colour=ROI_COLOUR, label: bool = True) -> np.ndarray:
    """A copy of ``image`` with ``roi`` drawn as ``lptrack run`` draws a state: outline, centre, axis-a line.

    ``roi`` is an :class:`Ellipse`, a ``--roi`` string or its numbers; ``image`` a frame as :func:`draw_grid` takes
    it. The ROI's ``--roi`` spec is written next to it when ``label`` is true.
    """
    roi = as_ellipse(roi)
    state = TrackState(roi, 1.0, 0.0, 1.0)
    out = draw_state(image, state, colour=colour, text=False)
    if label:
        x0, y0, w, h = roi.bounding_box()
        _label(out, f"ROI {roi.to_spec()}", (int(round(x0)), int(round(y0 + h)) + 3), colour)
    return out


#: File types ``lptrack plot`` writes (matplotlib picks the format from the name).
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def check_image_suffix(path, suffixes: tuple[str, ...], what: str) -> None:
    """Raise :class:`UsageError` unless ``path`` ends in one of ``suffixes`` (checked before any work)."""
    if Path(path).suffix.lower() not in suffixes:
        names = " or ".join(suffixes)
        raise UsageError(f"cannot write {what} '{path}': give a file name ending in {names}")


def write_png(path, image: np.ndarray, *, overwrite: bool = False, what: str = "output image") -> Path:
    """Write ``image`` as PNG atomically (temporary name in the same folder, then rename); return the path.

    Raises
    ------
    UsageError
        ``path`` does not end in .png.
    OutputError
        Folder missing or unwritable, file exists without ``overwrite``, or encoding failed.
    """
    check_image_suffix(path, (".png",), what)
    path = check_output_path(path, overwrite=overwrite, what=what)
    # Encoded in memory and written by Python: a full disk is then one OSError ("No space left on device"),
    # where cv2.imwrite let libpng print its own line first, and any name the file system takes will do.
    ok, encoded = cv2.imencode(".png", image)
    if not ok:
        raise OutputError(f"cannot write {what} '{path}': PNG encoding failed")
    with written_into_place(path, overwrite=overwrite, what=what) as temp:
        temp.write_bytes(encoded.tobytes())
    return path


def default_frame_png(video_path, index: int, folder=".", roi: Ellipse | None = None) -> Path:
    """Default output of ``lptrack frame``: ``<video stem>.frame<index>.png`` in ``folder``; with a candidate
    ``roi`` drawn, ``<video stem>.frame<index>.roi_<cx>_<cy>_<r>.png`` (its spec, commas as underscores), so that
    trying one ROI after another neither collides with the plain frame nor with the ROIs tried before."""
    tag = "" if roi is None else ".roi_" + roi.to_spec().replace(",", "_")
    return Path(folder) / f"{video_stem(video_path)}.frame{int(index)}{tag}.png"


def write_frame_png(video_path, out_png=None, *, index: int | None = None, time_s: float | None = None,
                    grid: int = 50, roi: Ellipse | None = None, overwrite: bool = False,
                    fps: float | None = None) -> Path:
    """What ``lptrack frame`` does: frame ``index`` (or at ``time_s``) with a grid and an optional ROI, as PNG.

    Parameters
    ----------
    video_path : str or Path
    out_png : str or Path, optional
        Default :func:`default_frame_png` in the current folder.
    index, time_s, fps
        See :func:`read_frame`.
    grid : int
        Grid step in pixels (0: none).
    roi : Ellipse, optional
        Candidate ROI to draw; checked against the frame as ``lptrack run`` checks it.
    overwrite : bool

    Returns
    -------
    Path
        The PNG written; same width and height as the frame.
    """
    frame = read_frame(video_path, index, time_s=time_s, fps=fps)
    out_png = default_frame_png(video_path, frame.index, roi=roi) if out_png is None else Path(out_png)
    check_image_suffix(out_png, (".png",), "output image")
    check_output_path(out_png, overwrite=overwrite, what="output image")
    image = frame.image
    if roi is not None:
        check_roi_fits(roi, frame.width, frame.height, source=f"'{frame.path.name}'")
    caption = f"{frame.width}x{frame.height} px  frame {frame.index}  t={frame.time_s:.3f} s"
    image = draw_grid(image, grid, caption=caption)
    if roi is not None:
        image = draw_roi(image, roi)
    return write_png(out_png, image, overwrite=overwrite)


# ----------------------------------------------------------------------------------------------------------
# ROI from what image tools give
# ----------------------------------------------------------------------------------------------------------

def _rounded(roi: Ellipse, tolerance: float) -> Ellipse:
    """``roi`` as a circle of equal area when its axes differ by at most ``tolerance`` (relative)."""
    if tolerance > 0 and roi.a - roi.b <= tolerance * roi.a:
        return Ellipse.circle(roi.cx, roi.cy, math.sqrt(roi.a * roi.b))
    return roi


def _normalised(cx: float, cy: float, a: float, b: float, angle_deg: float) -> Ellipse:
    """The same ellipse with ``a >= b`` and the angle in (-90, 90] (an axis has no direction)."""
    if b > a:
        a, b, angle_deg = b, a, angle_deg + 90.0
    angle = angle_deg % 180.0  # [0, 180): turning an axis by 180 degrees gives the same ellipse
    if angle > 90.0:
        angle -= 180.0
    if a == b:
        angle = 0.0
    return Ellipse(cx, cy, a, b, angle + 0.0)


def roi_from_box(box, *, round_tolerance: float = ROUND_TOLERANCE) -> Ellipse:
    """The ROI inscribed in an axis-aligned box ``x,y,w,h`` (top-left corner and size in pixels).

    Parameters
    ----------
    box : str or sequence of 4 numbers
        ``"x,y,w,h"`` as image tools and OTB ground truth give it (0-based pixels).
    round_tolerance : float
        A box whose sides differ by at most this fraction of the longer gives a circle ``cx,cy,r`` (r the
        radius of equal area); 0 always gives an ellipse.

    Raises
    ------
    RoiError
        Not 4 numbers (read as :func:`~logpolar_track.geometry.parse_numbers` reads them: plain decimals, no ``_``,
        ``nan`` or ``inf``), or a side <= 0.
    """
    # Semicolons separate too (x,y;w,h), as before there was one reader of number lists.
    values = (parse_numbers(box.replace(";", ","), "box", BOX_SYNTAX) if isinstance(box, str)
              else [float(v) for v in box])
    if len(values) != 4:
        raise RoiError(f"box '{box}' has {counted(len(values), 'number')}; expected {BOX_SYNTAX}")
    x, y, w, h = values
    if w <= 0 or h <= 0:
        raise RoiError(f"box '{box}': width and height must be > 0 pixels")
    e = ellipse_in_box(x, y, w, h)
    return _rounded(_normalised(e.cx, e.cy, e.a, e.b, e.angle_deg), round_tolerance)


def _circle_fit(points: np.ndarray) -> tuple[float, float, float]:
    """Least-squares circle through ``points`` (n >= 3, x/y pixels): algebraic fit of Kasa (1976)."""
    x, y = points[:, 0], points[:, 1]
    design = np.column_stack([x, y, np.ones_like(x)])
    rhs = x * x + y * y
    (p, q, c), *_ = np.linalg.lstsq(design, rhs, rcond=None)
    cx, cy = p / 2.0, q / 2.0
    return float(cx), float(cy), float(math.sqrt(max(c + cx * cx + cy * cy, 0.0)))


def _residual(e: Ellipse, points: np.ndarray) -> float:
    """Mean |(u/a)^2 + (v/b)^2 - 1| of ``points`` in the ellipse's own frame (0 on the outline)."""
    psi = math.radians(e.angle_deg)
    dx, dy = points[:, 0] - e.cx, -(points[:, 1] - e.cy)  # to a y-up frame: angles CCW on screen
    u = dx * math.cos(psi) + dy * math.sin(psi)
    v = -dx * math.sin(psi) + dy * math.cos(psi)
    return float(np.mean(np.abs((u / e.a) ** 2 + (v / e.b) ** 2 - 1.0)))


def roi_from_points(points, *, round_tolerance: float = ROUND_TOLERANCE) -> Ellipse:
    """The ROI fitted to points on the object's outline.

    Parameters
    ----------
    points : str or array-like
        ``"x1,y1,x2,y2,..."`` or an ``(n, 2)`` array of (x, y) pixels on the outline, spread around it (or an
        OpenCV contour, ``(n, 1, 2)``).
    round_tolerance : float
        Fits whose semi-axes differ by at most this fraction of the larger are reported as a circle
        (radius of equal area); 0 keeps the ellipse.

    Returns
    -------
    Ellipse
        ``a >= b``, angle of axis ``a`` in (-90, 90] degrees counter-clockwise on screen.

    Raises
    ------
    RoiError
        A text that is not a list of numbers (:func:`~logpolar_track.geometry.parse_numbers`), an odd count of
        numbers, an array of another shape, a point not finite, fewer than 3 distinct points, all
        points on a line, or no ellipse fits.

    Notes
    -----
    Points given more than once count once. 3 or 4 points determine a circle but not an ellipse (5 parameters):
    they give the least-squares circle through them (Kasa's algebraic fit). 5 or more give OpenCV's direct
    least-squares ellipse fit (``cv2.fitEllipseDirect``, Fitzgibbon, Pilu and Fisher, TPAMI 1999, which always
    returns an ellipse).
    OpenCV reports the rotated rectangle's angle in image coordinates (y down), i.e. clockwise on screen, and
    which side is "width" has changed between versions; the orientation is therefore taken from whichever
    reading of ``(w, h, angle)`` fits the points best, so it comes out counter-clockwise on screen whatever
    the version. Points covering only a short arc of the outline give an unreliable ellipse: spread them
    around the whole object.
    """
    if isinstance(points, str):
        values = parse_numbers(points.replace(";", ","), "points", POINTS_SYNTAX)  # 'x1,y1;x2,y2' too
        if len(values) % 2:
            raise RoiError(f"points give {len(values)} numbers; expected pairs x1,y1,x2,y2,... (pixels)")
        given = np.asarray(values, float).reshape(-1, 2)
    else:
        try:
            given = np.asarray(points, float)
        except (TypeError, ValueError):
            raise RoiError("points must be numbers: an (n, 2) array of (x, y) pixels") from None
        if given.ndim == 3 and given.shape[1] == 1:  # OpenCV's contours, (n, 1, 2)
            given = given[:, 0]
        if given.ndim != 2 or given.shape[1] != 2:
            # A (2, n) array (xs and ys) read as pairs gave a wrong ellipse without a word.
            raise RoiError(f"points must be an (n, 2) array of (x, y) pixels (or OpenCV's (n, 1, 2)), got shape "
                           f"{given.shape}")
        if not np.isfinite(given).all():
            raise RoiError("points must be finite numbers (pixels); some are NaN or infinite")
    # A point given twice adds nothing to the outline: 5 points of which 3 differ determine a circle, not the
    # arbitrary ellipse through 3 points that the ellipse fit returned.
    pts = np.unique(given, axis=0)
    n = len(pts)
    if n < 3:
        repeated = "" if n == len(given) else f" ({len(given)} given, some repeated)"
        raise RoiError(f"{counted(n, 'distinct point')}{repeated} cannot define an outline: give at least 3 "
                       f"points on it (3-4 fit a circle, 5 or more an ellipse)")
    centred = pts - pts.mean(axis=0)
    sv = np.linalg.svd(centred, compute_uv=False)
    if sv[1] <= 1e-6 * max(sv[0], 1e-12):
        raise RoiError("the points lie on a straight line; give points spread around the object's outline")
    if n < 5:
        cx, cy, r = _circle_fit(pts)
        return Ellipse.circle(cx, cy, r)
    (cx, cy), (w, h), theta = cv2.fitEllipseDirect(pts.astype(np.float32))
    if not all(math.isfinite(v) for v in (cx, cy, w, h, theta)) or min(w, h) <= 0:
        raise RoiError("no ellipse fits these points; give 5 or more points spread around the object's "
                       "outline")
    candidates = [Ellipse(cx, cy, sa / 2.0, sb / 2.0, sign * theta + extra)
                  for sa, sb, extra in ((w, h, 0.0), (h, w, 90.0)) for sign in (-1.0, 1.0)]
    best = min(candidates, key=lambda e: _residual(e, pts))
    return _rounded(_normalised(best.cx, best.cy, best.a, best.b, best.angle_deg), round_tolerance)


# ----------------------------------------------------------------------------------------------------------
# Run CSVs: read by evaluate.read_run_csv (here too as look.read_run_csv), the one reader eval uses as well
# ----------------------------------------------------------------------------------------------------------

def _as_table(run) -> RunTable:
    if isinstance(run, RunTable):
        return run
    if isinstance(run, (str, os.PathLike)):
        return read_run_csv(run)
    return RunTable.from_results(run)


def _video_stem(csv_path: Path) -> str:
    """``clip`` for ``clip.lptrack.csv``, ``clip.lptrack.jsonl`` (``lptrack run``'s default names) or ``clip.csv``."""
    for suffix in (".lptrack.csv", ".lptrack.jsonl"):
        if csv_path.name.endswith(suffix) and len(csv_path.name) > len(suffix):
            return csv_path.name[:-len(suffix)]
    return csv_path.stem


def _video_search(csv_path, folders: Sequence) -> tuple[str, list[tuple[Path, list[Path]]]]:
    """The stem looked for, and each folder searched (each once, in order) with the videos found there."""
    csv_path = Path(csv_path)
    stem = _video_stem(csv_path)
    searched, seen = [], set()
    for folder in [csv_path.parent, *map(Path, folders)]:
        key = folder.resolve()
        if key in seen:
            continue
        seen.add(key)
        found = [folder / f"{stem}{ext}" for ext in VIDEO_EXTENSIONS if (folder / f"{stem}{ext}").is_file()]
        # 'lptrack run img/%04d.jpg' names its CSV after the folder, img.lptrack.csv (OTB's layout).
        sequence = guess_image_sequence(folder / stem) if (folder / stem).is_dir() else None
        searched.append((folder, found + ([sequence] if sequence is not None else [])))
    return stem, searched


def find_video_for_csv(csv_path, folders: Sequence = (".",)) -> Path | None:
    """The video a run CSV was made from, when that is obvious; else None.

    A run CSV does not name its video. ``<stem>.lptrack.csv`` (``lptrack run``'s default name; or
    ``<stem>.lptrack.jsonl``) or ``<stem>.csv`` is matched with ``<stem>`` plus one of
    :data:`VIDEO_EXTENSIONS`, or with a folder ``<stem>`` of numbered images (as an image-sequence pattern,
    ``img/%04d.jpg`` for ``img.lptrack.csv``), in the CSV's folder, then in ``folders``; the first folder with
    exactly one such source wins. Annotated outputs (``*.lptrack.*``) are never chosen.
    :func:`describe_video_search` says why none was found.
    """
    for _, found in _video_search(csv_path, folders)[1]:
        if len(found) == 1:
            return found[0]
    return None


def describe_video_search(csv_path, folders: Sequence = (".",)) -> str:
    """Where :func:`find_video_for_csv` looked for the video of ``csv_path`` and why it took none, as a phrase
    for a message (``no clip.mp4 (or .avi, ...) in 'runs' or the current folder``)."""
    stem, searched = _video_search(csv_path, folders)
    here = Path.cwd().resolve()

    def place(folder: Path) -> str:
        return "the current folder" if folder.resolve() == here else f"'{folder}'"

    several = [(folder, found) for folder, found in searched if len(found) > 1]
    if several:
        folder, found = several[0]
        names = ", ".join(str(p.relative_to(folder)) for p in found)  # img/%04d.jpg for a sequence
        return f"{place(folder)} holds several videos it could be ({names})"
    others = ", ".join(VIDEO_EXTENSIONS[1:6]) + ", ..."
    return (f"no {stem}{VIDEO_EXTENSIONS[0]} (or {others}, or a folder {stem}/ of numbered images) in "
            f"{' or '.join(place(f) for f, _ in searched)}")


# ----------------------------------------------------------------------------------------------------------
# Plot (matplotlib, optional)
# ----------------------------------------------------------------------------------------------------------

def matplotlib_hint() -> str | None:
    """None if matplotlib can be imported, else a one-line hint on installing it."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return f"plotting needs matplotlib, which is not installed; install it with: {PLOT_HINT}"
    return None


#: Size of the figure written by :func:`plot_track`, in inches at :data:`PLOT_DPI`.
PLOT_SIZE_IN = (13.0, 7.5)
PLOT_DPI = 100


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges ``[start, stop)`` of consecutive True values."""
    padded = np.concatenate([[False], np.asarray(mask, bool), [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2], edges[1::2]))


def plot_track(run, out_png, *, video=None, ground_truth=None, overwrite: bool = False,
               title: str | None = None) -> Path:
    """Draw a track as a figure and save it as PNG (:data:`PLOT_SIZE_IN` x :data:`PLOT_DPI` pixels), or as PDF or
    SVG if ``out_png`` ends so (:data:`PLOT_SUFFIXES`).

    Panels: the centre path (over the run's first frame when ``video`` is given, in video pixels, y down;
    the initial outline dashed, lost frames as red crosses); scale; rotation (degrees CCW, cumulative); score,
    with lost frames shaded red. With ``ground_truth``, its path and values are overlaid (dashed, black) and
    a last panel plots the per-frame errors: centre error (px), scale error (%) and rotation error (deg).

    Parameters
    ----------
    run : str, Path, RunTable or iterable of FrameResult
        The track (a path is read with :func:`read_run_csv`).
    out_png : str or Path
    video : str or Path, optional
        The tracked video, for the thumbnail.
    ground_truth : str, Path or GroundTruth, optional
        A file or sequence folder as ``lptrack eval`` takes
        (:func:`~logpolar_track.datasets.load_ground_truth`); errors come from
        :func:`~logpolar_track.evaluate.score_track`.
    overwrite : bool
    title : str, optional

    Raises
    ------
    UsageError
        matplotlib is missing (the message is the install hint), or ``out_png`` does not end in .png, .pdf or .svg.
    GroundTruthError, VideoError, OutputError, InputError
    """
    check_image_suffix(out_png, PLOT_SUFFIXES, "output image")
    hint = matplotlib_hint()
    if hint:
        raise UsageError(hint)
    table = _as_table(run)
    out_png = check_output_path(out_png, overwrite=overwrite, what="output image")
    gt = load_ground_truth(ground_truth) if isinstance(ground_truth, (str, os.PathLike)) else ground_truth
    thumb = read_frame(video, int(table.frames[0])) if video is not None else None

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = table.time_s
    lost = table.lost
    fig = plt.figure(figsize=PLOT_SIZE_IN, dpi=PLOT_DPI)
    n_right = 4 if gt is not None else 3
    grid = fig.add_gridspec(n_right, 2, width_ratios=(1.15, 1.0))
    ax_path = fig.add_subplot(grid[:, 0])
    axes = [fig.add_subplot(grid[0, 1])]
    axes += [fig.add_subplot(grid[i, 1], sharex=axes[0]) for i in range(1, n_right)]
    ax_scale, ax_rot, ax_score = axes[:3]

    # Path, in video pixels (y down, as on screen).
    if thumb is not None:
        ax_path.imshow(cv2.cvtColor(thumb.image, cv2.COLOR_BGR2RGB), extent=(-0.5, thumb.width - 0.5,
                                                                             thumb.height - 0.5, -0.5))
    cx, cy = table.ellipses[:, 0], table.ellipses[:, 1]
    ax_path.plot(cx, cy, "-", color="tab:green", lw=1.5, label="track centre")
    first = Ellipse(*(float(v) for v in table.ellipses[0]))
    outline = np.vstack([first.boundary_points(128), first.boundary_points(128)[:1]])
    ax_path.plot(outline[:, 0], outline[:, 1], "--", color="tab:green", lw=1, label=f"frame {table.frames[0]}")
    ax_path.plot([cx[0]], [cy[0]], "o", color="tab:green", ms=5)
    if lost.any():
        ax_path.plot(cx[lost], cy[lost], "x", color="red", ms=5, label="lost")
    if gt is not None:
        gt_frames = table.frames[(table.frames < len(gt))]
        gt_frames = gt_frames[gt.valid[gt_frames]]
        ax_path.plot(gt.boxes[gt_frames, 0], gt.boxes[gt_frames, 1], "--", color="black", lw=1.2,
                     label="ground truth")
    if thumb is None:
        ax_path.invert_yaxis()
    else:
        # Zoom to where the object went (its outlines plus a margin), within the frame: a small path over a
        # whole frame would be a few pixels wide.
        margin = 1.5 * float(np.max(table.ellipses[:, 2:4]))
        x0 = max(-0.5, float(np.min(cx)) - margin)
        x1 = min(thumb.width - 0.5, float(np.max(cx)) + margin)
        y0 = max(-0.5, float(np.min(cy)) - margin)
        y1 = min(thumb.height - 0.5, float(np.max(cy)) + margin)
        if x1 > x0 and y1 > y0:
            ax_path.set_xlim(x0, x1)
            ax_path.set_ylim(y1, y0)
    ax_path.set_aspect("equal", adjustable="datalim" if thumb is None else "box")
    ax_path.set(xlabel="x (px)", ylabel="y (px, down)", title="centre path")
    ax_path.legend(fontsize=8, loc="best")

    ax_scale.plot(t, table.scale, color="tab:blue", lw=1.2, label="track")
    ax_scale.set_ylabel("scale")
    if np.isfinite(table.rotation_deg).any():
        ax_rot.plot(t, table.rotation_deg, color="tab:purple", lw=1.2, label="track")
    else:
        ax_rot.text(0.99, 0.05, "tracker does not measure rotation", ha="right", va="bottom",
                    transform=ax_rot.transAxes, fontsize=9, color="grey")
    ax_rot.set_ylabel("rotation (deg CCW)")
    ax_score.plot(t, table.score, color="tab:orange", lw=1.2)
    ax_score.set(ylabel="score", ylim=(0, 1.05))
    for start, stop in _runs(lost):
        # Shade each lost frame as the time span it stands for (half a frame interval either side).
        dt = np.median(np.diff(t)) if len(t) > 1 else 1.0
        for ax in axes[:3]:
            ax.axvspan(t[start] - dt / 2, t[stop - 1] + dt / 2, color="red", alpha=0.15, lw=0)
    if lost.any():
        count = int(lost.sum())
        ax_score.plot([], [], color="red", alpha=0.3, lw=6, label=f"lost ({count} frame{'' if count == 1 else 's'})")
        ax_score.legend(fontsize=8, loc="lower left")

    if gt is not None:
        metrics = score_track(gt, table.track())
        frames = np.asarray(metrics["frames"], int)
        rows = np.searchsorted(table.frames, frames)
        if frames.size:
            ts = t[rows]
            gs = gt.scale[frames] / gt.scale[frames[0]] * table.scale[rows[0]]
            ax_scale.plot(ts, gs, "--", color="black", lw=1, label="ground truth")
            ax_errors = axes[3]
            ax_errors.plot(ts, metrics["centre_error_px"], color="tab:green", lw=1.2, label="centre (px)")
            ps = table.scale[rows] / table.scale[rows[0]]
            ax_errors.plot(ts, scale_errors(ps, gt.scale[frames] / gt.scale[frames[0]]), color="tab:blue",
                           lw=1.2, label="scale (%)")
            if gt.rotation_deg is not None and gt.rotation_period:
                start = table.rotation_deg[rows[0]]
                gr = gt.rotation_deg[frames] - gt.rotation_deg[frames[0]] + (start if math.isfinite(start) else 0.0)
                ax_rot.plot(ts, gr, "--", color="black", lw=1, label="ground truth")
            if gt.rotation_deg is not None and gt.rotation_period and np.isfinite(table.rotation_deg[rows]).any():
                pr = table.rotation_deg[rows]
                ax_errors.plot(ts, rotation_errors(pr - pr[0], gr - gr[0], gt.rotation_period),
                               color="tab:purple", lw=1.2, label="rotation (deg)")
            ax_errors.set(ylabel="error")
            ax_errors.set_ylim(bottom=0)
            ax_errors.legend(fontsize=8, loc="upper left", ncol=3)
            med = metrics["centre_error_median_px"]
            ax_errors.set_title(f"vs ground truth: median centre error {med:.1f} px, "
                                f"AUC {metrics['auc']:.2f}", fontsize=9)
            ax_scale.legend(fontsize=8, loc="best")
            if ax_rot.get_legend_handles_labels()[0]:
                ax_rot.legend(fontsize=8, loc="best")
    for ax in axes:
        ax.grid(alpha=0.3)
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel("time (s)")
    n_lost = int(lost.sum())
    fig.suptitle(title or f"{table.source}: {len(table)} frames, {n_lost} lost", fontsize=11)
    try:
        with written_into_place(out_png, overwrite=overwrite, what="output image") as temp, \
                warnings.catch_warnings():
            # A file name in a script the font lacks (CJK) is drawn as boxes; matplotlib's warning about each
            # glyph, with its source line, would reach the user's terminal twice per character.
            warnings.filterwarnings("ignore", message="Glyph .* missing from", category=UserWarning)
            fig.tight_layout()
            fig.savefig(temp, dpi=PLOT_DPI)
    finally:
        plt.close(fig)
    return Path(out_png)


# ----------------------------------------------------------------------------------------------------------
# Contact sheet (pure OpenCV)
# ----------------------------------------------------------------------------------------------------------

def sheet_indices(n_rows: int, count: int) -> np.ndarray:
    """``count`` evenly spaced row indices from ``0`` to ``n_rows - 1`` (first and last included, unique)."""
    count = max(1, min(int(count), n_rows))
    return np.unique(np.round(np.linspace(0, n_rows - 1, count)).astype(int))


#: Rows of a contact sheet when neither ``rows`` nor ``count`` is given.
SHEET_ROWS = 3


def write_contact_sheet(video_path, run_csv_or_rows, out_png, *, cols: int = 4, rows: int | None = None,
                        count: int | None = None, width: int = 1600, overwrite: bool = False) -> Path:
    """Write a contact sheet: a grid of evenly spaced annotated frames of a run, as one PNG.

    Parameters
    ----------
    video_path : str or Path
        The tracked video.
    run_csv_or_rows : str, Path, RunTable or iterable of FrameResult
        The run: a run CSV path (checked against the contract) or the results themselves.
    out_png : str or Path
        PNG to write (atomically).
    cols : int
        Columns of tiles (as many as there are frames to show, when fewer).
    rows : int, optional
        Rows of tiles: ``cols * rows`` frames, evenly spaced over the run's rows, first and last included.
        Default :data:`SHEET_ROWS` (3), unless ``count`` is given.
    count : int, optional
        Instead of ``rows``: this many frames, in ``cols`` columns (rows as needed).
    width : int
        Width of the sheet in pixels; each tile is ``width // cols`` pixels wide, never wider than the video.
    overwrite : bool

    Returns
    -------
    Path
        The PNG written: ``cols * tile_w`` pixels wide, ``header + n_rows_used * (tile_h + label_h)`` high,
        where ``tile_h = round(tile_w * video_height / video_width)``; see :func:`sheet_geometry`.

    Raises
    ------
    UsageError
        Bad grid shape or width, both ``rows`` and ``count`` given (they are alternatives: either fixes the
        number of frames), or the run's frames are not in the video.
    GroundTruthError
        The CSV does not follow the contract.
    VideoError, OutputError

    Notes
    -----
    Each tile is the frame with the run's outline and axis line drawn as in the annotated video (green
    tracked, red lost), shrunk with area averaging, and a label strip below it: frame number, time, scale,
    rotation, score. The video is decoded once, from the start up to the last frame shown.
    """
    if rows is not None and count is not None:
        raise UsageError(f"give rows or count, not both: rows={rows} means {cols} x {rows} frames, count={count} "
                         f"means {count} frames in {cols} columns")
    rows = SHEET_ROWS if rows is None else rows
    for name, value in (("cols", cols), ("rows", rows), ("count", count), ("width", width)):
        if value is not None:
            check_frame_number(value, name, low=1)  # 2.5 columns were 2, True 1
    if width < 16 * cols:
        raise UsageError(f"sheet width {width} px is too small for {cols} columns (at least {16 * cols} px)")
    table = _as_table(run_csv_or_rows)
    check_image_suffix(out_png, (".png",), "contact sheet")
    out_png = check_output_path(out_png, overwrite=overwrite, what="contact sheet")
    wanted = sheet_indices(len(table), count if count is not None else cols * rows)
    cols = min(cols, len(wanted))  # fewer frames than columns: no empty columns
    by_frame = {int(table.frames[i]): i for i in wanted}
    video_path = Path(video_path)
    tiles: dict[int, np.ndarray] = {}
    with VideoReader(video_path) as reader:
        geometry = sheet_geometry(reader.width, reader.height, cols, len(wanted), width)
        tile_w, tile_h = geometry["tile"]
        last = max(by_frame)
        for index, _, frame in reader:
            i = by_frame.get(index)
            if i is not None:
                tiles[i] = _tile(frame, table.result(i), tile_w, tile_h, geometry["label_h"])
            if index >= last:
                break
    missing = [int(table.frames[i]) for i in wanted if i not in tiles]
    if missing:
        raise UsageError(f"frame {missing[0]} of the run is not in '{video_path}' (it has fewer frames); "
                         f"is this the video the run was made from?")
    sheet = np.full((geometry["size"][1], geometry["size"][0], 3), 32, np.uint8)
    n_lost = int(table.lost.sum())
    _label(sheet, f"{video_path.name}  {reader.width}x{reader.height}  run {table.source}: {len(table)} frames, "
                  f"{n_lost} lost  (showing {len(wanted)})", (0, 0), (255, 255, 255), scale=0.5, pad=6)
    cell_h = tile_h + geometry["label_h"]
    for k, i in enumerate(wanted):
        r, c = divmod(k, cols)
        y, x = geometry["header_h"] + r * cell_h, c * tile_w
        sheet[y:y + cell_h, x:x + tile_w] = tiles[i]
    return write_png(out_png, sheet, overwrite=overwrite, what="contact sheet")


def sheet_geometry(video_w: int, video_h: int, cols: int, n_frames: int, width: int = 1600) -> dict:
    """Pixel layout of a contact sheet: ``tile`` (w, h), ``label_h``, ``header_h`` and the sheet ``size`` (w, h)."""
    check_frame_number(cols, "cols", low=1)
    tile_w = max(16, min(int(width) // int(cols), int(video_w)))
    tile_h = max(1, int(round(tile_w * video_h / video_w)))
    label_h = 18
    header_h = 28
    n_rows = math.ceil(n_frames / cols)
    return {"tile": (tile_w, tile_h), "label_h": label_h, "header_h": header_h,
            "size": (cols * tile_w, header_h + n_rows * (tile_h + label_h))}


def _tile(frame: np.ndarray, result: FrameResult, tile_w: int, tile_h: int, label_h: int) -> np.ndarray:
    """One sheet cell: the annotated frame shrunk to ``tile_w`` x ``tile_h`` over a label strip."""
    shrink = frame.shape[1] / tile_w
    # Lines drawn `shrink` pixels thick stay about one pixel thick once shrunk.
    thickness = max(1, int(round(shrink)))
    annotated = draw_state(frame, result.state, status=result.status, thickness=thickness, text=False)
    small = cv2.resize(annotated, (tile_w, tile_h), interpolation=cv2.INTER_AREA)
    cell = np.full((tile_h + label_h, tile_w, 3), 32, np.uint8)
    cell[:tile_h] = small
    cell[:tile_h, -1] = 32  # a dark 1-px gutter between tiles
    colour = LOST_COLOUR if result.status == "lost" else TRACKED_COLOUR
    s = result.state
    rot = "" if s.rotation_deg is None else f" r{s.rotation_deg:+.0f}"
    text = f"frame {result.frame} {result.time_s:.2f}s x{s.scale:.2f}{rot} {s.score:.2f}"
    if result.status == "lost":
        text += " LOST"
    scale = 0.4
    while scale > 0.25 and cv2.getTextSize(text, _FONT, scale, 1)[0][0] > tile_w - 4:
        scale -= 0.025
    cv2.putText(cell, text, (2, tile_h + label_h - 5), _FONT, scale, colour, 1, cv2.LINE_AA)
    return cell
