"""Figures with matplotlib (the optional extra ``plot``): a run's track as a figure, and what every figure shares.

:func:`plot_track` (``lptrack plot``) draws the centre path over the run's first frame, scale, rotation and score
against time, and with ground truth its overlay and the errors. :func:`matplotlib_hint` and :data:`PLOT_SUFFIXES`
serve ``lptrack bench --plot`` too (:func:`logpolar_track.bench.plot_curves`). matplotlib is imported only when a
figure is drawn. Pixels with the origin at the top-left corner, x right, y down; angles in degrees counter-clockwise
as seen on screen.
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path

import cv2
import numpy as np

from .datasets import load_ground_truth
from .errors import UsageError
from .evaluate import as_run_table, no_frame_with_ground_truth, rotation_errors, scale_errors, score_track
from .geometry import Ellipse
from .outputs import check_image_suffix, check_output_path, written_into_place
from .video import read_frame

#: Hint shown when matplotlib is missing.
PLOT_HINT = "pip install matplotlib"
#: File types ``lptrack plot`` writes (matplotlib picks the format from the name).
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def matplotlib_hint() -> str | None:
    """None if matplotlib can be imported, else a one-line hint on installing it."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return f"plotting needs matplotlib, which is not installed; install it with: {PLOT_HINT}"
    return None

