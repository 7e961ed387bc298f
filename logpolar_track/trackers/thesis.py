"""The thesis' log-polar trackers: fixed template, difference decomposition, template update, two-template.

All four sample the frame in log-polar coordinates at the current scale and angle and phase-correlate the
result with a template sampled on the first frame: the peak's shift gives the change of scale and rotation,
its height the match score. They differ in how they find the centre and which templates they keep.

Centres are searched on an integer grid of ``window`` x ``window`` pixels around the last position; the best
cell is refined to sub-pixel precision with a parabola through its neighbours' scores, and the object is
re-sampled there once more to refine scale and rotation to sub-bin precision.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import Ellipse
from ..logpolar import LogPolarGrid, PhaseCorrelator, Peak, find_peaks, parabola_peak_2d
from .base import Similarity, SimilarityTracker, register


class LogPolarMatcher:
    """One log-polar template: its grid, its correlator and the template's spectrum.

    Parameters
    ----------
    a, b : float
        Semi-axes in pixels of the sampled ellipse at scale 1.
    n_rho, n_theta : int
        Log-polar image size.
    """

    def __init__(self, a: float, b: float, *, n_rho: int, n_theta: int):
        self.grid = LogPolarGrid(a, b, n_rho=n_rho, n_theta=n_theta)
        self.correlator = PhaseCorrelator((n_rho, n_theta))
        self.template: np.ndarray | None = None

    def spectra(self, gray: np.ndarray, centres: np.ndarray, scale: float, angle_deg: float) -> np.ndarray:
        """Spectra of the log-polar images at ``centres`` (N, 2) for the given scale and axis angle."""
        return self.correlator.spectrum(self.grid.sample(gray, centres, scale, angle_deg))

    def match(self, spectra: np.ndarray, template: np.ndarray | None = None) -> Peak:
        """Peaks of ``spectra`` correlated against ``template`` (default: the stored one)."""
        ref = self.template if template is None else template
        return find_peaks(self.correlator.correlate(ref, spectra))

    def to_change(self, peak: Peak, index) -> tuple[float, float]:
        """(scale factor, rotation in degrees CCW) that peak ``index`` stands for."""
        return (math.exp(float(peak.d_rho[index]) * self.grid.log_step),
                float(peak.d_theta[index]) * self.grid.degrees_per_bin)


def window_offsets(window: int) -> np.ndarray:
    """Integer pixel offsets ``(dx, dy)`` of a ``window`` x ``window`` grid, row-major, shape (window**2, 2)."""
    half = window // 2
    ys, xs = np.mgrid[-half:half + 1, -half:half + 1]
    return np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float32)


def rotate_screen(vectors: np.ndarray, angle_deg: float) -> np.ndarray:
    """Pixel vectors ``(N, 2)`` (y down) turned ``angle_deg`` counter-clockwise as seen on screen."""
    t = math.radians(angle_deg)
    c, s = math.cos(t), math.sin(t)
    x, y = vectors[:, 0], vectors[:, 1]
    return np.stack([x * c + y * s, -x * s + y * c], axis=1)


class _WindowSearch(SimilarityTracker):
    """Shared machinery: exhaustive centre search in a window, then one re-sampling to refine."""

    def __init__(self, *, window: int = 11, n_rho: int = 64, n_theta: int = 128, lost_threshold: float = 0.2):
        super().__init__(lost_threshold=lost_threshold)
        if window < 3 or window % 2 == 0:
            raise ValueError(f"window must be an odd number >= 3 pixels, got {window}")
        self.window = int(window)
        self.n_rho, self.n_theta = int(n_rho), int(n_theta)
        self.offsets = window_offsets(self.window)

    def _angle(self, sim: Similarity) -> float:
        return self.roi.angle_deg + sim.rotation_deg

    def _refine(self, matcher: LogPolarMatcher, gray, cx, cy, scale, rotation, template=None) -> Similarity:
        """Re-sample at the found centre with the found scale/angle and correct by the residual shift."""
        angle = self.roi.angle_deg + rotation
        peak = matcher.match(matcher.spectra(gray, np.array([[cx, cy]]), scale, angle), template)
        ds, dr = matcher.to_change(peak, 0)
        return Similarity(cx, cy, scale * ds, rotation + dr, float(peak.height[0]))

    def _best_cell(self, heights: np.ndarray) -> tuple[int, np.ndarray]:
        """Index of the best candidate and its sub-pixel offset ``(dx, dy)`` from the parabola fit."""
        grid = heights.reshape(self.window, self.window)
        row, col, _ = parabola_peak_2d(grid)
        best = int(np.argmax(heights))
        half = self.window // 2
        return best, np.array([col - half, row - half], dtype=np.float64)


@register
class FixedTemplateTracker(_WindowSearch):
    """Fixed template, exhaustive centre search (thesis)."""

    name = "fixed"
    summary = "fixed first-frame template; log-polar phase correlation at every centre of a window"

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        self.matcher = LogPolarMatcher(roi.a, roi.b, n_rho=self.n_rho, n_theta=self.n_theta)
        self.matcher.template = self.matcher.spectra(gray, np.array([[roi.cx, roi.cy]]), 1.0, roi.angle_deg)

    def _search(self, gray, last: Similarity, template=None) -> Similarity:
        centres = np.array([last.cx, last.cy], np.float32) + self.offsets
        peak = self.matcher.match(self.matcher.spectra(gray, centres, last.scale, self._angle(last)), template)
        best, offset = self._best_cell(peak.height)
        ds, dr = self.matcher.to_change(peak, best)
        return self._refine(self.matcher, gray, last.cx + offset[0], last.cy + offset[1],
                            last.scale * ds, last.rotation_deg + dr, template)

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        return self._search(gray, last)


@register
class DifferenceDecompositionTracker(_WindowSearch):
    """Difference decomposition: templates precomputed at every shifted centre (thesis)."""

    name = "diffdecomp"
    summary = "difference decomposition: one log-polar sample per frame against precomputed shifted templates"

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        self.matcher = LogPolarMatcher(roi.a, roi.b, n_rho=self.n_rho, n_theta=self.n_theta)
        centres = np.array([roi.cx, roi.cy], np.float32) + self.offsets
        self.shifted_templates = self.matcher.spectra(gray, centres, 1.0, roi.angle_deg)
        self.matcher.template = self.shifted_templates[len(self.offsets) // 2]

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        current = self.matcher.spectra(gray, np.array([[last.cx, last.cy]]), last.scale, self._angle(last))
        peak = self.matcher.match(current, self.shifted_templates)
        best, offset = self._best_cell(peak.height)
        # The current sample looks like the template sampled `offset` away from the object's centre, in the
        # object's own frame at scale 1: the object is that offset back, scaled and turned into the image.
        motion = -rotate_screen(offset[None, :], last.rotation_deg)[0] * last.scale
        ds, dr = self.matcher.to_change(peak, best)
        return self._refine(self.matcher, gray, last.cx + motion[0], last.cy + motion[1],
                            last.scale * ds, last.rotation_deg + dr)


@register
class TemplateUpdateTracker(FixedTemplateTracker):
    """Template update under a threshold (thesis)."""

    name = "update"
    summary = "fixed search against the first and the current template; current one renewed when trustworthy"

    def __init__(self, *, update_threshold: float = 0.35, **kwargs):
        super().__init__(**kwargs)
        self.update_threshold = float(update_threshold)

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        super()._start(gray, roi)
        self.current_template = self.matcher.template
        self._gray = gray

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        self._gray = gray
        from_initial = self._search(gray, last)
        from_current = self._search(gray, last, self.current_template)
        self._initial_score = from_initial.score
        return from_initial if from_initial.score >= from_current.score else from_current

    def _accept(self, estimate: Similarity) -> None:
        # Renew only when the anchor (first template) still agrees: this is what keeps it from drifting.
        if self._initial_score >= self.update_threshold:
            self.current_template = self.matcher.spectra(
                self._gray, np.array([[estimate.cx, estimate.cy]]), estimate.scale, self._angle(estimate))


@register
class TwoTemplateTracker(_WindowSearch):
    """Two concentric templates, the inner one weighted more, for occlusion from the border (thesis)."""

    name = "occlusion"
    summary = "inner and outer concentric templates, inner weighted more; tolerates occlusion from the border"

    def __init__(self, *, inner_ratio: float = 0.6, inner_weight: float = 0.7, **kwargs):
        super().__init__(**kwargs)
        if not 0 < inner_ratio < 1 or not 0 <= inner_weight <= 1:
            raise ValueError("inner_ratio must be in (0, 1) and inner_weight in [0, 1]")
        self.inner_ratio, self.inner_weight = float(inner_ratio), float(inner_weight)

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        centre = np.array([[roi.cx, roi.cy]])
        self.outer = LogPolarMatcher(roi.a, roi.b, n_rho=self.n_rho, n_theta=self.n_theta)
        self.inner = LogPolarMatcher(roi.a * self.inner_ratio, roi.b * self.inner_ratio,
                                     n_rho=self.n_rho, n_theta=self.n_theta)
        for m in (self.outer, self.inner):
            m.template = m.spectra(gray, centre, 1.0, roi.angle_deg)

    def _combine(self, gray, centres, scale, angle):
        peaks = [m.match(m.spectra(gray, centres, scale, angle)) for m in (self.inner, self.outer)]
        weights = (self.inner_weight, 1.0 - self.inner_weight)
        heights = weights[0] * peaks[0].height + weights[1] * peaks[1].height
        return peaks, weights, heights

    def _change(self, peaks, weights, index) -> tuple[float, float]:
        """Scale and rotation as the score-weighted mean of the two templates' estimates."""
        w = np.array([weights[i] * float(peaks[i].height[index]) for i in range(2)]) + 1e-9
        changes = [m.to_change(p, index) for m, p in zip((self.inner, self.outer), peaks)]
        log_scale = sum(wi * math.log(c[0]) for wi, c in zip(w, changes)) / w.sum()
        rotation = sum(wi * c[1] for wi, c in zip(w, changes)) / w.sum()
        return math.exp(log_scale), rotation

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        centres = np.array([last.cx, last.cy], np.float32) + self.offsets
        peaks, weights, heights = self._combine(gray, centres, last.scale, self._angle(last))
        best, offset = self._best_cell(heights)
        ds, dr = self._change(peaks, weights, best)
        cx, cy = last.cx + offset[0], last.cy + offset[1]
        scale, rotation = last.scale * ds, last.rotation_deg + dr
        peaks, weights, heights = self._combine(gray, np.array([[cx, cy]]), scale, self.roi.angle_deg + rotation)
        ds, dr = self._change(peaks, weights, 0)
        return Similarity(cx, cy, scale * ds, rotation + dr, float(heights[0]))
