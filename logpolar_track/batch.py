"""Track objects through many videos: find the videos, give each its ROI and outputs, run them, gather results.

``lptrack run`` with several inputs is :func:`plan_batch` then :func:`run_batch`:

- inputs are video files, folders (searched recursively for :data:`VIDEO_EXTENSIONS`, sorted) and ``-``
  (paths read from standard input, one per line) -- :func:`find_videos`;
- each video's ROI comes from a ROI file (:func:`read_roi_file`: ``video,roi[,start_frame][,tracker]``), else
  from one ROI given for all, else from the ``.roi`` sidecar next to the video;
- outputs mirror the inputs' relative paths under an output folder, never two inputs onto one output
  (:func:`plan_batch`); or every video's rows go to one stream with a leading ``video`` column;
- videos run one after another, in parallel worker processes, or on a Dask cluster
  (:mod:`logpolar_track.executor`), with the same outputs byte for byte whichever runs them.

One bad video (missing, not a video, no frames, ROI outside its frame, a worker killed) fails alone and is
reported; the others go on. Outputs are written under temporary names and renamed when complete, so a batch
cut short leaves only complete outputs, and ``skip_existing`` resumes it.
"""

from __future__ import annotations

import csv
import io
import json
import os
import sys
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, Callable, Iterable, Mapping, Sequence

from .errors import LptrackError, RoiError, UsageError, VideoError
from .executor import TaskOutcome, run_tasks
from .geometry import NUMBER_RULE, ROI_SYNTAX, Ellipse, parse_number, parse_roi
from .pipeline import (CSV_OUT_SUFFIX, DEFAULT_TRACKER, VIDEO_OUT_SUFFIX, RunSummary, decode_roi_text,
                       mirrored_path, read_roi_sidecar, read_roi_text, run_video)
from .results import FORMATS, header_line
from .trackers import tracker_class
from .outputs import remove_empty_folders, run_in_output_folders, temporary_path
from .video import (CODECS_BY_EXTENSION, VIDEO_EXTENSIONS, VideoReader, announced_frame_count, check_fps,
                    frames_to_track, is_image_sequence, video_stem)

#: Stem ending of lptrack's own annotated videos, which folder searches skip (``clip.lptrack.mp4``).
OUTPUT_STEM_SUFFIX = Path(VIDEO_OUT_SUFFIX).stem


@dataclass(frozen=True)
class VideoInput:
    """One input video.

    Attributes
    ----------
    path : Path
        The video as given or found (relative paths stay relative to the current folder).
    root : Path or None
        The input folder it was found in (outputs mirror the path relative to it); None for videos named
        directly, on standard input or in a ROI file.
    """

    path: Path
    root: Path | None = None


@dataclass(frozen=True)
class RoiEntry:
    """One line of a ROI file: the video, its ROI, and optionally its start frame and tracker."""

    video: Path
    roi: Ellipse
    start_frame: int | None = None
    tracker: str | None = None


@dataclass(frozen=True)
class VideoJob:
    """Everything a worker needs to track one video (picklable; paths absolute).

    ``roi`` None means: read the video's ``.roi`` sidecar. ``csv_out`` None with ``stream`` True means: return
    the rows (with the ``video`` column) instead of writing a file.
    """

    label: str
    video: Path
    roi: Ellipse | None
    tracker: str
    start_frame: int
    video_out: Path | None
    csv_out: Path | None
    data_format: str = "csv"
    overwrite: bool = False
    stream: bool = False
    max_frames: int | None = None
    #: Frames per second instead of the video's own (None: its own; see ``run_video``).
    fps: float | None = None
    #: Keyword tuning of ``tracker`` (a dict: left out of the job's hash).
    tracker_params: Mapping[str, object] | None = field(default=None, hash=False)


@dataclass(frozen=True)
class VideoOutcome:
    """What happened to one video of a batch.

    ``status`` is ``ok``, ``failed`` (``reason`` says why) or ``skipped`` (its outputs existed). ``frames``
    counts tracked frames; ``expected_frames`` is what the container announced, and ``truncated`` says that
    fewer came (:attr:`RunSummary.truncated <logpolar_track.pipeline.RunSummary.truncated>`). ``fps_assumed``
    is the frame rate assumed for a source that reports none (an image sequence, when no ``fps`` was given), else
    None. ``timestamps_from`` is, for a variable frame rate, ``(first frame timed by its timestamp, fps, start
    frame)`` (:attr:`RunSummary.timestamps_from <logpolar_track.pipeline.RunSummary.timestamps_from>`), else None.
    ``roi_flat``: the ROI held a flat region on the start frame (:attr:`RunSummary.roi_flat`). ``undecodable``:
    stretches of frames that could not be decoded, ``(first frame, count)`` (:attr:`RunSummary.undecodable`).
    ``image_gaps``: where an image sequence's numbers skip (:attr:`RunSummary.image_gaps`).
    """

    label: str
    status: str
    reason: str | None = None
    frames: int = 0
    lost: int = 0
    expected_frames: int = 0
    seconds: float = 0.0
    truncated: bool = False
    rows: str | None = None
    fps_assumed: float | None = None
    timestamps_from: tuple[int, float, int] | None = None
    roi_flat: bool = False
    undecodable: tuple[tuple[int, int], ...] = ()
    image_gaps: tuple[tuple[int, str, str], ...] = ()


@dataclass
class BatchSummary:
    """The outcome of every video in input order, and the wall-clock time of the batch."""

    outcomes: list[VideoOutcome] = field(default_factory=list)
    seconds: float = 0.0

    def count(self, status: str) -> int:
        return sum(o.status == status for o in self.outcomes)

    @property
    def frames(self) -> int:
        return sum(o.frames for o in self.outcomes)

    @property
    def failed(self) -> list[VideoOutcome]:
        return [o for o in self.outcomes if o.status == "failed"]


