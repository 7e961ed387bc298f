"""Run trackers over sequences with ground truth and compare them: tables, a JSON document, plots.

The unit of work is :func:`run_one` (one tracker on one sequence), a picklable top-level function, so local
process pools (``--jobs``) and other executors can share it. Accuracy metrics are those of
:mod:`logpolar_track.evaluate`; speed is the tracker's ``update()`` time alone (``time.perf_counter`` around
each call; decoding, ``init()`` and scoring excluded), reported as frames per second.

Summary rows average each per-sequence number over the sequences (every sequence weighs the same, as in OTB's
overall plots); the summary frames/s is total updated frames over total update time.

With several starts (:func:`start_roi`, ``lptrack bench --starts N``) each sequence is tracked from the ground
truth's ROI and from up to 12 perturbed ones, OTB's spatial robustness evaluation (SRE; Wu, Lim, Yang, CVPR
2013): a sequence's row is then the mean over its starts, which says more about a tracker than one run, whose
score on a hard sequence can swing by a third between starts a few pixels apart.
"""

from __future__ import annotations

import dataclasses
import math
import os
import platform
import time
from pathlib import Path
from typing import Callable, Iterable, Mapping

import numpy as np

from . import __version__
from .datasets import SEARCH_DEPTH, Sequence, discover, discover_one, ground_truth_file, load_ground_truth
from .errors import OutputError, RoiError, UsageError, is_whole
from .evaluate import (IOU_THRESHOLDS, PRECISION_PX, PRECISION_THRESHOLDS, SUCCESS_RADIUS_FRACTION, Track,
                       auc, no_frame_with_ground_truth, read_run_csv, rows_past_ground_truth, score_track,
                       success_curve)
from .executor import TRACKING_OPENCV_THREADS, describe_exception, opencv_threads, run_tasks
from .geometry import Ellipse
from .outputs import check_image_suffix, written_into_place
from .results import decode_text
from .plot import PLOT_SUFFIXES, matplotlib_hint
from .trackers import create_tracker, tracker_class, tracker_names
from .video import VIDEO_EXTENSIONS
from .trackers import opencv as _opencv_peers  # noqa: F401  (registers cv-mil, cv-kcf, cv-csrt)

#: Version of the JSON document written by :func:`bench_document`; bump on incompatible changes.
SCHEMA_VERSION = 1
#: Per-frame arrays kept in each result; dropped from the JSON document unless asked for.
PER_FRAME_KEYS = ("frames", "iou", "centre_error_px")


def default_dataset() -> Path | None:
    """The project's ``sample_videos/`` folder: beside the package in a checkout, else in the working folder."""
    for candidate in (Path(__file__).resolve().parents[1] / "sample_videos", Path.cwd() / "sample_videos"):
        if candidate.is_dir():
            return candidate
    return None


def resolve_trackers(spec: str | None) -> tuple[list[str], list[tuple[str, str]]]:
    """Tracker names to run from a comma-separated ``spec`` (None: every available tracker).

    Returns
    -------
    names : list of str
        Available trackers, in the order given (duplicates removed).
    skipped : list of (name, reason)
        Registered trackers that were asked for but cannot run here (e.g. contrib-only OpenCV peers).

    Raises
    ------
    UsageError
        For a name that is not registered at all, or an empty list.
    """
    if spec is None:
        names = tracker_names(include_unavailable=True)
    else:
        names = list(dict.fromkeys(n.strip() for n in spec.split(",") if n.strip()))
        if not names:
            raise UsageError("the list of trackers (--trackers) is empty; give comma-separated names from: "
                             + ", ".join(tracker_names(include_unavailable=True)))
    classes = [tracker_class(name) for name in names]  # an unknown name: UsageError, with "did you mean"
    available, skipped = [], []
    for name, cls in zip(names, classes):
        if cls.available():
            available.append(name)
        else:
            skipped.append((name, cls.unavailable_reason()))
    return available, skipped


#: Initial ROIs of the starts, in order: ``(dx, dy, scale)``, shifts as fractions of the ROI's bounding box's width
#: and height (x right, y down), scale of both semi-axes about the centre. Start 0 is the ground truth's ROI; 1-12
#: are OTB's SRE perturbations: 4 centre shifts and 4 corner shifts by 10 % of the box, and scales 0.8, 0.9, 1.1
#: and 1.2; 13-32 are 20 more, drawn once at random (shifts uniform within 8 % of the box, scales within 0.9 to
#: 1.1: ``rng = numpy.random.default_rng(0)``, then ``(rng.uniform(-0.08, 0.08), rng.uniform(-0.08, 0.08),
#: rng.uniform(0.9, 1.1))`` 20 times) and written out, so that every machine and NumPy gets the same: 13 starts
#: leave a mean that moves by about 0.01 with chance (a 1 % change of one of lpcf's parameters moves it that much),
#: and more starts narrow that.
STARTS = ((0.0, 0.0, 1.0),
          (-0.1, 0.0, 1.0), (0.1, 0.0, 1.0), (0.0, -0.1, 1.0), (0.0, 0.1, 1.0),
          (-0.1, -0.1, 1.0), (0.1, -0.1, 1.0), (-0.1, 0.1, 1.0), (0.1, 0.1, 1.0),
          (0.0, 0.0, 0.8), (0.0, 0.0, 0.9), (0.0, 0.0, 1.1), (0.0, 0.0, 1.2),
          (0.021913869971432687, -0.03683412579778075, 0.908194704787239),
          (-0.07735557831543535, 0.05012323827204358, 1.0825511154555445),
          (0.017061724122748784, 0.03671944975743975, 1.0087249982930846),
          (0.06961158780604292, 0.050536568659445155, 0.9005477000340296),
          (0.05718468425401109, -0.07462630795112571, 1.0459310892859888),
          (-0.05189510070359056, 0.058108627575981855, 1.0082922440498183),
          (-0.032046097514018435, -0.012370044608374653, 0.9056639342290926),
          (-0.06011467576006977, 0.027299906350980854, 1.02943790231485),
          (0.01846161783700062, -0.01861159131809865, 1.0994419871578422),
          (0.0769336542041968, 0.029686717516911154, 1.0300918552535634),
          (0.030151476891350407, -0.017772572163343395, 0.9270193010044823),
          (0.03543813443105308, 0.004056691596116144, 0.9620483751117912),
          (-0.0022663425869137444, 0.062318053495840034, 1.0868087031912501),
          (-0.022752768526548763, 0.011444772916761756, 0.9643738782151885),
          (0.015088004831951482, -0.02593420391885868, 0.9783238001056322),
          (0.06244389632076679, -0.04365478503465924, 1.0246374289372087),
          (-0.06655754502681843, 0.05322306362454364, 1.0574196614977367),
          (-0.041700889121127654, 0.06023747692971261, 0.9117136069610389),
          (-0.02622127031269434, -0.05595528529682575, 0.9900678733298575),
          (0.04741188324596708, -0.04309724656100041, 0.9104042602128819))


