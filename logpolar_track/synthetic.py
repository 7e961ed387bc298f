"""Synthetic sequences with exact ground truth: a textured ellipse moving over a textured background.

Used by the tests, the speed benchmark and the sample generator. The object's pose per frame is a
similarity: centre in pixels, scale relative to the first frame, cumulative rotation in degrees
counter-clockwise on screen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterator

import cv2
import numpy as np

from .geometry import Ellipse


@dataclass(frozen=True)
class Pose:
    """Ground truth of one frame: centre (pixels), scale (1 at frame 0), rotation (degrees CCW, unwrapped)."""

    cx: float
    cy: float
    scale: float
    rotation_deg: float


def random_texture(height: int, width: int, rng: np.random.Generator, *, colour: bool = True) -> np.ndarray:
    """A multi-scale random texture, uint8 BGR (or grey), rich enough to register against."""
    channels = 3 if colour else 1
    out = np.zeros((height, width, channels), np.float32)
    for sigma, gain in ((12.0, 1.0), (4.0, 0.7), (1.5, 0.5)):
        noise = rng.standard_normal((height, width, channels)).astype(np.float32)
        blurred = cv2.GaussianBlur(noise, (0, 0), sigma)
        if blurred.ndim == 2:
            blurred = blurred[..., None]
        out += gain * blurred / (blurred.std() + 1e-6)
    out = (out - out.min()) / (np.ptp(out) + 1e-6) * 255.0
    out = out.astype(np.uint8)
    return out if colour else out[..., 0]


def render_frame(background: np.ndarray, texture: np.ndarray, roi: Ellipse, pose: Pose) -> np.ndarray:
    """Draw ``texture`` (the object at scale 1, centred in the texture image) inside ``roi`` moved to ``pose``.

    The texture image is square with the object's centre at its centre; pixel (u, v) of the object frame maps
    to ``pose.centre + scale * R(rotation) (u, v)`` on screen. The ellipse edge is anti-aliased.
    """
    h, w = background.shape[:2]
    size = texture.shape[0]
    c0 = (size - 1) / 2.0
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    dx, dy = xs - pose.cx, ys - pose.cy
    t = math.radians(pose.rotation_deg)
    # Inverse similarity: screen offset -> object-frame offset (turn back by -rotation, divide by scale).
    ct, st = math.cos(t), math.sin(t)
    u = (dx * ct - dy * st) / pose.scale
    v = (dx * st + dy * ct) / pose.scale
    obj = cv2.remap(texture, u + c0, v + c0, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    # Ellipse in the object frame (axis a at roi.angle_deg CCW on screen at frame 0).
    psi = math.radians(roi.angle_deg)
    ea = u * math.cos(psi) - v * math.sin(psi)
    eb = -u * math.sin(psi) - v * math.cos(psi)
    dist = np.sqrt((ea / roi.a) ** 2 + (eb / roi.b) ** 2)
    alpha = np.clip((1.0 - dist) * min(roi.a, roi.b) * pose.scale + 0.5, 0.0, 1.0)[..., None]
    if background.ndim == 2:
        alpha = alpha[..., 0]
    return (alpha * obj + (1 - alpha) * background).astype(np.uint8)


def similarity_path(n_frames: int, start: tuple[float, float], *, scale_range=(0.5, 2.0),
                    turns: float = 1.5, radius_px: float = 60.0) -> list[Pose]:
    """A smooth path: the centre circles around ``start``, scale sweeps ``scale_range``, rotation ``turns``.

    Scale starts at 1, rises to the upper end, falls to the lower end and returns (geometrically); rotation
    grows linearly to ``turns`` full counter-clockwise turns (negative for clockwise).
    """
    lo, hi = scale_range
    poses = []
    for i in range(n_frames):
        f = i / max(n_frames - 1, 1)
        phase = 2 * math.pi * f
        log_s = math.sin(phase) * (math.log(hi) if math.sin(phase) > 0 else -math.log(lo))
        cx = start[0] + radius_px * math.sin(phase)
        cy = start[1] + 0.5 * radius_px * (1 - math.cos(phase))
        poses.append(Pose(cx, cy, math.exp(log_s), 360.0 * turns * f))
    return poses


def synthetic_sequence(poses: list[Pose], roi: Ellipse, *, size=(640, 480), seed: int = 0,
                       noise: float = 2.0, colour: bool = True) -> Iterator[np.ndarray]:
    """Frames (uint8 BGR) of a textured ellipse ``roi`` following ``poses`` over a static textured background.

    ``roi`` is the object's outline at frame 0; ``poses[0]`` should be ``(roi.cx, roi.cy, 1, 0)``. Gaussian
    pixel noise of standard deviation ``noise`` grey levels is added.
    """
    rng = np.random.default_rng(seed)
    width, height = size
    background = random_texture(height, width, rng, colour=colour)
    tex_size = int(2 * roi.radius * 1.2) + 3
    texture = random_texture(tex_size, tex_size, rng, colour=colour)
    # Make the object stand out from the background a little, as real objects do.
    texture = cv2.addWeighted(texture, 0.8, np.full_like(texture, 40), 1.0, 0)
    for pose in poses:
        frame = render_frame(background, texture, roi, pose).astype(np.float32)
        if noise > 0:
            frame += rng.normal(0.0, noise, frame.shape).astype(np.float32)
        yield np.clip(frame, 0, 255).astype(np.uint8)