# -- finding videos and their ROIs ---------------------------------------------------------------------

def is_video_name(path: Path) -> bool:
    """Whether a folder search takes ``path`` (relative to the folder): a video extension, nothing hidden on
    the way (temporary outputs are hidden), not one of lptrack's own annotated videos."""
    return (path.suffix.lower() in VIDEO_EXTENSIONS and not any(part.startswith(".") for part in path.parts)
            and not path.stem.endswith(OUTPUT_STEM_SUFFIX))


def mirrored_output_base(video, folder_videos: dict[Path, dict[str, set[str]]] | None = None) -> Path:
    """What ``--parents`` names ``video``'s outputs after, suffixes to come: its path as given
    (:func:`~logpolar_track.pipeline.mirrored_path`) with its stem for a name, or its whole file name where another
    video in its folder has that stem (``a.mp4`` beside ``a.avi``: ``a.mp4.lptrack.csv``). The folder decides, not
    the other videos of the run, so that runs given the two apart name them as one run does.

    ``folder_videos``, if given, keeps each folder's videos once read (:func:`_videos_by_stem`), so that a batch
    reads a folder once rather than once per video in it."""
    video = Path(video)
    mirrored = mirrored_path(video)
    stem = video_stem(video)
    if not is_image_sequence(video):
        read = {} if folder_videos is None else folder_videos
        if video.parent not in read:
            read[video.parent] = _videos_by_stem(video.parent)
        if read[video.parent].get(stem, set()) - {video.name}:
            return mirrored
    return mirrored.with_name(stem)


def _videos_by_stem(folder: Path) -> dict[str, set[str]]:
    """The video file names of ``folder`` (:func:`is_video_name`) by stem; empty where it cannot be read."""
    by_stem: dict[str, set[str]] = {}
    try:
        for entry in os.scandir(folder):
            if is_video_name(Path(entry.name)):
                by_stem.setdefault(Path(entry.name).stem, set()).add(entry.name)
    except OSError:
        pass
    return by_stem


def video_key(path) -> Path:
    """What makes two names of a video the same input: its folder resolved, its own file name kept.

    ``a.mp4``, ``./a.mp4`` and ``sub/../a.mp4`` are one input; a symbolic link to ``a.mp4`` is an input of its
    own, with its own outputs and ``.roi`` sidecar named after the link, as ``find`` and FFmpeg treat it.
    """
    path = Path(path).absolute()
    return path.parent.resolve() / path.name


def find_videos(inputs: Iterable[str], *, stdin: IO[str] | None = None,
                on_duplicate: Callable[[Path], None] | None = None,
                on_own_output: Callable[[Path, Path], None] | None = None,
                on_link_passed: Callable[[Path, bool], None] | None = None) -> list[VideoInput]:
    """The videos named by ``inputs``, in order, each once.

    Parameters
    ----------
    inputs : iterable of str
        Video files (kept even if missing: they fail as videos later, without stopping the others), folders
        (searched recursively for :func:`is_video_name` files, sorted by path) and ``-`` (one path per line
        from ``stdin``, blank lines and lines starting with ``#`` ignored; or, where the text holds a NUL, as
        ``find -print0`` writes, the paths between NULs exactly as written). A video named again (the same
        :func:`video_key`: a file also found in a folder given, a line repeated) is kept once, where it came
        first; links to one file are different videos.
    stdin : text stream, optional
        Where ``-`` reads (default ``sys.stdin``).
    on_duplicate : callable, optional
        Called with the path of each video named again, as it is dropped.
    on_own_output : callable, optional
        Called with ``(output, source)`` for each video dropped as lptrack's own annotated video of another input
        (``clip.lptrack.mp4`` beside ``clip.mp4``, as a shell's ``*.mp4`` names both).
    on_link_passed : callable, optional
        Called with ``(link, to_folder)`` for each symbolic link a folder search passes by: to a folder (not
        searched, as ``find`` does not follow links), or, named as a video, to nothing.

    Raises
    ------
    UsageError
        ``-`` given twice.
    """
    found: list[VideoInput] = []
    seen: set[Path] = set()

    def add(video: VideoInput) -> None:
        key = video_key(video.path)
        if key not in seen:
            seen.add(key)
            found.append(video)
        elif on_duplicate is not None:
            on_duplicate(video.path)

    read_stdin = False
    for text in inputs:
        if text == "-":
            if read_stdin:
                raise UsageError("'-' (video paths on standard input) can be given only once")
            read_stdin = True
            listing = _video_listing(stdin if stdin is not None else sys.stdin)
            if "\0" in listing:  # find -print0: names exactly as written, NUL after each
                names = [name for name in listing.split("\0") if name.strip("\n")]
                if names and not listing.endswith("\0"):  # the line end of an echo or printf after the last name
                    names[-1] = names[-1].rstrip("\r\n")
            else:
                names = [line.strip() for line in listing.splitlines()]
                names = [name for name in names if name and not name.startswith("#")]
            for name in names:
                add(VideoInput(Path(name)))
            continue
        path = Path(text)
        if path.is_dir():
            for entry in sorted(path.rglob("*")):
                name = entry.relative_to(path)
                if entry.is_file():
                    if is_video_name(name):
                        add(VideoInput(entry, root=path))
                elif (on_link_passed is not None and entry.is_symlink()
                      and not any(part.startswith(".") for part in name.parts)
                      and (entry.is_dir() or name.suffix.lower() in VIDEO_EXTENSIONS)):
                    on_link_passed(entry, entry.is_dir())
        else:
            add(VideoInput(path))
    # A shell's *.mp4 names lptrack's own annotated videos beside their sources: tracked again, they gave
    # clip.lptrack.lptrack.mp4, one more each run. One named with no source among the inputs is tracked, unless its
    # name holds its source's extension and that file is beside it.
    # Each input's key without its extension -> the first input of that stem; and its key with it, the name an
    # output takes where two videos share a stem (a.mp4 beside a.avi: a.mp4.lptrack.mp4).
    sources: dict[Path, Path] = {}
    for video in found:
        sources.setdefault(video_key(video.path).with_suffix(""), video.path)
    for video in found:
        sources.setdefault(video_key(video.path), video.path)
    kept = []
    for video in found:
        stem = Path(video.path.stem)
        source = sources.get(video_key(video.path).parent / stem.stem)
        named = video.path.with_name(stem.stem)  # a.avi for a.avi.lptrack.mp4, made beside a.mp4
        if source is None and named.suffix.lower() in VIDEO_EXTENSIONS and named.is_file():
            source = named  # *.mp4 names the output, not its source
        if stem.suffix == OUTPUT_STEM_SUFFIX and source is not None:
            if on_own_output is not None:
                on_own_output(video.path, source)
            continue
        kept.append(video)
    return kept


