"""The camera: one class (``Camera``) and one reader and writer of the camera file (a contract).

A camera file is what ``calibrate`` writes and what the renderer renders through; a calibrated file
drops into ``rigs/cameras/`` unchanged. Layout (docs/ARCHITECTURE.md, "Camera file"): ``name``;
``[image] width height``; ``[intrinsics] model fx fy cx cy distortion``; ``[extrinsics] position``
and ``rotation`` (or ``look_at`` with an optional ``up``) and ``registered``; ``[quality]`` and
``[calibration]`` provenance; the optional imaging model ``[exposure]``, ``[response]``, ``[noise]``,
``[colour]`` (read by ``camera_model/model.py``; a file without them renders as before).

Conventions:

- cabin frame: metres, x forward, y left, z up (see ``rigs/cabins/default.toml`` for the origin);
- ``rotation`` is R_cabin_from_camera: its columns are the camera's OpenCV axes (x right, y down,
  z forward) in cabin coordinates;
- pixel centres at integer coordinates (OpenCV), so the centre of a 640-wide image is x = 319.5;
- the lens is ``capture/lens.py``'s (its models, its projection); an ``opencv8`` lens keeps the
  distortion length the file gives (0, 4, 5, 8, 12 or 14), which the render cache key depends on.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import tomli_w

from isu_validate.atomic import write_text
from isu_validate.errors import UserError
from isu_validate.paths import resolve_rig
from isu_validate.tomlfile import read_toml as read_toml_file

from . import lens
from .camera_model.model import ImagingModel, ImagingModelError, plain
from .camera_model.model import from_dict as imaging_from_dict

# A camera at the cabin origin looking forward (+x), image x to the cabin's right (-y),
# image y down (-z): the pose written before any registration, marked as such.
FORWARD_ROTATION = ((0.0, 0.0, 1.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0))
LAYOUT = "see rigs/cameras/default.toml for the layout"


class CameraFileError(UserError, ValueError):
    """A camera file is missing something or is inconsistent; the message names the file and the fix."""


@dataclass(frozen=True, eq=False)
class Camera:
    """A camera: image, lens, pose in the cabin, where it came from and (optionally) its imaging model.

    ``intrinsics`` = [fx, fy, cx, cy, *distortion], the distortion as the file gives it. ``registered``
    False marks the placeholder pose (``FORWARD_ROTATION`` at the origin) that ``calibrate`` writes;
    ``pose_source`` names the rig the pose was taken from (``--extrinsics-from``), "" for this file."""
    name: str
    model: str
    width: int
    height: int
    intrinsics: np.ndarray
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[tuple[float, ...], ...] = FORWARD_ROTATION   # R_cabin_from_camera, row-major
    registered: bool = False
    quality: dict = field(default_factory=dict)
    calibration: dict = field(default_factory=dict)
    registration: dict = field(default_factory=dict)
    # exposure/response/noise/colour (capture/camera_model), applied to the linear render after the lens
    # warp; None renders the linear light as sRGB
    imaging: ImagingModel | None = None
    source: str = "<memory>"
    pose_source: str = ""

    def __post_init__(self):
        # plain Python numbers (the hash and the files are written from them) and a private, read-only
        # intrinsics vector: a camera does not change under its users
        intrinsics = np.array(self.intrinsics, dtype=np.float64)
        intrinsics.setflags(write=False)
        object.__setattr__(self, "intrinsics", intrinsics)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        object.__setattr__(self, "position", tuple(float(v) for v in self.position))
        object.__setattr__(self, "rotation", tuple(tuple(float(v) for v in row) for row in self.rotation))

    # ------------------------------------------------------------------ parameters
    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    @property
    def fx(self) -> float:
        return float(self.intrinsics[0])

    @property
    def fy(self) -> float:
        return float(self.intrinsics[1])

    @property
    def cx(self) -> float:
        return float(self.intrinsics[2])

    @property
    def cy(self) -> float:
        return float(self.intrinsics[3])

    @property
    def distortion(self) -> tuple[float, ...]:
        return tuple(float(v) for v in self.intrinsics[4:])

    @property
    def K(self) -> np.ndarray:
        return lens.camera_matrix(self.intrinsics)

    @property
    def D(self) -> np.ndarray:
        return np.array(self.intrinsics[4:])

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

    # ------------------------------------------------------------------ projection (capture/lens.py)
    def to_camera(self, points_cabin) -> np.ndarray:
        """Cabin points (N,3) in the camera's OpenCV frame."""
        p = np.atleast_2d(np.asarray(points_cabin, dtype=float))
        return (p - self.t) @ self.R

    def project(self, points_cabin) -> np.ndarray:
        """Pixel coordinates (N,2) of cabin points (N,3), through the lens; points behind the camera get NaN."""
        p = np.atleast_2d(np.asarray(points_cabin, dtype=float)).reshape(-1, 3)
        rvec, tvec = self.extrinsic_vectors()
        uv = lens.project(self.model, self.intrinsics, p, rvec, tvec)
        uv[self.to_camera(p)[:, 2] <= 0] = np.nan
        return uv

    def project_camera(self, points_cam) -> np.ndarray:
        """Pixel coordinates (N,2) of points (N,3) already in the camera's frame (calibration's view)."""
        return lens.project(self.model, self.intrinsics, points_cam)

    def rays(self, pixels) -> np.ndarray:
        """Normalised ray coordinates (x/z, y/z) (N,2) of pixels (N,2): the inverse of the lens that the
        renderer's warp is built from."""
        return lens.normalised(self.model, self.intrinsics, pixels)

    def unproject(self, pixels) -> np.ndarray:
        """Unit rays (N,3) in the camera frame of pixels (N,2); NaN where the lens has no inverse."""
        return lens.unproject(self.model, self.intrinsics, pixels)

    # ------------------------------------------------------------------ derived cameras
    def scaled(self, factor: float) -> "Camera":
        """The same camera at ``factor`` times the resolution (distortion is resolution-free)."""
        if factor == 1.0:
            return self
        w, h = round(self.width * factor), round(self.height * factor)
        sx, sy = w / self.width, h / self.height
        scaled = [self.fx * sx, self.fy * sy, (self.cx + 0.5) * sx - 0.5, (self.cy + 0.5) * sy - 0.5]
        return replace(self, width=w, height=h, intrinsics=np.array(scaled + list(self.distortion)))

    def nudged(self, shift=(0.0, 0.0, 0.0), turn_deg=(0.0, 0.0, 0.0), focal_scale: float = 1.0) -> "Camera":
        """This camera moved by ``shift`` (cabin frame, metres), turned by ``turn_deg`` about its own x (tilt),
        y (pan) and z (roll) axes in that order, and with its focal length times ``focal_scale`` (the principal
        point and the distortion kept): a camera mounted a little differently in the same place."""
        from scipy.spatial.transform import Rotation

        if focal_scale <= 0:
            raise ValueError(f"focal_scale must be positive, got {focal_scale}")
        if not np.any(shift) and not np.any(turn_deg) and focal_scale == 1.0:
            return self   # bit for bit: a zero nudge must not even flip a zero's sign in the hash
        turn = Rotation.from_euler("XYZ", turn_deg, degrees=True).as_matrix()   # R_camera_from_nudged
        intrinsics = np.array(self.intrinsics)
        intrinsics[:2] *= focal_scale
        return replace(self, position=tuple(self.t + np.asarray(shift, dtype=float)), rotation=self.R @ turn,
                       intrinsics=intrinsics)

    def with_pose_of(self, other: "Camera") -> "Camera":
        """This camera (lens, image) at the cabin pose of ``other``: ``--extrinsics-from OTHER``."""
        require_registered(other, "the --extrinsics-from rig")
        return replace(self, position=other.position, rotation=other.rotation, registered=True,
                       pose_source=other.source)

    # ------------------------------------------------------------------ as data
    def geometry(self) -> dict:
        """Name, image, lens and pose as plain values: the ``camera`` of a render's label and, without the
        name, what ``hash`` identifies."""
        return {"name": self.name, "image": {"width": self.width, "height": self.height},
                "intrinsics": {"model": self.model, "fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy,
                               "distortion": list(self.distortion)},
                "extrinsics": {"position": list(self.position), "rotation": [list(r) for r in self.rotation]}}

    @property
    def hash(self) -> str:
        """Identifies what the camera sees (not its name, provenance or comments): part of the render cache key."""
        blob = json.dumps({k: v for k, v in self.geometry().items() if k != "name"}, sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    def to_dict(self) -> dict:
        """The camera file's content (TOML- and JSON-writable)."""
        out = self.geometry()
        out["extrinsics"]["registered"] = self.registered
        if self.registration:
            out["extrinsics"]["registration"] = self.registration
        if self.quality:
            out["quality"] = self.quality
        if self.calibration:
            out["calibration"] = self.calibration
        if self.imaging is not None:
            out.update(self.imaging.to_dict())
        return plain(out)


# ---------------------------------------------------------------------- reading
def load_camera(name_or_path: str | os.PathLike = "default") -> Camera:
    """A camera by shipped name (``default``, ``rigs/cameras/``) or path; CameraFileError names the problem.

        camera = load_camera("cam.toml")              # e.g. written by `isu-validate calibrate`
        open_renderer(camera=camera, extrinsics_from=None if camera.registered else "default")
    """
    return read_toml(resolve_rig("cameras", name_or_path))


def read_toml(path: str | os.PathLike) -> Camera:
    """The camera file at ``path``; FileNotFoundError when there is none."""
    return camera_from_dict(read_toml_file(path, CameraFileError, "camera file"), str(path))


def camera_from_dict(raw: dict, where: str = "<camera>") -> Camera:
    """The one reader of a camera file's tables (``where`` names it in errors)."""
    image, intr = _table(raw, "image", where), _table(raw, "intrinsics", where)
    width, height = int(_need(image, "width", where, "image")), int(_need(image, "height", where, "image"))
    if width <= 0 or height <= 0:
        raise CameraFileError(f"{where}: [image] width and height must be positive, got {width}x{height}")
    model = str(intr.get("model", "pinhole"))
    if model not in lens.MODELS:
        raise CameraFileError(f"{where}: [intrinsics] model {model!r} is unknown; use one of "
                              f"{', '.join(lens.MODELS)}")
    fx, fy, cx, cy = (float(_need(intr, k, where, "intrinsics")) for k in ("fx", "fy", "cx", "cy"))
    if fx <= 0 or fy <= 0:
        raise CameraFileError(f"{where}: [intrinsics] fx and fy must be positive, got {fx}, {fy}")
    dist = [float(d) for d in intr.get("distortion", [])]
    _check_distortion(model, dist, where)
    position, rotation, registered, registration = _pose(raw, where)
    try:
        imaging = imaging_from_dict(raw, where)
    except ImagingModelError as exc:
        raise CameraFileError(str(exc)) from None
    return Camera(str(raw.get("name", Path(where).stem)), model, width, height, np.array([fx, fy, cx, cy, *dist]),
                  position, rotation, registered, raw.get("quality", {}), raw.get("calibration", {}), registration,
                  imaging, where)


def _pose(raw: dict, where: str) -> tuple:
    """(position, rotation, registered, registration) of [extrinsics]; without the table, the placeholder
    pose, unregistered. A table's pose counts as registered unless it says otherwise: hand-written rigs
    carry no flag, their pose is meant."""
    if "extrinsics" not in raw:
        return (0.0, 0.0, 0.0), FORWARD_ROTATION, False, {}
    extr = _table(raw, "extrinsics", where)
    position = tuple(float(v) for v in _need(extr, "position", where, "extrinsics"))
    if len(position) != 3:
        raise CameraFileError(f"{where}: [extrinsics] position needs 3 numbers (metres), got {list(position)}")
    rotation = _rotation(extr, np.array(position), where)
    registered = extr.get("registered", True)
    if not isinstance(registered, bool):
        raise CameraFileError(f"{where}: [extrinsics] registered must be true or false, got {registered!r}")
    return position, rotation, registered, extr.get("registration", {})


def _table(raw: dict, key: str, where: str) -> dict:
    if not isinstance(raw.get(key), dict):
        raise CameraFileError(f"{where}: missing [{key}] table ({LAYOUT})")
    return raw[key]


def _need(table: dict, key: str, where: str, name: str):
    if key not in table:
        raise CameraFileError(f"{where}: [{name}] has no {key!r} ({LAYOUT})")
    return table[key]


def _check_distortion(model: str, dist: list[float], where: str) -> None:
    if model == "pinhole" and any(dist):
        raise CameraFileError(f"{where}: model 'pinhole' takes no distortion; use model 'opencv8' for "
                              f"OpenCV coefficients or 'fisheye' for k1..k4")
    if model == "fisheye" and len(dist) != lens.N_DISTORTION["fisheye"]:
        raise CameraFileError(f"{where}: model 'fisheye' needs exactly 4 coefficients k1..k4, got {len(dist)}")
    if model == "opencv8" and len(dist) not in lens.OPENCV_LENGTHS:
        raise CameraFileError(f"{where}: model 'opencv8' takes 4, 5, 8, 12 or 14 coefficients in OpenCV "
                              f"order (k1 k2 p1 p2 [k3 [k4 k5 k6 ...]]), got {len(dist)}")


def _rotation(extr: dict, position: np.ndarray, where: str) -> np.ndarray:
    if "rotation" in extr:
        R = np.asarray(extr["rotation"], dtype=float)
        if R.shape != (3, 3):
            raise CameraFileError(f"{where}: [extrinsics] rotation must be a 3x3 matrix, got shape {R.shape}")
        err = np.abs(R.T @ R - np.eye(3)).max()
        if err > 1e-4 or np.linalg.det(R) < 0:
            raise CameraFileError(f"{where}: [extrinsics] rotation is not a proper rotation (orthonormality "
                                  f"error {err:.2g}, det {np.linalg.det(R):.3f}); write R_cabin_from_camera "
                                  f"whose columns are the camera's x right, y down, z forward axes")
        u, _, vt = np.linalg.svd(R)  # remove rounding noise from a written matrix
        return u @ vt
    if "look_at" in extr:
        return look_at_rotation(position, np.asarray(extr["look_at"], float),
                                np.asarray(extr.get("up", [0.0, 0.0, 1.0]), float), where)
    raise CameraFileError(f"{where}: [extrinsics] needs `rotation` (3x3, R_cabin_from_camera) or "
                          f"`look_at` = [x, y, z] (with optional `up`)")


def look_at_rotation(position, target, up=(0.0, 0.0, 1.0), where: str = "<camera>") -> np.ndarray:
    """R_cabin_from_camera of a camera at ``position`` looking at ``target`` with ``up`` roughly up in the image."""
    z = np.asarray(target, float) - np.asarray(position, float)
    if np.linalg.norm(z) < 1e-9:
        raise CameraFileError(f"{where}: look_at equals position; the camera needs a direction")
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, float))
    if np.linalg.norm(x) < 1e-6:
        raise CameraFileError(f"{where}: `up` is parallel to the viewing direction; give another up vector")
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


