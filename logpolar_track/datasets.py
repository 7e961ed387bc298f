"""Sequences with ground truth: lptrack's sample videos and public benchmark folders (OTB, VOT, UAV123, LaSOT,
GOT-10k, TrackingNet).

:func:`discover` finds every sequence under a folder; a :class:`Sequence` streams its frames (one decoded at a
time) and carries its ground truth (:class:`~logpolar_track.evaluate.GroundTruth`) and initial ROI.

Layouts recognised (file names case-sensitive as published); boxes are x,y,w,h in pixels, the top-left corner
then width and height, one line per frame:

lptrack samples
    ``<name>.mp4`` (or ``.avi``, ``.mkv``, ``.mov``, ``.webm``) with ``<name>.gt.csv`` beside it; initial ROI
    from ``<name>.roi`` (one line in ``--roi`` syntax) or else the first ground-truth ellipse.
OTB
    ``img/0001.jpg ...`` + ``groundtruth_rect.txt`` (x,y,w,h, 1-based; several targets as
    ``groundtruth_rect.1.txt``, ``.2.txt``: one sequence each).
VOT
    frames in the folder itself, in ``imgs/`` or in ``color/`` + ``groundtruth.txt`` (x,y,w,h or an 8-number
    quadrilateral per line, 0-based).
UAV123
    ``img/`` + ``<folder name>.txt`` (x,y,w,h, 1-based).
LaSOT
    ``<class>/<class>-<n>/img/00000001.jpg ...`` + ``groundtruth.txt`` (x,y,w,h, 1-based) + ``full_occlusion.txt``
    and ``out_of_view.txt`` (one comma-separated 0/1 flag per frame, on one line). A frame flagged in either is not
    scored: the target is absent there and its box arbitrary (``1,1,-1,-1``, or the last box seen).
GOT-10k (train and val splits)
    ``GOT-10k_Val_000001/00000001.jpg ...`` + ``groundtruth.txt`` (x,y,w,h, 1-based) + ``absence.label`` (0/1 per
    line) and, if present, ``cover.label`` (visible share in eighths, 0-8). A frame with absence 1 or cover 0 is
    not scored. Frame rate :data:`GOT10K_FPS`. The test split's ``groundtruth.txt`` has the first frame's box only
    (the rest is kept for the evaluation server): such a sequence cannot be scored and is skipped as unread.
TrackingNet
    a split folder (``TRAIN_0`` ... ``TRAIN_11``, ``TEST``) holding ``frames/<video>/0.jpg, 1.jpg ...`` and
    ``anno/<video>.txt`` (x,y,w,h, 0-based); a ``frames/<video>`` folder alone is read with its ``anno`` file too.
    The test split's files have one line (the first frame's box): skipped as unread, as GOT-10k's test split.

Line ``k`` of a benchmark ground-truth file belongs to the ``k``-th frame image in natural sort order (``10.jpg``
after ``9.jpg``). Frames without a ground-truth line (more frames than lines), NaN lines, empty boxes and frames a
benchmark flags as absent are not scored. The tracker is started on the first frame that has ground truth, from
the ellipse inscribed in that box (rotated rectangle for VOT polygons). 1-based boxes (Matlab's convention: the
top-left pixel is (1, 1)) are moved by -1 pixel in x and y. Image sequences carry no frame rate; ``time_s``
assumes :data:`IMAGE_FPS` (GOT-10k: :data:`GOT10K_FPS`).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Iterator

import numpy as np

from .errors import InputError, UsageError, VideoError, is_whole
from .evaluate import GroundTruth, GroundTruthError, read_box_text, read_gt_csv, there_and_back_rows
from .geometry import Ellipse
from .pipeline import read_roi_sidecar
from .video import VIDEO_EXTENSIONS

#: Frame rate assumed for image sequences (OTB, VOT, LaSOT and TrackingNet are mostly 30 fps captures), frames per
#: second.
IMAGE_FPS = 30.0
#: GOT-10k's frame rate (its videos were cut and annotated at 10 frames per second), frames per second.
GOT10K_FPS = 10.0
IMAGE_EXTENSIONS = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")
#: How many folders below a dataset folder sequences are looked for (`discover`).
SEARCH_DEPTH = 3


@dataclass
class Sequence:
    """One sequence: where its frames are, its ground truth and its initial ROI. Picklable, small.

    Attributes
    ----------
    name : str
        Display name (folder name or video stem).
    kind : str
        ``lptrack``, ``otb``, ``vot``, ``uav123``, ``lasot``, ``got10k`` or ``trackingnet``.
    path : Path
        The sequence folder, or the video file.
    gt_path : Path
        The ground-truth file.
    gt : GroundTruth
        One row per frame (rows beyond the file's end are NaN, i.e. unscored).
    roi : Ellipse
        Initial ROI, applied on frame ``start``.
    start : int
        Index of the frame the tracker is initialised on (the first with ground truth; 0 with a ``.roi``).
    n_frames : int
        Number of frames (for videos: the container's count, which may be approximate; 0 if unknown).
    fps : float
        Frames per second (:data:`IMAGE_FPS` for image sequences, :data:`GOT10K_FPS` for GOT-10k's).
    frame_files : tuple of Path or None
        Frame images in order, for image sequences.
    played_backwards : bool
        Made by :meth:`backwards`: frame ``k`` is the ``k``-th image from the last.
    frame_step : int
        Made by :meth:`every`: frame ``k`` is frame ``first_frame + k * frame_step`` of the source as played
        (backwards too, when :meth:`backwards` came first; 1: every frame).
    first_frame : int
        The frame of the source, as played, that is frame 0 here (0 unless made by :meth:`every`).
    notes : tuple of str
        What may put the ground truth out of step with the frames, found on reading the folder (a line count other
        than the image count, image numbers that skip): for a report to show.
    passes, pass_frames : int
        Made by :meth:`there_and_back`: the frames are played in ``passes`` passes, forwards and backwards in turn,
        the first ``pass_frames`` long and each later one a frame shorter (otherwise 1 and 0).
    """

    name: str
    kind: str
    path: Path
    gt_path: Path
    gt: GroundTruth
    roi: Ellipse
    start: int
    n_frames: int
    fps: float
    frame_files: tuple | None = None
    played_backwards: bool = False
    frame_step: int = 1
    first_frame: int = 0
    notes: tuple = ()
    passes: int = 1
    pass_frames: int = 0

    def frames(self) -> Iterator[tuple[int, float, np.ndarray]]:
        """Yield ``(index, time_s, frame)`` for every frame, decoding one at a time (BGR uint8).

        Raises
        ------
        VideoError
            If the video cannot be opened or a frame image cannot be read.
        """
        if self.frame_files is not None:
            # Times as the source's: frame k was image first_frame + k * frame_step at fps * frame_step.
            yield from _image_frames(self.frame_files, self.fps, self.first_frame / (self.fps * self.frame_step))
        elif self.frame_step == 1 and self.first_frame == 0:
            yield from _video_frames(self.path)
        else:
            # A video is decoded in order whatever is kept; time_s stays the video's own.
            for index, time_s, frame in _video_frames(self.path):
                offset = index - self.first_frame
                if offset >= 0 and offset % self.frame_step == 0:
                    yield offset // self.frame_step, time_s, frame

    def frame_name(self, index: int) -> str:
        """Where frame ``index`` comes from, for messages: its image's path, or ``frame N of VIDEO`` (N counted
        from 0 in the video as decoded)."""
        if self.frame_files is not None:
            return f"'{self.frame_files[index]}'"
        return f"frame {self.first_frame + index * self.frame_step} of '{self.path}'"

    def backwards(self) -> "Sequence":
        """This sequence played backwards, named ``<name>-backwards``: its frames from the last to the first, the
        ground truth reversed with them (:meth:`~logpolar_track.evaluate.GroundTruth.reversed`), started on the
        last frame with ground truth from the ellipse inscribed in its box.

        The same footage poses other tracking problems this way (an object grows where it shrank, arrives where it
        left, passes an occluder from the other side): a check on sequences a tracker was not tuned on.

        Raises
        ------
        UsageError
            For a video: only image sequences are played backwards (a video would have to be decoded whole).
        """
        if self.frame_files is None:
            raise UsageError(f"'{self.name}' is a video ({self.path.name}); only image sequences (OTB, VOT, UAV123, "
                             "LaSOT, GOT-10k, TrackingNet) can be played backwards")
        gt = self.gt.reversed()  # one row per frame already (see _image_sequence)
        return replace(self, name=f"{self.name}-backwards", gt=gt, roi=gt.initial_roi(), start=gt.first_valid,
                       frame_files=self.frame_files[::-1], played_backwards=True)

    def every(self, n: int) -> "Sequence":
        """This sequence at 1/``n`` of its frame rate, named ``<name>-every<n>``: its frame ``start`` (the tracker's
        first: the first with ground truth, or frame 0 with a ``.roi`` sidecar) and every ``n``-th frame after it,
        with their ground truth (:meth:`~logpolar_track.evaluate.GroundTruth.every`). The same footage with ``n``
        times the motion between frames: a check of how a tracker's search copes with fast motion. ``n`` = 1 gives
        the sequence itself.

        Raises
        ------
        UsageError
            ``n`` below 1.
        """
        if not (is_whole(n) and n >= 1):  # 1.5 failed in slicing, True was 1
            raise UsageError(f"every takes a whole number of frames >= 1, got {n!r}")
        if n == 1:
            return self
        files = None if self.frame_files is None else self.frame_files[self.start::n]
        if files is not None:
            n_frames = len(files)
        else:  # a video's count is its container's, 0 when unknown
            n_frames = -(-(self.n_frames - self.start) // n) if self.n_frames > self.start else 0
        return replace(self, name=f"{self.name}-every{n}", gt=self.gt.every(self.start, n), start=0, n_frames=n_frames,
                       fps=self.fps / n, frame_files=files, frame_step=self.frame_step * n,
                       first_frame=self.first_frame + self.start * self.frame_step)

    def there_and_back(self, passes: int) -> "Sequence":
        """This sequence played forwards and backwards in turn, ``passes`` passes over its frames from ``start`` (2:
        there and back; :func:`~logpolar_track.evaluate.there_and_back_rows`), named ``<name>-passes<passes>``, each
        frame with its own ground truth.

        A long run over known footage: the ground truth of a frame is the same on every pass, so a tracker that
        does not drift scores alike on each (see :func:`~logpolar_track.bench.auc_per_pass`). 1 gives the
        sequence itself.

        Raises
        ------
        UsageError
            ``passes`` below 1, or a video (only image sequences are played backwards).
        """
        if not (is_whole(passes) and passes >= 1):
            raise UsageError(f"passes takes a whole number >= 1, got {passes!r}")
        if passes == 1:
            return self
        if self.frame_files is None:
            raise UsageError(f"'{self.name}' is a video ({self.path.name}); only image sequences (OTB, VOT, UAV123, "
                             "LaSOT, GOT-10k, TrackingNet) can be played there and back")
        rows = there_and_back_rows(self.start, len(self.frame_files), passes)
        return replace(self, name=f"{self.name}-passes{passes}", gt=self.gt.there_and_back(self.start, passes),
                       start=0, n_frames=len(rows), frame_files=tuple(self.frame_files[i] for i in rows),
                       passes=passes, pass_frames=len(self.frame_files) - self.start)

    def describe(self) -> dict:
        """Plain-data summary for reports (JSON)."""
        return {"name": self.name, "kind": self.kind, "path": str(self.path), "ground_truth": str(self.gt_path),
                "frames": self.n_frames, "scored_frames": int(self.gt.valid[: self.n_frames or None].sum()),
                "rotated_ground_truth": bool(self.gt.rotated), "start_frame": self.start,
                "roi": self.roi.to_spec(), "backwards": self.played_backwards, "frame_step": self.frame_step,
                "first_frame": self.first_frame, "passes": self.passes, "pass_frames": self.pass_frames}


def _image_frames(files, fps: float, first_time_s: float = 0.0):
    import cv2

    from .video import opencv_path

    for i, path in enumerate(files):
        frame = cv2.imread(opencv_path(path, "image"), cv2.IMREAD_COLOR)
        if frame is None:
            raise VideoError(f"cannot read frame image '{path}'; expected a JPEG/PNG image")
        yield i, first_time_s + i / fps, frame


def _video_frames(path: Path):
    from .video import VideoReader

    with VideoReader(path) as reader:
        yield from reader


def _natural_key(path: Path):
    return _natural_name_key(path.name)


def _natural_name_key(name: str):
    return [int(t) if t.isdigit() else t.lower() for t in _DIGITS.split(name)]


_DIGITS = re.compile(r"(\d+)")
_TRAILING_NUMBER = re.compile(r"(\d+)$")


def _images_in(folder: Path) -> list[Path]:
    if not folder.is_dir():
        return []
    # Hidden files (macOS's ._0001.jpg beside 0001.jpg, copied from its disks) are not frames. os.scandir's entries
    # know whether they are files without a stat() each: a LaSOT or TrackingNet root lists millions of images.
    with os.scandir(folder) as entries:
        names = [e.name for e in entries
                 if not e.name.startswith(".") and os.path.splitext(e.name)[1].lower() in IMAGE_EXTENSIONS
                 and e.is_file()]
    return [folder / name for name in sorted(names, key=_natural_name_key)]


def _image_sequence(name: str, kind: str, folder: Path, gt_path: Path, files: list[Path], *,
                    one_based: bool | None = None, absent=None, flags: dict | None = None,
                    fps: float = IMAGE_FPS) -> Sequence:
    """An image sequence; ``absent`` (bool per line) marks lines not scored, as its ``flags`` files say (``{path:
    values}``, each noted if shorter than the ground truth)."""
    full = read_box_text(gt_path, source=kind, one_based=one_based, absent=absent)
    gt = full.truncated(len(files))
    if not gt.valid.any():
        # Said of the file: in a root of a thousand sequences, "the ground truth has no frame with a valid box" alone
        # left the user to find which.
        flagged = f", or flagged absent by {' or '.join(p.name for p in flags)}" if flags else ""
        raise GroundTruthError(f"'{gt_path}' has no box to start the tracker from on any of the {len(files)} "
                               f"images: every line is NaN, empty (w or h <= 0){flagged}")
    start = gt.first_valid
    notes = tuple(f"{path} has {len(values)} flags for the {len(full)} lines of {gt_path}; the lines past its end "
                  f"are scored as though the target were present" for path, values in (flags or {}).items()
                  if len(values) < len(full))
    return Sequence(name, kind, folder, gt_path, gt, gt.initial_roi(), start, len(files), fps, tuple(files),
                    notes=_alignment_notes(gt_path, len(full), files) + notes)


def _alignment_notes(gt_path: Path, n_lines: int, files: list[Path]) -> tuple[str, ...]:
    """What may put a folder's ground truth out of step with its images, which are matched line ``k`` to the
    ``k``-th image: a line count other than the image count, or image numbers that skip (a missing image moves every
    later line onto the next image's frame)."""
    notes = []
    if n_lines < len(files):
        notes.append(f"{gt_path} has {n_lines} lines for {len(files)} images; line k is matched to the k-th image "
                     f"from the first, and the images after the last line are not scored (an OTB sequence whose "
                     f"ground truth starts later, as David's at image 300, needs its images from there only)")
    elif n_lines > len(files):
        notes.append(f"{gt_path} has {n_lines} lines for {len(files)} images; line k is matched to the k-th image, "
                     f"and the lines after the last image are not used")
    numbers = [_TRAILING_NUMBER.search(os.path.splitext(f.name)[0]) for f in files]
    if all(numbers) and len(numbers) > 1:
        values = [int(m.group(1)) for m in numbers]
        gap = next((i for i in range(1, len(values)) if values[i] != values[i - 1] + 1), None)
        if gap is not None:
            notes.append(f"{files[gap].parent}: image numbers skip from {files[gap - 1].name} to {files[gap].name}; "
                         f"lines are still matched to images in order")
    return tuple(notes)


def _video_info(path: Path) -> tuple[int, float]:
    import cv2

    from .video import opencv_path

    cap = cv2.VideoCapture(opencv_path(path, "video"))
    try:
        if not cap.isOpened():
            raise VideoError(f"cannot open video '{path}'; expected a readable video file")
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    finally:
        cap.release()
    return max(n, 0), (fps if fps > 0 and math.isfinite(fps) else IMAGE_FPS)


def video_sequence(video: Path, gt_path: Path | None = None) -> Sequence:
    """The lptrack sample ``video`` with its ``<stem>.gt.csv`` and optional ``.roi`` sidecar
    (:func:`~logpolar_track.pipeline.read_roi_sidecar`).

    Raises
    ------
    GroundTruthError, RoiError, VideoError
        Missing or unreadable sidecar, malformed ROI, video that does not open.
    """
    video = Path(video)
    stem = video.name[: -len(video.suffix)]
    gt_path = Path(gt_path) if gt_path else video.with_name(stem + ".gt.csv")
    gt = read_gt_csv(gt_path)
    n, fps = _video_info(video)
    roi = read_roi_sidecar(video)  # as lptrack run reads it
    if roi is not None:
        start = 0
    else:
        roi, start = gt.initial_roi(), gt.first_valid
    if n and len(gt) < n:
        gt = gt.truncated(n)
    return Sequence(stem, "lptrack", video, gt_path, gt, roi, start, n, fps, None)


def _read_flags(path: Path) -> np.ndarray:
    """The whole numbers of a benchmark's per-frame label file, in order: LaSOT's ``full_occlusion.txt`` (one line,
    comma-separated) or GOT-10k's ``absence.label`` (one per line)."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise GroundTruthError(f"cannot read '{path}': {exc.strerror or exc}") from None
    fields = [f for f in re.split(r"[,\s]+", text) if f]
    try:
        return np.array([int(float(f)) for f in fields], int)
    except ValueError:
        bad = next(f for f in fields if not re.fullmatch(r"[-+]?\d+(\.0*)?", f))
        raise GroundTruthError(f"'{path}': '{bad[:20]}' is not a whole number; expected one number per frame, "
                               "separated by commas or line breaks") from None


def _absent(flags: list[np.ndarray]) -> np.ndarray:
    """Frames any of ``flags`` (0/1 arrays, of any lengths) marks, as one boolean array."""
    out = np.zeros(max(len(f) for f in flags), bool)
    for f in flags:
        out[: len(f)] |= f != 0
    return out


#: LaSOT's per-frame flags beside its groundtruth.txt: a frame flagged in either has no target to score.
_LASOT_FLAGS = ("full_occlusion.txt", "out_of_view.txt")


def _has_lasot_flags(folder: Path) -> bool:
    """Whether both of LaSOT's flag files are in ``folder``."""
    return all((folder / name).is_file() for name in _LASOT_FLAGS)


def _first_box_only(whose: str) -> str:
    """What a test split's ground truth is, said of ``whose`` ("GOT-10k's test split"), after "it has"."""
    return (f"one line, the first frame's box ({whose}, whose ground truth is kept for its evaluation server): nothing "
            f"to score")


def _lasot_flags(folder: Path) -> tuple[dict, np.ndarray]:
    """A LaSOT sequence folder's flag files (``{path: values}``) and the frames they mark absent."""
    flags = {folder / name: _read_flags(folder / name) for name in _LASOT_FLAGS}
    return flags, _absent(list(flags.values()))


def _lasot_sequence(folder: Path, img: list[Path]) -> Sequence:
    """A LaSOT sequence folder: ``img/`` + ``groundtruth.txt`` (1-based x,y,w,h) + its absence flags."""
    flags, absent = _lasot_flags(folder)
    gt_path = folder / "groundtruth.txt"
    return _image_sequence(folder.name, "lasot", folder, gt_path, img, one_based=True, absent=absent, flags=flags)


def _is_got10k(folder: Path) -> bool:
    """Whether ``folder`` looks like a GOT-10k sequence (its labels, its meta_info.ini or its published name)."""
    return (folder.name.startswith("GOT-10k_") or (folder / "absence.label").is_file()
            or (folder / "meta_info.ini").is_file())


def _one_line(path: Path) -> bool:
    """Whether a ground-truth text has at most one non-empty line (a test split's: the first frame's box only)."""
    try:
        with path.open("rb") as f:
            return sum(1 for line in f if line.strip()) <= 1
    except OSError:
        return False


def _got10k_fps(folder: Path) -> float:
    """``anno_fps`` of a GOT-10k ``meta_info.ini`` (``anno_fps: 10Hz``), else :data:`GOT10K_FPS`."""
    try:
        found = re.search(r"^anno_fps:\s*([0-9.]+)", (folder / "meta_info.ini").read_text(errors="replace"), re.M)
    except OSError:
        found = None
    fps = float(found.group(1)) if found and re.fullmatch(r"\d+(\.\d*)?", found.group(1)) else 0.0
    return fps if fps > 0 else GOT10K_FPS


def _got10k_flags(folder: Path) -> tuple[dict, np.ndarray]:
    """A GOT-10k sequence folder's ``absence.label`` (and ``cover.label`` if present) as ``{path: values}``, and the
    frames they mark absent (absence 1 or cover 0)."""
    flags = {folder / "absence.label": _read_flags(folder / "absence.label")}
    cover = folder / "cover.label"
    if cover.is_file():
        flags[cover] = _read_flags(cover)
    absent = _absent([flags[folder / "absence.label"]] + ([(flags[cover] == 0).astype(int)] if cover in flags
                                                          else []))
    return flags, absent


def _got10k_sequence(folder: Path, files: list[Path]) -> Sequence:
    """A GOT-10k train or val sequence: frames in the folder + ``groundtruth.txt`` (1-based x,y,w,h) +
    ``absence.label`` (and ``cover.label`` if present)."""
    flags, absent = _got10k_flags(folder)
    gt_path = folder / "groundtruth.txt"
    return _image_sequence(folder.name, "got10k", folder, gt_path, files, one_based=True, absent=absent,
                           fps=_got10k_fps(folder), flags=flags)


def _got10k_unscored(folder: Path) -> str | None:
    """Why a GOT-10k sequence folder (frames + ``groundtruth.txt``) cannot be scored, or None if it can."""
    gt_path = folder / "groundtruth.txt"
    if _one_line(gt_path):
        return "groundtruth.txt with " + _first_box_only("GOT-10k's test split")
    if not (folder / "absence.label").is_file():
        return ("GOT-10k's groundtruth.txt and images but no absence.label beside them, which says the frames "
                "where the target is absent")
    return None


def _is_trackingnet_split(folder: Path) -> bool:
    """Whether ``folder`` is a TrackingNet split (``TRAIN_0`` ... ``TEST``): ``frames/`` and ``anno/`` in it."""
    return (folder / "frames").is_dir() and (folder / "anno").is_dir()


def _trackingnet_split(folder: Path) -> tuple[list[Sequence], list[tuple[Path, str]]]:
    """The sequences of a TrackingNet split, and what it holds that cannot be scored: the videos whose ``anno``
    file has one line (the test split's), those without frames and those without an ``anno`` file."""
    frames, anno = folder / "frames", folder / "anno"
    with os.scandir(anno) as entries:
        boxes = {e.name[:-4]: anno / e.name for e in entries
                 if e.name.endswith(".txt") and not e.name.startswith(".") and e.is_file()}
    with os.scandir(frames) as entries:
        videos = {e.name for e in entries if not e.name.startswith(".") and e.is_dir()}
    found: list[Sequence] = []
    first_only: list[str] = []
    unread: list[tuple[Path, str]] = []
    for name in sorted(boxes.keys() | videos, key=_natural_name_key):
        if name not in videos:
            unread.append((boxes[name], f"no frames in '{frames / name}'"))
            continue
        files = _images_in(frames / name)
        if name not in boxes or not files:
            unread.append((frames / name, f"no ground truth '{anno / (name + '.txt')}'" if files
                           else "no images"))
        elif _one_line(boxes[name]) and len(files) > 1:
            first_only.append(name)
        else:
            found.append(_image_sequence(name, "trackingnet", frames / name, boxes[name], files, one_based=False))
    if first_only:
        why = _first_box_only("TrackingNet's test split")
        if found or unread:
            unread.extend((frames / name, f"{anno / (name + '.txt')} of {why}") for name in first_only)
        else:
            count = "1 video whose" if len(first_only) == 1 else f"{len(first_only)} videos whose"
            unread.append((folder, f"{count} anno/<video>.txt has {why}"))
    return found, unread


def _trackingnet_video(folder: Path) -> Path | None:
    """The ``anno/<video>.txt`` of a TrackingNet ``frames/<video>`` folder, or None."""
    if folder.parent.name != "frames":
        return None
    anno = folder.parent.parent / "anno" / f"{folder.name}.txt"
    return anno if anno.is_file() else None


#: Sub-folders that hold a sequence's frames (OTB's and UAV123's ``img/``; VOT's ``imgs/`` or ``color/``, or the
#: folder itself): never searched for sequences of their own.
_OTB_FRAME_FOLDER = "img"
_VOT_FRAME_FOLDERS = ("imgs", "color")
_FRAME_FOLDERS = frozenset((_OTB_FRAME_FOLDER, *_VOT_FRAME_FOLDERS))
#: A TrackingNet split's folders, read through :func:`_trackingnet_split`: never searched for sequences of their own.
_TRACKINGNET_FOLDERS = frozenset(("frames", "anno", "zips"))


def sequences_in(folder: Path) -> list[Sequence]:
    """The sequences stored directly in ``folder`` (no recursion); empty if it is not a sequence folder."""
    folder = Path(folder)
    found: list[Sequence] = []
    # lptrack samples: videos with a .gt.csv sidecar.
    for video in sorted(folder.iterdir(), key=_natural_key):
        if video.suffix.lower() in VIDEO_EXTENSIONS and video.is_file():
            stem = video.name[: -len(video.suffix)]
            if (folder / (stem + ".gt.csv")).is_file():
                found.append(video_sequence(video))
    if found:
        return found
    # OTB: img/ + groundtruth_rect.txt (or one file per target).
    img = _images_in(folder / _OTB_FRAME_FOLDER)
    otb = sorted(folder.glob("groundtruth_rect*.txt"), key=_natural_key)
    if img and otb:
        for gt_path in otb:
            suffix = gt_path.name[len("groundtruth_rect"):-len(".txt")].strip(".")
            name = folder.name + (f"-{suffix}" if suffix else "")
            found.append(_image_sequence(name, "otb", folder, gt_path, img))
        return found
    # LaSOT: img/ + groundtruth.txt + the absence flags.
    vot = folder / "groundtruth.txt"
    if img and vot.is_file() and _has_lasot_flags(folder):
        return [_lasot_sequence(folder, img)]
    # GOT-10k: groundtruth.txt + absence.label + frames in the folder (the test split's, one line: not scored).
    if vot.is_file() and _is_got10k(folder):
        files = _images_in(folder)
        if files:
            return [] if _got10k_unscored(folder) else [_got10k_sequence(folder, files)]
    # TrackingNet: a split (frames/ + anno/), or one frames/<video> folder.
    if _is_trackingnet_split(folder):
        return _trackingnet_split(folder)[0]
    anno = _trackingnet_video(folder)
    if anno is not None:
        files = _images_in(folder)
        if files and not (_one_line(anno) and len(files) > 1):
            return [_image_sequence(folder.name, "trackingnet", folder, anno, files, one_based=False)]
        return []
    # VOT: groundtruth.txt + frames in the folder, imgs/ or color/.
    if vot.is_file():
        for sub in (folder, *(folder / name for name in _VOT_FRAME_FOLDERS)):
            files = _images_in(sub)
            if files:
                return [_image_sequence(folder.name, "vot", folder, vot, files)]
    # UAV123: img/ + <name>.txt.
    uav = folder / f"{folder.name}.txt"
    if img and uav.is_file():
        return [_image_sequence(folder.name, "uav123", folder, uav, img)]
    return []


def discover(path, unread: list[tuple[Path, str]] | None = None) -> list[Sequence]:
    """Every sequence in ``path``: a sequence folder, a folder of sequence folders, or a sample video.

    Sub-folders are searched (up to three levels) except below an image sequence's folder. Results are in
    natural order of their paths. A folder that holds frames or ground truth but is not a sequence lptrack reads
    (OTB's ``img/`` without its ``groundtruth_rect.txt``, say), or a video without its ``.gt.csv`` beside videos with
    theirs, is skipped; ``unread``, if given, gets ``(folder or video, what it lacks)`` for each.

    Raises
    ------
    InputError
        If ``path`` does not exist.
    UsageError
        If ``path`` is a file that is not a video.
    GroundTruthError, RoiError, VideoError
        If a sequence's ground truth, ROI sidecar or video cannot be read.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"dataset '{path}' does not exist; give a folder of sequences or a sample video")
    if path.is_file():
        if path.suffix.lower() in VIDEO_EXTENSIONS:
            return [video_sequence(path)]
        raise UsageError(f"dataset '{path}' is a file; give a folder of sequences or a video with a .gt.csv")
    return _discover(path, SEARCH_DEPTH, [] if unread is None else unread)


def _discover(folder: Path, depth: int, unread: list[tuple[Path, str]]) -> list[Sequence]:
    split = _is_trackingnet_split(folder)
    if split:
        # Its frames/<video> folders are sequences read with anno/: not searched one by one, nor anno/ and zips/. Its
        # other folders are searched as any folder's are: OTB or VOT sequences beside a frames/ and an anno/ folder
        # of the user's own were lost without a word.
        found, skipped = _trackingnet_split(folder)
        unread.extend(skipped)
    else:
        found = sequences_in(folder)
    if found and found[0].frame_files is not None and not split:
        return found  # an image sequence's folder: what is below it are its frames
    if found and not split:
        # Videos with their ground truth, as lptrack samples writes them: those without are said to be skipped, and
        # the folders beside them searched, as 'lptrack run' searches a folder.
        with_truth = {s.path for s in found}
        lacking = [p for p in sorted(folder.iterdir(), key=_natural_key)
                   if p.suffix.lower() in VIDEO_EXTENSIONS and p.is_file() and p not in with_truth]
        unread.extend((video, f"no {video.name[:-len(video.suffix)]}.gt.csv ground truth beside it")
                      for video in lacking)
    if depth > 0:
        skip = _FRAME_FOLDERS | _TRACKINGNET_FOLDERS if split else _FRAME_FOLDERS
        for sub in sorted((p for p in folder.iterdir()
                           if p.is_dir() and not p.name.startswith(".") and p.name not in skip),
                          key=_natural_key):
            found.extend(_discover(sub, depth - 1, unread))
    if not found and not split:
        # Said only where nothing was found below: a stray image or video beside sequence folders is no sequence.
        lacking = _what_it_lacks(folder)
        if lacking is None and depth == 0 and _has_subfolders(folder):
            # The search stops here: sequences below (LaSOT's <class>/<class>-<n> under /data/LaSOT/LaSOTBenchmark,
            # four down from /data) were left out in silence.
            lacking = (f"sub-folders below the {SEARCH_DEPTH} levels searched under a dataset; give a folder nearer "
                       f"its sequences (its parent, say) as the dataset")
        if lacking is not None:
            unread.append((folder, lacking))
    return found


def _has_subfolders(folder: Path) -> bool:
    """Whether ``folder`` holds a folder :func:`_discover` would search (not hidden, not a frames folder)."""
    try:
        with os.scandir(folder) as entries:
            return any(e.is_dir() and not e.name.startswith(".") and e.name not in _FRAME_FOLDERS for e in entries)
    except OSError:
        return False


def _what_it_lacks(folder: Path) -> str | None:
    """For a folder that is not a sequence (:func:`sequences_in` found none) but holds frames, a ground-truth file
    or videos: what it lacks to be one, as a phrase after "it has". None for any other folder, or one that cannot be
    read."""
    try:
        if (folder / "groundtruth.txt").is_file() and _is_got10k(folder) and _images_in(folder):
            return _got10k_unscored(folder)
        anno = _trackingnet_video(folder)
        if anno is not None:
            return f"{anno} of " + _first_box_only("TrackingNet's test split") if _images_in(folder) else None
        otb_frames = _images_in(folder / _OTB_FRAME_FOLDER)
        vot_frames = next((sub for sub in (folder, *(folder / n for n in _VOT_FRAME_FOLDERS)) if _images_in(sub)),
                          None)
        truth = sorted(folder.glob("groundtruth*.txt"), key=_natural_key) + [
            p for p in (folder / f"{folder.name}.txt",) if p.is_file()]
        videos = any(p.suffix.lower() in VIDEO_EXTENSIONS for p in folder.iterdir() if p.is_file())
    except OSError:
        return None
    frames = folder / _OTB_FRAME_FOLDER if otb_frames else vot_frames
    if frames is None:
        if truth:
            return f"{truth[0].name} but no images (in img/, imgs/, color/ or the folder itself)"
        return "videos but no <name>.gt.csv ground truth beside them (as lptrack samples writes)" if videos else None
    readers = (f"groundtruth_rect.txt (OTB) or {folder.name}.txt (UAV123)" if otb_frames
               else "groundtruth.txt (VOT)")
    if not truth:
        return f"images in '{frames}' but no ground truth beside them; with images there lptrack reads {readers}"
    if otb_frames and truth[0].name == "groundtruth.txt":
        lacking = " and ".join(name for name in _LASOT_FLAGS if not (folder / name).is_file())
        return (f"groundtruth.txt and images in '{frames}' but not LaSOT's {lacking} beside them, which say the "
                f"frames where the target is absent; with images there lptrack reads groundtruth.txt with those "
                f"(LaSOT), {readers}")
    return (f"{truth[0].name} and images in '{frames}', which lptrack does not read together; with images there it "
            f"reads {readers}")


def load_ground_truth(path) -> GroundTruth:
    """Ground truth from a file in any supported format, or from a sequence folder / sample video.

    A LaSOT or GOT-10k ``groundtruth.txt`` and a TrackingNet ``anno/<video>.txt`` are read with their sequence (its
    absence flags, one row per image), as :func:`discover` reads them; without its frames beside it, with its flags
    and coordinates' origin all the same, one row per line.

    Raises
    ------
    InputError
        If ``path`` does not exist.
    UsageError
        If ``path`` is a folder holding no sequence or several, or the ground truth of a test split (its first
        frame's box only).
    GroundTruthError
        If the file cannot be read.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"ground truth '{path}' does not exist")
    if path.is_file() and path.suffix.lower() not in VIDEO_EXTENSIONS:
        from .evaluate import read_ground_truth

        flagged = _flagged_sequence_folder(path)
        if flagged is not None:  # read with its flags and its coordinates' origin, as bench reads it
            kind, folder = flagged
            if not _images_in(folder / _OTB_FRAME_FOLDER if kind == "lasot" else folder):
                return _ground_truth_without_frames(path, kind, folder)
            return discover_one(folder, "give the ground truth of a sequence with a box for every frame (a train "
                                        "or val split's)").gt
        return read_ground_truth(path)
    return discover_one(path, "give one sequence folder or ground-truth file (.gt.csv, groundtruth_rect.txt, "
                              "groundtruth.txt, <name>.txt)").gt


def _flagged_sequence_folder(path: Path) -> tuple[str, Path] | None:
    """The benchmark (``lasot``, ``got10k``, ``trackingnet``) and sequence folder a LaSOT or GOT-10k
    ``groundtruth.txt``, or a TrackingNet ``anno/<video>.txt`` (``frames/<video>``, extracted or not), belongs to:
    its labels and coordinates' origin are known only with it. None for any other file."""
    folder = path.parent
    if path.name == "groundtruth.txt" and _has_lasot_flags(folder):
        return "lasot", folder
    if path.name == "groundtruth.txt" and _is_got10k(folder):
        return "got10k", folder
    split = folder.parent
    if folder.name == "anno" and path.suffix == ".txt" and ((split / "frames").is_dir() or (split / "zips").is_dir()):
        return "trackingnet", split / "frames" / path.stem
    return None


def _ground_truth_without_frames(path: Path, kind: str, folder: Path) -> GroundTruth:
    """A LaSOT, GOT-10k or TrackingNet ground-truth file whose frames are not beside it (the annotations kept
    without the images, which scoring a run does not need), read as :func:`discover` reads it with them: with its
    absence flags and from its coordinates' origin, one row per line.

    Raises
    ------
    UsageError
        A test split's file (its first frame's box only), or a GOT-10k one without ``absence.label``.
    """
    if _one_line(path):
        raise UsageError(f"'{path}' has " + _first_box_only("a test split's") + "; give the ground truth of a "
                         "sequence with a box for every frame (a train or val split's)")
    if kind == "trackingnet":
        return read_box_text(path, source=kind, one_based=False)
    if kind == "got10k" and not (folder / "absence.label").is_file():
        raise UsageError(f"'{path}' is GOT-10k's, but no absence.label is beside it, which says the frames where "
                         f"the target is absent; give the sequence's labels with its ground truth")
    _, absent = _lasot_flags(folder) if kind == "lasot" else _got10k_flags(folder)
    return read_box_text(path, source=kind, one_based=True, absent=absent)


def ground_truth_file(path) -> Path:
    """The file :func:`load_ground_truth` reads for ``path``: ``path`` itself, or the ground-truth file of the
    sequence folder or video it names."""
    path = Path(path)
    if path.is_file() and path.suffix.lower() not in VIDEO_EXTENSIONS:
        return path
    return discover_one(path, "give one sequence folder or ground-truth file").gt_path


def discover_one(path, expected: str) -> Sequence:
    """The one sequence in ``path`` (:func:`discover`).

    Raises
    ------
    UsageError
        If ``path`` holds none or several: how many, what a folder that looks like a sequence lacks, then
        ``expected``.
    """
    unread: list[tuple[Path, str]] = []
    found = discover(path, unread)
    if len(found) == 1:
        return found[0]
    why = next((f": it has {lacking}" for folder, lacking in unread if folder == Path(path)), "")
    raise UsageError(f"'{path}' holds {len(found)} sequences{why}; {expected}")


__all__ = ["Sequence", "discover", "discover_one", "sequences_in", "video_sequence", "load_ground_truth",
           "ground_truth_file",
           "GroundTruthError", "IMAGE_FPS", "GOT10K_FPS"]
