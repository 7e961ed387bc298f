"""Trackers on synthetic sequences with exact ground truth (logpolar_track.synthetic).

Conventions: centre in pixels, scale relative to frame 0, rotation in degrees counter-clockwise on screen,
cumulative (unwrapped).
"""

import copy
import math
import re
from functools import lru_cache

import cv2
import numpy as np
import pytest

from logpolar_track.errors import LptrackError, NotStartedError, RoiError, UsageError
from logpolar_track.geometry import Ellipse
from logpolar_track.images import to_gray
from logpolar_track.synthetic import Pose, random_texture, render_frame, similarity_path, synthetic_sequence
from logpolar_track.trackers import (TrackState, create_tracker, tracker_class, tracker_names, tracker_parameters,
                                    tracker_params_from_text)

#: The thesis' log-polar trackers, held to the issue's bounds.
THESIS = ["fixed", "diffdecomp", "update", "occlusion"]


def _is_peer(name):
    return name.startswith("cv-") or not getattr(tracker_class(name), "measures_rotation", True)


#: Every registered tracker of lptrack's own held to the same bounds (new ones are covered automatically);
#: `spatial` is bounded by its grid and has its own test.
ACCURATE = sorted(set(THESIS) | {n for n in tracker_names() if not _is_peer(n) and n != "spatial"},
                  key=lambda n: (n not in THESIS, n))

SHAPES = {"circle": Ellipse.circle(160, 110, 35), "ellipse": Ellipse(160, 110, 40, 26, 30)}


@lru_cache(maxsize=None)
def sequence(shape, turns, scale_range=(0.5, 2.0), n=70, radius_px=30.0, seed=0):
    roi = SHAPES[shape]
    poses = similarity_path(n, (roi.cx, roi.cy), scale_range=scale_range, turns=turns, radius_px=radius_px)
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=seed))
    return roi, poses, frames


def track(name, roi, frames, **params):
    tracker = create_tracker(name, **params)
    first = tracker.init(frames[0], roi)
    assert first.scale == 1.0 and first.rotation_deg == 0.0
    return [tracker.update(f) for f in frames[1:]]


def errors(results, poses):
    centre = np.array([math.hypot(s.centre[0] - p.cx, s.centre[1] - p.cy) for (_, s), p in zip(results, poses[1:])])
    scale = np.array([abs(s.scale / p.scale - 1) for (_, s), p in zip(results, poses[1:])])
    rotation = np.array([abs(s.rotation_deg - p.rotation_deg) for (_, s), p in zip(results, poses[1:])])
    lost = sum(not ok for ok, _ in results)
    return centre, scale, rotation, lost


def test_thesis_trackers_are_registered():
    assert set(THESIS) <= set(tracker_names())
    assert "spatial" in tracker_names()


@pytest.mark.parametrize("turns", [1.3, -1.3], ids=["ccw", "cw"])
@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("name", ACCURATE)
def test_accuracy_scale_half_to_double_beyond_a_full_turn(name, shape, turns):
    roi, poses, frames = sequence(shape, turns)
    assert abs(poses[-1].rotation_deg) > 360 and min(p.scale for p in poses) < 0.55
    centre, scale, rotation, lost = errors(track(name, roi, frames), poses)
    assert lost == 0
    assert np.median(centre) <= 1.0
    assert np.median(scale) <= 0.02
    assert np.median(rotation) <= 1.0


@pytest.mark.parametrize("turns", [0.5, -0.5], ids=["ccw", "cw"])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_spatial_accuracy_within_its_grid(shape, turns):
    # The default grid follows at most 2 steps per frame: 4 % in scale and 4 degrees. This path moves at most
    # ~2.6 degrees and ~2.7 % per frame.
    roi, poses, frames = sequence(shape, turns, scale_range=(0.75, 1.35), n=80, radius_px=25.0)
    centre, scale, rotation, lost = errors(track("spatial", roi, frames), poses)
    assert lost == 0
    assert np.median(centre) <= 0.5 and centre.max() <= 1.5
    assert np.median(scale) <= 0.02          # one scale step
    assert np.median(rotation) <= 1.0        # half an angle step


def test_spatial_rejects_bad_grid():
    with pytest.raises(ValueError, match="odd"):
        create_tracker("spatial", n_angles=4)
    with pytest.raises(ValueError, match="window"):
        create_tracker("spatial", window=10)


def _turned_pair(angle_deg, scale=1.0):
    """Two frames built by hand: the second is the first turned ``angle_deg`` about the ROI's centre with
    cv2.getRotationMatrix2D, whose positive angle is counter-clockwise on screen (independent of synthetic.py)."""
    rng = np.random.default_rng(5)
    frame = random_texture(240, 320, rng)
    centre = (160.0, 120.0)
    m = cv2.getRotationMatrix2D(centre, angle_deg, scale)
    turned = cv2.warpAffine(frame, m, (320, 240), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return Ellipse.circle(*centre, 40), frame, turned


@pytest.mark.parametrize("name", ACCURATE + ["spatial"])
def test_counter_clockwise_turn_on_screen_is_positive(name):
    angle = 3.0 if name == "spatial" else 10.0  # spatial's default grid follows at most 4 degrees per frame
    roi, frame, turned = _turned_pair(angle, 1.03)
    ok, state = track(name, roi, [frame, turned])[0]
    assert ok
    assert state.rotation_deg == pytest.approx(angle, abs=1.0)
    assert state.scale == pytest.approx(1.03, abs=0.01)
    assert state.ellipse.angle_deg == pytest.approx(angle, abs=1.0)
    # Plain Python floats reach the caller, not NumPy scalars (which print as np.float64(...) under NumPy 2).
    e = state.ellipse
    assert all(type(v) is float for v in (e.cx, e.cy, e.a, e.b, e.angle_deg, state.scale, state.rotation_deg,
                                          state.score))


@pytest.mark.parametrize("name", THESIS)
def test_two_full_turns_read_720(name):
    roi = SHAPES["circle"]
    poses = [Pose(roi.cx, roi.cy, 1.0, 720.0 * i / 48) for i in range(49)]  # 15 degrees per frame
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=2))
    results = track(name, roi, frames)
    assert all(ok for ok, _ in results)
    assert results[-1][1].rotation_deg == pytest.approx(720.0, abs=1.0)


