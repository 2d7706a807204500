"""The camera model: a camera rig file (intrinsics, lens distortion, pose in the cabin) and its OpenCV projection.

One model serves the renderer (which pinhole image Blender renders and how it is warped into the
rig's lens) and calibration (projecting known cabin points). Conventions:

- cabin frame: metres, x forward, y left, z up (see ``rigs/cabins/default.toml`` for the origin);
- ``rotation`` is R_cabin_from_camera: its columns are the camera's OpenCV axes (x right, y down,
  z forward) in cabin coordinates;
- pixel centres at integer coordinates (OpenCV), so the centre of a 640-wide image is x = 319.5.

The file's optional ``[exposure]``/``[response]``/``[noise]``/``[colour]`` tables are the camera's
imaging model, parsed by ``capture.camera_model.model`` (the one reader of that part).
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np

from capture.camera_model.model import ImagingModel, ImagingModelError
from capture.camera_model.model import from_dict as imaging_from_dict

from ..paths import resolve_rig
from ..tomlfile import read_toml

MODELS = ("pinhole", "opencv8", "fisheye")
_OPENCV_LENGTHS = (0, 4, 5, 8, 12, 14)


class CameraRigError(ValueError):
    """A camera rig file is missing something or is inconsistent."""


@dataclass(frozen=True)
class CameraRig:
    name: str
    width: int
    height: int
    model: str
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...]
    position: tuple[float, float, float]
    rotation: tuple[tuple[float, ...], ...]   # R_cabin_from_camera, row-major
    source: str = "<memory>"
    extra: dict = field(default_factory=dict, compare=False, hash=False)
    registered: bool = True      # False: [extrinsics] is the placeholder `calibrate` writes before registration
    pose_source: str = ""        # the rig the pose was taken from (--extrinsics-from), "" = this file
    # the camera's exposure/response/noise/colour model (capture/camera_model), applied to the linear
    # render after it is warped through the lens; None renders the linear light as sRGB, as before
    imaging: "ImagingModel | None" = field(default=None, compare=False, hash=False)

    # ------------------------------------------------------------------ matrices
    @property
    def K(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def D(self) -> np.ndarray:
        return np.asarray(self.distortion, dtype=float)

    @property
    def R(self) -> np.ndarray:
        """R_cabin_from_camera (columns: camera x right, y down, z forward)."""
        return np.asarray(self.rotation, dtype=float)

    @property
    def t(self) -> np.ndarray:
        return np.asarray(self.position, dtype=float)

    def extrinsic_vectors(self) -> tuple[np.ndarray, np.ndarray]:
        """(rvec, tvec) of the cabin-to-camera transform, as OpenCV's projectPoints wants them."""
        R_cam_from_cabin = self.R.T
        rvec, _ = cv2.Rodrigues(R_cam_from_cabin)
        return rvec, -R_cam_from_cabin @ self.t

    @property
    def is_plain_pinhole(self) -> bool:
        """Blender renders this camera directly: no distortion, square pixels."""
        return not np.any(self.D) and abs(self.fx - self.fy) < 1e-9 * self.fx

    # ------------------------------------------------------------------ projection
    def to_camera(self, points_cabin) -> np.ndarray:
        """Cabin points (N,3) in the camera's OpenCV frame."""
        p = np.atleast_2d(np.asarray(points_cabin, dtype=float))
        return (p - self.t) @ self.R

    def project(self, points_cabin) -> np.ndarray:
        """Pixel coordinates (N,2) of cabin points (N,3), through the rig's lens model.
        Points behind the camera get NaN."""
        p = np.atleast_2d(np.asarray(points_cabin, dtype=float)).reshape(-1, 3)
        rvec, tvec = self.extrinsic_vectors()
        if self.model == "fisheye":
            uv, _ = cv2.fisheye.projectPoints(p.reshape(1, -1, 3), rvec, tvec, self.K, self.D)
        else:
            uv, _ = cv2.projectPoints(p, rvec, tvec, self.K, self.D if len(self.D) else None)
        uv = uv.reshape(-1, 2)
        uv[self.to_camera(p)[:, 2] <= 0] = np.nan
        return uv

    def rays(self, pixels) -> np.ndarray:
        """Normalised ray coordinates (x/z, y/z) (N,2) of pixels (N,2): the inverse of the lens."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
        if self.model == "fisheye":
            xy = cv2.fisheye.undistortPoints(uv, self.K, self.D)
        elif len(self.D):
            crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
            xy = cv2.undistortPointsIter(uv, self.K, self.D, None, None, crit)
        else:
            xy = cv2.undistortPoints(uv, self.K, None)
        return xy.reshape(-1, 2)

    # ------------------------------------------------------------------ derived rigs
    def scaled(self, factor: float) -> "CameraRig":
        """The same camera at ``factor`` times the resolution (distortion is resolution-free)."""
        if factor == 1.0:
            return self
        w, h = round(self.width * factor), round(self.height * factor)
        sx, sy = w / self.width, h / self.height
        return replace(self, width=w, height=h, fx=self.fx * sx, fy=self.fy * sy,
                       cx=(self.cx + 0.5) * sx - 0.5, cy=(self.cy + 0.5) * sy - 0.5)

    def with_pose_of(self, other: "CameraRig") -> "CameraRig":
        """This camera (lens, image) at the cabin pose of ``other``: ``--extrinsics-from OTHER``."""
        require_registered(other, "the --extrinsics-from rig")
        return replace(self, position=other.position, rotation=other.rotation, registered=True,
                       pose_source=other.source)

    def to_dict(self) -> dict:
        return {"name": self.name, "image": {"width": self.width, "height": self.height},
                "intrinsics": {"model": self.model, "fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy,
                               "distortion": list(self.distortion)},
                "extrinsics": {"position": list(self.position), "rotation": [list(r) for r in self.rotation]}}

    @property
    def hash(self) -> str:
        """Identifies what the camera sees (not its name or comments): part of the render cache key."""
        blob = json.dumps({k: v for k, v in self.to_dict().items() if k != "name"}, sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]


# ---------------------------------------------------------------------- loading
def load_camera(name_or_path: str | os.PathLike = "default") -> CameraRig:
    """A camera rig by shipped name (``default``) or path; raises CameraRigError naming the problem."""
    path = resolve_rig("cameras", name_or_path)
    raw = read_toml(path, CameraRigError, "camera rig")
    return camera_from_dict(raw, where=str(path))


def camera_from_dict(raw: dict, where: str = "<camera rig>") -> CameraRig:
    image, intr, extr = (_table(raw, k, where) for k in ("image", "intrinsics", "extrinsics"))
    width, height = int(_need(image, "width", where, "image")), int(_need(image, "height", where, "image"))
    if width <= 0 or height <= 0:
        raise CameraRigError(f"{where}: [image] width and height must be positive, got {width}x{height}")
    model = str(intr.get("model", "pinhole"))
    if model not in MODELS:
        raise CameraRigError(f"{where}: [intrinsics] model {model!r} is unknown; use one of {', '.join(MODELS)}")
    fx, fy, cx, cy = (float(_need(intr, k, where, "intrinsics")) for k in ("fx", "fy", "cx", "cy"))
    if fx <= 0 or fy <= 0:
        raise CameraRigError(f"{where}: [intrinsics] fx and fy must be positive, got {fx}, {fy}")
    dist = tuple(float(d) for d in intr.get("distortion", []))
    _check_distortion(model, dist, where)
    position = tuple(float(v) for v in _need(extr, "position", where, "extrinsics"))
    if len(position) != 3:
        raise CameraRigError(f"{where}: [extrinsics] position needs 3 numbers (metres), got {list(position)}")
    rotation = _rotation(extr, np.array(position), where)
    try:
        imaging = imaging_from_dict(raw, where)
    except ImagingModelError as exc:
        raise CameraRigError(str(exc)) from None
    registered = extr.get("registered", True)   # hand-written rigs carry no flag: their pose is meant
    if not isinstance(registered, bool):
        raise CameraRigError(f"{where}: [extrinsics] registered must be true or false, got {registered!r}")
    return CameraRig(str(raw.get("name", Path(where).stem)), width, height, model, fx, fy, cx, cy, dist,
                     position, tuple(tuple(float(v) for v in row) for row in rotation), where,
                     {k: v for k, v in raw.items() if k not in ("name", "image", "intrinsics", "extrinsics")},
                     registered, imaging=imaging)


def load_render_camera(camera: "str | os.PathLike | CameraRig" = "default",
                       extrinsics_from: "str | os.PathLike | CameraRig | None" = None) -> CameraRig:
    """The rig a render uses: ``camera`` (its pose replaced by that of ``extrinsics_from`` when given),
    refused with the fix when its pose was never registered in the cabin."""
    rig = camera if isinstance(camera, CameraRig) else load_camera(camera)
    if extrinsics_from is not None:
        other = extrinsics_from if isinstance(extrinsics_from, CameraRig) else load_camera(extrinsics_from)
        rig = rig.with_pose_of(other)
    require_registered(rig)
    return rig


def require_registered(rig: CameraRig, role: str = "the camera") -> None:
    """An unregistered pose (the cabin origin looking forward) renders the dashboard or nothing at all:
    every test would be judged on an image of no scene."""
    if rig.registered:
        return
    raise CameraRigError(
        f"{rig.source}: {role}'s pose in the cabin was never registered ([extrinsics] registered = false: "
        f"the placeholder pose `isu-validate calibrate` writes, at the cabin origin looking forward). Register it "
        f"from a photo of the cabin markers: `isu-validate calibrate register {rig.source} MARKER_SHOT.png "
        f"--markers MARKERS.toml`, or take the pose from a registered rig with --extrinsics-from RIG "
        f"(e.g. --extrinsics-from default)")


def _table(raw: dict, key: str, where: str) -> dict:
    if not isinstance(raw.get(key), dict):
        raise CameraRigError(f"{where}: missing [{key}] table (see rigs/cameras/default.toml for the layout)")
    return raw[key]


def _need(table: dict, key: str, where: str, name: str):
    if key not in table:
        raise CameraRigError(f"{where}: [{name}] has no {key!r} (see rigs/cameras/default.toml for the layout)")
    return table[key]


def _check_distortion(model: str, dist: tuple, where: str) -> None:
    if model == "pinhole" and any(dist):
        raise CameraRigError(f"{where}: model 'pinhole' takes no distortion; use model 'opencv8' for "
                             f"OpenCV coefficients or 'fisheye' for k1..k4")
    if model == "fisheye" and len(dist) != 4:
        raise CameraRigError(f"{where}: model 'fisheye' needs exactly 4 coefficients k1..k4, got {len(dist)}")
    if model == "opencv8" and len(dist) not in _OPENCV_LENGTHS:
        raise CameraRigError(f"{where}: model 'opencv8' takes 4, 5, 8, 12 or 14 coefficients in OpenCV "
                             f"order (k1 k2 p1 p2 [k3 [k4 k5 k6 ...]]), got {len(dist)}")


def _rotation(extr: dict, position: np.ndarray, where: str) -> np.ndarray:
    if "rotation" in extr:
        R = np.asarray(extr["rotation"], dtype=float)
        if R.shape != (3, 3):
            raise CameraRigError(f"{where}: [extrinsics] rotation must be a 3x3 matrix, got shape {R.shape}")
        err = np.abs(R.T @ R - np.eye(3)).max()
        if err > 1e-4 or np.linalg.det(R) < 0:
            raise CameraRigError(f"{where}: [extrinsics] rotation is not a proper rotation (orthonormality "
                                 f"error {err:.2g}, det {np.linalg.det(R):.3f}); write R_cabin_from_camera "
                                 f"whose columns are the camera's x right, y down, z forward axes")
        u, _, vt = np.linalg.svd(R)  # remove rounding noise from a written matrix
        return u @ vt
    if "look_at" in extr:
        return look_at_rotation(position, np.asarray(extr["look_at"], float),
                                np.asarray(extr.get("up", [0.0, 0.0, 1.0]), float), where)
    raise CameraRigError(f"{where}: [extrinsics] needs `rotation` (3x3, R_cabin_from_camera) or "
                         f"`look_at` = [x, y, z] (with optional `up`)")


def look_at_rotation(position, target, up=(0.0, 0.0, 1.0), where: str = "<camera>") -> np.ndarray:
    """R_cabin_from_camera of a camera at ``position`` looking at ``target`` with ``up`` roughly up in the image."""
    z = np.asarray(target, float) - np.asarray(position, float)
    if np.linalg.norm(z) < 1e-9:
        raise CameraRigError(f"{where}: look_at equals position; the camera needs a direction")
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, float))
    if np.linalg.norm(x) < 1e-6:
        raise CameraRigError(f"{where}: `up` is parallel to the viewing direction; give another up vector")
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


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


def pinhole_plan(rig: CameraRig) -> PinholePlan:
    """Distortion and non-square pixels are applied exactly: render a padded pinhole that covers
    every ray of the rig's image, then remap (OpenCV) into the rig's lens."""
    if rig.is_plain_pinhole:
        return PinholePlan(rig.width, rig.height, rig.fx, rig.cx, rig.cy)
    us, vs = np.meshgrid(np.arange(rig.width, dtype=np.float64), np.arange(rig.height, dtype=np.float64))
    xy = rig.rays(np.column_stack([us.ravel(), vs.ravel()])).reshape(rig.height, rig.width, 2)
    if not np.all(np.isfinite(xy)):
        raise CameraRigError(f"{rig.source}: the lens model maps some pixels to no ray (field of view near "
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
