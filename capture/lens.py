"""Lens models: projecting camera-frame points to pixels and back, with Jacobians.

An intrinsics vector is ``[fx, fy, cx, cy, *distortion]``.  The distortion follows
OpenCV exactly so that a camera file can be used with ``cv2.projectPoints`` (pinhole,
opencv8) or ``cv2.fisheye.projectPoints`` (fisheye) and gives the same pixels:

- ``pinhole``: no distortion.
- ``opencv8``: k1 k2 p1 p2 k3 k4 k5 k6 (OpenCV's rational model).
- ``fisheye``: k1..k4 of ``cv2.fisheye`` (equidistant: theta_d = theta (1 + k1 theta^2 + ...)).

A camera file may give an ``opencv8`` lens any distortion length OpenCV takes (``OPENCV_LENGTHS``:
shorter vectors mean the rest are zero); this module is the one place that calls OpenCV's projection.
The models' names and distortion lengths (``MODELS``, ``N_DISTORTION``) live in ``lens_models``, which
loads no OpenCV; they are re-exported here.
"""
from __future__ import annotations

import cv2
import numpy as np

from isu_validate.errors import InputError

from .lens_models import MODELS, N_DISTORTION, check_model  # noqa: F401  (re-exported as lens.*)

OPENCV_LENGTHS = (0, 4, 5, 8, 12, 14)   # distortion vectors cv2.projectPoints takes (k1 k2 p1 p2 [k3 [k4 k5 k6 ...]])


def n_intrinsics(model: str) -> int:
    return 4 + N_DISTORTION[check_model(model)]


def camera_matrix(intrinsics) -> np.ndarray:
    fx, fy, cx, cy = intrinsics[:4]
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def _distortion(model: str, intrinsics: np.ndarray) -> np.ndarray | None:
    """What OpenCV gets as distCoeffs: None for no coefficients, or a pinhole's (all zero, of any length)."""
    dist = intrinsics[4:]
    return dist if len(dist) and model != "pinhole" else None


def full_intrinsics(model: str, intrinsics) -> np.ndarray:
    """The intrinsics with exactly the model's number of coefficients (an ``opencv8`` lens written with 4 or
    5 is padded with zeros, one with 12 or 14 cut to 8 when the rest are zero), for consumers that need
    exactly that many (mrcal's OPENCV8); ValueError when the lens does not fit."""
    intrinsics = np.asarray(intrinsics, dtype=np.float64)
    need = N_DISTORTION[check_model(model)]
    dist = intrinsics[4:]
    if len(dist) < need and model == "opencv8":
        dist = np.concatenate([dist, np.zeros(need - len(dist))])
    elif len(dist) > need and not np.any(dist[need:]):
        dist = dist[:need]
    if len(dist) != need:
        raise InputError(f"{len(dist)} distortion coefficients do not fit a {need}-coefficient {model!r} lens "
                         f"(those beyond the first {need} are not all zero)")
    return np.concatenate([intrinsics[:4], dist])


def project(model: str, intrinsics, points, rvec=None, tvec=None, jacobian: bool = False):
    """Pixels of ``points`` (N,3), first moved by the pose (rvec, tvec) if given.

    With ``jacobian=True`` also returns d(pixels)/d(intrinsics) as (N,2,n_intrinsics)
    and d(pixels)/d(rvec, tvec) as (N,2,6), taken from OpenCV's own derivatives.
    """
    intrinsics = np.asarray(intrinsics, dtype=np.float64)
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    r = np.zeros(3) if rvec is None else np.asarray(rvec, dtype=np.float64).reshape(3)
    t = np.zeros(3) if tvec is None else np.asarray(tvec, dtype=np.float64).reshape(3)
    K = camera_matrix(intrinsics)
    dist = intrinsics[4:]
    n = len(pts)
    if n == 0:
        empty = np.zeros((0, 2))
        return (empty, np.zeros((0, 2, len(intrinsics))), np.zeros((0, 2, 6))) if jacobian else empty
    if model == "fisheye":
        px, jac = cv2.fisheye.projectPoints(pts.reshape(1, -1, 3), r, t, K, dist)
        jac = jac.reshape(n, 2, 15)
        j_intr, j_pose = jac[:, :, 0:8], jac[:, :, 8:14]
    else:
        check_model(model)
        px, jac = cv2.projectPoints(pts, r, t, K, _distortion(model, intrinsics))
        jac = jac.reshape(n, 2, -1)
        j_intr = jac[:, :, 6:6 + len(intrinsics)]
        j_pose = jac[:, :, 0:6]
    px = px.reshape(n, 2)
    return (px, j_intr, j_pose) if jacobian else px


