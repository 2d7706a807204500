"""``exposure fit``: frames with sidecars -> the camera's response, auto-exposure, noise (and sensitivity).

Each part is fitted from the frames that can determine it; a part the frames cannot determine keeps
what the camera file had, or is reported as underdetermined with what to capture."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from isu_validate.errors import InputError, InputNotFound

from . import frames as frames_mod
from .apply import auto_expose, forward_curve
from .metering import meter_frame
from .exposure_fit import fit_auto_exposure
from .model import AutoExposure, ImagingModel, Response
from .noise_fit import NOISE_ADVICE, fit_noise
from .response_fit import UnderdeterminedError, fit_response

MID_GREY = 0.18


@dataclass
class FitResult:
    model: ImagingModel
    warnings: list[str] = field(default_factory=list)
    predictions: list[dict] = field(default_factory=list)     # per auto-exposed frame: measured vs predicted

    def summary(self) -> dict:
        m = self.model
        out = {"warnings": self.warnings, "predictions": self.predictions}
        if m.exposure is not None:
            ae = m.exposure
            out["exposure"] = {"target": ae.target, "metering": ae.metering, "centre_sigma": ae.centre_sigma,
                               "exposure_us": list(ae.exposure_us), "gain": list(ae.gain), "order": ae.order,
                               "speed": ae.speed, "tolerance": ae.tolerance, "sensitivity": ae.sensitivity,
                               "target_relative_std": ae.fit.get("target_residual", {}).get("relative_std"),
                               "sensitivity_from": ae.fit.get("sensitivity_from")}
        if m.response is not None and m.response.fit:
            out["response"] = {"residual_codes": m.response.fit.get("residual_codes", {}).get("rms"),
                               "frames": len(m.response.fit.get("frames", []))}
        if m.noise is not None:
            out["noise"] = {"shot": m.noise.shot, "read": m.noise.read,
                            "relative_rms_residual": m.noise.fit.get("relative_rms_residual")}
        return out


def fit_camera(inputs, base: ImagingModel | None = None, exposure_us=None, gain=None, roi=None,
               sim_dir: str | Path | None = None) -> FitResult:
    base = base or ImagingModel()
    data = frames_mod.load(inputs)
    warnings = data.warnings()
    if not data.frames:
        raise UnderdeterminedError("no usable frame: " + "; ".join(warnings or ["none given"]))
    response, why_response = _response(data, base, warnings)
    ae = _auto_exposure(data, response, base, exposure_us, gain, roi, warnings)
    if ae is None and why_response:
        raise UnderdeterminedError(f"nothing to fit: {why_response}; and no auto-exposed frames under two or more "
                                   "light levels")
    noise = fit_noise(data.frames, response)
    if noise is None:
        warnings.append(f"noise not fitted (no repeated frames at one setting); {NOISE_ADVICE}")
        noise = base.noise
    if ae is not None:
        ae = _with_sensitivity(ae, data.auto, response, base, sim_dir, warnings)
    model = replace(base, exposure=ae or base.exposure, response=response, noise=noise)
    predictions = predict_frames(model, data.auto) if model.exposure is not None else []
    return FitResult(model, warnings, predictions)


def _response(data, base: ImagingModel, warnings: list[str]) -> tuple[Response, str]:
    try:
        fitted = fit_response(data.frames)
    except UnderdeterminedError as exc:
        if base.response is None:
            raise
        warnings.append(f"response kept from the camera file ({exc})")
        return base.response, str(exc)
    wb = base.response.white_balance if base.response is not None else (1.0, 1.0, 1.0)
    return replace(fitted, white_balance=wb), ""


def _auto_exposure(data, response, base, exposure_us, gain, roi, warnings) -> AutoExposure | None:
    try:
        return fit_auto_exposure(data.auto, response, base.exposure, exposure_us, gain, roi)
    except UnderdeterminedError as exc:
        if not data.auto and base.exposure is not None:
            warnings.append("auto-exposure kept from the camera file (no auto-exposed frames given)")
            return base.exposure
        if not data.auto:
            warnings.append(f"auto-exposure not fitted: {exc}")
            return None
        raise


def _with_sensitivity(ae: AutoExposure, auto, response, base, sim_dir, warnings) -> AutoExposure:
    """Sensor signal per render-linear unit and second: from renders of the captured scenes when given
    (``SIM_DIR/<frame stem>.exr``), else kept from the camera file, else assumed (a mid-grey render needs
    the middle of the exposure range) with a warning."""
    if sim_dir:
        value, detail = _sensitivity_from_renders(auto, response, Path(sim_dir))
        return replace(ae, sensitivity=value, fit={**ae.fit, "sensitivity_from": detail})
    if base.exposure is not None and base.exposure.fit.get("sensitivity_from", "").startswith("renders"):
        return replace(ae, sensitivity=base.exposure.sensitivity,
                       fit={**ae.fit, "sensitivity_from": base.exposure.fit["sensitivity_from"]})
    signal = float(response.to_linear(np.full((1, 3), ae.target))[0, 1])
    mid = float(np.sqrt(ae.product_range[0] * ae.product_range[1]))
    warnings.append("sensitivity assumed (a mid-grey render meters to the target at the middle of the exposure "
                    "range); pass --sim DIR with a linear render (.exr) of each captured scene to fit it")
    return replace(ae, sensitivity=signal / (MID_GREY * mid * 1e-6),
                   fit={**ae.fit, "sensitivity_from": "assumed: mid grey at the middle of the exposure range"})


def _sensitivity_from_renders(auto, response, sim_dir: Path) -> tuple[float, str]:
    from .develop import read_linear
    ratios, used = [], []
    for f in auto:
        exr = sim_dir / f"{f.path.stem}.exr"
        if not exr.exists():
            continue
        sim = read_linear(exr)
        if sim.shape[:2] != f.image.shape[:2]:
            raise InputError(f"{exr} is {sim.shape[1]}x{sim.shape[0]} but {f.path} is "
                             f"{f.image.shape[1]}x{f.image.shape[0]}; render at the camera's resolution")
        ok = (f.image.max(axis=2) < 0.95) & (f.image.min(axis=2) > 0.03)
        real = response.to_linear(f.image)[ok][:, 1].mean() / (f.product * 1e-6)
        ratios.append(real / max(float(sim[ok][:, 1].mean()), 1e-9))
        used.append(exr.name)
    if not ratios:
        raise InputNotFound(f"--sim {sim_dir}: no render named like an auto-exposed frame (<frame stem>.exr)")
    return float(np.median(ratios)), f"renders: {len(used)} pairs, spread {float(np.std(np.log(ratios))):.3f} (log)"


def predict_frames(model: ImagingModel, auto) -> list[dict]:
    """Measured against predicted exposure and brightness per auto-exposed frame: the frame's scene,
    recovered through the response, metered and exposed by the fitted auto-exposure."""
    ae, response = model.exposure, model.curve
    curve = forward_curve(response)
    out = []
    for f in auto:
        scene = response.to_linear(f.image) / (f.product * 1e-6 * ae.sensitivity)
        chosen = auto_expose(scene, ae, curve)
        measured = meter_frame(f.image, response, ae.metering, ae.centre_sigma, ae.roi)
        out.append({"frame": f.path.name, "measured_product": f.product,
                    "predicted_product": chosen.exposure_us * chosen.gain, "measured_level": measured,
                    "predicted_level": chosen.metered,
                    "residual_log_product": float(np.log(chosen.exposure_us * chosen.gain / f.product))})
    return out


def plot_predictions(result: FitResult, out: str | Path) -> Path:
    """Measured against predicted exposure product and metered level per frame, with the residual."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result.predictions
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    if p:
        mp, pp = [r["measured_product"] for r in p], [r["predicted_product"] for r in p]
        axes[0].loglog(mp, pp, "o")
        lim = [min(mp + pp) * 0.8, max(mp + pp) * 1.25]
        axes[0].plot(lim, lim, "k--", lw=1)
        rms = float(np.sqrt(np.mean([r["residual_log_product"] ** 2 for r in p])))
        axes[0].set_title(f"exposure x gain (us): RMS log residual {rms:.3f}")
        ml, pl = [r["measured_level"] for r in p], [r["predicted_level"] for r in p]
        axes[1].plot(ml, pl, "o")
        axes[1].plot([0, 1], [0, 1], "k--", lw=1)
        axes[1].set_title(f"metered level: RMS residual {float(np.sqrt(np.mean((np.array(ml) - pl) ** 2))):.4f}")
    axes[0].set_xlabel("measured (sidecar)")
    axes[0].set_ylabel("predicted (fitted model)")
    axes[1].set_xlabel("measured")
    axes[1].set_ylabel("predicted")
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out
