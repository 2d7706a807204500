"""Two-sample statistics between algorithms: the Wilcoxon rank-sum (Mann-Whitney U) test
and the Vargha-Delaney A12 effect size.

The p-value is exact whenever the pooled sample is small (the usual case: 5 to 30
repeated runs per algorithm): the permutation distribution of the rank sum is counted
by dynamic programming over mid-ranks, so ties are handled exactly too (SciPy's exact
method refuses ties and falls back to a normal approximation that is poor for tiny
samples).  Larger samples use the normal approximation with tie and continuity
correction, as SciPy does.

Too few runs: with n1 and n2 runs the exact test's smallest possible two-sided p-value
is 2 / C(n1 + n2, n1) (1.0 for one run per algorithm, 0.1 for three).  When even that
exceeds ``ALPHA``, no difference can be shown, so A12's magnitude reads "sample too
small" instead of a label ("large" for A12 = 0 from one run each) that would be noise.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.special import ndtr
from scipy.stats import rankdata

EXACT_LIMIT = 60  # pooled sample size up to which the p-value is computed exactly
ALPHA = 0.05      # the significance level the "sample too small" judgement refers to
TOO_SMALL = "sample too small"

# Vargha and Delaney (2000): thresholds on max(A, 1 - A)
A12_MAGNITUDES = ((0.56, "negligible"), (0.64, "small"), (0.71, "medium"))


@dataclass(frozen=True)
class RankSumResult:
    n1: int
    n2: int
    u: float              # Mann-Whitney U of the first sample (SciPy's statistic)
    p: float              # two-sided; NaN when undefined
    method: str           # exact | asymptotic | undefined
    note: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def rank_sum_test(x, y, exact_limit: int = EXACT_LIMIT) -> RankSumResult:
    """Two-sided Wilcoxon rank-sum test of ``x`` against ``y``."""
    x, y = _clean(x), _clean(y)
    n1, n2 = len(x), len(y)
    if n1 == 0 or n2 == 0:
        which = "first" if n1 == 0 else "second"
        return RankSumResult(n1, n2, math.nan, math.nan, "undefined",
                             f"the {which} group has no values; a test needs at least one in each")
    ranks = rankdata(np.concatenate([x, y]))
    u = float(ranks[:n1].sum() - n1 * (n1 + 1) / 2)
    if np.all(ranks == ranks[0]):
        return RankSumResult(n1, n2, u, 1.0, "exact", "all values tied")
    note = too_small_note(n1, n2)
    if n1 + n2 <= exact_limit:
        return RankSumResult(n1, n2, u, _exact_p(ranks, n1), "exact", note)
    return RankSumResult(n1, n2, u, _asymptotic_p(u, ranks, n1, n2), "asymptotic")


def smallest_p(n1: int, n2: int) -> float:
    """The smallest two-sided p-value the exact rank-sum test can give for these group sizes."""
    return min(1.0, 2.0 / math.comb(n1 + n2, n1)) if n1 and n2 else math.nan


def too_small_note(n1: int, n2: int) -> str:
    if not smallest_p(n1, n2) > ALPHA:
        return ""
    return (f"{TOO_SMALL}: with {n1} and {n2} runs no difference can reach p < {ALPHA:g} "
            f"(smallest possible p {smallest_p(n1, n2):.2g}); run more seeds")


def _clean(values) -> np.ndarray:
    arr = np.asarray(list(values), dtype=float).ravel()
    return arr[np.isfinite(arr)]


def _exact_p(ranks: np.ndarray, n1: int) -> float:
    """P-value from the exact permutation distribution of the first sample's rank sum.
    Doubled mid-ranks are integers, so subsets are counted by their doubled sum."""
    doubled = np.rint(2 * ranks).astype(np.int64)
    observed = int(doubled[:n1].sum())
    total = int(doubled.sum())
    counts = np.zeros((n1 + 1, total + 1))  # counts[k, s]: subsets of size k with doubled sum s
    counts[0, 0] = 1.0
    for value in doubled:
        counts[1:, value:] += counts[:-1, :total + 1 - value].copy()
    dist = counts[n1] / counts[n1].sum()
    p_low, p_high = dist[:observed + 1].sum(), dist[observed:].sum()
    return float(min(1.0, 2 * min(p_low, p_high)))


def _asymptotic_p(u: float, ranks: np.ndarray, n1: int, n2: int) -> float:
    n = n1 + n2
    _, tie_counts = np.unique(ranks, return_counts=True)
    tie_term = float((tie_counts ** 3 - tie_counts).sum()) / (n * (n - 1))
    sigma = math.sqrt(n1 * n2 / 12 * ((n + 1) - tie_term))
    u_big = max(u, n1 * n2 - u)
    z = (u_big - n1 * n2 / 2 - 0.5) / sigma
    return float(min(1.0, 2 * ndtr(-z)))


@dataclass(frozen=True)
class EffectSize:
    a12: float        # P(X > Y) + 0.5 P(X = Y); NaN when a group is empty
    magnitude: str    # negligible | small | medium | large | undefined | sample too small

    def to_dict(self) -> dict:
        return asdict(self)


def vargha_delaney(x, y) -> EffectSize:
    """A12: the probability that a value from ``x`` beats one from ``y`` (ties count half)."""
    x, y = _clean(x), _clean(y)
    if len(x) == 0 or len(y) == 0:
        return EffectSize(math.nan, "undefined")
    greater = (x[:, None] > y[None, :]).sum()
    equal = (x[:, None] == y[None, :]).sum()
    a12 = float((greater + 0.5 * equal) / (len(x) * len(y)))
    if smallest_p(len(x), len(y)) > ALPHA:
        return EffectSize(a12, TOO_SMALL)
    return EffectSize(a12, a12_magnitude(a12))


def a12_magnitude(a12: float) -> str:
    if not math.isfinite(a12):
        return "undefined"
    distance = round(max(a12, 1 - a12), 10)  # 0.56 must not read as 0.5600000000000001
    for limit, name in A12_MAGNITUDES:
        if distance < limit:
            return name
    return "large"
