"""The default tracker ``lpcf``: its conventions and confidence on synthetic cases.

It is also held to the thesis trackers' accuracy bounds (tests/test_trackers.py: their zoom-and-turn path, up to
6.5 % and 6.8 degrees a frame, within them in 24 of 24 runs over 6 seeds x 2 shapes x 2 directions). It is the
default because it is the most accurate tracker measured on sample_videos/ and on the real benchmark sequences.

Conventions: centre in pixels, scale relative to frame 0, rotation in degrees counter-clockwise on screen.
"""

import math
import re

import cv2
import numpy as np
import pytest

from logpolar_track.errors import UsageError
from logpolar_track.geometry import Ellipse
from logpolar_track.samples import SAMPLE_NAMES
from logpolar_track.synthetic import Pose, random_texture, render_frame, similarity_path, synthetic_sequence
from logpolar_track.trackers import DEFAULT_TRACKER, create_tracker
from logpolar_track.trackers.base import Similarity


def run(frames, roi, **params):
    tracker = create_tracker("lpcf", **params)
    tracker.init(frames[0], roi)
    return tracker, [tracker.update(f) for f in frames[1:]]


def centre_errors(results, poses):
    return np.array([math.hypot(s.centre[0] - p.cx, s.centre[1] - p.cy) for (_, s), p in zip(results, poses)])


def scale_errors(results, poses):
    """``|scale / true scale - 1|`` per frame."""
    return np.array([abs(s.scale / p.scale - 1) for (_, s), p in zip(results, poses)])


def rotation_errors(results, poses):
    """``|rotation - true rotation|`` per frame, degrees (unwrapped, both cumulative)."""
    return np.array([abs(s.rotation_deg - p.rotation_deg) for (_, s), p in zip(results, poses)])


def runs_on_seeds(roi, poses, seeds=range(4)):
    """``lpcf``'s results on ``poses`` of ``roi`` rendered at 640 x 480 with each of ``seeds``, one list at a time."""
    for seed in seeds:
        yield run(list(synthetic_sequence(poses, roi, size=(640, 480), seed=seed)), roi)[1]


def test_is_the_default():
    assert DEFAULT_TRACKER == "lpcf"


def _with_stranger(frames, poses, roi, first, count, seed=77):
    rng = np.random.default_rng(seed)
    stranger = random_texture(90, 90, rng)
    out = list(frames)
    for i in range(first, first + count):
        p = poses[i]
        out[i] = render_frame(frames[i], stranger, roi, Pose(p.cx, p.cy, p.scale, 0.0))
    return out


def test_confidence_drops_on_a_swapped_object_and_recovers():
    roi = Ellipse.circle(160, 120, 30)
    poses = [Pose(160 + 1.0 * i, 120 - 0.5 * i, 1.0, 1.0 * i) for i in range(30)]
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=8))
    swapped = _with_stranger(frames, poses, roi, 15, 3)
    tracker, results = run(swapped, roi)
    scores = np.array([s.score for _, s in results])
    ok = np.array([o for o, _ in results])
    # Frames 15-17 are results[14:17]; the object is back from frame 18 and tracked again within 3 frames.
    assert ok[:14].all() and not ok[14:17].any() and ok[20:].all()
    assert scores[:14].min() > 2 * scores[14:17].max()
    assert all(s.score < tracker.lost_threshold for _, s in results[14:17])
    # Lost rows keep the last good geometry.
    good = results[13][1]
    assert all(s.ellipse == good.ellipse for _, s in results[14:17])
    # Nothing of the stranger was learnt: tracking resumes on the object.
    assert np.median(centre_errors(results[20:], poses[21:])) <= 1.0


def test_packed_spectra_match_numpy_fft():
    """The tracker's packed (cv2.dft CCS) correlation equals NumPy's complex arithmetic up to float32 rounding."""
    from logpolar_track.spectra import PackedSpectra

    rng = np.random.default_rng(3)
    for h, w in [(64, 64), (52, 64), (64, 22)]:
        packed = PackedSpectra(h, w)
        x, a = rng.standard_normal((2, 3, h, w)).astype(np.float32)
        spec_x, spec_a = np.fft.rfft2(x.astype(np.float64)), np.fft.rfft2(a.astype(np.float64))
        px, pa = packed.forward(x), packed.forward(a)
        response = packed.correlate(packed.multiplier(pa), px)
        expected = np.fft.irfft2((spec_a * spec_x).sum(axis=0), s=(h, w))
        assert np.allclose(response, expected, atol=1e-4 * np.abs(expected).max())
        # Division by the summed power, as the filter does.
        power = packed.power(pa)
        response = packed.correlate(packed.multiplier(pa / (power + 1.0)), px)
        expected = np.fft.irfft2((spec_a * spec_x).sum(axis=0) / ((np.abs(spec_a) ** 2).sum(axis=0) + 1.0), s=(h, w))
        assert np.allclose(response, expected, atol=1e-4 * np.abs(expected).max())
        # An even image's spectrum, ready to multiply conj(x): label * conj(x).
        ys, xs = np.fft.fftfreq(h, 1.0 / h)[:, None], np.fft.fftfreq(w, 1.0 / w)[None, :]
        label = np.exp(-(xs ** 2 + ys ** 2) / 8.0)
        learnt = packed.real_spectrum(label) * px
        got = packed.correlate(packed.multiplier(learnt), px)
        expected = np.fft.irfft2((np.fft.rfft2(label) * np.conj(spec_x) * spec_x).sum(axis=0), s=(h, w))
        assert np.allclose(got, expected, atol=1e-4 * np.abs(expected).max())


@pytest.mark.parametrize("filter_shape, map_shape", [((64, 64), (135, 200)), ((40, 64), (240, 320)),
                                                      ((64, 22), (60, 80)), ((50, 64), (7, 9))])
def test_the_whole_frame_search_correlates_as_filter2d(filter_shape, map_shape):
    """The search's summed correlation, made in the Fourier domain, equals the channels' ``cv2.filter2D``
    correlations (anchored, zero beyond the map) summed, up to float32 rounding -- also for a map smaller than
    the kernels."""
    from logpolar_track.spectra import CoarseFilter, PackedSpectra

    rng = np.random.default_rng(5)
    filter_images = rng.standard_normal((7,) + filter_shape).astype(np.float32)
    coarse = CoarseFilter(PackedSpectra(*filter_shape).forward(filter_images))
    maps = rng.standard_normal((7,) + map_shape).astype(np.float32)
    expected = sum(cv2.filter2D(m, cv2.CV_32F, k, anchor=coarse.anchor, borderType=cv2.BORDER_CONSTANT)
                   for m, k in zip(maps, coarse.kernels))
    for _ in range(2):  # the second time with the kernels' spectra kept
        got = coarse.response(maps)
        assert got.shape == map_shape
        assert np.abs(got - expected).max() <= 1e-5 * np.abs(expected).max()


def test_the_whole_frame_search_keeps_a_bounded_number_of_kernel_spectra():
    """A search filter lives as long as the track (the long-term one) and a drifting scale gives every search a new
    map size: the spectra kept per size stay bounded, most recently used kept, and a size dropped and met again
    still correlates as ``cv2.filter2D``."""
    from logpolar_track.spectra import KERNEL_SPECTRA_KEPT, CoarseFilter, PackedSpectra

    rng = np.random.default_rng(6)
    coarse = CoarseFilter(PackedSpectra(40, 64).forward(rng.standard_normal((7, 40, 64)).astype(np.float32)))
    first = rng.standard_normal((7, 50, 70)).astype(np.float32)
    expected = sum(cv2.filter2D(m, cv2.CV_32F, k, anchor=coarse.anchor, borderType=cv2.BORDER_CONSTANT)
                   for m, k in zip(first, coarse.kernels))
    coarse.response(first)
    first_size = next(iter(coarse._kernel_spectra))
    for step in range(3 * KERNEL_SPECTRA_KEPT):
        coarse.response(np.zeros((7, 50 + 6 * step, 70 + 6 * step), np.float32))
        coarse.response(first)  # in use throughout: never the one dropped
        assert len(coarse._kernel_spectra) <= KERNEL_SPECTRA_KEPT
        assert first_size in coarse._kernel_spectra
    assert len(coarse._kernel_spectra) == KERNEL_SPECTRA_KEPT
    coarse.response(np.zeros((7, 50 + 6 * 1, 70 + 6 * 1), np.float32))  # dropped long ago: made again
    got = coarse.response(first)
    assert np.abs(got - expected).max() <= 1e-5 * np.abs(expected).max()


def test_packed_phase_correlation_matches_phase_correlator():
    """The tracker's packed log-polar correlation gives PhaseCorrelator's surface up to float32 rounding."""
    from logpolar_track.logpolar import PhaseCorrelator
    from logpolar_track.spectra import PackedPhaseCorrelator

    rng = np.random.default_rng(4)
    reference = rng.random((32, 64)).astype(np.float32)
    image = np.roll(reference, (2, -5), axis=(0, 1)) + 0.1 * rng.random((32, 64)).astype(np.float32)
    correlator = PhaseCorrelator((32, 64))
    packed = PackedPhaseCorrelator(correlator)
    spectra = correlator.spectrum(reference[None]), correlator.spectrum(image[None])
    expected, expected_plain = correlator.correlate(*spectra)[0], correlator.cross_correlate(*spectra)[0]
    got, cross = packed.correlate(packed.reference(reference), packed.spectrum(image))
    plain = packed.plain(cross)
    assert np.unravel_index(np.argmax(got), got.shape) == (2, 64 - 5)
    assert np.allclose(got, expected, atol=1e-5)
    assert np.allclose(plain, expected_plain, atol=1e-5)
    # The plain surface is the normalised cross-correlation: near 1 at the shift for a lightly noisy copy.
    assert np.unravel_index(np.argmax(plain), plain.shape) == (2, 64 - 5) and 0.9 < plain.max() <= 1.0


def _ramp_to(speed_px: float, start_x: float = 60.0, end_x: float = 580.0) -> list[Pose]:
    """Left to right along y = 240, accelerating from 5 px/frame to ``speed_px`` over 6 frames, turning 0.5
    degrees per frame."""
    xs, v = [start_x], 5.0
    while xs[-1] < end_x:
        xs.append(xs[-1] + v)
        v = min(speed_px, v + (speed_px - 5.0) / 6)
    return [Pose(x, 240.0, 1.0, 0.5 * i) for i, x in enumerate(xs)]


def test_motion_prediction_keeps_a_fast_pass():
    """65 px per frame, more than twice the object's radius: found only where the motion predicts it."""
    roi = Ellipse.circle(60, 240, 30)
    poses = _ramp_to(65.0)
    frames = list(synthetic_sequence(poses, roi, size=(640, 480), seed=5))
    _, results = run(frames, roi)
    assert all(ok for ok, _ in results)
    assert centre_errors(results, poses[1:]).max() <= 2.0
    _, blind = run(frames, roi, velocity_damping=0.0)  # the same tracker without prediction loses it
    assert centre_errors(blind, poses[1:]).max() > 50.0


def _bounce(speed_px: float, wall_x: float = 560.0) -> list[Pose]:
    """Accelerating from x = 80 to ``speed_px`` per frame (as :func:`_ramp_to`), back off a wall at ``wall_x`` at the
    same speed for 8 frames; y = 240, turning 0.5 degrees per frame."""
    poses = _ramp_to(speed_px, start_x=80.0, end_x=wall_x - speed_px)
    x = poses[-1].cx
    return poses + [Pose(x - speed_px * k, 240.0, 1.0, 0.5 * (len(poses) + k - 1)) for k in range(1, 9)]


@pytest.mark.parametrize("speed_px", [30.0, 40.0, 50.0])
def test_an_object_bouncing_back_is_looked_for_where_it_was_and_behind(speed_px):
    """Off the wall, the prediction is ahead of the object by 1.8 times its speed (radius 30 px, a patch 60 px
    either side), and the filter finds nothing there: reported lost at the wall until the whole-frame search,
    150-400 px behind, on 11 of 12 runs without the check below. A confident track turned weak where it was
    predicted also looks at the last place (30-50 px from the object; enough at 30 px a frame) and as far behind it
    as the prediction was ahead."""
    roi = Ellipse.circle(80, 240, 30)
    poses = _bounce(speed_px)
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 3.0


def _spinning(kind: str) -> list[Pose]:
    """A disc drifting 2 px a frame while it spins: 20 degrees a frame throughout (``steady``), speeding up to 25
    degrees a frame over 30 frames (``spin-up``), or 20 degrees a frame for 30 frames and then not at all
    (``stop``); 60 frames."""
    turns = {"steady": lambda k: 20.0, "spin-up": lambda k: min(25.0, 25.0 * k / 30), "stop": lambda k: 20.0 * (k < 30)}
    angle, poses = 0.0, []
    for i in range(60):
        poses.append(Pose(320.0 + 2.0 * i, 240.0 + 1.0 * i, 1.0, angle))
        angle += turns[kind](i)
    return poses


@pytest.mark.parametrize("kind", ["steady", "spin-up", "stop"])
def test_a_fast_spin_is_predicted(kind):
    """The motion prior on the log-polar match shrinks a turn of 10 degrees a frame or more, so without predicting
    the turn the estimate fell further behind each frame until the match was lost: 20 degrees a frame lost in 2 of
    4 seeds, the spin-up in 4 of 4, the spin that stops in 3 of 4. Every frame is tracked now, within 2 px; the
    angle within 2 degrees (median) and 8 degrees on every frame (the first turn, with no spin yet to predict, is
    read only in part: 14 of 20 degrees)."""
    roi = Ellipse.circle(320, 240, 40)
    poses = _spinning(kind)
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 2.0
        angle_errors = rotation_errors(results, poses[1:])
        assert np.median(angle_errors) <= 2.0 and angle_errors.max() <= 8.0


@pytest.mark.parametrize("turn, radius", [(30.0, 30), (45.0, 30), (30.0, 60), (45.0, 60)])
def test_a_turn_beyond_the_motion_prior_is_taken_once_verified(turn, radius):
    """A textured disc drifting 1.5 px and turning 30 or 45 degrees a frame from the first frame, faster than the
    motion prior lets the log-polar match move (and than the predicted spin, which needs a turn read first). It
    was lost on 24 of 24 runs (these and radius 45); the far peak of the raw surface, matched again from the pose
    it gives, now follows every frame within 0.4 px and 0.3 degrees (median 0.1)."""
    roi = Ellipse.circle(320, 240, radius)
    poses = [Pose(320.0 + 1.5 * i, 240.0 + 1.0 * i, 1.0, turn * i) for i in range(40)]
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 1.0
        angle_errors = rotation_errors(results, poses[1:])
        assert np.median(angle_errors) <= 0.5 and angle_errors.max() <= 2.0


@pytest.mark.parametrize("spin", [8.0, 20.0])
def test_a_salient_mark_does_not_pull_a_turning_object_off_its_centre(spin):
    """A textured 50 x 40 px ellipse with a bright dot (radius 8 px) 30 px from its centre, drifting 1.1 px a frame
    and turning 8 or 20 degrees a frame from the first frame. The filter followed the dot as it turned, the
    log-polar match at that wrong centre read part of the turn, and the two agreed on a wrong pose: 50-75 px off
    and reported tracked in 6 of these 8 runs (at 12 degrees a frame 4 of 4; without the dot none; fresh review,
    2026-12-07). Matched at the predicted centre once the refinement is no longer believed, every frame is now
    within 0.15 px and 0.2 degrees (measured)."""
    roi = Ellipse(160, 120, 50, 40, 0)
    poses = [Pose(160.0 + 1.0 * i, 120.0 + 0.5 * i, 1.0, spin * i) for i in range(30)]
    for seed in range(4):
        texture = random_texture(201, 201, np.random.default_rng(seed))
        cv2.circle(texture, (130, 100), 8, (255, 255, 255), -1)
        background = random_texture(240, 320, np.random.default_rng(100 + seed))
        frames = [render_frame(background, texture, roi, pose) for pose in poses]
        _, results = run(frames, roi)
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 0.5
        assert rotation_errors(results, poses[1:]).max() <= 0.5


