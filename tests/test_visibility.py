"""Per-feature visibility and unusable setups without Blender: the space's visible_parts and
min_visible, thresholds and run options, the judges leaving occluded features out, the frame checks,
an unregistered camera refused with the fix, and a whole run (test doubles) counting occluded
features apart in the archive, the export and the report."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest

from capture.camera import Camera, CameraFileError, load_camera, load_render_camera, write_toml
from isu_validate.archive.export import write_csv
from isu_validate.cli import main
from isu_validate.evaluate import make_judge
from isu_validate.pipeline import PipelineConfig
from isu_validate.protocols import SUTResponse
from isu_validate.render import open_renderer
from isu_validate.render.frame_check import BLACK_P99, frame_problem, frame_stats
from isu_validate.render.visibility import (DEFAULT_MIN_VISIBLE, feature_visibility, min_visible_for, needed_parts,
                                            parse_min_visible, part_shares)
from isu_validate.search import RunConfig, run_search
from isu_validate.space import SpaceError, load_space, space_from_dict
from isu_validate.sut import build_request

FACTORY = "tests.doubles:build"
SCENE = {"driver_gender": "FEMALE", "driver_emotion": "HAPPY", "driver_height": "H2", "driver_weight": "W2",
         "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "YES", "child": "NO",
         "child_seat_orientation": "FRONT_FACING", "car_lights": "OFF", "external_light": "MEDIUM",
         "luggage": "YES", "luggage_orientation": 60.0, "luggage_position": "BACK", "luggage_colour": "ANTHRACITE",
         "phone_codriver_seat": "NO", "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}


@pytest.fixture(scope="module")
def space():
    return load_space()


def _small_space(**luggage):
    return space_from_dict({"name": "tiny", "features": {
        "driver_gender": {"type": "categorical", "values": ["MALE", "FEMALE"], "predicted": True, "weight": 1.0,
                          "question": "Gender?", "visible_parts": ["driver_face"]},
        "luggage": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "weight": 1.0,
                    "question": "Luggage?", "options": ["YES", "NO"], **luggage},
        "seat_belt": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "weight": 2.0,
                      "question": "Belt?"}}})


# ------------------------------------------------------------------ the space file
def test_the_paper_space_names_a_render_part_for_every_predicted_feature(space):
    assert all(f.visible_parts for f in space.predicted)
    assert space.features["driver_gender"].visible_parts == ("driver_face",)
    assert space.features["luggage"].visible_parts == ("luggage",)
    assert "driver_face" in needed_parts(space) and "seat_belt" in needed_parts(space)
    again = space_from_dict(space.to_dict(), "round trip")   # run.json keeps them, so the space hash does too
    assert again.features["seat_belt"].visible_parts == ("seat_belt",) and again.hash == space.hash


@pytest.mark.parametrize("spec, problem", [
    ({"visible_parts": "luggage"}, "visible_parts must list"),
    ({"visible_parts": ["luggage"], "min_visible": 1.5}, r"min_visible must be a share in \[0, 1\]"),
    ({"min_visible": 0.3}, "min_visible needs visible_parts"),
])
def test_bad_visibility_keys_are_refused_naming_the_feature(spec, problem):
    with pytest.raises(SpaceError, match=f"'luggage'.*{problem}"):
        _small_space(**spec)


def test_an_unknown_part_and_visibility_on_an_unasked_feature_are_refused():
    with pytest.raises(SpaceError, match="visible part 'suitcase'.*parts: .*luggage"):
        needed_parts(_small_space(visible_parts=["suitcase"]))
    with pytest.raises(SpaceError, match="belong to predicted features"):
        space_from_dict({"features": {"x": {"type": "categorical", "values": ["A"], "visible_parts": ["driver"]}}})


def test_thresholds_default_space_and_run_overrides():
    small = _small_space(visible_parts=["luggage"], min_visible=0.4)
    assert min_visible_for(small) == {"driver_gender": DEFAULT_MIN_VISIBLE, "luggage": 0.4}
    assert min_visible_for(small, parse_min_visible(["0.1"])) == {"driver_gender": 0.1, "luggage": 0.1}
    assert min_visible_for(small, parse_min_visible(["0.1", "luggage=0.6"])) == {"driver_gender": 0.1, "luggage": 0.6}
    with pytest.raises(ValueError, match="'seat_belt', which is not a predicted feature with visible_parts"):
        min_visible_for(small, {"seat_belt": 0.5})
    with pytest.raises(ValueError, match=r"lie in \[0, 1\]"):
        min_visible_for(small, {"luggage": 2})
    with pytest.raises(ValueError, match="FEATURE=SHARE"):
        parse_min_visible(["luggage=lots"])


def test_visible_share_only_for_things_that_exist():
    small = _small_space(visible_parts=["luggage"])
    parts = part_shares({"driver_face": {"pixels": 30}, "luggage": {"pixels": 12}},
                        {"driver_face": 100, "luggage": 0, "seat_belt": 50})
    assert parts["luggage"] == {"pixels": 12, "footprint": 0, "share": 0.0}     # jitter beyond nothing: still 0
    assert parts["seat_belt"]["share"] == 0.0 and parts["driver_face"]["share"] == 0.3
    limits = min_visible_for(small)
    shares, hidden = feature_visibility(small, {"driver_gender": "MALE", "luggage": "YES", "seat_belt": "YES"},
                                        parts, limits)
    # a suitcase wholly outside the frame cannot be seen: share 0; the belt names no part: always judged
    assert shares == {"driver_gender": 0.3, "luggage": 0.0} and hidden == ["luggage"]
    shares, hidden = feature_visibility(small, {"driver_gender": "MALE", "luggage": "NO", "seat_belt": "NO"},
                                        parts, {**limits, "driver_gender": 0.31})
    assert shares == {"driver_gender": 0.3} and hidden == ["driver_gender"]   # NO: nothing to see, never hidden
    share_cap = part_shares({"luggage": {"pixels": 105}}, {"luggage": 100})
    assert share_cap["luggage"]["share"] == 1.0
    assert feature_visibility(small, {"driver_gender": "MALE", "luggage": "NO", "seat_belt": "NO"}, parts,
                              {"driver_gender": 0.0})[1] == []


# ------------------------------------------------------------------ the judges
def test_occluded_features_are_left_out_and_the_weights_renormalised(space):
    request = build_request(space, SCENE, "x.png", "vqa")
    truth = {q.key: q.truth for q in request.questions}
    judge = make_judge("vqa", space)
    wrong = dict(truth, luggage="NO", luggage_colour="YELLOW", driver_gender="MALE")
    hidden = ["luggage", "luggage_position", "luggage_colour"]
    plain = judge.judge(SCENE, request, SUTResponse(answers=wrong))
    verdict = judge.judge(SCENE, request, SUTResponse(answers=wrong), occluded=hidden)
    weights = {q.key: q.weight for q in request.questions}
    judged = sum(w for k, w in weights.items() if k not in hidden)
    assert verdict.primary == pytest.approx((judged - weights["driver_gender"]) / judged) and verdict.failed
    assert plain.primary < verdict.primary        # the hidden suitcase's mistakes cost nothing
    features = verdict.details["features"]
    assert features["luggage"] == {"status": "occluded", "answer": "NO", "truth": "YES", "weight": 0.1,
                                   "would_be": "wrong"}
    assert verdict.details["counts"]["occluded"] == 3 and verdict.details["counts"]["wrong"] == 1
    # hiding cannot help the search: a right answer about a hidden thing earns nothing either
    right = judge.judge(SCENE, request, SUTResponse(answers=dict(truth, driver_gender="MALE")), occluded=hidden)
    assert right.primary == pytest.approx(verdict.primary)


def test_everything_occluded_has_no_verdict(space):
    scene = {**SCENE, "child_seat": "NO", "luggage": "NO"}
    request = build_request(space, scene, "x.png", "vqa")
    every = [q.key for q in request.questions]
    verdict = make_judge("vqa", space).judge(scene, request, SUTResponse(answers={}), occluded=every)
    assert verdict.fitness == {} and not verdict.failed and "occluded" in verdict.details["no_verdict"]


def test_the_reference_caption_says_nothing_about_hidden_things(space):
    from isu_validate.evaluate import reference_caption
    full = reference_caption(space, SCENE)
    hidden = reference_caption(space, SCENE, hidden=["luggage", "luggage_position", "luggage_colour"])
    assert "suitcase" in full and "suitcase" not in hidden
    assert hidden.startswith("The image is taken from inside a car")


# ------------------------------------------------------------------ frames that cannot show the scene
def test_black_saturated_and_driverless_frames_are_named_with_the_fix():
    driver = {"driver": {"pixels": 900}}
    black = frame_stats(np.zeros((240, 320, 3), np.uint8))
    assert "black frame" in frame_problem(black, driver) and "camera rig's pose" in frame_problem(black, driver)
    assert "saturated frame" in frame_problem(frame_stats(np.full((240, 320, 3), 255, np.uint8)), driver)
    rng = np.random.default_rng(0)
    dim = rng.integers(0, 40, (240, 320, 3)).astype(np.uint8)   # dark, like LOW light with the lamps off
    assert frame_problem(frame_stats(dim), driver) is None
    assert "driver is not in the frame" in frame_problem(frame_stats(dim), {"cabin": {"pixels": 5}})
    assert frame_problem(frame_stats(dim), {"driver_face": {"pixels": 3}}) is None
    assert frame_stats(dim)["luma_p99"] > BLACK_P99


# ------------------------------------------------------------------ unregistered camera
@pytest.fixture()
def unregistered(tmp_path):
    """A calibrated camera file as `isu-validate calibrate` writes it before registration."""
    cam = Camera("lab-cam", "pinhole", 640, 480, np.array([300.0, 300.0, 319.5, 239.5]))
    return write_toml(cam, tmp_path / "lab-cam.toml")


def test_an_unregistered_pose_is_refused_with_the_fix(unregistered):
    assert not load_camera(unregistered).registered and load_camera("default").registered
    for refuse in (lambda: load_render_camera(unregistered), lambda: open_renderer("draft", unregistered)):
        with pytest.raises(CameraFileError, match="never registered") as err:
            refuse()
        assert "isu-validate calibrate register" in str(err.value) and "--extrinsics-from" in str(err.value)
    rig = load_render_camera(unregistered, extrinsics_from="default")
    default = load_camera("default")
    assert rig.position == default.position and rig.rotation == default.rotation and rig.fx == 300.0
    assert rig.pose_source == default.source and rig.hash != load_camera(unregistered).hash
    with pytest.raises(CameraFileError, match="--extrinsics-from rig's pose"):
        load_render_camera("default", extrinsics_from=unregistered)


def test_render_and_run_refuse_it_before_writing_anything(unregistered, tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    assert main(["render", str(scene), "--rig", str(unregistered), "--out", str(tmp_path / "img" / "x.png")]) == 2
    assert "calibrate register" in capsys.readouterr().err and not (tmp_path / "img").exists()
    out = tmp_path / "run"
    args = ["run", "--out", str(out), "--pipeline-factory", FACTORY, "--budget", "4", "--pop-size", "4",
            "--no-report", "--camera", str(unregistered)]
    assert main(args) == 2
    assert "--extrinsics-from RIG" in capsys.readouterr().err and not out.exists()
    assert main([*args[:-2], "--min-visible", "seat_belts=0.3"]) == 2
    assert "'seat_belts'" in capsys.readouterr().err and not out.exists()
    assert main([*args, "--extrinsics-from", "default", "--min-visible", "luggage=0.4"]) == 0
    pipeline = json.loads((out / "run.json").read_text())["config"]["pipeline"]
    assert pipeline["extrinsics_from"] == "default" and pipeline["min_visible"] == {"luggage": 0.4}
    capsys.readouterr()
    assert main(["run", "--out", str(out), "--resume", "--min-visible", "luggage=0.5"]) == 2   # measures otherwise
    assert "--min-visible luggage: 0.4 in the stored run, 0.5 now" in capsys.readouterr().err


# ------------------------------------------------------------------ a whole run with occlusion (doubles)
def test_a_run_counts_occluded_features_apart_everywhere(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_OCCLUDE", "1")   # the double hides a suitcase behind a child seat
    run_dir = tmp_path / "run"
    pipeline = PipelineConfig(run_dir=str(run_dir), sut="blind-double", factory=FACTORY)
    run_search(RunConfig(pipeline=pipeline, algorithm="rs", pop_size=10, seed=3, budget_tests=40))
    from isu_validate.analysis.runs import load_run
    run = load_run(run_dir)
    hidden = [r for r in run.records if r.occluded]
    assert hidden and all(set(r.occluded) <= {"luggage", "luggage_position", "luggage_colour"} for r in hidden)
    for r in hidden:   # the double always calls the suitcase YELLOW: never held against a hidden one
        label = json.loads((run_dir / "labels" / f"{r.test_id}.json").read_text())
        assert label["occluded"] == r.occluded and label["visibility"]["luggage"] == 0.05
        asked = [k for k in run.truth(r) if k not in r.occluded]
        weights = {f.name: f.weight for f in run.space.predicted}
        right = sum(weights[k] for k in asked if r.answers.get(k) == run.truth(r)[k])
        assert r.primary == pytest.approx(right / sum(weights[k] for k in asked))
    out = io.StringIO()
    write_csv(run_dir, out)
    rows = {row["test_id"]: row for row in csv.DictReader(io.StringIO(out.getvalue()))}
    for r in run.records:
        assert rows[r.test_id]["occluded"] == ";".join(r.occluded)
        assert rows[r.test_id]["visible.luggage"] == (str(r.visibility["luggage"]) if "luggage" in r.visibility else "")
    from isu_validate.analysis.failures import feature_errors
    from isu_validate.analysis.rq1 import run_rates
    per_feature = {row["feature"]: row for row in feature_errors([run])[0]}
    luggage_hidden = sum("luggage_colour" in r.occluded for r in run.valid)
    assert per_feature["luggage_colour"]["occluded"] == luggage_hidden
    assert run_rates(run)["occluded"] == sum(len(r.occluded) for r in run.valid)
    from isu_validate.analysis import write_run_report
    html = Path(write_run_report(run_dir)).read_text()
    assert "occluded features (not judged)" in html


def test_a_scene_with_everything_hidden_has_no_verdict_and_the_sut_is_not_asked(tmp_path, monkeypatch):
    monkeypatch.setenv("ISU_TEST_OCCLUDE", "all")
    run_dir = tmp_path / "run"
    pipeline = PipelineConfig(run_dir=str(run_dir), sut="blind-double", factory=FACTORY)
    summary = run_search(RunConfig(pipeline=pipeline, algorithm="rs", pop_size=4, seed=3, budget_tests=4))
    from isu_validate.analysis.runs import load_run
    run = load_run(run_dir)
    assert summary.errors == 4 and summary.failures == 0 and len(run.render_errors) == 4
    for r in run.records:
        assert "every feature asked about is occluded" in r.render_error
        assert r.sut_raw is None and r.answers is None and not r.failed and r.image


@pytest.mark.parametrize("mode", ["vqa", "vc"])
def test_the_run_and_the_judges_agree_on_a_scene_with_everything_hidden(tmp_path, monkeypatch, mode):
    """The pipeline (no verdict, SUT not asked, counted apart as an unusable frame) and a judge asked
    about the same scene anyway (pins, agree) must give the same answer: no verdict, never a failure."""
    monkeypatch.setenv("ISU_TEST_OCCLUDE", "all")
    run_dir = tmp_path / "run"
    pipeline = PipelineConfig(run_dir=str(run_dir), sut="blind-double", factory=FACTORY, mode=mode)
    run_search(RunConfig(pipeline=pipeline, algorithm="rs", pop_size=3, seed=5, budget_tests=3))
    from isu_validate.analysis.runs import load_run
    run = load_run(run_dir)
    judge = make_judge(mode, run.space)
    for r in run.records:
        request = build_request(run.space, r.canonical, run_dir / r.image, mode)
        anyway = SUTResponse(answers={q.key: q.truth for q in request.questions}, caption="A driver.")
        verdict = judge.judge(r.canonical, request, anyway, occluded=r.occluded)
        assert r.primary is None and not r.failed and r.render_error
        assert verdict.fitness == {} and not verdict.failed and verdict.details["no_verdict"] == r.render_error
