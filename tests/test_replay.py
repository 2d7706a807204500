"""``isu-validate replay``: a new SUT on a run's stored images, judged as the run judged, compared test by test.

Runs are made with the pipeline doubles (``tests.doubles:build``: a painted frame per scene, a SUT wrong about
seat belts in low light and the luggage's position); the new SUT is a registered adapter double that answers
from the scene beside the image, so every expected count is computed here from the run's own records.
"""
from __future__ import annotations

import csv
import json
import math
import shutil
import sys
from pathlib import Path

import pytest

import isu_validate as iv
from isu_validate.archive import open_run
from isu_validate.cli import main
from isu_validate.replay.compare import mcnemar
from isu_validate.sut.exchange import Exchange
from isu_validate.sut.registry import ADAPTERS

FACTORY = "tests.doubles:build"
SCRIPT = "<script>alert('replay')</script>"
CALLS: list[str] = []        # the tests the double was asked about, in order (cache hits never get here)


class DoubleSUT:
    """``replay-double:MODE``: answers from the scene in ``labels/`` beside the image. MODE ``truth``: always
    right; ``mixed``: right but for the driver's emotion of a female driver (and a note with a script tag);
    ``error``: every call fails; ``flaky``: fails where the car lights are on, else right; ``stop-after-N``:
    right, but the (N+1)th call is interrupted (Ctrl-C)."""

    def __init__(self, target, *, timeout_s=60.0, **options):
        self.mode = target
        self.id = "replay-double"
        self.fingerprint = f"replay-double:{'truth' if target.startswith('stop-after-') else target}"

    def send(self, request) -> Exchange:
        if self.mode.startswith("stop-after-") and len(CALLS) == int(self.mode.rsplit("-", 1)[1]):
            raise KeyboardInterrupt
        CALLS.append(Path(request.image).stem)
        scene = json.loads((Path(request.image).parent.parent / "labels" / f"{Path(request.image).stem}.json")
                           .read_text())["scene"]
        if self.mode == "error" or (self.mode == "flaky" and scene.get("car_lights") == "ON"):
            return Exchange(error="HTTP 503 from the SUT (test double)")
        answers = {q.key: q.truth for q in request.questions}
        content = {"answers": answers}
        if self.mode == "mixed":
            if scene.get("driver_gender") == "FEMALE" and "driver_emotion" in answers:
                answers["driver_emotion"] = "SERIOUS" if answers["driver_emotion"] == "HAPPY" else "HAPPY"
            content["note"] = SCRIPT
        return Exchange(raw=json.dumps(content), content=content)


@pytest.fixture(autouse=True)
def double_sut(monkeypatch):
    monkeypatch.setitem(ADAPTERS, "replay-double", DoubleSUT)
    CALLS.clear()


def _make_run(run_dir: Path, *extra, budget="20") -> Path:
    assert main(["run", "--out", str(run_dir), "--pipeline-factory", FACTORY, "--algorithm", "rs", "--budget",
                 budget, "--pop-size", "10", "--seed", "5", "--no-report", *extra]) == 0
    return run_dir


@pytest.fixture(scope="module")
def stored_run(tmp_path_factory) -> Path:
    """One doubles run (20 tests, 9 failing at 1.0), copied by the tests that change it."""
    return _make_run(tmp_path_factory.mktemp("stored") / "run")


@pytest.fixture
def run_copy(stored_run, tmp_path) -> Path:
    return Path(shutil.copytree(stored_run, tmp_path / "run"))


def _replay(run_dir: Path, out: Path, sut: str, *extra) -> int:
    return main(["replay", str(run_dir), "--sut", sut, "--out", str(out), *extra])


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def _csv(out: Path) -> list[dict]:
    with (out / "replay.csv").open(newline="") as f:
        return list(csv.DictReader(f))


def _expected_mixed(run_dir: Path, threshold: float) -> dict:
    """fixed/new/persisting/still_passing when the new SUT is wrong exactly about female drivers' emotion."""
    space = iv.load_space()
    counts = dict.fromkeys(("fixed", "new", "persisting", "still_passing"), 0)
    for r in open_run(run_dir).records():
        asked = {q.key: q.weight for q in space.questions(r.canonical) if q.key not in r.occluded}
        wrong = asked.get("driver_emotion", 0) if r.canonical["driver_gender"] == "FEMALE" else 0
        after = 1 - wrong / sum(asked.values())
        was, now = r.primary < threshold, after < threshold
        counts[{(True, False): "fixed", (False, True): "new", (True, True): "persisting"}.get(
            (was, now), "still_passing")] += 1
    return counts


