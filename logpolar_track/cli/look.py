"""``lptrack frame``, ``roi``, ``plot`` and ``sheet``: look at a video before a run and at a track after it.

Thin wrappers over the library: :mod:`logpolar_track.frame_png` (frame), :mod:`logpolar_track.roi_fit` (roi),
:mod:`logpolar_track.plot` (plot), :mod:`logpolar_track.contact_sheet` (sheet). Written files' paths go to stdout
(one per line), notes to stderr; errors are one ``lptrack: error:`` line.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import click

from ..contact_sheet import SHEET_ROWS, write_contact_sheet
from ..datasets import load_ground_truth
from ..errors import UsageError
from ..evaluate import read_run_csv, rows_past_ground_truth
from ..frame_png import write_frame_png
from ..geometry import check_roi_fits
from ..outputs import check_image_suffix
from ..pipeline import describe_video_search, find_streamed_video, find_video_for_csv
from ..plot import PLOT_SUFFIXES, matplotlib_hint, plot_track
from ..roi_fit import (ROUND_TOLERANCE, from_one_based, read_mask, roi_from_box, roi_from_mask, roi_from_points,
                       roi_from_quad)
from ..video import VIDEO_EXTENSIONS, input_label, read_frame
from . import (FrameRate, OneLineErrors, PathParam, TimeParam, WholeNumber, main, parse_roi_option, require_stdout,
               write_stdout)


def _default_png(csv_path: Path, out_png: Path | None, kind: str) -> Path:
    """``out_png``, or the default output of plot and sheet: ``clip.lptrack.csv`` -> ``clip.lptrack.<kind>.png``."""
    if out_png is not None:
        return out_png
    if str(csv_path) == "-":
        raise UsageError(f"the run comes from stdin ('-'), which names no PNG: give one with -o, e.g. -o {kind}.png")
    return Path(f"{csv_path.stem}.{kind}.png")


_VIDEO = PathParam(dir_okay=True, path_type=Path)


@main.command("frame", cls=OneLineErrors, epilog="""\b
Examples:
  lptrack frame clip.mp4                          # frame 0 -> clip.frame0.png
  lptrack frame clip.mp4 --at 120 --grid 20
  lptrack frame clip.mp4 --time 4.5 -o look.png
  lptrack frame clip.mp4 --roi 320,240,60,30,15   # -> clip.frame0.roi_320_240_60_30_15.png
""")
@click.argument("video", type=_VIDEO)
@click.option("--at", "index", type=int, metavar="N", help="Frame index, 0 = first frame of the file. Default 0.")
@click.option("--time", "time_s", type=TimeParam(), metavar="TIME",
              help="Instead of --at: the frame at this time, in seconds (4.8) or HH:MM:SS (0:04.8).")
@click.option("-o", "--out", "out_png", type=PathParam(dir_okay=False, path_type=Path), metavar="PNG",
              help="PNG to write. Default: <video stem>.frame<N>.png in the current folder "
                   "(with --roi: <video stem>.frame<N>.roi_<spec>.png).")
@click.option("--grid", type=WholeNumber(min=0), default=50, show_default=True, metavar="PX",
              help="Grid line spacing in pixels; 0 for no grid.")
@click.option("--roi", "roi_spec", metavar="SPEC",
              help="Draw this candidate ROI: 'cx,cy,r' or 'cx,cy,a,b,angle' (pixels; degrees CCW).")
@click.option("--fps", type=FrameRate(), default=None, metavar="RATE",
              help="Frames per second for --time instead of the video's own, as 'lptrack run --fps' (an image "
                   "sequence has none: 25 is assumed).")
@click.option("--overwrite", is_flag=True, help="Replace an existing PNG.")
def frame(video: Path, index: int | None, time_s: float | None, out_png: Path | None, grid: int,
          roi_spec: str | None, fps: float | None, overwrite: bool) -> None:
    """Write one frame of VIDEO as a PNG with a labelled pixel grid.

    The PNG has the frame's own size, so any image viewer's cursor position
    reads video pixels (x right, y down, origin top-left): read off an
    object's centre and radius for --roi. The frame is exactly the N-th
    decoded frame (earlier frames are decoded, not skipped by seeking).
    Prints the PNG's path on stdout.
    """
    require_stdout()  # for the PNG's path: checked before the PNG is written
    if index is not None and time_s is not None:
        raise UsageError("--at and --time contradict each other; give one of them")
    roi = parse_roi_option(roi_spec) if roi_spec is not None else None
    path = write_frame_png(video, out_png, index=index, time_s=time_s, grid=grid, roi=roi, overwrite=overwrite,
                           fps=fps)
    write_stdout(str(path) + "\n")


@main.command("roi", cls=OneLineErrors, epilog=f"""\b
3 or 4 points give the circle through them; 5 or more an ellipse (least
squares). A result whose semi-axes differ by at most --round-tol (default
{ROUND_TOLERANCE:g}, i.e. {ROUND_TOLERANCE:.0%}) is printed as a circle
cx,cy,r with the radius of equal area; --round-tol 0 keeps the ellipse.
Ellipses are printed with a >= b and the angle of axis a in (-90, 90]
degrees counter-clockwise as seen on screen.