def start_roi(roi: Ellipse, start: int) -> Ellipse:
    """The initial ROI of start number ``start`` (0 to ``len(STARTS) - 1``, see :data:`STARTS`) from the ground
    truth's ``roi``: moved by a fraction of its axis-aligned bounding box (pixels) and/or scaled about its
    centre; the angle is kept.

    Raises
    ------
    UsageError
        If ``start`` is out of range.
    """
    if not 0 <= start < len(STARTS):
        raise UsageError(f"start {start} is not one of 0 to {len(STARTS) - 1}")
    dx, dy, scale = STARTS[start]
    _, _, width, height = roi.bounding_box()
    return Ellipse(roi.cx + dx * width, roi.cy + dy * height, roi.a * scale, roi.b * scale, roi.angle_deg)


def collect_sequences(datasets: Iterable, unread: list[tuple[Path, str]] | None = None) -> list[Sequence]:
    """All sequences of the given dataset folders, in order; ``unread`` gets ``(folder, what it lacks)`` for each
    folder skipped that looked like a sequence (see :func:`~logpolar_track.datasets.discover`).

    Raises
    ------
    UsageError
        If a dataset holds no recognisable sequence, or two sequences share a name.
    """
    sequences: list[Sequence] = []
    unread = [] if unread is None else unread
    for dataset in datasets:
        before = len(unread)
        found = discover(dataset, unread)
        skipped = unread[before:]
        if not found and len(skipped) == 1 and skipped[0][0] == Path(dataset):
            raise UsageError(f"no sequences found in '{dataset}': it has {skipped[0][1]}")
        if not found:
            where = f"searched {SEARCH_DEPTH} folders down"
            if skipped:
                count = "a folder" if len(skipped) == 1 else f"{len(skipped)} folders, e.g."
                where += f"; skipped {count} '{skipped[0][0]}', which has {skipped[0][1]}"
            raise UsageError(f"no sequences found in '{dataset}' ({where}); expected "
                             "videos with .gt.csv sidecars, or OTB (img/ + groundtruth_rect.txt), VOT (groundtruth.txt "
                             "+ frames), UAV123 (img/ + <name>.txt), LaSOT (img/ + groundtruth.txt + "
                             "full_occlusion.txt + out_of_view.txt), GOT-10k (frames + groundtruth.txt + "
                             "absence.label) folders, "
                             "TrackingNet splits (frames/ + anno/), or a folder of such folders")
        sequences.extend(found)
    # A sequence given twice (`--dataset data --dataset data/toy`) is run once, as `lptrack run` runs a video named
    # twice: it was refused as two sequences of one name, the message naming the same folder twice.
    kept: list[Sequence] = []
    where: dict[tuple[Path, Path], int] = {}
    for s in sequences:
        key = (Path(s.path).resolve(), Path(s.gt_path).resolve())
        if key not in where:
            where[key] = len(kept)
            kept.append(s)
            continue
        first = kept[where[key]]
        again = "twice" if str(s.path) == str(first.path) else f"again as '{s.path}'"
        note = f"sequence '{first.path}' is given {again}; it is run once"
        if note not in first.notes:
            kept[where[key]] = dataclasses.replace(first, notes=(*first.notes, note))
    sequences = kept
    names = [s.name for s in sequences]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        where = " and ".join(f"'{s.path}'" for s in sequences if s.name == dupes[0])
        more = f" (also shared: {', '.join(dupes[1:])})" if len(dupes) > 1 else ""
        raise UsageError(f"several sequences are called {dupes[0]}: {where}{more}; give datasets whose names differ")
    return sequences