def _video_listing(stream) -> str:
    """All of ``stream`` (text): the list of video paths given as ``-``.

    Raises
    ------
    UsageError
        ``stream`` is closed (``<&-``), or holds binary data: a video piped in (``cat clip.mp4 | lptrack run -``)
        gave dozens of lines naming junk files.
    """
    what = "'-' reads the videos' paths from standard input"
    if stream is None:
        raise UsageError(f"{what}, which is closed")
    raw = getattr(stream, "buffer", None)
    # The bytes are decoded here, those that are not UTF-8 as lone surrogates (as the file system's names are):
    # under a locale whose standard input decodes strictly, one such byte raised a traceback.
    head = raw.read(_BINARY_SAMPLE) if raw is not None else stream.read(_BINARY_SAMPLE)
    text = head.decode("utf-8", "surrogateescape") if raw is not None else head
    # A list of file names has few undecodable bytes or control characters; a video has them everywhere.
    odd = sum(1 for c in text if ("\udc80" <= c <= "\udcff") or (c < " " and c not in "\t\n\r\0"))
    if odd > max(_BINARY_SHARE * len(text), _BINARY_MIN):
        raise UsageError(f"{what}, one per line (or NUL-separated, as find -print0 writes), but what it holds is not "
                         f"text (a video piped in?); give the video's path instead")
    if raw is None:
        return text + stream.read()
    return (head + raw.read()).decode("utf-8", "surrogateescape")  # whole, so that no character is cut in two


def _roi_listing(stream) -> str:
    """All of ``stream``, a ROI file given as ``--roi-file -``, as :func:`~logpolar_track.pipeline.read_roi_text`
    reads a file (UTF-8, or UTF-16 with a byte-order mark)."""
    if stream is None:
        raise UsageError("--roi-file - reads the ROI file from standard input, which is closed")
    raw = getattr(stream, "buffer", None)
    if raw is None:
        return stream.read()
    return decode_roi_text(raw.read(), "the ROI file from standard input")


#: How much of standard input is looked at, and the share of it (and a count) that may be bytes no list of paths
#: has: a short list with one name in Latin-1 is still a list.
_BINARY_SAMPLE, _BINARY_SHARE, _BINARY_MIN = 65536, 0.05, 16


