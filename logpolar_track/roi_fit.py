"""A ROI from what image tools give: an axis-aligned box, a rotated box's corners, or points clicked on the
object's outline.

Headless OpenCV has no ``selectROI``; a box (``x,y,w,h``, as image tools and OTB ground truth give it), the four
corners of a rotated box (as VOT's ground truth gives it) or points on the outline marked in any image viewer are
turned into the ellipse ``lptrack run --roi`` takes (:func:`roi_from_box`, :func:`roi_from_quad`,
:func:`roi_from_points`). Pixels with the origin at the top-left corner, x right, y down, 0-based (OTB's and
UAV123's boxes are 1-based, as Matlab counts: subtract 1 from x and y, or see :func:`from_one_based`); angles in
degrees counter-clockwise as seen on screen. Errors are :class:`~logpolar_track.errors.RoiError`.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from .errors import InputError, RoiError, counted
from .geometry import Ellipse, ellipse_in_box, parse_numbers

#: Default relative tolerance under which a fitted ellipse is reported as a circle: ``(a - b) / a``.
ROUND_TOLERANCE = 0.02
#: What :func:`roi_from_box`, :func:`roi_from_points` and :func:`roi_from_quad` take as text, for messages.
BOX_SYNTAX = "x,y,w,h (top-left corner and size in pixels; ';', tabs or spaces separate too)"
POINTS_SYNTAX = "x1,y1,x2,y2,... (pixels on the object's outline; 'x1,y1;x2,y2;...' too)"
QUAD_SYNTAX = ("x1,y1,x2,y2,x3,y3,x4,y4 (a rotated box's four corners in pixels, in any order; ';', tabs or spaces "
               "separate too)")


def _listed(text: str, what: str, syntax: str) -> list[float]:
    """The numbers of a box's or corners' text: separated by commas or ';', or, in a line with neither, by tabs or
    spaces (as benchmarks' ground-truth files have them: OTB's toy and crossing use tabs)."""
    text = text.replace(";", ",")
    if "," not in text:
        text = ",".join(text.split())
    return parse_numbers(text, what, syntax)


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
        ``"x,y,w,h"`` as image tools give it, in 0-based pixels (OTB's boxes are 1-based: see
        :func:`from_one_based`).
    round_tolerance : float
        A box whose sides differ by at most this fraction of the longer gives a circle ``cx,cy,r`` (r the
        radius of equal area); 0 always gives an ellipse.

    Raises
    ------
    RoiError
        Not 4 numbers (read as :func:`~logpolar_track.geometry.parse_numbers` reads them: plain decimals, no ``_``,
        ``nan`` or ``inf``), or a side <= 0.
    """
    if isinstance(box, str):
        values = _listed(box, "box", BOX_SYNTAX)
    else:
        try:
            values = [float(v) for v in np.asarray(box, float).ravel()]  # 4 numbers, or one row of them (1, 4)
        except (TypeError, ValueError):
            raise RoiError(f"a box is 4 numbers x, y, w, h (pixels); got {box!r:.60}") from None
        if not all(math.isfinite(v) for v in values):
            raise RoiError(f"box {box!r:.80}: a number is not finite")
    if len(values) != 4:
        raise RoiError(f"box '{box}' has {counted(len(values), 'number')}; expected {BOX_SYNTAX}")
    x, y, w, h = values
    if w <= 0 or h <= 0:
        raise RoiError(f"box '{box}': width and height must be > 0 pixels")
    e = ellipse_in_box(x, y, w, h)
    return _rounded(_normalised(e.cx, e.cy, e.a, e.b, e.angle_deg), round_tolerance)


def roi_from_quad(quad, *, round_tolerance: float = ROUND_TOLERANCE) -> Ellipse:
    """The ROI inscribed in a rotated box given by its four corners, as VOT's ground truth gives it.

    Parameters
    ----------
    quad : str or sequence of 8 numbers
        ``"x1,y1,x2,y2,x3,y3,x4,y4"``: the corners in 0-based pixels, in any order. A quadrilateral that is not
        quite a rectangle (drawn by hand, as VOT's are) stands for the smallest rotated rectangle around it
        (``cv2.minAreaRect``), as ``lptrack bench`` and ``eval`` read VOT's ground truth.
    round_tolerance : float
        As :func:`roi_from_box`.

    Returns
    -------
    Ellipse
        The ellipse inscribed in that rectangle, ``a >= b``, the angle of axis ``a`` in (-90, 90] degrees
        counter-clockwise on screen.

    Raises
    ------
    RoiError
        Not 8 numbers, or corners that span no area (all on a line).
    """
    from .evaluate import rect_from_polygon  # where VOT's polygons are read for scoring: the same rectangle

    if isinstance(quad, str):
        values = _listed(quad, "rotated box", QUAD_SYNTAX)
    else:
        try:
            values = [float(v) for v in np.asarray(quad, float).ravel()]  # 8 numbers or (4, 2) corners
        except (TypeError, ValueError):
            raise RoiError("a rotated box's corners must be numbers: 8 of them, or a (4, 2) array") from None
        if not all(math.isfinite(v) for v in values):
            raise RoiError(f"rotated box {quad!r:.80}: a corner is not finite")
    if len(values) != 8:
        raise RoiError(f"rotated box '{quad}' has {counted(len(values), 'number')}; expected {QUAD_SYNTAX}")
    cx, cy, w, h, angle = rect_from_polygon(values)
    if min(w, h) <= 0:
        raise RoiError(f"rotated box '{quad}' spans no area (its corners lie on a line); expected {QUAD_SYNTAX}")
    return _rounded(_normalised(cx, cy, w / 2.0, h / 2.0, angle), round_tolerance)


