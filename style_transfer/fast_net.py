"""A small feed-forward stylisation network (Johnson et al. 2016, sized for a CPU).

Johnson's network (32-64-128 channels, five residual blocks at 1/4 resolution) costs about
40 GFLOP on a 640x480 frame: seconds per image on two cores. This one downsamples three
times from the first layer on, keeps the residual blocks at 1/8 resolution and has a single thin
full-resolution layer, so the same frame costs about 1 GFLOP; instance normalisation (Ulyanov et al.) and nearest
upsampling followed by a convolution (no checkerboard artefacts) as in the original.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
import torch.nn as nn
import torch.nn.functional as F

from isu_validate.errors import InputError


@dataclass(frozen=True)
class FastNetConfig:
    width: int = 16      # channels after the first layer (1 GFLOP per 640x480 frame; 32: 4 GFLOP)
    blocks: int = 3      # residual blocks at 1/8 resolution
    noise: bool = True   # a seeded noise channel at full resolution, so the net can add sensor noise

    def to_dict(self) -> dict:
        return asdict(self)


def _conv(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.ReflectionPad2d(1), nn.Conv2d(cin, cout, 3, stride),
                         nn.InstanceNorm2d(cout, affine=True), nn.ReLU(inplace=True))


class _Residual(nn.Module):
    def __init__(self, ch: int):
        super().__init__()
        self.body = nn.Sequential(_conv(ch, ch), nn.ReflectionPad2d(1), nn.Conv2d(ch, ch, 3),
                                  nn.InstanceNorm2d(ch, affine=True))

    def forward(self, x):
        return x + self.body(x)


class _Up(nn.Module):
    def __init__(self, cin: int, cout: int):
        super().__init__()
        self.conv = _conv(cin, cout)

    def forward(self, x, size):
        return self.conv(F.interpolate(x, size=size, mode="nearest"))


class FastStyleNet(nn.Module):
    def __init__(self, cfg: FastNetConfig = FastNetConfig()):
        super().__init__()
        w = cfg.width
        self.cfg = cfg
        self.down = nn.ModuleList([_conv(3, w // 2, 2), _conv(w // 2, w, 2), _conv(w, 2 * w, 2)])
        self.res = nn.Sequential(*[_Residual(2 * w) for _ in range(cfg.blocks)])
        self.up = nn.ModuleList([_Up(2 * w, w), _Up(w, w // 2)])
        # the only full-resolution layer: cheap (w/2 + 1 -> 3 channels) but able to place
        # per-pixel detail, including noise drawn from the extra channel (Ulyanov et al. 2016)
        self.out = nn.Sequential(nn.ReflectionPad2d(1), nn.Conv2d(w // 2 + int(cfg.noise), 3, 3))
        # zero: the untrained net is the identity (the render itself, no noise); a default init adds
        # noise of +-0.3 that a CPU budget of a few hundred steps spends most of its time removing
        nn.init.zeros_(self.out[1].weight)
        nn.init.zeros_(self.out[1].bias)

    def forward(self, x: torch.Tensor, seed: int = 0) -> torch.Tensor:
        """(N, 3, H, W) RGB 0..1 to the stylised image, same size, 0..1; ``seed`` draws the noise."""
        if min(x.shape[-2:]) < 16:
            raise InputError(f"image of {tuple(x.shape[-2:])} pixels is too small for the fast style net "
                             "(16x16 at least)")
        sizes = []
        h = x
        for layer in self.down:
            sizes.append(h.shape[-2:])
            h = layer(h)
        h = self.res(h)
        for layer, size in zip(self.up, reversed(sizes[1:])):
            h = layer(h, size)
        h = F.interpolate(h, size=x.shape[-2:], mode="nearest")
        if self.cfg.noise:
            # drawn on the CPU's generator and moved: a seed gives the same noise on every device (a CUDA
            # generator's stream differs from the CPU's), so only float rounding separates their images
            gen = torch.Generator().manual_seed(seed)
            noise = torch.randn((x.shape[0], 1, *x.shape[-2:]), generator=gen, dtype=x.dtype).to(x.device)
            h = torch.cat([h, noise], dim=1)
        # A residual on the input: the scene's fine structure passes through untouched (what
        # the SUT must still recognise), and the untrained net starts at the identity, so a CPU
        # training budget goes to style rather than to relearning the scene.
        return (x + self.out(h)).clamp(0, 1)
