"""Output folders never clobber (``archive/output_dir.py``): every command that writes a folder refuses one that
holds another command's output, or its own made with other settings, with one clear line, and leaves what was
there byte for byte; ``--overwrite`` (``overwrite=True`` in Python) says otherwise, ``--resume`` continues.

Runs come from the pipeline doubles (``tests.doubles:build``), datasets from the painting renderer double, the
replayed SUT from ``tests/test_replay.py``'s adapter double: no Blender, no network.
"""
from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest

import isu_validate as iv
from isu_validate.archive.output_dir import MARKER, OutputInUse, claim_output, holder
from isu_validate.cli import main
from isu_validate.sut.registry import ADAPTERS
from tests.test_agree import setup  # noqa: F401 (a fixture: pairs and a SUT that answers from a table)
from tests.test_replay import DoubleSUT, _make_run

DATASET_FACTORY = "tests.dataset_doubles:renderer"


@pytest.fixture(autouse=True)
def double_sut(monkeypatch):
    monkeypatch.setitem(ADAPTERS, "replay-double", DoubleSUT)


@pytest.fixture(scope="module")
def stored_run(tmp_path_factory) -> Path:
    return _make_run(tmp_path_factory.mktemp("stored") / "run", budget="10")


@pytest.fixture
def run(stored_run, tmp_path) -> Path:
    return Path(shutil.copytree(stored_run, tmp_path / "run"))


