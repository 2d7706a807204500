"""The colour correction from rendered to camera RGB, fitted on a ColorChecker seen in both.

Patches are compared in linear light: the real frame through the camera's response (sRGB when none
is known), the render through sRGB (renders are sRGB-encoded linear light). White balance comes from
the neutral patches, then colour-science's ``matrix_colour_correction`` candidates (Cheung 2004,
Finlayson 2015 root-polynomial, Vandermonde) are ranked by leave-one-patch-out CIE dE2000, and the
best is refitted on every usable patch. dE2000 is measured between display colours, before (the render
as it is) and after (the render through the fitted white balance, correction and response)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from isu_validate.errors import UserError
from isu_validate.srgb import srgb_decode, srgb_encode_float

from .chart import NEUTRALS, PATCHES
from .model import ColourCorrection, Response

CANDIDATES = [("Cheung 2004", {"terms": 3}), ("Cheung 2004", {"terms": 5}), ("Cheung 2004", {"terms": 7}),
              ("Finlayson 2015", {"degree": 2}), ("Vandermonde", {"degree": 1}), ("Vandermonde", {"degree": 2})]
MIN_PATCHES = 6


class SingularColourError(UserError, ValueError):
    """The usable patches cannot determine a colour correction."""


@dataclass
class ColourFit:
    correction: ColourCorrection
    white_balance: tuple[float, float, float]
    exposure_scale: float
    de2000_before: dict
    de2000_after: dict
    de2000_before_exposure_matched: dict
    cross_validation: dict

    def to_dict(self) -> dict:
        return {"method": self.correction.method, **self.correction.options,
                "matrix": self.correction.matrix.tolist(), "white_balance": list(self.white_balance),
                "exposure_scale": self.exposure_scale, "de2000_before": self.de2000_before,
                "de2000_after": self.de2000_after,
                "de2000_before_exposure_matched": self.de2000_before_exposure_matched,
                "cross_validation_de2000": self.cross_validation}


def de2000(display_a: np.ndarray, display_b: np.ndarray) -> np.ndarray:
    """CIE dE2000 between colours shown as sRGB (output levels 0..1)."""
    import colour
    lab = [colour.XYZ_to_Lab(colour.sRGB_to_XYZ(np.clip(x, 0, 1))) for x in (display_a, display_b)]
    return np.asarray(colour.delta_E(lab[0], lab[1], method="CIE 2000"))


def stats(values: np.ndarray) -> dict:
    return {"mean": float(np.mean(values)), "max": float(np.max(values)), "patches": int(len(values))}


def fit_colour(sim_linear: np.ndarray, real_levels: np.ndarray, usable: np.ndarray,
               response: Response | None = None) -> ColourFit:
    """sim_linear: (24, 3) rendered linear RGB; real_levels: (24, 3) camera output levels (0..1)."""
    if usable.sum() < MIN_PATCHES:
        raise SingularColourError(f"only {int(usable.sum())} chart patches are usable (at least {MIN_PATCHES} are "
                                  "needed); reshoot the chart evenly lit and not overexposed")
    to_linear = response.to_linear if response is not None else srgb_decode
    to_output = (lambda x: response.to_output(np.clip(x, 0, 1))) if response is not None else srgb_encode_float
    sim, real_lin = sim_linear[usable], to_linear(real_levels[usable])
    wb, scale = _white_balance(sim_linear, to_linear(real_levels), usable)
    source = sim * wb * scale
    _check_span(source)
    real = real_levels[usable]
    cv = {f"{m} {list(o.values())[0]}": _loo(source, real_lin, real, m, o, to_output) for m, o in CANDIDATES}
    finite = {k: v for k, v in cv.items() if np.isfinite(v)}
    if not finite:
        raise SingularColourError("no colour correction could be fitted to these patches (every candidate is "
                                  "singular on them); reshoot the chart with all patches visible")
    name = min(finite, key=finite.get)
    method, options = next((m, o) for m, o in CANDIDATES if f"{m} {list(o.values())[0]}" == name)
    matrix = _matrix(source, real_lin, method, options)
    after = to_output(_apply(source, matrix, method, options))
    before_matched = srgb_encode_float(sim * scale)
    correction = ColourCorrection(method, matrix, dict(options))
    return ColourFit(correction, tuple(float(v) for v in wb), float(scale),
                     stats(de2000(srgb_encode_float(sim), real)), stats(de2000(after, real)),
                     stats(de2000(before_matched, real)), {k: (float(v) if np.isfinite(v) else "singular")
                                                          for k, v in cv.items()})


def _white_balance(sim: np.ndarray, real: np.ndarray, usable: np.ndarray) -> tuple[np.ndarray, float]:
    """Per-channel gains from the neutral patches (G = 1) and one exposure scale matching their G."""
    idx = [i for i in range(PATCHES)[NEUTRALS] if usable[i] and sim[i].min() > 1e-3]
    if len(idx) < 2:
        idx = [i for i in range(PATCHES) if usable[i] and sim[i].min() > 1e-3]
    ratios = real[idx] / sim[idx]
    gains = np.median(ratios, axis=0)
    if not np.all(np.isfinite(gains)) or gains[1] <= 0:
        raise SingularColourError("the chart's neutral patches are black in the frame; reshoot it brighter")
    return gains / gains[1], float(gains[1])


def _check_span(source: np.ndarray) -> None:
    sv = np.linalg.svd(source, compute_uv=False)
    if sv[-1] < 1e-6 * sv[0]:
        raise SingularColourError(f"a colour matrix would be singular: the usable simulated patches do not span "
                                  f"three colour directions (singular values {np.round(sv, 6).tolist()}); the "
                                  "simulated chart must show the chart's colours (is it grey, or one colour?)")


def _matrix(source, target, method, options) -> np.ndarray:
    from colour.characterisation import matrix_colour_correction
    return np.asarray(matrix_colour_correction(source, target, method=method, **options), dtype=float)


def _apply(rgb, matrix, method, options) -> np.ndarray:
    from colour.characterisation import apply_matrix_colour_correction
    return np.asarray(apply_matrix_colour_correction(rgb, matrix, method=method, **options), dtype=float)


def _loo(source, target_lin, target_levels, method, options, to_output) -> float:
    """Mean dE2000 of each patch predicted by a correction fitted without it (inf when singular)."""
    n = len(source)
    terms = _expanded(source, method, options).shape[-1]
    if n - 1 < terms + 2:
        return float("inf")
    errors = []
    for i in range(n):
        keep = np.arange(n) != i
        if np.linalg.matrix_rank(_expanded(source[keep], method, options), tol=1e-8) < terms:
            return float("inf")
        m = _matrix(source[keep], target_lin[keep], method, options)
        predicted = to_output(_apply(source[i:i + 1], m, method, options))
        errors.append(float(de2000(predicted, target_levels[i:i + 1])[0]))
    return float(np.mean(errors))


def _expanded(source, method, options) -> np.ndarray:
    from colour.characterisation import polynomial_expansion
    return np.asarray(polynomial_expansion(source, method, **options), dtype=float)
