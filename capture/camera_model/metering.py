"""Metering: the weighted output luma an auto-exposure steers to its target.

A camera meters on a statistics grid of block averages of its linear signal (where sensor noise
averages out) and judges them through its tone curve. A real frame is metered the same way (its
levels linearised through the response, averaged over the same grid, curved again), so a fitted
target means the same in both and does not carry the noise's bias (a concave curve lowers the mean
of noisy levels: 3.5% at high gain in ``bench exposure`` before this). Luma: BT.709 weights on the
output levels (0..1)."""
from __future__ import annotations

import cv2
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


CELLS = 4800


def grid(linear: np.ndarray, cells: int = CELLS) -> np.ndarray:
    """Block averages of a linear image (H, W, 3) on a grid of about ``cells`` cells (area resampling)."""
    h, w = linear.shape[:2]
    step = max(1.0, float(np.sqrt(h * w / cells)))
    size = (max(1, int(round(w / step))), max(1, int(round(h / step))))
    return cv2.resize(np.ascontiguousarray(linear, dtype=np.float32), size, interpolation=cv2.INTER_AREA)


def meter(stats: np.ndarray, curve, wts: np.ndarray, scale: float = 1.0) -> float:
    """The camera's meter: its statistics grid (``grid`` of linear camera RGB) times the exposure
    ``scale``, clipped at saturation, through its tone ``curve``, luma-weighted by ``wts``. Every
    metered level (auto-exposure choice, fitting, predicting) is this one function."""
    return level(curve(np.clip(stats * scale, 0.0, 1.0)), wts)


def frame_statistics(levels: np.ndarray, response) -> np.ndarray:
    """The statistics grid of a recorded frame (output levels 0..1): linearised through the response."""
    return grid(response.to_linear(levels))


def meter_frame(levels: np.ndarray, response, metering: str, centre_sigma: float = 0.25,
                roi=(0.0, 0.0, 1.0, 1.0)) -> float:
    """The metered level of a recorded frame (output levels 0..1) as its camera meters it."""
    stats = frame_statistics(levels, response)
    return meter(stats, response.to_output, weights(stats.shape[:2], metering, centre_sigma, roi))
