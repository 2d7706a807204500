"""Where a generation's tests are evaluated: in this process, a local process pool, or Dask.

Each executor yields records as they complete, so the run loop commits every test the
moment it exists (nothing is lost when the run is killed mid-generation).
"""
from __future__ import annotations

import atexit
import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Iterable, Iterator

from .archive import TestRecord
from .pipeline import Job, PipelineConfig, close_pipelines, evaluate_job

DASK_CONNECT_TIMEOUT_S = 10


class InProcessExecutor:
    """``--workers 1``: no pool, no pickling; the renderer worker is still its own process."""

    def __init__(self, config: PipelineConfig):
        self.config = config

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        for job in jobs:
            yield evaluate_job(self.config, job)

    def close(self) -> None:
        close_pipelines()


class LocalPoolExecutor:
    """``--workers N``: N processes, each with its own renderer and SUT client."""

    def __init__(self, config: PipelineConfig, workers: int):
        self.config = config
        # spawn, not fork: torch and the renderer's pipes do not survive a fork cleanly
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                        initializer=_close_at_exit)

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        futures = [self.pool.submit(evaluate_job, self.config, job) for job in jobs]
        for future in as_completed(futures):
            yield future.result()

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """``--cluster ADDRESS``: a Dask distributed scheduler (each worker builds one pipeline)."""

    def __init__(self, config: PipelineConfig, address: str):
        from distributed import Client

        self.config = config
        try:
            self.client = Client(address, timeout=f"{DASK_CONNECT_TIMEOUT_S}s")
        except OSError as exc:
            raise ConnectionError(f"cannot reach the Dask scheduler at {address}: {exc}; "
                                  "start one with `dask scheduler` or drop --cluster") from None

    def run(self, jobs: Iterable[Job]) -> Iterator[TestRecord]:
        from distributed import as_completed as dask_completed

        jobs = list(jobs)
        futures = [self.client.submit(evaluate_job, self.config, job, pure=False) for job in jobs]
        for future in dask_completed(futures):
            yield future.result()

    def close(self) -> None:
        self.client.close()


def _close_at_exit() -> None:
    atexit.register(close_pipelines)


def make_executor(config: PipelineConfig, workers: int = 1, cluster: str | None = None):
    if cluster:
        return DaskExecutor(config, cluster)
    if workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    return InProcessExecutor(config) if workers == 1 else LocalPoolExecutor(config, workers)