@pytest.mark.parametrize("spin", [1.0, 2.0])
def test_a_rigid_object_found_again_off_pose_is_put_back_on_it(spin):
    """The same kind of object (a textured 50 x 30 px ellipse with a bright dot), drifting and turning 1 or 2
    degrees a frame, hidden for frames 15-24. The search finds it again some pixels and degrees off, and there the
    filter, pulled towards the dot, and the log-polar match agreed on the wrong pose: at the end 5 px and 10 degrees
    off in 2 of 4 runs at 1 degree a frame, 11-23 px and 23-53 degrees in 4 of 4 at 2 (a fresh review found it).
    Every run whose track was reported lost under the cover and resumed now ends within 0.1 px and 0.2 degrees
    (measured); one run at 2 degrees a frame is reported tracked on the background under the cover instead, never
    resumes, and ends 11 px off (a limit: docs/lpcf.md)."""
    roi = Ellipse(150, 120, 50, 30, 20)
    poses = [Pose(150.0 + 1.0 * i, 120.0 + 0.5 * i, 1.0, spin * i) for i in range(40)]
    resumed = 0
    for seed in range(4):
        texture = random_texture(201, 201, np.random.default_rng(seed))
        cv2.circle(texture, (128, 90), 8, (255, 255, 255), -1)
        background = random_texture(240, 320, np.random.default_rng(100 + seed))
        frames = [background.copy() if 15 <= i < 25 else render_frame(background, texture, roi, pose)
                  for i, pose in enumerate(poses)]
        _, results = run(frames, roi)
        if all(ok for ok, _ in results[14:24]):
            continue  # reported tracked on the background under the cover: not a track that resumed
        resumed += 1
        assert centre_errors(results[-10:], poses[-10:]).max() <= 0.5
        assert rotation_errors(results[-10:], poses[-10:]).max() <= 0.5
    assert resumed >= 3


@pytest.mark.parametrize("a, b, spin", [(40, 15, 6.0), (50, 20, 8.0)])
def test_a_steady_turn_below_the_prediction_threshold_is_predicted(a, b, spin):
    """A textured 80 x 30 or 100 x 40 px ellipse drifting 1.5 px and turning 6 or 8 degrees a frame. On an
    elongated ellipse's own grid a turn is no plain shift and one match reads part of it (4.6 of 12 degrees), a turn
    under 10 degrees was never predicted, and the lag grew until the ellipse was lost: in 2 and 1 of 4 seeds (at 8
    degrees a frame the 80 x 30 one in 4 of 4, now 1). Turns of 3 degrees or more, the same way on three frames in
    a row, are now predicted (their mean, damped like the velocity): every frame tracked, within 1.5 px and 5
    degrees."""
    roi = Ellipse(320, 240, a, b, 20.0)
    poses = [Pose(320 + 1.5 * i, 240 + 1.0 * i, 1.0, spin * i) for i in range(50)]
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 1.5
        assert rotation_errors(results, poses[1:]).max() <= 5.0


def test_a_covered_object_is_not_taken_for_a_turned_twin_beside_it():
    """A textured disc (radius 30 px) spinning 10 degrees a frame moves right at 6 px a frame and stops touching an
    identical disc turned by 30 degrees; at frame 35 it is covered by a plain grey patch. The frame after the cover
    was reported lost, but with no drop counted, and the change beyond the motion prior was tried there: the filter
    had moved onto the twin, a turn of +43 degrees matched it at 0.93, and the twin was reported tracked for 24
    frames at a score of 0.94 (a reviewer's case, 1 of about 180 such runs). Now no frame after the cover is
    reported tracked."""
    rng = np.random.default_rng(2)
    background = random_texture(480, 640, rng)
    roi = Ellipse.circle(150, 240, 30)
    texture = cv2.addWeighted(random_texture(75, 75, rng), 0.8, np.full((75, 75, 3), 40, np.uint8), 1.0, 0)
    noise = np.random.default_rng(1002)
    stop = 330 - 2.05 * 30
    frames = []
    for i in range(60):
        frame = render_frame(background, texture, roi, Pose(330, 240, 1.0, 30.0))
        here = Pose(min(150 + 6.0 * i, stop), 240, 1.0, 10.0 * i)
        frame = render_frame(frame, texture, roi, here)
        if i >= 35:
            cv2.circle(frame, (int(here.cx), int(here.cy)), 33, (128, 128, 128), -1)
        frames.append(np.clip(frame + noise.normal(0, 2.0, frame.shape), 0, 255).astype(np.uint8))
    _, results = run(frames, roi)
    assert all(ok for ok, _ in results[:33])
    assert not any(ok for ok, _ in results[34:])


def _zooming(rate: float, frames_total: int) -> list[Pose]:
    """An object drifting 1.5 px and turning 1 degree a frame while its size changes by ``rate`` a frame (0.07: 7 %
    larger each frame), reached over the first 5 frames."""
    scale, poses = 1.0, []
    for i in range(frames_total):
        poses.append(Pose(320.0 + 1.5 * i, 240.0 + 0.5 * i, scale, 1.0 * i))
        scale *= (1 + rate) ** min(1.0, (i + 1) / 5)
    return poses


@pytest.mark.parametrize("rate, radius, frames_total", [(0.07, 35, 18), (-0.07, 80, 18), (0.10, 30, 14)],
                         ids=["in-7%", "out-7%", "in-10%"])
def test_a_fast_zoom_is_predicted(rate, radius, frames_total):
    """The motion prior on the log-polar match shrinks a zoom of 3.5 % a frame or more, and without predicting it
    the estimate fell behind until the match was lost (to 2.8 times or 0.34 times the size): lost in 1, 2 and 2 of 4
    seeds, up to 150 % off in scale. Every frame is tracked now, within 1 px and 2 % of the size."""
    roi = Ellipse.circle(320, 240, radius)
    poses = _zooming(rate, frames_total)
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 1.0
        assert scale_errors(results, poses[1:]).max() <= 0.02


def _reversing(change: str) -> list[Pose]:
    """An object drifting 1.5 px a frame that, for 15 frames, grows 5 % a frame while turning 5 degrees (``zoom``)
    or turns 20 degrees a frame (``spin``), and then at once shrinks or turns back as fast; 40 frames."""
    scale, angle, poses = 1.0, 0.0, []
    for i in range(40):
        poses.append(Pose(320.0 + 1.5 * i, 240.0 + 0.5 * i, scale, angle))
        sign = 1 if i < 15 else -1
        if change == "zoom":
            scale, angle = scale * 1.05 ** sign, angle + 5.0
        else:
            angle += 20.0 * sign
    return poses


@pytest.mark.parametrize("change", ["zoom", "spin"])
def test_a_predicted_turn_or_zoom_that_reverses_is_matched_unpredicted_too(change):
    """A predicted turn or zoom that matches worse than the last frame did is matched again from the last scale
    and angle and from as far on their other side. Without that, the zoom was lost at the reversal in 4 of 6 seeds
    (0-5), up to 250 % off in scale, where it was tracked before zooms were predicted; the spin in 6 of 6 (5 of 6
    before spins were predicted). Now every frame is tracked within 1 px, 2 % and 8 degrees."""
    roi = Ellipse.circle(320, 240, 40)
    poses = _reversing(change)
    for results in runs_on_seeds(roi, poses):
        assert all(ok for ok, _ in results)
        assert centre_errors(results, poses[1:]).max() <= 1.0
        assert scale_errors(results, poses[1:]).max() <= 0.02
        assert rotation_errors(results, poses[1:]).max() <= 8.0


def test_recovers_after_a_full_occlusion():
    """A larger disc of other texture covers the object for 8 frames while it moves on; the object is lost
    meanwhile (keeping its last good geometry) and found again as soon as it shows."""
    roi = Ellipse.circle(160, 240, 30)
    poses = [Pose(160 + 3.0 * i, 240 + 1.0 * i, 1.0, 0.5 * i) for i in range(60)]
    frames = list(synthetic_sequence(poses, roi, size=(640, 480), seed=6))
    cover = random_texture(200, 200, np.random.default_rng(9))
    covered = range(20, 28)
    for i in covered:
        p = poses[i]
        frames[i] = render_frame(frames[i], cover, Ellipse.circle(p.cx, p.cy, 50), Pose(p.cx, p.cy, 1.0, 0.0))
    _, results = run(frames, roi)
    ok = np.array([o for o, _ in results])
    errors = centre_errors(results, poses[1:])
    during = [i - 1 for i in covered]  # results[k] is frame k + 1
    assert ok[:19].all() and errors[:19].max() <= 1.5
    assert (~ok[during]).sum() >= 5
    assert ok[28:].all() and errors[28:].max() <= 1.5  # from the first uncovered frame on


def _half_covered(seed, frames_total=70, first=20, last=50):
    """A disc of radius 50 px turning 0.8 degrees and growing 0.3 % a frame; from ``first`` to ``last`` a
    rectangle of other texture covers its left half (to 3 px short of the centre)."""
    roi = Ellipse.circle(320, 240, 50)
    poses = [Pose(320 + 0.3 * i, 240, 1.0 + 0.003 * i, 0.8 * i) for i in range(frames_total)]
    frames = list(synthetic_sequence(poses, roi, size=(640, 480), seed=seed))
    cover = random_texture(480, 640, np.random.default_rng(seed + 100))
    for i in range(first, last):
        right, top, bottom = int(poses[i].cx) - 3, int(poses[i].cy) - 70, int(poses[i].cy) + 70
        frames[i] = frames[i].copy()
        frames[i][top:bottom, right - 80:right] = cover[top:bottom, right - 80:right]
    return roi, poses, frames


@pytest.mark.parametrize("seed", [8, 11, 14])
def test_occlusion_mask_hides_the_covered_half_and_recovers(seed):
    """``lpcf-masked`` marks the log-polar sectors facing the cover as hidden and those facing away as visible,
    and is back on the object once it is uncovered (measured on seeds 6-21: 14 of 16 back, within 0.2 px; 13 and
    20 not; with OpenCV 4.10, 13 of 16: seed 7, a close call, stays 11 px off, so the seeds tested are three that are
    back within 0.1 px with either). What the mask buys is now small: ``lpcf`` with its colour response is back in
    15 of 16 here and 11 of 16 after a 40-frame cover (``lpcf-masked`` 13), without colour (as ``lpcf-masked``) in
    15 of 16 and, over seeds 0-21 of the 40-frame cover, 17 of 22 against the mask's 18 (before the raw log-polar
    surface was trusted from a match of 0.4, the mask's 14 against 12 here)."""
    roi, poses, frames = _half_covered(seed)
    tracker = create_tracker("lpcf-masked")
    tracker.init(frames[0], roi)
    covered, uncovered, results = [], [], []
    for i, frame in enumerate(frames[1:], 1):
        results.append(tracker.update(frame))
        if 25 <= i < 50 and tracker.block_visibility is not None:
            # Sector j's middle direction on screen: (j + 1/2) * 45 degrees counter-clockwise from the ROI's axis,
            # turned with the object. The innermost band, within a few pixels of the centre, is left out.
            bands, sectors = tracker.block_visibility.shape
            screen = np.radians((np.arange(sectors) + 0.5) * 360 / sectors + results[-1][1].rotation_deg)
            visibility = tracker.block_visibility[1:]
            covered.append(visibility[:, np.cos(screen) < -0.3].mean())
            uncovered.append(visibility[:, np.cos(screen) > 0.3].mean())
    assert len(covered) >= 20  # the mask is on through the occlusion
    assert np.median(covered) <= 0.3 and np.median(uncovered) >= 0.7
    after = results[55:]  # frames 56 on
    truth = poses[56:]
    assert all(ok for ok, _ in after)
    assert np.median(centre_errors(after, truth)) <= 1.0
    assert np.median(scale_errors(after, truth)) <= 0.02
    assert np.median(rotation_errors(after, truth)) <= 1.0


def test_redetection_does_not_jump_to_a_patch_of_background():
    """While lost, a patch elsewhere with a sharper filter response is taken only if it also matches the
    object's log-polar appearance well enough not to be a drop itself. Here the cover (frames 20-49) throws the
    filter 17 px off the object: re-detection used to jump 150 then 300 px into the background and stay there; now
    the search stays near the object, reported lost, during the cover (frames 25-49), and takes it up again on the
    first frame without it (frame 50; frame 51 before the running level followed the match through drops, see
    ``_DROP_LEVEL_RATE``)."""
    roi, poses, frames = _half_covered(9)
    tracker = create_tracker("lpcf")
    tracker.init(frames[0], roi)
    results, searched = [], []
    for frame, pose in zip(frames[1:], poses[1:]):
        results.append(tracker.update(frame))
        searched.append(math.hypot(tracker.cursor.cx - pose.cx, tracker.cursor.cy - pose.cy))
    assert max(searched[19:]) <= 25.0
    assert not any(ok for ok, _ in results[24:49])


def test_a_half_covered_object_is_mostly_found_again():
    """Whether the object is found again after a half cover depends on the scene: when the cover goes it may
    have turned 25 degrees more than the estimate, which the filter does not recognise. Over seeds 0-15 of the
    half-cover scene, ``lpcf`` is back on the object (every frame tracked, median error <= 1 px) from 10 frames
    after the cover in 14 (measured; 15 over 80 frames; 11 and 11 before the raw log-polar surface was trusted
    from a match of 0.4, see ``trust_low``). The colour response pulls the covered object towards its visible
    half: without it, 15 (16 over 80 frames). ``lpcf-masked``, without colour: 14 (14 over 80 frames). Bound: 12."""
    back = 0
    for seed in range(16):
        roi, poses, frames = _half_covered(seed)
        _, results = run(frames, roi)
        back += all(ok for ok, _ in results[59:]) and np.median(centre_errors(results[59:], poses[60:])) <= 1.0
    assert back >= 12


def _leaves_and_returns(seed):
    """A disc of radius 30 px on a 320x240 frame, turning 0.3 degrees a frame, leaves by the right edge at 6 px a
    frame (frames 32-55 wholly out of view), and comes back 25 px lower, crossing the frame leftwards."""
    rng = np.random.default_rng(seed)
    background, texture = random_texture(240, 320, rng), random_texture(121, 121, rng)
    roi = Ellipse.circle(160, 120, 30)
    xs = list(np.arange(160.0, 400.0, 6.0)) + [400.0] * 10 + list(np.arange(400.0, 150.0, -6.0))
    poses = [Pose(float(x), 120.0 + (25.0 if i >= 50 else 0.0), 1.0, 0.3 * i) for i, x in enumerate(xs)]
    return roi, poses, [render_frame(background, texture, roi, pose) for pose in poses]


