"""The auto-exposure behaviour from auto-exposed frames under several light levels.

A converged camera meters every frame to its target unless it ran out of exposure time and gain.
So: the metering whose metered levels agree best across frames is the camera's; the target is their
mean over frames inside the limits; the limits and the trade-off order come from the sidecars; the
controller's speed from consecutive frames after a light change."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from . import metering
from .frames import Frame
from .model import AutoExposure, Response
from .response_fit import UnderdeterminedError

LIGHT_STEP = 0.25        # light levels closer than this (log, ~28%) count as one
AT_LIMIT = 0.01          # a setting within 1% of a limit is at it

CANDIDATES = {"average": ("average", {}), "centre 0.15": ("centre", {"centre_sigma": 0.15}),
              "centre 0.25": ("centre", {"centre_sigma": 0.25}), "centre 0.4": ("centre", {"centre_sigma": 0.4})}

LIGHT_ADVICE = ("capture auto-exposed frames under at least two clearly different light levels (e.g. the cabin "
                "in daylight and in shade or at dusk; external light LOW, MEDIUM and HIGH), letting the camera "
                "settle before each shot: `isu-validate capture shoot --auto-exposure --frames 10 ...`")


def scene_light(frame: Frame, response: Response) -> float:
    """The frame's scene brightness in camera units: linearised mean over unclipped pixels / exposure."""
    lin = response.to_linear(frame.image).mean(axis=2)
    ok = (frame.image.max(axis=2) < 0.98) & (frame.image.max(axis=2) > 0.02)
    return float(lin[ok].mean() / frame.product) if ok.any() else float("nan")


def light_levels(frames: list[Frame], response: Response) -> int:
    logs = np.sort(np.log([x for x in (scene_light(f, response) for f in frames) if np.isfinite(x) and x > 0]))
    return 0 if logs.size == 0 else 1 + int(np.sum(np.diff(logs) > LIGHT_STEP))


def fit_auto_exposure(frames: list[Frame], response: Response, start: AutoExposure | None = None,
                      exposure_us=None, gain=None, roi=None) -> AutoExposure:
    """Fit from auto-exposed frames; ``exposure_us``/``gain`` = (min, max) from a datasheet override the
    ranges seen; ``roi`` (fractions) adds a cabin region to the metering candidates."""
    if not frames:
        raise UnderdeterminedError(f"no auto-exposed frames (sidecar auto_exposure true); {LIGHT_ADVICE}")
    levels = light_levels(frames, response)
    if levels < 2:
        raise UnderdeterminedError(f"the auto-exposure is underdetermined: the {len(frames)} auto-exposed "
                                   f"frames show a single light level; {LIGHT_ADVICE}")
    base = start or AutoExposure()
    t_range = (tuple(exposure_us) if exposure_us
               else (min(f.exposure_us for f in frames), max(f.exposure_us for f in frames)))
    g_range = tuple(gain) if gain else (min(f.gain for f in frames), max(f.gain for f in frames))
    limits = [_at_limit(f, t_range, g_range) for f in frames]
    choice, levels_by, candidates = _choose_metering(frames, limits, roi, response)
    metered = levels_by[choice]
    inside = [m for m, lim in zip(metered, limits) if lim is None]
    limits = _confirm_limits(metered, limits, inside)
    inside = np.array([m for m, lim in zip(metered, limits) if lim is None])
    if inside.size == 0:
        raise UnderdeterminedError(f"every auto-exposed frame is at an exposure limit, so the target level is "
                                   f"not seen; {LIGHT_ADVICE} (include light where the camera is not at its "
                                   f"longest exposure and highest gain)")
    target = float(inside.mean())
    order, order_evidence = _order(frames, limits, t_range, g_range)
    tolerance = (float(max(0.01, np.percentile(np.abs(inside / target - 1.0), 95))) if inside.size > 1
                 else base.tolerance)
    speed, speed_fit = _speed(frames, metered, target, tolerance, base.speed)
    kind, options = candidates[choice]
    per_frame = [{"frame": str(f.path), "exposure_us": f.exposure_us, "gain": f.gain, "metered": m,
                  "at_limit": lim or ""} for f, m, lim in zip(frames, metered, limits)]
    fit = {"frames": len(frames), "light_levels": levels, "frames_inside_limits": int(inside.size),
           "target_residual": {"std": float(inside.std()), "max_abs": float(np.abs(inside - target).max()),
                               "relative_std": float(inside.std() / target)},
           "metering_candidates": {n: {"relative_spread": _spread(v, limits)} for n, v in levels_by.items()},
           "limits_from": "given" if exposure_us or gain else "the frames' sidecars (the widest settings seen)",
           "order_evidence": order_evidence, "speed": speed_fit, "per_frame": per_frame}
    return replace(base, target=target, exposure_us=t_range, gain=g_range, order=order, metering=kind,
                   centre_sigma=options.get("centre_sigma", base.centre_sigma), roi=tuple(options.get("roi", base.roi)),
                   speed=speed, tolerance=tolerance, fit=fit)


