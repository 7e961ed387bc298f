"""Contact sheets: a grid of evenly spaced annotated frames of a run, as one PNG (``lptrack sheet``).

Pure OpenCV, one pass over the video. Each tile is a frame with the run's outline and axis line drawn as in the
annotated video (:func:`~logpolar_track.draw.draw_state`: green tracked, red lost), shrunk, over a label strip.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from .draw import LABEL_FONT, LOST_COLOUR, TRACKED_COLOUR, draw_state, put_label, signed
from .errors import UsageError, counted
from .evaluate import as_run_table
from .outputs import check_image_suffix, check_output_path, write_png
from .results import FrameResult
from .video import VideoReader, check_frame_number


def sheet_indices(n_rows: int, count: int) -> np.ndarray:
    """``count`` evenly spaced row indices from ``0`` to ``n_rows - 1`` (first and last included, unique)."""
    count = max(1, min(int(count), n_rows))
    return np.unique(np.round(np.linspace(0, n_rows - 1, count)).astype(int))


#: Rows of a contact sheet when neither ``rows`` nor ``count`` is given.
SHEET_ROWS = 3


def write_contact_sheet(video_path, run_csv_or_rows, out_png, *, cols: int = 4, rows: int | None = None,
                        count: int | None = None, width: int = 1600, overwrite: bool = False) -> Path:
    """Write a contact sheet: a grid of evenly spaced annotated frames of a run, as one PNG.

    Parameters
    ----------
    video_path : str or Path
        The tracked video.
    run_csv_or_rows : str, Path, RunTable or iterable of FrameResult
        The run: a run CSV path (checked against the contract) or the results themselves.
    out_png : str or Path
        PNG to write (atomically).
    cols : int
        Columns of tiles (as many as there are frames to show, when fewer).
    rows : int, optional
        Rows of tiles: ``cols * rows`` frames, evenly spaced over the run's rows, first and last included.
        Default :data:`SHEET_ROWS` (3), unless ``count`` is given.
    count : int, optional
        Instead of ``rows``: this many frames, in ``cols`` columns (rows as needed).
    width : int
        Width of the sheet in pixels; each tile is ``width // cols`` pixels wide, never wider than the video.
    overwrite : bool

    Returns
    -------
    Path
        The PNG written: ``cols * tile_w`` pixels wide, ``header + n_rows_used * (tile_h + label_h)`` high,
        where ``tile_h = round(tile_w * video_height / video_width)``; see :func:`sheet_geometry`.

    Raises
    ------
    UsageError
        Bad grid shape or width, both ``rows`` and ``count`` given (they are alternatives: either fixes the
        number of frames), or the run's frames are not in the video.
    GroundTruthError
        The CSV does not follow the contract.
    VideoError, OutputError

    Notes
    -----
    Each tile is the frame with the run's outline and axis line drawn as in the annotated video (green
    tracked, red lost), shrunk with area averaging, and a label strip below it: frame number, time, scale,
    rotation, score. The video is decoded once, from the start up to the last frame shown.
    """
    if rows is not None and count is not None:
        raise UsageError(f"give rows or count, not both: rows={rows} means {cols} x {rows} frames, count={count} "
                         f"means {count} frames in {cols} columns")
    rows = SHEET_ROWS if rows is None else rows
    for name, value in (("cols", cols), ("rows", rows), ("count", count), ("width", width)):
        if value is not None:
            check_frame_number(value, name, low=1)  # 2.5 columns were 2, True 1
    if width < 16 * cols:
        raise UsageError(f"sheet width {width} px is too small for {cols} columns (at least {16 * cols} px)")
    table = as_run_table(run_csv_or_rows)
    check_image_suffix(out_png, (".png",), "contact sheet")
    out_png = check_output_path(out_png, overwrite=overwrite, what="contact sheet")
    wanted = sheet_indices(len(table), count if count is not None else cols * rows)
    cols = min(cols, len(wanted))  # fewer frames than columns: no empty columns
    by_frame = {int(table.frames[i]): i for i in wanted}
    video_path = Path(video_path)
    tiles: dict[int, np.ndarray] = {}
    with VideoReader(video_path) as reader:
        geometry = sheet_geometry(reader.width, reader.height, cols, len(wanted), width)
        sheet_w, sheet_h = geometry["size"]
        if sheet_w * sheet_h > MAX_SHEET_PIXELS:
            # Refused before decoding: the tiles and the sheet are held in memory (--count 4096 --cols 1 on a 4K
            # run asked for 6 gigapixels, 18 GB each).
            raise UsageError(f"a sheet of {len(wanted)} frames in {counted(cols, 'column')} would be "
                             f"{sheet_w}x{sheet_h} px, over {MAX_SHEET_PIXELS / 1e6:g} megapixels; give more columns "
                             f"(--cols) or fewer frames (--count, --rows)")
        tile_w, tile_h = geometry["tile"]
        last = max(by_frame)
        for index, _, frame in reader:
            i = by_frame.get(index)
            if i is not None:
                tiles[i] = _tile(frame, table.result(i), tile_w, tile_h, geometry["label_h"])
            if index >= last:
                break
    missing = [int(table.frames[i]) for i in wanted if i not in tiles]
    if missing:
        raise UsageError(f"frame {missing[0]} of the run is not in '{video_path}' (it has fewer frames); "
                         f"is this the video the run was made from?")
    sheet = np.full((geometry["size"][1], geometry["size"][0], 3), 32, np.uint8)
    n_lost = int(table.lost.sum())
    put_label(sheet, f"{video_path.name}  {reader.width}x{reader.height}  run {table.source}: {len(table)} frames, "
                  f"{n_lost} lost  (showing {len(wanted)})", (0, 0), (255, 255, 255), scale=0.5, pad=6)
    cell_h = tile_h + geometry["label_h"]
    for k, i in enumerate(wanted):
        r, c = divmod(k, cols)
        y, x = geometry["header_h"] + r * cell_h, c * tile_w
        sheet[y:y + cell_h, x:x + tile_w] = tiles[i]
    return write_png(out_png, sheet, overwrite=overwrite, what="contact sheet")


#: The largest contact sheet made, in pixels (300 MB of BGR, as many again for its tiles).
MAX_SHEET_PIXELS = 100_000_000


def sheet_geometry(video_w: int, video_h: int, cols: int, n_frames: int, width: int = 1600) -> dict:
    """Pixel layout of a contact sheet: ``tile`` (w, h), ``label_h``, ``header_h`` and the sheet ``size`` (w, h)."""
    check_frame_number(cols, "cols", low=1)
    tile_w = max(16, min(int(width) // int(cols), int(video_w)))
    tile_h = max(1, int(round(tile_w * video_h / video_w)))
    label_h = 18
    header_h = 28
    n_rows = math.ceil(n_frames / cols)
    return {"tile": (tile_w, tile_h), "label_h": label_h, "header_h": header_h,
            "size": (cols * tile_w, header_h + n_rows * (tile_h + label_h))}


def _tile(frame: np.ndarray, result: FrameResult, tile_w: int, tile_h: int, label_h: int) -> np.ndarray:
    """One sheet cell: the annotated frame shrunk to ``tile_w`` x ``tile_h`` over a label strip."""
    shrink = frame.shape[1] / tile_w
    # Lines drawn `shrink` pixels thick stay about one pixel thick once shrunk.
    thickness = max(1, int(round(shrink)))
    annotated = draw_state(frame, result.state, status=result.status, thickness=thickness, text=False)
    small = cv2.resize(annotated, (tile_w, tile_h), interpolation=cv2.INTER_AREA)
    cell = np.full((tile_h + label_h, tile_w, 3), 32, np.uint8)
    cell[:tile_h] = small
    cell[:tile_h, -1] = 32  # a dark 1-px gutter between tiles
    colour = LOST_COLOUR if result.status == "lost" else TRACKED_COLOUR
    s = result.state
    rot = "" if s.rotation_deg is None else f" r{signed(s.rotation_deg, 0)}"
    text = f"frame {result.frame} {result.time_s:.2f}s x{s.scale:.2f}{rot} {s.score:.2f}"
    if result.status == "lost":
        text += " LOST"
    scale = 0.4
    while scale > 0.25 and cv2.getTextSize(text, LABEL_FONT, scale, 1)[0][0] > tile_w - 4:
        scale -= 0.025
    cv2.putText(cell, text, (2, tile_h + label_h - 5), LABEL_FONT, scale, colour, 1, cv2.LINE_AA)
    return cell
