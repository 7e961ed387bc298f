"""``lptrack run``: track one object through one video; write the annotated video and the per-frame CSV."""

from __future__ import annotations

import os
import sys
import textwrap
from pathlib import Path

import click

from ..errors import RoiError, UsageError
from ..geometry import ROI_SYNTAX, parse_roi
from ..pipeline import CSV_OUT_SUFFIX, DEFAULT_TRACKER, VIDEO_OUT_SUFFIX, default_outputs, run_video
from ..results import COLUMNS
from ..trackers import tracker_class, tracker_names
from . import EXIT_FAILURE, main


class OneLineErrors(click.Command):
    """A command whose argument errors are one ``lptrack: error:`` line (exit 2), not click's usage block.

    Its epilog is built when help is shown, so it lists trackers registered after this module was imported.
    """

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        try:
            return super().parse_args(ctx, args)
        except click.UsageError as exc:
            raise UsageError(f"{exc.format_message()} (see 'lptrack {self.name} --help')") from None

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


def _tracker_lines() -> str:
    """One wrapped entry per registered tracker, from the registry's summaries."""
    lines = []
    for name in tracker_names(include_unavailable=True):
        cls = tracker_class(name)
        notes = [n for n, on in (("default", name == DEFAULT_TRACKER),
                                 ("not installed here", not getattr(cls, "available", lambda: True)())) if on]
        head = f"{name}" + (f" ({', '.join(notes)})" if notes else "")
        lines.append(f"  {head}")
        lines += textwrap.wrap(cls.summary, width=74, initial_indent="      ", subsequent_indent="      ")
    return "\n".join(lines)


def _epilog() -> str:
    """Help text after the options: ROI syntax, CSV columns, the registered trackers, examples."""
    return f"""\b
ROI (--roi, or one line in a sidecar file VIDEO-stem.roi next to the video):
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

\b
Trackers:
{_tracker_lines()}

\b
Examples:
  lptrack run clip.mp4 --roi 320,240,40
  lptrack run clip.mp4 --roi 320,240,60,30,15 --tracker diffdecomp
  lptrack run clip.mp4 --roi 320,240,40 --no-video --csv - > track.csv
"""


@main.command("run", cls=OneLineErrors)
@click.argument("video", type=click.Path(dir_okay=True, path_type=Path), metavar="VIDEO")
@click.option("--roi", "roi_spec", metavar="SPEC",
              help="Object on the start frame: 'cx,cy,r' or 'cx,cy,a,b,angle' (pixels; degrees CCW). "
                   "Default: read from VIDEO's .roi sidecar.")
@click.option("--tracker", type=TrackerChoice(), default=DEFAULT_TRACKER, show_default=True, metavar="NAME",
              help="Tracking method (see the list below).")
@click.option("--start-frame", type=click.IntRange(min=0), default=0, show_default=True, metavar="N",
              help="Frame index (0 = first) the ROI refers to; tracking starts there.")
@click.option("--out", "video_out", type=click.Path(dir_okay=False, path_type=Path), metavar="VIDEO_OUT",
              help=f"Annotated video to write. Default: <video stem>{VIDEO_OUT_SUFFIX} in the current folder. "
                   f"Extension .mp4/.mov (mp4v), .avi (MJPG), .mkv or .webm; falls back to MJPG .avi.")
@click.option("--csv", "csv_out", metavar="CSV_OUT",
              help=f"Per-frame CSV to write; '-' for stdout (then nothing else goes to stdout). "
                   f"Default: <video stem>{CSV_OUT_SUFFIX} in the current folder.")
@click.option("--no-video", is_flag=True, help="Do not write the annotated video (faster).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar, no summary line on stderr.")
def run(video: Path, roi_spec: str | None, tracker: str, start_frame: int, video_out: Path | None,
        csv_out: str | None, no_video: bool, overwrite: bool, quiet: bool) -> None:
    """Track the object inside a circle or ellipse through VIDEO.

    Writes an annotated copy of the video (the tracked outline, a radius line
    that turns with the object, a readout of frame, scale, rotation and score;
    lost frames in red) and a CSV with centre, size, scale and rotation per
    frame. Outputs are written to temporary names and renamed when complete;
    existing files are kept unless --overwrite is given.
    """
    roi = None
    if roi_spec is not None:
        try:
            roi = parse_roi(roi_spec)
        except RoiError as exc:
            message = str(exc)
            raise RoiError(message if ROI_SYNTAX in message else f"{message}; expected {ROI_SYNTAX}") from None
    if no_video and video_out is not None:
        raise UsageError("--out and --no-video contradict each other; give one of them")
    default_video, default_csv = default_outputs(video)
    if not no_video and video_out is None:
        video_out = default_video
    if csv_out is None:
        csv_out = str(default_csv)
    show = not quiet
    try:
        summary = run_video(video, roi, tracker=tracker, start_frame=start_frame,
                            video_out=None if no_video else video_out, csv_out=csv_out, overwrite=overwrite,
                            progress=show and sys.stderr.isatty())
    except BrokenPipeError:
        # `lptrack run ... --csv - | head`: the reader left; stop quietly, without Python's shutdown noise.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(EXIT_FAILURE)
    if not show:
        return
    if summary.video_fps_guessed:
        click.echo(f"lptrack: warning: '{video}' reports no frame rate; assumed {summary.video_fps:g} fps "
                   f"for time_s and the output video", err=True)
    if summary.video_out is not None and video_out is not None and summary.video_out != Path(video_out):
        click.echo(f"lptrack: warning: could not write '{video_out}'; wrote '{summary.video_out}' "
                   f"({summary.fourcc}) instead", err=True)
    outputs = []
    if summary.video_out is not None:
        outputs.append(f"video {summary.video_out} ({summary.fourcc}, {summary.video_fps:g} fps)")
    if summary.csv_out is not None:
        outputs.append("CSV to stdout" if summary.csv_out == "-" else f"CSV {summary.csv_out}")
    click.echo(f"lptrack: {video.name}: {summary.frames} frames ({summary.lost} lost) with {summary.tracker} "
               f"at {summary.processing_fps:.1f} frames/s; {'; '.join(outputs)}", err=True)