# ---------------------------------------------------------------------- the camera a render uses
def load_render_camera(camera: "str | os.PathLike | Camera" = "default",
                       extrinsics_from: "str | os.PathLike | Camera | None" = None) -> Camera:
    """The camera a render uses: ``camera`` (its pose replaced by that of ``extrinsics_from`` when given),
    refused with the fix when its pose was never registered in the cabin."""
    rig = camera if isinstance(camera, Camera) else load_camera(camera)
    if extrinsics_from is not None:
        other = extrinsics_from if isinstance(extrinsics_from, Camera) else load_camera(extrinsics_from)
        rig = rig.with_pose_of(other)
    require_registered(rig)
    return rig


def require_registered(rig: Camera, role: str = "the camera") -> None:
    """An unregistered pose (the cabin origin looking forward) renders the dashboard or nothing at all:
    every test would be judged on an image of no scene."""
    if rig.registered:
        return
    raise CameraFileError(
        f"{rig.source}: {role}'s pose in the cabin was never registered ([extrinsics] registered = false: "
        f"the placeholder pose `isu-validate calibrate` writes, at the cabin origin looking forward). Register it "
        f"from a photo of the cabin markers: `isu-validate calibrate register {rig.source} MARKER_SHOT.png "
        f"--markers MARKERS.toml`, or take the pose from a registered rig with --extrinsics-from RIG "
        f"(e.g. --extrinsics-from default)")


