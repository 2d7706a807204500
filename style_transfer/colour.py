"""Colour preservation (Gatys et al. 2016, "Preserving color in neural artistic style transfer").

Luminance-only transfer: keep the stylised image's luma and the content image's chroma, so
style transfer changes texture and tone but not the colours of the scene the SUT is asked about.
"""
from __future__ import annotations

import torch

# ITU-R BT.601 full-range RGB <-> YCbCr
_TO_YCC = torch.tensor([[0.299, 0.587, 0.114], [-0.168736, -0.331264, 0.5], [0.5, -0.418688, -0.081312]])


def rgb_to_ycc(x: torch.Tensor) -> torch.Tensor:
    return torch.einsum("ij,njhw->nihw", _TO_YCC.to(x), x)


def ycc_to_rgb(x: torch.Tensor) -> torch.Tensor:
    return torch.einsum("ij,njhw->nihw", torch.linalg.inv(_TO_YCC).to(x), x)


def preserve_colour(stylised: torch.Tensor, content: torch.Tensor) -> torch.Tensor:
    """The stylised luma with the content's chroma, both (N, 3, H, W) RGB in 0..1."""
    if stylised.shape != content.shape:
        raise ValueError("colour preservation needs equal sizes, "
                         f"got {tuple(stylised.shape)} and {tuple(content.shape)}")
    mixed = torch.cat([rgb_to_ycc(stylised)[:, :1], rgb_to_ycc(content)[:, 1:]], dim=1)
    return ycc_to_rgb(mixed).clamp(0, 1)
