"""``bench effectiveness --pipeline``: the same comparison through the real pipeline.

Every (algorithm, seed) is an ordinary run directory ``OUT/<algorithm>-s<seed>`` written
by ``run_search`` (render, SUT, judge, archive), so ``isu-validate report OUT`` reads them
like any run.  Runs go seed by seed, each algorithm in turn, so a killed bench leaves
balanced results; running the same command again resumes: finished runs are replayed
from their archives, a half-finished one continues where it stopped, and a run stored
with other settings is refused (``run_search`` checks the configuration) rather than
silently measured differently.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from isu_validate.archive import RunDir
from isu_validate.errors import InputError
from isu_validate.pipeline import PipelineConfig
from isu_validate.search.loop import RunConfig, RunError, run_search
from isu_validate.bench.effectiveness.harness import Outcome


@dataclass
class PipelineSettings:
    out: Path
    sut: str
    space: str
    algorithms: list[str]
    seeds: list[int]
    budget: int
    pop_size: int
    preset: str = "draft"
    camera: str = "default"
    cabin: str = "default"
    repeats: int = 1
    sut_timeout_s: float = 60.0
    sut_options: dict | None = None
    workers: int = 1
    render_threads: int = 0


def run_dir(settings: PipelineSettings, algorithm: str, seed: int) -> Path:
    return settings.out / f"{algorithm}-s{seed}"


def run_all(settings: PipelineSettings, log=print) -> list[Outcome]:
    jobs = [(seed, algo) for seed in settings.seeds for algo in settings.algorithms]
    for number, (seed, algo) in enumerate(jobs, 1):
        folder = run_dir(settings, algo, seed)
        config = _config(settings, algo, seed, folder)
        try:
            summary = run_search(config, resume=RunDir(folder).is_run(), progress_stream=sys.stderr)
        except RunError as exc:  # e.g. other settings than the stored runs: never measure them silently
            raise InputError(f"{exc} (bench effectiveness --pipeline resumes the runs in {settings.out}: "
                             "rerun it with their settings, or give another --out)") from None
        log(f"[{number}/{len(jobs)}] {algo} seed {seed}: {summary.tests} tests ({summary.evaluated_now} evaluated "
            f"now), {summary.failures} failing, {summary.errors} with errors -> {folder}")
    return [read_outcome(run_dir(settings, algo, seed), algo, seed, settings.sut) for seed, algo in jobs]


def _config(settings: PipelineSettings, algorithm: str, seed: int, folder: Path) -> RunConfig:
    pipeline = PipelineConfig(run_dir=str(folder), space=settings.space, sut=settings.sut, mode="vqa",
                              repeats=settings.repeats, preset=settings.preset, camera=settings.camera,
                              cabin=settings.cabin, sut_timeout_s=settings.sut_timeout_s,
                              sut_options=dict(settings.sut_options or {}), render_threads=settings.render_threads)
    return RunConfig(pipeline=pipeline, algorithm=algorithm, pop_size=settings.pop_size, seed=seed,
                     budget_tests=settings.budget, workers=settings.workers)


def read_outcome(folder: Path, algorithm: str, seed: int, sut: str) -> Outcome:
    """A finished run directory as an ``Outcome`` (the search's own time is not stored: None)."""
    return Outcome(algorithm, seed, sut, RunDir(folder).records(), search_s=None)
