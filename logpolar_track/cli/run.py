"""``lptrack run``: track one object through one video, or through many; write annotated videos and CSVs.

One video file runs in this process with a frame progress bar (:func:`~logpolar_track.pipeline.run_video`).
Several inputs, folders, ``-`` or a ROI file make a batch (:mod:`logpolar_track.batch`): videos run in worker
processes or on a Dask cluster, one failing video never stops the others, and a summary ends the run.
"""

from __future__ import annotations

import contextlib
import os
import select
import sys
import textwrap
import time
from dataclasses import replace
from pathlib import Path

import click

from ..batch import (VIDEO_EXTENSIONS, BatchProgress, BatchSummary, VideoOutcome, find_videos, mirrored_output_base,
                     outputs_complete, plan_batch, read_roi_file, run_batch)
from ..errors import OutputError, UsageError, counted
from ..executor import default_jobs
from ..pipeline import (CSV_OUT_SUFFIX, DEFAULT_TRACKER, VIDEO_OUT_SUFFIX, check_outputs, default_outputs,
                        resolve_roi, roi_sidecar_paths, run_video)
from ..results import COLUMNS, FORMATS, stdout_errors
from ..trackers import tracker_class, tracker_names
from ..trackers.base import check_available, did_you_mean
from ..outputs import make_output_folder, remove_empty_folders, run_in_output_folders, writes_in_place
from ..video import (IMAGE_EXTENSIONS, VideoReader, check_fps, guess_image_sequence, input_label, is_image_sequence,
                     read_frame)
from . import (EXIT_FAILURE, PARAM_HELP, FrameRate, OneLineErrors, PathParam, TimeParam, WholeNumber,
               check_jobs_or_scheduler, echo_progress, main, parse_param_options, parse_roi_option,
               stdout_reader_left)