def _stranger(frames, poses, roi, seed):
    """Frame 10 of the swapped-object scene with the object's disc replaced by an unrelated texture."""
    return render_frame(frames[10], random_texture(90, 90, np.random.default_rng(seed)), roi,
                        Pose(poses[9].cx, poses[9].cy, poses[9].scale, 0.0))


@pytest.mark.parametrize("name", [n for n in ACCURATE + ["spatial"] if n not in THESIS])
def test_lost_when_object_replaced_then_found_again(name):
    # Default settings. The thesis trackers' default lost_threshold sits on their noise floor: see the next test.
    roi, poses, frames = sequence("circle", 0.15, scale_range=(0.9, 1.1), n=20, radius_px=10.0)
    tracker = create_tracker(name)
    tracker.init(frames[0], roi)
    for f in frames[1:10]:
        ok, good = tracker.update(f)
        assert ok
    ok, state = tracker.update(_stranger(frames, poses, roi, 77))
    assert not ok
    assert state.ellipse == good.ellipse and state.scale == good.scale and state.rotation_deg == good.rotation_deg
    assert 0.0 <= state.score < tracker.lost_threshold
    # It keeps searching and finds the object when it comes back.
    ok, state = tracker.update(frames[10])
    assert ok and math.hypot(state.centre[0] - poses[10].cx, state.centre[1] - poses[10].cy) < 1.0


@pytest.mark.parametrize("name", THESIS)
def test_thesis_trackers_default_lost_threshold_sits_on_the_noise_floor(name):
    """Known limit, asserted rather than hidden: the thesis trackers' score (a phase-correlation peak height) of an
    unrelated texture put in the object's place is 0.11-0.23 with the default settings, and their default
    lost_threshold, 0.2, lies inside that range: some strangers are reported tracked. (Measured over 30 strangers
    here: fixed 10 tracked, update 12, occlusion 1, diffdecomp 1.) No default separates them: the object scores
    0.45 or more in this scene, but on sample_videos/ it scores down to 0.12-0.17 while half covered (occlusion) or
    changing (appearance), and raising the threshold to 0.25-0.3 there reports lost 6.7 % -> 39-51 % of
    appearance's frames (fixed, occlusion), halves update's success on occlusion (93 -> 35 % at 0.3) and occlusion's on
    noise_blur (94 -> 53 %); see README. A stranger reported lost keeps the last state, and the object is found
    again."""
    roi, poses, frames = sequence("circle", 0.15, scale_range=(0.9, 1.1), n=20, radius_px=10.0)
    tracker = create_tracker(name)
    assert tracker.lost_threshold == 0.2
    tracker.init(frames[0], roi)
    on_object = []
    for f in frames[1:10]:
        ok, good = tracker.update(f)
        assert ok
        on_object.append(good.score)
    scores, tracked = [], 0
    for seed in range(30):
        probe = copy.deepcopy(tracker)
        ok, state = probe.update(_stranger(frames, poses, roi, seed))
        scores.append(state.score)
        tracked += ok
        assert ok == (state.score >= tracker.lost_threshold)
        if not ok:
            assert state.ellipse == good.ellipse and state.scale == good.scale
            ok, state = probe.update(frames[10])
            assert ok and math.hypot(state.centre[0] - poses[10].cx, state.centre[1] - poses[10].cy) < 1.0
    # Far below the object here (a threshold of 0.3 would separate this scene) ...
    assert 0.1 < min(scores) and max(scores) < 0.3 and min(on_object) > 0.4
    # ... yet the default threshold is within the strangers' range: it does not separate them.
    assert max(scores) > tracker.lost_threshold - 0.02 and min(scores) < tracker.lost_threshold - 0.03
    if name in ("fixed", "update"):
        assert tracked >= 6  # a fifth or more of the strangers are reported tracked


@pytest.mark.parametrize("name", ACCURATE + ["spatial"])
def test_roi_partly_over_the_border_still_tracks(name):
    roi = Ellipse.circle(25, 120, 35)  # a third of the disc hangs over the left edge
    poses = [Pose(25 + 0.5 * i, 120 - 0.3 * i, 1.0 + 0.004 * i, 1.5 * i) for i in range(15)]
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=4))
    centre, scale, rotation, lost = errors(track(name, roi, frames), poses)
    assert lost == 0
    assert np.median(centre) <= 1.0 and np.median(scale) <= 0.02 and np.median(rotation) <= 1.0


@pytest.mark.parametrize("name", THESIS)
def test_coarse_to_fine_equals_exhaustive_reference(name):
    """The fast path (coarse=True) gives the exhaustive full-size search's estimates up to float rounding."""
    roi, poses, frames = sequence("ellipse", 1.3)
    frames = frames[:30]
    fast = track(name, roi, frames)
    reference = track(name, roi, frames, coarse=False)
    for (ok_f, f), (ok_r, r) in zip(fast, reference):
        assert ok_f == ok_r
        assert f.centre == pytest.approx(r.centre, abs=1e-3)
        assert f.scale == pytest.approx(r.scale, rel=1e-4)
        assert f.rotation_deg == pytest.approx(r.rotation_deg, abs=1e-3)
        assert f.score == pytest.approx(r.score, abs=1e-4)


def test_coarse_stage_finds_a_peak_the_checkerboard_skips():
    """The coarse stage scores the checkerboard, then the skipped cells beside its best: a peak on a skipped
    cell is found, with about half the cells scored."""
    tracker = create_tracker("fixed")
    n = tracker.window
    peak = 2 * n + 7  # row 2, column 7: offsets (2, -3), dx + dy odd, not on the checkerboard
    assert peak not in tracker.coarse_cells
    rows, cols = np.divmod(np.arange(n * n), n)
    surface = 1.0 / (1.0 + np.hypot(rows - 2, cols - 7))
    scored = []

    def score(cells):
        scored.extend(int(c) for c in cells)
        return surface[cells][None]

    assert tracker._coarse_starts(score).tolist() == [peak]
    assert len(scored) == len(set(scored)) < 0.6 * n * n
    corner = tracker.cell_neighbours[0].tolist()
    assert sorted(corner) == [-1, -1, 1, n]