@pytest.mark.parametrize("seed", [1, 3, 5])
def test_finds_the_object_again_after_it_left_the_view(seed):
    """Out of view, the object is reported lost; when it comes back elsewhere, the whole-frame search finds it
    (measured on seeds 0-5: all six back within 0.2 px; two of six before the search covered the whole frame;
    over 24 more varied generated cases 24 are found again: 7 with patches tried nearest the estimate first, 14
    with patches sweeping the whole frame, two a frame, 24 with the coarse correlation over the whole frame).
    Seeds 1, 3 and 5 each failed without one part: the search settled on background that matched less than a
    tracked frame does (1), the estimate sat at the frame's edge with a weak match and never counted as a drop
    (3), and the search's patches took the angle the estimate had drifted to while the object was away (5)."""
    roi, poses, frames = _leaves_and_returns(seed)
    tracker, results = run(frames, roi)
    out_of_view = [i for i, p in enumerate(poses) if p.cx >= 320 + 30]
    assert not any(results[i - 1][0] for i in out_of_view)
    back = [i for i, p in enumerate(poses) if i > 60 and p.cx <= 320 - 2 * 30]  # wholly inside for a while
    assert len(back) >= 15
    assert all(results[i - 1][0] for i in back)
    assert np.median(centre_errors([results[i - 1] for i in back], [poses[i] for i in back])) <= 1.0


@pytest.mark.parametrize("size, radius, place", [((640, 480), 25, (0.7, 0.6)), ((640, 480), 25, (0.1, 0.9)),
                                                  ((1920, 1080), 10, (0.95, 0.05))])
def test_whole_frame_search_points_at_the_object(size, radius, place):
    """The coarse whole-frame correlation (re-detection) puts its strongest place within a few pixels of the
    object, turned 10 degrees, anywhere in the frame. A small object in a large frame is searched one part of
    the frame per call (here 12 parts, in turn); the object is found in the part that holds it. Measured:
    1.2 and 1.6 px at 640x480 (one part), 0.3 px at 1920x1080 (the other parts' places are 386-1571 px away;
    before the kernel's half-sample alignment was right, 1.2, 4.0 and 1.5 px)."""
    width, height = size
    rng = np.random.default_rng(5)
    background = random_texture(height, width, rng)
    texture = random_texture(4 * radius + 1, 4 * radius + 1, rng)
    roi = Ellipse(width / 3, height / 3, radius, 0.8 * radius, 20)
    tracker = create_tracker("lpcf")
    tracker.init(render_frame(background, texture, roi, Pose(roi.cx, roi.cy, 1.0, 0.0)), roi)
    truth = np.array([width * place[0], height * place[1]])
    frame = render_frame(background, texture, roi, Pose(float(truth[0]), float(truth[1]), 1.0, 10.0))
    pose = Similarity(0.0, 0.0, 1.0, 10.0, 0.0)
    best = min(np.hypot(*(tracker._frame_candidates(frame, pose, 1)[0][0] - truth)) for _ in range(16))
    assert best <= 6.0


def _in_shade(frame, edge_x, gain=0.3, soft=4.0):
    """``frame`` (uint8 BGR) with the part right of ``edge_x`` (pixels) darkened ``gain`` times, over a
    ``soft``-pixel edge: a building's hard shade."""
    ramp = np.clip((np.arange(frame.shape[1], dtype=np.float32) - edge_x) / soft + 0.5, 0.0, 1.0)
    return np.clip(frame * (1.0 - (1.0 - gain) * ramp)[None, :, None], 0, 255).astype(np.uint8)


@pytest.mark.parametrize("seed", [0, 2, 5])
def test_whole_frame_search_points_at_an_object_in_shade(seed):
    """The object, learnt in the light, is in shade (x0.3) on the frame's right side: the strongest places of the
    search's map are on lit background (measured 181-329 px off on 7 of 8 seeds), and the places of the map
    normalised to local lighting include the object's (within 1.1 px on those 7; seed 3 is missed by both)."""
    rng = np.random.default_rng(seed)
    background, texture = random_texture(480, 640, rng), random_texture(101, 101, rng)
    roi = Ellipse(200, 240, 25, 20, 20)
    tracker = create_tracker("lpcf")
    tracker.init(render_frame(background, texture, roi, Pose(roi.cx, roi.cy, 1.0, 0.0)), roi)
    truth = np.array([500.0, 300.0])
    frame = _in_shade(render_frame(background, texture, roi, Pose(500.0, 300.0, 1.0, 0.0)), 320)
    pose = Similarity(0.0, 0.0, 1.0, 0.0, 0.0)
    places, relit = tracker._frame_candidates(frame, pose, 2, local_light=True)
    assert np.min(np.hypot(*(places[relit] - truth).T)) <= 3.0


@pytest.mark.parametrize("seed", [1, 3, 7])
def test_an_object_walking_into_hard_shade_is_found_there(seed):
    """A disc (radius 30 px) walks 3.8 px a frame from the light into a building's shade (x0.3, a 4 px edge) and
    on: wherever wholly in the shade (beyond two radii from the edge), it is reported tracked within a quarter
    radius, and no frame is reported tracked more than a radius off. Over seeds 0-11: found there in 10 runs
    (4 before the searches looked at the map normalised to local lighting); seed 0 stays on the shadow's edge,
    reported tracked at 0.33-0.36, seed 2 is not found. Seeds 1, 3 and 7 failed before."""
    radius = 30
    rng = np.random.default_rng(seed)
    background, texture = random_texture(480, 640, rng), random_texture(4 * radius + 1, 4 * radius + 1, rng)
    poses = [Pose(120 + 3.8 * i, 240 + 10 * math.sin(i / 12), 1.0, 0.2 * i) for i in range(110)]
    roi = Ellipse.circle(poses[0].cx, poses[0].cy, radius)
    frames = [_in_shade(render_frame(background, texture, roi, pose), 320) for pose in poses]
    _, results = run(frames, roi)
    errors = centre_errors(results, poses[1:])
    tracked = np.array([ok for ok, _ in results])
    in_shade = np.array([pose.cx - radius > 320 + 2 * radius for pose in poses[1:]])
    assert in_shade.sum() >= 30
    assert np.all(tracked[in_shade] & (errors[in_shade] < radius / 4))
    assert not np.any(tracked & (errors > radius))


@pytest.mark.parametrize("seed", [7])
def test_an_object_covered_for_good_in_dappled_shade_is_not_tracked_on_background(seed):
    """Blotchy shade (x0.3) over about half of a 640x480 frame, the object (radius 35 px) in a lit patch, covered
    for good from frame 25 by a textured board: no frame after is reported tracked. Seeds 0-11: 7 without the
    searches' map normalised to local lighting; 5 with it while its places were asked for no more than the plain
    map's (seeds 0 and 7 settled on background); 6 now (``_RELIT_MATCH_GAIN``; seed 0 still does). The other 5
    fail with or without it."""
    radius, rng = 35, np.random.default_rng(seed)
    background, texture = random_texture(480, 640, rng), random_texture(4 * radius + 1, 4 * radius + 1, rng)
    board = random_texture(480, 640, np.random.default_rng(seed + 1000))
    blobs = cv2.GaussianBlur(np.random.default_rng(seed + 3000).standard_normal((480, 640)).astype(np.float32),
                             (0, 0), 30)
    light = 1 - 0.7 * np.clip((blobs - np.median(blobs)) / (0.1 * blobs.std()) + 0.5, 0, 1)
    light[200:280, 360:500] = 1.0
    light = cv2.GaussianBlur(light, (0, 0), 2)[..., None]
    poses = [Pose(430 + 0.4 * i, 240.0, 1.0, 0.3 * i) for i in range(130)]
    roi = Ellipse.circle(430, 240, radius)
    noise = np.random.default_rng(seed + 5000)
    frames = []
    for i, pose in enumerate(poses):
        frame = render_frame(background, texture, roi, pose).astype(np.float32)
        if i >= 25:
            top, left = int(240 - 1.6 * radius), int(430 - 1.6 * radius)
            frame[top:int(240 + 1.6 * radius), left:int(430 + 1.6 * radius + 70)] = \
                board[top:int(240 + 1.6 * radius), left:int(430 + 1.6 * radius + 70)]
        frames.append(np.clip(frame * light + noise.normal(0, 2.0, frame.shape), 0, 255).astype(np.uint8))
    _, results = run(frames, roi)
    assert not any(ok for ok, _ in results[30:])


@pytest.mark.parametrize("size, radius, velocity, seed", [((320, 240), 30, (6, 0), 4), ((640, 360), 40, (-10, 0), 8),
                                                         ((320, 240), 30, (6, 0), 10), ((640, 480), 25, (0, 8), 9)])
def test_an_object_gone_for_good_is_not_tracked_on_background(size, radius, velocity, seed):
    """A tilted ellipse turning 0.5 degrees a frame leaves the view and never comes back (80 frames more): no frame
    after it has gone is reported tracked. Before the response had to be sharp to resume, the lost estimate was
    reported tracked for 81-85 frames on background that matched just above the resume level with a weak filter
    response (PSR 8.6 and 7.1, where 9.8 is now asked for): in the first case a patch it had wandered onto, in the
    second a place in the frame's corner the whole-frame search had found. (Over 80 such generated runs, see
    ``_RESUME_PSR``, 15 had a false track before and 11 after.) Before resuming at the edge needed a higher match
    (``_RESUME_AT_EDGE``), the last two were reported tracked for 84 and 17 frames on background at the frame's
    edge (half and two thirds of a semi-axis inside it) that matched at 0.47 and 0.44 of the running level."""
    width, height = size
    roi = Ellipse(width / 2, height / 2, radius, 0.8 * radius, 15.0 * seed)

    def in_view(x, y, margin):
        return -margin < x < width + margin and -margin < y < height + margin

    poses, (x, y) = [], (width / 2, height / 2)
    while in_view(x, y, 2 * radius):
        poses.append(Pose(x, y, 1.0, 0.5 * len(poses)))
        x, y = x + velocity[0], y + velocity[1]
    gone_from = next(i for i, p in enumerate(poses) if not in_view(p.cx, p.cy, radius))
    poses += [poses[-1]] * 80
    _, results = run(list(synthetic_sequence(poses, roi, size=size, seed=seed)), roi)
    assert all(ok for ok, _ in results[:gone_from - 9])  # tracked while well in view
    assert not any(ok for ok, _ in results[gone_from - 1:])


def _leaves_and_comes_back_from_below(seed):
    """A disc of radius 30 px on a 320x240 frame, turning 0.3 degrees a frame, leaves by the right edge at 7 px a
    frame, is out of view for 20 frames or more, and comes back from below at x = 128, rising 7 px a frame to
    y = 72: far from where it left, on the other side of the frame."""
    rng = np.random.default_rng(seed)
    background, texture = random_texture(240, 320, rng), random_texture(121, 121, rng)
    roi = Ellipse.circle(160, 120, 30)
    path = [(float(x), 120.0) for x in np.arange(160.0, 380.0, 7.0)] + [(380.0, 120.0)] * 10
    path += [(128.0, float(y)) for y in np.arange(300.0, 72.0, -7.0)]
    poses = [Pose(x, y, 1.0, 0.3 * i) for i, (x, y) in enumerate(path)]
    return roi, poses, [render_frame(background, texture, roi, pose) for pose in poses]


@pytest.mark.parametrize("seed", [6, 7])
def test_finds_the_object_coming_back_from_the_other_side(seed):
    """The estimate left at the right edge is not where the object comes back; the whole-frame search finds it
    there, on every frame it shows whole. Seeds 0-7: all 8 found, while still partly below the frame (median
    0.02-0.05 px off once whole); the search before (patches of the filter's size swept over the frame nearest
    the estimate first, two a frame) found 6, and not seeds 6 and 7."""
    roi, poses, frames = _leaves_and_comes_back_from_below(seed)
    _, results = run(frames, roi)
    back = [i for i, p in enumerate(poses) if p.cx == 128.0 and p.cy <= 240 - 30 - 40]  # whole, for 6 frames
    assert len(back) == 14
    assert all(results[i - 1][0] for i in back)
    assert np.median(centre_errors([results[i - 1] for i in back], [poses[i] for i in back])) <= 1.0


@pytest.mark.parametrize("size, radius, seed", [((640, 480), 30, 0), ((320, 240), 25, 0)])
def test_an_object_back_from_an_absence_turned_is_found_again(size, radius, seed):
    """A tilted ellipse vanishes for 30 frames and comes back elsewhere turned by 20 degrees: the whole-frame
    search, turning and resizing the object after its first three sweeps, finds it and tracks it to the end, with
    its turn; never reported tracked while away. At the last tracked angle alone it was not found in either
    case (nor in 7 of the 12 such runs of ``_SEARCH_POSES``' note)."""
    width, height = size
    rng = np.random.default_rng(seed)
    roi = Ellipse(width * 0.3, height * 0.4, radius, 0.7 * radius, 15.0 * seed)
    poses = [Pose(roi.cx + 2 * i, roi.cy + i, 1.0, 0.0) for i in range(30)]
    away = len(poses)
    poses += [Pose(-10.0 * width, -10.0 * height, 1.0, 0.0)] * 30
    back = len(poses)
    x, y = width * rng.uniform(0.25, 0.75), height * rng.uniform(0.3, 0.7)
    poses += [Pose(x + 1.5 * i, y - i, 1.0, 20.0 + 0.3 * i) for i in range(60)]
    _, results = run(list(synthetic_sequence(poses, roi, size=size, seed=seed)), roi)
    assert not any(ok for ok, _ in results[away - 1:back - 1])
    found = next(i for i in range(back, len(poses)) if results[i - 1][0])
    assert found - back <= 24  # one cycle of the turned and resized searches
    after = results[found - 1:]
    errors = centre_errors(after, poses[found:])
    assert all(ok for ok, _ in after) and errors.max() < 0.25 * radius
    assert np.median([abs(s.rotation_deg - p.rotation_deg) for (_, s), p in zip(after, poses[found:])]) < 1.0


def test_a_search_in_parts_covers_each_pose_part_by_part_in_turn(monkeypatch):
    """A frame searched in parts (a small object in a large frame; here a 640 x 480 frame, with parts made small):
    while lost, each pose's map is searched part after part, each part once, before the next pose, first the last
    tracked pose for ``_SEARCH_AS_LEFT`` sweeps, then ``_SEARCH_POSES`` in order, though a turned map has more
    parts than an upright one. (Counting on the part count of whichever map was searched last, poses changed half
    way through a map, or parts were skipped.)"""
    from logpolar_track.trackers import lpcf

    monkeypatch.setattr(lpcf, "_SEARCH_PART", 150)
    searched = []  # (turn from the last tracked angle in degrees, size factor, part, parts) per search
    frame_candidates = lpcf.LogPolarCorrelationTracker._frame_candidates

    def spy(self, frame, pose, count, long_term=False, local_light=False, coarse=None, maps=None):
        part = self._search_part
        centres = frame_candidates(self, frame, pose, count, long_term, local_light, coarse, maps)
        if not long_term:
            last = self._last_good
            searched.append((round(pose.rotation_deg - last.rotation_deg, 6), round(pose.scale / last.scale, 6),
                             part, self._search_parts))
        return centres

    monkeypatch.setattr(lpcf.LogPolarCorrelationTracker, "_frame_candidates", spy)
    roi = Ellipse(192.0, 192.0, 30.0, 21.0, 0.0)
    poses = [Pose(roi.cx + 2 * i, roi.cy + i, 1.0, 0.0) for i in range(30)] + [Pose(-1e4, -1e4, 1.0, 0.0)] * 130
    run(list(synthetic_sequence(poses, roi, size=(640, 480), seed=0)), roi)
    sweeps = []
    for turn, size, part, parts in searched:
        if part == 0:
            sweeps.append(((turn, size), parts, []))
        assert sweeps and sweeps[-1][0] == (turn, size) and sweeps[-1][1] == parts
        sweeps[-1][2].append(part)
    assert all(seen == list(range(parts)) for _, parts, seen in sweeps[:-1])
    assert sweeps[-1][2] == list(range(len(sweeps[-1][2])))
    order = [(0.0, 1.0)] * lpcf._SEARCH_AS_LEFT + list(lpcf._SEARCH_POSES) * 9
    assert [pose for pose, _, _ in sweeps] == order[:len(sweeps)]
    assert len(sweeps) > lpcf._SEARCH_AS_LEFT + len(lpcf._SEARCH_POSES)  # a whole cycle of the poses
    assert sweeps[0][1] >= 2 and len({parts for _, parts, _ in sweeps}) >= 2  # 2 parts upright, 4 turned


