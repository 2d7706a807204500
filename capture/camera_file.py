"""The camera file (a contract shared with the renderer): TOML, JSON and mrcal ``.cameramodel``.

Layout: ``name``; ``[image] width height``; ``[intrinsics] model fx fy cx cy distortion``;
``[extrinsics] position rotation`` (R_cabin_from_camera: columns are the camera's OpenCV
x right, y down, z forward axes in cabin coordinates); ``[quality]`` and the optional
``[calibration]`` provenance; the optional imaging model ``[exposure]``, ``[response]``,
``[noise]``, ``[colour]`` (see ``camera_model/model.py``; a file without them renders as before).
The renderer's ``isu_validate.render.camera`` loads the
same files; a calibrated file drops into ``rigs/cameras/`` unchanged.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import tomli_w

from . import lens
from .camera_model.model import ImagingModel, plain
from .camera_model.model import from_dict as imaging_from_dict
from isu_validate.tomlfile import read_toml as read_toml_file

# A camera at the cabin origin looking forward (+x), image x to the cabin's right (-y),
# image y down (-z): the pose written before any registration, marked as such.
FORWARD_ROTATION = ((0.0, 0.0, 1.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0))


class CameraFileError(ValueError):
    """A camera file is missing something or is inconsistent."""


@dataclass
class CameraModel:
    name: str
    model: str
    width: int
    height: int
    intrinsics: np.ndarray                      # [fx, fy, cx, cy, *distortion]
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple = FORWARD_ROTATION          # R_cabin_from_camera
    registered: bool = False                    # pose measured in the cabin (see registration.py)
    quality: dict = field(default_factory=dict)
    calibration: dict = field(default_factory=dict)
    registration: dict = field(default_factory=dict)
    imaging: ImagingModel | None = None          # exposure, response, noise, colour (optional)

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    def project(self, points_cam) -> np.ndarray:
        return lens.project(self.model, self.intrinsics, points_cam)

    def unproject(self, pixels) -> np.ndarray:
        return lens.unproject(self.model, self.intrinsics, pixels)

    def to_dict(self) -> dict:
        fx, fy, cx, cy, *dist = (float(v) for v in self.intrinsics)
        extrinsics = {"position": [float(v) for v in self.position],
                      "rotation": [[float(v) for v in row] for row in self.rotation],
                      "registered": self.registered}
        if self.registration:
            extrinsics["registration"] = self.registration
        out = {"name": self.name, "image": {"width": int(self.width), "height": int(self.height)},
               "intrinsics": {"model": self.model, "fx": fx, "fy": fy, "cx": cx, "cy": cy, "distortion": dist},
               "extrinsics": extrinsics}
        if self.quality:
            out["quality"] = self.quality
        if self.calibration:
            out["calibration"] = self.calibration
        if self.imaging is not None:
            out.update(self.imaging.to_dict())
        return plain(out)


def write_toml(camera: CameraModel, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = ("# Camera file written by isu-validate calibrate (layout: capture/camera_file.py).\n"
              "# Cabin frame: metres, x forward, y left, z up. rotation = R_cabin_from_camera.\n")
    path.write_text(header + tomli_w.dumps(camera.to_dict()))
    return path


def to_json(camera: CameraModel) -> str:
    return json.dumps(camera.to_dict(), indent=2)


def read_toml(path: str | Path) -> CameraModel:
    raw = read_toml_file(path, CameraFileError, "camera file")
    return from_dict(raw, str(path))


def from_dict(raw: dict, where: str = "<camera>") -> CameraModel:
    try:
        image, intr = raw["image"], raw["intrinsics"]
        model = lens.check_model(str(intr.get("model", "pinhole")))
        dist = [float(v) for v in intr.get("distortion", [])]
        values = [float(intr[k]) for k in ("fx", "fy", "cx", "cy")]
        width, height = int(image["width"]), int(image["height"])
    except KeyError as exc:
        raise CameraFileError(f"{where}: missing {exc.args[0]!r} ([image] width/height and [intrinsics] "
                              "model fx fy cx cy distortion are required)") from None
    dist = _distortion_for(model, dist, where)
    extr = raw.get("extrinsics", {})
    rotation = extr.get("rotation", FORWARD_ROTATION)
    return CameraModel(str(raw.get("name", Path(where).stem)), model, width, height, np.array(values + dist),
                       tuple(extr.get("position", (0.0, 0.0, 0.0))), tuple(tuple(r) for r in rotation),
                       bool(extr.get("registered", "position" in extr)), raw.get("quality", {}),
                       raw.get("calibration", {}), extr.get("registration", {}), imaging_from_dict(raw, where))


def _distortion_for(model: str, dist: list[float], where: str) -> list[float]:
    need = lens.N_DISTORTION[model]
    if model == "opencv8" and len(dist) in (4, 5) :
        return dist + [0.0] * (8 - len(dist))  # shorter OpenCV vectors mean the rest are zero
    if model == "opencv8" and len(dist) > 8 and not any(dist[8:]):
        return dist[:8]
    if model == "pinhole" and not any(dist):
        return []
    if len(dist) != need:
        raise CameraFileError(f"{where}: model {model!r} takes {need} distortion coefficients, got {len(dist)}")
    return dist


def write_imaging(source: str | Path, imaging: ImagingModel, out: str | Path, note: str = "") -> Path:
    """Copy the camera file ``source`` to ``out`` with its imaging tables replaced by ``imaging``'s;
    everything else (intrinsics, pose, calibration provenance) is kept as it was."""
    raw = read_toml_file(source, CameraFileError, "camera file")
    from_dict(raw, str(source))   # a broken input is named before anything is written
    for section in ("exposure", "response", "noise", "colour"):
        raw.pop(section, None)
    raw.update(plain(imaging.to_dict()))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    header = (f"# Camera file from {source} with its imaging model{note} (layout: capture/camera_file.py,\n"
              "# capture/camera_model/model.py). Comments of the source file are not carried over.\n")
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(header + tomli_w.dumps(raw))
    tmp.replace(out)
    return out


# ---------------------------------------------------------------- mrcal

MRCAL_LENSMODELS = {"pinhole": "LENSMODEL_PINHOLE", "opencv8": "LENSMODEL_OPENCV8"}


def write_cameramodel(camera: CameraModel, path: str | Path) -> Path:
    """mrcal's ``.cameramodel`` text format (a Python dict literal), for mrcal's tools.

    mrcal's extrinsics are rt_cam_ref: the transform from the reference (here: cabin)
    frame into the camera frame, as a Rodrigues rotation then a translation.
    """
    if camera.model not in MRCAL_LENSMODELS:
        raise CameraFileError(f"mrcal has no equivalent of OpenCV's {camera.model!r} lens model (its fisheye "
                              "models are splined or CAHVORE); calibrate with --model opencv8 to export to mrcal")
    R_cabin_from_cam = np.asarray(camera.rotation, dtype=float)
    R_cam_from_cabin = R_cabin_from_cam.T
    rvec = cv2.Rodrigues(R_cam_from_cabin)[0].ravel()
    tvec = -R_cam_from_cabin @ np.asarray(camera.position, dtype=float)

    def numbers(values):
        return ", ".join(repr(float(v)) for v in values)

    text = ("# generated by isu-validate from a camera file; reference frame = the cabin frame\n"
            "{\n"
            f"    'lensmodel': '{MRCAL_LENSMODELS[camera.model]}',\n"
            f"    'intrinsics': [ {numbers(camera.intrinsics)} ],\n"
            f"    'extrinsics': [ {numbers(rvec)}, {numbers(tvec)} ],\n"
            f"    'imagersize': [ {int(camera.width)}, {int(camera.height)} ],\n"
            "}\n")
    path = Path(path)
    path.write_text(text)
    return path


def read_cameramodel(path: str | Path) -> CameraModel:
    """Read an mrcal ``.cameramodel`` (pinhole or OPENCV8; optimisation inputs are ignored)."""
    import ast
    text = Path(path).read_text()
    try:
        raw = ast.literal_eval("\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#")))
    except (ValueError, SyntaxError) as exc:
        raise CameraFileError(f"{path}: not an mrcal .cameramodel: {exc}") from None
    models = {v: k for k, v in MRCAL_LENSMODELS.items()}
    if raw.get("lensmodel") not in models:
        raise CameraFileError(f"{path}: lens model {raw.get('lensmodel')!r} is not supported; "
                              f"only {', '.join(models)}")
    rt = np.asarray(raw.get("extrinsics", [0.0] * 6), dtype=float)
    R_cam_from_cabin = cv2.Rodrigues(rt[:3])[0]
    position = -R_cam_from_cabin.T @ rt[3:]
    w, h = raw["imagersize"]
    return CameraModel(Path(path).stem, models[raw["lensmodel"]], int(w), int(h),
                       np.asarray(raw["intrinsics"], dtype=float), tuple(position),
                       tuple(tuple(r) for r in R_cam_from_cabin.T), registered=True)
