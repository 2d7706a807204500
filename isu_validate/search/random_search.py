"""Random search: the baseline every other search is compared with."""
from __future__ import annotations

import numpy as np

from .base import SearchAlgorithm


class RandomSearch(SearchAlgorithm):
    """The baseline: batches of uniformly sampled valid scenes, duplicates resampled."""
    name = "rs"

    def __init__(self, space, pop_size, seed):
        super().__init__(space, pop_size, seed)
        self.rng = np.random.default_rng(seed)

    def ask(self, n_max: int) -> list[dict]:
        scenes = self._fresh(min(n_max, self.pop_size), self.rng, set())
        self.seen.update(self.space.key(s) for s in scenes)
        return scenes

    def tell(self, F: np.ndarray, records: list | None = None) -> None:
        pass  # random search learns nothing
