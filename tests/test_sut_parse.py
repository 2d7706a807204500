"""Reading real VLM output: the hard cases, and the prompt built from the space."""
from __future__ import annotations

import pytest

from isu_validate.space import load_space
from isu_validate.sut import build_request
from isu_validate.sut.parse import normalise_answer, parse_caption, parse_vqa

SCENE = {"driver_gender": "MALE", "driver_emotion": "HAPPY", "driver_height": "H1", "driver_weight": "W1",
         "phone_position": "P3", "seat_belt": "YES", "tshirt_colour": "BLACK", "child_seat": "YES", "child": "YES",
         "child_seat_orientation": "REAR_FACING", "car_lights": "ON", "external_light": "LOW", "luggage": "NO",
         "phone_codriver_seat": "NO", "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}


@pytest.fixture(scope="module")
def questions():
    return load_space().questions(SCENE)


def test_prompt_asks_only_active_features_in_figure_2_style():
    space = load_space()
    request = build_request(space, SCENE, "x.png", "vqa")
    assert [q.key for q in request.questions] == [q.key for q in space.questions(SCENE)]
    text = request.prompt
    assert text.startswith(space.prompt_rules[0]) and "Answer NONE" in text
    assert ('"child_seat_orientation": Is the baby seat front-facing or rear-facing? '
            'Options: FRONT_FACING, REAR_FACING, NONE') in text
    assert "luggage_colour" not in text and "REAR_FACING" in text and "Return JSON" in text
    custom = build_request(space, SCENE, "x.png", "vqa", prompt="Rules first.\n{questions}\nThanks.")
    assert custom.prompt.startswith("Rules first.\nQuestions") and custom.prompt.endswith("Thanks.")
    caption = build_request(space, SCENE, "x.png", "vc")
    assert caption.prompt.startswith("Describe what is visible in the scene") and caption.questions == ()
    with pytest.raises(ValueError, match="unknown SUT mode"):
        build_request(space, SCENE, "x.png", "detect")


@pytest.mark.parametrize("text, expected", [
    ('```json\n{"seat_belt": "YES", "child": "YES"}\n```', {"seat_belt": "YES", "child": "YES"}),
    ('Here you go: {"seat_belt": "yes", "child": "Yes"} Hope it helps!', {"seat_belt": "YES", "child": "YES"}),
    ("{'seat_belt': 'YES', 'driver_gender': 'male'}", {"seat_belt": "YES", "driver_gender": "MALE"}),
    ('{"seat_belt": true, "phone_codriver_seat": false}', {"seat_belt": "YES", "phone_codriver_seat": "NO"}),
    ("{seat_belt: YES, child_seat_orientation: rear-facing,}", {"seat_belt": "YES", "child_seat_orientation": "REAR_FACING"}),
    ('{"Seat Belt": "Yes.", "Is the driver male or female?": "Male"}', {"seat_belt": "YES", "driver_gender": "MALE"}),
    ('{"answers": {"seat_belt": "NO"}}', {"seat_belt": "NO"}),
    ('{"seat_belt": {"answer": "YES", "confidence": 0.8}}', {"seat_belt": "YES"}),
    ('seat_belt: NO\ndriver_gender: FEMALE', {"seat_belt": "NO", "driver_gender": "FEMALE"}),
    ('{"seat_belt": "Yes, clearly buckled"}', {"seat_belt": "YES"}),
    ('draft {"seat_belt": "NO"} final answer {"seat_belt": "YES", "child": "NO"}', {"seat_belt": "YES", "child": "NO"}),
    ('The driver\'s belt: {"seat_belt": "YES"}', {"seat_belt": "YES"}),
])
def test_tolerant_but_unambiguous(text, expected, questions):
    parsed = parse_vqa(text, questions)
    assert parsed.error is None
    assert parsed.answers == expected
    assert parsed.outcome == "partial"  # the other questions are missing
    missing = {q.key for q in questions} - set(expected)
    assert all(parsed.status[k] == "missing" for k in missing)


def test_every_question_answered_is_answered(questions):
    parsed = parse_vqa({q.key: q.truth for q in questions}, questions)
    assert parsed.outcome == "answered" and not parsed.problems


@pytest.mark.parametrize("value, options, expected", [
    ("GREY", ("YELLOW", "ANTHRACITE", "NONE"), None),          # invented option
    ("maybe", ("YES", "NO", "NONE"), None),
    ("No, there is none", ("YES", "NO", "NONE"), None),         # ambiguous: NO and NONE
    ("N/A", ("YES", "NO"), None),                               # NONE is no option here
    ("N/A", ("YES", "NO", "NONE"), "NONE"),
    (None, ("YES", "NO", "NONE"), "NONE"),
    (None, ("YES", "NO"), None),
    (True, ("MALE", "FEMALE"), None),
    (["YES", "NO"], ("YES", "NO"), None),
    (["yes"], ("YES", "NO"), "YES"),
    (1, ("YES", "NO"), None),
    ("", ("YES", "NO"), None),
    ("front facing", ("FRONT_FACING", "REAR_FACING", "NONE"), "FRONT_FACING"),
    ("FEMALE", ("MALE", "FEMALE", "NONE"), "FEMALE"),           # not confused with MALE
    ("y", ("YES", "NO"), "YES"),
])
def test_answer_normalisation(value, options, expected):
    assert normalise_answer(value, options)[0] == expected


def test_invalid_missing_and_conflicting_are_classified(questions):
    parsed = parse_vqa('{"seat_belt": "MAYBE", "child": "YES", "child": "NO", "driver_gender": "MALE"}', questions)
    assert parsed.status["seat_belt"] == "invalid" and parsed.status["child"] == "invalid"
    assert parsed.status["driver_gender"] == "answered" and parsed.status["phone_codriver_seat"] == "missing"
    assert any(p.startswith("seat_belt: invalid") and "MAYBE" in p for p in parsed.problems)
    assert any("conflicting" in p for p in parsed.problems)


def test_inactive_feature_answers_are_ignored(questions):
    parsed = parse_vqa('{"seat_belt": "YES", "luggage_colour": "YELLOW", "luggage_position": "BACK"}', questions)
    assert "luggage_colour" not in parsed.answers and parsed.ignored_keys == ["luggage_colour", "luggage_position"]


@pytest.mark.parametrize("text", [
    "I'm sorry, I can't help with that.",
    "",
    '{"foo": "bar"}',
    "```json\n{broken",
])
def test_unparseable_is_a_sut_error(text, questions):
    parsed = parse_vqa(text, questions)
    assert parsed.outcome == "error" and parsed.error.startswith("unparseable") and not parsed.answers


def test_captions():
    assert parse_caption("  A man drives.  ").caption == "A man drives."
    assert parse_caption('{"caption": "A woman."}').caption == "A woman."
    assert parse_caption({"caption": "A child."}).caption == "A child."
    assert parse_caption("```\nA car cabin.\n```").caption == "A car cabin."
    assert parse_caption("   \n").error.startswith("empty caption")
    assert parse_caption({"text": "x"}).error.startswith("unparseable")


def test_huge_and_pathological_replies_stay_fast(questions):
    import time
    for text in ["word " * 200_000, "{a:" + " " * 50_000 + "x", "{" * 20_000 + "}" * 20_000,
                 '{"seat_belt": "YES"}' + " filler" * 100_000]:
        start = time.perf_counter()
        parse_vqa(text, questions)
        assert time.perf_counter() - start < 3.0
