"""``isu-validate dataset``: the folder contract on a tiny dataset rendered with real Blender (COCO masks
against a re-render, VQA answers the real judge scores 1.0, style copies), focus sampling near the
failures of a run (never one of its scenes), rules read back, resume after a kill, and bad input (one
line, nothing written). The runs and most builds use the test doubles: no Blender."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from isu_validate.analysis.regions import failure_regions
from isu_validate.analysis.runs import load_run
from isu_validate.cli import main
from isu_validate.config import PipelineConfig, RunConfig
from isu_validate.dataset import DatasetSettings, build_dataset, focus_regions, focus_scenes, parse_rule
from isu_validate.errors import InputError
from isu_validate.evaluate import make_judge
from isu_validate.image_files import IMAGE_SUFFIXES
from isu_validate.render import Preset
from isu_validate.search import run_search
from isu_validate.space import load_space
from isu_validate.sut import build_request, interpret, vqa_prompt
from isu_validate.sut.exchange import Exchange

ROOT = Path(__file__).resolve().parent.parent
DOUBLE = "tests.dataset_doubles:renderer"
# 200x150, 2 samples, no denoiser (as tests/test_render.py)
TINY = Preset("test", 0.3125, 2, False, "NONE", 2, 1, 1, 3.0, 1.5)
SPACE = load_space()
# pycocotools' mask decoding (annToMask) under numpy 2; our code only encodes
DECODING = pytest.mark.filterwarnings("ignore:__array__ implementation doesn't accept a copy keyword")


def _blind_run(path: Path, threshold: float | None = None, budget: int = 40) -> Path:
    """A run of the doubles: the SUT misreads seat belts in low light and luggage on the passenger seat."""
    pipeline = PipelineConfig(run_dir=str(path), sut="blind-double", factory="tests.doubles:build", threshold=threshold)
    run_search(RunConfig(pipeline, algorithm="rs", pop_size=10, seed=3, budget_tests=budget))
    return path


@pytest.fixture(scope="module")
def failing_run(tmp_path_factory) -> Path:
    return _blind_run(tmp_path_factory.mktemp("runs") / "blind")


def _blind_fails(scene: dict) -> bool:
    """Whether the double's SUT errs on a scene (its two planted faults)."""
    return scene.get("external_light") == "LOW" or scene.get("luggage_position") == "PASSENGER"


def _dataset(out: Path, *extra: str) -> int:
    return main(["dataset", "--out", str(out), "--renderer-factory", DOUBLE, *extra])


def _rows(folder: Path, name: str = "metadata.jsonl") -> list[dict]:
    return [json.loads(line) for line in (folder / name).read_text().splitlines()]


# ---------------------------------------------------------------- the contract, rendered for real
def _style_photo(path: Path, flip: bool = False) -> Path:
    ramp = np.linspace(0, 255, 64, dtype=np.uint8)
    planes = [np.tile(ramp, (48, 1)), np.tile(ramp[::-1], (48, 1)), np.full((48, 64), 200 if flip else 90, np.uint8)]
    cv2.imwrite(str(path), np.dstack(planes))
    return path


def _fast_net(path: Path, style: Path) -> Path:
    """A fast style net in `stylize train`'s format for ``style`` (untrained: the wiring is what is tested)."""
    import hashlib

    from style_transfer.fast import save_model
    from style_transfer.fast_net import FastNetConfig, FastStyleNet

    meta = {"style": str(style), "style_sha256": hashlib.sha256(style.read_bytes()).hexdigest()}
    return save_model(FastStyleNet(FastNetConfig(width=8, blocks=1)), path, meta)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory) -> Path:
    """Three renders at a tiny preset, each with a Gatys copy (1 step at 32 px) and a fast-net copy."""
    root = tmp_path_factory.mktemp("dataset")
    gatys, fast = _style_photo(root / "gatys.png"), _style_photo(root / "fast.png", flip=True)
    settings = DatasetSettings(n=3, seed=2, preset=TINY, styles=(str(gatys), str(fast)),
                               style_models=(str(_fast_net(root / "fast.pt", fast)),), style_size=32, style_steps=1)
    build_dataset(settings, root / "ds")
    return root / "ds"


