"""ColorChecker detection and the colour correction, on synthetic frames of a camera with a known colour
matrix. Hard cases: no chart, a chart partly out of the frame or saturated, a singular colour matrix."""
from __future__ import annotations

import numpy as np
import pytest

from capture.camera_model import chart, synthetic
from capture.camera_model.apply import apply
from capture.camera_model.colour_fit import SingularColourError, fit_colour
from isu_validate.srgb import srgb_decode, srgb_encode_float

CORNERS = np.array([[200.0, 150.0], [430.0, 168.0], [422.0, 322.0], [192.0, 306.0]])


@pytest.fixture(scope="module")
def truth():
    return synthetic.camera().with_part(noise=None)


@pytest.fixture(scope="module")
def chart_linear():
    return synthetic.chart_scene(np.random.default_rng(5), corners=CORNERS)


def _real(truth, linear, seed=0):
    image, _ = apply(linear, truth, seed=seed)
    return image


def _sim(linear):
    return (srgb_encode_float(linear) * 255 + 0.5).astype(np.uint8)


@pytest.mark.parametrize("detector", chart.DETECTORS)
def test_both_detectors_find_the_chart_patches_in_reference_order(detector, truth):
    # a plain background: colour-checker-detection's segmentation also takes busy backgrounds for
    # the chart (`bench exposure` measures how often), mcc does not
    real = _real(truth, synthetic.chart_scene(np.random.default_rng(5), corners=CORNERS, plain=True))
    found = chart.detect(real, detector)
    assert found is not None
    quads, patches = chart.oriented(found.quads, chart.sample(real / 255.0, found.quads), truth.response.to_linear)
    assert patches.usable.sum() >= 22
    # the first patch (dark skin) sits at the chart's top-left corner, the white patch (19th) bottom-left
    assert np.linalg.norm(quads[0].mean(axis=0) - CORNERS[0]) < np.linalg.norm(quads[0].mean(axis=0) - CORNERS[2])
    assert np.linalg.norm(quads[18].mean(axis=0) - CORNERS[3]) < 60


def test_the_fitted_correction_brings_the_render_close_to_the_camera(truth, chart_linear):
    real, sim = _real(truth, chart_linear), _sim(chart_linear)
    r = chart.find(real)
    _, rp = chart.oriented(r.quads, chart.sample(real / 255.0, r.quads), truth.response.to_linear)
    s = chart.find(sim)
    _, sp = chart.oriented(s.quads, chart.sample(sim / 255.0, s.quads), srgb_decode)
    fit = fit_colour(srgb_decode(sp.colours), rp.colours, rp.usable & sp.usable, truth.response)
    assert fit.de2000_before["mean"] > 5
    assert fit.de2000_after["mean"] < 2 and fit.de2000_after["mean"] < fit.de2000_before["mean"] / 4
    np.testing.assert_allclose(fit.white_balance, np.array(truth.response.white_balance) /
                               truth.response.white_balance[1], rtol=0.15)
    assert fit.correction.method in ("Cheung 2004", "Finlayson 2015", "Vandermonde")
    # the refitted method is the cross-validation winner, and held out it still stays close to the camera
    held_out = {name: de for name, de in fit.cross_validation.items() if de != "singular"}
    best = min(held_out, key=held_out.get)
    assert best == f"{fit.correction.method} {list(fit.correction.options.values())[0]}" and held_out[best] < 1.0


def test_no_chart_in_the_frame_is_a_clear_error(truth):
    empty = _real(truth, synthetic.scene(np.random.default_rng(2), (240, 320)))
    with pytest.raises(chart.ChartNotFound, match=r"empty.png: no ColorChecker 24 found.*whole chart in the frame"):
        chart.find(empty, "mcc", "empty.png")


def test_patches_outside_the_frame_are_dropped_and_counted():
    image = np.full((100, 90, 3), 0.5, np.float32)
    quads = np.array([[[10 + 15 * c, 10 + 15 * r], [20 + 15 * c, 10 + 15 * r], [20 + 15 * c, 20 + 15 * r],
                       [10 + 15 * c, 20 + 15 * r]] for r in range(4) for c in range(6)], float)
    patches = chart.sample(image, quads)        # the right-most column (x 85..95) runs past x = 89
    assert patches.counts() == {"used": 20, "dropped": 4, "why": {"outside the frame": 4}}


def test_saturated_patches_are_dropped_and_counted(truth, chart_linear):
    from dataclasses import replace
    bright = truth.with_part(exposure=replace(truth.exposure, target=0.75))   # overexposes the light patches
    real = _real(bright, chart_linear)
    found = chart.find(real)
    _, patches = chart.oriented(found.quads, chart.sample(real / 255.0, found.quads), truth.response.to_linear)
    counts = patches.counts()
    assert counts["why"].get("saturated", 0) >= 1 and counts["used"] + counts["dropped"] == 24
    assert 18 not in np.flatnonzero(patches.usable)        # the white patch is among those dropped


def test_a_singular_colour_matrix_is_refused_with_the_reason():
    grey = np.repeat(np.linspace(0.05, 0.9, 24)[:, None], 3, axis=1)    # a 'chart' without colour
    with pytest.raises(SingularColourError, match="singular.*span three colour directions"):
        fit_colour(grey, srgb_encode_float(grey * [0.9, 1.0, 1.1]), np.ones(24, bool))


def test_too_few_usable_patches_are_refused():
    usable = np.zeros(24, bool)
    usable[:4] = True
    with pytest.raises(SingularColourError, match="only 4 chart patches"):
        fit_colour(chart.reference_linear(), srgb_encode_float(chart.reference_linear()), usable)