@pytest.mark.parametrize("seed", [0, 2])
def test_a_twin_far_away_is_not_taken_for_an_object_hidden_for_a_moment(seed):
    """A textured ellipse is hidden for 12 frames (taken away, not moved) while its twin stands 340 px away: the
    whole-frame searches do not jump to the twin, which the object cannot have reached so soon, and the object is
    tracked again when it is back. (Before the searches' reach the long-term search moved to the twin and tracked
    it to the end, in 3 of 4 seeds.)"""
    rng = np.random.default_rng(seed)
    background = random_texture(480, 640, rng)
    texture = random_texture(121, 121, rng)
    roi = Ellipse(170.0, 200.0, 30.0, 24.0, 20.0)
    twin = Pose(480.0, 320.0, 1.0, 0.0)
    poses = [Pose(roi.cx + i, roi.cy + 0.5 * i, 1.0, 0.2 * i) for i in range(70)]
    with_twin = [render_frame(background, texture, roi, twin) for _ in poses]
    frames = [f if 25 <= i < 37 else render_frame(f, texture, roi, p) for i, (f, p) in enumerate(zip(with_twin, poses))]
    _, results = run(frames, roi)
    assert not any(ok and math.hypot(s.centre[0] - twin.cx, s.centre[1] - twin.cy) < 60 for ok, s in results)
    assert all(ok for ok, _ in results[-20:]) and centre_errors(results[-20:], poses[-20:]).max() < 1.0


@pytest.mark.parametrize("seed", [0, 3])
def test_an_object_hidden_while_moving_fast_is_found_where_it_went(seed):
    """A textured ellipse crossing the frame at 20 px a frame (two thirds of its radius) is hidden for 8 frames:
    the searches' reach grows with the speed it was tracked at, so it is found as soon as it shows, 200 px on, and
    tracked to the end. (With a reach of a quarter semi-axis a frame alone, it was not found before it left.)"""
    rng = np.random.default_rng(seed)
    background = random_texture(480, 640, rng)
    texture = random_texture(121, 121, rng)
    roi = Ellipse(80.0, 240.0 + 40 * rng.uniform(-1, 1), 30.0, 24.0, 30.0 * seed)
    poses = [Pose(roi.cx + 20.0 * i, roi.cy + 2.0 * i, 1.0, 0.3 * i) for i in range(25)]
    frames = [background.copy() if 10 <= i < 18 else render_frame(background, texture, roi, p)
              for i, p in enumerate(poses)]
    _, results = run(frames, roi)
    back = results[18 - 1:]
    assert all(ok for ok, _ in back[2:]) and centre_errors(back[2:], poses[20:]).max() < 0.25 * roi.a


def _leaves_and_comes_back_elsewhere(case):
    """Case ``case`` of 24 generated leave-and-return scenes: a textured ellipse (radius 25-45 px, tilted 0-180
    degrees, turning 0.3 degrees a frame) leaves by the right edge at 6-10 px a frame, stays out for 10 frames and
    comes back across the frame from the right, the left or below (``case % 3``), on 640 x 480 or 320 x 240."""
    rng = np.random.default_rng(100 + case)
    width, height = [(640, 480), (320, 240)][case % 2]
    r = float(rng.uniform(25, 45))
    background = random_texture(height, width, rng)
    texture = random_texture(int(4 * r) | 1, int(4 * r) | 1, rng)
    roi = Ellipse(width / 2, height / 2, r, r * float(rng.uniform(0.7, 1.0)), float(rng.uniform(0, 180)))
    v = 6.0 + 4 * rng.random()
    path = [(x, height / 2) for x in np.arange(width / 2, width + 2 * r, v)] + [(width + 2 * r, height / 2)] * 10
    y_back = float(rng.uniform(0.3, 0.7)) * height
    if case % 3 == 0:
        path += [(x, y_back) for x in np.arange(width + 2 * r, width * 0.3, -v)]
    elif case % 3 == 1:
        path += [(x, y_back) for x in np.arange(-2 * r, width * 0.7, v)]
    else:
        path += [(width * 0.4, y) for y in np.arange(height + 2 * r, height * 0.3, -v)]
    poses = [Pose(float(x), float(y), 1.0, 0.3 * i) for i, (x, y) in enumerate(path)]
    return roi, poses, [render_frame(background, texture, roi, pose) for pose in poses], r


@pytest.mark.parametrize("case", [7, 11, 14, 16])
def test_a_tilted_object_is_found_again_and_never_tracked_on_background(case):
    """Tilted objects (ROIs at 52-172 degrees) leaving the view and coming back elsewhere. Over the 24 generated
    cases, all are found again (80 % of the last 15 frames with the object wholly in view, within a quarter of its
    radius) and none is reported tracked while away. These four failed when the patches turned with the ROI: the
    search, over a map turned alike, took the straight edge of the frame's constant surround for the object and
    settled on background by the edge (cases 11 and 16, tracked there while away), and a lost estimate wandering on
    background resumed at a weak match (14). (24 of 24 upright before that; 20 of 24 and 2 tracked while away
    then; with the mirrored surround alone 22 and 0; with resuming only at 0.4 of the running level too, 24 and 0.)"""
    roi, poses, frames, r = _leaves_and_comes_back_elsewhere(case)
    width, height = frames[0].shape[1], frames[0].shape[0]
    _, results = run(frames, roi)
    away = [k for k, p in enumerate(poses) if p.cx > width + r or p.cx < -r or p.cy > height + r]
    assert not any(results[k - 1][0] for k in away)
    back = [k for k, p in enumerate(poses) if k >= len(poses) - 15 and r < p.cx < width - r and r < p.cy < height - r]
    correct = [results[k - 1][0] and centre_errors([results[k - 1]], [poses[k]])[0] < 0.25 * r for k in back]
    assert back and np.mean(correct) >= 0.8


