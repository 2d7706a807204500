"""The imaging model: how one camera turns the light of a scene into pixels.

It lives in the camera rig file beside the intrinsics, one optional table per part:

- ``[exposure]``: auto-exposure. Metering (``average``, ``centre`` with ``centre_sigma``, or a
  cabin ``roi``), the ``target`` level (metered output luma, 0..1), ``exposure_us`` and ``gain``
  limits, the ``order`` in which exposure time and gain are spent, ``sensitivity`` (sensor signal,
  1 = saturation, per render-linear unit, second and unit gain) and the controller's convergence
  (``speed``: share of the log error corrected per frame, ``tolerance``: dead band, ``frames``: 0 =
  converged, N = N frames after ``start_exposure``).
- ``[response]``: the inverse tone curve per channel (``linear_r/g/b``: linear signal, 1 = saturation,
  at each output code 0..255) and ``white_balance`` gains.
- ``[noise]``: gain-dependent shot and read noise, variance = shot * gain * s + read^2 * gain^2.
- ``[colour]``: the colour correction from rendered to camera RGB (colour-science's
  ``matrix_colour_correction`` methods).

Each part may carry a ``fit`` sub-table: the data that produced it and its residual. A camera file
without any of these tables has no imaging model and renders as before.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from isu_validate.errors import UserError
from isu_validate.srgb import srgb_to_linear

METERING = ("average", "centre", "roi")
ORDERS = ("exposure_first", "gain_first")
SECTIONS = ("exposure", "response", "noise", "colour")
CODES = 256


class ImagingModelError(UserError, ValueError):
    """An imaging-model table of a camera file is inconsistent; the message names the file and key."""


@dataclass(frozen=True)
class AutoExposure:
    target: float = 0.45
    exposure_us: tuple[float, float] = (20.0, 33000.0)
    gain: tuple[float, float] = (1.0, 16.0)
    order: str = "exposure_first"
    metering: str = "centre"
    centre_sigma: float = 0.25          # of the image width/height
    roi: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0)   # x0 y0 x1 y1, fractions
    sensitivity: float = 100.0
    speed: float = 0.5
    tolerance: float = 0.02
    frames: int = 0
    start_exposure: float = 0.0         # exposure product (us x gain); 0 = geometric middle of the range
    fit: dict = field(default_factory=dict, compare=False)

    @property
    def product_range(self) -> tuple[float, float]:
        return self.exposure_us[0] * self.gain[0], self.exposure_us[1] * self.gain[1]

    def split(self, product: float) -> tuple[float, float]:
        """Exposure time (us) and gain for an exposure product, spending them in the camera's order."""
        (t0, t1), (g0, g1) = self.exposure_us, self.gain
        if self.order == "exposure_first":
            t = min(max(product / g0, t0), t1)
            return t, min(max(product / t, g0), g1)
        g = min(max(product / t0, g0), g1)
        return min(max(product / g, t0), t1), g


@dataclass(frozen=True)
class Response:
    linear: np.ndarray                  # (256, 3): linear signal at each output code, 1 at saturation
    white_balance: tuple[float, float, float] = (1.0, 1.0, 1.0)
    fit: dict = field(default_factory=dict, compare=False)

    @staticmethod
    def srgb(white_balance=(1.0, 1.0, 1.0), fit=None) -> "Response":
        lin = srgb_to_linear(np.arange(CODES) / (CODES - 1))
        return Response(np.repeat(lin[:, None], 3, axis=1), tuple(white_balance), fit or {})

    def to_output(self, signal: np.ndarray) -> np.ndarray:
        """Output levels (0..1) of linear signals (..., 3), by interpolating the inverse curve."""
        z = np.arange(CODES, dtype=np.float64) / (CODES - 1)
        return np.stack([np.interp(signal[..., c], self.linear[:, c], z) for c in range(3)], axis=-1)

    def to_linear(self, output: np.ndarray) -> np.ndarray:
        """Linear signals of output levels (..., 3) in 0..1."""
        z = np.arange(CODES, dtype=np.float64) / (CODES - 1)
        return np.stack([np.interp(output[..., c], z, self.linear[:, c]) for c in range(3)], axis=-1)


