"""Captioning metrics against hand-computed values, the hard cases, the oracles, the reference caption."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

from isu_validate.evaluate import make_judge, reference_caption
from isu_validate.evaluate.captioning import caption_metrics
from isu_validate.evaluate.reference_caption import parse_template
from isu_validate.evaluate.similarity import bertscore, cosine, f_emb
from isu_validate.evaluate.text_metrics import bleu, meteor, tokens
from isu_validate.protocols import SUTResponse
from isu_validate.space import SpaceError, load_space
from isu_validate.sut import build_request

SCENE = {"driver_gender": "FEMALE", "driver_emotion": "HAPPY", "driver_height": "H1", "driver_weight": "W1",
         "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "YES", "child": "NO",
         "child_seat_orientation": "REAR_FACING", "car_lights": "OFF", "external_light": "HIGH", "luggage": "YES",
         "luggage_orientation": 90.0, "luggage_position": "BACK", "luggage_colour": "ANTHRACITE",
         "phone_codriver_seat": "NO", "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}
GOOD = ("A smiling woman in a white T-shirt drives with her seat belt on. An empty rear-facing child seat is on "
        "the passenger seat and a dark grey suitcase lies on the back seat.")


@pytest.fixture(scope="module")
def space():
    return load_space()


# ---------------------------------------------------------------- hand-computed values
def test_bleu_hand_computed():
    # p1 = p2 = p3 = 1, p4 = 0/1 -> epsilon 0.1 (method1); BP = exp(1 - 6/3)
    assert bleu("the cat sat", "the cat sat on the mat") == pytest.approx(math.exp(-1) * 0.1 ** 0.25, rel=1e-9)
    assert bleu("The cat sat on the mat.", "the cat sat on the mat") == pytest.approx(1.0)


def test_meteor_hand_computed():
    # identical 6 words: P = R = 1, one chunk: penalty 0.5 * (1/6)^3
    assert meteor("the cat sat on the mat", "the cat sat on the mat") == pytest.approx(1 - 0.5 / 216)
    # a WordNet synonym (auto ~ car): one match, one chunk -> 1 - 0.5 * 1^3
    assert meteor("auto", "car") == pytest.approx(0.5)
    assert meteor("zebra", "car") == 0.0


def test_cosine_hand_computed_and_zero_vectors():
    assert cosine(np.array([1.0, 0.0]), np.array([1.0, 1.0])) == pytest.approx(1 / math.sqrt(2))
    assert cosine(np.zeros(384), np.ones(384)) == 0.0
    assert cosine(np.zeros(3), np.zeros(3)) == 0.0
    assert cosine(np.array([np.inf, 1.0]), np.array([1.0, 1.0])) == 0.0


def test_embedding_matches_sentence_transformers():
    # Values computed with sentence-transformers 6.2 SentenceTransformer(all-MiniLM-L6-v2).encode.
    base = "A man in a black T-shirt sits in the car."
    assert f_emb(base, base) == pytest.approx(1.0, abs=1e-6)
    assert f_emb(base, "Ein Mann sitzt im Auto.") == pytest.approx(0.205845, abs=2e-5)
    assert f_emb(base, "A yellow suitcase lies on the back seat.") == pytest.approx(0.215631, abs=2e-5)


def test_bertscore_matches_torchmetrics_values():
    # torchmetrics 1.9 BERTScore(model_name_or_path=<MiniLM>, num_layers=6) on this pair:
    score = bertscore("a man in a car", "a male driver in a car")
    assert score["precision"] == pytest.approx(0.8486, abs=1e-4)
    assert score["recall"] == pytest.approx(0.7866, abs=1e-4)
    assert score["f1"] == pytest.approx(0.8164, abs=1e-4)
    assert bertscore("a man in a car", "a man in a car")["f1"] == pytest.approx(1.0, abs=1e-5)


# ---------------------------------------------------------------- hard cases
@pytest.mark.parametrize("caption", ["", "   \n\t "])
def test_empty_and_whitespace_captions_score_zero(space, caption):
    assert caption_metrics(caption, reference_caption(space, SCENE)) == {
        "f_emb": 0.0, "f_bleu": 0.0, "f_meteor": 0.0, "f_bert": 0.0}
    request = build_request(space, SCENE, "x.png", "vc")
    verdict = make_judge("vc", space).judge(SCENE, request, SUTResponse(caption=caption))
    assert verdict.failed and verdict.primary == 0.0 and "empty caption" in verdict.details["problems"][0]


def test_identical_strings(space):
    reference = reference_caption(space, SCENE)
    scores = caption_metrics(reference, reference)
    assert scores["f_emb"] == pytest.approx(1.0, abs=1e-6) and scores["f_bleu"] == pytest.approx(1.0)
    assert scores["f_bert"] == pytest.approx(1.0, abs=1e-5) and scores["f_meteor"] > 0.99


def test_other_language_scores_low_but_defined(space):
    german = ("Eine lächelnde Frau in einem weißen T-Shirt fährt angeschnallt. Ein leerer Kindersitz steht auf dem "
              "Beifahrersitz, ein grauer Koffer liegt auf der Rückbank.")
    ours, theirs = (caption_metrics(GOOD, reference_caption(space, SCENE)),
                    caption_metrics(german, reference_caption(space, SCENE)))
    assert theirs["f_meteor"] < 0.1 < ours["f_meteor"] and theirs["f_emb"] < ours["f_emb"]
    assert theirs["f_bleu"] < 0.05
    assert all(math.isfinite(v) for v in theirs.values())


def test_ten_thousand_word_caption(space):
    words = (GOOD + " ").split() * 400
    caption = " ".join(words[:10_000])
    request = build_request(space, SCENE, "x.png", "vc")
    start = time.perf_counter()
    verdict = make_judge("vc", space).judge(SCENE, request, SUTResponse(caption=caption))
    assert time.perf_counter() - start < 20
    assert verdict.details["truncated"] is True
    # the embedding sees the first 256 tokens only: the same as for the first 400 words
    assert verdict.fitness["f_emb"] == pytest.approx(f_emb(" ".join(words[:400]), reference_caption(space, SCENE)),
                                                     abs=1e-6)
    assert all(math.isfinite(v) for v in verdict.fitness.values())
    assert verdict.fitness["f_bleu"] < 0.05  # the brevity penalty does not reward length, precision collapses


def test_tokens_keep_words_drop_punctuation():
    assert tokens("The driver's seat-belt: ON!") == ["the", "driver's", "seat-belt", "on"]
    assert tokens("Fahrer trägt Gurt") == ["fahrer", "trägt", "gurt"]


# ---------------------------------------------------------------- judge and oracles
def test_caption_judge_and_oracles(space):
    request = build_request(space, SCENE, "x.png", "vc")
    good = make_judge("vc", space).judge(SCENE, request, SUTResponse(caption=GOOD))
    bad = make_judge("vc", space).judge(SCENE, request, SUTResponse(caption="A sunny beach with palm trees."))
    assert set(good.fitness) == {"f_emb", "f_bleu", "f_meteor", "f_bert"} and good.primary == good.fitness["f_emb"]
    assert good.primary > 0.65 and not good.failed
    assert bad.primary <= 0.65 and bad.failed
    assert good.details["threshold"] == 0.65 and "BLEU" in good.details["metrics"]["bleu"]
    # the conjunction fails only when every given metric is at or below its threshold
    strict = {"f_emb": 0.99, "f_bleu": 0.99, "f_meteor": 0.99, "f_bert": 0.99}
    assert make_judge("vc", space, oracle="conjunction", threshold=strict).judge(
        SCENE, request, SUTResponse(caption=GOOD)).failed
    loose = dict(strict, f_bert=0.1)
    assert not make_judge("vc", space, oracle="conjunction", threshold=loose).judge(
        SCENE, request, SUTResponse(caption=GOOD)).failed
    with pytest.raises(ValueError, match="threshold per metric"):
        make_judge("vc", space, oracle="conjunction")
    with pytest.raises(ValueError, match="unknown caption metric"):
        make_judge("vc", space, oracle="conjunction", threshold={"f_cider": 0.5})


def test_repeated_captions_are_averaged(space):
    request = build_request(space, SCENE, "x.png", "vc")
    captions = [GOOD, "A woman drives a car."]
    verdict = make_judge("vc", space).judge(SCENE, request, SUTResponse(caption=GOOD, extra={"captions": captions}))
    one = [caption_metrics(c, reference_caption(space, SCENE)) for c in captions]
    assert verdict.fitness["f_bleu"] == pytest.approx((one[0]["f_bleu"] + one[1]["f_bleu"]) / 2)
    assert (verdict.details["consistency"] == pytest.approx(f_emb(*captions))
            and len(verdict.details["per_caption"]) == 2)


def test_sut_error_is_not_a_failure(space):
    request = build_request(space, SCENE, "x.png", "vc")
    verdict = make_judge("vc", space).judge(SCENE, request, SUTResponse(error="HTTP 503"))
    assert verdict.fitness == {} and not verdict.failed and verdict.details["sut_error"] == "HTTP 503"


# ---------------------------------------------------------------- reference caption
def test_reference_caption_follows_the_papers_template_with_only_active_features(space):
    text = reference_caption(space, SCENE)
    assert text == ("The image is taken from inside a car parked outside in daylight. A happy female driver "
                    "wearing a white T-shirt is seated in the car. The driver is wearing a safety belt. An "
                    "anthracite suitcase is visible on the rear seat. An empty rear-facing baby seat is positioned "
                    "on the front passenger seat.")
    bare = dict(SCENE, child_seat="NO", luggage="NO", colacan_codriver_seat="YES", phone_position="P3",
                car_lights="ON", external_light="LOW")
    text = reference_caption(space, bare)  # latent luggage colour and child-seat values are still in the dict
    assert "suitcase" not in text and "anthracite" not in text and "baby" not in text
    assert "parked outside at night with the interior lights on." in text
    assert text.endswith("The driver is holding a phone in the hand. "
                         "A cola can is visible on the front passenger seat.")


def test_earlier_caption_wording_is_kept_by_name_and_a_wrong_template_is_named(space, tmp_path):
    text = reference_caption(space, dict(SCENE, child_seat="NO", phone_codriver_seat="YES"), "isu-paper-compact")
    assert text == ("The image shows the inside of a car in bright daylight. A female driver in a white T-shirt "
                    "looks happy and is wearing a seat belt. An anthracite suitcase lies on the back seat. "
                    "A mobile phone lies on the front passenger seat.")
    with pytest.raises(SpaceError, match="caption template 'isu-paper-fancy' not found.*isu-paper-compact"):
        make_judge("vc", space, template="isu-paper-fancy")
    other = tmp_path / "other.toml"
    other.write_text('space = "trucks"\n[[sentences]]\ntext = "A truck."\n')
    with pytest.raises(SpaceError, match="for space 'trucks', not for 'isu-paper'"):
        reference_caption(space, SCENE, other)


def test_template_errors_name_the_problem(space):
    with pytest.raises(SpaceError, match="unknown feature 'hat'"):
        parse_template({"sentences": [{"text": "A {hat}."}]}, space, "t.toml")
    with pytest.raises(SpaceError, match="no \\[\\[sentences\\]\\]"):
        parse_template({}, space, "t.toml")
