"""Gradient refinement against an appearance subspace (logpolar_track.refine).

Conventions (the module's): patch sample (p, q) lies (p - w/2, q - h/2) samples from the centre; a step is
(du, dv, d_log_scale, d_angle) in samples, natural log and radians, counter-clockwise on screen positive.
"""

import math

import cv2
import numpy as np
import pytest

from logpolar_track.errors import UsageError
from logpolar_track.refine import AppearanceSubspace, similarity_step
from logpolar_track.synthetic import random_texture

SIZE = 40  # samples a side
SPACING = 2.0  # pixels between samples


@pytest.fixture(scope="module")
def texture() -> np.ndarray:
    """A grey texture blurred as lptrack blurs what it samples (here 2 px apart), so that sampling does not alias."""
    grey = cv2.cvtColor(random_texture(400, 400, np.random.default_rng(4)), cv2.COLOR_BGR2GRAY).astype(np.float32)
    return cv2.GaussianBlur(grey, (0, 0), 1.5)


def sample(image, cx, cy, scale=1.0, angle=0.0):
    """Patch of ``image`` in the module's convention: sample offsets (u, v) map to pixel
    ``centre + spacing * scale * R(angle) (u, v)`` with R turning counter-clockwise on screen (y down)."""
    k = SPACING * scale
    c, s = k * math.cos(angle), k * math.sin(angle)
    half = SIZE / 2.0
    matrix = np.array([[c, s, cx - c * half - s * half], [-s, c, cy + s * half - c * half]])
    return cv2.warpAffine(image, matrix, (SIZE, SIZE), flags=cv2.INTER_CUBIC | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REFLECT)


def disc_weights():
    v, u = np.mgrid[:SIZE, :SIZE] - SIZE / 2.0
    return np.sqrt(np.clip(1 - (u ** 2 + v ** 2) / (0.45 * SIZE) ** 2, 0, 1)).astype(np.float32)


def converge(image, model, state, steps=10):
    """Apply Gauss-Newton steps to ``state`` = (cx, cy, scale, angle) as the tracker does."""
    cx, cy, scale, angle = state
    for _ in range(steps):
        (du, dv, d_log_scale, d_angle), _ = similarity_step(sample(image, cx, cy, scale, angle), model)
        k = SPACING * scale
        # The step's centre move is in the patch's own (turned, scaled) frame.
        cx += k * (math.cos(angle) * du + math.sin(angle) * dv)
        cy += k * (-math.sin(angle) * du + math.cos(angle) * dv)
        scale *= math.exp(d_log_scale)
        angle += d_angle
    return cx, cy, scale, angle


@pytest.mark.parametrize("offset", [(1.5, -1.0, 0.04, 3.0), (-2.0, 0.5, -0.05, -4.0), (0.0, 0.0, 0.0, 5.0)])
def test_steps_recover_a_known_shift_scale_and_turn(texture, offset):
    """Started 1.5-2 px, 4-5 % and 3-5 degrees off, ten steps converge to the true pose within 0.02 px, 0.05 %
    and 0.02 degrees (the grid is turned, so the signs of the turn and of the centre move are checked)."""
    dx, dy, d_log_scale, d_deg = offset
    model = AppearanceSubspace(sample(texture, 200, 200), disc_weights(), n_components=0)
    cx, cy, scale, angle = converge(texture, model, (200 + dx, 200 + dy, math.exp(d_log_scale), math.radians(d_deg)))
    assert math.hypot(cx - 200, cy - 200) <= 0.02
    assert abs(scale - 1) <= 5e-4
    assert abs(math.degrees(angle)) <= 0.02


def test_a_counter_clockwise_turn_gives_a_positive_angle(texture):
    """The object turned 3 degrees counter-clockwise on screen (cv2.getRotationMatrix2D's positive angle):
    the first step from the unturned grid reads a positive d_angle near 3 degrees."""
    model = AppearanceSubspace(sample(texture, 200, 200), disc_weights(), n_components=0)
    turned = cv2.warpAffine(texture, cv2.getRotationMatrix2D((200.0, 200.0), 3.0, 1.0), (400, 400),
                            flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    (du, dv, d_log_scale, d_angle), _ = similarity_step(sample(turned, 200, 200), model)
    assert 2.0 <= math.degrees(d_angle) <= 4.0
    assert abs(du) < 0.1 and abs(dv) < 0.1 and abs(d_log_scale) < 0.005


def test_smooth_lighting_is_not_taken_for_motion(texture):
    """Brighter, higher contrast and lit by a ramp across the object: the pose found moves by under 0.05 px."""
    model = AppearanceSubspace(sample(texture, 200, 200), disc_weights(), n_components=0)
    ramp = np.linspace(0.0, 60.0, 400, dtype=np.float32)[None, :]
    lit = 1.3 * texture + 20.0 + ramp
    cx, cy, scale, angle = converge(lit, model, (200.0, 200.0, 1.0, 0.0))
    assert math.hypot(cx - 200, cy - 200) <= 0.05
    assert abs(scale - 1) <= 1e-3 and abs(math.degrees(angle)) <= 0.05


def test_distance_tells_the_object_from_another(texture):
    weights = disc_weights()
    model = AppearanceSubspace(sample(texture, 200, 200), weights, n_components=0)
    assert model.distance(sample(texture, 200, 200)) < 1e-3
    assert model.distance(2.0 * sample(texture, 200, 200) + 30.0) < 1e-3  # contrast and brightness
    assert model.distance(sample(texture, 120, 260)) > 0.8  # another patch of the texture


def test_principal_components_learn_a_recurring_change(texture):
    """An object first seen as look A, then blending back and forth between looks B and C: with one principal
    component, a new blend of B and C lies in the subspace (distance under 0.05); with the recent mean only, it
    does not (over 0.15)."""
    look_a, look_b, look_c = (sample(texture, x, y) for x, y in ((200, 200), (120, 260), (280, 120)))
    weights = disc_weights()
    with_pca = AppearanceSubspace(look_a, weights, n_components=1)
    mean_only = AppearanceSubspace(look_a, weights, n_components=0)
    for t in np.linspace(0.0, 1.0, 16):
        for model in (with_pca, mean_only):
            model.add((1 - t) * look_b + t * look_c)
    blend = 0.9 * look_b + 0.1 * look_c
    assert with_pca.distance(blend) < 0.05
    assert mean_only.distance(blend) > 0.15


@pytest.mark.parametrize("kwargs, got", [({"n_components": 16, "memory": 16}, "16, 16, 4, 2.0"),
                                         ({"refresh": 0}, "4, 16, 0, 2.0"), ({"highpass_sigma": -1}, "4, 16, 4, -1")])
def test_bad_settings_are_refused(kwargs, got):
    patch = np.zeros((8, 8), np.float32)
    with pytest.raises(UsageError) as refused:
        AppearanceSubspace(patch, np.ones_like(patch), **kwargs)
    assert str(refused.value) == ("need 0 <= n_components < memory, refresh >= 1 and highpass_sigma >= 0, got "
                                  + got)