def _behind_a_pole(seed, speed, width):
    """A textured disc of radius 30 px moving ``speed`` px a frame to the right (and a little up and down),
    turning 0.3 degrees a frame, behind a plain pole ``width`` px wide across the middle of a textured frame: it
    slides out of view gradually, so its match weakens with no sudden drop. Frames and poses."""
    rng = np.random.default_rng(seed)
    background = random_texture(480, 640, rng)
    texture = random_texture(99, 99, rng)
    roi = Ellipse.circle(100, 240, 30)
    poses = [Pose(100 + speed * k, 240 + 20 * math.sin(k / 15), 1.0, 0.3 * k) for k in range(int(440 / speed))]
    frames = []
    for pose in poses:
        frame = render_frame(background, texture, roi, pose).copy()
        frame[:, 320 - width // 2:320 + width // 2] = (40, 60, 50)
        frames.append(frame)
    return frames, poses, roi


@pytest.mark.parametrize("seed, speed, width", [(1, 8.0, 80), (1, 6.0, 60)])
def test_an_object_that_went_behind_a_pole_is_found_beyond_it(seed, speed, width):
    """The estimate stays on the pole while the object goes on; the long-term search looked only within the
    object's reach of that estimate, counting the frames it was not recognised, and the object was already
    further on (never found again in these two runs; 13 of 16 such runs were). It now also looks within reach of
    the place last reported tracked, at the speed the object had there, counting the frames since."""
    frames, poses, roi = _behind_a_pole(seed, speed, width)
    _, results = run(frames, roi)
    errors = centre_errors(results, poses[1:])
    assert np.all(errors[-8:] < 0.25 * roi.a)
    assert all(ok for ok, _ in results[-8:])


def _replaced_and_back_elsewhere(seed):
    """A textured disc (radius 30 px, on a 320x240 frame over a smoother background: a wall, not more of the
    object's texture) drifts right 2 px a frame while, over frames 10-50, its texture turns slowly into another
    (a head turning away); that other stays where it is from frame 50 on, the disc is out of view for 20 frames
    and is then back, as it was in the first frame, 120 px away, drifting 0.5 px a frame. Poses are None while it
    is away."""
    rng = np.random.default_rng(seed)
    background = cv2.GaussianBlur(random_texture(240, 320, rng), (0, 0), 2.0)
    texture, other = random_texture(121, 121, rng), random_texture(121, 121, rng)
    texture = cv2.addWeighted(texture, 0.8, np.full_like(texture, 40), 1.0, 0)
    roi = Ellipse.circle(96, 96, 30)
    frames, poses = [], []
    for i in range(110):
        pose = Pose(96 + 2.0 * min(i, 50), 96, 1.0, 0.0)
        if i < 50:
            turned = min(max((i - 10) / 40, 0.0), 1.0)
            frames.append(cv2.addWeighted(render_frame(background, texture, roi, pose), 1 - turned,
                                          render_frame(background, other, roi, pose), turned, 0))
            poses.append(pose)
            continue
        frame = render_frame(background, other, roi, pose)
        if i >= 70:
            poses.append(Pose(96 + 0.5 * (i - 70), 168, 1.0, 0.0))
            frame = render_frame(frame, texture, roi, poses[-1])
        else:
            poses.append(None)
        frames.append(frame)
    return roi, poses, frames


@pytest.mark.parametrize("seed", [0, 1, 4, 5, 7])
def test_the_long_term_model_finds_an_object_whose_match_faded_slowly(seed):
    """The disc's match fades with its texture, so no sudden drop starts the whole-frame search, and without the
    long-term model (``long_term=False``) the estimate stays where the disc was, on the wall or on the texture it
    turned into (seeds 0-5: found again in none, 92-113 px off; seeds 2 and 5 reported tracked on the other
    texture throughout). The first frame's filter no longer recognises the estimate, searches the frame, and
    finds the disc back: seeds 0, 1, 3, 4 and 5, within 0.4 px (of 0-5; seed 2 stays on the other texture, which
    the first frame's filter answers at 0.38, above ``_LONG_TERM_WEAK``, and which matches well enough to be
    reported tracked). Seed 3's estimate stays on the wall, which that filter answers at 0.24, reported lost: it is
    searched for once it has been reported lost for ``_LONG_TERM_LOST_RUN`` frames (before, it stayed there, 103
    px off, to the end). So are seeds 0, 4, 5 and 7 (lost 26-37 frames in a row), found 1-5 frames after the disc
    is back. Seed 3 is a close call, not tested: with OpenCV 4.10 its estimate, lost on the wall, drifts to another
    scale and angle (1.04 and -6 degrees at frame 71, against 0.98 and -3), at which the coarse map of the
    whole-frame search no longer ranks the disc among its candidates, and it is not found (seed 7 is, with both)."""
    roi, poses, frames = _replaced_and_back_elsewhere(seed)
    _, results = run(frames, roi)
    back = list(range(len(frames) - 25, len(frames)))
    assert all(results[k - 1][0] for k in back)
    assert np.median(centre_errors([results[k - 1] for k in back], [poses[k] for k in back])) <= 1.0


def _faded_out_and_back(seed, turn_deg=0.0):
    """A disc (radius 40 px, 640x480) still at (200, 240) for 20 frames, fading into the background over 25 while it
    turns ``turn_deg`` degrees, away for 20, then back for 60 frames 250 px to the right, at its first frame's angle:
    the ROI and the frames."""
    rng = np.random.default_rng(seed)
    background, texture = random_texture(480, 640, rng), random_texture(99, 99, rng)
    roi = Ellipse.circle(200, 240, 40)
    frames = [render_frame(background, texture, roi, Pose(200, 240, 1.0, 0.0))] * 20
    for k in range(1, 26):
        turned = render_frame(background, texture, roi, Pose(200, 240, 1.0, turn_deg * k / 25))
        frames.append(cv2.addWeighted(turned, 1 - k / 25, background, k / 25, 0))
    frames += [background] * 20 + [render_frame(background, texture, roi, Pose(450, 240, 1.0, 0.0))] * 60
    return roi, frames


def _found_back(results, within_px):
    """The first frame (65 or later) at which the disc of :func:`_faded_out_and_back` is reported tracked within
    ``within_px`` of its place, checking that nothing is reported tracked while it is away (frames 45-64) and every
    frame is from then on; None if it is not found."""
    statuses = [ok for ok, _ in results]  # results[k - 1] is frame k
    assert not any(statuses[44:64])
    found = [k for k in range(65, len(results) + 1) if statuses[k - 1]
             and math.hypot(results[k - 1][1].centre[0] - 450, results[k - 1][1].centre[1] - 240) < within_px]
    if found:
        assert all(statuses[found[0] - 1:])
    return found[0] if found else None


@pytest.mark.parametrize("seed", [1, 7])
def test_an_object_that_faded_out_is_searched_for_and_found_elsewhere(seed):
    """A disc (radius 40 px, 640x480, still) fades into the background over 25 frames, is away for 20 and is then
    shown 250 px to its right. Nothing makes a sudden drop, the running level sinks with the match, and where the
    first frame's filter answers the background left behind at ``_LONG_TERM_WEAK`` or more (seeds 1 and 7 of 0-7)
    nothing searched: the disc was reported lost to the end. Reported lost for ``_LONG_TERM_LOST_RUN`` frames, the
    estimate is searched for with the long-term model, and the disc is found (measured: 9 and 7 frames after it is
    back) and never reported tracked while it is away."""
    roi, frames = _faded_out_and_back(seed)
    _, results = run(frames, roi)
    found = _found_back(results, 10)
    assert found is not None and found - 65 <= 40


@pytest.mark.parametrize("seed", [0, 3, 5, 7, 8])
def test_an_object_back_at_its_first_angle_is_found_whatever_angle_the_estimate_wandered_to(seed):
    """As above, but the disc turns 50 degrees while it fades out (the estimate follows part of the turn, to 26-38
    degrees) and comes back at its first frame's angle, as a face turning away and back does. The long-term filter,
    the first frame's, searched at the estimate's angle only and did not find it (seeds 0, 3, 5, 7 and 8 of 0-11;
    found in 5 of the 12); it also searches at the first frame's angle now, and finds it within 5 frames in these
    (10 of the 12), at its own angle, and nothing is reported tracked while it is away."""
    roi, frames = _faded_out_and_back(seed, turn_deg=50.0)
    _, results = run(frames, roi)
    found = _found_back(results, 5)
    assert found is not None and found - 65 <= 15
    assert abs(results[-1][1].rotation_deg) < 2.0


@pytest.mark.parametrize("seed", [1, 4, 10])
def test_an_object_lost_during_a_drop_is_searched_for_by_the_long_term_model_too(seed):
    """As above (the disc turns 50 degrees while it fades out, and comes back at its first angle), where the fade
    makes a sudden drop: the short-term search then looks for the disc as it last looked, turned, and the long-term
    model's search, at the first frame's angle, did not start while that search was under way (the frames of a drop
    were not counted as lost by ``_LONG_TERM_LOST_RUN``): found 20 and 21 frames after it was back (seeds 1 and 4)
    and not at all (seed 10). Counted now, it is found within 5 frames (65, 69 and 70; asserted within 10, for margin),
    and nothing is reported tracked while it is away."""
    roi, frames = _faded_out_and_back(seed, turn_deg=50.0)
    _, results = run(frames, roi)
    found = _found_back(results, 5)
    assert found is not None and found - 65 <= 10


def test_a_frame_the_long_term_model_does_not_recognise_is_not_learnt():
    """Where the first frame's filter answers the estimate below ``_LONG_TERM_WEAK`` (and so does the snapshot of a
    later appearance, where there is one: see ``_SNAPSHOT_PSR``), the frame is not learnt, even
    where the short-term filter answers sharply enough to learn (what it would learn there may be a look-alike):
    a disc drifting 1 px a frame whose texture turns into another over 100 frames (seed 3: 14 such frames, all of
    them sharp)."""
    rng = np.random.default_rng(3)
    background = cv2.GaussianBlur(random_texture(240, 320, rng), (0, 0), 2.0)
    texture, other = random_texture(121, 121, rng), random_texture(121, 121, rng)
    roi = Ellipse.circle(96, 120, 30)
    tracker = create_tracker("lpcf")
    sharp = 0
    for i in range(140):
        pose = Pose(96 + 1.0 * i, 120, 1.0, 0.0)
        turned = min(max((i - 10) / 100, 0.0), 1.0)
        frame = cv2.addWeighted(render_frame(background, texture, roi, pose), 1 - turned,
                                render_frame(background, other, roi, pose), turned, 0)
        if i == 0:
            tracker.init(frame, roi)
            continue
        before = tracker.numerator.copy()  # _learn updates the filter's running sums in place
        tracker.update(frame)
        snapshot_peak = tracker.diagnostics["snapshot_peak"]  # the later appearance's, where it was needed
        if tracker.diagnostics["long_term_peak"] < 0.2 and (snapshot_peak is None or snapshot_peak < 0.2):
            assert np.array_equal(tracker.numerator, before)
            sharp += tracker.diagnostics["psr"] >= tracker.psr_learn
    assert sharp >= 10


def _changed_and_back_elsewhere(seed):
    """A disc (radius 40 px, 640x480) still at (200, 240) whose texture turns into another over frames 10-70 (a face
    that grows, turns and takes its glasses off), shown changed for 10 frames more, then gone (the background alone)
    for 20 frames, and back looking as it did last, 250 px to the right, for 60 frames: the ROI, the frames and the
    first frame it is back."""
    rng = np.random.default_rng(seed)
    background, texture, other = (random_texture(480, 640, rng), random_texture(99, 99, rng),
                                  random_texture(99, 99, rng))
    roi = Ellipse.circle(200, 240, 40)
    first, late = (render_frame(background, image, roi, Pose(200, 240, 1.0, 0.0)) for image in (texture, other))
    frames = [cv2.addWeighted(first, 1 - t, late, t, 0) for t in np.clip((np.arange(80) - 10) / 60, 0.0, 1.0)]
    frames += [background] * 20
    return roi, frames + [render_frame(background, other, roi, Pose(450, 240, 1.0, 0.0))] * 60, len(frames)


@pytest.mark.parametrize("seed", [1, 3, 11])
def test_an_object_that_changed_for_good_is_recognised_and_found_again_as_it_became(seed):
    """The long-term model remembers a later appearance too (``_SNAPSHOT_PSR``): the disc whose texture turned into
    another is recognised by that snapshot once the first frame's filter no longer answers it, and learnt on, and
    found again where it comes back, as it became. With the first frame's filter alone (seeds 1, 3 and 11 of 0-11)
    its frames were no longer learnt once it had changed, and it was not found again (reported lost to the end);
    with the snapshot, found on the first frame back (seeds 1 and 3) or the third (11), and nothing is reported
    tracked while it is away (found in 7 of the 12 seeds, against 4)."""
    roi, frames, back = _changed_and_back_elsewhere(seed)
    _, results = run(frames, roi)
    statuses = [ok for ok, _ in results]  # results[k - 1] is frame k
    assert not any(statuses[back - 21:back - 1])
    near = [k for k in range(back, len(frames)) if statuses[k - 1]
            and math.hypot(results[k - 1][1].centre[0] - 450, results[k - 1][1].centre[1] - 240) < 5]
    assert near and near[0] - back <= 5
    assert all(statuses[near[0] - 1:])


@pytest.mark.parametrize("seed", [1, 2, 4])
def test_a_plain_object_over_a_busy_background_is_followed(seed):
    """A bright disc with a quarter of its background's contrast, moving 3 px a frame over a still, busy
    background: the background held the filter (5-29 % of the frames tracked). Its filter now learns from the
    object alone: every frame (measured 0.6-1.0 px median)."""
    width, height, radius = 640, 480, 40.0
    rng = np.random.default_rng(seed)
    background = random_texture(height, width, rng)
    texture = random_texture(99, 99, rng).astype(np.float32)
    texture = (np.clip(texture.mean() + 0.25 * (texture - texture.mean()), 0, 255) * 0.8 + 40).astype(np.uint8)
    roi = Ellipse.circle(320, 240, radius)
    heading = rng.uniform(0, 2 * math.pi)
    poses = [Pose(320 + 3 * i * math.cos(heading), 240 + 1.5 * i * math.sin(heading), 1.0, 0.5 * i) for i in range(80)]
    frames = [np.clip(render_frame(background, texture, roi, p) + rng.normal(0, 2, (height, width, 3)), 0, 255)
              .astype(np.uint8) for p in poses]
    tracker, results = run(frames, roi)
    assert tracker.train_mask is not None
    assert np.mean(centre_errors(results, poses[1:]) < 0.25 * radius) >= 0.95


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("radius", [40.0, 43.0])
def test_a_roi_drawn_inside_a_finely_textured_disc_is_not_taken_for_a_plain_object(seed, radius):
    """A disc of radius 50 px, its texture finer than the patch's sampling, on a darker textured background, with
    the ROI drawn inside it: the disc's own edge, around the ROI, read as a busy surround, and the filter that
    learnt the inside alone lost the disc -- even standing still, from its second frame (a user's report). That
    filter is now checked on its own first frame and dropped: every frame followed, drifting 2 px a frame."""
    rng = np.random.default_rng(seed)
    texture = cv2.GaussianBlur((rng.random((201, 201, 3)) * 255).astype(np.uint8), (7, 7), 0)
    yy, xx = np.mgrid[-100:101, -100:101]
    disc = ((xx ** 2 + yy ** 2) <= 100 ** 2).astype(np.uint8) * 255
    background = cv2.GaussianBlur((rng.random((480, 640, 3)) * 120).astype(np.uint8), (5, 5), 0)
    frames, poses = [], []
    for i in range(20):
        place = cv2.getRotationMatrix2D((100, 100), 0.0, 0.5)  # the texture halved: finer than the patch's samples
        place[:, 2] += (220 + 2 * i, 140 + i)
        inside = cv2.warpAffine(disc, place, (640, 480)) > 127
        frame = background.copy()
        frame[inside] = cv2.warpAffine(texture, place, (640, 480))[inside]
        frames.append(frame)
        poses.append(Pose(320 + 2 * i, 240 + i, 1.0, 0.0))
    roi = Ellipse.circle(320, 240, radius)
    tracker, results = run(frames, roi)
    assert tracker.train_mask is None
    assert all(ok for ok, _ in results)
    assert np.max(centre_errors(results, poses[1:])) < 0.1 * radius


def test_a_wheel_with_one_mark_turning_steadily_is_followed_without_slipping():
    """A plain disc with one radial stripe (a wheel with a mark, a user's report) turning 3 degrees a frame: the
    filter's centre, pulled towards the stripe, made the log-polar match read the turn backwards, the refinement's
    bound (3 degrees) cut its correction short, and the wheel fell 10-20 degrees behind for good (36 degrees after
    1500 frames). Now the refinement may correct 6 degrees and the steady turn is predicted: within 1.5 degrees
    on every frame (measured 0.27; 11.6 before)."""
    rng = np.random.default_rng(0)
    background = (rng.random((480, 640, 3)) * 80).astype(np.uint8)
    tracker = create_tracker("lpcf")
    errors = []
    for i in range(120):
        frame = background.copy()
        cv2.circle(frame, (320 * 16, 240 * 16), 60 * 16, (200, 50, 50), -1, cv2.LINE_AA, 4)
        t = math.radians(3.0 * i)
        end = (round((320 + 58 * math.cos(t)) * 16), round((240 - 58 * math.sin(t)) * 16))
        cv2.line(frame, (320 * 16, 240 * 16), end, (255, 255, 255), 10, cv2.LINE_AA, 4)
        if i == 0:
            tracker.init(frame, Ellipse.circle(320, 240, 60))
            continue
        ok, state = tracker.update(frame)
        assert ok
        errors.append(state.rotation_deg - 3.0 * i)
    assert np.max(np.abs(errors)) < 1.5


def test_a_plain_disc_with_one_dot_does_not_drift():
    """A plain disc with one dot 40 px from its centre, turning 1 degree a frame (a turntable with a mark): the
    recent patches of the refinement's subspace, sampled at slightly wrong poses, explained the misalignment, and the
    estimate drifted while tracked at a high score (centre 3.8 px off, turn 5.1 degrees behind after 120 frames).
    Where the patch still looks as on the first frame the refinement aligns to that frame: within 2.5 px throughout
    and 1 degree at the end (measured 1.2 px, 0.1 degrees)."""
    rng = np.random.default_rng(0)
    background = (rng.random((480, 640, 3)) * 80).astype(np.uint8)
    tracker = create_tracker("lpcf")
    for i in range(120):
        frame = background.copy()
        cv2.circle(frame, (320 * 16, 240 * 16), 60 * 16, (200, 50, 50), -1, cv2.LINE_AA, 4)
        t = math.radians(1.0 * i)
        dot = (round((320 + 40 * math.cos(t)) * 16), round((240 - 40 * math.sin(t)) * 16))
        cv2.circle(frame, dot, 6 * 16, (255, 255, 255), -1, cv2.LINE_AA, 4)
        if i == 0:
            tracker.init(frame, Ellipse.circle(320, 240, 60))
            continue
        ok, state = tracker.update(frame)
        assert ok
        assert math.hypot(state.centre[0] - 320, state.centre[1] - 240) < 2.5
    assert abs(state.rotation_deg - 119.0) < 1.0


def _plain_disc(frames_total: int = 60, growth: float = 1.5, noise: float = 0.0, seed: int = 0):
    """A plain disc (one colour, anti-aliased) on a plain background, moving 3 px a frame to the right and up and
    down, its radius growing from 40 px by ``growth`` times: frames and true poses (scale against the first)."""
    rng = np.random.default_rng(seed)
    frames, poses = [], []
    for k in range(frames_total):
        radius = 40.0 * growth ** (k / (frames_total - 1))
        x, y = 200.0 + 3 * k, 240.0 + 40 * math.sin(k / 10)
        frame = np.full((480, 640, 3), 60, np.uint8)
        cv2.circle(frame, (round(16 * x), round(16 * y)), round(16 * radius), (200, 180, 160), -1, cv2.LINE_AA, 4)
        if noise:
            frame = np.clip(frame + rng.normal(0, noise, frame.shape), 0, 255).astype(np.uint8)
        frames.append(frame)
        poses.append(Pose(x, y, radius / 40.0, 0.0))
    return frames, poses


@pytest.mark.parametrize("noise, params", [(0.0, {}), (3.0, {}), (0.0, {"n_rho": 31, "anchor_weight": 0.3})])
def test_a_plain_disc_is_tracked_on_every_frame(noise, params):
    """A ball, a coin, a cell: the same at every angle, so the log-polar phase correlation peaks low (0.04) however
    well the images match, and the score fell with it: reported lost on 14 of 59 frames (the rows kept the last
    good place, up to 10 px behind) while the estimate was within 0.1 px. The score now takes the images' likeness
    there (see _SIMILARITY_POWER). Its turn cannot be seen, and is not read from the ridge's noise (it jumped by up
    to 10 degrees a frame; see _TURN_UNSEEN): what remains is the refinement's slow drift (2.6 degrees with
    noise)."""
    frames, poses = _plain_disc(noise=noise)
    roi = Ellipse.circle(poses[0].cx, poses[0].cy, 40.0)
    tracker, results = run(frames, roi, **params)  # an odd n_rho takes NumPy's correlator, not the packed one
    assert tracker.packed_correlator is None if params else tracker.packed_correlator is not None
    assert all(ok for ok, _ in results)
    assert min(state.score for _, state in results) >= tracker.lost_threshold
    assert centre_errors(results, poses[1:]).max() < 0.5
    assert scale_errors(results, poses[1:]).max() < 0.01
    turns = np.array([state.rotation_deg for _, state in results])
    assert np.abs(turns).max() < 4.0 and np.abs(np.diff(turns)).max() < 1.0


@pytest.mark.parametrize("a, b, spin, noise", [(60, 25, 1.0, 0.0), (60, 40, 1.0, 0.0), (60, 25, 2.0, 3.0),
                                                (50, 15, 1.0, 0.0)])
def test_a_plain_turning_ellipse_has_its_turn_from_the_refinement(a, b, spin, noise):
    """A plain ellipse on a plain background, moving 2 px and turning ``spin`` degrees a frame. On its own
    elliptical log-polar grid it looks alike at every angle, and the log-polar match read its turn wrong: 60 x 25
    px, 1 degree a frame, 23 of 39 degrees missed and the centre 15 px off; 60 x 40, lost on 26 of 39 frames and 26
    px off. Its turn is now held there (see _TURN_UNSEEN) and read by the gradient refinement."""
    rng = np.random.default_rng(0)
    frames, poses = [], []
    for k in range(40):
        frame = np.full((480, 640, 3), 60, np.uint8)
        cv2.ellipse(frame, (16 * (260 + 2 * k), 16 * 240), (16 * a, 16 * b), -spin * k, 0, 360, (200, 180, 160), -1,
                    cv2.LINE_AA, 4)  # cv2.ellipse's angle is clockwise on screen
        if noise:
            frame = np.clip(frame + rng.normal(0, noise, frame.shape), 0, 255).astype(np.uint8)
        frames.append(frame)
        poses.append(Pose(260.0 + 2 * k, 240.0, 1.0, spin * k))
    tracker, results = run(frames, Ellipse(260, 240, a, b, 0))
    assert not tracker._turn_seen
    assert all(ok for ok, _ in results)
    assert rotation_errors(results, poses[1:]).max() < 1.0
    assert centre_errors(results, poses[1:]).max() < 1.0


@pytest.mark.parametrize("noise, shade", [(4.0, 0.0), (8.0, 0.3)])
def test_a_ball_that_only_its_colour_tells_from_the_felt_is_followed(noise, shade):
    """A red ball on green felt, both about 85 in OpenCV's grey, rolling: its only grey structure is a white number
    that moves over it and goes round the back. Seen in grey it was followed with the number and lost (10 % of the
    frames within a quarter of its radius); the tracker now sees it through the colour direction that tells it
    from the felt (see _GREY_SEPARATION)."""
    rng = np.random.default_rng(0)
    radius, speed = 25, 5.0
    felt = np.clip(rng.normal(0, noise, (480, 640, 3)) + np.array([40, 120, 30]), 0, 255).astype(np.uint8)
    yy, xx = np.mgrid[:480, :640]
    frames, poses = [], []
    for k in range(80):
        x, y = 80 + speed * k, 240 + 60 * math.sin(k / 20)
        frame = felt.copy()
        cv2.circle(frame, (round(16 * x), round(16 * y)), 16 * radius, (20, 40, 200), -1, cv2.LINE_AA, 4)
        if shade:  # lit from the upper left
            inside = np.hypot(xx - x, yy - y) < radius
            light = 1 + shade * (0.5 - np.hypot(xx - x + 0.4 * radius, yy - y + 0.4 * radius) / (1.6 * radius))
            frame[inside] = np.clip(frame[inside] * light[inside][:, None], 0, 255).astype(np.uint8)
        turn = speed * k / radius  # radians the ball has rolled: the number goes round it
        if math.cos(turn) > 0:
            number = (round(16 * (x + 0.9 * radius * math.sin(turn))), round(16 * y))
            cv2.ellipse(frame, number, (max(1, round(16 * 8 * math.cos(turn))), 16 * 8), 0, 0, 360,
                        (235, 235, 235), -1, cv2.LINE_AA, 4)
        frames.append(frame)
        poses.append(Pose(x, y, 1.0, 0.0))
    tracker, results = run(frames, Ellipse.circle(poses[0].cx, poses[0].cy, radius))
    assert tracker.grey_matrix is not None
    assert np.mean(centre_errors(results, poses[1:]) < 0.25 * radius) >= 0.95


def test_a_textured_object_learns_from_its_whole_patch():
    roi = Ellipse.circle(320, 240, 40)
    frames = list(synthetic_sequence([Pose(320, 240, 1.0, 0.0)] * 2, roi, seed=1))
    tracker, _ = run(frames, roi)
    assert tracker.train_mask is None


def test_prediction_gives_way_under_camera_jitter():
    """The whole view shifted by an independent +-25 px each frame (a shaking camera, frames dropped): the last
    frame's motion then predicts the next one wrong, and predicting with it doubled the miss (41, 84, 95 and 84 % of
    the frames tracked, seeds 0-3). Predicting only as much as predicting has been helping: 99, 99, 95 and 94 %."""
    width, height, radius = 640, 480, 40.0
    for seed in range(4):
        rng = np.random.default_rng(seed)
        background = random_texture(height + 54, width + 54, rng)
        # An array, not a scalar, as addWeighted's second input: OpenCV 5.1 cannot convert the scalar 0 to a
        # 3-channel uint8 image (getConvertFunc assertion).
        texture = random_texture(99, 99, rng)
        texture = cv2.addWeighted(texture, 0.8, np.full_like(texture, 40), 1.0, 0)
        roi = Ellipse.circle(320, 240, radius)
        x, y, heading = 320.0, 240.0, rng.uniform(0, 2 * math.pi)
        poses, frames = [], []
        for i in range(80):
            sx, sy = (0, 0) if i == 0 else (int(v) for v in rng.integers(-25, 26, 2))
            poses.append(Pose(x + sx, y + sy, 1.0, 0.5 * i))
            view = background[27 - sy:27 - sy + height, 27 - sx:27 - sx + width]
            frames.append(render_frame(view, texture, roi, poses[-1]))
            heading += rng.normal(0, 0.08)
            x, y = x + 3 * math.cos(heading), y + 3 * math.sin(heading)
        _, results = run(frames, roi)
        assert np.mean(centre_errors(results, poses[1:]) < 0.25 * radius) >= 0.9


def test_motion_after_the_whole_frame_search_is_the_mean_motion_since_lost():
    """Where the search finds the object again, the velocity it predicts the next frame with is the mean motion
    from the last good place to the place found, over the frames since (damped as every velocity is; measured
    4.4-6.7 px a frame against the object's 7), not the jump to the place found counted as one frame's motion
    (29.5-29.9 px a frame, capped)."""
    for seed in (0, 3):
        roi, poses, frames = _leaves_and_comes_back_from_below(seed)
        tracker = create_tracker(DEFAULT_TRACKER)
        tracker.init(frames[0], roi)
        searching, found = False, None
        for k, frame in enumerate(frames[1:], start=1):
            last_good, gap = tracker._last_good, tracker.misses + 1
            tracker.update(frame)
            if searching and tracker.misses == 0:
                found = k
                break
            searching = tracker.misses >= tracker.redetect_after
        assert found is not None
        jump = np.array([tracker.cursor.cx - last_good.cx, tracker.cursor.cy - last_good.cy])
        assert gap > 10 and np.hypot(*jump) > 100
        np.testing.assert_allclose(tracker.velocity, tracker.velocity_damping * jump / gap, atol=1e-9)
        true_speed = math.hypot(poses[found].cx - poses[found - 1].cx, poses[found].cy - poses[found - 1].cy)
        assert 0.5 * true_speed <= np.hypot(*tracker.velocity) <= 1.5 * true_speed


def test_thin_patches_have_a_sidelobe():
    """A thin object's patch (10 samples across) still gives a peak-to-sidelobe ratio: it was NaN, so such an
    object was never learnt and never found again by the search."""
    from logpolar_track.trackers.lpcf import _peak_and_psr

    rng = np.random.default_rng(0)
    response = 0.05 * rng.random((10, 64))
    response[4, 30] = 1.0
    dy, dx, peak, psr = _peak_and_psr(response)
    assert (round(dy), round(dx), peak) == (4, 30, 1.0)
    assert math.isfinite(psr) and psr > 20


def _is_fast_dft_size(n: int) -> bool:
    for factor in (2, 3, 5):
        while n % factor == 0:
            n //= factor
    return n == 1


@pytest.mark.parametrize("b", [8, 11, 17, 19, 23, 29, 31, 37, 41, 47, 53, 59, 60])
def test_patch_sides_are_fast_dft_sizes_near_the_padded_extent(b):
    """Both patch sides are even products of 2, 3 and 5 (OpenCV's DFT took 2-3 times as long on 38 or 58
    samples as on 40 or 60), and the nearest such size to the padded object's extent: between consecutive such
    sizes up to 80 the gap is at most 8, so at most 4 samples off. The margin is the same on every side, padding
    times the mean radius sqrt(a b), except for an ellipse thinner than 1 to 4 (b 8 and 11), whose margin is
    padding times each semi-axis."""
    frame = random_texture(240, 320, np.random.default_rng(0))
    roi = Ellipse(160.0, 120.0, 60.0, float(b), 0.0)
    tracker = create_tracker("lpcf")
    tracker.init(frame, roi)
    margins = (60.0, float(b)) if b < 15 else (math.sqrt(60.0 * b),) * 2
    wanted = [(2 * half + 2 * tracker.padding * margin) / tracker.step for half, margin in zip((60.0, b), margins)]
    for side, extent in zip(tracker.size, wanted):
        assert side % 2 == 0 and _is_fast_dft_size(side), (side, extent)
        assert abs(side - extent) <= 4, (side, extent)


@pytest.mark.parametrize("seed", [1, 7])
@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 45.0, 90.0])
def test_a_thin_ellipse_keeps_its_angle(seed, angle_deg):
    """An 80 x 12 px textured ellipse (aspect 0.15) drifting 3 px and turning 0.5 degrees a frame keeps its angle
    within 3 degrees (median) and its centre within a quarter of its mean radius (3.9 px). Measured: every frame,
    0.2-1.3 degrees, at every tilt. Before its log-polar match was weighted to its outline (it covers 6 % of the
    circle it is matched on), the background led the match: tilted 45 and 90 degrees, 36-83 % of the frames. Before
    that, upright, on its own thin log-polar grid a small turn was a shear and the angle ran off (68 % and 10 % of
    the frames, 10 and 34 degrees); tilted, its search patch was its upright bounding box, mostly background (2 %
    and 12 %, 30 and 18 degrees)."""
    rng = np.random.default_rng(seed)
    roi = Ellipse(320, 240, 40, 6, angle_deg)
    x, y, heading = 320.0, 240.0, rng.uniform(0, 2 * math.pi)
    poses = []
    for k in range(60):
        poses.append(Pose(x, y, 1.0, 0.5 * k))
        heading += rng.normal(0, 0.08)
        x, y = x + 3 * math.cos(heading), y + 3 * math.sin(heading)
    frames = list(synthetic_sequence(poses, roi, seed=seed))
    _, results = run(frames, roi)
    within = np.mean(centre_errors(results, poses[1:]) < 0.25 * math.sqrt(roi.a * roi.b))
    assert within >= 0.95
    assert np.median(rotation_errors(results, poses[1:])) <= 3.0


