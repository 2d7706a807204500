"""Where the camera points, in numbers a technician can set with a tape, a spirit level and a protractor.

From the run's camera (``capture.camera.Camera``: position, R_cabin_from_camera, whose third column is
the optical axis) in the cabin frame (x forward, y left, z up):

* pan: the axis's heading about the vertical, counter-clockwise seen from above, 0° = facing forward
  (the sheet turns the suitcase with the same convention); 90° faces the car's left, 180° the rear;
* tilt: the axis's angle above the horizontal (negative: looking down);
* roll: the turn of the picture about the axis, clockwise seen from behind the camera; 0° = the
  picture's rows level (the camera's x axis horizontal);
* a point on the axis ``AIM_DISTANCE_M`` in front of the lens, to check the aim with a tape or a laser.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

AIM_DISTANCE_M = 1.0
CONVENTION = ("pan: counter-clockwise seen from above, 0° = facing forward, 90° = facing the car's left; "
              "tilt: above the horizontal, negative = looking down; roll: clockwise seen from behind the camera, "
              "0° = picture level")


@dataclass(frozen=True)
class Aim:
    position: tuple[float, float, float]   # cabin frame, metres; z is the mounting height above the floor
    pan_deg: float
    tilt_deg: float
    roll_deg: float
    point: tuple[float, float, float]      # on the optical axis, AIM_DISTANCE_M from the lens

    @property
    def height_m(self) -> float:
        return self.position[2]


def camera_aim(camera) -> Aim:
    """The aim of a ``capture.camera.Camera`` (its pose in the cabin)."""
    R = camera.R
    axis, right = R[:, 2], R[:, 0]
    pan = math.degrees(math.atan2(axis[1], axis[0]))
    tilt = math.degrees(math.asin(float(np.clip(axis[2], -1.0, 1.0))))
    # the picture's "down" (camera y) against the cabin's: the right side dipping (right[2] < 0) is clockwise
    roll = math.degrees(math.atan2(-right[2], -R[2, 1]))
    point = np.asarray(camera.position, float) + AIM_DISTANCE_M * axis
    return Aim(tuple(camera.position), pan, tilt, roll, tuple(float(v) for v in point))


def facing(pan_deg: float) -> str:
    """The pan in words: the nearest of forward, the car's left, the rear, the car's right, and how far off."""
    names = {0: "forward", 90: "towards the car's left", 180: "towards the rear", -90: "towards the car's right"}
    nearest = min(names, key=lambda a: abs(_wrap(pan_deg - a)))
    off = _wrap(pan_deg - nearest)
    if abs(off) < 0.5:
        return f"faces {names[nearest].removeprefix('towards ')}"
    rad = math.radians(pan_deg)   # which way the axis leans off the nearest direction
    side = ((("the car's left" if math.sin(rad) > 0 else "the car's right")) if nearest in (0, 180)
            else ("the front" if math.cos(rad) > 0 else "the rear"))
    return f"faces {names[nearest].removeprefix('towards ')}, turned {abs(off):.1f}° towards {side}"


def aim_lines(aim: Aim) -> list[str]:
    """The aim as short lines for the sheet."""
    x, y, z = aim.position
    px, py, pz = aim.point
    tilt = "level" if abs(aim.tilt_deg) < 0.05 else f"{abs(aim.tilt_deg):.1f}° {'down' if aim.tilt_deg < 0 else 'up'}"
    way = "clockwise" if aim.roll_deg > 0 else "anticlockwise"
    roll = "picture level" if abs(aim.roll_deg) < 0.05 else f"rolled {abs(aim.roll_deg):.1f}° {way} (seen from behind)"
    return [f"lens at x = {x:+.2f} m, y = {y:+.2f} m, mounted {z:.2f} m above the floor",
            f"{facing(aim.pan_deg)} (pan {_deg(aim.pan_deg)})",
            f"tilted {tilt} (tilt {_deg(aim.tilt_deg, '+')}), {roll} (roll {_deg(aim.roll_deg, '+')})",
            f"points at x = {px:+.2f} m, y = {py:+.2f} m, z = {pz:.2f} m, {AIM_DISTANCE_M:.2f} m in front of the lens"]


def _deg(angle: float, sign: str = "") -> str:
    return f"{round(angle, 1) or 0.0:{sign}.1f}°"   # no "-0.0°" from a rounding residue


def _wrap(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0
