"""Search algorithms behind one ask/tell seam: NSGA-II (pymoo) and random search.

``ask(n)`` proposes up to ``n`` valid scenes never proposed before in this run;
``tell(F)`` hands back their objectives (rows: [response fitness, -diversity]).
Randomness flows from the run's seed only, so a deterministic SUT replays exactly.
"""
from __future__ import annotations

import numpy as np
from pymoo.algorithms.moo.nsga2 import NSGA2, binary_tournament
from pymoo.core.evaluator import Evaluator
from pymoo.core.mixed import MixedVariableMating
from pymoo.core.population import Population
from pymoo.operators.selection.tournament import TournamentSelection
from pymoo.problems.static import StaticProblem
from pymoo.core.termination import NoTermination

from ..space import SceneSpace
from .algorithm_names import check_algorithm
from .operators import CanonicalDuplicateElimination, SceneRepair, SceneSampling
from .problem import SceneProblem

_TOP_UP_TRIES = 200


class SearchAlgorithm:
    name = ""

    def __init__(self, space: SceneSpace, pop_size: int, seed: int):
        if pop_size < 2:
            raise ValueError(f"population size must be at least 2, got {pop_size}")
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
        raise ValueError(f"the {self.name or 'chosen'} search does not learn from earlier runs (--learn-from); "
                         "use --algorithm surrogate")

    def tell(self, F: np.ndarray, records: list | None = None) -> None:
        """Objectives of the scenes last asked (rows in their order); ``records`` are their
        archive records (answers, per-feature verdicts) for algorithms that learn from them."""
        raise NotImplementedError


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


class NSGA2Search(SearchAlgorithm):
    """pymoo's NSGA-II with per-type crossover/mutation, repair and canonical duplicate elimination."""
    name = "nsga2"

    def __init__(self, space, pop_size, seed, mutation: dict | None = None):
        """``mutation``: pymoo mutation operators per variable type instead of pymoo's defaults
        (for diagnosing operator rates; ``nsga2`` itself always uses the defaults)."""
        super().__init__(space, pop_size, seed)
        self.problem = SceneProblem(space)
        self.topped_up = 0  # scenes of the last ask that were random, because pymoo ran short
        repair = SceneRepair()
        dedup = CanonicalDuplicateElimination(self.problem, self.seen)
        mating = MixedVariableMating(selection=TournamentSelection(func_comp=binary_tournament), mutation=mutation,
                                     repair=repair, eliminate_duplicates=dedup)
        self.algorithm = NSGA2(pop_size=pop_size, sampling=SceneSampling(), mating=mating,
                               repair=repair, eliminate_duplicates=dedup)
        self.algorithm.setup(self.problem, termination=NoTermination(), seed=seed, verbose=False)
        self._pending: Population | None = None

    def ask(self, n_max: int) -> list[dict]:
        target = min(n_max, self.pop_size)
        offspring = self.algorithm.ask()
        if offspring is None:  # pymoo gives up when duplicates leave no offspring; we resample instead
            self.algorithm.termination.force_termination = False
            offspring = []
        scenes = [self.problem.to_scene(ind.X) for ind in offspring][:target]
        taken = {self.space.key(s) for s in scenes}
        # duplicate elimination may leave pymoo short of offspring: resample fresh scenes
        fresh = self._fresh(target - len(scenes), self.algorithm.random_state, taken)
        self.topped_up = len(fresh)
        scenes += fresh
        self.seen.update(taken)
        self._pending = Population.new(X=np.array([self.problem.to_x(s) for s in scenes], dtype=object))
        return scenes

    def tell(self, F: np.ndarray, records: list | None = None) -> None:
        pending, self._pending = self._pending, None
        if pending is None or len(pending) == 0:
            return
        Evaluator().eval(StaticProblem(self.problem, F=np.asarray(F, dtype=float)), pending)
        self.algorithm.tell(infills=pending)

    @property
    def population(self) -> list[dict]:
        pop = self.algorithm.pop
        return [] if pop is None else [self.problem.to_scene(ind.X) for ind in pop]


def make_algorithm(name: str, space: SceneSpace, pop_size: int, seed: int) -> SearchAlgorithm:
    from .surrogate_search import SurrogateSearch

    classes = {"surrogate": SurrogateSearch, "nsga2": NSGA2Search, "rs": RandomSearch}
    return classes[check_algorithm(name)](space, pop_size, seed)
