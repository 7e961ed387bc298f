"""Drawing: the outline lies where the ellipse is (sign of the angle), the radius line turns, colours tell lost."""

from __future__ import annotations

import numpy as np
import pytest

from logpolar_track.draw import LOST_COLOUR, TRACKED_COLOUR, draw_state, readout_text, signed
from logpolar_track.errors import UsageError
from logpolar_track.geometry import Ellipse
from logpolar_track.trackers import TrackState

H, W = 200, 240


def _state(ellipse, rotation=0.0, score=0.9):
    return TrackState(ellipse, 1.0, rotation, score)


def _painted(image, colour):
    """Mask of pixels close to ``colour`` (anti-aliasing blends edges, so allow a margin)."""
    return np.abs(image.astype(int) - np.array(colour)).max(axis=2) < 90


def _near_mask(mask, points, radius=1):
    hits = 0
    for x, y in points:
        xi, yi = int(round(x)), int(round(y))
        hits += mask[max(yi - radius, 0):yi + radius + 1, max(xi - radius, 0):xi + radius + 1].any()
    return hits / len(points)


def test_returns_a_copy_and_leaves_the_frame_alone():
    frame = np.full((H, W, 3), 50, np.uint8)
    before = frame.copy()
    out = draw_state(frame, _state(Ellipse(120, 100, 40, 20, 30)), frame_index=4)
    assert np.array_equal(frame, before)
    assert out.shape == frame.shape and out.dtype == np.uint8 and out is not frame
    assert not np.array_equal(out, frame)


@pytest.mark.parametrize("angle", [30.0, -50.0, 120.0])
def test_outline_follows_the_ccw_angle(angle):
    """OpenCV's ellipse angle is clockwise on screen: the drawing must match Ellipse.boundary_points (CCW)."""
    ellipse = Ellipse(120, 100, 60, 20, angle)
    out = draw_state(np.zeros((H, W, 3), np.uint8), _state(ellipse), text=False)
    mask = _painted(out, TRACKED_COLOUR)
    assert _near_mask(mask, ellipse.boundary_points(72)) > 0.95
    mirrored = Ellipse(120, 100, 60, 20, -angle)
    assert _near_mask(mask, mirrored.boundary_points(72)) < 0.5  # fails if the angle's sign were wrong


@pytest.mark.parametrize("angle, on, off", [(0.0, (150, 100), (120, 70)),     # axis a to the right
                                            (90.0, (120, 70), (150, 100)),    # CCW 90: straight up
                                            (-90.0, (120, 130), (120, 70))])  # CW 90: straight down
def test_radius_line_points_along_axis_a(angle, on, off):
    ellipse = Ellipse(120, 100, 40, 40, angle)
    out = draw_state(np.zeros((H, W, 3), np.uint8), _state(ellipse, rotation=angle), text=False)
    mask = _painted(out, TRACKED_COLOUR)
    assert mask[on[1], on[0]]
    assert not mask[off[1], off[0]]


def test_lost_frames_use_the_lost_colour():
    ellipse = Ellipse(120, 100, 40, 30, 0)
    tracked = draw_state(np.zeros((H, W, 3), np.uint8), _state(ellipse), status="tracked", text=False)
    lost = draw_state(np.zeros((H, W, 3), np.uint8), _state(ellipse), status="lost", text=False)
    assert _painted(tracked, TRACKED_COLOUR).sum() > 100 and _painted(tracked, LOST_COLOUR).sum() == 0
    assert _painted(lost, LOST_COLOUR).sum() > 100 and _painted(lost, TRACKED_COLOUR).sum() == 0


def test_readout_is_drawn_top_left_only_when_asked():
    frame = np.full((H, W, 3), 128, np.uint8)
    state = _state(Ellipse(180, 150, 20, 20, 0))
    with_text = draw_state(frame, state, frame_index=7)
    without = draw_state(frame, state, frame_index=7, text=False)
    assert not np.array_equal(with_text[:15, :100], frame[:15, :100])
    assert np.array_equal(without[:15, :100], frame[:15, :100])


def test_readout_text():
    state = TrackState(Ellipse(0, 0, 1, 1), 1.23456, -45.04, 0.876)
    assert readout_text(state, frame_index=12) == "frame 12  scale 1.235  rot -45.0 deg  score 0.88"
    no_rotation = TrackState(Ellipse(0, 0, 1, 1), 1.0, None, 0.1)
    assert readout_text(no_rotation, status="lost") == "scale 1.000  score 0.10  LOST"


def test_readout_never_shows_minus_zero():
    # A rotation of a few hundredths of a degree below zero, as a tracker at rest reports, reads as no turn.
    for tiny in (-0.04, -0.0):
        state = TrackState(Ellipse(0, 0, 1, 1), 1.0, tiny, 0.5)
        assert readout_text(state) == "scale 1.000  rot +0.0 deg  score 0.50"
    assert signed(-0.4, 0) == "+0" and signed(-0.6, 0) == "-1" and signed(0.06, 1) == "+0.1"


def test_grey_frame_and_state_far_off_frame():
    grey = np.zeros((H, W), np.uint8)
    out = draw_state(grey, _state(Ellipse(1e9, -1e9, 1e7, 5, 10)))
    assert out.shape == (H, W, 3)


def test_drawing_takes_every_frame_a_tracker_takes():
    """draw_grid raised ValueError on a BGRA frame and cv2.error on float32; draw_roi an AttributeError on a --roi
    string (a fresh review of the library)."""
    from logpolar_track.draw import draw_grid, draw_roi

    bgr = np.random.default_rng(0).integers(0, 255, (100, 120, 3), np.uint8)
    variants = [bgr, np.dstack([bgr, np.full((100, 120), 255, np.uint8)]), bgr.astype(np.float32)]
    grids = [draw_grid(v, 20) for v in variants]
    rois = [draw_roi(v, "60,50,20") for v in variants]
    for drawn in (grids, rois):
        assert all(d.dtype == np.uint8 and d.shape == (100, 120, 3) for d in drawn)
        assert all(np.array_equal(d, drawn[0]) for d in drawn[1:])
    assert np.array_equal(rois[0], draw_roi(bgr, Ellipse(60, 50, 20, 20)))
    with pytest.raises(UsageError, match="a frame must be uint8"):
        draw_grid(bgr.astype(np.float64))