def unproject(model: str, intrinsics, pixels) -> np.ndarray:
    """Unit rays (N,3) in the camera frame for pixels (N,2); NaN where the model has no inverse."""
    intrinsics = np.asarray(intrinsics, dtype=np.float64)
    px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    if model == "fisheye":
        return _unproject_fisheye(intrinsics, px)
    check_model(model)
    K = camera_matrix(intrinsics)
    dist = _distortion(model, intrinsics)
    if dist is None:
        norm = cv2.undistortPoints(px.reshape(-1, 1, 2), K, None).reshape(-1, 2)
    else:
        # The iterative variant: plain undistortPoints stops after 5 fixed-point steps,
        # which leaves whole pixels of error in the corners of a strongly distorted lens.
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
        norm = cv2.undistortPointsIter(px.reshape(-1, 1, 2), K, dist, None, None, crit).reshape(-1, 2)
    rays = np.column_stack([norm, np.ones(len(norm))])
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    # Where the distortion polynomial folds back, the inverse is not unique: reject
    # rays that do not project back onto their pixel.
    back = project(model, intrinsics, rays)
    rays[np.linalg.norm(back - px, axis=1) > 0.01] = np.nan
    return rays


def normalised(model: str, intrinsics, pixels) -> np.ndarray:
    """Normalised ray coordinates (x/z, y/z) (N,2) of pixels (N,2), by OpenCV's own inverse of the lens.

    The renderer builds its warp maps from this (``render/camera.py pinhole_plan``), so its iteration
    settings are part of what a rendered frame looks like: they stay as they are. ``unproject`` (unit rays,
    folds rejected, fisheye beyond 90 degrees) is the calibration side's inverse."""
    intrinsics = np.asarray(intrinsics, dtype=np.float64)
    uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    K, dist = camera_matrix(intrinsics), _distortion(check_model(model), intrinsics)
    if model == "fisheye":
        xy = cv2.fisheye.undistortPoints(uv, K, dist)
    elif dist is not None:
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
        xy = cv2.undistortPointsIter(uv, K, dist, None, None, crit)
    else:
        xy = cv2.undistortPoints(uv, K, None)
    return xy.reshape(-1, 2)


def _unproject_fisheye(intrinsics: np.ndarray, px: np.ndarray) -> np.ndarray:
    # cv2.fisheye.undistortPoints returns x/z, which cannot express rays at or beyond
    # 90 degrees off-axis, yet 180-degree-class lenses image them.  Invert
    # theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8) by Newton.
    fx, fy, cx, cy, *k = intrinsics
    xd = (px[:, 0] - cx) / fx
    yd = (px[:, 1] - cy) / fy
    theta_d = np.hypot(xd, yd)
    theta = theta_d.copy()
    for _ in range(30):
        t2 = theta * theta
        poly = 1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))
        dpoly = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])))
        step = (theta * poly - theta_d) / np.where(np.abs(dpoly) > 1e-12, dpoly, 1e-12)
        theta = theta - step
    t2 = theta * theta
    residual = theta * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d
    scale = np.where(theta_d > 1e-12, np.sin(theta) / np.maximum(theta_d, 1e-12), 1.0)
    rays = np.column_stack([xd * scale, yd * scale, np.cos(theta)])
    bad = (np.abs(residual) > 1e-9) | (theta < 0) | (theta > np.pi)
    rays[bad] = np.nan
    return rays


def point_jacobian(model: str, intrinsics, points) -> np.ndarray:
    """d(pixels)/d(point) (N,2,3) for camera-frame points: the pose Jacobian's translation part."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty((len(pts), 2, 3))
    for i, p in enumerate(pts):
        # Projecting the origin moved by tvec = p: d/dtvec is exactly d/dpoint.
        _, _, j_pose = project(model, intrinsics, np.zeros((1, 3)), np.zeros(3), p, jacobian=True)
        out[i] = j_pose[0, :, 3:6]
    return out
