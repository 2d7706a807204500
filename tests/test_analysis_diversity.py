"""Coverage and normalised entropy over k-means clusters, with the hard cases."""
import math

import numpy as np
import pytest

from isu_validate.analysis.diversity import (CLUSTERINGS, cluster_counts, cluster_failures, coverage, entropy_gaps,
                                             normalised_entropy)


def test_entropy_hand_value_with_an_empty_cluster():
    labels = [0, 0, 1, 2]                 # counts 2, 1, 1, 0 over k = 4
    expected = -(0.5 * math.log(0.5) + 2 * 0.25 * math.log(0.25)) / math.log(4)
    assert normalised_entropy(labels, 4) == pytest.approx(expected)
    assert expected == pytest.approx(0.75)
    assert coverage(labels, 4) == 0.75


def test_even_spread_is_one_and_concentration_is_zero():
    assert normalised_entropy([0, 1, 2, 3] * 3, 4) == pytest.approx(1.0)
    assert normalised_entropy([2, 2, 2], 4) == 0.0
    assert coverage([2, 2, 2], 4) == 0.25


def test_single_cluster():
    assert normalised_entropy([0, 0, 0], 1) == 0.0
    assert coverage([0, 0, 0], 1) == 1.0


def test_no_failures():
    assert math.isnan(normalised_entropy([], 5))
    assert coverage([], 5) == 0.0
    assert list(cluster_counts([], 3)) == [0, 0, 0]


def test_k_larger_than_the_failures_is_lowered_and_said():
    points = np.random.default_rng(0).normal(size=(3, 8))
    result = cluster_failures(points, k=10)
    assert result.k == 3 and result.k_requested == 10
    assert sorted(result.labels) == [0, 1, 2]
    assert "lowered" in result.note


def test_duplicate_embeddings_count_once():
    points = np.array([[1.0, 0.0]] * 4 + [[0.0, 1.0]] * 2)
    result = cluster_failures(points, k=5)
    assert result.k == 2
    assert len(set(result.labels[:4])) == 1 and result.labels[0] != result.labels[4]


def test_clusters_follow_the_groups():
    rng = np.random.default_rng(1)
    centres = np.eye(3) * 10
    points = np.vstack([c + rng.normal(0, 0.1, size=(6, 3)) for c in centres])
    labels = cluster_failures(points, k=3, seed=0).labels
    for block in range(3):
        assert len(set(labels[block * 6:(block + 1) * 6])) == 1
    assert len(set(labels)) == 3


def test_zero_failures_and_bad_k():
    assert cluster_failures(np.zeros((0, 4)), k=3).k == 0
    with pytest.raises(ValueError, match="at least 1"):
        cluster_failures(np.ones((2, 2)), k=0)


def test_entropy_gaps_over_several_clusterings():
    rng = np.random.default_rng(0)
    spread = rng.normal(size=(40, 4))
    runs = [("b", r) for r in range(4) for _ in range(10)]
    # the same failures for both algorithms: exactly no difference in any clustering
    same = entropy_gaps(np.vstack([spread, spread]), [("a", r) for _, r in runs] + runs, k=5)
    assert same == {("a", "b"): [0.0] * CLUSTERINGS}
    # a's failures all one point, b's spread: lower in every clustering
    narrow = np.vstack([np.repeat(spread[:1], 20, axis=0), spread])
    gaps = entropy_gaps(narrow, [("a", r) for r in range(2) for _ in range(10)] + runs, k=5)[("a", "b")]
    assert len(gaps) == CLUSTERINGS and max(gaps) < 0
    assert entropy_gaps(np.zeros((0, 4)), [], k=5) == {}                        # no failures
    assert entropy_gaps(spread, runs, k=5) == {}                                # one algorithm: no pair
