"""Diversity of a scene: its distance to the nearest scene the run proposed before it.

Distances are ``SceneSpace.distances``: over active features, Hamming on categorical
ones and |a-b|/range on ordered ones, a feature active in only one scene counting 1,
averaged over all features (so 0 = same canonical scene, 1 = different in everything).
Taking the minimum (novelty against the archive) rewards scenes unlike anything
tested so far; the first scene of a run has nothing to compare with and gets 1.
"""
from __future__ import annotations

import numpy as np

from ..space import SceneSpace


class DiversityTracker:
    def __init__(self, space: SceneSpace, capacity: int = 1024):
        self.space = space
        self._rows = np.empty((capacity, len(space.names)), dtype=np.float32)
        self._n = 0

    def __len__(self) -> int:
        return self._n

    def add(self, scene: dict) -> float:
        """The scene's novelty against all scenes added before; then remember it."""
        vector = self.space.distance_rows(self.space.canonical_vector(scene))
        previous = self._rows[: self._n]
        novelty = float(self.space.distances_sentinel(vector, previous).min()) if self._n else 1.0
        if self._n == len(self._rows):
            self._rows = np.concatenate([self._rows, np.empty_like(self._rows)])
        self._rows[self._n] = vector
        self._n += 1
        return novelty
