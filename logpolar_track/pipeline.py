"""The one place that joins reader -> tracker -> drawing -> writers for one video.

:func:`track_video` yields a :class:`~logpolar_track.results.FrameResult` per frame (a library call, no
files written); :func:`run_video` does what ``lptrack run`` does: tracks, writes the annotated video and the
CSV atomically, and returns a :class:`RunSummary`. The names of a run's files are here too: its outputs
(:func:`default_outputs`), its ROI sidecar (:func:`roi_sidecar_paths`), and back from a run CSV to the video it
was made from (:func:`find_video_for_csv`).
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Sequence, Union

import numpy as np

from .draw import draw_state
from .errors import LptrackError, OutputError, RoiError, UsageError
from .executor import TRACKING_OPENCV_THREADS, opencv_threads
from .evaluate import stream_name_places
from .geometry import ROI_SYNTAX, Ellipse, as_ellipse, check_roi_fits, parse_roi
from .images import within_0_255
from .results import CsvWriter, FrameResult, decode_text
from .trackers import DEFAULT_TRACKER, Tracker, create_tracker
from .outputs import check_output_path, writes_in_place
from .video import (CODECS_BY_EXTENSION, VIDEO_EXTENSIONS, VideoReader, VideoWriter, check_frame_number,
                    frames_to_track, guess_image_sequence, image_sequence_files, is_image_sequence,
                    video_stem)

#: Suffixes appended to the video's stem for the default output names.
VIDEO_OUT_SUFFIX = ".lptrack.mp4"
CSV_OUT_SUFFIX = ".lptrack.csv"

RoiLike = Union[Ellipse, str, Sequence[float], None]
ProgressLike = Union[bool, Callable[[int, "int | None"], None], None]


def default_outputs(video_path, folder=".", name: str | None = None) -> tuple[Path, Path]:
    """Default ``(video_out, csv_out)`` for ``video_path``: ``<stem>.lptrack.mp4`` / ``.csv`` in ``folder``
    (:func:`~logpolar_track.video.video_stem`: ``frame`` for an image sequence ``frame_%04d.png``), or named after
    ``name`` instead of the stem."""
    stem = video_stem(video_path) if name is None else name
    folder = Path(folder)
    return folder / f"{stem}{VIDEO_OUT_SUFFIX}", folder / f"{stem}{CSV_OUT_SUFFIX}"


def _video_stem(csv_path: Path) -> str:
    """``clip`` for ``clip.lptrack.csv``, ``clip.lptrack.jsonl`` (``lptrack run``'s default names) or ``clip.csv``."""
    for suffix in (CSV_OUT_SUFFIX, ".lptrack.jsonl"):
        if csv_path.name.endswith(suffix) and len(csv_path.name) > len(suffix):
            return csv_path.name[:-len(suffix)]
    return csv_path.stem


def _video_search(csv_path, folders: Sequence) -> tuple[str, list[tuple[Path, list[Path]]]]:
    """The stem looked for, and each folder searched (each once, in order) with the videos found there."""
    csv_path = Path(csv_path)
    stem = _video_stem(csv_path)
    searched, seen = [], set()
    for folder in [csv_path.parent, *map(Path, folders)]:
        key = folder.resolve()
        if key in seen:
            continue
        seen.add(key)
        found = [folder / f"{stem}{ext}" for ext in VIDEO_EXTENSIONS if (folder / f"{stem}{ext}").is_file()]
        # 'lptrack run img/%04d.jpg' names its CSV after the folder, img.lptrack.csv (OTB's layout).
        sequence = guess_image_sequence(folder / stem) if (folder / stem).is_dir() else None
        searched.append((folder, found + ([sequence] if sequence is not None else [])))
    return stem, searched


def find_video_for_csv(csv_path, folders: Sequence = (".",)) -> Path | None:
    """The video a run CSV was made from, when that is obvious; else None.

    A run CSV does not name its video. ``<stem>.lptrack.csv`` (``lptrack run``'s default name; or
    ``<stem>.lptrack.jsonl``) or ``<stem>.csv`` is matched with ``<stem>`` plus one of
    :data:`~logpolar_track.video.VIDEO_EXTENSIONS`, or with a folder ``<stem>`` of numbered images (as an
    image-sequence pattern, ``img/%04d.jpg`` for ``img.lptrack.csv``), in the CSV's folder, then in ``folders``; the
    first folder with exactly one such source wins. Annotated outputs (``*.lptrack.*``) are never chosen.
    :func:`describe_video_search` says why none was found.
    """
    for _, found in _video_search(csv_path, folders)[1]:
        if len(found) == 1:
            return found[0]
    return None


def find_streamed_video(name: str | None, stream) -> Path | None:
    """The video a batch's stream names for its rows (``name``, its ``video`` column, the path as ``lptrack run`` was
    given it), found from the current folder or, where it is relative, from the folder of the file ``stream``
    (the run may have been started there); None if it is not found (or ``name`` is None)."""
    if not name:
        return None
    for place in stream_name_places(name, stream):
        # An image-sequence pattern is taken only with images to read, as find_video_for_csv takes a folder.
        if place.is_file() or (is_image_sequence(place) and image_sequence_files(place)):
            return place
    return None


def describe_video_search(csv_path, folders: Sequence = (".",)) -> str:
    """Where :func:`find_video_for_csv` looked for the video of ``csv_path`` and why it took none, as a phrase
    for a message (``no clip.mp4 (or .avi, ...) in 'runs' or the current folder``)."""
    stem, searched = _video_search(csv_path, folders)
    here = Path.cwd().resolve()

    def place(folder: Path) -> str:
        return "the current folder" if folder.resolve() == here else f"'{folder}'"

    several = [(folder, found) for folder, found in searched if len(found) > 1]
    if several:
        folder, found = several[0]
        names = ", ".join(str(p.relative_to(folder)) for p in found)  # img/%04d.jpg for a sequence
        return f"{place(folder)} holds several videos it could be ({names})"
    others = ", ".join(VIDEO_EXTENSIONS[1:6]) + ", ..."
    return (f"no {stem}{VIDEO_EXTENSIONS[0]} (or {others}, or a folder {stem}/ of numbered images) in "
            f"{' or '.join(place(f) for f, _ in searched)}")


def mirrored_path(path) -> Path:
    """``path`` as ``cp --parents`` names a copy under a folder, but never a step out of it: as given when it is
    relative and, once ``.`` and ``..`` are taken out of it, does not go up (``./cams/day1/cam.mp4`` and
    ``cams/x/../day1/cam.mp4`` -> ``cams/day1/cam.mp4``), else its absolute path without the root (``../cams/cam.mp4``
    from ``/home/me/work`` -> ``home/me/cams/cam.mp4``). It depends on that path alone,
    not on the other inputs of a run, so outputs land in the same place however a list of videos is split
    between runs (``xargs``, ``parallel``)."""
    path = Path(os.path.normpath(path))  # lexically, as cp does: 'cams/../b/c.mp4' is 'b/c.mp4'
    if not path.is_absolute() and path.parts[:1] != ("..",):
        return path
    absolute = Path(os.path.abspath(path))
    return absolute.relative_to(absolute.anchor)


def roi_sidecar_paths(video_path) -> list[Path]:
    """Where an initial-ROI sidecar of ``video_path`` may be: ``<stem>.roi``, then ``<file name>.roi``; for an
    image sequence, ``<stem>.roi`` in its folder (``frame.roi`` for ``frame_%04d.png``)."""
    video_path = Path(video_path)
    if is_image_sequence(video_path):
        return [video_path.with_name(video_stem(video_path) + ".roi")]
    return [video_path.with_suffix(".roi"), video_path.with_name(video_path.name + ".roi")]


def read_roi_text(path) -> str:
    """The text of a ROI file (a sidecar or a ``--roi-file``): UTF-8, with or without a byte-order mark, or UTF-16
    with one (what Windows PowerShell 5's ``echo 320,240,40 > clip.roi`` writes).

    Raises
    ------
    LptrackError
        The file cannot be read, or is not such text (exit code 1).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise LptrackError(f"cannot read ROI file '{path}': {exc.strerror or exc}") from None
    return decode_roi_text(data, f"ROI file '{path}'")


def decode_roi_text(data: bytes, source: str) -> str:
    """``data`` of a ROI file as :func:`read_roi_text` reads it; ``source`` names it in the message.

    Raises
    ------
    LptrackError
        It is not such text (exit code 1).
    """
    try:
        return decode_text(data)
    except UnicodeDecodeError:
        raise LptrackError(f"cannot read {source}: it is not text in UTF-8 (nor UTF-16 with a byte-order mark); "
                           f"save it as UTF-8") from None


def read_roi_sidecar(video_path) -> Ellipse | None:
    """The initial ROI stored next to a video, or None if there is no sidecar.

    The sidecar is ``<folder>/<stem>.roi`` (e.g. ``spin.roi`` for ``spin.mp4``) or ``<video file name>.roi``
    (``spin.mp4.roi``): one line in ``--roi`` syntax, UTF-8 or UTF-16 (see :func:`read_roi_text`). ``#`` starts a
    comment, to the end of its line; blank lines are ignored.

    Raises
    ------
    LptrackError
        A sidecar exists but cannot be read (exit code 1).
    RoiError
        If a sidecar exists but does not hold exactly one valid ROI, or both sidecars exist and disagree (the
        message names the files).
    """
    found: list[tuple[Path, Ellipse]] = []
    for candidate in roi_sidecar_paths(video_path):
        if not candidate.is_file():
            continue
        text = read_roi_text(candidate)
        lines = [(n, ln.split("#", 1)[0].strip()) for n, ln in enumerate(text.splitlines(), start=1)]
        lines = [(n, ln) for n, ln in lines if ln]
        if not lines:
            raise RoiError(f"ROI file '{candidate}' is empty; write one line {ROI_SYNTAX}")
        if len(lines) > 1:
            raise RoiError(f"ROI file '{candidate}' holds {len(lines)} lines (lines "
                           f"{', '.join(str(n) for n, _ in lines)}); write one line {ROI_SYNTAX}")
        try:
            found.append((candidate, parse_roi(lines[0][1])))
        except RoiError as exc:
            raise RoiError(f"ROI file '{candidate}': {exc}") from None
    if len(found) == 2 and found[0][1] != found[1][1]:
        (first, a), (second, b) = found
        raise RoiError(f"ROI files '{first}' ({a.to_spec()}) and '{second}' ({b.to_spec()}) disagree; keep one, "
                       f"or give --roi ('{first.name}' serves every video named '{first.stem}.*': to keep it to "
                       f"one, name it after that video's file name, as '{second.name}' is)")
    return found[0][1] if found else None


def resolve_roi(roi: RoiLike, video_path) -> Ellipse:
    """``roi`` as an :class:`Ellipse`, or, when it is None, the video's ``.roi`` sidecar's (see
    :func:`roi_sidecar_paths`); a :class:`UsageError` naming the sidecars looked for when there is none."""
    if roi is not None:
        return as_ellipse(roi)
    found = read_roi_sidecar(video_path)
    if found is None:
        # Paths, not names: an image sequence's sidecar is in its images' folder, named after the pattern.
        names = " or ".join(f"'{p}'" for p in roi_sidecar_paths(video_path))
        raise UsageError(f"no ROI given for '{video_path}': give --roi {ROI_SYNTAX}, or put one such line "
                         f"in {names}")
    return found


#: Levels (standard deviation, see roi_spread) under which a ROI on its start frame holds nothing to follow,
#: measured over the ROI enlarged FLAT_ROI_EXTENT times: a plain ball is flat inside, and its outline is what
#: trackers follow.
FLAT_ROI_SPREAD, FLAT_ROI_EXTENT = 1.0, 1.5


def roi_spread(frame: np.ndarray, roi: Ellipse) -> float:
    """Standard deviation in levels (0 to 255) of ``frame`` inside ``roi``'s ellipse, the largest of its colour
    channels' (a red ball on green felt is one grey): about 0 for a flat region (a letterbox bar, a blank wall),
    where no tracker finds anything to follow."""
    height, width = frame.shape[:2]
    x, y, w, h = roi.bounding_box()
    x0, y0 = max(int(math.floor(x)), 0), max(int(math.floor(y)), 0)
    x1, y1 = min(int(math.ceil(x + w)) + 1, width), min(int(math.ceil(y + h)) + 1, height)
    if x1 <= x0 or y1 <= y0:
        return 0.0
    # Every pixel of a small ROI; at most about 256 x 256 of a large one (a 4K frame's whole-frame ROI would
    # otherwise take a few hundred MB of index arrays).
    stride = max(1, math.ceil(max(x1 - x0, y1 - y0) / 256))
    ys, xs = np.mgrid[y0:y1:stride, x0:x1:stride]
    inside = roi.contains(xs, ys)
    if not inside.any():
        return 0.0
    region = frame[y0:y1:stride, x0:x1:stride]
    pixels = within_0_255(region[inside]) if frame.dtype != np.uint8 else region[inside]
    return float(np.asarray(pixels, np.float64).reshape(len(pixels), -1).std(axis=0).max())


def _make_tracker(tracker: str | Tracker, params: dict | None) -> Tracker:
    if isinstance(tracker, Tracker):
        if params:
            raise UsageError("tracker_params apply only when the tracker is given by name")
        return tracker
    return create_tracker(str(tracker), **(params or {}))


def _track(reader: VideoReader, roi: Ellipse, tracker: Tracker,
           max_frames: int | None = None) -> Iterator[tuple[np.ndarray, FrameResult]]:
    """Core loop shared by :func:`track_video` and :func:`run_video`: yields ``(frame, result)``."""
    check_roi_fits(roi, reader.width, reader.height, source=reader.path.name)
    frames = iter(reader)
    index, t, frame = next(frames)
    yield frame, FrameResult(index, t, tracker.init(frame, roi), "init")
    for done, (index, t, frame) in enumerate(frames, start=1):
        if max_frames is not None and done >= max_frames:
            break
        ok, state = tracker.update(frame)
        yield frame, FrameResult(index, t, state, "tracked" if ok else "lost")


def track_video(path, roi: RoiLike = None, tracker: str | Tracker = DEFAULT_TRACKER, *, start_frame: int = 0,
                max_frames: int | None = None, tracker_params: dict | None = None,
                fps: float | None = None) -> Iterator[FrameResult]:
    """Track one object through a video; yields one :class:`FrameResult` per frame, the first with status
    ``init``.

    Parameters
    ----------
    path : str or Path
        Video file.
    roi : Ellipse, str or sequence of float, optional
        The object on the start frame: an :class:`Ellipse`, text ``cx,cy,r`` / ``cx,cy,a,b,angle`` (pixels;
        angle in degrees counter-clockwise on screen), or those 3 or 5 numbers
        (:func:`~logpolar_track.geometry.as_ellipse`). If None, read from the video's ``.roi`` sidecar
        (:func:`read_roi_sidecar`).
    tracker : str or Tracker
        A registered tracker name (:func:`~logpolar_track.trackers.tracker_names`) or a Tracker instance.
    start_frame : int
        Index of the frame the ROI is drawn on; tracking starts there. ``FrameResult.frame`` counts from the
        start of the file.
    max_frames : int, optional
        Stop after this many frames (the start frame included); None: to the end of the video.
    tracker_params : dict, optional
        Keyword tuning parameters for a tracker given by name.
    fps : float, optional
        Frames per second for ``time_s`` instead of the video's own rate (an image sequence has none: 25 is
        assumed), as FFmpeg's ``-framerate``.

    Raises
    ------
    UsageError
        Unknown tracker, bad tracker parameters, or no ROI and no sidecar.
    RoiError
        Malformed ROI, or one that does not fit the frame (centre outside, mostly outside, too small).
    VideoError
        Missing file, not a video, no frames, start frame past the end.

    Notes
    -----
    A generator: nothing is opened until the first result is requested, and the video is released when the
    generator is closed or exhausted.
    """
    engine = _make_tracker(tracker, tracker_params)
    _check_max_frames(max_frames)
    with VideoReader(path, start_frame=start_frame, fps=fps) as reader:
        for _, result in _track(reader, resolve_roi(roi, path), engine, max_frames):
            yield result


@dataclass(frozen=True)
class RunSummary:
    """What :func:`run_video` did.

    Attributes
    ----------
    video : Path
        Input video.
    tracker : str
        Tracker name.
    frames, lost : int
        Frames processed (including the init frame) and how many of them were lost.
    start_frame : int
    processing_fps : float
        Frames per second of the whole loop (decode, track, draw, write), wall clock.
    seconds : float
        Wall-clock time of the loop.
    video_fps : float
        The input's frame rate (also the output's); ``video_fps_guessed`` if the container reported none.
    width, height : int
        Frame size in pixels.
    video_out : Path or None
        Annotated video actually written (its extension may differ from the one asked for if a fallback
        codec was needed).
    fourcc : str or None
        Codec of ``video_out``.
    csv_out : str or None
        CSV path, ``'-'`` for stdout, or None.
    expected_frames : int
        Frames from the start frame to the end (or ``max_frames`` if fewer) as the container announces them
        (0 when it does not say). Fewer ``frames`` and ``undecodable_frames`` than this means the video ended
        early (truncated file).
    undecodable : tuple of (int, int)
        Stretches of frames that could not be decoded (a file damaged there), as ``(first frame, count)``: they
        have no row, and tracking went on after them (:attr:`VideoReader.undecodable
        <logpolar_track.video.VideoReader.undecodable>`).
    image_gaps : tuple of (int, str, str)
        An image sequence's skipped numbers, ``(frame, image before, image after)`` (:attr:`VideoReader.image_gaps
        <logpolar_track.video.VideoReader.image_gaps>`).
    timestamps_from : int or None
        A variable frame rate: the first frame whose ``time_s`` is the stream's timestamp rather than ``frame /
        fps`` (:meth:`~logpolar_track.video.VideoReader.time_of`); None for a constant one.
    roi_flat : bool
        The ROI held a flat region on the start frame, its outline and surround included (:func:`roi_spread`
        of the ROI enlarged :data:`FLAT_ROI_EXTENT` times under :data:`FLAT_ROI_SPREAD`).
    """

    video: Path
    tracker: str
    frames: int
    lost: int
    start_frame: int
    processing_fps: float
    seconds: float
    video_fps: float
    video_fps_guessed: bool
    width: int
    height: int
    video_out: Path | None
    fourcc: str | None
    csv_out: str | None
    expected_frames: int = 0
    timestamps_from: int | None = None
    roi_flat: bool = False
    undecodable: tuple[tuple[int, int], ...] = ()
    image_gaps: tuple[tuple[int, str, str], ...] = ()

    @property
    def undecodable_frames(self) -> int:
        """How many frames could not be decoded (see ``undecodable``)."""
        return sum(count for _, count in self.undecodable)

    @property
    def truncated(self) -> bool:
        """The video ended before the frames its container announces (e.g. a file cut short)."""
        return 0 < self.frames + self.undecodable_frames < self.expected_frames


def _check_max_frames(max_frames: int | None) -> None:
    if max_frames is not None:
        check_frame_number(max_frames, "the number of frames to track", low=1)


def _no_op() -> None:
    pass


def _progress_callback(progress: ProgressLike, total: int | None):
    """(callback(done, total), finish()) for ``progress``: a callable, True (tqdm bar on stderr) or off."""
    if callable(progress):
        return (lambda done: progress(done, total)), _no_op
    if not progress:
        return (lambda done: None), _no_op
    from tqdm import tqdm

    bar = tqdm(total=total, unit="frame", file=sys.stderr, dynamic_ncols=True, leave=False,
               desc="lptrack")

    def update(done: int) -> None:
        bar.update(done - bar.n)

    return update, bar.close


#: Extensions a per-frame table is refused under, beside the videos'
#: (:data:`~logpolar_track.video.CODECS_BY_EXTENSION`).
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".gif", ".bmp", ".tif", ".tiff", ".webp")


def check_outputs(video_path: Path, video_out, csv_out, overwrite: bool) -> None:
    """Raise before any work if an output cannot be written (see :func:`run_video`): what :func:`run_video` checks
    before its first frame, for a caller with work of its own to do first (``lptrack run --start-time``)."""
    planned = []
    if video_out is not None:
        if str(video_out) == "-":
            raise UsageError("the annotated video cannot go to stdout ('-o -'); give it a file name, or use "
                             "--no-video (the rows go to stdout with --csv -)")
        if writes_in_place(video_out) or Path(video_out).is_dir():
            # A device or pipe: the video is renamed into place, so it cannot go there; a folder: said as such
            # rather than as a missing extension, as for the CSV.
            check_output_path(video_out, what="output video")
        if Path(video_out).suffix.lower() not in CODECS_BY_EXTENSION:
            raise UsageError(f"cannot write output video '{video_out}': unsupported extension "
                             f"'{Path(video_out).suffix}'; use one of {', '.join(CODECS_BY_EXTENSION)}")
        planned.append((Path(video_out), "output video"))
    if csv_out is not None and str(csv_out) != "-":
        if Path(csv_out).suffix.lower() in (*CODECS_BY_EXTENSION, *_IMAGE_SUFFIXES):
            # A table named as a video or an image is a slip (`--csv out.mp4` for `-o out.mp4`), not a wish.
            raise UsageError(f"cannot write the CSV to '{csv_out}': '{Path(csv_out).suffix}' is a video's or an "
                             f"image's extension; name it .csv (or .jsonl), or give the video with -o")
        planned.append((Path(csv_out), "output CSV"))
    inputs = [(video_path, "the input video")]
    inputs += [(roi, "the input's ROI file") for roi in roi_sidecar_paths(video_path)]
    # --skip-existing keeps outputs in files; the rows on stdout are none (so it is refused with --csv -). It keeps
    # an output only if this video wrote it: the same name is also what a video of that name in another folder takes
    # (a list split by xargs without --parents), which --skip-existing would skip as done, or replace.
    keep_hint = ("" if str(csv_out) == "-" else
                 " (or --skip-existing to keep it if this video wrote it; videos of one name from several folders "
                 "need --parents)")
    for out, what in planned:
        check_output_path(out, overwrite=overwrite, what=what, special_ok=what == "output CSV", keep_hint=keep_hint)
        for source, name in inputs:
            if out.exists() and source.exists() and out.resolve() == source.resolve():
                raise OutputError(f"{what} '{out}' is {name}; choose another name")
    if len(planned) == 2 and planned[0][0].resolve() == planned[1][0].resolve():
        raise OutputError(f"the output video and the output CSV are the same file '{planned[0][0]}'")


def _first_then(first: list, rest: Iterator[tuple]) -> Iterator[tuple]:
    """The one item of the list ``first``, taken out of it (a frame is not kept alive once used), then ``rest``."""
    yield first.pop()
    yield from rest


def run_video(path, roi: RoiLike = None, *, tracker: str | Tracker = DEFAULT_TRACKER, start_frame: int = 0,
              max_frames: int | None = None, video_out=None, csv_out=None, overwrite: bool = False,
              progress: ProgressLike = False, tracker_params: dict | None = None,
              csv_options: dict | None = None, threads: int | None = TRACKING_OPENCV_THREADS,
              fps: float | None = None) -> RunSummary:
    """Track one object through ``path`` and write the annotated video and/or the per-frame CSV.

    Parameters
    ----------
    path, roi, tracker, start_frame, max_frames, tracker_params, fps
        As in :func:`track_video`; ``fps`` is also the annotated video's rate.
    video_out : str or Path, optional
        Annotated video to write (same size, an odd one padded to even, frame count and frame rate as the
        input); None for none.
    csv_out : str or Path, optional
        CSV to write (:data:`~logpolar_track.results.COLUMNS`); ``'-'`` for stdout; None for none.
    overwrite : bool
        Replace existing outputs. Otherwise an existing output raises :class:`OutputError` before any work.
    progress : bool or callable
        True: a tqdm bar on stderr. A callable is called as ``progress(frames_done, total)`` after each
        frame (``total`` is the container's estimate of the remaining frames, or None).
    csv_options : dict, optional
        Further keyword arguments of :class:`~logpolar_track.results.CsvWriter` (``data_format``, ``video``,
        ``header``, ``stream``), e.g. JSON lines, or a labelled stream for batches.
    threads : int or None
        OpenCV's worker threads while tracking (:func:`~logpolar_track.executor.opencv_threads`): 1 by default,
        the fastest for every tracker (the video is decoded in a thread of its own); None leaves OpenCV's
        setting alone. Restored afterwards.

    Returns
    -------
    RunSummary

    Raises
    ------
    UsageError, RoiError, VideoError
        As :func:`track_video`; all before any output file is created.
    OutputError
        Output folder missing or unwritable, output exists without ``overwrite``, output is the input, or
        writing failed. Nothing half-written is left behind: outputs go to temporary names in their folders
        and are renamed only when complete; on any error (or Ctrl-C) they are deleted.
    """
    engine = _make_tracker(tracker, tracker_params)
    _check_max_frames(max_frames)
    tracker_name = engine.name or type(engine).__name__
    video_path = Path(path)
    with VideoReader(video_path, start_frame=start_frame, fps=fps) as reader:
        ellipse = resolve_roi(roi, video_path)
        check_roi_fits(ellipse, reader.width, reader.height, source=video_path.name)
        around = ellipse.moved(ellipse.cx, ellipse.cy, FLAT_ROI_EXTENT)
        roi_flat = roi_spread(reader.first_frame, around) < FLAT_ROI_SPREAD
        # Inputs are checked (above) before outputs, outputs before any frame is tracked or written.
        check_outputs(video_path, video_out, csv_out, overwrite)
        announced = frames_to_track(reader.frame_count, start_frame, max_frames) or 0  # 0: not known
        total = announced or max_frames
        csv_writer = video_writer = written = None
        finish = _no_op
        frames = lost = 0
        try:
            with opencv_threads(threads):
                started = time.perf_counter()
                tracked = _track(reader, ellipse, engine, max_frames)
                # The tracker starts before any output is opened: one that refuses the ROI (cv-mil on a box under
                # 5 px) leaves nothing, not a CSV header already on stdout.
                first = [next(tracked)]
                if csv_out is not None:
                    csv_writer = CsvWriter(csv_out, overwrite=overwrite, **(csv_options or {}))
                if video_out is not None:
                    video_writer = VideoWriter(video_out, reader.fps, overwrite=overwrite)
                step, finish = _progress_callback(progress, total)
                for frame, result in _first_then(first, tracked):
                    if csv_writer is not None:
                        csv_writer.write(result)
                    if video_writer is not None:
                        # The tracker is done with the frame: annotate it in place rather than a copy.
                        video_writer.write(draw_state(frame, result.state, frame_index=result.frame,
                                                      status=result.status, in_place=True))
                    frames += 1
                    lost += result.lost
                    step(frames)
                    # Not kept alive while the next frame is fetched and tracked (25 MB at 4K).
                    del frame
            seconds = time.perf_counter() - started
            written = video_writer.close() if video_writer is not None else None
            if csv_writer is not None:
                csv_writer.close()
        except BaseException:
            # Ctrl-C and failures alike: delete temporary outputs, keep nothing half-written -- nor a finished
            # video whose CSV then failed (a run either leaves all its outputs or none).
            try:
                if video_writer is not None:
                    video_writer.abort()
                    if written is not None:
                        written.unlink(missing_ok=True)
            finally:
                if csv_writer is not None:
                    csv_writer.abort()
            raise
        finally:
            finish()
    return RunSummary(
        video=video_path, tracker=tracker_name, frames=frames, lost=lost, start_frame=start_frame,
        processing_fps=frames / seconds if seconds > 0 else float("inf"), seconds=seconds,
        video_fps=reader.fps, video_fps_guessed=reader.fps_guessed, width=reader.width, height=reader.height,
        video_out=written, fourcc=video_writer.fourcc if video_writer is not None else None,
        csv_out=None if csv_writer is None else csv_writer.target, expected_frames=announced,
        timestamps_from=reader.timestamps_from, roi_flat=roi_flat, undecodable=tuple(reader.undecodable),
        image_gaps=tuple(reader.image_gaps))
