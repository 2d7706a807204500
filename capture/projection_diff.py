"""How differently two calibrations of one camera project the world (mrcal's projection diff).

Two camera models of the same lens may place their camera frames slightly differently
(a small rotation trades against cx, cy and the board poses; at a finite distance a
small shift trades against the focal length), so comparing parameters or raw
projections overstates the difference.  As mrcal does, the implied transform between
the two frames is fitted first: a rotation for points at infinity, a rotation and a
translation for points at a working distance.  What remains is what a user would
see: the same world point landing on different pixels.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from . import lens
from .uncertainty import grid


@dataclass
class DiffMap:
    us: np.ndarray
    vs: np.ndarray
    diff_px: np.ndarray              # (ny, nx); NaN where either model has no ray
    rotation_deg: float              # the fitted rotation between the two camera frames
    translation_m: tuple = (0.0, 0.0, 0.0)
    distance_m: float = math.inf

    def stats(self) -> dict:
        d = self.diff_px[np.isfinite(self.diff_px)]
        if d.size == 0:
            return {"median": float("nan"), "p90": float("nan"), "max": float("nan")}
        return {"median": float(np.median(d)), "p90": float(np.percentile(d, 90)), "max": float(d.max())}


def projection_diff(model_a: str, intr_a, model_b: str, intr_b, size, nx: int = 32, ny: int = 24,
                    fit: bool = True, distance_m: float = math.inf, fit_radius: float | None = None) -> DiffMap:
    """Where B projects the points that A sees at a grid of pixels (at ``distance_m`` along
    the rays, or at infinity), minus those pixels.

    The implied transform is fitted on the grid points within ``fit_radius`` px of the image
    centre (default: a third of the smaller side), where calibrations are most certain:
    fitting over the corners, where a lens model extrapolates, would spread their errors.
    """
    us, vs = grid(size, nx, ny)
    px = np.stack(np.meshgrid(us, vs), axis=-1).reshape(-1, 2)
    rays_a = lens.unproject(model_a, intr_a, px)
    rays_b = lens.unproject(model_b, intr_b, px)
    ok = np.all(np.isfinite(rays_a), axis=1) & np.all(np.isfinite(rays_b), axis=1)
    diff = np.full(len(px), np.nan)
    if ok.sum() < 3:
        return DiffMap(us, vs, diff.reshape(ny, nx), float("nan"), distance_m=distance_m)
    finite = math.isfinite(distance_m)
    points = rays_a * distance_m if finite else rays_a
    rot, shift = Rotation.identity(), np.zeros(3)
    if fit:
        radius = fit_radius if fit_radius is not None else min(size) / 3
        sel = ok & (np.linalg.norm(px - [(size[0] - 1) / 2, (size[1] - 1) / 2], axis=1) <= radius)
        sel = sel if sel.sum() >= 6 else ok
        rot, _ = Rotation.align_vectors(rays_b[sel], rays_a[sel])  # rot applied to A's rays gives B's
        if finite:
            rot, shift = _fit_rigid(model_b, intr_b, points[sel], px[sel], rot)
    q = lens.project(model_b, intr_b, rot.apply(points[ok]) + (shift if finite else 0.0))
    diff[ok] = np.linalg.norm(q - px[ok], axis=1)
    return DiffMap(us, vs, diff.reshape(ny, nx), float(np.degrees(rot.magnitude())), tuple(shift), distance_m)


def _fit_rigid(model_b, intr_b, points, px, rot0):
    """Rotation and translation taking A's points to where B sees the same pixels (6 parameters)."""
    def residual(p):
        return (lens.project(model_b, intr_b, Rotation.from_rotvec(p[:3]).apply(points) + p[3:]) - px).ravel()

    sol = least_squares(residual, np.concatenate([rot0.as_rotvec(), np.zeros(3)]), method="lm")
    return Rotation.from_rotvec(sol.x[:3]), sol.x[3:]
