"""Failures over time: cumulative failures against tests run and against wall time, per run,
and per algorithm the mean with a +-1 standard deviation band over its runs."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .runs import Run

TIME_POINTS = 200


@dataclass
class Band:
    x: np.ndarray
    mean: np.ndarray
    std: np.ndarray     # 0 where only one run reaches x
    runs: np.ndarray    # how many runs reach x


def cumulative(run: Run) -> tuple[np.ndarray, np.ndarray]:
    """(elapsed seconds, cumulative failures) after each test, in evaluation order."""
    failed = np.array([r.failed and not r.errored for r in run.records], dtype=float)
    elapsed = np.array([run.elapsed(r) for r in run.records], dtype=float)
    return elapsed, np.cumsum(failed)


def band_by_tests(runs: list[Run]) -> Band:
    curves = [cumulative(r)[1] for r in runs]
    length = max((len(c) for c in curves), default=0)
    x = np.arange(1, length + 1)
    return _band(x, [np.concatenate([c, np.full(length - len(c), np.nan)]) for c in curves])


def band_by_time(runs: list[Run], horizon: float | None = None) -> Band:
    """Failures found by each moment; a run that has ended keeps its final count."""
    curves = [cumulative(r) for r in runs]
    horizon = horizon or max((float(t[-1]) for t, _ in curves if len(t)), default=0.0)
    x = np.linspace(0.0, horizon, TIME_POINTS) if horizon > 0 else np.zeros(1)
    rows = []
    for t, c in curves:
        counts = np.searchsorted(t, x, side="right")
        rows.append(np.where(counts > 0, np.concatenate([[0.0], c])[counts], 0.0))
    return _band(x, rows)


def _band(x: np.ndarray, rows: list[np.ndarray]) -> Band:
    if not rows or len(x) == 0:
        return Band(x, np.zeros(len(x)), np.zeros(len(x)), np.zeros(len(x), dtype=int))
    data = np.vstack(rows)
    reached = np.isfinite(data).sum(axis=0)
    with np.errstate(invalid="ignore"):
        mean = np.nanmean(np.where(reached > 0, data, 0.0), axis=0)
        std = np.nanstd(np.where(reached > 0, data, 0.0), axis=0, ddof=0)
    return Band(x, mean, np.where(reached > 1, std, 0.0), reached)