def _swirling(seed, frames_total=60, turn_deg=3.0):
    """An ellipse (semi-axes 50 and 32 px, tilted 20 degrees) drifting 1 px a frame without turning, whose central
    disc (radius 18 px, other texture) turns ``turn_deg`` a frame inside it: a part of the object changing, as a
    face or a walker does, which the log-polar match, over all of the object and its outline, may read as a turn."""
    rng = np.random.default_rng(seed)
    background = random_texture(480, 640, rng)
    roi = Ellipse(320, 240, 50, 32, 20)
    size = 123
    outer, core = (cv2.addWeighted(random_texture(size, size, rng), 0.8, np.full((size, size, 3), 40, np.uint8), 1.0, 0)
                   for _ in range(2))
    yy, xx = np.mgrid[:size, :size] - (size - 1) / 2
    disc = (np.hypot(xx, yy) < 18)[..., None]
    poses, frames = [], []
    for i in range(frames_total):
        turn = cv2.getRotationMatrix2D(((size - 1) / 2, (size - 1) / 2), turn_deg * i, 1.0)
        texture = np.where(disc, cv2.warpAffine(core, turn, (size, size), borderMode=cv2.BORDER_REFLECT), outer)
        poses.append(Pose(320 + 1.0 * i, 240 + 0.3 * i, 1.0, 0.0))
        frame = render_frame(background, texture, roi, poses[-1]).astype(np.float32)
        frames.append(np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8))
    return roi, poses, frames


def test_a_turn_the_filter_does_not_see_is_undone():
    """Where the log-polar match is weak, a change of scale or angle that leaves the filter's response less sharp
    is undone. Here only the object's middle turns: without the rule the estimate turned with it, ending more than
    20 degrees off in 5 of these 8 seeds (up to 176 degrees) and lost in 3; with it, none (1 of 8 when only changes
    read by matches under 0.5 were judged; measured)."""
    off = 0
    for seed in range(8):
        roi, poses, frames = _swirling(seed)
        _, results = run(frames, roi)
        off += abs(results[-1][1].rotation_deg) > 20.0
    assert off <= 2


def _retextured(seed, frames_total=70):
    """A reddish disc of radius 25 px over a blue-green background, drifting 2 px a frame and swaying; over frames
    20-30 its texture turns into an unrelated one (an appearance change the filter does not know)."""
    rng = np.random.default_rng(seed)
    background = random_texture(240, 320, rng, colour=False).astype(np.float32)
    background = np.clip(background[..., None] * np.array([1.1, 1.0, 0.5]), 0, 255).astype(np.uint8)
    before, after = (random_texture(81, 81, rng, colour=False).astype(np.float32) for _ in range(2))
    roi = Ellipse.circle(100, 120, 25)
    poses, frames = [], []
    for i in range(frames_total):
        share = min(max((i - 20) / 10.0, 0.0), 1.0)
        texture = ((1 - share) * before + share * after)[..., None] * np.array([0.3, 0.45, 1.4])
        poses.append(Pose(100 + 2.0 * i, 120 + 20 * math.sin(i / 12), 1.0, 0.0))
        frames.append(render_frame(background, np.clip(texture, 0, 255).astype(np.uint8), roi, poses[-1]))
    return roi, poses, frames


def test_colour_keeps_the_estimate_on_an_object_whose_texture_changes():
    """Colour does not change where the texture does: with the colour response the tracker's own estimate (its
    cursor: frames after the change are reported lost, as the filter does not recognise the object) stays on the
    object on 78-84 % of the frames of seeds 1 and 9 (within 6 px), against 45-55 % without (measured with OpenCV
    4.10 and 5.1). Seed 2's disc is told from its background by colour so clearly that the tracker sees it through
    that colour direction (see _GREY_SEPARATION), and is then followed with or without the colour response (100 %
    both). Seed 3, tested before, followed the disc on 90 % of the frames without colour and 99-100 % with: it
    passed by 0.002 with OpenCV 5.1 and failed with 4.10, a margin that says nothing either way."""
    for seed in (1, 2, 9):
        roi, poses, frames = _retextured(seed)
        near, through_colour = {}, {}
        for weight in (0.0, 0.3):
            tracker = create_tracker("lpcf", colour_weight=weight)
            tracker.init(frames[0], roi)
            through_colour[weight] = tracker.grey_matrix is not None
            errors = []
            for frame, pose in zip(frames[1:], poses[1:]):
                tracker.update(frame)
                errors.append(math.hypot(tracker.cursor.cx - pose.cx, tracker.cursor.cy - pose.cy))
            near[weight] = np.mean(np.array(errors) < 6.0)
        assert through_colour[0.0] == through_colour[0.3] == (seed == 2)
        if seed == 2:
            assert min(near.values()) >= 0.95, (seed, near)
        else:
            assert near[0.3] >= 0.75 and near[0.3] >= near[0.0] + 0.1, (seed, near)


def _changing_as_it_travels(seed, speed_px, frames_total=90, fade_frames=45, turn_deg=0.0, zoom=0.0, axes=(30, 30)):
    """A disc of radius 30 px (size 60 px; or an ellipse of semi-axes ``axes``) moving ``speed_px`` a frame across a
    640 x 360 frame and back, swaying 40 px, turning ``turn_deg`` a frame and zooming by up to ``zoom`` (natural log)
    either way over 38 frames; over its first ``fade_frames`` frames (None: never) its texture fades into an unrelated
    one (an object that changes along its path, such as one turning out of plane, filmed at a low frame rate)."""
    rng = np.random.default_rng(seed)
    background = random_texture(360, 640, rng)
    side = int(2 * max(axes) * 1.2) + 3
    before, after = (cv2.addWeighted(random_texture(side, side, rng), 0.8, np.full((side, side, 3), 40, np.uint8), 1.0,
                                     0) for _ in range(2))
    roi = Ellipse.circle(100, 180, axes[0]) if axes[0] == axes[1] else Ellipse(100, 180, *axes, 0.0)
    x, step, poses, frames = 100.0, speed_px, [], []
    for i in range(frames_total):
        share = min(i / fade_frames, 1.0) if fade_frames else 0.0
        poses.append(Pose(x, 180 + 40 * math.sin(i / 7), math.exp(zoom * math.sin(i / 6)), turn_deg * i))
        frame = render_frame(background, cv2.addWeighted(before, 1 - share, after, share, 0), roi, poses[-1])
        frames.append(np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8))
        x += step
        if not 60 < x < 580:
            step = -step
            x += 2 * step
    return roi, poses, frames


@pytest.mark.parametrize("seed", [2, 4])
def test_a_fast_object_changing_along_its_path_is_learnt_by_distance(seed):
    """Learning by distance travelled (see _DISTANCE_LEARNING_SPEED): at 14 px a frame (0.23 of its size) the disc
    is within a quarter radius and reported tracked on 89 of 89 frames (seeds 2 and 4; 47 and 43 when the models
    learnt at the same rate a frame whatever the speed: they fell behind the change and lost it)."""
    roi, poses, frames = _changing_as_it_travels(seed, 14.0)
    _, results = run(frames, roi)
    near = (centre_errors(results, poses[1:]) < 7.5) & np.array([ok for ok, _ in results])
    assert near.mean() >= 0.95, near.mean()


