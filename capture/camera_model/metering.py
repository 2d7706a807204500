"""Metering: the weighted output luma an auto-exposure steers to its target.

The same weights meter a real frame (when fitting) and a simulated one (when applying), so a fitted
target means the same thing in both. Luma: BT.709 weights on the output levels (0..1)."""
from __future__ import annotations

import numpy as np

LUMA = np.array([0.2126, 0.7152, 0.0722])


def weights(shape: tuple[int, int], metering: str, centre_sigma: float = 0.25, roi=(0.0, 0.0, 1.0, 1.0)) -> np.ndarray:
    """Per-pixel metering weights (H, W), summing to 1."""
    h, w = shape
    y = (np.arange(h) + 0.5) / h
    x = (np.arange(w) + 0.5) / w
    if metering == "average":
        wts = np.ones((h, w))
    elif metering == "centre":
        wts = np.exp(-((y[:, None] - 0.5) ** 2 + (x[None, :] - 0.5) ** 2) / (2 * centre_sigma ** 2))
    elif metering == "roi":
        x0, y0, x1, y1 = roi
        wts = ((y[:, None] >= y0) & (y[:, None] <= y1) & (x[None, :] >= x0) & (x[None, :] <= x1)).astype(float)
        if not wts.any():   # an ROI thinner than one pixel of this grid: its nearest pixel
            wts[min(int((y0 + y1) / 2 * h), h - 1), min(int((x0 + x1) / 2 * w), w - 1)] = 1.0
    else:
        raise ValueError(f"unknown metering {metering!r}")
    return wts / wts.sum()


def level(output: np.ndarray, wts: np.ndarray) -> float:
    """Metered level of output levels (H, W, 3) in 0..1 under weights (H, W)."""
    return float(np.einsum("hwc,c,hw->", output, LUMA, wts))


def subsample_step(shape: tuple[int, int], pixels: int = 5000) -> int:
    """A pixel stride that leaves about ``pixels`` samples: a camera meters on a statistics grid too."""
    return max(1, int(np.sqrt(shape[0] * shape[1] / pixels)))
