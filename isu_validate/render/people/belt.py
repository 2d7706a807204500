"""The seat belt laid over the posed body: a taut strap from the B-pillar anchor over the driver's left
shoulder, diagonally across the chest to the buckle by the right hip, and a lap strap from the buckle
across the pelvis to the outboard anchor.

Each strap starts as straight lines through a few waypoints on the body and relaxes like a taut
string: it is smoothed towards straight lines and pushed back out to rest just on the surface
(never inside it), repeatedly. Only the torso, pelvis and thighs carry it (an arm raised past the
strap does not lift it off the chest)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .regions import bone_weights
from .skeleton import Posed
from .surface import Surface

WIDTH = 0.048
THICKNESS = 0.004
REST = THICKNESS / 2 + 0.0015      # the strap's centre line above the surface where it lies on it
_CARRIERS = ("root", "pelvis", "spine", "clavicle", "shoulder01", "neck01", "upperleg01", "upperleg02")


@dataclass
class Strap:
    points: np.ndarray     # (N, 3) centre line
    normals: np.ndarray    # (N, 3) the strap's flat side faces this way


def carrier_mask(model) -> np.ndarray:
    """Vertices that can carry the belt (mostly skinned to the torso, pelvis or thighs)."""
    return bone_weights(model, _CARRIERS) > 0.6


def lay_belt(posed: Posed, faces: np.ndarray, carriers: np.ndarray, hardware: dict) -> tuple[Strap, Strap]:
    surface = Surface(posed.vertices, faces, carriers)
    anchor, buckle, lap_anchor = (np.asarray(hardware[k], float) for k in ("upper_anchor", "buckle", "lap_anchor"))
    neck = posed.head("neck01")
    left, right = posed.head("upperarm01.L"), posed.head("upperarm01.R")
    hip_l, hip_r = posed.head("upperleg01.L"), posed.head("upperleg01.R")
    forward = np.array([1.0, 0.0, 0.0])
    # over the collarbone between neck and shoulder, the middle of the chest, in front of the right hip
    shoulder = neck + 0.45 * (left - neck) + np.array([0.0, 0.0, 0.08])
    chest = (neck + hip_r) / 2 + np.array([0.0, 0.04, 0.0]) + forward * 0.25
    hip = hip_r + forward * 0.2 + np.array([0.0, 0.04, 0.06])
    diagonal = _relax(surface, [anchor, shoulder, chest, hip, buckle], 48)
    lap = _relax(surface, [buckle, hip_r + forward * 0.25 + np.array([0, 0, 0.05]),
                           hip_l + forward * 0.25 + np.array([0, 0, 0.05]), lap_anchor], 40)
    return diagonal, lap


def _relax(surface: Surface, waypoints: list, n: int, rounds: int = 30) -> Strap:
    """A taut strap through the end points, resting on the surface between them."""
    ends = waypoints[0], waypoints[-1]
    points = _resample(np.array(waypoints, float), n)
    normals = np.zeros_like(points)
    for _ in range(rounds):
        inner = points[1:-1]
        # tension: each point moves to the middle of its neighbours (a string pulls itself straight)
        points[1:-1] = 0.5 * inner + 0.25 * (points[:-2] + points[2:])
        q, nrm, d = surface.closest(points[1:-1])
        low = d < REST
        points[1:-1][low] = q[low] + nrm[low] * REST
        normals[1:-1] = nrm
        points = _resample(points, n)
        points[0], points[-1] = ends
    q, nrm, d = surface.closest(points)
    normals = _smooth_normals(nrm, points)
    return Strap(points.astype(np.float32), normals.astype(np.float32))


def _resample(points: np.ndarray, n: int) -> np.ndarray:
    """n points evenly spaced along a polyline."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    at = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(at, s, points[:, k]) for k in range(3)])


def _smooth_normals(normals: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Surface normals along the strap, perpendicular to it and smoothed (a strap does not twist
    from triangle to triangle)."""
    out = normals.copy()
    for _ in range(4):
        out[1:-1] = 0.5 * out[1:-1] + 0.25 * (out[:-2] + out[2:])
    tangent = np.gradient(points, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    out -= tangent * (out * tangent).sum(axis=1, keepdims=True)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-9)
