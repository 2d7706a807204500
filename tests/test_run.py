"""Runs end to end through the real loop (test doubles for renderer and SUT): archive,
export, resume after SIGKILL, parallel evaluation (process pool and Dask)."""
import csv
import io
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from isu_validate import pipeline as pipeline_module
from isu_validate.archive import Archive
from isu_validate.archive.export import write_csv
from isu_validate.cli import main
from isu_validate.pipeline import PipelineConfig
from isu_validate.search import RunConfig, RunError, run_search
from isu_validate.space import load_space

from tests import doubles

ROOT = Path(__file__).resolve().parent.parent
FACTORY = "tests.doubles:build"


def config(run_dir, **kw) -> RunConfig:
    pipeline = PipelineConfig(run_dir=str(run_dir), sut="blind-double", factory=FACTORY)
    return RunConfig(pipeline=pipeline, **{"algorithm": "nsga2", "pop_size": 6, "seed": 5, "budget_tests": 24, **kw})


def records_of(run_dir):
    archive = Archive(Path(run_dir) / "archive.sqlite")
    try:
        return {r.test_id: r for r in archive}
    finally:
        archive.close()


def expected_f_qa(space, canonical, occluded=()) -> float:
    """What the blind double's answers score: seat belts misread in low light, a suitcase always said to be
    on the back seat. As the judge does, features the frame hid (``occluded``, as the record stores them)
    are left out of the weights."""
    questions = [q for q in space.questions(canonical) if q.key not in occluded]
    wrong = {q.key for q in questions if (q.key == "seat_belt" and canonical["external_light"] == "LOW")
             or (q.key == "luggage_position" and q.truth != "BACK")}
    return sum(q.weight for q in questions if q.key not in wrong) / sum(q.weight for q in questions)


