"""The known-risk bound of ``bench effectiveness --bound``: a failure probability estimated from other
noise draws of the SUT, and a picker that knows it but never the outcome."""
import numpy as np
import pytest

from isu_validate.analysis.diversity import cluster_failures
from isu_validate.cli import main
from isu_validate.bench.effectiveness import bound as bound_module
from isu_validate.bench.effectiveness.bound import KnownRiskSearch, RiskBank, risk_bank
from isu_validate.bench.effectiveness.harness import simulate
from isu_validate.bench.effectiveness.summary import summarize
from isu_validate.sut.planted import BenchmarkSUT, BlindSpot
from isu_validate.space import load_space
from isu_validate.space.conditions import parse_condition

SPACE = load_space()


def belt_sut(p):
    spot = BlindSpot("belt over black", parse_condition({"seat_belt": "YES", "tshirt_colour": "BLACK"}, "t"),
                     {"seat_belt": "NO"}, p)
    return BenchmarkSUT("belt", "test", [spot], noise=0.0)


def inside(scene):
    canonical = SPACE.canonical(scene)
    return canonical.get("seat_belt") == "YES" and canonical.get("tshirt_colour") == "BLACK"


def test_a_sure_blind_spot_has_risk_one_exactly_where_it_holds():
    bank = risk_bank(SPACE, belt_sut(1.0), size=300, seeds=3)
    where = np.array([inside(s) for s in bank.scenes])
    assert 0 < where.sum() < len(where)
    assert np.array_equal(bank.risk(1.0), where.astype(float))
    assert not bank.risk(0.5).any()   # one light answer wrong never reaches f_qa < 0.5


def test_the_risk_is_a_probability_over_other_noise_draws_not_one_outcome():
    bank = risk_bank(SPACE, belt_sut(0.5), size=400, seeds=8)
    risk, where = bank.risk(1.0), np.array([inside(s) for s in bank.scenes])
    assert not risk[~where].any()
    assert 0.35 < risk[where].mean() < 0.65 and len(np.unique(risk[where])) > 2  # the draws differ per seed


def test_the_picker_follows_the_risk_never_repeats_and_runs_dry_cleanly():
    scenes = SPACE.sample(np.random.default_rng(0), 40)
    risk = np.zeros(40)
    risk[:10] = 1.0
    bank = RiskBank(scenes, np.zeros((1, 40)))
    search = KnownRiskSearch(SPACE, 10, seed=1, bank=bank, risk=risk, alpha=2)
    first = search.ask(10)
    assert {id(s) for s in first} == {id(s) for s in scenes[:10]}
    rest = search.ask(100) + search.ask(100) + search.ask(100)   # no risk left: at random among the unused
    assert len(rest) == 30 and search.ask(5) == []
    assert len({SPACE.key(s) for s in first + rest}) == 40


def test_the_bound_refuses_a_sut_whose_noise_it_cannot_redraw_and_a_negative_alpha():
    class Opaque:
        name = "http-sut"
    with pytest.raises(ValueError, match="benchmark or emulated SUT"):
        risk_bank(SPACE, Opaque())
    with pytest.raises(ValueError, match="alpha"):
        KnownRiskSearch(SPACE, 4, 0, RiskBank([], np.zeros((1, 0))), np.zeros(0), alpha=-1)


def test_the_bound_beats_random_picks_on_a_planted_blind_spot():
    sut = belt_sut(1.0)
    bank = risk_bank(SPACE, sut, size=600, seeds=2)
    bound = simulate(SPACE, sut, "bound", 1, 30, 10,
                     make=lambda sp, pop, sd: KnownRiskSearch(sp, pop, sd, bank, bank.risk(1.0), 4))
    rs = simulate(SPACE, sut, "rs", 1, 30, 10)
    assert sum(r.failed for r in bound.records) > 2 * sum(r.failed for r in rs.records)


def test_the_bench_adds_the_bound_as_a_reference_row(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(bound_module, "risk_bank", lambda space, sut: risk_bank(space, sut, size=300, seeds=2))
    assert main(["bench", "effectiveness", "--suts", "blind-spots", "--algorithms", "surrogate,rs", "--seeds", "2",
                 "--budget", "24", "--pop-size", "8", "--bound", "2"]) == 0
    text = capsys.readouterr().out
    for needle in ("bound/rs", "a reference, not a search", "bound - rs entropy"):
        assert needle in text, needle
    assert main(["bench", "effectiveness", "--bound", "2", "--pipeline", "--out", str(tmp_path / "x")]) == 2
    assert "--bound runs in memory" in capsys.readouterr().err
    for alpha in ("-1", "nan"):
        assert main(["bench", "effectiveness", "--bound", alpha]) == 2
        assert "exponent" in capsys.readouterr().err


def test_the_bound_is_measured_on_the_searches_clusters_without_moving_them():
    sut = BenchmarkSUT("noisy-belt", "test", belt_sut(1.0).blind_spots, noise=0.05)
    runs = [simulate(SPACE, sut, algo, seed, 30, 10) for algo in ("surrogate", "rs") for seed in (1, 2)]
    bank = risk_bank(SPACE, sut, size=300, seeds=2)
    bound = [simulate(SPACE, sut, "bound", seed, 30, 10,
                      make=lambda sp, pop, sd: KnownRiskSearch(sp, pop, sd, bank, bank.risk(1.0), 2))
             for seed in (1, 2)]
    alone = summarize(SPACE, sut.name, "", runs, "rs", 4)
    both = summarize(SPACE, sut.name, "", runs + bound, "rs", 4, references=("bound",))
    for algo in ("surrogate", "rs"):
        assert both.diversity[algo] == alone.diversity[algo]
    assert both.entropy_gaps["surrogate"] == alone.entropy_gaps["surrogate"]
    assert np.isfinite(both.diversity["bound"]["entropy mean"]) and len(both.entropy_gaps["bound"]) == 5
    # Not asserted: that pooling the bound into the fit moves these clusters. Here it does not (the same
    # partition); the old `!=` on the entropy gaps held only through summation-order noise at 1e-16, which
    # another BLAS or an exactly rounded entropy removes. That failures outside the fit take the nearest
    # centre of the others' fit is the next test.


def test_failures_outside_the_fit_take_their_nearest_centre():
    rng = np.random.default_rng(0)
    centres = np.eye(3) * 5
    points = np.concatenate([c + rng.normal(0, 0.1, (20, 3)) for c in centres])
    fit = np.ones(len(points), dtype=bool)
    fit[::7] = False
    clustering = cluster_failures(points, 3, 0, fit)
    assert np.array_equal(clustering.labels[fit], cluster_failures(points[fit], 3, 0).labels)
    for i in np.flatnonzero(~fit):   # the same label as the fitted points of its own centre
        same = clustering.labels[fit][np.argmin(np.linalg.norm(points[fit] - points[i], axis=1))]
        assert clustering.labels[i] == same
    assert cluster_failures(points, 3, 0, np.zeros(len(points), dtype=bool)).k == 0