@pytest.mark.parametrize("name", ACCURATE + ["spatial"])
def test_frames_are_not_modified(name):
    roi, _, frames = sequence("circle", 0.3, scale_range=(0.9, 1.1), n=3, radius_px=5.0)
    copies = [f.copy() for f in frames]
    track(name, roi, frames)
    assert all(np.array_equal(a, b) for a, b in zip(frames, copies))


def test_update_before_init_raises():
    for name in [n for n in tracker_names() if n in ("fixed", "lpcf", "cv-mil")]:
        # A library error, and a RuntimeError as before.
        with pytest.raises(NotStartedError, match=r"update\(\) called before init\(\)"):
            create_tracker(name).update(np.zeros((10, 10, 3), np.uint8))
        assert issubclass(NotStartedError, RuntimeError) and issubclass(NotStartedError, LptrackError)


@pytest.mark.skipif("cv-mil" not in tracker_names(), reason="OpenCV's MIL is not in this build")
def test_a_refused_start_leaves_an_opencv_tracker_as_it_was():
    """MIL refuses a box that spans the frame (no negatives around it); its object, kept after the failed init,
    crashed the process on the next update (SIGSEGV), and a fresh one raised AttributeError."""
    frame = np.random.default_rng(0).integers(0, 255, (240, 320, 3), np.uint8)
    fresh = create_tracker("cv-mil")
    with pytest.raises(RoiError, match="cannot start on the ROI's box"):
        fresh.init(frame, (160, 120, 170, 130, 0))
    with pytest.raises(NotStartedError):
        fresh.update(frame)
    started = create_tracker("cv-mil")
    started.init(frame, (150, 120, 40))
    with pytest.raises(RoiError):
        started.init(frame, (160, 120, 170, 130, 0))
    ok, state = started.update(frame)  # the first track goes on
    assert ok and abs(state.ellipse.cx - 150) <= 2 and state.ellipse.a == 40.0


def test_a_float_frame_of_0_to_1_is_refused_at_the_start():
    frame = np.random.default_rng(1).random((120, 160, 3)).astype(np.float32)  # scikit-image's scale
    for name in [n for n in tracker_names() if n in ("fixed", "lpcf", "cv-mil")]:
        with pytest.raises(UsageError, match="values from 0 to 255 .* all within 0 to 1: multiply it by 255"):
            create_tracker(name).init(frame, (80, 60, 20))
        create_tracker(name).init(frame * 255, (80, 60, 20))


@pytest.mark.parametrize("name", [n for n in tracker_names() if n in ("fixed", "lpcf")])
@pytest.mark.parametrize("frame, roi, error, fragment", [
    (np.zeros((120, 160, 3), np.uint8), Ellipse(200, 60, 20, 20, 0), RoiError, "outside"),
    (np.zeros((120, 160, 3), np.uint8), Ellipse(80, 60, 0.5, 0.5, 0), RoiError, "small"),
    (np.zeros(160, np.uint8), Ellipse(80, 60, 20, 20, 0), UsageError, "(H, W)"),
    (np.zeros((120, 160, 2), np.uint8), Ellipse(80, 60, 20, 20, 0), UsageError, "(H, W)"),
    (np.zeros((120, 160, 3)), Ellipse(80, 60, 20, 20, 0), UsageError, "uint8 (or float32 with values 0 to 255), "
                                                                      "got float64"),
    (np.zeros((120, 160), np.uint16), Ellipse(80, 60, 20, 20, 0), UsageError, "got uint16; convert it first, e.g. "
                                                                                 "(frame >> 8).astype(np.uint8)"),
    (np.zeros((120, 160, 3)), Ellipse(80, 60, 20, 20, 0), UsageError, "e.g. frame.astype(np.float32) for values 0 "
                                                                      "to 255, (frame * 255).clip(0, 255)"),
    (np.zeros((120, 160), np.int16), Ellipse(80, 60, 20, 20, 0), UsageError, "got int16; convert it first, e.g. one "
                                                                                "scale for the whole video"),
])
def test_init_refuses_what_it_cannot_track(name, frame, roi, error, fragment):
    """Called from Python, a tracker says what is wrong with its start (as ``lptrack run`` does), instead of
    dividing by zero or reporting every frame lost."""
    with pytest.raises(error, match=re.escape(fragment)):
        create_tracker(name).init(frame, roi)


def _frame_kinds(bgr):
    """The same picture in every layout a tracker accepts: BGR, grey, (H, W, 1) grey, BGRA, float32 BGR."""
    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    return {"bgr": bgr, "grey": grey, "grey (H, W, 1)": grey[:, :, None],
            "bgra": cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA), "float32 bgr": bgr.astype(np.float32)}