def read_roi_file(path, *, stdin: IO[str] | None = None) -> list[RoiEntry]:
    """The entries of a ROI file, in file order.

    A CSV file with one video per line: ``video,roi[,start_frame][,tracker]``. ``roi`` is ``cx,cy,r`` or
    ``cx,cy,a,b,angle`` (pixels; degrees counter-clockwise on screen) and may be quoted or not
    (``clip.mp4,"320,240,40",0,lpcf`` and ``clip.mp4,320,240,40,0,lpcf`` are the same). An optional header line,
    before the first entry (comments may come before it), starts with ``video``; blank lines and lines starting
    with ``#`` are ignored. Relative video paths are relative to the ROI file's folder. UTF-8 or UTF-16 text (see
    :func:`~logpolar_track.pipeline.read_roi_text`). ``-`` reads ``stdin`` (default ``sys.stdin``), whose relative
    paths are relative to the current folder.

    Raises
    ------
    LptrackError
        The file cannot be read (missing, a folder, not text): exit code 1, as for any unreadable input.
    UsageError
        A line is malformed (the message gives its number), or lists a video twice.
    """
    path = Path(path)
    if str(path) == "-":  # as VIDEO '-' and --csv -: standard input, its relative paths from the current folder
        text, shown = _roi_listing(stdin if stdin is not None else sys.stdin), "ROI file (standard input)"
    else:
        text, shown = read_roi_text(path), f"ROI file '{path}'"
    entries: list[RoiEntry] = []
    seen: dict[Path, int] = {}
    expected = f"video,roi[,start_frame][,tracker] with roi {ROI_SYNTAX}"
    header_allowed = True  # on the first line that is not blank or a comment
    for number, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if header_allowed and row[0].strip().lower() == "video":
            header_allowed = False
            continue
        header_allowed = False
        where = f"{shown} line {number}"
        if len(row) == 1 and ";" in row[0]:
            # A spreadsheet saved as CSV where the decimal mark is a comma (most of Europe) separates by ';'.
            raise UsageError(f"{where}: expected {expected}, got '{row[0]}': separated by ';', not commas (a "
                             f"spreadsheet's CSV in a locale with decimal commas?); save it with commas")
        video_text = row[0].strip()
        if not video_text:
            raise UsageError(f"{where}: expected {expected}, got '{','.join(row)}'")
        if len(row) > 1 and "," in row[1]:
            # A quoted ROI: the columns are exactly video,roi,start_frame,tracker.
            roi_text, rest = row[1], [v.strip() for v in row[2:]]
            if len(rest) > 2:
                raise UsageError(f"{where}: expected {expected}, got {len(rest)} columns after the ROI")
            start_text = rest[0] if rest else ""
            tracker = rest[1] if len(rest) > 1 and rest[1] else None
            tracker_hint = " (for a tracker and no start frame, leave the column empty: video,\"roi\",,tracker)"
            taken = ""
        else:
            # An unquoted ROI spreads over 3 or 5 columns; a start frame is a 4th or 6th number, and a tracker
            # name, not being a number (as parse_roi reads numbers: 1_0, nan and inf are none), can only be the last
            # column.
            values = [v.strip() for v in row[1:] if v.strip()]
            tracker = values.pop() if values and parse_number(values[-1]) is None else None
            start_text = values.pop() if len(values) in (4, 6) else ""
            # Said where the line is refused: '1_0', nan or inf meant as a number read as a tracker's name.
            taken = "" if tracker is None else (f" (the last column, '{tracker}', is not a number ({NUMBER_RULE}), "
                                                f"so it is read as a tracker's name)")
            if len(values) not in (3, 5):
                raise UsageError(f"{where}: expected {expected}, got '{','.join(row)}'{taken}")
            roi_text, tracker_hint = ",".join(values), ""
        start_frame = None
        if start_text:
            if not start_text.isdigit():
                raise UsageError(f"{where}: the start_frame column holds '{start_text}'; it takes a frame index "
                                 f">= 0 (0 = first frame), or nothing{tracker_hint}")
            start_frame = int(start_text)
        try:
            roi = parse_roi(roi_text)
        except RoiError as exc:
            raise UsageError(f"{where}: {exc}") from None
        if tracker is not None:
            try:
                tracker_class(tracker)  # an unknown name is a UsageError listing the known ones
            except UsageError as exc:
                raise UsageError(f"{where}: in the tracker column, {exc}{taken}") from None
        video = Path(video_text)
        if not video.is_absolute():
            video = path.parent / video
        key = video_key(video)
        if key in seen:
            raise UsageError(f"{where}: '{video_text}' is already listed on line {seen[key]}")
        seen[key] = number
        entries.append(RoiEntry(video, roi, start_frame, tracker))
    return entries


# -- planning outputs ----------------------------------------------------------------------------------

def _data_suffix(data_format: str) -> str:
    return Path(CSV_OUT_SUFFIX).stem + FORMATS[data_format]  # ".lptrack" + ".csv" / ".jsonl"


def _relative_names(videos: list[VideoInput]) -> list[Path]:
    """Each input's path relative to its root folder; loose files relative to their common folder. Where several
    root folders are given, each one's inputs are named under its folder's name (``day1/cam.mp4``,
    ``day2/cam.mp4`` for ``day1 day2``), as ``cp -r day1 day2 out`` copies them, and under as many folders above as
    tell apart two of the same name (``day1/cams/cam.mp4``, ``day2/cams/cam.mp4`` for ``day1/cams day2/cams``)."""
    loose = [video_key(v.path).parent for v in videos if v.root is None]
    common = Path(os.path.commonpath(loose)) if loose else None
    # Each root folder's names from the top (never the root itself, which would make a name absolute).
    roots = {v.root: Path(os.path.abspath(v.root)) for v in videos if v.root is not None}
    parts = {root: path.relative_to(path.anchor).parts for root, path in roots.items()}
    # The folder's own name, however it was given ('.', '..', 'day1/'): never a step out of --out-dir. Where two
    # share it (day1/cams and day2/cams), as many of the folders above as tell them apart (day1/cams, day2/cams).
    distinct, depth = set(roots.values()), 1
    while (len({p[-depth:] for p in parts.values()}) < len(distinct)
           and depth < max(len(p) for p in parts.values())):
        depth += 1
    return [(Path(*parts[v.root][-depth:]) if len(distinct) > 1 else Path()) / v.path.relative_to(v.root)
            if v.root is not None else video_key(v.path).relative_to(common) for v in videos]


def video_output_candidates(video_out: Path) -> list[Path]:
    """Where the annotated video for ``video_out`` may end up (the wanted name, or a fallback codec's)."""
    options = CODECS_BY_EXTENSION.get(video_out.suffix.lower(), ())
    return list(dict.fromkeys(video_out.with_suffix(ext) if ext != video_out.suffix.lower() else video_out
                              for _, ext in options)) or [video_out]


