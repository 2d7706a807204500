"""Where a generation's tests are evaluated: in this process, a local process pool, or Dask.

Each executor yields records as they complete, so the run loop commits every test the
moment it exists (nothing is lost when the run is killed mid-generation).  Making an
executor checks the pipeline (every component is built once before the run writes
anything) and, for Dask, reaches the scheduler; ``cancel_pending`` drops the jobs not
yet started when the run must stop; ``close`` leaves no renderer running behind.

What runs is a ``Task``: the run's pipeline (``PIPELINE``, the default) or another per-process worker
state with the same four entry points (``dataset`` renders its images through ``dataset/images.py``).
"""
from __future__ import annotations

import atexit
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, Iterable, Iterator

from .archive import TestRecord
from .errors import InputError
from .pipeline import Job, PipelineConfig, check_pipeline, close_pipeline, close_pipelines, evaluate_job, open_pipeline

DASK_CONNECT_TIMEOUT_S = 10


@dataclass(frozen=True)
class Task:
    """What an executor runs, as module-level functions (they reach pool and Dask workers by reference):
    ``open(config)`` builds this process's worker state for ``config`` (kept for every job), ``check(config)``
    builds it once and closes it again (raises what a worker would), ``work(config, job)`` does one job,
    ``close(config)`` ends this process's state, ``close_all()`` every state of this process."""
    open: Callable[[Any], Any]
    check: Callable[[Any], None]
    work: Callable[[Any, Any], Any]
    close: Callable[[Any], None]
    close_all: Callable[[], None]


PIPELINE = Task(open_pipeline, check_pipeline, evaluate_job, close_pipeline, close_pipelines)


class InProcessExecutor:
    """``--workers 1``: no pool, no pickling; the renderer worker is still its own process."""

    def __init__(self, config: PipelineConfig, task: Task = PIPELINE):
        self.config, self.task = config, task
        task.open(config)  # built now (a bad setting fails here), then used for every job
        self._cancelled = False

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        self._cancelled = False
        for job in jobs:
            if self._cancelled:
                return
            yield self.task.work(self.config, job)

    def cancel_pending(self) -> None:
        self._cancelled = True

    def close(self) -> None:
        self.task.close(self.config)


class LocalPoolExecutor:
    """``--workers N``: N processes, each with its own renderer and SUT client."""

    def __init__(self, config: PipelineConfig, workers: int, task: Task = PIPELINE):
        self.config, self.task = config, task
        task.check(config)  # here, where an error is one clear line, before any worker starts
        # spawn, not fork: torch and the renderer's pipes do not survive a fork cleanly
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                        initializer=partial(_close_at_exit, task.close_all))
        self._futures: list = []

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        self._futures = [self.pool.submit(self.task.work, self.config, job) for job in jobs]
        for future in as_completed(self._futures):
            if not future.cancelled():
                yield future.result()

    def cancel_pending(self) -> None:
        for future in self._futures:
            future.cancel()  # only those not yet running: the others finish and are kept

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """``--cluster ADDRESS``: a Dask distributed scheduler (each worker builds one pipeline)."""

    def __init__(self, config: PipelineConfig, address: str, task: Task = PIPELINE):
        from distributed import Client

        self.config, self.task = config, task
        try:
            self.client = Client(address, timeout=f"{DASK_CONNECT_TIMEOUT_S}s")
        except OSError as exc:
            raise ConnectionError(f"cannot reach the Dask scheduler at {address}: {exc}; "
                                  "start one with `dask scheduler` or drop --cluster") from None
        try:  # on a worker: its files, its environment (API keys) are what the jobs will see
            self.client.submit(task.check, config, pure=False).result()
        except BaseException:
            self.client.close()
            raise
        self._futures: list = []

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        from distributed import as_completed as dask_completed

        self._futures = [self.client.submit(self.task.work, self.config, job, pure=False) for job in jobs]
        for future in dask_completed(self._futures):
            if not future.cancelled():
                yield future.result()

    def cancel_pending(self) -> None:
        self.client.cancel([f for f in self._futures if not f.done()])

    def close(self) -> None:
        # each worker keeps one pipeline (and its Blender process) per run configuration: end ours
        try:
            self.client.run(self.task.close, self.config)
        except Exception:  # noqa: BLE001 - a lost worker or scheduler has nothing left to close;
            pass           # an error here must not hide the one that ended the run
        finally:
            self.client.close()


def _close_at_exit(close_all: Callable[[], None]) -> None:
    atexit.register(close_all)


def make_executor(config: PipelineConfig, workers: int = 1, cluster: str | None = None, task: Task = PIPELINE):
    if cluster:
        return DaskExecutor(config, cluster, task)
    if workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    return InProcessExecutor(config, task) if workers == 1 else LocalPoolExecutor(config, workers, task)


def render_threads(workers: int) -> int:
    """Split the cores between parallel renderers (0 = Blender takes all, for one worker)."""
    return 0 if workers <= 1 else max(1, (os.cpu_count() or 1) // workers)
