"""Applying an imaging model to a linear render: what the camera would have recorded.

``apply(linear_rgb, model)`` is a pure function (the renderer's host side calls it on the linear
render, ``exposure apply`` on a saved EXR): white balance and colour correction in linear light,
auto-exposure metered as the camera meters, exposure time and gain within the limits in the
camera's order, gain-dependent noise, clipping at saturation, the response curve, 8-bit output.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from . import metering
from .model import AutoExposure, ColourCorrection, ImagingModel, Response

_LUT_SIZE = 65536   # forward response table: 1/65536 of full scale keeps dark codes exact


@dataclass(frozen=True)
class Exposure:
    """What the camera chose for one frame."""
    exposure_us: float
    gain: float
    metered: float              # metered output level (0..1) without noise
    target: float | None
    at_limit: str | None        # "max" (too dark to reach the target), "min" (too bright), or None
    iterations: int

    def to_dict(self) -> dict:
        return {"exposure_us": round(self.exposure_us, 3), "gain": round(self.gain, 4),
                "metered": round(self.metered, 5), "target": self.target, "at_limit": self.at_limit,
                "iterations": self.iterations}


def colour_correct(linear_rgb: np.ndarray, response: Response | None, colour: ColourCorrection | None,
                   scale: float = 1.0) -> np.ndarray:
    """Rendered linear RGB (H, W, 3) in the camera's linear RGB: white balance, then the correction,
    times ``scale`` (the exposure), as float32. A 3x3 correction with the white balance and the scale
    folded in is one OpenCV transform (~0.5 ms for 640x480, ten times numpy's matmul)."""
    x = np.ascontiguousarray(linear_rgb, dtype=np.float32)
    wb = np.asarray(response.white_balance if response is not None else (1.0, 1.0, 1.0), dtype=np.float64)
    if colour is None or colour.is_linear:
        matrix = (colour.matrix if colour is not None else np.eye(3)) @ np.diag(wb) * scale
        return cv2.transform(x, matrix.astype(np.float32))
    from colour.characterisation import apply_matrix_colour_correction   # lazy: colour imports in ~2-4 s
    out = apply_matrix_colour_correction(x * wb.astype(np.float32), colour.matrix, colour.method, **colour.options)
    return (np.asarray(out, dtype=np.float32) * np.float32(scale))


class ForwardCurve:
    """The response curve as a dense table (signal -> output level): one gather per pixel and channel."""

    def __init__(self, response: Response):
        grid = np.linspace(0.0, 1.0, _LUT_SIZE)
        table = response.to_output(np.repeat(grid[:, None], 3, axis=1))
        self.tables = [np.ascontiguousarray(table[:, c], dtype=np.float32) for c in range(3)]
        self.codes = [np.ascontiguousarray(np.round(table[:, c] * 255.0), dtype=np.uint8) for c in range(3)]

    def _gather(self, signal: np.ndarray, tables, dtype) -> np.ndarray:
        idx = (signal * np.float32(_LUT_SIZE - 1) + np.float32(0.5)).astype(np.uint16)
        out = np.empty(signal.shape, dtype=dtype)
        for c in range(3):
            np.take(tables[c], idx[..., c], out=out[..., c])
        return out

    def __call__(self, signal: np.ndarray) -> np.ndarray:
        """Output levels (0..1, float32) of signals (..., 3) already clipped to 0..1."""
        return self._gather(signal, self.tables, np.float32)

    def to_codes(self, signal: np.ndarray) -> np.ndarray:
        """8-bit output codes of signals (..., 3) already clipped to 0..1."""
        return self._gather(signal, self.codes, np.uint8)


_CURVES: dict[int, tuple[Response, ForwardCurve]] = {}


def forward_curve(response: Response) -> ForwardCurve:
    """The cached dense table of a response (building one costs ~30 ms; a render needs it once)."""
    key = id(response)
    if key not in _CURVES or _CURVES[key][0] is not response:
        _CURVES[key] = (response, ForwardCurve(response))
    return _CURVES[key][1]


def auto_expose(linear: np.ndarray, ae: AutoExposure, curve: ForwardCurve, to_camera=None) -> Exposure:
    """The camera's auto-exposure on a linear image (H, W, 3): its statistics grid (block averages),
    ``to_camera`` (render RGB -> camera RGB, applied to the small grid, not the frame) when given, metered
    as the camera meters, and the exposure time and gain it chooses. The one metering pipeline: the
    post-render step, ``exposure apply`` and ``exposure fit``'s predictions all call it."""
    stats = metering.grid(linear)
    return choose_exposure(to_camera(stats) if to_camera is not None else stats, ae, curve)


def choose_exposure(stats: np.ndarray, ae: AutoExposure, curve: ForwardCurve) -> Exposure:
    """Meter the camera's statistics grid (``metering.grid`` of its linear RGB) as the camera would and
    choose exposure time and gain."""
    sample = np.ascontiguousarray(stats, dtype=np.float32)
    wts = metering.weights(sample.shape[:2], ae.metering, ae.centre_sigma, ae.roi)

    def meter(product: float) -> float:
        t, g = ae.split(product)
        return metering.meter(sample, curve, wts, np.float32(t * 1e-6 * g * ae.sensitivity))

    lo, hi = ae.product_range
    if ae.frames > 0:
        product, iterations = _controller(meter, ae, lo, hi)
    else:
        product, iterations = _converged(meter, ae.target, lo, hi)
    t, g = ae.split(product)
    m = meter(product)
    limit = None
    if product >= hi * (1 - 1e-9) and m < ae.target * (1 - ae.tolerance):
        limit = "max"
    elif product <= lo * (1 + 1e-9) and m > ae.target * (1 + ae.tolerance):
        limit = "min"
    return Exposure(t, g, m, ae.target, limit, iterations)


def _converged(meter, target: float, lo: float, hi: float) -> tuple[float, int]:
    """The steady state of the camera's loop: the exposure product whose metered level is the target.
    Metering rises with exposure, so a bracketing root finder (Brent) on log exposure finds it."""
    from scipy.optimize import brentq
    if lo == hi or meter(hi) <= target:
        return hi, 1
    if meter(lo) >= target:
        return lo, 2
    root, info = brentq(lambda u: meter(float(np.exp(u))) - target, np.log(lo), np.log(hi),
                        xtol=1e-4, full_output=True)
    return float(np.exp(root)), info.function_calls + 2


def _controller(meter, ae: AutoExposure, lo: float, hi: float) -> tuple[float, int]:
    """``ae.frames`` frames of the camera's loop from ``start_exposure``: each frame corrects ``speed`` of
    the log error between target and metered level, and stops inside the dead band."""
    product = ae.start_exposure or float(np.sqrt(lo * hi))
    product = min(max(product, lo), hi)
    for i in range(ae.frames):
        m = meter(product)
        if abs(m / ae.target - 1.0) <= ae.tolerance:
            return product, i + 1
        ratio = ae.target / max(m, 1e-6)
        product = min(max(product * ratio ** ae.speed, lo), hi)
    return product, ae.frames


_BANK_SIZE = 1 << 21
_bank: np.ndarray | None = None


def standard_normal(shape: tuple[int, ...], seed: int) -> np.ndarray:
    """Seeded unit Gaussian noise of ``shape``. Drawing ~1M normals costs ~20-40 ms here, most of the
    50 ms budget, so a frame takes a seed-chosen window of a fixed bank of 2M draws (wrapping around):
    every frame's noise is Gaussian and independent across its pixels; frames differ by their window."""
    global _bank
    n = int(np.prod(shape))
    if n > _BANK_SIZE:
        return np.random.default_rng(seed).standard_normal(shape, dtype=np.float32)
    if _bank is None:
        draws = np.random.default_rng(0x5EED).standard_normal(_BANK_SIZE, dtype=np.float32)
        _bank = np.concatenate([draws, draws])
    start = int(np.random.default_rng(seed).integers(0, _BANK_SIZE))
    return _bank[start:start + n].reshape(shape)


def apply(linear_rgb: np.ndarray, model: ImagingModel, seed: int = 0,
          manual: tuple[float, float] | None = None) -> tuple[np.ndarray, Exposure | None]:
    """The 8-bit RGB frame (H, W, 3) the camera records of a linear render, and the exposure it chose.

    ``manual`` = (exposure_us, gain) fixes the exposure as a camera in manual mode (needs [exposure]
    for the sensitivity). Without [exposure] the render's linear values are the sensor signal.
    Noise is seeded: the same render and seed give the same frame."""
    curve = forward_curve(model.curve)
    ae, exposure = model.exposure, None
    if ae is not None and manual is not None:
        exposure = Exposure(float(manual[0]), float(manual[1]), float("nan"), None, None, 0)
    elif ae is not None:   # meter on the statistics grid before developing the whole frame
        exposure = auto_expose(linear_rgb, ae, curve, lambda stats: colour_correct(stats, model.response, model.colour))
    scale = exposure.exposure_us * 1e-6 * exposure.gain * ae.sensitivity if exposure is not None else 1.0
    signal = colour_correct(linear_rgb, model.response, model.colour, scale)
    gain = exposure.gain if exposure is not None else 1.0
    if model.noise is not None and (model.noise.shot or model.noise.read):
        sigma = np.maximum(signal, 0.0)                       # in place: each pass over 1M values counts
        sigma *= np.float32(model.noise.shot * gain)
        sigma += np.float32((model.noise.read * gain) ** 2)
        np.sqrt(sigma, out=sigma)
        sigma *= standard_normal(signal.shape, seed)
        signal += sigma
    np.clip(signal, 0.0, 1.0, out=signal)
    return curve.to_codes(signal), exposure