def outputs_complete(video_out: Path | None, csv_out: Path | None, *, source: Path | None = None,
                     start_frame: int = 0, max_frames: int | None = None, roi: Ellipse | None = None) -> bool:
    """Whether a run with these outputs (None: not wanted) finished: each exists under its final name and,
    given the ``source`` video, the data file covers the frames this run would track, from its ROI.

    Outputs are renamed to their final names only when complete, so existing means a run finished; but a run
    over other frames (a trial with ``--frames 5``, another start frame) finishes too. So the data file's
    first row must be ``start_frame`` and its last row at least the last frame wanted: ``max_frames`` on, or
    the end of the video as its container announces it (less 1 %, for containers that only estimate it; when
    the count is unknown, the end is not checked). Its first row must also be the ROI the run would start from
    (``roi``, or None: the video's ``.roi`` sidecar), within 0.05 pixels: a run from a ROI since corrected is
    redone. (The tracker, its parameters and a frame rate given are not in the file, so a run with others is not
    noticed.)
    """
    if video_out is None and csv_out is None:
        return False
    if csv_out is not None and not csv_out.exists():
        return False
    if video_out is not None and not any(p.exists() for p in video_output_candidates(video_out)):
        return False
    if csv_out is None or source is None:
        return True
    span = data_frame_span(csv_out)
    if span is None or span[0] != start_frame:
        return False
    if roi is None:
        try:
            roi = read_roi_sidecar(source)
        except LptrackError:
            return False  # the run will say what is wrong with it
    started_from = data_start_roi(csv_out)
    if roi is None or started_from is None or not roi.same_outline(started_from):
        return False
    announced = announced_frame_count(source)
    last_wanted = announced - 1 - announced // 100 if announced else None
    if max_frames is not None:
        wanted = start_frame + max_frames - 1
        last_wanted = wanted if last_wanted is None else min(wanted, last_wanted)
    if last_wanted is None or span[1] >= last_wanted:
        return True
    # Short of it: a trial over fewer frames (--frames 5), or a video cut short or damaged at its end, whose run
    # ended where its frames did (it was tracked again on every resumed batch). The frames up to the row after the
    # last are decoded to tell.
    try:
        with VideoReader(source, start_frame=span[1] + 1):
            return False
    except VideoError:  # past the end (FrameRangeError), or that frame cannot be decoded
        return True


def _data_ends(path: Path) -> tuple[str | None, str, str] | None:
    """The header line (None if there is none, as in JSON lines), the first row and the last row of an lptrack
    CSV or JSON Lines file, as text; None when it has no rows or cannot be read. Reads only its two ends."""
    try:
        with open(path, "rb") as f:
            head = f.read(4096).decode("utf-8", "replace").splitlines()
            f.seek(max(f.seek(0, os.SEEK_END) - 4096, 0))
            tail = f.read().decode("utf-8", "replace").splitlines()
    except OSError:
        return None
    header = next((line for line in head if line.startswith("frame,")), None)
    rows = [line for line in head if line.strip() and not line.startswith("frame,")]
    last_rows = [line for line in tail if line.strip()]
    if not rows or not last_rows:
        return None
    return header, rows[0], last_rows[-1]


def data_frame_span(path: Path) -> tuple[int, int] | None:
    """Frame numbers of the first and last rows of an lptrack CSV or JSON Lines file (None: no rows, or not
    such a file)."""
    ends = _data_ends(path)
    if ends is None:
        return None

    def frame_of(line: str) -> int | None:
        try:
            if line.startswith("{"):
                return int(json.loads(line)["frame"])
            return int(line.split(",", 1)[0])
        except (ValueError, KeyError, TypeError):
            return None

    first, last = frame_of(ends[1]), frame_of(ends[2])
    return None if first is None or last is None else (first, last)


def data_start_roi(path: Path) -> Ellipse | None:
    """The ellipse of the first row of an lptrack CSV or JSON Lines file: the ROI its run started from (None:
    no rows, or not such a file)."""
    ends = _data_ends(path)
    if ends is None:
        return None
    header, first, _ = ends
    try:
        if first.startswith("{"):
            record = json.loads(first)
        elif header is not None:
            record = dict(zip(header.split(","), next(csv.reader([first]))))
        else:
            return None
        return Ellipse(*(float(record[k]) for k in ("cx", "cy", "a", "b", "angle_deg")))
    except (ValueError, KeyError, TypeError, csv.Error):  # RoiError is a ValueError
        return None


@dataclass(frozen=True)
class BatchPlan:
    """The jobs to run, and the videos failed or skipped before running (e.g. no ROI, output clash)."""

    jobs: list[VideoJob]
    order: list[str]
    settled: dict[str, VideoOutcome]
    #: The folder the outputs mirror the inputs under (None: no files, e.g. streamed rows only).
    out_dir: Path | None = None

    def output_folders(self, job: VideoJob) -> list[Path]:
        """The folders below :attr:`out_dir` that ``job``'s outputs go in, innermost last."""
        folders = set()
        for out in (job.video_out, job.csv_out):
            if out is not None and self.out_dir is not None:
                folders.update(p for p in [out.parent, *out.parent.parents] if self.out_dir in p.parents)
        return sorted(folders, key=lambda p: len(p.parts))