--from-quad takes a rotated box's corners (VOT's ground truth) and gives
the ellipse inscribed in the smallest rectangle around them. --one-based
reads coordinates that count pixels from 1 (OTB's and UAV123's boxes).
--from-mask takes an image of the frame's size marking the object (a
segmentation): pixels above half its brightest, the largest region, give
the ellipse with the same second moments (scikit-image's regionprops).

\b
Examples:
  lptrack roi clip.mp4 --from-box 280,200,80,80          # -> 320,240,40
  lptrack roi clip.mp4 --from-points 380,240,320,270,260,240,320,210,362,261
  lptrack roi clip.mp4 --from-quad 300,250,340,210,380,250,340,290
  lptrack roi img/0001.jpg --from-box "$(head -1 groundtruth_rect.txt)" --one-based
  lptrack roi clip.mp4 --at 120 --from-mask object_mask.png
  lptrack run clip.mp4 --roi "$(lptrack roi clip.mp4 --from-box 280,200,120,60)"
""")
@click.argument("video", type=_VIDEO)
@click.option("--at", "index", type=WholeNumber(min=0), default=0, show_default=True, metavar="N",
              help="Frame the coordinates refer to (the ROI is checked against its size).")
@click.option("--from-box", "box", metavar="X,Y,W,H",
              help="Axis-aligned box: top-left corner and size in pixels; gives the inscribed ellipse.")
@click.option("--from-points", "points", metavar="X1,Y1,X2,Y2,...",
              help="Points on the object's outline in pixels (at least 3, spread around it).")
@click.option("--from-quad", "quad", metavar="X1,Y1,...,X4,Y4",
              help="A rotated box's four corners in pixels, in any order; gives the inscribed ellipse.")
@click.option("--from-mask", "mask_path", type=PathParam(path_type=Path), metavar="IMAGE",
              help="An image of the frame's size marking the object (bright on black, or a PNG's alpha); gives the "
                   "ellipse of equal moments.")
@click.option("--one-based", is_flag=True,
              help="Coordinates count pixels from 1, as Matlab's, OTB's and UAV123's do (1 is subtracted).")
@click.option("--round-tol", type=click.FloatRange(min=0.0, max=1.0), default=ROUND_TOLERANCE,
              show_default=True, metavar="FRACTION",
              help="Print a circle when the semi-axes differ by at most this fraction.")
def roi(video: Path, index: int, box: str | None, points: str | None, quad: str | None, mask_path: Path | None,
        one_based: bool, round_tol: float) -> None:
    """Turn a box, a rotated box's corners, points on an outline or a mask
    into a --roi spec, printed on stdout.

    For objects marked in another tool or a benchmark's ground truth. The
    ROI is checked as 'lptrack run' checks it (centre in the frame, at least
    half of it inside, semi-axes >= 2 px); a line on stderr shows how to
    draw it on the frame.
    """
    if sum(given is not None for given in (box, points, quad, mask_path)) != 1:
        raise UsageError("give exactly one of --from-box X,Y,W,H, --from-points X1,Y1,X2,Y2,..., --from-quad "
                         "X1,Y1,...,X4,Y4 or --from-mask IMAGE")
    if one_based and mask_path is not None:
        raise UsageError("--one-based is for coordinates (--from-box, --from-points, --from-quad), not a mask")
    # Coordinates are read before the frame is decoded (a typo is the error to see); a mask after, its size first.
    if box is not None:
        result = roi_from_box(box, round_tolerance=round_tol)
    elif quad is not None:
        result = roi_from_quad(quad, round_tolerance=round_tol)
    elif points is not None:
        result = roi_from_points(points, round_tolerance=round_tol)
    else:
        mask = read_mask(mask_path)
    if one_based:
        result = from_one_based(result)
    shot = read_frame(video, index)
    if mask_path is not None:
        # A mask of another frame (or image) is the error to see, not what its pixels look like.
        if mask.shape[:2] != (shot.height, shot.width):
            raise UsageError(f"mask '{mask_path}' is {mask.shape[1]}x{mask.shape[0]} pixels but frame {index} of "
                             f"'{input_label(video)}' is {shot.width}x{shot.height}: give a mask of the frame's size")
        result = roi_from_mask(mask, round_tolerance=round_tol)
    check_roi_fits(result, shot.width, shot.height, source=f"'{input_label(video)}' (frame {index})")
    spec = result.to_spec()
    write_stdout(spec + "\n")
    # Quoted as a shell needs them (a path with spaces), so that the line can be pasted.
    click.echo(f"lptrack: check it with: lptrack frame {shlex.quote(str(video))} --at {index} --roi {spec}",
               err=True)


@main.command("plot", cls=OneLineErrors, epilog="""\b
The run CSV does not name its video: the thumbnail comes from --video, or
from <stem>.mp4 (.m4v, .mov, .avi, .mkv, .webm, ...), or a folder <stem>/
of numbered images, when exactly one such source sits next to the CSV (or
in the current folder), where <stem> is the CSV's name without .lptrack.csv
(.lptrack.jsonl, .csv). A batch's stream names its video (its 'video'
column): that one, when found from here or from the stream's folder. A
note on stderr says which video was taken, or where none was found.
--no-video draws the path on blank axes. RUN.csv '-' reads the run from
stdin (then give -o).