@pytest.mark.parametrize("seed", [0, 5])
def test_a_fast_object_turning_fast_is_followed(seed):
    """The motion prior by distance travelled (see _PRIOR_BY_SPEED): a textured 40 x 25 px ellipse moving 20 px a
    frame (0.32 of its size) and turning 12 degrees a frame, as an object filmed at a low frame rate does, is within
    a quarter of its minor semi-axis and reported tracked on every frame. With the prior set for the full frame rate
    (and the mean speed built up from 0) the turn was held back and seed 5 lost from its 11th frame on (the other
    11 of seeds 0-11 followed either way)."""
    roi, poses, frames = _changing_as_it_travels(seed, 20.0, frames_total=60, fade_frames=None, turn_deg=12.0,
                                                 axes=(40, 25))
    _, results = run(frames, roi)
    assert all(ok for ok, _ in results)
    assert centre_errors(results, poses[1:]).max() < 6.25


def test_the_motion_prior_widens_by_the_learning_factor():
    """The log-polar match's motion prior is ``lp_prior`` for a slow object and, for a fast one, the same Gaussian
    with both widths (``scale_sigma``, ``rotation_sigma``) multiplied by learning's factor by distance travelled
    (see _PRIOR_BY_SPEED), to float32 precision."""
    from logpolar_track.trackers.lpcf import _DISTANCE_LEARNING_SPEED, _signed_bins
    tracker = create_tracker("lpcf")
    tracker.init(random_texture(240, 320, np.random.default_rng(0)), Ellipse.circle(160, 120, 30))
    assert tracker._motion_prior() is tracker.lp_prior
    tracker._mean_speed = 2.5 * _DISTANCE_LEARNING_SPEED  # learning counts 2.5 frames a step: the widths 2.5 times
    d_log_scale = _signed_bins(tracker.n_rho)[:, None] * tracker.grid.log_step
    d_angle = _signed_bins(tracker.n_theta)[None, :] * tracker.grid.degrees_per_bin
    wide = np.exp(-0.5 * ((d_log_scale / (2.5 * tracker.scale_sigma)) ** 2
                          + (d_angle / (2.5 * tracker.rotation_sigma)) ** 2))
    assert np.allclose(tracker._motion_prior(), wide, rtol=1e-5, atol=1e-5)


def test_a_fast_object_that_does_not_turn_keeps_its_angle_and_size():
    """The wider prior of a fast object (see _PRIOR_BY_SPEED; here 2.7 times) does not let its estimate wander: a
    textured 40 x 25 px ellipse moving 20 px a frame without turning or zooming is reported within 1 degree of its
    angle and 2 % of its size on every frame (measured: 0.37 degrees, 1.5 %; seeds 0-3)."""
    roi, poses, frames = _changing_as_it_travels(1, 20.0, frames_total=60, fade_frames=None, axes=(40, 25))
    tracker, results = run(frames, roi)
    assert tracker._motion_prior() is not tracker.lp_prior  # the wider prior was in use
    assert all(ok for ok, _ in results)
    assert max(abs(state.rotation_deg) for _, state in results) < 1.0
    assert max(abs(math.log(state.scale)) for _, state in results) < 0.02


def test_learning_counts_distance_from_a_speed_on():
    """A learning step makes up for more frames only for an object moving faster than _DISTANCE_LEARNING_SPEED of its
    size a frame, in proportion to its speed, and at most _DISTANCE_LEARNING_MAX times."""
    from logpolar_track.trackers.lpcf import (_DISTANCE_LEARNING_MAX, _DISTANCE_LEARNING_SPEED,
                                              learning_frames_for_speed)
    assert learning_frames_for_speed(0.0) == learning_frames_for_speed(_DISTANCE_LEARNING_SPEED) == 1.0
    assert learning_frames_for_speed(2 * _DISTANCE_LEARNING_SPEED) == pytest.approx(2.0)
    assert learning_frames_for_speed(100.0) == _DISTANCE_LEARNING_MAX
    # Measured on a track: for a disc moving 14 px a frame, 0.23 of its 60 px size, a learning step counts twice.
    roi, poses, frames = _changing_as_it_travels(4, 14.0, frames_total=20)
    tracker, _ = run(frames, roi)
    assert tracker._learning_frames() == pytest.approx(
        tracker.learn_every * 14.0 / 60.0 / _DISTANCE_LEARNING_SPEED, rel=0.1)


def test_grey_frames_with_a_channel_axis_track_as_grey():
    """(H, W, 1) frames (cv2.imread(..., IMREAD_UNCHANGED) of a grey PNG) give the same track as (H, W) ones,
    also where the patches reach out of the frame, whose mean grey fills them (it was read as a BGR mean, a
    ninth of the grey, and the track came back 191 px apart)."""
    roi, poses, frames = _leaves_and_returns(1)
    grey = [cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) for frame in frames]
    _, flat = run(grey, roi)
    _, with_axis = run([frame[:, :, None] for frame in grey], roi)
    assert [ok for ok, _ in flat] == [ok for ok, _ in with_axis]
    assert max(np.hypot(a.ellipse.cx - b.ellipse.cx, a.ellipse.cy - b.ellipse.cy)
               for (_, a), (_, b) in zip(flat, with_axis)) < 1e-6


def test_accuracy_on_a_gentle_similarity_path():
    """The default tracker on a generated sequence: 120 frames of 640x480, circle of radius 50, the centre
    circling 60 px, scale 0.8-1.25, half a turn. Bounds: the issue's targets for scale (1.5 %) and, with
    margin, rotation (measured: median scale error 0.65 %, rotation 0.20 degrees, centre 0.56 px). The motion
    prior that keeps real sequences from drifting would lag this steady zoom (3.9 %, 1.0 degree) if the
    near-perfect log-polar matches of a rigid texture were not read without it (``trust_low``)."""
    roi = Ellipse.circle(320, 240, 50)
    poses = similarity_path(120, (320, 240), scale_range=(0.8, 1.25), turns=0.5, radius_px=60)
    frames = list(synthetic_sequence(poses, roi, seed=3))
    _, results = run(frames, roi)
    truth = poses[1:]
    errors = centre_errors(results, truth)
    assert all(ok for ok, _ in results)
    assert np.mean(errors < 0.25 * roi.radius * np.array([p.scale for p in truth])) >= 0.98
    assert np.median(errors) <= 1.0
    assert np.median(scale_errors(results, truth)) <= 0.015
    assert np.median(rotation_errors(results, truth)) <= 0.5


def test_a_rigid_object_is_reported_at_the_trackers_own_scale():
    """Where the gradient refinement is believed (a rigid object) the size reported is the tracker's own, so the
    scale filter changes nothing there: the gentle similarity path gives the same states with and without it."""
    roi = Ellipse.circle(320, 240, 50)
    poses = similarity_path(60, (320, 240), scale_range=(0.8, 1.25), turns=0.5, radius_px=60)
    frames = list(synthetic_sequence(poses, roi, seed=3))
    with_filter, without = (run(frames, roi, scale_filter=on)[1] for on in (True, False))
    assert with_filter == without


def _zoom(rate: float, frames_total: int = 50) -> list[Pose]:
    return [Pose(320.0 + 1.5 * i, 240.0 + 0.5 * i, (1 + rate) ** i, 1.0 * i) for i in range(frames_total)]


@pytest.mark.parametrize("rate", [0.01, -0.01])
def test_where_the_refinement_is_not_believed_the_scale_filter_gives_the_size(rate):
    """With the refinement never believed (``refine_max_distance`` 0), the size reported is the scale filter's:
    on a rigid disc zooming 1 % a frame it follows the zoom with the lag the filter's partial reading leaves
    (measured over 4 seeds: median error 2.2-6.7 %, at most 10.3 %), while the tracker's own estimate -- which
    the filter never feeds -- is exactly what it is without the filter. Without colour: on colour video the
    colour's extent pulls both sizes towards it where the filter's size is reported (see _EXTENT_GAIN)."""
    roi = Ellipse.circle(320, 240, 40)
    poses = _zoom(rate)
    for seed in range(4):
        frames = list(synthetic_sequence(poses, roi, size=(640, 480), seed=seed))
        tracked = {}
        for on in (True, False):
            tracker = create_tracker("lpcf", refine_max_distance=0.0, scale_filter=on, colour_weight=0.0)
            tracker.init(frames[0], roi)
            tracked[on] = [(tracker.update(f), tracker.cursor) for f in frames[1:]]
        results = [result for result, _ in tracked[True]]
        assert all(ok for ok, _ in results)
        errors = scale_errors(results, poses[1:])
        assert np.median(errors) <= 0.08 and errors.max() <= 0.12, (seed, np.median(errors), errors.max())
        own = np.array([cursor.scale for _, cursor in tracked[True]])
        assert [cursor for _, cursor in tracked[True]] == [cursor for _, cursor in tracked[False]]
        assert np.median(np.abs(np.log([s.scale for _, s in results] / own))) > 0.01  # the filter's, not its own


def test_gradient_refinement_sharpens_a_rigid_object():
    """On the gentle similarity path, the refinement against the appearance subspace (on by default) finds
    centre and angle several times more precisely than the filter and log-polar match alone
    (``refine_steps=0``), and scale no less. Measured: median 0.05 px, 0.17 %, 0.02 degrees against 0.20 px,
    0.18 %, 0.11 degrees; largest 0.13 px, 0.08 degrees against 0.84 px, 0.42 degrees."""
    roi = Ellipse.circle(320, 240, 50)
    poses = similarity_path(120, (320, 240), scale_range=(0.8, 1.25), turns=0.5, radius_px=60)
    frames = list(synthetic_sequence(poses, roi, seed=3))
    truth = poses[1:]
    medians, distances = {}, []
    for steps in (2, 0):
        tracker = create_tracker("lpcf", refine_steps=steps)
        tracker.init(frames[0], roi)
        results = []
        for frame in frames[1:]:
            results.append(tracker.update(frame))
            distances.append(tracker.diagnostics["appearance_distance"])
        assert all(ok for ok, _ in results)
        medians[steps] = (np.median(centre_errors(results, truth)),
                          np.median(scale_errors(results, truth)), np.median(rotation_errors(results, truth)))
    refined, plain = medians[2], medians[0]
    assert refined[0] <= 0.1 and refined[1] <= 0.003 and refined[2] <= 0.05
    assert refined[0] < 0.5 * plain[0] and refined[2] < 0.5 * plain[2] and refined[1] <= 1.05 * plain[1]
    # Believed on every frame (the object is explained by its subspace); never tried without the refinement.
    assert max(distances[:len(results)]) < 0.3 and distances[len(results):] == [None] * len(results)