#: Size of the figure written by :func:`plot_track`, in inches at :data:`PLOT_DPI`.
PLOT_SIZE_IN = (13.0, 7.5)
PLOT_DPI = 100


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges ``[start, stop)`` of consecutive True values."""
    padded = np.concatenate([[False], np.asarray(mask, bool), [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2], edges[1::2]))


def plot_track(run, out_png, *, video=None, ground_truth=None, overwrite: bool = False,
               title: str | None = None) -> Path:
    """Draw a track as a figure and save it as PNG (:data:`PLOT_SIZE_IN` x :data:`PLOT_DPI` pixels), or as PDF or
    SVG if ``out_png`` ends so (:data:`PLOT_SUFFIXES`).

    Panels: the centre path (over the run's first frame when ``video`` is given, in video pixels, y down;
    the initial outline dashed, lost frames as red crosses); scale; rotation (degrees CCW, cumulative); score,
    with lost frames shaded red. With ``ground_truth``, its path and values are overlaid (dashed, black) and
    a last panel plots the per-frame errors: centre error (px), scale error (%) and rotation error (deg).

    Parameters
    ----------
    run : str, Path, RunTable or iterable of FrameResult
        The track (a path is read with :func:`~logpolar_track.evaluate.read_run_csv`).
    out_png : str or Path
    video : str or Path, optional
        The tracked video, for the thumbnail.
    ground_truth : str, Path or GroundTruth, optional
        A file or sequence folder as ``lptrack eval`` takes
        (:func:`~logpolar_track.datasets.load_ground_truth`); errors come from
        :func:`~logpolar_track.evaluate.score_track`.
    overwrite : bool
    title : str, optional

    Raises
    ------
    UsageError
        matplotlib is missing (the message is the install hint), or ``out_png`` does not end in .png, .pdf or .svg.
    GroundTruthError, VideoError, OutputError, InputError
    """
    check_image_suffix(out_png, PLOT_SUFFIXES, "output image")
    hint = matplotlib_hint()
    if hint:
        raise UsageError(hint)
    table = as_run_table(run)
    out_png = check_output_path(out_png, overwrite=overwrite, what="output image")
    gt = load_ground_truth(ground_truth) if isinstance(ground_truth, (str, os.PathLike)) else ground_truth
    if gt is not None and not gt.valid[table.frames[table.frames < len(gt)]].any():
        # Another video's ground truth, or one that ends before the run starts: the figure showed an empty error
        # panel and a legend line drawn nowhere, without a word, where `lptrack eval` refuses the pair.
        named = f"'{ground_truth}'" if isinstance(ground_truth, (str, os.PathLike)) else "the ground truth"
        raise no_frame_with_ground_truth(f"'{table.source}'", named)
    thumb = read_frame(video, int(table.frames[0])) if video is not None else None

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = table.time_s
    lost = table.lost
    fig = plt.figure(figsize=PLOT_SIZE_IN, dpi=PLOT_DPI)
    n_right = 4 if gt is not None else 3
    grid = fig.add_gridspec(n_right, 2, width_ratios=(1.15, 1.0))
    ax_path = fig.add_subplot(grid[:, 0])
    axes = [fig.add_subplot(grid[0, 1])]
    axes += [fig.add_subplot(grid[i, 1], sharex=axes[0]) for i in range(1, n_right)]
    ax_scale, ax_rot, ax_score = axes[:3]

    # Path, in video pixels (y down, as on screen).
    if thumb is not None:
        ax_path.imshow(cv2.cvtColor(thumb.image, cv2.COLOR_BGR2RGB), extent=(-0.5, thumb.width - 0.5,
                                                                             thumb.height - 0.5, -0.5))
    cx, cy = table.ellipses[:, 0], table.ellipses[:, 1]
    ax_path.plot(cx, cy, "-", color="tab:green", lw=1.5, label="track centre")
    first = Ellipse(*(float(v) for v in table.ellipses[0]))
    outline = np.vstack([first.boundary_points(128), first.boundary_points(128)[:1]])
    ax_path.plot(outline[:, 0], outline[:, 1], "--", color="tab:green", lw=1, label=f"frame {table.frames[0]}")
    ax_path.plot([cx[0]], [cy[0]], "o", color="tab:green", ms=5)
    if lost.any():
        ax_path.plot(cx[lost], cy[lost], "x", color="red", ms=5, label="lost")
    if gt is not None:
        gt_frames = table.frames[(table.frames < len(gt))]
        gt_frames = gt_frames[gt.valid[gt_frames]]
        ax_path.plot(gt.boxes[gt_frames, 0], gt.boxes[gt_frames, 1], "--", color="black", lw=1.2,
                     label="ground truth")
    if thumb is None:
        ax_path.invert_yaxis()
    else:
        # Zoom to where the object went (its outlines plus a margin), within the frame: a small path over a
        # whole frame would be a few pixels wide.
        margin = 1.5 * float(np.max(table.ellipses[:, 2:4]))
        x0 = max(-0.5, float(np.min(cx)) - margin)
        x1 = min(thumb.width - 0.5, float(np.max(cx)) + margin)
        y0 = max(-0.5, float(np.min(cy)) - margin)
        y1 = min(thumb.height - 0.5, float(np.max(cy)) + margin)
        if x1 > x0 and y1 > y0:
            ax_path.set_xlim(x0, x1)
            ax_path.set_ylim(y1, y0)
    ax_path.set_aspect("equal", adjustable="datalim" if thumb is None else "box")
    ax_path.set(xlabel="x (px)", ylabel="y (px, down)", title="centre path")
    ax_path.legend(fontsize=8, loc="best")

    ax_scale.plot(t, table.scale, color="tab:blue", lw=1.2, label="track")
    ax_scale.set_ylabel("scale")
    if np.isfinite(table.rotation_deg).any():
        ax_rot.plot(t, table.rotation_deg, color="tab:purple", lw=1.2, label="track")
    else:
        ax_rot.text(0.99, 0.05, "tracker does not measure rotation", ha="right", va="bottom",
                    transform=ax_rot.transAxes, fontsize=9, color="grey")
    ax_rot.set_ylabel("rotation (deg CCW)")
    ax_score.plot(t, table.score, color="tab:orange", lw=1.2)
    ax_score.set(ylabel="score", ylim=(0, 1.05))
    for start, stop in _runs(lost):
        # Shade each lost frame as the time span it stands for (half a frame interval either side).
        dt = np.median(np.diff(t)) if len(t) > 1 else 1.0
        for ax in axes[:3]:
            ax.axvspan(t[start] - dt / 2, t[stop - 1] + dt / 2, color="red", alpha=0.15, lw=0)
    if lost.any():
        count = int(lost.sum())
        ax_score.plot([], [], color="red", alpha=0.3, lw=6, label=f"lost ({count} frame{'' if count == 1 else 's'})")
        ax_score.legend(fontsize=8, loc="lower left")

    if gt is not None:
        metrics = score_track(gt, table.track())
        frames = np.asarray(metrics["frames"], int)
        rows = np.searchsorted(table.frames, frames)
        if frames.size:
            ts = t[rows]
            gs = gt.scale[frames] / gt.scale[frames[0]] * table.scale[rows[0]]
            ax_scale.plot(ts, gs, "--", color="black", lw=1, label="ground truth")
            ax_errors = axes[3]
            ax_errors.plot(ts, metrics["centre_error_px"], color="tab:green", lw=1.2, label="centre (px)")
            ps = table.scale[rows] / table.scale[rows[0]]
            ax_errors.plot(ts, scale_errors(ps, gt.scale[frames] / gt.scale[frames[0]]), color="tab:blue",
                           lw=1.2, label="scale (%)")
            if gt.rotation_deg is not None and gt.rotation_period:
                start = table.rotation_deg[rows[0]]
                gr = gt.rotation_deg[frames] - gt.rotation_deg[frames[0]] + (start if math.isfinite(start) else 0.0)
                ax_rot.plot(ts, gr, "--", color="black", lw=1, label="ground truth")
            if gt.rotation_deg is not None and gt.rotation_period and np.isfinite(table.rotation_deg[rows]).any():
                pr = table.rotation_deg[rows]
                ax_errors.plot(ts, rotation_errors(pr - pr[0], gr - gr[0], gt.rotation_period),
                               color="tab:purple", lw=1.2, label="rotation (deg)")
            ax_errors.set(ylabel="error")
            ax_errors.set_ylim(bottom=0)
            ax_errors.legend(fontsize=8, loc="upper left", ncol=3)
            med = metrics["centre_error_median_px"]
            ax_errors.set_title(f"vs ground truth: median centre error {med:.1f} px, "
                                f"AUC {metrics['auc']:.2f}", fontsize=9)
            ax_scale.legend(fontsize=8, loc="best")
            if ax_rot.get_legend_handles_labels()[0]:
                ax_rot.legend(fontsize=8, loc="best")
    for ax in axes:
        ax.grid(alpha=0.3)
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel("time (s)")
    n_lost = int(lost.sum())
    fig.suptitle(title or f"{table.source}: {len(table)} frames, {n_lost} lost", fontsize=11)
    try:
        with written_into_place(out_png, overwrite=overwrite, what="output image") as temp, \
                warnings.catch_warnings():
            # A file name in a script the font lacks (CJK) is drawn as boxes; matplotlib's warning about each
            # glyph, with its source line, would reach the user's terminal twice per character.
            warnings.filterwarnings("ignore", message="Glyph .* missing from", category=UserWarning)
            fig.tight_layout()
            fig.savefig(temp, dpi=PLOT_DPI)
    finally:
        plt.close(fig)
    return Path(out_png)