def _mcnemar_by_hand(b: int, c: int) -> float:
    n = b + c
    return 1.0 if n == 0 else min(1.0, 2 * sum(math.comb(n, i) for i in range(min(b, c) + 1)) / 2 ** n)


def test_a_replay_counts_fixed_and_new_failures_as_the_run_judged(stored_run, tmp_path, capsys):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:mixed") == 0
    s = _summary(out)
    records = open_run(stored_run).records()
    expected = _expected_mixed(stored_run, 1.0)
    assert {k: s[k] for k in expected} == expected
    assert expected["fixed"] and expected["new"] and expected["persisting"] and expected["still_passing"]
    for key in ("fixed", "new", "persisting", "still_passing", "n_tests", "n_replayed", "failures_before",
                "failures_after", "sut_errors", "not_replayed"):
        assert type(s[key]) is int, key
    assert s["threshold"] == 1.0 and s["n_tests"] == s["n_replayed"] == len(records) == 20
    assert s["fixed"] + s["persisting"] == s["failures_before"] == sum(r.failed for r in records)
    assert s["new"] + s["persisting"] == s["failures_after"]
    assert s["fixed"] + s["new"] + s["persisting"] + s["still_passing"] == s["n_replayed"]
    m = s["mcnemar"]
    assert (m["fixed"], m["new"], m["discordant"]) == (s["fixed"], s["new"], s["fixed"] + s["new"])
    assert m["p"] == pytest.approx(_mcnemar_by_hand(s["fixed"], s["new"]), rel=1e-12)
    at_1 = next(r for r in s["rates"] if r["threshold"] == 1.0)
    assert (at_1["failures_before"], at_1["failures_after"]) == (s["failures_before"], s["failures_after"])
    assert at_1["rate_before"] == pytest.approx(s["failures_before"] / 20)
    assert [r["threshold"] for r in s["rates"]] == [1.0, 0.9, 0.8, 0.7, 0.6, 0.5]
    emotion = s["per_feature"]["driver_emotion"]
    assert emotion["became_wrong"] == sum(r.canonical["driver_gender"] == "FEMALE" for r in records)
    assert emotion["became_right"] == 0 and s["per_feature"]["driver_gender"]["became_wrong"] == 0
    assert s["per_feature"]["seat_belt"]["became_right"] == sum(
        r.canonical["external_light"] == "LOW" and "seat_belt" in r.answers for r in records)
    assert f"fixed {s['fixed']}, new {s['new']}" in capsys.readouterr().out

    rows = _csv(out)
    assert [r["test_id"] for r in rows] == sorted(r.test_id for r in records)
    assert list(rows[0]) == ["test_id", "status", "f_qa_before", "f_qa_after", "became_right", "became_wrong",
                             "image", "note"]
    by_id = {r.test_id: r for r in records}
    for row in rows:
        assert float(row["f_qa_before"]) == pytest.approx(by_id[row["test_id"]].primary)
        assert ("driver_emotion" in row["became_wrong"]) == (row["status"] in ("new", "persisting")
                                                             and float(row["f_qa_after"]) < 1.0)
    assert {k: sum(r["status"] == k for r in rows) for k in expected} == expected

    html = (out / "report.html").read_text()
    assert SCRIPT not in html and "&lt;script&gt;alert(&#x27;replay&#x27;)&lt;/script&gt;" in html
    assert f"New failures ({s['new']})" in html and f"Fixed failures ({s['fixed']})" in html


def test_a_replay_names_the_model_it_asked_on_the_terminal_in_the_title_and_the_summary(stored_run, tmp_path,
                                                                                         capsys, monkeypatch):
    """v1 against v2: which model gave the "now" answers is named wherever the result is shown, and the
    failures that persist are shown too (a replay that fixed nothing and broke nothing still has pictures)."""
    monkeypatch.setattr(DoubleSUT, "model_version", "model v2 of the double", raising=False)
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:truth") == 0
    s = _summary(out)
    version = s["settings"]["sut_version"]
    assert (version["spec"], version["model"]) == ("replay-double:truth", "model v2 of the double")
    label = version["label"]
    assert label == f"replay-double:truth (model v2 of the double; fingerprint {version['fingerprint']})"
    assert f"against {label}" in capsys.readouterr().out.splitlines()[0]
    html = (out / "report.html").read_text()
    assert f"<title>Regression replay: {label}</title>" in html
    s_mixed = tmp_path / "mixed"
    assert _replay(stored_run, s_mixed, "replay-double:mixed") == 0
    persisting = _summary(s_mixed)["persisting"]
    assert persisting and f"Persisting failures ({persisting})" in (s_mixed / "report.html").read_text()


