"""The rank-sum test and A12 against SciPy, brute-force enumeration and hand-computed values."""
import itertools
import math

import numpy as np
import pytest
from scipy.stats import mannwhitneyu, rankdata

from isu_validate.analysis.stats import a12_magnitude, rank_sum_test, vargha_delaney


def brute_force_p(x, y):
    """Two-sided p from every relabelling of the pooled sample (the exact conditional test)."""
    pooled = np.concatenate([x, y]).astype(float)
    ranks = rankdata(pooled)
    observed = ranks[: len(x)].sum()
    sums = np.array([ranks[list(idx)].sum() for idx in itertools.combinations(range(len(pooled)), len(x))])
    low = np.mean(sums <= observed + 1e-9)
    high = np.mean(sums >= observed - 1e-9)
    return min(1.0, 2 * min(low, high))


@pytest.mark.parametrize("n1,n2", [(1, 1), (1, 4), (3, 4), (5, 5), (8, 7), (12, 10), (20, 25)])
def test_exact_p_matches_scipy_without_ties(n1, n2):
    rng = np.random.default_rng(n1 * 100 + n2)
    x, y = rng.normal(size=n1), rng.normal(0.7, 1, size=n2)
    ours = rank_sum_test(x, y)
    theirs = mannwhitneyu(x, y, method="exact")
    assert ours.method == "exact"
    assert ours.u == pytest.approx(theirs.statistic)
    assert ours.p == pytest.approx(theirs.pvalue, rel=1e-9)


@pytest.mark.parametrize("x,y", [([1, 1, 2, 2, 3], [2, 3, 3, 4, 4, 4]),
                                 ([0.0, 0.0, 0.0, 10.0], [0.0, 10.0, 10.0]),
                                 ([5, 5, 6], [5, 6, 6, 7, 7])])
def test_exact_p_with_ties_matches_enumeration(x, y):
    ours = rank_sum_test(x, y)
    assert ours.method == "exact"
    assert ours.u == pytest.approx(mannwhitneyu(x, y).statistic)
    assert ours.p == pytest.approx(brute_force_p(np.array(x), np.array(y)), rel=1e-12)


def test_large_samples_with_ties_match_scipy_asymptotic():
    rng = np.random.default_rng(7)
    x, y = rng.integers(0, 5, 40), rng.integers(1, 6, 45)
    ours = rank_sum_test(x, y)
    theirs = mannwhitneyu(x, y, method="asymptotic", use_continuity=True)
    assert ours.method == "asymptotic"
    assert ours.u == theirs.statistic
    assert ours.p == pytest.approx(theirs.pvalue, rel=1e-12)


def test_hand_computed_smallest_separation():
    # x entirely below y: U = 0; of the C(4,2) = 6 labellings only one is as extreme on each side
    result = rank_sum_test([1, 2], [3, 4])
    assert result.u == 0
    assert result.p == pytest.approx(2 / 6)


def test_all_ties_give_p_one():
    result = rank_sum_test([3, 3, 3], [3, 3])
    assert result.u == pytest.approx(3.0)  # n1 * n2 / 2
    assert result.p == 1.0
    assert "tied" in result.note


def test_single_value_per_group():
    result = rank_sum_test([0.2], [0.9])
    assert (result.u, result.p, result.method) == (0.0, 1.0, "exact")  # 2 labellings: cannot be significant


def test_identical_groups():
    values = [10.0, 20.0, 30.0, 40.0]
    result = rank_sum_test(values, list(values))
    assert result.u == pytest.approx(8.0)
    assert result.p == pytest.approx(1.0)


@pytest.mark.parametrize("x,y,which", [([], [1, 2], "first"), ([1, 2], [], "second"), ([], [], "first")])
def test_empty_group_is_undefined_with_a_reason(x, y, which):
    result = rank_sum_test(x, y)
    assert result.method == "undefined"
    assert math.isnan(result.p) and math.isnan(result.u)
    assert which in result.note


def test_nan_values_are_dropped():
    assert rank_sum_test([1, float("nan"), 2], [3, 4]).n1 == 2


def test_a12_hand_values():
    assert vargha_delaney([1, 2, 3], [1, 2, 3]).a12 == 0.5
    assert vargha_delaney([5], [1]).a12 == 1.0
    assert vargha_delaney([1], [5]).a12 == 0.0
    # [1, 2] vs [2, 3]: no win, one tie (2 = 2) of 4 pairs
    assert vargha_delaney([1, 2], [2, 3]).a12 == pytest.approx(0.125)
    assert vargha_delaney([7, 7], [7, 7, 7]).a12 == 0.5


def test_a12_equals_u_over_n1n2():
    rng = np.random.default_rng(3)
    x, y = rng.integers(0, 4, 9), rng.integers(0, 4, 11)
    assert vargha_delaney(x, y).a12 == pytest.approx(rank_sum_test(x, y).u / (9 * 11))


@pytest.mark.parametrize("a12,magnitude", [(0.5, "negligible"), (0.5599, "negligible"), (0.56, "small"),
                                           (0.44, "small"), (0.6399, "small"), (0.64, "medium"),
                                           (0.7099, "medium"), (0.71, "large"), (0.0, "large"), (1.0, "large")])
def test_a12_magnitudes_vargha_delaney(a12, magnitude):
    assert a12_magnitude(a12) == magnitude


def test_a12_with_an_empty_group_is_undefined():
    effect = vargha_delaney([], [1.0])
    assert math.isnan(effect.a12) and effect.magnitude == "undefined"


@pytest.mark.parametrize("n1,n2,too_small", [(1, 1, True), (1, 5, True), (2, 2, True), (3, 3, True), (3, 4, True),
                                             (4, 4, False), (2, 8, False), (10, 10, False)])
def test_a12_from_too_few_runs_says_the_sample_is_too_small(n1, n2, too_small):
    """One run per algorithm gives A12 = 0 or 1: 'large' would be noise, not an effect."""
    x, y = np.arange(n1) * 0.01, 1 + np.arange(n2) * 0.01   # every x below every y
    effect, test = vargha_delaney(x, y), rank_sum_test(x, y)
    assert effect.a12 == 0.0
    assert (effect.magnitude == "sample too small") == too_small
    assert ("sample too small" in test.note) == too_small
    if not too_small:
        assert effect.magnitude == "large" and test.p < 0.05