def run_one(sequence: Sequence, tracker_name: str, params: Mapping | None = None, start: int = 0,
            threads: int | None = TRACKING_OPENCV_THREADS) -> dict:
    """Run one tracker over one sequence and score it.

    Parameters
    ----------
    sequence : Sequence or path-like
        The sequence, or a path :func:`~logpolar_track.datasets.discover` resolves to exactly one.
    tracker_name : str
        Registered tracker name.
    params : mapping, optional
        ``{"tracker_params": {name: {keyword: value}}}``: keyword tuning passed to the tracker.
    start : int
        Which initial ROI (:func:`start_roi`): 0, the ground truth's, or one of OTB's perturbed ones.
    threads : int or None
        OpenCV's worker threads while the tracker runs (:func:`~logpolar_track.executor.opencv_threads`): 1 by
        default, so that every tracker, lptrack's and OpenCV's, is timed on one core; None leaves OpenCV's
        setting alone (its default uses every core, which CSRT's parallel loops use).

    Returns
    -------
    dict
        ``sequence``, ``tracker``, ``start``, ``updates`` (frames passed to ``update``),
        ``lost_frames`` (updates reported lost, with ground truth or not; ``lost_rate`` is the share of the scored
        frames), ``update_time_s``, ``fps`` (updates per second of update time), ``error`` (None, or
        the message of an exception that stopped the run; then the numbers cover the frames before it), and
        every key of :func:`~logpolar_track.evaluate.score_track`.
    """
    if not isinstance(sequence, Sequence):
        sequence = discover_one(sequence, "run_one takes one")
    params = dict(params or {})
    tracker_params = dict((params.get("tracker_params") or {}).get(tracker_name, {}))
    rows: list[tuple] = []
    statuses: list[str] = []
    update_time, updates, lost, error = 0.0, 0, 0, None
    try:
        roi = start_roi(sequence.roi, start)
        tracker = create_tracker(tracker_name, **tracker_params)
        with opencv_threads(threads):
            for index, _time_s, frame in sequence.frames():
                if index < sequence.start:
                    continue
                if index == sequence.start:
                    try:
                        state, status = tracker.init(frame, roi), "init"
                    except RoiError as exc:  # the ground truth's (or a .roi sidecar's) start: say which
                        raise RoiError(f"initial ROI {roi.to_spec()} on {sequence.frame_name(index)}: {exc}") from None
                else:
                    t0 = time.perf_counter()
                    ok, state = tracker.update(frame)
                    update_time += time.perf_counter() - t0
                    updates += 1
                    lost += not ok
                    status = "tracked" if ok else "lost"
                e = state.ellipse
                rot = math.nan if state.rotation_deg is None else state.rotation_deg
                rows.append((index, e.cx, e.cy, e.a, e.b, e.angle_deg, state.scale, rot, state.score))
                statuses.append(status)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # one failing pair must not sink the whole benchmark; it is reported
        error = describe_exception(exc)  # lptrack's own messages as they are, a bug's with its type
    table = np.array(rows, float).reshape(-1, 9)
    track = Track(table[:, 0].astype(int), table[:, 1:6], table[:, 6], table[:, 7], table[:, 8], statuses)
    result = {"sequence": sequence.name, "tracker": tracker_name, "start": start,
              "updates": updates, "lost_frames": lost,
              "update_time_s": update_time, "fps": updates / update_time if update_time > 0 else math.nan,
              "error": error}
    result.update(score_track(sequence.gt, track))
    if sequence.passes > 1:
        result["auc_per_pass"] = auc_per_pass(sequence, result["frames"], result["iou"])
    return result


def auc_per_pass(sequence: Sequence, frames, iou) -> list[float]:
    """The IoU success AUC of each pass of a sequence played there and back
    (:meth:`~logpolar_track.datasets.Sequence.there_and_back`), from the scored ``frames`` and their ``iou``
    (:func:`~logpolar_track.evaluate.score_track`'s), over each pass's frames with ground truth: those a run that
    stopped never reached count as misses (IoU 0), so that a failure does not read as a better later pass. NaN for
    a pass without ground truth."""
    reached = np.zeros(len(sequence.gt.valid))
    reached[np.asarray(frames, int)] = np.nan_to_num(np.asarray(iou, float))
    m = sequence.pass_frames
    ends = [m + k * (m - 1) for k in range(sequence.passes)]
    out = []
    for begin, end in zip([0] + ends[:-1], ends):
        scored = np.flatnonzero(sequence.gt.valid[begin:end]) + begin
        out.append(auc(success_curve(reached[scored])) if scored.size else math.nan)
    return out


def _run_pair(pair: tuple, report=None) -> dict:
    """:func:`run_one` as an :mod:`~logpolar_track.executor` task: ``pair`` is (sequence, tracker, params,
    start, threads)."""
    return run_one(*pair)


def run_bench(sequences: list[Sequence], trackers: list[str], *, params: Mapping | None = None, jobs: int = 1,
              scheduler=None, on_result: Callable[[dict], None] | None = None, starts: int = 1,
              threads: int | None = TRACKING_OPENCV_THREADS) -> list[dict]:
    """Run every tracker on every sequence; results in (sequence, tracker) order whatever ``jobs`` is.

    Parameters
    ----------
    starts : int
        Initial ROIs per sequence (1 to ``len(STARTS)``, see :func:`start_roi`): each (sequence, tracker) pair is
        run from the first ``starts`` of them, and its result is their mean (:func:`mean_over_starts`).
    jobs : int
        Worker processes, a fresh one per pair (:func:`~logpolar_track.executor.run_tasks`); 1 runs in this
        process. Several jobs share the CPU, so frames/s figures are only comparable between runs with the
        same ``jobs``. OpenCV's MIL gives repeatable results only per fresh process (jobs >= 2): run in one
        process one after another, its numbers vary slightly with what ran before.
    scheduler : str or dask.distributed.Client, optional
        Run the pairs on this Dask cluster instead (the sequences must be at the same paths on its workers).
    on_result : callable, optional
        Called with each result as it completes (progress display).
    threads : int or None
        OpenCV's worker threads per tracker (see :func:`run_one`).
    """
    if not (is_whole(starts) and 1 <= starts <= len(STARTS)):
        raise UsageError(f"starts must be a whole number from 1 to {len(STARTS)}, got {starts!r}")
    pairs = [(s, t, params, k, threads) for s in sequences for t in trackers for k in range(starts)]
    runs: list[dict | None] = [None] * len(pairs)
    for outcome in run_tasks(_run_pair, pairs, jobs=jobs, scheduler=scheduler):
        sequence, tracker, _, start, _ = pairs[outcome.index]
        # run_one reports its own failures; a worker that died reports here, as a failed pair without frames.
        result = outcome.value if outcome.ok else _failed_pair(sequence, tracker, outcome.error, start)
        runs[outcome.index] = result
        if on_result:
            on_result(result)
    if starts == 1:
        return runs
    return [mean_over_starts(runs[i:i + starts]) for i in range(0, len(runs), starts)]


