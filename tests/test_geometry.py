"""ROI parsing and validation, ellipse geometry: hand-computed values in lptrack's conventions
(pixels, y down, angles counter-clockwise on screen)."""

import math
import re

import numpy as np
import pytest

from logpolar_track.errors import RoiError
from logpolar_track.geometry import Ellipse, check_roi_fits, parse_roi, wrap_degrees


@pytest.mark.parametrize("spec, expected", [
    ("100,80,20", Ellipse(100, 80, 20, 20, 0)),
    (" 100 , 80 , 20 ", Ellipse(100, 80, 20, 20, 0)),
    ("10.5,20.25,30,15,-45", Ellipse(10.5, 20.25, 30, 15, -45)),
    ("1e2,8e1,2e1", Ellipse(100, 80, 20, 20, 0)),
    ("100,80,30,15,\u221245", Ellipse(100, 80, 30, 15, -45)),  # a minus sign copied from typeset text
], ids=["circle", "spaces", "ellipse", "exponent", "typeset-minus"])
def test_parse_roi_accepts(spec, expected):
    assert parse_roi(spec) == expected


@pytest.mark.parametrize("spec, fragment", [
    ("1,2", "has 2 numbers"),
    ("", "is empty"),
    ("1,2,3,4", "has 4 numbers"),
    ("a,b,c", "not a list of numbers"),
    ("1_40,120,30", "not a list of numbers"),
    ("1,2,nan", "'nan' is not a number (give plain decimals"),
    ("1,2,inf", "'inf' is not a number (give plain decimals"),
    ("10,10,0", "radius must be > 0 pixels (2 or more to track), got 0"),
    ("10,10,-5", "radius must be > 0"),
    ("10,10,5,0,30", "semi-axes must be > 0 pixels (2 or more to track), got a=5, b=0"),
], ids=["two", "empty", "four", "letters", "underscore", "nan", "inf", "zero-r", "negative-r", "zero-b"])
def test_parse_roi_rejects_with_message(spec, fragment):
    with pytest.raises(RoiError) as err:
        parse_roi(spec)
    message = str(err.value)
    assert fragment in message
    # Every rejection says what is accepted (except the radius ones, which name the bad value).
    assert "cx,cy" in message or "got" in message


@pytest.mark.parametrize("values, message", [
    ((80, 60, math.nan, 20, 0), "an ellipse needs finite numbers (pixels and degrees), got a=nan"),
    ((math.inf, 60, 20, 20, -math.inf), "an ellipse needs finite numbers (pixels and degrees), got cx=inf, "
                                        "angle_deg=-inf"),
    ((80, 60, 0, 20, 0), "an ellipse's semi-axes must be > 0 pixels, got a=0, b=20"),
    ((80, 60, 20, -1e-6, 0), "an ellipse's semi-axes must be > 0 pixels, got a=20, b=-1e-06"),
], ids=["nan-axis", "inf-centre-and-angle", "zero-axis", "negative-axis"])
def test_ellipse_refuses_non_finite_values_and_non_positive_semi_axes(values, message):
    with pytest.raises(RoiError) as err:
        Ellipse(*values)
    assert str(err.value) == message
    assert isinstance(err.value, ValueError)  # what callers outside lptrack catch


def test_an_ellipse_holds_plain_floats_whatever_numbers_it_is_given():
    """A detector's float32 ROI gave states with float32 fields (json.dumps refused them); a bool, a 1-element
    array or a text was taken as a number, or raised a TypeError."""
    e = Ellipse(np.float32(10.5), np.int64(20), 3, np.float64(2.0), np.float32(30))
    assert all(type(v) is float for v in (e.cx, e.cy, e.a, e.b, e.angle_deg)) and e == Ellipse(10.5, 20, 3, 2, 30)
    for bad in (True, np.array([1.0]), "150", None):
        with pytest.raises(RoiError, match="an ellipse needs numbers"):
            Ellipse(bad, 20.0, 3.0, 2.0)


def test_ellipse_made_from_another_is_checked_too():
    roi = Ellipse.circle(80, 60, 20)
    assert roi.moved(1e6, -1e6, 1e-3, 1e9) == Ellipse(1e6, -1e6, 0.02, 0.02, 1e9)  # odd but finite: kept
    with pytest.raises(RoiError, match="semi-axes must be > 0"):
        roi.moved(80, 60, 0.0)
    with pytest.raises(RoiError, match="got cx=nan"):
        roi.moved(math.nan, 60)
    with pytest.raises(RoiError, match="got a=-5, b=-5"):
        Ellipse.circle(0, 0, -5)


