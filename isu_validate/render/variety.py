"""Variety for training data: a renderer whose every scene is seen through its own jittered camera
(``camera_jitter``) and developed with its own sensor effects (``sensor_effects``), both drawn from a seed
and the scene, so a scene renders the same in any process, order or resume.

``VariedRenderer`` wraps a ``BlenderRenderer`` behind the same ``Renderer`` protocol: the dataset's slots
and the reference ISU's training sets use it; the search never does (its frames are the camera file's).
The render's label (its ``camera``, boxes, ``up``, visibility) is the jittered camera's, since the renderer
renders through it; ``RenderResult.variety`` and the label's ``variety`` say what was drawn.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from ..errors import InputError
from .camera_jitter import CameraJitter, parse_camera_jitter
from .sensor_effects import SensorEffects, apply_to_file, parse_sensor_effects

_JITTER_STREAM, _EFFECTS_STREAM = 1, 2


@dataclass(frozen=True)
class Variety:
    """What varies per scene and the seed the draws start from."""
    jitter: CameraJitter = CameraJitter()
    effects: SensorEffects = SensorEffects()
    seed: int = 0

    @classmethod
    def parse(cls, camera_jitter: str | None, sensor_effects: str | None, seed: int) -> "Variety":
        return cls(parse_camera_jitter(camera_jitter), parse_sensor_effects(sensor_effects), int(seed))

    @property
    def active(self) -> bool:
        return self.jitter.active or self.effects.active

    def describe(self) -> dict:
        """For settings, cards and cache keys: the canonical specs and the seed ({} when nothing varies)."""
        if not self.active:
            return {}
        return {"camera_jitter": self.jitter.text, "sensor_effects": self.effects.text, "seed": self.seed,
                "per_scene": "numpy Generator(SeedSequence([seed, stream, sha256(scene key)])): stream 1 the "
                             "camera, 2 the effects"}

    def rng(self, scene_key: str, stream: int):
        import numpy as np

        digest = hashlib.sha256(scene_key.encode()).digest()
        words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4)]
        return np.random.default_rng(np.random.SeedSequence([self.seed, stream, *words]))


class VariedRenderer:
    """A renderer that jitters its camera and applies sensor effects per scene (the ``Renderer`` protocol)."""

    def __init__(self, renderer, variety: Variety):
        if variety.jitter.active and not hasattr(renderer, "use_camera"):
            raise InputError(f"--camera-jitter needs a renderer that can move its camera; "
                             f"{type(renderer).__name__} cannot")
        self.inner = renderer
        self.variety = variety
        self.space = renderer.space
        self.rig = getattr(renderer, "rig", None)   # the camera file's camera: every jitter starts from it

    def camera_for(self, canonical: Mapping[str, Any]):
        """(the scene's camera, what was drawn); the rig itself when nothing jitters."""
        if not self.variety.jitter.active:
            return self.rig, {}
        return self.variety.jitter.draw(self.rig, self.variety.rng(self.space.key(canonical), _JITTER_STREAM))

    def render(self, scene: Mapping[str, Any], out: Path):
        canonical = self.space.check(scene)
        camera, jitter = self.camera_for(canonical)
        if self.variety.jitter.active:
            self.inner.use_camera(camera)
        result = self.inner.render(canonical, out)   # RenderError passes through: the frame is unusable
        drawn = {}
        if jitter:
            drawn["camera"] = jitter
        if self.variety.effects.active:
            drawn["sensor"] = apply_to_file(result.image, self.variety.effects,
                                            self.variety.rng(self.space.key(canonical), _EFFECTS_STREAM))
        result.variety = drawn
        label = result.channels.get("label")
        if label is not None and Path(label).exists():
            data = json.loads(Path(label).read_text())
            Path(label).write_text(json.dumps({**data, "variety": {**self.variety.describe(), **drawn}}, indent=1))
        return result

    def cache_key(self, canonical: Mapping[str, Any]) -> str:
        """The inner renderer's key through this scene's camera, with the effects: what decides the image."""
        camera, _ = self.camera_for(canonical)
        if self.variety.jitter.active:
            self.inner.use_camera(camera)
        inner = self.inner.cache_key(canonical) if hasattr(self.inner, "cache_key") else self.space.key(canonical)
        blob = json.dumps([inner, self.variety.describe()], sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()

    def close(self) -> None:
        self.inner.close()


def vary(renderer, variety: Variety):
    """``renderer`` itself when nothing varies (its frames and cache keys as before), else a VariedRenderer."""
    return VariedRenderer(renderer, variety) if variety.active else renderer
