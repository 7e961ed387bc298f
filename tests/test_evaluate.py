"""Metrics and ground-truth readers of logpolar_track.evaluate, on cases computed by hand."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from logpolar_track.errors import UsageError
from logpolar_track.evaluate import (GroundTruth, GroundTruthError, Track, auc, box_iou, ground_truth_from_boxes,
                                     ground_truth_from_ellipses, ground_truth_from_rects, precision_curve,
                                     read_box_text, read_gt_csv, read_run_csv, read_track_csv, rect_from_polygon,
                                     rotated_box_corners, rotated_box_iou, rotated_to_aabb, rotation_errors,
                                     scale_errors, score_track, success_curve, success_rate, unwrap_rects)


# ---------------------------------------------------------------------------------------------- IoU

def test_box_iou_hand_computed():
    a = np.array([[0, 0, 2, 2], [0, 0, 2, 2], [0, 0, 2, 2], [0, 0, 4, 4]], float)
    b = np.array([[1, 0, 2, 2], [5, 5, 1, 1], [0, 0, 2, 2], [1, 1, 2, 2]], float)
    # overlap 1x2=2, union 4+4-2=6 -> 1/3; disjoint; identical; contained 4/16.
    np.testing.assert_allclose(box_iou(a, b), [1 / 3, 0.0, 1.0, 0.25])


def test_a_box_overlaps_itself_at_one_exactly():
    # Its own area, subtracted from twice itself, came out a rounding error over it: IoU 1.0000000000009, which a
    # success curve's last threshold counts, so a perfect track scored 1.0 or 20/21 as rounding fell.
    box = np.array([497.1, 497.1, 0.1, 0.1])
    assert box_iou(box, box)[0] == 1.0
    assert auc(success_curve(box_iou(np.tile(box, (5, 1)), np.tile(box, (5, 1))))) == pytest.approx(20 / 21)


def test_box_iou_nan_rows_are_nan():
    out = box_iou([[0, 0, 2, 2], [np.nan] * 4], [[0, 0, 2, 2], [0, 0, 1, 1]])
    assert out[0] == 1.0 and math.isnan(out[1])


def test_rotated_iou_square_and_its_45_degree_turn():
    # Two 2x2 squares on one centre, one turned 45 deg: the overlap is a regular octagon of area 8(sqrt2 - 1).
    inter = 8 * (math.sqrt(2) - 1)
    expected = inter / (8 - inter)
    np.testing.assert_allclose(rotated_box_iou([0, 0, 2, 2, 0], [0, 0, 2, 2, 45]), [expected], rtol=1e-9)


def test_rotated_iou_symmetries_of_a_rectangle():
    base = [10, 20, 8, 2, 30]
    same = [[10, 20, 8, 2, 210], [10, 20, 2, 8, 120], [10, 20, 8, 2, -150]]
    np.testing.assert_allclose(rotated_box_iou([base] * 3, same), [1, 1, 1], atol=1e-9)
    # A quarter turn of a thin 8x2 bar on its centre: overlap 2x2=4, union 16+16-4=28.
    np.testing.assert_allclose(rotated_box_iou(base, [10, 20, 8, 2, 120]), [4 / 28], rtol=1e-9)


def test_rotated_iou_matches_axis_aligned_iou_at_angle_zero():
    rng = np.random.default_rng(3)
    xy = rng.uniform(0, 20, (50, 2))
    wh = rng.uniform(1, 15, (50, 2))
    a = np.column_stack([xy, wh])
    b = np.column_stack([xy + rng.uniform(-8, 8, (50, 2)), wh * rng.uniform(0.5, 1.5, (50, 2))])
    rot = lambda boxes: np.column_stack([boxes[:, :2] + boxes[:, 2:] / 2, boxes[:, 2:], np.zeros(len(boxes))])
    np.testing.assert_allclose(rotated_box_iou(rot(a), rot(b)), box_iou(a, b), atol=1e-9)


def test_rotated_box_corners_follow_the_ccw_on_screen_convention():
    # Side w (length 4) at 90 deg CCW on screen points up (-y): corners at y = cy -/+ 2, x = cx -/+ 1.
    corners = rotated_box_corners([10, 10, 4, 2, 90])
    np.testing.assert_allclose(sorted(corners[:, 0]), [9, 9, 11, 11], atol=1e-12)
    np.testing.assert_allclose(sorted(corners[:, 1]), [8, 8, 12, 12], atol=1e-12)
    # At 30 deg the w side's direction is (cos 30, -sin 30): up and to the right.
    c = rotated_box_corners([0, 0, 2, 1e-9, 30])
    d = c[0] - c[1]
    np.testing.assert_allclose(d / np.hypot(*d), [math.cos(math.radians(30)), -math.sin(math.radians(30))])


# ---------------------------------------------------------------------------- polygons and unwrapping

def _polygon(cx, cy, w, h, angle):
    return rotated_box_corners([cx, cy, w, h, angle])


@pytest.mark.parametrize("order", [(0, 1, 2, 3), (2, 3, 0, 1), (1, 0, 3, 2), (3, 2, 1, 0)])
def test_rect_from_polygon_recovers_the_rectangle_in_any_corner_order(order):
    poly = _polygon(50, 40, 30, 12, 25)[list(order)]
    cx, cy, w, h, angle = rect_from_polygon(poly)
    assert (cx, cy) == pytest.approx((50, 40), abs=1e-3)
    # Same rectangle up to the symmetries: compare by IoU.
    assert rotated_box_iou([cx, cy, w, h, angle], [50, 40, 30, 12, 25])[0] == pytest.approx(1, abs=1e-4)


def test_unwrap_rects_follows_two_turns_whatever_the_fit_reports():
    truth = np.arange(0, 720, 17.0)  # 17 deg per frame counter-clockwise, over two turns
    rng = np.random.default_rng(0)
    rects = []
    for t in truth:
        k = int(rng.integers(0, 4))  # report an equivalent variant: +90k, sides swapped for odd k
        w, h = (30.0, 12.0) if k % 2 == 0 else (12.0, 30.0)
        rects.append((0, 0, w, h, t + 90 * k - 360 * int(rng.integers(-1, 2))))
    out = unwrap_rects(np.array(rects))
    np.testing.assert_allclose(out[:, 4], truth, atol=1e-9)
    np.testing.assert_allclose(out[:, 2:4], np.tile([30.0, 12.0], (len(truth), 1)))


def test_unwrap_rects_first_rect_long_side_first_and_nan_rows_kept():
    out = unwrap_rects(np.array([[0, 0, 5, 10, 170], [np.nan] * 5, [0, 0, 10, 5, 265]]))
    assert out[0, 2] == 10 and out[0, 3] == 5 and out[0, 4] == pytest.approx(80)  # 170+90=260 -> 80
    assert np.isnan(out[1]).all()
    assert out[2, 4] == pytest.approx(85)


# ---------------------------------------------------------------------------------- curves and rates

def test_success_curve_and_auc_of_a_known_set():
    curve = success_curve(np.array([0.0, 0.5, 1.0]))
    assert len(curve) == 21
    # t = 0, 0.05, ..., 0.45 (10 thresholds): 2 of 3 above; t = 0.5..0.95 (10): 1 of 3; t = 1: none.
    np.testing.assert_allclose(curve[:10], 2 / 3)
    np.testing.assert_allclose(curve[10:20], 1 / 3)
    assert curve[20] == 0
    assert auc(curve) == pytest.approx(10 / 21)
    # A perfect tracker scores 20/21 under OTB's strict "IoU > t" at the 21 thresholds.
    assert auc(success_curve(np.ones(7))) == pytest.approx(20 / 21)


def test_precision_and_success_rate():
    errors = np.array([0.0, 10.0, 20.0, 30.0, np.nan])
    curve = precision_curve(errors)
    assert curve[20] == pytest.approx(3 / 5)  # at most 20 px; NaN counts as a miss
    assert curve[0] == pytest.approx(1 / 5)
    assert success_rate(np.array([1.0, 3.0, 2.4]), np.array([10.0, 10.0, 10.0])) == pytest.approx(2 / 3)


def test_edge_inputs_give_nan_or_an_error_not_numpy_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning would fail here
        assert np.isnan(scale_errors(np.array([1.0, 1.1]), np.array([0.0, 1.0]))[0])
        assert math.isnan(auc(np.array([])))
        with pytest.raises(UsageError, match="period must be a number of degrees > 0"):
            rotation_errors(np.array([170.0]), np.array([-10.0]), 0)


def test_scale_and_rotation_errors():
    np.testing.assert_allclose(scale_errors([1.1, 0.9, 2.0], [1.0, 1.0, 2.5]), [10, 10, 20])
    # Unwrapped, full turn known: a missed turn costs 360 degrees.
    np.testing.assert_allclose(rotation_errors([370.0, -5.0], [10.0, 5.0]), [360, 10])
    # Rectangle ground truth (180-symmetric): modulo 180, in [0, 90].
    np.testing.assert_allclose(rotation_errors([190.0, 100.0, -95.0], [10.0, 0.0, 0.0], 180), [0, 80, 85])


# ------------------------------------------------------------------------------------------- scoring

def _ellipse_track(ellipses, scale, rotation):
    e = np.asarray(ellipses, float)
    return Track(np.arange(len(e)), e, np.asarray(scale, float), np.asarray(rotation, float), np.ones(len(e)))


def test_score_track_perfect_rotating_ellipse():
    n = 30
    rot = np.linspace(0, 400, n)  # more than a turn
    scale = np.linspace(1, 2, n)
    e = np.column_stack([np.linspace(50, 80, n), np.full(n, 40), 20 * scale, 10 * scale, 15 + rot])
    gt = ground_truth_from_ellipses(e, scale, rot)
    m = score_track(gt, _ellipse_track(e, scale, rot))
    assert m["frames_scored"] == n and m["success_rate"] == 1.0
    assert m["auc"] == pytest.approx(20 / 21)
    assert m["centre_error_median_px"] == 0 and m["scale_error_median_pct"] == pytest.approx(0, abs=1e-9)
    assert m["rotation_error_median_deg"] == pytest.approx(0, abs=1e-9)


def test_score_track_errors_are_measured():
    n = 10
    e = np.tile([50.0, 40, 20, 20, 0], (n, 1))
    gt = ground_truth_from_ellipses(e, np.ones(n), np.zeros(n))
    moved = e.copy()
    moved[:, 0] += 3.0  # 3 px off: below 25 % of the 20 px radius (5 px)
    track = _ellipse_track(moved, np.full(n, 1.0), np.r_[0.0, np.full(n - 1, 360.0 + 4)])
    m = score_track(gt, track)
    assert m["success_rate"] == 1.0 and m["centre_error_median_px"] == pytest.approx(3)
    assert m["rotation_error_median_deg"] == pytest.approx(364)  # an extra turn is an error, unwrapped
    moved[:, 0] += 3.0  # 6 px: a failure
    assert score_track(gt, _ellipse_track(moved, np.ones(n), np.zeros(n)))["success_rate"] == 0.0


def test_score_track_axis_aligned_gt_compares_ellipse_bounding_box():
    gt = ground_truth_from_boxes(np.array([[10.0, 10, 20, 40]]))
    # Ellipse with a=20, b=10 turned 90 deg: its bounding box is 20 wide, 40 high = the ground-truth box.
    track = _ellipse_track([[20.0, 30, 20, 10, 90]], [1.0], [np.nan])
    m = score_track(gt, track)
    assert m["iou"][0] == pytest.approx(1.0)
    assert m["rotation_error_median_deg"] is None


def test_score_track_circle_ground_truth_ignores_orientation_of_the_box():
    n = 4
    rot = np.array([0.0, 30, 45, 60])
    circle = np.column_stack([np.full(n, 50.0), np.full(n, 40), np.full(n, 10), np.full(n, 10), rot])
    gt = ground_truth_from_ellipses(circle, np.ones(n), rot)
    # A box tracker (no rotation) that finds the disc exactly: full overlap on every frame.
    still = circle.copy()
    still[:, 4] = 0.0
    assert score_track(gt, _ellipse_track(still, np.ones(n), np.full(n, np.nan)))["iou"] == pytest.approx([1] * n)
    # The same for an ellipse ground truth is a rotated-box comparison: turning it 45 deg off costs overlap.
    ell = circle.copy()
    ell[:, 3] = 5.0
    flat = ell.copy()
    flat[:, 4] = 0.0
    gt_ellipse = ground_truth_from_ellipses(ell, np.ones(n), rot)
    iou = score_track(gt_ellipse, _ellipse_track(flat, np.ones(n), np.zeros(n)))["iou"]
    assert iou[0] == pytest.approx(1) and iou[2] < 0.6


def test_score_track_skips_unscored_and_missing_frames():
    boxes = np.tile([0.0, 0, 10, 10], (6, 1))
    boxes[2] = np.nan
    gt = ground_truth_from_boxes(boxes)
    track = _ellipse_track(np.tile([5.0, 5, 5, 5, 0], (4, 1)), np.ones(4), np.full(4, np.nan))  # frames 0..3
    m = score_track(gt, track)
    assert m["frames"] == [0, 1, 3] and m["frames_missing"] == 2


def test_score_track_says_how_often_tracked_is_wrong():
    boxes = np.tile([0.0, 0, 10, 10], (7, 1))
    boxes[5] = np.nan  # not scored, whatever its status
    gt = ground_truth_from_boxes(boxes)
    on, touching, off = [5.0, 5, 5, 5, 0], [14.0, 5, 5, 5, 0], [40.0, 40, 5, 5, 0]
    track = _ellipse_track([on, on, off, off, touching, off, on], np.ones(7), np.full(7, np.nan))
    track.status = ["init", "tracked", "tracked", "lost", "tracked", "tracked", "tracked"]
    m = score_track(gt, track)
    assert m["frames_scored"] == 6
    assert m["lost_rate"] == pytest.approx(1 / 6)
    # Of the 4 scored frames reported tracked, one misses the box (frame 2); frame 4 only overlaps it a little.
    assert m["off_tracked_rate"] == pytest.approx(1 / 4)
    track.status = []  # a track without statuses (another tool's CSV without the column) has no such figures
    m = score_track(gt, track)
    assert math.isnan(m["lost_rate"]) and math.isnan(m["off_tracked_rate"])
    track.status = ["init", "lost", "lost", "lost", "lost", "lost", "lost"]
    m = score_track(gt, track)
    assert m["lost_rate"] == pytest.approx(5 / 6) and math.isnan(m["off_tracked_rate"])


# ----------------------------------------------------------------------------------------- readers

@pytest.mark.parametrize("sep", [",", "\t", " "])
def test_read_box_text_separators_nan_and_one_based(tmp_path, sep):
    p = tmp_path / "groundtruth_rect.txt"
    lines = [sep.join(["11", "21", "30", "40"]), sep.join(["NaN"] * 4), sep.join(["12", "22", "0", "0"]), ""]
    p.write_text("\r\n".join(lines))
    gt = read_box_text(p)
    assert gt.source == "otb" and not gt.rotated and len(gt) == 3
    assert gt.valid.tolist() == [True, False, False]  # NaN line, zero-size box: unscored
    np.testing.assert_allclose(gt.boxes[0], [10 + 15, 20 + 20, 30, 40, 0])  # 1-based -> 0-based centre
    roi = gt.initial_roi()
    assert (roi.cx, roi.cy, roi.a, roi.b, roi.angle_deg) == (25, 40, 15, 20, 0)


def test_read_box_text_vot_polygons(tmp_path):
    p = tmp_path / "groundtruth.txt"
    rows = []
    for i, angle in enumerate([10, 30, 50, 70, 90, 110]):
        poly = _polygon(100, 80, 40, 20, angle)[[(i + k) % 4 for k in range(4)]]  # corner order varies
        rows.append(",".join(f"{v:.4f}" for v in poly.ravel()))
    rows.insert(3, "NaN,NaN,NaN,NaN,NaN,NaN,NaN,NaN")
    p.write_text("\n".join(rows) + "\n")
    gt = read_box_text(p)
    assert gt.source == "vot" and gt.rotated and gt.rotation_period == 180
    valid = gt.valid
    assert valid.tolist() == [True, True, True, False, True, True, True]
    np.testing.assert_allclose(gt.boxes[valid, 4], [10, 30, 50, 70, 90, 110], atol=1e-3)
    np.testing.assert_allclose(gt.rotation_deg[valid], [0, 20, 40, 60, 80, 100], atol=1e-3)
    np.testing.assert_allclose(gt.boxes[valid, 2:4], np.tile([40, 20], (6, 1)), atol=1e-3)
    roi = gt.initial_roi()
    assert (roi.a, roi.b, roi.angle_deg) == pytest.approx((20, 10, 10), abs=1e-3)


def test_read_box_text_rejects_bad_lines(tmp_path):
    p = tmp_path / "x.txt"
    p.write_text("1,2,3\n")
    with pytest.raises(GroundTruthError, match="expected 4"):
        read_box_text(p)
    p.write_text("1,2,three,4\n")
    with pytest.raises(GroundTruthError, match="line 1"):
        read_box_text(p)


def test_read_box_text_refuses_a_binary_file_in_one_clean_line_and_reads_utf16(tmp_path):
    # An image given as the ground truth (`lptrack eval run.csv img/0001.jpg`) was decoded with replacement
    # characters, and its first 60 bytes, NULs and control characters included, printed in the error line.
    jpeg = tmp_path / "0001.jpg"
    jpeg.write_bytes(b"\xff\xd8\xff\xe0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00\xff\xdb\x00C\x00\x02")
    with pytest.raises(GroundTruthError) as info:
        read_box_text(jpeg)
    assert str(info.value) == (f"cannot read ground truth '{jpeg}': not a text file (UTF-8, or UTF-16 with a "
                               f"byte-order mark); expected one x,y,w,h or x1,y1,...,x4,y4 line per frame")
    # UTF-16 without a byte-order mark: a NUL after each ASCII character.
    (tmp_path / "nobom.txt").write_bytes("11,21,30,40\n".encode("utf-16-le"))
    with pytest.raises(GroundTruthError, match="not a text file"):
        read_box_text(tmp_path / "nobom.txt")
    # With one, as Windows tools save text, it is read.
    (tmp_path / "groundtruth_rect.txt").write_bytes("11,21,30,40\r\n12,22,30,40\r\n".encode("utf-16"))
    gt = read_box_text(tmp_path / "groundtruth_rect.txt")
    np.testing.assert_allclose(gt.boxes[:, :4], [[25, 40, 30, 40], [26, 41, 30, 40]])


def test_a_run_csv_saved_as_utf16_is_read_and_a_binary_one_refused(tmp_path):
    # A run's CSV re-saved by a Windows tool as "Unicode text" (UTF-16 with a byte-order mark) was "not a text
    # file" for eval, plot and sheet, while a .roi file or ground truth so saved is read.
    text = ("frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status\r\n"
            "0,0.000000,50.000,40.000,20.000,10.000,30.000,1.00000,0.000,1.0000,init\r\n"
            "1,0.040000,51.000,40.000,20.000,10.000,31.000,1.00000,1.000,0.9000,tracked\r\n")
    utf8, utf16 = tmp_path / "a.csv", tmp_path / "b.csv"
    utf8.write_text(text, newline="")
    utf16.write_bytes(text.encode("utf-16"))
    a, b = read_run_csv(utf8), read_run_csv(utf16)
    assert b.frames.tolist() == a.frames.tolist() == [0, 1] and b.status == a.status
    np.testing.assert_array_equal(b.ellipses, a.ellipses)
    binary = tmp_path / "c.csv"
    binary.write_bytes(b"frame\x00\x01\x02")
    with pytest.raises(GroundTruthError) as info:
        read_run_csv(binary)
    assert str(info.value) == (f"cannot read run CSV '{binary}': not a text file (UTF-8, or UTF-16 with a "
                               f"byte-order mark)")


def test_read_gt_csv_and_run_csv(tmp_path):
    gt_path = tmp_path / "s.gt.csv"
    gt_path.write_text("frame,cx,cy,a,b,angle_deg,scale,rotation_deg\n"
                       "0,50,40,20,10,30,1,0\n1,51,40,22,11,40,1.1,10\n3,52,41,24,12,400,1.2,370\n")
    gt = read_gt_csv(gt_path)
    assert len(gt) == 4 and gt.valid.tolist() == [True, True, False, True]  # frame 2 has no row
    assert gt.rotation_deg[3] == 370 and gt.scale[1] == pytest.approx(1.1)
    np.testing.assert_allclose(gt.radius[0], math.sqrt(20 * 10))
    run = tmp_path / "run.csv"
    run.write_text("frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status\n"
                   "0,0,50,40,20,10,30,1,,1,init\n1,0.04,52,40,22,11,40,1.1,,0.9,tracked\n")
    track = read_track_csv(run)
    assert track.frames.tolist() == [0, 1] and np.isnan(track.rotation_deg).all()
    m = score_track(gt, track)
    assert m["frames_scored"] == 2 and m["centre_error_median_px"] == pytest.approx(0.5)
    assert m["lost_rate"] == 0.0 and m["off_tracked_rate"] == 0.0
    # Another tool's file, its columns in any order, without statuses: scored, how often it was lost not known;
    # plot and sheet, which draw statuses and times, refuse it.
    run.write_text("angle_deg,frame,cx,cy,a,b\n30,0,50,40,20,10\n30,1,90,40,20,10\n")
    m = score_track(gt, read_track_csv(run))
    assert m["frames_scored"] == 2 and math.isnan(m["lost_rate"]) and math.isnan(m["off_tracked_rate"])
    assert read_track_csv(run).scale.tolist() == [1.0, 1.0]
    # Its size is its axes: a scale it does not give is the size ratio to the first row (not 1, a claim that the
    # object kept its size), one it gives is taken as given.
    sized = tmp_path / "sized.csv"
    sized.write_text("frame,cx,cy,a,b,angle_deg,scale\n0,50,40,20,10,30,\n1,50,40,40,20,30,n/a\n2,50,40,40,20,30,3\n")
    assert read_track_csv(sized).scale.tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(GroundTruthError, match="has the header 'angle_deg,frame,cx,cy,a,b'; expected an lptrack run "
                                               "CSV with the header frame,time_s,.*JSON lines$"):
        read_run_csv(run)
    # Its values are checked as a run's are.
    for body, said in (("30,0,50,nan,20,10", "cy 'nan' is not a number"), ("30,0,50,40,-2,10", "a '-2' is not a "
                       "number > 0"), ("30,0.0,50,40,20,10", "frame '0.0' is not a frame index")):
        run.write_text(f"angle_deg,frame,cx,cy,a,b\n{body}\n")
        with pytest.raises(GroundTruthError, match=f"line 2: {said}"):
            read_track_csv(run)
    # What it does not give may be empty, nan or n/a; a status column left empty throughout is none, one mixing
    # statuses with empty fields is refused.
    run.write_text("frame,cx,cy,a,b,angle_deg,time_s,scale,rotation_deg,score,status,video\n"
                   "0,50,40,20,10,30,,n/a,nan,,,clip.mp4\n")
    track = read_track_csv(run)
    assert np.isnan([track.rotation_deg[0], track.score[0]]).all() and track.status == [] and track.scale[0] == 1
    run.write_text("frame,cx,cy,a,b,angle_deg,status\n0,50,40,20,10,30,tracked\n1,50,40,20,10,30,\n")
    with pytest.raises(GroundTruthError, match="line 3: status '' is not one of init, tracked, lost"):
        read_track_csv(run)
    run.write_text("frame,cx,cy,a,b,angle\n0,50,40,20,10,30\n")
    with pytest.raises(GroundTruthError, match="lacks column\\(s\\) angle_deg; expected an lptrack run CSV"):
        read_track_csv(run)
    # Frame numbers beyond int64 (a table's) are no frame index, not an overflow.
    run.write_text("frame,cx,cy,a,b,angle_deg\n0,50,40,20,10,30\n9223372036854775808,50,40,20,10,30\n")
    with pytest.raises(GroundTruthError, match="line 3: frame '9223372036854775808' is not a frame index"):
        read_track_csv(run)


def test_another_tools_stream_is_chosen_from_by_its_video_column_anywhere(tmp_path):
    """eval found a 'video' column anywhere in another tool's header; the one reader looked only at the first."""
    run = tmp_path / "other.csv"
    for name in ("a.mp4", "b.mp4"):
        (tmp_path / name).write_bytes(b"")  # a video named by the column is a file beside the stream
    lines = [f"{k},{50 + k},40,20,10,30,{name}" for name in ("a.mp4", "b.mp4") for k in range(3)]
    run.write_text("frame,cx,cy,a,b,angle_deg,video\n" + "\n".join(lines) + "\n")
    assert read_track_csv(run, tmp_path / "b.mp4").frames.tolist() == [0, 1, 2]
    with pytest.raises(GroundTruthError, match="holds the rows of 2 videos"):
        read_track_csv(run)
    run.write_text("frame,cx,cy,a,b,angle_deg,video\n" + "\n".join(lines[:3]) + "\n")
    # One video: scored without --video, but a --video naming another is refused (it scored the wrong rows).
    assert len(read_track_csv(run).frames) == 3
    with pytest.raises(GroundTruthError, match="holds the rows of 'a.mp4' only \\(its 'video' column\\), not of"):
        read_track_csv(run, tmp_path / "b.mp4")
    assert len(read_track_csv(run, tmp_path / "b.mp4", only_if_several=True).frames) == 3
    (tmp_path / "bad.csv").write_text("frame,cx\n0,1\n")
    with pytest.raises(GroundTruthError, match="lacks column"):
        read_gt_csv(tmp_path / "bad.csv")