class RunCommand(OneLineErrors):
    """``lptrack run``: its epilog is built when help is shown, so it lists trackers registered after import."""

    def format_epilog(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        self.epilog = _epilog()
        super().format_epilog(ctx, formatter)


class TrackerChoice(click.Choice):
    """``click.Choice`` over the tracker registry, read when used (trackers may register after import)."""

    def __init__(self) -> None:
        super().__init__((), case_sensitive=True)

    @property
    def choices(self) -> tuple[str, ...]:
        return tuple(tracker_names(include_unavailable=True))

    @choices.setter
    def choices(self, value) -> None:  # click.Choice.__init__ assigns; the registry is the source instead
        pass

    def convert(self, value, param, ctx):
        if value in self.choices:
            return value
        self.fail(f"'{value}' is not a tracker{did_you_mean(str(value), self.choices)}; choose one of: "
                  f"{', '.join(self.choices)}", param, ctx)


#: What each of FORMATS is called in messages.
_FORMAT_NAMES = {"csv": "CSV", "jsonl": "JSON lines"}
#: Data-file extensions of formats lptrack does not write: (what readers take the file for, whether that is a
#: compression).
_OTHER_DATA_SUFFIXES = {".json": ("one JSON document", False), ".tsv": ("tab-separated values", False),
                        ".parquet": ("Parquet", False), ".xlsx": ("Excel", False), ".gz": ("gzip", True),
                        ".bz2": ("bzip2", True), ".xz": ("xz", True), ".zst": ("zstd", True), ".zip": ("zip", True)}


def _tracker_lines() -> str:
    """One wrapped entry per registered tracker, from the registry's summaries."""
    lines = []
    for name in tracker_names(include_unavailable=True):
        cls = tracker_class(name)
        notes = [n for n, on in (("default", name == DEFAULT_TRACKER),
                                 ("not installed here", not cls.available())) if on]
        head = f"{name}" + (f" ({', '.join(notes)})" if notes else "")
        lines.append(f"  {head}")
        lines += textwrap.wrap(cls.summary, width=74, initial_indent="      ", subsequent_indent="      ")
    return "\n".join(lines)


def _epilog() -> str:
    """Help text after the options: ROI syntax, CSV columns, batches, the registered trackers, examples."""
    return f"""\b
ROI (--roi, a --roi-file line, or one line in a sidecar VIDEO-stem.roi):
  cx,cy,r          circle: centre and radius in pixels
  cx,cy,a,b,angle  ellipse: semi-axes a, b in pixels; angle of axis a in
                   degrees counter-clockwise as seen on screen
  Pixels of the start frame, origin top-left, x right, y down. The ROI may
  hang over the border but its centre must be in the frame and at least half
  of it inside.

\b
CSV columns (one row per frame):
  {",".join(COLUMNS)}
  scale is relative to the first row; rotation_deg is counter-clockwise on
  screen, cumulative (unwrapped); score in [0, 1]; status init/tracked/lost.
  --format jsonl writes the same as JSON lines (empty fields as null).

\b
Many videos (several VIDEOs, folders searched recursively, '-' = paths on
stdin, or --roi-file alone):
  ROI per video: its --roi-file line (video,roi[,start_frame][,tracker]),
  else --roi, else its .roi sidecar; a video with none fails alone.
  Outputs mirror the inputs under --out-dir (default: the current folder;
  --parents: each input's path as given, for lists split by xargs), or
  --csv - streams every video's rows with a leading 'video' column.
  Videos run in --jobs processes or on a Dask cluster (--scheduler); one bad
  video never stops the others. Exit 0 all ok, 1 any failed, 2 bad
  arguments, 130 interrupted (only complete outputs are left).

\b
Trackers:
{_tracker_lines()}

\b
Examples:
  lptrack run clip.mp4 --roi 320,240,40
  lptrack run clip.mp4 --roi 320,240,60,30,15 --tracker diffdecomp
  lptrack run clip.mp4 --roi 320,240,40 --param learning_rate=0.05
  lptrack run clip.mp4 --roi 320,240,40 --no-video --csv - > track.csv
  lptrack run 'shots/frame_%04d.png' --fps 30 --roi 320,240,40   # image sequence
  lptrack run footage/ --roi-file rois.csv --out-dir tracks --jobs 4
  find footage -name '*.mp4' | lptrack run - --roi-file rois.csv --no-video --csv - > all.csv
"""


@main.command("run", cls=RunCommand)
@click.argument("videos", nargs=-1, metavar="VIDEO...", type=PathParam())
@click.option("--roi", "roi_spec", metavar="SPEC",
              help="Object on the start frame: 'cx,cy,r' or 'cx,cy,a,b,angle' (pixels; degrees CCW). "
                   "Default: the video's .roi sidecar.")
@click.option("--roi-file", type=PathParam(path_type=Path), metavar="CSV",
              help="ROIs per video: lines 'video,roi[,start_frame][,tracker]' (paths relative to the file; '-': "
                   "standard input, paths relative to the current folder). With no VIDEO, its videos are the "
                   "inputs.")
@click.option("--tracker", type=TrackerChoice(), default=DEFAULT_TRACKER, show_default=True, metavar="NAME",
              help="Tracking method (see the list below).")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE", help=PARAM_HELP)
@click.option("--start-frame", type=WholeNumber(min=0), default=0, show_default=True, metavar="N",
              help="Frame index (0 = first) the ROI refers to; tracking starts there.")
@click.option("--start-time", type=TimeParam(), default=None, metavar="TIME",
              help="Instead of --start-frame: the frame at this time, in seconds (83.5) or HH:MM:SS (1:23.5), as "
                   "'lptrack frame --time' finds it (one video only).")
@click.option("--frames", "max_frames", type=WholeNumber(min=1), default=None, metavar="N",
              help="Track N frames (the start frame included), then stop. Default: to the end of the video.")
@click.option("--fps", type=FrameRate(), default=None, metavar="RATE",
              help="Frames per second of the input, for time_s and the annotated video, as FFmpeg's -framerate: "
                   "an image sequence's (it has none: 25 is assumed), or instead of a video's own.")
@click.option("--out", "-o", "video_out", type=PathParam(), metavar="VIDEO_OUT",
              help=f"Annotated video to write (one input only). Default: <video stem>{VIDEO_OUT_SUFFIX}. "
                   f"Extension .mp4/.m4v/.mov (mp4v), .avi (MJPG), .mkv or .webm; falls back to MJPG .avi.")
@click.option("--csv", "csv_out", metavar="CSV_OUT", type=PathParam(),
              help=f"Per-frame CSV to write (one input only), or '-' for stdout (then nothing else goes to "
                   f"stdout). Default: <video stem>{CSV_OUT_SUFFIX}.")
@click.option("--out-dir", type=PathParam(path_type=Path), metavar="DIR",
              help="Folder for the outputs lptrack names (created if needed), mirroring the inputs' folders; "
                   "--out and --csv paths are used as given. Default: the current folder.")
@click.option("--parents", is_flag=True,
              help="Name outputs after each input's path as given, folders included, as cp --parents: "
                   "cams/day1/cam.mp4 -> DIR/cams/day1/cam.lptrack.csv, whatever else is in the run (for lists "
                   "split by xargs or parallel). Absolute paths and paths going up (..) are mirrored from the root.")
@click.option("--format", "data_format", type=click.Choice(tuple(FORMATS)), default=None,
              help="Per-frame data as CSV or JSON lines. Default: from the --csv file's extension (.jsonl: JSON "
                   "lines), else CSV.")
@click.option("--no-video", is_flag=True, help="Do not write annotated videos (faster).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--skip-existing", is_flag=True,
              help="Leave alone videos whose outputs all exist and cover the frames asked for from the same ROI; "
                   "redo (replace) the others (resumes an interrupted batch).")
@click.option("--jobs", "-j", type=WholeNumber(min=1), default=None, metavar="N",
              help="Videos tracked in parallel processes. Default: the number of cores.")
@click.option("--scheduler", metavar="ADDRESS",
              help="Run the videos on this Dask scheduler (e.g. tcp://10.0.0.5:8786) instead; needs "
                   "pip install 'dask[distributed]' and the files at the same paths on the workers.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar and no summary on stderr (failures still).")
def run(videos: tuple[str, ...], roi_spec: str | None, roi_file: Path | None, tracker: str,
        params: tuple[str, ...], start_frame: int, start_time: float | None, max_frames: int | None, fps: float | None,
        video_out: str | None, csv_out: str | None, out_dir: Path | None, parents: bool, data_format: str,
        no_video: bool, overwrite: bool, skip_existing: bool, jobs: int | None, scheduler: str | None,
        quiet: bool) -> None:
    """Track the object inside a circle or ellipse through VIDEO (or many).

    VIDEO is a video file, or an image sequence named as FFmpeg takes it
    (frame_%04d.png: frame_0001.png, frame_0002.png, ...).

    Writes an annotated copy of the video (the tracked outline, a radius line
    that turns with the object, a readout of frame, scale, rotation and score;
    lost frames in red) and a CSV with centre, size, scale and rotation per
    frame. Outputs are written to temporary names and renamed when complete;
    existing files are kept unless --overwrite is given.
    """
    roi = None if roi_spec is None else parse_roi_option(roi_spec)
    _refuse_folder_as_file(video_out, "output video")
    _refuse_folder_as_file(csv_out, "output CSV")
    video_out = None if video_out is None else Path(video_out)
    suffix = Path(csv_out).suffix.lower() if csv_out else ""
    if data_format is None:
        data_format = "jsonl" if suffix == FORMATS["jsonl"] else "csv"
    elif suffix in FORMATS.values() and suffix != FORMATS[data_format] and not quiet:
        # As ffmpeg's -f, --format wins over the name; but a name that says otherwise misleads whoever opens it.
        click.echo(f"lptrack: note: writing {_FORMAT_NAMES[data_format]} to '{csv_out}' (--format {data_format}), "
                   f"whose name says {_FORMAT_NAMES[next(k for k, v in FORMATS.items() if v == suffix)]}", err=True)
    if suffix in _OTHER_DATA_SUFFIXES and not quiet:
        # pandas.read_csv('t.csv.gz') decompresses by the name, and fails on plain text.
        what, compressed = _OTHER_DATA_SUFFIXES[suffix]
        instead = "lptrack does not compress" if compressed else "lptrack writes CSV or JSON lines (--format jsonl)"
        click.echo(f"lptrack: note: writing {_FORMAT_NAMES[data_format]} to '{csv_out}', whose name says {what}; "
                   f"{instead}", err=True)
    if no_video and video_out is not None:
        raise UsageError("--out and --no-video contradict each other; give one of them")
    if overwrite and skip_existing:
        raise UsageError("--overwrite and --skip-existing contradict each other; give one of them")
    check_jobs_or_scheduler(jobs is not None, scheduler)
    check_fps(fps)
    if skip_existing and csv_out == "-":
        # The rows on stdout are no output to keep: with one video the annotated video was replaced regardless.
        raise UsageError("--skip-existing needs outputs in files; it cannot apply to --csv -")
    if not videos and roi_file is None:
        raise UsageError("give a VIDEO (a file, a folder, or '-' for paths on stdin), or --roi-file "
                         "(see 'lptrack run --help')")
    # With --scheduler even one video goes to the cluster, as a batch of one.
    single = (len(videos) == 1 and videos[0] != "-" and not Path(videos[0]).is_dir() and roi_file is None
              and scheduler is None)
    # Given at all, 0 too (its default is 0).
    if start_time is not None and (click.get_current_context().get_parameter_source("start_frame")
                                   is not click.core.ParameterSource.DEFAULT):
        raise UsageError("--start-frame and --start-time both say where to start; give one of them")
    if single:
        tuning = parse_param_options(params, [tracker])[tracker]
        _check_out_dir(out_dir, video_out=video_out, csv_out=csv_out, no_video=no_video, quiet=quiet,
                       parents=parents)
        _run_one(Path(videos[0]), roi, tracker=tracker, tuning=tuning, start_frame=start_frame, start_time=start_time,
                 max_frames=max_frames, fps=fps, video_out=video_out, csv_out=csv_out, out_dir=out_dir, parents=parents,
                 data_format=data_format, no_video=no_video, overwrite=overwrite, skip_existing=skip_existing,
                 quiet=quiet)
        return
    # Inputs first: a malformed ROI file is the error to see, not what the outputs would have been.
    if roi_file is not None and str(roi_file) == "-" and "-" in videos:
        raise UsageError("'-' (standard input) can give the videos' paths or the ROI file, not both: give the ROI "
                         "file's path, or list the videos in it and leave VIDEO out")
    entries = read_roi_file(roi_file) if roi_file is not None else []
    if scheduler is not None and len(videos) == 1:
        many = "with --scheduler"
    elif roi_file is not None:
        many = "with --roi-file"
    elif "-" in videos:
        many = "with '-' (paths on stdin)"
    elif len(videos) == 1:
        many = "with a folder"
    else:
        many = "with several videos"
    if start_time is not None:
        # Each video's frame at that time would be found by decoding it up to there before the batch starts.
        raise UsageError(f"--start-time is for one video; {many} give --start-frame N, or a start_frame for each "
                         f"video in --roi-file")
    if video_out is not None:
        raise UsageError(f"--out names one video's output in this process; {many} give --out-dir DIR")
    if csv_out not in (None, "-"):
        raise UsageError(f"--csv names one video's output in this process; {many} give --out-dir DIR, "
                         f"or --csv - for one stream with a 'video' column")
    _check_out_dir(out_dir, video_out=None, csv_out=csv_out, no_video=no_video, quiet=quiet, parents=parents)
    stream = csv_out == "-"
    if stream and sys.stdout is None:
        raise OutputError("cannot write the rows to stdout: it is closed")
    if not videos and not entries:  # without VIDEO arguments the ROI file's videos are the inputs
        shown = "on standard input (--roi-file -)" if str(roi_file) == "-" else f"in ROI file '{roi_file}'"
        raise UsageError(f"no videos found {shown}: write one line per video, video,roi[,start_frame][,tracker]")

    def named_again(path: Path) -> None:
        if not quiet:
            click.echo(f"lptrack: note: '{path}' is named more than once; tracked once", err=True)

    def own_output(path: Path, source: Path) -> None:
        if not quiet:
            click.echo(f"lptrack: note: skipping '{path}': lptrack's annotated video of '{source}' (name it "
                       f"without its source to track it)", err=True)

    def link_passed(link: Path, to_folder: bool) -> None:
        if not quiet:
            why = ("a link to a folder, which folder searches do not follow (as find does not); name it to search it"
                   if to_folder else "a link to nothing")
            click.echo(f"lptrack: note: skipping '{link}': {why}", err=True)

    inputs = find_videos(videos, on_duplicate=named_again, on_own_output=own_output, on_link_passed=link_passed)
    _refuse_still_images(inputs)
    if videos and not inputs:
        folders = [Path(v) for v in videos if v != "-" and Path(v).is_dir()]
        why = ""
        if folders:
            why = f" (folders are searched for {', '.join(VIDEO_EXTENSIONS[:5])}, ... files"
            pattern = next(filter(None, map(guess_image_sequence, folders)), None)
            why += f"; for an image sequence give its images' pattern, e.g. '{pattern}')" if pattern else ")"
        raise UsageError(f"no videos found in {', '.join('stdin' if v == '-' else repr(v) for v in videos)}{why}")
    plan = plan_batch(inputs, roi=roi, roi_entries=entries, tracker=tracker, start_frame=start_frame,
                      max_frames=max_frames, fps=fps, out_dir=out_dir or ".", video=not no_video, stream=stream,
                      data_format=data_format, overwrite=overwrite, skip_existing=skip_existing, parents=parents)
    for name in dict.fromkeys(job.tracker for job in plan.jobs) if scheduler is None else ():
        # Before any video, as one video's run refuses it (exit 2): each video of the batch failed with it instead,
        # one line per video, exit 1. (A Dask cluster's workers may have the OpenCV this one lacks.)
        check_available(name)
    if params:
        # Checked against the trackers of the videos that will run, so that a parameter none of them takes is
        # an error, not silently unused.
        used = list(dict.fromkeys(job.tracker for job in plan.jobs)) or [tracker]
        tuning = parse_param_options(params, used)
        plan = replace(plan, jobs=[replace(job, tracker_params=tuning[job.tracker]) for job in plan.jobs])
    # The folder is made (or refused, in one line) once, up front; if the batch leaves nothing in it, it goes.
    created = make_output_folder(out_dir) if out_dir is not None else []
    try:
        summary = _run_many(plan, jobs=jobs or default_jobs(), scheduler=scheduler, stream=stream,
                            data_format=data_format, quiet=quiet)
    finally:
        remove_empty_folders(created)
    if summary.failed:
        sys.exit(EXIT_FAILURE)


def _refuse_still_images(inputs) -> None:
    """Refuse inputs that are all still images, several of them: a shell's glob over an image sequence (``lptrack
    run shots/*.png``, the pattern unquoted or written as a glob) made each image a video of one frame, as many CSVs
    of one row each, and exit 0. (Among videos, as in a list from ``find -type f``, each is tracked as ever: one
    input never stops the others.)"""
    stills = [video.path for video in inputs
              if video.path.suffix.lower() in IMAGE_EXTENSIONS and not is_image_sequence(video.path)]
    if len(stills) < 2 or len(stills) < len(inputs):
        return
    pattern = guess_image_sequence(stills[0].parent) or stills[0].parent / "frame_%04d.png"
    raise UsageError(f"'{stills[0]}' and {counted(len(stills) - 1, 'other input')} are still images, each of which "
                     f"would be tracked as a video of one frame; give an image sequence as its images' pattern, "
                     f"quoted so that the shell leaves it alone, e.g. '{pattern}'")


def _refuse_folder_as_file(name: str | None, what: str) -> None:
    """Refuse a folder given to ``-o`` or ``--csv`` (``--csv out/``, ``-o tracks``), with ``--out-dir`` as the hint:
    the file's check said "it is a folder" alone, and ``-o out/`` lost its slash to a path and was "unsupported
    extension ''"."""
    if name is None or name == "-" or not (name.endswith(("/", os.sep)) or os.path.isdir(name)):
        return
    folder = name.rstrip("/" + os.sep) or name
    raise OutputError(f"cannot write {what} '{name}': it {'is' if os.path.isdir(name) else 'names'} a folder; give a "
                      f"file name (outputs go into a folder with --out-dir {folder})")


def _check_out_dir(out_dir: Path | None, *, video_out: Path | None, csv_out: str | None, no_video: bool,
                   quiet: bool, parents: bool = False) -> None:
    """``--out-dir`` holds the outputs lptrack names, and ``--parents`` names them; outputs named on the command
    line go where named (as in FFmpeg). Never silently: an --out-dir or --parents left nothing is an error, an
    --out-dir left some outputs is noted."""
    if out_dir is None and not parents:
        return
    video_named = "--no-video" if no_video else (f"--out {video_out}" if video_out is not None else None)
    csv_named = None if csv_out is None else f"--csv {csv_out}"
    if video_named and csv_named:
        left_none = f"{csv_named} and {video_named} leave it none"
        if out_dir is not None:
            raise UsageError(f"--out-dir would hold nothing: it is the folder for the outputs lptrack names, and "
                             f"{left_none}; drop --out-dir, or put the folder in the names")
        raise UsageError(f"--parents would name nothing: it names the outputs lptrack names, and {left_none}; drop "
                         f"--parents")
    if out_dir is None:
        return
    named = [str(p) for p in (video_out, csv_out) if p is not None and str(p) != "-"]
    if named and not quiet:
        click.echo(f"lptrack: note: --out-dir holds the outputs lptrack names; '{named[0]}' is written where "
                   f"named", err=True)


def _reader_left(stream) -> bool:
    """Whether the reader of ``stream``, a pipe (``| head``), has gone: seen without writing, so that a batch
    stops when it happens rather than when the next video's rows are ready."""
    if stream is None or not hasattr(select, "poll"):
        return False
    try:
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):  # not a file (a test runner's buffer)
        return False
    poller = select.poll()
    poller.register(fd, 0)  # no event asked for: POLLERR (a pipe without reader) and POLLHUP come anyway
    return any(events & (select.POLLERR | select.POLLHUP) for _, events in poller.poll(0))


