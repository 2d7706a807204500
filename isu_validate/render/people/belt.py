"""The seat belt laid over the posed body: a taut strap from the B-pillar anchor over the driver's left
shoulder, diagonally across the chest to the buckle by the right hip, and a lap strap from the buckle
across the pelvis to the outboard anchor.

Each strap starts as the straight line between its ends (through the body), is pressed onto the side
of the body it crosses, and relaxes like a taut string: pulled straight, lifted back to rest just on
the surface (never inside it), repeatedly. Only the torso, pelvis and thighs carry it (an arm raised
past the strap does not lift it off the chest)."""
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
    anchor, buckle, lap_anchor = (np.asarray(hardware[k], float) for k in ("upper_anchor", "buckle", "lap_anchor"))
    body = Surface(posed.vertices, faces, carriers)
    # a strap is pressed onto the side of the body it crosses: the diagonal from the front and above
    # (chest and shoulder), the lap strap from the front and above (belly and thighs)
    diagonal = _relax(body, anchor, buckle, 48, pressed_from=(1.0, 0.0, 0.5))
    lap = _relax(body, buckle, lap_anchor, 40, pressed_from=(1.0, 0.0, 1.0))
    return diagonal, lap


def _relax(surface: Surface, start, end, n: int, pressed_from, rounds: int = 20) -> Strap:
    """A taut strap from ``start`` to ``end`` resting on the surface: the straight line between them
    (through the body) is pressed onto the body from the ``pressed_from`` side (each point moved to
    where a ray from that side first meets the body), then tightened (each point pulled towards its
    neighbours) and lifted back out of the body, repeatedly, until it settles."""
    points = start + (end - start) * np.linspace(0.0, 1.0, n)[:, None]
    side = np.asarray(pressed_from, float) / np.linalg.norm(pressed_from)
    hit, normal, found = surface.cast(points[1:-1] + side * 1.0, -side)
    inner = points[1:-1]
    pressed = found & ((hit - inner) @ side > 0)        # only points inside the body (behind the hit)
    inner[pressed] = hit[pressed] + normal[pressed] * REST
    for _ in range(rounds):
        points = _resample(points, n)
        points[1:-1] = 0.5 * points[1:-1] + 0.25 * (points[:-2] + points[2:])
        _lift(surface, points)
    nrm = _lift(surface, points)
    normals = np.concatenate([nrm[:1], nrm, nrm[-1:]])
    return Strap(points.astype(np.float32), _smooth_normals(normals, points).astype(np.float32))


def _lift(surface: Surface, points: np.ndarray) -> np.ndarray:
    """Lift the strap's inner points that sink below their rest height back onto the surface; returns
    the surface normals under them."""
    q, nrm, d = surface.closest(points[1:-1])
    low = d < REST
    points[1:-1][low] = q[low] + nrm[low] * REST
    return nrm


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
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
    out -= tangent * (out * tangent).sum(axis=1, keepdims=True)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-9)