\b
Examples:
  lptrack plot clip.lptrack.csv --video clip.mp4 -o track.png
  lptrack plot spin.lptrack.csv --video sample_videos/spin.mp4 --gt sample_videos/spin.gt.csv
  lptrack run clip.mp4 --roi 320,240,40 --no-video --csv - | lptrack plot - --video clip.mp4 -o track.png
""")
@click.argument("run_csv", type=PathParam(path_type=Path), metavar="RUN.csv")
@click.option("-o", "--out", "out_png", type=PathParam(dir_okay=False, path_type=Path), metavar="PNG",
              help="Figure to write: .png, or .pdf or .svg. Default: RUN.csv's name with .plot.png for its "
                   "extension (clip.lptrack.plot.png), in the current folder.")
@click.option("--gt", "gt_path", type=PathParam(path_type=Path), metavar="GT",
              help="Ground truth to overlay and score: lptrack .gt.csv, OTB/UAV123 x,y,w,h .txt, VOT "
                   "groundtruth.txt, or a sequence folder holding one (as 'lptrack eval').")
@click.option("--video", "video", type=_VIDEO, metavar="VIDEO", help="The tracked video, for the thumbnail.")
@click.option("--no-video", is_flag=True, help="No thumbnail, even if the video can be found.")
@click.option("--overwrite", is_flag=True, help="Replace an existing PNG.")
@click.option("-q", "--quiet", is_flag=True, help="No note on stderr about which video was used, or that none was "
                                                   "found.")
def plot(run_csv: Path, out_png: Path | None, gt_path: Path | None, video: Path | None, no_video: bool,
         overwrite: bool, quiet: bool) -> None:
    """Draw a run CSV as a figure (PNG): path, scale, rotation, score.

    The centre path over the run's first frame; scale, rotation (degrees
    CCW, cumulative) and score against time, lost frames shaded red. With
    --gt: ground truth overlaid and the errors per frame (centre px, scale %,
    rotation deg). Needs matplotlib: pip install matplotlib.
    Prints the PNG's path on stdout.
    """
    require_stdout()  # for the PNG's path: checked before the PNG is written
    if out_png is not None:
        check_image_suffix(out_png, PLOT_SUFFIXES, "output image")
    hint = matplotlib_hint()
    if hint:
        raise UsageError(hint)
    if no_video and video is not None:
        raise UsageError("--video and --no-video contradict each other; give one of them")
    out_png = _default_png(run_csv, out_png, "plot")
    table = read_run_csv(run_csv, video, only_if_several=True)  # --video is also the thumbnail's, a copy or not
    note = None
    streamed = find_streamed_video(table.video, run_csv) if video is None and not no_video else None
    if streamed is not None:
        # A batch's stream names its video (the plain CSV does not): it was looked for by the stream's file name.
        video = streamed
        note = f"lptrack: thumbnail from '{video}', the stream's video (give --video to choose another)"
    elif video is None and not no_video and str(run_csv) == "-":
        why = "the run came from stdin" if table.video is None else f"the stream's video '{table.video}' is not found"
        note = (f"lptrack: note: no thumbnail: {why}; give the tracked video with --video VIDEO (or --no-video for "
                f"blank axes)")
    elif video is None and not no_video:
        video = find_video_for_csv(run_csv)
        if video is not None:
            note = f"lptrack: thumbnail from '{video}' (give --video to choose another)"
        else:
            why = describe_video_search(run_csv)
            if table.video is not None:
                why = f"the stream's video '{table.video}' is not found from here or beside the stream, and {why}"
            note = (f"lptrack: note: no thumbnail: {why}; give the tracked video with --video VIDEO (or --no-video "
                    f"for blank axes)")
    path = plot_track(table, out_png, video=video, ground_truth=gt_path, overwrite=overwrite)
    past = None if gt_path is None else rows_past_ground_truth(f"'{run_csv}'", table.frames,
                                                                load_ground_truth(gt_path), f"'{gt_path}'")
    if past is not None and not quiet:  # as 'lptrack eval' notes them: the error panel ends there
        click.echo(f"lptrack: note: {past}; they have no ground truth to plot (is it this video's ground truth?)",
                   err=True)
    if note is not None and not quiet:
        click.echo(note, err=True)  # after the plot, so that a failure is one error line, not a note before it
    write_stdout(str(path) + "\n")


@main.command("sheet", cls=OneLineErrors, epilog="""\b
Examples:
  lptrack sheet clip.mp4 clip.lptrack.csv                 # 4 x 3 frames
  lptrack sheet clip.mp4 clip.lptrack.csv --count 20 --cols 5 --width 2000
  lptrack run clip.mp4 --no-video --csv - | lptrack sheet clip.mp4 - -o sheet.png  # '-': stdin