def _start_frame_at_time(video: Path, time_s: float, fps: float | None, quiet: bool) -> int:
    """The index of ``video``'s frame at ``time_s`` seconds, as ``lptrack frame --time`` finds it (decoding up to
    there: the run decodes those frames again), said on stderr."""
    frame = read_frame(video, time_s=time_s, fps=fps)
    if not quiet:
        # An image sequence has no times of its own: said here, where the rate decides the frame, not only later.
        assumed = f" at an assumed {frame.fps:g} fps; give --fps to set it" if frame.fps_guessed else ""
        click.echo(f"lptrack: note: {time_s:g} s is frame {frame.index} of {input_label(video)} (at "
                   f"{frame.time_s:.3f} s{assumed}); tracking starts there", err=True)
    return frame.index


def _run_one(video: Path, roi, *, tracker: str, tuning: dict, start_frame: int, start_time: float | None,
             max_frames: int | None, fps: float | None, video_out: Path | None, csv_out: str | None,
             out_dir: Path | None, parents: bool, data_format: str, no_video: bool, overwrite: bool,
             skip_existing: bool, quiet: bool) -> None:
    """One video in this process, errors raised as they are (exit 1 or 2)."""
    name = None
    if parents:  # _check_out_dir made sure lptrack names at least one of the outputs
        base = Path(out_dir or ".") / mirrored_output_base(video)
        out_dir, name = base.parent, base.name
    # A run that failed or was stopped leaves no folder made for it.
    run_in_output_folders(
        [] if out_dir is None else [out_dir],
        lambda: _run_one_into(video, roi, tracker=tracker, tuning=tuning, start_frame=start_frame,
                              start_time=start_time, max_frames=max_frames, fps=fps, video_out=video_out,
                              csv_out=csv_out, out_dir=out_dir, name=name, data_format=data_format, no_video=no_video,
                              overwrite=overwrite, skip_existing=skip_existing, quiet=quiet),
        # Rows sent to stdout, or written in place (/dev/stdout, a named pipe) before the first frame's video opens,
        # would be sent again.
        retry=csv_out is None or not (csv_out == "-" or writes_in_place(Path(csv_out))))


