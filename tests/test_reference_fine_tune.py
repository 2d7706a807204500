"""``reference train --fine-tune``: the backbone's last blocks trained on the training renders (painted images
here, no Blender), its weights beside the heads, read back by every reader of the model, resumed after a kill."""
import json
import shutil

import numpy as np
import pytest
import torch

from isu_validate.errors import InputError, InputNotFound
from isu_validate.reference import fine_tune as fine_tune_module
from isu_validate.reference.backbone import FROZEN, Backbone, read_rgb
from isu_validate.reference.feature_bank import load_feature_set
from isu_validate.reference.fine_tune import WEIGHTS_FILE, FineTune, fine_tune_backbone
from isu_validate.reference.model import ReferenceISU
from isu_validate.reference.retrain import retrain_with_extra
from isu_validate.render import RENDERER_VERSION
from isu_validate.space import load_space
from tests.test_reference import PatchPainter, train_painted
from tests.test_reference_extra import make_dataset

SPACE = load_space()
SMALL = FineTune(blocks=2, epochs=2, batch=8, seed=3)


@pytest.fixture(scope="module")
def tuned(tmp_path_factory):
    return train_painted(tmp_path_factory, "tuned", PatchPainter(), 40, 20, fine_tune=SMALL)


def test_a_tuned_model_keeps_its_weights_beside_the_heads_and_reads_with_them(tuned):
    folder, card = tuned
    model = folder / "model"
    meta = json.loads((model / "heads.json").read_text())
    assert meta["backbone_weights"] == WEIGHTS_FILE and (model / WEIGHTS_FILE).is_file()
    assert "last 2 blocks fine-tuned" in meta["backbone"] and meta["backbone"] != FROZEN
    assert card["fine_tune"]["blocks"] == 2 and card["fine_tune"]["images"] == 40
    assert "--fine-tune 2" in (model / "MODEL_CARD.md").read_text()
    assert card["held_out"]["per_feature"]["tshirt_colour"]["accuracy"] >= 0.9
    # the model as a SUT reads an image with the tuned weights: the features the heads were fitted on
    reader = ReferenceISU(SPACE, model)
    stored = load_feature_set(model / "train_features.npz")
    first = sorted((folder / "work" / "train").glob("*.png"))[0]
    assert reader.backbone.name == meta["backbone"]
    np.testing.assert_allclose(reader.backbone.features([read_rgb(first)])[0], stored.features[0], atol=1e-4)
    frozen = Backbone(160, 120, threads=2).features([read_rgb(first)])[0]
    assert np.abs(frozen - stored.features[0]).max() > 1e-2   # the tuning changed what the backbone sees


def test_a_missing_torn_or_foreign_weights_file_is_a_clear_error(tuned, tmp_path):
    folder, _ = tuned
    model = tmp_path / "model"
    shutil.copytree(folder / "model", model)
    (model / WEIGHTS_FILE).write_bytes(b"not a torch file")
    with pytest.raises(InputError, match="cannot read the tuned backbone"):
        ReferenceISU(SPACE, model)
    (model / WEIGHTS_FILE).unlink()
    with pytest.raises(InputNotFound, match="copy the whole model folder"):
        ReferenceISU(SPACE, model)
    other = Backbone(160, 120, threads=2)   # weights of another tuning under the same file name
    other.tune({k: v + 0.01 for k, v in Backbone(160, 120, tuned=folder / "model" / WEIGHTS_FILE).tuned_state.items()},
               2)
    fine_tune_module.save_tuned(other, model)
    with pytest.raises(InputError, match="not the one the heads"):
        ReferenceISU(SPACE, model)


