"""The response curve from an exposure bracket: Debevec & Malik (1997) through colour-hdri.

colour-hdri 0.2.6 ships Debevec 1997 (``camera_response_functions_Debevec1997``: Grossberg 2003
histogram sampling, the smoothness-regularised ``g_solve``); its Robertson solver is not in this
release. The bracket is frames of one still scene at several exposure products (time x gain) in
manual mode; the curve is checked by predicting every frame of the bracket from every other."""
from __future__ import annotations

from collections import defaultdict
from dataclasses import replace

import numpy as np
from threadpoolctl import threadpool_limits

from isu_validate.errors import UserError

from .frames import Frame
from .model import CODES, Response

MIN_EXPOSURES = 2        # distinct exposure products a bracket needs (3 or more recommended)


class UnderdeterminedError(UserError, ValueError):
    """The frames cannot determine a part of the model; the message says what to capture."""


BRACKET_ADVICE = ("capture an exposure bracket: the same still scene in manual exposure at 3 or more exposure "
                  "times with fixed gain, e.g. `isu-validate capture shoot --exposure-us 1000 --iso 100 --frames 3 "
                  "--out shots/bracket/1000` then 2000, 4000, 8000 us, and pass the folder shots/bracket")


def bracket(frames: list[Frame]) -> list[Frame]:
    """The largest set of manual frames of one group (a folder named on the command line) with distinct
    exposure products; frames
    taken at the same setting are averaged into one (sensor noise falls with the square root of their count)."""
    groups: dict[str, dict[float, list[Frame]]] = defaultdict(lambda: defaultdict(list))
    for f in frames:
        if not f.auto:
            groups[f.group][round(f.product, 6)].append(f)
    best = {k: _average(v) for k, v in max(groups.values(), key=len, default={}).items()}
    if len(best) < MIN_EXPOSURES:
        seen = f"{len(best)} exposure setting" + ("s" if len(best) != 1 else "")
        raise UnderdeterminedError(f"the response curve is underdetermined: the manual frames show {seen} of one "
                                   f"scene (it needs at least {MIN_EXPOSURES}); {BRACKET_ADVICE}")
    return sorted(best.values(), key=lambda f: f.product)


def _average(frames: list[Frame]) -> Frame:
    if len(frames) == 1:
        return frames[0]
    mean = np.mean([f.image for f in frames], axis=0).astype(np.float32)
    return replace(frames[0], image=mean)


def fit_response(frames: list[Frame], smoothing: float = 15.0, samples: int = 1000) -> Response:
    """Debevec 1997 on a bracket; returns the inverse curve (linear at each code, 1 at code 255)."""
    from colour_hdri import Image, ImageStack, Metadata, camera_response_functions_Debevec1997

    stack_frames = bracket(frames)
    stack = ImageStack()
    for f in stack_frames:
        # exposure = time x gain: an ISO of 100 x gain at f/1 makes colour-hdri's exposure value the same product
        stack.append(Image(data=f.image.astype(np.float64),
                           metadata=Metadata(f_number=1.0, exposure_time=f.exposure_us * 1e-6, iso=f.gain * 100.0)))
    with threadpool_limits(limits=1):   # multi-threaded BLAS on 2 shared cores made this least squares ~10x slower
        crfs = camera_response_functions_Debevec1997(stack, sampling_function=samples_flat_blocks,
                                                     sampling_function_kwargs={"samples": samples}, l_s=smoothing,
                                                     extrapolating_function=None, n=CODES, normalise=False)
    linear = finish_curve(np.asarray(crfs, dtype=float))
    response = Response(linear)
    residual = bracket_residual(response, stack_frames)
    fit = {"method": "Debevec 1997 (colour-hdri g_solve), flat-block sampling", "smoothing": smoothing,
           "frames": [str(f.path) for f in stack_frames],
           "exposure_us": [f.exposure_us for f in stack_frames], "gain": [f.gain for f in stack_frames],
           "residual_codes": residual}
    return Response(linear, fit=fit)