#: Per-run numbers that :func:`mean_over_starts` averages (the rest are summed, or kept from the first run).
_MEAN_KEYS = ("success_rate", "auc", "iou_mean", "precision_20", "centre_error_median_px", "scale_error_median_pct",
              "rotation_error_median_deg", "lost_rate", "off_tracked_rate")


def mean_over_starts(runs: list[dict]) -> dict:
    """One result from the runs of a (sequence, tracker) pair from several starts: the mean of each score and
    curve over the runs that scored frames, updates, lost frames and update time summed (frames/s over all the
    runs), ``starts`` (how many runs), ``auc_per_start`` and ``failed_starts`` (those that stopped on an error,
    scored on the frames before it); the frame counts and per-frame arrays are the first
    run's (the ground truth's start). ``error`` is the first failed run's, naming its start."""
    merged = dict(runs[0])
    scored = [r for r in runs if r["frames_scored"]]
    for key in _MEAN_KEYS:
        value = _mean(r[key] for r in scored)
        if value is not None:  # else the first run's undefined value stands (None or NaN, as score_track gives)
            merged[key] = value
    for key in ("success_curve", "precision_curve"):
        if scored:
            merged[key] = np.mean([r[key] for r in scored], axis=0).tolist()
    for key in ("updates", "lost_frames", "update_time_s"):
        merged[key] = sum(r[key] for r in runs)
    merged["fps"] = merged["updates"] / merged["update_time_s"] if merged["update_time_s"] > 0 else math.nan
    merged["starts"] = len(runs)
    merged["auc_per_start"] = [r["auc"] for r in runs]
    if any("auc_per_pass" in r for r in runs):
        merged["auc_per_pass"] = _mean_per_pass([r.get("auc_per_pass") for r in scored])
    failed = [r for r in runs if r["error"]]
    merged["failed_starts"] = [r["start"] for r in failed]
    merged["error"] = f"start {failed[0]['start']}: {failed[0]['error']}" if failed else None
    return merged


def _failed_pair(sequence: Sequence, tracker: str, error: str, start: int = 0) -> dict:
    result = {"sequence": sequence.name, "tracker": tracker, "start": start, "frames": 0, "updates": 0,
              "lost_frames": 0, "update_time_s": 0.0, "fps": math.nan, "error": error}
    result.update(score_track(sequence.gt, Track(np.zeros(0, int), np.zeros((0, 5)), np.zeros(0), np.zeros(0),
                                                 np.zeros(0))))
    return result


def _mean_per_pass(lists) -> list[float | None]:
    """Pass by pass, the mean of the ``auc_per_pass`` lists given (None ones left out; None where no value)."""
    lists = [values for values in lists if values is not None]
    return [_mean(values[k] for values in lists) for k in range(max(map(len, lists), default=0))]


def _mean(values) -> float | None:
    vals = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(vals)) if vals else None


def summarise(results: list[dict], trackers: list[str]) -> list[dict]:
    """One summary per tracker: means over its sequences (see module notes), total frames/s, curves."""
    out = []
    for name in trackers:
        rs = [r for r in results if r["tracker"] == name]
        time_s = sum(r["update_time_s"] for r in rs)
        updates = sum(r["updates"] for r in rs)
        curves = [r["success_curve"] for r in rs if r["frames_scored"]]
        precs = [r["precision_curve"] for r in rs if r["frames_scored"]]
        succ = np.mean(curves, axis=0) if curves else np.full(len(IOU_THRESHOLDS), np.nan)
        out.append({
            "tracker": name,
            "sequences": len(rs),
            "errors": sum(r["error"] is not None for r in rs),
            "frames_scored": sum(r["frames_scored"] for r in rs),
            "success_rate": _mean(r["success_rate"] for r in rs),
            "auc": _mean(r["auc"] for r in rs),
            "precision_20": _mean(r["precision_20"] for r in rs),
            "centre_error_median_px": _mean(r["centre_error_median_px"] for r in rs),
            "scale_error_median_pct": _mean(r["scale_error_median_pct"] for r in rs),
            "rotation_error_median_deg": _mean(r["rotation_error_median_deg"] for r in rs),
            "lost_rate": _mean(r["lost_rate"] for r in rs),
            "off_tracked_rate": _mean(r["off_tracked_rate"] for r in rs),
            "fps": updates / time_s if time_s > 0 else None,
            **({"auc_per_pass": _mean_per_pass([r.get("auc_per_pass") for r in rs])}
               if any("auc_per_pass" in r for r in rs) else {}),
            "success_curve": succ.tolist(),
            "success_curve_auc": auc(succ) if curves else None,
            "precision_curve": (np.mean(precs, axis=0) if precs else
                                np.full(len(PRECISION_THRESHOLDS), np.nan)).tolist(),
        })
    return out