def _run_one_into(video: Path, roi, *, tracker: str, tuning: dict, start_frame: int, start_time: float | None,
                  max_frames: int | None, fps: float | None, video_out: Path | None, csv_out: str | None,
                  out_dir: Path | None, name: str | None, data_format: str, no_video: bool, overwrite: bool,
                  skip_existing: bool, quiet: bool) -> None:
    default_video, default_csv = default_outputs(video, out_dir or ".", name)
    if not no_video and video_out is None:
        video_out = default_video
    if csv_out is None:
        csv_out = str(default_csv.with_suffix(FORMATS[data_format]))
    show = not quiet
    label = input_label(video)
    if start_time is not None:
        # Finding the frame decodes the video up to that time (minutes into a long one): the input, its ROI and the
        # outputs are checked first, as a run checks them before its first frame.
        with VideoReader(video, fps=fps):
            pass
        roi = resolve_roi(roi, video)
        if not (overwrite or skip_existing):
            check_outputs(video, None if no_video else video_out, csv_out, overwrite=False)
        start_frame = _start_frame_at_time(video, start_time, fps, quiet)
    if skip_existing and outputs_complete(None if no_video else Path(video_out), Path(csv_out), source=video,
                                          start_frame=start_frame, max_frames=max_frames, roi=roi):
        if show:
            click.echo(f"lptrack: {label}: outputs exist; skipped (--skip-existing)", err=True)
        return
    try:
        summary = run_video(video, roi, tracker=tracker, start_frame=start_frame, max_frames=max_frames,
                            video_out=None if no_video else video_out, csv_out=csv_out,
                            overwrite=overwrite or skip_existing,
                            progress=(_stderr_is_terminal() or _LogProgress(label)) if show else False,
                            csv_options={"data_format": data_format},
                            tracker_params=tuning, fps=fps)
    except BrokenPipeError:
        stdout_reader_left()
    if csv_out == "-" and _reader_left(sys.stdout):
        stdout_reader_left()  # `| head` left after the last rows went into the pipe: as if their write had failed
    if summary.video_out is not None and video_out is not None and summary.video_out != Path(video_out):
        # Said under --quiet too: a script looks for the file it named.
        click.echo(f"lptrack: warning: could not write '{video_out}'; wrote '{summary.video_out}' "
                   f"({summary.fourcc}) instead", err=True)
    if not show:
        return
    if roi is None and start_frame > 0 and any(p.is_file() for p in roi_sidecar_paths(video)):
        click.echo(f"lptrack: note: the ROI came from {label}'s .roi file and was applied to start frame "
                   f"{start_frame}", err=True)
    if summary.video_fps_guessed:
        click.echo(f"lptrack: warning: {_rate_assumed(str(video), summary.video_fps, summary.video_out is not None)}",
                   err=True)
    if summary.undecodable:
        click.echo(f"lptrack: warning: {_undecodable(label, summary.undecodable)}", err=True)
    if summary.image_gaps:
        click.echo(f"lptrack: warning: {_image_gaps(label, summary.image_gaps)}", err=True)
    if summary.truncated:
        reached = summary.frames + summary.undecodable_frames
        click.echo(f"lptrack: warning: {_truncation(label, reached, summary.expected_frames)}", err=True)
    if summary.roi_flat:
        click.echo(f"lptrack: warning: {_flat_roi(label)}", err=True)
    if summary.timestamps_from is not None:
        varying = _varying_rate(label, summary.timestamps_from, summary.video_fps, summary.start_frame,
                                summary.video_out is not None)
        click.echo(f"lptrack: note: {varying}", err=True)
    outputs = []
    if summary.video_out is not None:
        outputs.append(f"video {summary.video_out} ({summary.fourcc}, {summary.video_fps:g} fps)")
    if summary.csv_out is not None:
        what = data_format.upper()
        outputs.append(f"{what} to stdout" if summary.csv_out == "-" else f"{what} {summary.csv_out}")
    click.echo(f"lptrack: {label}: {summary.frames} frame{'' if summary.frames == 1 else 's'} "
               f"({summary.lost} lost) with {summary.tracker} at {summary.processing_fps:.1f} frames/s; "
               f"{'; '.join(outputs)}", err=True)