@pytest.mark.blender
def test_the_folder_follows_the_contract_and_the_image_folder_convention(rendered):
    info = json.loads((rendered / "dataset.json").read_text())
    assert info["complete"] and (info["space"], info["space_hash"]) == (SPACE.name, SPACE.hash)
    assert info["versions"]["renderer"].startswith("isu-blender") and info["seeds"]["scenes"] == 2
    assert info["counts"]["renders"] == 3 and info["counts"]["images"] == 9
    assert [style["method"] for style in info["styles"]] == ["gatys", "fast"]
    assert sum(info["counts"]["feature_values"]["driver_gender"].values()) == 3
    assert any("CC0" in entry["licence"] for entry in info["licences"])
    assert "## Licences" in (rendered / "DATASET_CARD.md").read_text()
    rows = _rows(rendered)
    # image-folder: metadata.jsonl at the root, file_name relative to it, exactly one row per image file
    on_disk = sorted(p.relative_to(rendered).as_posix() for p in rendered.rglob("*")
                     if p.suffix.lower() in IMAGE_SUFFIXES and not any(part.startswith(".") for part in p.parts))
    assert sorted(r["file_name"] for r in rows) == on_disk and len(on_disk) == 9
    for row in rows:
        scene = SPACE.check(row["scene"])
        assert row["truth"] == {q.key: q.truth for q in SPACE.questions(scene)}
        assert set(row["occluded"]) <= set(row["truth"]) and row["space_hash"] == SPACE.hash
    copies = [r for r in rows if r["variant"] != "render"]
    assert sorted(r["variant"] for r in copies) == ["style1"] * 3 + ["style2"] * 3
    for copy in copies:   # labels shared with the render it was made from
        render = next(r for r in rows if r["file_name"] == copy["source"])
        shared = ("scene", "truth", "occluded", "visibility")
        assert [copy[k] for k in shared] == [render[k] for k in shared]
        styled, original = (cv2.imread(str(rendered / r["file_name"])) for r in (copy, render))
        assert styled.shape == original.shape
        if copy["variant"] == "style1":   # Gatys moved the pixels (the untrained fast net starts as the identity)
            assert not np.array_equal(styled, original)