def _at_limit(f: Frame, t_range, g_range) -> str | None:
    top = f.exposure_us >= t_range[1] * (1 - AT_LIMIT) and f.gain >= g_range[1] * (1 - AT_LIMIT)
    bottom = f.exposure_us <= t_range[0] * (1 + AT_LIMIT) and f.gain <= g_range[0] * (1 + AT_LIMIT)
    return "max" if top else "min" if bottom else None


def _confirm_limits(metered, limits, inside) -> list:
    """A frame at the extreme settings is only at a limit if it missed the target (it may just have
    met it there): compare it with the frames inside the limits."""
    if not inside:
        return limits
    centre = float(np.median(inside))
    out = []
    for m, lim in zip(metered, limits):
        missed = (lim == "max" and m < centre * 0.9) or (lim == "min" and m > centre * 1.1)
        out.append(lim if missed else None)
    return out


def _choose_metering(frames, limits, roi, response: Response) -> tuple[str, dict, dict]:
    """Metered levels of every frame under each candidate metering, and the candidate whose levels agree best."""
    candidates = dict(CANDIDATES)
    if roi:
        candidates["roi"] = ("roi", {"roi": tuple(roi)})
    stats = [metering.frame_statistics(f.image, response) for f in frames]
    levels_by = {}
    for name, (kind, options) in candidates.items():
        levels_by[name] = [metering.meter(s, response.to_output,
                                          metering.weights(s.shape[:2], kind, options.get("centre_sigma", 0.25),
                                                           options.get("roi", (0.0, 0.0, 1.0, 1.0))))
                           for s in stats]
    best = min(levels_by, key=lambda n: _spread(levels_by[n], limits))
    return best, levels_by, candidates


def _spread(levels, limits) -> float:
    inside = np.array([m for m, lim in zip(levels, limits) if lim is None])
    return float(inside.std() / inside.mean()) if inside.size > 1 and inside.mean() > 0 else float("inf")


def _order(frames, limits, t_range, g_range) -> tuple[str, dict]:
    """Which the camera spends first: a frame with gain above its minimum before the exposure time
    reached its maximum contradicts exposure_first, and the other way round."""
    against_exposure_first = sum(1 for f, lim in zip(frames, limits) if lim is None
                                 and f.gain > g_range[0] * (1 + AT_LIMIT)
                                 and f.exposure_us < t_range[1] * (1 - AT_LIMIT))
    against_gain_first = sum(1 for f, lim in zip(frames, limits) if lim is None
                             and f.exposure_us > t_range[0] * (1 + AT_LIMIT) and f.gain < g_range[1] * (1 - AT_LIMIT))
    evidence = {"frames_against_exposure_first": against_exposure_first,
                "frames_against_gain_first": against_gain_first}
    if against_exposure_first == against_gain_first:
        evidence["note"] = "the frames do not tell the order apart; exposure_first (the usual) assumed"
        return "exposure_first", evidence
    return ("exposure_first" if against_exposure_first < against_gain_first else "gain_first"), evidence


def _speed(frames, metered, target, tolerance, default) -> tuple[float, dict]:
    """Least squares through the origin of log(E[k+1]/E[k]) on log(target/metered[k]) over consecutive
    frames of one session whose metered level was off target."""
    order = sorted(range(len(frames)), key=lambda i: frames[i].order)
    xs, ys = [], []
    for a, b in zip(order[:-1], order[1:]):
        fa, fb = frames[a], frames[b]
        err = np.log(target / max(metered[a], 1e-6))
        if fa.order[0] == fb.order[0] and abs(err) > np.log1p(tolerance) and fb.product != fa.product:
            xs.append(err)
            ys.append(np.log(fb.product / fa.product))
    if len(xs) < 3:
        return default, {"fitted": False, "pairs": len(xs),
                         "note": "not fitted: needs a sequence of auto-exposed frames right after a light change"}
    xs, ys = np.array(xs), np.array(ys)
    speed = float(np.clip((xs @ ys) / (xs @ xs), 0.01, 1.0))
    return speed, {"fitted": True, "pairs": len(xs), "residual_log": float(np.sqrt(np.mean((ys - speed * xs) ** 2)))}
