"""``reference train --windows``: a yes/no feature read from the most positive window of the frame, trained where
the render labels box the feature's part (painted images and labels here, no Blender)."""
import copy
import json
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from isu_validate.errors import InputError
from isu_validate.reference.backbone import Backbone
from isu_validate.reference.feature_bank import load_feature_set
from isu_validate.reference.heads import fit_head, load_heads, load_window_heads, save_heads
from isu_validate.reference.model import ReferenceISU
from isu_validate.reference.retrain import retrain_with_extra
from isu_validate.reference.stacking import Stacking
from isu_validate.reference.training import accuracy
from isu_validate.reference.windows import (
    CELL_PX, NEGATIVES, WindowSettings, frame_probabilities, part_box, training_windows)
from isu_validate.render import RENDERER_VERSION
from isu_validate.render.outputs import channel_paths
from isu_validate.space import load_space
from tests.test_reference import train_painted

SPACE = load_space()
SMALL = WindowSettings(("phone_position",), height=192)   # the painted frames are 160x120


class PhonePainter:
    """Stands in for the renderer: a phone (a dark slab with a lit screen) somewhere in a cluttered frame when the
    scene has one, its box in the label beside the image as a render's label has it; a grey slab of the same size
    elsewhere in every frame, so that only what is in the phone's place tells the answer."""

    def render(self, scene, out: Path):
        rng = np.random.default_rng(abs(hash(json.dumps(scene, sort_keys=True))) % 2**32)
        img = rng.integers(60, 120, (120, 160, 3)).astype(np.uint8)
        x, y = int(rng.integers(5, 130)), int(rng.integers(5, 80))
        cv2.rectangle(img, (x, y), (x + 16, y + 28), (150, 150, 150), -1)   # the decoy
        visible = {}
        if scene["phone_position"] != "NONE":
            x, y = int(rng.integers(5, 135)), int(rng.integers(5, 85))
            cv2.rectangle(img, (x, y), (x + 16, y + 28), (20, 20, 20), -1)
            cv2.rectangle(img, (x + 3, y + 3), (x + 13, y + 22), (255, 230, 120), -1)
            visible["phone"] = {"id": 8, "pixels": 17 * 29, "bbox": [x, y, x + 16, y + 28]}
        cv2.imwrite(str(out), img)
        channel_paths(out)["label"].write_text(json.dumps({"visible": visible, "occluded": []}))


@pytest.fixture(scope="module")
def windowed(tmp_path_factory):
    return train_painted(tmp_path_factory, "windows", PhonePainter(), 30, 16, windows=SMALL)


def test_window_heads_answer_their_feature_and_the_card_keeps_the_whole_frame_figure(windowed):
    folder, card = windowed
    model = folder / "model"
    meta = json.loads((model / "heads.json").read_text())
    assert {k: meta["windows"][k] for k in ("features", "height", "cells")} == {
        "features": ["phone_position"], "height": 192, "cells": 3}
    slope, _ = meta["windows"]["calibration"]["phone_position"]
    assert slope > 0     # a more phone-like best window means a phone more likely
    assert list(meta["window_heads"]) == ["phone_position"] and "phone_position" in meta["heads"]
    assert card["windows"]["training_windows"]["phone_position"]["YES"] > 0
    whole = card["windows"]["whole_frame_held_out"]["phone_position"]["accuracy"]
    windows = card["held_out"]["per_feature"]["phone_position"]["accuracy"]
    assert windows >= 0.9
    # the whole-frame head's figure kept beside the window head's: its own accuracy on the stored held-out features
    held_out = load_feature_set(model / "held_out_features.npz")
    own = accuracy(SPACE, load_heads(model)[0], held_out.features, held_out.scenes)["per_feature"]["phone_position"]
    assert whole == pytest.approx(own["accuracy"])
    text = (model / "MODEL_CARD.md").read_text()
    assert "--windows phone_position" in text and "Window heads: `phone_position`" in text
    # calibrated out of fold, as the card says (one viewpoint: five folds by frame)
    assert meta["windows"]["calibration_folds"] == card["windows"]["calibration_folds"] == "5 by frame"
    assert "calibrated on the training renders' log-odds out of fold (folds 5 by frame)" in text
    # the model as a SUT answers from the windows: P(YES) is the most positive window's
    reader = ReferenceISU(SPACE, model)
    images = sorted((folder / "work" / "held-out").glob("*.png"))
    scenes = [json.loads(p.with_suffix(".json").read_text())["scene"] for p in images]
    said = [reader.read(p)[1]["phone_position"]["YES"] for p in images]
    truth = [s["phone_position"] != "NONE" for s in scenes]
    assert np.mean([(p >= 0.5) == t for p, t in zip(said, truth)]) == pytest.approx(windows)