def test_the_reference_isu_is_named_by_its_folder_and_heads_hash():
    import hashlib

    from isu_validate.reference.adapter import ReferenceAdapter
    from isu_validate.reference.model import default_model_dir
    from isu_validate.sut.version import sut_version

    folder = default_model_dir()
    heads = hashlib.sha1((folder / "heads.npz").read_bytes()).hexdigest()[:12]
    label = sut_version("reference", ReferenceAdapter(space=iv.load_space("isu-paper")))["label"]
    assert label.startswith(f"reference (model {folder.resolve()}, heads {heads}; fingerprint ")


def test_the_counts_follow_the_threshold_given(stored_run, tmp_path):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:mixed", "--threshold", "0.9") == 0
    s = _summary(out)
    assert s["threshold"] == 0.9 and {k: s[k] for k in ("fixed", "new", "persisting", "still_passing")} \
        == _expected_mixed(stored_run, 0.9)
    assert s["settings"]["threshold_run"] == 1.0


def test_mcnemar_exact_by_hand_with_no_discordant_pair_and_ties():
    assert mcnemar(0, 0)["p"] == 1.0                                # nothing changed: no evidence at all
    assert mcnemar(3, 3)["p"] == pytest.approx(1.0)                  # a tie
    assert mcnemar(7, 1)["p"] == pytest.approx(2 * (1 + 8) / 2 ** 8)  # 0.0703125
    assert mcnemar(1, 7)["p"] == pytest.approx(mcnemar(7, 1)["p"])    # two-sided
    assert mcnemar(10, 0)["p"] == pytest.approx(2 / 2 ** 10)
    for b, c in ((5, 2), (12, 4), (0, 6)):
        assert mcnemar(b, c)["p"] == pytest.approx(_mcnemar_by_hand(b, c), rel=1e-12)


def test_replies_are_cached_and_a_second_replay_pays_no_call(stored_run, tmp_path):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:mixed") == 0
    assert len(CALLS) == 20
    first = _summary(out)
    CALLS.clear()
    assert _replay(stored_run, out, "replay-double:mixed") == 0
    assert CALLS == [] and _summary(out) == first


def test_an_interrupted_replay_continues_without_paying_a_call_twice(stored_run, tmp_path, capsys):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:stop-after-7") == 130
    assert len(CALLS) == 7 and "run the same command again" in capsys.readouterr().err
    asked = list(CALLS)
    assert _replay(stored_run, out, "replay-double:stop-after-100") == 0
    assert len(CALLS) == 20 and len(set(CALLS)) == 20 and CALLS[:7] == asked   # the 13 others only, once each
    assert _summary(out)["n_replayed"] == 20


def test_the_runs_own_deterministic_sut_fixes_nothing_and_breaks_nothing(tmp_path):
    script = tmp_path / "isu.py"   # always the first option: right or wrong, but the same every time
    script.write_text("import json, sys\nmsg = json.load(sys.stdin)\n"
                      "print(json.dumps({'answers': {q['key']: q['options'][0] for q in msg['questions']}}))\n")
    sut = f"command:{sys.executable} {script}"
    run_dir = _make_run(tmp_path / "run", "--sut", sut, budget="10")
    failures = sum(r.failed for r in open_run(run_dir).records())
    assert 0 < failures
    assert _replay(run_dir, tmp_path / "replay", sut) == 0
    s = _summary(tmp_path / "replay")
    assert (s["fixed"], s["new"], s["persisting"], s["still_passing"]) == (0, 0, failures, 10 - failures)
    assert s["mcnemar"]["p"] == 1.0 and all(f["became_right"] == f["became_wrong"] == 0
                                            for f in s["per_feature"].values())
    assert [float(r["f_qa_before"]) for r in _csv(tmp_path / "replay")] == \
           [float(r["f_qa_after"]) for r in _csv(tmp_path / "replay")]


def _set_renderer_version(run_dir: Path, version: str) -> None:
    info = json.loads((run_dir / "run.json").read_text())
    info["versions"]["renderer"] = version
    (run_dir / "run.json").write_text(json.dumps(info))