def samples_flat_blocks(data: np.ndarray, samples: int = 1000, block: int = 6, seed: int = 0) -> np.ndarray:
    """Debevec's own sampling (the same scene points in every exposure), taken as means of flat
    ``block`` x ``block`` patches: averaging cuts sensor noise ~``block`` times, which colour-hdri's
    default histogram matching (Grossberg 2003) turns into a biased curve (seen: 3-4% of full scale).
    ``data`` is colour-hdri's stack (H, W, C, N) in 0..1; returns codes (samples, N, C)."""
    h, w, channels, n = data.shape
    hb, wb = h // block, w // block
    blocks = data[:hb * block, :wb * block].reshape(hb, block, wb, block, channels, n)
    means, spread = blocks.mean(axis=(1, 3)), blocks.std(axis=(1, 3))
    mid = means[..., n // 2].mean(axis=2).ravel()
    flat = spread.max(axis=(2, 3)).ravel()
    keep = np.flatnonzero(flat <= np.percentile(flat, 40))
    rng = np.random.default_rng(seed)
    order = keep[np.argsort(mid[keep])]          # stratified over the middle frame's brightness
    pick = order[np.linspace(0, len(order) - 1, min(samples, len(order))).astype(int)]
    pick = np.unique(np.concatenate([pick, rng.choice(keep, min(len(keep), samples // 4), replace=False)]))
    codes = np.rint(means.reshape(hb * wb, channels, n)[pick] * (CODES - 1))
    return np.transpose(codes, (0, 2, 1))


def finish_curve(solved: np.ndarray) -> np.ndarray:
    """A solved inverse response (256, 3) as the camera file keeps it: ends extended, rising, 1 at code 255
    (what any Debevec solver gives, colour-hdri's or OpenCV's, becomes comparable)."""
    return _monotonic(_extend_ends(solved))


RELIABLE = (32, 224)      # codes the hat weighting leaves well determined; beyond, power-law extrapolation
_REACH = 32              # codes next to each end the extrapolation is fitted on


def _extend_ends(linear: np.ndarray) -> np.ndarray:
    """Debevec's solution is weighted to nothing near codes 0 and 255 (noise and clipping live there):
    continue the well-determined middle into both ends as a power law (straight in log-log), fitted per
    channel on the ``_REACH`` codes next to each end. Code 255 is then the saturation level."""
    out = linear.copy()
    codes = np.arange(CODES, dtype=float)
    lo, hi = RELIABLE
    for c in range(out.shape[1]):
        for span, ends in (((lo, lo + _REACH), np.arange(0, lo)), ((hi - _REACH, hi), np.arange(hi + 1, CODES))):
            z = np.arange(*span)
            slope, icpt = np.polyfit(np.log(codes[z]), np.log(np.clip(out[z, c], 1e-9, None)), 1)
            out[ends, c] = np.exp(icpt + slope * np.log(np.maximum(codes[ends], 1.0)))
        out[0, c] = 0.0   # no light, code 0 (a black level is subtracted by the sensor)
    return out


def _monotonic(linear: np.ndarray) -> np.ndarray:
    """A strictly rising curve (noise can make Debevec's solution dip where data are thin), 1 at code 255."""
    out = np.maximum.accumulate(np.clip(linear, 1e-7, None), axis=0)
    out += np.arange(CODES)[:, None] * 1e-9
    return out / out[-1]


def bracket_residual(response: Response, frames: list[Frame]) -> dict:
    """Predict each frame of the bracket from its neighbour through the curve: RMS and p95 error in codes
    over pixels unsaturated in both (the data the curve came from, re-explained)."""
    errors, per_frame = [], []
    for a, b in zip(frames[:-1], frames[1:]):
        predicted = response.to_output(np.clip(response.to_linear(a.image) * (b.product / a.product), 0, 1))
        ok = (a.image < 0.98) & (b.image < 0.98) & (a.image > 0.02) & (b.image > 0.02)
        e = (predicted - b.image)[ok] * 255.0
        errors.append(e)
        per_frame.append({"from": a.path.name, "to": b.path.name,
                          "rms_codes": float(np.sqrt(np.mean(e ** 2))) if e.size else None})
    e = np.concatenate(errors) if errors else np.zeros(0)
    return {"rms": float(np.sqrt(np.mean(e ** 2))) if e.size else None,
            "p95": float(np.percentile(np.abs(e), 95)) if e.size else None, "pairs": per_frame}
