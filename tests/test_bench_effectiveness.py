"""``bench effectiveness``: benchmark SUTs with planted blind spots, the summary statistics,
the printed table, and the resumable real-pipeline mode."""
import json
import math

import numpy as np
import pytest

from isu_validate.archive import TestRecord as Record  # (a Test* name would be collected by pytest)
from isu_validate.cli import main
from isu_validate.protocols import SUTRequest
from isu_validate.bench.effectiveness.harness import Outcome
from isu_validate.analysis.diversity import CLUSTERINGS
from isu_validate.bench.effectiveness.summary import summarize
from isu_validate.bench.effectiveness.table import format_summary
from isu_validate.sut.planted import (BlindSpot, BenchmarkSUT, make_benchmark_sut,
                                                    random_blind_spots)
from isu_validate.space import load_space, space_from_dict
from isu_validate.space.conditions import parse_condition
from isu_validate.sut import open_sut

SPACE = load_space()


def scenes(n, seed=0):
    return [SPACE.canonical(s) for s in SPACE.sample(np.random.default_rng(seed), n)]


# ------------------------------------------------------------------ benchmark SUTs
def test_a_blind_spot_errs_exactly_where_it_holds_and_answers_are_stable():
    spot = BlindSpot("belt over black", parse_condition({"seat_belt": "YES", "tshirt_colour": "BLACK"}, "t"),
                     {"seat_belt": "NO"}, 1.0)
    sut = BenchmarkSUT("belt", "test", [spot], noise=0.0)
    for scene in scenes(200):
        answers = sut.answer(SPACE, scene)
        truth = {q.key: q.truth for q in SPACE.questions(scene)}
        wrong = {k for k in truth if answers[k] != truth[k]}
        inside = scene["seat_belt"] == "YES" and scene["tshirt_colour"] == "BLACK"
        assert wrong == ({"seat_belt"} if inside else set())
        assert answers == sut.answer(SPACE, dict(scene))  # same scene, same answer


def test_noise_errs_at_its_rate_on_every_feature_and_never_with_the_true_answer():
    sut = BenchmarkSUT("noise", "test", [], noise=0.1)
    wrong = total = 0
    for scene in scenes(600, seed=1):
        answers = sut.answer(SPACE, scene)
        for q in SPACE.questions(scene):
            assert answers[q.key] in q.options
            wrong += answers[q.key] != q.truth
            total += 1
    assert 0.085 < wrong / total < 0.115


def test_the_paper_blind_spots_skip_features_a_space_lacks():
    space = space_from_dict({"features": {
        "seat_belt": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "question": "belt?",
                      "options": ["YES", "NO", "NONE"]},
        "tshirt_colour": {"type": "categorical", "values": ["BLACK", "WHITE"]}}})
    sut = make_benchmark_sut("blind-spots", space)
    assert [s.name for s in sut.blind_spots] == ["seat belt missed over a black T-shirt"]
    assert len(sut.skipped) == 5
    assert len(make_benchmark_sut("blind-spots", SPACE).blind_spots) == 6


def test_random_blind_spots_are_drawn_over_any_space_and_hit_a_share_of_it():
    space = space_from_dict({"features": {
        **{n: {"type": "categorical", "values": ["P", "Q", "R"], "predicted": True, "question": f"{n}?"}
           for n in ("u", "v", "w")},
        "level": {"type": "continuous", "low": -1.0, "high": 1.0}}})
    sut = random_blind_spots(space, seed=4)
    assert len(sut.blind_spots) == 6
    sample = [space.canonical(s) for s in space.sample(np.random.default_rng(9), 2000)]
    for spot in sut.blind_spots:
        assert 0.01 < np.mean([spot.when.matches(s) for s in sample]) < 0.45
    assert random_blind_spots(space, seed=4).blind_spots == sut.blind_spots
    with pytest.raises(ValueError, match="random-spots-SEED"):
        make_benchmark_sut("random-spots-x", space)
    with pytest.raises(ValueError, match="unknown benchmark SUT"):
        make_benchmark_sut("gpt-5", space)