# ----------------------------------------------------------------------------------------------------------
# Reports
# ----------------------------------------------------------------------------------------------------------

_COLUMNS = (  # header, key, format: fraction shown as percent ("pct"), or a format spec
    ("frames", "frames_scored", "d"),
    ("success%", "success_rate", "pct"),
    ("AUC", "auc", ".3f"),
    ("prec@20%", "precision_20", "pct"),
    ("centre_px", "centre_error_median_px", ".1f"),
    ("scale_err%", "scale_error_median_pct", ".1f"),
    ("rot_err_deg", "rotation_error_median_deg", ".1f"),
    ("lost%", "lost_rate", "pct"),
    ("off_tracked%", "off_tracked_rate", "pct"),
    ("fps", "fps", ".1f"),
)


def _cell(value, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    if fmt == "pct":
        return f"{100 * value:.1f}"
    return format(value, fmt)


def format_table(results: list[dict], summary: list[dict], *, speed: bool = True) -> str:
    """Plain-text table, columns aligned: one row per (sequence, tracker), then one ``mean`` row per tracker.

    Rates are percentages of scored frames (``off_tracked%`` of those reported tracked); errors are medians (px,
    %, degrees); ``n/a`` where a number is undefined (e.g. rotation for trackers or ground truth without an
    angle); ``fps`` (left out when ``speed`` is False) is update()-only speed.
    """
    columns = _COLUMNS if speed else tuple(c for c in _COLUMNS if c[1] != "fps")
    header = ["sequence", "tracker"] + [c[0] for c in columns]
    rows = []
    for r in results:
        row = [r["sequence"], r["tracker"]] + [_cell(r.get(key), fmt) for _, key, fmt in columns]
        if r.get("error"):
            row[1] += " (failed)"
        rows.append(row)
    if summary:
        rows.append(None)
        n_seq = max(s["sequences"] for s in summary)
        for s in summary:
            # A failed run is scored over the frames it reached: say so where it enters the mean too.
            tracker = s["tracker"] + (f" ({s['errors']} failed)" if s.get("errors") else "")
            rows.append([f"mean ({n_seq})", tracker] + [_cell(s.get(key), fmt) for _, key, fmt in columns])
    return _aligned(header, rows, left=2)


def format_passes(summary: list[dict]) -> str:
    """Lines giving each tracker's mean IoU AUC per pass (sequences played there and back), or ''."""
    lines = [f"  {s['tracker']}: " + " / ".join(_cell(v, ".3f") for v in s["auc_per_pass"])
             for s in summary if s.get("auc_per_pass")]
    return "Mean IoU AUC per pass (--passes):\n" + "\n".join(lines) + "\n" if lines else ""


def _aligned(header: list[str], rows: list, left: int) -> str:
    """Plain-text table of ``rows`` (lists of strings; None draws a rule) under ``header``: columns as wide as
    their widest cell, the first ``left`` of them left-aligned and the others right-aligned."""
    widths = [max(len(header[i]), *(len(r[i]) for r in rows if r)) for i in range(len(header))]

    def line(cells):
        return "  ".join(c.ljust(w) if i < left else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths)))

    rule = line(["-" * w for w in widths])
    return "\n".join([line(header), rule] + [line(r) if r else rule for r in rows]) + "\n"


#: Student's t at 97.5 % for 1 to 32 degrees of freedom (two-sided 95 %; SciPy's ``t.ppf(0.975, df)``, rounded):
#: how many standard errors a mean over n starts must be from 0 to count as ahead or behind. With few starts the
#: standard error is itself a guess, and two of them called a fifth to a quarter of sequences with no difference
#: ahead or behind at 2 or 3 starts (a simulation of 300 such sequences).
_T_975 = (12.71, 4.30, 3.18, 2.78, 2.57, 2.45, 2.36, 2.31, 2.26, 2.23, 2.20, 2.18, 2.16, 2.14, 2.13, 2.12, 2.11, 2.10,
          2.09, 2.09, 2.08, 2.07, 2.07, 2.06, 2.06, 2.06, 2.05, 2.05, 2.05, 2.04, 2.04, 2.04)


