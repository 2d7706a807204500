"""pymoo operators that keep every scene valid and never propose a scene twice."""
from __future__ import annotations

import numpy as np
from pymoo.core.duplicate import DuplicateElimination
from pymoo.core.repair import Repair
from pymoo.core.sampling import Sampling


class SceneSampling(Sampling):
    """Valid scenes drawn from the space (uniform per feature, then repaired)."""

    def _do(self, problem, n_samples, random_state=None, **kwargs):
        scenes = problem.space.sample(random_state, n_samples)
        return np.array([problem.to_x(s) for s in scenes], dtype=object)


class SceneRepair(Repair):
    """Restores the space's constraints after sampling, crossover and mutation.

    Must be given to the mating as well as to the algorithm: a custom mating does not
    inherit the algorithm's repair (pymoo issue 575).
    """

    def _do(self, problem, X, random_state=None, **kwargs):
        rng = random_state if random_state is not None else np.random.default_rng()
        repaired = [problem.to_x(problem.space.repair(problem.to_scene(x), rng)) for x in X]
        return np.array(repaired, dtype=object)


class CanonicalDuplicateElimination(DuplicateElimination):
    """Scenes are duplicates when their canonical forms match (inactive features ignored),
    within a batch, against the batches given, and against every scene the run has
    already proposed (``seen``, a set of scene keys the search loop keeps up to date)."""

    def __init__(self, problem, seen: set[str]):
        super().__init__()
        self.problem = problem
        self.seen = seen

    def _keys(self, pop) -> list[str]:
        return [self.problem.space.key(self.problem.to_scene(ind.X)) for ind in pop]

    def _do(self, pop, other, is_duplicate):
        keys = self._keys(pop)
        if other is None:
            taken = set()
            for i, key in enumerate(keys):
                is_duplicate[i] = key in taken or key in self.seen
                taken.add(key)
        else:
            others = set(self._keys(other))
            is_duplicate |= np.array([k in others for k in keys], dtype=bool)
        return is_duplicate
