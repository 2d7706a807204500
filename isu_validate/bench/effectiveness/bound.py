"""The known-risk bound: what a search could reach if it knew where the SUT is likely to fail.

Not a search a user runs, but a reference line for ``bench effectiveness --bound``.  It picks
each test from a bank of random valid scenes with weight P(fail)^alpha, where P(fail) is each
scene's failure probability at the goal's threshold, estimated over other noise seeds of the
same benchmark or emulated SUT.  It knows the probability, never the outcome the bench then
draws: a search that had learnt the SUT perfectly could do this well and no better.  Because it
spreads its picks over the whole space in proportion to the risk, it shows whether a failure
rate and a failure-cluster entropy are reachable together on a SUT, which tells a search that
misses the goal from a goal that no search could meet.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from isu_validate.analysis.thresholds import fails_at
from isu_validate.space import SceneSpace
from isu_validate.search.base import SearchAlgorithm
from isu_validate.bench.effectiveness.harness import InstantEvaluation

BANK_SCENES = 2000          # random scenes the bound picks from
RISK_SEEDS = 8              # noise seeds of the SUT its failure probability is estimated over
RISK_SEED_OFFSET = 1000     # the estimate's draws: seeds apart from the one the bench's own draws use
BANK_SEED = 20261123


@dataclass
class RiskBank:
    """Random valid scenes and their response fitness under ``RISK_SEEDS`` other draws of the SUT."""
    scenes: list[dict]
    fitness: np.ndarray     # (seeds, scenes); nan where a draw gave no verdict

    def risk(self, threshold: float) -> np.ndarray:
        """Per scene, the share of draws failing at ``threshold`` (the judge's rule)."""
        fails = [[fails_at("vqa", None if np.isnan(v) else float(v), threshold) for v in row] for row in self.fitness]
        return np.array(fails, dtype=float).mean(axis=0) if len(fails) else np.zeros(len(self.scenes))


def risk_bank(space: SceneSpace, sut, size: int = BANK_SCENES, seeds: int = RISK_SEEDS) -> RiskBank:
    """The bank for ``sut``, which must be a benchmark or emulated SUT (its noise redrawn by ``seed``)."""
    if not (dataclasses.is_dataclass(sut) and any(f.name == "seed" for f in dataclasses.fields(sut))):
        raise ValueError(f"the bound redraws the noise of a benchmark or emulated SUT; {sut.name!r} is neither")
    if size < 1 or seeds < 1:
        raise ValueError(f"the bound needs at least one scene and one noise seed, got {size} and {seeds}")
    rng, scenes = np.random.default_rng(BANK_SEED), {}
    for _ in range(20 * size):  # a small space may hold fewer distinct scenes than asked for
        if len(scenes) >= size:
            break
        scene = space.sample(rng, 1)[0]
        scenes.setdefault(space.key(scene), scene)
    scenes = list(scenes.values())
    canonical = [space.canonical(s) for s in scenes]
    fitness = np.full((seeds, len(scenes)), np.nan)
    for row in range(seeds):
        evaluate = InstantEvaluation(space, dataclasses.replace(sut, seed=sut.seed + RISK_SEED_OFFSET + row))
        for i, scene in enumerate(canonical):
            primary = evaluate(scene)[1].primary
            fitness[row, i] = np.nan if primary is None else primary
    return RiskBank(scenes, fitness)


class KnownRiskSearch(SearchAlgorithm):
    """Each slot draws an untested bank scene with weight risk^alpha (at random where no risk is left)."""
    name = "bound"

    def __init__(self, space: SceneSpace, pop_size: int, seed: int, bank: RiskBank, risk: np.ndarray,
                 alpha: float):
        super().__init__(space, pop_size, seed)
        if alpha < 0 or not np.isfinite(alpha):
            raise ValueError(f"the bound's alpha must be a number >= 0, got {alpha}")
        self.bank, self.alpha = bank, alpha
        self.weights = np.power(np.clip(risk, 0.0, 1.0), alpha)
        self.rng = np.random.default_rng(seed)
        self._unused = np.ones(len(bank.scenes), dtype=bool)

    def ask(self, n_max: int) -> list[dict]:
        scenes = []
        for _ in range(min(n_max, self.pop_size, int(self._unused.sum()))):
            weights = self.weights * self._unused
            if weights.sum() <= 0:
                weights = self._unused.astype(float)
            pick = int(self.rng.choice(len(weights), p=weights / weights.sum()))
            self._unused[pick] = False
            scenes.append(self.bank.scenes[pick])
        self.seen.update(self.space.key(s) for s in scenes)
        return scenes

    def tell(self, F: np.ndarray, records: list | None = None) -> None:
        """Nothing to learn: the bound knows the risk from the start."""