def test_missing_images_of_another_renderer_are_named_and_the_rest_replayed(run_copy, tmp_path, capsys):
    _set_renderer_version(run_copy, "isu-blender-0")
    for test_id in ("g0000-i001", "g0001-i004"):
        (run_copy / "images" / f"{test_id}.png").unlink()
    out = tmp_path / "replay"
    assert _replay(run_copy, out, "replay-double:truth") == 0
    err = capsys.readouterr().err
    assert "g0000-i001, g0001-i004" in err and "isu-blender-0" in err and "not replayed" in err
    s = _summary(out)
    assert (s["n_tests"], s["n_replayed"], s["not_replayed"], s["new"]) == (20, 18, 2, 0)
    assert len(CALLS) == 18 and "g0000-i001" not in CALLS
    rows = {r["test_id"]: r for r in _csv(out)}
    assert rows["g0000-i001"]["status"] == "not_replayed" and "isu-blender-0" in rows["g0000-i001"]["note"]
    assert rows["g0000-i001"]["f_qa_after"] == ""
    assert any("g0000-i001" in p for p in s["problems"])

    shutil.rmtree(run_copy / "images")   # nothing left to replay: exit 1, said plainly
    assert _replay(run_copy, tmp_path / "none", "replay-double:truth") == 1
    assert "nothing could be replayed" in capsys.readouterr().err
    assert _summary(tmp_path / "none")["not_replayed"] == 20


def test_a_missing_image_of_this_renderer_is_rendered_again_into_the_replay_folder(run_copy, tmp_path, monkeypatch):
    import tests.doubles as doubles
    renders = []
    paint = doubles.PaintRenderer.render
    monkeypatch.setattr(doubles.PaintRenderer, "render", lambda self, scene, out: renders.append(out)
                        or paint(self, scene, out))
    (run_copy / "images" / "g0000-i001.png").unlink()
    out = tmp_path / "replay"
    assert _replay(run_copy, out, "replay-double:truth") == 0
    assert renders == [out / "images" / "g0000-i001.png"] and not (run_copy / "images" / "g0000-i001.png").exists()
    s = _summary(out)
    assert (s["n_replayed"], s["rerendered"], s["not_replayed"]) == (20, 1, 0)
    assert (out / "labels" / "g0000-i001.json").read_bytes() == (run_copy / "labels" / "g0000-i001.json").read_bytes()
    row = next(r for r in _csv(out) if r["test_id"] == "g0000-i001")
    assert row["note"] == "image rendered again" and row["f_qa_after"] == "1.0"
    assert _replay(run_copy, out, "replay-double:truth") == 0 and len(renders) == 1   # kept: not rendered twice


def test_a_sut_whose_model_knows_another_space_is_refused_naming_both(stored_run, tmp_path, capsys):
    from isu_validate.reference.model import default_model_dir
    model = Path(shutil.copytree(default_model_dir(), tmp_path / "model"))
    meta = json.loads((model / "heads.json").read_text())
    meta.update(space="isu-other", space_hash="0123456789abcdef")
    (model / "heads.json").write_text(json.dumps(meta))
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "reference", "--sut-option", f"model_dir={model}") == 2
    err = capsys.readouterr().err
    space_hash = json.loads((stored_run / "run.json").read_text())["space_hash"]
    assert err.startswith("isu-validate replay: error: the SUT 'reference' does not cover the run's scene space")
    assert "'isu-other' (hash 0123456789abcdef)" in err and f"'isu-paper' (hash {space_hash})" in err
    assert not (out / "summary.json").exists()


def test_a_sut_that_always_errors_stops_with_its_error_and_exit_1(stored_run, tmp_path, capsys):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:error") == 1
    err = capsys.readouterr().err
    assert "stopped after 5 SUT errors in a row" in err and "HTTP 503 from the SUT (test double)" in err
    s = _summary(out)
    assert (s["n_replayed"], s["sut_errors"], s["not_replayed"], s["new"]) == (0, 5, 15, 0) and len(CALLS) == 5

    assert _replay(stored_run, tmp_path / "all", "replay-double:error", "--stop-after-sut-errors", "0") == 1
    assert "nothing could be replayed" in capsys.readouterr().err
    assert _summary(tmp_path / "all")["sut_errors"] == 20