def snapshot(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` by its content's digest: equal snapshots, byte-identical folders."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def refused(argv: list[str], folder: Path, capsys, *words: str) -> str:
    """``argv`` exits 2 with one error line naming ``words``, and ``folder`` is as it was."""
    before = snapshot(folder)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith(f"isu-validate {argv[0]}: error: {folder}")
    for word in words:
        assert word in err
    assert snapshot(folder) == before
    return err


# ---- the three harmful cases of issue 35

def test_replay_into_the_runs_own_folder_is_refused_and_the_run_is_untouched(run, capsys):
    err = refused(["replay", str(run), "--sut", "replay-double:truth", "--out", str(run)], run, capsys,
                  "holds the output of `isu-validate run`", "choose another folder for --out", "--overwrite")
    assert "overwrite=True" not in err


def test_reference_train_into_a_run_is_refused_and_the_run_is_untouched(run, tmp_path, capsys):
    dataset = tmp_path / "data"
    assert main(["dataset", "--out", str(dataset), "--n", "2", "--renderer-factory", DATASET_FACTORY]) == 0
    capsys.readouterr()
    refused(["reference", "train", "--extra", str(dataset), "--out", str(run)], run, capsys,
            f"holds the output of `isu-validate run` ({MARKER})", "`isu-validate reference train` would change it")
    (run / MARKER).unlink()   # a run from before the marker: known by its run.json
    refused(["reference", "train", "--extra", str(dataset), "--out", str(run)], run, capsys,
            "holds the output of `isu-validate run` (run.json)")


def test_a_replay_of_another_model_is_not_replaced_unless_overwrite_is_given(stored_run, tmp_path, capsys):
    out = tmp_path / "replay"
    assert main(["replay", str(stored_run), "--sut", "replay-double:truth", "--out", str(out)]) == 0
    capsys.readouterr()
    refused(["replay", str(stored_run), "--sut", "replay-double:mixed", "--out", str(out)], out, capsys,
            "holds `isu-validate replay` output made with other settings", "sut_fingerprint",
            "'replay-double:truth' then, 'replay-double:mixed' now", "--overwrite")
    # the same replay again goes on (and pays nothing twice); --overwrite replaces it
    assert main(["replay", str(stored_run), "--sut", "replay-double:truth", "--out", str(out)]) == 0
    assert main(["replay", str(stored_run), "--sut", "replay-double:mixed", "--out", str(out), "--overwrite"]) == 0
    assert json.loads((out / "summary.json").read_text())["settings"]["sut"] == "replay-double:mixed"


def test_a_replay_folder_from_before_the_marker_is_recognised_by_its_files(stored_run, tmp_path, capsys):
    out = tmp_path / "replay"
    assert main(["replay", str(stored_run), "--sut", "replay-double:truth", "--out", str(out)]) == 0
    (out / MARKER).unlink()
    assert holder(out).command == "replay" and holder(out).evidence == "replay.csv"
    capsys.readouterr()
    refused(["replay", str(stored_run), "--sut", "replay-double:mixed", "--out", str(out)], out, capsys,
            "made with other settings", "sut_fingerprint")


# ---- every other command that writes a folder

def test_run_refuses_a_folder_that_holds_a_dataset(tmp_path, capsys):
    dataset = tmp_path / "data"
    assert main(["dataset", "--out", str(dataset), "--n", "2", "--renderer-factory", DATASET_FACTORY]) == 0
    capsys.readouterr()
    refused(["run", "--out", str(dataset), "--pipeline-factory", "tests.doubles:build", "--budget", "2"], dataset,
            capsys, "holds the output of `isu-validate dataset`")


def test_dataset_refuses_a_run_naming_it(run, capsys):
    refused(["dataset", "--out", str(run), "--n", "2", "--renderer-factory", DATASET_FACTORY], run, capsys,
            "holds the output of `isu-validate run`")


def test_report_refuses_a_run_and_a_report_of_other_runs(run, stored_run, tmp_path, capsys):
    refused(["report", str(stored_run), "--out", str(run), "--embedding", "scene"], run, capsys,
            "holds the output of `isu-validate run`")
    out = tmp_path / "report"
    assert main(["report", str(stored_run), "--out", str(out), "--embedding", "scene"]) == 0
    capsys.readouterr()
    refused(["report", str(run), "--out", str(out), "--embedding", "scene"], out, capsys,
            "holds `isu-validate report` output made with other settings", "runs:")
    assert main(["report", str(stored_run), "--out", str(out), "--embedding", "scene"]) == 0   # the same again


def test_recreate_refuses_a_run(run, stored_run, capsys):
    refused(["recreate", str(stored_run), "--select", "failing", "--n", "1", "--sheet-preset", "run",
             "--out", str(run)], run, capsys, "holds the output of `isu-validate run`")


def test_agree_refuses_a_run(run, setup, capsys):  # noqa: F811 (the imported fixture)
    pairs, space_file, sut, _ = setup
    refused(["agree", str(pairs), "--sut", sut, "--space", str(space_file), "--no-realism", "--out", str(run)], run,
            capsys, "holds the output of `isu-validate run`", "`isu-validate agree` would change it")


def test_exposure_check_refuses_a_run(run, tmp_path, capsys):
    refused(["exposure", "check", str(run / "images"), str(run / "images"), "--out", str(run)], run, capsys,
            "holds the output of `isu-validate run`", "`isu-validate exposure check` would change it")


def test_exposure_apply_refuses_a_run_as_its_folder(run, tmp_path, capsys):
    import numpy as np

    from capture.camera import load_camera, write_imaging
    from capture.camera_model import synthetic
    from tests.test_exposure_cli import _exr

    cam = write_imaging(load_camera("default").source, synthetic.camera(), tmp_path / "cam.toml")
    renders = tmp_path / "renders"
    _exr(renders / "images" / "t0000.exr", synthetic.scene(np.random.default_rng(0), (60, 80)) * 0.5)
    refused(["exposure", "apply", str(renders), "--camera", str(cam), "--out", str(run)], run, capsys,
            "holds the output of `isu-validate run`", "`isu-validate exposure apply` would change it")


def test_bench_refuses_a_run(run, capsys):
    refused(["bench", "render", "--out", str(run)], run, capsys,
            "holds the output of `isu-validate run`", "`isu-validate bench render` would change it")


def test_stylize_refuses_a_run(run, capsys):
    refused(["stylize", str(run / "images"), "--style", str(next((run / "images").glob("*.png"))),
             "--out", str(run)], run, capsys, "holds the output of `isu-validate run`")


# ---- the module itself

def test_the_python_api_names_its_arguments_and_the_command_line_its_flags(run):
    with pytest.raises(OutputInUse) as error:
        iv.replay_run(run, run, iv.ReplaySettings(sut="replay-double:truth"))
    assert "pass overwrite=True" in str(error.value) and "the out argument" in str(error.value)
    assert "--" not in str(error.value).split("; ")[-1]
    assert "pass --overwrite" in error.value.on_command_line() and "--out" in error.value.on_command_line()


def test_a_folder_with_nothing_but_a_marker_is_free(tmp_path):
    claim_output(tmp_path / "x", "report", {"a": 1}).mark()   # a start killed right after marking
    assert claim_output(tmp_path / "x", "replay", {"b": 2}).command == "replay"


def test_same_settings_pass_other_settings_are_named_and_resume_defers_to_the_command(tmp_path):
    out = tmp_path / "o"
    claim_output(out, "replay", {"run": "r1", "threshold": None}).mark()
    (out / "summary.json").write_text("{}")
    assert claim_output(out, "replay", {"run": "r1", "threshold": None})
    with pytest.raises(OutputInUse, match=r"threshold: \(default\) then, 0.8 now"):
        claim_output(out, "replay", {"run": "r1", "threshold": 0.8})
    assert claim_output(out, "replay", {"run": "r1", "threshold": 0.8}, resume=True)
    assert claim_output(out, "replay", {"run": "r1", "threshold": 0.8}, overwrite=True)
    with pytest.raises(OutputInUse, match="holds the output of `isu-validate replay`"):
        claim_output(out, "report", {}, resume=True)


def test_a_command_that_cannot_overwrite_does_not_offer_it(tmp_path):
    (tmp_path / "run.json").write_text("{}")
    with pytest.raises(OutputInUse) as error:
        claim_output(tmp_path, "dataset", {}, overwrite=None)
    assert "overwrite" not in str(error.value)


def test_realism_refuses_a_file_inside_a_run_and_a_file_that_exists(run, tmp_path, capsys):
    images = str(run / "images")
    refused(["realism", images, images, "--out", str(run / "fid.json")], run, capsys,
            "is inside the output of `isu-validate run`")
    earlier = tmp_path / "fid.json"
    earlier.write_text("mine")
    assert main(["realism", images, images, "--out", str(earlier)]) == 2
    assert "already exists" in capsys.readouterr().err and earlier.read_text() == "mine"


def test_render_random_refuses_a_run(run, capsys):
    refused(["render", "--random", "2", "--out", str(run)], run, capsys,
            "holds the output of `isu-validate run`", "`isu-validate render` would change it")


def test_capture_shoot_refuses_a_run(run, capsys):
    refused(["capture", "shoot", "--source", "replay:" + str(run / "images"), "--frames", "1", "--out", str(run)],
            run, capsys, "holds the output of `isu-validate run`")


def test_resume_errors_name_resume_true_in_python_and_resume_on_the_command_line(tmp_path):
    from isu_validate.archive.run_file import RunError
    from isu_validate.config import PipelineConfig, RunConfig
    from isu_validate.dataset.folder import DatasetError

    with pytest.raises(DatasetError) as no_dataset:
        iv.build_dataset(iv.DatasetSettings(n=2, renderer_factory=DATASET_FACTORY), tmp_path / "none", resume=True)
    assert "start one without resume=True" in str(no_dataset.value)
    assert "start one without --resume" in no_dataset.value.on_command_line()
    run = tmp_path / "run"
    config = RunConfig(PipelineConfig(run_dir=str(run), factory="tests.doubles:build"), algorithm="rs", pop_size=2,
                       budget_tests=2)
    iv.run_search(config)
    with pytest.raises(RunError) as other:
        iv.run_search(RunConfig(PipelineConfig(run_dir=str(run), factory="tests.doubles:build"), algorithm="rs",
                                pop_size=2, budget_tests=2, seed=9), resume=True)
    assert "another folder for the run_dir argument" in str(other.value) and "--out" not in str(other.value)
    assert "another folder for --out" in other.value.on_command_line()
