"""The sRGB transfer curve (IEC 61966-2-1): the one place it is written.

The renderer's 8-bit frames, the camera model's default response and the colour fitting all use it.
A leaf: imports numpy only, so ``render/`` and ``capture/`` can both import it.

- ``srgb_levels`` / ``srgb_to_linear``: the curve and its inverse, not clipped;
- ``srgb_encode``: linear light -> 8-bit codes (what the renderer writes);
- ``linear_from_srgb8``: an 8-bit sRGB colour as a technician would match it -> a linear RGB albedo tuple;
- ``srgb_encode_float`` / ``srgb_decode``: linear light <-> display levels 0..1 as float64, clipped
  (patch colours of the ColorChecker).
"""
from __future__ import annotations

import numpy as np


def srgb_levels(linear):
    """Linear values -> display levels (0..1 for 0..1), not clipped."""
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1 / 2.4) - 0.055)


def srgb_to_linear(levels):
    """The inverse of ``srgb_levels``: display levels -> linear values."""
    return np.where(levels <= 0.04045, levels / 12.92, ((levels + 0.055) / 1.055) ** 2.4)


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """Scene-linear RGB -> 8-bit sRGB (Blender's 'Standard' view transform). Computed in the input's
    precision (a float32 render stays float32), which the rendered frames' bytes depend on."""
    return np.round(srgb_levels(np.clip(linear, 0.0, 1.0)) * 255.0).astype(np.uint8)


def srgb_encode_float(linear):
    """Linear light (clipped to 0..1) -> display levels 0..1 as float64 (``srgb_encode`` gives 8-bit codes)."""
    return srgb_levels(np.clip(np.asarray(linear, dtype=float), 0.0, 1.0))


def srgb_decode(levels):
    """Display levels (clipped to 0..1) -> linear light, as float64."""
    return srgb_to_linear(np.clip(np.asarray(levels, dtype=float), 0.0, 1.0))


def linear_from_srgb8(*srgb_8bit: int) -> tuple[float, ...]:
    """An 8-bit sRGB colour (what a technician matches against a swatch) -> linear RGB floats."""
    return tuple(float(srgb_to_linear(c / 255.0)) for c in srgb_8bit)
