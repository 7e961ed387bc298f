"""Geometry of regions of interest: circles and ellipses in pixel coordinates.

Conventions used everywhere in lptrack:

* pixel coordinates, origin at the top-left corner of the frame, x to the right, y **down**;
* angles in degrees, **counter-clockwise as seen on screen**. A direction at angle ``t`` therefore points
  along ``(cos t, -sin t)`` in pixel coordinates (the minus because y grows downwards);
* an ellipse is ``(cx, cy, a, b, angle_deg)`` with semi-axes ``a`` and ``b`` in pixels and ``angle_deg`` the
  direction of axis ``a``; a circle is the ellipse with ``a == b``.

This module needs no OpenCV.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from .errors import RoiError, counted, is_real

_INF = math.inf

ROI_SYNTAX = "'cx,cy,r' (circle) or 'cx,cy,a,b,angle' (ellipse; pixels, angle in degrees counter-clockwise)"
#: Smallest semi-axis (pixels) of a ROI that is tracked (:func:`check_roi_fits`); the parser accepts any above 0.
MIN_TRACKED_SEMI_AXIS = 2.0


@dataclass(frozen=True)
class Ellipse:
    """An ellipse (or circle) in pixel coordinates.

    Parameters
    ----------
    cx, cy : float
        Centre in pixels (x right, y down, origin top-left).
    a, b : float
        Semi-axes in pixels, both > 0. ``a`` lies along ``angle_deg``.
    angle_deg : float
        Direction of axis ``a`` in degrees, counter-clockwise on screen from +x.

    Raises
    ------
    RoiError
        A value is not a finite number, or a semi-axis is not > 0 (a :class:`ValueError` too).
    """

    cx: float
    cy: float
    a: float
    b: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if not (type(self.cx) is float and type(self.cy) is float and type(self.a) is float
                and type(self.b) is float and type(self.angle_deg) is float):
            # Plain floats, whatever numbers were given (a detector's float32, ints): what a tracker's states carry
            # back to the caller, and what json.dumps takes. Not a bool, a 1-element array or a text.
            values = (self.cx, self.cy, self.a, self.b, self.angle_deg)
            if not all(is_real(value) for value in values):
                raise RoiError(f"an ellipse needs numbers (pixels and degrees), got cx, cy, a, b, angle_deg = "
                               f"{', '.join(repr(value) for value in values)}")
            for name, value in zip(("cx", "cy", "a", "b", "angle_deg"), values):
                object.__setattr__(self, name, float(value))
        # Chained comparisons rather than math.isfinite: NaN fails them too, and trackers build an ellipse every
        # frame (with the type test above, about 0.2 us more than the 0.6 us of the dataclass's own __init__).
        if not (0.0 < self.a < _INF and 0.0 < self.b < _INF and -_INF < self.cx < _INF and -_INF < self.cy < _INF
                and -_INF < self.angle_deg < _INF):
            raise RoiError(_invalid_message(self))

    @classmethod
    def circle(cls, cx: float, cy: float, r: float) -> "Ellipse":
        """The circle of radius ``r`` pixels centred on ``(cx, cy)``."""
        return cls(cx, cy, r, r, 0.0)

    @property
    def is_circle(self) -> bool:
        return math.isclose(self.a, self.b, rel_tol=1e-9)

    @property
    def centre(self) -> tuple[float, float]:
        return (self.cx, self.cy)

    @property
    def radius(self) -> float:
        """The larger semi-axis in pixels: the radius of the smallest circle around the ellipse."""
        return max(self.a, self.b)

    def moved(self, cx: float, cy: float, scale: float = 1.0, rotation_deg: float = 0.0) -> "Ellipse":
        """This ellipse with a new centre, semi-axes multiplied by ``scale``, turned by ``rotation_deg`` (CCW)."""
        return Ellipse(cx, cy, self.a * scale, self.b * scale, self.angle_deg + rotation_deg)

    def axis_a_nearest_x(self) -> "Ellipse":
        """The same ellipse written with its axis ``a`` within 45 degrees of +x (``angle_deg`` in (-45, 45]): one
        of the four ways to write it (either axis as ``a``, each way round). This ellipse itself where it is so
        already."""
        if -45.0 < self.angle_deg <= 45.0:
            return self
        angle = self.angle_deg % 180.0  # [0, 180): an axis turned half a turn is the same axis
        if angle > 135.0:
            return Ellipse(self.cx, self.cy, self.a, self.b, angle - 180.0)
        if angle > 45.0:
            return Ellipse(self.cx, self.cy, self.b, self.a, angle - 90.0)
        return Ellipse(self.cx, self.cy, self.a, self.b, angle)

    def axis_direction(self) -> tuple[float, float]:
        """Unit vector of axis ``a`` in pixel coordinates (y down)."""
        t = math.radians(self.angle_deg)
        return (math.cos(t), -math.sin(t))

    def axis_end(self) -> tuple[float, float]:
        """Pixel position of the end of axis ``a`` (the tip of the drawn radius line)."""
        ux, uy = self.axis_direction()
        return (self.cx + self.a * ux, self.cy + self.a * uy)

    def half_extents(self) -> tuple[float, float]:
        """Half width and half height in pixels of the axis-aligned bounding box."""
        t = math.radians(self.angle_deg)
        c, s = math.cos(t), math.sin(t)
        return (math.hypot(self.a * c, self.b * s), math.hypot(self.a * s, self.b * c))

    def bounding_box(self) -> tuple[float, float, float, float]:
        """Axis-aligned bounding box ``(x, y, w, h)`` in pixels, (x, y) the top-left corner."""
        hw, hh = self.half_extents()
        return (self.cx - hw, self.cy - hh, 2 * hw, 2 * hh)

    def boundary_points(self, n: int = 64) -> np.ndarray:
        """``n`` points on the outline as an ``(n, 2)`` float array of (x, y) pixels, counter-clockwise."""
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        u, v = self.a * np.cos(t), self.b * np.sin(t)
        psi = math.radians(self.angle_deg)
        x = self.cx + u * math.cos(psi) - v * math.sin(psi)
        y = self.cy - (u * math.sin(psi) + v * math.cos(psi))
        return np.stack([x, y], axis=1)

    def radius_squared(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Squared elliptical radius of pixel positions ``(x, y)``: 0 at the centre, 1 on the outline."""
        psi = math.radians(self.angle_deg)
        dx, dy = np.asarray(x) - self.cx, -(np.asarray(y) - self.cy)  # to a y-up frame
        u = dx * math.cos(psi) + dy * math.sin(psi)
        v = -dx * math.sin(psi) + dy * math.cos(psi)
        return (u / self.a) ** 2 + (v / self.b) ** 2

    def same_outline(self, other: "Ellipse", tolerance_px: float = 0.05) -> bool:
        """Whether ``other`` traces this outline within ``tolerance_px`` pixels, however each is written
        (either axis as ``a``, angles a half turn apart, a circle at any angle)."""
        if math.hypot(self.cx - other.cx, self.cy - other.cy) > tolerance_px:
            return False
        for e, f in ((self, other), (other, self)):
            x, y = e.boundary_points(32).T
            # (r - 1) * the larger semi-axis bounds the distance of a point at elliptical radius r from f's outline
            if np.max(np.abs(np.sqrt(f.radius_squared(x, y)) - 1.0)) * f.radius > tolerance_px:
                return False
        return True

    def contains(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Boolean mask of which pixel positions ``(x, y)`` lie inside the ellipse."""
        return self.radius_squared(x, y) <= 1.0

    def fraction_inside(self, width: int, height: int, samples: int = 41) -> float:
        """Share of the ellipse's area that lies inside a ``width`` x ``height`` frame (0 to 1)."""
        g = np.linspace(-1.0, 1.0, samples)
        u, v = np.meshgrid(g * self.a, g * self.b)
        inside = (u / self.a) ** 2 + (v / self.b) ** 2 <= 1.0
        psi = math.radians(self.angle_deg)
        x = self.cx + u * math.cos(psi) - v * math.sin(psi)
        y = self.cy - (u * math.sin(psi) + v * math.cos(psi))
        in_frame = (x >= -0.5) & (x <= width - 0.5) & (y >= -0.5) & (y <= height - 0.5)
        return float((inside & in_frame).sum() / max(inside.sum(), 1))

    def to_spec(self) -> str:
        """This ROI in ``--roi`` syntax (``cx,cy,r`` for a circle)."""
        if self.is_circle and self.angle_deg == 0.0:
            return f"{_fmt(self.cx)},{_fmt(self.cy)},{_fmt(self.a)}"
        return f"{_fmt(self.cx)},{_fmt(self.cy)},{_fmt(self.a)},{_fmt(self.b)},{_fmt(self.angle_deg)}"


def _invalid_message(e: Ellipse) -> str:
    """Why ``e`` is not a valid ellipse (it failed the check in ``__post_init__``)."""
    values = {"cx": e.cx, "cy": e.cy, "a": e.a, "b": e.b, "angle_deg": e.angle_deg}
    bad = [f"{name}={value}" for name, value in values.items() if not math.isfinite(value)]
    if bad:
        return f"an ellipse needs finite numbers (pixels and degrees), got {', '.join(bad)}"
    return f"an ellipse's semi-axes must be > 0 pixels, got a={e.a:g}, b={e.b:g}"


def _fmt(value: float) -> str:
    """A number for messages: up to 3 decimals, trailing zeros dropped; huge ones in exponent form (1e+308, not
    309 digits); one that rounds to zero is 0, never -0 (an angle of -0.0001 made a ROI spec '...,-0')."""
    if abs(value) >= 1e15:
        return f"{value:.6g}"
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


#: A number as lptrack reads one from text: a sign, digits with a decimal point or not, an exponent (``12``,
#: ``-3.5``, ``.5``, ``1e3``). What ``float()`` takes beyond that is refused: ``1_40`` (a typo for 140 as often as
#: not), ``nan`` and ``inf`` (no position). A minus sign copied from typeset text (U+2212) is a minus.
_PLAIN_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
#: What :func:`parse_number` accepts, for messages.
NUMBER_RULE = "plain decimals such as 12, -3.5 or 1e3; no '_', nan or inf"


def parse_number(text: str) -> float | None:
    """The number ``text`` holds (spaces around it allowed), or None if it holds none by lptrack's rule
    (:data:`NUMBER_RULE`): a sign, digits with or without a decimal point, an exponent; the typeset minus sign
    (U+2212) as a minus. Underscores (``1_40``), ``nan``, ``inf`` and numbers too large for a float (``1e999``) are
    none."""
    field = str(text).strip().replace("\u2212", "-")
    if not _PLAIN_NUMBER.fullmatch(field):
        return None
    value = float(field)
    return value if math.isfinite(value) else None


def parse_numbers(text: str, what: str, expected: str) -> list[float]:
    """The numbers of the comma-separated list ``text`` (spaces around them allowed), each read by
    :func:`parse_number`: the one reader of a list of numbers given as text (a ROI, a box, points).

    Parameters
    ----------
    text : str
    what : str
        What the list is, for messages (``"ROI"``, ``"box"``).
    expected : str
        What is accepted, for messages (``"x,y,w,h (top-left corner and size in pixels)"``).

    Raises
    ------
    RoiError
        An empty text, numbers not separated by commas, an empty field (a stray comma), or a field that is not a
        number by :data:`NUMBER_RULE` (named in the message). The count of numbers is the caller's to check.
    """
    text = str(text).strip()
    if not text:
        raise RoiError(f"the {what} is empty; expected {expected}")
    fields = [f.strip() for f in text.split(",")]
    if len(fields) == 1 and len(text.replace(";", " ").split()) > 1:
        raise RoiError(f"{what} '{text}': separate the numbers with commas; expected {expected}")
    if "" in fields and len(fields) > 1:
        raise RoiError(f"{what} '{text}' has an empty field (a stray comma?); expected {expected}")
    values = [parse_number(f) for f in fields]
    bad = next((f for f, v in zip(fields, values) if v is None), None)
    if bad is not None:
        if _PLAIN_NUMBER.fullmatch(bad.replace("\u2212", "-")):  # written as a number, beyond a float's range
            raise RoiError(f"{what} '{text}': '{bad}' is too large a number; expected {expected}")
        raise RoiError(f"{what} '{text}' is not a list of numbers: '{bad}' is not a number (give {NUMBER_RULE}); "
                       f"expected {expected}")
    return values


def parse_roi(spec: str) -> Ellipse:
    """Parse a ROI given as ``cx,cy,r`` or ``cx,cy,a,b,angle``.

    Parameters
    ----------
    spec : str
        Comma-separated numbers (spaces allowed): centre and radius in pixels, or centre, semi-axes in pixels
        and the angle of axis ``a`` in degrees counter-clockwise on screen.

    Returns
    -------
    Ellipse

    Raises
    ------
    RoiError
        If the text has the wrong number of fields, a field is not a number by :func:`parse_numbers`'s rule (plain
        decimals, the typeset minus sign as a minus; no ``_``, ``nan`` or ``inf``), or a radius is not > 0.

    Notes
    -----
    The angle may be any finite number of degrees; it is wrapped into (-180, 180].
    """
    values = parse_numbers(spec, "ROI", ROI_SYNTAX)
    if len(values) not in (3, 5):
        raise RoiError(f"ROI '{spec}' has {counted(len(values), 'number')}; expected {ROI_SYNTAX}")
    if len(values) == 3:
        cx, cy, r = values
        if r <= 0:
            raise RoiError(f"ROI '{spec}': radius must be > 0 pixels ({_fmt(MIN_TRACKED_SEMI_AXIS)} or more to track), "
                           f"got {_fmt(r)}")
        return Ellipse.circle(cx, cy, r)
    cx, cy, a, b, angle = values
    if a <= 0 or b <= 0:
        raise RoiError(f"ROI '{spec}': semi-axes must be > 0 pixels ({_fmt(MIN_TRACKED_SEMI_AXIS)} or more to track), "
                       f"got a={_fmt(a)}, b={_fmt(b)}")
    # Any angle names a direction; wrapped here, a huge one (1e308) cannot swamp the rotation added to it later.
    return Ellipse(cx, cy, a, b, wrap_degrees(angle))


def _numbers(values: np.ndarray) -> str:
    """``(300, 250, 64)``: numbers for messages, as _fmt writes them."""
    return "(" + ", ".join(_fmt(float(v)) for v in values[:8]) + (", ..." if len(values) > 8 else "") + ")"


def as_ellipse(roi) -> Ellipse:
    """A ROI as the Python API takes it: an :class:`Ellipse`, a ``--roi`` string (:func:`parse_roi`), or its 3 or
    5 numbers in a sequence (``(cx, cy, r)``, ``(cx, cy, a, b, angle)``: pixels, degrees counter-clockwise).

    Raises
    ------
    RoiError
        Anything else, with what is accepted; 4 numbers (an OpenCV box) are pointed to :func:`ellipse_in_box`.
    """
    if isinstance(roi, Ellipse):
        return roi
    if isinstance(roi, str):
        return parse_roi(roi)
    accepted = f"a ROI is an Ellipse, a string {ROI_SYNTAX}, or those 3 or 5 numbers"
    try:
        values = np.asarray(roi, dtype=np.float64) if roi is not None else None
    except (TypeError, ValueError):
        values = None
        if _looks_like_rotated_rect(roi):
            raise RoiError(f"{roi!r:.60} looks like an OpenCV RotatedRect ((cx, cy), (w, h), angle), whose angle is "
                           f"clockwise on screen: logpolar_track.geometry.ellipse_from_opencv(rect) is the ellipse "
                           f"inside it") from None
    if values is None or values.ndim != 1:
        raise RoiError(f"{accepted}; got {type(roi).__name__} {roi!r:.60}")
    if any(isinstance(v, (bool, np.bool_)) for v in (roi.tolist() if isinstance(roi, np.ndarray) else roi)):
        # As an Ellipse refuses one: True passed as 1 (a flag given where a number was meant).
        raise RoiError(f"{accepted}; got {roi!r:.60}, which holds True or False")
    if len(values) == 4:
        raise RoiError(f"a ROI of 4 numbers {_numbers(values)} looks like an OpenCV box (x, y, w, h); lptrack takes a "
                       f"circle or an ellipse: logpolar_track.geometry.ellipse_in_box(x, y, w, h) is the one inside it")
    if len(values) not in (3, 5):
        raise RoiError(f"{accepted}; got {counted(len(values), 'number')}: {_numbers(values)}")
    return parse_roi(",".join(repr(float(v)) for v in values))


def _looks_like_rotated_rect(roi) -> bool:
    """Whether ``roi`` has the shape of an OpenCV ``RotatedRect``: two pairs and a number."""
    try:
        centre, size, _ = roi
        return len(centre) == 2 and len(size) == 2
    except (TypeError, ValueError):
        return False


def check_roi_fits(roi: Ellipse, width: int, height: int, *, source: str | None = None,
                   min_inside: float = 0.5, min_radius: float = MIN_TRACKED_SEMI_AXIS) -> None:
    """Raise :class:`RoiError` unless ``roi`` is usable on a ``width`` x ``height`` frame.

    A ROI may hang over the border (trackers pad the frame), but its centre must lie in the frame (within its
    outermost pixel centres: 0 to ``width - 1``, 0 to ``height - 1``), at least
    ``min_inside`` of its area must be inside, and its smaller semi-axis must be at least ``min_radius`` pixels.
    """
    where = f"the {width}x{height} frame" + ("" if source is None else f" of {source}")
    # Within the outermost pixel centres, as trackers require of every estimate they report tracked (a centre
    # between them and the frame's edge was accepted here and then reported lost on every frame).
    if not (0 <= roi.cx <= width - 1 and 0 <= roi.cy <= height - 1):
        raise RoiError(f"ROI centre ({_fmt(roi.cx)}, {_fmt(roi.cy)}) lies outside {where}; "
                       f"give a centre with 0 <= cx <= {width - 1} and 0 <= cy <= {height - 1}")
    if min(roi.a, roi.b) < min_radius:
        raise RoiError(f"ROI {roi.to_spec()} is too small to track: semi-axes must be >= {min_radius:g} pixels")
    inside = roi.fraction_inside(width, height)
    if inside < min_inside:
        raise RoiError(f"ROI {roi.to_spec()} lies mostly outside {where} ({inside:.0%} inside); "
                       f"at least {min_inside:.0%} of it must be in the frame")


def ellipse_in_box(x: float, y: float, w: float, h: float) -> Ellipse:
    """The ellipse inscribed in the axis-aligned box with top-left ``(x, y)`` and size ``w`` x ``h`` pixels."""
    return Ellipse(x + w / 2.0, y + h / 2.0, w / 2.0, h / 2.0, 0.0)


def ellipse_in_rotated_rect(cx: float, cy: float, w: float, h: float, angle_deg: float) -> Ellipse:
    """The ellipse inscribed in a rotated rectangle.

    ``w`` lies along ``angle_deg`` (degrees counter-clockwise on screen), ``h`` across it. OpenCV's rotated
    rectangles measure their angle the other way: for one of those use :func:`ellipse_from_opencv`.
    """
    return Ellipse(cx, cy, w / 2.0, h / 2.0, angle_deg)


def ellipse_from_opencv(rotated_rect) -> Ellipse:
    """The ellipse inscribed in an OpenCV ``RotatedRect`` ``((cx, cy), (w, h), angle)``, as ``cv2.fitEllipse``,
    ``cv2.minAreaRect`` and ``cv2.CamShift`` return it: e.g. a ROI from a segmented object's contour.

    OpenCV's ``angle`` turns ``w``'s axis from +x towards +y, which with y down is clockwise on screen; lptrack's
    angles are counter-clockwise, so it is negated (``cv2.ellipse`` and ``cv2.boxPoints`` take it as OpenCV gives it).
    """
    try:
        (cx, cy), (w, h), angle = rotated_rect
        values = [float(v) for v in (cx, cy, w, h, angle)]
    except (TypeError, ValueError):
        raise RoiError(f"an OpenCV RotatedRect is ((cx, cy), (w, h), angle); got {rotated_rect!r:.60}") from None
    cx, cy, w, h, angle = values
    return as_ellipse((cx, cy, w / 2.0, h / 2.0, 0.0 - angle))  # 0.0 - 0.0 is 0.0, where -0.0 would show


def wrap_degrees(angle: float) -> float:
    """``angle`` wrapped into (-180, 180] degrees."""
    # fmod first: it is exact, where adding 180 to a huge angle (1e20) rounds it (280 came out as 100).
    wrapped = math.fmod(angle, 360.0)
    if wrapped > 180.0:
        wrapped -= 360.0
    elif wrapped <= -180.0:
        wrapped += 360.0
    return wrapped


def rotate_screen(vectors, angle_deg: float) -> np.ndarray:
    """Pixel vectors ``(x, y)`` (y down), one ``(2,)`` or many ``(N, 2)``, turned ``angle_deg`` counter-clockwise
    as seen on screen; a new float array of the same shape."""
    t = math.radians(angle_deg)
    c, s = math.cos(t), math.sin(t)
    vectors = np.asarray(vectors, dtype=np.float64)
    if vectors.shape == (2,):  # trackers turn one vector at a time several times a frame: no stacking
        x, y = float(vectors[0]), float(vectors[1])
        return np.array([x * c + y * s, -x * s + y * c])
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([x * c + y * s, -x * s + y * c], axis=-1)