def test_to_spec_round_trips():
    for roi in (Ellipse.circle(12.5, 7, 3), Ellipse(1, 2, 3, 4, 33.25)):
        assert parse_roi(roi.to_spec()) == roi


def test_to_spec_never_writes_minus_zero():
    # 'lptrack frame' named its PNG ...roi_300_200_80_30_-0.png, and 'lptrack roi' could print the same.
    assert parse_roi("300,200,80,30,-0.0001").to_spec() == "300,200,80,30,0"
    assert Ellipse(-0.0002, 5, 3, 2, -0.0004).to_spec() == "0,5,3,2,0"


def test_check_roi_fits_accepts_roi_partly_over_border():
    check_roi_fits(Ellipse.circle(10, 50, 15), 100, 100)  # about 70 % inside


def _share_inside(cx, cy, r, width, height, n=2001):
    """Share of a circle's area within the frame (pixels' outer edges: -0.5 to width - 0.5), on a fine grid."""
    g = np.linspace(-r, r, n)
    x, y = np.meshgrid(cx + g, cy + g)
    disc = (x - cx) ** 2 + (y - cy) ** 2 <= r * r
    framed = (x >= -0.5) & (x <= width - 0.5) & (y >= -0.5) & (y <= height - 0.5)
    return (disc & framed).sum() / disc.sum()


def test_check_roi_fits_wants_half_the_area_inside_and_the_centre_in_the_frame():
    """README: a ROI may hang over the border, but at least half its area lies inside and 0 <= cx, cy."""
    near_corner = Ellipse.circle(7, 7, 20)
    assert _share_inside(7, 7, 20, 100, 100) == pytest.approx(0.528, abs=0.005)
    check_roi_fits(near_corner, 100, 100)  # 53 % inside: accepted
    at_the_edge = Ellipse.circle(0, 50, 20)
    assert _share_inside(0, 50, 20, 100, 100) == pytest.approx(0.516, abs=0.005)
    check_roi_fits(at_the_edge, 100, 100)  # 52 % inside, centre on the first pixel: accepted
    assert _share_inside(5, 5, 20, 100, 100) == pytest.approx(0.447, abs=0.005)
    with pytest.raises(RoiError) as refused:
        check_roi_fits(Ellipse.circle(5, 5, 20), 100, 100, source="a.mp4")
    assert str(refused.value) == ("ROI 5,5,20 lies mostly outside the 100x100 frame of a.mp4 (45% inside); at least "
                                  "50% of it must be in the frame")
    with pytest.raises(RoiError) as refused:
        check_roi_fits(Ellipse.circle(-0.4, 50, 20), 100, 100, source="a.mp4")
    assert str(refused.value) == ("ROI centre (-0.4, 50) lies outside the 100x100 frame of a.mp4; give a centre "
                                  "with 0 <= cx <= 99 and 0 <= cy <= 99")
    with pytest.raises(RoiError, match=r"^ROI centre \(50, -0.4\) lies outside"):
        check_roi_fits(Ellipse.circle(50, -0.4, 20), 100, 100)


@pytest.mark.parametrize("roi, fragment", [
    (Ellipse.circle(120, 50, 10), "centre (120, 50) lies outside the 100x100 frame of a.mp4"),
    (Ellipse.circle(50, -1, 10), "lies outside"),
    (Ellipse.circle(1, 1, 40), "lies mostly outside"),
    (Ellipse(50, 50, 10, 1, 0), "too small"),
    # Beyond the last pixel centre: trackers report such a centre lost on every frame.
    (Ellipse.circle(99.4, 50, 10), "give a centre with 0 <= cx <= 99 and 0 <= cy <= 99"),
], ids=["centre-right", "centre-above", "mostly-outside", "too-thin", "beyond-last-pixel"])
def test_check_roi_fits_rejects(roi, fragment):
    with pytest.raises(RoiError, match=fragment.replace("(", r"\(").replace(")", r"\)")):
        check_roi_fits(roi, 100, 100, source="a.mp4")


