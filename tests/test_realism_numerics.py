"""FID/KID numerics on synthetic features: singular covariances, identical sets, tiny sets."""
import numpy as np
import pytest
import scipy.linalg

from isu_validate.realism import fid, fid_bootstrap, fid_from_stats, kid, trace_sqrt_product
from isu_validate.realism.compare import MetricSettings, compare_features
from isu_validate.realism.fid import GramFID, stats


@pytest.fixture(scope="module", autouse=True)
def single_threaded_blas():
    # on a shared 2-core machine multi-threaded BLAS spins against other jobs: 50x slower here
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1):
        yield


# d = 256 keeps the d^3 eigen route fast; sets with n < d have singular covariances
def feats(n, d=256, seed=0, shift=0.0, scale=1.0):
    rng = np.random.default_rng(seed)
    # Inception pool features are non-negative with a spread of scales; mimic that
    return np.abs(rng.normal(size=(n, d))) * np.linspace(0.1, 1.0, d) * scale + shift


def reference_fid(a, b):
    """pytorch-fid's formula with scipy.sqrtm; only trustworthy when the covariances are full rank."""
    (ma, sa), (mb, sb) = stats(a), stats(b)
    covmean = np.real(scipy.linalg.sqrtm(sa @ sb))
    return float((ma - mb) @ (ma - mb) + np.trace(sa) + np.trace(sb) - 2 * np.trace(covmean))


def test_full_rank_matches_scipy_reference():
    a, b = feats(400, d=32, seed=1), feats(300, d=32, seed=2, shift=0.2, scale=1.3)
    expected = reference_fid(a, b)
    assert expected > 0.1
    assert fid(a, b) == pytest.approx(expected, rel=1e-9)
    assert fid_from_stats(*stats(a), *stats(b)) == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("n_a,n_b", [(2, 2), (53, 53), (2, 500), (30, 7), (200, 150)])
def test_singular_covariances_finite_and_both_routes_agree(n_a, n_b):
    a, b = feats(n_a, seed=3), feats(n_b, seed=4, shift=0.05)
    gram = GramFID.from_features(a, b).fid()
    eig = fid_from_stats(*stats(a), *stats(b))
    assert np.isfinite(gram) and gram > 0
    assert gram == pytest.approx(eig, rel=1e-10)  # the bench goal is 1e-6; both are exact routes


def test_scipy_sqrtm_is_complex_where_we_are_not():
    a, b = feats(20, d=256, seed=5), feats(20, d=256, seed=6)
    (_, sa), (_, sb) = stats(a), stats(b)
    raw = scipy.linalg.sqrtm(sa @ sb)
    # the naive route leaves an imaginary part (or NaN) that pytorch-fid must discard
    assert np.iscomplexobj(raw) or not np.isfinite(raw).all()
    assert np.isfinite(fid(a, b))


@pytest.mark.parametrize("n", [2, 3, 53])
def test_identical_sets_give_zero(n):
    a = feats(n, seed=7)
    assert fid(a, a) == pytest.approx(0.0, abs=1e-8)
    assert fid_from_stats(*stats(a), *stats(a)) == pytest.approx(0.0, abs=1e-6)


def test_near_identical_sets_give_near_zero_and_grow_with_distance():
    a = feats(53, seed=8)
    rng = np.random.default_rng(9)
    small = fid(a, a + rng.normal(scale=1e-6, size=a.shape))
    large = fid(a, a + rng.normal(scale=1e-2, size=a.shape))
    assert 0.0 <= small < 1e-6
    assert large > small


def test_translation_adds_squared_shift():
    a = feats(40, seed=10)
    shift = np.full(a.shape[1], 0.01)
    assert fid(a, a + shift) == pytest.approx(shift @ shift, rel=1e-9)


def test_constant_sets_reduce_to_mean_distance():
    # black or saturated frames give the same features for every image: zero covariance
    black, white = np.zeros((5, 2048)), np.full((3, 2048), 0.5)
    assert fid(black, white) == pytest.approx(2048 * 0.25, rel=1e-12)
    assert fid_from_stats(*stats(black[:, :512]), *stats(white[:, :512])) == pytest.approx(512 * 0.25, rel=1e-12)
    assert fid(black, black) == 0.0


