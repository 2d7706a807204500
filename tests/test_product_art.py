"""The images drawn in code for the things in the cabin: the right size and range, deterministic, and
showing what they should (a red label with white lettering; a lit screen of many colours)."""
from __future__ import annotations

import numpy as np

from isu_validate.render import product_art as art


def test_the_images_are_rgba_in_range_and_the_same_every_time():
    for draw in (art.cola_label, art.home_screen, art.navigation_screen, art.instrument_dial):
        img = draw()
        assert img.dtype == np.float32 and img.ndim == 3 and img.shape[2] == 4
        assert 0.0 <= img.min() and img.max() <= 1.0 and (img[..., 3] == 1.0).all()
        assert np.array_equal(img, draw())


def test_the_label_is_red_with_white_lettering_above_its_wave():
    img = art.cola_label()
    red = (img[..., 0] > 0.6) & (img[..., 1] < 0.1)
    white = img[..., :3].min(axis=2) > 0.9
    assert red.mean() > 0.6 and 0.05 < white.mean() < 0.3
    upper, lower = white[: img.shape[0] // 2], white[img.shape[0] // 2:]
    assert upper.mean() > lower.mean()            # the word sits above the wave, row 0 at the top


def test_the_home_screen_has_many_coloured_icons_on_a_wallpaper():
    img = art.home_screen()
    colours = np.unique((img[..., :3] * 8).astype(int).reshape(-1, 3), axis=0)
    assert len(colours) > 20
    assert img[: img.shape[0] // 28, :, :3].mean() < img[img.shape[0] // 2, :, :3].mean()   # the status bar
