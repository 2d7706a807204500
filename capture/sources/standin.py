"""A stand-in for a camera where no car is at hand: the pair's scene rendered another way.

Not a photograph. The scene of a pair (``--pair``) is rendered through another camera rig
(``rigs/cameras/standin.toml`` unless named), under another sky (``standin_cabin``: a different
studio-light environment and window light), then given a sensor's gain and noise. It lets the RQ3
workflow (capture with the alignment aid, style transfer, ``agree``) run end to end in tests and demos;
every sidecar says ``"stand_in": true`` and what made the frame. One render per session; each frame
gets its own noise. The render itself is the command's (``capture shoot``/``align`` build it from the
renderer and close it): capture never opens Blender.
"""
from __future__ import annotations

import copy
import datetime as _dt
import shutil
import tempfile
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from .base import DeviceNotFound, ExposureRequest, Frame, FrameSource

DEFAULT_RIG = "standin"
PRESET = "draft"
ENVIRONMENT = "sunset"        # one sky for every scene (the default cabin changes it with the light): other light
LIGHT_SCALE = 0.7             # window, sky and sun light relative to the cabin rig
GAIN = 0.9                    # a slightly darker exposure than the render
NOISE_SIGMA = 5.0             # sensor noise, 8-bit levels


# render(rig, out): the pair's scene rendered at PRESET through camera rig ``rig``, in a cabin under
# ``standin_cabin``'s light, to the PNG ``out`` (its folder also takes Blender's log); returns the image path
RenderScene = Callable[[str, Path], Path]


def standin_cabin(cabin: dict) -> dict:
    """A copy of the cabin rig ``cabin`` under the stand-in's sky: another environment, dimmer light."""
    cabin = copy.deepcopy(cabin)
    light = cabin["lighting"]
    light["environment"] = ENVIRONMENT
    for key in ("environment_strength", "window_light_w", "sun_strength"):
        if key in light:
            light[key] = {level: value * LIGHT_SCALE for level, value in light[key].items()}
    return cabin


class StandInSource(FrameSource):
    def __init__(self, target: str, render: RenderScene | None, seed: int = 0):
        self.rig = target or DEFAULT_RIG
        self.spec = f"standin:{self.rig}"
        self.render, self.preset, self.seed = render, PRESET, seed
        self._image: np.ndarray | None = None
        self._tmp: Path | None = None
        self._index = 0

    def open(self) -> None:
        if self.render is None:
            raise DeviceNotFound("the stand-in source renders a pair's scene: use it with --pair PAIRS/<sample>")
        self._tmp = Path(tempfile.mkdtemp(prefix="isu-standin-"))
        self.environment = ENVIRONMENT

    def set_exposure(self, request: ExposureRequest) -> list[str]:
        return ["stand-in: exposure settings are ignored (a render has no shutter)"] if (
            request.manual or request.auto) else []

    def read(self) -> Frame:
        if self._image is None:
            image = self.render(self.rig, self._tmp / "standin.png")
            self._image = cv2.imread(str(image), cv2.IMREAD_COLOR)
        rng = np.random.default_rng([self.seed, self._index])
        noisy = self._image.astype(np.float32) * GAIN + rng.normal(0.0, NOISE_SIGMA, self._image.shape)
        image = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
        h, w = image.shape[:2]
        meta = {"device": "stand-in render (not a camera)", "source": self.spec, "stand_in": True,
                "camera_rig": self.rig, "environment": self.environment, "light_scale": LIGHT_SCALE,
                "gain": GAIN, "noise_sigma": NOISE_SIGMA, "noise_seed": [self.seed, self._index],
                "preset": self.preset, "resolution": [w, h], "exposure_us": None, "iso": None,
                "timestamp": _dt.datetime.now(_dt.timezone.utc).isoformat()}
        self._index += 1
        return Frame(image, meta)

    def close(self) -> None:
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
