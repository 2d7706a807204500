"""Sensor effects: what a real camera does to a picture that a clean render lacks (exposure and white-balance
error, vignetting, blur, noise, JPEG compression), applied to a finished 8-bit frame with a per-image
seeded strength, for training data (``dataset --sensor-effects``, ``reference train --sensor-effects``).

A spec is a named recipe and/or ``KEY=VALUE`` maxima: ``mild``, ``strong``, ``mild,jpeg=0.6`` or
``noise=0.02,blur=1``. Each image draws every effect's strength uniformly between nothing and its maximum
(exposure and white balance either way), records it, and applies it in the order a camera would: light
(exposure, white balance, vignetting, in linear light), optics (Gaussian blur), sensor (noise), then the
encoder (JPEG). A zero maximum leaves the image as it was, byte for byte. The ops are OpenCV's (blur, the
JPEG codec) and numpy's; the draws come from the caller's numpy Generator, so a seed gives the same image.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

from ..errors import InputError
from .strength import strength

# what each maximum means (the units a user writes)
MEANING = {"exposure": "stops either way", "white_balance": "relative gain of red and blue, either way",
           "vignette": "share of light lost at the corners", "blur": "Gaussian sigma, px",
           "noise": "Gaussian sigma, share of full scale", "jpeg": "JPEG quality lost (0: 100, 1: 20)"}
LIMITS = {"exposure": 2.0, "white_balance": 0.3, "vignette": 0.8, "blur": 4.0, "noise": 0.1, "jpeg": 1.0}
RECIPES = {
    "none": {},
    # an in-cabin camera in ordinary use: a little of everything
    "mild": {"exposure": 0.3, "white_balance": 0.05, "vignette": 0.2, "blur": 0.7, "noise": 0.012, "jpeg": 0.4},
    # a cheap or badly set camera
    "strong": {"exposure": 0.7, "white_balance": 0.12, "vignette": 0.45, "blur": 1.6, "noise": 0.03, "jpeg": 0.8},
}
WORST_JPEG_QUALITY = 20


@dataclass(frozen=True)
class SensorEffects:
    """The largest strength of each effect (0: never applied)."""
    exposure: float = 0.0
    white_balance: float = 0.0
    vignette: float = 0.0
    blur: float = 0.0
    noise: float = 0.0
    jpeg: float = 0.0

    @property
    def active(self) -> bool:
        return any(getattr(self, f.name) for f in fields(self))

    @property
    def text(self) -> str:
        """The canonical spec, every maximum spelt out (what settings and cards record); "" when off."""
        return ",".join(f"{f.name}={getattr(self, f.name):g}" for f in fields(self)) if self.active else ""

    def draw(self, rng) -> dict:
        """This image's strengths (one draw per effect, in a fixed order, whether or not it is active)."""
        u = rng.uniform(0.0, 1.0, 8)
        return {"exposure_stops": round(self.exposure * (2 * u[0] - 1), 4),
                "white_balance": [round(self.white_balance * (2 * u[1] - 1), 4),
                                  round(self.white_balance * (2 * u[2] - 1), 4)],   # red, blue gains - 1
                "vignette": round(self.vignette * u[3], 4), "blur_sigma": round(self.blur * u[4], 4),
                "noise_sigma": round(self.noise * u[5], 5),
                "jpeg_quality": round(100 - (100 - WORST_JPEG_QUALITY) * self.jpeg * u[6]) if self.jpeg else None,
                "noise_seed": int(u[7] * 2**31)}

    def apply(self, bgr, rng):
        """(the 8-bit BGR image with this image's effects, the strengths drawn)."""
        drawn = self.draw(rng)
        return apply_drawn(bgr, drawn), drawn


def apply_drawn(bgr, drawn: dict):
    """An 8-bit BGR image through the effects ``drawn`` (``SensorEffects.draw``'s numbers) in a camera's order."""
    import cv2
    import numpy as np

    from ..srgb import srgb_encode, srgb_to_linear

    image = bgr
    gain_r, gain_b = (1.0 + g for g in drawn["white_balance"])
    if drawn["exposure_stops"] or drawn["vignette"] or gain_r != 1.0 or gain_b != 1.0:
        linear = srgb_to_linear(image.astype(np.float64) / 255.0)
        linear *= 2.0 ** drawn["exposure_stops"] * np.array([gain_b, 1.0, gain_r])
        if drawn["vignette"]:
            linear *= _vignette(image.shape[:2], drawn["vignette"])[..., None]
        image = srgb_encode(linear)
    if drawn["blur_sigma"] > 0:
        image = cv2.GaussianBlur(image, (0, 0), drawn["blur_sigma"])
    if drawn["noise_sigma"] > 0:
        noise = np.random.default_rng(drawn["noise_seed"]).normal(0.0, drawn["noise_sigma"] * 255.0, image.shape)
        image = np.clip(np.rint(image + noise), 0, 255).astype(np.uint8)
    if drawn["jpeg_quality"] is not None and drawn["jpeg_quality"] < 100:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(drawn["jpeg_quality"])])
        image = cv2.imdecode(data, cv2.IMREAD_COLOR) if ok else image
    return image


def _vignette(shape: tuple[int, int], strength: float):
    """Light kept per pixel: 1 at the centre falling as the square of the radius to 1 - strength at the corners."""
    import numpy as np

    h, w = shape
    y, x = np.mgrid[0:h, 0:w]
    r2 = ((x - (w - 1) / 2) ** 2 + (y - (h - 1) / 2) ** 2) / (((w - 1) / 2) ** 2 + ((h - 1) / 2) ** 2 or 1.0)
    return 1.0 - strength * r2


def apply_to_file(path, effects: SensorEffects, rng) -> dict:
    """Rewrite the PNG at ``path`` with its effects; the strengths drawn."""
    import cv2

    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise OSError(f"cannot read the rendered frame {path}")
    out, drawn = effects.apply(image, rng)
    if not cv2.imwrite(str(path), out):
        raise OSError(f"cannot write {path}")
    return drawn


def parse_sensor_effects(text: str | None) -> SensorEffects:
    """``mild`` | ``strong`` | ``none`` and/or ``KEY=VALUE`` maxima, comma-separated (later ones win) ->
    SensorEffects; InputError names the fix."""
    if not text or not text.strip():
        return SensorEffects()
    values: dict[str, float] = {}
    for part in (p.strip() for p in text.split(",")):
        key, sep, value = part.partition("=")
        if not sep:
            if part not in RECIPES:
                raise InputError(f"--sensor-effects {text!r}: unknown recipe {part!r}; recipes: "
                                 f"{', '.join(RECIPES)}, or KEY=VALUE with KEY one of {', '.join(LIMITS)}")
            values.update(RECIPES[part])
            continue
        if key not in LIMITS:
            raise InputError(f"--sensor-effects {text!r}: unknown effect {key!r}; effects: "
                             + ", ".join(f"{k} ({MEANING[k]})" for k in LIMITS))
        values[key] = strength("--sensor-effects", text, key, value, LIMITS[key], MEANING[key])
    return SensorEffects(**values)