@pytest.mark.parametrize("name", tracker_names())
def test_every_accepted_frame_layout_tracks_alike(name):
    """A frame from cv2.imread(..., IMREAD_UNCHANGED) (grey with a channel axis, or BGRA) or a float32 one tracks
    as its BGR original does, for OpenCV's trackers too (which take only 3-channel uint8 themselves)."""
    rng = np.random.default_rng(4)
    first = cv2.GaussianBlur(random_texture(120, 160, rng), (0, 0), 1.5)
    moved = np.roll(first, (2, 3), axis=(0, 1))
    # Near the left edge, so that the patches reach out of the frame (which lpcf fills with the frame's mean).
    roi = Ellipse(30, 60, 22, 22, 0)
    centres = {}
    later = _frame_kinds(moved)
    for kind, start in _frame_kinds(first).items():
        tracker = create_tracker(name)
        tracker.init(start, roi)
        ok, state = tracker.update(later[kind])
        assert ok, kind
        centres[kind] = (state.ellipse.cx, state.ellipse.cy)
    # A layout read wrongly (channels taken for columns, BGRA's alpha for blue, float as bytes) loses the texture
    # or shifts it by far more than these bounds. OpenCV's trackers report whole-pixel boxes; ours track every layout
    # alike to rounding (measured: 0.03 px at most).
    alike = 1.0 if name.startswith("cv-") else 0.2
    # OpenCV 5.1's KCF does not follow this texture's shift at all (cv2.TrackerKCF's own box stays put, in every
    # layout, for shifts of 3 to 8 px): for it, only that every layout does the same.
    truth = centres["bgr"] if name == "cv-kcf" else (33, 62)
    for kind, centre in centres.items():
        assert centre == pytest.approx(truth, abs=max(alike, 0.5)), kind
        assert centre == pytest.approx(centres["grey"], abs=alike), kind


@pytest.mark.parametrize("name", tracker_names())
@pytest.mark.parametrize("frame, fragment", [
    (np.zeros((120, 160, 3)), "got float64"),
    (np.zeros((120, 160, 2), np.uint8), "got shape (120, 160, 2)"),
    (np.zeros((100, 160, 3), np.uint8), "the size of the first (160x120 pixels), got 160x100"),
    (np.zeros((120, 160), np.uint8), "laid out as the first (BGR uint8), got grey uint8"),
    (np.zeros((120, 160, 3), np.float32), "laid out as the first (BGR uint8), got BGR float32"),
])
def test_update_refuses_what_it_cannot_track(name, frame, fragment):
    """A frame given to update() is held to init()'s rules, and to the first frame's size and layout: one line
    saying what is wrong, not an OpenCV assertion or a track in the wrong place (lpcf's colour model, built from
    a BGR first frame, failed on a grey one in cv2.transform and on a float one in a shift)."""
    tracker = create_tracker(name)
    tracker.init(random_texture(120, 160, np.random.default_rng(0)), Ellipse(80, 60, 20, 20, 0))
    with pytest.raises(UsageError, match=re.escape(fragment)):
        tracker.update(frame)


@pytest.mark.parametrize("name", [n for n in tracker_names() if not n.startswith("cv-")])
def test_a_roi_angle_of_many_turns_tracks_as_its_angle_within_one(name):
    """An Ellipse's angle may be any finite number; the trackers compute their patches' angles from it, and one of
    1e300 degrees (through the API) left no precision for the turn tracked (4041 degrees reported for 39.5)."""
    roi = Ellipse(80, 60, 25, 15, 30.0)
    poses = [Pose(80, 60, 1.0, 2.0 * i) for i in range(6)]
    frames = list(synthetic_sequence(poses, roi, size=(160, 120), seed=2))
    rotations = []
    for angle in (30.0, 30.0 + 360.0 * 10 ** 6, 1e300):
        tracker = create_tracker(name)
        tracker.init(frames[0], Ellipse(80, 60, 25, 15, angle))
        rotations.append([tracker.update(f)[1].rotation_deg for f in frames[1:]])
    assert rotations[1] == pytest.approx(rotations[0], abs=1e-6)
    assert abs(rotations[2][-1] - 10.0) < 4.0  # 1e300 is some angle, another axis of the object: its turn is read


# MIL samples at random: its two runs below would differ whatever their frames.
@pytest.mark.parametrize("name", [n for n in tracker_names() if n != "cv-mil"])
@pytest.mark.parametrize("cx", [80, 0], ids=["inside", "over_the_edge"])
def test_float_frames_beyond_0_to_255_track_as_clipped(name, cx):
    """Float32 frames are taken with values 0 to 255; NaN, infinities and values beyond are read as clipped to
    that (NaN as 0), channel by channel, rather than passed on: NaN reached lpcf's features as a garbage bin index
    (IndexError). Also where the ROI hangs over the frame's edge, whose samples beyond it read the frame's mean grey:
    lpcf took that mean of the raw frame, NaN with one NaN pixel (fuzzing found it), and its init crashed."""
    frame = random_texture(120, 160, np.random.default_rng(0)).astype(np.float32)
    broken = frame.copy()
    broken[50:56, 70:76] = np.nan
    broken[60:63, 80:90] = np.inf
    broken[70, 60:70] = 1e30
    broken[72, 60:70] = -40.0
    broken[40:44, 60:64, 0] = np.nan  # one channel only: the others keep their values
    broken[45, 60:70, 2] = 1000.0
    clipped = np.clip(np.nan_to_num(broken, nan=0.0, posinf=255.0, neginf=0.0), 0, 255)
    roi = Ellipse(cx, 60, 20, 20, 0)
    states = []
    for start, later in ((broken, broken), (clipped, clipped)):
        tracker = create_tracker(name)
        tracker.init(start, roi)
        states.append(tracker.update(later))
    (ok, state), (ok_clipped, state_clipped) = states
    assert ok == ok_clipped and state == state_clipped
    assert np.array_equal(to_gray(broken), to_gray(clipped))


@pytest.mark.parametrize("name", [n for n in tracker_names() if n.startswith("cv-")])
def test_opencv_trackers_report_the_roi_moved_and_scaled(name):
    """OpenCV's box trackers report the ROI's own ellipse (its semi-axes times ``scale``, its angle kept), moved
    with their box: the first state is the ROI exactly, as the run CSV's init row must be."""
    # MIL draws random samples and features: init() seeds both (before its features were seeded, CI once saw 3.6 px
    # where 1.0 px was seen here). Over seeds 0-199 its worst centre error on this sequence was 0.5-4.3 px (measured
    # before, with other rand() states; another C library's rand() draws other features), so it gets a wider bound
    # than the deterministic trackers; a box left behind would be 15 px off by the last frame.
    tolerance_px = 5.0 if name == "cv-mil" else 3.0
    roi = Ellipse(160, 110, 40, 26, 30)
    poses = [Pose(160 + k, 110 + 0.5 * k, 1.0, 0.0) for k in range(15)]
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=4))
    tracker = create_tracker(name)
    assert tracker.init(frames[0], roi).ellipse == roi
    for frame, pose in zip(frames[1:], poses[1:]):
        ok, state = tracker.update(frame)
        e = state.ellipse
        assert state.rotation_deg is None and e.angle_deg == roi.angle_deg
        assert (e.a, e.b) == pytest.approx((roi.a * state.scale, roi.b * state.scale))
        assert math.hypot(e.cx - pose.cx, e.cy - pose.cy) <= tolerance_px