def roi_from_mask(mask, *, round_tolerance: float = ROUND_TOLERANCE) -> Ellipse:
    """The ellipse with the same second moments as the object in a mask (scikit-image's ``regionprops`` ellipse).

    Parameters
    ----------
    mask : array-like, shape (h, w) or (h, w, channels)
        The object's pixels are those above half the mask's largest value, so that a 0/1 mask, a 0/255 one and one
        saved as JPEG (its edges blurred) give the same object; of a colour mask its brightest colour channel counts,
        of one with an alpha channel that varies (a transparent PNG, a cutout) the alpha. Of several separate regions
        (8-connected), the largest: a segmentation's specks elsewhere would pull the ellipse towards them.
    round_tolerance : float
        As :func:`roi_from_box`.

    Returns
    -------
    Ellipse
        Centred on the region's centroid (pixel centres at whole numbers), with semi-axes twice the square roots of
        its second moments' principal values (each pixel a unit square), so that a filled ellipse gives itself back;
        ``a >= b``, the angle of axis ``a`` in (-90, 90] degrees counter-clockwise on screen.

    Raises
    ------
    RoiError
        Not a 2-D image (or one with channels), not numbers, no pixel above 0, or an object touching all four
        edges (a mask saved inverted).
    """
    try:
        image = np.asarray(mask)
        values = image.astype(np.float64)
    except (TypeError, ValueError):
        raise RoiError("a mask must be an image of numbers: an (h, w) or (h, w, channels) array") from None
    if values.ndim == 3 and values.shape[2] in (1, 2, 3, 4):
        # Grey + alpha (2 channels) or colour + alpha (4): an alpha that varies marks the object, as a cutout's
        # (rembg, an image editor's layer) does whatever colours its pixels have; an opaque one says nothing.
        colours = 1 if values.shape[2] == 2 else min(values.shape[2], 3)
        alpha = values[..., colours] if values.shape[2] in (2, 4) else None
        if alpha is not None and alpha.min() != alpha.max():
            values = alpha
        else:
            values = values[..., :colours].max(axis=2)
    if values.ndim != 2 or min(values.shape) == 0:
        raise RoiError(f"a mask must be an (h, w) or (h, w, channels) image, got shape {image.shape}")
    values = np.nan_to_num(values, nan=0.0, posinf=0.0, neginf=0.0)
    peak = values.max()
    if peak <= 0:
        raise RoiError("the mask is empty: no pixel above 0 marks the object")
    inside = (values > peak / 2).astype(np.uint8)
    _, labels, stats, _ = cv2.connectedComponentsWithStats(inside, connectivity=8)
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    left, top, width, height = (int(v) for v in stats[largest, :4])
    if left == 0 and top == 0 and left + width == values.shape[1] and top + height == values.shape[0]:
        # A mask saved inverted (the object black on white) or one that marks nothing (all white) would give an
        # ellipse around the whole frame, which 'lptrack run' takes without a word.
        raise RoiError(f"the mask's object touches all four edges of the {values.shape[1]}x{values.shape[0]} image; "
                       "mark the object bright on a black background (is the mask inverted?)")
    ys, xs = np.nonzero(labels == largest)
    cx, cy = float(xs.mean()), float(ys.mean())
    # Moments of unit squares, not of their centres: 1/12 on each axis, so that small regions keep their size.
    var_x, var_y = float(np.mean((xs - cx) ** 2)) + 1 / 12, float(np.mean((ys - cy) ** 2)) + 1 / 12
    cov = float(np.mean((xs - cx) * (ys - cy)))
    half_sum, half_diff = (var_x + var_y) / 2, math.hypot((var_x - var_y) / 2, cov)
    a, b = 2 * math.sqrt(half_sum + half_diff), 2 * math.sqrt(max(half_sum - half_diff, 0.0))
    # The major axis' direction in image coordinates turns from +x towards +y, which is down: clockwise on screen.
    angle = -math.degrees(0.5 * math.atan2(2 * cov, var_x - var_y))
    return _rounded(_normalised(cx, cy, a, b, angle), round_tolerance)


def read_mask(path) -> np.ndarray:
    """A mask image from a file as OpenCV reads it, unchanged (8 or 16 bits, grey, colour or with alpha), for
    :func:`roi_from_mask`.

    Raises
    ------
    InputError
        The file is missing or not an image OpenCV reads.
    """
    from .video import opencv_path

    text = opencv_path(path, "mask", InputError)
    # Said as other inputs are (exit 1), not as click's "does not exist" usage error (exit 2).
    if not Path(path).exists():
        raise InputError(f"mask '{path}' not found; give the path of an image of the frame's size")
    if Path(path).is_dir():
        raise InputError(f"mask '{path}' is a folder; give the path of an image of the frame's size")
    image = cv2.imread(text, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise InputError(f"cannot read mask '{path}' as an image (PNG, JPEG, TIFF, BMP, ...)")
    return image


def from_one_based(roi: Ellipse) -> Ellipse:
    """``roi`` read from 1-based coordinates (Matlab's, OTB's and UAV123's boxes: their top-left pixel is (1, 1))
    moved to lptrack's 0-based ones: 1 pixel left and up."""
    return roi.moved(roi.cx - 1.0, roi.cy - 1.0)


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
