"""The paper's search: pymoo's NSGA-II on the scene space (for replication)."""
from __future__ import annotations

import numpy as np
from pymoo.algorithms.moo.nsga2 import NSGA2, binary_tournament
from pymoo.core.evaluator import Evaluator
from pymoo.core.mixed import MixedVariableMating
from pymoo.core.population import Population
from pymoo.core.termination import NoTermination
from pymoo.operators.selection.tournament import TournamentSelection
from pymoo.problems.static import StaticProblem

from .base import SearchAlgorithm
from .operators import CanonicalDuplicateElimination, SceneRepair, SceneSampling
from .problem import SceneProblem


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
