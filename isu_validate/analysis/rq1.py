"""RQ1: how many failures does each algorithm find?  Per run, the failure rate at each
threshold (tests with a SUT or render error have no verdict: they are counted apart and
left out of the rates); per SUT, mode and algorithm, the mean and standard deviation over
repeated runs; between algorithms, the rank-sum test and A12 on the per-run rates."""
from __future__ import annotations

import itertools
import math
from collections import defaultdict

import numpy as np

from .runs import Run
from .thresholds import fails_at


def rate_key(threshold: float) -> str:
    return f"fail%@{threshold:g}"


def run_rates(run: Run) -> dict:
    """One row per run: counts and the failure rate (%) at each of its mode's thresholds."""
    values = [run.metric(r) for r in run.valid]
    row = {"run": run.name, "sut": run.sut, "mode": run.mode, "algorithm": run.algorithm, "seed": run.seed,
           "tests": len(run.records), "with_verdict": len(run.valid), "failures": len(run.failures),
           "sut_errors": len(run.sut_errors), "render_errors": len(run.render_errors),
           "occluded": sum(len(r.occluded) for r in run.valid)}   # features hidden, left out of the fitness
    for t in run.thresholds:
        failing = sum(fails_at(run.mode, v, t) for v in values)
        row[rate_key(t)] = 100.0 * failing / len(values) if values else math.nan
    return row


def _mean_std(values: list[float]) -> tuple[float, float]:
    arr = np.array([v for v in values if isinstance(v, (int, float)) and math.isfinite(v)], dtype=float)
    if len(arr) == 0:
        return math.nan, math.nan
    return float(arr.mean()), float(arr.std(ddof=1)) if len(arr) > 1 else math.nan


def grouped(runs: list[Run]) -> dict[tuple, list[Run]]:
    """(sut, mode, algorithm) -> runs, in a stable order."""
    groups: dict[tuple, list[Run]] = defaultdict(list)
    for run in runs:
        groups[(run.sut, run.mode, run.algorithm)].append(run)
    return dict(sorted(groups.items()))


def rq1_table(runs: list[Run]) -> dict[str, list[dict]]:
    """mode -> rows (one per SUT and algorithm): mean and std over runs (std needs two runs)."""
    tables: dict[str, list[dict]] = defaultdict(list)
    for (sut, mode, algorithm), members in grouped(runs).items():
        per_run = [run_rates(r) for r in members]
        row = {"sut": sut, "algorithm": algorithm, "runs": len(members)}
        rates = [rate_key(t) for t in members[0].thresholds]
        for column in ["tests", "failures", "sut_errors", "render_errors", "occluded"] + rates:
            row[f"{column} mean"], row[f"{column} std"] = _mean_std([r[column] for r in per_run])
        tables[mode].append(row)
    return dict(tables)


def comparisons(runs: list[Run]) -> list[dict]:
    """Every pair of algorithms within one SUT and mode, at every threshold."""
    from .stats import rank_sum_test, vargha_delaney  # SciPy: only when comparing

    rows = []
    by_setting: dict[tuple, dict[str, list[dict]]] = defaultdict(dict)
    for (sut, mode, algorithm), members in grouped(runs).items():
        by_setting[(sut, mode)][algorithm] = [run_rates(r) for r in members]
    for (sut, mode), algos in by_setting.items():
        for a, b in itertools.combinations(sorted(algos), 2):
            first = next(iter(r for r in runs if r.mode == mode))
            for t in first.thresholds:
                x = [r[rate_key(t)] for r in algos[a]]
                y = [r[rate_key(t)] for r in algos[b]]
                test, effect = rank_sum_test(x, y), vargha_delaney(x, y)
                note = test.note
                if test.method == "undefined":
                    empty = a if test.n1 == 0 else b
                    note = f"no run of {empty} has a test with a verdict: nothing to compare"
                rows.append({"sut": sut, "mode": mode, "threshold": t, "a": a, "b": b,
                             "runs_a": test.n1, "runs_b": test.n2,
                             "median_a": _median(x), "median_b": _median(y), "U": test.u, "p": test.p,
                             "method": test.method, "A12": effect.a12, "magnitude": effect.magnitude,
                             "note": note})
    return rows


def _median(values: list[float]) -> float:
    arr = np.array([v for v in values if math.isfinite(v)], dtype=float)
    return float(np.median(arr)) if len(arr) else math.nan
