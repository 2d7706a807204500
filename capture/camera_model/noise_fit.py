"""Shot and read noise from repeated frames of a still scene at fixed settings.

The difference of two frames taken at the same settings holds only temporal noise (the scene cancels):
its variance per brightness bin, taken back through the response curve to the linear signal, is fitted
with variance = shot * gain * s + read^2 * gain^2 (non-negative least squares), the simplest model that
fits sensors with a photon and a readout term."""
from __future__ import annotations

from collections import defaultdict

import numpy as np
from scipy.optimize import nnls

from .frames import Frame
from .model import CODES, Noise, Response

BINS = 24
MIN_PIXELS = 200
QUANTISATION = 1.0 / 12.0 / (CODES - 1) ** 2      # variance of 8-bit rounding, in output levels

NOISE_ADVICE = ("capture 2 or more frames of a still scene at the same manual exposure and gain (e.g. "
                "`isu-validate capture shoot --frames 4 --exposure-us 2000 --iso 100`), ideally at two gains")


def repeat_groups(frames: list[Frame]) -> list[list[Frame]]:
    groups: dict[tuple, list[Frame]] = defaultdict(list)
    for f in frames:
        if not f.auto:
            groups[(str(f.path.parent), round(f.exposure_us, 3), round(f.gain, 4))].append(f)
    return [g for g in groups.values() if len(g) >= 2]


def variance_samples(groups: list[list[Frame]], response: Response) -> np.ndarray:
    """(signal, gain, variance) per brightness bin and channel, in linear signal units."""
    rows = []
    slope = np.gradient(response.linear, axis=0) * (CODES - 1)        # d signal / d output level
    for group in groups:
        for a, b in zip(group[:-1], group[1:]):
            mean, diff = (a.image + b.image) / 2.0, a.image - b.image
            for c in range(3):
                m, d = mean[..., c].ravel(), diff[..., c].ravel()
                keep = (m > 0.03) & (m < 0.92)
                edges = np.linspace(0.03, 0.92, BINS + 1)
                idx = np.digitize(m[keep], edges) - 1
                for k in range(BINS):
                    sel = d[keep][idx == k]
                    if sel.size < MIN_PIXELS:
                        continue
                    level = float(m[keep][idx == k].mean())
                    var_out = max(float(sel.var()) / 2.0 - QUANTISATION, 0.0)
                    code = int(round(level * (CODES - 1)))
                    signal = float(np.interp(level, np.arange(CODES) / (CODES - 1), response.linear[:, c]))
                    rows.append((signal, a.gain, var_out * slope[code, c] ** 2))
    return np.array(rows).reshape(-1, 3)


def fit_noise(frames: list[Frame], response: Response) -> Noise | None:
    """None when no repeated frames were captured (the camera then renders without noise)."""
    groups = repeat_groups(frames)
    if not groups:
        return None
    data = variance_samples(groups, response)
    if len(data) < 3:
        return None
    s, g, v = data.T
    design = np.column_stack([g * s, g ** 2])
    weights = 1.0 / np.maximum(v, 1e-12)              # relative errors: bright and dark bins count alike
    coef, _ = nnls(design * weights[:, None] ** 0.5, v * weights ** 0.5)
    shot, read2 = coef
    predicted = design @ coef
    rel = (predicted - v) / np.maximum(v, 1e-12)
    fit = {"frames": sum(len(x) for x in groups), "groups": [[str(f.path) for f in x] for x in groups],
           "gains": sorted({float(x) for x in g}), "bins": int(len(v)),
           "relative_rms_residual": float(np.sqrt(np.mean(rel ** 2))),
           "samples": [{"signal": float(a), "gain": float(b), "variance": float(c), "predicted": float(d)}
                       for a, b, c, d in zip(s, g, v, predicted)]}
    return Noise(shot=float(shot), read=float(np.sqrt(read2)), fit=fit)