def test_a_run_commits_every_test_with_image_label_and_verdict(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_RENDER_DELAY", "0.03")  # each stage takes at least this long
    monkeypatch.setenv("ISU_TEST_SUT_DELAY", "0.02")
    monkeypatch.setenv("ISU_TEST_OCCLUDE", "1")   # a suitcase behind a child seat is hidden: not judged
    summary = run_search(config(tmp_path / "run"))
    records = records_of(tmp_path / "run")
    space = load_space()
    assert summary.tests == len(records) == 24 and summary.generations == 4
    for r in records.values():
        assert (tmp_path / "run" / r.image).exists()
        label = json.loads((tmp_path / "run" / "labels" / f"{r.test_id}.json").read_text())
        assert label["scene"] == r.canonical and label["occluded"] == r.occluded
        assert r.primary == pytest.approx(expected_f_qa(space, r.canonical, r.occluded))
        assert r.failed == (r.primary < 1.0)
        assert r.timings["render_s"] >= 0.03 and r.timings["sut_s"] >= 0.02 and r.timings["update_s"] == 0.0
    assert summary.failures == sum(r.failed for r in records.values()) > 0
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["space_hash"] and run["versions"]["pymoo"] == "0.6.2" and run["config"]["seed"] == 5


def test_export_csv_has_the_contract_columns(tmp_path):
    run_search(config(tmp_path / "run", budget_tests=12))
    out = io.StringIO()
    assert write_csv(tmp_path / "run", out) == 12
    rows = list(csv.DictReader(io.StringIO(out.getvalue())))
    for column in ["test_id", "algorithm", "seed", "generation", "x.seat_belt", "y.seat_belt", "x.luggage_orientation",
                   "f_qa", "f_div", "failed", "sut_error", "render_s", "sut_s", "image"]:
        assert column in rows[0], column
    assert "y.luggage_orientation" not in rows[0]  # not predicted: the SUT is never asked
    no_luggage = [r for r in rows if r["x.luggage"] == "NO"]
    assert all(r["x.luggage_colour"] == "" for r in no_luggage)


def test_an_existing_run_is_not_overwritten_and_resume_checks_the_configuration(tmp_path):
    run_search(config(tmp_path / "run", budget_tests=6))
    with pytest.raises(RunError, match="pass resume=True to continue it or choose another folder for the run_dir "
                                       "argument") as refused:   # the API's words, not the command line's
        run_search(config(tmp_path / "run", budget_tests=6))
    assert "pass --resume to continue it or choose another folder for --out" in refused.value.on_command_line()
    with pytest.raises(RunError, match="different configuration"):
        run_search(config(tmp_path / "run", seed=99), resume=True)
    summary = run_search(config(tmp_path / "run", budget_tests=12), resume=True)
    assert summary.evaluated_now == 6 and summary.tests == 12


def test_a_run_started_by_another_version_of_its_search_is_not_resumed(tmp_path):
    run_search(config(tmp_path / "run", algorithm="surrogate", budget_tests=6))
    run_file = tmp_path / "run" / "run.json"
    run = json.loads(run_file.read_text())
    assert run["versions"]["search"] == "surrogate-2"
    run["versions"]["search"] = "surrogate-1"            # as the search before the coupled error draws wrote it
    run_file.write_text(json.dumps(run))
    with pytest.raises(RunError, match="started by search surrogate-1; this installation's is surrogate-2"):
        run_search(config(tmp_path / "run", algorithm="surrogate", budget_tests=12), resume=True)
    assert len(records_of(tmp_path / "run")) == 6        # nothing evaluated, nothing lost
    del run["versions"]["search"]                         # a run from before versions: checked scene by scene
    run_file.write_text(json.dumps(run))
    assert run_search(config(tmp_path / "run", algorithm="surrogate", budget_tests=12), resume=True).tests == 12


def _cli(run_dir, *extra, env=None):
    return [sys.executable, "-m", "isu_validate.cli", "run", "--out", str(run_dir), "--pipeline-factory", FACTORY,
            "--budget", "30", "--pop-size", "6", "--seed", "11", "--no-report", *extra]


def test_resume_after_sigkill_loses_nothing_and_evaluates_nothing_twice(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT), ISU_TEST_RENDER_DELAY="0.15")
    reference = tmp_path / "uninterrupted"
    subprocess.run(_cli(reference), env=dict(env, ISU_TEST_RENDER_DELAY="0"), check=True, cwd=ROOT,
                   capture_output=True)

    killed = tmp_path / "killed"
    proc = subprocess.Popen(_cli(killed), env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 60
    while time.time() < deadline:
        time.sleep(0.2)
        try:
            with sqlite3.connect(killed / "archive.sqlite") as db:
                if db.execute("SELECT COUNT(*) FROM tests").fetchone()[0] >= 9:  # mid second generation
                    break
        except sqlite3.OperationalError:
            pass
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = records_of(killed)
    assert 9 <= len(before) < 30

    result = subprocess.run(_cli(killed, "--resume"), env=dict(env, ISU_TEST_RENDER_DELAY="0"), cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert f"({30 - len(before)} evaluated now)" in result.stdout
    after, expected = records_of(killed), records_of(reference)
    for test_id, record in before.items():  # nothing lost, nothing re-evaluated
        assert after[test_id].created == record.created
    assert {t: r.scene_key for t, r in after.items()} == {t: r.scene_key for t, r in expected.items()}
    assert {t: r.primary for t, r in after.items()} == {t: r.primary for t, r in expected.items()}


def test_process_pool_and_dask_give_the_same_run_as_one_process(tmp_path):
    from distributed import LocalCluster

    serial = run_search(config(tmp_path / "serial", budget_tests=12))
    pooled = run_search(config(tmp_path / "pool", budget_tests=12, workers=2))
    closed_before = len(doubles.CLOSED)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        dasked = run_search(config(tmp_path / "dask", budget_tests=12, cluster=cluster.scheduler_address))
        # the worker (in this process) keeps no pipeline, and no renderer, of the finished run
        assert not [key for key in pipeline_module._PIPELINES if str(tmp_path / "dask") in key]
        assert len(doubles.CLOSED) > closed_before
        # a setting only the pipeline can check is checked on a worker, before anything is written
        bad = RunConfig(pipeline=PipelineConfig(run_dir=str(tmp_path / "bad"), factory="tests.doubles:nothing"),
                        cluster=cluster.scheduler_address)
        with pytest.raises(ValueError, match="cannot load the pipeline factory"):
            run_search(bad)
        assert not (tmp_path / "bad").exists()
    keys = [{t: r.scene_key for t, r in records_of(tmp_path / name).items()} for name in ("serial", "pool", "dask")]
    assert keys[0] == keys[1] == keys[2]
    assert serial.population == pooled.population == dasked.population


def test_unreachable_cluster_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setattr("isu_validate.execution.DASK_CONNECT_TIMEOUT_S", 1)
    with pytest.raises(ConnectionError, match="cannot reach the Dask scheduler"):
        run_search(config(tmp_path / "run", cluster="tcp://127.0.0.1:9"))


def test_time_budget_stops_the_run(tmp_path):
    summary = run_search(config(tmp_path / "run", budget_tests=None, budget_s=0.5))
    assert summary.tests >= 6 and "time budget" in summary.stopped_because


def test_cli_run_and_export(tmp_path, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    assert main(["run", "--out", str(tmp_path / "r"), "--pipeline-factory", FACTORY, "--budget", "6",
                 "--pop-size", "3", "--no-report"]) == 0
    assert "6 tests" in capsys.readouterr().out
    assert main(["export", str(tmp_path / "r"), "--out", str(tmp_path / "t.csv")]) == 0
    rows = list(csv.DictReader((tmp_path / "t.csv").open()))
    records = records_of(tmp_path / "r")
    assert [r["test_id"] for r in rows] == sorted(records) and len(rows) == 6
    for row in rows:  # the row is its archived test: scene, answers, verdict
        record = records[row["test_id"]]
        assert float(row["f_qa"]) == pytest.approx(record.fitness["f_qa"], abs=1e-6)
        assert row["failed"] == str(int(record.failed)) and row["x.seat_belt"] == record.canonical["seat_belt"]
        assert row["y.seat_belt"] == record.answers["seat_belt"]
    assert main(["export", str(tmp_path / "nothing")]) == 2
    assert "not a run directory" in capsys.readouterr().err
    assert main(["run", "--out", str(tmp_path / "bad"), "--space", "nope", "--pipeline-factory", FACTORY]) == 2
    assert "no spaces rig named 'nope'" in capsys.readouterr().err


def test_render_and_sut_errors_are_recorded_not_counted_as_failures_and_the_run_goes_on(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_FAIL_RENDER_WITH_CAN", "1")
    monkeypatch.setenv("ISU_TEST_SUT_ERROR_WITH_BOTTLE", "1")
    summary = run_search(config(tmp_path / "run", budget_tests=18))
    records = records_of(tmp_path / "run").values()
    render_errors = [r for r in records if r.render_error]
    sut_errors = [r for r in records if r.sut_error]
    assert summary.tests == 18 and render_errors and sut_errors
    assert all(r.canonical["colacan_codriver_seat"] == "YES" and r.image is None and not r.failed
               for r in render_errors)
    assert all(r.canonical["colabottle_codriver_seat"] == "YES" and not r.failed and "502" in r.sut_raw
               for r in sut_errors)
    assert summary.errors == len(render_errors) + len(sut_errors)
    assert summary.failures == sum(r.failed for r in records) > 0
    out = io.StringIO()
    write_csv(tmp_path / "run", out)
    rows = list(csv.DictReader(io.StringIO(out.getvalue())))
    assert {r["test_id"] for r in rows if r["render_error"]} == {r.test_id for r in render_errors}


def test_an_unusable_sut_stops_the_run_with_a_clear_error(tmp_path, capsys):
    assert main(["run", "--out", str(tmp_path / "r"), "--sut", "command:/no/such/program", "--budget", "2",
                 "--pop-size", "2", "--no-report"]) == 2
    assert "not found" in capsys.readouterr().err


# ------------------------------------------------------------------ broken setups stop at once
def _run_cli(run_dir, *extra, budget="12", factory=FACTORY):
    return main(["run", "--out", str(run_dir), "--pipeline-factory", factory, "--budget", budget, "--pop-size", "6",
                 "--seed", "5", "--no-report", *extra])


def _script(tmp_path, body: str) -> str:
    path = tmp_path / "isu.py"
    path.write_text(body)
    return f"command:{sys.executable} {path}"


ANSWER_FIRST_OPTION = ("import json, sys\nmsg = json.load(sys.stdin)\n"
                       "print(json.dumps({'answers': {q['key']: q['options'][0] for q in msg['questions']}}))\n")


@pytest.mark.parametrize("broken, error", [
    ("import sys\nprint('CUDA out of memory', file=sys.stderr)\nsys.exit(3)\n", "exited with status 3"),
    ("print('Segmentation fault (core dumped)')\n", "unparseable"),
])
def test_a_broken_sut_stops_the_run_with_its_last_error_and_resume_continues_after_the_fix(
        tmp_path, capsys, broken, error):
    sut = _script(tmp_path, broken)
    assert _run_cli(tmp_path / "r", "--sut", sut, "--stop-after-sut-errors", "4") == 1
    err = capsys.readouterr().err
    assert "4 times in a row" in err and f"last SUT error: {error}" in err and "--resume" in err
    if "status 3" in error:
        assert "CUDA out of memory" in err  # the reason is on the console, not only in the CSV
    kept = records_of(tmp_path / "r")
    assert len(kept) == 4 and all(r.sut_error for r in kept.values())

    (tmp_path / "isu.py").write_text(ANSWER_FIRST_OPTION)  # the fix
    assert _run_cli(tmp_path / "r", "--resume") == 0
    after = records_of(tmp_path / "r")
    assert len(after) == 12 and sum(bool(r.sut_error) for r in after.values()) == 4
    assert all(after[t].created == r.created for t, r in kept.items())  # kept, not evaluated again


@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_closed_port_stops_the_run(tmp_path, capsys, workers):
    import socket

    with socket.socket() as s:  # a port that was free a moment ago: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert _run_cli(tmp_path / "r", "--sut", f"http:http://127.0.0.1:{port}/isu", "--sut-option", "max_retries=0",
                    "--stop-after-sut-errors", "3", "--workers", workers) == 1
    assert "last SUT error: cannot reach" in capsys.readouterr().err
    kept = len(records_of(tmp_path / "r"))
    # one process stops right at the third; a pool also keeps what was already running
    assert kept == 3 if workers == "1" else 3 <= kept <= 6


def test_sut_errors_between_answers_do_not_stop_the_run(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_SUT_ERROR_WITH_BOTTLE", "1")
    summary = run_search(config(tmp_path / "run", budget_tests=18, stop_after_sut_errors=2))
    assert summary.tests == 18 and summary.last_sut_error and 0 < summary.errors < 18


@pytest.mark.parametrize("flags, message", [
    (["--preset", "ultra"], "unknown render preset 'ultra'"),
    (["--camera", "nope"], "nope"),
    (["--cabin", "nope"], "nope"),
    (["--space", "nope"], "no spaces rig named 'nope'"),
    (["--threshold", "7"], "threshold must lie in 0..1"),
    (["--channels", "seg,xray"], "unknown render channel(s) xray"),
    (["--repeats", "0"], "repeats must be at least 1"),
    (["--sut-timeout", "0"], "timeout must be positive"),
    (["--pop-size", "1"], "population size must be at least 2"),
    (["--budget", "0"], "--budget must be at least 1"),
    (["--stop-after-sut-errors", "-1"], "0 (never stop) or more"),
    (["--sut", "command:/no/such/isu"], "not found"),
    (["--sut", "telepathy:x"], "unknown SUT spec"),
    (["--sut", "openai:gpt-4o@https://api.openai.com/v1"], "no API key; set the environment variable OPENAI_API_KEY"),
    (["--sut-option", "colour=blue"], "unknown option(s) colour"),
])
def test_every_setting_is_checked_before_the_first_file_is_written(tmp_path, capsys, monkeypatch, flags, message):
    """With the real pipeline (Blender is only started by a first render, which never comes)."""
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    sut = ["--sut", _script(tmp_path, ANSWER_FIRST_OPTION)] if "--sut" not in flags else []
    out = tmp_path / "r"
    assert main(["run", "--out", str(out), "--budget", "4", "--pop-size", "2", "--no-report", *sut, *flags]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_after_a_bad_flag_the_corrected_command_starts_the_run(tmp_path, capsys):
    assert _run_cli(tmp_path / "r", "--threshold", "1.5", factory="isu_validate.pipeline:build_components") == 2
    assert not (tmp_path / "r").exists()
    assert _run_cli(tmp_path / "r", "--threshold", "0.5") == 0


def test_resume_refuses_settings_that_differ_and_lists_them(tmp_path, capsys):
    assert _run_cli(tmp_path / "r", budget="6") == 0
    before = records_of(tmp_path / "r")
    capsys.readouterr()
    sut = _script(tmp_path, ANSWER_FIRST_OPTION)
    assert _run_cli(tmp_path / "r", "--resume", "--seed", "99", "--sut", sut, "--threshold", "0.5") == 2
    err = capsys.readouterr().err
    assert "--seed: 5 in the stored run, 99 now" in err
    assert f"--sut: 'reference' in the stored run, '{sut}' now" in err
    assert "--threshold: (default) in the stored run, 0.5 now" in err
    assert _run_cli(tmp_path / "r", "--resume", budget="3") == 2
    assert "may only grow" in capsys.readouterr().err
    assert {t: r.created for t, r in records_of(tmp_path / "r").items()} == {t: r.created for t, r in before.items()}
    # the same values typed again, a larger budget, and what only spreads the work: accepted
    assert _run_cli(tmp_path / "r", "--resume", "--seed", "5", "--stop-after-sut-errors", "0") == 0
    assert len(records_of(tmp_path / "r")) == 12


def test_unreachable_cluster_is_one_clear_line_and_leaves_no_run_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("isu_validate.execution.DASK_CONNECT_TIMEOUT_S", 1)
    assert _run_cli(tmp_path / "r", "--cluster", "tcp://127.0.0.1:9") == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_run_help_says_where_api_keys_come_from(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "API keys come from the environment only" in text and "never written to run.json" in text
    assert "$OPENAI_API_KEY" in text and "--sut-option api_key_env=NAME" in text
