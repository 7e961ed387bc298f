"""VideoReader and VideoWriter: what they deliver, how they fail, and that nothing half-written is left."""

from __future__ import annotations

import gc
import os
import re
import shutil
import sys
import signal
import threading
import time
import weakref
from pathlib import Path

import cv2
import numpy as np
import pytest

from conftest import count_frames, damage_middle, decode_all, write_video
from logpolar_track import video as video_module
from logpolar_track.errors import OutputError, UsageError, VideoError
from logpolar_track.outputs import temporary_path
from logpolar_track.video import FALLBACK_FPS, VideoReader, VideoWriter


@pytest.mark.parametrize("name", ["clip.mp4", "clip.avi"])
def test_reader_yields_every_frame_with_index_and_time(make_video, tmp_path, name):
    clip = make_video(tmp_path, name, fps=29.97)
    expected = decode_all(clip.path)
    with VideoReader(clip.path) as reader:
        assert (reader.width, reader.height) == clip.size
        assert reader.fps == pytest.approx(29.97, abs=0.01)  # a float, not truncated to 29
        assert not reader.fps_guessed
        items = list(reader)
    assert [i for i, _, _ in items] == list(range(clip.n_frames))
    assert len(expected) == clip.n_frames
    for (i, t, frame), ref in zip(items, expected):
        assert t == pytest.approx(i / reader.fps)
        assert np.array_equal(frame, ref)


def test_start_frame_skips_exactly(tiny_video):
    expected = decode_all(tiny_video.path)
    with VideoReader(tiny_video.path, start_frame=7) as reader:
        items = list(reader)
    assert [i for i, _, _ in items] == list(range(7, tiny_video.n_frames))
    assert items[0][1] == pytest.approx(7 / tiny_video.fps)
    assert all(np.array_equal(f, expected[i]) for i, _, f in items)


def test_start_frame_past_end_says_how_many_frames(tiny_video):
    with pytest.raises(VideoError, match=r"past the end .* has 20 frames"):
        VideoReader(tiny_video.path, start_frame=20)
    with pytest.raises(VideoError, match=r"which has 20 frames; give a start frame from 0 to 19"):
        VideoReader(tiny_video.path, start_frame=25)


def test_reading_goes_on_past_frames_that_cannot_be_decoded(make_video, tmp_path):
    """A file damaged in the middle (a failing copy or card) ended the frames there, as if cut short. FFmpeg's
    decoder resumes after the damage, as players do, and the frames after it keep their numbers."""
    clip = make_video(tmp_path, "clip.mp4", n_frames=60)
    intact = decode_all(clip.path)
    damage_middle(clip.path)
    with VideoReader(clip.path) as reader:
        items = list(reader)
    missing = {first + k for first, count in reader.undecodable for k in range(count)}
    assert 1 <= len(missing) <= 10 and max(missing) < 59
    assert [i for i, _, _ in items] == [i for i in range(60) if i not in missing]
    # The numbers are the stream's: every frame's timestamp is its number / fps. Numbered in decoding order, the
    # frames after the gap were stamped later than that, and the stamps took over (timestamps_from).
    assert reader.timestamps_from is None
    assert all(t == pytest.approx(i / clip.fps) for i, t, _ in items)
    # Away from the damage they are the intact file's frames: before the frame whose data it reached, and from the
    # next key frame on (OpenCV's mp4v writes one every 12 frames); between, FFmpeg conceals what it lacks.
    away = [i for i, _, _ in items if i < min(missing) - 1 or i > max(missing) + 12]
    assert len(away) >= 30
    assert all(np.array_equal(frame, intact[i]) for i, _, frame in items if i in away)


def test_a_start_frame_that_cannot_be_decoded_is_refused_and_the_next_one_is_exact(make_video, tmp_path):
    clip = make_video(tmp_path, "clip.mp4", n_frames=60)
    damage_middle(clip.path)
    with VideoReader(clip.path) as reader:
        for _ in reader:
            pass
    first, count = reader.undecodable[0]
    last = first + count - 1
    where = f"frame {first}" if count == 1 else f"frames {first}-{last}"
    message = (f"frame {last} of '{clip.path}' cannot be decoded (the file is damaged at {where}); "
               f"give another frame")
    with pytest.raises(VideoError, match=re.escape(message)):
        VideoReader(clip.path, start_frame=last)
    with VideoReader(clip.path, start_frame=last + 1) as reader:
        items = list(reader)
    assert items[0][:2] == (last + 1, pytest.approx((last + 1) / clip.fps))
    assert [i for i, _, _ in items] == list(range(last + 1, 60))


#: Test videos made by tests/data/make_counter_h264.py (FFmpeg is not needed to run the tests).
DATA = Path(__file__).parent / "data"


