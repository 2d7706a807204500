"""``reference train --extra``: retraining on a model's stored features plus a dataset's images, without
rendering the base set again (painted images, no Blender); and the shipped features are the ones the
shipped heads were fitted on."""
import json
from pathlib import Path

import numpy as np
import pytest

from isu_validate.cli import main
from isu_validate.reference import retrain as retrain_module
from isu_validate.reference.backbone import Backbone
from isu_validate.reference.feature_bank import load_bank, load_feature_set
from isu_validate.reference.heads import load_heads
from isu_validate.reference.model import default_model_dir
from isu_validate.reference.retrain import retrain_with_extra
from isu_validate.reference.training import accuracy, fit_heads, train_reference
from isu_validate.render import RENDERER_VERSION
from isu_validate.space import load_space
from tests.test_reference import PatchPainter

SPACE = load_space()


@pytest.fixture(scope="module")
def backbone():
    return Backbone(160, 120, threads=2)


@pytest.fixture(scope="module")
def base(tmp_path_factory, backbone):
    folder = tmp_path_factory.mktemp("base")
    train_reference(SPACE, PatchPainter(), folder / "model", folder / "work", n_train=40, n_test=20, seed=3,
                    preset="painted", backbone=backbone, renderer_version=RENDERER_VERSION)
    return folder / "model"


def make_dataset(folder: Path, n: int = 5, space_name: str = SPACE.name, space_hash: str = SPACE.hash,
                 occluded: tuple[str, ...] = ()) -> Path:
    """A dataset folder as `isu-validate dataset` writes it, painted."""
    (folder / "images").mkdir(parents=True)
    rows = []
    for i, scene in enumerate(SPACE.sample(np.random.default_rng(11), n)):
        canonical = SPACE.canonical(scene)
        PatchPainter().render(canonical, folder / "images" / f"{i:05d}.png")
        rows.append({"file_name": f"images/{i:05d}.png", "scene": canonical, "variant": "render",
                     "truth": {q.key: q.truth for q in SPACE.questions(canonical)}, "occluded": list(occluded)})
    (folder / "metadata.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    (folder / "dataset.json").write_text(json.dumps({"format": "isu-validate-dataset/1", "complete": True,
                                                     "space": space_name, "space_hash": space_hash,
                                                     "versions": {"renderer": RENDERER_VERSION}}))
    return folder


@pytest.fixture
def same_backbone(monkeypatch, backbone):
    monkeypatch.setattr(retrain_module, "Backbone", lambda *size, **where: backbone)


def test_extra_retrains_on_the_stored_features_and_compares_on_the_same_held_out_scenes(
        tmp_path, base, same_backbone, capsys):
    dataset = make_dataset(tmp_path / "ds", occluded=("tshirt_colour",))
    out = tmp_path / "retrained"
    assert main(["reference", "train", "--extra", str(dataset), "--base", str(base), "--out", str(out),
                 "--workdir", str(tmp_path / "w")]) == 0
    card = json.loads((out / "model_card.json").read_text())
    base_card = json.loads((base / "model_card.json").read_text())
    assert card["training_scenes"] == 45 and card["base_training_scenes"] == 40
    assert card["held_out_scenes"] == 20                      # the base's held-out scenes, nothing else
    assert card["extra"] == [{"dataset": str(dataset.resolve()), "content_hash": content_hash_of(dataset),
                              "images": 5, "labels_left_out": 5, "runs": []}]
    for name, row in card["comparison"].items():              # the base evaluated on the same stored features
        assert row["base"] == base_card["held_out"]["per_feature"][name]["accuracy"]
        assert row["change"] == pytest.approx(row["retrained"] - row["base"])
    assert set(card["comparison"]) == set(base_card["held_out"]["per_feature"])
    text = (out / "MODEL_CARD.md").read_text()
    assert "| feature | base | retrained | change | n |" in text and "Worst change" in text
    assert f"`{dataset.resolve()}` (content hash {content_hash_of(dataset)})" in text
    name, row = next(iter(card["comparison"].items()))   # accuracies in %, changes in points, as the README
    assert f"| {name} | {100 * row['base']:.1f}% | {100 * row['retrained']:.1f}% | {100 * row['change']:+.1f} pt |" \
        in text
    assert "model_dir=" in capsys.readouterr().out
    assert len(load_feature_set(out / "train_features.npz").scenes) == 45   # it can be a base in turn
    # the occluded T-shirt colour is not learnt from: 40 base rows + 0 of the dataset's
    heads, _ = load_heads(out)
    assert {h.feature for h in heads} == {f.name for f in SPACE.predicted}


