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

from ..atomic import write_json
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

    def spec(self) -> dict:
        """What decides the draws (cache keys hash this): the canonical specs and the seed ({} when nothing
        varies). Wording about them lives in ``describe`` only, so rewording never changes a key."""
        if not self.active:
            return {}
        return {"camera_jitter": self.jitter.text, "sensor_effects": self.effects.text, "seed": self.seed}

    def describe(self) -> dict:
        """For settings and cards: ``spec`` and how each scene's draws follow from it."""
        if not self.active:
            return {}
        return {**self.spec(), "per_scene": "numpy Generator(SeedSequence([seed, stream, sha256(scene key)])): "
                                            "stream 1 the camera, 2 the effects"}

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
        self._drawn: tuple[str, Any, dict] | None = None   # (scene key, camera, draw): cache_key's, for render

    def camera_for(self, canonical: Mapping[str, Any]):
        """(the scene's camera, what was drawn); the rig itself when nothing jitters. Drawn once per scene:
        ``cache_key`` and then ``render`` of the same scene share the draw."""
        if not self.variety.jitter.active:
            return self.rig, {}
        key = self.space.key(canonical)
        if self._drawn is None or self._drawn[0] != key:
            self._drawn = (key, *self.variety.jitter.draw(self.rig, self.variety.rng(key, _JITTER_STREAM)))
        return self._drawn[1], self._drawn[2]

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
            write_json(label, {**data, "variety": {**self.variety.describe(), **drawn}}, indent=1)
        return result

    def cache_key(self, canonical: Mapping[str, Any]) -> str:
        """The inner renderer's key through this scene's camera, with the effects: what decides the image."""
        camera, _ = self.camera_for(canonical)
        if self.variety.jitter.active:
            self.inner.use_camera(camera)
        inner = self.inner.cache_key(canonical) if hasattr(self.inner, "cache_key") else self.space.key(canonical)
        blob = json.dumps([inner, self.variety.spec()], sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()

    def close(self) -> None:
        self.inner.close()


def card_lines(described: dict) -> list[str]:
    """The variety of a set, for dataset and model cards alike (``Variety.describe()``): one bullet each."""
    return [f"- camera jitter: `{described['camera_jitter'] or 'none'}` (uniform per axis: shift in metres along "
            "the cabin's axes, turn in degrees about the camera's own, focal length relative); the labels (boxes, "
            "masks, `up`, visibility) are the jittered camera's",
            f"- sensor effects: `{described['sensor_effects'] or 'none'}` (each image draws every strength between "
            "none and its maximum; applied after rendering: exposure, white balance, vignetting, blur, noise, JPEG)",
            f"- seed {described['seed']}; per scene: {described['per_scene']}"]


def vary(renderer, variety: Variety):
    """``renderer`` itself when nothing varies (its frames and cache keys as before), else a VariedRenderer."""
    return VariedRenderer(renderer, variety) if variety.active else renderer
