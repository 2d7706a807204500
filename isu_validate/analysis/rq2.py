"""RQ2 over a set of runs of one SUT and mode: embed every failing test, cluster the
embeddings, and measure per run and per algorithm the coverage and entropy of its
failures over the clusters; compare algorithms on the per-run values, and the entropy
difference also over several clusterings (k-means seeds, ``diversity.entropy_gaps``)."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ..archive import TestRecord
from .diversity import Clustering, cluster_counts, cluster_failures, coverage, entropy_gaps, normalised_entropy
from .embeddings import Embedder
from .runs import Run


@dataclass
class Diversity:
    items: list[tuple[Run, TestRecord]]   # the clustered failures
    vectors: np.ndarray                   # their embeddings
    clustering: Clustering
    skipped: int                          # failures without an image file
    per_run: list[dict] = field(default_factory=list)
    per_algorithm: list[dict] = field(default_factory=list)
    counts: dict[str, np.ndarray] = field(default_factory=dict)   # algorithm -> failures per cluster
    statistics: list[dict] = field(default_factory=list)
    entropy_gaps: list[dict] = field(default_factory=list)       # per pair of algorithms, over several clusterings

    def assignments(self) -> list[dict]:
        return [{"run": r.name, "test_id": rec.test_id, "algorithm": r.algorithm, "cluster": int(c)}
                for (r, rec), c in zip(self.items, self.clustering.labels)]


def measure_diversity(runs: list[Run], embedder: Embedder, k: int, seed: int = 0, log=None) -> Diversity:
    items, vectors, skipped = embed_failures(runs, embedder, log)
    clustering = cluster_failures(vectors, k, seed)
    result = Diversity(items, vectors, clustering, skipped)
    pairs = [(run, int(c)) for (run, _), c in zip(items, clustering.labels)]
    result.per_run = [_measures(run.name, run.algorithm, run.seed, [c for r, c in pairs if r is run],
                                clustering.k) for run in runs]
    for algo in sorted({r.algorithm for r in runs}):
        labels = [c for r, c in pairs if r.algorithm == algo]
        result.counts[algo] = cluster_counts(labels, clustering.k)
        result.per_algorithm.append(_algorithm_row(algo, labels, clustering.k, result.per_run))
    result.statistics = compare(result.per_run, sorted(result.counts))
    if len(result.counts) > 1:
        gaps = entropy_gaps(vectors, [(run.algorithm, run.name) for run, _ in items], k, seed, first=clustering)
        result.entropy_gaps = [{"a": a, "b": b, "clusterings": len(g), "mean": float(np.mean(g)),
                                "min": min(g), "max": max(g), "sign stable": min(g) >= 0 or max(g) <= 0}
                               for (a, b), g in gaps.items()]
    return result


def embed_failures(runs: list[Run], embedder: Embedder, log=None):
    """(failing tests embedded, their vectors, how many had no image)."""
    items = [(run, rec) for run in runs for rec in run.failures]
    if not embedder.needs_images:
        return items, embedder.embed_scenes(runs[0].space, [rec.canonical for _, rec in items]), 0
    paths = [run.image_path(rec) for run, rec in items]
    kept = [(item, p) for item, p in zip(items, paths) if p is not None]
    if log:
        log(f"report: embedding {len(kept)} failing images ({embedder.name})")
    vectors = embedder.embed_images([p for _, p in kept]) if kept else np.zeros((0, 1))
    return [item for item, _ in kept], vectors, len(items) - len(kept)


def _measures(run: str, algorithm: str, seed, labels: list[int], k: int) -> dict:
    return {"run": run, "algorithm": algorithm, "seed": seed, "failures": len(labels),
            "coverage": coverage(labels, k) if k else math.nan,
            "entropy": normalised_entropy(labels, k) if k else math.nan}


def _algorithm_row(algo: str, labels: list[int], k: int, per_run: list[dict]) -> dict:
    """Pooled over the algorithm's runs, and mean/std of the per-run values."""
    row = _measures("", algo, "", labels, k)
    del row["run"], row["seed"]
    mine = [r for r in per_run if r["algorithm"] == algo]
    row["runs"] = len(mine)
    for measure in ("coverage", "entropy"):
        row[f"{measure} per run mean"], row[f"{measure} per run std"] = mean_std([r[measure] for r in mine])
    return row


def mean_std(values: list[float]) -> tuple[float, float]:
    """Over the finite values; the std needs two (NaN otherwise)."""
    arr = np.array([v for v in values if math.isfinite(v)], dtype=float)
    if len(arr) == 0:
        return math.nan, math.nan
    return float(arr.mean()), float(arr.std(ddof=1)) if len(arr) > 1 else math.nan


def compare(per_run: list[dict], algos: list[str]) -> list[dict]:
    """Rank-sum test and A12 on per-run coverage and entropy, for every pair of algorithms."""
    from .stats import rank_sum_test, vargha_delaney

    rows = []
    for measure in ("coverage", "entropy"):
        for a, b in itertools.combinations(algos, 2):
            x = [r[measure] for r in per_run if r["algorithm"] == a]
            y = [r[measure] for r in per_run if r["algorithm"] == b]
            test, effect = rank_sum_test(x, y), vargha_delaney(x, y)
            rows.append({"measure": measure, "a": a, "b": b, "runs_a": test.n1, "runs_b": test.n2, "U": test.u,
                         "p": test.p, "method": test.method, "A12": effect.a12, "magnitude": effect.magnitude,
                         "note": test.note})
    return rows