def test_a_base_fitted_before_clipping_is_named_in_the_card(tmp_path, base, same_backbone):
    """Retraining a model whose heads read features unclipped: the card says part of each change is the fit."""
    import shutil

    old = tmp_path / "old"
    shutil.copytree(base, old)
    meta = json.loads((old / "heads.json").read_text())
    del meta["clip_sigma"]
    (old / "heads.json").write_text(json.dumps(meta))
    dataset = make_dataset(tmp_path / "ds")
    for b, out in ((base, tmp_path / "a"), (old, tmp_path / "b")):
        assert main(["reference", "train", "--extra", str(dataset), "--base", str(b), "--out", str(out),
                     "--workdir", str(tmp_path / "w")]) == 0
    assert "unclipped" not in (tmp_path / "a" / "MODEL_CARD.md").read_text()
    assert json.loads((tmp_path / "b" / "model_card.json").read_text())["base_clip_sigma"] is None
    assert "the base's were read unclipped, so part of every change below is the fit" in \
        (tmp_path / "b" / "MODEL_CARD.md").read_text()


def content_hash_of(dataset: Path) -> str:
    """The images' bytes and their labels (occluded features left out), as the card should name them."""
    import hashlib

    digest = hashlib.sha256()
    for row in map(json.loads, (dataset / "metadata.jsonl").read_text().splitlines()):
        digest.update((dataset / row["file_name"]).read_bytes())
        labels = {k: v for k, v in SPACE.canonical(row["scene"]).items() if k not in row["occluded"]}
        digest.update(json.dumps(labels, sort_keys=True).encode())
    return digest.hexdigest()[:16]


def test_the_card_names_the_runs_behind_a_focused_dataset_and_its_reproduce_line_runs_as_printed(
        tmp_path, base, same_backbone, monkeypatch, capsys):
    import shlex

    dataset = make_dataset(tmp_path / "ds")
    info = json.loads((dataset / "dataset.json").read_text())
    info["focus"] = {"mode": "failing", "runs": ["runs/find"], "judged_by": [
        {"run": "/abs/runs/find", "sut": "reference", "sut_options": {}, "threshold": 0.9, "tests": 150,
         "failing": 19}]}
    (dataset / "dataset.json").write_text(json.dumps(info))
    out = tmp_path / "m"
    (tmp_path / "first").mkdir()
    monkeypatch.chdir(tmp_path / "first")   # its default workdir here, not a features cache kept in the checkout
    assert main(["reference", "train", "--extra", str(dataset), "--base", str(base), "--out", str(out)]) == 0
    card = json.loads((out / "model_card.json").read_text())
    assert card["extra"][0]["runs"] == [{"run": "/abs/runs/find", "sut": "reference", "sut_options": {},
                                         "threshold": 0.9}]
    text = (out / "MODEL_CARD.md").read_text()
    assert "drawn near the tests of `/abs/runs/find` (SUT `reference`, failing below threshold 0.9)" in text
    printed = shlex.split(card["reproduce"])
    assert f"- Reproduce: `{card['reproduce']}`" in text and printed[:3] == ["isu-validate", "reference", "train"]
    heads = (out / "heads.npz").read_bytes()
    monkeypatch.chdir(tmp_path)   # absolute paths: it runs from any folder, and makes the same model
    capsys.readouterr()
    assert main(printed[1:]) == 0
    assert (out / "heads.npz").read_bytes() == heads


@pytest.mark.parametrize("what, expected", [("missing", "does not exist"),
                                            ("run", "holds the output of `isu-validate run` (run.json), not a "
                                                    "reference ISU model"),
                                            ("empty", "holds no heads.npz, not a reference ISU model")])
