"""Reading and writing videos with OpenCV, without surprises.

:class:`VideoReader` iterates ``(index, time_s, frame)`` over a video file, decoding a frame ahead in a
background thread so that decoding overlaps tracking. :class:`VideoWriter` opens on the first frame, tries
codecs in order and says which one it used, encodes in a background thread so that encoding overlaps tracking
too, and writes to a temporary name that is renamed only when the video is complete -- a killed run never
leaves a file that looks finished.

Frames are BGR ``uint8`` arrays of shape ``(height, width, 3)`` as OpenCV decodes them. Frame indexes count
from 0 at the first frame of the file; ``time_s = index / fps`` (the nominal time of a constant-rate video), or a
varying rate's timestamps (:meth:`VideoReader.time_of`).
:func:`read_frame` gives exactly the N-th decoded frame (or the frame at a time) as a :class:`Frame`, and
:func:`count_frames` the number of frames by decoding them all.

An image sequence is read like a video where a file name holds a printf-style frame number, as FFmpeg takes it:
``frames/%04d.png`` (or ``frames/%4d.png``: a width pads with zeros) is ``frames/0001.png``, ``frames/0002.png``,
... Its frames are
its images in number order, whatever the first number (FFmpeg and OpenCV look only for 0 to 4), frame 0 the
lowest; it has no frame rate of its own (``fps_guessed``).
"""

from __future__ import annotations

import contextlib
import math
import os

# FFmpeg's own messages ("moov atom not found") would bury ours; FFmpeg reads the variable when a file is
# opened. (OpenCV's own log level is the CLI's to set: see logpolar_track.cli.)
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

import ctypes  # noqa: E402
import ctypes.util  # noqa: E402
import queue  # noqa: E402
import re  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Iterator  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from .errors import (FrameRangeError, LptrackError, OutputError, UsageError, VideoError, counted, is_real,  # noqa: E402
                     is_whole)
from .outputs import check_output_path, temporary_path, written_into_place  # noqa: E402

#: Frame rate assumed when a container reports none (0 or NaN), in frames per second.
FALLBACK_FPS = 25.0

#: Codecs tried for each output extension, in order: (fourcc, extension actually written).
#: mp4v in .mp4/.mov plays almost everywhere; MJPG in .avi reads back frame-exact, so it is the last resort.
CODECS_BY_EXTENSION: dict[str, tuple[tuple[str, str], ...]] = {
    ".mp4": (("mp4v", ".mp4"), ("MJPG", ".avi")),
    ".m4v": (("mp4v", ".m4v"), ("MJPG", ".avi")),
    ".mov": (("mp4v", ".mov"), ("MJPG", ".avi")),
    ".avi": (("MJPG", ".avi"), ("XVID", ".avi")),
    ".mkv": (("mp4v", ".mkv"), ("MJPG", ".mkv"), ("MJPG", ".avi")),
    ".webm": (("VP80", ".webm"), ("MJPG", ".avi")),
}

#: Fewest pixels (width x height) of a frame written with MJPG; smaller ones go to the next codec (XVID in .avi).
#: OpenCV's own MJPG encoder writes beyond its buffer on small frames (opencv/opencv#29112, #22420) and the process
#: aborts ("free(): invalid next size", exit 134, no message, a hidden part file left behind): with OpenCV 5.1.0,
#: frames of random noise 4x4, 2x8, 6x24 and 4x36 px did, none of 2 to 40 px a side above 144 pixels, so 32 x 32
#: keeps a margin for other content. Found by fuzzing ``lptrack run`` on a 4x4 image sequence with ``-o out.avi``.
MJPG_MIN_PIXELS = 32 * 32

#: File extensions taken for videos (case-insensitive), the commonest first: searched for in input folders, beside a
#: run CSV (``lptrack plot``) and in sequence folders.
VIDEO_EXTENSIONS: tuple[str, ...] = (".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".ts",
                                     ".mts", ".m2ts", ".wmv", ".flv", ".3gp", ".ogv")

_END = object()  # end-of-stream marker in the read-ahead queue


#: A printf-style frame number in a file name: ``%d``, ``%04d``.
_FRAME_NUMBER = re.compile(r"%0?\d*d")


def _frame_number_field(path: Path) -> re.Match | None:
    """The frame-number field of an image-sequence pattern ``path`` (a file name with exactly one such field that
    is not itself an existing file), else None."""
    fields = list(_FRAME_NUMBER.finditer(path.name))
    if len(fields) != 1 or path.exists():
        return None
    return fields[0]


def _frame_number_text(field: re.Match, number: int) -> str:
    """``number`` as the frame-number ``field`` writes it, as FFmpeg does: a width pads with zeros, given or not
    (``%04d`` and ``%4d``: ``0007``; ``%d``: ``7``). C's printf, and so OpenCV's reader, pads ``%4d`` with spaces,
    which no numbered image file has."""
    width = field.group(0)[1:-1]
    # No file name holds more than 255 characters: a wider field (a typo) is read as that wide, not built.
    return f"{number:0{min(int(width), 255)}d}" if width else str(number)


def is_image_sequence(path) -> bool:
    """Whether ``path`` names an image sequence (``frames/%04d.png``) rather than a video file."""
    return _frame_number_field(Path(path)) is not None


def image_sequence_files(path) -> list[Path]:
    """The images of image-sequence pattern ``path``, in frame-number order: the files of its folder whose
    names are the pattern with a number in the field, written as the field writes it (``%04d``, and ``%4d`` as
    FFmpeg takes it: ``0007``, ``12345``; ``%d``: ``7``). A number missing from the run is skipped. Empty if none (or
    no folder)."""
    return [file for _, file in _numbered_images(path)]


def _numbered_images(path) -> list[tuple[int, Path]]:
    """:func:`image_sequence_files` with each image's number."""
    path = Path(path)
    field = _frame_number_field(path)
    if field is None:
        raise ValueError(f"'{path}' is not an image-sequence pattern")
    name = path.name
    named = re.compile(re.escape(name[:field.start()]) + r"(\d+)" + re.escape(name[field.end():]) + r"\Z")
    folder = path.parent
    found = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return []
    for entry in entries:
        match = named.match(entry.name)
        # The number as the field writes it, so that '%04d' does not also take '7.png' or '00007.png'.
        if match and _frame_number_text(field, int(match.group(1))) == match.group(1) and entry.is_file():
            found.append((int(match.group(1)), folder / entry.name))
    return sorted(found)


#: Image files whose numbered runs :func:`guess_image_sequence` recognises in a folder.
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm")


def guess_image_sequence(folder) -> Path | None:
    """The image-sequence pattern of the first numbered image in ``folder`` (by name), its last run of digits
    as the frame number (``shots/frame_0100.png`` -> ``shots/frame_%04d.png``), or None if it has none: what to
    suggest to someone who gave the folder itself."""
    folder = Path(folder)
    try:
        names = sorted(entry.name for entry in os.scandir(folder) if entry.is_file())
    except OSError:
        return None
    for name in names:
        if Path(name).suffix.lower() in IMAGE_EXTENSIONS:
            digits = list(re.finditer(r"\d+", Path(name).stem))
            if digits:
                run = digits[-1]
                field = "%d" if len(run.group(0)) == 1 else f"%0{len(run.group(0))}d"
                return folder / (name[:run.start()] + field + name[run.end():])
    return None


def video_stem(path) -> str:
    """What the outputs and the ``.roi`` sidecar of input ``path`` are named after: a video's stem (``clip`` for
    ``clip.mp4``); for an image sequence, its file name without the frame number and the extension, trimmed of
    separators (``frame`` for ``frame_%04d.png``), or its folder's name if nothing is left (``img`` for
    ``img/%04d.jpg``)."""
    path = Path(path)
    field = _frame_number_field(path)
    if field is None:
        return path.stem
    rest = path.name[:field.start()] + path.name[field.end():]
    stem = rest[:len(rest) - len(path.suffix)].strip(" ._-")
    return stem or path.absolute().parent.name or "frames"