@pytest.mark.parametrize("roi", [Ellipse.circle(320, 240, 50), Ellipse(320, 240, 60, 40, 37.0)])
def test_gradient_refinement_reads_a_known_move_in_the_trackers_own_sampling(roi):
    """The refinement as the tracker runs it (its own patches and its own composition of the step): the frame
    moved by (1.5, -1) px, scaled by 3 % and turned 2.5 degrees counter-clockwise about the centre is read back
    within 0.05 px, 0.1 % and 0.05 degrees (measured: 0.02 px, 0.03 %, 0.03 degrees at most), in two calls."""
    rng = np.random.default_rng(21)
    frame = cv2.GaussianBlur(random_texture(480, 640, rng), (0, 0), 1.0)
    tracker = create_tracker("lpcf")
    tracker.init(frame, roi)
    m = cv2.getRotationMatrix2D((roi.cx, roi.cy), 2.5, 1.03)
    m[:, 2] += (1.5, -1.0)
    moved = cv2.warpAffine(frame, m, (640, 480), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    start = tracker.cursor
    state, distance = tracker._refine(moved, start)
    state, distance = tracker._refine(moved, state)
    assert math.hypot(state.cx - (roi.cx + 1.5), state.cy - (roi.cy - 1.0)) <= 0.05
    assert abs(state.scale / 1.03 - 1) <= 1e-3 and abs(state.rotation_deg - 2.5) <= 0.05
    assert distance < 0.1


def test_an_ellipse_is_tracked_alike_however_it_is_written():
    """One ellipse has four spellings (axis a either axis, each way round): a tall box's ellipse as the benchmark
    writes it (``cx,cy,w/2,h/2,0``) and as ``lptrack roi`` prints it (``a >= b``: ``cx,cy,h/2,w/2,90``) were
    tracked on grids turned by 90 degrees, equal up to rounding that a hard sequence amplified (crossing 0.775
    against 0.787). They are tracked alike now, each reported in its own spelling."""
    roi = Ellipse(160, 120, 15, 35, 10.0)
    poses = [Pose(160 + 1.5 * i, 120 - 0.5 * i, 1.0 + 0.004 * i, 0.7 * i) for i in range(25)]
    frames = list(synthetic_sequence(poses, roi, size=(320, 240), seed=3))
    spellings = [roi, Ellipse(160, 120, 35, 15, 100.0), Ellipse(160, 120, 35, 15, -80.0),
                 Ellipse(160, 120, 15, 35, 190.0)]
    tracks = []
    for spelling in spellings:
        _, results = run(frames, spelling)
        tracks.append([(s.centre, s.scale, s.rotation_deg, s.score, ok) for ok, s in results])
        last = results[-1][1].ellipse
        assert (last.a, last.b) == pytest.approx((spelling.a * results[-1][1].scale, spelling.b * results[-1][1].scale))
        assert last.angle_deg == pytest.approx(spelling.angle_deg + results[-1][1].rotation_deg)
    assert tracks[1] == tracks[0] and tracks[2] == tracks[0] and tracks[3] == tracks[0]


def test_no_gradient_refinement_on_a_sliver():
    """A 60 x 3 px ellipse is under a sample across: too little for the refinement's steps, which is left off."""
    frame = random_texture(240, 320, np.random.default_rng(2))
    tracker = create_tracker("lpcf")
    tracker.init(frame, Ellipse(160, 120, 60, 3, 20.0))
    assert tracker.appearance is None
    ok, _ = tracker.update(frame)
    assert ok and tracker.diagnostics["appearance_distance"] is None
    tracker.init(frame, Ellipse(160, 120, 60, 20, 20.0))
    assert tracker.appearance is not None


@pytest.mark.parametrize("end, seed", [(0.5, 0), (0.5, 1), (2.0, 0), (2.0, 1)])
def test_a_sliver_zooming_is_reported_at_its_own_size(end, seed):
    """A 100 x 15 px ellipse (no refinement: too thin) shrinking to half or growing to double over 120 frames,
    turning and drifting. Without the refinement to say the object is rigid, the size was the scale filter's, whose
    box of a sliver is mostly its surround: medians 17-29 % off, 0.82-0.84 at the end for 0.5. A log-polar match
    believed in full gives the tracker's own size instead (measured: medians 0.3-1.8 %)."""
    roi = Ellipse(320, 240, 100, 15, 20)
    poses = [Pose(320 + 0.3 * i, 240, end ** (i / 119), 0.2 * i) for i in range(120)]
    tracker, results = run(list(synthetic_sequence(poses, roi, seed=seed)), roi)
    assert tracker.appearance is None
    errors = scale_errors(results, poses[1:])
    assert all(ok for ok, _ in results) and np.median(errors) < 0.03 and errors[-1] < 0.05


def test_gradient_refinement_stands_aside_for_a_stranger():
    """Over a swapped object the patch is far from the subspace (so the refinement is not believed, and not
    tried again for the next four frames) and nothing of the stranger is learnt into it: the object is explained
    again when the refinement is next tried, two frames after it is back."""
    roi = Ellipse.circle(160, 120, 30)
    poses = [Pose(160 + 1.0 * i, 120 - 0.5 * i, 1.0, 1.0 * i) for i in range(30)]
    frames = _with_stranger(list(synthetic_sequence(poses, roi, size=(320, 240), seed=8)), poses, roi, 15, 3)
    tracker = create_tracker("lpcf")
    tracker.init(frames[0], roi)
    distances = []
    for frame in frames[1:]:
        tracker.update(frame)
        distances.append(tracker.diagnostics["appearance_distance"])
    assert max(distances[:14]) < 0.3  # frames 1-14
    assert distances[14] > 0.6  # the stranger, frames 15-17
    assert distances[15:19] == [None] * 4  # frames 16-19: not tried
    assert max(distances[19:]) < 0.3  # frames 20 on


@pytest.mark.parametrize("name", SAMPLE_NAMES)
def test_default_tracker_meets_the_issue_bounds_on_every_sample_video(name):
    """The best-tracker issue's targets on each bundled sample: tracked to the end with success >= 98 % (centre
    error < 25 % of the radius), median centre error <= 1 px, scale error <= 1.5 %, rotation error <= 1 degree.
    Tightest, measured (2026-12-06): appearance 0.58 px, 0.28 %, 0.86 degrees; lighting 0.76 px, 1.31 %, 0.74
    degrees, the same with OpenCV's and NumPy's AVX-512 and AVX2 paths turned off (before the gradient refinement
    both missed: 2.0 px, 3.3 % and 1.3 px)."""
    from pathlib import Path

    from logpolar_track.bench import collect_sequences, run_bench

    folder = Path(__file__).resolve().parents[1] / "sample_videos"
    # The samples are committed: one missing from the checkout is a failure, not a skip.
    assert all((folder / f"{name}{ext}").is_file() for ext in (".mp4", ".gt.csv", ".roi")), \
        f"sample_videos/{name} is missing from the checkout"
    sequences = [s for s in collect_sequences([folder]) if s.name == name]
    assert len(sequences) == 1, [s.name for s in sequences]
    [result] = run_bench(sequences, ["lpcf"])
    assert result["success_rate"] >= 0.98
    assert result["centre_error_median_px"] <= 1.0
    assert result["scale_error_median_pct"] <= 1.5
    assert result["rotation_error_median_deg"] <= 1.0


def _zoom_and_turn():
    """A disc of radius 50 px zooming (0.8-1.25) and turning half a turn over 120 frames."""
    roi = Ellipse.circle(320, 240, 50)
    poses = similarity_path(120, (320, 240), scale_range=(0.8, 1.25), turns=0.5, radius_px=60)
    return roi, poses, list(synthetic_sequence(poses, roi, seed=3))


def _counted(monkeypatch, method: str) -> list:
    """A list that grows by one at each call of ``LogPolarCorrelationTracker.<method>``."""
    import logpolar_track.trackers.lpcf as lpcf

    calls, original = [], getattr(lpcf.LogPolarCorrelationTracker, method)
    monkeypatch.setattr(lpcf.LogPolarCorrelationTracker, method,
                        lambda self, *args: calls.append(1) or original(self, *args))
    return calls


def _assert_tracks_within(results, others, px, relative_scale, degrees):
    for (_, a), (_, b) in zip(results, others, strict=True):
        assert math.hypot(a.centre[0] - b.centre[0], a.centre[1] - b.centre[1]) <= px
        assert abs(a.scale / b.scale - 1) <= relative_scale
        assert abs(a.rotation_deg - b.rotation_deg) <= degrees


def test_shortcuts_stay_close_to_the_straightforward_tracker(monkeypatch):
    """Two shortcuts save a third of a frame's time: the iterations stop once the estimates agree (no further
    correlation), and the learning step reuses the last correlated patch instead of sampling a fresh one. On a
    generated zoom-and-turn path the track stays within 0.5 px, 1 % and 0.5 degrees of the tracker without them
    (measured: 0.34 px, 0.73 %, 0.37 degrees at most; medians 0.14 px, 0.18 %, 0.06 degrees), and no further
    from the truth. They are shortcuts of the filter's iterations, which run where the gradient refinement is not
    believed; it is turned off here so that they run on every frame. So is the colour response, which these
    shortcuts do not touch (with it the shortcuts' track is 0.30 px from the truth, median, against 0.23)."""
    import logpolar_track.trackers.lpcf as lpcf

    roi, poses, frames = _zoom_and_turn()
    calls = _counted(monkeypatch, "_translate")
    _, shortcut = run(frames, roi, refine_steps=0, colour_weight=0.0)
    with_shortcuts, calls[:] = len(calls), []
    # Without them: every iteration runs, and every learning step samples its own patch.
    monkeypatch.setattr(lpcf, "_REUSE_OFF_CENTRE", -1.0)
    for name in ("_AGREED_LOG_SCALE", "_AGREED_DEGREES", "_AGREED_SAMPLES"):
        monkeypatch.setattr(lpcf, name, -1.0)
    _, straight = run(frames, roi, refine_steps=0, colour_weight=0.0)
    assert with_shortcuts < 0.8 * len(calls)  # the shortcuts do fire (measured: 245 against 357 patches)
    _assert_tracks_within(shortcut, straight, 0.5, 0.01, 0.5)
    truth = poses[1:]
    assert np.median(centre_errors(shortcut, truth)) <= 1.05 * np.median(centre_errors(straight, truth))


def test_learning_from_the_last_correlated_patch_stays_close_to_sampling_afresh(monkeypatch):
    """With the gradient refinement (the default) the last correlated patch comes before both log-polar matches,
    so its scale and angle may be up to a frame's change (2 % and 2 degrees) from the final estimate, and the
    learning step still learns from it. On a zoom-and-turn path (1.5 degrees and up to 0.4 % a frame) this saves
    every learning step's patch (measured: 120 patches against 179) and moves the track by at most 0.04 px, 0.08 %
    and 0.03 degrees (seed 3 here; seeds 4 and 5 alike), no further from the truth."""
    import logpolar_track.trackers.lpcf as lpcf

    roi, poses, frames = _zoom_and_turn()
    calls = _counted(monkeypatch, "_features_and_spectrum")
    _, reused = run(frames, roi)
    with_reuse, calls[:] = len(calls), []
    monkeypatch.setattr(lpcf, "_REUSE_OFF_CENTRE", -1.0)  # every learning step samples its own patch
    _, fresh = run(frames, roi)
    assert with_reuse <= len(calls) - 40
    _assert_tracks_within(reused, fresh, 0.2, 0.005, 0.2)
    truth = poses[1:]
    assert np.median(centre_errors(reused, truth)) <= np.median(centre_errors(fresh, truth)) + 0.02


def test_colour_frames_track_exactly_as_their_grey_conversion():
    """Only the sampled regions of a colour frame are converted to grey; without the colour response the track
    is the one of the frames converted whole. Grey video decoded as three equal channels is tracked on grey
    alone, colour response or not."""
    roi = Ellipse(160, 120, 36, 24, 20)
    poses = similarity_path(20, (160, 120), scale_range=(0.9, 1.1), turns=0.1, radius_px=20)
    grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in synthetic_sequence(poses, roi, size=(320, 240), seed=11)]
    rng = np.random.default_rng(2)
    colour = [cv2.merge([g, cv2.add(g, 30), (rng.random(g.shape) * 255).astype(np.uint8)]) for g in grey]
    _, from_colour = run(colour, roi, colour_weight=0.0)
    _, from_grey = run([cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in colour], roi)
    assert [s for _, s in from_colour] == [s for _, s in from_grey]
    _, from_colour = run(colour, roi)
    assert [s for _, s in from_colour] != [s for _, s in from_grey]  # the colour response is on by default
    _, from_three_greys = run([cv2.merge([g, g, g]) for g in grey], roi)
    _, from_grey = run(grey, roi)
    assert [s for _, s in from_three_greys] == [s for _, s in from_grey]


@pytest.mark.parametrize("scale, angle_deg", [(0.9, 0.0), (1.0, 30.0), (1.3, -60.0), (2.0, 10.0), (4.0, 100.0)])
def test_shrinking_patches_sample_like_a_full_size_blur(scale, angle_deg):
    """A patch whose samples are more than 1.5 px apart is cut from a crop reduced by ``cv2.pyrDown`` and blurred
    for the rest; its samples match those of the whole frame blurred by half the sample spacing at full size
    (RMS difference measured up to 3.9 % of the samples' spread at scales 0.75 to 5; bound 4.5 %)."""
    from logpolar_track.trackers.base import Similarity

    roi = Ellipse.circle(640, 480, 50)
    # A large frame, so that even the largest patch stays inside it (the two blurs differ at the frame's edge).
    frame = next(iter(synthetic_sequence([Pose(640, 480, 1.0, 0.0)], roi, size=(1280, 960), seed=5)))
    tracker = create_tracker(DEFAULT_TRACKER)
    tracker.init(frame, roi)
    state = Similarity(642.3, 478.6, scale, angle_deg, 1.0)
    tracker._blur_scale = scale
    patch = tracker._patch(frame, state)

    k = tracker.step * scale  # pixels between samples
    assert k > 1.5
    nx, ny = tracker.size
    t = math.radians(angle_deg)
    c, s = k * math.cos(t), k * math.sin(t)
    sample_to_pixel = np.array([[c, s, state.cx - c * nx / 2 - s * ny / 2],
                                [-s, c, state.cy + s * nx / 2 - c * ny / 2]])
    blurred = cv2.GaussianBlur(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32), (0, 0), k / 2)
    expected = cv2.warpAffine(blurred, sample_to_pixel, (nx, ny), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
    rms = float(np.sqrt(np.mean((patch - expected) ** 2)))
    assert rms <= 0.045 * float(expected.std())


@pytest.mark.parametrize("params, fragment", [
    ({"padding": -1}, "padding must be at least 0 and at most 10, got -1"),
    ({"learning_rate": 2}, "learning_rate must be above 0 and at most 1, got 2"),
    ({"scale_sigma": 0}, "scale_sigma must be above 0 and at most 10, got 0"),
    ({"iterations": 0}, "iterations must be at least 1 and at most 20, got 0"),
    # Bounded above too: 1e308 overflowed the float32 spectra and every frame was lost, with NumPy's warning.
    ({"regularisation": 1e308}, "regularisation must be above 0 and at most 1e+06, got 1e+308"),
    ({"iterations": 10 ** 9}, "iterations must be at least 1 and at most 20, got 1000000000"),
    ({"trust_low": 0.9, "trust_high": 0.9}, "trust_low must be below trust_high"),
    ({"scale_filter_rate": 0}, "scale_filter_rate must be above 0 and at most 1, got 0"),
])
def test_parameters_out_of_range_are_refused_with_the_range(params, fragment):
    with pytest.raises(UsageError, match=re.escape(fragment)):
        create_tracker("lpcf", **params)


def test_a_roi_on_a_flat_area_is_lost_not_a_crash():
    """A ROI on the black bar of a letterboxed video: object and surround are one colour, and the colour map's
    direction was 0/0, whose NaN reached the features' bin index (IndexError) after a few frames."""
    import warnings

    frame = np.zeros((480, 640, 3), np.uint8)
    frame[:, 320:] = np.random.default_rng(0).integers(0, 255, (480, 320, 3))
    tracker = create_tracker("lpcf")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no NaN on the way either
        tracker.init(frame, Ellipse.circle(100, 240, 40))
        results = [tracker.update(frame) for _ in range(40)]
    assert not any(ok for ok, _ in results)
    assert all(state.centre == (100.0, 240.0) and state.score == 0.0 for _, state in results)


def test_the_running_level_starts_from_the_tracked_frames_matches():
    """The level a drop is judged against is the mean of the matches tracked so far over the first frames, not
    pulled up by the first frame's perfect match with itself (which left a deforming object dropped on its 4th
    frame at a third of its frame rate, and never resumed)."""
    roi = Ellipse.circle(160, 120, 40)
    poses = [Pose(160 + 2 * k, 120, 1.0, 0.0) for k in range(8)]
    rng = np.random.default_rng(7)
    # Noise, so that matches are well below 1.
    frames = [np.clip(f + rng.normal(0, 25, f.shape), 0, 255).astype(np.uint8)
              for f in synthetic_sequence(poses, roi, size=(320, 240), seed=5)]
    tracker = create_tracker("lpcf")
    tracker.init(frames[0], roi)
    matches = []
    for frame in frames[1:]:
        ok, _ = tracker.update(frame)
        assert ok
        matches.append(tracker.diagnostics["match"])
    assert max(matches) < 0.9
    assert tracker.match_level == pytest.approx(np.mean(matches), rel=1e-6)


@pytest.mark.parametrize("grown", [0.8, 1.0, 1.25])
def test_the_colour_extent_reads_a_coloured_objects_size_change(grown):
    """The size cue of ``_EXTENT_GAIN``: the colour likelihood's region about the patch's centre measures the object
    whatever the tracker's own scale says. A textured red disc on a textured green ground, grown by ``grown``, read
    at the first frame's pose (scale 1): the cue's log size changes by log(grown) within 0.06 (a twentieth of a
    size change of 25 %); on grey video there is no cue."""
    rng = np.random.default_rng(5)
    ground = np.dstack([rng.integers(0, 60, (480, 640)), rng.integers(120, 200, (480, 640)),
                        rng.integers(0, 60, (480, 640))]).astype(np.uint8)

    def scene(radius: float) -> np.ndarray:
        frame = ground.copy()
        disc = np.zeros((480, 640), np.uint8)
        cv2.circle(disc, (320, 240), int(round(radius)), 1, -1)
        red = np.dstack([rng.integers(0, 50, (480, 640)), rng.integers(0, 50, (480, 640)),
                         rng.integers(150, 255, (480, 640))]).astype(np.uint8)
        frame[disc > 0] = red[disc > 0]
        return frame

    tracker = create_tracker("lpcf")
    first = scene(40)
    tracker.init(first, Ellipse.circle(320, 240, 40))
    at_first_pose = Similarity(320.0, 240.0, 1.0, 0.0, 1.0)
    before = tracker._colour_extent(first, at_first_pose)
    after = tracker._colour_extent(scene(40 * grown), at_first_pose)
    assert before is not None and after is not None
    assert abs((after - before) - math.log(grown)) < 0.06
    grey = create_tracker("lpcf")
    grey.init(cv2.cvtColor(first, cv2.COLOR_BGR2GRAY), Ellipse.circle(320, 240, 40))
    assert grey.colour is None  # the cue is read only where the colour model is


def test_the_re_detection_leaves_the_patch_of_the_estimate_it_returns():
    """The long-term check and learning read the patch last correlated (``_last_sample``) as the one the estimate was
    found on. The re-detection correlates candidates elsewhere; where it keeps the estimate it was given (here the
    object's own place), its patch must be that estimate's, not the last candidate's (a place 90 px away)."""
    roi = Ellipse(320.0, 240.0, 40.0, 30.0, 0.0)
    poses = [Pose(320.0, 240.0, 1.0, 0.0), Pose(330.0, 236.0, 1.0, 0.0)]
    for seed in range(4):
        frames = list(synthetic_sequence(poses, roi, size=(640, 480), seed=seed))
        tracker = create_tracker("lpcf")
        tracker.init(frames[0], roi)
        frame = tracker._prepared(frames[1])
        tracker.misses = tracker.redetect_after
        start = Similarity(330.0, 236.0, 1.0, 0.0, 1.0)
        moved, psr, peak = tracker._translate(frame, start)
        result = tracker._redetect(frame, start, moved, psr, peak)
        again = tracker._translate(frame, tracker._last_sample[0])[0]
        assert (again.cx, again.cy) == (result[0].cx, result[0].cy)
