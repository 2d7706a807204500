"""The reference ISU's learning machinery on images a painter makes (no Blender here):
balanced sampling, heads, NONE for absent things, captions, the SUT adapter, the card."""
import json
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from isu_validate.protocols import SUTRequest
from isu_validate.reference.backbone import Backbone
from isu_validate.reference.captioner import describe
from isu_validate.reference.heads import CLIP_SIGMA, fit_head, load_heads, save_heads
from isu_validate.reference.training import balanced_scenes, train_reference, visible_label
from isu_validate.render.outputs import channel_paths
from isu_validate.space import load_space

SPACE = load_space()


class PatchPainter:
    """Stands in for the renderer: big coloured patches for a few features."""

    def render(self, scene, out: Path):
        img = np.full((120, 160, 3), 90, np.uint8)
        cv2.rectangle(img, (10, 60), (60, 110), (255, 255, 255) if scene["tshirt_colour"] == "WHITE" else (0, 0, 0), -1)
        if scene["luggage"] == "YES":
            colour = (0, 220, 255) if scene["luggage_colour"] == "YELLOW" else (50, 50, 50)
            x = 90 if scene["luggage_position"] == "PASSENGER" else 40
            cv2.rectangle(img, (x, 5), (x + 60, 45), colour, -1)
        cv2.imwrite(str(out), img)


def train_painted(tmp_path_factory, name: str, painter, n_train: int, n_test: int, **options):
    """A model trained on a painter's images with its own small backbone: (folder, card); the model in
    folder/model, the painted sets in folder/work."""
    from isu_validate.render import RENDERER_VERSION

    folder = tmp_path_factory.mktemp(name)
    card = train_reference(SPACE, painter, folder / "model", folder / "work", n_train=n_train, n_test=n_test, seed=3,
                           preset="painted", backbone=Backbone(160, 120, threads=2),
                           renderer_version=RENDERER_VERSION, **options)
    return folder, card


@pytest.fixture(scope="module")
def backbone():
    return Backbone(160, 120, threads=2)


@pytest.fixture(scope="module")
def trained(tmp_path_factory, backbone):
    folder = tmp_path_factory.mktemp("ref")
    card = train_reference(SPACE, PatchPainter(), folder / "model", folder / "work", n_train=48, n_test=24,
                           seed=3, preset="painted", backbone=backbone)
    return folder, card


def test_balanced_scenes_are_valid_and_balanced():
    scenes = balanced_scenes(SPACE, 400, np.random.default_rng(0))
    assert all(SPACE.is_valid(s) for s in scenes)
    in_hand = np.mean([s["phone_position"] != "NONE" for s in scenes])
    assert 0.4 < in_hand < 0.6  # uniform values would give 10/11
    # the co-driver seat holds one kind of thing at a time: the loose objects are balanced on the
    # seats free for them, and there each can be seen without the others (a greedy balance over all
    # scenes once put all three on every free seat, and the heads learnt one identical 'something')
    free = [s for s in scenes if s["child_seat"] == "NO" and s.get("luggage_position") != "PASSENGER"]
    things = ("phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat")
    on_seat = np.array([[s[t] == "YES" for t in things] for s in free], dtype=float)
    assert np.all(np.abs(on_seat.mean(axis=0) - 0.5) < 0.05)
    assert len({tuple(row) for row in on_seat}) == 8          # every combination, the empty seat too
    assert np.abs(np.corrcoef(on_seat.T)[np.triu_indices(3, 1)]).max() < 0.6
    # a child seat only where the seat would also be free for it; still enough children to learn from
    assert 0.12 < np.mean([s["child_seat"] == "YES" for s in scenes]) < 0.5
    passenger = [s["luggage_position"] == "PASSENGER" for s in scenes if s["luggage"] == "YES"]
    assert 0.08 < np.mean(passenger) < 0.6


