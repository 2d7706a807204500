"""The search loop: propose scenes, evaluate them in parallel, commit each, learn.

Resuming replays the search from its seed: every test already in the archive is taken
from there instead of being evaluated again, so a resumed run proposes exactly the
scenes an uninterrupted one would (for a deterministic SUT) and loses nothing.
"""
from __future__ import annotations

import json
import platform
import time
from dataclasses import asdict, dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from ..archive import Archive, TestRecord
from ..execution import make_executor
from ..pipeline import Job, PipelineConfig
from ..progress import Progress
from ..space import load_space
from .algorithms import make_algorithm
from .diversity import DiversityTracker

RUN_FILE = "run.json"
ARCHIVE_FILE = "archive.sqlite"
# The fitness the search sees for a test without a verdict (SUT or render error): the
# best possible answer, so the search never mistakes an error for a failure.
NO_VERDICT_FITNESS = 1.0


class RunError(RuntimeError):
    """A run directory that cannot be started or resumed as asked."""


@dataclass
class RunConfig:
    pipeline: PipelineConfig
    algorithm: str = "surrogate"
    pop_size: int = 10
    seed: int = 1
    budget_tests: int | None = 40
    budget_s: float | None = None
    workers: int = 1
    cluster: str | None = None

    def identity(self) -> dict:
        """What must match for a resume to continue the same search."""
        data = asdict(self)
        for volatile in ("workers", "cluster", "budget_tests", "budget_s"):
            data.pop(volatile)
        data["pipeline"].pop("run_dir")
        data["pipeline"].pop("render_threads")  # how the work is spread, not what it computes
        return json.loads(json.dumps(data))  # as stored in run.json (tuples become lists)


@dataclass
class RunSummary:
    run_dir: Path
    tests: int = 0
    evaluated_now: int = 0
    failures: int = 0
    errors: int = 0
    generations: int = 0
    stopped_because: str = ""
    population: list = field(default_factory=list)


def _versions() -> dict:
    out = {"python": platform.python_version()}
    for name in ("isu-validate", "pymoo", "numpy", "bpy", "torch"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def _prepare_run_dir(config: RunConfig, resume: bool) -> Path:
    run_dir = Path(config.pipeline.run_dir)
    run_file = run_dir / RUN_FILE
    space = load_space(config.pipeline.space)
    if run_file.exists():
        if not resume:
            raise RunError(f"{run_dir} already holds a run; pass --resume to continue it or choose another --out")
        stored = json.loads(run_file.read_text())
        if stored.get("identity") != config.identity():
            raise RunError(f"{run_dir} holds a run with a different configuration; resume it with the options in "
                           f"{run_file}, or start a new run in another directory")
        if stored.get("space_hash") != space.hash:
            raise RunError(f"the scene space {config.pipeline.space!r} changed since {run_dir} was started "
                           f"(hash {stored.get('space_hash')} -> {space.hash}); start a new run")
        return run_dir
    if resume and run_dir.exists() and any(run_dir.iterdir()):
        raise RunError(f"nothing to resume: {run_file} is missing")
    run_dir.mkdir(parents=True, exist_ok=True)
    run_file.write_text(json.dumps({
        "identity": config.identity(), "config": asdict(config), "space_hash": space.hash,
        "space_source": space.source, "space": space.to_dict(), "versions": _versions(),
        "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }, indent=2, default=str))
    return run_dir


def run_search(config: RunConfig, resume: bool = False, progress_stream=None) -> RunSummary:
    run_dir = _prepare_run_dir(config, resume)
    space = load_space(config.pipeline.space)
    archive = Archive(run_dir / ARCHIVE_FILE)
    algorithm = make_algorithm(config.algorithm, space, config.pop_size, config.seed)
    diversity = DiversityTracker(space)
    executor = make_executor(config.pipeline, config.workers, config.cluster)
    progress = Progress(config.budget_tests, stream=progress_stream)
    summary = RunSummary(run_dir)
    elapsed_before = float(archive.get_meta("elapsed_s", 0.0))
    session_start = time.monotonic()
    try:
        generation = 0
        while True:
            reason = _budget_reason(config, summary.tests, elapsed_before + time.monotonic() - session_start)
            if reason:
                summary.stopped_because = reason
                break
            remaining = (config.budget_tests - summary.tests) if config.budget_tests else config.pop_size
            scenes = algorithm.ask(remaining)
            if not scenes:
                summary.stopped_because = "the scene space has no unseen scene left"
                break
            records = _evaluate_generation(config, generation, scenes, space, diversity, archive, executor,
                                           progress, summary)
            algorithm.tell(np.array([_objectives(r) for r in records]), records)
            archive.set_meta("elapsed_s", elapsed_before + time.monotonic() - session_start)
            generation += 1
            summary.generations = generation
    finally:
        archive.set_meta("elapsed_s", elapsed_before + time.monotonic() - session_start)
        executor.close()
        progress.close()
        archive.close()
    summary.population = getattr(algorithm, "population", [])
    return summary


def _budget_reason(config: RunConfig, tests: int, elapsed: float) -> str:
    if config.budget_tests is not None and tests >= config.budget_tests:
        return f"budget of {config.budget_tests} tests reached"
    if config.budget_s is not None and elapsed >= config.budget_s:
        return f"time budget of {config.budget_s:g} s reached"
    return ""


def _evaluate_generation(config, generation, scenes, space, diversity, archive, executor, progress, summary):
    records: list[TestRecord | None] = [None] * len(scenes)
    jobs = []
    for index, scene in enumerate(scenes):
        key = space.key(scene)
        job = Job(test_id=f"g{generation:04d}-i{index:03d}", generation=generation, index=index,
                  algorithm=config.algorithm, seed=config.seed, scene=scene, scene_key=key,
                  f_div=diversity.add(scene))
        stored = archive.get(job.test_id)
        if stored is None:
            jobs.append(job)
            continue
        if stored.scene_key != key:
            raise RunError(f"archive test {job.test_id} holds another scene than this search proposes; "
                           "the run was started with other settings or code: start a new run")
        records[index] = stored
        _count(summary, progress, stored, resumed=True)
    for record in executor.run(jobs):
        archive.add(record)  # durable before anything else happens
        records[record.index] = record
        summary.evaluated_now += 1
        _count(summary, progress, record, resumed=False)
    return records


def _count(summary: RunSummary, progress: Progress, record: TestRecord, resumed: bool) -> None:
    summary.tests += 1
    summary.failures += record.failed
    summary.errors += record.errored
    progress.update(failed=record.failed, errored=record.errored, resumed=resumed)


def _objectives(record: TestRecord) -> list[float]:
    fitness = NO_VERDICT_FITNESS if record.primary is None or record.errored else float(record.primary)
    return [fitness, -record.f_div]
