"""RQ2: how diverse are the failures?  Failing tests' embeddings are clustered with
k-means; per algorithm, coverage is the share of clusters holding at least one of its
failures and entropy the normalised Shannon entropy of its failures over all k clusters
(Biagiola and Tonella): 1 when spread evenly, 0 when all fall in one cluster.

k-means on such embeddings has many near-equal optima, so a difference in entropy between two
algorithms is also measured over several clusterings (``entropy_gaps``): a gap whose sign
changes with the k-means seed is not a finding."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from sklearn.cluster import KMeans


@dataclass(frozen=True)
class Clustering:
    labels: np.ndarray   # cluster of each embedded failure
    k_requested: int
    k: int               # clusters used: at most the number of distinct embeddings
    note: str = ""


def cluster_failures(embeddings: np.ndarray, k: int, seed: int = 0, fit: np.ndarray | None = None) -> Clustering:
    """k-means on L2-normalised embeddings (cosine geometry), k capped by the distinct points.
    ``fit``: a mask of the embeddings the clusters are fitted on; the others (a reference that must
    not move the clusters it is measured on) only get the label of their nearest centre."""
    if k < 1:
        raise ValueError(f"the number of clusters must be at least 1, got {k}")
    n = len(embeddings)
    unit = _normalise(np.asarray(embeddings, dtype=float)) if n else np.zeros((0, 0))
    fitted = unit if fit is None else unit[np.asarray(fit, dtype=bool)]
    if len(fitted) == 0:
        return Clustering(np.zeros(n, dtype=int), k, 0, "no failures to cluster")
    distinct = len(np.unique(np.round(fitted, 9), axis=0))
    used = min(k, distinct)
    note = f"k lowered from {k} to {used}: only {distinct} distinct failing embeddings" if used < k else ""
    if used == 1:
        return Clustering(np.zeros(n, dtype=int), k, 1, note)
    model = KMeans(n_clusters=used, n_init=10, random_state=seed).fit(fitted)
    labels = model.labels_ if fit is None else model.predict(unit)
    return Clustering(labels.astype(int), k, used, note)


def _normalise(x: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(x, axis=1, keepdims=True)
    return x / np.where(norms > 0, norms, 1.0)


def cluster_counts(labels, k: int) -> np.ndarray:
    """How many of the given failures fall in each of the k clusters (empty ones count 0)."""
    return np.bincount(np.asarray(labels, dtype=int), minlength=k)[:k] if k else np.zeros(0, dtype=int)


def coverage(labels, k: int) -> float:
    """Share of the k clusters that hold at least one of these failures (0 without failures)."""
    return float((cluster_counts(labels, k) > 0).sum() / k) if k else 0.0


def normalised_entropy(labels, k: int) -> float:
    """Shannon entropy of the failures over k clusters divided by log k.
    NaN without failures (undefined); 0 with a single cluster (no spread is possible)."""
    counts = cluster_counts(labels, k)
    total = counts.sum()
    if total == 0:
        return math.nan
    if k == 1:
        return 0.0
    p = counts[counts > 0] / total
    # rounded: an even spread is 1, not 1.0000000000000002 (float error in the sum)
    return round(min(1.0, float(-(p * np.log(p)).sum() / math.log(k))), 12)


CLUSTERINGS = 5   # k-means seeds an entropy gap is checked over (the first is the reported clustering)


def entropy_gaps(embeddings: np.ndarray, runs: list[tuple[str, object]], k: int, seed: int = 0,
                 clusterings: int = CLUSTERINGS, first: Clustering | None = None,
                 fit: np.ndarray | None = None) -> dict[tuple[str, str], list[float]]:
    """For every pair (a, b) of algorithms, the mean per-run entropy of a's failures minus b's, in
    each of ``clusterings`` k-means clusterings (seeds seed, seed + 1, ...; ``first``: the caller's
    clustering at ``seed``, not computed again; ``fit``: as ``cluster_failures``'s). ``runs`` names the
    (algorithm, run) of each embedded failure; runs without failures have no entropy and are left out."""
    if not runs:
        return {}
    algorithms = sorted({a for a, _ in runs})
    gaps: dict[tuple[str, str], list[float]] = {(a, b): [] for i, a in enumerate(algorithms)
                                                for b in algorithms[i + 1:]}
    for n in range(clusterings):
        clustering = first if n == 0 and first is not None else cluster_failures(embeddings, k, seed + n, fit)
        by_run: dict[tuple[str, object], list[int]] = {}
        for run, label in zip(runs, clustering.labels):
            by_run.setdefault(run, []).append(int(label))
        mean = {a: float(np.mean([normalised_entropy(labels, clustering.k) for run, labels in by_run.items()
                                  if run[0] == a])) for a in algorithms}
        for a, b in gaps:
            gaps[(a, b)].append(mean[a] - mean[b])
    return gaps