def input_label(path) -> str:
    """How messages name input ``path``: a video's file name; an image sequence's pattern with its folder
    (``img/%04d.jpg``, where the pattern alone says little)."""
    path = Path(path)
    if is_image_sequence(path) and path.absolute().parent.name:
        return f"{path.absolute().parent.name}/{path.name}"
    return path.name


def _check_input_path(path: Path) -> None:
    if _frame_number_field(path) is not None:
        # Whether any image matches is found when _open_capture lists the folder (once: it may be large).
        if not path.parent.is_dir():
            raise VideoError(f"image sequence '{path}': folder '{path.parent}' not found")
        return
    if not path.exists():
        raise VideoError(f"video '{path}' not found; give the path of a video file OpenCV can read "
                         f"(e.g. .mp4, .avi, .mov) or an image sequence's pattern (e.g. frames/%04d.png)")
    if path.is_dir():
        # `lptrack frame img/` for OTB's img/0001.jpg...: say the pattern that reads them, as `lptrack run` does.
        pattern = guess_image_sequence(path)
        hint = f"; for its images give their pattern, e.g. '{pattern}'" if pattern is not None else ""
        raise VideoError(f"'{path}' is a folder, not a video file{hint}")
    if not os.access(path, os.R_OK):
        raise VideoError(f"video '{path}' is not readable (permission denied)")
    if not path.is_file():
        # OpenCV reads a video by seeking in it, which a pipe, a FIFO or a device (/dev/stdin) cannot do.
        raise VideoError(f"'{path}' is a pipe or device, not a video file; OpenCV reads videos from files only: "
                         f"save the stream to a file first")
    if path.stat().st_size == 0:
        raise VideoError(f"video '{path}' is empty (0 bytes); it contains no frames")


def _not_opened(path: Path) -> VideoError:
    """Why ``path``'s capture did not open (:func:`_open_capture`)."""
    field = _frame_number_field(path)
    if field is not None:  # an image sequence opens unless no image matches
        example = path.name[:field.start()] + _frame_number_text(field, 1) + path.name[field.end():]
        return VideoError(f"no images match '{path}': {field.group(0)} stands for the frame number, e.g. "
                          f"'{path.parent / example}'")
    return VideoError(f"cannot read '{path}' as a video: OpenCV cannot decode it (not a video, a damaged or "
                      f"truncated file, or a format this OpenCV build does not support)")


def opencv_path(path, what: str, error: type[LptrackError] = VideoError) -> str:
    """``path`` as the text OpenCV's functions take.

    Raises
    ------
    LptrackError
        (``error``, a :class:`VideoError` unless given) If the name is not valid UTF-8: bytes a Linux file system
        allows in names, which Python keeps as surrogate escapes and OpenCV crashed on (a segmentation fault that
        took a whole batch with it). ``what`` names the file in the message, e.g. ``"video"``.
    """
    text = str(path)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        shown = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
        raise error(f"{what} '{shown}': its name is not valid UTF-8, which OpenCV cannot open; rename it") from None
    return text


def _open_capture(path: Path) -> cv2.VideoCapture:
    """OpenCV's capture for ``path``, or an :class:`_ImageSequenceCapture` for an image-sequence pattern (one
    seam, so tests can stand in for odd containers); a :class:`_MirroredCapture` for a video whose display matrix
    mirrors the picture."""
    if is_image_sequence(path):
        return _ImageSequenceCapture(_numbered_images(path))
    if path.suffix.lower() in IMAGE_EXTENSIONS and path.is_file():
        # A still image is read as an image sequence's images are (cv2.imread, which turns a photo upright by its
        # EXIF orientation): FFmpeg ignores the orientation, so 'lptrack roi img/0001.jpg' checked a ROI against
        # the picture on its side that 'lptrack run img/%04d.jpg' then tracked upright.
        return _ImageSequenceCapture([(0, path)])
    capture = cv2.VideoCapture(opencv_path(path, "video"))
    shown = _MIRRORS.get(display_matrix(path)) if capture.isOpened() else None
    # OpenCV turns frames by the matrix's angle alone, which takes a mirror for a half turn: its own turning is
    # switched off and the matrix applied here instead.
    if shown is not None and capture.set(cv2.CAP_PROP_ORIENTATION_AUTO, 0):
        return _MirroredCapture(capture, shown)
    return capture


#: How a decoded frame becomes the picture shown, for the display matrices that mirror it, keyed by their
#: :func:`display_matrix`. OpenCV turns the other four (a quarter, half or three-quarter turn) itself.
_MIRRORS = {
    (-1, 0, 0, 1): lambda frame: cv2.flip(frame, 1),  # left and right swapped (a mirror image)
    (1, 0, 0, -1): lambda frame: cv2.flip(frame, 0),  # top and bottom swapped
    (0, 1, 1, 0): cv2.transpose,  # a quarter turn clockwise, then left and right swapped
    (0, -1, -1, 0): lambda frame: cv2.flip(cv2.transpose(frame), -1),  # the same, counter-clockwise
}

#: Boxes an ISO BMFF file (.mp4, .mov, .m4v, .3gp) may begin with.
_BMFF_FIRST_BOXES = {b"ftyp", b"moov", b"mdat", b"free", b"skip", b"wide", b"pnot", b"uuid"}


def display_matrix(path) -> tuple[int, int, int, int] | None:
    """How an ISO BMFF video (.mp4, .mov: a phone's) says to show its frames: the first video track's display
    matrix, times the movie's, as the signs ``(a, b, c, d)`` of its 2x2 part, or None (not such a file, no video
    track, a matrix that is not a quarter turn or a mirror, or the file cannot be read).

    In QuickTime's convention, which players follow, a coded pixel ``(x, y)`` is shown at ``(a x + c y,
    b x + d y)``, then moved into the picture: ``(1, 0, 0, 1)`` as coded, ``(0, 1, -1, 0)`` a quarter turn
    clockwise (a phone held upright), ``(-1, 0, 0, 1)`` mirrored left to right. Only the headers are read, not
    the sample tables (megabytes in a long recording).

    References
    ----------
    ISO/IEC 14496-12 (ISO base media file format), the ``mvhd`` and ``tkhd`` boxes' ``matrix``.
    """
    try:
        if not Path(path).is_file():  # a FIFO or a device: opening one waits for a writer, reading one takes its bytes
            return None
        # Unbuffered: a buffered read after each seek took a buffer's worth, the file system's block size (4-16 MB
        # on a cluster's), for the few bytes of a box header.
        with open(path, "rb", buffering=0) as file:
            size = os.fstat(file.fileno()).st_size
            if file.read(8)[4:] not in _BMFF_FIRST_BOXES:
                return None
            moov = next((box for box in _bmff_boxes(file, 0, size) if box[0] == b"moov"), None)
            if moov is None:
                return None
            movie, track = ((1, 0), (0, 1)), None  # a movie matrix is optional: none is the identity
            for kind, start, end in _bmff_boxes(file, moov[1], moov[2]):
                if kind == b"mvhd":
                    movie = _box_matrix(file, start, end, 36)
                elif kind == b"trak" and _handler(file, start, end) == b"vide":
                    track = next((_box_matrix(file, at, stop, 40) for name, at, stop in _bmff_boxes(file, start, end)
                                  if name == b"tkhd"), None)
                    break
    except OSError:
        return None
    if track is None or movie is None:
        return None
    (a, b), (c, d) = track
    (e, f), (g, h) = movie
    signs = tuple(int(np.sign(value)) for value in (a * e + b * g, a * f + b * h, c * e + d * g, c * f + d * h))
    quarter_turns = {(1, 0, 0, 1), (0, 1, -1, 0), (-1, 0, 0, -1), (0, -1, 1, 0)}
    return signs if signs in quarter_turns or signs in _MIRRORS else None


