"""``lptrack frame``/``roi``/``plot``/``sheet`` and the library underneath (:mod:`logpolar_track.frame_png`,
:mod:`~logpolar_track.roi_fit`, :mod:`~logpolar_track.plot`, :mod:`~logpolar_track.contact_sheet`, and
:func:`~logpolar_track.video.read_frame`, :func:`~logpolar_track.draw.draw_grid`,
:func:`~logpolar_track.pipeline.find_video_for_csv`).

Frames are compared pixel for pixel with a direct sequential OpenCV read of the same file; ROIs are fitted to
points on known ellipses; plot and sheet run on a tiny ``lptrack run --tracker diffdecomp`` track.
"""

from __future__ import annotations

import csv
import errno
import json
import math
import re
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import CliRunner, decode_all

from logpolar_track.cli import main
from logpolar_track import contact_sheet
from logpolar_track.contact_sheet import sheet_geometry, write_contact_sheet
from logpolar_track.draw import GRID_COLOUR, draw_grid
from logpolar_track.errors import RoiError, UsageError
from logpolar_track.evaluate import GroundTruthError, read_box_text, read_run_csv, read_track_csv
from logpolar_track.frame_png import write_frame_png
from logpolar_track.geometry import Ellipse, parse_roi
from logpolar_track.pipeline import find_video_for_csv
from logpolar_track.plot import PLOT_DPI, PLOT_SIZE_IN
from logpolar_track.results import COLUMNS
from logpolar_track.roi_fit import from_one_based, roi_from_box, roi_from_mask, roi_from_points, roi_from_quad
from logpolar_track.video import read_frame


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def one_error_line(result, code: int) -> str:
    """Assert a clean failure: exit ``code``, exactly one ``lptrack: error:`` line, no traceback; return it."""
    assert result.exit_code == code, (result.exit_code, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lptrack: error: "), result.stderr
    assert "Traceback" not in result.stderr
    return lines[0]


def png_size(path: Path) -> tuple[int, int]:
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert image is not None, f"{path} is not a readable PNG"
    return image.shape[1], image.shape[0]


def angle_diff_mod180(a: float, b: float) -> float:
    return abs((a - b + 90.0) % 180.0 - 90.0)


# -- frame ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("index", [0, 1, 7, 19])
def test_read_frame_is_the_nth_sequentially_decoded_frame(tiny_video, index):
    expected = decode_all(tiny_video.path)[index]
    frame = read_frame(tiny_video.path, index)
    assert frame.index == index and frame.time_s == pytest.approx(index / 30.0)
    assert np.array_equal(frame.image, expected)


def test_read_frame_at_a_time_rounds_to_the_nearest_frame(tiny_video):
    frame = read_frame(tiny_video.path, time_s=0.49)  # 14.7 frames at 30 fps -> frame 15
    assert frame.index == 15
    assert np.array_equal(frame.image, decode_all(tiny_video.path)[15])


def test_read_frame_at_a_time_halfway_between_two_frames_is_the_later_on_every_frame(tiny_video):
    """A tie takes the later frame, as the README says; in floating point some halfway times came out nearer the
    earlier (at 25 fps, 0.06 s gave frame 1, 0.18 s frame 4)."""
    fps = read_frame(tiny_video.path, 0).fps
    for rate in (fps, 25.0):
        for k in range(18):
            assert read_frame(tiny_video.path, time_s=(k + 0.5) / rate, fps=rate).index == k + 1, (rate, k)


def test_read_frame_at_a_time_on_the_last_frame_is_the_last_frame(tiny_video):
    """A time while the last frame is on screen (19.6 frames at 30 fps: rounds to 20, past the end) gives it; the
    end of the video does not."""
    assert read_frame(tiny_video.path, time_s=19.6 / 30).index == 19
    with pytest.raises(UsageError, match=r"a time before 0.667 s"):
        read_frame(tiny_video.path, time_s=20 / 30)


def test_read_frame_past_the_end_gives_the_valid_range(tiny_video):
    # Only frames: roi, which reads a frame this way, takes no time.
    with pytest.raises(UsageError, match=r"frame 20 lies past the end .* 20 frames: give a frame from 0 to 19$"):
        read_frame(tiny_video.path, 20)


def test_read_frame_takes_whole_frame_numbers_only_as_track_video_does(tiny_video):
    """1.5 read frame 1, '3' frame 3 and True frame 1, where track_video refuses them."""
    for index in (1.5, "3", True):
        with pytest.raises(UsageError, match=f"frame index must be a whole number >= 0, got {re.escape(repr(index))}"):
            read_frame(tiny_video.path, index)
    with pytest.raises(UsageError, match="time must be a number of seconds >= 0, got '1'"):
        read_frame(tiny_video.path, time_s="1")
    assert read_frame(tiny_video.path, np.int64(3)).index == 3


def test_roi_from_points_refuses_an_array_of_another_shape_or_not_finite():
    """A (2, n) array (its xs and ys) was flattened and read as pairs: a wrong ellipse without a word."""
    t = np.radians(np.arange(0, 360, 30))
    xs, ys = 100 + 40 * np.cos(t), 100 - 20 * np.sin(t)
    with pytest.raises(RoiError, match=r"an \(n, 2\) array of \(x, y\) pixels .*got shape \(2, 12\)"):
        roi_from_points(np.array([xs, ys]))
    with pytest.raises(RoiError, match="finite"):
        roi_from_points(np.array([[1.0, 2.0], [np.nan, 3.0], [4.0, 5.0], [6.0, 1.0]]))
    fitted = roi_from_points(np.stack([xs, ys], axis=1))
    assert fitted == roi_from_points(np.stack([xs, ys], axis=1)[:, None, :])  # an OpenCV contour
    assert abs(fitted.a - 40) < 0.01 and abs(fitted.b - 20) < 0.01


def test_roi_hint_quotes_a_path_the_shell_would_split(tiny_video, tmp_path):
    spaced = tmp_path / "my clip.mp4"
    shutil.copy(tiny_video.path, spaced)
    result = invoke("roi", spaced, "--from-box", "60,40,40,40")
    assert result.exit_code == 0, result.stderr
    assert f"lptrack: check it with: lptrack frame '{spaced}' --at 0 --roi 80,60,20" in result.stderr


def test_frame_with_each_candidate_roi_gets_a_name_of_its_own(tiny_video, tmp_path, monkeypatch):
    """Trying ROIs one after another: each drawn frame was written to tiny.frame0.png, and the second try stopped
    with 'already exists'."""
    monkeypatch.chdir(tmp_path)
    names = []
    for args in ((), ("--roi", "80,60,20"), ("--roi", "80.5,60,20,12,30")):
        result = invoke("frame", tiny_video.path, *args)
        assert result.exit_code == 0, result.stderr
        names.append(result.stdout.strip())
    assert names == ["tiny.frame0.png", "tiny.frame0.roi_80_60_20.png", "tiny.frame0.roi_80.5_60_20_12_30.png"]
    assert all((tmp_path / name).is_file() for name in names)
    assert "already exists" in one_error_line(invoke("frame", tiny_video.path, "--roi", "80,60,20"), 1)


def test_write_frame_png_takes_a_roi_as_the_rest_of_the_api_does(tiny_video, tmp_path, monkeypatch):
    """A --roi string or its numbers, as draw_roi and a tracker's init take them (a string raised AttributeError)."""
    monkeypatch.chdir(tmp_path)
    as_text = write_frame_png(tiny_video.path, "text.png", index=3, roi="80,60,20")
    as_numbers = write_frame_png(tiny_video.path, "numbers.png", index=3, roi=(80, 60, 20))
    as_ellipse = write_frame_png(tiny_video.path, "ellipse.png", index=3, roi=Ellipse(80, 60, 20, 20, 0))
    assert np.array_equal(cv2.imread(str(as_text)), cv2.imread(str(as_ellipse)))
    assert np.array_equal(cv2.imread(str(as_numbers)), cv2.imread(str(as_ellipse)))
    assert write_frame_png(tiny_video.path, index=3, roi="80,60,20").name == "tiny.frame3.roi_80_60_20.png"
    with pytest.raises(RoiError, match="has 2 numbers"):
        write_frame_png(tiny_video.path, "bad.png", index=3, roi="80,60")


def test_frame_command_writes_the_exact_frame(tiny_video, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke("frame", tiny_video.path, "--at", 12, "--grid", 0)
    assert result.exit_code == 0, result.stderr
    out = tmp_path / "tiny.frame12.png"  # default name, in the current folder
    assert result.stdout.strip() == str(Path("tiny.frame12.png"))
    image = cv2.imread(str(out))
    expected = decode_all(tiny_video.path)[12]
    assert image.shape == expected.shape
    # Only the size caption in the bottom-right corner differs (PNG is lossless).
    assert np.array_equal(image[:96], expected[:96])


def test_frame_on_a_full_disk_is_one_line_and_leaves_nothing(tiny_video, tmp_path, monkeypatch):
    """cv2.imwrite let libpng print its own line ("libpng error: Write Error") before lptrack's; the PNG is now
    encoded in memory and written by Python, whose error is the one line."""
    def full_disk(self, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_bytes", full_disk)
    out = tmp_path / "out"
    out.mkdir()
    line = one_error_line(invoke("frame", tiny_video.path, "-o", out / "f.png"), 1)
    assert line == f"lptrack: error: cannot write output image '{out / 'f.png'}': No space left on device"
    assert list(out.iterdir()) == []


def test_frame_command_refuses_to_overwrite_and_bad_indexes(tiny_video, tmp_path):
    out = tmp_path / "f.png"
    assert invoke("frame", tiny_video.path, "-o", out).exit_code == 0
    before = out.read_bytes()
    assert "--overwrite" in one_error_line(invoke("frame", tiny_video.path, "--at", 3, "-o", out), 1)
    assert out.read_bytes() == before
    assert invoke("frame", tiny_video.path, "--at", 3, "-o", out, "--overwrite").exit_code == 0
    assert out.read_bytes() != before
    line = one_error_line(invoke("frame", tiny_video.path, "--at", 25, "-o", tmp_path / "g.png"), 2)
    assert "from 0 to 19" in line
    assert not (tmp_path / "g.png").exists()
    one_error_line(invoke("frame", tiny_video.path, "--at", 1, "--time", 0.1, "-o", tmp_path / "g.png"), 2)
    by_clock = invoke("frame", tiny_video.path, "--time", "0:00.2", "-o", tmp_path / "t.png")  # as FFmpeg's -ss
    by_index = invoke("frame", tiny_video.path, "--at", 6, "-o", tmp_path / "i.png")
    assert by_clock.exit_code == by_index.exit_code == 0
    assert (tmp_path / "t.png").read_bytes() == (tmp_path / "i.png").read_bytes()
    assert "'1:75' is not a time" in one_error_line(invoke("frame", tiny_video.path, "--time", "1:75"), 2)
    one_error_line(invoke("frame", tmp_path / "missing.mp4", "-o", tmp_path / "g.png"), 1)
    line = one_error_line(invoke("frame", tiny_video.path, "--roi", "500,60,20", "-o", tmp_path / "g.png"), 2)
    assert "outside" in line
    assert not (tmp_path / "g.png").exists()


@pytest.mark.parametrize("command, name, accepted", [
    ("frame", "f.jpg", ".png"), ("sheet", "s.jpg", ".png"), ("plot", "p.txt", ".png or .pdf or .svg"),
    ("plot", "noextension", ".png or .pdf or .svg")])
def test_an_output_name_of_the_wrong_type_is_a_usage_error(tiny_run, tmp_path, command, name, accepted):
    video, run_csv, _ = tiny_run
    args = {"frame": [video.path], "sheet": [video.path, run_csv], "plot": [run_csv, "--no-video"]}[command]
    line = one_error_line(invoke(command, *args, "-o", tmp_path / name), 2)
    assert f"give a file name ending in {accepted}" in line
    assert list(tmp_path.glob("*" + name)) == [] and list(tmp_path.glob(".*")) == []


def test_grid_lines_and_labels_are_at_their_pixel_positions():
    image = np.zeros((150, 230, 3), np.uint8)
    out = draw_grid(image, 50)
    grid = np.array(GRID_COLOUR, np.uint8)
    # Lines exactly on x = 50, 100, 150, 200 and y = 50, 100, and nowhere else (away from the labels).
    for x in (50, 100, 150, 200):
        assert (out[30:125:7, x] == grid).all()
    for y in (50, 100):
        assert (out[y, 30:220:7] == grid).all()
    assert not (out[75, 30:220] == grid).all(axis=1)[[c - 30 for c in range(30, 220) if c % 50]].any()
    # Each x label sits in the top strip just right of its line, before the next one.
    top = out[:14].astype(int).sum(axis=2) > 0
    for x in (50, 100, 150):
        cols = np.flatnonzero(top[:, x + 1:x + 50].any(axis=0)) + x + 1
        assert cols.size and cols.min() <= x + 6 and cols.max() < x + 45, (x, cols)
    # Each y label sits at the left edge just below its line.
    left = out[:, :14].astype(int).sum(axis=2) > 0
    for y in (50, 100):
        rows = np.flatnonzero(left[y + 1:y + 40].any(axis=1)) + y + 1
        assert rows.size and rows.min() <= y + 6, (y, rows)
    # The frame size in the bottom-right corner.
    assert (out[-14:, -60:].sum(axis=2) > 0).any()
    assert (out[-14:, :20].sum(axis=2) == 0).all()
    assert not image.any()  # input untouched


def test_frame_command_grid_positions_on_a_real_frame(tiny_video, tmp_path):
    out = tmp_path / "grid.png"
    assert invoke("frame", tiny_video.path, "--grid", 40, "-o", out).exit_code == 0
    image = cv2.imread(str(out))
    assert (image[30:100, 40] == GRID_COLOUR).all() and (image[30:100, 120] == GRID_COLOUR).all()
    assert (image[80, 30:150] == GRID_COLOUR).all()
    assert not (image[30:100, 41] == GRID_COLOUR).all(axis=1).all()


# -- roi -----------------------------------------------------------------------------------------------------

def test_roi_from_box_round_trips():
    e = roi_from_box("60,40,80,40")
    assert (e.cx, e.cy, e.a, e.b, e.angle_deg) == (100, 60, 40, 20, 0)
    tall = roi_from_box([60, 40, 40, 80])
    assert (tall.cx, tall.cy, tall.a, tall.b, tall.angle_deg) == (80, 80, 40, 20, 90)
    square = roi_from_box("10,20,40,40.5")  # within the 2 % tolerance: a circle of equal area
    assert square.is_circle and square.a == pytest.approx(math.sqrt(20 * 20.25))
    assert not roi_from_box("10,20,40,40.5", round_tolerance=0).is_circle
    with pytest.raises(RoiError, match="x,y,w,h"):
        roi_from_box("1,2,3")
    with pytest.raises(RoiError, match="> 0"):
        roi_from_box("1,2,0,3")


def test_roi_from_box_reads_a_benchmark_line_separated_by_tabs_or_spaces():
    # OTB's toy and crossing separate with tabs; a line pasted from them is the same box.
    for text in ("60\t40\t80\t40", "60 40 80 40", " 60  40 80\t40\n", "60;40;80;40"):
        e = roi_from_box(text)
        assert (e.cx, e.cy, e.a, e.b, e.angle_deg) == (100, 60, 40, 20, 0), text
    with pytest.raises(RoiError, match="'40 80' is not a number"):
        roi_from_box("60,40 80,40")  # commas and spaces mixed: not guessed


def test_roi_from_box_takes_an_array_row_as_roi_from_quad_does():
    """A box as numpy gives it, one row of a ground-truth file read with np.loadtxt (shape (1, 4)), is the box; it
    raised TypeError ('only 0-dimensional arrays can be converted'), and a field that is not a number ValueError,
    where roi_from_quad takes (1, 8) or (4, 2) corners and refuses others with a RoiError."""
    e = roi_from_box(np.array([[60, 40, 80, 40]]))
    assert (e.cx, e.cy, e.a, e.b, e.angle_deg) == (100, 60, 40, 20, 0)
    for bad in (np.zeros((2, 4)), [1, 2, 3, "x"], None):
        with pytest.raises(RoiError):
            roi_from_box(bad)
    with pytest.raises(RoiError, match="not finite"):
        roi_from_box((10, 20, 30, float("nan")))


@pytest.mark.parametrize("angle", [0.0, 25.0, -40.0, 90.0, 120.0])
def test_roi_from_quad_is_the_ellipse_in_a_rotated_box(angle):
    cx, cy, w, h = 150.0, 90.0, 80.0, 30.0
    # Corners built here: (u, v) in the box's frame, y-up, turned counter-clockwise on screen, then y flipped.
    psi = math.radians(angle)
    corners = []
    for u, v in ((w / 2, h / 2), (-w / 2, h / 2), (-w / 2, -h / 2), (w / 2, -h / 2)):
        corners.append((cx + u * math.cos(psi) - v * math.sin(psi), cy - (u * math.sin(psi) + v * math.cos(psi))))
    for order in ((0, 1, 2, 3), (2, 3, 0, 1), (3, 2, 1, 0)):  # VOT's corner order varies
        e = roi_from_quad(",".join(f"{c:.4f}" for i in order for c in corners[i]))
        assert math.dist(e.centre, (cx, cy)) < 1e-3 and e.a == pytest.approx(w / 2, abs=1e-3)
        assert e.b == pytest.approx(h / 2, abs=1e-3) and angle_diff_mod180(e.angle_deg, angle) < 1e-2
        assert -90 < e.angle_deg <= 90
    square = roi_from_quad([10, 10, 50, 10, 50, 50, 10, 50])
    assert square.is_circle and (square.cx, square.cy, square.a) == (30, 30, 20)
    assert roi_from_quad(np.array([[10, 10], [50, 10], [50, 50], [10, 50]])) == square  # corners as rows too
    with pytest.raises(RoiError, match="has 6 numbers; expected x1,y1,x2,y2,x3,y3,x4,y4"):
        roi_from_quad("1,2,3,4,5,6")
    with pytest.raises(RoiError, match="spans no area"):
        roi_from_quad("0,0,10,10,20,20,30,30")
    with pytest.raises(RoiError, match="not finite"):
        roi_from_quad([0, 0, 10, 0, 10, float("nan"), 0, 10])


def test_roi_from_quad_is_the_start_bench_and_eval_read_from_vot_ground_truth(tmp_path):
    line = "291.827,203.603,396.382,264.289,442.173,185.397,337.618,124.711"  # VOT bag's first line
    gt = tmp_path / "groundtruth.txt"
    gt.write_text(line + "\n")
    start = read_box_text(gt).initial_roi()
    got = roi_from_quad(line, round_tolerance=0)
    assert math.dist(got.centre, start.centre) < 1e-3
    assert sorted((got.a, got.b)) == pytest.approx(sorted((start.a, start.b)), abs=1e-3)
    assert angle_diff_mod180(got.angle_deg if got.a >= got.b else got.angle_deg + 90,
                             start.angle_deg if start.a >= start.b else start.angle_deg + 90) < 1e-2


def _filled_ellipse(e: Ellipse, size=(240, 320), value=255) -> np.ndarray:
    """A mask with ``e`` filled in: its outline's points (counter-clockwise angles, built by the Ellipse) as a
    polygon, so that the mask does not depend on cv2.ellipse's angle convention."""
    mask = np.zeros(size, np.uint8)
    cv2.fillPoly(mask, [np.round(e.boundary_points(720) * 16).astype(np.int32)], value, shift=4)
    return mask


@pytest.mark.parametrize("angle", [0.0, 30.0, -60.0, 89.0, 120.0])
def test_roi_from_mask_is_the_ellipse_with_the_masks_moments(angle):
    e = Ellipse(160.3, 119.6, 60.0, 25.0, angle)
    got = roi_from_mask(_filled_ellipse(e), round_tolerance=0)
    assert math.dist(got.centre, e.centre) < 0.15  # the raster of an outline off the pixel grid
    # A filled outline covers pixels whose centres lie on it: up to half a pixel more on each side.
    assert -0.1 < got.a - 60 < 0.8 and -0.1 < got.b - 25 < 0.8
    assert angle_diff_mod180(got.angle_deg, angle) < 0.2 and -90 < got.angle_deg <= 90


def test_roi_from_mask_reads_masks_as_segmentations_give_them():
    e = Ellipse(100.0, 80.0, 40.0, 22.0, 35.0)
    truth = roi_from_mask(_filled_ellipse(e), round_tolerance=0)
    same = [_filled_ellipse(e, value=1),                                                  # 0/1
            np.dstack([np.zeros((240, 320), np.uint8), _filled_ellipse(e), np.zeros((240, 320), np.uint8)]),
            np.dstack([np.zeros((240, 320, 3), np.uint8), _filled_ellipse(e)]),           # alpha only
            _filled_ellipse(e).astype(np.uint16) * 257,                                   # 16 bits
            cv2.imdecode(cv2.imencode(".jpg", _filled_ellipse(e), [cv2.IMWRITE_JPEG_QUALITY, 50])[1], 0)]
    specked = _filled_ellipse(e)
    specked[5:8, 300:303] = 255  # a speck far off: the largest region counts
    for mask in [*same, specked]:
        got = roi_from_mask(mask, round_tolerance=0)
        assert math.dist(got.centre, truth.centre) < 0.1 and abs(got.a - truth.a) < 0.3
        assert abs(got.b - truth.b) < 0.3 and angle_diff_mod180(got.angle_deg, truth.angle_deg) < 0.3
    disc = roi_from_mask(_filled_ellipse(Ellipse.circle(50.0, 60.0, 12.0)))
    assert disc.is_circle and disc.centre == pytest.approx((50, 60), abs=0.1) and 12 < disc.a < 12.8
    with pytest.raises(RoiError, match="the mask is empty"):
        roi_from_mask(np.zeros((20, 30)))
    with pytest.raises(RoiError, match=r"got shape \(5,\)"):
        roi_from_mask(np.ones(5))


def test_roi_from_mask_takes_a_cutouts_alpha_whatever_its_colours():
    # A cutout (rembg, an editor's layer exported with transparency): the object's own colours, alpha marking it.
    # Its brightest colours gave a part of the object; white under the transparent pixels gave the whole frame.
    e = Ellipse(100.0, 80.0, 40.0, 22.0, 35.0)
    truth = roi_from_mask(_filled_ellipse(e), round_tolerance=0)
    alpha = _filled_ellipse(e)
    texture = np.random.default_rng(1).integers(0, 256, (240, 320, 3), dtype=np.uint8)
    for colours in (texture * (alpha[..., None] > 0), texture, np.full((240, 320, 3), 255, np.uint8)):
        got = roi_from_mask(np.dstack([colours, alpha]), round_tolerance=0)
        assert got == truth
    opaque = np.dstack([np.dstack([alpha] * 3), np.full((240, 320), 255, np.uint8)])  # an opaque alpha: colours
    assert roi_from_mask(opaque, round_tolerance=0) == truth


def test_roi_from_mask_refuses_an_object_filling_the_frame():
    # An inverted mask (object black on white) or an all-white one gave an ellipse around the frame, exit 0.
    inverted = 255 - _filled_ellipse(Ellipse(100.0, 80.0, 40.0, 22.0, 35.0))
    for mask in (inverted, np.full((240, 320), 255, np.uint8)):
        with pytest.raises(RoiError, match="touches all four edges of the 320x240 image.*inverted"):
            roi_from_mask(mask)


def test_roi_command_from_a_mask(tiny_video, tmp_path):
    mask = tmp_path / "mask.png"
    cv2.imwrite(str(mask), _filled_ellipse(Ellipse(80.0, 60.0, 30.0, 12.0, 30.0), size=(120, 160)))
    result = invoke("roi", tiny_video.path, "--from-mask", mask)
    assert result.exit_code == 0, result.stderr
    got = parse_roi(result.stdout.strip())
    assert math.dist(got.centre, (80, 60)) < 0.1 and 30 < got.a < 30.8 and 12 < got.b < 12.8
    assert angle_diff_mod180(got.angle_deg, 30) < 0.3
    big = tmp_path / "big.png"
    cv2.imwrite(str(big), np.full((240, 320), 255, np.uint8))
    assert one_error_line(invoke("roi", tiny_video.path, "--from-mask", big), 2) == (
        f"lptrack: error: mask '{big}' is 320x240 pixels but frame 0 of 'tiny.mp4' is 160x120: give a mask of the "
        f"frame's size")
    not_image = tmp_path / "notes.png"
    not_image.write_text("not an image\n")
    assert "cannot read mask" in one_error_line(invoke("roi", tiny_video.path, "--from-mask", not_image), 1)
    missing = one_error_line(invoke("roi", tiny_video.path, "--from-mask", tmp_path / "missing.png"), 1)
    assert "not found" in missing  # exit 1 as for any input that is not there, not click's usage error (2)
    assert "not a mask" in one_error_line(invoke("roi", tiny_video.path, "--from-mask", mask, "--one-based"), 2)
    empty = tmp_path / "empty.png"
    cv2.imwrite(str(empty), np.zeros((120, 160), np.uint8))
    assert "the mask is empty" in one_error_line(invoke("roi", tiny_video.path, "--from-mask", empty), 2)
    inverted = tmp_path / "inverted.png"
    cv2.imwrite(str(inverted), 255 - cv2.imread(str(mask), cv2.IMREAD_UNCHANGED))
    assert "is the mask inverted?" in one_error_line(invoke("roi", tiny_video.path, "--from-mask", inverted), 2)


def test_one_based_coordinates_are_moved_a_pixel_left_and_up(tmp_path):
    # OTB's first box of a sequence is the start bench takes (read_box_text knows OTB files are 1-based).
    gt = tmp_path / "groundtruth_rect.txt"
    gt.write_text("152\t102\t40\t67\n")
    start = read_box_text(gt, one_based=True).initial_roi()
    got = from_one_based(roi_from_box("152\t102\t40\t67"))
    assert (got.cx, got.cy) == (start.cx, start.cy) == (171.0, 134.5)
    assert sorted((got.a, got.b)) == sorted((start.a, start.b)) == [20.0, 33.5]


@pytest.mark.parametrize("angle", [0.0, 30.0, -60.0, 75.0, 90.0, 135.0])
def test_roi_from_points_on_a_known_ellipse(angle):
    cx, cy, a, b = 120.0, 90.0, 45.0, 18.0
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 2 * np.pi, 9))
    # Points built here, not by the code under test: (u, v) in the ellipse's frame, y-up, then y flipped.
    psi = math.radians(angle)
    u, v = a * np.cos(t), b * np.sin(t)
    x = cx + u * math.cos(psi) - v * math.sin(psi)
    y = cy - (u * math.sin(psi) + v * math.cos(psi))
    points = np.column_stack([x, y]) + rng.normal(0, 0.2, (len(t), 2))
    e = roi_from_points(",".join(f"{p:.2f}" for p in points.ravel()))
    assert abs(e.cx - cx) < 1 and abs(e.cy - cy) < 1 and abs(e.a - a) < 1 and abs(e.b - b) < 1
    assert angle_diff_mod180(e.angle_deg, angle) < 1.0
    assert -90 < e.angle_deg <= 90
    # Counter-clockwise on screen: axis a ends up and to the right for 0 < angle < 90 (y is down).
    tip = (cx + a * math.cos(psi), cy - a * math.sin(psi))
    ends = [e.axis_end(), (2 * e.cx - e.axis_end()[0], 2 * e.cy - e.axis_end()[1])]
    assert min(math.dist(end, tip) for end in ends) < 1.5


def test_roi_from_few_points_is_a_circle_and_too_few_is_an_error():
    r, cx, cy = 25.0, 70.0, 50.0
    for n in (3, 4):
        t = np.array([0.3, 1.9, 4.0, 5.2][:n])
        pts = np.column_stack([cx + r * np.cos(t), cy - r * np.sin(t)])
        e = roi_from_points(pts)
        assert e.is_circle and math.dist(e.centre, (cx, cy)) < 1e-6 and e.a == pytest.approx(r)
    with pytest.raises(RoiError, match="at least 3 points"):
        roi_from_points("1,2,3,4")
    with pytest.raises(RoiError, match="pairs"):
        roi_from_points("1,2,3,4,5")
    with pytest.raises(RoiError, match="straight line"):
        roi_from_points("0,0,1,1,2,2,3,3,4,4")


def test_roi_from_points_counts_a_repeated_point_once():
    """5 points of which 3 differ determine a circle, not an ellipse; 4 of which 2 differ, nothing."""
    r, cx, cy = 25.0, 70.0, 50.0
    t = np.array([0.3, 1.9, 4.0])
    pts = np.column_stack([cx + r * np.cos(t), cy - r * np.sin(t)])
    e = roi_from_points(np.vstack([pts, pts[:2]]))
    assert e.is_circle and math.dist(e.centre, (cx, cy)) < 1e-6 and e.a == pytest.approx(r)
    with pytest.raises(RoiError, match=re.escape("2 distinct points (4 given, some repeated) cannot define")):
        roi_from_points("10,10,20,20,10,10,20,20")


def test_roi_command_prints_a_spec_checked_against_the_frame(tiny_video):
    result = invoke("roi", tiny_video.path, "--from-box", "60,40,40,40")
    assert result.exit_code == 0, result.stderr
    assert result.stdout == "80,60,20\n"
    assert "lptrack frame" in result.stderr and "--roi 80,60,20" in result.stderr
    e = Ellipse(80, 60, 30, 12, 30)
    pts = ",".join(f"{v:.3f}" for v in e.boundary_points(8).ravel())
    result = invoke("roi", tiny_video.path, "--at", 5, "--from-points", pts)
    got = parse_roi(result.stdout.strip())
    assert math.dist(got.centre, e.centre) < 1 and abs(got.a - 30) < 1 and abs(got.b - 12) < 1
    assert angle_diff_mod180(got.angle_deg, 30) < 1
    assert "outside" in one_error_line(invoke("roi", tiny_video.path, "--from-box", "200,10,20,20"), 2)
    one_error_line(invoke("roi", tiny_video.path), 2)
    one_error_line(invoke("roi", tiny_video.path, "--from-box", "1,2,3,4", "--from-points", "1,2,3,4,5,6"), 2)
    assert "exactly one of" in one_error_line(
        invoke("roi", tiny_video.path, "--from-box", "1,2,3,4", "--from-quad", "1,2,3,4,5,6,7,8"), 2)
    result = invoke("roi", tiny_video.path, "--from-quad", "60,40,100,40,100,80,60,80")
    assert result.exit_code == 0 and result.stdout == "80,60,20\n"
    result = invoke("roi", tiny_video.path, "--from-box", "61\t41\t40\t40", "--one-based")
    assert result.exit_code == 0 and result.stdout == "80,60,20\n"
    result = invoke("roi", tiny_video.path, "--from-quad", "61,41,101,41,101,81,61,81", "--one-based")
    assert result.exit_code == 0 and result.stdout == "80,60,20\n"
    assert "spans no area" in one_error_line(invoke("roi", tiny_video.path, "--from-quad", "0,0,1,1,2,2,3,3"), 2)
    assert "at least 3" in one_error_line(invoke("roi", tiny_video.path, "--from-points", "1,2,3,4"), 2)
    assert "0 to 19" in one_error_line(invoke("roi", tiny_video.path, "--at", 40, "--from-box", "60,40,40,40"), 2)


@pytest.mark.parametrize("bad", ["1_0", "nan", "inf", "-inf"])
def test_every_list_of_numbers_refuses_what_is_no_plain_number_alike(bad):
    """parse_roi refused 1_40 and took the typeset minus sign; roi_from_box and roi_from_points did the opposite
    (a box of width 8_0 gave a circle of radius 40)."""
    rule = f"'{bad}' is not a number (give plain decimals such as 12, -3.5 or 1e3; no '_', nan or inf)"
    for read, text in ((parse_roi, f"280,200,{bad}"), (roi_from_box, f"280,200,{bad},80"),
                       (roi_from_points, f"0,0,{bad},0,10,10"), (roi_from_quad, f"0,0,{bad},0,10,10,0,10")):
        with pytest.raises(RoiError, match=re.escape(rule)):
            read(text)


def test_a_number_beyond_a_floats_range_is_said_to_be_too_large():
    for read, text in ((parse_roi, "1e999,200,40"), (roi_from_box, "280,200,1e999,80")):
        with pytest.raises(RoiError, match="'1e999' is too large a number"):
            read(text)


def test_box_and_points_take_semicolons_as_before():
    """roi --from-box and --from-points read ';' as ',' before their numbers had one reader; it stays so."""
    assert roi_from_box("280;200;80;80") == roi_from_box("280,200,80,80")
    assert roi_from_points("380,240;320,270;260,240;320,210") == roi_from_points("380,240,320,270,260,240,320,210")


def test_every_list_of_numbers_takes_the_typeset_minus_sign(tiny_video):
    minus = "\u2212"
    assert parse_roi(f"{minus}280,200,40") == parse_roi("-280,200,40")
    assert roi_from_box(f"{minus}280,200,80,80") == roi_from_box("-280,200,80,80") == Ellipse.circle(-240, 240, 40)
    assert roi_from_points(f"{minus}10,0,10,0,0,10") == roi_from_points("-10,0,10,0,0,10")
    result = invoke("roi", tiny_video.path, "--from-box", "60,40,4_0,40")
    assert "'4_0' is not a number" in one_error_line(result, 2) and result.stdout == ""


# -- a tiny run for plot and sheet ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def tiny_run(_tiny_video_master, tmp_path_factory):
    """(video, run CSV, ground-truth CSV) of `lptrack run --tracker diffdecomp` on the tiny video."""
    folder = tmp_path_factory.mktemp("look_run")
    video = _tiny_video_master
    run_csv = folder / "tiny.lptrack.csv"
    result = invoke("run", video.path, "--tracker", "diffdecomp", "--no-video", "--csv", run_csv, "--quiet")
    assert result.exit_code == 0, result.stderr
    gt = folder / "tiny.gt.csv"
    with open(gt, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["frame", "cx", "cy", "a", "b", "angle_deg", "scale", "rotation_deg"])
        for k, p in enumerate(video.poses):
            r = video.roi.a * p.scale
            w.writerow([k, p.cx, p.cy, r, r, p.rotation_deg, p.scale, p.rotation_deg])
    return video, run_csv, gt


def bad_csvs(folder: Path, good: Path) -> dict[str, Path]:
    """Run CSVs that break the contract in different ways."""
    lines = good.read_text().splitlines()
    cases = {
        "header": ["frame,x,y,r"] + [",".join(line.split(",")[:4]) for line in lines[1:]],
        "status": lines[:2] + [lines[2].rsplit(",", 1)[0] + ",found"] + lines[3:],
        "number": lines[:3] + [lines[3].replace(lines[3].split(",")[2], "abc", 1)] + lines[4:],
        "score": lines[:4] + [",".join(lines[4].split(",")[:-2] + ["1.5", "tracked"])] + lines[5:],
        "empty": [],
    }
    paths = {}
    for name, content in cases.items():
        path = folder / f"bad_{name}.csv"
        path.write_text("\n".join(content) + ("\n" if content else ""))
        paths[name] = path
    return paths


def test_read_run_csv_takes_one_video_of_a_batch_stream(tiny_run, tmp_path):
    """``lptrack run a.mp4 b.mp4 --csv -`` leads with a 'video' column: plot and sheet refused it by its header;
    the rows of the only video, or of the video named, are taken."""
    video, run_csv, _ = tiny_run
    lines = run_csv.read_text().splitlines()
    other = tmp_path / "other.mp4"
    other.write_bytes(b"")
    stream = tmp_path / "all.csv"
    stream.write_text("\n".join(["video," + lines[0]] + [f"{video.path},{line}" for line in lines[1:]]
                                 + [f"{other},{line}" for line in lines[1:5]]) + "\n")
    alone = read_run_csv(run_csv)
    chosen = read_run_csv(stream, video.path)
    assert list(chosen.frames) == list(alone.frames) and np.array_equal(chosen.ellipses, alone.ellipses)
    assert len(read_run_csv(stream, other)) == 4
    with pytest.raises(GroundTruthError, match=r"holds the rows of 2 videos .*'video' column\); choose one with "
                                               r"--video VIDEO, or give one video's"):
        read_run_csv(stream)
    with pytest.raises(GroundTruthError, match="none of them is 'elsewhere.mp4'; give one video's run"):
        read_run_csv(stream, "elsewhere.mp4")
    single = tmp_path / "single.csv"
    single.write_text("\n".join(stream.read_text().splitlines()[:21]) + "\n")
    assert list(read_run_csv(single).frames) == list(alone.frames)


def test_read_run_csv_follows_the_contract(tiny_run, tmp_path):
    _, run_csv, _ = tiny_run
    table = read_run_csv(run_csv)
    assert len(table) == 20 and list(table.frames) == list(range(20))
    assert table.status[0] == "init" and table.scale[0] == 1.0
    assert table.result(3).state.ellipse.cx == table.ellipses[3, 0]
    messages = {}
    for name, path in bad_csvs(tmp_path, run_csv).items():
        with pytest.raises(GroundTruthError) as info:
            read_run_csv(path)
        messages[name] = str(info.value)
    assert ",".join(COLUMNS) in messages["header"]
    assert "line 3" in messages["status"] and "init, tracked, lost" in messages["status"]
    assert "line 4" in messages["number"] and "'abc' is not a number" in messages["number"]
    assert "line 5" in messages["score"] and "'1.5' is not in [0, 1]" in messages["score"]
    assert "empty" in messages["empty"]


def test_eval_refuses_a_status_or_score_off_contract_as_plot_and_sheet_do(tiny_run, tmp_path):
    """A status or a score the contract does not allow is a file gone wrong: eval scored a status 'found' and a
    score 1.5."""
    _, run_csv, _ = tiny_run
    cases = bad_csvs(tmp_path, run_csv)
    with pytest.raises(GroundTruthError, match="line 3: status 'found' is not one of init, tracked, lost"):
        read_track_csv(cases["status"])
    with pytest.raises(GroundTruthError, match=r"line 5: score '1.5' is not in \[0, 1\]"):
        read_track_csv(cases["score"])


def _with_field(good: Path, folder: Path, line: int, column: str, value: str) -> Path:
    """A copy of the run CSV ``good`` whose ``column`` on file line ``line`` (1: the header) holds ``value``."""
    lines = good.read_text().splitlines()
    fields = lines[line - 1].split(",")
    fields[COLUMNS.index(column)] = value
    lines[line - 1] = ",".join(fields)
    path = folder / f"run_{column}.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("line, column, value, said", [
    (4, "cx", "nan", "line 4: cx 'nan' is not a number"),
    (4, "a", "-5", "line 4: a '-5' is not a number > 0"),
    (3, "frame", "1.0", "line 3: frame '1.0' is not a frame index (integer >= 0)"),
    (4, "status", "", "line 4: status '' is not one of init, tracked, lost"),
], ids=["cx-nan", "a-negative", "frame-float", "status-empty"])
def test_eval_plot_and_sheet_refuse_a_run_csv_off_contract_alike(tiny_run, tmp_path, line, column, value, said):
    """One reader of a run CSV: eval had rules of its own and scored (exit 0) a file with a centre 'nan', a semi-axis
    -5, a frame '1.0' or an empty status, which plot and sheet refused."""
    video, run_csv, gt = tiny_run
    path = _with_field(run_csv, tmp_path, line, column, value)
    commands = {"eval": ("eval", path, gt), "sheet": ("sheet", video.path, path, "-o", tmp_path / "s.png")}
    if _has_matplotlib():  # plot says first that it needs it
        commands["plot"] = ("plot", path, "--no-video", "-o", tmp_path / "p.png")
    for name, args in commands.items():
        result = invoke(*args)
        expected = (1, "", f"lptrack: error: run CSV '{path}' {said}\n")
        assert (result.exit_code, result.stdout, result.stderr) == expected, name
    for read in (read_run_csv, read_track_csv):
        with pytest.raises(GroundTruthError, match=re.escape(said)):
            read(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]