def test_heads_learn_what_is_visible_and_the_card_says_how_well(trained):
    folder, card = trained
    acc = card["held_out"]["per_feature"]
    assert acc["tshirt_colour"]["accuracy"] >= 0.9
    assert acc["luggage"]["accuracy"] >= 0.85
    assert set(card["held_out"]["by_external_light"]) <= {"LOW", "MEDIUM", "HIGH"}
    text = (folder / "model" / "MODEL_CARD.md").read_text()
    assert "tshirt_colour" in text and "reference train --n 48" in text
    assert card["heads"] == {"C": 0.05, "clip_sigma": CLIP_SIGMA} and "clipped at +-3 training standard" in text
    assert json.loads((folder / "model" / "heads.json").read_text())["clip_sigma"] == CLIP_SIGMA
    assert (folder / "model" / "heads.npz").stat().st_size < 5_000_000


class DimPainter(PatchPainter):
    """The same scenes under another 'preset': darker and noisier, as a cheaper render would be."""

    def render(self, scene, out: Path):
        super().render(scene, out)
        img = cv2.imread(str(out)).astype(float) * 0.5
        noise = np.random.default_rng(len(str(out))).normal(0, 12, img.shape)
        cv2.imwrite(str(out), np.clip(img + noise, 0, 255).astype(np.uint8))


def test_held_out_accuracy_is_also_measured_at_other_presets(tmp_path, backbone):
    opened = []

    def renderer_for(preset):
        opened.append(preset)
        return DimPainter()

    card = train_reference(SPACE, PatchPainter(), tmp_path / "model", tmp_path / "work", n_train=48, n_test=24,
                           seed=3, preset="painted", backbone=backbone, other_presets={"dim": 10},
                           renderer_for=renderer_for)
    assert opened == ["dim"] and card["held_out_scenes_by_preset"] == {"painted": 24, "dim": 10}
    dim = card["held_out_by_preset"]["dim"]["per_feature"]
    assert dim["tshirt_colour"]["n"] == 10 and 0.0 <= dim["tshirt_colour"]["accuracy"] <= 1.0
    assert card["held_out_by_preset"]["painted"] == card["held_out"]
    assert len(list((tmp_path / "work" / "held-out-dim").glob("*.png"))) == 10
    text = (tmp_path / "model" / "MODEL_CARD.md").read_text()
    assert "| feature | painted | n | dim | n | training accuracy |" in text
    assert "--check-preset dim:10" in text and "(preset `dim`)" in text


class HidingPainter(PatchPainter):
    """Paints no luggage on the back bench and says so in a render label, as the renderer does."""

    def render(self, scene, out: Path):
        hidden = scene.get("luggage_position") == "BACK"
        super().render({**scene, "luggage": "NO"} if hidden else scene, out)
        occluded = ["luggage", "luggage_position", "luggage_colour"] if hidden else []
        channel_paths(out)["label"].write_text(json.dumps({"occluded": occluded}))


def test_what_a_render_hid_from_the_camera_is_neither_learnt_nor_scored(tmp_path, backbone):
    card = train_reference(SPACE, HidingPainter(), tmp_path / "model", tmp_path / "work", n_train=48, n_test=24,
                           seed=3, preset="painted", backbone=backbone)
    scenes = [SPACE.canonical(s) for s in balanced_scenes(SPACE, 24, np.random.default_rng(3 + 10_000))]
    back = sum(s.get("luggage_position") == "BACK" for s in scenes)
    with_luggage = sum("luggage_position" in s for s in scenes)
    assert back > 0 and card["hidden_from_camera"]["held_out"] == {"luggage": back, "luggage_colour": back,
                                                                   "luggage_position": back}
    assert card["held_out"]["per_feature"]["luggage_position"]["n"] == with_luggage - back
    assert card["held_out"]["per_feature"]["luggage"]["n"] == 24 - back
    assert card["held_out"]["per_feature"]["tshirt_colour"]["n"] == 24
    assert card["hidden_from_camera"]["training"]["luggage"] > 0
    text = (tmp_path / "model" / "MODEL_CARD.md").read_text()
    said = f"training: luggage {card['hidden_from_camera']['training']['luggage']}"
    assert f"Hidden from the camera, so not learnt from nor scored (the render label's `occluded`): {said}" in text
    assert f"held-out: luggage {back}" in text
    assert visible_label({"luggage": "YES"}, tmp_path / "no-label.png") == {"luggage": "YES"}