def test_mil_repeats_within_a_process():
    """A MIL run gives the same boxes whatever ran before it in the process. It draws its features with the C
    library's rand(), which init() now seeds beside OpenCV's generator; before, a run depended on how many MIL
    trackers had been made before it (30 runs in one process: 5 different boxes)."""
    roi = Ellipse(160, 110, 40, 26, 30)
    poses = [Pose(160 + k, 110 + 0.5 * k, 1.0, 0.0) for k in range(6)]
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=4))

    def run(seed=0):
        tracker = create_tracker("cv-mil", seed=seed)
        tracker.init(frames[0], roi)
        return [tracker.update(frame)[1].ellipse.centre for frame in frames[1:]]

    first = run()
    others = [run(seed) for seed in (1, 2, 3)]
    assert [run() for _ in range(3)] == [first] * 3
    assert any(other != first for other in others)  # the seed is what they depend on


def test_tracker_parameters_are_the_keywords_a_tracker_takes_with_defaults():
    lpcf = tracker_parameters("lpcf")
    assert lpcf["padding"] == 1.0 and lpcf["patch_samples"] == 64 and lpcf["scale_filter"] is True
    # lpcf-masked hands **params on to lpcf: it takes all of lpcf's, with its own defaults first.
    masked = tracker_parameters("lpcf-masked")
    assert set(masked) == set(lpcf) and masked["occlusion_mask"] is True and masked["colour_weight"] == 0.0
    assert tracker_parameters("update")["update_threshold"] == 0.35 and tracker_parameters("update")["window"] == 11
    assert tracker_parameters("cv-mil") == {"seed": 0}
    for name in tracker_names():  # every parameter listed is one the tracker accepts, at its default
        create_tracker(name, **tracker_parameters(name))


def test_tracker_params_from_text_converts_by_the_defaults_type():
    params = tracker_params_from_text(["lpcf", "fixed", "cv-mil"], [
        ("padding", "1.5"), ("patch_samples", "48"), ("scale_filter", "off"), ("lost_threshold", "0.25"),
        ("window", "9"), ("padding", "2")])
    assert params == {"lpcf": {"padding": 2.0, "patch_samples": 48, "scale_filter": False, "lost_threshold": 0.25},
                      "fixed": {"lost_threshold": 0.25, "window": 9}, "cv-mil": {}}
    assert type(params["lpcf"]["patch_samples"]) is int and type(params["lpcf"]["padding"]) is float
    assert tracker_params_from_text(["lpcf"], [("occlusion_mask", "TRUE")]) == {"lpcf": {"occlusion_mask": True}}
    assert tracker_params_from_text(["lpcf"], []) == {"lpcf": {}}


@pytest.mark.parametrize("trackers, pairs, fragments", [
    (["lpcf"], [("nosuch", "1")], ["no parameter 'nosuch' in lpcf: lpcf takes padding (1.0), patch_samples (64)"]),
    (["fixed", "cv-mil"], [("padding", "1")], ["in any of fixed, cv-mil", "cv-mil takes seed (0)"]),
    (["lpcf"], [("padding", "wide")], ["lpcf: parameter padding takes a finite number (default 1.0), got 'wide'"]),
    (["lpcf"], [("padding", "nan")], ["takes a finite number"]),
    (["lpcf"], [("patch_samples", "64.0")], ["takes a whole number (default 64)"]),
    (["lpcf"], [("scale_filter", "2")], ["takes true or false (or yes/no, on/off, 1/0) (default True), got '2'"]),
    (["lpcf"], [("padding", "-1")], ["lpcf: padding must be"]),
    (["nosuch"], [("padding", "1")], ["unknown tracker 'nosuch'"]),
    (["fixed"], [("window", "10")], ["fixed: window must be an odd number at least 3 and at most 101, got 10"]),
    (["fixed"], [("window", "100001")], ["at most 101, got 100001"]),  # not 149 GiB of candidate samples
    (["fixed"], [("n_rho", "0")], ["fixed: n_rho must be at least 8 and at most 512, got 0"]),
    (["fixed"], [("lost_threshold", "5")], ["fixed: lost_threshold must be at least 0 and at most 1, got 5"]),
    (["update"], [("update_threshold", "-3")], ["update: update_threshold must be at least 0"]),
    (["occlusion"], [("inner_ratio", "2")], ["occlusion: inner_ratio must be above 0 and at most 0.95, got 2"]),
    (["spatial"], [("n_scales", "4")], ["spatial: n_scales must be an odd number at least 1 and at most 31"]),
    (["spatial"], [("scale_step", "0")], ["spatial: scale_step must be above 0"]),
    (["cv-mil"], [("seed", "99999999999999999999")], ["cv-mil: seed must be at least 0 and at most 2147483647"]),
    (["fixed"], [("window", "1" + "0" * 50)], ["at most 101, got a 51-digit number"]),
    # Each in range, together gigabytes of sampling maps (and a traceback, before these checks).
    (["fixed"], [("coarse", "false"), ("window", "101"), ("n_rho", "512"), ("n_theta", "1024")],
     ["fixed: window^2 x n_rho x n_theta (101^2 x 512 x 1024) come to 5,348,261,888 samples a frame"]),
    (["spatial"], [("n_scales", "31"), ("scale_step", "0.5")], ["spatial: the grid must span at most half to double"]),
    (["spatial"], [("n_angles", "31"), ("angle_step_deg", "45")], ["angle_step_deg x (n_angles // 2) is 675"]),
])
def test_tracker_params_from_text_refuses_in_one_line(trackers, pairs, fragments):
    # (Every case also holds for the CLI: tests/test_cli_run.py runs some through `lptrack run --param`.)
    with pytest.raises(UsageError) as caught:
        tracker_params_from_text(trackers, pairs)
    message = str(caught.value)
    assert "\n" not in message and all(f in message for f in fragments), message


