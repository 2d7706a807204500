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

from isu_validate.archive import Archive
from isu_validate.archive.export import write_csv
from isu_validate.cli import main
from isu_validate.pipeline import PipelineConfig
from isu_validate.search import RunConfig, RunError, run_search
from isu_validate.space import load_space

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


def expected_f_qa(space, canonical) -> float:
    """What the blind double's answers score: seat belts misread in low light, luggage always yellow."""
    questions = space.questions(canonical)
    wrong = {q.key for q in questions if (q.key == "seat_belt" and canonical["external_light"] == "LOW")
             or (q.key == "luggage_colour" and q.truth != "YELLOW")}
    return sum(q.weight for q in questions if q.key not in wrong) / sum(q.weight for q in questions)


def test_a_run_commits_every_test_with_image_label_and_verdict(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_RENDER_DELAY", "0.03")  # each stage takes at least this long
    monkeypatch.setenv("ISU_TEST_SUT_DELAY", "0.02")
    summary = run_search(config(tmp_path / "run"))
    records = records_of(tmp_path / "run")
    space = load_space()
    assert summary.tests == len(records) == 24 and summary.generations == 4
    for r in records.values():
        assert (tmp_path / "run" / r.image).exists()
        label = json.loads((tmp_path / "run" / "labels" / f"{r.test_id}.json").read_text())
        assert label["scene"] == r.canonical
        assert r.primary == pytest.approx(expected_f_qa(space, r.canonical)) and r.failed == (r.primary < 1.0)
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
    with pytest.raises(RunError, match="--resume"):
        run_search(config(tmp_path / "run", budget_tests=6))
    with pytest.raises(RunError, match="different configuration"):
        run_search(config(tmp_path / "run", seed=99), resume=True)
    summary = run_search(config(tmp_path / "run", budget_tests=12), resume=True)
    assert summary.evaluated_now == 6 and summary.tests == 12


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
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        dasked = run_search(config(tmp_path / "dask", budget_tests=12, cluster=cluster.scheduler_address))
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
    assert all(r.canonical["can"] == "YES" and r.image is None and not r.failed for r in render_errors)
    assert all(r.canonical["cola_bottle"] == "YES" and not r.failed and "502" in r.sut_raw for r in sut_errors)
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