def test_gaussian_closed_form_for_commuting_covariances():
    sa, sb = np.diag([1.0, 4.0, 9.0]), np.diag([4.0, 4.0, 1.0])
    mu_a, mu_b = np.zeros(3), np.array([1.0, 0.0, 2.0])
    expected = 5.0 + (1 - 2) ** 2 + 0 + (3 - 1) ** 2
    assert fid_from_stats(mu_a, sa, mu_b, sb) == pytest.approx(expected, rel=1e-12)
    assert trace_sqrt_product(sa, sb) == pytest.approx(2 + 4 + 3, rel=1e-12)


def test_never_negative_on_many_random_tiny_sets():
    for seed in range(30):
        a, b = feats(2 + seed % 4, d=64, seed=seed), feats(3, d=64, seed=seed + 100)
        assert fid(a, a.copy()) == pytest.approx(0.0, abs=1e-9)
        value = fid(a, b)  # singular covariances: the Gram route must agree with the eigenvalue route
        assert value > 0.0 and value == pytest.approx(fid_from_stats(*stats(a), *stats(b)), rel=1e-8)


def test_fid_rejects_one_image_and_nan():
    with pytest.raises(ValueError, match="at least 2 images"):
        fid(feats(1), feats(5))
    bad = feats(4)
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        fid(bad, feats(4))


def test_bootstrap_is_seeded_and_ordered():
    a, b = feats(20, seed=11), feats(25, seed=12, shift=0.1)
    first = fid_bootstrap(a, b, 50, seed=3)
    assert first == fid_bootstrap(a, b, 50, seed=3)
    assert first != fid_bootstrap(a, b, 50, seed=4)
    assert first[0] < first[1] and np.isfinite(first).all()
    # sets of identical rows: every resample is the same two points, FID = squared mean distance
    assert fid_bootstrap(np.zeros((4, 8)), np.full((3, 8), 0.5), 20, seed=3) == pytest.approx((2.0, 2.0))


def test_kid_subset_larger_than_set_is_a_clear_error():
    with pytest.raises(ValueError, match=r"subset size 60 exceeds the smaller set \(53 images\)"):
        kid(feats(53), feats(100), subset_size=60)
    with pytest.raises(ValueError, match="at least 2 images"):
        kid(feats(1), feats(100))


def test_kid_default_subset_is_capped_by_the_smaller_set():
    result = kid(feats(2, seed=1), feats(500, seed=2), seed=0)
    assert result.subset_size == 2 and np.isfinite([result.mean, result.std]).all()
    assert result.std > 0  # subsets of the larger set differ


def test_kid_is_seeded_and_separates_distributions():
    a, same, other = feats(80, seed=1), feats(80, seed=2), feats(80, seed=3, shift=0.3)
    r1, r2 = kid(a, other, subset_size=40, seed=5), kid(a, other, subset_size=40, seed=5)
    assert (r1.mean, r1.std) == (r2.mean, r2.std)
    assert kid(a, other, subset_size=40, seed=6).mean != r1.mean
    close = kid(a, same, subset_size=40, seed=5).mean
    assert abs(close) < 0.1 * r1.mean and r1.mean > 0


def test_kid_of_a_set_with_itself_is_small_and_not_positive():
    a = feats(30, seed=4)
    assert -0.05 < kid(a, a, subset_size=30).mean <= 0.0


def test_compare_reports_every_setting_and_small_n_warning():
    a, b = feats(10, seed=1), feats(12, seed=2, shift=0.1)
    result = compare_features(a, b, MetricSettings(bootstrap=20, kid_subsets=10, seed=7))
    out = result.to_json()
    assert {"fid", "fid_ci", "kid_mean", "kid_std", "n_a", "n_b"} <= out.keys()
    assert out["settings"]["kid_subset_size"] == 10 and out["settings"]["seed"] == 7
    assert any("below 2048" in w for w in out["warnings"])
    assert all(np.isfinite([out["fid"], out["kid_mean"], out["kid_std"], *out["fid_ci"]]))


def test_bench_tables_report_agreement_below_the_goal(capsys):
    from isu_validate.bench.fid import agreement_table, spread_table, synthetic_pools
    a, b = synthetic_pools(60, dim=64, rank=8)
    agreement_table(a, b, [2, 53])
    spread_table(a, b, [2, 10], repeats=3, seed=0)
    lines = capsys.readouterr().out.splitlines()
    rows = [line.split() for line in lines if line.split() and line.split()[0] in ("2", "53")][:2]
    assert len(rows) == 2 and all(float(r[3]) < 1e-6 for r in rows)  # rel diff column
    assert any("n against spread" in line for line in lines)
