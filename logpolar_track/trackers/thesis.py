"""The thesis' log-polar trackers: fixed template, difference decomposition, template update, two-template.

All four sample the frame in log-polar coordinates at the current scale and angle and phase-correlate the
result with a template sampled on the first frame: the peak's shift gives the change of scale and rotation,
its height the match score. They differ in how they find the centre and which templates they keep.

Centres are searched on an integer grid of ``window`` x ``window`` pixels around the last position; the best
cell is refined to sub-pixel precision with a parabola through its neighbours' scores, and the object is
re-sampled there once more to refine scale and rotation to sub-bin precision.

Speed (``coarse=True``, the default): the window is first scored with a log-polar grid of half the size in
each direction (a quarter of the samples and FFT work a centre), at half of its centres (a checkerboard) and
then at the skipped centres beside the best few; the full-size heights are then computed only around the
coarse winner, climbing to the best neighbour until the cell beats all eight of its neighbours. That is the
exhaustive full-size search's answer whenever its maximum is reachable uphill from the coarse maximum (a
single peak over the window, the normal case); ``coarse=False`` runs the exhaustive search, kept as the
reference the tests compare against.
"""

from __future__ import annotations

import math
from abc import abstractmethod

import numpy as np

from ..errors import UsageError
from ..geometry import Ellipse, rotate_screen, wrap_degrees
from ..logpolar import LogPolarGrid, PhaseCorrelator, Peak, find_peaks, parabola_peak_2d
from .base import MAX_WINDOW, Similarity, SimilarityTracker, check_ranges, register


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


#: Most samples the search may take from one frame (window centres x log-polar samples): the defaults take about
#: 1 million (121 x 64 x 128), and sampling maps of this many float32 take 256 MB each.
MAX_SEARCH_SAMPLES = 1 << 26
#: How many of the best checkerboard cells have their other neighbours scored too in the coarse stage
#: (``_WindowSearch._coarse_starts``). With 5 the bundled samples' results are those of scoring every cell; the
#: checkerboard alone lost ``diffdecomp`` on ``clutter`` (100 -> 58 % success), and 3 lost ``update`` on
#: ``occlusion`` (74 -> 29 %).
COARSE_TOP = 5


def window_offsets(window: int) -> np.ndarray:
    """Integer pixel offsets ``(dx, dy)`` of a ``window`` x ``window`` grid, row-major, shape (window**2, 2)."""
    half = window // 2
    ys, xs = np.mgrid[-half:half + 1, -half:half + 1]
    return np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float32)


class _CellSpectra:
    """Full-size spectra of a window's cells, computed on demand in batches and remembered for this frame."""

    def __init__(self, matcher: LogPolarMatcher, gray, centres, scale, angle_deg):
        self.matcher, self.gray, self.centres = matcher, gray, centres
        self.scale, self.angle = scale, angle_deg
        self.cache: dict[int, np.ndarray] = {}

    def get(self, indices: np.ndarray) -> np.ndarray:
        missing = [int(i) for i in indices if int(i) not in self.cache]
        if missing:
            spectra = self.matcher.spectra(self.gray, self.centres[missing], self.scale, self.angle)
            self.cache.update(zip(missing, spectra))
        return np.stack([self.cache[int(i)] for i in indices])


def take(peak: Peak, index: int) -> Peak:
    """The single peak ``index`` of a batch, as a batch of one."""
    return Peak(peak.d_rho[index:index + 1], peak.d_theta[index:index + 1], peak.height[index:index + 1])