def test_eval_refuses_its_two_files_the_wrong_way_round(tiny_run):
    """A .gt.csv and a run CSV are both CSVs of frames and ellipses: given swapped, eval scored the ground truth
    against the run (exit 0), and a .gt.csv against itself at AUC 0.952."""
    _, run_csv, gt = tiny_run
    assert invoke("eval", run_csv, gt).exit_code == 0
    for pred, truth, said in ((gt, run_csv, "is ground truth (a .gt.csv), not a run"),
                              (gt, gt, "is ground truth (a .gt.csv), not a run"),
                              (run_csv, run_csv, "is an lptrack run (its columns include time_s and status)")):
        result = invoke("eval", pred, truth)
        assert result.exit_code == 2 and result.stdout == ""
        assert result.stderr.count("\n") == 1 and said in result.stderr
        assert "the run's CSV goes first: lptrack eval PRED.csv GT" in result.stderr


def test_eval_refuses_a_batch_stream_of_several_videos(tiny_run, tmp_path):
    """``run a b --csv -`` writes one stream with a 'video' column; its videos' frame numbers overlap, and eval
    scored the last video's rows against the first one's ground truth (AUC 0.038 for a run of 0.787)."""
    _, run_csv, _ = tiny_run
    header, *rows = run_csv.read_text().splitlines()
    stream = tmp_path / "two.csv"
    stream.write_text("\n".join(["video," + header] + ["a.mp4," + r for r in rows] + ["b.mp4," + r for r in rows])
                      + "\n")
    with pytest.raises(GroundTruthError, match=r"holds the rows of 2 videos \(a.mp4, b.mp4: its 'video' column\)"):
        read_track_csv(stream)
    stream.write_text("\n".join([header] + rows + rows[1:]) + "\n")
    with pytest.raises(GroundTruthError, match=f"line {len(rows) + 2}: frame 1 does not follow frame {len(rows) - 1}"):
        read_track_csv(stream)