@dataclass(frozen=True)
class Noise:
    shot: float = 0.0                   # variance per unit signal and unit gain
    read: float = 0.0                   # standard deviation at unit gain (signal units)
    fit: dict = field(default_factory=dict, compare=False)

    def variance(self, signal, gain):
        return self.shot * gain * np.maximum(signal, 0.0) + (self.read * gain) ** 2


@dataclass(frozen=True)
class ColourCorrection:
    method: str = "Cheung 2004"
    matrix: np.ndarray = field(default_factory=lambda: np.eye(3))
    options: dict = field(default_factory=dict)    # terms / degree / root_polynomial_expansion
    fit: dict = field(default_factory=dict, compare=False)

    @property
    def is_linear(self) -> bool:
        return self.matrix.shape == (3, 3)


@dataclass(frozen=True)
class ImagingModel:
    exposure: AutoExposure | None = None
    response: Response | None = None
    noise: Noise | None = None
    colour: ColourCorrection | None = None
    source: str = "<memory>"

    @property
    def empty(self) -> bool:
        return all(getattr(self, s) is None for s in SECTIONS)

    @property
    def curve(self) -> Response:
        """The response used when applying: the fitted one, else sRGB (what renders had before)."""
        return self.response if self.response is not None else Response.srgb()

    def to_dict(self, with_fit: bool = True) -> dict:
        out = {}
        for name in SECTIONS:
            part = getattr(self, name)
            if part is not None:
                out[name] = _part_to_dict(name, part, with_fit)
        return out

    @property
    def hash(self) -> str:
        """Identifies what the model does to an image (not how it was fitted): part of the render cache key."""
        blob = json.dumps(plain(self.to_dict(with_fit=False)), sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    def with_part(self, **parts) -> "ImagingModel":
        return replace(self, **parts)


def _part_to_dict(name: str, part, with_fit: bool) -> dict:
    if name == "response":
        d = {"white_balance": list(part.white_balance),
             **{f"linear_{c}": part.linear[:, i].tolist() for i, c in enumerate("rgb")}}
    elif name == "colour":
        d = {"method": part.method, "matrix": np.asarray(part.matrix).tolist(), **part.options}
    else:
        d = {f.name: getattr(part, f.name) for f in fields(part) if f.name != "fit"}
        d = {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}
    if with_fit and part.fit:
        d["fit"] = part.fit
    return d


def plain(value):
    """numpy values to TOML/JSON-writable Python values; NaN/inf become strings (JSON has none)."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else str(v)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


# ---------------------------------------------------------------------- reading
def from_dict(raw: dict, where: str = "<camera>") -> ImagingModel | None:
    """The imaging model of a camera file's tables; None when it has none (a camera as before)."""
    if not any(s in raw for s in SECTIONS):
        return None
    parts = {}
    for name, parse in (("exposure", _exposure), ("response", _response), ("noise", _noise), ("colour", _colour)):
        if name in raw:
            table = raw[name]
            if not isinstance(table, dict):
                raise ImagingModelError(f"{where}: [{name}] must be a table")
            parts[name] = parse(table, f"{where} [{name}]")
    return ImagingModel(source=where, **parts)


def _num(table: dict, key: str, where: str, default, lo=-math.inf, hi=math.inf, open_lo=False) -> float:
    value = table.get(key, default)
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ImagingModelError(f"{where}: {key} must be a number, got {value!r}") from None
    if not math.isfinite(value) or value < lo or value > hi or (open_lo and value == lo):
        bound = f"{'above' if open_lo else 'at least'} {lo:g}" + (f" and at most {hi:g}" if hi < math.inf else "")
        raise ImagingModelError(f"{where}: {key} = {value!r} is out of range (must be {bound})")
    return value


def _range(table: dict, key: str, where: str, default) -> tuple[float, float]:
    value = table.get(key, default)
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ImagingModelError(f"{where}: {key} must be [min, max], got {value!r}")
    lo, hi = (_num({key: v}, key, where, v, 0.0, open_lo=True) for v in value)
    if hi < lo:
        raise ImagingModelError(f"{where}: {key} = [{lo:g}, {hi:g}] has min above max")
    return lo, hi


def _choice(table: dict, key: str, where: str, options, default) -> str:
    value = str(table.get(key, default))
    if value not in options:
        raise ImagingModelError(f"{where}: {key} = {value!r} is unknown; use one of {', '.join(options)}")
    return value


def _exposure(t: dict, where: str) -> AutoExposure:
    d = AutoExposure()
    roi = t.get("roi", list(d.roi))
    if not isinstance(roi, (list, tuple)) or len(roi) != 4:
        raise ImagingModelError(f"{where}: roi must be [x0, y0, x1, y1] as fractions of the image, got {roi!r}")
    roi = tuple(_num({"roi": v}, "roi", where, v, 0.0, 1.0) for v in roi)
    if roi[2] <= roi[0] or roi[3] <= roi[1]:
        raise ImagingModelError(f"{where}: roi {list(roi)} is empty (x1 must exceed x0 and y1 y0)")
    return AutoExposure(
        target=_num(t, "target", where, d.target, 0.0, 1.0, open_lo=True),
        exposure_us=_range(t, "exposure_us", where, d.exposure_us), gain=_range(t, "gain", where, d.gain),
        order=_choice(t, "order", where, ORDERS, d.order), metering=_choice(t, "metering", where, METERING, d.metering),
        centre_sigma=_num(t, "centre_sigma", where, d.centre_sigma, 0.0, open_lo=True), roi=roi,
        sensitivity=_num(t, "sensitivity", where, d.sensitivity, 0.0, open_lo=True),
        speed=_num(t, "speed", where, d.speed, 0.0, 1.0, open_lo=True),
        tolerance=_num(t, "tolerance", where, d.tolerance, 0.0, 0.5),
        frames=int(_num(t, "frames", where, d.frames, 0.0, 10000.0)),
        start_exposure=_num(t, "start_exposure", where, d.start_exposure, 0.0), fit=dict(t.get("fit", {})))


def _response(t: dict, where: str) -> Response:
    wb = t.get("white_balance", [1.0, 1.0, 1.0])
    if not isinstance(wb, (list, tuple)) or len(wb) != 3:
        raise ImagingModelError(f"{where}: white_balance must be three gains [r, g, b], got {wb!r}")
    wb = tuple(_num({"white_balance": v}, "white_balance", where, v, 0.0, open_lo=True) for v in wb)
    keys = [f"linear_{c}" for c in "rgb"]
    if not any(k in t for k in keys):
        return Response.srgb(wb, dict(t.get("fit", {})))
    columns = []
    for k in keys:
        values = np.asarray(t.get(k, []), dtype=float)
        if values.shape != (CODES,) or not np.all(np.isfinite(values)):
            raise ImagingModelError(f"{where}: {k} must list {CODES} finite numbers (the linear signal at each "
                                    f"output code), got {values.size}")
        if np.any(np.diff(values) < 0) or values[-1] <= values[0]:
            raise ImagingModelError(f"{where}: {k} must rise with the code (a response curve is monotonic)")
        columns.append(values)
    return Response(np.stack(columns, axis=1), wb, dict(t.get("fit", {})))


def _noise(t: dict, where: str) -> Noise:
    return Noise(_num(t, "shot", where, 0.0, 0.0), _num(t, "read", where, 0.0, 0.0), dict(t.get("fit", {})))


def _colour(t: dict, where: str) -> ColourCorrection:
    method = _choice(t, "method", where, ("Cheung 2004", "Finlayson 2015", "Vandermonde"), "Cheung 2004")
    matrix = np.asarray(t.get("matrix", np.eye(3)), dtype=float)
    if matrix.ndim != 2 or matrix.shape[0] != 3 or not np.all(np.isfinite(matrix)):
        raise ImagingModelError(f"{where}: matrix must be 3 rows of finite numbers (3xN), got shape {matrix.shape}")
    options = {k: t[k] for k in ("terms", "degree", "root_polynomial_expansion") if k in t}
    return ColourCorrection(method, matrix, options, dict(t.get("fit", {})))
