"""The report's figures, drawn with matplotlib (Agg) and returned as PNG data URIs."""
from __future__ import annotations

import base64
import io
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from .timeline import Band  # noqa: E402

DPI = 100
COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"]


def to_data_uri(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def colour(i: int) -> str:
    return COLOURS[i % len(COLOURS)]


def bands(series: dict[str, Band], xlabel: str, title: str) -> str:
    """One mean line with a +-1 std band per algorithm."""
    fig, ax = plt.subplots(figsize=(6.2, 3.6))
    for i, (name, band) in enumerate(series.items()):
        runs = int(band.runs.max(initial=0))
        ax.plot(band.x, band.mean, color=colour(i), label=f"{name} ({runs} run{'' if runs == 1 else 's'})")
        ax.fill_between(band.x, band.mean - band.std, band.mean + band.std, color=colour(i), alpha=0.2, lw=0)
    ax.set(xlabel=xlabel, ylabel="cumulative failures", title=title)
    ax.set_ylim(bottom=0)
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    if xlabel == "tests":
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    if series:
        ax.legend(fontsize=8, loc="upper left")
    return to_data_uri(fig)


def rates_by_threshold(thresholds: Sequence[float], series: dict[str, tuple[list[float], list[float]]],
                       metric: str) -> str:
    """Failure rate (%) against threshold, mean with std error bars, one line per algorithm."""
    fig, ax = plt.subplots(figsize=(6.2, 3.6))
    for i, (name, (mean, std)) in enumerate(series.items()):
        ax.errorbar(thresholds, mean, yerr=np.nan_to_num(std), color=colour(i), marker="o", capsize=3, label=name)
    ax.set(xlabel=f"threshold on {metric}", ylabel="failure rate (%)", ylim=(-2, 102),
           title="Failure rate by threshold")
    ax.invert_xaxis()
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return to_data_uri(fig)


def horizontal_bars(labels: Sequence[str], values: Sequence[float], xlabel: str, title: str) -> str:
    height = max(1.8, 0.28 * len(labels) + 0.8)
    fig, ax = plt.subplots(figsize=(6.2, height))
    y = np.arange(len(labels))
    ax.barh(y, values, color="#c0392b")
    ax.set_yticks(y, labels, fontsize=8)
    ax.invert_yaxis()
    ax.set(xlabel=xlabel, title=title, xlim=(0, max(1.0, max(values, default=0) * 1.05)))
    ax.grid(axis="x", alpha=0.3)
    return to_data_uri(fig)


def fitness_over_tests(values: Sequence[float], failed: Sequence[bool], errors: Sequence[bool],
                       metric: str, threshold: float | None) -> str:
    """Each test's fitness in evaluation order, failures red, errors as grey ticks at the bottom,
    with the cumulative failures on a second axis."""
    fig, ax = plt.subplots(figsize=(6.8, 3.6))
    x = np.arange(1, len(values) + 1)
    vals = np.array([np.nan if v is None else v for v in values], dtype=float)
    fail = np.asarray(failed, dtype=bool)
    err = np.asarray(errors, dtype=bool)
    ax.scatter(x[~fail & ~err], vals[~fail & ~err], s=12, color="#2c7fb8", label="passed")
    ax.scatter(x[fail], vals[fail], s=14, color="#d62728", label="failed")
    if err.any():
        ax.scatter(x[err], np.zeros(err.sum()) - 0.04, marker="x", s=28, color="#555", label="SUT/render error")
    if threshold is not None:
        ax.axhline(threshold, color="#555", ls="--", lw=1, label=f"oracle threshold {threshold:g}")
    ax.set(xlabel="test (evaluation order)", ylabel=metric, ylim=(-0.08, 1.05), title="Tests over time")
    twin = ax.twinx()
    twin.step(x, np.cumsum(fail), where="post", color="#7b3294", lw=1.5)
    twin.set_ylabel("cumulative failures", color="#7b3294")
    twin.set_ylim(0, max(1, int(fail.sum())) * 1.05)
    twin.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    return to_data_uri(fig)


def cluster_map(points: np.ndarray, clusters: np.ndarray, groups: Sequence[str], title: str) -> str:
    """Failing tests' embeddings on their first two principal components: colour = cluster,
    marker = algorithm."""
    fig, ax = plt.subplots(figsize=(6.2, 4.2))
    xy = _pca2(points)
    markers = "os^Dv<>P*X"
    for j, name in enumerate(sorted(set(groups))):
        mask = np.array([g == name for g in groups])
        ax.scatter(xy[mask, 0], xy[mask, 1], c=[colour(int(c)) for c in clusters[mask]], marker=markers[j % 10],
                   s=30, edgecolors="k", linewidths=0.3, label=name)
    ax.set(xlabel="PC 1", ylabel="PC 2", title=title)
    leg = ax.legend(fontsize=8, title="marker = algorithm", title_fontsize=8)
    for handle in leg.legend_handles:
        handle.set_facecolor("#bbb")
    ax.grid(alpha=0.3)
    return to_data_uri(fig)


def _pca2(points: np.ndarray) -> np.ndarray:
    centred = points - points.mean(axis=0)
    if len(points) < 2 or not np.any(centred):
        return np.zeros((len(points), 2))
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    xy = centred @ vt[:2].T
    return np.pad(xy, ((0, 0), (0, 2 - xy.shape[1])))


def cluster_counts(counts: dict[str, np.ndarray], title: str) -> str:
    """Failures per cluster, grouped bars per algorithm."""
    fig, ax = plt.subplots(figsize=(6.2, 3.4))
    names = list(counts)
    k = len(next(iter(counts.values()))) if counts else 0
    width = 0.8 / max(1, len(names))
    for i, name in enumerate(names):
        ax.bar(np.arange(k) + i * width, counts[name], width, color=colour(i), label=name)
    ax.set_xticks(np.arange(k) + 0.4 - width / 2, [str(c) for c in range(k)])
    ax.set(xlabel="cluster", ylabel="failures", title=title)
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(axis="y", alpha=0.3)
    if names:
        ax.legend(fontsize=8)
    return to_data_uri(fig)
