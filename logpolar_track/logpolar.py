"""Log-polar sampling and FFT phase correlation: the numerical core of lptrack.

In log-polar coordinates around an object's centre, scaling the object by ``s`` shifts its image by ``ln s``
along the log-radius axis and turning it by ``t`` degrees shifts it by ``t`` along the angle axis. Phase
correlation of two log-polar images therefore recovers scale and rotation in one FFT, and its peak height
says how well they match.

Array conventions: a log-polar image has shape ``(n_rho, n_theta)``; row ``k`` is the ring at radius
``rho[k]`` (log-spaced, innermost first), column ``j`` is the direction ``theta[j] = 360 * j / n_theta``
degrees **counter-clockwise on screen** from the ellipse's axis ``a``.

References
----------
.. [1] B. S. Reddy, B. N. Chatterji, "An FFT-based technique for translation, rotation, and scale-invariant
   image registration", IEEE Trans. Image Processing 5(8), 1996.
.. [2] G. Wolberg, S. Zokai, "Robust image registration using log-polar transform", ICIP 2000.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np


#: cv2.remap's limit on the rows of its maps (SHRT_MAX, exclusive).
_REMAP_MAX_ROWS = 32767


@dataclass(frozen=True)
class LogPolarGrid:
    """Sampling pattern of a log-polar image over an ellipse of semi-axes ``a`` x ``b`` pixels.

    Along the direction ``theta`` (in the ellipse's own frame) the outermost ring lies on the ellipse, at
    ``r(theta) = a b / sqrt((b cos theta)^2 + (a sin theta)^2)``; the rings inside it are at
    ``rho[k] * r(theta)`` with ``rho`` log-spaced from ``inner_px / sqrt(a b)`` (at most 0.5, so that small
    ellipses still span a factor of two) to 1. For a circle this is the ordinary log-polar transform.

    Parameters
    ----------
    a, b : float
        Semi-axes in pixels at scale 1.
    n_rho, n_theta : int
        Number of rings and of directions.
    inner_px : float
        Approximate radius in pixels of the innermost ring.

    Notes
    -----
    One phase correlation recovers a scale change of at most about ``exp(+-log_step * n_rho / 4)`` and any
    rotation; trackers keep the residual small by re-sampling at the current scale and angle every frame.
    """

    a: float
    b: float
    n_rho: int = 64
    n_theta: int = 128
    inner_px: float = 1.0
    offsets: np.ndarray = field(init=False, repr=False, compare=False)
    #: The rings' radii ``(n_rho,)`` as fractions of the ellipse's own radius in each direction (log-spaced, last 1).
    rho: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (self.a > 0 and self.b > 0 and math.isfinite(self.a * self.b)):
            raise ValueError(f"semi-axes must be finite and > 0 pixels, got a={self.a}, b={self.b}")
        if self.n_rho < 2 or self.n_theta < 2 or not self.inner_px > 0:
            raise ValueError(f"need n_rho, n_theta >= 2 and inner_px > 0, got {self.n_rho}, {self.n_theta}, "
                             f"{self.inner_px}")
        rho_min = min(0.5, self.inner_px / math.sqrt(self.a * self.b))
        rho = np.exp(np.linspace(math.log(rho_min), 0.0, self.n_rho))
        theta = np.arange(self.n_theta) * (2 * np.pi / self.n_theta)
        r = self.a * self.b / np.hypot(self.b * np.cos(theta), self.a * np.sin(theta))
        u = rho[:, None] * (r * np.cos(theta))[None, :]
        v = rho[:, None] * (r * np.sin(theta))[None, :]
        object.__setattr__(self, "offsets", np.stack([u, v]).astype(np.float64))
        object.__setattr__(self, "rho", rho)

    @property
    def log_step(self) -> float:
        """Natural-log scale change between neighbouring rings."""
        return math.log(1.0 / self.rho[0]) / (self.n_rho - 1)

    @property
    def degrees_per_bin(self) -> float:
        return 360.0 / self.n_theta

    def pixel_offsets(self, scale: float, angle_deg: float) -> tuple[np.ndarray, np.ndarray]:
        """Offsets ``(dx, dy)`` in pixels (y down) of every sample from the centre, each ``(n_rho, n_theta)``.

        ``angle_deg`` is the direction of axis ``a`` on screen (counter-clockwise), ``scale`` multiplies
        both semi-axes.
        """
        psi = math.radians(angle_deg)
        c, s = scale * math.cos(psi), scale * math.sin(psi)
        u, v = self.offsets
        return (u * c - v * s).astype(np.float32), (-(u * s + v * c)).astype(np.float32)

    def sample(self, gray: np.ndarray, centres: np.ndarray, scale: float, angle_deg: float) -> np.ndarray:
        """Log-polar images of ``gray`` around each of ``centres``.

        Parameters
        ----------
        gray : ndarray, float32, (H, W)
            Single-channel frame.
        centres : array_like, (N, 2) or (2,)
            Centres ``(x, y)`` in pixels.
        scale, angle_deg : float
            Current size (relative to ``a``, ``b``) and axis direction (degrees CCW) of the ellipse.

        Returns
        -------
        ndarray, float32, (N, n_rho, n_theta)
            Bilinear samples; pixels beyond the border repeat the border (the frame is padded).
        """
        centres = np.asarray(centres, dtype=np.float32).reshape(-1, 2)
        dx, dy = self.pixel_offsets(scale, angle_deg)
        out = np.empty((len(centres), self.n_rho, self.n_theta), np.float32)
        # One remap for many centres, their images stacked as rows; cv2.remap takes maps of under 32767 rows
        # (a 23 x 23 window of 64-ring images has 33,856).
        per_call = max(1, (_REMAP_MAX_ROWS - 1) // self.n_rho)
        for first in range(0, len(centres), per_call):
            part = centres[first:first + per_call]
            map_x = (part[:, 0, None, None] + dx[None]).reshape(-1, self.n_theta)
            map_y = (part[:, 1, None, None] + dy[None]).reshape(-1, self.n_theta)
            out[first:first + len(part)] = cv2.remap(gray, map_x, map_y, cv2.INTER_LINEAR,
                                                     borderMode=cv2.BORDER_REPLICATE).reshape(len(part), self.n_rho,
                                                                                              self.n_theta)
        return out


def rfft2_float32(images: np.ndarray) -> np.ndarray:
    """``numpy.fft.rfft2`` of float32 ``(..., n, m)`` images over the last two axes, as complex64.

    Computed through the inverse transforms, which NumPy 2.4's pocketfft runs 3-5 times faster than the
    forward ones in single precision (measured: 121 x 64 x 128, 14.5 ms forward vs 3.1 ms this way). For real
    ``x``, ``rfft(x) = n conj(ihfft(x))`` and ``fft(z) = n conj(ifft(conj(z)))``, which combine to
    ``rfft2(x) = n m conj(ifft(ihfft(x), axis=-2))``. Equal to ``rfft2`` up to float32 rounding.
    """
    n, m = images.shape[-2:]
    half = np.fft.ihfft(images, axis=-1)
    out = np.fft.ifft(half, axis=-2)
    np.conjugate(out, out=out)
    out *= np.float32(n * m)
    return out


class PhaseCorrelator:
    """Batched FFT phase correlation of log-polar images of one shape.

    Images have their window-weighted mean taken off (so the windowed image has no DC term at all), are
    multiplied by a Hann window along the (non-periodic) log-radius axis and scaled to unit L2 norm, and
    transformed with real FFTs in float32. The normalised cross-power spectrum is weighted by a Gaussian
    low-pass of width ``lowpass`` (in cycles per sample), which suppresses noisy high frequencies and gives the
    peak a smooth shape for sub-bin fitting. ``None`` gives pure phase correlation, whose peak is one bin wide:
    its sub-bin offsets (:func:`find_peaks`) are then not to be trusted (a 1-bin shift read as 0.35 bin).

    Parameters
    ----------
    shape : (int, int)
        ``(n_rho, n_theta)``.
    lowpass : float or None
        Standard deviation of the Gaussian frequency weight, in cycles per sample.
    support : ndarray, (n_rho, n_theta), optional
        Weights, 0 to 1, multiplied into the window: the samples that belong to the object (e.g. a thin
        ellipse's own outline on the circle it is sampled on). Fixed to the grid, so like the window it does not
        move with the image's shifts, and a tight one reads them short: 58-65 % of a 4-7 degree turn or 5-6 %
        scale change for a 40 x 8 px outline on a 64 px circle (tests/test_logpolar.py). Trackers that sample
        again at each estimate read the rest on the next frame.
    """

    def __init__(self, shape: tuple[int, int], lowpass: float | None = 0.1, support: np.ndarray | None = None):
        n_rho, n_theta = shape
        self.shape = (n_rho, n_theta)
        self.window = np.hanning(n_rho + 2)[1:-1, None].astype(np.float32) * np.ones((1, n_theta), np.float32)
        if support is not None:
            support = np.asarray(support, dtype=np.float32)
            if support.shape != self.shape or not np.all((support >= 0) & (support <= 1)) or not support.any():
                raise ValueError(f"support must be {self.shape} weights from 0 to 1, not all 0")
            self.window = self.window * support
        fy = np.fft.fftfreq(n_rho)[:, None]
        fx = np.fft.rfftfreq(n_theta)[None, :]
        if lowpass is None:
            weight = np.ones((n_rho, n_theta // 2 + 1))
        else:
            weight = np.exp(-(fy ** 2 + fx ** 2) / (2 * lowpass ** 2))
        # rfft keeps half the spectrum: columns other than DC (and Nyquist) stand for two frequencies.
        multiplicity = np.full(weight.shape[1], 2.0)
        multiplicity[0] = 1.0
        if n_theta % 2 == 0:
            multiplicity[-1] = 1.0
        # Images are made zero-mean before the FFT, so the DC term of the cross-power spectrum is 0/0: its
        # phase would be rounding noise and shift the whole surface by +-1/peak_norm at random. Drop it.
        weight[0, 0] = 0.0
        self.weight = weight.astype(np.float32)
        self.peak_norm = float((weight * multiplicity[None, :]).sum())
        # The weight with the surface's normalisation folded in, so correlate() needs one product.
        self._scaled_weight = (weight * (n_rho * n_theta / self.peak_norm)).astype(np.float32)

    def spectrum(self, images: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Windowed, normalised real FFT of ``(..., n_rho, n_theta)`` images (complex64).

        ``mask`` (broadcastable, values 0 to 1) down-weights samples, e.g. rings or sectors that are occluded.
        """
        images = np.asarray(images, dtype=np.float32)
        w = self.window if mask is None else self.window * np.asarray(mask, dtype=np.float32)
        mean = (images * w).sum(axis=(-2, -1), keepdims=True) / w.sum()
        centred = images - mean
        centred *= w
        norm = np.sqrt(np.einsum("...ij,...ij->...", centred, centred))[..., None, None] + np.float32(1e-6)
        centred /= norm
        return rfft2_float32(centred)

    def correlate(self, ref_spec: np.ndarray, img_spec: np.ndarray) -> np.ndarray:
        """Correlation surfaces ``(..., n_rho, n_theta)`` of ``img`` against ``ref`` (broadcast over batch).

        The surface peaks at the shift ``(d_rho, d_theta)`` for which ``img[k, j] ~ ref[k - d_rho, j - d_theta]``;
        its height is 1 for identical images and near 0 for unrelated ones.
        """
        cross = img_spec * np.conj(ref_spec)
        # Normalise and weight with one real factor per bin (cheaper than dividing complex numbers).
        cross *= self._scaled_weight / (np.abs(cross) + np.float32(1e-12))
        return np.fft.irfft2(cross, s=self.shape).astype(np.float32, copy=False)

    def cross_correlate(self, ref_spec: np.ndarray, img_spec: np.ndarray) -> np.ndarray:
        """Plain (not whitened) circular cross-correlation surfaces ``(..., n_rho, n_theta)`` of the windowed,
        normalised images of :meth:`spectrum`, laid out as :meth:`correlate`'s surfaces: at each shift, the inner
        product of the windowed, zero-mean, unit-norm ``img`` with the same of ``ref`` moved (circularly) by it,
        from -1 to 1 (1 for identical images at no shift).

        Phase correlation weighs every frequency alike, so an image with little structure along one axis -- the
        log-polar image of a plain disc, the same at every angle -- has most of its frequencies made of noise, and
        its peak is low (0.04 for a plain disc matched with itself a frame later) though the images are alike
        (0.99 here)."""
        return np.fft.irfft2(img_spec * np.conj(ref_spec), s=self.shape).astype(np.float32, copy=False)


@dataclass(frozen=True)
class Peak:
    """Sub-bin peaks of a batch of correlation surfaces (arrays of shape ``(N,)``).

    ``d_rho`` and ``d_theta`` are shifts in bins, signed (``-n/2 <= d < n/2``); ``height`` is the surface
    value at the integer peak, clipped to [0, 1].
    """

    d_rho: np.ndarray
    d_theta: np.ndarray
    height: np.ndarray


def find_peaks(surfaces: np.ndarray) -> Peak:
    """Highest peak of each ``(n_rho, n_theta)`` surface, refined to sub-bin precision.

    The refinement fits a Gaussian (a parabola through the logarithms) through the peak and its two neighbours
    along each axis (wrapping around both axes, as the circular correlation does).
    """
    surfaces = np.asarray(surfaces)
    batch_shape = surfaces.shape[:-2]
    n_rho, n_theta = surfaces.shape[-2:]
    flat = surfaces.reshape(-1, n_rho, n_theta)
    idx = np.argmax(flat.reshape(len(flat), -1), axis=1)
    k, j = np.divmod(idx, n_theta)
    rows = np.arange(len(flat))
    centre = flat[rows, k, j]
    dk = _gaussian_offset(flat[rows, (k - 1) % n_rho, j], centre, flat[rows, (k + 1) % n_rho, j])
    dj = _gaussian_offset(flat[rows, k, (j - 1) % n_theta], centre, flat[rows, k, (j + 1) % n_theta])
    d_rho = _signed(k + dk, n_rho)
    d_theta = _signed(j + dj, n_theta)
    return Peak(d_rho.reshape(batch_shape), d_theta.reshape(batch_shape),
                np.clip(centre, 0.0, 1.0).reshape(batch_shape))


def _gaussian_offset(left: np.ndarray, centre: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Sub-bin offset of a peak from a Gaussian (parabola in log values) through three samples."""
    floor = 1e-4
    return _parabola_offset(np.log(np.maximum(left, floor)), np.log(np.maximum(centre, floor)),
                            np.log(np.maximum(right, floor)))


def _parabola_offset(left: np.ndarray, centre: np.ndarray, right: np.ndarray) -> np.ndarray:
    denom = left - 2 * centre + right
    with np.errstate(divide="ignore", invalid="ignore"):
        offset = np.where(denom < 0, 0.5 * (left - right) / denom, 0.0)
    return np.clip(offset, -0.5, 0.5)


def _signed(position: np.ndarray, n: int) -> np.ndarray:
    return (position + n / 2) % n - n / 2


def parabola_peak_2d(scores: np.ndarray) -> tuple[float, float, float]:
    """Sub-cell position ``(row, col)`` and value of the maximum of a 2-D score grid.

    A parabola is fitted through the maximum and its neighbours along each axis; at the grid's edge the
    position is not refined along that axis.
    """
    r, c = np.unravel_index(int(np.argmax(scores)), scores.shape)
    best = float(scores[r, c])
    dr = dc = 0.0
    if 0 < r < scores.shape[0] - 1:
        dr = float(_parabola_offset(scores[r - 1, c], best, scores[r + 1, c]))
    if 0 < c < scores.shape[1] - 1:
        dc = float(_parabola_offset(scores[r, c - 1], best, scores[r, c + 1]))
    return r + dr, c + dc, best
