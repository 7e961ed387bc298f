"""``lptrack bench`` (trackers side by side on sequences with ground truth) and ``lptrack eval`` (score a CSV)."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import click

from ..bench import (STARTS, bench_document, collect_sequences, default_dataset, eval_document, evaluate_stream_run,
                     format_paired, format_passes, format_table, paired_differences, plot_curves, resolve_trackers,
                     run_bench, scored_video, summarise)
from ..errors import OutputError, UsageError
from ..executor import TRACKING_OPENCV_THREADS
from ..outputs import check_image_suffix, check_output_path, write_text_atomic, writes_in_place
from ..plot import PLOT_SUFFIXES, matplotlib_hint
from . import (EXIT_FAILURE, PARAM_HELP, OneLineErrors, PathParam, WholeNumber, check_jobs_or_scheduler,
               echo_progress, main, parse_param_options, require_stdout, write_stdout)


#: Skipped folders named one by one before the rest are counted (a dataset laid out otherwise, UAV123's images
#: apart from its ground truth, would name each of its 123).
_SKIPPED_NOTES = 5

_BENCH_EPILOG = """\b
Datasets (--dataset, repeatable; default: the project's sample_videos/):
  lptrack samples  <name>.mp4 + <name>.gt.csv (+ <name>.roi)
  OTB              img/0001.jpg... + groundtruth_rect.txt (x,y,w,h, 1-based)
  VOT              frames (or imgs/, color/) + groundtruth.txt (x,y,w,h or
                   8-number rotated quadrilateral)
  UAV123           img/ + <name>.txt (x,y,w,h, 1-based)
  LaSOT            <class>/<class>-<n>/img/ + groundtruth.txt (x,y,w,h,
                   1-based) + full_occlusion.txt + out_of_view.txt
  GOT-10k          frames + groundtruth.txt (x,y,w,h, 1-based) +
                   absence.label (+ cover.label); train and val splits
  TrackingNet      TRAIN_k/frames/<video>/0.jpg... + TRAIN_k/anno/<video>.txt
                   (x,y,w,h, 0-based)
  or a folder of such folders (3 levels down). Trackers start on the first
  frame with ground truth from the ellipse inscribed in its box; frames
  without ground truth (NaN lines, more frames than lines) and frames a
  benchmark flags as absent (LaSOT's full occlusion or out of view, GOT-10k's
  absence or cover 0) are not scored. Test splits (one ground-truth line: the
  first frame's) are skipped with a note.

\b
Columns (per sequence and tracker; 'mean' rows average over sequences):
  frames       frames scored: those with ground truth, from the start frame
               on (a failed run: those it reached; --starts: the first
               start's; 'mean' rows: their sum)
  success%     frames with centre error < 25% of the object's radius
               (radius = sqrt(w*h)/2 of the ground-truth box)
  AUC          area under the OTB success curve (IoU > t, 21 thresholds)
  prec@20%     frames with centre error <= 20 px
  centre_px    median centre error, pixels
  scale_err%   median |scale / true scale - 1|
  rot_err_deg  median rotation error (ground truth with an angle only;
               modulo 180 for rectangles); n/a for OpenCV's trackers
  lost%        share of the scored frames reported lost
  off_tracked% share of the frames reported tracked whose box misses the
               object (IoU 0): how often 'tracked' is wrong
  fps          tracker update() calls per second (decoding excluded)

\b
Examples:
  lptrack bench
  lptrack bench --dataset ~/data/otb --trackers fixed,cv-mil --json res.json
  lptrack bench --trackers cv-csrt,cv-kcf --json - > res.json
  lptrack bench --dataset ~/data/otb --trackers lpcf,cv-csrt --starts 13 -j 2
  lptrack bench --dataset ~/data/otb --trackers lpcf,cv-csrt --backwards
  lptrack bench --dataset ~/data/otb --trackers lpcf,cv-csrt --every 3
  lptrack bench --dataset ~/data/otb --trackers lpcf,cv-csrt --passes 4
  lptrack bench --dataset ~/data/otb --trackers lpcf --param padding=1.5
"""


@main.command("bench", cls=OneLineErrors, epilog=_BENCH_EPILOG)
@click.option("--dataset", "datasets", multiple=True, metavar="DIR",
              type=PathParam(path_type=Path),
              help="Folder of sequences (repeatable). Default: sample_videos/ of the project.")
@click.option("--trackers", metavar="A,B,...",
              help="Comma-separated tracker names. Default: every available lptrack tracker and OpenCV peer.")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE", help=PARAM_HELP)
@click.option("--json", "json_out", metavar="PATH|-", type=PathParam(),
              help="Write every number, versions, machine and parameters as JSON; '-' for stdout (then the "
                   "table goes to stderr).")
@click.option("--per-frame", is_flag=True, help="Include per-frame IoU and centre error arrays in the --json "
              "file (with --starts, those of the first start: the ground truth's ROI).")
@click.option("--plot", "plot_out", metavar="PATH.png", type=PathParam(dir_okay=False, path_type=Path),
              help="Save success and precision plots (needs matplotlib: pip install matplotlib).")
@click.option("--jobs", "-j", type=WholeNumber(min=1), default=1, show_default=True, metavar="N",
              help="Run (sequence, tracker) pairs in N processes. Speeds are only comparable at equal N.")
@click.option("--scheduler", metavar="ADDRESS",
              help="Run the pairs on this Dask scheduler instead (pip install 'dask[distributed]'; the sequences "
                   "at the same paths on its workers).")
@click.option("--starts", type=WholeNumber(min=1, max=len(STARTS)), default=1, show_default=True, metavar="N",
              help=f"Track each sequence from N initial ROIs: the ground truth's, then OTB's spatial robustness "
                   f"(SRE) ones: shifted by 10 % of the box (4 to the sides, 4 to the corners), scaled by 0.8, "
                   f"0.9, 1.1, 1.2; from the 14th on, fixed random ones (shifts within 8 %, scales 0.9 to 1.1; at "
                   f"most {len(STARTS)}). Each row is the mean over its starts; with several trackers a second "
                   f"table gives the first one's AUC minus each other's, start by start, with its standard error.")
@click.option("--backwards", is_flag=True,
              help="Play each sequence backwards instead, from its last frame with ground truth (image sequences "
                   "only; rows named NAME-backwards): the same footage as other tracking problems, a check on "
                   "sequences a tracker was not tuned on.")
@click.option("--every", type=WholeNumber(min=1), default=1, show_default=True, metavar="N",
              help="Track every N-th frame only, from the tracker's first frame (the first with ground truth, or "
                   "frame 0 with a .roi sidecar; rows named NAME-everyN): the same footage at 1/N of its frame rate, "
                   "N times the motion between frames. With --backwards: every N-th frame of the sequence played "
                   "backwards.")
@click.option("--passes", type=WholeNumber(min=1), default=1, show_default=True, metavar="N",
              help="Play each sequence forwards and backwards in turn, N passes over its frames (2: there and back; "
                   "image sequences only; rows named NAME-passesN), each frame scored against its own ground truth, "
                   "the same on every pass: a long run over known footage, where a tracker that drifts scores less "
                   "pass after pass (each tracker's mean AUC per pass below the table, and per sequence in --json). "
                   "With --backwards or --every: of the sequence so played.")
@click.option("--threads", type=WholeNumber(min=1), default=None, metavar="N",
              help="OpenCV threads per tracker. Default 1: every tracker, lptrack's and OpenCV's, on one core, so "
                   "frames/s compare per core (more lets OpenCV's CSRT spread its work over cores).")
@click.option("--speed", is_flag=True,
              help="Time the trackers instead (thesis Table 4.1 on a 640x480 synthetic video, one core) with "
                   "decode and 'lptrack run' baselines; uses --trackers, --json, --overwrite and --quiet only. "
                   "LPTRACK_SPEED_FRAMES sets the frames per sequence (default 100).")
@click.option("--overwrite", is_flag=True, help="Replace existing --json and --plot files.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar and no notes on stderr.")
def bench(datasets: tuple[Path, ...], trackers: str | None, params: tuple[str, ...], json_out: str | None,
          per_frame: bool,
          plot_out: Path | None, jobs: int, scheduler: str | None, starts: int, backwards: bool, every: int,
          passes: int, threads: int | None, quiet: bool, speed: bool, overwrite: bool) -> None:
    """Run trackers over sequences with ground truth and compare them.

    Prints one row per sequence and tracker and a mean row per tracker:
    success rate, IoU success AUC, precision at 20 px, median centre, scale
    and rotation errors, how often it said lost and how often 'tracked' was
    wrong, and tracker frames/s. With --starts N > 1 and several trackers,
    then the first tracker's AUC minus each other's, start by start.

    With --speed: each tracker's ms/frame on circle and ellipse next to the
    thesis' Table 4.1, decode and decode + encode baselines, and 'lptrack run'
    with and without video output as a share of them.
    """
    jobs_given = click.get_current_context().get_parameter_source("jobs") is not click.core.ParameterSource.DEFAULT
    if speed:
        if (datasets or per_frame or plot_out is not None or starts != 1 or backwards or every != 1 or passes != 1
                or threads is not None or params or jobs_given or scheduler is not None):
            raise UsageError("--speed times trackers on a synthetic video on one core; it takes no --dataset, "
                             "--per-frame, --plot, --starts, --backwards, --every, --passes, --threads, --param, "
                             "--jobs or --scheduler")
    check_jobs_or_scheduler(jobs_given, scheduler)
    json_out = _json_out(json_out)
    if per_frame and json_out is None:
        # It adds arrays to the JSON, and without one it was ignored in silence.
        raise UsageError("--per-frame adds per-frame arrays to the JSON; give --json PATH (or --json -) too")
    # Outputs are checked before the work (a benchmark may run for hours), as `lptrack run` checks its own.
    _check_json_out(json_out, overwrite)
    if speed:
        _speed(trackers, json_out, quiet, overwrite)
        return
    if plot_out is not None:
        check_image_suffix(plot_out, PLOT_SUFFIXES, "plot")
        hint = matplotlib_hint()
        if hint:
            raise UsageError(hint)
        check_output_path(plot_out, overwrite=overwrite, what="plot")
    if not datasets:
        found = default_dataset()
        if found is None:
            raise UsageError("no --dataset given, and no sample_videos/ folder in the current folder or in the "
                             "source checkout lptrack runs from (a wheel install has none); give --dataset DIR "
                             "(lptrack samples, OTB, VOT, UAV123, LaSOT, GOT-10k or TrackingNet folders), or run it "
                             "in the checkout")
        datasets = (found,)
    names, skipped = _runnable_trackers(trackers)
    tuning = parse_param_options(params, names, [name for name, _ in skipped])
    unread: list[tuple[Path, str]] = []
    sequences = collect_sequences(datasets, unread)
    for flag, wanted in (("--backwards", backwards), ("--passes", passes > 1)):
        videos = [s.path.name for s in sequences if s.frame_files is None] if wanted else []
        if videos:
            raise UsageError(f"{flag} plays image sequences only (OTB, VOT, UAV123, LaSOT, GOT-10k, TrackingNet), and "
                             f"{videos[0]} is a video; give --dataset with such folders")
    if backwards:
        sequences = [s.backwards() for s in sequences]
    sequences = [s.every(every).there_and_back(passes) for s in sequences]
    # A video's frame count is its container's, 0 when unknown: then nothing is said before the run. A sequence left
    # a single frame is skipped with a note, as a folder without a sequence is (one short sequence stopped the run
    # of every other); only when that leaves none is it an error.
    short = [s for s in sequences if s.n_frames == 1] if every > 1 else []
    if short:
        if len(short) == len(sequences):
            raise UsageError(f"--every {every} leaves 1 frame of '{short[0].name}', nothing to track; give a smaller "
                             f"N")
        sequences = [s for s in sequences if s.n_frames != 1]
    _note_skipped(skipped, quiet)
    if not quiet:
        folder_notes = [f"skipped '{folder}', which has {lacking}" for folder, lacking in unread[:_SKIPPED_NOTES]]
        if len(unread) > _SKIPPED_NOTES:
            folder_notes.append(f"skipped {len(unread) - _SKIPPED_NOTES} more folders that hold frames, videos or "
                                f"ground truth but are not sequences")
        folder_notes += [f"skipped '{s.name}': --every {every} leaves it 1 frame, nothing to track" for s in short]
        for note in [*folder_notes, *dict.fromkeys(note for s in sequences for note in s.notes)]:
            click.echo(f"lptrack: note: {note}", err=True)
    threads = TRACKING_OPENCV_THREADS if threads is None else threads

    runs_total = len(sequences) * len(names) * starts
    bar = None
    if not quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=runs_total, unit="run", file=sys.stderr, leave=False)
    runs_done = [0]

    def progress(result: dict) -> None:
        if bar is not None:
            bar.set_postfix_str(f"{result['sequence']}/{result['tracker']}")
            bar.update(1)
        elif not quiet:
            # Not a terminal (a log, a CI job): a line at each tenth of the runs rather than a bar's redraws.
            runs_done[0] += 1
            if runs_done[0] * 10 // runs_total > (runs_done[0] - 1) * 10 // runs_total:
                echo_progress(f"lptrack: {runs_done[0]}/{runs_total} runs done (last: {result['tracker']} on "
                              f"{result['sequence']})")

    try:
        results = run_bench(sequences, names, params={"tracker_params": tuning}, jobs=jobs, scheduler=scheduler,
                            on_result=progress, starts=starts, threads=threads)
    finally:
        if bar is not None:
            bar.close()
    summary = summarise(results, names)
    table = format_table(results, summary)
    parameters = {"datasets": [str(d) for d in datasets], "trackers": names, "jobs": jobs,
                  "scheduler": scheduler, "starts": starts, "backwards": backwards, "every": every, "passes": passes,
                  "opencv_threads": threads,
                  "tracker_params": {name: chosen for name, chosen in tuning.items() if chosen},
                  "start_perturbations": [list(p) for p in STARTS[:starts]]}
    failed = [r for r in results if r["error"]]
    paired = paired_differences(results, names) if starts > 1 else []
    doc = None if json_out is None else bench_document(results, summary, sequences, parameters=parameters,
                                                       skipped=skipped, per_frame=per_frame, paired=paired)
    if starts > 1:
        table = f"Means over {starts} starts per sequence (--starts; per-start AUCs in --json).\n" + table
        if paired:
            table += "\n" + format_paired(paired)
    if passes > 1:
        table += "\n" + format_passes(summary)
    json_error = None
    try:
        _emit(table, doc, json_out, overwrite)
    except OutputError as exc:
        # The plot is still drawn: a long run's figures are not lost with its JSON (the table is already out).
        json_error = exc
    if plot_out is not None:
        # Which run a plot shows is not in its curves: say it, as the table's row names do.
        caption = f"{len(sequences)} sequence{'s' if len(sequences) != 1 else ''}"
        caption += " played backwards" if backwards else ""
        caption += f", every {_ordinal(every)} frame" if every > 1 else ""
        caption += f", {passes} passes there and back" if passes > 1 else ""
        caption += f", means over {starts} starts" if starts > 1 else ""
        try:
            plot_curves(summary, plot_out, caption, overwrite=overwrite)
        except OutputError as exc:
            if json_error is None:
                raise
            click.echo(f"lptrack: error: {exc}", err=True)
    for r in failed:
        click.echo(f"lptrack: error: {r['tracker']} failed on {r['sequence']}: {r['error']}", err=True)
    if json_error is not None:
        raise json_error
    if failed:
        sys.exit(EXIT_FAILURE)


def _ordinal(n: int) -> str:
    """``2nd``, ``3rd``, ``11th``, ``21st``..."""
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def _json_out(json_out: str | None) -> str | None:
    """``json_out``, or ``'-'`` where it names the file stdout writes to (``--json /dev/stdout``, ``/dev/fd/1``, or
    the file stdout is redirected to): the JSON then goes to stdout alone, as with ``--json -``, where the table
    was written after it into the same stream."""
    if json_out in (None, "-") or os.path.realpath(json_out) == os.devnull:  # `--json /dev/null > /dev/null`: quiet
        return json_out
    try:
        named, stdout = os.stat(json_out), os.fstat(sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no such file yet, or a stdout without a descriptor
        return json_out
    return "-" if (named.st_dev, named.st_ino) == (stdout.st_dev, stdout.st_ino) else json_out


def _check_json_out(json_out: str | None, overwrite: bool) -> None:
    """Refuse, before any work, a closed stdout (the table goes there, or the JSON with ``--json -``) and a --json
    file that cannot be written or exists without --overwrite."""
    require_stdout()
    if json_out not in (None, "-"):
        check_output_path(json_out, overwrite=overwrite, what="JSON output", special_ok=True)


def _speed(trackers: str | None, json_out: str | None, quiet: bool, overwrite: bool) -> None:
    """``lptrack bench --speed``: the Table 4.1 reproduction (see :mod:`logpolar_track.speed`)."""
    from ..speed import format_report, frames_from_environment, speed_report

    try:
        n_frames = frames_from_environment()
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    names, skipped = _runnable_trackers(trackers)
    _note_skipped(skipped, quiet)
    # A line per step, terminal or not: the steps take seconds each, so the lines are few.
    doc = speed_report(names, n_frames=n_frames,
                       on_step=None if quiet else (lambda label: echo_progress(f"lptrack: timing {label}")))
    doc["skipped_trackers"] = [{"tracker": n, "reason": why} for n, why in skipped]
    table = format_report(doc)
    _emit(table, doc, json_out, overwrite)


def _runnable_trackers(spec: str | None) -> tuple[list[str], list[tuple[str, str]]]:
    """The requested trackers that can run here, and (name, reason) for those skipped (see :func:`_note_skipped`)."""
    names, skipped = resolve_trackers(spec)
    if not names:
        reasons = "; ".join(f"{name}: {reason}" for name, reason in skipped)
        raise UsageError(f"none of the requested trackers can run here ({reasons})")
    return names, skipped


def _note_skipped(skipped: list[tuple[str, str]], quiet: bool) -> None:
    """The trackers skipped, noted on stderr once the arguments are known to be good (a bad one gets one line)."""
    if not quiet:
        for name, reason in skipped:
            click.echo(f"lptrack: note: skipping {name}: {reason}", err=True)


def _emit(table: str, doc: dict | None, json_out: str | None, overwrite: bool) -> None:
    """The table on stdout and the JSON document to ``json_out``; with ``--json -`` the table goes to stderr."""
    if json_out is not None:
        text = json.dumps(doc, indent=1) + "\n"
        if json_out == "-":
            click.echo(table, err=True, nl=False)
            write_stdout(text)
            return
        try:
            write_text_atomic(json_out, text, overwrite=overwrite)
        except OutputError as exc:
            path = Path(json_out)
            if not overwrite and not writes_in_place(path) and path.exists():
                # Another run wrote that name meanwhile (it was free when this run started): keep this run's too.
                kept = _free_name(path)
                write_text_atomic(kept, text, overwrite=False)
                exc = OutputError(f"{exc}; this run's JSON is in '{kept}'")
            write_stdout(table)  # a long run's figures are not lost with its JSON
            raise exc from None
    write_stdout(table)


def _free_name(path: Path) -> Path:
    """``path`` with ``.1``, ``.2``, ... before its suffix: the first such name that is free."""
    n = 1
    while (candidate := path.with_name(f"{path.stem}.{n}{path.suffix}")).exists():
        n += 1
    return candidate


@main.command("eval", cls=OneLineErrors)
@click.argument("prediction", metavar="PRED.csv", type=PathParam(path_type=Path))
@click.argument("ground_truth", metavar="GT", type=PathParam(path_type=Path))
@click.option("--json", "json_out", metavar="PATH|-", type=PathParam(),
              help="Write the metrics (and per-frame arrays) as JSON; '-' for stdout instead of the table.")
@click.option("--video", "video", type=PathParam(path_type=Path), metavar="VIDEO",
              help="With a batch's stream (PRED.csv from 'lptrack run a.mp4 b.mp4 --csv -'): score the rows of "
                   "this video. Default: GT when GT is a video.")
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
@click.option("--quiet", "-q", is_flag=True, help="No notes on stderr (frames not scored, an ignored --video).")
def eval_command(prediction: Path, ground_truth: Path, json_out: str | None, video: Path | None,
                 overwrite: bool, quiet: bool) -> None:
    """Score a run's CSV (PRED.csv from 'lptrack run'; '-': stdin) against ground truth GT.

    GT is a <name>.gt.csv, an OTB groundtruth_rect.txt, a VOT groundtruth.txt,
    a UAV123 <name>.txt, a LaSOT or GOT-10k groundtruth.txt or TrackingNet
    anno/<video>.txt (read with their sequence's absence flags), a sequence
    folder holding one of them, or a video (its <name>.gt.csv beside it, as
    in sample_videos/). Frames are
    matched by index (line k of a .txt file is frame k-1); the metrics are
    those of 'lptrack bench' (see 'lptrack bench --help'). A .gt.csv
    without a rotation_deg column has its rotation scored modulo 180
    degrees (an ellipse's angle repeats every half turn). PRED.csv is
    checked against the run CSV's contract as 'lptrack plot' checks it; a
    CSV of another tool with at least the columns frame,cx,cy,a,b,angle_deg
    (any order) is scored too, its values checked alike, and without a
    status column it has no lost% or off_tracked% (n/a).
    """
    json_out = _json_out(json_out)
    _check_json_out(json_out, overwrite)
    metrics, notes, streamed = evaluate_stream_run(prediction, ground_truth, video=video)
    # For the JSON: the video evaluate_run chose a stream's rows by; none for one video's own CSV (a --video it
    # ignored, or the video given as GT, chose nothing).
    video = None if streamed is None else scored_video(ground_truth, video)
    for note in [] if quiet else notes:
        click.echo(f"lptrack: note: {note}", err=True)
    row = {"sequence": prediction.name, "tracker": "(run)", **metrics}
    table = format_table([row], [], speed=False)
    if json_out is None:
        write_stdout(table)
        return
    text = json.dumps(eval_document(prediction, ground_truth, metrics, video=video), indent=1) + "\n"
    if json_out == "-":
        write_stdout(text)
    else:
        write_text_atomic(json_out, text, overwrite=overwrite)
        write_stdout(table)
