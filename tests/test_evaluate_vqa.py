"""VQA fitness: weighted exact match over the active predicted features, hand-computed."""
from __future__ import annotations

import pytest

from isu_validate.evaluate import FAILURE_THRESHOLDS, make_judge
from isu_validate.protocols import SUTResponse
from isu_validate.space import load_space, space_from_dict
from isu_validate.sut import build_request

# Active predicted features and Table 3 weights for this scene (child seat and luggage absent):
# driver_gender .05, driver_emotion .05, phone_position .1, seat_belt .1, tshirt_colour 0 (not in Table 3),
# child_seat .1, luggage .1, phone_codriver_seat .1, colacan_codriver_seat .05,
# colabottle_codriver_seat .05  -> total 0.70
SCENE = {"driver_gender": "MALE", "driver_emotion": "HAPPY", "driver_height": "H1", "driver_weight": "W1",
         "phone_position": "P2", "seat_belt": "YES", "tshirt_colour": "BLACK", "child_seat": "NO",
         "car_lights": "ON", "external_light": "LOW", "luggage": "NO", "phone_codriver_seat": "YES",
         "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}
TRUTH = {"driver_gender": "MALE", "driver_emotion": "HAPPY", "phone_position": "YES", "seat_belt": "YES",
         "tshirt_colour": "BLACK", "child_seat": "NO", "luggage": "NO", "phone_codriver_seat": "YES",
         "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}


@pytest.fixture(scope="module")
def space():
    return load_space()


def judge_answers(space, answers, threshold=None, **extra):
    request = build_request(space, SCENE, "x.png", "vqa")
    return make_judge("vqa", space, threshold=threshold).judge(SCENE, request,
                                                               SUTResponse(answers=answers, extra=extra))


def test_all_correct_is_one(space):
    verdict = judge_answers(space, dict(TRUTH))
    assert verdict.fitness == {"f_qa": pytest.approx(1.0)} and verdict.primary == pytest.approx(1.0)
    assert not verdict.failed


def test_weighted_mistakes_normalised_by_active_weights(space):
    answers = dict(TRUTH, seat_belt="NO", colacan_codriver_seat="YES")   # wrong: 0.1 + 0.05
    del answers["tshirt_colour"]                            # missing: 0 (not weighed)
    answers["driver_gender"] = "BOY"                         # invalid: 0.05
    verdict = judge_answers(space, answers)
    assert verdict.primary == pytest.approx((0.70 - 0.20) / 0.70)   # 0.714285...
    assert verdict.failed
    features = verdict.details["features"]
    assert features["seat_belt"]["status"] == "wrong" and features["tshirt_colour"]["status"] == "missing"
    assert features["driver_gender"]["status"] == "invalid" and features["luggage"]["status"] == "correct"
    assert verdict.details["counts"] == {"correct": 6, "wrong": 2, "missing": 1, "invalid": 1, "occluded": 0}


def test_thresholds(space):
    answers = dict(TRUTH, colabottle_codriver_seat="YES")    # 0.65/0.70 = 0.929
    assert judge_answers(space, answers).failed
    assert not judge_answers(space, answers, threshold=0.9).failed
    # a feature Table 3 does not weigh is judged and reported, but fails nothing
    shirt = judge_answers(space, dict(TRUTH, tshirt_colour="WHITE"))
    assert shirt.primary == pytest.approx(1.0) and not shirt.failed
    assert shirt.details["features"]["tshirt_colour"]["status"] == "wrong"
    assert FAILURE_THRESHOLDS["vqa"] == [1.0, 0.9, 0.8, 0.7, 0.6, 0.5]


def test_answers_for_inactive_features_are_ignored(space):
    answers = dict(TRUTH, luggage_colour="YELLOW", child="YES", child_seat_orientation="FRONT_FACING")
    verdict = judge_answers(space, answers)
    assert verdict.primary == pytest.approx(1.0)
    assert verdict.details["ignored"] == ["child", "child_seat_orientation", "luggage_colour"]
    assert "luggage_colour" not in verdict.details["features"]


def test_parser_invalid_status_is_kept(space):
    answers = dict(TRUTH)
    del answers["seat_belt"]
    verdict = judge_answers(space, answers, status={"seat_belt": "invalid"})
    assert verdict.details["features"]["seat_belt"]["status"] == "invalid"


def test_sut_error_is_not_a_failure(space):
    request = build_request(space, SCENE, "x.png", "vqa")
    verdict = make_judge("vqa", space).judge(SCENE, request, SUTResponse(error="timed out after 60 s"))
    assert verdict.fitness == {} and verdict.failed is False and verdict.details["sut_error"] == "timed out after 60 s"


def test_zero_weights_and_no_questions():
    space = space_from_dict({"name": "tiny", "features": {
        "a": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "weight": 0, "question": "A?"},
        "b": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "weight": 0, "question": "B?"},
        "c": {"type": "categorical", "values": ["X", "Y"]}}})
    scene = {"a": "YES", "b": "NO", "c": "X"}
    request = build_request(space, scene, "x.png", "vqa")
    verdict = make_judge("vqa", space).judge(scene, request, SUTResponse(answers={"a": "YES", "b": "YES"}))
    assert verdict.primary == pytest.approx(0.5) and "unweighted" in verdict.details["weighting"]
    bare = space_from_dict({"name": "bare", "features": {"c": {"type": "categorical", "values": ["X"]}}})
    verdict = make_judge("vqa", bare).judge({"c": "X"}, build_request(bare, {"c": "X"}, "x.png", "vqa"),
                                            SUTResponse(answers={}))
    assert verdict.primary == 1.0 and not verdict.failed


def test_bad_judge_configuration():
    space = load_space()
    with pytest.raises(ValueError, match="unknown mode"):
        make_judge("detect", space)
    with pytest.raises(ValueError, match="VQA oracle"):
        make_judge("vqa", space, oracle="conjunction")
