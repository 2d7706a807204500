"""Distances to a posed body's surface (the belt is laid on it; tests measure gaps with it).

trimesh's closest-point query (an R-tree over the triangles) gives the closest surface point; the
sign comes from the normal of the triangle it lies on (anny's mesh is not watertight, so no
inside/outside ray test): negative inside the body."""
from __future__ import annotations

import numpy as np


class Surface:
    def __init__(self, vertices: np.ndarray, faces: np.ndarray, keep: np.ndarray | None = None):
        """``keep``: a per-vertex mask of the part of the body to measure against (e.g. the torso)."""
        import trimesh
        faces = np.asarray(faces)
        if keep is not None:
            faces = faces[np.asarray(keep)[faces].all(axis=1)]
        self.mesh = trimesh.Trimesh(np.asarray(vertices, np.float64), faces, process=False)

    def closest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(closest surface points, outward normals there, signed distances) of points (N, 3)."""
        import trimesh
        points = np.asarray(points, np.float64)
        q, d, tri = trimesh.proximity.closest_point(self.mesh, points)
        n = self.mesh.face_normals[tri]
        sign = np.where(((points - q) * n).sum(axis=1) >= 0, 1.0, -1.0)
        return q, n, d * sign

    def cast(self, origins: np.ndarray, direction) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(first hits, normals there, hit?) of rays from ``origins`` along one ``direction``."""
        origins = np.asarray(origins, np.float64)
        direction = np.asarray(direction, float) / np.linalg.norm(direction)
        hits = np.full_like(origins, np.nan)
        normals = np.zeros_like(origins)
        locations, rays, tris = self.mesh.ray.intersects_location(
            origins, np.repeat(direction[None], len(origins), axis=0), multiple_hits=True)
        if len(rays):
            depth = (locations - origins[rays]) @ direction
            for ray in np.unique(rays):     # the nearest hit of each ray
                mine = np.flatnonzero(rays == ray)
                k = mine[np.argmin(depth[mine])]
                hits[ray], normals[ray] = locations[k], self.mesh.face_normals[tris[k]]
        return hits, normals, ~np.isnan(hits[:, 0])

    def distance(self, points: np.ndarray) -> np.ndarray:
        return self.closest(points)[2]