def test_the_bench_sut_answers_from_the_label_inside_a_run_and_refuses_outside(tmp_path):
    scene = scenes(1, seed=3)[0]
    (tmp_path / "images").mkdir()
    (tmp_path / "labels").mkdir()
    (tmp_path / "labels" / "g0000-i000.json").write_text(json.dumps({"scene": scene}))
    sut = open_sut("bench:blind-spots", space=SPACE)
    inside = sut.query(SUTRequest("vqa", tmp_path / "images" / "g0000-i000.png", "", SPACE.questions(scene)))
    assert inside.error is None
    assert inside.answers == make_benchmark_sut("blind-spots", SPACE).answer(SPACE, scene)
    outside = sut.query(SUTRequest("vqa", tmp_path / "elsewhere.png", "", SPACE.questions(scene)))
    assert outside.error and "label" in outside.error and "inside runs" in outside.error


# ------------------------------------------------------------------ summary statistics
def outcome(algorithm, seed, values, failed_at=1.0):
    records = []
    for i, v in enumerate(values):
        scene = scenes(1, seed=1000 * seed + i)[0]
        records.append(Record(f"t{i}", 0, i, algorithm, seed, SPACE.key(scene), scene, scene, primary=v,
                              failed=v is not None and v < failed_at, sut_error="down" if v is None else None))
    return Outcome(algorithm, seed, "made-up", records, search_s=0.01 * len(values))


def test_rates_ratio_and_effect_size_follow_the_definitions():
    # rs: 1 failure at 0.8 in 12 tests per run; better: 4 in 9 (its SUT error is left out of the rates)
    rs = [outcome("rs", s, [0.75] + [0.85] * 4 + [1.0] * 7) for s in range(4)]
    better = [outcome("better", s, [0.75] * 4 + [0.95] * 5 + [None]) for s in range(4)]
    summary = summarize(SPACE, "made-up", "hand-made runs", better + rs)
    j = summary.thresholds.index(0.8)
    assert summary.rates["rs"][0][j] == pytest.approx(100 / 12)
    assert summary.rates["better"][0][j] == pytest.approx(100 * 4 / 9)
    row = next(c for c in summary.comparisons if c["threshold"] == 0.8)
    assert row["ratio"] == pytest.approx((400 / 9) / (100 / 12)) and row["A12"] == 1.0 and row["p"] < 0.05
    same = next(c for c in summary.comparisons if c["threshold"] == 0.5)  # nobody fails: undefined ratio
    assert math.isnan(same["ratio"]) and same["A12"] == 0.5 and same["p"] == 1.0
    assert summary.goal["threshold"] == 0.8 and summary.goal["baseline_rate"] == pytest.approx(100 / 12)
    assert summary.search_ms["rs"] == pytest.approx(10.0)
    assert set(summary.diversity) == {"better", "rs"} and summary.clusters >= 1


def test_the_entropy_gap_is_checked_over_several_clusterings():
    # identical failures: no clustering can tell the algorithms apart (a tie, exactly)
    twins = [outcome(a, s, [0.5] * 12) for a in ("twin", "rs") for s in range(3)]
    summary = summarize(SPACE, "made-up", "same failures", twins)
    assert summary.entropy_gaps["twin"] == [0.0] * CLUSTERINGS
    # every failure of "narrow" is one scene: lower entropy than rs's spread failures in every clustering
    narrow = outcome("narrow", 0, [0.5] * 12)
    one = narrow.records[0]
    narrow.records = [Record(f"n{i}", 0, i, "narrow", 0, one.scene_key, one.scene, one.canonical,
                             primary=0.5, failed=True)
                      for i in range(12)]
    rs = [outcome("rs", s, [0.5] * 12) for s in range(1, 3)]
    summary = summarize(SPACE, "made-up", "narrow failures", [narrow] + rs)
    gaps = summary.entropy_gaps["narrow"]
    assert len(gaps) == CLUSTERINGS and max(gaps) < 0
    assert "entropy over 5 clusterings" in format_summary(summary) and "not a finding" not in format_summary(summary)


