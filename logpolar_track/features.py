"""Dense features for correlation-filter matching: normalised grey level plus oriented-gradient channels.

The oriented-gradient channels are a cell-free cousin of HOG (Dalal and Triggs, CVPR 2005): the gradient
magnitude is split between the two nearest of ``n_orient`` unsigned orientation bins, then blurred, so the
channels describe local shape while staying insensitive to brightness gain and small deformations.
"""

from __future__ import annotations

import cv2
import numpy as np


def gradient_channels(gray: np.ndarray, n_orient: int = 6, blur_sigma: float = 1.0) -> np.ndarray:
    """Oriented gradient energy of a float32 grey patch, shape ``(n_orient, H, W)``, float32.

    Orientation is unsigned (0 to 180 degrees). Each channel is normalised by the patch's mean gradient
    magnitude so a brightness gain does not change the features.
    """
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3)
    magnitude, angle = cv2.cartToPolar(gx, gy)
    position = (angle % np.pi) * (n_orient / np.pi)
    lower = np.floor(position).astype(np.int32) % n_orient
    upper_weight = position - np.floor(position)
    to_lower, to_upper = magnitude * (1 - upper_weight), magnitude * upper_weight
    channels = np.empty((n_orient,) + gray.shape, np.float32)
    for c in range(n_orient):
        channels[c] = np.where(lower == c, to_lower, 0) + np.where(lower == (c - 1) % n_orient, to_upper, 0)
    norm = magnitude.mean() + 1e-3
    for c in channels:
        cv2.GaussianBlur(c, (0, 0), blur_sigma, dst=c)
    return channels / norm


def patch_features(gray: np.ndarray, n_orient: int = 6) -> np.ndarray:
    """Features of a grey patch: ``(1 + n_orient, H, W)`` float32, grey normalised to zero mean, unit std."""
    grey = (gray - gray.mean()) / (gray.std() + 1e-3)
    return np.concatenate([grey[None].astype(np.float32), gradient_channels(gray, n_orient)], axis=0)