def paired_differences(results: list[dict], trackers: list[str]) -> list[dict]:
    """The first of ``trackers`` against each other one, start by start: per sequence, the mean over the starts
    of its AUC minus the other's from the same initial ROI (a paired comparison), and the standard error of that
    mean; over the sequences, the mean of those and its standard error. Empty with one tracker.

    The standard errors treat the starts as a random sample of initial ROIs (OTB's 12 are fixed perturbations,
    the 20 after them drawn at random) and the sequences as fixed: they say whether a difference on these
    sequences would hold from other starts, not whether it would hold on other footage. A start that failed for
    either tracker (an exception partway, scored on the frames before it) is left out.

    Returns
    -------
    list of dict
        One per other tracker: ``tracker``, ``against`` (the first tracker), ``difference`` and
        ``standard_error`` (AUC, over the sequences compared: the mean of theirs and ``sqrt(sum of squares) /
        n``; None where none could be compared, or, for the error, where one sequence has a single start),
        ``ahead``, ``level``, ``behind`` and ``undecided`` (sequences where the first tracker is ahead or behind
        by more than Student's t at 95 % times the standard error, within that, or with one start only), and
        ``sequences``: ``{name: {"difference", "standard_error", "starts"}}`` (starts compared; standard error
        None with one).
    """
    if len(trackers) < 2:
        return []
    by_pair = {(r["sequence"], r["tracker"]): r for r in results}
    names = list(dict.fromkeys(r["sequence"] for r in results))
    first = trackers[0]
    out = []
    for other in trackers[1:]:
        sequences, verdicts = {}, []
        for name in names:
            mine, theirs = by_pair.get((name, first)), by_pair.get((name, other))
            if mine is None or theirs is None or "auc_per_start" not in mine or "auc_per_start" not in theirs:
                continue
            failed = set(mine.get("failed_starts", ())) | set(theirs.get("failed_starts", ()))
            d = np.array([a - b for k, (a, b) in enumerate(zip(mine["auc_per_start"], theirs["auc_per_start"]))
                          if k not in failed and a is not None and b is not None
                          and math.isfinite(a) and math.isfinite(b)])
            if d.size == 0:
                continue
            mean = float(d.mean())
            se = float(d.std(ddof=1) / math.sqrt(d.size)) if d.size > 1 else None
            sequences[name] = {"difference": mean, "standard_error": se, "starts": int(d.size)}
            if se is None:
                verdicts.append("undecided")
            elif abs(mean) <= _T_975[min(d.size - 1, len(_T_975)) - 1] * se:
                verdicts.append("level")
            else:
                verdicts.append("ahead" if mean > 0 else "behind")
        errors = [s["standard_error"] for s in sequences.values()]
        known = bool(errors) and all(e is not None for e in errors)
        out.append({"tracker": other, "against": first,
                    "difference": float(np.mean([s["difference"] for s in sequences.values()])) if sequences else None,
                    "standard_error": math.sqrt(sum(e * e for e in errors)) / len(errors) if known else None,
                    **{v: verdicts.count(v) for v in ("ahead", "level", "behind", "undecided")},
                    "sequences": sequences})
    return out


def format_paired(paired: list[dict]) -> str:
    """:func:`paired_differences` as plain text: a column per other tracker, a row per sequence, then the mean
    (with the number of sequences it is over, where a column has fewer than the rows) and the count of sequences
    ahead / level / behind (/ undecided, if any); empty if there is nothing to compare."""
    if not paired:
        return ""

    def cell(d, se):
        if d is None:
            return "n/a"
        d = 0.0 if round(d, 3) == 0 else d  # no "-0.000"
        return f"{d:+.3f}" + ("" if se is None else f" ± {se:.3f}")

    names = list(dict.fromkeys(n for p in paired for n in p["sequences"]))
    header = ["sequence"] + [p["tracker"] for p in paired]
    rows = [[n] + [cell(p["sequences"][n]["difference"], p["sequences"][n]["standard_error"])
                   if n in p["sequences"] else "n/a" for p in paired] for n in names]
    rows.append(None)
    rows.append([f"mean ({len(names)})"] + [
        cell(p["difference"], p["standard_error"])
        + (f" ({len(p['sequences'])})" if 0 < len(p["sequences"]) < len(names) else "") for p in paired])
    undecided = any(p["undecided"] for p in paired)
    rows.append(["ahead/level/behind" + ("/undecided" if undecided else "")] + [
        f"{p['ahead']}/{p['level']}/{p['behind']}" + (f"/{p['undecided']}" if undecided else "") for p in paired])
    title = (f"{paired[0]['against']}'s AUC minus each other tracker's, start by start (mean ± standard error over "
             f"the starts; ahead or behind: beyond Student's t at 95 %):\n")
    return title + _aligned(header, rows, left=1)


def _opencv_flavour() -> str:
    from importlib.metadata import PackageNotFoundError, version

    for dist in ("opencv-contrib-python-headless", "opencv-contrib-python", "opencv-python-headless",
                 "opencv-python"):
        try:
            return f"{dist} {version(dist)}"
        except PackageNotFoundError:
            continue
    return "unknown"


def environment() -> dict:
    """Versions of lptrack, Python, NumPy and OpenCV, and a description of the machine."""
    import cv2

    return {
        "versions": {"lptrack": __version__, "python": platform.python_version(), "numpy": np.__version__,
                     "opencv": cv2.__version__, "opencv_package": _opencv_flavour()},
        "machine": {"platform": platform.platform(), "machine": platform.machine(),
                    "processor": platform.processor(), "cpu_count": os.cpu_count(),
                    "vector_extensions": vector_extensions()},
    }