@pytest.mark.parametrize("broken, message", [
    ("1,0.04,52,40,22,11,40,1.1", "line 3 has 8 fields; expected 11"),  # cut short, as head -c leaves it
    ("1,0.04,abc,40,22,11,40,1.1,,0.9,tracked", "line 3: cx 'abc' is not a number"),
    ("1.5,0.04,52,40,22,11,40,1.1,,0.9,tracked", r"line 3: frame '1.5' is not a frame index"),
    ("-1,0.04,52,40,22,11,40,1.1,,0.9,tracked", r"line 3: frame '-1' is not a frame index \(integer >= 0\)")])
def test_a_broken_run_csv_is_refused_naming_its_line(tmp_path, broken, message):
    run = tmp_path / "run.csv"
    run.write_text("frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status\n"
                   f"0,0,50,40,20,10,30,1,,1,init\n{broken}\n")
    with pytest.raises(GroundTruthError, match=message):
        read_track_csv(run)


def test_run_data_reads_the_same_as_csv_or_json_lines(tmp_path):
    """``lptrack run --format jsonl`` output is scored like its CSV (``null`` rotation as NaN); a line that is not
    a JSON object is named by its line number."""
    from logpolar_track.results import COLUMNS, json_line

    rows = [["0", "0.000000", "50.000", "40.000", "20.000", "10.000", "30.000", "1.00000", "", "1.0000", "init"],
            ["1", "0.040000", "52.500", "40.000", "22.000", "11.000", "40.000", "1.10000", "", "0.9000", "tracked"]]
    as_csv, as_jsonl = tmp_path / "run.csv", tmp_path / "run.jsonl"
    as_csv.write_text(",".join(COLUMNS) + "\n" + "".join(",".join(r) + "\n" for r in rows))
    as_jsonl.write_text("".join(json_line(r) for r in rows))
    a, b = read_track_csv(as_csv), read_track_csv(as_jsonl)
    assert b.frames.tolist() == [0, 1] and b.status == ["init", "tracked"]
    for field in ("ellipses", "scale", "rotation_deg", "score"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert np.isnan(b.rotation_deg).all()
    as_jsonl.write_text(json_line(rows[0]) + "not json\n")
    with pytest.raises(GroundTruthError, match="line 2 is not a JSON object"):
        read_track_csv(as_jsonl)


def test_gt_csv_without_rotation_unwraps_the_angles_and_scores_them_modulo_half_a_turn(tmp_path):
    """A ground truth spinning past 180 degrees, written within (-180, 180] and without the rotation column:
    a perfect track scores no rotation error (the angles jumped by 360 and scored 360 off), and the column, where
    given, is still scored in full."""
    n = 60
    turn = 8.0 * np.arange(n)  # to 472 degrees counter-clockwise
    angle = (30.0 + turn + 180.0) % 360.0 - 180.0
    rows = [f"{k},{100 + k},80,40,25,{float(angle[k])!r},1,{float(turn[k])!r}" for k in range(n)]
    with_turn, without = tmp_path / "a.gt.csv", tmp_path / "b.gt.csv"
    with_turn.write_text("frame,cx,cy,a,b,angle_deg,scale,rotation_deg\n" + "\n".join(rows) + "\n")
    without.write_text("frame,cx,cy,a,b,angle_deg\n" + "\n".join(r.rsplit(",", 2)[0] for r in rows) + "\n")
    ellipses = np.array([[100 + k, 80, 40, 25, 30 + turn[k]] for k in range(n)], float)
    perfect = Track(np.arange(n), ellipses, np.ones(n), turn.copy(), np.ones(n), ["tracked"] * n)
    # From frame 20 on, half a turn off (as a tracker fooled by a symmetric object would be).
    half_turn_off = Track(np.arange(n), ellipses, np.ones(n), turn + 180.0 * (np.arange(n) >= 20), np.ones(n),
                          ["tracked"] * n)
    full, modulo = read_gt_csv(with_turn), read_gt_csv(without)
    assert (full.rotation_period, modulo.rotation_period) == (360.0, 180.0)
    np.testing.assert_allclose(modulo.rotation_deg, turn)
    assert score_track(modulo, perfect)["rotation_error_median_deg"] == pytest.approx(0.0, abs=1e-9)
    assert score_track(full, perfect)["rotation_error_median_deg"] == pytest.approx(0.0, abs=1e-9)
    # Half a turn off is the same ellipse: no error modulo 180, the whole of it where the turn is known.
    assert score_track(modulo, half_turn_off)["rotation_error_median_deg"] == pytest.approx(0.0, abs=1e-9)
    assert score_track(full, half_turn_off)["rotation_error_median_deg"] == pytest.approx(180.0)


def test_ground_truth_reversed_is_relative_to_its_new_first_row():
    # Four frames; the last has no ground truth, so the reversed truth starts on its second row.
    rows = np.array([[10, 20, 8, 8], [12, 20, 10, 10], [14, 20, 12, 12], [np.nan] * 4])
    gt = ground_truth_from_boxes(rows)
    gt = GroundTruth(gt.boxes, True, gt.scale, np.array([0.0, 30.0, 50.0, np.nan]), 180.0, None, "vot")
    back = gt.reversed()
    assert back.valid.tolist() == [False, True, True, True] and back.first_valid == 1
    np.testing.assert_array_equal(back.boxes[1:], gt.boxes[2::-1])
    np.testing.assert_allclose(back.scale[1:], [1.0, 10 / 12, 8 / 12])
    np.testing.assert_allclose(back.rotation_deg[1:], [0.0, -20.0, -50.0])
    assert (back.rotated, back.rotation_period, back.source) == (True, 180.0, "vot")
    assert back.reversed().boxes[:3].tolist() == gt.boxes[:3].tolist()


def test_an_ellipse_is_scored_as_a_region_its_bounding_box_against_axis_aligned_ground_truth():
    # The convention the README states ("An ellipse against a box"): a rectangle 80 x 20 turned 30 degrees, tracked
    # perfectly by its inscribed ellipse, scores IoU 1 against the rotated rectangle (VOT) and, as the ellipse's own
    # axis-aligned bounding box (69.9 x 43.6 px), 0.67 against the rectangle's axis-aligned box (OTB: 79.3 x 57.3).
    rect = np.array([[100.0, 100, 80, 20, 30]])
    track = _ellipse_track([[100.0, 100, 40, 10, 30]], [1.0], [0.0])
    assert score_track(ground_truth_from_rects(rect), track)["iou"][0] == pytest.approx(1.0)
    aabb = rotated_to_aabb(rect)
    ellipse_box = 2 * math.sqrt(40**2 * 0.75 + 10**2 * 0.25) * 2 * math.sqrt(40**2 * 0.25 + 10**2 * 0.75)
    expected = ellipse_box / (aabb[0, 2] * aabb[0, 3])  # the ellipse's box lies inside the rectangle's
    assert score_track(ground_truth_from_boxes(aabb), track)["iou"][0] == pytest.approx(expected, rel=1e-6)
    assert expected == pytest.approx(0.671, abs=0.001)
