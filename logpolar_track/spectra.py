"""Correlation in OpenCV's packed real spectra: the multi-channel correlation filter's products, the log-polar
phase correlation for one reference at a time, and the whole-frame search's coarse filter (used by ``lpcf``).

``cv2.dft`` of a real ``h x w`` image returns its half spectrum packed into an ``h x w`` real array (CCS), about
twice as fast as NumPy's real FFT at the sizes trackers use (64 x 64 feature patches, log-polar images); the
classes here do their arithmetic in that layout, and give the same numbers as the straightforward complex
spectra up to float32 rounding (tests/test_lpcf.py).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .logpolar import PhaseCorrelator

#: A log-polar image whose windowed variation is below this fraction of its level is flat (no structure at all).
FLAT_LOG_POLAR = 1e-5
#: Padded sizes whose kernel spectra a whole-frame search filter keeps, the least recently used dropped first. The
#: long-term filter lives as long as the track, and a drifting scale gives each search new map sizes: kept without
#: a bound, freeman1's 325 frames had left 32 sizes (56 MB) in it, and a part of a large frame takes about 10 MB.
KERNEL_SPECTRA_KEPT = 6


class PackedSpectra:
    """Multi-channel correlation in OpenCV's packed real spectra (CCS), for ``h x w`` images, both even.

    ``cv2.dft`` of a real image returns its half spectrum packed into an ``h x w`` real array: most bins are
    a (re, im) pair -- adjacent along the row in columns 1 to w-2, adjacent down the column in columns 0 and
    w-1 -- and the four corners are real. It is about twice as fast as NumPy's real FFT on these sizes.
    A complex product ``a * x`` of packed spectra is, position by position, ``U * x + V * swap(x)``, where
    ``swap`` exchanges the members of every pair, ``U`` holds ``re(a)`` at both members and ``V`` holds
    ``-im(a)`` at the real member and ``+im(a)`` at the imaginary one. A filter ``a`` is turned once into
    ``(U, swap(V))`` (:meth:`multiplier`); then the response ``sum_c a_c * x_c`` costs two channel sums over
    contiguous arrays and the swap of one image (:meth:`correlate`).
    """

    def __init__(self, h: int, w: int):
        self.shape = (h, w)
        index = np.arange(h * w).reshape(h, w)
        swapped = index.copy()
        for (re, im), (index_re, index_im) in zip(self._pairs(swapped), self._pairs(index)):
            re[...], im[...] = index_im, index_re
        self.swap = swapped.ravel()
        #: Flat positions of the four real corners (their own partners in :attr:`swap`).
        self.corners = np.array([0, w - 1, (h - 1) * w, h * w - 1])
        #: +1 at real members of pairs and at the real corners, -1 at imaginary members: packed ``conj``.
        self.conj_sign = np.ones((h, w), np.float32)
        for _, im in self._pairs(self.conj_sign):
            im[...] = -1.0

    @staticmethod
    def _pairs(x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """Views of the real and imaginary members of the pairs of packed spectra ``x`` (..., h, w)."""
        w = x.shape[-1]
        edges = x[..., ::w - 1]  # columns 0 and w-1
        return [(x[..., 1:-1:2], x[..., 2:-1:2]), (edges[..., 1:-1:2, :], edges[..., 2:-1:2, :])]

    def forward(self, images: np.ndarray) -> np.ndarray:
        """Packed spectra ``(C, h, w)`` float32 of real images ``(C, h, w)``."""
        out = np.empty(images.shape, np.float32)
        for image, spectrum in zip(images, out):
            if image.dtype == np.float32:
                cv2.dft(image, dst=spectrum)
            else:
                spectrum[:] = cv2.dft(image)
        return out

    def multiplier(self, a: np.ndarray) -> np.ndarray:
        """``U`` and ``swap(V)`` of packed spectra ``a`` ``(C, h, w)``, stacked and flattened to ``(2, C, h w)``."""
        parts = np.zeros((2,) + a.shape, np.float32)
        u, v_swapped = parts
        u[...] = a
        for (re, im), (_, u_im), (v_re, v_im) in zip(self._pairs(a), self._pairs(u), self._pairs(v_swapped)):
            u_im[...] = re
            v_re[...] = im  # swap(V) holds +im(a) at the real member...
            np.negative(im, out=v_im)  # ...and -im(a) at the imaginary one
        return parts.reshape(2, len(a), -1)

    def correlate(self, parts: np.ndarray, spectra: np.ndarray) -> np.ndarray:
        """Real image ``sum_c a_c * x_c`` (inverse DFT, scaled like ``numpy.fft.irfft2``) of the filter
        ``parts`` (:meth:`multiplier`) and packed ``spectra`` ``(C, h, w)``."""
        return cv2.idft(self.product(parts, spectra), flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)

    def product(self, parts: np.ndarray, spectra: np.ndarray) -> np.ndarray:
        """Packed ``sum_c a_c * x_c`` ``(h, w)`` of the filter ``parts`` and packed ``spectra`` ``(C, h, w)``."""
        # Both channel sums in one einsum, without the (C, h w) products (7 channels of 64 x 64: 14.7 against
        # 18.7 us for multiplying and summing in one measurement, level in another). swap(V) * x summed over
        # channels, then swapped, equals the sum of V * swap(x).
        sums = np.einsum("kci,ci->ki", parts, spectra.reshape(len(spectra), -1))
        packed = sums[0] + sums[1][self.swap]
        return packed.reshape(self.shape)

    def power(self, x: np.ndarray) -> np.ndarray:
        """``sum_c |x_c|^2`` ``(h, w)`` of packed spectra ``(C, h, w)``, at both members of every pair (so
        that packed spectra can be divided by it)."""
        squares = (x * x).sum(axis=0).ravel()
        # Each member plus its partner (re + im at both: addition commutes exactly), the real corners as they are: one
        # gather instead of adding and copying over four strided views (5 against 9 us at 64 x 64).
        out = squares + squares[self.swap]
        out[self.corners] = squares[self.corners]
        return out.reshape(self.shape)

    def expand(self, half: np.ndarray) -> np.ndarray:
        """A real value per bin of NumPy's half spectrum ``(h, w // 2 + 1)``, placed at the packed position(s)
        of each bin, e.g. to weight packed spectra bin by bin."""
        h, w = self.shape
        out = np.empty(self.shape, np.float32)
        out[:, 1:-1:2] = out[:, 2:-1:2] = half[:, 1:w // 2]
        for col, j in (0, 0), (w - 1, w // 2):
            out[0, col], out[h - 1, col] = half[0, j], half[h // 2, j]
            out[1:-1:2, col] = out[2:-1:2, col] = half[1:h // 2, j]
        return out

    def real_spectrum(self, image: np.ndarray) -> np.ndarray:
        """Packed spectrum of a real image that is even (``f(-y, -x) = f(y, x)``, circularly), whose spectrum
        is therefore real: its values, at both members of every pair, times :attr:`conj_sign`, so that
        ``result * x`` is the packed ``spectrum * conj(x)``."""
        packed = cv2.dft(np.asarray(image, np.float64))
        for re, im in self._pairs(packed):
            im[...] = re
        return (packed * self.conj_sign).astype(np.float32)


class PackedPhaseCorrelator:
    """:class:`~logpolar_track.logpolar.PhaseCorrelator`'s normalised spectra and correlation surfaces for one
    reference at a time, in packed spectra (even sizes only): the same numbers up to float32 rounding, at
    about half the cost for one image (the log-polar step runs twice a frame)."""

    def __init__(self, correlator: PhaseCorrelator):
        self.packed = PackedSpectra(*correlator.shape)
        self.window = correlator.window
        self.window_sum = float(correlator.window.sum())
        self.weight = self.packed.expand(correlator._scaled_weight)

    def spectrum(self, image: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Packed spectrum of one log-polar image, windowed and normalised as ``PhaseCorrelator.spectrum``."""
        window = self.window if mask is None else self.window * mask
        total = self.window_sum if mask is None else float(window.sum())
        mean = float((image * window).sum()) / total
        centred = image - np.float32(mean)
        centred *= window
        norm = math.sqrt(float(np.vdot(centred, centred)))
        if norm <= FLAT_LOG_POLAR * (abs(mean) + 1.0) * math.sqrt(total):
            # A flat image: what is left is the float32 mean's rounding, which the normalisation would scale up to
            # an image that every flat image shares (two flat images were alike at 0.96-0.995 in lpcf's likeness).
            return np.zeros_like(centred)
        centred /= np.float32(norm + 1e-6)
        return cv2.dft(centred)

    def reference(self, image: np.ndarray) -> np.ndarray:
        """A reference image, ready to correlate with (the multiplier of its conjugate spectrum)."""
        return self.packed.multiplier((self.spectrum(image) * self.packed.conj_sign)[None])

    def correlate(self, reference: np.ndarray, spectrum: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Correlation surface ``(n_rho, n_theta)`` of the image of packed ``spectrum`` against ``reference``, and
        their packed cross-power spectrum, from which :meth:`plain` makes the plain cross-correlation."""
        cross = self.packed.product(reference, spectrum[None])
        whitened = cross * (self.weight / (np.sqrt(self.packed.power(cross[None])) + np.float32(1e-12)))
        return cv2.idft(whitened, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE), cross

    @staticmethod
    def plain(cross: np.ndarray) -> np.ndarray:
        """``PhaseCorrelator.cross_correlate``'s surface from a packed cross-power spectrum of :meth:`correlate`."""
        return cv2.idft(cross, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)


class CoarseFilter:
    """A correlation filter for the whole-frame search: for samples twice as far apart as the filter's own, as
    one correlation kernel per feature channel and their anchor ``(x, y)``, with which a response's peak falls on
    the object's sample; and the summed correlation of a multi-channel map with them.

    The sum is made in the Fourier domain, the kernels' spectra kept per padded map size: a search of ``C``
    channels costs ``C`` forward DFTs and one inverse. Equal, within float32 rounding (3e-7 of the response's
    range), to the sum of ``cv2.filter2D(channel, CV_32F, kernel, anchor, BORDER_CONSTANT)`` over the channels,
    which took two to three times as long (7 channels, kernels of 17 to 40 samples, maps of 60 x 80 to 512 x 512).
    """

    def __init__(self, spectra: np.ndarray):
        """``spectra``: the filter's packed spectra ``(C, h, w)`` (see :class:`PackedSpectra`)."""
        ny, nx = spectra.shape[1:]
        # Even offsets from the patch's centre (nx/2, ny/2) survive the halving, so the anchor is a sample.
        y0, x0 = (ny // 2) % 2, (nx // 2) % 2
        halve = np.array([0.25, 0.5, 0.25], np.float32)
        self.kernels = []
        for spectrum in spectra:
            # The filter convolves circularly; a correlation kernel is h(-k mod n).
            kernel = np.roll(cv2.flip(cv2.idft(spectrum, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE), -1), 1, (0, 1))
            kernel = cv2.sepFilter2D(kernel, -1, halve, halve, borderType=cv2.BORDER_CONSTANT)
            self.kernels.append(np.ascontiguousarray(kernel[y0::2, x0::2]))
        self.anchor = ((nx // 2 - x0) // 2, (ny // 2 - y0) // 2)
        self.shape = self.kernels[0].shape  # (rows, columns) of each kernel
        self._kernel_spectra: dict[tuple[int, int], list[np.ndarray]] = {}

    def response(self, maps: np.ndarray) -> np.ndarray:
        """``sum_c`` of the correlation of ``maps[c]`` (``(C, H, W)`` float32) with kernel ``c``, zero beyond the
        maps' edges: ``(H, W)`` float32, as ``cv2.filter2D`` with :attr:`anchor` and ``BORDER_CONSTANT``."""
        height, width = maps.shape[1:]
        kernel_h, kernel_w = self.shape
        # Padded so that the circular correlation never wraps a map's far edge onto its near one.
        size = cv2.getOptimalDFTSize(height + kernel_h - 1), cv2.getOptimalDFTSize(width + kernel_w - 1)
        kernel_spectra = self._kernel_spectra.pop(size, None)
        if kernel_spectra is None:
            kernel_spectra = [cv2.dft(cv2.copyMakeBorder(kernel, 0, size[0] - kernel_h, 0, size[1] - kernel_w,
                                                         cv2.BORDER_CONSTANT))
                              for kernel in self.kernels]
            if len(self._kernel_spectra) >= KERNEL_SPECTRA_KEPT:
                del self._kernel_spectra[next(iter(self._kernel_spectra))]  # the least recently used
        self._kernel_spectra[size] = kernel_spectra  # (re)inserted last: dicts keep insertion order
        padded = np.zeros(size, np.float32)
        total = None
        for image, kernel_spectrum in zip(maps, kernel_spectra):
            padded[:height, :width] = image
            product = cv2.mulSpectrums(cv2.dft(padded), kernel_spectrum, 0, conjB=True)
            total = product if total is None else cv2.add(total, product, dst=total)
        full = cv2.idft(total, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)
        # The circular correlation c[n] = sum_m k[m] s[n + m]; the anchored one at (x, y) is c[x - ax, y - ay].
        anchor_x, anchor_y = self.anchor
        return np.roll(full, (anchor_y, anchor_x), (0, 1))[:height, :width]