class _WindowSearch(SimilarityTracker):
    """Shared machinery: centre search in a window (coarse-to-fine or exhaustive), then one re-sampling.

    Parameters
    ----------
    window : int
        Side in pixels of the square of candidate centres around the last position (odd, >= 3).
    n_rho, n_theta : int
        Log-polar image size (rings x directions) of the full-size templates.
    lost_threshold : float
        Frames whose match height (0 to 1) is below this are reported lost. The default, 0.2, lies on the noise
        floor: an unrelated texture in the object's place scores 0.11-0.23, a look-alike more, and a half-covered
        object as little as 0.12, so no value separates them (README: the thesis trackers' `lost` status).
    coarse : bool
        Score the window on a half-size grid first and compute full-size heights only while climbing from the
        coarse winner (fast); False runs the exhaustive full-size search (the reference).
    """

    def __init__(self, *, window: int = 11, n_rho: int = 64, n_theta: int = 128, lost_threshold: float = 0.2,
                 coarse: bool = True):
        super().__init__(lost_threshold=lost_threshold)
        self.window = int(window)
        self.n_rho, self.n_theta = int(n_rho), int(n_theta)
        check_ranges(self, {"window": (3, MAX_WINDOW), "n_rho": (8, 512), "n_theta": (16, 1024),
                            "lost_threshold": (0.0, 1.0)}, odd={"window"})
        # Each parameter in range can still combine into gigabytes of sampling maps.
        samples = self.window ** 2 * self.n_rho * self.n_theta
        if samples > MAX_SEARCH_SAMPLES:
            raise UsageError(f"{self.name}: window^2 x n_rho x n_theta ({self.window}^2 x {self.n_rho} x "
                             f"{self.n_theta}) come to {samples:,} samples a frame, more than the "
                             f"{MAX_SEARCH_SAMPLES:,} allowed (256 MB a float32 sampling map); choose smaller ones")
        self.offsets = window_offsets(self.window)
        self.coarse = bool(coarse)
        #: Cells the coarse stage scores first: a checkerboard (``dx + dy`` even, the window's centre among them).
        self.coarse_cells = np.flatnonzero(self.offsets.sum(axis=1) % 2 == 0)
        n = self.window
        rows, cols = np.divmod(np.arange(n * n), n)
        neighbours = []
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            r, c = rows + dr, cols + dc
            neighbours.append(np.where((0 <= r) & (r < n) & (0 <= c) & (c < n), r * n + c, -1))
        #: Each cell's four neighbours along the axes, shape ``(cells, 4)`` (-1 outside the window).
        self.cell_neighbours = np.stack(neighbours, axis=1)

    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        found = self._locate(gray, last)
        # The search and the re-sampling each read a turn within half a turn, so together up to a whole turn in
        # one frame (a 180-degree symmetric object read -178 twice, 356 degrees, for a 2-degree turn): the pose is
        # the same with the frame's turn taken within half a turn, which keeps the cumulative rotation continuous.
        turn = wrap_degrees(found.rotation_deg - last.rotation_deg)
        return Similarity(found.cx, found.cy, found.scale, last.rotation_deg + turn, found.score)

    @abstractmethod
    def _locate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        """The frame's estimate, from the last good one (its turn is taken within half a turn afterwards)."""

    def _matchers(self, a: float, b: float) -> tuple[LogPolarMatcher, LogPolarMatcher | None]:
        """Full-size matcher, and the half-size one used to score the window when ``coarse`` is on."""
        full = LogPolarMatcher(a, b, n_rho=self.n_rho, n_theta=self.n_theta)
        if not self.coarse:
            return full, None
        return full, LogPolarMatcher(a, b, n_rho=max(8, self.n_rho // 2), n_theta=max(16, self.n_theta // 2))

    def _coarse_starts(self, score) -> np.ndarray:
        """The coarse stage: the cell each template's full-size climb starts from.

        ``score(indices)`` returns the coarse heights of those cells, shape ``(templates, len(indices))``. The
        checkerboard :attr:`coarse_cells` are scored first, then the cells beside the best ``COARSE_TOP`` of
        them that the checkerboard skips: about half the coarse work of scoring every cell, with the same
        winner unless that lies on a skipped cell beside none of those best ones.
        """
        cells = self.coarse_cells
        heights = np.reshape(score(cells), (-1, len(cells)))
        best = cells[np.argsort(heights, axis=1)[:, -COARSE_TOP:]]
        extra = np.setdiff1d(self.cell_neighbours[best].ravel(), [-1])
        if len(extra):
            cells = np.concatenate([cells, extra])
            heights = np.hstack([heights, np.reshape(score(extra), (-1, len(extra)))])
        return cells[np.argmax(heights, axis=1)]

    def _climb(self, start: int, evaluate) -> tuple[int, np.ndarray]:
        """Hill-climb full-size heights from cell ``start``; returns the best cell and its sub-pixel offset.

        ``evaluate(indices)`` returns the heights of those cells. The climb moves to the best of the current
        cell's (up to) eight neighbours until none is higher, so the cell it stops on is the highest of all
        cells evaluated, and its four neighbours are known for the parabola fit.
        """
        n = self.window
        grid = np.full((n, n), -np.inf)
        current = int(start)
        while True:
            r, c = divmod(current, n)
            rows = np.arange(max(r - 1, 0), min(r + 2, n))
            cols = np.arange(max(c - 1, 0), min(c + 2, n))
            cells = (rows[:, None] * n + cols[None, :]).ravel()
            todo = cells[np.isneginf(grid.ravel()[cells])]
            if len(todo):
                grid.ravel()[todo] = evaluate(todo)
            best = int(cells[np.argmax(grid.ravel()[cells])])
            if best == current or grid.ravel()[best] <= grid.ravel()[current]:
                break
            current = best
        return current, self._offset(grid)

    def _offset(self, grid: np.ndarray) -> np.ndarray:
        """Sub-pixel offset ``(dx, dy)`` from the window's centre of the best cell of ``grid`` ``(window, window)``
        (parabolas through its neighbours)."""
        row, col, _ = parabola_peak_2d(grid)
        half = self.window // 2
        return np.array([col - half, row - half], dtype=np.float64)

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
        return int(np.argmax(heights)), self._offset(heights.reshape(self.window, self.window))


@register
class FixedTemplateTracker(_WindowSearch):
    """Fixed template, centre search over a window (the thesis' exhaustive search; coarse-to-fine by default)."""

    name = "fixed"
    summary = "fixed first-frame template; log-polar phase correlation over a window of centres"

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        self.matcher, self.coarse_matcher = self._matchers(roi.a, roi.b)
        centre = np.array([[roi.cx, roi.cy]])
        for m in (self.matcher, self.coarse_matcher):
            if m is not None:
                m.template = m.spectra(gray, centre, 1.0, roi.angle_deg)

    def _search(self, gray, last: Similarity, template=None) -> Similarity:
        """Exhaustive full-size search of the window against ``template`` (default: the first frame's)."""
        centres = np.array([last.cx, last.cy], np.float32) + self.offsets
        peak = self.matcher.match(self.matcher.spectra(gray, centres, last.scale, self._angle(last)), template)
        best, offset = self._best_cell(peak.height)
        return self._finish(gray, last, take(peak, best), offset, template)

    def _finish(self, gray, last: Similarity, peak: Peak, offset, template=None) -> Similarity:
        ds, dr = self.matcher.to_change(peak, 0)
        return self._refine(self.matcher, gray, last.cx + offset[0], last.cy + offset[1],
                            last.scale * ds, last.rotation_deg + dr, template)

    def _coarse_to_fine(self, gray, last: Similarity, pairs) -> list[Similarity]:
        """Window search for each ``(full template, coarse template)`` of ``pairs``, sharing the samples."""
        centres = np.array([last.cx, last.cy], np.float32) + self.offsets
        scale, angle = last.scale, self._angle(last)
        coarse_refs = np.stack([c for _, c in pairs])[:, None]
        starts = self._coarse_starts(lambda cells: self.coarse_matcher.match(
            self.coarse_matcher.spectra(gray, centres[cells], scale, angle)[None], coarse_refs).height)
        cells = _CellSpectra(self.matcher, gray, centres, scale, angle)
        results = []
        for (template, _), start in zip(pairs, starts):
            peaks: dict[int, Peak] = {}

            def evaluate(indices, template=template, peaks=peaks):
                peak = self.matcher.match(cells.get(indices), template)
                peaks.update((int(i), take(peak, n)) for n, i in enumerate(indices))
                return peak.height

            best, offset = self._climb(int(start), evaluate)
            results.append(self._finish(gray, last, peaks[best], offset, template))
        return results

    def _locate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        if not self.coarse:
            return self._search(gray, last)
        return self._coarse_to_fine(gray, last, [(self.matcher.template, self.coarse_matcher.template)])[0]


@register
class DifferenceDecompositionTracker(_WindowSearch):
    """Difference decomposition: templates precomputed at every shifted centre (thesis)."""

    name = "diffdecomp"
    summary = "difference decomposition: one log-polar sample per frame against precomputed shifted templates"

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        self.matcher, self.coarse_matcher = self._matchers(roi.a, roi.b)
        centres = np.array([roi.cx, roi.cy], np.float32) + self.offsets
        self.shifted_templates = self.matcher.spectra(gray, centres, 1.0, roi.angle_deg)
        self.matcher.template = self.shifted_templates[len(self.offsets) // 2]
        if self.coarse_matcher is not None:
            self.coarse_shifted = self.coarse_matcher.spectra(gray, centres, 1.0, roi.angle_deg)

    def _locate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        centre = np.array([[last.cx, last.cy]])
        current = self.matcher.spectra(gray, centre, last.scale, self._angle(last))
        if self.coarse:
            coarse = self.coarse_matcher.spectra(gray, centre, last.scale, self._angle(last))
            start = self._coarse_starts(
                lambda cells: self.coarse_matcher.match(coarse, self.coarse_shifted[cells]).height)[0]
            peaks: dict[int, Peak] = {}

            def evaluate(indices):
                peak = self.matcher.match(current, self.shifted_templates[indices])
                peaks.update((int(i), take(peak, n)) for n, i in enumerate(indices))
                return peak.height

            best, offset = self._climb(int(start), evaluate)
            peak = peaks[best]
        else:
            peak = self.matcher.match(current, self.shifted_templates)
            best, offset = self._best_cell(peak.height)
            peak = take(peak, best)
        # The current sample looks like the template sampled `offset` away from the object's centre, in the
        # object's own frame at scale 1: the object is that offset back, scaled and turned into the image.
        motion = -rotate_screen(offset, last.rotation_deg) * last.scale
        ds, dr = self.matcher.to_change(peak, 0)
        return self._refine(self.matcher, gray, last.cx + motion[0], last.cy + motion[1],
                            last.scale * ds, last.rotation_deg + dr)


@register
class TemplateUpdateTracker(FixedTemplateTracker):
    """Template update under a threshold (thesis).

    Parameters
    ----------
    update_threshold : float
        Match height (0 to 1) of the first template above which the current template is renewed from the
        frame, where the first template's own estimate is the accepted one (within a pixel, a ring and a
        direction of the log-polar grid); otherwise the first template no longer vouches for the estimate.
    **kwargs
        ``window``, ``n_rho``, ``n_theta``, ``lost_threshold``, ``coarse``: as for ``fixed``.
    """

    name = "update"
    summary = "fixed search against the first and the current template; current one renewed when trustworthy"

    def __init__(self, *, update_threshold: float = 0.35, **kwargs):
        super().__init__(**kwargs)
        self.update_threshold = float(update_threshold)
        check_ranges(self, {"update_threshold": (0.0, 1.0)})

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        super()._start(gray, roi)
        self.current_template = self.matcher.template
        self.coarse_current = None if self.coarse_matcher is None else self.coarse_matcher.template
        self._gray = gray

    def _locate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        self._gray = gray
        if self.coarse:
            # Both templates are searched on the same samples: one coarse batch, shared full-size cells.
            from_initial, from_current = self._coarse_to_fine(
                gray, last, [(self.matcher.template, self.coarse_matcher.template),
                             (self.current_template, self.coarse_current)])
        else:
            from_initial = self._search(gray, last)
            from_current = self._search(gray, last, self.current_template)
        self._from_initial = from_initial
        return from_initial if from_initial.score >= from_current.score else from_current

    def _accept(self, estimate: Similarity) -> None:
        # Renew only when the anchor (first template) vouches for the estimate -- matches above the threshold,
        # and there: this is what keeps the current template from drifting.
        anchor = self._from_initial
        grid = self.matcher.grid
        if (anchor.score >= self.update_threshold
                and math.hypot(anchor.cx - estimate.cx, anchor.cy - estimate.cy) <= 1.0
                and abs(math.log(anchor.scale / estimate.scale)) <= grid.log_step
                and abs(wrap_degrees(anchor.rotation_deg - estimate.rotation_deg)) <= grid.degrees_per_bin):
            centre = np.array([[estimate.cx, estimate.cy]])
            self.current_template = self.matcher.spectra(self._gray, centre, estimate.scale, self._angle(estimate))
            if self.coarse_matcher is not None:
                self.coarse_current = self.coarse_matcher.spectra(self._gray, centre, estimate.scale,
                                                                  self._angle(estimate))


@register
class TwoTemplateTracker(_WindowSearch):
    """Two concentric templates, the inner one weighted more: the thesis' design for occlusion from the border.

    Measured, it beats ``fixed`` where the border moves otherwise than the object (a rim turning the other way:
    about half the scale and rotation error), but tracks an object whose outer ring is merely covered no better
    than ``fixed``, whose log-polar grid is as centre-weighted (few of its rings lie near the border); README.

    Parameters
    ----------
    inner_ratio : float
        Size of the inner template's ellipse as a fraction (0 to 1, exclusive) of the ROI's.
    inner_weight : float
        Weight (0 to 1) of the inner template's match in the combined score; the outer one gets the rest.
    **kwargs
        ``window``, ``n_rho``, ``n_theta``, ``lost_threshold``, ``coarse``: as for ``fixed``.
    """

    name = "occlusion"
    summary = "inner and outer concentric templates, inner weighted more; resists a border that moves otherwise"

    def __init__(self, *, inner_ratio: float = 0.6, inner_weight: float = 0.7, **kwargs):
        super().__init__(**kwargs)
        self.inner_ratio, self.inner_weight = float(inner_ratio), float(inner_weight)
        # An inner circle as large as the outer one would be no second template.
        check_ranges(self, {"inner_ratio": (0.0, 0.95), "inner_weight": (0.0, 1.0)}, positive={"inner_ratio"})

    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        centre = np.array([[roi.cx, roi.cy]])
        self.outer, self.coarse_outer = self._matchers(roi.a, roi.b)
        self.inner, self.coarse_inner = self._matchers(roi.a * self.inner_ratio, roi.b * self.inner_ratio)
        for m in (self.outer, self.inner, self.coarse_outer, self.coarse_inner):
            if m is not None:
                m.template = m.spectra(gray, centre, 1.0, roi.angle_deg)

    @property
    def weights(self) -> tuple[float, float]:
        """Weights of the inner and the outer template's match in the combined score."""
        return self.inner_weight, 1.0 - self.inner_weight

    def _combine(self, gray, centres, scale, angle, matchers=None):
        matchers = matchers or (self.inner, self.outer)
        peaks = [m.match(m.spectra(gray, centres, scale, angle)) for m in matchers]
        weights = self.weights
        heights = weights[0] * peaks[0].height + weights[1] * peaks[1].height
        return peaks, weights, heights

    def _change(self, peaks, weights, index) -> tuple[float, float]:
        """Scale and rotation as the score-weighted mean of the two templates' estimates."""
        w = np.array([weights[i] * float(peaks[i].height[index]) for i in range(2)]) + 1e-9
        changes = [m.to_change(p, index) for m, p in zip((self.inner, self.outer), peaks)]
        log_scale = sum(wi * math.log(c[0]) for wi, c in zip(w, changes)) / w.sum()
        rotation = sum(wi * c[1] for wi, c in zip(w, changes)) / w.sum()
        return math.exp(log_scale), rotation

    def _locate(self, gray: np.ndarray, last: Similarity) -> Similarity:
        centres = np.array([last.cx, last.cy], np.float32) + self.offsets
        if self.coarse:
            coarse = (self.coarse_inner, self.coarse_outer)
            start = self._coarse_starts(
                lambda cells: self._combine(gray, centres[cells], last.scale, self._angle(last), coarse)[2])[0]
            found: dict[int, list[Peak]] = {}

            def evaluate(indices):
                peaks, _, heights = self._combine(gray, centres[indices], last.scale, self._angle(last))
                found.update((int(i), [take(p, n) for p in peaks]) for n, i in enumerate(indices))
                return heights

            best, offset = self._climb(int(start), evaluate)
            ds, dr = self._change(found[best], self.weights, 0)
        else:
            peaks, weights, heights = self._combine(gray, centres, last.scale, self._angle(last))
            best, offset = self._best_cell(heights)
            ds, dr = self._change(peaks, weights, best)
        cx, cy = last.cx + offset[0], last.cy + offset[1]
        scale, rotation = last.scale * ds, last.rotation_deg + dr
        peaks, weights, heights = self._combine(gray, np.array([[cx, cy]]), scale, self.roi.angle_deg + rotation)
        ds, dr = self._change(peaks, weights, 0)
        return Similarity(cx, cy, scale * ds, rotation + dr, float(heights[0]))
