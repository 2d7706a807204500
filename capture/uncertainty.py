"""Projection uncertainty propagated from the observation noise through the solve (mrcal's method).

The question answered: if the same camera were calibrated again with new noise on the
same views, how far would a world point at the working distance move in the image?
Linearised: q = q(p) for parameters p with covariance sigma^2 (J^T J)^-1.  A point v in
the camera frame is tied to the world through the boards ("mean-frames" as in mrcal):
in each board's coordinates it is b_i = T_i^-1 v; a perturbed solution maps each b_i
back with its perturbed pose, and the point is their mean.  So a perturbation that
merely rotates the whole scene together with the camera frame moves nothing, which
is what makes the centre of the image trustworthy even when cx alone is uncertain.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from threadpoolctl import threadpool_limits

from . import lens
from .solve import Solution


@dataclass
class UncertaintyMap:
    distance_m: float
    us: np.ndarray           # (nx,) pixel columns of the grid
    vs: np.ndarray           # (ny,) pixel rows
    stdev_px: np.ndarray     # (ny, nx) worst-direction standard deviation; NaN where unprojectable


def grid(size, nx: int = 32, ny: int = 24) -> tuple[np.ndarray, np.ndarray]:
    w, h = size
    return np.linspace(0, w - 1, nx), np.linspace(0, h - 1, ny)


def projection_stdev(sol: Solution, pixels, distance_m: float) -> np.ndarray:
    """Worst-direction standard deviation (px) of projecting the world point seen at each pixel
    at ``distance_m`` along its ray; inf when the solve left parameters undetermined."""
    pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    out = np.full(len(pixels), np.nan)
    rays = lens.unproject(sol.model, sol.intrinsics, pixels)
    ok = np.all(np.isfinite(rays), axis=1)
    if sol.covariance is None:
        out[ok] = np.inf
        return out
    with threadpool_limits(1, user_api="blas"):
        grad = _gradient(sol, rays[ok] * distance_m)
        cov = np.einsum("gap,pq,gbq->gab", grad, sol.covariance, grad, optimize=True)
    out[ok] = np.sqrt(np.linalg.eigvalsh(cov)[:, -1].clip(min=0))
    return out


def _gradient(sol: Solution, v: np.ndarray) -> np.ndarray:
    """d(pixel)/d(all parameters) (G,2,P) for camera-frame points v under the mean-frames tie."""
    ni = sol.n_intrinsics
    n_frames = len(sol.rvecs)
    grad = np.zeros((len(v), 2, ni + 6 * n_frames))
    _, grad[:, :, :ni], _ = lens.project(sol.model, sol.intrinsics, v, jacobian=True)
    dq_dv = lens.point_jacobian(sol.model, sol.intrinsics, v)             # (G,2,3)
    for f, (r, t) in enumerate(zip(sol.rvecs, sol.tvecs)):
        R, dR = cv2.Rodrigues(r)                                           # dR: (3,9), row k = dR/dr_k
        b = (v - t) @ R                                                    # the points in board f's frame
        dv_dr = np.stack([b @ dR[k].reshape(3, 3).T for k in range(3)], axis=2)  # (G,3,3)
        dv = np.concatenate([dv_dr, np.broadcast_to(np.eye(3), (len(v), 3, 3))], axis=2)
        grad[:, :, ni + 6 * f: ni + 6 * f + 6] = dq_dv @ dv / n_frames
    return grad


def uncertainty_map(sol: Solution, distance_m: float, nx: int = 32, ny: int = 24) -> UncertaintyMap:
    us, vs = grid(sol.image_size, nx, ny)
    pts = np.stack(np.meshgrid(us, vs), axis=-1).reshape(-1, 2)
    return UncertaintyMap(distance_m, us, vs, projection_stdev(sol, pts, distance_m).reshape(ny, nx))


def summary_points(size) -> dict[str, np.ndarray]:
    """The image centre, the four edge midpoints and the four corners (pixel centres)."""
    w, h = size[0] - 1, size[1] - 1
    return {"centre": np.array([[w / 2, h / 2]]),
            "edge": np.array([[w / 2, 0], [w / 2, h], [0, h / 2], [w, h / 2]]),
            "corner": np.array([[0, 0], [w, 0], [0, h], [w, h]])}


def summary(sol: Solution, distance_m: float) -> dict:
    """Uncertainty at the centre, the worst edge midpoint and the worst corner (px)."""
    out = {}
    for name, pts in summary_points(sol.image_size).items():
        s = projection_stdev(sol, pts, distance_m)
        out[name] = float(np.nanmax(s)) if np.any(np.isfinite(s) | np.isinf(s)) else float("nan")
    out["distance_m"] = float(distance_m)
    return out
