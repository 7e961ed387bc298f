"""The thesis' spatial-domain baseline: masked normalised cross-correlation over a grid of scales and angles.

Where the log-polar trackers read scale and rotation off one phase correlation, this tracker tries them:
the first frame's region is warped to every candidate (scale, angle) of a small grid around the current
estimate, and each warped template is matched with :func:`cv2.matchTemplate` (``TM_CCOEFF_NORMED`` under an
elliptical mask) at every centre of a ``window`` x ``window`` pixel neighbourhood. The best of the
``n_scales * n_angles * window**2`` scores wins, refined to sub-step precision by parabolas through its
neighbours along scale, angle and position.

Limits: per frame it can follow at most ``(n_scales // 2)`` scale steps and ``(n_angles // 2)`` angle steps
(by default 4 % and 4 degrees) and ``window // 2`` pixels; faster motion is lost. Its cost grows with the
grid size and the template area, which is why the thesis found it an order of magnitude slower than the
log-polar trackers.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from ..errors import UsageError
from ..geometry import Ellipse
from ..logpolar import parabola_peak_2d
from .base import MAX_WINDOW, Similarity, SimilarityTracker, check_ranges, register


@register
class SpatialTracker(SimilarityTracker):
    """Exhaustive spatial template matching over angles x scales x centres (thesis baseline).

    Parameters
    ----------
    window : int
        Side in pixels of the square of candidate centres around the last position (odd, >= 3).
    n_scales, n_angles : int
        Number of candidate scale factors and angles (odd, >= 1), centred on the current estimate.
    scale_step : float
        Relative step between candidate scales (0.02: 2 %); candidates are ``(1 + scale_step) ** k``.
    angle_step_deg : float
        Step between candidate angles in degrees (counter-clockwise on screen).
    lost_threshold : float
        Frames whose best normalised cross-correlation is below this are reported lost.
    """

    name = "spatial"
    summary = "spatial baseline: masked NCC template matching over a 5x5 grid of scales x angles and a window"

    def __init__(self, *, window: int = 11, n_scales: int = 5, n_angles: int = 5, scale_step: float = 0.02,
                 angle_step_deg: float = 2.0, lost_threshold: float = 0.5):
        super().__init__(lost_threshold=lost_threshold)
        self.window, self.n_scales, self.n_angles = int(window), int(n_scales), int(n_angles)
        self.scale_step, self.angle_step_deg = float(scale_step), float(angle_step_deg)
        check_ranges(self, {"window": (3, MAX_WINDOW), "n_scales": (1, 31), "n_angles": (1, 31),
                            "scale_step": (0.0, 0.5), "angle_step_deg": (0.0, 45.0), "lost_threshold": (0.0, 1.0)},
                     positive={"scale_step", "angle_step_deg"}, odd={"window", "n_scales", "n_angles"})
        # The grid's far corners: templates scaled beyond half to double size, or turned past a half turn, are
        # no longer a local search (and a 31-scale grid of 50 % steps made templates 438 times the ROI).
        span = (1 + self.scale_step) ** (self.n_scales // 2)
        if span > 2.0 or self.angle_step_deg * (self.n_angles // 2) > 180.0:
            raise UsageError(f"{self.name}: the grid must span at most half to double size and a half turn either "
                             f"way; (1 + scale_step)^(n_scales // 2) is {span:.3g} and angle_step_deg x "
                             f"(n_angles // 2) is {self.angle_step_deg * (self.n_angles // 2):g}")
        self.log_scale_step = math.log1p(self.scale_step)

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        self.first = gray

    def template(self, scale: float, rotation_deg: float) -> tuple[np.ndarray, np.ndarray]:
        """The first frame's region as it would look at ``scale`` and turned ``rotation_deg`` CCW, and its mask.

        Returns a square float32 patch of odd side ``2h + 1`` with the object's centre at pixel ``(h, h)``, and
        a float32 mask (1 inside the ellipse, 0 outside) of the same shape.
        """
        roi = self.roi
        h = int(math.ceil(scale * roi.radius)) + 1
        # getRotationMatrix2D: positive angle turns counter-clockwise on screen, as our rotation does.
        m = cv2.getRotationMatrix2D((roi.cx, roi.cy), rotation_deg, scale)
        m[0, 2] += h - roi.cx
        m[1, 2] += h - roi.cy
        patch = cv2.warpAffine(self.first, m, (2 * h + 1, 2 * h + 1), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REPLICATE)
        ys, xs = np.mgrid[0:2 * h + 1, 0:2 * h + 1]
        mask = roi.moved(h, h, scale, rotation_deg).contains(xs, ys).astype(np.float32)
        return patch, mask

    def scores(self, gray: np.ndarray, cx: float, cy: float, scale: float, rotation_deg: float):
        """Masked NCC of every candidate, shape ``(n_scales, n_angles, window, window)``.

        Returns the scores, the integer centre ``(x, y)`` they are relative to (cell ``[..., r, c]`` is the
        centre ``(x + c - window // 2, y + r - window // 2)``), the candidate log-scales and rotations.
        """
        half = self.window // 2
        x0, y0 = int(round(cx)), int(round(cy))
        ks = np.arange(self.n_scales) - self.n_scales // 2
        js = np.arange(self.n_angles) - self.n_angles // 2
        log_scales = math.log(scale) + ks * self.log_scale_step
        rotations = rotation_deg + js * self.angle_step_deg
        h_max = int(math.ceil(math.exp(log_scales[-1]) * self.roi.radius)) + 1
        side = 2 * (h_max + half) + 1
        # Integer centre and odd size: getRectSubPix copies pixels without interpolating, replicating borders.
        search = cv2.getRectSubPix(gray, (side, side), (float(x0), float(y0)))
        out = np.empty((self.n_scales, self.n_angles, self.window, self.window), np.float32)
        for i, log_s in enumerate(log_scales):
            for j, rot in enumerate(rotations):
                patch, mask = self.template(math.exp(log_s), float(rot))
                h = patch.shape[0] // 2
                lo = h_max - h
                region = search[lo:side - lo, lo:side - lo]
                out[i, j] = cv2.matchTemplate(region, patch, cv2.TM_CCOEFF_NORMED, mask=mask)
        # Flat regions give 0/0: treat them as no match.
        np.nan_to_num(out, copy=False, nan=0.0, posinf=0.0, neginf=0.0)
        return out, (x0, y0), log_scales, rotations

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        out, (x0, y0), log_scales, rotations = self.scores(gray, last.cx, last.cy, last.scale, last.rotation_deg)
        i, j, r, c = np.unravel_index(int(np.argmax(out)), out.shape)
        # Sub-step refinement: parabolas across scale x angle at the best centre, and across the centres of
        # the best template.
        si, sj, best = parabola_peak_2d(out[:, :, r, c])
        row, col, _ = parabola_peak_2d(out[i, j])
        half = self.window // 2
        log_scale = log_scales[0] + si * self.log_scale_step
        rotation = rotations[0] + sj * self.angle_step_deg
        return Similarity(x0 + col - half, y0 + row - half, math.exp(log_scale), float(rotation),
                          float(np.clip(best, 0.0, 1.0)))
