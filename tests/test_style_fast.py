"""The fast feed-forward network: training, checkpoint resume, saving and applying."""
import numpy as np
import pytest
import torch
from PIL import Image

from style_transfer import FastNetConfig, FastStyleNet, FastTrainConfig, load_model, stylize_fast, train_fast


pytestmark = pytest.mark.usefixtures("few_torch_threads")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("fast")
    rng = np.random.default_rng(0)
    renders = root / "renders"
    renders.mkdir()
    for i in range(2):
        img = np.full((40, 48, 3), 100, np.uint8)
        img[5 + i * 5:25, 8:30] = (220, 50, 40)
        Image.fromarray(img).save(renders / f"r{i}.png")
    style = (rng.integers(0, 2, (40, 48, 1)) * np.array([[[200, 180, 40]]]) + 20).astype(np.uint8)
    Image.fromarray(style).save(root / "style.png")
    return root / "style.png", sorted(renders.glob("*.png"))


# shallow style layers stop VGG at relu2_2: the training loop is tested, not the style quality
TINY = dict(net=FastNetConfig(width=8, blocks=1), batch_size=1, crop=32, style_size=48, checkpoint_every=2,
            style_layers=("relu1_1", "relu2_1"))


def test_output_keeps_any_size_and_range():
    net = FastStyleNet(FastNetConfig(width=8, blocks=1)).eval()
    for h, w in [(37, 53), (16, 16), (48, 64)]:
        out = stylize_fast(net, torch.rand(1, 3, h, w))
        assert out.shape == (1, 3, h, w) and 0 <= out.min() and out.max() <= 1
    with pytest.raises(ValueError, match="too small"):
        stylize_fast(net, torch.rand(1, 3, 8, 30))


def _perturbed(cfg):
    """A net as after some training (an untrained one is the identity: see the next test)."""
    net = FastStyleNet(cfg).eval()
    torch.nn.init.normal_(net.out[1].weight, std=0.1, generator=torch.Generator().manual_seed(0))
    return net


def test_noise_channel_is_seeded_and_optional():
    x = torch.rand(1, 3, 32, 32, generator=torch.Generator().manual_seed(0))
    net = _perturbed(FastNetConfig(width=8, blocks=1))
    assert torch.equal(stylize_fast(net, x, 3), stylize_fast(net, x, 3))
    assert not torch.equal(stylize_fast(net, x, 3), stylize_fast(net, x, 4))
    quiet = _perturbed(FastNetConfig(width=8, blocks=1, noise=False))
    assert torch.equal(stylize_fast(quiet, x, 3), stylize_fast(quiet, x, 4))


def test_an_untrained_net_is_the_identity_and_a_working_size_keeps_detail():
    x = torch.rand(1, 3, 48, 64, generator=torch.Generator().manual_seed(0))
    assert torch.equal(stylize_fast(FastStyleNet(FastNetConfig(width=8, blocks=1)).eval(), x), x)
    net = _perturbed(FastNetConfig(width=8, blocks=1))
    small = stylize_fast(net, x, 3, size=32)
    assert small.shape == x.shape and 0 <= small.min() and small.max() <= 1
    # the change is made at 32 px and upsampled (smooth); the input's own pixel detail passes through
    def roughness(d):
        return (d[..., 1:] - d[..., :-1]).abs().mean()
    assert roughness(small - x) < 0.6 * roughness(stylize_fast(net, x, 3) - x)
    assert torch.equal(stylize_fast(net, x, 3, size=64), stylize_fast(net, x, 3))  # not above its own size


def test_training_lowers_loss_and_round_trips(files, tmp_path):
    style, renders = files
    out = tmp_path / "model.pt"
    report = train_fast(style, renders, out, FastTrainConfig(steps=8, lr=1e-2, **TINY))
    assert report.steps_done == 8 and np.isfinite(report.losses).all()
    assert np.mean(report.losses[-3:]) < np.mean(report.losses[:3])
    net, meta = load_model(out)
    assert meta["steps_done"] == 8 and meta["train"]["crop"] == 32 and len(meta["style_sha256"]) == 64
    assert not out.with_name("model.pt.ckpt").exists()
    x = torch.rand(1, 3, 40, 48, generator=torch.Generator().manual_seed(1))
    assert torch.equal(stylize_fast(net, x), stylize_fast(load_model(out)[0], x))


def test_interrupted_training_resumes_to_the_same_model(files, tmp_path):
    style, renders = files
    cfg = FastTrainConfig(steps=4, **TINY)
    straight = train_fast(style, renders, tmp_path / "a.pt", cfg)

    def stop_after_three(step, total, loss):
        if step == 3:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        train_fast(style, renders, tmp_path / "b.pt", cfg, progress=stop_after_three)
    assert (tmp_path / "b.pt.ckpt").exists()
    resumed = train_fast(style, renders, tmp_path / "b.pt", cfg)
    assert resumed.steps_done == 4 and len(resumed.losses) == 4
    assert resumed.losses == pytest.approx(straight.losses, rel=1e-4)


def test_bad_model_files_are_explained(tmp_path):
    with pytest.raises(FileNotFoundError, match="stylize train"):
        load_model(tmp_path / "missing.pt")
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"not a model")
    with pytest.raises(ValueError, match="cannot read fast style model"):
        load_model(junk)
    torch.save({"format": "something else"}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="not an isu-validate fast style model"):
        load_model(tmp_path / "other.pt")