def plan_batch(videos: list[VideoInput], *, roi: Ellipse | None = None, roi_entries: Iterable[RoiEntry] = (),
               tracker: str = DEFAULT_TRACKER, start_frame: int = 0, max_frames: int | None = None, out_dir=".",
               video: bool = True, stream: bool = False, data_format: str = "csv", overwrite: bool = False,
               skip_existing: bool = False, tracker_params: Mapping[str, Mapping[str, object]] | None = None,
               fps: float | None = None, parents: bool = False) -> BatchPlan:
    """Give every video its ROI, start frame, tracker and outputs.

    Parameters
    ----------
    videos : list of VideoInput
        From :func:`find_videos`. If empty, the videos of ``roi_entries`` are the inputs.
    roi : Ellipse, optional
        ROI for every video that has no entry in ``roi_entries``; without it, such videos read their ``.roi``
        sidecar (and fail alone if they have none).
    roi_entries : iterable of RoiEntry
        Per-video ROIs (:func:`read_roi_file`); their start frame and tracker override the defaults.
    tracker, start_frame
        Defaults for videos whose entry does not say.
    tracker_params : mapping, optional
        ``{tracker: {keyword: value}}``: tuning for each video tracked by that tracker
        (:func:`~logpolar_track.trackers.tracker_params_from_text` makes it from ``--param`` text).
    max_frames : int, optional
        Frames to track per video, the start frame included (None: to the end).
    fps : float, optional
        Frames per second of every video instead of its own (for image sequences, which have none).
    out_dir : path
        Outputs go to ``out_dir/<path relative to the input folder>/<stem>.lptrack.{mp4,csv}``; a file name
        shared by two inputs (``a.mp4`` and ``a.avi``) keeps its extension instead: ``a.mp4.lptrack.csv``; with
        several input folders, each is mirrored under its own name (``day1/cam.lptrack.csv``).
    parents : bool
        Mirror each input's path as given instead, folders included, whatever the other inputs
        (``cams/day1/cam.mp4`` -> ``out_dir/cams/day1/cam.lptrack.csv``, as ``cp --parents``:
        :func:`mirrored_output_base`), so that a list of videos split between runs lands as one run would put it.
    video : bool
        Write annotated videos.
    stream : bool
        Return each video's rows (labelled with a ``video`` column) instead of writing data files.
    data_format : {'csv', 'jsonl'}
    overwrite, skip_existing : bool
        Replace existing outputs; or leave alone every video whose outputs all exist (status ``skipped``) and
        redo the others, replacing whatever part of their outputs exists.
    """
    check_fps(fps)
    if not all(isinstance(tuning, Mapping) for tuning in (tracker_params or {}).values()):
        # {'padding': 1.5} (run_video's form) would be read as a tracker named 'padding' and dropped in silence.
        raise UsageError(f"tracker_params maps tracker names to their tuning, e.g. {{'lpcf': {{'padding': 1.5}}}}; "
                         f"got {dict(tracker_params)!r}")
    entries = {video_key(e.video): e for e in roi_entries}
    if not videos:
        videos = [VideoInput(e.video) for e in entries.values()]
    out_dir = Path(out_dir).resolve()
    relative = _relative_names(videos)
    # What each input's outputs are named after, in its relative folder.
    stems = [rel.with_name(video_stem(item.path)) for item, rel in zip(videos, relative)]
    by_stem: dict[Path, int] = {}
    for stem in stems:
        by_stem[stem] = by_stem.get(stem, 0) + 1
    jobs, order, settled = [], [], {}
    claimed: dict[Path, str] = {}
    folder_videos: dict[Path, dict[str, set[str]]] = {}  # each input folder read once (--parents)
    for item, rel, stem in zip(videos, relative, stems):
        label = str(item.path)
        order.append(label)
        # Two inputs sharing a stem in one folder keep their extension in the output names.
        base = mirrored_output_base(item.path, folder_videos) if parents else stem if by_stem[stem] == 1 else rel
        folder = out_dir / base.parent
        video_out = folder / f"{base.name}{VIDEO_OUT_SUFFIX}" if video else None
        csv_out = None if stream else folder / f"{base.name}{_data_suffix(data_format)}"
        entry = entries.get(video_key(item.path))
        job_tracker = entry.tracker if entry and entry.tracker else tracker
        job = VideoJob(label=label, video=video_key(item.path), roi=entry.roi if entry else roi,
                       tracker=job_tracker, tracker_params=dict((tracker_params or {}).get(job_tracker) or {}),
                       start_frame=(entry.start_frame if entry and entry.start_frame is not None else start_frame),
                       max_frames=max_frames, fps=fps, video_out=video_out, csv_out=csv_out,
                       data_format=data_format,
                       # A partial set (a run killed between its two renames) is redone whole.
                       overwrite=overwrite or skip_existing, stream=stream)
        clash = next((claimed[p] for p in (video_out, csv_out) if p is not None and p in claimed), None)
        if clash is not None:
            settled[label] = VideoOutcome(label, "failed", f"its outputs would overwrite those of '{clash}'; "
                                                           f"give the two videos different names or folders")
            continue
        claimed.update({p: label for p in (video_out, csv_out) if p is not None})
        if skip_existing and outputs_complete(job.video_out, job.csv_out, source=job.video,
                                              start_frame=job.start_frame, max_frames=max_frames, roi=job.roi):
            settled[label] = VideoOutcome(label, "skipped", "outputs exist")
            continue
        jobs.append(job)
    return BatchPlan(jobs, order, settled, out_dir)


# -- running -------------------------------------------------------------------------------------------

def run_job(job: VideoJob, report: Callable[[int], None] | None = None) -> VideoOutcome:
    """Track one video of a batch (the unit of work a worker runs); raises on failure.

    Output folders are created as needed (and left for the batch to remove if it leaves them empty).
    ``report(frames_done)`` is called as frames are tracked.
    """
    progress = None if report is None else (lambda done, total: report(done))

    def track() -> tuple[RunSummary, io.StringIO | None]:
        buffer = io.StringIO() if job.stream else None
        csv_options = {"data_format": job.data_format}
        if job.stream:
            csv_options.update(stream=buffer, video=job.label, header=False)
        summary = run_video(job.video, job.roi, tracker=job.tracker, start_frame=job.start_frame,
                            max_frames=job.max_frames, video_out=job.video_out,
                            csv_out="-" if job.stream else job.csv_out, overwrite=job.overwrite, progress=progress,
                            csv_options=csv_options, tracker_params=job.tracker_params, fps=job.fps)
        return summary, buffer

    # The rows of a stream are kept until the video is done: a start made again (its folder removed meanwhile by
    # another process) sends none twice.
    summary, buffer = run_in_output_folders([out.parent for out in (job.video_out, job.csv_out) if out is not None],
                                            track, remove_made=False)
    return VideoOutcome(job.label, "ok", frames=summary.frames, lost=summary.lost,
                        expected_frames=summary.expected_frames, seconds=summary.seconds,
                        truncated=summary.truncated, rows=None if buffer is None else buffer.getvalue(),
                        fps_assumed=summary.video_fps if summary.video_fps_guessed else None,
                        timestamps_from=(None if summary.timestamps_from is None
                                         else (summary.timestamps_from, summary.video_fps, summary.start_frame)),
                        roi_flat=summary.roi_flat, undecodable=summary.undecodable, image_gaps=summary.image_gaps)


