"""Shared fixtures: tiny generated videos with exact ground truth.

``make_video(folder, ...)`` writes a short synthetic clip (a textured disc moving, growing and turning over a
textured background, :mod:`logpolar_track.synthetic`) with OpenCV's VideoWriter and returns a
:class:`SyntheticVideo` describing it. ``tiny_video`` is one such clip (20 frames, 160x120, mp4v .mp4, 30 fps,
with a ``.roi`` sidecar) in a fresh per-test folder, so tests may write next to it and list the folder.
"""

from __future__ import annotations

import inspect
import os

os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import click.testing  # noqa: E402
import cv2  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from logpolar_track.geometry import Ellipse  # noqa: E402
from logpolar_track.synthetic import Pose, similarity_path, synthetic_sequence  # noqa: E402


class CliRunner(click.testing.CliRunner):
    """click's CliRunner with stderr kept apart from stdout (``result.stdout`` / ``result.stderr``) on every click
    the project supports: click >= 8.2 always keeps it apart, click 8.1 only when given ``mix_stderr=False`` (a
    parameter 8.2 removed). ``result.output`` differs: stdout and stderr interleaved in 8.2, stdout alone in 8.1,
    so tests read ``stdout`` or ``stderr``."""

    def __init__(self, **kwargs):
        if "mix_stderr" in inspect.signature(click.testing.CliRunner.__init__).parameters:  # click 8.1
            kwargs.setdefault("mix_stderr", False)
        super().__init__(**kwargs)


@dataclass(frozen=True)
class SyntheticVideo:
    """A generated clip: its file, the initial ROI, per-frame ground truth and the frames as written."""

    path: Path
    roi: Ellipse
    poses: list[Pose]
    frames: list[np.ndarray]
    fps: float
    fourcc: str

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.frames[0].shape[1], self.frames[0].shape[0]

    @property
    def n_frames(self) -> int:
        return len(self.frames)


def write_video(path: Path, frames, fps: float = 30.0, fourcc: str | None = None) -> Path:
    """Write BGR ``frames`` to ``path`` (mp4v for .mp4, MJPG for .avi unless ``fourcc``); return the path."""
    path = Path(path)
    fourcc = fourcc or ("MJPG" if path.suffix.lower() == ".avi" else "mp4v")
    frames = list(frames)
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (width, height))
    assert writer.isOpened(), f"test set-up: cannot open a {fourcc} writer for {path}"
    for frame in frames:
        writer.write(frame)
    writer.release()
    return path


def damage_middle(path: Path) -> Path:
    """Overwrite 1,500 bytes in the middle of video ``path`` with seeded noise, as a failing copy or card does: on a
    60-frame clip of :func:`_make_video`, a stretch of frames FFmpeg cannot decode, after which it decodes again."""
    data = bytearray(path.read_bytes())
    at = len(data) // 2
    data[at:at + 1500] = np.random.default_rng(0).integers(0, 256, 1500, dtype=np.uint8).tobytes()
    path.write_bytes(bytes(data))
    return path


def decode_all(path: Path) -> list[np.ndarray]:
    """Every frame of ``path``, read from the start with a plain ``cv2.VideoCapture`` (the reference for readers)."""
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
    cap.release()
    return frames


def count_frames(path: Path) -> tuple[int, tuple[int, int], float]:
    """Decode ``path`` completely: (frame count, (width, height), fps the container reports)."""
    cap = cv2.VideoCapture(str(path))
    assert cap.isOpened(), f"cannot open {path}"
    fps = cap.get(cv2.CAP_PROP_FPS)
    n, size = 0, None
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        n += 1
        size = (frame.shape[1], frame.shape[0])
    cap.release()
    return n, size, fps


def _make_video(folder: Path, name: str = "clip.mp4", *, n_frames: int = 20, size=(160, 120),
                start: tuple[float, float] | None = None, radius: float = 20.0, fps: float = 30.0,
                scale_range=(0.85, 1.2), turns: float = 0.25, path_radius: float = 10.0, seed: int = 1,
                fourcc: str | None = None, sidecar: bool = True) -> SyntheticVideo:
    width, height = size
    start = start or (width / 2.0, height / 2.0)
    roi = Ellipse.circle(start[0], start[1], radius)
    poses = similarity_path(n_frames, start, scale_range=scale_range, turns=turns, radius_px=path_radius)
    frames = list(synthetic_sequence(poses, roi, size=size, seed=seed))
    path = write_video(Path(folder) / name, frames, fps, fourcc)
    if sidecar:
        path.with_suffix(".roi").write_text(roi.to_spec() + "\n")
    return SyntheticVideo(path, roi, poses, frames, fps, fourcc or ("MJPG" if path.suffix == ".avi" else "mp4v"))


@pytest.fixture
def make_video():
    """Factory ``make_video(folder, name='clip.mp4', *, n_frames=20, size=(160, 120), start=None, radius=20,
    fps=30, scale_range=(0.85, 1.2), turns=0.25, path_radius=10, seed=1, fourcc=None, sidecar=True)``."""
    return _make_video


@pytest.fixture(scope="session")
def _tiny_video_master(tmp_path_factory) -> SyntheticVideo:
    return _make_video(tmp_path_factory.mktemp("tiny"), "tiny.mp4")


@pytest.fixture
def tiny_video(_tiny_video_master, tmp_path) -> SyntheticVideo:
    """20 frames, 160x120, mp4v .mp4 at 30 fps, ROI circle 80,60,20 in ``tiny.roi``, copied into ``tmp_path``."""
    master = _tiny_video_master
    path = tmp_path / master.path.name
    path.write_bytes(master.path.read_bytes())
    path.with_suffix(".roi").write_text(master.roi.to_spec() + "\n")
    return SyntheticVideo(path, master.roi, master.poses, master.frames, master.fps, master.fourcc)


@pytest.fixture
def two_opencv_threads():
    """OpenCV set to 2 threads for the test (restored after), so that a setting of 1 can be told from it."""
    previous = cv2.getNumThreads()
    cv2.setNumThreads(2)
    yield 2
    cv2.setNumThreads(previous)
