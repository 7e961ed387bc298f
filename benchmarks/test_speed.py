"""Speed benchmarks (pytest-benchmark), outside tests/ so the default `pytest` run does not collect them.

Run: ``pytest benchmarks/ --benchmark-only`` (one core: cv2.setNumThreads(1); NumPy's FFT is single-threaded).
640x480 synthetic video, object radius 50 px (ellipse 60 x 40), 11x11 window, as the thesis' Table 4.1.
"""

import cv2
import pytest

from logpolar_track.speed import SHAPES, THESIS_SECONDS, _frames, time_video_baselines
from logpolar_track.trackers import create_tracker, tracker_names

N_FRAMES = 40
TRACKERS = sorted(set(THESIS_SECONDS) | {n for n in tracker_names() if not n.startswith("cv-")})


@pytest.fixture(scope="module", autouse=True)
def one_core():
    previous = cv2.getNumThreads()
    cv2.setNumThreads(1)
    yield
    cv2.setNumThreads(previous)


@pytest.fixture(scope="module")
def frames():
    return {shape: _frames(roi, N_FRAMES) for shape, roi in SHAPES.items()}


@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("name", TRACKERS)
def test_tracker_update(benchmark, frames, name, shape):
    """One pass of update() over the sequence; stats are per pass of N_FRAMES - 1 frames."""
    roi, seq = SHAPES[shape], frames[shape]

    def setup():
        tracker = create_tracker(name)
        tracker.init(seq[0], roi)
        return (tracker,), {}

    def run(tracker):
        for f in seq[1:]:
            tracker.update(f)

    benchmark.extra_info["frames_per_round"] = len(seq) - 1
    benchmark.pedantic(run, setup=setup, rounds=3)


def test_decode_and_encode_baselines(benchmark, frames):
    decode, both = benchmark.pedantic(time_video_baselines, args=(frames["circle"],), rounds=1)
    benchmark.extra_info.update(decode_ms_per_frame=decode * 1e3, decode_encode_ms_per_frame=both * 1e3)