def test_check_preset_arguments_are_checked():
    from isu_validate.commands.reference import parse_check

    assert parse_check("standard:50", 200) == ("standard", 50) and parse_check("draft", 80) == ("draft", 80)
    with pytest.raises(ValueError, match="unknown render preset 'fancy'"):
        parse_check("fancy:3", 10)
    with pytest.raises(ValueError, match="between 1 and --held-out"):
        parse_check("standard:500", 200)
    with pytest.raises(ValueError, match="whole number"):
        parse_check("standard:many", 200)


def test_rendered_sets_resume_without_rendering_again(trained, backbone):
    folder, _ = trained

    class NoRenderer:
        def render(self, scene, out):
            raise AssertionError("re-rendered an image that was already there")

    train_reference(SPACE, NoRenderer(), folder / "model2", folder / "work", n_train=48, n_test=24, seed=3,
                    preset="painted", backbone=backbone)


def test_adapter_answers_only_what_is_asked_and_none_for_absent_things(trained, backbone, monkeypatch):
    from isu_validate.reference import model as model_module
    from isu_validate.reference.adapter import ReferenceAdapter

    folder, _ = trained
    monkeypatch.setattr(model_module, "Backbone", lambda *a, **where: backbone)
    adapter = ReferenceAdapter(space=SPACE, model_dir=str(folder / "model"))
    scene = SPACE.sample(np.random.default_rng(5), 1)[0]
    scene.update(luggage="NO", tshirt_colour="WHITE")
    image = folder / "probe.png"
    PatchPainter().render(scene, image)
    questions = SPACE.questions(scene)
    reply = adapter.send(SUTRequest("vqa", image, "", questions + [q for q in SPACE.questions(
        dict(scene, luggage="YES", luggage_position="BACK", luggage_colour="YELLOW", luggage_orientation=30.0))
        if q.key == "luggage_colour"]))
    answers = reply.content["answers"]
    assert answers["tshirt_colour"] == "WHITE" and answers["luggage"] == "NO"
    assert answers["luggage_colour"] == "NONE"  # it sees no luggage, so it names no colour
    assert json.loads(reply.raw) == reply.content
    caption = adapter.send(SUTRequest("vc", image, "")).content["caption"]
    assert "white T-shirt" in caption and "suitcase" not in caption


def test_missing_model_is_a_clear_error(tmp_path):
    from isu_validate.reference.adapter import ReferenceAdapter
    from isu_validate.sut.errors import SUTConfigError

    with pytest.raises(SUTConfigError, match="reference train"):
        ReferenceAdapter(space=SPACE, model_dir=str(tmp_path))


def test_heads_round_trip_and_single_class_heads(tmp_path):
    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 5))
    y = ["A" if v > 0 else "B" for v in X[:, 0]]
    heads = [fit_head("f", X, y), fit_head("g", X, ["ONLY"] * 200)]
    save_heads(heads, tmp_path, {"note": 1})
    loaded, meta = load_heads(tmp_path)
    assert meta["note"] == 1
    assert loaded[0].predict(X) == heads[0].predict(X)
    assert np.mean(np.array(loaded[0].predict(X)) == np.array(y)) > 0.9
    assert loaded[1].predict(X[:3]) == ["ONLY"] * 3
    assert meta["clip_sigma"] == CLIP_SIGMA and loaded[0].clip == CLIP_SIGMA