def shown_number(frame: np.ndarray) -> int:
    """The frame number a frame of tests/data/counter_h264.mp4 shows: 8 blocks of 16x16 pixels, white for a 1 bit,
    bit 0 top left, row by row (read at each block's centre, clear of the codec's blur at its edges)."""
    return sum(1 << bit for bit in range(8)
               if frame[bit // 4 * 16 + 4:bit // 4 * 16 + 12, bit % 4 * 16 + 4:bit % 4 * 16 + 12].mean() > 128)


def test_the_counter_video_shows_each_frames_number():
    """The undamaged H.264 file the damaged ones are cut from: each frame's pattern is its number (so that the
    tests below, which read frames' numbers from their pictures, can fail)."""
    with VideoReader(DATA / "counter_h264.mp4") as reader:
        assert [(i, shown_number(frame)) for i, _, frame in reader] == [(i, i) for i in range(40)]


def test_frames_after_damaged_h264_keep_their_numbers_and_times():
    """H.264 with B-frames whose packets of frames 14-18 are zeroed. FFmpeg refuses each packet as it reads it,
    before the frames its decoder still holds for reordering come out: counted as one frame each, the failures
    numbered frames 9-13 as 10-12, 17 and 18, with frame 12's picture under number 17 and time_s 0.48 s. The gap in
    the timestamps places the lost frames now."""
    with VideoReader(DATA / "damaged_h264.mp4") as reader:
        items = list(reader)
    assert [i for i, _, _ in items] == [*range(14), *range(19, 40)]
    assert reader.undecodable == [(14, 5)]
    assert all(t == pytest.approx(i / 25) for i, t, _ in items)
    assert reader.timestamps_from is None  # no gap in the times taken for a varying rate
    # Each frame shows its own number, but for those that refer to a lost frame (12, 13: B-frames of frame 14;
    # 19: a P-frame of 18), which FFmpeg conceals with another picture, until the key frame at 20.
    shown = {i: shown_number(frame) for i, _, frame in items}
    assert all(shown[i] == i for i in shown if not 12 <= i <= 19)


def test_frames_after_a_damaged_group_of_pictures_keep_their_numbers():
    """H.264 without B-frames, 200 bytes garbled in frame 7's group of pictures: frames 7-15 are lost, but FFmpeg
    refuses 4 packets. At most a frame per refusal numbered frame 16 as 11, and every later frame 5 numbers (0.2 s)
    early; at a steady rate the timestamps' gap is trusted in full."""
    with VideoReader(DATA / "damaged_gop_h264.mp4") as reader:
        items = list(reader)
    assert [i for i, _, _ in items] == [*range(7), *range(16, 40)]
    assert reader.undecodable == [(7, 9)]
    assert all(t == pytest.approx(i / 25) for i, t, _ in items)
    assert reader.timestamps_from is None  # the steady rate kept, no "rate varies"
    # Each shows its number, but for those FFmpeg conceals until the key frame at 20 (6: the damage starts in it).
    shown = {i: shown_number(frame) for i, _, frame in items}
    assert all(shown[i] == i for i in shown if not 6 <= i < 20)


def test_a_lost_frames_picture_out_of_order_is_left_out():
    """H.264 with B-frames, 400 bytes garbled: frames 9-17 lost, and after frame 18 comes a picture stamped as frame
    9, then 19. Numbered on, it was "19" and every later frame one number late (the last, 39, as 40)."""
    with VideoReader(DATA / "damaged_late_h264.mp4") as reader:
        items = list(reader)
    assert [i for i, _, _ in items] == [*range(9), *range(18, 40)]
    assert reader.undecodable == [(9, 9)]
    shown = {i: shown_number(frame) for i, _, frame in items}
    assert all(shown[i] == i for i in shown if not 18 <= i < 20)  # 18, 19: concealed until the key frame at 20


def test_a_start_frame_of_damaged_h264_is_that_frame():
    """From a start frame the same numbers: frame 20 is 20's picture, frame 13 is followed by 19, and a lost frame
    is refused, naming the lost ones (frame 13 was refused as "damaged at frames 13-16", and frame 17 was 12's
    picture)."""
    damaged = DATA / "damaged_h264.mp4"
    with VideoReader(damaged, start_frame=20) as reader:
        items = list(reader)
    assert [(i, shown_number(frame)) for i, _, frame in items] == [(i, i) for i in range(20, 40)]
    assert items[0][1] == pytest.approx(20 / 25)
    with VideoReader(damaged, start_frame=13) as reader:
        assert [(i, round(t, 6)) for i, t, _ in reader][:2] == [(13, 0.52), (19, 0.76)]
    with pytest.raises(VideoError, match=re.escape(f"frame 16 of '{damaged}' cannot be decoded (the file is "
                                                   f"damaged at frames 14-18); give another frame")):
        VideoReader(damaged, start_frame=16)
    assert shown_number(video_module.read_frame(damaged, 11).image) == 11


def test_frames_lost_in_a_varying_rate_are_counted_at_its_own_rate():
    """H.264 whose frames 10-19 were left out with their stamps (a pause: its 30 frames report 18.75 fps on average,
    25 fps elsewhere), then its frames 23-25 lost. Counted as frames, the failures came before frames 19 and 22 and
    numbered them 20 and 24; counted at the average rate, the gap of 0.16 s would be 2 frames, not 3. The pause, a
    varying rate, is not damage: its frames are numbered on."""
    with VideoReader(DATA / "damaged_vfr_h264.mp4") as reader:
        items = list(reader)
    assert reader.fps == 18.75 and reader.frame_count == 30
    assert [i for i, _, _ in items] == [*range(23), *range(26, 30)]
    assert reader.undecodable == [(23, 3)]
    times = {i: t for i, t, _ in items}
    assert (times[9], times[10], times[22], times[26]) == pytest.approx((0.36, 0.8, 1.28, 1.44))
    # Its frame k shows the number k, or k + 10 after the pause, but for those FFmpeg conceals (from 22: no key
    # frame follows the damage).
    assert [(i, shown_number(frame)) for i, _, frame in items if i < 22] == \
        [(i, i if i < 10 else i + 10) for i in range(22)]


def test_h264_cut_short_ends_after_its_last_frame_with_none_lost():
    """The first 70 % of the H.264 file: the packet cut in two is refused before the frames the decoder held (18,
    19) come out, which were numbered 19 and 20, after "1 frame could not be decoded: 18". No frame was lost
    before the end: frames 0-19, each its own picture, and the end (20 of the 40 announced) is the video's."""
    with VideoReader(DATA / "truncated_h264.mp4") as reader:
        items = list(reader)
    assert reader.frame_count == 40
    assert [(i, shown_number(frame)) for i, _, frame in items] == [(i, i) for i in range(20)]
    assert reader.undecodable == []
    assert video_module.count_frames(DATA / "truncated_h264.mp4") == 20


def test_close_early_stops_the_decoding_thread(tiny_video):
    reader = VideoReader(tiny_video.path, read_ahead=2)
    frames = iter(reader)
    next(frames), next(frames)
    assert reader._thread is not None  # decoding ahead has started
    reader.close()
    assert not reader._thread.is_alive()  # this reader's thread: another test's may still be winding down


def test_close_interrupted_while_waiting_still_releases_the_file(tiny_video, monkeypatch):
    """Ctrl-C while close() waits for the decoding thread: the thread, which owns the capture once started,
    still stops and releases it (before, close() released it itself after the wait, so an interrupted wait left
    the file open)."""
    reader = VideoReader(tiny_video.path, read_ahead=2)
    frames = iter(reader)
    next(frames), next(frames)
    thread = reader._thread
    wait = threading.Thread.join

    def interrupted_join(self, timeout=None):
        raise KeyboardInterrupt

    monkeypatch.setattr(threading.Thread, "join", interrupted_join)
    with pytest.raises(KeyboardInterrupt):
        reader.close()
    monkeypatch.setattr(threading.Thread, "join", wait)
    thread.join(timeout=10)
    assert not thread.is_alive()
    assert not reader._cap.isOpened()


def test_close_after_a_signal_in_thread_start_waits_for_the_thread(tiny_video, monkeypatch):
    """A stop signal landing while Thread.start() waits for the new thread to say it runs leaves start() by the
    exception; close() then met "cannot join thread before it is started" (a traceback and exit 1 instead of 143,
    seen once in CI). It now waits for the thread, which runs all the same, and joins it."""
    reader = VideoReader(tiny_video.path, read_ahead=2)
    frames = iter(reader)
    next(frames), next(frames)
    thread = reader._thread
    join = threading.Thread.join
    refusals = []

    def join_not_yet_started(self, timeout=None):
        if len(refusals) < 3:
            refusals.append(1)
            raise RuntimeError("cannot join thread before it is started")
        return join(self, timeout)

    monkeypatch.setattr(threading.Thread, "join", join_not_yet_started)
    reader.close()
    assert len(refusals) == 3
    assert not thread.is_alive()
    assert not reader._cap.isOpened()


@pytest.mark.parametrize("read_ahead", [1, 2])
def test_reader_decodes_at_most_read_ahead_frames_ahead_and_keeps_none(tiny_video, read_ahead):
    """Memory is bounded by the frames alive at once (25 MB each at 4K): the one the caller holds and at most
    ``read_ahead`` decoded or being decoded; the reader keeps no frame before the current one (the first frame
    included)."""
    reader = VideoReader(tiny_video.path, read_ahead=read_ahead)
    decoded = []  # frames decoded by the background thread
    capture = reader._cap

    class CountingCapture:
        def grab(self):
            ok = capture.grab()
            decoded.append(ok)
            return ok

        def retrieve(self):
            return capture.retrieve()

        def get(self, prop):
            return capture.get(prop)

        def release(self):
            capture.release()

    reader._cap = CountingCapture()
    seen = []
    with reader:
        for index, _, frame in reader:
            seen.append(weakref.ref(frame))
            del frame
            if 1 <= index < 8:  # frame 0 was decoded when the reader opened; the thread starts with frame 1
                # Wait until the thread has decoded as far ahead as it may (a fixed sleep may end before, on a
                # loaded machine, and so miss a thread that goes too far), then hold it to that.
                deadline = time.monotonic() + 30
                while len(decoded) < index + read_ahead and time.monotonic() < deadline:
                    time.sleep(0.001)
                assert len(decoded) == index + read_ahead
            elif index == 0:
                assert len(decoded) <= read_ahead
            gc.collect()
            assert sum(ref() is not None for ref in seen[:-1]) == 0  # none before the current one
    assert len(seen) == tiny_video.n_frames


def test_reader_iterates_once(tiny_video):
    with VideoReader(tiny_video.path) as reader:
        list(reader)
        with pytest.raises(RuntimeError, match="once"):
            iter(reader)


def test_missing_file(tmp_path):
    with pytest.raises(VideoError, match="not found"):
        VideoReader(tmp_path / "nope.mp4")


def test_folder_is_not_a_video(tmp_path):
    with pytest.raises(VideoError, match="folder"):
        VideoReader(tmp_path)


def test_text_file_is_not_a_video(tmp_path):
    fake = tmp_path / "fake.mp4"
    fake.write_text("this is not a video\n" * 50)
    with pytest.raises(VideoError, match="cannot read .* as a video"):
        VideoReader(fake)


def test_zero_byte_file(tmp_path):
    empty = tmp_path / "empty.mp4"
    empty.touch()
    with pytest.raises(VideoError, match="no frames"):
        VideoReader(empty)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_named_pipe_or_device_is_said_to_be_no_video_file(tmp_path):
    # OpenCV seeks in a video; a pipe was reported as "empty (0 bytes)", and must not be waited on either.
    fifo = tmp_path / "stream.mp4"
    os.mkfifo(fifo)
    for path in (fifo, Path("/dev/zero")):
        with pytest.raises(VideoError, match=r"is a pipe or device, not a video file; .*save the stream to a file"):
            VideoReader(path)


def test_video_closed_without_frames(tmp_path):
    path = tmp_path / "noframes.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (64, 48))
    writer.release()
    # The file opens (an AVI header) and yields no frame: that is said, not "cannot read".
    with pytest.raises(VideoError, match=r"^video '.*noframes\.avi' contains no frames \(empty or unreadable video\)$"):
        VideoReader(path)


def test_fps_fallback_when_container_reports_none(tiny_video, monkeypatch):
    class NoFps:
        """A capture whose container reports NaN fps (composition: subclassing cv2 classes is unsafe)."""

        def __init__(self, path):
            self._cap = cv2.VideoCapture(str(path))

        def get(self, prop):
            return float("nan") if prop == cv2.CAP_PROP_FPS else self._cap.get(prop)

        def __getattr__(self, name):
            return getattr(self._cap, name)

    monkeypatch.setattr(video_module, "_open_capture", NoFps)
    with VideoReader(tiny_video.path) as reader:
        assert reader.fps == FALLBACK_FPS and reader.fps_guessed
        items = list(reader)
    assert items[-1][1] == pytest.approx(19 / FALLBACK_FPS)


# -- writer --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, fourcc", [("out.mp4", "mp4v"), ("out.avi", "MJPG")])
def test_writer_round_trip_keeps_count_size_and_fps(tiny_video, tmp_path, name, fourcc):
    target = tmp_path / "w" / name
    target.parent.mkdir()
    with VideoWriter(target, 29.97) as writer:
        for frame in tiny_video.frames:
            writer.write(frame)
            # Until closed, only the hidden temporary file exists.
            assert not target.exists()
            assert temporary_path(target).exists()
    assert writer.fourcc == fourcc and writer.path == target
    assert sorted(p.name for p in target.parent.iterdir()) == [name]
    n, size, fps = count_frames(target)
    assert (n, size) == (tiny_video.n_frames, tiny_video.size)
    assert fps == pytest.approx(29.97, abs=0.01)


def test_writer_never_gives_a_small_frame_to_mjpg(tmp_path):
    """OpenCV's MJPG encoder writes beyond its buffer on small frames (opencv/opencv#29112): ``lptrack run`` of a 4x4
    image sequence with ``-o out.avi`` aborted (``free(): invalid next size``, exit 134, a part file left behind;
    found by fuzzing). Such a video is written with XVID. Run in a child process, as the abort would end pytest's."""
    import subprocess
    import textwrap

    import logpolar_track

    code = textwrap.dedent(f"""
        import numpy as np
        from logpolar_track.video import VideoWriter
        for width, height in ((4, 4), (2, 8), (6, 24), (4, 36)):
            with VideoWriter(r"{tmp_path}" + f"/out{{width}}x{{height}}.avi", 25.0) as writer:
                for i in range(3):
                    writer.write(np.random.default_rng(i).integers(0, 256, (height, width, 3), dtype=np.uint8))
            print(writer.fourcc)
    """)
    env = dict(os.environ, PYTHONPATH=str(Path(logpolar_track.__file__).parents[1]))
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr[-300:]
    assert result.stdout.split() == ["XVID"] * 4
    assert [count_frames(tmp_path / f"out{size}.avi")[:2] for size in ("4x4", "2x8", "6x24", "4x36")] == \
        [(3, (4, 4)), (3, (2, 8)), (3, (6, 24)), (3, (4, 36))]


def test_a_stop_while_the_writer_opens_leaves_nothing(tmp_path, monkeypatch):
    """A stop signal (raised as an exception by lptrack's handlers) can land between the OpenCV writer opening and
    its encoding thread starting; abort() then had a writer without an encoder, failed with AttributeError, and
    the run exited 1 instead of 143 (seen once in CI)."""
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(video_module, "_Encoder", interrupted)
    writer = VideoWriter(tmp_path / "out.mp4", 25.0)
    with pytest.raises(KeyboardInterrupt):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.abort()
    writer.abort()  # safe to repeat
    assert list(tmp_path.iterdir()) == []


def test_writer_whose_folder_went_says_so_not_that_no_codec_opens(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    writer = VideoWriter(folder / "v.mp4", 25.0)
    folder.rmdir()  # by a parallel run into the same folder that failed, say
    with pytest.raises(OutputError, match=r"^cannot write output video '.*v.mp4': folder '.*out' does not exist "
                                          r"\(removed after the run started\)$"):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.abort()


def test_writer_abort_on_exception_leaves_nothing(tiny_video, tmp_path):
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(tmp_path / "out.mp4", 30.0) as writer:
            writer.write(tiny_video.frames[0])
            raise KeyboardInterrupt
    assert list(tmp_path.glob("out*")) == [] and list(tmp_path.glob(".out*")) == []


def test_writer_encodes_frames_in_order_in_the_background(tmp_path):
    """Frames are encoded by a background thread, in the order given (MJPG reads back within 2 levels)."""
    frames = [np.full((48, 64, 3), 8 * i, np.uint8) for i in range(25)]
    with VideoWriter(tmp_path / "out.avi", 25.0) as writer:
        for frame in frames:
            writer.write(frame)
        assert writer._encoder is not None and not writer._encoder.done.is_set()
    assert writer._encoder.done.is_set()
    with VideoReader(tmp_path / "out.avi") as reader:
        levels = [float(f.mean()) for _, _, f in reader]
    assert len(levels) == 25
    assert all(abs(level - 8 * i) <= 2 for i, level in enumerate(levels))  # JPEG rounding: 8 reads as 7


def test_writer_interrupted_while_closing_never_releases_under_the_encoder(tmp_path, monkeypatch):
    """Ctrl-C while close() waits for the last frame's encoding, then abort() as the pipeline does: the OpenCV
    writer is released only after that encoding ends (releasing it mid-encode crashed the process), and no file
    is left."""
    events = []

    class SlowWriter:
        def __init__(self, path, *args):
            self.path = path
            open(path, "wb").close()

        def isOpened(self):
            return True

        def write(self, frame):
            events.append("write start")
            time.sleep(0.3)
            events.append("write end")

        def release(self):
            events.append("release")

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    monkeypatch.setattr(video_module.cv2, "VideoWriter", SlowWriter)
    writer = VideoWriter(tmp_path / "out.mp4", 25.0)
    writer.write(np.zeros((48, 64, 3), np.uint8))
    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        with pytest.raises(KeyboardInterrupt):
            writer.close()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    writer.abort()
    assert events == ["write start", "write end", "release"]
    assert list(tmp_path.iterdir()) == []


def _asleep_in_get(encoder) -> None:
    """Wait until the encoding thread sleeps in the queue's get()."""
    for _ in range(1000):
        if encoder._frames.not_empty._waiters:  # CPython's Condition keeps its sleepers there
            return
        time.sleep(0.01)
    raise AssertionError("the encoding thread never waited for a frame")


def _finishes(call) -> bool:
    """Run ``call`` in a thread; whether it returned (within a minute: a hang must fail the test, not stall it)."""
    worker = threading.Thread(target=call, daemon=True)
    worker.start()
    worker.join(60)
    return not worker.is_alive()


def test_an_encoder_not_told_of_its_frame_is_woken_by_finish(monkeypatch):
    """A stop signal between a frame entering the queue and the encoder being told of it left the encoder asleep
    beside its frame, and `lptrack run` stopped by a signal hung (about 1 run in 25): finish() wakes it again,
    and the frame is encoded."""
    monkeypatch.setattr(video_module, "_WAKE_EVERY_S", 0.05)
    written = []

    class Recorder:
        def write(self, frame):
            written.append(int(frame[0, 0, 0]))

    encoder = video_module._Encoder(Recorder(), "test-encoder")
    _asleep_in_get(encoder)
    with encoder._frames.mutex:  # what Queue.put does, less the notify the signal cut off
        encoder._frames._put(np.full((4, 4, 3), 7, np.uint8))
        encoder._frames.unfinished_tasks += 1
    stopped = []
    assert _finishes(lambda: stopped.append(encoder.finish()))
    assert stopped == [True] and written == [7] and encoder.done.is_set()


def test_an_abort_gives_up_on_an_encoder_that_never_stops(tmp_path, monkeypatch):
    """An encoder stuck in OpenCV's write is waited for a while, then left (a daemon thread): the abort returns,
    does not release the writer under it (which crashes the process), and leaves no file."""
    monkeypatch.setattr(video_module, "_WAKE_EVERY_S", 0.05)
    monkeypatch.setattr(video_module, "_ABANDON_AFTER_S", 0.3)
    writing, stuck, events = threading.Event(), threading.Event(), []

    class StuckWriter:
        def __init__(self, path, *args):
            open(path, "wb").close()

        def isOpened(self):
            return True

        def write(self, frame):
            events.append("write")
            writing.set()
            stuck.wait()

        def release(self):
            events.append("release")

    monkeypatch.setattr(video_module.cv2, "VideoWriter", StuckWriter)
    writer = VideoWriter(tmp_path / "out.mp4", 25.0)
    writer.write(np.zeros((48, 64, 3), np.uint8))
    try:
        assert writing.wait(60)
        assert _finishes(writer.abort)
        assert events == ["write"] and list(tmp_path.iterdir()) == []
    finally:
        stuck.set()


def test_writer_encoder_failure_is_reported_and_leaves_nothing(tiny_video, tmp_path, monkeypatch):
    """An error inside the encoding thread surfaces in the caller as an OutputError; no file is left."""
    real_writer = cv2.VideoWriter

    class BreaksOnSecondFrame:
        def __init__(self, *args):
            self.real, self.count = real_writer(*args), 0

        def isOpened(self):
            return self.real.isOpened()

        def write(self, frame):
            self.count += 1
            if self.count == 2:
                raise cv2.error("encoder exploded")
            self.real.write(frame)

        def release(self):
            self.real.release()

    monkeypatch.setattr(video_module.cv2, "VideoWriter", BreaksOnSecondFrame)
    writer = VideoWriter(tmp_path / "out.mp4", 30.0)
    with pytest.raises(OutputError, match="encoder exploded"):
        for frame in tiny_video.frames:
            writer.write(frame)
        writer.close()
    writer.abort()
    assert list(tmp_path.glob("out*")) == [] and list(tmp_path.glob(".out*")) == []


@pytest.mark.parametrize("name", ["out.mp4", "out.avi"])
def test_a_video_cut_short_by_a_full_disk_is_an_error_and_leaves_nothing(tiny_video, tmp_path, monkeypatch, name):
    """OpenCV's writer reports no failed write: a disk that fills up leaves the file as far as it got, an MP4
    without its index or an AVI that holds no frame by its header (seen on a 200 KB tmpfs, exit 0 and the broken
    file renamed into place). The finished file is read back before it is renamed."""
    real_writer = cv2.VideoWriter

    class DiskFillsUp:  # the file ends where the disk filled: at half of what was written
        def __init__(self, path, *args):
            self.path, self.real = path, real_writer(path, *args)

        def isOpened(self):
            return self.real.isOpened()

        def write(self, frame):
            self.real.write(frame)

        def release(self):
            self.real.release()
            with open(self.path, "r+b") as f:
                f.truncate(os.path.getsize(self.path) // 2)

    monkeypatch.setattr(video_module.cv2, "VideoWriter", DiskFillsUp)
    writer = VideoWriter(tmp_path / name, 30.0)
    for frame in tiny_video.frames:
        writer.write(frame)
    finished = r"the finished file (cannot be read back|cannot be read to its last frame|holds \d+ frames by its header)"
    with pytest.raises(OutputError, match=finished + r", of the \d+ written \(is the disk full\?\)"):
        writer.close()
    assert list(tmp_path.glob("out*")) == [] and list(tmp_path.glob(".out*")) == []


def test_writer_falls_back_to_next_codec_and_says_so(tiny_video, tmp_path, monkeypatch):
    monkeypatch.setitem(video_module.CODECS_BY_EXTENSION, ".mp4", (("ZZZZ", ".mp4"), ("MJPG", ".avi")))
    with VideoWriter(tmp_path / "out.mp4", 30.0) as writer:
        for frame in tiny_video.frames[:3]:
            writer.write(frame)
    assert writer.fourcc == "MJPG" and writer.path == tmp_path / "out.avi"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(("out", ".out"))] == ["out.avi"]
    assert count_frames(writer.path)[0] == 3


def test_writer_no_codec_at_all(tiny_video, tmp_path, monkeypatch):
    monkeypatch.setitem(video_module.CODECS_BY_EXTENSION, ".mp4", (("ZZZZ", ".mp4"),))
    writer = VideoWriter(tmp_path / "out.mp4", 30.0)
    with pytest.raises(OutputError, match="no codec"):
        writer.write(tiny_video.frames[0])
    writer.abort()
    assert [p for p in tmp_path.iterdir() if "out" in p.name] == []


def test_writer_refuses_existing_unless_overwrite(tiny_video, tmp_path):
    target = tmp_path / "out.mp4"
    target.write_bytes(b"precious")
    with pytest.raises(OutputError, match=r"already exists.*--overwrite"):
        VideoWriter(target, 30.0)
    assert target.read_bytes() == b"precious"
    with VideoWriter(target, 30.0, overwrite=True) as writer:
        writer.write(tiny_video.frames[0])
    assert count_frames(target)[0] == 1


def test_a_frame_rate_no_encoder_takes_is_refused_before_any_frame(tmp_path):
    with pytest.raises(UsageError, match=r"0.001 frames/s is below the 0.002 the video encoders take"):
        VideoWriter(tmp_path / "out.mp4", 0.001)
    with VideoWriter(tmp_path / "slow.mp4", 0.002) as writer:  # the lowest taken
        writer.write(np.zeros((48, 64, 3), np.uint8))
    assert count_frames(tmp_path / "slow.mp4")[0] == 1


def test_a_video_written_meanwhile_by_another_run_is_kept(tiny_video, tmp_path):
    target = tmp_path / "out.mp4"
    writer = VideoWriter(target, 30.0)
    writer.write(tiny_video.frames[0])
    target.write_bytes(b"the other run's video")
    with pytest.raises(OutputError, match=r"already exists \(written while this run went on\)"):
        writer.close()
    assert target.read_bytes() == b"the other run's video"
    assert [p.name for p in tmp_path.iterdir() if "out" in p.name] == ["out.mp4"]  # no temporary file left


@pytest.mark.parametrize("where, fragment", [("missing/out.mp4", "does not exist"),
                                             ("afile.txt/out.mp4", "not a folder")])
def test_writer_bad_folder(tmp_path, where, fragment):
    (tmp_path / "afile.txt").write_text("x")
    with pytest.raises(OutputError, match=fragment):
        VideoWriter(tmp_path / where, 30.0)


def test_writer_rejects_unknown_extension_and_size_change(tiny_video, tmp_path):
    with pytest.raises(UsageError, match="unsupported extension"):
        VideoWriter(tmp_path / "out.txt", 30.0)
    writer = VideoWriter(tmp_path / "out.avi", 30.0)
    writer.write(tiny_video.frames[0])
    with pytest.raises(OutputError, match="160x120"):
        writer.write(np.zeros((10, 10, 3), np.uint8))
    writer.abort()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.mp4", "tiny.roi"]


def test_write_video_helper_writes_readable_clip(tmp_path):
    frames = [np.full((48, 64, 3), i * 10, np.uint8) for i in range(5)]
    path = write_video(tmp_path / "grey.avi", frames, 10.0)
    assert count_frames(path)[:2] == (5, (64, 48))


def _turn_display_quarter_clockwise(path, abcd=(0, 1, -1, 0)) -> None:
    """Give an OpenCV-written .mp4 the display matrix of a phone held upright (its track header's rotation
    of 90 degrees clockwise), or the one whose 2x2 part is ``abcd`` (QuickTime's a, b, c, d: a coded pixel (x, y)
    is shown at (a x + c y, b x + d y)), as players and FFmpeg read it; the coded frames are left as they are."""
    data = bytearray(path.read_bytes())
    at = data.find(b"tkhd")
    if at < 0 or data[at + 4] != 0:
        pytest.skip("no version-0 track header in the written .mp4")
    matrix = at + 4 + 4 + 20 + 8 + 8  # version/flags, times/id/duration, reserved, layer/group/volume/reserved
    a, b, c, d = (value << 16 for value in abcd)
    data[matrix:matrix + 36] = np.array([a, b, 0, c, d, 0, 0, 0, 1 << 30], ">i4").tobytes()
    path.write_bytes(bytes(data))


def test_a_phone_video_is_read_and_tracked_upright_as_players_show_it(tiny_video):
    """A video with rotation metadata (phones record sideways and say how to turn it) is delivered turned, as
    players and FFmpeg show it: ROI coordinates are read off the upright picture, and the track is in them."""
    from logpolar_track.pipeline import track_video

    coded = decode_all(tiny_video.path)
    _turn_display_quarter_clockwise(tiny_video.path)
    with VideoReader(tiny_video.path) as reader:
        assert (reader.width, reader.height) == (120, 160)
        frames = [frame for _, _, frame in reader]
    assert all(np.array_equal(f, cv2.rotate(c, cv2.ROTATE_90_CLOCKWISE)) for f, c in zip(frames, coded))
    height = coded[0].shape[0]
    roi = tiny_video.roi
    upright = [(height - 1 - p.cy, p.cx) for p in tiny_video.poses]  # (x, y) turned a quarter clockwise
    results = list(track_video(tiny_video.path, f"{height - 1 - roi.cy:g},{roi.cx:g},{roi.a:g}"))
    assert [r.status for r in results[1:]] == ["tracked"] * (len(results) - 1)
    errors = [np.hypot(r.state.ellipse.cx - x, r.state.ellipse.cy - y) for r, (x, y) in zip(results, upright)]
    assert max(errors) < 1.5
    # Turning the picture keeps the sense of rotation: the object's turn is read as it is shown.
    assert max(abs(r.state.rotation_deg - p.rotation_deg) for r, p in zip(results, tiny_video.poses)) < 2.0


@pytest.mark.parametrize("abcd, shown", [
    ((-1, 0, 0, 1), lambda coded: coded[:, ::-1]),
    ((1, 0, 0, -1), lambda coded: coded[::-1]),
    ((0, 1, 1, 0), lambda coded: coded.transpose(1, 0, 2)),
    ((0, -1, -1, 0), lambda coded: coded.transpose(1, 0, 2)[::-1, ::-1]),
], ids=["mirrored", "upside-down-mirror", "quarter-turn-mirrored", "three-quarter-turn-mirrored"])
def test_a_mirroring_display_matrix_is_shown_as_players_show_it(tiny_video, abcd, shown):
    """A display matrix that mirrors the picture (a selfie camera's left-right swap) is applied as FFmpeg and
    QuickTime apply it. OpenCV turns frames by the matrix's angle alone: the mirror came out turned half round
    (upside down), the quarter turn mirrored as a plain quarter turn."""
    coded = decode_all(tiny_video.path)
    _turn_display_quarter_clockwise(tiny_video.path, abcd)
    with VideoReader(tiny_video.path) as reader:
        frames = [frame for _, _, frame in reader]
    assert len(frames) == len(coded)
    assert all(np.array_equal(frame, shown(c)) for frame, c in zip(frames, coded))
    assert video_module.display_matrix(tiny_video.path) == abcd


def test_a_mirrored_phone_video_is_tracked_as_shown(tiny_video):
    """Tracked in the mirrored picture: x mirrored, and the object's turns read the other way round."""
    from logpolar_track.pipeline import track_video

    _turn_display_quarter_clockwise(tiny_video.path, (-1, 0, 0, 1))
    width = tiny_video.size[0]
    roi = tiny_video.roi
    results = list(track_video(tiny_video.path, f"{width - 1 - roi.cx:g},{roi.cy:g},{roi.a:g}"))
    assert [r.status for r in results[1:]] == ["tracked"] * (len(results) - 1)
    errors = [np.hypot(r.state.ellipse.cx - (width - 1 - p.cx), r.state.ellipse.cy - p.cy)
              for r, p in zip(results, tiny_video.poses)]
    assert max(errors) < 1.5
    assert max(abs(r.state.rotation_deg + p.rotation_deg) for r, p in zip(results, tiny_video.poses)) < 2.0


def test_only_an_iso_media_files_display_matrix_is_read(tmp_path):
    """An .avi, a text file, a truncated .mp4 header: no display matrix, and no error."""
    write_video(tmp_path / "clip.avi", [np.zeros((48, 64, 3), np.uint8)] * 2)
    (tmp_path / "notes.mp4").write_text("not a video")
    (tmp_path / "cut.mp4").write_bytes(b"\x00\x00\x00\x20ftypisom\x00\x00")
    assert [video_module.display_matrix(tmp_path / name) for name in ("clip.avi", "notes.mp4", "cut.mp4")] == \
        [None, None, None]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_pipes_display_matrix_is_not_read(tmp_path):
    """A FIFO (or /dev/stdin) is not opened: opening one with no writer waited for ever (display_matrix is called on
    every capture), and with one it took bytes from the stream."""
    fifo = tmp_path / "stream.mp4"
    os.mkfifo(fifo)
    found = []
    reading = threading.Thread(target=lambda: found.append(video_module.display_matrix(fifo)), daemon=True)
    reading.start()
    reading.join(2.0)
    if reading.is_alive():  # waiting for a writer: give it one, so that the thread ends
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        reading.join(2.0)
        pytest.fail("display_matrix waited for a writer to the FIFO")
    assert found == [None]


@pytest.mark.skipif(not Path("/proc/self/io").exists(), reason="no per-process I/O counts here")
def test_a_display_matrix_is_read_from_the_headers_bytes_alone(tiny_video, tmp_path):
    """A long recording's layout (its index before 50 MB of frames, 2 MB of another track's tables in it): a few
    hundred bytes are read, not a buffer's worth at every seek (8 kB here, a block of 4-16 MB on a cluster's file
    system, where Python's buffer takes the file system's block size)."""
    data = tiny_video.path.read_bytes()
    start = data.find(b"moov") - 4
    moov = data[start:start + int.from_bytes(data[start:start + 4], "big")]
    tables = (8 + 2_000_000).to_bytes(4, "big") + b"free" + bytes(2_000_000)
    path = tmp_path / "long.mp4"
    with open(path, "wb") as file:
        file.write(data[:int.from_bytes(data[:4], "big")])  # ftyp
        file.write((len(moov) + len(tables)).to_bytes(4, "big") + b"moov" + tables + moov[8:])
        file.write((8 + 50_000_000).to_bytes(4, "big") + b"mdat")
        file.truncate(file.tell() + 50_000_000)

    def read_bytes():
        with open("/proc/self/io") as io:
            return next(int(line.split()[1]) for line in io if line.startswith("rchar"))

    before = read_bytes()
    assert video_module.display_matrix(path) == (1, 0, 0, 1)
    assert read_bytes() - before < 1024


def _mp4_boxes(data, start=0, end=None, parents=()):
    """``(offset, type, size, parents' offsets)`` of every box of an ISO BMFF (.mp4) file, depth first."""
    end = len(data) if end is None else end
    while start + 8 <= end:
        size, kind = int.from_bytes(data[start:start + 4], "big"), bytes(data[start + 4:start + 8])
        yield start, kind, size, parents
        if kind in (b"moov", b"trak", b"mdia", b"minf", b"stbl"):
            yield from _mp4_boxes(data, start + 8, start + size, parents + (start,))
        start += size


def _retime_mp4(path, ticks) -> list[float]:
    """Give an OpenCV-written .mp4 (one track, its index after the frames) the frame durations ``ticks``, in its
    track's time units (512 a frame at 30 fps), as a phone's varying rate has; its frames' times in seconds."""
    data = bytearray(path.read_bytes())
    boxes = list(_mp4_boxes(data))
    (stts, _, size, parents), = [box for box in boxes if box[1] == b"stts"]
    (mdhd,), (mdat,) = [[at for at, kind, _, _ in boxes if kind == name] for name in (b"mdhd", b"mdat")]
    assert mdat < parents[0] and data[mdhd + 8] == 0, "test set-up: an index after the frames, a version-0 mdhd"
    runs = []
    for tick in ticks:
        if runs and runs[-1][1] == tick:
            runs[-1][0] += 1
        else:
            runs.append([1, tick])
    table = np.array([0, len(runs), *[n for run in runs for n in run]], ">u4").tobytes()
    new = (8 + len(table)).to_bytes(4, "big") + b"stts" + table
    for at in parents:  # the boxes holding it grow with it; the frames' offsets, before them, stay
        data[at:at + 4] = (int.from_bytes(data[at:at + 4], "big") + len(new) - size).to_bytes(4, "big")
    data[stts:stts + size] = new
    edts = data.find(b"edts", parents[0])
    if edts > 0:  # the edit list would end the video at its first duration: made a free box
        data[edts:edts + 4] = b"free"
    path.write_bytes(bytes(data))
    units = int.from_bytes(data[mdhd + 20:mdhd + 24], "big")
    return [sum(ticks[:k]) / units for k in range(len(ticks))]


def test_a_phones_varying_rate_is_timed_by_its_timestamps_from_its_first_frames(tiny_video):
    """A clip recorded at 30 fps, then 15 in low light, then 30 (23.1 fps on average): every frame's time (a run's
    time_s) is its own timestamp. Times within half a frame of index / 23.1 fps were kept: frames 1 and 2 at 0.043
    and 0.087 s, not 0.033 and 0.067, and speeds from them 0.77, then 2.5 times the true ones."""
    stamps = _retime_mp4(tiny_video.path, [512] * 7 + [1024] * 6 + [512] * 7)
    assert stamps[1] == pytest.approx(1 / 30) and stamps[-1] == pytest.approx(25 / 30)
    with VideoReader(tiny_video.path) as reader:
        assert reader.fps == pytest.approx(20 / (26 / 30))  # frames / duration
        times = [time_s for _, time_s, _ in reader]
    assert times == pytest.approx(stamps, abs=1e-6)
    assert reader.timestamps_from == 1

# -- image sequences ------------------------------------------------------------------------------------------
def _numbered_images(folder, numbers, pattern="frame_%04d.png", size=(48, 64)):
    """Images whose every pixel is their position in ``numbers`` times 10 (grey level), one per number."""
    folder.mkdir(parents=True, exist_ok=True)
    for position, number in enumerate(numbers):
        cv2.imwrite(str(folder / (pattern % number)), np.full(size + (3,), 10 * position, np.uint8))
    return folder / pattern


def test_an_image_sequence_is_read_in_number_order_whatever_its_first_number(tmp_path):
    # FFmpeg and OpenCV look for a first number of 0 to 4 only; 100 is where a cut of a longer sequence starts.
    pattern = _numbered_images(tmp_path / "shots", [100, 101, 102, 110, 1000, 12345])
    for stranger in ("frame_0103.jpg", "frame_00104.png", "frame_7.png", "other_0105.png", "frame_0106.png.bak"):
        (tmp_path / "shots" / stranger).write_bytes(b"not one of the sequence's images")
    assert video_module.is_image_sequence(pattern)
    with VideoReader(pattern) as reader:
        assert (reader.width, reader.height, reader.frame_count) == (64, 48, 6)
        assert reader.fps_guessed and reader.fps == FALLBACK_FPS  # an image sequence has no frame rate
        got = [(index, time_s, int(frame[0, 0, 0]), frame.shape, frame.dtype) for index, time_s, frame in reader]
    # Gaps in the numbers (103-109) are skipped, not an end; %04d takes 12345, which it writes so.
    assert got == [(i, i / FALLBACK_FPS, 10 * i, (48, 64, 3), np.uint8) for i in range(6)]
    with VideoReader(pattern, start_frame=4) as reader:
        assert [(index, int(frame[0, 0, 0])) for index, _, frame in reader] == [(4, 40), (5, 50)]


def test_a_width_without_a_zero_pads_with_zeros_as_in_ffmpeg(tmp_path):
    # FFmpeg writes and reads frame_%4d.png as frame_0001.png (C's printf, and OpenCV, would pad with spaces).
    pattern = _numbered_images(tmp_path / "shots", [1, 2, 10])
    spaced = pattern.with_name("frame_%4d.png")
    assert [path.name for path in video_module.image_sequence_files(spaced)] == \
        ["frame_0001.png", "frame_0002.png", "frame_0010.png"]
    with VideoReader(spaced) as reader:
        assert [int(frame[0, 0, 0]) for _, _, frame in reader] == [0, 10, 20]
    with pytest.raises(VideoError, match=r"no images match '.*f_%3d.png': %3d stands for the frame number, "
                                         r"e.g. '.*shots/f_001.png'"):
        VideoReader(pattern.with_name("f_%3d.png"))
    for typo in ("f_%99999999999999999999d.png", "f_%999999999d.png"):  # a ValueError; a 1 GB string
        with pytest.raises(VideoError, match=r"no images match"):
            VideoReader(pattern.with_name(typo))


def test_grey_and_16_bit_images_are_read_as_8_bit_bgr(tmp_path):
    folder = tmp_path / "shots"
    folder.mkdir()
    cv2.imwrite(str(folder / "1.png"), np.full((20, 30), 200, np.uint8))
    cv2.imwrite(str(folder / "2.png"), np.full((20, 30), 100 * 257, np.uint16))
    with VideoReader(folder / "%d.png") as reader:
        frames = [frame for _, _, frame in reader]
    assert [(f.shape, f.dtype, int(f[0, 0, 0])) for f in frames] == [((20, 30, 3), np.uint8, 200),
                                                                        ((20, 30, 3), np.uint8, 100)]


def test_image_sequence_errors_say_what_is_wrong(tmp_path):
    with pytest.raises(VideoError, match=r"image sequence '.*nope/f_%04d.png': folder '.*nope' not found"):
        VideoReader(tmp_path / "nope" / "f_%04d.png")
    pattern = _numbered_images(tmp_path / "shots", [1, 2, 3])
    with pytest.raises(VideoError, match=r"no images match '.*f_%03d.png': %03d stands for the frame number, "
                                         r"e.g. '.*shots/f_001.png'"):
        VideoReader(pattern.with_name("f_%03d.png"))
    (tmp_path / "shots" / "frame_0002.png").write_bytes(b"damaged")
    with VideoReader(pattern) as reader:
        frames = iter(reader)
        next(frames)
        with pytest.raises(VideoError, match=r"failed after frame 0: cannot read '.*frame_0002.png' as an image"):
            next(frames)
    cv2.imwrite(str(tmp_path / "shots" / "frame_0002.png"), np.zeros((10, 20, 3), np.uint8))
    with VideoReader(pattern) as reader:
        frames = iter(reader)
        next(frames)
        with pytest.raises(VideoError, match=r"failed after frame 0: image '.*frame_0002.png' is 20x10 pixels, not "
                                             r"64x48 as the sequence's first"):
            next(frames)


@pytest.mark.skipif(sys.getfilesystemencoding().lower() not in ("utf-8", "utf8"), reason="file names not UTF-8")
def test_names_that_are_not_utf8_are_refused_before_opencv_sees_them(tiny_video, tmp_path):
    """OpenCV crashes (a segmentation fault) on a path with surrogate escapes, Python's form of name bytes that
    are not UTF-8: reading and writing such a name is a one-line error instead."""
    bad = Path(os.fsdecode(os.fsencode(str(tmp_path)) + b"/caf\xe9.mp4"))
    try:
        shutil.copy(tiny_video.path, bad)
    except OSError:
        pytest.skip("the file system refuses names that are not UTF-8")
    with pytest.raises(VideoError, match=r"video '.*caf\\xe9\.mp4': its name is not valid UTF-8"):
        VideoReader(bad)
    writer = VideoWriter(bad.with_name(bad.stem + "-out.mp4"), 25.0)
    with pytest.raises(OutputError, match="its name is not valid UTF-8, which OpenCV cannot open; rename it"):
        writer.write(tiny_video.frames[0])
    writer.abort()
    assert sorted(p.name for p in tmp_path.iterdir() if "-out" in p.name) == []


def test_a_video_file_with_a_percent_in_its_name_is_a_video(make_video, tmp_path):
    clip = make_video(tmp_path, "clip_%d.mp4")
    assert not video_module.is_image_sequence(clip.path)
    with VideoReader(clip.path) as reader:
        assert sum(1 for _ in reader) == clip.n_frames
    assert video_module.video_stem(clip.path) == "clip_%d"


@pytest.mark.parametrize("name, stem", [("clip.mp4", "clip"), ("shots/frame_%04d.png", "frame"),
                                        ("img/%04d.jpg", "img"), ("take 2 - %d.tif", "take 2"),
                                        ("%05d_left.png", "left")])
def test_outputs_of_an_image_sequence_are_named_after_its_name_without_the_number(tmp_path, name, stem):
    assert video_module.video_stem(tmp_path / name) == stem


def test_a_folder_of_images_suggests_its_pattern(tmp_path):
    _numbered_images(tmp_path / "shots", [7, 8], pattern="cam1_%05d.jpg")
    (tmp_path / "shots" / "notes.txt").write_text("a")
    assert video_module.guess_image_sequence(tmp_path / "shots") == tmp_path / "shots" / "cam1_%05d.jpg"
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "logo.png").write_bytes(b"x")
    assert video_module.guess_image_sequence(tmp_path / "plain") is None
    # Given to `lptrack frame`, `roi`, `sheet` or plot's --video, the folder's error says the pattern, as run's does.
    with pytest.raises(VideoError) as info:
        VideoReader(tmp_path / "shots")
    assert str(info.value) == (f"'{tmp_path / 'shots'}' is a folder, not a video file; for its images give their "
                               f"pattern, e.g. '{tmp_path / 'shots' / 'cam1_%05d.jpg'}'")
    with pytest.raises(VideoError) as info:
        VideoReader(tmp_path / "plain")
    assert str(info.value) == f"'{tmp_path / 'plain'}' is a folder, not a video file"


def test_times_follow_the_streams_timestamps_once_the_rate_varies(tiny_video):
    """A constant rate's timestamps (some containers round them to milliseconds) keep ``index / fps``; from the
    first frame whose timestamp lies more than 1.5 ms from it (a phone slowing to 15 fps in low light),
    ``time_s`` is the timestamp, and stays increasing whatever the stream says."""
    with VideoReader(tiny_video.path) as reader:  # 30 fps
        assert [reader.time_of(i, round(i / 30, 3)) for i in range(3)] == [0.0, 1 / 30, 2 / 30]
        assert reader.timestamps_from is None
        assert reader.time_of(3, 0.1 + 0.0014) == 0.1  # 1.4 ms late: still the nominal time
        assert reader.time_of(4, 4 / 30 + 0.4 / 30) == pytest.approx(0.1466667)  # 0.4 of a frame late: the stamp
        assert reader.timestamps_from == 4
        assert reader.time_of(5, 0.21) == 0.21  # from then on, the timestamps
        assert reader.time_of(6, 0.1) == pytest.approx(0.21 + 1 / 30)  # going back: a frame on instead
    with VideoReader(tiny_video.path, fps=30) as reader:  # --fps: the rate given, whatever the timestamps
        assert reader.time_of(4, 0.2) == 4 / 30 and reader.timestamps_from is None


def test_a_constant_rate_whose_container_states_it_roughly_keeps_index_over_fps(tmp_path):
    """FLV stores a video's rate to 3 digits (59.94 is read back as 959/16 = 59.9375 fps) and its timestamps in
    milliseconds: ``index / fps`` parts from the timestamps by 0.7 us a frame, 1.5 ms after 1,508 frames (25 s).
    Nothing varies: the times stay ``index / fps``, with no "frame rate varies" note (timestamps rounded to
    milliseconds, 16 or 17 ms apart, made speeds from the CSV jump by 6 % from row to row)."""
    path = tmp_path / "constant.flv"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FLV1"), 59.94, (16, 16))
    if not writer.isOpened():
        pytest.skip("this OpenCV writes no .flv")
    for k in range(1800):
        writer.write(np.full((16, 16, 3), k % 256, np.uint8))
    writer.release()
    with VideoReader(path) as reader:
        assert reader.fps == pytest.approx(59.9375)
        times = [time_s for _, time_s, _ in reader]
    assert len(times) == 1800 and reader.timestamps_from is None
    assert times == [k / reader.fps for k in range(1800)]


def test_a_rate_that_changes_late_in_a_clip_is_timed_by_its_timestamps_at_once(tiny_video, tmp_path):
    """30 fps for 20 s, then 24 (a phone dimming its rate in failing light): the first frame at the new rate takes
    its timestamp, 8.3 ms after ``index / fps``. Only a stamp more than half a frame off took it there (the
    allowance for a roughly stated rate, 0.1 % of 20 s, had grown past it): two frames 8.3 and 16.7 ms early,
    speeds over them 1.25 times the true ones. A step of a tick of QuickTime's 1/600 s (1.7 ms, stamps of 29.97 fps
    rounded to it) is no change of rate."""
    with VideoReader(tiny_video.path) as reader:  # 30 fps
        times = [reader.time_of(i, i / 30) for i in range(601)]
        assert reader.timestamps_from is None and times[-1] == 20.0
        assert reader.time_of(601, 20 + 1 / 24) == 20 + 1 / 24 and reader.timestamps_from == 601
    ntsc = write_video(tmp_path / "ntsc.mp4", [np.zeros((16, 16, 3), np.uint8)] * 2, 29.97)
    with VideoReader(ntsc) as reader:
        assert reader.fps == 29.97
        assert [reader.time_of(i, round(i * 600 / 29.97) / 600) for i in range(3000)][-1] == 2999 / 29.97
        assert reader.timestamps_from is None


@pytest.mark.parametrize("name", ["odd.mp4", "odd.avi"])
def test_an_odd_frame_size_is_padded_not_cut(tmp_path, name):
    """4:2:0 codecs need even sizes: OpenCV wrote 641 x 479 frames as 640 x 478, dropping the last column and
    row; they are padded to 642 x 480 instead, every pixel where it was."""
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (479, 641, 3), dtype=np.uint8) for _ in range(3)]
    frames[0][:, -1] = 255  # the last column, which the cut lost
    with VideoWriter(tmp_path / name, 25.0) as writer:
        for frame in frames:
            writer.write(frame)
    assert writer.size == (642, 480)
    capture = cv2.VideoCapture(str(tmp_path / name))
    ok, first = capture.read()
    capture.release()
    assert ok and first.shape == (480, 642, 3)
    assert first[:479, 640].mean() > 200  # the last column kept (white, up to compression)


