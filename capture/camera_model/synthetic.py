"""Synthetic cameras with known auto-exposure, response, noise and colour: the ground truth of the tests
and of ``bench exposure``. A synthetic camera records linear scenes through ``apply`` (the same forward
model the renderer uses), and writes frames with sidecars exactly as ``capture shoot`` does."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from .apply import apply  # noqa: F401 (re-exported for tests and the bench)
from .model import CODES, AutoExposure, ColourCorrection, ImagingModel, Noise, Response


def shoulder_response(gamma: float = 2.2, shoulder: float = 0.35, white_balance=(1.0, 1.0, 1.0)) -> Response:
    """A tone curve unlike sRGB: a power law with a soft shoulder, out = (1+a) p / (1 + a p), p = s^(1/gamma)."""
    s = np.linspace(0.0, 1.0, 20001)
    p = s ** (1.0 / gamma)
    out = (1 + shoulder) * p / (1 + shoulder * p)
    codes = np.arange(CODES) / (CODES - 1)
    linear = np.interp(codes, out, s)
    return Response(np.repeat(linear[:, None], 3, axis=1), tuple(white_balance))


# rendered linear RGB -> camera linear RGB: channel crosstalk of a real sensor (rows sum to 1)
CROSSTALK = np.array([[0.78, 0.17, 0.05], [0.12, 0.76, 0.12], [0.04, 0.22, 0.74]])


def camera(seed: int = 0, **overrides) -> ImagingModel:
    """The bench's reference camera (an in-cabin camera: 16.6 ms exposure cap, up to 16x gain)."""
    ae = AutoExposure(target=0.42, exposure_us=(40.0, 16600.0), gain=(1.0, 16.0), order="exposure_first",
                      metering="centre", centre_sigma=0.25, sensitivity=900.0, speed=0.6, tolerance=0.02)
    model = ImagingModel(ae, shoulder_response(white_balance=(1.25, 1.0, 0.8)), Noise(shot=4e-4, read=2e-3),
                         ColourCorrection("Cheung 2004", CROSSTALK.copy()), source=f"synthetic:{seed}")
    return model.with_part(**overrides) if overrides else model


def scene(rng: np.random.Generator, size=(480, 640), bright_at: float | None = None) -> np.ndarray:
    """A cabin-like linear scene (render units, mid grey ~0.18): smooth shading, objects of varied albedo,
    one bright window whose place moves the brightness around the frame (so metering modes differ)."""
    h, w = size
    y, x = np.mgrid[0:h, 0:w] / np.array([h, w])[:, None, None]
    base = 0.12 + 0.1 * np.sin(3 * x + rng.uniform(0, 6)) * np.cos(2 * y + rng.uniform(0, 6))
    img = np.repeat(base[..., None], 3, axis=2) * rng.uniform(0.8, 1.2, 3)
    for _ in range(12):
        x0, y0 = rng.uniform(0, 0.85, 2)
        dx, dy = rng.uniform(0.05, 0.3, 2)
        mask = (x >= x0) & (x < x0 + dx) & (y >= y0) & (y < y0 + dy)
        img[mask] = rng.uniform(0.03, 0.7, 3)
    cx = rng.uniform(0.05, 0.95) if bright_at is None else bright_at
    window = (np.abs(x - cx) < 0.12) & (y < 0.45)
    img[window] = rng.uniform(1.5, 4.0)
    return img.astype(np.float32)


def shoot(model: ImagingModel, linear: np.ndarray, seed: int, manual=None) -> tuple[np.ndarray, dict]:
    """One frame (8-bit RGB) and its sidecar, as ``capture shoot`` writes it."""
    image, exposure = apply(linear, model, seed=seed, manual=manual)
    meta = {"device": "synthetic", "source": model.source, "exposure_us": exposure.exposure_us,
            "iso": exposure.gain * 100.0, "gain": None, "auto_exposure": manual is None, "sequence": seed}
    return image, meta


def write_frame(folder: Path, name: str, image: np.ndarray, meta: dict | None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.png"
    cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    if meta is not None:
        path.with_suffix(".json").write_text(json.dumps({**meta, "frame": path.name}, indent=1))
    return path


def capture_set(model: ImagingModel, out: Path, seed: int = 0, light_levels=(0.02, 0.1, 0.4, 1.0, 3.0),
                scenes_per_level: int = 2, bracket=(250.0, 500.0, 1000.0, 2000.0, 4000.0, 8000.0, 16000.0),
                repeats: int = 4, size=(240, 320), per_exposure: int = 3) -> dict[str, list[Path]]:
    """What a technician captures to fit a camera: auto-exposed frames under several light levels,
    an exposure bracket of one still scene, and repeated frames at fixed settings (noise)."""
    rng = np.random.default_rng(seed)
    paths = {"auto": [], "bracket": [], "repeats": []}
    k = 0
    for light in light_levels:
        for _ in range(scenes_per_level):
            k += 1
            image, meta = shoot(model, scene(rng, size) * light, seed * 1000 + k)
            paths["auto"].append(write_frame(out / "auto", f"frame_{k:04d}", image, meta))
    still = scene(rng, size) * 0.25
    for i, t in enumerate(bracket):
        for j in range(per_exposure):
            image, meta = shoot(model, still, seed * 1000 + 500 + i * per_exposure + j, manual=(t, 1.0))
            paths["bracket"].append(write_frame(out / "bracket", f"frame_{i:02d}_{j}", image, meta))
    for gain in (1.0, 4.0):
        for r in range(repeats):
            image, meta = shoot(model, still, seed * 1000 + 700 + int(gain) * 10 + r, manual=(1500.0, gain))
            paths["repeats"].append(write_frame(out / f"repeats-gain{gain:g}", f"frame_{r:04d}", image, meta))
    return paths


def chart_scene(rng: np.random.Generator, size=(480, 640), corners=None, light: float = 1.0,
                plain: bool = False) -> np.ndarray:
    """A linear scene with a ColorChecker on it: ``corners`` (4x2 pixels, clockwise from the chart's top-left)
    or a random placement (a quarter to half the frame wide, tilted, rotated a little); on a cabin-like
    background, or a plain grey one."""
    from .chart import chart_image
    chart = chart_image()
    h, w = size
    if corners is None:
        width = rng.uniform(0.25, 0.5) * w
        cx, cy = rng.uniform(0.3, 0.7) * w, rng.uniform(0.35, 0.65) * h
        angle = np.radians(rng.uniform(-12, 12))
        half = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * [width / 2, width / 3]
        half = half * (1 + rng.uniform(-0.08, 0.08, (4, 1)))          # perspective: uneven corners
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        corners = half @ rot.T + [cx, cy]
    ch, cw = chart.shape[:2]
    hom = cv2.getPerspectiveTransform(np.float32([[0, 0], [cw, 0], [cw, ch], [0, ch]]), np.float32(corners))
    warped = cv2.warpPerspective(chart, hom, (w, h), flags=cv2.INTER_AREA)
    cover = cv2.warpPerspective(np.ones((ch, cw), np.float32), hom, (w, h), flags=cv2.INTER_AREA)[..., None]
    background = np.full((h, w, 3), 0.25, np.float32) if plain else scene(rng, size) * 0.6
    return ((background * (1 - cover) + warped) * light).astype(np.float32)