def _rate_assumed(label: str, fps: float, video: bool) -> str:
    uses = "time_s and the output video" if video else "time_s"
    return f"'{label}' reports no frame rate; assumed {fps:g} fps for {uses} (give --fps to set it)"


def _flat_roi(label: str) -> str:
    return (f"{label}: the ROI covers a flat area on its start frame (one colour: a letterbox bar, a blank "
            f"wall?), with nothing in it to follow: its track means nothing; see where it lies with lptrack frame "
            f"VIDEO --roi SPEC")


def _varying_rate(label: str, first: int, fps: float, start: int, video: bool) -> str:
    played = f"; the annotated video plays at a constant {fps:g} fps" if video else ""
    if first == start:
        return f"{label}'s frame rate varies: time_s follows its timestamps, not frame / {fps:g} fps{played}"
    return (f"{label}'s frame rate varies: time_s follows its timestamps from frame {first} on (before, frame / "
            f"{fps:g} fps kept to them){played}")


def _image_gaps(label: str, gaps) -> str:
    frame, before, after = gaps[0]
    more = f" (and {counted(len(gaps) - 1, 'more gap')})" if len(gaps) > 1 else ""
    return (f"{label}: image numbers skip from {before} to {after}{more}; frames are the images in number order, "
            f"so frame {frame} is {after}")


