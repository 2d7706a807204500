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
    # the paper's rules, word for word, then key/question/answer_options blocks and the JSON to return
    assert text.startswith("You are an image analysis assistant to evaluate in-cabin scenes.")
    for rule in ("- Return only the JSON.", "- Do not provide explanations.",
                 "- For each question, choose exactly one answer from the given `answer_options`.",
                 "- Do not create new answers, only choose from the provided options.",
                 '- If a question references something not present, select the provided "NONE".'):
        assert rule in text
    assert ('key: "driver_gender"\nquestion: "Is the driver male or female?"\n'
            'answer_options: ["MALE", "FEMALE"]') in text
    assert 'answer_options: ["FRONT_FACING", "REAR_FACING", "NONE"]' in text
    assert text.index("# Rules") < text.index("# Questions") < text.index("# Output")
    assert "luggage_colour" not in text and '"colabottle_codriver_seat": "..."' in text
    # the earlier wording, by name
    compact = build_request(space, SCENE, "x.png", "vqa", style="compact").prompt
    assert compact.startswith("You are an in-car scene understanding system") and "Answer NONE" in compact
    assert ('"child_seat_orientation": Is the baby seat front-facing or rear-facing? '
            'Options: FRONT_FACING, REAR_FACING, NONE') in compact and "Return JSON" in compact
    with pytest.raises(ValueError, match="unknown prompt style 'fancy'.*compact"):
        build_request(space, SCENE, "x.png", "vqa", style="fancy")
    custom = build_request(space, SCENE, "x.png", "vqa", prompt="Rules first.\n{questions}\nThanks.")
    assert custom.prompt.startswith("Rules first.\n# Questions") and custom.prompt.endswith("Thanks.")
    caption = build_request(space, SCENE, "x.png", "vc")
    assert caption.prompt.startswith("Describe what is visible in the scene") and caption.questions == ()
    with pytest.raises(ValueError, match="unknown SUT mode"):
        build_request(space, SCENE, "x.png", "detect")


@pytest.mark.parametrize("text, expected", [
    ('```json\n{"seat_belt": "YES", "child": "YES"}\n```', {"seat_belt": "YES", "child": "YES"}),
    ('Here you go: {"seat_belt": "yes", "child": "Yes"} Hope it helps!', {"seat_belt": "YES", "child": "YES"}),
    ("{'seat_belt': 'YES', 'driver_gender': 'male'}", {"seat_belt": "YES", "driver_gender": "MALE"}),
    ('{"seat_belt": true, "phone_codriver_seat": false}', {"seat_belt": "YES", "phone_codriver_seat": "NO"}),
    ("{seat_belt: YES, child_seat_orientation: rear-facing,}",
     {"seat_belt": "YES", "child_seat_orientation": "REAR_FACING"}),
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


def test_a_run_asks_in_its_prompt_style_and_resumes_in_it(tmp_path):
    import argparse

    from isu_validate.commands.run import add_run_options, config_from_args
    from isu_validate.pipeline import build_components
    from isu_validate.archive.run_file import ResumeMismatch, check_run_dir, write_run_file
    from isu_validate.commands.run import _mismatch_message
    from isu_validate.search import make_algorithm
    from isu_validate.search.loop import _run_file_content

    space = load_space()
    parser = argparse.ArgumentParser()
    add_run_options(parser)
    for argv, opening in ((["--out", str(tmp_path / "a")], "You are an image analysis assistant"),
                          (["--out", str(tmp_path / "b"), "--prompt-style", "compact"], "You are an in-car scene")):
        config = config_from_args(parser.parse_args(["--sut", "command:true"] + argv))
        parts = build_components(config.pipeline, space)   # the real renderer (not started), SUT and judge
        assert parts.build_request(space, SCENE, "x.png", "vqa", None).prompt.startswith(opening)
        # run.json, as a run writes it
        write_run_file(config.pipeline.run_dir, _run_file_content(config, space, config.identity(),
                                                                   make_algorithm("surrogate", space, 6, 0)))
    # resuming takes the style from run.json; another one is refused by name
    resumed = config_from_args(parser.parse_args(["--out", str(tmp_path / "b"), "--resume"]))
    assert resumed.pipeline.prompt_style == "compact"
    other = config_from_args(parser.parse_args(["--out", str(tmp_path / "b"), "--resume", "--prompt-style", "paper"]))
    with pytest.raises(ResumeMismatch) as refused:
        check_run_dir(tmp_path / "b", other.identity(), space.hash, {}, resume=True)
    assert "--prompt-style: 'compact' in the stored run, 'paper' now" in _mismatch_message(refused.value)
    with pytest.raises(SystemExit):
        parser.parse_args(["--prompt-style", "poetic"])
    vc = config_from_args(parser.parse_args(["--out", str(tmp_path / "c"), "--mode", "vc", "--sut", "command:true",
                                             "--caption-template", "isu-paper-compact"]))
    judge = build_components(vc.pipeline, space).judge
    assert judge.template == "isu-paper-compact"