def test_a_parameter_only_a_skipped_tracker_takes_is_named_as_such():
    with pytest.raises(UsageError) as caught:
        tracker_params_from_text(["fixed"], [("seed", "1")], skipped=["cv-kcf"])
    assert str(caught.value).endswith("(cv-kcf takes it but cannot run here)")


def test_create_tracker_reports_any_bad_keyword_as_a_usage_error():
    with pytest.raises(UsageError, match="tracker 'lpcf' has no parameter 'nosuch'; it takes: padding, "):
        create_tracker("lpcf", nosuch=1)
    with pytest.raises(UsageError, match=r"has no parameter 'learnig_rate' \(did you mean 'learning_rate'\?\)"):
        create_tracker("lpcf", learnig_rate=0.1)  # as the CLI's --param says it
    with pytest.raises(UsageError, match=r"fixed: parameter window takes a whole number \(default 11\), got inf"):
        create_tracker("fixed", window=float("inf"))  # int(inf): OverflowError in the constructor
    with pytest.raises(UsageError, match=r"lpcf: parameter padding takes a number \(default 1.0\), got 'wide'"):
        create_tracker("lpcf", padding="wide")  # float('wide'): ValueError in the constructor


def test_create_tracker_refuses_values_of_another_kind_than_the_parameters():
    """From Python, bool('false') is True and int(40.9) is 40: a flag given as text and a count given with a
    fraction were taken as something else without a word (a fresh review of the library)."""
    cases = [("lpcf", "long_term", "false", "takes True or False (default True), got 'false'"),
             ("fixed", "coarse", "no", "takes True or False"),
             ("lpcf", "scale_filter", None, "takes True or False"),
             ("lpcf", "n_rho", 40.9, "takes a whole number (default 32), got 40.9"),
             ("fixed", "window", True, "takes a whole number (default 11), got True"),
             ("lpcf", "padding", np.array([1.0]), "takes a number")]
    for name, key, value, said in cases:
        with pytest.raises(UsageError, match=re.escape(f"{name}: parameter {key} {said}")):
            create_tracker(name, **{key: value})
    tracker = create_tracker("lpcf", n_rho=40.0, long_term=np.bool_(False), padding=np.float32(1.5))
    assert (tracker.n_rho, tracker.long_term, tracker.padding) == (40, False, 1.5)


def test_tracker_classes_refuse_values_of_another_kind_as_create_tracker_does():
    """The classes are public: made directly, they took 'false' as True and cut 64.7 to 64 (a code review)."""
    from logpolar_track.trackers.lpcf import LogPolarCorrelationTracker, MaskedLogPolarCorrelationTracker
    from logpolar_track.trackers.thesis import FixedTemplateTracker
    cases = [(lambda: LogPolarCorrelationTracker(long_term="false"), "lpcf: parameter long_term takes True or False"),
             (lambda: LogPolarCorrelationTracker(patch_samples=64.7), "lpcf: parameter patch_samples takes a whole"),
             (lambda: MaskedLogPolarCorrelationTracker(n_rho=3.5), "lpcf-masked: parameter n_rho takes a whole number"),
             (lambda: FixedTemplateTracker(window=11.9), "fixed: parameter window takes a whole number")]
    for make, said in cases:
        with pytest.raises(UsageError, match=re.escape(said)):
            make()
    assert LogPolarCorrelationTracker(patch_samples=48.0).patch_samples == 48
    assert list(tracker_parameters("lpcf-masked"))[:3] == ["occlusion_mask", "colour_weight", "padding"]


@pytest.mark.parametrize("name", THESIS)
def test_thesis_trackers_turn_less_than_half_a_turn_a_frame(name):
    """The search and the re-sampling each read a turn within half a turn; together they read up to a whole turn
    in one frame (a plain disc, whose every angle matches alike, jumped from 90 to 445 degrees). A frame's turn
    is taken within half a turn, so the cumulative rotation stays continuous."""
    roi = Ellipse.circle(160, 120, 30)
    poses = [Pose(160 + 1.5 * k, 120 + 0.5 * k, 1.01 ** k, 3.0 * k) for k in range(25)]
    background, disc = np.full((240, 320, 3), 50, np.uint8), np.full((75, 75, 3), 200, np.uint8)
    frames = [render_frame(background, disc, roi, pose) for pose in poses]
    tracker = create_tracker(name)
    rotations = [tracker.init(frames[0], roi).rotation_deg]
    rotations += [tracker.update(frame)[1].rotation_deg for frame in frames[1:]]
    assert np.abs(np.diff(rotations)).max() <= 180.0


def test_an_estimate_whose_centre_left_the_frame_is_lost():
    """``spatial`` followed a disc out of the frame by matching the replicated border, tracked at 0.7 with its
    centre 90 px beyond the edge: an estimate outside the frame is lost, and the last good one is reported. (What
    it finds afterwards near the edge, a smooth background matching its template at 0.8, it reports tracked: it
    has no other judge of a match.)"""
    rng = np.random.default_rng(0)
    roi = Ellipse.circle(60, 60, 25)
    background, texture = random_texture(120, 160, rng), random_texture(61, 61, rng)
    poses = [Pose(60 - 4.0 * k, 60 - 3.0 * k, 1.0, 0.0) for k in range(30)]
    frames = [render_frame(background, texture, roi, pose) for pose in poses]
    tracker = create_tracker("spatial")
    tracker.init(frames[0], roi)
    lost = 0
    for frame in frames[1:]:
        ok, state = tracker.update(frame)
        if ok:
            assert 0 <= state.ellipse.cx <= 159 and 0 <= state.ellipse.cy <= 119
        lost += not ok
    assert lost > 0


