"""``bench effectiveness --emulate``: a SUT emulated from its stored runs (errors, joint errors, occlusion)."""
import json

import numpy as np
import pytest

from isu_validate.archive import Archive
from isu_validate.cli import main
from isu_validate.bench.effectiveness.emulate import EmulatedSUT
from isu_validate.bench.effectiveness.harness import InstantEvaluation, simulate
from isu_validate.sut.planted import BlindSpot, BenchmarkSUT
from isu_validate.space import load_space
from isu_validate.space.conditions import parse_condition

SPACE = load_space()
LUGGAGE_MISSED = {"luggage_position": "BACK", "external_light": "LOW"}


class PlantedSUT(BenchmarkSUT):
    """The stored SUT: misses back-seat luggage in low light (its position and presence wrong together),
    and its frames hide the seat belt whenever the cabin lights are on."""

    def occluded(self, space, canonical):
        return ["seat_belt"] if canonical.get("car_lights") == "ON" and "seat_belt" in canonical else []


def planted():
    spot = BlindSpot("luggage missed", parse_condition(LUGGAGE_MISSED, "t"),
                     {"luggage": "NO", "luggage_position": "NONE"}, 0.7)
    return PlantedSUT("planted", "test", [spot], noise=0.01)


def stored_runs(tmp_path, n_runs=3, budget=400):
    """Run directories as the pipeline leaves them (archive + run.json), from random search."""
    folders = []
    for seed in range(1, n_runs + 1):
        folder = tmp_path / f"rs-s{seed}"
        folder.mkdir()
        archive = Archive(folder / "archive.sqlite")
        for record in simulate(SPACE, planted(), "rs", seed, budget, 50).records:
            archive.add(record)
        archive.close()
        (folder / "run.json").write_text(json.dumps({"config": {"pipeline": {"sut": "planted-vlm"}}}))
        folders.append(folder)
    return folders


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return stored_runs(tmp_path_factory.mktemp("stored"))


def probe(n=2500, seed=7):
    return [SPACE.canonical(s) for s in SPACE.sample(np.random.default_rng(seed), n)]


def test_the_emulation_errs_where_the_stored_sut_erred_and_jointly(runs):
    emulated = EmulatedSUT.fit(SPACE, runs)
    inside, outside = [], []
    for scene in probe():
        if scene.get("luggage") != "YES":
            continue
        answers = emulated.answer(SPACE, scene)
        truth = {q.key: q.truth for q in SPACE.questions(scene)}
        wrong = (answers["luggage"] != truth["luggage"], answers["luggage_position"] != truth["luggage_position"])
        held = all(scene.get(k) == v for k, v in LUGGAGE_MISSED.items())
        (inside if held else outside).append(wrong)
        assert answers == emulated.answer(SPACE, dict(scene))  # deterministic, as at temperature 0
    inside, outside = np.array(inside), np.array(outside)
    assert 0.5 < inside[:, 0].mean() < 0.9 and outside[:, 0].mean() < 0.05
    # the two answers fail together (one missed suitcase), not as independent coins
    assert inside[inside[:, 0], 1].mean() > 0.8 and inside[~inside[:, 0], 1].mean() < 0.2
    assert "EMULATION of planted-vlm" in emulated.description and emulated.name == "emulated:planted-vlm"


def test_the_emulation_hides_what_the_stored_frames_hid_and_the_judge_leaves_it_out(runs):
    emulated = EmulatedSUT.fit(SPACE, runs)
    evaluate = InstantEvaluation(SPACE, emulated)
    hidden = {True: [], False: []}
    for scene in probe(600, seed=8):
        hidden[scene["car_lights"] == "ON"].append("seat_belt" in emulated.occluded(SPACE, scene))
        _, verdict = evaluate(scene)
        if "seat_belt" in emulated.occluded(SPACE, scene):
            assert verdict.details["features"]["seat_belt"]["status"] == "occluded"
    assert np.mean(hidden[True]) > 0.95 and np.mean(hidden[False]) < 0.05


def test_the_bench_runs_on_the_emulation_and_says_so(runs, capsys, tmp_path):
    out = tmp_path / "summary.json"
    assert main(["bench", "effectiveness", "--emulate", *map(str, runs), "--algorithms", "surrogate,rs",
                 "--seeds", "2", "--budget", "30", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "SUT emulated:planted-vlm: EMULATION of planted-vlm (not the real SUT)" in printed
    assert "goal at threshold" in printed
    assert json.loads(out.read_text())[0]["sut"] == "emulated:planted-vlm"


def test_emulating_what_cannot_be_emulated_says_why(tmp_path, capsys):
    assert main(["bench", "effectiveness", "--emulate", str(tmp_path)]) == 2
    assert "not a run directory" in capsys.readouterr().err
    folder = tmp_path / "perfect"
    folder.mkdir()
    archive = Archive(folder / "archive.sqlite")
    for record in simulate(SPACE, BenchmarkSUT("perfect", "t", [], noise=0.0), "rs", 1, 20, 10).records:
        archive.add(record)
    archive.close()
    with pytest.raises(ValueError, match="nothing to emulate"):
        EmulatedSUT.fit(SPACE, [folder])
    assert main(["bench", "effectiveness", "--emulate", str(folder), "--pipeline", "--out", str(tmp_path)]) == 2
    assert "leave out --pipeline" in capsys.readouterr().err
