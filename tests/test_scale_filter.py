"""The scale filter (DSST's): its response is DSST's, and it reads the direction and part of a known change of size
from rows sampled off a textured image."""

import math

import cv2
import numpy as np
import pytest

from logpolar_track.scale_filter import ScaleFilter
from logpolar_track.synthetic import random_texture

CENTRE = (100.0, 100.0)


@pytest.fixture(scope="module")
def image():
    grey = random_texture(200, 200, np.random.default_rng(3), colour=False).astype(np.float32)
    return cv2.GaussianBlur(grey, (0, 0), 0.7)  # smooth enough to sample bilinearly at any of the sizes below


def box_rows(image, side_px, log_factors, samples=16):
    """One row per size: the square box of ``side_px * exp(factor)`` pixels around CENTRE, ``samples`` a side,
    normalised together (as lpcf's features are)."""
    rows = []
    for factor in np.exp(log_factors):
        spacing = side_px * factor / samples
        offset = (np.arange(samples) - (samples - 1) / 2) * spacing
        map_x, map_y = np.meshgrid(CENTRE[0] + offset, CENTRE[1] + offset)
        rows.append(cv2.remap(image, map_x.astype(np.float32), map_y.astype(np.float32), cv2.INTER_LINEAR).ravel())
    rows = np.array(rows, np.float32)
    return (rows - rows.mean()) / rows.std()


def test_reads_the_direction_and_part_of_a_change_of_size(image):
    """Trained on the box at 60 px, the filter reads an object grown by ``zoom`` (the same box sampled at 60 / zoom
    px of the unchanged image) in the right direction, more for a larger change, but only part of it: DSST's
    window over the sizes holds the peak towards the middle row (measured: 34-61 % of the change here; lpcf
    therefore starts each search from the last size moved by part of its own change, see ``_SHOWN_FOLLOWS``)."""
    scale_filter = ScaleFilter(13, 1.025)
    scale_filter.learn(box_rows(image, 60.0, scale_filter.log_factors))
    zooms = [0.9, 0.95, 0.98, 1.0, 1.02, 1.05, 1.1]
    readings = [scale_filter.find(box_rows(image, 60.0 / zoom, scale_filter.log_factors)) for zoom in zooms]
    assert np.all(np.diff(readings) > 0)
    for zoom, reading in zip(zooms, readings):
        if zoom == 1.0:
            assert abs(reading) < 1e-6
        else:
            assert 0.3 <= reading / math.log(zoom) <= 0.8, (zoom, reading)


def test_its_own_training_rows_peak_in_the_middle(image):
    scale_filter = ScaleFilter(17, 1.02)
    rows = box_rows(image, 50.0, scale_filter.log_factors)
    scale_filter.learn(rows)
    response = scale_filter.response(rows)
    assert response.argmax() == 8
    assert abs(scale_filter.find(rows)) < 1e-6


def test_the_response_is_dsst_s_computed_with_numpy_ffts(image):
    """The half-spectrum matrix DFTs give DSST's response: FFTs along the size axis of the windowed rows, numerator
    label * conj(x), denominator sum |x|^2, both running averages."""
    rng = np.random.default_rng(0)
    first, second, probe = (rng.standard_normal((9, 40)).astype(np.float32) for _ in range(3))
    scale_filter = ScaleFilter(9, 1.03, regularisation=0.01)
    scale_filter.learn(first)
    scale_filter.learn(second, rate=0.3)
    offsets = np.arange(9) - 4
    label = np.fft.fft(np.exp(-0.5 * (offsets / (0.25 * 3)) ** 2))[:, None]
    window = np.hanning(11)[1:-1, None]
    a, b, z = (np.fft.fft(x * window, axis=0) for x in (first, second, probe))
    numerator = 0.7 * label * np.conj(a) + 0.3 * label * np.conj(b)
    denominator = 0.7 * (abs(a) ** 2).sum(axis=1) + 0.3 * (abs(b) ** 2).sum(axis=1)
    expected = np.fft.ifft((numerator * z).sum(axis=1) / (denominator + 0.01)).real
    np.testing.assert_allclose(scale_filter.response(probe), expected, rtol=1e-4, atol=1e-6 * abs(expected).max())


def test_rate_one_replaces_the_model(image):
    rng = np.random.default_rng(1)
    first, second = (rng.standard_normal((13, 30)).astype(np.float32) for _ in range(2))
    replaced, fresh = ScaleFilter(13), ScaleFilter(13)
    replaced.learn(first)
    replaced.learn(second, rate=1.0)
    fresh.learn(second)
    np.testing.assert_array_equal(replaced.response(first), fresh.response(first))


@pytest.mark.parametrize("kwargs, message", [({"n_scales": 12}, "odd"), ({"n_scales": 1}, "odd"),
                                             ({"scale_step": 1.0}, "above 1")])
def test_bad_settings_say_what_is_accepted(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ScaleFilter(**kwargs)


def test_response_before_learning_is_an_error():
    with pytest.raises(RuntimeError, match="before learn"):
        ScaleFilter().response(np.zeros((17, 4), np.float32))


def test_a_response_with_no_peak_reads_no_change():
    """Flat rows (a featureless patch) and NaN rows answer alike at every size: no change, not the smallest size
    (the first row, which an argmax of equal values gives)."""
    scale_filter = ScaleFilter()
    scale_filter.learn(np.zeros((17, 100), np.float32))
    assert scale_filter.find(np.zeros((17, 100), np.float32)) == 0.0
    assert scale_filter.find(np.full((17, 100), np.nan, np.float32)) == 0.0
