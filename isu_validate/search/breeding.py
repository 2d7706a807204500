"""Many children of many scenes at once, with pymoo's operators on whole populations.

pymoo's ``MixedVariableMating`` (what ``nsga2`` uses) runs crossover and mutation once
per categorical variable, building pymoo ``Individual`` objects for each: about 1 ms per
child here, too slow to screen thousands of candidates per generation.  Encoding every
discrete feature (categorical and ordinal) as the index of its value lets one call of
pymoo's uniform crossover (``UX``) and random-resetting mutation (``ChoiceRandomMutation``)
handle all of them, and polynomial mutation (``PM``) the numeric ones.  The children
are then repaired against the space's constraints like every other scene.
"""
from __future__ import annotations

import numpy as np
from pymoo.core.problem import Problem
from pymoo.core.variable import Choice
from pymoo.operators.crossover.ux import UX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.mutation.rm import ChoiceRandomMutation

from ..space import SceneSpace


class Breeder:
    """Children of parent scenes: ``crossover`` (uniform, then mutation) or ``mutants`` (mutation only).

    ``mutations`` is the expected number of features a mutation changes per child (each
    feature mutates with probability ``mutations / n_features``, as in the paper's
    "modifies single feature values"); a discrete feature is reset to a random value of
    its domain (which may be the same one), a numeric one moved by polynomial mutation.
    """

    def __init__(self, space: SceneSpace, mutations: float = 1.0):
        self.space = space
        searchable = [f for f in space.features.values() if f.span > 0]
        self.discrete = [f for f in searchable if f.discrete]
        self.numeric = [f for f in searchable if not f.discrete]
        rate = min(1.0, mutations / max(1, len(searchable)))
        self._discrete = Problem(vars={f.name: Choice(options=list(range(len(f.values)))) for f in self.discrete})
        self._numeric = Problem(n_var=len(self.numeric), xl=np.array([f.low for f in self.numeric], dtype=float),
                                xu=np.array([f.high for f in self.numeric], dtype=float))
        self._reset = ChoiceRandomMutation(prob=1.0, prob_var=rate)
        self._move = PM(prob=1.0, prob_var=rate)
        self._cross = UX(prob=1.0)

    # ------------------------------------------------------------------ encoding
    def to_rows(self, scenes: list[dict]) -> tuple[np.ndarray, np.ndarray]:
        D = np.array([[f.values.index(s[f.name]) for f in self.discrete] for s in scenes], dtype=float)
        N = np.array([[float(s[f.name]) for f in self.numeric] for s in scenes], dtype=float)
        return D.reshape(len(scenes), len(self.discrete)), N.reshape(len(scenes), len(self.numeric))

    def to_scenes(self, D: np.ndarray, N: np.ndarray, base: dict) -> list[dict]:
        """Scenes from rows; features that cannot vary are taken from ``base``."""
        out = []
        for d, n in zip(D, N):
            scene = dict(base)
            scene.update({f.name: f.values[int(v)] for f, v in zip(self.discrete, d)})
            scene.update({f.name: (int(round(v)) if f.type == "integer" else float(v))
                          for f, v in zip(self.numeric, n)})
            out.append(scene)
        return out

    # ------------------------------------------------------------------ operators
    def crossover(self, parents: list[dict], n: int, rng: np.random.Generator) -> list[dict]:
        """``n`` children of random parent pairs: uniform crossover, then mutation."""
        if len(parents) < 2 or n <= 0:
            return self.mutants(parents, n, rng)
        D, N = self.to_rows(parents)
        pairs = np.array([rng.choice(len(parents), 2, replace=False) for _ in range((n + 1) // 2)])
        D = self._uniform(D, pairs, rng)[:n]
        N = self._uniform(N, pairs, rng)[:n]
        return self._mutate(D, N, parents[0], rng)

    def mutants(self, parents: list[dict], n: int, rng: np.random.Generator) -> list[dict]:
        """``n`` mutated copies of parents drawn at random (local moves around them)."""
        if not parents or n <= 0:
            return []
        picks = rng.integers(len(parents), size=n)
        D, N = self.to_rows(parents)
        return self._mutate(D[picks], N[picks], parents[0], rng)

    # The operators' array-level ``_do`` (their extension point) is called directly: the
    # public ``do`` wraps every row in a pymoo ``Individual``, which cost more than the rest.
    def _uniform(self, X: np.ndarray, pairs: np.ndarray, rng) -> np.ndarray:
        if X.shape[1] == 0:
            return np.zeros((2 * len(pairs), 0))
        parents = np.stack([X[pairs[:, 0]], X[pairs[:, 1]]])   # (2 parents, matings, variables)
        return self._cross._do(None, parents, random_state=rng).reshape(-1, X.shape[1])

    def _mutate(self, D: np.ndarray, N: np.ndarray, base: dict, rng) -> list[dict]:
        if D.shape[1]:
            D = self._reset._do(self._discrete, D.astype(object), random_state=rng)
        if N.shape[1]:
            N = self._move._do(self._numeric, N, random_state=rng)
        return self.to_scenes(D.astype(float), N.astype(float), base)