def test_sut_errors_between_answers_are_counted_apart_never_as_failures(stored_run, tmp_path):
    out = tmp_path / "replay"
    assert _replay(stored_run, out, "replay-double:flaky", "--stop-after-sut-errors", "0") == 0
    s = _summary(out)
    lit = sum(r.canonical.get("car_lights") == "ON" for r in open_run(stored_run).records())
    assert 0 < lit < 20 and s["sut_errors"] == lit and s["n_replayed"] == 20 - lit
    assert s["new"] == s["persisting"] == s["failures_after"] == 0   # a truthful SUT where it answers
    assert {r["status"] for r in _csv(out) if r["note"].startswith("SUT error")} == {"sut_error"}


def test_a_run_verdict_the_judge_does_not_reproduce_is_named(run_copy, tmp_path):
    import sqlite3
    with sqlite3.connect(run_copy / "archive.sqlite") as db:   # as if another judge had scored this test
        db.execute("""UPDATE tests SET fitness = '{"f_qa": 0.5}', "primary" = 0.5 WHERE test_id = 'g0000-i003'""")
    assert _replay(run_copy, tmp_path / "replay", "replay-double:truth") == 0
    s = _summary(tmp_path / "replay")
    assert any(p.startswith("1 test(s) (e.g. g0000-i003: F_qa 0.5 in the run, 1.0 judging") for p in s["problems"])
    assert next(r for r in _csv(tmp_path / "replay") if r["test_id"] == "g0000-i003")["f_qa_before"] == "0.5"


@pytest.mark.parametrize("argv, message", [
    (["replay", "nowhere", "--sut", "replay-double:truth", "--out", "x"], "is not a run directory"),
    (["replay", "RUN", "--sut", "replay-double:truth", "--out", "x", "--threshold", "7"], "must lie in 0..1"),
    (["replay", "RUN", "--sut", "nonsense:x", "--out", "x"], "unknown SUT spec"),
    (["replay", "RUN", "--sut", "replay-double:truth", "--out", "x", "--sut-option", "novalue"], "NAME=VALUE"),
])
def test_bad_input_is_one_line_and_exit_2(stored_run, tmp_path, capsys, argv, message):
    argv = [str(stored_run) if a == "RUN" else str(tmp_path / a) if a == "x" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("isu-validate replay: error: ") and message in err and err.count("\n") == 1


def test_the_command_calls_the_public_function(stored_run, tmp_path, monkeypatch):
    import isu_validate.replay
    calls = []
    real = isu_validate.replay.replay_run
    monkeypatch.setattr(isu_validate.replay, "replay_run", lambda *a, **k: calls.append((a, k)) or real(*a, **k))
    assert main(["replay", str(stored_run), "--sut", "replay-double:truth", "--out", str(tmp_path / "r"),
                 "--repeats", "2"]) == 0
    (run, out, settings), _ = calls[0]
    assert isinstance(settings, iv.ReplaySettings) and (settings.sut, settings.repeats) == ("replay-double:truth", 2)
    result = iv.replay_run(stored_run, tmp_path / "r", iv.ReplaySettings(sut="replay-double:truth", threshold=0.8),
                           overwrite=True)   # other settings than the command's replay in the same folder
    assert (result.new, result.persisting) == (0, 0) and result.fixed == result.summary["failures_before"]
    assert set(result.rates) == {1.0, 0.9, 0.8, 0.7, 0.6, 0.5} and result.rates[0.8][1] == 0.0
    assert 0 < result.p <= 1 and result.exit_code == 0


@pytest.mark.blender
@pytest.mark.slow
def test_a_tiny_real_run_replayed_with_the_reference_isu(tmp_path):
    """Blender renders a scene, the reference ISU answers; replayed by the same model it changes nothing,
    also for a frame deleted and rendered again by Blender."""
    run_dir = tmp_path / "run"
    assert main(["run", "--sut", "reference", "--algorithm", "rs", "--budget", "1", "--pop-size", "2", "--seed", "3",
                 "--preset", "draft", "--no-report", "--out", str(run_dir)]) == 0
    records = open_run(run_dir).records()
    (run_dir / records[0].image).unlink()
    out = tmp_path / "replay"
    assert _replay(run_dir, out, "reference") == 0
    s = _summary(out)
    assert (s["n_tests"], s["n_replayed"], s["rerendered"], s["fixed"], s["new"]) == (1, 1, 1, 0, 0)
    assert s["persisting"] == sum(r.failed for r in records)
    assert (out / "images" / f"{records[0].test_id}.png").stat().st_size > 10_000   # a real render
