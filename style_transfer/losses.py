"""Gatys/Johnson losses on VGG activations."""
from __future__ import annotations

import torch
import torch.nn.functional as F


def gram(features: torch.Tensor) -> torch.Tensor:
    """(N, C, H, W) to (N, C, C), normalised by C*H*W so layers of any size weigh alike."""
    n, c, h, w = features.shape
    flat = features.reshape(n, c, h * w)
    return flat @ flat.transpose(1, 2) / (c * h * w)


def content_loss(features: dict, targets: dict, layers) -> torch.Tensor:
    return sum(F.mse_loss(features[layer], targets[layer]) for layer in layers) / len(layers)


def style_loss(features: dict, target_grams: dict, layers) -> torch.Tensor:
    # target grams have batch 1; they broadcast over a training batch
    return sum(F.mse_loss(gram(features[layer]), target_grams[layer].expand(features[layer].shape[0], -1, -1))
               for layer in layers) / len(layers)


def tv_loss(x: torch.Tensor) -> torch.Tensor:
    return (x[..., 1:, :] - x[..., :-1, :]).abs().mean() + (x[..., :, 1:] - x[..., :, :-1]).abs().mean()