def test_a_channel_the_training_never_moved_cannot_carry_the_answer():
    """A photo can move a backbone channel far beyond anything the renders did: the head reads it at most
    CLIP_SIGMA training deviations out, as it was fitted. Unclipped, the same head flips its answer."""
    rng = np.random.default_rng(1)
    X = rng.normal(size=(300, 6))
    X[:, 5] = 1.0 + 1e-3 * rng.normal(size=300)       # a channel the training set barely moves
    y = ["YES" if a + 0.3 * b > 0 else "NO" for a, b in zip(X[:, 0], X[:, 5] - 1.0)]
    head = fit_head("f", X, y)
    clear_no = np.array([[-2.0, 0, 0, 0, 0, 1.0]])
    far_out = clear_no.copy()
    far_out[0, 5] = 1.0 + 1e3                          # a million training deviations out
    assert head.predict(clear_no) == ["NO"]
    assert np.abs(head.standardise(far_out)).max() == CLIP_SIGMA
    assert head.predict(far_out) == ["NO"]
    unclipped = replace(head, clip=None)
    assert unclipped.predict(far_out) == ["YES"]      # what the head would say without the clip
    assert np.isfinite(head.probabilities(np.array([[np.inf] * 6]))).all()


def test_a_model_fitted_before_clipping_reads_its_features_unclipped(tmp_path):
    rng = np.random.default_rng(2)
    X = rng.normal(size=(100, 4))
    head = replace(fit_head("f", X, ["A" if v > 0 else "B" for v in X[:, 0]]), clip=None)
    save_heads([head], tmp_path, {})
    meta = json.loads((tmp_path / "heads.json").read_text())
    assert "clip_sigma" not in meta                   # as the files of such a model are
    loaded, _ = load_heads(tmp_path)
    far = np.array([[50.0, 0, 0, 0]])
    assert loaded[0].clip is None
    np.testing.assert_allclose(loaded[0].standardise(far), (far - head.mean) / head.scale, rtol=1e-6)


def test_captions_vary_in_wording_but_not_in_content():
    p = {"driver_gender": "FEMALE", "driver_emotion": "HAPPY", "tshirt_colour": "BLACK", "seat_belt": "NO",
         "phone_position": "YES", "child_seat": "YES", "child_seat_orientation": "REAR_FACING", "child": "YES",
         "luggage": "NO", "phone_codriver_seat": "YES", "colabottle_codriver_seat": "NO",
         "colacan_codriver_seat": "YES"}
    captions = {describe(p, v) for v in range(40)}
    assert len(captions) > 3
    assert all("rear-facing child seat" in c and "black T-shirt" in c and "mobile phone and a cola can" in c
               and "passenger seat" in c for c in captions)


def test_reference_train_leaves_the_shipped_model_alone_unless_it_is_named(tmp_path, monkeypatch, capsys):
    """The command with its defaults, the rendering and training replaced by recorders."""
    from isu_validate import render
    from isu_validate.cli import main
    import shutil

    from isu_validate.reference import model as reference_model, training

    written = []

    class NoRenderer:
        def close(self):
            pass

    def record(space, renderer, out, workdir, n, held_out, seed, preset, **extra):
        written.append(Path(out))
        return {"held_out": {"per_feature": {}}}

    monkeypatch.setattr(render, "open_renderer", lambda **kw: NoRenderer())
    monkeypatch.setattr(training, "train_reference", record)
    # a copy stands for the shipped model: the command marks the folder it writes, the checkout stays as it is
    shipped = shutil.copytree(reference_model.default_model_dir(), tmp_path / "shipped").resolve()
    monkeypatch.setattr(reference_model, "default_model_dir", lambda: shipped)
    assert main(["reference", "train", "--n", "10", "--held-out", "1", "--workdir", str(tmp_path / "w")]) == 0
    assert written[-1].resolve() != shipped and written[-1] == tmp_path / "w" / "model"
    assert f"--sut-option model_dir={tmp_path / 'w' / 'model'}" in capsys.readouterr().out
    # named, with other settings than the shipped model's marker says (600/200): refused, then replaced on purpose
    named = ["reference", "train", "--n", "10", "--held-out", "1", "--workdir", str(tmp_path / "w"),
             "--out", str(shipped)]
    assert main(named) == 2
    assert main(named + ["--overwrite"]) == 0
    assert written[-1].resolve() == shipped  # (re-pin afterwards)
