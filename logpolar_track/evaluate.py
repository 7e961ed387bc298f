"""Ground truth readers and accuracy metrics, shared by ``lptrack bench`` and ``lptrack eval``, and the one reader
of a run's CSV (:func:`read_run_csv`; :func:`as_run_table` for a path, a table or results), which ``eval``,
``plot`` and ``sheet`` share.

Conventions
-----------
* Pixel coordinates, origin at the top-left corner, x right, y down, 0-based (OTB and UAV123 files are 1-based
  and are shifted by -1 when read).
* A *box* is axis-aligned ``(x, y, w, h)``: top-left corner and size in pixels.
* A *rotated box* is ``(cx, cy, w, h, angle_deg)``: centre, side lengths in pixels, and the direction of side
  ``w`` in degrees **counter-clockwise as seen on screen** (lptrack's ROI convention: direction ``t`` points
  along ``(cos t, -sin t)``). ``h`` lies across ``w``.
* Ground truth is held as rotated boxes for every format; axis-aligned formats have angle 0 and
  ``rotated=False``. Rows of NaN are frames that are not scored.

Metrics (all computed only on *scored* frames: frames with finite ground truth and a prediction)
----------------------------------------------------------------------------------------------
overlap (IoU)
    Intersection over union of the tracker's box and the ground-truth box. When the ground truth is
    axis-aligned the tracker's box is the axis-aligned bounding box of its ellipse; when the ground truth is
    rotated (VOT polygons, lptrack ``.gt.csv`` ellipses) it is the ellipse's own rectangle
    ``(cx, cy, 2a, 2b, angle)``, and the ground truth of a ``.gt.csv`` is likewise its ellipse's rectangle
    -- except where that ellipse is a circle, which has no orientation to miss: there the axis-aligned
    bounding boxes are compared.
success rate
    Share of scored frames whose centre error is **below 25 % of the object's ground-truth radius**, the radius
    being ``sqrt(w*h)/2`` of the ground-truth box (``sqrt(a*b)`` for an ellipse: the radius of the circle of
    equal area). Scale-free, so it means the same on a 20-pixel and a 200-pixel object.
success curve and AUC
    OTB's success plot (Wu, Lim, Yang, TPAMI 2015): for 21 IoU thresholds 0, 0.05, ..., 1 the share of scored
    frames with IoU **strictly greater** than the threshold; AUC is the mean of the 21 values.
precision
    OTB's precision plot: share of scored frames with centre error **at most** t pixels, t = 0..50; the
    figure quoted is t = 20 px.
scale error
    ``|s_pred / s_gt - 1|`` in percent, both scales taken relative to the first scored frame. ``s_gt`` is the
    ``scale`` column of a ``.gt.csv``, otherwise the box size ratio ``sqrt(w*h) / sqrt(w0*h0)``; ``s_pred`` is
    the tracker's reported scale.
rotation error
    Only where the ground truth has an angle and the tracker measures rotation. Cumulative (unwrapped)
    rotation of both, relative to the first scored frame, compared directly for ``.gt.csv`` (a turn missed
    costs 360 degrees), and **modulo 180 degrees** (error in [0, 90]) for rectangle ground truth such as VOT's,
    whose rectangles look the same after half a turn so their cumulative rotation is only known up to
    multiples of 180 degrees.
lost rate
    Share of scored frames (the first, ``init``, included) the tracker reported ``lost`` (its ``status``; OpenCV's
    trackers: ``update`` said not ok). Those frames are scored like the others, with the geometry the tracker
    reported for them. Unknown (NaN) for a track without statuses.
tracked off the object
    Share of the scored frames reported ``tracked`` whose box does not overlap the ground truth at all (IoU 0, VOT's
    failure): how often a frame said to be tracked is not. With the lost rate it says how far ``status`` can be
    trusted: a tracker that reports ``lost`` on many frames but is rarely off the object when it says
    ``tracked`` gives data whose ``tracked`` rows a user can keep.

All metric functions are pure functions of numpy arrays.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

import numpy as np

from .errors import GroundTruthError, UsageError, counted, is_real
from .geometry import Ellipse, ellipse_in_rotated_rect, parse_number
from .results import COLUMNS, VIDEO_COLUMN, FrameResult, decode_text, off_contract, read_data_rows
from .trackers.base import TrackState

#: IoU thresholds of the OTB success plot.
IOU_THRESHOLDS = np.linspace(0.0, 1.0, 21)
#: Centre-error thresholds (pixels) of the OTB precision plot.
PRECISION_THRESHOLDS = np.arange(0.0, 51.0)
#: Centre error, as a fraction of the object's radius, under which a frame counts as a success.
SUCCESS_RADIUS_FRACTION = 0.25
#: Centre error (pixels) at which precision is quoted.
PRECISION_PX = 20.0

GT_CSV_COLUMNS = ("frame", "cx", "cy", "a", "b", "angle_deg", "scale", "rotation_deg")


# ----------------------------------------------------------------------------------------------------------
# Geometry of boxes
# ----------------------------------------------------------------------------------------------------------

def box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of axis-aligned boxes.

    Parameters
    ----------
    a, b : array_like, shape (n, 4) or (4,)
        Boxes ``(x, y, w, h)`` in pixels, (x, y) the top-left corner; continuous coordinates (a box covers
        ``[x, x+w] x [y, y+h]``).

    Returns
    -------
    ndarray, shape (n,)
        IoU in [0, 1]; NaN where either box has a NaN; 0 where the union is empty.
    """
    a = np.atleast_2d(np.asarray(a, float))
    b = np.atleast_2d(np.asarray(b, float))
    iw = np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2]) - np.maximum(a[:, 0], b[:, 0])
    ih = np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3]) - np.maximum(a[:, 1], b[:, 1])
    inter = np.clip(iw, 0, None) * np.clip(ih, 0, None)
    union = a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        # At most 1: equal boxes can come out a rounding error above it, which a success curve's last threshold
        # (IoU > 1) would count.
        iou = np.where(union > 0, np.minimum(inter / np.where(union > 0, union, 1.0), 1.0), 0.0)
    iou[np.isnan(a).any(axis=1) | np.isnan(b).any(axis=1)] = np.nan
    return iou


def rotated_box_corners(box) -> np.ndarray:
    """The four corners ``(4, 2)`` (x, y pixels) of a rotated box ``(cx, cy, w, h, angle_deg)``.

    Side ``w`` runs along ``angle_deg`` (counter-clockwise on screen), i.e. along ``(cos t, -sin t)``.
    """
    cx, cy, w, h, angle = (float(v) for v in box)
    t = math.radians(angle)
    u = np.array([math.cos(t), -math.sin(t)]) * (w / 2.0)
    v = np.array([-math.sin(t), -math.cos(t)]) * (h / 2.0)  # u turned by +90 degrees on screen
    c = np.array([cx, cy])
    return np.array([c + u + v, c - u + v, c - u - v, c + u - v])