def remove_temporary_outputs(job: VideoJob, pid: int) -> None:
    """Delete the temporary files a worker with process id ``pid`` left for ``job`` (it was killed)."""
    for out in (job.video_out, job.csv_out):
        if out is None:
            continue
        for candidate in video_output_candidates(out) if out == job.video_out else [out]:
            temporary_path(candidate, pid=pid).unlink(missing_ok=True)


def announced_job_frames(job: VideoJob) -> int | None:
    """Frames ``job`` will track as its video's container announces them: from its start frame to the end, at
    most ``max_frames``; ``max_frames`` itself when the container does not say; None when neither is known.

    Opens the video's container without decoding (about a millisecond for a local file); may be approximate
    for containers that store only a duration (.mkv, .webm).
    """
    frames = frames_to_track(announced_frame_count(job.video), job.start_frame, job.max_frames)
    return job.max_frames if frames is None else frames


class BatchProgress:
    """How far a batch has got, in frames and in videos, for a progress display.

    :func:`run_batch` keeps one up to date and hands it to its ``on_progress`` callback; its expected frame
    counts are read from the videos' containers in a background thread while the batch runs.

    Attributes
    ----------
    videos : int
        Videos of the plan, those settled before running (skipped, output clashes) included.
    ok, failed, skipped : int
        Videos settled so far with each status.
    frames_done : int
        Frames tracked so far. A video that fails part-way keeps the frames it had tracked (so the count
        never goes back), unlike :attr:`BatchSummary.frames`, which counts the frames of videos that succeeded.
    """

    def __init__(self, jobs: int, settled: Sequence[VideoOutcome] = ()) -> None:
        self.videos = jobs + len(settled)
        self.ok = self.failed = self.skipped = 0
        self.frames_done = 0
        self._lock = threading.Lock()
        self._expected: list[int | None] = [None] * jobs
        self._done = [0] * jobs
        self._finished = [False] * jobs
        self._finished_frames = 0
        # Running sums, so that an update costs the same whatever the number of videos.
        self._counted_sum = self._counted_n = 0  # every expected count known
        self._open_counted_sum = 0               # ... of the videos not finished
        self._open_uncounted = jobs              # videos not finished whose count is not known
        for outcome in settled:
            self._count(outcome.status)

    @property
    def videos_done(self) -> int:
        """Videos settled so far: ok, failed or skipped."""
        return self.ok + self.failed + self.skipped

    @property
    def frames_total(self) -> int | None:
        """Frames the whole batch will have tracked, as far as known (never below :attr:`frames_done`).

        A finished video counts its own frames; one still to finish, the frames its container announces
        (:func:`announced_job_frames`); one whose count is not known (the container does not say, the video
        is unreadable here, or its container has not been read yet), the mean of the known counts. None
        while no count is known and some video has yet to finish. Exact once every video has finished.
        """
        with self._lock:
            total = self._finished_frames + self._open_counted_sum
            if self._open_uncounted:
                if not self._counted_n:
                    return None
                total += round(self._open_uncounted * self._counted_sum / self._counted_n)
            return max(total, self.frames_done)

    def expect(self, index: int, frames: int | None) -> None:
        """Job ``index`` is expected to track ``frames`` frames (None: not known)."""
        if frames is None:
            return
        with self._lock:
            if self._expected[index] is not None:
                return
            self._expected[index] = frames
            self._counted_sum += frames
            self._counted_n += 1
            if not self._finished[index]:
                self._open_counted_sum += frames
                self._open_uncounted -= 1

    def advance(self, index: int, done: int) -> None:
        """Job ``index`` has tracked ``done`` frames so far."""
        with self._lock:
            if not self._finished[index] and done > self._done[index]:
                self.frames_done += done - self._done[index]
                self._done[index] = done

    def finish(self, index: int, outcome: VideoOutcome) -> None:
        """Job ``index`` has settled as ``outcome``."""
        with self._lock:
            if self._finished[index]:
                return
            self._finished[index] = True
            # A completed video's own count is exact; a failed one keeps what it had tracked.
            frames = outcome.frames if outcome.status == "ok" else self._done[index]
            self.frames_done += frames - self._done[index]
            self._done[index] = frames
            self._finished_frames += frames
            if self._expected[index] is None:
                self._open_uncounted -= 1
            else:
                self._open_counted_sum -= self._expected[index]
            self._count(outcome.status)

    def _count(self, status: str) -> None:
        self.ok += status == "ok"
        self.failed += status == "failed"
        self.skipped += status == "skipped"


#: Seconds the end of a batch waits for its frame-counting thread to leave the container it is reading.
_COUNTING_JOIN_SECONDS = 10.0