def _bmff_boxes(file, start: int, end: int):
    """``(type, contents' start, end)`` of the boxes of an ISO BMFF ``file`` between byte offsets ``start`` and
    ``end`` (a file's top level, or a box's contents), read by seeking from header to header."""
    at = start
    while at + 8 <= end:
        file.seek(at)
        header = file.read(16)
        if len(header) < 8:
            return
        size, kind, contents = int.from_bytes(header[:4], "big"), header[4:8], at + 8
        if size == 1:  # a 64-bit size follows
            size, contents = int.from_bytes(header[8:16], "big"), at + 16
        elif size == 0:  # to the end
            size = end - at
        if at + size > end or contents > at + size:
            return
        yield kind, contents, at + size
        at += size


def _handler(file, start: int, end: int) -> bytes | None:
    """The handler type (``vide``, ``soun``, ...) of the track whose ``trak`` box's contents span ``start``-``end``."""
    for kind, at, stop in _bmff_boxes(file, start, end):
        if kind == b"mdia":
            for name, hdlr, _ in _bmff_boxes(file, at, stop):
                if name == b"hdlr":
                    file.seek(hdlr + 8)  # version and flags, pre_defined
                    return file.read(4)
    return None


def _box_matrix(file, start: int, end: int, at: int) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """The 2x2 part ``((a, b), (c, d))`` (16.16 fixed point) of the matrix of the ``mvhd`` or ``tkhd`` box whose
    contents span ``start``-``end``: ``at`` bytes in for version 0 (36 in ``mvhd``, 40 in ``tkhd``), 12 more in
    version 1, whose times take 8 bytes each."""
    file.seek(start)
    at += start + (12 if file.read(1) == b"\x01" else 0)
    file.seek(at)
    fields = file.read(20)  # a, b, u, c, d
    if len(fields) < 20 or at + 20 > end:
        return None
    a, b, _, c, d = (int.from_bytes(fields[i:i + 4], "big", signed=True) for i in range(0, 20, 4))
    return (a, b), (c, d)


class _MirroredCapture:
    """A ``cv2.VideoCapture`` (its own turning switched off) whose frames come out as ``shown`` makes them: the
    picture players show for a display matrix that mirrors it (:data:`_MIRRORS`). Composition: cv2 classes are
    unsafe to subclass."""

    def __init__(self, capture: cv2.VideoCapture, shown):
        self._capture = capture
        self._shown = shown

    def retrieve(self) -> tuple[bool, np.ndarray | None]:
        ok, frame = self._capture.retrieve()
        return (ok, np.ascontiguousarray(self._shown(frame))) if ok and frame is not None else (ok, frame)

    def __getattr__(self, name):
        return getattr(self._capture, name)


class _ImageSequenceCapture:
    """What :class:`VideoReader` uses of ``cv2.VideoCapture``, over the files of an image sequence: each read with
    ``cv2.imread`` as BGR ``uint8`` (grey images made BGR, 16-bit ones reduced to 8 bits, as FFmpeg decodes
    them). It reports the image count as its frame count and no frame rate. Every image must have the first
    one's size, as a video's frames do. ``numbered``: ``(number, file)`` in number order (:func:`_numbered_images`).
    """

    def __init__(self, numbered: list[tuple[int, Path]]):
        self._numbers = [number for number, _ in numbered]
        self._files = [file for _, file in numbered]
        self._next = 0
        self._size: tuple[int, int] | None = None  # (width, height) of the first image read

    def isOpened(self) -> bool:  # noqa: N802 - cv2.VideoCapture's name
        return bool(self._files)

    def number_gaps(self) -> list[tuple[int, str, str]]:
        """Where the image numbers skip (``img_0001.png``, ``img_0003.png``): ``(frame, image before, image after)``,
        ``frame`` the number of the image after the gap. The frames stay the images in number order (that image
        is frame 1), so from the first gap on, frame numbers part from the images' numbers."""
        numbers, names = self._numbers, [file.name for file in self._files]
        return [(k, names[k - 1], names[k]) for k in range(1, len(numbers)) if numbers[k] != numbers[k - 1] + 1]

    def get(self, prop: int) -> float:
        return float(len(self._files)) if prop == cv2.CAP_PROP_FRAME_COUNT else 0.0

    def grab(self) -> bool:
        if self._next >= len(self._files):
            return False
        self._next += 1
        return True

    def retrieve(self) -> tuple[bool, np.ndarray | None]:
        file = self._files[self._next - 1]
        frame = cv2.imread(opencv_path(file, "image"), cv2.IMREAD_COLOR)
        if frame is None:
            raise VideoError(f"cannot read '{file}' as an image (not an image, damaged, or a format OpenCV "
                             f"cannot read)")
        size = frame.shape[1], frame.shape[0]
        if self._size is None:
            self._size = size
        elif size != self._size:
            raise VideoError(f"image '{file}' is {size[0]}x{size[1]} pixels, not {self._size[0]}x{self._size[1]} "
                             f"as the sequence's first: every image of a sequence must have one size")
        return True, frame

    def release(self) -> None:
        self._files = []


def announced_frame_count(path) -> int:
    """Frame count the container of video ``path`` announces, without decoding (0 when unknown or unreadable);
    may be approximate for containers that store only a duration (e.g. .mkv, .webm)."""
    capture = _open_capture(Path(path))
    try:
        count = capture.get(cv2.CAP_PROP_FRAME_COUNT) if capture.isOpened() else 0.0
    finally:
        capture.release()
    return int(count) if math.isfinite(count) and count > 0 else 0


#: How far (seconds) a constant rate's timestamps may lie from ``index / fps``: containers that store milliseconds
#: (MKV, WebM) round them, by up to 0.5 ms, and frame 0's stamp, which times count from, too. Past it, a frame's
#: time is its timestamp (:meth:`VideoReader.time_of`). Half a frame left a phone's varying rate's first frames up to
#: that far off: a clip at 30 fps, then 15 (22.5 on average), had frame 1 at 0.044 s, not 0.033, and speeds from the
#: CSV 0.75 and 1.5 times the true ones over its first two intervals.
STAMP_ROUNDING_S = 0.0015

#: How far a constant rate's timestamps may drift from ``index / fps`` on top of :data:`STAMP_ROUNDING_S`, as a
#: fraction of that time (0.001: 1 ms a second): a container may state its rate roughly (FLV to 3 digits: 59.94 fps
#: is read as 59.9375, whose ``index / fps`` parted from the timestamps by 1.5 ms after 25 s, with nothing varying).
STAMP_DRIFT = 0.001

#: Frame rates (frames per second) lptrack takes: 1e-300 gave time_s of 300 digits, and an encoder that refused it
#: was reported as "no codec could be opened".
FPS_RANGE = (0.001, 1e6)
#: The lowest frame rate (frames per second) OpenCV's video writers take: mp4v and MJPG refuse 0.001 (in .webm, VP8
#: failed on two or three frames at up to 0.08, though 150 frames at 0.05 were written).
MIN_VIDEO_FPS = 0.002


def check_fps(fps: float | None) -> None:
    """Refuse a frame rate that is given but not a number within :data:`FPS_RANGE` (frames per second)."""
    low, high = FPS_RANGE
    if fps is not None and not (is_real(fps) and math.isfinite(fps) and low <= fps <= high):
        shown = f"{fps:g}" if is_real(fps) else repr(fps)
        raise UsageError(f"the frame rate must be a positive number of frames per second, from {low:g} to "
                         f"{high:,.0f}, got {shown}")


def check_frame_number(value, what: str, low: int = 0) -> None:
    """Refuse a frame number or count (``what``, for the message) that is not a whole number of at least ``low``:
    the library took 1.5 as frame 1 and ``'3'`` raised a TypeError, where the CLI refuses both."""
    if not (is_whole(value) and value >= low):
        raise UsageError(f"{what} must be a whole number >= {low}, got {value!r}")