def _undecodable(label: str, stretches) -> str:
    total = sum(count for _, count in stretches)
    shown = [str(first) if count == 1 else f"{first}-{first + count - 1}" for first, count in stretches[:5]]
    more = ", ..." if len(stretches) > 5 else ""
    return (f"{label}: {counted(total, 'frame')} could not be decoded (the file is damaged there) and "
            f"{'has' if total == 1 else 'have'} no row: {', '.join(shown)}{more}; tracking went on after "
            f"{'it' if total == 1 else 'them'}")


def _truncation(label: str, frames: int, expected: int) -> str:
    return (f"{label}: ended after {frames} of the {expected} frames its container announces (cut short or "
            f"damaged?); its outputs end there")


def _stderr_is_terminal() -> bool:
    """Whether stderr is a terminal: progress bars are drawn only there."""
    return sys.stderr.isatty()


def _run_many(plan, *, jobs: int, scheduler: str | None, stream: bool, data_format: str,
              quiet: bool) -> BatchSummary:
    """A batch: a progress bar of frames over all videos (with videos done and failed beside it), then the
    summary and every failure on stderr."""
    bar = None
    terminal = _stderr_is_terminal()
    if not quiet and terminal:
        from tqdm import tqdm

        # Frames, not videos: a bar of videos stands still for minutes when there are few long ones.
        bar = tqdm(total=None, unit="frame", file=sys.stderr, dynamic_ncols=True, leave=False, desc="lptrack")
    videos_shown = [-1]
    # Elsewhere (a log file, a CI job, a cluster's job output) a bar's carriage returns make a mess: one line per
    # video as it settles instead, so that a long batch shows how far it has got.
    videos_settled = [0]
    videos_total = len(plan.jobs) + len(plan.settled)
    log_progress = None if quiet or terminal else _LogProgress(f"0/{videos_total} videos done")

    def stop_if_reader_left() -> None:
        # No more work for rows no one reads: SystemExit stops the workers and removes their temporary files.
        if stream and _reader_left(sys.stdout):
            stdout_reader_left()

    def on_outcome(outcome: VideoOutcome) -> None:
        stop_if_reader_left()
        if not quiet and not terminal:
            videos_settled[0] += 1
            # Counted, not listed: a resumed batch (--skip-existing) of thousands would list every video done before.
            if outcome.status != "skipped":
                echo_progress(f"lptrack: {videos_settled[0]}/{videos_total} {_settled_line(outcome)}")

    def log_batch_progress(progress: BatchProgress) -> None:
        # 'lptrack: 3/9 videos done: 9000 of 90000 frames (10 %), 812 frames/s'
        log_progress.label = f"{progress.videos_done}/{videos_total} videos done"
        log_progress(progress.frames_done, progress.frames_total)

    def on_progress(progress: BatchProgress) -> None:
        bar.total = progress.frames_total
        if progress.videos_done != videos_shown[0]:
            videos_shown[0] = progress.videos_done
            failed = f", {progress.failed} failed" if progress.failed else ""
            bar.set_postfix_str(f"{progress.videos_done}/{progress.videos} videos{failed}", refresh=False)
            bar.update(progress.frames_done - bar.n)
            bar.refresh()
        else:
            bar.update(progress.frames_done - bar.n)  # tqdm redraws at most ten times a second

    def note(text: str) -> None:
        if quiet:
            return
        if bar is not None:
            bar.write(f"lptrack: note: {text}", file=sys.stderr)  # above the bar, not across it
        else:
            echo_progress(f"lptrack: note: {text}")

    interrupted = False
    try:
        with stdout_errors() if stream else contextlib.nullcontext():
            summary = run_batch(plan, jobs=jobs, scheduler=scheduler, stream=sys.stdout if stream else None,
                                data_format=data_format, on_outcome=on_outcome,
                                on_frames=lambda frames: stop_if_reader_left(),
                                on_progress=on_progress if bar is not None else (
                                    None if log_progress is None else log_batch_progress),
                                on_note=note)
        stop_if_reader_left()
    except BrokenPipeError:
        stdout_reader_left()
    except KeyboardInterrupt:  # Ctrl-C, and SIGTERM or SIGHUP as lptrack turns them into it
        interrupted = True
        raise
    finally:
        if bar is not None:
            bar.close()
        if interrupted and scheduler is not None and not quiet:
            # lptrack cannot stop Dask's workers: a --skip-existing rerun started at once raced the videos still
            # running there, whose outputs appeared after "interrupted".
            click.echo("lptrack: note: videos a Dask worker had started go on there and leave their outputs when "
                       "done (wait for them before a --skip-existing rerun); the others were cancelled", err=True)
    _report(summary, quiet=quiet, video=any(job.video_out is not None for job in plan.jobs))
    return summary