def test_a_fine_tune_killed_after_an_epoch_resumes_to_the_same_weights(tmp_path, monkeypatch):
    images = []
    scenes = SPACE.sample(np.random.default_rng(1), 16)
    for i, scene in enumerate(scenes):
        images.append(tmp_path / f"{i}.png")
        PatchPainter().render(scene, images[-1])
    whole = Backbone(160, 120, threads=2)
    fine_tune_backbone(whole, images, scenes, SPACE, SMALL)

    checkpoint = tmp_path / "fine-tune.pt"
    real_epoch = fine_tune_module._Trainer.epoch

    def killed_in_the_second(self, pixels, targets, epoch):
        if epoch == 1:
            raise KeyboardInterrupt
        return real_epoch(self, pixels, targets, epoch)

    monkeypatch.setattr(fine_tune_module._Trainer, "epoch", killed_in_the_second)
    with pytest.raises(KeyboardInterrupt):
        fine_tune_backbone(Backbone(160, 120, threads=2), images, scenes, SPACE, SMALL, checkpoint=checkpoint)
    monkeypatch.setattr(fine_tune_module._Trainer, "epoch", real_epoch)
    assert torch.load(checkpoint, weights_only=True)["epochs_done"] == 1   # the kill left the first epoch committed
    resumed = Backbone(160, 120, threads=2)
    card = fine_tune_backbone(resumed, images, scenes, SPACE, SMALL, checkpoint=checkpoint)
    assert card["epochs"] == 2
    for name, tensor in whole.tuned_state.items():
        np.testing.assert_allclose(resumed.tuned_state[name].numpy(), tensor.numpy(), atol=1e-5, err_msg=name)

    with pytest.raises(InputError, match="was made with"):   # a checkpoint of other settings is never trained on
        fine_tune_backbone(Backbone(160, 120, threads=2), images, scenes, SPACE, FineTune(blocks=3, epochs=2),
                           checkpoint=checkpoint)
    checkpoint.write_bytes(b"\x00" * 10)
    with pytest.raises(InputError, match="delete it"):
        fine_tune_backbone(Backbone(160, 120, threads=2), images, scenes, SPACE, SMALL, checkpoint=checkpoint)


def test_fine_tune_settings_are_checked():
    with pytest.raises(InputError, match="16 blocks"):
        FineTune(blocks=0)
    with pytest.raises(InputError, match="16 blocks"):
        FineTune(blocks=17)
    with pytest.raises(InputError, match="at least one epoch"):
        FineTune(epochs=0)


def test_retraining_a_tuned_model_with_extra_data_keeps_its_backbone(tuned, tmp_path):
    folder, _ = tuned
    dataset = make_dataset(tmp_path / "extra", n=4)
    from isu_validate.dataset.folder import open_dataset
    from isu_validate.reference.extra_data import extra_set

    data = open_dataset(dataset)
    card = retrain_with_extra(SPACE, folder / "model", [extra_set(dataset, data.info(), data.metadata(), SPACE)],
                              tmp_path / "out", RENDERER_VERSION)
    assert card["backbone"] == json.loads((folder / "model" / "heads.json").read_text())["backbone"]
    kept, base = (Backbone(160, 120, tuned=f / WEIGHTS_FILE).tuned_state for f in (tmp_path / "out", folder / "model"))
    assert kept.keys() == base.keys() and all(np.array_equal(kept[k], base[k]) for k in kept)
    ReferenceISU(SPACE, tmp_path / "out")   # reads with the same weights, checked by name


def test_the_command_line_option_defaults_to_six_blocks_and_is_off_without_it():
    from isu_validate.cli import build_parser

    parse = lambda *extra: build_parser().parse_args(["reference", "train", *extra])  # noqa: E731

    def _fine_tune(args):   # what the command passes to train_reference (bench transfer's fine_tune=BLOCKS alike)
        return FineTune.optional(args.fine_tune, args.seed)

    assert _fine_tune(parse()) is None
    assert _fine_tune(parse("--fine-tune", "--seed", "4")) == FineTune(blocks=6, seed=4)
    assert _fine_tune(parse("--fine-tune", "3")).blocks == 3
    with pytest.raises(InputError, match="train 1 to 16"):   # 0 is refused, never read as "no fine-tune"
        _fine_tune(parse("--fine-tune", "0"))
