"""The one seam every search algorithm sits behind: ``ask``/``learn``/``tell``.

``ask(n)`` proposes up to ``n`` valid scenes never proposed before in this run;
``tell(F)`` hands back their objectives (rows: [response fitness, -diversity]).
Randomness flows from the run's seed only, so a deterministic SUT replays exactly.
"""
from __future__ import annotations

import numpy as np

from ..space import SceneSpace
from ..errors import InputError

_TOP_UP_TRIES = 200


class SearchAlgorithm:
    name = ""
    # bumped whenever a seed makes the algorithm propose other scenes: run.json records it, and a resumed run
    # of another version is refused before it replays (its archive holds scenes this version would not propose)
    version = 1

    def __init__(self, space: SceneSpace, pop_size: int, seed: int):
        if pop_size < 2:
            raise InputError(f"population size must be at least 2, got {pop_size}")
        self.space, self.pop_size, self.seed = space, pop_size, seed
        self.seen: set[str] = set()

    def _fresh(self, n: int, rng: np.random.Generator, taken: set[str]) -> list[dict]:
        """Up to ``n`` valid scenes whose keys are in neither ``seen`` nor ``taken``."""
        out = []
        for _ in range(_TOP_UP_TRIES):
            if len(out) >= n:
                break
            scene = self.space.sample(rng, 1)[0]
            key = self.space.key(scene)
            if key not in self.seen and key not in taken:
                taken.add(key)
                out.append(scene)
        return out

    def ask(self, n_max: int) -> list[dict]:
        raise NotImplementedError

    def learn(self, records: list) -> None:
        """Tests of earlier runs of the same SUT, before the first ``ask`` (``run --learn-from``)."""
        raise InputError(f"the {self.name or 'chosen'} search does not learn from earlier runs (--learn-from); "
                         "use --algorithm surrogate")

    def tell(self, F: np.ndarray, records: list | None = None) -> None:
        """Objectives of the scenes last asked (rows in their order); ``records`` are their
        archive records (answers, per-feature verdicts) for algorithms that learn from them."""
        raise NotImplementedError