def test_a_base_that_is_no_model_is_named_for_what_it_is(tmp_path, what, expected, capsys):
    base = tmp_path / "find"
    if what != "missing":
        base.mkdir()
    if what == "run":
        (base / "run.json").write_text("{}")
    dataset = make_dataset(tmp_path / "ds")
    assert main(["reference", "train", "--extra", str(dataset), "--base", str(base), "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert f"--base {base} {expected}" in err and "name a model folder (one with heads.npz" in err
    assert "trained before features were kept" not in err and not (tmp_path / "m").exists()


def test_a_second_retrain_of_the_same_dataset_embeds_nothing(tmp_path, base, same_backbone, monkeypatch):
    dataset = make_dataset(tmp_path / "ds")
    args = ["reference", "train", "--extra", str(dataset), "--base", str(base), "--workdir", str(tmp_path / "w")]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0

    def no_embedding(*a, **k):
        raise AssertionError("embedded the dataset again")

    monkeypatch.setattr(retrain_module, "embed_images", no_embedding)
    assert main(args + ["--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a" / "heads.npz").read_bytes() == (tmp_path / "b" / "heads.npz").read_bytes()


def test_a_dataset_of_another_space_is_refused_naming_both(tmp_path, base, capsys):
    dataset = make_dataset(tmp_path / "ds", space_name="my-cabin", space_hash="0123456789abcdef")
    assert main(["reference", "train", "--extra", str(dataset), "--base", str(base),
                 "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert "'my-cabin' (hash 0123456789abcdef)" in err and f"'isu-paper' (hash {SPACE.hash})" in err
    assert err.count("\n") == 1 and not (tmp_path / "m").exists()


def test_features_of_another_renderer_are_not_reused(tmp_path, base):
    import shutil

    old = tmp_path / "old"
    shutil.copytree(base, old)
    with pytest.raises(ValueError, match=f"renderer '{RENDERER_VERSION}'.*current renderer is 'isu-blender-99'"):
        load_bank(old, SPACE, "isu-blender-99")


@pytest.mark.parametrize("option", [["--n", "50"], ["--seed", "0"], ["--check-preset", "standard"], ["--fine-tune"]])
def test_options_of_a_new_training_do_not_apply_to_extra(tmp_path, option, capsys):
    assert main(["reference", "train", "--extra", str(tmp_path), *option]) == 2
    assert "do not apply" in capsys.readouterr().err


def test_no_extra_data_gives_the_base_heads_again(tmp_path, base, backbone):
    retrain_with_extra(SPACE, base, [], tmp_path / "again", RENDERER_VERSION, backbone=backbone)
    before, _ = load_heads(base)
    after, _ = load_heads(tmp_path / "again")
    for a, b in zip(before, after):
        assert a.classes == b.classes and np.allclose(a.weight, b.weight, atol=1e-5)


def test_the_shipped_features_are_those_the_shipped_heads_were_fitted_on():
    """Refitting three heads on the shipped training features gives the shipped heads and their held-out
    answers and accuracies (all 14 do; three keep the test quick).

    Not bit for bit: lbfgs runs through BLAS, whose kernels differ by processor. Measured on these heads
    (scratch runs with OPENBLAS_CORETYPE pinned, 1 or 2 threads): Haswell/Zen/SkylakeX/Sandybridge kernels move
    a weight by at most 2e-4 of the head's largest weight and a held-out probability by 1e-4; real changes
    move them far more: one training scene fewer (599 of 600) by 3e-2 and 1e-2, features stored as float16
    by 3e-3 and 4e-3 (luggage_position); solver newton-cg or saga, or C 10% higher, each fail too. The
    tolerances (1e-3 each) sit between. The held-out answers are the same under every kernel (none is within
    0.02 of a tie). The means are plain float32 sums (no BLAS), compared in the units the heads see (the
    feature's std): the same scenes summed in another order move them by 5e-6, float16 features by 3e-4,
    one scene fewer by 3e-2."""
    model = default_model_dir()
    train, held_out = load_bank(model, SPACE, RENDERER_VERSION)
    assert (len(train.scenes), len(held_out.scenes)) == (600, 200)
    shipped = {h.feature: h for h in load_heads(model)[0]}
    card = json.loads((model / "model_card.json").read_text())["held_out"]["per_feature"]
    names = ("tshirt_colour", "driver_gender", "luggage_position")
    space = _only(names)
    heads = fit_heads(space, train.features, train.scenes, seed=0)
    refit = accuracy(space, heads, held_out.features, held_out.scenes)["per_feature"]
    for head in heads:
        ship = shipped[head.feature]
        rows = [i for i, scene in enumerate(held_out.scenes) if head.feature in scene]
        assert head.classes == ship.classes
        assert head.predict(held_out.features[rows]) == ship.predict(held_out.features[rows])
        assert refit[head.feature]["accuracy"] == pytest.approx(card[head.feature]["accuracy"])
        np.testing.assert_allclose(head.weight, ship.weight, rtol=0, atol=1e-3 * np.abs(ship.weight).max())
        np.testing.assert_allclose(head.probabilities(held_out.features[rows]),
                                   ship.probabilities(held_out.features[rows]), rtol=0, atol=1e-3)
        np.testing.assert_array_less(np.abs(head.mean - ship.mean), 1e-4 * ship.scale)


def _only(names):
    """The space as fitting and scoring see it, with only ``names`` predicted (fewer heads: a quick test)."""
    from types import SimpleNamespace

    return SimpleNamespace(predicted=[SPACE.features[n] for n in names], features=SPACE.features)
