"""``run --learn-from RUN...``: the surrogate learns from earlier runs of the same SUT before its
first generation; those tests are never run again, and a resumed run learns from the same ones."""
import json
import shutil


from isu_validate.bench.effectiveness.harness import InstantEvaluation, simulate
from isu_validate.sut.planted import BenchmarkSUT, BlindSpot
from isu_validate.search.surrogate_search import SurrogateSearch
from isu_validate.space import load_space
from isu_validate.space.conditions import parse_condition

from tests.test_run import _run_cli, records_of

SPACE = load_space()


def test_a_search_that_learnt_from_earlier_tests_starts_where_they_failed():
    spot = BlindSpot("belt over black", parse_condition({"seat_belt": "YES", "tshirt_colour": "BLACK"}, "t"),
                     {"seat_belt": "NO", "tshirt_colour": "WHITE"}, 1.0)
    sut = BenchmarkSUT("belt", "test", [spot], noise=0.0)
    earlier = simulate(SPACE, sut, "rs", 1, 300, 15).records
    evaluate = InstantEvaluation(SPACE, sut)

    def first_generation_failures(search):
        scenes = search.ask(15)
        return scenes, sum(evaluate(SPACE.canonical(s))[1].failed for s in scenes)

    learner = SurrogateSearch(SPACE, 15, seed=2)
    learner.learn(earlier)
    assert len(learner.model) == len(earlier)
    scenes, learnt = first_generation_failures(learner)
    assert not {SPACE.key(s) for s in scenes} & {r.scene_key for r in earlier}   # none run again
    _, fresh = first_generation_failures(SurrogateSearch(SPACE, 15, seed=2))
    assert learnt >= 10 and learnt > 2 * fresh


def test_a_run_learns_from_earlier_runs_and_resumes_only_from_the_same_tests(tmp_path, capsys):
    first, second = tmp_path / "first", tmp_path / "second"
    assert _run_cli(first, "--algorithm", "surrogate") == 0
    assert _run_cli(second, "--algorithm", "surrogate", "--learn-from", str(first), budget="6") == 0
    identity = json.loads((second / "run.json").read_text())["identity"]
    assert identity["learn_from"] == [str(first.resolve())] and identity["learned_from"].startswith("12 tests, ")
    earlier = {r.scene_key for r in records_of(first).values()}
    assert not earlier & {r.scene_key for r in records_of(second).values()}
    assert _run_cli(second, "--resume", budget="12") == 0   # the same earlier tests: it goes on
    assert len(records_of(second)) == 12
    capsys.readouterr()
    assert _run_cli(first, "--resume", budget="18") == 0    # the earlier run grew since
    assert _run_cli(second, "--resume", budget="18") == 2
    assert "the tests of the --learn-from runs: '12 tests, " in capsys.readouterr().err
    assert len(records_of(second)) == 12


def test_what_cannot_be_learnt_from_is_refused_before_anything_is_written(tmp_path, capsys):
    first = tmp_path / "first"
    assert _run_cli(first, "--algorithm", "surrogate") == 0
    other = tmp_path / "other-sut"
    shutil.copytree(first, other)
    stored = json.loads((other / "run.json").read_text())
    stored["config"]["pipeline"]["sut"] = "openai:gpt-4o@https://api.openai.com/v1"
    (other / "run.json").write_text(json.dumps(stored))
    capsys.readouterr()
    for flags, message in [
        (["--algorithm", "nsga2", "--learn-from", str(first)], "use --algorithm surrogate"),
        (["--algorithm", "surrogate", "--learn-from", str(tmp_path)], "not a run directory"),
        (["--algorithm", "surrogate", "--learn-from", str(other)], "learn only from runs of the same SUT"),
    ]:
        out = tmp_path / "new"
        assert _run_cli(out, *flags) == 2
        assert message in capsys.readouterr().err
        assert not out.exists()
    assert _run_cli(first, "--resume", "--learn-from", str(first), budget="18") == 2
    assert "this run's own folder" in capsys.readouterr().err


def test_the_bench_measures_a_surrogate_that_learnt_first(tmp_path, capsys):
    from isu_validate.cli import main
    assert main(["bench", "effectiveness", "--suts", "blind-spots", "--algorithms", "surrogate,rs", "--seeds", "2",
                 "--budget", "24", "--pop-size", "8", "--prior-tests", "60"]) == 0
    assert "learnt first from 60 earlier random tests per run" in capsys.readouterr().out
    out = tmp_path / "x"
    assert main(["bench", "effectiveness", "--prior-tests", "60", "--pipeline", "--out", str(out)]) == 2
    assert "run --learn-from" in capsys.readouterr().err and not out.exists()   # a refused option: no folder