def polygon_area(points: np.ndarray) -> float:
    """Signed shoelace area of a polygon ``(n, 2)``; positive when counter-clockwise in (x, y) axes."""
    if len(points) < 3:
        return 0.0
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def clip_convex(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Intersection of two convex polygons (Sutherland-Hodgman), both ``(n, 2)`` with positive orientation.

    Returns the intersection polygon ``(m, 2)`` (``m`` may be 0).
    """
    out = subject
    n = len(clip)
    for i in range(n):
        if len(out) == 0:
            break
        p, q = clip[i], clip[(i + 1) % n]
        edge = q - p
        # Cross product > = 0: on the inner (left) side of the edge, for a positively oriented clip polygon.
        side = edge[0] * (out[:, 1] - p[1]) - edge[1] * (out[:, 0] - p[0])
        inside = side >= -1e-12
        result = []
        for j in range(len(out)):
            cur, nxt = out[j], out[(j + 1) % len(out)]
            s_cur, s_nxt = side[j], side[(j + 1) % len(out)]
            if inside[j]:
                result.append(cur)
            if (s_cur >= -1e-12) != (s_nxt >= -1e-12):
                f = s_cur / (s_cur - s_nxt)
                result.append(cur + f * (nxt - cur))
        out = np.array(result) if result else np.zeros((0, 2))
    return out


def rotated_box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of rotated boxes.

    Parameters
    ----------
    a, b : array_like, shape (n, 5) or (5,)
        Rotated boxes ``(cx, cy, w, h, angle_deg)``: centre and sides in pixels, angle of side ``w`` in degrees
        counter-clockwise on screen.

    Returns
    -------
    ndarray, shape (n,)
        IoU in [0, 1], exact up to float rounding (convex polygon clipping); NaN where either box has a NaN.
    """
    a = np.atleast_2d(np.asarray(a, float))
    b = np.atleast_2d(np.asarray(b, float))
    out = np.full(len(a), np.nan)
    for i in range(len(a)):
        if np.isnan(a[i]).any() or np.isnan(b[i]).any():
            continue
        pa, pb = _positive(rotated_box_corners(a[i])), _positive(rotated_box_corners(b[i]))
        area_a, area_b = polygon_area(pa), polygon_area(pb)
        inter = max(polygon_area(clip_convex(pa, pb)), 0.0)
        union = area_a + area_b - inter
        out[i] = min(inter / union, 1.0) if union > 0 else 0.0
    return out


def _positive(poly: np.ndarray) -> np.ndarray:
    return poly if polygon_area(poly) >= 0 else poly[::-1]


def boxes_to_rotated(boxes: np.ndarray) -> np.ndarray:
    """Axis-aligned boxes ``(n, 4)`` ``(x, y, w, h)`` as rotated boxes ``(n, 5)`` with angle 0."""
    boxes = np.atleast_2d(np.asarray(boxes, float))
    return np.column_stack([boxes[:, 0] + boxes[:, 2] / 2, boxes[:, 1] + boxes[:, 3] / 2,
                            boxes[:, 2], boxes[:, 3], np.zeros(len(boxes))])


def rotated_to_aabb(rboxes: np.ndarray) -> np.ndarray:
    """Axis-aligned bounding boxes ``(n, 4)`` of rotated boxes ``(n, 5)``."""
    r = np.atleast_2d(np.asarray(rboxes, float))
    t = np.radians(r[:, 4])
    c, s = np.abs(np.cos(t)), np.abs(np.sin(t))
    hw = (r[:, 2] * c + r[:, 3] * s) / 2
    hh = (r[:, 2] * s + r[:, 3] * c) / 2
    return np.column_stack([r[:, 0] - hw, r[:, 1] - hh, 2 * hw, 2 * hh])


def rect_from_polygon(points) -> tuple[float, float, float, float, float]:
    """The rotated rectangle fitted to a quadrilateral (``cv2.minAreaRect``) in lptrack's angle convention.

    Parameters
    ----------
    points : array_like, shape (4, 2) or (8,)
        Corners (x, y) in pixels, in any order (VOT's corner order varies between frames).

    Returns
    -------
    (cx, cy, w, h, angle_deg)
        Side ``w`` along ``angle_deg`` (counter-clockwise on screen). Which side is called ``w`` is arbitrary
        here (see :func:`unwrap_rects` for a consistent choice over a sequence).
    """
    import cv2

    pts = np.asarray(points, np.float32).reshape(-1, 2)
    rect = cv2.minAreaRect(pts)
    # Read sides and angle off the rectangle's corners rather than OpenCV's angle field, whose range and sign
    # convention changed between OpenCV versions.
    corners = cv2.boxPoints(rect).astype(float)
    side_w, side_h = corners[1] - corners[0], corners[2] - corners[1]
    angle = math.degrees(math.atan2(-side_w[1], side_w[0]))
    (cx, cy) = rect[0]
    return (float(cx), float(cy), float(np.hypot(*side_w)), float(np.hypot(*side_h)), angle)


def unwrap_rects(rects: np.ndarray) -> np.ndarray:
    """Choose side order and angle of each rotated rectangle so the angle changes continuously.

    A rectangle ``(cx, cy, w, h, t)`` is the same as ``(cx, cy, w, h, t + 180k)`` and ``(cx, cy, h, w, t + 90)``.
    The first finite rectangle is written with ``w >= h`` and ``t`` in (-90, 90]; each later one takes the
    variant ``t + 90k`` (sides swapped for odd ``k``) nearest to the previous finite angle, so the angle
    sequence is unwrapped (it can grow past 180 over several turns). This assumes less than 45 degrees of
    rotation between consecutive annotated frames.

    Parameters
    ----------
    rects : ndarray, shape (n, 5)
        Rotated rectangles; NaN rows are kept as NaN.

    Returns
    -------
    ndarray, shape (n, 5)
    """
    out = np.array(rects, float, copy=True)
    prev = None
    for i, (cx, cy, w, h, t) in enumerate(out):
        if not np.isfinite(out[i]).all():
            continue
        if prev is None:
            if h > w:
                w, h, t = h, w, t + 90.0
            t = t - 180.0 * math.ceil((t - 90.0) / 180.0)  # into (-90, 90]
        else:
            k = round((prev - t) / 90.0)
            t = t + 90.0 * k
            if k % 2:
                w, h = h, w
        out[i] = (cx, cy, w, h, t)
        prev = t
    return out


# ----------------------------------------------------------------------------------------------------------
# Ground truth and predictions
# ----------------------------------------------------------------------------------------------------------

@dataclass
class GroundTruth:
    """Ground truth of one sequence, one row per frame (NaN rows: not scored).

    Attributes
    ----------
    boxes : ndarray, shape (n, 5)
        Rotated boxes ``(cx, cy, w, h, angle_deg)`` in pixels / degrees CCW; row ``k`` is frame ``k``.
    rotated : bool
        True when the boxes carry a measured orientation (VOT polygons, ``.gt.csv`` ellipses); then overlap is
        computed between rotated boxes, otherwise between axis-aligned boxes.
    scale : ndarray, shape (n,)
        Object scale relative to the first finite row (``.gt.csv`` column or box size ratio).
    rotation_deg : ndarray, shape (n,) or None
        Cumulative counter-clockwise rotation since the first finite row, when the ground truth has an angle.
    rotation_period : float or None
        360 when rotation is known in full (``.gt.csv``), 180 for rectangles (VOT), None without an angle.
    ellipses : ndarray, shape (n, 5) or None
        ``(cx, cy, a, b, angle_deg)`` for ``.gt.csv`` ground truth.
    source : str
        Format name: ``lptrack``, ``otb``, ``vot``, ``uav123`` or ``boxes``.
    """

    boxes: np.ndarray
    rotated: bool
    scale: np.ndarray
    rotation_deg: np.ndarray | None = None
    rotation_period: float | None = None
    ellipses: np.ndarray | None = None
    source: str = "boxes"

    def __len__(self) -> int:
        return len(self.boxes)

    @property
    def valid(self) -> np.ndarray:
        """Boolean mask of scored frames (finite box with positive sides)."""
        b = self.boxes
        return np.isfinite(b).all(axis=1) & (np.nan_to_num(b[:, 2]) > 0) & (np.nan_to_num(b[:, 3]) > 0)

    @property
    def first_valid(self) -> int:
        """Index of the first scored frame; raises :class:`GroundTruthError` if there is none."""
        idx = np.flatnonzero(self.valid)
        if idx.size == 0:
            raise GroundTruthError("the ground truth has no frame with a valid box")
        return int(idx[0])

    @property
    def radius(self) -> np.ndarray:
        """The object's radius per frame in pixels: ``sqrt(w*h)/2`` (for an ellipse ``sqrt(a*b)``)."""
        return np.sqrt(self.boxes[:, 2] * self.boxes[:, 3]) / 2.0

    def truncated(self, n: int) -> "GroundTruth":
        """The first ``n`` rows, padded with NaN rows (unscored) when the sequence is longer than the file."""
        def fit(arr):
            if arr is None:
                return None
            if len(arr) >= n:
                return arr[:n].copy()
            pad = np.full((n - len(arr),) + arr.shape[1:], np.nan)
            return np.concatenate([arr, pad])
        return GroundTruth(fit(self.boxes), self.rotated, fit(self.scale), fit(self.rotation_deg),
                           self.rotation_period, fit(self.ellipses), self.source)

    def reversed(self) -> "GroundTruth":
        """The ground truth of the frames played backwards: row ``k`` is row ``n - 1 - k``, and ``scale`` and
        ``rotation_deg`` are relative to the new first valid row (the old last one)."""
        return self._rows(slice(None, None, -1))

    def every(self, first: int, n: int) -> "GroundTruth":
        """The ground truth of rows ``first``, ``first + n``, ``first + 2 n``, ... (every ``n``-th frame from
        ``first``); ``scale`` and ``rotation_deg`` relative to the new first valid row. A rotation unwrapped over
        every frame stays as unwrapped (every ``n``-th frame may turn by more than half a period between rows)."""
        return self._rows(slice(first, None, n))

    def there_and_back(self, first: int, passes: int) -> "GroundTruth":
        """The ground truth of rows ``first`` to the last, then back to ``first``, and so on: ``passes`` passes
        (:func:`there_and_back_rows`); ``scale`` and ``rotation_deg`` relative to the new first valid row."""
        return self._rows(there_and_back_rows(first, len(self), passes))

    def _rows(self, rows: slice | np.ndarray) -> "GroundTruth":
        """The ground truth of ``rows`` (a slice or row indices), in their order, with ``scale`` and
        ``rotation_deg`` relative to its first valid row."""
        valid = self.valid[rows]
        rotation = None if self.rotation_deg is None else _relative(self.rotation_deg[rows], valid, ratio=False)
        ellipses = None if self.ellipses is None else self.ellipses[rows].copy()
        return GroundTruth(self.boxes[rows].copy(), self.rotated, _relative(self.scale[rows], valid, ratio=True),
                           rotation, self.rotation_period, ellipses, self.source)

    def initial_roi(self) -> Ellipse:
        """The ellipse inscribed in the first valid box (the ``.gt.csv`` ellipse itself)."""
        i = self.first_valid
        if self.ellipses is not None:
            return Ellipse(*(float(v) for v in self.ellipses[i]))
        cx, cy, w, h, angle = (float(v) for v in self.boxes[i])
        return ellipse_in_rotated_rect(cx, cy, w, h, angle)


def there_and_back_rows(first: int, n: int, passes: int) -> np.ndarray:
    """Indices of frames ``first`` to ``n - 1`` played forwards and backwards in turn, ``passes`` passes: ``first``
    .. ``n - 1``, then ``n - 2`` .. ``first``, then ``first + 1`` .. ``n - 1``, ... (the frame a pass turns on is
    not shown twice). Every pass after the first has one frame fewer than it."""
    if passes < 1 or not 0 <= first < n:
        raise ValueError(f"need passes >= 1 and 0 <= first < n, got {passes}, {first}, {n}")
    forwards = np.arange(first, n)
    rows = [forwards] + [forwards[-2::-1] if k % 2 else forwards[1:] for k in range(1, passes)]
    return np.concatenate(rows)


def _relative(values: np.ndarray, valid: np.ndarray, *, ratio: bool) -> np.ndarray:
    idx = np.flatnonzero(valid & np.isfinite(values))
    if idx.size == 0:
        return np.full(len(values), np.nan)
    ref = values[idx[0]]
    return values / ref if ratio else values - ref


def ground_truth_from_boxes(boxes: np.ndarray, *, source: str = "boxes") -> GroundTruth:
    """Ground truth from axis-aligned boxes ``(n, 4)`` ``(x, y, w, h)`` (0-based pixels; NaN rows unscored)."""
    boxes = np.asarray(boxes, float).reshape(-1, 4)
    rboxes = boxes_to_rotated(boxes)
    gt = GroundTruth(rboxes, False, np.ones(len(rboxes)), source=source)
    size = np.sqrt(rboxes[:, 2] * rboxes[:, 3])
    gt.scale = _relative(size, gt.valid, ratio=True)
    return gt


def ground_truth_from_rects(rects: np.ndarray, *, source: str = "vot") -> GroundTruth:
    """Ground truth from rotated rectangles ``(n, 5)``, unwrapped; rotation known modulo 180 degrees."""
    rects = unwrap_rects(np.asarray(rects, float).reshape(-1, 5))
    gt = GroundTruth(rects, True, np.ones(len(rects)), rotation_period=180.0, source=source)
    valid = gt.valid
    gt.scale = _relative(np.sqrt(rects[:, 2] * rects[:, 3]), valid, ratio=True)
    gt.rotation_deg = _relative(rects[:, 4].copy(), valid, ratio=False)
    return gt


def ground_truth_from_ellipses(ellipses: np.ndarray, scale: np.ndarray | None = None,
                               rotation_deg: np.ndarray | None = None) -> GroundTruth:
    """Ground truth from ellipses ``(n, 5)`` ``(cx, cy, a, b, angle_deg)`` as in a ``.gt.csv``.

    ``scale`` and ``rotation_deg`` default to (and are filled where NaN from) the semi-axes' size ratio and
    the angle change since the first valid row. An ellipse's angle says its turn only modulo 180 degrees (it is
    the same ellipse half a turn round): the angles are unwrapped (assuming less than 90 degrees of turn between
    consecutive rows that have one), and rotation is then scored modulo 180, unless ``rotation_deg`` gives
    every valid row's cumulative turn (scored in full, a missed turn costing 360).
    """
    e = np.asarray(ellipses, float).reshape(-1, 5)
    boxes = np.column_stack([e[:, 0], e[:, 1], 2 * e[:, 2], 2 * e[:, 3], e[:, 4]])
    gt = GroundTruth(boxes, True, np.ones(len(e)), rotation_period=360.0, ellipses=e, source="lptrack")
    valid = gt.valid
    size_scale = _relative(np.sqrt(e[:, 2] * e[:, 3]), valid, ratio=True)
    angles = e[:, 4].copy()
    known = valid & np.isfinite(angles)
    # Written within (-180, 180] as the run CSV does, an ellipse spinning past 180 jumped by 360 (a perfect track
    # scored 360 degrees off).
    angles[known] = np.unwrap(angles[known], period=180.0)
    angle_rot = _relative(angles, valid, ratio=False)
    gt.scale = size_scale if scale is None else np.where(np.isfinite(scale), scale, size_scale)
    given = np.zeros(len(e), bool) if rotation_deg is None else np.isfinite(rotation_deg)
    gt.rotation_deg = np.where(given, np.nan if rotation_deg is None else rotation_deg, angle_rot)
    if not given[valid].all():
        gt.rotation_period = 180.0
    return gt


_SPLIT = re.compile(r"[,\s;]+")


def parse_number_lines(text: str, *, source: str = "ground truth") -> list[list[float]]:
    """Numbers per line of a benchmark ground-truth text (separators: comma, tab, space, semicolon).

    Trailing empty lines are dropped; an empty line inside the file is kept as an empty list (unscored).
    ``NaN`` is read as not-a-number.
    """
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    rows = []
    for number, line in enumerate(lines, 1):
        fields = [f for f in _SPLIT.split(line.strip()) if f]
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            raise GroundTruthError(f"{source}, line {number}: '{line.strip()[:60]}' is not a list of numbers; "
                                   "expected x,y,w,h or x1,y1,...,x4,y4 (commas, tabs or spaces)") from None
    return rows


def read_box_text(path, *, one_based: bool | None = None, source: str | None = None,
                  absent: np.ndarray | None = None) -> GroundTruth:
    """Read an OTB/UAV123/LaSOT/GOT-10k/TrackingNet ``x,y,w,h`` file or a VOT file (``x,y,w,h`` or 8-number polygons).

    Parameters
    ----------
    path : path-like
        Text file, line ``k`` (from 1) belonging to frame ``k - 1``.
    one_based : bool, optional
        Whether coordinates are 1-based (Matlab toolkits: OTB, UAV123) and must be shifted by -1 pixel.
        Default: False for a file named ``groundtruth.txt`` (VOT), True otherwise.
    source : str, optional
        Format name stored in the result; default ``vot`` for ``groundtruth.txt``, ``otb`` for
        ``groundtruth_rect*.txt``, else ``uav123``.
    absent : array of bool, optional
        Frames whose line is not scored whatever box it holds, as a benchmark's own flags say the target is absent
        there (LaSOT's full occlusion and out of view, GOT-10k's absence): ``absent[k]`` for line ``k + 1``; lines
        past its end are read as usual.

    Returns
    -------
    GroundTruth
        Rotated (VOT polygons fitted with ``cv2.minAreaRect``, see :func:`unwrap_rects`) if any line has 8
        numbers, else axis-aligned. Lines of NaN, empty lines, boxes with ``w <= 0`` or ``h <= 0``, and the
        lines of ``absent`` frames are unscored.

    Raises
    ------
    GroundTruthError
        If the file cannot be read or a line is not 4 or 8 numbers.
    """
    path = Path(path)
    name = path.name.lower()
    if one_based is None:
        one_based = name != "groundtruth.txt"
    if source is None:
        source = "vot" if name == "groundtruth.txt" else "otb" if name.startswith("groundtruth_rect") else "uav123"
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise GroundTruthError(f"cannot read ground truth '{path}': {exc.strerror or exc}") from None
    # UTF-8, or UTF-16 with a byte-order mark (a file saved by Windows tools). Anything else, an image given as the
    # ground truth, was decoded with replacement characters and its bytes printed in the error line.
    try:
        text = decode_text(data)
    except UnicodeDecodeError:
        raise GroundTruthError(f"cannot read ground truth '{path}': not a text file (UTF-8, or UTF-16 with a "
                               f"byte-order mark); expected one x,y,w,h or x1,y1,...,x4,y4 line per frame") from None
    rows = parse_number_lines(text, source=f"'{path}'")
    if not rows:
        raise GroundTruthError(f"ground truth '{path}' is empty; expected one x,y,w,h line per frame")
    shift = 1.0 if one_based else 0.0
    polygons = any(len(r) == 8 for r in rows)
    out = np.full((len(rows), 5 if polygons else 4), np.nan)
    flagged = np.zeros(len(rows), bool)
    if absent is not None:
        absent = np.asarray(absent, bool)[: len(rows)]
        flagged[: len(absent)] = absent
    for k, row in enumerate(rows):
        if len(row) == 0 or all(math.isnan(v) for v in row):
            continue
        if len(row) not in (4, 8):
            raise GroundTruthError(f"'{path}', line {k + 1}: {len(row)} numbers; expected 4 (x,y,w,h) or 8 "
                                   "(x1,y1,...,x4,y4)")
        if flagged[k] or any(math.isnan(v) for v in row):
            continue
        if len(row) == 4:
            x, y, w, h = row
            if w <= 0 or h <= 0:
                continue
            out[k] = (x - shift + w / 2, y - shift + h / 2, w, h, 0.0) if polygons else (x - shift, y - shift, w, h)
        else:
            cx, cy, w, h, angle = rect_from_polygon(np.array(row) - shift)
            if w > 0 and h > 0:
                out[k] = (cx, cy, w, h, angle)
    if polygons:
        return ground_truth_from_rects(out, source=source)
    return ground_truth_from_boxes(out, source=source)


def _float(text) -> float:
    text = (text or "").strip()
    if text.lower() in ("", "n/a", "na", "none", "nan"):
        return math.nan
    return float(text)


def read_data_file(path, what: str, hint: str = "") -> tuple[list[str], list[tuple[int, list[str]]]]:
    """:func:`~logpolar_track.results.read_data_rows` (a CSV file, or JSON lines as ``lptrack run`` writes them),
    its failures raised as :class:`GroundTruthError` naming ``what`` the file is, and ``hint`` on a bad line."""
    try:
        return read_data_rows(path)
    except (OSError, UnicodeDecodeError) as exc:
        why = ("it is a folder, not a file" if isinstance(exc, IsADirectoryError)
               else exc.strerror if isinstance(exc, OSError) and exc.strerror
               else "not a text file (UTF-8, or UTF-16 with a byte-order mark)")
        raise GroundTruthError(f"cannot read {what} '{path}': {why}") from None
    except ValueError as exc:
        raise GroundTruthError(f"{what} '{path}': {exc}" + (f"; {hint}" if hint else "")) from None


def _read_csv_columns(path, required: tuple[str, ...], what: str) -> tuple[list[dict], list[str], list[int]]:
    """Rows (as ``{column: text}``), header and the rows' line numbers in the file, of a data file
    (:func:`read_data_file`) with the ``required`` columns."""
    path = Path(path)
    header, body = read_data_file(path, what)
    if not header:
        raise GroundTruthError(f"{what} '{path}' is empty; expected a header with {','.join(required)}")
    missing = [c for c in required if c not in header]
    if missing:
        raise GroundTruthError(f"{what} '{path}' lacks column(s) {', '.join(missing)}; expected a header "
                               f"with {','.join(required)}")
    # A short row's missing fields read as empty, as csv.DictReader gives them.
    return ([{c: row[i] if i < len(row) else None for i, c in enumerate(header)} for _, row in body], header,
            [line for line, _ in body])


def read_gt_csv(path) -> GroundTruth:
    """Read an lptrack ground-truth sidecar ``<name>.gt.csv``.

    Columns ``frame,cx,cy,a,b,angle_deg,scale,rotation_deg`` (``scale`` and ``rotation_deg`` optional), the
    lptrack ROI conventions (pixels, semi-axes, degrees CCW, rotation cumulative). Row ``frame`` is placed at
    frame index ``frame``; frames without a row, and rows with empty/NaN fields, are unscored.

    Raises
    ------
    GroundTruthError
        Unreadable file, missing columns, fields that are not numbers, or a run's CSV (``lptrack run``'s).
    """
    rows, header, _ = _read_csv_columns(path, GT_CSV_COLUMNS[:6], "ground truth")
    if {"time_s", "status"} <= set(header):
        # It has every column a .gt.csv needs, and scored as one it gives a run's own guesses as the truth.
        raise GroundTruthError(f"ground truth '{path}' is an lptrack run (its columns include time_s and status), "
                               f"not ground truth")
    try:
        frames = [int(float(r["frame"])) for r in rows]
        values = np.array([[_float(r.get(c)) for c in GT_CSV_COLUMNS[1:]] for r in rows], float).reshape(-1, 7)
    except (TypeError, ValueError) as exc:
        raise GroundTruthError(f"ground truth '{path}' has a field that is not a number ({exc})") from None
    if not frames:
        raise GroundTruthError(f"ground truth '{path}' has a header but no rows")
    if min(frames) < 0:
        raise GroundTruthError(f"ground truth '{path}' has a negative frame number")
    n = max(frames) + 1
    table = np.full((n, 7), np.nan)
    table[frames] = values
    scale = table[:, 5] if "scale" in header else None
    rotation = table[:, 6] if "rotation_deg" in header else None
    return ground_truth_from_ellipses(table[:, :5], scale, rotation)


def read_ground_truth(path) -> GroundTruth:
    """Read ground truth in any supported format, chosen by the file name.

    ``*.csv``: lptrack ``.gt.csv``; ``groundtruth.txt``: VOT (0-based, 4 or 8 numbers); any other ``.txt``:
    OTB / UAV123 ``x,y,w,h`` (1-based). See :func:`read_gt_csv` and :func:`read_box_text`.
    """
    path = Path(path)
    if path.suffix.lower() == ".csv":
        return read_gt_csv(path)
    return read_box_text(path)


@dataclass
class Track:
    """A tracker's output over a sequence, one entry per frame (arrays of equal length).

    Attributes
    ----------
    frames : ndarray of int
        Frame indices.
    ellipses : ndarray, shape (n, 5)
        ``(cx, cy, a, b, angle_deg)`` pixels / degrees CCW.
    scale : ndarray
        Scale relative to the first frame.
    rotation_deg : ndarray
        Cumulative CCW rotation since the first frame; NaN where the tracker does not measure rotation.
    score : ndarray
        Confidence in [0, 1].
    status : list of str
        ``init``, ``tracked`` or ``lost`` per frame.
    """

    frames: np.ndarray
    ellipses: np.ndarray
    scale: np.ndarray
    rotation_deg: np.ndarray
    score: np.ndarray
    status: list = field(default_factory=list)

    def boxes(self, *, rotated: bool) -> np.ndarray:
        """Rotated boxes ``(n, 5)`` of the ellipses: their own rectangle, or (``rotated=False``) the
        axis-aligned bounding box of each ellipse expressed with angle 0."""
        e = self.ellipses
        own = np.column_stack([e[:, 0], e[:, 1], 2 * e[:, 2], 2 * e[:, 3], e[:, 4]])
        if rotated:
            return own
        # The bounding box of an ellipse is the bounding box of its own rectangle shrunk: half extents
        # sqrt((a cos t)^2 + (b sin t)^2), not a |cos t| + b |sin t|.
        t = np.radians(e[:, 4])
        hw = np.hypot(e[:, 2] * np.cos(t), e[:, 3] * np.sin(t))
        hh = np.hypot(e[:, 2] * np.sin(t), e[:, 3] * np.cos(t))
        return np.column_stack([e[:, 0], e[:, 1], 2 * hw, 2 * hh, np.zeros(len(e))])


# ----------------------------------------------------------------------------------------------------------
# A run's CSV: the one reader of it (plot, sheet and eval)
# ----------------------------------------------------------------------------------------------------------

@dataclass
class RunTable:
    """A run CSV as arrays, one entry per row (the contract's columns, :data:`~logpolar_track.results.COLUMNS`).

    Attributes
    ----------
    frames : ndarray of int
    time_s : ndarray
        Seconds.
    ellipses : ndarray, shape (n, 5)
        ``(cx, cy, a, b, angle_deg)`` pixels / degrees CCW on screen.
    scale, rotation_deg, score : ndarray
        ``rotation_deg`` is NaN where the tracker does not measure rotation.
    status : list of str
    source : str
        File name, for messages.
    video : str or None
        The video the rows are of, as a batch's stream names it (its ``video`` column, the path as ``run`` was
        given it); None for a run's own CSV, which does not name its video.
    """

    frames: np.ndarray
    time_s: np.ndarray
    ellipses: np.ndarray
    scale: np.ndarray
    rotation_deg: np.ndarray
    score: np.ndarray
    status: list
    source: str = "run"
    video: str | None = None

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def lost(self) -> np.ndarray:
        return np.array([s == "lost" for s in self.status], bool)

    def track(self) -> Track:
        """The same rows as :class:`~logpolar_track.evaluate.Track`, for scoring against ground truth."""
        return Track(self.frames, self.ellipses, self.scale, self.rotation_deg, self.score, list(self.status))

    def result(self, i: int) -> FrameResult:
        """Row ``i`` as a :class:`~logpolar_track.results.FrameResult`."""
        rot = float(self.rotation_deg[i])
        state = TrackState(Ellipse(*(float(v) for v in self.ellipses[i])), float(self.scale[i]),
                           rot if math.isfinite(rot) else None, float(self.score[i]))
        return FrameResult(int(self.frames[i]), float(self.time_s[i]), state, self.status[i])

    @classmethod
    def from_results(cls, results: Iterable[FrameResult], source: str = "run") -> "RunTable":
        """A table of :class:`~logpolar_track.results.FrameResult` values (e.g. from ``track_video``)."""
        results = list(results)
        if not results:
            raise UsageError("the run has no rows")
        ell = np.array([[r.state.ellipse.cx, r.state.ellipse.cy, r.state.ellipse.a, r.state.ellipse.b,
                         r.state.ellipse.angle_deg] for r in results], float)
        rot = np.array([math.nan if r.state.rotation_deg is None else r.state.rotation_deg for r in results])
        return cls(np.array([r.frame for r in results], int), np.array([r.time_s for r in results], float),
                   ell, np.array([r.state.scale for r in results], float), rot,
                   np.array([r.state.score for r in results], float), [r.status for r in results], source)


def no_frame_with_ground_truth(run: str, ground_truth: str) -> UsageError:
    """The error for a run none of whose frames has ground truth (another video's, or one that ends before the run
    starts): ``run`` and ``ground_truth`` as the message names them (quoted paths, say)."""
    return UsageError(f"no frame of {run} has ground truth in {ground_truth} (frames are matched by index, 0 = first "
                      f"frame)")


def rows_past_ground_truth(run: str, frames: np.ndarray, gt: GroundTruth, ground_truth: str) -> str | None:
    """The start of a note on the rows of a run whose ``frames`` lie past the end of ``gt`` (a ground truth cut
    short, or another sequence's, scored or plotted part of the run in silence), or None; ``run`` and
    ``ground_truth`` as the note names them (quoted paths, say)."""
    beyond = int((np.asarray(frames) >= len(gt)).sum())
    if not beyond:
        return None
    return (f"{beyond} of the {len(frames)} rows of {run} {'lies' if beyond == 1 else 'lie'} past the end of "
            f"{ground_truth} ({counted(len(gt), 'frame')})")


def several_videos(path, names: list[str], video=None) -> GroundTruthError:
    """The error for a batch's stream (a ``video`` column) of ``names`` where one video's run is needed: several,
    or none of them ``video`` if that was given."""
    if len(names) == 1 and video is not None:
        return GroundTruthError(f"run CSV '{path}' holds the rows of '{names[0]}' only (its 'video' column), not of "
                                f"'{video}'")
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    what = ("choose one with --video VIDEO, or give one video's run" if video is None
            else f"none of them is '{video}'; give one video's run")
    return GroundTruthError(f"run CSV '{path}' holds the rows of {len(names)} videos ({shown}: its 'video' "
                            f"column); {what} (its own CSV, as --out-dir writes them)")


def stream_name_places(name: str, stream=None) -> list[Path]:
    """Where a batch stream's ``video`` value ``name`` (the path as the run was given it) may be: from the current
    folder, and, where it is relative, from the folder of the file ``stream`` it came from (the run may have been
    started there; not for a stream read from stdin, ``'-'``)."""
    given = Path(name)
    if given.is_absolute() or stream is None or str(stream) == "-":
        return [given]
    return [given, Path(stream).parent / given]


def same_file(name: str, video, stream=None) -> bool:
    """Whether ``name`` (a batch stream's ``video`` value, the path as the run was given it) names the file
    ``video``: the same path, or two paths to one file, ``name`` taken from the current folder or, where it is
    relative, from the folder of the file ``stream`` it came from (the run may have been started there)."""
    a, b = Path(name), Path(video)
    if a == b:
        return True
    places = stream_name_places(name, stream)
    try:
        return b.exists() and any(place.exists() and place.samefile(b) for place in places)
    except OSError:
        return False


def _one_video(path: Path, header: list[str], body: list, video,
               only_if_several: bool) -> tuple[list[str], list, str]:
    """The header and rows of one video of a batch's stream (its ``video`` column: the first, as lptrack writes
    it, or another tool's anywhere), without that column, and that video's name in the column: the one whose
    name is the file ``video``, or the only one (whatever its name if ``only_if_several``). Its videos' frame
    numbers overlap, so one video's rows are read, never all of them (eval scored them all against the first
    one's ground truth)."""
    k = header.index(VIDEO_COLUMN)
    names = list(dict.fromkeys(row[k].strip() for _, row in body if len(row) > k))
    chosen = names[0] if len(names) == 1 and (video is None or only_if_several) else None
    if chosen is None and video is not None:
        chosen = next((name for name in names if same_file(name, video, path)), None)
    if chosen is None:
        raise several_videos(path, names, video)
    return (header[:k] + header[k + 1:],
            [(line, row[:k] + row[k + 1:]) for line, row in body if len(row) > k and row[k].strip() == chosen],
            chosen)


#: The columns of a run CSV that hold a number in every row, and the columns among them that must be > 0.
_NUMBER_COLUMNS = ("time_s", "cx", "cy", "a", "b", "angle_deg", "scale", "score")
_POSITIVE_COLUMNS = ("a", "b")
#: The columns another tool's CSV needs for ``lptrack eval`` (see :func:`read_run_csv`), and what a missing one of
#: the others reads as: NaN for a time or rotation (a scale not given is then the axes' size ratio), 1 for a score.
OTHER_TOOLS_COLUMNS = ("frame", "cx", "cy", "a", "b", "angle_deg")
_OTHER_TOOLS_DEFAULTS = {"time_s": "", "scale": "", "rotation_deg": "", "score": "1"}
#: What another tool may write in those columns for a value it does not give: NaN.
_NOT_GIVEN = ("", "nan", "n/a")


def read_run_csv(path, video=None, *, other_tools: bool = False, only_if_several: bool = False) -> RunTable:
    """Read a run CSV (or its JSON lines, as ``lptrack run`` writes them) and check that it follows the contract:
    the one reader of a run's file, for ``plot``, ``sheet`` and ``eval`` alike.

    The header must start with :data:`~logpolar_track.results.COLUMNS` in order (later columns, appended by
    newer versions, are ignored); every row needs a whole number ``frame`` >= 0 (digits only; increasing), a
    finite number in ``time_s``, ``cx``, ``cy``, ``a``, ``b`` (> 0), ``angle_deg``, ``scale`` and ``score`` (0 to
    1), a finite number or nothing in ``rotation_deg``, and a ``status`` among ``init``, ``tracked``, ``lost``.
    Numbers are read as :func:`~logpolar_track.geometry.parse_number` reads them (no ``nan``, ``inf`` or ``_``).

    With ``other_tools`` (what ``lptrack eval`` scores), a CSV whose header is not a run's but names at least
    :data:`OTHER_TOOLS_COLUMNS`, in any order, is read too, as another tool's track: its frames, centres, axes and
    angles are checked as above; ``time_s``, ``scale``, ``rotation_deg`` and ``score`` empty, ``nan`` or ``n/a`` are
    NaN (and those it lacks NaN, or 1 for ``score``), and a scale not given is the size ratio ``sqrt(a*b)`` to the
    first row's (what a run's ``scale`` is); without a ``status`` column, or with it empty
    throughout, the table's ``status`` is empty (how often the track was lost is not known). Its ``video`` column,
    if any, may be anywhere.

    A batch's stream (``lptrack run a.mp4 b.mp4 --csv -``) leads with a ``video`` column (another tool's CSV may have
    it anywhere): the rows of the video whose name is the file ``video`` are taken (a path; see :func:`same_file`),
    or without ``video`` those of the only one; ``only_if_several``: ``video`` only chooses among several (eval's
    ground truth given as the video).
    ``'-'`` reads stdin.

    Raises
    ------
    GroundTruthError
        (exit code 1) Unreadable file, or the first place where it departs from the contract: line number,
        column, value, and what is accepted; a batch's stream of several videos, none of them ``video``.
    """
    path = Path(path)
    expected = ",".join(COLUMNS)
    hint = f"expected an lptrack run CSV with the header {expected}, or its JSON lines"
    if other_tools:
        hint += f" (or another tool's CSV with at least the columns {','.join(OTHER_TOOLS_COLUMNS)})"
    header, body = read_data_file(path, "run CSV", hint)
    streamed = None
    if header[:1] == [VIDEO_COLUMN] or (other_tools and VIDEO_COLUMN in header):
        header, body, streamed = _one_video(path, header, body, video, only_if_several)
    if not header:
        raise GroundTruthError(f"run CSV '{path}' is empty; {hint}")
    lenient = False  # another tool's file: its optional columns may be empty (NaN), its statuses absent
    if tuple(header[:len(COLUMNS)]) == COLUMNS:
        place = {column: k for k, column in enumerate(COLUMNS)}
    elif other_tools and set(OTHER_TOOLS_COLUMNS) <= set(header):
        place = {column: header.index(column) for column in COLUMNS if column in header}
        lenient = True
    else:
        missing = [column for column in OTHER_TOOLS_COLUMNS if column not in header]
        if other_tools and len(missing) < len(OTHER_TOOLS_COLUMNS):
            raise GroundTruthError(f"run CSV '{path}' lacks column(s) {', '.join(missing)}; {hint}")
        got = ",".join(header)[:80]
        raise GroundTruthError(f"run CSV '{path}' has the header '{got}'; {hint}")
    if not body:
        raise GroundTruthError(f"run CSV '{path}' has a header but no rows")
    if lenient and "status" in place and not any(len(row) > place["status"] and row[place["status"]].strip()
                                                 for _, row in body):
        del place["status"]  # a status column left empty throughout: how often it was lost is not known
    needed = max(place.values()) + 1
    table: dict[str, list] = {c: [] for c in COLUMNS}
    for line, row in body:
        if len(row) < needed:  # a row cut short (a file copied while it was written, or cut with head -c)
            raise GroundTruthError(f"run CSV '{path}' line {line} has {len(row)} fields; expected "
                                   f"{len(header)} ({','.join(header)})")
        fields = {c: row[k].strip() for c, k in place.items()}
        fields = {**_OTHER_TOOLS_DEFAULTS, **fields}

        def bad(column: str, what: str) -> GroundTruthError:
            return GroundTruthError(f"run CSV '{path}' line {line}: {column} '{fields[column]}' is not {what}")
        text = fields["frame"]
        # int() takes '1_0' and ' 1', float() '1.0'; 19 digits and more overflow the table's int64.
        if not (text.isascii() and text.isdigit() and len(text) < 19):
            raise bad("frame", "a frame index (integer >= 0)")
        frame = int(text)
        if table["frame"] and frame <= table["frame"][-1]:
            raise GroundTruthError(f"run CSV '{path}' line {line}: frame {frame} does not follow frame "
                                   f"{table['frame'][-1]}; a run's frames increase")
        table["frame"].append(frame)
        for column in _NUMBER_COLUMNS:
            # (A column another tool's file lacks reads as its default: '' for time_s, so NaN too.)
            if lenient and column in _OTHER_TOOLS_DEFAULTS and fields[column].lower() in _NOT_GIVEN:
                table[column].append(math.nan)
                continue
            value = parse_number(fields[column])
            if value is None:
                raise bad(column, "a number" + (" > 0" if column in _POSITIVE_COLUMNS else ""))
            if column in _POSITIVE_COLUMNS and value <= 0:
                raise bad(column, "a number > 0")
            table[column].append(value)
        rotation = fields["rotation_deg"]
        value = parse_number(rotation) if rotation and not (lenient and rotation.lower() in _NOT_GIVEN) else math.nan
        if value is None:
            raise bad("rotation_deg", "a number or empty (a tracker that does not measure rotation)")
        table["rotation_deg"].append(value)
        status = fields["status"] if "status" in place else None
        broken = off_contract(status, table["score"][-1])
        if broken is not None:
            raise bad(*broken)
        if status is not None:
            table["status"].append(status)
    t = {c: np.asarray(v, float) for c, v in table.items() if c not in ("frame", "status")}
    if lenient and len(t["a"]):
        # Another tool's size is its axes: a scale of 1 for every frame it does not give would be scored as a
        # claim that the object kept its size.
        size = np.sqrt(t["a"] * t["b"])
        t["scale"] = np.where(np.isnan(t["scale"]), size / size[0], t["scale"])
    return RunTable(np.asarray(table["frame"], int), t["time_s"],
                    np.column_stack([t["cx"], t["cy"], t["a"], t["b"], t["angle_deg"]]), t["scale"],
                    t["rotation_deg"], t["score"], table["status"], path.name, video=streamed)


def as_run_table(run) -> RunTable:
    """``run`` as a :class:`RunTable`: a table as it is, a path read with :func:`read_run_csv` (checked against the
    contract), or :class:`~logpolar_track.results.FrameResult` values (:meth:`RunTable.from_results`)."""
    if isinstance(run, RunTable):
        return run
    if isinstance(run, (str, os.PathLike)):
        return read_run_csv(run)
    return RunTable.from_results(run)


def read_track_csv(path, video=None, *, only_if_several: bool = False) -> Track:
    """A run CSV read by :func:`read_run_csv` (the same checks, the same messages), or another tool's CSV
    (``other_tools``), as the :class:`Track` that :func:`score_track` scores: what ``lptrack eval`` reads."""
    return read_run_csv(path, video, other_tools=True, only_if_several=only_if_several).track()


# ----------------------------------------------------------------------------------------------------------
# Metrics
# ----------------------------------------------------------------------------------------------------------

def centre_error(pred_xy: np.ndarray, gt_xy: np.ndarray) -> np.ndarray:
    """Euclidean distance in pixels between predicted and ground-truth centres, arrays ``(n, 2)``."""
    d = np.asarray(pred_xy, float) - np.asarray(gt_xy, float)
    return np.hypot(d[..., 0], d[..., 1])


def success_rate(errors_px: np.ndarray, radius_px: np.ndarray, fraction: float = SUCCESS_RADIUS_FRACTION) -> float:
    """Share of frames whose centre error is below ``fraction`` of the object's radius (both pixels).

    NaN errors count as failures; returns NaN for no frames.
    """
    e, r = np.asarray(errors_px, float), np.asarray(radius_px, float)
    if e.size == 0:
        return math.nan
    return float(np.mean(np.nan_to_num(e, nan=np.inf) < fraction * r))


def success_curve(ious: np.ndarray, thresholds: np.ndarray = IOU_THRESHOLDS) -> np.ndarray:
    """OTB success curve: for each threshold, the share of frames with IoU strictly above it (NaN IoU = 0)."""
    iou = np.nan_to_num(np.asarray(ious, float), nan=0.0)
    if iou.size == 0:
        return np.full(len(thresholds), np.nan)
    return (iou[None, :] > np.asarray(thresholds)[:, None]).mean(axis=1)


def auc(curve: np.ndarray) -> float:
    """Area under a success curve sampled at evenly spaced thresholds on [0, 1]: OTB's mean of the samples (NaN
    for an empty curve)."""
    curve = np.asarray(curve, float)
    return float(np.mean(curve)) if curve.size else math.nan


def precision_curve(errors_px: np.ndarray, thresholds: np.ndarray = PRECISION_THRESHOLDS) -> np.ndarray:
    """OTB precision curve: for each threshold (pixels), the share of frames with centre error at most it."""
    e = np.nan_to_num(np.asarray(errors_px, float), nan=np.inf)
    if e.size == 0:
        return np.full(len(thresholds), np.nan)
    return (e[None, :] <= np.asarray(thresholds)[:, None]).mean(axis=1)


def scale_errors(pred_scale: np.ndarray, gt_scale: np.ndarray) -> np.ndarray:
    """Scale error per frame in percent: ``100 * |pred / gt - 1|`` (scales relative to a common frame); NaN where
    the ground truth's scale is not > 0."""
    gt = np.asarray(gt_scale, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        errors = 100.0 * np.abs(np.asarray(pred_scale, float) / gt - 1.0)
    return np.where(gt > 0, errors, np.nan)


def rotation_errors(pred_deg: np.ndarray, gt_deg: np.ndarray, period: float = 360.0,
                    *, unwrapped: bool = True) -> np.ndarray:
    """Rotation error per frame in degrees.

    Parameters
    ----------
    pred_deg, gt_deg : ndarray
        Cumulative counter-clockwise rotations in degrees, relative to a common frame.
    period : float
        Symmetry period of the ground truth's shape: 360 for a full orientation, 180 for a rectangle (which
        looks the same after half a turn).
    unwrapped : bool
        With ``period == 360``, True compares the cumulative angles directly (a missed full turn costs 360);
        False compares directions (error in [0, 180]). With any smaller period the error is the distance
        modulo ``period``, in [0, period / 2].

    Raises
    ------
    UsageError
        ``period`` is not a number > 0.
    """
    if not (is_real(period) and 0 < period < math.inf):
        raise UsageError(f"period must be a number of degrees > 0 (360, 180), got {period!r}")
    d = np.asarray(pred_deg, float) - np.asarray(gt_deg, float)
    if unwrapped and period >= 360.0:
        return np.abs(d)
    return np.abs((d + period / 2.0) % period - period / 2.0)


def _circles(gt: GroundTruth, frames: np.ndarray) -> np.ndarray:
    """Which of ``frames`` have a circular ground-truth ellipse (a == b within 0.1 %)."""
    if gt.ellipses is None:
        return np.zeros(len(frames), bool)
    e = gt.ellipses[frames]
    return np.isclose(e[:, 2], e[:, 3], rtol=1e-3)


def _nanmedian(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)] if x.size else x
    return float(np.median(x)) if x.size else math.nan


def score_track(gt: GroundTruth, track: Track) -> dict:
    """Score a tracker's output against ground truth on the frames both have (see the module notes).

    Parameters
    ----------
    gt : GroundTruth
    track : Track
        Predictions; frames are matched by index. Frames with ground truth but no prediction are not scored
        and counted in ``frames_missing``.

    Returns
    -------
    dict
        ``frames_scored``, ``frames_missing``, ``success_rate`` (fraction), ``auc``, ``iou_mean``,
        ``precision_20`` (fraction), ``centre_error_median_px``, ``scale_error_median_pct``,
        ``rotation_error_median_deg`` (None where not measurable), ``lost_rate`` and ``off_tracked_rate``
        (fractions; NaN where the track has no ``status``, or no frame scored is reported tracked),
        ``success_curve`` (21 values), ``precision_curve`` (51 values), and per-frame ``frames``, ``iou``,
        ``centre_error_px``. Undefined numbers are NaN.
    """
    valid = gt.valid
    pred_index = {int(f): i for i, f in enumerate(track.frames)}
    gt_frames = np.flatnonzero(valid)
    in_track = np.array([f in pred_index for f in gt_frames], bool)
    frames = gt_frames[in_track]
    rows = np.array([pred_index[int(f)] for f in frames], int)
    g = gt.boxes[frames]
    p = track.boxes(rotated=gt.rotated)[rows] if rows.size else np.zeros((0, 5))
    iou = np.zeros(0)
    if rows.size and gt.rotated:
        # A circle's outline has no orientation: compare axis-aligned boxes there, or a tracker that does not
        # measure rotation would lose overlap on a perfectly tracked disc. (Rotated boxes are clipped in Python,
        # about 0.3 ms a frame: only where needed.)
        circle = _circles(gt, frames)
        iou = np.empty(len(rows))
        iou[~circle] = rotated_box_iou(p[~circle], g[~circle])
        if circle.any():
            true_box = g[circle].copy()
            true_box[:, 4] = 0.0  # the bounding box of a circle is its own square, axis-aligned
            iou[circle] = box_iou(rotated_to_aabb(track.boxes(rotated=False)[rows[circle]]),
                                  rotated_to_aabb(true_box))
    elif rows.size:
        iou = box_iou(rotated_to_aabb(p), rotated_to_aabb(g))
    err = centre_error(p[:, :2], g[:, :2]) if rows.size else np.zeros(0)
    curve = success_curve(iou)
    prec = precision_curve(err)

    scale_med = math.nan
    rot_med = None
    lost_rate = off_tracked_rate = math.nan
    if rows.size and len(track.status) == len(track.frames):
        status = np.array(track.status, dtype=object)[rows]
        lost_rate = float(np.mean(status == "lost"))
        tracked = status == "tracked"
        if tracked.any():
            off_tracked_rate = float(np.mean(np.nan_to_num(iou[tracked]) <= 0.0))
    if rows.size:
        ps = track.scale[rows] / track.scale[rows[0]]
        gs = gt.scale[frames] / gt.scale[frames[0]]
        scale_med = _nanmedian(scale_errors(ps, gs))
        if gt.rotation_deg is not None and gt.rotation_period:
            pr = track.rotation_deg[rows]
            if np.isfinite(pr).any():
                pr = pr - pr[0]
                gr = gt.rotation_deg[frames] - gt.rotation_deg[frames[0]]
                rot_med = _nanmedian(rotation_errors(pr, gr, gt.rotation_period))
    return {
        "frames_scored": int(frames.size),
        "frames_missing": int((~in_track).sum()),
        "success_rate": success_rate(err, gt.radius[frames]),
        "auc": auc(curve) if frames.size else math.nan,
        "iou_mean": float(np.mean(np.nan_to_num(iou))) if frames.size else math.nan,
        "precision_20": float(np.mean(np.nan_to_num(err, nan=np.inf) <= PRECISION_PX)) if frames.size else math.nan,
        "centre_error_median_px": _nanmedian(err),
        "scale_error_median_pct": scale_med,
        "rotation_error_median_deg": rot_med,
        "lost_rate": lost_rate,
        "off_tracked_rate": off_tracked_rate,
        "success_curve": curve.tolist(),
        "precision_curve": prec.tolist(),
        "frames": frames.tolist(),
        "iou": iou.tolist(),
        "centre_error_px": err.tolist(),
    }