def test_no_failures_anywhere_leaves_rq2_empty_and_the_goal_explains_itself():
    runs = [outcome(a, s, [1.0] * 5) for a in ("surrogate", "rs") for s in range(2)]
    summary = summarize(SPACE, "perfect", "a SUT that never errs", runs)
    assert summary.diversity == {} and summary.goal["threshold"] == 1.0
    assert summary.goal["algorithms"]["surrogate"]["met"] is False


# ------------------------------------------------------------------ the command
def test_the_bench_prints_every_threshold_the_goal_and_writes_json(tmp_path, capsys):
    out = tmp_path / "eff.json"
    assert main(["bench", "effectiveness", "--suts", "blind-spots", "--seeds", "2", "--budget", "24",
                 "--pop-size", "8", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    for needle in ("SUT blind-spots", "surrogate/rs", "nsga2/rs", "RQ2", "entropy", "time per test",
                   "goal at threshold"):
        assert needle in text, needle
    data = json.loads(out.read_text())
    assert data[0]["runs"] == {"surrogate": 2, "nsga2": 2, "rs": 2} and data[0]["tests"]["rs"] == 24


def test_the_bench_rejects_unknown_algorithms_and_pipeline_without_out(capsys):
    with pytest.raises(SystemExit) as stop:   # argparse refuses it with the one parser's message
        main(["bench", "effectiveness", "--algorithms", "surrogate,sa"])
    assert stop.value.code == 2 and "unknown algorithm 'sa'" in capsys.readouterr().err
    assert main(["bench", "effectiveness", "--pipeline"]) == 2
    assert "--out" in capsys.readouterr().err


@pytest.mark.blender
@pytest.mark.slow
def test_the_pipeline_mode_writes_runs_that_resume_and_report(tmp_path, capsys):
    """Real renders, the planted-blind-spot SUT answering from the labels, two algorithms."""
    args = ["bench", "effectiveness", "--pipeline", "--sut", "bench:blind-spots", "--algorithms", "surrogate,rs",
            "--seeds", "1", "--pop-size", "2", "--out", str(tmp_path / "eff")]
    assert main(args + ["--budget", "2"]) == 0
    assert main(args + ["--budget", "4"]) == 0   # the same runs, extended: only the new tests are evaluated
    captured = capsys.readouterr()
    assert "surrogate seed 1: 4 tests (2 evaluated now)" in captured.err
    assert "SUT bench:blind-spots" in captured.out and "goal at threshold" in captured.out
    for algo in ("surrogate", "rs"):
        run = tmp_path / "eff" / f"{algo}-s1"
        assert json.loads((run / "run.json").read_text())["config"]["algorithm"] == algo
        assert len(list((run / "images").glob("*.png"))) == 4
    assert main(args + ["--budget", "4", "--preset", "standard"]) == 2  # other settings: refused, not remeasured
    assert "different configuration" in capsys.readouterr().err


def test_bench_search_splits_the_search_from_the_durable_commit(capsys):
    assert main(["bench", "search", "--sizes", "60,120", "--pop-size", "20", "--algorithm", "surrogate,rs"]) == 0
    out = capsys.readouterr().out
    assert out.count("search overhead") == 2 and "(surrogate, pop 20" in out and "(rs, pop 20" in out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("60 ", "120 "))]
    assert len(rows) == 4
    for _size, total, search, commit, cpu, *_ in rows:
        assert float(search) + float(commit) <= float(total) + 1e-6 and float(cpu) > 0


def test_diagnosis_compares_nsga2_with_its_causes_removed_and_traces_generations(capsys):
    assert main(["bench", "effectiveness", "--diagnose", "--suts", "blind-spots", "--seeds", "1", "--budget", "30",
                 "--pop-size", "10", "--pop-sizes", "15"]) == 0
    out = capsys.readouterr().out
    for needle in ("nsga2, diversity objective at 0", "nsga2, mutation 1/n per feature", "nsga2 (pop 15)",
                   "features changed vs nearest parent", "random top-ups", "surviving population passing"):
        assert needle in out, needle