#: Seconds between the progress lines of a run whose stderr is not a terminal (see :class:`_LogProgress`).
_LOG_PROGRESS_SECONDS = 30.0


class _LogProgress:
    """Progress for a stderr that is not a terminal (a log, a CI job): a line every :data:`_LOG_PROGRESS_SECONDS`
    of a long run, ``lptrack: clip.mp4: 9000 of 90000 frames (10 %), 812 frames/s``, where a bar's redraws would
    fill the log; a run shorter than that says nothing more than its summary."""

    def __init__(self, label: str) -> None:
        self.label = label
        self.started = self.shown = time.monotonic()
        # The first report's time and frames: the rate leaves out opening the video, seeking to --start-frame and
        # starting the tracker (or a batch's workers), which made it read low for the rest of the run.
        self.first: tuple[float, int] | None = None

    def __call__(self, done: int, total: int | None) -> None:
        now = time.monotonic()
        if self.first is None and done > 0:  # a batch reports its 0 frames as it starts its workers
            self.first = (now, done)
        if now - self.shown < _LOG_PROGRESS_SECONDS:
            return
        self.shown = now
        of, share = (f" of {total}", f" ({100.0 * done / total:.0f} %)") if total else ("", "")
        since, before = self.first or (self.started, 0)
        if done > before and now > since:
            rate = (done - before) / (now - since)
        else:
            rate = done / max(now - self.started, 1e-9)
        echo_progress(f"lptrack: {self.label}: {done}{of} frames{share}, {rate:.0f} frames/s")


