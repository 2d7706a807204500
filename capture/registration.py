"""Cabin registration: the camera's pose in the cabin frame from ArUco markers at known positions.

Marker table (in the cabin rig, or a small TOML file of its own):

    dictionary = "DICT_4X4_50"          # OpenCV predefined dictionary of the printed markers
    [[markers]]
    id = 7
    # the marker's four outer corners in cabin metres (x forward, y left, z up), in OpenCV's
    # order as printed: top-left, top-right, bottom-right, bottom-left
    corners = [[0.9, 0.30, 0.85], [0.9, 0.20, 0.85], [0.9, 0.20, 0.75], [0.9, 0.30, 0.75]]

One image showing at least one marker (two or more, spread apart, for a well-determined
pose) gives R_cabin_from_camera and the camera position by PnP on the calibrated lens.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from . import lens
from .camera import Camera
from isu_validate.tomlfile import read_toml
from isu_validate.errors import UserError


class RegistrationError(UserError, ValueError):
    """The markers could not give a camera pose."""


def load_markers(path: str | Path) -> tuple[str, dict[int, np.ndarray]]:
    """(dictionary name, {marker id: (4,3) cabin corners}) from a cabin rig or a marker file."""
    path = Path(path)
    raw = read_toml(path, RegistrationError, "marker file")
    table = raw.get("markers")
    if isinstance(table, dict) and "markers" in table:  # a cabin rig with a [markers] table of its own
        raw, table = table, table["markers"]
    if not isinstance(table, list) or not table:
        raise RegistrationError(f"{path}: no [[markers]] entries; each needs id and corners "
                                "(see capture/registration.py for the layout)")
    dictionary = str(raw.get("dictionary", "DICT_4X4_50"))
    if not hasattr(cv2.aruco, dictionary):
        raise RegistrationError(f"{path}: unknown ArUco dictionary {dictionary!r}")
    markers = {}
    for i, m in enumerate(table):
        corners = np.asarray(m.get("corners", []), dtype=float)
        if "id" not in m or corners.shape != (4, 3):
            raise RegistrationError(f"{path}: marker #{i + 1} needs an id and corners = four [x, y, z] points")
        markers[int(m["id"])] = corners
    return dictionary, markers


def detect_markers(image: np.ndarray, dictionary: str) -> dict[int, np.ndarray]:
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    params = cv2.aruco.DetectorParameters()
    # Sub-pixel corners: the default (none) leaves ~0.5 px errors, ~2 cm of camera position at 1 m.
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)), params)
    corners, ids, _ = detector.detectMarkers(gray)
    if ids is None:
        return {}
    return {int(i): c.reshape(4, 2).astype(np.float64) for i, c in zip(ids.ravel(), corners)}


def register(camera: Camera, image: np.ndarray, dictionary: str, markers: dict[int, np.ndarray],
             source: str = "") -> Camera:
    """The camera with its cabin pose set from the markers seen in ``image``."""
    if (image.shape[1], image.shape[0]) != camera.size:
        raise RegistrationError(f"registration image is {image.shape[1]}x{image.shape[0]} but the camera was "
                                f"calibrated at {camera.width}x{camera.height}; use the same resolution")
    seen = detect_markers(image, dictionary)
    used = sorted(set(seen) & set(markers))
    if not used:
        raise RegistrationError(f"none of the listed markers ({sorted(markers)}) was found in the image "
                                f"(found {sorted(seen) or 'none'} of {dictionary}); check the dictionary and lighting")
    obj = np.concatenate([markers[i] for i in used])
    px = np.concatenate([seen[i] for i in used])
    rvec, tvec = _pnp(camera, obj, px)
    err = np.linalg.norm(lens.project(camera.model, camera.intrinsics, obj, rvec, tvec) - px, axis=1)
    R_cam_from_cabin = cv2.Rodrigues(rvec)[0]
    info = {"image": source, "markers": used, "rms_px": float(np.sqrt(np.mean(err ** 2)))}
    if len(used) == 1:
        info["warning"] = "one marker only: the pose may flip between two solutions; show two or more"
    return replace(camera, position=tuple(-R_cam_from_cabin.T @ tvec), rotation=tuple(map(tuple, R_cam_from_cabin.T)),
                   registered=True, registration=info)


def _pnp(camera: Camera, obj: np.ndarray, px: np.ndarray):
    # PnP on unprojected rays works for every lens model (solvePnP itself knows no fisheye).
    rays = camera.unproject(px)
    ok = np.all(np.isfinite(rays), axis=1) & (rays[:, 2] > 0.05)
    if ok.sum() < 4:
        raise RegistrationError("too few marker corners inside the lens model's valid field of view")
    norm = rays[ok, :2] / rays[ok, 2:3]
    flags = cv2.SOLVEPNP_IPPE if ok.sum() == 4 else cv2.SOLVEPNP_SQPNP
    found, rvec, tvec = cv2.solvePnP(obj[ok], norm, np.eye(3), None, flags=flags)
    if not found:
        raise RegistrationError("solvePnP found no pose for the markers; check their cabin coordinates")
    rvec, tvec = cv2.solvePnPRefineLM(obj[ok], norm, np.eye(3), None, rvec, tvec)
    return rvec.ravel(), tvec.ravel()