def test_a_negative_start_frame_is_bad_usage(tiny_video):
    from logpolar_track.errors import UsageError

    with pytest.raises(UsageError, match="start frame must be a whole number >= 0, got -1"):
        VideoReader(tiny_video.path, start_frame=-1)


@pytest.mark.parametrize("kwargs, message", [
    ({"start_frame": 1.5}, "start frame must be a whole number >= 0, got 1.5"),
    ({"start_frame": "3"}, "start frame must be a whole number >= 0, got '3'"),
    ({"max_frames": 2.5}, "the number of frames to track must be a whole number >= 1, got 2.5"),
    ({"max_frames": 0}, "the number of frames to track must be a whole number >= 1, got 0"),
    ({"fps": "30"}, "the frame rate must be a positive number of frames per second, from 0.001 to 1,000,000, "
                    "got '30'"),
    ({"fps": True}, "got True"),
])
def test_the_library_refuses_frame_numbers_and_rates_the_cli_refuses(tiny_video, kwargs, message):
    """track_video took start_frame=1.5 as frame 1 and max_frames=2.5 as 3 frames, and start_frame='3' or fps='30'
    raised a TypeError: the CLI refuses them all with a usage line."""
    from logpolar_track.errors import UsageError
    from logpolar_track.pipeline import track_video

    with pytest.raises(UsageError, match=re.escape(message)):
        next(track_video(tiny_video.path, "80,60,20", **kwargs))
    # A NumPy integer is a whole number.
    assert next(track_video(tiny_video.path, "80,60,20", start_frame=np.int64(2))).frame == 2