""")
@click.argument("video", type=_VIDEO)
@click.argument("run_csv", type=PathParam(path_type=Path), metavar="RUN.csv")
@click.option("-o", "--out", "out_png", type=PathParam(dir_okay=False, path_type=Path), metavar="PNG",
              help="PNG to write. Default: RUN.csv's name with .sheet.png for its extension "
                   "(clip.lptrack.sheet.png), in the current folder.")
@click.option("--cols", type=WholeNumber(min=1, max=64), default=4, show_default=True, metavar="N",
              help="Columns.")
@click.option("--rows", type=WholeNumber(min=1, max=64), default=None, metavar="N",
              help=f"Rows: --cols x N frames. Default {SHEET_ROWS}; not with --count.")
@click.option("--count", type=WholeNumber(min=1, max=4096), metavar="N",
              help="Instead of --rows: N frames in --cols columns (rows as needed).")
@click.option("--width", type=WholeNumber(min=64, max=20000), default=1600, show_default=True, metavar="PX",
              help="Sheet width in pixels (tiles are never enlarged beyond the video's size).")
@click.option("--overwrite", is_flag=True, help="Replace an existing PNG.")
def sheet(video: Path, run_csv: Path, out_png: Path | None, cols: int, rows: int | None, count: int | None,
          width: int, overwrite: bool) -> None:
    """Write a contact sheet: evenly spaced annotated frames of a run, one PNG.

    Each tile is a frame of VIDEO with the run's outline and axis line (green
    tracked, red lost) and a label: frame number, time, scale (x), rotation
    (r, degrees CCW), score. First and last rows of the run are always shown.
    Prints the PNG's path on stdout.
    """
    require_stdout()  # for the PNG's path: checked before the PNG is written
    if rows is not None and count is not None:
        raise UsageError(f"--rows and --count contradict each other: --rows {rows} shows {cols} x {rows} frames, "
                         f"--count {count} shows {count} frames in {cols} columns; give one of them")
    if run_csv.suffix.lower() in VIDEO_EXTENSIONS and video.suffix.lower() in (".csv", ".jsonl"):
        # The two the other way round were "cannot read run CSV 'clip.mp4': not a text file".
        raise UsageError(f"RUN.csv '{run_csv}' is a video and VIDEO '{video}' a run's file; the video goes first: "
                         f"lptrack sheet VIDEO RUN.csv")
    out_png = _default_png(run_csv, out_png, "sheet")
    table = read_run_csv(run_csv, video, only_if_several=True)  # VIDEO is what to draw on, a copy or not
    path = write_contact_sheet(video, table, out_png, cols=cols, rows=rows, count=count, width=width,
                               overwrite=overwrite)
    write_stdout(str(path) + "\n")
