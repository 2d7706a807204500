"""Variety for training data: a renderer whose every scene is seen through its own jittered camera
(``camera_jitter``), optionally one of several rigs first (``camera_mix``: the renderer's own camera or one of
these, drawn per scene), and developed with its own sensor effects (``sensor_effects``), all drawn from a seed
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

_JITTER_STREAM, _EFFECTS_STREAM, _RIG_STREAM = 1, 2, 3


@dataclass(frozen=True)
class Variety:
    """What varies per scene and the seed the draws start from. ``cameras``: camera rigs (names or .toml paths)
    a scene may be seen through besides the renderer's own, one drawn uniformly per scene before the jitter."""
    jitter: CameraJitter = CameraJitter()
    effects: SensorEffects = SensorEffects()
    seed: int = 0
    cameras: tuple[str, ...] = ()

    @classmethod
    def parse(cls, camera_jitter: str | None, sensor_effects: str | None, seed: int,
              camera_mix: str | None = None) -> "Variety":
        return cls(parse_camera_jitter(camera_jitter), parse_sensor_effects(sensor_effects), int(seed),
                   parse_camera_mix(camera_mix))

    @property
    def active(self) -> bool:
        return self.jitter.active or self.effects.active or self.moves_camera

    @property
    def moves_camera(self) -> bool:
        """Whether a scene may be seen through another camera than the renderer's own."""
        return self.jitter.active or bool(self.cameras)

    def spec(self) -> dict:
        """What decides the draws (cache keys hash this): the canonical specs and the seed ({} when nothing
        varies; the camera mix only when given, so the sets made before it keep their keys). Wording about them
        lives in ``describe`` only, so rewording never changes a key."""
        if not self.active:
            return {}
        mix = {"camera_mix": ",".join(self.cameras)} if self.cameras else {}
        return {"camera_jitter": self.jitter.text, "sensor_effects": self.effects.text, "seed": self.seed, **mix}

    def describe(self) -> dict:
        """For settings and cards: ``spec`` and how each scene's draws follow from it."""
        if not self.active:
            return {}
        streams = "stream 1 the camera, 2 the effects" + (", 3 the camera rig" if self.cameras else "")
        return {**self.spec(), "per_scene": "numpy Generator(SeedSequence([seed, stream, sha256(scene key)])): "
                                            + streams}

    def rng(self, scene_key: str, stream: int):
        import numpy as np

        digest = hashlib.sha256(scene_key.encode()).digest()
        words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4)]
        return np.random.default_rng(np.random.SeedSequence([self.seed, stream, *words]))


class VariedRenderer:
    """A renderer that jitters its camera and applies sensor effects per scene (the ``Renderer`` protocol)."""

    def __init__(self, renderer, variety: Variety):
        if variety.moves_camera and not hasattr(renderer, "use_camera"):
            option = "--camera-jitter" if variety.jitter.active else "--camera-mix"
            raise InputError(f"{option} needs a renderer that can move its camera; "
                             f"{type(renderer).__name__} cannot")
        self.inner = renderer
        self.variety = variety
        self.space = renderer.space
        self.rig = getattr(renderer, "rig", None)   # the camera file's camera: every jitter starts from it (or a mix's)
        self.rigs = [self.rig, *(_mix_camera(name, self.rig) for name in variety.cameras)]
        self._drawn: tuple[str, Any, dict] | None = None   # (scene key, camera, draw): cache_key's, for render

    def camera_for(self, canonical: Mapping[str, Any]):
        """(the scene's camera, what was drawn: ``rig``, the mix's pick, and the jitter's numbers); the rig itself
        when nothing moves it. Drawn once per scene: ``cache_key`` and then ``render`` of the same scene share it."""
        if not self.variety.moves_camera:
            return self.rig, {}
        key = self.space.key(canonical)
        if self._drawn is None or self._drawn[0] != key:
            rig, drawn = self.rig, {}
            if self.variety.cameras:
                rig = self.rigs[int(self.variety.rng(key, _RIG_STREAM).integers(len(self.rigs)))]
                drawn["rig"] = rig.name
            camera = rig
            if self.variety.jitter.active:
                camera, jitter = self.variety.jitter.draw(rig, self.variety.rng(key, _JITTER_STREAM))
                drawn.update(jitter)
            self._drawn = (key, camera, drawn)
        return self._drawn[1], self._drawn[2]

    def render(self, scene: Mapping[str, Any], out: Path):
        canonical = self.space.check(scene)
        camera, moved = self.camera_for(canonical)
        if self.variety.moves_camera:
            self.inner.use_camera(camera)
        result = self.inner.render(canonical, out)   # RenderError passes through: the frame is unusable
        drawn = {}
        if moved:
            drawn["camera"] = moved
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
        if self.variety.moves_camera:
            self.inner.use_camera(camera)
        inner = self.inner.cache_key(canonical) if hasattr(self.inner, "cache_key") else self.space.key(canonical)
        blob = json.dumps([inner, self.variety.spec()], sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()

    def close(self) -> None:
        self.inner.close()


def parse_camera_mix(text: str | None) -> tuple[str, ...]:
    """``RIG[,RIG...]`` (names of shipped camera rigs or .toml paths; "" or None: none) -> the rigs, in order, each
    once. Whether each loads is checked when a renderer opens them (``VariedRenderer``)."""
    if not text or text.strip() in ("", "none", "off"):
        return ()
    return tuple(dict.fromkeys(part.strip() for part in text.split(",") if part.strip()))


def _mix_camera(name: str, own):
    """A camera of the mix, loaded as a render's camera (refused with the fix when unknown or unregistered, or when
    it is the renderer's own camera, which the mix holds already)."""
    from capture.camera import load_render_camera

    try:
        camera = load_render_camera(name)
    except (OSError, ValueError) as exc:
        raise InputError(f"--camera-mix {name!r}: {exc}") from exc
    if own is not None and camera.hash == own.hash:
        raise InputError(f"--camera-mix {name!r} is the set's own camera (--camera), which the mix holds already; "
                         "name only the other rigs")
    return camera


def card_lines(described: dict) -> list[str]:
    """The variety of a set, for dataset and model cards alike (``Variety.describe()``): one bullet each."""
    mix = ([f"- camera mix: each scene seen through the set's camera or one of `{described['camera_mix']}`, drawn "
            "uniformly per scene, then jittered; the labels are the camera's it was seen through"]
           if described.get("camera_mix") else [])
    return mix + [f"- camera jitter: `{described['camera_jitter'] or 'none'}` (uniform per axis: shift in metres along "
            "the cabin's axes, turn in degrees about the camera's own, focal length relative); the labels (boxes, "
            "masks, `up`, visibility) are the jittered camera's",
            f"- sensor effects: `{described['sensor_effects'] or 'none'}` (each image draws every strength between "
            "none and its maximum; applied after rendering: exposure, white balance, vignetting, blur, noise, JPEG)",
            f"- seed {described['seed']}; per scene: {described['per_scene']}"]


def vary(renderer, variety: Variety):
    """``renderer`` itself when nothing varies (its frames and cache keys as before), else a VariedRenderer."""
    return VariedRenderer(renderer, variety) if variety.active else renderer