def test_a_stream_whose_first_frame_is_stamped_late_keeps_its_nominal_times(tiny_video):
    """A recording cut mid-GOP: its first decodable frame is stamped 0.133 s, the rate constant all the same;
    compared with index / fps as they stood, every frame was taken for a varying rate and shifted."""
    with VideoReader(tiny_video.path) as reader:  # 30 fps
        assert [reader.time_of(i, 0.133 + i / 30) for i in range(4)] == [i / 30 for i in range(4)]
        assert reader.timestamps_from is None


def test_a_video_is_given_by_its_path_not_a_camera_index():
    """``track_video(0)`` (OpenCV's first camera) and bytes raised a TypeError from Path."""
    for path in (0, b"clip.mp4"):
        with pytest.raises(UsageError, match=r"a video is given by its file's path \(str or Path\), got "):
            VideoReader(path)


class ScriptedCapture:
    """A capture at 25 fps whose grabs follow ``script``: a stamp in frames of 1/25 s (a picture decoded) or None
    (a packet FFmpeg refused); each picture shows the stamp it was scripted with (its pixel value)."""

    def __init__(self, script, frame_count):
        self.script, self.frame_count, self.stamp = list(script), frame_count, None

    def isOpened(self):
        return True

    def grab(self):
        if not self.script:
            return False
        self.stamp = self.script.pop(0)
        return self.stamp is not None

    def retrieve(self):
        return True, np.full((8, 8, 3), self.stamp % 256, np.uint8)

    def get(self, prop):
        return {cv2.CAP_PROP_FPS: 25.0, cv2.CAP_PROP_FRAME_COUNT: float(self.frame_count),
                cv2.CAP_PROP_POS_MSEC: (self.stamp or 0) * 40.0,
                cv2.CAP_PROP_FOURCC: float(cv2.VideoWriter_fourcc(*"avc1"))}.get(prop, 0.0)

    def release(self):
        pass