def frames_to_track(frame_count: int, start_frame: int, max_frames: int | None) -> int | None:
    """Frames a run from ``start_frame`` tracks, at most ``max_frames``, in a video whose container announces
    ``frame_count`` frames (0 past the end); None when it does not say (``frame_count`` 0)."""
    if frame_count <= 0:
        return None
    remaining = max(frame_count - start_frame, 0)
    return remaining if max_frames is None else min(remaining, max_frames)


#: Pictures after a failed grab within which a gap in the stamps at a steady rate is lost frames (the decoder's
#: delay: its reordering and a group of pictures concealed).
_DAMAGE_REACH = 32


def _at_rate(interval: float, nominal: float) -> bool:
    """Whether ``interval`` between two frames (seconds) is a frame of ``nominal`` seconds: within 10 % and 1.5 ms
    of it, as a constant rate's stamps rounded to milliseconds (MKV) are."""
    return abs(interval - nominal) <= max(0.1 * nominal, 0.0015)


class VideoReader:
    """Frames of a video file as ``(index, time_s, frame)``, decoded ahead in a background thread.

    Parameters
    ----------
    path : str or Path
        Video file, anything OpenCV's FFmpeg backend decodes; or an image sequence's pattern
        (:func:`is_image_sequence`: ``frames/%04d.png``).
    start_frame : int, optional
        Index of the first frame to deliver (0 = first frame of the file). Earlier frames are decoded and
        dropped, which is exact where container seeking is not.
    read_ahead : int, optional
        How many frames the background thread may decode ahead of the one the caller holds, the one being
        decoded included: at most ``1 + read_ahead`` frames are alive at once (25 MB each at 4K). With 1, the
        next frame is decoded while the caller works on the current one.
    fps : float, optional
        Frames per second to use instead of the container's (which an image sequence does not have), as
        FFmpeg's ``-framerate``; must be positive and finite.

    Attributes
    ----------
    path : Path
    fps : float
        Frames per second as given, or as the container reports it, never rounded; :data:`FALLBACK_FPS` if it
        reports 0 or NaN (then ``fps_guessed`` is True).
    fps_guessed : bool
    timestamps_from : int or None
        The first frame whose time (``time_s``) is the stream's own timestamp, once iteration has reached it; None
        while the timestamps keep to ``index / fps`` (a constant frame rate; how closely: :meth:`time_of`).
    frame_count : int
        Frame count the container reports; may be approximate, and 0 when unknown.
    undecodable : list of (int, int)
        Stretches of frames that could not be decoded (a damaged file), as ``(first frame, count)``, once
        iteration has passed them. They keep their numbers: the frames after such a stretch are delivered with
        theirs, so an index is skipped, as a player shows the frames before and after the damage.
    image_gaps : list of (int, str, str)
        For an image sequence whose numbers skip (``img_0001.png``, ``img_0003.png``), where: ``(frame, image
        before, image after)``, ``frame`` the image after's frame number (frames are the images in number order);
        empty for a video.
    width, height : int
        Frame size in pixels, from the first decoded frame.

    Raises
    ------
    VideoError
        If the file is missing, not a video, contains no frames, or ``start_frame`` lies past its end or cannot be
        decoded.

    Notes
    -----
    Use as a context manager (or call :meth:`close`) so the decoding thread stops and the file is released.
    A reader can be iterated once.
    """

    def __init__(self, path, *, start_frame: int = 0, read_ahead: int = 1, fps: float | None = None):
        if not isinstance(path, (str, os.PathLike)):  # a camera's index (0), bytes: a TypeError from Path before
            raise UsageError(f"a video is given by its file's path (str or Path), got {path!r}; lptrack reads files "
                             f"and image sequences, not cameras")
        self.path = Path(path)
        check_frame_number(start_frame, "start frame")
        check_fps(fps)
        self.start_frame = int(start_frame)
        self._read_ahead = max(1, int(read_ahead))
        _check_input_path(self.path)
        self._cap = _open_capture(self.path)
        if not self._cap.isOpened():
            self._cap.release()
            raise _not_opened(self.path)
        if _fourcc(self._cap) == "ansi":  # FFmpeg renders any text file as a video of its characters
            self._cap.release()
            raise VideoError(f"cannot read '{self.path}' as a video: it is a text file")
        # The stream's timestamps time the frames only where its own rate is used: --fps overrides them, and an
        # image sequence or a container that reports no rate has none worth reading.
        stream_fps = 0.0 if is_image_sequence(self.path) else float(self._cap.get(cv2.CAP_PROP_FPS) or 0.0)
        # The container's own rate, by which the frames lost in a gap of the timestamps are counted (see
        # _grab_next), whatever --fps says; None for an image sequence or a container that reports none.
        self._stream_fps = stream_fps if math.isfinite(stream_fps) and stream_fps > 0 else None
        self._stamped = fps is None and self._stream_fps is not None
        if fps is None:
            fps = stream_fps
        self.fps_guessed = not (math.isfinite(fps) and fps > 0)
        self.fps = FALLBACK_FPS if self.fps_guessed else float(fps)
        self._previous_stamp: float | None = None  # the last decoded frame's stamp (seconds), see _grab_next
        self._unplaced = 0  # failed grabs whose lost frames no gap in the stamps has shown yet
        self._interval: float | None = None  # seconds between the last two frames decoded in a row
        self._steady = True  # whether every interval between frames decoded in a row so far was the container's
        # Pictures decoded since the last failed grab (a packet FFmpeg refused); None while none has failed.
        self._since_failure: int | None = None
        self._lost_spans: list[tuple[float, float]] = []  # stamps either side of each gap numbered as lost frames
        self.timestamps_from: int | None = None
        self._last_time = -math.inf
        self._stamp_offset: float | None = None
        self._deviation: float | None = None  # the last stamped frame's stamp less its index / fps (s): _rate_varies
        self._varied = False  # whether the rate varied in the frames skipped to the start frame
        count = self._cap.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(count) if math.isfinite(count) and count > 0 else 0
        self.undecodable: list[tuple[int, int]] = []
        # getattr: a capture of a video, or one a test stands in, has no image numbers.
        self.image_gaps: list[tuple[int, str, str]] = getattr(self._cap, "number_gaps", list)()
        # Skip to the start frame by decoding: exact, unlike CAP_PROP_POS_FRAMES on inter-coded streams.
        position = 0  # the number of the next frame
        while True:
            number = self._grab_next(position)
            if number is None:
                self._cap.release()
                if position == 0:
                    raise VideoError(f"video '{self.path}' contains no frames (empty or unreadable video)")
                raise _past_the_end(self.start_frame, self.path, position)
            if number >= self.start_frame:
                break
            if self._stamped and self._stamp_offset is None:
                # The first frame's stamp, less its time: times count from frame 0's (see time_of, which takes
                # it from the start frame when no frame is skipped).
                self._stamp_offset = self._stamp() - number / self.fps
            stamp = self._stamp()  # None where the timestamps do not time the frames
            if stamp is not None:
                # Called on every frame skipped, whatever it says: it follows the stamps' step from frame to frame.
                self._varied = self._rate_varies(number, stamp - self._stamp_offset) or self._varied
            position = number + 1
        ok, first = self._cap.retrieve() if number == self.start_frame else (False, None)
        self._first_stamp = self._stamp()
        if not ok or first is None or first.size == 0:
            self._cap.release()
            where = ("there" if number == self.start_frame else f"at frame {position}" if number == position + 1
                     else f"at frames {position}-{number - 1}")
            raise VideoError(f"frame {self.start_frame} of '{self.path}' cannot be decoded (the file is damaged "
                             f"{where}); give another frame")
        self.first_frame: np.ndarray = first
        self.height, self.width = first.shape[:2]
        # The slots bound the frames decoded ahead, counted from the start of their decoding: a bounded queue
        # alone let the thread decode one more frame while the queue was full (two frames ahead, 25 MB more at 4K).
        self._slots = threading.Semaphore(self._read_ahead)
        self._queue: queue.Queue = queue.Queue()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._iterated = False
        self._closed = False

    # -- context manager -------------------------------------------------------------------------------
    def __enter__(self) -> "VideoReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"VideoReader('{self.path}', {self.width}x{self.height}, fps={self.fps:g}, "
                f"frame_count={self.frame_count}, start_frame={self.start_frame})")

    # -- reading ---------------------------------------------------------------------------------------
    def time_of(self, index: int, stamp: float | None = None) -> float:
        """Time in seconds of frame ``index``: ``index / fps``, or the frame's timestamp ``stamp`` (seconds, taken
        relative to the stream's frame 0, whose time is 0) from the first frame whose timestamp lies more than
        :data:`STAMP_ROUNDING_S` plus :data:`STAMP_DRIFT` of ``index / fps`` (or half a frame, if less) from that,
        or moved from it by more than 3 ms (two stamps' rounding, or half a frame, if less) since the frame before
        (:attr:`timestamps_from`, on): a variable frame rate, as phones record in low light, where ``index / fps``
        (the average rate) drifts by seconds. A constant rate's timestamps, which some containers round to
        milliseconds, and whose rate some state to a few digits only, stay within that. Times stay increasing
        whatever a stream's timestamps do."""
        nominal = index / self.fps
        if stamp is not None and self._stamped:
            if self._stamp_offset is None:
                # Frame 0 is at time 0: a stream cut mid-GOP starts with a frame stamped after 0, a constant rate
                # all the same. (Past a start frame, frame 0's stamp was taken while skipping to it.)
                self._stamp_offset = stamp - nominal
            stamp -= self._stamp_offset
        usable = stamp is not None and math.isfinite(stamp) and stamp > self._last_time
        if (self.timestamps_from is None and usable and self._stamped
                and (self._rate_varies(index, stamp) or self._varied)):
            self.timestamps_from = index
        if self.timestamps_from is None:
            time_s = nominal
        else:
            time_s = stamp if usable else self._last_time + 1.0 / self.fps
        self._last_time = time_s
        return time_s

    def _rate_varies(self, index: int, stamp: float) -> bool:
        """Whether frame ``index``'s timestamp ``stamp`` (seconds from frame 0's) shows a varying rate: it lies more
        than :data:`STAMP_ROUNDING_S` plus :data:`STAMP_DRIFT` of ``index / fps`` from that, or it moved from it by
        more than twice :data:`STAMP_ROUNDING_S` (two stamps' rounding) since the previous frame's, however long
        the clip has run (at most half a frame either way)."""
        nominal = index / self.fps
        deviation = stamp - nominal
        previous, self._deviation = self._deviation, deviation
        half = 0.5 / self.fps
        return (abs(deviation) > min(STAMP_ROUNDING_S + STAMP_DRIFT * nominal, half)
                or previous is not None and abs(deviation - previous) > min(2 * STAMP_ROUNDING_S, half))

    def _grab_next(self, number: int) -> int | None:
        """Grab the next frame that decodes, ``number`` if none was lost since the last one: its number, or None at
        the end of the video.

        FFmpeg's decoder resumes after a damaged stretch, as players do; the frames it could not decode must keep
        their numbers. A failed grab is a packet FFmpeg refused, but it is reported when the packet is read, and
        the frames the decoder still held (for B-frames' reordering) come out after it: H.264 with B-frames
        reported the failures for frames 69-75 before frames 67 and 68. So a failure is not counted as a frame; it
        says that frames are missing, and the presentation timestamps say which: the first frame after
        failures whose stamp lies more than a frame after the previous one's is numbered by the gap, at the
        container's rate (or a varying rate's last interval): all of it where every interval so far was the
        container's (a steady rate), up to a frame per failure where the rate has varied. Without failures a gap
        is a varying rate, not damage (a phone that skipped frames: they are not in the file), and the number goes
        up by one; so are frames dropped without a failure (MPEG-TS damage: none is reported). At a steady rate,
        though, every gap within :data:`_DAMAGE_REACH` pictures of a failure is lost frames, and a picture stamped
        inside such a gap, half a frame or more before the last one's (a lost frame's, out of order), is left out.
        Without stamps (a container reporting no frame rate) each failure counts as a frame. Failures that no gap
        follows (a file cut short in a packet, the frames held still coming out) lost no frame before the end.

        Up to :data:`MAX_UNDECODABLE_RUN` failures in a row, or failures past the frames the container announces,
        end the video there (cut short)."""
        failed = 0
        while True:
            while not self._cap.grab():  # releases the GIL while FFmpeg decodes
                failed += 1
                if not (number + failed < self.frame_count and failed < MAX_UNDECODABLE_RUN):
                    return None
            stamp = self._frame_stamp()
            if failed:
                self._since_failure = 0
            elif self._since_failure is not None:
                self._since_failure += 1
            previous = self._previous_stamp
            # After damage at a steady rate, a picture stamped half a frame or more before the last one, inside a
            # gap numbered as lost frames, is a frame already passed, come out of order (H.264 with B-frames: frame
            # 8's after frames 16 and 17, when 9-15 were lost); numbered on, it put every later frame one number
            # late. It is left out. Not stamps that jump back elsewhere (MPEG-TS files joined with cat, a stamp
            # wrap): they start again, and every later picture would be left out.
            if not (self._steady and stamp is not None and previous is not None
                    and stamp < previous - 0.5 / self._stream_fps
                    and any(lo < stamp < hi for lo, hi in self._lost_spans)):
                break
        self._previous_stamp = stamp
        self._unplaced += failed
        if stamp is None:  # no stamps: each failure counts as a frame
            number, self._unplaced = number + self._unplaced, 0
            return number
        # A frame lasts 1 / the container's rate, exact for a constant rate (stamps rounded to milliseconds, as in
        # MKV, stay within 10 % and 1.5 ms of it); a varying one reports its average, 18.75 fps for 25 with a pause,
        # and the interval between its last two frames counts frames better (3 lost at 25 fps, not 2).
        lasts = nominal = 1.0 / self._stream_fps
        if self._interval is not None and not _at_rate(self._interval, nominal):
            lasts = self._interval
        frames_apart = round((stamp - (-lasts if previous is None else previous)) / lasts)  # frame 0 is at 0
        # Damage reaches as far as the decoder's delay: a gap long after the last failure is a pause (a phone's, in a
        # file whose average rate stays within 10 % of its frames' own), not lost frames.
        steady_damage = self._steady and self._since_failure is not None and self._since_failure <= _DAMAGE_REACH
        if (self._unplaced or steady_damage) and frames_apart > 1:
            # At most a frame per failure where the rate has varied: its pause within the decoder's delay after a
            # failure is not lost frames, and failures left over go to the next gap. At a steady rate, and before
            # the first frame, all of the gap, and every gap within the damage's reach: one failure can take a whole
            # group of pictures with it (H.264 without B-frames, 20 kB of a file damaged: 8 frames lost, one
            # failure reported), and the frames it took can come out in more than one gap.
            lost = frames_apart - 1 if previous is None or steady_damage else min(frames_apart - 1, self._unplaced)
            number, self._unplaced = number + lost, max(self._unplaced - lost, 0)
            if previous is not None:
                self._lost_spans = [*self._lost_spans[-7:], (previous, stamp)]
        elif previous is not None and stamp > previous:
            self._interval = stamp - previous
            self._steady = self._steady and _at_rate(self._interval, nominal)
        return number

    def _frame_stamp(self) -> float | None:
        """The frame just grabbed's presentation timestamp in seconds (OpenCV's ``CAP_PROP_POS_MSEC``: the stream's
        own stamp less its start time, so 0 for frame 0 of a file whose stamps start later, in presentation order
        with B-frames), or None for an image sequence, a container that reports no frame rate, or a stamp that
        is not a number."""
        if self._stream_fps is None:
            return None
        stamp = self._cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0
        return stamp if math.isfinite(stamp) else None

    def _stamp(self) -> float | None:
        """The last decoded frame's timestamp in seconds, if the stream's timestamps time its frames."""
        return self._previous_stamp if self._stamped else None

    def __iter__(self) -> Iterator[tuple[int, float, np.ndarray]]:
        if self._iterated:
            raise RuntimeError("a VideoReader can be iterated only once; open the video again")
        if self._closed:
            raise RuntimeError("VideoReader is closed")
        self._iterated = True
        return self._frames()

    def _frames(self) -> Iterator[tuple[int, float, np.ndarray]]:
        index = self.start_frame
        first, self.first_frame = self.first_frame, None  # do not keep a frame alive for the whole run
        yield index, self.time_of(index, self._first_stamp), first
        del first  # nor here, where the generator would hold it to the end
        if self._closed:
            return
        self._thread = threading.Thread(target=self._decode, name=f"lptrack-read-{self.path.name}",
                                        daemon=True)
        self._thread.start()
        while True:
            item = self._queue.get()
            self._slots.release()
            if item is _END:
                return
            if isinstance(item, BaseException):
                raise VideoError(f"reading '{self.path}' failed after frame {index}: {item}") from item
            frame, stamp, number = item
            del item
            if number > index + 1:
                self.undecodable.append((index + 1, number - index - 1))
            index = number
            yield index, self.time_of(index, stamp), frame

    def _decode(self) -> None:
        """Background thread: decode frames into the bounded queue until the end or :meth:`close`.

        Once started, the thread owns the capture and releases it as it ends, so that a :meth:`close` whose
        wait is interrupted (Ctrl-C) can neither release it mid-read nor leave it open."""
        number = self.start_frame + 1
        try:
            while self._free_slot():
                grabbed = self._grab_next(number)
                ok, frame = self._cap.retrieve() if grabbed is not None else (False, None)
                if not ok or frame is None:
                    break
                self._queue.put((frame, self._stamp(), grabbed))
                del frame  # the queue holds it; the consumer's taking it frees the slot
                number = grabbed + 1
            else:  # stopped by close(): nobody waits for the end
                return
        except Exception as exc:  # noqa: BLE001 - handed to the consumer, which raises it as a VideoError
            self._queue.put(exc)
            return
        finally:
            self._cap.release()
        self._queue.put(_END)

    def _free_slot(self) -> bool:
        """Wait until a frame may be decoded ahead (see ``read_ahead``); False once :meth:`close` stops the
        thread."""
        while not self._stop.is_set():
            if self._slots.acquire(timeout=0.05):
                return True
        return False

    def _join_decoder(self) -> None:
        # A stop signal (Ctrl-C, SIGTERM) can land while Thread.start() waits for the new thread to say it runs:
        # start() is then left by the exception, the thread runs all the same, and join() refuses ("cannot join
        # thread before it is started") until it has said so, a moment later. Seen once in CI, as a traceback
        # and exit 1 instead of 143.
        deadline = time.monotonic() + 5.0
        while True:
            try:
                self._thread.join()
                return
            except RuntimeError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.001)

    def close(self) -> None:
        """Stop the decoding thread and release the file. Safe to call more than once."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        self.first_frame = None
        if self._thread is None:
            self._cap.release()
        else:
            self._join_decoder()  # the thread releases the capture
        # Drop frames still queued so their memory is freed now.
        while True:
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break


#: Frames in a row that fail to decode after which a video is taken to end there (cut short, though its container
#: announces more) rather than to be damaged: a failed read at the end of a file takes 10-20 us.
MAX_UNDECODABLE_RUN = 250


def _past_the_end(start_frame: int, path: Path, n_frames: int) -> FrameRangeError:
    valid = "0" if n_frames == 1 else f"from 0 to {n_frames - 1}"
    return FrameRangeError(f"start frame {start_frame} lies past the end of '{path}', which has "
                           f"{counted(n_frames, 'frame')}; give a start frame {valid}")


@dataclass(frozen=True)
class Frame:
    """One decoded frame and where it is in its video.

    Attributes
    ----------
    image : ndarray
        BGR uint8, shape (height, width, 3), as OpenCV decodes it.
    index : int
        Frame index in the file (0 = first frame).
    time_s : float
        Time in seconds: ``index / fps``, or for a video whose frame rate varies its timestamp
        (:meth:`VideoReader.time_of`).
    fps : float
        Frame rate the container reports (25 if it reports none; then ``fps_guessed``).
    fps_guessed : bool
    path : Path
    """

    image: np.ndarray
    index: int
    time_s: float
    fps: float
    fps_guessed: bool
    path: Path

    @property
    def width(self) -> int:
        return int(self.image.shape[1])

    @property
    def height(self) -> int:
        return int(self.image.shape[0])


def count_frames(path) -> int:
    """Number of frames of ``path``, by decoding it completely (exact; container counts can be wrong). Frames that
    could not be decoded in a damaged stretch count, as they keep their numbers (:class:`VideoReader`)."""
    with VideoReader(path) as reader:
        last = -1
        for last, _, _ in reader:
            pass
        return last + 1


def read_frame(path, index: int | None = None, *, time_s: float | None = None, fps: float | None = None) -> Frame:
    """Exactly the ``index``-th decoded frame of a video (or the frame shown at ``time_s`` seconds).

    Parameters
    ----------
    path : str or Path
        Video file, or an image sequence's pattern (``frames/%04d.png``).
    index : int, optional
        Frame index, 0 = first frame of the file. Default 0.
    time_s : float, optional
        Instead of ``index``: time in seconds; the frame whose time, as a run's CSV gives it (``index / fps``, or
        a varying frame rate's timestamps), is nearest, or the last frame for a time within its time on screen.
    fps : float, optional
        Frames per second instead of the video's own (an image sequence has none), as ``lptrack run --fps``.

    Returns
    -------
    Frame

    Raises
    ------
    VideoError
        Missing or unreadable video.
    UsageError
        Negative index or time, both given, or a frame past the end (the message gives the valid range).

    Notes
    -----
    The frames before ``index`` are decoded and dropped (``VideoReader(start_frame=...)``), never skipped
    with ``CAP_PROP_POS_FRAMES``, whose seeking lands on a nearby key frame with some codecs: the result is
    the same pixels as reading the video from the start, at the cost of decoding ``index`` frames
    (~2,000 frames/s for 640x480 mp4v).
    """
    if index is not None and time_s is not None:
        raise UsageError("give a frame index or a time, not both")
    path = Path(path)
    if time_s is not None:
        if not (is_real(time_s) and math.isfinite(time_s) and time_s >= 0):
            raise UsageError(f"time must be a number of seconds >= 0, got {time_s!r}")
        return _frame_at_time(path, time_s, fps)
    index = 0 if index is None else index
    check_frame_number(index, "frame index")  # 1.5 was frame 1, '3' frame 3
    index = int(index)
    try:
        reader = VideoReader(path, start_frame=index, read_ahead=1, fps=fps)
    except VideoError:
        if index == 0:
            raise
        n = count_frames(path)  # raises the video's own error if it is unreadable
        if index < n:  # the video became unreadable half-way: say so rather than blame the index
            raise
        raise FrameRangeError(f"frame {index} lies past the end of '{path}', which has {counted(n, 'frame')}: "
                              f"give a frame from 0 to {n - 1}") from None
    with reader:
        _, time_s, image = next(iter(reader))  # its time as a run's CSV gives it (a varying rate's timestamp)
        return Frame(image.copy(), index, time_s, reader.fps, reader.fps_guessed, path)


def _frame_at_time(path: Path, time_s: float, fps: float | None) -> Frame:
    """The frame whose time (as a run's CSV gives it: ``index / fps``, or a varying rate's timestamp) is nearest
    ``time_s`` (of two as near, the later), or the last frame for a time within its time on screen."""
    with VideoReader(path, fps=fps) as reader:
        previous = None
        for index, time_i, image in reader:
            if time_i >= time_s:
                # Within a microsecond is a tie: 0.06 s at 25 fps is as near frame 1 (0.04) as frame 2 (0.08), but
                # 0.06 - 0.04 comes out below 0.08 - 0.06 in floating point, and the earlier frame was taken.
                if previous is not None and (time_i - time_s) - (time_s - previous[1]) > 1e-6:
                    index, time_i, image = previous
                return Frame(image.copy(), index, time_i, reader.fps, reader.fps_guessed, path)
            previous = index, time_i, image
        index, time_i, image = previous
        end = time_i + 1.0 / reader.fps  # the last frame shows until then
        if time_s < end:
            return Frame(image.copy(), index, time_i, reader.fps, reader.fps_guessed, path)
        n = index + 1
        raise FrameRangeError(f"time {time_s:g} s lies past the end of '{path}', which has {counted(n, 'frame')} "
                              f"(at {reader.fps:g} fps): give a time before {end:.3f} s or a frame from 0 to "
                              f"{n - 1}")


def keep_frames_off_the_heap(threshold_bytes: int = 10 << 20) -> None:
    """Fix glibc's mmap threshold so that 4K frame buffers are returned to the system when freed.

    glibc raises the threshold after each large block is freed, up to 32 MB, so after the first few frames a
    4K video's buffers (25 MB BGR, 33 MB float grey, 12 MB YUV in the codec) come from the heap, which
    fragments and kept peak memory 40-60 MB higher on a 4K run. The threshold is fixed at 10 MB, above a
    1080p float frame (8.3 MB): a lower one (1 MB, measured) maps and unmaps every smaller per-frame array
    and halved the thesis trackers' speed at 640x480. Process-wide, so called by the processes lptrack owns
    (the CLI, batch workers), not on import. No effect outside glibc.
    """
    name = ctypes.util.find_library("c")
    if not name or os.environ.get("MALLOC_MMAP_THRESHOLD_"):
        return
    try:
        libc = ctypes.CDLL(name)
        libc.mallopt(-3, threshold_bytes)  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):
        pass  # not glibc (musl, macOS): nothing to tune


def _fourcc_text(code: str) -> int:
    return cv2.VideoWriter_fourcc(*code)


@contextlib.contextmanager
def _fd2_silenced():
    """Discard what C code prints on file descriptor 2 meanwhile. OpenCV's FFmpeg writer prints notes such as
    "tag 'VP80' is not supported with ... 'webm'" (the file is written all the same) straight to it, past its
    log level; whether a writer opened is checked, and reported, by its caller."""
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all
        yield
        return
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _fourcc(capture: cv2.VideoCapture) -> str:
    """The codec of an open capture as four characters ('' when it reports none)."""
    code = int(capture.get(cv2.CAP_PROP_FOURCC)) & 0xFFFFFFFF
    return bytes((code >> shift) & 0xFF for shift in (0, 8, 16, 24)).decode("latin-1").strip("\0 ")


class VideoWriter:
    """An annotated video written atomically, with codec fallback.

    Parameters
    ----------
    path : str or Path
        Wanted output file. Its extension chooses the codecs tried (:data:`CODECS_BY_EXTENSION`); if none of
        them works the last fallback may write a different extension (e.g. ``.avi``): see :attr:`path`.
    fps : float
        Frame rate to record, in frames per second (pass the input's, unrounded).
    overwrite : bool, optional
        Replace an existing file. Otherwise an existing output raises :class:`OutputError`.

    Attributes
    ----------
    path : Path
        Where the finished video is (or will be) -- the wanted path unless a fallback changed the extension.
    fourcc : str or None
        Codec used, e.g. ``"mp4v"``; None until the first frame is written.
    frames_written : int
        Frames accepted by :meth:`write` (handed to the encoding thread; an encoding error is raised by the
        next :meth:`write` or by :meth:`close`).

    Raises
    ------
    OutputError
        From the constructor if the folder is missing/unwritable, the file exists (without ``overwrite``) or
        the extension is not supported; from :meth:`write` if no codec can be opened or a frame has a
        different size than the first.

    Notes
    -----
    Frames go to a hidden temporary file in the same folder (:func:`temporary_path`), renamed to
    :attr:`path` by :meth:`close`. :meth:`abort` (and leaving a ``with`` block by an exception) deletes it.

    Frames are encoded in a background thread (OpenCV releases the GIL while it encodes), one frame behind the
    caller: :meth:`write` waits for the previous frame to be encoded, hands the new one over and returns. A frame
    passed to :meth:`write` must therefore not be modified afterwards; pass a copy if you will reuse its buffer.
    """

    def __init__(self, path, fps: float, *, overwrite: bool = False):
        wanted = Path(path)
        suffix = wanted.suffix.lower()
        # Arguments it cannot take are a UsageError, as run_video's own check of them says.
        if suffix not in CODECS_BY_EXTENSION:
            raise UsageError(f"cannot write output video '{wanted}': unsupported extension '{wanted.suffix}'; "
                             f"use one of {', '.join(CODECS_BY_EXTENSION)}")
        if not (is_real(fps) and math.isfinite(fps) and fps > 0):
            raise UsageError(f"cannot write output video '{wanted}': frame rate must be > 0, got {fps!r}")
        if fps < MIN_VIDEO_FPS:  # refused now, not after the whole run was tracked
            raise UsageError(f"cannot write output video '{wanted}': {fps:g} frames/s is below the "
                             f"{MIN_VIDEO_FPS:g} the video encoders take; give a higher --fps, or --no-video")
        self.path = check_output_path(wanted, overwrite=overwrite, what="output video")
        self.wanted_path = self.path
        self.fps = float(fps)
        self.overwrite = overwrite
        self.fourcc: str | None = None
        self.frames_written = 0
        self.size: tuple[int, int] | None = None
        self._writer = None
        self._temp: Path | None = None
        self._closed = False
        self._encoder: _Encoder | None = None

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def _open(self, width: int, height: int) -> None:
        opencv_path(self.wanted_path, "output video", OutputError)  # its temporary name shares the name's stem
        if not self.wanted_path.parent.is_dir():  # removed since it was checked: OpenCV would say no codec opens
            raise OutputError(f"cannot write output video '{self.wanted_path}': folder '{self.wanted_path.parent}' "
                              f"does not exist (removed after the run started)")
        tried = []
        for code, extension in CODECS_BY_EXTENSION[self.wanted_path.suffix.lower()]:
            target = self.wanted_path.with_suffix(extension) if extension != self.wanted_path.suffix.lower() \
                else self.wanted_path
            if code == "MJPG" and width * height < MJPG_MIN_PIXELS:
                tried.append(f"{code}{extension} (a frame under {MJPG_MIN_PIXELS} pixels)")
                continue
            if target != self.wanted_path and target.exists() and not self.overwrite:
                tried.append(f"{code}{extension} ({target.name} exists)")
                continue
            # Known before the file exists, so that abort() deletes it even if a stop signal comes meanwhile.
            temp = self._temp = temporary_path(target)
            with _fd2_silenced():
                writer = cv2.VideoWriter(str(temp), _fourcc_text(code), self.fps, (width, height), True)
            if writer.isOpened():
                self._writer, self.path, self.fourcc = writer, target, code
                self.size = (width, height)
                self._encoder = _Encoder(writer, f"lptrack-write-{target.name}")
                return
            writer.release()
            temp.unlink(missing_ok=True)
            tried.append(f"{code}{extension}")
        raise OutputError(f"cannot write output video '{self.wanted_path}': no codec could be opened "
                          f"(tried {', '.join(tried)})")

    def write(self, frame: np.ndarray) -> None:
        """Append one BGR uint8 frame; the first frame fixes the video's size. An odd width or height is
        padded by one column or row (its last one repeated) to the even size the codecs need."""
        if self._closed:
            raise RuntimeError("VideoWriter is closed")
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        height, width = frame.shape[:2]
        if height % 2 or width % 2:
            # The codecs store colour at half resolution (4:2:0) and OpenCV dropped an odd last row and column
            # (641x479 became 640x478); padded instead, as FFmpeg users do (pad=ceil(iw/2)*2:ceil(ih/2)*2), every
            # pixel stays where it was.
            frame = cv2.copyMakeBorder(frame, 0, height % 2, 0, width % 2, cv2.BORDER_REPLICATE)
            height, width = frame.shape[:2]
        if self._writer is None:
            self._open(width, height)
        elif (width, height) != self.size:
            raise OutputError(f"cannot write output video '{self.path}': frame {self.frames_written} is "
                              f"{width}x{height}, the video is {self.size[0]}x{self.size[1]}")
        self._encoder.put(np.ascontiguousarray(frame, dtype=np.uint8))
        self._raise_failure()
        self.frames_written += 1

    def _raise_failure(self) -> None:
        failure = self._encoder.failure if self._encoder is not None else None
        if failure is not None:
            raise OutputError(f"cannot write output video '{self.path}': {failure}") from failure

    def close(self) -> Path | None:
        """Finish the video and move it to :attr:`path`; returns that path (None if no frame was written).

        Raises
        ------
        OutputError
            If the finished file cannot be moved into place (the temporary file is then deleted).
        """
        if self._closed:
            return self.path if self.frames_written else None
        self._closed = True
        if self._writer is None:
            return None
        self._encoder.finish()
        self._writer.release()
        with written_into_place(self.path, overwrite=self.overwrite, what="output video", temp=self._temp):
            self._raise_failure()
            if not self._temp.exists() or self._temp.stat().st_size == 0:
                raise OutputError(f"cannot write output video '{self.path}': the {self.fourcc} encoder produced "
                                  f"no data")
            self._check_readable()
        return self.path

    def _check_readable(self) -> None:
        """Raise :class:`OutputError` unless the finished temporary file opens as a video whose last frame can be
        read.

        OpenCV's writer reports no failed write: a disk that fills up mid-run leaves an MP4 without its index
        ("moov atom not found") or an AVI whose header says it holds no frames (FFmpeg still seeks in it, to
        what is there), which must not be renamed into place as if finished. A file cut short elsewhere fails to
        seek to its last frame. Costs one seek and the decoding of up to a key-frame interval (0.03 s for 1,500
        frames of mp4v or MKV, 0.14 s for WebM).
        """
        with _fd2_silenced():
            capture = cv2.VideoCapture(str(self._temp))
            try:
                opened = capture.isOpened()
                count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) if opened else 0
                last = opened and capture.set(cv2.CAP_PROP_POS_FRAMES, self.frames_written - 1) and capture.grab()
            finally:
                capture.release()
        # One frame less than written is allowed in the count, which a container may estimate from the duration
        # (but not none of a frame or more: a full disk's AVI says 0).
        short = count < max(self.frames_written - 1, 1)
        if not (last and not short):
            read = (f"holds {max(count, 0)} frames by its header" if opened and short
                    else "cannot be read to its last frame" if opened else "cannot be read back")
            raise OutputError(f"cannot write output video '{self.path}': the finished file {read}, of the "
                              f"{self.frames_written} written (is the disk full?)")

    def abort(self) -> None:
        """Stop writing and delete the temporary file; nothing is left behind. Safe to call more than once."""
        self._closed = True
        try:
            # A stop signal may land in _open between the writer and its encoder being set: either may be unset.
            # An encoder that did not stop is left with its writer: releasing the writer under it crashes.
            stopped = self._encoder is None or self._encoder.finish(discard=True)
            if self._writer is not None and stopped:
                self._writer.release()
                self._writer = None
        finally:  # even if a second Ctrl-C interrupts the wait for the encoder
            if self._temp is not None:
                self._temp.unlink(missing_ok=True)

    def __del__(self) -> None:
        # A writer dropped without close() or abort() (Python API use) must not keep its thread, encoder and
        # temporary file for the life of the process.
        if not getattr(self, "_closed", True):  # False only once __init__ has run
            try:
                self.abort()
            except Exception:  # noqa: BLE001 - nothing can be reported from a finaliser
                pass


#: How often (seconds) a caller waiting for the encoder to stop wakes it again, and how long an abort waits for it.
_WAKE_EVERY_S = 0.25
_ABANDON_AFTER_S = 5.0


class _Encoder:
    """A ``cv2.VideoWriter`` fed from a daemon thread, one frame at a time.

    The thread holds only the queue, the OpenCV writer and this object, never the :class:`VideoWriter`, so a
    dropped VideoWriter can still be finalised. Completion is signalled with an Event rather than learnt by
    ``Thread.join``: a join interrupted by Ctrl-C reports the thread as finished while it may still be
    encoding, and releasing the OpenCV writer under it crashes the process.
    """

    def __init__(self, writer: cv2.VideoWriter, name: str):
        self.failure: BaseException | None = None
        self.done = threading.Event()
        # The caller waits for the previous frame before handing over the next (see put): a frame waiting
        # besides the one being encoded would cost another frame of memory (25 MB at 4K) and buy nothing while
        # encoding is the faster side.
        self._frames: queue.Queue = queue.Queue(maxsize=1)
        threading.Thread(target=self._run, args=(self._frames, writer), name=name, daemon=True).start()

    def _run(self, frames: queue.Queue, writer: cv2.VideoWriter) -> None:
        try:
            while True:
                frame = frames.get()
                if frame is _END:
                    return
                if self.failure is None:
                    try:
                        writer.write(frame)
                    except Exception as exc:  # noqa: BLE001 - raised in the caller's thread by VideoWriter
                        self.failure = exc
                del frame  # before task_done, so that a waiting caller finds its memory freed
                frames.task_done()
        finally:
            self.done.set()

    def put(self, frame: np.ndarray) -> None:
        """Hand one frame over, once the previous one is encoded."""
        self._frames.join()
        self._frames.put(frame)

    def finish(self, *, discard: bool = False) -> bool:
        """Encode the frame handed over (or drop it if ``discard``) and stop the thread; safe to repeat. Whether
        the thread has stopped: with ``discard`` (an abort) it is waited for ``_ABANDON_AFTER_S`` at most, then
        left (a daemon thread, ended with the process), so that a stop never hangs."""
        if discard:
            try:
                self._frames.get_nowait()
            except queue.Empty:
                pass
        give_up_at = time.monotonic() + _ABANDON_AFTER_S if discard else math.inf
        # Both waits wake the encoder again now and then: a stop signal raised in a thread inside the queue's
        # hand-over (between an item going in and the encoder being told) can leave the encoder asleep beside its
        # item, and `lptrack run` stopped by a signal hung in about 1 run in 25 (encoder in get(), caller here).
        # Waking it when it is busy is harmless.
        while not self.done.is_set():
            try:
                self._frames.put(_END, timeout=_WAKE_EVERY_S)
                break
            except queue.Full:
                if not self._wake_before(give_up_at):
                    return False
        while not self.done.wait(_WAKE_EVERY_S):
            if not self._wake_before(give_up_at):
                return False
        return True

    def _wake_before(self, give_up_at: float) -> bool:
        """Wake the encoding thread, unless ``give_up_at`` (``time.monotonic()`` seconds) has passed."""
        if time.monotonic() >= give_up_at:
            return False
        with self._frames.not_empty:
            self._frames.not_empty.notify()
        return True
