"""Searches against a benchmark SUT in memory: the run loop's steps without rendering or disk.

One ``simulate`` call is one run: the algorithm proposes scenes (``ask``), each scene's
novelty comes from the same ``DiversityTracker`` the run loop uses, the benchmark SUT
answers, the real VQA judge scores, and the algorithm learns from the same records and
objectives the run loop hands it (``tell``).  Only ask, diversity and tell are timed:
that is the search's own cost per test, as CPU time of this thread (other processes
on a shared machine do not inflate it; wall-clock figures come from ``bench search``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from isu_validate.archive import TestRecord
from isu_validate.evaluate.vqa import VQAJudge
from isu_validate.protocols import SUTRequest, SUTResponse, Verdict
from isu_validate.space import SceneSpace
from isu_validate.search.algorithms import make_algorithm
from isu_validate.search.diversity import DiversityTracker
from isu_validate.search.loop import _objectives


@dataclass
class Outcome:
    """One run: its tests in order, and the seconds the search itself spent (None: not measured)."""
    algorithm: str
    seed: int
    sut: str
    records: list[TestRecord] = field(default_factory=list)
    search_s: float | None = 0.0

    def values(self) -> list[float]:
        """Response fitness of every test with a verdict."""
        return [r.primary for r in self.records if not r.errored and r.primary is not None]

    def failing_scenes(self) -> list[dict]:
        """Canonical scenes the run's oracle judged failing."""
        return [r.canonical for r in self.records if r.failed]


class InstantEvaluation:
    """A benchmark (or emulated) SUT answering and the real VQA judge scoring: a verdict in microseconds."""

    def __init__(self, space: SceneSpace, sut, threshold: float | None = None):
        self.space, self.sut, self.judge = space, sut, VQAJudge(space, threshold)

    def __call__(self, canonical: dict) -> tuple[dict, Verdict]:
        answers = self.sut.answer(self.space, canonical)
        request = SUTRequest(mode="vqa", image=Path(""), prompt="", questions=self.space.questions(canonical))
        occluded = self.sut.occluded(self.space, canonical)
        return answers, self.judge.judge(canonical, request, SUTResponse(raw=repr(answers), answers=answers), occluded)


def simulate(space: SceneSpace, sut, algorithm: str, seed: int, budget: int, pop_size: int,
             threshold: float | None = None, make=None) -> Outcome:
    """One run of ``algorithm`` (a name, or ``make(space, pop_size, seed)`` builds the search)."""
    search = make(space, pop_size, seed) if make else make_algorithm(algorithm, space, pop_size, seed)
    diversity = DiversityTracker(space)
    evaluate = InstantEvaluation(space, sut, threshold)
    outcome = Outcome(algorithm, seed, sut.name)
    generation = 0
    while len(outcome.records) < budget:
        start = time.thread_time()
        scenes = search.ask(budget - len(outcome.records))
        novelty = [diversity.add(scene) for scene in scenes]
        outcome.search_s += time.thread_time() - start
        if not scenes:
            break
        records = [_record(space, evaluate, algorithm, seed, generation, i, scene, f_div)
                   for i, (scene, f_div) in enumerate(zip(scenes, novelty))]
        start = time.thread_time()
        search.tell(np.array([_objectives(r) for r in records]), records)
        outcome.search_s += time.thread_time() - start
        outcome.records += records
        generation += 1
    return outcome


def _record(space, evaluate, algorithm, seed, generation, index, scene, f_div) -> TestRecord:
    """The test as the run loop would archive it (without image, timings or raw reply)."""
    canonical = space.canonical(scene)
    record = TestRecord(test_id=f"g{generation:04d}-i{index:03d}", generation=generation, index=index,
                        algorithm=algorithm, seed=seed, scene_key=space.key(scene), scene=scene,
                        canonical=canonical, f_div=f_div)
    answers, verdict = evaluate(canonical)
    record.answers = answers
    record.fitness, record.primary, record.failed = dict(verdict.fitness), verdict.primary, verdict.failed
    record.details["verdict"] = verdict.details
    return record