# ---------------------------------------------------------------------- writing
def write_toml(camera: Camera, path: str | os.PathLike, by: str = "isu-validate calibrate") -> Path:
    header = (f"# Camera file written by {by} (layout: capture/camera.py).\n"
              "# Cabin frame: metres, x forward, y left, z up. rotation = R_cabin_from_camera.\n")
    return write_text(path, header + tomli_w.dumps(camera.to_dict()))   # whole or not at all


def to_json(camera: Camera) -> str:
    return json.dumps(camera.to_dict(), indent=2)


def write_imaging(source: str | os.PathLike, imaging: ImagingModel, out: str | os.PathLike, note: str = "") -> Path:
    """Copy the camera file ``source`` to ``out`` with its imaging tables replaced by ``imaging``'s;
    everything else (intrinsics, pose, calibration provenance) is kept as it was."""
    raw = read_toml_file(source, CameraFileError, "camera file")
    camera_from_dict(raw, str(source))   # a broken input is named before anything is written
    for section in ("exposure", "response", "noise", "colour"):
        raw.pop(section, None)
    raw.update(plain(imaging.to_dict()))
    header = (f"# Camera file from {source} with its imaging model{note} (layout: capture/camera.py,\n"
              "# capture/camera_model/model.py). Comments of the source file are not carried over.\n")
    return write_text(out, header + tomli_w.dumps(raw))