#: CPU flags (``/proc/cpuinfo``) of the vector instruction sets NumPy's and OpenCV's kernels pick by, widest first.
_VECTOR_FLAGS = (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX"), ("sse4_2", "SSE4.2"), ("asimd", "NEON"))


def cpuinfo_value(prefixes: tuple[str, ...], cpuinfo: str | os.PathLike = "/proc/cpuinfo") -> str | None:
    """The text after ``:`` on the first line of ``cpuinfo`` that starts with one of ``prefixes`` (e.g.
    ``("model name",)``), stripped; None if there is no such line or no such file (as off Linux)."""
    try:
        with open(cpuinfo, encoding="utf-8") as f:
            for line in f:
                if line.startswith(prefixes):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def vector_extensions(cpuinfo: str | os.PathLike = "/proc/cpuinfo") -> str | None:
    """The widest vector instruction set the CPU reports in ``cpuinfo`` (``'AVX-512'``, ``'AVX2'``, ...
    ``'NEON'``), or None where it does not say (or there is no such file, as off Linux). Speeds depend on more
    than this: two virtual machines both named "AMD EPYC", with and without AVX-512, ran lptrack's trackers about
    three times apart and OpenCV's CSRT 1.5-2 times apart."""
    flags = set((cpuinfo_value(("flags", "Features"), cpuinfo) or "").split())
    return next((name for flag, name in _VECTOR_FLAGS if flag in flags), None)


def _clean(value):
    """JSON-safe copy: NaN/inf become None, numpy scalars become Python numbers."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def bench_document(results: list[dict], summary: list[dict], sequences: list[Sequence], *,
                   parameters: Mapping, skipped: list[tuple[str, str]] = (), per_frame: bool = False,
                   paired: list[dict] = ()) -> dict:
    """The whole benchmark as one JSON-ready document (``schema_version`` :data:`SCHEMA_VERSION`).

    Keys: ``schema_version``, ``tool``, ``created`` (UTC, ISO 8601), ``versions``, ``machine``, ``parameters``
    (with the metric definitions' constants), ``sequences``, ``skipped_trackers``, ``results`` (one per
    sequence and tracker, curves included; per-frame ``frames``/``iou``/``centre_error_px`` only with
    ``per_frame``), ``summary`` (one per tracker), ``paired`` (:func:`paired_differences`; empty with one start or
    one tracker). Undefined numbers are null.
    """
    env = environment()
    kept = [r if per_frame else {k: v for k, v in r.items() if k not in PER_FRAME_KEYS} for r in results]
    params = dict(parameters)
    params.update({"success_radius_fraction": SUCCESS_RADIUS_FRACTION, "precision_px": PRECISION_PX,
                   "iou_thresholds": IOU_THRESHOLDS.tolist(), "precision_thresholds_px": PRECISION_THRESHOLDS.tolist(),
                   "speed": "tracker update() only, time.perf_counter; decoding, init and scoring excluded"})
    return _clean({
        "schema_version": SCHEMA_VERSION,
        "tool": "lptrack bench",
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "versions": env["versions"],
        "machine": env["machine"],
        "parameters": params,
        "sequences": [s.describe() for s in sequences],
        "skipped_trackers": [{"tracker": n, "reason": why} for n, why in skipped],
        "results": kept,
        "summary": summary,
        "paired": list(paired),
    })


def plot_curves(summary: list[dict], path, caption: str | None = None, *, overwrite: bool = True) -> None:
    """Save OTB-style success (IoU) and precision (centre error) plots, one curve per tracker, as a PNG (or PDF
    or SVG, as ``path`` ends), under ``caption`` if given (what was run, e.g. "7 sequences played backwards"),
    over an existing file only with ``overwrite``.

    The legend gives each tracker's success AUC and precision at 20 px (means over sequences).

    Raises
    ------
    UsageError
        If matplotlib is not installed, or ``path`` does not end in .png, .pdf or .svg.
    OutputError
        If the file cannot be written.
    """
    check_image_suffix(path, PLOT_SUFFIXES, "plot")
    hint = matplotlib_hint()
    if hint:
        raise UsageError(hint)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    if not path.parent.is_dir():
        raise OutputError(f"cannot write plot '{path}': folder '{path.parent}' does not exist")
    fig, (ax_s, ax_p) = plt.subplots(1, 2, figsize=(11, 4.5))
    # Each tracker keeps its colour in both panels (the legends are ranked, each by its own panel's figure).
    palette = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colour = {s["tracker"]: palette[i % len(palette)] for i, s in enumerate(summary)}
    for s in sorted(summary, key=lambda s: -(s["auc"] or 0)):
        ax_s.plot(IOU_THRESHOLDS, s["success_curve"], color=colour[s["tracker"]],
                  label=f"{s['tracker']} [{_cell(s['auc'], '.3f')}]")
    for s in sorted(summary, key=lambda s: -(s["precision_20"] or 0)):
        ax_p.plot(PRECISION_THRESHOLDS, s["precision_curve"], color=colour[s["tracker"]],
                  label=f"{s['tracker']} [{_cell(s['precision_20'], '.3f')}]")
    # A little room above 1, so that a curve at 1 (a tracker right on every frame) is not hidden by the frame.
    ax_s.set(title="Success plot", xlabel="IoU threshold", ylabel="success rate", xlim=(0, 1), ylim=(0, 1.02))
    ax_p.set(title="Precision plot", xlabel="centre error threshold (px)", ylabel="precision",
             xlim=(0, PRECISION_THRESHOLDS[-1]), ylim=(0, 1.02))
    for ax in (ax_s, ax_p):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower left" if ax is ax_s else "lower right")
    if caption:
        fig.suptitle(caption, fontsize=10)
    fig.tight_layout()
    try:
        with written_into_place(path, overwrite=overwrite, what="plot") as temp:
            fig.savefig(temp, dpi=100)
    finally:
        plt.close(fig)


def evaluate_run(prediction, ground_truth, *, video=None) -> tuple[dict, list[str]]:
    """Score a run's CSV (or another tool's: :func:`~logpolar_track.evaluate.read_track_csv`) against ground truth,
    as ``lptrack eval`` does: the metrics of :func:`~logpolar_track.evaluate.score_track` and notes on what was not
    scored (frames with ground truth but no row, rows past the ground truth's end), one sentence each.

    Parameters
    ----------
    prediction : str or Path
        The run's CSV or JSON lines; ``'-'`` reads stdin.
    ground_truth : str or Path
        Any ground truth :func:`~logpolar_track.datasets.load_ground_truth` reads (a ``.gt.csv``, OTB, VOT or
        UAV123 file, a sequence folder, or a video with its ``.gt.csv`` beside it). Frames are matched by index.
    video : str or Path, optional
        With a batch's stream (a ``video`` column): the video whose rows are scored. Default: ``ground_truth`` when
        that is a video, among several videos (a stream of one is scored whatever its video's name).

    Raises
    ------
    UsageError
        The two given the other way round (a ``.gt.csv`` as the run, a run as the ground truth), or no row of the
        run has ground truth.
    GroundTruthError, InputError
        A file that cannot be read as what it is given as.
    """
    metrics, notes, _ = evaluate_stream_run(prediction, ground_truth, video=video)
    return metrics, notes


def evaluate_stream_run(prediction, ground_truth, *, video=None) -> tuple[dict, list[str], str | None]:
    """:func:`evaluate_run`, and the name of the video whose rows were scored as the run's ``video`` column
    gives it (None for one video's own CSV, which has no such column: ``video`` was then not used)."""
    prediction, ground_truth = Path(prediction), Path(ground_truth)
    _check_argument_order(prediction, ground_truth)
    scored = scored_video(ground_truth, video)
    table = read_run_csv(prediction, scored, other_tools=True, only_if_several=video is None)
    track = table.track()
    gt = load_ground_truth(ground_truth)
    metrics = score_track(gt, track)
    if metrics["frames_scored"] == 0:
        raise no_frame_with_ground_truth(f"'{prediction}'", f"'{ground_truth}'")
    notes = []
    if video is not None and table.video is None:
        # Said, not refused: the run's own CSV is what was meant. Ignored in silence, a mistyped name went unnoticed.
        notes.append(f"--video '{video}' is ignored: '{prediction}' is one video's run (it has no 'video' column); "
                     f"--video chooses among the videos of a batch's stream")
    if metrics["frames_missing"]:
        total = metrics["frames_scored"] + metrics["frames_missing"]
        notes.append(f"'{prediction}' has no row for {metrics['frames_missing']} of the {total} frames with ground "
                     f"truth; they are not scored")
    past = rows_past_ground_truth(f"'{prediction}'", track.frames, gt, f"'{ground_truth}'")
    if past is not None:
        # The other way round from the rows missing: a ground truth cut short, or another sequence's, scored part of
        # the run in silence.
        notes.append(f"{past}; they are not scored (is it this video's ground truth?)")
    return metrics, notes, table.video


def scored_video(ground_truth, video=None):
    """The video whose rows of a batch's stream ``lptrack eval`` scores: ``video``, or else the ground truth when it
    is given as a video (then it chooses only among several videos), or None."""
    if video is None and Path(ground_truth).suffix.lower() in VIDEO_EXTENSIONS:
        return Path(ground_truth)
    return video


def _check_argument_order(prediction: Path, ground_truth: Path) -> None:
    """Refuse a ground-truth file given as the run, or a run CSV given as the ground truth: both are CSVs of frames
    and ellipses, and eval scored them the other way round without a word (a .gt.csv against itself: AUC 0.952)."""
    usage = "the run's CSV goes first: lptrack eval PRED.csv GT"
    if prediction.name.lower().endswith(".gt.csv"):
        raise UsageError(f"PRED.csv '{prediction}' is ground truth (a .gt.csv), not a run; {usage}")
    if ground_truth.suffix.lower() in (".csv", ".jsonl") and ground_truth.is_file():
        columns = _first_line(ground_truth).replace('"', "").split(",")
        if ground_truth.suffix.lower() == ".jsonl" or {"time_s", "status"} <= {c.strip() for c in columns}:
            raise UsageError(f"GT '{ground_truth}' is an lptrack run (its columns include time_s and status), not "
                             f"ground truth; {usage}")


def _first_line(path: Path) -> str:
    """The first line of a text file, or '' if it cannot be read as text (its reader then says what is wrong)."""
    try:
        # UTF-8, or UTF-16 with a byte-order mark, as the run CSV's reader reads it (it reads it whole too).
        return decode_text(path.read_bytes()).partition("\n")[0].strip()
    except (OSError, UnicodeDecodeError):
        return ""


def eval_document(pred_path, gt_path, metrics: dict, *, per_frame: bool = True, video=None) -> dict:
    """JSON-ready document of ``lptrack eval``: inputs, metric constants and every metric; with ``video``, the video
    whose rows of a batch's stream were scored (``"video"``). ``"ground_truth"`` is ``gt_path`` as given;
    ``"ground_truth_file"``, where it differs, the file read for it (a video's ``.gt.csv``, a sequence folder's
    ``groundtruth_rect.txt``)."""
    kept = metrics if per_frame else {k: v for k, v in metrics.items() if k not in PER_FRAME_KEYS}
    chosen = {} if video is None else {"video": str(video)}
    read = ground_truth_file(gt_path)
    read_from = {} if read == Path(gt_path) else {"ground_truth_file": str(read)}
    return _clean({"schema_version": SCHEMA_VERSION, "tool": "lptrack eval", "prediction": str(pred_path), **chosen,
                   "ground_truth": str(gt_path), **read_from, "success_radius_fraction": SUCCESS_RADIUS_FRACTION,
                   "precision_px": PRECISION_PX, "metrics": kept})


__all__ = ["run_one", "run_bench", "mean_over_starts", "start_roi", "STARTS", "summarise", "format_table",
           "paired_differences", "format_paired", "auc_per_pass", "format_passes",
           "bench_document", "eval_document", "evaluate_run", "scored_video", "plot_curves", "resolve_trackers",
           "collect_sequences", "default_dataset", "environment", "SCHEMA_VERSION"]
