"""Dense features for correlation-filter matching: normalised grey level plus oriented-gradient channels.

The oriented-gradient channels are a cell-free cousin of HOG (Dalal and Triggs, CVPR 2005): the gradient
magnitude is split between the two nearest of ``n_orient`` unsigned orientation bins, then blurred, so the
channels describe local shape while staying insensitive to brightness gain and small deformations.

Speed: a tracker computes these on a 64 x 64 patch several times per frame, so every step is one vectorised
pass over the patch (no loop over channels); the channels are built pixel-major, ``(H, W, n_orient)``, so
that one multi-channel ``cv2.GaussianBlur`` call blurs them all.
"""

from __future__ import annotations

import math
import cv2
import numpy as np

def _orientation_channels(gray: np.ndarray, n_orient: int, blur_sigma: float) -> tuple[np.ndarray, np.float32]:
    """Blurred oriented gradient energy, pixel-major ``(H, W, n_orient)`` float32, and the mean magnitude."""
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3)
    magnitude, angle = cv2.cartToPolar(gx, gy)
    # Position in bins over the full circle (cartToPolar's angle is 0 to 2 pi): 0 to 2 n_orient. Orientation
    # is unsigned, so bin b and bin b + n_orient are the same; lookup tables fold them (cheaper than ``%``).
    angle *= np.float32(n_orient / np.pi)
    floor = np.floor(angle)
    angle -= floor  # the share of the upper bin
    lower_bin, upper_bin = _bin_tables(n_orient)
    whole = floor.astype(np.intp).ravel()
    # Each pixel's magnitude goes to its two neighbouring bins (linear interpolation), the others stay 0.
    height, width = gray.shape
    channels = np.zeros((height, width, n_orient), np.float32)
    flat = channels.reshape(-1)
    base = np.arange(0, flat.size, n_orient)
    to_upper = magnitude * angle
    flat[base + lower_bin[whole]] = (magnitude - to_upper).ravel()
    flat[base + upper_bin[whole]] = to_upper.ravel()
    # The kernel is cut at 2 sigma (OpenCV's default for float images is 4): the blur only makes the channels
    # tolerant of small shifts, and the shorter kernel halves its cost, a twentieth of lpcf's time per frame.
    size = 2 * math.ceil(2 * blur_sigma) + 1
    cv2.GaussianBlur(channels, (size, size), blur_sigma, dst=channels)
    return channels, np.float32(cv2.mean(magnitude)[0] + 1e-3)


def _bin_tables(n_orient: int) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper unsigned bin of each whole position 0 .. 2 n_orient on the full circle."""
    tables = _BIN_TABLES.get(n_orient)
    if tables is None:
        whole = np.arange(2 * n_orient + 1)
        tables = _BIN_TABLES[n_orient] = (whole % n_orient, (whole + 1) % n_orient)
    return tables


_BIN_TABLES: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def patch_features(gray: np.ndarray, n_orient: int = 6, window: np.ndarray | None = None) -> np.ndarray:
    """Features of a grey patch: ``(1 + n_orient, H, W)`` float32, grey normalised to zero mean, unit std.

    ``window`` (``(H, W)`` float32), if given, multiplies every channel (e.g. a Hann window before an FFT);
    it is folded into the normalisation, which saves a pass over the channels.
    """
    channels, norm = _orientation_channels(gray, n_orient, 1.0)
    mean, std = cv2.meanStdDev(gray)
    weight = np.ones(gray.shape, np.float32) if window is None else window
    out = np.empty((1 + n_orient,) + gray.shape, np.float32)
    np.multiply(gray - np.float32(mean[0, 0]), weight / np.float32(std[0, 0] + 1e-3), out=out[0])
    np.multiply(channels.transpose(2, 0, 1), weight / norm, out=out[1:])
    return out


def locally_normalised(features: np.ndarray, sigma: float, floor: float = 0.2) -> np.ndarray:
    """:func:`patch_features` of a large map ``(1 + n_orient, H, W)`` normalised to their neighbourhood, float32.

    The grey channel is centred on its local mean and divided by its local spread, the gradient channels are
    divided by the local mean of their sum (the gradient magnitude), both within a Gaussian of ``sigma`` samples,
    so that a part of the map in shade (or in a spotlight) has the contrast of the rest. ``floor``, a fraction of
    the map's mean spread and magnitude, is added to the divisors so that flat areas are not raised to noise.
    """
    if sigma <= 0 or floor < 0:
        raise ValueError(f"need sigma > 0 and floor >= 0, got {sigma} and {floor}")
    out = np.empty_like(features)
    grey = features[0] - cv2.GaussianBlur(features[0], (0, 0), sigma)
    spread = np.sqrt(cv2.GaussianBlur(grey * grey, (0, 0), sigma))
    np.divide(grey, spread + np.float32(floor * float(spread.mean()) + 1e-6), out=out[0])
    magnitude = cv2.GaussianBlur(features[1:].sum(axis=0), (0, 0), sigma)
    np.divide(features[1:], magnitude + np.float32(floor * float(magnitude.mean()) + 1e-6), out=out[1:])
    return out