def _count_frames_in_background(jobs: Sequence[VideoJob], progress: BatchProgress) -> Callable[[], None]:
    """Read every job's announced frame count into ``progress`` in a daemon thread, in the order the jobs
    run; call the returned function to stop it (it waits for the container being read, if any). In the
    background because opening thousands of containers (on a network file system, say) would otherwise hold up
    the start of the batch.

    The thread is waited for, not left behind: one still inside OpenCV when the interpreter exits aborts the
    process ("terminate called without an active exception", exit 134), which a batch whose videos all fail at
    once (missing files) did more often than not."""
    stop = threading.Event()

    def count() -> None:
        for index, job in enumerate(jobs):
            if stop.is_set():
                return
            try:
                progress.expect(index, announced_job_frames(job))
            except Exception:  # noqa: BLE001 - a count is only a display's estimate; the video fails on its own
                pass

    thread = threading.Thread(target=count, name="lptrack-frame-counts", daemon=True)
    thread.start()

    def stop_and_wait() -> None:
        stop.set()
        # Bounded: a container on a network file system that never answers must not hold up the end of the batch.
        thread.join(_COUNTING_JOIN_SECONDS)

    return stop_and_wait


def run_batch(plan: BatchPlan, *, jobs: int = 1, scheduler=None, stream: IO[str] | None = None,
              data_format: str = "csv",
              on_outcome: Callable[[VideoOutcome], None] | None = None,
              on_frames: Callable[[int], None] | None = None,
              on_progress: Callable[[BatchProgress], None] | None = None,
              on_note: Callable[[str], None] | None = None) -> BatchSummary:
    """Run a :func:`plan_batch` plan; return every video's outcome in input order.

    Parameters
    ----------
    jobs : int
        Worker processes (1: in this process).
    scheduler : str or dask.distributed.Client, optional
        Run on this Dask cluster instead.
    stream : text stream, optional
        Where streamed rows go (the plan must have been made with ``stream=True``): one CSV header (with the
        ``video`` column) first, then each video's rows together, in input order whatever order they finish in.
    on_outcome : callable, optional
        Called with each video's outcome as it settles (progress display).
    on_frames : callable, optional
        Called with the total frames tracked so far, as workers report them.
    on_progress : callable, optional
        Called with a :class:`BatchProgress` (frames done and expected, videos done) whenever it changes:
        as frames are tracked, in this process or in local worker processes (each reports a few times a
        second), and as each video settles. Dask workers report nothing until their video is done, so on a
        cluster the frames advance one finished video at a time.
    on_note : callable, optional
        Called with a sentence for the user (see :func:`~logpolar_track.executor.run_tasks`).
    """
    started = time.perf_counter()
    outcomes = dict(plan.settled)
    existing = {p for job in plan.jobs for p in plan.output_folders(job) if p.exists()}
    # The header goes out with the first rows, or once the batch has run: a batch that stops before (a Dask
    # scheduler that cannot be reached) leaves nothing on stdout.
    header_due = stream is not None and data_format == "csv"
    next_out = 0

    def write_header() -> None:
        nonlocal header_due
        if header_due:
            stream.write(header_line(video=True))
            header_due = False

    def flush_stream() -> None:
        nonlocal next_out
        while next_out < len(plan.order) and plan.order[next_out] in outcomes:
            rows = outcomes[plan.order[next_out]].rows
            if stream is not None and rows:
                write_header()
                stream.write(rows)
            next_out += 1
        if stream is not None:
            stream.flush()

    for outcome in plan.settled.values():
        if on_outcome is not None:
            on_outcome(outcome)
    flush_stream()
    done_frames = [0] * len(plan.jobs)
    shown = None if on_progress is None else BatchProgress(len(plan.jobs), list(plan.settled.values()))
    stop_counting = None if shown is None else _count_frames_in_background(plan.jobs, shown)
    if shown is not None:
        on_progress(shown)

    def progress(index: int, done: int) -> None:
        done_frames[index] = done
        if on_frames is not None:
            on_frames(sum(done_frames))
        if shown is not None:
            shown.advance(index, done)
            on_progress(shown)

    def worker_died(index: int, pid: int) -> None:
        remove_temporary_outputs(plan.jobs[index], pid)

    try:
        for result in run_tasks(run_job, plan.jobs, jobs=jobs, scheduler=scheduler, on_progress=progress,
                                on_worker_death=worker_died, on_note=on_note):
            outcome = _settle(plan.jobs[result.index], result)
            done_frames[result.index] = outcome.frames
            outcomes[outcome.label] = outcome
            if on_frames is not None:
                on_frames(sum(done_frames))
            if on_outcome is not None:
                on_outcome(outcome)
            if shown is not None:
                shown.finish(result.index, outcome)
                on_progress(shown)
            flush_stream()
        if stream is not None:
            write_header()
            stream.flush()
    finally:
        if stop_counting is not None:
            stop_counting()
        # Failed and interrupted videos leave no outputs, nor folders made only for them (the others' folders
        # hold their outputs, so are not empty).
        remove_empty_folders({p for job in plan.jobs for p in plan.output_folders(job)} - existing)
    return BatchSummary([replace(outcomes[label], rows=None) for label in plan.order],
                        time.perf_counter() - started)


def _settle(job: VideoJob, result: TaskOutcome) -> VideoOutcome:
    if result.ok:
        return result.value
    # The job's paths are absolute (a worker's current folder may differ); the line names the outputs below the
    # current folder relatively and the video as given, as a single run does (in that order: a video given by its
    # absolute path stays so).
    error, video = result.error, str(job.video)
    here = Path.cwd()
    if here != Path(here.anchor):
        error = error.replace(f"'{here}{os.sep}", "'")
        video = video.removeprefix(f"{here}{os.sep}")
    error = error.replace(f"'{video}'", f"'{job.label}'")
    return VideoOutcome(job.label, "failed", error)