def scripted_read(monkeypatch, tmp_path, script, frame_count):
    path = tmp_path / "scripted.ts"
    path.write_bytes(b"\0" * 188)
    monkeypatch.setattr(video_module, "_open_capture", lambda p: ScriptedCapture(script, frame_count))
    with VideoReader(path) as reader:
        return [(i, int(frame[0, 0, 0])) for i, _, frame in reader]


def test_stamps_that_start_again_after_damage_are_not_left_out(monkeypatch, tmp_path):
    """Two MPEG-TS files joined with cat (the second's stamps start again at 0), frame 10 of the first refused: the
    second's pictures are not 'out of order' pictures of lost frames (all but its last were left out)."""
    script = [*range(10), None, *range(11, 20), *range(20)]
    items = scripted_read(monkeypatch, tmp_path, script, 40)
    assert [shown for _, shown in items] == [*range(10), *range(11, 20), *range(20)]
    assert [i for i, _ in items] == [*range(10), *range(11, 40)]


def test_a_pause_long_after_damage_is_not_lost_frames(monkeypatch, tmp_path):
    """A phone's pause (frames 60-69 not in the file, no refusal) 50 frames after a refused packet: numbered on by
    one, as without damage, not as 10 lost frames."""
    script = [*range(10), None, *range(11, 60), *range(70, 80)]
    items = scripted_read(monkeypatch, tmp_path, script, 69)
    assert [i for i, _ in items] == [*range(10), *range(11, 70)]