@pytest.mark.parametrize("name", THESIS + ["spatial"])
def test_a_still_object_centred_on_the_outermost_pixel_is_not_lost(name):
    """check_roi_fits takes a centre on the outermost pixel centre (cx = width - 1, cy = 0, ...); a still object
    there was estimated a few hundredths of a pixel beyond it and reported lost on most frames (spatial on every
    one, at a score of 0.99; sample spin.mp4 with --roi 639,250,40: fixed and spatial lost on 29 of 29)."""
    rng = np.random.default_rng(0)
    frame = random_texture(120, 160, rng)
    for roi in (Ellipse.circle(159, 60, 25), Ellipse.circle(0, 60, 25), Ellipse.circle(80, 119, 25),
                Ellipse.circle(80, 0, 25)):
        tracker = create_tracker(name)
        tracker.init(frame, roi)
        for _ in range(6):
            noisy = np.clip(frame.astype(np.int16) + rng.integers(-3, 4, frame.shape), 0, 255).astype(np.uint8)
            ok, state = tracker.update(noisy)
            assert ok, (roi, state)
            assert 0 <= state.ellipse.cx <= 159 and 0 <= state.ellipse.cy <= 119
            assert math.hypot(state.ellipse.cx - roi.cx, state.ellipse.cy - roi.cy) < 1.0


def test_an_opencv_tracker_starts_on_a_roi_hanging_over_the_edge():
    """A ROI half inside the frame is accepted; MIL was given its box beyond the edge and ended with
    std::bad_alloc (or an assertion near a corner). The box is cut to the frame."""
    rng = np.random.default_rng(0)
    frame = random_texture(240, 320, rng)
    for roi in (Ellipse.circle(25, 120, 30), Ellipse.circle(295, 120, 30), Ellipse.circle(160, 5, 20),
                Ellipse.circle(2, 2, 3)):
        tracker = create_tracker("cv-mil")
        assert tracker.init(frame, roi).ellipse == roi
        ok, state = tracker.update(frame)
        assert ok and math.hypot(state.ellipse.cx - roi.cx, state.ellipse.cy - roi.cy) < 3.0


def test_an_opencv_tracker_that_cannot_start_on_the_roi_says_so_in_one_line():
    """A box spanning the frame leaves MIL no negative samples: OpenCV's assertion became a traceback; it is a
    RoiError (one line, exit 2 in the CLI) naming the box and the frame."""
    frame = random_texture(240, 320, np.random.default_rng(0))
    with pytest.raises(RoiError, match=r"cv-mil cannot start on the ROI's box \(250x240 px at 35,0\) in a 320x240 "
                                       r"frame: OpenCV says \(-215:Assertion failed\)"):
        create_tracker("cv-mil").init(frame, Ellipse.circle(160, 120, 125))


@pytest.mark.parametrize("name", THESIS)
def test_thesis_trackers_take_a_wide_window(name):
    """A 25 x 25 window (its full-density candidates overflow one cv2.remap's map) is sampled in parts."""
    roi, poses, frames = sequence("circle", 0.1, scale_range=(0.9, 1.1))
    centre, _, _, lost = errors(track(name, roi, frames[:8], window=25, coarse=False), poses[:8])
    assert lost == 0 and centre.max() < 1.0


@pytest.mark.parametrize("sample", ["ellipse", "noise_blur"])
def test_update_renews_only_where_the_first_template_vouches(sample):
    """``update`` renews its current template only where the first template's own estimate is the accepted one: a
    renewal from the current template's estimate, which the first template had not vetted, let it drift (bundled
    ellipse sample: median error 5.8 px, 2.6 % and 14.6 degrees; noise_blur 4.4 px, 8.8 %; now at most 1.0 px,
    2.3 %, 3.4 degrees)."""
    from pathlib import Path

    from logpolar_track.bench import collect_sequences, run_bench

    folder = Path(__file__).resolve().parents[1] / "sample_videos"
    sequences = [s for s in collect_sequences([folder]) if s.name == sample] if folder.is_dir() else []
    if not sequences:
        pytest.skip(f"sample_videos/{sample} not present")
    [result] = run_bench(sequences, ["update"])
    assert result["success_rate"] == 1.0
    assert result["centre_error_median_px"] <= 1.5
    assert result["scale_error_median_pct"] <= 3.0
    assert result["rotation_error_median_deg"] <= 5.0


def test_mil_refuses_a_box_it_would_hang_on():
    """OpenCV's MIL never returns from update() on a 4 x 4 px box (and deaf to signals while in it)."""
    if not tracker_class("cv-mil").available():
        pytest.skip("cv2.TrackerMIL not in this build")
    frame = random_texture(120, 160, np.random.default_rng(0))
    with pytest.raises(RoiError, match="cv-mil cannot start on a box under 5 px a side .the ROI's is 4x4 px."):
        create_tracker("cv-mil").init(frame, Ellipse.circle(80, 60, 2))
    create_tracker("cv-mil").init(frame, Ellipse.circle(80, 60, 3))  # 6 x 6 px: starts


def test_csrt_on_a_frame_a_few_pixels_high_reports_lost_rather_than_raising():
    """OpenCV's CSRT raised cv2.error from update() (an assertion in copyMakeBorder: its next crop was empty) once its
    box left a frame 3 px high; that frame is now lost (score 0, the last good geometry), and later ones tracked again
    where CSRT finds the box. Found by fuzzing."""
    if not tracker_class("cv-csrt").available():
        pytest.skip("cv2.TrackerCSRT not in this build (needs the contrib wheel)")
    lost = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        frames = [rng.integers(0, 256, (3, 36, 3), dtype=np.uint8) for _ in range(4)]
        tracker = create_tracker("cv-csrt")
        last = tracker.init(frames[0], Ellipse.circle(19, 1, 2))
        for frame in frames[1:]:
            ok, state = tracker.update(frame)
            if ok:
                last = state
            else:
                lost += 1
                assert state == TrackState(last.ellipse, last.scale, None, 0.0)
    assert lost > 0  # the case the test is about happened (20 of the 60 frames with OpenCV 5.1.0)