@pytest.mark.blender
@DECODING
def test_coco_masks_are_what_the_seg_channel_of_a_re_render_shows(rendered, tmp_path):
    from pycocotools.coco import COCO

    from isu_validate.render import open_renderer

    coco = COCO(str(rendered / "annotations.json"))
    names = {c["name"] for c in coco.loadCats(coco.getCatIds())}
    assert {"driver", "driver_face", "seat_belt", "phone", "luggage", "child_seat", "child",
            "phone_codriver_seat"} <= names
    for image in coco.loadImgs(coco.getImgIds()):
        covered = np.zeros((image["height"], image["width"]), int)
        for ann in coco.loadAnns(coco.getAnnIds(imgIds=[image["id"]])):
            mask = coco.annToMask(ann)
            ys, xs = np.nonzero(mask)
            assert ann["area"] == mask.sum() > 0
            assert ann["bbox"] == [xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
            covered += mask
        assert covered.max() == 1   # instances never overlap: one id per pixel
    first = coco.loadImgs([1])[0]
    row = next(r for r in _rows(rendered) if r["file_name"] == first["file_name"])
    with open_renderer(TINY, channels=("seg",), log_dir=tmp_path / "logs") as renderer:
        frame = renderer.render(row["scene"], tmp_path / "again.png")
    ids = cv2.imread(str(frame.channels["seg"]), cv2.IMREAD_UNCHANGED)
    anns = coco.loadAnns(coco.getAnnIds(imgIds=[1]))
    assert {a["category_id"] for a in anns} == {int(i) for i in np.unique(ids)} - {0}
    for ann in anns:
        assert np.array_equal(coco.annToMask(ann).astype(bool), ids == ann["category_id"])


@pytest.mark.blender
def test_each_vqa_chat_is_the_sut_prompt_then_an_answer_the_real_judge_scores_one(rendered):
    chats = _rows(rendered, "vqa.jsonl")
    metadata = {r["file_name"]: r for r in _rows(rendered)}
    assert [c["file_name"] for c in chats] == list(metadata)
    judge = make_judge("vqa", SPACE)
    for chat in chats:
        user, assistant = chat["messages"]
        assert (user["role"], assistant["role"]) == ("user", "assistant") and chat["images"] == [chat["file_name"]]
        row = metadata[chat["file_name"]]
        request = build_request(SPACE, row["scene"], rendered / chat["file_name"], "vqa")
        visible = [q for q in request.questions if q.key not in row["occluded"]]   # occluded: not asked, not taught
        assert user["content"] == [{"type": "text", "text": vqa_prompt(SPACE, visible)}, {"type": "image"}]
        answer = assistant["content"][0]["text"]
        response = interpret(request, Exchange(raw=answer, content=answer))
        verdict = judge.judge(row["scene"], request, response, occluded=row["occluded"])
        assert verdict.primary == 1.0 and not verdict.failed


# ---------------------------------------------------------------- focus
def test_focused_scenes_gather_near_the_failures_and_are_never_a_scene_of_the_run(failing_run):
    run = load_run(failing_run)
    rng = np.random.default_rng(0)
    focused = focus_scenes(SPACE, [failing_run], "failing", 60, rng)
    uniform = [SPACE.canonical(s) for s in SPACE.sample(np.random.default_rng(0), 60)]
    keys = [SPACE.key(f.scene) for f in focused]
    assert len(set(keys)) == 60 and not set(keys) & {t.scene_key for t in run.records}
    assert all(SPACE.is_valid(f.scene) for f in focused)
    canon = [SPACE.canonical(f.scene) for f in focused]
    share = np.mean([_blind_fails(s) for s in canon])
    assert share >= 0.85 and share > np.mean([_blind_fails(s) for s in uniform]) + 0.2
    failures = np.array([SPACE.canonical_vector(t.canonical) for t in run.failures])

    def nearest(scenes):
        return np.mean([SPACE.distances(SPACE.canonical_vector(s), failures).min() for s in scenes])
    assert nearest(canon) < 0.5 * nearest(uniform)
    regions = {r.name for r in focus_regions(SPACE, [run], "failing")}
    assert {f.region for f in focused} <= regions
    passing = focus_scenes(SPACE, [failing_run], "passing", 30, np.random.default_rng(1))
    assert np.mean([_blind_fails(SPACE.canonical(f.scene)) for f in passing]) < share - 0.3


def test_the_rules_report_prints_read_back_to_the_tests_they_cover(failing_run):
    run = load_run(failing_run)
    scenes, failed = [t.canonical for t in run.valid], [t.failed for t in run.valid]
    leaves = failure_regions(SPACE, scenes, failed)
    assert leaves
    for leaf in leaves:
        rule = parse_rule(SPACE, leaf["rule"])
        inside = [f for s, f in zip(scenes, failed) if rule.holds(s)]
        assert (len(inside), sum(inside)) == (leaf["tests"], leaf["failing"]), leaf["rule"]


def test_a_rule_by_hand_bounds_every_scene_and_bad_rules_say_what_is_wrong(failing_run, tmp_path):
    rule = "luggage_colour = YELLOW and external_light = HIGH"
    scenes = focus_scenes(SPACE, [failing_run], f"rule:{rule}", 20, np.random.default_rng(2))
    assert all(SPACE.canonical(f.scene).get("luggage_colour") == "YELLOW"
               and f.scene["external_light"] == "HIGH" for f in scenes)
    assert _dataset(tmp_path / "ds", "--n", "5", "--focus", "rule:luggage = YES") == 0   # no runs: inside the rule
    assert all(r["scene"]["luggage"] == "YES" for r in _rows(tmp_path / "ds"))
    numeric = parse_rule(SPACE, "luggage_orientation > 30 and <= 60 deg and child absent")
    assert numeric.holds({"luggage": "YES", "luggage_orientation": 60.0})
    assert not numeric.holds({"luggage": "YES", "luggage_orientation": 30.0})
    assert not numeric.holds({"luggage": "NO"}) and not numeric.holds({"child": "NO", "luggage_orientation": 40.0})
    for text, says in [("suitcase = YES", "unknown feature 'suitcase'"),
                       ("luggage_colour = PINK", "'PINK' is not a value of luggage_colour"),
                       ("external_light >= LOW", "cannot read external_light"),
                       ("seat_belt absent", "never absent"), ("luggage_orientation about 40", "cannot read")]:
        with pytest.raises(InputError, match=says):
            parse_rule(SPACE, text)


# ---------------------------------------------------------------- the command, with the renderer double
def test_a_focused_dataset_records_its_regions_and_replaces_unusable_frames(failing_run, tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_UNUSABLE_WITH_CAN", "1")
    assert _dataset(tmp_path / "ds", "--n", "12", "--from-run", str(failing_run)) == 0
    info = json.loads((tmp_path / "ds" / "dataset.json").read_text())
    assert info["focus"]["mode"] == "failing" and sum(r["scenes"] for r in info["focus"]["regions"]) == 12
    assert info["counts"]["renders"] == 12 and info["counts"]["skipped"] == len(info["skipped"]) > 0
    rows = _rows(tmp_path / "ds")
    assert len(rows) == 12 and all(r["scene"].get("colacan_codriver_seat") != "YES" for r in rows)
    assert not {r["scene_key"] for r in rows} & {t.scene_key for t in load_run(failing_run).records}
    assert "| region |" in (tmp_path / "ds" / "DATASET_CARD.md").read_text()


def test_a_training_row_never_teaches_an_answer_for_a_feature_the_frame_hides(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_HIDE_PHONE", "1")   # the double hides the phone in the driver's hand
    assert _dataset(tmp_path / "ds", "--n", "12", "--seed", "2") == 0
    metadata = {r["file_name"]: r for r in _rows(tmp_path / "ds")}
    judge = make_judge("vqa", SPACE)
    hidden = 0
    for chat in _rows(tmp_path / "ds", "vqa.jsonl"):
        row, (user, assistant) = metadata[chat["file_name"]], chat["messages"]
        answer = json.loads(assistant["content"][0]["text"])
        if row["scene"].get("phone_position", "NONE") != "NONE":
            hidden += 1
            assert "phone_position" in row["occluded"] and row["truth"]["phone_position"] == "YES"
            assert "phone_position" not in answer and "phone_position" not in user["content"][0]["text"]
        else:
            assert answer["phone_position"] == "NO"   # nothing to see is never occluded: still asked
        # what is asked is answered right: the real judge scores the row's answer 1.0
        request = build_request(SPACE, row["scene"], tmp_path / "ds" / chat["file_name"], "vqa")
        response = interpret(request, Exchange(raw=json.dumps(answer), content=answer))
        assert judge.judge(row["scene"], request, response, occluded=row["occluded"]).primary == 1.0
    assert hidden >= 3
    card = (tmp_path / "ds" / "DATASET_CARD.md").read_text()
    assert "left out of that row's questions and answer in `vqa.jsonl`" in card


def _cli(out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "isu_validate.cli", "dataset", "--out", str(out), "--n", "14", "--seed", "4",
            "--renderer-factory", DOUBLE, *extra]


def test_resume_after_a_kill_renders_no_image_twice_and_loses_none(tmp_path, capsys):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    assert _dataset(tmp_path / "whole", "--n", "14", "--seed", "4") == 0
    killed = tmp_path / "killed"
    proc = subprocess.Popen(_cli(killed), env=dict(env, ISU_TEST_RENDER_DELAY="0.3"), cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 60
    while time.time() < deadline and len(list((killed / "manifest").glob("*.json"))) < 5:
        time.sleep(0.1)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = {p.name: p.read_bytes() for p in (killed / "manifest").glob("*.json")}
    assert 5 <= len(before) < 14 and not (killed / "metadata.jsonl").exists()

    capsys.readouterr()
    assert _dataset(killed, "--resume", "--seed", "5") == 2   # other settings: refused, the difference named
    err = capsys.readouterr().err
    assert "seed: 4 (stored) vs 5 (given)" in err and len(err.strip().splitlines()) == 1
    resumed = subprocess.run([sys.executable, "-m", "isu_validate.cli", "dataset", "--out", str(killed), "--resume",
                              "--workers", "2"], env=env, cwd=ROOT, capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{14 - len(before)} rendered now" in resumed.stdout
    for name, content in before.items():   # kept as committed, not made again
        assert (killed / "manifest" / name).read_bytes() == content
    rows, whole = _rows(killed), _rows(tmp_path / "whole")
    assert [r["file_name"] for r in rows] == [r["file_name"] for r in whole]   # none twice, none lost
    assert [r["scene_key"] for r in rows] == [r["scene_key"] for r in whole]
    assert sorted(p.name for p in (killed / "images").iterdir()) == sorted(Path(r["file_name"]).name for r in rows)


# ---------------------------------------------------------------- bad input: one line, nothing written
@pytest.fixture(scope="module")
def passing_run(tmp_path_factory) -> Path:
    return _blind_run(tmp_path_factory.mktemp("runs") / "lenient", threshold=0.0, budget=10)


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, failing_run, passing_run):
    (tmp_path / "not-a-run").mkdir()
    broken = tmp_path / "style.png"
    broken.write_bytes(b"\x89PNG\r\n\x1a\n not really")
    cases = [
        (["--n", "0"], "--n must be at least 1"),
        (["--from-run", str(tmp_path / "not-a-run")], "is neither a run directory nor a folder of runs"),
        (["--from-run", str(passing_run)], "no failing test in"),
        (["--from-run", str(failing_run), "--focus", "worst"], "unknown --focus 'worst'"),
        (["--from-run", str(failing_run), "--focus", "rule:phone = P1"], "unknown feature 'phone'"),
        (["--focus", "failing"], "--focus failing needs --from-run"),
        (["--style", str(broken)], f"style image {broken} does not decode"),
        (["--preset", "ultra"], "unknown render preset 'ultra'"),
        (["--style", str(_style_photo(tmp_path / "a.png")), "--style-model",
          str(_fast_net(tmp_path / "b.pt", _style_photo(tmp_path / "b.png", flip=True)))],
         "was trained for another style image"),
    ]
    for flags, says in cases:
        out = tmp_path / "ds"
        assert _dataset(out, *flags) == 2, flags
        err = capsys.readouterr().err
        assert says in err and len(err.strip().splitlines()) == 1, (flags, err)
        assert not out.exists(), flags
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "notes.txt").write_text("mine")
    assert _dataset(tmp_path / "full", "--n", "2") == 2
    assert "not an empty folder" in capsys.readouterr().err and os.listdir(tmp_path / "full") == ["notes.txt"]
