"""Reproduce the thesis' Table 4.1 (seconds per frame of each tracker) on today's hardware.

The measurement follows the issue: a 640x480 synthetic video of a textured object of radius 50 pixels (circle)
or semi-axes 60 x 40 (ellipse), an 11x11 search window, one core (``cv2.setNumThreads(1)``; NumPy's FFT is
single-threaded). Tracker time is ``update()`` only, on frames already decoded. Baselines: decoding the same
video written as mp4v, and decoding + re-encoding it.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time

import cv2
import numpy as np

from .geometry import Ellipse
from .synthetic import similarity_path, synthetic_sequence
from .trackers import create_tracker, tracker_names

#: Table 4.1 of the thesis, seconds per frame (Matlab, 3.2 GHz Pentium 4, 11x11 window): (circle, ellipse).
THESIS_SECONDS = {
    "diffdecomp": (1.5, 1.7),
    "fixed": (1.5, 1.7),
    "update": (2.5, 4.0),
    "occlusion": (3.5, 5.0),
    "spatial": (22.0, 24.0),  # 5 angles x 5 scales
}

SHAPES = {"circle": Ellipse.circle(320, 230, 50), "ellipse": Ellipse(320, 230, 60, 40, 30)}


def _frames(roi: Ellipse, n_frames: int, seed: int = 0) -> list[np.ndarray]:
    # Gentle motion that every tracker (spatial's grid included) follows.
    poses = similarity_path(n_frames, (roi.cx, roi.cy), scale_range=(0.85, 1.2), turns=0.25, radius_px=30.0)
    return list(synthetic_sequence(poses, roi, size=(640, 480), seed=seed))


def time_tracker(name: str, frames: list[np.ndarray], roi: Ellipse, *, repeats: int = 1, **params) -> float:
    """Median seconds per ``update()`` of tracker ``name`` over ``frames`` (after ``init`` on the first)."""
    times = []
    for _ in range(repeats):
        tracker = create_tracker(name, **params)
        tracker.init(frames[0], roi)
        for frame in frames[1:]:
            t0 = time.perf_counter()
            tracker.update(frame)
            times.append(time.perf_counter() - t0)
    return statistics.median(times)


def time_video_baselines(frames: list[np.ndarray], fps: float = 25.0) -> tuple[float, float]:
    """Seconds per frame to decode an mp4v video of ``frames``, and to decode it and re-encode it as mp4v."""
    h, w = frames[0].shape[:2]
    fourcc = cv2.VideoWriter_fourcc(*"mp4v")
    with tempfile.TemporaryDirectory(prefix="lptrack-speed-") as tmp:
        src, dst = os.path.join(tmp, "in.mp4"), os.path.join(tmp, "out.mp4")
        writer = cv2.VideoWriter(src, fourcc, fps, (w, h))
        for f in frames:
            writer.write(f)
        writer.release()

        cap = cv2.VideoCapture(src)
        t0 = time.perf_counter()
        n = 0
        while cap.read()[0]:
            n += 1
        decode = (time.perf_counter() - t0) / max(n, 1)
        cap.release()

        cap = cv2.VideoCapture(src)
        writer = cv2.VideoWriter(dst, fourcc, fps, (w, h))
        t0 = time.perf_counter()
        n = 0
        while True:
            ok, frame = cap.read()
            if not ok:
                break
            writer.write(frame)
            n += 1
        writer.release()
        both = (time.perf_counter() - t0) / max(n, 1)
        cap.release()
    return decode, both


def speed_table(trackers: list[str] | None = None, *, n_frames: int = 60, repeats: int = 1,
                threads: int = 1) -> tuple[list[dict], str]:
    """Measure each tracker's ms/frame on circle and ellipse next to the thesis' Table 4.1.

    Parameters
    ----------
    trackers : list of str, optional
        Registered names to time (default: every available tracker).
    n_frames : int
        Frames per synthetic 640x480 sequence.
    repeats : int
        Passes over the sequence per tracker (the median per-frame time is reported).
    threads : int
        ``cv2.setNumThreads`` during the measurement (1: one core, as the issue asks); restored afterwards.

    Returns
    -------
    rows : list of dict
        One per tracker and one per baseline: ``tracker``, ``circle_ms``, ``ellipse_ms``, ``circle_fps``,
        ``ellipse_fps``, ``thesis_circle_s``, ``thesis_ellipse_s`` (None when the thesis has no figure),
        ``speedup_circle``, ``speedup_ellipse`` (thesis time / ours).
    table : str
        The rows formatted as a Markdown table.
    """
    names = trackers or tracker_names()
    previous = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        frames = {shape: _frames(roi, n_frames) for shape, roi in SHAPES.items()}
        rows = []
        for name in names:
            ms = {shape: 1e3 * time_tracker(name, frames[shape], roi, repeats=repeats)
                  for shape, roi in SHAPES.items()}
            rows.append(_row(name, ms["circle"], ms["ellipse"], THESIS_SECONDS.get(name)))
        decode, both = time_video_baselines(frames["circle"])
        rows.append(_row("(decode only, mp4v)", 1e3 * decode, 1e3 * decode, None))
        rows.append(_row("(decode + encode, mp4v)", 1e3 * both, 1e3 * both, None))
    finally:
        cv2.setNumThreads(previous)
    return rows, format_table(rows)


def _row(name: str, circle_ms: float, ellipse_ms: float, thesis) -> dict:
    row = {"tracker": name, "circle_ms": circle_ms, "ellipse_ms": ellipse_ms,
           "circle_fps": 1e3 / circle_ms, "ellipse_fps": 1e3 / ellipse_ms,
           "thesis_circle_s": None, "thesis_ellipse_s": None, "speedup_circle": None, "speedup_ellipse": None}
    if thesis is not None:
        row.update(thesis_circle_s=thesis[0], thesis_ellipse_s=thesis[1],
                   speedup_circle=thesis[0] * 1e3 / circle_ms, speedup_ellipse=thesis[1] * 1e3 / ellipse_ms)
    return row


def format_table(rows: list[dict]) -> str:
    """Markdown table of :func:`speed_table`'s rows."""
    lines = ["| tracker | circle ms/frame (fps) | ellipse ms/frame (fps) | thesis circle / ellipse s/frame "
             "| speed-up circle / ellipse |",
             "|---|---|---|---|---|"]
    for r in rows:
        thesis = speedup = "-"
        if r["thesis_circle_s"] is not None:
            thesis = f"{r['thesis_circle_s']:g} / {r['thesis_ellipse_s']:g}"
            speedup = f"{r['speedup_circle']:,.0f}x / {r['speedup_ellipse']:,.0f}x"
        lines.append(f"| {r['tracker']} | {r['circle_ms']:.2f} ({r['circle_fps']:.0f}) "
                     f"| {r['ellipse_ms']:.2f} ({r['ellipse_fps']:.0f}) | {thesis} | {speedup} |")
    return "\n".join(lines)