@pytest.mark.parametrize("angle, half_w, half_h", [
    (0.0, 20.0, 10.0),
    (90.0, 10.0, 20.0),
    (-90.0, 10.0, 20.0),
    (180.0, 20.0, 10.0),
    # At 45 degrees both half extents are sqrt((a^2 + b^2) / 2).
    (45.0, math.sqrt(250.0), math.sqrt(250.0)),
    # At 30 degrees: sqrt(a^2 cos^2 + b^2 sin^2) and sqrt(a^2 sin^2 + b^2 cos^2).
    (30.0, math.sqrt(400 * 0.75 + 100 * 0.25), math.sqrt(400 * 0.25 + 100 * 0.75)),
])
def test_bounding_box_of_rotated_ellipse(angle, half_w, half_h):
    x, y, w, h = Ellipse(50, 40, 20, 10, angle).bounding_box()
    assert (x, y, w, h) == pytest.approx((50 - half_w, 40 - half_h, 2 * half_w, 2 * half_h), abs=1e-9)


def test_bounding_box_contains_all_boundary_points():
    roi = Ellipse(0, 0, 17, 5, 23)
    x, y, w, h = roi.bounding_box()
    pts = roi.boundary_points(720)
    assert pts[:, 0].min() >= x - 1e-9 and pts[:, 0].max() <= x + w + 1e-9
    assert pts[:, 1].min() == pytest.approx(y, abs=1e-3) and pts[:, 1].max() == pytest.approx(y + h, abs=1e-3)


@pytest.mark.parametrize("angle, end", [
    (0.0, (110.0, 50.0)),     # right
    (90.0, (100.0, 40.0)),    # counter-clockwise on screen: up, i.e. smaller y
    (180.0, (90.0, 50.0)),    # left
    (-90.0, (100.0, 60.0)),   # clockwise: down
])
def test_axis_end_direction(angle, end):
    assert Ellipse(100, 50, 10, 4, angle).axis_end() == pytest.approx(end, abs=1e-9)


def test_boundary_points_go_counter_clockwise_on_screen():
    pts = Ellipse.circle(0, 0, 1).boundary_points(4)
    # Starting at +x, the next point a quarter turn CCW on screen is straight up (y negative).
    assert pts[0] == pytest.approx((1, 0), abs=1e-12)
    assert pts[1] == pytest.approx((0, -1), abs=1e-12)


@pytest.mark.parametrize("roi, expected, tol", [
    (Ellipse.circle(50, 50, 10), 1.0, 0.0),
    # The frame's edge is the outer edge of its border pixels, at -0.5 (pixel centres are integers).
    (Ellipse.circle(-0.5, 50, 10), 0.5, 0.03),       # centre on the left edge: half inside
    (Ellipse.circle(-0.5, -0.5, 10), 0.25, 0.03),    # on a corner: a quarter inside
    (Ellipse(50, -0.5, 30, 5, 90), 0.5, 0.03),       # tall ellipse cut by the top edge
    (Ellipse.circle(-100, 50, 10), 0.0, 0.0),
])
def test_fraction_inside(roi, expected, tol):
    assert roi.fraction_inside(100, 100) == pytest.approx(expected, abs=tol)


def test_contains_follows_rotation():
    roi = Ellipse(0, 0, 10, 2, 90)  # long axis pointing up on screen
    assert roi.contains(0, -9) and not roi.contains(9, 0)


@pytest.mark.parametrize("angle, wrapped", [(0, 0), (180, 180), (-180, 180), (190, -170), (720, 0), (-361, -1),
                                            (540, 180), (-540, 180), (1e20, 280 - 360), (-1e20, 360 - 280)])
def test_wrap_degrees(angle, wrapped):
    assert wrap_degrees(angle) == pytest.approx(wrapped)


@pytest.mark.parametrize("angle, wrapped", [("370", 10.0), ("-90", -90.0), ("-180", 180.0), ("1e308", None)])
def test_parse_roi_wraps_any_angle(angle, wrapped):
    """Any finite angle names a direction: it is kept wrapped into (-180, 180], so that even an absurd one
    (1e308, whose sum with a rotation would lose the rotation) tracks like its wrapped value."""
    roi = parse_roi(f"100,80,30,20,{angle}")
    assert -180 < roi.angle_deg <= 180
    if wrapped is not None:
        assert roi.angle_deg == pytest.approx(wrapped)
    assert roi.angle_deg + 5.0 - roi.angle_deg == pytest.approx(5.0)


