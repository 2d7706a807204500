"""``bench effectiveness --diagnose``: why NSGA-II barely beats random search, measured.

Against one benchmark SUT it runs NSGA-II as shipped and with one cause removed at a
time: the diversity objective held at zero, pymoo's categorical mutation rate lowered
from 1/2 per feature to 1/n, both, and population sizes for the same budget; and it
follows NSGA-II generation by generation: how far offspring are from their nearest
parent (against a random scene), how many were random top-ups after duplicate
elimination, how much of the surviving population passes, how novel the new tests are,
and how many of them fail.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pymoo.core.variable import Choice, Integer, Real
from pymoo.operators.mutation.pm import PM
from pymoo.operators.mutation.rm import ChoiceRandomMutation
from pymoo.operators.repair.rounding import RoundingRepair

from isu_validate.space import SceneSpace
from isu_validate.search.algorithms import NSGA2Search, make_algorithm
from isu_validate.bench.effectiveness.harness import simulate
from isu_validate.analysis.thresholds import thresholds_for
from isu_validate.bench.effectiveness.summary import BASELINE_RATE, failure_rates
from isu_validate.sut.planted import BenchmarkSUT


class _NoDiversity(NSGA2Search):
    """NSGA-II with the diversity objective held at zero: selection by fitness alone."""

    def tell(self, F, records=None):
        F = np.array(F, dtype=float)
        F[:, 1] = 0.0
        super().tell(F, records)


def _one_per_n(space, pop_size, seed, cls=NSGA2Search):
    n = sum(f.span > 0 for f in space.features.values())
    rate = 1.0 / n
    mutation = {Choice: ChoiceRandomMutation(prob_var=rate), Real: PM(prob_var=rate),
                Integer: PM(prob_var=rate, vtype=float, repair=RoundingRepair())}
    return cls(space, pop_size, seed, mutation=mutation)


VARIANTS = {
    "nsga2": lambda space, pop, seed: NSGA2Search(space, pop, seed),
    "nsga2, diversity objective at 0": lambda space, pop, seed: _NoDiversity(space, pop, seed),
    "nsga2, mutation 1/n per feature": lambda space, pop, seed: _one_per_n(space, pop, seed),
    "nsga2, both": lambda space, pop, seed: _one_per_n(space, pop, seed, _NoDiversity),
}


@dataclass
class Trace:
    """NSGA-II per generation, one list per measure (generations after the first)."""
    measures: dict[str, list[list[float]]] = field(default_factory=dict)

    def add(self, name: str, generation: int, value: float) -> None:
        rows = self.measures.setdefault(name, [])
        while len(rows) <= generation:
            rows.append([])
        rows[generation].append(value)


class _Traced(NSGA2Search):
    """NSGA-II as shipped, measuring what happens in each generation."""

    def __init__(self, space, pop_size, seed, trace: Trace, threshold: float):
        super().__init__(space, pop_size, seed)
        self.trace, self.threshold, self.generation = trace, threshold, 0
        self._probe = np.random.default_rng(seed + 10_000)

    def ask(self, n_max):
        parents = self.population
        scenes = super().ask(n_max)
        if parents and scenes:
            g = self.generation
            self.trace.add("features changed vs nearest parent", g, _changed(self.space, scenes, parents))
            self.trace.add("  the same for a random scene", g,
                           _changed(self.space, self.space.sample(self._probe, len(scenes)), parents))
            self.trace.add("random top-ups (share)", g, self.topped_up / len(scenes))
        return scenes

    def tell(self, F, records=None):
        super().tell(F, records)
        F = np.asarray(F, dtype=float)
        g = self.generation
        self.trace.add("novelty of the new tests", g, float(-F[:, 1].mean()))
        self.trace.add(f"new tests failing at {self.threshold:g} (share)", g, float(np.mean(F[:, 0] < self.threshold)))
        survivors = self.algorithm.pop.get("F")
        self.trace.add("surviving population passing (share)", g, float(np.mean(survivors[:, 0] >= 1.0)))
        self.generation += 1


def _changed(space: SceneSpace, scenes: list[dict], parents: list[dict]) -> float:
    """Mean number of features in which a scene differs from its nearest parent."""
    reference = np.array([space.canonical_vector(p) for p in parents])
    return float(np.mean([space.distances(space.canonical_vector(s), reference).min() for s in scenes])
                 * len(space.names))


def diagnose(space: SceneSpace, sut: BenchmarkSUT, seeds: list[int], budget: int, pop_size: int,
             pop_sizes: list[int]) -> list[str]:
    thresholds = list(thresholds_for("vqa"))
    makers = {"rs": lambda sp, pop, seed: make_algorithm("rs", sp, pop, seed), **VARIANTS,
              "surrogate": lambda sp, pop, seed: make_algorithm("surrogate", sp, pop, seed)}
    rows = [(f"{name} (pop {pop_size})", maker, pop_size) for name, maker in makers.items()]
    rows += [(f"nsga2 (pop {p})", VARIANTS["nsga2"], p) for p in pop_sizes if p != pop_size]
    rates = [np.mean([failure_rates(simulate(space, sut, "", seed, budget, pop, make=maker), thresholds)
                      for seed in seeds], axis=0) for _, maker, pop in rows]
    # the first threshold (from the most lenient) where random search finds less than 10%
    j = next((i for i, r in enumerate(rates[0]) if r < BASELINE_RATE), len(thresholds) - 1)
    lines = [f"diagnosis of nsga2 on {sut.name} ({sut.description}); budget {budget}, "
             f"{len(seeds)} seeds; failure rate (%) per threshold, mean over seeds", "",
             f"  {'variant':<40}" + "".join(f"{t:>7g}" for t in thresholds) + f"   ratio to rs at {thresholds[j]:g}"]
    for (label, _, _), r in zip(rows, rates):
        ratio = r[j] / rates[0][j] if rates[0][j] > 0 else float("nan")
        lines.append(f"  {label:<40}" + "".join(f"{v:7.1f}" for v in r) + f"   {ratio:.2f}x")
    lines += ["", f"  nsga2 (pop {pop_size}) per generation, mean over seeds:"]
    trace = Trace()
    for seed in seeds:
        simulate(space, sut, "", seed, budget, pop_size,
                 make=lambda sp, pop, sd: _Traced(sp, pop, sd, trace, thresholds[j]))
    for name, per_generation in trace.measures.items():
        values = [np.mean(v) if v else float("nan") for v in per_generation]
        lines.append(f"  {name:<42}" + "".join(f"{v:6.2f}" for v in values))
    return lines
