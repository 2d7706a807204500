"""How far an image's look is from a style set: the Gatys style loss at one fixed size.

One measure for every method and for the unstyled render, so their figures compare: Gram matrices
on relu1_1..relu5_1 of the image scaled to ``size`` pixels on its longer side, mean squared
difference to the style set's mean Grams, averaged over the layers (what Gatys minimises, weight 1).
``gap_closed`` = 1 - distance(stylised) / distance(render): the share of the render's distance to the
style that stylisation removed (1: the style's statistics exactly, 0: no change, < 0: further away).
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import torch

from .gatys import STYLE_LAYERS
from .imageio import load_image
from .losses import style_loss
from .style_set import load_style_grams
from .vgg import VGG19, preprocess

SIZE = 256  # the fast net's style size: coarser hides texture, finer costs VGG time per image


class StyleDistance:
    def __init__(self, styles: Sequence[Path], size: int = SIZE, layers: Sequence[str] = STYLE_LAYERS,
                 vgg: VGG19 | None = None, device: str = "cpu"):
        self.size, self.layers = size, tuple(layers)
        self.vgg = vgg or VGG19("avg").to(device)
        self.targets = load_style_grams(self.vgg, styles, size, self.layers)

    def __call__(self, image: Path | torch.Tensor) -> float:
        """Distance of an image file, or a (1, 3, H, W) 0..1 tensor already at the measuring size."""
        x = load_image(image, self.size) if isinstance(image, (str, Path)) else image
        with torch.no_grad():
            return float(style_loss(self.vgg(preprocess(x.to(self.vgg.device)), self.layers), self.targets,
                                    self.layers))

    def settings(self) -> dict:
        return {"size": self.size, "layers": list(self.layers), "target": "mean Gram of the style set"}


def gap_closed(stylised: float, render: float) -> float | None:
    return 1.0 - stylised / render if render > 0 else None