def test_same_outline_however_written():
    e = Ellipse(10.0, 20.0, 30.0, 15.0, 200.0)
    assert e.same_outline(Ellipse(10.0, 20.0, 15.0, 30.0, 110.0))  # axes swapped, a quarter turn on
    assert e.same_outline(Ellipse(10.0, 20.0, 30.0, 15.0, -160.0004))  # a half turn off, CSV rounding
    assert Ellipse.circle(1.0, 2.0, 5.0).same_outline(Ellipse(1.0, 2.0, 5.0, 5.0, 33.0))
    assert not e.same_outline(Ellipse(10.1, 20.0, 30.0, 15.0, 200.0))
    assert not e.same_outline(Ellipse(10.0, 20.0, 30.1, 15.0, 200.0))
    assert not e.same_outline(Ellipse(10.0, 20.0, 30.0, 15.0, 201.0))


def test_rotate_screen_turns_counter_clockwise_on_screen():
    from logpolar_track.geometry import rotate_screen

    # +x turned a quarter turn counter-clockwise on screen points up: negative y (y down).
    assert rotate_screen((1.0, 0.0), 90.0) == pytest.approx([0.0, -1.0])
    many = rotate_screen(np.array([[1.0, 0.0], [0.0, 2.0]]), 90.0)
    assert many.shape == (2, 2) and many == pytest.approx(np.array([[0.0, -1.0], [2.0, 0.0]]))


@pytest.mark.parametrize("roi", ["30,40,10", (30, 40, 10), [30.0, 40.0, 10.0], np.array([30, 40, 10]),
                                 Ellipse.circle(30, 40, 10)])
def test_as_ellipse_takes_what_a_python_user_passes(roi):
    from logpolar_track.geometry import as_ellipse

    assert as_ellipse(roi) == Ellipse.circle(30, 40, 10)
    assert as_ellipse((30, 40, 10, 5, 400)) == Ellipse(30, 40, 10, 5, 40)


@pytest.mark.parametrize("roi, fragment", [
    ((10, 20, 30, 40), "looks like an OpenCV box (x, y, w, h); lptrack takes a circle or an ellipse: "
                       "logpolar_track.geometry.ellipse_in_box(x, y, w, h)"),
    ((1, 2), "or those 3 or 5 numbers; got 2 numbers: (1, 2)"),
    (None, "a ROI is an Ellipse, a string"),
    ([[300, 250, 64]], "a ROI is an Ellipse, a string"),
    (object(), "a ROI is an Ellipse, a string"),
    ({"cx": 1}, "a ROI is an Ellipse, a string"),
    ((True, 30, 10), "or those 3 or 5 numbers; got (True, 30, 10), which holds True or False"),  # was cx 1 (fuzzing)
    (np.array([True, True, True]), "which holds True or False"),
    (((300, 250), (120, 70), 20.0), "looks like an OpenCV RotatedRect ((cx, cy), (w, h), angle), whose angle is "
                                    "clockwise on screen: logpolar_track.geometry.ellipse_from_opencv(rect)"),
])
def test_as_ellipse_says_what_is_accepted(roi, fragment):
    from logpolar_track.geometry import as_ellipse

    with pytest.raises(RoiError, match=re.escape(fragment)):
        as_ellipse(roi)


def test_a_huge_number_is_said_in_exponent_form():
    with pytest.raises(RoiError, match=r"^ROI 300,250,1e\+308 lies mostly outside"):
        check_roi_fits(Ellipse.circle(300, 250, 1e308), 640, 480)


def test_an_opencv_rotated_rect_gives_the_ellipse_inside_it_turned_counter_clockwise():
    import cv2

    from logpolar_track.geometry import ellipse_from_opencv

    # An ellipse turned 20 degrees counter-clockwise on screen: its long axis rises to the right (y down).
    truth = Ellipse(250, 240, 60, 35, 20)
    assert truth.axis_end()[1] < truth.cy
    points = truth.boundary_points(90).astype(np.float32)
    for rect in (cv2.fitEllipse(points), cv2.minAreaRect(points)):
        assert ellipse_from_opencv(rect).same_outline(truth, tolerance_px=0.5)
    # OpenCV's own angle is the other way round: taken as lptrack's, the outline would be mirrored.
    (cx, cy), (w, h), angle = cv2.fitEllipse(points)
    assert not Ellipse(cx, cy, w / 2, h / 2, angle).same_outline(truth, tolerance_px=5)
    with pytest.raises(RoiError, match=r"an OpenCV RotatedRect is \(\(cx, cy\), \(w, h\), angle\); got"):
        ellipse_from_opencv((1, 2, 3))
    with pytest.raises(RoiError, match="semi-axes|positive|greater than 0"):
        ellipse_from_opencv(((10, 10), (0, 5), 0))
