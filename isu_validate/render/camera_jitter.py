"""Camera jitter: a seeded, per-scene perturbation of the camera around its rig, for training data that
does not teach one exact viewpoint (``dataset --camera-jitter``, ``reference train --camera-jitter``).

A spec reads ``pos=0.05,angle=5,focal=0.1``: each scene's camera is moved by up to ``pos`` metres along each
cabin axis, turned by up to ``angle`` degrees about each of its own axes (tilt, pan, roll) and has its
focal length scaled by up to ``focal`` (relative) either way, all drawn uniformly. The camera moved is the
rig's ``capture.camera.Camera`` (``Camera.nudged``): the render, its labels (boxes, ``up``, visibility) and
its cache key all follow the camera actually used. The search's frames never jitter.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .strength import strength

# beyond these a "jitter" is another camera (the default rig hangs 7 cm under the roof and frames the tallest
# driver's head a few pixels from the top edge); frames a draw leaves unusable are skipped as any other
LIMITS = {"pos": 0.1, "angle": 15.0, "focal": 0.3}
EXAMPLE = "pos=0.05,angle=5,focal=0.1"


@dataclass(frozen=True)
class CameraJitter:
    """Largest shift (m, per cabin axis), turn (deg, per camera axis) and relative focal change."""
    pos: float = 0.0
    angle: float = 0.0
    focal: float = 0.0

    @property
    def active(self) -> bool:
        return any((self.pos, self.angle, self.focal))

    @property
    def text(self) -> str:
        """The canonical spec (what settings and cards record); "" when off."""
        return f"pos={self.pos:g},angle={self.angle:g},focal={self.focal:g}" if self.active else ""

    def draw(self, camera, rng):
        """(camera nudged by this scene's draw, the draw as plain numbers): ``rng`` a numpy Generator."""
        shift = rng.uniform(-self.pos, self.pos, 3) if self.pos else [0.0, 0.0, 0.0]
        turn = rng.uniform(-self.angle, self.angle, 3) if self.angle else [0.0, 0.0, 0.0]
        scale = 1.0 + float(rng.uniform(-self.focal, self.focal)) if self.focal else 1.0
        drawn = {"shift_m": [round(float(v), 5) for v in shift], "turn_deg": [round(float(v), 4) for v in turn],
                 "focal_scale": round(scale, 5)}
        # the rounded draw is the one applied, so the recorded numbers rebuild the camera exactly
        return camera.nudged(drawn["shift_m"], drawn["turn_deg"], drawn["focal_scale"]), drawn


def parse_camera_jitter(text: str | None) -> CameraJitter:
    """``pos=0.05,angle=5,focal=0.1`` (any subset; "" or None: off) -> CameraJitter; InputError names the fix."""
    if not text or text.strip() in ("", "none", "off"):
        return CameraJitter()
    values = {}
    for part in text.split(","):
        key, sep, value = part.strip().partition("=")
        if not sep or key not in LIMITS:
            raise InputError(f"--camera-jitter {text!r}: {part.strip()!r} is not KEY=VALUE with KEY one of "
                             f"{', '.join(LIMITS)} (e.g. --camera-jitter {EXAMPLE})")
        unit = "metres" if key == "pos" else "degrees" if key == "angle" else "relative"
        values[key] = strength("--camera-jitter", text, key, value, LIMITS[key], unit)
    return CameraJitter(**values)
