"""The colour likelihood of an object against its surround (logpolar_track.colour)."""

import numpy as np
import pytest

from logpolar_track.colour import ColourLikelihood


def _patch(colour, shape=(8, 8)):
    return np.broadcast_to(np.array(colour, np.uint8), shape + (3,)).copy()


def test_object_colours_score_high_surround_low_and_unseen_half():
    model = ColourLikelihood()
    samples = np.concatenate([_patch((20, 30, 200)), _patch((40, 180, 40))], axis=1)  # red object, green around
    inside = np.zeros(samples.shape[:2], bool)
    inside[:, :8] = True
    model.fit(model.bins(samples), inside, ~inside)
    probe = np.concatenate([_patch((22, 28, 205)), _patch((44, 176, 38)), _patch((200, 40, 40))], axis=1)
    likelihood = model.likelihood(model.bins(probe))
    assert likelihood.dtype == np.float32 and likelihood.shape == probe.shape[:2]
    assert np.all(likelihood[:, :8] == 1.0)  # the object's colour (within a bin)
    assert np.all(likelihood[:, 8:16] == 0.0)  # the surround's
    assert np.all(likelihood[:, 16:] == 0.5)  # a colour seen in neither


def test_a_colour_in_both_scores_by_its_share_and_updates_blend():
    model = ColourLikelihood(learning_rate=0.25)
    samples = np.concatenate([_patch((100, 100, 100)), _patch((100, 100, 100), (8, 24))], axis=1)
    inside = np.zeros(samples.shape[:2], bool)
    inside[:, :8] = True
    bins = model.bins(samples)
    model.fit(bins, inside, ~inside)
    # Both histograms are all in this one bin: P(c | object) = P(c | surround) = 1.
    assert model.likelihood(bins)[0, 0] == pytest.approx(0.5)
    other = model.bins(np.concatenate([_patch((10, 10, 250)), _patch((100, 100, 100), (8, 24))], axis=1))
    model.update(other, inside, ~inside)
    # The object's histogram is now 0.75 grey and 0.25 red; the surround's still all grey.
    assert model.likelihood(bins)[0, 0] == pytest.approx(0.75 / 1.75)
    assert model.likelihood(other)[0, 0] == pytest.approx(1.0)


def test_bins_cover_the_colour_cube():
    model = ColourLikelihood(bits=4)
    corners = np.array([[[0, 0, 0], [255, 255, 255], [255, 0, 0], [0, 0, 255]]], np.uint8)
    assert model.bins(corners).tolist() == [[0, 4095, 15 << 8, 15]]
    with pytest.raises(RuntimeError, match=r"^fit\(\) first$"):
        model.likelihood(model.bins(corners))
    with pytest.raises(ValueError, match="^bits must be 1 to 8, got 0$"):
        ColourLikelihood(bits=0)