@pytest.mark.parametrize("name", [n for n in tracker_names() if n.startswith("cv-")])
def test_opencv_trackers_report_a_centre_within_the_frame(name):
    """An object sliding out of the view on the right: OpenCV's box may move part-way out of the frame, and its
    reported centre was beyond the outermost pixel centre (CSRT: 159.5 in a 160 px frame, KCF up to 5.5 px beyond
    in fuzzing); it is reported on the edge, as lpcf reports an object leaving the view."""
    width, height = 160, 120
    background = np.full((height, width, 3), 90, np.uint8)
    texture = random_texture(41, 41, np.random.default_rng(0))
    roi = Ellipse.circle(width - 30.0, 60.0, 15.0)
    frames = [render_frame(background, texture, roi, Pose(width - 30.0 + 4 * i, 60.0, 1.0, 0.0)) for i in range(16)]
    tracker = create_tracker(name)
    tracker.init(frames[0], roi)
    for frame in frames[1:]:
        ok, state = tracker.update(frame)
        assert 0.0 <= state.ellipse.cx <= width - 1 and 0.0 <= state.ellipse.cy <= height - 1


def test_the_contrib_hint_follows_the_installed_wheels(monkeypatch):
    """Both OpenCV wheels installed (lptrack reinstalled after the swap): uninstalling only the plain one, as the
    swap says, would leave cv2 broken; the hint says to reinstall the contrib one alone."""
    import importlib.metadata

    from logpolar_track.trackers import opencv

    installed = {"opencv-python-headless": "5.1.0.95"}

    def version(name):
        if name not in installed:
            raise importlib.metadata.PackageNotFoundError(name)
        return installed[name]

    monkeypatch.setattr(importlib.metadata, "version", version)
    assert opencv._contrib_hint().startswith("needs opencv-contrib-python-headless instead of")
    installed["opencv-contrib-python-headless"] = "5.1.0.95"
    assert opencv._contrib_hint().startswith("both opencv-python-headless and opencv-contrib-python-headless are")
    assert "pip uninstall -y opencv-python-headless opencv-contrib-python-headless && pip install" in \
        opencv._contrib_hint()


@pytest.mark.parametrize("name", ["lpcf", "fixed", "cv-mil"])
def test_init_takes_a_roi_string_or_numbers(name):
    """As track_video does: init(frame, '80,60,20') or (80, 60, 20) raised AttributeError ('str' has no 'cx');
    an OpenCV-style box is pointed to ellipse_in_box."""
    frame = random_texture(120, 160, np.random.default_rng(0))
    for roi in ("80,60,20", (80, 60, 20)):
        state = create_tracker(name).init(frame, roi)
        assert state.ellipse == Ellipse.circle(80, 60, 20)
    with pytest.raises(RoiError, match="looks like an OpenCV box"):
        create_tracker(name).init(frame, (60, 40, 40, 40))


def _turning_rim_scene(seed, n=50):
    """A textured disc (radius 35 px) moving and turning 1.5 degrees a frame whose rim (the outer half of its radius,
    of the same texture) turns the other way, 3 degrees a frame: the border misleads, the centre does not."""
    rng = np.random.default_rng(seed)
    roi = Ellipse.circle(160, 120, 35)
    background = random_texture(240, 320, rng)
    texture = random_texture(91, 91, rng).astype(np.float32)
    texture = 128 + 0.5 * (texture - texture.mean())
    ys, xs = np.mgrid[0:91, 0:91] - 45
    rim = (np.hypot(xs, ys) > 0.5 * 35)[..., None]
    poses = [Pose(160 - 0.6 * k, 120 + 0.18 * k, 1.0 + 0.002 * k, 1.5 * k) for k in range(n)]
    frames = []
    for k, pose in enumerate(poses):
        m = cv2.getRotationMatrix2D((45, 45), -4.5 * k, 1.0)
        turned = cv2.warpAffine(texture, m, (91, 91), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
        drawn = np.clip(np.where(rim, turned, texture), 0, 255).astype(np.uint8)
        frames.append(render_frame(background, drawn, roi, pose))
    return roi, poses, frames


def test_occlusion_weights_its_inner_template_against_a_misleading_border():
    """Where ``occlusion`` beats ``fixed`` as designed: a border that moves otherwise than the object (a rim turning
    the other way). Its inner template, weighted 0.7, is not misled: median scale error about half of ``fixed``'s
    and largest rotation error about half (measured over 9 seeds: 0.33-1.2 % against 0.59-2.6 %, 0.6-1.2 against
    1.7-2.3 degrees); with the weights swapped (inner 0.3) it gives most of that back (0.40-2.0 %, 1.2-1.8 degrees).
    In the scenes where the border is merely covered it is no better than ``fixed`` (README)."""
    errs = {"fixed": [], "occlusion": [], "swapped": []}
    for seed in (0, 1):
        roi, poses, frames = _turning_rim_scene(seed)
        for label, name, params in (("fixed", "fixed", {}), ("occlusion", "occlusion", {}),
                                    ("swapped", "occlusion", {"inner_weight": 0.3})):
            centre, scale, rotation, lost = errors(track(name, roi, frames, **params), poses)
            assert lost == 0 and np.median(centre) < 0.5
            errs[label].append((np.median(scale), rotation.max()))
    scale = {k: np.mean([e[0] for e in v]) for k, v in errs.items()}
    worst_turn = {k: np.mean([e[1] for e in v]) for k, v in errs.items()}
    assert scale["occlusion"] < 0.7 * scale["fixed"] and scale["occlusion"] < 0.85 * scale["swapped"], scale
    assert worst_turn["occlusion"] < 0.7 * worst_turn["fixed"], worst_turn
    assert worst_turn["occlusion"] < 0.85 * worst_turn["swapped"], worst_turn
