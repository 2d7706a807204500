"""What Blender renders for a camera: the square-pixel pinhole image and the warp into the camera's lens.

The camera itself (its file, its lens, its pose) is ``capture.camera``'s ``Camera``; this module is the
renderer's own use of it."""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from capture.camera import Camera, CameraFileError


# ---------------------------------------------------------------------- what Blender renders
@dataclass(frozen=True)
class PinholePlan:
    """The square-pixel pinhole image Blender renders, and the warp from it into the rig's image.

    ``map_x``/``map_y`` (rig-sized float32) say where each rig pixel samples the pinhole image
    (cv2.remap); they are None when the rig is itself a plain pinhole."""
    width: int
    height: int
    f: float
    cx: float
    cy: float
    map_x: np.ndarray | None = None
    map_y: np.ndarray | None = None

    def blender_camera(self) -> dict:
        """Blender camera settings giving exactly this pinhole (horizontal sensor fit)."""
        sensor = 36.0
        return {"width": self.width, "height": self.height, "sensor_width": sensor,
                "lens": self.f * sensor / self.width,
                # Blender's image plane centre sits at OpenCV pixel (W-1)/2; shift is in units of the width
                "shift_x": ((self.width - 1) / 2 - self.cx) / self.width,
                "shift_y": (self.cy - (self.height - 1) / 2) / self.width}


_MAX_PAD_AREA = 4.0   # the padded pinhole may hold at most this many times the rig's pixels


def pinhole_plan(rig: Camera) -> PinholePlan:
    """Distortion and non-square pixels are applied exactly: render a padded pinhole that covers
    every ray of the rig's image, then remap (OpenCV) into the rig's lens."""
    if rig.is_plain_pinhole:
        return PinholePlan(rig.width, rig.height, rig.fx, rig.cx, rig.cy)
    us, vs = np.meshgrid(np.arange(rig.width, dtype=np.float64), np.arange(rig.height, dtype=np.float64))
    xy = rig.rays(np.column_stack([us.ravel(), vs.ravel()])).reshape(rig.height, rig.width, 2)
    if not np.all(np.isfinite(xy)):
        raise CameraFileError(f"{rig.source}: the lens model maps some pixels to no ray (field of view near "
                              f"or beyond 180 deg); the renderer supports fields of view below ~170 deg")
    lo, hi = xy.reshape(-1, 2).min(axis=0), xy.reshape(-1, 2).max(axis=0)
    f = max(rig.fx, rig.fy)  # keep the rig's central sampling density
    area = (hi - lo).prod() * f * f
    if area > _MAX_PAD_AREA * rig.width * rig.height:  # wide lenses: trade edge sharpness for speed
        f *= math.sqrt(_MAX_PAD_AREA * rig.width * rig.height / area)
    cx, cy = -lo[0] * f + 1.0, -lo[1] * f + 1.0
    width, height = int(math.ceil((hi[0] - lo[0]) * f)) + 3, int(math.ceil((hi[1] - lo[1]) * f)) + 3
    map_x = (xy[..., 0] * f + cx).astype(np.float32)
    map_y = (xy[..., 1] * f + cy).astype(np.float32)
    return PinholePlan(width, height, f, cx, cy, map_x, map_y)


def warp(image: np.ndarray, plan: PinholePlan, nearest: bool = False) -> np.ndarray:
    """The rendered pinhole image seen through the rig's lens (identity for a plain pinhole)."""
    if plan.map_x is None:
        return image
    interp = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.remap(image, plan.map_x, plan.map_y, interp, borderMode=cv2.BORDER_REPLICATE)
