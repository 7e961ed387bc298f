"""What ``lptrack frame`` writes: one frame of a video as a PNG with a labelled pixel grid and a candidate ROI.

Before a run (headless OpenCV has no ``selectROI``) the user reads the object's pixel coordinates off this picture:
it keeps the frame's own size, so an image viewer's cursor position *is* the video coordinate (x right, y down,
origin top-left). The parts are elsewhere: the frame from :func:`~logpolar_track.video.read_frame`, the grid and
ROI from :func:`~logpolar_track.draw.draw_grid` and :func:`~logpolar_track.draw.draw_roi`, the file from
:func:`~logpolar_track.outputs.write_png`.
"""

from __future__ import annotations

from pathlib import Path

from .draw import draw_grid, draw_roi
from .geometry import Ellipse, as_ellipse, check_roi_fits
from .outputs import check_image_suffix, check_output_path, write_png
from .video import read_frame, video_stem


def default_frame_png(video_path, index: int, folder=".", roi: Ellipse | None = None) -> Path:
    """Default output of ``lptrack frame``: ``<video stem>.frame<index>.png`` in ``folder``; with a candidate
    ``roi`` drawn, ``<video stem>.frame<index>.roi_<cx>_<cy>_<r>.png`` (its spec, commas as underscores), so that
    trying one ROI after another neither collides with the plain frame nor with the ROIs tried before."""
    tag = "" if roi is None else ".roi_" + roi.to_spec().replace(",", "_")
    return Path(folder) / f"{video_stem(video_path)}.frame{int(index)}{tag}.png"


def write_frame_png(video_path, out_png=None, *, index: int | None = None, time_s: float | None = None,
                    grid: int = 50, roi: Ellipse | str | None = None, overwrite: bool = False,
                    fps: float | None = None) -> Path:
    """What ``lptrack frame`` does: frame ``index`` (or at ``time_s``) with a grid and an optional ROI, as PNG.

    Parameters
    ----------
    video_path : str or Path
    out_png : str or Path, optional
        Default :func:`default_frame_png` in the current folder.
    index, time_s, fps
        See :func:`~logpolar_track.video.read_frame`.
    grid : int
        Grid step in pixels (0: none).
    roi : Ellipse, str or sequence of float, optional
        Candidate ROI to draw (an :class:`~logpolar_track.geometry.Ellipse`, a ``--roi`` string or its numbers, as
        :func:`~logpolar_track.draw.draw_roi` takes it); checked against the frame as ``lptrack run`` checks it.
    overwrite : bool

    Returns
    -------
    Path
        The PNG written; same width and height as the frame.
    """
    roi = None if roi is None else as_ellipse(roi)
    frame = read_frame(video_path, index, time_s=time_s, fps=fps)
    out_png = default_frame_png(video_path, frame.index, roi=roi) if out_png is None else Path(out_png)
    check_image_suffix(out_png, (".png",), "output image")
    check_output_path(out_png, overwrite=overwrite, what="output image")
    image = frame.image
    if roi is not None:
        check_roi_fits(roi, frame.width, frame.height, source=f"'{frame.path.name}'")
    caption = f"{frame.width}x{frame.height} px  frame {frame.index}  t={frame.time_s:.3f} s"
    image = draw_grid(image, grid, caption=caption)
    if roi is not None:
        image = draw_roi(image, roi)
    return write_png(out_png, image, overwrite=overwrite)
