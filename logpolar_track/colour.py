"""How much a colour looks like the object rather than its surround: colour histograms of both.

The per-pixel score of Staple (L. Bertinetto et al., "Staple: complementary learners for real-time tracking",
CVPR 2016): the likelihood that a pixel of colour ``c`` belongs to the object is ``P(c | object) / (P(c | object)
+ P(c | surround))``, from normalised histograms of the object's pixels and of the pixels around it. It does not
depend on where the colours are, so it holds while the object deforms, where a correlation filter's template does
not; a tracker adds it to the filter's response (see :mod:`logpolar_track.trackers.lpcf`).
"""

from __future__ import annotations

import cv2
import numpy as np


class ColourLikelihood:
    """Colour histograms of an object and of its surround, and the likelihood of object per colour.

    Parameters
    ----------
    bits : int
        Bits kept of each of the three colour channels (4: 16 levels, 4096 bins). Finer bins spread a small
        object's few pixels too thinly.
    learning_rate : float
        Running-average weight (0 to 1) of a new frame's histograms in :meth:`update`.

    Notes
    -----
    Samples are BGR ``uint8`` arrays ``(H, W, 3)``. A colour seen in neither histogram has likelihood 0.5.
    """

    def __init__(self, bits: int = 4, learning_rate: float = 0.04):
        if not 1 <= bits <= 8:
            raise ValueError(f"bits must be 1 to 8, got {bits}")
        if not 0.0 <= learning_rate <= 1.0:
            raise ValueError(f"learning_rate must be 0 to 1, got {learning_rate}")
        self.bits = int(bits)
        self.learning_rate = float(learning_rate)
        self._shift = np.uint8(8 - self.bits)
        # Bin = level_b * 2^(2 bits) + level_g * 2^bits + level_r: one cv2.transform (half the time of numpy's
        # shifts and ors); exact in float32, whose 24-bit mantissa holds every bin.
        self._weights = np.array([[1 << (2 * self.bits), 1 << self.bits, 1]], np.float32)
        self.object_histogram = self.surround_histogram = None
        self._table: np.ndarray | None = None

    def bins(self, samples: np.ndarray) -> np.ndarray:
        """Histogram bin of each BGR sample, ``(H, W)`` integers from 0 to ``2 ** (3 bits) - 1``."""
        levels = (samples[..., :3] >> self._shift).astype(np.float32)
        return cv2.transform(levels, self._weights).astype(np.intp)

    def fit(self, bins: np.ndarray, inside: np.ndarray, outside: np.ndarray) -> None:
        """Start both histograms from the samples of ``bins`` where ``inside`` (the object) and ``outside`` (its
        surround), boolean masks of the same shape."""
        self.object_histogram = self._histogram(bins[inside])
        self.surround_histogram = self._histogram(bins[outside])
        self._likelihood_table()

    def update(self, bins: np.ndarray, inside: np.ndarray, outside: np.ndarray, rate: float | None = None) -> None:
        """Blend in a new frame's histograms at ``rate`` (``learning_rate`` unless given)."""
        rate = self.learning_rate if rate is None else float(rate)
        self.object_histogram = (1 - rate) * self.object_histogram + rate * self._histogram(bins[inside])
        self.surround_histogram = (1 - rate) * self.surround_histogram + rate * self._histogram(bins[outside])
        self._likelihood_table()

    def likelihood(self, bins: np.ndarray) -> np.ndarray:
        """Likelihood of object (0 to 1) of each sample, float32, shaped like ``bins``."""
        if self._table is None:
            raise RuntimeError("fit() first")
        return self._table[bins]

    def _histogram(self, bins: np.ndarray) -> np.ndarray:
        counts = np.bincount(bins, minlength=1 << (3 * self.bits)).astype(np.float32)
        return counts / max(float(counts.sum()), 1.0)

    def _likelihood_table(self) -> None:
        total = self.object_histogram + self.surround_histogram
        table = np.full(total.shape, 0.5, np.float32)
        np.divide(self.object_histogram, total, out=table, where=total > 0)
        self._table = table
