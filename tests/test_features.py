"""Dense features: the local-lighting normalisation used by lpcf's whole-frame search."""

import numpy as np
import pytest

from logpolar_track.features import locally_normalised, patch_features
from logpolar_track.synthetic import random_texture


def _grey_texture(height, width, seed=0):
    return random_texture(height, width, np.random.default_rng(seed), colour=False).astype(np.float32)


def _rms(x):
    return float(np.sqrt(np.mean(x * x)))


def test_locally_normalised_gives_a_shaded_half_nearly_the_contrast_of_the_lit_one():
    """A map whose right half is in shade (x0.3): the patch-normalised gradient channels there are 3.1-4.2 times
    weaker than in the lit half; locally normalised, every channel is within 1.6 times (measured 1.16-1.52: the
    floor, a fraction of the whole map's level, weighs more in the shade)."""
    grey = _grey_texture(120, 240)
    grey[:, 120:] *= 0.3
    features = patch_features(grey)
    local = locally_normalised(features, sigma=6.0)
    left, right = np.s_[10:-10, 10:100], np.s_[10:-10, 140:-10]  # away from the shadow's edge
    for channel in range(1, len(features)):
        assert _rms(features[channel][left]) > 2.5 * _rms(features[channel][right])  # the problem
    for channel in range(len(features)):
        assert 1 / 1.6 < _rms(local[channel][left]) / _rms(local[channel][right]) < 1.6


def test_locally_normalised_does_not_raise_a_flat_area_to_the_level_of_texture():
    """Faint noise (0.5 grey levels) on a flat half: with the floor its level stays at about a quarter of the
    textured half's (measured 0.26); without it the noise is raised to the texture's level (0.96)."""
    rng = np.random.default_rng(1)
    grey = _grey_texture(120, 240)
    grey[:, 120:] = 128 + rng.normal(0, 0.5, (120, 120))
    features = patch_features(grey)
    flat, textured = np.s_[:, 10:-10, 140:-10], np.s_[:, 10:-10, 10:100]
    local = locally_normalised(features, sigma=6.0)
    assert _rms(local[flat]) < 0.35 * _rms(local[textured])
    unfloored = locally_normalised(features, sigma=6.0, floor=0.0)
    assert _rms(unfloored[flat]) > 0.8 * _rms(unfloored[textured])


@pytest.mark.parametrize("sigma, floor", [(0.0, 0.2), (-1.0, 0.2), (4.0, -0.1)])
def test_locally_normalised_refuses_meaningless_parameters(sigma, floor):
    with pytest.raises(ValueError, match="sigma > 0 and floor >= 0"):
        locally_normalised(np.zeros((7, 16, 16), np.float32), sigma, floor)