def _jpeg_turned_by_exif(path, image, orientation=6):
    """``image`` as a JPEG whose EXIF says to show it turned (6: a quarter turn clockwise), as a phone writes one."""
    ok, data = cv2.imencode(".jpg", image)
    assert ok
    tiff = (b"MM\x00\x2a\x00\x00\x00\x08" + b"\x00\x01" + b"\x01\x12\x00\x03\x00\x00\x00\x01"
            + orientation.to_bytes(2, "big") + b"\x00\x00" + b"\x00\x00\x00\x00")
    app1 = b"Exif\x00\x00" + tiff
    data = data.tobytes()
    path.write_bytes(data[:2] + b"\xff\xe1" + (len(app1) + 2).to_bytes(2, "big") + app1 + data[2:])


def test_a_still_image_is_read_as_its_image_sequence_reads_it(tmp_path):
    """A photo whose EXIF turns it: read alone (FFmpeg, which ignores the orientation) it was 200x100, in an image
    sequence (cv2.imread) 100x200, so 'lptrack roi img/0001.jpg' checked and gave a ROI in a picture on its side
    that 'lptrack run img/%04d.jpg' then refused or tracked elsewhere."""
    image = np.zeros((100, 200, 3), np.uint8)
    image[10:30, 150:190] = 255
    for k in (1, 2):
        _jpeg_turned_by_exif(tmp_path / f"{k:04d}.jpg", image)
    alone = video_module.read_frame(tmp_path / "0001.jpg")
    in_sequence = video_module.read_frame(tmp_path / "%04d.jpg")
    assert alone.image.shape == in_sequence.image.shape
    assert np.array_equal(alone.image, in_sequence.image)