def test_a_model_with_window_heads_cannot_be_retrained_with_extra_data(windowed, tmp_path):
    folder, _ = windowed
    with pytest.raises(InputError, match="window heads, which --extra cannot retrain"):
        retrain_with_extra(SPACE, folder / "model", [], tmp_path / "out", RENDERER_VERSION,
                           backbone=Backbone(160, 120, threads=2))


def test_training_windows_centre_on_the_part_and_negatives_stay_clear_of_it():
    rows, cols, cells = 8, 10, 3
    maps = np.arange(rows * cols, dtype=np.float32).reshape(rows, cols, 1)   # a window's value names its place
    box = (4 * CELL_PX, 3 * CELL_PX, 5 * CELL_PX, 4 * CELL_PX)                   # centre at cell (4.5, 3.5)
    X, y = training_windows(maps, "YES", box, cells, np.random.default_rng(0))
    places = [(int(v[0]) // cols, int(v[0]) % cols) for v, answer in zip(X, y) if answer == "YES"]
    assert places and all(abs(i + 1.5 - 4.5) <= 1 and abs(j + 1.5 - 3.5) <= 1 for j, i in places)
    for v, answer in zip(X, y):
        j, i = divmod(int(v[0]), cols)
        if answer == "NO":   # no part of the box inside a negative window
            assert (i + cells) * CELL_PX <= box[0] or i * CELL_PX >= box[2] or (j + cells) * CELL_PX <= box[1] \
                or j * CELL_PX >= box[3]
    assert training_windows(maps, "YES", None, cells, np.random.default_rng(0)) == ([], [])   # no place to learn
    X, y = training_windows(maps, "NO", None, cells, np.random.default_rng(0))
    assert y == ["NO"] * NEGATIVES


def test_part_boxes_are_joined_scaled_and_absent_when_the_label_has_none():
    label = {"visible": {"phone": {"bbox": [10, 20, 19, 39]}, "hand": {"bbox": [0, 30, 14, 49]}}}
    assert part_box(label, ["phone"], 2.0) == (20.0, 40.0, 40.0, 80.0)   # inclusive pixel box, scaled
    assert part_box(label, ["phone", "hand"], 1.0) == (0.0, 20.0, 20.0, 50.0)
    assert part_box(label, ["seat_belt"], 1.0) is None and part_box({}, ["phone"], 1.0) is None


def test_a_frame_reads_as_its_most_positive_window():
    X = np.array([[0.0], [0.1], [0.9], [1.0]] * 5)
    head = fit_head("phone_position", X, ["NO", "NO", "YES", "YES"] * 5)
    maps = np.array([[[0.0], [0.05]], [[0.95], [0.1]]])
    alone = {"phone_position": Stacking(1.0, 0.0, 0.0)}     # no calibration
    p = frame_probabilities([head], alone, maps)["phone_position"]
    best = head.probabilities(np.array([[0.95]]))[0, head.classes.index("YES")]
    assert p["YES"] == pytest.approx(best) and p["NO"] == pytest.approx(1 - best) and p["YES"] > 0.5
    # a calibration that asks for more than one good window: the same best window reads as less sure
    stricter = frame_probabilities([head], {"phone_position": Stacking(1.0, 0.0, -2.0)}, maps)["phone_position"]["YES"]
    assert stricter == pytest.approx(1 / (1 + np.exp(-(np.log(best / (1 - best)) - 2.0))), abs=1e-6)
    # a window the head is sure of stays finite through the log-odds
    sure = frame_probabilities([head], {"phone_position": Stacking(1.0, 0.0, 0.0)}, np.full((1, 1, 1), 1e6))
    assert 0.5 < sure["phone_position"]["YES"] <= 1.0


def test_window_heads_round_trip_beside_the_whole_frame_heads(tmp_path):
    X = np.random.default_rng(0).normal(size=(20, 4))
    y = ["YES" if v > 0 else "NO" for v in X[:, 0]]
    whole, window = fit_head("phone_position", X, y), fit_head("phone_position", -X, y)
    save_heads([whole], tmp_path, {"backbone": "b"}, [window])
    heads, meta = load_heads(tmp_path)
    loaded = load_window_heads(tmp_path, meta)
    assert [h.feature for h in heads] == ["phone_position"] and len(loaded) == 1
    assert np.allclose(loaded[0].weight, window.weight, atol=1e-6) and np.allclose(heads[0].weight, whole.weight,
                                                                                  atol=1e-6)
    save_heads([whole], tmp_path, {"backbone": "b"})
    assert load_window_heads(tmp_path, load_heads(tmp_path)[1]) == []   # a model without windows


@pytest.mark.parametrize("text, message", [
    ("", "name the yes/no features"),
    ("no_such_feature", "no predicted feature 'no_such_feature'"),
    ("tshirt_colour", "answers a yes/no question"),
    ("driver_gender", "answers a yes/no question"),
])
def test_window_settings_are_checked_against_the_space(text, message):
    with pytest.raises(InputError, match=message):
        WindowSettings.parse(text, SPACE)


def test_window_settings_parse_and_a_feature_no_render_part_shows_is_refused():
    assert WindowSettings.parse(None, SPACE) is None
    assert WindowSettings.parse("phone_position, seat_belt,phone_position", SPACE).features == (
        "phone_position", "seat_belt")
    partless = copy.copy(SPACE)
    partless.features = {**SPACE.features, "seat_belt": replace(SPACE.features["seat_belt"], visible_parts=())}
    with pytest.raises(InputError, match="no render part"):
        WindowSettings.parse("seat_belt", partless)


def test_transfer_sets_the_window_heads_own_held_out_answers_beside_the_photos(windowed):
    from isu_validate.transfer.renders import held_out_records
    folder, card = windowed
    records, about = held_out_records(folder / "model", SPACE, ["phone_position", "tshirt_colour"])
    phone = [r for r in records if "phone_position" in r["truth"]]
    right = np.mean([r["said"]["phone_position"] == r["truth"]["phone_position"] for r in phone])
    assert right == pytest.approx(card["held_out"]["per_feature"]["phone_position"]["accuracy"])
    assert len(phone) == card["held_out"]["per_feature"]["phone_position"]["n"]
    (folder / "model" / "held_out_windows.json").rename(folder / "moved.json")
    try:
        with pytest.raises(InputError, match="copy the model folder whole"):
            held_out_records(folder / "model", SPACE, ["phone_position"])
    finally:
        (folder / "moved.json").rename(folder / "model" / "held_out_windows.json")


def test_window_maps_keep_the_frame_aspect_and_an_absurdly_narrow_frame_still_has_a_window():
    backbone = Backbone(160, 120, threads=2)
    wide = backbone.windows(np.zeros((100, 400, 3), np.uint8), 3, 192)      # 768x192: 24x6 cells
    square = backbone.windows(np.zeros((300, 300, 3), np.uint8), 3, 192)    # 192x192: 6x6 cells
    narrow = backbone.windows(np.zeros((400, 10, 3), np.uint8), 3, 192)     # widened to one window: 3x6 cells
    assert wide.shape == (4, 22, 1280) and square.shape == (4, 4, 1280) and narrow.shape == (4, 1, 1280)


def test_the_reference_sut_answers_from_windows_and_its_fingerprint_names_them(windowed):
    from isu_validate.protocols import SUTRequest
    from isu_validate.reference.adapter import ReferenceAdapter
    folder, _ = windowed
    adapter = ReferenceAdapter(space=SPACE, model_dir=str(folder / "model"), device="cpu")
    image = sorted((folder / "work" / "held-out").glob("*.png"))[0]
    scene = json.loads(image.with_suffix(".json").read_text())["scene"]
    questions = [q for q in SPACE.questions(scene) if q.key == "phone_position"]
    reply = adapter.send(SUTRequest("vqa", image, "", questions))
    p = reply.meta["probabilities"]["phone_position"]
    assert reply.content["answers"]["phone_position"] == max(p, key=p.get)
    assert p == ReferenceISU(SPACE, folder / "model").read(image)[1]["phone_position"]   # the window head's
    heads = json.loads((folder / "model" / "heads.json").read_text())
    heads["windows"]["calibration"]["phone_position"][1] += 1.0          # another calibration: another SUT
    (folder / "model" / "heads.json").write_text(json.dumps(heads))
    try:
        again = ReferenceAdapter(space=SPACE, model_dir=str(folder / "model"), device="cpu")
        assert again.fingerprint != adapter.fingerprint
    finally:
        heads["windows"]["calibration"]["phone_position"][1] -= 1.0
        (folder / "model" / "heads.json").write_text(json.dumps(heads))


def test_the_reproduce_line_names_the_space_and_rigs_a_model_was_trained_in():
    from isu_validate.reference.training import model_card_markdown
    card = {"render_preset": "standard", "held_out": {"per_feature": {}, "by_external_light": {}},
            "held_out_scenes": 100, "training_scenes": 300, "seed": 1, "backbone": "b", "input_size": [320, 240],
            "space": "isu-diverse", "space_hash": "h", "training": {},
            "rigs": {"camera": "passenger-side", "cabin": "default"}}
    line = next(x for x in model_card_markdown(card).splitlines() if x.startswith("- Reproduce"))
    assert line.startswith("- Reproduce: `isu-validate reference train --space isu-diverse --camera passenger-side "
                           "--n 300 ")
    assert "--cabin" not in line          # the default rig is not spelt out
    shipped = {**card, "space": "isu-paper"}
    del shipped["rigs"]                   # a card from before the rigs were recorded
    line = next(x for x in model_card_markdown(shipped).splitlines() if x.startswith("- Reproduce"))
    assert line.startswith("- Reproduce: `isu-validate reference train --n 300 ")


def belted_training_frames(folder):
    """A painted model's training frames as ``fit_window_heads`` takes them (images, scenes, labels), each scene
    given a belt answer and a belt box: the painter draws no belt, and a second window feature needs both."""
    images = sorted((folder / "work" / "train").glob("*.png"))
    scenes = [json.loads(p.with_suffix(".json").read_text())["scene"] for p in images]
    labels = [json.loads(channel_paths(p)["label"].read_text()) for p in images]
    for scene in scenes:
        scene["seat_belt"] = "YES" if scene["phone_position"] == "NONE" else "NO"
    for label in labels:
        label["visible"]["seat_belt"] = {"bbox": [0, 0, 40, 40]}
    return images, scenes, labels


def test_a_features_window_head_does_not_change_with_the_other_features_asked_for(windowed, tmp_path):
    from isu_validate.reference.windows import fit_window_heads
    images, scenes, labels = belted_training_frames(windowed[0])
    backbone = Backbone(160, 120, threads=2)
    alone = fit_window_heads(SPACE, SMALL, backbone, images, scenes, labels, seed=3)[0][0]
    both = WindowSettings(("seat_belt", "phone_position"), SMALL.height)
    paired = fit_window_heads(SPACE, both, backbone, images, scenes, labels, seed=3)[0][1]
    assert paired.feature == "phone_position" and np.allclose(paired.weight, alone.weight, atol=1e-8)
