"""The search loop: propose scenes, evaluate them in parallel, commit each, learn.

Resuming replays the search from its seed: every test already in the archive is taken
from there instead of being evaluated again, so a resumed run proposes exactly the
scenes an uninterrupted one would (for a deterministic SUT) and loses nothing.

Nothing is written before every setting has been checked: the search algorithm, the
run directory (``archive.run_file``) and every component of the pipeline are built or
validated first, so a typo leaves no half-started run behind.
"""
from __future__ import annotations

import platform
import time
from dataclasses import asdict, dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from ..archive import Archive, TestRecord
from ..archive.run_file import ARCHIVE_FILE, RUN_FILE, RunError, check_run_dir, read_run_file, write_run_file
from ..execution import make_executor
from ..config import RunConfig   # a light module: the CLI shows RunConfig's defaults
from ..pipeline import Job, check_render_settings
from ..progress import Progress
from ..space import load_space
from .algorithms import make_algorithm
from .diversity import DiversityTracker
from .error_streak import SUTErrorsStop, SUTErrorStreak
from .prior_runs import read_prior_tests

__all__ = ["ARCHIVE_FILE", "RUN_FILE", "RunConfig", "RunError", "RunSummary", "SUTErrorsStop", "run_search"]
# The fitness the search sees for a test without a verdict (SUT or render error): the
# best possible answer, so the search never mistakes an error for a failure.
NO_VERDICT_FITNESS = 1.0

@dataclass
class RunSummary:
    run_dir: Path
    tests: int = 0
    evaluated_now: int = 0
    failures: int = 0
    errors: int = 0
    generations: int = 0
    stopped_because: str = ""
    last_sut_error: str | None = None
    population: list = field(default_factory=list)


def search_version(algorithm) -> str:
    return f"{algorithm.name}-{algorithm.version}"


def _versions(algorithm) -> dict:
    from ..render.renderer import RENDERER_VERSION   # `replay` re-renders a lost frame only with the same one

    out = {"python": platform.python_version(), "renderer": RENDERER_VERSION, "search": search_version(algorithm)}
    for name in ("isu-validate", "pymoo", "numpy", "bpy", "torch"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def run_search(config: RunConfig, resume: bool = False, progress_stream=None) -> RunSummary:
    """Run (or resume) a search; raises RunError (nothing written) for a run that cannot start as
    asked, and SUTErrorsStop (everything evaluated kept) when the SUT keeps failing.

        summary = run_search(RunConfig(PipelineConfig(run_dir="runs/s1", preset="draft"), budget_tests=4, pop_size=2))
        summary.tests, summary.failures, tests_table(summary.run_dir)
    """
    config.check()
    space = load_space(config.pipeline.space)
    check_render_settings(config.pipeline, space)   # an unregistered camera, a bad --min-visible
    run_dir = Path(config.pipeline.run_dir)
    algorithm = make_algorithm(config.algorithm, space, config.pop_size, config.seed)
    identity = config.identity()
    if config.learn_from:
        identity["learned_from"] = _learn(algorithm, config, space)
    new = check_run_dir(run_dir, identity, space.hash,
                        {"budget_tests": config.budget_tests, "budget_s": config.budget_s}, resume)
    if not new:
        _check_search_version(run_dir, algorithm)
    executor = make_executor(config.pipeline, config.workers, config.cluster)  # builds (checks) every component
    try:
        if new:
            write_run_file(run_dir, _run_file_content(config, space, identity, algorithm))
        summary, streak = _search(config, space, run_dir, algorithm, executor, progress_stream)
    finally:
        executor.close()
    if streak.tripped:
        raise SUTErrorsStop(streak, summary)
    return summary


def _learn(algorithm, config: RunConfig, space) -> str:
    """Hand the earlier runs' tests to the search; the digest of what it learnt from."""
    prior = read_prior_tests(config.learn_from, config.pipeline, space, config.pipeline.run_dir)
    try:
        algorithm.learn(prior.records)
    except ValueError as exc:
        raise RunError(str(exc)) from None
    return f"{len(prior.records)} tests, {prior.digest}"


def _check_search_version(run_dir: Path, algorithm) -> None:
    """A run started by another version of its search cannot be resumed: the seed would propose other scenes
    than its archive holds. (A run from before versions were recorded is checked scene by scene instead.)"""
    started = (read_run_file(run_dir).get("versions") or {}).get("search")
    if started not in (None, search_version(algorithm)):
        raise RunError(f"{run_dir} was started by search {started}; this installation's is "
                       f"{search_version(algorithm)}, which proposes other scenes for the same seed: start a new "
                       f"run in another folder (a surrogate run started with --learn-from {run_dir} learns from "
                       "this one's tests)")


def _run_file_content(config: RunConfig, space, identity: dict, algorithm) -> dict:
    return {"identity": identity, "config": asdict(config), "space_hash": space.hash,
            "space_source": space.source, "space": space.to_dict(), "versions": _versions(algorithm),
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def _search(config, space, run_dir, algorithm, executor, progress_stream):
    archive = Archive(run_dir / ARCHIVE_FILE)
    diversity = DiversityTracker(space)
    progress = Progress(config.budget_tests, stream=progress_stream)
    summary = RunSummary(run_dir)
    streak = SUTErrorStreak(config.stop_after_sut_errors)
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
                                           progress, summary, streak)
            if streak.tripped:
                summary.stopped_because = f"{streak.length} SUT errors in a row"
                break
            algorithm.tell(np.array([_objectives(r) for r in records]), records)
            archive.set_meta("elapsed_s", elapsed_before + time.monotonic() - session_start)
            generation += 1
            summary.generations = generation
    finally:
        archive.set_meta("elapsed_s", elapsed_before + time.monotonic() - session_start)
        progress.close()
        archive.close()
    summary.population = getattr(algorithm, "population", [])
    return summary, streak


def _budget_reason(config: RunConfig, tests: int, elapsed: float) -> str:
    if config.budget_tests is not None and tests >= config.budget_tests:
        return f"budget of {config.budget_tests} tests reached"
    if config.budget_s is not None and elapsed >= config.budget_s:
        return f"time budget of {config.budget_s:g} s reached"
    return ""


def _evaluate_generation(config, generation, scenes, space, diversity, archive, executor, progress, summary, streak):
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
        streak.add(record)
        if streak.tripped:
            executor.cancel_pending()  # what is already running still comes back and is kept
    return records


def _count(summary: RunSummary, progress: Progress, record: TestRecord, resumed: bool) -> None:
    summary.tests += 1
    summary.failures += record.failed
    summary.errors += record.errored
    summary.last_sut_error = record.sut_error or summary.last_sut_error
    progress.update(failed=record.failed, errored=record.errored, resumed=resumed)


def _objectives(record: TestRecord) -> list[float]:
    fitness = NO_VERDICT_FITNESS if record.primary is None or record.errored else float(record.primary)
    return [fitness, -record.f_div]