def _settled_line(outcome: VideoOutcome) -> str:
    """One video of a batch as it settles, for a stderr that is not a terminal: ``clip.mp4: 148 frames (2 lost)
    in 0.6 s``; a failure's reason is said again with the batch's summary, for a reader of its last lines."""
    if outcome.status == "failed":
        return f"{outcome.label}: failed: {outcome.reason}"
    lost = f" ({outcome.lost} lost)" if outcome.lost else ""
    return f"{outcome.label}: {counted(outcome.frames, 'frame')}{lost} in {outcome.seconds:.1f} s"


def _report(summary: BatchSummary, *, quiet: bool, video: bool) -> None:
    """The end of a batch on stderr: one summary line, then one line per failed or truncated video."""
    if not quiet:
        seconds = max(summary.seconds, 1e-9)
        parts = [f"{summary.count('ok')} ok"]
        if summary.count("skipped"):
            parts.append(f"{summary.count('skipped')} skipped (outputs exist)")
        parts.append(f"{summary.count('failed')} failed")
        ran = summary.count("ok") + summary.count("failed")
        count = len(summary.outcomes)
        # Rates only where something was tracked: a batch whose videos all failed at once has none worth a number.
        rates = (f" ({summary.frames / seconds:.1f} frames/s, {ran / seconds:.2f} videos/s)" if summary.frames
                 else "")
        click.echo(f"lptrack: {count} video{'' if count == 1 else 's'}: {', '.join(parts)}; {summary.frames} "
                   f"frame{'' if summary.frames == 1 else 's'} in {summary.seconds:.1f} s{rates}", err=True)
        for outcome in summary.outcomes:
            if outcome.fps_assumed is not None:
                click.echo(f"lptrack: warning: {_rate_assumed(outcome.label, outcome.fps_assumed, video)}", err=True)
            if outcome.undecodable:
                click.echo(f"lptrack: warning: {_undecodable(outcome.label, outcome.undecodable)}", err=True)
            if outcome.image_gaps:
                click.echo(f"lptrack: warning: {_image_gaps(outcome.label, outcome.image_gaps)}", err=True)
            if outcome.truncated:
                reached = outcome.frames + sum(count for _, count in outcome.undecodable)
                click.echo(f"lptrack: warning: {_truncation(outcome.label, reached, outcome.expected_frames)}",
                           err=True)
            if outcome.roi_flat:
                click.echo(f"lptrack: warning: {_flat_roi(outcome.label)}", err=True)
            if outcome.timestamps_from is not None:
                click.echo(f"lptrack: note: {_varying_rate(outcome.label, *outcome.timestamps_from, video)}",
                           err=True)
    for outcome in summary.failed:
        click.echo(f"lptrack: failed: {outcome.label}: {outcome.reason}", err=True)