def test_eval_plot_and_sheet_word_an_empty_run_csv_alike(tiny_run, tmp_path):
    video, run_csv, gt = tiny_run
    empty, header_only = tmp_path / "empty.csv", tmp_path / "header.csv"
    empty.write_text("")
    header_only.write_text(run_csv.read_text().splitlines()[0] + "\n")
    for path, said in ((empty, "is empty; expected"), (header_only, "has a header but no rows")):
        commands = [("eval", path, gt), ("sheet", video.path, path, "-o", tmp_path / "s.png")]
        if _has_matplotlib():  # plot says first that it needs it
            commands.append(("plot", path, "--no-video", "-o", tmp_path / "p.png"))
        for args in commands:
            result = invoke(*args)
            assert result.exit_code == 1, args
            assert result.stderr.startswith(f"lptrack: error: run CSV '{path}' {said}"), (args, result.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.csv", "header.csv"]


def test_eval_plot_and_sheet_refuse_a_folder_as_the_run_csv_alike(tiny_run, tmp_path):
    # plot and sheet left it to click (exit 2, "File 'd' is a directory"), eval said "Is a directory" (exit 1).
    video, run_csv, gt = tiny_run
    folder = tmp_path / "runs"
    folder.mkdir()
    commands = [("eval", folder, gt), ("sheet", video.path, folder, "-o", tmp_path / "s.png")]
    if _has_matplotlib():  # plot says first that it needs it
        commands.append(("plot", folder, "--no-video", "-o", tmp_path / "p.png"))
    for args in commands:
        line = one_error_line(invoke(*args), 1)
        assert line == f"lptrack: error: cannot read run CSV '{folder}': it is a folder, not a file", args
    assert [p.name for p in tmp_path.iterdir()] == ["runs"]


def test_eval_scores_one_video_of_a_batch_stream(tiny_run, tmp_path, monkeypatch):
    """``lptrack run a.mp4 b.mp4 --csv - > all.csv``: eval scores the video named by --video, or by GT when GT is
    a video (its .gt.csv beside it), as its own run's CSV scores."""
    video, run_csv, gt = tiny_run
    for stem in ("tiny", "copy"):
        (tmp_path / f"{stem}.mp4").write_bytes(video.path.read_bytes())
        (tmp_path / f"{stem}.roi").write_text(video.roi.to_spec() + "\n")
        (tmp_path / f"{stem}.gt.csv").write_text(gt.read_text())
    (tmp_path / "copy.mp4").write_bytes((tmp_path / "copy.mp4").read_bytes()[:-1])  # another file, same frames
    monkeypatch.chdir(tmp_path)
    streamed = invoke("run", "tiny.mp4", "copy.mp4", "--tracker", "diffdecomp", "--no-video", "--csv", "-", "-q")
    assert streamed.exit_code == 0, streamed.stderr
    Path("all.csv").write_text(streamed.stdout)
    alone = invoke("eval", str(run_csv), str(gt))
    assert alone.exit_code == 0, alone.stderr
    by_option = invoke("eval", "all.csv", "tiny.gt.csv", "--video", "tiny.mp4")
    by_gt = invoke("eval", "all.csv", "tiny.mp4")
    for result in (by_option, by_gt):
        assert result.exit_code == 0, result.stderr
        # The table's row, but for its first column (the CSV's name).
        assert result.stdout.splitlines()[2].split()[1:] == alone.stdout.splitlines()[2].split()[1:]
    scored = json.loads(invoke("eval", "all.csv", "tiny.gt.csv", "--video", "copy.mp4", "--json", "-").stdout)
    assert scored["prediction"] == "all.csv" and scored["video"] == "copy.mp4"  # which of the stream's videos
    assert "video" not in json.loads(invoke("eval", str(run_csv), str(gt), "--json", "-").stdout)
    refused = invoke("eval", "all.csv", "tiny.gt.csv")
    assert refused.exit_code == 1 and refused.stderr == (
        "lptrack: error: run CSV 'all.csv' holds the rows of 2 videos (tiny.mp4, copy.mp4: its 'video' column); "
        "choose one with --video VIDEO, or give one video's run (its own CSV, as --out-dir writes them)\n")
    elsewhere = invoke("eval", "all.csv", "tiny.gt.csv", "--video", "other.mp4")
    assert elsewhere.exit_code == 1 and "none of them is 'other.mp4'; give one video's run" in elsewhere.stderr
    # One video's own CSV has no choice to make: --video is said to be ignored (a mistyped name went unnoticed).
    own = invoke("eval", str(run_csv), str(gt), "--video", "other.mp4")
    assert own.exit_code == 0 and own.stdout == alone.stdout
    assert own.stderr == (f"lptrack: note: --video 'other.mp4' is ignored: '{run_csv}' is one video's run (it has no "
                          f"'video' column); --video chooses among the videos of a batch's stream\n")
    assert invoke("eval", str(run_csv), str(gt), "--video", "other.mp4", "-q").stderr == ""  # notes only; rows kept
    # ... and its JSON does not name the ignored --video as the video whose rows were scored.
    doc = json.loads(invoke("eval", str(run_csv), str(gt), "--video", "other.mp4", "--json", "-").stdout)
    assert "video" not in doc
    # Nor the video given as GT (its .gt.csv beside it): no stream's rows were chosen by it.
    assert "video" not in json.loads(invoke("eval", str(run_csv), "tiny.mp4", "--json", "-").stdout)


def test_eval_plot_and_sheet_read_the_run_from_stdin_as_dash(tiny_run, tmp_path, monkeypatch):
    """``lptrack run clip.mp4 --csv - | lptrack eval - clip.gt.csv``: '-' was taken for a file of that name."""
    video, run_csv, gt = tiny_run
    text = run_csv.read_text()
    monkeypatch.chdir(tmp_path)

    def piped(*args):
        return CliRunner().invoke(main, [str(a) for a in args], input=text, catch_exceptions=False)

    from_file, from_stdin = invoke("eval", run_csv, gt), piped("eval", "-", gt)
    assert from_stdin.exit_code == 0, from_stdin.stderr
    assert from_stdin.stdout.splitlines()[2].split()[1:] == from_file.stdout.splitlines()[2].split()[1:]
    sheet = piped("sheet", video.path, "-", "-o", "s.png")
    assert sheet.exit_code == 0 and sheet.stdout == "s.png\n" and (tmp_path / "s.png").is_file()
    unnamed = piped("sheet", video.path, "-")
    assert unnamed.exit_code == 2 and unnamed.stderr == ("lptrack: error: the run comes from stdin ('-'), which "
                                                         "names no PNG: give one with -o, e.g. -o sheet.png\n")
    if _has_matplotlib():
        plot = piped("plot", "-", "-o", "p.png")
        assert plot.exit_code == 0 and (tmp_path / "p.png").is_file()
        assert plot.stderr.startswith("lptrack: note: no thumbnail: the run came from stdin; give the tracked video")
    assert sorted(p.name for p in tmp_path.iterdir()) == (["p.png"] if _has_matplotlib() else []) + ["s.png"]


def test_a_streams_video_names_are_found_from_the_folder_of_the_stream_too(tiny_run, tmp_path, monkeypatch):
    """A batch run from one folder names its videos from there; plot, sheet and eval run from another matched them
    against the current folder only ("none of them is '../vids/b.mp4'")."""
    video, run_csv, gt = tiny_run
    (tmp_path / "vids").mkdir()
    (tmp_path / "runs").mkdir()
    shutil.copy(video.path, tmp_path / "vids/tiny.mp4")
    header, *rows = run_csv.read_text().splitlines()
    stream = tmp_path / "runs/all.csv"
    stream.write_text("\n".join(["video," + header] + [f"../vids/tiny.mp4,{r}" for r in rows]
                                + [f"../vids/other.mp4,{r}" for r in rows]) + "\n")
    monkeypatch.chdir(tmp_path)
    result = invoke("eval", "runs/all.csv", gt, "--video", "vids/tiny.mp4")
    assert result.exit_code == 0, result.stderr
    assert len(read_run_csv("runs/all.csv", "vids/tiny.mp4")) == len(rows)
    sheet = invoke("sheet", "vids/tiny.mp4", "runs/all.csv", "-o", "s.png")
    assert sheet.exit_code == 0, sheet.stderr


def test_plot_takes_the_thumbnail_from_the_video_a_stream_names(tiny_run, tmp_path, monkeypatch):
    """A batch's stream names its video in its 'video' column; plot looked for '<stream name>.mp4' instead and drew
    no thumbnail ("no all.mp4 ... in the current folder") for a video the stream names."""
    pytest.importorskip("matplotlib")
    video, run_csv, _ = tiny_run
    (tmp_path / "vids").mkdir()
    (tmp_path / "runs").mkdir()
    shutil.copy(video.path, tmp_path / "vids/tiny.mp4")
    header, *rows = run_csv.read_text().splitlines()
    stream = tmp_path / "runs/all.csv"
    stream.write_text("\n".join(["video," + header] + [f"../vids/tiny.mp4,{r}" for r in rows]) + "\n")
    monkeypatch.chdir(tmp_path)
    given = invoke("plot", "runs/all.csv", "--video", "vids/tiny.mp4", "-o", "given.png")
    assert given.exit_code == 0, given.stderr
    result = invoke("plot", "runs/all.csv", "-o", "streamed.png")  # named from the stream's folder
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ("lptrack: thumbnail from 'runs/../vids/tiny.mp4', the stream's video (give --video to "
                             "choose another)\n")
    assert Path("streamed.png").read_bytes() == Path("given.png").read_bytes()
    monkeypatch.chdir(tmp_path / "runs")  # named from the current folder, and from stdin
    result = CliRunner().invoke(main, ["plot", "-", "-o", "stdin.png"], input=stream.read_text())
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ("lptrack: thumbnail from '../vids/tiny.mp4', the stream's video (give --video to choose "
                             "another)\n")
    given = CliRunner().invoke(main, ["plot", "-", "--video", "../vids/tiny.mp4", "-o", "given.png"],
                               input=stream.read_text())
    assert given.exit_code == 0 and Path("stdin.png").read_bytes() == Path("given.png").read_bytes()
    monkeypatch.chdir(tmp_path)  # a name found nowhere: the note says so
    result = CliRunner().invoke(main, ["plot", "-", "-o", "none.png"], input=stream.read_text())
    assert result.exit_code == 0 and result.stderr == (
        "lptrack: note: no thumbnail: the stream's video '../vids/tiny.mp4' is not found; give the tracked video "
        "with --video VIDEO (or --no-video for blank axes)\n")
    # A pattern whose folder holds no images is not found either (it was taken, and plot failed on it, exit 1).
    (tmp_path / "img").mkdir()
    pattern = stream.read_text().replace("../vids/tiny.mp4", "img/%04d.jpg")
    result = CliRunner().invoke(main, ["plot", "-", "-o", "none2.png"], input=pattern)
    assert result.exit_code == 0 and "the stream's video 'img/%04d.jpg' is not found" in result.stderr


def test_sheet_given_its_two_files_the_other_way_round_says_so(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    result = invoke("sheet", run_csv, video.path, "-o", tmp_path / "s.png")
    assert result.exit_code == 2 and result.stderr == (
        f"lptrack: error: RUN.csv '{video.path}' is a video and VIDEO '{run_csv}' a run's file; the video goes "
        f"first: lptrack sheet VIDEO RUN.csv\n")
    assert list(tmp_path.iterdir()) == []


def test_a_number_option_given_text_says_a_whole_number_is_wanted(tiny_run):
    video, run_csv, _ = tiny_run
    result = invoke("sheet", video.path, run_csv, "--count", "x")
    assert result.exit_code == 2 and result.stderr == ("lptrack: error: Invalid value for '--count': 'x' is not a "
                                                       "whole number; give one from 1 to 4096 (see 'lptrack sheet "
                                                       "--help')\n")


def test_json_lines_of_a_run_read_back_as_its_csv(tiny_run, tmp_path):
    """What ``run --format jsonl`` writes, ``plot``, ``sheet`` and ``eval`` read as the CSV."""
    video, run_csv, _ = tiny_run
    jsonl = tmp_path / "tiny.lptrack.jsonl"
    result = invoke("run", video.path, "--tracker", "diffdecomp", "--no-video", "--csv", jsonl, "--quiet")
    assert result.exit_code == 0, result.stderr
    a, b = read_run_csv(run_csv), read_run_csv(jsonl)
    assert list(b.frames) == list(a.frames) and b.status == a.status
    for field in ("time_s", "ellipses", "scale", "rotation_deg", "score"):
        np.testing.assert_array_equal(getattr(b, field), getattr(a, field))
    result = invoke("sheet", video.path, jsonl, "-o", tmp_path / "sheet.png")
    assert result.exit_code == 0, result.stderr


def test_sheet_has_the_expected_size_and_shows_the_run(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    out = tmp_path / "sheet.png"
    result = invoke("sheet", video.path, run_csv, "-o", out)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == str(out)
    geometry = sheet_geometry(160, 120, 4, 12, 1600)
    assert geometry["tile"] == (160, 120)  # tiles are never enlarged beyond the video
    assert png_size(out) == geometry["size"] == (640, 28 + 3 * (120 + 18))
    # --count with --cols and --width: 5 frames in 2 columns of 100 px tiles -> 3 rows.
    out2 = tmp_path / "sheet2.png"
    assert invoke("sheet", video.path, run_csv, "-o", out2, "--count", 5, "--cols", 2, "--width", 200).exit_code == 0
    assert png_size(out2) == (200, 28 + 3 * (75 + 18))
    # The first tile is frame 0 with the green outline drawn on it: its centre row crosses green pixels.
    sheet = cv2.imread(str(out))
    tile = sheet[28:28 + 120, :160].astype(int)
    green = (tile[..., 1] > 180) & (tile[..., 0] < 80) & (tile[..., 2] < 80)
    assert green[60].any()


@pytest.mark.parametrize("rows", [2, 3], ids=["other", "the default's value"])
def test_sheet_rows_and_count_are_alternatives(tiny_run, tmp_path, rows):
    """Either fixes the number of frames, so giving both is an error, not one silently ignored."""
    video, run_csv, _ = tiny_run
    out = tmp_path / "sheet.png"
    line = one_error_line(invoke("sheet", video.path, run_csv, "-o", out, "--rows", rows, "--count", 5), 2)
    assert line == (f"lptrack: error: --rows and --count contradict each other: --rows {rows} shows 4 x {rows} "
                    f"frames, --count 5 shows 5 frames in 4 columns; give one of them")
    assert not out.exists()
    with pytest.raises(UsageError, match="rows or count, not both"):
        write_contact_sheet(video.path, run_csv, out, rows=rows, count=5)
    assert not out.exists()
    # Alone, --rows still sets the rows: 4 x 2 frames.
    assert invoke("sheet", video.path, run_csv, "-o", out, "--rows", 2).exit_code == 0
    assert png_size(out) == sheet_geometry(160, 120, 4, 8, 1600)["size"] == (640, 28 + 2 * (120 + 18))


def test_sheet_of_fewer_frames_than_columns_has_no_empty_columns(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    out = tmp_path / "sheet.png"
    assert invoke("sheet", video.path, run_csv, "-o", out, "--count", 2, "--cols", 4, "--width", 400).exit_code == 0
    assert png_size(out) == (2 * 160, 28 + 120 + 18)  # 2 tiles of the video's own size, not 4 of 100 px


def test_a_sheet_too_large_to_hold_is_refused_before_decoding(tiny_run, tmp_path, monkeypatch):
    """--count 4096 --cols 1 on a 4K run asked for 6 gigapixels, tiles and sheet held in memory; refused at
    MAX_SHEET_PIXELS (here lowered to 100,000 for the 160x120 video)."""
    monkeypatch.setattr(contact_sheet, "MAX_SHEET_PIXELS", 100_000)
    video, run_csv, _ = tiny_run
    out = tmp_path / "sheet.png"
    line = one_error_line(invoke("sheet", video.path, run_csv, "-o", out, "--count", 20, "--cols", 1), 2)
    assert line == ("lptrack: error: a sheet of 20 frames in 1 column would be 160x2788 px, over 0.1 megapixels; give "
                    "more columns (--cols) or fewer frames (--count, --rows)")
    assert not out.exists()
    assert invoke("sheet", video.path, run_csv, "-o", out, "--count", 2, "--cols", 2).exit_code == 0  # 320x166


def test_write_contact_sheet_accepts_results(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    table = read_run_csv(run_csv)
    results = [table.result(i) for i in range(len(table))]
    out = write_contact_sheet(video.path, results, tmp_path / "s.png", cols=3, rows=1, width=300)
    assert png_size(out) == (300, 28 + 75 + 18)


def test_contact_sheet_grid_takes_whole_numbers(tiny_run, tmp_path):
    """From Python, cols=2.5 made 2 columns and cols=True 1; sheet_geometry(cols=0) divided by zero."""
    video, run_csv, _ = tiny_run
    for grid in ({"cols": 2.5}, {"cols": True}, {"rows": 0}, {"count": 1.5, "cols": 2}, {"width": 300.5}):
        with pytest.raises(UsageError, match=f"{next(iter(grid))} must be a whole number >= 1"):
            write_contact_sheet(video.path, run_csv, tmp_path / "s.png", **grid)
    with pytest.raises(UsageError, match="cols must be a whole number >= 1, got 0"):
        sheet_geometry(160, 120, 0, 4)
    assert not (tmp_path / "s.png").exists()


def test_sheet_and_plot_fail_cleanly_on_a_csv_off_contract(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    for name, path in bad_csvs(tmp_path, run_csv).items():
        out = tmp_path / f"{name}.png"
        line = one_error_line(invoke("sheet", video.path, path, "-o", out), 1)
        assert str(path) in line
        assert not out.exists()
        if "matplotlib" in sys.modules or _has_matplotlib():
            one_error_line(invoke("plot", path, "-o", out, "--no-video"), 1)
            assert not out.exists()
    assert "0 to" not in one_error_line(invoke("sheet", tmp_path / "nothere.mp4", run_csv, "-o",
                                               tmp_path / "x.png"), 1)
    assert list(p.name for p in tmp_path.iterdir() if p.suffix == ".png") == []


def test_sheet_of_a_run_longer_than_the_video_says_so(tiny_run, tmp_path):
    video, run_csv, _ = tiny_run
    lines = run_csv.read_text().splitlines()
    extra = lines[-1].split(",")
    extra[0] = "30"
    longer = tmp_path / "longer.csv"
    longer.write_text("\n".join(lines + [",".join(extra)]) + "\n")
    assert "frame 30" in one_error_line(invoke("sheet", video.path, longer, "-o", tmp_path / "x.png"), 2)
    assert not (tmp_path / "x.png").exists()


def _has_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


needs_matplotlib = pytest.mark.skipif(not _has_matplotlib(), reason="matplotlib not installed (extra 'plot')")
PLOT_SIZE = (int(PLOT_SIZE_IN[0] * PLOT_DPI), int(PLOT_SIZE_IN[1] * PLOT_DPI))


@needs_matplotlib
def test_plot_has_the_expected_size_with_and_without_ground_truth(tiny_run, tmp_path):
    video, run_csv, gt = tiny_run
    out = tmp_path / "track.png"
    result = invoke("plot", run_csv, "-o", out, "--video", video.path)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == str(out) and png_size(out) == PLOT_SIZE
    out_gt = tmp_path / "track_gt.png"
    result = invoke("plot", run_csv, "-o", out_gt, "--gt", gt, "--no-video")
    assert result.exit_code == 0, result.stderr
    assert png_size(out_gt) == PLOT_SIZE
    assert "--overwrite" in one_error_line(invoke("plot", run_csv, "-o", out, "--no-video"), 1)


@needs_matplotlib
def test_plot_of_a_file_named_in_a_script_the_font_lacks_says_nothing_more(tiny_run, tmp_path):
    """matplotlib warned about every CJK glyph of the title (the file's name), with its source lines, on stderr."""
    _, run_csv, _ = tiny_run
    named = tmp_path / "my clip ü 日本.lptrack.csv"
    named.write_text(run_csv.read_text())
    import warnings
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # as a plain `python -W default` run shows them
        result = invoke("plot", named, "-o", tmp_path / "out.png", "--no-video")
    assert result.exit_code == 0, result.stderr
    assert not [w for w in caught if "Glyph" in str(w.message)]


@needs_matplotlib
def test_plot_takes_a_sequence_folder_as_ground_truth_as_eval_does(tiny_run, tmp_path):
    video, run_csv, gt = tiny_run
    folder = tmp_path / "tiny"
    folder.mkdir()
    shutil.copy(video.path, folder / "tiny.mp4")
    shutil.copy(gt, folder / "tiny.gt.csv")
    from_file, from_folder = tmp_path / "file.png", tmp_path / "folder.png"
    assert invoke("plot", run_csv, "-o", from_file, "--gt", gt, "--no-video").exit_code == 0
    result = invoke("plot", run_csv, "-o", from_folder, "--gt", folder, "--no-video")
    assert result.exit_code == 0, result.stderr
    assert from_folder.read_bytes() == from_file.read_bytes()


@needs_matplotlib
def test_plot_refuses_a_run_given_as_ground_truth_as_eval_does(tiny_run, tmp_path):
    """A run CSV has every column a .gt.csv needs; taken as one, it scored the run against itself (AUC 1)."""
    _, run_csv, _ = tiny_run
    out = tmp_path / "p.png"
    result = invoke("plot", run_csv, "-o", out, "--gt", run_csv, "--no-video")
    assert result.exit_code == 1 and result.stderr == (
        f"lptrack: error: ground truth '{run_csv}' is an lptrack run (its columns include time_s and status), "
        f"not ground truth\n")
    assert not out.exists() and list(tmp_path.iterdir()) == []


@needs_matplotlib
def test_plot_refuses_ground_truth_without_a_frame_of_the_run_as_eval_does(tiny_run, tmp_path):
    """Ground truth that ends before the run's frames (another video's, a cut one) drew an empty error panel and a
    legend line drawn nowhere, exit 0, without a word; `lptrack eval` refuses the pair."""
    _, run_csv, gt = tiny_run
    lines = gt.read_text().splitlines()
    short = tmp_path / "short.gt.csv"
    short.write_text("\n".join(lines[:2]) + "\n")  # frame 0 only
    late = tmp_path / "late.csv"
    rows = run_csv.read_text().splitlines()
    late.write_text("\n".join([rows[0], *rows[2:]]) + "\n")  # the run from frame 1 on
    out = tmp_path / "p.png"
    result = invoke("plot", late, "-o", out, "--gt", short, "--no-video")
    assert result.exit_code == 2 and result.stderr == (
        f"lptrack: error: no frame of 'late.csv' has ground truth in '{short}' (frames are matched by index, "
        f"0 = first frame)\n")
    assert not out.exists()
    assert invoke("eval", late, short).exit_code == 2  # as eval says
    result = invoke("plot", run_csv, "-o", out, "--gt", short, "--no-video")  # one frame in common: drawn
    assert result.exit_code == 0, result.stderr
    # and the rows past its end noted, as eval notes them (the error panel ends there).
    n = len(rows) - 1
    assert result.stderr == (f"lptrack: note: {n - 1} of the {n} rows of '{run_csv}' lie past the end of '{short}' "
                             f"(1 frame); they have no ground truth to plot (is it this video's ground truth?)\n")


@needs_matplotlib
def test_plot_finds_the_video_next_to_a_default_named_csv(tiny_run, tmp_path, monkeypatch):
    video, run_csv, _ = tiny_run
    folder = tmp_path / "here"
    folder.mkdir()
    (folder / "tiny.mp4").write_bytes(video.path.read_bytes())
    (folder / "tiny.lptrack.csv").write_text(run_csv.read_text())
    assert find_video_for_csv(folder / "tiny.lptrack.csv") == folder / "tiny.mp4"
    assert find_video_for_csv(run_csv, folders=()) is None  # no tiny.mp4 beside it
    monkeypatch.chdir(folder)
    result = invoke("plot", "tiny.lptrack.csv")
    assert result.exit_code == 0, result.stderr
    assert "thumbnail from" in result.stderr and "tiny.mp4" in result.stderr
    assert png_size(folder / "tiny.lptrack.plot.png") == PLOT_SIZE


def test_the_source_of_an_image_sequence_run_is_its_folder_of_the_csvs_name(tiny_run, tmp_path):
    # 'lptrack run img/%04d.jpg' (OTB's layout) writes img.lptrack.csv beside img/.
    _, run_csv, _ = tiny_run
    (tmp_path / "img").mkdir()
    for i in (1, 2, 3):
        cv2.imwrite(str(tmp_path / "img" / f"{i:04d}.png"), np.full((8, 8, 3), 40 * i, np.uint8))
    (tmp_path / "img" / "notes.txt").write_text("not an image")
    (tmp_path / "img.lptrack.csv").write_text(run_csv.read_text())
    found = find_video_for_csv(tmp_path / "img.lptrack.csv", folders=())
    assert found == tmp_path / "img" / "%04d.png"
    assert read_frame(found, 2).image[0, 0, 0] == 120
    # A folder of that name without numbered images is no source.
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "cover.png").write_bytes((tmp_path / "img" / "0001.png").read_bytes())
    (tmp_path / "other.lptrack.csv").write_text(run_csv.read_text())
    assert find_video_for_csv(tmp_path / "other.lptrack.csv", folders=()) is None


@needs_matplotlib
def test_plot_says_where_it_looked_when_it_finds_no_video(tiny_run, tmp_path, monkeypatch):
    _, run_csv, _ = tiny_run
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "tiny.lptrack.csv").write_text(run_csv.read_text())
    monkeypatch.chdir(tmp_path)
    result = invoke("plot", "runs/tiny.lptrack.csv", "-o", "p.png")
    assert result.exit_code == 0 and result.stdout == "p.png\n"
    assert result.stderr == ("lptrack: note: no thumbnail: no tiny.mp4 (or .m4v, .mov, .avi, .mkv, .webm, ..., or a "
                             "folder tiny/ of numbered images) in 'runs' "
                             "or the current folder; give the tracked video with --video VIDEO (or --no-video for "
                             "blank axes)\n")
    (tmp_path / "tiny.mp4").write_bytes(b"")
    (tmp_path / "tiny.avi").write_bytes(b"")
    result = invoke("plot", "runs/tiny.lptrack.csv", "-o", "p.png", "--overwrite")
    assert result.exit_code == 0
    assert "no thumbnail: the current folder holds several videos it could be (tiny.mp4, tiny.avi); give the " \
           "tracked video with --video VIDEO" in result.stderr
    for quiet in ("-q", "--no-video"):
        result = invoke("plot", "runs/tiny.lptrack.csv", "-o", "p.png", "--overwrite", quiet)
        assert result.exit_code == 0 and result.stderr == ""
    # A failed plot is one error line, without the note before it.
    assert "already exists" in one_error_line(invoke("plot", "runs/tiny.lptrack.csv", "-o", "p.png"), 1)


def test_video_of_a_json_lines_run_is_found_by_its_stem_not_the_annotated_copy(tmp_path):
    for name in ("clip.lptrack.mp4", "clip.mp4"):
        (tmp_path / name).write_bytes(b"")
    assert find_video_for_csv(tmp_path / "clip.lptrack.jsonl", folders=()) == tmp_path / "clip.mp4"
    assert find_video_for_csv(tmp_path / "clip.lptrack.csv", folders=()) == tmp_path / "clip.mp4"


def test_plot_without_matplotlib_gives_the_install_hint(tiny_run, tmp_path, monkeypatch):
    _, run_csv, _ = tiny_run
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` raise ImportError
    line = one_error_line(invoke("plot", run_csv, "-o", tmp_path / "p.png"), 2)
    assert "pip install matplotlib" in line
    assert not (tmp_path / "p.png").exists()


def test_frame_command_on_an_image_sequence_takes_its_rate_from_fps(tiny_video, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "shots").mkdir()
    for number, image in enumerate(tiny_video.frames, start=1):
        cv2.imwrite(str(tmp_path / "shots" / f"frame_{number:04d}.png"), image)
    pattern = Path("shots") / "frame_%04d.png"
    result = invoke("frame", pattern, "--time", 0.5, "--fps", 10, "--grid", 0)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == "frame.frame5.png"  # named after the pattern; 0.5 s at 10 fps: frame 5
    assert np.array_equal(cv2.imread("frame.frame5.png")[:96], tiny_video.frames[5][:96])
    assert "25 fps" in one_error_line(invoke("frame", pattern, "--time", 1.0), 2)  # 25 assumed without --fps
    assert (read_frame(pattern, time_s=0.5).fps_guessed, read_frame(pattern, time_s=0.5, fps=10).fps_guessed) == \
        (True, False)
    assert one_error_line(invoke("frame", pattern, "--fps", 0), 2) == \
        "lptrack: error: the frame rate must be a positive number of frames per second, from 0.001 to 1,000,000, got 0"


@needs_matplotlib
def test_plot_draws_the_csvs_path_y_down_its_rotation_and_its_lost_frames(tiny_run, tmp_path, monkeypatch):
    """What is drawn, not only that a PNG came out: the path is the CSV's (cx, cy) on a y-down axis (as on
    screen), the rotation panel the CSV's rotation_deg (CCW, not negated), red crosses at the lost frames."""
    from matplotlib.figure import Figure

    video, run_csv, _ = tiny_run
    rows = list(csv.DictReader(run_csv.open()))
    lost_frames = [5, 12]
    for k in lost_frames:
        rows[k]["status"] = "lost"
    marked = tmp_path / "marked.lptrack.csv"
    with open(marked, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    rotation = np.array([float(r["rotation_deg"]) for r in rows])
    assert np.ptp(rotation) > 10  # a sign flip would show
    drawn = {}

    def record(figure, path, **kwargs):
        Path(path).write_bytes(b"")
        drawn["figure"] = figure

    monkeypatch.setattr(Figure, "savefig", record)
    result = invoke("plot", marked, "-o", tmp_path / "p.png", "--no-video")
    assert result.exit_code == 0, result.stderr
    axes = drawn["figure"].axes
    (path_ax,) = [ax for ax in axes if ax.get_title() == "centre path"]
    (rot_ax,) = [ax for ax in axes if ax.get_ylabel() == "rotation (deg CCW)"]
    assert path_ax.yaxis_inverted() and not path_ax.xaxis_inverted()
    lines = {line.get_label(): line for line in path_ax.lines}
    cx, cy = (np.array([float(r[k]) for r in rows]) for k in ("cx", "cy"))
    np.testing.assert_allclose(lines["track centre"].get_xdata(), cx)
    np.testing.assert_allclose(lines["track centre"].get_ydata(), cy)
    np.testing.assert_allclose(lines["lost"].get_xdata(), cx[lost_frames])
    np.testing.assert_allclose(lines["lost"].get_ydata(), cy[lost_frames])
    (track,) = [line for line in rot_ax.lines if line.get_label() == "track"]
    np.testing.assert_allclose(track.get_xdata(), [float(r["time_s"]) for r in rows])
    np.testing.assert_allclose(track.get_ydata(), rotation)


def test_the_old_look_module_still_imports_its_names_with_a_warning():
    # 0.x's logpolar_track.look held these; its jobs moved to their own modules (2026-12-07).
    import importlib
    import sys

    from logpolar_track import contact_sheet, plot, roi_fit, video

    sys.modules.pop("logpolar_track.look", None)
    with pytest.warns(DeprecationWarning, match="logpolar_track.look is deprecated"):
        look = importlib.import_module("logpolar_track.look")
    assert (look.read_frame, look.roi_from_box, look.plot_track, look.write_contact_sheet) == (
        video.read_frame, roi_fit.roi_from_box, plot.plot_track, contact_sheet.write_contact_sheet)

